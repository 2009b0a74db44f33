#include "model/anatomy_calibration.h"

#include "basics/errors.h"
#include "basics/bound.h"

#include "estimation/ceres_logging.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>

namespace armsim {

void AnatomyCalibrationOptions::validate() const {
    const Bound sd = Bound{0, 5, true, false, "ln units"};
    checkField("specific_tension_sd", specificTensionSd, sd);
    checkField("volume_sd", volumeSd, sd);
    checkField("fascicle_length_sd", fascicleLengthSd, sd);
    checkField("tendon_length_sd", tendonLengthSd, sd);
    auto range = [](const char* name, double lo, double hi) {
        if (!(lo > 0 && lo <= 1 && hi >= 1))
            throw FieldError(name, "[" + std::to_string(lo) + ", " + std::to_string(hi) +
                                       "]: expected positive bounds around 1");
    };
    range("volume bounds", volumeMin, volumeMax);
    range("fascicle bounds", fascicleMin, fascicleMax);
    range("tendon bounds", tendonMin, tendonMax);
    range("specific tension bounds", specificTensionMin, specificTensionMax);
}

namespace {

bool isFitted(TargetKind k) {
    return k == TargetKind::Mvc || k == TargetKind::Share || k == TargetKind::OptimumAngle || k == TargetKind::Volume ||
           k == TargetKind::ForearmMvc || k == TargetKind::PostureRatio;
}

constexpr double kMissingResidual = 3;
constexpr double kNfMargin = 0.90;         // fraction of the nf limit a relaxed fascicle may reach
constexpr double kMarginWeight = 100;      // per unit of relative excess   // a value the model does not have (no optimum in range): 3 scales out

// The band as a Gaussian: centre and sd = half the band + the tolerance (a point value: its tolerance).
double calcTargetResidual(const TargetScore& s) {
    const AnatomyTarget& t = s.target;
    const double w = std::sqrt(t.weight);
    if (!std::isfinite(s.value)) return w * kMissingResidual;
    const double centre = 0.5 * (t.upper + t.lower);
    double sd = 0.5 * (t.upper - t.lower) + t.tolerance;
    if (sd <= 0) sd = 0.1 * std::abs(centre);
    return w * (s.value - centre) / sd;
}

// x = [ln s, ln v, ln f per group..., ln t per muscle...].
struct AnatomyProblem {
    const ArmSetup* setup;
    const std::vector<AnatomyTarget>* targets;   // the fitted ones
    const AnatomyCalibrationOptions* options;
    std::vector<MuscleGroup> groups;
    const AnatomySweep* sweep;
    int numResiduals = 0;

    int getGroupIndex(MuscleGroup g) const { return int(std::find(groups.begin(), groups.end(), g) - groups.begin()); }
    int getNumUnknowns() const { return 3 * int(groups.size()) + setup->getNumMuscles(); }

    std::vector<MuscleCalibration> calcCalibration(const double* x) const {
        std::vector<MuscleCalibration> c(setup->muscles.size());
        for (int m = 0; m < setup->getNumMuscles(); ++m) {
            const int g = getGroupIndex(setup->muscles[m].group);
            const double s = std::exp(x[3 * g]), v = std::exp(x[3 * g + 1]), f = std::exp(x[3 * g + 2]);
            c[m].specificTensionScale = s;
            c[m].fascicleLengthScale = f;
            c[m].forceScale = v / f;
            c[m].tendonLengthScale = std::exp(x[3 * int(groups.size()) + m]);
        }
        return c;
    }

    bool operator()(double const* const* x, double* r) const {
        try {
            const ArmSetup s = applyCalibration(*setup, calcCalibration(x[0]));
            const std::vector<TargetScore> scores = scoreAnatomy(s, *targets, *sweep);
            int k = 0;
            for (const TargetScore& t : scores) r[k++] = calcTargetResidual(t);
            const int G = int(groups.size());
            for (int g = 0; g < G; ++g) {
                r[k++] = x[0][3 * g] / options->specificTensionSd;
                r[k++] = x[0][3 * g + 1] / options->volumeSd;
                r[k++] = x[0][3 * g + 2] / options->fascicleLengthSd;
            }
            for (int m = 0; m < setup->getNumMuscles(); ++m) r[k++] = x[0][3 * G + m] / options->tendonLengthSd;
            // A relaxed fascicle at the longest path (slack tendon: its longest) keeps a margin below the nf
            // limit, as a population's draws do (experiments/population.h): no calibration on the edge.
            for (int m = 0; m < setup->getNumMuscles(); ++m) {
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
    std::vector<AnatomyTarget> fitted;
    for (const AnatomyTarget& t : targets)
        if (isFitted(t.kind)) fitted.push_back(t);
    const AnatomySweep sweep = calcAnatomySweep(setup, fitted);
    std::vector<MuscleCalibration> identity(setup.muscles.size());
    const ArmSetup source = applyCalibration(setup, identity);

    AnatomyCalibrationResult result;
    result.before = scoreAnatomy(source, fitted, sweep);
    if (result.before.empty())
        throw InputError("anatomy calibration: no mvc, share, optimum_angle or volume target names a muscle of model '" +
                         setup.name + "'");
    AnatomyProblem problem{&source, &fitted, &options, {}, &sweep, 0};
    for (const MuscleSpec& m : setup.muscles)
        if (std::find(problem.groups.begin(), problem.groups.end(), m.group) == problem.groups.end())
            problem.groups.push_back(m.group);
    const int n = problem.getNumUnknowns();
    problem.numResiduals = int(result.before.size()) + n + setup.getNumMuscles();

    std::vector<double> x(n, 0.0);
    auto* cost = new ceres::DynamicNumericDiffCostFunction<AnatomyProblem, ceres::CENTRAL>(new AnatomyProblem(problem));
    cost->AddParameterBlock(n);
    cost->SetNumResiduals(problem.numResiduals);
    ceres::Problem pr;
    pr.AddResidualBlock(cost, nullptr, x.data());
    const int G = int(problem.groups.size());
    auto bound = [&](int j, double lo, double hi) {
        pr.SetParameterLowerBound(x.data(), j, std::log(lo));
        pr.SetParameterUpperBound(x.data(), j, std::log(hi));
    };
    for (int g = 0; g < G; ++g) {
        bound(3 * g, options.specificTensionMin, options.specificTensionMax);
        bound(3 * g + 1, options.volumeMin, options.volumeMax);
        bound(3 * g + 2, options.fascicleMin, options.fascicleMax);
    }
    for (int m = 0; m < setup.getNumMuscles(); ++m) bound(3 * G + m, options.tendonMin, options.tendonMax);
    quietCeresLogging();
    ceres::Solver::Options so;
    so.max_num_iterations = options.maxIterations;
    so.function_tolerance = 1e-8;
    so.parameter_tolerance = 1e-8;
    ceres::Solver::Summary summary;
    ceres::Solve(so, &pr, &summary);
    if (summary.termination_type == ceres::FAILURE)
        throw SimulationError("anatomy calibration of model '" + setup.name + "' failed: " + summary.message +
                              " (a muscle has no steady state at the start or within the bounds)");

    result.muscles = problem.calcCalibration(x.data());
    for (int g = 0; g < G; ++g)
        result.groups.push_back({problem.groups[g], std::exp(x[3 * g]), std::exp(x[3 * g + 1]), std::exp(x[3 * g + 2])});
    result.after = scoreAnatomy(applyCalibration(setup, result.muscles), fitted, sweep);
    result.cost = summary.final_cost;
    result.iterations = int(summary.iterations.size());
    result.converged = summary.termination_type == ceres::CONVERGENCE;
    result.report = summary.BriefReport();
    return result;
}

}  // namespace armsim
