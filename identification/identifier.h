// Identification of muscle parameters (by default mass M and optimal tendon length L0T) from measured
// isometric forces: thesis chapters 4.5, 4.6, 7.1, 7.2 and a bounded Levenberg-Marquardt fit (Ceres).
//
// Problem: unknowns x (unknowns.h), observations k with path P_k, activation U_k and measured force
// y_d,k; a ForceModel predicts y_k(x). Residuals r_k = y_k(x) - y_d,k [N]; cost = 0.5 sum r_k^2 [N^2].
// Inside every solver the unknowns are scaled, z_j = x_j / scale_j (order 1).
//
// Methods (selected by name, getMethodNames()):
//
// "false-position"  One unknown, one observation (thesis 4.5.1). The unknown's bounds are the bracket
//     [a, b]; r must change sign on it. Regula falsi with the Illinois modification (the retained end's
//     r is halved when the same end is kept twice: plain regula falsi can keep one end forever, so its
//     bracket never shrinks). Converged when the bracket is narrower than Unknown::tolerance (thesis:
//     1e-3 cm), so the error in the unknown is below that tolerance.
//
// "ilc-standard"  One output (thesis 7.1, eq. 4.42): x_{i+1} = x_i + g (y_d - y_i) with the constant
//     gain vector g = (Unknown::gain) [unit/N]; thesis: 0.5 g/N for M and 0.01 cm/N for L0T. The thesis
//     text prints +0.01 in 7.1 but -0.01 in its constant gain matrix (7.2.1), and its Table 7.1 moves
//     L0T down while M goes up; the force falls with L0T at 40 cm, so the default is -0.01 cm/N
//     (-1e-4 m/N). With two unknowns and one output the result is A point on the iso-force curve,
//     not THE parameters (thesis Table 7.1). Needs exactly one observation; exempt from the
//     "at least as many distinct points as unknowns" rule, since its purpose is to show that rule.
//
// The two-output learning family (thesis 7.2, eq. 7.2): x_{i+1} = x_i + G_i (y_d - y_i) with a p x n
// gain matrix G_i (p unknowns, n >= p outputs; thesis p = n = 2). The thesis's equations 7.2-7.5 are
// garbled in the text; armsim builds G_i as follows.
//   "ilc-constant"  G constant: IdentificationOptions::gainMatrix, or by default every column equal to
//       the unknowns' gains, which for n = 2 is exactly the thesis matrix [[0.5, 0.5], [-0.01, -0.01]]
//       (g/N; cm/N) of 7.2.1. That matrix has rank 1: it moves x along one fixed direction and can only
//       null the sum of the two errors, so it stops at a wrong point (thesis: 329.8 g, 24.26 cm), which
//       armsim reports as "no-progress".
//   "ilc-secant"  The thesis's difference quotient (7.3), g = (x_{i-1} - x_{i-2}) / (f(x_{i-1}) -
//       f(x_{i-2})), taken element by element is a rank-1 outer product and never changes its
//       direction; armsim uses its multi-dimensional form instead: a secant (Broyden) estimate F_i of
//       the Jacobian dy/dx, updated from each new pair (x_{i-1} - x_{i-2}, y_{i-1} - y_{i-2}) by
//       F += (dy - F dz) dz^T / (dz^T dz) in scaled coordinates, and G_i = F_i^+ (the pseudo-inverse:
//       G = F^{-1} is the thesis's fastest gain, 4.6.2). F_0 comes from p learning trials that each
//       change one unknown by IdentificationOptions::probeStep * scale: then 7.3 holds exactly per
//       element. Steps are taken without a descent test (thesis 7.2.2).
//   "ilc-bounded-secant"  As ilc-secant, then every element of G_i is clipped in magnitude to
//       [Unknown::gainMin, Unknown::gainMax] of its row's unknown, keeping its sign (thesis 7.2.3,
//       0.01 < |g| < 0.2 in g/N and cm/N).
//   "ilc-sign-search"  Bounded magnitude with searched sign (thesis 7.2.4, eq. 7.5): d = lambda |G_i
//       (y_d - y_i)| with G_i the bounded secant gain and lambda in (0, 1]; the step's signs are
//       searched, x + s o d for all 2^p sign vectors s (thesis: 4 trials for two unknowns), and the
//       trial with the smallest cost is kept if it descends (thesis: "the greatest descending among the
//       four control directions"). Every trial is also a secant pair for the Jacobian estimate. When no
//       sign descends, lambda is halved for the next iteration (restored after a descent); "no-progress"
//       when it falls below 1e-10.
// All ILC variants project x into the bounds and converge when every |r_k| <= forceTolerance (thesis:
// 0.1 N).
//
// "lm"  Levenberg-Marquardt (Ceres) on the scaled unknowns with bounds (SetParameterLowerBound /
//     UpperBound; steps are projected onto the bounds, without Ceres's projected line search, which
//     costs a Jacobian per trial step). Difference step and parameter tolerance come from the
//     ForceModel (steady: 1e-6, 1e-12; faithful: 1e-3, 1e-5, matched to its integration noise).
//     Derivatives: "central" (armsim's cost function returns the Jacobian from central differences
//     of the forward model, one-sided at a bound) or "ceres-numeric" (Ceres's
//     DynamicNumericDiffCostFunction, central). Noise model "absolute" fits r_k [N]; "relative" fits
//     r_k / y_d,k (force errors proportional to the force, e.g. "2 % noise"). Uncertainty from
//     ceres::Covariance (J^T J)^{-1} of the weighted residuals, times s^2 = SSR / (n - p) with
//     Student-t quantiles when n > p, or times a given sd^2 (forceSd or relativeForceSd) with normal
//     quantiles. With n == p and no forceSd there is no noise level: no intervals (uncertaintyNote says
//     so). Multi-start: the first start is the unknowns' start, the others uniform in the bounds from a
//     seeded generator; the lowest final cost wins. With n == p the fit must also reproduce every force
//     within forceTolerance, otherwise "not-converged".
//
// Honesty: a run that ends with an unknown at a bound and the forces not reproduced stops as
// "bound-hit" (e.g. forces above what the model can produce inside the bounds); a forward model that
// fails stops the ILC variants as "not-converged" with the reason. Never a silent wrong answer.
#pragma once

#include "basics/numbers.h"

#include "identification/force_model.h"
#include "identification/observations.h"
#include "identification/unknowns.h"

#include <functional>
#include <string>
#include <vector>

namespace armsim {

/// Identification method (see the file comment).
enum class Method {
    FalsePosition,       ///< "false-position"
    IlcStandard,         ///< "ilc-standard"
    IlcConstant,         ///< "ilc-constant"
    IlcSecant,           ///< "ilc-secant"
    IlcBoundedSecant,    ///< "ilc-bounded-secant"
    IlcSignSearch,       ///< "ilc-sign-search"
    LevenbergMarquardt   ///< "lm"
};
std::string getMethodName(Method m);
/// InputError listing the names for an unknown one.
Method parseMethodName(const std::string& name);
std::vector<std::string> getMethodNames();

/// How lm gets its Jacobian.
enum class Derivatives {
    Central,       ///< "central": armsim's central differences of the forward model (bound-aware)
    CeresNumeric   ///< "ceres-numeric": Ceres's DynamicNumericDiffCostFunction (central)
};
std::string getDerivativesName(Derivatives d);
Derivatives parseDerivativesName(const std::string& name);

/// lm's noise model: how residuals are weighted and what an interval assumes.
enum class NoiseModel {
    Absolute,   ///< "absolute": the same force sd for every observation; residuals in N
    Relative    ///< "relative": sd proportional to the measured force; residuals divided by it (forces > 0)
};
std::string getNoiseModelName(NoiseModel m);
NoiseModel parseNoiseModelName(const std::string& name);

/// Options of identify(). Validated by identify (FieldError "options.<field>").
struct IdentificationOptions {
    Method method = Method::LevenbergMarquardt;
    int maxIterations = 200;         ///< solver iterations (ILC updates, LM steps, false-position steps)
    double forceTolerance = 0.1;     ///< [N] every |model - measured| <= this counts as reproduced (thesis +/-0.1 N)
    /// ilc-constant gain G, p rows x n columns [unit/N]; empty: each column = the unknowns' gains.
    std::vector<std::vector<double>> gainMatrix;
    double lambda = 1.0;             ///< ilc-sign-search step factor, (0, 1]
    double probeStep = 0.01;         ///< secant ILC: initial one-at-a-time trials change x_j by this * scale_j
    int stallIterations = 50;        ///< ILC "no-progress" after this many iterations without a lower cost
    Derivatives derivatives = Derivatives::Central;   ///< lm
    double differenceStep = kNaN;      ///< lm: central-difference step [scaled]; NaN: ForceModel::getDifferenceStep()
    double parameterTolerance = kNaN;  ///< lm: Ceres parameter_tolerance; NaN: ForceModel::getParameterTolerance()
    NoiseModel noise = NoiseModel::Absolute;  ///< lm: residual weighting
    double forceSd = kNaN;      ///< lm, absolute noise: known force sd [N]; NaN: estimate from residuals (n > p)
    double relativeForceSd = kNaN;  ///< lm, relative noise: known sd / force [1]; NaN: estimate (n > p)
    double confidenceLevel = 0.95;   ///< lm: two-sided interval level
    int starts = 1;                  ///< lm: number of starts (>= 1)
    unsigned seed = 1;               ///< lm: seed of the multi-start generator
    /// Optional, lm with several starts: called with (starts done, starts) after each (progress).
    std::function<void(int, int)> progress;
};

/// Why a run stopped.
enum class StopReason {
    Converged,       ///< "converged": tolerance met
    MaxIterations,   ///< "max-iterations": iteration limit reached first
    NoProgress,      ///< "no-progress": the cost stopped decreasing (fixed point, stalled steps)
    NotConverged,    ///< "not-converged": failed (forward model failure, no sign change, residuals left); message says why
    BoundHit         ///< "bound-hit": stopped at a bound of an unknown with the forces not reproduced
};
std::string getStopReasonName(StopReason r);

/// One identified parameter.
struct ParameterEstimate {
    std::string name;                 ///< e.g. "mass"
    std::string unit;                 ///< SI unit
    double value = 0;                 ///< estimate [unit]
    double start = 0;                 ///< start value [unit]
    double lower = 0, upper = 0;      ///< bounds [unit]
    bool atBound = false;             ///< within the unknown's tolerance of a bound
    double standardError = kNaN; ///< [unit] (lm; NaN: unavailable)
    double ciLower = kNaN;       ///< interval at IdentificationOptions::confidenceLevel [unit]
    double ciUpper = kNaN;
};

/// State after one solver iteration (iteration 0 = the start).
struct IterationRecord {
    int iteration = 0;
    int evaluations = 0;               ///< forward evaluations used so far
    std::vector<double> parameters;    ///< x [SI]
    std::vector<double> residuals;     ///< model - measured [N]
    double cost = 0;                   ///< 0.5 sum r^2 [N^2]
};

/// A forward model's forces at a run's estimate: the re-check of an estimate with a second model
/// (e.g. the faithful model at the full protocol after iterations with a cheaper one).
struct ModelCheck {
    std::string model;               ///< ForceModel::getName()
    std::string note;                ///< the model and its settings in words (e.g. FaithfulForceModel::describe()); empty: the name
    std::vector<double> forces;      ///< model forces at the estimate [N] (NaN where it failed)
    std::vector<double> residuals;   ///< model - measured [N]
    double rmsResidual = kNaN;  ///< [N]
    std::string failure;             ///< why the model failed (empty: it ran)
};

/// Everything a run produced.
struct IdentificationReport {
    std::string method;                   ///< method name
    std::string forceModel;               ///< ForceModel::getName()
    std::string dataSource;               ///< ObservationSet::source
    StopReason stopReason = StopReason::NotConverged;
    std::string message;                  ///< why it stopped, in words
    std::vector<ParameterEstimate> parameters;
    MuscleParameters muscle;              ///< the base muscle with the estimate written in
    std::vector<Observation> observations;
    std::vector<double> modelForces;      ///< at the estimate [N] (NaN where the model failed)
    std::vector<double> residuals;        ///< model - measured [N]
    double cost = 0;                      ///< 0.5 sum r^2 [N^2]
    double rmsResidual = 0;               ///< [N]
    int iterations = 0;
    int forwardEvaluations = 0;           ///< ForceModel::calcForces calls (each covers all observations)
    double wallTime = 0;                  ///< [s]
    // Uncertainty (lm only).
    bool hasUncertainty = false;
    std::string uncertaintyNote;          ///< why intervals are missing, or how they were made
    int degreesOfFreedom = 0;             ///< n - p
    double residualSd = kNaN;        ///< s: sqrt(SSR / (n - p)) or the given sd [N; 1 for relative noise]
    double intervalQuantile = kNaN;  ///< t or z quantile used for the intervals
    std::vector<std::vector<double>> covariance;   ///< p x p [unit_i unit_j]
    std::vector<std::vector<double>> correlation;  ///< p x p [1]
    std::vector<double> startCosts;       ///< lm multi-start: final cost of every start [N^2]
    std::vector<IterationRecord> history; ///< of the run (the best start for lm)
    std::vector<ModelCheck> checks;       ///< re-checks of the estimate with other models (addModelCheck)

    bool isConverged() const { return stopReason == StopReason::Converged; }
};

/// What to identify from what.
struct IdentificationProblem {
    MuscleParameters base;                             ///< known parameters + defaults for unknowns
    ObservationSet data;
    std::vector<Unknown> unknowns = makeDefaultUnknowns();
};

/// Runs the chosen method. Throws InputError for bad input: invalid observations (naming source and
/// line), a path beyond P_max, fewer distinct (path, activation) points than unknowns, a method that
/// does not fit the problem (false-position with more than one unknown, ...), invalid options.
/// Solver trouble never throws: it is reported in stopReason and message.
IdentificationReport identify(const IdentificationProblem& problem, const ForceModel& model,
                              const IdentificationOptions& options = {});

/// Identifies with `model` starting from the estimate of a cheap `warmModel` (lm on the same
/// problem, the unknowns' starts as given): an expensive model then only walks the last few
/// iterations. The warm estimate is used only when the warm run converged; otherwise the given
/// starts are kept (the message says which). The report is the second run's: its counts are the
/// expensive model's, its wallTime covers both runs and its message names the warm run's cost.
IdentificationReport identifyWarmStarted(const IdentificationProblem& problem, const ForceModel& warmModel,
                                         const ForceModel& model, const IdentificationOptions& options = {});

/// Settings of identifyCorrected.
struct CorrectionOptions {
    int maxCorrections = 10;    ///< expensive-model evaluations at most
    /// Stop when no unknown moves by more than this * its scale between corrections; NaN: the
    /// expensive model's getParameterTolerance() (below it the corrections only chase its noise).
    double tolerance = kNaN;
};

/// Output correction (defect correction, a form of space mapping): identifies with the cheap model
/// shifted by the expensive model's offset at the current estimate, c_j = fine(x_j) - cheap(x_j),
/// then re-evaluates the expensive model at the new estimate, until the estimate stops moving. Each
/// correction costs one expensive evaluation, whatever the method: five-angle identification with
/// the faithful model in ~3-4 faithful evaluations for every method. The fixed point x* minimises
/// ||cheap(x) + c* - y_d||; where the data can be reproduced (noise-free, or n = p) that is exactly
/// the expensive model's solution, otherwise it differs from the expensive model's own least-squares
/// point by a term in the difference of the two models' Jacobians (small when the offset varies
/// slowly with x, as the tare and transient offsets do).
/// Report: method as given, forceModel "<fine> (corrected <cheap>)", residuals and modelForces of the
/// expensive model, iterations = the inner runs' iterations, forwardEvaluations = expensive
/// evaluations, history = one record per correction (expensive residuals), uncertainty from the last
/// inner run (the cheap model's Jacobian). Stop reason: the last inner run's, or max-iterations when
/// the corrections did not settle.
IdentificationReport identifyCorrected(const IdentificationProblem& problem, const ForceModel& cheap,
                                       const ForceModel& fine, const IdentificationOptions& options = {},
                                       const CorrectionOptions& correction = {});

/// Evaluates `model` at report.muscle for report.observations and appends the forces and residuals
/// to report.checks; a model failure is recorded in ModelCheck::failure, never thrown.
void addModelCheck(IdentificationReport& report, const ForceModel& model, const std::string& note = "");

/// Unknowns with default settings from names ("mass", "optimal_tendon_length", ...).
std::vector<Unknown> makeUnknowns(const std::vector<std::string>& names);

}  // namespace armsim
