// Field tables: the one description of a result struct (each field's name, unit and format) from which
// its CSV header and rows, its JSON object and any line format built on CSV (the study journal) are
// written and read back. A result gains a column by gaining a row in its table.
#pragma once

#include "basics/csv.h"

#include <nlohmann/json.hpp>

#include <charconv>
#include <cmath>
#include <functional>
#include <stdexcept>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace armsim {

/// Reads a CSV number cell: the whole cell, locale-free ("inf" and "-inf" too); an empty cell is NaN.
inline bool parseCsvNumber(const std::string& cell, double& v) {
    if (cell.empty()) {
        v = std::numeric_limits<double>::quiet_NaN();
        return true;
    }
    const char* b = cell.data();
    const auto r = std::from_chars(b, b + cell.size(), v);
    return r.ec == std::errc() && r.ptr == b + cell.size();
}

/// Reads a CSV integer cell (the whole cell; not empty).
inline bool parseCsvInteger(const std::string& cell, long& v) {
    const char* b = cell.data();
    const auto r = std::from_chars(b, b + cell.size(), v);
    return !cell.empty() && r.ec == std::errc() && r.ptr == b + cell.size();
}

/// One field of a result struct T.
template <class T>
struct Field {
    std::string name;   ///< CSV column and JSON key, unit suffixed as the house spells it ("mass_kg")
    std::string unit;   ///< of the written value: an SI unit, "%", "mm", "1" (dimensionless) or "" (text, code)
    std::function<void(const T&, CsvRow&)> write;               ///< appends the field's cell
    std::function<bool(const std::string&, T&)> read;           ///< the cell back; false: malformed
    std::function<nlohmann::json(const T&)> toJson;             ///< the JSON value (null for a missing number)
    /// The value in SI units (a % field as a fraction, mm as m; a flag as -1/0/1) under its SI name
    /// ("mass_error_pct" -> "mass_error", "tendon_error_mm" -> "tendon_error_m"): what Python returns.
    std::string siName;
    std::function<nlohmann::json(const T&)> toSi;
};

/// A scaled field's SI name: "_pct" (scale 100) dropped, "_mm" (scale 1000) made "_m".
inline std::string getSiFieldName(const std::string& name, double scale) {
    auto endsWith = [&](const std::string& tail) {
        return name.size() > tail.size() && name.compare(name.size() - tail.size(), tail.size(), tail) == 0;
    };
    if (scale == 1) return name;
    if (scale == 100 && endsWith("_pct")) return name.substr(0, name.size() - 4);
    if (scale == 1000 && endsWith("_mm")) return name.substr(0, name.size() - 3) + "_m";
    throw std::logic_error("field '" + name + "' is written scaled by " + std::to_string(scale) +
                           ": expected a name ending in _pct (100) or _mm (1000)");
}

/// A result struct's fields in column order.
template <class T>
class FieldTable {
public:
    explicit FieldTable(std::vector<Field<T>> fields) : fields_(std::move(fields)) {}
    const std::vector<Field<T>>& getFields() const { return fields_; }
    std::vector<std::string> getNames() const {
        std::vector<std::string> names;
        for (const Field<T>& f : fields_) names.push_back(f.name);
        return names;
    }
    std::string getHeader() const {
        std::string header;
        for (const Field<T>& f : fields_) header += (header.empty() ? "" : ",") + f.name;
        return header;
    }
    CsvRow formatRow(const T& r) const {
        CsvRow row;
        for (const Field<T>& f : fields_) f.write(r, row);
        return row;
    }
    /// A whole CSV file of the rows, header first.
    std::string formatCsv(const std::vector<T>& rows) const {
        CsvText csv(getNames());
        for (const T& r : rows) csv.addRow(formatRow(r));
        return csv.getText();
    }
    /// Reads a row's cells into r (fields without a reader are skipped); false when the count differs
    /// or a cell is malformed.
    bool parseRow(const std::vector<std::string>& cells, T& r) const {
        if (cells.size() != fields_.size()) return false;
        for (std::size_t i = 0; i < fields_.size(); ++i)
            if (fields_[i].read && !fields_[i].read(cells[i], r)) return false;
        return true;
    }
    nlohmann::ordered_json toJson(const T& r) const {
        nlohmann::ordered_json j = nlohmann::ordered_json::object();
        for (const Field<T>& f : fields_) j[f.name] = f.toJson(r);
        return j;
    }

private:
    std::vector<Field<T>> fields_;
};

// Field makers. `at` gives the member of a (const or not) T, e.g. [](auto& r) -> auto& { return r.mass; }.

/// A number written as scale * member (e.g. 100 for a fraction shown in %), shortest round-trip form or
/// `digits` significant digits; missing (NaN) is an empty cell and a JSON null. Read back as cell / scale
/// (exact when scale is 1 and digits 0).
template <class T, class At>
Field<T> numberField(const std::string& name, const std::string& unit, At at, double scale = 1, int digits = 0) {
    return {name, unit,
            [at, scale, digits](const T& r, CsvRow& row) {
                const double v = scale * double(at(r));
                if (digits > 0) row.addNumber(v, digits);
                else row.addNumber(v);
            },
            [at, scale](const std::string& s, T& r) {
                double v = 0;
                if (!parseCsvNumber(s, v)) return false;
                at(r) = static_cast<std::remove_reference_t<decltype(at(r))>>(scale == 1 ? v : v / scale);
                return true;
            },
            [at, scale](const T& r) {
                const double v = scale * double(at(r));
                return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
            },
            getSiFieldName(name, scale),
            [at](const T& r) {
                const double v = double(at(r));
                return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
            }};
}

template <class T, class At>
Field<T> integerField(const std::string& name, const std::string& unit, At at) {
    return {name, unit, [at](const T& r, CsvRow& row) { row.addInteger((long long)(at(r))); },
            [at](const std::string& s, T& r) {
                long v = 0;
                if (!parseCsvInteger(s, v)) return false;
                at(r) = static_cast<std::remove_reference_t<decltype(at(r))>>(v);
                return true;
            },
            [at](const T& r) { return nlohmann::json((long long)(at(r))); }, name,
            [at](const T& r) { return nlohmann::json((long long)(at(r))); }};
}

template <class T, class At>
Field<T> textField(const std::string& name, At at) {
    return {name, "", [at](const T& r, CsvRow& row) { row.addText(at(r)); },
            [at](const std::string& s, T& r) { return at(r) = s, true; },
            [at](const T& r) { return nlohmann::json(at(r)); }, name, [at](const T& r) { return nlohmann::json(at(r)); }};
}

/// A yes/no written 1/0 (JSON true/false).
template <class T, class At>
Field<T> boolField(const std::string& name, At at) {
    return {name, "", [at](const T& r, CsvRow& row) { row.addInteger(at(r) ? 1 : 0); },
            [at](const std::string& s, T& r) {
                if (s != "0" && s != "1") return false;
                return at(r) = s == "1", true;
            },
            [at](const T& r) { return nlohmann::json(bool(at(r))); }, name,
            [at](const T& r) { return nlohmann::json(bool(at(r))); }};
}

/// An int member that is 1/0 or -1 for "not known" (e.g. covered by an interval or not, no interval):
/// written 1, 0 or an empty cell (JSON true, false, null).
template <class T, class At>
Field<T> flagField(const std::string& name, At at) {
    return {name, "",
            [at](const T& r, CsvRow& row) {
                if (at(r) < 0) row.addEmpty();
                else row.addInteger(at(r));
            },
            [at](const std::string& s, T& r) {
                if (s.empty()) return at(r) = -1, true;
                if (s != "0" && s != "1") return false;
                return at(r) = s == "1", true;
            },
            [at](const T& r) { return at(r) < 0 ? nlohmann::json(nullptr) : nlohmann::json(at(r) == 1); }, name,
            [at](const T& r) { return nlohmann::json(int(at(r))); }};
}

}  // namespace armsim
