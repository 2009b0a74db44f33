#include "render/video.h"

#include "basics/bound.h"
#include "basics/errors.h"

#include <png.h>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/error.h>
#include <libavutil/log.h>
#include <libavutil/opt.h>
#include <libswscale/swscale.h>
}

#include <unistd.h>

#include <csetjmp>
#include <cstdio>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <cctype>
#include <condition_variable>
#include <deque>
#include <filesystem>
#include <mutex>
#include <stdexcept>
#include <system_error>
#include <thread>

namespace armsim {

namespace fs = std::filesystem;

namespace {

constexpr int kMinSize = 16;
constexpr int kMaxSize = 4096;
constexpr double kMinFps = 1;    // below: a slide show (and FFmpeg refuses tiny rates)
constexpr double kMaxFps = 240;

struct CodecInfo {
    const char* encoder;     // FFmpeg encoder name
    const char* extension;
};

// Accepted codec names (lower case) and what they mean.
bool findCodec(const std::string& name, CodecInfo& info) {
    std::string n = name;
    std::transform(n.begin(), n.end(), n.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    if (n == "h264" || n == "avc1") {
        info = {"libx264", ".mp4"};
        return true;
    }
    if (n == "mjpg") {
        info = {"mjpeg", ".avi"};
        return true;
    }
    return false;
}

void checkEvenSize(const std::string& field, int value) {
    checkField(field, value, Bound::closed(kMinSize, kMaxSize, "px"));
    if (value % 2 != 0)
        throw FieldError(field, "= " + std::to_string(value) + ": expected an even number of pixels");
}

// Checks that path can be created: right extension, existing writable directory, not a directory.
void checkOutputPath(const std::string& what, const std::string& path, const std::string& extension) {
    if (path.empty()) throw InputError(what + " path is empty: expected a file name ending in " + extension);
    const fs::path p(path);
    if (p.extension().string() != extension)
        throw InputError(what + " '" + path + "': extension '" + p.extension().string() + "': expected '" +
                         extension + "'");
    const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path(".");
    std::error_code ec;
    if (!fs::is_directory(dir, ec))
        throw InputError(what + " '" + path + "': directory '" + dir.string() +
                         "' does not exist: expected an existing directory");
    if (::access(dir.c_str(), W_OK) != 0)
        throw InputError(what + " '" + path + "': directory '" + dir.string() + "' is not writable");
    if (fs::is_directory(p, ec))
        throw InputError(what + " '" + path + "' is a directory: expected a file path");
}

std::string makeTemporaryPath(const std::string& path) {
    static std::atomic<unsigned> counter{0};
    const fs::path p(path);
    // A staging file's name is hidden already (".armsim-partial-<pid>-..."): kept as its prefix, so a
    // temporary left by a killed process is recognised and removed by the next run in the folder.
    const std::string hide = p.stem().string().rfind('.', 0) == 0 ? "" : ".";
    const std::string name = hide + p.stem().string() + ".tmp-" + std::to_string(::getpid()) + "-" +
                             std::to_string(counter++) + p.extension().string();
    return (p.has_parent_path() ? p.parent_path() / name : fs::path(name)).string();
}

void removeQuietly(const std::string& path) {
    std::error_code ec;
    fs::remove(path, ec);
}

// Writes an 8-bit gray, BGR or BGRA image as PNG with libpng; returns "" or libpng's message. Only
// plain locals live across the setjmp.
std::string writePngFile(const std::string& path, const cv::Mat& frame) {
    std::FILE* file = std::fopen(path.c_str(), "wb");
    if (!file) return std::strerror(errno);
    static thread_local char message[256];
    message[0] = 0;
    png_structp png = png_create_write_struct(
        PNG_LIBPNG_VER_STRING, nullptr,
        [](png_structp p, png_const_charp text) {
            const int error = errno;   // a failed fwrite (libpng says only "Write Error")
            std::snprintf(message, sizeof message, "%s%s%s", text, error ? ": " : "", error ? std::strerror(error) : "");
            png_longjmp(p, 1);
        },
        [](png_structp, png_const_charp) {});
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    errno = 0;
    if (!png || !info) {
        png_destroy_write_struct(&png, &info);
        std::fclose(file);
        return "out of memory";
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        std::fclose(file);
        return message[0] ? message : "libpng failed";
    }
    png_init_io(png, file);
    const int channels = frame.channels();
    const int colour = channels == 1 ? PNG_COLOR_TYPE_GRAY : channels == 3 ? PNG_COLOR_TYPE_RGB : PNG_COLOR_TYPE_RGBA;
    png_set_IHDR(png, info, png_uint_32(frame.cols), png_uint_32(frame.rows), 8, colour, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    if (channels > 1) png_set_bgr(png);   // OpenCV's byte order
    for (int row = 0; row < frame.rows; ++row) png_write_row(png, frame.ptr<png_byte>(row));
    png_write_end(png, info);
    png_destroy_write_struct(&png, &info);
    const bool flushed = std::fflush(file) == 0;
    const int error = errno;
    const bool closed = std::fclose(file) == 0;
    if (!flushed || !closed) return std::strerror(flushed ? errno : error);
    return "";
}

std::string avError(int code) {
    char text[AV_ERROR_MAX_STRING_SIZE] = {0};
    av_strerror(code, text, sizeof text);
    return text;
}

// One video file through FFmpeg's libraries: BGR frames converted to YUV and encoded into an MP4
// (libx264) or AVI (mjpeg) container. Not thread-safe; the writer's worker owns it.
// x264 runs on one thread with no lookahead or B-frames: its defaults (3 frame threads, a 40-frame
// lookahead, macroblock tree) cost about 200 MB at 1280 x 720 for files of under 100 kB here; these
// settings cost about 10 MB (docs/benchmarks.md, issue 30).
class Encoder {
public:
    Encoder(const std::string& path, const CodecInfo& info, const VideoSettings& s) {
        try {
            open(path, info, s);
        } catch (...) {
            release();   // a throwing constructor runs no destructor
            throw;
        }
    }
    ~Encoder() { release(); }
    Encoder(const Encoder&) = delete;
    Encoder& operator=(const Encoder&) = delete;

private:
    void open(const std::string& path, const CodecInfo& info, const VideoSettings& s) {
        // FFmpeg's own log lines are off for the whole process: failures come back as exceptions.
        av_log_set_level(AV_LOG_QUIET);
        check(avformat_alloc_output_context2(&format_, nullptr, nullptr, path.c_str()), "choose a container");
        const AVCodec* codec = avcodec_find_encoder_by_name(info.encoder);
        if (!codec) throw std::runtime_error(std::string("FFmpeg has no '") + info.encoder + "' encoder");
        stream_ = avformat_new_stream(format_, nullptr);
        context_ = avcodec_alloc_context3(codec);
        if (!stream_ || !context_) throw std::runtime_error("out of memory");
        const AVRational rate = av_d2q(s.fps, 1000000);
        context_->width = s.width;
        context_->height = s.height;
        context_->framerate = rate;
        context_->time_base = av_inv_q(rate);
        context_->thread_count = 1;
        if (std::string(info.encoder) == "mjpeg") {
            context_->pix_fmt = AV_PIX_FMT_YUVJ420P;
            context_->flags |= AV_CODEC_FLAG_QSCALE;
            context_->global_quality = FF_QP2LAMBDA * 3;   // qscale 3: visually lossless for drawings
        } else {
            context_->pix_fmt = AV_PIX_FMT_YUV420P;
            context_->gop_size = std::max(1, int(std::lround(2 * s.fps)));
            av_opt_set(context_->priv_data, "preset", "veryfast", 0);
            av_opt_set(context_->priv_data, "crf", "23", 0);
            av_opt_set(context_->priv_data, "x264-params", "rc-lookahead=0:bframes=0:mbtree=0:sync-lookahead=0", 0);
        }
        if (format_->oformat->flags & AVFMT_GLOBALHEADER) context_->flags |= AV_CODEC_FLAG_GLOBAL_HEADER;
        check(avcodec_open2(context_, codec, nullptr), "open the encoder");
        check(avcodec_parameters_from_context(stream_->codecpar, context_), "set the stream");
        stream_->time_base = context_->time_base;
        check(avio_open(&format_->pb, path.c_str(), AVIO_FLAG_WRITE), "open the file");
        check(avformat_write_header(format_, nullptr), "write the header");
        frame_ = av_frame_alloc();
        packet_ = av_packet_alloc();
        if (!frame_ || !packet_) throw std::runtime_error("out of memory");
        frame_->format = context_->pix_fmt;
        frame_->width = s.width;
        frame_->height = s.height;
        check(av_frame_get_buffer(frame_, 0), "allocate a frame");
        scaler_ = sws_getContext(s.width, s.height, AV_PIX_FMT_BGR24, s.width, s.height, context_->pix_fmt,
                                 SWS_BILINEAR, nullptr, nullptr, nullptr);
        if (!scaler_) throw std::runtime_error("no BGR to YUV conversion");
    }
    void release() {
        sws_freeContext(scaler_);
        scaler_ = nullptr;
        av_packet_free(&packet_);
        av_frame_free(&frame_);
        avcodec_free_context(&context_);
        if (format_ && format_->pb) avio_closep(&format_->pb);
        avformat_free_context(format_);
        format_ = nullptr;
        stream_ = nullptr;
    }

public:
    void write(const cv::Mat& bgr) {
        check(av_frame_make_writable(frame_), "reuse the frame");
        const uint8_t* source[1] = {bgr.data};
        const int stride[1] = {int(bgr.step[0])};
        sws_scale(scaler_, source, stride, 0, bgr.rows, frame_->data, frame_->linesize);
        frame_->pts = next_++;
        check(avcodec_send_frame(context_, frame_), "encode a frame");
        drain();
    }
    // Flushes the encoder, writes the trailer and closes the file.
    void finish() {
        check(avcodec_send_frame(context_, nullptr), "flush the encoder");
        drain();
        check(av_write_trailer(format_), "write the trailer");
        const int closed = avio_closep(&format_->pb);
        check(closed, "close the file");
    }

private:
    void drain() {
        for (;;) {
            const int r = avcodec_receive_packet(context_, packet_);
            if (r == AVERROR(EAGAIN) || r == AVERROR_EOF) return;
            check(r, "encode a frame");
            if (packet_->duration <= 0) packet_->duration = 1;   // one frame: else the last one has no length
            av_packet_rescale_ts(packet_, context_->time_base, stream_->time_base);
            packet_->stream_index = stream_->index;
            check(av_interleaved_write_frame(format_, packet_), "write a frame");   // takes the packet
            if (format_->pb && format_->pb->error < 0) check(format_->pb->error, "write a frame");
        }
    }
    static void check(int code, const char* what) {
        if (code < 0) throw std::runtime_error(std::string("cannot ") + what + ": " + avError(code));
    }

    AVFormatContext* format_ = nullptr;
    AVStream* stream_ = nullptr;
    AVCodecContext* context_ = nullptr;
    AVFrame* frame_ = nullptr;
    AVPacket* packet_ = nullptr;
    SwsContext* scaler_ = nullptr;
    int64_t next_ = 0;
};

}  // namespace

void VideoSettings::validate() const {
    checkField("fps", fps, Bound::closed(kMinFps, kMaxFps, "1/s"));
    checkEvenSize("width", width);
    checkEvenSize("height", height);
    CodecInfo info;
    if (!findCodec(codec, info))
        throw FieldError("codec", "= '" + codec + "': expected one of 'h264', 'avc1', 'mjpg'");
}

// Frames are encoded on a worker thread so that rendering the next frame overlaps encoding this
// one; the queue is bounded so a slow encoder throttles the producer.
struct VideoWriter::Impl {
    static constexpr size_t kMaxQueued = 1;   // frames waiting: each is 2.7 MB at 1280 x 720

    std::unique_ptr<Encoder> encoder;
    std::string path, temporary;
    cv::Size size;
    int frames = 0;
    bool open = false;

    std::thread worker;
    std::mutex mutex;
    std::condition_variable changed;
    std::deque<cv::Mat> queue;
    std::vector<cv::Mat> spare;   // encoded frames' buffers, reused by write()
    bool finishing = false;
    std::string error;   // first encoder failure, reported by the next write() or close()

    void startWorker() {
        finishing = false;
        error.clear();
        worker = std::thread([this] { encodeLoop(); });
    }
    void encodeLoop() {
        std::unique_lock<std::mutex> lock(mutex);
        for (;;) {
            changed.wait(lock, [&] { return finishing || !queue.empty(); });
            if (queue.empty()) return;
            cv::Mat frame = std::move(queue.front());
            queue.pop_front();
            lock.unlock();
            std::string failure;
            try {
                encoder->write(frame);
            } catch (const std::exception& e) {
                failure = e.what();
            }
            lock.lock();
            spare.push_back(std::move(frame));
            if (!failure.empty() && error.empty()) error = failure;
            changed.notify_all();
        }
    }
    // Waits for queued frames to be encoded (or drops them) and stops the worker.
    void stopWorker(bool dropQueued) {
        if (!worker.joinable()) return;
        {
            std::lock_guard<std::mutex> lock(mutex);
            if (dropQueued) queue.clear();
            finishing = true;
        }
        changed.notify_all();
        worker.join();
    }
    void abandon() {
        stopWorker(true);
        encoder.reset();
        if (!temporary.empty()) removeQuietly(temporary);
        open = false;
        frames = 0;
    }
    ~Impl() {
        if (open) abandon();
    }
    [[noreturn]] void failWithEncoderError(const std::string& message) {
        abandon();
        throw InputError("video file '" + path + "': encoding failed: " + message + "; nothing was saved");
    }
};

VideoWriter::VideoWriter() : impl_(std::make_unique<Impl>()) {}
VideoWriter::~VideoWriter() = default;
VideoWriter::VideoWriter(VideoWriter&&) noexcept = default;
VideoWriter& VideoWriter::operator=(VideoWriter&&) noexcept = default;

void VideoWriter::open(const std::string& path, const VideoSettings& settings) {
    settings.validate();
    CodecInfo info;
    findCodec(settings.codec, info);
    checkOutputPath("video file", path, info.extension);
    if (impl_->open) impl_->abandon();

    impl_->path = path;
    impl_->temporary = makeTemporaryPath(path);
    impl_->size = cv::Size(settings.width, settings.height);
    impl_->frames = 0;
    try {
        impl_->encoder = std::make_unique<Encoder>(impl_->temporary, info, settings);
    } catch (const std::exception& e) {
        impl_->abandon();
        throw InputError("video file '" + path + "': FFmpeg could not open a '" + settings.codec + "' encoder (" +
                         info.encoder + ") for " + std::to_string(settings.width) + "x" +
                         std::to_string(settings.height) + " at " + std::to_string(settings.fps) + " fps: " +
                         e.what());
    }
    impl_->open = true;
    impl_->startWorker();
}

void VideoWriter::write(const cv::Mat& frame) {
    if (!impl_->open) throw InputError("video: write() called without an open video");
    if (frame.type() != CV_8UC3 || frame.size() != impl_->size)
        throw InputError("video file '" + impl_->path + "': frame " + std::to_string(frame.cols) + "x" +
                         std::to_string(frame.rows) + " of OpenCV type " + std::to_string(frame.type()) +
                         ": expected " + std::to_string(impl_->size.width) + "x" +
                         std::to_string(impl_->size.height) + " CV_8UC3 (BGR)");
    cv::Mat copy;   // the caller may reuse its buffer: copied into a spare one
    {
        std::lock_guard<std::mutex> lock(impl_->mutex);
        if (!impl_->spare.empty()) {
            copy = std::move(impl_->spare.back());
            impl_->spare.pop_back();
        }
    }
    frame.copyTo(copy);
    std::string error;
    {
        std::unique_lock<std::mutex> lock(impl_->mutex);
        impl_->changed.wait(lock, [&] { return impl_->queue.size() < Impl::kMaxQueued || !impl_->error.empty(); });
        error = impl_->error;
        if (error.empty()) impl_->queue.push_back(std::move(copy));
    }
    if (!error.empty()) impl_->failWithEncoderError(error);
    impl_->changed.notify_all();
    ++impl_->frames;
}

void VideoWriter::close() {
    if (!impl_->open) throw InputError("video: close() called without an open video");
    if (impl_->frames == 0) {
        impl_->abandon();
        throw InputError("video file '" + impl_->path + "': no frames were written; nothing was saved");
    }
    impl_->stopWorker(false);
    if (!impl_->error.empty()) impl_->failWithEncoderError(impl_->error);
    try {
        impl_->encoder->finish();
    } catch (const std::exception& e) {
        impl_->failWithEncoderError(e.what());
    }
    impl_->encoder.reset();
    std::error_code ec;
    if (!fs::is_regular_file(impl_->temporary, ec) || fs::file_size(impl_->temporary, ec) == 0) {
        impl_->abandon();
        throw InputError("video file '" + impl_->path + "': the encoder produced no output; nothing was saved");
    }
    fs::rename(impl_->temporary, impl_->path, ec);
    if (ec) {
        impl_->abandon();
        throw InputError("video file '" + impl_->path + "': cannot rename the finished temporary into place: " +
                         ec.message());
    }
    impl_->open = false;
}

void VideoWriter::discard() {
    if (impl_->open) impl_->abandon();
}

bool VideoWriter::isOpen() const { return impl_->open; }
int VideoWriter::getNumFramesWritten() const { return impl_->frames; }
const std::string& VideoWriter::getPath() const { return impl_->path; }
const std::string& VideoWriter::getTemporaryPath() const { return impl_->temporary; }

void writePng(const std::string& path, const cv::Mat& frame) {
    checkOutputPath("image file", path, ".png");
    if (frame.empty() || (frame.type() != CV_8UC1 && frame.type() != CV_8UC3 && frame.type() != CV_8UC4))
        throw InputError("image file '" + path + "': frame is empty or of OpenCV type " +
                         std::to_string(frame.type()) + ": expected CV_8UC1, CV_8UC3 or CV_8UC4");
    const std::string temporary = makeTemporaryPath(path);
    std::string failure = writePngFile(temporary, frame);
    std::error_code ec;
    if (failure.empty()) fs::rename(temporary, path, ec);
    if (!failure.empty() || ec) {
        removeQuietly(temporary);
        throw InputError("image file '" + path + "': cannot be written: " + (ec ? ec.message() : failure));
    }
}

int writeTrialVideoAndStill(const std::string& videoPath, const VideoSettings& video, int frames,
                            const std::function<int(int)>& rowOfFrame, const std::string& stillPath, int stillRow,
                            const std::function<cv::Mat(int)>& render, const std::function<void(int, int)>& progress) {
    VideoWriter writer;
    if (!videoPath.empty()) writer.open(videoPath, video);   // checked before the still is drawn
    if (stillRow >= 0) writePng(stillPath, render(stillRow));
    if (!writer.isOpen()) return 0;
    for (int k = 0; k < frames; ++k) {
        checkInterruption();   // Ctrl-C: the writer's destructor removes the partial video
        writer.write(render(rowOfFrame(k)));
        if (progress) progress(k + 1, frames);
    }
    writer.close();
    return frames;
}

}  // namespace armsim
