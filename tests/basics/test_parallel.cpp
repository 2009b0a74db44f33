#include "basics/errors.h"
#include "basics/parallel.h"

#include <gtest/gtest.h>

#include <atomic>
#include <csignal>
#include <stdexcept>
#include <thread>
#include <vector>

#include <sched.h>

using namespace armsim;

TEST(RunParallel, RunsEveryTaskOnceAndReportsProgressInOrder) {
    for (int jobs : {1, 2, 7}) {
        std::vector<std::atomic<int>> runs(50);
        std::vector<int> reported;
        runParallel(50, jobs, [&](int i) { ++runs[i]; }, [&](int done, int total) {
            EXPECT_EQ(total, 50);
            reported.push_back(done);
        });
        for (auto& r : runs) EXPECT_EQ(r.load(), 1);
        ASSERT_FALSE(reported.empty());
        EXPECT_EQ(reported.back(), 50);
        for (std::size_t k = 1; k < reported.size(); ++k) EXPECT_GT(reported[k], reported[k - 1]);
    }
}

TEST(RunParallel, FirstErrorStopsTasksNotYetStartedAndIsRethrown) {
    std::atomic<int> started{0};
    try {
        runParallel(1000, 1, [&](int i) {
            ++started;
            if (i == 3) throw std::runtime_error("task 3 failed");
        });
        ADD_FAILURE() << "no exception";
    } catch (const std::runtime_error& e) {
        EXPECT_STREQ(e.what(), "task 3 failed");
    }
    EXPECT_EQ(started.load(), 4);  // one thread: tasks 0..3, then nothing
}

TEST(RunParallel, InterruptionStopsBeforeTheNextTask) {
    std::atomic<int> started{0};
    EXPECT_THROW(runParallel(100, 1, [&](int i) {
        ++started;
        if (i == 0) requestInterruption(SIGINT);
    }), InterruptedError);
    requestInterruption(0);
    EXPECT_EQ(started.load(), 1);  // checked before task 1
    EXPECT_EQ(getInterruption(), 0);
}

// The default thread count follows the affinity mask (taskset, Slurm's binding), not the machine.
TEST(UsableCpus, CountTheAffinityMask) {
    cpu_set_t mask;
    ASSERT_EQ(sched_getaffinity(0, sizeof mask, &mask), 0);
    EXPECT_EQ(getNumUsableCpus(), CPU_COUNT(&mask));
    int first = 0;
    while (!CPU_ISSET(first, &mask)) ++first;
    int restricted = 0;
    std::thread([&] {  // the mask is per thread: narrow this one to a single CPU, as `taskset -c` does
        cpu_set_t one;
        CPU_ZERO(&one);
        CPU_SET(first, &one);
        if (sched_setaffinity(0, sizeof one, &one) == 0) restricted = getNumUsableCpus();
    }).join();
    EXPECT_EQ(restricted, 1);
}

TEST(UsableCpus, RanksShareTheNodeUnlessBoundToTheirOwnCpus) {
    EXPECT_EQ(calcThreadsPerRank(2, 2, 1), 2);    // one rank, the whole node
    EXPECT_EQ(calcThreadsPerRank(2, 2, 2), 1);    // two unbound ranks share two CPUs
    EXPECT_EQ(calcThreadsPerRank(64, 64, 4), 16);
    EXPECT_EQ(calcThreadsPerRank(1, 2, 2), 1);    // mpirun's bind-to-core
    EXPECT_EQ(calcThreadsPerRank(8, 64, 2), 8);   // srun --cpus-per-task=8 with task binding
    EXPECT_EQ(calcThreadsPerRank(32, 64, 8), 8);  // bound to a socket shared by four ranks: its share
    EXPECT_EQ(calcThreadsPerRank(4, 2, 3), 1);    // never below one
}
