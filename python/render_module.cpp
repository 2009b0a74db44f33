// The Python module armsim._render: a recorded arm trial to an mp4 (renderTrialVideo) or one frame to
// an (H, W, 3) uint8 RGB array (TrialRenderer), offscreen through OSMesa. A separate extension so
// that `import armsim` does not load the render stack (OSMesa, OpenCV video); armsim.render_video
// and render_frame import it on first use.
#include "basics/bound.h"
#include "python/module_support.h"
#include "model/osim_forward.h"
#include "render/osim_video.h"
#include "render/trial_video.h"

#include <opencv2/imgproc.hpp>

using namespace armsim;
using namespace armsim::python;

namespace {

TrialVideoSettings makeSettings(int width, int height, int supersample, bool overlay, const std::string& colorBy) {
    TrialVideoSettings v;
    v.render.width = width;
    v.render.height = height;
    v.render.supersample = supersample;
    v.overlay = overlay;
    if (colorBy == "force") v.scene.muscleColoring = MuscleColoring::Force;
    else if (colorBy != "activation")
        throw InputError("color_by = '" + colorBy + "': expected activation or force");
    v.tableName = "series";
    return v;
}

OsimVideoSettings makeOsimSettings(int width, int height, int supersample, bool overlay) {
    OsimVideoSettings v;
    v.render.width = width;
    v.render.height = height;
    v.render.supersample = supersample;
    v.overlay = overlay;
    v.tableName = "series";
    return v;
}

py::array_t<std::uint8_t> toRgbArray(const cv::Mat& bgr) {
    cv::Mat rgb;
    cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
    py::array_t<std::uint8_t> a({rgb.rows, rgb.cols, 3});
    for (int r = 0; r < rgb.rows; ++r) std::memcpy(a.mutable_data(r, 0, 0), rgb.ptr(r), std::size_t(rgb.cols) * 3);
    return a;
}

}  // namespace

PYBIND11_MODULE(_render, mod) {
    using namespace pybind11::literals;
    mod.doc() = "armsim rendering: trial videos and frames, offscreen (OSMesa, no display).";
    py::module_::import("armsim._armsim");  // registers armsim.Model

    mod.def(
        "render_video",
        [](const Model& m, const py::dict& series, const std::string& path, double fps, int width, int height,
           double playbackSpeed, bool overlay, const std::string& codec, int supersample, const std::string& colorBy) {
            if (path.empty()) throw InputError("path: expected a video file (.mp4 for h264, .avi for mjpg)");
            TrialVideoSettings v = makeSettings(width, height, supersample, overlay, colorBy);
            v.fps = fps;
            v.playbackSpeed = playbackSpeed;
            v.codec = codec;
            v.videoPath = path;
            const Table table = toTable(series, "series");
            TrialVideoResult r;
            runInterruptible([&] {
                r = renderTrialVideo(m.setup, table, v);
            });
            py::dict d;
            d["path"] = r.videoPath;
            d["frames"] = r.frames;
            return d;
        },
        "model"_a, "series"_a, "path"_a, "fps"_a = 30.0, "width"_a = 1280, "height"_a = 720, "playback_speed"_a = 1.0,
        "overlay"_a = true, "codec"_a = "h264", "supersample"_a = 2, "color_by"_a = "activation",
        R"(Renders a recorded trial of `model` (the series dict arm_trial returns, with its state_*
columns, so the replay is exact) to a video file: H.264 .mp4 (codec 'h264') or Motion JPEG .avi
('mjpg'), at fps frames per second of video and playback_speed trial seconds per video second;
width and height even, in [16, 4096]. The arm's decorations with the muscles coloured by
color_by ('activation' or 'force'), the transducer, a force arrow and, with overlay, time, angle,
forces and live plots. Written whole or not at all. Returns {'path', 'frames'}. Releases the GIL; Ctrl-C raises KeyboardInterrupt.)");

    mod.def(
        "render_frame",
        [](const Model& m, const py::dict& series, double time, int width, int height, bool overlay, int supersample,
           const std::string& colorBy) {
            const TrialVideoSettings v = makeSettings(width, height, supersample, overlay, colorBy);
            const Table table = toTable(series, "series");
            if (table.hasColumn("time_s") && table.getNumRows() > 0)  // the renderer checks the rest of the table
                checkField("time", time, Bound::closed(table.get(0, "time_s"), table.get(table.getNumRows() - 1, "time_s"),
                                                       "s, within the trial"));
            cv::Mat rgb;
            runInterruptible([&] {
                TrialRenderer renderer(m.setup, table, v);
                cv::cvtColor(renderer.renderRow(renderer.findRow(time)), rgb, cv::COLOR_BGR2RGB);
            });
            py::array_t<std::uint8_t> a({rgb.rows, rgb.cols, 3});
            for (int r = 0; r < rgb.rows; ++r)
                std::memcpy(a.mutable_data(r, 0, 0), rgb.ptr(r), std::size_t(rgb.cols) * 3);
            return a;
        },
        "model"_a, "series"_a, "time"_a, "width"_a = 640, "height"_a = 360, "overlay"_a = true, "supersample"_a = 2,
        "color_by"_a = "activation",
        R"(One frame of a recorded trial (the series dict arm_trial returns) at the sample nearest to
`time` [s]: an (height, width, 3) uint8 RGB array (for matplotlib's imshow), the same pixels as the
video's frame at that sample.)");

    mod.def(
        "render_osim_video",
        [](const py::object& model, const py::dict& series, const std::string& path, double fps, int width, int height,
           double playbackSpeed, bool overlay, const std::string& codec, int supersample) {
            if (path.empty()) throw InputError("path: expected a video file (.mp4 for h264, .avi for mjpg)");
            OsimVideoSettings v = makeOsimSettings(width, height, supersample, overlay);
            v.fps = fps;
            v.playbackSpeed = playbackSpeed;
            v.codec = codec;
            v.videoPath = path;
            const OsimModel m = readOsimFile(findOsimModelFile(toPathString(model, "model"), "model"));
            const Table table = toTable(series, "series");
            OsimVideoResult r;
            runInterruptible([&] { r = renderOsimTrialVideo(m, table, v); });
            py::dict d;
            d["path"] = r.videoPath;
            d["frames"] = r.frames;
            return d;
        },
        "model"_a, "series"_a, "path"_a, "fps"_a = 30.0, "width"_a = 1280, "height"_a = 720, "playback_speed"_a = 1.0,
        "overlay"_a = true, "codec"_a = "h264", "supersample"_a = 2,
        R"(render_video for an OpenSim model's trial (the series isometric_trial or free_movement returns).)");

    mod.def(
        "render_osim_frame",
        [](const py::object& model, const py::dict& series, double time, int width, int height, bool overlay, int supersample) {
            const OsimVideoSettings v = makeOsimSettings(width, height, supersample, overlay);
            const OsimModel m = readOsimFile(findOsimModelFile(toPathString(model, "model"), "model"));
            const Table table = toTable(series, "series");
            cv::Mat bgr;
            runInterruptible([&] { bgr = renderOsimTrialFrame(m, table, v, time); });
            return toRgbArray(bgr);
        },
        "model"_a, "series"_a, "time"_a, "width"_a = 640, "height"_a = 360, "overlay"_a = true, "supersample"_a = 2,
        R"(render_frame for an OpenSim model's trial.)");
}
