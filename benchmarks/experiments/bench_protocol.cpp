// The thesis MVC protocol end to end (assets/protocols/mvc_force_angle.yaml: five angles x three
// repetitions, 3 s holds at 1000 Hz, synthetic EMG and transducer noise) on 2 threads, with and
// without writing its files; and the synthetic EMG of one 3.5 s trial.
#include "experiments/emg.h"
#include "experiments/protocol.h"
#include "muscles/muscle_file.h"

#include <benchmark/benchmark.h>

#include <filesystem>
#include <unistd.h>

namespace {

const std::string kMvc = std::string(ARMSIM_ASSET_DIR) + "/protocols/mvc_force_angle.yaml";

// Arg: 1 = write the run directory (per-trial CSV + .sto, tables, plots, manifest), 0 = compute only.
void BM_MvcProtocol(benchmark::State& state) {
    const armsim::Protocol p = armsim::readProtocol(kMvc);
    const armsim::ArmSetup subject = armsim::loadProtocolSubject(p);
    const std::string out = state.range(0)
        ? (std::filesystem::temp_directory_path() / ("armsim_bench_mvc_" + std::to_string(::getpid()))).string()
        : "";
    for (auto _ : state) benchmark::DoNotOptimize(armsim::runProtocol(p, subject, {out, 2, {}}));
    if (!out.empty()) std::filesystem::remove_all(out);
}
BENCHMARK(BM_MvcProtocol)->Arg(0)->Arg(1)->ArgName("files")->Unit(benchmark::kMillisecond)->UseRealTime()
    ->Iterations(3)->Repetitions(5)->ReportAggregatesOnly(true);

// One MVC trial's EMG: 3501 samples at 1000 Hz from 10 kHz synthesis, 3 + 3 units x 20 trains.
void BM_SurfaceEmgTrial(benchmark::State& state) {
    const armsim::VirtualMuscle m(
        armsim::loadMuscleParameters(std::string(ARMSIM_ASSET_DIR) + "/muscles/biceps_long_head.yaml"));
    const armsim::ActivationProfile U = armsim::ActivationProfile::step(0.5, 0.0, 1.0);
    armsim::SurfaceEmgSettings s;
    s.acquisition.electrodeNoiseRms = 5e-6;
    auto rng = armsim::PortableRandom::fromSeed(1);
    for (auto _ : state) benchmark::DoNotOptimize(armsim::calcSurfaceEmg(m, U, 0.0, 3501, s, rng));
}
BENCHMARK(BM_SurfaceEmgTrial)->Unit(benchmark::kMillisecond);

}  // namespace
