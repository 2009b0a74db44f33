// The arm with its biceps long head: an ArmModel plus a VirtualMuscleForce from the origin station
// on the upper arm to the insertion station on the forearm.
#pragma once

#include "model/arm.h"
#include "muscles/activation.h"
#include "muscles/muscle_force.h"
#include "muscles/virtual_muscle.h"

#include <memory>

namespace armsim {

/// Everything that defines the simulated subject: arm and biceps parameters (immutable model).
struct ArmSetup {
    ArmParameters arm;            ///< segments, geometry, transducer, joint stops
    MuscleParameters biceps;      ///< the biceps long head
    /// true: the muscle's P_max is set to the path length at the elbow's extension limit (issue 3
    /// default); false: keep the muscle file's value.
    bool musclePmaxFromArm = true;

    /// The muscle parameters the arm uses (P_max applied), validated.
    MuscleParameters calcBicepsParameters() const;
    /// Loads the default subject: assets/arm/default_male.yaml and assets/muscles/biceps_long_head.yaml.
    static ArmSetup loadDefault();
};

/// One simulated arm: its own Simbody System (build one per thread). The biceps is driven by the
/// given activation profile; the System is finalized (topology realized) on construction.
class BicepsArm {
public:
    BicepsArm(const ArmSetup& setup, ActivationProfile activation);
    BicepsArm(const BicepsArm&) = delete;
    BicepsArm& operator=(const BicepsArm&) = delete;

    const ArmModel& getArm() const { return *arm_; }
    const VirtualMuscleForce& getBiceps() const { return biceps_; }
    const VirtualMuscle& getMuscle() const { return *muscle_; }
    const SimTK::MultibodySystem& getSystem() const { return arm_->getSystem(); }
    /// Default state: elbow extended, muscle states zero (set them before integrating).
    const SimTK::State& getDefaultState() const { return arm_->getDefaultState(); }

private:
    std::unique_ptr<ArmModel> arm_;
    std::shared_ptr<const VirtualMuscle> muscle_;
    VirtualMuscleForce biceps_;
};

}  // namespace armsim
