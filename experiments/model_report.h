// `armsim model show`: a model's muscle table, moment arms and steady MVC torque-angle curves as CSV and
// PNG, with the published reference points of assets/measured/elbow_reference.yaml on the plots.
#pragma once

#include "basics/table.h"
#include "model/model_file.h"
#include "model/mvc_curve.h"

#include <string>
#include <vector>

namespace armsim {

/// Published moment-arm range of a muscle (or of a muscle family: doesFamilyCoverMuscle).
struct MomentArmReference {
    std::string muscle;
    double flexionDeg = 0;
    double min = 0, max = 0;   ///< [m], + = flexor
    std::string source;
};

/// A published MVC torque (mean and SD).
struct MvcTorqueReference {
    double flexionDeg = 0;
    double torque = 0;         ///< [N m], + = flexion
    double sd = 0;             ///< [N m], 0 = not given
    std::string source;
};

/// Published elbow reference data.
struct ElbowReference {
    std::vector<MomentArmReference> momentArms;
    std::vector<MvcTorqueReference> mvcFlexion, mvcExtension;
};

/// Reads a reference file (format of assets/measured/elbow_reference.yaml); errors name file, line, key.
ElbowReference loadElbowReference(const std::string& path);
/// assets/measured/elbow_reference.yaml.
ElbowReference loadDefaultElbowReference();


/// Muscle table: one row per muscle (F0, L0, L0T, mass, P_max, slow fraction, calibration scales).
/// Columns are numbers; muscle i is row i (names from setup).
Table calcMuscleTable(const ArmSetup& setup);
/// Path lengths and moment arms (virtual work) every stepDeg over the elbow's range: flexion_deg,
/// elbow_angle_deg, then path_<m>_m and moment_arm_<m>_m per muscle.
Table calcMomentArmTable(const ArmSetup& setup, double stepDeg);
/// Moment arms over the forearm rotation's range at one flexion angle [deg]: rotation_deg (every stepDeg
/// from the most pronated, + = supinated), forearm_moment_arm_<m>_m (+ = supinates) and moment_arm_<m>_m
/// (elbow, + = flexes) per muscle. Throws InputError for a model without a forearm rotation.
Table calcForearmMomentArmTable(const ArmSetup& setup, double flexionDeg, double stepDeg);
/// Steady MVC curve as a table: flexion_deg, elbow_angle_deg, torque_total_Nm, then torque_<m>_Nm,
/// force_<m>_N, fibre_length_<m> (L/L0) per muscle, and for a flexion effort the primary muscle's share
/// of the flexors' torque (primary_share).
Table formatMvcCurve(const ArmSetup& setup, const SteadyMvcCurve& curve);

/// Summary numbers of a flexion or extension MVC curve.
struct MvcCurveSummary {
    double peakTorque = 0;      ///< largest |total| [N m]
    double peakFlexionDeg = 0;  ///< where (parabola through the largest sample and its neighbours)
    double torqueAt90 = 0;      ///< |total| at 90 deg [N m] (interpolated)
};
MvcCurveSummary summarizeMvcCurve(const SteadyMvcCurve& curve);

/// What writeModelReport wrote.
struct ModelReportFiles {
    std::vector<std::string> files;
    Table muscles;                 ///< calcMuscleTable(setup), as written to muscles.csv
    MvcCurveSummary flexion, extension;
    double primaryShareAt90 = 0;   ///< primary muscle's share of the flexors' torque at 90 deg
};

/// Writes muscles.csv, moment_arms.csv/.png, mvc_flexion.csv/.png and mvc_extension.csv/.png (steady MVC at
/// the model's subject effort) into outDir (created). Every file is written whole or not at all.
ModelReportFiles writeModelReport(const ArmSetup& setup, const std::string& outDir, double stepDeg,
                                  const ElbowReference& reference);

}  // namespace armsim
