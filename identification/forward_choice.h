// Identification as `armsim identify` (and the Python module's identify) runs it: the forward model
// chosen by name, iterations with a fast protocol, then the estimate re-checked with the steady model
// and with the faithful model at the thesis's reference protocol (1000 Hz). One function, so the
// command and the module give the same report for the same inputs.
#pragma once

#include "identification/faithful_model.h"
#include "identification/identifier.h"

#include <string>

namespace armsim {

/// The forward model an identification iterates with.
struct ForwardModelChoice {
    /// "steady" (isometric solve), "faithful" (Simbody arm trials in the loop, warm-started from the
    /// steady estimate unless warmStart is false) or "corrected" (steady iterations corrected by the
    /// faithful model, identifyCorrected).
    std::string model = "steady";
    ForceEstimate estimate = ForceEstimate::MomentArm;  ///< faithful: the force the experimenter reports
    double holdDuration = 3.0;   ///< faithful iterations: effort [s]; the mean of its last third (at most 1 s)
    double sampleRate = 200.0;   ///< faithful iterations: transducer sample rate [Hz]
    bool warmStart = true;       ///< faithful: start from the steady lm estimate
    int jobs = 2;                ///< faithful: trials run in parallel

    /// InputError naming the field (model, jobs) and the expected values; hold and rate are checked
    /// by the faithful model (FaithfulProtocol::validate, fields protocol.hold, protocol.sample_rate).
    void validate() const;
    /// The faithful model's options in the iterations.
    FaithfulModelOptions makeIterationOptions() const;
    /// The same at the reference protocol (FaithfulProtocol::makeReference), for the re-check.
    FaithfulModelOptions makeReferenceOptions() const;
};

/// The names ForwardModelChoice::model may take.
const std::vector<std::string>& getForwardModelNames();

/// Identifies `problem` with `choice`'s forward model on `arm`, then appends two re-checks of the
/// estimate (addModelCheck): the steady model, and the faithful model at the reference protocol.
/// For the faithful kinds the observations' elbow angles are checked first (InputError naming the
/// file and line of a path outside the elbow's range). iterationModel, if given, receives the
/// iterating faithful model's description (empty for steady).
IdentificationReport identifyAndRecheck(const IdentificationProblem& problem, const IdentificationOptions& options,
                                        const ArmParameters& arm, const ForwardModelChoice& choice,
                                        std::string* iterationModel = nullptr);

/// Path length P(theta) of the arm's straight-line biceps, for observations given as elbow angles.
PathFromAngle makeArmPathFromAngle(const ArmParameters& arm);

/// readObservations with angle columns converted by the arm's own geometry.
ObservationSet readArmObservations(const std::string& file, const ArmParameters& arm, int subject = -1);

}  // namespace armsim
