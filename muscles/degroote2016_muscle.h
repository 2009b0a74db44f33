// The De Groote-Fregly 2016 Hill-type muscle as OpenSim 4 defines it (DeGrooteFregly2016Muscle, its
// explicit tendon-compliance mode): smooth curves (three Gaussian-like terms for the active
// force-length curve, an exponential passive curve, an asinh force-velocity curve, an exponential
// tendon), first-order activation dynamics with a tanh switch, and the normalised tendon force as the
// second state, so the fibre velocity comes from the force-velocity curve's closed-form inverse.
//
// Sources: De Groote F, Kinney AL, Rao AV, Fregly BJ (2016) Ann Biomed Eng 44:2922-2936, supplement
// (the curves); OpenSim 4 source (opensim-core OpenSim/Actuators/DeGrooteFregly2016Muscle.h/.cpp),
// read for its corrected constants (b11, c2, c3, d1, d4; the -d3 the supplement's inverse misses),
// the passive curve's offset and the explicit tendon dynamics. Written here from those equations.
//
// One addition: the excitation is clamped to [minimum_activation, 1] (default 0.01, as Thelen2003Muscle):
// OpenSim's explicit mode divides by a f_L, and at a = 0 the fibre velocity is not defined.
//
// Kept as OpenSim has them (no guard added): the tendon curve f_T = c1 e^(kT (l~T - c2)) - c3 goes
// below zero for a tendon shorter than its slack length (a slack tendon "pushes", down to -c3 = -0.2
// F0), so the state and the output force can be negative; and on a path shorter than the tendon the
// fibre's length along the tendon is negative, and cos(phi) with it. checkStates stops a run whose
// tendon force reaches -c3 (the curve's asymptote, where the tendon length is undefined).
#pragma once

#include "muscles/muscle_model.h"

#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace armsim {

/// Everything that defines one De Groote-Fregly 2016 muscle. Defaults are OpenSim 4's
/// (DeGrooteFregly2016Muscle::constructProperties); the shipped values are assets/muscles/degroote2016.yaml.
struct DeGroote2016Parameters {
    std::string name;                        ///< the muscle's name in its model file
    double maxIsometricForce = 0;            ///< F0^M [N]
    double optimalFiberLength = 0;           ///< l0^M [m]
    double tendonSlackLength = 0;            ///< l^T_s [m]
    double pennationAngleAtOptimal = 0;      ///< alpha0 [rad], in [0, pi/2)
    /// Longest path accepted (anatomical limit) [m]; infinity: no limit.
    double maxPathLength = std::numeric_limits<double>::infinity();
    double maxContractionVelocity = 10;      ///< vmax [l0^M/s] (OpenSim Muscle default)
    double activationTimeConstant = 0.015;   ///< tau_a [s] (OpenSim 4)
    double deactivationTimeConstant = 0.060; ///< tau_d [s] (OpenSim 4)
    double activationDynamicsSmoothing = 0.1;  ///< b, steepness of tanh(b (u - a)) [1] (OpenSim 4: the paper's 0.1)
    double activeForceWidthScale = 1.0;      ///< widens f_L about l~ = 1 [1] (OpenSim 4)
    double fiberDamping = 0.0;               ///< damping force F0 * this * v~ [1] (OpenSim 4)
    double passiveFiberStrainAtOneNormForce = 0.6;  ///< e0 [1] (OpenSim 4)
    double tendonStrainAtOneNormForce = 0.049;      ///< tendon strain at F0 [1] (OpenSim 4; the paper's kT = 35)
    double minimumActivation = 0.01;         ///< floor on the excitation (armsim's, see the file comment) [1]

    /// Throws FieldError naming the field (snake_case, as in model files), its value and the bound.
    void validate() const;
};

// ---- Normalised curves (plain functions, the supplement's equations with OpenSim's constants) ------

/// f_L(l~): the sum of three Gaussian-like curves, widened about 1 by active_force_width_scale.
double calcDeGrooteActiveForceLength(const DeGroote2016Parameters& p, double L);
/// f_PE(l~) = (exp(kPE (l~ - 1) / e0) - offset) / (exp(kPE) - offset), kPE = 4, 0 at l~ = 0.2.
double calcDeGrootePassiveForceLength(const DeGroote2016Parameters& p, double L);
/// f_V(v~) = d1 ln(d2 v~ + d3 + sqrt((d2 v~ + d3)^2 + 1)) + d4, v~ = velocity / (vmax l0), through
/// (-1, 0) and (0, 1).
double calcDeGrooteForceVelocity(double vN);
/// The inverse of calcDeGrooteForceVelocity: v~ = (sinh((f_V - d4) / d1) - d3) / d2.
double calcDeGrooteForceVelocityInverse(double fv);
/// f_T(l~T) = c1 exp(kT (l~T - c2)) - c3, c1 = 0.2, c2 = 1, c3 = 0.2; kT from the tendon strain at F0.
double calcDeGrooteTendonForceLength(const DeGroote2016Parameters& p, double LT);
/// Its inverse, l~T(f_T).
double calcDeGrooteTendonLength(const DeGroote2016Parameters& p, double fT);
/// kT = ln((1 + c3) / c1) / (1 + strain - c2) (36.6 at the default 4.9 % strain).
double calcDeGrooteTendonStiffness(const DeGroote2016Parameters& p);

/// A built De Groote-Fregly 2016 muscle. State: [a, f~T] (activation, tendon force / F0). Its
/// derivatives depend on the path's lengthening speed (usesPathVelocity()).
class DeGroote2016Muscle final : public MuscleModel {
public:
    explicit DeGroote2016Muscle(DeGroote2016Parameters params);

    const DeGroote2016Parameters& getParameters() const { return p_; }
    const char* getModelName() const override { return "degroote2016"; }
    const std::string& getName() const override { return p_.name; }
    int getNumStates() const override { return 2; }
    std::vector<std::string> getStateNames() const override { return {"activation", "normalized_tendon_force"}; }
    double getF0() const override { return p_.maxIsometricForce; }
    double getOptimalFascicleLength() const override { return p_.optimalFiberLength; }
    double getMaxPathLength() const override { return p_.maxPathLength; }
    bool usesPathVelocity() const override { return true; }

    static constexpr int kActivation = 0;
    static constexpr int kTendonForce = 1;

    void checkPathLength(double pathLength) const override;
    double calcForce(double pathLength, const double* y) const override;
    void calcStateDerivative(double pathLength, double U, const double* y, double* ydot,
                             MuscleOutputs* outputs = nullptr) const override;
    void calcMovingStateDerivative(double pathLength, double pathVelocity, double U, const double* y,
                                   double* ydot, MuscleOutputs* outputs = nullptr) const override;
    void checkStates(double t, const double* y) const override;
    SteadyState calcSteadyState(double pathLength, double U) const override;
    double calcFascicleLength(double pathLength, const double* y) const override;
    double calcFascicleVelocity(double pathLength, double U, const double* y) const override;

private:
    DeGroote2016Parameters p_;
    double width_ = 0;  // l0 sin(alpha0), the fixed fibre width [m]
};

struct MuscleModelInput;
/// The coefficient keys a model file may give degroote2016 (OpenSim's property names).
std::vector<std::string> getDeGroote2016CoefficientKeys();
/// Parameters from a muscle's morphometry (as calcThelen2003Parameters) and coefficients.
DeGroote2016Parameters calcDeGroote2016Parameters(const MuscleModelInput& input);
/// The registry's builder (muscles/muscle_models.h).
std::shared_ptr<const MuscleModel> buildDeGroote2016Muscle(const MuscleModelInput& input);

}  // namespace armsim
