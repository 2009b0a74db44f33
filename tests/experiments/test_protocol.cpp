// Experiment protocols: the shipped files, malformed files, determinism (seed, threads), agreement
// of the summary tables with the per-trial files, %MVC resolution and EMG normalisation, the
// composition grid, and runs that fail without leaving output behind.
#include "basics/csv.h"
#include "basics/errors.h"
#include "basics/files.h"
#include "basics/storage_file.h"
#include "experiments/protocol.h"
#include "model/geometry.h"
#include "tests/support/temp_files.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

using namespace armsim;
namespace fs = std::filesystem;

namespace {

fs::path freshDir(const std::string& name) { return armsim::testing::makeFreshDir("protocol", name); }
std::string readText(const fs::path& p) { return armsim::testing::readFileText(p); }

const std::string kProtocols = std::string(ARMSIM_ASSET_DIR) + "/protocols/";
constexpr double kAngleTol = 1e-9;       // deg, degree -> radian -> degree round trip
constexpr double kNormTol = 1e-12;       // quantities that are 1 by construction
constexpr double kForceTol = 1e-6;       // N, bisection to 1e-12 in U at ~1000 N per unit U

fs::path writeProtocol(const fs::path& dir, const std::string& name, const std::string& text) {
    const fs::path p = dir / name;
    std::ofstream(p) << text;
    return p;
}

/// A short MVC protocol (3 angles x 2 repetitions, 0.5 s holds) with EMG and transducer noise.
const std::string kSmallMvc = R"(name: small_mvc
kind: mvc
seed: 7
order: random
repetitions: 2
trial:
  rest: 0.2
  hold: 0.5
  averaging_window: 0.2
conditions:
  elbow_angles_deg: [80, 100, 120]
sensors:
  transducer:
    noise_rms: 1.0
  emg:
    trains_per_unit: 5
)";

/// Line (1-based) of the first occurrence of `fragment` in text.
int lineOf(const std::string& text, const std::string& fragment) {
    const std::size_t at = text.find(fragment);
    int line = 1;
    for (std::size_t i = 0; i < at && i < text.size(); ++i) line += text[i] == '\n';
    return line;
}

/// The error message readProtocol gives for text ("" if none).
std::string protocolError(const fs::path& dir, const std::string& text) {
    const fs::path p = writeProtocol(dir, "bad.yaml", text);
    try {
        readProtocol(p.string());
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
    const std::size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return text.replace(at, from.size(), to);
}

/// Every regular file under dir, relative path -> bytes.
std::map<std::string, std::string> readTree(const fs::path& dir) {
    std::map<std::string, std::string> files;
    for (const auto& e : fs::recursive_directory_iterator(dir))
        if (e.is_regular_file()) files[fs::relative(e.path(), dir).string()] = readText(e.path());
    return files;
}

/// Siblings of target whose names start with "." + target's name (temporary run directories).
int countTemporarySiblings(const fs::path& target) {
    int n = 0;
    for (const auto& e : fs::directory_iterator(target.parent_path()))
        if (e.path().filename().string().rfind("." + target.filename().string() + ".", 0) == 0) ++n;
    return n;
}

}  // namespace

TEST(ProtocolFile, ShippedProtocolsReadWithTheThesisConditions) {
    const Protocol mvc = readProtocol(kProtocols + "mvc_force_angle.yaml");
    EXPECT_EQ(mvc.kind, ProtocolKind::Mvc);
    ASSERT_EQ(mvc.elbowAngles.size(), 5u);
    for (int i = 0; i < 5; ++i) EXPECT_NEAR(radToDeg(mvc.elbowAngles[i]), kThesisMvcAnglesDeg[i], kAngleTol);
    EXPECT_EQ(mvc.repetitions, 3);
    EXPECT_EQ(mvc.trial.holdDuration, 3.0);
    EXPECT_TRUE(mvc.randomOrder);
    EXPECT_TRUE(mvc.emgEnabled);
    EXPECT_EQ(mvc.emg.acquisition.gain, 5000);
    EXPECT_EQ(mvc.emg.acquisition.outputRate, 1000);

    const Protocol sub = readProtocol(kProtocols + "submaximal_emg.yaml");
    EXPECT_EQ(sub.kind, ProtocolKind::Submaximal);
    EXPECT_EQ(sub.levels, (std::vector<double>{0.1, 0.2, 0.4, 0.6, 0.8, 1.0}));
    EXPECT_EQ(sub.elbowAngles.size(), 3u);
    EXPECT_EQ(sub.trial.holdDuration, 5.0);

    const Protocol fl = readProtocol(kProtocols + "force_length.yaml");
    EXPECT_EQ(fl.kind, ProtocolKind::ForceLength);
    constexpr double kPathTol = 1e-12;  // m
    EXPECT_NEAR(fl.pathLengths.front(), 0.27, kPathTol);
    EXPECT_NEAR(fl.pathLengths.back(), 0.43, kPathTol);
    EXPECT_NEAR(radToDeg(fl.elbowAngles.front()), 40, kAngleTol);
    EXPECT_NEAR(radToDeg(fl.elbowAngles.back()), 175, kAngleTol);

    const Protocol comp = readProtocol(kProtocols + "motor_unit_composition.yaml");
    EXPECT_EQ(comp.kind, ProtocolKind::Composition);
    EXPECT_EQ(comp.slowUnitsTo, 10);
    EXPECT_EQ(comp.fastUnitsTo, 10);
    EXPECT_EQ(comp.compositionActivation, 0.9);
    EXPECT_EQ(comp.compositionPath, 0.375);
}

TEST(ProtocolFile, MalformedFilesNameFileLineAndKey) {
    const fs::path d = freshDir("malformed");
    ASSERT_EQ(protocolError(d, kSmallMvc), "");

    std::string e = protocolError(d, replaced(kSmallMvc, "[80, 100, 120]", "[80, 100, 120"));
    EXPECT_NE(e.find("bad.yaml:"), std::string::npos) << e;
    EXPECT_NE(e.find("invalid YAML"), std::string::npos) << e;

    std::string text = replaced(kSmallMvc, "  hold: 0.5\n", "  hold: 0.5\n  holdd: 3\n");
    e = protocolError(d, text);
    EXPECT_NE(e.find("bad.yaml:" + std::to_string(lineOf(text, "holdd"))), std::string::npos) << e;
    EXPECT_NE(e.find("unknown field 'trial.holdd'"), std::string::npos) << e;

    text = replaced(kSmallMvc, "  hold: 0.5", "  hold: -1");
    e = protocolError(d, text);
    EXPECT_NE(e.find("bad.yaml:" + std::to_string(lineOf(text, "hold: -1"))), std::string::npos) << e;
    EXPECT_NE(e.find("'trial.hold' = -1"), std::string::npos) << e;

    text = replaced(kSmallMvc, "[80, 100, 120]", "[80,\n    185]");
    e = protocolError(d, text);
    EXPECT_NE(e.find("bad.yaml:" + std::to_string(lineOf(text, "185"))), std::string::npos) << e;
    EXPECT_NE(e.find("conditions.elbow_angles_deg' (entry 2) = 185"), std::string::npos) << e;

    text = replaced(kSmallMvc, "[80, 100, 120]", "[]");
    e = protocolError(d, text);
    EXPECT_NE(e.find("bad.yaml:" + std::to_string(lineOf(text, "elbow_angles_deg"))), std::string::npos) << e;
    EXPECT_NE(e.find("'conditions.elbow_angles_deg' is empty"), std::string::npos) << e;

    text = replaced(kSmallMvc, "kind: mvc", "kind: submaximal");
    text = replaced(text, "[80, 100, 120]\n", "[80, 100, 120]\n  levels_pct_mvc: [10, 50]\n");
    e = protocolError(d, text);
    EXPECT_NE(e.find("bad.yaml:" + std::to_string(lineOf(text, "levels_pct_mvc"))), std::string::npos) << e;
    EXPECT_NE(e.find("lacks 100"), std::string::npos) << e;

    text = replaced(kSmallMvc, "trains_per_unit: 5", "internal_rate: 2500");
    e = protocolError(d, text);
    EXPECT_NE(e.find("bad.yaml:" + std::to_string(lineOf(text, "internal_rate"))), std::string::npos) << e;
    EXPECT_NE(e.find("sensors.emg.internal_rate"), std::string::npos) << e;
    fs::remove_all(d);
}

// A sample rate the EMG filters cannot take is refused while EMG is on, and accepted with enabled:
// false (no EMG is made, so its band need not lie below Nyquist).
TEST(ProtocolFile, DisabledEmgIsNotCheckedAgainstTheSampleRate) {
    const fs::path d = freshDir("emg_disabled");
    const std::string mvc = readText(kProtocols + "mvc_force_angle.yaml");
    const std::string slow = replaced(mvc, "sample_rate: 1000 ", "sample_rate: 200 ");
    EXPECT_NE(protocolError(d, slow).find("band_high"), std::string::npos);
    const std::string off = replaced(slow, "enabled: true", "enabled: false");
    EXPECT_EQ(protocolError(d, off), "");
    EXPECT_FALSE(readProtocol(writeProtocol(d, "off.yaml", off).string()).emgEnabled);
    fs::remove_all(d);
}

TEST(ProtocolRun, SameSeedGivesByteIdenticalFilesWhateverTheThreadCount) {
    const fs::path d = freshDir("determinism");
    const Protocol p = readProtocol(writeProtocol(d, "p.yaml", kSmallMvc).string());
    const ArmSetup subject = loadProtocolSubject(p);
    runProtocol(p, subject, {(d / "a").string(), 2, {}});
    runProtocol(p, subject, {(d / "b").string(), 2, {}});
    runProtocol(p, subject, {(d / "c").string(), 1, {}});
    const auto a = readTree(d / "a"), b = readTree(d / "b"), c = readTree(d / "c");
    ASSERT_GT(a.size(), 12u);  // 6 trials x (csv, sto) + tables, plots, manifest
    EXPECT_TRUE(a.count("trials/a100_r2.sto"));
    EXPECT_TRUE(a.count("force_angle.png"));
    for (const auto& [name, bytes] : a) {
        ASSERT_TRUE(b.count(name) && c.count(name)) << name;
        EXPECT_TRUE(bytes == b.at(name)) << name << " differs between two runs";
        EXPECT_TRUE(bytes == c.at(name)) << name << " differs between --jobs 2 and --jobs 1";
    }
    EXPECT_EQ(a.size(), b.size());
    EXPECT_EQ(a.size(), c.size());

    // The seed matters: another seed changes the EMG and the transducer noise.
    const Protocol other = readProtocol(writeProtocol(d, "q.yaml", replaced(kSmallMvc, "seed: 7", "seed: 8")).string());
    runProtocol(other, subject, {(d / "e").string(), 2, {}});
    EXPECT_NE(readText(d / "e" / "trials.csv"), a.at("trials.csv"));
    fs::remove_all(d);
}

TEST(ProtocolRun, SummaryTablesAgreeWithThePerTrialFiles) {
    const fs::path d = freshDir("summary");
    const Protocol p = readProtocol(writeProtocol(d, "p.yaml", kSmallMvc).string());
    const ProtocolResult r = runProtocol(p, loadProtocolSubject(p), {(d / "run").string(), 2, {}});
    const Table trials = Table::readCsv((d / "run" / "trials.csv").string());
    const Table summary = Table::readCsv((d / "run" / "summary.csv").string());
    ASSERT_EQ(trials.getNumRows(), 6);
    ASSERT_EQ(summary.getNumRows(), 3);
    constexpr double kFileRelTol = 1e-8;  // values pass through 10-digit files
    auto near = [&](double a, double b) { return std::abs(a - b) <= kFileRelTol * std::max(1.0, std::abs(b)); };

    for (int i = 0; i < trials.getNumRows(); ++i) {
        const Table series = Table::readCsv((d / "run" / "trials" / (r.trialIds[i] + ".csv")).string());
        const std::vector<double> time = series.getColumn("time_s");
        const double from = time.back() - p.trial.averagingWindow - 1e-9;  // the window rule of model/trial.cpp
        double force = 0, measured = 0, square = 0;
        int n = 0;
        for (int k = 0; k < series.getNumRows(); ++k)
            if (time[k] >= from) {
                force += series.get(k, "muscle_force_N");
                measured += series.get(k, "force_moment_arm_N");
                square += series.get(k, "emg_V") * series.get(k, "emg_V");
                ++n;
            }
        EXPECT_TRUE(near(force / n, trials.get(i, "muscle_force_N"))) << r.trialIds[i];
        EXPECT_TRUE(near(measured / n, trials.get(i, "force_measured_N"))) << r.trialIds[i];
        EXPECT_TRUE(near(std::sqrt(square / n), trials.get(i, "emg_rms_V"))) << r.trialIds[i];
        EXPECT_NEAR(series.get(0, "elbow_angle_deg"), trials.get(i, "elbow_angle_deg"), kAngleTol);

        // The .sto holds the same numbers as the CSV (without the muscle states).
        const Table sto = readStorage((d / "run" / "trials" / (r.trialIds[i] + ".sto")).string());
        ASSERT_EQ(sto.getNumRows(), series.getNumRows());
        for (int c = 1; c < sto.getNumColumns(); ++c) {
            EXPECT_EQ(sto.getColumnNames()[c].rfind("state_", 0), std::string::npos);
            EXPECT_EQ(sto.getColumn(sto.getColumnNames()[c]), series.getColumn(sto.getColumnNames()[c]));
        }
    }
    for (int s = 0; s < summary.getNumRows(); ++s) {
        std::vector<double> force, emg;
        for (int i = 0; i < trials.getNumRows(); ++i)
            if (trials.get(i, "elbow_angle_deg") == summary.get(s, "elbow_angle_deg")) {
                force.push_back(trials.get(i, "force_measured_N"));
                emg.push_back(trials.get(i, "emg_rms_V"));
            }
        ASSERT_EQ(force.size(), 2u);
        const MeanSd f = calcMeanSd(force), e = calcMeanSd(emg);
        EXPECT_EQ(summary.get(s, "n"), 2);
        EXPECT_TRUE(near(summary.get(s, "force_measured_N_mean"), f.mean));
        EXPECT_NEAR(summary.get(s, "force_measured_N_sd"), f.sd, kFileRelTol * f.mean);  // sd of rounded means
        EXPECT_TRUE(near(summary.get(s, "emg_rms_V_mean"), e.mean));
        // MVC-normalised EMG averages to 1 over each angle's MVC trials.
        EXPECT_NEAR(summary.get(s, "emg_norm_mean"), 1.0, kFileRelTol);
    }
    // The quadratic fit in the result is the fit of the per-trial forces.
    const QuadraticFit q = fitQuadratic(trials.getColumn("elbow_angle_deg"), trials.getColumn("muscle_force_N"));
    constexpr double kPeakTol = 1e-6;  // deg and N: fit of 10-digit file values vs full precision
    auto expectSame = [&](double a, double b) {   // NaN: no peak (three angles fix any quadratic)
        if (std::isnan(b)) EXPECT_TRUE(std::isnan(a)) << a;
        else EXPECT_NEAR(a, b, kPeakTol);
    };
    expectSame(r.quadraticFits.at("muscle_force").peakX, q.peakX);
    expectSame(r.quadraticFits.at("muscle_force").peakY, q.peakY);
    // fits.csv holds the result's fits (10 digits).
    std::istringstream fits(readText(d / "run" / "fits.csv"));
    std::string line;
    std::getline(fits, line);
    EXPECT_EQ(splitCsvRecord(line), std::vector<std::string>({"fit", "c0", "c1", "c2", "r_squared", "rms_residual",
                                                              "points", "peak_x", "peak_y"}));
    int rows = 0;
    while (std::getline(fits, line)) {
        const std::vector<std::string> cells = splitCsvRecord(line);
        ASSERT_EQ(cells.size(), 9u) << line;
        const QuadraticFit& f = r.quadraticFits.at(cells[0]);
        for (int k = 0; k < 3; ++k) EXPECT_TRUE(near(std::stod(cells[1 + k]), f.fit.coefficients[k])) << line;
        EXPECT_EQ(std::stoi(cells[6]), f.fit.points);
        if (cells[8].empty()) EXPECT_TRUE(std::isnan(f.peakY)) << line;   // no peak: an empty cell
        else EXPECT_TRUE(near(std::stod(cells[8]), f.peakY)) << line;
        ++rows;
    }
    EXPECT_EQ(rows, int(r.quadraticFits.size()));
    fs::remove_all(d);
}

TEST(ProtocolRun, SubmaximalLevelsAreResolvedAgainstTheSimulatedMvc) {
    const fs::path d = freshDir("submax");
    const std::string text = R"(name: small_submax
kind: submaximal
seed: 3
repetitions: 2
trial:
  rest: 0.2
  hold: 1.0
  averaging_window: 0.3
conditions:
  elbow_angles_deg: [90]
  levels_pct_mvc: [50, 100]
sensors:
  emg:
    trains_per_unit: 5
)";
    const Protocol p = readProtocol(writeProtocol(d, "s.yaml", text).string());
    const ProtocolResult r = runProtocol(p, loadProtocolSubject(p), {});
    const Table& s = r.summary;
    ASSERT_EQ(s.getNumRows(), 2);
    const int full = s.get(0, "level_pct_mvc") == 100 ? 0 : 1, half = 1 - full;
    EXPECT_EQ(s.get(full, "activation_mean"), 1.0);
    EXPECT_NEAR(s.get(full, "emg_norm_mean"), 1.0, kNormTol);   // by construction
    EXPECT_NEAR(s.get(full, "force_norm_mean"), 1.0, kNormTol);
    // The level was resolved with the steady solve; the trial's force after 1 s agrees within 1 %.
    constexpr double kLevelTol = 0.01;
    EXPECT_NEAR(s.get(half, "force_norm_mean"), 0.5, kLevelTol);
    EXPECT_LT(s.get(half, "activation_mean"), 1.0);
    EXPECT_LT(s.get(half, "emg_norm_mean"), 1.0);
    ASSERT_TRUE(r.emgToActivation.has_value());
    EXPECT_EQ(r.emgToActivation->points, 4);
    fs::remove_all(d);
}

TEST(ProtocolRun, ActivationForActiveForceHitsTheTarget) {
    const ArmSetup subject = ArmSetup::loadDefault();
    const VirtualMuscle m(subject.calcBicepsParameters());
    constexpr double kP = 0.39;
    const double passive = m.calcSteadyState(kP, 0).force, full = m.calcSteadyState(kP, 1).force - passive;
    for (double fraction : {0.1, 0.5, 0.9}) {
        const double U = calcActivationForActiveForce(m, kP, fraction * full);
        EXPECT_NEAR(m.calcSteadyState(kP, U).force - passive, fraction * full, kForceTol) << fraction;
    }
    EXPECT_EQ(calcActivationForActiveForce(m, kP, 1.1 * full), 1.0);
}

TEST(ProtocolRun, CompositionGridMatchesTheSteadySolveAndTheThesisTable) {
    const fs::path d = freshDir("composition");
    const std::string text = R"(name: small_composition
kind: composition
conditions:
  slow_units: {from: 2, to: 3}
  fast_units: {from: 2, to: 3}
  activation: 0.9
  path_length: 0.375
)";
    const Protocol p = readProtocol(writeProtocol(d, "c.yaml", text).string());
    const ArmSetup subject = loadProtocolSubject(p);
    const ProtocolResult r = runProtocol(p, subject, {(d / "run").string(), 1, {}});
    ASSERT_EQ(r.composition.getNumRows(), 4);
    for (int i = 0; i < 4; ++i) {
        MuscleParameters mp = subject.calcBicepsParameters();
        mp.numSlowUnits = int(r.composition.get(i, "slow_units"));
        mp.numFastUnits = int(r.composition.get(i, "fast_units"));
        EXPECT_EQ(r.composition.get(i, "force_N"), VirtualMuscle(mp).calcSteadyState(0.375, 0.9).force);
        if (mp.numSlowUnits == 3 && mp.numFastUnits == 3) {
            constexpr double kThesisTableRelTol = 0.01;  // thesis Table 7.4: 346.13 N for 3 + 3 units
            EXPECT_NEAR(r.composition.get(i, "force_N"), 346.13, kThesisTableRelTol * 346.13);
        }
    }
    // The matrix file: rows are slow counts, columns fast counts.
    const Table matrix = Table::readCsv((d / "run" / "composition_matrix.csv").string());
    EXPECT_EQ(matrix.getColumnNames(), (std::vector<std::string>{"slow_units", "fast_2", "fast_3"}));
    for (int i = 0; i < 4; ++i) {
        const int row = int(r.composition.get(i, "slow_units")) - 2;
        const std::string col = "fast_" + std::to_string(int(r.composition.get(i, "fast_units")));
        constexpr double kMatrixRelTol = 1e-9;  // 10 significant digits in the file
        EXPECT_NEAR(matrix.get(row, col), r.composition.get(i, "force_N"), kMatrixRelTol * r.composition.get(i, "force_N"));
    }
    EXPECT_TRUE(fs::exists(d / "run" / "composition_heatmap.png"));
    fs::remove_all(d);
}

TEST(ProtocolRun, AFailedRunLeavesNoOutputAndKeepsTheEarlierRun) {
    const fs::path d = freshDir("failure");
    const Protocol p = readProtocol(writeProtocol(d, "p.yaml", kSmallMvc).string());
    const ArmSetup subject = loadProtocolSubject(p);
    const fs::path target = d / "run";
    auto failAtSecondTrial = [](int done, int) {
        if (done == 2) throw InputError("interrupted");
    };
    EXPECT_THROW(runProtocol(p, subject, {target.string(), 2, failAtSecondTrial}), InputError);
    EXPECT_FALSE(fs::exists(target));
    EXPECT_EQ(countTemporarySiblings(target), 0);

    runProtocol(p, subject, {target.string(), 2, {}});
    const auto before = readTree(target);
    EXPECT_THROW(runProtocol(p, subject, {target.string(), 2, failAtSecondTrial}), InputError);
    EXPECT_EQ(readTree(target), before);
    EXPECT_EQ(countTemporarySiblings(target), 0);

    // A directory that is not a protocol run is never replaced.
    const fs::path foreign = d / "foreign";
    fs::create_directories(foreign);
    std::ofstream(foreign / "notes.txt") << "keep me";
    try {
        runProtocol(p, subject, {foreign.string(), 2, {}});
        FAIL() << "expected a refusal";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("refusing to replace"), std::string::npos) << e.what();
    }
    EXPECT_EQ(readText(foreign / "notes.txt"), "keep me");
    fs::remove_all(d);
}

// Issue 29: these protocols simulate the primary's motor units; with a Hill-type primary the run is
// refused before anything is written, naming the muscle and its model.
TEST(ProtocolRun, RefusesAPrimaryMuscleWithoutMotorUnits) {
    const fs::path d = freshDir("hill_primary");
    const Protocol p = readProtocol(writeProtocol(d, "p.yaml", kSmallMvc).string());
    ArmSetup subject = loadProtocolSubject(p);
    setMuscleModel(subject, "thelen2003");
    try {
        runProtocol(p, subject, {(d / "out").string(), 1, {}});
        ADD_FAILURE();
    } catch (const InputError& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find("muscle_model thelen2003"), std::string::npos) << m;
        EXPECT_NE(m.find("expected virtual_muscle"), std::string::npos) << m;
    }
    EXPECT_FALSE(fs::exists(d / "out"));
    fs::remove_all(d);
}
