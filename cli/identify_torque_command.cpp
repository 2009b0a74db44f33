// armsim identify-torque: the biceps long head's mass and tendon length from tared elbow torque data
// (a torque data file: measured, or written by `armsim protocol` for a torque protocol) and the lab's
// other channels (--channels: ultrasound, EMG, anthropometry) with every elbow method (thesis,
// synergist, synergist-va, channels), with residuals checked against the measurement noise per channel.
#include "basics/output_folder.h"
#include "basics/plot.h"
#include "cli/commands.h"
#include "experiments/channels.h"
#include "identification/torque_identification.h"
#include "muscles/muscle_file.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>

namespace armsim::cli {

namespace {

struct IdentifyTorqueOptions {
    std::string data;
    std::string population;
    double noiseLevel = NAN;     // relative sd of one trial's torque; NaN: from repetitions
    double activation = NAN;     // measured voluntary activation (twitch interpolation); NaN: not measured
    double activationSd = 0.02;
    std::string channels;        // channel CSV; empty: torque only
    double emgCrosstalk = 0.10;
    bool freeSlowFraction = false;
    std::string out = "out/identify_torque";
};

/// Where the judging noise level comes from, for a person.
std::string describeNoiseSource(const IdentifyTorqueOptions& o, const std::vector<MuscleEstimate>& estimates) {
    const int dof = estimates.empty() ? 0 : estimates.back().noiseDegreesOfFreedom;
    if (std::isfinite(o.noiseLevel)) return "--noise-level";
    const bool floored = !estimates.empty() && estimates.back().noiseLevel == kMinTorqueNoiseLevel;
    const std::string floor = floored ? fmt::format("; raised to the floor of {:g} %{}", 100 * kMinTorqueNoiseLevel,
                                                    dof > 0 ? ": the repetitions scatter less" : "") : "";
    if (dof > 0) return "estimated from the repetitions, " + std::to_string(dof) + " degrees of freedom" + floor;
    return "the prior population's transducer noise: no condition is repeated to estimate it from" + floor;
}

void runIdentifyTorque(const IdentifyTorqueOptions& o) {
    checkOutputFolder("--out", o.out);
    const std::string file = findAsset(o.data);
    const std::vector<TorqueObservation> data = readTorqueData(file);
    const Population prior = o.population.empty() ? loadDefaultPopulation() : loadPopulation(findAssetFor("--population", o.population));
    std::printf("torque data %s: %zu trials; prior population '%s' (model '%s')\n", file.c_str(), data.size(),
                prior.name.c_str(), prior.base.name.c_str());
    TorqueIdentificationOptions to;
    to.noiseLevel = o.noiseLevel;
    to.activation = o.activation;
    to.activationSd = o.activationSd;
    to.freeSlowFraction = o.freeSlowFraction;
    to.emgCrosstalk = o.emgCrosstalk;
    if (!o.channels.empty()) {
        to.channels = readChannelData(findAssetFor("--channels", o.channels));
        std::printf("channel data %s: %zu measurements\n", findAssetFor("--channels", o.channels).c_str(), to.channels.size());
    }
    std::string skipped;
    const std::vector<MuscleEstimate> estimates = identifyTorqueData(prior, data, to, &skipped);
    if (!skipped.empty()) std::printf("%s\n", skipped.c_str());
    const double noise = findJudgingNoiseLevel(to, estimates);
    const MuscleParameters& b = prior.base.biceps();
    std::printf("prior (population base) %s: M %.1f g, L0T %.1f cm; residuals judged against a relative torque sd of "
                "%.1f %% (%s)\n",
                b.name.c_str(), 1000 * b.mass, 100 * b.optimalTendonLength, 100 * noise,
                describeNoiseSource(o, estimates).c_str());
    std::printf("%-13s %9s %21s %9s %21s %10s %12s %6s %8s\n", "method", "M (g)", "95 % interval", "L0T (cm)",
                "95 % interval", "rms (N m)", "chi2 / dof", "p", "verdict");
    for (const MuscleEstimate& e : estimates) {
        const TorqueResidualCheck c = checkTorqueResiduals(data, e, noise);
        if (!std::isfinite(e.mass) || c.n == 0) {
            std::printf("%-13s no estimate: %s\n", e.method.c_str(), e.message.c_str());
            continue;
        }
        std::printf("%-13s %9.1f   [%7.1f, %7.1f] %9.2f   [%7.2f, %7.2f] %10.2f %6.1f / %-4d %6.3f %8s%s\n",
                    e.method.c_str(), 1000 * e.mass, 1000 * e.massLower, 1000 * e.massUpper, 100 * e.tendonLength,
                    100 * e.tendonLower, 100 * e.tendonUpper, c.rms, c.chiSquare, c.dof, c.p,
                    c.p >= 0.05 ? "noise" : "misfit", e.converged ? "" : "  (not converged)");
    }
    std::printf("verdict: 'noise' = residuals consistent with the measurement noise (chi-square p >= 0.05), "
                "'misfit' = larger than the noise explains\n");
    for (const MuscleEstimate& e : estimates) {
        const auto besidesTorque = std::count_if(e.channelFits.begin(), e.channelFits.end(),
                                                 [](const ChannelFit& f) { return f.channel != "prior"; });
        if (besidesTorque < 2) {  // torque alone: the table above, and the prior's check in a line
            for (const ChannelFit& f : e.channelFits)
                if (f.channel == "prior")
                    std::printf("%s: prior check chi2 %.1f / %d, p %.3f: %s\n", e.method.c_str(), f.chiSquare, f.n, f.p,
                                f.p >= 0.05 ? "a person the prior's population holds"
                                            : ("outside the prior's population, furthest: " + f.worst).c_str());
            continue;
        }
        if (e.method == "channels")
            std::printf("channels fit: F0 %.0f N [%.0f, %.0f] at specific tension %.1f N/cm^2\n", e.maxForce,
                        e.maxForceLower, e.maxForceUpper, 1e-4 * e.specificTension);
        else
            std::printf("%s fit, each channel:\n", e.method.c_str());
        std::printf("%-17s %4s %10s %7s %8s   %s\n", "channel", "n", "chi2", "p", "verdict", "largest residual (sd): where");
        for (const ChannelFit& f : e.channelFits)
            std::printf("%-17s %4d %10.1f %7.3f %8s   %+.1f: %s\n", f.channel.c_str(), f.n, f.chiSquare, f.p,
                        f.channel == "prior" ? (f.p >= 0.05 ? "holds" : "conflict") : (f.p >= 0.05 ? "noise" : "misfit"),
                        f.worstResidual, f.worst.c_str());
    }
    std::printf("%-10s %6s %7s %6s %4s %11s", "effort", "angle", "forearm", "level", "rep", "measured");
    for (const MuscleEstimate& e : estimates) std::printf(" %13s", e.method.c_str());
    std::printf("   (predicted torque, N m)\n");
    for (std::size_t k = 0; k < data.size(); ++k) {
        const TorqueObservation& d = data[k];
        std::printf("%-10s %6.1f %7s %6.2f %4d %11.2f", getEffortName(d.effort), d.flexionDeg, formatPosture(d.rotationDeg).c_str(),
                    d.level, d.repetition, d.torque);
        for (const MuscleEstimate& e : estimates) {
            if (std::isfinite(e.predictedTorque[k])) std::printf(" %13.2f", e.predictedTorque[k]);
            else std::printf(" %13s", "-");  // not fitted (the thesis method's other efforts, a rotation effort)
        }
        std::printf("\n");
    }
    OutputFolder out(o.out, OutputFolder::Mode::AddFiles);
    out.write("torque_estimates.csv", formatTorqueEstimatesCsv(data, estimates, noise));
    out.write("torque_predictions.csv", formatTorquePredictionsCsv(data, estimates));
    out.write("channel_fits.csv", formatChannelFitsCsv(estimates));
    PlotSpec plot;
    plot.title = "Torque data and each method's fit";
    plot.xLabel = "elbow flexion (deg, 0 = extended)";
    plot.yLabel = "tared torque (N m, + = flexion)";
    PlotSeries measured{"measured", {}, {}, true, 7};
    for (const TorqueObservation& d : data)  // the flexion axis of flexion and extension efforts (what is fitted)
        if (!isForearmEffort(d.effort)) measured.x.push_back(d.flexionDeg), measured.y.push_back(d.torque);
    plot.series.push_back(measured);
    for (std::size_t m = 0; m < estimates.size(); ++m) {
        PlotSeries s{estimates[m].method, {}, {}, true, int(m)};
        for (std::size_t k = 0; k < data.size(); ++k)
            if (std::isfinite(estimates[m].predictedTorque[k]))
                s.x.push_back(data[k].flexionDeg), s.y.push_back(estimates[m].predictedTorque[k]);
        plot.series.push_back(s);
    }
    out.writeWith("torque_fit.png", [&](const std::string& p) { writePlotPng(p, plot); });
    out.commit();
    std::printf("wrote %s/torque_estimates.csv, torque_predictions.csv, channel_fits.csv, torque_fit.png\n", o.out.c_str());
}

void addIdentifyTorqueCommand(CLI::App& app) {
    auto o = std::make_shared<IdentifyTorqueOptions>();
    CLI::App* c = app.add_subcommand("identify-torque",
                                     "biceps mass and tendon length from tared elbow torque data with the thesis, "
                                     "synergist and (with --activation) synergist-va methods");
    c->add_option("data", o->data,
                  "torque CSV: flexion_deg, torque_Nm [, effort, level, repetition, rotation_deg, forearm_torque_Nm]")
        ->required();
    c->add_option("--population", o->population, "prior population (default assets/subjects/default_population.yaml)");
    c->add_option("--noise-level", o->noiseLevel,
                  "relative sd of one trial's torque (default: estimated from repeated trials)")
        ->transform(inRange(kMinTorqueNoiseLevel, 0.5));
    c->add_option("--activation", o->activation, "measured voluntary activation (twitch interpolation): adds synergist-va")
        ->check(CLI::Validator(
            [](std::string& text) {
                // 0 is no voluntary drive at all: not a measurement of a maximal effort.
                const double v = std::strtod(text.c_str(), nullptr);
                return v > 0 && v <= 1 ? std::string()
                                       : "voluntary activation " + text + ": expected in (0, 1] (a fraction of full drive)";
            },
            "(0, 1]"));
    c->add_option("--activation-sd", o->activationSd, "sd of that measurement")->capture_default_str()->transform(inRange(1e-4, 0.5))
        ->needs("--activation");
    c->add_option("--channels", o->channels,
                  "channel CSV (docs/channels.md: ultrasound fascicle length and volume, EMG, upper-arm length): adds "
                  "the channels fit");
    c->add_option("--emg-crosstalk", o->emgCrosstalk, "crosstalk c of the EMG measurement model")
        ->capture_default_str()->transform(inRange(0.0, 0.5))
        ->needs("--channels");
    c->add_flag("--free-slow-fraction", o->freeSlowFraction, "the synergist fits free the flexors' slow-fibre fractions");
    c->add_option("--out", o->out, "output directory")->capture_default_str();
    c->callback([o] { runIdentifyTorque(*o); });
}

const CommandRegistrar registerIdentifyTorque(56, addIdentifyTorqueCommand);

}  // namespace

}  // namespace armsim::cli
