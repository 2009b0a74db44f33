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
};

/// The synergist-aware MAP identifier with the population as prior.
BicepsEstimate identifySynergistAware(const Population& prior, const std::vector<TorqueObservation>& data,
                                      const SynergistOptions& options = {});

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

/// Bias, RMSE and coverage of one method at one noise level.
struct ElbowValidationSummary {
    std::string method;
    double noise = 0;
    int subjects = 0, converged = 0;
    double massBias = 0, massRmse = 0;        ///< relative [1]
    double tendonBias = 0, tendonRmse = 0;    ///< [m]
    double massCoverage = 0.0 / 0.0, tendonCoverage = 0.0 / 0.0;  ///< fraction of subjects [1]
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
