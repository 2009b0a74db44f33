#include "experiments/protocol.h"

#include "basics/errors.h"
#include "basics/output_folder.h"
#include "basics/parallel.h"
#include "basics/storage_file.h"
#include "experiments/protocol_run.h"
#include "model/geometry.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace armsim {

using detail::ArmTrialOutcome;
using detail::ArmTrialPlan;
using detail::getProtocolKindSpec;
using detail::ProtocolKindSpec;
using detail::kCsvDigits;
using detail::ProtocolRun;
using detail::uniqueSorted;

namespace {

constexpr double kTimeTol = 1e-9;           // s, sample times compared against window edges
constexpr double kBisectionTol = 1e-12;     // activation, calcActivationForActiveForce

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
            throw SimulationError("no steady state at path " + fmt::format("{:.4f}", pathLength) + " m, U = " + fmt::format("{:.6f}", U) +
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

// ---- Trials ---------------------------------------------------------------------------------------

std::string angleId(double angle) { return fmt::format("a{:03.0f}", radToDeg(angle)); }

ArmTrialOutcome runArmTrial(const ArmTrialPlan& plan, const Protocol& protocol, const ArmSetup& subject,
                            const VirtualMuscle& muscle, OutputFolder& dir, bool keepSeries) {
    IsometricTrialSettings s = protocol.trial;
    s.elbowAngle = plan.angle;
    // The subject's effort: agonists at the planned drive times the voluntary activation, antagonists
    // co-contracting; both vary from trial to trial (seeded) and fade with fatigue over repetitions.
    const SubjectEffort& e = subject.effort;
    auto effortRng = PortableRandom::fromSeed(splitMix(plan.seed ^ 0xE1F0E1F0ULL));
    const double variation = 1 + e.trialCv * effortRng.drawNormal();
    const double antagonistVariation = 1 + e.trialCv * effortRng.drawNormal();
    const double fatigue = std::pow(1 - e.fatigue, plan.repetition - 1);
    s.activation = std::clamp(plan.activation * e.voluntaryActivation * variation * fatigue, 0.0, 1.0);
    s.antagonistActivation = std::clamp(e.coContraction * antagonistVariation * fatigue, 0.0, 1.0);
    const IsometricTrialResult r = runIsometricTrial(subject, s);
    const Table& t = r.series;
    const int rows = t.getNumRows();
    const ArmParameters& ap = subject.arm;
    const double h = r.summary.momentArm;

    // Transducer noise: every reading and the estimates derived from it.
    auto noiseRng = PortableRandom::fromSeed(splitMix(plan.seed ^ 0x5A5A5A5AULL));
    auto emgRng = PortableRandom::fromSeed(splitMix(plan.seed));
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
            const TransducerReading r =
                calcTransducerReading(ap, row[cStrap] + protocol.transducerNoiseRms * noiseRng.drawNormal(), plan.angle, h, row[cForce]);
            row[cStrap] = r.strapForce;
            row[cSat] = r.saturated ? 1.0 : 0.0;
            row[cByArm] = r.forceMomentArm;
            row[cByRatio] = r.forceFixedRatio;
            row[cErrArm] = r.errorMomentArmPct;
            row[cErrRatio] = r.errorFixedRatioPct;
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
                                  const VirtualMuscle& muscle, OutputFolder& dir) {
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

/// Reports how many trials (or composition rows) have finished in all.
using Progress = std::function<void(int done)>;

/// Composition: the steady force over the grid of slow x fast unit counts.
void runComposition(const Protocol& protocol, const ArmSetup& subject, ProtocolResult& result, const Progress& progress) {
    MuscleParameters mp = subject.calcBicepsParameters();
    result.composition = Table({"slow_units", "fast_units", "force_N"});
    for (int slow = protocol.slowUnitsFrom; slow <= protocol.slowUnitsTo; ++slow) {
        for (int fast = protocol.fastUnitsFrom; fast <= protocol.fastUnitsTo; ++fast) {
            mp.numSlowUnits = slow;
            mp.numFastUnits = fast;
            const SteadyState ss = VirtualMuscle(mp).calcSteadyState(protocol.compositionPath, protocol.compositionActivation);
            result.composition.appendRow({double(slow), double(fast), ss.converged ? ss.force : NAN});
        }
        checkInterruption();
        progress(slow - protocol.slowUnitsFrom + 1);
    }
}

/// The arm trials in canonical order (angle, level, repetition) and their run order: phase 1 = the
/// 100 % MVC trials (the references), phase 2 = the rest; each phase shuffled with the seed unless
/// listed order is asked for.
void planArmTrials(const Protocol& protocol, ProtocolRun& run, std::vector<int>& phase1, std::vector<int>& phase2) {
    const bool levelInId = getProtocolKindSpec(protocol.kind).levelInTrialId;
    for (double angle : protocol.elbowAngles)
        for (double level : protocol.levels)
            for (int rep = 1; rep <= protocol.repetitions; ++rep) {
                ArmTrialPlan p;
                p.index = int(run.plans.size());
                p.angle = angle;
                p.level = level;
                p.repetition = rep;
                p.seed = trialSeed(protocol.seed, p.index);
                p.id = angleId(angle);
                if (levelInId) p.id += fmt::format("_l{:03.0f}", 100 * level);
                if (protocol.repetitions > 1) p.id += "_r" + std::to_string(rep);
                run.plans.push_back(p);
            }
    for (const auto& p : run.plans) (p.level == 1.0 ? phase1 : phase2).push_back(p.index);
    auto orderRng = PortableRandom::fromSeed(splitMix(protocol.seed ^ 0x0DDBA11ULL));
    if (protocol.randomOrder) {
        orderRng.shuffle(phase1);
        orderRng.shuffle(phase2);
    }
    run.runPosition.assign(run.plans.size(), 0);
    int pos = 0;
    for (int i : phase1) run.runPosition[i] = pos++;
    for (int i : phase2) run.runPosition[i] = pos++;
    for (double P : protocol.pathLengths) run.muscleIds.push_back(fmt::format("p{:04.0f}mm", 1000 * P));
}

/// Arm and muscle-alone trials (their time series go to dir as they finish), the trial, summary and
/// sweep tables.
void runTrials(const Protocol& protocol, const ArmSetup& subject, const VirtualMuscle& muscle, OutputFolder& dir,
               int jobs, ProtocolRun& run, const Progress& progress) {
    std::vector<int> phase1, phase2;
    planArmTrials(protocol, run, phase1, phase2);
    std::vector<ArmTrialPlan>& plans = run.plans;
    const int numMuscle = int(protocol.pathLengths.size());
    std::vector<ArmTrialOutcome> outcomes(plans.size());
    std::vector<MuscleTrialOutcome> muscleOutcomes(numMuscle);
    MuscleParameters sweepParams = subject.calcBicepsParameters();
    if (protocol.maxPathLength > 0) sweepParams.maxPathLength = protocol.maxPathLength;
    const VirtualMuscle sweepMuscle(sweepParams);

    // Phase 1 (with the muscle-alone trials of force_length).
    runParallel(
        int(phase1.size()) + numMuscle, jobs,
        [&](int k) {
            if (k < int(phase1.size())) {
                const int i = phase1[k];
                outcomes[i] = runArmTrial(plans[i], protocol, subject, muscle, dir, i == 0);
            } else {
                const int m = k - int(phase1.size());
                muscleOutcomes[m] = runMuscleTrial(protocol.pathLengths[m], run.muscleIds[m], protocol, sweepMuscle, dir);
            }
        },
        [&](int done, int) { progress(done); });

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
            int(phase2.size()), jobs,
            [&](int k) {
                const int i = phase2[k];
                outcomes[i] = runArmTrial(plans[i], protocol, subject, muscle, dir, i == 0);
            },
            [&, base = int(phase1.size()) + numMuscle](int done, int) { progress(base + done); });
    }

    ProtocolResult& result = run.result;
    if (!plans.empty()) {
        result.trials = buildTrialTable(plans, outcomes, run.runPosition);
        result.summary = buildSummaryTable(result.trials);
        for (const auto& p : plans) result.trialIds.push_back(p.id);
        run.example = std::move(outcomes[0]);
    }
    if (numMuscle > 0) {
        result.muscleSweep = Table({"path_length_m", "muscle_force_N", "steady_force_N", "passive_force_N"});
        for (const auto& o : muscleOutcomes) result.muscleSweep.appendRow({o.pathLength, o.force, o.steadyForce, o.passiveForce});
    }
}

}  // namespace

namespace detail {

// Force-angle quadratics of the MVC forces (three angles at least).
void fitMvc(const Protocol&, ProtocolResult& result) {
    if (result.trials.getNumRows() == 0 || uniqueSorted(result.trials.getColumn("elbow_angle_deg")).size() < 3) return;
    const std::vector<double> a = result.trials.getColumn("elbow_angle_deg");
    result.quadraticFits["muscle_force"] = fitQuadratic(a, result.trials.getColumn("muscle_force_N"));
    result.quadraticFits["force_measured"] = fitQuadratic(a, result.trials.getColumn("force_measured_N"));
    result.quadraticFits["force_fixed_ratio"] = fitQuadratic(a, result.trials.getColumn("force_fixed_ratio_N"));
}

// The EMG-to-activation map (thesis 6.2.3), with EMG and three distinct levels at least.
void fitSubmaximal(const Protocol& protocol, ProtocolResult& result) {
    if (!protocol.emgEnabled) return;
    const std::vector<double> e = result.trials.getColumn("emg_norm");
    if (uniqueSorted(e).size() >= 3) result.emgToActivation = fitPolynomial(e, result.trials.getColumn("activation"), 2);
}

// The force-length peaks: of the muscle alone and in the arm (mean over repetitions, by path length).
void fitForceLength(const Protocol&, ProtocolResult& result) {
    if (result.muscleSweep.getNumRows() >= 3)
        if (auto f = fitPeak(result.muscleSweep.getColumn("path_length_m"), result.muscleSweep.getColumn("muscle_force_N"), 2))
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

}  // namespace detail

ProtocolResult runProtocol(const Protocol& protocol, const ArmSetup& subject, const ProtocolRunOptions& options) {
    // These protocols simulate the primary muscle's motor units (EMG spike trains, the activation for
    // a submaximal force, the muscle-alone sweep, the unit grid): Virtual Muscle only.
    const MuscleSpec& primary = subject.muscles.at(subject.primary);
    if (primary.muscleModel != kDefaultMuscleModel)
        throw InputError("protocol '" + protocol.name + "' (" + getProtocolKindName(protocol.kind) +
                         ") simulates the primary muscle's motor units, but muscle '" + primary.params.name +
                         "' of model '" + subject.name + "' is muscle_model " + primary.muscleModel +
                         ": expected virtual_muscle (torque protocols, with conditions:, work with every muscle model)");
    OutputFolder dir(options.outDir, OutputFolder::Mode::ReplaceRun, "manifest.json");
    const VirtualMuscle muscle(subject.calcBicepsParameters());
    ProtocolRun run;
    int total = 0;
    const Progress progress = [&](int done) {
        if (options.progress) options.progress(done, total);
    };
    const ProtocolKindSpec& kind = getProtocolKindSpec(protocol.kind);
    if (!kind.armTrials) {
        total = protocol.slowUnitsTo - protocol.slowUnitsFrom + 1;
        runComposition(protocol, subject, run.result, progress);
    } else {
        total = int(protocol.elbowAngles.size() * protocol.levels.size()) * protocol.repetitions +
                int(protocol.pathLengths.size());
        runTrials(protocol, subject, muscle, dir, options.jobs, run, progress);
    }
    if (kind.fit) kind.fit(protocol, run.result);
    if (dir.isEnabled()) detail::writeProtocolFiles(dir, protocol, subject, muscle, run, options.beforeCommit);
    return std::move(run.result);
}

}  // namespace armsim
