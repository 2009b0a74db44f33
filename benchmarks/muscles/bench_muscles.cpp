// Speed of the muscle model: derivative, steady solve, a 3 s muscle-only isometric trial.
// Targets (issue 2): derivative well under 1 us, steady solve under 20 us, trial under 15 ms.
#include "muscles/muscle_file.h"
#include "muscles/simbody_isometric.h"

#include <benchmark/benchmark.h>

using namespace armsim;

namespace {

const VirtualMuscle& muscle() {
    static const VirtualMuscle m(loadMuscleParameters(std::string(ARMSIM_ASSET_DIR) + "/muscles/biceps_long_head.yaml"));
    return m;
}

void BM_StateDerivative(benchmark::State& state) {
    const VirtualMuscle& m = muscle();
    const std::vector<double> y = m.calcSteadyState(0.375, 0.7).states;
    std::vector<double> ydot(m.getNumStates());
    for (auto _ : state) {
        m.calcStateDerivative(0.375, 0.7, y.data(), ydot.data());
        benchmark::DoNotOptimize(ydot.data());
    }
}
BENCHMARK(BM_StateDerivative);

void BM_SteadySolve(benchmark::State& state) {
    const VirtualMuscle& m = muscle();
    int evaluations = 0;
    for (auto _ : state) {
        const SteadyState s = m.calcSteadyState(0.375, 1.0);
        evaluations = s.evaluations;
        benchmark::DoNotOptimize(s.force);
    }
    state.counters["evaluations"] = evaluations;
}
BENCHMARK(BM_SteadySolve)->Unit(benchmark::kMicrosecond);

void BM_IsometricTrial3s(benchmark::State& state) {
    MuscleIsometricSettings s;
    s.pathLength = 0.375;
    s.duration = 3.0;
    s.sampleRate = 1000;
    s.integration.accuracy = 1e-4;
    IntegrationStats stats;
    for (auto _ : state) benchmark::DoNotOptimize(runMuscleIsometric(muscle(), s, &stats));
    state.counters["steps"] = stats.steps;
}
BENCHMARK(BM_IsometricTrial3s)->Unit(benchmark::kMillisecond);

}  // namespace
