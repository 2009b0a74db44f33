// Sampled integration of a stiff ODE y' = f(t, y) with CPodes (SUNDIALS' BDF/Newton solver as
// shipped in Simbody's SimTKmath), without a Simbody System: the right-hand side is a plain function.
//
// Used where the multibody part is frozen (a locked elbow, a muscle on a fixed path): there the
// System would be realized at every right-hand side only to hand the same path lengths to the
// muscles again. The solver is driven exactly as Simbody's CPodesIntegrator drives it (BDF, Newton,
// dense LAPACK Jacobian by finite differences, scalar tolerances rtol = accuracy and
// atol = accuracy / 10, nonlinear convergence coefficient 0.01, one internal step per call, restart
// at every breakpoint, end of segment interpolated by CPodes), and samples come from the same cubic
// Hermite interpolation as simulateSampled's, so for the same y and f both paths take the same steps
// and give the same samples (checked in tests to 1e-6 relative). CPodes is called through its C
// interface with an N_Vector over plain arrays that does the arithmetic of Simbody's own
// (numerics/cpodes_c.h), so no SimTK::Vector temporaries are made.
#pragma once

#include "basics/errors.h"

#include <functional>
#include <vector>

namespace armsim {

/// Settings of the stiff integrator (CPodes, BDF with Newton iteration).
struct IntegrationSettings {
    /// Smallest step [s]. A model that fails (throws) at a time it cannot step past makes CPodes cut
    /// the step towards zero forever; this floor turns that into an error naming the time.
    static constexpr double kMinStepSize = 1e-12;
    double accuracy = 1e-4;     ///< relative accuracy of CPodes' error control [1]
    double maxStepSize = 0.0;   ///< largest step [s]; 0 = no limit
    void validate() const;
};

/// Most samples one sampled run records (10 million rows; a 33-column arm trial table is then 2.6 GB).
constexpr double kMaxSamples = 1e7;

/// calcNumSamples' error: an InputError that keeps the duration and rate, so a command can say it in
/// the options the user typed (cli's runNamingOptions).
class SampleCountError : public InputError {
public:
    SampleCountError(double duration, double sampleRate, std::string detail);
    double getDuration() const { return duration_; }
    double getSampleRate() const { return sampleRate_; }
    /// "= 5000000501 samples: expected at most 1e+07 (...)", after "duration x rate".
    const std::string& getDetail() const { return detail_; }

private:
    double duration_, sampleRate_;
    std::string detail_;
};

/// Samples of a sampled run of `duration` at `sampleRate`: round(duration x rate) + 1. SampleCountError
/// naming both values and the count when it exceeds kMaxSamples (a typo like --rate 1e12 would
/// otherwise exhaust memory or run for days), or when no sample follows the start.
long calcNumSamples(double duration, double sampleRate);

/// What an integration cost.
struct IntegrationStats {
    int steps = 0;              ///< internal steps taken
    int restarts = 0;           ///< restarts at input discontinuities (breakpoints)
    int realizations = 0;       ///< right-hand-side evaluations (Simbody realizations or f calls), Jacobians included
    int partialEvaluations = 0; ///< of those, calls of a block-structured f that evaluated one block or none
    int newtonIterations = 0;   ///< Newton iterations (one linear solve each)
    int krylovIterations = 0;   ///< OdeArrow: Krylov iterations of those solves (1 each when the
                                ///< preconditioner is the exact inverse); 0 for the direct solvers
    int jacobians = 0;          ///< OdeBlocks::calcBlockJacobian: Newton matrices built from it
};

/// f(t, y, ydot): writes dy/dt. May throw SimulationError for a state outside the model: the solver
/// then retries with a smaller step, and reports the message if it gives up.
using OdeRhs = std::function<void(double t, const double* y, double* ydot)>;
/// Called with a time and the state at that time.
using OdeVisitor = std::function<void(double t, const double* y)>;

/// Integrates y' = f(t, y) from t0 for `duration` seconds; y holds y(t0) on entry and y(t0 + duration)
/// on return. sample(t, y) is called at t0 + k / sampleRate for every such time up to t0 + duration (k = 0
/// .. round(duration * sampleRate), the last only when it is not beyond the end),
/// with y from cubic Hermite interpolation between internal steps; the solver restarts at each
/// breakpoint inside the interval; check(t, y) runs after every internal step and may throw
/// SimulationError; every y is checked for NaN there too. Throws SimulationError naming the time
/// when the solver fails.
IntegrationStats integrateSampled(const OdeRhs& f, double t0, std::vector<double>& y, double duration,
                                  double sampleRate, const std::vector<double>& breakpoints,
                                  const IntegrationSettings& settings, const OdeVisitor& sample,
                                  const OdeVisitor& check = {});

/// y' = f(t, y) made of independent blocks (the muscles of a locked arm): block b holds the states
/// [first[b], first[b] + size[b]), the blocks partition y, and block b's derivative depends on t and
/// its own states only. calcBlock(b, t, y, ydot) gets whole-length arrays and writes block b's
/// entries of ydot only. It must be a pure function: the same arguments give the same bits.
struct OdeBlocks {
    std::vector<int> first, size;
    std::function<void(int block, double t, const double* y, double* ydot)> calcBlock;
    /// Newton's linear systems as a band matrix of half-bandwidth max(size) - 1 (the Jacobian is block
    /// diagonal), so factorisation and solves cost linear in the number of blocks instead of cubic in
    /// y's size. Steps and samples then differ from the dense solve's by rounding only; false keeps the
    /// dense solve, bit for bit the OdeRhs path.
    bool banded = false;
    /// Optional, with banded: block b's Jacobian d(ydot_b)/d(y_b) at (t, y), row-major size x size, in
    /// place of CPODES' difference quotients (no f calls for Newton's matrices); return false to have
    /// that block differenced (forward, step sqrt(eps) max(1, |y_j|)) instead.
    std::function<bool(int block, double t, const double* y, double* jacobian)> calcBlockJacobian;
};

/// integrateSampled for a block-structured f, with the same steps and samples as for the equivalent
/// OdeRhs (unless banded): a call at the time of the last full evaluation whose state differs from
/// that one in some blocks only (a column, or with `banded` a column group, of CPODES'
/// difference-quotient Jacobian) evaluates those blocks and copies the others' derivatives, which are
/// bit-for-bit what a full evaluation would give. std::invalid_argument if the blocks do not partition y.
IntegrationStats integrateSampled(const OdeBlocks& f, double t0, std::vector<double>& y, double duration,
                                  double sampleRate, const std::vector<double>& breakpoints,
                                  const IntegrationSettings& settings, const OdeVisitor& sample,
                                  const OdeVisitor& check = {});

/// y' = f(t, y) whose Jacobian is an arrow: the first numCoupled states (a free joint's q and u) may
/// drive every derivative, while block b, states [first[b], first[b] + size[b]) (one muscle), drives
/// only its own derivatives and the coupled states' (blocks follow the coupled states and partition
/// the rest of y). Newton's systems are then solved by block LU factorisations and the Schur
/// complement of the coupled states: cost linear in the blocks (CPODES' Krylov solver with that
/// factorisation as an exact preconditioner and the stored Jacobian as its operator, so it converges
/// in one iteration). The Jacobian is still built by CPODES' difference quotients, one f call per
/// state: f should make a call that moves one block's states cheap (the caller's concern). Steps
/// differ from the dense solve's by rounding and by when the Jacobian is refreshed.
struct OdeArrow {
    OdeRhs f;
    int numCoupled = 0;
    std::vector<int> first, size;
};

/// integrateSampled for an arrow-structured f; std::invalid_argument if the blocks do not follow the
/// coupled states and partition the rest of y.
IntegrationStats integrateSampled(const OdeArrow& f, double t0, std::vector<double>& y, double duration,
                                  double sampleRate, const std::vector<double>& breakpoints,
                                  const IntegrationSettings& settings, const OdeVisitor& sample,
                                  const OdeVisitor& check = {});

namespace detail {

/// Sample times, restart segments and the cubic Hermite sampling shared by integrateSampled and
/// simulateSampled.
class SampledRun {
public:
    SampledRun(double t0, double duration, double sampleRate, const std::vector<double>& breakpoints, int size);
    /// Segment ends in increasing order; the last is t0 + duration.
    const std::vector<double>& getSegmentEnds() const { return cuts_; }
    /// Time tolerance for "reached" comparisons [s].
    double getEpsilon() const { return eps_; }
    /// The caller has emitted the sample at t0.
    void start() { next_ = 1; }
    /// The solver is at a new segment start (ta, ya, yda).
    void restart(double ta, const double* ya, const double* yda);
    /// A step ended at (tb, yb, ydb): emits every sample in (ta, tb] and makes tb the new start.
    /// atBreakpoint: the end slope jumps at tb (an input steps there), so the interpolant is the
    /// quadratic through (ta, ya, yda) and (tb, yb).
    void advance(double tb, const double* yb, const double* ydb, bool atBreakpoint, const OdeVisitor& emit);
    bool isBreakpoint(double t, double segmentEnd) const { return t >= segmentEnd - eps_ && segmentEnd < tEnd_; }

private:
    double sampleTime(long k) const { return t0_ + double(k) / rate_; }
    double t0_, tEnd_, rate_, eps_;
    long numSamples_, next_ = 0;
    std::vector<double> cuts_;
    double ta_ = 0;
    std::vector<double> ya_, yda_, y_;
};

}  // namespace detail
}  // namespace armsim
