// Reading OpenSim model files (.osim, format 4.x `Version="40000"` and 3.3 `Version="30000"`) into plain
// data: bodies and their mass properties, joints (weld, pin, custom with their transform axes and
// functions) with their coordinates and frames, wrap objects, and the muscles of the supported models
// with their paths (path points, conditional and moving path points, path wraps). Framework-free: no
// Simbody here; building a simulation from it is another step.
//
// Strict the way armsim's YAML readers are: a value that cannot be read, a reference to a body or wrap
// object that does not exist, or a component that could change results and is not supported (another
// muscle model, a joint with an unsupported axis function) is an OsimError naming the file, the line,
// the element and what was expected. What cannot change a simulated force or motion (display
// geometry, markers, probes, controllers, analyses) is skipped, and each skipped kind is reported
// once in OsimModel::skipped.
//
// The format is OpenSim's (opensim-core: OpenSim/Simulation/SimbodyEngine/*Joint.h, Model/PathPoint.h,
// ConditionalPathPoint.h, MovingPathPoint.h, Wrap/*.h, Actuators/Thelen2003Muscle.h), read from its
// source and the shipped models (opensim-models); written here from those documents.
#pragma once

#include "basics/errors.h"

#include <array>
#include <map>
#include <string>
#include <vector>

namespace armsim {

/// A problem in an .osim file: "FILE:LINE: <Element name="x">: what, expected ...".
class OsimError : public InputError {
public:
    using InputError::InputError;
};

using Vec3d = std::array<double, 3>;

/// An OpenSim function of one variable (a coordinate's value).
struct OsimFunction {
    enum class Kind { Constant, Linear, SimmSpline, NaturalCubicSpline, PiecewiseLinear };
    Kind kind = Kind::Constant;
    std::vector<double> x, y;   ///< knots (splines, piecewise linear)
    double value = 0;           ///< Constant
    double slope = 1, intercept = 0;  ///< LinearFunction: coefficients (slope, intercept)
    int line = 0;               ///< where it was defined
};

/// A body: mass properties in its own frame.
struct OsimBody {
    std::string name;
    double mass = 0;                   ///< [kg]
    Vec3d massCenter{};                ///< [m]
    std::array<double, 6> inertia{};   ///< Ixx Iyy Izz Ixy Ixz Iyz about the mass centre [kg m^2]
    int line = 0;
};

/// A frame fixed on a body (4.x PhysicalOffsetFrame; 3.3 a joint's location/orientation in parent/child).
struct OsimFrame {
    std::string name;
    std::string body;                  ///< the body (or "ground") it is fixed on
    Vec3d translation{};               ///< [m] in the body's frame
    Vec3d orientation{};               ///< body-fixed X-Y-Z rotation angles [rad]
};

/// A generalized coordinate.
struct OsimCoordinate {
    std::string name;
    bool rotational = true;            ///< false: translational (from the joint's axis kind)
    double defaultValue = 0;           ///< [rad or m]
    std::array<double, 2> range{};     ///< [rad or m]; absent in the file: OpenSim's default [-10, 10]
    bool locked = false;
    bool clamped = false;
    int line = 0;
};

/// One of a CustomJoint's six transform axes (rotation1..3, translation1..3).
struct OsimTransformAxis {
    std::string name;                  ///< "rotation1", ..., "translation3"
    bool rotation = true;
    Vec3d axis{};                      ///< in the parent frame
    std::vector<std::string> coordinates;  ///< the coordinate(s) its function takes (at most one supported)
    OsimFunction function;             ///< of the coordinate: the angle [rad] or displacement [m]
    bool hasFunction = false;          ///< false: the axis does not move
};

/// A joint: a weld, a pin (rotation about the parent frame's Z) or a custom joint.
struct OsimJoint {
    enum class Kind { Weld, Pin, Custom };
    std::string name;
    Kind kind = Kind::Weld;
    OsimFrame parent;                  ///< the joint's frame on the parent body
    OsimFrame child;                   ///< the joint's frame on the child body
    std::vector<OsimCoordinate> coordinates;
    std::vector<OsimTransformAxis> axes;  ///< Custom only
    int line = 0;
};

/// A wrapping surface fixed on a body.
struct OsimWrapObject {
    enum class Kind { Cylinder, Sphere, Ellipsoid };
    std::string name;
    Kind kind = Kind::Cylinder;
    std::string body;
    Vec3d translation{};               ///< [m] in the body's frame
    Vec3d xyzBodyRotation{};           ///< [rad]
    double radius = 0;                 ///< cylinder, sphere [m]
    double length = 0;                 ///< cylinder [m]
    Vec3d dimensions{};                ///< ellipsoid radii [m]
    std::string quadrant = "all";      ///< "all", "x", "-x", "y", "-y", "z", "-z"
    bool active = true;
    int line = 0;
};

/// A point of a muscle path.
struct OsimPathPoint {
    enum class Kind { Fixed, Conditional, Moving };
    std::string name;
    Kind kind = Kind::Fixed;
    std::string body;
    Vec3d location{};                  ///< [m] in the body's frame (Fixed, Conditional)
    std::string coordinate;            ///< Conditional: the coordinate that enables it
    std::array<double, 2> range{};     ///< Conditional: active while the coordinate is in range [rad or m]
    std::array<OsimFunction, 3> locationFunctions;  ///< Moving: x, y, z of the coordinates below
    std::array<std::string, 3> locationCoordinates; ///< Moving
    int line = 0;
};

/// A wrap of a muscle path over a wrap object.
struct OsimPathWrap {
    std::string wrapObject;
    std::string method = "hybrid";     ///< OpenSim's algorithm name (hybrid, midpoint, axial)
    std::array<int, 2> range{-1, -1};  ///< path points (1-based) it applies between; -1 -1: all
    int line = 0;
};

/// A muscle of a supported model.
struct OsimMuscle {
    std::string name;
    std::string type;                  ///< "Thelen2003Muscle", "Millard2012EquilibriumMuscle", "DeGrooteFregly2016Muscle"
    double maxIsometricForce = 0;      ///< [N]
    double optimalFiberLength = 0;     ///< [m]
    double tendonSlackLength = 0;      ///< [m]
    double pennationAngleAtOptimal = 0;  ///< [rad]
    double maxContractionVelocity = 10;  ///< [optimal fibre lengths/s]
    /// The model's other numeric properties as the file gives them (OpenSim's names, e.g.
    /// "FmaxTendonStrain", "activation_time_constant"); absent ones take the model's defaults.
    std::map<std::string, double> properties;
    /// The line of each numeric property element the file gives (OpenSim's names, max_isometric_force etc.
    /// included), for messages about its value.
    std::map<std::string, int> propertyLines;
    std::vector<OsimPathPoint> path;
    std::vector<OsimPathWrap> wraps;
    bool appliesForce = true;
    int line = 0;
};

/// An .osim model as data.
struct OsimModel {
    std::string file;
    std::string name;
    int version = 0;                   ///< the document's Version attribute (30000, 40000, ...)
    std::string credits, publications;
    Vec3d gravity{0, -9.80665, 0};     ///< [m/s^2]
    std::vector<OsimBody> bodies;      ///< "ground" is not listed
    std::vector<OsimJoint> joints;
    std::vector<OsimWrapObject> wrapObjects;
    std::vector<OsimMuscle> muscles;
    /// What was skipped because it cannot change results: "Marker (3)", "ContactGeometry" ...
    std::vector<std::string> skipped;

    const OsimBody* findBody(const std::string& name) const;
    const OsimCoordinate* findCoordinate(const std::string& name) const;
};

/// Reads an .osim file. Throws OsimError (file, line, element) for anything it cannot read or support.
OsimModel readOsimFile(const std::string& path);
/// The same from text (sourceName names it in messages).
OsimModel readOsimText(const std::string& text, const std::string& sourceName);

}  // namespace armsim
