#include "model/arm_parameters.h"

#include "basics/param_node.h"

#include <cmath>

namespace armsim {

namespace {

// A person's size: the heaviest and tallest recorded people (about 635 kg, 2.72 m) inside, a typo's
// factor of 1000 outside.
constexpr Bound kBodyMass{0, 700, true, false, "kg, a person"};
constexpr Bound kBodyHeight{0, 3, true, false, "m, a person"};
constexpr Bound kSegmentLength{0, 1, true, false, "m, a human arm segment"};

}  // namespace

void ArmParameters::validate() const {
    const double reach = (forearmLength + handLength) / forearmLength;  // fingertip in forearm lengths
    checkField("body.mass", bodyMass, kBodyMass);
    checkField("body.height", bodyHeight, kBodyHeight);

    checkField("upper_arm.length", upperArmLength, kSegmentLength);
    // A segment of one arm: Winter 2009 Table 4.1 gives 0.028 (upper arm) and 0.022 (forearm + hand) of
    // the body's mass and radii of gyration of 0.32-0.47 segment lengths; the bounds leave room for any person.
    const Bound kSegmentMassFraction{0, 0.1, true, false, "of body mass"};
    const Bound kGyrationFraction{0, 1, true, false, "segment lengths"};
    checkField("upper_arm.mass_fraction", upperArmMassFraction, kSegmentMassFraction);
    checkField("upper_arm.com_fraction", upperArmComFraction, Bound::open(0, 1));
    checkField("upper_arm.gyration_fraction", upperArmGyrationFraction, kGyrationFraction);

    checkField("forearm_hand.forearm_length", forearmLength, kSegmentLength);
    checkField("forearm_hand.hand_length", handLength, kSegmentLength);
    checkField("forearm_hand.mass_fraction", forearmHandMassFraction, kSegmentMassFraction);
    checkField("forearm_hand.com_fraction", forearmHandComFraction,
               Bound{0, reach, true, false, "forearm lengths, elbow to fingertip"});
    checkField("forearm_hand.gyration_fraction", forearmHandGyrationFraction, kGyrationFraction);
    checkField("forearm_hand.hand_com_fraction", handComFraction,
               Bound{1, reach, false, false, "forearm lengths, wrist to fingertip"});

    checkField("biceps.insertion_distance", insertionDistance, Bound{0, forearmLength, true, false, "m"});
    // The origin lies on the upper arm or the shoulder girdle above it (the thesis's A = 0.37 m for a
    // 0.32 m upper arm): twice the upper arm's length bounds it and keeps a value in mm out.
    checkField("biceps.origin_distance", originDistance,
               Bound{insertionDistance, 2 * upperArmLength, true, false, "m, above insertion_distance and within twice upper_arm.length"});

    checkField("transducer.strap_distance", strapDistance,
               Bound{0, forearmLength + handLength, true, false, "m, on the forearm or hand"});
    checkField("transducer.range", transducerRange, Bound{0, 1e5, true, false, "N"});

    checkField("elbow.min_angle_deg", minElbowAngleDeg, Bound::open(0, 180, "deg"));
    checkDegreesNotRadians("elbow.min_angle_deg", {minElbowAngleDeg, maxElbowAngleDeg});
    checkField("elbow.max_angle_deg", maxElbowAngleDeg,
               Bound{minElbowAngleDeg, 180, true, false, "deg, above min_angle_deg"});
    checkField("elbow.stop_stiffness", stopStiffness, Bound{0, 1e6, true, false, "N m/rad"});
    checkField("elbow.stop_dissipation", stopDissipation, Bound::closed(0, 100, "s/rad"));

    if (forearmRotation.enabled) {
        const ForearmRotation& r = forearmRotation;
        checkField("forearm_rotation.min_deg", r.minDeg, Bound::closed(-120, 0, "deg"));
        checkField("forearm_rotation.max_deg", r.maxDeg, Bound::closed(0, 120, "deg"));
        checkField("forearm_rotation.posture_deg", r.postureDeg, Bound::closed(r.minDeg, r.maxDeg, "deg"));
        checkDegreesNotRadians("forearm_rotation.min_deg", {r.minDeg, r.maxDeg, r.postureDeg});
        checkField("forearm_rotation.mass_fraction", r.massFraction, Bound{0, 1, true, true, "of the forearm + hand mass"});
        const auto& d = r.axisDirection;
        checkField("forearm_rotation.axis_direction (length)", std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]),
                   Bound{0, 1e3, true, false, "a direction"});
        for (double c : r.axisPoint) checkField("forearm_rotation.axis_point", c, Bound::closed(-1, 1, "m"));
    }
    checkField("gravity", gravity, Bound::closed(0, 100, "m/s^2; Earth 9.81, 0 for none"));
    checkField("hand_load", handLoad, bounds::kHandLoad);   // as a trial's hand_load
}

ArmParameters ArmParameters::scaled(double newBodyMass, double newBodyHeight) const {
    checkField("body.mass", newBodyMass, kBodyMass);
    checkField("body.height", newBodyHeight, kBodyHeight);
    ArmParameters p = *this;
    const double s = newBodyHeight / bodyHeight;
    p.bodyMass = newBodyMass;
    p.bodyHeight = newBodyHeight;
    p.upperArmLength *= s;
    p.forearmLength *= s;
    p.handLength *= s;
    p.originDistance *= s;
    p.insertionDistance *= s;
    p.strapDistance *= s;
    for (double& c : p.forearmRotation.axisPoint) c *= s;
    return p;
}

ArmParameters loadArmParameters(const std::string& path) {
    const ParamNode root = ParamNode::loadFile(path);
    root.getString("source", "");
    ArmParameters p;
    readArmParameters(root, p, true);
    root.finish();
    root.rethrowWithLocation([&] { p.validate(); });
    return p;
}

bool readArmParameters(const ParamNode& root, ArmParameters& p, bool requireBiceps) {
    const Bound any = Bound::any();

    const ParamNode body = root.child("body");
    p.bodyMass = body.getNumber("mass", any);
    p.bodyHeight = body.getNumber("height", any);
    body.finish();

    const ParamNode upper = root.child("upper_arm");
    p.upperArmLength = upper.getNumber("length", any);
    p.upperArmMassFraction = upper.getNumber("mass_fraction", any);
    p.upperArmComFraction = upper.getNumber("com_fraction", any);
    p.upperArmGyrationFraction = upper.getNumber("gyration_fraction", any);
    upper.finish();

    const ParamNode fore = root.child("forearm_hand");
    p.forearmLength = fore.getNumber("forearm_length", any);
    p.handLength = fore.getNumber("hand_length", any);
    p.forearmHandMassFraction = fore.getNumber("mass_fraction", any);
    p.forearmHandComFraction = fore.getNumber("com_fraction", any);
    p.forearmHandGyrationFraction = fore.getNumber("gyration_fraction", any);
    p.handComFraction = fore.getNumber("hand_com_fraction", any);
    fore.finish();

    const bool hasBiceps = requireBiceps || root.has("biceps");
    if (hasBiceps) {
        const ParamNode biceps = root.child("biceps");
        p.originDistance = biceps.getNumber("origin_distance", any);
        p.insertionDistance = biceps.getNumber("insertion_distance", any);
        biceps.finish();
    }

    const ParamNode transducer = root.child("transducer");
    p.strapDistance = transducer.getNumber("strap_distance", any);
    p.transducerRange = transducer.getNumber("range", any);
    transducer.finish();

    const ParamNode elbow = root.child("elbow");
    p.minElbowAngleDeg = elbow.getNumber("min_angle_deg", any);
    p.maxElbowAngleDeg = elbow.getNumber("max_angle_deg", any);
    p.stopStiffness = elbow.getNumber("stop_stiffness", any);
    p.stopDissipation = elbow.getNumber("stop_dissipation", any);
    elbow.finish();

    if (root.has("forearm_rotation")) {
        const ParamNode r = root.child("forearm_rotation");
        ArmParameters::ForearmRotation& f = p.forearmRotation;
        f.enabled = true;
        auto vec3 = [&](const char* key) {
            const std::vector<double> v = r.getNumbers(key, any);
            if (v.size() != 3)
                throw InputError(r.where(key) + ": field " + describeField(r.path(key)) + " has " + std::to_string(v.size()) +
                                 " numbers: expected 3 (x, y, z in the forearm frame)");
            return std::array<double, 3>{v[0], v[1], v[2]};
        };
        f.axisPoint = vec3("axis_point");
        f.axisDirection = vec3("axis_direction");
        f.minDeg = r.getNumber("min_deg", any, f.minDeg);
        f.maxDeg = r.getNumber("max_deg", any, f.maxDeg);
        f.postureDeg = r.getNumber("posture_deg", any, f.postureDeg);
        f.massFraction = r.getNumber("mass_fraction", any, f.massFraction);
        r.getString("source", "");
        r.finish();
    }
    p.gravity = root.getNumber("gravity", any);
    p.handLoad = root.getNumber("hand_load", any);
    return hasBiceps;
}

}  // namespace armsim
