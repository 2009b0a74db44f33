#include "muscles/thelen2003_muscle.h"

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
constexpr double kToe = 3.0;            // toe-region exponent (Thelen 2003 eq. 2)
constexpr double kFtoe = 0.33;          // tendon force at the end of the toe region / F0
constexpr double kSteadyTolL = 1e-13;   // steady solve: bracket width on l~M
constexpr double kSignificant = 1e-14;  // OpenSim's SimTK::SignificantReal for doubles (eps^(7/8))

// The toe region's end strain and the linear stiffness, exact (OpenSim's comment: the paper's
// 0.609 eps0 is rounded): epsToe = 99 eps0 e^3 / (166 e^3 - 67), kLin = 0.67 / (eps0 - epsToe).
double calcToeStrain(double eps0) {
    const double e3 = std::exp(kToe);
    return 99.0 * eps0 * e3 / (166.0 * e3 - 67.0);
}


}  // namespace

void Thelen2003Parameters::validate() const {
    const std::string q = name.empty() ? "" : "muscle '" + name + "': ";
    checkField(q + "max_isometric_force", maxIsometricForce, Bound::positive("N"));
    checkField(q + "optimal_fiber_length", optimalFiberLength, Bound::positive("m"));
    checkField(q + "tendon_slack_length", tendonSlackLength, Bound::positive("m"));
    checkField(q + "pennation_angle", pennationAngleAtOptimal, {0, kPi / 2, false, true, "rad"});
    if (!(maxPathLength > 0))
        throw FieldError(q + "max_path_length", "max_path_length = " + formatNumber(maxPathLength) + ": expected > 0 (m)");
    checkField(q + "max_contraction_velocity", maxContractionVelocity, Bound::positive("optimal fibre lengths/s"));
    checkField(q + "fmax_tendon_strain", fmaxTendonStrain, Bound::open(0, 1));
    checkField(q + "fmax_muscle_strain", fmaxMuscleStrain, Bound::positive());
    checkField(q + "kshape_active", kshapeActive, Bound::positive());
    checkField(q + "kshape_passive", kshapePassive, Bound::positive());
    checkField(q + "af", af, Bound::positive());
    checkField(q + "flen", flen, {1, 1e300, true, false, ""});
    checkField(q + "fv_linear_extrap_threshold", fvLinearExtrapThreshold, {1 / flen, 1, true, false, ""});
    checkField(q + "maximum_pennation_angle", maximumPennationAngle, Bound::closed(0, kPi / 2, "rad"));
    if (pennationAngleAtOptimal > maximumPennationAngle)
        throw FieldError(q + "pennation_angle", "pennation_angle = " + formatNumber(pennationAngleAtOptimal) +
                                                    " rad: expected <= maximum_pennation_angle = " +
                                                    formatNumber(maximumPennationAngle) + " rad");
    // OpenSim's defaults are 10 and 40 ms; a bound of 1 s keeps a value in ms out.
    checkField(q + "activation_time_constant", activationTimeConstant, Bound{0, 1, true, false, "s"});
    checkField(q + "deactivation_time_constant", deactivationTimeConstant, Bound{0, 1, true, false, "s"});
    // OpenSim refuses a_min < 0.01: below it the fibre velocity's singularity at a -> 0 is too near.
    checkField(q + "minimum_activation", minimumActivation, {0.01, 1, false, true, ""});
}

// ---- Curves ---------------------------------------------------------------------------------------

double calcThelenActiveForceLength(const Thelen2003Parameters& p, double L) {
    return std::exp(-(L - 1) * (L - 1) / p.kshapeActive);
}

double calcThelenPassiveForceLength(const Thelen2003Parameters& p, double L) {
    if (L <= 1.0) return 0.0;
    return (std::exp(p.kshapePassive * (L - 1) / p.fmaxMuscleStrain) - 1) / (std::exp(p.kshapePassive) - 1);
}

double calcThelenTendonForceLength(const Thelen2003Parameters& p, double LT) {
    const double eps = LT - 1;
    if (eps <= 0) return 0.0;
    const double epsToe = calcToeStrain(p.fmaxTendonStrain);
    if (eps > epsToe) return (1 - kFtoe) / (p.fmaxTendonStrain - epsToe) * (eps - epsToe) + kFtoe;
    return kFtoe / (std::exp(kToe) - 1) * (std::exp(kToe * eps / epsToe) - 1);
}

namespace {

// dl~/dt / vmax and its slope d/dFm on the curve of Thelen 2003 eqs. 6-7 at force Fm (no extrapolation).
void calcCurveVelocity(const Thelen2003Parameters& p, double a, double afl, double Fm, double& v, double& dvdF) {
    double b, db;
    if (Fm <= afl) {  // shortening (concentric)
        b = afl + Fm / p.af;
        db = 1 / p.af;
    } else {  // lengthening (eccentric)
        b = (2 + 2 / p.af) * (afl * p.flen - Fm) / (p.flen - 1);
        db = -(2 + 2 / p.af) / (p.flen - 1);
    }
    const double k = 0.25 + 0.75 * a;
    v = k * (Fm - afl) / b;
    dvdF = k / b - k * (Fm - afl) / (b * b) * db;
}

}  // namespace

double calcThelenFiberVelocity(const Thelen2003Parameters& p, double a, double fal, double Fm) {
    const double afl = a * fal;
    const double upper = p.fvLinearExtrapThreshold * afl * p.flen;
    double v, dvdF;
    if (Fm > 0 && Fm < upper) {
        calcCurveVelocity(p, a, afl, Fm, v, dvdF);
        return v;
    }
    const double F0 = Fm <= 0 ? 0.0 : upper;  // the last force on the curve
    calcCurveVelocity(p, a, afl, F0, v, dvdF);
    return v + dvdF * (Fm - F0);
}

double calcThelenForceVelocity(const Thelen2003Parameters& p, double a, double fal, double vN) {
    // Newton on Fm = a fal fv from fv = 1 (calcThelenFiberVelocity is monotonic and C1).
    const double afl = a * fal;
    double Fm = afl;
    for (int i = 0; i < 100; ++i) {
        const double upper = p.fvLinearExtrapThreshold * afl * p.flen;
        const double F0 = Fm <= 0 ? 0.0 : (Fm >= upper ? upper : Fm);
        double v, dvdF;
        calcCurveVelocity(p, a, afl, F0, v, dvdF);
        v += dvdF * (Fm - F0);
        const double err = v - vN;
        if (std::abs(err) < 1e-12) break;
        Fm -= err / dvdF;
    }
    return std::max(0.0, Fm / afl);
}

double calcThelenActivationRate(const Thelen2003Parameters& p, double a, double u) {
    a = std::clamp(a, p.minimumActivation, 1.0);
    const double tau = u > a ? p.activationTimeConstant * (0.5 + 1.5 * a)
                             : p.deactivationTimeConstant / (0.5 + 1.5 * a);
    return (u - a) / tau;
}

// ---- Thelen2003Muscle -------------------------------------------------------------------------------

Thelen2003Muscle::Thelen2003Muscle(Thelen2003Parameters params) : p_(std::move(params)) {
    p_.validate();
    height_ = p_.optimalFiberLength * std::sin(p_.pennationAngleAtOptimal);
    maxSinPennation_ = std::sin(p_.maximumPennationAngle);
    // OpenSim's fixed-width pennation model: the fibre at the largest pennation, or 1 % of l0 when
    // pennation is not allowed at all.
    minFiberLength_ = p_.maximumPennationAngle > kSignificant ? height_ / maxSinPennation_ : 0.01 * p_.optimalFiberLength;
}

double Thelen2003Muscle::calcPennationAngle(double lM) const {
    if (p_.pennationAngleAtOptimal <= 1e-16) return 0.0;
    if (lM <= minFiberLength_) return p_.maximumPennationAngle;
    const double s = height_ / lM;
    return s < maxSinPennation_ ? std::asin(s) : p_.maximumPennationAngle;
}

void Thelen2003Muscle::checkPathLength(double P) const { checkPathWithin(P, p_.maxPathLength, p_.name); }

double Thelen2003Muscle::calcForce(double P, const double* y) const {
    const double lM = std::max(y[kFiberLength] * p_.optimalFiberLength, minFiberLength_);
    const double tl = P - lM * std::cos(calcPennationAngle(lM));
    return p_.maxIsometricForce * calcThelenTendonForceLength(p_, tl / p_.tendonSlackLength);
}

void Thelen2003Muscle::calcStateDerivative(double P, double U, const double* y, double* ydot,
                                           MuscleOutputs* out) const {
    const double l0 = p_.optimalFiberLength;
    const double a = std::clamp(y[kActivation], p_.minimumActivation, 1.0);
    const double u = std::clamp(U, p_.minimumActivation, 1.0);
    ydot[kActivation] = calcThelenActivationRate(p_, y[kActivation], u);

    const double lM = std::max(y[kFiberLength] * l0, minFiberLength_);
    const double phi = calcPennationAngle(lM);
    const double cosPhi = std::cos(phi);
    const double tl = P - lM * cosPhi;
    const double fse = calcThelenTendonForceLength(p_, tl / p_.tendonSlackLength);
    const double L = lM / l0;
    const double fal = calcThelenActiveForceLength(p_, L), fpe = calcThelenPassiveForceLength(p_, L);
    const double afalfv = fse / cosPhi - fpe;  // a f_L f_V from the equilibrium (cos phi >= 0.1)
    double vN = calcThelenFiberVelocity(p_, a, fal, afalfv);
    double fv = afalfv / (a * fal);
    // The unilateral stop: a fibre at its minimum length does not shorten further.
    const bool clamped = y[kFiberLength] * l0 <= minFiberLength_ * (1 + 1e-12) && vN <= 0;
    if (clamped) {
        vN = 0;
        fv = 1;
    }
    ydot[kFiberLength] = vN * p_.maxContractionVelocity;
    if (out) {
        out->Fse = p_.maxIsometricForce * fse;
        out->Fce = p_.maxIsometricForce * (a * fal * fv + fpe) * cosPhi;
        out->L = L;
        out->V = ydot[kFiberLength];
        out->LT = tl / p_.tendonSlackLength;
        out->tendonLength = tl;
        out->activeFraction = a;
        out->Af.clear();
        out->fenv.clear();
    }
}

void Thelen2003Muscle::checkStates(double t, const double* y) const {
    checkFiniteStates(t, y, {"activation", "fiber_length"}, p_.name);
    checkPositiveFiberLength(t, y[kFiberLength], p_.name);
}

double Thelen2003Muscle::calcFascicleLength(double, const double* y) const {
    return std::max(y[kFiberLength] * p_.optimalFiberLength, minFiberLength_);
}

double Thelen2003Muscle::calcFascicleVelocity(double P, double U, const double* y) const {
    double ydot[2];
    calcStateDerivative(P, U, y, ydot);
    return ydot[kFiberLength] * p_.optimalFiberLength;
}

SteadyState Thelen2003Muscle::calcSteadyState(double P, double U) const {
    checkPathLength(P);
    if (!(U >= 0 && U <= 1)) throw InputError("activation U = " + formatNumber(U) + ": expected in [0, 1]");
    SteadyState r;
    const double a = std::clamp(U, p_.minimumActivation, 1.0), l0 = p_.optimalFiberLength;
    // (a f_L + f_PE) cos phi - f_SE at fibre length lM (V = 0, so f_V = 1).
    auto imbalance = [&](double lM) {
        const double cosPhi = std::cos(calcPennationAngle(lM));
        const double L = lM / l0;
        return (a * calcThelenActiveForceLength(p_, L) + calcThelenPassiveForceLength(p_, L)) * cosPhi -
               calcThelenTendonForceLength(p_, (P - lM * cosPhi) / p_.tendonSlackLength);
    };
    // Brackets: the shortest fibre (tendon longest) and the fibre that leaves the tendon at its slack
    // length (f_SE = 0, so the imbalance is >= a f_L cos phi > 0).
    const double lo = std::max(minFiberLength_, 1e-9 * l0);
    const double along = P - p_.tendonSlackLength;  // fibre length along the tendon at slack
    double lM;
    r.evaluations = 1;
    const double flo = imbalance(lo);
    if (flo >= 0 || along <= lo * std::cos(calcPennationAngle(lo))) {
        // The fibre would shorten past every length. With pennation, OpenSim's stop holds it at the
        // minimum length ("fibre at its lower bound"), a rest the derivative keeps; without pennation
        // the minimum is 0, where no fibre can rest.
        if (minFiberLength_ <= 0) {
            r.message = "no steady state at path " + formatNumber(P) + " m: the fibre would shorten to zero length "
                        "(the path is too short for this muscle's tendon)";
            return r;
        }
        lM = lo;
    } else {
        const double hi = std::sqrt(along * along + height_ * height_);
        const double fhi = imbalance(hi);
        const BrentResult root = findRootBrent(imbalance, lo, hi, flo, fhi, kSteadyTolL * l0, 200);
        r.evaluations = root.evaluations;
        if (!root.converged) {
            r.message = "steady solve did not converge in 200 iterations at path " + formatNumber(P) + " m";
            return r;
        }
        lM = root.x;
    }
    r.converged = true;
    r.L = lM / l0;
    r.fascicleLength = lM;
    const double cosPhi = std::cos(calcPennationAngle(lM));
    r.normalizedForce = calcThelenTendonForceLength(p_, (P - lM * cosPhi) / p_.tendonSlackLength);
    r.force = p_.maxIsometricForce * r.normalizedForce;
    r.states = {a, r.L};
    return r;
}

// ---- Registry --------------------------------------------------------------------------------------

namespace {

const CoefficientField<Thelen2003Parameters> kCoefficients[] = {
    {"max_contraction_velocity", &Thelen2003Parameters::maxContractionVelocity},
    {"fmax_tendon_strain", &Thelen2003Parameters::fmaxTendonStrain},
    {"fmax_muscle_strain", &Thelen2003Parameters::fmaxMuscleStrain},
    {"kshape_active", &Thelen2003Parameters::kshapeActive},
    {"kshape_passive", &Thelen2003Parameters::kshapePassive},
    {"af", &Thelen2003Parameters::af},
    {"flen", &Thelen2003Parameters::flen},
    {"fv_linear_extrap_threshold", &Thelen2003Parameters::fvLinearExtrapThreshold},
    {"maximum_pennation_angle", &Thelen2003Parameters::maximumPennationAngle},
    {"activation_time_constant", &Thelen2003Parameters::activationTimeConstant},
    {"deactivation_time_constant", &Thelen2003Parameters::deactivationTimeConstant},
    {"minimum_activation", &Thelen2003Parameters::minimumActivation},
};

}  // namespace

std::vector<std::string> getThelen2003CoefficientKeys() { return listCoefficientKeys(kCoefficients); }

Thelen2003Parameters calcThelen2003Parameters(const MuscleModelInput& in) {
    return makeHillParameters(in, kCoefficients, "thelen2003");
}

std::shared_ptr<const MuscleModel> buildThelen2003Muscle(const MuscleModelInput& in) {
    return std::make_shared<Thelen2003Muscle>(calcThelen2003Parameters(in));
}

}  // namespace armsim
