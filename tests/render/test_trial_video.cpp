// Tests of trial videos: replay of recorded trial tables into the arm, pixel checks on the rendered
// arm (forearm motion, muscle colour, nothing outside the scene), the written video, and bad input.
// Runs without an X display.
#include "basics/errors.h"
#include "model/geometry.h"
#include "model/trial.h"
#include "render/trial_video.h"
#include "render/video.h"
#include "tests/render/render_test_util.h"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include <cmath>
#include <cstdlib>

namespace armsim {
namespace {

using test::ScratchDir;
using SimTK::Vec3;

constexpr double kIsoAngleDeg = 90;             // isometric trial angle
constexpr double kIsoRest = 0.2, kIsoHold = 0.6;  // (s)
constexpr double kFreeOnset = 0.1, kFreeDuration = 0.6;  // free movement: U = 1 from onset (s)
constexpr double kSampleRate = 200;             // table rows per second (Hz)
constexpr int kWidth = 640, kHeight = 360;      // test frames (px)
constexpr double kFps = 25;                     // test video rate (1/s)
constexpr double kFpsTolerance = 1e-6;          // container frame rate vs requested (1/s)
constexpr double kMinDecodedPsnr = 28;          // decoded H.264 frame vs the rendered frame (dB)
constexpr double kMinSwingDeg = 60;             // the free movement must move at least this much
constexpr double kMinCentroidShiftPx = 20;      // skin-pixel centroid shift over the free movement
constexpr double kMinDirectionCosine = 0.7;     // ... in the direction the hand moved on screen
constexpr int kDominanceMargin = 80;            // colour channel lead that identifies a hue (0-255)
constexpr int kLineColourTolerance = 2;         // line centre pixel vs the muscle's colour (0-255)
constexpr int kEdgeMarginPx = 6;                // half the widest line (8 px) + anti-aliasing spill
constexpr int kMinFrameMarginPx = 4;            // the scene box stays this far inside the frame

// Background with distinct channels (multiples of 1/255) so exact comparisons work.
const Vec3 kBackground(240 / 255.0, 236 / 255.0, 232 / 255.0);

class TrialVideo : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        ::unsetenv("DISPLAY");
        setup_ = new ArmSetup(ArmSetup::loadDefault());
        IsometricTrialSettings iso;
        iso.elbowAngle = degToRad(kIsoAngleDeg);
        iso.restDuration = kIsoRest;
        iso.holdDuration = kIsoHold;
        iso.averagingWindow = 0.5 * kIsoHold;
        iso.sampleRate = kSampleRate;
        isometric_ = new Table(runIsometricTrial(*setup_, iso).series);
        FreeMovementSettings free;
        free.activation = ActivationProfile::step(kFreeOnset, 0.0, 1.0);
        free.duration = kFreeDuration;
        free.sampleRate = kSampleRate;
        free_ = new Table(runFreeMovement(*setup_, free));
    }
    static void TearDownTestSuite() {
        delete setup_;
        delete isometric_;
        delete free_;
    }

    static TrialVideoSettings plainSettings() {
        TrialVideoSettings v;
        v.render.width = kWidth;
        v.render.height = kHeight;
        v.render.background = kBackground;
        v.fps = kFps;
        v.overlay = false;
        return v;
    }

    static ArmSetup* setup_;
    static Table* isometric_;
    static Table* free_;
};
ArmSetup* TrialVideo::setup_ = nullptr;
Table* TrialVideo::isometric_ = nullptr;
Table* TrialVideo::free_ = nullptr;

// Skin-coloured (upper arm, forearm, hand): R > G > B with both ratios near the skin's 0.82; the
// other scene colours (bone, strap, floor, transducer, muscle, arrow, background) fail this.
bool isSkin(const cv::Vec3b& p) {
    const double b = p[0], g = p[1], r = p[2];
    return r > 60 && g > 0.72 * r && g < 0.90 * r && b > 0.72 * g && b < 0.90 * g;
}

cv::Point2d skinCentroid(const cv::Mat& frame, int* count) {
    double sx = 0, sy = 0;
    int n = 0;
    for (int y = 0; y < frame.rows; ++y)
        for (int x = 0; x < frame.cols; ++x)
            if (isSkin(frame.at<cv::Vec3b>(y, x))) sx += x + 0.5, sy += y + 0.5, ++n;
    *count = n;
    return n ? cv::Point2d(sx / n, sy / n) : cv::Point2d(-1, -1);
}

cv::Point2d toPoint(const SimTK::Vec2& p) { return {p[0], p[1]}; }

// Pixels on the projected muscle line at fractions from the origin to the insertion.
std::vector<cv::Vec3b> sampleMuscle(TrialRenderer& r, int row, const cv::Mat& frame) {
    const SimTK::State& s = r.setRow(row);
    const ArmModel& arm = r.getModel().getArm();
    const Vec3 o = arm.getUpperArm().findStationLocationInGround(s, arm.getOriginStation());
    const Vec3 i = arm.getForearm().findStationLocationInGround(s, arm.getInsertionStation());
    std::vector<cv::Vec3b> px;
    for (double f = 0.15; f <= 0.851; f += 0.05)
        px.push_back(frame.at<cv::Vec3b>(test::pixelOf(r.getRenderSettings(), o + f * (i - o))));
    return px;
}

using test::Decoded;
using test::decode;

// ---------------------------------------------------------------------------------------------

TEST_F(TrialVideo, RendersWithoutDisplay) {
    ASSERT_EQ(std::getenv("DISPLAY"), nullptr);
    TrialRenderer r(*setup_, *free_, plainSettings());
    const cv::Mat frame = r.renderRow(0);
    EXPECT_EQ(frame.size(), cv::Size(kWidth, kHeight));
    EXPECT_EQ(frame.type(), CV_8UC3);
}

TEST_F(TrialVideo, ReplaySetsTheRecordedState) {
    TrialRenderer r(*setup_, *free_, plainSettings());
    const int row = free_->getNumRows() / 2;
    const SimTK::State& s = r.setRow(row);
    EXPECT_DOUBLE_EQ(s.getTime(), free_->get(row, "time_s"));
    EXPECT_NEAR(radToDeg(r.getModel().getArm().getElbowAngle(s)), free_->get(row, "elbow_angle_deg"), 1e-9);
    // The muscle force recomputed from the replayed state is the recorded one.
    EXPECT_NEAR(r.getModel().getBiceps().getForce(s), free_->get(row, "muscle_force_N"),
                1e-6 * std::abs(free_->get(row, "muscle_force_N")) + 1e-6);
}

TEST_F(TrialVideo, FramesAreDeterministic) {
    TrialRenderer a(*setup_, *free_, plainSettings()), b(*setup_, *free_, plainSettings());
    const int row = free_->getNumRows() - 10;
    const cv::Mat first = a.renderRow(row);
    a.renderRow(3);
    EXPECT_EQ(cv::norm(first, a.renderRow(row), cv::NORM_INF), 0);
    EXPECT_EQ(cv::norm(first, b.renderRow(row), cv::NORM_INF), 0);
    EXPECT_GT(cv::norm(first, a.renderRow(3), cv::NORM_INF), 0);   // and a different state differs
}

TEST_F(TrialVideo, ForearmPixelsFollowTheFreeMovement) {
    const int last = free_->getNumRows() - 1;
    const double swing = free_->get(0, "elbow_angle_deg") - free_->get(last, "elbow_angle_deg");
    ASSERT_GT(swing, kMinSwingDeg) << "the test trial does not flex the elbow";
    TrialRenderer r(*setup_, *free_, plainSettings());
    int n0 = 0, n1 = 0;
    const cv::Point2d c0 = skinCentroid(r.renderRow(0), &n0);
    const cv::Point2d c1 = skinCentroid(r.renderRow(last), &n1);
    ASSERT_GT(n0, 1000);
    ASSERT_GT(n1, 1000);
    // Where the hand went on screen.
    const ArmModel& arm = r.getModel().getArm();
    const Vec3 hand0 = arm.getForearm().findStationLocationInGround(r.setRow(0), arm.getHandStation());
    const Vec3 hand1 = arm.getForearm().findStationLocationInGround(r.setRow(last), arm.getHandStation());
    const Camera& cam = r.getRenderSettings().camera;
    const cv::Point2d handShift = toPoint(projectToPixel(cam, kWidth, kHeight, hand1)) -
                                  toPoint(projectToPixel(cam, kWidth, kHeight, hand0));
    const cv::Point2d shift = c1 - c0;
    const double length = std::hypot(shift.x, shift.y);
    EXPECT_GT(length, kMinCentroidShiftPx);
    EXPECT_GT(shift.dot(handShift) / (length * std::hypot(handShift.x, handShift.y)), kMinDirectionCosine)
        << "centroid moved " << shift << ", hand moved " << handShift;
}

TEST_F(TrialVideo, MuscleColourFollowsActivation) {
    TrialRenderer r(*setup_, *isometric_, plainSettings());
    const int rest = r.findRow(0.5 * kIsoRest), active = isometric_->getNumRows() - 1;
    ASSERT_EQ(isometric_->get(rest, "activation"), 0.0);
    ASSERT_EQ(isometric_->get(active, "activation"), 1.0);
    const cv::Mat restFrame = r.renderRow(rest), activeFrame = r.renderRow(active);
    for (const cv::Vec3b& p : sampleMuscle(r, rest, restFrame))
        EXPECT_TRUE(test::dominates(p, 0, kDominanceMargin)) << p;
    for (const cv::Vec3b& p : sampleMuscle(r, active, activeFrame))
        EXPECT_TRUE(test::dominates(p, 2, kDominanceMargin)) << p;
    // The line's centre has exactly the muscle's own colour for its active fraction.
    for (int row : {rest, active}) {
        const cv::Mat frame = r.renderRow(row);
        const SimTK::State& s = r.setRow(row);
        const double af = r.getModel().getBiceps().calcOutputs(s).activeFraction;
        const cv::Vec3b expected = test::toBgr8(MuscleForce::calcActivationColor(af));
        const std::vector<cv::Vec3b> px = sampleMuscle(r, row, frame);
        const cv::Vec3b mid = px[px.size() / 2];
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(mid[c], expected[c], kLineColourTolerance) << "row " << row;
    }
}

TEST_F(TrialVideo, ForceColouringFollowsTheForce) {
    TrialVideoSettings v = plainSettings();
    v.scene.muscleColoring = MuscleColoring::Force;
    TrialRenderer r(*setup_, *isometric_, v);
    const int rest = r.findRow(0.5 * kIsoRest), active = isometric_->getNumRows() - 1;
    ASSERT_LT(isometric_->get(rest, "muscle_force_N"), 0.05 * isometric_->get(active, "muscle_force_N"));
    const cv::Mat restFrame = r.renderRow(rest), activeFrame = r.renderRow(active);
    for (const cv::Vec3b& p : sampleMuscle(r, rest, restFrame))
        EXPECT_TRUE(test::dominates(p, 0, kDominanceMargin)) << p;
    for (const cv::Vec3b& p : sampleMuscle(r, active, activeFrame))
        EXPECT_TRUE(test::dominates(p, 2, kDominanceMargin)) << p;
}

TEST_F(TrialVideo, NothingIsDrawnOutsideTheSceneBox) {
    for (const Table* table : {isometric_, free_}) {
        TrialRenderer r(*setup_, *table, plainSettings());
        const RenderSettings& s = r.getRenderSettings();
        const auto [lo, hi] = r.calcSceneBox();
        double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
        for (int i = 0; i < 8; ++i) {
            const Vec3 corner(i & 1 ? hi[0] : lo[0], i & 2 ? hi[1] : lo[1], i & 4 ? hi[2] : lo[2]);
            const SimTK::Vec2 p = projectToPixel(s.camera, s.width, s.height, corner);
            x0 = std::min(x0, p[0]), x1 = std::max(x1, p[0]), y0 = std::min(y0, p[1]), y1 = std::max(y1, p[1]);
        }
        const cv::Rect inside(cv::Point(int(x0) - kEdgeMarginPx, int(y0) - kEdgeMarginPx),
                              cv::Point(int(x1) + kEdgeMarginPx + 1, int(y1) + kEdgeMarginPx + 1));
        // The camera frames the whole scene, and a real margin remains around it.
        EXPECT_GE(inside.x, kMinFrameMarginPx);
        EXPECT_GE(inside.y, kMinFrameMarginPx);
        EXPECT_LE(inside.br().x, s.width - kMinFrameMarginPx);
        EXPECT_LE(inside.br().y, s.height - kMinFrameMarginPx);
        ASSERT_LT(inside.area(), 0.8 * s.width * s.height);
        const cv::Vec3b bg = test::toBgr8(kBackground);
        for (int row : {0, table->getNumRows() / 3, 2 * table->getNumRows() / 3, table->getNumRows() - 1}) {
            const cv::Mat frame = r.renderRow(row);
            const test::DrawnPixels drawn = test::countDrawn(frame, bg, inside);
            EXPECT_EQ(drawn.outside, 0) << "row " << row;
            EXPECT_GT(drawn.inside, 2000) << "row " << row;
        }
    }
}

TEST_F(TrialVideo, OverlayStaysInTheTopPanelsAndShowsThePlots) {
    TrialVideoSettings v = plainSettings();
    v.render.width = 1280;   // overlay sizes are for 720 px frames: no scaling here
    v.render.height = 720;
    TrialRenderer plain(*setup_, *isometric_, v);
    v.overlay = true;
    TrialRenderer withOverlay(*setup_, *isometric_, v);
    const int row = isometric_->getNumRows() - 1;
    const cv::Mat a = plain.renderRow(row), b = withOverlay.renderRow(row);
    const cv::Rect bottom(0, v.render.height / 2, v.render.width, v.render.height / 2);
    EXPECT_EQ(cv::norm(a(bottom), b(bottom), cv::NORM_INF), 0);
    const std::vector<cv::Rect> plots = calcPlotAreas(a.size(), 2, v.overlayStyle);
    ASSERT_EQ(plots.size(), 2u);
    for (const cv::Rect& p : plots) EXPECT_GT(cv::norm(a(p), b(p), cv::NORM_L1), 0);
}

TEST_F(TrialVideo, VideoReopensWithExpectedFramesSizeAndRate) {
    ScratchDir dir;
    TrialVideoSettings v = plainSettings();
    v.overlay = true;
    v.videoPath = dir.file("free.mp4");
    const TrialVideoResult res = renderTrialVideo(*setup_, *free_, v);
    const int expected = int(std::floor(kFreeDuration * kFps + 1e-9)) + 1;   // both ends
    EXPECT_EQ(res.frames, expected);
    const Decoded d = decode(v.videoPath);
    EXPECT_EQ(d.size, cv::Size(kWidth, kHeight));
    EXPECT_NEAR(d.fps, kFps, kFpsTolerance);
    EXPECT_EQ(d.reportedCount, expected);
    ASSERT_EQ(int(d.frames.size()), expected);
    // Frames are the rendered rows at the frame times, in order.
    TrialRenderer r(*setup_, *free_, v);
    const cv::Mat first = r.renderRow(r.findRow(0)), last = r.renderRow(r.findRow((expected - 1) / kFps));
    EXPECT_GT(cv::PSNR(d.frames.front(), first), kMinDecodedPsnr);
    EXPECT_GT(cv::PSNR(d.frames.back(), last), kMinDecodedPsnr);
    EXPECT_LT(cv::PSNR(d.frames.front(), last), kMinDecodedPsnr);
    EXPECT_EQ(dir.list(), std::vector<std::string>{"free.mp4"});
}

TEST_F(TrialVideo, PlaybackSpeedAndMjpgAndStill) {
    ScratchDir dir;
    TrialVideoSettings v = plainSettings();
    v.codec = "mjpg";
    v.playbackSpeed = 0.5;   // slow motion: twice the frames
    v.videoPath = dir.file("iso.avi");
    v.stillTime = kIsoRest + kIsoHold;
    v.stillPath = dir.file("still.png");
    const TrialVideoResult res = renderTrialVideo(*setup_, *isometric_, v);
    const int expected = int(std::floor((kIsoRest + kIsoHold) * kFps / 0.5 + 1e-9)) + 1;
    EXPECT_EQ(res.frames, expected);
    const Decoded d = decode(v.videoPath);
    EXPECT_EQ(int(d.frames.size()), expected);
    EXPECT_NEAR(d.fps, kFps, kFpsTolerance);
    const cv::Mat still = cv::imread(v.stillPath, cv::IMREAD_COLOR);
    ASSERT_FALSE(still.empty());
    TrialRenderer r(*setup_, *isometric_, v);
    EXPECT_EQ(cv::norm(still, r.renderRow(isometric_->getNumRows() - 1), cv::NORM_INF), 0);  // lossless PNG
}

TEST_F(TrialVideo, BadSettingsGiveNamedErrorsAndNoFile) {
    ScratchDir dir;
    struct Case {
        const char* expectInMessage;
        void (*mutate)(TrialVideoSettings&, const std::string& dir);
    };
    const Case cases[] = {
        {"'width'", [](TrialVideoSettings& v, const std::string&) { v.render.width = 0; }},
        {"'height'", [](TrialVideoSettings& v, const std::string&) { v.render.height = 0; }},
        {"vp9", [](TrialVideoSettings& v, const std::string&) { v.codec = "vp9"; }},
        {"'fps'", [](TrialVideoSettings& v, const std::string&) { v.fps = 0; }},
        {"playback_speed", [](TrialVideoSettings& v, const std::string&) { v.playbackSpeed = -1; }},
        {"no-such-dir", [](TrialVideoSettings& v, const std::string& d) { v.videoPath = d + "/no-such-dir/v.mp4"; }},
        {"'.avi'", [](TrialVideoSettings& v, const std::string& d) { v.videoPath = d + "/v.avi"; }},
        {"still.jpg",
         [](TrialVideoSettings& v, const std::string& d) { v.stillTime = 0.1, v.stillPath = d + "/still.jpg"; }},
        {"still_at", [](TrialVideoSettings& v, const std::string& d) { v.stillTime = 99; v.stillPath = d + "/s.png"; }},
        {"still_at", [](TrialVideoSettings& v, const std::string& d) { v.stillPath = d + "/s.png"; }},
        {"nothing to render", [](TrialVideoSettings& v, const std::string&) { v.videoPath.clear(); }},
    };
    for (const Case& c : cases) {
        TrialVideoSettings v = plainSettings();
        v.videoPath = dir.file("v.mp4");
        c.mutate(v, dir.path());
        try {
            renderTrialVideo(*setup_, *free_, v);
            ADD_FAILURE() << "no error for " << c.expectInMessage;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(c.expectInMessage), std::string::npos) << e.what();
        }
        EXPECT_TRUE(dir.list().empty()) << c.expectInMessage;
    }
}

TEST_F(TrialVideo, BadTablesNameTheColumnOrLine) {
    ScratchDir dir;
    TrialVideoSettings v = plainSettings();
    v.videoPath = dir.file("v.mp4");
    v.tableName = "recorded.csv";
    // Without a muscle state column.
    std::vector<std::string> names;
    for (const std::string& n : free_->getColumnNames())
        if (n != "state_L") names.push_back(n);
    Table noState(names);
    for (int i = 0; i < free_->getNumRows(); ++i) {
        std::vector<double> row;
        for (const std::string& n : names) row.push_back(free_->get(i, n));
        noState.appendRow(row);
    }
    try {
        renderTrialVideo(*setup_, noState, v);
        ADD_FAILURE() << "no error for a missing state column";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("'state_L'"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("recorded.csv"), std::string::npos) << e.what();
    }
    // Time going backwards.
    Table backwards(free_->getColumnNames());
    for (int i : {0, 2, 1}) backwards.appendRow(free_->getRow(i));
    try {
        renderTrialVideo(*setup_, backwards, v);
        ADD_FAILURE() << "no error for decreasing time";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("row 3: time_s"), std::string::npos) << e.what();
    }
    // A strap arrow for a free movement.
    v.scene.forceArrow = ForceArrowKind::Strap;
    EXPECT_THROW(renderTrialVideo(*setup_, *free_, v), InputError);
    EXPECT_TRUE(dir.list().empty());
}

}  // namespace
}  // namespace armsim
