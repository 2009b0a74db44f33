#include "identification/forward_choice.h"

#include "basics/bound.h"
#include "model/geometry.h"

#include <algorithm>

namespace armsim {

const std::vector<std::string>& getForwardModelNames() {
    static const std::vector<std::string> names = {"steady", "faithful", "corrected"};
    return names;
}

void ForwardModelChoice::validate() const {
    const auto& names = getForwardModelNames();
    if (std::find(names.begin(), names.end(), model) == names.end())
        throw InputError("forward model '" + model + "': expected steady, faithful or corrected");
    checkField("jobs", jobs, Bound::closed(1, 64));  // hold and rate: FaithfulProtocol::validate
}

FaithfulModelOptions ForwardModelChoice::makeIterationOptions() const {
    FaithfulModelOptions o;
    o.estimate = estimate;
    o.protocol.holdDuration = holdDuration;
    o.protocol.averagingWindow = std::min(o.protocol.averagingWindow, holdDuration / 3);
    o.protocol.sampleRate = sampleRate;
    o.jobs = jobs;
    return o;
}

FaithfulModelOptions ForwardModelChoice::makeReferenceOptions() const {
    FaithfulModelOptions o = makeIterationOptions();
    o.protocol = FaithfulProtocol::makeReference();
    return o;
}

IdentificationReport identifyAndRecheck(const IdentificationProblem& pr, const IdentificationOptions& o,
                                        const ArmParameters& arm, const ForwardModelChoice& choice,
                                        std::string* iterationModel) {
    choice.validate();
    const SteadyForceModel steady;
    const FaithfulForceModel fast(arm, choice.makeIterationOptions()), reference(arm, choice.makeReferenceOptions());
    IdentificationReport r;
    if (iterationModel) iterationModel->clear();
    // Every path inside the arm's range, before any work: the faithful model rechecks the fit below
    // whichever model fits (an error here names the data's file and line).
    fast.calcElbowAngles(pr.data);
    if (choice.model == "steady") {
        r = identify(pr, steady, o);
    } else {
        if (choice.model == "faithful")
            r = choice.warmStart ? identifyWarmStarted(pr, steady, fast, o) : identify(pr, fast, o);
        else
            r = identifyCorrected(pr, steady, fast, o);
        if (iterationModel) *iterationModel = fast.describe();
    }
    addModelCheck(r, steady, "steady model (isometric solve)");
    addModelCheck(r, reference, reference.describe());
    return r;
}

PathFromAngle makeArmPathFromAngle(const ArmParameters& arm) {
    const double A = arm.originDistance, B = arm.insertionDistance;
    return [A, B](double theta) { return calcBicepsPathLength(A, B, theta); };
}

ObservationSet readArmObservations(const std::string& file, const ArmParameters& arm, int subject) {
    ObservationOptions oo;
    oo.pathFromAngle = makeArmPathFromAngle(arm);
    oo.subject = subject;
    return readObservations(file, oo);
}

}  // namespace armsim
