#include "estimation/map_estimate.h"

#include "basics/errors.h"
#include "estimation/ceres_logging.h"
#include "estimation/numeric_diff.h"

#include <ceres/ceres.h>
#include <Eigen/Cholesky>
#include <Eigen/Dense>

#include <algorithm>
#include <stdexcept>
#include <string>

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

// The same cost with the data rows' Jacobian from MapProblem::jacobian and the prior rows' L^{-1}.
class AnalyticMapCost final : public ceres::CostFunction {
public:
    explicit AnalyticMapCost(const MapCost& cost) : cost_(cost) {
        mutable_parameter_block_sizes()->push_back(int(cost.mean.size()));
        set_num_residuals(cost.problem->numResiduals + int(cost.mean.size()));
    }
    bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
        if (jacobians == nullptr || jacobians[0] == nullptr) return cost_(parameters, residuals);
        const int n = int(cost_.mean.size()), m = cost_.problem->numResiduals;
        const double* x = parameters[0];
        if (!cost_.problem->jacobian(x, residuals, jacobians[0])) return false;
        const Eigen::VectorXd d = Eigen::Map<const Eigen::VectorXd>(x, n) - cost_.mean;
        Eigen::Map<Eigen::VectorXd>(residuals + m, n) = cost_.priorL.triangularView<Eigen::Lower>().solve(d);
        Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(jacobians[0] + std::size_t(m) * n, n, n) =
            cost_.priorL.triangularView<Eigen::Lower>().solve(Eigen::MatrixXd::Identity(n, n));
        return true;
    }

private:
    MapCost cost_;
};

constexpr double kSmoothStep = 1e-3;  // on x: ln scales and activations

// Stops the solve at the next iteration after Ctrl-C (requestInterruption); the caller then throws.
struct InterruptionCallback : ceres::IterationCallback {
    ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
        return getInterruption() ? ceres::SOLVER_ABORT : ceres::SOLVER_CONTINUE;
    }
};

// The Laplace covariance (J^T J)^{-1} of every residual, data and prior, with J by central differences
// of step kSmoothStep (one-sided at a bound), the fixed coordinates left out (zero rows and columns).
// Empty when a probe fails or the Hessian is not positive definite.
std::vector<std::vector<double>> calcSmoothedCovariance(const MapProblem& problem, const MapCost& cost,
                                                        const std::vector<double>& x, const std::vector<int>& fixed) {
    const int n = int(x.size()), m = problem.numResiduals + n;
    std::vector<int> free;
    for (int j = 0; j < n; ++j)
        if (std::find(fixed.begin(), fixed.end(), j) == fixed.end()) free.push_back(j);
    Eigen::MatrixXd J(m, free.size());
    Eigen::VectorXd up(m), down(m);
    std::vector<double> probe = x;
    for (std::size_t k = 0; k < free.size(); ++k) {
        const int j = free[k];
        const double hi = problem.upper.empty() ? x[j] + kSmoothStep : std::min(x[j] + kSmoothStep, problem.upper[j]);
        const double lo = problem.lower.empty() ? x[j] - kSmoothStep : std::max(x[j] - kSmoothStep, problem.lower[j]);
        const double* p = probe.data();
        probe[j] = hi;
        if (!cost(&p, up.data())) return {};
        probe[j] = lo;
        if (!cost(&p, down.data())) return {};
        probe[j] = x[j];
        if (!(hi > lo)) return {};
        J.col(Eigen::Index(k)) = (up - down) / (hi - lo);
    }
    const Eigen::MatrixXd H = J.transpose() * J;
    const Eigen::LLT<Eigen::MatrixXd> llt(H);
    if (llt.info() != Eigen::Success) return {};
    const Eigen::MatrixXd C = llt.solve(Eigen::MatrixXd::Identity(H.rows(), H.cols()));
    std::vector<std::vector<double>> out(n, std::vector<double>(n, 0.0));
    for (std::size_t a = 0; a < free.size(); ++a)
        for (std::size_t b = 0; b < free.size(); ++b) out[free[a]][free[b]] = C(Eigen::Index(a), Eigen::Index(b));
    return out;
}

}  // namespace

MapResult calcMapEstimate(const MapProblem& problem) {
    // Ceres reports a singular covariance through glog's stderr as well as through Compute's result;
    // armsim reports it in the message (and falls back on the smoothed Jacobian).
    quietCeresLogging();
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
    ceres::CostFunction* cost = problem.jacobian ? static_cast<ceres::CostFunction*>(new AnalyticMapCost(functor))
                                                 : new SteppingNumericDiffCost<MapCost>(new MapCost(functor), n, problem.numResiduals + n);
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
    InterruptionCallback interruption;
    so.callbacks.push_back(&interruption);
    ceres::Solver::Summary summary;
    ceres::Solve(so, &pr, &summary);
    checkInterruption();
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
    } else if (!(result.covariance = calcSmoothedCovariance(problem, functor, result.x, fixed)).empty()) {
        // Ceres's Jacobian (relative steps of 1e-6) straddled a step of a piecewise model (a motor
        // unit's recruitment): its Hessian is near singular in that direction. The slope over a wider
        // step is the model's average one.
        result.message += "; posterior covariance from a smoothed Jacobian (step 1e-3)";
    } else {
        result.message += "; no posterior covariance (singular Hessian)";
    }
    return result;
}

}  // namespace armsim
