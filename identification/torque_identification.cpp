#include "identification/torque_identification.h"
#include "basics/numbers.h"

#include "basics/bound.h"
#include "basics/csv.h"
#include "estimation/statistics.h"

#include <algorithm>
#include <cmath>
#include <set>

namespace armsim {

const std::vector<std::string>& getElbowMethodKinds() {
    static const std::vector<std::string> kinds = {"thesis", "synergist", "synergist-va", "channels"};
    return kinds;
}

MuscleEstimate identifyElbowMethod(const ElbowMethod& method, const Population& population,
                                   const std::vector<TorqueObservation>& data, unsigned seed, int subject,
                                   const std::vector<ChannelObservation>& channels) {
    population.base.requireVirtualMuscles("the identifiers (prior population '" + population.name + "')");
    MuscleEstimate e;
    if (method.kind == "thesis") {
        e = identifyThesisMethod(population.base, data);
    } else if (method.kind == "synergist") {
        SynergistOptions o = method.options;
        o.measuredActivation = kNaN;
        e = identifySynergistAware(population, data, o);
    } else if (method.kind == "synergist-va") {
        SynergistOptions o = method.options;
        checkField("activation_sd", o.activationSd, Bound{0, 0.5, true, false});
        o.measuredActivation = measureVoluntaryActivation(data, o.activationSd, seed + 7919u * unsigned(subject));
        e = identifySynergistAware(population, data, o);
    } else if (method.kind == "channels") {
        if (channels.empty())
            throw InputError("identifier 'channels': the data hold no channel besides torque (the protocol records "
                             "none: add ultrasound or emg to its conditions, or measurements)");
        SynergistOptions o = method.options;
        checkField("activation_sd", o.activationSd, Bound{0, 0.5, false, false});
        o.measuredActivation = o.activationSd > 0
                                   ? measureVoluntaryActivation(data, o.activationSd, seed + 7919u * unsigned(subject))
                                   : kNaN;
        o.channels = channels;
        e = identifySynergistAware(population, data, o);
    } else {
        throw InputError("identifier '" + method.kind + "': expected thesis, synergist, synergist-va or channels");
    }
    e.method = method.label.empty() ? method.kind : method.label;
    return e;
}

std::string formatTorqueEstimatesCsv(const std::vector<TorqueObservation>& data,
                                     const std::vector<MuscleEstimate>& estimates, double noiseLevel) {
    CsvText csv({"method", "converged", "mass_kg", "mass_lower_kg", "mass_upper_kg", "tendon_length_m",
                 "tendon_lower_m", "tendon_upper_m", "rms_residual_Nm", "chi_square", "dof", "p_value", "noise_level",
                 "max_force_N", "max_force_lower_N", "max_force_upper_N", "specific_tension_N_per_m2"});
    for (const MuscleEstimate& e : estimates) {
        const TorqueResidualCheck c = checkTorqueResiduals(data, e, noiseLevel);
        CsvRow row;
        row.addText(e.method).addInteger(e.converged ? 1 : 0).addNumber(e.mass).addNumber(e.massLower);
        row.addNumber(e.massUpper).addNumber(e.tendonLength).addNumber(e.tendonLower).addNumber(e.tendonUpper);
        row.addNumber(c.rms).addNumber(c.chiSquare).addInteger(c.dof).addNumber(c.p).addNumber(noiseLevel);
        row.addNumber(e.maxForce).addNumber(e.maxForceLower).addNumber(e.maxForceUpper).addNumber(e.specificTension);
        csv.addRow(row);
    }
    return csv.getText();
}

std::string formatChannelFitsCsv(const std::vector<MuscleEstimate>& estimates) {
    CsvText csv({"method", "channel", "n", "chi_square", "p_value", "verdict", "worst", "worst_residual_sd"});
    for (const MuscleEstimate& e : estimates)
        for (const ChannelFit& f : e.channelFits) {
            CsvRow row;
            row.addText(e.method).addText(f.channel).addInteger(f.n).addNumber(f.chiSquare).addNumber(f.p);
            const bool prior = f.channel == "prior";  // the prior's check: the person fits the population or not
            row.addText(f.p >= 0.05 ? (prior ? "holds" : "noise") : (prior ? "conflict" : "misfit"));
            row.addText(f.worst).addNumber(f.worstResidual);
            csv.addRow(row);
        }
    return csv.getText();
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
    if (!std::isnan(noiseLevel)) checkField("noise_level", noiseLevel, Bound::closed(1e-4, 0.5));
    if (!std::isnan(activation)) checkField("activation", activation, Bound{0, 1, true, false, "fraction of full drive"});
    checkField("activation_sd", activationSd, Bound::closed(1e-4, 0.5));
    checkField("emg_crosstalk", emgCrosstalk, Bound::closed(0, 0.5));
}

std::vector<MuscleEstimate> identifyTorqueData(const Population& prior, const std::vector<TorqueObservation>& data,
                                               const TorqueIdentificationOptions& o, std::string* skipped) {
    o.validate();
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
