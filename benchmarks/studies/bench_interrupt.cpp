// How long Ctrl-C takes to stop a long library call (issue 32: KeyboardInterrupt within 0.5 s): a
// population validation of the twin (recommended protocol, every method, two threads) is started, a stop
// is requested (requestInterruption, what the command line's and the Python module's SIGINT handlers
// call) after a delay that walks over a 0.4 s cycle, and the time from the request to the
// InterruptedError leaving runElbowValidation is measured. The loops poll the flag per integrator step,
// solver iteration, draw and task; the latency is the longest such step in flight.
#include "basics/errors.h"
#include "studies/torque_validation.h"

#include <benchmark/benchmark.h>

#include <chrono>
#include <thread>

using namespace armsim;

namespace {

using Clock = std::chrono::steady_clock;

void BM_InterruptLatency(benchmark::State& state) {
    setenv("ARMSIM_ASSETS", ARMSIM_ASSET_DIR, 0);
    static const Population population = loadDefaultPopulation();
    ElbowValidationSettings settings;
    settings.subjects = 100000;
    settings.jobs = 2;
    settings.protocol = readTorqueProtocol(std::string(ARMSIM_ASSET_DIR) + "/protocols/recommended.yaml");
    int k = 0;
    double worst = 0;
    for (auto _ : state) {
        state.PauseTiming();
        clearInterruption();
        Clock::time_point requested;
        std::thread stopper([&] {
            std::this_thread::sleep_for(std::chrono::milliseconds(300 + 37 * (k++ % 11)));
            requested = Clock::now();
            requestInterruption(2);
        });
        Clock::time_point stopped;
        try {
            runElbowValidation(population, population, settings);
        } catch (const InterruptedError&) {
            stopped = Clock::now();
        }
        stopper.join();
        const double latency = std::chrono::duration<double>(stopped - requested).count();
        worst = std::max(worst, latency);
        state.SetIterationTime(latency);
        state.ResumeTiming();
    }
    clearInterruption();
    state.counters["worst_ms"] = 1000 * worst;
}

}  // namespace

BENCHMARK(BM_InterruptLatency)->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(11);
