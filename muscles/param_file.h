// Strict reading of armsim's YAML parameter files and the validation helpers every parameter struct
// uses. Framework-free (yaml-cpp only).
//
// Every user error becomes an armsim::InputError whose message names the file, the line, the field,
// the offending value and what was expected, e.g.
//   "assets/muscles/biceps.yaml:4: field 'mass' = -0.3: expected > 0 (kg)".
#pragma once

#include <map>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace YAML { class Node; }

namespace armsim {

/// Shortest round-trip decimal form of v, locale-free (for error messages).
std::string formatNumber(double v);

/// A user error (bad file, bad value, bad option). The CLI prints what() and exits non-zero.
class InputError : public std::invalid_argument {
public:
    using std::invalid_argument::invalid_argument;
};

/// A simulation that cannot go on (NaN in a state, a fascicle beyond the model's validity bound,
/// an integrator failure). The message names the simulated time and the element.
class SimulationError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// A run stopped because the user asked (SIGINT or SIGTERM, see requestInterruption); the work in
/// progress was abandoned and its partial output removed by the writers' destructors.
class InterruptedError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// Records that signal `sig` asked the process to stop (async-signal-safe: sets an atomic).
void requestInterruption(int sig);
/// The signal that asked to stop, 0 if none.
int getInterruption();
/// Throws InterruptedError when an interruption was requested; long loops call it between tasks
/// (runParallel does before every task).
void checkInterruption();

/// A value that violates a documented bound. field is the dotted parameter name ("slow.Tf1"), so a
/// loader can add the file and line where that field was written.
class FieldError : public InputError {
public:
    FieldError(std::string field, const std::string& message);
    const std::string& getField() const { return field_; }
    const std::string& getDetail() const { return detail_; }
private:
    std::string field_;
    std::string detail_;
};

/// A closed/open interval used to validate one scalar field.
struct Bound {
    double lo = -1e300;      ///< lower bound
    double hi = 1e300;       ///< upper bound
    bool loOpen = false;     ///< true: value must be > lo; false: >= lo
    bool hiOpen = false;     ///< true: value must be < hi; false: <= hi
    const char* unit = "";   ///< unit shown in messages

    static Bound positive(const char* unit = "") { return {0, 1e300, true, false, unit}; }
    static Bound nonNegative(const char* unit = "") { return {0, 1e300, false, false, unit}; }
    static Bound closed(double lo, double hi, const char* unit = "") { return {lo, hi, false, false, unit}; }
    static Bound open(double lo, double hi, const char* unit = "") { return {lo, hi, true, true, unit}; }
    static Bound any(const char* unit = "") { return {-1e300, 1e300, false, false, unit}; }
    bool contains(double v) const;
    std::string describe() const;   ///< e.g. "> 0 (kg)" or "in [0, 1]"
};

/// Throws FieldError naming field, value and bound unless value is finite and inside bound.
void checkField(const std::string& field, double value, const Bound& bound);

/// One YAML mapping of a parameter file, read strictly: reading a key marks it used, and
/// finish() rejects keys that were never read (misspellings are errors, not silently ignored).
class ParamNode {
public:
    /// Loads a whole file; throws InputError naming the file for a missing file or bad YAML.
    static ParamNode loadFile(const std::string& path);
    /// Parses YAML text; sourceName stands for the file in messages.
    static ParamNode loadString(const std::string& text, const std::string& sourceName);

    ParamNode(const ParamNode&);
    ParamNode& operator=(const ParamNode&);
    ~ParamNode();

    bool has(const std::string& key) const;
    /// The sub-mapping under key (required).
    ParamNode child(const std::string& key) const;
    /// The mappings of the list under key (required), each named "key[i]" in messages.
    std::vector<ParamNode> children(const std::string& key) const;
    /// true when key holds a mapping (false when missing or of another kind).
    bool isMapping(const std::string& key) const;
    double getNumber(const std::string& key, const Bound& bound) const;
    double getNumber(const std::string& key, const Bound& bound, double defaultValue) const;
    int getInt(const std::string& key, int lo, int hi) const;
    int getInt(const std::string& key, int lo, int hi, int defaultValue) const;
    bool getBool(const std::string& key, bool defaultValue) const;
    std::string getString(const std::string& key) const;
    std::string getString(const std::string& key, const std::string& defaultValue) const;
    /// One of allowed (error lists them).
    std::string getChoice(const std::string& key, const std::vector<std::string>& allowed,
                          const std::string& defaultValue) const;
    std::vector<double> getNumbers(const std::string& key, const Bound& bound) const;
    /// The non-empty strings of the list under key (required).
    std::vector<std::string> getStrings(const std::string& key) const;
    /// The keys of this mapping in file order (marks none used).
    std::vector<std::string> getKeys() const;
    /// Throws InputError naming file, line and key for every key this node has that was not read.
    void finish() const;

    /// "file:line" of key (or of this mapping when key is empty).
    std::string where(const std::string& key = "") const;
    /// Dotted path of key, e.g. "fibre_types.slow.Tf1".
    std::string path(const std::string& key) const;
    const std::string& getSourceName() const;
    /// Directory of the source file, for resolving relative references.
    std::string getDirectory() const;
    /// The file named by the string under key: relative to this file's directory, else as given (from
    /// the working directory), else under fallbackDirectory when one is given. Throws InputError naming
    /// file, line, key and value, calling the missing file `what` ("muscle file").
    std::string findFile(const std::string& key, const std::string& what,
                         const std::string& fallbackDirectory = "") const;

    /// Runs f (which may throw FieldError for field "x.y") and rethrows with the file and line of
    /// the key the field came from. fieldPrefix is prepended to FieldError fields before lookup.
    template <class F> void rethrowWithLocation(F&& f) const {
        try { f(); } catch (const FieldError& e) { throwLocated(e); }
    }
    [[noreturn]] void throwLocated(const FieldError& e) const;

private:
    struct Impl;
    explicit ParamNode(std::shared_ptr<Impl> impl);
    const YAML::Node& node() const;
    YAML::Node requireKey(const std::string& key) const;
    std::shared_ptr<Impl> impl_;
};

/// The whole file as bytes. Throws InputError naming the path when it cannot be read.
std::string readFileText(const std::string& path);
/// InputError unless `path` (when it exists) is a regular file of at most maxBytes (a folder, a device
/// such as /dev/zero or a pipe would make a reader block or grow without bound).
void checkInputFile(const std::string& path, std::uintmax_t maxBytes);

/// Writes text to path atomically: to a temporary beside it, then rename. Throws InputError naming
/// the path when it cannot be written. Parent directories are created.
void writeFileAtomically(const std::string& path, const std::string& text);

}  // namespace armsim
