// Throughput of the offscreen video pipeline on the test pendulum at 1280x720: rendering alone (by
// supersampling factor), the overlay, H.264 encoding alone, and the whole render + overlay + encode
// loop; and a trial video: replay of a recorded free-movement table into the arm, overlay, H.264.
// Target: >= 60 frames per second for the whole loop. Times are wall-clock (llvmpipe and x264 use
// worker threads), so "fps" counters are real frames per second.
#include "render/overlay.h"
#include "model/trial.h"
#include "render/renderer.h"
#include "render/trial_video.h"
#include "render/video.h"
#include "tests/render/pendulum_scene.h"

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>

namespace {

using namespace armsim;

constexpr int kWidth = 1280, kHeight = 720;
constexpr double kFps = 60;            // video frame rate (1/s)
constexpr double kSwingFrequency = 0.5;  // pendulum motion in the clip (Hz)

RenderSettings benchSettings(int supersample) {
    RenderSettings s;
    s.width = kWidth;
    s.height = kHeight;
    s.supersample = supersample;
    s.camera.position = SimTK::Vec3(0, -0.2, 1.5);
    s.camera.lookAt = SimTK::Vec3(0, -0.2, 0);
    return s;
}

double angleAt(double t) { return 0.8 * std::sin(2 * M_PI * kSwingFrequency * t); }

// A scratch directory for the clips, removed afterwards.
struct Scratch {
    std::string dir;
    Scratch() {
        std::string pattern = (std::filesystem::temp_directory_path() / "armsim-bench-XXXXXX").string();
        dir = ::mkdtemp(pattern.data()) ? pattern : "";
    }
    ~Scratch() {
        std::error_code ec;
        std::filesystem::remove_all(dir, ec);
    }
};

void drawDemoOverlay(cv::Mat& frame, double t, double q, std::vector<SimTK::Vec2>& trace) {
    trace.emplace_back(t, q);
    PlotTrace plot;
    plot.title = "angle (rad)";
    plot.samples = trace;
    plot.tRange = SimTK::Vec2(0, std::max(2.0, t));
    plot.yRange = SimTK::Vec2(-1, 1);
    char angle[32], time[32];
    std::snprintf(time, sizeof time, "%.3f s", t);
    std::snprintf(angle, sizeof angle, "%.1f deg", q * 180 / M_PI);
    drawOverlay(frame, {{"time", time}, {"angle", angle}}, {plot});
}

void BM_Render720p(benchmark::State& state) {
    test::PendulumScene scene;
    OffscreenRenderer renderer(benchSettings(int(state.range(0))));
    int i = 0;
    for (auto _ : state) {
        const double t = i++ / kFps;
        benchmark::DoNotOptimize(renderer.renderFrame(scene.getSystem(), scene.makeState(angleAt(t), 0.5)));
    }
    state.counters["fps"] = benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Render720p)->ArgName("supersample")->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMillisecond);

void BM_Overlay720p(benchmark::State& state) {
    test::PendulumScene scene;
    OffscreenRenderer renderer(benchSettings(2));
    const cv::Mat base = renderer.renderFrame(scene.getSystem(), scene.makeState(0.3, 0.5));
    std::vector<SimTK::Vec2> trace;
    int i = 0;
    for (auto _ : state) {
        cv::Mat frame = base.clone();
        const double t = i++ / kFps;
        drawDemoOverlay(frame, std::fmod(t, 10.0), angleAt(t), trace);
        if (trace.size() > 600) trace.clear();
        benchmark::DoNotOptimize(frame.data);
    }
    state.counters["fps"] = benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Overlay720p)->UseRealTime()->Unit(benchmark::kMillisecond);

void BM_EncodeH264_720p(benchmark::State& state) {
    test::PendulumScene scene;
    OffscreenRenderer renderer(benchSettings(2));
    std::vector<cv::Mat> frames;
    for (int i = 0; i < 60; ++i)
        frames.push_back(renderer.renderFrame(scene.getSystem(), scene.makeState(angleAt(i / kFps), 0.5)));
    Scratch scratch;
    VideoWriter writer;
    writer.open(scratch.dir + "/encode.mp4", {kFps, kWidth, kHeight, "h264"});
    size_t i = 0;
    for (auto _ : state) writer.write(frames[i++ % frames.size()]);
    writer.close();
    state.counters["fps"] = benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_EncodeH264_720p)->UseRealTime()->Unit(benchmark::kMillisecond);

// The whole loop of a trial video: render, overlay, encode H.264. Encoding overlaps rendering (the
// writer's worker thread); the last <= 3 queued frames are finished after the timed loop.
void BM_RenderOverlayEncodeH264_720p(benchmark::State& state) {
    test::PendulumScene scene;
    OffscreenRenderer renderer(benchSettings(int(state.range(0))));
    Scratch scratch;
    VideoWriter writer;
    writer.open(scratch.dir + "/trial.mp4", {kFps, kWidth, kHeight, "h264"});
    std::vector<SimTK::Vec2> trace;
    int i = 0;
    for (auto _ : state) {
        const double t = i++ / kFps, q = angleAt(t);
        cv::Mat frame = renderer.renderFrame(scene.getSystem(), scene.makeState(q, 0.5 + 0.5 * std::sin(t)));
        drawDemoOverlay(frame, std::fmod(t, 10.0), q, trace);
        if (trace.size() > 600) trace.clear();
        writer.write(frame);
    }
    writer.close();
    state.counters["fps"] = benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_RenderOverlayEncodeH264_720p)
    ->ArgName("supersample")->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMillisecond);

// A trial video as `armsim trial --video` makes it: a 2 s free movement recorded at 1000 Hz, replayed
// row by row (setStateFromTrialRow) at the video's frame times, drawn with the overlay (text and two
// live plots) and encoded as H.264, 1280x720, 30 fps. The frames cycle through the trial.
void BM_TrialReplayH264_720p(benchmark::State& state) {
    const ArmSetup setup = ArmSetup::loadDefault();
    FreeMovementSettings free;
    free.activation = ActivationProfile::step(0.2, 0.0, 1.0);
    const Table table = runFreeMovement(setup, free);
    TrialVideoSettings v;
    v.render.width = kWidth;
    v.render.height = kHeight;
    v.render.supersample = int(state.range(0));
    TrialRenderer renderer(setup, table, v);
    Scratch scratch;
    VideoWriter writer;
    writer.open(scratch.dir + "/trial.mp4", {v.fps, kWidth, kHeight, "h264"});
    const int frames = renderer.getNumFrames();
    int k = 0;
    for (auto _ : state) {
        writer.write(renderer.renderRow(renderer.findRow(renderer.getFrameTime(k))));
        k = (k + 1) % frames;
    }
    writer.close();
    state.counters["fps"] = benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_TrialReplayH264_720p)
    ->ArgName("supersample")->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace
