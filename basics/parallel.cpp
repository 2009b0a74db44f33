#include "basics/parallel.h"

#include "basics/errors.h"

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

#include <sched.h>

namespace armsim {

void runParallel(int n, int jobs, const std::function<void(int)>& task,
                 const std::function<void(int, int)>& onDone) {
    if (n <= 0) return;
    std::atomic<int> next{0};
    std::atomic<bool> stop{false};
    std::mutex mutex;
    std::condition_variable finished;
    int done = 0;  // tasks finished, failed or skipped: reaches n in every case
    std::exception_ptr error;
    auto fail = [&] {
        std::lock_guard<std::mutex> lock(mutex);
        if (!error) error = std::current_exception();
        stop = true;
    };
    auto worker = [&] {
        for (int i = next++; i < n; i = next++) {
            if (!stop) {
                try {
                    checkInterruption();
                    task(i);
                } catch (...) {
                    fail();
                }
            }
            std::lock_guard<std::mutex> lock(mutex);
            ++done;
            finished.notify_all();
        }
    };
    std::vector<std::thread> threads;
    const int numThreads = std::max(1, std::min(jobs, n));
    for (int k = 0; k < numThreads; ++k) threads.emplace_back(worker);
    for (int reported = 0; reported < n;) {
        int now;
        {
            std::unique_lock<std::mutex> lock(mutex);
            finished.wait(lock, [&] { return done != reported; });
            now = done;
        }
        // Tasks may finish together: every count is reported, in order.
        for (; reported < now; ++reported) {
            if (stop || !onDone) continue;
            try {
                onDone(reported + 1, n);
            } catch (...) {
                fail();
            }
        }
    }
    for (auto& t : threads) t.join();
    if (error) std::rethrow_exception(error);
}

int getNumUsableCpus() {
    cpu_set_t mask;
    CPU_ZERO(&mask);
    if (sched_getaffinity(0, sizeof mask, &mask) == 0) {
        const int n = CPU_COUNT(&mask);
        if (n > 0) return n;
    }
    return int(std::max(1u, std::thread::hardware_concurrency()));
}

int calcThreadsPerRank(int usableCpus, int nodeCpus, int localRanks) {
    usableCpus = std::max(1, usableCpus);
    localRanks = std::max(1, localRanks);
    const int share = std::max(1, std::max(nodeCpus, usableCpus) / localRanks);
    return usableCpus < nodeCpus ? std::min(usableCpus, share) : share;
}

}  // namespace armsim
