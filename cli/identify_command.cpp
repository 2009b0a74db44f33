// armsim identify: muscle mass and optimal tendon length (or other parameters) from measured MVC forces,
// with the steady or the faithful forward model; armsim validate: the identifiers against ground truth
// on synthetic MVC data; and the main-job step that identifies the thesis's and our own MVC data.
#include "basics/quick_run.h"
#include "basics/bound.h"
#include "basics/errors.h"
#include "basics/files.h"
#include "basics/format.h"
#include "basics/output_folder.h"
#include "basics/plot.h"
#include "basics/table.h"
#include "cli/commands.h"
#include "experiments/channels.h"
#include "studies/torque_validation.h"
#include "identification/faithful_model.h"
#include "identification/forward_choice.h"
#include "identification/identifier.h"
#include "identification/report_io.h"
#include "identification/thesis_cases.h"
#include "studies/validation.h"
#include "model/geometry.h"
#include "model/muscle_arm.h"
#include "muscles/muscle_file.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <filesystem>
#include <memory>

namespace armsim::cli {

namespace {

/// Parameter name with the short aliases of the command line (tendon_length, fascicle_length).
ParameterId parseParameter(const std::string& option, const std::string& name) {
    const std::string full = name == "tendon_length" ? "optimal_tendon_length"
                             : name == "fascicle_length" ? "optimal_fascicle_length"
                                                         : name;
    try {
        return parseParameterName(full);
    } catch (const InputError& e) {
        throw InputError(option + ": " + e.what() + " (or the aliases tendon_length, fascicle_length)");
    }
}

/// "name=value" -> (name, value).
std::pair<std::string, std::string> splitAssignment(const std::string& option, const std::string& text) {
    const auto eq = text.find('=');
    if (eq == std::string::npos || eq == 0)
        throw InputError(option + " '" + text + "': expected name=value");
    return {text.substr(0, eq), text.substr(eq + 1)};
}

struct ModelOptions {
    std::string model = "steady";
    std::string estimate = "moment-arm";
    double hold = 3.0, rate = 200.0;
    bool noWarmStart = false;
    int jobs = 2;

    void add(CLI::App& c, bool withModel) {
        if (withModel)
            c.add_option("--forward", model, "forward model: steady | faithful (Simbody arm in the loop) | corrected "
                                           "(steady iterations corrected by the faithful model)")
                ->capture_default_str()
                ->check(CLI::IsMember(getForwardModelNames()));
        c.add_option("--estimate", estimate, "faithful: force the experimenter reports: moment-arm | fixed-ratio | true")
            ->capture_default_str()
            ->check(CLI::IsMember({"moment-arm", "fixed-ratio", "true"}));
        c.add_option("--hold", hold, "faithful: effort duration in iterations [s] (mean of the last third)")
            ->capture_default_str();
        c.add_option("--rate", rate, "faithful: transducer sample rate in iterations [Hz]")->capture_default_str();
        c.add_option("--jobs", jobs, "faithful: trials run in parallel")->capture_default_str()->transform(inRange(1, 64));
    }
    ForwardModelChoice makeChoice() const {
        ForwardModelChoice c;
        c.model = model;
        c.estimate = parseForceEstimateName(estimate);
        c.holdDuration = hold;
        c.sampleRate = rate;
        c.warmStart = !noWarmStart;
        c.jobs = jobs;
        return c;
    }
};

struct IdentifyOptions {
    MuscleOptions muscle;
    std::string data;
    std::string method = "lm";
    std::vector<std::string> freeList = {"mass", "optimal_tendon_length"};
    std::vector<std::string> bounds, starts;
    ModelOptions model;
    double forceSd = NAN;
    std::string noise = "absolute";
    int multistart = 1;
    unsigned seed = 1;
    int maxIterations = 200;
    double tolerance = 0.1;
    int subject = -1;
    bool thesisCases = false;
    std::string out = "out/identify";
};

IdentificationReport runIdentification(const IdentificationProblem& pr, const IdentificationOptions& o,
                                       const ArmParameters& arm, const ModelOptions& m, bool verbose = true) {
    std::string iterationModel;
    IdentificationReport r = identifyAndRecheck(pr, o, arm, m.makeChoice(), &iterationModel);
    if (verbose && !iterationModel.empty()) std::printf("in the iterations: %s\n", iterationModel.c_str());
    return r;
}

void printThesisCases(const MuscleParameters& base, const ForceModel& model, const std::string& outDir) {
    const std::vector<ThesisCase> cases = reproduceThesisCases(base, model);
    std::printf("%s", formatThesisComparison(cases).c_str());
    const std::string path = outDir + "/thesis_cases_" + model.getName() + ".csv";
    writeFileAtomically(path, formatThesisCasesCsv(cases));
    std::printf("wrote %s\n", showPath(path).c_str());
}

void runIdentify(const IdentifyOptions& o) {
    checkOutputFolder("--out", o.out);
    const ArmSetup setup = o.muscle.loadSetup();
    const MuscleParameters base = setup.calcBicepsParameters();
    if (o.thesisCases) {
        if (o.model.model == "corrected")
            throw InputError("--thesis-cases: --forward corrected is not a single forward model; expected steady or faithful");
        if (o.model.model == "steady") {
            printThesisCases(base, SteadyForceModel(), o.out);
        } else {
            const FaithfulForceModel fast(setup.arm, o.model.makeChoice().makeIterationOptions());
            std::printf("thesis cases with the %s\n", fast.describe().c_str());
            printThesisCases(base, fast, o.out);
        }
        return;
    }
    if (o.data.empty()) throw InputError("identify: no data file given: expected DATA.csv or --thesis-cases");

    IdentificationProblem pr;
    pr.base = base;
    runNamingOptions({{"subject", "--subject"}}, [&] { pr.data = readArmObservations(findAsset(o.data), setup.arm, o.subject); });
    pr.unknowns.clear();
    const std::string freeList = formatList(o.freeList);
    for (const std::string& name : o.freeList) pr.unknowns.push_back(makeUnknown(parseParameter("--free", name)));
    if (pr.unknowns.empty()) throw InputError("--free '" + freeList + "': expected at least one parameter");
    auto findUnknown = [&](const std::string& option, const std::string& name) -> Unknown& {
        const ParameterId id = parseParameter(option, name);
        for (Unknown& u : pr.unknowns)
            if (u.id == id) return u;
        throw InputError(option + " " + name + ": not a free parameter (--free " + freeList + ")");
    };
    for (const std::string& b : o.bounds) {
        const auto [name, range] = splitAssignment("--bounds", b);
        const auto colon = range.find(':');
        if (colon == std::string::npos) throw InputError("--bounds '" + b + "': expected name=lo:hi");
        Unknown& u = findUnknown("--bounds", name);
        u.lower = parseNumber("--bounds " + name + " lower", range.substr(0, colon));
        u.upper = parseNumber("--bounds " + name + " upper", range.substr(colon + 1));
        // Inside what the parameter may be anywhere else (--mass, a muscle file): basics/bound.h.
        const Bound* physical = u.id == ParameterId::Mass ? &bounds::kMuscleMass
                              : u.id == ParameterId::OptimalTendonLength ? &bounds::kTendonLength : nullptr;
        if (physical) {
            checkField("--bounds " + name + " lower", u.lower, *physical);
            checkField("--bounds " + name + " upper", u.upper, *physical);
        }
    }
    for (const std::string& s : o.starts) {
        const auto [name, value] = splitAssignment("--start", s);
        findUnknown("--start", name).start = parseNumber("--start " + name, value);
    }

    IdentificationOptions io;
    io.method = parseMethodName(o.method);
    io.forceSd = o.forceSd;
    io.noise = parseNoiseModelName(o.noise);
    if (io.noise == NoiseModel::Relative && !std::isnan(o.forceSd)) io.relativeForceSd = o.forceSd, io.forceSd = NAN;
    io.starts = o.multistart;
    io.progress = [](int done, int total) { printProgress("lm starts", done, total); };
    io.seed = o.seed;
    io.maxIterations = o.maxIterations;
    io.forceTolerance = o.tolerance;
    // A tolerance every measured force already meets would end the fit at its start.
    double largest = 0;
    for (const Observation& x : pr.data.points) largest = std::max(largest, x.force);
    if (o.tolerance >= largest)
        throw InputError("--tolerance = " + formatNumber(o.tolerance) + " N: not below the largest measured force, " +
                         formatNumber(largest) + " N (" + pr.data.source + "): expected a tolerance the fit must work to meet");

    IdentificationReport r;
    try {
        runNamingOptions({{"options.max_iterations", "--max-iterations"}, {"options.force_tolerance", "--tolerance"},
                          {"options.force_sd", "--force-sd"}, {"options.relative_force_sd", "--force-sd"},
                          {"options.starts", "--multistart"}, {"protocol.sample_rate", "--rate"},
                          {"protocol.hold", "--hold"}},
                         [&] { r = runIdentification(pr, io, setup.arm, o.model); });
    } catch (const FieldError& e) {   // an unknown's field, in the options' words: unknowns.<name>.<what>
        const std::string& f = e.getField();
        const auto dot = f.rfind('.');
        if (f.rfind("unknowns.", 0) != 0 || dot == std::string::npos || dot < 9) throw;
        const std::string name = f.substr(9, dot - 9), what = f.substr(dot + 1);
        const bool started = std::any_of(o.starts.begin(), o.starts.end(), [&](const std::string& x) {
            return parseParameter("--start", splitAssignment("--start", x).first) == parseParameter("--free", name);
        });   // --start tendon_length=... names optimal_tendon_length too
        if (what == "lower" || what == "upper") {
            const bool bounded = std::any_of(o.bounds.begin(), o.bounds.end(), [&](const std::string& b) {
                return parseParameter("--bounds", splitAssignment("--bounds", b).first) == parseParameter("--free", name);
            });
            throw InputError((bounded ? "--bounds " + name + " " + what
                                      : "the default " + what + " bound of " + name + " (give --bounds " + name + "=LO:HI)") +
                             " " + e.getDetail());
        }
        if (what == "start")
            throw InputError((started ? "--start " + name : "the default start of " + name + " (give --start " + name +
                                                                "=VALUE inside --bounds)") + " " + e.getDetail());
        if (what == "id") throw InputError("--free " + e.getDetail());
        throw;
    }
    std::printf("%s", formatReport(r).c_str());
    for (const std::string& p : writeReportFiles(r, o.out)) std::printf("wrote %s\n", p.c_str());
}

void addIdentifyCommand(CLI::App& app) {
    auto o = std::make_shared<IdentifyOptions>();
    CLI::App* c = app.add_subcommand("identify", "identify muscle parameters (default: mass and optimal tendon length) "
                                                 "from measured isometric forces");
    c->add_option("data", o->data, "force CSV: path_m | path_cm | angle_deg, force_N [, trial, subject, activation]");
    c->add_option("--method", o->method, "lm | false-position | ilc-standard | ilc-constant | ilc-secant | "
                                         "ilc-bounded-secant | ilc-sign-search")
        ->capture_default_str()
        ->check(CLI::IsMember(getMethodNames()));
    addNameListOption(*c, "--free", o->freeList, "comma-separated unknowns (mass, tendon_length, fascicle_length, "
                                         "slow_fraction, max_path_length)")
        ->capture_default_str();
    c->add_option("--bounds", o->bounds, "name=lo:hi in SI units, repeatable");
    c->add_option("--start", o->starts, "name=value in SI units, repeatable");
    o->model.add(*c, true);
    c->add_flag("--no-warm-start", o->model.noWarmStart, "faithful: start from --start, not from the steady estimate");
    c->add_option("--force-sd", o->forceSd, "lm: known force sd [N] (relative noise: fraction of the force)");
    c->add_option("--noise", o->noise, "lm noise model: absolute | relative")
        ->capture_default_str()
        ->check(CLI::IsMember({"absolute", "relative"}));
    c->add_option("--multistart", o->multistart, "lm: starts (the first at --start, others seeded uniform in the bounds)")
        ->capture_default_str()
        ->transform(inRange(1, 10000));
    c->add_option("--seed", o->seed, "lm multi-start seed")->capture_default_str();
    c->add_option("--max-iterations", o->maxIterations, "solver iterations")->capture_default_str();
    c->add_option("--tolerance", o->tolerance, "force tolerance [N] (forces reproduced)")->capture_default_str();
    c->add_option("--subject", o->subject, "keep only this subject's rows (-1: all)")->capture_default_str();
    c->add_flag("--thesis-cases", o->thesisCases, "rerun the thesis's cases (4.5.1, Tables 7.1-7.3) beside its numbers")
        ->excludes(c->get_option("data"));
    o->muscle.add(*c);
    c->add_option("--out", o->out, "output directory (report JSON, history CSV, convergence PNG)")->capture_default_str();
    c->callback([o, c] {
        // The faithful model's options would be ignored by the steady model.
        for (const char* option : {"--estimate", "--hold", "--rate", "--no-warm-start", "--jobs"})
            if (o->model.model == "steady" && c->count(option))
                throw InputError(std::string(option) + " is an option of the faithful forward model: with --forward "
                                 "steady (the default) it would be ignored; add --forward faithful or corrected");
        // Options of the least-squares fit would be ignored by the learning-control family.
        for (const char* option : {"--force-sd", "--noise", "--multistart", "--seed"})
            if (o->method != "lm" && c->count(option))
                throw InputError(std::string(option) + " is an option of --method lm: --method " + o->method +
                                 " would ignore it");
        if (c->count("--seed") && o->multistart <= 1)   // the seed draws the starts after the first
            throw InputError("--seed " + std::to_string(o->seed) + " with --multistart " + std::to_string(o->multistart) +
                             ": the seed draws the multi-start points after the first, so it would be ignored; add "
                             "--multistart N (N > 1)");
        // One --bounds or --start per unknown: a second would silently win.
        for (const auto& [option, list] : {std::pair<const char*, const std::vector<std::string>*>{"--bounds", &o->bounds},
                                           {"--start", &o->starts}}) {
            std::set<ParameterId> seen;   // by the unknown it names (tendon_length is optimal_tendon_length)
            for (const std::string& item : *list) {
                const std::string name = splitAssignment(option, item).first;
                if (!seen.insert(parseParameter(option, name)).second)
                    throw InputError(std::string(option) + " " + item + ": '" + name + "' is given twice: expected one " +
                                     option + " per unknown");
            }
        }
        runIdentify(*o);
    });
}

// ---- validate -----------------------------------------------------------------------------------

struct ValidateOptions {
    MuscleOptions muscle;
    int seeds = 1;
    unsigned seed = 1;
    std::vector<double> noise = {0, 1, 2, 5};  // [% of the force]
    std::vector<std::string> methods;
    std::string model = "corrected";
    std::string estimate = "moment-arm";
    int jobs = 2;
    std::string out = "out/validate";
    std::string truth = "thesis";
    std::string population;
    std::string truthPopulation;   // out of family: subjects drawn from here ...
    std::string prior;             // ... identified with this prior (both default to --population)
    int subjects = 200;
    double activationSd = 0.02;
    std::vector<double> angles;  // flexion angles [deg] of the elbow protocol; empty: the thesis's five
    int repetitions = 3;
    std::string protocol;   // torque protocol file (replaces --angles/--repetitions)
    bool freeSlowFraction = false;
    bool noiseGiven = false;
};

// Identified vs true biceps mass per method, and the error against two nuisances.
void addElbowValidationPlots(const std::vector<ElbowValidationRow>& rows, OutputFolder& out) {
    PlotSpec vsTruth;
    vsTruth.title = "Biceps long-head mass: identified vs true (virtual subjects as truth)";
    vsTruth.xLabel = "true mass (g)";
    vsTruth.yLabel = "identified mass (g)";
    PlotSpec vsActivation = vsTruth, vsSynergists = vsTruth;
    vsActivation.title = "Mass error vs the subject's voluntary activation";
    vsActivation.xLabel = "voluntary activation";
    vsActivation.yLabel = "mass error (%)";
    vsSynergists.title = "Mass error vs synergist strength relative to the biceps";
    vsSynergists.xLabel = "synergists' mass scale / biceps's";
    vsSynergists.yLabel = "mass error (%)";
    double lo = 1e9, hi = 0;
    for (const char* method : {"thesis", "synergist", "synergist-va", "channels"}) {
        const std::string m = method;
        const int color = m == "thesis" ? 1 : m == "synergist" ? 0 : m == "synergist-va" ? 2 : 3;
        if (std::none_of(rows.begin(), rows.end(), [&](const ElbowValidationRow& r) { return r.method == m; })) continue;
        // Fits that did not converge are drawn as a series of their own (grey), never as results.
        PlotSeries a{method, {}, {}, true, color}, b = a, c = a;
        PlotSeries fa{std::string(method) + ": not converged", {}, {}, true, 5}, fb = fa, fc = fa;
        for (const ElbowValidationRow& r : rows) {
            if (r.method != method || !std::isfinite(r.estimate.mass)) continue;
            const bool ok = r.estimate.converged;
            (ok ? a : fa).x.push_back(1000 * r.trueMass);
            (ok ? a : fa).y.push_back(1000 * r.estimate.mass);
            (ok ? b : fb).x.push_back(r.voluntaryActivation);
            (ok ? b : fb).y.push_back(100 * r.massError);
            (ok ? c : fc).x.push_back(r.synergistScale);
            (ok ? c : fc).y.push_back(100 * r.massError);
            lo = std::min(lo, 1000 * r.trueMass);
            hi = std::max(hi, 1000 * r.trueMass);
        }
        vsTruth.series.push_back(a);
        vsActivation.series.push_back(b);
        vsSynergists.series.push_back(c);
        if (!fa.x.empty()) {
            vsTruth.series.push_back(fa);
            vsActivation.series.push_back(fb);
            vsSynergists.series.push_back(fc);
        }
    }
    vsTruth.series.push_back({"identity", {lo, hi}, {lo, hi}, false, 7});
    out.writeWith("mass_identified_vs_true.png", [&](const std::string& p) { writePlotPng(p, vsTruth); });
    out.writeWith("mass_error_vs_activation.png", [&](const std::string& p) { writePlotPng(p, vsActivation); });
    out.writeWith("mass_error_vs_synergists.png", [&](const std::string& p) { writePlotPng(p, vsSynergists); });
}

void runElbowValidate(const ValidateOptions& o) {
    // Files as everywhere else: a path, or a name under the assets folder.
    const Population family = o.population.empty() ? loadDefaultPopulation() : loadPopulation(findAssetFor("--population", o.population));
    const Population population = o.truthPopulation.empty() ? family : loadPopulation(findAssetFor("--truth-population", o.truthPopulation));
    const Population prior = o.prior.empty() ? family : loadPopulation(findAssetFor("--prior", o.prior));
    const bool inFamily = o.truthPopulation.empty() && o.prior.empty();
    ElbowValidationSettings s;
    s.subjects = capForQuickRun(o.subjects, kQuickSubjects, "validation subjects");
    s.seed = o.seed;
    s.jobs = o.jobs;
    s.activationSd = o.activationSd;
    s.freeSlowFraction = o.freeSlowFraction;
    if (!o.protocol.empty()) {
        s.protocol = readTorqueProtocol(findAssetFor("--protocol", o.protocol));
    } else {
        std::vector<double> angles = getThesisMvcFlexionDeg();
        if (!o.angles.empty()) angles = o.angles;
        s.protocol.conditions = TorqueProtocol::makeFlexionMvcs(angles, o.repetitions);
    }
    if (o.noiseGiven)
        for (double pct : o.noise) s.noiseLevels.push_back(pct / 100.0);
    const long fits = countElbowValidationFits(population, prior, s);   // checks the settings and the work's size
    if (!inFamily)
        std::printf("out of family: truth population '%s' (%s, model %s), identifiers' prior '%s' (%s, model %s)\n",
                    population.name.c_str(), population.file.c_str(), population.base.name.c_str(), prior.name.c_str(),
                    prior.file.c_str(), prior.base.name.c_str());
    std::printf("validation on virtual subjects of the %s model as truth: population '%s' (%s), %d subjects (%ld fits), seed %u; "
                "protocol '%s' (%d trials: %s); identifiers: thesis (biceps only), synergist-aware (MAP) and, with "
                "--activation-sd > 0, synergist-aware with voluntary activation measured by twitch interpolation "
                "(synergist-va)%s\n",
                population.base.name.c_str(), population.name.c_str(), population.file.c_str(), s.subjects, fits, s.seed,
                s.protocol.name.c_str(),
                s.protocol.getNumTrials(), describeConditions(s.protocol).c_str(),
                s.protocol.hasChannels() ? "; with the protocol's channels besides torque, the same MAP fitting every "
                                           "channel (channels)" : "");
    std::fflush(stdout);
    const std::vector<ElbowValidationRow> rows =
        runElbowValidation(population, prior, s, [](int d, int n) { printProgress("subjects", d, n); });
    const std::vector<ElbowValidationSummary> summary = summarizeElbowValidation(rows);
    std::printf("%-13s %6s %9s %17s %17s %13s %20s %20s %13s\n", "method", "noise", "converged", "mass bias",
                "mass RMSE", "coverage", "L0T bias", "L0T RMSE", "coverage");
    std::set<double> mvcAngles;   // the thesis method's: flexion MVCs in the model's posture
    for (const TorqueCondition& c : s.protocol.conditions)
        if (c.effort == Effort::Flexion && c.level == 1 && std::isnan(c.rotationDeg)) mvcAngles.insert(c.flexionDeg);
    for (const ElbowValidationSummary& x : summary)
        if (x.converged == 0) {
            std::string why;
            if (x.method == "synergist-va") why = " (its twitch interpolation needs maximal efforts: has the protocol an MVC?)";
            if (x.method == "thesis" && mvcAngles.size() < 2)
                why = " (the thesis method fits flexion MVCs at >= 2 angles; the protocol has " + std::to_string(mvcAngles.size()) + ")";
            std::printf("%-13s %5.1f%% %5d/%-3d no fit converged: nothing to summarise%s\n", x.method.c_str(), 100 * x.noise,
                        x.converged, x.subjects, why.c_str());
        }
        else
        std::printf("%-13s %5.1f%% %5d/%-3d %+8.1f +/- %3.1f%% %8.1f +/- %3.1f%% %5.2f +/- %4.2f %+8.1f +/- %3.1f mm "
                    "%8.1f +/- %3.1f mm %5.2f +/- %4.2f\n",
                    x.method.c_str(), 100 * x.noise, x.converged, x.subjects, 100 * x.massBias, 100 * x.massBiasSe,
                    100 * x.massRmse, 100 * x.massRmseSe, x.massCoverage, x.massCoverageSe, 1000 * x.tendonBias,
                    1000 * x.tendonBiasSe, 1000 * x.tendonRmse, 1000 * x.tendonRmseSe, x.tendonCoverage,
                    x.tendonCoverageSe);
    std::printf("(+/- one standard error over the subjects; a 95 %% interval is about twice that)\n");
    for (const ElbowValidationSummary& x : summary)
        if (std::isfinite(x.maxForceRmse))
            std::printf("%-13s F0: bias %+.1f %%, RMSE %.1f %%, coverage %.2f\n", x.method.c_str(), 100 * x.maxForceBias,
                        100 * x.maxForceRmse, x.maxForceCoverage);
    std::printf("goal (issue 11, synergist-aware at 2 %% noise): |mass bias| <= 3 %%, mass RMSE <= 10 %%, "
                "L0T RMSE <= 10 mm, coverage 0.90-0.98\n");
    if (s.protocol.hasChannels())
        std::printf("goal (issue 31, every channel, out of family): |mass bias| <= 3 %%, mass and F0 RMSE <= 7 %%, "
                    "mass coverage 0.90-0.98, L0T RMSE <= 5 mm\n");
    OutputFolder out(o.out, OutputFolder::Mode::AddFiles);
    out.write("elbow_validation.csv", formatElbowValidationCsv(rows));
    out.write("elbow_validation_summary.csv", formatElbowValidationSummaryCsv(summary));
    addElbowValidationPlots(rows, out);
    out.commit();
    std::printf("wrote %s/elbow_validation.csv, elbow_validation_summary.csv, mass_identified_vs_true.png, "
                "mass_error_vs_activation.png, mass_error_vs_synergists.png\n", o.out.c_str());
}

void runValidate(const ValidateOptions& o) {
    checkOutputFolder("--out", o.out);
    if (o.truth == "elbow") return runElbowValidate(o);
    const ArmSetup setup = o.muscle.loadSetup();
    ValidationSettings s;
    s.seeds = o.seeds;
    s.seed = o.seed;
    s.noiseLevels.clear();
    for (double pct : o.noise) {   // in the unit typed (percent), before it becomes a fraction
        checkField("--noise", pct, {0, 50, false, true, "%, relative force sd"});
        s.noiseLevels.push_back(pct / 100.0);
    }
    // Levels of 0.05 % or less (no transducer is that quiet) are fractions typed for percent.
    constexpr double kQuietestTransducerPct = 0.05;
    if (std::any_of(o.noise.begin(), o.noise.end(), [](double p) { return p > 0; }) &&
        std::all_of(o.noise.begin(), o.noise.end(), [](double p) { return p <= kQuietestTransducerPct; })) {
        std::string percent;
        for (double p : o.noise) percent += (percent.empty() ? "" : ",") + formatNumber(100 * p, 6);
        throw InputError("--noise " + formatList(o.noise) + ": every level is at most " + formatNumber(kQuietestTransducerPct) +
                         " %, quieter than any force transducer: fractions? expected percent of the force (--noise " +
                         percent + ")");
    }
    for (const std::string& m : o.methods) {
        try {
            s.methods.push_back(parseMethodName(m));
        } catch (const InputError& e) {
            throw InputError(std::string("--methods: ") + e.what());
        }
    }
    s.model = parseValidationModelName(o.model);
    s.estimate = parseForceEstimateName(o.estimate);
    s.jobs = o.jobs;
    runNamingOptions({{"seeds", "--seeds"}, {"jobs", "--jobs"}}, [&] { s.validate(setup.arm); });
    std::printf("validation: data from the faithful model (thesis protocol, 1000 Hz, %s estimate) at %zu angles, "
                "identified with the %s model, start 330 g / 22 cm; %.0f fits\n",
                o.estimate.c_str(), s.anglesDeg.size(), o.model.c_str(), s.countFits());
    std::fflush(stdout);
    const std::vector<ValidationRow> rows = runValidation(setup.arm, setup.calcBicepsParameters(), s,
                                                          [](int d, int n) { printProgress("identifications", d, n); });
    std::printf("%s", formatValidationTable(rows).c_str());
    OutputFolder out(o.out, OutputFolder::Mode::AddFiles);
    out.write("validation.csv", formatValidationCsv(rows));
    out.commit();
    std::printf("wrote %s\n", out.getTargetPath("validation.csv").c_str());
}

void addValidateCommand(CLI::App& app) {
    auto o = std::make_shared<ValidateOptions>();
    CLI::App* c = app.add_subcommand("validate", "identifiers vs ground truth on synthetic MVC data (faithful model, "
                                                 "transducer noise)");
    c->add_option("--seeds", o->seeds, "random true muscles besides the thesis's")->capture_default_str();
    c->add_option("--seed", o->seed, "generator seed (truths and noise)")->capture_default_str();
    addNumberListOption(*c, "--noise", o->noise, "comma-separated transducer noise levels [% of the force]")
        ->capture_default_str();
    addNameListOption(*c, "--methods", o->methods, "comma-separated methods (default: lm and the two-output learning family)");
    c->add_option("--forward", o->model, "identifying forward model: corrected | faithful | steady")
        ->capture_default_str()
        ->check(CLI::IsMember({"steady", "faithful", "corrected"}));
    c->add_option("--estimate", o->estimate, "force the experimenter reports: moment-arm | fixed-ratio | true")
        ->capture_default_str()
        ->check(CLI::IsMember({"moment-arm", "fixed-ratio", "true"}));
    c->add_option("--jobs", o->jobs, "trials run in parallel")->capture_default_str()->transform(inRange(1, 64));
    o->muscle.add(*c);
    c->add_option("--out", o->out, "output directory (validation.csv)")->capture_default_str();
    c->add_option("--truth", o->truth,
                  "thesis: biceps-only truths (the identifier's own model); elbow: multi-muscle virtual subjects "
                  "drawn from --population (default: the anatomical twin's), identified by the thesis method "
                  "and the synergist-aware identifiers")
        ->capture_default_str()
        ->check(CLI::IsMember({"thesis", "elbow"}));
    c->add_option("--population", o->population,
                  "population file for --truth elbow (default assets/subjects/default_population.yaml)");
    c->add_option("--truth-population", o->truthPopulation,
                  "--truth elbow: draw the subjects from this population file instead (out of family; e.g. "
                  "assets/subjects/mismatch/stronger.yaml)");
    c->add_option("--prior", o->prior,
                  "--truth elbow: population file the identifiers take as their prior and model (default: "
                  "--population, or the default population)");
    c->add_option("--activation-sd", o->activationSd,
                  "--truth elbow: sd of a twitch-interpolation measurement of voluntary activation for the "
                  "synergist-va identifier (0: leave it out)")
        ->capture_default_str()
        ->transform(inRange(0.0, 0.5));
    addNumberListOption(*c, "--angles", o->angles,
                  "--truth elbow: comma-separated flexion angles of the MVC protocol [deg, 0 = extended] "
                  "(default the thesis's 135,120,90,60,30)");
    c->add_option("--repetitions", o->repetitions, "--truth elbow: efforts per angle")
        ->capture_default_str()
        ->transform(inRange(1, 100));
    c->add_option("--protocol", o->protocol,
                  "--truth elbow: torque protocol file (kind: torque, e.g. written by `armsim design`) instead of "
                  "--angles/--repetitions; channels it records besides torque add the channels fit (e.g. "
                  "assets/protocols/recommended.yaml)");
    c->add_flag("--free-slow-fraction", o->freeSlowFraction,
                "--truth elbow: the synergist identifiers free the flexors' slow-fibre fractions");
    c->add_option("--subjects", o->subjects, "subjects for --truth elbow")->capture_default_str()->transform(inRange(1, 1000000));
    c->callback([o, c] {
        o->noiseGiven = c->count("--noise") > 0;
        if (c->count("--protocol") && (c->count("--angles") || c->count("--repetitions")))
            throw InputError("--protocol replaces --angles and --repetitions: give one or the other");
        if (c->count("--population") && c->count("--truth-population") && c->count("--prior"))
            throw InputError("--population is both the truth and the prior: with --truth-population and --prior "
                             "it has nothing left to do; give two of the three");
        for (const char* option : {"--population", "--truth-population", "--prior", "--subjects", "--activation-sd",
                                   "--angles", "--repetitions", "--protocol", "--free-slow-fraction"})
            if (o->truth != "elbow" && c->count(option))
                throw InputError(std::string(option) + " needs --truth elbow");
        // The truths set every muscle's mass and tendon length (thesis: Table 7.2's and drawn ones; elbow:
        // the population's people), so these would be ignored.
        for (const char* option : {"--mass", "--tendon-length"})
            if (c->count(option))
                throw InputError(std::string(option) + ": validate draws the true muscles (--seeds, or --truth elbow's "
                                 "population), so a given value would be ignored");
        if (o->truth == "elbow")
            for (const char* option : {"--model", "--muscle", "--arm", "--slow-units", "--fast-units", "--max-path"})
                if (c->count(option))
                    throw InputError(std::string(option) + " with --truth elbow: the subjects come from the population "
                                     "file (--population, --truth-population), so it would be ignored");
        if (o->truth == "elbow")
            for (const char* option : {"--seeds", "--methods", "--forward", "--estimate"})
                if (c->count(option))
                    throw InputError(std::string(option) + " applies to --truth thesis only (--truth elbow runs the "
                                     "thesis, synergist and synergist-va identifiers on --subjects drawn subjects)");
        runNamingOptions({{"angles", "--angles"}}, [&] {   // before any work, in the option's words
            for (double a : o->angles) checkField("angles", a, Bound::closed(0, 180, "deg, 0 = extended"));
            checkDegreesNotRadians("angles", o->angles);
        });
        for (std::size_t i = 0; i < o->methods.size(); ++i)   // a method twice would run and be written twice
            for (std::size_t j = 0; j < i; ++j)
                if (o->methods[i] == o->methods[j])
                    throw InputError("--methods '" + o->methods[i] + "' is listed twice: expected each method once");
        runValidate(*o);
    });
}

// ---- main job -----------------------------------------------------------------------------------

void printEstimateLine(const std::string& label, const IdentificationReport& r, double mass, double tendon,
                       const std::string& reference) {
    const ModelCheck* faithful = nullptr;
    for (const ModelCheck& c : r.checks)
        if (c.model == "faithful") faithful = &c;
    std::printf("  %-34s %8.2f g %7.3f cm   (%s %.2f g, %.3f cm)  %-14s %3d it %4d ev %6.2f s  rms %.3g N "
                "(faithful re-check %.3g N)\n",
                label.c_str(), 1000 * r.parameters[0].value, 100 * r.parameters[1].value, reference.c_str(),
                1000 * mass, 100 * tendon, getStopReasonName(r.stopReason).c_str(), r.iterations,
                r.forwardEvaluations, r.wallTime, r.rmsResidual, faithful ? faithful->rmsResidual : NAN);
}

void runIdentificationStep(const MainJobContext& ctx) {
    const ArmSetup setup = ctx.muscle.loadSetup();
    const MuscleParameters base = setup.calcBicepsParameters();
    ModelOptions faithful;
    faithful.model = "faithful";
    faithful.jobs = ctx.jobs;
    ModelOptions steadyOnly = faithful;
    steadyOnly.model = "steady";
    const std::string dir = ctx.outDir + "/identification";
    createFolder(dir);
    auto problemFor = [&](const ObservationSet& data) {
        IdentificationProblem pr;
        pr.base = base;
        pr.data = data;
        pr.unknowns[0].start = kThesisStartMass;
        pr.unknowns[1].start = kThesisStartTendonLength;
        return pr;
    };

    // 1. The thesis's measured forces (600 N at 41 cm, 458 N at 37.5 cm).
    std::printf("faithful model in the iterations: %s; re-checks at 1000 Hz\n",
                FaithfulForceModel(setup.arm, faithful.makeChoice().makeIterationOptions()).describe().c_str());
    std::printf("thesis measured data (Table 7.3: 600 N at 41 cm, 458 N at 37.5 cm), lm from 330 g / 22 cm:\n");
    const IdentificationProblem measured = problemFor(readArmObservations(findAsset("measured/thesis_measured.csv"), setup.arm));
    IdentificationOptions lm;
    struct Run {
        const char* label;
        const char* stem;
        ModelOptions model;
    };
    ModelOptions fixedRatio = faithful;
    fixedRatio.estimate = "fixed-ratio";
    for (const Run& run : {Run{"steady model", "thesis_measured_steady", steadyOnly},
                           Run{"faithful model (moment-arm est.)", "thesis_measured_faithful", faithful},
                           Run{"faithful model (fixed-ratio est.)", "thesis_measured_faithful_fixed_ratio", fixedRatio}}) {
        const IdentificationReport r = runIdentification(measured, lm, setup.arm, run.model, false);
        printEstimateLine(run.label, r, kThesisMeasuredMass, kThesisMeasuredTendonLength, "thesis");
        writeReportFiles(r, dir, run.stem);
    }

    // 2. Our own MVC data: five angles, the faithful model at the thesis protocol, the default subject.
    const FaithfulModelOptions ro = faithful.makeChoice().makeReferenceOptions();
    const FaithfulForceModel reference(setup.arm, ro);
    const std::vector<double> anglesDeg(std::begin(kThesisMvcAnglesDeg), std::end(kThesisMvcAnglesDeg));
    const ObservationSet angles = makeAnglePoints(anglesDeg, makeArmPathFromAngle(setup.arm));
    const std::vector<double> y = reference.calcForces(base, angles.points);
    Table mvc({"angle_deg", "force_N"});
    for (std::size_t k = 0; k < y.size(); ++k) mvc.appendRow({kThesisMvcAnglesDeg[k], y[k]});
    const std::string csv = "# MVC forces of armsim's default subject (" + base.name + ", M = " +
                            formatNumber(base.mass) + " kg, L0T = " + formatNumber(base.optimalTendonLength) +
                            " m): " + reference.describe() + "\n" + mvc.toCsv(10);
    const std::string dataPath = dir + "/mvc_five_angles.csv";
    writeFileAtomically(dataPath, csv);
    std::printf("own MVC data (%s; truth %.2f g, %.3f cm), from 330 g / 22 cm:\n", showPath(dataPath).c_str(), 1000 * base.mass,
                100 * base.optimalTendonLength);
    IdentificationProblem own = problemFor(readArmObservations(dataPath, setup.arm));
    own.data.source = showPath(dataPath);  // where the file will be (the job writes into a staging folder)
    for (Method m : {Method::LevenbergMarquardt, Method::IlcSignSearch}) {
        IdentificationOptions o;
        o.method = m;
        for (const Run& run : {Run{"steady model", "steady", steadyOnly}, Run{"faithful model", "faithful", faithful}}) {
            const IdentificationReport r = runIdentification(own, o, setup.arm, run.model, false);
            printEstimateLine(getMethodName(m) + ", " + run.label, r, base.mass, base.optimalTendonLength, "truth");
            writeReportFiles(r, dir, "mvc_" + getMethodName(m) + "_" + run.stem);
        }
    }

    // 3. The thesis's cases with the steady model.
    std::printf("thesis cases (steady model) beside the thesis's numbers:\n");
    printThesisCases(base, SteadyForceModel(), dir);
    std::printf("  wrote reports (JSON, history CSV, convergence PNG) to %s/\n", showPath(dir).c_str());
}

// One virtual person out of family (subject 0 of the stronger mismatch population, the default population
// as prior) through the recommended protocol: every channel synthesized and plotted, identified with
// every method, truth beside estimate and interval.
void runOutOfFamilyPersonStep(const MainJobContext& ctx) {
    const Population truth = loadPopulation(findAsset("subjects/mismatch/stronger.yaml"));
    const Population prior = loadDefaultPopulation();
    ElbowValidationSettings s;
    s.subjects = 1;
    s.protocol = readTorqueProtocol(findAsset("protocols/recommended.yaml"));
    std::printf("truth: person 0 of population %s (%s); prior: %s; protocol %s: %s\n", truth.name.c_str(),
                truth.file.c_str(), prior.name.c_str(), s.protocol.name.c_str(), describeConditions(s.protocol).c_str());
    std::fflush(stdout);
    const ElbowValidationSubject person = runElbowValidationSubject(truth, prior, s, 0);
    const std::vector<ElbowValidationRow>& rows = person.rows;
    const std::vector<TorqueObservation> torque = setTransducerNoise(person.torque, truth.transducerNoise);
    const std::vector<ChannelObservation>& channels = person.channels;
    const std::string dir = ctx.outDir + "/out_of_family_person";
    createFolder(dir);
    writeTorqueProtocolRun(dir, s.protocol, torque, channels);
    writeFileAtomically(dir + "/estimates.csv", formatElbowValidationCsv(rows));
    std::printf("%-13s %22s %22s %22s\n", "method", "M (g) [95 %]", "L0T (cm) [95 %]", "F0 (N) [95 %]");
    const ElbowValidationRow& t = rows.front();
    std::printf("%-13s %22.1f %22.2f %22.0f\n", "truth", 1000 * t.trueMass, 100 * t.trueTendonLength, t.trueMaxForce);
    PlotSpec plot;
    plot.title = "One person out of family: biceps long-head mass per method";
    plot.xLabel = "method (1 thesis, 2 synergist, 3 synergist-va, 4 channels)";
    plot.yLabel = "mass (g)";
    PlotSeries estimate{"estimate", {}, {}, true, 0}, interval{"95 % interval ends", {}, {}, true, 5};
    for (std::size_t k = 0; k < rows.size(); ++k) {
        const MuscleEstimate& e = rows[k].estimate;
        auto cell = [](double v, double lo, double hi, double scale, int digits) {
            if (!std::isfinite(v)) return std::string("-");
            char b[64];
            std::snprintf(b, sizeof b, "%.*f [%.*f, %.*f]", digits, scale * v, digits, scale * lo, digits, scale * hi);
            return std::string(b);
        };
        std::printf("%-13s %22s %22s %22s%s\n", e.method.c_str(), cell(e.mass, e.massLower, e.massUpper, 1000, 1).c_str(),
                    cell(e.tendonLength, e.tendonLower, e.tendonUpper, 100, 2).c_str(),
                    cell(e.maxForce, e.maxForceLower, e.maxForceUpper, 1, 0).c_str(), e.converged ? "" : "  (not converged)");
        if (!std::isfinite(e.mass)) continue;
        estimate.x.push_back(double(k + 1));
        estimate.y.push_back(1000 * e.mass);
        for (double end : {e.massLower, e.massUpper})
            if (std::isfinite(end)) interval.x.push_back(double(k + 1)), interval.y.push_back(1000 * end);
    }
    plot.series = {estimate, interval, {"truth", {0.5, double(rows.size()) + 0.5}, {1000 * t.trueMass, 1000 * t.trueMass}, false, 1}};
    writePlotPng(dir + "/mass_estimates.png", plot);
    for (const MuscleEstimate& e : {rows.back().estimate})
        for (const ChannelFit& f : e.channelFits)
            std::printf("  %s fit, %-17s n %3d  chi2 %6.1f  p %.3f  %s\n", e.method.c_str(), f.channel.c_str(), f.n,
                        f.chiSquare, f.p, f.p >= 0.05 ? "noise" : ("misfit, worst: " + f.worst).c_str());
    std::printf("  wrote torque and channel data, their plots, estimates.csv and mass_estimates.png to %s/\n", showPath(dir).c_str());
}

const CommandRegistrar registerIdentify(40, addIdentifyCommand);
const CommandRegistrar registerValidate(41, addValidateCommand);
// Before any step: the thesis's measured forces are paths the subject's arm must reach.
void checkIdentificationStep(const MainJobContext& ctx) {
    const std::string data = findAsset("measured/thesis_measured.csv");
    try {
        const ArmParameters arm = ctx.muscle.loadSetup().arm;
        FaithfulForceModel(arm).calcElbowAngles(readArmObservations(data, arm));
    } catch (const InputError& e) {
        throw InputError("--model " + ctx.muscle.model + (ctx.muscle.armFile.empty() ? "" : " with --arm " + ctx.muscle.armFile) +
                         ": the main job identifies the biceps from the thesis's measured forces (" + data +
                         "), which this arm cannot take: " + e.what() +
                         "; the main job needs an arm with the thesis's biceps geometry (--model thesis, the default)");
    }
}

const MainJobStepRegistrar registerIdentificationStep(50, "Identification: mass and tendon length (thesis data, own MVC data)",
                                                      runIdentificationStep, checkIdentificationStep);
const MainJobStepRegistrar registerOutOfFamilyPersonStep(
    52, "Identification out of family: one person of a stronger population, every channel of the recommended protocol",
    runOutOfFamilyPersonStep);

}  // namespace

}  // namespace armsim::cli
