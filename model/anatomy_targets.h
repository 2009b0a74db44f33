// Anatomy targets (assets/reference/elbow_targets.yaml) and a model's score against them: moment arms
// vs angle, net MVC torque vs angle, muscle volumes, flexor torque shares and the angle at which each
// muscle works at its optimal fibre length. What `armsim model check` reports and what a calibration
// to anatomy fits.
#pragma once

#include "basics/numbers.h"

#include "model/model_file.h"
#include "model/mvc_curve.h"

#include <map>
#include <string>
#include <vector>

namespace armsim {

/// What a target measures.
enum class TargetKind { MomentArm, Mvc, Volume, Share, OptimumAngle, ForearmMvc, PostureRatio };
const char* getTargetKindName(TargetKind k);
/// The unit a target file gives a kind's bands in ("mm", "N m", "cm^3", "1", "deg", "N m", "1").
const char* getTargetFileUnit(TargetKind k);
/// The SI unit of a kind's bands and values ("m", "N m", "m^3", "1", "deg").
const char* getTargetSiUnit(TargetKind k);
/// Factor from the file unit to SI (1e-3 for mm).
double getTargetFileToSi(TargetKind k);

/// True when a family name covers a model muscle: a prefix (family "ABC" covers muscles "ABClong" and
/// "ABCshort"; the names are the target file's and the model file's).
bool doesFamilyCoverMuscle(const std::string& family, const std::string& muscle);

/// One published value with its band. Family names cover model muscles by prefix
/// (doesFamilyCoverMuscle); moment-arm and optimum-angle targets score each covered muscle, volume and
/// share targets the family's sum.
struct AnatomyTarget {
    TargetKind kind = TargetKind::MomentArm;
    std::string muscle;           ///< family or muscle name; empty for mvc
    MuscleGroup direction = MuscleGroup::Flexor;   ///< mvc: flexion or extension effort
    Effort forearmEffort = Effort::Supination;   ///< forearm_mvc: supination or pronation
    double rotationDeg = 0;       ///< forearm posture [deg] (forearm_mvc, posture_ratio; + = supinated)
    double flexionDeg = kNaN;///< angle [deg] (moment_arm, mvc, share); NaN for volume, optimum_angle
    double lower = 0, upper = 0;  ///< published band, SI (m, N m, m^3, 1, deg)
    double tolerance = 0;         ///< added on both sides of the band before judging (SI, as the band)
    double weight = 1;            ///< in a calibration's objective [1]
    std::string source;           ///< where the band comes from
    std::string where;            ///< "file:line" of the entry
};

/// What a target's effort or posture is, for reports: "flexion", "extension", "supination at rotation -45 deg",
/// "flexion at rotation 60 deg / neutral"; "" for kinds without one.
std::string describeTargetCondition(const AnatomyTarget& t);

/// Reads a target file; errors name file, line, field, value and what was expected.
std::vector<AnatomyTarget> loadAnatomyTargets(const std::string& path);
/// assets/reference/elbow_targets.yaml.
std::vector<AnatomyTarget> loadDefaultAnatomyTargets();

/// The model's value for one target (and one muscle of it where the target scores each).
struct TargetScore {
    AnatomyTarget target;
    std::string muscle;           ///< the model muscle (or family) scored
    double value = kNaN;     ///< model value, SI; NaN when the model has none (e.g. no optimum in range)
    double fitValue = kNaN;  ///< value, or where the model's trend puts it beyond the range (what a fit steers by)
    bool pass = false;            ///< value within [lower - tolerance, upper + tolerance]
};

/// A model as scoring sees it: its muscles' names and volumes, and at sorted flexion angles (0 =
/// extended) their moment arms and steady MVC curves. armsim models (calcAnatomyCurves) and OpenSim
/// models (model/osim_anatomy.h) are scored through it.
struct AnatomyCurves {
    std::vector<std::string> muscles;
    std::vector<double> volume;                    ///< per muscle [m^3]; NaN: not known (volume targets not scored)
    double minFlexionDeg = 0, maxFlexionDeg = 0;   ///< the elbow's range [deg]
    std::vector<double> flexionDeg;                ///< sorted, unique [deg]
    std::vector<std::vector<double>> momentArm;    ///< [angle][muscle] h, + = flexes [m]
    SteadyMvcCurve flexion, extension;             ///< the MVC curves at the model's effort
    SteadyMvcCurve full;                           ///< flexion at full activation without co-contraction
};
/// The curves of an armsim model at flexionDeg (sorted, unique, within the elbow's range).
AnatomyCurves calcAnatomyCurves(const ArmSetup& setup, const std::vector<double>& flexionDeg);
/// The angles a scoring needs: each target's within [minDeg, maxDeg], and every 1 deg of the range when
/// an optimum_angle target needs the fibre-length crossing.
std::vector<double> findAnatomyAngles(const std::vector<AnatomyTarget>& targets, double minDeg, double maxDeg);
/// Scores the curves against the moment-arm, MVC, volume, share and optimum-angle targets as
/// scoreAnatomy does (forearm targets need an armsim model's forearm: not scored here). The curves must
/// hold every angle findAnatomyAngles gives.
std::vector<TargetScore> scoreAnatomyCurves(const AnatomyCurves& curves, const std::vector<AnatomyTarget>& targets);

/// Scores `setup` against every target. Moment arms from virtual work at the angle, MVC torque from the
/// steady MVC curve at the model's subject effort (the magnitude for extension), forearm_mvc the
/// magnitude of the steady forearm torque of a supination or pronation MVC at the angle and posture,
/// posture_ratio the flexion MVC at the posture over that in neutral (both skipped for a model without a
/// forearm rotation), volume = mass / density,
/// share = the family's part of the flexion torque of the muscles all share targets name (as the
/// sources, whose shares add up to 1) at a flexion MVC, not scored when a family they name has no muscle, optimum angle = the flexion angle
/// where the muscle's steady fibre length at a full flexion MVC crosses L0 (NaN: it does not within the
/// elbow's range). Targets naming no model muscle are skipped.
std::vector<TargetScore> scoreAnatomy(const ArmSetup& setup, const std::vector<AnatomyTarget>& targets);

/// Throws InputError at a moment_arm target's line when its band lies on the other side of zero from a
/// muscle it names (flexors > 0, extensors < 0: elbow moment arms are positive in flexion).
void checkMomentArmSigns(const ArmSetup& setup, const std::vector<AnatomyTarget>& targets);

/// The angles scoreAnatomy evaluates a model at (each target's angle, and every 1 deg of the elbow's range
/// when an optimum_angle target needs the fibre-length crossing) and the geometry there, per forearm
/// posture for the forearm targets. Scales of a calibration change no geometry, so a fit computes it once.
struct AnatomySweep {
    std::vector<double> flexionDeg;   ///< sorted, unique [deg]
    MvcGeometry geometry;
    /// The forearm targets' angles (sorted, unique) at each forearm posture they need [deg]: theirs, and
    /// neutral for a posture_ratio. Empty without a forearm rotation.
    std::map<double, MvcGeometry> byRotation;
};
AnatomySweep calcAnatomySweep(const ArmSetup& setup, const std::vector<AnatomyTarget>& targets);
/// scoreAnatomy on a sweep made for this model's geometry.
std::vector<TargetScore> scoreAnatomy(const ArmSetup& setup, const std::vector<AnatomyTarget>& targets,
                                      const AnatomySweep& sweep);

/// Passed and scored counts of one kind (and muscle, when not empty).
struct ScoreSummary {
    TargetKind kind;
    std::string muscle;
    int passed = 0, scored = 0;
};
/// Per kind, and per muscle for moment arms and optimum angles.
std::vector<ScoreSummary> summarizeScores(const std::vector<TargetScore>& scores);

}  // namespace armsim
