// armsim model: list the shipped models, show one (muscle table, moment arms, steady MVC torque-angle
// curves as CSV + PNG), score it against anatomy targets, calibrate a model's muscle strength to the elbow
// target curves.
#include "basics/errors.h"
#include "basics/files.h"
#include "basics/format.h"
#include "cli/commands.h"
#include "experiments/model_check.h"
#include "experiments/model_report.h"
#include "experiments/osim_report.h"
#include "model/osim_forward.h"
#include "muscles/muscle_file.h"
#include "muscles/muscle_models.h"
#include "model/anatomy_calibration.h"
#include "model/strength_calibration.h"

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

namespace armsim::cli {

namespace {

void printSummary(const char* effort, const MvcCurveSummary& s) {
    std::printf("%s MVC: peak %.1f N m at %.1f deg flexion; %.1f N m at 90 deg\n", effort, s.peakTorque,
                s.peakFlexionDeg, s.torqueAt90);
}

// Writes the model report to out and prints its muscle table and MVC summary.
void showModel(const ArmSetup& setup, const std::string& out, double step, const ElbowReference& ref) {
    const ModelReportFiles r = writeModelReport(setup, out, step, ref);
    const Table& t = r.muscles;
    std::printf("model %s: %s\n%-9s %-8s %-14s %8s %7s %7s %7s %6s  calibration k f t\n", setup.name.c_str(),
                setup.description.c_str(), "muscle", "group", "muscle model", "F0 (N)", "L0 (m)", "L0T (m)", "M (kg)", "slow");
    for (int i = 0; i < t.getNumRows(); ++i) {
        const std::vector<double> row = t.getRow(i);
        const std::string& model = setup.muscles[i].muscleModel;
        std::printf("%-9s %-8s %-14s %8.1f %7.4f %7.4f %7.4f %6.3f  %.3f %.3f %.3f\n", setup.muscles[i].params.name.c_str(),
                    getMuscleGroupName(setup.muscles[i].group), model.empty() ? kDefaultMuscleModel : model.c_str(), row[0],
                    row[1], row[2], row[3], row[5], row[7], row[8], row[9]);
    }
    printSummary("flexion", r.flexion);
    printSummary("extension", r.extension);
    std::printf("primary muscle (%s) share of the flexors' torque at 90 deg: %.1f %%\n",
                setup.muscles[setup.primary].params.name.c_str(), 100 * r.primaryShareAt90);
    for (const std::string& f : r.files) std::printf("wrote %s\n", showPath(f).c_str());
}

// Prints the per-kind summary, what was not scored and every failed target of a check written to files.
void printModelCheck(const std::string& name, const ModelCheckResult& r, const std::vector<AnatomyTarget>& targets,
                     const char* unscoredWhy) {
    std::printf("model %s against %zu targets:\n", name.c_str(), targets.size());
    // Targets of muscles this model lacks are not scored (one target file serves several models): said, not silent.
    std::vector<std::string> unscored;
    for (const AnatomyTarget& t : targets) {
        bool found = false;
        for (const TargetScore& s : r.scores)
            found = found || (s.target.where == t.where && s.target.muscle == t.muscle);
        if (!found) unscored.push_back(t.where + (t.muscle.empty() ? "" : " (" + t.muscle + ")"));
    }
    if (!unscored.empty())
        std::printf("  not scored: %zu targets the model has nothing for (%s): %s%s\n", unscored.size(), unscoredWhy,
                    unscored.front().c_str(), unscored.size() > 1 ? ", ..." : "");
    for (const ScoreSummary& s : r.summary)
        std::printf("  %-14s %-9s %3d of %3d pass\n", getTargetKindName(s.kind), s.muscle.empty() ? "all" : s.muscle.c_str(),
                    s.passed, s.scored);
    for (const TargetScore& s : r.scores)
        if (!s.pass)
            std::printf("  fail: %s %s%s%s: %g outside [%g, %g] +/- %g (SI units; %s)\n", getTargetKindName(s.target.kind),
                        s.muscle.c_str(), describeTargetCondition(s.target).c_str(),
                        std::isfinite(s.target.flexionDeg) ? (" at " + formatNumber(s.target.flexionDeg) + " deg").c_str() : "",
                        s.value, s.target.lower, s.target.upper, s.target.tolerance, s.target.where.c_str());
    for (const std::string& f : r.files) std::printf("wrote %s\n", showPath(f).c_str());
}

// Writes the scorecard of an armsim model to out and prints it.
void checkModel(const ArmSetup& setup, const std::vector<AnatomyTarget>& targets, const std::string& out) {
    printModelCheck(setup.name, writeModelCheck(setup, targets, out), targets, "no such muscle, a share family missing, or no forearm rotation");
}

void addModelCommands(CLI::App& app) {
    CLI::App* model = app.add_subcommand("model", "model files: list, show, check, calibrate");
    model->require_subcommand(1);

    model->add_subcommand("list", "names of the shipped models (assets/models/)")->callback([] {
        for (const std::string& n : listModels()) {
            const ArmSetup s = loadModel(n);
            std::printf("%-10s %d muscle(s)  %s\n", n.c_str(), s.getNumMuscles(), s.description.c_str());
        }
    });

    {
        auto name = std::make_shared<std::string>(kDefaultSubjectModel);
        auto out = std::make_shared<std::string>("out/model");
        auto step = std::make_shared<double>(5.0);
        auto reference = std::make_shared<std::string>();
        CLI::App* c = model->add_subcommand(
            "show", "muscle table, moment arms and steady MVC torque-angle curves (CSV + PNG)");
        auto muscleModel = std::make_shared<std::string>();
        c->add_option("--model", *name, "model name or file (an armsim .yaml or an OpenSim .osim)")->capture_default_str();
        c->add_option("--muscle-model", *muscleModel,
                      "every muscle's model: virtual_muscle, thelen2003 or degroote2016 (default: the model file's)");
        c->add_option("--out", *out, "output directory")->capture_default_str();
        c->add_option("--step", *step, "angle step [deg]")->capture_default_str();
        c->add_option("--reference", *reference,
                      "published reference data (default assets/measured/elbow_reference.yaml)");
        auto coordinate = std::make_shared<std::string>();
        c->add_option("--coordinate", *coordinate,
                      "an OpenSim model's coordinate to sweep (default: its only moving one)");
        c->callback([=] {
            checkOutputFolder("--out", *out);
            if (!(*step >= 0.01 && *step <= 90))   // before any folder is made; 0.01 deg: at most ~14000 angles
                throw InputError("--step = " + formatNumber(*step) + " deg: expected in [0.01, 90] (the angle step" +
                                 (*step > 0 && *step < 0.01 ? ", " + std::to_string(long(std::floor(140 / *step))) +
                                                                  " angles over the elbow's range)" : std::string(")")));
            // An OpenSim model: a file ending .osim, or a shipped name with only an .osim file.
            if (isOsimModel(*name)) {
                const std::string osim = findOsimModelFile(*name);
                const OsimModel m = readOsimFile(osim);
                OsimReportSettings s;
                s.coordinate = *coordinate;
                s.stepDeg = *step;
                s.muscleModel = *muscleModel;
                const OsimReportFiles r = writeOsimModelReport(m, s, *out);
                std::printf("model %s (%s): %zu muscles; swept %s\n", m.name.c_str(), osim.c_str(), m.muscles.size(),
                            r.coordinate.c_str());
                std::printf("steady torque, + direction muscles fully excited: peak %.1f N m at %.1f deg\n", r.peakPositive,
                            r.peakPositiveDeg);
                std::printf("steady torque, - direction muscles fully excited: peak %.1f N m at %.1f deg\n", r.peakNegative,
                            r.peakNegativeDeg);
                for (const std::string& f : r.files) std::printf("wrote %s\n", showPath(f).c_str());
                return;
            }
            if (!coordinate->empty()) throw InputError("--coordinate '" + *coordinate + "': only for OpenSim models (.osim)");
            const ElbowReference ref = reference->empty() ? loadDefaultElbowReference() : loadElbowReference(*reference);
            showModel(loadModelWithMuscles(*name, *muscleModel), *out, *step, ref);
        });
    }

    {
        auto name = std::make_shared<std::string>(kDefaultSubjectModel);
        auto out = std::make_shared<std::string>("out/model_check");
        auto targets = std::make_shared<std::string>();
        CLI::App* c = model->add_subcommand(
            "check", "score a model against anatomy targets: scorecard.csv, score_summary.csv, plots with the bands");
        auto muscleModel = std::make_shared<std::string>();
        c->add_option("--model", *name, "model name or file")->capture_default_str();
        c->add_option("--muscle-model", *muscleModel,
                      "every muscle's model: virtual_muscle, thelen2003 or degroote2016 (default: the model file's)");
        c->add_option("--targets", *targets, "target file (default assets/reference/elbow_targets.yaml)");
        c->add_option("--out", *out, "output directory")->capture_default_str();
        auto coordinate = std::make_shared<std::string>();
        c->add_option("--coordinate", *coordinate,
                      "an OpenSim model's coordinate scored as the elbow: its value in deg as flexion, + = flexion "
                      "(default: its only moving one)");
        c->callback([=] {
            checkOutputFolder("--out", *out);
            const std::vector<AnatomyTarget> t = targets->empty() ? loadDefaultAnatomyTargets() : loadAnatomyTargets(*targets);
            if (!isOsimModel(*name) && !coordinate->empty())
                throw InputError("--coordinate '" + *coordinate + "': only for OpenSim models (.osim)");
            try {
                if (isOsimModel(*name)) {
                    const OsimModel m = readOsimFile(findOsimModelFile(*name));
                    printModelCheck(m.name + " (OpenSim)", writeOsimModelCheck(m, *coordinate, *muscleModel, t, *out), t,
                                    "no such muscle, a share family missing, no muscle masses for volumes, no armsim forearm");
                } else {
                    checkModel(loadModelWithMuscles(*name, *muscleModel), t, *out);
                }
            } catch (const InputError& e) {   // an empty scorecard: name the file and the model
                if (std::string(e.what()).rfind("none of the targets", 0) != 0) throw;
                throw InputError("--targets " + (targets->empty() ? std::string("(the default)") : *targets) + " and --model " +
                                 *name + ": " + e.what());
            }
        });
    }

    {
        auto name = std::make_shared<std::string>("elbow");
        auto targets = std::make_shared<std::string>();
        CLI::App* c = model->add_subcommand(
            "calibrate", "fit muscle scales: to a target file (--targets: MVC, shares, optimum angles, volumes, "
                         "with priors) or, without it, strength to the elbow's target MVC curves; prints calibration lines");
        c->add_option("--model", *name, "model name or file")->capture_default_str();
        c->add_option("--targets", *targets, "anatomy target file (e.g. assets/reference/elbow_targets.yaml)");
        c->callback([=] {
            ArmSetup setup = loadModel(*name);
            if (!targets->empty()) {
                const std::vector<AnatomyTarget> t = loadAnatomyTargets(*targets);
                std::printf("fitting model %s to %s (specific tension, volume and fascicle length per group, "
                            "tendon and fascicle length per muscle; priors: model/anatomy_calibration.h)\n",
                            setup.name.c_str(), targets->c_str());
                std::fflush(stdout);
                AnatomyCalibrationOptions options;
                options.progress = [](int stage, int numStages, int passed, int total) {
                    std::printf("  stage %d of %d: %d of %d targets pass\n", stage, numStages, passed, total);
                    std::fflush(stdout);
                };
                const AnatomyCalibrationResult r = calibrateToAnatomy(setup, t, options);
                auto passed = [](const std::vector<TargetScore>& s) {
                    int n = 0;
                    for (const TargetScore& x : s) n += x.pass;
                    return n;
                };
                std::printf("  %s\n  targets passed: %d of %d as given, %d after\n", r.report.c_str(),
                            passed(r.before), int(r.before.size()), passed(r.after));
                for (const GroupScales& g : r.groups)
                    std::printf("  %-8s specific tension x%.3f, volume x%.3f, fascicle length x%.3f\n",
                                getMuscleGroupName(g.group), g.specificTension, g.volume, g.fascicleLength);
                for (const TargetScore& x : r.after) {
                    if (x.pass) continue;
                    const double u = getTargetFileToSi(x.target.kind);
                    std::printf("  fails: %s %s%s%s: %.4g, band %.4g..%.4g +/- %.4g %s (%s)\n", getTargetKindName(x.target.kind),
                                x.muscle.c_str(), describeTargetCondition(x.target).c_str(),
                                std::isfinite(x.target.flexionDeg) ? (" at " + formatNumber(x.target.flexionDeg) + " deg").c_str() : "",
                                x.value / u, x.target.lower / u, x.target.upper / u, x.target.tolerance / u,
                                getTargetFileUnit(x.target.kind), x.target.where.c_str());
                }
                setup = applyCalibration(setup, r.muscles);
            } else {
                for (const MvcTorqueTarget& target : {getElbowFlexionTarget(), getElbowExtensionTarget()}) {
                    std::printf("fitting the %s muscles to: %s\n", getMuscleGroupName(target.effort), target.source.c_str());
                    std::fflush(stdout);
                    StrengthCalibrationResult r = calibrateStrength(setup, target);
                    std::printf("  %s\n  torque error: rms %.2f N m, max %.2f N m\n", r.report.c_str(), r.rmsTorqueError,
                                r.maxTorqueError);
                    setup = applyCalibration(setup, r.muscles);
                }
            }
            std::printf("calibration lines for the model file:\n");
            for (const MuscleSpec& m : setup.muscles) {
                const MuscleCalibration& k = m.calibration;
                std::printf("  %-9s calibration: {force_scale: %.6f, fascicle_length_scale: %.6f, tendon_length_scale: %.6f",
                            m.params.name.c_str(), k.forceScale, k.fascicleLengthScale, k.tendonLengthScale);
                if (k.specificTensionScale != 1) std::printf(", specific_tension_scale: %.6f", k.specificTensionScale);
                std::printf("}\n");
            }
        });
    }
}

const CommandRegistrar registerModel(15, addModelCommands);
const MainJobStepRegistrar registerSubjectModel(
    25, "Anatomical twin (the virtual subject): muscles, moment arms, steady MVC torque-angle curves",
    [](const MainJobContext& ctx) {
        showModel(loadModel(kDefaultSubjectModel), ctx.outDir + "/model_twin", 5.0, loadDefaultElbowReference());
    });
const MainJobStepRegistrar registerTwinCheck(
    26, "Anatomical twin: scorecard against the anatomy targets (moment arms, MVC, volumes, shares, postures)",
    [](const MainJobContext& ctx) { checkModel(loadModel("twin"), loadDefaultAnatomyTargets(), ctx.outDir + "/check_twin"); });

}  // namespace

}  // namespace armsim::cli
