#include "python/module_support.h"

#include "basics/errors.h"
#include "muscles/muscle_file.h"

#include <csignal>
#include <mutex>

namespace armsim::python {

py::dict toDict(const Table& t) { return toDict(Table(t)); }

py::dict toDict(Table&& t) {
    const py::ssize_t n = t.getNumRows(), m = t.getNumColumns();
    const std::vector<std::string> names = t.getColumnNames();
    if (n == 0) {
        py::dict d;
        for (const std::string& name : names) d[py::str(name)] = py::array_t<double>(0);
        return d;
    }
    auto* values = new std::vector<double>(t.releaseData());
    const py::capsule owner(values, [](void* p) { delete static_cast<std::vector<double>*>(p); });
    py::dict d;
    for (py::ssize_t c = 0; c < m; ++c)
        d[py::str(names[c])] = py::array_t<double>({n}, {py::ssize_t(sizeof(double)) * m}, values->data() + c, owner);
    return d;
}

Table toTable(const py::dict& columns, const std::string& what) {
    std::vector<std::string> names;
    std::vector<py::array_t<double>> arrays;
    py::ssize_t rows = -1;
    for (auto item : columns) {
        const std::string name = py::str(item.first);
        const py::array raw = py::array::ensure(item.second);
        const char kind = raw ? raw.dtype().kind() : 'O';
        const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(item.second);
        if (!a || a.ndim() != 1 || (kind != 'f' && kind != 'i' && kind != 'u' && kind != 'b'))
            throw InputError(what + ": column '" + name + "': expected a 1-D sequence of numbers");
        if (rows >= 0 && a.shape(0) != rows)
            throw InputError(what + ": column '" + name + "' has " + std::to_string(a.shape(0)) + " values: expected " +
                             std::to_string(rows) + " like column '" + names[0] + "'");
        rows = a.shape(0);
        names.push_back(name);
        arrays.push_back(a);
    }
    Table t(names);
    std::vector<double> row(names.size());
    for (py::ssize_t r = 0; r < std::max<py::ssize_t>(rows, 0); ++r) {
        for (std::size_t c = 0; c < arrays.size(); ++c) row[c] = arrays[c].at(r);
        t.appendRow(row);
    }
    return t;
}

py::array_t<double> toArray(const std::vector<double>& v) {
    return py::array_t<double>(py::ssize_t(v.size()), v.data());
}

py::array_t<double> toArray(const std::vector<std::vector<double>>& rows) {
    const std::size_t n = rows.size(), m = rows.empty() ? 0 : rows[0].size();
    py::array_t<double> a({n, m});
    auto w = a.mutable_unchecked<2>();
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = 0; j < m; ++j) w(i, j) = rows[i][j];
    return a;
}

void throwFileNotFound(const std::string& path, const char* what) {
    PyErr_SetString(PyExc_FileNotFoundError, (path + ": cannot open " + what + " (no such file)").c_str());
    throw py::error_already_set();
}

std::string toPathString(const py::object& o, const char* argument) {
    if (!py::isinstance<py::str>(o) && !py::hasattr(o, "__fspath__"))
        throw py::type_error(std::string(argument) + ": expected a name or a file path (str or os.PathLike), got " +
                             py::str(py::type::of(o).attr("__name__")).cast<std::string>());
    return py::str(py::module_::import("os").attr("fspath")(o));
}

std::string findFile(const std::string& name) {
    try {
        return findAsset(name);
    } catch (const InputError& e) {
        PyErr_SetString(PyExc_FileNotFoundError, e.what());
        throw py::error_already_set();
    }
}

namespace {

std::mutex sigintMutex;
int sigintUsers = 0;             // scopes routing SIGINT now (calls from several Python threads)
struct sigaction pythonSigint;   // Python's handler, put back by the last scope

extern "C" void onSigint(int sig) { requestInterruption(sig); }

// Python's main thread with Python's own SIGINT handler in place (not SIG_IGN, not a user handler).
bool shouldRoute() {
    const py::module_ threading = py::module_::import("threading");
    if (!threading.attr("current_thread")().is(threading.attr("main_thread")())) return false;
    const py::module_ signal = py::module_::import("signal");
    return signal.attr("getsignal")(signal.attr("SIGINT")).is(signal.attr("default_int_handler"));
}

}  // namespace

InterruptibleScope::InterruptibleScope() {
    if (shouldRoute()) {
        std::lock_guard<std::mutex> lock(sigintMutex);
        if (sigintUsers++ == 0) {
            struct sigaction a {};
            a.sa_handler = onSigint;
            sigemptyset(&a.sa_mask);
            sigaction(SIGINT, &a, &pythonSigint);
        }
        routed_ = true;
    }
    saved_ = PyEval_SaveThread();
}

InterruptibleScope::~InterruptibleScope() {
    if (routed_) {
        std::lock_guard<std::mutex> lock(sigintMutex);
        if (--sigintUsers == 0) sigaction(SIGINT, &pythonSigint, nullptr);
    }
    PyEval_RestoreThread(saved_);   // the GIL back
}

void InterruptibleScope::raiseKeyboardInterrupt(bool clear) {
    if (clear) clearInterruption();
    PyErr_SetNone(PyExc_KeyboardInterrupt);
    throw py::error_already_set();
}

}  // namespace armsim::python
