// armsim forward: OpenSim's Forward tool on an .osim model (model/osim_forward.h): excitations from a
// controls file, states written as OpenSim writes them. Parses and calls; no science here.
#include "basics/bound.h"
#include "basics/errors.h"
#include "basics/numbers.h"
#include "basics/files.h"
#include "basics/format.h"
#include "basics/output_folder.h"
#include "basics/plot.h"
#include "cli/commands.h"
#include "model/osim_forward.h"
#include "numerics/stiff_ode.h"

#include <chrono>
#include <map>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

namespace armsim::cli {

namespace {

struct ForwardOptions {
    std::string setup;          ///< a Forward tool setup file (positional)
    std::string model;          ///< .osim file or a shipped model's name (arm26)
    std::string controls, initialStates;
    double initialTime = kNaN, finalTime = kNaN;
    double rate = 200;
    double accuracy = kNaN;  ///< NaN: the setup's tolerance, else 1e-5
    double maxStepSize = 0;  ///< [s] the setup's maximum_integrator_step_size; 0: none
    std::string muscleModel;
    std::string out;
};

// outOption: the command's --out, given the folder used (the setup's or the default) so the folder's
// index.html report is written as for any other command.
void runForward(const ForwardOptions& given, CLI::Option* outOption) {
    ForwardOptions o = given;
    if (!o.setup.empty()) {
        const OsimForwardSetup s = readOsimForwardSetup(o.setup);
        if (o.model.empty()) o.model = s.modelFile;
        if (o.controls.empty()) o.controls = s.controlsFile;
        if (o.initialStates.empty()) o.initialStates = s.statesFile;
        if (!std::isfinite(o.initialTime)) o.initialTime = s.initialTime;
        if (!std::isfinite(o.finalTime)) o.finalTime = s.finalTime;
        if (o.out.empty()) o.out = s.resultsDirectory;
        if (!std::isfinite(o.accuracy)) o.accuracy = s.tolerance;
        o.maxStepSize = s.maxStepSize;
    }
    if (o.model.empty()) throw InputError("forward: no model: give --model FILE.osim (or a Forward tool setup file)");
    if (o.controls.empty()) throw InputError("forward: no controls: give --controls FILE.sto (or a Forward tool setup file)");
    if (!std::isfinite(o.finalTime)) throw InputError("forward: no final time: give --final-time SECONDS");
    if (!std::isfinite(o.accuracy)) o.accuracy = 1e-5;  // OpenSim's Forward tool default
    if (o.out.empty()) o.out = "out/forward";
    if (given.out.empty()) outOption->default_val(o.out);
    checkOutputFolder("--out", o.out);
    // An input among the files written into --out would be replaced by an output.
    {
        namespace fs = std::filesystem;
        const std::pair<const char*, std::string> inputs[] = {
            {"--model", o.model}, {"--controls", o.controls}, {"--initial-states", o.initialStates}, {"setup file", o.setup}};
        for (const char* written : {"states.sto", "states.csv", "coordinates.png", "activations.png", "index.html"}) {
            std::error_code ec;
            const fs::path target = fs::weakly_canonical(fs::path(o.out) / written, ec);
            if (ec) continue;   // a path that cannot be resolved is checked when it is written
            for (const auto& [what, file] : inputs) {
                std::error_code ecFile;
                if (file.empty()) continue;
                const fs::path input = fs::weakly_canonical(file, ecFile);
                if (!ecFile && input == target)
                    throw InputError(std::string(what) + " '" + file + "' is " + written + " of --out '" + o.out +
                                     "', which forward writes: expected another output folder (it would replace the input)");
            }
        }
    }
    const OsimModel model = readOsimFile(findOsimModelFile(o.model));
    const OsimStorage controls = readOsimStorage(o.controls);
    OsimStorage initial;
    if (!o.initialStates.empty()) initial = readOsimStorage(o.initialStates);
    OsimForwardSettings s;
    s.initialTime = o.initialTime;
    s.finalTime = o.finalTime;
    s.sampleRate = o.rate;
    s.muscleModel = o.muscleModel;
    s.integration.accuracy = o.accuracy;
    s.integration.maxStepSize = o.maxStepSize;
    s.progress = [](double t, double duration) { printTimeProgress("forward", t, duration); };
    const auto start = std::chrono::steady_clock::now();
    std::map<std::string, std::string> typed;   // settings the command line gave, named as typed
    if (std::isfinite(given.finalTime)) typed["final_time"] = "--final-time";
    if (std::isfinite(given.initialTime)) typed["initial_time"] = "--initial-time";
    if (std::isfinite(given.accuracy)) typed["accuracy"] = "--accuracy";
    typed["sample_rate"] = "--rate";
    OsimForwardResult r;
    try {
        runNamingOptions(typed, [&] { r = runOsimForward(model, controls, o.initialStates.empty() ? nullptr : &initial, s); });
    } catch (const SampleCountError& e) {   // the run's length and the rate, as the options gave them
        const std::string end = std::isfinite(given.finalTime) ? "--final-time" : "the controls' last time";
        const std::string start = std::isfinite(given.initialTime) ? "--initial-time" : "the controls' first time";
        throw InputError(end + " - " + start + " = " + formatNumber(e.getDuration()) + " s x --rate " +
                         formatNumber(e.getSampleRate()) + " Hz " + e.getDetail());
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    for (const std::string& note : r.notes) std::printf("note: %s\n", note.c_str());
    const Table& t = r.states;
    std::printf("forward: %s, %s to %s s, %d steps in %.0f ms\n", model.name.c_str(), formatNumber(t.get(0, 0)).c_str(),
                formatNumber(t.get(t.getNumRows() - 1, 0)).c_str(), r.stats.steps, 1000 * seconds);

    OutputFolder out(o.out, OutputFolder::Mode::AddFiles);
    out.write("states.sto", formatStorage(t, model.name + "_states", false, 17));
    out.write("states.csv", t.toCsv(17));
    PlotSpec angles;
    angles.title = model.name + ": coordinates";
    angles.xLabel = "time (s)";
    angles.yLabel = "angle (deg)";
    PlotSpec activations;
    activations.title = model.name + ": activations";
    activations.xLabel = "time (s)";
    activations.yLabel = "activation";
    const std::vector<double> time = t.getColumn("time");
    for (const OsimJoint& j : model.joints)
        for (const OsimCoordinate& k : j.coordinates) {
            if (!t.hasColumn(k.name)) continue;
            std::vector<double> y = t.getColumn(k.name);
            if (k.rotational)
                for (double& v : y) v *= 180 / 3.14159265358979323846;
            angles.series.push_back({k.name, time, y, false, int(angles.series.size() % 8)});
        }
    for (const OsimMuscle& m : model.muscles)
        if (t.hasColumn(m.name + ".activation"))
            activations.series.push_back({m.name, time, t.getColumn(m.name + ".activation"), false, int(activations.series.size() % 8)});
    if (!angles.series.empty()) out.writeWith("coordinates.png", [&](const std::string& p) { writePlotPng(p, angles); });
    if (!activations.series.empty()) out.writeWith("activations.png", [&](const std::string& p) { writePlotPng(p, activations); });
    out.commit();
    std::printf("wrote %s/states.sto, states.csv, coordinates.png, activations.png\n", o.out.c_str());
}

void addForwardCommand(CLI::App& app) {
    auto o = std::make_shared<ForwardOptions>();
    CLI::App* c = app.add_subcommand("forward",
                                     "forward dynamics of an OpenSim model (.osim) driven by an OpenSim controls file, "
                                     "as OpenSim's Forward tool; states.sto with OpenSim's column names");
    c->add_option("setup", o->setup, "a Forward tool setup file (<ForwardTool>): model, controls, times, tolerance")
        ->check(CLI::ExistingFile);
    c->add_option("--model", o->model, "the .osim file, or a shipped one's name (arm26)");
    c->add_option("--controls", o->controls, "controls storage file (.sto): time and one excitation column per muscle");
    c->add_option("--initial-states", o->initialStates,
                  "states storage file: the row at or before the initial time (default: the model's defaults, muscles "
                  "in equilibrium)");
    c->add_option("--initial-time", o->initialTime, "[s] (default: the controls' first time)");
    c->add_option("--final-time", o->finalTime, "[s]");
    c->add_option("--rate", o->rate, "rows of states.sto per second [Hz]")->capture_default_str()->transform(inRange(1e-3, 1e6));
    c->add_option("--accuracy", o->accuracy,
                  "integrator relative accuracy (default: the setup's integrator_error_tolerance, else 1e-5)")
        ->transform(inRange(bounds::kAccuracy.lo, bounds::kAccuracy.hi));
    c->add_option("--muscle-model", o->muscleModel,
                  "every muscle under this model: thelen2003, thelen2003_opensim2 (OpenSim 2.x's equations) or "
                  "degroote2016 (default: each muscle's type in the file)");
    CLI::Option* out = c->add_option("--out", o->out, "output folder (default: the setup's results_directory, else out/forward)");
    c->callback([o, out, c] {
        // NaN stands for "not given" inside: a NaN typed is refused, not read as absent.
        const std::pair<const char*, double> numbers[] = {
            {"--initial-time", o->initialTime}, {"--final-time", o->finalTime}, {"--accuracy", o->accuracy}};
        for (const auto& [name, value] : numbers)
            if (c->count(name) > 0 && !std::isfinite(value))
                throw InputError(std::string(name) + " = " + formatNumber(value) + ": expected a finite number");
        if (c->count("--muscle-model") > 0 && o->muscleModel.empty())
            throw InputError("--muscle-model is empty: expected thelen2003, thelen2003_opensim2 or degroote2016 (or leave "
                             "it out for each muscle's type in the file)");
        runForward(*o, out);
    });
}

}  // namespace

const CommandRegistrar registerForward(62, addForwardCommand);

}  // namespace armsim::cli
