// The study's machinery: the output folder (lock, journal, final files), the worker threads of one
// process, the coordinator (rank 0) and the worker-rank loop. The numbers come from runStudyGroup.
#include "basics/bound.h"
#include "basics/numbers.h"
#include "basics/errors.h"
#include "basics/files.h"
#include "basics/output_folder.h"
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
#include <cstdint>
#include <functional>
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

// One status byte per cell: what rank 0 keeps of a result (the result itself is in the journal).
enum CellStatus : std::uint8_t { kMissing = 0, kOk, kNotConverged, kFailed, kSkipped };

std::uint8_t getCellStatus(const std::string& status) {
    return status == "ok" ? kOk : status == "not-converged" ? kNotConverged : status == "failed" ? kFailed : kSkipped;
}

// A journal file after its header line (the header skipped when skipHeader).
std::unique_ptr<std::istream> openJournal(const std::string& path, bool skipHeader) {
    auto in = std::make_unique<std::ifstream>(path, std::ios::binary);
    if (!*in) throw InputError(path + ": cannot read");
    std::string header;
    if (skipHeader) std::getline(*in, header);
    return in;
}

// The output folder: an exclusive lock for this run (released by the kernel when the process dies) and
// the journal of finished cells. A shard (--shard I/N) has its own lock and journal
// (journal-shard-I-of-N.log), so the shards of a job array run side by side; a plain run merges every
// shard journal of the study into journal.log and removes them. Journals are read and compacted one
// line at a time; of each cell only its status byte stays in memory.
class StudyFolder {
public:
    StudyFolder(const std::string& dir, const std::string& fingerprint, const Study& study, bool restart,
                int shard = 0, int shards = 0)
        : dir_(dir), status_(std::size_t(study.getNumTasks()), kMissing) {
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
        removeStaleScratch();
        const std::string header = "# armsim study journal; fingerprint " + fingerprint + "; study " + study.name;
        AtomicFileWriter kept(journalPath_);  // compacted: valid lines only, so appends start on a clean line
        kept.write(header + '\n');
        if (doesPathExist(journalPath_) && !restart) {
            readJournal(fingerprint, study, kept);
            if (!headerNote_.empty()) summary_ = (summary_.empty() ? journalName_ + ": " : summary_ + "; ") + headerNote_;
        } else if (restart) {
            std::remove((dir_ + "/journal_repairs.log").c_str());  // the repairs of a discarded journal
        }
        const std::vector<std::string> merged = shards > 0 ? std::vector<std::string>() : mergeShards(fingerprint, study, restart, kept);
        kept.commit();
        for (const std::string& name : merged) {  // now in journal.log
            std::remove((dir_ + "/" + name).c_str());
            std::remove((dir_ + "/.lock" + name.substr(7, name.size() - 11)).c_str());
        }
        shardLocks_.clear();
        journal_.reset(std::fopen(journalPath_.c_str(), "ab"));
        if (!journal_) throw InputError("study output '" + dir_ + "': cannot append to " + journalName_);
    }
    bool isDone(long task) const { return status_[std::size_t(task)] != kMissing; }
    std::uint8_t getStatus(long task) const { return status_[std::size_t(task)]; }
    const std::vector<StudyJournalDrop>& getDropped() const { return dropped_; }
    const std::string& getDroppedSummary() const { return summary_; }
    long getNumMerged() const { return merged_; }
    int getNumShardJournals() const { return shardJournals_; }
    const std::string& getJournalName() const { return journalName_; }
    const std::string& getJournalPath() const { return journalPath_; }
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
            status_[std::size_t(r.task)] = getCellStatus(r.status);
        }
        if (std::fwrite(text.data(), 1, text.size(), journal_.get()) != text.size() || std::fflush(journal_.get()) != 0)
            throw InputError("study output '" + dir_ + "': cannot append to " + journalName_);
    }
    void closeJournal() { journal_.reset(); }

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

    // What a run killed while compacting its journal or sorting its results left (ours to remove: we
    // hold the lock): this journal's temporaries and, for a plain run, the sorting folders.
    void removeStaleScratch() const {
        std::error_code ec;
        for (const fs::directory_entry& e : fs::directory_iterator(dir_, ec)) {
            const std::string name = e.path().filename().string();
            const bool journalTemp = name.rfind(journalName_ + ".tmp.", 0) == 0;
            const bool sorting = journalName_ == "journal.log" && name.rfind(".sort.", 0) == 0;
            if (journalTemp || sorting) fs::remove_all(e.path(), ec);
        }
    }

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

    // A journal's first line: true when it is an intact header (its fingerprint in `theirs`).
    static bool readHeader(const std::string& path, std::string& theirs) {
        std::ifstream in(path, std::ios::binary);
        std::string first;
        std::getline(in, first);
        while (!first.empty() && (first.back() == '\r' || first.back() == ' ')) first.pop_back();
        const std::string prefix = "# armsim study journal; fingerprint ";
        const bool intact = first.rfind(prefix, 0) == 0 && first.size() >= prefix.size() + 16 &&
                            first.find_first_not_of("0123456789abcdef", prefix.size()) == prefix.size() + 16 &&
                            first.compare(prefix.size() + 16, 8, "; study ") == 0;
        if (intact) theirs = first.substr(prefix.size(), 16);
        return intact;
    }

    // Reads journal.log's results into the status bytes and `kept`. An intact header of another
    // fingerprint is refused; a damaged header (an editor, a disk error) is recovered when the journal's
    // first result, computed again now, is the same: the journal is then this study's, whatever its
    // header says.
    void readJournal(const std::string& fingerprint, const Study& study, AtomicFileWriter& kept) {
        std::string theirs;
        const bool intact = readHeader(journalPath_, theirs);
        if (intact && theirs != fingerprint)
            throw InputError("study output '" + dir_ + "': " + journalName_ + " holds results of another study or " +
                             "of a changed study file, protocol or population (fingerprint " + theirs +
                             ", this study's " + fingerprint + "); use another output folder or --restart to "
                             "discard them");
        std::string firstResult;
        long results = 0;
        dropped_ = scanStudyJournal([this, intact] { return openJournal(journalPath_, intact); }, study.getNumTasks(),
                                    intact ? 2 : 1, [&](const std::string& line, StudyResult&& r) {
                                        if (firstResult.empty()) firstResult = line;
                                        status_[std::size_t(r.task)] = getCellStatus(r.status);
                                        kept.write(line + '\n');
                                        ++results;
                                    });
        if (!intact) {
            if (!dropped_.empty() && dropped_.front().line == 1) {
                dropped_.front().kind = "header";
                dropped_.front().detail =
                    "the header line is damaged (expected '# armsim study journal; fingerprint <16 hex digits>; study <name>')";
            }
            if (results == 0) {
                headerNote_ = "the header is damaged and no line is a result: nothing to resume, every cell is computed";
            } else {
                StudyResult mine;
                parseStudyJournalLine(firstResult, mine);
                const StudyTask t = getStudyTask(study, mine.task);
                const std::vector<StudyResult> ours = runStudyGroup(study, t.getGroup(study), {t.index});
                if (ours.size() != 1 || formatStudyResult(ours.front()) != formatStudyResult(mine))
                    throw InputError("study output '" + dir_ + "': " + journalName_ + "'s header is damaged and its results " +
                                     "are not this study's (task " + std::to_string(t.index) + " computed now differs from " +
                                     "its journal line); use another output folder or --restart to discard them");
                headerNote_ = "the header was damaged: recovered (task " + std::to_string(t.index) +
                              ", computed again, equals its journal line)";
            }
        }
        summary_ = summarizeStudyJournalDrops(dropped_, [this](long task) { return isDone(task); }, journalName_);
    }

    // Adds the cells of every shard journal (journal-shard-I-of-N.log) to the status bytes and `kept`;
    // returns their names (removed once journal.log holds them). A shard still running, or a shard
    // journal of another study or with a damaged header, is refused. restart: shard journals are discarded.
    std::vector<std::string> mergeShards(const std::string& fingerprint, const Study& study, bool restart,
                                         AtomicFileWriter& kept) {
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
            const std::string path = dir_ + "/" + name;
            std::string theirs;
            if (!readHeader(path, theirs) || theirs != fingerprint)
                throw InputError("study output '" + dir_ + "': " + name + (theirs.empty() ? " has a damaged header" :
                                 " holds results of another study (fingerprint " + theirs + ", this study's " + fingerprint + ")") +
                                 ": remove it (its cells are computed again) or use --restart to discard every journal");
            std::vector<StudyJournalDrop> dropped = scanStudyJournal(
                [&path] { return openJournal(path, true); }, study.getNumTasks(), 2,
                [&](const std::string& line, StudyResult&& r) {
                    if (isDone(r.task)) return;  // also in journal.log or an earlier shard: the same cell
                    status_[std::size_t(r.task)] = getCellStatus(r.status);
                    kept.write(line + '\n');
                    ++merged_;
                });
            ++shardJournals_;
            if (!dropped.empty()) {
                const std::string s = summarizeStudyJournalDrops(dropped, [this](long task) { return isDone(task); }, name);
                summary_ += (summary_.empty() ? "" : "; ") + s;
                for (StudyJournalDrop& d : dropped) d.file = name;
                dropped_.insert(dropped_.end(), dropped.begin(), dropped.end());
            }
        }
        return names;
    }

    std::string dir_, journalName_, journalPath_;
    Lock lock_;
    std::vector<Lock> shardLocks_;  // held while their journals are merged
    std::unique_ptr<std::FILE, int (*)(std::FILE*)> journal_{nullptr, std::fclose};
    std::vector<std::uint8_t> status_;  // per task
    std::vector<StudyJournalDrop> dropped_;
    std::string summary_, headerNote_;
    long merged_ = 0;
    int shardJournals_ = 0;
};

// The cells still to compute, handed out as units of work: whole groups (one synthesis for all their
// cells) while at least as many groups are left as threads asking for work, then a group's cells split
// over the idle threads that ask together (each piece synthesizes the subject again, in parallel: it
// pays in wall time, never queueing a piece behind a busy thread). Groups are found from the status
// bytes as they are handed out: nothing is held per group.
class WorkQueue {
public:
    WorkQueue(const Study& study, const StudyFolder& folder, long first, long step)
        : folder_(folder), next_(first), step_(step), cells_(study.getCellsPerGroup()) {
        for (long g = first; g < study.getNumGroups(); g += step) {
            long missing = 0;
            for (long t = g * cells_; t < (g + 1) * cells_; ++t) {
                ++total_;
                if (folder.isDone(t)) continue;
                ++missing;
                if (firstMissing_ < 0) firstMissing_ = t;
            }
            missing_ += missing;
            groupsLeft_ += missing > 0;
        }
    }
    long getNumCells() const { return total_; }        // of this run's share
    long getNumMissing() const { return missing_; }    // at the start
    long getFirstMissing() const { return firstMissing_; }
    bool isEmpty() const { return pieces_.empty() && groupsLeft_ == 0; }
    // The next unit for one of `idle` threads asking now (the caller hands out `idle` units in a row).
    GroupWork take(int idle) {
        if (!pieces_.empty()) {
            GroupWork w = std::move(pieces_.front());
            pieces_.pop_front();
            return w;
        }
        GroupWork w;
        for (;; next_ += step_) {
            w.group = next_;
            for (long t = next_ * cells_; t < (next_ + 1) * cells_; ++t)
                if (!folder_.isDone(t)) w.tasks.push_back(t);
            if (!w.tasks.empty()) break;
        }
        next_ += step_;
        const long groups = groupsLeft_--;  // this one included
        if (groups >= idle || w.tasks.size() < 2) return w;
        const long pieces = std::min<long>(long(w.tasks.size()), (idle + groups - 1) / groups);
        const std::vector<long> tasks = std::move(w.tasks);
        for (long i = 0; i < pieces; ++i) {
            GroupWork piece{w.group, {}};
            piece.tasks.assign(tasks.begin() + long(tasks.size()) * i / pieces,
                               tasks.begin() + long(tasks.size()) * (i + 1) / pieces);
            pieces_.push_back(std::move(piece));
        }
        GroupWork first = std::move(pieces_.front());
        pieces_.pop_front();
        return first;
    }

private:
    const StudyFolder& folder_;
    long next_, step_, cells_;
    long total_ = 0, missing_ = 0, firstMissing_ = -1, groupsLeft_ = 0;
    std::deque<GroupWork> pieces_;
};

// Per (truth, protocol, method): a statistic of the summary against the noise level.
void writeNoisePlot(const std::string& path, const std::string& title, const std::string& yLabel,
                    const std::vector<StudySummaryRow>& summary, double (*statistic)(const ElbowValidationSummary&),
                    bool severalTruths) {
    PlotSpec spec;
    spec.title = title;
    spec.xLabel = "transducer noise (% of the torque)";
    spec.yLabel = yLabel;
    std::map<std::string, std::size_t> seriesOf;
    for (const StudySummaryRow& r : summary) {
        const double y = statistic(r.stats);
        if (!std::isfinite(y)) continue;
        const std::string key = (severalTruths ? r.truth + " / " : std::string()) + r.protocol + " / " + r.stats.method;
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

// A statistic of the summary as a table: a row per truth, a column per (protocol, method[, noise]).
void writeTruthHeatMap(const std::string& path, const std::string& title, const std::string& zLabel,
                       const Study& study, const std::vector<StudySummaryRow>& summary,
                       double (*statistic)(const ElbowValidationSummary&), int decimals) {
    auto columnOf = [&study](const StudySummaryRow& r) {
        std::string c = (study.protocols.size() > 1 ? r.protocol + " / " : std::string()) + r.stats.method;
        if (study.noiseLevels.size() > 1) c += " / " + formatNumber(100 * r.stats.noise) + " %";
        return c;
    };
    std::vector<std::string> columns;
    for (const StudySummaryRow& r : summary) {
        const std::string c = columnOf(r);
        if (std::find(columns.begin(), columns.end(), c) == columns.end()) columns.push_back(c);
    }
    HeatMapSpec spec;
    spec.title = title;
    spec.zLabel = zLabel;
    spec.xLabel = "identifier";
    spec.yLabel = "";
    spec.labelDecimals = decimals;
    spec.xNames = columns;
    for (std::size_t i = 0; i < columns.size(); ++i) spec.x.push_back(double(i));
    const std::size_t nt = study.truths.size();
    for (std::size_t j = 0; j < nt; ++j) {  // first truth on top
        spec.y.push_back(double(j));
        spec.yNames.push_back(study.truths[nt - 1 - j].label);
    }
    spec.z.assign(columns.size() * nt, kNaN);
    bool any = false;
    for (const StudySummaryRow& r : summary) {
        const std::size_t i = std::size_t(std::find(columns.begin(), columns.end(), columnOf(r)) - columns.begin());
        std::size_t t = 0;
        while (t < nt && study.truths[t].label != r.truth) ++t;
        const double z = statistic(r.stats);
        if (t == nt || !std::isfinite(z)) continue;
        spec.z[i * nt + (nt - 1 - t)] = z;
        any = true;
    }
    if (!any) return;
    spec.height = std::max(500, 140 + 60 * int(nt));
    writeHeatMapPng(path, spec);
}

// The journal's results in task order, a range of tasks at a time: f(result) for each. A journal that
// fits in `passBytes` is read once; a larger one is first split by task range into bucket files (one
// read and one write of it), then each bucket is read, ordered and handed on: memory stays near
// passBytes whatever the number of results.
void forEachResultInTaskOrder(const std::string& journalPath, const std::string& scratchDir, long numTasks, long passBytes,
                              const std::function<void(const StudyResult&)>& f) {
    std::error_code ec;
    const std::uintmax_t size = fs::file_size(journalPath, ec);
    if (ec) throw InputError(journalPath + ": cannot read: " + ec.message());
    const long wanted = std::clamp<long>(long(size / std::uintmax_t(std::max(1L, passBytes))) + 1, 1, 512);
    const long perBucket = (numTasks + wanted - 1) / wanted;
    const long buckets = (numTasks + perBucket - 1) / perBucket;
    auto emitRange = [&](const std::string& path, bool skipHeader, long lo, long hi) {
        std::vector<std::string> lines(std::size_t(hi - lo));
        std::unique_ptr<std::istream> in = openJournal(path, skipHeader);
        for (std::string line; std::getline(*in, line);) {
            const long task = peekStudyJournalTask(line);
            if (task >= lo && task < hi && lines[std::size_t(task - lo)].empty()) lines[std::size_t(task - lo)] = std::move(line);
        }
        for (const std::string& line : lines) {
            if (line.empty()) continue;
            StudyResult r;
            if (!parseStudyJournalLine(line, r))
                throw InputError(journalPath + ": a line changed while the study ran (task " + std::to_string(peekStudyJournalTask(line)) +
                                 " fails its checksum); run the study again to recompute it");
            f(r);
        }
    };
    if (buckets == 1) return emitRange(journalPath, true, 0, numTasks);
    struct Scratch {  // removed however the writing ends
        std::string dir;
        ~Scratch() {
            std::error_code e;
            fs::remove_all(dir, e);
        }
    } scratch{scratchDir};
    fs::create_directories(scratch.dir, ec);
    if (ec) throw InputError(scratch.dir + ": cannot create the sorting folder: " + ec.message());
    {
        std::vector<std::unique_ptr<std::FILE, int (*)(std::FILE*)>> files;
        for (long b = 0; b < buckets; ++b) {
            files.emplace_back(std::fopen((scratch.dir + "/" + std::to_string(b)).c_str(), "wb"), std::fclose);
            if (!files.back()) throw InputError(scratch.dir + ": cannot write the sorting files");
        }
        std::unique_ptr<std::istream> in = openJournal(journalPath, true);
        for (std::string line; std::getline(*in, line);) {
            const long task = peekStudyJournalTask(line);
            if (task < 0 || task >= numTasks) continue;
            line += '\n';
            std::FILE* out = files[std::size_t(task / perBucket)].get();
            if (std::fwrite(line.data(), 1, line.size(), out) != line.size())
                throw InputError(scratch.dir + ": write failed (disk full?)");
        }
        for (auto& file : files)
            if (std::fflush(file.get()) != 0) throw InputError(scratch.dir + ": write failed (disk full?)");
    }
    for (long b = 0; b < buckets; ++b)
        emitRange(scratch.dir + "/" + std::to_string(b), false, b * perBucket, std::min(numTasks, (b + 1) * perBucket));
}

std::vector<std::string> writeStudyFilesInto(OutputFolder& folder, const Study& study, const std::string& dir,
                                             const std::string& journalPath, long passBytes);

// The study's files join its folder (beside the journal) together at the end, or none of them; errors
// name them where they would have been.
std::vector<std::string> writeStudyFiles(const Study& study, const std::string& dir, const std::string& journalPath,
                                         long passBytes) {
    OutputFolder folder(dir, OutputFolder::Mode::AddFiles);
    try {
        return writeStudyFilesInto(folder, study, dir, journalPath, passBytes);
    } catch (const InputError& e) {
        throw InputError(folder.showPaths(e.what()));
    }
}

std::vector<std::string> writeStudyFilesInto(OutputFolder& folder, const Study& study, const std::string& dir,
                                             const std::string& journalPath, long passBytes) {
    AtomicFileWriter table(folder.addFile("results.csv")), timing(folder.addFile("timing.csv"));
    table.write(getStudyResultsHeader() + '\n');
    timing.write("task,rank,synthesis_s,identification_s\n");
    StudySummaryAccumulator sum(study);
    forEachResultInTaskOrder(journalPath, dir + "/.sort." + std::to_string(::getpid()), study.getNumTasks(), passBytes,
                             [&](const StudyResult& r) {
                                 table.write(formatStudyResult(r) + '\n');
                                 timing.write(std::to_string(r.task) + ',' + std::to_string(r.rank) + ',' +
                                              formatNumber(r.synthesisTime) + ',' + formatNumber(r.identificationTime) + '\n');
                                 sum.add(r);
                             });
    const std::vector<StudySummaryRow> summary = sum.getRows();
    table.commit();
    timing.commit();
    folder.write("summary.csv", formatStudySummaryCsv(summary));
    std::vector<std::string> files = {"results.csv", "summary.csv", "timing.csv"};
    if (!study.file.empty()) {
        folder.write("study.yaml", readFileText(study.file));
        files.push_back("study.yaml");
    }
    const std::string& primary = study.prior.base.muscles.at(study.prior.base.primary).params.name;
    const struct {
        const char* file;
        const char* title;
        const char* yLabel;
        double (*statistic)(const ElbowValidationSummary&);
    } plots[] = {
        {"mass_rmse_vs_noise.png", "mass: RMSE of the identified mass", "mass RMSE (%)",
         [](const ElbowValidationSummary& x) { return 100 * x.massRmse; }},
        {"mass_coverage_vs_noise.png", "mass: coverage of the 95 % interval", "coverage of the true mass",
         [](const ElbowValidationSummary& x) { return x.massCoverage; }},
        {"tendon_rmse_vs_noise.png", "L0T: RMSE", "L0T RMSE (mm)",
         [](const ElbowValidationSummary& x) { return 1000 * x.tendonRmse; }},
    };
    for (const auto& p : plots) {
        folder.writeWith(p.file, [&](const std::string& path) {
            writeNoisePlot(path, primary + " " + p.title, p.yLabel, summary, p.statistic, study.truths.size() > 1);
            if (doesPathExist(path)) files.push_back(p.file);
        });
    }
    if (study.truths.size() > 1) {
        const struct {
            const char* file;
            const char* title;
            const char* zLabel;
            double (*statistic)(const ElbowValidationSummary&);
            int decimals;
        } maps[] = {
            {"mass_bias_by_truth.png", "mass: bias by truth", "mass bias (%)",
             [](const ElbowValidationSummary& x) { return 100 * x.massBias; }, 1},
            {"mass_rmse_by_truth.png", "mass: RMSE by truth", "mass RMSE (%)",
             [](const ElbowValidationSummary& x) { return 100 * x.massRmse; }, 1},
            {"mass_coverage_by_truth.png", "mass: coverage of the 95 % interval", "coverage",
             [](const ElbowValidationSummary& x) { return x.massCoverage; }, 2},
            {"tendon_rmse_by_truth.png", "L0T: RMSE by truth", "L0T RMSE (mm)",
             [](const ElbowValidationSummary& x) { return 1000 * x.tendonRmse; }, 1},
            {"max_force_rmse_by_truth.png", "F0: RMSE by truth", "F0 RMSE (%)",
             [](const ElbowValidationSummary& x) { return 100 * x.maxForceRmse; }, 1},
        };
        for (const auto& m : maps) {
            folder.writeWith(m.file, [&](const std::string& path) {
                writeTruthHeatMap(path, primary + " " + m.title, m.zLabel, study, summary, m.statistic, m.decimals);
                if (doesPathExist(path)) files.push_back(m.file);
            });
        }
    }
    folder.commit();
    return files;
}

int defaultThreads() { return getNumUsableCpus(); }

// The run options' combinations: a shard's range and company, --merge's needs.
void checkStudyRunOptions(const StudyRunOptions& options, const std::string& output, bool existed, bool ranks) {
    const bool sharded = options.shards > 0;
    if (sharded && (options.shard < 0 || options.shard >= options.shards))
        throw InputError("study: shard " + std::to_string(options.shard) + "/" + std::to_string(options.shards) +
                         ": expected I/N with 0 <= I < N");
    if (sharded && (options.merge || ranks))
        throw InputError("study: a shard (--shard) runs on its own threads: not with --merge or MPI ranks");
    if (options.merge && options.restart)
        throw InputError("study: --merge with --restart: --restart discards the journals --merge would merge; give one");
    if (options.merge && !existed)   // nothing made: a folder with only a lock would be left
        throw InputError("study output '" + output + "': --merge: the folder does not exist, so there is "
                         "nothing to merge (run the shards with --shard I/N into it first)");
}

// Hands the missing cells out (this process's threads, and MPI ranks through link) until every cell is
// recorded and every rank told to stop; record() takes each batch of results, report() the progress
// (called at most once a second).
void dispatchStudyWork(const Study& study, int threads, WorkQueue& pending, StudyCoordinatorLink* link,
                       const std::string& fingerprint, const StudyProgress& progress, StudyOutcome& outcome,
                       const std::function<void(const std::vector<StudyResult>&)>& record,
                       const std::function<void()>& report) {
    LocalWorkers local(study, pending.isEmpty() ? 0 : threads, 0);
    int localInFlight = 0, stopped = 0;
    const int workers = link ? link->getNumWorkers() : 0;
    std::vector<bool> told(workers + 1, false);
    auto lastReport = Clock::now();
    report();
    while (progress.done < progress.total || stopped < workers) {
        while (localInFlight < local.getNumThreads() && !pending.isEmpty()) {
            local.add(pending.take(local.getNumThreads() - localInFlight));
            ++outcome.units;
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
            while (int(give.size()) < want && !pending.isEmpty()) {
                give.push_back(pending.take(want - int(give.size())));
                ++outcome.units;
            }
            link->send(worker, formatWork(give, pending.isEmpty()));
            if (pending.isEmpty() && !told[worker]) told[worker] = true, ++stopped;
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
    // A new folder is checked before it is made (nothing left behind); an existing one for what it lacks, below.
    const bool existed = std::filesystem::exists(outcome.output);
    checkStudyRunOptions(options, outcome.output, existed, link != nullptr);
    if (sharded && options.shard >= study.getNumGroups())   // g % N == I holds for no group g
        throw InputError("study: shard " + std::to_string(options.shard) + "/" + std::to_string(options.shards) +
                         ": the study has " + std::to_string(study.getNumGroups()) +
                         (study.getNumGroups() == 1 ? " group" : " groups") +
                         " (truths x subjects x protocols), so this shard has none to compute: expected N at "
                         "most the number of groups (--shard I/N)");
    if (!options.merge && !existed) checkStudyFitsOnDisk(study, study.getNumTasks() / std::max(1, options.shards), outcome.output);
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

    // Missing cells, in task order (a shard's: its groups only).
    WorkQueue pending(study, folder, sharded ? options.shard : 0, sharded ? options.shards : 1);
    outcome.total = pending.getNumCells();
    outcome.resumed = outcome.total - pending.getNumMissing();
    // Resumed: the journal grows by what is missing, but the results and the sort's scratch cover every task.
    if (!options.merge && existed && pending.getNumMissing() > 0)
        checkStudyFitsOnDisk(study, study.getNumTasks() / std::max(1, options.shards), outcome.output);
    if (options.merge && pending.getNumMissing() > 0)
        throw InputError("study output '" + outcome.output + "': --merge: " + std::to_string(pending.getNumMissing()) +
                         " of " + std::to_string(outcome.total) + " cells are in no journal (a shard failed or has not " +
                         "run; first missing: task " + std::to_string(pending.getFirstMissing()) + "); run the " +
                         "study without --merge to compute them");
    auto countOurs = [&](std::uint8_t status) {  // cells of this run's share with that status
        long n = 0;
        for (long task = 0; task < study.getNumTasks(); ++task)
            n += folder.getStatus(task) == status &&
                 (!sharded || getStudyTask(study, task).getGroup(study) % options.shards == options.shard);
        return n;
    };

    StudyProgress progress;
    progress.total = outcome.total;
    progress.resumed = progress.done = outcome.resumed;
    progress.failed = countOurs(kFailed);
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
        progress.remaining = computed > 0 ? double(progress.total - progress.done) / progress.rate : kNaN;
        options.progress(progress);
    };

    const int threads = options.threads > 0 ? options.threads : defaultThreads();
    outcome.threads = threads;
    outcome.ranks = 1 + (link ? link->getNumWorkers() : 0);
    dispatchStudyWork(study, threads, pending, link, fingerprint, progress, outcome, record, report);
    report();

    if (sharded) {  // the plain run (or --merge) after the job array writes the files
        outcome.files = {folder.getJournalName()};
    } else {
        folder.closeJournal();
        outcome.files = writeStudyFiles(study, outcome.output, folder.getJournalPath(), options.resultsPassBytes);
    }
    if (doesPathExist(outcome.output + "/journal_repairs.log")) outcome.files.push_back("journal_repairs.log");
    outcome.failed = countOurs(kFailed);
    outcome.notConverged = countOurs(kNotConverged);
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
