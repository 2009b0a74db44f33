// Calibration to anatomy: fits a few scales of a model so that its MVC torque-angle curves, flexor
// shares, optimum-length angles and muscle volumes fall in the bands of a target file
// (model/anatomy_targets.h), each scale held near the model file's value (its anatomy) by a prior.
// `armsim model calibrate --targets FILE` runs it; assets/models/twin.yaml's `calibration:` lines are
// its output.
//
// Unknowns, all as ln(scale) around the model file's values (MuscleCalibration):
//   per muscle group (flexor, extensor, forearm): specific tension s, volume v, optimal fascicle length f;
//   per muscle: optimal tendon length t and its own fascicle scale f_m (architecture sources differ per
//   muscle: Murray et al. 2000 against arm26 spans 0.82-1.15).
// Then F0' = s v F0 / (f f_m) and mass' = v mass. Residuals, for each target of kind mvc, forearm_mvc,
// posture_ratio, share, optimum_angle or volume:
//   - the band's shape: sqrt(weight) (value - band centre) / (half the band + tolerance), a Gaussian;
//   - the goal, from the second stage on: zero inside the pass region (band +/- tolerance) less a margin
//     of a quarter of the tolerance (1 % of the value at least), then the excess in units of
//     stage x tolerance. The stages (goalStages, 1 then 0.3 then 0.1) tighten it from where the last
//     ended: what passes is a constraint, and the bands' shape and the priors choose among the models
//     that pass;
// for each unknown ln(scale) / prior sd; a penalty when a relaxed fascicle at the longest path would
// pass 90 % of its nf limit (room for the length spread of a population and of the identifier's prior,
// whose draws must have a steady state at every angle). Moment arms do not change with these scales and
// are not fitted. Only s v / f (F0) and v (volume) are pinned by torque and volume targets; how F0's
// scale splits between s and f is the priors' (and the optimum angles') call.
#pragma once

#include "model/anatomy_targets.h"
#include "model/model_file.h"

#include <functional>
#include <string>
#include <vector>

namespace armsim {

/// Priors and bounds of the fit (ln sds; bounds on the scales).
struct AnatomyCalibrationOptions {
    double specificTensionSd = 0.25;   ///< s per group: in vivo values spread 25-30 N/cm^2 between studies and 16 % between people (docs/twin_literature.md B)
    double volumeSd = 0.40;            ///< v per group: MRI volumes of young adults have CV 44-48 % (Holzbaur et al. 2007)
    double fascicleLengthSd = 0.15;    ///< f per group: architecture sources differ by 10-20 % (docs/twin_literature.md D)
    double tendonLengthSd = 0.15;      ///< t per muscle: tendon slack lengths are the least known (model choice)
    double muscleFascicleLengthSd = 0.10;   ///< f_m per muscle about its group's f: Murray et al. 2000 / arm26 per muscle, 0.82-1.15
    std::vector<double> goalStages = {1, 0.3, 0.1};   ///< goal residual units, tightened in turn (none: the bands' shape alone)
    double volumeMin = 0.4, volumeMax = 2.5;
    double fascicleMin = 0.7, fascicleMax = 1.5;            ///< the group's f
    double muscleFascicleMin = 0.8, muscleFascicleMax = 1.25;   ///< a muscle's own f_m (so f f_m spans 0.56-1.88)
    double tendonMin = 0.5, tendonMax = 1.5;
    double specificTensionMin = 0.3, specificTensionMax = 4.0;
    int maxIterations = 200;     ///< per stage
    /// Called after each stage (1-based) with the targets it passes; may be empty.
    std::function<void(int stage, int numStages, int passed, int total)> progress;
    /// Throws FieldError naming the field for a non-positive sd or an empty bound.
    void validate() const;
};

/// The fitted scales of one muscle group.
struct GroupScales {
    MuscleGroup group = MuscleGroup::Flexor;
    double specificTension = 1;   ///< s [1]
    double volume = 1;            ///< v [1]
    double fascicleLength = 1;    ///< f [1] (each muscle's scale is f f_m: MuscleCalibration)
};

/// Result of a calibration to anatomy.
struct AnatomyCalibrationResult {
    std::vector<MuscleCalibration> muscles;   ///< one per muscle (k = v / (f f_m), f f_m, t, s)
    std::vector<GroupScales> groups;          ///< groups present in the model
    std::vector<TargetScore> before, after;   ///< scores of the model file as given and calibrated
    double cost = 0;                          ///< final 0.5 sum of squared residuals
    int iterations = 0;                       ///< over every stage
    bool converged = false;
    std::string report;                       ///< the solver's one-line report
};

/// Fits the scales starting from the model's source parameters (its present calibration is
/// replaced). Throws InputError when no target of a fitted kind names the model's muscles.
AnatomyCalibrationResult calibrateToAnatomy(const ArmSetup& setup, const std::vector<AnatomyTarget>& targets,
                                            const AnatomyCalibrationOptions& options = {});

}  // namespace armsim
