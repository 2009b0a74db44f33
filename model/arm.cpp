#include "model/arm.h"

#include "basics/bound.h"
#include "model/geometry.h"

#include <cmath>
#include <stdexcept>

namespace armsim {

using namespace SimTK;

namespace {

// Longitudinal / transverse radius-of-gyration ratios (de Leva 1996, male upper arm 0.158/0.285 and
// forearm 0.121/0.276). Winter's table gives only the transverse radius; the longitudinal inertia
// does not enter the planar pin dynamics but must make a physical inertia.
constexpr double kUpperArmLongitudinalRatio = 0.158 / 0.285;
constexpr double kForearmLongitudinalRatio = 0.121 / 0.276;

// Decoration sizes [m]: visual only.
constexpr double kUpperArmRadius = 0.045;
constexpr double kForearmRadius = 0.035;
constexpr double kHandHalfWidth = 0.045;
constexpr double kHandHalfThickness = 0.018;
constexpr double kMarkerRadius = 0.008;
constexpr double kStrapHalfWidth = 0.012;

const ArmParameters& validated(const ArmParameters& p) {
    p.validate();
    return p;
}

// Mass properties about the body origin of a segment lying along the body's Y axis: mass m, mass
// centre com, transverse radius of gyration k about the mass centre, and a longitudinal one kLong.
MassProperties segmentMassProperties(double m, const Vec3& com, double k, double kLong) {
    const Inertia central(Vec3(m * k * k, m * kLong * kLong, m * k * k));
    return MassProperties(m, com, central.shiftFromMassCenter(-com, m));
}

MassProperties scaleMassProperties(const MassProperties& m, double share) {
    if (share == 1) return m;
    return MassProperties(share * m.getMass(), m.getMassCenter(), m.getUnitInertia());
}

}  // namespace

ArmModel::ArmModel(const ArmParameters& params)
    : params_(validated(params)),
      matter_(system_),
      forces_(system_),
      gravity_(forces_, matter_, -YAxis, params.gravity) {
    const ArmParameters& p = params_;
    origin_ = Vec3(0, p.originDistance, 0);
    insertion_ = Vec3(0, -p.insertionDistance, 0);
    strap_ = Vec3(0, -p.strapDistance, 0);
    hand_ = Vec3(0, -p.calcHandComDistance(), 0);

    // Upper arm: elbow at the origin, shoulder at +Y; COM measured from the shoulder in the table.
    const double Lu = p.upperArmLength;
    const double ku = p.upperArmGyrationFraction * Lu;
    Body::Rigid upperBody(segmentMassProperties(p.calcUpperArmMass(),
                                                Vec3(0, (1 - p.upperArmComFraction) * Lu, 0), ku,
                                                kUpperArmLongitudinalRatio * ku));
    upperArm_ = MobilizedBody::Weld(matter_.updGround(), Transform(), upperBody, Transform());

    // Forearm + hand on a pin about Z at the elbow centre; q = flexion angle.
    const ArmParameters::ForearmRotation& rot = p.forearmRotation;
    const double foreShare = rot.enabled ? 1 - rot.massFraction : 1;
    Body::Rigid foreBody(scaleMassProperties(calcForearmMassProperties(), foreShare));
    forearm_ = MobilizedBody::Pin(upperArm_, Transform(), foreBody, Transform());
    if (rot.enabled) {
        // The pin's Z axis along the rotation axis, in both frames: the radius frame is the forearm's at 0.
        const Vec3 d(rot.axisDirection[0], rot.axisDirection[1], rot.axisDirection[2]);
        const Transform X(Rotation(UnitVec3(d), ZAxis), Vec3(rot.axisPoint[0], rot.axisPoint[1], rot.axisPoint[2]));
        Body::Rigid radiusBody(scaleMassProperties(calcForearmMassProperties(), rot.massFraction));
        radius_ = MobilizedBody::Pin(forearm_, X, radiusBody, X);
        Force::MobilityLinearStop(forces_, radius_, MobilizerQIndex(0), p.stopStiffness, p.stopDissipation,
                                  degToRad(rot.minDeg), degToRad(rot.maxDeg));
    }

    // Soft stops on q = pi - theta: theta in [min, max] <=> q in [pi - max, pi - min].
    elbowStop_ = Force::MobilityLinearStop(forces_, forearm_, MobilizerQIndex(0), p.stopStiffness,
                                           p.stopDissipation,
                                           flexionFromElbowAngle(degToRad(p.maxElbowAngleDeg)),
                                           flexionFromElbowAngle(degToRad(p.minElbowAngleDeg)));

    // Decorations (cylinders and ellipsoids are along their local Y axis).
    const Vec3 skin(0.93, 0.76, 0.62), bone(0.85, 0.85, 0.8), red(0.8, 0.1, 0.1), strapColor(0.9, 0.5, 0.1);
    upperArm_.addBodyDecoration(Transform(Vec3(0, Lu / 2, 0)),
                                DecorativeCylinder(kUpperArmRadius, Lu / 2).setColor(skin));
    upperArm_.addBodyDecoration(Transform(), DecorativeSphere(kUpperArmRadius).setColor(bone));
    upperArm_.addBodyDecoration(Transform(Vec3(0, Lu, 0)), DecorativeSphere(kUpperArmRadius).setColor(skin));
    upperArm_.addBodyDecoration(Transform(origin_), DecorativeSphere(kMarkerRadius).setColor(red));

    const double Lf = p.forearmLength, Lh = p.handLength;
    forearm_.addBodyDecoration(Transform(Vec3(0, -Lf / 2, 0)),
                               DecorativeCylinder(kForearmRadius, Lf / 2).setColor(skin));
    forearm_.addBodyDecoration(Transform(Vec3(0, -Lf - Lh / 2, 0)),
                               DecorativeEllipsoid(Vec3(kHandHalfWidth, Lh / 2, kHandHalfThickness)).setColor(skin));
    forearm_.addBodyDecoration(Transform(insertion_), DecorativeSphere(kMarkerRadius).setColor(red));
    const double strapRadius = (p.strapDistance <= Lf ? kForearmRadius : kHandHalfWidth) * 1.15;
    forearm_.addBodyDecoration(Transform(strap_),
                               DecorativeCylinder(strapRadius, kStrapHalfWidth).setColor(strapColor));
}

MassProperties ArmModel::calcForearmMassProperties() const {
    const ArmParameters& p = params_;
    const double k = p.forearmHandGyrationFraction * p.forearmLength;
    const double m = p.calcForearmHandMass();
    const Vec3 com(0, -p.calcForearmHandComDistance(), 0);
    const MassProperties arm = segmentMassProperties(m, com, k, kForearmLongitudinalRatio * k);
    if (p.handLoad == 0) return arm;
    const Vec3 hand(0, -p.calcHandComDistance(), 0);
    const double total = m + p.handLoad;
    return MassProperties(total, (m * com + p.handLoad * hand) / total,
                          arm.getInertia() + Inertia::pointMassAt(hand, p.handLoad));
}

void ArmModel::requireNotFinalized(const char* what) const {
    if (finalized_)
        throw std::logic_error(std::string("ArmModel::") + what +
                               ": the model is finalized; call it before finalize()");
}

GeneralForceSubsystem& ArmModel::updForces() {
    requireNotFinalized("updForces");
    return forces_;
}

void ArmModel::setHandLoad(double mass) {
    requireNotFinalized("setHandLoad");
    checkField("hand_load", mass, bounds::kHandLoad);
    params_.handLoad = mass;
    forearm_.setDefaultMassProperties(calcForearmMassProperties());
}

const State& ArmModel::finalize() {
    requireNotFinalized("finalize");
    defaultState_ = system_.realizeTopology();
    system_.realizeModel(defaultState_);
    if (params_.forearmRotation.enabled) radius_.lockAt(defaultState_, degToRad(params_.forearmRotation.postureDeg));
    finalized_ = true;
    return defaultState_;
}

const State& ArmModel::getDefaultState() const {
    if (!finalized_) throw std::logic_error("ArmModel::getDefaultState: call finalize() first");
    return defaultState_;
}

void ArmModel::setElbowAngle(State& state, double theta) const {
    forearm_.setQ(state, flexionFromElbowAngle(theta));
}

double ArmModel::getElbowAngle(const State& state) const {
    return elbowAngleFromFlexion(forearm_.getQ(state));
}

void ArmModel::setElbowAngularVelocity(State& state, double thetaDot) const {
    forearm_.setU(state, -thetaDot);
}

double ArmModel::getElbowAngularVelocity(const State& state) const { return -forearm_.getU(state); }

void ArmModel::lockElbow(State& state, double theta) const {
    forearm_.lockAt(state, flexionFromElbowAngle(theta));
}

void ArmModel::unlockElbow(State& state) const { forearm_.unlock(state); }

void ArmModel::lockForearmRotation(State& state, double phi) const {
    if (!hasForearmRotation()) throw std::logic_error("ArmModel::lockForearmRotation: the arm has no forearm rotation");
    radius_.lockAt(state, phi);
}

double ArmModel::getForearmRotation(const State& state) const {
    if (!hasForearmRotation()) throw std::logic_error("ArmModel::getForearmRotation: the arm has no forearm rotation");
    return radius_.getQ(state);
}

double ArmModel::calcForearmHoldingTorque(const State& state) const {
    if (!hasForearmRotation() || !radius_.isLocked(state))
        throw std::logic_error("ArmModel::calcForearmHoldingTorque: no locked forearm rotation");
    if (state.getSystemStage() < Stage::Acceleration)
        throw std::logic_error("ArmModel::calcForearmHoldingTorque: realize the state to Stage::Acceleration first");
    Vector motionForces;
    matter_.findMotionForces(state, motionForces);
    return -motionForces[radius_.getFirstUIndex(state)];
}

double ArmModel::calcPathLength(const State& state) const {
    return (upperArm_.findStationLocationInGround(state, origin_) -
            forearm_.findStationLocationInGround(state, insertion_)).norm();
}

double ArmModel::calcMomentArm(const State& state) const {
    // Elbow centre = Ground origin, so the insertion's Ground position is its lever arm.
    const Vec3 rI = forearm_.findStationLocationInGround(state, insertion_);
    const Vec3 rO = upperArm_.findStationLocationInGround(state, origin_);
    return cross(rI, (rO - rI).normalize())[2];
}

double ArmModel::calcHoldingTorque(const State& state) const {
    if (!forearm_.isLocked(state))
        throw std::logic_error("ArmModel::calcHoldingTorque: the elbow is not locked (call lockElbow)");
    if (state.getSystemStage() < Stage::Acceleration)
        throw std::logic_error("ArmModel::calcHoldingTorque: realize the state to Stage::Acceleration first");
    Vector motionForces;
    matter_.findMotionForces(state, motionForces);
    // Simbody's motion forces enter the equations as M udot = f_applied - f_motion, so the torque the
    // lock applies is their negative; +q is flexion.
    return -motionForces[forearm_.getFirstUIndex(state)];
}

}  // namespace armsim
