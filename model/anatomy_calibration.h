// Calibration to anatomy: fits a few scales of a model so that its MVC torque-angle curves, flexor
// shares, optimum-length angles and muscle volumes fall in the bands of a target file
// (model/anatomy_targets.h), each scale held near the model file's value (its anatomy) by a prior.
// `armsim model calibrate --targets FILE` runs it; assets/models/twin.yaml's `calibration:` lines are
// its output.
//
// Unknowns, all as ln(scale) around the model file's values (MuscleCalibration):
//   per muscle group (flexor, extensor): specific tension s, volume v, optimal fascicle length f;
//   per muscle: optimal tendon length t.
// Then k = v / f, so F0' = s v F0 / f and mass' = v mass. Residuals: for each target of kind mvc,
// forearm_mvc, posture_ratio, share, optimum_angle or volume, sqrt(weight) (value - band centre) / (half the band + tolerance): a
// band read as a Gaussian; for each unknown ln(scale) / prior sd; a penalty when a relaxed fascicle at
// the longest path would pass 90 % of its nf limit (room for the length spread of a population and of
// the identifier's prior, whose draws must have a steady state at every angle). Moment arms do not change with these scales and
// are not fitted. Only s v / f (F0) and v (volume) are pinned by torque and volume targets; how F0's
// scale splits between s and f is the priors' (and the optimum angles') call.
#pragma once

#include "model/anatomy_targets.h"
#include "model/model_file.h"

#include <string>
#include <vector>

namespace armsim {

/// Priors and bounds of the fit (ln sds; bounds on the scales).
struct AnatomyCalibrationOptions {
    double specificTensionSd = 0.25;   ///< s per group: in vivo values spread 25-30 N/cm^2 between studies and 16 % between people (docs/twin_literature.md B)
    double volumeSd = 0.40;            ///< v per group: MRI volumes of young adults have CV 44-48 % (Holzbaur et al. 2007)
    double fascicleLengthSd = 0.15;    ///< f per group: architecture sources differ by 10-20 % (docs/twin_literature.md D)
    double tendonLengthSd = 0.15;      ///< t per muscle: tendon slack lengths are the least known (model choice)
    double volumeMin = 0.4, volumeMax = 2.5;
    double fascicleMin = 0.7, fascicleMax = 1.5;
    double tendonMin = 0.5, tendonMax = 1.5;
    double specificTensionMin = 0.3, specificTensionMax = 4.0;
    int maxIterations = 60;
    /// Throws FieldError naming the field for a non-positive sd or an empty bound.
    void validate() const;
};

/// The fitted scales of one muscle group.
struct GroupScales {
    MuscleGroup group = MuscleGroup::Flexor;
    double specificTension = 1;   ///< s [1]
    double volume = 1;            ///< v [1]
    double fascicleLength = 1;    ///< f [1]
};

/// Result of a calibration to anatomy.
struct AnatomyCalibrationResult {
    std::vector<MuscleCalibration> muscles;   ///< one per muscle (k = v / f, f, t, s)
    std::vector<GroupScales> groups;          ///< groups present in the model
    std::vector<TargetScore> before, after;   ///< scores of the model file as given and calibrated
    double cost = 0;                          ///< final 0.5 sum of squared residuals
    int iterations = 0;
    bool converged = false;
    std::string report;                       ///< the solver's one-line report
};

/// Fits the scales starting from the model's source parameters (its present calibration is
/// replaced). Throws InputError when no target of a fitted kind names the model's muscles.
AnatomyCalibrationResult calibrateToAnatomy(const ArmSetup& setup, const std::vector<AnatomyTarget>& targets,
                                            const AnatomyCalibrationOptions& options = {});

}  // namespace armsim
