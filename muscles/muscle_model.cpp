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

}  // namespace armsim
