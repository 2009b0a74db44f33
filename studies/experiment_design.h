// Bayesian experiment design for the synergist-aware identifier (`armsim design`).
//
// A protocol's expected posterior uncertainty is computed with the Laplace approximation the identifier
// itself reports: for a parameter vector x, the posterior covariance is
//     C(x) = (Sigma^{-1} + sum_i n_i J_i(x)^T J_i(x) / s_i(x)^2 [+ e_VA e_VA^T / sd_VA^2])^{-1},
// with Sigma the identifier's prior covariance (identification/synergist_identifier.h, SynergistModel),
// J_i the gradient of condition i's tared torque T_i (central differences), n_i its repetitions and
// s_i = sigma |T_i| its sd (sigma^2 = transducer noise^2 + trial cv^2: each trial's torque varies with
// the effort and the sensor), and the last term when voluntary activation is measured by twitch
// interpolation. The expectation is over `draws` parameter vectors drawn from the identifier's prior
// (Gaussian, clipped to its bounds, seeded).
//
// Criterion (minimised): mean over draws of var(ln M) / g_M^2 + var(ln L0T) / g_T^2 with the design's
// goals g_M = 10 % (mass RMSE) and g_T = 1 cm / L0T (tendon RMSE): each width counts relative to its goal.
// The variances are the identifier's error covariance with the consider parameters (what its fit shares
// or holds and the population varies: SynergistModel::calcConsideredCovariance) unless
// DesignSettings::ownModelCriterion asks for the Laplace covariance above.
// Design: greedy, a block of `repetitions` trials of the candidate condition that lowers the criterion
// most, until the trial budget is spent or no block lowers it (information adds over trials, so this is the usual greedy
// approximation to the optimal exact design); a condition picked twice gets twice the repetitions.
#pragma once

#include "basics/numbers.h"

#include "identification/torque_identification.h"
#include "studies/torque_validation.h"

#include <functional>
#include <string>
#include <vector>

namespace armsim {

/// Lab minutes of what a design across channels may pick (docs/channels.md, Lab time: assumptions,
/// no published protocol states minutes).
struct LabCosts {
    double mvcBlock = 8;          ///< one condition's 3 efforts with 2 min rests (scaled by repetitions / 3) [min]
    double emgSetup = 20;         ///< electrodes and MVC normalisation, once [min]
    double ultrasoundAngle = 7;   ///< fascicle images at rest and at the plateau during one condition's trials [min]
    double volumeScan = 10;       ///< one muscle's panoramic scan [min]
    double anthropometry = 10;    ///< [min]
    /// Lab minutes of a protocol: MVC blocks, ultrasound per condition, EMG set-up, volume scans and
    /// anthropometry (twitch interpolation, about 25 min, not counted: every design has it or not).
    double calcMinutes(const TorqueProtocol& protocol) const;
};

/// The trials of a design not given any: the most whole blocks of `repetitions` within the thesis's 15
/// (15 for 3 or 5, 14 for 2), one block when a block is larger.
inline int getDefaultDesignTrials(int repetitions) {
    return repetitions >= 1 && repetitions <= 15 ? 15 / repetitions * repetitions : repetitions;
}

/// What an experimenter may do.
struct DesignSettings {
    std::vector<double> flexionDeg = {15, 30, 45, 60, 75, 90, 105, 120, 135};  ///< allowed angles [deg]
    bool extension = true;               ///< extension MVCs allowed
    /// Submaximal levels allowed (EMG feedback: the agonists' EMG held at that fraction of its MVC
    /// value; needs surface EMG), fractions in (0, 1); empty: maximal efforts only.
    std::vector<double> levels;
    /// Forearm postures allowed besides the model's [deg], + = supination (a model with a forearm
    /// rotation): flexion and extension MVCs at every angle in each, and supination and pronation MVCs at
    /// every angle in each and in the model's posture; every trial then reads both transducer axes
    /// (the design's protocol says forearm_torque). Empty: the model's posture and flexion axis only.
    std::vector<double> postures;
    /// What the greedy design minimises: the widths with the consider parameters (what the identifier's
    /// intervals report; default), or the Laplace widths of the fit's own model (the design before
    /// 2026-11-26: it buys information that the population's per-muscle variation takes back, e.g.
    /// flexion MVCs in other forearm postures).
    bool ownModelCriterion = false;
    int trials = 15;                     ///< budget: total trials, whole blocks of repetitions (thesis: 5 angles x 3)
    int repetitions = 3;                 ///< trials per pick (>= 2: the identifier estimates its noise from repeats)
    int draws = 32;                      ///< prior draws the criterion averages over
    unsigned seed = 1;
    double activationSd = 0.02;          ///< > 0: VA measured by twitch interpolation to this sd; 0: not
    bool freeSlowFraction = false;       ///< the identifier frees the slow fractions (SynergistOptions)
    int jobs = 2;                        ///< threads (over draws)
    /// > 0: design across channels within this many lab minutes (designChannelProtocol) [min].
    double budgetMinutes = 0;
    LabCosts costs;
    /// FieldError naming the field for values out of range.
    void validate() const;
};

/// A protocol's predicted uncertainty (averages over the prior draws).
struct ProtocolPrediction {
    std::string name;
    int trials = 0;
    int drawsUsed = 0;                   ///< prior draws with a steady state at every condition
    double criterion = kNaN;        ///< as minimised (1 = both widths at their goals) [1]
    double massSd = kNaN;           ///< RMS over draws of the posterior sd of ln M [1] (~ relative sd of M)
    double tendonSd = kNaN;         ///< RMS over draws of the posterior sd of L0T [m]
    /// RMS posterior sd of the mean of the flexors' ln mass scales (total flexor strength) [1]: small
    /// when the data pin the flexors' sum while massSd stays near the per-muscle prior sd (the split).
    double flexorStrengthSd = kNaN;
    double priorFlexorStrengthSd = kNaN;  ///< its prior sd [1]
    double priorMassSd = kNaN;      ///< the prior's sd of ln M [1]
    double priorTendonSd = kNaN;    ///< the prior's sd of L0T [m]
    /// massSd and tendonSd with what the fit shares or holds and the truth varies (the identifier's
    /// consider parameters, SynergistModel::calcConsideredCovariance): the widths its intervals report
    /// [1], [m]. NaN where not computed (the greedy search's trial designs).
    double massSdConsidered = kNaN;
    double tendonSdConsidered = kNaN;
    /// RMS over draws of the posterior sd of the primary's ln F0 (= ln sigma + ln M - ln L0 + const) [1],
    /// its prior sd, and the same with the consider parameters (NaN where not computed).
    double maxForceSd = kNaN;
    double priorMaxForceSd = kNaN;
    double maxForceSdConsidered = kNaN;
    std::vector<std::string> parameterNames;
    /// Mean over draws of the posterior correlation of ln M with each parameter.
    std::vector<double> massCorrelation;
    /// Mean over draws of the posterior sd of each parameter (its own units: ln scale or activation).
    std::vector<double> posteriorSd;
};

/// One greedy pick.
struct DesignStep {
    TorqueCondition condition;           ///< with repetitions = the block (0 for an item of no condition)
    double criterion = 0;                ///< after the pick
    std::string item = "torque";         ///< torque, ultrasound, emg, volume MUSCLE, anthropometry
    double minutes = kNaN;          ///< its lab minutes (designs across channels)
};

struct DesignResult {
    TorqueProtocol protocol;             ///< the design (name "designed")
    ProtocolPrediction predicted;        ///< its prediction
    ProtocolPrediction reference;        ///< the reference protocol's, on the same prior draws
    std::vector<DesignStep> steps;
    std::vector<TorqueCondition> candidates;  ///< every condition considered
};

/// design_steps.csv: step, effort, flexion_deg, level, repetitions, criterion after the pick, item, minutes,
/// rotation_deg (empty: the model's posture).
std::string formatDesignStepsCsv(const DesignResult& result);

/// `draws` parameter vectors of the identifier's prior (Gaussian, clipped to its bounds), seeded by
/// (seed, draw): the draws the predictions average over. A draw whose person has no steady state in some
/// condition of the model is drawn again (seeded by the attempt too); SimulationError after 101 tries.
std::vector<std::vector<double>> drawFromPrior(const SynergistModel& model, unsigned seed, int draws);

/// Predicted uncertainty of the synergist-aware identifier with this protocol (with its channels when it
/// records any: the channels fit).
ProtocolPrediction predictProtocol(const Population& prior, const TorqueProtocol& protocol,
                                   const DesignSettings& settings);

/// The greedy design within the settings' budget and options, and the reference protocol's
/// prediction on the same draws (a draw without a steady state at some condition of either is left out
/// of both). progress(done, total) over the sensitivities (the expensive part) and the picks.
DesignResult designProtocol(const Population& prior, const DesignSettings& settings, const TorqueProtocol& reference,
                            const std::function<void(int, int)>& progress = {});

/// The design across channels: greedy by criterion drop per lab minute over MVC blocks at the candidate
/// angles and levels, ultrasound at a picked condition, EMG (once: every block), a volume scan of each
/// superficial flexor (surface_emg role) and anthropometry, until nothing fits settings.budgetMinutes.
/// Channel errors are the reference protocol's channelNoise. Predicted widths include every channel
/// (Laplace approximation as the identifier's). Throws InputError when no MVC block fits the budget.
DesignResult designChannelProtocol(const Population& prior, const DesignSettings& settings,
                                   const TorqueProtocol& reference, const std::function<void(int, int)>& progress = {});

/// One row of a design's validation: a protocol, an identifier run on it, what it obtained on virtual
/// subjects and what the design predicted for it.
struct DesignValidationRow {
    std::string protocol;                ///< the reference's name, or "designed"
    ElbowValidationSummary obtained;     ///< bias, RMSE, coverage and widths over the subjects
    ProtocolPrediction predicted;        ///< the prediction this method is compared with
};

/// The reference protocol and the design validated on `subjects` virtual subjects of the prior (seeded;
/// settings' jobs, activation sd and slow-fraction option): the identifiers the prediction is about
/// (not the thesis method), each beside its prediction. The design's prediction is its channels fit's
/// when it was designed across channels (budgetMinutes > 0): other fits of the design are left out; the
/// torque-only fits compare with the reference's. progress(protocol name, done, total).
std::vector<DesignValidationRow> validateDesign(
    const Population& prior, const DesignSettings& settings, const TorqueProtocol& reference, const DesignResult& design,
    int subjects, const std::function<void(const std::string&, int, int)>& progress = {});

/// design_validation.csv: protocol, method, subjects, converged, mass_bias_pct, mass_rmse_pct,
/// mass_coverage, mass_interval_width_pct, tendon_bias_mm, tendon_rmse_mm, tendon_coverage,
/// tendon_interval_width_mm, predicted_mass_sd_pct, predicted_tendon_sd_mm.
std::string formatDesignValidationCsv(const std::vector<DesignValidationRow>& rows);

/// CSV: one row per protocol: name, trials, criterion, mass_sd_pct, tendon_sd_mm, prior sds, the same
/// widths with the consider parameters, and the mean posterior correlation of ln M with every parameter.
std::string formatPredictionsCsv(const std::vector<ProtocolPrediction>& predictions);

}  // namespace armsim
