// ArmParameters: defaults, the YAML asset, validation messages and scaling.
#include "basics/errors.h"
#include "basics/files.h"
#include "model/arm_parameters.h"
#include "model/geometry.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

namespace armsim {
namespace {

const std::string kDefaultFile = std::string(ARMSIM_ASSET_DIR) + "/arm/default_male.yaml";
constexpr double kDecimalTol = 1e-12;  // a product like 0.186 * 1.741 vs its decimal in the file

std::string readText(const std::string& path) {
    std::ifstream in(path);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

// Writes text to a fresh file in the build tree and returns its path.
std::string writeTemp(const std::string& name, const std::string& text) {
    const std::string path = std::string(ARMSIM_BINARY_DIR) + "/test_model_tmp/" + name;
    writeFileAtomically(path, text);
    return path;
}

// The default file with the first occurrence of `from` replaced by `to`.
std::string editedDefault(const std::string& from, const std::string& to) {
    std::string text = readText(kDefaultFile);
    const auto at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return text.replace(at, from.size(), to);
}

// 1-based line of the first occurrence of needle in text.
int lineOf(const std::string& text, const std::string& needle) {
    const auto at = text.find(needle);
    EXPECT_NE(at, std::string::npos) << needle;
    return 1 + int(std::count(text.begin(), text.begin() + at, '\n'));
}

// "path:line:" of needle in the file's text.
std::string located(const std::string& path, const std::string& text, const std::string& needle) {
    return path + ":" + std::to_string(lineOf(text, needle)) + ":";
}

// The message of the InputError f throws ("" if none).
std::string errorOf(const std::function<void()>& f) {
    try {
        f();
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

TEST(ArmParameters, DefaultsValidateAndMatchTheTable) {
    const ArmParameters p;
    EXPECT_NO_THROW(p.validate());
    EXPECT_NEAR(p.calcForearmHandMass(), 0.022 * 73.0, kDecimalTol);
    EXPECT_NEAR(p.calcForearmHandComDistance(), 0.682 * 0.146 * 1.741, kDecimalTol);
    EXPECT_NEAR(p.strapDistance / p.insertionDistance, 6, kDecimalTol);
    EXPECT_NEAR(p.transducerRange, 490.3325, kDecimalTol);
    // The hand COM fraction is the one Winter's forearm, hand and forearm+hand rows imply.
    constexpr double kTableRounding = 1e-3;
    EXPECT_NEAR(p.handComFraction, (0.022 * 0.682 - 0.016 * 0.430) / 0.006, kTableRounding);
}

TEST(ArmParameters, DefaultFileEqualsStructDefaults) {
    const ArmParameters f = loadArmParameters(kDefaultFile), d;
    const std::pair<double ArmParameters::*, const char*> fields[] = {
        {&ArmParameters::bodyMass, "bodyMass"},
        {&ArmParameters::bodyHeight, "bodyHeight"},
        {&ArmParameters::upperArmLength, "upperArmLength"},
        {&ArmParameters::upperArmMassFraction, "upperArmMassFraction"},
        {&ArmParameters::upperArmComFraction, "upperArmComFraction"},
        {&ArmParameters::upperArmGyrationFraction, "upperArmGyrationFraction"},
        {&ArmParameters::forearmLength, "forearmLength"},
        {&ArmParameters::handLength, "handLength"},
        {&ArmParameters::forearmHandMassFraction, "forearmHandMassFraction"},
        {&ArmParameters::forearmHandComFraction, "forearmHandComFraction"},
        {&ArmParameters::forearmHandGyrationFraction, "forearmHandGyrationFraction"},
        {&ArmParameters::handComFraction, "handComFraction"},
        {&ArmParameters::originDistance, "originDistance"},
        {&ArmParameters::insertionDistance, "insertionDistance"},
        {&ArmParameters::strapDistance, "strapDistance"},
        {&ArmParameters::transducerRange, "transducerRange"},
        {&ArmParameters::minElbowAngleDeg, "minElbowAngleDeg"},
        {&ArmParameters::maxElbowAngleDeg, "maxElbowAngleDeg"},
        {&ArmParameters::stopStiffness, "stopStiffness"},
        {&ArmParameters::stopDissipation, "stopDissipation"},
        {&ArmParameters::gravity, "gravity"},
        {&ArmParameters::handLoad, "handLoad"},
    };
    for (const auto& [member, name] : fields) EXPECT_NEAR(f.*member, d.*member, kDecimalTol) << name;
}

TEST(ArmParameters, ValidationNamesFieldValueAndBound) {
    ArmParameters p;
    p.bodyMass = -70;
    std::string msg = errorOf([&] { p.validate(); });
    EXPECT_TRUE(contains(msg, "body.mass") && contains(msg, "-70") && contains(msg, "(0, 700] (kg, a person)")) << msg;

    p = ArmParameters();
    p.originDistance = 0.05;  // A < B
    msg = errorOf([&] { p.validate(); });
    EXPECT_TRUE(contains(msg, "biceps.origin_distance") && contains(msg, "0.05")) << msg;
    p.originDistance = p.insertionDistance;  // A == B: the path would vanish at full extension
    EXPECT_TRUE(contains(errorOf([&] { p.validate(); }), "biceps.origin_distance"));

    p = ArmParameters();
    p.minElbowAngleDeg = 0;
    msg = errorOf([&] { p.validate(); });
    EXPECT_TRUE(contains(msg, "elbow.min_angle_deg") && contains(msg, "(0, 180)")) << msg;
    p = ArmParameters();
    p.maxElbowAngleDeg = 181;
    msg = errorOf([&] { p.validate(); });
    EXPECT_TRUE(contains(msg, "elbow.max_angle_deg") && contains(msg, "181")) << msg;
    p = ArmParameters();
    p.maxElbowAngleDeg = 30;  // below min_angle_deg
    EXPECT_TRUE(contains(errorOf([&] { p.validate(); }), "elbow.max_angle_deg"));

    p = ArmParameters();
    p.strapDistance = 0.5;  // beyond the fingertips
    EXPECT_TRUE(contains(errorOf([&] { p.validate(); }), "transducer.strap_distance"));
    p = ArmParameters();
    p.stopDissipation = -1;
    EXPECT_TRUE(contains(errorOf([&] { p.validate(); }), "elbow.stop_dissipation"));
}

TEST(ArmParameters, FileErrorsNameFileLineAndField) {
    // Each case: a one-edit copy of the default file, and what the message must name.
    struct Case {
        const char* name;
        std::string text;
        const char* lineOf;  // the message must give this text's line ("" = no line check)
        std::vector<std::string> parts;
    };
    const Case cases[] = {
        {"unknown_key.yaml", editedDefault("  stop_stiffness:", "  colour: red\n  stop_stiffness:"),
         "colour:", {"unknown field", "elbow.colour"}},
        {"unknown_top.yaml", readText(kDefaultFile) + "gravty: 9.8\n", "gravty:", {"unknown field", "gravty"}},
        {"negative_mass.yaml", editedDefault("mass: 73.0", "mass: -73.0"), "mass: -73.0",
         {"body.mass", "-73", "(0, 700]"}},
        {"a_below_b.yaml", editedDefault("origin_distance: 0.37", "origin_distance: 0.04"),
         "origin_distance:", {"biceps.origin_distance", "0.04"}},
        {"range.yaml", editedDefault("max_angle_deg: 180", "max_angle_deg: 190"), "max_angle_deg:",
         {"elbow.max_angle_deg", "190"}},
        {"not_a_number.yaml", editedDefault("gravity: 9.80665", "gravity: strong"), "gravity:",
         {"gravity", "strong"}},
        {"missing.yaml", editedDefault("  hand_length: 0.188028", "  #"), "", {"forearm_hand.hand_length", "missing"}},
    };
    for (const Case& c : cases) {
        const std::string path = writeTemp(c.name, c.text);
        const std::string msg = errorOf([&] { loadArmParameters(path); });
        EXPECT_TRUE(contains(msg, path)) << c.name << ": " << msg;
        if (*c.lineOf) {
            EXPECT_TRUE(contains(msg, located(path, c.text, c.lineOf))) << c.name << ": " << msg;
        }
        for (const auto& part : c.parts) EXPECT_TRUE(contains(msg, part)) << c.name << ": " << msg;
    }
    EXPECT_TRUE(contains(errorOf([&] { loadArmParameters("no/such/arm.yaml"); }), "no/such/arm.yaml"));
}

TEST(ArmParameters, ScalingByBodyMassAndHeight) {
    const ArmParameters d;
    const ArmParameters p = d.scaled(90, 1.90);
    EXPECT_NO_THROW(p.validate());
    const double s = 1.90 / d.bodyHeight;
    EXPECT_NEAR(p.calcForearmHandMass(), 0.022 * 90, kDecimalTol);
    EXPECT_NEAR(p.calcUpperArmMass(), 0.028 * 90, kDecimalTol);
    EXPECT_NEAR(p.forearmLength, 0.146 * 1.90, kDecimalTol);  // still 0.146 H
    EXPECT_NEAR(p.upperArmLength, 0.186 * 1.90, kDecimalTol);
    EXPECT_NEAR(p.strapDistance / p.insertionDistance, 6, kDecimalTol);
    EXPECT_NEAR(calcBicepsPathLength(p.originDistance, p.insertionDistance, kPi / 2),
                s * calcBicepsPathLength(d.originDistance, d.insertionDistance, kPi / 2), kDecimalTol);
    EXPECT_TRUE(contains(errorOf([&] { d.scaled(-1, 1.8); }), "body.mass"));
    EXPECT_TRUE(contains(errorOf([&] { d.scaled(70, 0); }), "body.height"));
}

}  // namespace
}  // namespace armsim
