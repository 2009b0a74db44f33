// armsim protocol: runs an experiment protocol file (assets/protocols/*.yaml); and the thesis MVC
// protocol as a main-job step.
#include "basics/errors.h"
#include "basics/files.h"
#include "basics/output_folder.h"
#include "basics/parallel.h"
#include "basics/table.h"
#include "cli/commands.h"
#include "experiments/channels.h"
#include "cli/plugins.h"
#include "experiments/protocol.h"
#include "experiments/torque_protocol.h"
#include "muscles/muscle_file.h"

#ifdef ARMSIM_WITH_RENDER
#include "render/render_plugin.h"
#endif

#include <cmath>
#include <filesystem>
#include <cstdio>
#include <memory>

namespace armsim::cli {

namespace {

struct ProtocolOptions {
    std::string file;
    std::string out;
    int jobs = 2;
    bool video = false;      ///< render every trial's video into <out>/videos/
    double videoFps = 30;
    int videoWidth = 1280, videoHeight = 720;
};

#ifdef ARMSIM_WITH_RENDER
TrialVideoSettings makeVideoSettings(const ProtocolOptions& o) {
    TrialVideoSettings v;
    v.fps = o.videoFps;
    v.render.width = o.videoWidth;
    v.render.height = o.videoHeight;
    return v;
}
#endif

/// The renderer loaded and the --video-* options checked, named as typed.
void checkVideoOptions(const ProtocolOptions& o) {
    const RenderPlugin& render = getRenderPlugin("--video");
#ifdef ARMSIM_WITH_RENDER
    runNamingOptions({{"fps", "--video-fps"}, {"width", "--video-width"}, {"height", "--video-height"}},
                     [&] { render.validate(makeVideoSettings(o)); });
#else
    (void)render;
#endif
}

/// Renders the video of every trial of a run (replaying trials/<id>.csv) into its videos/, before the
/// run is put in place: the run and its videos appear together.
void renderProtocolVideos(const ProtocolOptions& o, const ArmSetup& subject, const ProtocolResult& r, OutputFolder& dir) {
#ifdef ARMSIM_WITH_RENDER
    const int n = int(r.trialIds.size());
    if (n == 0) {
        std::printf("  --video: this protocol has no arm trials to render\n");
        return;
    }
    const RenderPlugin& render = getRenderPlugin("--video");
    std::vector<std::string> csv(n), video(n), name(n);
    for (int i = 0; i < n; ++i) {  // addFile records the names: on this thread, before the workers
        csv[i] = dir.addFile("trials/" + r.trialIds[i] + ".csv");
        video[i] = dir.addFile("videos/" + r.trialIds[i] + ".mp4");
        name[i] = dir.getTargetPath("trials/" + r.trialIds[i] + ".csv");
    }
    runParallel(
        n, o.jobs,
        [&](int i) {
            TrialVideoSettings v = makeVideoSettings(o);
            v.videoPath = video[i];
            v.tableName = name[i];
            render.renderTrialVideo(subject, Table::readCsv(csv[i]), v, {});
        },
        [](int d, int total) { printProgress("trial videos", d, total); });
    std::printf("  rendered %d videos into videos/\n", n);
#else
    (void)o, (void)subject, (void)r, (void)dir;
    throw InputError("--video: this armsim was built without the renderer (-DARMSIM_RENDER=OFF)");
#endif
}

void printFit(const char* label, const QuadraticFit& q, const char* xUnit, double xScale, const char* reference) {
    std::printf("  %-34s peak %7.1f N at %6.1f %s (R^2 %.4f)%s\n", label, q.peakY, xScale * q.peakX, xUnit,
                q.fit.rSquared, reference);
}

void printResult(const Protocol& p, const ProtocolResult& r, const std::string& outDir) {
    if (r.trials.getNumRows() > 0) {
        const Table& s = r.summary;
        std::printf("  angle  level   n  activation  muscle F (N)        measured F (N)     fixed ratio (N)%s\n",
                    p.emgEnabled ? "  EMG RMS (mV)      MNF (Hz)  MDF (Hz)" : "");
        for (int i = 0; i < s.getNumRows(); ++i) {
            std::printf("  %5.0f  %4.0f%%  %2.0f  %10.4f  %7.2f +- %-7.2f  %7.2f +- %-7.2f  %8.2f",
                        s.get(i, "elbow_angle_deg"), s.get(i, "level_pct_mvc"), s.get(i, "n"),
                        s.get(i, "activation_mean"), s.get(i, "muscle_force_N_mean"), s.get(i, "muscle_force_N_sd"),
                        s.get(i, "force_measured_N_mean"), s.get(i, "force_measured_N_sd"),
                        s.get(i, "force_fixed_ratio_N_mean"));
            if (p.emgEnabled)
                std::printf("  %6.3f +- %-6.3f  %8.1f  %8.1f", 1000 * s.get(i, "emg_rms_V_mean"),
                            1000 * s.get(i, "emg_rms_V_sd"), s.get(i, "emg_mnf_Hz_mean"), s.get(i, "emg_mdf_Hz_mean"));
            std::printf("\n");
        }
    }
    const auto fit = [&](const char* key) { return r.quadraticFits.find(key); };
    if (p.kind == ProtocolKind::Mvc) {
        std::printf("  quadratic force-angle fits (thesis: 603.3 N at 101.2 deg):\n");
        if (auto it = fit("muscle_force"); it != r.quadraticFits.end())
            printFit("true muscle force", it->second, "deg", 1, "");
        if (auto it = fit("force_measured"); it != r.quadraticFits.end())
            printFit("transducer / moment arm (tared)", it->second, "deg", 1, "");
        if (auto it = fit("force_fixed_ratio"); it != r.quadraticFits.end())
            printFit("thesis fixed-ratio estimate", it->second, "deg", 1, "");
    }
    if (r.emgToActivation) {
        const auto& c = r.emgToActivation->coefficients;
        std::printf("  EMG-to-activation map: U = %.4f %+.4f e %+.4f e^2 (e = EMG RMS / MVC EMG RMS; R^2 %.4f)\n", c[0],
                    c[1], c[2], r.emgToActivation->rSquared);
    }
    if (auto it = fit("muscle_alone_peak"); it != r.quadraticFits.end())
        printFit("force-length, muscle alone", it->second, "cm", 100, "  (thesis: ~600 N at 40-41 cm)");
    if (auto it = fit("arm_peak"); it != r.quadraticFits.end())
        printFit("force-length, in the arm", it->second, "cm", 100, "");
    if (r.composition.getNumRows() > 0) {
        for (int i = 0; i < r.composition.getNumRows(); ++i)
            if (r.composition.get(i, "slow_units") == 3 && r.composition.get(i, "fast_units") == 3)
                std::printf("  3 slow + 3 fast units: %.2f N (thesis Table 7.4: 346.13 N)\n",
                            r.composition.get(i, "force_N"));
        std::printf("  %d compositions; table in composition_matrix.csv, heat map composition_heatmap.png\n",
                    r.composition.getNumRows());
    }
    if (!outDir.empty()) std::printf("  wrote %zu files to %s/\n", r.files.size(), showPath(outDir).c_str());
}

std::string defaultOut(const Protocol& p) { return "out/" + p.name; }

/// A torque protocol (kind: torque, e.g. from `armsim design`): its trials on the subject it names,
/// tared torque per trial as a data file the identifiers read.
void runTorqueProtocolCommand(const ProtocolOptions& o, const std::string& file) {
    if (o.video) throw InputError("--video: torque protocols have no per-trial series to render; run `armsim trial`");
    const TorqueProtocol protocol = readTorqueProtocol(file);
    const std::string out = o.out.empty() ? "out/" + protocol.name : o.out;
    std::printf("protocol %s (torque): %s\n  %d trials: %s\n", protocol.name.c_str(), protocol.description.c_str(),
                protocol.getNumTrials(), describeConditions(protocol).c_str());
    std::fflush(stdout);
    const TorqueProtocolRun run = runTorqueProtocol(protocol, o.jobs);
    const std::vector<TorqueObservation>& data = run.data;
    std::printf("  subject: %s\n", run.subject.c_str());
    const bool twoAxis = protocol.readsForearmTorque();
    std::printf("  %-10s %6s %7s %6s %4s %12s%s\n", "effort", "angle", "forearm", "level", "rep", "torque (N m)",
                twoAxis ? "  forearm axis (N m, + = supination)" : "");
    for (const TorqueObservation& d : data) {
        std::printf("  %-10s %6.1f %7s %6.2f %4d %12.2f", getEffortName(d.effort), d.flexionDeg,
                    formatPosture(d.rotationDeg).c_str(), d.level, d.repetition, d.torque);
        if (twoAxis) std::printf("  %12.2f", d.forearmTorque);
        std::printf("\n");
    }
    const std::vector<ChannelObservation>& channels = run.channels;
    if (!channels.empty()) std::printf("  channels besides torque: %zu measurements (channel_data.csv)\n", channels.size());
    const std::vector<std::string> files = writeTorqueProtocolRun(out, protocol, data, channels);
    std::printf("wrote");
    for (const std::string& f : files) std::printf(" %s", f.c_str());
    std::printf("\n(identify with `armsim identify-torque %s/torque_data.csv%s`)\n", out.c_str(),
                channels.empty() ? "" : (" --channels " + out + "/channel_data.csv").c_str());
}

void runProtocolCommand(const ProtocolOptions& o) {
    if (o.video) checkVideoOptions(o);  // before the run: a missing renderer or a bad setting fails first
    const std::string file = findAsset(o.file);
    if (isTorqueProtocolFile(file)) return runTorqueProtocolCommand(o, file);
    const Protocol protocol = readProtocol(file);
    const ArmSetup subject = loadProtocolSubject(protocol);
    const std::string out = o.out.empty() ? defaultOut(protocol) : o.out;
    std::printf("protocol %s (%s): %s\n", protocol.name.c_str(), getProtocolKindName(protocol.kind).c_str(),
                protocol.description.c_str());
    std::fflush(stdout);
    ProtocolRunOptions run{out, o.jobs, [&](int d, int n) { printProgress(protocol.name, d, n); }, {}};
    if (o.video) run.beforeCommit = [&](OutputFolder& dir, const ProtocolResult& r) { renderProtocolVideos(o, subject, r, dir); };
    const ProtocolResult r = runProtocol(protocol, subject, run);
    printResult(protocol, r, out);
}

void addProtocolCommand(CLI::App& app) {
    auto o = std::make_shared<ProtocolOptions>();
    CLI::App* c = app.add_subcommand("protocol", "run an experiment protocol (YAML file, e.g. protocols/mvc_force_angle.yaml)");
    c->add_option("file", o->file, "protocol file (path, or name under assets/)")->required();
    c->add_option("--out", o->out, "run directory (default out/<protocol name>); an earlier run there is replaced");
    c->add_option("--jobs", o->jobs, "worker threads (results do not depend on it)")->capture_default_str()->transform(inRange(1, 64));
    c->add_flag("--video", o->video, "also render every trial's video (H.264) into <out>/videos/");
    c->add_option("--video-fps", o->videoFps, "video frame rate [1/s]")->capture_default_str()->needs("--video");
    c->add_option("--video-width", o->videoWidth, "video width [px]")->capture_default_str()->needs("--video");
    c->add_option("--video-height", o->videoHeight, "video height [px]")->capture_default_str()->needs("--video");
    c->callback([o] { runProtocolCommand(*o); });
}

/// Main job: the thesis MVC protocol (five angles x three repetitions, synthetic EMG).
void runMvcProtocol(const MainJobContext& ctx) {
    const Protocol protocol = readProtocol(findAsset("protocols/mvc_force_angle.yaml"));
    ArmSetup subject = loadProtocolSubject(protocol);
    subject.biceps() = ctx.muscle.loadParameters();
    const std::string out = ctx.outDir + "/protocol_mvc";
    const ProtocolResult r =
        runProtocol(protocol, subject, {out, ctx.jobs, [](int d, int n) { printProgress("MVC protocol trials", d, n); }});
    printResult(protocol, r, out);
    std::printf("  plots: %s/force_angle.png, force_length.png, emg_trial.png\n", showPath(out).c_str());
}

const CommandRegistrar registerProtocol(30, addProtocolCommand);
const MainJobStepRegistrar registerMvcProtocol(35, "Protocol: thesis MVC force-angle (5 angles x 3 repetitions, EMG)",
                                               runMvcProtocol);

}  // namespace

}  // namespace armsim::cli
