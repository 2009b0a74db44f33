#include "muscles/stiff_ode.h"

#include "basics/bound.h"
#include "muscles/simbody.h"

#include <algorithm>
#include <cmath>
#include <regex>
#include <sstream>

using SimTK::CPodes;
using SimTK::Real;
using SimTK::Vector;

namespace armsim {

void IntegrationSettings::validate() const {
    checkField("accuracy", accuracy, Bound::open(0, 1));
    checkField("max_step", maxStepSize, Bound::nonNegative("s"));
    if (maxStepSize > 0 && maxStepSize < kMinStepSize)
        checkField("max_step", maxStepSize, Bound{kMinStepSize, 1e300, false, false, "s, 0 or at least the 1e-12 s minimum step"});
}

long calcNumSamples(double duration, double sampleRate) {
    const double n = std::round(duration * sampleRate) + 1;
    if (!(n <= kMaxSamples))
        throw InputError("duration " + formatNumber(duration) + " s x sample_rate " + formatNumber(sampleRate) +
                         " Hz = " + formatNumber(n) + " samples: expected at most " + formatNumber(kMaxSamples) +
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

// CPodes' view of f. A throwing f becomes a recoverable error (CPodes cuts the step), as in Simbody's
// CPodesIntegrator; the last message is kept for the report if CPodes gives up.
class RhsSystem : public SimTK::CPodesSystem {
public:
    RhsSystem(const OdeRhs& f, int& count) : f_(f), count_(count) {}
    int explicitODE(Real t, const Vector& y, Vector& ydot) const override {
        ++count_;
        try {
            if (y.hasContiguousData() && ydot.hasContiguousData()) {
                f_(t, &y[0], &ydot[0]);
            } else {  // views with strides: go through copies
                std::vector<double> yv(y.size()), dv(y.size());
                for (int i = 0; i < y.size(); ++i) yv[i] = y[i];
                f_(t, yv.data(), dv.data());
                for (int i = 0; i < y.size(); ++i) ydot[i] = dv[i];
            }
        } catch (const std::exception& e) {
            lastError_ = e.what();
            return CPodes::RecoverableError;
        } catch (...) {
            lastError_ = "unknown exception";
            return CPodes::RecoverableError;
        }
        return CPodes::Success;
    }
    // CPodes' own diagnostics: kept for the exception rather than printed to stderr.
    // Its messages start "At t = <t>" glued to the text; the time is reported by the caller.
    void errorHandler(int, const char*, const char*, char* msg) const override {
        static const std::regex timePrefix("^At t = [-+0-9.eE]+,? *");
        solverMessage_ = std::regex_replace(std::string(msg), timePrefix, "");
    }
    const std::string& getLastError() const { return lastError_; }
    void clearLastError() { lastError_.clear(); }
    const std::string& getSolverMessage() const { return solverMessage_; }

private:
    const OdeRhs& f_;
    int& count_;
    mutable std::string lastError_, solverMessage_;
};

}  // namespace

IntegrationStats integrateSampled(const OdeRhs& f, double t0, std::vector<double>& y, double duration,
                                  double sampleRate, const std::vector<double>& breakpoints,
                                  const IntegrationSettings& settings, const OdeVisitor& sample,
                                  const OdeVisitor& check) {
    settings.validate();
    checkField("duration", duration, Bound::nonNegative("s"));
    checkField("sample_rate", sampleRate, Bound::positive("Hz"));
    const int n = int(y.size());
    detail::SampledRun run(t0, duration, sampleRate, breakpoints, n);
    IntegrationStats stats;
    RhsSystem system(f, stats.realizations);
    auto evaluate = [&](double t, const Vector& yIn, Vector& ydot) {
        if (system.explicitODE(t, yIn, ydot) != CPodes::Success)
            throw SimulationError("t = " + formatNumber(t) + " s: " + system.getLastError());
    };

    if (check) check(t0, y.data());
    checkFinite(t0, y.data(), n);
    sample(t0, y.data());
    run.start();
    const Real relTol = settings.accuracy, absTol = settings.accuracy / 10;  // CPodesIntegrator's choice
    double t = t0;
    Vector yv(n, y.data()), ydot(n), yout(n), ypout(n);
    for (double segmentEnd : run.getSegmentEnds()) {
        evaluate(t, yv, ydot);
        run.restart(t, &yv[0], &ydot[0]);
        CPodes cpodes(CPodes::ExplicitODE, CPodes::BDF, CPodes::Newton);
        cpodes.init(system, t, yv, ydot, CPodes::ScalarScalar, relTol, const_cast<Real*>(&absTol));
        cpodes.setErrHandlerFn();
        cpodes.lapackDense(n);
        cpodes.setNonlinConvCoef(0.01);
        cpodes.setMinStep(IntegrationSettings::kMinStepSize);
        if (settings.maxStepSize > 0) cpodes.setMaxStep(settings.maxStepSize);
        ++stats.restarts;
        while (t < segmentEnd - run.getEpsilon()) {
            checkInterruption();  // a long trial stops within a step of Ctrl-C
            Real tret = t;
            system.clearLastError();  // report only this step's model errors
            int res = cpodes.step(segmentEnd, &tret, yout, ypout, CPodes::OneStep);
            if (res == CPodes::TooClose) {  // segment shorter than CPodes can step: treat as reached
                tret = segmentEnd;
                yout = yv;
                res = CPodes::Success;
            }
            if (res < 0) {
                std::ostringstream msg;
                msg << "t = " << t << " s: the integrator failed";
                if (!system.getSolverMessage().empty()) msg << ": " << system.getSolverMessage();
                msg << " (CPodes flag " << res << ")";
                if (!system.getLastError().empty()) msg << "; last model error: " << system.getLastError();
                throw SimulationError(msg.str());
            }
            if (tret > segmentEnd) {  // overshot: CPodes' own interpolant at the segment end
                cpodes.getDky(segmentEnd, 0, yout);
                tret = segmentEnd;
            }
            t = tret;
            yv = yout;
            if (check) check(t, &yv[0]);
            checkFinite(t, &yv[0], n);
            evaluate(t, yv, ydot);
            run.advance(t, &yv[0], &ydot[0], run.isBreakpoint(t, segmentEnd), sample);
        }
        int steps = 0;
        cpodes.getNumSteps(&steps);
        stats.steps += steps;
    }
    stats.restarts -= 1;
    for (int i = 0; i < n; ++i) y[i] = yv[i];
    return stats;
}

}  // namespace armsim
