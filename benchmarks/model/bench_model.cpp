// Speed of arm trials. Targets (issue 3): one 3 s isometric MVC trial under 20 ms; the five thesis
// angles under 100 ms on one thread and faster on two. Issue 10: a 3 s MVC of the seven-muscle elbow
// at one angle <= 40 ms; path lengths and moment arms of all its muscles at one pose <= 20 us.
#include "model/geometry.h"
#include "model/muscle_arm.h"
#include "model/mvc_curve.h"
#include "model/trial.h"

#include <benchmark/benchmark.h>

using namespace armsim;

namespace {

ArmSetup loadShippedModel(const char* name) {
    setenv("ARMSIM_ASSETS", ARMSIM_ASSET_DIR, 0);
    return loadModel(name);
}

const ArmSetup& subject() {
    static const ArmSetup s = loadShippedModel("thesis");
    return s;
}

const ArmSetup& elbow() {
    static const ArmSetup s = loadShippedModel("elbow");
    return s;
}

// One isometric trial per iteration; arg = sample rate.
void measureIsometricTrial(benchmark::State& state, const ArmSetup& setup, IsometricTrialSettings s) {
    s.sampleRate = double(state.range(0));
    int steps = 0;
    for (auto _ : state) steps = runIsometricTrial(setup, s).summary.stats.steps;
    state.counters["steps"] = steps;
}

void BM_IsometricMvcTrial(benchmark::State& state) {
    measureIsometricTrial(state, subject(), {});  // 0.5 s rest + 3 s hold at 90 deg
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

// Issue 10: 0.5 s rest + 3 s hold at 90 deg flexion, agonists 0.95, antagonists 0.10; arg = sample rate.
void BM_ElbowMvcTrial(benchmark::State& state) {
    IsometricTrialSettings s;
    s.activation = elbow().effort.voluntaryActivation;
    s.antagonistActivation = elbow().effort.coContraction;
    measureIsometricTrial(state, elbow(), s);
}
BENCHMARK(BM_ElbowMvcTrial)->Arg(1000)->Arg(100)->Unit(benchmark::kMillisecond);

// Issue 10: path length and virtual-work moment arm of all seven muscles at one pose (the pose changes
// every iteration so nothing is cached).
void BM_ElbowPathsAndMomentArms(benchmark::State& state) {
    ArmGeometry g(elbow());
    double q = 0.5, sum = 0;
    for (auto _ : state) {
        q = q < 2.5 ? q + 0.01 : 0.5;
        g.setElbowAngle(q + 0.7);
        for (int i = 0; i < g.getNumMuscles(); ++i) sum += g.calcPathLength(i) + g.calcMomentArm(i);
    }
    benchmark::DoNotOptimize(sum);
}
BENCHMARK(BM_ElbowPathsAndMomentArms)->Unit(benchmark::kMicrosecond);

// The steady MVC curve of `armsim model show` (both efforts, 29 angles).
void BM_ElbowSteadyMvcCurve(benchmark::State& state) {
    std::vector<double> q;
    for (double a = 0; a <= 140; a += 5) q.push_back(a);
    for (auto _ : state)
        for (MuscleGroup g : {MuscleGroup::Flexor, MuscleGroup::Extensor})
            benchmark::DoNotOptimize(calcSteadyMvcCurve(elbow(), g, elbow().effort, q));
}
BENCHMARK(BM_ElbowSteadyMvcCurve)->Unit(benchmark::kMillisecond);

}  // namespace
