#include "basics/errors.h"
#include "basics/parallel.h"

#include <gtest/gtest.h>

#include <atomic>
#include <csignal>
#include <stdexcept>
#include <vector>

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
