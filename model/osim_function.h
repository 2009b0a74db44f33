// OpenSim's functions of one variable, evaluated: Constant, LinearFunction, PiecewiseLinearFunction,
// SimmSpline and NaturalCubicSpline, as OpenSim computes them (opensim-core OpenSim/Common/*.cpp).
//
// SimmSpline is Forsythe, Malcolm & Moler's cubic spline (Computer Methods for Mathematical
// Computations, 1977, SPLINE/SEVAL): C2 at the knots, with end conditions that match the third
// derivative of the cubic through the four end knots (so it reproduces any cubic exactly when it has
// four knots or more); with three knots the end third derivatives are 0, with two it is the line.
// OpenSim's NaturalCubicSpline computes the same coefficients (its calcCoefficients is SimmSpline's,
// despite the name), so both kinds are the same spline here. Outside the knots every spline and the
// piecewise-linear function continue along the line of their end slope, as OpenSim's calcValue does.
#pragma once

#include "model/osim_file.h"

#include <vector>

namespace armsim {

/// An OsimFunction ready to evaluate (its spline coefficients computed once).
class OsimFunctionEvaluator {
public:
    OsimFunctionEvaluator() = default;
    explicit OsimFunctionEvaluator(const OsimFunction& f);

    /// f(x).
    double calcValue(double x) const;
    /// df/dx (the end slope beyond the knots).
    double calcDerivative(double x) const;

private:
    // The knot interval of x for the splines and piecewise-linear function: -1 before the first knot,
    // n - 1 past the last.
    int findInterval(double x) const;

    OsimFunction::Kind kind_ = OsimFunction::Kind::Constant;
    double value_ = 0, slope_ = 0, intercept_ = 0;
    std::vector<double> x_, y_, b_, c_, d_;   // y + b dx + c dx^2 + d dx^3 on [x_k, x_k+1]
};

}  // namespace armsim
