// An OpenSim model (model/osim_file.h, read as data) built as a Simbody system: its bodies with their
// mass properties, its joints as mobilizers, its gravity, and one MuscleForce per muscle on a
// MusclePath converted from the file's path points and wrap objects, driven by an excitation each.
//
// What is built, and how it maps OpenSim's definitions (opensim-core: SimbodyEngine/PinJoint.h,
// CustomJoint.h, SpatialTransform.h; Model/GeometryPath.cpp; Wrap/*.h):
//   - WeldJoint: a weld between the joint's parent and child frames.
//   - PinJoint: rotation about the joint frames' common Z by the coordinate (as OpenSim).
//   - CustomJoint whose spatial transform moves by one rotation axis about `axis` (in the parent joint
//     frame) with the coordinate as the angle (LinearFunction slope 1, intercept 0), the other five axes
//     constant zero: a pin about that axis. Other transforms (coupled or translating axes, a scaled or
//     offset function) are refused naming the joint and axis: not supported yet.
//   - Coordinates start at their default value; a locked coordinate is locked there. Ranges are not
//     forces in OpenSim's forward dynamics either (no CoordinateLimitForce is read).
//   - Path points on their bodies; a ConditionalPathPoint is a via point active while its coordinate is
//     within its range. A MovingPathPoint sits at its x, y and z functions (model/osim_function.h) of one
//     coordinate clamped to that coordinate's range; its tension also drives the coordinate with the
//     generalized force f . dp/dq, as OpenSim's GeometryPath adds it, except beyond the range, where dp/dq
//     is 0 as the clamped location says (OpenSim's getdPointdQ takes the slope at the unclamped value).
//   - Wrap objects: WrapCylinder (its z axis; no wrap when both tangent points lie beyond its length,
//     as OpenSim), WrapSphere and WrapEllipsoid, with the quadrant as the side the path passes (all: the
//     shorter way); as in OpenSim a wrap is off while a neighbouring path point lies inside its object,
//     and a sphere or ellipsoid wraps only while the straight segment cuts it. OpenSim picks, at every
//     configuration, the segment of the wrap's point range that the object intersects (else the one whose
//     wrap lengthens the path least); here each wrap is placed once, on the segment of its range whose
//     straight line passes nearest the object's centre in the default pose, and stays there. Several
//     wraps on one segment are wrapped in turn, in the order their centres lie along it, until the path
//     settles (muscles/muscle_path.h, with its limitation where the passes do not settle).
//   - Muscles: Thelen2003Muscle (thelen2003) and DeGrooteFregly2016Muscle (degroote2016) with the
//     file's properties, or every muscle under another model (buildOsimMuscleModel);
//     Millard2012EquilibriumMuscle is refused.
#pragma once

#include "model/osim_file.h"
#include "muscles/activation.h"
#include "muscles/muscle_force.h"
#include "muscles/simbody.h"

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace armsim {

/// The muscle model of an .osim muscle with the file's properties (F0, l0, slack length, pennation,
/// curves' coefficients, time constants): the file's type (Thelen2003Muscle: thelen2003,
/// DeGrooteFregly2016Muscle: degroote2016), or muscleModel when given (thelen2003, degroote2016, or
/// thelen2003_opensim2: the same properties under OpenSim 2.x's equations, for results OpenSim 2 made).
/// OsimError naming the muscle for a model armsim does not have.
std::shared_ptr<const MuscleModel> buildOsimMuscleModel(const OsimModel& model, const OsimMuscle& muscle,
                                                        const std::string& muscleModel = "");

/// One .osim model as a simulation: its own Simbody System (build one per thread).
class OsimArm {
public:
    /// Builds bodies, joints, gravity and muscles; excitations by muscle name (missing muscles get 0).
    /// Throws OsimError (file, line, element) for anything it cannot build.
    explicit OsimArm(OsimModel model, const std::map<std::string, ActivationProfile>& excitations = {},
                     const std::string& muscleModel = "");
    OsimArm(const OsimArm&) = delete;
    OsimArm& operator=(const OsimArm&) = delete;

    const OsimModel& getModel() const { return model_; }
    const SimTK::MultibodySystem& getSystem() const { return system_; }
    const SimTK::SimbodyMatterSubsystem& getMatter() const { return matter_; }
    /// Coordinates at their defaults, speeds 0, muscle states 0 (set them before integrating).
    const SimTK::State& getDefaultState() const { return defaultState_; }

    /// @name Coordinates (radians; one per moving joint, in the order the joints are built from ground)
    /// @{
    int getNumCoordinates() const { return int(coordinates_.size()); }
    const OsimCoordinate& getCoordinate(int i) const { return coordinates_.at(i).spec; }
    /// Its index, or -1.
    int findCoordinate(const std::string& name) const;
    double getCoordinateValue(const SimTK::State& s, int i) const;
    void setCoordinateValue(SimTK::State& s, int i, double value) const;
    double getCoordinateSpeed(const SimTK::State& s, int i) const;
    void setCoordinateSpeed(SimTK::State& s, int i, double speed) const;
    /// The mobilizer that moves with coordinate i.
    const SimTK::MobilizedBody& getCoordinateBody(int i) const { return coordinates_.at(i).body; }
    /// @}

    /// @name Muscles (file order)
    /// @{
    int getNumMuscles() const { return int(forces_.size()); }
    const std::string& getMuscleName(int i) const { return model_.muscles.at(i).name; }
    const MuscleForce& getMuscleForce(int i) const { return forces_.at(i); }
    /// Path length of muscle i [m] (Stage::Position).
    double calcPathLength(const SimTK::State& s, int i) const;
    /// Moment arm of muscle i about coordinate j [m]: the generalized force of a unit tension on j's
    /// mobility (virtual work; equals -dP/dq). Stage::Position.
    double calcMomentArm(const SimTK::State& s, int muscle, int coordinate) const;
    /// @}

private:
    // A MovingPathPoint's location function and the mobilizer of its coordinate (OsimError otherwise).
    void setMovingLocation(const OsimModel& m, const OsimPathPoint& pp, PathElement& e) const;
    // Every body on its joint (coordinates_ filled) and gravity.
    std::map<std::string, SimTK::MobilizedBody> buildBodies();
    // A muscle's path: its points and each active wrap on the segment of its range that passes nearest
    // the surface in `pose` (the default pose).
    MusclePath buildMusclePath(const OsimMuscle& mu, const std::map<std::string, SimTK::MobilizedBody>& bodies,
                               const SimTK::State& pose) const;

    struct Coordinate {
        OsimCoordinate spec;
        SimTK::MobilizedBody body;
    };
    OsimModel model_;
    SimTK::MultibodySystem system_;
    SimTK::SimbodyMatterSubsystem matter_;
    SimTK::GeneralForceSubsystem forces_subsystem_;
    std::vector<Coordinate> coordinates_;
    std::vector<MuscleForce> forces_;
    SimTK::State defaultState_;
};

}  // namespace armsim
