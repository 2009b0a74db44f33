// The study's machinery: the output folder (lock, journal, final files), the worker threads of one
// process, the coordinator (rank 0) and the worker-rank loop. The numbers come from runStudyGroup.
#include "basics/bound.h"
#include "basics/errors.h"
#include "basics/files.h"
#include "basics/format.h"
#include "basics/parallel.h"
#include "basics/plot.h"
#include "studies/study.h"

#include <algorithm>
#include <chrono>
#include <cerrno>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <exception>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>
#include <thread>

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

namespace armsim {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// Cells of one (subject, protocol) still to compute.
struct GroupWork {
    long group = 0;
    std::vector<long> tasks;
};

std::string formatWork(const std::vector<GroupWork>& work, bool noMore) {
    std::ostringstream s;
    s << "W " << (noMore ? 1 : 0) << '\n';
    for (const GroupWork& w : work) {
        s << w.group;
        for (long t : w.tasks) s << ' ' << t;
        s << '\n';
    }
    return s.str();
}

std::vector<GroupWork> parseWork(const std::string& text, bool& noMore) {
    std::istringstream in(text);
    std::string tag, line;
    int flag = 0;
    if (!(in >> tag >> flag) || tag != "W") throw std::logic_error("study: malformed work message");
    noMore = flag != 0;
    std::getline(in, line);
    std::vector<GroupWork> out;
    while (std::getline(in, line)) {
        std::istringstream l(line);
        GroupWork w;
        l >> w.group;
        for (long t; l >> t;) w.tasks.push_back(t);
        out.push_back(w);
    }
    return out;
}

// A request carries the worker's study fingerprint: every rank must have read the same study.
std::string formatRequest(int want, const std::string& fingerprint, const std::vector<StudyResult>& results) {
    std::string s = "R " + std::to_string(want) + ' ' + fingerprint + '\n';
    for (const StudyResult& r : results) s += formatStudyJournalLine(r) + '\n';
    return s;
}

std::vector<StudyResult> parseRequest(const std::string& text, int& want, std::string& fingerprint) {
    std::istringstream in(text);
    std::string tag, line;
    if (!(in >> tag >> want >> fingerprint) || tag != "R") throw std::logic_error("study: malformed request message");
    std::getline(in, line);
    std::vector<StudyResult> out;
    while (std::getline(in, line)) {
        StudyResult r;
        if (!parseStudyJournalLine(line, r)) throw std::logic_error("study: corrupt result in a worker's message");
        out.push_back(std::move(r));
    }
    return out;
}

// The threads of one process: groups in, results out.
class LocalWorkers {
public:
    LocalWorkers(const Study& study, int threads, int rank) {
        try {
            start(study, threads, rank);
        } catch (...) {  // a thread could not be created: stop the ones that were
            stop();
            throw;
        }
    }
    ~LocalWorkers() { stop(); }
    int getNumThreads() const { return int(threads_.size()); }
    void add(GroupWork w) {
        std::lock_guard<std::mutex> lock(mutex_);
        work_.push_back(std::move(w));
        workReady_.notify_one();
    }
    // Finished groups (waits up to `wait` for the first); the number of groups they came from via `groups`.
    std::vector<StudyResult> take(std::chrono::milliseconds wait, int& groups) {
        std::unique_lock<std::mutex> lock(mutex_);
        resultReady_.wait_for(lock, wait, [this] { return !results_.empty() || error_; });
        if (error_) std::rethrow_exception(error_);
        std::vector<StudyResult> out;
        groups = int(results_.size());
        for (auto& r : results_) out.insert(out.end(), std::make_move_iterator(r.begin()), std::make_move_iterator(r.end()));
        results_.clear();
        return out;
    }

private:
    void start(const Study& study, int threads, int rank) {
        for (int i = 0; i < threads; ++i)
            threads_.emplace_back([this, &study, rank] { work(study, rank); });
    }
    void stop() {
        {
            std::lock_guard<std::mutex> lock(mutex_);
            closed_ = true;
            work_.clear();
        }
        workReady_.notify_all();
        for (std::thread& t : threads_) t.join();
        threads_.clear();
    }
    void work(const Study& study, int rank) {
        for (;;) {
            GroupWork w;
            {
                std::unique_lock<std::mutex> lock(mutex_);
                workReady_.wait(lock, [this] { return closed_ || !work_.empty(); });
                if (work_.empty()) return;
                w = std::move(work_.front());
                work_.pop_front();
            }
            std::vector<StudyResult> r;
            std::exception_ptr error;
            try {
                r = runStudyGroup(study, w.group, w.tasks, rank);
            } catch (...) {
                error = std::current_exception();
            }
            std::lock_guard<std::mutex> lock(mutex_);
            if (error && !error_) error_ = error;
            results_.push_back(std::move(r));
            resultReady_.notify_all();
        }
    }

    std::mutex mutex_;
    std::condition_variable workReady_, resultReady_;
    std::deque<GroupWork> work_;
    std::deque<std::vector<StudyResult>> results_;
    std::exception_ptr error_;
    bool closed_ = false;
    std::vector<std::thread> threads_;
};

// The output folder: an exclusive lock for this run (released by the kernel when the process dies) and
// the journal of finished cells. A shard (--shard I/N) has its own lock and journal
// (journal-shard-I-of-N.log), so the shards of a job array run side by side; a plain run merges every
// shard journal of the study into journal.log and removes them.
class StudyFolder {
public:
    StudyFolder(const std::string& dir, const std::string& fingerprint, const Study& study, bool restart,
                int shard = 0, int shards = 0)
        : dir_(dir) {
        std::error_code ec;
        fs::create_directories(dir_, ec);
        if (ec || !fs::is_directory(dir_, ec))
            throw InputError("study output '" + dir_ + "': cannot create the folder" + (ec ? ": " + ec.message() : ""));
        const std::string suffix = shards > 0 ? "-shard-" + std::to_string(shard) + "-of-" + std::to_string(shards) : "";
        if (!lockFile(".lock" + suffix, lock_))
            throw InputError("study output '" + dir_ + "': another armsim study" +
                             (shards > 0 ? " of shard " + std::to_string(shard) + "/" + std::to_string(shards) : "") +
                             " is running in this folder");
        journalName_ = shards > 0 ? "journal" + suffix + ".log" : "journal.log";
        journalPath_ = dir_ + "/" + journalName_;
        const std::string header = "# armsim study journal; fingerprint " + fingerprint + "; study " + study.name;
        std::string kept = header + '\n';
        if (doesPathExist(journalPath_) && !restart) {
            StudyJournal journal = readJournal(readFileText(journalPath_), fingerprint, study);
            for (const std::string& line : journal.lines) kept += line + '\n';
            summary_ = summarizeStudyJournalDrops(journal.dropped, &journal, journalName_);
            if (!headerNote_.empty()) summary_ = (summary_.empty() ? journalName_ + ": " : summary_ + "; ") + headerNote_;
            done_ = std::move(journal.results);
            dropped_ = std::move(journal.dropped);
        } else if (restart) {
            std::remove((dir_ + "/journal_repairs.log").c_str());  // the repairs of a discarded journal
        }
        const std::vector<std::string> merged = shards > 0 ? std::vector<std::string>() : mergeShards(fingerprint, study, restart, kept);
        writeFileAtomically(journalPath_, kept);  // compacted: valid lines only, so appends start on a clean line
        for (const std::string& name : merged) {  // now in journal.log
            std::remove((dir_ + "/" + name).c_str());
            std::remove((dir_ + "/.lock" + name.substr(7, name.size() - 11)).c_str());
        }
        shardLocks_.clear();
        journal_.reset(std::fopen(journalPath_.c_str(), "ab"));
        if (!journal_) throw InputError("study output '" + dir_ + "': cannot append to " + journalName_);
    }
    const std::map<long, StudyResult>& getDone() const { return done_; }
    const std::vector<StudyJournalDrop>& getDropped() const { return dropped_; }
    const std::string& getDroppedSummary() const { return summary_; }
    long getNumMerged() const { return merged_; }
    int getNumShardJournals() const { return shardJournals_; }
    const std::string& getJournalName() const { return journalName_; }
    // Appends what the journal dropped to journal_repairs.log (one write), so the repair stays on record
    // after the compacted journal no longer shows it.
    void recordRepairs() const {
        if (summary_.empty()) return;
        const std::string text = "# " + journalName_ + " read at the start of a run\n" + summary_ + '\n' +
                                 formatStudyJournalDrops(dropped_);
        std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen((dir_ + "/journal_repairs.log").c_str(), "ab"),
                                                            std::fclose);
        if (!f || std::fwrite(text.data(), 1, text.size(), f.get()) != text.size() || std::fflush(f.get()) != 0)
            throw InputError("study output '" + dir_ + "': cannot append to journal_repairs.log");
    }
    // Journals results (one write and flush: a kill leaves at most one torn line).
    void append(const std::vector<StudyResult>& results) {
        std::string text;
        for (const StudyResult& r : results) {
            text += formatStudyJournalLine(r) + '\n';
            done_.emplace(r.task, r);
        }
        if (std::fwrite(text.data(), 1, text.size(), journal_.get()) != text.size() || std::fflush(journal_.get()) != 0)
            throw InputError("study output '" + dir_ + "': cannot append to " + journalName_);
    }

private:
    struct Lock {  // closing the descriptor releases the lock, also when the constructor throws
        int fd = -1;
        Lock() = default;
        Lock(Lock&& o) noexcept : fd(o.fd) { o.fd = -1; }
        Lock& operator=(Lock&&) = delete;
        ~Lock() {
            if (fd >= 0) ::close(fd);
        }
    };

    // Takes the lock file `name` in the folder: false when another process holds it.
    bool lockFile(const std::string& name, Lock& lock) const {
        lock.fd = ::open((dir_ + "/" + name).c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
        if (lock.fd < 0) throw InputError("study output '" + dir_ + "': cannot write in the folder");
        if (::flock(lock.fd, LOCK_EX | LOCK_NB) == 0) return true;
        if (errno == EWOULDBLOCK) return false;
        throw InputError("study output '" + dir_ + "': cannot lock " + dir_ + "/" + name + " (" + std::strerror(errno) +
                         "): the file system does not support flock (Lustre: mount with -o flock); use an "
                         "output folder on another file system");
    }

    // The header: "intact" (with its fingerprint in `theirs`) or damaged.
    static bool readHeader(const std::string& text, std::size_t& end, std::string& theirs) {
        end = std::min(text.find('\n'), text.size());
        std::string first = text.substr(0, end);
        while (!first.empty() && (first.back() == '\r' || first.back() == ' ')) first.pop_back();
        const std::string prefix = "# armsim study journal; fingerprint ";
        const bool intact = first.rfind(prefix, 0) == 0 && first.size() >= prefix.size() + 16 &&
                            first.find_first_not_of("0123456789abcdef", prefix.size()) == prefix.size() + 16 &&
                            first.compare(prefix.size() + 16, 8, "; study ") == 0;
        if (intact) theirs = first.substr(prefix.size(), 16);
        return intact;
    }

    // The journal's results. An intact header of another fingerprint is refused; a damaged header (an
    // editor, a disk error) is recovered when the journal's first result, computed again now, is the
    // same: the journal is then this study's, whatever its header says.
    StudyJournal readJournal(const std::string& text, const std::string& fingerprint, const Study& study) {
        std::size_t end = 0;
        std::string theirs;
        if (readHeader(text, end, theirs)) {
            if (theirs != fingerprint)
                throw InputError("study output '" + dir_ + "': " + journalName_ + " holds results of another study or " +
                                 "of a changed study file, protocol or population (fingerprint " + theirs +
                                 ", this study's " + fingerprint + "); use another output folder or --restart to "
                                 "discard them");
            return parseStudyJournal(text.substr(std::min(end + 1, text.size())), study.getNumTasks());
        }
        StudyJournal journal = parseStudyJournal(text, study.getNumTasks(), 1);  // line 1 may be a result
        if (!journal.dropped.empty() && journal.dropped.front().line == 1) {
            journal.dropped.front().kind = "header";
            journal.dropped.front().detail =
                "the header line is damaged (expected '# armsim study journal; fingerprint <16 hex digits>; study <name>')";
        }
        if (journal.lines.empty()) {
            headerNote_ = "the header is damaged and no line is a result: nothing to resume, every cell is computed";
            return journal;
        }
        StudyResult mine;
        parseStudyJournalLine(journal.lines.front(), mine);
        const StudyTask t = getStudyTask(study, mine.task);
        const std::vector<StudyResult> ours = runStudyGroup(study, t.getGroup(study), {t.index});
        if (ours.size() != 1 || formatStudyResult(ours.front()) != formatStudyResult(mine))
            throw InputError("study output '" + dir_ + "': " + journalName_ + "'s header is damaged and its results " +
                             "are not this study's (task " + std::to_string(t.index) + " computed now differs from " +
                             "its journal line); use another output folder or --restart to discard them");
        headerNote_ = "the header was damaged: recovered (task " + std::to_string(t.index) +
                      ", computed again, equals its journal line)";
        return journal;
    }

    // Adds the cells of every shard journal (journal-shard-I-of-N.log) to done_ and `kept`; returns their
    // names (removed once journal.log holds them). A shard still running, or a shard journal of another
    // study or with a damaged header, is refused. restart: shard journals are discarded.
    std::vector<std::string> mergeShards(const std::string& fingerprint, const Study& study, bool restart,
                                         std::string& kept) {
        std::vector<std::string> names;
        for (const fs::directory_entry& e : fs::directory_iterator(dir_)) {
            const std::string name = e.path().filename().string();
            if (name.size() > 18 && name.rfind("journal-shard-", 0) == 0 && name.compare(name.size() - 4, 4, ".log") == 0)
                names.push_back(name);
        }
        std::sort(names.begin(), names.end());
        for (const std::string& name : names) {
            const std::string shard = name.substr(14, name.size() - 18);  // I-of-N
            shardLocks_.emplace_back();
            if (!lockFile(".lock-shard-" + shard, shardLocks_.back()))
                throw InputError("study output '" + dir_ + "': shard " + shard + " is still running in this folder (" +
                                 name + " is in use): wait for the job array to end");
            if (restart) continue;
            const std::string text = readFileText(dir_ + "/" + name);
            std::size_t end = 0;
            std::string theirs;
            if (!readHeader(text, end, theirs) || theirs != fingerprint)
                throw InputError("study output '" + dir_ + "': " + name + (theirs.empty() ? " has a damaged header" :
                                 " holds results of another study (fingerprint " + theirs + ", this study's " + fingerprint + ")") +
                                 ": remove it (its cells are computed again) or use --restart to discard every journal");
            StudyJournal journal = parseStudyJournal(text.substr(std::min(end + 1, text.size())), study.getNumTasks());
            ++shardJournals_;
            for (const std::string& line : journal.lines) {
                StudyResult r;
                parseStudyJournalLine(line, r);
                if (done_.count(r.task)) continue;  // also in journal.log or an earlier shard: the same cell
                done_.emplace(r.task, std::move(r));
                kept += line + '\n';
                ++merged_;
            }
            if (!journal.dropped.empty()) {
                const std::string s = summarizeStudyJournalDrops(journal.dropped, &journal, name);
                summary_ += (summary_.empty() ? "" : "; ") + s;
                for (StudyJournalDrop& d : journal.dropped) d.file = name;
                dropped_.insert(dropped_.end(), journal.dropped.begin(), journal.dropped.end());
            }
        }
        return names;
    }

    std::string dir_, journalName_, journalPath_;
    Lock lock_;
    std::vector<Lock> shardLocks_;  // held while their journals are merged
    std::unique_ptr<std::FILE, int (*)(std::FILE*)> journal_{nullptr, std::fclose};
    std::map<long, StudyResult> done_;
    std::vector<StudyJournalDrop> dropped_;
    std::string summary_, headerNote_;
    long merged_ = 0;
    int shardJournals_ = 0;
};

// Per (protocol, method): a statistic of the summary against the noise level.
void writeNoisePlot(const std::string& path, const std::string& title, const std::string& yLabel,
                    const std::vector<StudySummaryRow>& summary, double (*statistic)(const ElbowValidationSummary&)) {
    PlotSpec spec;
    spec.title = title;
    spec.xLabel = "transducer noise (% of the torque)";
    spec.yLabel = yLabel;
    std::map<std::string, std::size_t> seriesOf;
    for (const StudySummaryRow& r : summary) {
        const double y = statistic(r.stats);
        if (!std::isfinite(y)) continue;
        const std::string key = r.protocol + " / " + r.stats.method;
        if (!seriesOf.count(key)) {
            seriesOf[key] = spec.series.size();
            spec.series.push_back({key, {}, {}, false, int(spec.series.size() % 8)});
        }
        PlotSeries& s = spec.series[seriesOf[key]];
        s.x.push_back(100 * r.stats.noise);
        s.y.push_back(y);
    }
    if (spec.series.empty()) return;
    for (PlotSeries& s : spec.series) s.markers = s.x.size() == 1;
    writePlotPng(path, spec);
}

std::vector<std::string> writeStudyFiles(const Study& study, const std::string& dir,
                                         const std::map<long, StudyResult>& done) {
    std::vector<StudyResult> results;
    results.reserve(done.size());
    std::string table = getStudyResultsHeader() + '\n', timing = "task,rank,synthesis_s,identification_s\n";
    for (const auto& [task, r] : done) {
        table += formatStudyResult(r) + '\n';
        timing += std::to_string(task) + ',' + std::to_string(r.rank) + ',' + formatNumber(r.synthesisTime) + ',' +
                  formatNumber(r.identificationTime) + '\n';
        results.push_back(r);
    }
    const std::vector<StudySummaryRow> summary = summarizeStudy(study, results);
    writeFileAtomically(dir + "/results.csv", table);
    writeFileAtomically(dir + "/timing.csv", timing);
    writeFileAtomically(dir + "/summary.csv", formatStudySummaryCsv(summary));
    std::vector<std::string> files = {"results.csv", "summary.csv", "timing.csv"};
    if (!study.file.empty()) {
        writeFileAtomically(dir + "/study.yaml", readFileText(study.file));
        files.push_back("study.yaml");
    }
    const struct {
        const char* file;
        const char* title;
        const char* yLabel;
        double (*statistic)(const ElbowValidationSummary&);
    } plots[] = {
        {"mass_rmse_vs_noise.png", "Biceps long-head mass: RMSE of the identified mass", "mass RMSE (%)",
         [](const ElbowValidationSummary& x) { return 100 * x.massRmse; }},
        {"mass_coverage_vs_noise.png", "Biceps long-head mass: coverage of the 95 % interval", "coverage of the true mass",
         [](const ElbowValidationSummary& x) { return x.massCoverage; }},
        {"tendon_rmse_vs_noise.png", "Optimal tendon length: RMSE", "L0T RMSE (mm)",
         [](const ElbowValidationSummary& x) { return 1000 * x.tendonRmse; }},
    };
    for (const auto& p : plots) {
        writeNoisePlot(dir + "/" + p.file, p.title, p.yLabel, summary, p.statistic);
        if (doesPathExist(dir + "/" + p.file)) files.push_back(p.file);
    }
    return files;
}

int defaultThreads() { return getNumUsableCpus(); }

}  // namespace

StudyOutcome runStudy(const Study& study, const StudyRunOptions& options, StudyCoordinatorLink* link) {
    study.validate();
    checkField("threads", options.threads, Bound::closed(0, kMaxStudyThreads, "0: every CPU this process may use"));
    const auto start = Clock::now();
    StudyOutcome outcome;
    outcome.output = options.output.empty() ? study.output : options.output;
    if (outcome.output.empty()) throw InputError("study: no output folder (set `output:` or --out)");
    const std::string fingerprint = calcStudyFingerprint(study);
    const bool sharded = options.shards > 0;
    if (sharded && (options.shard < 0 || options.shard >= options.shards))
        throw InputError("study: shard " + std::to_string(options.shard) + "/" + std::to_string(options.shards) +
                         ": expected I/N with 0 <= I < N");
    if (sharded && (options.merge || link))
        throw InputError("study: a shard (--shard) runs on its own threads: not with --merge or MPI ranks");
    StudyFolder folder(outcome.output, fingerprint, study, options.restart, options.shard, options.shards);
    outcome.journalDrops = folder.getDropped();
    outcome.journalSummary = folder.getDroppedSummary();
    outcome.merged = folder.getNumMerged();
    outcome.shardJournals = folder.getNumShardJournals();
    outcome.shard = options.shard;
    outcome.shards = options.shards;
    if (!outcome.journalSummary.empty()) {
        folder.recordRepairs();
        if (options.notice)
            options.notice(outcome.journalSummary + " (every line in " + outcome.output + "/journal_repairs.log)");
    }

    // Missing cells, grouped, in task order (a shard's: its groups only).
    std::deque<GroupWork> pending;
    const int cells = study.getCellsPerGroup();
    for (long g = sharded ? options.shard : 0; g < study.getNumGroups(); g += sharded ? options.shards : 1) {
        GroupWork w{g, {}};
        for (long t = g * cells; t < (g + 1) * cells; ++t) {
            if (!folder.getDone().count(t)) w.tasks.push_back(t);
            else ++outcome.resumed;
            ++outcome.total;
        }
        if (!w.tasks.empty()) pending.push_back(std::move(w));
    }
    if (options.merge && !pending.empty()) {
        long missing = 0;
        for (const GroupWork& w : pending) missing += long(w.tasks.size());
        throw InputError("study output '" + outcome.output + "': --merge: " + std::to_string(missing) + " of " +
                         std::to_string(outcome.total) + " cells are in no journal (a shard failed or has not run; " +
                         "first missing: task " + std::to_string(pending.front().tasks.front()) + "); run the " +
                         "study without --merge to compute them");
    }

    StudyProgress progress;
    progress.total = outcome.total;
    progress.resumed = progress.done = outcome.resumed;
    for (const auto& [task, r] : folder.getDone())
        progress.failed += r.status == "failed" && (!sharded || getStudyTask(study, task).getGroup(study) % options.shards == options.shard);
    auto record = [&](const std::vector<StudyResult>& results) {
        if (results.empty()) return;
        folder.append(results);
        for (const StudyResult& r : results) {
            ++progress.done;
            ++outcome.computed;
            progress.failed += r.status == "failed";
            outcome.taskTime += r.synthesisTime + r.identificationTime;
            outcome.synthesisTime += r.synthesisTime;
        }
    };
    auto report = [&] {
        if (!options.progress) return;
        progress.elapsed = std::chrono::duration<double>(Clock::now() - start).count();
        const long computed = progress.done - progress.resumed;
        progress.rate = progress.elapsed > 0 ? double(computed) / progress.elapsed : 0;
        progress.remaining = computed > 0 ? double(progress.total - progress.done) / progress.rate : 0.0 / 0.0;
        options.progress(progress);
    };

    const int threads = options.threads > 0 ? options.threads : defaultThreads();
    outcome.threads = threads;
    outcome.ranks = 1 + (link ? link->getNumWorkers() : 0);
    {
        LocalWorkers local(study, pending.empty() ? 0 : threads, 0);
        int localInFlight = 0, stopped = 0;
        const int workers = link ? link->getNumWorkers() : 0;
        std::vector<bool> told(workers + 1, false);
        auto lastReport = Clock::now();
        report();
        while (progress.done < progress.total || stopped < workers) {
            while (localInFlight < local.getNumThreads() && !pending.empty()) {
                local.add(std::move(pending.front()));
                pending.pop_front();
                ++localInFlight;
            }
            int worker = 0;
            std::string message;
            while (link && link->receive(worker, message)) {
                int want = 0;
                std::string theirs;
                const std::vector<StudyResult> results = parseRequest(message, want, theirs);
                if (theirs != fingerprint)
                    throw InputError("rank " + std::to_string(worker) + " read a different study (fingerprint " + theirs +
                                     ", rank 0: " + fingerprint + "): the study, protocol and population files must "
                                     "be the same on every node");
                record(results);
                std::vector<GroupWork> give;
                while (int(give.size()) < want && !pending.empty()) {
                    give.push_back(std::move(pending.front()));
                    pending.pop_front();
                }
                link->send(worker, formatWork(give, pending.empty()));
                if (pending.empty() && !told[worker]) told[worker] = true, ++stopped;
            }
            int groups = 0;
            record(local.take(std::chrono::milliseconds(link ? 1 : 200), groups));
            localInFlight -= groups;
            if (Clock::now() - lastReport > std::chrono::seconds(1)) {
                report();
                lastReport = Clock::now();
            }
        }
    }
    report();

    if (sharded) {  // the plain run (or --merge) after the job array writes the files
        outcome.files = {folder.getJournalName()};
    } else {
        outcome.files = writeStudyFiles(study, outcome.output, folder.getDone());
    }
    if (doesPathExist(outcome.output + "/journal_repairs.log")) outcome.files.push_back("journal_repairs.log");
    for (const auto& [task, r] : folder.getDone()) {
        if (sharded && getStudyTask(study, task).getGroup(study) % options.shards != options.shard) continue;
        outcome.failed += r.status == "failed";
        outcome.notConverged += r.status == "not-converged";
    }
    outcome.wallTime = std::chrono::duration<double>(Clock::now() - start).count();
    return outcome;
}

bool isLaunchedByMpi() {
    return std::getenv("OMPI_COMM_WORLD_SIZE") || std::getenv("PMIX_RANK") || std::getenv("PMI_RANK");
}

void runStudyWorker(const Study& study, int threads, StudyWorkerLink& link) {
    study.validate();
    threads = threads > 0 ? threads : defaultThreads();
    const std::string fingerprint = calcStudyFingerprint(study);
    LocalWorkers local(study, threads, link.getRank());
    const int capacity = threads;  // no prefetch: a queued group could leave another rank idle at the end
    int inFlight = 0;
    bool noMore = false;
    std::vector<StudyResult> finished;
    for (;;) {
        const int want = noMore ? 0 : capacity - inFlight;
        if (want > 0 || !finished.empty()) {
            const std::vector<GroupWork> work = parseWork(link.exchange(formatRequest(want, fingerprint, finished)), noMore);
            finished.clear();
            for (const GroupWork& w : work) local.add(w);
            inFlight += int(work.size());
        }
        if (noMore && inFlight == 0) return;
        int groups = 0;
        finished = local.take(std::chrono::milliseconds(200), groups);
        inFlight -= groups;
    }
}

}  // namespace armsim
