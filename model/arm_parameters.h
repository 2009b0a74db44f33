// Parameters of the two-segment Simbody arm: anthropometry, biceps path geometry, force transducer,
// elbow range and joint stops. Framework-free.
//
// Sources:
//  - Segment masses, centres of mass and radii of gyration: Winter DA (2009) "Biomechanics and Motor
//    Control of Human Movement", 4th ed., Table 4.1 (Dempster's cadaver data). The forearm and hand
//    are one rigid body here, Winter's "forearm and hand" segment (elbow axis to ulnar styloid).
//  - Segment lengths: fractions of body height from Winter (2009) Fig. 4.1 (Drillis & Contini 1966):
//    upper arm 0.186 H, forearm 0.146 H, hand 0.108 H.
//  - Default body mass and height: the male sample of Zatsiorsky et al. as reported by de Leva P
//    (1996) J Biomech 29:1223-1230 (73.0 kg, 1.741 m).
//  - Biceps origin/insertion distances A, B, the d1/d2 = 6 strap ratio, the 50 kg transducer and the
//    40..180 deg elbow range: the thesis, sections 5.2.1, 5.2.2, 5.3.2 and 6.1.2.
#pragma once

#include <array>
#include <string>

namespace armsim {

/// Everything that defines the arm. Plain data in SI units (angles in degrees: they are user-facing);
/// segment masses follow from bodyMass through the mass fractions. Call validate() after editing.
struct ArmParameters {
    // Body.
    double bodyMass = 73.0;     ///< [kg] total body mass; de Leva 1996 male reference sample
    double bodyHeight = 1.741;  ///< [m] stature; de Leva 1996 male reference sample

    // Upper arm (welded to ground; only its geometry matters for the dynamics).
    double upperArmLength = 0.186 * 1.741;  ///< [m] shoulder to elbow joint centre; 0.186 H, Winter 2009 Fig. 4.1
    double upperArmMassFraction = 0.028;    ///< [1] of body mass; Winter 2009 Table 4.1
    double upperArmComFraction = 0.436;     ///< [1] of upperArmLength, from the shoulder; Winter 2009 Table 4.1
    double upperArmGyrationFraction = 0.322;  ///< [1] radius of gyration about the COM / upperArmLength; Winter 2009 Table 4.1

    // Forearm + hand (one body on the elbow pin).
    double forearmLength = 0.146 * 1.741;     ///< [m] elbow axis to ulnar styloid; 0.146 H, Winter 2009 Fig. 4.1
    double handLength = 0.108 * 1.741;        ///< [m] wrist to fingertip; 0.108 H, Winter 2009 Fig. 4.1
    double forearmHandMassFraction = 0.022;   ///< [1] of body mass; Winter 2009 Table 4.1 "forearm and hand"
    double forearmHandComFraction = 0.682;    ///< [1] of forearmLength, from the elbow; Winter 2009 Table 4.1
    double forearmHandGyrationFraction = 0.468;  ///< [1] radius of gyration about the COM / forearmLength; Winter 2009 Table 4.1
    /// [1] hand COM from the elbow / forearmLength, where a load held in the hand sits; derived from
    /// Winter 2009 Table 4.1: (0.022*0.682 - 0.016*0.430) / 0.006 = 1.354.
    double handComFraction = 1.354;

    // Biceps path (straight line, van Zuylen 1988; thesis 5.2.2, 6.1.2).
    double originDistance = 0.37;     ///< [m] A: elbow centre to biceps origin along the upper arm; thesis 6.1.2
    double insertionDistance = 0.06;  ///< [m] B: elbow centre to biceps insertion along the forearm; thesis 6.1.2

    // Force transducer on a strap (thesis 5.2.1, 5.3.2).
    double strapDistance = 6 * 0.06;  ///< [m] d1: elbow centre to strap along the forearm; thesis d1/d2 = 6 with d2 = B
    double transducerRange = 50 * 9.80665;  ///< [N] full scale of the transducer, 50 kg-force; thesis 5.3.2

    // Elbow range and its soft stops.
    double minElbowAngleDeg = 40;    ///< [deg] most flexed included angle; thesis Fig. 5.1 (40..180 deg)
    double maxElbowAngleDeg = 180;   ///< [deg] most extended included angle (180 = straight); thesis Fig. 5.1
    double stopStiffness = 2000;     ///< [N m/rad] joint-stop stiffness; model choice (the forearm's weight sags 0.08 deg into the extension stop)
    double stopDissipation = 0.1;    ///< [s/rad] Hunt-Crossley stop dissipation (0 = elastic); model choice

    /// Forearm rotation (pronation-supination): the radius, carrying the hand, turns on a pin about an
    /// axis fixed in the forearm (ulna) frame. Off unless the arm has a `forearm_rotation` section; the
    /// angle is locked at the posture in every trial (an isometric transducer holds the hand).
    struct ForearmRotation {
        bool enabled = false;
        std::array<double, 3> axisPoint{0, 0, 0};      ///< [m] a point of the axis in the forearm frame (the radial head)
        std::array<double, 3> axisDirection{0, -1, 0}; ///< [1] positive rotation about it (right-hand rule) is supination
        double minDeg = -90;      ///< [deg] most pronated; 0 = neutral (thumb up at 90 deg flexion)
        double maxDeg = 90;       ///< [deg] most supinated
        double postureDeg = 0;    ///< [deg] the posture trials hold
        double massFraction = 0.1;  ///< [1] of the forearm + hand mass carried by the radius body (model choice; no trial moves it)
    } forearmRotation;

    double gravity = 9.80665;  ///< [m/s^2] magnitude of gravity, along -Y; standard gravity
    double handLoad = 0;       ///< [kg] point mass held in the hand, at the hand COM; 0 = none

    /// The elbow's range as flexion angles (0 = straight) [deg].
    double getMinFlexionDeg() const { return 180.0 - maxElbowAngleDeg; }
    double getMaxFlexionDeg() const { return 180.0 - minElbowAngleDeg; }
    /// Mass of the forearm + hand body without handLoad [kg].
    double calcForearmHandMass() const { return forearmHandMassFraction * bodyMass; }
    /// Mass of the upper arm [kg].
    double calcUpperArmMass() const { return upperArmMassFraction * bodyMass; }
    /// Distance from the elbow to the forearm + hand COM [m].
    double calcForearmHandComDistance() const { return forearmHandComFraction * forearmLength; }
    /// Distance from the elbow to the hand COM (where handLoad sits) [m].
    double calcHandComDistance() const { return handComFraction * forearmLength; }

    /// Throws FieldError naming the field (its YAML path, e.g. "biceps.origin_distance"), the value and
    /// the violated bound for the first invalid field.
    void validate() const;

    /// A copy for a subject of the given body mass [kg] and height [m]: masses follow through the
    /// fractions; every length (segments, A, B, d1) scales by bodyHeight / this->bodyHeight, so d1/B and
    /// the fractions are unchanged. Throws FieldError for a non-positive mass or height.
    ArmParameters scaled(double newBodyMass, double newBodyHeight) const;
};

/// Reads an arm file (e.g. assets/arm/default_male.yaml) strictly: every field is required, unknown
/// keys are errors, and every error names the file, line, field, value and expected bound.
ArmParameters loadArmParameters(const std::string& path);

class ParamNode;
/// Reads the arm sections of root (an arm file, or a model file's `arm` mapping) into p without
/// validating or finishing root. The `biceps` section is required when requireBiceps; returns whether
/// it was there.
bool readArmParameters(const ParamNode& root, ArmParameters& p, bool requireBiceps);

}  // namespace armsim
