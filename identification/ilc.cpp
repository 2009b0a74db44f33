// Iterative learning identification (thesis 4.6, 7.1, 7.2): x_{i+1} = x_i + G_i (y_d - y_i).
// How G_i is built for each variant is documented in identifier.h.
#include "basics/format.h"
#include "identification/solver_context.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace armsim::detail {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

VectorXd toEigen(const std::vector<double>& v) { return Eigen::Map<const VectorXd>(v.data(), Eigen::Index(v.size())); }
std::vector<double> toStd(const VectorXd& v) { return {v.data(), v.data() + v.size()}; }

/// The learning loop shared by all variants: current point, its residuals and cost, the stall and
/// divergence bookkeeping, and the outcome.
class Learner {
public:
    explicit Learner(SolverContext& ctx) : ctx_(ctx), p_(ctx.getNumUnknowns()), n_(ctx.getNumObservations()) {
        scale_ = toEigen(ctx.map.getScale());
    }

    /// Evaluates the start; false (outcome set) when the model fails there.
    bool start() {
        x_ = ctx_.map.getStart();
        if (!ctx_.calcResiduals(x_, r_)) {
            out_.x = x_;
            out_.message = "the model failed at the start: " + ctx_.getLastFailure();
            return false;
        }
        cost_ = bestCost_ = startCost_ = calcCost(r_);
        ctx_.record(0, x_, r_);
        return true;
    }

    /// True (outcome set) when the forces are reproduced.
    bool done(int it) {
        out_.iterations = it;
        if (!ctx_.isReproduced(r_)) return false;
        finish(StopReason::Converged, "every force within " + formatNumber(ctx_.options.forceTolerance, 8) + " N after " +
                                          std::to_string(it) + " iterations");
        return true;
    }

    /// Moves to x (already evaluated, residuals r) and checks for stalling; false (outcome set) to stop.
    bool accept(int it, const std::vector<double>& x, const std::vector<double>& r) {
        const bool moved = x != x_;
        x_ = x, r_ = r, cost_ = calcCost(r);
        ctx_.record(it, x_, r_);
        if (cost_ < bestCost_ * (1.0 - 1e-12)) {
            bestCost_ = cost_;
            stall_ = 0;
        } else if (++stall_ >= ctx_.options.stallIterations || !moved) {
            out_.iterations = it;
            finish(StopReason::NoProgress,
                   !moved ? "the update no longer moves the parameters (a fixed point of the learning law, or "
                            "held at a bound); forces not reproduced"
                          : "cost not reduced for " + std::to_string(stall_) +
                                " iterations; forces not reproduced (the gain cannot reduce these errors)");
            return false;
        }
        if (!std::isfinite(cost_) || cost_ > 1e6 * (1.0 + startCost_)) {
            out_.iterations = it;
            finish(StopReason::NotConverged, "diverging: cost " + formatNumber(cost_, 8) + " N^2");
            return false;
        }
        return true;
    }

    /// Evaluates a trial; false when the model fails there.
    bool trial(const std::vector<double>& x, std::vector<double>& r) { return ctx_.calcResiduals(x, r); }

    void stop(int it, StopReason reason, const std::string& why) {
        out_.iterations = it;
        finish(reason, why);
    }
    void fail(int it, const std::string& why) { stop(it, StopReason::NotConverged, why); }

    SolverOutcome outcome(int maxIterations) {
        if (out_.x.empty()) {
            out_.iterations = maxIterations;
            finish(StopReason::MaxIterations, "forces not reproduced within " + formatNumber(ctx_.options.forceTolerance, 8) +
                                                  " N after " + std::to_string(maxIterations) + " iterations");
        }
        return out_;
    }

    /// Error e = y_d - y = -r.
    VectorXd error() const { return -toEigen(r_); }
    const std::vector<double>& x() const { return x_; }
    const std::vector<double>& r() const { return r_; }
    double cost() const { return cost_; }
    const VectorXd& scale() const { return scale_; }
    int p() const { return p_; }
    int n() const { return n_; }
    SolverContext& ctx() const { return ctx_; }

private:
    void finish(StopReason reason, const std::string& message) {
        out_.x = x_;
        out_.r = r_;
        out_.reason = reason;
        out_.message = message;
    }
    SolverContext& ctx_;
    int p_, n_;
    VectorXd scale_;
    std::vector<double> x_, r_;
    double cost_ = 0, bestCost_ = 0, startCost_ = 0;
    int stall_ = 0;
    SolverOutcome out_;
};

/// Constant gain: ilc-standard (n = 1) and ilc-constant.
SolverOutcome solveConstantGain(SolverContext& ctx) {
    Learner L(ctx);
    if (!L.start()) return L.outcome(0);
    MatrixXd G(L.p(), L.n());
    const auto& unknowns = ctx.map.getUnknowns();
    for (int j = 0; j < L.p(); ++j)
        for (int k = 0; k < L.n(); ++k)
            G(j, k) = ctx.options.gainMatrix.empty() ? unknowns[j].gain : ctx.options.gainMatrix[j][k];
    std::vector<double> r;
    for (int it = 1; it <= ctx.options.maxIterations; ++it) {
        if (L.done(it - 1)) return L.outcome(0);
        const std::vector<double> x = ctx.map.project(toStd(toEigen(L.x()) + G * L.error()));
        if (!L.trial(x, r)) {
            L.fail(it, "the model failed at the next learning trial: " + ctx.getLastFailure());
            return L.outcome(0);
        }
        if (!L.accept(it, x, r)) return L.outcome(0);
    }
    L.done(ctx.options.maxIterations);
    return L.outcome(ctx.options.maxIterations);
}

/// Secant (Broyden) Jacobian estimate in scaled coordinates, Fz = dy/dz (n x p) [N].
class SecantJacobian {
public:
    /// p one-at-a-time learning trials (thesis eq. 7.3 with one parameter changed per trial).
    bool probe(Learner& L) {
        SolverContext& ctx = L.ctx();
        Fz_.resize(L.n(), L.p());
        const auto& u = ctx.map.getUnknowns();
        std::vector<double> r;
        for (int j = 0; j < L.p(); ++j) {
            std::vector<double> x = L.x();
            double h = ctx.options.probeStep * u[j].scale;
            if (x[j] + h > u[j].upper) h = -h;
            x[j] += h;
            if (!L.trial(x, r)) {
                x[j] = L.x()[j] - h;
                h = -h;
                if (!L.trial(x, r)) return false;
            }
            Fz_.col(j) = (toEigen(r) - toEigen(L.r())) / (h / u[j].scale);
        }
        return true;
    }
    /// Broyden's rank-1 update from the pair (x1 - x0, r1 - r0).
    void update(const Learner& L, const std::vector<double>& x0, const std::vector<double>& r0,
                const std::vector<double>& x1, const std::vector<double>& r1) {
        const VectorXd dz = (toEigen(x1) - toEigen(x0)).cwiseQuotient(L.scale());
        const double dd = dz.squaredNorm();
        if (!(dd > 1e-28)) return;
        const VectorXd dy = toEigen(r1) - toEigen(r0);
        Fz_ += (dy - Fz_ * dz) * dz.transpose() / dd;
    }
    /// G = S Fz^+ [unit/N], elements clipped to the unknowns' gain bounds when bounded.
    MatrixXd gain(const Learner& L, bool bounded) const {
        const MatrixXd pinv = Fz_.completeOrthogonalDecomposition().pseudoInverse();
        MatrixXd G = L.scale().asDiagonal() * pinv;
        if (bounded) {
            const auto& u = L.ctx().map.getUnknowns();
            for (int j = 0; j < G.rows(); ++j)
                for (int k = 0; k < G.cols(); ++k) {
                    const double s = G(j, k) < 0 ? -1.0 : 1.0;
                    G(j, k) = s * std::clamp(std::abs(G(j, k)), u[j].gainMin, u[j].gainMax);
                }
        }
        return G;
    }

private:
    MatrixXd Fz_;
};

/// ilc-secant and ilc-bounded-secant: plain steps with the secant gain.
SolverOutcome solveSecant(SolverContext& ctx, bool bounded) {
    Learner L(ctx);
    if (!L.start()) return L.outcome(0);
    SecantJacobian F;
    if (!F.probe(L)) {
        L.fail(0, "the model failed in the initial learning trials: " + ctx.getLastFailure());
        return L.outcome(0);
    }
    std::vector<double> r;
    for (int it = 1; it <= ctx.options.maxIterations; ++it) {
        if (L.done(it - 1)) return L.outcome(0);
        VectorXd step = F.gain(L, bounded) * L.error();
        std::vector<double> x;
        bool ok = false;
        for (int halvings = 0; halvings < 8 && !ok; ++halvings, step *= 0.5) {
            x = ctx.map.project(toStd(toEigen(L.x()) + step));
            ok = L.trial(x, r);
        }
        if (!ok) {
            L.fail(it, "the model failed at the next learning trial (step halved 8 times): " + ctx.getLastFailure());
            return L.outcome(0);
        }
        F.update(L, L.x(), L.r(), x, r);
        if (!L.accept(it, x, r)) return L.outcome(0);
    }
    L.done(ctx.options.maxIterations);
    return L.outcome(ctx.options.maxIterations);
}

/// ilc-sign-search: bounded secant magnitude, searched signs, best descent kept.
SolverOutcome solveSignSearch(SolverContext& ctx) {
    Learner L(ctx);
    if (!L.start()) return L.outcome(0);
    SecantJacobian F;
    if (!F.probe(L)) {
        L.fail(0, "the model failed in the initial learning trials: " + ctx.getLastFailure());
        return L.outcome(0);
    }
    const double lambda = ctx.options.lambda;
    double lambdaNow = lambda;
    std::vector<double> r;
    for (int it = 1; it <= ctx.options.maxIterations; ++it) {
        if (L.done(it - 1)) return L.outcome(0);
        const VectorXd magnitude = (lambdaNow * F.gain(L, true) * L.error()).cwiseAbs();
        std::vector<std::vector<double>> tried;
        std::vector<double> bestX, bestR;
        double bestCost = L.cost();
        const std::vector<double> x0 = L.x(), r0 = L.r();
        for (int signs = 0; signs < (1 << L.p()); ++signs) {
            VectorXd x = toEigen(x0);
            for (int j = 0; j < L.p(); ++j) x[j] += (signs >> j & 1 ? -1.0 : 1.0) * magnitude[j];
            const std::vector<double> xt = ctx.map.project(toStd(x));
            if (xt == x0 || std::find(tried.begin(), tried.end(), xt) != tried.end()) continue;
            tried.push_back(xt);
            if (!L.trial(xt, r)) continue;
            F.update(L, x0, r0, xt, r);
            if (calcCost(r) < bestCost) bestCost = calcCost(r), bestX = xt, bestR = r;
        }
        if (bestX.empty()) {
            lambdaNow *= 0.5;
            if (lambdaNow < 1e-10 * lambda) {
                L.stop(it, StopReason::NoProgress, "no sign combination descends even with the step shrunk to " + formatNumber(lambdaNow, 8) +
                              " lambda; forces not reproduced" +
                              (ctx.getLastFailure().empty() ? "" : " (last model failure: " + ctx.getLastFailure() + ")"));
                return L.outcome(0);
            }
            continue;
        }
        lambdaNow = lambda;
        if (!L.accept(it, bestX, bestR)) return L.outcome(0);
    }
    L.done(ctx.options.maxIterations);
    return L.outcome(ctx.options.maxIterations);
}

}  // namespace

SolverOutcome solveIlc(SolverContext& ctx) {
    switch (ctx.options.method) {
        case Method::IlcStandard:
        case Method::IlcConstant: return solveConstantGain(ctx);
        case Method::IlcSecant: return solveSecant(ctx, false);
        case Method::IlcBoundedSecant: return solveSecant(ctx, true);
        case Method::IlcSignSearch: return solveSignSearch(ctx);
        default: throw std::logic_error("solveIlc: not an ILC method");
    }
}

}  // namespace armsim::detail
