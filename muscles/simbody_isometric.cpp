#include "muscles/simbody_isometric.h"

#include "basics/bound.h"
#include "muscles/muscle_force.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>

using namespace SimTK;

namespace armsim {

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
    detail::SampledRun run(state.getTime(), duration, sampleRate, breakpoints, state.getNY());

    CPodesIntegrator integ(system, CPodes::BDF, CPodes::Newton);
    integ.setAccuracy(settings.accuracy);
    integ.setMinimumStepSize(IntegrationSettings::kMinStepSize);
    if (settings.maxStepSize > 0) integ.setMaximumStepSize(settings.maxStepSize);
    integ.setReturnEveryInternalStep(true);
    integ.setProjectEveryStep(false);

    // Samples come from cubic Hermite interpolation of y = [q u z] between internal steps, written into
    // one scratch State: asking Simbody for interpolated reports copies a whole State per sample,
    // which costs more than the integration itself.
    State scratch = state;
    const int nq = state.getNQ(), nu = state.getNU(), nz = state.getNZ();
    const OdeVisitor emit = [&](double t, const double* y) {
        scratch.setTime(t);
        // Write q and u only when they moved (a locked joint keeps them), so the scratch state
        // keeps its position-level cache and a sample costs less to realize.
        bool qMoved = false, uMoved = false;
        for (int i = 0; i < nq; ++i) qMoved = qMoved || y[i] != scratch.getQ()[i];
        for (int i = 0; i < nu; ++i) uMoved = uMoved || y[nq + i] != scratch.getU()[i];
        if (qMoved) scratch.updQ() = Vector(nq, y);
        if (uMoved) scratch.updU() = Vector(nu, y + nq);
        if (nz > 0) {
            Vector& z = scratch.updZ();
            for (int i = 0; i < nz; ++i) z[i] = y[nq + nu + i];
        }
        sample(scratch);
    };

    IntegrationStats stats;
    if (check) check(state);
    checkFinite(state);
    system.realize(state, Stage::Acceleration);
    sample(state);
    run.start();
    Vector ya, yda;
    for (double segmentEnd : run.getSegmentEnds()) {
        integ.initialize(state);
        ++stats.restarts;
        const State& a = integ.getState();
        system.realize(a, Stage::Acceleration);
        ya = a.getY();
        yda = a.getYDot();
        run.restart(a.getTime(), &ya[0], &yda[0]);
        while (integ.getTime() < segmentEnd - run.getEpsilon()) {
            checkInterruption();
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
            ya = b.getY();
            yda = b.getYDot();
            run.advance(b.getTime(), &ya[0], &yda[0], run.isBreakpoint(b.getTime(), segmentEnd), emit);
        }
        state = integ.getState();
        stats.steps += integ.getNumStepsTaken();
        stats.realizations += integ.getNumRealizations();
    }
    stats.restarts -= 1;
    return stats;
}

void MuscleIsometricSettings::validate(const MuscleModel& muscle) const {
    muscle.checkPathLength(pathLength);
    checkField("duration", duration, Bound::positive("s"));
    checkField("sample_rate", sampleRate, Bound::positive("Hz"));
    calcNumSamples(duration, sampleRate);
    integration.validate();
}

Table runMuscleIsometric(const MuscleModel& muscle, const MuscleIsometricSettings& settings,
                         IntegrationStats* stats) {
    settings.validate(muscle);
    const double P = settings.pathLength;
    const double L0 = muscle.getOptimalFascicleLength();
    Table table({"time_s", "activation", "force_N", "fce_N", "fascicle_length_m", "fascicle_velocity_mps",
                 "tendon_length_m", "active_fraction"});
    table.reserveRows(int(std::lround(settings.duration * settings.sampleRate)) + 1);
    const OdeVisitor sample = [&](double t, const double* z) {
        const double U = settings.activation.getValue(t);
        const MuscleOutputs o = muscle.calcOutputs(P, U, z);
        table.appendRow({t, U, o.Fse, o.Fce, o.L * L0, o.V * L0, o.tendonLength, o.activeFraction});
    };
    std::vector<double> z;
    if (settings.startSteady) {
        const SteadyState ss = muscle.calcSteadyState(P, settings.activation.getValue(0));
        if (!ss.converged && ss.message.rfind("no steady state at path", 0) == 0)   // the settings' path, not the solver
            throw FieldError("path_length", "= " + formatNumber(P) + " m: " + ss.message);
        if (!ss.converged) throw SimulationError(ss.message);
        z = ss.states;
    } else {
        z = muscle.calcInitialState(P);
    }
    const std::vector<double> restarts = findRestartTimes(muscle, settings.activation);
    IntegrationStats st;
    if (!settings.integrateSimbodySystem) {
        st = integrateSampled(
            [&](double t, const double* y, double* ydot) {
                muscle.calcStateDerivative(P, settings.activation.getValue(t), y, ydot);
            },
            0.0, z, settings.duration, settings.sampleRate, restarts,
            settings.integration, sample, [&](double t, const double* y) { muscle.checkStates(t, y); });
    } else {
        MultibodySystem system;
        SimbodyMatterSubsystem matter(system);
        GeneralForceSubsystem forces(system);
        // The caller's muscle outlives the system: share it without ownership.
        const MuscleForce force(forces, std::shared_ptr<const MuscleModel>(&muscle, [](const MuscleModel*) {}),
                                matter.Ground(), Vec3(0), matter.Ground(), Vec3(P, 0, 0), settings.activation);
        system.realizeTopology();
        State state = system.getDefaultState();
        force.setMuscleStates(state, z);
        st = simulateSampled(
            system, state, settings.duration, settings.sampleRate, restarts,
            settings.integration, [&](const State& s) { sample(s.getTime(), &s.getZ()[0]); },
            [&](const State& s) { force.checkMuscleStates(s); });
    }
    if (stats) *stats = st;
    return table;
}

}  // namespace armsim
