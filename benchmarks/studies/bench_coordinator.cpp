// Scaling by simulation (issue 33): runStudy's real coordinator loop (rank 0: requests parsed and
// checksummed, results journaled with a write and flush per message, groups handed out, its own thread
// computing real groups) serving W simulated worker ranks. A simulated worker "computes" a group for a
// time drawn around T (uniform 0.5 T .. 1.5 T, seeded: the measured spread of group costs is about 3x)
// and then sends its precomputed journal lines, as a real rank would. Reported per (W, T): the groups/s
// served, the efficiency (the time the same groups take with a coordinator that costs nothing, over the
// run's) and rank 0's load (its main thread's CPU time over the run). T small enough saturates the
// coordinator: its ceiling. Rank 0's thread computes some of the groups itself (about 40 ms each), which
// matters below about 100 workers only.
#include "basics/files.h"
#include "studies/study.h"

#include <benchmark/benchmark.h>

#include <chrono>
#include <ctime>
#include <filesystem>
#include <queue>
#include <random>
#include <sstream>
#include <unistd.h>

using namespace armsim;

namespace {

using Clock = std::chrono::steady_clock;
constexpr int kCellsPerGroup = 2;

// Groups of a one-trial protocol: rank 0's own thread computes real ones (about 40 ms each).
Study makeCoordinatorStudy(int groups) {
    Study s;
    s.name = "coordinator";
    s.setPopulation(loadDefaultPopulation());
    s.subjects = groups;
    StudyProtocol one{"one.yaml", TorqueProtocol()};
    one.protocol.name = "one";
    one.protocol.conditions = TorqueProtocol::makeFlexionMvcs({90}, 1);
    s.protocols = {one};
    s.noiseLevels = {0.02};
    ElbowMethod a, b;
    a.kind = a.label = "thesis";
    b.kind = "thesis";
    b.label = "thesis2";
    s.methods = {a, b};
    return s;
}

double getThreadCpuTime() {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

// W worker ranks speaking the study's text protocol (docs/scaling.md): a request "R <want> <fingerprint>"
// with the journal lines of the worker's last group, a reply "W <no more>" with group and task numbers.
// A worker's request arrives when its group's simulated time has passed.
class SimulatedWorkers : public StudyCoordinatorLink {
public:
    SimulatedWorkers(int workers, double meanGroupTime, const std::vector<std::string>& lines,
                     const std::string& fingerprint)
        : workers_(workers), mean_(meanGroupTime), lines_(lines), fingerprint_(fingerprint),
          tasks_(std::size_t(workers) + 1) {
        const Clock::time_point now = Clock::now();
        for (int w = 1; w <= workers; ++w) arrivals_.push({now, w});
    }
    int getNumWorkers() const override { return workers_; }
    /// The run's time with a free coordinator: the drawn group times, in dispatch order, list-scheduled
    /// on the W workers (each takes the next group when it frees up).
    double calcIdealTime() const {
        std::priority_queue<double, std::vector<double>, std::greater<double>> free;
        for (int w = 0; w < workers_; ++w) free.push(0.0);
        double end = 0;
        for (double t : times_) {
            const double done = free.top() + t;
            free.pop();
            free.push(done);
            end = std::max(end, done);
        }
        return end;
    }
    bool receive(int& worker, std::string& message) override {
        if (arrivals_.empty() || arrivals_.top().first > Clock::now()) return false;
        worker = arrivals_.top().second;
        arrivals_.pop();
        message = "R 1 " + fingerprint_ + '\n';
        for (long t : tasks_[std::size_t(worker)]) message += lines_[std::size_t(t)];
        tasks_[std::size_t(worker)].clear();
        return true;
    }
    void send(int worker, const std::string& message) override {
        std::istringstream in(message);
        std::string tag, line;
        int noMore = 0;
        in >> tag >> noMore;
        std::getline(in, line);
        bool got = false;
        while (std::getline(in, line)) {
            std::istringstream l(line);
            long group = 0;
            l >> group;
            for (long t; l >> t;) tasks_[std::size_t(worker)].push_back(t);
            got = true;
        }
        if (!got && noMore) return;  // done
        const double time = got ? mean_ * std::uniform_real_distribution<double>(0.5, 1.5)(random_) : 0.2;
        if (got) times_.push_back(time);
        arrivals_.push({Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(time)),
                        worker});
    }

private:
    using Arrival = std::pair<Clock::time_point, int>;
    int workers_;
    double mean_;
    std::vector<double> times_;  // drawn group times, in dispatch order
    const std::vector<std::string>& lines_;
    std::string fingerprint_;
    std::vector<std::vector<long>> tasks_;  // by worker: the tasks it is computing
    std::priority_queue<Arrival, std::vector<Arrival>, std::greater<Arrival>> arrivals_;
    std::mt19937 random_{33};
};

// Args: workers, mean group time [ms], groups per worker.
void BM_CoordinatorWithSimulatedWorkers(benchmark::State& state) {
    const int workers = int(state.range(0));
    const double meanGroupTime = 1e-3 * double(state.range(1));
    const int groups = workers * int(state.range(2));
    const Study s = makeCoordinatorStudy(groups);
    const std::string fingerprint = calcStudyFingerprint(s);
    std::vector<std::string> lines;  // a result per task, as a worker would send it
    const std::vector<StudyResult> model = runStudyGroup(s, 0, {0, 1});
    for (long t = 0; t < s.getNumTasks(); ++t) {
        StudyResult r = model[std::size_t(t % kCellsPerGroup)];
        r.task = t;
        r.row.subject = int(t / kCellsPerGroup);
        r.rank = 1;
        lines.push_back(formatStudyJournalLine(r) + '\n');
    }
    const std::string out = std::filesystem::temp_directory_path().string() + "/armsim_bench_coordinator_" +
                            std::to_string(::getpid());
    double loop = 0, cpu0 = -1, cpu = 0, ideal = 0;
    for (auto _ : state) {
        SimulatedWorkers link(workers, meanGroupTime, lines, fingerprint);
        StudyRunOptions o;
        o.output = out;
        o.threads = 1;
        o.restart = true;
        o.progress = [&](const StudyProgress& p) {  // the coordinator's thread; the last call ends its loop
            if (cpu0 < 0) cpu0 = getThreadCpuTime();
            cpu = getThreadCpuTime() - cpu0;
            loop = p.elapsed;
        };
        benchmark::DoNotOptimize(runStudy(s, o, &link));
        ideal = link.calcIdealTime();
        state.SetIterationTime(loop);
    }
    std::filesystem::remove_all(out);
    state.counters["groups_per_s"] = double(groups) / loop;
    state.counters["offered_per_s"] = double(workers) / meanGroupTime;
    state.counters["efficiency"] = ideal / loop;  // rank 0's own groups make it up to a few % optimistic
    state.counters["rank0_load"] = cpu / loop;
}

}  // namespace

BENCHMARK(BM_CoordinatorWithSimulatedWorkers)
    ->Args({100, 500, 8})->Args({1000, 500, 8})->Args({10000, 500, 8})  // groups of 0.5 s
    ->Args({10000, 100, 8})->Args({10000, 20, 20})                                          // saturating
    ->UseManualTime()->Iterations(1)->Unit(benchmark::kMillisecond);
