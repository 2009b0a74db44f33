// armsim trial: one isometric or free-movement trial of the arm; and the MVC-per-angle main-job step.
#include "basics/files.h"
#include "basics/output_folder.h"
#include "basics/param_node.h"
#include "basics/plot.h"
#include "cli/commands.h"
#include "cli/plugins.h"
#include "experiments/mvc_angles.h"
#include "model/geometry.h"
#include "model/osim_forward.h"
#include "model/osim_trial.h"
#include "model/trial.h"
#include "muscles/muscle_file.h"
#ifdef ARMSIM_WITH_RENDER
#include "render/render_plugin.h"
#endif

#include <algorithm>
#include <cstdio>
#include <memory>

namespace armsim::cli {

namespace {

struct TrialOptions {
    MuscleOptions muscle;
    std::string settingsFile;
    std::string coordinate, effort = "positive";  // OpenSim models
    std::string type = "isometric";
    double angleDeg = 90, activation = 1.0, rest = 0.5, rise = 0.0, hold = 3.0;
    double initialAngleDeg = 150, initialVelocityDegps = 0, onset = 0.2, duration = 2.0, load = 0.0;
    bool loadGiven = false;      // --load given; else the arm file's hand_load
    double rate = 1000, accuracy = 1e-4;
    std::string out = "out/trial.csv", plot, video;
};

#ifdef ARMSIM_WITH_RENDER
TrialVideoSettings makeVideoSettings(const TrialOptions& o, const std::string& path, double handLoad) {
    TrialVideoSettings v;
    v.videoPath = path;
    v.tableName = o.out;
    v.scene.handLoad = handLoad;
    return v;
}
#endif

// --video: renders the written table (a replay of the trial) to `path` (the staged file); its frame count.
int renderVideo(const TrialOptions& o, const std::string& path, const ArmSetup& setup, const Table& table, double handLoad) {
#ifdef ARMSIM_WITH_RENDER
    return getRenderPlugin("--video")
        .renderTrialVideo(setup, table, makeVideoSettings(o, path, handLoad), [](int d, int n) { printProgress("video", d, n); })
        .frames;
#else
    (void)o, (void)path, (void)setup, (void)table, (void)handLoad;
    return 0;
#endif
}

#ifdef ARMSIM_WITH_RENDER
OsimVideoSettings makeOsimVideoSettings(const TrialOptions& o, const std::string& path) {
    OsimVideoSettings v;
    v.videoPath = path;
    v.tableName = o.out;
    v.muscleModel = o.muscle.muscleModel;
    return v;
}
#endif

// --video of an OpenSim model's trial: checked before the work (a missing renderer, a bad path), then
// rendered from the table into `path` (the staged file); its frame count.
void checkOsimVideo(const TrialOptions& o, const std::string& path) {
    if (o.video.empty()) return;
#ifdef ARMSIM_WITH_RENDER
    getRenderPlugin("--video").validateOsim(makeOsimVideoSettings(o, path));
#else
    (void)path;
    getRenderPlugin("--video");  // a missing renderer fails first
#endif
}

int renderOsimVideo(const TrialOptions& o, const std::string& path, const OsimModel& model, const Table& table) {
#ifdef ARMSIM_WITH_RENDER
    return getRenderPlugin("--video")
        .renderOsimTrialVideo(model, table, makeOsimVideoSettings(o, path), [](int d, int n) { printProgress("video", d, n); })
        .frames;
#else
    (void)o, (void)path, (void)model, (void)table;
    return 0;
#endif
}

// An OpenSim model's trial outputs: every file checked and staged before the work, the model read.
struct OsimTrialOutputs {
    explicit OsimTrialOutputs(const TrialOptions& o) : osim(findOsimModelFile(o.muscle.model)) {
        files.addInput("--model", osim);
        csvPath = files.add("--out", o.out, true);
        plotPath = files.add("--plot", checkPngPath("--plot", o.plot));
        videoPath = files.add("--video", o.video);
        checkOsimVideo(o, videoPath);
        model = readOsimFile(osim);
    }
    OutputFiles files;
    std::string osim, csvPath, plotPath, videoPath;
    OsimModel model;
};

// An isometric trial of an OpenSim model: --coordinate locked at --angle (its value in deg), the others
// at their defaults; the muscles that pull it the --effort way excited.
void runOsimTrialCommand(const TrialOptions& o) {
    OsimTrialOutputs out(o);
    OutputFiles& files = out.files;
    const std::string &osim = out.osim, &csvPath = out.csvPath, &plotPath = out.plotPath, &videoPath = out.videoPath;
    const OsimModel& model = out.model;
    OsimIsometricTrialSettings s;
    s.coordinate = o.coordinate;
    s.angleDeg = o.angleDeg;
    s.direction = o.effort == "positive" ? 1 : -1;
    s.activation = o.activation;
    s.restDuration = o.rest;
    s.riseTime = o.rise;
    s.holdDuration = o.hold;
    s.averagingWindow = std::min(s.averagingWindow, o.hold);
    s.sampleRate = o.rate;
    s.integration.accuracy = o.accuracy;
    s.muscleModel = o.muscle.muscleModel;
    OsimIsometricTrialResult r;
    runNamingOptions({{"coordinate", "--coordinate"}, {"angle_deg", "--angle"}, {"activation", "--activation"},
                      {"rest", "--rest"}, {"rise", "--rise"}, {"hold", "--hold"}, {"sample_rate", "--rate"},
                      {"accuracy", "--accuracy"}},
                     [&] { r = runOsimIsometricTrial(model, s); });
    const OsimIsometricSummary& m = r.summary;
    files.writeWith(csvPath, [&](const std::string& p) { r.series.writeCsv(p); });
    int frames = 0;
    if (!o.video.empty()) files.writeWith(videoPath, [&](const std::string& p) { frames = renderOsimVideo(o, p, model, r.series); });
    if (!o.plot.empty()) {
        PlotSpec spec;
        spec.title = model.name + ": isometric " + o.effort + " effort at " + m.coordinate + " = " + formatNumber(m.angleDeg) + " deg";
        spec.xLabel = "time (s)";
        spec.yLabel = "torque about " + m.coordinate + " (N m)";
        spec.series.push_back({"muscle torque (tared)", r.series.getColumn("time_s"), r.series.getColumn("tared_torque_Nm")});
        spec.series.push_back({"muscle torque (raw, passive included)", r.series.getColumn("time_s"),
                               r.series.getColumn("muscle_torque_Nm"), false, 1});
        files.writeWith(plotPath, [&](const std::string& p) { writePlotPng(p, spec); });
    }
    files.commit();
    std::printf("isometric trial of %s (%s): %s locked at %s deg, the other coordinates at their defaults; %s effort\n",
                model.name.c_str(), osim.c_str(), m.coordinate.c_str(), formatNumber(m.angleDeg).c_str(), o.effort.c_str());
    std::printf("  torque about %s   %8.2f N m tared (mean of the last %s s); %.2f N m passive at rest\n",
                m.coordinate.c_str(), m.meanTaredTorque, formatNumber(s.averagingWindow).c_str(), m.restTorque);
    std::printf("  %-12s %16s %9s %14s %13s\n", "muscle", "moment arm (cm)", "agonist", "mean force (N)", "torque (N m)");
    for (std::size_t i = 0; i < m.muscles.size(); ++i)
        std::printf("  %-12s %16.2f %9s %14.1f %13.2f\n", m.muscles[i].c_str(), 100 * m.momentArms[i],
                    m.agonists[i] ? "yes" : "no", m.meanForces[i], m.momentArms[i] * m.meanForces[i]);
    std::printf("wrote %s\n", o.out.c_str());
    if (!o.video.empty()) std::printf("wrote %s (%d frames)\n", o.video.c_str(), frames);
    if (!o.plot.empty()) std::printf("wrote %s\n", o.plot.c_str());
}

// A free movement of an OpenSim model: --coordinate free from --initial-angle (its default when not
// given), the others held, the muscles pulling the --effort way excited from --onset.
void runOsimFreeTrialCommand(const TrialOptions& o, bool initialAngleGiven, bool accuracyGiven) {
    OsimTrialOutputs out(o);
    OutputFiles& files = out.files;
    const std::string &osim = out.osim, &csvPath = out.csvPath, &plotPath = out.plotPath, &videoPath = out.videoPath;
    const OsimModel& model = out.model;
    OsimFreeMovementSettings s;
    s.coordinate = o.coordinate;
    s.initialAngleDeg = initialAngleGiven ? o.initialAngleDeg : kNaN;
    s.initialVelocityDegps = o.initialVelocityDegps;
    s.direction = o.effort == "positive" ? 1 : -1;
    s.activation = o.activation;
    s.onset = o.onset;
    s.rise = o.rise;
    s.duration = o.duration;
    s.sampleRate = o.rate;
    if (accuracyGiven) s.integration.accuracy = o.accuracy;
    s.muscleModel = o.muscle.muscleModel;
    s.progress = [d = o.duration](double t) { printTimeProgress("free movement", t, d); };
    Table t;
    IntegrationStats stats;
    runNamingOptions({{"coordinate", "--coordinate"}, {"initial_angle_deg", "--initial-angle"},
                      {"initial_velocity_degps", "--initial-velocity"}, {"activation", "--activation"},
                      {"onset", "--onset"}, {"rise", "--rise"}, {"duration", "--duration"}, {"sample_rate", "--rate"},
                      {"accuracy", "--accuracy"}},
                     [&] { t = runOsimFreeMovement(model, s, &stats); });
    const std::string coordinate = t.getColumnNames()[2].substr(0, t.getColumnNames()[2].size() - 4);  // "<c>_deg"
    files.writeWith(csvPath, [&](const std::string& p) { t.writeCsv(p); });
    int frames = 0;
    if (!o.video.empty()) files.writeWith(videoPath, [&](const std::string& p) { frames = renderOsimVideo(o, p, model, t); });
    if (!o.plot.empty()) {
        PlotSpec spec;
        spec.title = model.name + ": free movement of " + coordinate + " (" + o.effort + " effort)";
        spec.xLabel = "time (s)";
        spec.yLabel = coordinate + " (deg)";
        spec.series.push_back({coordinate, t.getColumn("time_s"), t.getColumn(coordinate + "_deg")});
        files.writeWith(plotPath, [&](const std::string& p) { writePlotPng(p, spec); });
    }
    files.commit();
    const int last = t.getNumRows() - 1;
    std::printf("free movement of %s (%s): %s %.1f -> %.1f deg in %s s, the other coordinates held (%d integrator steps)\n",
                model.name.c_str(), osim.c_str(), coordinate.c_str(), t.get(0, 2), t.get(last, 2),
                formatNumber(o.duration).c_str(), stats.steps);
    if (const OsimCoordinate* c = model.findCoordinate(coordinate)) {   // ranges are not forces: say when it left its own
        const double lo = c->range[0] * 180 / kPi, hi = c->range[1] * 180 / kPi;
        for (int k = 0; k <= last; ++k)
            if (t.get(k, 2) < lo - 1e-9 || t.get(k, 2) > hi + 1e-9) {
                std::printf("note: %s left its range [%s, %s] deg at t = %s s (OpenSim's coordinate ranges are not forces; "
                            "its forward dynamics let it pass them too)\n", coordinate.c_str(), formatNumber(lo, 4).c_str(),
                            formatNumber(hi, 4).c_str(), formatNumber(t.get(k, 0)).c_str());
                break;
            }
    }
    std::printf("wrote %s\n", o.out.c_str());
    if (!o.video.empty()) std::printf("wrote %s (%d frames)\n", o.video.c_str(), frames);
    if (!o.plot.empty()) std::printf("wrote %s\n", o.plot.c_str());
}

/// An isometric trial's summary: the true force beside the transducer and the thesis's two estimates.
void printIsometricSummary(const ArmSetup& setup, const IsometricSummary& s, double averagingWindow) {
    std::printf("isometric trial at %.1f deg: path %.2f cm, moment arm %.2f cm\n", radToDeg(s.elbowAngle),
                100 * s.pathLength, 100 * s.momentArm);
    std::printf("  true muscle force      %8.2f N (mean of the last %.2f s; final %.2f N)\n", s.meanForce,
                averagingWindow, s.finalForce);
    std::printf("  transducer (tared)     %8.2f N%s\n", s.meanStrapForce, s.saturated ? "  SATURATED" : "");
    std::printf("  estimate, moment arm   %8.2f N (tare hides %.2f N of passive force)\n", s.meanForceMomentArm,
                s.restForce);
    std::printf("  estimate, fixed ratio  %8.2f N (error %+.2f %%)\n", s.meanForceFixedRatio,
                100 * (s.meanForceFixedRatio - s.meanForce) / s.meanForce);
    if (setup.getNumMuscles() > 1)   // the thesis's estimates assume one muscle makes the whole torque
        std::printf("  (the estimates are the thesis's one-muscle method: the tared torque of all %d muscles "
                    "credited to %s)\n", setup.getNumMuscles(), setup.muscles[setup.primary].params.name.c_str());
}

void runTrialCommand(const TrialOptions& o) {
    // Every output checked and staged before the trial; all appear together at the end, or none.
    OutputFiles files;
    o.muscle.declareInputs(files);
    files.addInput("--settings", o.settingsFile);
    const std::string csvPath = files.add("--out", o.out, true), plotPath = files.add("--plot", checkPngPath("--plot", o.plot)),
                      videoPath = files.add("--video", o.video);
#ifdef ARMSIM_WITH_RENDER
    if (!o.video.empty()) getRenderPlugin("--video").validate(makeVideoSettings(o, videoPath, o.load));
#else
    if (!o.video.empty()) getRenderPlugin("--video");  // a missing renderer fails first
#endif
    const ArmSetup setup = o.muscle.loadSetup();
    int frames = 0;
    std::string type = o.type;
    IsometricTrialSettings iso;
    FreeMovementSettings free;
    if (!o.settingsFile.empty()) {
        const ParamNode root = ParamNode::loadFile(o.settingsFile);
        type = root.getChoice("type", {"isometric", "free"}, "isometric");
        if (type == "isometric") {
            iso = readIsometricTrialSettings(root, setup.arm);
            root.rethrowWithLocation([&] { iso.calcActivationProfiles(setup); });   // an effort the model's muscles make
        } else {
            free = readFreeMovementSettings(root, setup.arm);
        }
    } else if (type == "isometric") {
        iso.elbowAngle = degToRad(o.angleDeg);
        iso.activation = o.activation;
        iso.restDuration = o.rest;
        iso.riseTime = o.rise;
        iso.holdDuration = o.hold;
        iso.averagingWindow = std::min(iso.averagingWindow, o.hold);
        iso.sampleRate = o.rate;
        iso.integration.accuracy = o.accuracy;
        runNamingOptions({{"elbow_angle_deg", "--angle"}, {"activation", "--activation"}, {"rest", "--rest"},
                          {"rise", "--rise"}, {"hold", "--hold"}, {"sample_rate", "--rate"}, {"accuracy", "--accuracy"}},
                         [&] { iso.validate(setup.arm); iso.calcActivationProfiles(setup); });   // in the options' words, before any work
    } else {
        free.initialAngle = degToRad(o.initialAngleDeg);
        free.initialVelocity = degToRad(o.initialVelocityDegps);
        checkField("--activation", o.activation, Bound::closed(0, 1));
        checkField("--onset", o.onset, Bound::nonNegative("s"));
        checkField("--rise", o.rise, Bound::nonNegative("s"));
        if (o.activation > 0 && !(o.onset < o.duration))
            throw InputError("--onset " + formatNumber(o.onset) + " s is not before the end of the movement (--duration " +
                             formatNumber(o.duration) + " s): expected an onset before the end (the activation would "
                             "never start)");
        free.activation = o.rise > 0 ? ActivationProfile::ramp(o.onset, o.onset + o.rise, 0.0, o.activation)
                                     : ActivationProfile::step(o.onset, 0.0, o.activation);
        free.duration = o.duration;
        free.handLoad = o.loadGiven ? o.load : setup.arm.handLoad;
        free.sampleRate = o.rate;
        free.integration.accuracy = o.accuracy;
        runNamingOptions({{"initial_angle_deg", "--initial-angle"}, {"initial_velocity_degps", "--initial-velocity"},
                          {"duration", "--duration"}, {"hand_load", "--load"}, {"sample_rate", "--rate"},
                          {"accuracy", "--accuracy"}},
                         [&] { free.validate(setup.arm); });
    }

    PlotSpec spec;
    spec.xLabel = "time (s)";
    if (type == "isometric") {
        IsometricTrialResult r;
        iso.progress = [d = iso.getDuration()](double t) { printTimeProgress("isometric trial", t, d); };   // a long hold's
        runNamingOptions({{"elbow_angle_deg", o.settingsFile.empty() ? "--angle" : o.settingsFile + ": elbow_angle_deg"}},
                         [&] { r = runIsometricTrial(setup, iso); });
        files.writeWith(csvPath, [&](const std::string& p) { r.series.writeCsv(p); });
        if (!o.video.empty())
            files.writeWith(videoPath, [&](const std::string& p) { frames = renderVideo(o, p, setup, r.series, 0); });
        const IsometricSummary& s = r.summary;
        printIsometricSummary(setup, s, iso.averagingWindow);
        spec.title = "isometric trial at " + std::to_string(int(radToDeg(s.elbowAngle) + 0.5)) + " deg";
        spec.yLabel = "force (N)";
        spec.series.push_back({"true muscle force", r.series.getColumn("time_s"), r.series.getColumn("muscle_force_N")});
        spec.series.push_back({"estimate (tared torque / moment arm)", r.series.getColumn("time_s"),
                               r.series.getColumn("force_moment_arm_N"), false, 1});
        spec.series.push_back({"thesis fixed-ratio estimate", r.series.getColumn("time_s"),
                               r.series.getColumn("force_fixed_ratio_N"), false, 2});
    } else {
        IntegrationStats stats;
        free.progress = [d = free.duration](double t) { printTimeProgress("free movement", t, d); };
        noteUnreachedActivation(free.activation, free.duration);
        const Table t = runFreeMovement(setup, free, &stats);
        files.writeWith(csvPath, [&](const std::string& p) { t.writeCsv(p); });
        if (!o.video.empty())
            files.writeWith(videoPath, [&](const std::string& p) { frames = renderVideo(o, p, setup, t, free.handLoad); });
        std::printf("free movement: elbow %.1f -> %.1f deg in %.2f s (%d integrator steps)\n",
                    t.get(0, "elbow_angle_deg"), t.get(t.getNumRows() - 1, "elbow_angle_deg"), free.duration,
                    stats.steps);
        spec.title = "free movement";
        spec.yLabel = "elbow angle (deg)";
        spec.series.push_back({"elbow angle", t.getColumn("time_s"), t.getColumn("elbow_angle_deg")});
    }
    if (!o.plot.empty()) files.writeWith(plotPath, [&](const std::string& p) { writePlotPng(p, spec); });
    files.commit();
    std::printf("wrote %s\n", o.out.c_str());
    if (!o.video.empty()) std::printf("wrote %s (%d frames)\n", o.video.c_str(), frames);
    if (!o.plot.empty()) std::printf("wrote %s\n", o.plot.c_str());
}

void addTrialCommand(CLI::App& app) {
    auto o = std::make_shared<TrialOptions>();
    CLI::App* c = app.add_subcommand("trial", "one trial of the arm: isometric (elbow locked) or free movement; of an OpenSim model (.osim), "
                                       "either about one coordinate (--coordinate)");
    o->muscle.add(*c);
    o->muscle.addMuscleModel(*c);
    c->add_option("--settings", o->settingsFile,
                  "YAML trial settings (type: isometric|free, and the keys of that trial type) instead of options");
    c->add_option("--type", o->type, "isometric | free")->capture_default_str()->check(CLI::IsMember({"isometric", "free"}));
    c->add_option("--angle", o->angleDeg, "isometric: elbow angle [deg], 180 = extended (an OpenSim model: "
                                        "--coordinate's value [deg])")->capture_default_str();
    c->add_option("--activation", o->activation, "target activation U in [0, 1]")->capture_default_str();
    c->add_option("--rest", o->rest, "isometric: rest before the effort, transducer tared [s]")->capture_default_str();
    c->add_option("--rise", o->rise, "activation ramp time [s] (0 = step)")->capture_default_str();
    c->add_option("--hold", o->hold, "isometric: effort duration [s]")->capture_default_str();
    c->add_option("--initial-angle", o->initialAngleDeg, "free: elbow angle at t = 0 [deg] (an OpenSim model: "
                                                        "--coordinate's value, default its default value)")->capture_default_str();
    c->add_option("--initial-velocity", o->initialVelocityDegps, "free: elbow angular velocity at t = 0 [deg/s]");
    c->add_option("--onset", o->onset, "free: activation onset [s]")->capture_default_str();
    c->add_option("--duration", o->duration, "free: simulated time [s]")->capture_default_str();
    c->add_option("--load", o->load, "free: mass held in the hand [kg] (default: the arm file's hand_load, 0 in the shipped ones)");
    c->add_option("--rate", o->rate, "samples per second [Hz]")->capture_default_str();
    c->add_option("--accuracy", o->accuracy, "integrator relative accuracy")->capture_default_str();
    c->add_option("--out", o->out, "CSV output")->capture_default_str();
    c->add_option("--plot", o->plot, "PNG plot (optional)");
    c->add_option("--video", o->video, "video of the trial (.mp4, H.264), rendered from the written table (optional)");
    // Options that would be ignored are refused: the settings file gives the whole trial, and each
    // trial type takes its own options.
    const std::vector<std::string> trialOptions = {"--type", "--angle", "--activation", "--rest", "--rise", "--hold",
                                                   "--initial-angle", "--initial-velocity", "--onset", "--duration",
                                                   "--load", "--rate", "--accuracy"};
    for (const std::string& name : trialOptions) c->get_option("--settings")->excludes(c->get_option(name));
    c->add_option("--coordinate", o->coordinate,
                  "an OpenSim model's coordinate to lock and act about (default: its only moving one)");
    c->add_option("--effort", o->effort, "an OpenSim model: the effort's direction about --coordinate")
        ->capture_default_str()
        ->check(CLI::IsMember({"positive", "negative"}));
    c->callback([o, c] {
        if (c->count("--coordinate") > 0 && o->coordinate.empty())
            throw InputError("--coordinate is empty: expected a coordinate's name (or leave it out for a model with one)");
        if (c->count("--muscle-model") > 0 && o->muscle.muscleModel.empty())
            throw InputError("--muscle-model is empty: expected a muscle model's name (or leave it out for the model's own)");
        if (isOsimModel(o->muscle.model)) {
            const std::string& mm = o->muscle.muscleModel;
            if (!mm.empty() && mm != "thelen2003" && mm != "degroote2016" && mm != "thelen2003_opensim2")
                throw InputError("--muscle-model '" + mm + "' with the OpenSim model '" + o->muscle.model + "': expected "
                                 "thelen2003, degroote2016 or thelen2003_opensim2 (an .osim model's muscles are Hill-type)");
            if (c->count("--initial-angle") > 0 && !std::isfinite(o->initialAngleDeg))
                throw InputError("--initial-angle = " + formatNumber(o->initialAngleDeg) + ": expected a finite angle (deg; "
                                 "leave it out to start at the coordinate's default)");
            // What an OpenSim model's trial would ignore or cannot do yet is refused, naming the option.
            const bool free = o->type == "free";
            for (const char* name : {"--settings", "--muscle", "--arm", "--slow-units", "--fast-units", "--mass",
                                     "--tendon-length", "--max-path", "--load"})
                if (c->count(name) > 0)
                    throw InputError(std::string(name) + " with the OpenSim model '" + o->muscle.model +
                                     "': not for .osim models (their trials take --coordinate, --effort, --activation, "
                                     "--rise, --rate, --accuracy, --muscle-model, --out, --plot, --video; isometric --angle (the "
                                     "coordinate's value, deg), --rest, --hold; free --initial-angle, --initial-velocity, "
                                     "--onset, --duration)");
            for (const char* name : {"--angle", "--rest", "--hold"})
                if (free && c->count(name) > 0)
                    throw InputError(std::string(name) + " is an isometric trial's option: with --type free it would be "
                                     "ignored (the free trial starts at --initial-angle)");
            for (const char* name : {"--initial-angle", "--initial-velocity", "--onset", "--duration"})
                if (!free && c->count(name) > 0)
                    throw InputError(std::string(name) + " is a free movement's option: the isometric trial (the default "
                                     "--type) would ignore it; add --type free");
            if (free) runOsimFreeTrialCommand(*o, c->count("--initial-angle") > 0, c->count("--accuracy") > 0);
            else runOsimTrialCommand(*o);
            return;
        }
        for (const char* name : {"--coordinate", "--effort"})
            if (c->count(name) > 0)
                throw InputError(std::string(name) + ": only for OpenSim models (.osim); model '" + o->muscle.model +
                                 "' is an armsim model (its trials act about the elbow)");
        const bool free = o->type == "free";
        for (const char* name : {"--angle", "--rest", "--hold"})
            if (free && c->count(name) > 0)
                throw InputError(std::string(name) + " is an isometric trial's option: with --type free it would be "
                                 "ignored (the free trial starts at --initial-angle)");
        for (const char* name : {"--initial-angle", "--initial-velocity", "--onset", "--duration", "--load"})
            if (!free && c->count(name) > 0)
                throw InputError(std::string(name) + " is a free movement's option: the isometric trial (the default "
                                 "--type) would ignore it; add --type free");
        o->loadGiven = c->count("--load") > 0;
        runTrialCommand(*o);
    });
}

const std::vector<double> kMainJobAnglesDeg{std::begin(kThesisMvcAnglesDeg), std::end(kThesisMvcAnglesDeg)};

/// Main job: the thesis arm's MVC at the thesis's five angles, in parallel.
void runMvcAngles(const MainJobContext& ctx) {
    const MvcAngleSweep sweep = runMvcAngleSweep(ctx.muscle.loadSetup(), kMainJobAnglesDeg, ctx.jobs,
                                                 [](int d, int n) { printProgress("MVC trials", d, n); });
    const Table& t = sweep.table;
    std::printf("  angle (deg)  path (cm)  muscle F (N)  strap (N)  est. moment arm (N)  est. fixed ratio (N)\n");
    for (int k = 0; k < t.getNumRows(); ++k)
        std::printf("  %11.0f  %9.2f  %12.2f  %9.2f  %19.2f  %20.2f\n", t.get(k, "elbow_angle_deg"),
                    100 * t.get(k, "path_length_m"), t.get(k, "muscle_force_N"), t.get(k, "strap_force_N"),
                    t.get(k, "force_moment_arm_N"), t.get(k, "force_fixed_ratio_N"));
    t.writeCsv(ctx.outDir + "/mvc_angles.csv");
    writePlotPng(ctx.outDir + "/mvc_angles.png", sweep.plot);
    std::printf("  (thesis measured 450-600 N, quadratic peak 603.3 N at 101.2 deg; see README on short paths)\n");
    std::printf("  wrote %s/mvc_angles.csv, mvc_angles.png\n", showPath(ctx.outDir).c_str());
}

/// Main job: the same five-angle MVC on the anatomical twin, with the thesis's biceps-force estimate
/// beside every muscle's true force.
void runSubjectMvcAngles(const MainJobContext& ctx) {
    const ArmSetup setup = loadModel(kDefaultSubjectModel);
    const MvcAngleSweep sweep = runSubjectMvcAngleSweep(setup, kMainJobAnglesDeg, ctx.jobs,
                                                        [](int d, int n) { printProgress("twin MVC trials", d, n); });
    const Table& t = sweep.table;
    const std::string biceps = setup.muscles[setup.primary].params.name;
    std::printf("  angle (deg)  flexion (deg)  torque (N m)  %s (N)  biceps, both heads (N)  thesis estimate (N)  "
                "error\n", biceps.c_str());
    for (int k = 0; k < t.getNumRows(); ++k)
        std::printf("  %11.0f  %13.0f  %12.1f  %*.1f  %22.1f  %19.1f  %+5.0f %%\n", t.get(k, "elbow_angle_deg"),
                    t.get(k, "flexion_deg"), t.get(k, "tared_torque_Nm"), int(biceps.size()) + 4,
                    t.get(k, "primary_force_N"), t.get(k, "biceps_both_heads_N"), t.get(k, "thesis_estimate_N"),
                    t.get(k, "estimate_error_vs_both_heads_pct"));
    t.writeCsv(ctx.outDir + "/mvc_angles_twin.csv");
    writePlotPng(ctx.outDir + "/mvc_angles_twin.png", sweep.plot);
    std::printf("  the estimate credits the biceps with the brachialis' and brachioradialis' torque, less the\n"
                "  triceps' co-contraction; wrote %s/mvc_angles_twin.csv, mvc_angles_twin.png\n",
                showPath(ctx.outDir).c_str());
}

const CommandRegistrar registerTrial(20, addTrialCommand);
const MainJobStepRegistrar registerMvc(30, "Thesis arm (biceps only): MVC at the thesis's five elbow angles", runMvcAngles);
const MainJobStepRegistrar registerSubjectMvc(32, "Anatomical twin (ten muscles): MVC at the thesis's five angles",
                                              runSubjectMvcAngles);

}  // namespace

}  // namespace armsim::cli
