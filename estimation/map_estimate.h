// Maximum a posteriori estimation with a Gaussian prior and the Laplace approximation of the posterior
// (bounded Levenberg-Marquardt, Ceres).
//
// Minimises 0.5 |r(x)|^2 + 0.5 (x - mu)^T Sigma^{-1} (x - mu), where r are the data residuals already
// divided by their standard deviations, within box bounds. The posterior covariance is the inverse
// Gauss-Newton Hessian of all residuals at the optimum, (J^T J + Sigma^{-1})^{-1}: exact for a linear
// model with Gaussian noise and prior (then the 95 % intervals x_j +/- 1.96 sd_j cover the truth 95 %
// of the time when truths are drawn from the prior), approximate otherwise.
#pragma once

#include <functional>
#include <string>
#include <vector>

namespace armsim {

/// r(x): writes the whitened data residuals; returns false where the model has no solution (the
/// solver then rejects the step).
using ResidualFunction = std::function<bool(const double* x, double* residuals)>;

/// r(x) and its Jacobian dr/dx, row-major (jacobian[i * n + j] = d r_i / d x_j); false as ResidualFunction.
using ResidualJacobianFunction = std::function<bool(const double* x, double* residuals, double* jacobian)>;

struct MapProblem {
    ResidualFunction residuals;
    /// Optional: the data residuals' Jacobian in closed form; empty: central differences of residuals
    /// (Ceres's steps). The smoothed covariance's fallback (a wider step) always differences.
    ResidualJacobianFunction jacobian;
    int numResiduals = 0;
    std::vector<double> priorMean;                   ///< mu
    std::vector<std::vector<double>> priorCovariance;  ///< Sigma (symmetric positive definite)
    std::vector<double> lower, upper;                ///< bounds (empty: none); lower == upper holds x_j fixed
    std::vector<double> start;                       ///< empty: the prior mean
    int maxIterations = 300;
    /// Stop when an iteration lowers the cost by less than this fraction (Ceres function_tolerance).
    /// Piecewise-smooth models (a tendon going slack) can crawl in the last digits at 1e-10.
    double functionTolerance = 1e-7;
};

struct MapResult {
    std::vector<double> x;                           ///< the estimate
    std::vector<std::vector<double>> covariance;     ///< posterior covariance (empty when singular)
    bool converged = false;
    bool failed = false;                             ///< the solver failed (x is the start, no covariance)
    std::string message;                             ///< Ceres's brief report, and why no covariance
    double dataCost = 0;                             ///< 0.5 |r(x)|^2 at the estimate
    int iterations = 0;                              ///< solver iterations (successful and rejected steps)
};

/// Throws std::invalid_argument for inconsistent sizes or a prior covariance that is not positive definite.
MapResult calcMapEstimate(const MapProblem& problem);

}  // namespace armsim
