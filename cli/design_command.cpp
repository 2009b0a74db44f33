// armsim design: the torque protocol that minimises the synergist-aware identifier's expected posterior
// uncertainty of the biceps mass and tendon length over a population (studies/experiment_design.h),
// compared with the thesis's five-angle protocol, predicted and (with --validate-subjects) obtained.
#include "basics/quick_run.h"
#include "basics/csv.h"
#include "basics/format.h"
#include "basics/output_folder.h"
#include "basics/plot.h"
#include "cli/commands.h"
#include "muscles/muscle_file.h"
#include "studies/experiment_design.h"
#include "studies/torque_validation.h"

#include <cmath>
#include <cstdio>
#include <memory>

namespace armsim::cli {

namespace {

struct DesignOptions {
    std::string population;
    std::vector<double> angles = {15, 30, 45, 60, 75, 90, 105, 120, 135};
    std::vector<double> levels;
    std::vector<double> postures;
    std::string criterion = "considered";
    bool noExtension = false;
    int trials = 15;
    int repetitions = 3;
    int draws = 32;
    unsigned seed = 1;
    double activationSd = 0.02;
    int jobs = 2;
    int validateSubjects = 0;
    bool freeSlowFraction = false;
    double budget = 0;           // lab minutes: > 0 designs across channels
    std::string out = "out/design";
};

void printPrediction(const ProtocolPrediction& p) {
    std::printf("  %-10s %3d trials  sd(ln M) %5.1f %%  sd(L0T) %5.1f mm  sd(ln F0) %5.1f %%  sd(total flexor strength) %4.1f %%  "
                "criterion %.2f  (prior: %.1f %%, %.1f mm, %.1f %%, %.1f %%; %d draws)\n",
                p.name.c_str(), p.trials, 100 * p.massSd, 1000 * p.tendonSd, 100 * p.maxForceSd, 100 * p.flexorStrengthSd,
                p.criterion, 100 * p.priorMassSd, 1000 * p.priorTendonSd, 100 * p.priorMaxForceSd,
                100 * p.priorFlexorStrengthSd, p.drawsUsed);
    if (std::isfinite(p.massSdConsidered))
        std::printf("             with what the fit shares or holds and people vary (the intervals' widening): "
                    "sd(ln M) %.1f %%, sd(L0T) %.1f mm, sd(ln F0) %.1f %%\n", 100 * p.massSdConsidered,
                    1000 * p.tendonSdConsidered, 100 * p.maxForceSdConsidered);
    std::printf("             posterior correlation of ln M with:");
    for (std::size_t j = 0; j < p.parameterNames.size(); ++j)
        if (std::abs(p.massCorrelation[j]) >= 0.3 && p.massCorrelation[j] < 0.999)
            std::printf(" %s %+.2f;", p.parameterNames[j].c_str(), p.massCorrelation[j]);
    std::printf("\n");
}

// The greedy picks, one line each with the criterion after it (and the lab minutes so far).
void printDesignSteps(const DesignResult& d, bool channels, int repetitions) {
    std::printf("greedy picks (%s, criterion after the pick; 1 = both sds at the goals 10 %%, 1 cm):\n",
                channels ? "largest drop per lab minute" : ("block of " + std::to_string(repetitions) + " trials each").c_str());
    double minutes = 0;
    for (std::size_t k = 0; k < d.steps.size(); ++k) {
        const DesignStep& step = d.steps[k];
        const std::string what = step.item == "torque" || step.item == "ultrasound"
                                     ? std::string(step.item == "ultrasound" ? "ultrasound at " : "") +
                                           getEffortName(step.condition.effort) + " " +
                                           (step.condition.level == 1 ? "MVC" : formatNumber(100 * step.condition.level) + " %") +
                                           " at " + formatNumber(step.condition.flexionDeg) + " deg" +
                                           (std::isnan(step.condition.rotationDeg)
                                                ? std::string()
                                                : ", forearm " + formatNumber(step.condition.rotationDeg) + " deg")
                                     : step.item;
        minutes += std::isfinite(step.minutes) ? step.minutes : 0;
        std::printf("  %2zu. %-38s criterion %.3f%s\n", k + 1, what.c_str(), step.criterion,
                    channels ? (", " + formatNumber(minutes) + " min").c_str() : "");
    }
}

// design_criterion.png: the criterion after each pick against trials or lab minutes spent.
PlotSpec makeDesignPlot(const DesignResult& d, bool channels, int repetitions) {
    PlotSpec plot;
    plot.title = channels ? "Greedy design across channels: expected criterion after each pick"
                          : "Greedy design: expected criterion after each block of trials";
    plot.xLabel = channels ? "lab minutes" : "trials";
    plot.yLabel = "criterion (1 = sds at the goals)";
    PlotSeries greedy{"designed", {}, {}, false, 0};
    double spent = 0;
    for (std::size_t k = 0; k < d.steps.size(); ++k) {
        spent += channels ? d.steps[k].minutes : double(repetitions);
        greedy.x.push_back(spent);
        greedy.y.push_back(d.steps[k].criterion);
    }
    plot.series = {greedy};
    if (!channels)  // the reference's lab minutes are not on this axis with channels
        plot.series.push_back({"thesis five angles", {double(d.reference.trials)}, {d.reference.criterion}, true, 1});
    return plot;
}

// Every file a design writes: an earlier design's that this one does not write is removed at the commit.
const std::vector<std::string> kDesignFiles = {"designed_protocol.yaml", "design_predictions.csv", "design_steps.csv",
                                               "design_criterion.png", "design_validation.csv"};

// --validate-subjects' work, counted (and bounded) before the design's: the reference protocol's fits
// twice, and the channels fit of a design across channels.
void announceValidation(const Population& population, const DesignSettings& s, const TorqueProtocol& reference,
                        int subjects, bool channels) {
    ElbowValidationSettings v;
    v.subjects = capForQuickRun(subjects, kQuickSubjects, "validation subjects");
    v.activationSd = s.activationSd;
    v.protocol = reference;
    long perProtocol = 0;
    runNamingOptions({{"subjects", "--validate-subjects"}},
                     [&] { perProtocol = countElbowValidationFits(population, population, v); });
    std::printf("then validation of both protocols on %d subject%s: about %ld fits\n", v.subjects, v.subjects == 1 ? "" : "s",
                2 * perProtocol + (channels ? long(v.subjects) : 0L));
}

void runDesign(const DesignOptions& o) {
    checkOutputFolder("--out", o.out);
    const Population population = o.population.empty() ? loadDefaultPopulation() : loadPopulation(findAssetFor("--population", o.population));
    DesignSettings s;
    s.flexionDeg = o.angles;
    s.levels = o.levels;
    s.postures = o.postures;
    s.ownModelCriterion = o.criterion == "own";
    s.extension = !o.noExtension;
    s.trials = o.trials;
    s.repetitions = o.repetitions;
    s.draws = o.draws;
    s.seed = o.seed;
    s.activationSd = o.activationSd;
    s.jobs = o.jobs;
    s.freeSlowFraction = o.freeSlowFraction;
    s.budgetMinutes = o.budget;
    runNamingOptions({{"angles", "--angles"}, {"levels", "--levels"}, {"postures", "--postures"},
                      {"repetitions", "--repetitions"}, {"trials", "--trials"}, {"draws", "--draws"},
                      {"activation_sd", "--activation-sd"}, {"jobs", "--jobs"}, {"budget", "--budget"}},
                     [&] { s.validate(); });
    const std::string budget = s.budgetMinutes > 0 ? formatNumber(s.budgetMinutes, 6) + " lab minutes"
                                                   : std::to_string(s.trials) + " trials";
    std::printf("experiment design for the synergist-aware identifier: population '%s', budget %s in blocks "
                "of %d, angles %s deg, extension MVCs %s, submaximal EMG-feedback levels %s, VA %s; %d prior draws\n",
                population.name.c_str(), budget.c_str(), s.repetitions, formatList(o.angles).c_str(), s.extension ? "allowed" : "not allowed",
                o.levels.empty() ? "none" : formatList(o.levels).c_str(),
                s.activationSd > 0 ? ("measured (sd " + formatNumber(s.activationSd) + ")").c_str() : "not measured",
                s.draws);
    const TorqueProtocol thesis = [] { TorqueProtocol t; t.name = "thesis"; return t; }();
    const bool channels = s.budgetMinutes > 0;
    if (o.validateSubjects > 0) announceValidation(population, s, thesis, o.validateSubjects, channels);
    if (channels)
        std::printf("across channels: budget %s lab minutes (MVC block %s, EMG set-up %s, ultrasound per condition %s, volume "
                    "scan %s, anthropometry %s min: docs/channels.md)\n",
                    formatNumber(s.budgetMinutes, 6).c_str(), formatNumber(s.costs.mvcBlock).c_str(),
                    formatNumber(s.costs.emgSetup).c_str(), formatNumber(s.costs.ultrasoundAngle).c_str(),
                    formatNumber(s.costs.volumeScan).c_str(), formatNumber(s.costs.anthropometry).c_str());
    std::fflush(stdout);
    auto progress = [](int done, int n) { printProgress("design", done, n); };
    DesignResult d;
    runNamingOptions({{"postures", "--postures"}}, [&] {
        d = channels ? designChannelProtocol(population, s, thesis, progress) : designProtocol(population, s, thesis, progress);
    });
    const ProtocolPrediction& reference = d.reference;

    printDesignSteps(d, channels, s.repetitions);
    std::printf("designed protocol: %s\n", describeConditions(d.protocol).c_str());
    std::printf("predicted uncertainty (Laplace, mean over prior draws):\n");
    printPrediction(reference);
    printPrediction(d.predicted);
    if (channels) {
        // The shipped protocols beside the design; two_axis.yaml on a prior whose forearm rotates.
        for (const char* name : {"recommended.yaml", "two_axis.yaml"}) {
            const TorqueProtocol shipped = readTorqueProtocol(findAsset(std::string("protocols/") + name));
            if (shipped.readsForearmTorque() && !population.base.arm.forearmRotation.enabled) continue;
            std::printf("  (%s, %.0f lab minutes:)\n", name, s.costs.calcMinutes(shipped));
            printPrediction(predictProtocol(population, shipped, s));
        }
    }

    OutputFolder out(o.out, OutputFolder::Mode::AddFiles);
    out.setResultFileNames(kDesignFiles);
    const std::string protocolPath = out.getTargetPath("designed_protocol.yaml");
    out.write("designed_protocol.yaml", "# Written by `armsim design` (studies/experiment_design.h). Run it with\n"
                                        "#   armsim protocol " + protocolPath + "\n#   armsim validate --truth elbow --protocol " +
                                        protocolPath + "\n" + formatTorqueProtocol(d.protocol));
    out.write("design_predictions.csv", formatPredictionsCsv({reference, d.predicted}));
    out.write("design_steps.csv", formatDesignStepsCsv(d));
    const PlotSpec plot = makeDesignPlot(d, channels, s.repetitions);
    out.writeWith("design_criterion.png", [&](const std::string& p) { writePlotPng(p, plot); });
    // The design's files and its validation appear together at the end, or (an error, a stop) neither.
    auto commitDesign = [&] {
        out.commit();
        std::printf("wrote %s, %s/design_predictions.csv, design_steps.csv, design_criterion.png%s\n",
                    protocolPath.c_str(), o.out.c_str(), o.validateSubjects > 0 ? ", design_validation.csv" : "");
    };
    if (o.validateSubjects <= 0) return commitDesign();
    std::printf("validation of both protocols on %d subjects (seed %u):\n", o.validateSubjects, o.seed);
    const std::vector<DesignValidationRow> rows =
        validateDesign(population, s, thesis, d, capForQuickRun(o.validateSubjects, kQuickSubjects, "validation subjects"),
                       [](const std::string& protocol, int done, int n) { printProgress("validate " + protocol, done, n); });
    for (const DesignValidationRow& r : rows) {
        const ElbowValidationSummary& x = r.obtained;
        if (x.converged == 0)
            std::printf("  %-9s %-13s no fit converged in %d subjects%s\n", r.protocol.c_str(), x.method.c_str(), x.subjects,
                        x.method == "synergist-va" ? " (its twitch interpolation needs maximal efforts: the protocol has none)" : "");
        else
            std::printf("  %-9s %-13s mass bias %+5.1f %%  RMSE %5.1f %% (predicted sd %4.1f %%)  coverage %.2f  "
                        "95 %% width %5.1f %%   L0T RMSE %5.1f mm (predicted %4.1f mm)  coverage %.2f\n",
                        r.protocol.c_str(), x.method.c_str(), 100 * x.massBias, 100 * x.massRmse, 100 * r.predicted.massSd,
                        x.massCoverage, 100 * x.massIntervalWidth, 1000 * x.tendonRmse, 1000 * r.predicted.tendonSd,
                        x.tendonCoverage);
    }
    std::printf("  (predicted: %s; the RMSE is the obtained counterpart of the predicted sd)\n",
                channels ? "the thesis protocol's for synergist-va, the design's for the channels fit"
                         : o.activationSd > 0 ? "synergist-va" : "synergist-aware");
    out.write("design_validation.csv", formatDesignValidationCsv(rows));
    commitDesign();
}

void addDesignCommand(CLI::App& app) {
    auto o = std::make_shared<DesignOptions>();
    CLI::App* c = app.add_subcommand(
        "design", "torque protocol minimising the synergist-aware identifier's expected uncertainty of biceps mass "
                  "and tendon length (Bayesian, Laplace approximation, greedy), vs the thesis's five angles");
    c->add_option("--population", o->population, "prior population (default assets/subjects/default_population.yaml)");
    addNumberListOption(*c, "--angles", o->angles, "allowed flexion angles [deg, 0 = extended], comma-separated")
        ->capture_default_str();
    addNumberListOption(*c, "--levels", o->levels,
                  "allowed submaximal levels (EMG feedback, fractions of MVC in (0, 1)), comma-separated; default none");
    c->add_flag("--no-extension", o->noExtension, "no extension MVCs");
    c->add_option("--criterion", o->criterion,
                  "widths minimised: considered (with what the identifier's fit shares or holds and people vary: what "
                  "its intervals report) or own (the Laplace widths of the fit's own model)")
        ->capture_default_str()
        ->check(CLI::IsMember({"considered", "own"}));
    addNumberListOption(*c, "--postures", o->postures,
                        "forearm postures allowed besides the model's [deg, + = supination, -90..90], comma-separated: "
                        "flexion, extension, supination and pronation MVCs in them, both transducer axes read; default none");
    c->add_option("--budget", o->budget,
                  "lab minutes: design across channels (MVC blocks, ultrasound, EMG, volume scans, anthropometry; "
                  "costs in docs/channels.md) instead of a trial budget")
        ->transform(inRange(1.0, 10000.0));
    c->add_flag("--free-slow-fraction", o->freeSlowFraction,
                "the identifier frees the flexors' slow-fibre fractions (biceps heads, synergists)");
    c->add_option("--trials", o->trials, "budget: total trials, a multiple of --repetitions (at most 100; default "
                                         "the most whole blocks within 15)");
    c->add_option("--repetitions", o->repetitions, "trials per picked condition (>= 2 lets the identifier estimate its noise)")
        ->capture_default_str()
        ->transform(inRange(1, 100));
    c->add_option("--draws", o->draws, "prior draws the expected uncertainty averages over")->capture_default_str()->transform(inRange(1, 100000));
    c->add_option("--seed", o->seed, "seed of the prior draws and of --validate-subjects")->capture_default_str();
    c->add_option("--activation-sd", o->activationSd,
                  "voluntary activation measured by twitch interpolation to this sd (0: not measured)")
        ->capture_default_str()
        ->transform(inRange(0.0, 0.5));
    c->add_option("--jobs", o->jobs, "threads")->capture_default_str()->transform(inRange(1, 64));
    c->add_option("--validate-subjects", o->validateSubjects,
                  "also run `validate --truth elbow` with the thesis's and the designed protocol on this many subjects")
        ->capture_default_str()
        ->transform(inRange(0, 1000000));
    c->add_option("--out", o->out, "output directory")->capture_default_str();
    c->callback([o, c] {
        if (c->count("--budget") && c->count("--trials"))
            throw InputError("--trials with --budget: a lab-minute budget sets how many trials fit, so --trials would "
                             "be ignored; give one or the other");
        if (!c->count("--trials")) o->trials = getDefaultDesignTrials(o->repetitions);   // whole blocks
        runDesign(*o);
    });
}

const CommandRegistrar registerDesign(57, addDesignCommand);

}  // namespace

}  // namespace armsim::cli
