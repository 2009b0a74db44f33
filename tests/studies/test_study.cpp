// Population studies (issue 13): task numbering, the journal line format, a study cell against the
// validation's own computation (a second path to the same numbers), failures recorded, resume from a
// partial and torn journal, hand-damaged journals (CRLF, garbage, altered and duplicate lines: every
// dropped line reported, issue 33), shards of a job array merged, thread-count independence, and bad
// study files.
#include "basics/errors.h"
#include "basics/files.h"
#include "basics/format.h"
#include "basics/plot.h"
#include "studies/study.h"
#include "tests/support/temp_files.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

using namespace armsim;
namespace fs = std::filesystem;

namespace {

fs::path freshDir(const std::string& name) { return armsim::testing::makeFreshDir("study", name); }
std::string readText(const fs::path& p) { return armsim::testing::readFileText(p); }

// 3 subjects x {thesis, one angle} x {1 %, 5 %} x {thesis, synergist-va}: the thesis method cannot
// identify two unknowns from one angle, so 6 of its cells fail by design.
Study makeSmallStudy() {
    Study s;
    s.name = "small";
    s.setPopulation(loadDefaultPopulation());
    s.subjects = 3;
    s.seed = 5;
    StudyProtocol thesis{"thesis", TorqueProtocol()};
    StudyProtocol one{"one_angle.yaml", TorqueProtocol()};
    one.protocol.name = "one_angle";
    one.protocol.conditions = TorqueProtocol::makeFlexionMvcs({90}, 3);
    s.protocols = {thesis, one};
    s.noiseLevels = {0.01, 0.05};
    ElbowMethod a, b;
    a.kind = a.label = "thesis";
    b.kind = b.label = "synergist-va";
    s.methods = {a, b};
    return s;
}

const Study& smallStudy() {
    static const Study s = makeSmallStudy();
    return s;
}

// The uninterrupted run on two threads, computed once for the tests that compare against it.
const std::string& referenceResults() {
    static const std::string text = [] {
        const fs::path d = freshDir("reference");
        StudyRunOptions o;
        o.output = d.string();
        o.threads = 2;
        runStudy(smallStudy(), o);
        return readText(d / "results.csv") + readText(d / "summary.csv");
    }();
    return text;
}

}  // namespace

TEST(Study, TasksAreNumberedSubjectMajorAndGroupedBySubjectAndProtocol) {
    const Study& s = smallStudy();
    ASSERT_EQ(s.getNumTasks(), 3 * 2 * 2 * 2);
    std::set<std::tuple<int, int, int, int>> seen;
    for (long i = 0; i < s.getNumTasks(); ++i) {
        const StudyTask t = getStudyTask(s, i);
        EXPECT_EQ(((long(t.subject) * 2 + t.protocol) * 2 + t.noise) * 2 + t.method, i);
        EXPECT_EQ(t.getGroup(s), i / s.getCellsPerGroup());
        seen.insert({t.subject, t.protocol, t.noise, t.method});
    }
    EXPECT_EQ(long(seen.size()), s.getNumTasks());  // every cell exactly once
    EXPECT_THROW(getStudyTask(s, s.getNumTasks()), std::out_of_range);
}

// The study's cells are the validation's identifications: same subject, data, noise and method give the
// same numbers through runStudyGroup as through runElbowValidation (which shares only the identifier).
TEST(Study, CellsEqualTheElbowValidationOfTheSameSubjects) {
    const Study& s = smallStudy();
    ElbowValidationSettings v;
    v.subjects = 2;
    v.seed = s.seed;
    v.noiseLevels = s.noiseLevels;
    v.activationSd = 0.02;
    v.jobs = 2;
    const std::vector<ElbowValidationRow> rows = runElbowValidation(s.truths[0].population, v);
    int compared = 0;
    for (int subject = 0; subject < 2; ++subject) {
        const long group = long(subject) * 2;  // the thesis protocol
        std::vector<long> tasks;
        for (long t = group * 4; t < group * 4 + 4; ++t) tasks.push_back(t);
        for (const StudyResult& r : runStudyGroup(s, group, tasks)) {
            for (const ElbowValidationRow& w : rows) {
                if (w.subject != subject || w.noise != r.row.noise || w.method != r.row.method) continue;
                EXPECT_EQ(r.row.estimate.mass, w.estimate.mass) << r.row.method;  // bitwise: same computation
                EXPECT_EQ(r.row.estimate.tendonLength, w.estimate.tendonLength);
                EXPECT_EQ(r.row.trueMass, w.trueMass);
                EXPECT_EQ(r.row.massCovered, w.massCovered);
                EXPECT_EQ(r.status == "ok", w.estimate.converged);
                ++compared;
            }
        }
    }
    EXPECT_EQ(compared, 2 * 2 * 2);
}

TEST(Study, JournalLinesRoundTripExactlyAndRejectTornOrAlteredLines) {
    const Study& s = smallStudy();
    const std::vector<StudyResult> results = runStudyGroup(s, 1, {4, 5, 6, 7}, 3);  // subject 0, one angle
    ASSERT_EQ(results.size(), 4u);
    for (const StudyResult& r : results) {
        const std::string line = formatStudyJournalLine(r);
        StudyResult back;
        ASSERT_TRUE(parseStudyJournalLine(line, back)) << line;
        EXPECT_EQ(formatStudyJournalLine(back), line);
        EXPECT_EQ(formatStudyResult(back), formatStudyResult(r));
        EXPECT_EQ(back.rank, 3);
        // The fields themselves, not only their text (a field neither written nor read would pass above).
        auto same = [](double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); };
        EXPECT_EQ(back.task, r.task);
        EXPECT_EQ(back.row.subject, r.row.subject);
        EXPECT_EQ(back.row.method, r.row.method);
        EXPECT_EQ(back.row.estimate.method, r.row.method);
        EXPECT_EQ(back.row.estimate.converged, r.status == "ok");
        EXPECT_EQ(back.row.estimate.iterations, r.row.estimate.iterations);
        EXPECT_EQ(back.row.estimate.numParameters, r.row.estimate.numParameters);
        EXPECT_EQ(back.row.massCovered, r.row.massCovered);
        EXPECT_TRUE(same(back.row.estimate.mass, r.row.estimate.mass));
        EXPECT_TRUE(same(back.row.estimate.tendonUpper, r.row.estimate.tendonUpper));
        EXPECT_TRUE(same(back.row.trueMaxForce, r.row.trueMaxForce));
        EXPECT_TRUE(same(back.row.synergistScale, r.row.synergistScale));
        EXPECT_EQ(back.synthesisTime, std::stod(formatNumber(r.synthesisTime)));
        for (std::size_t cut : {line.size() - 1, line.size() / 2, std::size_t(20)})
            EXPECT_FALSE(parseStudyJournalLine(line.substr(0, cut), back)) << "torn at " << cut;
        std::string altered = line;
        altered[line.size() / 2] = altered[line.size() / 2] == '1' ? '2' : '1';
        EXPECT_FALSE(parseStudyJournalLine(altered, back));
    }
}

// The thesis method on one angle fails (two unknowns, one distinct point): recorded with its reason;
// every other cell completes.
TEST(Study, AFailingTaskIsRecordedWithItsReasonAndTheOthersComplete) {
    const fs::path d = freshDir("failing");
    StudyRunOptions o;
    o.output = d.string();
    o.threads = 2;
    const StudyOutcome out = runStudy(smallStudy(), o);
    EXPECT_EQ(out.computed, 24);
    EXPECT_EQ(out.failed, 6);
    std::istringstream in(readText(d / "results.csv"));
    std::string line;
    std::getline(in, line);
    EXPECT_EQ(line, getStudyResultsHeader());
    int failed = 0, ok = 0;
    long previous = -1;
    while (std::getline(in, line)) {
        const long task = std::stol(line.substr(0, line.find(',')));
        EXPECT_EQ(task, previous + 1);  // sorted, none dropped
        previous = task;
        if (line.find(",failed,") != std::string::npos) {
            ++failed;
            EXPECT_NE(line.find(",one_angle,thesis,"), std::string::npos) << line;
            EXPECT_NE(line.find("expected at least as many distinct points as unknowns"), std::string::npos) << line;
        } else {
            ++ok;
        }
    }
    EXPECT_EQ(failed, 6);
    EXPECT_EQ(ok, 18);
    EXPECT_NE(readText(d / "summary.csv").find("one_angle,thesis,0.01,3,0,0,3,,"), std::string::npos);
    for (const char* f : {"timing.csv", "mass_rmse_vs_noise.png", "mass_coverage_vs_noise.png"})
        EXPECT_TRUE(fs::exists(d / f)) << f;
}

TEST(Study, ResultsDoNotDependOnTheThreadCount) {
    const fs::path d = freshDir("one_thread");
    StudyRunOptions o;
    o.output = d.string();
    o.threads = 1;
    runStudy(smallStudy(), o);
    EXPECT_EQ(readText(d / "results.csv") + readText(d / "summary.csv"), referenceResults());
}

// Cells are the unit of work: one protocol and 2 subjects make 2 groups of 4 cells. On 4 idle threads
// each group is split in 2 (each piece synthesizing its subject): 4 units; on 1 thread, 2 units; on 2,
// 2 units. The files are the same.
TEST(StudyWork, GroupsAreSplitOverIdleThreadsAndTheFilesStayTheSame) {
    Study two = smallStudy();
    two.subjects = 2;
    two.protocols.resize(1);
    std::string files[3];
    const int threads[3] = {1, 2, 4};
    const long units[3] = {2, 2, 4};
    for (int i = 0; i < 3; ++i) {
        const fs::path d = freshDir("split_" + std::to_string(threads[i]));
        StudyRunOptions o;
        o.output = d.string();
        o.threads = threads[i];
        const StudyOutcome r = runStudy(two, o);
        EXPECT_EQ(r.computed, 8);
        EXPECT_EQ(r.units, units[i]) << threads[i] << " threads";
        files[i] = readText(d / "results.csv") + readText(d / "summary.csv");
    }
    EXPECT_EQ(files[0], files[1]);
    EXPECT_EQ(files[0], files[2]);
}

// The final files are written from the journal in task order, a bounded range of tasks per pass
// (memory independent of the number of results): with a pass of 1 byte (one task per bucket file) or
// 2000 bytes (a few tasks each), the files equal the one-pass run's, and no sorting folder is left.
TEST(StudyWork, FinalFilesWrittenInManyPassesEqualTheOnePassFiles) {
    fs::path done;  // a finished study's folder
    for (long bytes : {1L, 2000L}) {
        const fs::path d = done = freshDir("passes_" + std::to_string(bytes));
        StudyRunOptions o;
        o.output = d.string();
        o.threads = 2;
        o.resultsPassBytes = bytes;
        runStudy(smallStudy(), o);
        EXPECT_EQ(readText(d / "results.csv") + readText(d / "summary.csv"), referenceResults()) << bytes << " bytes";
        for (const fs::directory_entry& e : fs::directory_iterator(d))
            EXPECT_EQ(e.path().filename().string().find(".sort"), std::string::npos) << e.path();
    }
    // What a killed run left (a sorting folder, a journal temporary) is removed by the next run.
    const fs::path& d = done;
    fs::create_directories(d / ".sort.99999");
    std::ofstream(d / ".sort.99999" / "0") << "x\n";
    std::ofstream(d / "journal.log.tmp.99999") << "x\n";
    StudyRunOptions o;
    o.output = d.string();
    o.threads = 1;
    EXPECT_EQ(runStudy(smallStudy(), o).computed, 0);
    EXPECT_FALSE(fs::exists(d / ".sort.99999"));
    EXPECT_FALSE(fs::exists(d / "journal.log.tmp.99999"));
}

// A run killed after some groups leaves a journal with complete lines and maybe one torn line; the
// next run computes only what is missing and writes the same files as an uninterrupted run.
TEST(Study, ResumeFromAPartialJournalWithATornLineGivesTheUninterruptedResults) {
    const fs::path full = freshDir("full"), partial = freshDir("partial");
    StudyRunOptions o;
    o.output = full.string();
    o.threads = 2;
    runStudy(smallStudy(), o);
    std::istringstream journal(readText(full / "journal.log"));
    std::string header, line, kept;
    std::getline(journal, header);
    int lines = 0;
    while (std::getline(journal, line))
        if (++lines <= 10) kept += line + '\n';
    ASSERT_EQ(lines, 24);
    std::getline(std::istringstream(readText(full / "journal.log")).ignore(1 << 20, '\n'), line);
    std::ofstream(partial / "journal.log", std::ios::binary) << header << '\n' << kept << line.substr(0, 40);

    o.output = partial.string();
    const StudyOutcome resumed = runStudy(smallStudy(), o);
    EXPECT_EQ(resumed.resumed, 10);
    EXPECT_EQ(resumed.computed, 14);  // the torn line's task is computed again
    EXPECT_EQ(readText(partial / "results.csv") + readText(partial / "summary.csv"), referenceResults());

    const StudyOutcome again = runStudy(smallStudy(), o);  // finished: nothing left to compute
    EXPECT_EQ(again.computed, 0);
    EXPECT_EQ(readText(partial / "results.csv") + readText(partial / "summary.csv"), referenceResults());
}

TEST(Study, AJournalOfAnotherStudyIsRefusedUnlessRestarted) {
    const fs::path d = freshDir("other");
    Study a = smallStudy();
    a.subjects = 1;
    a.protocols.resize(1);
    a.methods.resize(1);
    a.noiseLevels.resize(1);
    StudyRunOptions o;
    o.output = d.string();
    o.threads = 1;
    runStudy(a, o);
    Study b = a;
    b.seed = 6;
    try {
        runStudy(b, o);
        FAIL() << "another study's journal was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("--restart"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find(d.string()), std::string::npos) << e.what();
    }
    o.restart = true;
    EXPECT_EQ(runStudy(b, o).computed, 1);
}

TEST(Study, ReadsAStudyFileAndNamesTheFileLineAndFieldOfEveryError) {
    const fs::path d = freshDir("files");
    std::ofstream(d / "one.yaml") << "kind: torque\nname: one\nconditions:\n  - {flexion_deg: 90}\n";
    const std::string good = "kind: study\nname: s\nsubjects: 2\nprotocols: [thesis, one.yaml]\nnoise_levels: [0.02]\n"
                             "methods:\n  - {method: thesis, label: th\u00e9se \u03bc\U0001F4AA}\n  - {method: synergist-va, label: va, activation_sd: 0.03}\n";
    std::ofstream(d / "good.yaml") << good;
    const Study s = readStudy((d / "good.yaml").string());
    EXPECT_EQ(s.methods[0].label, "th\u00e9se \u03bc\U0001F4AA");  // UTF-8 of 2, 2 and 4 bytes
    EXPECT_EQ(s.subjects, 2);
    ASSERT_EQ(s.protocols.size(), 2u);
    EXPECT_EQ(s.protocols[1].protocol.name, "one");
    ASSERT_EQ(s.methods.size(), 2u);
    EXPECT_EQ(s.methods[1].label, "va");
    EXPECT_EQ(s.methods[1].options.activationSd, 0.03);
    EXPECT_EQ(s.output, "out/study/s");
    EXPECT_EQ(calcStudyFingerprint(s), calcStudyFingerprint(readStudy((d / "good.yaml").string())));

    struct Case {
        std::string text, expected;
    };
    const std::vector<Case> cases = {
        {"kind: torque\n", "expected 'study'"},
        {good + "subject: 3\n", "subject"},                                       // unknown key
        {"kind: study\nsubjects: 0\nprotocols: [thesis]\nmethods:\n  - {method: thesis}\n", "subjects"},
        {"kind: study\nsubjects: 2\nprotocols: [missing.yaml]\nmethods:\n  - {method: thesis}\n", "missing.yaml"},
        {"kind: study\nsubjects: 2\nprotocols: [thesis]\nmethods:\n  - {method: lm}\n", "'method' (methods, entry 1)"},
        {"kind: study\nsubjects: 2\nprotocols: [thesis]\nmethods:\n  - {method: thesis}\n  - {method: thesis}\n",
         "expected unique labels"},
        {"kind: study\nsubjects: 2\nprotocols: [thesis]\nnoise_levels: [0.7]\nmethods:\n  - {method: thesis}\n",
         "'noise_levels' (entry 1)"},
        {"kind: study\nsubjects: 2\nprotocols: [thesis, thesis]\nmethods:\n  - {method: thesis}\n",
         "expected unique protocol names"},
        {"kind: study\nsubjects: 2\nprotocols: []\nmethods:\n  - {method: thesis}\n", "protocols"},
        {"kind: study\nsubjects: 2\nprotocols: [thesis]\nmethods:\n  - {method: thesis, label: \"a\\tb\"}\n",
         "'label' (methods, entry 1)"},
        // Latin-1 bytes (a file not saved as UTF-8): PLplot would print "malformed" and draw nothing.
        {"kind: study\nsubjects: 2\nprotocols: [thesis]\nmethods:\n  - {method: thesis, label: caf\xe9}\n",
         "field 'label' (methods, entry 1) = 'caf\\xe9': not UTF-8 text"},
        {"kind: study\nname: r\xe9sum\xe9\nsubjects: 2\nprotocols: [thesis]\nmethods:\n  - {method: thesis}\n",
         "field 'name' = 'r\\xe9sum\\xe9': not UTF-8 text"},
        // Several truths (issue 31): a prior, unique labels, known keys, one way of naming the truth.
        {"kind: study\nsubjects: 2\ntruths:\n  - {population: default}\nprotocols: [thesis]\nmethods:\n  - {method: thesis}\n",
         "needs 'prior'"},
        {"kind: study\nsubjects: 2\nprior: default\ntruths:\n  - {population: default, label: x}\n"
         "  - {population: " + std::string(ARMSIM_ASSET_DIR) + "/subjects/mismatch/hill_muscles.yaml, label: x}\n"
         "protocols: [thesis]\nmethods:\n  - {method: thesis}\n",
         "'label' (truths, entry 2) = 'x': also the label of entry 1"},
        // The same people under two labels would run every task twice (issue 34).
        {"kind: study\nsubjects: 2\nprior: default\ntruths:\n  - {population: default, label: a}\n"
         "  - {population: default, label: b}\nprotocols: [thesis]\nmethods:\n  - {method: thesis}\n",
         ".yaml:6: truth population 'default' is also the truth at "},
        {"kind: study\nsubjects: 2\nprior: default\ntruths:\n  - {population: default, lable: x}\n"
         "protocols: [thesis]\nmethods:\n  - {method: thesis}\n",
         "lable"},
        {"kind: study\nsubjects: 2\nprior: default\ntruths:\n  - {population: nowhere.yaml}\n"
         "protocols: [thesis]\nmethods:\n  - {method: thesis}\n",
         "nowhere.yaml"},
        {"kind: study\nsubjects: 2\nprior: default\ntruths: []\nprotocols: [thesis]\nmethods:\n  - {method: thesis}\n",
         "empty list"},
        {"kind: study\nsubjects: 2\nprior: default\ntruth: default\ntruths:\n  - {population: default}\n"
         "protocols: [thesis]\nmethods:\n  - {method: thesis}\n",
         "not several"},
    };
    for (std::size_t i = 0; i < cases.size(); ++i) {
        const fs::path p = d / ("bad" + std::to_string(i) + ".yaml");
        std::ofstream(p) << cases[i].text;
        try {
            readStudy(p.string());
            ADD_FAILURE() << "accepted: " << cases[i].text;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(p.string()), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find(cases[i].expected), std::string::npos) << e.what();
        }
    }
}

// Out of family in a study file (issue 31): `truth:` draws the subjects, `prior:` is what the
// identifiers assume; the cells equal runElbowValidation(truth, prior) of the same subjects, an in-family
// study keeps its fingerprint, and `population` with `truth` is refused.
TEST(Study, TruthAndPriorInAStudyFileAreTheOutOfFamilyValidation) {
    const fs::path dir = fs::temp_directory_path() / ("armsim_study_oof_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const std::string stronger = std::string(ARMSIM_ASSET_DIR) + "/subjects/mismatch/stronger.yaml";
    const std::string body = "subjects: 1\nseed: 3\nprotocols: [thesis]\nnoise_levels: [0.02]\nmethods:\n  - {method: synergist}\n";
    std::ofstream(dir / "oof.yaml") << "kind: study\nname: oof\ntruth: " << stronger << "\nprior: default\n" << body;
    std::ofstream(dir / "fam.yaml") << "kind: study\nname: oof\npopulation: " << stronger << "\n" << body;
    std::ofstream(dir / "both.yaml") << "kind: study\nname: oof\npopulation: default\ntruth: " << stronger << "\n" << body;
    const Study oof = readStudy((dir / "oof.yaml").string()), fam = readStudy((dir / "fam.yaml").string());
    EXPECT_EQ(oof.prior.name, "default");
    EXPECT_EQ(oof.truths.at(0).population.name, "stronger");
    EXPECT_NE(calcStudyFingerprint(oof), calcStudyFingerprint(fam));
    ElbowValidationSettings v;
    v.subjects = 1;
    v.seed = 3;
    v.noiseLevels = {0.02};
    v.activationSd = 0;
    const std::vector<ElbowValidationRow> rows = runElbowValidation(oof.truths[0].population, oof.prior, v);
    int compared = 0;
    for (const StudyResult& r : runStudyGroup(oof, 0, {0})) {
        for (const ElbowValidationRow& w : rows)
            if (w.method == r.row.method) {
                EXPECT_EQ(r.row.estimate.mass, w.estimate.mass);   // bitwise: the same computation
                EXPECT_EQ(r.row.trueMass, w.trueMass);
                ++compared;
            }
    }
    EXPECT_EQ(compared, 1);
    try {
        readStudy((dir / "both.yaml").string());
        FAIL() << "population and truth together were accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("not several"), std::string::npos) << e.what();
    }
    fs::remove_all(dir);
}

// Several truths in one study (issue 31's out-of-family study): tasks are truth-major, every truth's
// cells equal runElbowValidation(that truth, prior) of the same subjects, results and summary carry the
// truth's label, and the by-truth heat maps are drawn.
TEST(Study, SeveralTruthsAreEachTheOutOfFamilyValidationOfTheirSubjects) {
    const fs::path dir = freshDir("truths");
    const std::string mismatch = std::string(ARMSIM_ASSET_DIR) + "/subjects/mismatch/";
    std::ofstream(dir / "truths.yaml")
        << "kind: study\nname: truths\nprior: default\ntruths:\n  - {population: default, label: in family}\n"
           "  - {population: " << mismatch << "stronger.yaml}\n  - {population: " << mismatch << "weaker.yaml}\n"
           "subjects: 2\nseed: 3\nprotocols: [thesis]\nnoise_levels: [0.02]\nmethods:\n  - {method: synergist}\n";
    const Study s = readStudy((dir / "truths.yaml").string());
    ASSERT_EQ(s.truths.size(), 3u);
    EXPECT_EQ(s.truths[0].label, "in family");
    EXPECT_EQ(s.truths[1].label, "stronger");  // the population's name
    EXPECT_EQ(s.truths[2].label, "weaker");
    ASSERT_EQ(s.getNumTasks(), 3 * 2);
    for (long i = 0; i < s.getNumTasks(); ++i) {
        const StudyTask t = getStudyTask(s, i);
        EXPECT_EQ(t.truth * 2 + t.subject, i);
        EXPECT_EQ(t.getGroup(s), i);
    }
    // The last truth's second subject, against the validation of that truth with the same prior.
    ElbowValidationSettings v;
    v.subjects = 2;
    v.seed = 3;
    v.noiseLevels = {0.02};
    v.activationSd = 0;
    const std::vector<ElbowValidationRow> rows = runElbowValidation(s.truths[2].population, s.prior, v);
    const std::vector<StudyResult> cell = runStudyGroup(s, 5, {5});
    ASSERT_EQ(cell.size(), 1u);
    EXPECT_EQ(cell[0].truth, "weaker");
    int compared = 0;
    for (const ElbowValidationRow& w : rows)
        if (w.subject == 1 && w.method == "synergist") {
            EXPECT_EQ(cell[0].row.estimate.mass, w.estimate.mass);  // bitwise: the same computation
            EXPECT_EQ(cell[0].row.trueMass, w.trueMass);
            EXPECT_EQ(cell[0].row.trueMaxForce, w.trueMaxForce);
            ++compared;
        }
    EXPECT_EQ(compared, 1);

    StudyRunOptions o;
    o.output = (dir / "out").string();
    o.threads = 2;
    runStudy(s, o);
    const std::string results = readText(dir / "out" / "results.csv");
    EXPECT_EQ(results.rfind("task,truth,subject,protocol,method,", 0), 0u) << results.substr(0, 80);
    EXPECT_NE(results.find("\n5,weaker,1,thesis_mvc,synergist,"), std::string::npos) << results;
    const std::string summary = readText(dir / "out" / "summary.csv");
    for (const char* label : {"\nin family,thesis_mvc,synergist,", "\nstronger,thesis_mvc,synergist,", "\nweaker,thesis_mvc,synergist,"})
        EXPECT_NE(summary.find(label), std::string::npos) << label << " in\n" << summary;
    for (const char* png : {"mass_bias_by_truth.png", "mass_rmse_by_truth.png", "mass_coverage_by_truth.png",
                            "tendon_rmse_by_truth.png"})
        EXPECT_TRUE(isWholePng((dir / "out" / png).string())) << png;
    // Resumed from its journal, the files are the same.
    const std::string first = results + summary;
    StudyRunOptions again = o;
    const StudyOutcome resumed = runStudy(s, again);
    EXPECT_EQ(resumed.computed, 0);
    EXPECT_EQ(readText(dir / "out" / "results.csv") + readText(dir / "out" / "summary.csv"), first);
}


namespace {

// A journal line of task `task` without computing it (the parser only needs a well-formed result).
std::string makeJournalLine(long task) {
    StudyResult r;
    r.task = task;
    r.protocol = "thesis";
    r.status = "ok";
    r.row.subject = int(task);
    r.row.method = r.row.estimate.method = "thesis";
    r.row.noise = 0.02;
    r.row.estimate.mass = 0.1 + 0.01 * double(task);
    return formatStudyJournalLine(r);
}

// 3 subjects x thesis x 1 % x thesis: 3 cells, about a second.
Study makeTinyStudy() {
    Study s = smallStudy();
    s.protocols.resize(1);
    s.noiseLevels.resize(1);
    s.methods.resize(1);
    return s;
}

std::string kindsOf(const StudyJournal& j) {
    std::string out;
    for (const StudyJournalDrop& d : j.dropped) out += std::to_string(d.line) + ":" + std::to_string(d.task) + ":" + d.kind + " ";
    return out;
}

}  // namespace

TEST(StudyJournal, CrlfLineEndsAndTrailingBlanksLoseNothing) {
    const std::string a = makeJournalLine(0), b = makeJournalLine(1), c = makeJournalLine(2);
    const StudyJournal crlf = parseStudyJournal(a + "\r\n" + b + "\r\n" + c + "\r\n", 3);
    EXPECT_EQ(crlf.results.size(), 3u);
    EXPECT_TRUE(crlf.dropped.empty()) << kindsOf(crlf);
    EXPECT_EQ(crlf.lines, (std::vector<std::string>{a, b, c}));  // kept without the CR
    const StudyJournal blanks = parseStudyJournal(a + "  \t\n" + b + "\n" + c, 3);  // last line whole, no line end
    EXPECT_EQ(blanks.results.size(), 3u);
    EXPECT_TRUE(blanks.dropped.empty()) << kindsOf(blanks);
    EXPECT_EQ(summarizeStudyJournalDrops(blanks.dropped), "");
}

TEST(StudyJournal, EveryDroppedLineIsListedWithItsCellAndWhy) {
    const std::string a = makeJournalLine(0), b = makeJournalLine(1), c = makeJournalLine(2), d = makeJournalLine(3);
    std::string altered = b;
    altered[altered.size() / 2] = altered[altered.size() / 2] == '1' ? '2' : '1';
    const std::string text = a + "\n" +                         // line 2: kept
                             altered + "\n" +                   // 3: damaged, task 1
                             "\n" +                             // 4: blank
                             a + "\n" +                         // 5: duplicate of line 2
                             makeJournalLine(99) + "\n" +       // 6: out of range
                             "rm -rf / # not a journal line\n" + // 7: unreadable
                             c + "\n" +                         // 8: kept
                             std::string(5, '\0') + "\n" +      // 9: a NUL-filled tail
                             d.substr(0, 40);                   // 10: torn, task 3
    const StudyJournal j = parseStudyJournal(text, 10);
    EXPECT_EQ(j.results.size(), 2u);
    EXPECT_EQ(j.lines, (std::vector<std::string>{a, c}));
    EXPECT_EQ(kindsOf(j), "3:1:damaged 4:-1:blank 5:0:duplicate 6:99:out of range 7:-1:unreadable 9:-1:blank "
                          "10:3:torn ");
    const std::string summary = summarizeStudyJournalDrops(j.dropped, &j);
    EXPECT_NE(summary.find("7 lines dropped (2 blank, 1 damaged, 1 duplicate, 1 out of range, 1 torn, 1 unreadable)"),
              std::string::npos) << summary;
    EXPECT_NE(summary.find("computed again: tasks 1, 3"), std::string::npos) << summary;
    EXPECT_NE(summary.find("1 line named no readable task"), std::string::npos) << summary;
    const std::string details = formatStudyJournalDrops(j.dropped);
    EXPECT_NE(details.find("line 3 (task 1): damaged: its checksum does not match"), std::string::npos) << details;
    EXPECT_NE(details.find("line 5 (task 0): duplicate: task 0 is also line 2"), std::string::npos) << details;
    EXPECT_NE(details.find("line 9: blank: only NUL bytes"), std::string::npos) << details;
    EXPECT_NE(details.find("line 10 (task 3): torn"), std::string::npos) << details;
}

// A journal converted to CRLF and damaged by hand: the run keeps every intact cell, recomputes the
// damaged ones, says which (notice, outcome, journal_repairs.log) and writes the uninterrupted files.
TEST(StudyJournal, AHandDamagedJournalIsRepairedVisiblyAndEndsWithTheUninterruptedFiles) {
    const fs::path full = freshDir("journal_full"), damaged = freshDir("journal_damaged");
    const Study s = makeTinyStudy();
    StudyRunOptions o;
    o.output = full.string();
    o.threads = 2;
    const StudyOutcome first = runStudy(s, o);
    ASSERT_EQ(first.total, 3);
    EXPECT_TRUE(first.journalDrops.empty());
    EXPECT_FALSE(fs::exists(full / "journal_repairs.log"));

    std::istringstream in(readText(full / "journal.log"));
    std::string header, line;
    std::getline(in, header);
    std::vector<std::string> lines;
    while (std::getline(in, line)) lines.push_back(line);
    ASSERT_EQ(lines.size(), 3u);
    std::sort(lines.begin(), lines.end(), [](const std::string& x, const std::string& y) {
        return std::stol(x.substr(17)) < std::stol(y.substr(17));  // by task
    });
    lines[1][lines[1].size() / 2] = lines[1][lines[1].size() / 2] == '1' ? '2' : '1';  // task 1 altered
    std::ofstream(damaged / "journal.log", std::ios::binary)
        << header << "\r\n" << lines[0] << "\r\n" << lines[1] << "\r\n" << lines[2] << "\r\n" << "garbage\x01\x02\r\n";

    std::vector<std::string> notices;
    o.output = damaged.string();
    o.notice = [&](const std::string& text) { notices.push_back(text); };
    const StudyOutcome repaired = runStudy(s, o);
    EXPECT_EQ(repaired.resumed, 2);   // tasks 0 and 2 survive the CRLF
    EXPECT_EQ(repaired.computed, 1);  // task 1 again
    ASSERT_EQ(repaired.journalDrops.size(), 2u);
    EXPECT_EQ(repaired.journalDrops[0].kind, "damaged");
    EXPECT_EQ(repaired.journalDrops[0].task, 1);
    EXPECT_EQ(repaired.journalDrops[0].line, 3);
    EXPECT_EQ(repaired.journalDrops[1].kind, "unreadable");
    ASSERT_EQ(notices.size(), 1u);
    EXPECT_NE(notices[0].find("2 lines dropped (1 damaged, 1 unreadable); computed again: task 1"), std::string::npos)
        << notices[0];
    const std::string record = readText(damaged / "journal_repairs.log");
    EXPECT_NE(record.find("line 3 (task 1): damaged"), std::string::npos) << record;
    EXPECT_NE(record.find("line 5: unreadable"), std::string::npos) << record;
    EXPECT_EQ(readText(damaged / "results.csv") + readText(damaged / "summary.csv"),
              readText(full / "results.csv") + readText(full / "summary.csv"));

    notices.clear();
    const StudyOutcome again = runStudy(s, o);  // the journal was compacted: nothing more to drop
    EXPECT_TRUE(again.journalDrops.empty());
    EXPECT_TRUE(notices.empty());
    EXPECT_EQ(again.resumed, 3);
    EXPECT_EQ(readText(damaged / "journal_repairs.log"), record);  // the record stays
}

TEST(StudyJournal, ThreadsOutOfRangeAreRefusedWithTheValue) {
    StudyRunOptions o;
    o.output = freshDir("threads").string();
    for (int threads : {-3, 5000}) {
        o.threads = threads;
        try {
            runStudy(smallStudy(), o);
            FAIL() << "threads = " << threads << " was accepted";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("'threads' = " + std::to_string(threads)), std::string::npos) << e.what();
        }
    }
}

// A damaged header (an editor, a disk error) is recovered when the journal's first result, computed
// again, equals its line; the same damaged journal under another seed is refused; a file with no
// result line starts over. Each says so.
TEST(StudyJournal, ADamagedHeaderIsRecoveredOnlyForTheStudyWhoseResultsItHolds) {
    const Study s = makeTinyStudy();
    const fs::path full = freshDir("header_full"), damaged = freshDir("header_damaged"), other = freshDir("header_other"),
                   junk = freshDir("header_junk");
    StudyRunOptions o;
    o.output = full.string();
    o.threads = 2;
    runStudy(s, o);
    const std::string journal = readText(full / "journal.log");
    const std::string body = journal.substr(journal.find('\n') + 1);
    const std::string broken = std::string("# armsim stu\x17\x00dy jo") + "\n" + body;  // line 1 overwritten
    std::ofstream(damaged / "journal.log", std::ios::binary) << broken;
    std::ofstream(other / "journal.log", std::ios::binary) << broken;
    std::ofstream(junk / "journal.log", std::ios::binary) << "\x7f\x45garbage\n";

    std::vector<std::string> notices;
    o.notice = [&](const std::string& text) { notices.push_back(text); };
    o.output = damaged.string();
    const StudyOutcome recovered = runStudy(s, o);
    EXPECT_EQ(recovered.resumed, 3);
    EXPECT_EQ(recovered.computed, 0);
    ASSERT_EQ(notices.size(), 1u);
    EXPECT_NE(notices[0].find("journal.log: 1 line dropped (1 header); the header was damaged: recovered (task"),
              std::string::npos) << notices[0];
    EXPECT_NE(readText(damaged / "journal_repairs.log").find("line 1: header: the header line is damaged"),
              std::string::npos);
    EXPECT_EQ(readText(damaged / "results.csv"), readText(full / "results.csv"));
    EXPECT_EQ(readText(damaged / "journal.log"), journal);  // compacted under a good header again

    Study reseeded = s;
    reseeded.seed = 6;
    o.output = other.string();
    try {
        runStudy(reseeded, o);
        FAIL() << "a damaged journal of another seed was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("header is damaged and its results are not this study's"), std::string::npos)
            << e.what();
        EXPECT_NE(std::string(e.what()).find("--restart"), std::string::npos) << e.what();
    }
    EXPECT_EQ(readText(other / "journal.log"), broken);  // refused: left as it was

    notices.clear();
    o.output = junk.string();
    const StudyOutcome fresh = runStudy(s, o);
    EXPECT_EQ(fresh.computed, 3);
    ASSERT_EQ(notices.size(), 1u);
    EXPECT_NE(notices[0].find("no line is a result: nothing to resume"), std::string::npos) << notices[0];
}

// Job arrays (--shard I/N): each shard computes its groups (g % N == I) into its own journal and writes
// no files; --merge takes the finished shards' journals into journal.log but refuses to write files
// while cells are missing; a shard still running blocks the merge; the merge after the last shard
// computes nothing and writes the uninterrupted run's files.
TEST(StudyShards, ShardsThenAPlainRunWriteTheUninterruptedFiles) {
    const fs::path d = freshDir("shards");
    StudyRunOptions o;
    o.output = d.string();
    o.threads = 1;
    o.shards = 3;
    long computed = 0;
    for (int shard : {0, 1}) {
        o.shard = shard;
        const StudyOutcome r = runStudy(smallStudy(), o);
        EXPECT_EQ(r.total, 8);  // 2 of the 6 groups x 4 cells
        EXPECT_EQ(r.computed, 8);
        EXPECT_EQ(r.files, std::vector<std::string>{"journal-shard-" + std::to_string(shard) + "-of-3.log"});
        computed += r.computed;
    }
    EXPECT_FALSE(fs::exists(d / "results.csv"));
    EXPECT_THROW(runStudy(smallStudy(), StudyRunOptions{o.output, 1, false, {}, {}, 3, 3}), InputError);  // no shard 3/3

    StudyRunOptions merge;
    merge.output = d.string();
    merge.merge = true;
    try {
        runStudy(smallStudy(), merge);
        FAIL() << "--merge with shard 2/3 missing was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("--merge: 8 of 24 cells are in no journal"), std::string::npos) << e.what();
    }
    o.shard = 2;
    computed += runStudy(smallStudy(), o).computed;
    EXPECT_EQ(computed, 24);

    {  // shard 2 running again (its lock held): the merge waits for it
        const int fd = ::open((d / ".lock-shard-2-of-3").c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
        ASSERT_GE(fd, 0);
        ASSERT_EQ(::flock(fd, LOCK_EX | LOCK_NB), 0);
        try {
            runStudy(smallStudy(), merge);
            FAIL() << "a merge while a shard runs was accepted";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("shard 2-of-3 is still running"), std::string::npos) << e.what();
        }
        ::close(fd);
    }
    const StudyOutcome merged = runStudy(smallStudy(), merge);
    EXPECT_EQ(merged.computed, 0);
    EXPECT_EQ(merged.resumed, 24);
    EXPECT_EQ(merged.merged, 8);  // shard 2's; the first --merge took shards 0 and 1 into journal.log
    EXPECT_EQ(merged.shardJournals, 1);
    EXPECT_EQ(readText(d / "results.csv") + readText(d / "summary.csv"), referenceResults());
    for (int shard : {0, 1, 2}) EXPECT_FALSE(fs::exists(d / ("journal-shard-" + std::to_string(shard) + "-of-3.log")));
    StudyRunOptions plain;
    plain.output = o.output;
    plain.threads = 1;
    const StudyOutcome again = runStudy(smallStudy(), plain);  // all in journal.log now
    EXPECT_EQ(again.resumed, 24);
    EXPECT_EQ(again.merged, 0);
}
