// De Groote-Fregly 2016 (OpenSim's DeGrooteFregly2016Muscle, explicit tendon dynamics): the curves
// against their defining points, the steady solve against integration, the moving path through the
// Simbody adapter against a plain integration with the same P(t), and the path's lengthening speed
// against a finite difference of its length.
#include "basics/errors.h"
#include "muscles/degroote2016_muscle.h"
#include "muscles/muscle_force.h"
#include "muscles/muscle_models.h"
#include "muscles/simbody_isometric.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace armsim;
using namespace SimTK;

namespace {

// arm26's BIClong (opensim-models Arm26/arm26.osim): F0 624.3 N, l0 0.1157 m, slack 0.2723 m, no pennation.
DeGroote2016Parameters bicLong(double pennation = 0) {
    DeGroote2016Parameters p;
    p.name = "BIClong";
    p.maxIsometricForce = 624.3;
    p.optimalFiberLength = 0.1157;
    p.tendonSlackLength = 0.2723;
    p.pennationAngleAtOptimal = pennation;
    return p;
}

double column(const Table& t, const char* name, int row) { return t.getRow(row)[t.findColumn(name)]; }

constexpr double kCurveTol = 1e-9;    // the corrected constants put the curves through their points to ~1e-16
constexpr double kSteadyTol = 1e-6;   // steady solve vs integration, relative force
constexpr double kMovingTol = 1e-5;   // Simbody adapter (moving path) vs plain integration, relative force

}  // namespace

TEST(DeGroote2016Curves, PassThroughTheirDefiningPoints) {
    const DeGroote2016Parameters p = bicLong();
    EXPECT_NEAR(calcDeGrooteActiveForceLength(p, 1.0), 1.0, 1e-6);  // b11 chosen so that f_L(1) = 1
    EXPECT_NEAR(calcDeGrooteForceVelocity(0.0), 1.0, kCurveTol);
    EXPECT_NEAR(calcDeGrooteForceVelocity(-1.0), 0.0, kCurveTol);
    for (double v : {-0.9, -0.3, 0.0, 0.4, 0.9}) EXPECT_NEAR(calcDeGrooteForceVelocityInverse(calcDeGrooteForceVelocity(v)), v, kCurveTol);
    EXPECT_NEAR(calcDeGrootePassiveForceLength(p, 0.2), 0.0, kCurveTol);
    EXPECT_NEAR(calcDeGrootePassiveForceLength(p, 1.6), 1.0, kCurveTol);
    EXPECT_NEAR(calcDeGrooteTendonForceLength(p, 1.0), 0.0, kCurveTol);
    EXPECT_NEAR(calcDeGrooteTendonForceLength(p, 1.049), 1.0, kCurveTol);
    EXPECT_NEAR(calcDeGrooteTendonLength(p, calcDeGrooteTendonForceLength(p, 1.03)), 1.03, kCurveTol);
    // Values OpenSim's own tests state (opensim-core testDeGrooteFregly2016Muscle.cpp): the passive
    // multiplier at the optimal length and the force-velocity multiplier at full lengthening speed.
    EXPECT_NEAR(calcDeGrootePassiveForceLength(p, 1.0), 0.0182288, 1e-7);
    EXPECT_NEAR(calcDeGrooteForceVelocity(1.0), 1.794, 1e-3);
    // Wider with active_force_width_scale, same peak.
    DeGroote2016Parameters wide = p;
    wide.activeForceWidthScale = 1.5;
    EXPECT_NEAR(calcDeGrooteActiveForceLength(wide, 1.0), calcDeGrooteActiveForceLength(p, 1.0), kCurveTol);
    EXPECT_GT(calcDeGrooteActiveForceLength(wide, 0.6), calcDeGrooteActiveForceLength(p, 0.6));
}

TEST(DeGroote2016Muscle, SteadySolveEqualsTheEndOfAnIntegration) {
    for (double pennation : {0.0, 0.3}) {
        const DeGroote2016Muscle muscle(bicLong(pennation));
        for (double P : {0.36, 0.39, 0.42})
            for (double U : {0.05, 0.5, 1.0}) {
                const SteadyState ss = muscle.calcSteadyState(P, U);
                ASSERT_TRUE(ss.converged) << ss.message;
                double ydot[2];
                muscle.calcStateDerivative(P, U, ss.states.data(), ydot);
                EXPECT_NEAR(ydot[0], 0.0, 1e-12);
                EXPECT_NEAR(ydot[1], 0.0, 1e-8);
                MuscleIsometricSettings s;
                s.pathLength = P;
                s.activation = ActivationProfile::constant(U);
                s.duration = 3.0;
                s.sampleRate = 10;
                s.integration.accuracy = 1e-8;
                const Table t = runMuscleIsometric(muscle, s);
                EXPECT_NEAR(column(t, "force_N", t.getNumRows() - 1), ss.force, kSteadyTol * ss.force)
                    << "pennation " << pennation << " P " << P << " U " << U;
            }
    }
}

// The insertion slides away at a constant speed v (a very heavy body on a slider): the tendon force
// through Simbody (path speed from virtual power) equals a plain integration with P = P0 + v t, dP/dt = v.
TEST(DeGroote2016Muscle, MovingPathThroughSimbodyEqualsThePlainIntegration) {
    const auto muscle = std::make_shared<DeGroote2016Muscle>(bicLong(0.2));
    const double P0 = 0.37, v = 0.05, U = 0.6;
    MultibodySystem system;
    SimbodyMatterSubsystem matter(system);
    GeneralForceSubsystem forces(system);
    const Body::Rigid heavy(MassProperties(1e12, Vec3(0), UnitInertia(1)));
    MobilizedBody::Translation slider(matter.Ground(), Vec3(0), heavy, Vec3(0));
    const MuscleForce force(forces, muscle, matter.Ground(), Vec3(0), slider, Vec3(0), ActivationProfile::constant(U));
    system.realizeTopology();
    State s = system.getDefaultState();
    slider.setQToFitTranslation(s, Vec3(P0, 0, 0));
    slider.setUToFitLinearVelocity(s, Vec3(v, 0, 0));
    const std::vector<double> y0 = muscle->calcSteadyState(P0, U).states;
    force.setMuscleStates(s, y0);
    IntegrationSettings settings;
    settings.accuracy = 1e-8;
    std::vector<double> simbodyForce, plainForce;
    simulateSampled(system, s, 0.5, 20, {}, settings, [&](const State& st) {
        system.realize(st, Stage::Position);
        simbodyForce.push_back(force.getForce(st));
    });
    std::vector<double> y = y0;
    integrateSampled(
        [&](double t, const double* yy, double* ydot) { muscle->calcMovingStateDerivative(P0 + v * t, v, U, yy, ydot); },
        0.0, y, 0.5, 20, {}, settings, [&](double t, const double* yy) { plainForce.push_back(muscle->calcForce(P0 + v * t, yy)); });
    ASSERT_EQ(simbodyForce.size(), plainForce.size());
    for (std::size_t k = 0; k < plainForce.size(); ++k) EXPECT_NEAR(simbodyForce[k], plainForce[k], kMovingTol * plainForce.back()) << k;
    // Stretching an active muscle raises its force (eccentric), unlike the isometric case.
    EXPECT_GT(plainForce.back(), muscle->calcSteadyState(P0 + v * 0.5, U).force);
}

TEST(DeGroote2016Muscle, RegistryBuildsItAndRefusesBadCoefficients) {
    const DeGroote2016Parameters p = bicLong();
    EXPECT_THROW(DeGroote2016Muscle(DeGroote2016Parameters{}), FieldError);
    DeGroote2016Parameters bad = p;
    bad.activeForceWidthScale = 0.5;  // OpenSim: >= 1
    try {
        DeGroote2016Muscle x(bad);
        ADD_FAILURE();
    } catch (const FieldError& e) {
        EXPECT_NE(std::string(e.what()).find("active_force_width_scale"), std::string::npos) << e.what();
    }
    const MuscleModelType& type = findMuscleModelType("degroote2016");
    EXPECT_EQ(type.coefficientFile, "degroote2016.yaml");
    EXPECT_NE(std::find(type.coefficientKeys.begin(), type.coefficientKeys.end(), "fiber_damping"), type.coefficientKeys.end());
}

// Activation dynamics as De Groote et al. 2016 eqs. (1)-(2) write them (their b = 0.1 smoothing): da/dt =
// [f / (tau_a (0.5 + 1.5 a)) + (1 - f)(0.5 + 1.5 a) / tau_d] (u - a), f = 0.5 + 0.5 tanh(b (u - a)),
// evaluated by hand at points of rise and fall, with the excitation floored at minimum_activation; the
// derivative the model returns equals it, and with a steep switch (b = 100) rise and fall take the
// activation and deactivation time constants.
TEST(DeGroote2016Muscle, ActivationDynamicsAreThePapersEquations) {
    for (double b : {0.1, 100.0}) {
        DeGroote2016Parameters p = bicLong();
        p.activationDynamicsSmoothing = b;
        const DeGroote2016Muscle muscle(p);
        const double P = 0.38;
        for (double a : {0.05, 0.3, 0.9})
            for (double U : {0.0, 0.2, 1.0}) {
                const SteadyState ss = muscle.calcSteadyState(P, 0.5);
                ASSERT_TRUE(ss.converged);
                const double y[2] = {a, ss.states[1]};
                double ydot[2];
                muscle.calcStateDerivative(P, U, y, ydot);
                const double u = std::max(U, p.minimumActivation), z = 0.5 + 1.5 * a;
                const double f = 0.5 + 0.5 * std::tanh(b * (u - a));
                const double expected = (f / (p.activationTimeConstant * z) + (1 - f) * z / p.deactivationTimeConstant) * (u - a);
                EXPECT_NEAR(ydot[0], expected, 1e-12 * std::abs(expected) + 1e-15) << "b " << b << " a " << a << " U " << U;
                if (b == 100 && std::abs(u - a) > 0.1) {  // the switch is a step: one time constant or the other
                    const double tau = u > a ? p.activationTimeConstant * z : p.deactivationTimeConstant / z;
                    EXPECT_NEAR(ydot[0], (u - a) / tau, 1e-6 * std::abs(ydot[0])) << "a " << a << " U " << U;
                }
            }
    }
}
