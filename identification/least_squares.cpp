// Bounded Levenberg-Marquardt (Ceres) with covariance-based intervals and seeded multi-start.
#include "basics/errors.h"
#include "basics/format.h"
#include "basics/portable_random.h"
#include "identification/solver_context.h"
#include "estimation/ceres_logging.h"
#include "estimation/statistics.h"

#include <ceres/ceres.h>

#include <cmath>
#include <limits>
#include <memory>
#include <sstream>

namespace armsim::detail {

namespace {

/// Central-difference step in scaled units (z ~ 1): the option, else the model's suggestion.
double getDifferenceStep(const SolverContext& ctx) {
    return std::isnan(ctx.options.differenceStep) ? ctx.model.getDifferenceStep() : ctx.options.differenceStep;
}

double getParameterTolerance(const SolverContext& ctx) {
    return std::isnan(ctx.options.parameterTolerance) ? ctx.model.getParameterTolerance()
                                                      : ctx.options.parameterTolerance;
}

/// Residual weights of the noise model: 1, or 1 / measured force.
std::vector<double> calcWeights(const SolverContext& ctx) {
    std::vector<double> w;
    for (const Observation& o : ctx.observations)
        w.push_back(ctx.options.noise == NoiseModel::Relative ? 1.0 / o.force : 1.0);
    return w;
}

double calcWeightedCost(const std::vector<double>& r, const std::vector<double>& w) {
    double c = 0;
    for (std::size_t k = 0; k < r.size(); ++k) c += (w[k] * r[k]) * (w[k] * r[k]);
    return 0.5 * c;
}

/// r(z) = model(x = z * scale) - measured, with the Jacobian from central differences.
class ForceCostFunction : public ceres::CostFunction {
public:
    explicit ForceCostFunction(SolverContext& ctx) : ctx_(ctx), w_(calcWeights(ctx)), step_(getDifferenceStep(ctx)) {
        set_num_residuals(ctx.getNumObservations());
        mutable_parameter_block_sizes()->push_back(ctx.getNumUnknowns());
    }
    bool Evaluate(double const* const* params, double* residuals, double** jacobians) const override {
        const int p = ctx_.getNumUnknowns(), n = ctx_.getNumObservations();
        const std::vector<double> z(params[0], params[0] + p);
        std::vector<double> r;
        if (!ctx_.calcResiduals(ctx_.map.fromScaled(z), r)) return false;
        for (int k = 0; k < n; ++k) residuals[k] = w_[k] * r[k];
        if (!jacobians || !jacobians[0]) return true;
        const std::vector<double> lo = ctx_.map.toScaled(ctx_.map.getLower());
        const std::vector<double> hi = ctx_.map.toScaled(ctx_.map.getUpper());
        std::vector<double> rPlus, rMinus;
        for (int j = 0; j < p; ++j) {
            const double h = step_ * std::max(1.0, std::abs(z[j]));
            std::vector<double> zp = z, zm = z;
            zp[j] = std::min(z[j] + h, hi[j]);
            zm[j] = std::max(z[j] - h, lo[j]);
            const bool plusSide = zp[j] > z[j], minusSide = zm[j] < z[j];
            if (plusSide && !ctx_.calcResiduals(ctx_.map.fromScaled(zp), rPlus)) return false;
            if (minusSide && !ctx_.calcResiduals(ctx_.map.fromScaled(zm), rMinus)) return false;
            if (!plusSide) rPlus = r;
            if (!minusSide) rMinus = r;
            for (int k = 0; k < n; ++k) jacobians[0][k * p + j] = w_[k] * (rPlus[k] - rMinus[k]) / (zp[j] - zm[j]);
        }
        return true;
    }

private:
    SolverContext& ctx_;
    std::vector<double> w_;
    double step_;
};

/// The same residuals for Ceres's own numeric differentiation.
struct ForceResidual {
    SolverContext* ctx;
    std::vector<double> w;
    bool operator()(double const* const* params, double* residuals) const {
        const std::vector<double> z(params[0], params[0] + ctx->getNumUnknowns());
        std::vector<double> r;
        if (!ctx->calcResiduals(ctx->map.fromScaled(z), r)) return false;
        for (std::size_t k = 0; k < r.size(); ++k) residuals[k] = w[k] * r[k];
        return true;
    }
};

/// Records the history after every Ceres iteration (points already evaluated: served from the cache).
class HistoryCallback : public ceres::IterationCallback {
public:
    HistoryCallback(SolverContext& ctx, const std::vector<double>& z) : ctx_(ctx), z_(z) {}
    ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
        if (getInterruption()) return ceres::SOLVER_ABORT;   // Ctrl-C: runFrom throws after the solve
        if (s.iteration == 0 || s.step_is_successful) {
            std::vector<double> r;
            const std::vector<double> x = ctx_.map.fromScaled(z_);
            if (ctx_.calcResiduals(x, r)) ctx_.record(s.iteration, x, r);
        }
        return ceres::SOLVER_CONTINUE;
    }

private:
    SolverContext& ctx_;
    const std::vector<double>& z_;
};

struct Run {
    std::vector<double> z;
    ceres::Solver::Summary summary;
    std::vector<IterationRecord> history;
    double cost = std::numeric_limits<double>::infinity();
    std::unique_ptr<ceres::Problem> problem;
};

Run runFrom(SolverContext& ctx, const std::vector<double>& xStart) {
    Run run;
    run.z = ctx.map.toScaled(xStart);
    ceres::Problem::Options po;
    run.problem = std::make_unique<ceres::Problem>(po);
    ceres::CostFunction* cost = nullptr;
    if (ctx.options.derivatives == Derivatives::Central) {
        cost = new ForceCostFunction(ctx);
    } else {
        ceres::NumericDiffOptions nd;
        nd.relative_step_size = getDifferenceStep(ctx);
        auto* numeric = new ceres::DynamicNumericDiffCostFunction<ForceResidual, ceres::CENTRAL>(
            new ForceResidual{&ctx, calcWeights(ctx)}, ceres::TAKE_OWNERSHIP, nd);
        numeric->AddParameterBlock(ctx.getNumUnknowns());
        numeric->SetNumResiduals(ctx.getNumObservations());
        cost = numeric;
    }
    run.problem->AddResidualBlock(cost, nullptr, run.z.data());
    const std::vector<double> lo = ctx.map.toScaled(ctx.map.getLower());
    const std::vector<double> hi = ctx.map.toScaled(ctx.map.getUpper());
    for (int j = 0; j < ctx.getNumUnknowns(); ++j) {
        run.problem->SetParameterLowerBound(run.z.data(), j, lo[j]);
        run.problem->SetParameterUpperBound(run.z.data(), j, hi[j]);
    }
    HistoryCallback callback(ctx, run.z);
    ceres::Solver::Options so;
    so.minimizer_type = ceres::TRUST_REGION;
    so.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
    so.linear_solver_type = ceres::DENSE_QR;
    so.max_num_iterations = ctx.options.maxIterations;
    so.function_tolerance = 1e-14;
    so.gradient_tolerance = 1e-14;
    so.parameter_tolerance = getParameterTolerance(ctx);
    // No projected line search after each step (Ceres's default for bounded problems): it evaluates the
    // Jacobian at every trial step size, 2p extra model runs each, and the bounds are still enforced by
    // projecting the step. Measured on five angles: steady lm 35 -> 20 evaluations, faithful 35 -> 20.
    so.max_num_line_search_step_size_iterations = 0;
    so.num_threads = 1;
    so.logging_type = ceres::SILENT;
    so.minimizer_progress_to_stdout = false;
    so.update_state_every_iteration = true;
    so.callbacks.push_back(&callback);
    ceres::Solve(so, run.problem.get(), &run.summary);
    checkInterruption();   // Ctrl-C: HistoryCallback aborted the solve
    run.history = ctx.takeHistory();
    std::vector<double> r;
    if (ctx.calcResiduals(ctx.map.fromScaled(run.z), r)) run.cost = calcWeightedCost(r, calcWeights(ctx));
    return run;
}

void addUncertainty(SolverContext& ctx, Run& run, const std::vector<double>& r, IdentificationReport& report) {
    const int p = ctx.getNumUnknowns(), n = ctx.getNumObservations();
    const IdentificationOptions& o = ctx.options;
    report.degreesOfFreedom = n - p;
    const bool relative = o.noise == NoiseModel::Relative;
    const double givenSd = relative ? o.relativeForceSd : o.forceSd;
    const std::string unit = relative ? " (relative)" : " N";
    double variance = 0;
    if (!std::isnan(givenSd)) {
        variance = givenSd * givenSd;
        report.residualSd = givenSd;
        report.intervalQuantile = calcNormalQuantile(0.5 + 0.5 * o.confidenceLevel);
        report.uncertaintyNote = "covariance (J^T J)^-1 sd^2 with the given " + getNoiseModelName(o.noise) +
                                 " force sd " + formatNumber(givenSd, 8) + unit + "; normal quantile";
    } else if (n > p) {
        variance = 2.0 * calcWeightedCost(r, calcWeights(ctx)) / (n - p);
        report.residualSd = std::sqrt(variance);
        report.intervalQuantile = calcStudentTQuantile(0.5 + 0.5 * o.confidenceLevel, n - p);
        report.uncertaintyNote = "covariance (J^T J)^-1 s^2, s^2 = SSR/(n - p) with n - p = " +
                                 std::to_string(n - p) + ", " + getNoiseModelName(o.noise) +
                                 " noise model; Student-t quantile";
    } else {
        report.uncertaintyNote = "no intervals: as many observations as unknowns (n = p = " + std::to_string(n) +
                                 ") leave no residual to estimate the noise; give the measurement's force sd "
                                 "(armsim identify --force-sd; IdentificationOptions::forceSd) to get them";
        return;
    }
    quietCeresLogging();  // a rank-deficient covariance is reported in uncertaintyNote, not on stderr
    ceres::Covariance::Options co;
    co.algorithm_type = ceres::DENSE_SVD;
    co.num_threads = 1;
    ceres::Covariance covariance(co);
    const std::vector<std::pair<const double*, const double*>> blocks = {{run.z.data(), run.z.data()}};
    if (!covariance.Compute(blocks, run.problem.get())) {
        report.uncertaintyNote = "no intervals: the Jacobian is rank deficient at the estimate (an unknown is not "
                                 "identifiable from these data)";
        return;
    }
    std::vector<double> c(p * p);
    covariance.GetCovarianceBlock(run.z.data(), run.z.data(), c.data());
    const std::vector<double> s = ctx.map.getScale();
    report.covariance.assign(p, std::vector<double>(p));
    report.correlation.assign(p, std::vector<double>(p));
    for (int i = 0; i < p; ++i)
        for (int j = 0; j < p; ++j) report.covariance[i][j] = c[i * p + j] * s[i] * s[j] * variance;
    for (int i = 0; i < p; ++i)
        for (int j = 0; j < p; ++j)
            report.correlation[i][j] =
                report.covariance[i][j] / std::sqrt(report.covariance[i][i] * report.covariance[j][j]);
    report.hasUncertainty = true;
}

}  // namespace

SolverOutcome solveLeastSquares(SolverContext& ctx, IdentificationReport& report) {
    const int p = ctx.getNumUnknowns(), n = ctx.getNumObservations();
    auto rng = PortableRandom::fromSeed(ctx.options.seed);
    const std::vector<double> lo = ctx.map.getLower(), hi = ctx.map.getUpper();
    Run best;
    int iterations = 0;
    for (int s = 0; s < ctx.options.starts; ++s) {
        std::vector<double> x0 = ctx.map.getStart();
        if (s > 0)
            for (int j = 0; j < p; ++j) x0[j] = rng.drawUniform(lo[j], hi[j]);
        Run run = runFrom(ctx, x0);
        iterations += int(run.summary.iterations.size()) - 1;
        report.startCosts.push_back(run.cost);
        if (s == 0 || run.cost < best.cost) best = std::move(run);
        if (ctx.options.progress && ctx.options.starts > 1) ctx.options.progress(s + 1, ctx.options.starts);
    }

    SolverOutcome out;
    out.x = ctx.map.fromScaled(best.z);
    out.iterations = iterations;
    report.history = best.history;
    if (!ctx.calcResiduals(out.x, out.r)) {
        out.r.clear();
        out.message = "Ceres: " + best.summary.message + "; the model fails at the end point: " + ctx.getLastFailure();
        return out;
    }
    const std::string starts = ctx.options.starts > 1 ? " (best of " + std::to_string(ctx.options.starts) + " starts)" : "";
    switch (best.summary.termination_type) {
        case ceres::CONVERGENCE:
            out.reason = StopReason::Converged;
            out.message = "Ceres: " + best.summary.message + starts;
            break;
        case ceres::NO_CONVERGENCE:
            out.reason = StopReason::MaxIterations;
            out.message = "Ceres: " + best.summary.message + starts;
            break;
        default:
            out.reason = StopReason::NotConverged;
            out.message = "Ceres failed: " + best.summary.message + starts;
            break;
    }
    if (out.reason == StopReason::Converged && n == p && !ctx.isReproduced(out.r))
        out.reason = StopReason::NotConverged, out.message =
            "least-squares minimum with forces not reproduced within " + formatNumber(ctx.options.forceTolerance, 8) +
            " N (rms " + formatNumber(std::sqrt(2.0 * calcCost(out.r) / n), 8) +
            " N) although there are as many observations as unknowns: the model cannot produce these "
            "forces, or this is a local minimum (try more starts); " + out.message;
    addUncertainty(ctx, best, out.r, report);
    if (report.hasUncertainty) {
        const auto& u = ctx.map.getUnknowns();
        for (int j = 0; j < p; ++j) {
            const double x = out.x[j];
            if (x <= u[j].lower + u[j].tolerance || x >= u[j].upper - u[j].tolerance)
                report.uncertaintyNote += "; " + getParameterName(u[j].id) +
                                          " is at a bound: its interval assumes an unconstrained optimum";
        }
    }
    return out;
}

}  // namespace armsim::detail
