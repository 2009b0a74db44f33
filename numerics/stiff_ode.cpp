#include "numerics/stiff_ode.h"

#include "basics/bound.h"
#include "numerics/cpodes_c.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cstdio>
#include <cfloat>
#include <cmath>
#include <limits>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <regex>
#include <sstream>

namespace armsim {

void IntegrationSettings::validate() const {
    checkField("accuracy", accuracy, bounds::kAccuracy);
    checkField("max_step", maxStepSize, Bound::nonNegative("s"));
    if (maxStepSize > 0 && maxStepSize < kMinStepSize)
        checkField("max_step", maxStepSize, Bound{kMinStepSize, 1e300, false, false, "s, 0 or at least the 1e-12 s minimum step"});
}

namespace {
std::string shortNumber(double v) {   // 3 significant digits, for a message
    char text[32];
    std::snprintf(text, sizeof text, "%.3g", v);
    return text;
}
}  // namespace

SampleCountError::SampleCountError(double duration, double sampleRate, std::string detail)
    : InputError("duration " + formatNumber(duration) + " s x sample_rate " + formatNumber(sampleRate) + " Hz " + detail),
      duration_(duration), sampleRate_(sampleRate), detail_(std::move(detail)) {}

long calcNumSamples(double duration, double sampleRate) {
    const double n = std::round(duration * sampleRate) + 1;
    if (duration > 0 && duration * sampleRate < 1 - 1e-9)   // no sample after the start: its end silently dropped
        throw SampleCountError(duration, sampleRate,
                               "= " + formatNumber(std::stod(shortNumber(duration * sampleRate))) +
                                   " samples after the start: expected at least one (raise the sample rate to " +
                                   shortNumber(1 / duration) + " Hz or more)");
    if (!(n <= kMaxSamples))
        throw SampleCountError(duration, sampleRate,
                               "= " + formatNumber(n) + " samples: expected at most " + formatNumber(kMaxSamples) +
                                   " (lower the sample rate or the duration)");
    return long(n);
}

namespace detail {

SampledRun::SampledRun(double t0, double duration, double sampleRate, const std::vector<double>& breakpoints,
                       int size)
    : t0_(t0), tEnd_(t0 + duration), rate_(sampleRate), eps_(1e-9 / sampleRate),
      numSamples_(calcNumSamples(duration, sampleRate)), ya_(size), yda_(size), y_(size) {
    for (double b : breakpoints)
        if (b > t0 + eps_ && b < tEnd_ - eps_) cuts_.push_back(b);
    std::sort(cuts_.begin(), cuts_.end());
    cuts_.erase(std::unique(cuts_.begin(), cuts_.end()), cuts_.end());
    cuts_.push_back(tEnd_);
}

void SampledRun::restart(double ta, const double* ya, const double* yda) {
    ta_ = ta;
    std::copy(ya, ya + ya_.size(), ya_.begin());
    std::copy(yda, yda + yda_.size(), yda_.begin());
}

void SampledRun::advance(double tb, const double* yb, const double* ydb, bool atBreakpoint, const OdeVisitor& emit) {
    const double h = tb - ta_;
    const std::size_t n = y_.size();
    while (next_ < numSamples_ && sampleTime(next_) <= tb + eps_) {
        const double t = std::min(sampleTime(next_), tb);
        const double s = h > 0 ? (t - ta_) / h : 1.0;
        double c0, c1, c2, c3;  // weights of ya, h*yda, yb, h*ydb
        if (!atBreakpoint) {
            c0 = (1 + 2 * s) * (1 - s) * (1 - s);
            c1 = s * (1 - s) * (1 - s);
            c2 = s * s * (3 - 2 * s);
            c3 = s * s * (s - 1);
        } else {
            c0 = 1 - s * s;
            c1 = s * (1 - s);
            c2 = s * s;
            c3 = 0;
        }
        for (std::size_t i = 0; i < n; ++i) y_[i] = c0 * ya_[i] + c1 * h * yda_[i] + c2 * yb[i] + c3 * h * ydb[i];
        emit(t, y_.data());
        ++next_;
    }
    restart(tb, yb, ydb);
}

}  // namespace detail

namespace {

void checkFinite(double t, const double* y, int n) {
    for (int i = 0; i < n; ++i)
        if (!std::isfinite(y[i])) {
            std::ostringstream msg;
            msg << "t = " << t << " s: state y[" << i << "] is " << y[i] << " (not finite)";
            throw SimulationError(msg.str());
        }
}

// What CPODES calls back: f, counted, and its diagnostics. A throwing f becomes a recoverable error
// (CPODES cuts the step), as in Simbody's CPodesIntegrator; the last message is kept for the report
// if CPODES gives up. With blocks, a call that differs from the last full evaluation (same t) in one
// block evaluates only that block.
class RhsContext {
public:
    RhsContext(const OdeRhs& f, const OdeBlocks* blocks, int n) : f_(f), blocks_(blocks) {
        if (blocks_) {
            baseY_.resize(n);
            baseYdot_.resize(n);
        }
    }
    int getNumEvaluations() const { return count_; }
    int getNumPartialEvaluations() const { return partial_; }
    const std::string& getLastError() const { return lastError_; }
    void clearLastError() { lastError_.clear(); }
    const std::string& getSolverMessage() const { return solverMessage_; }
    /// f(t, y, ydot), counted; nonzero when f failed (a recoverable error for CPODES).
    int tryEvaluate(double t, const double* y, double* ydot) { return calc(t, y, ydot); }
    /// f(t, y, ydot); throws SimulationError naming t if f fails.
    void evaluate(double t, const double* y, double* ydot) {
        if (calc(t, y, ydot) != 0) throw SimulationError("t = " + formatNumber(t) + " s: " + lastError_);
    }
    /// CPDlsBandJacExplFn: each block's Jacobian from calcBlockJacobian (or its difference quotients).
    static int calcBandJacobian(int n, int, int, double t, cpodes::NVector y, cpodes::NVector fy, cpodes::DlsMat J,
                                void* context, cpodes::NVector, cpodes::NVector, cpodes::NVector) {
        return static_cast<RhsContext*>(context)->fillJacobian(n, t, cpodes::ArrayVector::updData(y),
                                                               cpodes::ArrayVector::updData(fy), J, true);
    }
    /// CPDlsDenseJacExplFn: the same into a dense matrix (a band as wide as the system).
    static int calcDenseJacobian(int n, double t, cpodes::NVector y, cpodes::NVector fy, cpodes::DlsMat J,
                                 void* context, cpodes::NVector, cpodes::NVector, cpodes::NVector) {
        return static_cast<RhsContext*>(context)->fillJacobian(n, t, cpodes::ArrayVector::updData(y),
                                                               cpodes::ArrayVector::updData(fy), J, false);
    }
    int getNumJacobians() const { return jacobians_; }
    bool hasBlockJacobian() const { return blocks_ && blocks_->banded && blocks_->calcBlockJacobian; }
    static int calcRhs(double t, cpodes::NVector y, cpodes::NVector ydot, void* context) {
        return static_cast<RhsContext*>(context)->calc(t, cpodes::ArrayVector::updData(y),
                                                       cpodes::ArrayVector::updData(ydot));
    }
    // CPODES' own diagnostics: kept for the exception rather than printed to stderr. Its messages
    // start "At t = <t>" glued to the text; the time is reported by the caller.
    static void handleError(int, const char*, const char*, char* msg, void* context) {
        static const std::regex timePrefix("^At t = [-+0-9.eE]+,? *");
        static_cast<RhsContext*>(context)->solverMessage_ = std::regex_replace(std::string(msg), timePrefix, "");
    }

private:
    int fillJacobian(int n, double t, const double* y, const double* fy, cpodes::DlsMat J, bool band) {
        ++jacobians_;
        try {
            std::fill(J->data, J->data + std::size_t(J->ldim) * std::size_t(n), 0.0);
            const int offset = band ? J->s_mu : 0;   // entry (i, j): cols[j][i - j + s_mu] or cols[j][i]
            bool haveWork = false;   // differenceBlock's copies of y and fy, made once
            for (int b = 0; b < int(blocks_->first.size()); ++b) {
                const int first = blocks_->first[b], m = blocks_->size[b];
                blockJ_.assign(std::size_t(m) * std::size_t(m), 0.0);
                if (!blocks_->calcBlockJacobian(b, t, y, blockJ_.data())) {
                    if (!haveWork) {
                        work_.assign(y, y + n);
                        workDot_.assign(fy, fy + n);
                        haveWork = true;
                    }
                    differenceBlock(b, t, fy);
                }
                for (int i = 0; i < m; ++i)
                    for (int j = 0; j < m; ++j)
                        J->cols[first + j][band ? i - j + offset : first + i] =
                            blockJ_[std::size_t(i) * std::size_t(m) + std::size_t(j)];
            }
        } catch (const std::exception& e) {
            lastError_ = e.what();
            return 1;   // recoverable: CPODES retries with a smaller step
        }
        return 0;
    }
    // Forward difference quotients of block b into blockJ_ (a model without an analytic Jacobian), from
    // work_ = y and workDot_ = fy outside the block (calcBlock writes block b's entries only; work_ is
    // restored after each column).
    void differenceBlock(int b, double t, const double* fy) {
        const int first = blocks_->first[b], m = blocks_->size[b];
        for (int j = 0; j < m; ++j) {
            const double yj = work_[std::size_t(first + j)], h = std::sqrt(std::numeric_limits<double>::epsilon()) * std::max(1.0, std::abs(yj));
            work_[std::size_t(first + j)] = yj + h;
            blocks_->calcBlock(b, t, work_.data(), workDot_.data());
            for (int i = 0; i < m; ++i)
                blockJ_[std::size_t(i) * std::size_t(m) + std::size_t(j)] = (workDot_[std::size_t(first + i)] - fy[first + i]) / h;
            work_[std::size_t(first + j)] = yj;
        }
    }
    int calc(double t, const double* y, double* ydot) {
        ++count_;
        try {
            if (!blocks_) {
                f_(t, y, ydot);
            } else if (!calcFromBase(t, y, ydot)) {
                hasBase_ = false;
                f_(t, y, ydot);
                baseT_ = t;
                std::copy(y, y + baseY_.size(), baseY_.begin());
                std::copy(ydot, ydot + baseYdot_.size(), baseYdot_.begin());
                hasBase_ = true;
            }
        } catch (const std::exception& e) {
            lastError_ = e.what();
            return 1;  // recoverable
        } catch (...) {
            lastError_ = "unknown exception";
            return 1;
        }
        return 0;
    }
    // ydot from the last full evaluation and the blocks in which y differs from it, at the same t
    // (bitwise: a block function may tell -0 from +0); false when every block differs.
    bool calcFromBase(double t, const double* y, double* ydot) {
        if (!hasBase_ || t != baseT_) return false;
        const int numBlocks = int(blocks_->first.size());
        changed_.clear();
        for (int b = 0; b < numBlocks; ++b) {
            const std::size_t first = std::size_t(blocks_->first[b]), bytes = sizeof(double) * blocks_->size[b];
            if (std::memcmp(y + first, &baseY_[first], bytes) != 0) changed_.push_back(b);
        }
        if (numBlocks > 1 && int(changed_.size()) == numBlocks) return false;
        std::copy(baseYdot_.begin(), baseYdot_.end(), ydot);
        for (int b : changed_) blocks_->calcBlock(b, t, y, ydot);
        ++partial_;
        return true;
    }
    const OdeRhs& f_;
    const OdeBlocks* blocks_;
    int count_ = 0, partial_ = 0, jacobians_ = 0;
    std::vector<double> blockJ_, work_, workDot_;
    bool hasBase_ = false;
    double baseT_ = 0;
    std::vector<double> baseY_, baseYdot_;  // the last full evaluation
    std::vector<int> changed_;
    std::string lastError_, solverMessage_;
};

// Newton's systems (I - gamma J) x = b of an arrow-structured J (OdeArrow), for CPODES' Krylov solver:
// setup() builds J by CPODES' difference quotients (when CPODES asks for a fresh one) and factors
// P = I - gamma J as block LUs and the coupled states' Schur complement; solve() applies P^-1 and
// multiply() J: with the same J in both, GMRES converges in one iteration.
class ArrowSolver {
public:
    ArrowSolver(const OdeArrow& f, RhsContext& context, int n) : context_(context), nc_(f.numCoupled), n_(n) {
        first_ = f.first;
        size_ = f.size;
        const int nb = int(first_.size());
        Jcc_.setZero(nc_, nc_);
        Jcb_.resize(nb);
        Jbc_.resize(nb);
        Jbb_.resize(nb);
        lu_.resize(nb);
        DinvAbc_.resize(nb);
        DinvB_.resize(nb);
        for (int b = 0; b < nb; ++b) {
            Jcb_[b].setZero(nc_, size_[b]);
            Jbc_[b].setZero(size_[b], nc_);
            Jbb_[b].setZero(size_[b], size_[b]);
        }
        yWork_.resize(n);
        fWork_.resize(n);
        ewt_.resize(n);
        owner_.assign(n, -1);
        for (int b = 0; b < nb; ++b)
            for (int i = first_[b]; i < first_[b] + size_[b]; ++i) owner_[i] = b;
    }
    void setCpodes(void* mem) { mem_ = mem; }

    static int setupCallback(double t, cpodes::NVector y, cpodes::NVector fy, cpodes::booleantype jok,
                             cpodes::booleantype* jcurPtr, double gamma, void* data, cpodes::NVector,
                             cpodes::NVector, cpodes::NVector) {
        auto* self = static_cast<ArrowSolver*>(data);
        if (!jok) {
            const int r = self->calcJacobian(t, cpodes::ArrayVector::updData(y), cpodes::ArrayVector::updData(fy));
            if (r != 0) return r;
            *jcurPtr = 1;
        } else {
            *jcurPtr = 0;
        }
        return self->factor(gamma) ? 0 : 1;   // singular: recoverable (CPODES cuts the step)
    }
    static int solveCallback(double, cpodes::NVector, cpodes::NVector, cpodes::NVector b, cpodes::NVector x, double,
                             double, int, void* data, cpodes::NVector) {
        static_cast<ArrowSolver*>(data)->solve(cpodes::ArrayVector::updData(b), cpodes::ArrayVector::updData(x));
        return 0;
    }
    static int multiplyCallback(double, cpodes::NVector, cpodes::NVector, cpodes::NVector v, cpodes::NVector Jv,
                                void* data, cpodes::NVector) {
        static_cast<ArrowSolver*>(data)->multiply(cpodes::ArrayVector::updData(v), cpodes::ArrayVector::updData(Jv));
        return 0;
    }

private:
    // CPODES' dense difference quotients (cpDlsDenseDQJacExpl): column j from f(y + inc e_j), inc =
    // max(sqrt(uround) |y_j|, minInc / ewt_j), minInc from the step and the weighted norm of f.
    int calcJacobian(double t, const double* y, const double* fy) {
        std::vector<double>& ewt = ewt_;
        cpodes::ArrayVector ewtv(n_, ewt.data());
        cpodes::CPodeGetErrWeights(mem_, &ewtv);
        double h = 0;
        cpodes::CPodeGetCurrentStep(mem_, &h);
        double fnorm = 0;
        for (int i = 0; i < n_; ++i) fnorm += (fy[i] * ewt[i]) * (fy[i] * ewt[i]);
        fnorm = std::sqrt(fnorm / n_);
        const double uround = DBL_EPSILON, srur = std::sqrt(uround);
        const double minInc = fnorm != 0 ? 1000 * std::abs(h) * uround * n_ * fnorm : 1.0;
        std::copy(y, y + n_, yWork_.begin());
        for (int j = 0; j < n_; ++j) {
            const double yj = yWork_[j];
            const double inc = std::max(srur * std::abs(yj), minInc / ewt[j]);
            yWork_[j] = yj + inc;
            const int r = context_.tryEvaluate(t, yWork_.data(), fWork_.data());
            yWork_[j] = yj;
            if (r != 0) return r;
            const double invInc = 1 / inc;
            const int bj = owner_[j];
            // Rows of the coupled states, then of the block(s) the column may reach.
            for (int i = 0; i < nc_; ++i) {
                const double d = (fWork_[i] - fy[i]) * invInc;
                if (bj < 0) Jcc_(i, j) = d;
                else Jcb_[bj](i, j - first_[bj]) = d;
            }
            if (bj < 0) {
                for (std::size_t b = 0; b < first_.size(); ++b)
                    for (int i = 0; i < size_[b]; ++i)
                        Jbc_[b](i, j) = (fWork_[first_[b] + i] - fy[first_[b] + i]) * invInc;
            } else {
                for (int i = 0; i < size_[bj]; ++i)
                    Jbb_[bj](i, j - first_[bj]) = (fWork_[first_[bj] + i] - fy[first_[bj] + i]) * invInc;
            }
        }
        return 0;
    }
    bool factor(double gamma) {
        Eigen::MatrixXd S = Eigen::MatrixXd::Identity(nc_, nc_) - gamma * Jcc_;
        for (std::size_t b = 0; b < first_.size(); ++b) {
            const Eigen::MatrixXd D = Eigen::MatrixXd::Identity(size_[b], size_[b]) - gamma * Jbb_[b];
            lu_[b].compute(D);
            if (!(std::abs(lu_[b].determinant()) > 0)) return false;
            DinvAbc_[b] = lu_[b].solve(-gamma * Jbc_[b]);
            S -= (-gamma * Jcb_[b]) * DinvAbc_[b];
        }
        gamma_ = gamma;
        if (nc_ > 0) {
            schur_.compute(S);
            if (!(std::abs(schur_.determinant()) > 0)) return false;
        }
        return true;
    }
    // x = P^-1 b: x_c = S^-1 (b_c - sum A_cb D^-1 b_b), x_b = D^-1 b_b - D^-1 A_bc x_c.
    void solve(const double* b, double* x) {
        rhsC_ = Eigen::Map<const Eigen::VectorXd>(b, nc_);
        for (std::size_t k = 0; k < first_.size(); ++k) {
            DinvB_[k] = lu_[k].solve(Eigen::Map<const Eigen::VectorXd>(b + first_[k], size_[k]));
            rhsC_ -= (-gamma_ * Jcb_[k]) * DinvB_[k];
        }
        Eigen::Map<Eigen::VectorXd> xc(x, nc_);
        if (nc_ > 0) xc = schur_.solve(rhsC_);
        for (std::size_t k = 0; k < first_.size(); ++k) {
            Eigen::Map<Eigen::VectorXd> xb(x + first_[k], size_[k]);
            xb = DinvB_[k];
            if (nc_ > 0) xb -= DinvAbc_[k] * xc;
        }
    }
    void multiply(const double* v, double* Jv) {
        const Eigen::Map<const Eigen::VectorXd> vc(v, nc_);
        Eigen::Map<Eigen::VectorXd> Jvc(Jv, nc_);
        Jvc = Jcc_ * vc;
        for (std::size_t k = 0; k < first_.size(); ++k) {
            const Eigen::Map<const Eigen::VectorXd> vb(v + first_[k], size_[k]);
            Jvc += Jcb_[k] * vb;
            Eigen::Map<Eigen::VectorXd> Jvb(Jv + first_[k], size_[k]);
            Jvb = Jbb_[k] * vb + Jbc_[k] * vc;
        }
    }

    RhsContext& context_;
    void* mem_ = nullptr;
    int nc_, n_;
    std::vector<int> first_, size_, owner_;
    Eigen::MatrixXd Jcc_;
    std::vector<Eigen::MatrixXd> Jcb_, Jbc_, Jbb_;
    std::vector<Eigen::MatrixXd> DinvAbc_;   // of the last factor(): D^-1 (-gamma Jbc)
    double gamma_ = 0;                       // and its gamma
    std::vector<Eigen::PartialPivLU<Eigen::MatrixXd>> lu_;
    Eigen::PartialPivLU<Eigen::MatrixXd> schur_;
    std::vector<Eigen::VectorXd> DinvB_;   // solve()'s workspace
    Eigen::VectorXd rhsC_;
    std::vector<double> yWork_, fWork_, ewt_;
};

// One CPODES run (a segment between breakpoints), configured as Simbody's CPodesIntegrator configures
// its CPodes: BDF, Newton, dense LAPACK Jacobian by CPODES' difference quotients (or, with a half
// bandwidth >= 0, a LAPACK band Jacobian by CPODES' grouped difference quotients).
class Cpodes {
public:
    Cpodes(RhsContext& context, double t0, std::vector<double>& y0, std::vector<double>& yp0, double relTol,
           double absTol, const IntegrationSettings& settings, int halfBandwidth, ArrowSolver* arrow = nullptr)
        : mem_(cpodes::CPodeCreate(cpodes::CP_EXPL, cpodes::CP_BDF, cpodes::CP_NEWTON)), absTol_(absTol) {
        if (!mem_) throw std::bad_alloc();
        try {
            const int n = int(y0.size());
            cpodes::ArrayVector y(n, y0.data()), yp(n, yp0.data());
            check(cpodes::CPodeInit(mem_, reinterpret_cast<void*>(&RhsContext::calcRhs), &context, t0, &y, &yp,
                                    cpodes::CP_SS, relTol, &absTol_),
                  "CPodeInit", t0);
            check(cpodes::CPodeSetErrHandlerFn(mem_, &RhsContext::handleError, &context), "CPodeSetErrHandlerFn",
                  t0);
            if (arrow) {
                krylov_ = true;
                arrow->setCpodes(mem_);
                check(cpodes::CPSpgmr(mem_, cpodes::PREC_LEFT, 5), "CPSpgmr", t0);
                check(cpodes::CPSpilsSetPreconditioner(
                          mem_, reinterpret_cast<void*>(cpodes::CPSpilsPrecSetupExplFn(&ArrowSolver::setupCallback)),
                          reinterpret_cast<void*>(cpodes::CPSpilsPrecSolveExplFn(&ArrowSolver::solveCallback)), arrow),
                      "CPSpilsSetPreconditioner", t0);
                check(cpodes::CPSpilsSetJacTimesVecFn(
                          mem_, reinterpret_cast<void*>(cpodes::CPSpilsJacTimesVecExplFn(&ArrowSolver::multiplyCallback)),
                          arrow),
                      "CPSpilsSetJacTimesVecFn", t0);
            } else if (halfBandwidth < 0) {
                check(cpodes::CPLapackDense(mem_, n), "CPLapackDense", t0);
                if (context.hasBlockJacobian())
                    check(cpodes::CPDlsSetJacFn(mem_, reinterpret_cast<void*>(&RhsContext::calcDenseJacobian), &context),
                          "CPDlsSetJacFn", t0);
            } else {
                check(cpodes::CPLapackBand(mem_, n, halfBandwidth, halfBandwidth), "CPLapackBand", t0);
                if (context.hasBlockJacobian())
                    check(cpodes::CPDlsSetJacFn(mem_, reinterpret_cast<void*>(&RhsContext::calcBandJacobian), &context),
                          "CPDlsSetJacFn", t0);
            }
            check(cpodes::CPodeSetNonlinConvCoef(mem_, 0.01), "CPodeSetNonlinConvCoef", t0);
            check(cpodes::CPodeSetMinStep(mem_, IntegrationSettings::kMinStepSize), "CPodeSetMinStep", t0);
            if (settings.maxStepSize > 0)
                check(cpodes::CPodeSetMaxStep(mem_, settings.maxStepSize), "CPodeSetMaxStep", t0);
        } catch (...) {
            cpodes::CPodeFree(&mem_);
            throw;
        }
    }
    Cpodes(const Cpodes&) = delete;
    Cpodes& operator=(const Cpodes&) = delete;
    ~Cpodes() { cpodes::CPodeFree(&mem_); }
    /// One internal step towards tout; CPODES' flag.
    int step(double tout, double* tret, std::vector<double>& y, std::vector<double>& yp) {
        cpodes::ArrayVector yv(long(y.size()), y.data()), ypv(long(yp.size()), yp.data());
        return cpodes::CPode(mem_, tout, tret, &yv, &ypv, cpodes::CP_ONE_STEP);
    }
    /// y(t) from CPODES' interpolant over the last step.
    void calcInterpolated(double t, std::vector<double>& y) {
        cpodes::ArrayVector yv(long(y.size()), y.data());
        check(cpodes::CPodeGetDky(mem_, t, 0, &yv), "CPodeGetDky", t);
    }
    int getNumSteps() const {
        long steps = 0;
        cpodes::CPodeGetNumSteps(mem_, &steps);
        return int(steps);
    }
    int getNumNewtonIterations() const {
        long iterations = 0;
        cpodes::CPodeGetNumNonlinSolvIters(mem_, &iterations);
        return int(iterations);
    }
    int getNumKrylovIterations() const {
        long iterations = 0;
        if (krylov_) cpodes::CPSpilsGetNumLinIters(mem_, &iterations);
        return int(iterations);
    }

private:
    static void check(int flag, const char* call, double t) {
        if (flag != cpodes::CP_SUCCESS)
            throw SimulationError("t = " + formatNumber(t) + " s: " + call + " failed (CPodes flag " +
                                  std::to_string(flag) + ")");
    }
    void* mem_;
    double absTol_;
    bool krylov_ = false;
};

// The N_Vector layout declared in cpodes_c.h, checked once against the loaded library.
void checkCpodesLayout() {
    static const std::string mismatch = cpodes::findCpodesLayoutMismatch();
    if (!mismatch.empty())
        throw SimulationError("the CPodes C interface of the loaded libSimTKmath differs from the one armsim was "
                              "written for (Simbody 3.7): " + mismatch);
}

// integrateSampled for f, whose blocks (if any) are `blocks`.
IntegrationStats integrate(const OdeRhs& f, const OdeBlocks* blocks, double t0, std::vector<double>& y,
                           double duration, double sampleRate, const std::vector<double>& breakpoints,
                           const IntegrationSettings& settings, const OdeVisitor& sample, const OdeVisitor& check,
                           const OdeArrow* arrowShape = nullptr) {
    settings.validate();
    checkField("duration", duration, Bound::nonNegative("s"));
    checkField("sample_rate", sampleRate, Bound::positive("Hz"));
    checkCpodesLayout();
    const int n = int(y.size());
    detail::SampledRun run(t0, duration, sampleRate, breakpoints, n);
    IntegrationStats stats;
    RhsContext context(f, blocks, n);
    std::unique_ptr<ArrowSolver> arrow;
    if (arrowShape) arrow = std::make_unique<ArrowSolver>(*arrowShape, context, n);

    if (check) check(t0, y.data());
    checkFinite(t0, y.data(), n);
    sample(t0, y.data());
    run.start();
    const double relTol = settings.accuracy, absTol = settings.accuracy / 10;  // CPodesIntegrator's choice
    int halfBandwidth = -1;  // dense
    if (blocks && blocks->banded) halfBandwidth = *std::max_element(blocks->size.begin(), blocks->size.end()) - 1;
    if (2 * halfBandwidth + 1 >= n) halfBandwidth = -1;   // a band as wide as y: the dense solve (LAPACK's band storage would be larger)
    double t = t0;
    std::vector<double> yv = y, ydot(n), yout(n), ypout(n);
    for (double segmentEnd : run.getSegmentEnds()) {
        context.evaluate(t, yv.data(), ydot.data());
        run.restart(t, yv.data(), ydot.data());
        Cpodes cpodes(context, t, yv, ydot, relTol, absTol, settings, halfBandwidth, arrow.get());
        ++stats.restarts;
        while (t < segmentEnd - run.getEpsilon()) {
            checkInterruption();  // a long trial stops within a step of Ctrl-C
            double tret = t;
            context.clearLastError();  // report only this step's model errors
            int res = cpodes.step(segmentEnd, &tret, yout, ypout);
            if (res == cpodes::CP_TOO_CLOSE) {  // segment shorter than CPodes can step: treat as reached
                tret = segmentEnd;
                yout = yv;
                res = cpodes::CP_SUCCESS;
            }
            if (res < 0) {
                std::ostringstream msg;
                msg << "t = " << t << " s: the integrator failed";
                if (!context.getSolverMessage().empty()) msg << ": " << context.getSolverMessage();
                msg << " (CPodes flag " << res << ")";
                if (!context.getLastError().empty()) msg << "; last model error: " << context.getLastError();
                throw SimulationError(msg.str());
            }
            if (tret > segmentEnd) {  // overshot: CPodes' own interpolant at the segment end
                cpodes.calcInterpolated(segmentEnd, yout);
                tret = segmentEnd;
            }
            t = tret;
            yv.swap(yout);
            if (check) check(t, yv.data());
            checkFinite(t, yv.data(), n);
            context.evaluate(t, yv.data(), ydot.data());
            run.advance(t, yv.data(), ydot.data(), run.isBreakpoint(t, segmentEnd), sample);
        }
        stats.steps += cpodes.getNumSteps();
        stats.newtonIterations += cpodes.getNumNewtonIterations();
        stats.krylovIterations += cpodes.getNumKrylovIterations();
    }
    stats.restarts -= 1;
    stats.realizations = context.getNumEvaluations();
    stats.partialEvaluations = context.getNumPartialEvaluations();
    stats.jacobians = context.getNumJacobians();
    y = yv;
    return stats;
}

}  // namespace

IntegrationStats integrateSampled(const OdeRhs& f, double t0, std::vector<double>& y, double duration,
                                  double sampleRate, const std::vector<double>& breakpoints,
                                  const IntegrationSettings& settings, const OdeVisitor& sample,
                                  const OdeVisitor& check) {
    return integrate(f, nullptr, t0, y, duration, sampleRate, breakpoints, settings, sample, check);
}

IntegrationStats integrateSampled(const OdeBlocks& f, double t0, std::vector<double>& y, double duration,
                                  double sampleRate, const std::vector<double>& breakpoints,
                                  const IntegrationSettings& settings, const OdeVisitor& sample,
                                  const OdeVisitor& check) {
    const std::size_t numBlocks = f.first.size();
    if (f.size.size() != numBlocks || !f.calcBlock)
        throw std::invalid_argument("integrateSampled: blocks need a first state, a size and calcBlock");
    std::vector<int> owner(y.size(), -1);
    for (std::size_t b = 0; b < numBlocks; ++b) {
        if (f.size[b] <= 0)
            throw std::invalid_argument("integrateSampled: block " + std::to_string(b) + " is empty");
        for (int i = f.first[b]; i < f.first[b] + f.size[b]; ++i) {
            if (i < 0 || i >= int(y.size()) || owner[i] >= 0)
                throw std::invalid_argument("integrateSampled: block " + std::to_string(b) +
                                            " is outside y or overlaps another block");
            owner[i] = int(b);
        }
    }
    if (std::count(owner.begin(), owner.end(), -1) > 0)
        throw std::invalid_argument("integrateSampled: the blocks do not cover y");
    const OdeRhs whole = [&f, numBlocks](double t, const double* yIn, double* ydot) {
        for (std::size_t b = 0; b < numBlocks; ++b) f.calcBlock(int(b), t, yIn, ydot);
    };
    return integrate(whole, &f, t0, y, duration, sampleRate, breakpoints, settings, sample, check);
}

IntegrationStats integrateSampled(const OdeArrow& f, double t0, std::vector<double>& y, double duration,
                                  double sampleRate, const std::vector<double>& breakpoints,
                                  const IntegrationSettings& settings, const OdeVisitor& sample,
                                  const OdeVisitor& check) {
    if (!f.f || f.first.size() != f.size.size() || f.numCoupled < 0)
        throw std::invalid_argument("integrateSampled: an arrow needs f, a first state and a size per block");
    int next = f.numCoupled;
    for (std::size_t b = 0; b < f.first.size(); ++b) {
        if (f.first[b] != next || f.size[b] <= 0)
            throw std::invalid_argument("integrateSampled: arrow block " + std::to_string(b) +
                                        " does not follow the coupled states and the blocks before it");
        next += f.size[b];
    }
    if (next != int(y.size()))
        throw std::invalid_argument("integrateSampled: the arrow's states do not cover y");
    return integrate(f.f, nullptr, t0, y, duration, sampleRate, breakpoints, settings, sample, check, &f);
}

}  // namespace armsim
