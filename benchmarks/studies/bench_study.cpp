// The study machinery's cost (issue 13): the same 8 groups (8 subjects x the thesis protocol x 2 %
// noise x {thesis, synergist}) computed by calling runStudyGroup in a loop, and by runStudy on one
// thread (scheduling, the journal, the final CSVs and plots). The ratio of the two is the machinery's
// overhead (goal <= 2 % of task time). BM_StudyRecordRoundTrip is what one task costs on the wire and in
// the journal (format, checksum, parse).
#include "studies/study.h"

#include <benchmark/benchmark.h>

#include <filesystem>
#include <unistd.h>

using namespace armsim;

namespace {

const Study& benchStudy() {
    static const Study s = [] {
        Study x;
        x.name = "bench";
        x.setPopulation(loadDefaultPopulation());
        x.subjects = 8;
        x.protocols = {{"thesis", TorqueProtocol()}};
        x.noiseLevels = {0.02};
        ElbowMethod a, b;
        a.kind = a.label = "thesis";
        b.kind = b.label = "synergist";
        x.methods = {a, b};
        return x;
    }();
    return s;
}

void BM_StudyGroupsDirect(benchmark::State& state) {
    const Study& s = benchStudy();
    for (auto _ : state)
        for (long g = 0; g < s.getNumGroups(); ++g) benchmark::DoNotOptimize(runStudyGroup(s, g, {2 * g, 2 * g + 1}));
    state.counters["tasks"] = double(s.getNumTasks());
}

void BM_StudyRunOneThread(benchmark::State& state) {
    const Study& s = benchStudy();
    const std::string out = std::filesystem::temp_directory_path().string() + "/armsim_bench_study_" + std::to_string(::getpid());
    StudyRunOptions o;
    o.output = out;
    o.threads = 1;
    o.restart = true;  // every iteration computes every task
    for (auto _ : state) benchmark::DoNotOptimize(runStudy(s, o));
    std::filesystem::remove_all(out);
    state.counters["tasks"] = double(s.getNumTasks());
}

void BM_StudyRecordRoundTrip(benchmark::State& state) {
    const std::vector<StudyResult> r = runStudyGroup(benchStudy(), 0, {0, 1});
    StudyResult back;
    for (auto _ : state) {
        const std::string line = formatStudyJournalLine(r[1]);
        benchmark::DoNotOptimize(parseStudyJournalLine(line, back));
    }
}

}  // namespace

BENCHMARK(BM_StudyGroupsDirect)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_StudyRunOneThread)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_StudyRecordRoundTrip)->Unit(benchmark::kMicrosecond);
