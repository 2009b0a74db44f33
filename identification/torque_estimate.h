// An identifier's estimate of the primary muscle's mass and optimal tendon length, with intervals and
// the nuisance parameters: the result every torque-data identifier returns.
#pragma once

#include "basics/numbers.h"

#include <string>
#include <vector>

namespace armsim {

/// How one channel's measurements fit at an estimate: chi-square of (model - value) / sd.
struct ChannelFit {
    std::string channel;           ///< torque, fascicle_length, volume, emg, upper_arm_length, activation
    int n = 0;                     ///< measurements
    double chiSquare = kNaN;
    double p = kNaN;          ///< chi-square tail probability with n degrees of freedom; < 0.05: misfit
    std::string worst;             ///< the measurement with the largest |residual| / sd, described
    double worstResidual = kNaN;  ///< its (model - value) / sd
};

/// An identifier's estimate of the primary muscle (the biceps long head).
struct MuscleEstimate {
    std::string method;                  ///< "thesis", "synergist" or "synergist-va"
    bool converged = false;
    std::string message;                 ///< solver summary or why it failed
    double mass = kNaN;             ///< M [kg]
    double tendonLength = kNaN;     ///< L0T [m]
    double massLower = kNaN, massUpper = kNaN;        ///< 95 % interval [kg]
    double tendonLower = kNaN, tendonUpper = kNaN;    ///< 95 % interval [m]
    double noiseLevel = kNaN;       ///< relative torque sd used to weight the data [1]
    int noiseDegreesOfFreedom = 0;       ///< of that sd's estimate (repetitions); 0: taken as known
    std::vector<std::string> nuisanceNames;    ///< synergist: activation, co-contraction, length and mass scales
    std::vector<double> nuisance;              ///< their estimates
    double massTendonCorrelation = kNaN;  ///< posterior correlation of ln M and ln L0T
    double rmsResidual = kNaN;            ///< of the torque [N m] (thesis: of the force [N])
    /// Per observation: the torque the method predicts at the estimate [N m] (thesis: the fitted biceps
    /// force x the biceps moment arm, flexion MVCs only; NaN elsewhere).
    std::vector<double> predictedTorque;
    /// F0 = sigma M / (rho L0) of the primary muscle [N] with its 95 % interval, and the specific tension
    /// sigma the mass assumes [N/m^2] (NaN for methods that do not estimate them).
    double maxForce = kNaN, maxForceLower = kNaN, maxForceUpper = kNaN;
    double specificTension = kNaN;
    /// Per channel (torque first), the fit at the estimate (synergist kinds only).
    std::vector<ChannelFit> channelFits;
    int numParameters = 0;                     ///< free parameters of the fit
    int iterations = 0;                        ///< solver iterations
};

}  // namespace armsim
