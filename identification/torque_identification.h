// Identification from one person's joint torque data (`armsim identify-torque`, validations and
// studies): the identifiers by name, the set run on a lab's data, residual checks and the CSV tables.
#pragma once

#include "basics/fields.h"

#include "basics/numbers.h"

#include "identification/synergist_identifier.h"
#include "identification/thesis_method.h"

#include <string>
#include <vector>

namespace armsim {

/// Which identifiers identifyTorqueData runs on one person's torque data (as `armsim identify-torque`).
struct TorqueIdentificationOptions {
    double noiseLevel = kNaN;   ///< relative sd of one trial's torque [1]; NaN: estimated from repetitions
    double activation = kNaN;   ///< measured voluntary activation [1]; NaN: not measured (no synergist-va)
    double activationSd = 0.02;      ///< sd of that measurement [1]
    bool freeSlowFraction = false;   ///< the synergist kinds free the flexors' slow-fibre fractions
    /// Channels besides torque (experiments/channels.h); non-empty: also the "channels" fit.
    std::vector<ChannelObservation> channels;
    double emgCrosstalk = 0.10;      ///< c of the EMG measurement model [1]
    /// InputError naming the field (noise_level in [1e-4, 0.5], activation in [0, 1], activation_sd
    /// in [1e-4, 0.5], emg_crosstalk in [0, 0.5]).
    void validate() const;
};

/// Runs "thesis" (when the data hold flexion MVCs at two or more angles; otherwise *skipped says why),
/// "synergist", with a measured activation "synergist-va", and with channels "channels" (every
/// channel, and the activation when measured), each with the prior population.
std::vector<MuscleEstimate> identifyTorqueData(const Population& prior, const std::vector<TorqueObservation>& data,
                                               const TorqueIdentificationOptions& options = {},
                                               std::string* skipped = nullptr);

/// An estimate's torque residuals judged against a relative noise level: chi-square with
/// sd_k = noise * max(|torque_k|, 1 N m). The thesis method's two free parameters are subtracted from
/// the degrees of freedom; the MAP fits' are not (their prior keeps the effective count lower: a
/// conservative test for them).
struct TorqueResidualCheck {
    double rms = kNaN;      ///< of predicted - measured [N m], over the observations it predicts
    double chiSquare = kNaN;
    int n = 0, dof = 0;
    double p = kNaN;        ///< chi-square tail probability; >= 0.05: consistent with the noise
};
TorqueResidualCheck checkTorqueResiduals(const std::vector<TorqueObservation>& data, const MuscleEstimate& estimate,
                                         double noiseLevel);
/// One row of torque_estimates.csv: an estimate, its residual check and the noise level it was judged at.
struct TorqueEstimateRow {
    MuscleEstimate estimate;
    TorqueResidualCheck check;
    double noiseLevel = kNaN;   ///< relative torque sd [1]
};
const FieldTable<TorqueEstimateRow>& getTorqueEstimateFields();
/// One row of channel_fits.csv: an estimate's method and one of its channel fits.
struct ChannelFitRow {
    std::string method;
    ChannelFit fit;
};
const FieldTable<ChannelFitRow>& getChannelFitFields();
/// torque_estimates.csv of `armsim identify-torque`: per estimate its interval, its residual check against
/// noiseLevel (checkTorqueResiduals) and the noise level.
std::string formatTorqueEstimatesCsv(const std::vector<TorqueObservation>& data,
                                     const std::vector<MuscleEstimate>& estimates, double noiseLevel);
/// channel_fits.csv: per estimate and channel, the chi-square check and the worst measurement.
std::string formatChannelFitsCsv(const std::vector<MuscleEstimate>& estimates);
/// torque_predictions.csv: every observation with each estimate's predicted torque (empty where none).
std::string formatTorquePredictionsCsv(const std::vector<TorqueObservation>& data,
                                       const std::vector<MuscleEstimate>& estimates);
/// The noise level residuals are judged against: the given one, or else the last (synergist) fit's
/// estimate from the repetitions.
double findJudgingNoiseLevel(const TorqueIdentificationOptions& options, const std::vector<MuscleEstimate>& estimates);

/// One identifier of a validation or a study, with its options.
struct ElbowMethod {
    std::string label;           ///< its name in results (default: the kind)
    std::string kind = "synergist";  ///< "thesis", "synergist", "synergist-va" or "channels"
    /// synergist kinds: freeSlowFraction, includeSynergists, noiseLevel; synergist-va and channels also
    /// activationSd (the twitch-interpolation measurement's sd, drawn per subject by
    /// measureVoluntaryActivation; channels: 0 = not measured); channels also emgCrosstalk.
    SynergistOptions options;
};
/// The kinds ElbowMethod::kind may name.
const std::vector<std::string>& getElbowMethodKinds();

/// Identifies `data` of person `subject` with `method` (population as the synergist prior, its base
/// model as the thesis method's assumed model); the channels method also fits `channels` (every channel
/// the protocol recorded) with twitch interpolation. seed: of the study or validation (the VA
/// measurement's seed derives from it and the subject). Throws what the identifier throws, and
/// InputError for the channels method without channel data.
MuscleEstimate identifyElbowMethod(const ElbowMethod& method, const Population& population,
                                   const std::vector<TorqueObservation>& data, unsigned seed, int subject,
                                   const std::vector<ChannelObservation>& channels = {});


}  // namespace armsim
