#include "basics/bound.h"

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

}  // namespace armsim
