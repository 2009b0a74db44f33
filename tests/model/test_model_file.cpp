// Model files, muscle paths with wrapping, and the arm built from them.
#include "model/geometry.h"
#include "model/muscle_arm.h"
#include "model/trial.h"
#include "muscles/param_file.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

using namespace armsim;
using SimTK::Vec2;

namespace {

constexpr double kExactTol = 1e-12;        // m: closed forms
constexpr double kMomentArmRelTol = 1e-6;  // two ways to a moment arm (issue 10)
constexpr double kDerivativeStep = 1e-6;   // rad, central difference of the path length

const ArmSetup& elbow() {
    static const ArmSetup s = loadModel("elbow");
    return s;
}

std::string writeTemp(const std::string& name, const std::string& text) {
    const auto path = std::filesystem::temp_directory_path() / name;
    std::ofstream(path) << text;
    return path.string();
}

std::string messageOf(const std::string& file) {
    try {
        loadModel(file);
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}

}  // namespace

TEST(CircleWrap, TangentArcTangentAroundTheGivenSide) {
    // p = (0, 2), q = (0, -2), R = 1, round +x: tangents at +-30 deg, arc pi/3, tangents sqrt(3) long.
    const CircleWrap w = calcCircleWrap(Vec2(0, 2), Vec2(0, -2), 1.0, Vec2(1, 0), true);
    ASSERT_TRUE(w.active);
    EXPECT_EQ(w.direction, -1);  // clockwise
    EXPECT_NEAR(w.angle, kPi / 3, kExactTol);
    EXPECT_NEAR(w.lengthP, std::sqrt(3.0), kExactTol);
    EXPECT_NEAR(w.lengthQ, std::sqrt(3.0), kExactTol);
    EXPECT_NEAR(w.tp[0], std::cos(kPi / 6), kExactTol);
    EXPECT_NEAR(w.tp[1], std::sin(kPi / 6), kExactTol);
    EXPECT_NEAR(w.tq[1], -std::sin(kPi / 6), kExactTol);
}

TEST(CircleWrap, ClearOnTheAllowedSideWrapsBehindTheStrip) {
    EXPECT_FALSE(calcCircleWrap(Vec2(2, 2), Vec2(2, -2), 1.0, Vec2(1, 0), true).active);  // passes at +x
    const CircleWrap behind = calcCircleWrap(Vec2(-2, 2), Vec2(-2, -2), 1.0, Vec2(1, 0), true);
    ASSERT_TRUE(behind.active);  // crosses the strip behind the circle: round +x
    EXPECT_NEAR(behind.angle, 2 * (3 * kPi / 4 - std::acos(1 / std::sqrt(8.0))), kExactTol);
    EXPECT_FALSE(calcCircleWrap(Vec2(-2, 3), Vec2(2, 3), 1.0, Vec2(1, 0), true).active);  // far above
    // Without a side: only a segment that cuts the circle wraps, the shorter way.
    EXPECT_FALSE(calcCircleWrap(Vec2(1.5, 2), Vec2(1.5, -2), 1.0, Vec2(0, 0), false).active);
    const CircleWrap cut = calcCircleWrap(Vec2(0.5, 2), Vec2(0.5, -2), 1.0, Vec2(0, 0), false);
    ASSERT_TRUE(cut.active);
    EXPECT_EQ(cut.direction, -1);  // round +x, the side the segment passes
    EXPECT_LT(cut.angle, kPi);
}

TEST(ModelFile, ThesisModelIsTheStraightBicepsArm) {
    const ArmSetup s = loadModel("thesis");
    ASSERT_EQ(s.getNumMuscles(), 1);
    EXPECT_EQ(s.biceps().name, "biceps");
    EXPECT_NEAR(s.arm.originDistance, 0.37, kExactTol);
    EXPECT_NEAR(s.arm.insertionDistance, 0.06, kExactTol);
    // P_max from the range: the path at full extension, A + B.
    EXPECT_NEAR(s.biceps().maxPathLength, 0.43, kExactTol);
    ArmGeometry g(s);
    for (double deg = 40; deg <= 180; deg += 10) {
        g.setElbowAngle(degToRad(deg));
        EXPECT_NEAR(g.calcPathLength(0), calcBicepsPathLength(0.37, 0.06, degToRad(deg)), kExactTol) << deg;
        EXPECT_NEAR(g.calcMomentArm(0), calcBicepsMomentArm(0.37, 0.06, degToRad(deg)), kExactTol) << deg;
    }
}

TEST(ModelFile, ElbowHasSevenMusclesConvertedFromOpenSim) {
    const ArmSetup& s = elbow();
    ASSERT_EQ(s.getNumMuscles(), 7);
    EXPECT_EQ(s.biceps().name, "BIClong");
    int flexors = 0;
    for (const MuscleSpec& m : s.muscles) flexors += m.group == MuscleGroup::Flexor;
    EXPECT_EQ(flexors, 4);
    // mass = F0 L0 rho / sigma, so the Virtual Muscle's F0 is OpenSim's max_isometric_force.
    EXPECT_NEAR(VirtualMuscle(s.calcMuscleParameters(s.findMuscle("BIClong"))).getF0(), 624.3, 1e-9);
    EXPECT_NEAR(VirtualMuscle(s.calcMuscleParameters(s.findMuscle("BRA"))).getF0(), 987.26, 1e-9);
    // L0T = tendon slack length / LrT.
    EXPECT_NEAR(s.muscles[s.findMuscle("BIClong")].params.optimalTendonLength, 0.2723 / 0.964, kExactTol);
    EXPECT_THROW(s.findMuscle("deltoid"), InputError);
}

// Issue 10: moment arm of every muscle two ways, -dP/dq by central differences and the elbow torque
// of a unit tension (Simbody's system Jacobian), over the elbow's range.
TEST(ModelFile, ElbowMomentArmsTwoWaysAgree) {
    ArmGeometry g(elbow());
    const double lo = elbow().arm.minElbowAngleDeg + 1, hi = elbow().arm.maxElbowAngleDeg - 1;
    for (int i = 0; i < g.getNumMuscles(); ++i)
        for (double deg = lo; deg <= hi; deg += 3) {
            const double theta = degToRad(deg);
            g.setElbowAngle(theta + kDerivativeStep);
            const double up = g.calcPathLength(i);
            g.setElbowAngle(theta - kDerivativeStep);
            const double down = g.calcPathLength(i);
            g.setElbowAngle(theta);
            const double byDerivative = (up - down) / (2 * kDerivativeStep);  // dP/dtheta = -dP/dq
            const double byVirtualWork = g.calcMomentArm(i);
            EXPECT_NEAR(byVirtualWork, byDerivative, kMomentArmRelTol * std::abs(byDerivative) + 1e-9)
                << elbow().muscles[i].params.name << " at " << deg << " deg";
        }
}

// Published ranges (assets/measured/elbow_reference.yaml: Pigeon et al. 1996, Ramsay et al. 2009 and
// a regression page, evaluated at the angle), widened by 35 % for model-to-specimen spread; triceps heads
// against the pooled triceps value. Flexion angles; the model's included angle is 180 - flexion.
TEST(ModelFile, ElbowMomentArmsInPublishedRanges) {
    ArmGeometry g(elbow());
    struct Range { const char* muscle; double flexion, lo, hi; };
    const Range ranges[] = {{"BIClong", 45, 0.0268, 0.0360}, {"BIClong", 90, 0.0471, 0.0483},
                            {"BICshort", 90, 0.0471, 0.0483}, {"BRA", 90, 0.0269, 0.0303},
                            {"BRD", 90, 0.0544, 0.0687}, {"TRIlong", 90, -0.0222, -0.0190},
                            {"TRIlat", 45, -0.0266, -0.0234}, {"TRImed", 120, -0.0182, -0.0162}};
    constexpr double kSpread = 0.35;
    for (const Range& r : ranges) {
        g.setElbowAngle(degToRad(180 - r.flexion));
        const double h = g.calcMomentArm(elbow().findMuscle(r.muscle));
        const double width = std::abs(r.hi - r.lo) + kSpread * std::abs(r.hi + r.lo) / 2;
        EXPECT_NEAR(h, (r.lo + r.hi) / 2, width) << r.muscle << " at " << r.flexion << " deg flexion";
    }
}

// The lock's torque at every sample, from the muscle forces and moment arms, equals Simbody's
// findMotionForces on a realized sample (issue 3's reading, now with seven muscles).
TEST(ModelFile, ElbowIsometricTorqueMatchesTheLockReaction) {
    IsometricTrialSettings s;
    s.elbowAngle = degToRad(100);
    s.activation = 0.95;
    s.antagonistActivation = 0.1;
    s.holdDuration = 0.5;
    s.averagingWindow = 0.2;
    s.sampleRate = 200;
    const IsometricTrialResult fast = runIsometricTrial(elbow(), s);
    s.realizeEverySample = true;
    const IsometricTrialResult slow = runIsometricTrial(elbow(), s);
    const std::vector<double> a = fast.series.getColumn("holding_torque_Nm"), b = slow.series.getColumn("holding_torque_Nm");
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t k = 0; k < a.size(); ++k) EXPECT_NEAR(a[k], b[k], 1e-9 * (1 + std::abs(b[k]))) << k;
    EXPECT_GT(fast.summary.meanMuscleTorque, 0);  // a flexion effort
    // The tared torque is the sum of the muscles' torques less their torques at rest.
    double torque = 0;
    for (int i = 0; i < elbow().getNumMuscles(); ++i)
        torque += fast.summary.momentArms[i] * fast.summary.meanForces[i];
    EXPECT_GT(torque, fast.summary.meanMuscleTorque - 5.0);
    ASSERT_TRUE(fast.series.hasColumn("force_TRIlong_N"));
    ASSERT_TRUE(fast.series.hasColumn("state_BIClong_L"));
    EXPECT_NEAR(fast.series.get(fast.series.getNumRows() - 1, "activation_TRIlong"), 0.1, kExactTol);

    s.effort = MuscleGroup::Extensor;
    s.realizeEverySample = false;
    EXPECT_LT(runIsometricTrial(elbow(), s).summary.meanMuscleTorque, 0);  // an extension effort
}

TEST(ModelFile, BadFilesNameTheFileLineAndKey) {
    const std::string head = "name: bad\narm: arm/default_male.yaml\nmuscles:\n";
    const std::string muscle =
        "  - name: m\n    parameters: " + std::string(ARMSIM_ASSET_DIR) + "/muscles/biceps_long_head.yaml\n";
    const std::string path = "    path:\n      origin: {body: upper_arm, location: [0, 0.3, 0]}\n"
                             "      insertion: {body: forearm, location: [0, -0.05, 0]}\n";
    std::string msg = messageOf(writeTemp("bad1.yaml", head + muscle + "    colour: red\n" + path));
    EXPECT_NE(msg.find("bad1.yaml:"), std::string::npos) << msg;
    EXPECT_NE(msg.find("colour"), std::string::npos) << msg;

    msg = messageOf(writeTemp("bad2.yaml", head + muscle +
                                               "    path:\n      origin: {body: shoulder, location: [0, 0.3, 0]}\n"
                                               "      insertion: {body: forearm, location: [0, -0.05, 0]}\n"));
    EXPECT_NE(msg.find("shoulder"), std::string::npos) << msg;

    msg = messageOf(writeTemp("bad3.yaml", head + muscle +
                                               "    path:\n      origin: {body: upper_arm, location: [0, 0.3]}\n"
                                               "      insertion: {body: forearm, location: [0, -0.05, 0]}\n"));
    EXPECT_NE(msg.find("expected 3"), std::string::npos) << msg;

    msg = messageOf(writeTemp("bad4.yaml",
                              head + muscle +
                                  "    path:\n      origin: {body: upper_arm, location: [0, 0.3, 0]}\n"
                                  "      via:\n        - {body: upper_arm, sphere: {centre: [0, 0, 0], radius: 0.01}}\n"
                                  "        - {body: upper_arm, sphere: {centre: [0, 0.1, 0], radius: 0.01}}\n"
                                  "      insertion: {body: forearm, location: [0, -0.05, 0]}\n"));
    EXPECT_NE(msg.find("follow each other"), std::string::npos) << msg;

    msg = messageOf(writeTemp("bad5.yaml", "name: bad\narm: arm/no_such_arm.yaml\nmuscles: []\n"));
    EXPECT_NE(msg.find("bad5.yaml:2"), std::string::npos) << msg;

    msg = messageOf("no_such_model");
    EXPECT_NE(msg.find("no such model"), std::string::npos) << msg;
    EXPECT_NE(msg.find("elbow"), std::string::npos) << msg;  // lists the shipped models
}
