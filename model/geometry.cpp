#include "model/geometry.h"

#include "basics/bound.h"

#include <cmath>

namespace armsim {

double calcBicepsPathLength(double A, double B, double theta) {
    return std::sqrt(A * A + B * B - 2 * A * B * std::cos(theta));
}

double calcBicepsMomentArm(double A, double B, double theta) {
    return A * B * std::sin(theta) / calcBicepsPathLength(A, B, theta);
}

double calcInsertionAngle(double A, double B, double theta) {
    return std::atan2(A * std::sin(theta), B - A * std::cos(theta));
}

double calcStrapTorque(double strapForce, double beta, double strapDistance) {
    return strapForce * std::sin(beta) * strapDistance;
}

double calcBicepsForceFixedRatio(double strapForce, double alpha, double beta, double ratio) {
    checkField("alpha", cleanDegrees(alpha), Bound::open(0, 180, "deg"));
    checkField("d1/d2 ratio", ratio, Bound::positive());
    return strapForce * std::sin(beta) * ratio / std::sin(alpha);
}

double calcBicepsForceFromTorque(double holdingTorque, double momentArm) {
    checkField("moment arm", momentArm, Bound::positive("m"));
    return holdingTorque / momentArm;
}

}  // namespace armsim
