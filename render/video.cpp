#include "render/video.h"

#include "basics/bound.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <condition_variable>
#include <deque>
#include <filesystem>
#include <mutex>
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
    const char* fourcc;
    const char* extension;
};

// Accepted codec names (lower case) and what they mean.
bool findCodec(const std::string& name, CodecInfo& info) {
    std::string n = name;
    std::transform(n.begin(), n.end(), n.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    if (n == "h264" || n == "avc1") {
        info = {"avc1", ".mp4"};
        return true;
    }
    if (n == "mjpg") {
        info = {"MJPG", ".avi"};
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
    const std::string name = "." + p.stem().string() + ".tmp-" + std::to_string(::getpid()) + "-" +
                             std::to_string(counter++) + p.extension().string();
    return (p.has_parent_path() ? p.parent_path() / name : fs::path(name)).string();
}

void removeQuietly(const std::string& path) {
    std::error_code ec;
    fs::remove(path, ec);
}

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
    static constexpr size_t kMaxQueued = 3;

    cv::VideoWriter writer;
    std::string path, temporary;
    cv::Size size;
    int frames = 0;
    bool open = false;

    std::thread worker;
    std::mutex mutex;
    std::condition_variable changed;
    std::deque<cv::Mat> queue;
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
                writer.write(frame);
            } catch (const std::exception& e) {
                failure = e.what();
            }
            lock.lock();
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
        if (writer.isOpened()) writer.release();
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
    const int fourcc = cv::VideoWriter::fourcc(info.fourcc[0], info.fourcc[1], info.fourcc[2], info.fourcc[3]);
    bool ok = false;
    std::string reason;
    try {
        ok = impl_->writer.open(impl_->temporary, cv::CAP_FFMPEG, fourcc, settings.fps, impl_->size, true);
    } catch (const cv::Exception& e) {
        reason = std::string(": ") + e.what();
    }
    if (!ok) {
        impl_->abandon();
        throw InputError("video file '" + path + "': OpenCV/FFmpeg could not open a '" + settings.codec +
                         "' encoder (fourcc " + info.fourcc + ") for " + std::to_string(settings.width) + "x" +
                         std::to_string(settings.height) + " at " + std::to_string(settings.fps) + " fps" +
                         reason);
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
    cv::Mat copy = frame.clone();   // the caller may reuse its buffer
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
    impl_->writer.release();
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
    bool ok = false;
    std::string reason;
    try {
        ok = cv::imwrite(temporary, frame);
    } catch (const cv::Exception& e) {
        reason = std::string(": ") + e.what();
    }
    std::error_code ec;
    if (ok) fs::rename(temporary, path, ec);
    if (!ok || ec) {
        removeQuietly(temporary);
        throw InputError("image file '" + path + "': cannot be written" + (ec ? ": " + ec.message() : reason));
    }
}

}  // namespace armsim
