// Strength calibration: fits per-muscle scales of a model (MuscleCalibration: tendon length per muscle,
// one fascicle-length and one force scale per muscle group) so that its steady MVC torque-angle curve
// (model/mvc_curve.h) matches a target curve. This is how assets/models/elbow.yaml's `calibration:`
// entries were made (docs/elbow_model_sources.md); `armsim model calibrate` runs it.
#pragma once

#include "model/model_file.h"
#include "model/mvc_curve.h"

#include <string>
#include <vector>

namespace armsim {

/// A target MVC torque-angle curve of one effort.
struct MvcTorqueTarget {
    MuscleGroup effort = MuscleGroup::Flexor;
    std::vector<double> flexionDeg;   ///< 0 = full extension
    std::vector<double> torque;       ///< net muscle torque, + = flexion [N m]
    std::string source;               ///< where the numbers come from
};

/// Target for the elbow's flexion MVC: peak 80 N m at 95 deg flexion (centre of the accepted 70-90 N m
/// at 80-110 deg; Holzbaur et al. 2007 J Biomech 40:2442: 79.5 +/- 8.1 N m at 90 deg),
/// falling as a parabola on each side to 55 % of the peak at 20 and 130 deg (the accepted floor is
/// 45 %; the thesis's bell-shaped force-angle curve stays above 75 % of its peak between 30 and 135 deg).
/// Sampled every 10 deg from 20 to 130 deg.
MvcTorqueTarget getElbowFlexionTarget();
/// Target for the elbow's extension MVC: -60 N m at 90 deg flexion (centre of the accepted 45-75 N m).
MvcTorqueTarget getElbowExtensionTarget();

/// Bounds and weights of the fit.
struct StrengthCalibrationOptions {
    double tendonScaleMin = 0.5, tendonScaleMax = 1.2;       ///< t per muscle
    double fascicleScaleMin = 0.8, fascicleScaleMax = 1.5;   ///< f of the group (fixed 1 if !fitFascicleLength)
    double forceScaleMin = 0.8, forceScaleMax = 2.5;         ///< k of the group
    bool fitFascicleLength = true;
    /// Weight of the prior ln(scale) = 0 residuals against the torque residuals in units of
    /// torqueScale: keeps an under-determined fit near the source values.
    double regularization = 1.0;
    double torqueScale = 10.0;                               ///< [N m] per unit residual
    /// Every muscle of the group keeps its steady fascicle length within 1 +/- midRangeTolerance (L0) at
    /// midRangeDeg (a penalty residual outside): no muscle may fall slack or overstretched mid-range to
    /// buy breadth elsewhere (every elbow flexor is active and strong at 90 deg).
    double midRangeDeg = 90.0;
    double midRangeTolerance = 0.2;
    double midRangeWeight = 20.0;
    /// Angles [deg] where every muscle must keep a steady state in a flexion and an extension effort
    /// (the elbow's range ends by default).
    std::vector<double> feasibilityDeg;
    int maxIterations = 100;
};

/// Result of a calibration.
struct StrengthCalibrationResult {
    std::vector<MuscleCalibration> muscles;   ///< one per muscle; identity outside the target's group
    double rmsTorqueError = 0;                ///< [N m] over the target's angles
    double maxTorqueError = 0;                ///< [N m]
    int iterations = 0;
    bool converged = false;
    std::string report;                       ///< the solver's one-line report
};

/// Fits the scales of the muscles of target.effort's group, starting from the source parameters (the
/// model's present calibration of those muscles is replaced). Other muscles keep theirs and act at
/// their co-contraction level. Throws InputError for an empty target or angles outside the range.
StrengthCalibrationResult calibrateStrength(const ArmSetup& setup, const MvcTorqueTarget& target,
                                            const StrengthCalibrationOptions& options = {});

}  // namespace armsim
