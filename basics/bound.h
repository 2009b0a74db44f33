// Bounds of scalar parameters and the check every parameter struct's validate() uses. Framework-free.
#pragma once

#include "basics/errors.h"
#include "basics/format.h"

#include <string>
#include <vector>

namespace armsim {

/// A closed/open interval used to validate one scalar field.
struct Bound {
    double lo = -1e300;      ///< lower bound
    double hi = 1e300;       ///< upper bound
    bool loOpen = false;     ///< true: value must be > lo; false: >= lo
    bool hiOpen = false;     ///< true: value must be < hi; false: <= hi
    const char* unit = "";   ///< unit shown in messages

    static Bound positive(const char* unit = "") { return {0, 1e300, true, false, unit}; }
    static Bound nonNegative(const char* unit = "") { return {0, 1e300, false, false, unit}; }
    static Bound closed(double lo, double hi, const char* unit = "") { return {lo, hi, false, false, unit}; }
    static Bound open(double lo, double hi, const char* unit = "") { return {lo, hi, true, true, unit}; }
    static Bound any(const char* unit = "") { return {-1e300, 1e300, false, false, unit}; }
    bool contains(double v) const;
    std::string describe() const;   ///< e.g. "> 0 (kg)" or "in [0, 1]"
};

/// Bounds of quantities read in several places (command-line options, model, arm and trial files,
/// render settings, Python), so that every entry point refuses the same values.
namespace bounds {
constexpr Bound kHandLoad{0, 50, false, false, "kg"};   ///< a load held in the hand
constexpr Bound kMuscleMass{0, 10, true, false, "kg"};  ///< a muscle's mass (10 L; the largest muscles ~1 kg)
constexpr Bound kTendonLength{0, 2, true, false, "m"};  ///< a muscle's optimal tendon length L0T
constexpr Bound kPathLength{0, 3, true, false, "m"};    ///< a musculotendon path's length (a whole limb's ~1 m)
/// Motor units of one fibre type (Virtual Muscle lumps a muscle's units into a few; 100 + 100 make a 3 s
/// trial of about 1.3 s, 1000 + 1000 one of minutes: docs/reliability.md).
constexpr Bound kMotorUnits{0, 100, false, false, ""};
constexpr Bound kMaxIsometricForce{0, 1e5, true, false, "N"};  ///< a muscle's F0 (the strongest ~10 kN)
/// An integrator's relative accuracy: CPodes refuses much below 1e-12 ("too much accuracy requested").
constexpr Bound kAccuracy{1e-12, 0.1, false, false, ""};
/// A trial of an armsim model: Virtual Muscle's stiff ODE fails its corrector below about 1e-8 (CPodes
/// flag -4: the thesis arm's isometric trial at 1e-9 and 1e-10, the elbow's at 1e-10; measured 2026-11-28).
constexpr Bound kTrialAccuracy{1e-8, 0.1, false, false, ""};
}  // namespace bounds

/// Throws FieldError naming field, value and bound unless value is finite and inside bound.
void checkField(const std::string& field, double value, const Bound& bound);

/// Throws FieldError naming `field` when angles meant in degrees look like radians: every one within
/// [-pi, pi] and one of them not whole (0.52, 1.05, 1.57 are 30, 60 and 90 deg in radians). Whole
/// degrees (0, 1, 2) and any set with an angle past pi pass.
void checkDegreesNotRadians(const std::string& field, const std::vector<double>& degrees);
/// Index of the first value that is not whole (values.size(): none), for naming the entry or line that
/// checkDegreesNotRadians' refusal points at.
std::size_t findFirstFractional(const std::vector<double>& values);

}  // namespace armsim
