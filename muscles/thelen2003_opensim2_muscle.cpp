#include "muscles/thelen2003_opensim2_muscle.h"

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
constexpr double kToe = 3.0;             // toe exponent
constexpr double kToeForce = 0.333333;   // f_T at the end of the toe (OpenSim 2.x's rounding)
constexpr double kToeStrain = 0.609;     // end of the toe / eps0 (the paper's rounding)
constexpr double kLinear = 1.712;        // linear stiffness x eps0
constexpr double kTendonFloor = 0.001;   // the everywhere-positive tendon stiffness
constexpr double kFvEpsilon = 1e-6;      // OpenSim 2.x: smallest activation, extrapolation step
constexpr double kSteadyTolL = 1e-13;    // steady solve: bracket width on lM / l0

}  // namespace

void Thelen2003Opensim2Parameters::validate() const {
    const std::string q = name.empty() ? "" : "muscle '" + name + "': ";
    checkField(q + "max_isometric_force", maxIsometricForce, Bound::positive("N"));
    checkField(q + "optimal_fiber_length", optimalFiberLength, Bound::positive("m"));
    checkField(q + "tendon_slack_length", tendonSlackLength, Bound::positive("m"));
    checkField(q + "pennation_angle", pennationAngleAtOptimal, {0, kPi / 2, false, true, "rad"});
    if (!(maxPathLength > 0))
        throw FieldError(q + "max_path_length", "max_path_length = " + formatNumber(maxPathLength) + ": expected > 0 (m)");
    checkField(q + "vmax", vmax, Bound::positive("optimal fibre lengths/s"));
    checkField(q + "vmax0", vmax0, Bound::positive("optimal fibre lengths/s"));
    checkField(q + "fmax_tendon_strain", fmaxTendonStrain, Bound::open(0, 1));
    checkField(q + "fmax_muscle_strain", fmaxMuscleStrain, Bound::positive());
    checkField(q + "kshape_active", kshapeActive, Bound::positive());
    checkField(q + "kshape_passive", kshapePassive, Bound::positive());
    checkField(q + "damping", damping, {0, 1e300, true, false, ""});
    checkField(q + "af", af, Bound::positive());
    checkField(q + "flen", flen, {1, 1e300, false, false, ""});
    // OpenSim's defaults are 10 and 40 ms; a bound of 1 s keeps a value in ms out.
    checkField(q + "activation_time_constant", activationTimeConstant, Bound{0, 1, true, false, "s"});
    checkField(q + "deactivation_time_constant", deactivationTimeConstant, Bound{0, 1, true, false, "s"});
}

// ---- Curves ---------------------------------------------------------------------------------------

double calcThelen2ActiveForceLength(const Thelen2003Opensim2Parameters& p, double L) {
    return std::exp(-(L - 1) * (L - 1) / p.kshapeActive);
}

double calcThelen2PassiveForceLength(const Thelen2003Opensim2Parameters& p, double L) {
    const double k = p.kshapePassive, e0 = p.fmaxMuscleStrain;
    if (L > 1 + e0) return 1 + k / e0 * (L - (1 + e0));  // slope of the exponential at 1 + e0
    return std::exp(k * (L - 1) / e0) / std::exp(k);
}

double calcThelen2TendonForce(const Thelen2003Opensim2Parameters& p, double eps) {
    const double toe = kToeStrain * p.fmaxTendonStrain;
    double f = 0;
    if (eps > toe) f = kLinear / p.fmaxTendonStrain * (eps - toe) + kToeForce;
    else if (eps > 0) f = kToeForce * (std::exp(kToe * eps / toe) - 1) / (std::exp(kToe) - 1);
    return f + kTendonFloor * (1 + eps);
}

namespace {

// Thelen's inverse with damping d on its two branches (no extrapolation).
double calcCurve(const Thelen2003Opensim2Parameters& p, double Fa, double Fv) {
    const double b = Fv < Fa ? Fa + Fv / p.af : (2 + 2 / p.af) * (Fa * p.flen - Fv) / (p.flen - 1);
    return (Fv - Fa) / (b + p.damping);
}

}  // namespace

double calcThelen2FiberVelocity(const Thelen2003Opensim2Parameters& p, double a, double fal, double Fv) {
    const double Fa = std::max(a, kFvEpsilon) * fal;
    if (Fv < 0) {  // shortening against a negative force: the line through the curve at 0 and epsilon
        const double v0 = calcCurve(p, Fa, 0.0), v1 = calcCurve(p, Fa, kFvEpsilon);
        return v0 + Fv * (v1 - v0) / kFvEpsilon;
    }
    const double upper = 0.95 * Fa * p.flen;
    if (Fv < upper) return calcCurve(p, Fa, Fv);
    // Beyond 0.95 Flen: the line through the curve at upper and (0.95 + epsilon) Fa Flen.
    const double F1 = (0.95 + kFvEpsilon) * Fa * p.flen;
    const double v0 = calcCurve(p, Fa, upper), v1 = calcCurve(p, Fa, F1);
    return v0 + (v1 - v0) / (F1 - upper) * (Fv - upper);
}

double calcThelen2ActivationRate(const Thelen2003Opensim2Parameters& p, double a, double u) {
    return (u - a) / (u >= a ? p.activationTimeConstant : p.deactivationTimeConstant);
}

// ---- Thelen2003Opensim2Muscle -------------------------------------------------------------------------

Thelen2003Opensim2Muscle::Thelen2003Opensim2Muscle(Thelen2003Opensim2Parameters params) : p_(std::move(params)) {
    p_.validate();
}

double Thelen2003Opensim2Muscle::calcPennationAngle(double lM) const {
    if (p_.pennationAngleAtOptimal <= 0 || !(lM > 0)) return 0.0;
    const double s = p_.optimalFiberLength * std::sin(p_.pennationAngleAtOptimal) / lM;
    return s >= 1 ? kPi / 2 : std::asin(s);
}

void Thelen2003Opensim2Muscle::checkPathLength(double P) const { checkPathWithin(P, p_.maxPathLength, p_.name); }

double Thelen2003Opensim2Muscle::calcForce(double P, const double* y) const {
    const double lM = y[kFiberLength] * p_.optimalFiberLength;
    const double tl = P - lM * std::cos(calcPennationAngle(lM));
    return p_.maxIsometricForce * calcThelen2TendonForce(p_, tl / p_.tendonSlackLength - 1);
}

void Thelen2003Opensim2Muscle::calcStateDerivative(double P, double U, const double* y, double* ydot,
                                                   MuscleOutputs* out) const {
    const double l0 = p_.optimalFiberLength;
    const double a = y[kActivation];
    ydot[kActivation] = calcThelen2ActivationRate(p_, a, U);
    const double L = y[kFiberLength];
    const double lM = L * l0;
    const double cosPhi = std::cos(calcPennationAngle(lM));
    const double tl = P - lM * cosPhi;
    const double fT = calcThelen2TendonForce(p_, tl / p_.tendonSlackLength - 1);
    const double fal = calcThelen2ActiveForceLength(p_, L), fpe = calcThelen2PassiveForceLength(p_, L);
    const double vmax = a < 1 ? p_.vmax0 + a * (p_.vmax - p_.vmax0) : p_.vmax;  // [l0/s]
    double vN = 0;
    if (cosPhi > 1e-12) vN = calcThelen2FiberVelocity(p_, a, fal, fT / cosPhi - fpe);
    ydot[kFiberLength] = vN * vmax;  // d(lM / l0)/dt
    if (out) {
        out->Fse = p_.maxIsometricForce * fT;
        out->Fce = out->Fse;
        out->L = L;
        out->V = ydot[kFiberLength];
        out->LT = tl / p_.tendonSlackLength;
        out->tendonLength = tl;
        out->activeFraction = a;
        out->Af.clear();
        out->fenv.clear();
    }
}

void Thelen2003Opensim2Muscle::checkStates(double t, const double* y) const {
    checkFiniteStates(t, y, {"activation", "fiber_length"}, p_.name);
    checkPositiveFiberLength(t, y[kFiberLength], p_.name);
}

double Thelen2003Opensim2Muscle::calcFascicleLength(double, const double* y) const {
    return y[kFiberLength] * p_.optimalFiberLength;
}

double Thelen2003Opensim2Muscle::calcFascicleVelocity(double P, double U, const double* y) const {
    double ydot[2];
    calcStateDerivative(P, U, y, ydot);
    return ydot[kFiberLength] * p_.optimalFiberLength;
}

SteadyState Thelen2003Opensim2Muscle::calcSteadyState(double P, double U) const {
    checkPathLength(P);
    if (!(U >= 0 && U <= 1)) throw InputError("activation U = " + formatNumber(U) + ": expected in [0, 1]");
    SteadyState r;
    const double a = U, l0 = p_.optimalFiberLength;
    // Fibre minus tendon force at fibre length lM (V = 0: the velocity-dependent force is a f_L).
    auto imbalance = [&](double lM) {
        const double cosPhi = std::cos(calcPennationAngle(lM));
        const double L = lM / l0;
        return (a * calcThelen2ActiveForceLength(p_, L) + calcThelen2PassiveForceLength(p_, L)) * cosPhi -
               calcThelen2TendonForce(p_, (P - lM * cosPhi) / p_.tendonSlackLength - 1);
    };
    // The tendon's force grows without bound as the fibre shortens and vanishes at zero tendon length.
    const double lo = 1e-6 * l0, hi = std::max(P, 2 * lo);
    const double flo = imbalance(lo), fhi = imbalance(hi);
    if (!(flo < 0 && fhi > 0)) {
        r.message = "no steady state at path " + formatNumber(P) + " m: fibre and tendon forces do not cross";
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
    r.normalizedForce = calcThelen2TendonForce(p_, (P - root.x * std::cos(calcPennationAngle(root.x))) / p_.tendonSlackLength - 1);
    r.force = p_.maxIsometricForce * r.normalizedForce;
    r.states = {a, r.L};
    return r;
}

// ---- Registry --------------------------------------------------------------------------------------

namespace {

const CoefficientField<Thelen2003Opensim2Parameters> kCoefficients[] = {
    {"vmax", &Thelen2003Opensim2Parameters::vmax},
    {"vmax0", &Thelen2003Opensim2Parameters::vmax0},
    {"fmax_tendon_strain", &Thelen2003Opensim2Parameters::fmaxTendonStrain},
    {"fmax_muscle_strain", &Thelen2003Opensim2Parameters::fmaxMuscleStrain},
    {"kshape_active", &Thelen2003Opensim2Parameters::kshapeActive},
    {"kshape_passive", &Thelen2003Opensim2Parameters::kshapePassive},
    {"damping", &Thelen2003Opensim2Parameters::damping},
    {"af", &Thelen2003Opensim2Parameters::af},
    {"flen", &Thelen2003Opensim2Parameters::flen},
    {"activation_time_constant", &Thelen2003Opensim2Parameters::activationTimeConstant},
    {"deactivation_time_constant", &Thelen2003Opensim2Parameters::deactivationTimeConstant},
};

}  // namespace

std::vector<std::string> getThelen2003Opensim2CoefficientKeys() { return listCoefficientKeys(kCoefficients); }

Thelen2003Opensim2Parameters calcThelen2003Opensim2Parameters(const MuscleModelInput& in) {
    return makeHillParameters(in, kCoefficients, "thelen2003_opensim2");
}

std::shared_ptr<const MuscleModel> buildThelen2003Opensim2Muscle(const MuscleModelInput& in) {
    return std::make_shared<Thelen2003Opensim2Muscle>(calcThelen2003Opensim2Parameters(in));
}

}  // namespace armsim
