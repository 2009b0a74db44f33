#include "identification/elbow_identification.h"

#include "basics/bound.h"
#include "basics/csv.h"
#include "basics/parallel.h"
#include "basics/portable_random.h"
#include "identification/identifier.h"
#include "identification/map_estimate.h"
#include "identification/statistics.h"
#include "model/geometry.h"
#include "model/mvc_curve.h"
#include "model/trial.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <tuple>

namespace armsim {

namespace {

// Tared steady torque at each angle of the geometry: the curve of an effort of `group` less the
// relaxed one, summed over the muscles not left out. Throws SimulationError when a muscle has no steady
// state.
std::vector<double> calcTaredTorque(const std::vector<MuscleSpec>& muscles, const MvcGeometry& g, MuscleGroup group,
                                    const SubjectEffort& effort, const SteadyMvcCurve& relaxed,
                                    const std::vector<int>& leftOut = {}) {
    const SteadyMvcCurve active = calcSteadyMvcCurve(muscles, g, group, effort);
    std::vector<double> torque;
    for (std::size_t a = 0; a < g.flexionDeg.size(); ++a) {
        double t = 0;
        for (std::size_t i = 0; i < muscles.size(); ++i)
            if (std::find(leftOut.begin(), leftOut.end(), int(i)) == leftOut.end())
                t += active.points[a][i].torque - relaxed.points[a][i].torque;
        torque.push_back(t);
    }
    return torque;
}

SteadyMvcCurve calcRelaxedCurve(const std::vector<MuscleSpec>& muscles, const MvcGeometry& g) {
    return calcSteadyMvcCurve(muscles, g, MuscleGroup::Flexor, SubjectEffort{0, 0});
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
// of freedom.
std::pair<double, int> estimateNoiseLevel(const std::vector<TorqueObservation>& data) {
    std::map<std::tuple<double, int, double>, std::vector<double>> byCondition;
    for (const TorqueObservation& o : data) byCondition[{o.flexionDeg, int(o.effort), o.level}].push_back(o.torque);
    double ss = 0;
    int dof = 0;
    for (const auto& [condition, v] : byCondition) {
        if (v.size() < 2) continue;
        double m = 0;
        for (double x : v) m += x;
        m /= double(v.size());
        for (double x : v) ss += (x / m - 1) * (x / m - 1);
        dof += int(v.size()) - 1;
    }
    return {dof > 0 ? std::sqrt(ss / dof) : NAN, dof};
}

}  // namespace

std::vector<double> calcTaredSteadyTorque(const ArmSetup& setup, const SubjectEffort& effort,
                                          const std::vector<double>& flexionDeg, MuscleGroup group) {
    const MvcGeometry g = calcMvcGeometry(setup, flexionDeg);
    return calcTaredTorque(setup.muscles, g, group, effort, calcRelaxedCurve(setup.muscles, g));
}

BicepsEstimate identifyThesisMethod(const ArmSetup& assumed, const std::vector<TorqueObservation>& allData) {
    BicepsEstimate est;
    est.method = "thesis";
    std::vector<TorqueObservation> data;  // the method knows flexion MVCs only
    for (const TorqueObservation& o : allData)
        if (o.isFlexionMvc()) data.push_back(o);
    if (data.empty()) throw InputError("thesis method: no flexion MVC in the data (it uses those only)");
    std::vector<double> angles;
    for (const TorqueObservation& o : data) angles.push_back(o.flexionDeg);
    const MvcGeometry g = calcMvcGeometry(assumed, angles);
    IdentificationProblem problem;
    problem.base = assumed.calcBicepsParameters();
    problem.data.source = "tared torque / biceps moment arm";
    for (std::size_t k = 0; k < data.size(); ++k) {
        Observation o;
        o.pathLength = g.pathLength[k][assumed.primary];
        o.activation = 1.0;  // the thesis assumes a maximal effort is full activation
        o.force = data[k].torque / g.momentArm[k][assumed.primary];
        o.angle = elbowAngleFromFlexion(degToRad(data[k].flexionDeg));
        o.trial = data[k].repetition;
        problem.data.points.push_back(o);
    }
    IdentificationOptions options;
    options.noise = NoiseModel::Relative;
    const IdentificationReport r = identify(problem, SteadyForceModel(), options);
    est.converged = r.isConverged();
    est.message = getStopReasonName(r.stopReason) + ": " + r.message;
    est.iterations = r.iterations;
    est.mass = r.parameters.at(0).value;
    est.tendonLength = r.parameters.at(1).value;
    est.massLower = r.parameters[0].ciLower;
    est.massUpper = r.parameters[0].ciUpper;
    est.tendonLower = r.parameters[1].ciLower;
    est.tendonUpper = r.parameters[1].ciUpper;
    est.noiseLevel = r.residualSd;
    if (r.hasUncertainty) est.massTendonCorrelation = r.correlation[0][1];
    est.rmsResidual = r.rmsResidual;
    est.numParameters = 2;
    std::size_t k = 0;
    for (const TorqueObservation& o : allData) {
        est.predictedTorque.push_back(o.isFlexionMvc() ? r.modelForces[k] * g.momentArm[k][assumed.primary] : NAN);
        k += o.isFlexionMvc();
    }
    return est;
}

SynergistModel::SynergistModel(const Population& prior, const SynergistOptions& options,
                               const std::vector<TorqueCondition>& conditions)
    : base_(&prior.base) {
    const ArmSetup& base = prior.base;
    biceps_ = findMuscles(base, options.biceps, "biceps");
    synergists_ = findMuscles(base, options.synergists, "synergists");
    if (!options.includeSynergists) leftOut_ = synergists_;
    for (int i = 0; i < base.getNumMuscles(); ++i)
        if (base.muscles[i].group == MuscleGroup::Extensor) extensors_.push_back(i);
    if (std::find(biceps_.begin(), biceps_.end(), base.primary) == biceps_.end())
        throw InputError("synergist-aware identifier: the primary muscle '" + base.muscles[base.primary].params.name +
                         "' is not in the biceps group");
    std::vector<double> angles;
    for (const TorqueCondition& c : conditions) {
        auto it = std::find(angles.begin(), angles.end(), c.flexionDeg);
        angleOf_.push_back(int(it - angles.begin()));
        if (it == angles.end()) angles.push_back(c.flexionDeg);
        auto kt = std::find_if(kinds_.begin(), kinds_.end(),
                               [&](const EffortKind& k) { return k.group == c.effort && k.level == c.level; });
        kindOf_.push_back(int(kt - kinds_.begin()));
        if (kt == kinds_.end()) kinds_.push_back({c.effort, c.level});
    }
    geometry_ = calcMvcGeometry(base, angles);

    const int n = getNumParameters();
    const double s2 = prior.strengthSubjectSd * prior.strengthSubjectSd;
    const double m2 = prior.strengthMuscleSd * prior.strengthMuscleSd;
    auto uniformSd = [](const UniformRange& r) { return std::max((r.max - r.min) / std::sqrt(12.0), 1e-4); };
    priorCovariance_.assign(n, std::vector<double>(n, 0.0));
    auto& cov = priorCovariance_;
    std::vector<int> masses = {kExtensorMass};
    for (int a = kFirstMass; a < n; ++a) masses.push_back(a);
    for (int a : masses)
        for (int b : masses) cov[a][b] = s2;
    cov[kBicepsSlow][kBicepsSlow] = cov[kSynergistSlow][kSynergistSlow] = std::pow(prior.slowFractionSd, 2);
    cov[kExtensorMass][kExtensorMass] += m2 / double(std::max<std::size_t>(extensors_.size(), 1));
    for (int a = kFirstMass; a < n; ++a) cov[a][a] += m2;
    cov[kTendon][kTendon] = cov[kSynergistTendon][kSynergistTendon] = std::pow(prior.tendonLengthSd, 2);
    cov[kFascicle][kFascicle] = cov[kSynergistFascicle][kSynergistFascicle] = std::pow(prior.fascicleLengthSd, 2);
    cov[kActivation][kActivation] = std::pow(uniformSd(prior.voluntaryActivation), 2);
    cov[kCoContraction][kCoContraction] = std::pow(uniformSd(prior.coContraction), 2);
    for (int j = 0; j < n; ++j) cov[j][j] = std::max(cov[j][j], 1e-10);  // a zero spread: the value is known
    priorMean_.assign(n, 0.0);
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
        lower_[j] = options.freeSlowFraction ? -0.3 : 0.0;
        upper_[j] = options.freeSlowFraction ? 0.3 : 0.0;
    }
    lower_[kActivation] = inside(prior.voluntaryActivation.min);
    upper_[kActivation] = inside(prior.voluntaryActivation.max);
    lower_[kCoContraction] = inside(prior.coContraction.min);
    upper_[kCoContraction] = inside(prior.coContraction.max);
    for (int j : {kActivation, kCoContraction}) priorMean_[j] = std::clamp(priorMean_[j], lower_[j], upper_[j]);
}

std::vector<std::string> SynergistModel::getParameterNames() const {
    std::vector<std::string> names = {"ln_biceps_tendon_scale", "voluntary_activation", "co_contraction",
                                      "ln_biceps_fascicle_scale", "ln_synergist_tendon_scale",
                                      "ln_synergist_fascicle_scale", "ln_extensor_mass_scale",
                                      "biceps_slow_fraction_shift", "synergist_slow_fraction_shift"};
    for (int i : biceps_) names.push_back("ln_" + base_->muscles[i].params.name + "_mass_scale");
    for (int i : synergists_) names.push_back("ln_" + base_->muscles[i].params.name + "_mass_scale");
    return names;
}

int SynergistModel::findMassIndex(int muscle) const {
    for (std::size_t k = 0; k < biceps_.size(); ++k)
        if (biceps_[k] == muscle) return kFirstMass + int(k);
    for (std::size_t k = 0; k < synergists_.size(); ++k)
        if (synergists_[k] == muscle) return kFirstMass + int(biceps_.size() + k);
    return -1;
}

int SynergistModel::getMassIndex() const { return findMassIndex(base_->primary); }

std::vector<int> SynergistModel::getFlexorMassIndices() const {
    std::vector<int> out;
    for (std::size_t k = 0; k < biceps_.size() + synergists_.size(); ++k) out.push_back(kFirstMass + int(k));
    return out;
}

std::vector<MuscleSpec> SynergistModel::makeMuscles(const double* x) const {
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
    return m;
}

std::vector<double> SynergistModel::calcTorques(const double* x) const {
    // Guard: the bounds keep difference probes inside [0, 1].
    const double va = std::clamp(x[kActivation], 0.0, 1.0), cc = std::clamp(x[kCoContraction], 0.0, 1.0);
    const std::vector<MuscleSpec> muscles = makeMuscles(x);
    const SteadyMvcCurve relaxed = calcRelaxedCurve(muscles, geometry_);
    std::vector<std::vector<double>> byKind;
    for (const EffortKind& k : kinds_)
        byKind.push_back(calcTaredTorque(muscles, geometry_, k.group, makeEffort(k.level, va, cc), relaxed, leftOut_));
    std::vector<double> t;
    for (std::size_t c = 0; c < angleOf_.size(); ++c) t.push_back(byKind[kindOf_[c]][angleOf_[c]]);
    return t;
}

BicepsEstimate identifySynergistAware(const Population& prior, const std::vector<TorqueObservation>& data,
                                      const SynergistOptions& options) {
    if (data.empty()) throw InputError("synergist-aware identifier: no observations");
    const bool measured = std::isfinite(options.measuredActivation);
    if (measured) {
        checkField("measured voluntary activation", options.measuredActivation, Bound::closed(0, 1));
        checkField("activation sd", options.activationSd, Bound::positive());
    }
    // One condition per observation: the model computes each distinct angle and effort kind once.
    std::vector<TorqueCondition> conditions;
    std::vector<double> torque;
    for (const TorqueObservation& o : data) {
        conditions.push_back({o.flexionDeg, o.effort, o.level, 1});
        torque.push_back(o.torque);
    }
    const SynergistModel model(prior, options, conditions);

    BicepsEstimate est;
    est.method = measured ? "synergist-va" : "synergist";
    std::tie(est.noiseLevel, est.noiseDegreesOfFreedom) = estimateNoiseLevel(data);
    if (std::isfinite(options.noiseLevel)) {
        checkField("noise level", options.noiseLevel, Bound{0, 0.5, true, true, "relative sd"});
        est.noiseLevel = options.noiseLevel;
        est.noiseDegreesOfFreedom = 0;
    } else if (!std::isfinite(est.noiseLevel)) {
        est.noiseLevel = prior.transducerNoise;
        est.noiseDegreesOfFreedom = 0;
    }
    est.noiseLevel = std::max(est.noiseLevel, 0.002);  // floor: the scatter of few repetitions can be ~0
    std::vector<double> sd;
    for (double t : torque) sd.push_back(est.noiseLevel * std::max(std::abs(t), 1.0));

    using P = SynergistModel;
    MapProblem map;
    map.priorMean = model.getPriorMean();
    map.priorCovariance = model.getPriorCovariance();
    map.lower = model.getLower();
    map.upper = model.getUpper();
    map.numResiduals = int(torque.size()) + (measured ? 1 : 0);
    map.residuals = [&](const double* x, double* r) {
        if (measured) r[torque.size()] = (x[P::kActivation] - options.measuredActivation) / options.activationSd;
        std::vector<double> t;
        try {
            t = model.calcTorques(x);
        } catch (const std::exception&) {
            return false;
        }
        for (std::size_t k = 0; k < torque.size(); ++k) r[k] = (t[k] - torque[k]) / sd[k];
        return true;
    };
    const MapResult m = calcMapEstimate(map);
    const std::vector<double>& x = m.x;
    est.converged = m.converged;
    est.message = m.message;
    est.iterations = m.iterations;
    if (m.failed) return est;  // no estimate: mass and tendon length stay NaN

    const ArmSetup& base = prior.base;
    const MuscleParameters& b = base.muscles[base.primary].params;
    const int im = model.getMassIndex();
    est.numParameters = model.getNumParameters();
    est.mass = b.mass * std::exp(x[im]);
    est.tendonLength = b.optimalTendonLength * std::exp(x[P::kTendon]);
    est.nuisanceNames = {"voluntary_activation", "co_contraction", "biceps_fascicle_scale", "synergist_tendon_scale",
                         "synergist_fascicle_scale", "extensor_mass_scale"};
    est.nuisance = {x[P::kActivation], x[P::kCoContraction], std::exp(x[P::kFascicle]),
                    std::exp(x[P::kSynergistTendon]), std::exp(x[P::kSynergistFascicle]), std::exp(x[P::kExtensorMass])};
    if (options.freeSlowFraction) {
        est.nuisanceNames.insert(est.nuisanceNames.end(), {"biceps_slow_fraction_shift", "synergist_slow_fraction_shift"});
        est.nuisance.insert(est.nuisance.end(), {x[P::kBicepsSlow], x[P::kSynergistSlow]});
    }
    for (int i = 0; i < base.getNumMuscles(); ++i) {
        const int k = model.findMassIndex(i);
        if (k < 0 || i == base.primary) continue;
        est.nuisanceNames.push_back(base.muscles[i].params.name + "_mass_scale");
        est.nuisance.push_back(std::exp(x[k]));
    }
    try {
        const std::vector<double> t = model.calcTorques(x.data());
        double ss = 0;
        for (std::size_t k = 0; k < torque.size(); ++k) {
            est.predictedTorque.push_back(t[k]);
            ss += std::pow(t[k] - torque[k], 2);
        }
        est.rmsResidual = std::sqrt(ss / double(torque.size()));
    } catch (const std::exception& e) {
        est.converged = false;
        est.message += "; no steady state at the estimate: " + std::string(e.what());
        return est;
    }
    if (!m.covariance.empty()) {
        const double quantile = est.noiseDegreesOfFreedom > 0 ? calcStudentTQuantile(0.975, est.noiseDegreesOfFreedom)
                                                          : calcNormalQuantile(0.975);
        const double sm = std::sqrt(m.covariance[im][im]), st = std::sqrt(m.covariance[P::kTendon][P::kTendon]);
        est.massLower = b.mass * std::exp(x[im] - quantile * sm);
        est.massUpper = b.mass * std::exp(x[im] + quantile * sm);
        est.tendonLower = b.optimalTendonLength * std::exp(x[P::kTendon] - quantile * st);
        est.tendonUpper = b.optimalTendonLength * std::exp(x[P::kTendon] + quantile * st);
        est.massTendonCorrelation = m.covariance[im][P::kTendon] / (sm * st);
    }
    return est;
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

const std::vector<std::string>& getElbowMethodKinds() {
    static const std::vector<std::string> kinds = {"thesis", "synergist", "synergist-va"};
    return kinds;
}

BicepsEstimate identifyElbowMethod(const ElbowMethod& method, const Population& population,
                                   const std::vector<TorqueObservation>& data, unsigned seed, int subject) {
    BicepsEstimate e;
    if (method.kind == "thesis") {
        e = identifyThesisMethod(population.base, data);
    } else if (method.kind == "synergist") {
        SynergistOptions o = method.options;
        o.measuredActivation = 0.0 / 0.0;
        e = identifySynergistAware(population, data, o);
    } else if (method.kind == "synergist-va") {
        SynergistOptions o = method.options;
        checkField("activation_sd", o.activationSd, Bound{0, 0.5, true, false});
        o.measuredActivation = measureVoluntaryActivation(data, o.activationSd, seed + 7919u * unsigned(subject));
        e = identifySynergistAware(population, data, o);
    } else {
        throw InputError("identifier '" + method.kind + "': expected thesis, synergist or synergist-va");
    }
    e.method = method.label.empty() ? method.kind : method.label;
    return e;
}

ElbowValidationRow makeElbowValidationRow(const Population& population, const VirtualSubject& v, double noise,
                                          const std::string& method, const BicepsEstimate& e) {
    const int primary = population.base.primary;
    ElbowValidationRow row;
    row.subject = v.index;
    row.noise = noise;
    row.method = method;
    row.trueMass = v.setup.muscles[primary].params.mass;
    row.trueTendonLength = v.setup.muscles[primary].params.optimalTendonLength;
    row.estimate = e;
    row.massError = e.mass / row.trueMass - 1;
    row.tendonError = e.tendonLength - row.trueTendonLength;
    if (std::isfinite(e.massLower)) row.massCovered = row.trueMass >= e.massLower && row.trueMass <= e.massUpper;
    if (std::isfinite(e.tendonLower))
        row.tendonCovered = row.trueTendonLength >= e.tendonLower && row.trueTendonLength <= e.tendonUpper;
    row.voluntaryActivation = v.setup.effort.voluntaryActivation;
    row.coContraction = v.setup.effort.coContraction;
    row.strengthLevel = v.strengthLevel;
    // Nuisance truths of the muscles the model has (a model without them leaves NaN).
    auto present = [&](const std::vector<std::string>& names) {
        std::vector<int> out;
        for (const std::string& n : names)
            for (int i = 0; i < population.base.getNumMuscles(); ++i)
                if (population.base.muscles[i].params.name == n) out.push_back(i);
        return out;
    };
    for (int i : present(SynergistOptions().biceps))
        if (i != primary) row.bicepsShortScale = v.massScale[i] / v.massScale[primary];
    const std::vector<int> synergists = present(SynergistOptions().synergists);
    double syn = 0;
    for (int i : synergists) syn += v.massScale[i];
    if (!synergists.empty()) row.synergistScale = syn / double(synergists.size()) / v.massScale[primary];
    return row;
}

std::vector<ElbowValidationRow> runElbowValidation(const Population& population, const ElbowValidationSettings& settings,
                                                   const std::function<void(int, int)>& progress) {
    population.validate();
    settings.protocol.validate();
    checkField("subjects", settings.subjects, Bound::closed(1, 1e6));
    checkField("activation_sd", settings.activationSd, Bound::closed(0, 0.5));
    std::vector<double> levels = settings.noiseLevels;
    if (levels.empty()) levels.push_back(population.transducerNoise);
    for (double v : levels) checkField("noise", v, Bound{0, 0.5, false, true, "relative sd"});
    std::vector<ElbowMethod> methods(settings.activationSd > 0 ? 3 : 2);
    for (std::size_t k = 0; k < methods.size(); ++k) {
        methods[k].kind = getElbowMethodKinds()[k];
        methods[k].options.freeSlowFraction = settings.freeSlowFraction;
        methods[k].options.activationSd = settings.activationSd;
    }

    std::vector<std::vector<ElbowValidationRow>> perSubject(settings.subjects);
    runParallel(settings.subjects, settings.jobs, [&](int s) {
        const VirtualSubject v = drawSubject(population, settings.seed, s);
        const std::vector<TorqueObservation> clean = synthesizeTorqueData(v, settings.protocol, settings.seed, 1);
        for (double level : levels) {
            const std::vector<TorqueObservation> data = setTransducerNoise(clean, level);
            for (const ElbowMethod& m : methods) {
                // A method that cannot use these data (the thesis method with fewer flexion-MVC angles
                // than unknowns) is recorded as failed, not fatal.
                BicepsEstimate e;
                try {
                    e = identifyElbowMethod(m, population, data, settings.seed, s);
                } catch (const std::exception& x) {
                    e.method = m.kind;
                    e.message = x.what();
                }
                perSubject[s].push_back(makeElbowValidationRow(population, v, level, m.kind, e));
            }
        }
    }, progress);
    std::vector<ElbowValidationRow> rows;
    for (auto& r : perSubject) rows.insert(rows.end(), r.begin(), r.end());
    return rows;
}

std::vector<ElbowValidationSummary> summarizeElbowValidation(const std::vector<ElbowValidationRow>& rows) {
    std::vector<ElbowValidationSummary> out;
    for (const ElbowValidationRow& r : rows) {
        auto it = std::find_if(out.begin(), out.end(),
                               [&](const ElbowValidationSummary& s) { return s.method == r.method && s.noise == r.noise; });
        if (it == out.end()) {
            out.push_back({});
            it = out.end() - 1;
            it->method = r.method;
            it->noise = r.noise;
        }
        ++it->subjects;
    }
    for (ElbowValidationSummary& s : out) {
        double mb = 0, mm = 0, tb = 0, tm = 0, mw = 0, tw = 0;
        int mc = 0, mn = 0, tc = 0, tn = 0, n = 0;
        for (const ElbowValidationRow& r : rows) {
            if (r.method != s.method || r.noise != s.noise) continue;
            if (r.estimate.converged) ++s.converged;
            if (!std::isfinite(r.massError) || !std::isfinite(r.tendonError)) continue;
            ++n;
            mb += r.massError, mm += r.massError * r.massError;
            tb += r.tendonError, tm += r.tendonError * r.tendonError;
            if (r.massCovered >= 0) {
                ++mn, mc += r.massCovered;
                mw += (r.estimate.massUpper - r.estimate.massLower) / r.estimate.mass;
            }
            if (r.tendonCovered >= 0) {
                ++tn, tc += r.tendonCovered;
                tw += r.estimate.tendonUpper - r.estimate.tendonLower;
            }
        }
        s.massBias = s.massRmse = s.tendonBias = s.tendonRmse = 0.0 / 0.0;  // no estimate
        if (n > 0) {
            s.massBias = mb / n, s.massRmse = std::sqrt(mm / n);
            s.tendonBias = tb / n, s.tendonRmse = std::sqrt(tm / n);
        }
        if (mn > 0) s.massCoverage = double(mc) / mn, s.massIntervalWidth = mw / mn;
        if (tn > 0) s.tendonCoverage = double(tc) / tn, s.tendonIntervalWidth = tw / tn;
    }
    return out;
}

std::string formatElbowValidationCsv(const std::vector<ElbowValidationRow>& rows) {
    CsvText csv({"subject", "noise", "method", "converged", "true_mass_kg", "mass_kg", "mass_lower_kg", "mass_upper_kg",
                 "mass_error_pct", "mass_covered", "true_tendon_length_m", "tendon_length_m", "tendon_lower_m",
                 "tendon_upper_m", "tendon_error_mm", "tendon_covered", "voluntary_activation", "co_contraction",
                 "strength_level", "biceps_short_scale", "synergist_scale", "noise_level_used", "rms_residual"});
    auto flag = [](CsvRow& row, int c) -> CsvRow& { return c < 0 ? row.addEmpty() : row.addInteger(c); };
    for (const ElbowValidationRow& r : rows) {
        const BicepsEstimate& e = r.estimate;
        CsvRow row;
        row.addInteger(r.subject).addNumber(r.noise).addText(r.method).addInteger(e.converged ? 1 : 0);
        row.addNumber(r.trueMass).addNumber(e.mass).addNumber(e.massLower).addNumber(e.massUpper);
        flag(row.addNumber(100 * r.massError), r.massCovered);
        row.addNumber(r.trueTendonLength).addNumber(e.tendonLength).addNumber(e.tendonLower).addNumber(e.tendonUpper);
        flag(row.addNumber(1000 * r.tendonError), r.tendonCovered);
        row.addNumber(r.voluntaryActivation).addNumber(r.coContraction).addNumber(r.strengthLevel);
        row.addNumber(r.bicepsShortScale).addNumber(r.synergistScale).addNumber(e.noiseLevel).addNumber(e.rmsResidual);
        csv.addRow(row);
    }
    return csv.getText();
}

std::string formatElbowValidationSummaryCsv(const std::vector<ElbowValidationSummary>& summaries) {
    CsvText csv({"method", "noise", "subjects", "converged", "mass_bias_pct", "mass_rmse_pct", "mass_coverage",
                 "tendon_bias_mm", "tendon_rmse_mm", "tendon_coverage"});
    for (const ElbowValidationSummary& s : summaries) {
        CsvRow row;
        row.addText(s.method).addNumber(s.noise).addInteger(s.subjects).addInteger(s.converged);
        row.addNumber(100 * s.massBias).addNumber(100 * s.massRmse).addNumber(s.massCoverage);
        row.addNumber(1000 * s.tendonBias).addNumber(1000 * s.tendonRmse).addNumber(s.tendonCoverage);
        csv.addRow(row);
    }
    return csv.getText();
}

std::string formatTorqueEstimatesCsv(const std::vector<TorqueObservation>& data,
                                     const std::vector<BicepsEstimate>& estimates, double noiseLevel) {
    CsvText csv({"method", "converged", "mass_kg", "mass_lower_kg", "mass_upper_kg", "tendon_length_m",
                 "tendon_lower_m", "tendon_upper_m", "rms_residual_Nm", "chi_square", "dof", "p_value", "noise_level"});
    for (const BicepsEstimate& e : estimates) {
        const TorqueResidualCheck c = checkTorqueResiduals(data, e, noiseLevel);
        CsvRow row;
        row.addText(e.method).addInteger(e.converged ? 1 : 0).addNumber(e.mass).addNumber(e.massLower);
        row.addNumber(e.massUpper).addNumber(e.tendonLength).addNumber(e.tendonLower).addNumber(e.tendonUpper);
        row.addNumber(c.rms).addNumber(c.chiSquare).addInteger(c.dof).addNumber(c.p).addNumber(noiseLevel);
        csv.addRow(row);
    }
    return csv.getText();
}

std::string formatTorquePredictionsCsv(const std::vector<TorqueObservation>& data,
                                       const std::vector<BicepsEstimate>& estimates) {
    std::vector<std::string> header = {"flexion_deg", "effort", "level", "repetition", "torque_Nm"};
    for (const BicepsEstimate& e : estimates) header.push_back(e.method + "_Nm");
    CsvText csv(header);
    for (std::size_t k = 0; k < data.size(); ++k) {
        const TorqueObservation& d = data[k];
        CsvRow row;
        row.addNumber(d.flexionDeg).addInteger(d.effort == MuscleGroup::Flexor ? 1 : -1).addNumber(d.level);
        row.addInteger(d.repetition).addNumber(d.torque);
        for (const BicepsEstimate& e : estimates) row.addNumber(e.predictedTorque[k]);
        csv.addRow(row);
    }
    return csv.getText();
}

void TorqueIdentificationOptions::validate() const {
    if (!std::isnan(noiseLevel)) checkField("noise_level", noiseLevel, Bound::closed(1e-4, 0.5));
    if (!std::isnan(activation)) checkField("activation", activation, Bound::closed(0, 1));
    checkField("activation_sd", activationSd, Bound::closed(1e-4, 0.5));
}

std::vector<BicepsEstimate> identifyTorqueData(const Population& prior, const std::vector<TorqueObservation>& data,
                                               const TorqueIdentificationOptions& o, std::string* skipped) {
    o.validate();
    std::vector<BicepsEstimate> estimates;
    std::set<double> mvcAngles;
    for (const TorqueObservation& d : data)
        if (d.isFlexionMvc()) mvcAngles.insert(d.flexionDeg);
    if (skipped) skipped->clear();
    if (mvcAngles.size() >= 2)
        estimates.push_back(identifyThesisMethod(prior.base, data));
    else if (skipped)
        *skipped = "thesis method: skipped (it fits flexion MVCs at >= 2 angles; these data have " +
                   std::to_string(mvcAngles.size()) + ")";
    SynergistOptions so;
    so.noiseLevel = o.noiseLevel;
    estimates.push_back(identifySynergistAware(prior, data, so));
    if (std::isfinite(o.activation)) {
        so.measuredActivation = o.activation;
        so.activationSd = o.activationSd;
        estimates.push_back(identifySynergistAware(prior, data, so));
    }
    return estimates;
}

double findJudgingNoiseLevel(const TorqueIdentificationOptions& o, const std::vector<BicepsEstimate>& estimates) {
    if (std::isfinite(o.noiseLevel) || estimates.empty()) return o.noiseLevel;
    return estimates.back().noiseLevel;
}

TorqueResidualCheck checkTorqueResiduals(const std::vector<TorqueObservation>& data, const BicepsEstimate& e,
                                         double noise) {
    TorqueResidualCheck c;
    double sum = 0, chi = 0;
    for (std::size_t k = 0; k < data.size() && k < e.predictedTorque.size(); ++k) {
        if (!std::isfinite(e.predictedTorque[k])) continue;
        const double residual = e.predictedTorque[k] - data[k].torque;
        const double sd = noise * std::max(std::abs(data[k].torque), 1.0);
        sum += residual * residual;
        chi += std::pow(residual / sd, 2);
        ++c.n;
    }
    c.rms = std::sqrt(sum / std::max(c.n, 1));
    c.chiSquare = chi;
    c.dof = std::max(1, c.n - (e.method == "thesis" ? e.numParameters : 0));
    c.p = calcChiSquareSurvival(c.chiSquare, c.dof);
    return c;
}

}  // namespace armsim
