// The Simbody adapter of a muscle model (muscles/muscle_model.h): a Force::Custom that owns the muscle
// states as Simbody continuous (z) states and applies the tendon force along its path (muscles/muscle_path.h): a straight line between
// two stations, or a path through via points and over wrapping surfaces.
#pragma once

#include "muscles/activation.h"
#include "muscles/muscle_path.h"
#include "muscles/simbody.h"
#include "muscles/muscle_model.h"

#include <memory>
#include <vector>

namespace armsim {

/// A muscle model acting along a MusclePath.
///
/// The muscle's states (MuscleModel::getNumStates(), all of order 1) are allocated as z states in
/// realizeTopology and their derivatives written in realizeDynamics; the tension Fse acts along the
/// path (pulling origin and insertion together, pressing on via points and wrapping surfaces).
/// Activation U(t) comes from an ActivationProfile evaluated at the state's time. Path length P [m]
/// must stay inside (0, P_max].
///
/// Like every Simbody handle this class has no data members; the implementation holds the model.
class MuscleForce : public SimTK::Force::Custom {
public:
    MuscleForce() = default;
    MuscleForce(SimTK::GeneralForceSubsystem& forces, std::shared_ptr<const MuscleModel> muscle,
                       const SimTK::MobilizedBody& originBody, const SimTK::Vec3& originStation,
                       const SimTK::MobilizedBody& insertionBody, const SimTK::Vec3& insertionStation,
                       ActivationProfile activation);
    MuscleForce(SimTK::GeneralForceSubsystem& forces, std::shared_ptr<const MuscleModel> muscle,
                       MusclePath path, ActivationProfile activation);

    const MuscleModel& getMuscle() const;
    const MusclePath& getPath() const;
    const ActivationProfile& getActivationProfile() const;
    /// Replaces U(t). The derivatives of states realized at Stage::Dynamics or above are stale afterwards:
    /// a caller invalidates them (State::invalidateAllCacheAtOrAbove(Stage::Dynamics)).
    void setActivationProfile(ActivationProfile activation);

    /// Path length P [m] (Stage::Position).
    double getPathLength(const SimTK::State& s) const;
    /// The path at the state's configuration: length, unit-tension loads, polyline (Stage::Position).
    PathGeometry calcPathGeometry(const SimTK::State& s, bool withPolyline = false) const;
    /// Activation U at the state's time [1].
    double getActivation(const SimTK::State& s) const;
    /// Muscle (series-elastic) force Fse [N] (Stage::Position).
    double getForce(const SimTK::State& s) const;
    /// Fascicle length L L0 [m] and velocity V L0 [m/s] (positive = lengthening).
    double getFascicleLength(const SimTK::State& s) const;
    double getFascicleVelocity(const SimTK::State& s) const;
    /// All derived outputs (Fse, Fce, per-unit Af and fenv, ...) (Stage::Position).
    MuscleOutputs calcOutputs(const SimTK::State& s) const;

    /// The muscle's slice of the state vector.
    std::vector<double> getMuscleStates(const SimTK::State& s) const;
    /// Where the muscle's states start in s.getZ() (after realizeTopology).
    int getFirstStateIndex(const SimTK::State& s) const;
    void setMuscleStates(SimTK::State& s, const std::vector<double>& y) const;
    /// Sets the spec-5 initial state for the current path length (Stage::Position realized here).
    void setInitialMuscleStates(SimTK::State& s) const;
    /// Sets the steady isometric state at the current path length and activation at the state's
    /// time; throws SimulationError if the steady solve finds no equilibrium.
    void setSteadyMuscleStates(SimTK::State& s) const;

    /// Throws SimulationError naming the time, the muscle and the state element if a muscle state is
    /// not finite or the fascicle has left the model's validity range (nf > 0, L > 0). Call at step
    /// boundaries.
    void checkMuscleStates(const SimTK::State& s) const;

    /// Colour of the path line as a function of the PCSA-weighted activation (blue at rest, red at 1).
    static SimTK::Vec3 calcActivationColor(double activeFraction);

    class Impl;
private:
    const Impl& getImpl() const;
};

}  // namespace armsim
