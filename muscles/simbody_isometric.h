// Time integration helpers shared by every armsim simulation, and the muscle-only isometric run
// (both path ends on Ground at a fixed path length).
#pragma once

#include "basics/table.h"
#include "muscles/activation.h"
#include "muscles/simbody.h"
#include "numerics/stiff_ode.h"
#include "muscles/muscle_model.h"

#include <functional>
#include <vector>

namespace armsim {

/// Integrates system with CPodes from state.getTime() for `duration` seconds.
/// - sample(state) is called at t0 + k / sampleRate for k = 0 .. round(duration * sampleRate), with
///   a scratch State holding the time and the interpolated q, u, z (cubic Hermite between internal
///   steps) and realized to no stage: realize what you need, or use the pure model on getZ();
/// - the integrator restarts at each breakpoint inside the interval (discontinuities of inputs such
///   as a step in activation), so a step never smears across an error-controlled step;
/// - check(state) runs after every internal step (step boundaries): it throws SimulationError to stop
///   a run that left the model's validity range; every q, u and z is checked for NaN here too.
/// Throws SimulationError naming the time when the integrator fails.
IntegrationStats simulateSampled(const SimTK::MultibodySystem& system, SimTK::State& state, double duration,
                                 double sampleRate, const std::vector<double>& breakpoints,
                                 const IntegrationSettings& settings,
                                 const std::function<void(const SimTK::State&)>& sample,
                                 const std::function<void(const SimTK::State&)>& check = {});

/// A muscle-only isometric trial: the path held at a constant length.
struct MuscleIsometricSettings {
    double pathLength = 0.375;                                 ///< P [m] (thesis 37.5 cm)
    ActivationProfile activation = ActivationProfile::constant(1.0);  ///< U(t)
    double duration = 3.0;                                     ///< simulated time [s]
    double sampleRate = 1000.0;                                ///< output samples per second [Hz]
    bool startSteady = false;  ///< true: start at the steady state for U(0); false: spec-5 initial state
    /// false (default): integrate the muscle ODE directly (integrateSampled); true: integrate a Simbody
    /// System holding the muscle between two Ground points (simulateSampled), the reference path the
    /// tests compare the default with (same steps, same samples to 1e-6; about 10x slower).
    bool integrateSimbodySystem = false;
    IntegrationSettings integration;
    /// Throws InputError naming the field for a bad value (path checked against the muscle's P_max).
    void validate(const MuscleModel& muscle) const;
};

/// Runs the trial and returns its time series: time_s, activation, force_N (Fse), fce_N,
/// fascicle_length_m, fascicle_velocity_mps, tendon_length_m, active_fraction.
Table runMuscleIsometric(const MuscleModel& muscle, const MuscleIsometricSettings& settings,
                         IntegrationStats* stats = nullptr);

}  // namespace armsim
