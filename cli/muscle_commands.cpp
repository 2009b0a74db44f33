// armsim muscle steady | sweep | trial: the muscle alone, both path ends fixed.
#include "basics/bound.h"
#include "basics/output_folder.h"
#include "basics/plot.h"
#include "cli/commands.h"
#include "basics/files.h"
#include "model/arm_parameters.h"
#include "model/muscle_arm.h"
#include "muscles/muscle_file.h"
#include "muscles/simbody_isometric.h"

#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>

namespace armsim::cli {

void MuscleOptions::declareInputs(OutputFiles& files) const {
    files.addInput("--muscle", file);
    files.addInput("--arm", armFile);
    if (isRegularFile(model)) files.addInput("--model", model);
}

namespace {
// A steady solve that failed at a path the user typed: the path is the input's fault when no steady
// state exists there (exit 2 naming the option), the solver's otherwise (exit 3).
[[noreturn]] void throwSteadyFailure(const std::string& option, const std::string& message) {
    if (message.rfind("no steady state at path", 0) == 0) throw InputError(option + ": " + message);
    throw SimulationError(message);
}

// The muscle's own check of a path the user typed (and, for a trial, of its initial state there), named
// as the option (InputError).
void checkPathWithin(const MuscleModel& m, const std::string& option, double path, bool initialState = false) {
    try {
        m.checkPathLength(path);
        if (initialState) m.calcInitialState(path);
    } catch (const InputError& e) {
        throw InputError(option + ": " + e.what());
    }
}
}  // namespace

void MuscleOptions::add(CLI::App& app) {
    app.add_option("--model", model, "model: a name under assets/models/ (thesis, elbow) or a model file")
        ->capture_default_str();
    app.add_option("--muscle", file, "muscle file replacing the primary muscle's parameters (path, or name under assets/)");
    app.add_option("--arm", armFile, "arm file replacing the model's arm (path, or name under assets/); its biceps A and B are the thesis "
                                       "method's straight-line geometry, the muscles keep the model's paths");
    app.add_option("--slow-units", slowUnits, "number of slow motor units (default: from the model)");
    app.add_option("--fast-units", fastUnits, "number of fast motor units (default: from the model)");
    app.add_option("--mass", mass, "muscle mass M [kg] (default: from the model)");
    app.add_option("--tendon-length", tendonLength, "optimal tendon length L0T [m] (default: from the model)");
    app.add_option("--max-path", maxPathLength, "path length at the anatomical limit P_max [m] (default: the "
                                                "longest path over the elbow range)");
}

void MuscleOptions::addMuscleModel(CLI::App& app) {
    app.add_option("--muscle-model", muscleModel,
                   "every muscle's model: virtual_muscle, thelen2003 or degroote2016; an OpenSim model's: thelen2003, "
                   "degroote2016 or thelen2003_opensim2 (default: the model file's)");
}

ArmSetup loadModelWithMuscles(const std::string& name, const std::string& muscleModel) {
    ArmSetup s = loadModel(name);
    if (muscleModel.empty()) return s;
    try {
        findMuscleModelType(muscleModel);
    } catch (const InputError& e) {
        const std::string m = e.what();
        throw InputError("option --muscle-model = '" + muscleModel + "': " + m.substr(m.find("expected")));
    }
    setMuscleModel(s, muscleModel);
    return s;
}

ArmSetup MuscleOptions::loadSetup() const {
    ArmSetup s = loadModelWithMuscles(model, muscleModel);
    if (!armFile.empty()) {
        const ArmParameters a = loadArmParameters(findAsset(armFile));
        s.arm = a;
    }
    MuscleParameters& p = s.biceps();
    if (!file.empty()) {
        const std::string name = p.name;
        p = loadMuscleParameters(findAsset(file));
        p.name = name;
    }
    auto check = [](const char* option, double v, const Bound& b) {
        try {
            checkField(option, v, b);
        } catch (const FieldError& e) {
            throw InputError(std::string("option ") + e.what());
        }
    };
    const MuscleSpec& primary = s.muscles[s.primary];
    if ((slowUnits || fastUnits) && primary.muscleModel != kDefaultMuscleModel)
        throw InputError(std::string(slowUnits ? "--slow-units" : "--fast-units") + ": muscle '" + p.name + "' is a " +
                         primary.muscleModel + " muscle (" + (muscleModel.empty() ? "model " + model : "--muscle-model") +
                         "), which has no motor units: it would be ignored (motor units are Virtual Muscle's)");
    if (slowUnits) check("--slow-units", *slowUnits, bounds::kMotorUnits), p.numSlowUnits = *slowUnits;
    if (fastUnits) check("--fast-units", *fastUnits, bounds::kMotorUnits), p.numFastUnits = *fastUnits;
    if ((slowUnits || fastUnits) && p.numSlowUnits + p.numFastUnits == 0)
        throw InputError("options --slow-units " + std::to_string(p.numSlowUnits) + " and --fast-units " +
                         std::to_string(p.numFastUnits) + ": expected at least one motor unit in all (without units "
                         "a muscle makes no active force)");
    if (mass) check("--mass", *mass, bounds::kMuscleMass), p.mass = *mass;
    if (tendonLength) check("--tendon-length", *tendonLength, bounds::kTendonLength), p.optimalTendonLength = *tendonLength;
    if (maxPathLength) {
        check("--max-path", *maxPathLength, bounds::kPathLength);
        p.maxPathLength = *maxPathLength;
        s.muscles[s.primary].maxPathFromRange = false;
    }
    if (!armFile.empty()) resolveMaxPathLengths(s);
    try {
        s.validate();
        return s;
    } catch (const FieldError& e) {
        throw InputError(std::string("muscle '") + p.name + "' (model " + model +
                         (file.empty() ? "" : ", muscle file " + file) + ", with command-line overrides): " + e.what());
    }
}

MuscleParameters MuscleOptions::loadParameters() const {
    const ArmSetup s = loadSetup();
    s.requireVirtualMuscles("this command's force model and identifiers", s.primary);
    return s.calcBicepsParameters();
}

std::shared_ptr<const MuscleModel> MuscleOptions::build() const {
    const ArmSetup s = loadSetup();
    return s.buildMuscleModel(s.primary);
}

namespace {

void checkActivation(double U) { checkField("--activation", U, Bound::closed(0, 1)); }

}  // namespace

namespace {

void addMuscleCommands(CLI::App& app) {
    CLI::App* muscle = app.add_subcommand("muscle", "the muscle alone, path ends fixed (steady solve, sweeps, trials)");
    muscle->require_subcommand(1);

    // steady ---------------------------------------------------------------------------------
    {
        auto opts = std::make_shared<MuscleOptions>();
        auto path = std::make_shared<double>(0.375);
        auto U = std::make_shared<double>(1.0);
        CLI::App* c = muscle->add_subcommand("steady", "steady isometric force at one path length and activation");
        opts->add(*c);
        opts->addMuscleModel(*c);
        c->add_option("--path", *path, "path length P [m]")->capture_default_str();
        c->add_option("--activation", *U, "activation U in [0, 1]")->capture_default_str();
        c->callback([=] {
            checkActivation(*U);
            checkField("--path", *path, bounds::kPathLength);
            const std::shared_ptr<const MuscleModel> built = opts->build();
            const MuscleModel& m = *built;
            checkPathWithin(m, "--path", *path);
            const SteadyState s = m.calcSteadyState(*path, *U);
            if (!s.converged) throwSteadyFailure("--path", s.message);
            std::printf("muscle            %s\n", m.getName().c_str());
            std::printf("path length       %.6f m\nactivation        %.4f\n", *path, *U);
            std::printf("force Fse         %.4f N  (F0 = %.3f N)\n", s.force, m.getF0());
            std::printf("fascicle length   %.6f m  (L = %.6f L0)\n", s.fascicleLength, s.L);
            std::printf("tendon length     %.6f m\n", m.calcOutputs(*path, *U, s.states.data()).tendonLength);
        });
    }

    // sweep ----------------------------------------------------------------------------------
    {
        auto opts = std::make_shared<MuscleOptions>();
        auto from = std::make_shared<double>(0.27), to = std::make_shared<double>(0.43);
        auto step = std::make_shared<double>(0.0025);
        auto U = std::make_shared<double>(1.0);
        auto out = std::make_shared<std::string>("out/force_length.csv");
        auto plot = std::make_shared<std::string>();
        CLI::App* c = muscle->add_subcommand("sweep", "steady force over a range of path lengths (force-length)");
        opts->add(*c);
        opts->addMuscleModel(*c);
        c->add_option("--from", *from, "first path length [m]")->capture_default_str();
        c->add_option("--to", *to, "last path length [m] (at most P_max)")->capture_default_str();
        c->add_option("--step", *step, "path length step [m]")->capture_default_str();
        c->add_option("--activation", *U, "activation U in [0, 1]")->capture_default_str();
        c->add_option("--out", *out, "CSV output")->capture_default_str();
        c->add_option("--plot", *plot, "PNG plot output (optional)");
        c->callback([=] {
            checkActivation(*U);
            checkField("--step", *step, Bound::positive("m"));
            if (!(*to >= *from))
                throw InputError("--to " + formatNumber(*to) + " m is below --from " + formatNumber(*from) +
                                 " m: expected --to at least --from");
            if (*to > *from && (*to - *from) / *step + 1e-9 < 1)   // as the sweep counts its lengths
                throw InputError("--step " + formatNumber(*step) + " m is longer than --from " + formatNumber(*from) +
                                 " m to --to " + formatNumber(*to) + " m: expected a step that gives two path lengths "
                                 "at least (or --to equal to --from for one)");
            if ((*to - *from) / *step > 1e6)
                throw InputError("--step " + formatNumber(*step) + " m over " + formatNumber(*from) + ".." +
                                 formatNumber(*to) + " m gives " + formatNumber(std::floor((*to - *from) / *step) + 1) +
                                 " path lengths: expected at most 1000001");
            OutputFiles files;  // both appear at the end, or neither
            opts->declareInputs(files);
            const std::string csvPath = files.add("--out", *out, true), plotPath = files.add("--plot", checkPngPath("--plot", *plot));
            const std::shared_ptr<const MuscleModel> built = opts->build();
            const MuscleModel& m = *built;
            for (const auto& [option, P] : {std::pair<const char*, double>{"--from", *from}, {"--to", *to}})
                checkPathWithin(m, option, P);
            Table t({"path_length_m", "activation", "force_N", "fascicle_length_m", "converged"});
            const int n = int(std::floor((*to - *from) / *step + 1e-9)) + 1;
            std::vector<double> x, y;
            std::vector<double> failed;   // path lengths with no steady state
            std::string why;
            for (int i = 0; i < n; ++i) {
                const double P = std::min(*to, *from + i * *step);
                const SteadyState s = m.calcSteadyState(P, *U);
                t.appendRow({P, *U, s.converged ? s.force : NAN, s.converged ? s.fascicleLength : NAN,
                             s.converged ? 1.0 : 0.0});
                if (s.converged) {
                    x.push_back(100 * P);
                    y.push_back(s.force);
                } else {
                    if (failed.empty()) why = s.message;
                    failed.push_back(P);
                }
            }
            if (int(failed.size()) == n) throwSteadyFailure("--from " + formatNumber(*from) + " to --to " + formatNumber(*to), why);
            if (!failed.empty())   // said, not left to a column of NaN
                std::fprintf(stderr, "note: %zu of %d path lengths (%s to %s m) have no steady state; their rows hold NaN "
                             "and converged 0 (the first: %s)\n", failed.size(), n, formatNumber(failed.front()).c_str(),
                             formatNumber(failed.back()).c_str(), why.c_str());
            files.writeWith(csvPath, [&](const std::string& p) { t.writeCsv(p); });
            if (!plot->empty()) {
                PlotSpec spec;
                spec.title = m.getName() + ": steady force vs path length";
                spec.xLabel = "path length (cm)";
                spec.yLabel = "force Fse (N)";
                spec.series.push_back({"U = " + std::to_string(*U).substr(0, 4), x, y});
                files.writeWith(plotPath, [&](const std::string& p) { writePlotPng(p, spec); });
            }
            files.commit();
            std::printf("wrote %s (%d path lengths)\n", out->c_str(), n);
            if (!plot->empty()) std::printf("wrote %s\n", plot->c_str());
        });
    }

    // trial ----------------------------------------------------------------------------------
    {
        auto opts = std::make_shared<MuscleOptions>();
        auto settings = std::make_shared<MuscleIsometricSettings>();
        auto U = std::make_shared<double>(1.0);
        auto onset = std::make_shared<double>(0.0);
        auto rise = std::make_shared<double>(0.0);
        auto out = std::make_shared<std::string>("out/muscle_trial.csv");
        auto plot = std::make_shared<std::string>();
        auto trace = std::make_shared<std::string>();
        CLI::App* c = muscle->add_subcommand("trial", "isometric time integration (CPodes) at a fixed path length");
        opts->add(*c);
        opts->addMuscleModel(*c);
        c->add_option("--path", settings->pathLength, "path length P [m]")->capture_default_str();
        c->add_option("--activation", *U, "activation level after onset, in [0, 1]")->capture_default_str();
        c->add_option("--onset", *onset, "activation onset time [s] (0 before it)")->capture_default_str();
        c->add_option("--rise", *rise, "rise time of the activation ramp [s] (0 = step)")->capture_default_str();
        c->add_option("--activation-trace", *trace,
                      "CSV with columns time_s,activation: a sampled U(t) instead of --activation/--onset")
            ->excludes("--activation")->excludes("--onset")->excludes("--rise");
        c->add_option("--duration", settings->duration, "simulated time [s]")->capture_default_str();
        c->add_option("--rate", settings->sampleRate, "output samples per second [Hz]")->capture_default_str();
        c->add_option("--accuracy", settings->integration.accuracy, "integrator relative accuracy")->capture_default_str();
        c->add_flag("--steady-start", settings->startSteady, "start from the steady state at U(0)");
        c->add_option("--out", *out, "CSV output")->capture_default_str();
        c->add_option("--plot", *plot, "PNG plot of force and activation (optional)");
        c->callback([=] {
            checkActivation(*U);
            checkField("--path", settings->pathLength, bounds::kPathLength);
            checkField("--onset", *onset, Bound::nonNegative("s"));
            checkField("--rise", *rise, Bound::nonNegative("s"));
            if (trace->empty() && *U > 0 && !(*onset < settings->duration))
                throw InputError("--onset " + formatNumber(*onset) + " s is not before the end of the trial (--duration " +
                                 formatNumber(settings->duration) + " s): expected an onset before the end (the "
                                 "activation would never start)");
            runNamingOptions({{"duration", "--duration"}, {"sample_rate", "--rate"}, {"accuracy", "--accuracy"}},
                             [&] { settings->integration.validate(); checkField("duration", settings->duration,
                                                                               Bound::positive("s"));
                                   checkField("sample_rate", settings->sampleRate, Bound::positive("Hz"));
                                   calcNumSamples(settings->duration, settings->sampleRate); });
            OutputFiles files;  // both appear at the end, or neither
            opts->declareInputs(files);
            files.addInput("--activation-trace", *trace);
            const std::string csvPath = files.add("--out", *out, true), plotPath = files.add("--plot", checkPngPath("--plot", *plot));
            const std::shared_ptr<const MuscleModel> built = opts->build();
            const MuscleModel& m = *built;
            checkPathWithin(m, "--path", settings->pathLength, !settings->startSteady);
            MuscleIsometricSettings s = *settings;
            if (!trace->empty()) s.activation = loadActivationTrace(*trace);
            else if (*rise > 0) s.activation = ActivationProfile::ramp(*onset, *onset + *rise, 0.0, *U);
            else if (*onset > 0) s.activation = ActivationProfile::step(*onset, 0.0, *U);
            else s.activation = ActivationProfile::constant(*U);
            noteUnreachedActivation(s.activation, s.duration);
            IntegrationStats stats;
            Table t;
            runNamingOptions({{"path_length", "--path"}}, [&] { t = runMuscleIsometric(m, s, &stats); });
            files.writeWith(csvPath, [&](const std::string& p) { t.writeCsv(p); });
            const int last = t.getNumRows() - 1;
            if (!plot->empty()) {
                PlotSpec spec;
                spec.title = m.getName() + ": isometric trial at P = " + std::to_string(100 * s.pathLength).substr(0, 5) + " cm";
                spec.xLabel = "time (s)";
                spec.yLabel = "force Fse (N)";
                spec.series.push_back({"force", t.getColumn("time_s"), t.getColumn("force_N")});
                files.writeWith(plotPath, [&](const std::string& p) { writePlotPng(p, spec); });
            }
            files.commit();
            std::printf("final force %.4f N at t = %.3f s (%d steps, %d restarts); wrote %s\n", t.get(last, "force_N"),
                        t.get(last, "time_s"), stats.steps, stats.restarts, out->c_str());
            if (!plot->empty()) std::printf("wrote %s\n", plot->c_str());
        });
    }
}

const CommandRegistrar registerMuscle(10, addMuscleCommands);

}  // namespace

}  // namespace armsim::cli
