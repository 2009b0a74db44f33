#include "estimation/statistics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace armsim {

namespace {

// Continued fraction of I_x(a, b) (Numerical Recipes 6.4, betacf).
double betaContinuedFraction(double a, double b, double x) {
    constexpr double tiny = 1e-300, eps = 1e-16;
    const double qab = a + b, qap = a + 1.0, qam = a - 1.0;
    double c = 1.0, d = 1.0 - qab * x / qap;
    if (std::abs(d) < tiny) d = tiny;
    d = 1.0 / d;
    double h = d;
    for (int m = 1; m <= 10000; ++m) {
        const int m2 = 2 * m;
        double aa = m * (b - m) * x / ((qam + m2) * (a + m2));
        d = 1.0 + aa * d;
        if (std::abs(d) < tiny) d = tiny;
        c = 1.0 + aa / c;
        if (std::abs(c) < tiny) c = tiny;
        d = 1.0 / d;
        h *= d * c;
        aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
        d = 1.0 + aa * d;
        if (std::abs(d) < tiny) d = tiny;
        c = 1.0 + aa / c;
        if (std::abs(c) < tiny) c = tiny;
        d = 1.0 / d;
        const double del = d * c;
        h *= del;
        if (std::abs(del - 1.0) < eps) break;
    }
    return h;
}

void checkProbability(double p) {
    if (!(p > 0 && p < 1)) throw std::invalid_argument("probability " + std::to_string(p) + ": expected in (0, 1)");
}

}  // namespace

double calcIncompleteBeta(double a, double b, double x) {
    if (!(a > 0 && b > 0 && x >= 0 && x <= 1)) throw std::invalid_argument("calcIncompleteBeta: bad arguments");
    if (x == 0 || x == 1) return x;
    const double lbeta = std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b);
    const double front = std::exp(lbeta + a * std::log(x) + b * std::log1p(-x));
    if (x < (a + 1.0) / (a + b + 2.0)) return front * betaContinuedFraction(a, b, x) / a;
    return 1.0 - front * betaContinuedFraction(b, a, 1.0 - x) / b;
}

double calcStudentTCdf(double t, double dof) {
    if (!(dof > 0)) throw std::invalid_argument("calcStudentTCdf: dof must be > 0");
    if (std::isinf(dof)) return 0.5 * std::erfc(-t / std::sqrt(2.0));
    const double tail = 0.5 * calcIncompleteBeta(0.5 * dof, 0.5, dof / (dof + t * t));
    return t >= 0 ? 1.0 - tail : tail;
}

double calcStudentTQuantile(double p, double dof) {
    checkProbability(p);
    if (p == 0.5) return 0.0;
    double lo = -1.0, hi = 1.0;
    while (calcStudentTCdf(lo, dof) > p) lo *= 2.0;
    while (calcStudentTCdf(hi, dof) < p) hi *= 2.0;
    for (int i = 0; i < 200 && hi - lo > 1e-14 * std::max(1.0, std::abs(hi)); ++i) {
        const double mid = 0.5 * (lo + hi);
        (calcStudentTCdf(mid, dof) < p ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

double calcNormalQuantile(double p) {
    return calcStudentTQuantile(p, std::numeric_limits<double>::infinity());
}

double calcUpperIncompleteGamma(double a, double x) {
    if (!(a > 0 && x >= 0)) throw std::invalid_argument("calcUpperIncompleteGamma: bad arguments");
    if (x == 0) return 1.0;
    const double front = std::exp(-x + a * std::log(x) - std::lgamma(a));
    if (x < a + 1.0) {  // P by its series, Q = 1 - P
        double term = 1.0 / a, sum = term;
        for (int n = 1; n < 10000 && std::abs(term) > 1e-16 * std::abs(sum); ++n) {
            term *= x / (a + n);
            sum += term;
        }
        return 1.0 - front * sum;
    }
    // Continued fraction for Q (modified Lentz).
    constexpr double tiny = 1e-300;
    double b = x + 1.0 - a, c = 1.0 / tiny, d = 1.0 / b, h = d;
    for (int i = 1; i < 10000; ++i) {
        const double an = -i * (i - a);
        b += 2.0;
        d = an * d + b;
        if (std::abs(d) < tiny) d = tiny;
        c = b + an / c;
        if (std::abs(c) < tiny) c = tiny;
        d = 1.0 / d;
        const double delta = d * c;
        h *= delta;
        if (std::abs(delta - 1.0) < 1e-16) break;
    }
    return front * h;
}

double calcChiSquareSurvival(double x, double dof) {
    if (!(dof > 0)) throw std::invalid_argument("calcChiSquareSurvival: dof must be > 0");
    return calcUpperIncompleteGamma(0.5 * dof, 0.5 * std::max(x, 0.0));
}

}  // namespace armsim
