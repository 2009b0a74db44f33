// A steppable simulation of a model's arm (what OpenSim's Manager and MuJoCo's mj_step give): the
// elbow free or locked, one excitation U_i(t) per muscle that may be replaced between steps, the state
// read and written between steps, and samples recorded on a fixed grid.
#pragma once

#include "basics/numbers.h"

#include "basics/angles.h"
#include "basics/table.h"
#include "model/muscle_arm.h"
#include "numerics/stiff_ode.h"

#include <memory>
#include <string>
#include <vector>

namespace armsim {

/// How the simulation starts and what it records.
struct SimulationSettings {
    bool lockedElbow = false;              ///< true: the elbow is held (isometric); false: it moves freely
    double elbowAngle = degToRad(90);      ///< theta at the start, included angle (locked: where) [rad]
    double elbowVelocity = 0.0;            ///< dtheta/dt at the start, + = extending [rad/s]; 0 when locked
    /// Forearm rotation the radius is locked at [deg], + = supination; NaN = the model's posture. Only for
    /// a model with a forearm rotation (InputError otherwise).
    double forearmRotationDeg = kNaN;
    double handLoad = 0.0;                 ///< mass held in the hand [kg]
    double sampleRate = 1000.0;            ///< samples per second of simulated time [Hz]
    /// true: every muscle starts at its steady isometric state for U(0) at its initial path (V = 0);
    /// false: the spec-5 initial state.
    bool startSteady = true;
    IntegrationSettings integration;
    /// Throws InputError naming the field unless every value is in range.
    void validate(const ArmParameters& arm) const;
};

/// A simulation that advances on request. Free: CPodes on the arm with the muscles coupled through the
/// joint (FreeMovementSolver::MuscleBlocks); locked: the whole Simbody System with the elbow locked
/// (TrialSolver::SimbodySystem), the lock's torque read at every sample. Each advanceTo restarts the
/// integrator from the present state, so the state and the excitations may be changed between calls.
///
/// Samples are recorded at t0 + k / sampleRate (t0 = the start time) as they are passed, in a table with
/// columns time_s, elbow_angle_deg, elbow_velocity_degps (+ = extending), holding_torque_Nm (the lock's
/// torque, + = flexion; NaN when free), forearm_holding_torque_Nm (with a forearm rotation, + =
/// supination; NaN when free), then per muscle excitation_<m> (U), active_fraction_<m> (Virtual Muscle:
/// sum_u Af_u p_u; Hill: a), force_<m>_N, fascicle_length_<m>_m, then the muscle states
/// (state_<m>_<state>). Not thread-safe; one per thread.
class ArmSimulation {
public:
    /// excitations: one profile per muscle in the model's order (empty: every muscle at U = 0).
    ArmSimulation(const ArmSetup& setup, const SimulationSettings& settings,
                  std::vector<ActivationProfile> excitations = {});
    ~ArmSimulation();
    ArmSimulation(const ArmSimulation&) = delete;
    ArmSimulation& operator=(const ArmSimulation&) = delete;

    const MuscleArm& getModel() const { return *model_; }
    const SimulationSettings& getSettings() const { return settings_; }
    int getNumMuscles() const { return model_->getNumMuscles(); }
    bool isLocked() const { return settings_.lockedElbow; }

    /// @name State
    /// @{
    double getTime() const;
    /// theta [rad] and dtheta/dt [rad/s] (+ = extending).
    double getElbowAngle() const;
    double getElbowVelocity() const;
    /// Moves the elbow (locked: re-locks it there); theta inside the model's elbow range (InputError).
    void setElbowAngle(double theta);
    /// Free only (InputError on a locked elbow unless 0); |dtheta/dt| <= 2000 deg/s.
    void setElbowVelocity(double thetaDot);
    /// Every muscle's states in the order of getMuscleStateNames().
    std::vector<double> getMuscleStates() const;
    /// Sets them; InputError naming the state for a wrong count or a value that is not finite or
    /// leaves a muscle's validity range (checked at once).
    void setMuscleStates(const std::vector<double>& y);
    /// Sets any of angle, velocity and muscle states together: all are checked first, and a refused call
    /// changes nothing (InputError naming the value).
    void setState(const double* theta, const double* thetaDot, const std::vector<double>* muscleStates);
    /// "<muscle>_<state>" (a one-muscle model: "<state>").
    std::vector<std::string> getMuscleStateNames() const;
    /// Every muscle's tendon force Fse [N] in the present state.
    std::vector<double> calcMuscleForces() const;
    /// @}

    /// @name Excitation
    /// @{
    /// Replaces every muscle's U(t) (absolute time; the past already simulated stays as it was).
    /// One profile per muscle (InputError otherwise).
    void setExcitations(std::vector<ActivationProfile> excitations);
    const ActivationProfile& getExcitation(int muscle) const;
    /// @}

    /// Integrates from getTime() to t (>= getTime(); InputError otherwise), recording the samples passed.
    /// Throws SimulationError when the integrator cannot go on (the state is left at the last good
    /// step's start: the call's start) and Interrupted on a stop request.
    IntegrationStats advanceTo(double t);
    /// The checks advanceTo makes before any work (a finite time not before getTime(), a sample count a
    /// table may hold): InputError otherwise.
    void checkAdvance(double t) const;

    /// Every sample recorded since the start (columns above).
    const Table& getSamples() const { return samples_; }
    /// Integration counters summed over every advanceTo.
    const IntegrationStats& getStats() const { return stats_; }

private:
    void recordSample(const SimTK::State& s);
    void integrate(double duration, double sampleRate);
    double calcGridTolerance(double t) const;

    ArmSetup setup_;
    SimulationSettings settings_;
    std::unique_ptr<MuscleArm> model_;
    std::unique_ptr<SimTK::State> state_;
    Table samples_;
    IntegrationStats stats_;
    double t0_ = 0;
    long lastSample_ = -1;  ///< grid index of the last recorded sample
};

}  // namespace armsim
