// What the Python module's source files share: the Model handle (one definition, so the _render
// extension accepts the Models that _armsim makes), conversions to numpy and dicts, and the
// FileNotFoundError of the command line's wording.
#pragma once

#include "basics/errors.h"
#include "basics/fields.h"
#include "basics/table.h"
#include "model/model_file.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <map>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace armsim::python {

namespace py = pybind11;

/// The Python face of an ArmSetup (armsim.Model): immutable; with_muscle returns a changed copy.
/// Pickled as what made it: the model it was loaded from (a name, or a file's absolute path, read again
/// when unpickled), the with_muscle changes, in order, and the with_muscle_model choice.
struct Model {
    ArmSetup setup;
    std::string source;  ///< a name under assets/models/ or a file's absolute path
    std::vector<std::pair<std::string, std::vector<std::pair<std::string, double>>>> changes;  ///< muscle, (key, value)
    std::string muscleModel;  ///< with_muscle_model's model for every muscle ("" = the file's)
    std::map<std::string, double> muscleModelCoefficients;  ///< and its coefficients
};

/// A table's columns as a dict of float64 arrays, in column order. The arrays are views (stride: one
/// table row) of one buffer taken from the table without a copy, which they keep alive (a copy of
/// a 3.5 s trial's table costs about 5 % of the trial: docs/benchmarks.md).
py::dict toDict(Table&& table);
/// The same for a table that stays with its owner (copied first).
py::dict toDict(const Table& table);
/// A dict of equal-length 1-D arrays (e.g. a trial series) as a Table, in the dict's order.
/// ValueError naming `what` and the column for a non-numeric, non-1-D or short column.
Table toTable(const py::dict& columns, const std::string& what);
/// A float64 array of the values.
py::array_t<double> toArray(const std::vector<double>& values);
/// Rows (equal lengths) as an (n, m) float64 array.
py::array_t<double> toArray(const std::vector<std::vector<double>>& rows);

/// Result rows as columns under their fields' SI names (basics/fields.h): text fields as lists of str,
/// every other field (numbers, counts, yes/no, flags -1/0/1) as a float64 array, missing numbers NaN.
template <class T>
py::dict toFieldColumns(const FieldTable<T>& table, const std::vector<T>& rows) {
    py::dict out;
    for (const Field<T>& f : table.getFields()) {
        py::list text;
        std::vector<double> numbers;
        for (const T& r : rows) {
            const nlohmann::json v = f.toSi(r);
            if (v.is_string()) text.append(v.template get<std::string>());
            else numbers.push_back(v.is_null() ? std::nan("") : v.is_boolean() ? double(v.template get<bool>())
                                                                              : v.template get<double>());
        }
        if (!text.empty()) out[py::str(f.siName)] = text;
        else out[py::str(f.siName)] = toArray(numbers);
    }
    return out;
}

/// One result as a dict under its fields' SI names: numbers as float (NaN when missing), counts as
/// int, yes/no as bool, flags -1/0/1, text as str.
template <class T>
py::dict toFieldDict(const FieldTable<T>& table, const T& r) {
    py::dict d;
    for (const Field<T>& f : table.getFields()) {
        const nlohmann::json v = f.toSi(r);
        if (v.is_null()) d[py::str(f.siName)] = std::nan("");
        else if (v.is_string()) d[py::str(f.siName)] = v.template get<std::string>();
        else if (v.is_boolean()) d[py::str(f.siName)] = v.template get<bool>();
        else if (v.is_number_integer()) d[py::str(f.siName)] = v.template get<long long>();
        else d[py::str(f.siName)] = v.template get<double>();
    }
    return d;
}

/// A str or os.PathLike argument as a path string; TypeError naming the argument and the type given
/// otherwise.
std::string toPathString(const py::object& o, const char* argument);
/// Raises FileNotFoundError "<path>: cannot open <what> (no such file)".
[[noreturn]] void throwFileNotFound(const std::string& path, const char* what);
/// findAsset(name) (a path, or a name under the asset folder), FileNotFoundError with its message
/// when neither exists.
std::string findFile(const std::string& name);

/// For the duration of a long call: the GIL released and, when called on Python's main thread with
/// Python's own SIGINT handler in place (not ignored, not the user's), Ctrl-C routed to armsim's stop
/// (requestInterruption, as the command line does): the loops stop at their next step, task or solver
/// iteration and their writers remove partial output. Python's handler is back when the scope ends.
/// Use runInterruptible.
class InterruptibleScope {
public:
    InterruptibleScope();   ///< with the GIL held
    ~InterruptibleScope();
    InterruptibleScope(const InterruptibleScope&) = delete;
    InterruptibleScope& operator=(const InterruptibleScope&) = delete;
    bool isRouted() const { return routed_; }
    /// Raises KeyboardInterrupt; `clear`: forget the stop (the routed call does, once it has stopped).
    [[noreturn]] static void raiseKeyboardInterrupt(bool clear);

private:
    bool routed_ = false;
    PyThreadState* saved_ = nullptr;   // the GIL, released (PyEval_SaveThread)
};

/// Runs f() in an InterruptibleScope and returns what it returns. Ctrl-C during it raises
/// KeyboardInterrupt (within about one trial step, solver iteration or task: tests/python); a call on
/// another thread that the stop reaches raises it too.
template <class F>
auto runInterruptible(F&& f) -> decltype(f()) {
    using R = decltype(f());
    bool routed = false;
    try {
        if constexpr (std::is_void_v<R>) {
            {
                InterruptibleScope scope;
                routed = scope.isRouted();
                f();
            }
            if (routed && getInterruption()) InterruptibleScope::raiseKeyboardInterrupt(true);
        } else {
            R r = [&] {
                InterruptibleScope scope;
                routed = scope.isRouted();
                return f();
            }();
            if (routed && getInterruption()) InterruptibleScope::raiseKeyboardInterrupt(true);
            return r;
        }
    } catch (const py::error_already_set&) {
        throw;
    } catch (const InterruptedError&) {
        InterruptibleScope::raiseKeyboardInterrupt(routed);
    } catch (...) {
        // Another error on the way out of a stopped call: the stop is what the user asked for.
        if (routed && getInterruption()) InterruptibleScope::raiseKeyboardInterrupt(true);
        throw;
    }
}

/// Adds identify, identify_torque, read_torque_data, validate, validate_elbow, design_protocol and
/// run_protocol (python/identification_bindings.cpp).
void addIdentificationBindings(py::module_& module);
/// Adds Simulation (python/simulation_bindings.cpp).
void addSimulationBindings(py::module_& module);

}  // namespace armsim::python
