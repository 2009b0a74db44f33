// Identification of mass and tendon length from the five thesis angles: with the steady model (target
// under 10 ms) and with the faithful model, the MVC protocol in the Simbody arm (target under 2 s), in
// the loop, warm-started from steady lm, and as corrections of the steady model. Counters:
// forward_evaluations (ForceModel::calcForces calls; faithful: five arm trials each), iterations, and
// thesis_iterations = 52 (thesis Table 7.2, one forward run per iteration) for comparison.
#include "identification/torque_identification.h"
#include "identification/faithful_model.h"
#include "identification/identifier.h"
#include "model/geometry.h"
#include "model/muscle_arm.h"
#include "muscles/muscle_file.h"

#include <benchmark/benchmark.h>

#include <cmath>

using namespace armsim;

namespace {

IdentificationProblem makeFiveAngleProblem() {
    IdentificationProblem pr;
    pr.base = loadMuscleParameters(std::string(ARMSIM_ASSET_DIR) + "/muscles/biceps_long_head.yaml");
    MuscleParameters truth = pr.base;
    truth.mass = 0.336;
    truth.optimalTendonLength = 0.245;
    pr.data.source = "synthetic five angles";
    for (double deg : kThesisMvcAnglesDeg) {
        Observation o;
        o.pathLength = calcThesisPathLength(degToRad(deg));
        pr.data.points.push_back(o);
    }
    const std::vector<double> y = SteadyForceModel().calcForces(truth, pr.data.points);
    for (std::size_t k = 0; k < y.size(); ++k) pr.data.points[k].force = y[k];
    pr.unknowns[0].start = 0.330;
    pr.unknowns[1].start = 0.22;
    return pr;
}

void runIdentification(benchmark::State& state, Method method) {
    const IdentificationProblem pr = makeFiveAngleProblem();
    const SteadyForceModel model;
    IdentificationOptions o;
    o.method = method;
    int evaluations = 0, iterations = 0;
    for (auto _ : state) {
        const IdentificationReport r = identify(pr, model, o);
        if (!r.isConverged()) state.SkipWithError(r.message.c_str());
        evaluations = r.forwardEvaluations;
        iterations = r.iterations;
        benchmark::DoNotOptimize(r.parameters.data());
    }
    state.counters["forward_evaluations"] = evaluations;
    state.counters["iterations"] = iterations;
}

void BM_IdentifyFiveAnglesLm(benchmark::State& s) { runIdentification(s, Method::LevenbergMarquardt); }
void BM_IdentifyFiveAnglesSignSearch(benchmark::State& s) { runIdentification(s, Method::IlcSignSearch); }

void BM_SteadyForwardEvaluation(benchmark::State& state) {
    const IdentificationProblem pr = makeFiveAngleProblem();
    const SteadyForceModel model;
    for (auto _ : state) benchmark::DoNotOptimize(model.calcForces(pr.base, pr.data.points));
}

constexpr double kThesisIterations = 52;  // thesis Table 7.2

/// Five-angle data made by the faithful model at the thesis protocol (1000 Hz) for M = 336 g,
/// L0T = 24.5 cm; the default subject's arm.
struct FaithfulCase {
    ArmSetup setup = ArmSetup::loadDefault();
    IdentificationProblem problem;
    FaithfulForceModel fast{setup.arm};
    FaithfulCase() {
        problem.base = setup.calcBicepsParameters();
        MuscleParameters truth = problem.base;
        truth.mass = 0.336;
        truth.optimalTendonLength = 0.245;
        problem.data.source = "faithful five angles";
        for (double deg : kThesisMvcAnglesDeg) {
            Observation o;
            o.angle = degToRad(deg);
            o.pathLength = calcBicepsPathLength(setup.arm.originDistance, setup.arm.insertionDistance, o.angle);
            problem.data.points.push_back(o);
        }
        FaithfulModelOptions ro;
        ro.protocol = FaithfulProtocol::makeReference();
        const std::vector<double> y = FaithfulForceModel(setup.arm, ro).calcForces(truth, problem.data.points);
        for (std::size_t k = 0; k < y.size(); ++k) problem.data.points[k].force = y[k];
        problem.unknowns[0].start = 0.330;
        problem.unknowns[1].start = 0.22;
    }
};

enum class Scheme { InTheLoop, WarmStarted, Corrected };

void runFaithful(benchmark::State& state, Method method, Scheme scheme) {
    const FaithfulCase c;
    IdentificationOptions o;
    o.method = method;
    const SteadyForceModel steady;
    IdentificationReport r;
    for (auto _ : state) {
        switch (scheme) {
            case Scheme::InTheLoop: r = identify(c.problem, c.fast, o); break;
            case Scheme::WarmStarted: r = identifyWarmStarted(c.problem, steady, c.fast, o); break;
            case Scheme::Corrected: r = identifyCorrected(c.problem, steady, c.fast, o); break;
        }
        if (!r.isConverged()) state.SkipWithError(r.message.c_str());
    }
    state.counters["forward_evaluations"] = r.forwardEvaluations;
    state.counters["iterations"] = r.iterations;
    state.counters["thesis_iterations"] = kThesisIterations;
    state.counters["mass_error_pct"] = 100 * (r.parameters[0].value / 0.336 - 1);
    state.counters["tendon_error_pct"] = 100 * (r.parameters[1].value / 0.245 - 1);
}

void BM_FaithfulLm(benchmark::State& s) { runFaithful(s, Method::LevenbergMarquardt, Scheme::InTheLoop); }
void BM_FaithfulLmWarmStarted(benchmark::State& s) { runFaithful(s, Method::LevenbergMarquardt, Scheme::WarmStarted); }
void BM_FaithfulSignSearch(benchmark::State& s) { runFaithful(s, Method::IlcSignSearch, Scheme::InTheLoop); }
void BM_FaithfulSignSearchWarmStarted(benchmark::State& s) { runFaithful(s, Method::IlcSignSearch, Scheme::WarmStarted); }
void BM_CorrectedLm(benchmark::State& s) { runFaithful(s, Method::LevenbergMarquardt, Scheme::Corrected); }
void BM_CorrectedSignSearch(benchmark::State& s) { runFaithful(s, Method::IlcSignSearch, Scheme::Corrected); }

/// One faithful evaluation: five 3.5 s arm trials on two threads, at 200 Hz (iterations) and
/// 1000 Hz (the reference protocol).
void BM_FaithfulForwardEvaluation(benchmark::State& state) {
    const FaithfulCase c;
    FaithfulModelOptions o;
    o.protocol.sampleRate = double(state.range(0));
    const FaithfulForceModel model(c.setup.arm, o);
    for (auto _ : state) benchmark::DoNotOptimize(model.calcForces(c.problem.base, c.problem.data.points));
    state.counters["trials"] = double(c.problem.data.points.size());
}

// Issue 11: one synergist-aware identification (elbow model, five angles x 3 efforts of a drawn
// subject; the data are synthesized once, outside the timing). Target: median <= 1 s.
void BM_SynergistAwareIdentification(benchmark::State& state) {
    setenv("ARMSIM_ASSETS", ARMSIM_ASSET_DIR, 0);
    static const Population population = loadDefaultPopulation();
    static const std::vector<TorqueObservation> data = synthesizeTorqueData(drawSubject(population, 1, 0), {}, 1, 2);
    double error = 0;
    for (auto _ : state) {
        const MuscleEstimate e = identifySynergistAware(population, data);
        error = e.mass / drawSubject(population, 1, 0).setup.biceps().mass - 1;
    }
    state.counters["mass_error_pct"] = 100 * error;
}

// Issue 31: one identification with every channel of assets/protocols/recommended.yaml (15 MVCs, 18
// fascicle images, 75 EMG amplitudes, 3 volumes, the arm length, measured activation) of a drawn
// subject of the stronger mismatch population; data synthesized once, outside the timing.
// Target: median <= 0.5 s.
void BM_ChannelsIdentification(benchmark::State& state) {
    setenv("ARMSIM_ASSETS", ARMSIM_ASSET_DIR, 0);
    static const Population prior = loadDefaultPopulation();
    static const TorqueProtocol protocol = readTorqueProtocol(std::string(ARMSIM_ASSET_DIR) + "/protocols/recommended.yaml");
    static const VirtualSubject v =
        drawSubject(loadPopulation(std::string(ARMSIM_ASSET_DIR) + "/subjects/mismatch/stronger.yaml"), 1, 0);
    static const std::vector<TorqueObservation> data = synthesizeTorqueData(v, protocol, 1, 2);
    SynergistOptions o;
    o.channels = synthesizeChannelData(v, protocol, data, 1);
    o.measuredActivation = measureVoluntaryActivation(data, 0.02, 1);
    double error = 0;
    int iterations = 0;
    for (auto _ : state) {
        const MuscleEstimate e = identifySynergistAware(prior, data, o);
        error = e.mass / v.setup.biceps().mass - 1;
        iterations = e.iterations;
    }
    state.counters["mass_error_pct"] = 100 * error;
    state.counters["iterations"] = iterations;
    state.counters["measurements"] = double(data.size() + o.channels.size());
}

}  // namespace

BENCHMARK(BM_SynergistAwareIdentification)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ChannelsIdentification)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_IdentifyFiveAnglesLm)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_IdentifyFiveAnglesSignSearch)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SteadyForwardEvaluation)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_FaithfulForwardEvaluation)->Arg(200)->Arg(1000)->Unit(benchmark::kMillisecond);
#define ARMSIM_SLOW(b) BENCHMARK(b)->Unit(benchmark::kMillisecond)->Iterations(1)->Repetitions(3)->ReportAggregatesOnly(true)
ARMSIM_SLOW(BM_FaithfulLm);
ARMSIM_SLOW(BM_FaithfulLmWarmStarted);
ARMSIM_SLOW(BM_FaithfulSignSearch);
ARMSIM_SLOW(BM_FaithfulSignSearchWarmStarted);
ARMSIM_SLOW(BM_CorrectedLm);
ARMSIM_SLOW(BM_CorrectedSignSearch);
