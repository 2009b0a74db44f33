// The protocol file kinds' table and what each row runs (experiments/protocol_files.h).
#include "experiments/protocol_files.h"

#include "basics/errors.h"
#include "basics/files.h"
#include "basics/output_folder.h"
#include "basics/param_node.h"
#include "experiments/protocol_run.h"

#include <fmt/printf.h>
#include <nlohmann/json.hpp>

#include <cmath>

namespace armsim {

namespace {

/// printf-style formatting (fmt's) appended to text.
template <class... Args>
void appendf(std::string& text, const char* format, const Args&... args) {
    text += fmt::sprintf(format, args...);
}

/// The run folder: none when computing only, else the one asked for, else out/<protocol name>.
std::string findRunFolder(const ProtocolFileOptions& o, const std::string& name) {
    return !o.write ? std::string() : o.outDir.empty() ? "out/" + name : o.outDir;
}

void appendFit(std::string& text, const char* label, const QuadraticFit& q, const char* xUnit, double xScale,
               const char* reference) {
    if (std::isnan(q.peakX))
        appendf(text, "  %-34s no peak: %s (R^2 %.4f)%s\n", label,
                !q.hasMaximum ? "the fit curves up" : "three angles or paths fix any quadratic, or the vertex lies outside them",
                q.fit.rSquared, reference);
    else
        appendf(text, "  %-34s peak %7.1f N at %6.1f %s (R^2 %.4f)%s\n", label, q.peakY, xScale * q.peakX, xUnit,
                q.fit.rSquared, reference);
}

void appendSummaryTable(std::string& text, const Protocol& p, const ProtocolResult& r) {
    const Table& s = r.summary;
    appendf(text, "  angle  level   n  activation  muscle F (N)        measured F (N)     fixed ratio (N)%s\n",
            p.emgEnabled ? "  EMG RMS (mV)      MNF (Hz)  MDF (Hz)" : "");
    for (int i = 0; i < s.getNumRows(); ++i) {
        appendf(text, "  %5.0f  %4.0f%%  %2.0f  %10.4f  %7.2f +- %-7.2f  %7.2f +- %-7.2f  %8.2f",
                s.get(i, "elbow_angle_deg"), s.get(i, "level_pct_mvc"), s.get(i, "n"), s.get(i, "activation_mean"),
                s.get(i, "muscle_force_N_mean"), s.get(i, "muscle_force_N_sd"), s.get(i, "force_measured_N_mean"),
                s.get(i, "force_measured_N_sd"), s.get(i, "force_fixed_ratio_N_mean"));
        if (p.emgEnabled)
            appendf(text, "  %6.3f +- %-6.3f  %8.1f  %8.1f", 1000 * s.get(i, "emg_rms_V_mean"),
                    1000 * s.get(i, "emg_rms_V_sd"), s.get(i, "emg_mnf_Hz_mean"), s.get(i, "emg_mdf_Hz_mean"));
        text += "\n";
    }
}

void appendFits(std::string& text, const Protocol& p, const ProtocolResult& r) {
    const auto fit = [&](const char* key) { return r.quadraticFits.find(key); };
    if (p.kind == ProtocolKind::Mvc) {
        text += "  quadratic force-angle fits (thesis: 603.3 N at 101.2 deg):\n";
        if (auto it = fit("muscle_force"); it != r.quadraticFits.end())
            appendFit(text, "true muscle force", it->second, "deg", 1, "");
        if (auto it = fit("force_measured"); it != r.quadraticFits.end())
            appendFit(text, "transducer / moment arm (tared)", it->second, "deg", 1, "");
        if (auto it = fit("force_fixed_ratio"); it != r.quadraticFits.end())
            appendFit(text, "thesis fixed-ratio estimate", it->second, "deg", 1, "");
    }
    if (r.emgToActivation) {
        const auto& c = r.emgToActivation->coefficients;
        appendf(text, "  EMG-to-activation map: U = %.4f %+.4f e %+.4f e^2 (e = EMG RMS / MVC EMG RMS; R^2 %.4f)\n",
                c[0], c[1], c[2], r.emgToActivation->rSquared);
    }
    if (auto it = fit("muscle_alone_peak"); it != r.quadraticFits.end())
        appendFit(text, "force-length, muscle alone", it->second, "cm", 100, "  (thesis: ~600 N at 40-41 cm)");
    if (auto it = fit("arm_peak"); it != r.quadraticFits.end())
        appendFit(text, "force-length, in the arm", it->second, "cm", 100, "");
}

void appendComposition(std::string& text, const ProtocolResult& r) {
    if (r.composition.getNumRows() == 0) return;
    for (int i = 0; i < r.composition.getNumRows(); ++i)
        if (r.composition.get(i, "slow_units") == 3 && r.composition.get(i, "fast_units") == 3)
            appendf(text, "  3 slow + 3 fast units: %.2f N (thesis Table 7.4: 346.13 N)\n", r.composition.get(i, "force_N"));
    appendf(text, "  %d compositions; table in composition_matrix.csv, heat map composition_heatmap.png\n",
            r.composition.getNumRows());
}

/// The arm kinds' row: readProtocol, its subject, runProtocol.
ProtocolFileRun runArmProtocolFile(const std::string& path, const ProtocolFileOptions& o) {
    ProtocolFileRun run;
    const Protocol protocol = readProtocol(path);
    const ArmSetup subject = loadProtocolSubject(protocol);
    run.kind = getProtocolKindName(protocol.kind);
    run.name = protocol.name;
    run.outDir = findRunFolder(o, protocol.name);
    if (o.onStart) o.onStart(protocol.name, "protocol " + protocol.name + " (" + run.kind + "): " + protocol.description + "\n");
    ProtocolRunOptions options{run.outDir, o.jobs, o.progress, {}};
    if (o.beforeCommit)
        options.beforeCommit = [&](OutputFolder& dir, const ProtocolResult& r) { o.beforeCommit(dir, subject, r); };
    ProtocolResult r = runProtocol(protocol, subject, options);
    run.text = formatProtocolResult(protocol, r, run.outDir);
    run.files = r.files;
    run.armProtocol = protocol;
    run.armResult = std::move(r);   // the trial table can be large: not copied
    return run;
}

std::string formatTorqueTable(const TorqueProtocol& protocol, const TorqueProtocolRun& r) {
    std::string text;
    appendf(text, "  subject: %s\n", r.subject.c_str());
    const bool twoAxis = protocol.readsForearmTorque();
    appendf(text, "  %-10s %6s %7s %6s %4s %12s%s\n", "effort", "angle", "forearm", "level", "rep", "torque (N m)",
            twoAxis ? "  forearm axis (N m, + = supination)" : "");
    for (const TorqueObservation& d : r.data) {
        appendf(text, "  %-10s %6.1f %7s %6.2f %4d %12.2f", getEffortName(d.effort), d.flexionDeg,
                formatPosture(d.rotationDeg).c_str(), d.level, d.repetition, d.torque);
        if (twoAxis) appendf(text, "  %12.2f", d.forearmTorque);
        text += "\n";
    }
    if (!r.channels.empty())
        appendf(text, "  channels besides torque: %zu measurements (channel_data.csv)\n", r.channels.size());
    return text;
}

/// The torque kind's row: readTorqueProtocol, runTorqueProtocol, writeTorqueProtocolRun.
ProtocolFileRun runTorqueProtocolFile(const std::string& path, const ProtocolFileOptions& o) {
    if (o.beforeCommit)
        throw InputError("--video: torque protocols have no per-trial series to render; run `armsim trial`");
    ProtocolFileRun run;
    const TorqueProtocol protocol = readTorqueProtocol(path);
    run.kind = "torque";
    run.name = protocol.name;
    run.outDir = findRunFolder(o, protocol.name);
    // The run folder as an arm protocol's: checked before the work, replaced whole (an earlier run's
    // channel_data.csv no longer stays beside a run that has none), its files all there or none.
    OutputFolder dir(run.outDir, OutputFolder::Mode::ReplaceRun, "manifest.json");
    if (o.onStart)
        o.onStart(protocol.name, "protocol " + protocol.name + " (torque): " + protocol.description + "\n  " +
                  std::to_string(protocol.getNumTrials()) + " trials: " + describeConditions(protocol) + "\n");
    const TorqueProtocolRun r = runTorqueProtocol(protocol, o.jobs, o.progress);
    run.text = formatTorqueTable(protocol, r);
    if (dir.isEnabled()) {
        const std::string staging = dir.getStagingPath();
        for (const std::string& staged : writeTorqueProtocolRun(staging, protocol, r.data, r.channels))
            run.files.push_back(dir.getTargetPath(staged.substr(staging.size() + 1)));
        nlohmann::ordered_json manifest;
        manifest["armsim_version"] = ARMSIM_VERSION;
        manifest["protocol"] = protocol.name;
        manifest["kind"] = "torque";
        manifest["trials"] = r.data.size();
        manifest["channel_measurements"] = r.channels.size();
        dir.write("manifest.json", manifest.dump(2) + "\n");
        dir.addStagedFiles();   // writeTorqueProtocolRun's files
        dir.commit();
        run.text += "wrote";
        for (const std::string& f : run.files) run.text += " " + f;
        run.text += "\n(identify with `armsim identify-torque " + run.outDir + "/torque_data.csv" +
                    (r.channels.empty() ? "" : " --channels " + run.outDir + "/channel_data.csv") + "`)\n";
    }
    run.torqueProtocol = protocol;
    run.torqueRun = r;
    return run;
}

}  // namespace

std::string formatProtocolResult(const Protocol& protocol, const ProtocolResult& r, const std::string& outDir) {
    std::string text;
    if (r.trials.getNumRows() > 0) appendSummaryTable(text, protocol, r);
    appendFits(text, protocol, r);
    appendComposition(text, r);
    if (!outDir.empty()) appendf(text, "  wrote %zu files to %s/\n", r.files.size(), showPath(outDir).c_str());
    return text;
}

const std::vector<ProtocolFileKind>& getProtocolFileKinds() {
    static const std::vector<ProtocolFileKind> kinds = [] {
        std::vector<ProtocolFileKind> k;
        for (const detail::ProtocolKindSpec& arm : detail::getProtocolKindSpecs()) k.push_back({arm.name, runArmProtocolFile});
        k.push_back({"torque", runTorqueProtocolFile});
        return k;
    }();
    return kinds;
}

ProtocolFileRun runProtocolFile(const std::string& path, const ProtocolFileOptions& options) {
    const ParamNode root = ParamNode::loadFile(path);
    std::vector<std::string> names;
    for (const ProtocolFileKind& k : getProtocolFileKinds()) names.push_back(k.name);
    root.getString("kind");   // required
    const std::string kind = root.getChoice("kind", names, "");
    for (const ProtocolFileKind& k : getProtocolFileKinds())
        if (kind == k.name) return k.run(path, options);
    throw std::logic_error("protocol kind '" + kind + "' has no row in getProtocolFileKinds");
}

}  // namespace armsim
