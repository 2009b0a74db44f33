// Thelen 2003 (OpenSim's Thelen2003Muscle): the normalised curves against the paper's defining values,
// the activation dynamics against their closed-form solution, the steady isometric solve against time
// integration, the Simbody adapter against the plain integration, and the registry's conversions.
#include "basics/errors.h"
#include "muscles/muscle_file.h"
#include "muscles/muscle_models.h"
#include "muscles/simbody_isometric.h"
#include "muscles/thelen2003_muscle.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace armsim;

namespace {

// arm26's TRIlong (opensim-models Arm26/arm26.osim): F0 798.52 N, l0 0.134 m, slack 0.143 m, 0.2094 rad.
Thelen2003Parameters triLong() {
    Thelen2003Parameters p;
    p.name = "TRIlong";
    p.maxIsometricForce = 798.52;
    p.optimalFiberLength = 0.134;
    p.tendonSlackLength = 0.143;
    p.pennationAngleAtOptimal = 0.20943951;
    return p;
}

double column(const Table& t, const char* name, int row) { return t.getRow(row)[t.findColumn(name)]; }

constexpr double kCurveTol = 1e-12;    // closed-form values of the curves
constexpr double kSteadyTol = 1e-6;    // steady solve vs integration, relative force
constexpr double kAdapterTol = 1e-6;   // Simbody adapter vs plain integration, relative

}  // namespace

TEST(Thelen2003Curves, MatchTheDefiningValuesOfThelen2003) {
    const Thelen2003Parameters p = triLong();
    // Eq. 4: a Gaussian of width gamma, 1 at l~ = 1 and 1/2 at 1 +/- sqrt(gamma ln 2).
    EXPECT_NEAR(calcThelenActiveForceLength(p, 1.0), 1.0, kCurveTol);
    const double half = std::sqrt(p.kshapeActive * std::log(2.0));
    EXPECT_NEAR(calcThelenActiveForceLength(p, 1 + half), 0.5, kCurveTol);
    EXPECT_NEAR(calcThelenActiveForceLength(p, 1 - half), 0.5, kCurveTol);
    // Eq. 3: no passive force up to l~ = 1, F0 at the strain eps0^M.
    EXPECT_EQ(calcThelenPassiveForceLength(p, 0.9), 0.0);
    EXPECT_NEAR(calcThelenPassiveForceLength(p, 1.0 + p.fmaxMuscleStrain), 1.0, kCurveTol);
    // Eq. 2: slack below l^T_s, F0 at eps0^T, 0.33 F0 where the toe ends (the paper's rounded 0.609 eps0).
    EXPECT_EQ(calcThelenTendonForceLength(p, 0.999), 0.0);
    EXPECT_NEAR(calcThelenTendonForceLength(p, 1.0 + p.fmaxTendonStrain), 1.0, kCurveTol);
    const double epsToe = 0.609 * p.fmaxTendonStrain;
    EXPECT_NEAR(calcThelenTendonForceLength(p, 1.0 + epsToe), 0.33, 2e-3);
    // C1 at the toe's end (exact toe strain): one-sided slopes agree.
    const double e3 = std::exp(3.0), toe = 99.0 * p.fmaxTendonStrain * e3 / (166.0 * e3 - 67.0), h = 1e-7;
    const double left = (calcThelenTendonForceLength(p, 1 + toe) - calcThelenTendonForceLength(p, 1 + toe - h)) / h;
    const double right = (calcThelenTendonForceLength(p, 1 + toe + h) - calcThelenTendonForceLength(p, 1 + toe)) / h;
    EXPECT_NEAR(left, right, 1e-4 * right);
    EXPECT_NEAR(calcThelenTendonForceLength(p, 1 + toe), 0.33, kCurveTol);
}

TEST(Thelen2003Curves, ForceVelocityFollowsEquations6And7AndInvertsEverywhere) {
    const Thelen2003Parameters p = triLong();
    // Eq. 6 at full activation and l~ = 1: unloaded shortening at vmax, isometric at F0.
    EXPECT_NEAR(calcThelenFiberVelocity(p, 1.0, 1.0, 0.0), -1.0, kCurveTol);
    EXPECT_NEAR(calcThelenFiberVelocity(p, 1.0, 1.0, 1.0), 0.0, kCurveTol);
    // At a = 0.2 the maximal velocity is (0.25 + 0.75 a) vmax (Thelen's activation-dependent vmax).
    EXPECT_NEAR(calcThelenFiberVelocity(p, 0.2, 1.0, 0.0), -(0.25 + 0.75 * 0.2), kCurveTol);
    // Monotonic and C1 across both extrapolation boundaries (Fm = 0 and 0.95 Flen a fL).
    const double a = 0.6, fal = 0.8, afl = a * fal;
    double previous = -1e300;
    for (double Fm = -0.2 * afl; Fm < 1.6 * afl; Fm += 0.01 * afl) {
        const double v = calcThelenFiberVelocity(p, a, fal, Fm);
        EXPECT_GT(v, previous) << Fm;
        previous = v;
        // The inverse returns the multiplier (clamped at 0 below zero force).
        EXPECT_NEAR(calcThelenForceVelocity(p, a, fal, v), std::max(0.0, Fm / afl), 1e-9) << Fm;
    }
    // Interior points against eqs. 6-7 written out: shortening v = k (Fm - a fL) / (a fL + Fm / Af),
    // lengthening v = k (Fm - a fL) / ((2 + 2 / Af)(a fL Flen - Fm) / (Flen - 1)), k = 0.25 + 0.75 a.
    const double k = 0.25 + 0.75 * a;
    for (double Fm : {0.1 * afl, 0.5 * afl, 0.9 * afl})
        EXPECT_NEAR(calcThelenFiberVelocity(p, a, fal, Fm), k * (Fm - afl) / (afl + Fm / p.af), kCurveTol) << Fm;
    for (double Fm : {1.05 * afl, 1.15 * afl, 1.25 * afl})  // below the extrapolation at 0.95 Flen a fL
        EXPECT_NEAR(calcThelenFiberVelocity(p, a, fal, Fm),
                    k * (Fm - afl) / ((2 + 2 / p.af) * (afl * p.flen - Fm) / (p.flen - 1)), kCurveTol) << Fm;
    for (double edge : {0.0, p.fvLinearExtrapThreshold * p.flen * afl}) {
        const double h = 1e-7;
        const double left = (calcThelenFiberVelocity(p, a, fal, edge) - calcThelenFiberVelocity(p, a, fal, edge - h)) / h;
        const double right = (calcThelenFiberVelocity(p, a, fal, edge + h) - calcThelenFiberVelocity(p, a, fal, edge)) / h;
        EXPECT_NEAR(left, right, 1e-4 * std::abs(right)) << edge;
    }
}

TEST(Thelen2003Muscle, ActivationRisesAsTheClosedFormSolution) {
    // u = 1: da/dt = (1 - a) / (tau (0.5 + 1.5 a)), so t(a) = tau [2 ln((1 - a0)/(1 - a)) - 1.5 (a - a0)].
    const Thelen2003Muscle muscle(triLong());
    MuscleIsometricSettings s;
    s.pathLength = 0.28;
    s.activation = ActivationProfile::constant(1.0);
    s.duration = 0.1;
    s.sampleRate = 1000;
    s.integration.accuracy = 1e-8;
    const Table t = runMuscleIsometric(muscle, s);
    const double tau = muscle.getParameters().activationTimeConstant, a0 = muscle.getParameters().minimumActivation;
    for (int row : {5, 20, 50}) {
        const double a = column(t, "active_fraction", row);
        const double time = tau * (2 * std::log((1 - a0) / (1 - a)) - 1.5 * (a - a0));
        EXPECT_NEAR(time, column(t, "time_s", row), 1e-5) << row;
    }
}

TEST(Thelen2003Muscle, ActivationFallsAsTheClosedFormSolution) {
    // U = 0 from a = 1, the excitation floored at a_min = m (OpenSim's min_control): da/dt =
    // (m - a)(0.5 + 1.5 a) / tau_d, so t(a) = tau_d / (0.5 + 1.5 m) ln[g(a0) / g(a)], g(a) = (a - m) / (0.5 + 1.5 a).
    const Thelen2003Muscle muscle(triLong());
    MuscleIsometricSettings s;
    s.pathLength = 0.28;
    const double off = 0.01;  // [s] U = 1 (the steady start: a = 1) until then, 0 after
    s.activation = ActivationProfile::step(off, 1.0, 0.0);
    s.startSteady = true;
    s.duration = 0.1;
    s.sampleRate = 1000;
    s.integration.accuracy = 1e-8;
    const Table t = runMuscleIsometric(muscle, s);
    const double tau = muscle.getParameters().deactivationTimeConstant, m = muscle.getParameters().minimumActivation;
    auto g = [m](double a) { return (a - m) / (0.5 + 1.5 * a); };
    ASSERT_NEAR(column(t, "active_fraction", 0), 1.0, 1e-12);
    for (int row : {20, 50, 100}) {
        const double a = column(t, "active_fraction", row);
        EXPECT_NEAR(off + tau / (0.5 + 1.5 * m) * std::log(g(1.0) / g(a)), column(t, "time_s", row), 1e-5) << row;
    }
}

TEST(Thelen2003Muscle, SteadySolveEqualsTheEndOfAnIntegration) {
    for (double pennation : {0.0, 0.3}) {
        Thelen2003Parameters p = triLong();
        p.pennationAngleAtOptimal = pennation;
        const Thelen2003Muscle muscle(p);
        for (double P : {0.24, 0.28, 0.32})
            for (double U : {0.05, 0.4, 1.0}) {
                const SteadyState ss = muscle.calcSteadyState(P, U);
                ASSERT_TRUE(ss.converged) << ss.message;
                // The steady state is an equilibrium of the ODE.
                double ydot[2];
                muscle.calcStateDerivative(P, U, ss.states.data(), ydot);
                EXPECT_NEAR(ydot[0], 0.0, 1e-12);
                EXPECT_NEAR(ydot[1], 0.0, 1e-9);
                // ... and where an integration from rest ends.
                MuscleIsometricSettings s;
                s.pathLength = P;
                s.activation = ActivationProfile::constant(U);
                s.duration = 3.0;
                s.sampleRate = 10;
                s.integration.accuracy = 1e-8;
                const Table t = runMuscleIsometric(muscle, s);
                const double F = column(t, "force_N", t.getNumRows() - 1);
                EXPECT_NEAR(F, ss.force, kSteadyTol * ss.force) << "pennation " << pennation << " P " << P << " U " << U;
                EXPECT_NEAR(column(t, "fascicle_length_m", t.getNumRows() - 1), ss.fascicleLength, 1e-6 * ss.fascicleLength);
            }
    }
}

TEST(Thelen2003Muscle, SimbodyAdapterGivesThePlainIntegrationsSamples) {
    const Thelen2003Muscle muscle(triLong());
    MuscleIsometricSettings s;
    s.pathLength = 0.27;
    s.activation = ActivationProfile::step(0.2, 0.0, 1.0);
    s.duration = 0.6;
    s.sampleRate = 100;
    const Table plain = runMuscleIsometric(muscle, s);
    s.integrateSimbodySystem = true;
    const Table simbody = runMuscleIsometric(muscle, s);
    ASSERT_EQ(plain.getNumRows(), simbody.getNumRows());
    for (int r = 0; r < plain.getNumRows(); ++r)
        EXPECT_NEAR(column(simbody, "force_N", r), column(plain, "force_N", r),
                    kAdapterTol * std::max(1.0, column(plain, "force_N", r)))
            << r;
    // The step in drive raises the force from rest to near the steady MVC.
    EXPECT_NEAR(column(plain, "force_N", plain.getNumRows() - 1), muscle.calcSteadyState(0.27, 1.0).force,
                1e-3 * muscle.calcSteadyState(0.27, 1.0).force);
}

// Review finding: without pennation the fibre's minimum length is 0, where no fibre rests; a path so
// short that the fibre would shorten past every length has no steady state (it used to report one at
// 1e-9 l0 whose derivative was not zero). With pennation the stop holds it, and that rest is one.
TEST(Thelen2003Muscle, APathTooShortForTheTendonHasNoSteadyStateUnlessTheStopHoldsIt) {
    Thelen2003Parameters p = triLong();
    p.pennationAngleAtOptimal = 0;
    const SteadyState none = Thelen2003Muscle(p).calcSteadyState(p.tendonSlackLength * 1.0001, 1.0);
    EXPECT_FALSE(none.converged);
    EXPECT_NE(none.message.find("shorten to zero"), std::string::npos) << none.message;
    const Thelen2003Muscle pennate(triLong());
    const double P = 0.143 + 0.5 * pennate.getMinimumFiberLength() * std::cos(triLong().maximumPennationAngle);
    const SteadyState held = pennate.calcSteadyState(P, 1.0);
    ASSERT_TRUE(held.converged) << held.message;
    EXPECT_NEAR(held.fascicleLength, pennate.getMinimumFiberLength(), 1e-15);
    double ydot[2];
    pennate.calcStateDerivative(P, 1.0, held.states.data(), ydot);
    EXPECT_EQ(ydot[1], 0.0);  // the stop
}

TEST(Thelen2003Muscle, RefusesOutOfRangeParametersNamingTheField) {
    Thelen2003Parameters p = triLong();
    p.fmaxTendonStrain = 0;
    try {
        Thelen2003Muscle m(p);
        ADD_FAILURE();
    } catch (const FieldError& e) {
        EXPECT_NE(std::string(e.what()).find("fmax_tendon_strain"), std::string::npos) << e.what();
    }
    p = triLong();
    p.minimumActivation = 0.001;  // OpenSim refuses < 0.01
    EXPECT_THROW(Thelen2003Muscle{p}, FieldError);
    p = triLong();
    p.flen = 1.0;
    EXPECT_THROW(Thelen2003Muscle{p}, FieldError);
}

TEST(MuscleModels, RegistryBuildsThelenFromMorphometryWithTheStatedConversions) {
    const MuscleParameters vm =
        loadMuscleParameters(std::string(ARMSIM_ASSET_DIR) + "/muscles/biceps_long_head.yaml");
    const MuscleModelType& type = findMuscleModelType("thelen2003");
    const auto built = type.build({vm, {{"activation_time_constant", 0.01}}});
    const auto& thelen = dynamic_cast<const Thelen2003Muscle&>(*built);
    // F0 = sigma M / (rho L0), the Virtual Muscle relation; slack = LrT L0T (model/model_file.h).
    EXPECT_DOUBLE_EQ(thelen.getF0(), calcMaxIsometricForce(vm));
    EXPECT_DOUBLE_EQ(thelen.getParameters().tendonSlackLength, vm.coefficients.LrT * vm.optimalTendonLength);
    EXPECT_DOUBLE_EQ(thelen.getOptimalFascicleLength(), vm.optimalFascicleLength);
    EXPECT_DOUBLE_EQ(thelen.getParameters().activationTimeConstant, 0.01);
    EXPECT_DOUBLE_EQ(thelen.getParameters().deactivationTimeConstant, 0.05);  // OpenSim 4 default
    try {
        type.build({vm, {{"tau", 0.01}}});
        ADD_FAILURE();
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("'tau'"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("activation_time_constant"), std::string::npos) << e.what();
    }
    try {
        findMuscleModelType("thelen");
        ADD_FAILURE();
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("virtual_muscle, thelen2003"), std::string::npos) << e.what();
    }
    // Virtual Muscle through the registry is the same muscle.
    const auto v = findMuscleModelType("virtual_muscle").build({vm, {}});
    EXPECT_EQ(v->calcSteadyState(0.35, 1.0).force, VirtualMuscle(vm).calcSteadyState(0.35, 1.0).force);
}
