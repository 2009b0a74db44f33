// Model files, muscle paths with wrapping, and the arm built from them.
#include "basics/errors.h"
#include "model/geometry.h"
#include "model/muscle_arm.h"
#include "model/mvc_curve.h"
#include "model/trial.h"
#include "muscles/thelen2003_muscle.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

using namespace armsim;
using SimTK::Vec2;

namespace {

/// One muscle of a model file's `muscles:` list (L0 0.12 m, slack 0.2 m, human fibre types, a straight
/// path) with `fields` (each an indented line) for its size and the rest.
std::string makeMuscleEntry(const std::string& name, const std::string& fields) {
    const std::string types = std::string(ARMSIM_ASSET_DIR) + "/muscles/human_fibre_types.yaml";
    return "  - name: " + name + "\n" + fields +
           "    optimal_fascicle_length: 0.12\n    tendon_slack_length: 0.2\n"
           "    fibre_types: " + types + "\n    fibre_fractions: {slow: 0.5, fast: 0.5}\n"
           "    path:\n      origin: {body: upper_arm, location: [0, 0.3, 0]}\n"
           "      insertion: {body: forearm, location: [0, -0.05, 0]}\n";
}

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

// A path wound round a surface by more than half a turn (a supinator round the radius in pronation):
// both ends beside the circle behind it, the segment clear of the strip. Without `winds` it runs
// straight; with it, it wraps round +y: from p at 198.4 deg clockwise through 90 deg to q at 225 deg,
// 333.4 deg of polar angle less the two tangent angles acos(R / |p|) and acos(R / |q|).
TEST(CircleWrap, AWoundPathWrapsTheLongWayRoundItsSide) {
    const Vec2 p(-1.5, -0.5), q(-1.2, -1.2), side(0, 1);
    EXPECT_FALSE(calcCircleWrap(p, q, 1.0, side, true).active);
    const CircleWrap w = calcCircleWrap(p, q, 1.0, side, true, true);
    ASSERT_TRUE(w.active);
    EXPECT_EQ(w.direction, -1);
    const double polar = std::atan2(p[1], p[0]) - std::atan2(q[1], q[0]) + 2 * kPi;
    EXPECT_NEAR(w.angle, polar - std::acos(1 / p.norm()) - std::acos(1 / q.norm()), kExactTol);
    EXPECT_GT(w.angle, kPi);
    EXPECT_NEAR(w.tp.norm(), 1.0, kExactTol);           // tangent: on the circle, perpendicular to the line
    EXPECT_NEAR(dot(w.tp, p - w.tp), 0.0, kExactTol);
    EXPECT_NEAR(dot(w.tq, q - w.tq), 0.0, kExactTol);
    // A segment that passes by the centre on the allowed side stays straight, winding or not.
    EXPECT_FALSE(calcCircleWrap(Vec2(-1.5, 1.2), Vec2(1.5, 1.2), 1.0, side, true, true).active);
    // Where the old rule wraps (behind, in the strip), winding keeps its way and arc.
    const CircleWrap a = calcCircleWrap(Vec2(-2, 2), Vec2(-2, -2), 1.0, Vec2(1, 0), true);
    const CircleWrap b = calcCircleWrap(Vec2(-2, 2), Vec2(-2, -2), 1.0, Vec2(1, 0), true, true);
    EXPECT_EQ(a.direction, b.direction);
    EXPECT_NEAR(a.angle, b.angle, kExactTol);
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
    // Source values: mass = F0 L0 rho / sigma, so the Virtual Muscle's F0 is OpenSim's
    // max_isometric_force; L0T = tendon slack length / LrT.
    for (const char* name : {"BIClong", "BRA"}) {
        const MuscleSpec& m = s.muscles[s.findMuscle(name)];
        MuscleParameters source = m.sourceParams;
        source.maxPathLength = m.params.maxPathLength;
        EXPECT_NEAR(VirtualMuscle(source).getF0(), std::string(name) == "BRA" ? 987.26 : 624.3, 1e-9) << name;
        // The calibration scales F0, L0 and L0T by k, f and t.
        const MuscleCalibration& c = m.calibration;
        EXPECT_FALSE(c.isIdentity()) << name;
        EXPECT_NEAR(VirtualMuscle(s.calcMuscleParameters(s.findMuscle(name))).getF0(),
                    c.forceScale * VirtualMuscle(source).getF0(), 1e-9) << name;
        EXPECT_NEAR(m.params.optimalFascicleLength, c.fascicleLengthScale * source.optimalFascicleLength, kExactTol);
        EXPECT_NEAR(m.params.optimalTendonLength, c.tendonLengthScale * source.optimalTendonLength, kExactTol);
    }
    EXPECT_NEAR(s.muscles[s.findMuscle("BIClong")].sourceParams.optimalTendonLength, 0.2723 / 0.964, kExactTol);
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
    s.bandedNewton = false;   // the same steps as the Simbody path, so the same samples
    const IsometricTrialResult fast = runIsometricTrial(elbow(), s);
    s.solver = TrialSolver::SimbodyPerSample;
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

    s.effort = Effort::Extension;
    s.solver = TrialSolver::LockedOde;
    EXPECT_LT(runIsometricTrial(elbow(), s).summary.meanMuscleTorque, 0);  // an extension effort
}

// Issue 10's acceptance numbers for the calibrated elbow (steady MVC at the model's subject effort):
// flexion peak 70-90 N m between 80 and 110 deg flexion (Holzbaur et al. 2007: 79.5 +/- 8.1 N m at
// 90 deg), at least 45 % of the peak at 20 and 130 deg; extension 45-75 N m at 90 deg.
TEST(MvcCurve, CalibratedElbowMeetsThePublishedTargets) {
    std::vector<double> q;
    for (double a = 0; a <= 140; a += 2.5) q.push_back(a);
    const SteadyMvcCurve flexion = calcSteadyMvcCurve(elbow(), MuscleGroup::Flexor, elbow().effort, q);
    const auto peak = std::max_element(flexion.totalTorque.begin(), flexion.totalTorque.end());
    const double peakDeg = q[peak - flexion.totalTorque.begin()];
    EXPECT_GE(peakDeg, 80.0);
    EXPECT_LE(peakDeg, 110.0);
    EXPECT_GE(*peak, 70.0);
    EXPECT_LE(*peak, 90.0);
    auto at = [&](const SteadyMvcCurve& c, double deg) { return c.totalTorque[std::size_t(deg / 2.5 + 0.5)]; };
    EXPECT_GE(at(flexion, 20), 0.45 * *peak);
    EXPECT_GE(at(flexion, 130), 0.45 * *peak);
    const SteadyMvcCurve extension = calcSteadyMvcCurve(elbow(), MuscleGroup::Extensor, elbow().effort, {90.0});
    EXPECT_LE(extension.totalTorque[0], -45.0);
    EXPECT_GE(extension.totalTorque[0], -75.0);
    // Every flexor pulls at 90 deg (none was calibrated into slack or overstretch to buy breadth): the
    // fit's soft bound is 1 +/- 0.2 L0; a penalty, so a little beyond is allowed.
    constexpr double kMidRangeBand = 0.25;
    const SteadyMvcCurve mid = calcSteadyMvcCurve(elbow(), MuscleGroup::Flexor, elbow().effort, {90.0});
    for (int i = 0; i < elbow().getNumMuscles(); ++i)
        if (elbow().muscles[i].group == MuscleGroup::Flexor) {
            EXPECT_GT(mid.calcFlexorShare(0, i), 0.1) << mid.muscles[i];
            EXPECT_NEAR(mid.points[0][i].fibreLength, 1.0, kMidRangeBand) << mid.muscles[i];
        }
}

// One quantity two ways: the steady MVC torque (equilibrium solve of every muscle) against the time
// integration of the locked arm (CPodes, sag and yield included), the latter tared at rest so the
// steady passive torque is taken off. Tolerance: the end of a 2 s hold is within 1.5 % of steady state.
TEST(MvcCurve, SteadyTorqueMatchesTimeIntegration) {
    constexpr double kRelTol = 0.015;
    SubjectEffort rest;
    rest.voluntaryActivation = 0;
    rest.coContraction = 0;
    for (Effort g : {Effort::Flexion, Effort::Extension})
        for (double deg : {45.0, 100.0}) {
            const double steady = calcSteadyMvcCurve(elbow(), g, elbow().effort, {deg}).totalTorque[0] -
                                  calcSteadyMvcCurve(elbow(), g, rest, {deg}).totalTorque[0];
            IsometricTrialSettings s;
            s.elbowAngle = degToRad(180 - deg);
            s.effort = g;
            s.activation = elbow().effort.voluntaryActivation;
            s.antagonistActivation = elbow().effort.coContraction;
            s.holdDuration = 2.0;
            s.averagingWindow = 0.2;
            s.sampleRate = 100;
            const double integrated = runIsometricTrial(elbow(), s).summary.meanMuscleTorque;
            EXPECT_NEAR(integrated, steady, kRelTol * std::abs(steady)) << getEffortName(g) << " " << deg;
        }
}

// The same on the twin's forearm axis (issue 31, the two-axis transducer): a supination and a pronation
// effort in two postures, steady forearm torque (agonists by their forearm moment arm in the pose)
// against the locked arm's integration, both tared at rest; and a flexion effort's forearm axis.
TEST(MvcCurve, SteadyForearmTorqueMatchesTimeIntegration) {
    constexpr double kRelTol = 0.015;  // as above: 2 s holds
    static const ArmSetup twin = loadModel("twin");
    const SubjectEffort rest{0, 0};
    struct Case {
        Effort effort;
        double deg, rotationDeg;
    };
    for (const Case& c : {Case{Effort::Supination, 90, -30}, Case{Effort::Pronation, 60, 30}, Case{Effort::Flexion, 90, 0}}) {
        const MvcGeometry g = calcMvcGeometry(twin, {c.deg}, c.rotationDeg);
        const double steady = calcSteadyMvcCurve(twin.muscles, g, c.effort, twin.effort).totalForearmTorque[0] -
                              calcSteadyMvcCurve(twin.muscles, g, c.effort, rest).totalForearmTorque[0];
        IsometricTrialSettings s;
        s.elbowAngle = degToRad(180 - c.deg);
        s.forearmRotationDeg = c.rotationDeg;
        s.effort = c.effort;
        s.activation = twin.effort.voluntaryActivation;
        s.antagonistActivation = twin.effort.coContraction;
        s.holdDuration = 2.0;
        s.averagingWindow = 0.2;
        s.sampleRate = 100;
        const double integrated = runIsometricTrial(twin, s).summary.meanForearmTorque;
        EXPECT_GT(std::abs(steady), 1.0) << getEffortName(c.effort);  // N m: the axis carries torque
        EXPECT_NEAR(integrated, steady, kRelTol * std::abs(steady)) << getEffortName(c.effort) << " " << c.deg;
        if (c.effort == Effort::Supination) { EXPECT_GT(steady, 0); }
        if (c.effort == Effort::Pronation) { EXPECT_LT(steady, 0); }
    }
}

TEST(ModelFile, BadCalibrationNamesTheField) {
    const std::string text = "name: bad\narm: " + std::string(ARMSIM_ASSET_DIR) +
                             "/arm/default_male.yaml\nmuscles:\n  - name: m\n    parameters: " +
                             std::string(ARMSIM_ASSET_DIR) + "/muscles/biceps_long_head.yaml\n" +
                             "    calibration: {force_scale: 0, tendon_length_scale: 1}\n"
                             "    path:\n      origin: {body: upper_arm, location: [0, 0.3, 0]}\n"
                             "      insertion: {body: forearm, location: [0, -0.05, 0]}\n";
    const std::string msg = messageOf(writeTemp("badcal.yaml", text));
    EXPECT_NE(msg.find("badcal.yaml:6"), std::string::npos) << msg;
    EXPECT_NE(msg.find("force_scale"), std::string::npos) << msg;
    EXPECT_NE(msg.find("[0.2, 5]"), std::string::npos) << msg;
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

    // A path on one body (a flexor that does not cross the elbow) is named at its insertion's line.
    msg = messageOf(writeTemp("bad6.yaml", head + muscle +
                                               "    path:\n      origin: {body: upper_arm, location: [0, 0.3, 0]}\n"
                                               "      insertion: {body: upper_arm, location: [0, -0.05, 0]}\n"));
    EXPECT_NE(msg.find("bad6.yaml:8"), std::string::npos) << msg;
    EXPECT_NE(msg.find("muscle 'm': its origin, insertion and every via point are on the upper_arm"), std::string::npos) << msg;

    msg = messageOf(writeTemp("bad5.yaml", "name: bad\narm: arm/no_such_arm.yaml\nmuscles: []\n"));
    EXPECT_NE(msg.find("bad5.yaml:2"), std::string::npos) << msg;

    msg = messageOf("no_such_model");
    EXPECT_NE(msg.find("no such model"), std::string::npos) << msg;
    EXPECT_NE(msg.find("elbow"), std::string::npos) << msg;  // lists the shipped models
}

// A wrapping surface's side reversed sends the biceps long head round the far side of its sphere: at
// full extension its path (0.4736 m against 0.4304 m) asks for a fascicle past nf's zero, where no
// steady state exists. The load refuses it, naming the muscle and the length (it used to load, and
// `model show` failed with exit 3 at 0 deg).
TEST(ModelFile, APathTheMuscleCannotSpanIsRefusedAtLoad) {
    std::ifstream in(std::string(ARMSIM_ASSET_DIR) + "/models/elbow.yaml");
    std::stringstream buffer;
    buffer << in.rdbuf();
    std::string text = buffer.str();
    for (std::size_t at = text.find("../"); at != std::string::npos; at = text.find("../", at))
        text.replace(at, 3, std::string(ARMSIM_ASSET_DIR) + "/");
    const std::string side = "side: [0.44621, 0.86849, 0.21591]";
    const std::size_t at = text.find(side);
    ASSERT_NE(at, std::string::npos);
    EXPECT_EQ(messageOf(writeTemp("elbow_side.yaml", text)), "");   // the shipped model, moved: loads
    text.replace(at, side.size(), "side: [-0.44621, -0.86849, -0.21591]");
    const std::string msg = messageOf(writeTemp("elbow_side.yaml", text));
    EXPECT_NE(msg.find("elbow_side.yaml: muscle 'BIClong': its path over the elbow's range reaches 0.473588 m, where it "
                       "has no steady state at activation 0"),
              std::string::npos) << msg;
}

// Drive apart from the fibre-type file (issue 28): max_firing_rate from the model file or the muscle
// replaces the file's fmax, and a unit at full drive fires at it (the envelope at U = 1).
TEST(ModelFile, MaxFiringRateReplacesTheFibreTypeFilesFmax) {
    auto muscle = [](const std::string& name, const std::string& fields) {
        return makeMuscleEntry(name, fields + "    volume: 80.0e-6\n");
    };
    const std::string text = "name: drive\narm: arm/default_male.yaml\nmax_firing_rate: 3.5\nmuscles:\n" +
                             muscle("modelRate", "") + muscle("ownRate", "    max_firing_rate: 2.5\n");
    const ArmSetup s = loadModel(writeTemp("drive.yaml", text));
    EXPECT_EQ(s.maxFiringRate, 3.5);
    const MuscleParameters a = s.calcMuscleParameters(0), b = s.calcMuscleParameters(1);
    EXPECT_EQ(a.coefficients.fmax, 3.5);
    EXPECT_EQ(b.coefficients.fmax, 2.5);
    EXPECT_DOUBLE_EQ(calcEnvelopeFrequency(a.coefficients, 0.3, 1.0), 3.5);
    // Without it: the fibre-type file's (Virtual Muscle's 2), as the thesis model keeps.
    const ArmSetup thesis = loadModel("thesis");
    EXPECT_EQ(thesis.maxFiringRate, 0);
    EXPECT_EQ(thesis.biceps().coefficients.fmax, 2.0);
    // The twin's rate fuses both fibre types down to 0.7 L0 (assets/models/twin.yaml; Bellemare 1983):
    // Af >= 0.93 there, where Virtual Muscle's fmax 2 gives 0.38 (slow).
    const ArmSetup twin = loadModel("twin");
    const MuscleParameters& p = twin.muscles[0].params;
    const double L = 0.7;
    EXPECT_GE(calcActivationFrequency(p.slow, p.coefficients.fmax, calcNf(p.slow, L)), 0.93);
    EXPECT_GE(calcActivationFrequency(p.fast, p.coefficients.fmax * p.fast.aS2, calcNf(p.fast, L)), 0.93);
    EXPECT_LT(calcActivationFrequency(p.slow, 2.0, calcNf(p.slow, L)), 0.5);

    // A `parameters:` muscle file keeps its own rate; one without gets the model's.
    const std::string types = std::string(ARMSIM_ASSET_DIR) + "/muscles/human_fibre_types.yaml";
    auto muscleFile = [&](const std::string& name, const std::string& own) {
        return writeTemp(name + ".yaml", "name: " + name + "\nmass: 0.3\noptimal_fascicle_length: 0.12\n"
                                         "optimal_tendon_length: 0.2\nmax_path_length: 0.4\n"
                                         "fibre_fractions: {slow: 0.5, fast: 0.5}\nmotor_units: {slow: 3, fast: 3}\n"
                                         "fibre_types: " + types + "\n" + own);
    };
    const std::string path = "    path:\n      origin: {body: upper_arm, location: [0, 0.3, 0]}\n"
                             "      insertion: {body: forearm, location: [0, -0.05, 0]}\n";
    const ArmSetup f = loadModel(writeTemp("drive_files.yaml",
        "name: drive\narm: arm/default_male.yaml\nmax_firing_rate: 3.5\nmuscles:\n"
        "  - name: ownFile\n    parameters: " + muscleFile("own_rate", "max_firing_rate: 2.5\n") + "\n" + path +
        "  - name: plainFile\n    parameters: " + muscleFile("plain_rate", "") + "\n" + path));
    EXPECT_EQ(f.calcMuscleParameters(0).coefficients.fmax, 2.5);
    EXPECT_EQ(f.calcMuscleParameters(1).coefficients.fmax, 3.5);

    // Bounds: above fmin (0.5 is refused, named with the file and line), at most 8.
    const std::string msg = messageOf(writeTemp("drive_bad.yaml", "name: drive\narm: arm/default_male.yaml\n"
                                                                  "max_firing_rate: 0.5\nmuscles:\n" + muscle("m", "")));
    EXPECT_NE(msg.find("drive_bad.yaml:3"), std::string::npos) << msg;
    EXPECT_NE(msg.find("max_firing_rate' = 0.5"), std::string::npos) << msg;
    EXPECT_NE(msg.find("above fmin"), std::string::npos) << msg;
    EXPECT_EQ(loadModel(writeTemp("drive_top.yaml", "name: drive\narm: arm/default_male.yaml\nmax_firing_rate: 8\n"
                                                    "muscles:\n" + muscle("m", ""))).maxFiringRate, 8.0);
    EXPECT_NE(messageOf(writeTemp("drive_over.yaml", "name: drive\narm: arm/default_male.yaml\nmax_firing_rate: 8.5\n"
                                                     "muscles:\n" + muscle("m", ""))).find("max_firing_rate' = 8.5"),
              std::string::npos);
}

// Strength apart from size (issue 28): sigma from the model file or the muscle, mass from a volume,
// F0 = sigma V / L0 following sigma; a muscle given by max_isometric_force keeps F0 whatever sigma.
TEST(ModelFile, SpecificTensionAndVolumeSetF0AndMass) {
    const auto muscle = makeMuscleEntry;
    const double sigma = 250000, own = 400000, V = 80e-6, F0 = 600, L0 = 0.12;
    const std::string text = "name: sigma\narm: arm/default_male.yaml\nspecific_tension: 250000\nmuscles:\n" +
                             muscle("byVolume", "    volume: 80.0e-6\n") +
                             muscle("ownSigma", "    volume: 80.0e-6\n    specific_tension: 400000\n") +
                             muscle("byForce", "    max_isometric_force: 600\n");
    const ArmSetup s = loadModel(writeTemp("sigma.yaml", text));
    EXPECT_EQ(s.specificTension, sigma);
    const double rho = s.muscles[0].params.coefficients.density;
    const VirtualMuscle a(s.calcMuscleParameters(0)), b(s.calcMuscleParameters(1)), c(s.calcMuscleParameters(2));
    EXPECT_NEAR(a.getParameters().mass, rho * V, 1e-15);
    EXPECT_NEAR(a.getF0(), sigma * V / L0, 1e-9);
    EXPECT_NEAR(b.getParameters().mass, rho * V, 1e-15);
    EXPECT_NEAR(b.getF0(), own * V / L0, 1e-9);
    EXPECT_NEAR(c.getF0(), F0, 1e-9);
    EXPECT_NEAR(c.getParameters().mass, F0 * L0 * rho / sigma, 1e-15);
    // Without specific_tension: Virtual Muscle's 31.8 N/cm^2 from the fibre-type file.
    const ArmSetup thesis = loadModel("thesis");
    EXPECT_EQ(thesis.specificTension, 0);
    EXPECT_EQ(thesis.biceps().coefficients.sigma, 318000);

    std::string msg = messageOf(writeTemp("sigma_bad.yaml", "name: sigma\narm: arm/default_male.yaml\n"
                                                            "specific_tension: 25\nmuscles:\n" +
                                                                muscle("m", "    volume: 80.0e-6\n")));
    EXPECT_NE(msg.find("sigma_bad.yaml:3"), std::string::npos) << msg;
    EXPECT_NE(msg.find("specific_tension"), std::string::npos) << msg;
    EXPECT_NE(msg.find("N/cm^2"), std::string::npos) << msg;
    msg = messageOf(writeTemp("sigma_two.yaml", "name: sigma\narm: arm/default_male.yaml\nmuscles:\n" +
                                                    muscle("m", "    volume: 80.0e-6\n    mass: 0.1\n")));
    EXPECT_NE(msg.find("not 2"), std::string::npos) << msg;
    // Bounds in files as on the command line: F0 up to 1e5 N, mass up to 10 kg (the volume's 10 L).
    msg = messageOf(writeTemp("f0_huge.yaml", "name: sigma\narm: arm/default_male.yaml\nmuscles:\n" +
                                                  muscle("m", "    max_isometric_force: 1e9\n")));
    EXPECT_NE(msg.find("max_isometric_force' (muscles, entry 1) = 1e+09: expected in (0, 1e+05] (N)"), std::string::npos) << msg;
    msg = messageOf(writeTemp("mass_huge.yaml", "name: sigma\narm: arm/default_male.yaml\nmuscles:\n" +
                                                    muscle("m", "    mass: 50\n")));
    EXPECT_NE(msg.find("mass"), std::string::npos) << msg;
    EXPECT_NE(msg.find("50"), std::string::npos) << msg;
}

// loadModel reuses a model while its files are unchanged: the reused model equals a fresh load, and an
// edit of a file the model only refers to (its muscle file) is seen by the next load.
TEST(ModelFile, AReloadSeesAnEditedMuscleFile) {
    const auto dir = std::filesystem::temp_directory_path() / ("armsim_model_cache_" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    const std::string asset = ARMSIM_ASSET_DIR;
    auto writeMuscle = [&](double mass) {
        std::ofstream(dir / "m.yaml") << "name: m\nmass: " << mass
                                      << "\noptimal_fascicle_length: 0.16\noptimal_tendon_length: 0.245\n"
                                         "max_path_length: 0.43\nfibre_fractions: {slow: 0.3, fast: 0.7}\n"
                                         "motor_units: {slow: 3, fast: 3}\nfibre_types: "
                                      << asset << "/muscles/human_fibre_types.yaml\n";
    };
    writeMuscle(0.3);
    const std::string model = (dir / "model.yaml").string();
    std::ofstream(model) << "name: cached\narm: arm/default_male.yaml\nmuscles:\n  - name: m\n    parameters: m.yaml\n"
                            "    path:\n      origin: {body: upper_arm, location: [0, 0.3, 0]}\n"
                            "      insertion: {body: forearm, location: [0, -0.05, 0]}\n";
    const ArmSetup first = loadModel(model);
    const ArmSetup again = loadModel(model);
    EXPECT_EQ(again.muscles.at(0).params.mass, 0.3);
    EXPECT_EQ(again.muscles.at(0).params.maxPathLength, first.muscles.at(0).params.maxPathLength);
    EXPECT_EQ(again.file, model);

    const std::string otherSpelling = (dir / "." / "model.yaml").string();
    EXPECT_EQ(loadModel(otherSpelling).file, otherSpelling);

    writeMuscle(0.4);
    EXPECT_EQ(loadModel(model).muscles.at(0).params.mass, 0.4);

    // `arm: arm/default_male.yaml` was found in the assets; an arm file that appears beside the model
    // is looked up first, so the next load takes it.
    const ArmSetup before = loadModel(model);
    std::filesystem::create_directories(dir / "arm");
    {
        std::ifstream in(asset + "/arm/default_male.yaml");
        std::stringstream text;
        text << in.rdbuf();
        std::string arm = text.str();
        const std::size_t at = arm.find("mass: 73.0");
        ASSERT_NE(at, std::string::npos);
        arm.replace(at, 10, "mass: 90.0");
        std::ofstream(dir / "arm" / "default_male.yaml") << arm;
    }
    EXPECT_EQ(before.arm.bodyMass, 73.0);
    EXPECT_EQ(loadModel(model).arm.bodyMass, 90.0);
    std::filesystem::remove(dir / "m.yaml");
    EXPECT_NE(messageOf(model).find("m.yaml"), std::string::npos) << messageOf(model);
    std::filesystem::remove_all(dir);
}

// Two links to one model file from two folders: the model's references are looked up beside the link,
// so each folder's muscle file counts and the cache keeps them apart.
TEST(ModelFile, LinksInTwoFoldersAreTwoModels) {
    namespace fs = std::filesystem;
    const fs::path dir = fs::temp_directory_path() / ("armsim_model_links_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    for (const char* sub : {"shared", "a", "b"}) fs::create_directories(dir / sub);
    std::ofstream(dir / "shared" / "model.yaml")
        << "name: linked\narm: arm/default_male.yaml\nmuscles:\n  - name: m\n    parameters: m.yaml\n"
           "    path:\n      origin: {body: upper_arm, location: [0, 0.3, 0]}\n"
           "      insertion: {body: forearm, location: [0, -0.05, 0]}\n";
    for (const auto& [sub, mass] : {std::pair<const char*, double>{"a", 0.3}, {"b", 0.5}}) {
        std::ofstream(dir / sub / "m.yaml") << "name: m\nmass: " << mass
                                            << "\noptimal_fascicle_length: 0.16\noptimal_tendon_length: 0.245\n"
                                               "max_path_length: 0.43\nfibre_fractions: {slow: 0.3, fast: 0.7}\n"
                                               "motor_units: {slow: 3, fast: 3}\nfibre_types: "
                                            << ARMSIM_ASSET_DIR << "/muscles/human_fibre_types.yaml\n";
        fs::create_symlink(dir / "shared" / "model.yaml", dir / sub / "model.yaml");
    }
    EXPECT_EQ(loadModel((dir / "a" / "model.yaml").string()).muscles.at(0).params.mass, 0.3);
    EXPECT_EQ(loadModel((dir / "b" / "model.yaml").string()).muscles.at(0).params.mass, 0.5);
    EXPECT_EQ(loadModel((dir / "a" / "model.yaml").string()).muscles.at(0).params.mass, 0.3);
    fs::remove_all(dir);
}

// The forearm rotation (issue 28): the twin's radius turns about MoBL-ARMS's pro_sup axis. Its moment
// arms two ways (virtual work through Simbody's Jacobian vs -dP/dphi by central differences), the
// rotators' signs, and the lock.
TEST(ForearmRotation, TwinMomentArmsTwoWaysAndTheRotatorsSigns) {
    const ArmSetup twin = loadModel("twin");
    ASSERT_TRUE(twin.arm.forearmRotation.enabled);
    ArmGeometry g(twin);
    EXPECT_NEAR(g.getArm().getForearmRotation(g.getState()), 0.0, kExactTol);   // the posture of the file
    for (double flexion : {30.0, 90.0})
        for (double phiDeg : {-80.0, -60.0, 0.0, 45.0}) {
            g.setElbowAngle(elbowAngleFromFlexion(degToRad(flexion)));
            const double phi = degToRad(phiDeg);
            for (int i = 0; i < g.getNumMuscles(); ++i) {
                g.setForearmRotation(phi + kDerivativeStep);
                const double up = g.calcPathLength(i);
                g.setForearmRotation(phi - kDerivativeStep);
                const double down = g.calcPathLength(i);
                g.setForearmRotation(phi);
                const double byDerivative = -(up - down) / (2 * kDerivativeStep);
                EXPECT_NEAR(g.calcForearmMomentArm(i), byDerivative, kMomentArmRelTol * std::abs(byDerivative) + 1e-9)
                    << twin.muscles[i].params.name << " at " << flexion << " deg flexion, " << phiDeg << " deg rotation";
            }
        }
    // At 90 deg flexion and neutral: the biceps and the supinator supinate, the pronators pronate, and
    // muscles on the upper arm and ulna alone (BRA, triceps) have no forearm moment arm.
    g.setElbowAngle(elbowAngleFromFlexion(kPi / 2));
    g.setForearmRotation(0);
    EXPECT_GT(g.calcForearmMomentArm(twin.findMuscle("BIClong")), 0.005);
    EXPECT_GT(g.calcForearmMomentArm(twin.findMuscle("SUP")), 0.003);
    EXPECT_LT(g.calcForearmMomentArm(twin.findMuscle("PT")), -0.005);
    EXPECT_LT(g.calcForearmMomentArm(twin.findMuscle("PQ")), -0.003);
    EXPECT_EQ(g.calcForearmMomentArm(twin.findMuscle("BRA")), 0.0);
    EXPECT_EQ(g.calcForearmMomentArm(twin.findMuscle("TRIlong")), 0.0);
    // Over the whole range the supinator supinates (it winds round the radius in pronation) and the
    // pronator teres pronates until about 85 deg pronation.
    for (double phiDeg = -90; phiDeg <= 90; phiDeg += 5) {
        g.setForearmRotation(degToRad(phiDeg));
        EXPECT_GT(g.calcForearmMomentArm(twin.findMuscle("SUP")), 0.004) << phiDeg;
        if (phiDeg >= -80) {
            EXPECT_LT(g.calcForearmMomentArm(twin.findMuscle("PT")), -0.001) << phiDeg;
        }
    }
    // The brachioradialis turns the forearm towards neutral: a supinator when pronated, a pronator when supinated.
    g.setForearmRotation(degToRad(-80));
    EXPECT_GT(g.calcForearmMomentArm(twin.findMuscle("BRD")), 0.005);
    g.setForearmRotation(degToRad(80));
    EXPECT_LT(g.calcForearmMomentArm(twin.findMuscle("BRD")), -0.005);
    // The elbow model has no forearm rotation and no radius.
    EXPECT_FALSE(elbow().arm.forearmRotation.enabled);
    ArmGeometry e(elbow());
    EXPECT_THROW(e.setForearmRotation(0.1), std::logic_error);
    EXPECT_EQ(e.calcForearmMomentArm(0), 0.0);
    const std::string bad = messageOf(writeTemp("radius_without_rotation.yaml",
        "name: bad\narm: arm/default_male.yaml\nmuscles:\n  - name: m\n    parameters: " + std::string(ARMSIM_ASSET_DIR) +
        "/muscles/biceps_long_head.yaml\n    path:\n      origin: {body: upper_arm, location: [0, 0.3, 0]}\n"
        "      insertion: {body: radius, location: [0, -0.05, 0]}\n"));
    EXPECT_NE(bad.find("forearm_rotation"), std::string::npos) << bad;
}

// A conditional via point (MoBL's PT-P4, `active_rotation_deg: [-29.2, 90]`): outside its range the
// path is the path without it (a second model with the point removed), inside it the path through it.
TEST(ForearmRotation, ConditionalViaPointIsSkippedOutsideItsRange) {
    const ArmSetup twin = loadModel("twin");
    const int pt = twin.findMuscle("PT");
    ArmSetup without = twin;
    auto& path = without.muscles[pt].path;
    const auto conditional = std::find_if(path.begin(), path.end(), [](const PathElementSpec& e) { return e.isConditional(); });
    ASSERT_NE(conditional, path.end());
    path.erase(conditional);
    ArmGeometry a(twin), b(without);
    for (ArmGeometry* g : {&a, &b}) g->setElbowAngle(elbowAngleFromFlexion(kPi / 2));
    for (double phiDeg : {-60.0, -30.0}) {
        a.setForearmRotation(degToRad(phiDeg));
        b.setForearmRotation(degToRad(phiDeg));
        EXPECT_NEAR(a.calcPathLength(pt), b.calcPathLength(pt), kExactTol) << phiDeg;
    }
    for (double phiDeg : {-29.0, 0.0, 60.0}) {
        a.setForearmRotation(degToRad(phiDeg));
        b.setForearmRotation(degToRad(phiDeg));
        EXPECT_GT(a.calcPathLength(pt), b.calcPathLength(pt) + 1e-4) << phiDeg;   // through the point: longer
    }
    // Refused: a range on an arm without a forearm rotation, a malformed range, winding without a side.
    const std::string muscle = "name: bad\narm: arm/default_male.yaml\nmuscles:\n  - name: m\n    parameters: " +
                               std::string(ARMSIM_ASSET_DIR) + "/muscles/biceps_long_head.yaml\n    path:\n"
                               "      origin: {body: upper_arm, location: [0, 0.3, 0]}\n";
    const std::string noRotation = messageOf(writeTemp("conditional_no_rotation.yaml", muscle +
        "      via:\n        - {body: forearm, location: [0.02, -0.02, 0], active_rotation_deg: [-30, 90]}\n"
        "      insertion: {body: forearm, location: [0.01, -0.05, 0]}\n"));
    EXPECT_NE(noRotation.find("active_rotation_deg"), std::string::npos) << noRotation;
    EXPECT_NE(noRotation.find("forearm_rotation"), std::string::npos) << noRotation;
    const std::string reversed = messageOf(writeTemp("conditional_reversed.yaml", muscle +
        "      via:\n        - {body: forearm, location: [0.02, -0.02, 0], active_rotation_deg: [90, -30]}\n"
        "      insertion: {body: forearm, location: [0.01, -0.05, 0]}\n"));
    EXPECT_NE(reversed.find("= 90,-30"), std::string::npos) << reversed;
    EXPECT_NE(reversed.find(".yaml:9"), std::string::npos) << reversed;
    const std::string sideless = messageOf(writeTemp("winds_without_side.yaml", muscle +
        "      via:\n        - {body: upper_arm, cylinder: {centre: [0, 0, 0], axis: [0, 0, 1], radius: 0.01}, winds: true}\n"
        "      insertion: {body: forearm, location: [0.01, -0.05, 0]}\n"));
    EXPECT_NE(sideless.find("winds"), std::string::npos) << sideless;
    EXPECT_NE(sideless.find("side"), std::string::npos) << sideless;
}

// Muscle roles come from the model file (no muscle name in library code): the elbow names its biceps
// heads and synergists; a model without `roles:` has the primary alone; a role that leaves out the
// primary or names no muscle is refused with file, line and field.
TEST(ModelFile, RolesComeFromTheModelFile) {
    const ArmSetup& e = elbow();
    ASSERT_EQ(e.getBicepsHeads().size(), 2u);
    EXPECT_EQ(e.muscles[e.getBicepsHeads()[1]].params.name, "BICshort");
    ASSERT_EQ(e.synergists.size(), 2u);
    EXPECT_EQ(e.muscles[e.synergists[0]].params.name, "BRA");
    const ArmSetup thesis = loadModel("thesis");
    EXPECT_EQ(thesis.getBicepsHeads(), std::vector<int>{thesis.primary});
    EXPECT_TRUE(thesis.synergists.empty());
    const std::string head = "name: r\narm: arm/default_male.yaml\nmuscles:\n  - name: a\n    parameters: " +
                             std::string(ARMSIM_ASSET_DIR) + "/muscles/biceps_long_head.yaml\n" +
                             "    path:\n      origin: {body: upper_arm, location: [0, 0.3, 0]}\n"
                             "      insertion: {body: forearm, location: [0, -0.05, 0]}\n";
    std::string msg = messageOf(writeTemp("roles_bad1.yaml", head + "roles: {synergists: [BRA]}\n"));
    EXPECT_NE(msg.find("roles_bad1.yaml:9"), std::string::npos) << msg;
    EXPECT_NE(msg.find("'BRA'"), std::string::npos) << msg;
    msg = messageOf(writeTemp("roles_empty.yaml", head + "roles: {biceps: []}\n"));
    EXPECT_EQ(msg, "");   // empty: the primary alone
    msg = messageOf(writeTemp("roles_bad3.yaml", head.substr(0, head.find("  - name: a")) +
                                                     "  - name: b\n    parameters: " + std::string(ARMSIM_ASSET_DIR) +
                                                     "/muscles/biceps_short_head.yaml\n" +
                                                     "    path:\n      origin: {body: upper_arm, location: [0, 0.3, 0]}\n"
                                                     "      insertion: {body: forearm, location: [0, -0.05, 0]}\n" +
                                                     head.substr(head.find("  - name: a")) + "primary: a\nroles: {biceps: [b]}\n"));
    EXPECT_NE(msg.find("primary muscle 'a'"), std::string::npos) << msg;
}

// Issue 29: `muscle_model:` chooses each muscle's model: at the top for every muscle, in a muscle for
// that one (a name replaces the model, coefficients add to it); unknown models and coefficients are
// refused naming the file's line; a population's `muscle_model:` swaps the model and keeps the people.
TEST(ModelFile, MuscleModelKeyChoosesEachMusclesModel) {
    const std::string head = "name: hill\narm: " + std::string(ARMSIM_ASSET_DIR) + "/arm/default_male.yaml\n";
    const std::string file = writeTemp(
        "armsim_hill_model.yaml",
        head + "muscle_model: {model: thelen2003, activation_time_constant: 0.01}\nmuscles:\n" +
            makeMuscleEntry("A", "    mass: 0.1\n") +
            makeMuscleEntry("B", "    mass: 0.1\n    muscle_model: {deactivation_time_constant: 0.04}\n") +
            makeMuscleEntry("C", "    mass: 0.1\n    muscle_model: virtual_muscle\n"));
    const ArmSetup s = loadModel(file);
    ASSERT_EQ(s.getNumMuscles(), 3);
    const auto a = s.buildMuscleModel(0), b = s.buildMuscleModel(1), c = s.buildMuscleModel(2);
    EXPECT_STREQ(a->getModelName(), "thelen2003");
    EXPECT_STREQ(c->getModelName(), "virtual_muscle");
    const auto& ta = dynamic_cast<const Thelen2003Muscle&>(*a).getParameters();
    const auto& tb = dynamic_cast<const Thelen2003Muscle&>(*b).getParameters();
    EXPECT_EQ(ta.activationTimeConstant, 0.01);
    EXPECT_EQ(ta.deactivationTimeConstant, 0.05);  // assets/muscles/thelen2003.yaml
    EXPECT_EQ(tb.activationTimeConstant, 0.01);    // the model's, kept
    EXPECT_EQ(tb.deactivationTimeConstant, 0.04);  // the muscle's own
    // The same F0 in both models (F0 = sigma M / (rho L0)).
    EXPECT_DOUBLE_EQ(a->getF0(), c->getF0());
    EXPECT_FALSE(s.hasOnlyVirtualMuscles());
    // What models every muscle as a Virtual Muscle refuses a Hill-type one, naming it.
    EXPECT_NO_THROW(s.requireVirtualMuscles("the identifiers", 2));
    try {
        s.requireVirtualMuscles("the identifiers");
        ADD_FAILURE();
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("muscle 'A'"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("muscle_model thelen2003"), std::string::npos) << e.what();
    }

    const std::string unknown = writeTemp("armsim_hill_unknown.yaml", head + "muscle_model: hill\nmuscles:\n" +
                                                                          makeMuscleEntry("A", "    mass: 0.1\n"));
    EXPECT_NE(messageOf(unknown).find("armsim_hill_unknown.yaml:3"), std::string::npos) << messageOf(unknown);
    EXPECT_NE(messageOf(unknown).find("expected one of virtual_muscle, thelen2003"), std::string::npos) << messageOf(unknown);
    const std::string badKey = writeTemp(
        "armsim_hill_key.yaml", head + "muscles:\n" +
                                    makeMuscleEntry("A", "    mass: 0.1\n    muscle_model: {model: thelen2003, tau: 1}\n"));
    EXPECT_NE(messageOf(badKey).find("muscle_model.tau"), std::string::npos) << messageOf(badKey);
    EXPECT_NE(messageOf(badKey).find(":6"), std::string::npos) << messageOf(badKey);
    const std::string badValue = writeTemp(
        "armsim_hill_value.yaml", head + "muscle_model: {model: thelen2003, fmax_tendon_strain: -0.1}\nmuscles:\n" +
                                      makeMuscleEntry("A", "    mass: 0.1\n"));
    EXPECT_NE(messageOf(badValue).find("fmax_tendon_strain"), std::string::npos) << messageOf(badValue);
    EXPECT_NE(messageOf(badValue).find("-0.1"), std::string::npos) << messageOf(badValue);
}

// Issue 29: dP/dt of every twin path (via points, cylinders, spheres) from the virtual power of a unit
// tension equals the central difference of P along the elbow's motion.
TEST(MusclePath, LengtheningSpeedEqualsTheDerivativeOfTheLength) {
    const ArmSetup twin = loadModel("twin");
    const MuscleArm arm(twin, ActivationProfile::constant(0.0));
    SimTK::State s = arm.getDefaultState();
    const double u = 1.3, h = 1e-6;  // rad/s; rad
    for (double theta : {1.0, 1.8, 2.6}) {
        auto lengths = [&](double q) {
            arm.getArm().setElbowAngle(s, q);
            arm.getSystem().realize(s, SimTK::Stage::Position);
            std::vector<double> P;
            for (int i = 0; i < arm.getNumMuscles(); ++i) P.push_back(arm.calcPathLength(s, i));
            return P;
        };
        const std::vector<double> plus = lengths(theta + h), minus = lengths(theta - h);
        arm.getArm().setElbowAngle(s, theta);
        arm.getArm().getForearm().setOneU(s, 0, u);
        arm.getSystem().realize(s, SimTK::Stage::Velocity);
        const double qdot = arm.getArm().getElbowAngularVelocity(s);  // d(theta)/dt for this u
        for (int i = 0; i < arm.getNumMuscles(); ++i) {
            const MuscleForce& f = arm.getMuscleForce(i);
            const double speed = f.getPath().calcLengtheningSpeed(s, f.calcPathGeometry(s));
            const double expected = (plus[i] - minus[i]) / (2 * h) * qdot;
            EXPECT_NEAR(speed, expected, 1e-7) << arm.getMuscleName(i) << " at " << theta;
        }
    }
}
