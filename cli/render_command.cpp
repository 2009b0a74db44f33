// armsim render: a video and/or PNG still of a recorded trial (replayed from its table); and the
// main-job step that leaves an MVC video, a free-movement video and a still in the output directory.
#include "basics/files.h"
#include "basics/format.h"
#include "basics/output_folder.h"
#include "basics/param_node.h"
#include "cli/commands.h"
#include "cli/plugins.h"
#include "model/geometry.h"
#include "model/osim_forward.h"
#include "model/trial.h"
#include "muscles/muscle_file.h"

#ifdef ARMSIM_WITH_RENDER
#include "render/render_plugin.h"

#include <malloc.h>

#include <cstdio>
#include <future>
#include <map>
#include <memory>
#include <set>
#endif

namespace armsim::cli {

namespace {

#ifdef ARMSIM_WITH_RENDER

struct RenderOptions {
    MuscleOptions muscle;
    std::string table, out, still, renderSettingsFile;
    double stillAt = 0, fps = 30, speed = 1, load = 0, arrowScale = 0;
    int width = 1280, height = 720, supersample = 2;
    std::string codec = "h264", colorBy = "activation", arrow = "auto";
    bool noOverlay = false, noFloor = false, fixedThickness = false;
    CLI::Option* stillAtOption = nullptr;
    CLI::Option* widthOption = nullptr;
    CLI::Option* heightOption = nullptr;
    CLI::Option* supersampleOption = nullptr;
    CLI::Option* loadOption = nullptr;
};

// armsim render of an OpenSim model's trial table (--model FILE.osim): render/osim_video.h. The arm
// scene's options (hand load, arrow, floor, colouring) do not apply and are refused by the caller.
void runOsimRenderCommand(const RenderOptions& o) {
    OsimVideoSettings v;
    v.render.width = o.width;
    v.render.height = o.height;
    v.render.supersample = o.supersample;
    v.fps = o.fps;
    v.codec = o.codec;
    v.playbackSpeed = o.speed;
    v.overlay = !o.noOverlay;
    if (o.stillAtOption->count()) v.stillTime = o.stillAt;
    v.tableName = o.table;
    v.muscleModel = o.muscle.muscleModel;
    if (o.out.empty() && !v.stillTime)
        throw InputError("armsim render: nothing to write: expected --out VIDEO and/or --still-at T --still FILE.png");
    v.videoPath = o.out;
    v.stillPath = o.still;
    runNamingOptions({{"fps", "--fps"}, {"codec", "--codec"}, {"playback_speed", "--speed"}, {"still_at", "--still-at"},
                      {"still", "--still"}, {"width", "--width"}, {"height", "--height"}, {"supersample", "--supersample"}},
                     [&] { getRenderPlugin("render").validateOsim(v); });   // before the table is read
    OutputFiles files;
    const std::string osim = findOsimModelFile(o.muscle.model);
    files.addInput("--model", osim);
    files.addInput("the trial-table argument", o.table);
    v.videoPath = files.add("--out", o.out);
    v.stillPath = files.add("--still", o.still);
    const OsimModel model = readOsimFile(osim);
    const Table table = Table::readCsv(o.table);
    OsimVideoResult r;
    files.writeWith(v.videoPath.empty() ? v.stillPath : v.videoPath, [&](const std::string&) {
        runNamingOptions({{"still_at", "--still-at"}, {"playback_speed", "--speed"}, {"fps", "--fps"}}, [&] {
            r = getRenderPlugin("render").renderOsimTrialVideo(model, table, v,
                                                               [](int d, int n) { printProgress("rendering", d, n); });
        });
    });
    files.commit();
    if (!r.stillPath.empty()) std::printf("wrote %s (still at t = %.3f s)\n", o.still.c_str(), *v.stillTime);
    if (!r.videoPath.empty())
        std::printf("wrote %s (%d frames, %dx%d, %g fps, %s)\n", o.out.c_str(), r.frames, v.render.width, v.render.height,
                    v.fps, v.codec.c_str());
}

void runRenderCommand(const RenderOptions& o) {
    TrialVideoSettings v;
    std::set<std::string> fromFile;   // width, height, supersample as the settings file gives them
    if (!o.renderSettingsFile.empty()) {
        const ParamNode node = ParamNode::loadFile(o.renderSettingsFile);
        v.autoCamera = !node.has("camera");
        v.render = getRenderPlugin("--render-settings").readRenderSettings(node);
        const std::pair<const char*, const CLI::Option*> both[] = {
            {"width", o.widthOption}, {"height", o.heightOption}, {"supersample", o.supersampleOption}};
        for (const auto& [key, option] : both) {
            if (!node.has(key)) continue;
            if (option->count())
                throw InputError(option->get_name() + " and " + node.where(key) + " (" + key + ": in --render-settings) "
                                 "both set the frame's " + key + ": expected one of them");
            fromFile.insert(key);
        }
    }
    if (!fromFile.count("width")) v.render.width = o.width;
    if (!fromFile.count("height")) v.render.height = o.height;
    if (!fromFile.count("supersample")) v.render.supersample = o.supersample;
    v.fps = o.fps;
    v.codec = o.codec;
    v.playbackSpeed = o.speed;
    v.overlay = !o.noOverlay;
    v.scene.muscleColoring = o.colorBy == "force" ? MuscleColoring::Force : MuscleColoring::Activation;
    v.scene.thicknessFollows = !o.fixedThickness;
    v.scene.forceArrow = o.arrow == "strap"    ? ForceArrowKind::Strap
                         : o.arrow == "muscle" ? ForceArrowKind::Muscle
                         : o.arrow == "none"   ? ForceArrowKind::None
                                               : ForceArrowKind::Auto;
    v.scene.arrowScale = o.arrowScale;
    v.scene.floor = !o.noFloor;
    const ArmSetup setup = o.muscle.loadSetup();
    v.scene.handLoad = o.loadOption->count() ? o.load : setup.arm.handLoad;   // as the trial held it
    if (o.stillAtOption->count()) v.stillTime = o.stillAt;
    v.tableName = o.table;
    if (o.out.empty() && !v.stillTime)
        throw InputError("armsim render: nothing to write: expected --out VIDEO and/or --still-at T --still FILE.png");
    v.videoPath = o.out;  // validated as typed, then staged
    v.stillPath = o.still;
    // Settings from options named as typed (width, height and supersample come from --render-settings
    // when it is given).
    std::map<std::string, std::string> options = {
        {"hand_load", "--load"}, {"fps", "--fps"}, {"codec", "--codec"}, {"playback_speed", "--speed"},
        {"arrow_scale", "--arrow-scale"}, {"still_at", "--still-at"}, {"still", "--still"}};
    for (const char* key : {"width", "height", "supersample"})
        if (!fromFile.count(key)) options.insert({key, std::string("--") + key});
    runNamingOptions(options, [&] { getRenderPlugin("render").validate(v); });  // before the table is read
    OutputFiles files;  // the video and the still appear together at the end, or neither
    o.muscle.declareInputs(files);
    files.addInput("the trial-table argument", o.table);
    v.videoPath = files.add("--out", o.out);
    v.stillPath = files.add("--still", o.still);

    const Table table = Table::readCsv(o.table);
    if (o.loadOption->count() && table.hasColumn("strap_force_N"))   // as armsim trial refuses it
        throw InputError("--load = " + formatNumber(o.load) + " kg: " + o.table + " is an isometric trial (it has "
                         "strap_force_N), which holds the arm file's hand_load (" + formatNumber(setup.arm.handLoad) +
                         " kg); --load is a free trial's option");
    TrialVideoResult r;
    files.writeWith(v.videoPath.empty() ? v.stillPath : v.videoPath, [&](const std::string&) {
        runNamingOptions(options, [&] {   // settings checked against the table (its duration, its times)
            r = getRenderPlugin("render").renderTrialVideo(setup, table, v,
                                                           [](int d, int n) { printProgress("rendering", d, n); });
        });
    });
    files.commit();
    if (!r.stillPath.empty()) std::printf("wrote %s (still at t = %.3f s)\n", o.still.c_str(), *v.stillTime);
    if (!r.videoPath.empty())
        std::printf("wrote %s (%d frames, %dx%d, %g fps, %s)\n", o.out.c_str(), r.frames, v.render.width,
                    v.render.height, v.fps, v.codec.c_str());
}

// Options that would be ignored, or a still half given, are refused naming them (before "nothing to write").
void refuseUnusedRenderOptions(const CLI::App& c, const RenderOptions& o) {
    if (c.count("--out") > 0 && o.out.empty())
        throw InputError("--out is empty: expected a video file (.mp4 or .avi), or no --out for a still alone");
    if (c.count("--still") > 0 && o.still.empty()) throw InputError("--still is empty: expected a .png file");
    if (c.count("--still") > 0 && c.count("--still-at") == 0)
        throw InputError("--still '" + o.still + "' needs --still-at T: the trial time of the still [s]");
    if (c.count("--still-at") > 0 && c.count("--still") == 0)
        throw InputError("--still-at " + formatNumber(o.stillAt) + " needs --still FILE.png: the file of the still");
    if (o.out.empty())
        for (const char* name : {"--fps", "--codec", "--speed"})
            if (c.count(name) > 0)
                throw InputError(std::string(name) + " is a video's option: without --out VIDEO it would be ignored (a "
                                 "still takes --still-at, --still, --width, --height, --supersample)");
    if (c.count("--arrow-scale") > 0 && o.arrow == "none")
        throw InputError("--arrow-scale with --arrow none: there is no arrow to scale");
}

void addRenderCommand(CLI::App& app) {
    auto o = std::make_shared<RenderOptions>();
    CLI::App* c = app.add_subcommand("render", "video and/or PNG still of a recorded trial table (armsim trial CSV)");
    c->add_option("table", o->table, "trial table written by armsim trial (CSV with state_* columns; an OpenSim "
                                     "model's: with --model FILE.osim)")
        ->required()->check(CLI::ExistingFile);
    c->add_option("--out", o->out, "video file: .mp4 (h264) or .avi (mjpg)");
    c->add_option("--fps", o->fps, "video frames per second")->capture_default_str();
    o->widthOption = c->add_option("--width", o->width, "frame width [px], even")->capture_default_str();
    o->heightOption = c->add_option("--height", o->height, "frame height [px], even")->capture_default_str();
    c->add_option("--codec", o->codec, "h264 | mjpg")->capture_default_str();
    c->add_option("--speed", o->speed, "trial seconds per video second (1 = the trial's time scale)")
        ->capture_default_str();
    o->supersampleOption = c->add_option("--supersample", o->supersample, "anti-aliasing factor 1-4 (1 = off)")->capture_default_str();
    c->add_option("--render-settings", o->renderSettingsFile,
                  "YAML render settings (width, height, supersample, background, lighting, camera {...}); "
                  "without a camera key the sagittal camera is used");
    o->stillAtOption = c->add_option("--still-at", o->stillAt, "trial time of a PNG still [s]");
    c->add_option("--still", o->still, "PNG file of the still");
    c->add_option("--color-by", o->colorBy, "muscle colour follows: activation | force")
        ->capture_default_str()->check(CLI::IsMember({"activation", "force"}));
    c->add_flag("--fixed-thickness", o->fixedThickness, "muscle line thickness does not follow the colour");
    c->add_option("--arrow", o->arrow, "force arrow: auto (strap if isometric, else muscle) | strap | muscle | none")
        ->capture_default_str()->check(CLI::IsMember({"auto", "strap", "muscle", "none"}));
    c->add_option("--arrow-scale", o->arrowScale,
                  "arrow length per newton [m/N] (0: a round scale, the peak force within 15 cm)")
        ->capture_default_str();
    o->loadOption = c->add_option("--load", o->load, "mass held in the hand [kg], drawn as a ball (as given to armsim "
                                                     "trial; default: the arm file's hand_load)");
    c->add_flag("--no-floor", o->noFloor, "no floor (with 10 cm ticks)");
    c->add_flag("--no-overlay", o->noOverlay, "no text panel and plots");
    o->muscle.add(*c);
    o->muscle.addMuscleModel(*c);
    c->callback([o, c] {
        refuseUnusedRenderOptions(*c, *o);
        if (isOsimModel(o->muscle.model)) {
            for (const char* name : {"--render-settings", "--color-by", "--fixed-thickness", "--arrow", "--arrow-scale", "--load",
                                     "--no-floor", "--muscle", "--arm", "--slow-units", "--fast-units", "--mass",
                                     "--tendon-length", "--max-path"})
                if (c->count(name) > 0)
                    throw InputError(std::string(name) + " with the OpenSim model '" + o->muscle.model +
                                     "': not for .osim models (their videos take --out, --fps, --width, --height, --codec, "
                                     "--speed, --supersample, --still-at, --still, --no-overlay)");
            runOsimRenderCommand(*o);
            return;
        }
        if (c->count("--muscle-model") > 0)
            throw InputError("--muscle-model: only for OpenSim models here (an armsim model's trial table records its "
                             "own muscles' states)");
        // The drawing is the model's geometry (--model, --arm) in the table's recorded states and forces:
        // a muscle's parameters would change nothing in the video.
        for (const char* name : {"--muscle", "--slow-units", "--fast-units", "--mass", "--tendon-length", "--max-path"})
            if (c->count(name) > 0)
                throw InputError(std::string(name) + ": the trial table '" + o->table + "' records the muscle's states and "
                                 "forces, so its parameters do not change the video (they are armsim trial's options; "
                                 "render takes the geometry: --model, --arm)");
        runRenderCommand(*o);
    });
}

/// Main job: one MVC video of the anatomical twin (isometric at 90 deg, the virtual subject's
/// effort), one free-movement video of the thesis arm, and a still of the MVC. The last step: the
/// renderer's libraries (llvmpipe's LLVM, FFmpeg; ~90 MB resident) stay mapped once loaded.
void runTrialVideos(const MainJobContext& ctx) {
    ::malloc_trim(0);   // give the earlier steps' freed heap back before the renderer's buffers come
    const ArmSetup setup = ctx.muscle.loadSetup();
    const ArmSetup subject = loadModel(kDefaultSubjectModel);
    IsometricTrialSettings iso;
    iso.elbowAngle = degToRad(90);
    iso.activation = subject.effort.voluntaryActivation;
    iso.antagonistActivation = subject.effort.coContraction;
    FreeMovementSettings free;
    free.handLoad = setup.arm.handLoad;   // the arm file's load, as armsim trial holds it
    // Two Systems, two threads.
    auto freeTable = std::async(ctx.jobs > 1 ? std::launch::async : std::launch::deferred,
                                [&] { return runFreeMovement(setup, free); });
    const Table mvc = runIsometricTrial(subject, iso).series;
    const Table movement = freeTable.get();
    mvc.writeCsv(ctx.outDir + "/trial_mvc_90deg.csv");
    movement.writeCsv(ctx.outDir + "/trial_free_movement.csv");

    TrialVideoSettings v;
    v.videoPath = ctx.outDir + "/video_mvc_90deg.mp4";
    v.stillTime = iso.restDuration + iso.holdDuration - 0.5;
    v.stillPath = ctx.outDir + "/still_mvc_90deg.png";
    v.tableName = "trial_mvc_90deg.csv";
    const RenderPlugin& render = getRenderPlugin("videos");
    TrialVideoResult r = render.renderTrialVideo(subject, mvc, v, [](int d, int n) { printProgress("MVC video", d, n); });
    std::printf("  wrote %s (%d frames) and %s\n", showPath(r.videoPath).c_str(), r.frames, showPath(r.stillPath).c_str());

    v.videoPath = ctx.outDir + "/video_free_movement.mp4";
    v.stillTime.reset();
    v.stillPath.clear();
    v.tableName = "trial_free_movement.csv";
    r = render.renderTrialVideo(setup, movement, v, [](int d, int n) { printProgress("free-movement video", d, n); });
    std::printf("  wrote %s (%d frames)\n", showPath(r.videoPath).c_str(), r.frames);
}

const CommandRegistrar registerRender(60, addRenderCommand);
const MainJobStepRegistrar registerVideos(60, "Videos: anatomical-twin MVC at 90 deg, thesis-arm free movement", runTrialVideos,
                                          [](const MainJobContext&) { checkRenderPluginFile("videos"); });

#else

void addRenderCommand(CLI::App& app) {
    CLI::App* c = app.add_subcommand("render", "video of a recorded trial (not in this build)");
    c->allow_extras();
    c->callback([] {
        throw InputError("armsim render: this armsim was built without the renderer: configure with "
                         "-DARMSIM_RENDER=ON");
    });
}

const CommandRegistrar registerRender(60, addRenderCommand);

#endif

}  // namespace

}  // namespace armsim::cli
