#include "identification/elbow_identification.h"

#include "identification/identifier.h"
#include "identification/map_estimate.h"
#include "identification/statistics.h"
#include "experiments/portable_random.h"
#include "model/geometry.h"
#include "model/mvc_curve.h"
#include "model/parallel.h"
#include "model/trial.h"
#include "muscles/param_file.h"

#include <algorithm>
#include <cmath>
#include <map>
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

// The synergist-aware problem. x = [ln t_b, VA, CC, ln f_b, ln t_s, ln f_s, ln s_e, then ln s_m for every
// biceps head and every synergist m]: t tendon, f fascicle length and s mass scales; b the biceps heads
// (one tendon and one fascicle scale), s the synergists, e the extensors (one mass scale).
struct SynergistProblem {
    static constexpr int kTendon = 0, kActivation = 1, kCoContraction = 2, kFascicle = 3, kSynergistTendon = 4,
                         kSynergistFascicle = 5, kExtensorMass = 6, kFirstMass = 7;
    // The distinct effort kinds of the data, each predicted at every angle.
    struct EffortKind {
        MuscleGroup group;
        double level;
    };
    const ArmSetup* base;
    MvcGeometry geometry;
    std::vector<EffortKind> kinds;
    std::vector<int> angleOf, kindOf;         // observation -> angle index, effort kind
    std::vector<double> torque, sd;           // observations and their sd [N m]
    std::vector<int> biceps, synergists, extensors, leftOut;

    int size() const { return kFirstMass + int(biceps.size() + synergists.size()); }
    /// Index in x of muscle i's own mass scale (-1: extensor or ungrouped).
    int findMassIndex(int i) const {
        for (std::size_t k = 0; k < biceps.size(); ++k)
            if (biceps[k] == i) return kFirstMass + int(k);
        for (std::size_t k = 0; k < synergists.size(); ++k)
            if (synergists[k] == i) return kFirstMass + int(biceps.size() + k);
        return -1;
    }
    std::vector<MuscleSpec> makeMuscles(const double* x) const {
        std::vector<MuscleSpec> m = base->muscles;
        for (std::size_t k = 0; k < biceps.size(); ++k) {
            MuscleParameters& q = m[biceps[k]].params;
            q.mass *= std::exp(x[kFirstMass + k]);
            q.optimalTendonLength *= std::exp(x[kTendon]);
            q.optimalFascicleLength *= std::exp(x[kFascicle]);
        }
        for (std::size_t k = 0; k < synergists.size(); ++k) {
            MuscleParameters& q = m[synergists[k]].params;
            q.mass *= std::exp(x[kFirstMass + biceps.size() + k]);
            q.optimalTendonLength *= std::exp(x[kSynergistTendon]);
            q.optimalFascicleLength *= std::exp(x[kSynergistFascicle]);
        }
        for (int i : extensors) m[i].params.mass *= std::exp(x[kExtensorMass]);
        return m;
    }
    /// [kind][angle] tared torque.
    std::vector<std::vector<double>> predict(const double* x) const {
        // Guard: the bounds keep difference probes inside [0, 1] (see identifySynergistAware).
        const double va = std::clamp(x[kActivation], 0.0, 1.0), cc = std::clamp(x[kCoContraction], 0.0, 1.0);
        const std::vector<MuscleSpec> muscles = makeMuscles(x);
        const SteadyMvcCurve relaxed = calcRelaxedCurve(muscles, geometry);
        std::vector<std::vector<double>> t;
        for (const EffortKind& k : kinds)
            t.push_back(calcTaredTorque(muscles, geometry, k.group, makeEffort(k.level, va, cc), relaxed, leftOut));
        return t;
    }
    double predicted(const std::vector<std::vector<double>>& t, std::size_t k) const { return t[kindOf[k]][angleOf[k]]; }
    // Whitened data residuals; false where a muscle has no steady state.
    bool calcResiduals(const double* x, double* residuals) const {
        std::vector<std::vector<double>> t;
        try {
            t = predict(x);
        } catch (const std::exception&) {
            return false;
        }
        for (std::size_t k = 0; k < torque.size(); ++k) residuals[k] = (predicted(t, k) - torque[k]) / sd[k];
        return true;
    }
};

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
        if (o.effort == MuscleGroup::Flexor && o.level == 1) data.push_back(o);
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
    est.mass = r.parameters.at(0).value;
    est.tendonLength = r.parameters.at(1).value;
    est.massLower = r.parameters[0].ciLower;
    est.massUpper = r.parameters[0].ciUpper;
    est.tendonLower = r.parameters[1].ciLower;
    est.tendonUpper = r.parameters[1].ciUpper;
    est.noiseLevel = r.residualSd;
    if (r.hasUncertainty) est.massTendonCorrelation = r.correlation[0][1];
    est.rmsResidual = r.rmsResidual;
    return est;
}

BicepsEstimate identifySynergistAware(const Population& prior, const std::vector<TorqueObservation>& data,
                                      const SynergistOptions& options) {
    if (data.empty()) throw InputError("synergist-aware identifier: no observations");
    const ArmSetup& base = prior.base;
    SynergistProblem p;
    p.base = &base;
    p.biceps = findMuscles(base, options.biceps, "biceps");
    p.synergists = findMuscles(base, options.synergists, "synergists");
    if (!options.includeSynergists) p.leftOut = p.synergists;
    const bool measured = std::isfinite(options.measuredActivation);
    if (measured) {
        checkField("measured voluntary activation", options.measuredActivation, Bound::closed(0, 1));
        checkField("activation sd", options.activationSd, Bound::positive());
    }
    for (int i = 0; i < base.getNumMuscles(); ++i)
        if (base.muscles[i].group == MuscleGroup::Extensor) p.extensors.push_back(i);
    if (std::find(p.biceps.begin(), p.biceps.end(), base.primary) == p.biceps.end())
        throw InputError("synergist-aware identifier: the primary muscle '" + base.muscles[base.primary].params.name +
                         "' is not in the biceps group");

    std::vector<double> angles;
    for (const TorqueObservation& o : data) {
        auto it = std::find(angles.begin(), angles.end(), o.flexionDeg);
        p.angleOf.push_back(int(it - angles.begin()));
        if (it == angles.end()) angles.push_back(o.flexionDeg);
        auto kt = std::find_if(p.kinds.begin(), p.kinds.end(), [&](const SynergistProblem::EffortKind& k) {
            return k.group == o.effort && k.level == o.level;
        });
        p.kindOf.push_back(int(kt - p.kinds.begin()));
        if (kt == p.kinds.end()) p.kinds.push_back({o.effort, o.level});
        p.torque.push_back(o.torque);
    }
    p.geometry = calcMvcGeometry(base, angles);

    BicepsEstimate est;
    est.method = measured ? "synergist-va" : "synergist";
    std::tie(est.noiseLevel, est.noiseDegreesOfFreedom) = estimateNoiseLevel(data);
    if (!std::isfinite(est.noiseLevel)) {
        est.noiseLevel = prior.transducerNoise;
        est.noiseDegreesOfFreedom = 0;
    }
    est.noiseLevel = std::max(est.noiseLevel, 0.002);  // floor: the scatter of few repetitions can be ~0
    for (double t : p.torque) p.sd.push_back(est.noiseLevel * std::max(std::abs(t), 1.0));

    // Prior: every mass scale shares the person-level variance (the extensors' one scale averages
    // their muscle terms); lengths and effort independent.
    using P = SynergistProblem;
    const int n = p.size();
    const double s2 = prior.strengthSubjectSd * prior.strengthSubjectSd;
    const double m2 = prior.strengthMuscleSd * prior.strengthMuscleSd;
    auto uniformSd = [](const UniformRange& r) { return std::max((r.max - r.min) / std::sqrt(12.0), 1e-4); };
    MapProblem map;
    map.priorCovariance.assign(n, std::vector<double>(n, 0.0));
    auto& cov = map.priorCovariance;
    for (int a = P::kExtensorMass; a < n; ++a)
        for (int b = P::kExtensorMass; b < n; ++b) cov[a][b] = s2;
    cov[P::kExtensorMass][P::kExtensorMass] += m2 / double(std::max<std::size_t>(p.extensors.size(), 1));
    for (int a = P::kFirstMass; a < n; ++a) cov[a][a] += m2;
    cov[P::kTendon][P::kTendon] = cov[P::kSynergistTendon][P::kSynergistTendon] = std::pow(prior.tendonLengthSd, 2);
    cov[P::kFascicle][P::kFascicle] = cov[P::kSynergistFascicle][P::kSynergistFascicle] =
        std::pow(prior.fascicleLengthSd, 2);
    cov[P::kActivation][P::kActivation] = std::pow(uniformSd(prior.voluntaryActivation), 2);
    cov[P::kCoContraction][P::kCoContraction] = std::pow(uniformSd(prior.coContraction), 2);
    for (int j = 0; j < n; ++j) cov[j][j] = std::max(cov[j][j], 1e-10);  // a zero spread: the value is known
    map.priorMean.assign(n, 0.0);
    map.priorMean[P::kActivation] = 0.5 * (prior.voluntaryActivation.min + prior.voluntaryActivation.max);
    map.priorMean[P::kCoContraction] = 0.5 * (prior.coContraction.min + prior.coContraction.max);
    const double lnLo = std::log(0.25), lnHi = std::log(4.0), lenLo = std::log(0.6), lenHi = std::log(1.4);
    map.lower.assign(n, lnLo);
    map.upper.assign(n, lnHi);
    for (int j : {P::kTendon, P::kFascicle, P::kSynergistTendon, P::kSynergistFascicle}) {
        map.lower[j] = lenLo;
        map.upper[j] = lenHi;
    }
    // Activations stay 1e-5 inside [0, 1], so the Jacobian's difference probes (relative step 1e-6) do
    // not cross the model's domain; a range of zero width holds the value fixed.
    auto inside = [](double v) { return std::clamp(v, 1e-5, 1 - 1e-5); };
    map.lower[P::kActivation] = inside(prior.voluntaryActivation.min);
    map.upper[P::kActivation] = inside(prior.voluntaryActivation.max);
    map.lower[P::kCoContraction] = inside(prior.coContraction.min);
    map.upper[P::kCoContraction] = inside(prior.coContraction.max);
    for (int j : {P::kActivation, P::kCoContraction}) map.priorMean[j] = std::clamp(map.priorMean[j], map.lower[j], map.upper[j]);
    map.numResiduals = int(p.torque.size()) + (measured ? 1 : 0);
    map.residuals = [&](const double* x, double* r) {
        if (measured) r[p.torque.size()] = (x[P::kActivation] - options.measuredActivation) / options.activationSd;
        return p.calcResiduals(x, r);
    };
    const MapResult m = calcMapEstimate(map);
    const std::vector<double>& x = m.x;
    est.converged = m.converged;
    est.message = m.message;
    if (m.failed) return est;  // no estimate: mass and tendon length stay NaN

    const MuscleParameters& b = base.muscles[base.primary].params;
    const int im = p.findMassIndex(base.primary);
    est.mass = b.mass * std::exp(x[im]);
    est.tendonLength = b.optimalTendonLength * std::exp(x[P::kTendon]);
    est.nuisanceNames = {"voluntary_activation", "co_contraction", "biceps_fascicle_scale", "synergist_tendon_scale",
                         "synergist_fascicle_scale", "extensor_mass_scale"};
    est.nuisance = {x[P::kActivation], x[P::kCoContraction], std::exp(x[P::kFascicle]),
                    std::exp(x[P::kSynergistTendon]), std::exp(x[P::kSynergistFascicle]), std::exp(x[P::kExtensorMass])};
    for (int i = 0; i < base.getNumMuscles(); ++i) {
        const int k = p.findMassIndex(i);
        if (k < 0 || i == base.primary) continue;
        est.nuisanceNames.push_back(base.muscles[i].params.name + "_mass_scale");
        est.nuisance.push_back(std::exp(x[k]));
    }
    try {
        const std::vector<std::vector<double>> t = p.predict(x.data());
        double ss = 0;
        for (std::size_t k = 0; k < p.torque.size(); ++k) ss += std::pow(p.predicted(t, k) - p.torque[k], 2);
        est.rmsResidual = std::sqrt(ss / double(p.torque.size()));
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

std::vector<ElbowValidationRow> runElbowValidation(const Population& population, const ElbowValidationSettings& settings,
                                                   const std::function<void(int, int)>& progress) {
    population.validate();
    settings.protocol.validate();
    checkField("subjects", settings.subjects, Bound::closed(1, 1e6));
    checkField("activation_sd", settings.activationSd, Bound::closed(0, 0.5));
    std::vector<double> levels = settings.noiseLevels;
    if (levels.empty()) levels.push_back(population.transducerNoise);
    for (double v : levels) checkField("noise", v, Bound{0, 0.5, false, true, "relative sd"});
    const int primary = population.base.primary;
    int bicepsShort = -1;  // the other biceps head
    for (int i : findMuscles(population.base, SynergistOptions().biceps, "biceps"))
        if (i != primary) bicepsShort = i;
    const std::vector<int> synergists = findMuscles(population.base, SynergistOptions().synergists, "synergists");

    std::vector<std::vector<ElbowValidationRow>> perSubject(settings.subjects);
    runParallel(settings.subjects, settings.jobs, [&](int s) {
        const VirtualSubject v = drawSubject(population, settings.seed, s);
        const std::vector<TorqueObservation> clean = synthesizeTorqueData(v, settings.protocol, settings.seed, 1);
        for (double level : levels) {
            const std::vector<TorqueObservation> data = setTransducerNoise(clean, level);
            std::vector<BicepsEstimate> estimates = {identifyThesisMethod(population.base, data),
                                                     identifySynergistAware(population, data)};
            if (settings.activationSd > 0) {
                SynergistOptions withVa;
                withVa.activationSd = settings.activationSd;
                withVa.measuredActivation = measureVoluntaryActivation(data, settings.activationSd, settings.seed + 7919u * unsigned(s));
                estimates.push_back(identifySynergistAware(population, data, withVa));
            }
            for (const BicepsEstimate& e : estimates) {
                ElbowValidationRow row;
                row.subject = s;
                row.noise = level;
                row.method = e.method;
                row.trueMass = v.setup.muscles[primary].params.mass;
                row.trueTendonLength = v.setup.muscles[primary].params.optimalTendonLength;
                row.estimate = e;
                row.massError = e.mass / row.trueMass - 1;
                row.tendonError = e.tendonLength - row.trueTendonLength;
                if (std::isfinite(e.massLower))
                    row.massCovered = row.trueMass >= e.massLower && row.trueMass <= e.massUpper;
                if (std::isfinite(e.tendonLower))
                    row.tendonCovered = row.trueTendonLength >= e.tendonLower && row.trueTendonLength <= e.tendonUpper;
                row.voluntaryActivation = v.setup.effort.voluntaryActivation;
                row.coContraction = v.setup.effort.coContraction;
                row.strengthLevel = v.strengthLevel;
                if (bicepsShort >= 0) row.bicepsShortScale = v.massScale[bicepsShort] / v.massScale[primary];
                double syn = 0;
                for (int i : synergists) syn += v.massScale[i];
                row.synergistScale = syn / double(synergists.size()) / v.massScale[primary];
                perSubject[s].push_back(row);
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
        double mb = 0, mm = 0, tb = 0, tm = 0;
        int mc = 0, mn = 0, tc = 0, tn = 0, n = 0;
        for (const ElbowValidationRow& r : rows) {
            if (r.method != s.method || r.noise != s.noise) continue;
            if (r.estimate.converged) ++s.converged;
            if (!std::isfinite(r.massError) || !std::isfinite(r.tendonError)) continue;
            ++n;
            mb += r.massError, mm += r.massError * r.massError;
            tb += r.tendonError, tm += r.tendonError * r.tendonError;
            if (r.massCovered >= 0) ++mn, mc += r.massCovered;
            if (r.tendonCovered >= 0) ++tn, tc += r.tendonCovered;
        }
        if (n > 0) {
            s.massBias = mb / n, s.massRmse = std::sqrt(mm / n);
            s.tendonBias = tb / n, s.tendonRmse = std::sqrt(tm / n);
        }
        if (mn > 0) s.massCoverage = double(mc) / mn;
        if (tn > 0) s.tendonCoverage = double(tc) / tn;
    }
    return out;
}

namespace {

std::string formatCell(double v) { return std::isfinite(v) ? formatNumber(v) : ""; }

}  // namespace

std::string formatElbowValidationCsv(const std::vector<ElbowValidationRow>& rows) {
    std::string out =
        "subject,noise,method,converged,true_mass_kg,mass_kg,mass_lower_kg,mass_upper_kg,mass_error_pct,mass_covered,"
        "true_tendon_length_m,tendon_length_m,tendon_lower_m,tendon_upper_m,tendon_error_mm,tendon_covered,"
        "voluntary_activation,co_contraction,strength_level,biceps_short_scale,synergist_scale,noise_level_used,"
        "rms_residual\n";
    for (const ElbowValidationRow& r : rows) {
        const BicepsEstimate& e = r.estimate;
        const std::vector<double> cells = {r.trueMass, e.mass, e.massLower, e.massUpper, 100 * r.massError};
        out += std::to_string(r.subject) + "," + formatNumber(r.noise) + "," + r.method + "," +
               (e.converged ? "1" : "0");
        for (double v : cells) out += "," + formatCell(v);
        out += "," + (r.massCovered < 0 ? std::string() : std::to_string(r.massCovered));
        for (double v : {r.trueTendonLength, e.tendonLength, e.tendonLower, e.tendonUpper, 1000 * r.tendonError})
            out += "," + formatCell(v);
        out += "," + (r.tendonCovered < 0 ? std::string() : std::to_string(r.tendonCovered));
        for (double v : {r.voluntaryActivation, r.coContraction, r.strengthLevel, r.bicepsShortScale, r.synergistScale,
                         e.noiseLevel, e.rmsResidual})
            out += "," + formatCell(v);
        out += "\n";
    }
    return out;
}

std::string formatElbowValidationSummaryCsv(const std::vector<ElbowValidationSummary>& summaries) {
    std::string out = "method,noise,subjects,converged,mass_bias_pct,mass_rmse_pct,mass_coverage,tendon_bias_mm,"
                      "tendon_rmse_mm,tendon_coverage\n";
    for (const ElbowValidationSummary& s : summaries)
        out += s.method + "," + formatNumber(s.noise) + "," + std::to_string(s.subjects) + "," +
               std::to_string(s.converged) + "," + formatCell(100 * s.massBias) + "," + formatCell(100 * s.massRmse) +
               "," + formatCell(s.massCoverage) + "," + formatCell(1000 * s.tendonBias) + "," +
               formatCell(1000 * s.tendonRmse) + "," + formatCell(s.tendonCoverage) + "\n";
    return out;
}

}  // namespace armsim
