// pi and angle units, once for the whole project. Radians inside; degrees only at user boundaries.
#pragma once

#include <cmath>

namespace armsim {

constexpr double kPi = 3.14159265358979323846;

/// Degrees to radians.
constexpr double degToRad(double deg) { return deg * (kPi / 180.0); }
/// Radians to degrees.
constexpr double radToDeg(double rad) { return rad * (180.0 / kPi); }
/// Degrees (or deg/s) of an angle (or rate) a user gave in degrees and armsim holds in radians, rounded
/// to 1e-9: the round trip's last-bit noise removed (60 deg comes back as 59.99999999999999), so bound
/// checks and messages see the value as typed.
inline double cleanDegrees(double rad) { return std::round(radToDeg(rad) * 1e9) / 1e9; }

}  // namespace armsim
