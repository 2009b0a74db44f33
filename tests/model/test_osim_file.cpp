// Reading .osim files (issue 29): arm26 as shipped (opensim-models, CC BY 3.0) read completely, each
// muscle's numbers equal to the file's by a second reading (a plain text scan), the 3.3 layout read to
// the same data, and every kind of problem named with its file and line.
#include "basics/files.h"
#include "model/osim_file.h"

#include <gtest/gtest.h>

#include <regex>
#include <string>

using namespace armsim;

namespace {

const std::string& arm26Text() {
    static const std::string t = readFileText(std::string(ARMSIM_ASSET_DIR) + "/models/arm26.osim");
    return t;
}

std::string replaced(std::string s, const std::string& from, const std::string& to) {
    const auto at = s.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) s.replace(at, from.size(), to);
    return s;
}

std::string errorOf(const std::string& text) {
    try {
        readOsimText(text, "bad.osim");
    } catch (const OsimError& e) {
        return e.what();
    }
    return "";
}

int lineOf(const std::string& text, const std::string& what) {
    const auto at = text.find(what);
    return at == std::string::npos ? -1 : 1 + int(std::count(text.begin(), text.begin() + long(at), '\n'));
}

}  // namespace

TEST(OsimFile, Arm26IsReadWhole) {
    const OsimModel m = readOsimText(arm26Text(), "arm26.osim");
    EXPECT_EQ(m.version, 40000);
    EXPECT_EQ(m.name, "arm26");
    EXPECT_NE(m.credits.find("Creative Commons"), std::string::npos);
    ASSERT_EQ(m.bodies.size(), 3u);
    EXPECT_EQ(m.bodies[1].name, "r_humerus");
    EXPECT_DOUBLE_EQ(m.bodies[1].mass, 1.8645719999999999);
    EXPECT_DOUBLE_EQ(m.bodies[1].massCenter[1], -0.18049599999999999);
    ASSERT_EQ(m.joints.size(), 3u);
    EXPECT_EQ(m.joints[0].kind, OsimJoint::Kind::Weld);
    const OsimJoint& elbow = m.joints[2];
    EXPECT_EQ(elbow.name, "r_elbow");
    EXPECT_EQ(elbow.parent.body, "r_humerus");
    EXPECT_EQ(elbow.child.body, "r_ulna_radius_hand");
    ASSERT_EQ(elbow.coordinates.size(), 1u);
    EXPECT_EQ(elbow.coordinates[0].name, "r_elbow_flex");
    EXPECT_NEAR(elbow.coordinates[0].range[1], 2.2689280300000001, 1e-15);
    ASSERT_EQ(elbow.axes.size(), 6u);
    EXPECT_EQ(elbow.axes[0].coordinates, std::vector<std::string>{"r_elbow_flex"});
    EXPECT_EQ(elbow.axes[0].function.kind, OsimFunction::Kind::Linear);
    EXPECT_EQ(m.joints[1].parent.translation[2], 0.17000000000000001);  // base_offset of r_shoulder
    EXPECT_NE(m.findCoordinate("r_shoulder_elev"), nullptr);

    // Every muscle's numbers equal the file's, read a second way (a text scan of each muscle's block).
    ASSERT_EQ(m.muscles.size(), 6u);
    const std::regex block("<Thelen2003Muscle name=\"([A-Za-z]+)\">([\\s\\S]*?)</Thelen2003Muscle>");
    auto value = [](const std::string& b, const std::string& tag) {
        std::smatch v;
        EXPECT_TRUE(std::regex_search(b, v, std::regex("<" + tag + ">([^<]+)</" + tag + ">"))) << tag;
        return std::stod(v[1]);
    };
    int found = 0;
    for (auto it = std::sregex_iterator(arm26Text().begin(), arm26Text().end(), block); it != std::sregex_iterator(); ++it, ++found) {
        const std::string name = (*it)[1], body = (*it)[2];
        const auto mu = std::find_if(m.muscles.begin(), m.muscles.end(), [&](const OsimMuscle& x) { return x.name == name; });
        ASSERT_NE(mu, m.muscles.end()) << name;
        EXPECT_EQ(mu->type, "Thelen2003Muscle");
        EXPECT_EQ(mu->maxIsometricForce, value(body, "max_isometric_force")) << name;
        EXPECT_EQ(mu->optimalFiberLength, value(body, "optimal_fiber_length")) << name;
        EXPECT_EQ(mu->tendonSlackLength, value(body, "tendon_slack_length")) << name;
        EXPECT_EQ(mu->pennationAngleAtOptimal, value(body, "pennation_angle_at_optimal")) << name;
        EXPECT_EQ(mu->properties.at("FmaxTendonStrain"), value(body, "FmaxTendonStrain")) << name;
        EXPECT_EQ(mu->properties.at("Flen"), value(body, "Flen")) << name;
        static const std::regex pathPoint("<PathPoint ");
        const auto points = std::distance(std::sregex_iterator(body.begin(), body.end(), pathPoint), std::sregex_iterator());
        EXPECT_EQ(long(mu->path.size()), points) << name;
    }
    EXPECT_EQ(found, 6);
    const OsimMuscle& bic = *std::find_if(m.muscles.begin(), m.muscles.end(), [](const OsimMuscle& x) { return x.name == "BIClong"; });
    EXPECT_EQ(bic.path.front().body, "base");
    EXPECT_EQ(bic.path.back().body, "r_ulna_radius_hand");
    ASSERT_EQ(bic.wraps.size(), 1u);
    EXPECT_EQ(bic.wraps[0].wrapObject, "BIClonghh");
    EXPECT_EQ(bic.wraps[0].range, (std::array<int, 2>{2, 3}));
    const auto hh = std::find_if(m.wrapObjects.begin(), m.wrapObjects.end(), [](const OsimWrapObject& o) { return o.name == "BIClonghh"; });
    ASSERT_NE(hh, m.wrapObjects.end());
    EXPECT_EQ(hh->kind, OsimWrapObject::Kind::Ellipsoid);
    EXPECT_EQ(hh->body, "r_humerus");
    EXPECT_EQ(hh->quadrant, "-y");
}

// OpenSim 3.3 writes joints inside their child body, inertia as six elements and path points with
// <body>: the same arm reads to the same data.
TEST(OsimFile, Version30000LayoutReadsToTheSameData) {
    const std::string v3 = R"(<?xml version="1.0" encoding="UTF-8"?>
<OpenSimDocument Version="30000">
  <Model name="two">
    <gravity>0 -9.80665 0</gravity>
    <BodySet><objects>
      <Body name="ground"><mass>0</mass><mass_center>0 0 0</mass_center>
        <inertia_xx>0</inertia_xx><inertia_yy>0</inertia_yy><inertia_zz>0</inertia_zz>
        <inertia_xy>0</inertia_xy><inertia_xz>0</inertia_xz><inertia_yz>0</inertia_yz><Joint/></Body>
      <Body name="forearm"><mass>1.5</mass><mass_center>0 -0.18 0</mass_center>
        <inertia_xx>0.01</inertia_xx><inertia_yy>0.002</inertia_yy><inertia_zz>0.01</inertia_zz>
        <inertia_xy>0</inertia_xy><inertia_xz>0</inertia_xz><inertia_yz>0</inertia_yz>
        <Joint><CustomJoint name="elbow">
          <parent_body>ground</parent_body>
          <location_in_parent>0 -0.29 0</location_in_parent><orientation_in_parent>0 0 0</orientation_in_parent>
          <location>0 0 0</location><orientation>0 0 0</orientation>
          <CoordinateSet><objects><Coordinate name="flex"><default_value>0.5</default_value>
            <range>0 2.26</range><clamped>true</clamped><locked>false</locked></Coordinate></objects></CoordinateSet>
          <SpatialTransform>
            <TransformAxis name="rotation1"><function><LinearFunction><coefficients>1 0</coefficients></LinearFunction></function>
              <coordinates>flex</coordinates><axis>0 0 1</axis></TransformAxis>
          </SpatialTransform>
        </CustomJoint></Joint></Body>
    </objects></BodySet>
    <ForceSet><objects>
      <Thelen2003Muscle name="M"><GeometryPath><PathPointSet><objects>
          <PathPoint name="p1"><location>0 0.1 0</location><body>ground</body></PathPoint>
          <ConditionalPathPoint name="p2"><location>0.01 -0.28 0</location><body>ground</body>
            <coordinate>flex</coordinate><range>0 1</range></ConditionalPathPoint>
          <PathPoint name="p3"><location>0 -0.05 0</location><body>forearm</body></PathPoint>
        </objects></PathPointSet></GeometryPath>
        <max_isometric_force>600</max_isometric_force><optimal_fiber_length>0.12</optimal_fiber_length>
        <tendon_slack_length>0.2</tendon_slack_length><pennation_angle_at_optimal>0</pennation_angle_at_optimal>
        <FmaxTendonStrain>0.033</FmaxTendonStrain>
      </Thelen2003Muscle>
    </objects></ForceSet>
  </Model>
</OpenSimDocument>)";
    const OsimModel m = readOsimText(v3, "v3.osim");
    EXPECT_EQ(m.version, 30000);
    ASSERT_EQ(m.bodies.size(), 1u);  // ground is not a body
    EXPECT_EQ(m.bodies[0].inertia[1], 0.002);
    ASSERT_EQ(m.joints.size(), 1u);
    EXPECT_EQ(m.joints[0].parent.body, "ground");
    EXPECT_EQ(m.joints[0].child.body, "forearm");
    EXPECT_EQ(m.joints[0].parent.translation[1], -0.29);
    EXPECT_EQ(m.joints[0].coordinates[0].defaultValue, 0.5);
    EXPECT_TRUE(m.joints[0].coordinates[0].clamped);
    EXPECT_EQ(m.joints[0].axes[0].function.kind, OsimFunction::Kind::Linear);
    ASSERT_EQ(m.muscles.size(), 1u);
    ASSERT_EQ(m.muscles[0].path.size(), 3u);
    EXPECT_EQ(m.muscles[0].path[1].kind, OsimPathPoint::Kind::Conditional);
    EXPECT_EQ(m.muscles[0].path[1].coordinate, "flex");
    EXPECT_EQ(m.muscles[0].path[2].body, "forearm");
    EXPECT_EQ(m.muscles[0].properties.at("FmaxTendonStrain"), 0.033);
    // Without <range> a coordinate has OpenSim's default range (Coordinate.cpp: -10 .. 10).
    std::string noRange = v3;
    noRange.replace(noRange.find("<range>0 2.26</range>"), 21, "");
    EXPECT_EQ(readOsimText(noRange, "v3.osim").joints[0].coordinates[0].range, (std::array<double, 2>{-10, 10}));
}

// Issue 34: a model in other units reads as metres and newtons: a path point in mm gave a 896,380 N m
// peak, a wrap radius of 16 (mm) and F0 0.8 (kN) were accepted. Each is refused at its line.
TEST(OsimFile, LengthsAndForcesInOtherUnitsAreRefusedAtTheirLine) {
    const std::string& t = arm26Text();
    struct Case {
        std::string from, to, expected;
    } cases[] = {
        {"<location>-0.027140000000000001 -0.11441 -0.0066400000000000001</location>", "<location>-27.14 -114.41 -6.64</location>",
         "(-27.14, -114.41, -6.64) is 117.8 m from the body's origin: expected within 1 m (OpenSim lengths are in metres: is it in mm?)"},
        {"<radius>0.016</radius>", "<radius>16</radius>", "radius 16: expected at most 0.5 m (OpenSim lengths are in metres: is it in mm?)"},
        {"<dimensions>0.035000000000000003 0.02 0.02</dimensions>", "<dimensions>35 20 20</dimensions>", "dimensions 35: expected at most 0.5 m"},
        {"<translation>0.0028 -0.29189999999999999 -0.0068999999999999999</translation>", "<translation>2.8 -291.9 -6.9</translation>",
         "is 292 m from the body's origin: expected within 1 m"},
        {"<translation>0 0.80000000000000004 0</translation>", "<translation>0 800 0</translation>", "is 800 m from the body's origin: expected within 2 m"},
        {"<max_isometric_force>798.51999999999998</max_isometric_force>", "<max_isometric_force>0.79852</max_isometric_force>",
         "max_isometric_force 0.79852: expected at least 1 N (OpenSim forces are in newtons: is it in kN?)"},
    };
    for (const Case& c : cases) {
        const std::string bad = replaced(t, c.from, c.to);
        const std::string e = errorOf(bad);
        EXPECT_NE(e.find("bad.osim:" + std::to_string(lineOf(bad, c.to)) + ":"), std::string::npos) << c.to << "\n" << e;
        EXPECT_NE(e.find(c.expected), std::string::npos) << c.to << "\n" << e;
    }
    // The shipped arm's own values pass (every case above is one value changed).
    EXPECT_NO_THROW(readOsimText(t, "arm26.osim"));
}

TEST(OsimFile, ProblemsAreNamedWithFileLineAndElement) {
    const std::string& t = arm26Text();
    // Not XML.
    std::string e = errorOf(replaced(t, "<mass>0</mass>", "<mass>0</mas>"));
    EXPECT_NE(e.find("bad.osim:"), std::string::npos) << e;
    EXPECT_NE(e.find("not valid XML"), std::string::npos) << e;
    // A number that is not one.
    std::string bad = replaced(t, "<max_isometric_force>798.51999999999998</max_isometric_force>",
                               "<max_isometric_force>lots</max_isometric_force>");
    e = errorOf(bad);
    EXPECT_NE(e.find("bad.osim:" + std::to_string(lineOf(bad, "<max_isometric_force>lots"))), std::string::npos) << e;
    EXPECT_NE(e.find("'lots' is not a number"), std::string::npos) << e;
    // Another muscle model: refused (it would change results), naming it.
    bad = replaced(t, "<Thelen2003Muscle name=\"TRIlat\">", "<RigidTendonMuscle name=\"TRIlat\">");
    bad = replaced(bad, "</Thelen2003Muscle>\n\t\t\t\t<Thelen2003Muscle name=\"TRImed\">", "</RigidTendonMuscle>\n\t\t\t\t<Thelen2003Muscle name=\"TRImed\">");
    e = errorOf(bad);
    EXPECT_NE(e.find("<RigidTendonMuscle name=\"TRIlat\">"), std::string::npos) << e;
    EXPECT_NE(e.find("expected a Thelen2003Muscle"), std::string::npos) << e;
    EXPECT_NE(e.find("bad.osim:" + std::to_string(lineOf(bad, "<RigidTendonMuscle"))), std::string::npos) << e;
    // A wrap object that does not exist.
    bad = replaced(t, "<wrap_object>BIClonghh</wrap_object>", "<wrap_object>BIClong_head</wrap_object>");
    e = errorOf(bad);
    EXPECT_NE(e.find("wrap object 'BIClong_head' does not exist"), std::string::npos) << e;
    EXPECT_NE(e.find("bad.osim:" + std::to_string(lineOf(bad, "<wrap_object>BIClong_head"))), std::string::npos) << e;
    // A path point on a body that does not exist.
    bad = replaced(t, "<socket_parent_frame>/bodyset/r_ulna_radius_hand</socket_parent_frame>",
                   "<socket_parent_frame>/bodyset/r_ulna</socket_parent_frame>");
    e = errorOf(bad);
    EXPECT_NE(e.find("body 'r_ulna' does not exist"), std::string::npos) << e;
    // A property that would change results and is not modelled.
    bad = replaced(t, "<max_contraction_velocity>10</max_contraction_velocity>",
                   "<max_contraction_velocity>10</max_contraction_velocity><ignore_passive_fiber_force>true</ignore_passive_fiber_force>");
    e = errorOf(bad);
    EXPECT_NE(e.find("<ignore_passive_fiber_force>: true: not supported"), std::string::npos) << e;
    // An unsupported joint.
    bad = replaced(t, "<CustomJoint name=\"r_shoulder\">", "<BallJoint name=\"r_shoulder\">");
    bad = replaced(bad, "</CustomJoint>", "</BallJoint>");
    e = errorOf(bad);
    EXPECT_NE(e.find("joint type BallJoint is not supported"), std::string::npos) << e;
    // A name twice: everything else refers to muscles, coordinates and bodies by name.
    bad = replaced(t, "<Thelen2003Muscle name=\"BICshort\">", "<Thelen2003Muscle name=\"BIClong\">");
    e = errorOf(bad);
    const auto second = bad.rfind("<Thelen2003Muscle name=\"BIClong\">");
    const int secondLine = 1 + int(std::count(bad.begin(), bad.begin() + long(second), '\n'));
    EXPECT_NE(e.find("bad.osim:" + std::to_string(secondLine) + ": muscle 'BIClong' is named twice (first at line " +
                     std::to_string(lineOf(bad, "<Thelen2003Muscle name=\"BIClong\">")) + ")"),
              std::string::npos) << e;
    // Gravity beyond the arm files' bound.
    bad = replaced(t, "<gravity>0 -9.8065999999999995 0</gravity>", "<gravity>0 -1e9 0</gravity>");
    e = errorOf(bad);
    EXPECT_NE(e.find("<gravity>: magnitude 1e+09 m/s^2: expected at most 100 m/s^2"), std::string::npos) << e;
    // Not an OpenSim document at all.
    e = errorOf("<?xml version=\"1.0\"?><html/>");
    EXPECT_NE(e.find("expected an <OpenSimDocument>"), std::string::npos) << e;
}
