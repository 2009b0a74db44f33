#include "studies/torque_validation.h"
#include "basics/numbers.h"

#include "basics/bound.h"
#include "basics/format.h"
#include "basics/csv.h"
#include "basics/parallel.h"
#include "basics/quick_run.h"
#include "identification/synergist_identifier.h"

#include <fmt/format.h>

#include <algorithm>
#include <iterator>
#include <cmath>

namespace armsim {

ElbowValidationRow makeElbowValidationRow(const Population& population, const VirtualSubject& v, double noise,
                                          const std::string& method, const MuscleEstimate& e) {
    const int primary = population.base.primary;
    ElbowValidationRow row;
    row.subject = v.index;
    row.noise = noise;
    row.method = method;
    row.trueMass = v.setup.muscles[primary].params.mass;
    row.trueTendonLength = v.setup.muscles[primary].params.optimalTendonLength;
    const MuscleParameters& q = v.setup.muscles[primary].params;
    row.trueMaxForce = q.coefficients.sigma * q.mass / (q.coefficients.density * q.optimalFascicleLength);
    if (std::isfinite(e.maxForce)) row.maxForceError = e.maxForce / row.trueMaxForce - 1;
    if (std::isfinite(e.maxForceLower))
        row.maxForceCovered = row.trueMaxForce >= e.maxForceLower && row.trueMaxForce <= e.maxForceUpper;
    row.estimate = e;
    for (const ChannelFit& f : e.channelFits)
        if (f.channel == "prior") row.priorCheckP = f.p;
    row.massError = e.mass / row.trueMass - 1;
    row.tendonError = e.tendonLength - row.trueTendonLength;
    if (std::isfinite(e.massLower)) row.massCovered = row.trueMass >= e.massLower && row.trueMass <= e.massUpper;
    if (std::isfinite(e.tendonLower))
        row.tendonCovered = row.trueTendonLength >= e.tendonLower && row.trueTendonLength <= e.tendonUpper;
    row.voluntaryActivation = v.setup.effort.voluntaryActivation;
    row.coContraction = v.setup.effort.coContraction;
    row.strengthLevel = v.strengthLevel;
    // Nuisance truths of the model file's roles (a model without them leaves NaN).
    const ArmSetup& base = population.base;
    for (int i : base.getBicepsHeads())
        if (i != primary) row.bicepsShortScale = v.massScale[i] / v.massScale[primary];
    double syn = 0;
    for (int i : base.synergists) syn += v.massScale[i];
    if (!base.synergists.empty()) row.synergistScale = syn / double(base.synergists.size()) / v.massScale[primary];
    return row;
}

std::vector<ElbowValidationRow> runElbowValidation(const Population& population, const ElbowValidationSettings& settings,
                                                   const std::function<void(int, int)>& progress) {
    return runElbowValidation(population, population, settings, progress);
}

namespace {

// What every subject of a validation shares: the noise levels and the methods.
struct ValidationPlan {
    std::vector<double> levels;
    std::vector<ElbowMethod> methods;
};

ValidationPlan planElbowValidation(const Population& population, const Population& prior,
                                   const ElbowValidationSettings& settings) {
    population.validate();
    prior.validate();
    checkIdentifiablePrior(prior);
    prior.base.requireVirtualMuscles("the identifiers (prior population '" + prior.name + "')");
    const std::string& truthPrimary = population.base.muscles[population.base.primary].params.name;
    const std::string& priorPrimary = prior.base.muscles[prior.base.primary].params.name;
    if (truthPrimary != priorPrimary)
        throw InputError("the prior's model '" + prior.base.name + "'" + (prior.file.empty() ? "" : " (" + prior.file + ")") +
                         " identifies muscle '" + priorPrimary + "', the truth's model '" + population.base.name + "'" +
                         (population.file.empty() ? "" : " (" + population.file + ")") + " has '" + truthPrimary +
                         "' as its primary muscle: expected the same muscle");
    settings.protocol.validate();
    checkField("subjects", settings.subjects, Bound::closed(1, 1e6));
    checkField("activation_sd", settings.activationSd, Bound::closed(0, 0.5));
    ValidationPlan plan;
    plan.levels = settings.noiseLevels;
    if (plan.levels.empty()) plan.levels.push_back(population.transducerNoise);
    for (double v : plan.levels) checkField("noise", v, Bound{0, 0.5, false, true, "relative sd"});
    for (const std::string& kind : getElbowMethodKinds()) {
        if ((kind == "synergist-va" && settings.activationSd == 0) || (kind == "channels" && !settings.protocol.hasChannels()))
            continue;
        ElbowMethod m;
        m.kind = kind;
        m.options.freeSlowFraction = settings.freeSlowFraction;
        m.options.activationSd = settings.activationSd;
        m.options.emgCrosstalk = settings.protocol.channelNoise.emgCrosstalk;
        plan.methods.push_back(m);
    }
    const double fits = double(settings.subjects) * double(plan.levels.size()) * double(plan.methods.size());
    if (fits > kMaxElbowValidationFits)
        throw InputError(fmt::format("{} subjects x {} noise levels x {} identifiers = {:.0f} fits, each a row kept in "
                                     "memory (about {}): expected at most {:.0f} (fewer subjects or noise levels; "
                                     "armsim study journals its rows)",
                                     settings.subjects, plan.levels.size(), plan.methods.size(), fits,
                                     formatBytes(2 * fits * sizeof(ElbowValidationRow)), kMaxElbowValidationFits));
    return plan;
}

ElbowValidationSubject runPlannedSubject(const Population& population, const Population& prior,
                                         const ElbowValidationSettings& settings, const ValidationPlan& plan, int index) {
    ElbowValidationSubject out;
    out.subject = drawSubject(population, settings.seed, index);
    const VirtualSubject& v = out.subject;
    out.torque = synthesizeTorqueData(v, settings.protocol, settings.seed, 1);
    if (settings.protocol.hasChannels()) out.channels = synthesizeChannelData(v, settings.protocol, out.torque, settings.seed);
    for (double level : plan.levels) {
        const std::vector<TorqueObservation> data = setTransducerNoise(out.torque, level);
        for (const ElbowMethod& m : plan.methods) {
            // A method that cannot use these data (the thesis method with fewer flexion-MVC angles
            // than unknowns) is recorded as failed, not fatal.
            MuscleEstimate e;
            try {
                e = identifyElbowMethod(m, prior, data, settings.seed, index, out.channels);
            } catch (const std::exception& x) {
                e.method = m.kind;
                e.message = x.what();
            }
            out.rows.push_back(makeElbowValidationRow(population, v, level, m.kind, e));
        }
    }
    return out;
}

}  // namespace

long countElbowValidationFits(const Population& truth, const Population& prior, const ElbowValidationSettings& settings) {
    const ValidationPlan plan = planElbowValidation(truth, prior, settings);
    return long(settings.subjects) * long(plan.levels.size()) * long(plan.methods.size());
}

ElbowValidationSubject runElbowValidationSubject(const Population& truth, const Population& prior,
                                                 const ElbowValidationSettings& settings, int index) {
    checkField("subject index", index, Bound::closed(0, 1e6));
    return runPlannedSubject(truth, prior, settings, planElbowValidation(truth, prior, settings), index);
}

std::vector<ElbowValidationRow> runElbowValidation(const Population& population, const Population& prior,
                                                   const ElbowValidationSettings& settings,
                                                   const std::function<void(int, int)>& progress) {
    const ValidationPlan plan = planElbowValidation(population, prior, settings);
    const int subjects = capForQuickRun(settings.subjects, kQuickSubjects, "validation subjects");
    std::vector<std::vector<ElbowValidationRow>> perSubject(subjects);
    runParallel(subjects, settings.jobs, [&](int s) {
        perSubject[s] = runPlannedSubject(population, prior, settings, plan, s).rows;
    }, progress);
    std::vector<ElbowValidationRow> rows;
    for (auto& r : perSubject) {
        rows.insert(rows.end(), std::make_move_iterator(r.begin()), std::make_move_iterator(r.end()));
        std::vector<ElbowValidationRow>().swap(r);   // each subject's rows freed as they are merged
    }
    return rows;
}

std::vector<ElbowValidationSummary> summarizeElbowValidation(const std::vector<ElbowValidationRow>& rows) {
    ElbowValidationAccumulator sum;
    for (const ElbowValidationRow& r : rows) sum.add(r);
    return sum.getSummaries();
}

void ElbowValidationAccumulator::Running::add(double x) {
    ++n;
    const double d = x - mean;
    mean += d / double(n);
    m2 += d * (x - mean);
}

void ElbowValidationAccumulator::add(const ElbowValidationRow& r) {
    auto it = std::find_if(cells_.begin(), cells_.end(), [&](const Cell& c) { return c.method == r.method && c.noise == r.noise; });
    if (it == cells_.end()) {
        cells_.push_back({});
        it = cells_.end() - 1;
        it->method = r.method;
        it->noise = r.noise;
    }
    Cell& c = *it;
    ++c.subjects;
    if (r.estimate.converged) ++c.converged;
    if (std::isfinite(r.maxForceError)) {
        ++c.fn, c.fb += r.maxForceError, c.fm += r.maxForceError * r.maxForceError;
        if (r.maxForceCovered >= 0) ++c.fcn, c.fc += r.maxForceCovered;
    }
    if (!std::isfinite(r.massError) || !std::isfinite(r.tendonError)) return;
    ++c.n;
    c.mb += r.massError, c.mm += r.massError * r.massError;
    c.tb += r.tendonError, c.tm += r.tendonError * r.tendonError;
    c.massError.add(r.massError), c.massSquare.add(r.massError * r.massError);
    c.tendonError.add(r.tendonError), c.tendonSquare.add(r.tendonError * r.tendonError);
    if (r.massCovered >= 0) {
        ++c.mn, c.mc += r.massCovered;
        c.mw += (r.estimate.massUpper - r.estimate.massLower) / r.estimate.mass;
    }
    if (r.tendonCovered >= 0) {
        ++c.tn, c.tc += r.tendonCovered;
        c.tw += r.estimate.tendonUpper - r.estimate.tendonLower;
    }
    if (std::isfinite(r.priorCheckP)) {
        ++c.pn;
        if (r.priorCheckP < 0.05) {
            ++c.pf;
        } else {
            if (r.massCovered >= 0) ++c.pmn, c.pmc += r.massCovered;
            if (r.tendonCovered >= 0) ++c.ptn, c.ptc += r.tendonCovered;
        }
    }
}

std::vector<ElbowValidationSummary> ElbowValidationAccumulator::getSummaries() const {
    std::vector<ElbowValidationSummary> out;
    for (const Cell& c : cells_) {
        ElbowValidationSummary s;
        s.method = c.method;
        s.noise = c.noise;
        s.subjects = c.subjects;
        s.converged = c.converged;
        s.massBias = s.massRmse = s.tendonBias = s.tendonRmse = kNaN;  // no estimate
        if (c.n > 0) {
            s.massBias = c.mb / c.n, s.massRmse = std::sqrt(c.mm / c.n);
            s.tendonBias = c.tb / c.n, s.tendonRmse = std::sqrt(c.tm / c.n);
        }
        if (c.mn > 0) s.massCoverage = double(c.mc) / c.mn, s.massIntervalWidth = c.mw / c.mn;
        if (c.fn > 0) s.maxForceBias = c.fb / c.fn, s.maxForceRmse = std::sqrt(c.fm / c.fn);
        if (c.fcn > 0) s.maxForceCoverage = double(c.fc) / c.fcn;
        if (c.tn > 0) s.tendonCoverage = double(c.tc) / c.tn, s.tendonIntervalWidth = c.tw / c.tn;
        if (c.pn > 0) s.priorFlagged = double(c.pf) / c.pn;
        if (c.pmn > 0) s.massCoveragePassed = double(c.pmc) / c.pmn;
        if (c.ptn > 0) s.tendonCoveragePassed = double(c.ptc) / c.ptn;
        // Standard errors over subjects: the mean's, the RMSE's by the delta method (sd of the squared
        // error / (2 RMSE sqrt n)), a fraction's binomial sqrt(p (1 - p) / n).
        auto errors = [](const Running& e, const Running& e2, double rmse, double& biasSe, double& rmseSe) {
            const double k = double(e.n);
            if (k < 2) return;
            biasSe = std::sqrt(e.m2 / (k - 1) / k);
            rmseSe = rmse > 0 ? std::sqrt(e2.m2 / (k - 1) / k) / (2 * rmse) : 0.0;
        };
        errors(c.massError, c.massSquare, s.massRmse, s.massBiasSe, s.massRmseSe);
        errors(c.tendonError, c.tendonSquare, s.tendonRmse, s.tendonBiasSe, s.tendonRmseSe);
        if (c.mn > 0) s.massCoverageSe = std::sqrt(s.massCoverage * (1 - s.massCoverage) / c.mn);
        if (c.tn > 0) s.tendonCoverageSe = std::sqrt(s.tendonCoverage * (1 - s.tendonCoverage) / c.tn);
        out.push_back(s);
    }
    return out;
}

#define ARMSIM_AT(member) [](auto& r) -> auto& { return r.member; }

const FieldTable<ElbowValidationRow>& getElbowValidationFields() {
    using R = ElbowValidationRow;
    static const FieldTable<R> fields({
        integerField<R>("subject", "", ARMSIM_AT(subject)),
        numberField<R>("noise", "1", ARMSIM_AT(noise)),
        textField<R>("method", ARMSIM_AT(method)),
        boolField<R>("converged", ARMSIM_AT(estimate.converged)),
        numberField<R>("true_mass_kg", "kg", ARMSIM_AT(trueMass)),
        numberField<R>("mass_kg", "kg", ARMSIM_AT(estimate.mass)),
        numberField<R>("mass_lower_kg", "kg", ARMSIM_AT(estimate.massLower)),
        numberField<R>("mass_upper_kg", "kg", ARMSIM_AT(estimate.massUpper)),
        numberField<R>("mass_error_pct", "%", ARMSIM_AT(massError), 100),
        flagField<R>("mass_covered", ARMSIM_AT(massCovered)),
        numberField<R>("true_tendon_length_m", "m", ARMSIM_AT(trueTendonLength)),
        numberField<R>("tendon_length_m", "m", ARMSIM_AT(estimate.tendonLength)),
        numberField<R>("tendon_lower_m", "m", ARMSIM_AT(estimate.tendonLower)),
        numberField<R>("tendon_upper_m", "m", ARMSIM_AT(estimate.tendonUpper)),
        numberField<R>("tendon_error_mm", "mm", ARMSIM_AT(tendonError), 1000),
        flagField<R>("tendon_covered", ARMSIM_AT(tendonCovered)),
        numberField<R>("voluntary_activation", "1", ARMSIM_AT(voluntaryActivation)),
        numberField<R>("co_contraction", "1", ARMSIM_AT(coContraction)),
        numberField<R>("strength_level", "1", ARMSIM_AT(strengthLevel)),
        numberField<R>("biceps_short_scale", "1", ARMSIM_AT(bicepsShortScale)),
        numberField<R>("synergist_scale", "1", ARMSIM_AT(synergistScale)),
        numberField<R>("noise_level_used", "1", ARMSIM_AT(estimate.noiseLevel)),
        numberField<R>("rms_residual_Nm", "N m", ARMSIM_AT(estimate.rmsResidual)),
        numberField<R>("true_max_force_N", "N", ARMSIM_AT(trueMaxForce)),
        numberField<R>("max_force_N", "N", ARMSIM_AT(estimate.maxForce)),
        numberField<R>("max_force_lower_N", "N", ARMSIM_AT(estimate.maxForceLower)),
        numberField<R>("max_force_upper_N", "N", ARMSIM_AT(estimate.maxForceUpper)),
        numberField<R>("max_force_error_pct", "%", ARMSIM_AT(maxForceError), 100),
        flagField<R>("max_force_covered", ARMSIM_AT(maxForceCovered)),
        numberField<R>("prior_check_p", "1", ARMSIM_AT(priorCheckP)),
    });
    return fields;
}

const FieldTable<ElbowValidationSummary>& getElbowValidationSummaryFields() {
    using S = ElbowValidationSummary;
    static const FieldTable<S> fields({
        textField<S>("method", ARMSIM_AT(method)),
        numberField<S>("noise", "1", ARMSIM_AT(noise)),
        integerField<S>("subjects", "", ARMSIM_AT(subjects)),
        integerField<S>("converged", "", ARMSIM_AT(converged)),
        numberField<S>("mass_bias_pct", "%", ARMSIM_AT(massBias), 100),
        numberField<S>("mass_rmse_pct", "%", ARMSIM_AT(massRmse), 100),
        numberField<S>("mass_coverage", "1", ARMSIM_AT(massCoverage)),
        numberField<S>("tendon_bias_mm", "mm", ARMSIM_AT(tendonBias), 1000),
        numberField<S>("tendon_rmse_mm", "mm", ARMSIM_AT(tendonRmse), 1000),
        numberField<S>("tendon_coverage", "1", ARMSIM_AT(tendonCoverage)),
        numberField<S>("mass_bias_se_pct", "%", ARMSIM_AT(massBiasSe), 100),
        numberField<S>("mass_rmse_se_pct", "%", ARMSIM_AT(massRmseSe), 100),
        numberField<S>("mass_coverage_se", "1", ARMSIM_AT(massCoverageSe)),
        numberField<S>("tendon_bias_se_mm", "mm", ARMSIM_AT(tendonBiasSe), 1000),
        numberField<S>("tendon_rmse_se_mm", "mm", ARMSIM_AT(tendonRmseSe), 1000),
        numberField<S>("tendon_coverage_se", "1", ARMSIM_AT(tendonCoverageSe)),
        numberField<S>("max_force_bias_pct", "%", ARMSIM_AT(maxForceBias), 100),
        numberField<S>("max_force_rmse_pct", "%", ARMSIM_AT(maxForceRmse), 100),
        numberField<S>("max_force_coverage", "1", ARMSIM_AT(maxForceCoverage)),
        numberField<S>("prior_flagged", "1", ARMSIM_AT(priorFlagged)),
        numberField<S>("mass_coverage_prior_passed", "1", ARMSIM_AT(massCoveragePassed)),
        numberField<S>("tendon_coverage_prior_passed", "1", ARMSIM_AT(tendonCoveragePassed)),
        numberField<S>("mass_interval_width", "1", ARMSIM_AT(massIntervalWidth)),
        numberField<S>("tendon_interval_width_mm", "mm", ARMSIM_AT(tendonIntervalWidth), 1000),
    });
    return fields;
}

#undef ARMSIM_AT

std::string formatElbowValidationCsv(const std::vector<ElbowValidationRow>& rows) {
    return getElbowValidationFields().formatCsv(rows);
}

std::string formatElbowValidationSummaryCsv(const std::vector<ElbowValidationSummary>& summaries) {
    return getElbowValidationSummaryFields().formatCsv(summaries);
}


}  // namespace armsim
