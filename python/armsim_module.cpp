// The Python module armsim._armsim: models, steady states, muscle and arm trials and
// population studies on the C++ libraries, numpy arrays out. SI units and the YAML files' names;
// errors keep the C++ messages (InputError -> ValueError, a missing file -> FileNotFoundError,
// SimulationError -> RuntimeError). Long calls release the GIL.
#include "estimation/ceres_logging.h"
#include "basics/angles.h"
#include "basics/bound.h"
#include "basics/files.h"
#include "studies/study.h"
#include "model/osim_forward.h"
#include "model/osim_trial.h"
#include "model/mvc_curve.h"
#include "model/trial.h"
#include "muscles/simbody_isometric.h"
#include "python/module_support.h"

#include <filesystem>
#include <cmath>

using namespace armsim;
using namespace armsim::python;

namespace {

// A model name (under assets/models/) or an existing model file.
ArmSetup loadModelChecked(const std::string& nameOrFile) {
    const bool looksLikePath = nameOrFile.find('/') != std::string::npos || (nameOrFile.size() > 5 &&
                               nameOrFile.compare(nameOrFile.size() - 5, 5, ".yaml") == 0);
    if (looksLikePath && !isRegularFile(nameOrFile)) throwFileNotFound(nameOrFile, "model file");
    return loadModel(nameOrFile);
}

int findMuscleIndex(const ArmSetup& s, const py::object& muscle) {
    if (muscle.is_none()) return s.primary;
    return s.findMuscle(muscle.cast<std::string>());
}

py::dict toDict(const MuscleParameters& p) {
    py::dict d;
    d["name"] = p.name;
    d["mass"] = p.mass;
    d["optimal_fascicle_length"] = p.optimalFascicleLength;
    d["optimal_tendon_length"] = p.optimalTendonLength;
    d["max_path_length"] = p.maxPathLength;
    d["slow_fraction"] = p.slowFraction;
    d["slow_units"] = p.numSlowUnits;
    d["fast_units"] = p.numFastUnits;
    return d;
}

// Applies keyword overrides with the YAML names (mass, optimal_tendon_length, ...) to muscle i.
void applyOverrides(ArmSetup& s, int i, const py::dict& kw) {
    MuscleParameters& p = s.muscles[i].params;
    for (auto item : kw) {
        const std::string k = item.first.cast<std::string>();
        // A value of the wrong type is a TypeError naming the parameter (not pybind11's cast error).
        auto number = [&]() -> double {
            if (!py::isinstance<py::float_>(item.second) && !py::isinstance<py::int_>(item.second))
                throw py::type_error("muscle parameter '" + k + "' = " + py::repr(item.second).cast<std::string>() +
                                     ": expected a number");
            return item.second.cast<double>();
        };
        auto whole = [&]() -> int {
            if (!py::isinstance<py::int_>(item.second))
                throw py::type_error("muscle parameter '" + k + "' = " + py::repr(item.second).cast<std::string>() +
                                     ": expected a whole number");
            return item.second.cast<int>();
        };
        if (k == "mass") p.mass = number();
        else if (k == "optimal_fascicle_length") p.optimalFascicleLength = number();
        else if (k == "optimal_tendon_length") p.optimalTendonLength = number();
        else if (k == "max_path_length") p.maxPathLength = number(), s.muscles[i].maxPathFromRange = false;
        else if (k == "slow_fraction") p.slowFraction = number();
        else if (k == "slow_units") p.numSlowUnits = whole();
        else if (k == "fast_units") p.numFastUnits = whole();
        else
            throw InputError("unknown muscle parameter '" + k + "': expected mass, optimal_fascicle_length, "
                             "optimal_tendon_length, max_path_length, slow_fraction, slow_units or fast_units");
    }
}

constexpr int kModelPickleFormat = 2;  // 2: with the muscle model (1: without, still read)

// A model loaded from a name or file, remembering which (a path made absolute) for pickling.
Model loadPythonModel(const std::string& nameOrFile) {
    Model m{loadModelChecked(nameOrFile), nameOrFile, {}, {}, {}};
    if (isRegularFile(nameOrFile)) m.source = std::filesystem::absolute(nameOrFile).lexically_normal().string();
    return m;
}

// with_muscle's change, validated (ValueError / TypeError naming the field) and recorded.
void applyChange(Model& m, const py::object& muscle, const py::dict& kw) {
    const int i = findMuscleIndex(m.setup, muscle);
    applyOverrides(m.setup, i, kw);
    m.setup.calcMuscleParameters(i);  // validates: ValueError naming the field
    std::vector<std::pair<std::string, double>> values;
    for (const auto& item : kw) values.push_back({item.first.cast<std::string>(), item.second.cast<double>()});
    m.changes.push_back({m.setup.muscles[i].params.name, values});
}

std::shared_ptr<const MuscleModel> buildMuscle(const Model& m, const py::object& muscle) {
    return m.setup.buildMuscleModel(findMuscleIndex(m.setup, muscle));
}

}  // namespace

PYBIND11_MODULE(_armsim, mod) {
    armsim::quietCeresLogging();  // once, at import: armsim reports what Ceres would log
    mod.doc() = "armsim: a musculoskeletal arm simulator with Virtual Muscle force elements (C++ core).";
    mod.attr("__version__") = ARMSIM_VERSION;   // the CMake project's version

    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const SimulationError& e) {
            PyErr_SetString(PyExc_RuntimeError, e.what());
        }
    });

    py::class_<Model>(mod, "Model",
                      "An arm with its muscles: a model file of assets/models/ ('thesis': the thesis's biceps-only\n"
                      "arm; 'elbow': seven muscles on wrapped paths) or your own. Immutable: with_muscle returns a\n"
                      "changed copy. Pass it to the trial, identification and render functions.")
        .def_static(
            "load",
            [](const py::object& nameOrFile) {   // str or os.PathLike (pathlib.Path)
                return loadPythonModel(py::module_::import("os").attr("fspath")(nameOrFile).cast<std::string>());
            },
            py::arg("name_or_file"),
            "Loads a model: a name under assets/models/ ('thesis', 'elbow', 'twin') or a model file path (str or\n"
            "pathlib.Path).\n"
            "Raises FileNotFoundError for a missing file, ValueError (the CLI's message) for a bad one.")
        .def_property_readonly("name", [](const Model& m) { return m.setup.name; }, "the model's name")
        .def("__copy__", [](const Model& m) { return m; })
        .def("__deepcopy__", [](const Model& m, const py::dict&) { return m; }, py::arg("memo"))
        .def(py::pickle(
            [](const Model& m) {  // what made it: the model read again, the changes applied again
                py::list changes;
                for (const auto& [muscle, values] : m.changes) {
                    py::dict kw;
                    for (const auto& [key, value] : values)  // unit counts stay whole numbers
                        kw[py::str(key)] = key == "slow_units" || key == "fast_units" ? py::object(py::int_(long(value)))
                                                                                       : py::object(py::float_(value));
                    changes.append(py::make_tuple(muscle, kw));
                }
                py::dict coefficients;
                for (const auto& [key, value] : m.muscleModelCoefficients) coefficients[py::str(key)] = value;
                return py::make_tuple(kModelPickleFormat, m.source, changes, m.muscleModel, coefficients);
            },
            [](const py::tuple& state) {
                const int format = state.size() >= 1 ? state[0].cast<int>() : 0;
                if (!((format == 1 && state.size() == 3) || (format == 2 && state.size() == 5)))
                    throw py::value_error("armsim.Model: a pickle of another armsim version (expected format 1 or " +
                                          std::to_string(kModelPickleFormat) + ")");
                Model m = loadPythonModel(state[1].cast<std::string>());
                for (const py::handle change : state[2].cast<py::list>()) {
                    const py::tuple c = change.cast<py::tuple>();
                    applyChange(m, py::cast<py::object>(c[0]), c[1].cast<py::dict>());
                }
                if (format == 2 && !state[3].cast<std::string>().empty()) {
                    m.muscleModel = state[3].cast<std::string>();
                    for (const auto& item : state[4].cast<py::dict>())
                        m.muscleModelCoefficients[py::cast<std::string>(item.first)] = py::cast<double>(item.second);
                    setMuscleModel(m.setup, m.muscleModel, m.muscleModelCoefficients);
                }
                return m;
            }))
        .def_property_readonly(
            "muscles", [](const Model& m) {
                std::vector<std::string> names;
                for (const MuscleSpec& s : m.setup.muscles) names.push_back(s.params.name);
                return names;
            },
            "muscle names in model order")
        .def_property_readonly("primary", [](const Model& m) { return m.setup.muscles[m.setup.primary].params.name; },
                               "the primary muscle (the thesis's biceps)")
        .def(
            "parameters", [](const Model& m, const py::object& muscle) {
                return toDict(m.setup.calcMuscleParameters(findMuscleIndex(m.setup, muscle)));
            },
            py::arg("muscle") = py::none(),
            "A muscle's parameters (default: the primary's) with the muscle files' names and SI units:\n"
            "mass [kg], optimal_fascicle_length, optimal_tendon_length, max_path_length [m], slow_fraction,\n"
            "slow_units, fast_units.")
        .def(
            "with_muscle", [](const Model& m, const py::object& muscle, const py::kwargs& kw) {
                Model c = m;
                applyChange(c, muscle, kw);
                return c;
            },
            py::arg("muscle") = py::none(),
            "A copy with a muscle's parameters changed by keyword (the names of parameters()), e.g.\n"
            "model.with_muscle(mass=0.3, optimal_tendon_length=0.24). Raises ValueError for a bad value.")
        .def(
            "with_muscle_model", [](const Model& m, const std::string& name, const py::kwargs& kw) {
                Model c = m;
                std::map<std::string, double> coefficients;
                for (const auto& item : kw) coefficients[py::cast<std::string>(item.first)] = py::cast<double>(item.second);
                setMuscleModel(c.setup, name, coefficients);
                c.muscleModel = name;
                c.muscleModelCoefficients = coefficients;
                return c;
            },
            py::arg("name"),
            "A copy whose every muscle follows muscle model `name` ('virtual_muscle', 'thelen2003',\n"
            "'degroote2016') with the same geometry and morphometry, e.g.\n"
            "model.with_muscle_model('thelen2003', activation_time_constant=0.01). Coefficients by keyword\n"
            "(assets/muscles/<name>.yaml lists them); raises ValueError for an unknown model, key or value.")
        .def(
            "geometry", [](const Model& m, const std::vector<double>& flexionDeg) {
                const MvcGeometry g = calcMvcGeometry(m.setup, flexionDeg);
                py::dict d;
                d["flexion_deg"] = toArray(g.flexionDeg);
                d["path_length_m"] = toArray(g.pathLength);
                d["moment_arm_m"] = toArray(g.momentArm);
                return d;
            },
            py::arg("flexion_deg"),
            "Muscle path lengths and moment arms (from virtual work; + flexes) at elbow flexion angles [deg,\n"
            "0 = extended]: dict of flexion_deg (n,), path_length_m and moment_arm_m (n, muscles).")
        .def("__repr__", [](const Model& m) {
            return "<armsim.Model '" + m.setup.name + "', " + std::to_string(m.setup.getNumMuscles()) + " muscles>";
        });

    mod.def(
        "steady_state", [](const Model& m, double pathLength, double activation, const py::object& muscle) {
            const auto vm = buildMuscle(m, muscle);
            checkField("activation", activation, Bound::closed(0, 1));
            const SteadyState s = vm->calcSteadyState(pathLength, activation);
            if (!s.converged) throw SimulationError("steady state at path " + formatNumber(pathLength) + " m: " + s.message);
            py::dict d;
            d["force_N"] = s.force;
            d["fascicle_length_m"] = s.fascicleLength;
            d["normalized_fascicle_length"] = s.L;
            return d;
        },
        py::arg("model"), py::arg("path_length"), py::arg("activation") = 1.0, py::arg("muscle") = py::none(),
        "The steady isometric state of one muscle (default the primary) at path length P [m] and activation\n"
        "U in [0, 1]: dict of force_N (Fse = Fce), fascicle_length_m, normalized_fascicle_length.");

    mod.def(
        "muscle_trial",
        [](const Model& m, double pathLength, double activation, double onset, double rise, double duration,
           double rate, bool steadyStart, const py::object& muscle) {
            const auto vm = buildMuscle(m, muscle);
            checkField("activation", activation, Bound::closed(0, 1));
            checkField("onset", onset, Bound::nonNegative("s"));
            checkField("rise", rise, Bound::nonNegative("s"));
            MuscleIsometricSettings s;
            s.pathLength = pathLength;
            s.duration = duration;
            s.sampleRate = rate;
            s.startSteady = steadyStart;
            if (rise > 0) s.activation = ActivationProfile::ramp(onset, onset + rise, 0.0, activation);
            else if (onset > 0) s.activation = ActivationProfile::step(onset, 0.0, activation);
            else s.activation = ActivationProfile::constant(activation);
            Table t;
            runInterruptible([&] {
                t = runMuscleIsometric(*vm, s);
            });
            return toDict(std::move(t));
        },
        py::arg("model"), py::arg("path_length") = 0.375, py::arg("activation") = 1.0, py::arg("onset") = 0.0,
        py::arg("rise") = 0.0, py::arg("duration") = 3.0, py::arg("rate") = 1000.0, py::arg("steady_start") = false,
        py::arg("muscle") = py::none(),
        "An isometric trial of one muscle at a fixed path length (as `armsim muscle trial`): activation 0\n"
        "until onset [s], then a ramp of `rise` [s] (0: a step) to `activation`. Returns a dict of float64\n"
        "arrays: time_s, activation, force_N, fce_N, fascicle_length_m, fascicle_velocity_mps,\n"
        "tendon_length_m, active_fraction, and the states (views of one buffer, strided: np.ascontiguousarray\n"
        "copies one column out). Releases the GIL; Ctrl-C raises KeyboardInterrupt.");

    mod.def(
        "forward",
        [](const py::object& model, const py::object& controls, const py::object& initialStates, double finalTime,
           std::optional<double> initialTime, double rate, const std::string& muscleModel, double accuracy) {
            const OsimModel m = readOsimFile(findOsimModelFile(toPathString(model, "model"), "model"));
            // A storage file's path (str or os.PathLike) or a dict of equal-length columns, time first.
            auto storageOf = [](const py::object& o, const char* what) {
                if (py::isinstance<py::dict>(o)) {
                    OsimStorage s;
                    s.file = what;
                    s.table = toTable(o.cast<py::dict>(), what);
                    return s;
                }
                return readOsimStorage(py::str(py::module_::import("os").attr("fspath")(o)).cast<std::string>());
            };
            const OsimStorage c = storageOf(controls, "controls");
            OsimStorage initial;
            if (!initialStates.is_none()) initial = storageOf(initialStates, "initial_states");
            OsimForwardSettings s;
            s.finalTime = finalTime;
            if (initialTime) s.initialTime = *initialTime;
            s.sampleRate = rate;
            s.muscleModel = muscleModel;
            s.integration.accuracy = accuracy;
            OsimForwardResult r;
            runInterruptible([&] { r = runOsimForward(m, c, initialStates.is_none() ? nullptr : &initial, s); });
            return toDict(std::move(r.states));
        },
        py::arg("model"), py::arg("controls"), py::arg("initial_states") = py::none(), py::arg("final_time") = 1.0,
        py::arg("initial_time") = py::none(), py::arg("rate") = 200.0, py::arg("muscle_model") = "",
        py::arg("accuracy") = 1e-5,
        "Forward dynamics of an OpenSim model, as `armsim forward`: model is an .osim path or a shipped name\n"
        "('arm26'); controls and initial_states are storage-file paths (.sto) or dicts of equal-length arrays\n"
        "(time first, then one excitation per muscle; states by OpenSim's column names). Returns a dict of\n"
        "float64 arrays with OpenSim's column names: time, each coordinate (rad), <coordinate>_u,\n"
        "<muscle>.activation, <muscle>.fiber_length (m). Releases the GIL; Ctrl-C raises KeyboardInterrupt.");

    mod.def(
        "isometric_trial",
        [](const py::object& model, const std::string& coordinate, double angleDeg, const std::string& effort,
           double activation, double antagonist, double rest, double rise, double hold, double rate,
           std::optional<double> window, const std::string& muscleModel, double accuracy) {
            const OsimModel m = readOsimFile(findOsimModelFile(toPathString(model, "model"), "model"));
            OsimIsometricTrialSettings s;
            s.coordinate = coordinate;
            s.angleDeg = angleDeg;
            if (effort != "positive" && effort != "negative")
                throw InputError("effort = '" + effort + "': expected 'positive' or 'negative' (the coordinate's direction)");
            s.direction = effort == "positive" ? 1 : -1;
            s.activation = activation;
            s.antagonistActivation = antagonist;
            s.restDuration = rest;
            s.riseTime = rise;
            s.holdDuration = hold;
            s.sampleRate = rate;
            s.averagingWindow = window ? *window : std::min(s.averagingWindow, s.holdDuration);
            s.muscleModel = muscleModel;
            s.integration.accuracy = accuracy;
            OsimIsometricTrialResult r;
            runInterruptible([&] { r = runOsimIsometricTrial(m, s); });
            const OsimIsometricSummary& x = r.summary;
            py::dict summary;
            summary["coordinate"] = x.coordinate;
            summary["angle_deg"] = x.angleDeg;
            summary["muscles"] = x.muscles;
            summary["agonists"] = x.agonists;
            summary["path_lengths_m"] = x.pathLengths;
            summary["moment_arms_m"] = x.momentArms;
            summary["mean_forces_N"] = x.meanForces;
            summary["rest_torque_Nm"] = x.restTorque;
            summary["mean_muscle_torque_Nm"] = x.meanMuscleTorque;
            summary["mean_tared_torque_Nm"] = x.meanTaredTorque;
            return py::make_tuple(toDict(std::move(r.series)), summary);
        },
        py::arg("model"), py::arg("coordinate") = "", py::arg("angle_deg") = 90.0, py::arg("effort") = "positive",
        py::arg("activation") = 1.0, py::arg("antagonist_activation") = 0.0, py::arg("rest") = 0.5,
        py::arg("rise") = 0.0, py::arg("hold") = 3.0, py::arg("rate") = 1000.0,
        py::arg("averaging_window") = py::none(), py::arg("muscle_model") = "", py::arg("accuracy") = 1e-4,
        "An isometric trial of an OpenSim model, as `armsim trial --model FILE.osim`: model an .osim path or a\n"
        "shipped name ('arm26'); `coordinate` locked at angle_deg (its value in degrees; '' = the model's only\n"
        "moving coordinate), the others at their defaults; after `rest` [s] the muscles that pull it the\n"
        "`effort` way ('positive' or 'negative') rise to `activation` over `rise` [s] and hold for `hold` [s],\n"
        "the others go to antagonist_activation. Returns (series, summary): series a dict of float64 arrays\n"
        "(time_s, excitation, <coordinate>_deg, muscle_torque_Nm, tared_torque_Nm, per muscle force_<m>_N,\n"
        "torque_<m>_Nm, excitation_<m>, activation_<m>, fiber_length_<m>_m); summary: coordinate, angle_deg,\n"
        "muscles, agonists, path_lengths_m, moment_arms_m, mean_forces_N, rest_torque_Nm,\n"
        "mean_muscle_torque_Nm, mean_tared_torque_Nm (means over the last averaging_window [s]; None: 1 s or\n"
        "the whole hold). Releases the GIL; Ctrl-C raises KeyboardInterrupt.");

    mod.def(
        "free_movement",
        [](const py::object& model, const std::string& coordinate, std::optional<double> initialAngleDeg,
           double initialVelocityDegps, const std::string& effort, double activation, double onset, double rise,
           double duration, double rate, const std::string& muscleModel, double accuracy) {
            const OsimModel m = readOsimFile(findOsimModelFile(toPathString(model, "model"), "model"));
            OsimFreeMovementSettings s;
            s.coordinate = coordinate;
            if (initialAngleDeg) s.initialAngleDeg = *initialAngleDeg;
            s.initialVelocityDegps = initialVelocityDegps;
            if (effort != "positive" && effort != "negative")
                throw InputError("effort = '" + effort + "': expected 'positive' or 'negative' (the coordinate's direction)");
            s.direction = effort == "positive" ? 1 : -1;
            s.activation = activation;
            s.onset = onset;
            s.rise = rise;
            s.duration = duration;
            s.sampleRate = rate;
            s.muscleModel = muscleModel;
            s.integration.accuracy = accuracy;
            Table t;
            runInterruptible([&] { t = runOsimFreeMovement(m, s); });
            return toDict(std::move(t));
        },
        py::arg("model"), py::arg("coordinate") = "", py::arg("initial_angle_deg") = py::none(),
        py::arg("initial_velocity_degps") = 0.0, py::arg("effort") = "positive", py::arg("activation") = 1.0,
        py::arg("onset") = 0.2, py::arg("rise") = 0.0, py::arg("duration") = 2.0, py::arg("rate") = 200.0,
        py::arg("muscle_model") = "", py::arg("accuracy") = 1e-5,
        "A free movement of an OpenSim model (what `armsim trial --model FILE.osim --type free` runs, with\n"
        "these defaults: activation 1, 200 Hz): `coordinate`\n"
        "free from initial_angle_deg (None: its default), the other coordinates held at their defaults; the\n"
        "muscles that pull it the `effort` way at the start ('positive' or 'negative') excited to\n"
        "`activation` from `onset` [s] (a ramp over `rise` [s]; 0: a step), from every muscle in equilibrium.\n"
        "OpenSim's ranges are not forces: the coordinate may leave its range. Returns a dict of float64\n"
        "arrays: time_s, excitation, <coordinate>_deg, <coordinate>_speed_degps, per muscle force_<m>_N,\n"
        "activation_<m>, fiber_length_<m>_m. Releases the GIL; Ctrl-C raises KeyboardInterrupt.");

    mod.def(
        "arm_trial",
        [](const Model& m, double angleDeg, double activation, const std::string& effort, double antagonist,
           double rest, double rise, double hold, double rate, std::optional<double> window,
           std::optional<double> rotationDeg) {
            IsometricTrialSettings s;
            s.elbowAngle = degToRad(angleDeg);
            if (rotationDeg) s.forearmRotationDeg = *rotationDeg;
            s.activation = activation;
            s.effort = parseEffortName(effort);
            s.antagonistActivation = antagonist;
            s.restDuration = rest;
            s.riseTime = rise;
            s.holdDuration = hold;
            s.sampleRate = rate;
            s.averagingWindow = window ? *window : std::min(s.averagingWindow, s.holdDuration);   // as a trial file's default
            IsometricTrialResult r;
            runInterruptible([&] {
                r = runIsometricTrial(m.setup, s);
            });
            py::dict summary;
            summary["mean_force_N"] = r.summary.meanForce;
            summary["mean_muscle_torque_Nm"] = r.summary.meanMuscleTorque;
            summary["mean_forearm_torque_Nm"] = r.summary.meanForearmTorque;   // 0 without a forearm rotation
            summary["mean_strap_force_N"] = r.summary.meanStrapForce;
            summary["path_length_m"] = r.summary.pathLength;
            summary["moment_arm_m"] = r.summary.momentArm;
            summary["mean_forces_N"] = r.summary.meanForces;
            summary["saturated"] = r.summary.saturated;
            return py::make_tuple(toDict(std::move(r.series)), summary);
        },
        py::arg("model"), py::arg("angle_deg") = 90.0, py::arg("activation") = 1.0, py::arg("effort") = "flexion",
        py::arg("antagonist_activation") = 0.0, py::arg("rest") = 0.5, py::arg("rise") = 0.0, py::arg("hold") = 3.0,
        py::arg("rate") = 1000.0, py::arg("averaging_window") = py::none(), py::arg("rotation_deg") = py::none(),
        "An isometric arm trial with the elbow locked at angle_deg (included angle, as `armsim trial`) and,\n"
        "on a model whose forearm rotates (the twin), the forearm locked at rotation_deg (+ = supination;\n"
        "None: the model's posture):\n"
        "rest [s] relaxed (the transducer is tared), then the agonists of `effort` ('flexion',\n"
        "'extension', or on a rotating forearm 'supination' or 'pronation') rise to `activation` over `rise`\n"
        "[s] and hold for `hold` [s]; the antagonists go to\n"
        "antagonist_activation. Returns (series, summary): series a dict of float64 arrays (time_s,\n"
        "activation, elbow_angle_deg, muscle_force_N, holding_torque_Nm, muscle_torque_Nm, strap_force_N,\n"
        "per-muscle force_<muscle>_N with several muscles, states); summary the means over the last\n"
        "averaging_window [s] (None: 1 s, or the whole hold when shorter): mean_force_N (primary muscle),\n"
        "mean_muscle_torque_Nm, mean_forearm_torque_Nm, mean_strap_force_N, path_length_m, moment_arm_m,\n"
        "mean_forces_N (per muscle), saturated. Releases the GIL; Ctrl-C raises KeyboardInterrupt.");

    mod.def(
        "run_study",
        [](const std::string& file, int threads, const std::string& out, bool restart) {
            checkField("threads", threads, Bound::closed(0, kMaxStudyThreads, "0: every CPU this process may use"));
            if (!isRegularFile(file)) throwFileNotFound(file, "study file");
            const Study study = readStudy(file);
            StudyRunOptions o;
            o.threads = threads;
            o.output = out;
            o.restart = restart;
            StudyOutcome r;
            runInterruptible([&] {
                r = runStudy(study, o);
            });
            py::dict d;
            d["output"] = r.output;
            d["total"] = r.total;
            d["computed"] = r.computed;
            d["resumed"] = r.resumed;
            d["failed"] = r.failed;
            d["not_converged"] = r.notConverged;
            d["wall_time_s"] = r.wallTime;
            d["journal_dropped"] = r.journalDrops.size();
            d["journal_summary"] = r.journalSummary;
            d["files"] = r.files;
            return d;
        },
        py::arg("study_file"), py::arg("threads") = 0, py::arg("out") = "", py::arg("restart") = false,
        "Runs a population study file (as `armsim study`, on threads: 1 .. 1024, or 0 for every CPU this\n"
        "process may use) and returns what it did: output\n"
        "folder, total, computed, resumed, failed and not_converged task counts, wall_time_s, files,\n"
        "journal_dropped (journal lines the run could not use; their cells were computed again) and\n"
        "journal_summary (what they were; also in the folder's journal_repairs.log).\n"
        "Resumes from the folder's journal like the command. Releases the GIL; Ctrl-C raises KeyboardInterrupt.");

    addIdentificationBindings(mod);
    addSimulationBindings(mod);
}
