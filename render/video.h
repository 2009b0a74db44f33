// Video output through FFmpeg's libraries (libx264 in MP4, MJPEG in AVI) and PNG stills through libpng. Files are written whole or not at all: frames go to a
// hidden temporary beside the target ("<dir>/.<name>.tmp-<pid>-<n>.<ext>") that close() renames into
// place; a failure, discard() or destruction before close() removes the temporary. The target's
// directory must already exist (it is not created).
#pragma once

#include <opencv2/core.hpp>

#include <functional>
#include <memory>
#include <optional>
#include <string>

namespace armsim {

/// Encoding settings of a video file.
struct VideoSettings {
    double fps = 30;              ///< frame rate (1/s), in (0, 240]
    int width = 1280;             ///< frame width (px), even, in [16, 4096]
    int height = 720;             ///< frame height (px), even, in [16, 4096]
    std::string codec = "h264";   ///< "h264" or "avc1" (H.264 in .mp4) or "mjpg" (Motion JPEG in .avi)

    /// Throws FieldError naming the field (fps, width, height, codec), its value and what was expected.
    void validate() const;
};

/// Writes BGR frames to a video file through FFmpeg's libraries (x264 on one thread, no lookahead). Encoding runs on a
/// worker thread owned by the writer, so rendering the next frame overlaps encoding this one: write()
/// copies the frame into a queue of at most 1 frame and blocks while it is full. Use one writer from
/// one thread at a time.
class VideoWriter {
public:
    VideoWriter();
    /// Discards an unfinished video (removes its temporary).
    ~VideoWriter();
    /// A moved-from writer may only be destroyed or assigned to.
    VideoWriter(VideoWriter&&) noexcept;
    /// Discards the unfinished video this writer had, if any, and takes over other's.
    VideoWriter& operator=(VideoWriter&&) noexcept;
    VideoWriter(const VideoWriter&) = delete;
    VideoWriter& operator=(const VideoWriter&) = delete;

    /// Validates settings and path before anything is written, then opens the encoder on the
    /// temporary. Throws InputError (FieldError for settings) naming the setting or path, the value
    /// and what was expected: bad size, fps or codec; a path whose extension does not suit the codec
    /// (.mp4 for h264/avc1, .avi for mjpg); a missing or unwritable directory; a path that is a
    /// directory; or an encoder that cannot be opened. Closes (discards) a video already open.
    void open(const std::string& path, const VideoSettings& settings);
    /// Appends one frame: CV_8UC3 BGR of exactly the opened size, else InputError. An encoder failure
    /// discards the video and throws InputError here or in close().
    void write(const cv::Mat& frame);
    /// Finishes the file and renames it to the path given to open() (replacing an existing file).
    /// Throws InputError if no frame was written or the file cannot be finished; nothing is left then.
    void close();
    /// Abandons the video: removes the temporary; the target path is untouched.
    void discard();

    bool isOpen() const;
    int getNumFramesWritten() const;
    const std::string& getPath() const;           ///< target path given to open()
    const std::string& getTemporaryPath() const;  ///< where frames go until close()

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

/// A replayed trial's video and still: the still (stillRow >= 0) to stillPath, then, when videoPath is
/// not empty, `frames` frames, frame k drawn by render(rowOfFrame(k)), with a stop checked before each
/// (Ctrl-C: the partial video is removed) and progress(k + 1, frames) after. Returns the frames written.
int writeTrialVideoAndStill(const std::string& videoPath, const VideoSettings& video, int frames,
                            const std::function<int(int)>& rowOfFrame, const std::string& stillPath, int stillRow,
                            const std::function<cv::Mat(int)>& render, const std::function<void(int, int)>& progress);

/// writeTrialVideoAndStill for a trial renderer (TrialRenderer, the OpenSim trials' renderer: getNumFrames,
/// getFrameTime, findRow, renderRow): its frames over the trial and the still at stillTime (none: no still).
template <class Renderer>
int writeReplay(Renderer& renderer, const std::string& videoPath, const VideoSettings& video,
                const std::optional<double>& stillTime, const std::string& stillPath,
                const std::function<void(int, int)>& progress) {
    return writeTrialVideoAndStill(
        videoPath, video, renderer.getNumFrames(), [&](int k) { return renderer.findRow(renderer.getFrameTime(k)); },
        stillPath, stillTime ? renderer.findRow(*stillTime) : -1, [&](int row) { return renderer.renderRow(row); }, progress);
}

/// Writes frame (CV_8UC1, CV_8UC3 BGR or CV_8UC4 BGRA) to a .png path atomically (temporary, then
/// rename). Throws InputError naming the path for a wrong extension, missing or unwritable
/// directory, empty frame or failed encoding; nothing is left behind on failure.
void writePng(const std::string& path, const cv::Mat& frame);

}  // namespace armsim
