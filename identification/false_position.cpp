// Regula falsi with the Illinois modification for one unknown (thesis 4.5.1, eq. 4.33).
#include "basics/format.h"
#include "identification/solver_context.h"

#include <cmath>
#include <sstream>

namespace armsim::detail {

namespace {
}  // namespace

SolverOutcome solveFalsePosition(SolverContext& ctx) {
    const Unknown& u = ctx.map.getUnknowns()[0];
    const std::string unit = " " + getParameterUnit(u.id);
    SolverOutcome out;
    std::vector<double> ra, rb, rc;
    double a = u.lower, b = u.upper;
    const bool okA = ctx.calcResiduals({a}, ra);
    const std::string failA = ctx.getLastFailure();
    const bool okB = ctx.calcResiduals({b}, rb);
    if (!okA || !okB) {
        out.x = {okA ? b : a};
        out.message = "false-position needs the model at both ends of the bracket [" + formatNumber(a, 8) + ", " + formatNumber(b, 8) + "]" +
                      unit + ": " + (okA ? ctx.getLastFailure() : failA);
        return out;
    }
    double fa = ra[0], fb = rb[0];
    ctx.record(0, {std::abs(fa) < std::abs(fb) ? a : b}, std::abs(fa) < std::abs(fb) ? ra : rb);
    if (fa == 0 || fb == 0) {
        out.x = {fa == 0 ? a : b};
        out.r = fa == 0 ? ra : rb;
        out.reason = StopReason::Converged;
        out.message = "the force is met exactly at an end of the bracket";
        return out;
    }
    if ((fa > 0) == (fb > 0)) {
        out.x = {std::abs(fa) < std::abs(fb) ? a : b};
        out.r = std::abs(fa) < std::abs(fb) ? ra : rb;
        out.message = "no sign change of model - measured force on the bracket [" + formatNumber(a, 8) + ", " + formatNumber(b, 8) + "]" +
                      unit + " (" + formatNumber(fa, 8) + " N, " + formatNumber(fb, 8) + " N): the measured force is " +
                      (fa > 0 ? "below" : "above") +
                      " the model's at both ends, or the bracket holds two roots; change the bounds";
        return out;
    }
    int side = 0;  // which end was kept last: -1 a, +1 b
    double c = a;
    for (int it = 1; it <= ctx.options.maxIterations; ++it) {
        c = (a * fb - b * fa) / (fb - fa);
        if (!ctx.calcResiduals({c}, rc)) {
            out.x = {c};
            out.iterations = it;
            out.message = "the model failed inside the bracket: " + ctx.getLastFailure();
            return out;
        }
        const double fc = rc[0];
        ctx.record(it, {c}, rc);
        out.iterations = it;
        if (fc == 0) {
            a = b = c;
        } else if ((fc > 0) == (fb > 0)) {
            b = c, fb = fc;
            if (side == +1) fa *= 0.5;
            side = +1;
        } else {
            a = c, fa = fc;
            if (side == -1) fb *= 0.5;
            side = -1;
        }
        if (std::abs(b - a) <= u.tolerance) {
            out.x = {c};
            out.r = rc;
            out.reason = StopReason::Converged;
            out.message = "bracket narrower than the tolerance " + formatNumber(u.tolerance, 8) + unit + " after " +
                          std::to_string(it) + " iterations";
            return out;
        }
    }
    out.x = {c};
    out.r = rc;
    out.reason = StopReason::MaxIterations;
    out.message = "bracket still " + formatNumber(std::abs(b - a), 8) + unit + " wide after " +
                  std::to_string(ctx.options.maxIterations) + " iterations";
    return out;
}

}  // namespace armsim::detail
