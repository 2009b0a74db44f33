// Small distribution functions for confidence intervals (no Boost on the dependency list).
#pragma once

namespace armsim {

/// Regularised incomplete beta function I_x(a, b), x in [0, 1], a, b > 0 (continued fraction,
/// Lentz's method; Press et al., Numerical Recipes 3rd ed., 6.4).
double calcIncompleteBeta(double a, double b, double x);
/// Student-t cumulative distribution P(T <= t) with dof > 0 degrees of freedom.
double calcStudentTCdf(double t, double dof);
/// Quantile q with P(T <= q) = p of Student's t, p in (0, 1); dof = infinity gives the normal quantile.
double calcStudentTQuantile(double p, double dof);
/// Standard normal quantile, p in (0, 1).
double calcNormalQuantile(double p);
/// Regularised upper incomplete gamma Q(a, x) = Gamma(a, x) / Gamma(a), a > 0, x >= 0 (series for
/// x < a + 1, else continued fraction; Numerical Recipes 3rd ed., 6.2).
double calcUpperIncompleteGamma(double a, double x);
/// P(X >= x) for X chi-square with dof > 0 degrees of freedom.
double calcChiSquareSurvival(double x, double dof);

}  // namespace armsim
