#include "identification/force_model.h"

#include <limits>

namespace armsim {

std::vector<double> SteadyForceModel::calcForces(const MuscleParameters& params,
                                                 const std::vector<Observation>& observations) const {
    const VirtualMuscle muscle(params);
    std::vector<double> forces;
    forces.reserve(observations.size());
    for (const Observation& o : observations) {
        const SteadyState s = muscle.calcSteadyState(o.pathLength, o.activation);
        forces.push_back(s.converged ? s.force : std::numeric_limits<double>::quiet_NaN());
    }
    return forces;
}

}  // namespace armsim
