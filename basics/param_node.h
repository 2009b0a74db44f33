// Strict reading of armsim's YAML parameter files. Framework-free (yaml-cpp only).
//
// Every user error becomes an armsim::InputError whose message names the file, the line, the field,
// the offending value and what was expected, e.g.
//   "assets/muscles/biceps.yaml:4: field 'mass' = -0.3: expected > 0 (kg)".
#pragma once

#include "basics/bound.h"
#include "basics/errors.h"

#include <map>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace YAML { class Node; }

namespace armsim {

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

}  // namespace armsim
