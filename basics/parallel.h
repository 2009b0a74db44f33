// A small fixed-size worker pool for independent simulations (one Simbody System per task), and the
// default number of worker threads: the CPUs this process may use.
#pragma once

#include <functional>

namespace armsim {

/// Runs task(0 .. n-1) on `jobs` threads. onDone(done, n) runs in the caller's thread once for every
/// finished task, with done = 1, 2, ..., n in order (for progress). The first exception, from a task or from onDone, stops the tasks not yet
/// started and is rethrown once every thread has joined. Tasks must not share mutable state.
void runParallel(int n, int jobs, const std::function<void(int)>& task,
                 const std::function<void(int done, int total)>& onDone = {});

/// The CPUs this process may run on: the count of its affinity mask (sched_getaffinity), which
/// taskset, Slurm's and mpirun's task binding and a container's cpuset restrict; the machine's
/// hardware threads where the mask cannot be read. At least 1.
int getNumUsableCpus();

/// Default worker threads of one MPI rank: a rank whose mask is its own (bound by the launcher, so
/// narrower than the node: usableCpus < nodeCpus) uses its CPUs, but no more than its share of the
/// node; ranks that all see the whole node share it. localRanks: ranks on this node. At least 1.
int calcThreadsPerRank(int usableCpus, int nodeCpus, int localRanks);

}  // namespace armsim
