// armsim identify / validate end to end (the built binary through popen): reports written whole,
// bad data rejected with file and line, a tiny validation table.
#include "basics/table.h"
#include "tests/support/run_armsim.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

constexpr int kInputErrorExit = 2;             // main(): InputError
constexpr std::uintmax_t kMinPngBytes = 1000;  // a real plot, not an empty file
constexpr double kThesisTable73Tol = 0.01;     // relative: steady estimate vs thesis Table 7.3 (337.7 g, 24.4 cm)

using armsim::testing::CommandResult;
using armsim::testing::runArmsim;

fs::path freshDir(const std::string& name) {
    const fs::path d = fs::temp_directory_path() / ("armsim_ident_cli_" + name + "_" + std::to_string(::getpid()));
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

std::string measuredFile() { return std::string(ARMSIM_ASSET_DIR) + "/measured/thesis_measured.csv"; }

void expectReportFiles(const fs::path& d) {
    ASSERT_TRUE(fs::exists(d / "identification.json"));
    std::ifstream in(d / "identification.json");
    const nlohmann::json j = nlohmann::json::parse(in);
    EXPECT_EQ(j["parameters"].size(), 2u);
    EXPECT_EQ(j["model_checks"].size(), 2u);  // steady and faithful re-checks
    const armsim::Table h = armsim::Table::readCsv((d / "identification_history.csv").string());
    EXPECT_GT(h.getNumRows(), 1);
    EXPECT_TRUE(h.hasColumn("mass_kg"));
    EXPECT_GT(fs::file_size(d / "identification_convergence.png"), kMinPngBytes);
}

/// Writes `body` after a header to a fresh file; returns its path.
std::string writeData(const fs::path& dir, const std::string& name, const std::string& body) {
    const fs::path p = dir / name;
    std::ofstream(p) << "path_cm,force_N\n" << body;
    return p.string();
}

}  // namespace

TEST(CliIdentify, ShippedMeasuredFileGivesTheThesisEstimateAndWritesTheReport) {
    const fs::path d = freshDir("measured");
    const CommandResult r = runArmsim("identify " + measuredFile() + " --out " + d.string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("converged"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("re-check with the faithful model"), std::string::npos) << r.output;
    expectReportFiles(d);
    std::ifstream in(d / "identification.json");
    const nlohmann::json j = nlohmann::json::parse(in);
    EXPECT_LT(std::abs(j["parameters"][0]["value"].get<double>() / 0.3377 - 1), kThesisTable73Tol);
    EXPECT_LT(std::abs(j["parameters"][1]["value"].get<double>() / 0.244 - 1), kThesisTable73Tol);
}

TEST(CliIdentify, FaithfulModelRunsOnTheMeasuredFile) {
    const fs::path d = freshDir("faithful");
    const CommandResult r = runArmsim("identify " + measuredFile() + " --forward faithful --method ilc-sign-search --out " +
                                      d.string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("faithful model (moment-arm estimate"), std::string::npos) << r.output;
    expectReportFiles(d);
}

TEST(CliIdentify, BadDataExitsNonZeroNamingFileAndLine) {
    const fs::path d = freshDir("bad");
    struct Case {
        std::string name, body, expected;
    };
    const Case cases[] = {
        {"nan.csv", "41,600\n37.5,nan\n", "nan.csv:3"},
        {"negative.csv", "41,-600\n37.5,458\n", "negative.csv:2"},
        {"one_point.csv", "41,600\n", "one_point.csv:2"},
        {"duplicate.csv", "41,600\n37.5,458\n41,600\n", "duplicate.csv:4"},
    };
    for (const Case& c : cases) {
        const std::string file = writeData(d, c.name, c.body);
        const CommandResult r = runArmsim("identify " + file + " --out " + (d / "out").string());
        EXPECT_EQ(r.exitCode, kInputErrorExit) << c.name << ": " << r.output;
        EXPECT_NE(r.output.find(c.expected), std::string::npos) << c.name << ": " << r.output;
    }
    EXPECT_FALSE(fs::exists(d / "out" / "identification.json"));  // nothing written for bad data

    // A path the arm cannot take is an error for the faithful model, with file and line.
    const std::string far = writeData(d, "far.csv", "41,600\n30,300\n");
    const CommandResult r = runArmsim("identify " + far + " --forward faithful --out " + (d / "out").string());
    EXPECT_EQ(r.exitCode, kInputErrorExit) << r.output;
    EXPECT_NE(r.output.find("far.csv:3"), std::string::npos) << r.output;
}

// 600 N at 37.5 cm and 50 N at 40 cm: no mass and tendon length make this force ratio. The command
// reports the stop as not converged with the reason, and keeps the report, history and plot.
TEST(CliIdentify, DataNoModelReproducesStopNotConvergedWithTheReasonAndTheHistory) {
    const fs::path d = freshDir("noconverge");
    const std::string data = writeData(d, "d.csv", "37.5,600\n40,50\n");
    const CommandResult r = runArmsim("identify " + data + " --out " + (d / "id").string());
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("not-converged"), std::string::npos) << r.output;
    expectReportFiles(d / "id");
    std::ifstream in(d / "id" / "identification.json");
    const nlohmann::json j = nlohmann::json::parse(in);
    EXPECT_FALSE(j["converged"].get<bool>());
    EXPECT_EQ(j["stop_reason"], "not-converged");
    EXPECT_NE(j["message"].get<std::string>().find("the model cannot produce these forces"), std::string::npos)
        << j["message"];
    const armsim::Table h = armsim::Table::readCsv((d / "id" / "identification_history.csv").string());
    EXPECT_EQ(h.getNumRows(), j["history_length"].get<int>());
}

TEST(CliIdentify, BadOptionsNameTheOption) {
    CommandResult r = runArmsim("identify " + measuredFile() + " --bounds mass=0.5");
    EXPECT_EQ(r.exitCode, kInputErrorExit) << r.output;
    EXPECT_NE(r.output.find("--bounds"), std::string::npos) << r.output;
    r = runArmsim("identify " + measuredFile() + " --start tendon=0.2");
    EXPECT_EQ(r.exitCode, kInputErrorExit) << r.output;
    EXPECT_NE(r.output.find("unknown parameter 'tendon'"), std::string::npos) << r.output;
}

TEST(CliIdentify, ThesisCasesPrintOursBesideTheThesis) {
    const fs::path d = freshDir("thesis");
    const CommandResult r = runArmsim("identify --thesis-cases --out " + d.string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    for (const char* c : {"Table 7.1 ilc-standard", "Table 7.2 ilc-sign-search", "Table 7.3 lm"})
        EXPECT_NE(r.output.find(c), std::string::npos) << c << "\n" << r.output;
    EXPECT_TRUE(fs::exists(d / "thesis_cases_steady.csv"));
}

TEST(CliValidate, TinyConfigurationPrintsItsTableAndWritesTheCsv) {
    const fs::path d = freshDir("validate");
    const CommandResult r = runArmsim("validate --seeds 0 --noise 0,2 --methods lm --out " + d.string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("thesis"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("dM (%)"), std::string::npos) << r.output;
    std::ifstream in(d / "validation.csv");
    std::string header, line;
    std::getline(in, header);
    int rows = 0;
    while (std::getline(in, line)) ++rows;
    EXPECT_EQ(rows, 2);
    EXPECT_NE(header.find("mass_error_pct"), std::string::npos);
    const CommandResult bad = runArmsim("validate --noise 80 --out " + d.string());
    EXPECT_EQ(bad.exitCode, kInputErrorExit) << bad.output;
    EXPECT_NE(bad.output.find("noise"), std::string::npos) << bad.output;
}

// validate --truth elbow: both identifiers on drawn subjects, per-subject and summary CSV, plots; the
// elbow-only options are refused without it.
// Population and protocol files are found as every file option finds them: a path, or a name under the
// assets folder (the shipped `subjects/...` and `protocols/...`).
TEST(CliValidate, PopulationAndProtocolNamesUnderTheAssetsFolderAreFound) {
    const fs::path d = freshDir("validate_by_name");
    const CommandResult r = runArmsim("validate --truth elbow --subjects 1 --truth-population subjects/mismatch/stronger.yaml "
                                      "--protocol protocols/designed_emg_torque.yaml --activation-sd 0 --out " + d.string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("stronger"), std::string::npos) << r.output;
    EXPECT_TRUE(fs::exists(d / "elbow_validation.csv"));
}

TEST(CliValidate, ElbowTruthWritesPerSubjectAndSummaryFilesAndPlots) {
    const fs::path d = freshDir("elbow_validate");
    const CommandResult r = runArmsim("validate --truth elbow --subjects 3 --jobs 2 --out " + d.string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    auto readLines = [](const fs::path& p) {
        std::vector<std::vector<std::string>> lines;
        std::ifstream in(p);
        for (std::string line; std::getline(in, line);) {
            std::vector<std::string> cells;
            std::stringstream ss(line);
            for (std::string c; std::getline(ss, c, ',');) cells.push_back(c);
            lines.push_back(cells);
        }
        return lines;
    };
    const auto rows = readLines(d / "elbow_validation.csv");
    ASSERT_EQ(rows.size(), 10u);  // header + 3 subjects x 3 methods
    ASSERT_EQ(rows[0][4], "true_mass_kg");
    ASSERT_EQ(rows[0][5], "mass_kg");
    ASSERT_EQ(rows[0][8], "mass_error_pct");
    for (std::size_t i = 1; i < rows.size(); ++i) {
        const double truth = std::stod(rows[i][4]), mass = std::stod(rows[i][5]), error = std::stod(rows[i][8]);
        EXPECT_NEAR(error, 100 * (mass / truth - 1), 1e-6 * (1 + std::abs(error))) << i;
    }
    const auto summary = readLines(d / "elbow_validation_summary.csv");
    ASSERT_EQ(summary.size(), 4u);  // header + thesis + synergist + synergist-va
    EXPECT_EQ(summary[1][0], "thesis");
    EXPECT_EQ(summary[2][0], "synergist");
    EXPECT_EQ(summary[3][0], "synergist-va");
    for (const char* png : {"mass_identified_vs_true.png", "mass_error_vs_activation.png", "mass_error_vs_synergists.png"})
        EXPECT_GT(fs::file_size(d / png), kMinPngBytes) << png;
    EXPECT_NE(r.output.find("synergist"), std::string::npos) << r.output;

    for (const char* option : {"--subjects 3", "--angles 30,90", "--repetitions 2"}) {
        const CommandResult bad = runArmsim("validate " + std::string(option) + " --out " + d.string());
        EXPECT_EQ(bad.exitCode, kInputErrorExit) << bad.output;
        EXPECT_NE(bad.output.find("needs --truth elbow"), std::string::npos) << bad.output;
    }
    // Out of family: the stronger mismatch population as the truth, the default population as the prior.
    const fs::path o = freshDir("elbow_validate_out_of_family");
    const CommandResult oof = runArmsim("validate --truth elbow --truth-population " + std::string(ARMSIM_ASSET_DIR) +
                                        "/subjects/mismatch/stronger.yaml --subjects 1 --jobs 2 --out " + o.string());
    ASSERT_EQ(oof.exitCode, 0) << oof.output;
    EXPECT_NE(oof.output.find("out of family: truth population 'stronger'"), std::string::npos) << oof.output;
    EXPECT_NE(oof.output.find("prior 'default'"), std::string::npos) << oof.output;
    EXPECT_EQ(readLines(o / "elbow_validation.csv").size(), 4u);
    const CommandResult outside = runArmsim("validate --truth elbow --subjects 1 --angles 30,170 --out " + d.string());
    EXPECT_EQ(outside.exitCode, kInputErrorExit) << outside.output;
    EXPECT_NE(outside.output.find("170"), std::string::npos) << outside.output;
}

// The design pipeline end to end: `design` writes a protocol file, `protocol` runs it on the subject it
// names and writes torque data, `identify-torque` fits those data with every method that applies.
TEST(CliDesign, DesignedProtocolRunsAndItsDataAreIdentified) {
    const fs::path d = freshDir("design_pipeline");
    CommandResult r = runArmsim("design --draws 4 --trials 6 --repetitions 2 --levels 0.5 --validate-subjects 1 --out " +
                                (d / "design").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const fs::path protocol = d / "design" / "designed_protocol.yaml";
    ASSERT_TRUE(fs::exists(protocol)) << r.output;
    EXPECT_NE(r.output.find("designed protocol:"), std::string::npos) << r.output;
    // Counted before the design's work: 2 protocols x (thesis, synergist, synergist-va) for one subject.
    EXPECT_NE(r.output.find("then validation of both protocols on 1 subject: about 6 fits"), std::string::npos) << r.output;
    EXPECT_LT(r.output.find("about 6 fits"), r.output.find("greedy picks")) << r.output;
    for (const char* f : {"design_predictions.csv", "design_steps.csv", "design_criterion.png"})
        EXPECT_TRUE(fs::exists(d / "design" / f)) << f;
    {  // --validate-subjects: both protocols, both synergist methods
        std::ifstream v(d / "design" / "design_validation.csv");
        std::vector<std::string> lines;
        for (std::string line; std::getline(v, line);) lines.push_back(line);
        ASSERT_EQ(lines.size(), 5u);
        EXPECT_EQ(lines[1].rfind("thesis,synergist,1,", 0), 0u) << lines[1];
        EXPECT_EQ(lines[4].rfind("designed,synergist-va,1,", 0), 0u) << lines[4];
    }
    r = runArmsim("validate --truth elbow --protocol " + protocol.string() + " --angles 90");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("--protocol replaces --angles"), std::string::npos) << r.output;

    r = runArmsim("protocol " + protocol.string() + " --out " + (d / "run").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    std::ifstream in(d / "run" / "torque_data.csv");
    int rows = 0;
    for (std::string line; std::getline(in, line);)
        if (!line.empty() && line[0] != '#' && line.rfind("flexion_deg", 0) != 0) ++rows;
    EXPECT_EQ(rows, 6);  // the budget

    r = runArmsim("identify-torque " + (d / "run" / "torque_data.csv").string() + " --activation 0.9 --out " +
                  (d / "fit").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    std::ifstream est(d / "fit" / "torque_estimates.csv");
    std::string header, line;
    std::getline(est, header);
    int fits = 0;
    while (std::getline(est, line)) {
        const std::string method = line.substr(0, line.find(','));
        EXPECT_TRUE(method == "thesis" || method == "synergist" || method == "synergist-va") << line;
        fits += method != "thesis";
    }
    EXPECT_EQ(fits, 2);  // synergist and synergist-va
    EXPECT_TRUE(fs::exists(d / "fit" / "torque_fit.png"));

    r = runArmsim("identify-torque " + (d / "missing.csv").string());
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("missing.csv"), std::string::npos) << r.output;

    // Where the judging noise comes from is said as it is: with no repeated condition it is the prior
    // population's, not "estimated from the repetitions".
    {
        std::ofstream single(d / "single.csv");
        single << "flexion_deg,torque_Nm\n90,60\n45,50\n120,55\n30,40\n135,45\n";
    }
    r = runArmsim("identify-torque " + (d / "single.csv").string() + " --out " + (d / "single_fit").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("no condition is repeated to estimate it from"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("estimated from the repetitions"), std::string::npos) << r.output;
    // Repetitions that agree exactly (numbered: without numbers a row twice is refused as pasted twice):
    // the level is raised to its floor, and the line says so.
    {
        std::ofstream twice(d / "twice.csv");
        twice << "flexion_deg,torque_Nm,repetition\n90,60,0\n45,50,0\n120,55,0\n90,60,1\n45,50,1\n120,55,1\n";
    }
    r = runArmsim("identify-torque " + (d / "twice.csv").string() + " --out " + (d / "twice_fit").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("relative torque sd of 0.2 % (estimated from the repetitions, 3 degrees of freedom; raised to "
                            "the floor of 0.2 %"), std::string::npos) << r.output;
}

// The two-axis protocol (docs/channels.md): its run writes the forearm axis and the supination efforts,
// and identify-torque fits the forearm readings as a channel of their own, for every synergist-aware
// method, each judged consistent with the noise on this person of the protocol's population.
TEST(CliIdentifyTorque, TwoAxisProtocolReadsAndFitsTheForearmAxis) {
    const fs::path d = freshDir("two_axis");
    const std::string protocol = std::string(ARMSIM_ASSET_DIR) + "/protocols/two_axis.yaml";
    CommandResult r = runArmsim("protocol " + protocol + " --out " + (d / "run").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("supination"), std::string::npos) << r.output;
    std::ifstream data(d / "run" / "torque_data.csv");
    std::string header, line;
    while (std::getline(data, header) && header.rfind("#", 0) == 0) {}
    EXPECT_EQ(header, "flexion_deg,effort,level,repetition,torque_Nm,rotation_deg,forearm_torque_Nm,activation,"
                      "clean_torque_Nm,clean_forearm_torque_Nm");
    r = runArmsim("identify-torque " + (d / "run" / "torque_data.csv").string() + " --channels " +
                  (d / "run" / "channel_data.csv").string() + " --activation 0.93 --out " + (d / "fit").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    std::ifstream in(d / "fit" / "channel_fits.csv");
    std::getline(in, header);
    int forearm = 0;
    while (std::getline(in, line)) {
        if (line.find(",forearm_torque,") == std::string::npos) continue;
        ++forearm;
        EXPECT_NE(line.find(",noise,"), std::string::npos) << line;
        EXPECT_NE(line.find(",25,"), std::string::npos) << line;  // 15 flexion and 10 supination trials
    }
    EXPECT_EQ(forearm, 3);  // synergist, synergist-va, channels
}

// docs/channels.md's worked example: the recommended protocol writes every channel beside the torque,
// and identify-torque --channels fits them, prints the per-channel check and writes channel_fits.csv
// and the F0 columns. A bad channel file names its line.
TEST(CliIdentifyTorque, RecommendedProtocolChannelsAreSynthesizedAndFitted) {
    const fs::path d = freshDir("channels");
    const std::string protocol = std::string(ARMSIM_ASSET_DIR) + "/protocols/recommended.yaml";
    CommandResult r = runArmsim("protocol " + protocol + " --out " + (d / "recommended").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    for (const char* f : {"torque_data.csv", "channel_data.csv", "fascicle_length.png", "emg.png"})
        EXPECT_TRUE(fs::exists(d / "recommended" / f)) << f;
    r = runArmsim("identify-torque " + (d / "recommended" / "torque_data.csv").string() + " --channels " +
                  (d / "recommended" / "channel_data.csv").string() + " --activation 0.93 --out " +
                  (d / "identify_channels").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("channels fit: F0"), std::string::npos) << r.output;
    std::ifstream in(d / "identify_channels" / "channel_fits.csv");
    std::string header, line;
    std::getline(in, header);
    EXPECT_EQ(header, "method,channel,n,chi_square,p_value,verdict,worst,worst_residual_sd");
    int channels = 0;
    while (std::getline(in, line)) channels += line.rfind("channels,", 0) == 0;
    EXPECT_EQ(channels, 7);  // torque, fascicle_length, emg, volume, upper_arm_length, activation, prior
    std::ifstream est(d / "identify_channels" / "torque_estimates.csv");
    std::getline(est, header);
    EXPECT_NE(header.find("max_force_N"), std::string::npos) << header;
    bool found = false;
    while (std::getline(est, line)) found = found || line.rfind("channels,1,", 0) == 0;
    EXPECT_TRUE(found) << "no converged channels estimate";

    std::ofstream(d / "bad.csv") << "channel,muscle,value,sd\nvolume,BIClong,0.0002,0.00002\nvolume,NOPE,0.0002,0.00002\n";
    r = runArmsim("identify-torque " + (d / "recommended" / "torque_data.csv").string() + " --channels " +
                  (d / "bad.csv").string() + " --out " + (d / "bad").string());
    EXPECT_EQ(r.exitCode, kInputErrorExit) << r.output;
    EXPECT_NE(r.output.find("bad.csv:3"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("NOPE"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(d / "bad"));
}
