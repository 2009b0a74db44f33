// Brent's bracketing root finder (Brent 1973, "Algorithms for Minimization without Derivatives",
// ch. 4) as a header template, so a muscle model's scalar steady solve inlines its residual.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

namespace armsim {

/// Result of findRootBrent.
struct BrentResult {
    bool converged = false;  ///< the bracket shrank below the tolerance within maxIterations
    double x = 0;            ///< the root's estimate (the bracket end with the smaller residual)
    double fx = 0;           ///< f(x)
    int evaluations = 0;     ///< calls of f, the two end values included
};

/// A root of f in [a, b] given fa = f(a) and fb = f(b) of opposite signs: stops when half the
/// bracket is within 2 eps |x| + tolX / 2 or f(x) == 0. evaluations counts the two given values.
template <class F>
BrentResult findRootBrent(F&& f, double a, double b, double fa, double fb, double tolX, int maxIterations) {
    BrentResult r;
    r.evaluations = 2;
    double c = a, fc = fa, d = b - a, e = d;
    for (int iter = 0; iter < maxIterations; ++iter) {
        if ((fb > 0) == (fc > 0)) { c = a; fc = fa; d = e = b - a; }
        if (std::abs(fc) < std::abs(fb)) { a = b; b = c; c = a; fa = fb; fb = fc; fc = fa; }
        const double tol = 2.0 * std::numeric_limits<double>::epsilon() * std::abs(b) + 0.5 * tolX;
        const double m = 0.5 * (c - b);
        if (std::abs(m) <= tol || fb == 0.0) {
            r.converged = true;
            break;
        }
        if (std::abs(e) >= tol && std::abs(fa) > std::abs(fb)) {
            double p, q, rr, s = fb / fa;
            if (a == c) {
                p = 2.0 * m * s;
                q = 1.0 - s;
            } else {
                q = fa / fc;
                rr = fb / fc;
                p = s * (2.0 * m * q * (q - rr) - (b - a) * (rr - 1.0));
                q = (q - 1.0) * (rr - 1.0) * (s - 1.0);
            }
            if (p > 0) q = -q; else p = -p;
            if (2.0 * p < std::min(3.0 * m * q - std::abs(tol * q), std::abs(e * q))) {
                e = d;
                d = p / q;
            } else {
                d = m;
                e = m;
            }
        } else {
            d = m;
            e = m;
        }
        a = b;
        fa = fb;
        b += std::abs(d) > tol ? d : (m > 0 ? tol : -tol);
        fb = f(b);
        ++r.evaluations;
    }
    r.x = b;
    r.fx = fb;
    return r;
}

}  // namespace armsim
