// Validation of the identifiers against ground truth: MVC data synthesized with the faithful model
// (the Simbody arm through the transducer chain, thesis protocol at 1000 Hz) for known muscles, with
// transducer noise, identified by every method; one row per (truth, noise level, method).
#pragma once

#include "basics/fields.h"

#include "identification/faithful_model.h"
#include "identification/identifier.h"
#include "identification/thesis_cases.h"
#include "model/geometry.h"

#include <functional>
#include <iterator>
#include <string>
#include <vector>

namespace armsim {

/// Range of the random true masses [kg]: the thesis's 336 g +/- about 30 % (biceps heads weigh
/// 0.1..0.5 kg, thesis Table 4.2 after Li & Tong 2005).
constexpr double kValidationMassLow = 0.25, kValidationMassHigh = 0.45;
/// Range of the random true optimal tendon lengths [m]: 24.5 cm +/- 2 cm, which keeps the five MVC
/// angles on both sides of the force-length peak with L0 = 16 cm and the default arm (a wider range
/// puts all five on one limb, where mass and L0T trade off almost exactly).
constexpr double kValidationTendonLow = 0.225, kValidationTendonHigh = 0.265;

/// How validation identifies (the data always come from the faithful model at the reference protocol).
enum class ValidationModel {
    Steady,     ///< "steady": the steady model alone (shows its bias on tared transducer data)
    Faithful,   ///< "faithful": the faithful model (200 Hz) in the loop, warm-started from steady lm
    Corrected   ///< "corrected": steady iterations corrected by the faithful model (identifyCorrected)
};
std::string getValidationModelName(ValidationModel m);
ValidationModel parseValidationModelName(const std::string& name);

struct ValidationSettings {
    std::vector<double> noiseLevels = {0, 0.01, 0.02, 0.05};  ///< relative sd of each measured force [1]
    int seeds = 1;                 ///< random truths in addition to the thesis's (M = 336 g, L0T = 24.5 cm)
    unsigned seed = 1;             ///< seed of the truths and the noise
    std::vector<Method> methods;   ///< empty: getValidationMethods()
    std::vector<double> anglesDeg{std::begin(kThesisMvcAnglesDeg), std::end(kThesisMvcAnglesDeg)};  ///< MVC angles [deg]
    ForceEstimate estimate = ForceEstimate::MomentArm;       ///< what the simulated experimenter reports
    ValidationModel model = ValidationModel::Corrected;
    double startMass = kThesisStartMass;                 ///< [kg] every run's start (thesis Tables 7.2, 7.3)
    double startTendonLength = kThesisStartTendonLength;  ///< [m]
    int jobs = 2;                  ///< threads for the trials of one evaluation
    /// InputError naming the field for bad values (noise in [0, 0.5), seeds >= 0, angles in the arm's range,
    /// at most kMaxValidationFits fits).
    void validate(const ArmParameters& arm) const;
    /// (seeds + 1) x noise levels x methods: the identifications runValidation makes.
    double countFits() const;
};

/// The most fits runValidation takes (its rows are kept in memory, about 1 GB at this count; a study
/// journals its rows instead).
constexpr double kMaxValidationFits = 4e6;

/// One identification of one synthetic data set.
struct ValidationRow {
    std::string truth;             ///< "thesis" or "random N"
    double noise = 0;              ///< relative force sd [1]
    std::string method;
    double trueMass = 0, trueTendonLength = 0;   ///< [kg], [m]
    double mass = 0, tendonLength = 0;           ///< estimates [kg], [m]
    double massError = 0, tendonLengthError = 0; ///< relative errors (estimate / truth - 1) [1]
    int massCovered = -1;          ///< 1/0: the truth is inside / outside the 95 % interval; -1: no interval
    int tendonLengthCovered = -1;
    std::string stopReason;
    int iterations = 0;
    int evaluations = 0;           ///< forward evaluations of the identifying model (faithful ones when it is used)
    double wallTime = 0;           ///< [s]
};

/// The methods that fit two unknowns and several observations: lm and the two-output learning family
/// (false-position and ilc-standard need one unknown or one observation).
std::vector<Method> getValidationMethods();

/// Makes the truths (the thesis's, then `seeds` uniform draws in the ranges above), synthesizes each
/// one's data once with the reference faithful model, adds noise sd * force * eps with the SAME
/// standard-normal eps at every noise level (common random numbers: rows differ only by the level),
/// and identifies with every method. progress(done, total) after each identification.
std::vector<ValidationRow> runValidation(const ArmParameters& arm, const MuscleParameters& base,
                                         const ValidationSettings& settings,
                                         const std::function<void(int, int)>& progress = {});

/// A row's fields (basics/fields.h): validation.csv is made from them.
const FieldTable<ValidationRow>& getValidationFields();
/// CSV text (header + one line per row; errors in %, coverage 1/0/empty).
std::string formatValidationCsv(const std::vector<ValidationRow>& rows);
/// Fixed-width table for a terminal (g, cm, %), and per method and noise level the interval coverage
/// over the truths.
std::string formatValidationTable(const std::vector<ValidationRow>& rows);

}  // namespace armsim
