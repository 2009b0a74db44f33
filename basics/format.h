// Number formatting for messages and files. Fixed-format text (reports, CSV cells, overlay labels) is
// written with libfmt (fmt::format("{:.3g}", v)), locale-free; this header adds the one form libfmt
// spells differently.
#pragma once

#include <charconv>
#include <string>

namespace armsim {

/// Shortest decimal form of v that reads back as v, locale-free ("0.1", "1e+300", "nan", "inf"):
/// the form of every number quoted in an error message.
inline std::string formatNumber(double v) {
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, r.ptr);
}

}  // namespace armsim
