// armsim.Simulation: a model's arm advanced on request (model/simulation.h), with per-muscle excitations
// given as numbers, arrays over time, a callable of time or a controls file, and the state read and
// written between calls.
#include "basics/files.h"
#include "basics/format.h"
#include "basics/storage_file.h"
#include "model/simulation.h"
#include "python/module_support.h"

#include <cmath>
#include <map>
#include <memory>
#include <optional>

using namespace armsim;
using namespace armsim::python;

namespace {

struct PySimulation {
    Model model;
    std::unique_ptr<ArmSimulation> sim;
    py::object callable;   ///< an excitation given as a callable of time (None otherwise)
    bool busy = false;     ///< advance_to runs (without the GIL): other calls on this object are refused
};

// A Simulation is one object stepped by one thread at a time: while advance_to runs (the GIL released),
// another thread's call on it would race with the integration.
void requireIdle(const PySimulation& ps) {
    if (ps.busy) throw std::runtime_error("armsim.Simulation: advance_to is running in another thread; one "
                                          "Simulation is stepped by one thread at a time");
}

// 1-D float64 values, contiguous (a column of a result dict is a strided view).
std::vector<double> toVector(const py::handle& v, const std::string& what) {
    const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(v);
    if (!a) throw InputError(what + ": expected numbers");
    if (a.ndim() != 1) throw InputError(what + ": expected a 1-D array, got " + std::to_string(a.ndim()) + " dimensions");
    return std::vector<double>(a.data(), a.data() + a.size());
}

std::vector<std::string> muscleNames(const ArmSetup& setup) {
    std::vector<std::string> names;
    for (const MuscleSpec& m : setup.muscles) names.push_back(m.params.name);
    return names;
}

int findMuscleOrThrow(const ArmSetup& setup, const std::string& name, const std::string& where) {
    for (int i = 0; i < setup.getNumMuscles(); ++i)
        if (setup.muscles[i].params.name == name) return i;
    std::string list;
    for (const std::string& n : muscleNames(setup)) list += (list.empty() ? "" : ", ") + n;
    throw InputError(where + ": '" + name + "' is not a muscle of model '" + setup.name + "' (muscles: " + list + ")");
}

double toNumber(const py::handle& v, const std::string& what) {
    if (py::isinstance<py::bool_>(v) || !(py::isinstance<py::float_>(v) || py::isinstance<py::int_>(v) ||
                                          py::hasattr(v, "__float__")))
        throw py::type_error(what + " = " + py::repr(v).cast<std::string>() + ": expected a number");
    return v.cast<double>();
}

// A number, a sequence of one number per muscle, or a dict {muscle: number}: constant values per muscle.
std::vector<double> toValues(const ArmSetup& setup, const py::handle& v, const std::string& what) {
    const int n = setup.getNumMuscles();
    if (py::isinstance<py::dict>(v)) {
        std::vector<double> values(n, 0.0);
        for (const auto& item : v.cast<py::dict>()) {
            const std::string name = py::str(item.first).cast<std::string>();
            values[findMuscleOrThrow(setup, name, what)] = toNumber(item.second, what + "['" + name + "']");
        }
        return values;
    }
    if (py::isinstance<py::str>(v)) throw py::type_error(what + " = " + py::repr(v).cast<std::string>() + ": expected a number, one per muscle or a dict");
    if (py::isinstance<py::array>(v) && py::reinterpret_borrow<py::array>(v).ndim() == 0)
        return std::vector<double>(n, toNumber(py::module_::import("builtins").attr("float")(v), what));
    if (py::isinstance<py::array>(v) || (py::hasattr(v, "__len__") && !py::hasattr(v, "__float__"))) {
        const py::sequence s = py::reinterpret_borrow<py::sequence>(py::module_::import("builtins").attr("list")(v));
        if (int(s.size()) != n)
            throw InputError(what + ": " + std::to_string(s.size()) + " values for a model with " + std::to_string(n) +
                             " muscles: expected one per muscle (" + py::str(py::cast(muscleNames(setup))).cast<std::string>() + ")");
        std::vector<double> values;
        for (int i = 0; i < n; ++i) values.push_back(toNumber(s[i], what + "[" + std::to_string(i) + "]"));
        return values;
    }
    return std::vector<double>(n, toNumber(v, what));
}

std::vector<ActivationProfile> constantProfiles(const ArmSetup& setup, const std::vector<double>& values,
                                                const std::string& what) {
    std::vector<ActivationProfile> p;
    for (int i = 0; i < setup.getNumMuscles(); ++i)
        p.emplace_back(std::vector<double>{0.0}, std::vector<double>{values[i]},
                       what + " of " + setup.muscles[i].params.name);
    return p;
}

// A controls file: .sto/.mot (OpenSim: a time column, then muscles by name or /forceset/<muscle>) or .csv
// (time_s, then muscles by name, or one `activation` column for every muscle). Muscles without a column: 0.
std::vector<ActivationProfile> readControls(const ArmSetup& setup, const std::string& path) {
    if (!isRegularFile(path)) throwFileNotFound(path, "excitation file");
    const bool csv = path.size() > 4 && path.compare(path.size() - 4, 4, ".csv") == 0;
    const Table t = csv ? Table::readCsv(path) : readStorage(path);
    const std::string timeName = csv ? "time_s" : "time";
    if (!t.hasColumn(timeName))
        throw InputError(path + ": no '" + timeName + "' column (expected " + timeName + ", then one column per muscle)");
    const std::vector<double> time = t.getColumn(timeName);
    const int n = setup.getNumMuscles();
    std::vector<ActivationProfile> p(n, ActivationProfile::constant(0.0));
    for (const std::string& c : t.getColumnNames()) {
        if (c == timeName) continue;
        if (csv && c == "activation") {
            for (int i = 0; i < n; ++i) p[i] = ActivationProfile(time, t.getColumn(c), path + " column activation");
            continue;
        }
        const std::string name = c.rfind("/forceset/", 0) == 0 ? c.substr(10) : c;
        const int i = findMuscleOrThrow(setup, name, path + " column " + c);
        p[i] = ActivationProfile(time, t.getColumn(c), path + " column " + c);
    }
    return p;
}

// dict with a time_s key: {time_s: (T,), muscle: (T,) ...}, linear between the rows.
std::vector<ActivationProfile> readTraces(const ArmSetup& setup, const py::dict& d) {
    auto column = [&](const py::handle& v, const std::string& what) { return toVector(v, what); };
    const std::vector<double> time = column(d["time_s"], "excitation['time_s']");
    std::vector<ActivationProfile> p(setup.getNumMuscles(), ActivationProfile::constant(0.0));
    for (const auto& item : d) {
        const std::string name = py::str(item.first).cast<std::string>();
        if (name == "time_s") continue;
        const std::string what = "excitation['" + name + "']";
        const int i = findMuscleOrThrow(setup, name, "excitation");
        const std::vector<double> v = column(item.second, what);
        if (v.size() != time.size())
            throw InputError(what + ": " + std::to_string(v.size()) + " values against " + std::to_string(time.size()) +
                             " times in excitation['time_s']: expected one per time");
        p[i] = ActivationProfile(time, v, what);
    }
    return p;
}

// What a user may pass as excitation; a callable is kept in ps.callable and sampled per advance_to.
// The profiles an excitation gives (a callable: its value at 0, and *callable receives it; None otherwise).
// Nothing of `ps` changes here: a refused excitation leaves the simulation as it was.
std::vector<ActivationProfile> toProfiles(const ArmSetup& setup, const py::object& e, py::object* callable) {
    *callable = py::none();
    if (e.is_none()) return constantProfiles(setup, std::vector<double>(setup.getNumMuscles(), 0.0), "excitation");
    if (PyCallable_Check(e.ptr()) && !py::isinstance<py::type>(e)) {
        // Its value at 0, checked now; each advance_to replaces it with the callable sampled over the step.
        std::vector<ActivationProfile> start = constantProfiles(setup, toValues(setup, e(0.0), "excitation(0)"), "excitation");
        *callable = e;
        return start;
    }
    if (py::isinstance<py::str>(e) || py::hasattr(e, "__fspath__"))
        return readControls(setup, py::str(py::module_::import("os").attr("fspath")(e)).cast<std::string>());
    if (py::isinstance<py::dict>(e) && e.cast<py::dict>().contains("time_s")) return readTraces(setup, e.cast<py::dict>());
    return constantProfiles(setup, toValues(setup, e, "excitation"), "excitation");
}

// The callable at t0, t0 + 1/rate, ..., t1 (both ends), linear between.
std::vector<ActivationProfile> sampleCallable(const PySimulation& ps, double t0, double t1) {
    const ArmSetup& setup = ps.model.setup;
    const double rate = ps.sim->getSettings().sampleRate;
    const long steps = std::max(1L, long(std::ceil((t1 - t0) * rate - 1e-9)));   // checkAdvance bounded it
    std::vector<double> times;
    std::vector<std::vector<double>> values(setup.getNumMuscles());
    for (long k = 0; k <= steps; ++k) {
        const double t = k == steps ? t1 : t0 + double(k) / rate;
        const std::string what = "excitation(" + formatNumber(t) + ")";
        const std::vector<double> v = toValues(setup, ps.callable(t), what);
        times.push_back(t);
        for (std::size_t i = 0; i < v.size(); ++i) values[i].push_back(v[i]);
    }
    std::vector<ActivationProfile> p;
    for (int i = 0; i < setup.getNumMuscles(); ++i)
        p.emplace_back(times, values[i], "excitation of " + setup.muscles[i].params.name + " (the callable's value)");
    return p;
}

py::dict getState(const PySimulation& ps) {
    py::dict d;
    d["time_s"] = ps.sim->getTime();
    d["elbow_angle_deg"] = radToDeg(ps.sim->getElbowAngle());
    d["elbow_velocity_degps"] = radToDeg(ps.sim->getElbowVelocity());
    d["muscle_states"] = toArray(ps.sim->getMuscleStates());
    return d;
}

}  // namespace

namespace armsim::python {

void addSimulationBindings(py::module_& mod) {
    py::class_<PySimulation>(mod, "Simulation",
        "A model's arm advanced on request, with its state read and written between calls (what OpenSim's\n"
        "Manager and MuJoCo's mj_step give).\n\n"
        "    sim = armsim.Simulation(model, angle_deg=120, excitation={'BRA': 0.3})\n"
        "    for t in np.arange(0.01, 1.0, 0.01):\n"
        "        sim.advance_to(t)\n"
        "        sim.set_excitation({'BRA': 0.3 + 0.01 * (sim.state['elbow_angle_deg'] - 90)})\n"
        "    samples = sim.samples()      # dict of arrays, pandas.DataFrame(samples) works\n\n"
        "Free (the elbow moves under its muscles, gravity and a hand load) or locked (held at angle_deg; the\n"
        "lock's torque is recorded). Samples are taken every 1/rate s of simulated time from the start,\n"
        "however advance_to cuts the time.")
        .def(py::init([](const Model& m, bool locked, double angleDeg, double velocityDegps,
                         std::optional<double> rotationDeg, std::optional<double> handLoadKg, const py::object& excitation,
                         double rateHz, const std::string& start, std::optional<double> accuracy) {
                 auto ps = std::make_unique<PySimulation>();
                 ps->model = m;
                 SimulationSettings s;
                 s.lockedElbow = locked;
                 s.elbowAngle = degToRad(angleDeg);
                 s.elbowVelocity = degToRad(velocityDegps);
                 if (rotationDeg) s.forearmRotationDeg = *rotationDeg;
                 s.handLoad = handLoadKg ? *handLoadKg : m.setup.arm.handLoad;   // None: the model's arm file
                 s.sampleRate = rateHz;
                 if (start != "steady" && start != "initial")
                     throw InputError("start = '" + start + "': expected 'steady' or 'initial'");
                 s.startSteady = start == "steady";
                 if (accuracy) s.integration.accuracy = *accuracy;
                 std::vector<ActivationProfile> profiles = toProfiles(m.setup, excitation, &ps->callable);
                 try {   // errors name the arguments as typed
                     ps->sim = std::make_unique<ArmSimulation>(m.setup, s, std::move(profiles));
                 } catch (const FieldError& e) {
                     static const std::map<std::string, std::string> argument = {
                         {"elbow_angle_deg", "angle_deg"}, {"elbow_velocity_degps", "velocity_degps"},
                         {"sample_rate", "rate"}, {"accuracy", "accuracy"}};
                     const auto it = argument.find(e.getField());
                     if (it == argument.end()) throw;
                     throw InputError(it->second + " " + e.getDetail());
                 }
                 return ps;
             }),
             py::arg("model"), py::arg("locked") = false, py::arg("angle_deg") = 90.0, py::arg("velocity_degps") = 0.0,
             py::arg("rotation_deg") = py::none(), py::arg("hand_load") = py::none(), py::arg("excitation") = py::none(),
             py::arg("rate") = 1000.0, py::arg("start") = "steady", py::arg("accuracy") = py::none(),
             "model: an armsim.Model. locked: hold the elbow at angle_deg (included angle, deg; 180 = extended).\n"
             "velocity_degps: dtheta/dt at the start (+ = extending; free only). rotation_deg: forearm rotation the\n"
             "radius is held at (+ = supination; None: the model's posture). hand_load: a mass in the hand [kg]\n"
             "(None: the arm file's hand_load, 0 in the shipped ones).\n"
             "rate: samples per second of simulated time [Hz].\n"
             "excitation U in [0, 1] per muscle: None (0), a number (every muscle), one number per muscle, a dict\n"
             "{muscle: number}, a dict of arrays {'time_s': t, muscle: u, ...} (linear between rows), a callable\n"
             "f(t) returning any of the constant forms (sampled every 1/rate, linear between), or a controls\n"
             "file (.sto/.mot as OpenSim writes them, or .csv with time_s); muscles not named get 0.\n"
             "start: 'steady' (each muscle at its steady state for U(0)) or 'initial' (the spec-5 state).\n"
             "accuracy: the integrator's relative accuracy (None: the trials' default).")
        .def_property_readonly("muscles", [](const PySimulation& ps) { return muscleNames(ps.model.setup); },
                               "muscle names in model order (the order of per-muscle arrays)")
        .def_property_readonly("locked", [](const PySimulation& ps) { return ps.sim->isLocked(); })
        .def_property_readonly("time_s", [](const PySimulation& ps) { return ps.sim->getTime(); },
                               "the simulation's time [s]")
        .def_property_readonly("state_names", [](const PySimulation& ps) { return ps.sim->getMuscleStateNames(); },
                               "names of the muscle_states entries: '<muscle>_<state>'")
        .def_property_readonly("state", [](const PySimulation& ps) { requireIdle(ps); return getState(ps); },
                               "dict: time_s, elbow_angle_deg, elbow_velocity_degps (+ = extending), muscle_states "
                               "(array, order of state_names)")
        .def_property_readonly(
            "muscle_forces_N", [](const PySimulation& ps) { return toArray(ps.sim->calcMuscleForces()); },
            "each muscle's tendon force [N] now (array, order of muscles)")
        .def(
            "set_state",
            [](PySimulation& ps, const py::object& state, std::optional<double> angleDeg,
               std::optional<double> velocityDegps, const py::object& muscleStates) {
                requireIdle(ps);
                py::object states = muscleStates;
                if (!state.is_none()) {
                    if (!py::isinstance<py::dict>(state))
                        throw py::type_error("state = " + py::repr(state).cast<std::string>() + ": expected a dict (Simulation.state)");
                    const py::dict d = state.cast<py::dict>();
                    for (const auto& item : d) {
                        const std::string k = py::str(item.first).cast<std::string>();
                        if (k == "time_s") {
                            const double t = toNumber(item.second, "state['time_s']");
                            if (std::abs(t - ps.sim->getTime()) > 1e-12)
                                throw InputError("state['time_s'] = " + formatNumber(t) + " s: the simulation is at " +
                                                 formatNumber(ps.sim->getTime()) + " s; time moves with advance_to only");
                        } else if (k == "elbow_angle_deg") {
                            if (!angleDeg) angleDeg = toNumber(item.second, "state['elbow_angle_deg']");
                        } else if (k == "elbow_velocity_degps") {
                            if (!velocityDegps) velocityDegps = toNumber(item.second, "state['elbow_velocity_degps']");
                        } else if (k == "muscle_states") {
                            if (states.is_none()) states = py::reinterpret_borrow<py::object>(item.second);
                        } else {
                            throw InputError("state['" + k + "']: unknown key (expected time_s, elbow_angle_deg, "
                                             "elbow_velocity_degps, muscle_states)");
                        }
                    }
                }
                // All checked before any is set: a refused call changes nothing.
                std::optional<std::vector<double>> y;
                if (!states.is_none()) y = toVector(states, "muscle_states");
                const double theta = angleDeg ? degToRad(*angleDeg) : 0, thetaDot = velocityDegps ? degToRad(*velocityDegps) : 0;
                ps.sim->setState(angleDeg ? &theta : nullptr, velocityDegps ? &thetaDot : nullptr, y ? &*y : nullptr);
            },
            py::arg("state") = py::none(), py::kw_only(), py::arg("elbow_angle_deg") = py::none(),
            py::arg("elbow_velocity_degps") = py::none(), py::arg("muscle_states") = py::none(),
            "Sets the state: a dict as `state` returns (its time_s must be the present time), or any of the\n"
            "keywords. Raises ValueError (naming the value) for an angle outside the elbow's range, a velocity on\n"
            "a locked elbow or muscle states a muscle cannot hold; nothing is changed then.")
        .def(
            "set_excitation",
            [](PySimulation& ps, const py::object& excitation) {
                requireIdle(ps);
                py::object callable;
                ps.sim->setExcitations(toProfiles(ps.model.setup, excitation, &callable));
                ps.callable = callable;
            },
            py::arg("excitation"),
            "Replaces every muscle's excitation (the forms of the constructor; times are absolute). The time\n"
            "already simulated keeps what it had.")
        .def(
            "advance_to",
            [](PySimulation& ps, double t) {
                requireIdle(ps);
                ps.sim->checkAdvance(t);   // before the callable is sampled over the interval
                if (!ps.callable.is_none() && t > ps.sim->getTime())
                    ps.sim->setExcitations(sampleCallable(ps, ps.sim->getTime(), t));
                IntegrationStats st;
                ps.busy = true;
                struct Idle {
                    bool& busy;
                    ~Idle() { busy = false; }
                } idle{ps.busy};
                runInterruptible([&] { st = ps.sim->advanceTo(t); });
                return getState(ps);
            },
            py::arg("time_s"),
            "Integrates to time_s [s] (not before the present time: ValueError) and returns the new state.\n"
            "Raises RuntimeError when the integrator cannot go on (the simulation stays where the call began).\n"
            "Releases the GIL; Ctrl-C raises KeyboardInterrupt (and leaves the simulation where the call began).")
        .def(
            "samples", [](const PySimulation& ps) { requireIdle(ps); return toDict(ps.sim->getSamples()); },
            "Every sample so far as a dict of float64 arrays: time_s, elbow_angle_deg, elbow_velocity_degps,\n"
            "holding_torque_Nm (the lock's, + = flexion; NaN when free), forearm_holding_torque_Nm (a rotating\n"
            "forearm), then per muscle excitation_<m>, active_fraction_<m> (the muscle's activation: Virtual\n"
            "Muscle sum Af p, Hill a), force_<m>_N, fascicle_length_<m>_m, and the states state_<m>_<state>.")
        .def("__repr__", [](const PySimulation& ps) {
            return "<armsim.Simulation '" + ps.model.setup.name + "', " + (ps.sim->isLocked() ? "locked" : "free") +
                   ", t = " + formatNumber(ps.sim->getTime()) + " s>";
        });
}

}  // namespace armsim::python
