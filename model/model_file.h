// Model files (assets/models/*.yaml): an arm and its muscles, each a muscle model (Virtual Muscle by
// default) on its own path.
// Framework-free data; model/muscle_arm.h builds the Simbody system from it.
//
// A model file has
//   name, source, description            text
//   arm:                                 the arm file's sections inline (body, upper_arm,
//                                        forearm_hand, transducer, elbow, gravity, hand_load; see
//                                        model/arm_parameters.h), or the name of an arm file.
//                                        Its optional `biceps` section (A, B of the thesis's straight
//                                        line) defaults to the primary muscle's origin and insertion
//                                        distances from the elbow centre.
//   subject:                             voluntary_activation, co_contraction, trial_cv, fatigue
//                                        (defaults of the virtual subject's effort, see SubjectEffort)
//   specific_tension: SIGMA              [N/m^2] every muscle's sigma unless the muscle gives its own
//                                        (default: the fibre-type file's, Virtual Muscle's 31.8 N/cm^2)
//   max_firing_rate: FMAX                [f0.5] every motor unit's firing rate at full drive unless the
//                                        muscle gives its own (default: the fibre-type file's fmax, 2)
//   roles: {biceps: [NAMES], synergists: [NAMES], surface_emg: [NAMES]}
//                                        the heads of the thesis's "biceps" (the primary among them) and
//                                        the flexors the synergist-aware identifier estimates one by one
//                                        (default: the primary alone; none)
//   muscle_model: NAME or {model: NAME, COEFFICIENT: VALUE, ...}
//                                        every muscle's model (muscles/muscle_models.h: virtual_muscle,
//                                        the default, or thelen2003) and coefficients of that model over
//                                        its shipped file's (assets/muscles/NAME.yaml); a muscle's own
//                                        `muscle_model:` replaces the model, or adds coefficients to it
//   primary: NAME                        the muscle the thesis calls "the biceps": the transducer
//                                        estimate and the identification address it (default: first)
//   muscles: [...]                       each: name, group (flexor|extensor|forearm), muscle_model, Virtual Muscle
//                                        parameters (a `parameters:` muscle file and/or the fields of a
//                                        muscle file; `max_isometric_force` [N] or `volume` [m^3] may
//                                        stand for `mass` and `tendon_slack_length` [m] for
//                                        `optimal_tendon_length`; `specific_tension` [N/m^2],
//                                        `max_firing_rate` [f0.5]), and a
//                                        path: origin, via (points, cylinders, spheres), insertion.
//                                        A `parameters:` file's mass stays as that file gives it.
//
// Conversions from OpenSim (Holzbaur et al. 2005) parameters, stated once here:
//   mass = F0 L0 rho / sigma              (spec 1: F0 = sigma M / (rho L0)), sigma the muscle's
//   mass = rho V                          from an MRI volume V; F0 = sigma V / L0 then follows sigma
//   L0T  = tendon_slack_length / LrT      the VM series-elastic force is F0 cT (LT - LrT) on its linear
//                                         part, so LrT L0T is the length where the tendon's linear force
//                                         extrapolates to zero: the slack length of a Hill tendon. The
//                                         VM tendon then strains 1/LrT - 1 = 3.7 % at F0 (Thelen 2003's
//                                         OpenSim tendon: 3.3 %).
#pragma once

#include "basics/numbers.h"

#include "model/arm_parameters.h"
#include "muscles/muscle_models.h"
#include "muscles/virtual_muscle.h"

#include <array>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace armsim {

/// Which elbow effort recruits a muscle: a flexion or an extension MVC; Forearm: neither (a forearm
/// rotator: it acts at the co-contraction level in elbow efforts). As an effort direction only Flexor
/// (flexion) and Extensor (extension) are used.
enum class MuscleGroup { Flexor, Extensor, Forearm };
const char* getMuscleGroupName(MuscleGroup g);

/// What a subject tries to do in an isometric effort. Its agonists: the flexors (Flexion), the
/// extensors (Extension), or the muscles whose moment arm about the forearm axis in the pose turns the
/// forearm that way by more than kForearmAgonistMomentArm (Supination, Pronation; models with a
/// forearm rotation). Everything else acts at the co-contraction level.
enum class Effort { Flexion, Extension, Supination, Pronation };
/// Every effort, in enum order.
inline constexpr Effort kEfforts[] = {Effort::Flexion, Effort::Extension, Effort::Supination, Effort::Pronation};
/// "flexion", "extension", "supination" or "pronation".
const char* getEffortName(Effort e);
/// The effort getEffortName names; InputError "effort = 'x': expected flexion, extension, supination
/// or pronation" otherwise.
Effort parseEffortName(const std::string& name);
/// true for Supination and Pronation (the forearm axis is the effort's own).
inline bool isForearmEffort(Effort e) { return e == Effort::Supination || e == Effort::Pronation; }
/// Smallest moment arm about the forearm axis that makes a muscle an agonist of a rotation effort [m].
inline constexpr double kForearmAgonistMomentArm = 1e-3;
/// true when a muscle of `group` with moment arm `forearmMomentArm` about the forearm axis in the
/// effort's pose [m, + = supinates] is one of the effort's agonists.
inline bool isAgonistOf(Effort e, MuscleGroup group, double forearmMomentArm) {
    switch (e) {
        case Effort::Flexion: return group == MuscleGroup::Flexor;
        case Effort::Extension: return group == MuscleGroup::Extensor;
        case Effort::Supination: return forearmMomentArm > kForearmAgonistMomentArm;
        case Effort::Pronation: return forearmMomentArm < -kForearmAgonistMomentArm;
    }
    return false;
}

/// The bodies a path element can sit on (the radius only in arms with a forearm rotation).
enum class ArmBody { UpperArm, Forearm, Radius };
const char* getArmBodyName(ArmBody b);

/// One element of a muscle path in a model file (body frame, metres; frames in model/arm.h).
struct PathElementSpec {
    enum class Kind { Point, Cylinder, Sphere };
    Kind kind = Kind::Point;
    ArmBody body = ArmBody::UpperArm;
    std::array<double, 3> location{};   ///< point, or surface centre [m]
    std::array<double, 3> axis{0, 0, 1};  ///< cylinder axis [1]
    double radius = 0;                  ///< [m]
    std::array<double, 3> side{};       ///< the path passes on this side; zero = the shorter way
    bool winds = false;                 ///< with a side: may wind round by more than half a turn (muscle_path.h)
    /// A via point used only while the forearm rotation is in [min, max] (OpenSim's conditional path
    /// point; `active_rotation_deg: [min, max]`, + = supination) [deg]; both NaN = always.
    std::array<double, 2> activeRotationDeg{kNaN, kNaN};
    bool isConditional() const { return activeRotationDeg[0] == activeRotationDeg[0]; }
    std::string label;                  ///< "origin", "via 1", "cylinder 2", "insertion"
};

/// Scales fitted to a subject's measured strength or to anatomy targets (a model file's per-muscle
/// `calibration:`), applied to the source parameters: F0' = k s F0, L0' = f L0, L0T' = t L0T,
/// mass' = k f mass, sigma' = s sigma (so a muscle given by its volume V has volume k f V).
struct MuscleCalibration {
    double forceScale = 1;             ///< k, on the maximal isometric force F0 [1]
    double fascicleLengthScale = 1;    ///< f, on the optimal fascicle length L0 [1]
    double tendonLengthScale = 1;      ///< t, on the optimal tendon length L0T [1]
    double specificTensionScale = 1;   ///< s, on the specific tension sigma (F0 without mass) [1]
    bool isIdentity() const {
        return forceScale == 1 && fascicleLengthScale == 1 && tendonLengthScale == 1 && specificTensionScale == 1;
    }
    /// Throws FieldError naming the field unless every scale is in [0.2, 5].
    void validate() const;
};

/// One muscle of a model.
struct MuscleSpec {
    MuscleParameters params;              ///< Virtual Muscle parameters in use (calibration applied)
    MuscleParameters sourceParams;        ///< as the sources give them (before calibration)
    MuscleCalibration calibration;        ///< identity unless the file has `calibration:`
    MuscleGroup group = MuscleGroup::Flexor;
    std::vector<PathElementSpec> path;    ///< origin, via elements, insertion
    /// true: P_max is the longest path over the elbow's range (resolved by resolveMaxPathLengths);
    /// false: params.maxPathLength as given.
    bool maxPathFromRange = true;
    std::string source;                   ///< where the numbers come from
    /// The muscle model it is built with (muscles/muscle_models.h registry name) and that model's own
    /// coefficients (the model's shipped file, then the model file's, then the muscle's own).
    std::string muscleModel = kDefaultMuscleModel;
    std::map<std::string, double> muscleModelCoefficients;
    /// Sets calibration and recomputes params from sourceParams (P_max kept).
    void setCalibration(const MuscleCalibration& c);
};

/// The muscle built with its muscle model from its parameters as they stand (not validated as Virtual
/// Muscle parameters unless it is one; ArmSetup::buildMuscleModel validates them first).
std::shared_ptr<const MuscleModel> buildMuscleModel(const MuscleSpec& muscle);

/// The virtual subject's effort in a trial (spec: a realistic MVC).
struct SubjectEffort {
    double voluntaryActivation = 1.0;  ///< U of the agonists at a maximal effort [1]
    double coContraction = 0.0;        ///< U of the antagonists during an effort [1]
    double trialCv = 0.0;              ///< trial-to-trial coefficient of variation of the effort [1]
    double fatigue = 0.0;              ///< fractional loss of effort per repetition [1]
    void validate() const;
};

/// Everything that defines a simulated arm and its muscles (immutable model).
struct ArmSetup {
    std::string name = "thesis";          ///< model name
    std::string file;                     ///< the model file it came from ("" when built in code)
    std::string description;
    ArmParameters arm;                    ///< segments, elbow range, transducer (and the thesis's A, B)
    /// The model file's specific_tension [N/m^2]; 0: none given (each muscle's fibre-type file's sigma).
    double specificTension = 0;
    /// The model file's max_firing_rate, every motor unit's firing rate at full drive [f0.5]; 0: none
    /// given (each muscle's fibre-type file's fmax).
    double maxFiringRate = 0;
    SubjectEffort effort;                 ///< defaults of the subject's effort
    std::vector<MuscleSpec> muscles;
    int primary = 0;                      ///< index of the thesis's "biceps"
    /// Roles from the model file's `roles:` (muscle indices). bicepsHeads: the muscles that together are
    /// the thesis's "biceps" (the primary among them; empty: the primary alone, see getBicepsHeads);
    /// synergists: the other flexors an identifier estimates one by one (default none).
    std::vector<int> bicepsHeads;
    std::vector<int> synergists;
    /// surface_emg: the muscles surface electrodes reach (their EMG is a channel; default none).
    std::vector<int> surfaceEmg;
    std::vector<int> getBicepsHeads() const { return bicepsHeads.empty() ? std::vector<int>{primary} : bicepsHeads; }

    int getNumMuscles() const { return int(muscles.size()); }
    /// Index of the muscle called name; throws InputError listing the names.
    int findMuscle(const std::string& name) const;
    /// The primary muscle's parameters (the thesis's biceps).
    const MuscleParameters& biceps() const { return muscles.at(primary).params; }
    MuscleParameters& biceps() { return muscles.at(primary).params; }
    /// Validated parameters of muscle i (P_max as resolved).
    MuscleParameters calcMuscleParameters(int i) const;
    /// Muscle i built with its muscle model (validated; P_max as resolved).
    std::shared_ptr<const MuscleModel> buildMuscleModel(int i) const;
    /// true when every muscle is a Virtual Muscle.
    bool hasOnlyVirtualMuscles() const;
    /// Throws InputError unless muscle i (-1: every muscle) is a Virtual Muscle: `what` (e.g. "the
    /// identifiers") models it as one, and a Hill-type muscle must not be read as one silently.
    void requireVirtualMuscles(const std::string& what, int i = -1) const;
    /// The primary muscle's, as calcMuscleParameters(primary).
    MuscleParameters calcBicepsParameters() const { return calcMuscleParameters(primary); }
    /// Throws InputError for an inconsistent model (no muscles, duplicate names, bad primary).
    void validate() const;

    /// The thesis model (assets/models/thesis.yaml).
    static ArmSetup loadDefault();
};

/// The model with calibration[i] applied to muscle i (MuscleSpec::setCalibration; P_max, a geometric
/// limit, is kept). Throws std::logic_error unless there is one calibration per muscle.
ArmSetup applyCalibration(const ArmSetup& setup, const std::vector<MuscleCalibration>& calibration);

/// The model virtual subjects default to (the default population's, the main job's, protocols' and
/// `model show` / `check`'s): the anatomical twin.
inline const char* const kDefaultSubjectModel = "twin";

/// Every muscle of setup built with model `name` and coefficients (over the model's shipped file's);
/// InputError naming an unknown model or coefficient.
void setMuscleModel(ArmSetup& setup, const std::string& name, const std::map<std::string, double>& coefficients = {});
class ParamNode;
/// setMuscleModel from node's `muscle_model:` key (a name or {model: NAME, COEFFICIENT: VALUE}), as a
/// model file writes it; errors name the file and line.
void readMuscleModelKey(const ParamNode& node, ArmSetup& setup);

/// Loads a model: a name under assets/models/ ("thesis", "elbow", "twin") or a file path. Every error names
/// the file, line, key and value. P_max of muscles with `max_path_length: range` is resolved
/// (model/muscle_arm.h: resolveMaxPathLengths). A model loaded before is returned again without
/// the work while its file and every file it read (arm, muscle and fibre-type files) read byte for byte
/// as they did and no file it looked for has appeared or gone (thread-safe; up to 32 model files of
/// up to 4 MB are kept).
ArmSetup loadModel(const std::string& nameOrFile);

/// Names of the shipped models (files in assets/models/).
std::vector<std::string> listModels();

}  // namespace armsim
