// Trials on the biceps arm: isometric contractions with the elbow locked (the thesis's MVC setup:
// wrist strap, force transducer, gravity tare) and free movement with the elbow unlocked.
// A trial is a function of (subject, settings) returning a result table; each builds its own
// Simbody System, so trials run in parallel threads and give the same numbers as a sequential run.
#pragma once

#include "model/biceps_arm.h"
#include "muscles/simbody_isometric.h"
#include "muscles/table.h"

#include <functional>
#include <string>
#include <vector>

namespace armsim {

class ParamNode;

/// Trial tables end with one column per muscle state, named this prefix + the state's name
/// ("state_L", "state_feff_3"), so a recorded trial can be replayed exactly (rendering, analysis).
inline const std::string kStateColumnPrefix = "state_";

/// Sets time, elbow angle and velocity, and every muscle state of `state` from one row of a trial
/// table (isometric or free movement). Throws InputError if a state column is missing.
void setStateFromTrialRow(const BicepsArm& model, const Table& table, int row, SimTK::State& state);

/// An isometric trial: elbow locked at theta; rest (muscle off, transducer tared), activation rises
/// to the target (step or ramp), held; sampled at sampleRate.
struct IsometricTrialSettings {
    double elbowAngle = 90 * 3.14159265358979323846 / 180;  ///< theta, included angle [rad]
    double activation = 1.0;       ///< target U during the hold [1]
    double restDuration = 0.5;     ///< muscle inactive; the transducer is tared at its start [s]
    double riseTime = 0.0;         ///< ramp from 0 to the target; 0 = step [s]
    double holdDuration = 3.0;     ///< time at the target [s] (thesis: 3 s efforts)
    double sampleRate = 1000.0;    ///< output rate [Hz] (thesis: 1000 Hz)
    double averagingWindow = 1.0;  ///< end of the hold averaged for the summary [s]
    /// How the holding torque is read. false (default): findMotionForces at every integrator step;
    /// a sample between two steps takes the torque interpolated linearly in the muscle force, which is
    /// exact for a locked elbow (gravity and the stop are constant there, so the lock's torque is
    /// affine in Fse). true: realize every sample and call findMotionForces on it (3x slower; the
    /// reference the tests compare the default with).
    bool realizeEverySample = false;
    IntegrationSettings integration;

    /// Throws InputError naming the field unless every value is in range (angle inside the arm's
    /// elbow range, durations positive, activation in [0, 1], window inside the hold).
    void validate(const ArmParameters& arm) const;
    /// Onset, rise and hold as an activation profile.
    ActivationProfile calcActivationProfile() const;
    double getDuration() const { return restDuration + riseTime + holdDuration; }
};

/// Summary of an isometric trial, averaged over the last averagingWindow of the hold.
struct IsometricSummary {
    double elbowAngle = 0;          ///< theta [rad]
    double pathLength = 0;          ///< P [m]
    double momentArm = 0;           ///< h [m]
    double tareTorque = 0;          ///< holding torque at rest, subtracted by the tare [N m]
    double restForce = 0;           ///< passive muscle force at rest (hidden by the tare) [N]
    double finalForce = 0;          ///< true muscle force Fse at the last sample [N]
    double meanForce = 0;           ///< true muscle force, window mean [N]
    double meanStrapForce = 0;      ///< transducer reading, window mean [N]
    double meanForceMomentArm = 0;  ///< estimate from tared torque / h, window mean [N]
    double meanForceFixedRatio = 0; ///< thesis fixed-ratio estimate, window mean [N]
    bool saturated = false;         ///< the transducer exceeded its range at some sample
    IntegrationStats stats;
};

struct IsometricTrialResult {
    /// Columns: time_s, activation, elbow_angle_deg, elbow_velocity_degps (0: locked),
    /// muscle_force_N, fascicle_length_m, fascicle_velocity_mps,
    /// holding_torque_Nm (raw lock torque, + = flexion), muscle_torque_Nm (tared, + = flexion),
    /// strap_force_N (transducer reading, clipped to its range), saturated (0/1),
    /// force_moment_arm_N, force_fixed_ratio_N, error_moment_arm_pct, error_fixed_ratio_pct
    /// (errors of the estimates against the true muscle force), then the muscle states.
    Table series;
    IsometricSummary summary;
};

IsometricTrialResult runIsometricTrial(const ArmSetup& setup, const IsometricTrialSettings& settings);

/// Runs several isometric trials on `jobs` threads (one System per trial). Results are in input
/// order and identical to a sequential run. progress(done, total) is called from the caller's thread.
std::vector<IsometricTrialResult> runIsometricTrials(const ArmSetup& setup,
                                                     const std::vector<IsometricTrialSettings>& settings,
                                                     int jobs,
                                                     const std::function<void(int, int)>& progress = {});

/// Free movement: the elbow unlocked, an optional load in the hand, an activation profile.
struct FreeMovementSettings {
    double initialAngle = 150 * 3.14159265358979323846 / 180;  ///< theta at t = 0 [rad]
    double initialVelocity = 0.0;      ///< dtheta/dt at t = 0 [rad/s]
    ActivationProfile activation = ActivationProfile::step(0.2, 0.0, 0.5);  ///< U(t)
    double duration = 2.0;             ///< [s]
    double handLoad = 0.0;             ///< mass held in the hand [kg]
    double sampleRate = 1000.0;        ///< [Hz]
    /// true: the muscle starts at its steady state for U(0) at the initial path (V = 0);
    /// false: the spec-5 initial state.
    bool startSteady = true;
    IntegrationSettings integration;
    void validate(const ArmParameters& arm) const;
};

/// Columns: time_s, activation, elbow_angle_deg, elbow_velocity_degps (+ = extending),
/// path_length_m, moment_arm_m, muscle_force_N, fascicle_length_m, fascicle_velocity_mps,
/// active_fraction, then the muscle states.
Table runFreeMovement(const ArmSetup& setup, const FreeMovementSettings& settings, IntegrationStats* stats = nullptr);

/// Reads trial settings from a YAML mapping (keys: elbow_angle_deg, activation, rest, rise, hold,
/// sample_rate, accuracy, averaging_window); unknown keys are errors naming file and line.
IsometricTrialSettings readIsometricTrialSettings(const ParamNode& node, const ArmParameters& arm);
/// Keys: initial_angle_deg, initial_velocity_degps, activation, onset, rise, duration, hand_load,
/// sample_rate, accuracy.
FreeMovementSettings readFreeMovementSettings(const ParamNode& node, const ArmParameters& arm);

}  // namespace armsim
