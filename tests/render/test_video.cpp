// Tests of video and PNG output: files reopen with the expected properties and content, are written
// whole or not at all, and bad settings are rejected before anything is written.
#include "basics/errors.h"
#include "render/renderer.h"
#include "render/video.h"
#include "tests/render/pendulum_scene.h"
#include "tests/render/render_test_util.h"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <fstream>

namespace armsim {
namespace {

using test::ScratchDir;

constexpr double kFpsTolerance = 1e-6;          // container frame rate vs requested (1/s)
constexpr double kFlatColourTolerance = 6;      // mean |decoded - written| on flat frames (0-255)
constexpr double kMinRenderedPsnr = 30;         // decoded vs rendered pendulum frame (dB)

// Frame i of a test clip: a flat colour that changes with i plus a white square moving right.
cv::Mat testFrame(int i, cv::Size size) {
    cv::Mat f(size, CV_8UC3, cv::Scalar(20 + 10 * i, 200 - 8 * i, 100));
    cv::rectangle(f, cv::Rect(8 + 6 * i, 8, 24, 24), cv::Scalar(255, 255, 255), cv::FILLED);
    return f;
}

using test::Decoded;
using test::decode;

void expectRoundTrip(const std::string& codec, const std::string& name) {
    ScratchDir dir;
    VideoSettings vs;
    vs.width = 320;
    vs.height = 240;
    vs.fps = 25;
    vs.codec = codec;
    const int n = 20;
    VideoWriter writer;
    writer.open(dir.file(name), vs);
    for (int i = 0; i < n; ++i) writer.write(testFrame(i, {vs.width, vs.height}));
    writer.close();

    const Decoded d = decode(dir.file(name));
    EXPECT_EQ(d.size, cv::Size(vs.width, vs.height));
    EXPECT_NEAR(d.fps, vs.fps, kFpsTolerance);
    EXPECT_EQ(d.reportedCount, n);
    ASSERT_EQ(int(d.frames.size()), n);
    for (int i : {0, n / 2, n - 1}) {
        const cv::Mat expected = testFrame(i, {vs.width, vs.height});
        EXPECT_LT(cv::norm(d.frames[i], expected, cv::NORM_L1) / expected.total() / 3, kFlatColourTolerance)
            << codec << " frame " << i;
    }
    EXPECT_EQ(dir.list(), std::vector<std::string>{name});   // no temporary left
}

TEST(VideoWriter, H264RoundTripKeepsFrameCountSizeFpsAndContent) { expectRoundTrip("h264", "clip.mp4"); }
TEST(VideoWriter, MjpgRoundTripKeepsFrameCountSizeFpsAndContent) { expectRoundTrip("mjpg", "clip.avi"); }

TEST(VideoWriter, RenderedPendulumVideoDecodesToTheRenderedFrames) {
    ScratchDir dir;
    test::PendulumScene scene;
    RenderSettings rs;
    rs.width = 320;
    rs.height = 240;
    rs.camera.position = SimTK::Vec3(0, -0.2, 1.5);
    rs.camera.lookAt = SimTK::Vec3(0, -0.2, 0);
    OffscreenRenderer renderer(rs);
    VideoSettings vs;
    vs.width = rs.width;
    vs.height = rs.height;
    vs.fps = 30;
    VideoWriter writer;
    writer.open(dir.file("pendulum.mp4"), vs);
    std::vector<cv::Mat> rendered;
    for (int i = 0; i < 15; ++i) {
        rendered.push_back(renderer.renderFrame(scene.getSystem(), scene.makeState(0.8 * std::sin(0.4 * i), i / 14.0)));
        writer.write(rendered.back());
    }
    writer.close();
    const Decoded d = decode(dir.file("pendulum.mp4"));
    ASSERT_EQ(d.frames.size(), rendered.size());
    for (size_t i = 0; i < rendered.size(); ++i)
        EXPECT_GT(cv::PSNR(d.frames[i], rendered[i]), kMinRenderedPsnr) << "frame " << i;
}

TEST(VideoWriter, FileAppearsOnlyOnClose) {
    ScratchDir dir;
    VideoSettings vs;
    vs.width = 64;
    vs.height = 48;
    const std::string target = dir.file("clip.mp4");
    {
        VideoWriter writer;
        writer.open(target, vs);
        writer.write(testFrame(0, {64, 48}));
        EXPECT_FALSE(std::filesystem::exists(target));
        EXPECT_TRUE(std::filesystem::exists(writer.getTemporaryPath()));
        EXPECT_EQ(std::filesystem::path(writer.getTemporaryPath()).parent_path(), std::filesystem::path(dir.path()));
    }   // destroyed without close(): discarded
    EXPECT_TRUE(dir.list().empty());

    VideoWriter writer;
    writer.open(target, vs);
    writer.write(testFrame(0, {64, 48}));
    writer.discard();
    EXPECT_TRUE(dir.list().empty());

    writer.open(target, vs);
    writer.write(testFrame(0, {64, 48}));
    writer = VideoWriter();   // assignment discards the unfinished video
    EXPECT_TRUE(dir.list().empty());

    writer.open(target, vs);
    EXPECT_THROW(writer.close(), InputError);   // no frames: nothing saved
    EXPECT_TRUE(dir.list().empty());

    writer.open(target, vs);
    EXPECT_THROW(writer.write(cv::Mat(48, 62, CV_8UC3)), InputError);   // wrong size
    writer.write(testFrame(1, {64, 48}));
    writer.close();
    EXPECT_EQ(dir.list(), std::vector<std::string>{"clip.mp4"});
    EXPECT_FALSE(writer.isOpen());
}

TEST(VideoWriter, FailedWriteLeavesExistingFileUntouched) {
    ScratchDir dir;
    const std::string target = dir.file("clip.mp4");
    std::ofstream(target) << "old";
    VideoSettings vs;
    vs.width = 64;
    vs.height = 48;
    VideoWriter writer;
    writer.open(target, vs);
    writer.write(testFrame(0, {64, 48}));
    writer.discard();
    std::ifstream in(target);
    std::string content;
    in >> content;
    EXPECT_EQ(content, "old");
    EXPECT_EQ(dir.list().size(), 1u);
}

TEST(VideoWriter, BadSettingsThrowBeforeAnythingIsWritten) {
    ScratchDir dir;
    struct Case {
        const char* field;
        void (*mutate)(VideoSettings&);
        const char* expectInMessage;
    };
    const Case cases[] = {
        {"width", [](VideoSettings& v) { v.width = 0; }, "'width' = 0: expected in [16, 4096] (px)"},
        {"height", [](VideoSettings& v) { v.height = 0; }, "'height' = 0"},
        {"width", [](VideoSettings& v) { v.width = 321; }, "even"},
        {"height", [](VideoSettings& v) { v.height = 10000; }, "4096"},
        {"fps", [](VideoSettings& v) { v.fps = 0; }, "'fps' = 0: expected in [1, 240]"},
        {"fps", [](VideoSettings& v) { v.fps = 1e-9; }, "'fps' = 1e-09"},
        {"fps", [](VideoSettings& v) { v.fps = -5; }, "'fps' = -5"},
        {"codec", [](VideoSettings& v) { v.codec = "xvid"; }, "'codec' = 'xvid': expected one of"},
    };
    for (const Case& c : cases) {
        VideoSettings vs;
        c.mutate(vs);
        VideoWriter writer;
        try {
            writer.open(dir.file("clip.mp4"), vs);
            ADD_FAILURE() << "no error for " << c.expectInMessage;
        } catch (const FieldError& e) {
            EXPECT_EQ(e.getField(), c.field);
            EXPECT_NE(std::string(e.what()).find(c.expectInMessage), std::string::npos) << e.what();
        }
        EXPECT_FALSE(writer.isOpen());
        EXPECT_TRUE(dir.list().empty()) << c.expectInMessage;
    }
}

TEST(VideoWriter, BadPathsThrowAndLeaveNoFile) {
    ScratchDir dir;
    const std::string missingRoot = "/armsim-no-such-root-" + std::to_string(::getpid());
    struct Case {
        std::string path;
        std::string expectInMessage;
    };
    const std::vector<Case> cases = {
        {"/proc/x/y.mp4", "directory '/proc/x' does not exist"},
        {missingRoot + "/y.mp4", "directory '" + missingRoot + "' does not exist"},
        {dir.file("clip.avi"), "extension '.avi': expected '.mp4'"},
        {dir.file("sub.mp4"), "is a directory"},
        {"", "path is empty"},
    };
    std::filesystem::create_directory(dir.file("sub.mp4"));
    for (const Case& c : cases) {
        VideoWriter writer;
        try {
            writer.open(c.path, VideoSettings());
            ADD_FAILURE() << "no error for '" << c.path << "'";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(c.expectInMessage), std::string::npos) << e.what();
        }
    }
    EXPECT_FALSE(std::filesystem::exists(missingRoot));
    EXPECT_EQ(dir.list(), std::vector<std::string>{"sub.mp4"});
    EXPECT_TRUE(std::filesystem::is_empty(dir.file("sub.mp4")));
}

TEST(WritePng, RoundTripsExactlyAndRejectsBadPaths) {
    ScratchDir dir;
    const cv::Mat frame = testFrame(3, {96, 64});
    writePng(dir.file("still.png"), frame);
    const cv::Mat back = cv::imread(dir.file("still.png"), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(back.size(), frame.size());
    EXPECT_EQ(cv::norm(back, frame, cv::NORM_INF), 0);
    EXPECT_EQ(dir.list(), std::vector<std::string>{"still.png"});

    EXPECT_THROW(writePng("/proc/x/y.png", frame), InputError);
    EXPECT_THROW(writePng(dir.file("still.jpg"), frame), InputError);
    EXPECT_THROW(writePng(dir.file("empty.png"), cv::Mat()), InputError);
    EXPECT_EQ(dir.list(), std::vector<std::string>{"still.png"});
}

}  // namespace
}  // namespace armsim
