#include "model/strength_calibration.h"

#include "basics/errors.h"

#include "estimation/ceres_logging.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>

namespace armsim {

namespace {

MvcTorqueTarget makeParabolaTarget() {
    constexpr double kPeak = 80.0, kPeakDeg = 95.0, kEndFraction = 0.55, kLo = 20.0, kHi = 130.0;
    MvcTorqueTarget t;
    t.effort = MuscleGroup::Flexor;
    for (double q = kLo; q <= kHi + 1e-9; q += 10.0) {
        const double half = q < kPeakDeg ? kPeakDeg - kLo : kHi - kPeakDeg;
        t.flexionDeg.push_back(q);
        t.torque.push_back(kPeak * (1.0 - (1.0 - kEndFraction) * std::pow((q - kPeakDeg) / half, 2)));
    }
    t.source = "peak 80 N m at 95 deg, 55 % at 20 and 130 deg (Holzbaur et al. 2007: 79.5 N m at 90 deg)";
    return t;
}

/// The fit's unknowns: x = [t per group muscle..., f, k].
struct CalibrationProblem {
    const ArmSetup* setup;
    const MvcTorqueTarget* target;
    const StrengthCalibrationOptions* options;
    std::vector<int> members;   // muscle indices of the target's group
    // The target's effort at the target angles, the mid-range angle and the feasibility angles; the
    // other effort at the feasibility angles (the calibration changes no geometry).
    MvcGeometry effortGeometry, feasibilityGeometry;

    std::vector<MuscleCalibration> calcCalibration(const double* x) const {
        std::vector<MuscleCalibration> c;
        for (const MuscleSpec& m : setup->muscles) c.push_back(m.calibration);
        const int n = int(members.size());
        for (int j = 0; j < n; ++j) {
            MuscleCalibration& m = c[members[j]];
            m.tendonLengthScale = x[j];
            m.fascicleLengthScale = options->fitFascicleLength ? x[n] : 1.0;
            m.forceScale = x[n + 1];
        }
        return c;
    }
    int getNumResiduals() const { return int(target->flexionDeg.size() + 2 * members.size()) + 1; }

    /// false when a muscle has no steady state somewhere (Ceres then rejects the step).
    bool operator()(double const* const* x, double* r) const {
        try {
            const ArmSetup s = applyCalibration(*setup, calcCalibration(x[0]));
            const std::size_t numTarget = target->flexionDeg.size();
            const SteadyMvcCurve c = calcSteadyMvcCurve(s.muscles, effortGeometry, target->effort, s.effort);
            const MuscleGroup other = target->effort == MuscleGroup::Flexor ? MuscleGroup::Extensor : MuscleGroup::Flexor;
            calcSteadyMvcCurve(s.muscles, feasibilityGeometry, other, s.effort);
            const std::vector<SteadyMusclePoint>& mid = c.points[numTarget];
            int k = 0;
            for (std::size_t a = 0; a < numTarget; ++a)
                r[k++] = (c.totalTorque[a] - target->torque[a]) / options->torqueScale;
            const int n = int(members.size());
            for (int j = 0; j < n; ++j) r[k++] = options->regularization * std::log(x[0][j]);
            r[k++] = options->regularization * std::log(x[0][n]);
            for (int j = 0; j < n; ++j) {
                const double excess = std::abs(mid[members[j]].fibreLength - 1.0) - options->midRangeTolerance;
                r[k++] = options->midRangeWeight * std::max(0.0, excess);
            }
            return true;
        } catch (const SimulationError&) {
            return false;
        } catch (const InputError&) {
            return false;
        }
    }
};

}  // namespace

MvcTorqueTarget getElbowFlexionTarget() { return makeParabolaTarget(); }

MvcTorqueTarget getElbowExtensionTarget() {
    MvcTorqueTarget t;
    t.effort = MuscleGroup::Extensor;
    t.flexionDeg = {90.0};
    t.torque = {-60.0};
    t.source = "-60 N m at 90 deg (centre of the accepted 45-75 N m)";
    return t;
}

StrengthCalibrationResult calibrateStrength(const ArmSetup& setup, const MvcTorqueTarget& target,
                                            const StrengthCalibrationOptions& options) {
    if (target.flexionDeg.empty() || target.flexionDeg.size() != target.torque.size())
        throw InputError("strength calibration: the target needs as many torques as angles (got " +
                         std::to_string(target.flexionDeg.size()) + " angles, " +
                         std::to_string(target.torque.size()) + " torques)");
    StrengthCalibrationOptions opts = options;
    if (opts.feasibilityDeg.empty())
        opts.feasibilityDeg = {setup.arm.getMinFlexionDeg(), setup.arm.getMaxFlexionDeg()};
    std::vector<double> angles = target.flexionDeg;
    angles.push_back(opts.midRangeDeg);
    angles.insert(angles.end(), opts.feasibilityDeg.begin(), opts.feasibilityDeg.end());
    // The geometry checks the angles before fitting (InputError with the model's range).
    CalibrationProblem problem{&setup, &target, &opts, {}, calcMvcGeometry(setup, angles),
                               calcMvcGeometry(setup, opts.feasibilityDeg)};
    for (int i = 0; i < setup.getNumMuscles(); ++i)
        if (setup.muscles[i].group == target.effort) problem.members.push_back(i);
    if (problem.members.empty())
        throw InputError("strength calibration: model '" + setup.name + "' has no " +
                         getMuscleGroupName(target.effort) + " muscles");

    const int n = int(problem.members.size());
    std::vector<double> x(n + 2, 1.0);
    auto* cost = new ceres::DynamicNumericDiffCostFunction<CalibrationProblem, ceres::CENTRAL>(
        new CalibrationProblem(problem));
    cost->AddParameterBlock(n + 2);
    cost->SetNumResiduals(problem.getNumResiduals());
    ceres::Problem pr;
    pr.AddResidualBlock(cost, nullptr, x.data());
    for (int j = 0; j < n + 2; ++j) {
        const double lo = j < n ? options.tendonScaleMin : j == n ? options.fascicleScaleMin : options.forceScaleMin;
        const double hi = j < n ? options.tendonScaleMax : j == n ? options.fascicleScaleMax : options.forceScaleMax;
        pr.SetParameterLowerBound(x.data(), j, lo);
        pr.SetParameterUpperBound(x.data(), j, hi);
    }
    if (!options.fitFascicleLength) pr.SetManifold(x.data(), new ceres::SubsetManifold(n + 2, {n}));
    quietCeresLogging();
    ceres::Solver::Options so;
    so.max_num_iterations = options.maxIterations;
    so.function_tolerance = 1e-10;
    so.parameter_tolerance = 1e-10;
    ceres::Solver::Summary summary;
    ceres::Solve(so, &pr, &summary);

    StrengthCalibrationResult result;
    result.muscles = problem.calcCalibration(x.data());
    result.iterations = int(summary.iterations.size());
    result.converged = summary.termination_type == ceres::CONVERGENCE;
    result.report = summary.BriefReport();
    const ArmSetup s = applyCalibration(setup, result.muscles);
    if (summary.termination_type == ceres::FAILURE)
        throw SimulationError("strength calibration of model '" + setup.name + "' failed: " + summary.message +
                              " (a muscle has no steady state at the start or within the bounds)");
    const SteadyMvcCurve c = calcSteadyMvcCurve(s, target.effort, s.effort, target.flexionDeg);
    double sum = 0;
    for (std::size_t a = 0; a < c.totalTorque.size(); ++a) {
        const double e = c.totalTorque[a] - target.torque[a];
        sum += e * e;
        result.maxTorqueError = std::max(result.maxTorqueError, std::abs(e));
    }
    result.rmsTorqueError = std::sqrt(sum / c.totalTorque.size());
    return result;
}

}  // namespace armsim
