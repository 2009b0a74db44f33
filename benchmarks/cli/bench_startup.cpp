// Start-up of the armsim command (issue 14: <= 50 ms for `armsim muscle steady`): the wall time of a
// whole process, spawned and waited for, for a short command that does almost no work. Rendering and
// MPI are plugins loaded only where they are used (cli/plugins.h), so this measures the loading of the
// command and its remaining libraries.
#include <benchmark/benchmark.h>

#include <spawn.h>
#include <sys/wait.h>

#include <stdexcept>
#include <string>
#include <vector>

extern char** environ;

namespace {

void runQuietly(std::vector<std::string> args) {
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", 0x1 /* O_WRONLY */, 0);
    pid_t pid = 0;
    if (posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ) != 0)
        throw std::runtime_error("cannot start " + args[0]);
    posix_spawn_file_actions_destroy(&actions);
    int status = 0;
    waitpid(pid, &status, 0);
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) throw std::runtime_error(args[0] + " failed");
}

void BM_StartupMuscleSteady(benchmark::State& state) {
    for (auto _ : state) runQuietly({ARMSIM_EXE, "muscle", "steady"});
}
BENCHMARK(BM_StartupMuscleSteady)->Unit(benchmark::kMillisecond)->UseRealTime();

// The floor of any process start on this machine: spawning /bin/true.
void BM_SpawnTrue(benchmark::State& state) {
    for (auto _ : state) runQuietly({"/bin/true"});
}
BENCHMARK(BM_SpawnTrue)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_StartupHelp(benchmark::State& state) {
    for (auto _ : state) runQuietly({ARMSIM_EXE, "--help"});
}
BENCHMARK(BM_StartupHelp)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
