// pi and angle units, once for the whole project. Radians inside; degrees only at user boundaries.
#pragma once

namespace armsim {

constexpr double kPi = 3.14159265358979323846;

/// Degrees to radians.
constexpr double degToRad(double deg) { return deg * (kPi / 180.0); }
/// Radians to degrees.
constexpr double radToDeg(double rad) { return rad * (180.0 / kPi); }

}  // namespace armsim
