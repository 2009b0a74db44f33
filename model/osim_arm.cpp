#include "model/osim_arm.h"

#include "model/osim_function.h"
#include "muscles/degroote2016_muscle.h"
#include "muscles/thelen2003_muscle.h"
#include "muscles/thelen2003_opensim2_muscle.h"

#include <algorithm>
#include <cmath>
#include <limits>

using namespace SimTK;

namespace armsim {

namespace {

Vec3 toVec3(const Vec3d& v) { return Vec3(v[0], v[1], v[2]); }

// OpenSim's frames: body-fixed X-Y-Z rotation angles, then the translation.
Transform toTransform(const Vec3d& orientation, const Vec3d& translation) {
    return Transform(Rotation(BodyRotationSequence, orientation[0], XAxis, orientation[1], YAxis, orientation[2], ZAxis),
                     toVec3(translation));
}

std::string where(const OsimModel& m, int line, const std::string& element) {
    return m.file + ":" + std::to_string(line) + ": " + element + ": ";
}

bool isConstantZero(const OsimTransformAxis& a) {
    if (!a.hasFunction) return true;
    const OsimFunction& f = a.function;
    if (f.kind == OsimFunction::Kind::Constant) return f.value == 0;
    if (f.kind == OsimFunction::Kind::Linear) return a.coordinates.empty() && f.intercept == 0 && f.slope == 0;
    return false;
}

bool isIdentity(const OsimFunction& f) {
    if (f.kind == OsimFunction::Kind::Linear) return f.slope == 1 && f.intercept == 0;
    if (f.kind == OsimFunction::Kind::PiecewiseLinear || f.kind == OsimFunction::Kind::SimmSpline ||
        f.kind == OsimFunction::Kind::NaturalCubicSpline) {
        // Knots on y = x make the identity (3.3 files often write the pin this way).
        if (f.x.size() < 2 || f.x.size() != f.y.size()) return false;
        for (std::size_t k = 0; k < f.x.size(); ++k)
            if (std::abs(f.y[k] - f.x[k]) > 1e-12 * std::max(1.0, std::abs(f.x[k]))) return false;
        return true;
    }
    return false;
}

// The pin axis of a CustomJoint (in its parent joint frame), or OsimError naming what is not supported.
UnitVec3 findPinAxis(const OsimModel& m, const OsimJoint& j) {
    const OsimTransformAxis* moving = nullptr;
    for (const OsimTransformAxis& a : j.axes) {
        if (isConstantZero(a)) continue;
        const std::string at = where(m, j.line, "<CustomJoint name=\"" + j.name + "\">") + "transform axis " + a.name;
        if (moving)
            throw OsimError(at + " moves as well as " + moving->name +
                            ": a CustomJoint with more than one moving axis is not supported yet (expected one rotation)");
        if (!a.rotation) throw OsimError(at + " translates: translating CustomJoint axes are not supported yet");
        if (a.coordinates.size() != 1 || !isIdentity(a.function))
            throw OsimError(at + ": its function is not the coordinate itself (LinearFunction 1 0): "
                                 "scaled, offset or coupled axes are not supported yet");
        moving = &a;
    }
    if (!moving) throw OsimError(where(m, j.line, "<CustomJoint name=\"" + j.name + "\">") +
                                 "no axis moves: expected one rotation with its coordinate");
    const Vec3 axis = toVec3(moving->axis);
    if (!(axis.norm() > 0)) throw OsimError(where(m, j.line, "<CustomJoint name=\"" + j.name + "\">") + "a zero axis");
    return UnitVec3(axis);
}

double property(const OsimMuscle& mu, const char* name, double fallback) {
    const auto it = mu.properties.find(name);
    return it == mu.properties.end() ? fallback : it->second;
}

const char* wrapElementName(OsimWrapObject::Kind kind) {
    switch (kind) {
        case OsimWrapObject::Kind::Cylinder: return "WrapCylinder";
        case OsimWrapObject::Kind::Sphere: return "WrapSphere";
        case OsimWrapObject::Kind::Ellipsoid: return "WrapEllipsoid";
    }
    return "Wrap";
}

// The file's morphometry into a Hill model's parameters.
template <class Params>
Params makeMorphometry(const OsimMuscle& mu) {
    Params p;
    p.name = mu.name;
    p.maxIsometricForce = mu.maxIsometricForce;
    p.optimalFiberLength = mu.optimalFiberLength;
    p.tendonSlackLength = mu.tendonSlackLength;
    p.pennationAngleAtOptimal = mu.pennationAngleAtOptimal;
    return p;
}

// The muscle built, a bad parameter named with the file's line.
template <class Muscle, class Params>
std::shared_ptr<const MuscleModel> makeMuscle(const OsimModel& model, const OsimMuscle& mu, const Params& p) {
    try {
        return std::make_shared<Muscle>(p);
    } catch (const FieldError& e) {
        // The model's field ("muscle 'M': pennation_angle") as the file's element, at its line.
        static const std::map<std::string, std::string> kElement = {
            {"pennation_angle", "pennation_angle_at_optimal"}, {"vmax", "max_contraction_velocity"},
            {"fmax_tendon_strain", "FmaxTendonStrain"}, {"fmax_muscle_strain", "FmaxMuscleStrain"},
            {"kshape_active", "KshapeActive"}, {"kshape_passive", "KshapePassive"}, {"af", "Af"}, {"flen", "Flen"}};
        const std::string& field = e.getField();
        std::string element = field.substr(field.rfind(": ") == std::string::npos ? 0 : field.rfind(": ") + 2);
        if (const auto it = kElement.find(element); it != kElement.end()) element = it->second;
        const auto line = mu.propertyLines.find(element);
        const std::string what = e.what(), value = what.substr(what.find("' ") == std::string::npos ? 0 : what.find("' ") + 2);
        if (line == mu.propertyLines.end())
            throw OsimError(where(model, mu.line, "<" + mu.type + " name=\"" + mu.name + "\">") + element + " (default) " + value);
        throw OsimError(model.file + ":" + std::to_string(line->second) + ": <" + element + "> (muscle '" + mu.name + "') " + value);
    }
}

}  // namespace

std::shared_ptr<const MuscleModel> buildOsimMuscleModel(const OsimModel& model, const OsimMuscle& mu,
                                                        const std::string& muscleModel) {
    std::string name = muscleModel;
    if (name.empty()) name = mu.type == "Thelen2003Muscle" ? "thelen2003" : mu.type == "DeGrooteFregly2016Muscle" ? "degroote2016" : "";
    if (name == "thelen2003_opensim2") {
        // The file's Thelen properties under OpenSim 2.x's equations (its Vmax is max_contraction_velocity).
        auto p = makeMorphometry<Thelen2003Opensim2Parameters>(mu);
        p.vmax = mu.maxContractionVelocity;
        p.vmax0 = property(mu, "Vmax0", p.vmax0);
        p.fmaxTendonStrain = property(mu, "FmaxTendonStrain", p.fmaxTendonStrain);
        p.fmaxMuscleStrain = property(mu, "FmaxMuscleStrain", p.fmaxMuscleStrain);
        p.kshapeActive = property(mu, "KshapeActive", p.kshapeActive);
        p.kshapePassive = property(mu, "KshapePassive", p.kshapePassive);
        p.damping = property(mu, "damping", p.damping);
        p.af = property(mu, "Af", p.af);
        p.flen = property(mu, "Flen", p.flen);
        p.activationTimeConstant = property(mu, "activation_time_constant", p.activationTimeConstant);
        p.deactivationTimeConstant = property(mu, "deactivation_time_constant", p.deactivationTimeConstant);
        return makeMuscle<Thelen2003Opensim2Muscle>(model, mu, p);
    }
    if (name == "thelen2003") {
        auto p = makeMorphometry<Thelen2003Parameters>(mu);
        p.maxContractionVelocity = mu.maxContractionVelocity;
        p.fmaxTendonStrain = property(mu, "FmaxTendonStrain", p.fmaxTendonStrain);
        p.fmaxMuscleStrain = property(mu, "FmaxMuscleStrain", p.fmaxMuscleStrain);
        p.kshapeActive = property(mu, "KshapeActive", p.kshapeActive);
        p.kshapePassive = property(mu, "KshapePassive", p.kshapePassive);
        p.af = property(mu, "Af", p.af);
        p.flen = property(mu, "Flen", p.flen);
        p.fvLinearExtrapThreshold = property(mu, "fv_linear_extrap_threshold", p.fvLinearExtrapThreshold);
        p.maximumPennationAngle = property(mu, "maximum_pennation_angle", p.maximumPennationAngle);
        p.activationTimeConstant = property(mu, "activation_time_constant", p.activationTimeConstant);
        p.deactivationTimeConstant = property(mu, "deactivation_time_constant", p.deactivationTimeConstant);
        p.minimumActivation = property(mu, "minimum_activation", p.minimumActivation);
        return makeMuscle<Thelen2003Muscle>(model, mu, p);
    }
    if (name == "degroote2016") {
        auto p = makeMorphometry<DeGroote2016Parameters>(mu);
        p.maxContractionVelocity = mu.maxContractionVelocity;
        p.activationTimeConstant = property(mu, "activation_time_constant", p.activationTimeConstant);
        p.deactivationTimeConstant = property(mu, "deactivation_time_constant", p.deactivationTimeConstant);
        p.activationDynamicsSmoothing = property(mu, "activation_dynamics_smoothing", p.activationDynamicsSmoothing);
        p.activeForceWidthScale = property(mu, "active_force_width_scale", p.activeForceWidthScale);
        p.fiberDamping = property(mu, "fiber_damping", p.fiberDamping);
        p.passiveFiberStrainAtOneNormForce =
            property(mu, "passive_fiber_strain_at_one_norm_force", p.passiveFiberStrainAtOneNormForce);
        p.tendonStrainAtOneNormForce = property(mu, "tendon_strain_at_one_norm_force", p.tendonStrainAtOneNormForce);
        return makeMuscle<DeGroote2016Muscle>(model, mu, p);
    }
    if (!muscleModel.empty())
        throw InputError("muscle model '" + muscleModel + "' for .osim muscles: expected thelen2003, thelen2003_opensim2 or degroote2016");
    throw OsimError(where(model, mu.line, "<" + mu.type + " name=\"" + mu.name + "\">") + mu.type +
                    " cannot be simulated yet: expected Thelen2003Muscle or DeGrooteFregly2016Muscle");
}

std::map<std::string, MobilizedBody> OsimArm::buildBodies() {
    const OsimModel& m = model_;
    // Ground, then each joint's child once its parent exists (any file order).
    std::map<std::string, MobilizedBody> bodies = {{"ground", matter_.updGround()}};
    std::vector<bool> built(m.joints.size(), false);
    for (std::size_t pass = 0, done = 0; done < m.joints.size(); ++pass) {
        if (pass > m.joints.size())
            for (std::size_t k = 0; k < m.joints.size(); ++k)
                if (!built[k])
                    throw OsimError(where(m, m.joints[k].line, "<Joint name=\"" + m.joints[k].name + "\">") +
                                    "its parent '" + m.joints[k].parent.body + "' is not reached from ground");
        for (std::size_t k = 0; k < m.joints.size(); ++k) {
            const OsimJoint& j = m.joints[k];
            if (built[k] || !bodies.count(j.parent.body)) continue;
            const OsimBody* b = m.findBody(j.child.body);
            const std::string at = where(m, j.line, "<Joint name=\"" + j.name + "\">");
            if (!b) throw OsimError(at + "its child '" + j.child.body + "' is not a body of the model");
            if (bodies.count(b->name)) throw OsimError(at + "body '" + b->name + "' has a second joint: loops are not supported");
            const Vec3 com = toVec3(b->massCenter);
            const Inertia centralI(b->inertia[0], b->inertia[1], b->inertia[2], b->inertia[3], b->inertia[4], b->inertia[5]);
            const MassProperties mass(b->mass, com, centralI.shiftFromMassCenter(-com, b->mass));
            Transform X_PF = toTransform(j.parent.orientation, j.parent.translation);
            Transform X_BM = toTransform(j.child.orientation, j.child.translation);
            MobilizedBody& parent = bodies.at(j.parent.body);
            if (j.kind == OsimJoint::Kind::Weld) {
                bodies[b->name] = MobilizedBody::Weld(parent, X_PF, mass, X_BM);
            } else {
                if (j.coordinates.empty())
                    throw OsimError(at + "no coordinate: a moving joint needs one (expected one rotation; a joint that "
                                    "does not move is a WeldJoint)");
                if (j.coordinates.size() > 1)
                    throw OsimError(at + std::to_string(j.coordinates.size()) + " coordinates: joints with more than one "
                                    "coordinate are not supported yet (expected one rotation)");
                if (!(b->mass > 0)) throw OsimError(at + "body '" + b->name + "' has no mass but moves: expected a mass > 0 kg");
                if (j.kind == OsimJoint::Kind::Custom) {
                    const Rotation R_FJ(findPinAxis(m, j), ZAxis);  // the pin's z along the axis
                    X_PF = X_PF * Transform(R_FJ);
                    X_BM = X_BM * Transform(R_FJ);
                }
                MobilizedBody::Pin pin(parent, X_PF, mass, X_BM);
                bodies[b->name] = pin;
                coordinates_.push_back({j.coordinates[0], pin});
            }
            built[k] = true;
            ++done;
        }
    }
    const Vec3 g = toVec3(m.gravity);
    if (g.norm() > 0) Force::Gravity(forces_subsystem_, matter_, UnitVec3(g), g.norm());

    return bodies;
}

namespace {

// A wrap object as a path surface on its body.
PathElement makeWrapSurface(const OsimModel& m, const std::map<std::string, MobilizedBody>& bodies,
                            const OsimWrapObject& o) {
    if (!bodies.count(o.body))
        throw OsimError(where(m, o.line, std::string("<") + wrapElementName(o.kind) + " name=\"" + o.name + "\">") + "its body '" + o.body +
                        "' has no joint to ground: not built");
    PathElement e;
    e.body = bodies.at(o.body);
    e.location = toVec3(o.translation);
    e.label = o.name;
    e.passWhenInside = true;  // OpenSim: a path point inside a wrap object turns the wrap off
    const Rotation R_BW(BodyRotationSequence, o.xyzBodyRotation[0], XAxis, o.xyzBodyRotation[1], YAxis,
                        o.xyzBodyRotation[2], ZAxis);
    if (o.quadrant != "all") {
        Vec3 side(0);
        side[o.quadrant.back() - 'x'] = o.quadrant[0] == '-' ? -1 : 1;
        e.side = R_BW * side;
    }
    switch (o.kind) {
        case OsimWrapObject::Kind::Cylinder:
            e.kind = PathElement::Kind::Cylinder;
            e.axis = UnitVec3(R_BW * Vec3(0, 0, 1));
            e.radius = o.radius;
            e.length = o.length;
            break;
        case OsimWrapObject::Kind::Sphere:
            e.kind = PathElement::Kind::Sphere;
            e.radius = o.radius;
            e.onlyWhenCut = true;
            break;
        case OsimWrapObject::Kind::Ellipsoid:
            e.kind = PathElement::Kind::Ellipsoid;
            e.onlyWhenCut = true;
            e.radii = toVec3(o.dimensions);
            e.orientation = R_BW;
            break;
    }
    return e;

}

}  // namespace

MusclePath OsimArm::buildMusclePath(const OsimMuscle& mu, const std::map<std::string, MobilizedBody>& bodies,
                                    const State& pose) const {
    const OsimModel& m = model_;
    auto findWrap = [&](const std::string& name) -> const OsimWrapObject* {
        for (const OsimWrapObject& o : m.wrapObjects)
            if (o.name == name) return &o;
        return nullptr;
    };
    auto coordinateBody = [&](const std::string& name, int line, const std::string& element) {
        for (const Coordinate& c : coordinates_)
            if (c.spec.name == name) return c.body;
        throw OsimError(where(m, line, element) + "coordinate '" + name + "' does not move a built joint");
    };

    const std::string element = "<" + mu.type + " name=\"" + mu.name + "\">";
    std::vector<PathElement> points;
    for (const OsimPathPoint& pp : mu.path) {
        const std::string at = where(m, pp.line, "<PathPoint name=\"" + pp.name + "\">");
        if (!bodies.count(pp.body)) throw OsimError(at + "body '" + pp.body + "' is not built");
        PathElement e;
        e.body = bodies.at(pp.body);
        e.location = toVec3(pp.location);
        e.label = pp.name;
        if (pp.kind == OsimPathPoint::Kind::Moving) setMovingLocation(m, pp, e);
        if (pp.kind == OsimPathPoint::Kind::Conditional) {
            e.joint = coordinateBody(pp.coordinate, pp.line, "<ConditionalPathPoint name=\"" + pp.name + "\">");
            e.activeMin = pp.range[0];
            e.activeMax = pp.range[1];
        }
        points.push_back(e);
    }
    if (points.size() < 2) throw OsimError(where(m, mu.line, element) + "a path needs two points");
    // Each wrap on one segment [k, k+1] of its range: the one whose straight line passes nearest the
    // surface's centre (relative to its size) in the default pose.
    // Surfaces after point k, ordered along the segment by where its line passes nearest them.
    std::vector<std::vector<std::pair<double, PathElement>>> wrapAfter(points.size());
    for (const OsimPathWrap& w : mu.wraps) {
        const OsimWrapObject* o = findWrap(w.wrapObject);
        const std::string at = where(m, w.line, "<PathWrap>") + "muscle '" + mu.name + "': ";
        if (!o) throw OsimError(at + "wrap object '" + w.wrapObject + "' does not exist");
        if (!o->active) continue;
        const int n = int(points.size());
        const int first = w.range[0] < 1 ? 0 : w.range[0] - 1;
        const int last = w.range[1] < 1 ? n - 1 : w.range[1] - 1;
        if (first >= last || last >= n)
            throw OsimError(at + "range " + std::to_string(w.range[0]) + " " + std::to_string(w.range[1]) +
                            ": expected two path points 1.." + std::to_string(n) + " in order");
        const PathElement surface = makeWrapSurface(m, bodies, *o);
        const Vec3 c = surface.body.getBodyTransform(pose) * surface.location;
        const double size = surface.kind == PathElement::Kind::Ellipsoid
                                ? std::max({surface.radii[0], surface.radii[1], surface.radii[2]})
                                : surface.radius;
        int best = -1;
        double bestDistance = std::numeric_limits<double>::infinity(), bestT = 0;
        for (int k = first; k < last; ++k) {
            if (points[k].isConditional() || points[k + 1].isConditional()) continue;
            const Vec3 a = points[k].body.getBodyTransform(pose) * points[k].findLocation(pose);
            const Vec3 b = points[k + 1].body.getBodyTransform(pose) * points[k + 1].findLocation(pose);
            const Vec3 d = b - a;
            const double t = d.normSqr() > 0 ? std::clamp(dot(c - a, d) / d.normSqr(), 0.0, 1.0) : 0.0;
            const double distance = (a + t * d - c).norm() / size;
            if (distance < bestDistance) bestDistance = distance, best = k, bestT = t;
        }
        if (best < 0) throw OsimError(at + "no segment between fixed points in its range");
        wrapAfter[best].emplace_back(bestT, surface);
    }
    std::vector<PathElement> elements;
    for (std::size_t k = 0; k < points.size(); ++k) {
        elements.push_back(points[k]);
        std::stable_sort(wrapAfter[k].begin(), wrapAfter[k].end(),
                         [](const auto& x, const auto& y) { return x.first < y.first; });
        for (const auto& [t, surface] : wrapAfter[k]) elements.push_back(surface);
    }
    MusclePath path = [&] {
        try {
            return MusclePath(elements);
        } catch (const std::exception& e) {
            throw OsimError(where(m, mu.line, element) + e.what());
        }
    }();
    return path;
}

OsimArm::OsimArm(OsimModel model, const std::map<std::string, ActivationProfile>& excitations,
                 const std::string& muscleModel)
    : model_(std::move(model)), matter_(system_), forces_subsystem_(system_) {
    const OsimModel& m = model_;
    for (const auto& excitation : excitations) {
        const std::string& name = excitation.first;
        if (std::none_of(m.muscles.begin(), m.muscles.end(), [&name](const OsimMuscle& x) { return x.name == name; }))
            throw InputError(m.file + ": no muscle '" + name + "' to excite");
    }
    const std::map<std::string, MobilizedBody> bodies = buildBodies();

    // The default pose, to place each wrap on its segment.
    State pose = system_.realizeTopology();
    for (const Coordinate& c : coordinates_) c.body.setOneQ(pose, 0, c.spec.defaultValue);
    system_.realize(pose, Stage::Position);

    for (const OsimMuscle& mu : m.muscles) {
        MusclePath path = buildMusclePath(mu, bodies, pose);
        const auto ex = excitations.find(mu.name);
        forces_.emplace_back(forces_subsystem_, buildOsimMuscleModel(m, mu, muscleModel), std::move(path),
                             ex == excitations.end() ? ActivationProfile() : ex->second);
    }

    defaultState_ = system_.realizeTopology();
    for (const Coordinate& c : coordinates_) {
        c.body.setOneQ(defaultState_, 0, c.spec.defaultValue);
        if (c.spec.locked) c.body.lockAt(defaultState_, c.spec.defaultValue, Motion::Position);
    }
    system_.realizeModel(defaultState_);
    system_.realize(defaultState_, Stage::Position);
}

void OsimArm::setMovingLocation(const OsimModel& m, const OsimPathPoint& pp, PathElement& e) const {
    const std::string at = where(m, pp.line, "<MovingPathPoint name=\"" + pp.name + "\">");
    // One coordinate drives x, y and z, as OpenSim 4 requires (MovingPathPoint::extendConnectToModel); with
    // none the point is its functions at 0.
    static const char* kAxis[] = {"x", "y", "z"};
    const std::string name = pp.locationCoordinates[0];
    std::array<bool, 3> driven{};
    for (int k = 0; k < 3; ++k) {
        const std::string& c = pp.locationCoordinates[k];
        driven[k] = !c.empty();
        if (c != name)
            throw OsimError(at + "its x location follows " + (name.empty() ? "no coordinate" : "'" + name + "'") + " and its " +
                            kAxis[k] + " location " + (c.empty() ? "none" : "'" + c + "'") +
                            ": expected one coordinate for x, y and z (as OpenSim requires)");
    }
    std::array<OsimFunctionEvaluator, 3> f;
    for (int k = 0; k < 3; ++k) f[k] = OsimFunctionEvaluator(pp.locationFunctions[k]);
    if (name.empty()) {   // nothing drives it: a fixed point
        e.location = Vec3(f[0].calcValue(0), f[1].calcValue(0), f[2].calcValue(0));
        return;
    }
    const int i = findCoordinate(name);
    if (i < 0) throw OsimError(at + "coordinate '" + name + "' does not move a built joint");
    if (!coordinates_[i].spec.rotational)
        throw OsimError(at + "coordinate '" + name + "' translates: only rotational coordinates are built");
    e.mover = coordinates_[i].body;
    const std::array<double, 2> range = coordinates_[i].spec.range;
    // OpenSim evaluates each function at the coordinate clamped to its range; beyond the range the point
    // stays put, so its derivative there is 0 (OpenSim's getdPointdQ takes the slope at the unclamped
    // value, which disagrees with its own location outside the range).
    e.calcMovingLocation = [f, driven, range](double q, Vec3& p, Vec3& dpdq) {
        const double qc = std::clamp(q, range[0], range[1]);
        for (int k = 0; k < 3; ++k) {
            p[k] = f[k].calcValue(driven[k] ? qc : 0.0);
            dpdq[k] = driven[k] && q == qc ? f[k].calcDerivative(qc) : 0.0;
        }
    };
}

int OsimArm::findCoordinate(const std::string& name) const {
    for (int i = 0; i < getNumCoordinates(); ++i)
        if (coordinates_[i].spec.name == name) return i;
    return -1;
}

double OsimArm::getCoordinateValue(const State& s, int i) const { return coordinates_.at(i).body.getOneQ(s, 0); }
void OsimArm::setCoordinateValue(State& s, int i, double value) const { coordinates_.at(i).body.setOneQ(s, 0, value); }
double OsimArm::getCoordinateSpeed(const State& s, int i) const { return coordinates_.at(i).body.getOneU(s, 0); }
void OsimArm::setCoordinateSpeed(State& s, int i, double speed) const { coordinates_.at(i).body.setOneU(s, 0, speed); }

double OsimArm::calcPathLength(const State& s, int i) const { return forces_.at(i).getPathLength(s); }

double OsimArm::calcMomentArm(const State& s, int muscle, int coordinate) const {
    const PathGeometry g = forces_.at(muscle).calcPathGeometry(s);
    return calcPathGeneralizedForces(matter_, s, g)[coordinates_.at(coordinate).body.getFirstUIndex(s)];
}

}  // namespace armsim
