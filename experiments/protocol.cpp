#include "experiments/protocol.h"

#include "experiments/data_files.h"
#include "experiments/plot.h"
#include "model/geometry.h"
#include "model/parallel.h"
#include "muscles/param_file.h"

#include <nlohmann/json.hpp>

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <set>

#ifndef ARMSIM_VERSION
#define ARMSIM_VERSION "unknown"
#endif
#ifndef ARMSIM_SIMBODY_VERSION
#define ARMSIM_SIMBODY_VERSION "unknown"
#endif

namespace fs = std::filesystem;

namespace armsim {

namespace {

constexpr double kTimeTol = 1e-9;           // s, sample times compared against window edges
constexpr double kBisectionTol = 1e-12;     // activation, calcActivationForActiveForce
constexpr int kCsvDigits = 10;              // significant digits of result files

// ---- Small helpers --------------------------------------------------------------------------------

/// SplitMix64 (Steele, Lea & Flood 2014): a well-mixed 64-bit value from a 64-bit input.
std::uint64_t splitMix(std::uint64_t x) {
    x += 0x9E3779B97F4A7C15ULL;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
    return x ^ (x >> 31);
}

/// Seed of trial `index` of a protocol seeded with `seed`; independent of run order and threads.
std::uint64_t trialSeed(std::uint64_t seed, int index) { return splitMix(splitMix(seed) ^ std::uint64_t(index + 1)); }

std::string fmt(const char* format, double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, format, v);
    return buf;
}

/// Degrees of an angle read in degrees and stored in radians, without the round-trip's last-digit noise.
double cleanDegrees(double radians) { return std::round(radToDeg(radians) * 1e9) / 1e9; }

std::vector<std::size_t> columnsWithoutStates(const Table& t) {
    std::vector<std::size_t> keep;
    for (int c = 0; c < t.getNumColumns(); ++c)
        if (t.getColumnNames()[c].rfind(kStateColumnPrefix, 0) != 0) keep.push_back(std::size_t(c));
    return keep;
}

Table selectColumns(const Table& t, const std::vector<std::size_t>& columns) {
    std::vector<std::string> names;
    for (std::size_t c : columns) names.push_back(t.getColumnNames()[c]);
    Table out(names);
    for (int i = 0; i < t.getNumRows(); ++i) {
        std::vector<double> row;
        row.reserve(columns.size());
        for (std::size_t c : columns) row.push_back(t.get(i, int(c)));
        out.appendRow(std::move(row));
    }
    return out;
}

/// First row of the averaging window: time >= end - window (as model/trial.cpp).
std::size_t windowStart(const std::vector<double>& time, double window) {
    const double from = time.back() - window - kTimeTol;
    std::size_t first = 0;
    while (first < time.size() && time[first] < from) ++first;
    return first;
}

double meanFrom(const std::vector<double>& v, std::size_t from) {
    double s = 0;
    for (std::size_t i = from; i < v.size(); ++i) s += v[i];
    return v.size() > from ? s / double(v.size() - from) : NAN;
}

}  // namespace

double calcActivationForActiveForce(const VirtualMuscle& muscle, double pathLength, double targetForce) {
    auto force = [&](double U) {
        const SteadyState s = muscle.calcSteadyState(pathLength, U);
        if (!s.converged)
            throw SimulationError("no steady state at path " + fmt("%.4f", pathLength) + " m, U = " + fmt("%.6f", U) +
                                  ": " + s.message);
        return s.force;
    };
    const double passive = force(0.0);
    if (force(1.0) - passive <= targetForce) return 1.0;
    double lo = 0, hi = 1;
    while (hi - lo > kBisectionTol) {
        const double mid = 0.5 * (lo + hi);
        (force(mid) - passive < targetForce ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

namespace {

// ---- The run directory ----------------------------------------------------------------------------

/// Files of a run, written under a temporary sibling of the target and renamed into place by commit().
/// Destroyed without commit(), it removes the temporary directory.
class RunDirectory {
public:
    explicit RunDirectory(const std::string& outDir) {
        if (outDir.empty()) return;
        target_ = fs::path(outDir).lexically_normal();
        if (target_.filename().empty()) target_ = target_.parent_path();
        checkReplaceable();
        const fs::path parent = target_.has_parent_path() ? target_.parent_path() : fs::path(".");
        std::error_code ec;
        fs::create_directories(parent, ec);
        const std::string stem = "." + target_.filename().string();
        removeStaleLeftovers(parent, stem);
        temp_ = parent / (stem + ".partial." + std::to_string(::getpid()));
        old_ = parent / (stem + ".old." + std::to_string(::getpid()));
        fs::remove_all(temp_, ec);
        if (!fs::create_directories(temp_ / "trials", ec) || ec)
            throw InputError(outDir + ": cannot create the run directory next to it (" + ec.message() + ")");
    }
    RunDirectory(const RunDirectory&) = delete;
    RunDirectory& operator=(const RunDirectory&) = delete;
    ~RunDirectory() {
        std::error_code ec;
        if (!temp_.empty() && !committed_) fs::remove_all(temp_, ec);
    }

    bool isEnabled() const { return !temp_.empty(); }
    /// Absolute path of a file in the temporary directory; records it.
    std::string addFile(const std::string& relative) {
        std::lock_guard<std::mutex> lock(mutex_);
        files_.insert(relative);
        return (temp_ / relative).string();
    }
    /// Writes a whole file (thread-safe for distinct names).
    void write(const std::string& relative, const std::string& text) {
        const std::string path = addFile(relative);
        std::ofstream out(path, std::ios::binary);
        out << text;
        out.flush();
        if (!out) throw InputError((target_ / relative).string() + ": write failed (disk full?)");
    }
    std::vector<std::string> getFiles() const { return {files_.begin(), files_.end()}; }

    /// Moves the finished run into place (replacing an earlier run).
    void commit() {
        checkReplaceable();
        std::error_code ec;
        const bool replace = fs::exists(target_);
        if (replace) {
            fs::rename(target_, old_, ec);
            if (ec) throw InputError(target_.string() + ": cannot move the earlier run aside: " + ec.message());
        }
        fs::rename(temp_, target_, ec);
        if (ec) {
            std::error_code ignored;
            if (replace) fs::rename(old_, target_, ignored);
            throw InputError(target_.string() + ": cannot move the run into place: " + ec.message());
        }
        committed_ = true;
        if (replace) fs::remove_all(old_, ec);
    }

private:
    /// What a run killed before its cleanup (SIGKILL, a second Ctrl-C) left beside the target:
    /// <stem>.partial.<pid> folders of processes that no longer exist are removed; a <stem>.old.<pid>
    /// folder holds the earlier run, moved aside just before the kill: moved back when the target is
    /// missing, removed otherwise.
    void removeStaleLeftovers(const fs::path& parent, const std::string& stem) const {
        std::error_code ec;
        std::vector<fs::path> entries;
        for (const fs::directory_entry& e : fs::directory_iterator(parent, ec)) entries.push_back(e.path());
        for (const fs::path& p : entries) {
            const std::string name = p.filename().string();
            for (const std::string kind : {".partial.", ".old."}) {
                const std::string prefix = stem + kind;
                if (name.rfind(prefix, 0) != 0) continue;
                const std::string digits = name.substr(prefix.size());
                if (digits.empty() || digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos)
                    continue;
                const pid_t pid = pid_t(std::stol(digits));
                // Ours are stale too: this run has not made its folders yet (pids repeat in containers).
                if (pid != ::getpid() && (::kill(pid, 0) == 0 || errno == EPERM)) continue;  // its process still runs
                if (kind == ".old." && !fs::exists(target_, ec)) fs::rename(p, target_, ec);
                else fs::remove_all(p, ec);
            }
        }
    }

    void checkReplaceable() const {
        std::error_code ec;
        if (!fs::exists(target_, ec)) return;
        if (fs::is_directory(target_, ec) &&
            (fs::is_empty(target_, ec) || fs::exists(target_ / "manifest.json", ec)))
            return;
        throw InputError(target_.string() + ": exists and is not an armsim protocol run (no manifest.json): "
                         "refusing to replace it; choose another output directory");
    }

    fs::path target_, temp_, old_;
    bool committed_ = false;
    std::mutex mutex_;
    std::set<std::string> files_;
};

// ---- Trials ---------------------------------------------------------------------------------------

/// One arm trial of the protocol.
struct ArmTrialPlan {
    int index = 0;            ///< canonical index
    std::string id;           ///< file stem
    double angle = 0;         ///< [rad]
    double level = 1;         ///< fraction of MVC
    int repetition = 1;       ///< 1-based
    double activation = 1;    ///< U during the hold
    std::uint64_t seed = 0;   ///< trial seed
};

/// What an arm trial gives, per-trial metrics and (for the example plot) its time series.
struct ArmTrialOutcome {
    IsometricSummary summary;
    double muscleForce = NAN, activeForce = NAN, forceMeasured = NAN, forceFixedRatio = NAN, strapForce = NAN;
    bool saturated = false;
    EmgFeatures emg{NAN, NAN, NAN};
    std::vector<double> time, emgSignal, emgRms;
};

std::string angleId(double angle) { return fmt("a%03.0f", radToDeg(angle)); }

ArmTrialOutcome runArmTrial(const ArmTrialPlan& plan, const Protocol& protocol, const ArmSetup& subject,
                            const VirtualMuscle& muscle, RunDirectory& dir, bool keepSeries) {
    IsometricTrialSettings s = protocol.trial;
    s.elbowAngle = plan.angle;
    // The subject's effort: agonists at the planned drive times the voluntary activation, antagonists
    // co-contracting; both vary from trial to trial (seeded) and fade with fatigue over repetitions.
    const SubjectEffort& e = subject.effort;
    std::mt19937_64 effortRng(splitMix(plan.seed ^ 0xE1F0E1F0ULL));
    std::normal_distribution<double> unit(0.0, 1.0);
    const double variation = 1 + e.trialCv * unit(effortRng), antagonistVariation = 1 + e.trialCv * unit(effortRng);
    const double fatigue = std::pow(1 - e.fatigue, plan.repetition - 1);
    s.activation = std::clamp(plan.activation * e.voluntaryActivation * variation * fatigue, 0.0, 1.0);
    s.antagonistActivation = std::clamp(e.coContraction * antagonistVariation * fatigue, 0.0, 1.0);
    const IsometricTrialResult r = runIsometricTrial(subject, s);
    const Table& t = r.series;
    const int rows = t.getNumRows();
    const ArmParameters& ap = subject.arm;
    const double h = r.summary.momentArm;

    // Transducer noise: every reading and the estimates derived from it.
    std::mt19937_64 noiseRng(splitMix(plan.seed ^ 0x5A5A5A5AULL)), emgRng(splitMix(plan.seed));
    std::normal_distribution<double> noise(0.0, protocol.transducerNoiseRms > 0 ? protocol.transducerNoiseRms : 1.0);
    const int cForce = t.findColumn("muscle_force_N"), cStrap = t.findColumn("strap_force_N"),
              cSat = t.findColumn("saturated"), cByArm = t.findColumn("force_moment_arm_N"),
              cByRatio = t.findColumn("force_fixed_ratio_N"), cErrArm = t.findColumn("error_moment_arm_pct"),
              cErrRatio = t.findColumn("error_fixed_ratio_pct");

    SurfaceEmg emg;
    std::vector<double> emgRms;
    if (protocol.emgEnabled) {
        emg = calcSurfaceEmg(muscle, s.calcActivationProfile(), t.getRow(0)[0], std::size_t(rows), protocol.emg, emgRng);
        emgRms = calcMovingRms(emg.emg, emg.sampleRate, protocol.emgRmsWindow);
    }

    // The trial table with the EMG columns inserted before the muscle states.
    const std::vector<std::size_t> base = columnsWithoutStates(t);
    std::vector<std::string> names;
    for (std::size_t c : base) names.push_back(t.getColumnNames()[c]);
    if (protocol.emgEnabled) {
        names.push_back("emg_V");
        names.push_back("emg_rms_V");
    }
    for (int c = int(base.size()); c < t.getNumColumns(); ++c) names.push_back(t.getColumnNames()[c]);
    Table out(names);
    for (int i = 0; i < rows; ++i) {
        std::vector<double> row = t.getRow(i);
        if (protocol.transducerNoiseRms > 0) {
            double strap = row[cStrap] + noise(noiseRng);
            const bool saturated = std::abs(strap) > ap.transducerRange;
            if (saturated) strap = std::copysign(ap.transducerRange, strap);
            const double F = row[cForce];
            row[cStrap] = strap;
            row[cSat] = saturated ? 1.0 : 0.0;
            row[cByArm] = calcBicepsForceFromTorque(strap * ap.strapDistance, h);
            row[cByRatio] = calcBicepsForceFixedRatio(strap, plan.angle, kPi / 2);
            row[cErrArm] = F > 0 ? 100 * (row[cByArm] - F) / F : NAN;
            row[cErrRatio] = F > 0 ? 100 * (row[cByRatio] - F) / F : NAN;
        }
        if (protocol.emgEnabled) {
            row.insert(row.begin() + std::ptrdiff_t(base.size()), {emg.emg[i], emgRms[i]});
        }
        out.appendRow(std::move(row));
    }

    ArmTrialOutcome o;
    o.summary = r.summary;
    const std::vector<double> time = out.getColumn("time_s");
    const std::size_t first = windowStart(time, s.averagingWindow);
    o.muscleForce = meanFrom(out.getColumn("muscle_force_N"), first);
    o.activeForce = o.muscleForce - r.summary.restForce;
    o.forceMeasured = meanFrom(out.getColumn("force_moment_arm_N"), first);
    o.forceFixedRatio = meanFrom(out.getColumn("force_fixed_ratio_N"), first);
    o.strapForce = meanFrom(out.getColumn("strap_force_N"), first);
    for (double v : out.getColumn("saturated")) o.saturated = o.saturated || v != 0;
    if (protocol.emgEnabled) o.emg = calcEmgFeatures(emg.emg, emg.sampleRate, first, emg.emg.size());
    if (keepSeries) {
        o.time = time;
        o.emgSignal = emg.emg;
        o.emgRms = emgRms;
    }
    if (dir.isEnabled()) {
        dir.write("trials/" + plan.id + ".csv", out.toCsv(kCsvDigits));
        dir.write("trials/" + plan.id + ".sto",
                  formatStorage(selectColumns(out, columnsWithoutStates(out)), plan.id, true, kCsvDigits));
    }
    return o;
}

/// A muscle-alone isometric trial at U = 1 (force_length).
struct MuscleTrialOutcome {
    double pathLength = 0, force = NAN, steadyForce = NAN, passiveForce = NAN;
};

MuscleTrialOutcome runMuscleTrial(double pathLength, const std::string& id, const Protocol& protocol,
                                  const VirtualMuscle& muscle, RunDirectory& dir) {
    const IsometricTrialSettings& tr = protocol.trial;
    MuscleIsometricSettings s;
    s.pathLength = pathLength;
    s.activation = tr.calcActivationProfile();
    s.duration = tr.getDuration();
    s.sampleRate = tr.sampleRate;
    s.startSteady = true;
    s.integration = tr.integration;
    const Table t = runMuscleIsometric(muscle, s);
    MuscleTrialOutcome o;
    o.pathLength = pathLength;
    o.force = meanFrom(t.getColumn("force_N"), windowStart(t.getColumn("time_s"), tr.averagingWindow));
    const SteadyState full = muscle.calcSteadyState(pathLength, 1.0), passive = muscle.calcSteadyState(pathLength, 0.0);
    o.steadyForce = full.converged ? full.force : NAN;
    o.passiveForce = passive.converged ? passive.force : NAN;
    if (dir.isEnabled()) {
        dir.write("trials/" + id + ".csv", t.toCsv(kCsvDigits));
        dir.write("trials/" + id + ".sto", formatStorage(t, id, false, kCsvDigits));
    }
    return o;
}

// ---- Tables, fits, plots --------------------------------------------------------------------------

const std::vector<std::string> kTrialColumns = {
    "trial", "run_order", "elbow_angle_deg", "level_pct_mvc", "repetition", "activation", "path_length_m",
    "moment_arm_m", "rest_force_N", "muscle_force_N", "active_force_N", "force_measured_N", "force_fixed_ratio_N",
    "strap_force_N", "saturated", "emg_rms_V", "emg_mnf_Hz", "emg_mdf_Hz", "emg_norm", "force_norm"};
/// Trial columns summarised per condition.
const std::vector<std::string> kSummarised = {
    "activation", "muscle_force_N", "active_force_N", "force_measured_N", "force_fixed_ratio_N",
    "emg_rms_V", "emg_mnf_Hz", "emg_mdf_Hz", "emg_norm", "force_norm"};

Table buildTrialTable(const std::vector<ArmTrialPlan>& plans, const std::vector<ArmTrialOutcome>& outcomes,
                      const std::vector<int>& runPosition) {
    // References per angle: means over the 100 % MVC trials.
    std::map<double, std::pair<double, double>> sums;  // angle -> (sum rms, sum active force)
    std::map<double, int> counts;
    for (std::size_t k = 0; k < plans.size(); ++k)
        if (plans[k].level == 1.0) {
            sums[plans[k].angle].first += outcomes[k].emg.rms;
            sums[plans[k].angle].second += outcomes[k].activeForce;
            ++counts[plans[k].angle];
        }
    Table t(kTrialColumns);
    for (std::size_t k = 0; k < plans.size(); ++k) {
        const ArmTrialPlan& p = plans[k];
        const ArmTrialOutcome& o = outcomes[k];
        const double n = counts[p.angle];
        const double emgRef = sums[p.angle].first / n, forceRef = sums[p.angle].second / n;
        t.appendRow({double(p.index), double(runPosition[k]), cleanDegrees(p.angle), 100 * p.level, double(p.repetition),
                     p.activation, o.summary.pathLength, o.summary.momentArm, o.summary.restForce, o.muscleForce,
                     o.activeForce, o.forceMeasured, o.forceFixedRatio, o.strapForce, o.saturated ? 1.0 : 0.0,
                     o.emg.rms, o.emg.mnf, o.emg.mdf, o.emg.rms / emgRef, o.activeForce / forceRef});
    }
    return t;
}

Table buildSummaryTable(const Table& trials) {
    std::vector<std::string> names = {"elbow_angle_deg", "level_pct_mvc", "n", "path_length_m"};
    for (const auto& c : kSummarised) {
        names.push_back(c + "_mean");
        names.push_back(c + "_sd");
    }
    Table s(names);
    std::vector<std::pair<double, double>> conditions;  // in order of first appearance
    for (int i = 0; i < trials.getNumRows(); ++i) {
        const std::pair<double, double> key{trials.get(i, "elbow_angle_deg"), trials.get(i, "level_pct_mvc")};
        if (std::find(conditions.begin(), conditions.end(), key) == conditions.end()) conditions.push_back(key);
    }
    for (const auto& [angle, level] : conditions) {
        std::vector<int> rows;
        for (int i = 0; i < trials.getNumRows(); ++i)
            if (trials.get(i, "elbow_angle_deg") == angle && trials.get(i, "level_pct_mvc") == level) rows.push_back(i);
        std::vector<double> row = {angle, level, double(rows.size()), trials.get(rows[0], "path_length_m")};
        for (const auto& c : kSummarised) {
            std::vector<double> v;
            for (int i : rows) v.push_back(trials.get(i, c));
            const MeanSd m = calcMeanSd(v);
            row.push_back(m.mean);
            row.push_back(m.sd);
        }
        s.appendRow(std::move(row));
    }
    return s;
}

/// Quadratic through the points within `halfWidth` samples of the largest y (x sorted ascending).
std::optional<QuadraticFit> fitPeak(const std::vector<double>& x, const std::vector<double>& y, int halfWidth) {
    if (x.size() < 3) return std::nullopt;
    std::size_t best = 0;
    for (std::size_t i = 1; i < y.size(); ++i)
        if (y[i] > y[best]) best = i;
    const std::size_t lo = best > std::size_t(halfWidth) ? best - halfWidth : 0;
    const std::size_t hi = std::min(x.size(), best + halfWidth + 1);
    if (hi - lo < 3) return std::nullopt;
    return fitQuadratic({x.begin() + std::ptrdiff_t(lo), x.begin() + std::ptrdiff_t(hi)},
                        {y.begin() + std::ptrdiff_t(lo), y.begin() + std::ptrdiff_t(hi)});
}

PlotSeries curve(const std::string& label, const PolynomialFit& f, double x0, double x1, int color) {
    PlotSeries s{label, {}, {}, false, color};
    for (int i = 0; i <= 100; ++i) {
        const double x = x0 + (x1 - x0) * i / 100.0;
        s.x.push_back(x);
        s.y.push_back(f.evaluate(x));
    }
    return s;
}

void plotExampleEmg(RunDirectory& dir, const std::string& id, const ArmTrialOutcome& o) {
    PlotSpec spec;
    spec.title = "synthetic surface EMG, trial " + id + " (referred to the electrodes)";
    spec.xLabel = "time (s)";
    spec.yLabel = "EMG (mV)";
    PlotSeries raw{"acquired EMG (10-400 Hz, 50 Hz notch, 1000 Hz)", o.time, o.emgSignal, false, 5};
    PlotSeries rms{"moving RMS", o.time, o.emgRms, false, 3};
    for (double& v : raw.y) v *= 1000;
    for (double& v : rms.y) v *= 1000;
    spec.series = {raw, rms};
    writePlotPng(dir.addFile("emg_trial.png"), spec);
}

std::vector<double> uniqueSorted(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
    return v;
}

void plotMvc(RunDirectory& dir, const Table& trials, const Table& summary, const std::map<std::string, QuadraticFit>& fits) {
    const std::vector<double> angle = trials.getColumn("elbow_angle_deg");
    const double a0 = *std::min_element(angle.begin(), angle.end()), a1 = *std::max_element(angle.begin(), angle.end());
    PlotSpec spec;
    spec.xLabel = "elbow angle (deg, 180 = extended)";
    spec.yLabel = "force (N)";
    spec.title = "MVC force vs elbow angle (thesis fit: peak 603.3 N at 101.2 deg)";
    spec.series.push_back({"true force", angle, trials.getColumn("muscle_force_N"), true, 0});
    spec.series.push_back({"transducer / moment arm", angle, trials.getColumn("force_measured_N"), true, 2});
    spec.series.push_back({"fixed ratio (thesis)", angle, trials.getColumn("force_fixed_ratio_N"), true, 1});
    const auto addFit = [&](const char* key, const char* label, int color) {
        const auto it = fits.find(key);
        if (it == fits.end()) return;
        spec.series.push_back(curve(std::string(label) + fmt(" %.1f N", it->second.peakY) + " at " +
                                        fmt("%.1f deg", it->second.peakX),
                                    it->second.fit, a0, a1, color));
    };
    addFit("muscle_force", "fit, peak", 0);
    addFit("force_fixed_ratio", "fit, peak", 1);
    spec.legend = PlotSpec::Legend::BottomRight;
    spec.yMin = 0;
    writePlotPng(dir.addFile("force_angle.png"), spec);

    PlotSpec fl;
    fl.title = "MVC force vs biceps path length (mean over repetitions)";
    fl.xLabel = "musculotendon path length (cm)";
    fl.yLabel = "force (N)";
    PlotSeries truth{"true muscle force", {}, {}, true, 0}, active{"active force (tared)", {}, {}, true, 2};
    for (int i = 0; i < summary.getNumRows(); ++i) {
        truth.x.push_back(100 * summary.get(i, "path_length_m"));
        truth.y.push_back(summary.get(i, "muscle_force_N_mean"));
        active.x.push_back(100 * summary.get(i, "path_length_m"));
        active.y.push_back(summary.get(i, "active_force_N_mean"));
    }
    fl.series = {truth, active};
    fl.legend = PlotSpec::Legend::BottomRight;
    writePlotPng(dir.addFile("force_length.png"), fl);
}

void plotSubmaximal(RunDirectory& dir, const Table& trials, const std::optional<PolynomialFit>& map) {
    const std::vector<double> angles = uniqueSorted(trials.getColumn("elbow_angle_deg"));
    auto byAngle = [&](const std::string& xc, const std::string& yc) {
        std::vector<PlotSeries> s;
        for (std::size_t k = 0; k < angles.size(); ++k) {
            PlotSeries p{fmt("%.0f deg", angles[k]), {}, {}, true, int(k)};
            for (int i = 0; i < trials.getNumRows(); ++i)
                if (trials.get(i, "elbow_angle_deg") == angles[k]) {
                    p.x.push_back(trials.get(i, xc));
                    p.y.push_back(trials.get(i, yc));
                }
            s.push_back(p);
        }
        return s;
    };
    PlotSpec fe;
    fe.title = "force vs EMG (both normalised to MVC at the same angle)";
    fe.xLabel = "EMG RMS / MVC EMG RMS";
    fe.yLabel = "active force / MVC force";
    fe.series = byAngle("emg_norm", "force_norm");
    writePlotPng(dir.addFile("force_emg.png"), fe);

    PlotSpec fa;
    fa.title = "force vs activation (levels resolved against the simulated MVC)";
    fa.xLabel = "activation U";
    fa.yLabel = "active force / MVC force";
    fa.series = byAngle("activation", "force_norm");
    writePlotPng(dir.addFile("force_activation.png"), fa);

    if (map) {
        PlotSpec ea;
        ea.title = "EMG-to-activation map (thesis 6.2.3)";
        ea.xLabel = "EMG RMS / MVC EMG RMS";
        ea.yLabel = "activation U";
        ea.series = byAngle("emg_norm", "activation");
        const std::vector<double> e = trials.getColumn("emg_norm");
        ea.series.push_back(curve("quadratic fit, R^2 = " + fmt("%.4f", map->rSquared), *map,
                                  *std::min_element(e.begin(), e.end()), *std::max_element(e.begin(), e.end()), 7));
        writePlotPng(dir.addFile("emg_activation.png"), ea);
    }
}

nlohmann::ordered_json fitJson(const PolynomialFit& f) {
    nlohmann::ordered_json j;
    j["coefficients"] = f.coefficients;
    j["r_squared"] = f.rSquared;
    j["rms_residual"] = f.rmsResidual;
    j["points"] = f.points;
    return j;
}

std::string fitsCsv(const std::map<std::string, QuadraticFit>& quadratic, const std::optional<PolynomialFit>& map) {
    std::string s = "fit,c0,c1,c2,r_squared,rms_residual,points,peak_x,peak_y\n";
    auto num = [](double v) { return std::isnan(v) ? std::string("NaN") : fmt("%.10g", v); };
    for (const auto& [name, q] : quadratic) {
        const auto& c = q.fit.coefficients;
        s += name + "," + num(c[0]) + "," + num(c[1]) + "," + num(c[2]) + "," + num(q.fit.rSquared) + "," +
             num(q.fit.rmsResidual) + "," + std::to_string(q.fit.points) + "," + num(q.peakX) + "," + num(q.peakY) + "\n";
    }
    if (map) {
        const auto& c = map->coefficients;
        s += "emg_to_activation," + num(c[0]) + "," + num(c[1]) + "," + num(c[2]) + "," + num(map->rSquared) + "," +
             num(map->rmsResidual) + "," + std::to_string(map->points) + ",NaN,NaN\n";
    }
    return s;
}

nlohmann::ordered_json protocolJson(const Protocol& p) {
    nlohmann::ordered_json j;
    j["name"] = p.name;
    j["kind"] = getProtocolKindName(p.kind);
    j["description"] = p.description;
    j["file"] = fs::path(p.sourcePath).filename().string();
    if (p.kind != ProtocolKind::Composition) {
        j["seed"] = p.seed;
        j["order"] = p.randomOrder ? "random" : "listed";
        j["repetitions"] = p.repetitions;
        j["inter_trial_rest_s"] = p.interTrialRest;
        j["inter_trial_rest_note"] = "recorded only: no fatigue model, so the rest costs no simulated time";
        const IsometricTrialSettings& t = p.trial;
        j["trial"] = {{"rest_s", t.restDuration}, {"rise_s", t.riseTime}, {"hold_s", t.holdDuration},
                      {"sample_rate_Hz", t.sampleRate}, {"averaging_window_s", t.averagingWindow},
                      {"accuracy", t.integration.accuracy}};
        std::vector<double> angles;
        for (double a : p.elbowAngles) angles.push_back(cleanDegrees(a));
        j["elbow_angles_deg"] = angles;
        std::vector<double> levels;
        for (double l : p.levels) levels.push_back(100 * l);
        j["levels_pct_mvc"] = levels;
        if (!p.pathLengths.empty()) j["path_lengths_m"] = p.pathLengths;
        if (p.maxPathLength > 0) j["max_path_length_m"] = p.maxPathLength;
        const EmgAcquisitionSettings& a = p.emg.acquisition;
        j["sensors"] = {
            {"transducer_noise_rms_N", p.transducerNoiseRms},
            {"emg",
             {{"enabled", p.emgEnabled}, {"internal_rate_Hz", p.emg.internalRate}, {"isi_cv", p.emg.isiCv},
              {"trains_per_unit", p.emg.trainsPerUnit}, {"muap_amplitude_V", p.emg.muapAmplitude},
              {"muap_width_slow_s", p.emg.muapWidthSlow}, {"muap_width_fast_s", p.emg.muapWidthFast},
              {"rms_window_s", p.emgRmsWindow}, {"gain", a.gain}, {"band_Hz", {a.bandLow, a.bandHigh}},
              {"band_order", a.bandOrder}, {"notch", a.notch}, {"notch_quality", a.notchQuality},
              {"mains_frequency_Hz", a.mainsFrequency}, {"mains_amplitude_V", a.mainsAmplitude},
              {"electrode_noise_rms_V", a.electrodeNoiseRms}, {"anti_alias_cutoff_Hz", a.antiAliasCutoff},
              {"anti_alias_order", a.antiAliasOrder}, {"zero_phase", a.zeroPhase},
              {"output_rate_Hz", a.outputRate}}}};
    } else {
        j["slow_units"] = {p.slowUnitsFrom, p.slowUnitsTo};
        j["fast_units"] = {p.fastUnitsFrom, p.fastUnitsTo};
        j["activation"] = p.compositionActivation;
        j["path_length_m"] = p.compositionPath;
    }
    return j;
}

nlohmann::ordered_json subjectJson(const Protocol& p, const ArmSetup& subject, const VirtualMuscle& m) {
    const MuscleParameters& mp = m.getParameters();
    const ArmParameters& a = subject.arm;
    nlohmann::ordered_json j;
    j["model"] = subject.name;
    j["arm_file"] = p.armFile.empty() ? std::string("(model)") : fs::path(p.armFile).filename().string();
    j["muscle_file"] = p.muscleFile.empty() ? std::string("(model)") : fs::path(p.muscleFile).filename().string();
    j["effort"] = {{"voluntary_activation", subject.effort.voluntaryActivation},
                   {"co_contraction", subject.effort.coContraction}, {"trial_cv", subject.effort.trialCv},
                   {"fatigue", subject.effort.fatigue}};
    j["arm"] = {{"body_mass_kg", a.bodyMass}, {"body_height_m", a.bodyHeight},
                {"origin_distance_m", a.originDistance}, {"insertion_distance_m", a.insertionDistance},
                {"strap_distance_m", a.strapDistance}, {"transducer_range_N", a.transducerRange},
                {"elbow_range_deg", {a.minElbowAngleDeg, a.maxElbowAngleDeg}}};
    j["muscle"] = {{"name", mp.name}, {"mass_kg", mp.mass}, {"optimal_fascicle_length_m", mp.optimalFascicleLength},
                   {"optimal_tendon_length_m", mp.optimalTendonLength}, {"max_path_length_m", mp.maxPathLength},
                   {"F0_N", m.getF0()}, {"slow_fraction", mp.slowFraction}, {"slow_units", mp.numSlowUnits},
                   {"fast_units", mp.numFastUnits}, {"f05_slow_pps", mp.slow.f05}, {"f05_fast_pps", mp.fast.f05}};
    return j;
}

}  // namespace

ProtocolResult runProtocol(const Protocol& protocol, const ArmSetup& subject, const ProtocolRunOptions& options) {
    RunDirectory dir(options.outDir);
    const VirtualMuscle muscle(subject.calcBicepsParameters());
    ProtocolResult result;
    nlohmann::ordered_json manifest;
    manifest["armsim_version"] = ARMSIM_VERSION;
    manifest["simbody_version"] = ARMSIM_SIMBODY_VERSION;
    manifest["protocol"] = protocolJson(protocol);
    manifest["subject"] = subjectJson(protocol, subject, muscle);
    nlohmann::ordered_json results;

    int done = 0, total = 0;
    auto tick = [&](int, int) {
        ++done;
        if (options.progress) options.progress(done, total);
    };

    if (protocol.kind == ProtocolKind::Composition) {
        MuscleParameters mp = subject.calcBicepsParameters();
        result.composition = Table({"slow_units", "fast_units", "force_N"});
        HeatMapSpec heat;
        heat.title = "steady force at U = " + fmt("%.2f", protocol.compositionActivation) + ", path " +
                     fmt("%.1f cm", 100 * protocol.compositionPath) + " (thesis 7.3)";
        heat.xLabel = "fast units Nf";
        heat.yLabel = "slow units Ns";
        heat.zLabel = "force (N)";
        for (int f = protocol.fastUnitsFrom; f <= protocol.fastUnitsTo; ++f) heat.x.push_back(f);
        for (int s = protocol.slowUnitsFrom; s <= protocol.slowUnitsTo; ++s) heat.y.push_back(s);
        heat.z.assign(heat.x.size() * heat.y.size(), NAN);
        std::string matrix = "slow_units";
        for (double f : heat.x) matrix += ",fast_" + std::to_string(int(f));
        matrix += "\n";
        total = int(heat.y.size());
        for (std::size_t j = 0; j < heat.y.size(); ++j) {
            matrix += std::to_string(int(heat.y[j]));
            for (std::size_t i = 0; i < heat.x.size(); ++i) {
                mp.numSlowUnits = int(heat.y[j]);
                mp.numFastUnits = int(heat.x[i]);
                const SteadyState ss =
                    VirtualMuscle(mp).calcSteadyState(protocol.compositionPath, protocol.compositionActivation);
                const double F = ss.converged ? ss.force : NAN;
                result.composition.appendRow({heat.y[j], heat.x[i], F});
                heat.z[i * heat.y.size() + j] = F;
                matrix += "," + (std::isnan(F) ? std::string("NaN") : fmt("%.10g", F));
            }
            matrix += "\n";
            tick(0, 0);
        }
        if (dir.isEnabled()) {
            dir.write("composition.csv", result.composition.toCsv(kCsvDigits));
            dir.write("composition_matrix.csv", matrix);
            writeHeatMapPng(dir.addFile("composition_heatmap.png"), heat);
        }
    } else {
        // Arm trials in canonical order: angle, level, repetition.
        std::vector<ArmTrialPlan> plans;
        for (double angle : protocol.elbowAngles)
            for (double level : protocol.levels)
                for (int rep = 1; rep <= protocol.repetitions; ++rep) {
                    ArmTrialPlan p;
                    p.index = int(plans.size());
                    p.angle = angle;
                    p.level = level;
                    p.repetition = rep;
                    p.seed = trialSeed(protocol.seed, p.index);
                    p.id = angleId(angle);
                    if (protocol.kind == ProtocolKind::Submaximal) p.id += fmt("_l%03.0f", 100 * level);
                    if (protocol.repetitions > 1) p.id += "_r" + std::to_string(rep);
                    plans.push_back(p);
                }
        const int numMuscle = int(protocol.pathLengths.size());
        total = int(plans.size()) + numMuscle;

        // Run order: phase 1 = the 100 % MVC trials (the references), phase 2 = the rest; each phase
        // shuffled with the seed unless listed order is asked for.
        std::vector<int> phase1, phase2;
        for (const auto& p : plans) (p.level == 1.0 ? phase1 : phase2).push_back(p.index);
        std::mt19937_64 orderRng(splitMix(protocol.seed ^ 0x0DDBA11ULL));
        if (protocol.randomOrder) {
            std::shuffle(phase1.begin(), phase1.end(), orderRng);
            std::shuffle(phase2.begin(), phase2.end(), orderRng);
        }
        std::vector<int> runPosition(plans.size());
        {
            int pos = 0;
            for (int i : phase1) runPosition[i] = pos++;
            for (int i : phase2) runPosition[i] = pos++;
        }

        std::vector<ArmTrialOutcome> outcomes(plans.size());
        std::vector<MuscleTrialOutcome> muscleOutcomes(numMuscle);
        MuscleParameters sweepParams = subject.calcBicepsParameters();
        if (protocol.maxPathLength > 0) sweepParams.maxPathLength = protocol.maxPathLength;
        const VirtualMuscle sweepMuscle(sweepParams);
        auto muscleId = [&](int k) { return fmt("p%04.0fmm", 1000 * protocol.pathLengths[k]); };

        // Phase 1 (with the muscle-alone trials of force_length).
        runParallel(
            int(phase1.size()) + numMuscle, options.jobs,
            [&](int k) {
                if (k < int(phase1.size())) {
                    const int i = phase1[k];
                    outcomes[i] = runArmTrial(plans[i], protocol, subject, muscle, dir, i == 0);
                } else {
                    const int m = k - int(phase1.size());
                    muscleOutcomes[m] = runMuscleTrial(protocol.pathLengths[m], muscleId(m), protocol, sweepMuscle, dir);
                }
            },
            tick);

        // Phase 2: resolve each level against the simulated MVC at its angle.
        if (!phase2.empty()) {
            std::map<double, std::pair<double, int>> mvc;  // angle -> (sum active force, n)
            for (int i : phase1) {
                mvc[plans[i].angle].first += outcomes[i].activeForce;
                ++mvc[plans[i].angle].second;
            }
            for (int i : phase2) {
                const auto& [sum, n] = mvc.at(plans[i].angle);
                double P = 0;  // the arm's path at this angle
                for (int j : phase1)
                    if (plans[j].angle == plans[i].angle) P = outcomes[j].summary.pathLength;
                plans[i].activation = calcActivationForActiveForce(muscle, P, plans[i].level * sum / n);
            }
            runParallel(
                int(phase2.size()), options.jobs,
                [&](int k) {
                    const int i = phase2[k];
                    outcomes[i] = runArmTrial(plans[i], protocol, subject, muscle, dir, i == 0);
                },
                tick);
        }

        if (!plans.empty()) {
            result.trials = buildTrialTable(plans, outcomes, runPosition);
            result.summary = buildSummaryTable(result.trials);
            for (const auto& p : plans) result.trialIds.push_back(p.id);
        }
        if (numMuscle > 0) {
            result.muscleSweep = Table({"path_length_m", "muscle_force_N", "steady_force_N", "passive_force_N"});
            for (const auto& o : muscleOutcomes)
                result.muscleSweep.appendRow({o.pathLength, o.force, o.steadyForce, o.passiveForce});
        }

        // Fits.
        if (protocol.kind == ProtocolKind::Mvc && uniqueSorted(result.trials.getColumn("elbow_angle_deg")).size() >= 3) {
            const std::vector<double> a = result.trials.getColumn("elbow_angle_deg");
            result.quadraticFits["muscle_force"] = fitQuadratic(a, result.trials.getColumn("muscle_force_N"));
            result.quadraticFits["force_measured"] = fitQuadratic(a, result.trials.getColumn("force_measured_N"));
            result.quadraticFits["force_fixed_ratio"] = fitQuadratic(a, result.trials.getColumn("force_fixed_ratio_N"));
        }
        if (protocol.kind == ProtocolKind::Submaximal && protocol.emgEnabled) {
            const std::vector<double> e = result.trials.getColumn("emg_norm");
            if (uniqueSorted(e).size() >= 3)
                result.emgToActivation = fitPolynomial(e, result.trials.getColumn("activation"), 2);
        }
        if (protocol.kind == ProtocolKind::ForceLength) {
            if (numMuscle >= 3)
                if (auto f = fitPeak(result.muscleSweep.getColumn("path_length_m"),
                                     result.muscleSweep.getColumn("muscle_force_N"), 2))
                    result.quadraticFits["muscle_alone_peak"] = *f;
            if (result.summary.getNumRows() >= 3) {
                std::vector<double> P = result.summary.getColumn("path_length_m"),
                                    F = result.summary.getColumn("muscle_force_N_mean");
                std::vector<std::size_t> order(P.size());
                for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
                std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return P[a] < P[b]; });
                std::vector<double> Ps, Fs;
                for (std::size_t k : order) {
                    Ps.push_back(P[k]);
                    Fs.push_back(F[k]);
                }
                if (auto f = fitPeak(Ps, Fs, 2)) result.quadraticFits["arm_peak"] = *f;
            }
        }

        // Files.
        if (dir.isEnabled()) {
            if (!plans.empty()) {
                dir.write("trials.csv", result.trials.toCsv(kCsvDigits));
                dir.write("summary.csv", result.summary.toCsv(kCsvDigits));
                if (protocol.emgEnabled) plotExampleEmg(dir, plans[0].id, outcomes[0]);
            }
            if (numMuscle > 0) dir.write("muscle_sweep.csv", result.muscleSweep.toCsv(kCsvDigits));
            if (!result.quadraticFits.empty() || result.emgToActivation)
                dir.write("fits.csv", fitsCsv(result.quadraticFits, result.emgToActivation));
            if (protocol.kind == ProtocolKind::Mvc) plotMvc(dir, result.trials, result.summary, result.quadraticFits);
            if (protocol.kind == ProtocolKind::Submaximal) plotSubmaximal(dir, result.trials, result.emgToActivation);
            if (protocol.kind == ProtocolKind::ForceLength) {
                PlotSpec spec;
                spec.title = "force-length at full activation";
                spec.xLabel = "musculotendon path length (cm)";
                spec.yLabel = "force (N)";
                if (numMuscle > 0) {
                    PlotSeries m{"muscle alone, 3 s integration", {}, {}, true, 0},
                        st{"muscle alone, steady solve", {}, {}, false, 0}, pa{"passive (U = 0)", {}, {}, false, 5};
                    for (const auto& o : muscleOutcomes) {
                        m.x.push_back(100 * o.pathLength);
                        m.y.push_back(o.force);
                        st.x.push_back(100 * o.pathLength);
                        st.y.push_back(o.steadyForce);
                        pa.x.push_back(100 * o.pathLength);
                        pa.y.push_back(o.passiveForce);
                    }
                    spec.series = {st, m, pa};
                }
                if (!plans.empty()) {
                    PlotSeries a{"in the arm (elbow angle sweep)", {}, {}, true, 1};
                    for (int i = 0; i < result.summary.getNumRows(); ++i) {
                        a.x.push_back(100 * result.summary.get(i, "path_length_m"));
                        a.y.push_back(result.summary.get(i, "muscle_force_N_mean"));
                    }
                    spec.series.push_back(a);
                }
                writePlotPng(dir.addFile("force_length.png"), spec);
            }
        }

        nlohmann::ordered_json trialList = nlohmann::ordered_json::array();
        for (const auto& p : plans)
            trialList.push_back({{"id", p.id}, {"index", p.index}, {"run_order", runPosition[p.index]},
                                 {"elbow_angle_deg", cleanDegrees(p.angle)}, {"level_pct_mvc", 100 * p.level},
                                 {"repetition", p.repetition}, {"activation", p.activation}, {"seed", p.seed}});
        for (int m = 0; m < numMuscle; ++m)
            trialList.push_back({{"id", muscleId(m)}, {"path_length_m", protocol.pathLengths[m]}, {"activation", 1.0}});
        manifest["trials"] = trialList;
    }

    for (const auto& [name, q] : result.quadraticFits) {
        nlohmann::ordered_json j = fitJson(q.fit);
        j["peak_x"] = q.peakX;
        j["peak_y"] = q.peakY;
        j["has_maximum"] = q.hasMaximum;
        results[name] = j;
    }
    if (result.emgToActivation) results["emg_to_activation"] = fitJson(*result.emgToActivation);
    manifest["results"] = results;

    if (dir.isEnabled()) {
        dir.write("protocol.yaml", protocol.sourceText);
        dir.addFile("manifest.json");
        result.files = dir.getFiles();
        manifest["files"] = result.files;
        dir.write("manifest.json", manifest.dump(2) + "\n");
        dir.commit();
    }
    return result;
}

}  // namespace armsim
