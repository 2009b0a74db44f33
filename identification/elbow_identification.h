// Identifying the biceps on a realistic elbow (issue 11): MVC torque data synthesized from virtual
// subjects (experiments/population.h) in the seven-muscle arm, and identifiers of the biceps long
// head's mass M and optimal tendon length L0T from them:
//
// "thesis"       The thesis's method as it is: the biceps force is the tared torque over the biceps
//                moment arm, a biceps-only model at full activation is fitted to those forces (steady
//                model, lm, relative noise; intervals from the residual scatter).
// "synergist"    Maximum a posteriori fit of the net tared joint torque predicted by the whole elbow
//                model (identification/map_estimate.h). Free: a log mass scale per biceps head and per
//                synergist, one for the extensors, the biceps heads' tendon and fascicle length scales,
//                the synergists' tendon and fascicle scales, voluntary activation VA and co-contraction
//                CC. Prior: the population's (mass scales share the person-level variance and add the
//                per-muscle one; lengths and effort from their spreads and ranges). Data residuals are
//                weighted by a relative noise level estimated from the repetitions' scatter. The
//                posterior covariance is the Laplace approximation; 95 % intervals are symmetric in the
//                log scales (Student-t quantile with the noise estimate's degrees of freedom, since the
//                noise level is estimated), so the M and L0T intervals are exp-transformed.
// "synergist-va" The same with VA measured by twitch interpolation (one more residual).
// The prediction is the steady isometric torque at the protocol's angles with the subject's effort
// less the relaxed torque (the transducer is tared at rest), summed over every muscle.
#pragma once

#include "experiments/torque_protocol.h"
#include "model/mvc_curve.h"

#include <functional>
#include <string>
#include <vector>

namespace armsim {

/// An identifier's estimate of the primary muscle (the biceps long head).
struct BicepsEstimate {
    std::string method;                  ///< "thesis", "synergist" or "synergist-va"
    bool converged = false;
    std::string message;                 ///< solver summary or why it failed
    double mass = 0.0 / 0.0;             ///< M [kg]
    double tendonLength = 0.0 / 0.0;     ///< L0T [m]
    double massLower = 0.0 / 0.0, massUpper = 0.0 / 0.0;        ///< 95 % interval [kg]
    double tendonLower = 0.0 / 0.0, tendonUpper = 0.0 / 0.0;    ///< 95 % interval [m]
    double noiseLevel = 0.0 / 0.0;       ///< relative torque sd used to weight the data [1]
    int noiseDegreesOfFreedom = 0;       ///< of that sd's estimate (repetitions); 0: taken as known
    std::vector<std::string> nuisanceNames;    ///< synergist: activation, co-contraction, length and mass scales
    std::vector<double> nuisance;              ///< their estimates
    double massTendonCorrelation = 0.0 / 0.0;  ///< posterior correlation of ln M and ln L0T
    double rmsResidual = 0.0 / 0.0;            ///< of the torque [N m] (thesis: of the force [N])
    /// Per observation: the torque the method predicts at the estimate [N m] (thesis: the fitted biceps
    /// force x the biceps moment arm, flexion MVCs only; NaN elsewhere).
    std::vector<double> predictedTorque;
    int numParameters = 0;                     ///< free parameters of the fit
    int iterations = 0;                        ///< solver iterations
};

/// The thesis's method on torque data, with `assumed` as the experimenter's model (geometry and the
/// biceps's other parameters; its primary muscle is the biceps).
BicepsEstimate identifyThesisMethod(const ArmSetup& assumed, const std::vector<TorqueObservation>& data);

/// The synergist-aware identifier's model and extra measurements.
struct SynergistOptions {
    /// Which muscles the model groups (names in the population's base model).
    std::vector<std::string> biceps = {"BIClong", "BICshort"};  ///< share s_b and t_b
    std::vector<std::string> synergists = {"BRA", "BRD"};       ///< share s_s
    /// false: the synergists are left out of the identifier's model (no torque from them): the
    /// ablation that shows what they are for.
    bool includeSynergists = true;
    // Every extensor shares s_e.
    /// The subject's voluntary activation measured by twitch interpolation (superimposed stimulation
    /// during the MVCs) [1]; NaN: not measured. Adds the residual (VA - measured) / activationSd.
    double measuredActivation = 0.0 / 0.0;
    double activationSd = 0.02;  ///< sd of that measurement [1] (an assumption, see measureVoluntaryActivation)
    /// Free the flexors' slow-fibre fractions (one shift for the biceps heads, one for the synergists;
    /// prior sd the population's): submaximal efforts depend on them.
    bool freeSlowFraction = false;
    /// Relative sd of one trial's torque [1]; NaN: estimated from the repetitions (pooled over the
    /// conditions), or the population's transducer noise when nothing is repeated.
    double noiseLevel = 0.0 / 0.0;
};

/// The synergist-aware identifier's model: its parameters x, their prior and bounds, and the tared
/// steady torque it predicts for a list of effort conditions (also used by experiment design).
/// x = [ln t_b, VA, CC, ln f_b, ln t_s, ln f_s, ln s_e, d_b, d_s, then ln s_m for every biceps head and
/// synergist m]: t tendon, f fascicle length and s mass scales; b the biceps heads (one tendon and one
/// fascicle scale), s the synergists, e the extensors (one mass scale); d the change of the slow-fibre
/// fraction F_slow (added, biceps heads and synergists; held at 0 unless freeSlowFraction). Prior: every mass scale shares the
/// person-level variance (the extensors' one scale averages their muscle terms); lengths and effort
/// independent, effort uniform ranges as their mean and sd.
class SynergistModel {
public:
    /// Throws InputError for muscle names not in the population's model or a primary muscle that is
    /// not in the biceps group. Conditions may repeat (each distinct angle and effort kind is computed
    /// once); their repetitions are ignored.
    SynergistModel(const Population& prior, const SynergistOptions& options,
                   const std::vector<TorqueCondition>& conditions);
    int getNumParameters() const { return kFirstMass + int(biceps_.size() + synergists_.size()); }
    std::vector<std::string> getParameterNames() const;
    int getMassIndex() const;                 ///< ln M of the primary muscle
    std::vector<int> getFlexorMassIndices() const;  ///< the biceps heads' and synergists' ln mass scales
    static constexpr int getTendonIndex() { return kTendon; }          ///< ln t_b
    static constexpr int getActivationIndex() { return kActivation; }  ///< VA
    const std::vector<double>& getPriorMean() const { return priorMean_; }
    const std::vector<std::vector<double>>& getPriorCovariance() const { return priorCovariance_; }
    const std::vector<double>& getLower() const { return lower_; }
    const std::vector<double>& getUpper() const { return upper_; }
    /// Tared torque of every condition at x [N m]; throws SimulationError where a muscle has no steady state.
    std::vector<double> calcTorques(const double* x) const;
    /// The population's model with x's muscles.
    std::vector<MuscleSpec> makeMuscles(const double* x) const;

private:
    static constexpr int kTendon = 0, kActivation = 1, kCoContraction = 2, kFascicle = 3, kSynergistTendon = 4,
                         kSynergistFascicle = 5, kExtensorMass = 6, kBicepsSlow = 7, kSynergistSlow = 8,
                         kFirstMass = 9;
    struct EffortKind {
        MuscleGroup group;
        double level;
    };
    int findMassIndex(int muscle) const;
    const ArmSetup* base_;
    std::vector<int> biceps_, synergists_, extensors_, leftOut_;
    MvcGeometry geometry_;
    std::vector<EffortKind> kinds_;
    std::vector<int> angleOf_, kindOf_;       // condition -> angle index, effort kind
    std::vector<double> priorMean_, lower_, upper_;
    std::vector<std::vector<double>> priorCovariance_;
    friend BicepsEstimate identifySynergistAware(const Population&, const std::vector<TorqueObservation>&,
                                                 const SynergistOptions&);
};

/// The synergist-aware MAP identifier with the population as prior.
BicepsEstimate identifySynergistAware(const Population& prior, const std::vector<TorqueObservation>& data,
                                      const SynergistOptions& options = {});

/// Which identifiers identifyTorqueData runs on one person's torque data (as `armsim identify-torque`).
struct TorqueIdentificationOptions {
    double noiseLevel = 0.0 / 0.0;   ///< relative sd of one trial's torque [1]; NaN: estimated from repetitions
    double activation = 0.0 / 0.0;   ///< measured voluntary activation [1]; NaN: not measured (no synergist-va)
    double activationSd = 0.02;      ///< sd of that measurement [1]
    /// InputError naming the field (noise_level in [1e-4, 0.5], activation in [0, 1], activation_sd
    /// in [1e-4, 0.5]).
    void validate() const;
};

/// Runs "thesis" (when the data hold flexion MVCs at two or more angles; otherwise *skipped says why),
/// "synergist" and, with a measured activation, "synergist-va", each with the prior population.
std::vector<BicepsEstimate> identifyTorqueData(const Population& prior, const std::vector<TorqueObservation>& data,
                                               const TorqueIdentificationOptions& options = {},
                                               std::string* skipped = nullptr);

/// An estimate's torque residuals judged against a relative noise level: chi-square with
/// sd_k = noise * max(|torque_k|, 1 N m). The thesis method's two free parameters are subtracted from
/// the degrees of freedom; the MAP fits' are not (their prior keeps the effective count lower: a
/// conservative test for them).
struct TorqueResidualCheck {
    double rms = 0.0 / 0.0;      ///< of predicted - measured [N m], over the observations it predicts
    double chiSquare = 0.0 / 0.0;
    int n = 0, dof = 0;
    double p = 0.0 / 0.0;        ///< chi-square tail probability; >= 0.05: consistent with the noise
};
TorqueResidualCheck checkTorqueResiduals(const std::vector<TorqueObservation>& data, const BicepsEstimate& estimate,
                                         double noiseLevel);
/// torque_estimates.csv of `armsim identify-torque`: per estimate its interval, its residual check against
/// noiseLevel (checkTorqueResiduals) and the noise level.
std::string formatTorqueEstimatesCsv(const std::vector<TorqueObservation>& data,
                                     const std::vector<BicepsEstimate>& estimates, double noiseLevel);
/// torque_predictions.csv: every observation with each estimate's predicted torque (empty where none).
std::string formatTorquePredictionsCsv(const std::vector<TorqueObservation>& data,
                                       const std::vector<BicepsEstimate>& estimates);
/// The noise level residuals are judged against: the given one, or else the last (synergist) fit's
/// estimate from the repetitions.
double findJudgingNoiseLevel(const TorqueIdentificationOptions& options, const std::vector<BicepsEstimate>& estimates);

/// A twitch-interpolation measurement of the subject's voluntary activation: the mean activation of
/// the efforts actually produced, plus N(0, sd^2) measurement error, within [0, 1]. The default sd
/// 0.02 is an assumption for a practised lab, not a cited value.
double measureVoluntaryActivation(const std::vector<TorqueObservation>& data, double sd, unsigned seed);

/// Net tared steady torque of `setup` at the angles [N m]: every muscle at its steady state with the
/// agonists of `group` at `effort`'s voluntary activation and the antagonists at its co-contraction,
/// less the same with every muscle relaxed (what a tared transducer reads at the plateau of an effort).
std::vector<double> calcTaredSteadyTorque(const ArmSetup& setup, const SubjectEffort& effort,
                                          const std::vector<double>& flexionDeg, MuscleGroup group = MuscleGroup::Flexor);

/// One identification in a validation: truth, estimate, coverage.
struct ElbowValidationRow {
    int subject = 0;
    double noise = 0;                  ///< transducer noise used [1]
    std::string method;
    double trueMass = 0, trueTendonLength = 0;   ///< the subject's primary muscle [kg], [m]
    BicepsEstimate estimate;
    double massError = 0.0 / 0.0;      ///< estimate / truth - 1 [1]
    double tendonError = 0.0 / 0.0;    ///< estimate - truth [m]
    int massCovered = -1;              ///< 1/0: truth inside/outside the interval; -1: no interval
    int tendonCovered = -1;
    // Nuisance truths, for error-vs-nuisance plots.
    double voluntaryActivation = 0, coContraction = 0, strengthLevel = 0;
    double bicepsShortScale = 0.0 / 0.0;  ///< second biceps head's mass scale / primary's [1]
    double synergistScale = 0.0 / 0.0;    ///< mean mass scale of the synergists / primary's [1]
};

/// One identifier of a validation or a study, with its options.
struct ElbowMethod {
    std::string label;           ///< its name in results (default: the kind)
    std::string kind = "synergist";  ///< "thesis", "synergist" or "synergist-va"
    /// synergist kinds: freeSlowFraction, includeSynergists, noiseLevel; synergist-va also activationSd
    /// (the twitch-interpolation measurement's sd, drawn per subject by measureVoluntaryActivation).
    SynergistOptions options;
};
/// The kinds ElbowMethod::kind may name.
const std::vector<std::string>& getElbowMethodKinds();

/// Identifies `data` of person `subject` with `method` (population as the synergist prior, its base
/// model as the thesis method's assumed model). seed: of the study or validation (the VA measurement's
/// seed derives from it and the subject). Throws what the identifier throws.
BicepsEstimate identifyElbowMethod(const ElbowMethod& method, const Population& population,
                                   const std::vector<TorqueObservation>& data, unsigned seed, int subject);

/// A validation row: the subject's truth beside the estimate.
ElbowValidationRow makeElbowValidationRow(const Population& population, const VirtualSubject& subject, double noise,
                                          const std::string& method, const BicepsEstimate& estimate);

/// Bias, RMSE and coverage of one method at one noise level.
struct ElbowValidationSummary {
    std::string method;
    double noise = 0;
    int subjects = 0, converged = 0;
    double massBias = 0, massRmse = 0;        ///< relative [1]; NaN when no subject has an estimate
    double tendonBias = 0, tendonRmse = 0;    ///< [m]
    double massCoverage = 0.0 / 0.0, tendonCoverage = 0.0 / 0.0;  ///< fraction of subjects [1]
    double massIntervalWidth = 0.0 / 0.0;     ///< mean 95 % interval width / estimate [1]
    double tendonIntervalWidth = 0.0 / 0.0;   ///< mean 95 % interval width [m]
};

/// Settings of runElbowValidation.
struct ElbowValidationSettings {
    int subjects = 200;
    unsigned seed = 1;                        ///< population and noise seed
    std::vector<double> noiseLevels;          ///< transducer noise levels; empty: the population's
    /// > 0: also run "synergist-va", the synergist-aware identifier with voluntary activation measured
    /// by twitch interpolation to this sd [1]; 0: not.
    double activationSd = 0.02;
    TorqueProtocol protocol;
    bool freeSlowFraction = false;            ///< the synergist identifiers free the slow fractions (SynergistOptions)
    int jobs = 2;                             ///< threads (over subjects)
};

/// Draws subjects 0..subjects-1, synthesizes each one's data once per noise level (common random
/// numbers across levels), identifies with both methods. progress(done, total) per subject.
std::vector<ElbowValidationRow> runElbowValidation(const Population& population, const ElbowValidationSettings& settings,
                                                   const std::function<void(int, int)>& progress = {});
std::vector<ElbowValidationSummary> summarizeElbowValidation(const std::vector<ElbowValidationRow>& rows);
/// One CSV line per row: truth, estimate, 95 % interval, coverage, nuisance truths (SI units, errors in %).
std::string formatElbowValidationCsv(const std::vector<ElbowValidationRow>& rows);
/// Per method and noise level: bias, RMSE, coverage (CSV).
std::string formatElbowValidationSummaryCsv(const std::vector<ElbowValidationSummary>& summaries);

}  // namespace armsim
