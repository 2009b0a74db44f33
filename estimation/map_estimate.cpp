#include "estimation/map_estimate.h"

#include <ceres/ceres.h>
#include <Eigen/Cholesky>
#include <Eigen/Dense>

#include <stdexcept>

namespace armsim {

namespace {

// Data residuals, then the prior's whitened residuals L^{-1} (x - mu) with Sigma = L L^T.
struct MapCost {
    const MapProblem* problem;
    Eigen::VectorXd mean;
    Eigen::MatrixXd priorL;
    bool operator()(double const* const* parameters, double* residuals) const {
        const double* x = parameters[0];
        if (!problem->residuals(x, residuals)) return false;
        const int n = int(mean.size());
        const Eigen::VectorXd d = Eigen::Map<const Eigen::VectorXd>(x, n) - mean;
        Eigen::Map<Eigen::VectorXd>(residuals + problem->numResiduals, n) =
            priorL.triangularView<Eigen::Lower>().solve(d);
        return true;
    }
};

}  // namespace

MapResult calcMapEstimate(const MapProblem& problem) {
    const int n = int(problem.priorMean.size());
    if (n == 0 || int(problem.priorCovariance.size()) != n)
        throw std::invalid_argument("calcMapEstimate: prior mean and covariance sizes differ");
    if ((!problem.lower.empty() && int(problem.lower.size()) != n) ||
        (!problem.upper.empty() && int(problem.upper.size()) != n) ||
        (!problem.start.empty() && int(problem.start.size()) != n))
        throw std::invalid_argument("calcMapEstimate: bounds or start have the wrong size");
    Eigen::MatrixXd cov(n, n);
    for (int i = 0; i < n; ++i) {
        if (int(problem.priorCovariance[i].size()) != n)
            throw std::invalid_argument("calcMapEstimate: prior covariance is not square");
        for (int j = 0; j < n; ++j) cov(i, j) = problem.priorCovariance[i][j];
    }
    const Eigen::LLT<Eigen::MatrixXd> llt(cov);
    if (llt.info() != Eigen::Success) throw std::invalid_argument("calcMapEstimate: prior covariance not positive definite");

    MapCost functor{&problem, Eigen::Map<const Eigen::VectorXd>(problem.priorMean.data(), n), llt.matrixL()};
    MapResult result;
    result.x = problem.start.empty() ? problem.priorMean : problem.start;
    auto* cost = new ceres::DynamicNumericDiffCostFunction<MapCost, ceres::CENTRAL>(new MapCost(functor));
    cost->AddParameterBlock(n);
    cost->SetNumResiduals(problem.numResiduals + n);
    ceres::Problem pr;
    pr.AddResidualBlock(cost, nullptr, result.x.data());
    std::vector<int> fixed;
    for (int j = 0; j < n; ++j) {
        if (!problem.lower.empty() && !problem.upper.empty() && problem.lower[j] >= problem.upper[j]) {
            result.x[j] = problem.lower[j];
            fixed.push_back(j);
            continue;
        }
        if (!problem.lower.empty()) pr.SetParameterLowerBound(result.x.data(), j, problem.lower[j]);
        if (!problem.upper.empty()) pr.SetParameterUpperBound(result.x.data(), j, problem.upper[j]);
    }
    if (int(fixed.size()) == n) pr.SetParameterBlockConstant(result.x.data());
    else if (!fixed.empty()) pr.SetManifold(result.x.data(), new ceres::SubsetManifold(n, fixed));
    ceres::Solver::Options so;
    so.logging_type = ceres::SILENT;   // failures are reported through the summary, not glog
    so.max_num_iterations = problem.maxIterations;
    so.function_tolerance = problem.functionTolerance;
    so.parameter_tolerance = 1e-10;
    ceres::Solver::Summary summary;
    ceres::Solve(so, &pr, &summary);
    result.converged = summary.termination_type == ceres::CONVERGENCE;
    result.failed = summary.termination_type == ceres::FAILURE;
    result.message = summary.BriefReport();
    result.iterations = summary.num_successful_steps + summary.num_unsuccessful_steps;
    if (result.failed) {
        result.message += ": " + summary.message;
        return result;
    }

    std::vector<double> r(problem.numResiduals);
    if (problem.residuals(result.x.data(), r.data()))
        for (double v : r) result.dataCost += 0.5 * v * v;
    ceres::Covariance::Options co;
    co.algorithm_type = ceres::DENSE_SVD;
    ceres::Covariance covariance(co);
    const std::vector<std::pair<const double*, const double*>> blocks{{result.x.data(), result.x.data()}};
    if (covariance.Compute(blocks, &pr)) {
        std::vector<double> c(std::size_t(n) * n);
        covariance.GetCovarianceBlock(result.x.data(), result.x.data(), c.data());
        result.covariance.assign(n, std::vector<double>(n));
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j) result.covariance[i][j] = c[std::size_t(i) * n + j];
    } else {
        result.message += "; no posterior covariance (singular Hessian)";
    }
    return result;
}

}  // namespace armsim
