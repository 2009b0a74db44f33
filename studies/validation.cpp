#include "studies/validation.h"

#include "basics/bound.h"
#include "basics/csv.h"
#include "basics/portable_random.h"
#include "identification/forward_choice.h"
#include "model/geometry.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

namespace armsim {

namespace {

constexpr double kThesisMass = 0.336, kThesisTendonLength = 0.245;  // thesis Table 7.2 target

constexpr std::pair<ValidationModel, const char*> kModels[] = {
    {ValidationModel::Steady, "steady"}, {ValidationModel::Faithful, "faithful"}, {ValidationModel::Corrected, "corrected"}};

struct Truth {
    std::string name;
    double mass, tendon;
};

}  // namespace

std::string getValidationModelName(ValidationModel m) {
    for (const auto& [id, name] : kModels)
        if (id == m) return name;
    throw std::logic_error("unknown ValidationModel");
}

ValidationModel parseValidationModelName(const std::string& name) {
    for (const auto& [id, n] : kModels)
        if (name == n) return id;
    throw InputError("model '" + name + "': expected steady, faithful or corrected");
}

void ValidationSettings::validate(const ArmParameters& arm) const {
    if (noiseLevels.empty()) throw InputError("noise levels: none given: expected at least one");
    for (double s : noiseLevels) checkField("noise", s, {0, 0.5, false, true, "relative force sd"});
    checkField("seeds", seeds, Bound::closed(0, 1e6));
    checkField("jobs", jobs, Bound::closed(1, 256));
    const double fits = countFits();
    if (fits > kMaxValidationFits)
        throw FieldError("seeds", fmt::format("= {}: {} truths x {} noise levels x {} methods = {:.0f} fits, each a row "
                                              "kept in memory (about {}): expected at most {:.0f} fits",
                                              seeds, seeds + 1, noiseLevels.size(), methods.empty() ? getValidationMethods().size() : methods.size(),
                                              fits, formatBytes(long(2 * fits * sizeof(ValidationRow))), kMaxValidationFits));
    if (anglesDeg.size() < 2) throw InputError("angles: expected at least two for two unknowns");
    for (double a : anglesDeg) checkField("angle", a, Bound::closed(arm.minElbowAngleDeg, arm.maxElbowAngleDeg, "deg"));
    for (Method m : methods)
        if (m == Method::FalsePosition || m == Method::IlcStandard)
            throw InputError("method '" + getMethodName(m) +
                             "': not for validation (it needs one unknown or one observation); expected one of lm, "
                             "ilc-constant, ilc-secant, ilc-bounded-secant, ilc-sign-search");
}

double ValidationSettings::countFits() const {
    const std::size_t m = methods.empty() ? getValidationMethods().size() : methods.size();
    return double(seeds + 1) * double(noiseLevels.size()) * double(m);
}

std::vector<Method> getValidationMethods() {
    return {Method::LevenbergMarquardt, Method::IlcSignSearch, Method::IlcSecant, Method::IlcBoundedSecant,
            Method::IlcConstant};
}

std::vector<ValidationRow> runValidation(const ArmParameters& arm, const MuscleParameters& base,
                                         const ValidationSettings& settings,
                                         const std::function<void(int, int)>& progress) {
    settings.validate(arm);
    const std::vector<Method> methods = settings.methods.empty() ? getValidationMethods() : settings.methods;

    std::vector<Truth> truths = {{"thesis", kThesisMass, kThesisTendonLength}};
    auto rng = PortableRandom::fromSeed(settings.seed);
    for (int s = 0; s < settings.seeds; ++s) {
        const double m = rng.drawUniform(kValidationMassLow, kValidationMassHigh);
        const double t = rng.drawUniform(kValidationTendonLow, kValidationTendonHigh);
        truths.push_back({"random " + std::to_string(s + 1), m, t});
    }

    FaithfulModelOptions referenceOptions;
    referenceOptions.protocol = FaithfulProtocol::makeReference();
    referenceOptions.estimate = settings.estimate;
    referenceOptions.jobs = settings.jobs;
    const FaithfulForceModel reference(arm, referenceOptions);
    FaithfulModelOptions fastOptions = referenceOptions;
    fastOptions.protocol = FaithfulProtocol();
    const FaithfulForceModel fast(arm, fastOptions);
    const SteadyForceModel steady;

    const ObservationSet clean = makeAnglePoints(settings.anglesDeg, makeArmPathFromAngle(arm));

    const int total = int(truths.size() * settings.noiseLevels.size() * methods.size());
    int done = 0;
    std::vector<ValidationRow> rows;
    for (std::size_t i = 0; i < truths.size(); ++i) {
        Truth& truth = truths[i];
        MuscleParameters muscle = base;
        muscle.mass = truth.mass;
        muscle.optimalTendonLength = truth.tendon;
        std::vector<double> y0 = reference.calcForces(muscle, clean.points);
        // A random truth that pulls nothing at some angle (a tendon so long that the fascicle is slack
        // there) cannot be measured with relative noise: it is drawn again from a stream of its own, so
        // the truths that can keep their values.
        for (unsigned attempt = 1; i > 0 && std::any_of(y0.begin(), y0.end(), [](double f) { return !(f > 0); }); ++attempt) {
            if (attempt > 100)
                throw SimulationError("validation: " + truth.name + " pulls nothing at some angle after 100 draws");
            PortableRandom redraw{unsigned(settings.seed), unsigned(i), attempt};
            truth.mass = muscle.mass = redraw.drawUniform(kValidationMassLow, kValidationMassHigh);
            truth.tendon = muscle.optimalTendonLength = redraw.drawUniform(kValidationTendonLow, kValidationTendonHigh);
            y0 = reference.calcForces(muscle, clean.points);
        }
        std::vector<double> eps;
        for (std::size_t k = 0; k < y0.size(); ++k) eps.push_back(rng.drawNormal());
        for (double sd : settings.noiseLevels) {
            IdentificationProblem pr;
            pr.base = base;
            pr.data = clean;
            pr.data.source = fmt::format("synthetic MVC ({} truth, {:.3g} % noise)", truth.name, 100 * sd);
            for (std::size_t k = 0; k < y0.size(); ++k)
                pr.data.points[k].force = std::max(0.0, y0[k] * (1.0 + sd * eps[k]));
            pr.unknowns[0].start = settings.startMass;
            pr.unknowns[1].start = settings.startTendonLength;
            for (Method m : methods) {
                IdentificationOptions o;
                o.method = m;
                o.noise = NoiseModel::Relative;  // transducer noise proportional to the force
                IdentificationReport r;
                switch (settings.model) {
                    case ValidationModel::Steady: r = identify(pr, steady, o); break;
                    case ValidationModel::Faithful: r = identifyWarmStarted(pr, steady, fast, o); break;
                    case ValidationModel::Corrected: r = identifyCorrected(pr, steady, fast, o); break;
                }
                ValidationRow row;
                row.truth = truth.name;
                row.noise = sd;
                row.method = getMethodName(m);
                row.trueMass = truth.mass;
                row.trueTendonLength = truth.tendon;
                row.mass = r.parameters[0].value;
                row.tendonLength = r.parameters[1].value;
                row.massError = row.mass / truth.mass - 1;
                row.tendonLengthError = row.tendonLength / truth.tendon - 1;
                auto covered = [](const ParameterEstimate& e, double t) {
                    return std::isfinite(e.ciLower) ? int(e.ciLower <= t && t <= e.ciUpper) : -1;
                };
                row.massCovered = covered(r.parameters[0], truth.mass);
                row.tendonLengthCovered = covered(r.parameters[1], truth.tendon);
                row.stopReason = getStopReasonName(r.stopReason);
                row.iterations = r.iterations;
                row.evaluations = r.forwardEvaluations;
                row.wallTime = r.wallTime;
                rows.push_back(row);
                if (progress) progress(++done, total);
            }
        }
    }
    return rows;
}

const FieldTable<ValidationRow>& getValidationFields() {
#define ARMSIM_AT(member) [](auto& r) -> auto& { return r.member; }
    using R = ValidationRow;
    static const FieldTable<R> fields({
        textField<R>("truth", ARMSIM_AT(truth)),
        numberField<R>("noise_pct", "%", ARMSIM_AT(noise), 100, 10),
        textField<R>("method", ARMSIM_AT(method)),
        numberField<R>("true_mass_kg", "kg", ARMSIM_AT(trueMass), 1, 10),
        numberField<R>("true_tendon_length_m", "m", ARMSIM_AT(trueTendonLength), 1, 10),
        numberField<R>("mass_kg", "kg", ARMSIM_AT(mass), 1, 10),
        numberField<R>("tendon_length_m", "m", ARMSIM_AT(tendonLength), 1, 10),
        numberField<R>("mass_error_pct", "%", ARMSIM_AT(massError), 100, 10),
        numberField<R>("tendon_length_error_pct", "%", ARMSIM_AT(tendonLengthError), 100, 10),
        flagField<R>("mass_covered", ARMSIM_AT(massCovered)),
        flagField<R>("tendon_length_covered", ARMSIM_AT(tendonLengthCovered)),
        textField<R>("stop_reason", ARMSIM_AT(stopReason)),
        integerField<R>("iterations", "", ARMSIM_AT(iterations)),
        integerField<R>("evaluations", "", ARMSIM_AT(evaluations)),
        numberField<R>("wall_time_s", "s", ARMSIM_AT(wallTime), 1, 4),
    });
#undef ARMSIM_AT
    return fields;
}

std::string formatValidationCsv(const std::vector<ValidationRow>& rows) { return getValidationFields().formatCsv(rows); }

std::string formatValidationTable(const std::vector<ValidationRow>& rows) {
    std::ostringstream s;
    s << fmt::format("{:<9} {:>5} {:<19} {:>8} {:>7} {:>9} {:>9} {:>5} {:<15} {:>5} {:>5} {:>7}\n", "truth", "noise",
                     "method", "M (g)", "L0T(cm)", "dM (%)", "dL0T (%)", "in CI", "stop", "iter", "evals", "time(s)");
    auto cover = [](int m, int t) {
        if (m < 0 || t < 0) return std::string("-");
        return std::string(m ? "y" : "n") + (t ? "y" : "n");
    };
    for (const ValidationRow& r : rows) {
        s << fmt::format("{:<9} {:4.0f}% {:<19} {:8.2f} {:7.3f} {:+9.4f} {:+9.4f} {:>5} {:<15} {:5} {:5} {:7.3f}\n",
                         r.truth, 100 * r.noise, r.method, 1000 * r.mass, 100 * r.tendonLength, 100 * r.massError,
                         100 * r.tendonLengthError, cover(r.massCovered, r.tendonLengthCovered), r.stopReason,
                         r.iterations, r.evaluations, r.wallTime);
    }
    // Coverage per (method, noise) over the truths, where intervals exist.
    std::map<std::pair<std::string, double>, std::pair<int, int>> mass, tendon;
    for (const ValidationRow& r : rows) {
        if (r.massCovered < 0 || r.tendonLengthCovered < 0) continue;
        auto& m = mass[{r.method, r.noise}];
        auto& t = tendon[{r.method, r.noise}];
        m.first += r.massCovered, ++m.second;
        t.first += r.tendonLengthCovered, ++t.second;
    }
    for (const auto& [key, m] : mass) {
        const auto& t = tendon[key];
        s << fmt::format("95 % interval coverage, {} at {:.0f} % noise: mass {}/{}, L0T {}/{}\n", key.first,
                         100 * key.second, m.first, m.second, t.first, t.second);
    }
    return s.str();
}

}  // namespace armsim
