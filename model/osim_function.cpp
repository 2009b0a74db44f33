#include "model/osim_function.h"

#include <algorithm>

namespace armsim {

namespace {

// Forsythe, Malcolm & Moler's SPLINE: coefficients b, c, d of s(x) = y_k + b_k dx + c_k dx^2 + d_k dx^3.
void calcSplineCoefficients(const std::vector<double>& x, const std::vector<double>& y, std::vector<double>& b,
                            std::vector<double>& c, std::vector<double>& d) {
    const int n = int(x.size());
    b.assign(n, 0.0);
    c.assign(n, 0.0);
    d.assign(n, 0.0);
    if (n == 2) {
        b[0] = b[1] = (y[1] - y[0]) / (x[1] - x[0]);
        return;
    }
    // The tridiagonal system for sigma_k = s''(x_k) / 6: h (diagonal b), h_k (off-diagonal d), the
    // divided differences' differences (right-hand side c).
    std::vector<double> h(n - 1), diag(n), rhs(n, 0.0);
    for (int k = 0; k < n - 1; ++k) h[k] = x[k + 1] - x[k];
    for (int k = 1; k < n - 1; ++k) {
        diag[k] = 2 * (h[k - 1] + h[k]);
        rhs[k] = (y[k + 1] - y[k]) / h[k] - (y[k] - y[k - 1]) / h[k - 1];
    }
    // End conditions: the third derivative at each end equals that of the cubic through the four end
    // knots (third divided differences); with three knots, 0.
    diag[0] = -h[0];
    diag[n - 1] = -h[n - 2];
    if (n > 3) {
        auto dd2 = [&](int k) {   // second divided difference over x_k, x_k+1, x_k+2
            return ((y[k + 2] - y[k + 1]) / h[k + 1] - (y[k + 1] - y[k]) / h[k]) / (x[k + 2] - x[k]);
        };
        const double third0 = (dd2(1) - dd2(0)) / (x[3] - x[0]);
        const double thirdN = (dd2(n - 3) - dd2(n - 4)) / (x[n - 1] - x[n - 4]);
        rhs[0] = h[0] * h[0] * third0;
        rhs[n - 1] = -h[n - 2] * h[n - 2] * thirdN;
    }
    // Forward elimination, back substitution.
    for (int k = 1; k < n; ++k) {
        const double t = h[k - 1] / diag[k - 1];
        diag[k] -= t * h[k - 1];
        rhs[k] -= t * rhs[k - 1];
    }
    std::vector<double> sigma(n);
    sigma[n - 1] = rhs[n - 1] / diag[n - 1];
    for (int k = n - 2; k >= 0; --k) sigma[k] = (rhs[k] - h[k] * sigma[k + 1]) / diag[k];
    // Polynomial coefficients.
    for (int k = 0; k < n - 1; ++k) {
        b[k] = (y[k + 1] - y[k]) / h[k] - h[k] * (sigma[k + 1] + 2 * sigma[k]);
        c[k] = 3 * sigma[k];
        d[k] = (sigma[k + 1] - sigma[k]) / h[k];
    }
    b[n - 1] = (y[n - 1] - y[n - 2]) / h[n - 2] + h[n - 2] * (sigma[n - 2] + 2 * sigma[n - 1]);
    c[n - 1] = 3 * sigma[n - 1];
    d[n - 1] = d[n - 2];
}

}  // namespace

OsimFunctionEvaluator::OsimFunctionEvaluator(const OsimFunction& f)
    : kind_(f.kind), value_(f.value), slope_(f.slope), intercept_(f.intercept), x_(f.x), y_(f.y) {
    if (kind_ == OsimFunction::Kind::SimmSpline || kind_ == OsimFunction::Kind::NaturalCubicSpline) {
        calcSplineCoefficients(x_, y_, b_, c_, d_);
    } else if (kind_ == OsimFunction::Kind::PiecewiseLinear) {
        const int n = int(x_.size());
        b_.assign(n, 0.0);
        for (int k = 0; k + 1 < n; ++k) b_[k] = (y_[k + 1] - y_[k]) / (x_[k + 1] - x_[k]);
        if (n >= 2) b_[n - 1] = b_[n - 2];
    }
}

int OsimFunctionEvaluator::findInterval(double x) const {
    const int n = int(x_.size());
    if (x < x_.front()) return -1;
    if (x >= x_.back()) return n - 1;
    return int(std::upper_bound(x_.begin(), x_.end(), x) - x_.begin()) - 1;
}

double OsimFunctionEvaluator::calcValue(double x) const {
    switch (kind_) {
        case OsimFunction::Kind::Constant: return value_;
        case OsimFunction::Kind::Linear: return slope_ * x + intercept_;
        default: break;
    }
    const int k = findInterval(x);
    if (k < 0) return y_.front() + (x - x_.front()) * b_.front();
    if (k == int(x_.size()) - 1) return y_.back() + (x - x_.back()) * b_.back();
    const double dx = x - x_[k];
    if (kind_ == OsimFunction::Kind::PiecewiseLinear) return y_[k] + dx * b_[k];
    return y_[k] + dx * (b_[k] + dx * (c_[k] + dx * d_[k]));
}

double OsimFunctionEvaluator::calcDerivative(double x) const {
    switch (kind_) {
        case OsimFunction::Kind::Constant: return 0;
        case OsimFunction::Kind::Linear: return slope_;
        default: break;
    }
    const int k = findInterval(x);
    if (k < 0) return b_.front();
    if (k == int(x_.size()) - 1) return b_.back();
    if (kind_ == OsimFunction::Kind::PiecewiseLinear) return b_[k];
    const double dx = x - x_[k];
    return b_[k] + dx * (2 * c_[k] + 3 * dx * d_[k]);
}

}  // namespace armsim
