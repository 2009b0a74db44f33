// The steppable simulation against the one-shot trials it must reproduce, and its state and excitation
// access between steps.
#include "basics/errors.h"
#include "model/model_file.h"
#include "model/simulation.h"
#include "model/trial.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

using namespace armsim;

namespace {

const ArmSetup& twin() {
    static const ArmSetup s = loadModel("twin");
    return s;
}

// Flexors driven by `flexors`, the rest at 0: what runFreeMovement does.
std::vector<ActivationProfile> flexorProfiles(const ArmSetup& setup, const ActivationProfile& flexors) {
    std::vector<ActivationProfile> p;
    for (const MuscleSpec& m : setup.muscles)
        p.push_back(m.group == MuscleGroup::Flexor ? flexors : ActivationProfile::constant(0.0));
    return p;
}

// Largest |a - b| over a column, and the column's largest |b|.
std::pair<double, double> compareColumns(const Table& a, const std::string& ca, const Table& b, const std::string& cb) {
    const std::vector<double> x = a.getColumn(ca), y = b.getColumn(cb);
    EXPECT_EQ(x.size(), y.size()) << ca;
    double worst = 0, largest = 0;
    for (std::size_t k = 0; k < std::min(x.size(), y.size()); ++k) {
        worst = std::max(worst, std::abs(x[k] - y[k]));
        largest = std::max(largest, std::abs(y[k]));
    }
    return {worst, largest};
}

}  // namespace

// One advanceTo over the whole movement is runFreeMovement's integration: the same steps, the same samples.
TEST(ArmSimulation, OneAdvanceIsTheFreeMovementTrial) {
    constexpr double kRelTol = 1e-12;  // same solver, same steps: rounding only
    FreeMovementSettings fm;
    fm.initialAngle = degToRad(120);
    fm.activation = ActivationProfile::step(0.05, 0.0, 0.6);
    fm.duration = 0.5;
    const Table trial = runFreeMovement(twin(), fm);

    SimulationSettings s;
    s.elbowAngle = fm.initialAngle;
    ArmSimulation sim(twin(), s, flexorProfiles(twin(), fm.activation));
    sim.advanceTo(fm.duration);
    const Table& t = sim.getSamples();
    ASSERT_EQ(t.getNumRows(), trial.getNumRows());
    for (const auto& [a, b] : std::vector<std::pair<std::string, std::string>>{
             {"time_s", "time_s"}, {"elbow_angle_deg", "elbow_angle_deg"}, {"elbow_velocity_degps", "elbow_velocity_degps"},
             {"force_BRA_N", "force_BRA_N"}, {"force_TRIlong_N", "force_TRIlong_N"}, {"excitation_BIClong", "activation_BIClong"},
             {"state_BICshort_L", "state_BICshort_L"}}) {
        const auto [worst, largest] = compareColumns(t, a, trial, b);
        EXPECT_LE(worst, kRelTol * std::max(largest, 1.0)) << a;
    }
    EXPECT_LT(sim.getElbowAngle(), degToRad(100));  // it flexed
    EXPECT_NEAR(sim.getTime(), fm.duration, 1e-15);
}

// Cut into calls at arbitrary times, the samples stay on the grid t0 + k / rate (none twice, none
// missing), and the movement equals the one-call run within the integration error.
TEST(ArmSimulation, CallsAtAnyTimesKeepTheSampleGridAndTheMovement) {
    constexpr double kAngleTol = 0.05;  // deg: restarts at each call change the steps (accuracy 1e-4)
    const ActivationProfile u = ActivationProfile::step(0.05, 0.0, 0.6);
    SimulationSettings s;
    s.elbowAngle = degToRad(120);
    s.sampleRate = 500;
    ArmSimulation whole(twin(), s, flexorProfiles(twin(), u));
    whole.advanceTo(0.4);
    ArmSimulation cut(twin(), s, flexorProfiles(twin(), u));
    for (double t : {0.0123, 0.0123, 0.05, 0.0771, 0.2, 0.20001, 0.333, 0.4}) cut.advanceTo(t);
    const Table& a = cut.getSamples();
    const Table& b = whole.getSamples();
    ASSERT_EQ(a.getNumRows(), 201);
    ASSERT_EQ(b.getNumRows(), 201);
    for (int k = 0; k < a.getNumRows(); ++k) EXPECT_NEAR(a.get(k, "time_s"), k / 500.0, 1e-12) << k;
    EXPECT_LE(compareColumns(a, "elbow_angle_deg", b, "elbow_angle_deg").first, kAngleTol);
    EXPECT_NEAR(cut.getTime(), 0.4, 1e-15);
    EXPECT_THROW(cut.advanceTo(0.3), InputError);
}

// Locked: the lock's torque and the muscle forces equal the isometric trial's reference solver (the
// same Simbody System, locked the same way).
TEST(ArmSimulation, LockedIsTheIsometricTrialsSimbodyReference) {
    constexpr double kRelTol = 1e-6;  // issue 30's agreement with the Simbody path
    IsometricTrialSettings it;
    it.elbowAngle = degToRad(90);
    it.restDuration = 0.2;
    it.holdDuration = 0.3;
    it.averagingWindow = 0.1;
    it.solver = TrialSolver::SimbodyPerSample;
    const IsometricTrialResult trial = runIsometricTrial(twin(), it);

    SimulationSettings s;
    s.lockedElbow = true;
    s.elbowAngle = it.elbowAngle;
    s.startSteady = true;
    ArmSimulation sim(twin(), s, it.calcActivationProfiles(twin()));
    sim.advanceTo(it.getDuration());
    const Table& t = sim.getSamples();
    for (const auto& [a, b] : std::vector<std::pair<std::string, std::string>>{
             {"holding_torque_Nm", "holding_torque_Nm"}, {"force_BIClong_N", "force_BIClong_N"},
             {"force_BRD_N", "force_BRD_N"}, {"elbow_angle_deg", "elbow_angle_deg"}}) {
        const auto [worst, largest] = compareColumns(t, a, trial.series, b);
        EXPECT_LE(worst, kRelTol * largest) << a;
    }
}

// A new excitation set between calls is a step in the profile given at the start.
TEST(ArmSimulation, ExcitationSetBetweenCallsIsAStepInTheProfile) {
    // Both restart at the step; the profile's last step before it sees U after the step at its end point
    // (BDF evaluates f there), the live run U before it: they differ by the integration error.
    constexpr double kRelTol = 1e-5;
    const ActivationProfile u = ActivationProfile::step(0.1, 0.2, 0.7);
    SimulationSettings s;
    s.elbowAngle = degToRad(110);
    s.integration.accuracy = 1e-8;
    ArmSimulation planned(twin(), s, flexorProfiles(twin(), u));
    planned.advanceTo(0.3);
    ArmSimulation live(twin(), s, flexorProfiles(twin(), ActivationProfile::constant(0.2)));
    live.advanceTo(0.1);
    live.setExcitations(flexorProfiles(twin(), ActivationProfile::constant(0.7)));
    live.advanceTo(0.3);
    const auto [worst, largest] = compareColumns(live.getSamples(), "force_BRA_N", planned.getSamples(), "force_BRA_N");
    EXPECT_LE(worst, kRelTol * largest);
    EXPECT_NEAR(live.getElbowAngle(), planned.getElbowAngle(), kRelTol);
}

// The state read back is the state written; a state the model cannot hold is refused whole.
TEST(ArmSimulation, StateSetAndGetRoundTripAndBadStatesAreRefused) {
    SimulationSettings s;
    ArmSimulation a(twin(), s), b(twin(), s);
    a.advanceTo(0.05);
    const std::vector<double> y = a.getMuscleStates();
    ASSERT_EQ(y.size(), a.getMuscleStateNames().size());
    b.setMuscleStates(y);
    b.setElbowAngle(a.getElbowAngle());
    b.setElbowVelocity(a.getElbowVelocity());
    EXPECT_EQ(b.getMuscleStates(), y);
    EXPECT_EQ(b.calcMuscleForces(), a.calcMuscleForces());
    std::vector<double> bad = y;
    bad[0] = NAN;
    EXPECT_THROW(b.setMuscleStates(bad), InputError);
    EXPECT_THROW(b.setMuscleStates({1.0}), InputError);
    EXPECT_EQ(b.getMuscleStates(), y);
    EXPECT_THROW(b.setElbowAngle(degToRad(200)), FieldError);
    SimulationSettings locked;
    locked.lockedElbow = true;
    ArmSimulation c(twin(), locked);
    EXPECT_THROW(c.setElbowVelocity(1.0), FieldError);
    c.setElbowAngle(degToRad(60));
    c.advanceTo(0.01);
    EXPECT_NEAR(c.getElbowAngle(), degToRad(60), 1e-12);  // held where it was put
}
