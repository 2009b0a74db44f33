// The muscle-model interface: what a force element, a trial, a steady solve and a report need from a
// muscle model, as plain functions of (path length, input, state). Virtual Muscle
// (muscles/virtual_muscle.h) and Thelen 2003 (muscles/thelen2003_muscle.h) implement it; the Simbody
// adapter (muscles/muscle_force.h) owns the states. No Simbody, GL or OpenCV here.
//
// Conventions: SI units at the boundary (path length P [m], forces [N]); the input U in [0, 1] is the
// model's neural drive (Virtual Muscle: the recruitment activation; a Hill-type model: the
// excitation its activation dynamics follow); states are of order 1 (as CPodes needs).
#pragma once

#include "muscles/activation.h"

#include <string>
#include <vector>

namespace armsim {

/// Quantities derived from a state, for output and drawing.
struct MuscleOutputs {
    double Fse = 0;              ///< tendon (output) force [N]
    double Fce = 0;              ///< fibre force along the tendon [N]
    double L = 0;                ///< fascicle length / L0 [1]
    double V = 0;                ///< fascicle velocity [L0/s], + = lengthening
    double LT = 0;               ///< tendon length / the model's reference length (VM: L0T; Hill: slack length) [1]
    double tendonLength = 0;     ///< tendon length [m]
    double activeFraction = 0;   ///< how active the muscle is (Virtual Muscle: sum_u Af_u p_u; Hill: a) [1]
    std::vector<double> Af;      ///< per motor unit activation-frequency Af_u (Virtual Muscle only) [1]
    std::vector<double> fenv;    ///< per motor unit envelope firing frequency (Virtual Muscle only) [f0.5]
};

/// The steady isometric state at constant P and U.
struct SteadyState {
    bool converged = false;      ///< false: no equilibrium; message says why
    std::string message;         ///< why it failed (empty on success)
    double force = 0;            ///< tendon force = fibre force along the tendon [N]
    double normalizedForce = 0;  ///< force / F0 [1]
    double L = 0;                ///< fascicle length / L0 [1]
    double fascicleLength = 0;   ///< L * L0 [m]
    int evaluations = 0;         ///< residual evaluations the root finder used
    std::vector<double> states;  ///< full state vector, ready for a time integration
};

/// How a steady state moves with its inputs, by the implicit function theorem on the steady balance
/// (d L / d theta = -(dR/d theta) / (dR/d L), R the model's steady imbalance): the derivatives of the
/// normalized force F / F0 and of the normalized fascicle length L with respect to ln P (path), ln L0
/// (optimal fascicle length), ln L0T (the tendon's reference length), ln P_max (the longest path) and U.
/// F0's own dependence on L0 is not included (F = F0 Fn: the caller adds it).
struct SteadySensitivity {
    enum Input { kLnPath = 0, kLnFascicle, kLnTendon, kLnMaxPath, kInput, kNumInputs };
    bool valid = false;          ///< false: not available (the caller takes difference quotients)
    double dFn[kNumInputs] = {}; ///< d (F / F0) / d input [1]
    double dL[kNumInputs] = {};  ///< d L / d input [1]
};

/// A built muscle model: immutable, cheap to share between threads.
class MuscleModel {
public:
    virtual ~MuscleModel() = default;

    /// The registry name of the model ("virtual_muscle", "thelen2003").
    virtual const char* getModelName() const = 0;
    /// The muscle's name, as its model file gives it.
    virtual const std::string& getName() const = 0;
    virtual int getNumStates() const = 0;
    /// Names of the state entries, in order.
    virtual std::vector<std::string> getStateNames() const = 0;
    /// Maximal isometric force F0 [N].
    virtual double getF0() const = 0;
    /// Optimal fascicle length L0 [m].
    virtual double getOptimalFascicleLength() const = 0;
    /// Longest path the model accepts (the anatomical limit P_max) [m].
    virtual double getMaxPathLength() const = 0;

    /// Throws InputError unless 0 < P <= getMaxPathLength().
    virtual void checkPathLength(double pathLength) const = 0;
    /// A state to start an integration from at path P with no drive. Default: the steady state at U = 0
    /// (InputError naming the muscle when there is none).
    virtual std::vector<double> calcInitialState(double pathLength) const;
    /// Tendon (output) force [N] at path P for state y.
    virtual double calcForce(double pathLength, const double* y) const = 0;
    /// dy/dt at path P, input U. Optionally fills outputs.
    virtual void calcStateDerivative(double pathLength, double U, const double* y, double* ydot,
                                     MuscleOutputs* outputs = nullptr) const = 0;
    /// true when the derivatives depend on how fast the path lengthens (a tendon-force state); the
    /// Simbody adapter then passes it to calcMovingStateDerivative.
    virtual bool usesPathVelocity() const { return false; }
    /// dy/dt with the path lengthening at pathVelocity [m/s]; calcStateDerivative is its isometric case.
    /// The default ignores pathVelocity (models whose states do not need it).
    virtual void calcMovingStateDerivative(double pathLength, double pathVelocity, double U, const double* y,
                                           double* ydot, MuscleOutputs* outputs = nullptr) const {
        (void)pathVelocity;
        calcStateDerivative(pathLength, U, y, ydot, outputs);
    }
    /// d(dy/dt)/dy at path P, input U for state y, row-major (jacobian[i * n + j] = d ydot_i / d y_j, n =
    /// getNumStates()); one-sided where the derivative has a branch (the value's). false: the model has
    /// no analytic Jacobian and callers take difference quotients (the default).
    virtual bool calcStateJacobian(double pathLength, double U, const double* y, double* jacobian) const {
        (void)pathLength, (void)U, (void)y, (void)jacobian;
        return false;
    }
    /// Throws SimulationError naming the time t, the muscle and the state unless y is finite and inside
    /// the model's validity range (call at step boundaries).
    virtual void checkStates(double t, const double* y) const = 0;
    /// Outputs at path P, input U for state y.
    virtual MuscleOutputs calcOutputs(double pathLength, double U, const double* y) const;
    /// Steady isometric state at path P and input U. Never throws for a missing equilibrium: returns
    /// converged = false with the reason.
    virtual SteadyState calcSteadyState(double pathLength, double U) const = 0;
    /// Sensitivity of the steady state L (calcSteadyState's, at the same P and U) to its inputs. The
    /// default: not available (valid = false).
    virtual SteadySensitivity calcSteadySensitivity(double pathLength, double U, double L) const {
        (void)pathLength, (void)U, (void)L;
        return {};
    }
    /// Fascicle length [m] of state y at path P.
    virtual double calcFascicleLength(double pathLength, const double* y) const = 0;
    /// Fascicle velocity [m/s] (+ = lengthening) of state y at path P, input U.
    virtual double calcFascicleVelocity(double pathLength, double U, const double* y) const = 0;
    /// true when the fascicle velocity is a state, so calcFascicleVelocity ignores P and U (callers that
    /// sample many states may then skip looking the input up).
    virtual bool hasFascicleVelocityState() const { return false; }
    /// Activations U at which calcStateDerivative jumps (Virtual Muscle: the units' recruitment
    /// thresholds; none for a model smooth in U). An integrator restarts where U(t) passes one, so no
    /// step straddles a jump (findRestartTimes).
    virtual std::vector<double> getActivationThresholds() const { return {}; }
};

/// Where an integrator of `muscle` driven by `profile` restarts: the profile's breakpoints (only its
/// steps, two points at one time, when stepsOnly: a dense trace's every row would cost more than it
/// gains) and the times it passes one of the muscle's activation thresholds. Unsorted, may repeat.
std::vector<double> findRestartTimes(const MuscleModel& muscle, const ActivationProfile& profile,
                                     bool stepsOnly = false);

}  // namespace armsim
