#include "muscles/muscle_model.h"

#include "basics/errors.h"

namespace armsim {

std::vector<double> MuscleModel::calcInitialState(double pathLength) const {
    const SteadyState s = calcSteadyState(pathLength, 0.0);
    if (!s.converged) throw InputError("muscle '" + getName() + "': " + s.message);
    return s.states;
}

MuscleOutputs MuscleModel::calcOutputs(double pathLength, double U, const double* y) const {
    MuscleOutputs out;
    std::vector<double> ydot(static_cast<std::size_t>(getNumStates()));
    calcStateDerivative(pathLength, U, y, ydot.data(), &out);
    return out;
}

std::vector<double> findRestartTimes(const MuscleModel& muscle, const ActivationProfile& profile, bool stepsOnly) {
    const std::vector<double>& t = profile.getBreakpoints();
    std::vector<double> times;
    for (std::size_t k = 0; k < t.size(); ++k)
        if (!stepsOnly || (k > 0 && t[k] == t[k - 1])) times.push_back(t[k]);
    const std::vector<double> crossings = profile.findCrossings(muscle.getActivationThresholds());
    times.insert(times.end(), crossings.begin(), crossings.end());
    return times;
}

}  // namespace armsim
