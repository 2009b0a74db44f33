// JSON report, history CSV and convergence plot of a run.
#include "basics/table.h"
#include "identification/report_io.h"
#include "test_support.h"

#include <fstream>

using namespace armsim;
using namespace armsim::test;
namespace fs = std::filesystem;

namespace {

bool isPng(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    unsigned char h[8] = {};
    in.read(reinterpret_cast<char*>(h), 8);
    const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    return std::equal(sig, sig + 8, h);
}

}  // namespace

TEST(ReportIo, WritesJsonHistoryAndPlotThatMatchTheReport) {
    const ObservationSet data = makeSyntheticData(makeTruth(), thesisAnglePaths());
    IdentificationOptions o;
    o.method = Method::IlcSignSearch;
    const IdentificationReport r = identify(makeProblem(data), SteadyForceModel(), o);
    ASSERT_TRUE(r.isConverged()) << r.message;
    const fs::path dir = tempPath("report");
    const std::vector<std::string> files = writeReportFiles(r, dir.string(), "run");
    ASSERT_EQ(files.size(), 3u);

    std::ifstream in(files[0]);
    const nlohmann::json j = nlohmann::json::parse(in);
    EXPECT_EQ(j["method"], "ilc-sign-search");
    EXPECT_EQ(j["stop_reason"], "converged");
    EXPECT_EQ(j["forward_evaluations"], r.forwardEvaluations);
    EXPECT_EQ(j["parameters"][0]["name"], "mass");
    EXPECT_DOUBLE_EQ(j["parameters"][1]["value"].get<double>(), r.parameters[1].value);
    EXPECT_EQ(j["observations"].size(), data.points.size());
    EXPECT_TRUE(j["parameters"][0]["standard_error"].is_null());   // ILC: no intervals

    const Table h = Table::readCsv(files[1]);
    ASSERT_EQ(h.getNumRows(), int(r.history.size()));
    EXPECT_TRUE(h.hasColumn("mass_kg"));
    EXPECT_TRUE(h.hasColumn("optimal_tendon_length_m"));
    EXPECT_TRUE(h.hasColumn("residual_5_N"));
    const int last = h.getNumRows() - 1;
    EXPECT_NEAR(h.get(last, "mass_kg"), r.parameters[0].value, 1e-11);
    EXPECT_NEAR(h.get(last, "cost_N2"), r.cost, 1e-9 * (1 + r.cost));
    EXPECT_TRUE(isPng(files[2]));
    EXPECT_NE(formatReport(r).find("converged"), std::string::npos);
    fs::remove_all(dir);
}

// A run whose forward model never produced a finite cost has nothing to plot: the report and the
// history are written, the plot is left out (it used to end the command with an internal error).
TEST(ReportIo, ARunWithoutAFiniteCostIsWrittenWithoutAPlot) {
    const ObservationSet data = makeSyntheticData(makeTruth(), thesisAnglePaths());
    IdentificationReport r = identify(makeProblem(data), SteadyForceModel());
    for (IterationRecord& h : r.history) h.cost = NAN;
    const fs::path dir = tempPath("report_nan");
    const std::vector<std::string> files = writeReportFiles(r, dir.string(), "run");
    ASSERT_EQ(files.size(), 2u);
    EXPECT_TRUE(fs::exists(files[0]) && fs::exists(files[1]));
    EXPECT_FALSE(fs::exists(dir / "run_convergence.png"));
    r.history.back().cost = 1.0;  // one finite cost: the plot is back
    EXPECT_EQ(writeReportFiles(r, dir.string(), "run").size(), 3u);
    fs::remove_all(dir);
}

TEST(ReportIo, UnwritablePathsFailAndLeaveNoFile) {
    const ObservationSet data = makeSyntheticData(makeTruth(), {0.375, 0.40});
    const IdentificationReport r = identify(makeProblem(data), SteadyForceModel());
    EXPECT_THROW(writeReportJson("/proc/armsim/r.json", r), std::exception);
    EXPECT_THROW(writeHistoryCsv("/proc/armsim/h.csv", r), std::exception);
    EXPECT_THROW(writeConvergencePlot("/proc/armsim/c.png", r), std::exception);
    EXPECT_FALSE(fs::exists("/proc/armsim/r.json"));
}
