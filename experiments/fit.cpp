#include "experiments/fit.h"

#include "basics/errors.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <set>
#include <string>

namespace armsim {

double PolynomialFit::evaluate(double x) const {
    double y = 0;
    for (std::size_t k = coefficients.size(); k-- > 0;) y = y * x + coefficients[k];
    return y;
}

PolynomialFit fitPolynomial(const std::vector<double>& x, const std::vector<double>& y, int degree) {
    if (degree < 0 || degree > 10) throw InputError("polynomial degree " + std::to_string(degree) + ": expected 0..10");
    if (x.size() != y.size())
        throw InputError("polynomial fit: " + std::to_string(x.size()) + " x values but " + std::to_string(y.size()) +
                         " y values");
    const int n = int(x.size());
    std::set<double> distinct;
    for (int i = 0; i < n; ++i) {
        if (!std::isfinite(x[i]) || !std::isfinite(y[i]))
            throw InputError("polynomial fit: point " + std::to_string(i) + " is not finite");
        distinct.insert(x[i]);
    }
    if (int(distinct.size()) < degree + 1)
        throw InputError("polynomial fit of degree " + std::to_string(degree) + " needs at least " +
                         std::to_string(degree + 1) + " distinct x values, got " + std::to_string(distinct.size()));

    // Fit in s = (x - centre) / scale, then expand back to powers of x.
    const double lo = *distinct.begin(), hi = *distinct.rbegin();
    const double centre = 0.5 * (lo + hi), scale = hi > lo ? 0.5 * (hi - lo) : 1.0;
    Eigen::MatrixXd A(n, degree + 1);
    Eigen::VectorXd b(n);
    for (int i = 0; i < n; ++i) {
        const double s = (x[i] - centre) / scale;
        double p = 1;
        for (int k = 0; k <= degree; ++k, p *= s) A(i, k) = p;
        b(i) = y[i];
    }
    const Eigen::VectorXd a = A.colPivHouseholderQr().solve(b);

    // sum_k a_k ((x - c)/s)^k = sum_j coef_j x^j (binomial expansion).
    PolynomialFit f;
    f.coefficients.assign(degree + 1, 0.0);
    for (int k = 0; k <= degree; ++k) {
        const double ak = a(k) / std::pow(scale, k);
        double binom = 1;  // C(k, j)
        for (int j = 0; j <= k; ++j) {
            f.coefficients[j] += ak * binom * std::pow(-centre, k - j);
            binom = binom * (k - j) / (j + 1);
        }
    }
    const Eigen::VectorXd r = A * a - b;
    f.points = n;
    f.rmsResidual = std::sqrt(r.squaredNorm() / n);
    const double meanY = b.mean();
    const double ssTot = (b.array() - meanY).square().sum();
    f.rSquared = ssTot > 0 ? 1.0 - r.squaredNorm() / ssTot : 1.0;
    return f;
}

QuadraticFit fitQuadratic(const std::vector<double>& x, const std::vector<double>& y) {
    QuadraticFit q;
    q.fit = fitPolynomial(x, y, 2);
    const double c1 = q.fit.coefficients[1], c2 = q.fit.coefficients[2];
    q.hasMaximum = c2 < 0;
    // A peak is a maximum inside the points' span, fitted at more abscissae than the three that fix any
    // quadratic (through three, or their means, the fit says nothing of the curve's shape).
    const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
    std::vector<double> distinct(x);
    std::sort(distinct.begin(), distinct.end());
    distinct.erase(std::unique(distinct.begin(), distinct.end()), distinct.end());
    const double vertex = c2 != 0 ? -c1 / (2 * c2) : NAN;
    const bool peak = q.hasMaximum && distinct.size() > 3 && vertex >= *lo && vertex <= *hi;
    q.peakX = peak ? vertex : NAN;
    q.peakY = peak ? q.fit.evaluate(vertex) : NAN;
    return q;
}

MeanSd calcMeanSd(const std::vector<double>& v) {
    MeanSd m;
    m.n = int(v.size());
    if (v.empty()) return m;
    double s = 0;
    for (double a : v) s += a;
    m.mean = s / double(v.size());
    if (v.size() > 1) {
        double ss = 0;
        for (double a : v) ss += (a - m.mean) * (a - m.mean);
        m.sd = std::sqrt(ss / double(v.size() - 1));
    }
    return m;
}

}  // namespace armsim
