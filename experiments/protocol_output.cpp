// The files of a protocol run: tables, fits, plots, protocol.yaml and manifest.json (protocol_run.h).
#include "basics/csv.h"
#include "basics/errors.h"
#include "basics/plot.h"
#include "experiments/protocol_run.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>

#ifndef ARMSIM_VERSION
#define ARMSIM_VERSION "unknown"
#endif
#ifndef ARMSIM_SIMBODY_VERSION
#define ARMSIM_SIMBODY_VERSION "unknown"
#endif

namespace fs = std::filesystem;

namespace armsim::detail {

namespace {

PlotSeries curve(const std::string& label, const PolynomialFit& f, double x0, double x1, int color) {
    PlotSeries s{label, {}, {}, false, color};
    for (int i = 0; i <= 100; ++i) {
        const double x = x0 + (x1 - x0) * i / 100.0;
        s.x.push_back(x);
        s.y.push_back(f.evaluate(x));
    }
    return s;
}

void plotExampleEmg(OutputFolder& dir, const std::string& id, const ArmTrialOutcome& o) {
    PlotSpec spec;
    spec.title = "synthetic surface EMG, trial " + id + " (referred to the electrodes)";
    spec.xLabel = "time (s)";
    spec.yLabel = "EMG (mV)";
    PlotSeries raw{"acquired EMG (10-400 Hz, 50 Hz notch, 1000 Hz)", o.time, o.emgSignal, false, 5};
    PlotSeries rms{"moving RMS", o.time, o.emgRms, false, 3};
    for (double& v : raw.y) v *= 1000;
    for (double& v : rms.y) v *= 1000;
    spec.series = {raw, rms};
    dir.writeWith("emg_trial.png", [&](const std::string& p) { writePlotPng(p, spec); });
}

void plotMvc(OutputFolder& dir, const Table& trials, const Table& summary, const std::map<std::string, QuadraticFit>& fits) {
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
        const QuadraticFit& q = it->second;
        spec.series.push_back(curve(std::isnan(q.peakX) ? std::string("quadratic fit (no peak)")
                                                        : std::string(label) + fmt::format(" {:.1f} N at {:.1f} deg", q.peakY, q.peakX),
                                    q.fit, a0, a1, color));
    };
    addFit("muscle_force", "fit, peak", 0);
    addFit("force_fixed_ratio", "fit, peak", 1);
    spec.yMin = 0;
    dir.writeWith("force_angle.png", [&](const std::string& p) { writePlotPng(p, spec); });

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
    dir.writeWith("force_length.png", [&](const std::string& p) { writePlotPng(p, fl); });
}

void plotSubmaximal(OutputFolder& dir, const Table& trials, const std::optional<PolynomialFit>& map) {
    const std::vector<double> angles = uniqueSorted(trials.getColumn("elbow_angle_deg"));
    auto byAngle = [&](const std::string& xc, const std::string& yc) {
        std::vector<PlotSeries> s;
        for (std::size_t k = 0; k < angles.size(); ++k) {
            PlotSeries p{fmt::format("{:.0f} deg", angles[k]), {}, {}, true, int(k)};
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
    dir.writeWith("force_emg.png", [&](const std::string& p) { writePlotPng(p, fe); });

    PlotSpec fa;
    fa.title = "force vs activation (levels resolved against the simulated MVC)";
    fa.xLabel = "activation U";
    fa.yLabel = "active force / MVC force";
    fa.series = byAngle("activation", "force_norm");
    dir.writeWith("force_activation.png", [&](const std::string& p) { writePlotPng(p, fa); });

    if (map) {
        PlotSpec ea;
        ea.title = "EMG-to-activation map (thesis 6.2.3)";
        ea.xLabel = "EMG RMS / MVC EMG RMS";
        ea.yLabel = "activation U";
        ea.series = byAngle("emg_norm", "activation");
        const std::vector<double> e = trials.getColumn("emg_norm");
        ea.series.push_back(curve("quadratic fit, R^2 = " + fmt::format("{:.4f}", map->rSquared), *map,
                                  *std::min_element(e.begin(), e.end()), *std::max_element(e.begin(), e.end()), 7));
        dir.writeWith("emg_activation.png", [&](const std::string& p) { writePlotPng(p, ea); });
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

// One row per fit; a cell without a value (no peak, the EMG map's peak) is empty, as in every CSV.
std::string fitsCsv(const std::map<std::string, QuadraticFit>& quadratic, const std::optional<PolynomialFit>& map) {
    CsvText csv({"fit", "c0", "c1", "c2", "r_squared", "rms_residual", "points", "peak_x", "peak_y"});
    auto fitRow = [](const std::string& name, const PolynomialFit& f) {
        CsvRow row;
        row.addText(name);
        for (std::size_t k = 0; k < 3; ++k) row.addNumber(k < f.coefficients.size() ? f.coefficients[k] : NAN, kCsvDigits);
        row.addNumber(f.rSquared, kCsvDigits).addNumber(f.rmsResidual, kCsvDigits).addInteger(f.points);
        return row;
    };
    for (const auto& [name, q] : quadratic)
        csv.addRow(fitRow(name, q.fit).addNumber(q.peakX, kCsvDigits).addNumber(q.peakY, kCsvDigits));
    if (map) csv.addRow(fitRow("emg_to_activation", *map).addEmpty().addEmpty());
    return csv.getText();
}

nlohmann::ordered_json protocolJson(const Protocol& p) {
    nlohmann::ordered_json j;
    j["name"] = p.name;
    j["kind"] = getProtocolKindName(p.kind);
    j["description"] = p.description;
    j["file"] = fs::path(p.sourcePath).filename().string();
    if (getProtocolKindSpec(p.kind).armTrials) {
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

void writeComposition(OutputFolder& dir, const Protocol& protocol, const Table& composition) {
    HeatMapSpec heat;
    heat.title = "steady force at U = " + fmt::format("{:.2f}", protocol.compositionActivation) + ", path " +
                 fmt::format("{:.1f} cm", 100 * protocol.compositionPath) + " (thesis 7.3)";
    heat.xLabel = "fast units Nf";
    heat.yLabel = "slow units Ns";
    heat.zLabel = "force (N)";
    for (int f = protocol.fastUnitsFrom; f <= protocol.fastUnitsTo; ++f) heat.x.push_back(f);
    for (int s = protocol.slowUnitsFrom; s <= protocol.slowUnitsTo; ++s) heat.y.push_back(s);
    heat.z.assign(heat.x.size() * heat.y.size(), NAN);
    std::vector<std::string> header = {"slow_units"};
    for (double f : heat.x) header.push_back("fast_" + std::to_string(int(f)));
    Table matrix(header);
    // composition rows are slow-major: row j * nx + i holds (slow y[j], fast x[i]).
    for (std::size_t j = 0; j < heat.y.size(); ++j) {
        std::vector<double> row = {heat.y[j]};
        for (std::size_t i = 0; i < heat.x.size(); ++i) {
            const double F = composition.get(int(j * heat.x.size() + i), 2);
            heat.z[i * heat.y.size() + j] = F;
            row.push_back(F);
        }
        matrix.appendRow(row);
    }
    dir.write("composition.csv", composition.toCsv(kCsvDigits));
    dir.write("composition_matrix.csv", matrix.toCsv(kCsvDigits));
    dir.writeWith("composition_heatmap.png", [&](const std::string& p) { writeHeatMapPng(p, heat); });
}

void plotForceLength(OutputFolder& dir, const ProtocolResult& result) {
    PlotSpec spec;
    spec.title = "force-length at full activation";
    spec.xLabel = "musculotendon path length (cm)";
    spec.yLabel = "force (N)";
    const Table& sweep = result.muscleSweep;
    if (sweep.getNumRows() > 0) {
        PlotSeries m{"muscle alone, 3 s integration", {}, {}, true, 0},
            st{"muscle alone, steady solve", {}, {}, false, 0}, pa{"passive (U = 0)", {}, {}, false, 5};
        for (int i = 0; i < sweep.getNumRows(); ++i) {
            const double x = 100 * sweep.get(i, "path_length_m");
            m.x.push_back(x);
            m.y.push_back(sweep.get(i, "muscle_force_N"));
            st.x.push_back(x);
            st.y.push_back(sweep.get(i, "steady_force_N"));
            pa.x.push_back(x);
            pa.y.push_back(sweep.get(i, "passive_force_N"));
        }
        spec.series = {st, m, pa};
    }
    if (result.trials.getNumRows() > 0) {
        PlotSeries a{"in the arm (elbow angle sweep)", {}, {}, true, 1};
        for (int i = 0; i < result.summary.getNumRows(); ++i) {
            a.x.push_back(100 * result.summary.get(i, "path_length_m"));
            a.y.push_back(result.summary.get(i, "muscle_force_N_mean"));
        }
        spec.series.push_back(a);
    }
    dir.writeWith("force_length.png", [&](const std::string& p) { writePlotPng(p, spec); });
}

}  // namespace

void writeMvcFiles(OutputFolder& dir, const Protocol&, const ProtocolResult& result) {
    plotMvc(dir, result.trials, result.summary, result.quadraticFits);
}

void writeSubmaximalFiles(OutputFolder& dir, const Protocol&, const ProtocolResult& result) {
    plotSubmaximal(dir, result.trials, result.emgToActivation);
}

void writeForceLengthFiles(OutputFolder& dir, const Protocol&, const ProtocolResult& result) { plotForceLength(dir, result); }

void writeCompositionFiles(OutputFolder& dir, const Protocol& protocol, const ProtocolResult& result) {
    writeComposition(dir, protocol, result.composition);
}

void writeProtocolFiles(OutputFolder& dir, const Protocol& protocol, const ArmSetup& subject,
                        const VirtualMuscle& muscle, ProtocolRun& run,
                        const std::function<void(OutputFolder&, const ProtocolResult&)>& beforeCommit) {
    ProtocolResult& result = run.result;
    nlohmann::ordered_json manifest;
    manifest["armsim_version"] = ARMSIM_VERSION;
    manifest["simbody_version"] = ARMSIM_SIMBODY_VERSION;
    manifest["protocol"] = protocolJson(protocol);
    manifest["subject"] = subjectJson(protocol, subject, muscle);
    const ProtocolKindSpec& kind = getProtocolKindSpec(protocol.kind);
    if (!kind.armTrials) {
        kind.write(dir, protocol, result);
    } else {
        if (!run.plans.empty()) {
            dir.write("trials.csv", result.trials.toCsv(kCsvDigits));
            dir.write("summary.csv", result.summary.toCsv(kCsvDigits));
            if (protocol.emgEnabled) plotExampleEmg(dir, run.plans[0].id, run.example);
        }
        if (result.muscleSweep.getNumRows() > 0) dir.write("muscle_sweep.csv", result.muscleSweep.toCsv(kCsvDigits));
        if (!result.quadraticFits.empty() || result.emgToActivation)
            dir.write("fits.csv", fitsCsv(result.quadraticFits, result.emgToActivation));
        kind.write(dir, protocol, result);

        nlohmann::ordered_json trialList = nlohmann::ordered_json::array();
        for (const auto& p : run.plans)
            trialList.push_back({{"id", p.id}, {"index", p.index}, {"run_order", run.runPosition[p.index]},
                                 {"elbow_angle_deg", cleanDegrees(p.angle)}, {"level_pct_mvc", 100 * p.level},
                                 {"repetition", p.repetition}, {"activation", p.activation}, {"seed", p.seed}});
        for (std::size_t m = 0; m < run.muscleIds.size(); ++m)
            trialList.push_back({{"id", run.muscleIds[m]}, {"path_length_m", protocol.pathLengths[m]}, {"activation", 1.0}});
        manifest["trials"] = trialList;
    }
    nlohmann::ordered_json results;
    for (const auto& [name, q] : result.quadraticFits) {
        nlohmann::ordered_json j = fitJson(q.fit);
        j["peak_x"] = q.peakX;
        j["peak_y"] = q.peakY;
        j["has_maximum"] = q.hasMaximum;
        results[name] = j;
    }
    if (result.emgToActivation) results["emg_to_activation"] = fitJson(*result.emgToActivation);
    manifest["results"] = results;
    dir.write("protocol.yaml", protocol.sourceText);
    if (beforeCommit) {
        try {
            beforeCommit(dir, result);
        } catch (const InputError& e) {  // the run's files named where they would have been
            throw InputError(dir.showPaths(e.what()));
        } catch (const SimulationError& e) {
            throw SimulationError(dir.showPaths(e.what()));
        }
    }
    dir.addFile("manifest.json");
    result.files = dir.getFiles();
    manifest["files"] = result.files;
    dir.write("manifest.json", manifest.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) + "\n");
    dir.commit();
}

}  // namespace armsim::detail
