// Numeric constants every room uses.
#pragma once

#include <limits>

namespace armsim {

/// Not a number: "not measured", "not estimated" or "does not apply" in result fields.
inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

}  // namespace armsim
