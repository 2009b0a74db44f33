// The Virtual Muscle equations against the analytic anchors of the spec and against each other.
#include "muscles/muscle_file.h"
#include "muscles/virtual_muscle.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace armsim;

namespace {

MuscleParameters bicepsLongHead() {
    return loadMuscleParameters(std::string(ARMSIM_ASSET_DIR) + "/muscles/biceps_long_head.yaml");
}

}  // namespace

TEST(VirtualMuscle, MaximalForceFromMassAndLength) {
    constexpr double kTol = 1e-9;  // relative; F0 = sigma M / (rho L0) is exact arithmetic
    MuscleParameters p = bicepsLongHead();
    p.mass = 0.336;
    p.optimalFascicleLength = 0.16;
    EXPECT_NEAR(VirtualMuscle(p).getF0(), 630.000, 630.0 * kTol);
}

TEST(VirtualMuscle, RecruitmentThresholdsForThreePlusThreeUnits) {
    constexpr double kTol = 5e-6;  // the spec prints five digits
    const auto units = calcRecruitment(3, 3, 0.3, 0.8, Apportioning::Thesis);
    const double fractions[] = {0.08, 0.10, 0.12, 0.18667, 0.23333, 0.28};
    const double thresholds[] = {0.064, 0.144, 0.24, 0.38933, 0.576, 0.8};
    ASSERT_EQ(units.size(), 6u);
    for (int u = 0; u < 6; ++u) {
        EXPECT_NEAR(units[u].fraction, fractions[u], kTol) << "unit " << u;
        EXPECT_NEAR(units[u].threshold, thresholds[u], kTol) << "unit " << u;
        EXPECT_EQ(units[u].slow, u < 3);
    }
}

TEST(VirtualMuscle, RecruitmentWithNoUnitsOfOneTypeKeepsTheWholePcsa) {
    constexpr double kTol = 1e-12;
    for (auto [ns, nf] : {std::pair{0, 4}, std::pair{5, 0}, std::pair{1, 1}, std::pair{10, 10}}) {
        for (Apportioning a : {Apportioning::Thesis, Apportioning::Equal}) {
            const auto units = calcRecruitment(ns, nf, 0.3, 0.8, a);
            ASSERT_EQ(int(units.size()), ns + nf);
            double sum = 0, slowSum = 0;
            for (const auto& u : units) {
                sum += u.fraction;
                if (u.slow) slowSum += u.fraction;
            }
            EXPECT_NEAR(sum, 1.0, kTol);
            const double expectedSlow = ns == 0 ? 0.0 : (nf == 0 ? 1.0 : 0.3);
            EXPECT_NEAR(slowSum, expectedSlow, kTol);
            EXPECT_DOUBLE_EQ(units.back().threshold, 0.8);
        }
    }
    EXPECT_TRUE(calcRecruitment(0, 0, 0.3, 0.8, Apportioning::Thesis).empty());
}

TEST(VirtualMuscle, ElementsAreOneAtTheirReferencePoint) {
    constexpr double kTol = 1e-15;
    const MuscleParameters p = bicepsLongHead();
    for (const FibreType* t : {&p.slow, &p.fast}) {
        EXPECT_NEAR(calcForceLength(*t, 1.0), 1.0, kTol) << t->name;
        for (double L : {0.7, 1.0, 1.3}) EXPECT_NEAR(calcForceVelocity(*t, 0.0, L), 1.0, kTol) << t->name;
        // Shortening at Vmax gives no force; lengthening gives more than isometric.
        EXPECT_NEAR(calcForceVelocity(*t, t->Vmax, 1.0), 0.0, kTol) << t->name;
        EXPECT_GT(calcForceVelocity(*t, 0.5, 1.0), 1.0) << t->name;
    }
}

TEST(VirtualMuscle, InitialLengthConstantsRecomputedFromCoefficients) {
    constexpr double kTol = 5e-8;  // the spec prints seven digits
    const MuscleCoefficients c = bicepsLongHead().coefficients;
    EXPECT_NEAR(calcPassiveForceAtLimit(c), 0.0259506, kTol);
    EXPECT_NEAR(calcTendonLengthAtLimit(c), 0.956877, 5e-7);
    const auto [a, b] = calcInitialLengthConstants(c);
    EXPECT_NEAR(a, 0.8542867, kTol);
    EXPECT_NEAR(b, 0.1021739, kTol);
    // LTstar really carries PF: Fse(LTstar) = PF.
    EXPECT_NEAR(calcSeriesElastic(c, calcTendonLengthAtLimit(c)), calcPassiveForceAtLimit(c), 1e-14);
}

TEST(VirtualMuscle, LmaxPutsTheFascicleAtTheLimitWhereTendonAndPassiveForcesBalance) {
    // At P = P_max and L = Lmax the tendon carries PF and PE1 (V = 0) gives PF too: the definition.
    constexpr double kTol = 1e-12;
    const VirtualMuscle m(bicepsLongHead());
    const auto& p = m.getParameters();
    const double LT = (p.maxPathLength - m.getLmax() * p.optimalFascicleLength) / p.optimalTendonLength;
    EXPECT_NEAR(calcSeriesElastic(p.coefficients, LT), calcPassiveStretch(p.coefficients, m.getLmax(), 0, m.getLmax()),
                kTol);
}

TEST(VirtualMuscle, NfLimitOfTheSlowType) {
    constexpr double kTol = 5e-4;  // the spec prints 1.730
    const VirtualMuscle m(bicepsLongHead());
    EXPECT_NEAR(m.getNfLimit(), 5.0 / (5.0 - 2.11), 1e-12);
    EXPECT_NEAR(m.getNfLimit(), 1.730, kTol);
    EXPECT_NEAR(calcNf(m.getParameters().slow, m.getNfLimit()), 0.0, 1e-12);
}

TEST(VirtualMuscle, StateDerivativeVanishesAtTheSteadyState) {
    constexpr double kRateTol = 1e-9;     // |dy/dt| of order-1 states [1/s]
    constexpr double kForceTol = 1e-10;   // |Fse - Fce| / F0
    const VirtualMuscle m(bicepsLongHead());
    const auto& p = m.getParameters();
    for (double P : {0.34, 0.375, 0.40, 0.43})
        for (double U : {0.0, 0.1, 0.2, 0.5, 0.6, 0.9, 1.0}) {
            const SteadyState ss = m.calcSteadyState(P, U);
            ASSERT_TRUE(ss.converged) << ss.message;
            std::vector<double> ydot(m.getNumStates());
            MuscleOutputs out;
            m.calcStateDerivative(P, U, ss.states.data(), ydot.data(), &out);
            for (int i = 0; i < m.getNumStates(); ++i) {
                if (i == VirtualMuscle::kV) continue;
                EXPECT_NEAR(ydot[i], 0.0, kRateTol) << "P " << P << " U " << U << " " << m.getStateNames()[i];
            }
            const double imbalance = ydot[VirtualMuscle::kV] * m.getNodeMass() * p.optimalFascicleLength / m.getF0();
            EXPECT_NEAR(imbalance, 0.0, kForceTol) << "P " << P << " U " << U;
            EXPECT_NEAR(out.Fse, ss.force, 1e-9 * m.getF0());
        }
}

TEST(VirtualMuscle, FullActivationForceIndependentOfUnitCountAndSplit) {
    constexpr double kTol = 1e-9;  // relative
    MuscleParameters p = bicepsLongHead();
    const double reference = VirtualMuscle(p).calcSteadyState(0.40, 1.0).force;
    ASSERT_GT(reference, 100.0);
    for (auto [ns, nf] : {std::pair{1, 1}, std::pair{10, 5}, std::pair{2, 7}, std::pair{7, 2}})
        for (Apportioning a : {Apportioning::Thesis, Apportioning::Equal}) {
            p.numSlowUnits = ns;
            p.numFastUnits = nf;
            p.apportioning = a;
            EXPECT_NEAR(VirtualMuscle(p).calcSteadyState(0.40, 1.0).force, reference, kTol * reference)
                << ns << "+" << nf;
        }
    // ...but a submaximal force does depend on it (so the test above can tell).
    p.numSlowUnits = p.numFastUnits = 3;
    const double f3 = VirtualMuscle(p).calcSteadyState(0.40, 0.5).force;
    p.numSlowUnits = p.numFastUnits = 10;
    EXPECT_GT(std::abs(VirtualMuscle(p).calcSteadyState(0.40, 0.5).force - f3), 1.0);
}

TEST(VirtualMuscle, SteadyForceRisesWithActivation) {
    const VirtualMuscle m(bicepsLongHead());
    double last = -1;
    for (int k = 0; k <= 20; ++k) {
        const double U = 0.05 * k;
        const double f = m.calcSteadyState(0.375, U).force;
        EXPECT_GE(f, last) << "U " << U;
        last = f;
    }
}

TEST(VirtualMuscle, SteadySolveReportsMissingEquilibriumHonestly) {
    MuscleParameters p = bicepsLongHead();
    // Too short: the tendon is slack at every fascicle length while the active muscle pulls.
    const SteadyState slack = VirtualMuscle(p).calcSteadyState(0.05, 1.0);
    EXPECT_FALSE(slack.converged);
    EXPECT_NE(slack.message.find("slack"), std::string::npos) << slack.message;
    // Too long: the tendon needs a fascicle beyond the slow fibres' nf limit.
    p.maxPathLength = 0.9;
    const SteadyState tooLong = VirtualMuscle(p).calcSteadyState(0.9, 1.0);
    EXPECT_FALSE(tooLong.converged);
    EXPECT_NE(tooLong.message.find("nf"), std::string::npos) << tooLong.message;
}

TEST(VirtualMuscle, ThesisCompositionAnchorAtActivationNinetyPercent) {
    // Thesis Table 7.4: 3 slow + 3 fast units, U = 0.9, P = 37.5 cm: 346.128 N. Not an exact anchor
    // (the thesis used its own garbled equations); we accept 2 %.
    constexpr double kRelTol = 0.02;
    const VirtualMuscle m(bicepsLongHead());
    EXPECT_NEAR(m.calcSteadyState(0.375, 0.9).force, 346.128, kRelTol * 346.128);
}

// The analytic Jacobian d(dy/dt)/dy against central difference quotients of calcStateDerivative, at
// seeded states of both fibre types' units (rising and falling Tf branches, sag, yield, shortening and
// lengthening), away from the branch points (fint = feff, feff = 0.1, V = 0) by more than the step.
TEST(VirtualMuscle, AnalyticJacobianEqualsDifferenceQuotients) {
    constexpr double kStep = 1e-7;          // relative to max(1, |y_j|)
    constexpr double kTol = 2e-5;           // of the row's largest entry: central differences, step 1e-7
    MuscleParameters p = bicepsLongHead();
    const VirtualMuscle m(p);
    const int n = m.getNumStates();
    const double P = 0.9 * m.getMaxPathLength();
    std::uint32_t seed = 12345;
    auto uniform = [&](double lo, double hi) {   // LCG: portable and seeded
        seed = seed * 1664525u + 1013904223u;
        return lo + (hi - lo) * (seed >> 8) / double(1u << 24);
    };
    int checkedStates = 0, nonzero = 0;
    for (int trial = 0; trial < 12; ++trial) {
        const double U = trial % 3 == 0 ? 0.3 : trial % 3 == 1 ? 0.7 : 0.98;
        std::vector<double> y = m.calcSteadyState(P, U).states;
        ASSERT_EQ(int(y.size()), n);
        y[VirtualMuscle::kL] = uniform(0.75, 1.2);
        y[VirtualMuscle::kV] = (trial % 2 ? 1 : -1) * uniform(0.05, 0.6);
        for (int u = 0; u < m.getNumUnits(); ++u) {
            const double feff = uniform(0.2, 1.6);
            y[m.getFeffIndex(u)] = feff;
            y[m.getFintIndex(u)] = feff * (trial % 4 < 2 ? uniform(1.05, 1.4) : uniform(0.6, 0.95));   // both Tf branches
            if (m.getSagIndex(u) >= 0) y[m.getSagIndex(u)] = uniform(0.75, 1.0);
        }
        for (bool slow : {true, false})
            if (m.getYieldIndex(slow) >= 0) y[m.getYieldIndex(slow)] = uniform(0.8, 1.0);
        std::vector<double> J(std::size_t(n * n)), plus(n), minus(n);
        ASSERT_TRUE(m.calcStateJacobian(P, U, y.data(), J.data()));
        for (int j = 0; j < n; ++j) {
            const double h = kStep * std::max(1.0, std::abs(y[j]));
            std::vector<double> a = y, b = y;
            a[j] += h;
            b[j] -= h;
            m.calcStateDerivative(P, U, a.data(), plus.data());
            m.calcStateDerivative(P, U, b.data(), minus.data());
            for (int i = 0; i < n; ++i) {
                double rowMax = 1e-12;
                for (int k = 0; k < n; ++k) rowMax = std::max(rowMax, std::abs(J[std::size_t(i * n + k)]));
                const double fd = (plus[i] - minus[i]) / (2 * h);
                EXPECT_NEAR(J[std::size_t(i * n + j)], fd, kTol * rowMax)
                    << "d " << m.getStateNames()[i] << " / d " << m.getStateNames()[j] << " at trial " << trial;
                nonzero += J[std::size_t(i * n + j)] != 0;
            }
        }
        ++checkedStates;
    }
    EXPECT_EQ(checkedStates, 12);
    EXPECT_GT(nonzero, 12 * 3 * n);   // not an empty matrix: every unit couples to L, V and its own states
}

// The steady state's sensitivity (implicit function theorem) against central differences of steady
// states solved afresh (bracket 1e-13) with each input moved: the path, U, and muscles rebuilt with
// L0, L0T and P_max scaled; over the ascending and descending limbs and three drives.
TEST(VirtualMuscle, SteadySensitivityEqualsDifferencesOfSolvedStates) {
    using S = SteadySensitivity;
    constexpr double kStep = 1e-5;   // on ln inputs and on U
    constexpr double kTol = 2e-6;    // absolute, on derivatives of order 0.1-10: truncation ~kStep^2
    const MuscleParameters base = bicepsLongHead();
    const VirtualMuscle m(base);
    int checked = 0;
    double largest = 0;
    for (double fraction : {0.8, 0.88, 0.96})
        for (double U : {0.3, 0.7, 0.98}) {
            const double P = fraction * m.getMaxPathLength();
            const SteadyState st = m.calcSteadyState(P, U);
            ASSERT_TRUE(st.converged) << st.message;
            const S s = m.calcSteadySensitivity(P, U, st.L);
            ASSERT_TRUE(s.valid);
            for (int k = 0; k < S::kNumInputs; ++k) {
                auto solve = [&](double by) {
                    MuscleParameters q = base;
                    double path = P, u = U;
                    if (k == S::kLnPath) path *= std::exp(by);
                    if (k == S::kLnFascicle) q.optimalFascicleLength *= std::exp(by);
                    if (k == S::kLnTendon) q.optimalTendonLength *= std::exp(by);
                    if (k == S::kLnMaxPath) q.maxPathLength *= std::exp(by);
                    if (k == S::kInput) u += by;
                    const SteadyState r = VirtualMuscle(q).calcSteadyState(path, u);
                    EXPECT_TRUE(r.converged) << r.message;
                    return r;
                };
                const SteadyState hi = solve(kStep), lo = solve(-kStep);
                const double dFn = (hi.normalizedForce - lo.normalizedForce) / (2 * kStep);
                const double dL = (hi.L - lo.L) / (2 * kStep);
                EXPECT_NEAR(s.dFn[k], dFn, kTol) << "d Fn / d input " << k << " at P " << P << ", U " << U;
                EXPECT_NEAR(s.dL[k], dL, kTol) << "d L / d input " << k << " at P " << P << ", U " << U;
                largest = std::max(largest, std::abs(dFn));
                ++checked;
            }
        }
    EXPECT_EQ(checked, 9 * S::kNumInputs);
    EXPECT_GT(largest, 0.5);   // not all zero
}
