// One muscle's curves as the main job shows them: the steady force-length curve checked against full
// time integrations at a few paths (one quantity two ways), and a step-activation time course.
// Tables and plots; no printing.
#pragma once

#include "basics/plot.h"
#include "basics/table.h"
#include "muscles/virtual_muscle.h"

#include <functional>
#include <vector>

namespace armsim {

/// The steady force-length curve with its integration checks.
struct ForceLengthSweep {
    /// Columns: path_length_m, force_U1_N, force_U05_N, force_passive_N, fascicle_length_U1_m (NaN where
    /// the steady solve does not converge).
    Table table;
    PlotSpec plot;
    std::vector<double> checkPaths;        ///< [m]
    std::vector<double> steadyForces;      ///< steady solve at U = 1 at each check path [N]
    std::vector<double> integratedForces;  ///< end of a 3 s CPodes integration at U = 1 [N]
    double peakForce = 0, peakPath = 0;    ///< the curve's largest force at U = 1 [N] and its path [m]
};

/// The steady force at U = 1, 0.5 and 0 from `from` to the muscle's P_max in steps of `step` [m], and
/// 3 s integrations at each of checkPaths [m]; progress(done, total) after each integration.
ForceLengthSweep calcForceLengthSweep(const VirtualMuscle& m, double from, double step,
                                      const std::vector<double>& checkPaths,
                                      const std::function<void(int, int)>& progress = {});

/// A step of activation 0 -> 1 at `onset` [s], path held at `pathLength` [m], `duration` [s] long.
struct StepResponse {
    Table table;              ///< runMuscleIsometric's columns
    PlotSpec plot;
    double finalForce = 0;    ///< Fse at the end [N]
    double steadyForce = 0;   ///< the steady solve at U = 1 at the same path [N]
    double riseTime = 0;      ///< from onset to 90 % of finalForce [s]; NaN if never reached
    int steps = 0;            ///< integrator steps
};
StepResponse runStepActivation(const VirtualMuscle& m, double pathLength, double onset, double duration);

}  // namespace armsim
