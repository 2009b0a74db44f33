// Speed of arm trials. Targets (issue 3): one 3 s isometric MVC trial under 20 ms; the five thesis
// angles under 100 ms on one thread and faster on two.
#include "model/geometry.h"
#include "model/trial.h"

#include <benchmark/benchmark.h>

using namespace armsim;

namespace {

const ArmSetup& subject() {
    static const ArmSetup s = [] {
        setenv("ARMSIM_ASSETS", ARMSIM_ASSET_DIR, 0);
        return ArmSetup::loadDefault();
    }();
    return s;
}

void BM_IsometricMvcTrial(benchmark::State& state) {
    IsometricTrialSettings s;  // 0.5 s rest + 3 s hold at 90 deg, 1000 Hz
    s.sampleRate = double(state.range(0));
    int steps = 0;
    for (auto _ : state) steps = runIsometricTrial(subject(), s).summary.stats.steps;
    state.counters["steps"] = steps;
}
BENCHMARK(BM_IsometricMvcTrial)->Arg(1000)->Arg(100)->Unit(benchmark::kMillisecond);

void BM_FiveAnglesMvc(benchmark::State& state) {
    std::vector<IsometricTrialSettings> settings;
    for (double deg : {45, 60, 90, 120, 150}) {
        IsometricTrialSettings s;
        s.elbowAngle = degToRad(deg);
        settings.push_back(s);
    }
    for (auto _ : state) benchmark::DoNotOptimize(runIsometricTrials(subject(), settings, int(state.range(0))));
}
BENCHMARK(BM_FiveAnglesMvc)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_FreeMovement2s(benchmark::State& state) {
    FreeMovementSettings s;
    for (auto _ : state) benchmark::DoNotOptimize(runFreeMovement(subject(), s));
}
BENCHMARK(BM_FreeMovement2s)->Unit(benchmark::kMillisecond);

}  // namespace
