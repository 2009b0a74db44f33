// `armsim model show` for an OpenSim model (.osim): the muscle table, each muscle's path length and
// moment arm over one coordinate's range (the others at their defaults), and the steady "MVC" torque
// about it in each direction, as the armsim-model report writes them (model show's files and columns).
#pragma once

#include "model/osim_file.h"

#include <string>
#include <vector>

namespace armsim {

/// What to sweep.
struct OsimReportSettings {
    std::string coordinate;  ///< the swept coordinate; "" = the model's only moving coordinate
    double stepDeg = 5;      ///< [deg]
    std::string muscleModel; ///< "" = each muscle's type in the file (model/osim_arm.h)
};

/// What was written, and the curves' summary.
struct OsimReportFiles {
    std::vector<std::string> files;
    std::string coordinate;                            ///< the one swept
    double peakPositive = 0, peakPositiveDeg = 0;      ///< largest torque in the + direction [N m], where [deg]
    double peakNegative = 0, peakNegativeDeg = 0;      ///< largest in the - direction (a positive number) [N m], [deg]
};

/// Writes into outDir (created; every file whole or not at all):
/// - muscles.csv: muscle, muscle_model, F0_N, optimal_fiber_length_m, tendon_slack_length_m, pennation_angle_rad;
/// - moment_arms.csv/.png: flexion_deg (the coordinate, deg) over its range, moment_arm_<muscle>_m (virtual
///   work, + = the coordinate's positive direction) and path_length_<muscle>_m;
/// - mvc_flexion.csv/.png and mvc_extension.csv/.png: flexion_deg, torque_total_Nm, torque_<muscle>_Nm and
///   fibre_length_<muscle>: the steady isometric torque with every muscle that moves the coordinate in
///   that direction at full excitation and the others at none (their passive force), + for flexion.
/// InputError naming the coordinate for one that is not there, not rotational, or when none was named
/// and the model has several.
OsimReportFiles writeOsimModelReport(const OsimModel& model, const OsimReportSettings& settings, const std::string& outDir);

}  // namespace armsim
