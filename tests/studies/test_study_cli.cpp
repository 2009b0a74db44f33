// armsim study end to end: threads, one MPI rank and two MPI ranks write byte-identical results; a
// study killed with SIGKILL (the whole process, or one MPI rank) and started again with the same command
// finishes with the files of an uninterrupted run; the default thread count follows the affinity mask;
// a repaired journal is reported on stderr and in the run's summary.
#include "tests/support/temp_files.h"
#include "tests/support/run_armsim.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <sched.h>
#include <sys/resource.h>
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

// Without --threads a study uses the CPUs its process may use: taskset -c 0 gives one thread.
TEST(StudyCli, DefaultThreadsAreTheCpusOfTheAffinityMask) {
    const fs::path d = freshDir("affinity");
    std::ofstream(d / "one.yaml") << "kind: study\nname: one\nsubjects: 1\nprotocols: [thesis]\nnoise_levels: [0.02]\n"
                                     "methods:\n  - {method: thesis}\n";
    cpu_set_t mask;
    ASSERT_EQ(sched_getaffinity(0, sizeof mask, &mask), 0);
    const int cpus = CPU_COUNT(&mask);
    auto threadsOf = [](const std::string& output) {
        std::smatch m;
        return std::regex_search(output, m, std::regex("rank x (\\d+) thread")) ? std::stoi(m[1]) : -1;
    };
    const CommandResult all = runArmsim("study " + (d / "one.yaml").string() + " --quiet --out " + (d / "all").string());
    ASSERT_EQ(all.exitCode, 0) << all.output;
    EXPECT_EQ(threadsOf(all.output), cpus) << all.output;
    if (runScript(d, "command -v taskset\n").exitCode != 0) GTEST_SKIP() << "taskset (util-linux) not installed";
    const CommandResult one = runScript(d, "taskset -c 0 " + std::string(ARMSIM_EXE) + " study " +
                                               (d / "one.yaml").string() + " --quiet --out " + (d / "one").string() + "\n");
    ASSERT_EQ(one.exitCode, 0) << one.output;
    EXPECT_EQ(threadsOf(one.output), 1) << one.output;
}

// A journal copied through Windows (CRLF) with junk appended: every result is kept, the junk line is
// reported (stderr warning and the summary) and the files are the first run's.
TEST(StudyCli, ARepairedJournalIsReportedOnStderrAndInTheSummary) {
    const fs::path d = freshDir("journal");
    std::ofstream(d / "two.yaml") << "kind: study\nname: two\nsubjects: 2\nprotocols: [thesis]\nnoise_levels: [0.02]\n"
                                     "methods:\n  - {method: thesis}\n";
    const std::string command = "study " + (d / "two.yaml").string() + " --threads 1 --quiet --out " + (d / "out").string();
    const CommandResult first = runArmsim(command);
    ASSERT_EQ(first.exitCode, 0) << first.output;
    const std::string reference = results(d / "out");
    const std::string journal = readText(d / "out" / "journal.log");
    std::string crlf;
    for (char c : journal) crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
    std::ofstream(d / "out" / "journal.log", std::ios::binary) << crlf << "junk after a crash\r\n";
    const CommandResult again = runArmsim(command);
    ASSERT_EQ(again.exitCode, 0) << again.output;
    EXPECT_EQ(resumedCount(again.output), 2) << again.output;
    EXPECT_NE(again.output.find("warning: journal.log: 1 line dropped (1 unreadable)"), std::string::npos) << again.output;
    EXPECT_NE(again.output.find("  journal.log: 1 line dropped (1 unreadable); 1 line named no readable task"),
              std::string::npos) << again.output;
    EXPECT_NE(readText(d / "out" / "journal_repairs.log").find("line 4: unreadable"), std::string::npos);
    EXPECT_EQ(results(d / "out"), reference);
}

// Rank 0's memory does not grow with the study: a study of 10 million subjects (1e7 cells) is started,
// stopped (SIGTERM) after its first results, and peaks within kFlatKib of a 2-subject study's peak
// (measured: 42 MB and 52 MB; the one byte of status per cell is 10 MB of it; before the cells were
// streamed, 681 MB).
TEST(StudyCli, RankZeroMemoryIsFlatInTheNumberOfTasks) {
    constexpr long kFlatKib = 40 * 1024;
    rusage before{};
    ::getrusage(RUSAGE_CHILDREN, &before);
    if (before.ru_maxrss > 0) GTEST_SKIP() << "this process ran other commands first (run the test alone, as ctest does)";
    const fs::path d = freshDir("memory");
    auto studyFile = [&](long subjects) {
        const fs::path p = d / ("study_" + std::to_string(subjects) + ".yaml");
        std::ofstream(p) << "kind: study\nname: memory\nsubjects: " << subjects << "\nseed: 1\nprotocols: [thesis]\n"
                            "noise_levels: [0.02]\nmethods:\n  - {method: thesis}\n";
        return p;
    };
    const CommandResult small = runArmsim("study " + studyFile(2).string() + " --threads 1 --quiet --out " + (d / "small").string());
    ASSERT_EQ(small.exitCode, 0) << small.output;
    rusage afterSmall{};
    ::getrusage(RUSAGE_CHILDREN, &afterSmall);
    const fs::path big = d / "big";
    const CommandResult stopped = runScript(d, std::string(ARMSIM_EXE) + " study " + studyFile(10000000).string() +
                                                   " --threads 1 --quiet --out " + big.string() + " > /dev/null 2>&1 &\n"
                                                   "job=$!\n"
                                                   "for i in $(seq 1 1500); do n=$(($(cat " + (big / "journal.log").string() +
                                                   " 2>/dev/null | wc -l) - 1)); [ $n -ge 2 ] && break; sleep 0.02; done\n"
                                                   "kill -TERM $job\nwait $job\necho exit $? after $n results\n");
    ASSERT_NE(stopped.output.find("exit 143 after"), std::string::npos) << stopped.output;
    EXPECT_EQ(stopped.output.find("after -1 results"), std::string::npos) << "no result before the stop\n" << stopped.output;
    rusage afterBig{};
    ::getrusage(RUSAGE_CHILDREN, &afterBig);
    EXPECT_LT(afterBig.ru_maxrss - afterSmall.ru_maxrss, kFlatKib)
        << "2 subjects: " << afterSmall.ru_maxrss << " KiB, 1e7 subjects: " << afterBig.ru_maxrss << " KiB";
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

TEST(StudyCli, ABadShardIsRefusedNamingTheValue) {
    const fs::path d = freshDir("bad_shard");
    for (const std::string shard : {"3/2", "x", "1/0", "-1/2", "1/2x", "/2"}) {
        const CommandResult r = runArmsim("study " + (d / "none.yaml").string() + " --shard '" + shard + "' --out " +
                                          (d / "out").string());
        EXPECT_NE(r.exitCode, 0) << shard;
        EXPECT_NE(r.output.find("--shard '" + shard + "': expected I/N"), std::string::npos) << r.output;
    }
    EXPECT_FALSE(fs::exists(d / "out"));
}
