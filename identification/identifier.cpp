#include "identification/identifier.h"

#include "basics/bound.h"
#include "basics/format.h"
#include "identification/solver_context.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

namespace armsim {

namespace {

constexpr std::pair<Method, const char*> kMethods[] = {
    {Method::FalsePosition, "false-position"},    {Method::IlcStandard, "ilc-standard"},
    {Method::IlcConstant, "ilc-constant"},        {Method::IlcSecant, "ilc-secant"},
    {Method::IlcBoundedSecant, "ilc-bounded-secant"}, {Method::IlcSignSearch, "ilc-sign-search"},
    {Method::LevenbergMarquardt, "lm"}};

constexpr std::size_t kCacheSize = 64;

void validateOptions(const IdentificationOptions& o) {
    checkField("options.max_iterations", o.maxIterations, Bound::closed(1, 1e7));
    checkField("options.force_tolerance", o.forceTolerance, Bound::positive("N"));
    checkField("options.lambda", o.lambda, {0, 1, true, false, ""});
    checkField("options.probe_step", o.probeStep, Bound::open(0, 1));
    checkField("options.stall_iterations", o.stallIterations, Bound::closed(1, 1e7));
    if (!std::isnan(o.forceSd)) checkField("options.force_sd", o.forceSd, Bound{0, 1e5, true, false, "N"});
    if (!std::isnan(o.relativeForceSd))   // a relative sd of 1 already spans zero force
        checkField("options.relative_force_sd", o.relativeForceSd, Bound{0, 1, true, false, "fraction of the force"});
    checkField("options.confidence_level", o.confidenceLevel, Bound::open(0, 1));
    checkField("options.starts", o.starts, Bound::closed(1, 1e6));
    if (!std::isnan(o.differenceStep)) checkField("options.difference_step", o.differenceStep, Bound::open(0, 1));
    if (!std::isnan(o.parameterTolerance))
        checkField("options.parameter_tolerance", o.parameterTolerance, Bound::open(0, 1));
}

}  // namespace

std::string getMethodName(Method m) {
    for (const auto& [id, name] : kMethods)
        if (id == m) return name;
    throw std::logic_error("unknown Method");
}

std::vector<std::string> getMethodNames() {
    std::vector<std::string> names;
    for (const auto& entry : kMethods) names.push_back(entry.second);
    return names;
}

Method parseMethodName(const std::string& name) {
    std::string all;
    for (const auto& [id, n] : kMethods) {
        if (name == n) return id;
        all += std::string(all.empty() ? "" : ", ") + n;
    }
    throw InputError("method '" + name + "': expected one of " + all);
}

std::string getDerivativesName(Derivatives d) {
    return d == Derivatives::Central ? "central" : "ceres-numeric";
}

Derivatives parseDerivativesName(const std::string& name) {
    if (name == "central") return Derivatives::Central;
    if (name == "ceres-numeric") return Derivatives::CeresNumeric;
    throw InputError("derivatives '" + name + "': expected central or ceres-numeric");
}

std::string getNoiseModelName(NoiseModel m) { return m == NoiseModel::Absolute ? "absolute" : "relative"; }

NoiseModel parseNoiseModelName(const std::string& name) {
    if (name == "absolute") return NoiseModel::Absolute;
    if (name == "relative") return NoiseModel::Relative;
    throw InputError("noise model '" + name + "': expected absolute or relative");
}

std::string getStopReasonName(StopReason r) {
    switch (r) {
        case StopReason::Converged: return "converged";
        case StopReason::MaxIterations: return "max-iterations";
        case StopReason::NoProgress: return "no-progress";
        case StopReason::NotConverged: return "not-converged";
        case StopReason::BoundHit: return "bound-hit";
    }
    throw std::logic_error("unknown StopReason");
}

std::vector<Unknown> makeUnknowns(const std::vector<std::string>& names) {
    std::vector<Unknown> u;
    for (const std::string& n : names) u.push_back(makeUnknown(parseParameterName(n)));
    return u;
}

namespace detail {

SolverContext::SolverContext(const ParameterMap& m, const ForceModel& f, const std::vector<Observation>& obs,
                             const IdentificationOptions& o)
    : map(m), model(f), observations(obs), options(o) {}

bool SolverContext::calcResiduals(const std::vector<double>& x, std::vector<double>& r) {
    for (const CacheEntry& e : cache_)
        if (e.x == x) {
            r = e.r;
            lastFailure_ = e.failure;
            return e.ok;
        }
    CacheEntry entry;
    entry.x = x;
    ++evaluations_;
    try {
        const std::vector<double> y = model.calcForces(map.toMuscle(x), observations);
        if (y.size() != observations.size())
            throw SimulationError("force model '" + model.getName() + "' returned " +
                                  std::to_string(y.size()) + " forces for " +
                                  std::to_string(observations.size()) + " observations");
        entry.ok = true;
        entry.r.resize(y.size());
        for (std::size_t k = 0; k < y.size(); ++k) {
            entry.r[k] = y[k] - observations[k].force;
            if (!std::isfinite(y[k]) && entry.ok) {
                entry.ok = false;
                entry.failure = "the " + model.getName() + " model has no solution at path " +
                                formatNumber(observations[k].pathLength, 8) + " m, activation " +
                                formatNumber(observations[k].activation, 8) + " for " + describe(x);
            }
        }
    } catch (const InterruptedError&) {
        throw;  // the user stopped the run: not a model failure
    } catch (const InputError&) {
        throw;  // bad input (a protocol beyond the sample limit, an angle the arm cannot take): not a model failure
    } catch (const std::exception& e) {
        entry.ok = false;
        entry.failure = std::string("the ") + model.getName() + " model failed for " + describe(x) + ": " + e.what();
    }
    r = entry.r;
    lastFailure_ = entry.failure;
    const bool ok = entry.ok;
    if (cache_.size() < kCacheSize) {
        cache_.push_back(std::move(entry));
    } else {
        cache_[cacheNext_] = std::move(entry);
        cacheNext_ = (cacheNext_ + 1) % kCacheSize;
    }
    return ok;
}

void SolverContext::record(int iteration, const std::vector<double>& x, const std::vector<double>& r) {
    history_.push_back({iteration, evaluations_, x, r, calcCost(r)});
}

std::vector<IterationRecord> SolverContext::takeHistory() {
    std::vector<IterationRecord> h;
    h.swap(history_);
    return h;
}

std::string SolverContext::describe(const std::vector<double>& x) const {
    std::string s;
    for (int j = 0; j < map.size() && j < int(x.size()); ++j)
        s += (j ? ", " : "") + getParameterName(map.getUnknowns()[j].id) + " = " + formatNumber(x[j], 8) + " " +
             getParameterUnit(map.getUnknowns()[j].id);
    return s;
}

bool SolverContext::isReproduced(const std::vector<double>& r) const {
    if (r.size() != observations.size()) return false;
    for (double v : r)
        if (!(std::abs(v) <= options.forceTolerance)) return false;
    return true;
}

double calcCost(const std::vector<double>& r) {
    double c = 0;
    for (double v : r) c += v * v;
    return 0.5 * c;
}

}  // namespace detail

namespace {

// The data against the unknowns and the method: paths within P_max, positive forces for relative
// noise, enough distinct points, and what each method needs (thesis 4.5.1, 7.1).
void checkProblem(const IdentificationProblem& problem, const ParameterMap& map, const IdentificationOptions& options) {
    const ObservationSet& data = problem.data;
    const int p = map.size(), n = int(data.points.size());
    // P_max: fixed, or an unknown whose lower bound must admit every path.
    double maxPath = 0;
    int maxPathIndex = 0;
    for (int k = 0; k < n; ++k)
        if (data.points[k].pathLength > maxPath) maxPath = data.points[k].pathLength, maxPathIndex = k;
    const auto& unknowns = map.getUnknowns();
    const auto pmax = std::find_if(unknowns.begin(), unknowns.end(),
                                   [](const Unknown& u) { return u.id == ParameterId::MaxPathLength; });
    if (pmax == unknowns.end() && maxPath > problem.base.maxPathLength)
        throw InputError(data.where(maxPathIndex) + ": path " + formatNumber(maxPath, 8) + " m exceeds max_path_length = " +
                         formatNumber(problem.base.maxPathLength, 8) + " m of muscle '" + problem.base.name +
                         "': expected paths no longer than the anatomical limit");
    if (pmax != unknowns.end() && pmax->lower < maxPath)
        throw FieldError("unknowns.max_path_length.lower", "= " + formatNumber(pmax->lower, 8) +
                                                               " m: expected >= the longest path " + formatNumber(maxPath, 8) +
                                                               " m (" + data.where(maxPathIndex) + ")");

    if (options.method == Method::LevenbergMarquardt && options.noise == NoiseModel::Relative)
        for (int k = 0; k < n; ++k)
            if (!(data.points[k].force > 0))
                throw InputError(data.where(k) + ": force_N = " + formatNumber(data.points[k].force, 8) +
                                 ": expected > 0 for the relative noise model (residuals are divided by it)");
    const int distinct = data.countDistinctPoints();
    std::string names;
    for (const std::string& s : map.getNames()) names += (names.empty() ? "" : ", ") + s;
    if (options.method != Method::IlcStandard && distinct < p) {
        std::string lines;
        for (int k = 0; k < n && k < 5; ++k) lines += (k ? ", " : "") + data.where(k);
        if (n > 5) lines += ", ...";
        throw InputError(data.source + ": " + std::to_string(distinct) + " distinct (path, activation) point(s) (" +
                         lines + ") for " +
                         std::to_string(p) + " unknowns (" + names +
                         "): expected at least as many distinct points as unknowns");
    }
    switch (options.method) {
        case Method::FalsePosition:
            if (p != 1 || n != 1)
                throw InputError("false-position: " + std::to_string(p) + " unknowns (" + names + ") and " +
                                 std::to_string(n) + " observations in " + data.source +
                                 ": expected exactly one unknown and one observation (thesis 4.5.1)");
            break;
        case Method::IlcStandard:
            if (n != 1)
                throw InputError("ilc-standard: " + std::to_string(n) + " observations in " + data.source +
                                 ": expected exactly one (thesis 7.1 learns from one output; use a "
                                 "two-output method for more)");
            [[fallthrough]];
        case Method::IlcConstant:
            if (options.method == Method::IlcStandard || options.gainMatrix.empty()) {
                for (const Unknown& u : unknowns)
                    if (std::isnan(u.gain))
                        throw InputError("unknowns." + getParameterName(u.id) + ".gain: not set; " +
                                         getMethodName(options.method) +
                                         " needs a learning gain for every unknown [unit/N]");
            } else {
                bool ok = int(options.gainMatrix.size()) == p;
                for (const auto& row : options.gainMatrix) ok = ok && int(row.size()) == n;
                if (!ok)
                    throw InputError("options.gain_matrix: expected " + std::to_string(p) + " rows (unknowns) of " +
                                     std::to_string(n) + " columns (observations)");
            }
            break;
        default:
            break;
    }

}

// Each unknown's estimate, interval and bound flag; a bound the data push against is the stop reason.
void setParameterEstimates(IdentificationReport& report, const ParameterMap& map, const detail::SolverOutcome& out,
                           const detail::SolverContext& ctx) {
    const auto& unknowns = map.getUnknowns();
    const int p = map.size();
    std::string atBound;
    for (int j = 0; j < p; ++j) {
        const Unknown& u = unknowns[j];
        ParameterEstimate& e = report.parameters.emplace_back();
        e.name = getParameterName(u.id);
        e.unit = getParameterUnit(u.id);
        e.value = out.x[j];
        e.start = u.start;
        e.lower = u.lower;
        e.upper = u.upper;
        const bool low = e.value <= u.lower + u.tolerance, high = e.value >= u.upper - u.tolerance;
        e.atBound = low || high;
        if (report.hasUncertainty) {
            e.standardError = std::sqrt(report.covariance[j][j]);
            e.ciLower = e.value - report.intervalQuantile * e.standardError;
            e.ciUpper = e.value + report.intervalQuantile * e.standardError;
        }
        if (e.atBound)
            atBound += (atBound.empty() ? "" : "; ") + e.name + " = " + formatNumber(e.value, 8) + " " + e.unit + " at its " +
                       (low ? "lower" : "upper") + " bound " + formatNumber(low ? u.lower : u.upper, 8) + " " + e.unit;
    }
    if (!atBound.empty()) {
        if (!ctx.isReproduced(out.r) && report.stopReason != StopReason::NotConverged) {
            report.stopReason = StopReason::BoundHit;
            report.message = atBound + ": the data ask for a value outside the bounds (forces not reproduced, rms " +
                             formatNumber(report.rmsResidual, 8) + " N); " + report.message;
        } else {
            report.message += " (note: " + atBound + ")";
        }
    }
}

}  // namespace

IdentificationReport identify(const IdentificationProblem& problem, const ForceModel& model,
                              const IdentificationOptions& options) {
    const auto t0 = std::chrono::steady_clock::now();
    validateOptions(options);
    const ObservationSet& data = problem.data;
    if (data.points.empty()) throw InputError(data.source + ": no observations");
    validateObservations(data);
    const ParameterMap map(problem.base, problem.unknowns);
    const int n = int(data.points.size());

    checkProblem(problem, map, options);

    detail::SolverContext ctx(map, model, data.points, options);
    IdentificationReport report;
    report.method = getMethodName(options.method);
    report.forceModel = model.getName();
    report.dataSource = data.source;
    report.observations = data.points;

    detail::SolverOutcome out;
    switch (options.method) {
        case Method::FalsePosition: out = detail::solveFalsePosition(ctx); break;
        case Method::LevenbergMarquardt: out = detail::solveLeastSquares(ctx, report); break;
        default: out = detail::solveIlc(ctx); break;
    }

    report.stopReason = out.reason;
    report.message = out.message;
    report.iterations = out.iterations;
    report.muscle = map.toMuscle(out.x);
    report.residuals = out.r;
    report.modelForces.assign(n, std::numeric_limits<double>::quiet_NaN());
    if (int(out.r.size()) == n)
        for (int k = 0; k < n; ++k) report.modelForces[k] = data.points[k].force + out.r[k];
    else
        report.residuals.assign(n, std::numeric_limits<double>::quiet_NaN());
    report.cost = detail::calcCost(report.residuals);
    report.rmsResidual = std::sqrt(2.0 * report.cost / n);

    setParameterEstimates(report, map, out, ctx);
    report.forwardEvaluations = ctx.getEvaluations();
    if (report.history.empty()) report.history = ctx.takeHistory();
    report.wallTime = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return report;
}

IdentificationReport identifyWarmStarted(const IdentificationProblem& problem, const ForceModel& warmModel,
                                         const ForceModel& model, const IdentificationOptions& options) {
    IdentificationOptions warmOptions = options;
    warmOptions.method = Method::LevenbergMarquardt;
    warmOptions.differenceStep = warmOptions.parameterTolerance = std::numeric_limits<double>::quiet_NaN();
    const IdentificationReport warm = identify(problem, warmModel, warmOptions);
    IdentificationProblem second = problem;
    std::string how;
    if (warm.isConverged()) {
        for (std::size_t j = 0; j < second.unknowns.size(); ++j) second.unknowns[j].start = warm.parameters[j].value;
        how = "started from the " + warmModel.getName() + "-model lm estimate (" + std::to_string(warm.iterations) +
              " iterations, " + std::to_string(warm.forwardEvaluations) +
              " evaluations; its time is in the wall time)";
    } else {
        how = "the " + warmModel.getName() + "-model warm start did not converge (" +
              getStopReasonName(warm.stopReason) + "), started from the given starts";
    }
    IdentificationReport report = identify(second, model, options);
    for (std::size_t j = 0; j < report.parameters.size(); ++j) report.parameters[j].start = problem.unknowns[j].start;
    report.message += "; " + how;
    report.wallTime += warm.wallTime;
    return report;
}

void addModelCheck(IdentificationReport& report, const ForceModel& model, const std::string& note) {
    ModelCheck c;
    c.model = model.getName();
    c.note = note;
    const std::size_t n = report.observations.size();
    c.forces.assign(n, std::numeric_limits<double>::quiet_NaN());
    c.residuals = c.forces;
    try {
        const std::vector<double> y = model.calcForces(report.muscle, report.observations);
        if (y.size() != n) throw SimulationError("returned " + std::to_string(y.size()) + " forces for " +
                                                 std::to_string(n) + " observations");
        double ssr = 0;
        for (std::size_t k = 0; k < n; ++k) {
            c.forces[k] = y[k];
            c.residuals[k] = y[k] - report.observations[k].force;
            ssr += c.residuals[k] * c.residuals[k];
        }
        c.rmsResidual = std::sqrt(ssr / double(n));
        if (!std::isfinite(c.rmsResidual)) c.failure = "no solution at some observation (NaN force)";
    } catch (const InterruptedError&) {
        throw;
    } catch (const InputError&) {
        throw;
    } catch (const std::exception& e) {
        c.failure = e.what();
    }
    report.checks.push_back(std::move(c));
}

}  // namespace armsim
