// Anatomy targets: the loader's errors, and each kind of score checked a second way (path-length
// differences for moment arms, mass / density for volumes, the steady fibre length at the optimum angle).
#include "basics/errors.h"
#include "model/anatomy_targets.h"
#include "model/mvc_curve.h"
#include "model/geometry.h"
#include "model/muscle_arm.h"
#include "tests/support/temp_files.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

using namespace armsim;

namespace {

constexpr double kMomentArmTol = 1e-6;   // m: virtual-work moment arm vs central difference of the path
constexpr double kFibreLengthTol = 2e-3; // L/L0 at the reported optimum angle (linear interpolation over 1 deg)

std::string writeTargets(const std::string& body) {
    const auto dir = armsim::testing::makeFreshDir("anatomy_targets", ::testing::UnitTest::GetInstance()->current_test_info()->name());
    const std::string path = (dir / "targets.yaml").string();
    std::ofstream(path) << "targets:\n" << body;
    return path;
}

const ArmSetup& elbow() {
    static const ArmSetup s = loadModel("elbow");
    return s;
}

}  // namespace

TEST(AnatomyTargets, LoaderNamesFileLineFieldAndValue) {
    try {
        loadAnatomyTargets(writeTargets("  - {kind: moment_arm, muscle: BRA, flexion_deg: 90, lower: 30, upper: 20, source: x}\n"));
        FAIL() << "lower > upper accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("targets.yaml:2"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("'upper' = 20 mm"), std::string::npos) << e.what();
    }
    EXPECT_THROW(loadAnatomyTargets(writeTargets("  - {kind: moment, muscle: BRA, flexion_deg: 90, lower: 1, upper: 2, source: x}\n")), InputError);
    EXPECT_THROW(loadAnatomyTargets(writeTargets("  - {kind: volume, muscle: BRA, lower: 1, upper: 2, sourse: x}\n")), InputError);
    try {   // a point without tolerance: only the value itself would pass, and a fit has no unit for it
        loadAnatomyTargets(writeTargets("  - {kind: share, muscle: BIC, flexion_deg: 90, lower: 0.3, upper: 0.3, source: x}\n"));
        FAIL() << "point band without tolerance accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("targets.yaml:2"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("needs a tolerance"), std::string::npos) << e.what();
    }
    EXPECT_NO_THROW(loadDefaultAnatomyTargets());
}

TEST(AnatomyTargets, ScoresEqualASecondMethodAndBandsDecidePass) {
    const ArmSetup& s = elbow();
    const int bra = s.findMuscle("BRA");
    // Moment arm: virtual work vs -dP/dtheta (central difference, 0.01 deg).
    const double h = 0.01;
    const MvcGeometry g = calcMvcGeometry(s, {90 - h, 90, 90 + h});
    const double fd = (g.pathLength[0][bra] - g.pathLength[2][bra]) / (2 * h * M_PI / 180);
    const double value = g.momentArm[1][bra];
    EXPECT_NEAR(value, fd, kMomentArmTol);
    // A band around the value passes, one beside it fails; tolerance widens it.
    const std::string mm = std::to_string(1000 * value);
    const auto scores = scoreAnatomy(s, loadAnatomyTargets(writeTargets(
        "  - {kind: moment_arm, muscle: BRA, flexion_deg: 90, lower: " + std::to_string(1000 * value - 0.1) +
        ", upper: " + std::to_string(1000 * value + 0.1) + ", source: a}\n"
        "  - {kind: moment_arm, muscle: BRA, flexion_deg: 90, lower: " + std::to_string(1000 * value + 1) +
        ", upper: " + std::to_string(1000 * value + 2) + ", source: b}\n"
        "  - {kind: moment_arm, muscle: BRA, flexion_deg: 90, lower: " + std::to_string(1000 * value + 1) +
        ", upper: " + std::to_string(1000 * value + 2) + ", tolerance: 1.5, source: c}\n"
        "  - {kind: volume, muscle: BIC, lower: 1, upper: 1e5, source: d}\n"
        "  - {kind: optimum_angle, muscle: BICshort, lower: 0, upper: 180, source: e}\n"
        "  - {kind: moment_arm, muscle: XYZ, flexion_deg: 90, lower: 0, upper: 1, source: f}\n")));
    ASSERT_EQ(scores.size(), 5u);  // the target naming no model muscle is skipped
    EXPECT_NEAR(scores[0].value, value, 1e-12);
    EXPECT_TRUE(scores[0].pass);
    EXPECT_FALSE(scores[1].pass);
    EXPECT_TRUE(scores[2].pass);
    // Volume: both biceps heads' mass / density.
    double v = 0;
    for (const char* m : {"BIClong", "BICshort"}) {
        const MuscleParameters& p = s.muscles[s.findMuscle(m)].params;
        v += p.mass / p.coefficients.density;
    }
    EXPECT_NEAR(scores[3].value, v, 1e-12 * v);
    // Optimum angle: the steady fibre length at a full flexion MVC is L0 there.
    ASSERT_TRUE(std::isfinite(scores[4].value));
    const SteadyMvcCurve c = calcSteadyMvcCurve(s, MuscleGroup::Flexor, SubjectEffort{1, 0}, {scores[4].value});
    EXPECT_NEAR(c.points[0][s.findMuscle("BICshort")].fibreLength, 1.0, kFibreLengthTol);
}

// Shares are taken among the families the share targets name (as Kawakami 1994's, which add up to 1):
// with BIC and BRA named, the two shares add up to 1 although BRD and PT also flex; each equals its
// torque over the pair's, from the steady flexion curve at the model's effort.
TEST(AnatomyTargets, SharesAreAmongTheNamedFamilies) {
    const ArmSetup twin = loadModel("twin");
    const auto scores = scoreAnatomy(twin, loadAnatomyTargets(writeTargets(
        "  - {kind: share, muscle: BIC, flexion_deg: 90, lower: 0, upper: 1, source: a}\n"
        "  - {kind: share, muscle: BRA, flexion_deg: 90, lower: 0, upper: 1, source: b}\n")));
    ASSERT_EQ(scores.size(), 2u);
    EXPECT_NEAR(scores[0].value + scores[1].value, 1.0, 1e-12);
    const SteadyMvcCurve c = calcSteadyMvcCurve(twin, MuscleGroup::Flexor, twin.effort, {90});
    const double bic = c.points[0][twin.findMuscle("BIClong")].torque + c.points[0][twin.findMuscle("BICshort")].torque;
    const double bra = c.points[0][twin.findMuscle("BRA")].torque;
    EXPECT_GT(c.points[0][twin.findMuscle("BRD")].torque, 0.1 * bra);  // a flexor the shares leave out
    EXPECT_NEAR(scores[0].value, bic / (bic + bra), 1e-9);
}

// Forearm efforts two ways (issue 28): the steady curve's supination torque (sum of forearm moment arm x
// tendon force) against the torque Simbody's forearm lock must apply to hold the radius still with every
// muscle at that steady state (gravity off), and the posture ratio against two flexion curves.
TEST(AnatomyTargets, ForearmTorqueEqualsTheForearmLockReaction) {
    constexpr double kReactionTol = 1e-6;   // relative: two computations of one torque
    ArmSetup twin = loadModel("twin");
    twin.arm.gravity = 0;
    const double flexion = 90;
    for (const auto& [effort, rotation] : {std::pair{Effort::Supination, -67.5}, std::pair{Effort::Pronation, 0.0}}) {
        const MvcGeometry g = calcMvcGeometry(twin, {flexion}, rotation);
        const SteadyMvcCurve c = calcSteadyMvcCurve(twin.muscles, g, effort, twin.effort);
        std::vector<ActivationProfile> U;
        for (const SteadyMusclePoint& p : c.points[0]) U.push_back(ActivationProfile::constant(p.activation));
        MuscleArm arm(twin, U);
        SimTK::State s = arm.getDefaultState();
        arm.getArm().lockElbow(s, elbowAngleFromFlexion(degToRad(flexion)));
        arm.getArm().lockForearmRotation(s, degToRad(rotation));
        arm.getSystem().realize(s, SimTK::Stage::Position);
        arm.setSteadyMuscleStates(s);
        arm.getSystem().realize(s, SimTK::Stage::Acceleration);
        const double reaction = arm.getArm().calcForearmHoldingTorque(s);
        EXPECT_NEAR(-reaction, c.totalForearmTorque[0], kReactionTol * std::abs(c.totalForearmTorque[0]));
        EXPECT_GT((effort == Effort::Supination ? 1 : -1) * c.totalForearmTorque[0], 1.0);
        for (const SteadyMusclePoint& p : c.points[0])   // agonists at the subject's voluntary activation
            EXPECT_EQ(p.activation, (effort == Effort::Supination ? 1 : -1) * p.forearmMomentArm > kForearmAgonistMomentArm
                                        ? twin.effort.voluntaryActivation : twin.effort.coContraction);
    }
    AnatomyTarget ratio;
    ratio.kind = TargetKind::PostureRatio;
    ratio.flexionDeg = 90;
    ratio.rotationDeg = -90;
    const std::vector<TargetScore> scores = scoreAnatomy(twin, {ratio});
    ASSERT_EQ(scores.size(), 1u);
    const double pronated = calcSteadyMvcCurve(twin.muscles, calcMvcGeometry(twin, {90}, -90), MuscleGroup::Flexor, twin.effort).totalTorque[0];
    const double neutral = calcSteadyMvcCurve(twin, MuscleGroup::Flexor, twin.effort, {90}).totalTorque[0];
    EXPECT_NEAR(scores[0].value, pronated / neutral, 1e-12);
    EXPECT_TRUE(scoreAnatomy(loadModel("elbow"), {ratio}).empty());   // no forearm rotation: not scored
}

// The twin's mended paths against the published moment-arm bands (issue 28's goal: every muscle within
// the published spread +/- 3 mm at >= 80 % of the scored angles, 0-130 deg). The bands are the target
// file's (Pigeon 1996, Ramsay 2009, ...); the test fails if a path edit moves a curve out of them.
TEST(AnatomyTargets, TwinMomentArmsAreInThePublishedBands) {
    constexpr double kGoalFraction = 0.80;   // issue 28
    std::vector<AnatomyTarget> momentArms;
    for (const AnatomyTarget& t : loadDefaultAnatomyTargets())
        if (t.kind == TargetKind::MomentArm) momentArms.push_back(t);
    const ArmSetup twin = loadModel("twin");
    int muscles = 0;
    for (const ScoreSummary& s : summarizeScores(scoreAnatomy(twin, momentArms))) {
        if (s.muscle.empty()) continue;
        ++muscles;
        ASSERT_GT(s.scored, 0) << s.muscle;
        EXPECT_GE(double(s.passed) / s.scored, kGoalFraction) << s.muscle << ": " << s.passed << " of " << s.scored;
    }
    EXPECT_EQ(muscles, 7);   // both biceps heads, BRA, BRD and the three triceps heads are scored
}

// The twin as calibrated meets every goal of the target file (issue 28): MVC vs angle and posture,
// Holzbaur's 90-deg values, volumes within 1.5x, shares, optimum angles, forearm torques. The test
// fails when a change to the muscle model, the paths or the calibration lines moves any target out.
TEST(AnatomyTargets, TwinMeetsEveryTargetOfTheFile) {
    const ArmSetup twin = loadModel("twin");
    const std::vector<TargetScore> scores = scoreAnatomy(twin, loadDefaultAnatomyTargets());
    ASSERT_GT(scores.size(), 100u);   // moment arms, MVCs, volumes, shares, optimum angles, forearm
    for (const TargetScore& s : scores)
        EXPECT_TRUE(s.pass) << getTargetKindName(s.target.kind) << " " << s.muscle << " " << describeTargetCondition(s.target) << " at " << s.target.flexionDeg
                            << " deg: " << s.value << " outside [" << s.target.lower << ", " << s.target.upper
                            << "] +/- " << s.target.tolerance << " (" << s.target.where << ")";
}
