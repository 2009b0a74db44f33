// `armsim model check`: a model's scorecard against anatomy targets (model/anatomy_targets.h) as CSV,
// a per-kind summary and plots with the published bands drawn.
#pragma once

#include "model/anatomy_targets.h"
#include "model/osim_file.h"

#include <string>
#include <vector>

namespace armsim {

/// What writeModelCheck wrote and scored.
struct ModelCheckResult {
    std::vector<TargetScore> scores;
    std::vector<ScoreSummary> summary;
    std::vector<std::string> files;
};

/// Scores `setup` and writes into outDir (created): scorecard.csv (one row per target and muscle: kind,
/// muscle, direction, flexion_deg, value, lower, upper, tolerance, unit, pass, source, where; SI units),
/// score_summary.csv (passed / scored per kind and muscle), check_moment_arms.png (each muscle's moment
/// arm over the elbow's range with the target bands) and check_mvc.png (flexion and extension MVC
/// curves with their bands). Files are written whole or not at all.
ModelCheckResult writeModelCheck(const ArmSetup& setup, const std::vector<AnatomyTarget>& targets,
                                 const std::string& outDir);

/// The same for an OpenSim model (model/osim_anatomy.h): `coordinate` as the elbow (its value in
/// degrees as flexion), each muscle's model from the file or muscleModel. Volume and forearm targets are
/// not scored (the file has no muscle masses or armsim forearm).
ModelCheckResult writeOsimModelCheck(const OsimModel& model, const std::string& coordinate, const std::string& muscleModel,
                                     const std::vector<AnatomyTarget>& targets, const std::string& outDir);

}  // namespace armsim
