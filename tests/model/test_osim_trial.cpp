// Isometric trials of an .osim model (model/osim_trial.h) on arm26: the per-muscle integration at fixed
// paths against the whole Simbody System integrated with every coordinate locked, the end of a long hold
// against the steady isometric solve, and bad settings named by their field.
#include "model/osim_trial.h"

#include "basics/errors.h"
#include "model/osim_arm.h"
#include "model/osim_forward.h"
#include "muscles/simbody_isometric.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

using namespace armsim;

namespace {

const OsimModel& arm26() {
    static const OsimModel m = readOsimFile(std::string(ARMSIM_ASSET_DIR) + "/models/arm26.osim");
    return m;
}

constexpr double kDeg = 3.14159265358979323846 / 180;

std::string errorOf(const OsimIsometricTrialSettings& s) {
    try {
        runOsimIsometricTrial(arm26(), s);
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}

}  // namespace

// The trial's torque sum_i r_i F_i at every sample equals the one of the Simbody System integrated whole
// with both coordinates locked (CPodes on [q u z], every muscle's force from the MuscleForce, moment arms
// from the locked state): a second integration and a second geometry path. Both at accuracy 1e-8;
// tolerance 1e-5 of the peak torque (the two take different steps; measured 8.2e-7 and 4.7e-7).
TEST(OsimIsometricTrial, Arm26TorqueEqualsTheLockedSimbodySystem) {
    for (int direction : {1, -1}) {
        OsimIsometricTrialSettings s;
        s.coordinate = "r_elbow_flex";
        s.angleDeg = 60;
        s.direction = direction;
        s.antagonistActivation = 0.1;
        s.restDuration = 0.2;
        s.riseTime = 0.05;
        s.holdDuration = 0.4;
        s.averagingWindow = 0.2;
        s.sampleRate = 200;
        s.integration.accuracy = 1e-8;
        const OsimIsometricTrialResult r = runOsimIsometricTrial(arm26(), s);

        OsimModel locked = arm26();
        std::map<std::string, ActivationProfile> excitation;
        for (OsimJoint& joint : locked.joints)
            for (OsimCoordinate& c : joint.coordinates) {
                c.locked = true;
                if (c.name == s.coordinate) c.defaultValue = s.angleDeg * kDeg;
            }
        for (std::size_t i = 0; i < locked.muscles.size(); ++i)
            excitation[locked.muscles[i].name] = ActivationProfile::ramp(
                s.restDuration, s.restDuration + s.riseTime, 0.0, r.summary.agonists[i] ? s.activation : s.antagonistActivation);
        const OsimArm arm(locked, excitation);
        const int j = arm.findCoordinate(s.coordinate);
        SimTK::State state = arm.getDefaultState();
        arm.getSystem().realize(state, SimTK::Stage::Position);
        for (int i = 0; i < arm.getNumMuscles(); ++i)
            arm.getMuscleForce(i).setMuscleStates(state, arm.getMuscleForce(i).getMuscle().calcInitialState(arm.calcPathLength(state, i)));
        std::vector<double> torque;
        simulateSampled(arm.getSystem(), state, s.getDuration(), s.sampleRate, {s.restDuration, s.restDuration + s.riseTime},
                        s.integration, [&](const SimTK::State& x) {
                            arm.getSystem().realize(x, SimTK::Stage::Dynamics);
                            double sum = 0;
                            for (int i = 0; i < arm.getNumMuscles(); ++i)
                                sum += arm.calcMomentArm(x, i, j) * arm.getMuscleForce(i).getForce(x);
                            torque.push_back(sum);
                        });
        const std::vector<double> trial = r.series.getColumn("muscle_torque_Nm");
        ASSERT_EQ(trial.size(), torque.size());
        double peak = 0, worst = 0;
        for (double v : torque) peak = std::max(peak, std::abs(v));
        for (std::size_t k = 0; k < torque.size(); ++k) worst = std::max(worst, std::abs(trial[k] - torque[k]));
        EXPECT_LT(worst, 1e-5 * peak) << "direction " << direction << ": peak " << peak << " N m";
        EXPECT_GT(direction * r.summary.meanTaredTorque, 10) << "the effort turns the elbow its way";
        // The tare: the first sample reads zero, the raw torque there is the passive torque.
        EXPECT_EQ(r.series.get(0, "tared_torque_Nm"), 0.0);
        EXPECT_NEAR(r.series.get(0, "muscle_torque_Nm"), r.summary.restTorque, 1e-12);
    }
}

// At the end of a 3 s hold at full excitation the muscles are at their steady isometric states: the
// torque equals sum_i r_i F_i of MuscleModel::calcSteadyState at U = 1 for the agonists and 0 for the
// others (`model show`'s MVC curve), to 1e-3 relative, at three elbow angles, both directions.
// Measured: 1.1e-7 to 1.9e-4.
TEST(OsimIsometricTrial, LongHoldEndsAtTheSteadyTorque) {
    const OsimArm arm(arm26());
    const int j = arm.findCoordinate("r_elbow_flex");
    for (double deg : {20.0, 80.0, 120.0})
        for (int direction : {1, -1}) {
            OsimIsometricTrialSettings s;
            s.coordinate = "r_elbow_flex";
            s.angleDeg = deg;
            s.direction = direction;
            s.sampleRate = 100;
            const OsimIsometricTrialResult r = runOsimIsometricTrial(arm26(), s);
            SimTK::State state = arm.getDefaultState();
            arm.setCoordinateValue(state, j, deg * kDeg);
            arm.getSystem().realize(state, SimTK::Stage::Position);
            double steady = 0;
            for (int i = 0; i < arm.getNumMuscles(); ++i) {
                const double R = arm.calcMomentArm(state, i, j);
                const bool agonist = direction * R > kOsimAgonistMomentArm;
                const SteadyState ss =
                    arm.getMuscleForce(i).getMuscle().calcSteadyState(arm.calcPathLength(state, i), agonist ? 1.0 : 0.0);
                ASSERT_TRUE(ss.converged) << ss.message;
                steady += R * ss.force;
                EXPECT_EQ(r.summary.agonists[i], agonist);
            }
            const double last = r.series.get(r.series.getNumRows() - 1, "muscle_torque_Nm");
            EXPECT_NEAR(last, steady, 1e-3 * std::abs(steady)) << deg << " deg, direction " << direction;
        }
}

// A muscle that does not cross the coordinate has a moment arm of rounding size about it, not zero: it
// is no agonist either way (arm26's shoulder: BRA, TRIlat and TRImed span the elbow only).
TEST(OsimIsometricTrial, MusclesThatDoNotCrossTheCoordinateAreNoAgonists) {
    for (int direction : {1, -1}) {
        OsimIsometricTrialSettings s;
        s.coordinate = "r_shoulder_elev";
        s.angleDeg = 80;
        s.direction = direction;
        s.holdDuration = 0.2;
        s.restDuration = 0.1;
        s.averagingWindow = 0.1;
        s.sampleRate = 100;
        const OsimIsometricTrialResult r = runOsimIsometricTrial(arm26(), s);
        for (std::size_t i = 0; i < r.summary.muscles.size(); ++i) {
            const std::string& m = r.summary.muscles[i];
            if (m == "BRA" || m == "TRIlat" || m == "TRImed") {
                EXPECT_LT(std::abs(r.summary.momentArms[i]), 1e-12) << m;
                EXPECT_FALSE(r.summary.agonists[i]) << m << ", direction " << direction;
            }
        }
    }
}

// Bad settings: the field, the value and what was expected.
TEST(OsimIsometricTrial, BadSettingsNameTheField) {
    OsimIsometricTrialSettings s;
    s.coordinate = "r_elbow_flex";
    s.angleDeg = 200;
    EXPECT_NE(errorOf(s).find("angle_deg"), std::string::npos) << errorOf(s);
    EXPECT_NE(errorOf(s).find("200"), std::string::npos) << errorOf(s);
    s.angleDeg = 90;
    s.coordinate = "r_knee";
    EXPECT_NE(errorOf(s).find("'r_knee': not a coordinate of arm26 (r_shoulder_elev, r_elbow_flex)"), std::string::npos)
        << errorOf(s);
    s.coordinate = "";
    EXPECT_NE(errorOf(s).find("name the one to lock"), std::string::npos) << errorOf(s);
    s.coordinate = "r_elbow_flex";
    OsimModel none = arm26();   // no muscles: nothing to excite
    none.muscles.clear();
    try {
        runOsimIsometricTrial(none, s);
        ADD_FAILURE() << "a model without muscles ran";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("has no muscles"), std::string::npos) << e.what();
    }
    OsimModel locked = arm26();   // a free movement of a coordinate the file locks
    for (OsimJoint& j : locked.joints)
        for (OsimCoordinate& c : j.coordinates) c.locked = c.locked || c.name == "r_elbow_flex";
    OsimFreeMovementSettings f;
    f.coordinate = "r_elbow_flex";
    try {
        runOsimFreeMovement(locked, f);
        ADD_FAILURE() << "a locked coordinate moved";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("'r_elbow_flex' is locked in"), std::string::npos) << e.what();
    }
    s.activation = 1.5;
    EXPECT_NE(errorOf(s).find("activation"), std::string::npos) << errorOf(s);
    s.activation = 1;
    s.averagingWindow = 5;
    EXPECT_NE(errorOf(s).find("averaging_window"), std::string::npos) << errorOf(s);
}

// A free movement (the elbow free from 20 deg, the shoulder held, the flexors ramped to 0.4 from 0.1 s)
// against the Forward tool's path (model/osim_forward.h) on the same model with the shoulder locked and
// a controls table holding the same ramp: another excitation reader and another start (the controls'
// equilibrium). Both at accuracy 1e-7; the trial restarts the integrator at the ramp's corners, the
// Forward tool does not, so they differ by their integration errors: tolerance 1e-3 deg and 1e-5 in
// activation (measured 9.6e-5 deg and 5.1e-7).
TEST(OsimFreeMovement, EqualsTheForwardToolWithTheSameControls) {
    OsimFreeMovementSettings s;
    s.coordinate = "r_elbow_flex";
    s.initialAngleDeg = 20;
    s.activation = 0.4;
    s.onset = 0.1;
    s.rise = 0.05;
    s.duration = 0.6;
    s.sampleRate = 100;
    s.integration.accuracy = 1e-7;
    IntegrationStats stats;
    const Table t = runOsimFreeMovement(arm26(), s, &stats);
    ASSERT_EQ(t.getNumRows(), 61);
    EXPECT_GT(t.get(60, "r_elbow_flex_deg"), 30.0) << "the flexors flex the elbow";

    OsimModel held = arm26();   // the shoulder held at its default; the elbow starts at 20 deg from a states table
    for (OsimJoint& joint : held.joints)
        for (OsimCoordinate& c : joint.coordinates)
            if (c.name == "r_shoulder_elev") c.locked = true;
    OsimStorage start;
    start.file = "states";
    start.table = Table({"time", "r_elbow_flex"});
    start.table.appendRow({0.0, 20 * kDeg});
    OsimStorage controls;
    controls.file = "controls";
    std::vector<std::string> names{"time"};
    for (const OsimMuscle& m : held.muscles) names.push_back(m.name);
    controls.table = Table(names);
    const bool flexor[] = {false, false, false, true, true, true};   // TRIlong, TRIlat, TRImed, BIClong, BICshort, BRA
    for (double time : {0.0, 0.1, 0.15, 0.6}) {
        std::vector<double> row{time};
        for (bool f : flexor) row.push_back(f && time > 0.1 ? 0.4 : 0.0);
        controls.table.appendRow(row);
    }
    OsimForwardSettings f;
    f.initialTime = 0;
    f.finalTime = 0.6;
    f.sampleRate = 100;
    f.integration.accuracy = 1e-7;
    const OsimForwardResult r = runOsimForward(held, controls, &start, f);
    ASSERT_EQ(r.states.getNumRows(), 61);
    double worstAngle = 0, worstActivation = 0;
    for (int k = 0; k < 61; ++k) {
        worstAngle = std::max(worstAngle, std::abs(t.get(k, "r_elbow_flex_deg") - r.states.get(k, "r_elbow_flex") / kDeg));
        for (const char* m : {"BIClong", "TRIlong"})
            worstActivation = std::max(worstActivation, std::abs(t.get(k, std::string("activation_") + m) -
                                                                 r.states.get(k, std::string(m) + ".activation")));
    }
    EXPECT_LT(worstAngle, 1e-3);
    EXPECT_LT(worstActivation, 1e-5);
}
