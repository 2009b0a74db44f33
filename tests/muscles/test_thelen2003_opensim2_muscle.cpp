// Thelen 2003 as OpenSim 2.x defined it (muscles/thelen2003_opensim2_muscle.h): the curves at their
// defining points and joins, the force-velocity inverse's branches and extrapolations, the linear
// activation dynamics against their closed form, and the steady solve against time integration.
#include "basics/errors.h"
#include "muscles/muscle_models.h"
#include "muscles/simbody_isometric.h"
#include "muscles/thelen2003_opensim2_muscle.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace armsim;

namespace {

// arm26's BIClong as the OpenSim 2 tutorial model gives it: F0 624.3 N, l0 0.1157 m, slack 0.2723 m.
Thelen2003Opensim2Parameters bicLong() {
    Thelen2003Opensim2Parameters p;
    p.name = "BIClong";
    p.maxIsometricForce = 624.3;
    p.optimalFiberLength = 0.1157;
    p.tendonSlackLength = 0.2723;
    return p;
}

double column(const Table& t, const char* name, int row) { return t.getRow(row)[t.findColumn(name)]; }

constexpr double kCurveTol = 1e-12;  // closed-form values of the curves
constexpr double kSteadyTol = 1e-6;  // steady solve vs integration, relative force

}  // namespace

TEST(Thelen2003Opensim2Curves, DefiningValuesAndJoins) {
    const Thelen2003Opensim2Parameters p = bicLong();
    EXPECT_NEAR(calcThelen2ActiveForceLength(p, 1.0), 1.0, kCurveTol);
    EXPECT_NEAR(calcThelen2ActiveForceLength(p, 1.5), std::exp(-0.25 / 0.5), kCurveTol);
    // Passive: e^(k (L - 1) / e0) / e^k, 1 at 1 + e0, joined by a line of the same slope, no offset at 1.
    EXPECT_NEAR(calcThelen2PassiveForceLength(p, 1.6), 1.0, kCurveTol);
    EXPECT_NEAR(calcThelen2PassiveForceLength(p, 1.0), std::exp(-4.0), kCurveTol);
    const double h = 1e-7;
    const double left = (calcThelen2PassiveForceLength(p, 1.6) - calcThelen2PassiveForceLength(p, 1.6 - h)) / h;
    const double right = (calcThelen2PassiveForceLength(p, 1.6 + h) - calcThelen2PassiveForceLength(p, 1.6)) / h;
    EXPECT_NEAR(left, 4 / 0.6, 1e-5);
    EXPECT_NEAR(right, 4 / 0.6, 1e-7);  // a line: exact but for rounding
    // Tendon: 0.001 at slack, the toe's end at 0.609 eps0 with 0.333333 (+ the floor), linear 1.712 / eps0.
    const double toe = 0.609 * 0.033;
    EXPECT_NEAR(calcThelen2TendonForce(p, 0.0), 0.001, kCurveTol);
    EXPECT_NEAR(calcThelen2TendonForce(p, -0.5), 0.0005, kCurveTol);
    EXPECT_NEAR(calcThelen2TendonForce(p, toe), 0.333333 + 0.001 * (1 + toe), 1e-9);
    EXPECT_NEAR(calcThelen2TendonForce(p, toe + 0.01) - calcThelen2TendonForce(p, toe), 0.01 * (1.712 / 0.033 + 0.001), 1e-9);
    EXPECT_NEAR(calcThelen2TendonForce(p, 0.033), 1.712 * (1 - 0.609) + 0.333333 + 0.001 * 1.033, 1e-9);
}

// The inverse: zero velocity at Fv = a f_L; Thelen's two branches with damping d,
// v = (Fv - Fa) / (Fa + Fv / Af + d) shortening and (Fv - Fa) / ((2 + 2 / Af)(Fa Flen - Fv) / (Flen - 1) + d)
// lengthening; continuous and increasing through both extrapolations (Fv < 0, Fv > 0.95 Fa Flen).
TEST(Thelen2003Opensim2Curves, ForceVelocityBranchesAndExtrapolations) {
    const Thelen2003Opensim2Parameters p = bicLong();
    const double a = 0.6, fal = 0.9, Fa = a * fal;
    EXPECT_NEAR(calcThelen2FiberVelocity(p, a, fal, Fa), 0.0, kCurveTol);
    EXPECT_NEAR(calcThelen2FiberVelocity(p, a, fal, 0.3), (0.3 - Fa) / (Fa + 0.3 / 0.3 + 0.05), kCurveTol);
    const double Fl = 0.8;
    EXPECT_NEAR(calcThelen2FiberVelocity(p, a, fal, Fl), (Fl - Fa) / ((2 + 2 / 0.3) * (Fa * 1.8 - Fl) / 0.8 + 0.05), kCurveTol);
    double last = calcThelen2FiberVelocity(p, a, fal, -0.2001);
    for (double Fv = -0.2; Fv <= 1.2; Fv += 1e-4) {
        const double v = calcThelen2FiberVelocity(p, a, fal, Fv);
        EXPECT_GT(v, last) << Fv;
        EXPECT_LT(v - last, 0.05) << "a jump at Fv = " << Fv;
        last = v;
    }
    // Zero activation is read as 1e-6 (OpenSim 2.x): finite velocities.
    EXPECT_TRUE(std::isfinite(calcThelen2FiberVelocity(p, 0.0, fal, 0.01)));
}

// u = 1 from a = 0: a(t) = 1 - e^(-t / tau_act); then u = 0: a decays with tau_deact (no floor).
TEST(Thelen2003Opensim2Muscle, ActivationFollowsTheClosedFormBothWays) {
    const Thelen2003Opensim2Muscle muscle(bicLong());
    MuscleIsometricSettings s;
    s.pathLength = 0.38;
    s.activation = ActivationProfile::step(0.05, 1.0, 0.0);
    s.duration = 0.2;
    s.sampleRate = 1000;
    s.startSteady = false;
    s.integration.accuracy = 1e-9;
    const Table t = runMuscleIsometric(muscle, s);
    for (int row : {10, 30, 50}) {
        const double time = column(t, "time_s", row);
        EXPECT_NEAR(column(t, "active_fraction", row), 1 - std::exp(-time / 0.01), 1e-6) << row;
    }
    const double a50 = 1 - std::exp(-0.05 / 0.01);
    for (int row : {80, 120, 200}) {
        const double time = column(t, "time_s", row);
        EXPECT_NEAR(column(t, "active_fraction", row), a50 * std::exp(-(time - 0.05) / 0.04), 1e-6) << row;
    }
}

TEST(Thelen2003Opensim2Muscle, SteadySolveEqualsTheEndOfAnIntegration) {
    for (double pennation : {0.0, 0.3}) {
        Thelen2003Opensim2Parameters p = bicLong();
        p.pennationAngleAtOptimal = pennation;
        const Thelen2003Opensim2Muscle muscle(p);
        for (double P : {0.34, 0.38, 0.43})
            for (double U : {0.05, 0.4, 1.0}) {
                const SteadyState ss = muscle.calcSteadyState(P, U);
                ASSERT_TRUE(ss.converged) << ss.message;
                double ydot[2];
                muscle.calcStateDerivative(P, U, ss.states.data(), ydot);
                EXPECT_NEAR(ydot[0], 0.0, 1e-12);
                EXPECT_NEAR(ydot[1], 0.0, 1e-9);
                MuscleIsometricSettings s;
                s.pathLength = P;
                s.activation = ActivationProfile::constant(U);
                s.duration = 3.0;
                s.sampleRate = 10;
                s.integration.accuracy = 1e-8;
                const Table t = runMuscleIsometric(muscle, s);
                const double F = column(t, "force_N", t.getNumRows() - 1);
                EXPECT_NEAR(F, ss.force, kSteadyTol * ss.force) << "pennation " << pennation << " P " << P << " U " << U;
            }
    }
}

// One registration line: the registry builds it from morphometry and coefficients, and a bad value names
// the field.
TEST(Thelen2003Opensim2Muscle, RegisteredAndValidated) {
    const MuscleModelType& type = findMuscleModelType("thelen2003_opensim2");
    EXPECT_EQ(type.coefficientFile, "thelen2003_opensim2.yaml");
    Thelen2003Opensim2Parameters p = bicLong();
    p.damping = -0.1;
    try {
        Thelen2003Opensim2Muscle m(p);
        FAIL() << "accepted a negative damping";
    } catch (const FieldError& e) {
        EXPECT_NE(std::string(e.what()).find("damping"), std::string::npos) << e.what();
    }
}
