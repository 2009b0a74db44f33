#include "studies/experiment_design.h"
#include "basics/numbers.h"

#include "basics/bound.h"
#include "basics/csv.h"
#include "basics/errors.h"
#include "basics/format.h"
#include "basics/parallel.h"
#include "basics/portable_random.h"

#include <fmt/format.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <memory>

namespace armsim {

namespace {

constexpr double kMassGoal = 0.10;     // the design goal: mass RMSE <= 10 %
constexpr double kTendonGoal = 0.010;  // the design goal: tendon-length RMSE <= 1 cm [m]
constexpr double kMargin = 2e-4;       // prior draws stay this far inside the bounds (ln scales and activations)
constexpr unsigned kMaxRedraws = 100;  // prior draws tried again for one without a steady state
constexpr int kMaxDesignRepetitions = 100;   // of one condition: a torque protocol's bound on repetitions

Eigen::MatrixXd toMatrix(const std::vector<std::vector<double>>& rows) {
    Eigen::MatrixXd m(int(rows.size()), rows.empty() ? 0 : int(rows.front().size()));
    for (int a = 0; a < m.rows(); ++a)
        for (int b = 0; b < m.cols(); ++b) m(a, b) = rows[a][b];
    return m;
}

// Predictions of every row (candidate conditions' tared torques, then channel measurements) and their
// gradients at one prior draw.
struct DrawSensitivity {
    bool ok = false;
    std::vector<double> prediction;  // [row]
    Eigen::MatrixXd jacobian;        // [row][parameter], each row divided by the row's sd (whitened)
    // [row][parameter, then consider parameter]: the free columns jacobian's, the held and consider
    // parameters' secants (SynergistModel::getSecantSteps), whitened alike
    Eigen::MatrixXd considerJacobian;
};

struct Sensitivities {
    std::vector<std::string> names;
    int massIndex = 0, tendonIndex = 0, activationIndex = 0, sizeIndex = 0;
    int numTorqueRows = 0;           // rows 0..numTorqueRows-1 are torques, then channels, then forearm torques
    std::vector<ChannelObservation> channels;
    bool forearm = false;            // a forearm-axis row per condition after the channels
    ChannelNoise noise;
    Eigen::VectorXd flexorMean;    // weights of the mean of the flexors' ln mass scales
    Eigen::VectorXd forceWeights;  // ln F0 = ln sigma + ln M - ln f_b - ln g (+ constants)
    Eigen::MatrixXd priorPrecision;
    double priorMassSd = 0, priorTendonSd = 0, priorFlexorStrengthSd = 0, priorForceSd = 0, baseTendonLength = 0;
    double relativeSd = 0;         // sigma: relative sd of one trial's torque
    double activationSd = 0;
    std::vector<DrawSensitivity> draws;
    std::shared_ptr<const SynergistModel> model;  // for the consider parameters' widening
    bool consideredCriterion = true;               // !DesignSettings::ownModelCriterion
};

}  // namespace

namespace {

// The postures are the model's own one and these: each once (the model's is always a candidate).
void checkPosturesBesideTheModels(const DesignSettings& settings, const ArmParameters& arm) {
    for (double r : settings.postures)
        if (arm.forearmRotation.enabled && r == arm.forearmRotation.postureDeg)
            throw FieldError("postures", "lists " + formatNumber(r) + " deg, the model's own posture, which is always a "
                                         "candidate: expected other postures only");
}

}  // namespace

std::vector<std::vector<double>> drawFromPrior(const SynergistModel& model, unsigned seed, int draws) {
    const int n = model.getNumParameters();
    // Only the free coordinates are drawn (held ones stay at their mean), so the draws do not depend on
    // which held parameters the model carries.
    std::vector<int> free;
    for (int j = 0; j < n; ++j)
        if (model.getLower()[j] + kMargin < model.getUpper()[j] - kMargin) free.push_back(j);
    const Eigen::MatrixXd sigma = toMatrix(model.getPriorCovariance());
    Eigen::MatrixXd freeSigma(free.size(), free.size());
    for (std::size_t a = 0; a < free.size(); ++a)
        for (std::size_t b = 0; b < free.size(); ++b) freeSigma(a, b) = sigma(free[a], free[b]);
    const Eigen::MatrixXd L = Eigen::LLT<Eigen::MatrixXd>(freeSigma).matrixL();
    std::vector<std::vector<double>> out;
    for (int d = 0; d < draws; ++d) {
        checkInterruption();
        // A draw whose person has no steady state in some condition (a fascicle past the nf limit at the
        // longest path) is drawn again, as population draws are (experiments/population.h).
        for (unsigned attempt = 0;; ++attempt) {
            PortableRandom rng = attempt == 0 ? PortableRandom{seed, 0x5EED1u, unsigned(d)}
                                              : PortableRandom{seed, 0x5EED1u, unsigned(d), attempt};
            Eigen::VectorXd z(free.size());
            for (int j = 0; j < z.size(); ++j) z(j) = rng.drawNormal();
            const Eigen::VectorXd v = L * z;
            std::vector<double> x = model.getPriorMean();
            for (std::size_t k = 0; k < free.size(); ++k) {
                const int j = free[k];  // kept inside the bounds by more than the difference step
                x[j] = std::clamp(x[j] + v(k), model.getLower()[j] + kMargin, model.getUpper()[j] - kMargin);
            }
            try {
                model.calcTorques(x.data());
            } catch (const SimulationError&) {
                if (attempt < kMaxRedraws) continue;
                throw SimulationError("prior draw " + std::to_string(d) + ": no person with a steady state in every "
                                      "condition after " + std::to_string(kMaxRedraws + 1) + " draws");
            }
            out.push_back(x);
            break;
        }
    }
    return out;
}

namespace {

// The sd of row r whose prediction is v: torques of either axis as the identifier weights them
// (transducer and trial variation; v the trial's load), channels as their measurement models
// (experiments/channels.h).
double calcRowSd(const Sensitivities& s, int r, double v) {
    v = std::abs(v);
    const int nc = int(s.channels.size());
    if (r < s.numTorqueRows || r >= s.numTorqueRows + nc) return s.relativeSd * std::max(v, 1.0);  // either axis
    const std::string& channel = s.channels[r - s.numTorqueRows].channel;
    if (channel == "fascicle_length") return s.noise.fascicleLength * v;
    if (channel == "volume") return s.noise.volume * v;
    if (channel == "emg") return s.noise.emg * std::max(v, kEmgFloor);
    return s.noise.upperArmLength;
}

// One prior draw x: the predictions of every row, their whitened tangents (through the steady states;
// held parameters zero) and the held and consider parameters' secants (what the truth varies and the
// fit does not). Throws SimulationError where x has no steady state.
DrawSensitivity calcDrawSensitivity(const Sensitivities& s, const std::vector<TorqueCondition>& conditions,
                                    std::vector<double> x) {
    const SynergistModel& model = *s.model;
    const int n = model.getNumParameters(), nt = int(conditions.size()), nch = int(s.channels.size());
    const int rows = nt + nch + (s.forearm ? nt : 0);
    const std::vector<SynergistModel::ConsiderParameter> considered = model.getConsiderParameters();
    const std::vector<double> secant = model.getSecantSteps();
    const int nk = int(considered.size());
    SynergistModel::PredictionCache cache;   // this draw's probes, on this thread
    auto predict = [&](const std::vector<SynergistModel::MuscleDeviation>* deviations = nullptr) {
        std::vector<double> t, f, c;
        model.calcPredictions(x.data(), deviations, t, f, c, &cache);
        t.insert(t.end(), c.begin(), c.end());
        if (s.forearm) t.insert(t.end(), f.begin(), f.end());
        return t;
    };
    DrawSensitivity out;
    std::vector<double> t, f, c, dt, df, dc;
    model.calcPredictionJacobian(x.data(), t, f, c, dt, df, dc, &cache);
    out.prediction = t;
    out.prediction.insert(out.prediction.end(), c.begin(), c.end());
    if (s.forearm) out.prediction.insert(out.prediction.end(), f.begin(), f.end());
    out.jacobian.resize(rows, n);
    for (int r = 0; r < rows; ++r) {
        const double* g = r < nt ? &dt[std::size_t(r) * n] : r < nt + nch ? &dc[std::size_t(r - nt) * n]
                                                                           : &df[std::size_t(r - nt - nch) * n];
        for (int j = 0; j < n; ++j) out.jacobian(r, j) = model.getLower()[j] == model.getUpper()[j] ? 0.0 : g[j];
    }
    // A secant without a steady state leaves the draw without them (its own widths still count).
    out.considerJacobian = Eigen::MatrixXd::Zero(rows, n + nk);
    out.considerJacobian.leftCols(n) = out.jacobian;
    std::vector<SynergistModel::MuscleDeviation> deviations(model.makeMuscles(x.data()).size());
    try {
        for (int j = 0; j < n + nk; ++j) {
            if (!(secant[j] > 0)) continue;
            std::vector<double> up, down;
            if (j < n) {
                const double x0 = x[j];
                x[j] = x0 + secant[j];
                up = predict();
                x[j] = x0 - secant[j];
                down = predict();
                x[j] = x0;
            } else {
                SynergistModel::setDeviation(deviations, considered[j - n], secant[j]);
                up = predict(&deviations);
                SynergistModel::setDeviation(deviations, considered[j - n], -secant[j]);
                down = predict(&deviations);
                SynergistModel::setDeviation(deviations, considered[j - n], 0);
            }
            for (int r = 0; r < rows; ++r) out.considerJacobian(r, j) = (up[r] - down[r]) / (2 * secant[j]);
        }
    } catch (const SimulationError&) {
        out.considerJacobian.resize(0, 0);
    }
    // Transducer rows as the identifier weights them: sd relative to the trial's load (both axes when
    // the forearm axis is read); a rotation effort's flexion axis is not fitted.
    for (int r = 0; r < rows; ++r) {
        const bool axis = r < nt || r >= nt + nch;
        const int k = r < nt ? r : r - nt - nch;
        double v = out.prediction[r];
        if (axis && s.forearm) v = std::hypot(out.prediction[k], out.prediction[nt + nch + k]);
        const double sd = calcRowSd(s, r, v);
        out.jacobian.row(r) /= sd;
        if (out.considerJacobian.size() > 0) out.considerJacobian.row(r) /= sd;
        if (r < nt && isForearmEffort(conditions[k].effort)) {
            out.jacobian.row(r).setZero();
            if (out.considerJacobian.size() > 0) out.considerJacobian.row(r).setZero();
        }
    }
    out.ok = true;
    return out;
}

Sensitivities calcSensitivities(const Population& prior, const std::vector<TorqueCondition>& conditions,
                                const DesignSettings& settings, const std::function<void(int, int)>& progress,
                                const std::vector<ChannelObservation>& channels = {}, const ChannelNoise& noise = {},
                                bool forearm = false) {
    SynergistOptions options;
    options.readsForearmTorque = forearm;
    options.freeSlowFraction = settings.freeSlowFraction;
    options.channels = channels;
    options.emgCrosstalk = noise.emgCrosstalk;
    Sensitivities s;
    s.model = std::make_shared<const SynergistModel>(prior, options, conditions);
    const SynergistModel& model = *s.model;
    const int n = model.getNumParameters();
    s.names = model.getParameterNames();
    s.massIndex = model.getMassIndex();
    s.tendonIndex = SynergistModel::getTendonIndex();
    s.activationIndex = SynergistModel::getActivationIndex();
    s.sizeIndex = SynergistModel::getSizeIndex();
    s.numTorqueRows = int(conditions.size());
    s.channels = channels;
    s.noise = noise;
    s.forearm = forearm;
    const Eigen::MatrixXd sigma = toMatrix(model.getPriorCovariance());
    s.priorPrecision = sigma.inverse();
    s.flexorMean = Eigen::VectorXd::Zero(n);
    const std::vector<int> flexors = model.getFlexorMassIndices();
    for (int j : flexors) s.flexorMean(j) = 1.0 / double(flexors.size());
    s.priorFlexorStrengthSd = std::sqrt(s.flexorMean.dot(sigma * s.flexorMean));
    const std::vector<double> force = model.getLnMaxForceWeights();
    s.forceWeights = Eigen::Map<const Eigen::VectorXd>(force.data(), n);
    s.priorForceSd = std::sqrt(s.forceWeights.dot(sigma * s.forceWeights));
    s.baseTendonLength = prior.base.muscles[prior.base.primary].params.optimalTendonLength;
    s.priorMassSd = std::sqrt(sigma(s.massIndex, s.massIndex));
    s.priorTendonSd = s.baseTendonLength * std::sqrt(sigma(s.tendonIndex, s.tendonIndex) + sigma(s.sizeIndex, s.sizeIndex) +
                                                     2 * sigma(s.tendonIndex, s.sizeIndex));
    s.relativeSd = std::hypot(prior.transducerNoise, prior.trialCv);
    s.activationSd = settings.activationSd;
    s.consideredCriterion = !settings.ownModelCriterion;

    const std::vector<std::vector<double>> xs = drawFromPrior(model, settings.seed, settings.draws);
    s.draws.resize(xs.size());
    runParallel(int(xs.size()), settings.jobs, [&](int d) {
        try {
            s.draws[d] = calcDrawSensitivity(s, conditions, xs[d]);
        } catch (const SimulationError&) {
            s.draws[d].ok = false;  // no steady state for this draw: left out of the averages
        }
    }, progress);
    return s;
}

// Posterior covariance at draw d with `counts[c]` trials of condition c.
Eigen::MatrixXd calcPosterior(const Sensitivities& s, int d, const std::vector<int>& counts) {
    const DrawSensitivity& ds = s.draws[d];
    Eigen::MatrixXd precision = s.priorPrecision;
    for (std::size_t c = 0; c < counts.size(); ++c) {
        if (counts[c] == 0) continue;
        const Eigen::RowVectorXd g = ds.jacobian.row(int(c));  // whitened
        precision += double(counts[c]) * g.transpose() * g;
    }
    if (s.activationSd > 0) precision(s.activationIndex, s.activationIndex) += 1 / (s.activationSd * s.activationSd);
    return precision.inverse();
}

// The error covariance of draw d's fit with what the fit shares or holds and the truth varies
// (SynergistModel::calcConsideredCovariance): empty when a matrix is not positive definite.
std::vector<std::vector<double>> calcConsideredPosterior(const Sensitivities& s, int d, const std::vector<int>& counts) {
    const DrawSensitivity& ds = s.draws[d];
    const int cols = int(ds.considerJacobian.cols());
    if (cols == 0) return {};   // its secants had no steady state
    std::vector<std::vector<double>> J;
    for (std::size_t c = 0; c < counts.size(); ++c) {
        if (counts[c] == 0) continue;
        std::vector<double> row(cols);
        for (int j = 0; j < cols; ++j) row[j] = std::sqrt(double(counts[c])) * ds.considerJacobian(int(c), j);
        J.push_back(std::move(row));
    }
    if (s.activationSd > 0) {
        J.emplace_back(cols, 0.0);
        J.back()[s.activationIndex] = 1 / s.activationSd;
    }
    std::vector<std::vector<double>> C0, C;
    if (!s.model->calcConsideredCovariance(J, C0, C)) return {};
    return C;
}

ProtocolPrediction evaluate(const Sensitivities& s, const std::vector<int>& counts, const std::string& name,
                            bool considered = false) {
    ProtocolPrediction p;
    p.name = name;
    for (int c = 0; c < s.numTorqueRows && c < int(counts.size()); ++c) p.trials += counts[c];
    p.parameterNames = s.names;
    p.priorMassSd = s.priorMassSd;
    p.priorTendonSd = s.priorTendonSd;
    const int n = int(s.names.size());
    p.massCorrelation.assign(n, 0.0);
    p.posteriorSd.assign(n, 0.0);
    const double gT = kTendonGoal / s.baseTendonLength;
    double crit = 0, vm = 0, vt = 0, vf = 0, vF = 0, wm = 0, wt = 0, wF = 0;
    int used = 0, widened = 0;
    for (std::size_t d = 0; d < s.draws.size(); ++d) {
        if (!s.draws[d].ok) continue;
        const Eigen::MatrixXd C = calcPosterior(s, int(d), counts);
        const double cm = C(s.massIndex, s.massIndex);
        const double ct = C(s.tendonIndex, s.tendonIndex) + C(s.sizeIndex, s.sizeIndex) + 2 * C(s.tendonIndex, s.sizeIndex);
        std::vector<std::vector<double>> W;   // with the consider parameters (empty: not computed, or not definite)
        if (considered || s.consideredCriterion) W = calcConsideredPosterior(s, int(d), counts);
        const double wmm = W.empty() ? cm : W[s.massIndex][s.massIndex];
        const double wtt = W.empty() ? ct : W[s.tendonIndex][s.tendonIndex] + W[s.sizeIndex][s.sizeIndex] + 2 * W[s.tendonIndex][s.sizeIndex];
        crit += s.consideredCriterion ? wmm / (kMassGoal * kMassGoal) + wtt / (gT * gT)
                                      : cm / (kMassGoal * kMassGoal) + ct / (gT * gT);
        vm += cm;
        vt += ct;
        vf += s.flexorMean.dot(C * s.flexorMean);
        vF += s.forceWeights.dot(C * s.forceWeights);
        for (int j = 0; j < n; ++j) {
            p.massCorrelation[j] += C(s.massIndex, j) / std::sqrt(cm * C(j, j));
            p.posteriorSd[j] += std::sqrt(C(j, j));
        }
        if (considered && !W.empty()) {
            wm += wmm;
            wt += wtt;
            for (int a = 0; a < n; ++a)
                for (int b = 0; b < n; ++b) wF += s.forceWeights(a) * W[a][b] * s.forceWeights(b);
            ++widened;
        }
        ++used;
    }
    if (widened > 0) {
        p.massSdConsidered = std::sqrt(wm / widened);
        p.tendonSdConsidered = s.baseTendonLength * std::sqrt(wt / widened);
        p.maxForceSdConsidered = std::sqrt(wF / widened);
    }
    if (used == 0) throw SimulationError("experiment design: no prior draw has a steady state at every condition");
    p.drawsUsed = used;
    p.criterion = crit / used;
    p.massSd = std::sqrt(vm / used);
    p.tendonSd = s.baseTendonLength * std::sqrt(vt / used);
    p.flexorStrengthSd = std::sqrt(vf / used);
    p.maxForceSd = std::sqrt(vF / used);
    p.priorMaxForceSd = s.priorForceSd;
    p.priorFlexorStrengthSd = s.priorFlexorStrengthSd;
    for (int j = 0; j < n; ++j) {
        p.massCorrelation[j] /= used;
        p.posteriorSd[j] /= used;
    }
    return p;
}

std::vector<int> countTrials(const std::vector<TorqueCondition>& conditions) {
    std::vector<int> counts;
    for (const TorqueCondition& c : conditions) counts.push_back(c.repetitions);
    return counts;
}

// Every condition the settings allow: flexion (and extension) efforts at each angle and level, then in
// each other posture the maximal ones, then supination and pronation MVCs at each angle in every posture.
std::vector<TorqueCondition> makeCandidates(const DesignSettings& settings) {
    std::vector<TorqueCondition> out;
    std::vector<double> levels = {1.0};
    levels.insert(levels.end(), settings.levels.begin(), settings.levels.end());
    for (Effort effort : {Effort::Flexion, Effort::Extension}) {
        if (effort == Effort::Extension && !settings.extension) continue;
        for (double level : levels)
            for (double q : settings.flexionDeg) out.push_back({q, effort, level, 1});
        for (double r : settings.postures)
            for (double q : settings.flexionDeg) {
                TorqueCondition c{q, effort, 1.0, 1};
                c.rotationDeg = r;
                out.push_back(c);
            }
    }
    if (!settings.postures.empty()) {
        std::vector<double> postures = {kNaN};
        postures.insert(postures.end(), settings.postures.begin(), settings.postures.end());
        for (Effort effort : {Effort::Supination, Effort::Pronation})
            for (double r : postures)
                for (double q : settings.flexionDeg) {
                    TorqueCondition c{q, effort, 1.0, 1};
                    c.rotationDeg = r;
                    out.push_back(c);
                }
    }
    return out;
}

// Whether a condition can carry ultrasound and EMG: flexion or extension in the model's posture.
bool takesChannels(const TorqueCondition& c) { return std::isnan(c.rotationDeg) && !isForearmEffort(c.effort); }

ChannelObservation makeRow(const char* channel, const std::string& muscle, double flexionDeg, Effort effort,
                           double level) {
    ChannelObservation o;
    o.channel = channel;
    o.muscle = muscle;
    o.flexionDeg = flexionDeg;
    o.effort = effort;
    o.level = level;
    o.sd = 1;  // the sd comes from calcRowSd
    return o;
}

// The channel rows a condition can record: its fascicle at rest and at the plateau, then every
// surface_emg muscle's EMG.
std::vector<ChannelObservation> makeConditionRows(const ArmSetup& base, const TorqueCondition& c, bool ultrasound, bool emg) {
    std::vector<ChannelObservation> rows;
    const std::string& primary = base.muscles[base.primary].params.name;
    if (ultrasound) {
        rows.push_back(makeRow("fascicle_length", primary, c.flexionDeg, c.effort, 0));
        rows.push_back(makeRow("fascicle_length", primary, c.flexionDeg, c.effort, c.level));
    }
    if (emg)
        for (int m : base.surfaceEmg) {
            const MuscleGroup g = base.muscles[m].group;
            if (g == MuscleGroup::Flexor || g == MuscleGroup::Extensor)
                rows.push_back(makeRow("emg", base.muscles[m].params.name, c.flexionDeg, c.effort, c.level));
        }
    return rows;
}

}  // namespace

void DesignSettings::validate() const {
    if (flexionDeg.empty()) throw FieldError("angles", "no angles: expected at least one");
    for (double q : flexionDeg) checkField("angles", q, Bound::closed(0, 180, "deg, 0 = extended"));
    checkDegreesNotRadians("angles", flexionDeg);
    for (double l : levels) checkField("levels", l, Bound::open(0, 1, "fraction of maximal"));
    for (double r : postures) checkField("postures", r, Bound::closed(-90, 90, "deg, + = supination"));
    if (!postures.empty()) checkDegreesNotRadians("postures", postures);
    // A candidate given twice would be one condition listed twice in the designed protocol.
    auto once = [](const std::vector<double>& v, const char* field) {
        for (std::size_t i = 0; i < v.size(); ++i)
            for (std::size_t j = 0; j < i; ++j)
                if (v[i] == v[j])
                    throw FieldError(field, "= " + formatNumber(v[i]) + " is listed twice: expected each value once");
    };
    once(flexionDeg, "angles");
    once(levels, "levels");
    once(postures, "postures");
    checkField("repetitions", repetitions, Bound::closed(1, 100));
    // At most 100 trials: every pick may fall on one condition, whose repetitions a torque protocol bounds at 100.
    if (budgetMinutes > 0)   // across channels the budget is lab minutes; trials are not used
        checkField("trials", trials, Bound{double(repetitions), 10000, false, false, "at least one block of repetitions"});
    else
        checkField("trials", trials, Bound{double(repetitions), 100, false, false, "at least one block of repetitions, at most 100"});
    if (budgetMinutes <= 0 && trials % repetitions != 0)   // the design picks whole blocks: the rest would be dropped
        throw FieldError("trials", "= " + std::to_string(trials) + ": expected a multiple of the repetitions " +
                                       std::to_string(repetitions) + " (the design picks blocks of them: " +
                                       std::to_string(trials / repetitions * repetitions) +
                                       ((trials / repetitions + 1) * repetitions <= 100
                                            ? " or " + std::to_string((trials / repetitions + 1) * repetitions) : "") + ")");
    checkField("draws", draws, Bound::closed(1, 100000));
    checkField("activation_sd", activationSd, Bound::closed(0, 0.5));
    checkField("jobs", jobs, Bound::closed(1, 1024));
    checkField("budget", budgetMinutes, Bound::closed(0, 10000, "min"));
    const double block = costs.mvcBlock * double(repetitions) / 3;   // designChannelProtocol's smallest torque pick
    if (budgetMinutes > 0 && budgetMinutes < block)
        throw FieldError("budget", "= " + formatNumber(budgetMinutes) + " min: no MVC block (" + formatNumber(block, 4) +
                                       " min for " + std::to_string(repetitions) + " repetitions) fits: expected at least " +
                                       formatNumber(block, 4) + " min");
}

ProtocolPrediction predictProtocol(const Population& prior, const TorqueProtocol& protocol,
                                   const DesignSettings& settings) {
    protocol.validate();
    settings.validate();
    std::vector<int> counts = countTrials(protocol.conditions);
    std::vector<ChannelObservation> rows;
    for (std::size_t k = 0; k < protocol.volumeScan.size(); ++k) {
        try {
            prior.base.findMuscle(protocol.volumeScan[k]);
        } catch (const InputError& e) {
            throw InputError((protocol.volumeScanWhere.empty() ? protocol.describe() : protocol.volumeScanWhere) + ": " + describeField("measurements.volume_scan[" + std::to_string(k) + "]") + ": " + e.what());
        }
    }
    for (const TorqueCondition& c : protocol.conditions)
        if (c.emg && prior.base.surfaceEmg.empty())
            throw InputError(protocol.describe() + " records emg, but model '" + prior.base.name +
                             "' names no muscles for it: expected a roles: surface_emg list in the model file");
    for (const TorqueCondition& c : protocol.conditions)
        for (const ChannelObservation& o : makeConditionRows(prior.base, c, c.ultrasound, c.emg)) {
            rows.push_back(o);
            counts.push_back(c.repetitions);
        }
    for (const std::string& m : protocol.volumeScan) {
        rows.push_back(makeRow("volume", m, kNaN, Effort::Flexion, 0));
        counts.push_back(1);
    }
    if (protocol.anthropometry) {
        rows.push_back(makeRow("upper_arm_length", "", kNaN, Effort::Flexion, 0));
        counts.push_back(1);
    }
    const bool forearm = protocol.readsForearmTorque();
    if (forearm && !prior.base.arm.forearmRotation.enabled)
        throw InputError(protocol.describe() + " reads the forearm axis, but the prior's model '" +
                         prior.base.name + "' has no forearm rotation");
    if (forearm)
        for (const TorqueCondition& c : protocol.conditions) counts.push_back(c.repetitions);
    const Sensitivities s = calcSensitivities(prior, protocol.conditions, settings, {}, rows, protocol.channelNoise, forearm);
    return evaluate(s, counts, protocol.name, true);
}

double LabCosts::calcMinutes(const TorqueProtocol& p) const {
    double minutes = 0;
    bool emg = false;
    for (const TorqueCondition& c : p.conditions) {
        minutes += mvcBlock * double(c.repetitions) / 3 + (c.ultrasound ? ultrasoundAngle : 0);
        emg = emg || c.emg;
    }
    return minutes + (emg ? emgSetup : 0) + volumeScan * double(p.volumeScan.size()) + (p.anthropometry ? anthropometry : 0);
}

namespace {

// The design's measurement rows beside the candidates' torques (row numbers count from nc, the number
// of candidates): per candidate its fascicle and EMG rows, the volume candidates (the flexors surface
// electrodes reach: superficial, so a panoramic scan reaches them too) and the arm.
struct ChannelRows {
    std::vector<ChannelObservation> rows;
    std::vector<std::vector<int>> ultrasound, emg;          // [candidate] row numbers
    std::vector<std::pair<std::string, int>> volume;        // (muscle, row)
    int arm = 0;
};

ChannelRows makeChannelRows(const ArmSetup& base, const std::vector<TorqueCondition>& candidates) {
    const int nc = int(candidates.size());
    ChannelRows r;
    r.ultrasound.resize(nc);
    r.emg.resize(nc);
    for (int c = 0; c < nc; ++c) {
        if (!takesChannels(candidates[c])) continue;
        for (const ChannelObservation& o : makeConditionRows(base, candidates[c], true, false)) {
            r.ultrasound[c].push_back(nc + int(r.rows.size()));
            r.rows.push_back(o);
        }
        for (const ChannelObservation& o : makeConditionRows(base, candidates[c], false, true)) {
            r.emg[c].push_back(nc + int(r.rows.size()));
            r.rows.push_back(o);
        }
    }
    for (int m : base.surfaceEmg)
        if (base.muscles[m].group == MuscleGroup::Flexor) {
            r.volume.push_back({base.muscles[m].params.name, nc + int(r.rows.size())});
            r.rows.push_back(makeRow("volume", base.muscles[m].params.name, kNaN, Effort::Flexion, 0));
        }
    r.arm = nc + int(r.rows.size());
    r.rows.push_back(makeRow("upper_arm_length", "", kNaN, Effort::Flexion, 0));
    return r;
}

// What the design has chosen: MVC repetitions per candidate, ultrasound per candidate, EMG (every picked
// block), a volume scan per muscle, anthropometry.
struct Choice {
    std::vector<int> torque;
    std::vector<bool> ultrasound;
    bool emg = false, arm = false;
    std::vector<bool> volume;
    // Trials (measurements) of every row: torques, the channel rows, then the forearm axis of the same trials.
    std::vector<int> toCounts(const ChannelRows& r, bool forearm) const {
        const int nc = int(torque.size());
        std::vector<int> counts(nc + r.rows.size() + (forearm ? nc : 0), 0);
        for (int c = 0; c < nc; ++c) {
            counts[c] = torque[c];
            if (forearm) counts[nc + r.rows.size() + c] = torque[c];
            if (ultrasound[c]) for (int k : r.ultrasound[c]) counts[k] = torque[c];
            if (emg) for (int k : r.emg[c]) counts[k] = torque[c];
        }
        for (std::size_t v = 0; v < r.volume.size(); ++v) counts[r.volume[v].second] = volume[v] ? 1 : 0;
        counts[r.arm] = arm ? 1 : 0;
        return counts;
    }
};

// The protocol of a choice: its MVC blocks with their channels, the scans and the noise model.
TorqueProtocol makeDesignedProtocol(const std::vector<TorqueCondition>& candidates, const ChannelRows& r,
                                    const Choice& chosen, bool forearm, const ChannelNoise& noise) {
    TorqueProtocol p;
    p.name = "designed";
    p.conditions.clear();   // not the default protocol's
    for (std::size_t c = 0; c < candidates.size(); ++c)
        if (chosen.torque[c] > 0) {
            TorqueCondition tc = candidates[c];
            tc.repetitions = chosen.torque[c];
            tc.ultrasound = chosen.ultrasound[c];
            tc.emg = chosen.emg && takesChannels(tc);
            p.conditions.push_back(tc);
        }
    p.forearmTorque = forearm;
    for (std::size_t v = 0; v < r.volume.size(); ++v)
        if (chosen.volume[v]) p.volumeScan.push_back(r.volume[v].first);
    p.anthropometry = chosen.arm;
    p.channelNoise = noise;
    return p;
}

std::string describeDesign(const DesignSettings& settings, const TorqueProtocol& p, const ProtocolPrediction& predicted) {
    return fmt::format(
        "designed by armsim design --budget {}: {:.0f} lab minutes ({} trials), {} prior draws (seed {}); predicted "
        "sd of ln M {:.1f} %, of L0T {:.1f} mm with what the fit shares ({:.1f} %, {:.1f} mm for its own model)",
        formatNumber(settings.budgetMinutes), settings.costs.calcMinutes(p), predicted.trials, settings.draws,
        settings.seed, 100 * predicted.massSdConsidered, 1000 * predicted.tendonSdConsidered,
        100 * predicted.massSd, 1000 * predicted.tendonSd);
}

}  // namespace

DesignResult designChannelProtocol(const Population& prior, const DesignSettings& settings,
                                   const TorqueProtocol& reference, const std::function<void(int, int)>& progress) {
    reference.validate();
    settings.validate();
    prior.validate();
    prior.base.requireVirtualMuscles("the design's identifiers (prior population '" + prior.name + "'" +
                                     (prior.file.empty() ? "" : ", " + prior.file) + ")");
    if (!(settings.budgetMinutes > 0)) throw FieldError("budget", "expected > 0 minutes for a design across channels");
    const ArmSetup& base = prior.base;
    const LabCosts& cost = settings.costs;
    DesignResult result;
    result.candidates = makeCandidates(settings);
    const int nc = int(result.candidates.size());
    const bool forearm = !settings.postures.empty();
    if (forearm && !base.arm.forearmRotation.enabled)
        throw InputError("design: postures need a model whose forearm rotates; the prior's model '" + base.name +
                         "' has none");
    checkPosturesBesideTheModels(settings, base.arm);
    const ChannelRows rows = makeChannelRows(base, result.candidates);
    const ChannelNoise noise = reference.channelNoise;
    const int total = 2 * settings.draws + 1;
    Sensitivities s = calcSensitivities(prior, result.candidates, settings, [&](int done, int) {
        if (progress) progress(done, total);
    }, rows.rows, noise, forearm);
    Sensitivities r = calcSensitivities(prior, reference.conditions, settings, [&](int done, int) {
        if (progress) progress(settings.draws + done, total);
    });
    for (std::size_t d = 0; d < s.draws.size(); ++d) s.draws[d].ok = r.draws[d].ok = s.draws[d].ok && r.draws[d].ok;
    result.reference = evaluate(r, countTrials(reference.conditions), reference.name, true);

    // Greedy by criterion drop per minute.
    Choice chosen{std::vector<int>(nc, 0), std::vector<bool>(nc, false), false, false, std::vector<bool>(rows.volume.size(), false)};
    const int reps = settings.repetitions;
    const double block = cost.mvcBlock * double(reps) / 3;
    double spent = 0, current = evaluate(s, chosen.toCounts(rows, forearm), "").criterion;
    for (;;) {
        double bestScore = 0, bestMinutes = 0, bestCriterion = current;
        Choice best;
        std::string bestItem;
        TorqueCondition bestCondition;
        auto consider = [&](const Choice& ch, double minutes, const std::string& item, const TorqueCondition& c) {
            if (spent + minutes > settings.budgetMinutes + 1e-9) return;
            checkInterruption();
            const double v = evaluate(s, ch.toCounts(rows, forearm), "").criterion;
            const double score = (current - v) / minutes;
            if (score > bestScore) bestScore = score, best = ch, bestMinutes = minutes, bestItem = item, bestCriterion = v,
                                   bestCondition = c;
        };
        for (int c = 0; c < nc; ++c) {
            Choice ch = chosen;
            ch.torque[c] += reps;
            if (ch.torque[c] <= kMaxDesignRepetitions) consider(ch, block, "torque", result.candidates[c]);
            if (chosen.torque[c] > 0 && !chosen.ultrasound[c] && takesChannels(result.candidates[c])) {
                ch = chosen;
                ch.ultrasound[c] = true;
                consider(ch, cost.ultrasoundAngle, "ultrasound", result.candidates[c]);
            }
        }
        const TorqueCondition none{kNaN, Effort::Flexion, 0, 0};
        bool emgPossible = false;
        for (int c = 0; c < nc; ++c) emgPossible = emgPossible || (chosen.torque[c] > 0 && takesChannels(result.candidates[c]));
        if (!chosen.emg && emgPossible) {
            Choice ch = chosen;
            ch.emg = true;
            consider(ch, cost.emgSetup, "emg", none);
        }
        for (std::size_t v = 0; v < rows.volume.size(); ++v)
            if (!chosen.volume[v]) {
                Choice ch = chosen;
                ch.volume[v] = true;
                consider(ch, cost.volumeScan, "volume " + rows.volume[v].first, none);
            }
        if (!chosen.arm) {
            Choice ch = chosen;
            ch.arm = true;
            consider(ch, cost.anthropometry, "anthropometry", none);
        }
        if (bestItem.empty()) break;  // nothing fits the budget or helps
        chosen = best;
        spent += bestMinutes;
        current = bestCriterion;
        DesignStep step;
        step.condition = bestCondition;
        step.condition.repetitions = bestItem == "torque" ? reps : 0;
        step.criterion = current;
        step.item = bestItem;
        step.minutes = bestMinutes;
        result.steps.push_back(step);
        if (progress) progress(2 * settings.draws, total);
    }
    if (progress) progress(total, total);
    if (std::none_of(chosen.torque.begin(), chosen.torque.end(), [](int n) { return n > 0; }))
        throw InputError("design --budget " + formatNumber(settings.budgetMinutes) + " min: no MVC block (" +
                         formatNumber(block, 4) + " min) fits: expected a larger budget");
    result.protocol = makeDesignedProtocol(result.candidates, rows, chosen, forearm, noise);
    TorqueProtocol& p = result.protocol;
    result.predicted = evaluate(s, chosen.toCounts(rows, forearm), p.name, true);
    p.description = describeDesign(settings, p, result.predicted);
    return result;
}

DesignResult designProtocol(const Population& prior, const DesignSettings& settings, const TorqueProtocol& reference,
                            const std::function<void(int, int)>& progress) {
    reference.validate();
    settings.validate();
    prior.validate();
    prior.base.requireVirtualMuscles("the design's identifiers (prior population '" + prior.name + "'" +
                                     (prior.file.empty() ? "" : ", " + prior.file) + ")");
    DesignResult result;
    result.candidates = makeCandidates(settings);
    const int picks = settings.trials / settings.repetitions;
    const int total = 2 * settings.draws + picks;
    const bool forearm = !settings.postures.empty();
    if (forearm && !prior.base.arm.forearmRotation.enabled)
        throw InputError("design: postures need a model whose forearm rotates; the prior's model '" + prior.base.name +
                         "' has none");
    checkPosturesBesideTheModels(settings, prior.base.arm);
    Sensitivities s = calcSensitivities(prior, result.candidates, settings, [&](int done, int) {
        if (progress) progress(done, total);
    }, {}, {}, forearm);
    // Rows: every candidate's torque, then (both axes read) its forearm torque.
    auto withForearm = [&](std::vector<int> counts) {
        if (forearm) counts.insert(counts.end(), counts.begin(), counts.end());
        return counts;
    };
    Sensitivities r = calcSensitivities(prior, reference.conditions, settings, [&](int done, int) {
        if (progress) progress(settings.draws + done, total);
    });
    for (std::size_t d = 0; d < s.draws.size(); ++d) s.draws[d].ok = r.draws[d].ok = s.draws[d].ok && r.draws[d].ok;
    result.reference = evaluate(r, countTrials(reference.conditions), reference.name, true);

    std::vector<int> counts(result.candidates.size(), 0);
    double current = INFINITY;
    for (int k = 0; k < picks; ++k) {
        int best = -1;
        double bestCriterion = INFINITY;
        for (std::size_t c = 0; c < counts.size(); ++c) {
            checkInterruption();
            counts[c] += settings.repetitions;
            const double v = evaluate(s, withForearm(counts), "").criterion;
            counts[c] -= settings.repetitions;
            if (v < bestCriterion) bestCriterion = v, best = int(c);
        }
        if (best < 0) throw SimulationError("experiment design: no candidate has a finite criterion");
        // With the widened widths more trials can widen them (the fit then pins what it shares on the
        // data): the design stops below the budget when no block narrows them.
        if (k > 0 && !(bestCriterion < current)) break;
        current = bestCriterion;
        counts[best] += settings.repetitions;
        TorqueCondition picked = result.candidates[best];
        picked.repetitions = settings.repetitions;
        result.steps.push_back({picked, bestCriterion});
        if (progress) progress(2 * settings.draws + k + 1, total);
    }

    TorqueProtocol& p = result.protocol;
    p.name = "designed";
    p.conditions.clear();
    for (std::size_t c = 0; c < counts.size(); ++c)
        if (counts[c] > 0) {
            TorqueCondition tc = result.candidates[c];
            tc.repetitions = counts[c];
            p.conditions.push_back(tc);
        }
    p.forearmTorque = forearm;
    result.predicted = evaluate(s, withForearm(counts), p.name, true);
    p.description = fmt::format(
        "designed by armsim design: {} trials, {} prior draws (seed {}); predicted sd of ln M {:.1f} %, of L0T {:.1f} mm "
        "with what the fit shares ({:.1f} %, {:.1f} mm for its own model)",
        result.predicted.trials, settings.draws, settings.seed, 100 * result.predicted.massSdConsidered,
        1000 * result.predicted.tendonSdConsidered, 100 * result.predicted.massSd, 1000 * result.predicted.tendonSd);
    return result;
}

std::string formatDesignStepsCsv(const DesignResult& result) {
    CsvText csv({"step", "effort", "flexion_deg", "level", "repetitions", "criterion", "item", "minutes", "rotation_deg"});
    for (std::size_t k = 0; k < result.steps.size(); ++k) {
        const DesignStep& s = result.steps[k];
        CsvRow row;
        row.addInteger(long(k) + 1).addText(getEffortName(s.condition.effort)).addNumber(s.condition.flexionDeg);
        row.addNumber(s.condition.level).addInteger(s.condition.repetitions).addNumber(s.criterion);
        row.addText(s.item).addNumber(s.minutes);
        row.addText(std::isnan(s.condition.rotationDeg) ? std::string() : formatNumber(s.condition.rotationDeg));
        csv.addRow(row);
    }
    return csv.getText();
}

std::string formatPredictionsCsv(const std::vector<ProtocolPrediction>& predictions) {
    if (predictions.empty()) return "";
    std::vector<std::string> header = {"protocol", "trials", "draws_used", "criterion", "mass_sd_pct", "tendon_sd_mm",
                                       "flexor_strength_sd_pct", "prior_mass_sd_pct", "prior_tendon_sd_mm",
                                       "prior_flexor_strength_sd_pct", "mass_sd_considered_pct",
                                       "tendon_sd_considered_mm", "max_force_sd_pct", "prior_max_force_sd_pct",
                                       "max_force_sd_considered_pct"};
    for (const std::string& n : predictions.front().parameterNames) header.push_back("corr_lnM_" + n);
    for (const std::string& n : predictions.front().parameterNames) header.push_back("sd_" + n);
    CsvText csv(header);
    for (const ProtocolPrediction& p : predictions) {
        CsvRow row;
        row.addText(p.name).addInteger(p.trials).addInteger(p.drawsUsed).addNumber(p.criterion);
        row.addNumber(100 * p.massSd).addNumber(1000 * p.tendonSd).addNumber(100 * p.flexorStrengthSd);
        row.addNumber(100 * p.priorMassSd).addNumber(1000 * p.priorTendonSd).addNumber(100 * p.priorFlexorStrengthSd);
        row.addNumber(100 * p.massSdConsidered).addNumber(1000 * p.tendonSdConsidered);
        row.addNumber(100 * p.maxForceSd).addNumber(100 * p.priorMaxForceSd).addNumber(100 * p.maxForceSdConsidered);
        for (double v : p.massCorrelation) row.addNumber(v);
        for (double v : p.posteriorSd) row.addNumber(v);
        csv.addRow(row);
    }
    return csv.getText();
}

std::vector<DesignValidationRow> validateDesign(const Population& prior, const DesignSettings& settings,
                                                const TorqueProtocol& reference, const DesignResult& design, int subjects,
                                                const std::function<void(const std::string&, int, int)>& progress) {
    const bool channels = settings.budgetMinutes > 0;
    std::vector<DesignValidationRow> rows;
    for (const auto& [protocol, predicted] :
         {std::pair{reference, design.reference}, std::pair{design.protocol, design.predicted}}) {
        ElbowValidationSettings v;
        v.subjects = subjects;
        v.seed = settings.seed;
        v.jobs = settings.jobs;
        v.activationSd = settings.activationSd;
        v.protocol = protocol;
        v.freeSlowFraction = settings.freeSlowFraction;
        const std::string name = protocol.name;
        const std::vector<ElbowValidationRow> validation = runElbowValidation(prior, v, [&](int done, int n) {
            if (progress) progress(name, done, n);
        });
        for (const ElbowValidationSummary& x : summarizeElbowValidation(validation)) {
            if (x.method == "thesis") continue;   // the prediction is about the synergist-aware fits
            if (channels && name == design.protocol.name && x.method != "channels") continue;
            rows.push_back({name, x, predicted});
        }
    }
    return rows;
}

std::string formatDesignValidationCsv(const std::vector<DesignValidationRow>& rows) {
    CsvText csv({"protocol", "method", "subjects", "converged", "mass_bias_pct", "mass_rmse_pct", "mass_coverage",
                 "mass_interval_width_pct", "tendon_bias_mm", "tendon_rmse_mm", "tendon_coverage",
                 "tendon_interval_width_mm", "predicted_mass_sd_pct", "predicted_tendon_sd_mm"});
    for (const DesignValidationRow& r : rows) {
        const ElbowValidationSummary& x = r.obtained;
        CsvRow row;
        row.addText(r.protocol).addText(x.method).addInteger(x.subjects).addInteger(x.converged);
        row.addNumber(100 * x.massBias).addNumber(100 * x.massRmse).addNumber(x.massCoverage);
        row.addNumber(100 * x.massIntervalWidth).addNumber(1000 * x.tendonBias).addNumber(1000 * x.tendonRmse);
        row.addNumber(x.tendonCoverage).addNumber(1000 * x.tendonIntervalWidth).addNumber(100 * r.predicted.massSd);
        row.addNumber(1000 * r.predicted.tendonSd);
        csv.addRow(row);
    }
    return csv.getText();
}

}  // namespace armsim
