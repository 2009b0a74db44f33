#include "muscles/muscle_path.h"

#include "basics/bound.h"

#include <algorithm>
#include <cmath>
#include <sstream>

using namespace SimTK;

namespace armsim {

namespace {

constexpr double kTwoPi = 6.283185307179586476925;
// A wrap whose arc would exceed this is the path clearing the surface the long way round: inactive.
constexpr double kMaxWrapAngle = 0.75 * kTwoPi;
constexpr int kArcSamplesPerRadian = 8;

double cross2(const Vec2& a, const Vec2& b) { return a[0] * b[1] - a[1] * b[0]; }

// Tangent points, arc and polyline of one surface between the fixed points a and b (Ground).
struct SurfaceWrap {
    bool active = false;
    Vec3 ta{0}, tb{0};
    double length = 0;  // |ta - a| + arc + |b - tb|
    std::vector<Vec3> arc;
};

[[noreturn]] void throwInside(const std::string& muscle, const PathElement& e, double distance) {
    std::ostringstream msg;
    msg << "muscle '" << muscle << "': a path point lies inside the wrapping surface '" << e.label
        << "' (distance " << distance << " m from its axis or centre, radius " << e.radius
        << " m): move the point or shrink the surface";
    throw SimulationError(msg.str());
}

// The 2D wrap lifted to 3D: e1, e2 span the wrap plane, e3 is the cylinder axis (zero for a sphere).
SurfaceWrap liftWrap(const CircleWrap& w, const Vec3& c, const UnitVec3& e1, const UnitVec3& e2, const Vec3& e3,
                     double zp, double zq, double R, bool withArc) {
    SurfaceWrap out;
    out.active = true;
    const double planar = w.lengthP + R * w.angle + w.lengthQ;
    const double dz = zq - zp;
    const double zTp = zp + dz * w.lengthP / planar;
    const double zTq = zp + dz * (w.lengthP + R * w.angle) / planar;
    out.ta = c + w.tp[0] * e1 + w.tp[1] * e2 + zTp * e3;
    out.tb = c + w.tq[0] * e1 + w.tq[1] * e2 + zTq * e3;
    out.length = std::sqrt(planar * planar + dz * dz);
    if (withArc) {
        const double th0 = std::atan2(w.tp[1], w.tp[0]);
        const int n = std::max(2, int(std::ceil(w.angle * kArcSamplesPerRadian)));
        for (int k = 1; k < n; ++k) {
            const double f = double(k) / n;
            const double th = th0 + w.direction * w.angle * f;
            out.arc.push_back(c + R * std::cos(th) * e1 + R * std::sin(th) * e2 + (zTp + f * (zTq - zTp)) * e3);
        }
    }
    return out;
}

SurfaceWrap wrapSurface(const PathElement& e, const State& s, const Vec3& a, const Vec3& b,
                        const std::string& muscle, bool withArc) {
    const Transform& X_GB = e.body.getBodyTransform(s);
    const Vec3 c = X_GB * e.location;
    const Vec3 side = X_GB.R() * e.side;
    const Vec3 p = a - c, q = b - c;
    if (e.kind == PathElement::Kind::Cylinder) {
        const UnitVec3 e3 = X_GB.R() * e.axis;
        const UnitVec3 e1 = e3.perp();
        const UnitVec3 e2(e3 % e1, true);
        const Vec2 p2(dot(p, e1), dot(p, e2)), q2(dot(q, e1), dot(q, e2)), s2(dot(side, e1), dot(side, e2));
        if (p2.norm() <= e.radius) throwInside(muscle, e, p2.norm());
        if (q2.norm() <= e.radius) throwInside(muscle, e, q2.norm());
        const CircleWrap w = calcCircleWrap(p2, q2, e.radius, s2, s2.norm() > 0, e.winds);
        if (!w.active) return {};
        return liftWrap(w, c, e1, e2, Vec3(e3), dot(p, e3), dot(q, e3), e.radius, withArc);
    }
    // Sphere: the great circle in the plane of the centre, a and b.
    if (p.norm() <= e.radius) throwInside(muscle, e, p.norm());
    if (q.norm() <= e.radius) throwInside(muscle, e, q.norm());
    Vec3 n = p % q;
    if (n.norm() <= 1e-12 * p.norm() * q.norm()) n = p % side;
    if (n.norm() <= 1e-12 * p.norm() * (side.norm() + 1e-300)) n = UnitVec3(p).perp().asVec3();
    const UnitVec3 e1(p), e3(n);
    const UnitVec3 e2(e3 % e1, true);
    const Vec2 p2(p.norm(), 0), q2(dot(q, e1), dot(q, e2)), s2(dot(side, e1), dot(side, e2));
    const CircleWrap w = calcCircleWrap(p2, q2, e.radius, s2, s2.norm() > 0, e.winds);
    if (!w.active) return {};
    return liftWrap(w, c, e1, e2, Vec3(0), 0, 0, e.radius, withArc);
}

}  // namespace

CircleWrap calcCircleWrap(const Vec2& p, const Vec2& q, double R, const Vec2& side, bool hasSide, bool winds) {
    CircleWrap w;
    const Vec2 d = q - p;
    const double dd = d.normSqr();
    if (dd == 0) return w;
    const double tClosest = -dot(p, d) / dd;  // parameter of the line's point closest to the centre
    int sigma;
    if (hasSide) {
        // The path may not pass through the circle nor through the strip behind it (the side opposite
        // s, as wide as the circle): clip the segment to the band |x . u| < R (u normal to s) and
        // look for a point of the clipped part inside the circle or behind the centre.
        const Vec2 s = side / side.norm(), u(-s[1], s[0]);
        const double a = dot(p, u), b = dot(d, u);
        double u0 = 0, u1 = 1;
        bool inStrip = true;
        if (std::abs(b) < 1e-300) {
            inStrip = std::abs(a) < R;
        } else {
            const double e0 = (-R - a) / b, e1 = (R - a) / b;
            u0 = std::max(0.0, std::min(e0, e1));
            u1 = std::min(1.0, std::max(e0, e1));
            inStrip = u0 < u1;
        }
        bool blocked = false;
        if (inStrip) {
            const bool behind = std::min(dot(p + u0 * d, s), dot(p + u1 * d, s)) < 0;
            const double tc = std::clamp(tClosest, u0, u1);
            blocked = behind || (p + tc * d).norm() < R;
        }
        if (!blocked && (!winds || dot(p + std::clamp(tClosest, 0.0, 1.0) * d, s) >= 0)) return w;
        if (!winds) {
            // Passing on the +s side puts the centre on the path's right when s is on its left: clockwise.
            sigma = cross2(d, s) > 0 ? -1 : +1;
        } else {
            // Wound (the segment's direction says nothing past half a turn): the shorter of the ways whose
            // arc passes s, else the way whose arc's middle is nearest s.
            const double ths = std::atan2(s[1], s[0]);
            double best = -1e300;
            sigma = 1;
            for (int sg : {1, -1}) {
                const double thP = std::atan2(p[1], p[0]) + sg * std::acos(R / p.norm());
                const double thQ = std::atan2(q[1], q[0]) - sg * std::acos(R / q.norm());
                double angle = std::fmod(sg * (thQ - thP), kTwoPi);
                if (angle < 0) angle += kTwoPi;
                double toS = std::fmod(sg * (ths - thP), kTwoPi);
                if (toS < 0) toS += kTwoPi;
                const double score = toS <= angle ? 2 * kTwoPi - angle : std::cos(thP + sg * 0.5 * angle - ths);
                if (score > best) best = score, sigma = sg;
            }
        }
    } else {
        if (tClosest <= 0 || tClosest >= 1) return w;
        const Vec2 c = p + tClosest * d;
        if (c.norm() >= R) return w;
        sigma = cross2(d, c) > 0 ? -1 : +1;  // round the side the segment passes: the shorter way
    }
    const double rp = p.norm(), rq = q.norm();
    const double alpha = std::acos(R / rp), beta = std::acos(R / rq);
    const double thP = std::atan2(p[1], p[0]) + sigma * alpha;
    const double thQ = std::atan2(q[1], q[0]) - sigma * beta;
    double angle = std::fmod(sigma * (thQ - thP), kTwoPi);
    if (angle < 0) angle += kTwoPi;
    if (angle > kMaxWrapAngle) return w;
    w.active = true;
    w.direction = sigma;
    w.angle = angle;
    w.tp = Vec2(R * std::cos(thP), R * std::sin(thP));
    w.tq = Vec2(R * std::cos(thQ), R * std::sin(thQ));
    w.lengthP = std::sqrt(std::max(0.0, rp * rp - R * R));
    w.lengthQ = std::sqrt(std::max(0.0, rq * rq - R * R));
    return w;
}

MusclePath::MusclePath(const MobilizedBody& originBody, const Vec3& origin, const MobilizedBody& insertionBody,
                       const Vec3& insertion) {
    PathElement o, i;
    o.body = originBody;
    o.location = origin;
    o.label = "origin";
    i.body = insertionBody;
    i.location = insertion;
    i.label = "insertion";
    elements_ = {o, i};
}

MusclePath::MusclePath(std::vector<PathElement> elements) : elements_(std::move(elements)) {
    const int n = int(elements_.size());
    if (n < 2) throw InputError("muscle path: needs an origin and an insertion, got " + std::to_string(n) + " elements");
    if (elements_.front().isSurface() || elements_.back().isSurface())
        throw InputError("muscle path: the origin and the insertion must be points, not wrapping surfaces");
    for (int k = 0; k < n; ++k) {
        const PathElement& e = elements_[k];
        if (!e.isSurface()) continue;
        if (elements_[k + 1].isSurface())
            throw InputError("muscle path: wrapping surfaces '" + e.label + "' and '" + elements_[k + 1].label +
                             "' follow each other; put a via point between them (one surface between two points)");
        checkField(e.label + ".radius", e.radius, Bound::positive("m"));
    }
    for (int k = 0; k < n; ++k) {
        if (!elements_[k].isConditional()) continue;
        if (k == 0 || k == n - 1 || elements_[k].isSurface() || elements_[k - 1].isSurface() || elements_[k + 1].isSurface())
            throw InputError("muscle path: '" + elements_[k].label +
                             "' is used over a range of rotation: it must be a via point between two points, not next to a wrapping surface");
        if (!(elements_[k].activeMin < elements_[k].activeMax))
            throw InputError("muscle path: '" + elements_[k].label + "': its active range is empty");
    }
}

PathGeometry MusclePath::calcGeometry(const State& s, const std::string& muscleName, bool withPolyline) const {
    PathGeometry g;
    const int n = int(elements_.size());
    g.wrapping.assign(n, false);
    auto pointInGround = [&](int k) {
        return elements_[k].body.getBodyTransform(s) * elements_[k].location;
    };
    auto addLoad = [&](int k, const Vec3& point, const Vec3& force) {
        const MobilizedBody& body = elements_[k].body;
        g.loads.push_back({k, body.getMobilizedBodyIndex(), point, point - body.getBodyTransform(s).p(), force});
    };
    auto isActive = [&](int k) {
        const PathElement& e = elements_[k];
        if (!e.isConditional()) return true;
        const double q = e.joint.getOneQ(s, MobilizerQIndex(0));
        return q >= e.activeMin && q <= e.activeMax;
    };
    int i = 0;
    Vec3 a = pointInGround(0);
    if (withPolyline) g.polyline.push_back(a);
    while (i < n - 1) {
        int next = i + 1;
        while (!isActive(next)) ++next;   // conditional points lie between points: next is a point
        const int k = elements_[next].isSurface() ? next : -1;  // the surface between two points
        const int j = k >= 0 ? next + 1 : next;
        const Vec3 b = pointInGround(j);
        SurfaceWrap w;
        if (k >= 0) {
            w = wrapSurface(elements_[k], s, a, b, muscleName, withPolyline);
            if (w.active) {
                g.wrapping[k] = true;
                addLoad(k, w.ta, Vec3(UnitVec3(a - w.ta).asVec3()));
                addLoad(k, w.tb, Vec3(UnitVec3(b - w.tb).asVec3()));
            }
        }
        if (w.active) {
            g.length += w.length;
            addLoad(i, a, Vec3(UnitVec3(w.ta - a).asVec3()));
            addLoad(j, b, Vec3(UnitVec3(w.tb - b).asVec3()));
            if (withPolyline) {
                g.polyline.push_back(w.ta);
                g.polyline.insert(g.polyline.end(), w.arc.begin(), w.arc.end());
                g.polyline.push_back(w.tb);
            }
        } else {
            const Vec3 d = b - a;
            const double len = d.norm();
            g.length += len;
            const Vec3 u = len > 0 ? Vec3(d / len) : Vec3(0);
            addLoad(i, a, u);
            addLoad(j, b, -u);
        }
        if (withPolyline) g.polyline.push_back(b);
        i = j;
        a = b;
    }
    return g;
}

double MusclePath::calcLength(const State& s) const {
    if (isStraight())
        return (elements_[1].body.getBodyTransform(s) * elements_[1].location -
                elements_[0].body.getBodyTransform(s) * elements_[0].location).norm();
    return calcGeometry(s).length;
}

double MusclePath::calcLengtheningSpeed(const State& s, const PathGeometry& g) const {
    // The power of a unit tension is -dP/dt: sum over its loads of force . (point velocity).
    double power = 0;
    for (const PathLoad& l : g.loads) {
        const SpatialVec V = elements_[l.element].body.getBodyVelocity(s);
        power += dot(l.force, V[1] + cross(V[0], l.arm));
    }
    return -power;
}

void MusclePath::applyTension(const PathGeometry& g, double tension, Vector_<SpatialVec>& bodyForces) {
    for (const PathLoad& l : g.loads) {
        const Vec3 f = tension * l.force;
        bodyForces[l.body] += SpatialVec(l.arm % f, f);
    }
}

void appendPathDecorations(const MusclePath& path, const PathGeometry& g, const Vec3& color, double lineThickness,
                           Array_<DecorativeGeometry>& geometry) {
    constexpr double kViaRadius = 0.004;       // m, drawing only
    constexpr double kCylinderHalfLength = 0.02;  // m, drawing only
    for (std::size_t k = 1; k < g.polyline.size(); ++k)
        geometry.push_back(DecorativeLine(g.polyline[k - 1], g.polyline[k]).setColor(color).setLineThickness(lineThickness));
    const std::vector<PathElement>& elements = path.getElements();
    for (std::size_t k = 0; k < elements.size(); ++k) {
        const PathElement& e = elements[k];
        const int body = int(e.body.getMobilizedBodyIndex());
        if (e.kind == PathElement::Kind::Point) {
            if (k == 0 || k + 1 == elements.size()) continue;  // origin and insertion: the line ends there
            geometry.push_back(DecorativeSphere(kViaRadius).setBodyId(body).setTransform(Transform(e.location))
                                   .setColor(Vec3(0.9, 0.9, 0.2)));
            continue;
        }
        const double opacity = g.wrapping.size() > k && g.wrapping[k] ? 0.55 : 0.25;
        const Vec3 surfaceColor(0.55, 0.6, 0.75);
        if (e.kind == PathElement::Kind::Cylinder) {
            // DecorativeCylinder runs along its Y axis: rotate Y onto the cylinder's axis.
            const Rotation R_BC(e.axis, YAxis);
            geometry.push_back(DecorativeCylinder(e.radius, kCylinderHalfLength).setBodyId(body)
                                   .setTransform(Transform(R_BC, e.location)).setColor(surfaceColor).setOpacity(opacity));
        } else {
            geometry.push_back(DecorativeSphere(e.radius).setBodyId(body).setTransform(Transform(e.location))
                                   .setColor(surfaceColor).setOpacity(opacity));
        }
    }
}

}  // namespace armsim
