// armsim study end to end: threads, one MPI rank and two MPI ranks write byte-identical results; a
// study killed with SIGKILL (the whole process, or one MPI rank) and started again with the same command
// finishes with the files of an uninterrupted run.
#include "tests/support/temp_files.h"
#include "tests/support/run_armsim.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <unistd.h>

namespace fs = std::filesystem;
using armsim::testing::CommandResult;
using armsim::testing::runArmsim;

namespace {

fs::path freshDir(const std::string& name) { return armsim::testing::makeFreshDir("study_cli", name); }
std::string readText(const fs::path& p) { return armsim::testing::readFileText(p); }

constexpr int kTasks = 4 * 2 * 1 * 2;  // subjects x protocols x noise levels x methods

// The study: the thesis protocol and a one-angle protocol on which the thesis method fails by design.
fs::path writeStudy(const fs::path& d) {
    std::ofstream(d / "one_angle.yaml") << "kind: torque\nname: one_angle\nconditions:\n"
                                           "  - {flexion_deg: 90, effort: flexion, level: 1, repetitions: 3}\n";
    std::ofstream(d / "study.yaml") << "kind: study\nname: cli\nsubjects: 4\nseed: 3\nprotocols: [thesis, one_angle.yaml]\n"
                                       "noise_levels: [0.02]\nmethods:\n  - {method: thesis}\n  - {method: synergist}\n"
                                       "output: " << (d / "default_out").string() << "\n";
    return d / "study.yaml";
}

// Runs a bash script (for mpirun, background jobs and kill).
CommandResult runScript(const fs::path& dir, const std::string& script) {
    const fs::path p = dir / "script.sh";
    std::ofstream(p) << "set -u\n" << script;
    std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(("bash " + p.string() + " 2>&1").c_str(), "r"), pclose);
    std::string out;
    char buf[4096];
    while (std::fgets(buf, sizeof buf, pipe.get())) out += buf;
    const int status = pclose(pipe.release());
    return {WEXITSTATUS(status), out};
}

std::string mpirun() {
    return std::string("mpirun ") + (::getuid() == 0 ? "--allow-run-as-root " : "") + "--oversubscribe ";
}

std::string results(const fs::path& out) { return readText(out / "results.csv") + readText(out / "summary.csv"); }

int resumedCount(const std::string& output) {
    std::smatch m;
    if (!std::regex_search(output, m, std::regex("computed in .*, (\\d+) resumed from the journal"))) return -1;
    return std::stoi(m[1]);
}

// Waits (in the script) until the journal holds `lines` results, then kills `pid` with SIGKILL.
std::string killAfter(const fs::path& journal, int lines, const std::string& pid) {
    return "for i in $(seq 1 600); do n=$(($(cat " + journal.string() + " 2>/dev/null | wc -l) - 1)); "
           "[ $n -ge " + std::to_string(lines) + " ] && break; sleep 0.02; done\n"
           "kill -9 " + pid + "\nwait $job 2>/dev/null\necho killed after $n results\n";
}

}  // namespace

TEST(StudyCli, ThreadsOneRankAndTwoRanksWriteByteIdenticalResults) {
    const fs::path d = freshDir("ranks");
    const fs::path study = writeStudy(d);
    const CommandResult threads = runArmsim("study " + study.string() + " --threads 2 --out " + (d / "threads").string());
    ASSERT_EQ(threads.exitCode, 0) << threads.output;
    EXPECT_NE(threads.output.find(std::to_string(kTasks) + " tasks"), std::string::npos) << threads.output;
    EXPECT_NE(threads.output.find("4 failed"), std::string::npos) << threads.output;  // thesis x one angle x 4
#if ARMSIM_HAVE_MPI
    for (int ranks : {1, 2}) {
        const fs::path out = d / ("mpi" + std::to_string(ranks));
        const CommandResult r = runScript(d, mpirun() + "-n " + std::to_string(ranks) + " " + ARMSIM_EXE + " study " +
                                                 study.string() + " --threads 1 --quiet --out " + out.string() + "\n");
        ASSERT_EQ(r.exitCode, 0) << r.output;
        EXPECT_NE(r.output.find("on " + std::to_string(ranks) + " rank"), std::string::npos) << r.output;
        EXPECT_EQ(results(out), results(d / "threads")) << ranks << " ranks";
        std::set<std::string> ranksSeen;  // timing.csv: task,rank,...: dynamic balancing gave every rank work
        std::istringstream timing(readText(out / "timing.csv"));
        std::string line;
        std::getline(timing, line);
        while (std::getline(timing, line)) ranksSeen.insert(line.substr(line.find(',') + 1, 1));
        EXPECT_EQ(int(ranksSeen.size()), ranks) << readText(out / "timing.csv");
    }
#else
    GTEST_SKIP() << "armsim built without MPI: the threaded run was checked, the MPI runs were not";
#endif
}

TEST(StudyCli, AStudyKilledMidwayAndStartedAgainFinishesWithTheUninterruptedFiles) {
    const fs::path d = freshDir("kill");
    const fs::path study = writeStudy(d);
    const CommandResult full = runArmsim("study " + study.string() + " --threads 1 --quiet --out " + (d / "full").string());
    ASSERT_EQ(full.exitCode, 0) << full.output;

    const fs::path out = d / "killed";
    const std::string command = std::string(ARMSIM_EXE) + " study " + study.string() + " --threads 1 --quiet --out " +
                                out.string();
    const CommandResult killed = runScript(d, command + " > /dev/null 2>&1 &\njob=$!\n" +
                                                  killAfter(out / "journal.log", 3, "$job"));
    ASSERT_NE(killed.output.find("killed"), std::string::npos) << killed.output;
    const CommandResult again = runArmsim("study " + study.string() + " --threads 1 --quiet --out " + out.string());
    ASSERT_EQ(again.exitCode, 0) << again.output;
    const int resumed = resumedCount(again.output);
    EXPECT_GE(resumed, 3) << again.output;
    EXPECT_LT(resumed, kTasks) << "the kill came after the end: nothing was resumed\n" << again.output;
    EXPECT_EQ(results(out), results(d / "full"));
}

#if ARMSIM_HAVE_MPI
// mpirun aborts the job when one rank dies; the same command then finishes the missing tasks.
TEST(StudyCli, AnMpiStudyWithOneRankKilledFinishesWhenStartedAgain) {
    const fs::path d = freshDir("rank_kill");
    const fs::path study = writeStudy(d);
    const CommandResult full = runArmsim("study " + study.string() + " --threads 2 --quiet --out " + (d / "full").string());
    ASSERT_EQ(full.exitCode, 0) << full.output;

    const fs::path out = d / "killed";
    const std::string command = mpirun() + "-n 2 " + ARMSIM_EXE + " study " + study.string() +
                                " --threads 1 --quiet --out " + out.string();
    // Kill the worker rank (the youngest armsim child of mpirun), not mpirun itself.
    const CommandResult killed = runScript(
        d, command + " > /dev/null 2>&1 &\njob=$!\n" +
               killAfter(out / "journal.log", 3, "$(pgrep -n -P $job armsim || pgrep -n -f 'armsim study " +
                                                     study.string() + "')"));
    ASSERT_NE(killed.output.find("killed"), std::string::npos) << killed.output;
    const CommandResult again = runScript(d, command + "\n");
    ASSERT_EQ(again.exitCode, 0) << again.output;
    const int resumed = resumedCount(again.output);
    EXPECT_GE(resumed, 3) << again.output;
    EXPECT_LT(resumed, kTasks) << again.output;
    EXPECT_EQ(results(out), results(d / "full"));
}
#endif
