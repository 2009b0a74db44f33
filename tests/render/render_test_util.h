// Helpers shared by the render tests: a scratch directory and pixel predicates.
#pragma once

#include "render/renderer.h"

#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

namespace armsim::test {

/// A fresh empty directory, removed with its contents on destruction.
class ScratchDir {
public:
    ScratchDir() {
        std::string pattern = (std::filesystem::temp_directory_path() / "armsim-render-XXXXXX").string();
        path_ = ::mkdtemp(pattern.data()) ? pattern : std::string();
    }
    ~ScratchDir() {
        std::error_code ec;
        if (!path_.empty()) std::filesystem::remove_all(path_, ec);
    }
    ScratchDir(const ScratchDir&) = delete;
    ScratchDir& operator=(const ScratchDir&) = delete;
    const std::string& path() const { return path_; }
    std::string file(const std::string& name) const { return path_ + "/" + name; }
    /// Names of all entries (including hidden temporaries).
    std::vector<std::string> list() const {
        std::vector<std::string> names;
        for (const auto& e : std::filesystem::directory_iterator(path_)) names.push_back(e.path().filename());
        return names;
    }

private:
    std::string path_;
};

/// The BGR value OpenGL stores for an RGB colour whose channels are multiples of 1/255.
inline cv::Vec3b toBgr8(const SimTK::Vec3& rgb) {
    return {uchar(std::lround(255 * rgb[2])), uchar(std::lround(255 * rgb[1])), uchar(std::lround(255 * rgb[0]))};
}

/// The pixel that contains the projection of p_G.
inline cv::Point pixelOf(const RenderSettings& s, const SimTK::Vec3& p_G) {
    const SimTK::Vec2 p = projectToPixel(s.camera, s.width, s.height, p_G);
    return {int(std::floor(p[0])), int(std::floor(p[1]))};
}

/// True if channel c (0 = B, 1 = G, 2 = R) exceeds both others by at least margin.
inline bool dominates(const cv::Vec3b& bgr, int c, int margin) {
    for (int k = 0; k < 3; ++k)
        if (k != c && int(bgr[c]) - int(bgr[k]) < margin) return false;
    return true;
}

/// Pixels that differ from the background bg, inside and outside the rectangle `inside`.
struct DrawnPixels {
    int inside = 0, outside = 0;
};
inline DrawnPixels countDrawn(const cv::Mat& frame, const cv::Vec3b& bg, const cv::Rect& inside) {
    DrawnPixels n;
    for (int y = 0; y < frame.rows; ++y)
        for (int x = 0; x < frame.cols; ++x)
            if (frame.at<cv::Vec3b>(y, x) != bg) (inside.contains({x, y}) ? n.inside : n.outside)++;
    return n;
}

/// A video file decoded back with OpenCV (FFmpeg backend).
struct Decoded {
    double fps = 0, reportedCount = 0;
    cv::Size size;
    std::vector<cv::Mat> frames;
};

/// Every frame of the video at path; empty if it cannot be opened.
inline Decoded decode(const std::string& path) {
    cv::VideoCapture cap(path, cv::CAP_FFMPEG);
    Decoded d;
    if (!cap.isOpened()) return d;
    d.fps = cap.get(cv::CAP_PROP_FPS);
    d.reportedCount = cap.get(cv::CAP_PROP_FRAME_COUNT);
    d.size = cv::Size(int(cap.get(cv::CAP_PROP_FRAME_WIDTH)), int(cap.get(cv::CAP_PROP_FRAME_HEIGHT)));
    cv::Mat f;
    while (cap.read(f)) d.frames.push_back(f.clone());
    return d;
}

}  // namespace armsim::test
