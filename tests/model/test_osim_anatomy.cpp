// An OpenSim model scored against anatomy targets (model/osim_anatomy.h), each score a second way: moment
// arms against central differences of the path length, the flexion MVC against the end of an integrated
// isometric trial (model/osim_trial.h), the optimum angle against the steady fibre length there; what the
// file cannot say (volumes, shares without every named family, forearm targets) is not scored.
#include "model/osim_anatomy.h"

#include "model/osim_arm.h"
#include "model/osim_trial.h"
#include "tests/support/temp_files.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

using namespace armsim;

namespace {

constexpr double kDeg = 3.14159265358979323846 / 180;

const OsimModel& arm26() {
    static const OsimModel m = readOsimFile(std::string(ARMSIM_ASSET_DIR) + "/models/arm26.osim");
    return m;
}

std::vector<AnatomyTarget> writeTargets(const std::string& body) {
    const auto dir = armsim::testing::makeFreshDir("osim_anatomy", ::testing::UnitTest::GetInstance()->current_test_info()->name());
    const std::string path = (dir / "targets.yaml").string();
    std::ofstream(path) << "targets:\n" << body;
    return loadAnatomyTargets(path);
}

}  // namespace

TEST(OsimAnatomy, ScoresEqualASecondMethodAndWhatTheFileCannotSayIsNotScored) {
    const std::vector<AnatomyTarget> targets = writeTargets(
        "  - {kind: moment_arm, muscle: BRA, flexion_deg: 70, lower: 0, upper: 100, source: a}\n"
        "  - {kind: mvc, direction: flexion, flexion_deg: 80, lower: 0, upper: 200, source: b}\n"
        "  - {kind: optimum_angle, muscle: BICshort, lower: 0, upper: 180, source: c}\n"
        "  - {kind: volume, muscle: BIC, lower: 1, upper: 1000, source: d}\n"
        "  - {kind: share, muscle: BIC, flexion_deg: 90, lower: 0, upper: 1, source: e}\n"
        "  - {kind: share, muscle: BRD, flexion_deg: 90, lower: 0, upper: 1, source: f}\n"
        "  - {kind: forearm_mvc, direction: supination, flexion_deg: 90, rotation_deg: 0, lower: 0, upper: 100, source: g}\n");
    const std::array<double, 2> range = getOsimCoordinateRangeDeg(arm26(), "r_elbow_flex");
    EXPECT_EQ(range[0], 0);
    EXPECT_EQ(range[1], 130);
    const AnatomyCurves c = calcOsimAnatomyCurves(arm26(), "r_elbow_flex", findAnatomyAngles(targets, range[0], range[1]));
    const std::vector<TargetScore> scores = scoreAnatomyCurves(c, targets);
    ASSERT_EQ(scores.size(), 3u);   // volume (no masses), shares (no BRD in arm26) and the forearm: not scored

    // Moment arm: -dP/dq by central differences.
    const OsimArm arm(arm26());
    SimTK::State s = arm.getDefaultState();
    auto length = [&](double deg) {
        arm.setCoordinateValue(s, 1, deg * kDeg);
        arm.getSystem().realize(s, SimTK::Stage::Position);
        return arm.calcPathLength(s, 5);
    };
    const double h = 1e-4;
    EXPECT_EQ(scores[0].muscle, "BRA");
    EXPECT_NEAR(scores[0].value, -(length(70 + h) - length(70 - h)) / (2 * h * kDeg), 1e-8);

    // MVC: the end of a 3 s integrated flexion trial at 80 deg (raw torque, passive included).
    OsimIsometricTrialSettings trial;
    trial.coordinate = "r_elbow_flex";
    trial.angleDeg = 80;
    trial.holdDuration = 3;
    trial.averagingWindow = 0.1;
    trial.sampleRate = 100;
    const double integrated = runOsimIsometricTrial(arm26(), trial).summary.meanMuscleTorque;
    EXPECT_NEAR(scores[1].value, integrated, 2e-4 * integrated);
    EXPECT_GT(scores[1].value, 50);   // arm26: about 64 N m

    // Optimum angle: the steady fibre length is L0 there (linear interpolation over 1 deg).
    ASSERT_TRUE(std::isfinite(scores[2].value));
    const AnatomyCurves at = calcOsimAnatomyCurves(arm26(), "r_elbow_flex", {scores[2].value});
    EXPECT_NEAR(at.full.points[0][4].fibreLength, 1.0, 2e-3);
    EXPECT_EQ(at.muscles[4], "BICshort");
}

// Outside the coordinate's range an angle is refused, naming the range (a grid's rounding error past the
// end is the end); an unknown coordinate names the model's.
TEST(OsimAnatomy, BadAnglesAndCoordinatesAreNamed) {
    const AnatomyCurves end = calcOsimAnatomyCurves(arm26(), "r_elbow_flex", {130 + 5e-10});
    EXPECT_EQ(end.flexion.totalTorque[0], calcOsimAnatomyCurves(arm26(), "r_elbow_flex", {130}).flexion.totalTorque[0]);
    try {
        calcOsimAnatomyCurves(arm26(), "r_elbow_flex", {140});
        ADD_FAILURE() << "accepted 140 deg";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("outside r_elbow_flex's range [0, 130] deg"), std::string::npos) << e.what();
    }
    try {
        calcOsimAnatomyCurves(arm26(), "", {40});
        ADD_FAILURE() << "accepted no coordinate";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("r_shoulder_elev, r_elbow_flex"), std::string::npos) << e.what();
    }
}
