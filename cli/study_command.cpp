// armsim study STUDY.yaml: a population study on threads, or over MPI ranks under mpirun.
#include "basics/errors.h"
#include "cli/commands.h"
#include "cli/report.h"
#include "basics/format.h"
#include "cli/plugins.h"
#include "studies/study.h"
#include "studies/study_mpi.h"

#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <unistd.h>

namespace armsim::cli {

namespace {

struct StudyOptions {
    std::string file;
    std::string out;
    int threads = 0;
    bool restart = false;
    std::string shard;  ///< I/N
    bool merge = false;
};

// --shard I/N: an InputError naming the value unless 0 <= I < N.
void parseShard(const std::string& text, int& shard, int& shards) {
    const std::size_t slash = text.find('/');
    std::size_t used = 0, usedN = 0;
    bool ok = slash != std::string::npos && slash > 0;
    try {
        if (ok) {
            shard = std::stoi(text.substr(0, slash), &used);
            shards = std::stoi(text.substr(slash + 1), &usedN);
        }
    } catch (const std::exception&) {
        ok = false;
    }
    ok = ok && used == slash && usedN == text.size() - slash - 1 && shards >= 1 && shards <= 1000000 && shard >= 0 &&
         shard < shards;
    if (!ok)
        throw InputError("--shard '" + text + "': expected I/N, shard I of N with 0 <= I < N (e.g. 0/4 .. 3/4)");
}

// One line per report on a log; one updated line on a terminal.
void printStudyProgress(const StudyProgress& p) {
    std::fflush(stdout);
    const bool tty = isatty(fileno(stderr));
    std::fprintf(stderr, "%sstudy: %ld/%ld tasks done (%ld resumed), %ld failed, %.2f tasks/s, %s left%s",
                 tty ? "\r" : "", p.done, p.total, p.resumed, p.failed, p.rate, formatDuration(p.remaining).c_str(),
                 tty && p.done < p.total ? "   " : "\n");
    std::fflush(stderr);
}

void runStudyCommand(const StudyOptions& o) {
    StudyRunOptions run;
    run.output = o.out;
    run.threads = o.threads;
    run.restart = o.restart;
    run.merge = o.merge;
    if (!o.shard.empty()) parseShard(o.shard, run.shard, run.shards);
    if (run.shards > 0 && o.merge) throw InputError("--shard '" + o.shard + "' with --merge: expected one of them");
    if (run.shards > 0 && isLaunchedByMpi())
        throw InputError("--shard '" + o.shard + "' under MPI: a shard runs on threads (job arrays without MPI)");
    if (!isQuiet()) run.progress = printStudyProgress;
    run.notice = [](const std::string& text) {  // a repaired journal, also under --quiet
        std::fflush(stdout);
        std::fprintf(stderr, "warning: %s\n", text.c_str());
        std::fflush(stderr);
    };

    std::optional<std::pair<Study, StudyOutcome>> done;
    if (isLaunchedByMpi()) {
        done = getStudyMpiPlugin().runStudyOnMpi(o.file, run);  // every rank reads the study after MPI starts
        if (!done) return;                  // a worker rank: rank 0 reports
    } else {
        const Study study = readStudy(o.file);
        if (!isQuiet())   // the size before the work: a study of millions of tasks says so at once
            std::fprintf(stderr, "study '%s': %s, about %s of journal and results\n", study.name.c_str(),
                         study.describeSize().c_str(), formatBytes(double(study.getNumTasks()) * kStudyBytesPerTask).c_str());
        done.emplace(study, runStudy(study, run));
    }
    const Study& study = done->first;
    const StudyOutcome& r = done->second;
    if (r.shards > 0)
        std::printf("shard %d/%d: ", r.shard, r.shards);
    const std::string truths = study.truths.size() > 1 ? std::to_string(study.truths.size()) + " truths x " : "";
    std::printf("study '%s': %ld tasks (%s%d subjects x %zu protocols x %zu noise levels x %zu methods); %ld computed "
                "in %.1f s on %d rank%s x %d thread%s, %ld resumed from the journal\n",
                study.name.c_str(), r.total, truths.c_str(), study.subjects, study.protocols.size(), study.noiseLevels.size(),
                study.methods.size(), r.computed, r.wallTime, r.ranks, r.ranks == 1 ? "" : "s", r.threads,
                r.threads == 1 ? "" : "s", r.resumed);
    if (r.computed > 0)
        std::printf("  task time %.1f s (synthesis %.0f %%, identification %.0f %%); %.2f tasks/s\n", r.taskTime,
                    100 * r.synthesisTime / r.taskTime, 100 * (1 - r.synthesisTime / r.taskTime),
                    double(r.computed) / r.wallTime);
    if (r.shardJournals > 0)
        std::printf("  %d shard journal%s merged into journal.log: %ld of the resumed tasks\n", r.shardJournals,
                    r.shardJournals == 1 ? "" : "s", r.merged);
    if (!r.journalSummary.empty()) std::printf("  %s (every line in journal_repairs.log)\n", r.journalSummary.c_str());
    if (r.failed + r.notConverged > 0)
        std::printf("  %ld failed, %ld not converged: their reasons are in results.csv (status, reason)%s\n", r.failed,
                    r.notConverged, r.shards > 0 ? " once the shards are merged" : "");
    setReportFolder(r.output);   // --out, or the study file's `output:`
    std::printf("wrote to %s:", r.output.c_str());
    for (const std::string& f : r.files) std::printf(" %s", f.c_str());
    std::printf("\n");
}

void addStudyCommand(CLI::App& app) {
    auto o = std::make_shared<StudyOptions>();
    CLI::App* c = app.add_subcommand(
        "study", "Monte Carlo study of identifiers over virtual subjects, protocols and noise levels (threads; "
                 "`mpirun -n K armsim study` spreads it over MPI ranks); resumes after an interruption");
    c->add_option("study", o->file, "study file (kind: study)")->required();
    c->add_option("--out", o->out, "output folder (default: the study's `output`)");
    c->add_option("--threads", o->threads, "worker threads per process (default: the CPUs it may use, its "
                                           "affinity mask as set by taskset or Slurm; shared by the ranks of a "
                                           "node under MPI when they all see the whole node)")
        ->transform(inRange(1, kMaxStudyThreads));
    c->add_flag("--restart", o->restart, "discard the output folder's journal and compute every task again");
    c->add_option("--shard", o->shard, "I/N: compute shard I of N (0 <= I < N; the groups g with g % N == I) "
                                       "into its own journal, for job arrays; the next run without --shard "
                                       "merges the shards' journals and writes the files");
    c->add_flag("--merge", o->merge, "only assemble the journals (the shards') into the files; an error when "
                                     "cells are missing");
    c->callback([o, c] {
        if (o->merge && c->count("--threads"))   // --merge computes nothing
            throw InputError("--threads " + std::to_string(o->threads) + " with --merge: --merge only assembles the "
                             "journals into the files (an error when cells are missing), so the threads would be ignored");
        runStudyCommand(*o);
    });
}

const CommandRegistrar registerStudy(58, addStudyCommand);

}  // namespace

}  // namespace armsim::cli
