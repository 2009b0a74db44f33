// Virtual Muscle 4.0 ("natural discrete" recruitment) as plain functions of parameters and scalars.
// The definition is ../shared/spec/virtual-muscle.md (Cheng, Brown & Loeb 2000; Brown & Loeb 2000;
// Song, Raphael, Lan & Loeb 2008; Zhang 2009 thesis ch. 4). No Simbody, GL or OpenCV here: the
// Simbody adapter is muscles/muscle_force.h.
//
// Notation (spec section 1). Lengths are SI (m) at every boundary; the equations work in the
// normalised quantities below, so no cm appear anywhere in the code.
//
// | paper   | code                    | meaning                                              | unit     |
// |---------|-------------------------|------------------------------------------------------|----------|
// | P       | pathLength              | musculotendon path length, origin to insertion       | m        |
// | P_max   | maxPathLength           | path length at the anatomical limit                  | m        |
// | M       | mass                    | wet belly mass                                       | kg       |
// | L0      | optimalFascicleLength   | optimal fascicle length                              | m        |
// | L0T     | optimalTendonLength     | series-elastic length at F0                          | m        |
// | L       | L                       | fascicle length / L0                                 | 1        |
// | V       | V                       | fascicle velocity, positive = lengthening            | L0/s     |
// | LT      | LT                      | series-elastic length / L0T                          | 1        |
// | Lmax    | getLmax()               | fascicle length at P_max, normalised (spec 5)        | 1        |
// | U       | U                       | neural activation                                    | 1        |
// | F0      | getF0()                 | maximal isometric force = sigma * M / (rho * L0)     | N        |
// | p_u     | MotorUnit::fraction     | PCSA fraction of unit u                              | 1        |
// | thr_u   | MotorUnit::threshold    | recruitment threshold of unit u                      | 1        |
// | fenv    | calcEnvelopeFrequency   | envelope firing frequency                            | f0.5     |
// | fint    | state                   | intermediate firing frequency (rise/fall filter)     | f0.5     |
// | feff    | state                   | effective firing frequency                           | f0.5     |
// | Af      | calcActivationFrequency | activation-frequency relation of a unit              | 1        |
// | S       | state                   | sag (fibre types with sag: human fast)               | 1        |
// | Y       | state                   | yield (fibre types with yield: human slow)           | 1        |
// | FL, FV  | calcForceLength, ...    | force-length, force-velocity                         | 1        |
// | Fpe1/2  | calcPassiveStretch, ... | passive elements, normalised to F0                   | 1        |
// | Fce     | Outputs::Fce            | contractile-element force                            | N        |
// | Fse     | Outputs::Fse            | series-elastic force = the muscle's output force     | N        |
#pragma once

#include "basics/bound.h"
#include "muscles/muscle_model.h"

#include <string>
#include <vector>

namespace armsim {

/// Coefficients of one fibre type (spec section 2; thesis Table 4.1; VM 4.0 human database).
struct FibreType {
    std::string name;     ///< "slow" or "fast"
    double beta = 0;      ///< force-length exponent beta [1]
    double omega = 0;     ///< force-length width omega [1]
    double rho = 0;       ///< force-length roundness rho [1]
    double Vmax = 0;      ///< maximal shortening velocity, negative [L0/s]
    double cV0 = 0;       ///< shortening FV coefficient cV0 [1]
    double cV1 = 0;       ///< shortening FV coefficient cV1 [1]
    double bV = 0;        ///< lengthening FV coefficient bV [L0/s]
    double aV0 = 0;       ///< lengthening FV coefficient aV0 [1]
    double aV1 = 0;       ///< lengthening FV coefficient aV1 [1]
    double aV2 = 0;       ///< lengthening FV coefficient aV2 [1]
    double af = 0;        ///< activation-frequency scale af [f0.5]
    double nf0 = 0;       ///< activation-frequency exponent at L = 1, nf0 [1]
    double nf1 = 0;       ///< length dependence of the exponent, nf1 [1]
    double Tf1 = 0;       ///< rise time constant, length term Tf1 [s]
    double Tf2 = 0;       ///< rise time constant, frequency term Tf2 [s]
    double Tf3 = 0;       ///< fall time constant Tf3 [s]
    double Tf4 = 0;       ///< fall time constant, activation term Tf4 [s]
    double aS1 = 1;       ///< sag target while feff < 0.1 (1 with aS2 = 1: no sag) [1]
    double aS2 = 1;       ///< sag target while feff >= 0.1 [1]
    double TS = 1;        ///< sag time constant [s]
    double cY = 0;        ///< yield magnitude (0: no yield) [1]
    double VY = 1;        ///< yield velocity scale [L0/s]
    double TY = 1;        ///< yield time constant [s]
    /// f0.5: firing rate at which a unit of this type gives half its maximal isometric force at L = 1
    /// [pps]; fenv, fint, feff are in its units. Not used by the force model; 0 = not given (the
    /// synthetic EMG, which turns fenv into spike trains, requires it).
    double f05 = 0;

    bool hasSag() const { return aS1 != 1.0 || aS2 != 1.0; }
    bool hasYield() const { return cY != 0.0; }
    /// Fascicle length at which nf = nf0 + nf1 (1/L - 1) reaches 0 (infinity if it never does).
    double calcNfZeroLength() const;
    /// Throws FieldError ("<prefix>.<field>") for a value outside its documented bound.
    void validate(const std::string& prefix) const;
};
/// Every field equal (name included).
bool operator==(const FibreType& a, const FibreType& b);
inline bool operator!=(const FibreType& a, const FibreType& b) { return !(a == b); }

/// Whole-muscle coefficients (spec section 2).
struct MuscleCoefficients {
    double c1 = 0;        ///< PE1 scale c1 [1]
    double k1 = 0;        ///< PE1 curvature k1 [1]
    double Lr1 = 0;       ///< PE1 rest length Lr1, relative to Lmax [1]
    double eta = 0;       ///< PE1 viscosity eta [F0 s/L0]
    double c2 = 0;        ///< PE2 (thick-filament compression) scale c2, negative [1]
    double k2 = 0;        ///< PE2 curvature k2, negative [1]
    double Lr2 = 0;       ///< PE2 rest length Lr2 [1]
    double cT = 0;        ///< series-elastic scale cT [1]
    double kT = 0;        ///< series-elastic curvature kT [1]
    double LrT = 0;       ///< series-elastic rest length LrT [1]
    double Ur = 0;        ///< activation at which every unit is recruited [1]
    double fmin = 0;      ///< firing frequency at recruitment [f0.5]
    double fmax = 0;      ///< firing frequency at U = 1 [f0.5]
    double sigma = 0;     ///< specific tension [N/m^2] (spec: 31.8 N/cm^2)
    double density = 0;   ///< muscle density [kg/m^3] (spec: 1.06 g/cm^3)

    void validate(const std::string& prefix) const;
};
/// Every field equal.
bool operator==(const MuscleCoefficients& a, const MuscleCoefficients& b);
inline bool operator!=(const MuscleCoefficients& a, const MuscleCoefficients& b) { return !(a == b); }

/// How a fibre type's PCSA fraction is split among its units.
enum class Apportioning {
    Thesis,  ///< p_i = F_type (N + i) / sum_{n=1..N} (N + n) (thesis eq. 4.11/4.12)
    Equal    ///< p_i = F_type / N
};

/// L0's bound, [1 mm, 1 m] (a muscle fascicle), where it is typed and in validate().
Bound getOptimalFascicleLengthBound();

/// Everything that defines one muscle (model: immutable once built).
struct MuscleParameters {
    std::string name;                   ///< e.g. "biceps long head"
    double mass = 0;                    ///< M, wet belly mass [kg] (thesis Table 4.2)
    double optimalFascicleLength = 0;   ///< L0 [m] (thesis Table 4.2)
    double optimalTendonLength = 0;     ///< L0T [m] (thesis Table 4.2)
    double maxPathLength = 0;           ///< P_max, path at the anatomical limit [m]
    /// Pennation angle at L0 [rad]: not used by Virtual Muscle; Hill-type models built from these
    /// parameters (muscles/muscle_models.h) use it.
    double pennationAngle = 0;
    double slowFraction = 0;            ///< F_slow, PCSA fraction of slow fibres [1] (Table 4.3)
    int numSlowUnits = 3;               ///< Ns (thesis default 3)
    int numFastUnits = 3;               ///< Nf (thesis default 3)
    Apportioning apportioning = Apportioning::Thesis;
    FibreType slow;                     ///< slow fibre coefficients
    FibreType fast;                     ///< fast fibre coefficients
    MuscleCoefficients coefficients;    ///< whole-muscle coefficients

    /// Throws FieldError naming the field, its value and the violated bound.
    void validate() const;
};
/// F0 = sigma M / (rho L0) [N] (spec section 2): the only way mass, sigma and density enter the model.
double calcMaxIsometricForce(const MuscleParameters& p);
/// Whether a and b have the same steady isometric states up to the scale F0: every field equal except
/// name, mass, coefficients.sigma and coefficients.density (calcMaxIsometricForce's inputs).
bool haveSameNormalizedStates(const MuscleParameters& a, const MuscleParameters& b);

// ---- Elements (spec section 4), plain functions -------------------------------------------------

/// softplus(x) = ln(exp(x) + 1), evaluated without overflow.
double softplus(double x);
/// FL(L) = exp(-|(L^beta - 1) / omega|^rho).
double calcForceLength(const FibreType& t, double L);
/// FV(V, L): shortening (V <= 0) and lengthening (V > 0) branches; FV(0, L) = 1.
double calcForceVelocity(const FibreType& t, double V, double L);
/// Fpe1(L, V) = c1 k1 ln(exp((L/Lmax - Lr1)/k1) + 1) + eta V, normalised to F0.
double calcPassiveStretch(const MuscleCoefficients& c, double L, double V, double Lmax);
/// Fpe2(L) = min(0, c2 (exp(k2 (L - Lr2)) - 1)), normalised to F0.
double calcPassiveCompression(const MuscleCoefficients& c, double L);
/// Fse(LT) / F0 = cT kT ln(exp((LT - LrT)/kT) + 1).
double calcSeriesElastic(const MuscleCoefficients& c, double LT);
/// nf(L) = nf0 + nf1 (1/L - 1).
double calcNf(const FibreType& t, double L);
/// Af = 1 - exp(-((Y S feff) / (af nf))^nf); 0 for feff <= 0.
double calcActivationFrequency(const FibreType& t, double feffScaled, double nf);
/// fenv of a unit with threshold thr at activation U (0 below threshold).
double calcEnvelopeFrequency(const MuscleCoefficients& c, double threshold, double U);

/// One motor unit of a built muscle.
struct MotorUnit {
    bool slow = true;         ///< fibre type
    double fraction = 0;      ///< p_u, PCSA fraction [1]
    double threshold = 0;     ///< thr_u = Ur * sum_{j <= u} p_j [1]
};

/// Per-unit PCSA fractions and thresholds for Ns + Nf units (spec section 3). With no units of a
/// type, that type's PCSA goes to the other type (the muscle keeps F0; thesis Table 7.4 rows).
std::vector<MotorUnit> calcRecruitment(int numSlow, int numFast, double slowFraction,
                                       double Ur, Apportioning apportioning);

/// A built Virtual Muscle: validated parameters plus derived constants (F0, Lmax, units, state
/// layout). Immutable and cheap to copy; safe to share between threads.
///
/// State vector (all entries of order 1, as CPodes needs): [L, V, Y per type with yield,
/// (fint, feff) per unit, S per unit whose type has sag].
class VirtualMuscle final : public MuscleModel {
public:
    explicit VirtualMuscle(MuscleParameters params);
    const char* getModelName() const override { return "virtual_muscle"; }
    const std::string& getName() const override { return params_.name; }
    double getOptimalFascicleLength() const override { return params_.optimalFascicleLength; }
    double getMaxPathLength() const override { return params_.maxPathLength; }
    double calcFascicleLength(double, const double* y) const override { return y[kL] * params_.optimalFascicleLength; }
    double calcFascicleVelocity(double, double, const double* y) const override {
        return y[kV] * params_.optimalFascicleLength;
    }
    bool hasFascicleVelocityState() const override { return true; }
    /// The units' recruitment thresholds thr_u: fenv jumps from 0 to fmin there.
    std::vector<double> getActivationThresholds() const override;

    const MuscleParameters& getParameters() const { return params_; }
    const std::vector<MotorUnit>& getUnits() const { return units_; }
    int getNumUnits() const { return int(units_.size()); }
    int getNumStates() const override { return numStates_; }
    double getF0() const override { return F0_; }
    double getLmax() const { return Lmax_; }
    /// Mass of the muscle mass node, M / 2 [kg].
    double getNodeMass() const { return 0.5 * params_.mass; }
    /// Largest fascicle length (/ L0) at which every present fibre type keeps nf > 0.
    double getNfLimit() const { return nfLimit_; }
    /// Names of the state entries ("L", "V", "Y_slow", "fint_3", ...).
    std::vector<std::string> getStateNames() const override;

    // State layout.
    static constexpr int kL = 0;
    static constexpr int kV = 1;
    int getYieldIndex(bool slow) const { return slow ? yieldSlow_ : yieldFast_; }  ///< -1: none
    int getFintIndex(int u) const { return unitBase_ + 2 * u; }
    int getFeffIndex(int u) const { return unitBase_ + 2 * u + 1; }
    int getSagIndex(int u) const { return sagIndex_[u]; }  ///< -1: none

    /// Throws InputError unless 0 < P <= P_max.
    void checkPathLength(double pathLength) const override;
    /// L(0) of spec section 5 (approximate passive equilibrium at path P).
    double calcInitialFascicleLength(double pathLength) const;
    /// Initial state of spec section 5 at path P.
    std::vector<double> calcInitialState(double pathLength) const override;
    /// Output force Fse [N] at path P for state y.
    double calcForce(double pathLength, const double* y) const override;
    /// dy/dt at path P, activation U. Optionally fills outputs.
    void calcStateDerivative(double pathLength, double U, const double* y, double* ydot,
                             MuscleOutputs* outputs = nullptr) const override;
    /// d(dy/dt)/dy, analytic (checked against difference quotients in tests/muscles).
    bool calcStateJacobian(double pathLength, double U, const double* y, double* jacobian) const override;
    /// Throws SimulationError naming the time t, the muscle and the state unless every entry of y is
    /// finite and 0 < L < getNfLimit() (the model's validity range; step boundaries).
    void checkStates(double t, const double* y) const override;
    /// Steady isometric state at path P and activation U: solves Fse(L) = Fce(L, V = 0).
    /// Never throws for a missing equilibrium: returns converged = false with the reason.
    SteadyState calcSteadyState(double pathLength, double U) const override;
    /// The steady state's sensitivity by the implicit function theorem on calcSteadyImbalance; the
    /// partial derivatives of the balance's two sides by central differences (steps 1e-7).
    SteadySensitivity calcSteadySensitivity(double pathLength, double U, double L) const override;

private:
    /// (Fse - Fce) / F0 in the steady state at fascicle length L (V = 0, feff = fenv, Y = 1).
    double calcSteadyImbalance(double pathLength, double U, double L) const;
    /// Its fibre side Fce / F0 at L, U and normalized longest fascicle Lmax.
    double calcSteadyFibreForce(double U, double L, double Lmax) const;
    MuscleParameters params_;
    std::vector<MotorUnit> units_;
    double F0_ = 0, Lmax_ = 0, nfLimit_ = 0;
    int numStates_ = 0, unitBase_ = 0, yieldSlow_ = -1, yieldFast_ = -1;
    std::vector<int> sagIndex_;
};

/// Passive force at the anatomical limit, PF / F0 (spec section 5).
double calcPassiveForceAtLimit(const MuscleCoefficients& c);
/// LTstar: tendon length carrying PF (spec section 5; 0.956877 for the spec coefficients).
double calcTendonLengthAtLimit(const MuscleCoefficients& c);
/// The two constants of the initial-length formula (spec section 5):
/// first = LrT + kT ln(c1 k1 / (cT kT)) - kT Lr1 / k1 (0.8542867), second = kT / k1 (0.1021739).
std::pair<double, double> calcInitialLengthConstants(const MuscleCoefficients& c);

}  // namespace armsim
