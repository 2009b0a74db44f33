// Least-squares polynomial fits (Eigen) for experiment results: the thesis's quadratic force-angle
// fit and its peak, and the EMG-to-activation map.
#pragma once

#include <vector>

namespace armsim {

/// y ~ sum_k coefficients[k] x^k, fitted by linear least squares.
struct PolynomialFit {
    std::vector<double> coefficients;  ///< c0, c1, ..., c_degree (units of y / units of x^k)
    double rmsResidual = 0;            ///< sqrt(mean squared residual), units of y
    double rSquared = 0;               ///< 1 - SS_res / SS_tot (1 when the data have no spread)
    int points = 0;                    ///< number of (x, y) pairs fitted

    /// The polynomial at x.
    double evaluate(double x) const;
};

/// Fits a polynomial of the given degree (0..10) to (x, y) by least squares (column-pivoting
/// Householder QR on the Vandermonde matrix, with x centred and scaled internally for conditioning).
/// Throws InputError unless x and y have equal length, at least degree + 1 points, finite values, and
/// at least degree + 1 distinct x.
PolynomialFit fitPolynomial(const std::vector<double>& x, const std::vector<double>& y, int degree);

/// A quadratic fit and its vertex.
struct QuadraticFit {
    PolynomialFit fit;     ///< degree-2 polynomial
    bool hasMaximum = false;  ///< c2 < 0: the vertex is a maximum
    double peakX = 0;      ///< the vertex -c1 / (2 c2) when it is a maximum within the points' x span and
                           ///< more than three distinct x were fitted; NaN otherwise (no peak)
    double peakY = 0;      ///< value at the vertex (NaN: no peak)
};

/// fitPolynomial(x, y, 2) and its vertex (the thesis's "peak force 603.3 N at 101.2 deg").
QuadraticFit fitQuadratic(const std::vector<double>& x, const std::vector<double>& y);

/// Sample mean and standard deviation (n - 1 in the denominator; 0 for fewer than two values).
struct MeanSd {
    double mean = 0, sd = 0;
    int n = 0;
};
MeanSd calcMeanSd(const std::vector<double>& v);

}  // namespace armsim
