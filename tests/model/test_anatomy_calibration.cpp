// Calibration to anatomy (model/anatomy_calibration.h): a model with known scales makes the targets;
// the fit recovers its volumes and predicts its torque where it was not fitted (identified vs true);
// the twin's file read back two ways.
#include "basics/errors.h"
#include "model/anatomy_calibration.h"
#include "model/mvc_curve.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

using namespace armsim;

namespace {

constexpr double kBandHalfWidth = 0.005;    // targets made from the truth: +/- 0.5 %
constexpr double kVolumeScaleTol = 0.01;    // relative: volumes are pinned by their own targets
constexpr double kHeldOutTorqueTol = 0.02;  // relative: flexion MVC at angles between the targets' ones
constexpr double kExactTol = 1e-9;

AnatomyTarget makeTarget(TargetKind kind, const std::string& muscle, MuscleGroup direction, double deg, double value) {
    AnatomyTarget t;
    t.kind = kind;
    t.muscle = muscle;
    t.direction = direction;
    t.flexionDeg = deg;
    t.lower = value * (1 - kBandHalfWidth);
    t.upper = value * (1 + kBandHalfWidth);
    t.source = "truth model";
    return t;
}

}  // namespace

TEST(AnatomyCalibration, RecoversTheScalesOfAModelThatMadeTheTargets) {
    const ArmSetup twin = loadModel("twin");
    const std::vector<MuscleCalibration> identity(twin.muscles.size());
    const ArmSetup source = applyCalibration(twin, identity);
    // The truth: flexors 1.4x stronger per area and 1.3x larger, extensors 1.2x and 1.1x; the forearm
    // rotators (no elbow moment arm, no target sees them) as the file.
    std::vector<MuscleCalibration> truthScales(twin.muscles.size());
    for (std::size_t m = 0; m < truthScales.size(); ++m) {
        const MuscleGroup group = twin.muscles[m].group;
        if (group == MuscleGroup::Forearm) continue;
        const bool flexor = group == MuscleGroup::Flexor;
        truthScales[m].specificTensionScale = flexor ? 1.4 : 1.2;
        truthScales[m].forceScale = flexor ? 1.3 : 1.1;  // f = 1: k = v
    }
    const ArmSetup truth = applyCalibration(twin, truthScales);
    std::vector<AnatomyTarget> targets;
    // Four angles: with a fused MVC drive (fmax 3) the twin's curve is more peaked, and three angles
    // 20-30 deg apart (60, 90, 110) left it 3.4 % off at 100 deg.
    const std::vector<double> angles = {60, 80, 90, 110};
    const SteadyMvcCurve flexion = calcSteadyMvcCurve(truth, MuscleGroup::Flexor, truth.effort, angles);
    for (std::size_t a = 0; a < angles.size(); ++a)
        targets.push_back(makeTarget(TargetKind::Mvc, "", MuscleGroup::Flexor, angles[a], flexion.totalTorque[a]));
    const SteadyMvcCurve extension = calcSteadyMvcCurve(truth, MuscleGroup::Extensor, truth.effort, {90});
    targets.push_back(makeTarget(TargetKind::Mvc, "", MuscleGroup::Extensor, 90, -extension.totalTorque[0]));
    for (const char* family : {"BIC", "BRA", "BRD", "TRI"}) {
        double v = 0;
        for (const MuscleSpec& m : truth.muscles)
            if (doesFamilyCoverMuscle(family, m.params.name)) v += m.params.mass / m.params.coefficients.density;
        targets.push_back(makeTarget(TargetKind::Volume, family, MuscleGroup::Flexor, NAN, v));
    }

    const AnatomyCalibrationResult r = calibrateToAnatomy(source, targets);
    int passedBefore = 0, passedAfter = 0;
    for (const TargetScore& s : r.before) passedBefore += s.pass;
    for (const TargetScore& s : r.after) passedAfter += s.pass;
    EXPECT_LT(passedBefore, int(targets.size()));   // the source model misses them
    EXPECT_EQ(passedAfter, int(targets.size())) << r.report;
    ASSERT_EQ(r.groups.size(), 3u);
    for (const GroupScales& g : r.groups) {
        const double truth = g.group == MuscleGroup::Flexor ? 1.3 : g.group == MuscleGroup::Extensor ? 1.1 : 1.0;
        EXPECT_NEAR(g.volume, truth, kVolumeScaleTol * truth) << getMuscleGroupName(g.group);
    }
    // s, f and t trade against each other in the torque (only volumes pin v): judge the fitted model by
    // the truth's torque at angles it was not fitted to.
    const ArmSetup fitted = applyCalibration(twin, r.muscles);
    const std::vector<double> heldOut = {70, 100};  // midway between fitted angles
    const SteadyMvcCurve a = calcSteadyMvcCurve(fitted, MuscleGroup::Flexor, fitted.effort, heldOut);
    const SteadyMvcCurve b = calcSteadyMvcCurve(truth, MuscleGroup::Flexor, truth.effort, heldOut);
    for (std::size_t i = 0; i < heldOut.size(); ++i)
        EXPECT_NEAR(a.totalTorque[i], b.totalTorque[i], kHeldOutTorqueTol * b.totalTorque[i]) << heldOut[i] << " deg";
    // The result's calibration is the groups' scales: k = v / f.
    for (std::size_t m = 0; m < r.muscles.size(); ++m) {
        const GroupScales& g = *std::find_if(r.groups.begin(), r.groups.end(),
                                             [&](const GroupScales& x) { return x.group == twin.muscles[m].group; });
        EXPECT_NEAR(r.muscles[m].forceScale * r.muscles[m].fascicleLengthScale, g.volume, kExactTol);
        EXPECT_NEAR(r.muscles[m].specificTensionScale, g.specificTension, kExactTol);
    }
}

// The twin's file: F0 = s sigma V' / L0' with V' = k f V (its calibration applied to the MRI volume)
// against the Virtual Muscle's own F0 = sigma M / (rho L0).
TEST(AnatomyCalibration, TwinForceFollowsVolumeAndSpecificTension) {
    const ArmSetup twin = loadModel("twin");
    ASSERT_EQ(twin.getNumMuscles(), 10);
    EXPECT_EQ(twin.specificTension, 300000);
    for (int m = 0; m < twin.getNumMuscles(); ++m) {
        const MuscleSpec& spec = twin.muscles[m];
        const MuscleCalibration& c = spec.calibration;
        const double V = spec.sourceParams.mass / spec.sourceParams.coefficients.density;   // the file's volume
        const double L0 = spec.params.optimalFascicleLength;
        const double expected = c.specificTensionScale * 300000 * (c.forceScale * c.fascicleLengthScale * V) / L0;
        EXPECT_NEAR(VirtualMuscle(twin.calcMuscleParameters(m)).getF0(), expected, 1e-9 * expected) << spec.params.name;
        EXPECT_NEAR(L0, c.fascicleLengthScale * spec.sourceParams.optimalFascicleLength, 1e-15);
    }
}

TEST(AnatomyCalibration, RejectsTargetsThatNameNoMuscleOfTheModel) {
    const ArmSetup twin = loadModel("twin");
    AnatomyTarget t = makeTarget(TargetKind::Volume, "DELT", MuscleGroup::Flexor, NAN, 1e-4);
    EXPECT_THROW(calibrateToAnatomy(twin, {t}), InputError);
    AnatomyCalibrationOptions bad;
    bad.volumeSd = 0;
    EXPECT_THROW(calibrateToAnatomy(twin, {t}, bad), FieldError);
}

// The goal stages: a wide band far from the prior. The band's shape alone (a Gaussian about its centre)
// and the prior settle between them, below the band; with the goal as a constraint the fit ends inside.
TEST(AnatomyCalibration, GoalStagesMeetABandTheBandsShapeAloneMisses) {
    const ArmSetup twin = loadModel("twin");
    double v = 0;   // the biceps' volume as calibrated
    for (const MuscleSpec& m : twin.muscles)
        if (doesFamilyCoverMuscle("BIC", m.params.name)) v += m.params.mass / m.params.coefficients.density;
    AnatomyTarget t = makeTarget(TargetKind::Volume, "BIC", MuscleGroup::Flexor, NAN, 0);
    const double identityV = v / twin.muscles[0].calibration.forceScale / twin.muscles[0].calibration.fascicleLengthScale;
    t.lower = 2.2 * identityV;   // the scale's prior sd is 0.40 in ln units: 2.2x is 2 sd out
    t.upper = 3.2 * identityV;
    AnatomyCalibrationOptions shapeOnly;
    shapeOnly.goalStages.clear();
    const AnatomyCalibrationResult a = calibrateToAnatomy(twin, {t}, shapeOnly);
    const AnatomyCalibrationResult b = calibrateToAnatomy(twin, {t});
    ASSERT_EQ(a.after.size(), 1u);
    ASSERT_EQ(b.after.size(), 1u);
    EXPECT_FALSE(a.after[0].pass) << a.after[0].value / identityV;
    EXPECT_TRUE(b.after[0].pass) << b.after[0].value / identityV;
    // Inside by most of the margin (1 % of the band's centre without a tolerance; the goal is a steep
    // penalty, not a hard bound, so the prior leaves a little of it).
    EXPECT_GE(b.after[0].value, t.lower + 0.5 * 0.01 * 0.5 * (t.lower + t.upper));
}
