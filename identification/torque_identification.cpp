#include "identification/torque_identification.h"
#include "basics/numbers.h"

#include "basics/bound.h"
#include "estimation/statistics.h"

#include <algorithm>
#include <cmath>
#include <set>

namespace armsim {

namespace {

using ElbowIdentifier = MuscleEstimate (*)(const ElbowMethod& method, const Population& population,
                                           const std::vector<TorqueObservation>& data, unsigned seed, int subject,
                                           const std::vector<ChannelObservation>& channels);

/// The subject's voluntary activation as twitch interpolation measures it (sd activationSd), drawn per
/// subject from the seed.
double measureSubjectActivation(const std::vector<TorqueObservation>& data, double activationSd, unsigned seed,
                                int subject) {
    return measureVoluntaryActivation(data, activationSd, seed + 7919u * unsigned(subject));
}

MuscleEstimate identifyWithThesisMethod(const ElbowMethod&, const Population& population,
                                        const std::vector<TorqueObservation>& data, unsigned, int,
                                        const std::vector<ChannelObservation>&) {
    return identifyThesisMethod(population.base, data);
}

MuscleEstimate identifyWithSynergists(const ElbowMethod& method, const Population& population,
                                      const std::vector<TorqueObservation>& data, unsigned, int,
                                      const std::vector<ChannelObservation>&) {
    SynergistOptions o = method.options;
    o.measuredActivation = kNaN;
    return identifySynergistAware(population, data, o);
}

MuscleEstimate identifyWithMeasuredActivation(const ElbowMethod& method, const Population& population,
                                              const std::vector<TorqueObservation>& data, unsigned seed, int subject,
                                              const std::vector<ChannelObservation>&) {
    SynergistOptions o = method.options;
    checkField("activation_sd", o.activationSd, Bound{0, 0.5, true, false});
    o.measuredActivation = measureSubjectActivation(data, o.activationSd, seed, subject);
    return identifySynergistAware(population, data, o);
}

MuscleEstimate identifyWithChannels(const ElbowMethod& method, const Population& population,
                                    const std::vector<TorqueObservation>& data, unsigned seed, int subject,
                                    const std::vector<ChannelObservation>& channels) {
    if (channels.empty())
        throw InputError("identifier 'channels': the data hold no channel besides torque (the protocol records "
                         "none: add ultrasound or emg to its conditions, or measurements)");
    SynergistOptions o = method.options;
    checkField("activation_sd", o.activationSd, Bound{0, 0.5, false, false});
    o.measuredActivation = o.activationSd > 0 ? measureSubjectActivation(data, o.activationSd, seed, subject) : kNaN;
    o.channels = channels;
    return identifySynergistAware(population, data, o);
}

/// The identifiers of torque data, one row each: a new identifier is a function and a row.
const std::vector<std::pair<std::string, ElbowIdentifier>>& getElbowIdentifiers() {
    static const std::vector<std::pair<std::string, ElbowIdentifier>> identifiers = {
        {"thesis", identifyWithThesisMethod},
        {"synergist", identifyWithSynergists},
        {"synergist-va", identifyWithMeasuredActivation},
        {"channels", identifyWithChannels},
    };
    return identifiers;
}

}  // namespace

const std::vector<std::string>& getElbowMethodKinds() {
    static const std::vector<std::string> kinds = [] {
        std::vector<std::string> k;
        for (const auto& [name, identify] : getElbowIdentifiers()) k.push_back(name);
        return k;
    }();
    return kinds;
}

MuscleEstimate identifyElbowMethod(const ElbowMethod& method, const Population& population,
                                   const std::vector<TorqueObservation>& data, unsigned seed, int subject,
                                   const std::vector<ChannelObservation>& channels) {
    population.base.requireVirtualMuscles("the identifiers (prior population '" + population.name + "')");
    for (const auto& [name, identify] : getElbowIdentifiers())
        if (method.kind == name) {
            MuscleEstimate e = identify(method, population, data, seed, subject, channels);
            e.method = method.label.empty() ? method.kind : method.label;
            return e;
        }
    std::string names;
    for (const std::string& k : getElbowMethodKinds()) names += (names.empty() ? "" : ", ") + k;
    throw InputError("identifier '" + method.kind + "': expected one of " + names);
}

#define ARMSIM_AT(member) [](auto& r) -> auto& { return r.member; }

const FieldTable<TorqueEstimateRow>& getTorqueEstimateFields() {
    using R = TorqueEstimateRow;
    static const FieldTable<R> fields({
        textField<R>("method", ARMSIM_AT(estimate.method)),
        boolField<R>("converged", ARMSIM_AT(estimate.converged)),
        numberField<R>("mass_kg", "kg", ARMSIM_AT(estimate.mass)),
        numberField<R>("mass_lower_kg", "kg", ARMSIM_AT(estimate.massLower)),
        numberField<R>("mass_upper_kg", "kg", ARMSIM_AT(estimate.massUpper)),
        numberField<R>("tendon_length_m", "m", ARMSIM_AT(estimate.tendonLength)),
        numberField<R>("tendon_lower_m", "m", ARMSIM_AT(estimate.tendonLower)),
        numberField<R>("tendon_upper_m", "m", ARMSIM_AT(estimate.tendonUpper)),
        numberField<R>("rms_residual_Nm", "N m", ARMSIM_AT(check.rms)),
        numberField<R>("chi_square", "1", ARMSIM_AT(check.chiSquare)),
        integerField<R>("dof", "", ARMSIM_AT(check.dof)),
        numberField<R>("p_value", "1", ARMSIM_AT(check.p)),
        numberField<R>("noise_level", "1", ARMSIM_AT(noiseLevel)),
        numberField<R>("max_force_N", "N", ARMSIM_AT(estimate.maxForce)),
        numberField<R>("max_force_lower_N", "N", ARMSIM_AT(estimate.maxForceLower)),
        numberField<R>("max_force_upper_N", "N", ARMSIM_AT(estimate.maxForceUpper)),
        numberField<R>("specific_tension_N_per_m2", "N/m^2", ARMSIM_AT(estimate.specificTension)),
    });
    return fields;
}

namespace {

/// A channel fit's verdict: the prior's check holds or conflicts; a data channel is within its noise or
/// a misfit (p < 0.05).
std::string getChannelVerdict(const ChannelFit& f) {
    const bool prior = f.channel == "prior";
    return f.p >= 0.05 ? (prior ? "holds" : "noise") : (prior ? "conflict" : "misfit");
}

}  // namespace

const FieldTable<ChannelFitRow>& getChannelFitFields() {
    using R = ChannelFitRow;
    Field<R> verdict{"verdict", "", [](const R& r, CsvRow& row) { row.addText(getChannelVerdict(r.fit)); },
                     nullptr,   // follows from p: not read back
                     [](const R& r) { return nlohmann::json(getChannelVerdict(r.fit)); }, "verdict",
                     [](const R& r) { return nlohmann::json(getChannelVerdict(r.fit)); }};
    static const FieldTable<R> fields({
        textField<R>("method", ARMSIM_AT(method)),
        textField<R>("channel", ARMSIM_AT(fit.channel)),
        integerField<R>("n", "", ARMSIM_AT(fit.n)),
        numberField<R>("chi_square", "1", ARMSIM_AT(fit.chiSquare)),
        numberField<R>("p_value", "1", ARMSIM_AT(fit.p)),
        verdict,
        textField<R>("worst", ARMSIM_AT(fit.worst)),
        numberField<R>("worst_residual_sd", "1", ARMSIM_AT(fit.worstResidual)),
    });
    return fields;
}

#undef ARMSIM_AT

std::string formatTorqueEstimatesCsv(const std::vector<TorqueObservation>& data,
                                     const std::vector<MuscleEstimate>& estimates, double noiseLevel) {
    std::vector<TorqueEstimateRow> rows;
    for (const MuscleEstimate& e : estimates) rows.push_back({e, checkTorqueResiduals(data, e, noiseLevel), noiseLevel});
    return getTorqueEstimateFields().formatCsv(rows);
}

std::string formatChannelFitsCsv(const std::vector<MuscleEstimate>& estimates) {
    std::vector<ChannelFitRow> rows;
    for (const MuscleEstimate& e : estimates)
        for (const ChannelFit& f : e.channelFits) rows.push_back({e.method, f});
    return getChannelFitFields().formatCsv(rows);
}

std::string formatTorquePredictionsCsv(const std::vector<TorqueObservation>& data,
                                       const std::vector<MuscleEstimate>& estimates) {
    const bool postures = hasPostures(data);
    std::vector<std::string> header = {"flexion_deg", "effort", "level", "repetition", "torque_Nm"};
    if (postures) header.push_back("rotation_deg");   // NaN: the model's posture
    for (const MuscleEstimate& e : estimates) header.push_back(e.method + "_Nm");
    CsvText csv(header);
    for (std::size_t k = 0; k < data.size(); ++k) {
        const TorqueObservation& d = data[k];
        CsvRow row;
        row.addNumber(d.flexionDeg).addInteger(getEffortCode(d.effort)).addNumber(d.level);
        row.addInteger(d.repetition).addNumber(d.torque);
        if (postures) row.addNumber(d.rotationDeg);
        for (const MuscleEstimate& e : estimates) row.addNumber(e.predictedTorque[k]);
        csv.addRow(row);
    }
    return csv.getText();
}

void TorqueIdentificationOptions::validate() const {
    if (!std::isnan(noiseLevel)) checkField("noise_level", noiseLevel, Bound::closed(kMinTorqueNoiseLevel, 0.5, "relative sd"));
    if (!std::isnan(activation)) checkField("activation", activation, Bound{0, 1, true, false, "fraction of full drive"});
    checkField("activation_sd", activationSd, Bound::closed(1e-4, 0.5));
    checkField("emg_crosstalk", emgCrosstalk, Bound::closed(0, 0.5));
}

std::vector<MuscleEstimate> identifyTorqueData(const Population& prior, const std::vector<TorqueObservation>& data,
                                               const TorqueIdentificationOptions& o, std::string* skipped) {
    o.validate();
    prior.base.requireVirtualMuscles("the identifiers (prior population '" + prior.name + "'" +
                                     (prior.file.empty() ? "" : ", " + prior.file) + ")");
    std::vector<MuscleEstimate> estimates;
    std::set<double> mvcAngles;
    for (const TorqueObservation& d : data)
        if (d.isThesisMvc()) mvcAngles.insert(d.flexionDeg);
    if (skipped) skipped->clear();
    if (mvcAngles.size() >= 2)
        estimates.push_back(identifyThesisMethod(prior.base, data));
    else if (skipped)
        *skipped = "thesis method: skipped (it fits flexion MVCs at >= 2 angles in the model's forearm posture; these data have " +
                   std::to_string(mvcAngles.size()) + ")";
    SynergistOptions so;
    so.noiseLevel = o.noiseLevel;
    so.freeSlowFraction = o.freeSlowFraction;
    estimates.push_back(identifySynergistAware(prior, data, so));
    if (std::isfinite(o.activation)) {
        so.measuredActivation = o.activation;
        so.activationSd = o.activationSd;
        estimates.push_back(identifySynergistAware(prior, data, so));
    }
    if (!o.channels.empty()) {
        so.channels = o.channels;
        so.emgCrosstalk = o.emgCrosstalk;
        estimates.push_back(identifySynergistAware(prior, data, so));
    }
    return estimates;
}

double findJudgingNoiseLevel(const TorqueIdentificationOptions& o, const std::vector<MuscleEstimate>& estimates) {
    if (std::isfinite(o.noiseLevel) || estimates.empty()) return o.noiseLevel;
    return estimates.back().noiseLevel;
}

TorqueResidualCheck checkTorqueResiduals(const std::vector<TorqueObservation>& data, const MuscleEstimate& e,
                                         double noise) {
    TorqueResidualCheck c;
    double sum = 0, chi = 0;
    for (std::size_t k = 0; k < data.size() && k < e.predictedTorque.size(); ++k) {
        if (!std::isfinite(e.predictedTorque[k])) continue;
        const double residual = e.predictedTorque[k] - data[k].torque;
        const double sd = noise * std::max(data[k].getLoad(), 1.0);
        sum += residual * residual;
        chi += std::pow(residual / sd, 2);
        ++c.n;
    }
    if (c.n == 0) {   // no prediction (a failed fit): no check, not a perfect one
        c.rms = c.chiSquare = c.p = NAN;
        c.dof = 0;
        return c;
    }
    c.rms = std::sqrt(sum / c.n);
    c.chiSquare = chi;
    c.dof = std::max(1, c.n - (e.method == "thesis" ? e.numParameters : 0));
    c.p = calcChiSquareSurvival(c.chiSquare, c.dof);
    return c;
}


}  // namespace armsim
