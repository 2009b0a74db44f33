// Trials on the biceps arm: isometric contractions with the elbow locked (the thesis's MVC setup:
// wrist strap, force transducer, gravity tare) and free movement with the elbow unlocked.
// A trial is a function of (subject, settings) returning a result table; each builds its own
// Simbody System, so trials run in parallel threads and give the same numbers as a sequential run.
#pragma once

#include "basics/numbers.h"

#include "basics/angles.h"
#include "basics/table.h"
#include "model/muscle_arm.h"
#include "muscles/simbody_isometric.h"

#include <functional>
#include <string>
#include <vector>

namespace armsim {

class ParamNode;

/// Trial tables end with one column per muscle state (MuscleArm::getStateColumnNames: "state_L",
/// "state_feff_3" for a one-muscle model, "state_<muscle>_L" otherwise), so a recorded trial can be
/// replayed exactly (rendering, analysis). Models with several muscles also get per-muscle columns
/// force_<muscle>_N and activation_<muscle>.
inline const std::string kStateColumnPrefix = "state_";

/// Sets time, elbow angle and velocity, and every muscle state of `state` from one row of a trial
/// table (isometric or free movement). Throws InputError if a state column is missing.
void setStateFromTrialRow(const MuscleArm& model, const Table& table, int row, SimTK::State& state);

/// The activation of every muscle of a model over a trial, as recorded in a trial table: the
/// activation_<muscle> columns, or the `activation` column for every muscle of a one-muscle model.
std::vector<ActivationProfile> readActivationProfiles(const ArmSetup& setup, const Table& table,
                                                      const std::string& tableName);

/// An isometric trial: elbow locked at theta; rest (muscles off, transducer tared), activation rises
/// to the target (step or ramp), held; sampled at sampleRate. The agonists (muscles of the effort's
/// group) rise to `activation`, the antagonists to `antagonistActivation` (co-contraction).
/// How an isometric (locked-elbow) trial is integrated. Every solver reads the holding torque as the
/// torque at rest (findMotionForces) less sum_i h_i (F_i - F_i,rest), with every muscle's force from
/// its interpolated states: exact for a locked elbow (gravity, the stop and the moment arms are
/// constant there), except SimbodyPerSample.
enum class TrialSolver {
    /// Default: the locked arm's ODE on the System's own state vector [q u z] (q' = u = 0, u' = 0,
    /// every muscle's z' from its pure model at its fixed path length) integrated by CPodes directly
    /// (integrateSampled), without realizing the multibody System at every right-hand side.
    LockedOde,
    /// The whole Simbody System integrated by CPodesIntegrator (simulateSampled): the reference the
    /// tests compare LockedOde with (same steps, samples within 1e-6 relative; 5-10x slower).
    SimbodySystem,
    /// SimbodySystem, and every sample realized to Stage::Acceleration with the lock's torque read by
    /// findMotionForces: the reference of the torque formula (slower still).
    SimbodyPerSample
};

struct IsometricTrialSettings {
    double elbowAngle = degToRad(90);  ///< theta, included angle [rad]
    /// Forearm rotation the radius is locked at [deg], + = supination; NaN = the model's posture. Only
    /// for a model with a forearm rotation (InputError otherwise).
    double forearmRotationDeg = kNaN;
    double activation = 1.0;       ///< target U of the agonists during the hold [1]
    /// What the subject does: a flexion or an extension effort, or (a model with a forearm rotation) a
    /// supination or a pronation effort, whose agonists turn the forearm that way in the pose.
    Effort effort = Effort::Flexion;
    double antagonistActivation = 0.0;  ///< target U of the other group during the hold [1]
    double restDuration = 0.5;     ///< muscle inactive; the transducer is tared at its start [s]
    double riseTime = 0.0;         ///< ramp from 0 to the target; 0 = step [s]
    double holdDuration = 3.0;     ///< time at the target [s] (thesis: 3 s efforts)
    double sampleRate = 1000.0;    ///< output rate [Hz] (thesis: 1000 Hz)
    double averagingWindow = 1.0;  ///< end of the hold averaged for the summary [s]
    /// How the trial is integrated and the holding torque read (TrialSolver).
    TrialSolver solver = TrialSolver::LockedOde;
    /// LockedOde with several muscles: Newton's systems as a band matrix (the muscles' states are
    /// independent blocks; numerics/stiff_ode.h), cost linear in the muscles. false: the dense solve.
    bool bandedNewton = true;
    /// With bandedNewton: Newton's matrices from the muscle models' analytic Jacobians
    /// (MuscleModel::calcStateJacobian; a model without one is differenced) instead of CPODES'
    /// difference quotients. Off by default: it takes 7-15 % more steps and is 6-12 % slower
    /// (docs/benchmarks.md, the motor units' rise/fall switch at fint = feff, which the quotients smooth).
    bool analyticJacobian = false;
    IntegrationSettings integration;
    /// Optional: called with the time [s] of every sample (a long hold's progress).
    std::function<void(double)> progress;

    /// Throws InputError naming the field unless every value is in range (angle inside the arm's
    /// elbow range, durations positive, activation in [0, 1], window inside the hold).
    void validate(const ArmParameters& arm) const;
    /// Onset, rise and hold of the agonists as an activation profile.
    ActivationProfile calcActivationProfile() const;
    /// One profile per muscle of setup: agonists to `activation`, antagonists to antagonistActivation.
    std::vector<ActivationProfile> calcActivationProfiles(const ArmSetup& setup) const;
    /// Which muscles of setup are the effort's agonists (in the trial's pose).
    std::vector<bool> findAgonists(const ArmSetup& setup) const;
    double getDuration() const { return restDuration + riseTime + holdDuration; }
};

/// The checks every isometric trial's effort and timing share (IsometricTrialSettings::validate and
/// OpenSim models' trials): activations in [0, 1], rest and hold > 0, rise >= 0, a positive sample rate,
/// a window in (0, hold] (its mean takes the last sample at least), and the run's sample count. FieldError naming the
/// field (activation, antagonist_activation, rest, rise, hold, sample_rate, averaging_window).
void checkIsometricEffort(double activation, double antagonistActivation, double rest, double rise, double hold,
                          double sampleRate, double averagingWindow);

/// Summary of an isometric trial, averaged over the last averagingWindow of the hold.
struct IsometricSummary {
    double elbowAngle = 0;          ///< theta [rad]
    double pathLength = 0;          ///< P of the primary muscle [m]
    double momentArm = 0;           ///< h of the primary muscle [m]
    double tareTorque = 0;          ///< holding torque at rest, subtracted by the tare [N m]
    double restForce = 0;           ///< passive force of the primary muscle at rest (hidden by the tare) [N]
    double finalForce = 0;          ///< true force Fse of the primary muscle at the last sample [N]
    double meanForce = 0;           ///< true force of the primary muscle, window mean [N]
    double restFascicleLength = 0;  ///< fascicle length L of the primary muscle at rest (first sample) [m]
    double meanFascicleLength = 0;  ///< fascicle length of the primary muscle, window mean [m]
    double meanMuscleTorque = 0;    ///< tared elbow torque (what the transducer sees), window mean [N m]
    /// Tared torque about the forearm axis, + = supination (a two-axis transducer's second axis), window
    /// mean [N m]; 0 without a forearm rotation.
    double meanForearmTorque = 0;
    std::vector<double> forearmMomentArms;  ///< per muscle [m], + = supinates (0 without a forearm rotation)
    std::vector<double> pathLengths;     ///< per muscle [m]
    std::vector<double> momentArms;      ///< per muscle [m], + = flexor
    std::vector<double> meanForces;      ///< per muscle, window mean [N]
    double meanStrapForce = 0;      ///< transducer reading, window mean [N]
    double meanForceMomentArm = 0;  ///< estimate from tared torque / h, window mean [N]
    double meanForceFixedRatio = 0; ///< thesis fixed-ratio estimate, window mean [N]
    bool saturated = false;         ///< the transducer exceeded its range at some sample
    IntegrationStats stats;
};

struct IsometricTrialResult {
    /// Columns: time_s, activation (of the agonists), elbow_angle_deg, elbow_velocity_degps (0: locked),
    /// muscle_force_N, fascicle_length_m, fascicle_velocity_mps (of the primary muscle),
    /// holding_torque_Nm (raw lock torque, + = flexion), muscle_torque_Nm (tared, + = flexion),
    /// strap_force_N (transducer reading, clipped to its range), saturated (0/1),
    /// force_moment_arm_N, force_fixed_ratio_N, error_moment_arm_pct, error_fixed_ratio_pct
    /// (errors of the estimates against the true force of the primary muscle), on a model with a forearm
    /// rotation forearm_torque_Nm (tared, + = supination), with several muscles force_<muscle>_N and
    /// activation_<muscle> per muscle, then the muscle states.
    Table series;
    IsometricSummary summary;
};

IsometricTrialResult runIsometricTrial(const ArmSetup& setup, const IsometricTrialSettings& settings);

/// What the strap transducer reports and what the thesis derives from it (the trial table's columns
/// strap_force_N .. error_fixed_ratio_pct).
struct TransducerReading {
    double strapForce = 0;          ///< reading, clipped to the transducer's range [N]
    bool saturated = false;         ///< the force was beyond the range
    double forceMomentArm = 0;      ///< estimate strap x d1 / h [N]
    double forceFixedRatio = 0;     ///< the thesis's fixed-ratio estimate at this elbow angle [N]
    double errorMomentArmPct = 0;   ///< against the true muscle force [%] (NaN when that is <= 0)
    double errorFixedRatioPct = 0;  ///< likewise [%]
};

/// The reading of a (tared, perpendicular) strap force [N] at elbow angle theta [rad] for a primary
/// muscle of moment arm h [m] and true force F [N]: the trial's own reading and a protocol's noisy
/// one (strap force plus noise) go through here.
TransducerReading calcTransducerReading(const ArmParameters& arm, double strapForce, double elbowAngle,
                                        double momentArm, double muscleForce);

/// calcTransducerReading at one elbow angle and moment arm, with the angle's constants checked and
/// computed once (a locked trial reads the transducer at every sample: per sample only products).
class TransducerAtAngle {
public:
    /// Throws InputError (as calcTransducerReading) for an angle outside (0, 180) deg or a moment arm <= 0.
    TransducerAtAngle(const ArmParameters& arm, double elbowAngle, double momentArm);
    TransducerReading read(double strapForce, double muscleForce) const;

private:
    double range_, strapDistance_, momentArm_, fixedRatioPerNewton_;
};

/// Runs several isometric trials on `jobs` threads (one System per trial). Results are in input
/// order and identical to a sequential run. progress(done, total) is called from the caller's thread.
std::vector<IsometricTrialResult> runIsometricTrials(const ArmSetup& setup,
                                                     const std::vector<IsometricTrialSettings>& settings,
                                                     int jobs,
                                                     const std::function<void(int, int)>& progress = {});

/// How a free movement is integrated.
enum class FreeMovementSolver {
    /// Default: CPodes on the System's state vector [q u z] (integrateSampled). A right-hand side
    /// realizes the System; a difference-quotient Jacobian column that moves one muscle's state
    /// evaluates that muscle alone (its pure model at the column's path length and speed) and adds
    /// its change of tension times its moment arm over the elbow's inertia to the elbow's
    /// acceleration: the muscles are coupled only through the joint. A Jacobian then costs a few
    /// realizations instead of one per state, and Newton's systems are solved as an arrow (OdeArrow:
    /// an LU per muscle and the joint's Schur complement), cost linear in the muscles. Needs the elbow as the only free mobility (a forearm
    /// rotation locked) and no states but q, u and the muscles' (std::logic_error otherwise).
    MuscleBlocks,
    /// The whole Simbody System integrated by CPodesIntegrator (simulateSampled): the reference the
    /// tests compare MuscleBlocks with. The two take different steps and differ by their
    /// integration errors (at accuracy 1e-8: up to 6e-5 of a column's largest value).
    SimbodySystem
};

/// Free movement: the elbow unlocked, an optional load in the hand, an activation profile for the
/// flexors (the other muscles rest).
struct FreeMovementSettings {
    double initialAngle = degToRad(150);  ///< theta at t = 0 [rad]
    double initialVelocity = 0.0;      ///< dtheta/dt at t = 0 [rad/s]
    ActivationProfile activation = ActivationProfile::step(0.2, 0.0, 0.5);  ///< U(t)
    double duration = 2.0;             ///< [s]
    double handLoad = 0.0;             ///< mass held in the hand [kg]
    double sampleRate = 1000.0;        ///< [Hz]
    /// true: the muscle starts at its steady state for U(0) at the initial path (V = 0);
    /// false: the spec-5 initial state.
    bool startSteady = true;
    FreeMovementSolver solver = FreeMovementSolver::MuscleBlocks;
    /// MuscleBlocks, for tests: every one-muscle evaluation is also realized, and std::logic_error is
    /// thrown unless the two agree to 1e-9 (relative, or absolute below 1; measured: 1e-16 relative,
    /// 1e-12 absolute where a tendon-force derivative cancels near equilibrium).
    bool checkPartialEvaluations = false;
    IntegrationSettings integration;
    /// Optional: called with the time [s] of every sample (a long run's progress).
    std::function<void(double)> progress;
    void validate(const ArmParameters& arm) const;
};

/// Columns: time_s, activation, elbow_angle_deg, elbow_velocity_degps (+ = extending),
/// path_length_m, moment_arm_m, muscle_force_N, fascicle_length_m, fascicle_velocity_mps,
/// active_fraction (of the primary muscle), per-muscle force and activation columns for several
/// muscles, then the muscle states.
Table runFreeMovement(const ArmSetup& setup, const FreeMovementSettings& settings, IntegrationStats* stats = nullptr);

/// Throws FieldError naming `field` unless deg (a forearm rotation [deg], + = supination; NaN: none given)
/// is NaN or inside the arm's forearm-rotation range (an arm without one takes none).
void checkForearmRotationDeg(const std::string& field, double deg, const ArmParameters& arm);

/// Integrates a free arm (FreeMovementSolver::MuscleBlocks) from `state` for `duration` seconds; on return
/// `state` is the end state (realized to Stage::Time). sample gets a State realized to Stage::Time at
/// state.getTime() + k / sampleRate, the start included. checkPartial: as
/// FreeMovementSettings::checkPartialEvaluations.
IntegrationStats integrateCoupledMuscles(const MuscleArm& model, SimTK::State& state, double duration, double sampleRate,
                                         const std::vector<double>& breakpoints, const IntegrationSettings& integration,
                                         bool checkPartial, const std::function<void(const SimTK::State&)>& sample);

/// Reads trial settings from a YAML mapping (keys: elbow_angle_deg, activation, rest, rise, hold,
/// sample_rate, accuracy, averaging_window); unknown keys are errors naming file and line.
IsometricTrialSettings readIsometricTrialSettings(const ParamNode& node, const ArmParameters& arm);
/// Keys: initial_angle_deg, initial_velocity_degps, activation, onset, rise, duration, hand_load,
/// sample_rate, accuracy.
FreeMovementSettings readFreeMovementSettings(const ParamNode& node, const ArmParameters& arm);

}  // namespace armsim
