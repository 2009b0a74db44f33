// Population studies: Monte Carlo over virtual subjects. A study file names the truth (a
// population of virtual subjects around a model: `population:`, or `truth:` with `prior:`, the
// population the identifiers assume, for a study out of family; or several truths, `truths:` with
// `prior:`, each drawn and identified against the same prior), the protocols, the identifiers with their options,
// the transducer noise levels, the number of subjects, the seed and the output folder. Every
// (subject, protocol, noise, method) cell is one task: the subject's data are synthesized, read at the
// noise level and identified; the estimate, the truth, the 95 % intervals, the residual, the iterations
// and a status are recorded. The cells of one (truth, subject, protocol) share one synthesis, so they are
// scheduled together as a group while there are enough groups for the threads asking for work; past
// that (the end of a run, a study of few subjects) a group's cells are split over the idle threads, each
// piece synthesizing the subject again. Each cell is recorded (and resumed) on its own. Rank 0 keeps one status byte per cell
// and streams results to the journal; the final files are written from it in task order, a bounded
// range of tasks per pass, so its memory does not grow with the results.
//
// Results are a function of the study alone: a cell depends only on (seed, truth, subject, protocol,
// noise, method), numbers are written in shortest round-trip form and the table is sorted by task, so the
// result files are byte-identical for any number of ranks or threads and any completion order. Times
// (which are not) go to timing.csv.
//
// Resume: finished cells are appended to OUT/journal.log as they complete (one line per cell with a
// checksum, flushed per group). A run that finds a journal of the same study (same fingerprint: the
// study, its protocols and its population) computes only the cells the journal lacks; a torn last line
// (a kill mid-write) fails its checksum and is dropped. Every dropped line (torn, damaged, unreadable,
// duplicate) is reported (options.notice, the outcome, OUT/journal_repairs.log) and its cell computed
// again; CRLF line ends and trailing blanks are tolerated. A damaged header is recovered when the
// journal's first result, computed again, equals its line (the journal is then this study's); an intact
// header of another study is refused. A task that throws is recorded as failed with the reason and
// never stops the study.
#pragma once

#include "basics/fields.h"

#include "studies/torque_validation.h"

#include <cstdint>
#include <functional>
#include <istream>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace armsim {

/// A protocol of a study: "thesis" (the thesis's five flexion MVCs x 3) or a torque protocol file.
struct StudyProtocol {
    std::string reference;     ///< as written in the study file
    TorqueProtocol protocol;   ///< its conditions; protocol.name labels its results
};

/// A population the subjects of a study are drawn from.
struct StudyTruth {
    std::string reference = "default";  ///< "default" or the population file as written
    std::string label;                  ///< names its results (default: the population's name)
    Population population;
};

/// A study (units SI; noise levels relative).
struct Study {
    std::string name;                       ///< labels outputs
    std::string description;
    std::string file;                       ///< the study file ("" when built in code)
    /// The truths (`population:` or `truth:`: one; `truths:`: several): subjects are drawn from each.
    std::vector<StudyTruth> truths;
    std::string priorReference;             ///< `prior:` as written; "" = the truth population (in family)
    Population prior;                       ///< the identifiers' prior and model (the truth unless `prior:`)
    int subjects = 20;                      ///< persons 0 .. subjects-1 of each truth
    unsigned seed = 1;                      ///< population, synthesis noise and VA-measurement seed
    std::vector<StudyProtocol> protocols;   ///< at least one
    std::vector<double> noiseLevels;        ///< transducer noise (relative sd) [1]; at least one
    std::vector<ElbowMethod> methods;       ///< identifiers (unique labels); at least one
    std::string output;                     ///< output folder (relative to the working directory)

    /// One truth, in family (prior = truth): what code building a study by hand usually wants.
    void setPopulation(const Population& population, const std::string& reference = "default");
    long getNumGroups() const { return long(truths.size()) * long(subjects) * long(protocols.size()); }
    int getCellsPerGroup() const { return int(noiseLevels.size() * methods.size()); }
    long getNumTasks() const { return getNumGroups() * getCellsPerGroup(); }
    /// "N tasks (T truths x S subjects x P protocols x L noise levels x M methods)": the study's size.
    std::string describeSize() const;
    /// FieldError naming the field for an empty list, a duplicate label or a value out of range.
    void validate() const;
};

/// Reads a study file (`kind: study`) strictly: unknown keys, values out of range, missing protocol or
/// population files are InputErrors naming the file, line, field and value. Protocol and population
/// files are resolved relative to the study file, then to the working directory.
Study readStudy(const std::string& path);

/// A 16-hex-digit fingerprint of everything that decides the results: the study's settings (not its
/// output folder), every protocol's conditions and each truth's and the prior's distributions and base model.
std::string calcStudyFingerprint(const Study& study);

/// One cell. Tasks are numbered truth- then subject-major:
/// (((truth x S + subject) x P + protocol) x N + noise) x K + method.
/// Disk a task takes in a study folder: its journal line (~470 B measured on a thesis-method study), its
/// results.csv row (~450 B) and the task-order sort's scratch copy (~470 B), rounded up [B].
constexpr double kStudyBytesPerTask = 1500;

/// Refuses (InputError naming the study's size, the need and the space) a run whose `tasksToCompute`
/// would need more disk than the file system holding `outputFolder` has free; a folder that does not
/// exist yet is measured at its nearest existing parent.
void checkStudyFitsOnDisk(const Study& study, long tasksToCompute, const std::string& outputFolder);

struct StudyTask {
    long index = 0;
    int truth = 0, subject = 0, protocol = 0, noise = 0, method = 0;
    long getGroup(const Study& study) const {
        return (long(truth) * long(study.subjects) + subject) * long(study.protocols.size()) + protocol;
    }
};
StudyTask getStudyTask(const Study& study, long index);

/// What one task recorded.
struct StudyResult {
    long task = 0;
    std::string truth;             ///< the truth's label
    std::string protocol;          ///< the protocol's name
    std::string status;            ///< "ok", "not-converged", "failed" or "skipped" (channels on a torque-only protocol)
    std::string reason;            ///< why not ok (the solver's report or the error); "" when ok
    ElbowValidationRow row;        ///< truth, estimate, intervals, coverage (row.method: the method's label)
    // Not part of the deterministic results (timing.csv):
    double synthesisTime = 0;      ///< [s] this cell's share of its group's synthesis
    double identificationTime = 0; ///< [s]
    int rank = 0;                  ///< MPI rank that computed it
};

/// Computes the listed tasks (all of group `group`): draws the subject, synthesizes the protocol once,
/// identifies at every listed (noise, method). Never throws for a task's failure: a synthesis or
/// identification error is that task's "failed" result with the message.
std::vector<StudyResult> runStudyGroup(const Study& study, long group, const std::vector<long>& tasks, int rank = 0);

/// results.csv's fields (basics/fields.h): its header, rows and the journal's lines are made from them.
const FieldTable<StudyResult>& getStudyResultFields();
/// Column names of results.csv.
std::string getStudyResultsHeader();
/// One results.csv line (no newline); every number in shortest round-trip form.
std::string formatStudyResult(const StudyResult& result);
/// A journal line: checksum, result, timing (no newline). parseStudyJournalLine reads it back exactly
/// and returns false for a torn or altered line.
std::string formatStudyJournalLine(const StudyResult& result);
bool parseStudyJournalLine(const std::string& line, StudyResult& result);
/// The task a journal line names (its first field after the checksum), without checking the checksum;
/// -1 when it names none.
long peekStudyJournalTask(const std::string& line);

/// A journal line a run could not use; its cell, if it names one, is computed again.
struct StudyJournalDrop {
    long line = 0;       ///< in journal.log, 1-based (the header is line 1)
    long task = -1;      ///< the cell the line names (read without trusting a damaged line); -1: none
    std::string kind;    ///< torn, damaged, unreadable, blank, out of range, duplicate, header
    std::string detail;  ///< the why, for a person
    std::string file;    ///< the journal it is in when not journal.log (a shard's)
};
/// A journal's results (after its header line) and the lines it dropped.
struct StudyJournal {
    std::map<long, StudyResult> results;  ///< by task
    std::vector<std::string> lines;       ///< the valid lines, in journal order, without line ends
    std::vector<StudyJournalDrop> dropped;
};
/// Reads the result lines of a journal (its text after the header; firstLine: the number of the first).
/// CRLF line ends and trailing blanks or NUL bytes are tolerated; a last line without its line end is
/// kept when its checksum holds. Every other line that is not a valid result of a task in
/// 0 .. numTasks-1 is listed in `dropped`: torn, damaged (checksum), unreadable, blank, out of range,
/// or a duplicate of an earlier line (the earlier is kept).
StudyJournal parseStudyJournal(const std::string& text, long numTasks, long firstLine = 2);
/// The same reading, one line at a time, in memory independent of the journal's length: `open()` gives
/// the journal's text after its header (called a second time only when lines repeat a task, to name the
/// line kept); every valid result goes to keep(line as kept, result) in journal order; returns the lines
/// dropped.
std::vector<StudyJournalDrop> scanStudyJournal(const std::function<std::unique_ptr<std::istream>()>& open, long numTasks,
                                               long firstLine,
                                               const std::function<void(const std::string&, StudyResult&&)>& keep);
/// One line: the number of lines dropped, by kind, and the cells computed again (those without a
/// result in the journal); "" when none.
std::string summarizeStudyJournalDrops(const std::vector<StudyJournalDrop>& dropped, const StudyJournal* journal = nullptr,
                                       const std::string& file = "journal.log");
/// The same with hasResult(task): whether the journal holds a valid result of the task.
std::string summarizeStudyJournalDrops(const std::vector<StudyJournalDrop>& dropped,
                                       const std::function<bool(long)>& hasResult, const std::string& file);
/// Every dropped line, one per text line: "line 5 (task 4): damaged: ...".
std::string formatStudyJournalDrops(const std::vector<StudyJournalDrop>& dropped);

/// One cell of the summary: a truth, protocol, method and noise level over the subjects.
struct StudySummaryRow {
    std::string truth;
    std::string protocol;
    ElbowValidationSummary stats;  ///< bias, RMSE, coverage over the tasks with an estimate (ok, not-converged)
    int notConverged = 0, failed = 0;
};
/// Per (truth, protocol, method, noise), in the study's order.
std::vector<StudySummaryRow> summarizeStudy(const Study& study, const std::vector<StudyResult>& results);
/// summarizeStudy one result at a time (add them in task order: the sums then match summarizeStudy's to
/// the bit), in memory independent of the number of results.
class StudySummaryAccumulator {
public:
    explicit StudySummaryAccumulator(const Study& study);
    void add(const StudyResult& result);
    std::vector<StudySummaryRow> getRows() const;

private:
    struct Counts {
        int notConverged = 0, failed = 0;
    };
    struct Cell {  // one (truth, protocol)
        std::string truth, protocol;
        ElbowValidationAccumulator stats;
        std::map<std::pair<std::string, double>, Counts> counts;  // by (method, noise)
    };
    std::vector<Cell> cells_;
};
/// summary.csv: counts by status, bias, RMSE, coverage and interval width of the mass, L0T and F0,
/// with standard errors over the subjects.
std::string formatStudySummaryCsv(const std::vector<StudySummaryRow>& rows);

/// Progress of a run, reported by the coordinator (rank 0).
struct StudyProgress {
    long total = 0;       ///< tasks in the study
    long resumed = 0;     ///< found done in the journal at the start
    long done = 0;        ///< done in all (resumed included)
    long failed = 0;      ///< of done
    double elapsed = 0;   ///< [s] since this run started
    double rate = 0;      ///< tasks per second in this run
    double remaining = 0; ///< [s] estimated; NaN before the first task
};

/// Worker threads of one process at most (the command line's --threads bound).
constexpr int kMaxStudyThreads = 1024;

struct StudyRunOptions {
    std::string output;          ///< "" : the study's
    int threads = 0;             ///< worker threads of this process (0 .. kMaxStudyThreads); 0: every CPU it may use
    bool restart = false;        ///< discard a journal (of this or another study) and start over
    std::function<void(const StudyProgress&)> progress;  ///< about once a second and at the end
    std::function<void(const std::string&)> notice;      ///< at the start: what a repaired journal dropped
    /// A share of a job array: groups g with g % shards == shard, journaled in
    /// journal-shard-I-of-N.log (no final files). shards 0: the whole study, merging any shard journals.
    int shard = 0, shards = 0;
    bool merge = false;          ///< assemble the journals into the final files; refuse when cells are missing
    /// Memory bound of writing the final files [bytes of journal text per pass]: results.csv is written
    /// in task order from the journal, one range of tasks per pass (one pass for studies below it).
    long resultsPassBytes = 64L << 20;
};

/// What a finished run did and wrote.
struct StudyOutcome {
    std::string output;                ///< the folder
    long total = 0, resumed = 0, computed = 0, failed = 0, notConverged = 0;
    double wallTime = 0;               ///< [s] this run
    double taskTime = 0;               ///< [s] summed over the tasks computed in this run (all ranks)
    double synthesisTime = 0;          ///< [s] of taskTime
    int ranks = 1, threads = 1;        ///< workers: ranks x threads per rank
    std::vector<std::string> files;    ///< written, in the folder
    std::vector<StudyJournalDrop> journalDrops;  ///< journal lines dropped at the start (also in journal_repairs.log)
    long merged = 0;                   ///< of resumed: cells taken from shard journals
    int shardJournals = 0;             ///< shard journals merged (and removed)
    int shard = 0, shards = 0;         ///< a shard's run: total, resumed and computed count its cells only
    std::string journalSummary;        ///< summarizeStudyJournalDrops of them; "" when none
    /// Work units handed out in this run, each one synthesis of its subject: whole (subject, protocol)
    /// groups while at least as many are left as threads asking, then pieces of a group over the idle
    /// threads (each piece synthesizes the subject again).
    long units = 0;
};

/// Byte transport from the coordinator to worker ranks (MPI in study_mpi.cpp).
class StudyCoordinatorLink {
public:
    virtual ~StudyCoordinatorLink() = default;
    virtual int getNumWorkers() const = 0;          ///< worker ranks (numbered 1 .. n)
    /// A worker's message if one has arrived (does not block).
    virtual bool receive(int& worker, std::string& message) = 0;
    virtual void send(int worker, const std::string& message) = 0;
};
/// Byte transport from a worker rank to the coordinator.
class StudyWorkerLink {
public:
    virtual ~StudyWorkerLink() = default;
    virtual int getRank() const = 0;
    /// Sends message to the coordinator and waits for its reply.
    virtual std::string exchange(const std::string& message) = 0;
};

/// Runs the study's missing tasks on this process's threads (and on the workers behind `link`, which
/// ask for groups as their threads free up: dynamic load balancing), journals each result as it
/// arrives, and writes results.csv, timing.csv, summary.csv, study.yaml and plots to the output folder
/// (each whole or not at all). Throws InputError for an output folder that cannot be used, one that
/// holds another study's journal (unless restart; also a journal with a damaged header whose first
/// result, computed again, differs), or one another run is using.
StudyOutcome runStudy(const Study& study, const StudyRunOptions& options, StudyCoordinatorLink* link = nullptr);
/// A worker rank's part: asks the coordinator for groups, computes them on `threads` threads, sends
/// the results back, until the coordinator has no more.
void runStudyWorker(const Study& study, int threads, StudyWorkerLink& link);

/// true when this process was started by mpirun/mpiexec/srun (OpenMPI, PMIx or PMI environment).
bool isLaunchedByMpi();

}  // namespace armsim
