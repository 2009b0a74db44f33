// armsim.identify, identify_torque, validate, validate_elbow, design_protocol and run_protocol: the
// library functions the commands call (identifyAndRecheck, identifyTorqueData, runValidation,
// runElbowValidation, designProtocol, runProtocol), with keyword arguments named as the YAML files
// and the command's options, numpy arrays out. The identification report has the keys of the JSON
// report `armsim identify` writes (report_io.h).
#include "basics/bound.h"
#include "basics/files.h"
#include "experiments/channels.h"
#include "experiments/protocol.h"
#include "experiments/protocol_files.h"
#include "studies/torque_validation.h"
#include "studies/experiment_design.h"
#include "identification/forward_choice.h"
#include "identification/report_io.h"
#include "studies/validation.h"
#include "model/geometry.h"
#include "python/module_support.h"

#include <cmath>
#include <filesystem>
#include <map>
#include <optional>

namespace armsim::python {

namespace {

using python::toDict;

// ---- conversions ---------------------------------------------------------------------------------

bool isNumberArray(const nlohmann::json& j) {
    if (!j.is_array() || j.empty()) return j.is_array();
    for (const auto& x : j)
        if (!x.is_number() && !x.is_null()) return false;
    return true;
}

/// JSON (as report_io.h writes it) to Python: arrays of numbers become float64 arrays, null (written
/// for a non-finite number) NaN.
py::object toPython(const nlohmann::json& j) {
    switch (j.type()) {
    case nlohmann::json::value_t::null: return py::float_(NAN);
    case nlohmann::json::value_t::boolean: return py::bool_(j.get<bool>());
    case nlohmann::json::value_t::number_integer:
    case nlohmann::json::value_t::number_unsigned: return py::int_(j.get<long long>());
    case nlohmann::json::value_t::number_float: return py::float_(j.get<double>());
    case nlohmann::json::value_t::string: return py::str(j.get<std::string>());
    case nlohmann::json::value_t::array: {
        if (isNumberArray(j)) {
            std::vector<double> v;
            for (const auto& x : j) v.push_back(x.is_null() ? NAN : x.get<double>());
            return toArray(v);
        }
        py::list l;
        for (const auto& x : j) l.append(toPython(x));
        return std::move(l);
    }
    case nlohmann::json::value_t::object: {
        py::dict d;
        for (auto it = j.begin(); it != j.end(); ++it) d[py::str(it.key())] = toPython(it.value());
        return std::move(d);
    }
    default: return py::none();
    }
}

/// An array of flat objects (the report's observations) as a dict of float64 arrays.
py::dict toColumns(const nlohmann::json& rows) {
    py::dict d;
    if (rows.empty()) return d;
    for (auto it = rows[0].begin(); it != rows[0].end(); ++it) {
        std::vector<double> v;
        for (const auto& r : rows) v.push_back(r[it.key()].is_null() ? NAN : r[it.key()].get<double>());
        d[py::str(it.key())] = toArray(v);
    }
    return d;
}

py::dict toPython(const IdentificationReport& r) {
    const nlohmann::json j = toJson(r);
    py::dict d = toPython(j).cast<py::dict>();
    d["observations"] = toColumns(j["observations"]);
    py::dict estimate;
    for (const ParameterEstimate& e : r.parameters) estimate[py::str(e.name)] = e.value;
    d["estimate"] = estimate;
    py::dict u = d["uncertainty"].cast<py::dict>();
    u["covariance"] = toArray(r.covariance);
    u["correlation"] = toArray(r.correlation);
    d["history"] = toDict(makeHistoryTable(r));
    return d;
}

bool isPath(const py::object& o) {
    return py::isinstance<py::str>(o) || py::hasattr(o, "__fspath__");
}

/// A str or os.PathLike argument as a path; InputError naming the argument otherwise.
std::string pathOf(const py::object& o, const char* argument) {
    if (!isPath(o))
        throw InputError(std::string(argument) + ": expected a file path (str or os.PathLike), got " +
                         py::str(py::type::of(o).attr("__name__")).cast<std::string>());
    return py::str(py::module_::import("os").attr("fspath")(o));
}

/// A mapping of columns (a dict, or anything with keys()) as a dict; nullopt for something else.
std::optional<py::dict> asColumns(const py::object& o) {
    if (py::isinstance<py::dict>(o)) return o.cast<py::dict>();
    if (py::hasattr(o, "keys") && py::hasattr(o, "__getitem__")) return py::dict(o);
    return std::nullopt;
}

/// Identification data: a CSV path (as `armsim identify DATA.csv`) or a dict of columns with the
/// file's names (force_N and one of path_m, path_cm, angle_deg; optional activation, trial, subject).
ObservationSet toObservations(const py::object& data, const ArmSetup& setup, int subject) {
    if (isPath(data)) return readArmObservations(findFile(pathOf(data, "data")), setup.arm, subject);
    const std::optional<py::dict> columns = asColumns(data);
    if (!columns)
        throw InputError("data: expected a CSV path or a dict of columns (force_N and one of path_m, path_cm, angle_deg)");
    ObservationOptions oo;
    oo.pathFromAngle = makeArmPathFromAngle(setup.arm);
    oo.subject = subject;
    return makeObservations(toTable(*columns, "data"), "data", oo);
}

std::vector<TorqueObservation> toTorqueData(const py::object& data) {
    if (isPath(data)) return readTorqueData(findFile(pathOf(data, "data")));
    const std::optional<py::dict> columns = asColumns(data);
    if (!columns)
        throw InputError("data: expected a torque CSV path or a dict of columns (flexion_deg, torque_Nm, and "
                         "optionally effort, level, repetition, rotation_deg)");
    return makeTorqueData(toTable(*columns, "data"), "data");
}

/// Torque data as columns with the torque data file's names (formatTorqueData with the truth).
py::dict toDict(const std::vector<TorqueObservation>& data) {
    std::vector<double> deg, effort, level, rep, torque, activation, clean, rotation, forearm, cleanForearm;
    for (const TorqueObservation& o : data) {
        deg.push_back(o.flexionDeg);
        rotation.push_back(o.rotationDeg);
        forearm.push_back(o.forearmTorque);
        cleanForearm.push_back(o.cleanForearmTorque);
        effort.push_back(getEffortCode(o.effort));
        level.push_back(o.level);
        rep.push_back(o.repetition);
        torque.push_back(o.torque);
        activation.push_back(o.activation);
        clean.push_back(o.cleanTorque);
    }
    py::dict d;
    d["flexion_deg"] = toArray(deg);
    d["effort"] = toArray(effort);
    d["level"] = toArray(level);
    d["repetition"] = toArray(rep);
    d["torque_Nm"] = toArray(torque);
    d["rotation_deg"] = toArray(rotation);   // NaN: the model's forearm posture
    d["forearm_torque_Nm"] = toArray(forearm);   // NaN: the forearm axis not read
    d["activation"] = toArray(activation);
    d["clean_torque_Nm"] = toArray(clean);
    d["clean_forearm_torque_Nm"] = toArray(cleanForearm);
    return d;
}

/// Channel data as columns with channel_data.csv's names (formatChannelData with the truth).
py::dict toDict(const std::vector<ChannelObservation>& data) {
    py::list channel, muscle, unit;
    std::vector<double> flexion, effort, level, repetition, value, sd, clean;
    for (const ChannelObservation& o : data) {
        channel.append(o.channel);
        muscle.append(o.muscle);
        flexion.push_back(o.flexionDeg);
        effort.push_back(o.effort == Effort::Flexion ? 1 : -1);
        level.push_back(o.level);
        repetition.push_back(o.repetition);
        value.push_back(o.value);
        sd.push_back(o.sd);
        clean.push_back(o.cleanValue);
        unit.append(o.channel == "volume" ? "m^3" : o.channel == "emg" ? "1" : "m");
    }
    py::dict d;
    d["channel"] = channel;
    d["muscle"] = muscle;
    d["flexion_deg"] = toArray(flexion);
    d["effort"] = toArray(effort);
    d["level"] = toArray(level);
    d["repetition"] = toArray(repetition);
    d["value"] = toArray(value);
    d["sd"] = toArray(sd);
    d["clean_value"] = toArray(clean);
    d["unit"] = unit;   // of value, sd and clean_value: each channel has its own
    return d;
}

py::dict toDict(const MuscleEstimate& e) {
    py::dict d;
    d["method"] = e.method;
    d["converged"] = e.converged;
    d["message"] = e.message;
    d["mass_kg"] = e.mass;
    d["tendon_length_m"] = e.tendonLength;
    d["mass_interval_kg"] = py::make_tuple(e.massLower, e.massUpper);
    d["tendon_interval_m"] = py::make_tuple(e.tendonLower, e.tendonUpper);
    d["noise_level"] = e.noiseLevel;
    d["noise_degrees_of_freedom"] = e.noiseDegreesOfFreedom;
    py::dict nuisance;
    for (std::size_t k = 0; k < e.nuisanceNames.size() && k < e.nuisance.size(); ++k)
        nuisance[py::str(e.nuisanceNames[k])] = e.nuisance[k];
    d["nuisance"] = nuisance;
    d["mass_tendon_correlation"] = e.massTendonCorrelation;
    d[e.method == "thesis" ? "rms_residual_N" : "rms_residual_Nm"] = e.rmsResidual;   // thesis: of the force
    d["predicted_torque_Nm"] = toArray(e.predictedTorque);
    d["parameters"] = e.numParameters;
    d["iterations"] = e.iterations;
    d["max_force_N"] = e.maxForce;
    d["max_force_interval_N"] = py::make_tuple(e.maxForceLower, e.maxForceUpper);
    d["specific_tension_N_per_m2"] = e.specificTension;
    py::list fits;
    for (const ChannelFit& f : e.channelFits) {
        py::dict c;
        c["channel"] = f.channel;
        c["n"] = f.n;
        c["chi_square"] = f.chiSquare;
        c["p_value"] = f.p;
        c["consistent_with_noise"] = f.p >= 0.05;
        c["worst"] = f.worst;
        c["worst_residual_sd"] = f.worstResidual;
        fits.append(c);
    }
    d["channel_fits"] = fits;
    return d;
}

Population toPopulation(const py::object& population) {
    if (population.is_none()) return loadDefaultPopulation();
    return loadPopulation(findFile(pathOf(population, "population")));
}

/// An optional number: NaN when not given; a given NaN or infinity is an error naming the argument.
double optionalNumber(const std::optional<double>& v, const char* argument) {
    if (!v) return NAN;
    if (!std::isfinite(*v)) throw InputError(std::string(argument) + " = " + formatNumber(*v) + ": expected a finite number or None");
    return *v;
}


py::dict toDict(const TorqueCondition& c) {
    py::dict d;
    d["flexion_deg"] = c.flexionDeg;
    d["effort"] = getEffortName(c.effort);
    d["level"] = c.level;
    d["repetitions"] = c.repetitions;
    d["rotation_deg"] = c.rotationDeg;   // NaN: the model's forearm posture
    return d;
}

py::dict toDict(const ProtocolPrediction& p) {
    py::dict d;
    d["name"] = p.name;
    d["trials"] = p.trials;
    d["draws_used"] = p.drawsUsed;
    d["criterion"] = p.criterion;
    d["mass_sd"] = p.massSd;
    d["tendon_sd_m"] = p.tendonSd;
    d["flexor_strength_sd"] = p.flexorStrengthSd;
    d["prior_mass_sd"] = p.priorMassSd;
    d["prior_tendon_sd_m"] = p.priorTendonSd;
    d["prior_flexor_strength_sd"] = p.priorFlexorStrengthSd;
    d["mass_sd_considered"] = p.massSdConsidered;     // with what the fit shares (the intervals' widening)
    d["tendon_sd_considered_m"] = p.tendonSdConsidered;
    d["max_force_sd"] = p.maxForceSd;                 // of ln F0
    d["prior_max_force_sd"] = p.priorMaxForceSd;
    d["max_force_sd_considered"] = p.maxForceSdConsidered;
    d["parameter_names"] = p.parameterNames;
    d["mass_correlation"] = toArray(p.massCorrelation);
    d["posterior_sd"] = toArray(p.posteriorSd);
    return d;
}

// A force's quadratic fit against x: the elbow angle [deg] (overAngle) or the path length [m].
py::dict toDict(const QuadraticFit& q, bool overAngle) {
    py::dict d;
    d["coefficients"] = toArray(q.fit.coefficients);
    d["r_squared"] = q.fit.rSquared;
    d["rms_residual_N"] = q.fit.rmsResidual;
    d["has_maximum"] = q.hasMaximum;
    d[overAngle ? "peak_angle_deg" : "peak_path_length_m"] = q.peakX;
    d["peak_force_N"] = q.peakY;
    return d;
}

// ---- the functions -------------------------------------------------------------------------------

py::dict identifyPy(const Model& m, const py::object& data, const std::string& method, const std::vector<std::string>& free,
                    const std::optional<std::map<std::string, std::pair<double, double>>>& bounds,
                    const std::optional<std::map<std::string, double>>& start, const std::string& forward,
                    const std::string& estimate, double hold, double rate, bool warmStart, int jobs,
                    const std::optional<double>& forceSd, const std::string& noise, int multistart, unsigned seed,
                    int maxIterations, double tolerance, int subject, const py::object& out) {
    IdentificationProblem pr;
    m.setup.requireVirtualMuscles("identify's force models", m.setup.primary);
    pr.base = m.setup.calcBicepsParameters();
    pr.data = toObservations(data, m.setup, subject);
    pr.unknowns.clear();
    for (const std::string& name : free) pr.unknowns.push_back(makeUnknown(parseParameterName(name)));
    if (pr.unknowns.empty()) throw InputError("free: expected at least one parameter");
    auto findUnknown = [&](const std::string& what, const std::string& name) -> Unknown& {
        const ParameterId id = parseParameterName(name);
        for (Unknown& u : pr.unknowns)
            if (u.id == id) return u;
        throw InputError(what + " '" + name + "': not a free parameter (free: " + py::str(py::cast(free)).cast<std::string>() + ")");
    };
    if (bounds)
        for (const auto& [name, lohi] : *bounds) {
            Unknown& u = findUnknown("bounds", name);
            u.lower = lohi.first;
            u.upper = lohi.second;
        }
    if (start)
        for (const auto& [name, value] : *start) findUnknown("start", name).start = value;

    IdentificationOptions io;
    io.method = parseMethodName(method);
    io.noise = parseNoiseModelName(noise);
    const double sd = optionalNumber(forceSd, "force_sd");
    if (io.noise == NoiseModel::Relative) io.relativeForceSd = sd;
    else io.forceSd = sd;
    io.starts = multistart;
    io.seed = seed;
    io.maxIterations = maxIterations;
    io.forceTolerance = tolerance;

    ForwardModelChoice choice;
    choice.model = forward;
    choice.estimate = parseForceEstimateName(estimate);
    choice.holdDuration = hold;
    choice.sampleRate = rate;
    choice.warmStart = warmStart;
    choice.jobs = jobs;
    IdentificationReport r;
    runInterruptible([&] {
        r = identifyAndRecheck(pr, io, m.setup.arm, choice);
    });
    py::dict d = toPython(r);
    if (!out.is_none()) {
        const std::string dir = pathOf(out, "out");
        createFolder(dir);
        d["files"] = writeReportFiles(r, dir);
    }
    return d;
}

py::list identifyTorquePy(const py::object& data, const py::object& population, const std::optional<double>& noiseLevel,
                          const std::optional<double>& activation, double activationSd, const py::object& channels,
                          double emgCrosstalk, bool freeSlowFraction) {
    const std::vector<TorqueObservation> obs = toTorqueData(data);
    const Population prior = toPopulation(population);
    TorqueIdentificationOptions o;
    o.noiseLevel = optionalNumber(noiseLevel, "noise_level");
    o.activation = optionalNumber(activation, "activation");
    o.activationSd = activationSd;
    o.emgCrosstalk = emgCrosstalk;
    o.freeSlowFraction = freeSlowFraction;
    if (!channels.is_none()) o.channels = readChannelData(findFile(pathOf(channels, "channels")));
    std::vector<MuscleEstimate> estimates;
    std::string skipped;
    runInterruptible([&] {
        estimates = identifyTorqueData(prior, obs, o, &skipped);
    });
    if (!skipped.empty() && PyErr_WarnEx(PyExc_UserWarning, skipped.c_str(), 1) != 0) throw py::error_already_set();
    const double noise = findJudgingNoiseLevel(o, estimates);
    py::list l;
    for (const MuscleEstimate& e : estimates) {
        py::dict d = toDict(e);
        const TorqueResidualCheck c = checkTorqueResiduals(obs, e, noise);
        py::dict check;
        check["noise_level"] = noise;
        check["rms_Nm"] = c.rms;
        check["chi_square"] = c.chiSquare;
        check["degrees_of_freedom"] = c.dof;
        check["p_value"] = c.p;
        if (c.n > 0) check["consistent_with_noise"] = c.p >= 0.05;
        else check["consistent_with_noise"] = py::none();   // no prediction: the fit failed
        d["residual_check"] = check;
        l.append(d);
    }
    return l;
}

py::dict validatePy(const Model& m, int seeds, unsigned seed, const std::vector<double>& noise,
                    const std::vector<std::string>& methods, const std::string& forward, const std::string& estimate,
                    int jobs) {
    ValidationSettings s;
    s.seeds = seeds;
    s.seed = seed;
    s.noiseLevels = noise;
    for (const std::string& name : methods) s.methods.push_back(parseMethodName(name));
    s.model = parseValidationModelName(forward);
    s.estimate = parseForceEstimateName(estimate);
    s.jobs = jobs;
    s.validate(m.setup.arm);
    m.setup.requireVirtualMuscles("validate's force models", m.setup.primary);
    std::vector<ValidationRow> rows;
    runInterruptible([&] {
        rows = runValidation(m.setup.arm, m.setup.calcBicepsParameters(), s);
    });
    return toFieldColumns(getValidationFields(), rows);
}

py::tuple validateElbowPy(const py::object& population, int subjects, unsigned seed,
                          const std::optional<std::vector<double>>& noise, double activationSd,
                          const std::optional<std::vector<double>>& angles, const std::optional<int>& repetitions,
                          const py::object& protocol,
                          bool freeSlowFraction, int jobs, const py::object& truthPopulation, const py::object& prior) {
    const Population family = toPopulation(population);
    const Population pop = truthPopulation.is_none() ? family : toPopulation(truthPopulation);
    const Population priorPop = prior.is_none() ? family : toPopulation(prior);
    ElbowValidationSettings s;
    s.subjects = subjects;
    s.seed = seed;
    s.noiseLevels = noise.value_or(std::vector<double>{});
    s.activationSd = activationSd;
    s.freeSlowFraction = freeSlowFraction;
    s.jobs = jobs;
    checkField("subjects", subjects, Bound::closed(1, 1e6));
    checkField("activation_sd", activationSd, Bound::closed(0, 0.5));
    checkField("jobs", jobs, Bound::closed(1, 64));
    if (!protocol.is_none()) {
        if (angles || repetitions) throw InputError("protocol replaces angles and repetitions: give one or the other");
        s.protocol = readTorqueProtocol(findFile(pathOf(protocol, "protocol")));
    } else {
        checkField("repetitions", repetitions.value_or(3), Bound::closed(1, 100));
        s.protocol.conditions =
            TorqueProtocol::makeFlexionMvcs(angles.value_or(getThesisMvcFlexionDeg()), repetitions.value_or(3));
        s.protocol.validate();
    }
    std::vector<ElbowValidationRow> rows;
    runInterruptible([&] {
        rows = runElbowValidation(pop, priorPop, s);
    });
    py::list summary;
    for (const ElbowValidationSummary& x : summarizeElbowValidation(rows))
        summary.append(toFieldDict(getElbowValidationSummaryFields(), x));
    return py::make_tuple(toFieldColumns(getElbowValidationFields(), rows), summary);
}

py::dict designPy(const py::object& population, const std::vector<double>& angles,
                  const std::optional<std::vector<double>>& levels,
                  bool extension, std::optional<int> trials, int repetitions, int draws, unsigned seed, double activationSd,
                  bool freeSlowFraction, int jobs, const std::optional<std::vector<double>>& postures,
                  const std::string& criterion, double budgetMinutes) {
    const Population pop = toPopulation(population);
    DesignSettings s;
    s.flexionDeg = angles;
    s.levels = levels.value_or(std::vector<double>{});
    s.postures = postures.value_or(std::vector<double>{});
    if (criterion != "considered" && criterion != "own")
        throw InputError("criterion '" + criterion + "': expected 'considered' or 'own'");
    s.ownModelCriterion = criterion == "own";
    s.budgetMinutes = budgetMinutes;
    s.extension = extension;
    s.trials = trials ? *trials : getDefaultDesignTrials(repetitions);
    s.repetitions = repetitions;
    s.draws = draws;
    s.seed = seed;
    s.activationSd = activationSd;
    s.freeSlowFraction = freeSlowFraction;
    s.jobs = jobs;
    s.validate();
    TorqueProtocol thesis;
    thesis.name = "thesis";
    DesignResult r;
    runInterruptible([&] {
        r = s.budgetMinutes > 0 ? designChannelProtocol(pop, s, thesis) : designProtocol(pop, s, thesis);
    });
    py::dict d;
    py::list conditions, steps;
    for (const TorqueCondition& c : r.protocol.conditions) conditions.append(toDict(c));
    for (const DesignStep& st : r.steps) {
        py::dict x = toDict(st.condition);
        x["criterion"] = st.criterion;
        steps.append(x);
    }
    d["conditions"] = conditions;
    d["protocol_yaml"] = formatTorqueProtocol(r.protocol);
    d["predicted"] = toDict(r.predicted);
    d["reference"] = toDict(r.reference);
    d["steps"] = steps;
    return d;
}

py::dict runProtocolPy(const py::object& file, const py::object& outArgument, int jobs) {
    const std::string path = findFile(pathOf(file, "file"));
    const std::string out = outArgument.is_none() ? std::string() : pathOf(outArgument, "out");
    checkField("jobs", jobs, Bound::closed(1, 64));
    ProtocolFileOptions options;
    options.outDir = out;
    options.write = !out.empty();
    options.jobs = jobs;
    ProtocolFileRun run;
    runInterruptible([&] { run = runProtocolFile(path, options); });
    py::dict d;
    d["name"] = run.name;
    d["kind"] = run.kind;
    if (run.torqueRun) {
        d["subject"] = run.torqueRun->subject;
        d["data"] = toDict(run.torqueRun->data);
        d["channels"] = toDict(run.torqueRun->channels);
        d["files"] = run.files;
        return d;
    }
    const Protocol& protocol = *run.armProtocol;
    ProtocolResult& r = *run.armResult;
    d["trials"] = toDict(std::move(r.trials));
    d["trial_ids"] = r.trialIds;
    d["summary"] = toDict(std::move(r.summary));
    py::dict fits;
    for (const auto& [key, q] : r.quadraticFits)   // mvc: over the angle; force_length: over the path
        fits[py::str(key)] = toDict(q, protocol.kind == ProtocolKind::Mvc);
    d["fits"] = fits;
    if (r.emgToActivation) {
        py::dict e;
        e["coefficients"] = toArray(r.emgToActivation->coefficients);
        e["r_squared"] = r.emgToActivation->rSquared;
        d["emg_to_activation"] = e;
    } else {
        d["emg_to_activation"] = py::none();
    }
    d["muscle_sweep"] = toDict(std::move(r.muscleSweep));
    d["composition"] = toDict(std::move(r.composition));
    d["files"] = r.files;
    return d;
}

}  // namespace

void addIdentificationBindings(py::module_& mod) {
    using namespace pybind11::literals;
    mod.def("identify", &identifyPy, "model"_a, "data"_a, "method"_a = "lm",
            "free"_a = std::vector<std::string>{"mass", "optimal_tendon_length"}, "bounds"_a = py::none(),
            "start"_a = py::none(), "forward"_a = "steady", "estimate"_a = "moment-arm", "hold"_a = 3.0,
            "rate"_a = 200.0, "warm_start"_a = true, "jobs"_a = 2, "force_sd"_a = py::none(), "noise"_a = "absolute",
            "multistart"_a = 1, "seed"_a = 1u, "max_iterations"_a = 200, "tolerance"_a = 0.1, "subject"_a = -1,
            "out"_a = py::none(),
            R"(Identifies the primary muscle's parameters from isometric forces, as `armsim identify`.

data: a CSV path, or a dict of columns with the file's names: force_N [N] and one of path_m,
  path_cm, angle_deg (included elbow angle, 180 = extended, converted with the model's geometry);
  optional activation (default 1), trial, subject (keep one with subject=).
method: lm | false-position | ilc-standard | ilc-constant | ilc-secant | ilc-bounded-secant |
  ilc-sign-search.  free: unknowns (mass, optimal_tendon_length, optimal_fascicle_length,
  slow_fraction, max_path_length).  bounds: {name: (lower, upper)}, start: {name: value}, SI units.
forward: steady | faithful (Simbody arm trials in the loop, at hold [s] and rate [Hz]; warm-started
  from the steady estimate unless warm_start=False) | corrected (steady iterations corrected by the
  faithful model).  estimate: the force the simulated experimenter reports: moment-arm |
  fixed-ratio | true.  lm only: force_sd (known sd: N, or a fraction with noise='relative'),
  noise (absolute | relative), multistart and seed.  out: also write the report files there.

Returns the report as a dict with the keys of the command's JSON report (method, stop_reason,
converged, message, parameters with intervals, uncertainty with covariance and correlation arrays,
model_checks: the estimate re-checked by the steady model and the faithful model at 1000 Hz), plus
estimate {name: value}, observations and history as dicts of float64 arrays. Releases the GIL; Ctrl-C raises KeyboardInterrupt.)");

    mod.def("identify_torque", &identifyTorquePy, "data"_a, "population"_a = py::none(), "noise_level"_a = py::none(),
            "activation"_a = py::none(), "activation_sd"_a = 0.02, "channels"_a = py::none(), "emg_crosstalk"_a = 0.10,
            "free_slow_fraction"_a = false,
            R"(Identifies the biceps long head's mass and tendon length from tared elbow torque data with
every elbow method, as `armsim identify-torque`: 'thesis' (flexion MVCs at >= 2 angles),
'synergist' (MAP over the whole elbow, the population as prior), given a measured voluntary
activation 'synergist-va', and given channel data (`channels`: a channel CSV path, docs/channels.md:
ultrasound fascicle length and volume, EMG, upper-arm length) 'channels', which also reports
max_force_N (F0) with its interval, the specific_tension_N_per_m2 the mass assumes and channel_fits (a
chi-square check per channel naming its worst measurement).

data: a torque CSV path or a dict of columns (flexion_deg [deg, 0 = extended], torque_Nm, optional
effort 1/-1, level, repetition; e.g. run_protocol(...)['data']).  population: prior population file
(default assets/subjects/default_population.yaml).  noise_level: relative sd of one trial's torque
(default: estimated from the repetitions).  Returns one dict per method: mass_kg, tendon_length_m,
95 % mass_interval_kg and tendon_interval_m, nuisance estimates, rms_residual_Nm (thesis: rms_residual_N,
of the force), predicted_torque_Nm, and residual_check (rms_Nm, chi-square against the noise level). A method that cannot run on these data (the
thesis method without flexion MVCs at two angles) is left out with a UserWarning saying why.
Releases the GIL; Ctrl-C raises KeyboardInterrupt.)");

    mod.def(
        "read_torque_data", [](const py::object& path) { return toDict(readTorqueData(findFile(pathOf(path, "path")))); },
        "path"_a,
        R"(Reads a torque data file (a path or a name under assets/) with the strict reader the command
uses: columns flexion_deg [deg, 0 = extended], torque_Nm (tared, + = flexion) and optionally effort
(1 flexion, -1 extension), level (fraction of MVC), repetition. Returns a dict of float64 arrays
with the columns of run_protocol's torque data (activation and clean_torque_Nm, the truth of
synthetic data, are NaN: the reader ignores them): pass it to identify_torque. ValueError names the file, line, column and value.)");

    mod.def("validate", &validatePy, "model"_a, "seeds"_a = 1, "seed"_a = 1u,
            "noise"_a = std::vector<double>{0, 0.01, 0.02, 0.05}, "methods"_a = std::vector<std::string>{},
            "forward"_a = "corrected", "estimate"_a = "moment-arm", "jobs"_a = 2,
            R"(The identifiers against ground truth on synthetic MVC data of the model's biceps (as
`armsim validate --truth thesis`): the thesis's truth and `seeds` random ones, each at every noise
level (relative force sd, a fraction: 0.02 = 2 %), identified by every method (default lm and the
two-output learning family) with the `forward` model (corrected | faithful | steady).
Returns the rows as columns: truth, noise, method, true_mass_kg, true_tendon_length_m, mass_kg,
tendon_length_m, mass_error and tendon_length_error (relative; tendon_length_error was named
tendon_length_error_m before 2026-11-27, a fraction all along), mass_covered, tendon_length_covered (1/0, -1
without an interval), stop_reason, iterations, evaluations, wall_time_s: validation.csv's columns
(studies/validation.h) in SI units.)");

    mod.def("validate_elbow", &validateElbowPy, "population"_a = py::none(), "subjects"_a = 200, "seed"_a = 1u,
            "noise"_a = py::none(), "activation_sd"_a = 0.02, "angles"_a = py::none(), "repetitions"_a = py::none(),
            "protocol"_a = py::none(), "free_slow_fraction"_a = false, "jobs"_a = 2,
            "truth_population"_a = py::none(), "prior"_a = py::none(),
            R"(Validation on multi-muscle virtual subjects (default: the anatomical twin; as `armsim validate --truth elbow`):
`subjects` people drawn from the population (default assets/subjects/default_population.yaml),
or out of family from `truth_population` with `prior` as the identifiers' prior (each defaults to
`population`; as --truth-population and --prior),
MVC torque data synthesized per noise level (fractions; default the population's), identified by
the thesis, synergist and (activation_sd > 0) synergist-va methods. The protocol: flexion MVCs at
`angles` [deg flexion, default 135, 120, 90, 60, 30] x repetitions, or a torque protocol file.
Returns (rows, summary): rows as columns (subject, noise, method, true_mass_kg, true_tendon_length_m,
mass_kg, tendon_length_m, mass_lower_kg, mass_upper_kg, tendon_lower_m, tendon_upper_m, converged,
mass_error (relative), tendon_error_m, mass_covered, tendon_covered, and the nuisance truths
voluntary_activation, co_contraction, strength_level, biceps_short_scale, synergist_scale); summary
one dict per method and noise (mass_bias, mass_rmse relative; tendon_bias_m, tendon_rmse_m;
coverages; mass_interval_width relative, tendon_interval_width_m). Releases the GIL; Ctrl-C raises KeyboardInterrupt.)");

    mod.def("design_protocol", &designPy, "population"_a = py::none(),
            "angles"_a = std::vector<double>{15, 30, 45, 60, 75, 90, 105, 120, 135}, "levels"_a = py::none(),
            "extension"_a = true, "trials"_a = py::none(), "repetitions"_a = 3, "draws"_a = 32, "seed"_a = 1u,
            "activation_sd"_a = 0.02, "free_slow_fraction"_a = false, "jobs"_a = 2, "postures"_a = py::none(),
            "criterion"_a = "considered", "budget_minutes"_a = 0.0,
            R"(The torque protocol that minimises the synergist-aware identifier's expected uncertainty of
the biceps mass and tendon length over the population (as `armsim design`): greedy picks of blocks
of `repetitions` trials among flexion MVCs at `angles` [deg], extension MVCs (extension=True) and
submaximal `levels` (fractions of MVC), within `trials` (a multiple of repetitions; None: the most whole
blocks within 15); with `postures` [deg, + = supination] also
flexion, extension, supination and pronation MVCs in those forearm postures (both transducer axes
read). criterion: 'considered' (the widths the identifier's intervals report, with what its fit
shares) or 'own' (the fit's own Laplace widths). budget_minutes > 0: design across channels within
that many lab minutes (as `armsim design --budget`; trials ignored). Returns conditions, protocol_yaml (a torque
protocol file's text: write it and pass it to run_protocol or validate_elbow), predicted and
reference (the thesis's five angles) uncertainty, and the greedy steps. Releases the GIL; Ctrl-C raises KeyboardInterrupt.)");

    mod.def("run_protocol", &runProtocolPy, "file"_a, "out"_a = py::none(), "jobs"_a = 2,
            R"(Runs an experiment protocol file (a path or a name under assets/, e.g.
'protocols/mvc_force_angle.yaml'), as `armsim protocol`. out: the run directory to write (arm
protocols: written whole and replacing an earlier run; torque protocols: torque_data.csv,
protocol.yaml and torque_angle.png written into it); None computes only.
Arm protocols (mvc, submaximal, force_length, composition) return trials and summary (dicts of
float64 arrays: per trial and per condition), fits (quadratic fits of a force: mvc over the angle, with
peak_angle_deg; force_length over the path, with peak_path_length_m; peak_force_N), emg_to_activation,
muscle_sweep, composition, files. Torque protocols (kind: torque) return data: the tared torque per
trial with the torque data file's columns, ready for identify_torque. Releases the GIL; Ctrl-C raises KeyboardInterrupt.)");
}

}  // namespace armsim::python
