// EMG signal processing: the acquisition chain on 3 s at 10 kHz, spectral features on 3 s at 1 kHz.
#include "experiments/signal.h"
#include "experiments/spectrum.h"

#include <benchmark/benchmark.h>

#include <random>
#include <vector>

namespace {

std::vector<double> noise(std::size_t n, double sigma, unsigned seed) {
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> d(0.0, sigma);
    std::vector<double> x(n);
    for (double& v : x) v = d(rng);
    return x;
}

// 3 s of 10 kHz electrode signal -> 3000 samples at 1 kHz, with mains and electrode noise on.
void BM_AcquireEmg3s(benchmark::State& state) {
    const std::vector<double> x = noise(30000, 1e-4, 1);
    armsim::EmgAcquisitionSettings s;
    s.mainsAmplitude = 1e-4;
    s.electrodeNoiseRms = 5e-6;
    s.zeroPhase = state.range(0) != 0;
    auto rng = armsim::PortableRandom::fromSeed(2);
    for (auto _ : state) benchmark::DoNotOptimize(armsim::calcAcquiredEmg(x, 10000, s, rng));
}
BENCHMARK(BM_AcquireEmg3s)->Arg(0)->Arg(1)->ArgName("zeroPhase")->Unit(benchmark::kMicrosecond);

// PSD (segment length = Arg; 0 = whole-signal periodogram) plus MNF and MDF over 10-400 Hz.
void BM_SpectralFeatures3s(benchmark::State& state) {
    const std::vector<double> x = noise(3000, 1e-3, 3);
    armsim::SpectrumSettings s;
    s.segmentLength = std::size_t(state.range(0));
    for (auto _ : state) {
        const armsim::PowerSpectrum p = armsim::calcPowerSpectrum(x, 1000, s);
        benchmark::DoNotOptimize(armsim::calcMeanFrequency(p, 10, 400));
        benchmark::DoNotOptimize(armsim::calcMedianFrequency(p, 10, 400));
    }
}
BENCHMARK(BM_SpectralFeatures3s)->Arg(0)->Arg(256)->ArgName("segment")
    ->Unit(benchmark::kMicrosecond);

}  // namespace
