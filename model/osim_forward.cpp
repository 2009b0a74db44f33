#include "model/osim_forward.h"

#include "basics/bound.h"
#include "basics/errors.h"
#include "basics/files.h"
#include "basics/format.h"
#include "basics/numbers.h"
#include "model/osim_arm.h"
#include "muscles/muscle_file.h"
#include "muscles/simbody_isometric.h"

#include <tinyxml2.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>

namespace armsim {

namespace {

// The .osim extension in any case (ARM26.OSIM).
bool hasOsimExtension(const std::string& name) {
    if (name.size() <= 5) return false;
    std::string ext = name.substr(name.size() - 5);
    for (char& ch : ext) ch = char(std::tolower(static_cast<unsigned char>(ch)));
    return ext == ".osim";
}

}  // namespace

namespace {

constexpr double kPi = 3.14159265358979323846;

// A muscle's column in a controls file: "<muscle>" or "/forceset/<muscle>".
std::string stripForceset(const std::string& column) {
    const std::string prefix = "/forceset/";
    return column.rfind(prefix, 0) == 0 ? column.substr(prefix.size()) : column;
}

}  // namespace

OsimStorage readOsimStorage(const std::string& path) {
    OsimStorage s;
    s.file = path;
    s.table = readStorage(path, &s.header);
    if (s.table.getNumRows() == 0) throw InputError(path + ": no rows after the column labels");
    return s;
}

std::string findOsimModelFile(const std::string& model, const std::string& option) {
    if (model.find('/') == std::string::npos && !hasOsimExtension(model)) {
        const std::string asset = getAssetDirectory() + "/models/" + model + ".osim";
        if (!isRegularFile(asset))
            throw InputError(option + " '" + model + "': no shipped OpenSim model assets/models/" + model + ".osim");
        return asset;
    }
    if (!isRegularFile(model)) throw InputError(option + " '" + model + "': no such .osim file");
    return model;
}

bool isOsimModel(const std::string& name) {
    if (hasOsimExtension(name)) return true;
    return name.find('/') == std::string::npos && !doesPathExist(getAssetDirectory() + "/models/" + name + ".yaml") &&
           doesPathExist(getAssetDirectory() + "/models/" + name + ".osim");
}

void OsimForwardSettings::validate() const {
    if (std::isfinite(initialTime) && !(finalTime > initialTime))
        throw FieldError("final_time", "= " + formatNumber(finalTime) + " s: expected after the initial time " +
                                           formatNumber(initialTime) + " s");
    checkField("final_time", finalTime, Bound{-1e9, 1e9, true, true, "s"});
    checkField("sample_rate", sampleRate, Bound::positive("Hz"));
    integration.validate();
}

namespace {

// The controls' times: finite and not decreasing (a row repeating a time replaces the earlier one).
void checkControlTimes(const OsimStorage& controls) {
    const Table& c = controls.table;
    for (int r = 0; r < c.getNumRows(); ++r) {
        const double t = c.get(r, 0);
        if (!std::isfinite(t) || std::abs(t) > 1e9)
            throw InputError(controls.file + ": row " + std::to_string(r + 1) + ": time " + formatNumber(t) +
                             ": expected a finite time within +/-1e9 s");
        if (r > 0 && t < c.get(r - 1, 0))
            throw InputError(controls.file + ": row " + std::to_string(r + 1) + ": time " + formatNumber(t) + " s is before the "
                             "previous row's " + formatNumber(c.get(r - 1, 0)) + " s: expected times in increasing order");
    }
}

// Excitations as OpenSim's ControlLinear: linear between the rows (a row repeating a time replaces the
// earlier one), extrapolated linearly beyond the first and last rows and clamped to [0, 1] (the
// muscles' min and max control); notes for extrapolation and muscles without a column.
std::map<std::string, ActivationProfile> makeExcitations(const OsimModel& model, const OsimStorage& controls, double t0,
                                                         double finalTime, std::vector<std::string>& notes) {
    const Table& c = controls.table;
    std::vector<int> rows;  // the rows kept, by time
    for (int r = 0; r < c.getNumRows(); ++r) {
        if (!rows.empty() && c.get(rows.back(), 0) == c.get(r, 0)) rows.back() = r;
        else rows.push_back(r);
    }
    std::map<std::string, ActivationProfile> excitations;
    for (int k = 1; k < c.getNumColumns(); ++k) {
        const std::string muscle = stripForceset(c.getColumnNames()[k]);
        if (std::none_of(model.muscles.begin(), model.muscles.end(), [&](const OsimMuscle& m) { return m.name == muscle; }))
            throw InputError(controls.file + ": column '" + c.getColumnNames()[k] + "' names no muscle of " + model.file +
                             " (expected a muscle's name or /forceset/<muscle>)");
        std::vector<double> times, values;
        for (int r : rows) {
            const double v = c.get(r, k);
            if (!(v >= 0 && v <= 1))
                throw InputError(controls.file + ": column '" + c.getColumnNames()[k] + "' at t = " + formatNumber(c.get(r, 0)) +
                                 " s: excitation " + formatNumber(v) + ": expected in [0, 1]");
            times.push_back(c.get(r, 0));
            values.push_back(v);
        }
        auto extrapolate = [&](std::size_t i, std::size_t j, double t) {  // the line through rows i, j at t
            const double slope = times[j] != times[i] ? (values[j] - values[i]) / (times[j] - times[i]) : 0.0;
            return std::clamp(values[i] + slope * (t - times[i]), 0.0, 1.0);
        };
        const std::size_t n = times.size();
        if (t0 < times.front()) {
            const double v = n > 1 ? extrapolate(0, 1, t0) : values.front();
            times.insert(times.begin(), t0);
            values.insert(values.begin(), v);
        }
        if (finalTime > times.back()) {
            const std::size_t m = times.size();
            const double v = n > 1 ? extrapolate(m - 2, m - 1, finalTime) : values.back();
            times.push_back(finalTime);
            values.push_back(v);
        }
        excitations[muscle] = ActivationProfile(times, values, "controls column " + muscle);
    }
    if (finalTime > c.get(c.getNumRows() - 1, 0) || t0 < c.get(0, 0))
        notes.push_back(controls.file + ": controls from " + formatNumber(c.get(0, 0)) + " to " +
                               formatNumber(c.get(c.getNumRows() - 1, 0)) +
                               " s, extrapolated linearly beyond (OpenSim's ControlLinear), clamped to [0, 1]");
    for (const OsimMuscle& m : model.muscles)
        if (!excitations.count(m.name)) notes.push_back("muscle " + m.name + " has no control column: excitation 0");

    return excitations;
}

constexpr double kMaxFibreStretch = 3;   // a fibre's longest length over its optimal one

// A states file marked inDegrees=yes whose every rotational coordinate value, in every row, lies within
// pi and is not whole holds radians (the elbow would start at 1.3 deg instead of 75).
void checkStatesInDegrees(const OsimArm& arm, const OsimStorage& initial, const std::map<std::string, std::string>& jointOf) {
    const Table& st = initial.table;
    std::vector<double> angles;
    for (int i = 0; i < arm.getNumCoordinates(); ++i) {
        if (!arm.getCoordinate(i).rotational) continue;
        const std::string& n = arm.getCoordinate(i).name;
        const auto it = jointOf.find(n);
        for (int k = 1; k < st.getNumColumns(); ++k) {
            const std::string& c = st.getColumnNames()[k];
            if (c != n && (it == jointOf.end() || c != "/jointset/" + it->second + "/" + n + "/value")) continue;
            for (int r = 0; r < st.getNumRows(); ++r) angles.push_back(st.get(r, k));
        }
    }
    try {
        checkDegreesNotRadians("coordinates", angles);
    } catch (const FieldError& e) {
        throw InputError(initial.file + ": header 'inDegrees=yes', but its coordinate values " + e.getDetail() +
                         ": expected inDegrees=no for radians, or the values in degrees");
    }
}

// The initial state from the initial-states row `given` (coordinates in the file's unit, muscle states
// in OpenSim's), each value checked; muscles without every state start at equilibrium. Notes the
// columns nothing reads (a misspelt column would otherwise leave its state at the default).
void setInitialStates(const OsimModel& model, const OsimArm& arm, const OsimStorage* initial,
                      const std::map<std::string, double>& given, double t0,
                      const std::vector<std::vector<std::string>>& stateNames,
                      const std::vector<std::vector<double>>& stateScales, SimTK::State& s,
                      std::vector<std::string>& notes) {
    std::map<std::string, std::string> jointOf;  // coordinate -> joint, for 4.x column names
    for (const OsimJoint& j : model.joints)
        for (const OsimCoordinate& k : j.coordinates) jointOf[k.name] = j.name;
    const double degree = initial && initial->header.inDegrees ? kPi / 180 : 1.0;
    if (initial && initial->header.inDegrees) checkStatesInDegrees(arm, *initial, jointOf);
    // Every value of the row used is finite, and the columns nothing reads are named in a note (a
    // misspelt column would otherwise leave its state at the default).
    std::set<std::string> used;
    auto take = [&](const std::vector<std::string>& names, double& value) {
        for (const std::string& n : names) {
            const auto it = given.find(n);
            if (it == given.end()) continue;
            used.insert(n);
            if (!std::isfinite(it->second))
                throw InputError(initial->file + ": column '" + n + "' at t = " + formatNumber(t0) + " s: " +
                                 formatNumber(it->second) + ": expected a finite number");
            return value = it->second, true;
        }
        return false;
    };
    for (int i = 0; i < arm.getNumCoordinates(); ++i) {
        const std::string& n = arm.getCoordinate(i).name;
        const std::string path = "/jointset/" + jointOf[n] + "/" + n;
        double v;
        if (take({n, path + "/value"}, v)) arm.setCoordinateValue(s, i, v * (arm.getCoordinate(i).rotational ? degree : 1));
        if (take({n + "_u", path + "/speed"}, v)) arm.setCoordinateSpeed(s, i, v * (arm.getCoordinate(i).rotational ? degree : 1));
    }
    arm.getSystem().realize(s, SimTK::Stage::Velocity);
    for (int i = 0; i < arm.getNumMuscles(); ++i) {
        const MuscleForce& f = arm.getMuscleForce(i);
        const std::vector<std::string>& names = stateNames[i];
        const std::string& muscle = arm.getMuscleName(i);
        std::vector<double> y(names.size());
        bool all = true;
        for (std::size_t k = 0; k < names.size(); ++k) {
            double v;
            if (take({muscle + "." + names[k], "/forceset/" + muscle + "/" + names[k]}, v)) {
                // A fibre past kMaxFibreStretch optimal lengths is beyond every force-length curve (a length
                // in mm ended in the integrator's raw failure).
                const double longest = kMaxFibreStretch * stateScales[i][k];
                if ((names[k] == "activation" && !(v >= 0 && v <= 1)) ||
                    (names[k] == "fiber_length" && !(v > 0 && v <= longest)))
                    throw InputError(initial->file + ": column '" + muscle + "." + names[k] + "' at t = " + formatNumber(t0) +
                                     " s: " + formatNumber(v) + ": expected " +
                                     (names[k] == "activation" ? "an activation in [0, 1]"
                                                               : "a fibre length in (0, " + formatNumber(longest, 4) + "] m (" +
                                                                     formatNumber(kMaxFibreStretch) + " times its optimal_fiber_length " +
                                                                     formatNumber(stateScales[i][k], 4) + " m; OpenSim lengths are in metres)"));
                y[k] = v / stateScales[i][k];
            } else {
                all = false;
            }
        }
        if (all) f.setMuscleStates(s, y);
        else f.setSteadyMuscleStates(s);  // equilibrium at the excitation of t0 (solve_for_equilibrium)
    }

    if (initial) {
        std::string unused;
        for (const auto& [name, value] : given)
            if (!used.count(name)) unused += (unused.empty() ? "" : ", ") + name;
        if (!unused.empty())
            notes.push_back(initial->file + ": columns not used (no state of " + model.name + " by that name): " + unused);
    }

}

}  // namespace

OsimForwardResult runOsimForward(const OsimModel& model, const OsimStorage& controls, const OsimStorage* initial,
                                 const OsimForwardSettings& settings) {
    settings.validate();
    OsimForwardResult result;
    const Table& c = controls.table;
    checkControlTimes(controls);
    double t0 = std::isfinite(settings.initialTime) ? settings.initialTime : c.get(0, 0);
    // Initial states: the row at or before t0, or the first row when t0 is before it; the run starts at
    // that row's time (the Forward tool's rule). Else defaults and equilibrium.
    std::map<std::string, double> given;
    if (initial) {
        const Table& st = initial->table;
        int row = 0;
        for (int r = 0; r < st.getNumRows(); ++r)
            if (st.get(r, 0) <= t0 + 1e-12) row = r;
        if (st.get(row, 0) != t0)
            result.notes.push_back(initial->file + ": the run starts at its row's time " + formatNumber(st.get(row, 0)) +
                                   " s (asked: " + formatNumber(t0) + " s), as OpenSim's Forward tool does");
        t0 = st.get(row, 0);
        for (int k = 1; k < st.getNumColumns(); ++k) given[st.getColumnNames()[k]] = st.get(row, k);
    }
    if (!(settings.finalTime > t0))
        throw InputError("final time " + formatNumber(settings.finalTime) + " s: expected after the initial time " +
                         formatNumber(t0) + " s" + (initial ? " (from " + initial->file + ")" : std::string()));
    if (settings.integration.maxStepSize > 0 && (settings.finalTime - t0) / settings.integration.maxStepSize > kMaxSamples)
        throw FieldError("maximum_integrator_step_size",
                         "= " + formatNumber(settings.integration.maxStepSize) + " s: " +
                             formatNumber((settings.finalTime - t0) / settings.integration.maxStepSize, 3) + " steps over " +
                             formatNumber(settings.finalTime - t0) + " s: expected at most " + formatNumber(kMaxSamples) +
                             " steps (a larger step limit)");

    {   // the rows fall every 1/rate from t0; said when the last is not the final time asked
        const double lastRow = t0 + std::floor((settings.finalTime - t0) * settings.sampleRate + 1e-9) / settings.sampleRate;
        if (lastRow < settings.finalTime - 1e-9 / settings.sampleRate)
            result.notes.push_back("rows every " + formatNumber(1 / settings.sampleRate) + " s from " + formatNumber(t0) +
                                   " s: the last at " + formatNumber(lastRow, 10) + " s, not at the final time " +
                                   formatNumber(settings.finalTime) + " s (the interval from the start is not a whole "
                                   "number of rows)");
    }
    const std::map<std::string, ActivationProfile> excitations = makeExcitations(model, controls, t0, settings.finalTime, result.notes);
    const OsimArm arm(model, excitations, settings.muscleModel);
    SimTK::State s = arm.getDefaultState();
    s.setTime(t0);

    // Each muscle state's names and its storage unit per state unit (OpenSim writes fibre lengths in
    // metres, armsim's Hill states hold them over l0).
    std::vector<std::vector<std::string>> stateNames(arm.getNumMuscles());
    std::vector<std::vector<double>> stateScales(arm.getNumMuscles());
    for (int i = 0; i < arm.getNumMuscles(); ++i) {
        const MuscleModel& m = arm.getMuscleForce(i).getMuscle();
        stateNames[i] = m.getStateNames();
        for (const std::string& n : stateNames[i]) stateScales[i].push_back(n == "fiber_length" ? m.getOptimalFascicleLength() : 1.0);
    }
    setInitialStates(model, arm, initial, given, t0, stateNames, stateScales, s, result.notes);

    // The states table.
    std::vector<std::string> columns = {"time"};
    for (int i = 0; i < arm.getNumCoordinates(); ++i) columns.push_back(arm.getCoordinate(i).name);
    for (int i = 0; i < arm.getNumCoordinates(); ++i) columns.push_back(arm.getCoordinate(i).name + "_u");
    for (int i = 0; i < arm.getNumMuscles(); ++i)
        for (const std::string& n : stateNames[i]) columns.push_back(arm.getMuscleName(i) + "." + n);
    result.states = Table(columns);
    auto sample = [&](const SimTK::State& x) {
        std::vector<double> row = {x.getTime()};
        for (int i = 0; i < arm.getNumCoordinates(); ++i) row.push_back(arm.getCoordinateValue(x, i));
        for (int i = 0; i < arm.getNumCoordinates(); ++i) row.push_back(arm.getCoordinateSpeed(x, i));
        for (int i = 0; i < arm.getNumMuscles(); ++i) {
            const std::vector<double> y = arm.getMuscleForce(i).getMuscleStates(x);
            for (std::size_t k = 0; k < y.size(); ++k) row.push_back(y[k] * stateScales[i][k]);
        }
        result.states.appendRow(row);
        if (settings.progress) settings.progress(x.getTime() - t0, settings.finalTime - t0);
    };
    // The excitations are continuous (linear between rows): the solver's error control takes their kinks
    // without restarts, but not a jump of the muscle's own (a Virtual Muscle's recruitment threshold).
    std::vector<double> breakpoints;
    for (int i = 0; i < arm.getNumMuscles(); ++i) {
        const MuscleForce& f = arm.getMuscleForce(i);
        const std::vector<double> r = findRestartTimes(f.getMuscle(), f.getActivationProfile(), true);
        breakpoints.insert(breakpoints.end(), r.begin(), r.end());
    }
    auto check = [&](const SimTK::State& x) {
        for (int i = 0; i < arm.getNumMuscles(); ++i) {
            const MuscleForce& f = arm.getMuscleForce(i);
            const std::vector<double> y = f.getMuscleStates(x);
            f.getMuscle().checkStates(x.getTime(), y.data());
        }
    };
    result.stats = simulateSampled(arm.getSystem(), s, settings.finalTime - t0, settings.sampleRate, breakpoints,
                                   settings.integration, sample, check);
    // The sample grid may end short of the final time (its length x rate rounded): the run is done all the same.
    const double last = result.states.get(result.states.getNumRows() - 1, 0);
    if (settings.progress && last < settings.finalTime) settings.progress(settings.finalTime - t0, settings.finalTime - t0);
    return result;
}

namespace {

// An element's text without surrounding white space ("" when absent).
std::string elementText(const tinyxml2::XMLElement* e, const char* tag) {
    const tinyxml2::XMLElement* c = e->FirstChildElement(tag);
    std::string v = c && c->GetText() ? c->GetText() : "";
    const std::size_t b = v.find_first_not_of(" \t\r\n");
    return b == std::string::npos ? std::string() : v.substr(b, v.find_last_not_of(" \t\r\n") - b + 1);
}

// Every element of <ForwardTool> is one readOsimForwardSetup uses, one that cannot change the states
// (skipped), or one refused naming its line; none twice.
void checkForwardToolElements(const tinyxml2::XMLElement* tool, const std::string& path) {
    using tinyxml2::XMLElement;
    static const std::set<std::string> kUsed = {"model_file", "results_directory", "initial_time", "final_time",
                                                "integrator_error_tolerance", "maximum_integrator_step_size",
                                                "states_file", "ControllerSet", "controls_file"};
    // Output precision, step counts and floors, equilibrium of auxiliary states (armsim solves it when no
    // states file is given), analyses (their own outputs), and force sets or loads left empty.
    // OpenSim 2.x's setups add the corrective springs of external loads (their parameters harmless while
    // the springs are off) and output flags.
    static const std::set<std::string> kHarmless = {
        "output_precision", "maximum_number_of_integrator_steps", "minimum_integrator_step_size",
        "integrator_fine_tolerance", "solve_for_equilibrium_for_auxiliary_states", "AnalysisSet", "print_every",
        "output_detailed_results", "spring_transition_start_time", "spring_transition_end_time",
        "spring_linear_stiffness", "spring_linear_damping", "spring_rotational_stiffness", "spring_rotational_damping",
        "spring_force_threshold", "spring_torque_threshold", "tau"};
    static const std::set<std::string> kRefusedWhenSet = {
        "force_set_files", "replace_force_set", "external_loads_file", "external_loads_model_kinematics_file",
        "lowpass_cutoff_frequency_for_load_kinematics", "use_specified_dt", "external_loads_body1", "external_loads_body2",
        "body1_linear_corrective_spring_active", "body1_torsional_corrective_spring_active",
        "body2_linear_corrective_spring_active", "body2_torsional_corrective_spring_active"};
    std::map<std::string, int> seen;   // element -> its first line
    for (const XMLElement* e = tool->FirstChildElement(); e; e = e->NextSiblingElement()) {
        const std::string name = e->Name();
        const std::string where = path + ":" + std::to_string(e->GetLineNum()) + ": <" + name + ">";
        if (const auto [it, first] = seen.emplace(name, e->GetLineNum()); !first)
            throw OsimError(where + ": given twice (first at line " + std::to_string(it->second) + "): expected once");
        if (kUsed.count(name) || kHarmless.count(name)) continue;
        if (kRefusedWhenSet.count(name)) {
            const std::string v = elementText(tool, name.c_str());
            const bool unset = v.empty() || v == "Unassigned" || v == "false" ||
                               (name == "lowpass_cutoff_frequency_for_load_kinematics" && v.find('-') == 0);
            if (unset) continue;
            throw OsimError(where + " '" + v + "': not supported yet (the Forward tool would " +
                            (name == "use_specified_dt"                                  ? std::string("step at the controls' times")
                             : name == "force_set_files" || name == "replace_force_set" ? std::string("add or replace forces")
                             : name.find("spring") != std::string::npos ? std::string("add corrective springs")
                                                                        : std::string("apply external loads")) +
                            "; armsim runs the model's own muscles only): remove it to run without");
        }
        throw OsimError(where + ": not an element of OpenSim's Forward tool setup (a misspelling?): expected model_file, "
                                "results_directory, initial_time, final_time, integrator_error_tolerance, states_file, "
                                "ControllerSet or another ForwardTool property");
    }
}

}  // namespace

OsimForwardSetup readOsimForwardSetup(const std::string& path) {
    using namespace tinyxml2;
    if (!isRegularFile(path)) throw InputError(path + ": no such Forward tool setup file");
    XMLDocument doc;
    if (doc.LoadFile(path.c_str()) != XML_SUCCESS)
        throw OsimError(path + ":" + std::to_string(doc.ErrorLineNum()) + ": not XML: " + doc.ErrorStr());
    const XMLElement* root = doc.RootElement();
    const XMLElement* tool = root ? (std::string(root->Name()) == "ForwardTool" ? root : root->FirstChildElement("ForwardTool")) : nullptr;
    if (!tool) throw OsimError(path + ": no <ForwardTool>: expected an OpenSim Forward tool setup file");
    const std::string folder = std::filesystem::path(path).parent_path().string();
    auto text = [](const XMLElement* e, const char* tag) { return elementText(e, tag); };
    auto file = [&](const std::string& name) {
        if (name.empty()) return name;
        const std::filesystem::path p(name);
        return p.is_absolute() || folder.empty() ? name : (std::filesystem::path(folder) / p).string();
    };
    auto number = [&](const char* tag, double fallback) {
        const std::string v = text(tool, tag);
        if (v.empty()) return fallback;
        // The whole text a finite decimal number ("0.2abc" and hexadecimal "0x1p-2" are not).
        char* end = nullptr;
        const double x = std::strtod(v.c_str(), &end);
        if (end == v.c_str() || *end != '\0' || !std::isfinite(x) || isHexadecimalText(v.c_str()))
            throw OsimError(path + ":" + std::to_string(tool->FirstChildElement(tag)->GetLineNum()) + ": <" + tag + "> '" + v +
                            "': expected a number");
        return x;
    };
    checkForwardToolElements(tool, path);
    OsimForwardSetup s;
    s.modelFile = file(text(tool, "model_file"));
    if (s.modelFile.empty())
        throw OsimError(path + ":" + std::to_string(tool->GetLineNum()) + ": <ForwardTool>: no <model_file>");
    s.resultsDirectory = file(text(tool, "results_directory"));
    s.initialTime = number("initial_time", 0);
    s.finalTime = number("final_time", 1);
    s.tolerance = number("integrator_error_tolerance", 1e-5);
    s.maxStepSize = number("maximum_integrator_step_size", 1);
    if (!(s.maxStepSize > 0))
        throw OsimError(path + ":" + std::to_string(tool->FirstChildElement("maximum_integrator_step_size")->GetLineNum()) +
                        ": <maximum_integrator_step_size> " + formatNumber(s.maxStepSize) + ": expected > 0 s");
    s.statesFile = file(text(tool, "states_file"));
    if (const std::string c = text(tool, "controls_file"); !c.empty() && c != "Unassigned") s.controlsFile = file(c);  // OpenSim 2.x
    for (const XMLElement* e = tool->FirstChildElement("ControllerSet"); e; e = nullptr)
        if (const XMLElement* objects = e->FirstChildElement("objects"))
            for (const XMLElement* ctl = objects->FirstChildElement(); ctl; ctl = ctl->NextSiblingElement()) {
                const std::string at = path + ":" + std::to_string(ctl->GetLineNum()) + ": <" + ctl->Name() + ">";
                if (std::string(ctl->Name()) != "ControlSetController")
                    throw OsimError(at + ": controller type " + ctl->Name() + " is not supported yet (expected a "
                                    "ControlSetController with a controls_file)");
                const std::string f = text(ctl, "controls_file");
                if (f.empty() || f == "Unassigned") continue;
                if (!s.controlsFile.empty())
                    throw OsimError(at + ": a second controls file '" + f + "': expected one ControlSetController with a "
                                    "controls file (merge the files' columns into one)");
                if (f.size() >= 4 && f.substr(f.size() - 4) == ".xml")
                    throw OsimError(path + ":" + std::to_string(ctl->GetLineNum()) + ": <" + ctl->Name() + ">: controls file '" +
                                    f + "' is an XML ControlSet: not supported yet (expected a .sto storage file)");
                s.controlsFile = file(f);
            }
    if (s.controlsFile.empty())
        throw OsimError(path + ":" + std::to_string(tool->GetLineNum()) + ": <ForwardTool>: no controls_file in its ControllerSet");
    return s;
}

}  // namespace armsim
