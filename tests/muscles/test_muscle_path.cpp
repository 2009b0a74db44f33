// Wrapping over an ellipsoid (muscles/muscle_path.h): a round ellipsoid is the sphere, and the loads of
// a unit tension do the virtual work of the length (moment arm = -dP/dq, power = -dP/dt) with the
// surface on the moving body, where its force and couple matter.
#include "muscles/muscle_path.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace armsim;
using namespace SimTK;

namespace {

// Ground and one body on a pin about Ground's z through the origin; the path runs from a Ground point
// over a surface fixed on the body to a point on the body.
struct PinRig {
    MultibodySystem system;
    SimbodyMatterSubsystem matter{system};
    GeneralForceSubsystem forces{system};
    MobilizedBody::Pin body;
    State state;
    PinRig() {
        body = MobilizedBody::Pin(matter.Ground(), Transform(), MassProperties(1.0, Vec3(0), UnitInertia(0.01)),
                                  Transform());
        state = system.realizeTopology();
    }
    // Generalized force of a unit tension on the pin: the moment arm by virtual work.
    double calcMomentArm(const PathGeometry& g) {
        return calcPathGeneralizedForces(matter, state, g)[0];
    }
    void setAngle(double q) {
        body.setOneQ(state, 0, q);
        system.realize(state, Stage::Position);
    }
};

PathElement point(const MobilizedBody& b, const Vec3& at, const char* label) {
    PathElement e;
    e.body = b;
    e.location = at;
    e.label = label;
    return e;
}

PathElement ellipsoid(const MobilizedBody& b, const Vec3& centre, const Vec3& radii, const Rotation& R, const Vec3& side) {
    PathElement e;
    e.kind = PathElement::Kind::Ellipsoid;
    e.body = b;
    e.location = centre;
    e.radii = radii;
    e.orientation = R;
    e.side = side;
    e.label = "ellipsoid";
    return e;
}

}  // namespace

// With three equal semi-axes and any orientation the ellipsoid is the sphere of that radius: the same
// length (1e-12 m: the quadrature of a circle's arc is exact to rounding) and moment arm (1e-9 m).
TEST(EllipsoidWrap, ARoundEllipsoidIsTheSphere) {
    PinRig rig;
    const Rotation R(BodyRotationSequence, 0.3, XAxis, -0.7, YAxis, 1.1, ZAxis);
    const Vec3 origin(-0.05, 0.12, 0.01), centre(0.02, 0.0, 0.0), insertion(0.08, -0.1, -0.01);
    PathElement sphere = point(rig.body, centre, "sphere");
    sphere.kind = PathElement::Kind::Sphere;
    sphere.radius = 0.03;
    sphere.side = Vec3(-1, 0, 0);
    const MusclePath bySphere({point(rig.matter.Ground(), origin, "o"), sphere, point(rig.body, insertion, "i")});
    const MusclePath byEllipsoid({point(rig.matter.Ground(), origin, "o"),
                                  ellipsoid(rig.body, centre, Vec3(0.03), R, Vec3(-1, 0, 0)),
                                  point(rig.body, insertion, "i")});
    int wrapped = 0;
    for (double q = -0.5; q <= 1.5; q += 0.1) {
        rig.setAngle(q);
        const PathGeometry a = bySphere.calcGeometry(rig.state), b = byEllipsoid.calcGeometry(rig.state);
        EXPECT_NEAR(b.length, a.length, 1e-12) << q;
        EXPECT_EQ(a.wrapping[1], b.wrapping[1]) << q;
        EXPECT_NEAR(rig.calcMomentArm(b), rig.calcMomentArm(a), 1e-9) << q;
        wrapped += a.wrapping[1];
    }
    EXPECT_GE(wrapped, 5);  // the comparison saw the surface in use
}

// An elongated, tilted ellipsoid on the moving body, the path from Ground: the moment arm by virtual
// work equals -dP/dq by central differences (h = 1e-6 rad) to 1e-8 m, and the lengthening speed the
// derivative of the length to 1e-8 m/s, wherever the path wraps. Without the surface body's couple the
// moment arm is off by 0.2 mm and more (tried).
TEST(EllipsoidWrap, LoadsDoTheVirtualWorkOfTheLength) {
    PinRig rig;
    const Rotation R(BodyRotationSequence, 0.4, XAxis, 0.2, YAxis, -0.6, ZAxis);
    const MusclePath path({point(rig.matter.Ground(), Vec3(-0.06, 0.14, 0.02), "o"),
                           ellipsoid(rig.body, Vec3(0.03, 0.01, 0.0), Vec3(0.045, 0.02, 0.03), R, Vec3(-1, 0, 0)),
                           point(rig.body, Vec3(0.12, -0.06, -0.015), "i")});
    const double h = 1e-6, u = 0.8;
    int wrapped = 0;
    for (double q = -0.6; q <= 1.6; q += 0.05) {
        rig.setAngle(q + h);
        const double plus = path.calcLength(rig.state);
        rig.setAngle(q - h);
        const double minus = path.calcLength(rig.state);
        rig.setAngle(q);
        const PathGeometry g = path.calcGeometry(rig.state);
        if (!g.wrapping[1]) continue;
        ++wrapped;
        const double dPdq = (plus - minus) / (2 * h);
        EXPECT_NEAR(rig.calcMomentArm(g), -dPdq, 1e-8) << "q = " << q;
        rig.body.setOneU(rig.state, 0, u);
        rig.system.realize(rig.state, Stage::Velocity);
        EXPECT_NEAR(path.calcLengtheningSpeed(rig.state, g), dPdq * u, 1e-8) << "q = " << q;
        rig.body.setOneU(rig.state, 0, 0.0);
    }
    EXPECT_GE(wrapped, 10);
}

// The arc is the plane's: with semi-axes (2, 1, 1) and the points on the long axis's plane, the wrapped
// length equals tangent + elliptic arc + tangent computed by hand in 2D (a point at (0, 3), one at
// (0, -3) passing +x: tangents to the ellipse x^2/4 + y^2 = 1 from (0, +-3) touch at y = +-1/3).
TEST(EllipsoidWrap, PlanarLengthEqualsTheEllipseByHand) {
    PinRig rig;
    rig.setAngle(0);
    const MusclePath path({point(rig.matter.Ground(), Vec3(0, 3, 0), "o"),
                           ellipsoid(rig.matter.Ground(), Vec3(0), Vec3(2, 1, 1), Rotation(), Vec3(1, 0, 0)),
                           point(rig.matter.Ground(), Vec3(0, -3, 0), "i")});
    const PathGeometry g = path.calcGeometry(rig.state);
    ASSERT_TRUE(g.wrapping[1]);
    // Tangent point from (0, 3): y = 1/3, x = 2 sqrt(1 - 1/9); arc from th = asin(1/3) to -asin(1/3) on
    // x = 2 cos th, y = sin th, length by Simpson's rule on 20000 intervals.
    const double yt = 1.0 / 3, xt = 2 * std::sqrt(1 - yt * yt);
    const double tangent = std::hypot(xt, 3 - yt);
    const double th = std::asin(yt);
    const int n = 20000;
    double arc = 0;
    for (int k = 0; k <= n; ++k) {
        const double t = -th + 2 * th * k / n;
        const double w = (k == 0 || k == n) ? 1 : (k % 2 ? 4 : 2);
        arc += w * std::hypot(2 * std::sin(t), std::cos(t));
    }
    arc *= 2 * th / n / 3;
    EXPECT_NEAR(g.length, 2 * tangent + arc, 1e-10);
}

// Two surfaces on one segment (OpenSim's several wrap objects on a segment): a cylinder on Ground and an
// ellipsoid on the moving body, both in use over part of the motion. The chain's length is the
// settled path's; the loads (from its gradient) give -dP/dq to 1e-8 m and the lengthening speed dP/dt.
TEST(EllipsoidWrap, TwoSurfacesInARowDoTheVirtualWorkOfTheLength) {
    PinRig rig;
    PathElement cylinder = point(rig.matter.Ground(), Vec3(-0.02, 0.06, 0), "cylinder");
    cylinder.kind = PathElement::Kind::Cylinder;
    cylinder.axis = UnitVec3(0, 0, 1);
    cylinder.radius = 0.012;
    cylinder.side = Vec3(-1, 0, 0);
    const Rotation R(BodyRotationSequence, 0.4, XAxis, 0.2, YAxis, -0.6, ZAxis);
    const MusclePath path({point(rig.matter.Ground(), Vec3(0.0, 0.16, 0.01), "o"), cylinder,
                           ellipsoid(rig.body, Vec3(0.03, 0.01, 0.0), Vec3(0.045, 0.02, 0.03), R, Vec3(-1, 0, 0)),
                           point(rig.body, Vec3(0.12, -0.06, -0.015), "i")});
    const double h = 1e-6, u = 0.8;
    int both = 0;
    for (double q = -0.6; q <= 1.6; q += 0.05) {
        rig.setAngle(q + h);
        const double plus = path.calcLength(rig.state);
        rig.setAngle(q - h);
        const double minus = path.calcLength(rig.state);
        rig.setAngle(q);
        const PathGeometry g = path.calcGeometry(rig.state);
        both += g.wrapping[1] && g.wrapping[2];
        // Drawing the path (its polyline) gives the same path (it once wrapped again and could differ).
        const PathGeometry drawn = path.calcGeometry(rig.state, "", true);
        EXPECT_EQ(drawn.length, g.length) << "q = " << q;
        EXPECT_GE(drawn.polyline.size(), 2u);
        const double dPdq = (plus - minus) / (2 * h);
        EXPECT_NEAR(rig.calcMomentArm(g), -dPdq, 1e-8) << "q = " << q;
        rig.body.setOneU(rig.state, 0, u);
        rig.system.realize(rig.state, Stage::Velocity);
        EXPECT_NEAR(path.calcLengtheningSpeed(rig.state, g), dPdq * u, 1e-8) << "q = " << q;
        rig.body.setOneU(rig.state, 0, 0.0);
    }
    EXPECT_GE(both, 5);  // the chain case was exercised
}
