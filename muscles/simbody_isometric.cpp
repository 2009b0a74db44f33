#include "muscles/simbody_isometric.h"

#include "muscles/muscle_force.h"
#include "muscles/param_file.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>

using namespace SimTK;

namespace armsim {

void IntegrationSettings::validate() const {
    checkField("accuracy", accuracy, Bound::open(0, 1));
    checkField("max_step", maxStepSize, Bound::nonNegative("s"));
}

namespace {

void checkFinite(const State& s) {
    auto scan = [&](const Vector& v, const char* what) {
        for (int i = 0; i < v.size(); ++i)
            if (!std::isfinite(v[i])) {
                std::ostringstream msg;
                msg << "t = " << s.getTime() << " s: state " << what << "[" << i << "] is " << v[i]
                    << " (not finite)";
                throw SimulationError(msg.str());
            }
    };
    scan(s.getQ(), "q");
    scan(s.getU(), "u");
    scan(s.getZ(), "z");
}

}  // namespace

IntegrationStats simulateSampled(const MultibodySystem& system, State& state, double duration, double sampleRate,
                                 const std::vector<double>& breakpoints, const IntegrationSettings& settings,
                                 const std::function<void(const State&)>& sample,
                                 const std::function<void(const State&)>& check) {
    settings.validate();
    checkField("duration", duration, Bound::nonNegative("s"));
    checkField("sample_rate", sampleRate, Bound::positive("Hz"));
    const double t0 = state.getTime(), tEnd = t0 + duration;
    const long numSamples = std::lround(duration * sampleRate) + 1;
    auto sampleTime = [&](long k) { return t0 + double(k) / sampleRate; };
    const double eps = 1e-9 / sampleRate;

    std::vector<double> cuts;
    for (double b : breakpoints)
        if (b > t0 + eps && b < tEnd - eps) cuts.push_back(b);
    std::sort(cuts.begin(), cuts.end());
    cuts.erase(std::unique(cuts.begin(), cuts.end()), cuts.end());
    cuts.push_back(tEnd);

    CPodesIntegrator integ(system, CPodes::BDF, CPodes::Newton);
    integ.setAccuracy(settings.accuracy);
    if (settings.maxStepSize > 0) integ.setMaximumStepSize(settings.maxStepSize);
    integ.setReturnEveryInternalStep(true);
    integ.setProjectEveryStep(false);

    // Samples come from cubic Hermite interpolation of y = [q u z] between internal steps, written into
    // one scratch State: asking Simbody for interpolated reports copies a whole State per sample,
    // which costs more than the integration itself.
    State scratch = state;
    Vector ya, yda, yb, ydb, y(state.getNY());
    double ta = t0;
    auto emitUpTo = [&](long& next, double tb, bool endSlopeValid) {
        const double h = tb - ta;
        while (next < numSamples && sampleTime(next) <= tb + eps) {
            const double t = std::min(sampleTime(next), tb);
            const double s = h > 0 ? (t - ta) / h : 1.0;
            double c0, c1, c2, c3;  // weights of ya, h*yda, yb, h*ydb
            if (endSlopeValid) {
                c0 = (1 + 2 * s) * (1 - s) * (1 - s);
                c1 = s * (1 - s) * (1 - s);
                c2 = s * s * (3 - 2 * s);
                c3 = s * s * (s - 1);
            } else {  // quadratic through (ta, ya, yda) and (tb, yb): the end slope jumps at a breakpoint
                c0 = 1 - s * s;
                c1 = s * (1 - s);
                c2 = s * s;
                c3 = 0;
            }
            for (int i = 0; i < y.size(); ++i)
                y[i] = c0 * ya[i] + c1 * h * yda[i] + c2 * yb[i] + c3 * h * ydb[i];
            scratch.setTime(t);
            // Write q and u only when they moved (a locked joint keeps them), so the scratch state
            // keeps its position-level cache and a sample costs less to realize.
            const int nq = scratch.getNQ(), nu = scratch.getNU(), nz = scratch.getNZ();
            bool qMoved = false, uMoved = false;
            for (int i = 0; i < nq; ++i) qMoved = qMoved || y[i] != scratch.getQ()[i];
            for (int i = 0; i < nu; ++i) uMoved = uMoved || y[nq + i] != scratch.getU()[i];
            if (qMoved) scratch.updQ() = y(0, nq);
            if (uMoved) scratch.updU() = y(nq, nu);
            scratch.updZ() = y(nq + nu, nz);
            sample(scratch);
            ++next;
        }
    };

    IntegrationStats stats;
    if (check) check(state);
    checkFinite(state);
    system.realize(state, Stage::Acceleration);
    sample(state);
    long next = 1;
    for (double segmentEnd : cuts) {
        integ.initialize(state);
        ++stats.restarts;
        const State& a = integ.getState();
        system.realize(a, Stage::Acceleration);
        ta = a.getTime();
        ya = a.getY();
        yda = a.getYDot();
        while (integ.getTime() < segmentEnd - eps) {
            Integrator::SuccessfulStepStatus status;
            try {
                status = integ.stepTo(segmentEnd, segmentEnd);
            } catch (const std::exception& e) {
                // CPodes gives up (e.g. repeated error-test or Newton failures): say when, and the last
                // good state's validity, rather than an internal error.
                const State& last = integ.getState();
                if (check) check(last);
                checkFinite(last);
                std::ostringstream msg;
                msg << "t = " << last.getTime() << " s: the integrator failed: " << e.what();
                throw SimulationError(msg.str());
            }
            if (status == Integrator::EndOfSimulation || status == Integrator::InvalidSuccessfulStepStatus) {
                std::ostringstream msg;
                msg << "t = " << integ.getTime() << " s: integration stopped: "
                    << Integrator::getTerminationReasonString(integ.getTerminationReason());
                throw SimulationError(msg.str());
            }
            const State& b = integ.getState();
            if (check) check(b);  // element-specific checks first: they name the muscle and state
            checkFinite(b);
            system.realize(b, Stage::Acceleration);
            yb = b.getY();
            ydb = b.getYDot();
            const bool atBreakpoint = b.getTime() >= segmentEnd - eps && segmentEnd < tEnd;
            emitUpTo(next, b.getTime(), !atBreakpoint);
            ta = b.getTime();
            ya = yb;
            yda = ydb;
        }
        state = integ.getState();
        stats.steps += integ.getNumStepsTaken();
        stats.realizations += integ.getNumRealizations();
    }
    stats.restarts -= 1;
    return stats;
}

void MuscleIsometricSettings::validate(const VirtualMuscle& muscle) const {
    muscle.checkPathLength(pathLength);
    checkField("duration", duration, Bound::positive("s"));
    checkField("sample_rate", sampleRate, Bound::positive("Hz"));
    integration.validate();
}

Table runMuscleIsometric(const VirtualMuscle& muscle, const MuscleIsometricSettings& settings,
                         IntegrationStats* stats) {
    settings.validate(muscle);
    MultibodySystem system;
    SimbodyMatterSubsystem matter(system);
    GeneralForceSubsystem forces(system);
    const VirtualMuscleForce force(forces, std::make_shared<VirtualMuscle>(muscle), matter.Ground(), Vec3(0),
                                   matter.Ground(), Vec3(settings.pathLength, 0, 0), settings.activation);
    system.realizeTopology();
    State state = system.getDefaultState();
    if (settings.startSteady) force.setSteadyMuscleStates(state);
    else force.setInitialMuscleStates(state);

    const double L0 = muscle.getParameters().optimalFascicleLength;
    const double L0T = muscle.getParameters().optimalTendonLength;
    Table table({"time_s", "activation", "force_N", "fce_N", "fascicle_length_m", "fascicle_velocity_mps",
                 "tendon_length_m", "active_fraction"});
    const IntegrationStats st = simulateSampled(
        system, state, settings.duration, settings.sampleRate, settings.activation.getBreakpoints(),
        settings.integration,
        [&](const State& s) {
            // Pure model at the known, fixed path: no Simbody realization per sample.
            const double t = s.getTime(), U = settings.activation.getValue(t);
            const MuscleOutputs o = muscle.calcOutputs(settings.pathLength, U, &s.getZ()[0]);
            table.appendRow({t, U, o.Fse, o.Fce, o.L * L0, o.V * L0, o.LT * L0T, o.activeFraction});
        },
        [&](const State& s) { force.checkMuscleStates(s); });
    if (stats) *stats = st;
    return table;
}

}  // namespace armsim
