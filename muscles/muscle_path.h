// A muscle's path: from an origin point through via points and over wrapping surfaces (cylinders,
// spheres) fixed to bodies, to an insertion point. Simbody types (it lives beside the force adapter);
// the Virtual Muscle equations never see it, only the path length P it yields.
//
// Why not Simbody's CablePath: Debian's Simbody 3.7 cable subsystem prints debugging text on stdout
// from realizeTopology/realizeInstance and from every obstacle event (1.2 MB for 5000 realizations of
// one cable over one cylinder), its initial-path solve is a stub, and a realization with one cylinder
// cost 27-600 us (measured; docs/elbow_model.md). Wrapping over one cylinder or sphere between two
// fixed points has a closed form, which is what OpenSim's WrapCylinder/WrapSphere compute too:
//   - cylinder: the path's projection on the plane normal to the axis is the 2D shortest path
//     (tangent, arc, tangent) around the circle; the axial coordinate is linear in the projected arc
//     length (a helix on the developed surface), so P = sqrt(Lplanar^2 + dz^2);
//   - sphere: the shortest path lies in the plane through the centre and the two neighbouring points
//     (a great circle), where it is the same 2D construction;
//   - ellipsoid (OpenSim's WrapEllipsoid): the map x -> D^-1 R^T (x - c) takes the ellipsoid to the unit
//     sphere and keeps lines, planes and tangency, so the sphere's construction there, mapped back, is
//     the shortest path within the plane through the centre and the two points (tangent, elliptic arc,
//     tangent; the arc's length by Gauss-Legendre quadrature). That planar path is not the geodesic of
//     a general ellipsoid (nor OpenSim's iterative one), so its loads are not the tangent-point forces:
//     they come from the length's exact gradient (forces at the two points, a force and a moment on the
//     surface's body), and the moment arm stays -dP/dq.
// The path is a local shortest path, so the tension's body forces (at the fixed points and at the
// tangent points of each active surface) do virtual work T dP: the moment arm from these forces
// equals -dP/dq, which tests check against finite differences.
//
// Contact rule of a surface with a `side` s (OpenSim's quadrant): the path passes the surface on the
// +s side; it wraps when the straight segment cuts the surface or crosses the strip behind it (the
// -s side, as wide as the surface); the wrap length grows continuously from zero as the segment comes
// to touch the surface on the +s side (OpenSim's quadrant rule, with the same jump where a segment
// enters the strip from its flank). Without a side the path wraps only when the
// straight segment cuts the surface, the shorter way round.
#pragma once

#include "muscles/simbody.h"

#include <functional>
#include <string>
#include <vector>

namespace armsim {

/// One element of a muscle path, fixed on a body (all vectors in that body's frame, metres).
struct PathElement {
    enum class Kind { Point, Cylinder, Sphere, Ellipsoid };
    Kind kind = Kind::Point;
    SimTK::MobilizedBody body;        ///< body the element is fixed to
    SimTK::Vec3 location{0};          ///< the point, or the surface's centre [m]
    SimTK::UnitVec3 axis{0, 0, 1};    ///< cylinder axis (unit) [1]
    /// Cylinder length [m]; 0: unbounded. With a length, as OpenSim's WrapCylinder, the path does not wrap
    /// when both tangent points lie beyond its ends (more than length / 2 from the centre along the axis).
    double length = 0;
    double radius = 0;                ///< cylinder or sphere radius [m]
    SimTK::Vec3 radii{0};             ///< ellipsoid semi-axes along its own x, y, z [m]
    SimTK::Rotation orientation;      ///< ellipsoid: its axes in the body's frame (R_BE)
    SimTK::Vec3 side{0};              ///< the path passes on this side of the surface; 0 = shorter way
    /// With a side: the path may wind round the surface by more than half a turn (a rotator round the
    /// radius), so a straight segment passing by the centre on the far side still wraps.
    bool winds = false;
    /// OpenSim's rule: while a neighbouring path point lies inside the surface, the path does not wrap
    /// it (false: that is an error naming the muscle, the rule of armsim's own model files).
    bool passWhenInside = false;
    /// OpenSim's rule for WrapSphere and WrapEllipsoid: wrap only while the straight segment cuts the
    /// surface (the side then only chooses the way round), not when it passes behind it.
    bool onlyWhenCut = false;
    /// A via point used only while `joint`'s coordinate is in [activeMin, activeMax] (OpenSim's
    /// conditional path point); its neighbours must be points. Empty joint = always.
    SimTK::MobilizedBody joint;
    double activeMin = 0, activeMax = 0;   ///< [rad]
    bool isConditional() const { return !joint.isEmptyHandle(); }
    /// A point that moves on its body with `mover`'s coordinate q (OpenSim's moving path point):
    /// calcMovingLocation(q, location, dLocation/dq), both in the body's frame [m, m/rad]; `location`
    /// above is then unused. Its tension also does work on q: a generalized force (PathGeometry).
    SimTK::MobilizedBody mover;
    std::function<void(double q, SimTK::Vec3& location, SimTK::Vec3& dLocationDq)> calcMovingLocation;
    bool isMoving() const { return !mover.isEmptyHandle(); }
    /// The point's location in its body's frame at the state's configuration [m] (Stage::Position).
    SimTK::Vec3 findLocation(const SimTK::State& s) const;
    std::string label;                ///< for messages and drawing ("via 1", "cylinder TRI")
    bool isSurface() const { return kind != Kind::Point; }
};

/// A unit-tension load the path applies to one of its bodies: force_G [1] at point_G (Ground) [m].
struct PathLoad {
    int element = 0;                  ///< index into MusclePath::getElements()
    SimTK::MobilizedBodyIndex body;   ///< the body it acts on
    SimTK::Vec3 point{0};             ///< where it acts, Ground [m]
    SimTK::Vec3 arm{0};               ///< point minus the body origin, Ground [m]
    SimTK::Vec3 force{0};             ///< direction and size per newton of tension, Ground [1]
    SimTK::Vec3 moment{0};            ///< a couple on the body per newton of tension, Ground [m] (ellipsoids)
};

/// A unit-tension generalized force on one mobility: what a moving point's own motion on its body
/// does (the tension's force on the point . d point / dq, Ground).
struct PathMobilityLoad {
    SimTK::UIndex u;                  ///< the mover's (one) mobility
    double force = 0;                 ///< per newton of tension [m]
};

/// The path at one configuration.
struct PathGeometry {
    double length = 0;                       ///< P [m]
    std::vector<SimTK::Vec3> polyline;       ///< the path in Ground, arcs sampled (for drawing) [m]
    std::vector<PathLoad> loads;             ///< unit-tension loads on the bodies
    std::vector<PathMobilityLoad> mobilityLoads;  ///< unit-tension generalized forces (moving points)
    std::vector<bool> wrapping;              ///< per element: a surface the path touches now
};

/// The elements of one muscle's path, in order from origin to insertion. Immutable once built.
class MusclePath {
public:
    MusclePath() = default;
    /// A straight path from origin to insertion.
    MusclePath(const SimTK::MobilizedBody& originBody, const SimTK::Vec3& origin,
               const SimTK::MobilizedBody& insertionBody, const SimTK::Vec3& insertion);
    /// A path from a list of elements: first and last must be points, radii positive, axes non-zero.
    /// Surfaces in a row (several wrap objects on one segment) are wrapped in turn until the path
    /// settles; while two or more of them are in use, the loads come from the gradient of the length by
    /// central differences. Throws InputError naming the element otherwise.
    explicit MusclePath(std::vector<PathElement> elements);

    const std::vector<PathElement>& getElements() const { return elements_; }
    bool isStraight() const { return elements_.size() == 2; }

    /// Length and loads at the state's configuration (Stage::Position realized). muscleName names the
    /// muscle in the SimulationError thrown when a fixed point lies inside a wrapping surface.
    PathGeometry calcGeometry(const SimTK::State& s, const std::string& muscleName = "",
                              bool withPolyline = false) const;
    /// P [m] (Stage::Position).
    double calcLength(const SimTK::State& s) const;
    /// dP/dt [m/s] of the path whose geometry at s is g (Stage::Velocity): minus the power of a unit
    /// tension along it (virtual power; wrapping arcs roll with their surfaces).
    double calcLengtheningSpeed(const SimTK::State& s, const PathGeometry& g) const;
    /// Adds the forces of a tension [N] along the path to bodyForces and mobilityForces (Simbody's
    /// calcForce layout; mobilityForces takes the moving points' generalized forces).
    static void applyTension(const PathGeometry& g, double tension, SimTK::Vector_<SimTK::SpatialVec>& bodyForces,
                             SimTK::Vector& mobilityForces);

private:
    std::vector<PathElement> elements_;
};

/// The generalized forces of a unit tension along the path whose geometry at s is g (one per mobility;
/// Stage::Position): minus dP/dq by virtual work, i.e. the moment arms about each mobility [m].
SimTK::Vector calcPathGeneralizedForces(const SimTK::SimbodyMatterSubsystem& matter, const SimTK::State& s,
                                        const PathGeometry& g);

/// Appends the drawing of a path to `geometry` (Ground frame): the polyline of g (calcGeometry with
/// withPolyline) as lines of the given colour and thickness, its via points as small spheres and its
/// wrapping surfaces as translucent cylinders and spheres (more opaque while the path touches them).
void appendPathDecorations(const MusclePath& path, const PathGeometry& g, const SimTK::Vec3& color,
                           double lineThickness, SimTK::Array_<SimTK::DecorativeGeometry>& geometry);

/// Result of wrapping a path from p to q around a circle of radius R at the origin (2D).
struct CircleWrap {
    bool active = false;          ///< the path touches the circle
    SimTK::Vec2 tp{0}, tq{0};     ///< tangent points (entry from p, exit to q) when active
    double angle = 0;             ///< arc angle swept from tp to tq [rad], >= 0
    int direction = 0;            ///< +1 counter-clockwise, -1 clockwise
    double lengthP = 0;           ///< |tp - p|
    double lengthQ = 0;           ///< |q - tq|
};

/// The 2D construction both surfaces use (see the file comment). p and q must lie outside the circle
/// (|p|, |q| > R). side: the path passes on this side; hasSide false: the shorter way, only if the
/// segment p-q cuts the circle. winds (with a side): the path may be wound round the +side by more than
/// half a turn, so a segment clear of the strip behind the circle whose nearest point to the centre is on
/// the far side wraps too, and every wrap goes the shorter way whose arc passes the side.
CircleWrap calcCircleWrap(const SimTK::Vec2& p, const SimTK::Vec2& q, double R, const SimTK::Vec2& side,
                          bool hasSide, bool winds = false);

}  // namespace armsim
