// Least-squares fits: a known parabola and its vertex, exact polynomials, optimality of the
// least-squares solution (residual orthogonal to the basis), errors, mean and sd.
#include "basics/errors.h"
#include "experiments/fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace armsim;

namespace {
constexpr double kExactTol = 1e-12;          // exact data: round-off only
constexpr double kOrthogonalityTol = 1e-10;  // |residual . x^k| relative to sum |y x^k|
}  // namespace

TEST(Fit, QuadraticRecoversAKnownParabolaAndItsPeak) {
    // The thesis's reported curve shape: peak 603.3 N at 101.2 deg.
    constexpr double kPeakY = 603.3, kPeakX = 101.2, kCurv = -0.05, kTol = 1e-9;
    std::vector<double> x, y;
    for (double a : {45.0, 60.0, 90.0, 120.0, 150.0})
        for (int rep = 0; rep < 3; ++rep) {
            x.push_back(a);
            y.push_back(kPeakY + kCurv * (a - kPeakX) * (a - kPeakX));
        }
    const QuadraticFit q = fitQuadratic(x, y);
    EXPECT_TRUE(q.hasMaximum);
    EXPECT_NEAR(q.peakX, kPeakX, kTol);
    EXPECT_NEAR(q.peakY, kPeakY, kTol * kPeakY);
    EXPECT_NEAR(q.fit.coefficients[2], kCurv, kTol);
    EXPECT_NEAR(q.fit.coefficients[1], -2 * kCurv * kPeakX, kTol * 100);
    EXPECT_NEAR(q.fit.rSquared, 1.0, kExactTol);
    EXPECT_NEAR(q.fit.rmsResidual, 0.0, kTol);
    EXPECT_EQ(q.fit.points, 15);
}

TEST(Fit, CubicIsRecoveredExactly) {
    const std::vector<double> c = {0.3, -1.2, 0.7, 0.05};
    std::vector<double> x, y;
    for (int i = 0; i < 12; ++i) {
        x.push_back(0.2 * i - 1);
        y.push_back(c[0] + c[1] * x.back() + c[2] * x.back() * x.back() + c[3] * std::pow(x.back(), 3));
    }
    const PolynomialFit f = fitPolynomial(x, y, 3);
    for (int k = 0; k < 4; ++k) EXPECT_NEAR(f.coefficients[k], c[k], kExactTol);
    EXPECT_NEAR(f.evaluate(0.37), c[0] + c[1] * 0.37 + c[2] * 0.37 * 0.37 + c[3] * std::pow(0.37, 3), kExactTol);
}

TEST(Fit, NoisyFitIsTheLeastSquaresSolution) {
    // At the least-squares optimum the residual is orthogonal to every basis function x^k.
    std::mt19937_64 rng(5);
    std::normal_distribution<double> noise(0, 5);
    std::vector<double> x, y;
    for (int i = 0; i < 40; ++i) {
        x.push_back(40 + 3.5 * i);
        y.push_back(600 - 0.05 * (x.back() - 100) * (x.back() - 100) + noise(rng));
    }
    const PolynomialFit f = fitPolynomial(x, y, 2);
    for (int k = 0; k <= 2; ++k) {
        double dot = 0, scale = 0;
        for (std::size_t i = 0; i < x.size(); ++i) {
            dot += (f.evaluate(x[i]) - y[i]) * std::pow(x[i], k);
            scale += std::abs(y[i]) * std::pow(x[i], k);
        }
        EXPECT_LT(std::abs(dot), kOrthogonalityTol * scale) << "k = " << k;
    }
    EXPECT_GT(f.rSquared, 0.9);
    EXPECT_LT(f.rSquared, 1.0);
}

TEST(Fit, TooFewDistinctPointsOrBadInputAreErrors) {
    EXPECT_THROW(fitPolynomial({1, 1, 2}, {1, 2, 3}, 2), InputError);
    EXPECT_THROW(fitPolynomial({1, 2}, {1}, 1), InputError);
    EXPECT_THROW(fitPolynomial({1, 2, NAN}, {1, 2, 3}, 1), InputError);
    EXPECT_THROW(fitPolynomial({1, 2, 3}, {1, 2, 3}, 11), InputError);
}

TEST(Fit, MeanAndSampleSd) {
    const MeanSd m = calcMeanSd({2, 4, 4, 4, 5, 5, 7, 9});
    EXPECT_DOUBLE_EQ(m.mean, 5.0);
    EXPECT_NEAR(m.sd, std::sqrt(32.0 / 7.0), kExactTol);
    EXPECT_EQ(m.n, 8);
    EXPECT_EQ(calcMeanSd({3}).sd, 0.0);
}
