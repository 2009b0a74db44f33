// OpenSim's functions of one variable (model/osim_function.h) against analytic values: the splines
// through their knots, exact on cubics, C2 at interior knots, continued along their end slope; the
// piecewise-linear, linear and constant functions.
#include "model/osim_function.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace armsim;

namespace {

OsimFunction spline(OsimFunction::Kind kind, std::vector<double> x, std::vector<double> y) {
    OsimFunction f;
    f.kind = kind;
    f.x = std::move(x);
    f.y = std::move(y);
    return f;
}

double cubic(double x) { return 0.3 - 1.2 * x + 0.7 * x * x - 0.25 * x * x * x; }
double cubicSlope(double x) { return -1.2 + 1.4 * x - 0.75 * x * x; }

}  // namespace

// Forsythe-Malcolm-Moler end conditions make the spline exact on a cubic (unequal knots), in value
// and slope, inside the knots: 1e-12.
TEST(OsimFunction, SplinesReproduceACubicExactly) {
    const std::vector<double> x = {-1.0, -0.4, 0.1, 0.35, 1.0, 1.8};
    std::vector<double> y;
    for (double v : x) y.push_back(cubic(v));
    for (const auto kind : {OsimFunction::Kind::SimmSpline, OsimFunction::Kind::NaturalCubicSpline}) {
        const OsimFunctionEvaluator f(spline(kind, x, y));
        for (double v = -1.0; v <= 1.8; v += 0.013) {
            EXPECT_NEAR(f.calcValue(v), cubic(v), 1e-12) << v;
            EXPECT_NEAR(f.calcDerivative(v), cubicSlope(v), 1e-11) << v;
        }
    }
}

// On data that is no cubic: through every knot, value, slope and curvature continuous at interior
// knots (one-sided limits 1e-9 either side; curvature by differences over 1e-6), slope equal to central differences (1e-7), and a
// straight continuation along the end slope beyond the knots.
TEST(OsimFunction, SplineInterpolatesIsC2AndContinuesAlongItsEndSlopes) {
    const std::vector<double> x = {0.0, 0.3, 0.5, 1.1, 1.4, 2.0, 2.3};
    const std::vector<double> y = {0.01, 0.013, 0.02, 0.018, 0.005, 0.004, 0.009};
    const OsimFunctionEvaluator f(spline(OsimFunction::Kind::SimmSpline, x, y));
    for (std::size_t k = 0; k < x.size(); ++k) EXPECT_NEAR(f.calcValue(x[k]), y[k], 1e-15) << k;
    const double e = 1e-9;
    for (std::size_t k = 1; k + 1 < x.size(); ++k) {
        EXPECT_NEAR(f.calcValue(x[k] - e), f.calcValue(x[k] + e), 1e-6 * std::abs(y[k]) + 1e-10) << k;
        EXPECT_NEAR(f.calcDerivative(x[k] - e), f.calcDerivative(x[k] + e), 1e-6) << k;
        const double h = 1e-6;
        const double curvLeft = (f.calcDerivative(x[k] - e) - f.calcDerivative(x[k] - h)) / (h - e);
        const double curvRight = (f.calcDerivative(x[k] + h) - f.calcDerivative(x[k] + e)) / (h - e);
        EXPECT_NEAR(curvLeft, curvRight, 1e-3 * std::abs(curvLeft) + 1e-4) << k;
    }
    for (double v = 0.02; v < 2.3; v += 0.037) {
        const double h = 1e-6;
        EXPECT_NEAR(f.calcDerivative(v), (f.calcValue(v + h) - f.calcValue(v - h)) / (2 * h), 1e-7) << v;
    }
    const double b0 = f.calcDerivative(0.0), bn = f.calcDerivative(2.3);
    EXPECT_DOUBLE_EQ(f.calcValue(-0.5), y.front() - 0.5 * b0);
    EXPECT_DOUBLE_EQ(f.calcValue(2.8), y.back() + 0.5 * bn);
    EXPECT_EQ(f.calcDerivative(-0.5), b0);
    EXPECT_EQ(f.calcDerivative(2.8), bn);
    // NaturalCubicSpline is the same spline in OpenSim.
    const OsimFunctionEvaluator g(spline(OsimFunction::Kind::NaturalCubicSpline, x, y));
    for (double v = -0.3; v < 2.6; v += 0.05) EXPECT_EQ(g.calcValue(v), f.calcValue(v)) << v;
}

// Two knots: the line through them; three knots: a parabola is not reproduced, but the knots are.
TEST(OsimFunction, SplinesWithTwoAndThreeKnots) {
    const OsimFunctionEvaluator line(spline(OsimFunction::Kind::SimmSpline, {1.0, 3.0}, {2.0, 6.0}));
    for (double v : {0.0, 1.0, 2.2, 3.0, 4.5}) {
        EXPECT_NEAR(line.calcValue(v), 2.0 * v, 1e-14) << v;
        EXPECT_EQ(line.calcDerivative(v), 2.0) << v;
    }
    const OsimFunctionEvaluator three(spline(OsimFunction::Kind::SimmSpline, {0.0, 1.0, 3.0}, {1.0, -1.0, 2.0}));
    EXPECT_NEAR(three.calcValue(0.0), 1.0, 1e-15);
    EXPECT_NEAR(three.calcValue(1.0), -1.0, 1e-15);
    EXPECT_NEAR(three.calcValue(3.0), 2.0, 1e-15);
}

TEST(OsimFunction, PiecewiseLinearLinearAndConstant) {
    const OsimFunctionEvaluator p(spline(OsimFunction::Kind::PiecewiseLinear, {0.0, 1.0, 3.0}, {1.0, 3.0, 2.0}));
    EXPECT_DOUBLE_EQ(p.calcValue(0.5), 2.0);
    EXPECT_DOUBLE_EQ(p.calcValue(2.0), 2.5);
    EXPECT_DOUBLE_EQ(p.calcDerivative(0.5), 2.0);
    EXPECT_DOUBLE_EQ(p.calcDerivative(2.0), -0.5);
    EXPECT_DOUBLE_EQ(p.calcValue(-1.0), -1.0);   // along the first segment
    EXPECT_DOUBLE_EQ(p.calcValue(5.0), 1.0);     // along the last
    OsimFunction l;
    l.kind = OsimFunction::Kind::Linear;
    l.slope = -2;
    l.intercept = 0.5;
    EXPECT_DOUBLE_EQ(OsimFunctionEvaluator(l).calcValue(1.5), -2.5);
    EXPECT_DOUBLE_EQ(OsimFunctionEvaluator(l).calcDerivative(1.5), -2.0);
    OsimFunction c;
    c.value = 0.042;
    EXPECT_DOUBLE_EQ(OsimFunctionEvaluator(c).calcValue(7.0), 0.042);
    EXPECT_DOUBLE_EQ(OsimFunctionEvaluator(c).calcDerivative(7.0), 0.0);
}
