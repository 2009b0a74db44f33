#include "muscles/virtual_muscle.h"

#include "numerics/brent.h"

#include "basics/bound.h"
#include "basics/format.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <sstream>

namespace armsim {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
/// Lower bound on nf inside the derivative (spec 4: nf must stay positive). Runs stop with an error
/// before L reaches the nf limit (see VirtualMuscle::getNfLimit); this only keeps trial steps finite.
constexpr double kNfFloor = 0.05;
/// Lower bound on L inside 1/L terms, for trial steps of the integrator only.
constexpr double kLFloor = 1e-3;
/// Lowest fascicle length (/ L0) the steady solve brackets from.
constexpr double kSteadyLmin = 1e-3;
/// Root-finder tolerance on L (/ L0) for the steady solve.
constexpr double kSteadyTolL = 1e-13;

/// Exponents of the force-length curve (VM 4.0: 1.55-2.3): past 100, pow() overflows to inf.
constexpr Bound kShapeExponent{0, 100, true, false, ""};

std::string fmt(double v) {
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);  // shortest round-trip form
    return std::string(buf, r.ptr);
}

}  // namespace

// ---- Validation ---------------------------------------------------------------------------------

double FibreType::calcNfZeroLength() const {
    // nf0 + nf1 (1/L - 1) = 0  <=>  L = nf1 / (nf1 - nf0), reached only when nf1 > nf0.
    return nf1 > nf0 ? nf1 / (nf1 - nf0) : kInf;
}

void FibreType::validate(const std::string& p) const {
    const std::string q = p + ".";
    checkField(q + "beta", beta, kShapeExponent);
    checkField(q + "omega", omega, Bound{0, 10, true, false, "width of the force-length curve, L0"});
    checkField(q + "rho", rho, kShapeExponent);
    checkField(q + "Vmax", Vmax, {-1e300, 0, false, true, "L0/s"});
    checkField(q + "cV0", cV0, Bound::any());
    checkField(q + "cV1", cV1, Bound::any());
    checkField(q + "bV", bV, Bound::positive("L0/s"));
    checkField(q + "aV0", aV0, Bound::any());
    checkField(q + "aV1", aV1, Bound::any());
    checkField(q + "aV2", aV2, Bound::any());
    checkField(q + "af", af, Bound::positive("f0.5"));
    checkField(q + "nf0", nf0, Bound::positive());
    checkField(q + "nf1", nf1, Bound::any());
    // Time constants: VM 4.0's are 14-47 ms (Tf), 43-350 ms (TS), 200 ms (TY); the upper bounds (30 to 50
    // times those) keep a value in ms from passing as s.
    const Bound kTf{0, 1, true, false, "s"}, kTfSlope{0, 1, false, false, "s"}, kSlow{0, 10, true, false, "s"};
    checkField(q + "Tf1", Tf1, kTf);
    checkField(q + "Tf2", Tf2, kTfSlope);
    checkField(q + "Tf3", Tf3, kTf);
    checkField(q + "Tf4", Tf4, kTfSlope);
    checkField(q + "aS1", aS1, Bound::positive());
    checkField(q + "aS2", aS2, Bound::positive());
    checkField(q + "TS", TS, kSlow);
    checkField(q + "cY", cY, Bound::closed(0, 1));
    checkField(q + "VY", VY, Bound::positive("L0/s"));
    checkField(q + "TY", TY, kSlow);
    if (f05 != 0.0) checkField(q + "f05", f05, Bound::positive("pps, or 0 = not given"));
}

void MuscleCoefficients::validate(const std::string& p) const {
    const std::string q = p + ".";
    checkField(q + "c1", c1, Bound::nonNegative());
    checkField(q + "k1", k1, Bound::positive());
    checkField(q + "Lr1", Lr1, Bound::positive());
    checkField(q + "eta", eta, Bound::nonNegative("F0 s/L0"));
    checkField(q + "c2", c2, {-1e300, 0, false, false, ""});
    checkField(q + "k2", k2, Bound::any());
    checkField(q + "Lr2", Lr2, Bound::positive());
    checkField(q + "cT", cT, Bound::positive());
    checkField(q + "kT", kT, Bound::positive());
    checkField(q + "LrT", LrT, Bound::positive());
    checkField(q + "Ur", Ur, {0, 1, true, false, ""});
    checkField(q + "fmin", fmin, Bound::positive("f0.5"));
    checkField(q + "fmax", fmax, {fmin, 1e300, true, false, "f0.5, above fmin"});
    // Published specific tensions span 0.1-1 MPa, muscle density 1.04-1.11 g/cm^3: the bounds keep N/cm^2
    // and g/cm^3 out.
    checkField(q + "sigma", sigma, Bound{1e4, 3e6, false, false, "N/m^2"});
    checkField(q + "density", density, Bound{500, 2000, false, false, "kg/m^3"});
}

Bound getOptimalFascicleLengthBound() { return Bound{1e-3, 1, false, false, "m, a muscle fascicle"}; }

void MuscleParameters::validate() const {
    checkField("mass", mass, bounds::kMuscleMass);
    checkField("optimal_fascicle_length", optimalFascicleLength, getOptimalFascicleLengthBound());
    checkField("optimal_tendon_length", optimalTendonLength, bounds::kTendonLength);
    checkField("max_path_length", maxPathLength, bounds::kPathLength);
    checkField("fibre_fractions.slow", slowFraction, Bound::closed(0, 1));
    checkField("motor_units.slow", numSlowUnits, bounds::kMotorUnits);
    checkField("motor_units.fast", numFastUnits, bounds::kMotorUnits);
    slow.validate("fibre_types.slow");
    fast.validate("fibre_types.fast");
    coefficients.validate("coefficients");
    const double LTstar = calcTendonLengthAtLimit(coefficients);
    const double minPmax = LTstar * optimalTendonLength;
    checkField("max_path_length", maxPathLength,
               {minPmax, 1e300, true, false, "m; P_max must exceed LTstar * L0T so that Lmax > 0"});
}

// ---- Elements -----------------------------------------------------------------------------------

double softplus(double x) { return x > 0 ? x + std::log1p(std::exp(-x)) : std::log1p(std::exp(x)); }

double calcForceLength(const FibreType& t, double L) {
    return std::exp(-std::pow(std::abs((std::pow(L, t.beta) - 1.0) / t.omega), t.rho));
}

double calcForceVelocity(const FibreType& t, double V, double L) {
    if (V <= 0) return (t.Vmax - V) / (t.Vmax + (t.cV0 + t.cV1 * L) * V);
    return (t.bV - (t.aV0 + t.aV1 * L + t.aV2 * L * L) * V) / (t.bV + V);
}

double calcPassiveStretch(const MuscleCoefficients& c, double L, double V, double Lmax) {
    return c.c1 * c.k1 * softplus((L / Lmax - c.Lr1) / c.k1) + c.eta * V;
}

double calcPassiveCompression(const MuscleCoefficients& c, double L) {
    return std::min(0.0, c.c2 * (std::exp(c.k2 * (L - c.Lr2)) - 1.0));
}

double calcSeriesElastic(const MuscleCoefficients& c, double LT) {
    return c.cT * c.kT * softplus((LT - c.LrT) / c.kT);
}

double calcNf(const FibreType& t, double L) { return t.nf0 + t.nf1 * (1.0 / L - 1.0); }

double calcActivationFrequency(const FibreType& t, double feffScaled, double nf) {
    if (feffScaled <= 0) return 0.0;
    return 1.0 - std::exp(-std::pow(feffScaled / (t.af * nf), nf));
}

double calcEnvelopeFrequency(const MuscleCoefficients& c, double threshold, double U) {
    if (U < threshold) return 0.0;
    return c.fmin + (c.fmax - c.fmin) * (U - threshold) / (1.0 - threshold);
}

std::vector<MotorUnit> calcRecruitment(int numSlow, int numFast, double slowFraction, double Ur,
                                       Apportioning apportioning) {
    double fs = slowFraction;
    if (numSlow == 0) fs = 0.0;
    if (numFast == 0 && numSlow > 0) fs = 1.0;
    std::vector<MotorUnit> units;
    auto addType = [&](int N, double F, bool slow) {
        const double denom = 0.5 * (3.0 * N * N + N);  // sum_{n=1..N} (N + n)
        for (int i = 1; i <= N; ++i) {
            MotorUnit u;
            u.slow = slow;
            u.fraction = apportioning == Apportioning::Thesis ? F * (N + i) / denom : F / N;
            units.push_back(u);
        }
    };
    addType(numSlow, fs, true);
    addType(numFast, 1.0 - fs, false);
    double cumulative = 0;
    for (auto& u : units) {
        cumulative += u.fraction;
        u.threshold = Ur * cumulative;
    }
    if (!units.empty()) units.back().threshold = Ur;  // exact, not accumulated round-off
    return units;
}

double calcPassiveForceAtLimit(const MuscleCoefficients& c) {
    return c.c1 * c.k1 * softplus((1.0 - c.Lr1) / c.k1);
}

double calcTendonLengthAtLimit(const MuscleCoefficients& c) {
    const double PF = calcPassiveForceAtLimit(c);
    return c.kT * std::log(std::expm1(PF / (c.cT * c.kT))) + c.LrT;
}

std::pair<double, double> calcInitialLengthConstants(const MuscleCoefficients& c) {
    return {c.LrT + c.kT * std::log(c.c1 * c.k1 / (c.cT * c.kT)) - c.kT * c.Lr1 / c.k1, c.kT / c.k1};
}

// ---- Comparisons -----

// A field added to one of these structs must be added to its comparison below. The size checks catch
// most additions, not one int-sized field in MuscleParameters' 4 bytes of tail padding after
// `apportioning`: add such a field to haveSameNormalizedStates by hand.
static_assert(sizeof(FibreType) == sizeof(std::string) + 24 * sizeof(double), "FibreType changed: update operator==");
static_assert(sizeof(MuscleCoefficients) == 15 * sizeof(double), "MuscleCoefficients changed: update operator==");
static_assert(sizeof(MuscleParameters) == sizeof(std::string) + 6 * sizeof(double) + 4 * sizeof(int) +
                                              2 * sizeof(FibreType) + sizeof(MuscleCoefficients),
              "MuscleParameters changed: update haveSameNormalizedStates");

bool operator==(const FibreType& a, const FibreType& b) {
    return a.name == b.name && a.beta == b.beta && a.omega == b.omega && a.rho == b.rho && a.Vmax == b.Vmax &&
           a.cV0 == b.cV0 && a.cV1 == b.cV1 && a.bV == b.bV && a.aV0 == b.aV0 && a.aV1 == b.aV1 && a.aV2 == b.aV2 &&
           a.af == b.af && a.nf0 == b.nf0 && a.nf1 == b.nf1 && a.Tf1 == b.Tf1 && a.Tf2 == b.Tf2 && a.Tf3 == b.Tf3 &&
           a.Tf4 == b.Tf4 && a.aS1 == b.aS1 && a.aS2 == b.aS2 && a.TS == b.TS && a.cY == b.cY && a.VY == b.VY &&
           a.TY == b.TY && a.f05 == b.f05;
}

bool operator==(const MuscleCoefficients& a, const MuscleCoefficients& b) {
    return a.c1 == b.c1 && a.k1 == b.k1 && a.Lr1 == b.Lr1 && a.eta == b.eta && a.c2 == b.c2 && a.k2 == b.k2 &&
           a.Lr2 == b.Lr2 && a.cT == b.cT && a.kT == b.kT && a.LrT == b.LrT && a.Ur == b.Ur && a.fmin == b.fmin &&
           a.fmax == b.fmax && a.sigma == b.sigma && a.density == b.density;
}

double calcMaxIsometricForce(const MuscleParameters& p) {
    return p.coefficients.sigma * p.mass / (p.coefficients.density * p.optimalFascicleLength);
}

bool haveSameNormalizedStates(const MuscleParameters& a, const MuscleParameters& b) {
    MuscleCoefficients ca = a.coefficients;
    ca.sigma = b.coefficients.sigma;
    ca.density = b.coefficients.density;
    return a.optimalFascicleLength == b.optimalFascicleLength && a.optimalTendonLength == b.optimalTendonLength &&
           a.maxPathLength == b.maxPathLength && a.pennationAngle == b.pennationAngle && a.slowFraction == b.slowFraction &&
           a.numSlowUnits == b.numSlowUnits && a.numFastUnits == b.numFastUnits && a.apportioning == b.apportioning &&
           a.slow == b.slow && a.fast == b.fast && ca == b.coefficients;
}

// ---- VirtualMuscle ------------------------------------------------------------------------------

VirtualMuscle::VirtualMuscle(MuscleParameters params) : params_(std::move(params)) {
    params_.validate();
    const auto& c = params_.coefficients;
    const double L0 = params_.optimalFascicleLength;
    F0_ = calcMaxIsometricForce(params_);
    Lmax_ = (params_.maxPathLength - calcTendonLengthAtLimit(c) * params_.optimalTendonLength) / L0;
    units_ = calcRecruitment(params_.numSlowUnits, params_.numFastUnits, params_.slowFraction, c.Ur,
                             params_.apportioning);

    bool anySlow = false, anyFast = false;
    for (const auto& u : units_) (u.slow ? anySlow : anyFast) = true;
    nfLimit_ = kInf;
    if (anySlow) nfLimit_ = std::min(nfLimit_, params_.slow.calcNfZeroLength());
    if (anyFast) nfLimit_ = std::min(nfLimit_, params_.fast.calcNfZeroLength());

    int n = 2;
    if (anySlow && params_.slow.hasYield()) yieldSlow_ = n++;
    if (anyFast && params_.fast.hasYield()) yieldFast_ = n++;
    unitBase_ = n;
    n += 2 * getNumUnits();
    sagIndex_.assign(units_.size(), -1);
    for (int u = 0; u < getNumUnits(); ++u)
        if ((units_[u].slow ? params_.slow : params_.fast).hasSag()) sagIndex_[u] = n++;
    numStates_ = n;
}

std::vector<std::string> VirtualMuscle::getStateNames() const {
    std::vector<std::string> names(numStates_);
    names[kL] = "L";
    names[kV] = "V";
    if (yieldSlow_ >= 0) names[yieldSlow_] = "Y_slow";
    if (yieldFast_ >= 0) names[yieldFast_] = "Y_fast";
    for (int u = 0; u < getNumUnits(); ++u) {
        names[getFintIndex(u)] = "fint_" + std::to_string(u + 1);
        names[getFeffIndex(u)] = "feff_" + std::to_string(u + 1);
        if (sagIndex_[u] >= 0) names[sagIndex_[u]] = "S_" + std::to_string(u + 1);
    }
    return names;
}

void VirtualMuscle::checkPathLength(double P) const {
    if (!(P > 0) || !std::isfinite(P))
        throw InputError("path length = " + fmt(P) + " m: expected > 0");
    if (P > params_.maxPathLength)
        throw InputError("path length = " + fmt(P) + " m exceeds max_path_length (P_max) = " +
                         fmt(params_.maxPathLength) + " m of muscle '" + params_.name +
                         "': expected a path no longer than the anatomical limit");
}

double VirtualMuscle::calcInitialFascicleLength(double P) const {
    const auto [a, b] = calcInitialLengthConstants(params_.coefficients);
    const double L0 = params_.optimalFascicleLength, L0T = params_.optimalTendonLength;
    return (P - a * L0T) / (L0 * (1.0 + b * L0T / (Lmax_ * L0)));
}

std::vector<double> VirtualMuscle::calcInitialState(double P) const {
    std::vector<double> y(numStates_, 0.0);
    y[kL] = calcInitialFascicleLength(P);
    if (!(y[kL] > 0))
        throw InputError("path length = " + fmt(P) + " m is too short for muscle '" + params_.name +
                         "': its fascicle would start at " + formatNumber(y[kL], 6) + " L0: expected a path "
                         "whose tendon, at its slack length, leaves a fascicle of positive length");
    if (yieldSlow_ >= 0) y[yieldSlow_] = 1.0;
    if (yieldFast_ >= 0) y[yieldFast_] = 1.0;
    for (int u = 0; u < getNumUnits(); ++u)
        if (sagIndex_[u] >= 0) y[sagIndex_[u]] = (units_[u].slow ? params_.slow : params_.fast).aS1;
    return y;
}

double VirtualMuscle::calcForce(double P, const double* y) const {
    const double LT = (P - params_.optimalFascicleLength * y[kL]) / params_.optimalTendonLength;
    return F0_ * calcSeriesElastic(params_.coefficients, LT);
}

std::vector<double> VirtualMuscle::getActivationThresholds() const {
    std::vector<double> thresholds;
    for (const MotorUnit& u : units_) thresholds.push_back(u.threshold);
    return thresholds;
}

void VirtualMuscle::calcStateDerivative(double P, double U, const double* y, double* ydot,
                                        MuscleOutputs* out) const {
    const auto& c = params_.coefficients;
    const double L = y[kL], V = y[kV];
    const double Ls = std::max(L, kLFloor);
    const double LT = (P - params_.optimalFascicleLength * L) / params_.optimalTendonLength;
    const double fse = calcSeriesElastic(c, LT);

    // Per fibre type: FL * FV + Fpe2, nf and yield.
    const double fpe2 = calcPassiveCompression(c, L);
    struct TypeTerms { double active, nf, Y; double sum = 0; };
    auto typeTerms = [&](const FibreType& t, int yieldIndex) {
        TypeTerms tt;
        tt.active = calcForceLength(t, L) * calcForceVelocity(t, V, L) + fpe2;
        tt.nf = std::max(calcNf(t, Ls), kNfFloor);
        tt.Y = yieldIndex >= 0 ? y[yieldIndex] : 1.0;
        if (yieldIndex >= 0)
            ydot[yieldIndex] = (1.0 - t.cY * (1.0 - std::exp(-std::abs(V) / t.VY)) - tt.Y) / t.TY;
        return tt;
    };
    TypeTerms slow = typeTerms(params_.slow, yieldSlow_);
    TypeTerms fast = typeTerms(params_.fast, yieldFast_);

    if (out) {
        out->Af.resize(units_.size());
        out->fenv.resize(units_.size());
    }
    for (int u = 0; u < getNumUnits(); ++u) {
        const MotorUnit& mu = units_[u];
        const FibreType& t = mu.slow ? params_.slow : params_.fast;
        TypeTerms& tt = mu.slow ? slow : fast;
        const double fenv = calcEnvelopeFrequency(c, mu.threshold, U);
        const double fint = y[getFintIndex(u)], feff = y[getFeffIndex(u)];
        const int si = sagIndex_[u];
        const double S = si >= 0 ? y[si] : 1.0;
        const double Af = calcActivationFrequency(t, tt.Y * S * feff, tt.nf);
        const double Tf = fint >= feff ? t.Tf1 * L * L + t.Tf2 * fenv : (t.Tf3 + t.Tf4 * Af) / Ls;
        ydot[getFintIndex(u)] = (fenv - fint) / Tf;
        ydot[getFeffIndex(u)] = (fint - feff) / Tf;
        if (si >= 0) ydot[si] = ((feff < 0.1 ? t.aS1 : t.aS2) - S) / t.TS;
        tt.sum += Af * mu.fraction;
        if (out) {
            out->Af[u] = Af;
            out->fenv[u] = fenv;
        }
    }
    const double fce = std::max(0.0, calcPassiveStretch(c, L, V, Lmax_) + slow.sum * slow.active +
                                         fast.sum * fast.active);
    ydot[kL] = V;
    ydot[kV] = (fse - fce) * F0_ / (getNodeMass() * params_.optimalFascicleLength);
    if (out) {
        out->Fse = F0_ * fse;
        out->Fce = F0_ * fce;
        out->L = L;
        out->V = V;
        out->LT = LT;
        out->tendonLength = LT * params_.optimalTendonLength;
        out->activeFraction = slow.sum + fast.sum;
    }
}

namespace {

double calcSigmoid(double x) { return x >= 0 ? 1.0 / (1.0 + std::exp(-x)) : std::exp(x) / (1.0 + std::exp(x)); }

// d FL / dL.
double calcForceLengthSlope(const FibreType& t, double L) {
    const double g = (std::pow(L, t.beta) - 1.0) / t.omega;
    if (g == 0) return 0.0;
    const double a = std::abs(g);
    return -calcForceLength(t, L) * t.rho * std::pow(a, t.rho - 1.0) * (g > 0 ? 1.0 : -1.0) * t.beta *
           std::pow(L, t.beta - 1.0) / t.omega;
}

// d FV / dV and d FV / dL (the branch of the value at V).
void calcForceVelocitySlopes(const FibreType& t, double V, double L, double& dV, double& dL) {
    if (V <= 0) {
        const double num = t.Vmax - V, den = t.Vmax + (t.cV0 + t.cV1 * L) * V;
        dV = (-den - num * (t.cV0 + t.cV1 * L)) / (den * den);
        dL = -num * t.cV1 * V / (den * den);
        return;
    }
    const double a = t.aV0 + t.aV1 * L + t.aV2 * L * L, num = t.bV - a * V, den = t.bV + V;
    dV = (-a * den - num) / (den * den);
    dL = -(t.aV1 + 2.0 * t.aV2 * L) * V / den;
}

}  // namespace

namespace {

// calcStateJacobian's per fibre type: active = FL FV + Fpe2 and its slopes; nf; Y; the sum of Af x
// fraction and its slopes (filled unit by unit). Writes the type's yield rows.
struct JacobianFibreType {
    double active = 0, dActiveL = 0, dActiveV = 0, nf = 0, dNfL = 0, Y = 1;
    int yieldIndex = -1;
    double sum = 0, dSumL = 0, dSumY = 0;
};

JacobianFibreType makeJacobianFibreType(const FibreType& t, const double* y, double L, double V, double fpe2,
                                        double dFpe2, int yieldIndex, double* J, int n) {
    JacobianFibreType k;
    const double Ls = std::max(L, kLFloor), dLs = L > kLFloor ? 1.0 : 0.0;
    const double fl = calcForceLength(t, L), fv = calcForceVelocity(t, V, L);
    double dFvV = 0, dFvL = 0;
    calcForceVelocitySlopes(t, V, L, dFvV, dFvL);
    k.active = fl * fv + fpe2;
    k.dActiveL = calcForceLengthSlope(t, L) * fv + fl * dFvL + dFpe2;
    k.dActiveV = fl * dFvV;
    const double nfRaw = calcNf(t, Ls);
    k.nf = std::max(nfRaw, kNfFloor);
    k.dNfL = nfRaw > kNfFloor ? -t.nf1 / (Ls * Ls) * dLs : 0.0;
    k.yieldIndex = yieldIndex;
    if (yieldIndex >= 0) {
        k.Y = y[yieldIndex];
        J[std::size_t(yieldIndex) * n + yieldIndex] = -1.0 / t.TY;
        const double e = std::exp(-std::abs(V) / t.VY);
        J[std::size_t(yieldIndex) * n + VirtualMuscle::kV] = -t.cY * e * (V > 0 ? 1.0 : V < 0 ? -1.0 : 0.0) / (t.VY * t.TY);
    }
    return k;
}

}  // namespace

bool VirtualMuscle::calcStateJacobian(double P, double U, const double* y, double* J) const {
    const auto& c = params_.coefficients;
    const int n = numStates_;
    std::fill(J, J + std::size_t(n) * std::size_t(n), 0.0);
    auto at = [&](int i, int j) -> double& { return J[std::size_t(i) * std::size_t(n) + std::size_t(j)]; };
    const double L = y[kL], V = y[kV];
    const double Ls = std::max(L, kLFloor), dLs = L > kLFloor ? 1.0 : 0.0;
    const double L0 = params_.optimalFascicleLength;
    const double LT = (P - L0 * L) / params_.optimalTendonLength;
    const double dFse = c.cT * calcSigmoid((LT - c.LrT) / c.kT) * (-L0 / params_.optimalTendonLength);   // d/dL
    const double e2 = c.c2 * (std::exp(c.k2 * (L - c.Lr2)) - 1.0);
    const double fpe2 = std::min(0.0, e2), dFpe2 = e2 < 0 ? c.c2 * c.k2 * std::exp(c.k2 * (L - c.Lr2)) : 0.0;

    JacobianFibreType slow = makeJacobianFibreType(params_.slow, y, L, V, fpe2, dFpe2, yieldSlow_, J, n);
    JacobianFibreType fast = makeJacobianFibreType(params_.fast, y, L, V, fpe2, dFpe2, yieldFast_, J, n);

    // Row V = K (dFse - dFce) collects -K d fce / d(unit states) as it goes: fce = stretch + sum_s
    // active_s + sum_f active_f (each unit's feff and sag are columns of their own).
    const double K = F0_ / (getNodeMass() * L0);
    for (int u = 0; u < getNumUnits(); ++u) {
        const MotorUnit& mu = units_[u];
        const FibreType& t = mu.slow ? params_.slow : params_.fast;
        JacobianFibreType& k = mu.slow ? slow : fast;
        const double fenv = calcEnvelopeFrequency(c, mu.threshold, U);
        const int fi = getFintIndex(u), fe = getFeffIndex(u), si = sagIndex_[u];
        const double fint = y[fi], feff = y[fe], S = si >= 0 ? y[si] : 1.0;
        const double x = k.Y * S * feff;
        const double Af = calcActivationFrequency(t, x, k.nf);
        // Af = 1 - exp(-w), w = (x / (af nf))^nf: dAf/dx = exp(-w) w nf / x, dAf/dnf = exp(-w) w (ln z - 1).
        double dAfX = 0, dAfNf = 0;
        if (x > 0) {
            const double z = x / (t.af * k.nf), w = std::pow(z, k.nf), e = std::exp(-w);
            dAfX = e * w * k.nf / x;
            dAfNf = e * w * (std::log(z) - 1.0);
        }
        const double dAfL = dAfNf * k.dNfL, dAfFeff = dAfX * k.Y * S, dAfS = dAfX * k.Y * feff, dAfY = dAfX * S * feff;
        // Tf and its slopes (the branch of the value: rise while fint >= feff).
        double Tf, dTfL = 0, dTfFeff = 0, dTfS = 0, dTfY = 0;
        if (fint >= feff) {
            Tf = t.Tf1 * L * L + t.Tf2 * fenv;
            dTfL = 2.0 * t.Tf1 * L;
        } else {
            Tf = (t.Tf3 + t.Tf4 * Af) / Ls;
            dTfL = t.Tf4 * dAfL / Ls - (t.Tf3 + t.Tf4 * Af) * dLs / (Ls * Ls);
            dTfFeff = t.Tf4 * dAfFeff / Ls;
            dTfS = t.Tf4 * dAfS / Ls;
            dTfY = t.Tf4 * dAfY / Ls;
        }
        const double a = fenv - fint, b = fint - feff, Tf2 = Tf * Tf;
        at(fi, fi) = -1.0 / Tf;
        at(fi, kL) = -a / Tf2 * dTfL;
        at(fi, fe) = -a / Tf2 * dTfFeff;
        at(fe, fi) = 1.0 / Tf;
        at(fe, fe) = -1.0 / Tf - b / Tf2 * dTfFeff;
        at(fe, kL) = -b / Tf2 * dTfL;
        if (si >= 0) {
            at(fi, si) = -a / Tf2 * dTfS;
            at(fe, si) = -b / Tf2 * dTfS;
            at(si, si) = -1.0 / t.TS;
        }
        if (k.yieldIndex >= 0) {
            at(fi, k.yieldIndex) = -a / Tf2 * dTfY;
            at(fe, k.yieldIndex) = -b / Tf2 * dTfY;
        }
        k.sum += Af * mu.fraction;
        k.dSumL += dAfL * mu.fraction;
        k.dSumY += dAfY * mu.fraction;
        at(kV, fe) = -K * (dAfFeff * mu.fraction * k.active);
        if (si >= 0) at(kV, si) = -K * (dAfS * mu.fraction * k.active);
    }
    const double fceRaw = calcPassiveStretch(c, L, V, Lmax_) + slow.sum * slow.active + fast.sum * fast.active;
    at(kL, kV) = 1.0;
    if (fceRaw < 0) {   // fce = 0: only the tendon moves the node
        std::fill(&at(kV, 0), &at(kV, 0) + n, 0.0);
        at(kV, kL) = K * dFse;
        return true;
    }
    const double dFceL = c.c1 * calcSigmoid((L / Lmax_ - c.Lr1) / c.k1) / Lmax_ + slow.dSumL * slow.active +
                         slow.sum * slow.dActiveL + fast.dSumL * fast.active + fast.sum * fast.dActiveL;
    at(kV, kL) = -K * dFceL + K * dFse;
    at(kV, kV) = -K * (c.eta + slow.sum * slow.dActiveV + fast.sum * fast.dActiveV);
    if (slow.yieldIndex >= 0) at(kV, slow.yieldIndex) = -K * (slow.dSumY * slow.active);
    if (fast.yieldIndex >= 0) at(kV, fast.yieldIndex) = -K * (fast.dSumY * fast.active);
    return true;
}

void VirtualMuscle::checkStates(double t, const double* y) const {
    for (int i = 0; i < numStates_; ++i)
        if (!std::isfinite(y[i])) {
            std::ostringstream msg;
            msg << "t = " << t << " s: muscle '" << params_.name << "' state " << getStateNames()[i] << " is "
                << y[i] << " (not finite)";
            throw SimulationError(msg.str());
        }
    const double L = y[kL];
    if (!(L > 0) || !(L < nfLimit_)) {
        std::ostringstream msg;
        msg << "t = " << t << " s: muscle '" << params_.name << "' fascicle length L = " << L
            << " L0 left the model's range (0, " << nfLimit_
            << ") L0; beyond it the activation-frequency exponent nf is not positive (spec 4)";
        throw SimulationError(msg.str());
    }
}

double VirtualMuscle::calcSteadyImbalance(double P, double U, double L) const {
    const double LT = (P - params_.optimalFascicleLength * L) / params_.optimalTendonLength;
    return calcSeriesElastic(params_.coefficients, LT) - calcSteadyFibreForce(U, L, Lmax_);
}

double VirtualMuscle::calcSteadyFibreForce(double U, double L, double Lmax) const {
    const auto& c = params_.coefficients;
    const double fpe2 = calcPassiveCompression(c, L);
    const double nfS = calcNf(params_.slow, L), nfF = calcNf(params_.fast, L);
    double sumS = 0, sumF = 0;
    for (const MotorUnit& mu : units_) {
        const FibreType& t = mu.slow ? params_.slow : params_.fast;
        const double fenv = calcEnvelopeFrequency(c, mu.threshold, U);
        const double S = t.hasSag() ? (fenv < 0.1 ? t.aS1 : t.aS2) : 1.0;
        (mu.slow ? sumS : sumF) += calcActivationFrequency(t, S * fenv, mu.slow ? nfS : nfF) * mu.fraction;
    }
    double fce = calcPassiveStretch(c, L, 0.0, Lmax);
    if (sumS > 0) fce += sumS * (calcForceLength(params_.slow, L) + fpe2);
    if (sumF > 0) fce += sumF * (calcForceLength(params_.fast, L) + fpe2);
    return std::max(0.0, fce);
}

SteadySensitivity VirtualMuscle::calcSteadySensitivity(double P, double U, double L) const {
    using S = SteadySensitivity;
    const auto& c = params_.coefficients;
    const double L0 = params_.optimalFascicleLength, L0T = params_.optimalTendonLength;
    const double LT = (P - L0 * L) / L0T;
    constexpr double h = 1e-7;
    const double dFse = (calcSeriesElastic(c, LT + h) - calcSeriesElastic(c, LT - h)) / (2 * h);
    const double dFceL = (calcSteadyFibreForce(U, L + h, Lmax_) - calcSteadyFibreForce(U, L - h, Lmax_)) / (2 * h);
    const double Uhi = std::min(U + h, 1.0), Ulo = std::max(U - h, 0.0);
    const double dFceU = (calcSteadyFibreForce(Uhi, L, Lmax_) - calcSteadyFibreForce(Ulo, L, Lmax_)) / (Uhi - Ulo);
    // Lmax enters through the passive stretch only, and only while the fibre side is positive.
    const double hm = h * Lmax_;
    const double dFceLmax = calcSteadyFibreForce(U, L, Lmax_) > 0
        ? (calcPassiveStretch(c, L, 0.0, Lmax_ + hm) - calcPassiveStretch(c, L, 0.0, Lmax_ - hm)) / (2 * hm) : 0.0;
    // LT = (P - L0 L) / L0T and Lmax = (Pmax - LT* L0T) / L0: their partials by each input.
    double dLT[S::kNumInputs] = {P / L0T, -L0 * L / L0T, -LT, 0.0, 0.0};
    double dLmax[S::kNumInputs] = {0.0, -Lmax_, -calcTendonLengthAtLimit(c) * L0T / L0, params_.maxPathLength / L0, 0.0};
    const double dLTdL = -L0 / L0T;
    const double RL = dFse * dLTdL - dFceL;
    SteadySensitivity s;
    if (!(RL != 0) || !std::isfinite(RL)) return s;
    for (int k = 0; k < S::kNumInputs; ++k) {
        const double Rk = dFse * dLT[k] - dFceLmax * dLmax[k] - (k == S::kInput ? dFceU : 0.0);
        s.dL[k] = -Rk / RL;
        s.dFn[k] = dFse * (dLT[k] + dLTdL * s.dL[k]);
    }
    s.valid = std::all_of(std::begin(s.dFn), std::end(s.dFn), [](double v) { return std::isfinite(v); });
    return s;
}

SteadyState VirtualMuscle::calcSteadyState(double P, double U) const {
    checkPathLength(P);
    if (!(U >= 0 && U <= 1)) throw InputError("activation U = " + fmt(U) + ": expected in [0, 1]");
    SteadyState result;
    const double L0 = params_.optimalFascicleLength;
    const bool nfBound = nfLimit_ * (1.0 - 1e-9) < P / L0;
    double a = kSteadyLmin, b = nfBound ? nfLimit_ * (1.0 - 1e-9) : P / L0;
    const double fa = calcSteadyImbalance(P, U, a), fb = calcSteadyImbalance(P, U, b);
    result.evaluations = 2;
    if (!(fa > 0) || !(fb < 0)) {
        std::ostringstream msg;
        if (nfBound && fb >= 0)
            msg << "no steady state at path " << P << " m: the tendon would need a fascicle longer than "
                << nfLimit_ << " L0, where the activation-frequency exponent nf reaches 0 (spec 4)";
        else
            msg << "no steady state at path " << P << " m: the tendon is slack for every fascicle "
                << "length in (0, P/L0]; the path is too short for this muscle";
        result.message = msg.str();
        return result;
    }
    const BrentResult root = findRootBrent([&](double L) { return calcSteadyImbalance(P, U, L); }, a, b, fa, fb,
                                           kSteadyTolL, 200);
    result.evaluations = root.evaluations;
    result.converged = root.converged;
    if (!result.converged) {
        result.message = "steady solve did not converge in 200 iterations at path " + fmt(P) + " m";
        return result;
    }
    b = root.x;
    result.L = b;
    result.fascicleLength = b * L0;
    const double LT = (P - L0 * b) / params_.optimalTendonLength;
    result.normalizedForce = calcSeriesElastic(params_.coefficients, LT);
    result.force = F0_ * result.normalizedForce;

    std::vector<double>& y = result.states;
    y.assign(numStates_, 0.0);
    y[kL] = b;
    if (yieldSlow_ >= 0) y[yieldSlow_] = 1.0;
    if (yieldFast_ >= 0) y[yieldFast_] = 1.0;
    for (int u = 0; u < getNumUnits(); ++u) {
        const double fenv = calcEnvelopeFrequency(params_.coefficients, units_[u].threshold, U);
        y[getFintIndex(u)] = y[getFeffIndex(u)] = fenv;
        if (sagIndex_[u] >= 0) {
            const FibreType& t = units_[u].slow ? params_.slow : params_.fast;
            y[sagIndex_[u]] = fenv < 0.1 ? t.aS1 : t.aS2;
        }
    }
    return result;
}

}  // namespace armsim
