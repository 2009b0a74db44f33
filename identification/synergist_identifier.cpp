#include "identification/synergist_identifier.h"

#include "basics/bound.h"
#include "basics/format.h"
#include "basics/portable_random.h"
#include "estimation/map_estimate.h"
#include "estimation/statistics.h"
#include "model/geometry.h"
#include "model/trial.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <array>
#include <limits>
#include <tuple>

namespace armsim {

namespace {

// Tared steady torque at angle a: the active curve less the relaxed one, summed over the muscles not
// left out; about the elbow (axis = &SteadyMusclePoint::torque) or the forearm axis (::forearmTorque).
double sumTaredTorque(const SteadyMvcCurve& active, const SteadyMvcCurve& relaxed, std::size_t a,
                      const std::vector<int>& leftOut = {}, double SteadyMusclePoint::*axis = &SteadyMusclePoint::torque) {
    double t = 0;
    for (std::size_t i = 0; i < active.points[a].size(); ++i)
        if (std::find(leftOut.begin(), leftOut.end(), int(i)) == leftOut.end())
            t += active.points[a][i].*axis - relaxed.points[a][i].*axis;
    return t;
}

// Every muscle at rest (U = 0), with an optional cache (SteadyCurveCache) and sensitivities.
SteadyMvcCurve calcRelaxedCurve(const std::vector<MuscleSpec>& muscles, const MvcGeometry& g,
                                SteadyCurveCache* cache = nullptr, bool sensitivities = false) {
    const std::vector<std::vector<bool>> any(g.flexionDeg.size(), std::vector<bool>(muscles.size(), true));
    return calcSteadyMvcCurve(muscles, g, Effort::Flexion, any, SubjectEffort{0, 0}, cache, sensitivities);
}

// The effort of a condition at level l: agonists l VA, antagonists l CC.
SubjectEffort makeEffort(double level, double voluntaryActivation, double coContraction) {
    SubjectEffort e;
    e.voluntaryActivation = level * voluntaryActivation;
    e.coContraction = level * coContraction;
    return e;
}

std::vector<int> findMuscles(const ArmSetup& setup, const std::vector<std::string>& names, const char* what) {
    std::vector<int> out;
    for (const std::string& n : names) {
        try {
            out.push_back(setup.findMuscle(n));
        } catch (const InputError& e) {
            throw InputError(std::string("synergist-aware identifier: ") + what + ": " + e.what());
        }
    }
    return out;
}

// Relative torque sd pooled over the conditions' repetitions (NaN without repetitions) and its degrees
// of freedom: each axis's scatter about its mean, relative to the mean load (TorqueObservation::getLoad).
std::pair<double, int> estimateNoiseLevel(const std::vector<TorqueObservation>& data) {
    std::map<ConditionKey, std::vector<const TorqueObservation*>> byCondition;
    for (const TorqueObservation& o : data) byCondition[getConditionKey(o)].push_back(&o);
    double ss = 0;
    int dof = 0;
    for (const auto& [condition, v] : byCondition) {
        if (v.size() < 2) continue;
        const bool forearm = std::all_of(v.begin(), v.end(), [](const TorqueObservation* o) { return std::isfinite(o->forearmTorque); });
        double t = 0, f = 0, load = 0;
        for (const TorqueObservation* o : v) {
            t += o->torque;
            f += forearm ? o->forearmTorque : 0.0;
            load += o->getLoad();
        }
        const double n = double(v.size());
        t /= n, f /= n, load /= n;
        if (!(load > 0)) continue;
        for (const TorqueObservation* o : v) {
            ss += std::pow((o->torque - t) / load, 2);
            if (forearm) ss += std::pow((o->forearmTorque - f) / load, 2);
        }
        dof += (forearm ? 2 : 1) * (int(v.size()) - 1);
    }
    return {dof > 0 ? std::sqrt(ss / dof) : NAN, dof};
}

// A muscle's surface EMG is a channel only where the model says electrodes reach it (roles.surface_emg):
// a deep muscle's "EMG" is its neighbours' crosstalk, which the EMG model does not describe.
void checkSurfaceEmgMuscle(const ArmSetup& base, int m, const std::string& at) {
    if (std::find(base.surfaceEmg.begin(), base.surfaceEmg.end(), m) != base.surfaceEmg.end()) return;
    std::string reached;
    for (int k : base.surfaceEmg) reached += (reached.empty() ? "" : ", ") + base.muscles[k].params.name;
    throw InputError(at + "emg of muscle '" + base.muscles[m].params.name + "': model '" + base.name + "' " +
                     (reached.empty() ? "names no muscle surface electrodes reach (roles.surface_emg)"
                                      : "has surface EMG of " + reached + " only (roles.surface_emg)") +
                     ": expected EMG of one of those");
}

// An effort's EMG or fascicle length is recorded during a torque trial: a row at an angle, effort and
// level no trial of the torque data has is another session's (or a unit slip) and would be fitted to an
// activation the torque never constrains.
void checkRecordedInATrial(const ChannelObservation& o, const std::vector<TorqueCondition>& conditions,
                           const std::string& at) {
    std::set<double> angles;   // the torque data's angles at this effort and level
    for (const TorqueCondition& c : conditions)
        if (c.effort == o.effort && c.level == o.level) {
            if (std::abs(c.flexionDeg - o.flexionDeg) <= 1e-9) return;
            angles.insert(c.flexionDeg);
        }
    std::string list;
    for (double a : angles) list += (list.empty() ? "" : ", ") + formatNumber(a);
    throw InputError(at + o.channel + " at " + formatNumber(o.flexionDeg) + " deg, " + getEffortName(o.effort) +
                     " effort, level " + formatNumber(o.level) + ": the torque data has no such trial (" +
                     (list.empty() ? "no " + std::string(getEffortName(o.effort)) + " trial at level " + formatNumber(o.level)
                                   : "its trials of that effort and level are at " + list + " deg") +
                     "): expected each channel row of an effort to come from a torque trial");
}

}  // namespace

std::vector<double> calcTaredSteadyTorque(const ArmSetup& setup, const SubjectEffort& effort,
                                          const std::vector<double>& flexionDeg, MuscleGroup group) {
    const MvcGeometry g = calcMvcGeometry(setup, flexionDeg);
    const SteadyMvcCurve active = calcSteadyMvcCurve(setup.muscles, g, group, effort);
    const SteadyMvcCurve relaxed = calcRelaxedCurve(setup.muscles, g);
    std::vector<double> torque;
    for (std::size_t a = 0; a < flexionDeg.size(); ++a) torque.push_back(sumTaredTorque(active, relaxed, a));
    return torque;
}

SynergistModel::SynergistModel(const Population& prior, const SynergistOptions& options,
                               const std::vector<TorqueCondition>& conditions)
    : base_(&prior.base), prior_(&prior) {
    const ArmSetup& base = prior.base;
    biceps_ = options.biceps.empty() ? base.getBicepsHeads() : findMuscles(base, options.biceps, "biceps");
    synergists_ = options.synergists.empty() ? base.synergists : findMuscles(base, options.synergists, "synergists");
    if (!options.includeSynergists) leftOut_ = synergists_;
    for (int i = 0; i < base.getNumMuscles(); ++i) {
        const bool named = std::find(biceps_.begin(), biceps_.end(), i) != biceps_.end() ||
                           std::find(synergists_.begin(), synergists_.end(), i) != synergists_.end();
        if (base.muscles[i].group == MuscleGroup::Extensor) extensors_.push_back(i);
        else if (!named) rotators_.push_back(i);
    }
    if (std::find(biceps_.begin(), biceps_.end(), base.primary) == biceps_.end())
        throw InputError("synergist-aware identifier: the primary muscle '" + base.muscles[base.primary].params.name +
                         "' is not in the biceps group");
    std::vector<std::pair<double, double>> poses;   // (flexion, rotation; the model's posture as +inf)
    for (const TorqueCondition& c : conditions) {
        if (!std::isnan(c.rotationDeg) && !base.arm.forearmRotation.enabled)
            throw InputError("synergist-aware identifier: a condition at forearm rotation " + formatNumber(c.rotationDeg) +
                             " deg, but the prior's model '" + base.name + "' has no forearm rotation");
        angleOf_.push_back(findPose(c.flexionDeg, poses, c.rotationDeg));
        if (isForearmEffort(c.effort) && !base.arm.forearmRotation.enabled)
            throw InputError(std::string("synergist-aware identifier: a ") + getEffortName(c.effort) +
                             " effort, but the prior's model '" + base.name + "' has no forearm rotation");
        kindOf_.push_back(findKind(c.effort, c.level));
    }
    channels_ = options.channels;
    emgCrosstalk_ = options.emgCrosstalk;
    checkField("emg crosstalk", emgCrosstalk_, Bound::closed(0, 0.5));
    for (const ChannelObservation& o : channels_) {
        const std::string at = o.line > 0 ? (o.source.empty() ? "channel data" : o.source) + ":" + std::to_string(o.line) + ": "
                                          : "channel data: ";
        int m = -1, angle = -1, kind = -1;
        if (o.channel != "upper_arm_length") {
            try {
                m = base.findMuscle(o.muscle);
            } catch (const InputError& e) {
                throw InputError(at + o.channel + " of muscle '" + o.muscle + "': " + e.what());
            }
        }
        if (o.channel == "fascicle_length" || o.channel == "emg") {
            const double lo = base.arm.getMinFlexionDeg(), hi = base.arm.getMaxFlexionDeg();
            if (!(o.flexionDeg >= lo - 1e-9 && o.flexionDeg <= hi + 1e-9))
                throw InputError(at + o.channel + " at flexion_deg " + formatNumber(o.flexionDeg) +
                                 ": expected an angle in the elbow's range [" + formatNumber(lo) + ", " +
                                 formatNumber(hi) + "] deg of model '" + base.name + "'");
            angle = findPose(o.flexionDeg, poses);
            if (o.channel == "fascicle_length" && o.level > 0) kind = findKind(o.effort, o.level);
        }
        if (o.channel == "emg" && base.muscles[m].group != MuscleGroup::Flexor && base.muscles[m].group != MuscleGroup::Extensor)
            throw InputError(at + "emg of muscle '" + o.muscle + "': expected a flexor or an extensor (its MVC normalises it)");
        if (o.channel == "emg") checkSurfaceEmgMuscle(base, m, at);
        if ((o.channel == "emg" || o.channel == "fascicle_length") && o.level > 0) checkRecordedInATrial(o, conditions, at);
        channelMuscle_.push_back(m);
        channelAngle_.push_back(angle);
        channelKind_.push_back(kind);
    }
    setGeometry(poses);
    setPrior(prior, options, conditions);
    prepareConsidered();
}

// The geometry of every pose, one calcMvcGeometry per posture, rows in pose order, and each effort
// kind's agonists in it.
void SynergistModel::setGeometry(const std::vector<std::pair<double, double>>& poses) {
    const ArmSetup& base = *base_;
    std::map<double, std::vector<int>> byRotation;
    for (std::size_t k = 0; k < poses.size(); ++k) byRotation[poses[k].second].push_back(int(k));
    geometry_.flexionDeg.assign(poses.size(), 0);
    geometry_.pathLength.assign(poses.size(), {});
    geometry_.momentArm.assign(poses.size(), {});
    geometry_.forearmMomentArm.assign(poses.size(), {});
    for (const auto& [rotation, rows] : byRotation) {
        std::vector<double> flexion;
        for (int k : rows) flexion.push_back(poses[k].first);
        const MvcGeometry g = calcMvcGeometry(base, flexion, std::isinf(rotation) ? NAN : rotation);
        for (std::size_t j = 0; j < rows.size(); ++j) {
            geometry_.flexionDeg[rows[j]] = g.flexionDeg[j];
            geometry_.pathLength[rows[j]] = g.pathLength[j];
            geometry_.momentArm[rows[j]] = g.momentArm[j];
            geometry_.forearmMomentArm[rows[j]] = g.forearmMomentArm[j];
        }
    }
    // Each kind's agonists from the prior's geometry: a rotation effort's set stays put when the size
    // scale moves a moment arm across kForearmAgonistMomentArm (the residuals stay smooth in x).
    for (const EffortKind& k : kinds_) agonists_.push_back(findAgonists(base.muscles, geometry_, k.effort));

}

void checkIdentifiablePrior(const Population& prior) {
    const std::string where = "prior population '" + prior.name + "'" + (prior.file.empty() ? "" : " (" + prior.file + ")");
    if (prior.strengthSubjectSd == 0 && prior.strengthMuscleSd == 0)
        throw InputError(where + ": strength.subject_sd and strength.muscle_sd are both 0: the muscle masses would be known "
                         "before any data: expected a spread > 0 to identify them");
    if (prior.tendonLengthSd == 0)
        throw InputError(where + ": tendon_length.sd = 0: the tendon lengths would be known before any data: expected a "
                         "spread > 0 to identify them");
}

// The prior's mean and covariance of x and its bounds (SynergistModel's class comment).
void SynergistModel::setPrior(const Population& prior, const SynergistOptions& options,
                              const std::vector<TorqueCondition>& conditions) {
    const int n = getNumParameters();
    const double s2 = prior.strengthSubjectSd * prior.strengthSubjectSd;
    const double m2 = prior.strengthMuscleSd * prior.strengthMuscleSd;
    checkIdentifiablePrior(prior);
    auto uniformSd = [](const UniformRange& r) { return std::max((r.max - r.min) / std::sqrt(12.0), 1e-4); };
    priorCovariance_.assign(n, std::vector<double>(n, 0.0));
    auto& cov = priorCovariance_;
    std::vector<int> masses = {kExtensorMass};
    for (int a = kFirstMass; a < n; ++a) masses.push_back(a);
    for (int a : masses)
        for (int b : masses) cov[a][b] = s2;
    cov[kBicepsSlow][kBicepsSlow] = cov[kSynergistSlow][kSynergistSlow] = std::pow(prior.slowFractionSd, 2);
    cov[kSigma][kSigma] = std::pow(prior.specificTensionSd, 2);
    cov[kSize][kSize] = std::pow(prior.geometryScaleSd, 2);
    cov[kExtensorMass][kExtensorMass] += m2 / double(std::max<std::size_t>(extensors_.size(), 1));
    for (int a = kFirstMass; a < n; ++a) cov[a][a] += m2;
    cov[kTendon][kTendon] = cov[kSynergistTendon][kSynergistTendon] = std::pow(prior.tendonLengthSd, 2);
    cov[kFascicle][kFascicle] = cov[kSynergistFascicle][kSynergistFascicle] = std::pow(prior.fascicleLengthSd, 2);
    cov[kActivation][kActivation] = std::pow(uniformSd(prior.voluntaryActivation), 2);
    cov[kCoContraction][kCoContraction] = std::pow(uniformSd(prior.coContraction), 2);
    for (int j = 0; j < n; ++j) cov[j][j] = std::max(cov[j][j], 1e-10);  // a zero spread: the value is known
    priorMean_.assign(n, 0.0);
    for (int a : masses) priorMean_[a] = std::log(prior.strengthMeanScale);
    priorMean_[kBicepsSlow] = priorMean_[kSynergistSlow] = prior.slowFractionMeanShift;
    priorMean_[kSigma] = std::log(prior.specificTensionMeanScale);
    priorMean_[kSize] = std::log(prior.geometryMeanScale);
    priorMean_[kActivation] = 0.5 * (prior.voluntaryActivation.min + prior.voluntaryActivation.max);
    priorMean_[kCoContraction] = 0.5 * (prior.coContraction.min + prior.coContraction.max);
    const double lnLo = std::log(0.25), lnHi = std::log(4.0), lenLo = std::log(0.6), lenHi = std::log(1.4);
    lower_.assign(n, lnLo);
    upper_.assign(n, lnHi);
    for (int j : {kTendon, kFascicle, kSynergistTendon, kSynergistFascicle}) {
        lower_[j] = lenLo;
        upper_[j] = lenHi;
    }
    // Activations stay 1e-5 inside [0, 1], so the Jacobian's difference probes (relative step 1e-6) do
    // not cross the model's domain; a range of zero width holds the value fixed.
    auto inside = [](double v) { return std::clamp(v, 1e-5, 1 - 1e-5); };
    for (int j : {kBicepsSlow, kSynergistSlow}) {
        lower_[j] = options.freeSlowFraction ? prior.slowFractionMeanShift - 0.3 : prior.slowFractionMeanShift;
        upper_[j] = options.freeSlowFraction ? prior.slowFractionMeanShift + 0.3 : prior.slowFractionMeanShift;
    }
    // Person-level scales the prior does not vary are known: held at their mean.
    if (prior.specificTensionSd == 0) lower_[kSigma] = upper_[kSigma] = priorMean_[kSigma];
    if (prior.geometryScaleSd == 0) lower_[kSize] = upper_[kSize] = priorMean_[kSize];
    // The rotators' scales are held (freeRotatorMass frees them) and out of the prior's coupling too, or
    // holding them at their mean would condition the other masses on the person-level strength they share.
    coupledCovariance_ = cov;
    for (int a = getFirstRotatorIndex(); a < n; ++a) {
        lower_[a] = upper_[a] = priorMean_[a];
        for (int j = 0; j < n; ++j)
            if (j != a) cov[a][j] = cov[j][a] = 0;
    }
    lower_[kActivation] = inside(prior.voluntaryActivation.min);
    upper_[kActivation] = inside(prior.voluntaryActivation.max);
    lower_[kCoContraction] = inside(prior.coContraction.min);
    upper_[kCoContraction] = inside(prior.coContraction.max);
    for (int j : {kActivation, kCoContraction}) priorMean_[j] = std::clamp(priorMean_[j], lower_[j], upper_[j]);
    if (options.readsForearmTorque ||
        std::any_of(conditions.begin(), conditions.end(), [](const TorqueCondition& c) { return isForearmEffort(c.effort); }))
        freeRotatorMass();
}

std::vector<std::string> SynergistModel::getParameterNames() const {
    std::vector<std::string> names = {"ln_biceps_tendon_scale", "voluntary_activation", "co_contraction",
                                      "ln_biceps_fascicle_scale", "ln_synergist_tendon_scale",
                                      "ln_synergist_fascicle_scale", "ln_extensor_mass_scale",
                                      "biceps_slow_fraction_shift", "synergist_slow_fraction_shift",
                                      "ln_specific_tension_scale", "ln_size_scale"};
    for (int i : biceps_) names.push_back("ln_" + base_->muscles[i].params.name + "_mass_scale");
    for (int i : synergists_) names.push_back("ln_" + base_->muscles[i].params.name + "_mass_scale");
    for (int i : rotators_) names.push_back("ln_" + base_->muscles[i].params.name + "_mass_scale");
    return names;
}

int SynergistModel::findPose(double flexionDeg, std::vector<std::pair<double, double>>& poses, double rotationDeg) {
    const std::pair<double, double> pose(flexionDeg, std::isnan(rotationDeg) ? INFINITY : rotationDeg);
    auto it = std::find(poses.begin(), poses.end(), pose);
    if (it != poses.end()) return int(it - poses.begin());
    poses.push_back(pose);
    return int(poses.size()) - 1;
}

int SynergistModel::findKind(Effort effort, double level) {
    auto it = std::find_if(kinds_.begin(), kinds_.end(), [&](const EffortKind& k) { return k.effort == effort && k.level == level; });
    if (it != kinds_.end()) return int(it - kinds_.begin());
    kinds_.push_back({effort, level});
    return int(kinds_.size()) - 1;
}

void SynergistModel::freeRotatorMass() {
    for (int a = getFirstRotatorIndex(); a < getNumParameters(); ++a) {
        lower_[a] = lower_[kExtensorMass];
        upper_[a] = upper_[kExtensorMass];
    }
    priorCovariance_ = coupledCovariance_;
}

std::vector<std::vector<double>> SynergistModel::calcPrimitiveCovariance() const {
    const int nm = int(base_->muscles.size()), nv = getNumPrimitives();
    std::vector<std::vector<double>> v(nv, std::vector<double>(nv, 0.0));
    const Population& p = *prior_;
    const double s2 = p.strengthSubjectSd * p.strengthSubjectSd, m2 = p.strengthMuscleSd * p.strengthMuscleSd;
    for (int i = 0; i < nm; ++i) {
        v[4 * i][4 * i] = p.tendonLengthSd * p.tendonLengthSd;
        v[4 * i + 1][4 * i + 1] = p.fascicleLengthSd * p.fascicleLengthSd;
        v[4 * i + 2][4 * i + 2] = p.slowFractionSd * p.slowFractionSd;
        for (int j = 0; j < nm; ++j) v[4 * i + 3][4 * j + 3] = s2 + (i == j ? m2 : 0.0);
    }
    auto uniformVar = [](const UniformRange& r) { return (r.max - r.min) * (r.max - r.min) / 12.0; };
    v[4 * nm][4 * nm] = p.specificTensionSd * p.specificTensionSd;
    v[4 * nm + 1][4 * nm + 1] = p.geometryScaleSd * p.geometryScaleSd;
    v[4 * nm + 2][4 * nm + 2] = uniformVar(p.voluntaryActivation);
    v[4 * nm + 3][4 * nm + 3] = uniformVar(p.coContraction);
    return v;
}

std::vector<std::vector<std::pair<int, double>>> SynergistModel::getParameterTruths() const {
    const int nm = int(base_->muscles.size()), primary = base_->primary;
    std::vector<std::vector<std::pair<int, double>>> t(getNumParameters());
    t[kTendon] = {{4 * primary, 1.0}};
    t[kFascicle] = {{4 * primary + 1, 1.0}};
    t[kBicepsSlow] = {{4 * primary + 2, 1.0}};
    if (!synergists_.empty()) {
        t[kSynergistTendon] = {{4 * synergists_[0], 1.0}};
        t[kSynergistFascicle] = {{4 * synergists_[0] + 1, 1.0}};
        t[kSynergistSlow] = {{4 * synergists_[0] + 2, 1.0}};
    }
    if (!extensors_.empty()) t[kExtensorMass] = {{4 * extensors_[0] + 3, 1.0}};
    t[kSigma] = {{4 * nm, 1.0}};
    t[kSize] = {{4 * nm + 1, 1.0}};
    t[kActivation] = {{4 * nm + 2, 1.0}};
    t[kCoContraction] = {{4 * nm + 3, 1.0}};
    for (int i = 0; i < nm; ++i) {
        const int k = findMassIndex(i);
        if (k >= 0) t[k] = {{4 * i + 3, 1.0}};
    }
    return t;
}

std::vector<SynergistModel::ConsiderParameter> SynergistModel::getConsiderParameters() const {
    std::vector<ConsiderParameter> out;
    auto in = [](const std::vector<int>& group, int i) { return std::find(group.begin(), group.end(), i) != group.end(); };
    const int nm = int(base_->muscles.size());
    for (int i = 0; i < nm; ++i) {
        // The muscle whose scale x gives muscle i (its group's first), or -1: x has none for it.
        const int anchor = in(biceps_, i) ? base_->primary : in(synergists_, i) ? synergists_[0] : -1;
        for (int kind = 0; kind < 3; ++kind) {
            if (anchor == i) continue;  // x's own
            ConsiderParameter c{i, kind, {{4 * i + kind, 1.0}}};
            if (anchor >= 0) c.truth.push_back({4 * anchor + kind, -1.0});
            out.push_back(c);
        }
        if (in(extensors_, i) && i != extensors_[0]) out.push_back({i, 3, {{4 * i + 3, 1.0}, {4 * extensors_[0] + 3, -1.0}}});
        if (findMassIndex(i) < 0 && !in(extensors_, i)) out.push_back({i, 3, {{4 * i + 3, 1.0}}});
    }
    return out;
}

int SynergistModel::findMassIndex(int muscle) const {
    for (std::size_t k = 0; k < biceps_.size(); ++k)
        if (biceps_[k] == muscle) return kFirstMass + int(k);
    for (std::size_t k = 0; k < synergists_.size(); ++k)
        if (synergists_[k] == muscle) return kFirstMass + int(biceps_.size() + k);
    for (std::size_t k = 0; k < rotators_.size(); ++k)
        if (rotators_[k] == muscle) return getFirstRotatorIndex() + int(k);
    return -1;
}

int SynergistModel::getMassIndex() const { return findMassIndex(base_->primary); }

std::vector<double> SynergistModel::getLnMaxForceWeights() const {
    std::vector<double> g(std::size_t(getNumParameters()), 0.0);
    g[std::size_t(kSigma)] += 1, g[std::size_t(getMassIndex())] += 1, g[kFascicle] -= 1, g[kSize] -= 1;
    return g;
}

std::vector<int> SynergistModel::getFlexorMassIndices() const {
    std::vector<int> out;
    for (std::size_t k = 0; k < biceps_.size() + synergists_.size(); ++k) out.push_back(kFirstMass + int(k));
    return out;
}

std::vector<MuscleSpec> SynergistModel::makeMuscles(const double* x, const std::vector<MuscleDeviation>* deviations) const {
    std::vector<MuscleSpec> m = base_->muscles;
    for (std::size_t k = 0; k < biceps_.size(); ++k) {
        MuscleParameters& q = m[biceps_[k]].params;
        q.mass *= std::exp(x[kFirstMass + k]);
        q.optimalTendonLength *= std::exp(x[kTendon]);
        q.optimalFascicleLength *= std::exp(x[kFascicle]);
        q.slowFraction = std::clamp(q.slowFraction + x[kBicepsSlow], 0.05, 0.95);
    }
    for (std::size_t k = 0; k < synergists_.size(); ++k) {
        MuscleParameters& q = m[synergists_[k]].params;
        q.mass *= std::exp(x[kFirstMass + biceps_.size() + k]);
        q.optimalTendonLength *= std::exp(x[kSynergistTendon]);
        q.optimalFascicleLength *= std::exp(x[kSynergistFascicle]);
        q.slowFraction = std::clamp(q.slowFraction + x[kSynergistSlow], 0.05, 0.95);
    }
    for (int i : extensors_) m[i].params.mass *= std::exp(x[kExtensorMass]);
    for (std::size_t k = 0; k < rotators_.size(); ++k) m[rotators_[k]].params.mass *= std::exp(x[getFirstRotatorIndex() + k]);
    if (deviations)
        for (std::size_t i = 0; i < m.size() && i < deviations->size(); ++i) {
            const MuscleDeviation& d = (*deviations)[i];
            MuscleParameters& q = m[i].params;
            q.optimalTendonLength *= std::exp(d.lnTendon);
            q.optimalFascicleLength *= std::exp(d.lnFascicle);
            q.mass *= std::exp(d.lnMass);
            if (d.slowShift != 0) q.slowFraction = std::clamp(q.slowFraction + d.slowShift, 0.05, 0.95);
        }
    const double sigma = std::exp(x[kSigma]), g = std::exp(x[kSize]);
    for (MuscleSpec& spec : m) {
        MuscleParameters& q = spec.params;
        q.coefficients.sigma *= sigma;
        q.optimalFascicleLength *= g;
        q.optimalTendonLength *= g;
        q.maxPathLength *= g;
    }
    return m;
}

std::vector<double> SynergistModel::calcTorques(const double* x) const {
    std::vector<double> torques, channels;
    calcPredictions(x, torques, channels);
    return torques;
}

void SynergistModel::calcPredictions(const double* x, std::vector<double>& torques, std::vector<double>& channels) const {
    std::vector<double> forearm;
    calcPredictions(x, torques, forearm, channels);
}

void SynergistModel::calcPredictions(const double* x, std::vector<double>& torques, std::vector<double>& forearmTorques,
                                     std::vector<double>& channels) const {
    calcPredictions(x, nullptr, torques, forearmTorques, channels);
}

struct SynergistModel::Evaluation {
    std::vector<MuscleSpec> muscles;
    SteadyMvcCurve relaxed;
    std::vector<SteadyMvcCurve> active;   // per effort kind
    double va = 0, cc = 0, g = 1;
};

SynergistModel::Evaluation SynergistModel::evaluate(const double* x, const std::vector<MuscleDeviation>* deviations,
                                                    PredictionCache* cache, bool sensitivities) const {
    Evaluation e;
    // Guard: the bounds keep difference probes inside [0, 1].
    e.va = std::clamp(x[kActivation], 0.0, 1.0);
    e.cc = std::clamp(x[kCoContraction], 0.0, 1.0);
    e.muscles = makeMuscles(x, deviations);
    e.g = std::exp(x[kSize]);
    MvcGeometry scaled;
    if (e.g != 1) {  // every length scales by g: paths and moment arms too
        scaled = geometry_;
        for (auto* table : {&scaled.pathLength, &scaled.momentArm, &scaled.forearmMomentArm})
            for (std::vector<double>& row : *table)
                for (double& v : row) v *= e.g;
    }
    const MvcGeometry& geometry = e.g != 1 ? scaled : geometry_;
    if (cache) cache->active.resize(kinds_.size());
    e.relaxed = calcRelaxedCurve(e.muscles, geometry, cache ? &cache->relaxed : nullptr, sensitivities);
    for (std::size_t j = 0; j < kinds_.size(); ++j)
        e.active.push_back(calcSteadyMvcCurve(e.muscles, geometry, kinds_[j].effort, agonists_[j],
                                              makeEffort(kinds_[j].level, e.va, e.cc),
                                              cache ? &cache->active[j] : nullptr, sensitivities));
    return e;
}

void SynergistModel::readPredictions(const Evaluation& e, std::vector<double>& torques,
                                     std::vector<double>& forearmTorques, std::vector<double>& channels) const {
    torques.clear();
    forearmTorques.clear();
    for (std::size_t c = 0; c < angleOf_.size(); ++c) {
        torques.push_back(sumTaredTorque(e.active[kindOf_[c]], e.relaxed, std::size_t(angleOf_[c]), leftOut_));
        forearmTorques.push_back(sumTaredTorque(e.active[kindOf_[c]], e.relaxed, std::size_t(angleOf_[c]), leftOut_,
                                                &SteadyMusclePoint::forearmTorque));
    }
    channels.clear();
    for (std::size_t k = 0; k < channels_.size(); ++k) {
        const ChannelObservation& o = channels_[k];
        const int m = channelMuscle_[k];
        const MuscleParameters& q = e.muscles[std::size_t(std::max(m, 0))].params;
        double v = 0;
        if (o.channel == "fascicle_length") {
            const SteadyMvcCurve& curve = channelKind_[k] < 0 ? e.relaxed : e.active[channelKind_[k]];
            v = curve.points[channelAngle_[k]][m].fibreLength * q.optimalFascicleLength;
        } else if (o.channel == "volume") {
            v = q.mass / q.coefficients.density;
        } else if (o.channel == "emg") {
            const bool agonist = isAgonistOf(o.effort, e.muscles[m].group, 0.0);
            const double own = o.level * (agonist ? e.va : e.cc), other = o.level * (agonist ? e.cc : e.va);
            v = (own + emgCrosstalk_ * other) / (e.va + emgCrosstalk_ * e.cc);
        } else {  // upper_arm_length
            v = base_->arm.upperArmLength * e.g;
        }
        channels.push_back(v);
    }
}

void SynergistModel::calcPredictions(const double* x, const std::vector<MuscleDeviation>* deviations,
                                     std::vector<double>& torques, std::vector<double>& forearmTorques,
                                     std::vector<double>& channels, PredictionCache* cache) const {
    readPredictions(evaluate(x, deviations, cache, false), torques, forearmTorques, channels);
}

namespace {

// d F / d x_j and d L / d x_j of one muscle at one steady point: the chain rule through the point's
// sensitivity, its inputs' log-derivatives d (row j of SynergistModel::InputDerivatives) and the drive's
// derivatives by VA and CC.
void differentiatePoint(const SteadyMusclePoint& p, double F0, const SynergistModel::InputDerivatives& d, int va,
                        int cc, double dUdVa, double dUdCc, std::vector<double>& dForce, std::vector<double>& dFibre) {
    using S = SteadySensitivity;
    using I = SynergistModel::Input;
    const S& s = p.sensitivity;
    const int n = int(d.size());
    dForce.resize(n);
    dFibre.resize(n);
    for (int j = 0; j < n; ++j) {
        const double dU = (j == va ? dUdVa : 0.0) + (j == cc ? dUdCc : 0.0);
        double dFn = s.dFn[S::kInput] * dU, dL = s.dL[S::kInput] * dU;
        for (int k = 0; k < S::kInput; ++k) {
            dFn += s.dFn[k] * d[j][k];
            dL += s.dL[k] * d[j][k];
        }
        // F = F0 Fn with F0 = sigma M / (rho L0).
        dForce[j] = p.force * (d[j][I::kLnMass] + d[j][I::kLnTension] - d[j][I::kLnL0]) + F0 * dFn;
        dFibre[j] = dL;
    }
}

bool haveSensitivities(const SteadyMvcCurve& curve) {
    for (const auto& row : curve.points)
        for (const SteadyMusclePoint& p : row)
            if (!p.sensitivity.valid) return false;
    return true;
}

}  // namespace

std::vector<SynergistModel::InputDerivatives> SynergistModel::calcInputDerivatives() const {
    const int n = getNumParameters();
    const std::size_t nm = base_->muscles.size();
    std::vector<InputDerivatives> d(nm, InputDerivatives(std::size_t(n), std::array<double, Input::kNumInputs>{}));
    for (std::size_t i = 0; i < nm; ++i) {
        d[i][kSize] = {1, 1, 1, 1, 0, 0, 1};   // every length
        d[i][kSigma][Input::kLnTension] = 1;
        const int mass = findMassIndex(int(i));
        if (mass >= 0) d[i][mass][Input::kLnMass] = 1;
    }
    for (int i : extensors_) d[i][kExtensorMass][Input::kLnMass] = 1;
    for (const auto& [group, tendon, fascicle] : {std::tuple{&biceps_, kTendon, kFascicle},
                                                  std::tuple{&synergists_, kSynergistTendon, kSynergistFascicle}})
        for (int i : *group) {
            d[i][tendon][Input::kLnL0T] = 1;
            d[i][fascicle][Input::kLnL0] = 1;
        }
    return d;
}

void SynergistModel::addTorqueDerivatives(const Evaluation& e, const std::vector<InputDerivatives>& d, const double* x,
                                          std::vector<double>& dTorques, std::vector<double>& dForearmTorques) const {
    const int n = getNumParameters();
    const int va = x[kActivation] > 0 && x[kActivation] < 1 ? kActivation : -1;   // clamped outside
    const int cc = x[kCoContraction] > 0 && x[kCoContraction] < 1 ? kCoContraction : -1;
    std::vector<double> dForce, dFibre, dRelaxed(n), dRelaxedForearm(n);
    for (std::size_t a = 0; a < geometry_.flexionDeg.size(); ++a)
        for (std::size_t i = 0; i < e.muscles.size(); ++i) {
            if (std::find(leftOut_.begin(), leftOut_.end(), int(i)) != leftOut_.end()) continue;
            const double F0 = calcMaxIsometricForce(e.muscles[i].params);
            // The relaxed point, subtracted from every condition at this pose; torque = h F, h ~ g.
            const SteadyMusclePoint& r = e.relaxed.points[a][i];
            differentiatePoint(r, F0, d[i], va, cc, 0, 0, dForce, dFibre);
            for (int j = 0; j < n; ++j) {
                const double dF = dForce[j] + r.force * d[i][j][Input::kLnArm];
                dRelaxed[j] = r.momentArm * dF;
                dRelaxedForearm[j] = r.forearmMomentArm * dF;
            }
            for (std::size_t kind = 0; kind < kinds_.size(); ++kind) {
                const SteadyMusclePoint& p = e.active[kind].points[a][i];
                const double level = kinds_[kind].level;
                const bool agonist = agonists_[kind][a][i];
                bool differentiated = false;
                for (std::size_t c = 0; c < angleOf_.size(); ++c) {
                    if (angleOf_[c] != int(a) || kindOf_[c] != int(kind)) continue;
                    if (!differentiated) differentiatePoint(p, F0, d[i], va, cc, agonist ? level : 0.0, agonist ? 0.0 : level, dForce, dFibre);
                    differentiated = true;
                    for (int j = 0; j < n; ++j) {
                        const double dF = dForce[j] + p.force * d[i][j][Input::kLnArm];
                        dTorques[c * n + j] += p.momentArm * dF - dRelaxed[j];
                        dForearmTorques[c * n + j] += p.forearmMomentArm * dF - dRelaxedForearm[j];
                    }
                }
            }
        }
}

void SynergistModel::calcChannelDerivatives(const Evaluation& e, const std::vector<InputDerivatives>& d, const double* x,
                                            const std::vector<double>& channels, std::vector<double>& dChannels) const {
    const int n = getNumParameters();
    const int va = x[kActivation] > 0 && x[kActivation] < 1 ? kActivation : -1;
    const int cc = x[kCoContraction] > 0 && x[kCoContraction] < 1 ? kCoContraction : -1;
    std::vector<double> dForce, dFibre;
    for (std::size_t k = 0; k < channels_.size(); ++k) {
        const ChannelObservation& o = channels_[k];
        const int m = channelMuscle_[k];
        double* row = &dChannels[k * n];
        if (o.channel == "fascicle_length") {   // L L0
            const int kind = channelKind_[k];
            const SteadyMusclePoint& p = (kind < 0 ? e.relaxed : e.active[kind]).points[channelAngle_[k]][m];
            const bool agonist = kind >= 0 && agonists_[kind][channelAngle_[k]][m];
            const double level = kind < 0 ? 0.0 : kinds_[kind].level;
            differentiatePoint(p, calcMaxIsometricForce(e.muscles[m].params), d[m], va, cc, agonist ? level : 0.0,
                               agonist || kind < 0 ? 0.0 : level, dForce, dFibre);
            const double L0 = e.muscles[m].params.optimalFascicleLength;
            for (int j = 0; j < n; ++j) row[j] = L0 * dFibre[j] + channels[k] * d[m][j][Input::kLnL0];
        } else if (o.channel == "volume") {   // M / rho
            for (int j = 0; j < n; ++j) row[j] = channels[k] * d[m][j][Input::kLnMass];
        } else if (o.channel == "emg") {   // (own + c other) / (VA + c CC)
            const bool agonist = isAgonistOf(o.effort, e.muscles[m].group, 0.0);
            const double c = emgCrosstalk_, D = e.va + c * e.cc;
            const double N = o.level * (agonist ? e.va + c * e.cc : e.cc + c * e.va);
            if (va >= 0) row[va] = (o.level * (agonist ? 1.0 : c) * D - N) / (D * D);
            if (cc >= 0) row[cc] = (o.level * (agonist ? c : 1.0) * D - N * c) / (D * D);
        } else {  // upper_arm_length, ~ g
            row[kSize] = channels[k];
        }
    }
}

void SynergistModel::calcPredictionJacobian(const double* x, std::vector<double>& torques,
                                            std::vector<double>& forearmTorques, std::vector<double>& channels,
                                            std::vector<double>& dTorques, std::vector<double>& dForearmTorques,
                                            std::vector<double>& dChannels, PredictionCache* cache) const {
    const int n = getNumParameters();
    const Evaluation e = evaluate(x, nullptr, cache, true);
    readPredictions(e, torques, forearmTorques, channels);
    const std::size_t nc = torques.size(), nk = channels.size();
    dTorques.assign(nc * n, 0.0);
    dForearmTorques.assign(nc * n, 0.0);
    dChannels.assign(nk * n, 0.0);
    bool analytic = haveSensitivities(e.relaxed);
    for (const SteadyMvcCurve& curve : e.active) analytic = analytic && haveSensitivities(curve);
    if (analytic) {
        const std::vector<InputDerivatives> d = calcInputDerivatives();   // once for both
        addTorqueDerivatives(e, d, x, dTorques, dForearmTorques);
        calcChannelDerivatives(e, d, x, channels, dChannels);
    }
    // Columns by central differences (Ceres's steps): the slow-fraction shifts when free, or every
    // column when a muscle has no steady sensitivity.
    std::vector<double> xp(x, x + n), t, f, ch, plus, minus;
    auto flatten = [&](std::vector<double>& out) {
        out.assign(t.begin(), t.end());
        out.insert(out.end(), f.begin(), f.end());
        out.insert(out.end(), ch.begin(), ch.end());
    };
    for (int j = 0; j < n; ++j) {
        if (analytic && !((j == kBicepsSlow || j == kSynergistSlow) && lower_[j] < upper_[j])) continue;
        const double delta = std::max(std::sqrt(std::numeric_limits<double>::epsilon()), std::abs(x[j]) * 1e-6);
        xp[j] = x[j] + delta;
        calcPredictions(xp.data(), nullptr, t, f, ch, cache);
        flatten(plus);
        xp[j] = x[j] - delta;
        calcPredictions(xp.data(), nullptr, t, f, ch, cache);
        flatten(minus);
        xp[j] = x[j];
        for (std::size_t r = 0; r < plus.size(); ++r) {
            const double v = (plus[r] - minus[r]) / (2 * delta);
            if (r < nc) dTorques[r * n + j] = v;
            else if (r < 2 * nc) dForearmTorques[(r - nc) * n + j] = v;
            else dChannels[(r - 2 * nc) * n + j] = v;
        }
    }
}

// The error covariance of the linearized fit when the truth also varies what the fit holds or shares
// (SynergistModel, consider parameters): with F the free parameters, Lambda the prior's precision on
// them, C0 = (J_F' J_F + Lambda)^-1 and w = (x_F, x_held, considered) - their means with the prior
// population's covariance S, the error is C0 (J_F' n + B w), B = [-Lambda, J_F' J_held, J_F' J_c], so
// its covariance is C0 (J_F' J_F + B S B') C0 (C0 again when the fit's model is the truth's).
void SynergistModel::prepareConsidered() {
    const std::vector<ConsiderParameter> considered = getConsiderParameters();
    const int n = getNumParameters(), nk = int(considered.size());
    for (int j = 0; j < n; ++j) (lower_[j] >= upper_[j] ? held_ : free_).push_back(j);
    const int nf = int(free_.size()), nh = int(held_.size());
    Eigen::MatrixXd P(n, n);
    for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b) P(a, b) = priorCovariance_[a][b];
    const Eigen::LLT<Eigen::MatrixXd> pl(P);
    if (nf == 0 || pl.info() != Eigen::Success) return;
    const Eigen::MatrixXd Pinv = pl.solve(Eigen::MatrixXd::Identity(n, n));
    freePrecision_.assign(nf, std::vector<double>(nf));
    for (int a = 0; a < nf; ++a)
        for (int b = 0; b < nf; ++b) freePrecision_[a][b] = Pinv(free_[a], free_[b]);
    // w = T v: the truths as combinations of the population's independent primitives v; a parameter
    // that stands for none (a group the model does not have) keeps the fit's own prior variance.
    const std::vector<std::vector<std::pair<int, double>>> truths = getParameterTruths();
    const std::vector<std::vector<double>> V = calcPrimitiveCovariance();
    const int nv = int(V.size()), nw = nf + nh + nk;
    Eigen::MatrixXd T = Eigen::MatrixXd::Zero(nw, nv + nw);
    auto fill = [&](int row, const std::vector<std::pair<int, double>>& terms, int parameter) {
        for (const auto& [v, coefficient] : terms) T(row, v) += coefficient;
        if (terms.empty() && parameter >= 0) T(row, nv + row) = std::sqrt(priorCovariance_[parameter][parameter]);
    };
    for (int a = 0; a < nf; ++a) fill(a, truths[free_[a]], free_[a]);
    for (int a = 0; a < nh; ++a) fill(nf + a, truths[held_[a]], -1);  // held and standing for nothing: known
    for (int a = 0; a < nk; ++a) fill(nf + nh + a, considered[a].truth, -1);
    Eigen::MatrixXd Vm = Eigen::MatrixXd::Identity(nv + nw, nv + nw);  // private primitives: unit variance
    for (int a = 0; a < nv; ++a)
        for (int b = 0; b < nv; ++b) Vm(a, b) = V[a][b];
    const Eigen::MatrixXd S = T * Vm * T.transpose();
    truthCovariance_.assign(nw, std::vector<double>(nw));
    for (int a = 0; a < nw; ++a)
        for (int b = 0; b < nw; ++b) truthCovariance_[a][b] = S(a, b);
}

namespace {

// The linearized fit at J (the whitened data rows over the n parameters, then the consider parameters):
// G = [J_free, J_held, J_considered] in the truths' order, S their covariance, lambda the prior precision
// on the free ones, H = J_free' J_free and C0 = (H + lambda)^-1.
struct LinearizedFit {
    Eigen::MatrixXd G, S, lambda, H, C0;
};

// false when H + lambda is not positive definite.
bool linearizeFit(const std::vector<std::vector<double>>& J, int n, const std::vector<int>& free,
                  const std::vector<int>& held, const std::vector<std::vector<double>>& freePrecision,
                  const std::vector<std::vector<double>>& truthCovariance, LinearizedFit& f) {
    const int R = int(J.size()), nf = int(free.size()), nh = int(held.size()), nw = int(truthCovariance.size()),
              nk = nw - nf - nh;
    f.G.resize(R, nw);
    for (int k = 0; k < R; ++k) {
        for (int a = 0; a < nf; ++a) f.G(k, a) = J[k][free[a]];
        for (int a = 0; a < nh; ++a) f.G(k, nf + a) = J[k][held[a]];
        for (int a = 0; a < nk; ++a) f.G(k, nf + nh + a) = J[k][n + a];
    }
    f.lambda.resize(nf, nf);
    for (int a = 0; a < nf; ++a)
        for (int b = 0; b < nf; ++b) f.lambda(a, b) = freePrecision[a][b];
    f.S.resize(nw, nw);
    for (int a = 0; a < nw; ++a)
        for (int b = 0; b < nw; ++b) f.S(a, b) = truthCovariance[a][b];
    f.H = f.G.leftCols(nf).transpose() * f.G.leftCols(nf);
    const Eigen::LLT<Eigen::MatrixXd> hl(f.H + f.lambda);
    if (hl.info() != Eigen::Success) return false;
    f.C0 = hl.solve(Eigen::MatrixXd::Identity(nf, nf));
    return true;
}

}  // namespace

bool SynergistModel::calcConsideredCovariance(const std::vector<std::vector<double>>& J,
                                              std::vector<std::vector<double>>& c0Out,
                                              std::vector<std::vector<double>>& cOut) const {
    const int n = getNumParameters(), R = int(J.size());
    const int nf = int(free_.size()), nh = int(held_.size()), nw = int(truthCovariance_.size()), nk = nw - nf - nh;
    if (truthCovariance_.empty()) return false;
    if (R > 0 && int(J[0].size()) != n + nk)
        throw std::logic_error("calcConsideredCovariance: expected " + std::to_string(n + nk) + " Jacobian columns");
    LinearizedFit f;
    if (!linearizeFit(J, n, free_, held_, freePrecision_, truthCovariance_, f)) return false;
    Eigen::MatrixXd B(nf, nw);
    B.leftCols(nf) = -f.lambda;
    B.rightCols(nh + nk) = f.G.leftCols(nf).transpose() * f.G.rightCols(nh + nk);
    Eigen::MatrixXd C = f.C0 * (f.H + B * f.S * B.transpose()) * f.C0;
    C = 0.5 * (C + C.transpose());
    c0Out.assign(n, std::vector<double>(n, 0.0));
    cOut.assign(n, std::vector<double>(n, 0.0));
    for (int a = 0; a < nf; ++a)
        for (int b = 0; b < nf; ++b) {
            c0Out[free_[a]][free_[b]] = f.C0(a, b);
            cOut[free_[a]][free_[b]] = C(a, b);
        }
    return true;
}

ChannelFit SynergistModel::calcPriorCheck(const std::vector<std::vector<double>>& J, const std::vector<double>& x) const {
    ChannelFit fit;
    fit.channel = "prior";
    fit.chiSquare = 0;
    const int n = getNumParameters(), R = int(J.size());
    const int nf = int(free_.size()), nh = int(held_.size()), nw = int(truthCovariance_.size()), nk = nw - nf - nh;
    if (truthCovariance_.empty() || R == 0 || int(J[0].size()) != n + nk) return fit;
    LinearizedFit f;
    if (!linearizeFit(J, n, free_, held_, freePrecision_, truthCovariance_, f)) return fit;
    const Eigen::MatrixXd M = f.G.leftCols(nf).transpose() * f.G;
    Eigen::MatrixXd D = f.C0 * (M * f.S * M.transpose() + f.H) * f.C0;
    D = 0.5 * (D + D.transpose());
    const Eigen::MatrixXd& S = f.S;
    // The log-scale parameters the fit moves, off their bounds.
    std::vector<int> use;
    for (int a = 0; a < nf; ++a) {
        const int j = free_[a];
        if (j == kActivation || j == kCoContraction) continue;
        if (!(x[j] > lower_[j] + 1e-9 && x[j] < upper_[j] - 1e-9)) continue;
        use.push_back(a);
    }
    const int m = int(use.size());
    if (m == 0) return fit;
    Eigen::MatrixXd Ds(m, m), Ss(m, m);
    Eigen::VectorXd d(m);
    for (int a = 0; a < m; ++a) {
        d(a) = x[free_[use[a]]] - priorMean_[free_[use[a]]];
        for (int b = 0; b < m; ++b) Ds(a, b) = D(use[a], use[b]), Ss(a, b) = S(use[a], use[b]);
    }
    const Eigen::LLT<Eigen::MatrixXd> sl(Ss);
    if (sl.info() != Eigen::Success) return fit;
    const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> ges(Ds, Ss);
    if (ges.info() != Eigen::Success) return fit;
    for (int i = 0; i < m; ++i) {
        const double l = ges.eigenvalues()(i);
        if (!(l >= kPriorCheckShare)) continue;
        const double u = ges.eigenvectors().col(i).dot(d);  // eigenvectors: v' Ss v = 1
        fit.chiSquare += u * u / l;
        ++fit.n;
    }
    const std::vector<std::string> names = getParameterNames();
    for (int a = 0; a < m; ++a) {
        if (!(Ds(a, a) >= kPriorCheckShare * Ss(a, a))) continue;
        const double z = d(a) / std::sqrt(Ds(a, a));
        if (!(std::abs(z) <= std::abs(fit.worstResidual))) {
            fit.worstResidual = z;
            fit.worst = names[std::size_t(free_[use[a]])] + " from the prior mean";
        }
    }
    if (fit.n > 0) fit.p = calcChiSquareSurvival(fit.chiSquare, fit.n);
    return fit;
}

void SynergistModel::setDeviation(std::vector<MuscleDeviation>& deviations, const ConsiderParameter& c, double by) {
    MuscleDeviation& d = deviations.at(std::size_t(c.muscle));
    (c.kind == 0 ? d.lnTendon : c.kind == 1 ? d.lnFascicle : c.kind == 2 ? d.slowShift : d.lnMass) = by;
}

std::vector<double> SynergistModel::getSecantSteps() const {
    const std::vector<ConsiderParameter> considered = getConsiderParameters();
    const int n = getNumParameters();
    std::vector<double> steps(std::size_t(n) + considered.size(), 0.0);
    for (int j = 0; j < n; ++j)
        if (lower_[j] >= upper_[j]) steps[j] = 0.5 * std::sqrt(priorCovariance_[j][j]);
    const double sd[4] = {prior_->tendonLengthSd, prior_->fascicleLengthSd, prior_->slowFractionSd, prior_->strengthMuscleSd};
    for (std::size_t k = 0; k < considered.size(); ++k) steps[n + k] = 0.5 * sd[considered[k].kind];
    return steps;
}

// One synergist-aware fit, in named steps: the data's rows and their sds, the residuals and their
// Jacobian, the MAP estimate, each channel's judgement and the intervals.
class SynergistFit {
public:
    using P = SynergistModel;
    SynergistFit(const Population& prior, const std::vector<TorqueObservation>& data, const SynergistOptions& options)
        : prior_(prior), data_(data), options_(options), channels_(options.channels),
          measured_(std::isfinite(options.measuredActivation)), model_(prior, checkInputs(), conditions_) {
        n_ = model_.getNumParameters();
        for (const ChannelObservation& o : channels_)
            if (!(o.sd > 0) || !std::isfinite(o.value))
                throw InputError("synergist-aware identifier: " + o.channel + " measurement" +
                                 (o.line > 0 ? " on line " + std::to_string(o.line) : std::string()) +
                                 " has value " + formatNumber(o.value) + " and sd " + formatNumber(o.sd) +
                                 ": expected a finite value and sd > 0");
    }
    MuscleEstimate run();

private:
    struct Row {   // a transducer reading: observation and axis
        std::size_t observation;
        bool forearm;
    };
    const Population& prior_;
    const std::vector<TorqueObservation>& data_;
    const SynergistOptions& options_;
    const std::vector<ChannelObservation>& channels_;
    const bool measured_;
    std::vector<TorqueCondition> conditions_;
    SynergistOptions modelOptions_;
    std::vector<Row> rows_;
    std::size_t nFlexion_ = 0;
    const SynergistModel model_;
    int n_ = 0;
    std::vector<double> torque_, sd_;   // per row
    P::PredictionCache cache_;          // the fit, its covariance and the consider Jacobian run on this thread
    struct {
        std::vector<double> x, r, J;
    } last_;                            // the last Jacobian (Ceres asks twice at an accepted point)

    const SynergistOptions& checkInputs();
    void setNoise(MuscleEstimate& est);
    int getNumResiduals() const { return int(rows_.size() + channels_.size()) + (measured_ ? 1 : 0); }
    std::vector<double> calcResiduals(const double* x, double* r, const std::vector<P::MuscleDeviation>* deviations = nullptr);
    bool calcResidualJacobian(const double* x, double* r, double* J);
    MapProblem makeProblem();
    void setParameters(MuscleEstimate& est, const std::vector<double>& x) const;
    void judgeChannels(MuscleEstimate& est, const std::vector<double>& r) const;
    bool calcConsiderJacobian(const std::vector<double>& x, std::vector<std::vector<double>>& J);
    void setIntervals(MuscleEstimate& est, const MapResult& m);
};

// Checks the options, builds one condition per observation (the model computes each distinct angle and
// effort kind once) and the transducer's rows; returns the model's options.
const SynergistOptions& SynergistFit::checkInputs() {
    if (data_.empty()) throw InputError("synergist-aware identifier: no observations");
    if (measured_) {
        checkField("measured voluntary activation", options_.measuredActivation, Bound{0, 1, true, false, "fraction of full drive"});
        checkField("activation sd", options_.activationSd, Bound::positive());
    }
    bool readsForearm = false;
    for (const TorqueObservation& o : data_) {
        TorqueCondition c{o.flexionDeg, o.effort, o.level, 1};
        c.rotationDeg = o.rotationDeg;
        conditions_.push_back(c);
        readsForearm = readsForearm || std::isfinite(o.forearmTorque);
        if (isForearmEffort(o.effort) && !std::isfinite(o.forearmTorque))
            throw InputError(std::string("synergist-aware identifier: a ") + getEffortName(o.effort) + " effort at " +
                             formatNumber(o.flexionDeg) + " deg without its forearm torque");
    }
    // The transducer's rows: the flexion axis of every flexion and extension effort, then the forearm
    // axis wherever it was read. A rotation effort's flexion axis is left out: it is the flexors'
    // co-contraction, whose motor-unit recruitment steps (a unit starts at its minimum firing rate)
    // make the steady prediction jump at the low activations that carry it.
    for (std::size_t k = 0; k < data_.size(); ++k)
        if (!isForearmEffort(data_[k].effort)) rows_.push_back({k, false});
    nFlexion_ = rows_.size();
    for (std::size_t k = 0; k < data_.size(); ++k)
        if (std::isfinite(data_[k].forearmTorque)) rows_.push_back({k, true});
    modelOptions_ = options_;
    modelOptions_.readsForearmTorque = options_.readsForearmTorque || readsForearm;
    return modelOptions_;
}

// The relative noise level (given, estimated from the repetitions or the population's transducer
// noise) and each row's sd: the level times the transducer's load (1 N m at least).
void SynergistFit::setNoise(MuscleEstimate& est) {
    std::tie(est.noiseLevel, est.noiseDegreesOfFreedom) = estimateNoiseLevel(data_);
    if (std::isfinite(options_.noiseLevel)) {
        checkField("noise level", options_.noiseLevel, Bound::closed(kMinTorqueNoiseLevel, 0.5, "relative sd"));
        est.noiseLevel = options_.noiseLevel;
        est.noiseDegreesOfFreedom = 0;
    } else if (!std::isfinite(est.noiseLevel)) {
        est.noiseLevel = prior_.transducerNoise;
        est.noiseDegreesOfFreedom = 0;
    }
    est.noiseLevel = std::max(est.noiseLevel, kMinTorqueNoiseLevel);
    for (const Row& row : rows_) {
        const TorqueObservation& o = data_[row.observation];
        torque_.push_back(row.forearm ? o.forearmTorque : o.torque);
        sd_.push_back(est.noiseLevel * std::max(o.getLoad(), 1.0));
    }
}

// Residuals: torques, then channels, then the measured activation; returns the flexion-axis torques.
std::vector<double> SynergistFit::calcResiduals(const double* x, double* r, const std::vector<P::MuscleDeviation>* deviations) {
    const std::size_t nt = rows_.size(), nc = channels_.size();
    std::vector<double> t, f, c;
    model_.calcPredictions(x, deviations, t, f, c, &cache_);
    for (std::size_t k = 0; k < nt; ++k) r[k] = ((rows_[k].forearm ? f : t)[rows_[k].observation] - torque_[k]) / sd_[k];
    for (std::size_t k = 0; k < nc; ++k) r[nt + k] = (c[k] - channels_[k].value) / channels_[k].sd;
    if (measured_) r[nt + nc] = (x[P::kActivation] - options_.measuredActivation) / options_.activationSd;
    return t;
}

// The same residuals with their Jacobian through the steady states (calcPredictionJacobian).
bool SynergistFit::calcResidualJacobian(const double* x, double* r, double* J) {
    const std::size_t R = std::size_t(getNumResiduals()), nt = rows_.size(), nc = channels_.size(), n = std::size_t(n_);
    if (last_.x.size() == n && std::equal(last_.x.begin(), last_.x.end(), x)) {
        std::copy(last_.r.begin(), last_.r.end(), r);
        std::copy(last_.J.begin(), last_.J.end(), J);
        return true;
    }
    last_.x.clear();
    std::vector<double> t, f, c, dt, df, dc;
    try {
        model_.calcPredictionJacobian(x, t, f, c, dt, df, dc, &cache_);
    } catch (const std::exception&) {
        return false;
    }
    std::fill(J, J + R * n, 0.0);
    for (std::size_t k = 0; k < nt; ++k) {
        const Row& row = rows_[k];
        r[k] = ((row.forearm ? f : t)[row.observation] - torque_[k]) / sd_[k];
        const double* d = &(row.forearm ? df : dt)[row.observation * n];
        for (std::size_t j = 0; j < n; ++j) J[k * n + j] = d[j] / sd_[k];
    }
    for (std::size_t k = 0; k < nc; ++k) {
        r[nt + k] = (c[k] - channels_[k].value) / channels_[k].sd;
        for (std::size_t j = 0; j < n; ++j) J[(nt + k) * n + j] = dc[k * n + j] / channels_[k].sd;
    }
    if (measured_) {
        r[nt + nc] = (x[P::kActivation] - options_.measuredActivation) / options_.activationSd;
        J[(nt + nc) * n + P::kActivation] = 1 / options_.activationSd;
    }
    last_.x.assign(x, x + n);
    last_.r.assign(r, r + R);
    last_.J.assign(J, J + R * n);
    return true;
}

MapProblem SynergistFit::makeProblem() {
    MapProblem map;
    map.priorMean = model_.getPriorMean();
    map.priorCovariance = model_.getPriorCovariance();
    map.lower = model_.getLower();
    map.upper = model_.getUpper();
    map.numResiduals = getNumResiduals();
    map.residuals = [this](const double* x, double* r) {
        try {
            calcResiduals(x, r);
        } catch (const std::exception&) {
            return false;
        }
        return true;
    };
    map.jacobian = [this](const double* x, double* r, double* J) { return calcResidualJacobian(x, r, J); };
    return map;
}

// Mass, tendon length, F0, specific tension and the nuisance parameters at the estimate x.
void SynergistFit::setParameters(MuscleEstimate& est, const std::vector<double>& x) const {
    const ArmSetup& base = prior_.base;
    const MuscleParameters& b = base.muscles[base.primary].params;
    est.numParameters = n_;
    est.mass = b.mass * std::exp(x[model_.getMassIndex()]);
    est.tendonLength = b.optimalTendonLength * std::exp(x[P::kTendon] + x[P::kSize]);
    est.nuisanceNames = {"voluntary_activation", "co_contraction", "biceps_fascicle_scale", "synergist_tendon_scale",
                         "synergist_fascicle_scale", "extensor_mass_scale"};
    est.nuisance = {x[P::kActivation], x[P::kCoContraction], std::exp(x[P::kFascicle]),
                    std::exp(x[P::kSynergistTendon]), std::exp(x[P::kSynergistFascicle]), std::exp(x[P::kExtensorMass])};
    if (options_.freeSlowFraction) {
        est.nuisanceNames.insert(est.nuisanceNames.end(), {"biceps_slow_fraction_shift", "synergist_slow_fraction_shift"});
        est.nuisance.insert(est.nuisance.end(), {x[P::kBicepsSlow], x[P::kSynergistSlow]});
    }
    if (prior_.specificTensionSd > 0) {
        est.nuisanceNames.push_back("specific_tension_scale");
        est.nuisance.push_back(std::exp(x[P::kSigma]));
    }
    if (prior_.geometryScaleSd > 0) {
        est.nuisanceNames.push_back("size_scale");
        est.nuisance.push_back(std::exp(x[P::kSize]));
    }
    for (int i = 0; i < base.getNumMuscles(); ++i) {
        const int k = model_.findMassIndex(i);
        if (k < 0 || i == base.primary || model_.getLower()[k] == model_.getUpper()[k]) continue;  // held: a rotator
        est.nuisanceNames.push_back(base.muscles[i].params.name + "_mass_scale");
        est.nuisance.push_back(std::exp(x[k]));
    }
    const MuscleParameters q = model_.makeMuscles(x.data())[base.primary].params;
    est.specificTension = q.coefficients.sigma;
    est.maxForce = q.coefficients.sigma * q.mass / (q.coefficients.density * q.optimalFascicleLength);
}

// Per channel: chi-square of its residuals r and the worst measurement.
void SynergistFit::judgeChannels(MuscleEstimate& est, const std::vector<double>& r) const {
    const std::size_t nt = rows_.size(), nc = channels_.size();
    auto addFit = [&](const std::string& channel, std::size_t k, const std::string& what) {
        auto it = std::find_if(est.channelFits.begin(), est.channelFits.end(),
                               [&](const ChannelFit& f) { return f.channel == channel; });
        if (it == est.channelFits.end()) {
            ChannelFit f;
            f.channel = channel;
            f.chiSquare = 0;
            est.channelFits.push_back(f);
            it = est.channelFits.end() - 1;
        }
        ++it->n;
        it->chiSquare += r[k] * r[k];
        if (!(std::abs(r[k]) <= std::abs(it->worstResidual))) {
            it->worstResidual = r[k];
            it->worst = what;
        }
    };
    auto describe = [](double flexionDeg, Effort effort, double level) {
        return std::string(getEffortName(effort)) + (level == 1 ? " MVC" : level == 0 ? " (at rest)" : " " + formatNumber(100 * level) + " %") +
               " at " + formatNumber(flexionDeg) + " deg";
    };
    auto posture = [](const TorqueObservation& o) {
        return std::isnan(o.rotationDeg) ? std::string() : ", forearm at " + formatNumber(o.rotationDeg) + " deg";
    };
    for (std::size_t k = 0; k < nt; ++k) {
        const TorqueObservation& o = data_[rows_[k].observation];
        addFit(rows_[k].forearm ? "forearm_torque" : "torque", k, describe(o.flexionDeg, o.effort, o.level) + posture(o));
    }
    for (std::size_t k = 0; k < nc; ++k) {
        const ChannelObservation& o = channels_[k];
        addFit(o.channel, nt + k,
               o.muscle + (std::isfinite(o.flexionDeg) ? ", " + describe(o.flexionDeg, o.effort, o.level) : std::string()));
    }
    if (measured_) addFit("activation", nt + nc, "twitch interpolation");
    for (ChannelFit& f : est.channelFits) f.p = calcChiSquareSurvival(f.chiSquare, f.n);
}

// The whitened data residuals' Jacobian at the estimate over every parameter (free and held) and every
// consider parameter: for the free parameters the tangent (calcResidualJacobian); for the held and
// considered ones a central secant over +/- half their prior sd, the spread the truth has (muscle forces
// step with motor-unit recruitment: a tangent there can be any size). false where a probe has no steady state.
bool SynergistFit::calcConsiderJacobian(const std::vector<double>& x, std::vector<std::vector<double>>& J) {
    const std::vector<P::ConsiderParameter> considered = model_.getConsiderParameters();
    const int n = n_, nk = int(considered.size()), R = getNumResiduals();
    J.assign(R, std::vector<double>(n + nk, 0.0));
    const std::vector<double> steps = model_.getSecantSteps();
    std::vector<double> r0(R), J0(std::size_t(R) * n);
    if (!calcResidualJacobian(x.data(), r0.data(), J0.data())) return false;
    for (int j = 0; j < n; ++j)
        if (model_.getLower()[j] < model_.getUpper()[j])
            for (int k = 0; k < R; ++k) J[k][j] = J0[std::size_t(k) * n + j];
    std::vector<double> xp = x, rp(R), rm(R);
    std::vector<P::MuscleDeviation> deviations(prior_.base.muscles.size());
    auto shift = [&](int j, double by) {
        if (j < n) return void(xp[j] = x[j] + by);
        P::setDeviation(deviations, considered[j - n], by);
    };
    try {
        for (int j = 0; j < n + nk; ++j) {
            if (!(steps[j] > 0)) continue;  // free (a tangent), or the prior does not vary it
            shift(j, steps[j]);
            calcResiduals(xp.data(), rp.data(), &deviations);
            shift(j, -steps[j]);
            calcResiduals(xp.data(), rm.data(), &deviations);
            shift(j, 0);
            for (int k = 0; k < R; ++k) J[k][j] = (rp[k] - rm[k]) / (2 * steps[j]);
        }
    } catch (const std::exception&) {
        return false;
    }
    return true;
}

// The 95 % intervals of M, L0T and F0 from the estimate's error covariance with the consider parameters
// (the Laplace covariance where the consider Jacobian has no value), and the prior's check.
void SynergistFit::setIntervals(MuscleEstimate& est, const MapResult& m) {
    const std::vector<double>& x = m.x;
    const int n = n_;
    // Reported quantities as linear combinations of x: ln M; ln L0T = ln t_b + ln g; ln F0.
    std::vector<double> gm(n, 0.0), gt(n, 0.0), gf = model_.getLnMaxForceWeights();
    gm[model_.getMassIndex()] = 1;
    gt[P::kTendon] += 1, gt[P::kSize] += 1;
    auto quadratic = [&](const std::vector<double>& a, const std::vector<std::vector<double>>& M, const std::vector<double>& b) {
        double v = 0;
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j) v += a[i] * M[i][j] * b[j];
        return v;
    };
    std::vector<std::vector<double>> J;
    const bool haveJacobian = calcConsiderJacobian(x, J);   // else the Laplace covariance and the conservative quantile
    // C0: the Laplace covariance; C: the estimate's error covariance with the consider parameters.
    std::vector<std::vector<double>> C0 = m.covariance, C = m.covariance;
    if (haveJacobian) {
        model_.calcConsideredCovariance(J, C0, C);
        const ChannelFit check = model_.calcPriorCheck(J, x);
        if (check.n > 0) est.channelFits.push_back(check);
    }
    // Degrees of freedom of each interval. The torque rows' sd is the noise level estimated with nu
    // dof; a quantity whose error variance owes the fraction f = g'C0 Ht C0 g / g'C g to the torque
    // rows (Ht = Jt'Jt, their whitened Jacobian) has that variance estimated with about nu / f^2 dof
    // (Satterthwaite); the channels' and the prior's sds are known. Torque alone: f near 1, the
    // Student-t of nu; a volume measured: f small, near the normal quantile.
    std::vector<double> fraction(3, 1.0);
    const int nu = est.noiseDegreesOfFreedom;
    if (nu > 0 && haveJacobian) {
        std::vector<std::vector<double>> ht(n, std::vector<double>(n, 0.0));
        for (std::size_t k = 0; k < rows_.size(); ++k)
            for (int a = 0; a < n; ++a)
                if (J[k][a] != 0)
                    for (int b = 0; b < n; ++b) ht[a][b] += J[k][a] * J[k][b];
        int q = 0;
        for (const std::vector<double>* g : {&gm, &gt, &gf}) {
            std::vector<double> cg(n, 0.0);  // C0 g
            for (int a = 0; a < n; ++a)
                for (int b = 0; b < n; ++b) cg[a] += C0[a][b] * (*g)[b];
            const double v = quadratic(*g, C, *g);
            fraction[q++] = v > 0 ? std::clamp(quadratic(cg, ht, cg) / v, 0.0, 1.0) : 1.0;
        }
    }
    auto quantileOf = [&](double f) {
        if (nu <= 0 || f <= 0) return calcNormalQuantile(0.975);
        return calcStudentTQuantile(0.975, std::min(double(nu) / (f * f), 1e6));
    };
    const double sm = std::sqrt(std::max(quadratic(gm, C, gm), 0.0)), st = std::sqrt(std::max(quadratic(gt, C, gt), 0.0)),
                 sf = std::sqrt(std::max(quadratic(gf, C, gf), 0.0));
    const double qm = quantileOf(fraction[0]), qt = quantileOf(fraction[1]), qf = quantileOf(fraction[2]);
    est.massLower = est.mass * std::exp(-qm * sm);
    est.massUpper = est.mass * std::exp(qm * sm);
    est.tendonLower = est.tendonLength * std::exp(-qt * st);
    est.tendonUpper = est.tendonLength * std::exp(qt * st);
    est.maxForceLower = est.maxForce * std::exp(-qf * sf);
    est.maxForceUpper = est.maxForce * std::exp(qf * sf);
    est.massTendonCorrelation = quadratic(gm, C, gt) / (sm * st);
}

MuscleEstimate SynergistFit::run() {
    MuscleEstimate est;
    est.method = !channels_.empty() ? "channels" : measured_ ? "synergist-va" : "synergist";
    est.predictedTorque.assign(data_.size(), NAN);   // whole even when the fit fails
    setNoise(est);
    const MapResult m = calcMapEstimate(makeProblem());
    est.converged = m.converged;
    est.message = m.message;
    est.iterations = m.iterations;
    if (m.failed) {  // no estimate: mass and tendon length stay NaN
        est.converged = false;
        return est;
    }
    setParameters(est, m.x);
    std::vector<double> r(static_cast<std::size_t>(getNumResiduals()));
    try {
        const std::vector<double> t = calcResiduals(m.x.data(), r.data());
        double ss = 0;
        for (std::size_t k = 0; k < nFlexion_; ++k) ss += std::pow(t[rows_[k].observation] - torque_[k], 2);
        est.predictedTorque = t;  // the flexion axis; NaN where it is not fitted (rotation efforts)
        for (std::size_t k = 0; k < data_.size(); ++k)
            if (isForearmEffort(data_[k].effort)) est.predictedTorque[k] = NAN;
        est.rmsResidual = std::sqrt(ss / double(std::max<std::size_t>(nFlexion_, 1)));
    } catch (const std::exception& e) {
        est.converged = false;
        est.message += "; no steady state at the estimate: " + std::string(e.what());
        return est;
    }
    judgeChannels(est, r);
    if (!m.covariance.empty()) setIntervals(est, m);
    return est;
}

MuscleEstimate identifySynergistAware(const Population& prior, const std::vector<TorqueObservation>& data,
                                      const SynergistOptions& options) {
    return SynergistFit(prior, data, options).run();
}

double measureVoluntaryActivation(const std::vector<TorqueObservation>& data, double sd, unsigned seed) {
    checkField("activation sd", sd, Bound::nonNegative());
    PortableRandom rng{seed};
    double mean = 0;
    int n = 0;
    for (const TorqueObservation& o : data)
        if (o.level == 1) mean += o.activation, ++n;
    if (n == 0) throw InputError("measureVoluntaryActivation: no maximal efforts (twitch interpolation needs MVCs)");
    mean /= n;
    return std::clamp(mean + sd * rng.drawNormal(), 0.0, 1.0);
}


}  // namespace armsim
