// Number formatting for messages and files. Fixed-format text (reports, CSV cells, overlay labels) is
// written with libfmt (fmt::format("{:.3g}", v)), locale-free; this header adds the one form libfmt
// spells differently.
#pragma once

#include <charconv>
#include <string>
#include <vector>

namespace armsim {

/// Shortest decimal form of v that reads back as v, locale-free ("0.1", "1e+300", "nan", "inf"):
/// the form of every number quoted in an error message.
inline std::string formatNumber(double v) {
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, r.ptr);
}

/// v with `significantDigits` (1..17) significant digits in printf's %g form ("0.33599", "1e-05",
/// "inf"): numbers in descriptions and progress messages, where the round-trip form would be noise.
std::string formatNumber(double v, int significantDigits);
/// A duration for a progress message: "42s", "3m05s", "2h10m"; "?" when not finite.
std::string formatDuration(double seconds);
/// A size in bytes for a message, 3 significant digits in B, kB, MB or GB (decimal): "15 GB", "1.5 kB".
std::string formatBytes(double bytes);

/// Numbers as a comma-separated list in formatNumber's form ("15,30,45"), as list options take them.
inline std::string formatList(const std::vector<double>& values) {
    std::string s;
    for (double v : values) s += (s.empty() ? "" : ",") + formatNumber(v);
    return s;
}

/// Names as a comma-separated list ("mass,optimal_tendon_length").
inline std::string formatList(const std::vector<std::string>& names) {
    std::string s;
    for (std::size_t i = 0; i < names.size(); ++i) s += (i ? "," : "") + names[i];
    return s;
}

}  // namespace armsim
