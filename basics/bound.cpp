#include "basics/bound.h"

#include "basics/angles.h"

#include <cmath>

namespace armsim {

bool Bound::contains(double v) const {
    if (!std::isfinite(v)) return false;
    if (loOpen ? !(v > lo) : !(v >= lo)) return false;
    if (hiOpen ? !(v < hi) : !(v <= hi)) return false;
    return true;
}

std::string Bound::describe() const {
    const bool hasLo = lo > -1e299, hasHi = hi < 1e299;
    std::string s;
    if (hasLo && hasHi)
        s = std::string("in ") + (loOpen ? "(" : "[") + formatNumber(lo) + ", " + formatNumber(hi) +
            (hiOpen ? ")" : "]");
    else if (hasLo)
        s = std::string(loOpen ? "> " : ">= ") + formatNumber(lo);
    else if (hasHi)
        s = std::string(hiOpen ? "< " : "<= ") + formatNumber(hi);
    else
        s = "a finite number";
    if (unit && *unit) s += std::string(" (") + unit + ")";
    return s;
}

void checkField(const std::string& field, double value, const Bound& bound) {
    if (!bound.contains(value))
        throw FieldError(field, "= " + formatNumber(value) + ": expected " + bound.describe());
}

void checkDegreesNotRadians(const std::string& field, const std::vector<double>& degrees) {
    // pi as typed to three places (3.142) still counts as within pi.
    constexpr double kWhole = 1e-9, kTyped = 1e-3;
    bool fractional = false;
    for (double a : degrees) {
        if (!std::isfinite(a) || std::abs(a) > kPi + kTyped) return;
        fractional = fractional || std::abs(a - std::round(a)) > kWhole;
    }
    if (!fractional) return;
    std::string typed, asDegrees;
    for (std::size_t k = 0; k < degrees.size() && k < 5; ++k) {
        typed += (k ? ", " : "") + formatNumber(degrees[k]);
        asDegrees += (k ? ", " : "") + formatNumber(std::round(radToDeg(degrees[k]) * 10) / 10);
    }
    if (degrees.size() > 5) typed += ", ...", asDegrees += ", ...";
    throw FieldError(field, "= " + typed + ": expected degrees; every angle is within pi and not all are whole, as "
                            "radians would be (in degrees: " + asDegrees + ")");
}

std::size_t findFirstFractional(const std::vector<double>& values) {
    for (std::size_t k = 0; k < values.size(); ++k)
        if (values[k] != std::round(values[k])) return k;
    return values.size();
}

}  // namespace armsim
