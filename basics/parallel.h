// A small fixed-size worker pool for independent simulations (one Simbody System per task).
#pragma once

#include <functional>

namespace armsim {

/// Runs task(0 .. n-1) on `jobs` threads. onDone(done, n) runs in the caller's thread once for every
/// finished task, with done = 1, 2, ..., n in order (for progress). The first exception, from a task or from onDone, stops the tasks not yet
/// started and is rethrown once every thread has joined. Tasks must not share mutable state.
void runParallel(int n, int jobs, const std::function<void(int)>& task,
                 const std::function<void(int done, int total)>& onDone = {});

}  // namespace armsim
