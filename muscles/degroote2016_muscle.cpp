#include "muscles/degroote2016_muscle.h"

#include "basics/bound.h"
#include "basics/errors.h"
#include "basics/format.h"
#include "muscles/muscle_models.h"
#include "numerics/brent.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace armsim {

namespace {

constexpr double kPi = 3.14159265358979323846;
// The supplement's curve constants as OpenSim 4 corrected them (DeGrooteFregly2016Muscle.h).
constexpr double b11 = 0.8150671134243542, b21 = 1.055033428970575, b31 = 0.162384573599574, b41 = 0.063303448465465;
constexpr double b12 = 0.433004984392647, b22 = 0.716775413397760, b32 = -0.029947116970696, b42 = 0.200356847296188;
constexpr double b13 = 0.1, b23 = 1.0, b33 = 0.353553390593274, b43 = 0.0;
constexpr double kPE = 4.0;
constexpr double c1 = 0.2, c2 = 1.0, c3 = 0.2;
constexpr double d1 = -0.3211346127989808, d2 = -8.149, d3 = -0.374, d4 = 0.8825327733249912;
constexpr double kMinNormFiberLength = 0.2;  // the passive curve's zero; the steady solve's lower end
constexpr double kSteadyTolL = 1e-13;

double gaussianLike(double x, double b1, double b2, double b3, double b4) {
    const double w = b3 + b4 * x;
    return b1 * std::exp(-0.5 * (x - b2) * (x - b2) / (w * w));
}


}  // namespace

void DeGroote2016Parameters::validate() const {
    const std::string q = name.empty() ? "" : "muscle '" + name + "': ";
    checkField(q + "max_isometric_force", maxIsometricForce, Bound::positive("N"));
    checkField(q + "optimal_fiber_length", optimalFiberLength, Bound::positive("m"));
    checkField(q + "tendon_slack_length", tendonSlackLength, Bound::positive("m"));
    checkField(q + "pennation_angle", pennationAngleAtOptimal, {0, kPi / 2, false, true, "rad"});
    if (!(maxPathLength > 0))
        throw FieldError(q + "max_path_length", "max_path_length = " + formatNumber(maxPathLength) + ": expected > 0 (m)");
    checkField(q + "max_contraction_velocity", maxContractionVelocity, Bound::positive("optimal fibre lengths/s"));
    // OpenSim's defaults are 10 and 40 ms; a bound of 1 s keeps a value in ms out.
    checkField(q + "activation_time_constant", activationTimeConstant, Bound{0, 1, true, false, "s"});
    checkField(q + "deactivation_time_constant", deactivationTimeConstant, Bound{0, 1, true, false, "s"});
    checkField(q + "activation_dynamics_smoothing", activationDynamicsSmoothing, Bound::positive());
    checkField(q + "active_force_width_scale", activeForceWidthScale, {1, 1e300, false, false, ""});
    checkField(q + "fiber_damping", fiberDamping, Bound::nonNegative());
    checkField(q + "passive_fiber_strain_at_one_norm_force", passiveFiberStrainAtOneNormForce, Bound::positive());
    checkField(q + "tendon_strain_at_one_norm_force", tendonStrainAtOneNormForce, Bound::open(0, 1));
    checkField(q + "minimum_activation", minimumActivation, {0.001, 1, false, true, ""});
}

// ---- Curves ---------------------------------------------------------------------------------------

double calcDeGrooteActiveForceLength(const DeGroote2016Parameters& p, double L) {
    const double x = (L - 1.0) / p.activeForceWidthScale + 1.0;
    return gaussianLike(x, b11, b21, b31, b41) + gaussianLike(x, b12, b22, b32, b42) + gaussianLike(x, b13, b23, b33, b43);
}

double calcDeGrootePassiveForceLength(const DeGroote2016Parameters& p, double L) {
    const double e0 = p.passiveFiberStrainAtOneNormForce;
    const double offset = std::exp(kPE * (kMinNormFiberLength - 1.0) / e0);
    return (std::exp(kPE * (L - 1.0) / e0) - offset) / (std::exp(kPE) - offset);
}

double calcDeGrooteForceVelocity(double vN) {
    const double t = d2 * vN + d3;
    return d1 * std::log(t + std::sqrt(t * t + 1.0)) + d4;
}

double calcDeGrooteForceVelocityInverse(double fv) { return (std::sinh((fv - d4) / d1) - d3) / d2; }

double calcDeGrooteTendonStiffness(const DeGroote2016Parameters& p) {
    return std::log((1.0 + c3) / c1) / (1.0 + p.tendonStrainAtOneNormForce - c2);
}

double calcDeGrooteTendonForceLength(const DeGroote2016Parameters& p, double LT) {
    return c1 * std::exp(calcDeGrooteTendonStiffness(p) * (LT - c2)) - c3;
}

double calcDeGrooteTendonLength(const DeGroote2016Parameters& p, double fT) {
    return std::log((fT + c3) / c1) / calcDeGrooteTendonStiffness(p) + c2;
}

// ---- DeGroote2016Muscle -----------------------------------------------------------------------------

DeGroote2016Muscle::DeGroote2016Muscle(DeGroote2016Parameters params) : p_(std::move(params)) {
    p_.validate();
    width_ = p_.optimalFiberLength * std::sin(p_.pennationAngleAtOptimal);
}

void DeGroote2016Muscle::checkPathLength(double P) const { checkPathWithin(P, p_.maxPathLength, p_.name); }

double DeGroote2016Muscle::calcForce(double, const double* y) const { return p_.maxIsometricForce * y[kTendonForce]; }

void DeGroote2016Muscle::calcStateDerivative(double P, double U, const double* y, double* ydot,
                                             MuscleOutputs* out) const {
    calcMovingStateDerivative(P, 0.0, U, y, ydot, out);
}

void DeGroote2016Muscle::calcMovingStateDerivative(double P, double dP, double U, const double* y, double* ydot,
                                                   MuscleOutputs* out) const {
    const double a = y[kActivation], fT = y[kTendonForce];
    const double u = std::clamp(U, p_.minimumActivation, 1.0);
    // da/dt = [(f + 1/2) / (tau_a z) + (1/2 - f) z / tau_d] (u - a), f = tanh(b (u - a)) / 2, z = 1/2 + 3a/2.
    const double z = 0.5 + 1.5 * a, f = 0.5 * std::tanh(p_.activationDynamicsSmoothing * (u - a));
    ydot[kActivation] = ((f + 0.5) / (p_.activationTimeConstant * z) + (0.5 - f) * z / p_.deactivationTimeConstant) * (u - a);

    const double l0 = p_.optimalFiberLength, kT = calcDeGrooteTendonStiffness(p_);
    const double LT = calcDeGrooteTendonLength(p_, fT);
    const double along = P - p_.tendonSlackLength * LT;  // fibre length along the tendon
    const double lM = std::sqrt(along * along + width_ * width_);
    const double cosPhi = along / lM;
    const double L = lM / l0;
    const double fal = calcDeGrooteActiveForceLength(p_, L), fpe = calcDeGrootePassiveForceLength(p_, L);
    const double fv = (fT / cosPhi - fpe) / (a * fal);
    const double vN = calcDeGrooteForceVelocityInverse(fv);
    const double vM = vN * p_.maxContractionVelocity * l0;
    const double vT = dP - vM / cosPhi;  // tendon lengthening speed
    ydot[kTendonForce] = vT / p_.tendonSlackLength * c1 * kT * std::exp(kT * (LT - c2));
    if (out) {
        out->Fse = p_.maxIsometricForce * fT;
        out->Fce = p_.maxIsometricForce * (a * fal * fv + fpe + p_.fiberDamping * vN) * cosPhi;
        out->L = L;
        out->V = vM / l0;
        out->LT = LT;
        out->tendonLength = p_.tendonSlackLength * LT;
        out->activeFraction = a;
        out->Af.clear();
        out->fenv.clear();
    }
}

void DeGroote2016Muscle::checkStates(double t, const double* y) const {
    checkFiniteStates(t, y, {"activation", "normalized_tendon_force"}, p_.name);
    // The tendon curve's asymptote is -c3; the activation must stay positive (f_V divides by a f_L).
    if (!(y[kTendonForce] > -c3) || !(y[kActivation] > 0)) {
        std::ostringstream msg;
        msg << "t = " << t << " s: muscle '" << p_.name << "' left the model's range: activation "
            << y[kActivation] << " (expected > 0), normalized tendon force " << y[kTendonForce]
            << " (expected > " << -c3 << ")";
        throw SimulationError(msg.str());
    }
}

double DeGroote2016Muscle::calcFascicleLength(double P, const double* y) const {
    const double along = P - p_.tendonSlackLength * calcDeGrooteTendonLength(p_, y[kTendonForce]);
    return std::sqrt(along * along + width_ * width_);
}

double DeGroote2016Muscle::calcFascicleVelocity(double P, double U, const double* y) const {
    MuscleOutputs out;
    double ydot[2];
    calcStateDerivative(P, U, y, ydot, &out);
    return out.V * p_.optimalFiberLength;
}

SteadyState DeGroote2016Muscle::calcSteadyState(double P, double U) const {
    checkPathLength(P);
    if (!(U >= 0 && U <= 1)) throw InputError("activation U = " + formatNumber(U) + ": expected in [0, 1]");
    SteadyState r;
    const double a = std::clamp(U, p_.minimumActivation, 1.0), l0 = p_.optimalFiberLength;
    // At rest f_V = 1 (the curve passes (0, 1)): (a f_L + f_PE) cos phi = f_T(l~T) with l~T from the path.
    auto tendonForceAt = [&](double lM) {
        const double along = std::sqrt(std::max(0.0, lM * lM - width_ * width_));
        return calcDeGrooteTendonForceLength(p_, (P - along) / p_.tendonSlackLength);
    };
    auto imbalance = [&](double lM) {
        const double along = std::sqrt(std::max(0.0, lM * lM - width_ * width_));
        const double L = lM / l0;
        return (a * calcDeGrooteActiveForceLength(p_, L) + calcDeGrootePassiveForceLength(p_, L)) * (along / lM) -
               tendonForceAt(lM);
    };
    // Brackets: the fibre at 0.2 l0 (where f_PE is 0) and the fibre that leaves the tendon at its slack
    // length (f_T = 0, so the imbalance is a f_L cos phi + f_PE cos phi > 0).
    const double lo = std::max(kMinNormFiberLength * l0, width_ * (1 + 1e-9));
    const double along = P - p_.tendonSlackLength;
    const double hi = std::sqrt(std::max(0.0, along * along) + width_ * width_);
    if (!(along > 0) || !(hi > lo)) {
        r.message = "no steady state at path " + formatNumber(P) + " m: the tendon is slack for every fibre longer than " +
                    formatNumber(kMinNormFiberLength) + " l0; the path is too short for this muscle";
        return r;
    }
    const double flo = imbalance(lo), fhi = imbalance(hi);
    if (!(flo < 0) || !(fhi > 0)) {
        r.message = "no steady state at path " + formatNumber(P) + " m: no fibre length in [" + formatNumber(lo) + ", " +
                    formatNumber(hi) + "] m balances the tendon";
        return r;
    }
    const BrentResult root = findRootBrent(imbalance, lo, hi, flo, fhi, kSteadyTolL * l0, 200);
    r.evaluations = root.evaluations;
    if (!root.converged) {
        r.message = "steady solve did not converge in 200 iterations at path " + formatNumber(P) + " m";
        return r;
    }
    r.converged = true;
    r.L = root.x / l0;
    r.fascicleLength = root.x;
    r.normalizedForce = tendonForceAt(root.x);
    r.force = p_.maxIsometricForce * r.normalizedForce;
    r.states = {a, r.normalizedForce};
    return r;
}

// ---- Registry --------------------------------------------------------------------------------------

namespace {

const CoefficientField<DeGroote2016Parameters> kCoefficients[] = {
    {"max_contraction_velocity", &DeGroote2016Parameters::maxContractionVelocity},
    {"activation_time_constant", &DeGroote2016Parameters::activationTimeConstant},
    {"deactivation_time_constant", &DeGroote2016Parameters::deactivationTimeConstant},
    {"activation_dynamics_smoothing", &DeGroote2016Parameters::activationDynamicsSmoothing},
    {"active_force_width_scale", &DeGroote2016Parameters::activeForceWidthScale},
    {"fiber_damping", &DeGroote2016Parameters::fiberDamping},
    {"passive_fiber_strain_at_one_norm_force", &DeGroote2016Parameters::passiveFiberStrainAtOneNormForce},
    {"tendon_strain_at_one_norm_force", &DeGroote2016Parameters::tendonStrainAtOneNormForce},
    {"minimum_activation", &DeGroote2016Parameters::minimumActivation},
};

}  // namespace

std::vector<std::string> getDeGroote2016CoefficientKeys() { return listCoefficientKeys(kCoefficients); }

DeGroote2016Parameters calcDeGroote2016Parameters(const MuscleModelInput& in) {
    return makeHillParameters(in, kCoefficients, "degroote2016");
}

std::shared_ptr<const MuscleModel> buildDeGroote2016Muscle(const MuscleModelInput& in) {
    return std::make_shared<DeGroote2016Muscle>(calcDeGroote2016Parameters(in));
}

}  // namespace armsim
