// Internal to armsim_identification: the state the solvers share (forward evaluations, history).
#pragma once

#include "identification/identifier.h"

#include <string>
#include <vector>

namespace armsim::detail {

/// Forward-model access for one identify() run: counts evaluations, keeps the history and a small
/// cache of recent evaluations (so a solver callback can look up a point it already evaluated).
class SolverContext {
public:
    SolverContext(const ParameterMap& map, const ForceModel& model, const std::vector<Observation>& obs,
                  const IdentificationOptions& options);

    const ParameterMap& map;
    const ForceModel& model;
    const std::vector<Observation>& observations;
    const IdentificationOptions& options;

    int getNumObservations() const { return int(observations.size()); }
    int getNumUnknowns() const { return map.size(); }
    /// r = model - measured at x [N]. False (and getLastFailure() says why) when the model fails
    /// or returns a non-finite force. Counts one forward evaluation unless the point is cached.
    bool calcResiduals(const std::vector<double>& x, std::vector<double>& r);
    const std::string& getLastFailure() const { return lastFailure_; }
    int getEvaluations() const { return evaluations_; }
    /// Appends (iteration, x, r, cost) to the history.
    void record(int iteration, const std::vector<double>& x, const std::vector<double>& r);
    std::vector<IterationRecord>& getHistory() { return history_; }
    /// Resets history (multi-start keeps the best start's history).
    std::vector<IterationRecord> takeHistory();
    /// "mass = 0.336 kg, optimal_tendon_length = 0.245 m".
    std::string describe(const std::vector<double>& x) const;
    /// True when every |r_k| <= forceTolerance.
    bool isReproduced(const std::vector<double>& r) const;

private:
    struct CacheEntry {
        std::vector<double> x, r;
        bool ok = false;
        std::string failure;
    };
    int evaluations_ = 0;
    std::string lastFailure_;
    std::vector<IterationRecord> history_;
    std::vector<CacheEntry> cache_;
    std::size_t cacheNext_ = 0;
};

/// 0.5 sum r^2.
double calcCost(const std::vector<double>& r);

/// What a solver returns to identify().
struct SolverOutcome {
    std::vector<double> x;       ///< estimate [SI]
    std::vector<double> r;       ///< residuals at x [N] (empty: model failed at x)
    StopReason reason = StopReason::NotConverged;
    std::string message;
    int iterations = 0;
};

SolverOutcome solveFalsePosition(SolverContext& ctx);
SolverOutcome solveIlc(SolverContext& ctx);
/// Also fills the report's uncertainty fields and start costs.
SolverOutcome solveLeastSquares(SolverContext& ctx, IdentificationReport& report);

}  // namespace armsim::detail
