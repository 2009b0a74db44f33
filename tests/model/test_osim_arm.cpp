// .osim models built as Simbody systems (model/osim_arm.h): arm26 as shipped (opensim-models, CC BY 3.0)
// with its joints, gravity, wraps and Thelen muscles; its moment arms two ways; what is not supported yet
// named with its line.
#include "model/osim_arm.h"

#include "basics/files.h"

#include <gtest/gtest.h>

#include <cmath>
#include <regex>
#include <sstream>

using namespace armsim;

namespace {

const OsimModel& arm26() {
    static const OsimModel m = readOsimFile(std::string(ARMSIM_ASSET_DIR) + "/models/arm26.osim");
    return m;
}

constexpr double kDeg = 3.14159265358979323846 / 180;

}  // namespace

// Two coordinates (shoulder elevation, elbow flexion), six Thelen muscles whose F0 and optimal fibre
// length are the file's, and the system's mass the sum of the file's body masses.
TEST(OsimArm, Arm26BuildsWithItsCoordinatesMusclesAndMasses) {
    const OsimArm arm(arm26());
    ASSERT_EQ(arm.getNumCoordinates(), 2);
    EXPECT_EQ(arm.getCoordinate(0).name, "r_shoulder_elev");
    EXPECT_EQ(arm.getCoordinate(1).name, "r_elbow_flex");
    EXPECT_EQ(arm.findCoordinate("r_elbow_flex"), 1);
    EXPECT_EQ(arm.findCoordinate("nope"), -1);
    ASSERT_EQ(arm.getNumMuscles(), 6);
    for (int i = 0; i < arm.getNumMuscles(); ++i) {
        const OsimMuscle& mu = arm26().muscles[i];
        EXPECT_EQ(arm.getMuscleName(i), mu.name);
        EXPECT_EQ(arm.getMuscleForce(i).getMuscle().getF0(), mu.maxIsometricForce) << mu.name;
        EXPECT_EQ(arm.getMuscleForce(i).getMuscle().getOptimalFascicleLength(), mu.optimalFiberLength) << mu.name;
        EXPECT_STREQ(arm.getMuscleForce(i).getMuscle().getModelName(), "thelen2003");
    }
    // Total mass as the file's (base 0 kg, humerus, forearm-hand).
    SimTK::State s = arm.getDefaultState();
    arm.getSystem().realize(s, SimTK::Stage::Position);
    double mass = 0;
    for (const OsimBody& b : arm26().bodies) mass += b.mass;
    EXPECT_NEAR(arm.getMatter().calcSystemMass(s), mass, 1e-12);
}

// Moment arms by virtual work (the generalized force of a unit tension) equal -dP/dq by central
// differences (h = 1e-6 rad) to 0.01 mm (the tolerance), for every muscle about both
// coordinates, over the elbow's range 0-130 deg and shoulder elevation -30 to +90 deg. Wrapping is
// exercised: the triceps over the elbow cylinder and the biceps long head over the humeral-head
// ellipsoid both wrap somewhere on the grid.
TEST(OsimArm, Arm26MomentArmsEqualTheDerivativeOfThePathLength) {
    const OsimArm arm(arm26());
    SimTK::State s = arm.getDefaultState();
    const double h = 1e-6;
    double worst = 0;
    std::vector<int> wraps(arm.getNumMuscles(), 0);
    for (double shoulder = -30; shoulder <= 90; shoulder += 30)
        for (double elbow = 0; elbow <= 130; elbow += 10) {
            for (int j = 0; j < 2; ++j) {
                auto lengthAt = [&](double dq) {
                    arm.setCoordinateValue(s, 0, shoulder * kDeg + (j == 0 ? dq : 0));
                    arm.setCoordinateValue(s, 1, elbow * kDeg + (j == 1 ? dq : 0));
                    arm.getSystem().realize(s, SimTK::Stage::Position);
                    std::vector<double> P;
                    for (int i = 0; i < arm.getNumMuscles(); ++i) P.push_back(arm.calcPathLength(s, i));
                    return P;
                };
                const std::vector<double> plus = lengthAt(h), minus = lengthAt(-h);
                lengthAt(0);
                for (int i = 0; i < arm.getNumMuscles(); ++i) {
                    const double r = arm.calcMomentArm(s, i, j), fd = -(plus[i] - minus[i]) / (2 * h);
                    EXPECT_NEAR(r, fd, 1e-5) << arm.getMuscleName(i) << " about " << arm.getCoordinate(j).name
                                             << " at shoulder " << shoulder << ", elbow " << elbow;
                    worst = std::max(worst, std::abs(r - fd));
                    if (j == 0) {
                        const PathGeometry g = arm.getMuscleForce(i).calcPathGeometry(s);
                        for (bool w : g.wrapping) wraps[i] += w;
                    }
                }
            }
        }
    std::ostringstream text;
    text << worst;
    RecordProperty("worst_difference_m", text.str());
    for (int i = 0; i < arm.getNumMuscles(); ++i) RecordProperty("wraps_" + arm.getMuscleName(i), wraps[i]);
    EXPECT_GT(wraps[0], 0) << "TRIlong never wraps";
    EXPECT_GT(wraps[3], 0) << "BIClong never wraps";
}

// Elbow moment arms of arm26 at 90 deg against the values OpenSim gives for the same file, read from
// arm26's published moment-arm plots is not possible here; instead the biceps long head flexes and the
// triceps extends at every elbow angle, and the brachialis's arm stays in 5-25 mm (Murray et al. 2000:
// about 6-22 mm over the range).
TEST(OsimArm, Arm26MomentArmSigns) {
    const OsimArm arm(arm26());
    SimTK::State s = arm.getDefaultState();
    for (double elbow = 0; elbow <= 130; elbow += 10) {
        arm.setCoordinateValue(s, 1, elbow * kDeg);
        arm.getSystem().realize(s, SimTK::Stage::Position);
        EXPECT_GT(arm.calcMomentArm(s, 3, 1), 0) << "BIClong at " << elbow;
        EXPECT_LT(arm.calcMomentArm(s, 0, 1), 0) << "TRIlong at " << elbow;
        const double bra = arm.calcMomentArm(s, 5, 1);
        EXPECT_GT(bra, 0.005) << elbow;
        EXPECT_LT(bra, 0.025) << elbow;
    }
}

// What cannot be built yet is named with the file, the line and the element.
TEST(OsimArm, UnsupportedJointsAndPointsNameTheirLine) {
    const std::string text = readFileText(std::string(ARMSIM_ASSET_DIR) + "/models/arm26.osim");
    struct Case {
        std::string anchor, from, to, expected;
    };
    const std::vector<Case> cases = {
        // The shoulder's second rotation turned by a constant (a fixed tilt): a second moving axis.
        {"<TransformAxis name=\"rotation2\">", "<value>0</value>", "<value>0.3</value>",
         "more than one moving axis is not supported yet"},
        // The elbow's rotation scaled.
        {"<coordinates>r_elbow_flex</coordinates>", "<coefficients> 1 0</coefficients>",
         "<coefficients> 2 0</coefficients>", "scaled, offset or coupled axes are not supported yet"},
        // A muscle on a missing wrap object.
        {"<Thelen2003Muscle name=\"BIClong\">", "<wrap_object>BIClonghh</wrap_object>",
         "<wrap_object>nowhere</wrap_object>", "wrap object 'nowhere'"},
    };
    for (const Case& c : cases) {
        const std::size_t anchor = text.find(c.anchor);
        ASSERT_NE(anchor, std::string::npos) << c.anchor;
        const std::size_t at = text.find(c.from, anchor);
        ASSERT_NE(at, std::string::npos) << c.from;
        std::string changed = text;
        changed.replace(at, c.from.size(), c.to);
        try {
            OsimArm arm(readOsimText(changed, "changed.osim"));
            ADD_FAILURE() << "built: " << c.expected;
        } catch (const OsimError& e) {
            EXPECT_NE(std::string(e.what()).find(c.expected), std::string::npos) << e.what();
            EXPECT_TRUE(std::regex_search(std::string(e.what()), std::regex("changed\\.osim:[0-9]+: "))) << e.what();
        }
    }
}

namespace {

// arm26 with the brachialis inserting on a MovingPathPoint of the elbow: x a SimmSpline, y a
// NaturalCubicSpline, z a Constant; `yCoordinate` drives y and `zCoordinate` z ("": no socket).
std::string arm26WithMovingBrachialis(const std::string& yCoordinate = "/jointset/r_elbow/r_elbow_flex",
                                      const std::string& zCoordinate = "/jointset/r_elbow/r_elbow_flex") {
    std::string text = readFileText(std::string(ARMSIM_ASSET_DIR) + "/models/arm26.osim");
    const std::size_t begin = text.find("<PathPoint name=\"BRA-P2\">");
    const std::size_t end = text.find("</PathPoint>", begin) + std::string("</PathPoint>").size();
    const std::string moving =
        "<MovingPathPoint name=\"BRA-P2\">"
        "<socket_parent_frame>/bodyset/r_ulna_radius_hand</socket_parent_frame>"
        "<x_location><SimmSpline><x>0 0.6 1.2 1.8 2.4</x><y>-0.0032 0.002 0.006 0.004 -0.001</y></SimmSpline></x_location>"
        "<y_location><NaturalCubicSpline><x>0 1.2 2.4</x><y>-0.0239 -0.03 -0.026</y></NaturalCubicSpline></y_location>"
        "<z_location><Constant><value>0.0009</value></Constant></z_location>"
        "<socket_x_coordinate>/jointset/r_elbow/r_elbow_flex</socket_x_coordinate>"
        "<socket_y_coordinate>" + yCoordinate + "</socket_y_coordinate>" +
        (zCoordinate.empty() ? std::string() : "<socket_z_coordinate>" + zCoordinate + "</socket_z_coordinate>") +
        "</MovingPathPoint>";
    text.replace(begin, end - begin, moving);
    return text;
}

}  // namespace

// A MovingPathPoint (OpenSim's: location functions of one coordinate clamped to its range, and the
// generalized force f . dp/dq on that coordinate). Moment arms by virtual work, which now include that
// generalized force, equal -dP/dq by central differences (1e-9 m) over the elbow's range; the term
// itself is more than 1 mm somewhere, so leaving it out fails the test. The path's lengthening speed
// equals -r u, the point stays put beyond the coordinate's range, and the System's mobility forces
// (MuscleForce::calcForce) carry tension x the term.
TEST(OsimArm, MovingPathPointMomentArmsIncludeItsGeneralizedForce) {
    const OsimArm arm(readOsimText(arm26WithMovingBrachialis(), "moving.osim"));
    const int bra = 5, elbow = 1;
    ASSERT_EQ(arm.getMuscleName(bra), "BRA");
    SimTK::State s = arm.getDefaultState();
    const double h = 1e-6;
    double largestTerm = 0;
    for (double q = 5; q <= 125; q += 5) {   // inside the range: at its ends the location has a kink
        auto lengthAt = [&](double dq) {
            arm.setCoordinateValue(s, elbow, q * kDeg + dq);
            arm.getSystem().realize(s, SimTK::Stage::Position);
            return arm.calcPathLength(s, bra);
        };
        const double fd = -(lengthAt(h) - lengthAt(-h)) / (2 * h);
        lengthAt(0);
        EXPECT_NEAR(arm.calcMomentArm(s, bra, elbow), fd, 1e-9) << q;
        EXPECT_NEAR(arm.calcMomentArm(s, bra, 0), 0.0, 1e-9) << "about the shoulder at " << q;
        const PathGeometry g = arm.getMuscleForce(bra).calcPathGeometry(s);
        ASSERT_EQ(g.mobilityLoads.size(), 1u);
        largestTerm = std::max(largestTerm, std::abs(g.mobilityLoads[0].force));
        arm.setCoordinateSpeed(s, elbow, 0.7);
        arm.getSystem().realize(s, SimTK::Stage::Velocity);
        EXPECT_NEAR(arm.getMuscleForce(bra).getPath().calcLengtheningSpeed(s, g), -fd * 0.7, 1e-9) << q;
        arm.setCoordinateSpeed(s, elbow, 0);
    }
    EXPECT_GT(largestTerm, 1e-3);

    // Beyond the range (arm26: 0 to 130 deg) the point stays where the range ends.
    const SimTK::Vec3 top = [&] {
        arm.setCoordinateValue(s, elbow, arm.getCoordinate(elbow).range[1]);
        arm.getSystem().realize(s, SimTK::Stage::Position);
        return arm.getMuscleForce(bra).getPath().getElements()[1].findLocation(s);
    }();
    arm.setCoordinateValue(s, elbow, arm.getCoordinate(elbow).range[1] + 0.2);
    arm.getSystem().realize(s, SimTK::Stage::Position);
    EXPECT_EQ(arm.getMuscleForce(bra).getPath().getElements()[1].findLocation(s), top);
    EXPECT_TRUE(std::isfinite(arm.calcMomentArm(s, bra, elbow)));
    EXPECT_TRUE(arm.getMuscleForce(bra).calcPathGeometry(s).mobilityLoads[0].force == 0.0);

    // Through the System: at 60 deg with the muscles in their initial states, the elbow's mobility force
    // is the brachialis tension times the term (no other force applies mobility forces).
    arm.setCoordinateValue(s, elbow, 60 * kDeg);
    arm.getSystem().realize(s, SimTK::Stage::Position);
    for (int i = 0; i < arm.getNumMuscles(); ++i) {
        const MuscleForce& f = arm.getMuscleForce(i);
        f.setMuscleStates(s, f.getMuscle().calcInitialState(f.getPathLength(s)));
    }
    arm.getSystem().realize(s, SimTK::Stage::Dynamics);
    const double tension = arm.getMuscleForce(bra).getForce(s);
    EXPECT_GT(tension, 0);
    const double term = arm.getMuscleForce(bra).calcPathGeometry(s).mobilityLoads[0].force;
    const SimTK::Vector& mobility = arm.getSystem().getMobilityForces(s, SimTK::Stage::Dynamics);
    EXPECT_NEAR(mobility[arm.getCoordinateBody(elbow).getFirstUIndex(s)], tension * term, 1e-12 * tension);
}

// OpenSim 4 requires one coordinate for x, y and z (or none): two, or one left without, are named with
// the line.
TEST(OsimArm, MovingPathPointWithTwoCoordinatesIsRefused) {
    for (const auto& [y, z] : std::vector<std::pair<std::string, std::string>>{
             {"/jointset/r_shoulder/r_shoulder_elev", "/jointset/r_elbow/r_elbow_flex"}, {"/jointset/r_elbow/r_elbow_flex", ""}}) {
        try {
            OsimArm arm(readOsimText(arm26WithMovingBrachialis(y, z), "two.osim"));
            ADD_FAILURE() << "built with y " << y << ", z " << z;
        } catch (const OsimError& e) {
            EXPECT_NE(std::string(e.what()).find("expected one coordinate for x, y and z"), std::string::npos) << e.what();
            EXPECT_TRUE(std::regex_search(std::string(e.what()), std::regex("two\\.osim:[0-9]+: <MovingPathPoint name=\"BRA-P2\">"))) << e.what();
        }
    }
}
