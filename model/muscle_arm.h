// The arm built from a model (model/model_file.h): an ArmModel plus one muscle force element (its
// muscle model from the model file) per muscle, each on its own path (muscles/muscle_path.h: via points, wrapping cylinders and spheres).
#pragma once

#include "model/arm.h"
#include "model/model_file.h"
#include "muscles/activation.h"
#include "muscles/muscle_force.h"
#include "muscles/virtual_muscle.h"

#include <memory>
#include <string>
#include <vector>

namespace armsim {

/// The MusclePath of a muscle spec on an arm's bodies.
MusclePath buildMusclePath(const ArmModel& arm, const MuscleSpec& muscle);

/// One simulated arm with its muscles: its own Simbody System (build one per thread), finalized on
/// construction. Muscle i is driven by activations[i].
class MuscleArm {
public:
    MuscleArm(const ArmSetup& setup, std::vector<ActivationProfile> activations);
    /// Every muscle driven by the same profile.
    MuscleArm(const ArmSetup& setup, const ActivationProfile& activation);
    MuscleArm(const MuscleArm&) = delete;
    MuscleArm& operator=(const MuscleArm&) = delete;

    const ArmSetup& getSetup() const { return setup_; }
    const ArmModel& getArm() const { return *arm_; }
    const SimTK::MultibodySystem& getSystem() const { return arm_->getSystem(); }
    /// Default state: elbow extended, muscle states zero (set them before integrating).
    const SimTK::State& getDefaultState() const { return arm_->getDefaultState(); }

    int getNumMuscles() const { return int(forces_.size()); }
    const MuscleForce& getMuscleForce(int i) const { return forces_.at(i); }
    /// For replacing muscle i's activation profile (MuscleForce::setActivationProfile).
    MuscleForce& updMuscleForce(int i) { return forces_.at(i); }
    const MuscleModel& getMuscle(int i) const { return forces_.at(i).getMuscle(); }
    const std::string& getMuscleName(int i) const { return setup_.muscles.at(i).params.name; }
    /// The primary muscle (the thesis's biceps).
    const MuscleForce& getBiceps() const { return forces_.at(setup_.primary); }
    const MuscleModel& getMuscle() const { return getBiceps().getMuscle(); }

    /// Path length of muscle i [m] (Stage::Position).
    double calcPathLength(const SimTK::State& s, int i) const;
    /// Moment arm of muscle i about the elbow [m], + = flexes: the elbow torque of a unit tension along
    /// its path, through Simbody's system Jacobian (virtual work). Equals -dP/dq. Stage::Position.
    double calcMomentArm(const SimTK::State& s, int i) const;
    /// Moment arm of muscle i about the forearm rotation axis [m], + = supinates; 0 without one.
    double calcForearmMomentArm(const SimTK::State& s, int i) const;

    /// Every muscle at its steady isometric state for the present path and activation; throws
    /// SimulationError naming the muscle when one has no equilibrium.
    void setSteadyMuscleStates(SimTK::State& s) const;
    /// Every muscle at the spec-5 initial state.
    void setInitialMuscleStates(SimTK::State& s) const;
    /// checkMuscleStates of every muscle (step boundaries).
    void checkMuscleStates(const SimTK::State& s) const;

    /// Names of the trial-table state columns, in state order: "state_<state>" for a one-muscle
    /// model, "state_<muscle>_<state>" otherwise.
    std::vector<std::string> getStateColumnNames() const;
    /// Every muscle's states, in the order of getStateColumnNames().
    void appendMuscleStates(const SimTK::State& s, std::vector<double>& row) const;
    /// Sets every muscle's states from values in that order.
    void setMuscleStates(SimTK::State& s, const std::vector<double>& y) const;

private:
    ArmSetup setup_;
    std::unique_ptr<ArmModel> arm_;
    std::vector<MuscleForce> forces_;
};

/// Path geometry of a model without muscles or states: lengths and moment arms at any elbow angle.
/// Cheap to query (one Position realization); not thread-safe (owns one State).
class ArmGeometry {
public:
    explicit ArmGeometry(const ArmSetup& setup);
    int getNumMuscles() const { return int(paths_.size()); }
    /// Sets the elbow to theta (included angle, rad) and realizes positions.
    void setElbowAngle(double theta);
    /// Path geometry of muscle i at the present angle (length, unit-tension loads).
    PathGeometry calcPathGeometry(int i) const;
    /// Path length of muscle i at the present angle [m].
    double calcPathLength(int i) const { return calcPathGeometry(i).length; }
    /// Moment arm by virtual work [m] (as MuscleArm::calcMomentArm) of a path geometry at the present angle.
    double calcMomentArm(const PathGeometry& g) const;
    double calcMomentArm(int i) const { return calcMomentArm(calcPathGeometry(i)); }
    /// Locks the forearm rotation at phi [rad] (+ = supination) and realizes positions; the arm must
    /// have a forearm rotation (std::logic_error otherwise).
    void setForearmRotation(double phi);
    /// Moment arm about the forearm rotation axis by virtual work [m], + = supinates; 0 without one.
    double calcForearmMomentArm(const PathGeometry& g) const;
    double calcForearmMomentArm(int i) const { return calcForearmMomentArm(calcPathGeometry(i)); }
    const ArmModel& getArm() const { return arm_; }
    const SimTK::State& getState() const { return state_; }
    const MusclePath& getPath(int i) const { return paths_.at(i); }

private:
    ArmModel arm_;
    std::vector<MusclePath> paths_;
    std::vector<std::string> names_;
    SimTK::State state_;
};

/// Moment arm [m] of a path's unit-tension loads about the pin of `joint`: the generalized force
/// J^T F on its first mobility (Stage::Position).
double calcPathMomentArm(const SimTK::SimbodyMatterSubsystem& matter, const SimTK::MobilizedBody& joint,
                         const SimTK::State& s, const PathGeometry& g);

/// Sets P_max of every muscle with maxPathFromRange to its longest path over the elbow's range
/// (sampled every degree, then refined to 1e-10 rad).
void resolveMaxPathLengths(ArmSetup& setup);

/// Where an integrator of the arm restarts: findRestartTimes (muscles/muscle_model.h) of every muscle
/// and its own activation profile, together.
std::vector<double> findRestartTimes(const MuscleArm& model, bool stepsOnly = false);

}  // namespace armsim
