#include "model/osim_file.h"

#include "basics/numbers.h"
#include "basics/bound.h"
#include "basics/files.h"
#include "basics/angles.h"
#include "basics/format.h"

#include <tinyxml2.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>

namespace armsim {

namespace {

// Lengths past which a model is in other units (its lengths in mm read as hundreds of metres): a path
// point or wrap centre within 1 m of its body's origin, a joint's frame within 2 m (a whole body's
// bones are under 0.5 m long), a wrap surface's radius at most 0.5 m (the arm's are about 0.02 m).
constexpr double kMaxPointDistance = 1.0;
constexpr double kMaxOffsetDistance = 2.0;
constexpr double kMaxWrapRadius = 0.5;

/// " (element <NAME>)" when tinyxml2's error text names an element, else "".
std::string findXmlErrorElement(const std::string& errorText) {
    const std::size_t at = errorText.find("name=");
    if (at == std::string::npos) return "";
    const std::size_t end = errorText.find_first_of(" \t\n", at + 5);
    return " (element <" + errorText.substr(at + 5, end == std::string::npos ? std::string::npos : end - at - 5) + ">)";
}

/// tinyxml2's error in words (its ErrorStr is "Error=XML_ERROR_... ErrorID=14 (0xe) Line number=4: ...").
std::string describeXmlError(tinyxml2::XMLError e) {
    switch (e) {
    case tinyxml2::XML_ERROR_MISMATCHED_ELEMENT: return "an element closed by another element's end tag (or never closed)";
    case tinyxml2::XML_ERROR_PARSING_ELEMENT: return "a malformed element (a tag that does not end, or a stray '<')";
    case tinyxml2::XML_ERROR_PARSING_ATTRIBUTE: return "a malformed attribute (expected name=\"value\")";
    case tinyxml2::XML_ERROR_PARSING_TEXT: return "malformed text between tags";
    case tinyxml2::XML_ERROR_PARSING_CDATA: return "a malformed CDATA section";
    case tinyxml2::XML_ERROR_PARSING_COMMENT: return "a comment that does not end ('-->')";
    case tinyxml2::XML_ERROR_PARSING_DECLARATION: return "a malformed declaration ('<?xml ...?>')";
    case tinyxml2::XML_ERROR_EMPTY_DOCUMENT: return "the file holds no element";
    case tinyxml2::XML_ELEMENT_DEPTH_EXCEEDED: return "elements nested too deep";
    default: return std::string("unreadable XML (") + tinyxml2::XMLDocument::ErrorIDToName(e) + ")";
    }
}


using tinyxml2::XMLElement;

// Muscle models the reader accepts, with the numeric properties each may carry (OpenSim's names).
const std::map<std::string, std::vector<std::string>>& getMuscleProperties() {
    static const std::map<std::string, std::vector<std::string>> m = {
        {"Thelen2003Muscle",
         {"FmaxTendonStrain", "FmaxMuscleStrain", "KshapeActive", "KshapePassive", "Af", "Flen",
          "fv_linear_extrap_threshold", "maximum_pennation_angle", "activation_time_constant",
          "deactivation_time_constant", "minimum_activation"}},
        {"DeGrooteFregly2016Muscle",
         {"activation_time_constant", "deactivation_time_constant", "default_activation",
          "default_normalized_tendon_force", "active_force_width_scale", "fiber_damping",
          "passive_fiber_strain_at_one_norm_force", "tendon_strain_at_one_norm_force",
          "activation_dynamics_smoothing"}},
        {"Millard2012EquilibriumMuscle",
         {"fiber_damping", "default_activation", "default_fiber_length", "activation_time_constant",
          "deactivation_time_constant", "minimum_activation", "maximum_pennation_angle"}},
    };
    return m;
}

class Reader {
public:
    explicit Reader(std::string source) : source_(std::move(source)) {}

    [[noreturn]] void fail(const XMLElement* e, const std::string& what) const {
        std::string where = source_;
        if (e) {
            where += ":" + std::to_string(e->GetLineNum()) + ": <" + std::string(e->Name());
            if (const char* n = e->Attribute("name")) where += " name=\"" + std::string(n) + "\"";
            where += ">";
        }
        throw OsimError(where + ": " + what);
    }

    const XMLElement* child(const XMLElement* e, const char* tag, bool required = true) const {
        const XMLElement* c = e->FirstChildElement(tag);
        if (!c && required) fail(e, std::string("missing <") + tag + ">");
        return c;
    }

    std::string text(const XMLElement* e, const char* tag, const std::string& fallback = "") const {
        const XMLElement* c = e->FirstChildElement(tag);
        if (!c || !c->GetText()) return fallback;
        std::string s = c->GetText();
        s.erase(0, s.find_first_not_of(" \t\r\n"));
        s.erase(s.find_last_not_of(" \t\r\n") + 1);
        return s;
    }

    std::vector<double> numbers(const XMLElement* c) const {
        std::vector<double> v;
        if (!c->GetText()) return v;
        std::istringstream in(c->GetText());
        std::string token;
        while (in >> token) {
            double x = 0;
            if (!parseNumber(token, x)) fail(c, "'" + token + "' is not a number");
            v.push_back(x);
        }
        return v;
    }

    std::vector<double> numbers(const XMLElement* e, const char* tag, std::size_t count, bool required = true,
                                std::vector<double> fallback = {}) const {
        const XMLElement* c = e->FirstChildElement(tag);
        if (!c) {
            if (required) fail(e, std::string("missing <") + tag + ">");
            return fallback;
        }
        std::vector<double> v = numbers(c);
        if (count && v.size() != count)
            fail(c, std::to_string(v.size()) + " numbers: expected " + std::to_string(count));
        return v;
    }

    double number(const XMLElement* e, const char* tag, bool required = true, double fallback = 0) const {
        return numbers(e, tag, 1, required, {fallback})[0];
    }

    Vec3d vec3(const XMLElement* e, const char* tag, bool required = true) const {
        const std::vector<double> v = numbers(e, tag, 3, required, {0, 0, 0});
        return {v[0], v[1], v[2]};
    }

    // A point or offset of a body's frame [m]: farther than `within` from its origin is a model in other
    // units (a path point in mm reads as hundreds of metres and gave a 896,380 N m peak).
    Vec3d position(const XMLElement* e, const char* tag, double within, bool required = true) const {
        const Vec3d v = vec3(e, tag, required);
        const double d = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        if (d > within)
            fail(child(e, tag), "(" + formatNumber(v[0]) + ", " + formatNumber(v[1]) + ", " + formatNumber(v[2]) + ") is " +
                                    formatNumber(d, 4) + " m from the body's origin: expected within " + formatNumber(within) +
                                    " m (OpenSim lengths are in metres: is it in mm?)");
        return v;
    }

    // A wrap object's radius or semi-axis [m].
    double radius(const XMLElement* e, const char* tag, double value) const {
        if (!(value > 0)) fail(child(e, tag), std::string(tag) + " " + formatNumber(value) + ": expected > 0 m");
        if (value > kMaxWrapRadius)
            fail(child(e, tag), std::string(tag) + " " + formatNumber(value) + ": expected at most " + formatNumber(kMaxWrapRadius) +
                                    " m (OpenSim lengths are in metres: is it in mm?)");
        return value;
    }

    bool flag(const XMLElement* e, const char* tag, bool fallback) const {
        const std::string t = text(e, tag, fallback ? "true" : "false");
        if (t == "true" || t == "1") return true;
        if (t == "false" || t == "0") return false;
        fail(child(e, tag), "'" + t + "': expected true or false");
    }

    static bool parseNumber(const std::string& s, double& x) {
        try {
            std::size_t used = 0;
            x = std::stod(s, &used);
            return used == s.size() && std::isfinite(x) && !isHexadecimalText(s.c_str());
        } catch (...) {
            return false;
        }
    }

    // A function element (Constant, LinearFunction, SimmSpline, NaturalCubicSpline,
    // PiecewiseLinearFunction) under e, or under e's <function> wrapper (3.3).
    OsimFunction function(const XMLElement* e) const {
        const XMLElement* holder = e->FirstChildElement("function");
        const XMLElement* scope = holder ? holder : e;
        for (const XMLElement* c = scope->FirstChildElement(); c; c = c->NextSiblingElement()) {
            const std::string kind = c->Name();
            OsimFunction f;
            f.line = c->GetLineNum();
            if (kind == "Constant") {
                f.kind = OsimFunction::Kind::Constant;
                f.value = number(c, "value");
                return f;
            }
            if (kind == "LinearFunction") {
                f.kind = OsimFunction::Kind::Linear;
                const std::vector<double> k = numbers(c, "coefficients", 2);
                f.slope = k[0];
                f.intercept = k[1];
                return f;
            }
            if (kind == "SimmSpline" || kind == "NaturalCubicSpline" || kind == "PiecewiseLinearFunction") {
                f.kind = kind == "SimmSpline"           ? OsimFunction::Kind::SimmSpline
                         : kind == "NaturalCubicSpline" ? OsimFunction::Kind::NaturalCubicSpline
                                                        : OsimFunction::Kind::PiecewiseLinear;
                f.x = numbers(c, "x", 0);
                f.y = numbers(c, "y", 0);
                if (f.x.size() != f.y.size() || f.x.size() < 2)
                    fail(c, std::to_string(f.x.size()) + " x and " + std::to_string(f.y.size()) +
                                " y values: expected as many of each, at least 2");
                for (std::size_t i = 1; i < f.x.size(); ++i)
                    if (!(f.x[i] > f.x[i - 1])) fail(c, "x values not increasing at " + std::to_string(i + 1));
                return f;
            }
            if (kind == "coordinates" || kind == "axis" || kind == "FrameGeometry") continue;
            fail(c, "function type " + kind +
                        " is not supported: expected Constant, LinearFunction, SimmSpline, NaturalCubicSpline or "
                        "PiecewiseLinearFunction");
        }
        fail(e, "no function");
    }

    // "/bodyset/r_humerus", "r_humerus", "/ground", "ground" -> the body name ("ground" for ground).
    std::string bodyOf(const std::string& path) const {
        std::string p = path;
        if (p.rfind("/bodyset/", 0) == 0) p = p.substr(9);
        else if (p.rfind("../", 0) == 0) p = p.substr(3);
        if (p == "/ground") p = "ground";
        return p;
    }

    OsimModel read(const std::string& xml) {
        tinyxml2::XMLDocument doc;
        if (const tinyxml2::XMLError e = doc.Parse(xml.c_str(), xml.size()); e != tinyxml2::XML_SUCCESS)
            throw OsimError(source_ + ":" + std::to_string(doc.ErrorLineNum()) + ": not valid XML: " + describeXmlError(e) +
                            findXmlErrorElement(doc.ErrorStr() ? doc.ErrorStr() : ""));
        const XMLElement* root = doc.RootElement();
        if (!root || std::string(root->Name()) != "OpenSimDocument")
            throw OsimError(source_ + ": expected an <OpenSimDocument> (an OpenSim model file)");
        OsimModel m;
        m.file = source_;
        m.version = root->IntAttribute("Version", 0);
        if (m.version < 30000)
            fail(root, "Version=\"" + std::to_string(m.version) + "\": expected an OpenSim 3.3 (30000) or 4.x (40000) file");
        const XMLElement* model = child(root, "Model");
        m.name = model->Attribute("name") ? model->Attribute("name") : "";
        m.credits = text(model, "credits");
        m.publications = text(model, "publications");
        if (model->FirstChildElement("gravity")) {
            m.gravity = vec3(model, "gravity");
            const double g = std::sqrt(m.gravity[0] * m.gravity[0] + m.gravity[1] * m.gravity[1] + m.gravity[2] * m.gravity[2]);
            if (!(g <= 100))   // the arm files' bound (bounds: gravity in [0, 100] m/s^2)
                fail(child(model, "gravity"), "magnitude " + formatNumber(g) + " m/s^2: expected at most 100 m/s^2");
        }
        readBodies(model, m);
        readJoints(model, m);
        readForces(model, m);
        readSkipped(model, m);
        check(m);
        return m;
    }

private:
    void note(OsimModel& m, const std::string& what) {
        if (std::find(m.skipped.begin(), m.skipped.end(), what) == m.skipped.end()) m.skipped.push_back(what);
    }

    void readBodies(const XMLElement* model, OsimModel& m) {
        const XMLElement* set = child(model, "BodySet");
        const XMLElement* objects = child(set, "objects");
        for (const XMLElement* b = objects->FirstChildElement(); b; b = b->NextSiblingElement()) {
            if (std::string(b->Name()) != "Body") fail(b, "expected <Body>");
            OsimBody body;
            body.name = b->Attribute("name") ? b->Attribute("name") : "";
            body.line = b->GetLineNum();
            if (body.name.empty()) fail(b, "a body without a name");
            body.mass = number(b, "mass");
            if (!(body.mass >= 0 && body.mass <= 1e5))   // a segment of any animal modelled (100 t), not a typo's 1e9
                fail(child(b, "mass"), "mass " + formatNumber(body.mass) + ": expected 0 to 1e5 kg");
            body.massCenter = vec3(b, "mass_center");
            if (b->FirstChildElement("inertia")) {
                const std::vector<double> I = numbers(b, "inertia", 6);
                std::copy(I.begin(), I.end(), body.inertia.begin());
            } else {  // 3.3: inertia_xx ... inertia_yz
                const char* tags[] = {"inertia_xx", "inertia_yy", "inertia_zz", "inertia_xy", "inertia_xz", "inertia_yz"};
                for (int k = 0; k < 6; ++k) body.inertia[k] = number(b, tags[k]);
            }
            if (body.name == "ground") {
                // 3.3 lists ground as a body; 4.x has <Ground>. Its mass does not matter.
            } else {
                m.bodies.push_back(body);
            }
            if (const XMLElement* ws = b->FirstChildElement("WrapObjectSet")) readWrapObjects(ws, body.name, m);
            if (const XMLElement* j = b->FirstChildElement("Joint")) readJoint33(j, body.name, m);
        }
        if (const XMLElement* g = model->FirstChildElement("Ground"))
            if (const XMLElement* ws = g->FirstChildElement("WrapObjectSet")) readWrapObjects(ws, "ground", m);
    }

    void readWrapObjects(const XMLElement* set, const std::string& body, OsimModel& m) {
        const XMLElement* objects = set->FirstChildElement("objects");
        if (!objects) return;
        for (const XMLElement* w = objects->FirstChildElement(); w; w = w->NextSiblingElement()) {
            const std::string kind = w->Name();
            OsimWrapObject o;
            o.name = w->Attribute("name") ? w->Attribute("name") : "";
            o.body = body;
            o.line = w->GetLineNum();
            o.active = flag(w, "active", true);
            o.translation = position(w, "translation", kMaxPointDistance, false);
            o.xyzBodyRotation = vec3(w, "xyz_body_rotation", false);
            o.quadrant = text(w, "quadrant", "all");
            static const std::set<std::string> quadrants = {"all", "x", "-x", "+x", "y", "-y", "+y", "z", "-z", "+z"};
            if (!quadrants.count(o.quadrant)) fail(child(w, "quadrant"), "'" + o.quadrant + "': expected all, x, -x, y, -y, z or -z");
            if (kind == "WrapCylinder") {
                o.kind = OsimWrapObject::Kind::Cylinder;
                o.radius = number(w, "radius");
                o.length = number(w, "length", false, 1.0);
            } else if (kind == "WrapSphere") {
                o.kind = OsimWrapObject::Kind::Sphere;
                o.radius = number(w, "radius");
            } else if (kind == "WrapEllipsoid") {
                o.kind = OsimWrapObject::Kind::Ellipsoid;
                o.dimensions = vec3(w, "dimensions");
                for (double a : o.dimensions) radius(w, "dimensions", a);
            } else {
                fail(w, "wrap object type " + kind + " is not supported: expected WrapCylinder, WrapSphere or WrapEllipsoid");
            }
            if (o.kind == OsimWrapObject::Kind::Cylinder || o.kind == OsimWrapObject::Kind::Sphere) radius(w, "radius", o.radius);
            m.wrapObjects.push_back(o);
        }
    }

    void readCoordinates(const XMLElement* set, OsimJoint& j) {
        if (!set) return;
        for (const XMLElement* c = set->FirstChildElement("Coordinate"); c; c = c->NextSiblingElement("Coordinate")) {
            OsimCoordinate k;
            k.name = c->Attribute("name") ? c->Attribute("name") : "";
            k.line = c->GetLineNum();
            k.defaultValue = number(c, "default_value", false, 0);
            const std::vector<double> r = numbers(c, "range", 2, false, {-10, 10});
            k.range = {r[0], r[1]};
            if (!(k.range[0] <= k.range[1]))
                fail(child(c, "range"), "range [" + formatNumber(k.range[0]) + ", " + formatNumber(k.range[1]) +
                                            "] not increasing: expected the lower end first");
            k.locked = flag(c, "locked", false);
            k.clamped = flag(c, "clamped", false);
            if (const std::string mt = text(c, "motion_type"); mt == "translational") k.rotational = false;
            // A rotational range is in radians: an end past one turn (but not a huge "unbounded" sentinel)
            // is a range in degrees, which would bound the coordinate nowhere.
            for (double end : k.range)   // (without <range>, OpenSim's default -10 .. 10 holds)
                if (k.rotational && c->FirstChildElement("range") && std::abs(end) > 2 * kPi + 0.01 && std::abs(end) < 1e3)
                    fail(child(c, "range"), "range [" + formatNumber(k.range[0]) + ", " + formatNumber(k.range[1]) +
                                                "] of a rotational coordinate: past one turn (2 pi): expected radians (" +
                                                formatNumber(end) + " rad is " + formatNumber(std::round(radToDeg(end))) + " deg)");
            j.coordinates.push_back(k);
        }
    }

    void readSpatialTransform(const XMLElement* joint, OsimJoint& j) {
        const XMLElement* st = child(joint, "SpatialTransform");
        for (const XMLElement* a = st->FirstChildElement("TransformAxis"); a; a = a->NextSiblingElement("TransformAxis")) {
            OsimTransformAxis t;
            t.name = a->Attribute("name") ? a->Attribute("name") : "";
            t.rotation = t.name.rfind("rotation", 0) == 0;
            if (!t.rotation && t.name.rfind("translation", 0) != 0)
                fail(a, "expected a TransformAxis named rotation1-3 or translation1-3");
            t.axis = vec3(a, "axis");
            std::istringstream in(text(a, "coordinates"));
            for (std::string c; in >> c;) t.coordinates.push_back(c);
            if (t.coordinates.size() > 1)
                fail(a, "a function of " + std::to_string(t.coordinates.size()) + " coordinates: expected at most one");
            bool hasFunction = false;  // any element besides coordinates and axis is the function
            for (const XMLElement* c = a->FirstChildElement(); c; c = c->NextSiblingElement())
                hasFunction = hasFunction || (std::string(c->Name()) != "coordinates" && std::string(c->Name()) != "axis");
            if (hasFunction) {
                t.function = function(a);
                t.hasFunction = true;
            }
            if (!t.coordinates.empty() && !t.hasFunction) fail(a, "a coordinate but no function");
            for (OsimCoordinate& k : j.coordinates)
                if (!t.coordinates.empty() && k.name == t.coordinates[0] && !t.rotation) k.rotational = false;
            j.axes.push_back(t);
        }
    }

    OsimJoint::Kind jointKind(const XMLElement* e) const {
        const std::string k = e->Name();
        if (k == "WeldJoint") return OsimJoint::Kind::Weld;
        if (k == "PinJoint") return OsimJoint::Kind::Pin;
        if (k == "CustomJoint") return OsimJoint::Kind::Custom;
        fail(e, "joint type " + k + " is not supported: expected WeldJoint, PinJoint or CustomJoint");
    }

    // 4.x: <JointSet><objects><CustomJoint> with sockets and <frames>.
    void readJoints(const XMLElement* model, OsimModel& m) {
        const XMLElement* set = model->FirstChildElement("JointSet");
        if (!set) return;
        const XMLElement* objects = set->FirstChildElement("objects");
        for (const XMLElement* e = objects ? objects->FirstChildElement() : nullptr; e; e = e->NextSiblingElement()) {
            OsimJoint j;
            j.kind = jointKind(e);
            j.name = e->Attribute("name") ? e->Attribute("name") : "";
            j.line = e->GetLineNum();
            std::map<std::string, OsimFrame> frames;
            if (const XMLElement* fs = e->FirstChildElement("frames"))
                for (const XMLElement* f = fs->FirstChildElement("PhysicalOffsetFrame"); f;
                     f = f->NextSiblingElement("PhysicalOffsetFrame")) {
                    OsimFrame fr;
                    fr.name = f->Attribute("name") ? f->Attribute("name") : "";
                    fr.body = bodyOf(text(f, "socket_parent"));
                    fr.translation = position(f, "translation", kMaxOffsetDistance, false);
                    fr.orientation = vec3(f, "orientation", false);
                    frames[fr.name] = fr;
                }
            auto frameOf = [&](const char* socket) {
                const std::string ref = text(e, socket);
                if (ref.empty()) fail(e, std::string("missing <") + socket + ">");
                if (frames.count(ref)) return frames.at(ref);
                OsimFrame fr;
                fr.name = ref;
                fr.body = bodyOf(ref);
                return fr;
            };
            j.parent = frameOf("socket_parent_frame");
            j.child = frameOf("socket_child_frame");
            readCoordinates(e->FirstChildElement("coordinates"), j);
            if (j.kind == OsimJoint::Kind::Custom) readSpatialTransform(e, j);
            if (j.kind == OsimJoint::Kind::Pin && j.coordinates.size() != 1) fail(e, "a PinJoint needs one coordinate");
            m.joints.push_back(j);
        }
    }

    // 3.3: <Body><Joint><CustomJoint> with parent_body, location_in_parent, orientation_in_parent,
    // location, orientation and a CoordinateSet.
    void readJoint33(const XMLElement* holder, const std::string& childBody, OsimModel& m) {
        const XMLElement* e = holder->FirstChildElement();
        if (!e) return;  // ground's empty <Joint/>
        OsimJoint j;
        j.kind = jointKind(e);
        j.name = e->Attribute("name") ? e->Attribute("name") : "";
        j.line = e->GetLineNum();
        j.parent.body = text(e, "parent_body");
        if (j.parent.body.empty()) fail(e, "missing <parent_body>");
        j.parent.translation = position(e, "location_in_parent", kMaxOffsetDistance, false);
        j.parent.orientation = vec3(e, "orientation_in_parent", false);
        j.child.body = childBody;
        j.child.translation = position(e, "location", kMaxOffsetDistance, false);
        j.child.orientation = vec3(e, "orientation", false);
        if (const XMLElement* cs = e->FirstChildElement("CoordinateSet")) readCoordinates(cs->FirstChildElement("objects"), j);
        if (j.kind == OsimJoint::Kind::Custom) readSpatialTransform(e, j);
        m.joints.push_back(j);
    }

    void readPath(const XMLElement* muscle, OsimMuscle& mu) {
        const XMLElement* gp = child(muscle, "GeometryPath");
        const XMLElement* pps = child(gp, "PathPointSet");
        const XMLElement* objects = child(pps, "objects");
        for (const XMLElement* p = objects->FirstChildElement(); p; p = p->NextSiblingElement()) {
            const std::string kind = p->Name();
            OsimPathPoint pt;
            pt.name = p->Attribute("name") ? p->Attribute("name") : "";
            pt.line = p->GetLineNum();
            pt.body = bodyOf(text(p, "socket_parent_frame", text(p, "body")));
            if (pt.body.empty()) fail(p, "missing <socket_parent_frame> (4.x) or <body> (3.3)");
            if (kind == "PathPoint") {
                pt.location = position(p, "location", kMaxPointDistance);
            } else if (kind == "ConditionalPathPoint") {
                pt.kind = OsimPathPoint::Kind::Conditional;
                pt.location = position(p, "location", kMaxPointDistance);
                pt.coordinate = text(p, "socket_coordinate", text(p, "coordinate"));
                if (pt.coordinate.rfind("/jointset/", 0) == 0) pt.coordinate = pt.coordinate.substr(pt.coordinate.rfind('/') + 1);
                if (pt.coordinate.empty()) fail(p, "missing <socket_coordinate> (4.x) or <coordinate> (3.3)");
                const std::vector<double> r = numbers(p, "range", 2);
                pt.range = {r[0], r[1]};
            } else if (kind == "MovingPathPoint") {
                pt.kind = OsimPathPoint::Kind::Moving;
                const char* loc[] = {"x_location", "y_location", "z_location"};
                const char* sock[] = {"socket_x_coordinate", "socket_y_coordinate", "socket_z_coordinate"};
                const char* old[] = {"x_coordinate", "y_coordinate", "z_coordinate"};
                for (int k = 0; k < 3; ++k) {
                    const XMLElement* l = child(p, loc[k]);
                    pt.locationFunctions[k] = function(l);
                    std::string c = text(p, sock[k], text(p, old[k]));
                    if (c.rfind("/jointset/", 0) == 0) c = c.substr(c.rfind('/') + 1);
                    pt.locationCoordinates[k] = c;
                }
            } else {
                fail(p, "path point type " + kind + " is not supported: expected PathPoint, ConditionalPathPoint or MovingPathPoint");
            }
            mu.path.push_back(pt);
        }
        if (mu.path.size() < 2) fail(pps, std::to_string(mu.path.size()) + " path points: expected at least 2");
        if (const XMLElement* pws = gp->FirstChildElement("PathWrapSet"))
            if (const XMLElement* wo = pws->FirstChildElement("objects"))
                for (const XMLElement* w = wo->FirstChildElement("PathWrap"); w; w = w->NextSiblingElement("PathWrap")) {
                    OsimPathWrap pw;
                    pw.line = child(w, "wrap_object")->GetLineNum();
                    pw.wrapObject = text(w, "wrap_object");
                    pw.method = text(w, "method", "hybrid");
                    const std::vector<double> r = numbers(w, "range", 2, false, {-1, -1});
                    pw.range = {int(r[0]), int(r[1])};
                    mu.wraps.push_back(pw);
                }
    }

    void readForces(const XMLElement* model, OsimModel& m) {
        const XMLElement* set = model->FirstChildElement("ForceSet");
        if (!set) return;
        const XMLElement* objects = set->FirstChildElement("objects");
        for (const XMLElement* f = objects ? objects->FirstChildElement() : nullptr; f; f = f->NextSiblingElement()) {
            const std::string type = f->Name();
            const auto props = getMuscleProperties().find(type);
            if (props == getMuscleProperties().end()) {
                if (type.find("Muscle") != std::string::npos || type == "PathActuator" || type == "PathSpring" ||
                    type == "CoordinateLimitForce" || type == "Ligament" || type == "SpringGeneralizedForce" ||
                    type == "ExpressionBasedCoordinateForce" || type == "HuntCrossleyForce" || type == "ElasticFoundationForce")
                    fail(f, "force type " + type + " is not supported (it would change results): expected a Thelen2003Muscle, "
                            "DeGrooteFregly2016Muscle or Millard2012EquilibriumMuscle");
                if (type == "CoordinateActuator" || type == "PointActuator" || type == "TorqueActuator") {
                    note(m, type + " (an actuator with no control here exerts no force)");
                    continue;
                }
                fail(f, "force type " + type + " is not supported");
            }
            OsimMuscle mu;
            mu.name = f->Attribute("name") ? f->Attribute("name") : "";
            mu.type = type;
            mu.line = f->GetLineNum();
            mu.appliesForce = flag(f, "appliesForce", !flag(f, "isDisabled", false));
            mu.maxIsometricForce = number(f, "max_isometric_force");
            mu.optimalFiberLength = number(f, "optimal_fiber_length");
            mu.tendonSlackLength = number(f, "tendon_slack_length");
            mu.pennationAngleAtOptimal = number(f, "pennation_angle_at_optimal", false, 0);
            mu.maxContractionVelocity = number(f, "max_contraction_velocity", false, 10);
            // The bounds an armsim model file has (basics/bound.h).
            auto within = [&](const char* tag, double v, const Bound& b) {
                if (!b.contains(v)) fail(child(f, tag), std::string(tag) + " " + formatNumber(v) + ": expected " + b.describe());
            };
            within("max_isometric_force", mu.maxIsometricForce, bounds::kMaxIsometricForce);
            if (mu.maxIsometricForce < 1)   // the weakest muscles of an arm model are some 10 N
                fail(child(f, "max_isometric_force"), "max_isometric_force " + formatNumber(mu.maxIsometricForce) +
                                                          ": expected at least 1 N (OpenSim forces are in newtons: is it in kN?)");
            within("optimal_fiber_length", mu.optimalFiberLength, bounds::kTendonLength);
            within("tendon_slack_length", mu.tendonSlackLength, bounds::kTendonLength);
            for (const std::string& p : props->second)
                if (f->FirstChildElement(p.c_str())) mu.properties[p] = number(f, p.c_str());
            for (const XMLElement* e = f->FirstChildElement(); e; e = e->NextSiblingElement()) mu.propertyLines[e->Name()] = e->GetLineNum();
            if (const std::string mode = text(f, "tendon_compliance_dynamics_mode"); !mode.empty() && mode != "explicit")
                fail(child(f, "tendon_compliance_dynamics_mode"), "'" + mode + "': expected explicit (implicit is for direct collocation)");
            if (flag(f, "ignore_tendon_compliance", false))
                fail(child(f, "ignore_tendon_compliance"), "true: a rigid tendon is not supported (expected false)");
            if (flag(f, "ignore_passive_fiber_force", false))
                fail(child(f, "ignore_passive_fiber_force"), "true: not supported (expected false)");
            if (flag(f, "ignore_activation_dynamics", false))
                fail(child(f, "ignore_activation_dynamics"), "true: expected false (activation dynamics are part of the model)");
            readPath(f, mu);
            m.muscles.push_back(mu);
        }
    }

    void readSkipped(const XMLElement* model, OsimModel& m) {
        for (const XMLElement* e = model->FirstChildElement(); e; e = e->NextSiblingElement()) {
            const std::string n = e->Name();
            if (n == "MarkerSet" || n == "ContactGeometrySet" || n == "ProbeSet" || n == "ControllerSet") {
                const XMLElement* o = e->FirstChildElement("objects");
                if (o && o->FirstChildElement()) note(m, n + " (cannot change a muscle-driven trial here)");
            }
            if (n == "ConstraintSet") {
                const XMLElement* o = e->FirstChildElement("objects");
                if (o && o->FirstChildElement()) fail(o->FirstChildElement(), "constraints are not supported (they would change the motion)");
            }
        }
    }

    // Every reference resolves: bodies of joints and path points, wrap objects of path wraps,
    // coordinates of conditional and moving points.
    void check(const OsimModel& m) const {
        auto isBody = [&](const std::string& b) { return b == "ground" || m.findBody(b); };
        auto where = [&](int line) { return source_ + ":" + std::to_string(line) + ": "; };
        // Names are how everything else refers to a muscle, coordinate or body: each once.
        auto unique = [&](const char* what, const std::vector<std::pair<std::string, int>>& named) {
            std::map<std::string, int> first;
            for (const auto& [name, line] : named) {
                const auto [it, inserted] = first.emplace(name, line);
                if (!inserted)
                    throw OsimError(where(line) + std::string(what) + " '" + name + "' is named twice (first at line " +
                                    std::to_string(it->second) + "): expected unique names");
            }
        };
        std::vector<std::pair<std::string, int>> muscles, coordinates, bodies;
        for (const OsimMuscle& mu : m.muscles) muscles.emplace_back(mu.name, mu.line);
        for (const OsimJoint& j : m.joints)
            for (const OsimCoordinate& c : j.coordinates) coordinates.emplace_back(c.name, c.line);
        for (const OsimBody& b : m.bodies) bodies.emplace_back(b.name, b.line);
        unique("muscle", muscles);
        unique("coordinate", coordinates);
        unique("body", bodies);
        for (const OsimJoint& j : m.joints) {
            if (!isBody(j.parent.body)) throw OsimError(where(j.line) + "joint '" + j.name + "': parent body '" + j.parent.body + "' does not exist");
            if (!isBody(j.child.body)) throw OsimError(where(j.line) + "joint '" + j.name + "': child body '" + j.child.body + "' does not exist");
            for (const OsimTransformAxis& a : j.axes)
                for (const std::string& c : a.coordinates)
                    if (std::none_of(j.coordinates.begin(), j.coordinates.end(), [&](const OsimCoordinate& k) { return k.name == c; }))
                        throw OsimError(where(j.line) + "joint '" + j.name + "' " + a.name + ": coordinate '" + c + "' is not the joint's");
        }
        for (const OsimMuscle& mu : m.muscles) {
            for (const OsimPathPoint& p : mu.path) {
                if (!isBody(p.body))
                    throw OsimError(where(p.line) + "muscle '" + mu.name + "' point '" + p.name + "': body '" + p.body + "' does not exist");
                auto coordinateExists = [&](const std::string& c) { return c.empty() || m.findCoordinate(c); };
                if (!coordinateExists(p.coordinate))
                    throw OsimError(where(p.line) + "muscle '" + mu.name + "' point '" + p.name + "': coordinate '" + p.coordinate + "' does not exist");
                for (const std::string& c : p.locationCoordinates)
                    if (!coordinateExists(c))
                        throw OsimError(where(p.line) + "muscle '" + mu.name + "' point '" + p.name + "': coordinate '" + c + "' does not exist");
            }
            for (const OsimPathWrap& w : mu.wraps)
                if (std::none_of(m.wrapObjects.begin(), m.wrapObjects.end(), [&](const OsimWrapObject& o) { return o.name == w.wrapObject; }))
                    throw OsimError(where(w.line) + "muscle '" + mu.name + "': wrap object '" + w.wrapObject + "' does not exist");
        }
    }

    std::string source_;
};

}  // namespace

const OsimBody* OsimModel::findBody(const std::string& n) const {
    for (const OsimBody& b : bodies)
        if (b.name == n) return &b;
    return nullptr;
}

const OsimCoordinate* OsimModel::findCoordinate(const std::string& n) const {
    for (const OsimJoint& j : joints)
        for (const OsimCoordinate& c : j.coordinates)
            if (c.name == n) return &c;
    return nullptr;
}

OsimModel readOsimText(const std::string& text, const std::string& sourceName) { return Reader(sourceName).read(text); }

OsimModel readOsimFile(const std::string& path) { return readOsimText(readFileText(path), path); }

}  // namespace armsim
