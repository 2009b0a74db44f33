// Strength calibration (model/strength_calibration.h) against ground truth.
#include "basics/errors.h"
#include "model/strength_calibration.h"

#include <gtest/gtest.h>

using namespace armsim;

// A target made by the elbow model with known scales is fitted back to them: no prior, no mid-range
// penalty, fascicle length fixed (force and tendon scales are identifiable from 12 torque samples).
TEST(StrengthCalibration, RecoversKnownScales) {
    constexpr double kScaleTol = 1e-3;
    const ArmSetup elbow = loadModel("elbow");
    std::vector<MuscleCalibration> truth;
    for (const MuscleSpec& m : elbow.muscles) truth.push_back(m.calibration);
    const double tendon[] = {0.92, 1.05, 0.8, 0.9};
    int j = 0;
    for (std::size_t i = 0; i < truth.size(); ++i)
        if (elbow.muscles[i].group == MuscleGroup::Flexor) {
            truth[i] = MuscleCalibration{1.3, 1.0, tendon[j++]};
        }
    const ArmSetup truthModel = applyCalibration(elbow, truth);
    MvcTorqueTarget target;
    for (double q = 20; q <= 130; q += 10) target.flexionDeg.push_back(q);
    target.torque = calcSteadyMvcCurve(truthModel, MuscleGroup::Flexor, truthModel.effort, target.flexionDeg).totalTorque;

    StrengthCalibrationOptions o;
    o.fitFascicleLength = false;
    o.regularization = 0;
    o.midRangeWeight = 0;
    const StrengthCalibrationResult r = calibrateStrength(elbow, target, o);
    EXPECT_TRUE(r.converged) << r.report;
    EXPECT_LT(r.maxTorqueError, 1e-3);
    for (std::size_t i = 0; i < truth.size(); ++i) {
        EXPECT_NEAR(r.muscles[i].forceScale, truth[i].forceScale, kScaleTol) << elbow.muscles[i].params.name;
        EXPECT_NEAR(r.muscles[i].tendonLengthScale, truth[i].tendonLengthScale, kScaleTol) << elbow.muscles[i].params.name;
        EXPECT_NEAR(r.muscles[i].fascicleLengthScale, truth[i].fascicleLengthScale, kScaleTol);
    }
}

// The shipped elbow is the calibration's own output: refitting from it moves nothing.
TEST(StrengthCalibration, ShippedElbowIsAFixedPoint) {
    constexpr double kScaleTol = 2e-3;   // the file keeps 4 decimals
    const ArmSetup elbow = loadModel("elbow");
    std::vector<MuscleCalibration> source(elbow.muscles.size());  // fit from the source values
    const ArmSetup uncalibrated = applyCalibration(elbow, source);
    const StrengthCalibrationResult r = calibrateStrength(uncalibrated, getElbowFlexionTarget());
    for (std::size_t i = 0; i < elbow.muscles.size(); ++i) {
        if (elbow.muscles[i].group != MuscleGroup::Flexor) continue;
        EXPECT_NEAR(r.muscles[i].forceScale, elbow.muscles[i].calibration.forceScale, kScaleTol);
        EXPECT_NEAR(r.muscles[i].fascicleLengthScale, elbow.muscles[i].calibration.fascicleLengthScale, kScaleTol);
        EXPECT_NEAR(r.muscles[i].tendonLengthScale, elbow.muscles[i].calibration.tendonLengthScale, kScaleTol);
    }
}

TEST(StrengthCalibration, BadTargetsAreRejected) {
    const ArmSetup elbow = loadModel("elbow");
    MvcTorqueTarget t;
    EXPECT_THROW(calibrateStrength(elbow, t), InputError);
    t.flexionDeg = {170};
    t.torque = {50};
    EXPECT_THROW(calibrateStrength(elbow, t), InputError);  // outside the elbow's range
    t.effort = MuscleGroup::Extensor;
    const ArmSetup thesis = loadModel("thesis");
    t.flexionDeg = {90};
    EXPECT_THROW(calibrateStrength(thesis, t), InputError);  // the thesis model has no extensor
}
