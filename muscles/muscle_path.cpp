#include "muscles/muscle_path.h"

#include "basics/bound.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

using namespace SimTK;

namespace armsim {

namespace {

constexpr double kTwoPi = 6.283185307179586476925;
// A wrap whose arc would exceed this is the path clearing the surface the long way round: inactive.
constexpr double kMaxWrapAngle = 0.75 * kTwoPi;
constexpr int kArcSamplesPerRadian = 8;

double cross2(const Vec2& a, const Vec2& b) { return a[0] * b[1] - a[1] * b[0]; }

// Whether the segment p-q passes inside the circle of radius R about the origin (2D).
bool segmentCutsCircle(const Vec2& p, const Vec2& q, double R) {
    const Vec2 d = q - p;
    const double dd = d.normSqr();
    if (dd == 0) return false;
    const double t = -dot(p, d) / dd;
    return t > 0 && t < 1 && (p + t * d).norm() < R;
}

// Tangent points, arc and polyline of one surface between the fixed points a and b (Ground).
struct SurfaceWrap {
    bool active = false;
    Vec3 ta{0}, tb{0};
    double length = 0;     // |ta - a| + arc + |b - tb|
    double arcLength = 0;  // the part on the surface
    std::vector<Vec3> arc;
};

[[noreturn]] void throwInside(const std::string& muscle, const PathElement& e, double distance) {
    std::ostringstream msg;
    msg << "muscle '" << muscle << "': a path point lies inside the wrapping surface '" << e.label
        << "' (distance " << distance << " m from its axis or centre, ";
    if (e.kind == PathElement::Kind::Ellipsoid)
        msg << "semi-axes " << e.radii[0] << ", " << e.radii[1] << ", " << e.radii[2];
    else
        msg << "radius " << e.radius;
    msg << " m): move the point or shrink the surface";
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
    out.arcLength = R * w.angle * (planar > 0 ? out.length / planar : 1.0);  // the helix's share
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

SurfaceWrap wrapEllipsoid(const PathElement& e, const Transform& X_GB, const Vec3& a, const Vec3& b,
                          const std::string& muscle, bool withArc);

SurfaceWrap wrapSurface(const PathElement& e, const Transform& X_GB, const Vec3& a, const Vec3& b,
                        const std::string& muscle, bool withArc) {
    if (e.kind == PathElement::Kind::Ellipsoid) return wrapEllipsoid(e, X_GB, a, b, muscle, withArc);
    const Vec3 c = X_GB * e.location;
    const Vec3 side = X_GB.R() * e.side;
    const Vec3 p = a - c, q = b - c;
    if (e.kind == PathElement::Kind::Cylinder) {
        const UnitVec3 e3 = X_GB.R() * e.axis;
        const UnitVec3 e1 = e3.perp();
        const UnitVec3 e2(e3 % e1, true);
        const Vec2 p2(dot(p, e1), dot(p, e2)), q2(dot(q, e1), dot(q, e2)), s2(dot(side, e1), dot(side, e2));
        if (std::min(p2.norm(), q2.norm()) <= e.radius) {
            if (e.passWhenInside) return {};
            throwInside(muscle, e, std::min(p2.norm(), q2.norm()));
        }
        const CircleWrap w = calcCircleWrap(p2, q2, e.radius, s2, s2.norm() > 0, e.winds);
        if (!w.active) return {};
        SurfaceWrap out = liftWrap(w, c, e1, e2, Vec3(e3), dot(p, e3), dot(q, e3), e.radius, withArc);
        if (e.length > 0 && std::abs(dot(out.ta - c, e3)) > e.length / 2 && std::abs(dot(out.tb - c, e3)) > e.length / 2)
            return {};  // both tangent points beyond the cylinder's ends
        return out;
    }
    // Sphere: the great circle in the plane of the centre, a and b.
    if (std::min(p.norm(), q.norm()) <= e.radius) {
        if (e.passWhenInside) return {};
        throwInside(muscle, e, std::min(p.norm(), q.norm()));
    }
    Vec3 n = p % q;
    if (n.norm() <= 1e-12 * p.norm() * q.norm()) n = p % side;
    if (n.norm() <= 1e-12 * p.norm() * (side.norm() + 1e-300)) n = UnitVec3(p).perp().asVec3();
    const UnitVec3 e1(p), e3(n);
    const UnitVec3 e2(e3 % e1, true);
    const Vec2 p2(p.norm(), 0), q2(dot(q, e1), dot(q, e2)), s2(dot(side, e1), dot(side, e2));
    if (e.onlyWhenCut && !segmentCutsCircle(p2, q2, e.radius)) return {};
    const CircleWrap w = calcCircleWrap(p2, q2, e.radius, s2, s2.norm() > 0, e.winds);
    if (!w.active) return {};
    return liftWrap(w, c, e1, e2, Vec3(0), 0, 0, e.radius, withArc);
}

// Length of the ellipse arc x(th) = E (cos th u + sin th v), th from th0 over `angle` in direction
// `direction` (E: the map from the unit sphere's space to Ground, u, v orthonormal there): Gauss-Legendre
// with 16 nodes on pieces of at most pi/8.
double calcEllipseArcLength(const Mat33& E, const Vec3& u, const Vec3& v, double th0, double angle, int direction) {
    static const double x[8] = {0.0950125098376374, 0.2816035507792589, 0.4580167776572274, 0.6178762444026438,
                                0.7554044083550030, 0.8656312023878318, 0.9445750230732326, 0.9894009349916499};
    static const double w[8] = {0.1894506104550685, 0.1826034150449236, 0.1691565193950025, 0.1495959888165767,
                                0.1246289712555339, 0.0951585116824928, 0.0622535239386479, 0.0271524594117541};
    const int pieces = std::max(1, int(std::ceil(angle / (kTwoPi / 16))));
    const double h = angle / pieces;
    // Nodes by the angle-addition formulas: one sine and cosine per node offset and per piece.
    double co[8], si[8];
    for (int j = 0; j < 8; ++j) co[j] = std::cos(x[j] * 0.5 * h), si[j] = direction * std::sin(x[j] * 0.5 * h);
    const Vec3 Eu = E * u, Ev = E * v;
    double length = 0;
    for (int k = 0; k < pieces; ++k) {
        const double mid = th0 + direction * (k + 0.5) * h;
        const double cm = std::cos(mid), sm = std::sin(mid);
        for (int j = 0; j < 8; ++j)
            for (int sgn : {-1, 1}) {
                const double c = cm * co[j] - sm * sgn * si[j], sn = sm * co[j] + cm * sgn * si[j];
                length += w[j] * 0.5 * h * (-sn * Eu + c * Ev).norm();
            }
    }
    return length;
}

// The ellipsoid's planar wrap between a and b (Ground), through the unit sphere's construction.
SurfaceWrap wrapEllipsoid(const PathElement& e, const Transform& X_GB, const Vec3& a, const Vec3& b,
                          const std::string& muscle, bool withArc) {
    const Vec3 c = X_GB * e.location;
    const Rotation R_GE = X_GB.R() * e.orientation;
    const Mat33 D(e.radii[0], 0, 0, 0, e.radii[1], 0, 0, 0, e.radii[2]);
    const Mat33 Dinv(1 / e.radii[0], 0, 0, 0, 1 / e.radii[1], 0, 0, 0, 1 / e.radii[2]);
    const Mat33 toSphere = Dinv * ~R_GE.asMat33(), fromSphere = R_GE.asMat33() * D;
    // The half-space s . x > 0 maps to n . x' > 0 with n = D R^T s (a normal maps by the inverse transpose).
    const Vec3 p = toSphere * (a - c), q = toSphere * (b - c), side = D * (~R_GE.asMat33() * (X_GB.R() * e.side));
    if (p.norm() <= 1 || q.norm() <= 1) {
        if (e.passWhenInside) return {};
        throwInside(muscle, e, (p.norm() <= 1 ? a - c : b - c).norm());
    }
    Vec3 n = p % q;
    if (n.norm() <= 1e-12 * p.norm() * q.norm()) n = p % side;
    if (n.norm() <= 1e-12 * p.norm() * (side.norm() + 1e-300)) n = UnitVec3(p).perp().asVec3();
    const UnitVec3 e1(p), e3(n);
    const UnitVec3 e2(e3 % e1, true);
    const Vec2 p2(p.norm(), 0), q2(dot(q, e1), dot(q, e2)), s2(dot(side, e1), dot(side, e2));
    if (e.onlyWhenCut && !segmentCutsCircle(p2, q2, 1.0)) return {};
    const CircleWrap w = calcCircleWrap(p2, q2, 1.0, s2, s2.norm() > 0, e.winds);
    if (!w.active) return {};
    SurfaceWrap out;
    out.active = true;
    out.ta = c + fromSphere * (w.tp[0] * e1 + w.tp[1] * e2);
    out.tb = c + fromSphere * (w.tq[0] * e1 + w.tq[1] * e2);
    const double th0 = std::atan2(w.tp[1], w.tp[0]);
    out.arcLength = calcEllipseArcLength(fromSphere, Vec3(e1), Vec3(e2), th0, w.angle, w.direction);
    out.length = (out.ta - a).norm() + out.arcLength + (b - out.tb).norm();
    if (withArc) {
        const int m = std::max(2, int(std::ceil(w.angle * kArcSamplesPerRadian)));
        for (int k = 1; k < m; ++k) {
            const double th = th0 + w.direction * w.angle * double(k) / m;
            out.arc.push_back(c + fromSphere * (std::cos(th) * e1 + std::sin(th) * e2));
        }
    }
    return out;
}

// Several surfaces between the fixed points a and b, in path order (OpenSim applies several wrap
// objects to one segment in turn, up to 8 passes): each wraps between its active neighbours' tangent
// points (or a, b), in passes until no tangent point moves by more than 1e-13 m (at most 40). Where two
// paths alternate from pass to pass, the longer of two successive passes' paths is taken (a path that
// wraps more is clear of more surfaces), not the one the pass count's parity lands on. Limitation: the
// passes can settle on different paths from nearby configurations (a cylinder and an ellipsoid on one
// segment can give two paths centimetres apart, both with both surfaces in use; README, OpenSim files);
// OpenSim's own passes do not settle there either.
struct ChainWrap {
    std::vector<SurfaceWrap> wraps;
    double length = 0;
    int active = 0;
};

ChainWrap wrapChain(const std::vector<const PathElement*>& es, const std::vector<Transform>& X, const Vec3& a,
                    const Vec3& b, const std::string& muscle, bool withArc) {
    constexpr int kMaxPasses = 40;
    const int K = int(es.size());
    std::vector<SurfaceWrap> wraps(K);
    auto ends = [&](int k) {
        Vec3 from = a, to = b;
        for (int r = k - 1; r >= 0; --r)
            if (wraps[r].active) {
                from = wraps[r].tb;
                break;
            }
        for (int r = k + 1; r < K; ++r)
            if (wraps[r].active) {
                to = wraps[r].ta;
                break;
            }
        return std::make_pair(from, to);
    };
    auto pass = [&] {  // one pass; the largest move of a tangent point (1 when a surface switched)
        double change = 0;
        for (int k = 0; k < K; ++k) {
            const auto [from, to] = ends(k);
            SurfaceWrap w = wrapSurface(*es[k], X[k], from, to, muscle, withArc);
            const SurfaceWrap& old = wraps[k];
            if (w.active != old.active) change = 1;
            else if (w.active) change = std::max({change, (w.ta - old.ta).norm(), (w.tb - old.tb).norm()});
            wraps[k] = std::move(w);
        }
        return change;
    };
    auto lengthOf = [&](const std::vector<SurfaceWrap>& w) {
        double length = 0;
        Vec3 at = a;
        for (const SurfaceWrap& x : w)
            if (x.active) {
                length += (x.ta - at).norm() + x.arcLength;
                at = x.tb;
            }
        return length + (b - at).norm();
    };
    bool settled = false;
    for (int n = 0; n < kMaxPasses && !settled; ++n) settled = pass() <= 1e-13;
    if (!settled) {
        const std::vector<SurfaceWrap> first = wraps;
        pass();
        if (lengthOf(first) > lengthOf(wraps)) wraps = first;
    }
    ChainWrap c;
    c.wraps = std::move(wraps);
    c.length = lengthOf(c.wraps);
    for (const SurfaceWrap& x : c.wraps) c.active += x.active;
    return c;
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

Vec3 PathElement::findLocation(const State& s) const {
    if (!isMoving()) return location;
    Vec3 p, dpdq;
    calcMovingLocation(mover.getOneQ(s, MobilizerQIndex(0)), p, dpdq);
    return p;
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
        if (e.kind == PathElement::Kind::Ellipsoid) {
            for (int d = 0; d < 3; ++d) checkField(e.label + ".radii[" + std::to_string(d) + "]", e.radii[d], Bound::positive("m"));
        } else {
            checkField(e.label + ".radius", e.radius, Bound::positive("m"));
        }
    }
    for (int k = 0; k < n; ++k) {
        const PathElement& e = elements_[k];
        if (e.isMoving() && (e.isSurface() || e.isConditional() || !e.calcMovingLocation))
            throw InputError("muscle path: '" + e.label + "' moves with a coordinate: it must be a point with a location function");
        if (!e.isConditional()) continue;
        if (k == 0 || k == n - 1 || elements_[k].isSurface() || elements_[k - 1].isSurface() || elements_[k + 1].isSurface())
            throw InputError("muscle path: '" + elements_[k].label +
                             "' is used over a range of rotation: it must be a via point between two points, not next to a wrapping surface");
        if (!(elements_[k].activeMin < elements_[k].activeMax))
            throw InputError("muscle path: '" + elements_[k].label + "': its active range is empty");
    }
}

namespace {

// Builds one PathGeometry (MusclePath::calcGeometry): the length, the loads of a unit tension on the
// bodies (points, tangent points, surfaces' centres with couples) and the polyline.
class GeometryBuilder {
public:
    GeometryBuilder(const std::vector<PathElement>& elements, const State& s, const std::string& muscleName,
                    bool withPolyline)
        : elements_(elements), s_(s), muscleName_(muscleName), withPolyline_(withPolyline) {
        g_.wrapping.assign(elements.size(), false);
    }

    PathGeometry build() {
        const int n = int(elements_.size());
        int i = 0;
        Vec3 a = pointInGround(0);
        if (withPolyline_) g_.polyline.push_back(a);
        while (i < n - 1) {
            int next = i + 1;
            while (!isActive(next)) ++next;   // conditional points lie between points: next is a point or a surface
            int j = next;                     // the surfaces between two points are next .. j - 1
            while (elements_[j].isSurface()) ++j;
            const Vec3 b = pointInGround(j);
            if (j - next == 0) addStraight(i, j, a, b);
            else if (j - next == 1) addOneSurface(i, next, j, a, b);   // the common case
            else addChain(i, next, j, a, b);
            if (withPolyline_) g_.polyline.push_back(b);
            i = j;
            a = b;
        }
        return std::move(g_);
    }

private:
    Vec3 pointInGround(int k) const { return elements_[k].body.getBodyTransform(s_) * elements_[k].findLocation(s_); }

    void addLoad(int k, const Vec3& point, const Vec3& force) {
        const PathElement& e = elements_[k];
        const MobilizedBody& body = e.body;
        g_.loads.push_back({k, body.getMobilizedBodyIndex(), point, point - body.getBodyTransform(s_).p(), force});
        if (e.isMoving()) {
            // The point's own motion on its body: the force's virtual work along d point / dq.
            Vec3 location, dLocationDq;
            e.calcMovingLocation(e.mover.getOneQ(s_, MobilizerQIndex(0)), location, dLocationDq);
            g_.mobilityLoads.push_back({e.mover.getFirstUIndex(s_), dot(force, body.getBodyRotation(s_) * dLocationDq)});
        }
    }

    bool isActive(int k) const {
        const PathElement& e = elements_[k];
        if (!e.isConditional()) return true;
        const double q = e.joint.getOneQ(s_, MobilizerQIndex(0));
        return q >= e.activeMin && q <= e.activeMax;
    }

    void addStraight(int i, int j, const Vec3& a, const Vec3& b) {
        const Vec3 d = b - a;
        const double len = d.norm();
        g_.length += len;
        const Vec3 u = len > 0 ? Vec3(d / len) : Vec3(0);
        addLoad(i, a, u);
        addLoad(j, b, -u);
    }

    void addArc(const SurfaceWrap& w) {
        if (!withPolyline_) return;
        g_.polyline.push_back(w.ta);
        g_.polyline.insert(g_.polyline.end(), w.arc.begin(), w.arc.end());
        g_.polyline.push_back(w.tb);
    }

    // One wrapping surface k between the points i and j.
    void addOneSurface(int i, int k, int j, const Vec3& a, const Vec3& b) {
        const SurfaceWrap w = wrapSurface(elements_[k], elements_[k].body.getBodyTransform(s_), a, b, muscleName_, withPolyline_);
        if (!w.active) return addStraight(i, j, a, b);
        g_.wrapping[k] = true;
        g_.length += w.length;
        addSurfaceLoads(i, k, j, a, b, w);
        addArc(w);
    }

    void addSurfaceLoads(int i, int k, int j, const Vec3& a, const Vec3& b, const SurfaceWrap& w) {
        if (elements_[k].kind == PathElement::Kind::Ellipsoid) addEllipsoidLoads(i, k, j, a, b, w);
        else addTangentLoads(i, k, j, a, b, w);
    }

    // Loads of an active ellipsoid alone between a and b: the gradient of its planar length (central
    // differences) at the points, and on its body what rigid invariance leaves (a force and a couple
    // about its centre).
    void addEllipsoidLoads(int i, int k, int j, const Vec3& a, const Vec3& b, const SurfaceWrap& w) {
        const PathElement& e = elements_[k];
        const Transform& X_GB = e.body.getBodyTransform(s_);
        const Vec3 c = X_GB * e.location;
        const double h = 1e-5 * std::min({e.radii[0], e.radii[1], e.radii[2]});
        auto lengthAt = [&](const Vec3& pa, const Vec3& pb) {
            const SurfaceWrap x = wrapEllipsoid(e, X_GB, pa, pb, muscleName_, false);
            return x.active ? x.length : (pb - pa).norm();
        };
        Vec3 ga(0), gb(0);
        const Vec3 normal = (a - c) % (b - c);
        if (normal.norm() > 1e-6 * (a - c).norm() * (b - c).norm()) {
            // Within the plane of c, a and b the path is that plane's shortest: the gradient is the unit
            // vector from the tangent point (envelope theorem). Only the plane's tilt needs differences.
            const UnitVec3 n(normal);
            const double dna = (lengthAt(a + h * n, b) - lengthAt(a - h * n, b)) / (2 * h);
            const double dnb = (lengthAt(a, b + h * n) - lengthAt(a, b - h * n)) / (2 * h);
            auto inPlane = [&](const Vec3& v) { return v - dot(v, n) * n; };
            ga = inPlane(UnitVec3(a - w.ta).asVec3()) + dna * n;
            gb = inPlane(UnitVec3(b - w.tb).asVec3()) + dnb * n;
        } else {
            for (int d = 0; d < 3; ++d) {
                Vec3 dx(0);
                dx[d] = h;
                ga[d] = (lengthAt(a + dx, b) - lengthAt(a - dx, b)) / (2 * h);
                gb[d] = (lengthAt(a, b + dx) - lengthAt(a, b - dx)) / (2 * h);
            }
        }
        addLoad(k, c, ga + gb);
        g_.loads.back().moment = (a - c) % ga + (b - c) % gb;
        addLoad(i, a, -ga);
        addLoad(j, b, -gb);
    }

    // Loads of one active cylinder or sphere: the tension at its tangent points (the path is a geodesic).
    void addTangentLoads(int i, int k, int j, const Vec3& a, const Vec3& b, const SurfaceWrap& w) {
        addLoad(k, w.ta, Vec3(UnitVec3(a - w.ta).asVec3()));
        addLoad(k, w.tb, Vec3(UnitVec3(b - w.tb).asVec3()));
        addLoad(i, a, Vec3(UnitVec3(w.ta - a).asVec3()));
        addLoad(j, b, Vec3(UnitVec3(w.tb - b).asVec3()));
    }

    // The surfaces next .. j - 1 between the points i and j, wrapped in turn (wrapChain).
    void addChain(int i, int next, int j, const Vec3& a, const Vec3& b) {
        std::vector<int> ks;
        std::vector<const PathElement*> es;
        std::vector<Transform> X;
        for (int k = next; k < j; ++k) {
            ks.push_back(k);
            es.push_back(&elements_[k]);
            X.push_back(elements_[k].body.getBodyTransform(s_));
        }
        const ChainWrap c = wrapChain(es, X, a, b, muscleName_, withPolyline_);
        if (c.active == 0) return addStraight(i, j, a, b);
        g_.length += c.length;
        for (std::size_t m = 0; m < ks.size(); ++m) g_.wrapping[ks[m]] = c.wraps[m].active;
        if (c.active == 1) {
            std::size_t m = 0;
            while (m + 1 < c.wraps.size() && !c.wraps[m].active) ++m;
            addSurfaceLoads(i, ks[m], j, a, b, c.wraps[m]);
        } else {
            addChainLoads(i, j, a, b, ks, es, X, c);
        }
        for (const SurfaceWrap& w : c.wraps)
            if (w.active) addArc(w);
    }

    // Several surfaces in use: loads from the gradient of the chain's length (central differences) with
    // respect to a, b and each active surface's pose (a force and a couple about its centre), whatever
    // their kinds.
    void addChainLoads(int i, int j, const Vec3& a, const Vec3& b, const std::vector<int>& ks,
                       const std::vector<const PathElement*>& es, const std::vector<Transform>& X, const ChainWrap& c) {
        auto chainLength = [&](const Vec3& pa, const Vec3& pb, const std::vector<Transform>& XX) {
            return wrapChain(es, XX, pa, pb, muscleName_, false).length;
        };
        const double h = 1e-7, hr = 1e-6;  // m, rad
        Vec3 ga(0), gb(0);
        for (int d = 0; d < 3; ++d) {
            Vec3 dx(0);
            dx[d] = h;
            ga[d] = (chainLength(a + dx, b, X) - chainLength(a - dx, b, X)) / (2 * h);
            gb[d] = (chainLength(a, b + dx, X) - chainLength(a, b - dx, X)) / (2 * h);
        }
        addLoad(i, a, -ga);
        addLoad(j, b, -gb);
        for (std::size_t m = 0; m < ks.size(); ++m) {
            if (!c.wraps[m].active) continue;
            const Vec3 centre = X[m] * elements_[ks[m]].location;
            Vec3 force(0), moment(0);
            for (int d = 0; d < 3; ++d) {
                std::vector<Transform> plus = X, minus = X;
                Vec3 dx(0);
                dx[d] = h;
                plus[m].updP() += dx;
                minus[m].updP() -= dx;
                force[d] = -(chainLength(a, b, plus) - chainLength(a, b, minus)) / (2 * h);
                for (int sign : {1, -1}) {
                    const Rotation R(sign * hr, CoordinateAxis(d));
                    (sign > 0 ? plus : minus)[m] = Transform(R * X[m].R(), centre + R * (X[m].p() - centre));
                }
                moment[d] = -(chainLength(a, b, plus) - chainLength(a, b, minus)) / (2 * hr);
            }
            addLoad(ks[m], centre, force);
            g_.loads.back().moment = moment;
        }
    }

    const std::vector<PathElement>& elements_;
    const State& s_;
    const std::string& muscleName_;
    const bool withPolyline_;
    PathGeometry g_;
};

}  // namespace

PathGeometry MusclePath::calcGeometry(const State& s, const std::string& muscleName, bool withPolyline) const {
    return GeometryBuilder(elements_, s, muscleName, withPolyline).build();
}

double MusclePath::calcLength(const State& s) const {
    if (isStraight())
        return (elements_[1].body.getBodyTransform(s) * elements_[1].findLocation(s) -
                elements_[0].body.getBodyTransform(s) * elements_[0].findLocation(s)).norm();
    return calcGeometry(s).length;
}

double MusclePath::calcLengtheningSpeed(const State& s, const PathGeometry& g) const {
    // The power of a unit tension is -dP/dt: sum over its loads of force . (point velocity).
    double power = 0;
    for (const PathLoad& l : g.loads) {
        const SpatialVec V = elements_[l.element].body.getBodyVelocity(s);
        power += dot(l.force, V[1] + cross(V[0], l.arm)) + dot(l.moment, V[0]);
    }
    for (const PathMobilityLoad& m : g.mobilityLoads) power += m.force * s.getU()[m.u];
    return -power;
}

void MusclePath::applyTension(const PathGeometry& g, double tension, Vector_<SpatialVec>& bodyForces,
                              Vector& mobilityForces) {
    for (const PathLoad& l : g.loads) {
        const Vec3 f = tension * l.force;
        bodyForces[l.body] += SpatialVec(l.arm % f + tension * l.moment, f);
    }
    for (const PathMobilityLoad& m : g.mobilityLoads) mobilityForces[m.u] += tension * m.force;
}

Vector calcPathGeneralizedForces(const SimbodyMatterSubsystem& matter, const State& s, const PathGeometry& g) {
    Vector_<SpatialVec> bodyForces(matter.getNumBodies(), SpatialVec(Vec3(0), Vec3(0)));
    Vector mobilityForces(s.getNU(), 0.0), f;
    MusclePath::applyTension(g, 1.0, bodyForces, mobilityForces);
    matter.multiplyBySystemJacobianTranspose(s, bodyForces, f);
    return f + mobilityForces;
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
            if (e.isMoving()) continue;  // drawn where the line bends (its location needs the state)
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
        } else if (e.kind == PathElement::Kind::Ellipsoid) {
            geometry.push_back(DecorativeEllipsoid(e.radii).setBodyId(body).setTransform(Transform(e.orientation, e.location))
                                   .setColor(surfaceColor).setOpacity(opacity));
        } else {
            geometry.push_back(DecorativeSphere(e.radius).setBodyId(body).setTransform(Transform(e.location))
                                   .setColor(surfaceColor).setOpacity(opacity));
        }
    }
}

}  // namespace armsim
