// Elbow angle conventions and the closed-form biceps geometry of the thesis (sections 5.2.1, 5.2.2).
// Pure functions, no Simbody. Radians everywhere here; degrees only at user boundaries (files, CLI),
// converted with degToRad / radToDeg.
//
// Angles:
//   theta  included elbow angle between upper arm and forearm: pi (180 deg) = fully extended,
//          smaller = more flexed. The thesis's "elbow angle" (6.1.2).
//   q      flexion angle = pi - theta, the Simbody pin coordinate (0 = extended).
//
// Geometry (van Zuylen 1988, thesis 5.2.2): the biceps is a straight line from its origin, at
// distance A from the elbow centre along the upper arm, to its insertion, at distance B along the
// forearm (both points on the segment axes through the elbow centre).
#pragma once

#include "basics/angles.h"

#include <vector>

namespace armsim {

/// The thesis's MVC elbow angles theta [deg] (6.1.2; assets/protocols/mvc_force_angle.yaml).
inline constexpr double kThesisMvcAnglesDeg[] = {45, 60, 90, 120, 150};
/// The same five angles as elbow flexion [deg, 0 = extended], most flexed first (135 .. 30): the
/// torque protocols' and the elbow validation's default, derived from kThesisMvcAnglesDeg.
inline std::vector<double> getThesisMvcFlexionDeg() {
    std::vector<double> flexion;
    for (double theta : kThesisMvcAnglesDeg) flexion.push_back(180.0 - theta);
    return flexion;
}
/// Flexion angle q (pin coordinate, 0 = extended) from the included elbow angle theta [rad].
constexpr double flexionFromElbowAngle(double theta) { return kPi - theta; }
/// Included elbow angle theta (pi = extended) from the flexion angle q [rad].
constexpr double elbowAngleFromFlexion(double q) { return kPi - q; }

/// Biceps path length P(theta) = sqrt(A^2 + B^2 - 2 A B cos theta) [m], the law of cosines in the
/// triangle elbow-origin-insertion. A, B [m], theta [rad]. P(pi) = A + B.
double calcBicepsPathLength(double A, double B, double theta);

/// Biceps flexion moment arm h(theta) = A B sin(theta) / P(theta) [m]: the distance from the elbow
/// centre to the line of action. Equals dP/dtheta (virtual work): a tension F in the path produces a
/// flexion torque F h. Zero at theta = pi.
double calcBicepsMomentArm(double A, double B, double theta);

/// Angle phi at the insertion between the forearm (insertion to elbow) and the muscle line (insertion
/// to origin), thesis eq. 5.1: tan phi = A sin theta / (B - A cos theta) [rad]. h = B sin phi.
double calcInsertionAngle(double A, double B, double theta);

/// Elbow torque of the transducer strap [N m]: F_T sin(beta) d1, with strapForce F_T [N], beta the
/// angle between the strap and the forearm axis [rad] (pi/2 = perpendicular) and d1 the elbow-strap
/// distance [m].
double calcStrapTorque(double strapForce, double beta, double strapDistance);

/// The thesis's biceps force estimate from the strap force (5.2.1), taken literally:
///     F_B cos(gamma) d2 = F_T sin(beta) d1,   gamma = alpha - 90 deg,   d1/d2 = ratio (thesis: 6),
/// so F_B = F_T sin(beta) ratio / sin(alpha) [N].
/// Our reading of the symbols: alpha is the included elbow angle theta and beta the strap-forearm
/// angle. Then cos(gamma) = sin(theta) is the forearm-normal fraction of a force PARALLEL TO THE UPPER
/// ARM: the thesis treats the biceps as running along the upper arm (origin infinitely far, A/B -> inf)
/// and uses a fixed ratio d1/d2 instead of the subject's strap and insertion distances. Compared with
/// the exact calcBicepsForceFromTorque(calcStrapTorque(...), h) it is off by the factor
/// (A / P(theta)) * (ratio B / d1): about -1.3 % at 90 deg, +12 % at 45 deg, -12.5 % at 150 deg for the
/// thesis geometry with d1 = 6 B. (Passing alpha = calcInsertionAngle(A, B, theta) instead makes the
/// angle part exact.) Gravity is not in the equation: the transducer must be tared.
/// Throws InputError unless alpha is in (0, pi) and ratio > 0.
double calcBicepsForceFixedRatio(double strapForce, double alpha, double beta, double ratio = 6.0);

/// The exact biceps force that balances a flexion holding torque [N m] through the moment arm
/// h(theta) [m]: F_B = torque / h. Throws InputError unless momentArm > 0.
double calcBicepsForceFromTorque(double holdingTorque, double momentArm);

}  // namespace armsim
