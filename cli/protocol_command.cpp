// armsim protocol: runs an experiment protocol file (assets/protocols/*.yaml); and the thesis MVC
// protocol as a main-job step.
#include "basics/errors.h"
#include "basics/files.h"
#include "basics/output_folder.h"
#include "basics/parallel.h"
#include "basics/table.h"
#include "cli/commands.h"
#include "cli/report.h"
#include "cli/plugins.h"
#include "experiments/protocol.h"
#include "experiments/protocol_files.h"
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

void runProtocolCommand(const ProtocolOptions& o) {
    if (o.video) checkVideoOptions(o);  // before the run: a missing renderer or a bad setting fails first
    ProtocolFileOptions run;
    run.outDir = o.out;
    run.jobs = o.jobs;
    std::string name;
    run.onStart = [&](const std::string& protocolName, const std::string& text) {
        name = protocolName;
        std::printf("%s", text.c_str());
        std::fflush(stdout);
    };
    run.progress = [&](int d, int n) { printProgress(name, d, n); };
    if (o.video)
        run.beforeCommit = [&](OutputFolder& dir, const ArmSetup& subject, const ProtocolResult& r) {
            renderProtocolVideos(o, subject, r, dir);
        };
    const ProtocolFileRun r = runProtocolFile(findAsset(o.file), run);
    if (!r.outDir.empty()) setReportFolder(r.outDir);   // --out, or out/NAME
    std::printf("%s", r.text.c_str());
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

/// Main job: the thesis MVC protocol (five angles x three repetitions, synthetic EMG), on the main
/// job's muscle.
void runMvcProtocol(const MainJobContext& ctx) {
    const Protocol protocol = readProtocol(findAsset("protocols/mvc_force_angle.yaml"));
    ArmSetup subject = loadProtocolSubject(protocol);
    subject.biceps() = ctx.muscle.loadParameters();
    const std::string out = ctx.outDir + "/protocol_mvc";
    const ProtocolResult r =
        runProtocol(protocol, subject, {out, ctx.jobs, [](int d, int n) { printProgress("MVC protocol trials", d, n); }});
    std::printf("%s", formatProtocolResult(protocol, r, out).c_str());
    std::printf("  plots: %s/force_angle.png, force_length.png, emg_trial.png\n", showPath(out).c_str());
}

const CommandRegistrar registerProtocol(30, addProtocolCommand);
const MainJobStepRegistrar registerMvcProtocol(35, "Protocol: thesis MVC force-angle (5 angles x 3 repetitions, EMG)",
                                               runMvcProtocol);

}  // namespace

}  // namespace armsim::cli
