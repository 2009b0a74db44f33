#include "model/anatomy_calibration.h"

#include "basics/errors.h"
#include "basics/bound.h"

#include "estimation/ceres_logging.h"
#include "estimation/numeric_diff.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>

namespace armsim {

void AnatomyCalibrationOptions::validate() const {
    const Bound sd = Bound{0, 5, true, false, "ln units"};
    checkField("specific_tension_sd", specificTensionSd, sd);
    checkField("volume_sd", volumeSd, sd);
    checkField("fascicle_length_sd", fascicleLengthSd, sd);
    checkField("muscle_fascicle_length_sd", muscleFascicleLengthSd, sd);
    for (double stage : goalStages)
        if (!(stage > 0)) throw FieldError("goal_stages", std::to_string(stage) + ": expected > 0");
    checkField("tendon_length_sd", tendonLengthSd, sd);
    auto range = [](const char* name, double lo, double hi) {
        if (!(lo > 0 && lo <= 1 && hi >= 1))
            throw FieldError(name, "[" + std::to_string(lo) + ", " + std::to_string(hi) +
                                       "]: expected positive bounds around 1");
    };
    range("volume bounds", volumeMin, volumeMax);
    range("fascicle bounds", fascicleMin, fascicleMax);
    range("muscle fascicle bounds", muscleFascicleMin, muscleFascicleMax);
    range("tendon bounds", tendonMin, tendonMax);
    range("specific tension bounds", specificTensionMin, specificTensionMax);
}

namespace {

bool isFitted(TargetKind k) {
    return k == TargetKind::Mvc || k == TargetKind::Share || k == TargetKind::OptimumAngle || k == TargetKind::Volume ||
           k == TargetKind::ForearmMvc || k == TargetKind::PostureRatio;
}

constexpr double kMissingResidual = 3;     // a value the model does not have: 3 scales out
constexpr double kNfMargin = 0.90;         // fraction of the nf limit a relaxed fascicle may reach
constexpr double kMarginWeight = 100;      // per unit of relative excess
constexpr double kGoalMarginOfTolerance = 0.25;  // the goal region ends this part of the tolerance inside the pass region
constexpr double kGoalMarginOfValue = 0.01;      // ... and at least this part of the band centre
constexpr double kValueUnit = 0.05;        // the goal residual's unit for a target without tolerance, of its centre

// The band's shape: a Gaussian with centre the band's and sd = half the band + the tolerance (a point
// value: its tolerance).
double calcBandResidual(const TargetScore& s) {
    const AnatomyTarget& t = s.target;
    const double w = std::sqrt(t.weight);
    if (!std::isfinite(s.fitValue)) return w * kMissingResidual;
    const double centre = 0.5 * (t.upper + t.lower);
    double sd = 0.5 * (t.upper - t.lower) + t.tolerance;
    if (sd <= 0) sd = 0.1 * std::abs(centre);
    return w * (s.fitValue - centre) / sd;
}

// The goal: zero inside the pass region [lower - tolerance, upper + tolerance] less a margin, then the
// excess in units of stage x the tolerance (stage x 5 % of the value without one).
double calcGoalResidual(const TargetScore& s, double stage) {
    const AnatomyTarget& t = s.target;
    const double w = std::sqrt(t.weight);
    if (!std::isfinite(s.fitValue)) return w * kMissingResidual / stage;
    const double centre = 0.5 * (t.upper + t.lower);
    const double passHalf = 0.5 * (t.upper - t.lower) + t.tolerance;
    const double margin = std::min(std::max(kGoalMarginOfTolerance * t.tolerance, kGoalMarginOfValue * std::abs(centre)),
                                   0.5 * passHalf);
    double unit = t.tolerance > 0 ? t.tolerance : kValueUnit * std::abs(centre);
    if (!(unit > 0)) unit = passHalf;   // a band about 0 without tolerance (a point band needs one: the loader)
    const double d = s.fitValue - centre;
    const double excess = std::max(0.0, std::abs(d) - (passHalf - margin));
    return w * std::copysign(excess, d) / (stage * unit);
}

// x = [ln s, ln v, ln f per group..., ln t per muscle..., ln f_m per muscle...]: a muscle's fascicle
// scale is its group's f times its own f_m.
struct AnatomyProblem {
    const ArmSetup* setup;
    const std::vector<AnatomyTarget>* targets;   // the fitted ones
    const AnatomyCalibrationOptions* options;
    std::vector<MuscleGroup> groups;
    const AnatomySweep* sweep;
    int numResiduals = 0;
    double stage = 0;   // goal stage (0: the bands' shape alone)

    int getGroupIndex(MuscleGroup g) const { return int(std::find(groups.begin(), groups.end(), g) - groups.begin()); }
    int getNumMuscles() const { return setup->getNumMuscles(); }
    int getTendonIndex(int m) const { return 3 * int(groups.size()) + m; }
    int getFascicleIndex(int m) const { return 3 * int(groups.size()) + getNumMuscles() + m; }
    int getNumUnknowns() const { return 3 * int(groups.size()) + 2 * getNumMuscles(); }

    std::vector<MuscleCalibration> calcCalibration(const double* x) const {
        std::vector<MuscleCalibration> c(setup->muscles.size());
        for (int m = 0; m < getNumMuscles(); ++m) {
            const int g = getGroupIndex(setup->muscles[m].group);
            const double s = std::exp(x[3 * g]), v = std::exp(x[3 * g + 1]);
            const double f = std::exp(x[3 * g + 2] + x[getFascicleIndex(m)]);
            c[m].specificTensionScale = s;
            c[m].fascicleLengthScale = f;
            c[m].forceScale = v / f;
            c[m].tendonLengthScale = std::exp(x[getTendonIndex(m)]);
        }
        return c;
    }

    bool operator()(double const* const* x, double* r) const {
        if (getInterruption()) return false;   // a stop: every evaluation fails at once, the callback ends the solve
        try {
            const ArmSetup s = applyCalibration(*setup, calcCalibration(x[0]));
            const std::vector<TargetScore> scores = scoreAnatomy(s, *targets, *sweep);
            int k = 0;
            for (const TargetScore& t : scores) {
                r[k++] = calcBandResidual(t);
                r[k++] = stage > 0 ? calcGoalResidual(t, stage) : 0.0;
            }
            for (int g = 0; g < int(groups.size()); ++g) {
                r[k++] = x[0][3 * g] / options->specificTensionSd;
                r[k++] = x[0][3 * g + 1] / options->volumeSd;
                r[k++] = x[0][3 * g + 2] / options->fascicleLengthSd;
            }
            for (int m = 0; m < getNumMuscles(); ++m) {
                r[k++] = x[0][getTendonIndex(m)] / options->tendonLengthSd;
                r[k++] = x[0][getFascicleIndex(m)] / options->muscleFascicleLengthSd;
            }
            // A relaxed fascicle at the longest path (slack tendon: its longest) keeps a margin below the nf
            // limit, as a population's draws do (experiments/population.h): no calibration on the edge.
            for (int m = 0; m < getNumMuscles(); ++m) {
                const MuscleParameters& p = s.muscles[m].params;
                const double L = (p.maxPathLength - p.coefficients.LrT * p.optimalTendonLength) / p.optimalFascicleLength;
                const double limit = kNfMargin * VirtualMuscle(p).getNfLimit();
                r[k++] = kMarginWeight * std::max(0.0, L / limit - 1);
            }
            return k == numResiduals;
        } catch (const SimulationError&) {
            return false;
        } catch (const InputError&) {
            return false;
        }
    }
};

}  // namespace

AnatomyCalibrationResult calibrateToAnatomy(const ArmSetup& setup, const std::vector<AnatomyTarget>& targets,
                                            const AnatomyCalibrationOptions& options) {
    options.validate();
    checkMomentArmSigns(setup, targets);   // scored, not fitted: refused before a fit of minutes
    std::vector<AnatomyTarget> fitted;
    for (const AnatomyTarget& t : targets)
        if (isFitted(t.kind)) fitted.push_back(t);
    const AnatomySweep sweep = calcAnatomySweep(setup, fitted);
    std::vector<MuscleCalibration> identity(setup.muscles.size());
    const ArmSetup source = applyCalibration(setup, identity);

    AnatomyCalibrationResult result;
    result.before = scoreAnatomy(source, fitted, sweep);
    if (result.before.empty()) {
        std::string file = fitted.empty() ? std::string() : fitted.front().where;
        if (const std::size_t colon = file.rfind(':'); colon != std::string::npos) file.erase(colon);
        std::string named, muscles;
        for (const AnatomyTarget& t : fitted)
            if (!t.muscle.empty() && named.find("'" + t.muscle + "'") == std::string::npos)
                named += (named.empty() ? "'" : ", '") + t.muscle + "'";
        for (const MuscleSpec& m : setup.muscles) muscles += (muscles.empty() ? "" : ", ") + m.params.name;
        throw InputError((file.empty() ? std::string("anatomy calibration") : file) +
                         ": no mvc, share, optimum_angle or volume target names a muscle of model '" + setup.name + "'" +
                         (named.empty() ? std::string() : " (the targets name " + named + ")") +
                         ": expected targets of its muscles (" + muscles + ")");
    }
    AnatomyProblem problem{&source, &fitted, &options, {}, &sweep, 0};
    for (const MuscleSpec& m : setup.muscles)
        if (std::find(problem.groups.begin(), problem.groups.end(), m.group) == problem.groups.end())
            problem.groups.push_back(m.group);
    const int n = problem.getNumUnknowns();
    problem.numResiduals = 2 * int(result.before.size()) + n + setup.getNumMuscles();   // targets twice, priors, nf margins

    std::vector<double> x(n, 0.0);
    const int G = int(problem.groups.size());
    quietCeresLogging();
    std::vector<double> stages = {0};
    stages.insert(stages.end(), options.goalStages.begin(), options.goalStages.end());
    ceres::Solver::Summary summary;
    int iterations = 0;
    bool allConverged = true;
    std::string stageReports;
    for (std::size_t k = 0; k < stages.size(); ++k) {   // each stage starts where the last ended
        const double stage = stages[k];
        problem.stage = stage;
        auto* cost = new SteppingNumericDiffCost<AnatomyProblem>(new AnatomyProblem(problem), n, problem.numResiduals);
        ceres::Problem pr;
        pr.AddResidualBlock(cost, nullptr, x.data());
        auto bound = [&](int j, double lo, double hi) {
            pr.SetParameterLowerBound(x.data(), j, std::log(lo));
            pr.SetParameterUpperBound(x.data(), j, std::log(hi));
        };
        for (int g = 0; g < G; ++g) {
            bound(3 * g, options.specificTensionMin, options.specificTensionMax);
            bound(3 * g + 1, options.volumeMin, options.volumeMax);
            bound(3 * g + 2, options.fascicleMin, options.fascicleMax);
        }
        for (int m = 0; m < setup.getNumMuscles(); ++m) {
            bound(problem.getTendonIndex(m), options.tendonMin, options.tendonMax);
            bound(problem.getFascicleIndex(m), options.muscleFascicleMin, options.muscleFascicleMax);
        }
        ceres::Solver::Options so;
        so.max_num_iterations = options.maxIterations;
        so.function_tolerance = 1e-8;
        so.parameter_tolerance = 1e-8;
        struct StopOnInterruption : ceres::IterationCallback {
            ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
                return getInterruption() ? ceres::SOLVER_ABORT : ceres::SOLVER_CONTINUE;
            }
        } stop;
        so.callbacks.push_back(&stop);
        ceres::Solve(so, &pr, &summary);
        checkInterruption();
        iterations += int(summary.iterations.size());
        allConverged = allConverged && summary.termination_type == ceres::CONVERGENCE;
        if (summary.termination_type != ceres::CONVERGENCE)
            stageReports += "; stage " + std::to_string(k + 1) + " of " + std::to_string(stages.size()) + ": " +
                            ceres::TerminationTypeToString(summary.termination_type);
        if (summary.termination_type == ceres::FAILURE)
            throw SimulationError("anatomy calibration of model '" + setup.name + "' failed: " + summary.message +
                                  " (a muscle has no steady state at the start or within the bounds)");
        if (options.progress) {
            int passed = 0;
            const std::vector<TargetScore> now = scoreAnatomy(applyCalibration(setup, problem.calcCalibration(x.data())), fitted, sweep);
            for (const TargetScore& t : now) passed += t.pass;
            options.progress(int(k) + 1, int(stages.size()), passed, int(now.size()));
        }
    }

    result.muscles = problem.calcCalibration(x.data());
    for (int g = 0; g < G; ++g)
        result.groups.push_back({problem.groups[g], std::exp(x[3 * g]), std::exp(x[3 * g + 1]), std::exp(x[3 * g + 2])});
    result.after = scoreAnatomy(applyCalibration(setup, result.muscles), fitted, sweep);
    result.cost = summary.final_cost;
    result.iterations = iterations;
    result.converged = allConverged;
    result.report = summary.BriefReport() + stageReports;
    return result;
}

}  // namespace armsim
