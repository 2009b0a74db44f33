#include "basics/format.h"

#include <fmt/format.h>

#include <cmath>

namespace armsim {

// Out of line: libfmt's templates instantiated in a translation unit that has `using namespace SimTK`
// meet SimTK's operator templates (an ambiguous, non-constexpr comparison).
std::string formatNumber(double v, int significantDigits) { return fmt::format("{:.{}g}", v, significantDigits); }

std::string formatDuration(double seconds) {
    if (!std::isfinite(seconds)) return "?";
    const long s = long(std::lround(seconds));
    if (s >= 3600) return fmt::format("{}h{:02}m", s / 3600, s / 60 % 60);
    if (s >= 60) return fmt::format("{}m{:02}s", s / 60, s % 60);
    return fmt::format("{}s", s);
}

std::string formatBytes(double bytes) {
    const char* units[] = {"B", "kB", "MB", "GB", "TB"};
    int u = 0;
    while (u < 4 && std::abs(bytes) >= 1000) bytes /= 1000, ++u;
    return fmt::format("{:.3g} {}", bytes, units[u]);
}

}  // namespace armsim
