// The MAP estimate with its Laplace covariance on a linear-Gaussian case, where the posterior is known
// in closed form.
#include "estimation/map_estimate.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <cmath>
#include <random>

using namespace armsim;

// y = A x + e, e ~ N(0, s^2 I), x ~ N(mu, Sigma): the posterior is Gaussian with covariance
// P = (A^T A / s^2 + Sigma^-1)^-1 and mean P (A^T y / s^2 + Sigma^-1 mu). calcMapEstimate must give
// both, and its 95 % intervals must cover truths drawn from the prior 95 % of the time.
TEST(MapEstimate, LinearGaussianPosteriorMatchesTheClosedFormAndCovers95Percent) {
    constexpr int kDraws = 1000;
    constexpr double kNoiseSd = 0.3;
    Eigen::MatrixXd A(5, 2);
    A << 1, 0.5, 1, 1.0, 1, 1.5, 1, 2.0, 0.5, -1.0;
    Eigen::Vector2d mu(1.0, -0.5);
    Eigen::Matrix2d Sigma;
    Sigma << 0.5, 0.2, 0.2, 0.3;
    const Eigen::Matrix2d P = (A.transpose() * A / (kNoiseSd * kNoiseSd) + Sigma.inverse()).inverse();
    const Eigen::Matrix2d L = Sigma.llt().matrixL();
    std::mt19937_64 rng(5);
    std::normal_distribution<double> normal;
    int covered[2] = {0, 0};
    for (int d = 0; d < kDraws; ++d) {
        const Eigen::Vector2d truth = mu + L * Eigen::Vector2d(normal(rng), normal(rng));
        Eigen::VectorXd y = A * truth;
        for (int k = 0; k < y.size(); ++k) y[k] += kNoiseSd * normal(rng);
        MapProblem m;
        m.numResiduals = 5;
        m.residuals = [&](const double* x, double* r) {
            const Eigen::VectorXd pred = A * Eigen::Vector2d(x[0], x[1]);
            for (int k = 0; k < 5; ++k) r[k] = (pred[k] - y[k]) / kNoiseSd;
            return true;
        };
        m.priorMean = {mu[0], mu[1]};
        m.functionTolerance = 1e-14;  // solve to round-off: the closed form is compared at 1e-6
        m.priorCovariance = {{Sigma(0, 0), Sigma(0, 1)}, {Sigma(1, 0), Sigma(1, 1)}};
        const MapResult r = calcMapEstimate(m);
        ASSERT_TRUE(r.converged) << r.message;
        ASSERT_EQ(r.covariance.size(), 2u) << r.message;
        const Eigen::Vector2d mean = P * (A.transpose() * y / (kNoiseSd * kNoiseSd) + Sigma.inverse() * mu);
        for (int j = 0; j < 2; ++j) {
            EXPECT_NEAR(r.x[j], mean[j], 1e-6) << d;
            for (int k = 0; k < 2; ++k) EXPECT_NEAR(r.covariance[j][k], P(j, k), 1e-6 * P(j, j)) << d;
            covered[j] += std::abs(r.x[j] - truth[j]) <= 1.959963984540054 * std::sqrt(r.covariance[j][j]);
        }
    }
    const double tolerance = 3 * std::sqrt(0.95 * 0.05 / kDraws);  // three binomial standard errors
    for (int j = 0; j < 2; ++j) EXPECT_NEAR(covered[j] / double(kDraws), 0.95, tolerance) << j;
}

// The same posterior with the data rows' Jacobian given in closed form (MapProblem::jacobian): the
// estimate and the covariance equal the closed form, and the covariance is built from that Jacobian
// (a Jacobian twice too large gives the posterior of noise half as large).
TEST(MapEstimate, AClosedFormJacobianGivesTheClosedFormPosterior) {
    constexpr double kNoiseSd = 0.3;
    Eigen::MatrixXd A(3, 2);
    A << 1, 0.5, 1, 2.0, 0.5, -1.0;
    const Eigen::Vector2d mu(1.0, -0.5);
    Eigen::Matrix2d Sigma;
    Sigma << 0.5, 0.2, 0.2, 0.3;
    const Eigen::Vector3d y(1.2, 0.3, 1.1);
    for (double scale : {1.0, 2.0}) {
        MapProblem m;
        m.numResiduals = 3;
        m.residuals = [&](const double* x, double* r) {
            const Eigen::VectorXd pred = A * Eigen::Vector2d(x[0], x[1]);
            for (int k = 0; k < 3; ++k) r[k] = (pred[k] - y[k]) / kNoiseSd;
            return true;
        };
        int calls = 0;
        m.jacobian = [&](const double* x, double* r, double* J) {
            ++calls;
            m.residuals(x, r);
            for (int k = 0; k < 3; ++k)
                for (int j = 0; j < 2; ++j) J[k * 2 + j] = scale * A(k, j) / kNoiseSd;
            return true;
        };
        m.priorMean = {mu[0], mu[1]};
        m.functionTolerance = 1e-14;
        m.priorCovariance = {{Sigma(0, 0), Sigma(0, 1)}, {Sigma(1, 0), Sigma(1, 1)}};
        const MapResult r = calcMapEstimate(m);
        ASSERT_EQ(r.covariance.size(), 2u) << r.message;
        EXPECT_GT(calls, 0);
        const Eigen::Matrix2d P = (A.transpose() * A / (kNoiseSd * kNoiseSd) + Sigma.inverse()).inverse();
        const Eigen::Matrix2d Pj = (scale * scale * A.transpose() * A / (kNoiseSd * kNoiseSd) + Sigma.inverse()).inverse();
        if (scale == 1) {
            const Eigen::Vector2d mean = P * (A.transpose() * y / (kNoiseSd * kNoiseSd) + Sigma.inverse() * mu);
            for (int j = 0; j < 2; ++j) EXPECT_NEAR(r.x[j], mean[j], 1e-7);   // the solver's tolerances
        }
        for (int j = 0; j < 2; ++j)
            for (int k = 0; k < 2; ++k) EXPECT_NEAR(r.covariance[j][k], Pj(j, k), 1e-9 * P(j, j)) << "scale " << scale;
    }
}

// A model with a step (a motor unit's recruitment) where the estimate sits: Ceres's Jacobian, with
// steps of 1e-6, sees a slope of ~1e9 there and its covariance is near singular; the smoothed
// Jacobian's (step 1e-3) is not. The smooth coordinate keeps its closed-form variance: y = x1 + e with
// a flat prior, so var(x1) = s^2; the step coordinate's variance is below its prior's.
TEST(MapEstimate, AStepAtTheEstimateKeepsTheCovariance) {
    constexpr double kNoiseSd = 0.1, kJump = 1e3, kRelTol = 1e-6;
    MapProblem p;
    p.numResiduals = 2;
    p.priorMean = {0.0, 0.0};
    p.priorCovariance = {{1e6, 0.0}, {0.0, 1e6}};
    p.residuals = [](const double* x, double* r) {
        r[0] = (x[0] - 0.3) / kNoiseSd;
        r[1] = (x[1] - 0.5) / kNoiseSd + (x[1] > 0.5 ? kJump : 0.0);  // the step just right of the optimum
        return true;
    };
    const MapResult m = calcMapEstimate(p);
    ASSERT_TRUE(m.converged) << m.message;
    ASSERT_FALSE(m.covariance.empty()) << m.message;
    EXPECT_NE(m.message.find("smoothed Jacobian"), std::string::npos) << m.message;
    EXPECT_NEAR(m.x[1], 0.5, 1e-4);
    EXPECT_NEAR(m.covariance[0][0], kNoiseSd * kNoiseSd, kRelTol * kNoiseSd * kNoiseSd + 1e-12);
    EXPECT_GT(m.covariance[1][1], 0);
    EXPECT_LT(m.covariance[1][1], 1e6);
    EXPECT_NEAR(m.covariance[0][1], 0, 1e-12);
}
