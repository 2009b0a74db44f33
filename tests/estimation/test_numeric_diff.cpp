// SteppingNumericDiffCost (estimation/numeric_diff.h): Ceres's central differences where both probes
// have a value, the one-sided difference where one has not, failure only where neither has.
#include "estimation/numeric_diff.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace armsim;

namespace {

// r = (x0^2 sqrt(1 - x1), 3 x0 x1): no value for x1 > 1 (a model without a steady state there).
struct EdgeFunctor {
    bool operator()(double const* const* p, double* r) const {
        const double* x = p[0];
        if (x[1] > 1) return false;
        r[0] = x[0] * x[0] * std::sqrt(1 - x[1]);
        r[1] = 3 * x[0] * x[1];
        return true;
    }
};

void evaluate(const ceres::CostFunction& f, const double* x, double* r, double* J) {
    double* jacobians[1] = {J};
    const double* parameters[1] = {x};
    ASSERT_TRUE(f.Evaluate(parameters, r, jacobians));
}

}  // namespace

TEST(SteppingNumericDiff, EqualsCeresCentralDifferencesInsideTheDomain) {
    const SteppingNumericDiffCost<EdgeFunctor> stepping(new EdgeFunctor, 2, 2);
    ceres::DynamicNumericDiffCostFunction<EdgeFunctor, ceres::CENTRAL> central(new EdgeFunctor);
    central.AddParameterBlock(2);
    central.SetNumResiduals(2);
    const double x[2] = {1.3, 0.4};
    double r1[2], r2[2], J1[4], J2[4];
    evaluate(stepping, x, r1, J1);
    evaluate(central, x, r2, J2);
    for (int i = 0; i < 4; ++i) EXPECT_EQ(J1[i], J2[i]) << i;   // the same arithmetic
    for (int i = 0; i < 2; ++i) EXPECT_EQ(r1[i], r2[i]);
}

TEST(SteppingNumericDiff, FallsBackToOneSidedDifferencesAtTheDomainsEdge) {
    constexpr double kOneSidedTol = 1e-4;   // relative: forward difference, step 1e-6 |x|, curvature of sqrt near its edge
    const SteppingNumericDiffCost<EdgeFunctor> stepping(new EdgeFunctor, 2, 2);
    ceres::DynamicNumericDiffCostFunction<EdgeFunctor, ceres::CENTRAL> central(new EdgeFunctor);
    central.AddParameterBlock(2);
    central.SetNumResiduals(2);
    const double x[2] = {1.3, 1 - 1e-3};    // both probes of x1 (step 1e-6) inside
    const double edge[2] = {1.3, 1 - 5e-7}; // the forward probe of x1 outside
    double r[2], J[4];
    const double* parameters[1] = {edge};
    double* jacobians[1] = {J};
    EXPECT_FALSE(central.Evaluate(parameters, r, jacobians));   // Ceres fails the whole Jacobian
    ASSERT_TRUE(stepping.Evaluate(parameters, r, jacobians));
    // x0's column is central; x1's is the backward secant of step 1e-6 (|x1| 1e-6 > sqrt(eps)).
    constexpr double kSecantTol = 1e-6;   // relative: rounding of a difference of 1e-6
    const double delta = 1e-6 * edge[1];
    const double secant = edge[0] * edge[0] * (std::sqrt(1 - edge[1]) - std::sqrt(1 - edge[1] + delta)) / delta;
    EXPECT_NEAR(J[0 * 2 + 0], 2 * edge[0] * std::sqrt(1 - edge[1]), 1e-6);
    EXPECT_NEAR(J[0 * 2 + 1], secant, kSecantTol * std::abs(secant));
    EXPECT_NEAR(J[1 * 2 + 1], 3 * edge[0], kSecantTol * 3 * edge[0]);
    double r2[2], J2[4];
    evaluate(stepping, x, r2, J2);   // away from the edge: accurate
    EXPECT_NEAR(J2[0 * 2 + 1], -x[0] * x[0] / (2 * std::sqrt(1 - x[1])), kOneSidedTol * std::abs(J2[0 * 2 + 1]));
    const double outside[2] = {1.3, 1.1};   // no value at x itself: a failure, as Ceres
    parameters[0] = outside;
    EXPECT_FALSE(stepping.Evaluate(parameters, r, jacobians));
}

// Both probes of a coordinate without a value: no Jacobian (a failure, not a made-up column).
TEST(SteppingNumericDiff, FailsWhereBothProbesHaveNoValue) {
    struct Point {   // a value only on the line x1 = 0.5
        bool operator()(double const* const* p, double* r) const {
            if (p[0][1] != 0.5) return false;
            r[0] = p[0][0];
            return true;
        }
    };
    const SteppingNumericDiffCost<Point> stepping(new Point, 2, 1);
    const double x[2] = {1.0, 0.5};
    double r[1], J[2];
    const double* parameters[1] = {x};
    double* jacobians[1] = {J};
    EXPECT_FALSE(stepping.Evaluate(parameters, r, jacobians));
    double* noJacobian[1] = {nullptr};   // the value alone is there
    EXPECT_TRUE(stepping.Evaluate(parameters, r, noJacobian));
    EXPECT_EQ(r[0], 1.0);
}
