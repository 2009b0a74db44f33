// The Simbody arm (model/arm.h): stations vs closed forms, virtual work, holding torque, energy
// conservation, joint stops and the force hook.
#include "basics/errors.h"
#include "model/arm.h"
#include "model/geometry.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>

namespace armsim {
namespace {

using namespace SimTK;

constexpr double kStationTol = 1e-12;  // [m] station geometry vs closed form: rounding only
constexpr double kThesisRoundingCm = 0.01;
// Central difference of the station path length, step 1e-6 rad: rounding ~eps*P/step ~1e-10 m.
constexpr double kDerivativeStep = 1e-6;
constexpr double kVirtualWorkTol = 1e-8;  // [m]
constexpr double kTorqueRelTol = 1e-9;

const double kAnglesDeg[] = {40, 45, 60, 75, 90, 120, 150, 179};

// Integrates from state to tEnd, calling f on every internal step's state.
void simulate(const ArmModel& arm, const State& state, double tEnd, double accuracy,
              const std::function<void(const State&)>& f) {
    RungeKuttaMersonIntegrator integ(arm.getSystem());
    integ.setAccuracy(accuracy);
    integ.setReturnEveryInternalStep(true);
    integ.initialize(state);
    f(integ.getState());
    while (integ.getTime() < tEnd) {
        integ.stepTo(tEnd);
        ASSERT_FALSE(integ.isSimulationOver() && integ.getTime() < tEnd)
            << Integrator::getTerminationReasonString(integ.getTerminationReason());
        f(integ.getState());
    }
}

TEST(ArmModel, StationsMatchClosedForms) {
    ArmModel arm{ArmParameters()};
    State s = arm.finalize();
    const ArmParameters& p = arm.getParameters();
    for (double deg : kAnglesDeg) {
        const double th = degToRad(deg);
        arm.setElbowAngle(s, th);
        arm.getSystem().realize(s, Stage::Position);
        EXPECT_NEAR(arm.getElbowAngle(s), th, kStationTol);
        EXPECT_NEAR(arm.calcPathLength(s), calcBicepsPathLength(p.originDistance, p.insertionDistance, th),
                    kStationTol) << deg;
        EXPECT_NEAR(arm.calcMomentArm(s), calcBicepsMomentArm(p.originDistance, p.insertionDistance, th),
                    kStationTol) << deg;
        // The strap station is at d1 from the elbow centre, on the forearm axis at angle theta to +Y.
        const Vec3 strap = arm.getForearm().findStationLocationInGround(s, arm.getStrapStation());
        EXPECT_NEAR(strap.norm(), p.strapDistance, kStationTol);
        EXPECT_NEAR(std::acos(strap[1] / strap.norm()), th, 1e-9) << deg;  // acos loses digits near 0, pi
        EXPECT_GT(strap[0], 0) << "flexed forearm points anterior (+X)";
    }
    arm.setElbowAngle(s, degToRad(90));
    arm.getSystem().realize(s, Stage::Position);
    EXPECT_NEAR(100 * arm.calcPathLength(s), 37.48, kThesisRoundingCm);
}

TEST(ArmModel, MomentArmEqualsDerivativeOfStationPathLength) {
    ArmModel arm{ArmParameters()};
    State s = arm.finalize();
    const auto pathAt = [&](double th) {
        arm.setElbowAngle(s, th);
        arm.getSystem().realize(s, Stage::Position);
        return arm.calcPathLength(s);
    };
    for (double deg : kAnglesDeg) {
        const double th = degToRad(deg);
        const double dP = (pathAt(th + kDerivativeStep) - pathAt(th - kDerivativeStep)) / (2 * kDerivativeStep);
        pathAt(th);
        EXPECT_NEAR(arm.calcMomentArm(s), dP, kVirtualWorkTol) << deg;
    }
}

// m g r sin(theta) by hand from the parameters, plus a hand load at the hand COM.
double gravityTorqueByHand(const ArmParameters& p, double theta) {
    const double m = p.forearmHandMassFraction * p.bodyMass;
    const double r = p.forearmHandComFraction * p.forearmLength;
    const double rh = p.handComFraction * p.forearmLength;
    return p.gravity * (m * r + p.handLoad * rh) * std::sin(theta);
}

TEST(ArmModel, HoldingTorqueBalancesGravity) {
    for (double load : {0.0, 2.5}) {
        ArmParameters p;
        p.handLoad = load;
        ArmModel arm(p);
        State s = arm.finalize();
        for (double deg : {45.0, 90.0, 135.0, 170.0}) {
            arm.lockElbow(s, degToRad(deg));
            arm.getSystem().realize(s, Stage::Acceleration);
            const double expected = gravityTorqueByHand(p, degToRad(deg));
            EXPECT_NEAR(arm.calcHoldingTorque(s), expected, kTorqueRelTol * expected) << deg << " deg, load " << load;
            EXPECT_NEAR(arm.getForearm().getOneUDot(s, MobilizerUIndex(0)), 0, 1e-12);
        }
        arm.unlockElbow(s);
        arm.getSystem().realize(s, Stage::Acceleration);
        EXPECT_THROW(arm.calcHoldingTorque(s), std::logic_error);
    }
}

TEST(ArmModel, ReleasedForearmAcceleratesLikeAPendulum) {
    // Checks the inertia about the elbow (MassProperties must hold it about the body origin):
    // d2theta/dt2 = m g r sin(theta) / (m (k^2 + r^2)) from rest, k = radius of gyration about the COM.
    const ArmParameters p;
    ArmModel arm(p);
    State s = arm.finalize();
    const double m = p.forearmHandMassFraction * p.bodyMass, r = p.forearmHandComFraction * p.forearmLength;
    const double k = p.forearmHandGyrationFraction * p.forearmLength;
    for (double deg : {60.0, 90.0, 150.0}) {
        arm.setElbowAngle(s, degToRad(deg));
        arm.getSystem().realize(s, Stage::Acceleration);
        const double expected = m * p.gravity * r * std::sin(degToRad(deg)) / (m * (k * k + r * r));
        const double thetaDDot = -arm.getForearm().getOneUDot(s, MobilizerUIndex(0));
        EXPECT_NEAR(thetaDDot, expected, kTorqueRelTol * expected) << deg << " deg";
    }
}

TEST(ArmModel, SetHandLoadBeforeFinalizeEqualsParameter) {
    ArmParameters p;
    p.handLoad = 1.5;
    ArmModel viaParams(p), viaSetter{ArmParameters()};
    viaSetter.setHandLoad(1.5);
    State a = viaParams.finalize(), b = viaSetter.finalize();
    viaParams.lockElbow(a, 1.0);
    viaSetter.lockElbow(b, 1.0);
    viaParams.getSystem().realize(a, Stage::Acceleration);
    viaSetter.getSystem().realize(b, Stage::Acceleration);
    EXPECT_NEAR(viaSetter.calcHoldingTorque(b), viaParams.calcHoldingTorque(a), 1e-12);
    EXPECT_THROW(viaSetter.setHandLoad(1), std::logic_error);
}

TEST(ArmModel, ForceHookAddsTorqueBeforeFinalize) {
    constexpr double kFlexionTorque = 3.0;  // N m, stands in for the muscle
    ArmModel arm{ArmParameters()};
    Force::MobilityConstantForce(arm.updForces(), arm.getForearm(), MobilizerUIndex(0), kFlexionTorque);
    State s = arm.finalize();
    EXPECT_THROW(arm.updForces(), std::logic_error);
    arm.lockElbow(s, degToRad(90));
    arm.getSystem().realize(s, Stage::Acceleration);
    const double expected = gravityTorqueByHand(arm.getParameters(), degToRad(90)) - kFlexionTorque;
    EXPECT_NEAR(arm.calcHoldingTorque(s), expected, kTorqueRelTol * std::abs(expected));
}

TEST(ArmModel, FreeSwingConservesEnergyIncludingStop) {
    // No stop dissipation; released at rest at 90 deg, the forearm falls into the extension stop
    // (theta = 180 deg, ~3 deg deep) and bounces. Energy includes the stop's k x^2 / 2; without it the
    // total would dip by ~m g r at each bounce. RK-Merson at accuracy 1e-8 over 2 s: measured drift
    // 7e-8 m g r; the tolerance 1e-6 m g r leaves room for the accumulation of local errors.
    constexpr double kAccuracy = 1e-8, kDuration = 2.0, kEnergyRelTol = 1e-6;
    ArmParameters p;
    p.stopDissipation = 0;
    ArmModel arm(p);
    State s = arm.finalize();
    arm.setElbowAngle(s, degToRad(90));
    const double scale = gravityTorqueByHand(p, kPi / 2);  // m g r [J]
    double e0 = NaN, maxDrift = 0, maxTheta = 0;
    int bounces = 0;
    double lastRate = 0;
    simulate(arm, s, kDuration, kAccuracy, [&](const State& st) {
        arm.getSystem().realize(st, Stage::Dynamics);
        const double e = arm.getSystem().calcEnergy(st);
        if (std::isnan(e0)) e0 = e;
        maxDrift = std::max(maxDrift, std::abs(e - e0));
        maxTheta = std::max(maxTheta, arm.getElbowAngle(st));
        const double rate = arm.getElbowAngularVelocity(st);
        if (lastRate > 0 && rate <= 0) ++bounces;
        lastRate = rate;
    });
    EXPECT_GT(maxTheta, kPi) << "the swing must penetrate the extension stop";
    EXPECT_GE(bounces, 2);
    EXPECT_LT(maxDrift, kEnergyRelTol * scale) << "drift " << maxDrift << " J of " << scale << " J";
}

// Largest stop penetration [rad] energy allows: the stop's k x^2 / 2 cannot exceed the initial
// kinetic energy plus the largest gravitational energy the forearm can release (dissipation >= 0).
double penetrationBound(const ArmParameters& p, double theta0, double thetaDot0) {
    const double m = p.calcForearmHandMass(), r = p.calcForearmHandComDistance();
    const double k = p.forearmHandGyrationFraction * p.forearmLength;
    const double kinetic = 0.5 * m * (k * k + r * r) * thetaDot0 * thetaDot0;
    const double release = m * p.gravity * r * (1 + std::cos(theta0));  // COM height above its lowest point
    return std::sqrt(2 * (kinetic + release) / p.stopStiffness);
}

TEST(ArmModel, JointStopsKeepElbowInRange) {
    const ArmParameters p;
    const double lo = degToRad(p.minElbowAngleDeg), hi = degToRad(p.maxElbowAngleDeg);
    struct Start { double thetaDeg, thetaDot; };
    for (const Start& start : {Start{60, -6.0}, Start{150, 6.0}}) {  // into the flexion / extension stop
        ArmModel arm(p);
        State s = arm.finalize();
        arm.setElbowAngle(s, degToRad(start.thetaDeg));
        arm.setElbowAngularVelocity(s, start.thetaDot);
        const double bound = penetrationBound(p, degToRad(start.thetaDeg), start.thetaDot);
        ASSERT_LT(bound, degToRad(6)) << "the bound must be small to mean anything";
        double minTheta = kPi, maxTheta = 0;
        simulate(arm, s, 1.5, 1e-6, [&](const State& st) {
            minTheta = std::min(minTheta, arm.getElbowAngle(st));
            maxTheta = std::max(maxTheta, arm.getElbowAngle(st));
        });
        SCOPED_TRACE(::testing::Message() << "start " << start.thetaDeg << " deg, " << start.thetaDot
                                          << " rad/s; penetration bound " << radToDeg(bound) << " deg");
        EXPECT_GE(minTheta, lo - bound);
        EXPECT_LE(maxTheta, hi + bound);
        if (start.thetaDot < 0) {
            EXPECT_LT(minTheta, lo) << "must have reached the flexion stop";
        }
        EXPECT_GT(maxTheta, hi) << "must have reached the extension stop";
    }
}

TEST(ArmModel, InvalidParametersRejectedAtConstruction) {
    ArmParameters p;
    p.forearmHandMassFraction = -0.1;
    try {
        ArmModel arm(p);
        FAIL() << "negative mass fraction accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("forearm_hand.mass_fraction"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace armsim
