// The Simbody arm: upper arm welded to Ground, forearm + hand on an elbow pin, gravity, soft joint
// stops, and the stations of the biceps path and the transducer strap. No muscle: force elements
// (the Virtual Muscle) are added through updForces() before finalize().
//
// Frames (planar model in the sagittal X-Y plane; the thesis's 15 deg shoulder abduction (6.1.2) is
// ignored, it does not change the elbow mechanics of a fixed upper arm in a vertical plane):
//   Ground = upper-arm frame: origin at the elbow centre, +Y up along the upper arm to the shoulder,
//            +X anterior (the flexed forearm points there), +Z the elbow axis (lateral).
//   Forearm frame: origin at the elbow centre, forearm axis along -Y, elbow pin about +Z.
//   Pin coordinate q = flexion angle = pi - theta: q = 0 fully extended (forearm hanging along -Y),
//   q = pi/2 forearm horizontal along +X. Positive pin torque flexes the elbow.
//   Radius frame (arms with a forearm rotation): coincides with the forearm frame at phi = 0 and turns
//   by phi about the rotation axis (+ = supination); the radius carries the given fraction of the
//   forearm + hand mass properties, the forearm the rest (the same sum at phi = 0).
// Angles are radians here; theta is the included elbow angle (geometry.h).
#pragma once

#include "model/arm_parameters.h"
#include "muscles/simbody.h"

namespace armsim {

class ArmModel {
public:
    /// Validates params (FieldError naming the field) and builds bodies, mobilizers, gravity, joint
    /// stops, stations and decorations. Does NOT realize topology: add force elements first.
    explicit ArmModel(const ArmParameters& params);
    ArmModel(const ArmModel&) = delete;
    ArmModel& operator=(const ArmModel&) = delete;

    const ArmParameters& getParameters() const { return params_; }

    /// @name Construction (before finalize())
    /// @{
    /// The force subsystem to which force elements (the muscle) are added. Throws std::logic_error
    /// after finalize(), when a new element would not be part of the realized topology.
    SimTK::GeneralForceSubsystem& updForces();
    /// Sets the point mass [kg] held at the hand COM (replaces params.handLoad). Before finalize().
    void setHandLoad(double mass);
    /// Realizes topology and model; returns the default state (elbow extended, theta = pi, at rest).
    /// Call once, after every force element is added.
    const SimTK::State& finalize();
    bool isFinalized() const { return finalized_; }
    /// The default state made by finalize(); throws std::logic_error before it.
    const SimTK::State& getDefaultState() const;
    /// @}

    /// @name Simbody objects
    /// @{
    const SimTK::MultibodySystem& getSystem() const { return system_; }
    SimTK::MultibodySystem& updSystem() { return system_; }
    const SimTK::SimbodyMatterSubsystem& getMatter() const { return matter_; }
    const SimTK::GeneralForceSubsystem& getForces() const { return forces_; }
    const SimTK::MobilizedBody::Weld& getUpperArm() const { return upperArm_; }
    const SimTK::MobilizedBody::Pin& getForearm() const { return forearm_; }
    /// The radius (and hand) on its pronation-supination pin; an empty handle unless the arm has a
    /// forearm rotation (ArmParameters::forearmRotation).
    const SimTK::MobilizedBody::Pin& getRadius() const { return radius_; }
    bool hasForearmRotation() const { return params_.forearmRotation.enabled; }
    const SimTK::Force::Gravity& getGravity() const { return gravity_; }
    const SimTK::Force::MobilityLinearStop& getElbowStop() const { return elbowStop_; }
    /// @}

    /// @name Stations (body-frame positions, m)
    /// @{
    /// Biceps origin on the upper arm: (0, A, 0).
    const SimTK::Vec3& getOriginStation() const { return origin_; }
    /// Biceps insertion on the forearm: (0, -B, 0).
    const SimTK::Vec3& getInsertionStation() const { return insertion_; }
    /// Transducer strap on the forearm: (0, -d1, 0).
    const SimTK::Vec3& getStrapStation() const { return strap_; }
    /// Hand COM on the forearm, where the hand load sits: (0, -handComFraction * forearmLength, 0).
    const SimTK::Vec3& getHandStation() const { return hand_; }
    /// @}

    /// @name Elbow state (theta = included angle, rad)
    /// @{
    /// Sets q = pi - theta (no range check: the stops act in simulation).
    void setElbowAngle(SimTK::State& state, double theta) const;
    double getElbowAngle(const SimTK::State& state) const;
    /// Sets dtheta/dt [rad/s] (u = -dtheta/dt).
    void setElbowAngularVelocity(SimTK::State& state, double thetaDot) const;
    /// dtheta/dt [rad/s]: positive while extending.
    double getElbowAngularVelocity(const SimTK::State& state) const;
    /// Locks the elbow at theta (q = pi - theta, u = 0) with MobilizedBody::lockAt; lowers the state
    /// to Stage::Model.
    void lockElbow(SimTK::State& state, double theta) const;
    void unlockElbow(SimTK::State& state) const;
    bool isElbowLocked(const SimTK::State& state) const { return forearm_.isLocked(state); }
    /// @}

    /// @name Forearm rotation (phi, rad: + = supination, 0 = neutral); only with hasForearmRotation()
    /// @{
    /// Locks the radius at phi (the default state holds the posture of the parameters); lowers the
    /// state to Stage::Model. Throws std::logic_error without a forearm rotation.
    void lockForearmRotation(SimTK::State& state, double phi) const;
    double getForearmRotation(const SimTK::State& state) const;
    /// Torque [N m] the forearm lock applies about the rotation axis, + = supination (as
    /// calcHoldingTorque: the state locked and realized to Stage::Acceleration).
    double calcForearmHoldingTorque(const SimTK::State& state) const;
    /// @}

    /// @name Measurements
    /// @{
    /// Biceps path length |origin - insertion| [m] from the Simbody station positions.
    /// State realized to Stage::Position.
    double calcPathLength(const SimTK::State& state) const;
    /// Biceps flexion moment arm [m] from the station positions: the Z component of
    /// r_insertion x unit(origin - insertion) about the elbow centre, i.e. the pin torque per newton of
    /// path tension; positive = the muscle flexes. State realized to Stage::Position.
    double calcMomentArm(const SimTK::State& state) const;
    /// Torque [N m] the elbow lock applies to hold the forearm, from findMotionForces. Sign: positive
    /// = applied in the flexion direction (+q), so under gravity alone with the forearm forward it is
    /// +m g r sin(theta); a muscle pulling harder than gravity makes it negative. The state must be
    /// locked (lockElbow) and realized to Stage::Acceleration; throws std::logic_error otherwise.
    double calcHoldingTorque(const SimTK::State& state) const;
    /// Mass properties of the forearm body (forearm + hand + hand load) about its origin, in its frame.
    SimTK::MassProperties calcForearmMassProperties() const;
    /// @}

private:
    void requireNotFinalized(const char* what) const;

    ArmParameters params_;
    SimTK::MultibodySystem system_;
    SimTK::SimbodyMatterSubsystem matter_;
    SimTK::GeneralForceSubsystem forces_;
    SimTK::Force::Gravity gravity_;
    SimTK::MobilizedBody::Weld upperArm_;
    SimTK::MobilizedBody::Pin forearm_;
    SimTK::MobilizedBody::Pin radius_;
    SimTK::Force::MobilityLinearStop elbowStop_;
    SimTK::Vec3 origin_, insertion_, strap_, hand_;
    SimTK::State defaultState_;
    bool finalized_ = false;
};

}  // namespace armsim
