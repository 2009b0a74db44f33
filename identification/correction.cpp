// Output correction: identification with a cheap model shifted by an expensive model's offset
// (identifier.h, identifyCorrected).
#include "basics/bound.h"
#include "basics/format.h"
#include "identification/identifier.h"

#include <chrono>
#include <cmath>
#include <sstream>

namespace armsim {

namespace {

/// cheap(x) + offset, element by element (the observations must be the ones the offset was made for).
class OffsetForceModel : public ForceModel {
public:
    OffsetForceModel(const ForceModel& base, std::vector<double> offset) : base_(base), offset_(std::move(offset)) {}
    std::vector<double> calcForces(const MuscleParameters& p, const std::vector<Observation>& obs) const override {
        std::vector<double> y = base_.calcForces(p, obs);
        if (y.size() != offset_.size()) throw std::logic_error("OffsetForceModel: observation count changed");
        for (std::size_t k = 0; k < y.size(); ++k) y[k] += offset_[k];
        return y;
    }
    std::string getName() const override { return base_.getName(); }
    double getDifferenceStep() const override { return base_.getDifferenceStep(); }
    double getParameterTolerance() const override { return base_.getParameterTolerance(); }

private:
    const ForceModel& base_;
    std::vector<double> offset_;
};

}  // namespace

IdentificationReport identifyCorrected(const IdentificationProblem& problem, const ForceModel& cheap,
                                       const ForceModel& fine, const IdentificationOptions& options,
                                       const CorrectionOptions& correction) {
    const auto t0 = std::chrono::steady_clock::now();
    checkField("correction.max_corrections", correction.maxCorrections, Bound::closed(1, 1000));
    const double tolerance = std::isnan(correction.tolerance) ? fine.getParameterTolerance() : correction.tolerance;
    checkField("correction.tolerance", tolerance, Bound::positive());
    const std::vector<Observation>& obs = problem.data.points;
    const std::size_t n = obs.size();
    std::vector<double> offset(n, 0.0);
    IdentificationProblem inner = problem;
    IdentificationReport report;
    std::vector<IterationRecord> history;
    int fineEvaluations = 0, innerIterations = 0, innerEvaluations = 0;
    bool settled = false;
    std::string failure;
    std::vector<double> fineForces;
    for (int j = 0; j < correction.maxCorrections; ++j) {
        const OffsetForceModel shifted(cheap, offset);
        report = identify(inner, shifted, options);
        innerIterations += report.iterations;
        innerEvaluations += report.forwardEvaluations;
        ++fineEvaluations;
        try {
            fineForces = fine.calcForces(report.muscle, obs);
        } catch (const InterruptedError&) {
            throw;
        } catch (const InputError&) {
            throw;
        } catch (const std::exception& e) {
            failure = std::string("the ") + fine.getName() + " model failed at correction " + std::to_string(j + 1) +
                      ": " + e.what();
            fineForces.clear();
            break;
        }
        const std::vector<double> cheapForces = cheap.calcForces(report.muscle, obs);
        IterationRecord rec;
        rec.iteration = j + 1;
        rec.evaluations = fineEvaluations;
        for (const ParameterEstimate& e : report.parameters) rec.parameters.push_back(e.value);
        double cost = 0;
        for (std::size_t k = 0; k < n; ++k) {
            rec.residuals.push_back(fineForces[k] - obs[k].force);
            cost += 0.5 * rec.residuals[k] * rec.residuals[k];
            offset[k] = fineForces[k] - cheapForces[k];
        }
        rec.cost = cost;
        double move = 0;
        if (!history.empty())
            for (std::size_t i = 0; i < rec.parameters.size(); ++i) {
                const double scale = std::isnan(inner.unknowns[i].scale) ? std::abs(history.back().parameters[i])
                                                                          : inner.unknowns[i].scale;
                move = std::max(move, std::abs(rec.parameters[i] - history.back().parameters[i]) / scale);
            }
        history.push_back(rec);
        if (!std::isfinite(cost)) {
            failure = "the " + fine.getName() + " model has no solution at the estimate of correction " +
                      std::to_string(j + 1);
            break;
        }
        if (j > 0 && move <= tolerance) {
            settled = true;
            break;
        }
        for (std::size_t i = 0; i < inner.unknowns.size(); ++i) inner.unknowns[i].start = rec.parameters[i];
    }

    report.forceModel = fine.getName() + " (corrected " + cheap.getName() + ")";
    report.iterations = innerIterations;
    report.forwardEvaluations = fineEvaluations;
    report.history = history;
    for (std::size_t j = 0; j < report.parameters.size(); ++j) report.parameters[j].start = problem.unknowns[j].start;
    const std::string counts = std::to_string(history.size()) + " corrections (" + std::to_string(fineEvaluations) +
                               " " + fine.getName() + " and " + std::to_string(innerEvaluations) + " " +
                               cheap.getName() + " evaluations)";
    if (!failure.empty()) {
        report.stopReason = StopReason::NotConverged;
        report.message = failure + "; " + counts;
    } else {
        report.modelForces = fineForces;
        double ssr = 0;
        for (std::size_t k = 0; k < n; ++k) {
            report.residuals[k] = fineForces[k] - obs[k].force;
            ssr += report.residuals[k] * report.residuals[k];
        }
        report.cost = 0.5 * ssr;
        report.rmsResidual = std::sqrt(ssr / double(n));
        if (!settled) {
            report.stopReason = StopReason::MaxIterations;
            report.message = "corrections did not settle within " + std::to_string(correction.maxCorrections) +
                             " (tolerance " + formatNumber(tolerance, 6) + " of the scale); " + counts +
                             "; last inner run: " + report.message;
        } else {
            report.message = counts + " settled; last inner run: " + report.message;
        }
    }
    if (report.hasUncertainty) report.uncertaintyNote += " (Jacobian of the corrected " + cheap.getName() + " model)";
    report.wallTime = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return report;
}

}  // namespace armsim
