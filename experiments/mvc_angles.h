// MVC at a list of elbow angles, as the main job shows them: the thesis arm's force per angle beside
// the thesis's two force estimates, and a multi-muscle subject's every muscle force and torque beside
// the thesis's biceps estimate (tared torque over the biceps moment arm). Tables and plots; no printing.
#pragma once

#include "basics/plot.h"
#include "basics/table.h"
#include "model/trial.h"

#include <functional>
#include <vector>

namespace armsim {

/// A sweep's results: one table row per angle (column names below), and its plot.
struct MvcAngleSweep {
    Table table;
    PlotSpec plot;
};

/// The setup's MVC (U = 1 on the primary muscle's arm, 3 s hold, mean of the last second) at each angle
/// [deg, thesis convention: 180 = extended], in parallel. Columns: elbow_angle_deg, path_length_m,
/// moment_arm_m, muscle_force_N, strap_force_N, force_moment_arm_N, force_fixed_ratio_N, rest_force_N.
MvcAngleSweep runMvcAngleSweep(const ArmSetup& setup, const std::vector<double>& anglesDeg, int jobs,
                               const std::function<void(int, int)>& progress = {});

/// A virtual subject's MVC (agonists at its voluntary activation, antagonists co-contracting) at each
/// angle. Columns: elbow_angle_deg, flexion_deg, tared_torque_Nm, strap_force_N, primary_moment_arm_m,
/// primary_force_N, biceps_both_heads_N (every head the model file names), thesis_estimate_N,
/// estimate_error_vs_both_heads_pct, then force_<muscle>_N and torque_<muscle>_Nm per muscle.
MvcAngleSweep runSubjectMvcAngleSweep(const ArmSetup& setup, const std::vector<double>& anglesDeg, int jobs,
                                      const std::function<void(int, int)>& progress = {});

}  // namespace armsim
