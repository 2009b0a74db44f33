// Calling through Python vs the C++ call (issue 12: <= 5 % for a 3 s trial). Each pair runs the same
// trial with the same settings: the C++ function directly, and armsim.<function> through an embedded
// interpreter (argument parsing, the GIL release, and the result's conversion to numpy included).
#include "model/trial.h"
#include "muscles/simbody_isometric.h"

#include <benchmark/benchmark.h>
#include <pybind11/embed.h>

namespace py = pybind11;
using namespace armsim;

namespace {

const ArmSetup& thesis() {
    static const ArmSetup s = loadModel("thesis");
    return s;
}

// A 3 s isometric trial of the biceps alone at 37.5 cm, U = 1, 1000 Hz (armsim.muscle_trial's defaults).
void BM_MuscleTrial3sCpp(benchmark::State& state) {
    const VirtualMuscle m(thesis().calcBicepsParameters());
    MuscleIsometricSettings s;
    s.pathLength = 0.375;
    s.duration = 3.0;
    s.sampleRate = 1000;
    s.activation = ActivationProfile::constant(1.0);
    for (auto _ : state) benchmark::DoNotOptimize(runMuscleIsometric(m, s));
}
BENCHMARK(BM_MuscleTrial3sCpp)->Unit(benchmark::kMillisecond);

void BM_MuscleTrial3sPython(benchmark::State& state) {
    py::module_ armsim = py::module_::import("armsim");
    py::object model = armsim.attr("Model").attr("load")("thesis"), trial = armsim.attr("muscle_trial");
    for (auto _ : state) benchmark::DoNotOptimize(trial(model).ptr());
}
BENCHMARK(BM_MuscleTrial3sPython)->Unit(benchmark::kMillisecond);

// The thesis arm's MVC at 90 deg: 0.5 s rest + 3 s hold, 1000 Hz (armsim.arm_trial's defaults).
void BM_ArmMvcTrialCpp(benchmark::State& state) {
    const IsometricTrialSettings s;
    for (auto _ : state) benchmark::DoNotOptimize(runIsometricTrial(thesis(), s));
}
BENCHMARK(BM_ArmMvcTrialCpp)->Unit(benchmark::kMillisecond);

void BM_ArmMvcTrialPython(benchmark::State& state) {
    py::module_ armsim = py::module_::import("armsim");
    py::object model = armsim.attr("Model").attr("load")("thesis"), trial = armsim.attr("arm_trial");
    for (auto _ : state) benchmark::DoNotOptimize(trial(model).ptr());
}
BENCHMARK(BM_ArmMvcTrialPython)->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
    py::scoped_interpreter python;
    py::module_::import("sys").attr("path").attr("insert")(0, ARMSIM_PYTHON_DIR);
    benchmark::Initialize(&argc, argv);
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
}
