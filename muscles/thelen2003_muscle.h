// The Thelen 2003 Hill-type muscle as OpenSim 4 defines it (Thelen2003Muscle): first-order activation
// dynamics, a Gaussian active force-length curve, an exponential passive curve, Thelen's
// force-velocity relation inverted for the fibre velocity (with OpenSim's linear extrapolation), an
// exponential-then-linear elastic tendon and a fixed-width pennation model.
//
// Sources: Thelen DG (2003) J Biomech Eng 125:70-77, eqs. 1-7; OpenSim 4 source
// (opensim-core OpenSim/Actuators/Thelen2003Muscle.cpp, MuscleFixedWidthPennationModel.cpp,
// MuscleFirstOrderActivationDynamicModel.cpp), read for the modifications OpenSim made to the
// paper (exact toe-region constants, the extrapolated force-velocity inverse, the clamped fibre).
// Written here from those equations; no OpenSim code is copied.
//
// | paper / OpenSim         | code                         | meaning                                  | unit   |
// |-------------------------|------------------------------|------------------------------------------|--------|
// | F0^M, max_isometric_force | maxIsometricForce          | maximal isometric force                  | N      |
// | l0^M, optimal_fiber_length | optimalFiberLength        | optimal fibre length                     | m      |
// | l^T_s, tendon_slack_length | tendonSlackLength         | tendon slack length                      | m      |
// | alpha0                  | pennationAngleAtOptimal      | pennation at optimal fibre length        | rad    |
// | a, u                    | state 0, U                   | activation, excitation                   | 1      |
// | l~M = l^M / l0^M        | state 1 (L)                  | normalised fibre length                  | 1      |
// | f_L, f_PE, f_SE, f_V    | calcActiveForceLength, ...   | normalised curves                        | 1      |
#pragma once

#include "muscles/muscle_model.h"

#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace armsim {

/// Everything that defines one Thelen 2003 muscle. Defaults are OpenSim 4's
/// (Thelen2003Muscle::constructProperties; Muscle's max_contraction_velocity); the shipped values are
/// assets/muscles/thelen2003.yaml.
struct Thelen2003Parameters {
    std::string name;                       ///< the muscle's name in its model file
    double maxIsometricForce = 0;           ///< F0^M [N]
    double optimalFiberLength = 0;          ///< l0^M [m]
    double tendonSlackLength = 0;           ///< l^T_s [m]
    double pennationAngleAtOptimal = 0;     ///< alpha0 [rad], in [0, pi/2)
    /// Longest path accepted (anatomical limit) [m]; infinity: no limit.
    double maxPathLength = std::numeric_limits<double>::infinity();
    double maxContractionVelocity = 10;     ///< vmax [l0^M/s] (OpenSim Muscle default)
    double fmaxTendonStrain = 0.04;         ///< tendon strain at F0^M, eps0^T [1] (OpenSim 4; OpenSim 2.x and arm26.osim: 0.033)
    double fmaxMuscleStrain = 0.6;          ///< passive fibre strain at F0^M, eps0^M [1] (OpenSim 4)
    double kshapeActive = 0.45;             ///< gamma, width of the Gaussian force-length curve [1] (OpenSim 4)
    double kshapePassive = 5.0;             ///< k^PE, passive exponential shape [1] (OpenSim 4)
    double af = 0.25;                       ///< A_f, force-velocity shape factor [1] (OpenSim 4)
    double flen = 1.4;                      ///< F^M_len, maximal lengthening force / F0 [1] (OpenSim 4; OpenSim 2.x and arm26.osim: 1.8)
    double fvLinearExtrapThreshold = 0.95;  ///< fraction of F^M_len beyond which fv^-1 is extrapolated [1] (OpenSim)
    double maximumPennationAngle = 1.4706289056333368;  ///< [rad] (OpenSim: acos(0.1))
    double activationTimeConstant = 0.015;  ///< tau_act [s] (OpenSim 4)
    double deactivationTimeConstant = 0.050;  ///< tau_deact [s] (OpenSim 4)
    double minimumActivation = 0.01;        ///< a_min [1] (OpenSim 4)

    /// Throws FieldError naming the field (snake_case, as in model files), its value and the bound.
    void validate() const;
};

// ---- Normalised curves (plain functions; Thelen 2003 eqs. 1-7 with OpenSim's constants) ----------

/// f_L(l~) = exp(-(l~ - 1)^2 / gamma) (Thelen 2003 eq. 4).
double calcThelenActiveForceLength(const Thelen2003Parameters& p, double L);
/// f_PE(l~) = (exp(k^PE (l~ - 1) / eps0^M) - 1) / (exp(k^PE) - 1) for l~ > 1, else 0 (eq. 3).
double calcThelenPassiveForceLength(const Thelen2003Parameters& p, double L);
/// f_SE(l^T / l^T_s): 0 when slack; Ftoe (exp(kToe eps / epsToe) - 1) / (exp(kToe) - 1) in the toe;
/// kLin (eps - epsToe) + Ftoe beyond it, with kToe = 3, Ftoe = 0.33 and epsToe, kLin exact so that
/// the curve is C1 and reaches 1 at eps0^T (eq. 2; OpenSim's exact constants).
double calcThelenTendonForceLength(const Thelen2003Parameters& p, double LT);
/// The normalised fibre velocity dl~/dt / vmax for a force Fm = a f_L f_V (eqs. 6-7; linear beyond
/// Fm <= 0 and Fm >= threshold * F^M_len a f_L, as OpenSim).
double calcThelenFiberVelocity(const Thelen2003Parameters& p, double a, double fal, double Fm);
/// f_V at normalised velocity vN (the inverse of calcThelenFiberVelocity, by Newton's method).
double calcThelenForceVelocity(const Thelen2003Parameters& p, double a, double fal, double vN);
/// da/dt for activation a and excitation u (OpenSim's first-order model: tau = tau_act (0.5 + 1.5 a)
/// while u > a, tau_deact / (0.5 + 1.5 a) otherwise; a clamped to [a_min, 1]).
double calcThelenActivationRate(const Thelen2003Parameters& p, double a, double u);

/// A built Thelen 2003 muscle. State: [a, l~M] (activation, fibre length / l0^M). The input U is the
/// excitation, clamped to [a_min, 1] (OpenSim's min_control is a_min).
class Thelen2003Muscle final : public MuscleModel {
public:
    explicit Thelen2003Muscle(Thelen2003Parameters params);

    const Thelen2003Parameters& getParameters() const { return p_; }
    const char* getModelName() const override { return "thelen2003"; }
    const std::string& getName() const override { return p_.name; }
    int getNumStates() const override { return 2; }
    std::vector<std::string> getStateNames() const override { return {"activation", "fiber_length"}; }
    double getF0() const override { return p_.maxIsometricForce; }
    double getOptimalFascicleLength() const override { return p_.optimalFiberLength; }
    double getMaxPathLength() const override { return p_.maxPathLength; }
    /// Shortest fibre (OpenSim's fixed-width pennation model: h / sin(alpha_max), or 1 % of l0^M when
    /// alpha_max is 0) [m].
    double getMinimumFiberLength() const { return minFiberLength_; }

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

    /// Pennation angle of a fibre of length lM [m] (fixed width) [rad].
    double calcPennationAngle(double fiberLength) const;

private:
    Thelen2003Parameters p_;
    double height_ = 0, maxSinPennation_ = 0, minFiberLength_ = 0;
};

struct MuscleModelInput;
/// The coefficient keys a model file may give thelen2003 (snake_case of OpenSim's property names).
std::vector<std::string> getThelen2003CoefficientKeys();
/// Thelen 2003 parameters from a muscle's morphometry and coefficients: F0 = sigma M / (rho L0) (the
/// Virtual Muscle relation, so the same person has the same F0 in both models), l0^M = L0,
/// l^T_s = LrT L0T (the inverse of model/model_file.h's L0T = slack / LrT), alpha0 = the pennation
/// angle, the path limit P_max; every other field from coefficients or OpenSim 4's default.
Thelen2003Parameters calcThelen2003Parameters(const MuscleModelInput& input);
/// The registry's builder (muscles/muscle_models.h).
std::shared_ptr<const MuscleModel> buildThelen2003Muscle(const MuscleModelInput& input);

}  // namespace armsim
