// The Thelen 2003 muscle as OpenSim 2.x defined it (its Thelen2003Muscle, the model of the OpenSim 2
// tutorials and of their reference results): first-order activation with constant time constants and no
// floor, a maximal shortening velocity that grows with activation (Vmax0 at a = 0 to Vmax at a = 1),
// Thelen's force-velocity relation inverted with a passive damping term, a tendon with a small
// everywhere-positive stiffness and the paper's rounded toe constants, and an exponential passive curve
// without an offset. OpenSim 3 and 4 changed every one of these (muscles/thelen2003_muscle.h).
//
// Sources: Thelen DG (2003) J Biomech Eng 125:70-77; OpenSim 2.x source (Thelen2003Muscle.cpp:
// computeActuation, calcTendonForce, calcPassiveForce, calcActiveForce, calcFiberVelocity), read for the
// forms and constants. Written here from those equations; no OpenSim code is copied.
//
// | OpenSim 2.x             | code                     | meaning                                      | unit   |
// |-------------------------|--------------------------|----------------------------------------------|--------|
// | max_isometric_force     | maxIsometricForce        | F0                                           | N      |
// | optimal_fiber_length    | optimalFiberLength       | l0                                           | m      |
// | tendon_slack_length     | tendonSlackLength        | slack length                                 | m      |
// | pennation_angle         | pennationAngleAtOptimal  | at the optimal fibre length                  | rad    |
// | Vmax, Vmax0             | vmax, vmax0              | shortening speed limit at a = 1, a = 0       | l0/s   |
// | damping                 | damping                  | passive damping in the force-velocity inverse| 1      |
#pragma once

#include "muscles/muscle_model.h"

#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace armsim {

/// Everything that defines one OpenSim 2.x Thelen muscle. Defaults are OpenSim 2.x's
/// (Thelen2003Muscle::setupProperties); shipped values: assets/muscles/thelen2003_opensim2.yaml.
struct Thelen2003Opensim2Parameters {
    std::string name;                       ///< the muscle's name in its model file
    double maxIsometricForce = 0;           ///< F0 [N]
    double optimalFiberLength = 0;          ///< l0 [m]
    double tendonSlackLength = 0;           ///< [m]
    double pennationAngleAtOptimal = 0;     ///< at l0 [rad], in [0, pi/2)
    /// Longest path accepted (anatomical limit) [m]; infinity: no limit.
    double maxPathLength = std::numeric_limits<double>::infinity();
    double vmax = 10;                       ///< shortening speed limit at full activation [l0/s] (OpenSim 2.x)
    double vmax0 = 5;                       ///< the same at zero activation [l0/s] (OpenSim 2.x)
    double fmaxTendonStrain = 0.033;        ///< tendon strain at F0 [1] (OpenSim 2.x)
    double fmaxMuscleStrain = 0.6;          ///< passive fibre strain at F0 [1] (OpenSim 2.x)
    double kshapeActive = 0.5;              ///< width of the Gaussian force-length curve [1] (OpenSim 2.x)
    double kshapePassive = 4.0;             ///< passive exponential shape [1] (OpenSim 2.x)
    double damping = 0.05;                  ///< passive damping in the force-velocity inverse [1] (OpenSim 2.x)
    double af = 0.3;                        ///< force-velocity shape factor [1] (OpenSim 2.x)
    double flen = 1.8;                      ///< maximal lengthening force / F0 [1] (OpenSim 2.x)
    double activationTimeConstant = 0.01;   ///< [s] (OpenSim 2.x)
    double deactivationTimeConstant = 0.04; ///< [s] (OpenSim 2.x)
    /// Throws FieldError naming the field (snake_case), its value and the bound.
    void validate() const;
};

// ---- Normalised curves (plain functions) -----------------------------------------------------------

/// f_L(L) = exp(-(L - 1)^2 / KshapeActive).
double calcThelen2ActiveForceLength(const Thelen2003Opensim2Parameters& p, double L);
/// f_PE(L) = exp(k (L - 1) / e0) / exp(k) up to L = 1 + e0 (where it is 1), linear with the same slope
/// beyond (> 0 at every length: OpenSim 2.x has no offset).
double calcThelen2PassiveForceLength(const Thelen2003Opensim2Parameters& p, double L);
/// f_T(eps) for tendon strain eps = l_T / slack - 1: 0.333333 (e^(3 eps / epsToe) - 1) / (e^3 - 1) up to
/// epsToe = 0.609 eps0, then 1.712 / eps0 (eps - epsToe) + 0.333333; 0 when slack; plus 0.001 (1 + eps)
/// everywhere (OpenSim 2.x: the tendon never quite goes slack).
double calcThelen2TendonForce(const Thelen2003Opensim2Parameters& p, double eps);
/// The normalised fibre velocity (in units of the activation's Vmax) for activation a, f_L and the
/// velocity-dependent force Fv = f_T / cos(phi) - f_PE: Thelen's inverse with damping, linear for
/// Fv < 0 and for Fv >= 0.95 a f_L Flen (OpenSim 2.x's calcFiberVelocity).
double calcThelen2FiberVelocity(const Thelen2003Opensim2Parameters& p, double a, double fal, double Fv);
/// da/dt = (u - a) / tau_act while u >= a, (u - a) / tau_deact otherwise.
double calcThelen2ActivationRate(const Thelen2003Opensim2Parameters& p, double a, double u);

/// A built OpenSim 2.x Thelen muscle. State: [a, lM / l0]. The input U is the excitation (no floor).
class Thelen2003Opensim2Muscle final : public MuscleModel {
public:
    explicit Thelen2003Opensim2Muscle(Thelen2003Opensim2Parameters params);

    const Thelen2003Opensim2Parameters& getParameters() const { return p_; }
    const char* getModelName() const override { return "thelen2003_opensim2"; }
    const std::string& getName() const override { return p_.name; }
    int getNumStates() const override { return 2; }
    std::vector<std::string> getStateNames() const override { return {"activation", "fiber_length"}; }
    double getF0() const override { return p_.maxIsometricForce; }
    double getOptimalFascicleLength() const override { return p_.optimalFiberLength; }
    double getMaxPathLength() const override { return p_.maxPathLength; }

    static constexpr int kActivation = 0;
    static constexpr int kFiberLength = 1;

    void checkPathLength(double pathLength) const override;
    double calcForce(double pathLength, const double* y) const override;
    void calcStateDerivative(double pathLength, double U, const double* y, double* ydot,
                             MuscleOutputs* outputs = nullptr) const override;
    void checkStates(double t, const double* y) const override;
    SteadyState calcSteadyState(double pathLength, double U) const override;
    double calcFascicleLength(double, const double* y) const override;
    double calcFascicleVelocity(double pathLength, double U, const double* y) const override;

    /// Pennation of a fibre of length lM [m] (constant thickness; 90 deg once the fibre is that thick).
    double calcPennationAngle(double fiberLength) const;

private:
    Thelen2003Opensim2Parameters p_;
};

struct MuscleModelInput;
/// The coefficient keys a model file may give thelen2003_opensim2.
std::vector<std::string> getThelen2003Opensim2CoefficientKeys();
/// Parameters from a muscle's morphometry (as calcThelen2003Parameters) and coefficients.
Thelen2003Opensim2Parameters calcThelen2003Opensim2Parameters(const MuscleModelInput& input);
/// The registry's builder (muscles/muscle_models.h).
std::shared_ptr<const MuscleModel> buildThelen2003Opensim2Muscle(const MuscleModelInput& input);

}  // namespace armsim
