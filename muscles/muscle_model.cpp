#include "muscles/muscle_model.h"

namespace armsim {

MuscleOutputs MuscleModel::calcOutputs(double pathLength, double U, const double* y) const {
    MuscleOutputs out;
    std::vector<double> ydot(static_cast<std::size_t>(getNumStates()));
    calcStateDerivative(pathLength, U, y, ydot.data(), &out);
    return out;
}

}  // namespace armsim
