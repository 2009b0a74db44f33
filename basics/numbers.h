// Numeric constants every room uses.
#pragma once

#include <cctype>
#include <limits>

namespace armsim {

/// Not a number: "not measured", "not estimated" or "does not apply" in result fields.
inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// true for text strtod would read as hexadecimal ("0x258", "-0X1p-2"): every reader takes decimal
/// numbers only (the YAML files already did; a CSV cell or an option read 0x258 as 600).
inline bool isHexadecimalText(const char* s) {
    while (std::isspace(static_cast<unsigned char>(*s))) ++s;
    if (*s == '+' || *s == '-') ++s;
    return s[0] == '0' && (s[1] == 'x' || s[1] == 'X');
}

}  // namespace armsim
