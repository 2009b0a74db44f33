// Identification of mass and tendon length from the five thesis angles with the steady model
// (target: under 10 ms per identification). Counter forward_evaluations: ForceModel::calcForces calls
// per identification (the thesis's ILC needed ~50 iterations, one forward run each).
#include "identification/identifier.h"
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
    for (double deg : {45.0, 60.0, 90.0, 120.0, 150.0}) {
        Observation o;
        o.pathLength = calcThesisPathLength(deg * 3.14159265358979323846 / 180.0);
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

}  // namespace

BENCHMARK(BM_IdentifyFiveAnglesLm)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_IdentifyFiveAnglesSignSearch)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SteadyForwardEvaluation)->Unit(benchmark::kMicrosecond);
