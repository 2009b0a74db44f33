// Forward models for identification: muscle parameters + observation conditions -> predicted forces.
#pragma once

#include "identification/observations.h"
#include "muscles/virtual_muscle.h"

#include <string>
#include <vector>

namespace armsim {

/// The forward model an identifier fits: the muscle force predicted at each observation's path
/// length and activation for a given parameter set. Implementations must be const-thread-safe.
///
/// Contract: returns one force [N] per observation, in order. An entry is NaN when the model has no
/// solution there (no equilibrium, a fascicle beyond the model's range); the identifier treats it as
/// a failed trial. Invalid parameters throw InputError/FieldError, a model that cannot run at all
/// throws SimulationError; the identifier reports both as a failed evaluation, with the message.
///
/// Two models: SteadyForceModel (the steady isometric solve, this file) and a "faithful" model that
/// runs the full protocol in the Simbody arm (added in experiments/model by the lead).
class ForceModel {
public:
    virtual ~ForceModel() = default;
    /// Predicted forces [N] at the observations' path lengths and activations.
    virtual std::vector<double> calcForces(const MuscleParameters& params,
                                           const std::vector<Observation>& observations) const = 0;
    /// Short name for reports ("steady", "faithful").
    virtual std::string getName() const = 0;
};

/// The steady isometric force: VirtualMuscle::calcSteadyState(P, U).force (spec section 6), i.e. the
/// plateau of an isometric MVC trial without the transient. Microseconds per observation.
class SteadyForceModel : public ForceModel {
public:
    std::vector<double> calcForces(const MuscleParameters& params,
                                   const std::vector<Observation>& observations) const override;
    std::string getName() const override { return "steady"; }
};

}  // namespace armsim
