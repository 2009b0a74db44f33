// Videos and stills of OpenSim-model trials (render/osim_video.h) on arm26: the elbow joint drawn where
// the model puts it (projected with the video's camera), the forearm where the trial's angle puts it,
// the muscles blue at rest and red when excited, the frame count, and a table of another model refused.
#include "render/osim_video.h"

#include "basics/errors.h"
#include "model/osim_arm.h"
#include "model/osim_trial.h"
#include "tests/render/render_test_util.h"

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

using namespace armsim;
using armsim::test::ScratchDir;

namespace {

constexpr double kDeg = 3.14159265358979323846 / 180;
constexpr int kWidth = 320, kHeight = 240;

const OsimModel& arm26() {
    static const OsimModel m = readOsimFile(std::string(ARMSIM_ASSET_DIR) + "/models/arm26.osim");
    return m;
}

// The elbow from 20 deg with the flexors fully excited from 0.1 s, the shoulder held.
const Table& freeTrial() {
    static const Table t = [] {
        OsimFreeMovementSettings s;
        s.coordinate = "r_elbow_flex";
        s.initialAngleDeg = 20;
        s.activation = 1;
        s.onset = 0.1;
        s.duration = 0.3;
        s.sampleRate = 100;
        return runOsimFreeMovement(arm26(), s);
    }();
    return t;
}

OsimVideoSettings stillAt(const ScratchDir& dir, double t, const std::string& name) {
    OsimVideoSettings v;
    v.render.width = kWidth;
    v.render.height = kHeight;
    v.render.supersample = 1;
    v.overlay = false;
    v.stillTime = t;
    v.stillPath = dir.file(name);
    v.tableName = "free.csv";
    return v;
}

// Where a body-fixed point of the model is at the table's row, in pixels of the video's camera.
cv::Point project(const Camera& camera, const char* body, double angleDeg, bool jointCentre) {
    const OsimArm arm(arm26());
    SimTK::State s = arm.getDefaultState();
    arm.setCoordinateValue(s, arm.findCoordinate("r_elbow_flex"), angleDeg * kDeg);
    arm.getSystem().realize(s, SimTK::Stage::Position);
    const SimTK::MobilizedBody& b = arm.getCoordinateBody(arm.findCoordinate("r_elbow_flex"));
    (void)body;
    const SimTK::Vec3 p = jointCentre ? b.getBodyTransform(s) * b.getOutboardFrame(s).p()
                                      : b.getBodyTransform(s) * (2.0 * b.getBodyMassCenterStation(s) - b.getOutboardFrame(s).p());
    const SimTK::Vec2 px = projectToPixel(camera, kWidth, kHeight, p);
    return {int(px[0]), int(px[1])};
}

// Pixels whose red channel exceeds the blue by more than 80 (an excited muscle), and the reverse.
std::pair<int, int> countRedBlue(const cv::Mat& bgr) {
    int red = 0, blue = 0;
    for (int y = 0; y < bgr.rows; ++y)
        for (int x = 0; x < bgr.cols; ++x) {
            const cv::Vec3b c = bgr.at<cv::Vec3b>(y, x);
            red += c[2] > c[0] + 80;
            blue += c[0] > c[2] + 80;
        }
    return {red, blue};
}

bool isBackground(const cv::Mat& bgr, cv::Point p) {
    const cv::Vec3b c = bgr.at<cv::Vec3b>(p);
    return c[0] > 235 && c[1] > 235 && c[2] > 235;   // the background is 0.96 grey (245)
}

}  // namespace

TEST(OsimVideo, StillsDrawTheModelWhereTheTrialPutsIt) {
    ScratchDir dir;
    const Table& t = freeTrial();
    const OsimVideoSettings early = stillAt(dir, 0.0, "early.png"), late = stillAt(dir, 0.3, "late.png");
    renderOsimTrialVideo(arm26(), t, early);
    renderOsimTrialVideo(arm26(), t, late);
    const cv::Mat a = cv::imread(early.stillPath), b = cv::imread(late.stillPath);
    ASSERT_EQ(a.cols, kWidth);
    const Camera camera = calcOsimTrialCamera(arm26(), t, early);
    const double angle0 = t.get(0, "r_elbow_flex_deg"), angle1 = t.get(t.getNumRows() - 1, "r_elbow_flex_deg");
    ASSERT_GT(angle1 - angle0, 30.0) << "the flexors flex the elbow";
    // The elbow joint (held in place by the shoulder) is drawn at its projection in both stills; the
    // forearm's end where the angle puts it: drawn there in its own still, background in the other.
    const cv::Point elbow = project(camera, "r_ulna_radius_hand", angle0, true);
    EXPECT_EQ(elbow, project(camera, "r_ulna_radius_hand", angle1, true));
    EXPECT_FALSE(isBackground(a, elbow));
    EXPECT_FALSE(isBackground(b, elbow));
    const cv::Point hand0 = project(camera, "r_ulna_radius_hand", angle0, false),
                    hand1 = project(camera, "r_ulna_radius_hand", angle1, false);
    ASSERT_GT(cv::norm(hand0 - hand1), 20.0);
    // The bone ends at the hand point; a pixel just inside it along the bone is drawn.
    auto inside = [&](cv::Point end) { return end + (elbow - end) * 0.05; };
    EXPECT_FALSE(isBackground(a, inside(hand0)));
    EXPECT_TRUE(isBackground(a, hand1));
    EXPECT_FALSE(isBackground(b, inside(hand1)));
    EXPECT_TRUE(isBackground(b, hand0));
    // Muscles: blue at rest (no red), red once excited.
    const auto [redA, blueA] = countRedBlue(a);
    const auto [redB, blueB] = countRedBlue(b);
    EXPECT_EQ(redA, 0);
    EXPECT_GT(blueA, 50);
    EXPECT_GT(redB, 50);
}

TEST(OsimVideo, VideoHasAFramePerIntervalAndATableOfAnotherModelIsRefused) {
    ScratchDir dir;
    OsimVideoSettings v;
    v.render.width = kWidth;
    v.render.height = kHeight;
    v.render.supersample = 1;
    v.fps = 20;
    v.videoPath = dir.file("free.mp4");
    v.tableName = "free.csv";
    const OsimVideoResult r = renderOsimTrialVideo(arm26(), freeTrial(), v);
    EXPECT_EQ(r.frames, 7);   // 0.3 s at 20 frames per second: 0, 0.05, ..., 0.3
    EXPECT_EQ(test::decode(v.videoPath).frames.size(), 7u);
    Table other({"time_s", "excitation", "r_knee_deg"});
    other.appendRow({0, 0, 10});
    v.videoPath = dir.file("other.mp4");
    try {
        renderOsimTrialVideo(arm26(), other, v);
        ADD_FAILURE() << "a table of another model was rendered";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("free.csv: no <coordinate>_deg column names a coordinate of arm26"),
                  std::string::npos) << e.what();
    }
    EXPECT_FALSE(std::filesystem::exists(v.videoPath));
}
