// The thesis's method on joint torque data: the biceps force is the tared torque over the primary
// muscle's moment arm, and a primary-muscle-only model at full activation is fitted to those forces
// (steady model, Levenberg-Marquardt, relative noise; intervals from the residual scatter).
#pragma once

#include "experiments/torque_protocol.h"
#include "identification/torque_estimate.h"

namespace armsim {

/// The thesis's method on torque data, with `assumed` as the experimenter's model (geometry and the
/// biceps's other parameters; its primary muscle is the biceps).
MuscleEstimate identifyThesisMethod(const ArmSetup& assumed, const std::vector<TorqueObservation>& data);

}  // namespace armsim
