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
/// Two models: SteadyForceModel (the steady isometric solve, this file) and FaithfulForceModel
/// (faithful_model.h), which runs the MVC protocol in the Simbody arm through the transducer chain.
class ForceModel {
public:
    virtual ~ForceModel() = default;
    /// Predicted forces [N] at the observations' path lengths and activations.
    virtual std::vector<double> calcForces(const MuscleParameters& params,
                                           const std::vector<Observation>& observations) const = 0;
    /// Short name for reports ("steady", "faithful").
    virtual std::string getName() const = 0;
    /// Central-difference step for lm's Jacobian, in the unknowns' scaled units (x / scale), suited to
    /// the model's numerical noise: a step h turns a relative force noise e into a derivative error of
    /// about e / h. Default 1e-6 for a model solved to round-off.
    virtual double getDifferenceStep() const { return 1e-6; }
    /// lm stops when a step changes the scaled unknowns by less than this (Ceres parameter_tolerance);
    /// below the model's noise a smaller value only buys rejected steps. Default 1e-12.
    virtual double getParameterTolerance() const { return 1e-12; }
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
