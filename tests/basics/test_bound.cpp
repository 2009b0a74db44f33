// The radians guard for angles meant in degrees (basics/bound.h; the bounds' own tests are in
// test_param_node.cpp).
#include "basics/bound.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

using namespace armsim;

namespace {

std::string errorOf(const std::vector<double>& degrees) {
    try {
        checkDegreesNotRadians("angles", degrees);
    } catch (const FieldError& e) {
        return e.what();
    }
    return "";
}

}  // namespace

// Radians typed where degrees are meant: every angle within pi and one not whole. Whole degrees near
// extension, and any set with an angle past pi, are degrees.
TEST(Bound, AnglesThatLookLikeRadiansAreRefusedWithTheirDegrees) {
    EXPECT_EQ(errorOf({30, 60, 90}), "");
    EXPECT_EQ(errorOf({0, 1, 2, 3}), "");          // whole degrees near full extension
    EXPECT_EQ(errorOf({2.5, 90}), "");             // an angle past pi: degrees
    EXPECT_EQ(errorOf({}), "");
    const std::string e = errorOf({0.5236, 1.0472, 1.5708});
    EXPECT_NE(e.find("angles"), std::string::npos) << e;
    EXPECT_NE(e.find("= 0.5236, 1.0472, 1.5708"), std::string::npos) << e;
    EXPECT_NE(e.find("expected degrees"), std::string::npos) << e;
    EXPECT_NE(e.find("(in degrees: 30, 60, 90)"), std::string::npos) << e;
    EXPECT_NE(errorOf({-1.5708, 0, 1.5708}), "");   // a forearm range in radians
    EXPECT_NE(errorOf({3.1416}), "");               // pi as typed to four places
}
