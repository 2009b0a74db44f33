// The synergist-aware identifier: a maximum a posteriori fit of the net tared joint torque predicted
// by the whole model (every muscle at its steady state), with the population as prior. Free: a log
// mass scale per biceps head and per synergist, one for the extensors, the biceps heads' tendon and
// fascicle length scales, the synergists' tendon and fascicle scales, voluntary activation VA and
// co-contraction CC (and optionally the flexors' slow-fibre fractions); the person's specific-tension
// and size scales when the prior population varies them. Data residuals are weighted by
// a relative noise level estimated from the repetitions' scatter; the posterior covariance is the
// Laplace approximation; 95 % intervals are symmetric in the log scales, so the M, L0T and F0 intervals
// are exp-transformed. Their quantile is Student-t's with nu / f^2 degrees of freedom: nu those of the
// torque noise estimate, f the share of the quantity's posterior variance owed to the torque rows
// (Satterthwaite; channels and prior have known sds, so f -> 0 gives the normal quantile). With VA
// measured by twitch interpolation it has one more residual ("synergist-va"); with the channels of
// experiments/channels.h (ultrasound fascicle length and volume, EMG, anthropometry) one residual per
// measurement, each divided by its own sd ("channels"). A two-axis transducer's forearm torque (the
// observations' forearmTorque, supination and pronation efforts included) adds one residual per
// reading, with the sd of its trial's load; the rotators (the muscles in no other group: pronators,
// supinator) then get a mass scale each.
#pragma once

#include "basics/numbers.h"

#include "experiments/channels.h"
#include "identification/torque_estimate.h"
#include "model/mvc_curve.h"

#include <array>
#include <string>
#include <utility>
#include <vector>

namespace armsim {

/// The smallest relative torque sd a fit weights its data by [1]: a few repetitions can scatter by ~0,
/// which would weight the data as exact (0.2 %: about 0.1 N m of an MVC). An estimated level is raised to
/// it and says so; a given one below it is refused.
constexpr double kMinTorqueNoiseLevel = 0.002;

/// The synergist-aware identifier's model and extra measurements.
/// InputError naming the population unless it can serve as the identifiers' prior: a spread > 0 of the
/// muscle masses (strength.subject_sd or muscle_sd) and of the tendon lengths (tendon_length.sd), the
/// quantities identified (with none the fit returns the prior's mean).
void checkIdentifiablePrior(const Population& prior);

struct SynergistOptions {
    /// Which muscles the model groups (names in the population's base model); empty: the model file's
    /// roles (ArmSetup::bicepsHeads, ArmSetup::synergists).
    std::vector<std::string> biceps;       ///< share s_b and t_b
    std::vector<std::string> synergists;   ///< share s_s
    /// false: the synergists are left out of the identifier's model (no torque from them): the
    /// ablation that shows what they are for.
    bool includeSynergists = true;
    // Every extensor shares s_e.
    /// The subject's voluntary activation measured by twitch interpolation (superimposed stimulation
    /// during the MVCs) [1]; NaN: not measured. Adds the residual (VA - measured) / activationSd.
    double measuredActivation = kNaN;
    double activationSd = 0.02;  ///< sd of that measurement [1] (an assumption, see measureVoluntaryActivation)
    /// Free the flexors' slow-fibre fractions (one shift for the biceps heads, one for the synergists;
    /// prior sd the population's): submaximal efforts depend on them.
    bool freeSlowFraction = false;
    /// Relative sd of one trial's torque [1], at least kMinTorqueNoiseLevel; NaN: estimated from the
    /// repetitions (pooled over the conditions; raised to kMinTorqueNoiseLevel), or the population's
    /// transducer noise when nothing is repeated.
    double noiseLevel = kNaN;
    /// Measurements besides torque (experiments/channels.h), each a residual (model - value) / sd.
    std::vector<ChannelObservation> channels;
    double emgCrosstalk = 0.10;  ///< c of the EMG measurement model (ChannelNoise::emgCrosstalk) [1]
    /// The data read the forearm axis (a two-axis transducer): the rotators' mass scales are free.
    /// identifySynergistAware sets it from the data; a rotation effort among the conditions implies it.
    bool readsForearmTorque = false;
};

class SynergistFit;

/// The synergist-aware identifier's model: its parameters x, their prior and bounds, and the tared
/// steady torque it predicts for a list of effort conditions (also used by experiment design).
/// x = [ln t_b, VA, CC, ln f_b, ln t_s, ln f_s, ln s_e, d_b, d_s, ln sigma, ln g, then ln s_m for every
/// biceps head, synergist and rotator m]: t tendon, f fascicle length and s mass scales; b the biceps
/// heads (one tendon and one fascicle scale), s the synergists, e the extensors (one mass scale), the
/// rotators the muscles in none of those groups (pronators, supinator: held at the prior's mean unless
/// the data read the forearm axis); d the change of
/// the slow-fibre fraction F_slow (added, biceps heads and synergists; held at 0 unless
/// freeSlowFraction); sigma the person's specific-tension scale (every muscle; F0 = sigma M / (rho L0))
/// and g the person's size (every length; moment arms and path lengths scale with it), each held at the
/// prior's mean when the prior population does not vary it. Prior: every mass scale shares the
/// person-level variance (the extensors' one scale averages their muscle terms); lengths, sigma, g and
/// effort independent, effort uniform ranges as their mean and sd.
///
/// The population draws every muscle's lengths, slow fraction and mass on its own, while x shares or
/// holds them: the 95 % intervals add what that costs (consider parameters, getConsiderParameters: the
/// estimate's error covariance C (J'J + B S B') C of the linearized fit, C its Laplace covariance, S the
/// prior population's covariance of the truths x stands for, of the held parameters and of the
/// considered ones, B their effect on the fit), so intervals keep their coverage in family.
class SynergistModel {
public:
    /// Throws InputError for muscle names not in the population's model or a primary muscle that is
    /// not in the biceps group, and for channel measurements of muscles not in the model. Conditions
    /// may repeat (each distinct angle and effort kind is computed once); their repetitions are ignored.
    /// options.channels are the measurements calcChannels predicts.
    SynergistModel(const Population& prior, const SynergistOptions& options,
                   const std::vector<TorqueCondition>& conditions);
    int getNumParameters() const { return getFirstRotatorIndex() + int(rotators_.size()); }
    std::vector<std::string> getParameterNames() const;
    int getMassIndex() const;                 ///< ln M of the primary muscle
    /// The primary's ln F0 = ln sigma + ln M - ln f_b - ln g (+ constants) as weights on the parameters.
    std::vector<double> getLnMaxForceWeights() const;
    std::vector<int> getFlexorMassIndices() const;  ///< the biceps heads' and synergists' ln mass scales
    static constexpr int getTendonIndex() { return kTendon; }          ///< ln t_b
    static constexpr int getActivationIndex() { return kActivation; }  ///< VA
    static constexpr int getFascicleIndex() { return kFascicle; }      ///< ln f_b
    static constexpr int getSpecificTensionIndex() { return kSigma; }  ///< ln sigma
    static constexpr int getSizeIndex() { return kSize; }              ///< ln g
    /// The first rotator's ln mass scale (the rotators follow in model order).
    int getFirstRotatorIndex() const { return kFirstMass + int(biceps_.size() + synergists_.size()); }
    /// ln s of muscle i (a biceps head, a synergist or a rotator), -1 for an extensor.
    int findMassIndex(int muscle) const;
    const std::vector<double>& getPriorMean() const { return priorMean_; }
    const std::vector<std::vector<double>>& getPriorCovariance() const { return priorCovariance_; }
    const std::vector<double>& getLower() const { return lower_; }
    const std::vector<double>& getUpper() const { return upper_; }
    /// Tared torque of every condition at x [N m]; throws SimulationError where a muscle has no steady state.
    std::vector<double> calcTorques(const double* x) const;
    /// Tared torques and every channel measurement's predicted value (options.channels' order) at x.
    void calcPredictions(const double* x, std::vector<double>& torques, std::vector<double>& channels) const;
    /// The same and every condition's tared torque about the forearm axis (+ = supination) [N m].
    void calcPredictions(const double* x, std::vector<double>& torques, std::vector<double>& forearmTorques,
                         std::vector<double>& channels) const;
    /// A muscle's own departure from what x gives it (the fit's group scales, or the prior's mean where
    /// x has no scale for it): ln tendon and ln fascicle scale, slow-fraction shift, ln mass scale.
    struct MuscleDeviation {
        double lnTendon = 0, lnFascicle = 0, slowShift = 0, lnMass = 0;
    };
    /// Scratch of calcPredictions for the many calls of a fit or a Jacobian, one per thread: the steady
    /// states of the last call, reused where a muscle's inputs are unchanged (SteadyCurveCache; the
    /// predictions are bit-identical to calls without it).
    struct PredictionCache {
        SteadyCurveCache relaxed;
        std::vector<SteadyCurveCache> active;   ///< per effort kind
    };
    /// The same predictions with muscle i departing by (*deviations)[i] (nullptr: none), with an
    /// optional cache.
    void calcPredictions(const double* x, const std::vector<MuscleDeviation>* deviations, std::vector<double>& torques,
                         std::vector<double>& forearmTorques, std::vector<double>& channels,
                         PredictionCache* cache = nullptr) const;
    /// The predictions (as calcPredictions without deviations) and their derivatives by x, row-major with
    /// getNumParameters() columns (dTorques[c * n + j] = d torques[c] / d x_j): through every muscle's
    /// steady state by the implicit function theorem (MuscleModel::calcSteadySensitivity) and the chain
    /// rule through x's scales. Columns that move the slow-fibre fractions (when free), and every column
    /// when a muscle's model has no steady sensitivity, by central differences with Ceres's steps.
    void calcPredictionJacobian(const double* x, std::vector<double>& torques, std::vector<double>& forearmTorques,
                                std::vector<double>& channels, std::vector<double>& dTorques,
                                std::vector<double>& dForearmTorques, std::vector<double>& dChannels,
                                PredictionCache* cache = nullptr) const;
    /// What calcPredictionJacobian's chain rule reads: d ln(input) / d x_j of one muscle's steady
    /// inputs (SteadySensitivity's first four, then mass, specific tension and moment arm), [j][input].
    struct Input {
        enum { kLnP = 0, kLnL0, kLnL0T, kLnPmax, kLnMass, kLnTension, kLnArm, kNumInputs };
    };
    using InputDerivatives = std::vector<std::array<double, Input::kNumInputs>>;
    /// The population's model with x's muscles (and each muscle's deviation, when given).
    std::vector<MuscleSpec> makeMuscles(const double* x, const std::vector<MuscleDeviation>* deviations = nullptr) const;

    /// What the prior population varies per person, as independent centred "primitives": for muscle i,
    /// index 4 i + 0..3 its ln tendon scale, ln fascicle scale, slow-fraction shift and ln mass scale;
    /// then ln sigma, ln size, voluntary activation and co-contraction (getNumPrimitives() in all).
    int getNumPrimitives() const { return 4 * int(base_->muscles.size()) + 4; }
    /// Their covariance: the population's sds (uniform ranges as their variance); the masses share the
    /// person-level strength.
    std::vector<std::vector<double>> calcPrimitiveCovariance() const;
    /// The truth each parameter stands for, as (primitive, coefficient) terms: a group's shared scale
    /// stands for its first muscle's (the primary's for the biceps heads).
    std::vector<std::vector<std::pair<int, double>>> getParameterTruths() const;
    /// What the fit's model simplifies away and the prior varies (the consider parameters of the
    /// intervals): each muscle's own tendon, fascicle and slow fraction where its group shares one scale
    /// (the departure from the group's first muscle) or where x has none, and the extensor heads' and
    /// ungrouped muscles' own masses.
    struct ConsiderParameter {
        int muscle = 0;
        int kind = 0;                                  ///< 0 tendon, 1 fascicle, 2 slow fraction, 3 mass
        std::vector<std::pair<int, double>> truth;     ///< (primitive, coefficient)
    };
    std::vector<ConsiderParameter> getConsiderParameters() const;
    /// Sets c's entry of deviations (sized one per muscle) to `by`.
    static void setDeviation(std::vector<MuscleDeviation>& deviations, const ConsiderParameter& c, double by);
    /// The Jacobian steps of the intervals' secants, over the n parameters then getConsiderParameters():
    /// half the prior's sd for a held parameter and half the population's sd for a consider parameter
    /// (muscle forces step with motor-unit recruitment: a tangent there can be any size); 0 for a free
    /// parameter (its column is a tangent) and for what the prior does not vary.
    std::vector<double> getSecantSteps() const;
    /// The estimate's error covariance with the consider parameters (the class comment): J the whitened
    /// residuals' Jacobian, rows over the n parameters then getConsiderParameters(). Writes C0 (the
    /// Laplace covariance of the free parameters) and C, both n x n with zero rows for held parameters;
    /// false, leaving them, when a matrix is not positive definite.
    bool calcConsideredCovariance(const std::vector<std::vector<double>>& J, std::vector<std::vector<double>>& C0,
                                  std::vector<std::vector<double>>& C) const;
    /// The prior's check (channel "prior"): is this person one the prior's population could hold? With
    /// J as above and x the estimate, the estimate's deviation d = x - mu over the free log-scale
    /// parameters (activation and co-contraction, and parameters at a bound, left out) has, under the
    /// linearized fit and the prior's population (what the fit shares included), the covariance
    /// D = C0 J_F' (G S G' + I) J_F C0 (G: the Jacobian over the truths' parameters, S their covariance).
    /// In the directions v where the data explain at least kPriorCheckShare of the prior's variance
    /// (D v = lambda S_F v), sum (v'd)^2 / lambda is chi-square with that many degrees of freedom; `worst`
    /// names the parameter furthest from the prior mean in its own sd of D. n = 0 when no direction
    /// qualifies or a matrix is not positive definite.
    ChannelFit calcPriorCheck(const std::vector<std::vector<double>>& J, const std::vector<double>& x) const;
    static constexpr double kPriorCheckShare = 0.2;

private:
    static constexpr int kTendon = 0, kActivation = 1, kCoContraction = 2, kFascicle = 3, kSynergistTendon = 4,
                         kSynergistFascicle = 5, kExtensorMass = 6, kBicepsSlow = 7, kSynergistSlow = 8,
                         kSigma = 9, kSize = 10, kFirstMass = 11;
    struct EffortKind {
        Effort effort;
        double level;
    };
    const ArmSetup* base_;
    const Population* prior_;
    std::vector<int> biceps_, synergists_, extensors_, rotators_, leftOut_;
    MvcGeometry geometry_;                    // one row per pose (flexion angle, forearm posture)
    std::vector<EffortKind> kinds_;
    std::vector<std::vector<std::vector<bool>>> agonists_;  // [kind][pose][muscle], of the prior's geometry
    std::vector<int> angleOf_, kindOf_;       // condition -> pose index, effort kind
    std::vector<ChannelObservation> channels_;
    std::vector<int> channelMuscle_, channelAngle_, channelKind_;  // kind -1: relaxed
    double emgCrosstalk_ = 0;
    int findKind(Effort effort, double level);
    /// x's muscles and every steady curve the predictions read (the relaxed one and one per effort kind).
    struct Evaluation;
    Evaluation evaluate(const double* x, const std::vector<MuscleDeviation>* deviations, PredictionCache* cache,
                        bool sensitivities) const;
    void readPredictions(const Evaluation& e, std::vector<double>& torques, std::vector<double>& forearmTorques,
                         std::vector<double>& channels) const;
    std::vector<InputDerivatives> calcInputDerivatives() const;   // [muscle]
    void addTorqueDerivatives(const Evaluation& e, const std::vector<InputDerivatives>& d, const double* x,
                              std::vector<double>& dTorques, std::vector<double>& dForearmTorques) const;
    void calcChannelDerivatives(const Evaluation& e, const std::vector<InputDerivatives>& d, const double* x,
                                const std::vector<double>& channels, std::vector<double>& dChannels) const;
    /// Frees the rotators' scales within the mass scales' bounds (the data read the forearm axis).
    void freeRotatorMass();
    /// Index of the pose (flexion, forearm rotation; NaN = the model's posture, kept as +inf), added if new.
    int findPose(double flexionDeg, std::vector<std::pair<double, double>>& poses, double rotationDeg = kNaN);
    std::vector<double> priorMean_, lower_, upper_;
    std::vector<std::vector<double>> priorCovariance_;
    // What calcConsideredCovariance needs of the model alone, computed once at construction
    // (prepareConsidered): the free and held parameters, the prior's precision on the free ones and the
    // covariance S of the truths (free, held, considered). Both empty when the prior covariance is not
    // positive definite.
    std::vector<int> free_, held_;
    std::vector<std::vector<double>> freePrecision_, truthCovariance_;
    void prepareConsidered();
    void setGeometry(const std::vector<std::pair<double, double>>& poses);
    void setPrior(const Population& prior, const SynergistOptions& options, const std::vector<TorqueCondition>& conditions);
    std::vector<std::vector<double>> coupledCovariance_;  // with the rotators coupled (freeRotatorMass)
    friend class SynergistFit;   // identifySynergistAware's steps
};

/// The synergist-aware MAP identifier with the population as prior.
MuscleEstimate identifySynergistAware(const Population& prior, const std::vector<TorqueObservation>& data,
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

}  // namespace armsim
