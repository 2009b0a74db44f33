#include "basics/format.h"

#include <fmt/format.h>

#include <cmath>

namespace armsim {

// Out of line: libfmt's templates instantiated in a translation unit that has `using namespace SimTK`
// meet SimTK's operator templates (an ambiguous, non-constexpr comparison).
std::string formatNumber(double v, int significantDigits) { return fmt::format("{:.{}g}", v, significantDigits); }

std::string formatBytes(double bytes) {
    const char* units[] = {"B", "kB", "MB", "GB", "TB"};
    int u = 0;
    while (u < 4 && std::abs(bytes) >= 1000) bytes /= 1000, ++u;
    return fmt::format("{:.3g} {}", bytes, units[u]);
}

}  // namespace armsim
