// The MVC torque-angle curve of a model from the steady isometric state of every muscle (no time
// integration): what `armsim model show` plots and what the elbow calibration fits.
#pragma once

#include "basics/numbers.h"

#include "model/model_file.h"
#include "muscles/muscle_model.h"

#include <string>
#include <vector>

namespace armsim {

/// One muscle at one elbow angle during a steady maximal effort.
struct SteadyMusclePoint {
    double pathLength = 0;   ///< P [m]
    double momentArm = 0;    ///< h, + = flexes [m] (virtual work)
    double activation = 0;   ///< U [1]
    double fibreLength = 0;  ///< L / L0 at the steady state [1]
    double force = 0;        ///< tendon force Fse [N]
    double torque = 0;       ///< h Fse, + = flexion [N m]
    double forearmMomentArm = 0;  ///< about the forearm rotation axis, + = supinates [m] (0 without one)
    double forearmTorque = 0;     ///< forearmMomentArm Fse, + = supination [N m]
    /// How the steady state moves with its inputs (MuscleModel::calcSteadySensitivity); filled only
    /// when the curve is asked for it, else valid = false.
    SteadySensitivity sensitivity;
};

/// The steady MVC torque-angle curve of a model: rows = angles, columns = muscles.
struct SteadyMvcCurve {
    Effort effort = Effort::Flexion;
    std::vector<std::string> muscles;
    std::vector<double> flexionDeg;                       ///< 0 = full extension
    std::vector<std::vector<SteadyMusclePoint>> points;   ///< [angle][muscle]
    std::vector<double> totalTorque;                      ///< sum of muscle torques, + = flexion [N m]
    std::vector<double> totalForearmTorque;               ///< sum about the forearm axis, + = supination [N m]
    /// Share of the flexion torque of the flexors that muscle m gives at angle a [1].
    double calcFlexorShare(int a, int m) const;
};

/// Path length and moment arm of every muscle at each flexion angle: the part of the curve that muscle
/// parameters do not change, so fits that vary the parameters compute it once.
struct MvcGeometry {
    std::vector<double> flexionDeg;                     ///< 0 = full extension
    std::vector<std::vector<double>> pathLength;        ///< [angle][muscle] P [m]
    std::vector<std::vector<double>> momentArm;         ///< [angle][muscle] h, + = flexes [m] (virtual work)
    std::vector<std::vector<double>> forearmMomentArm;  ///< [angle][muscle] + = supinates [m]; 0 without a forearm rotation
    double rotationDeg = 0;                             ///< forearm posture [deg] (0 without a forearm rotation)
};

/// The geometry of `setup` at the flexion angles [deg], in forearm posture rotationDeg (NaN: the model's
/// posture; ignored without a forearm rotation). Throws InputError for an angle outside the elbow's or
/// the rotation's range.
MvcGeometry calcMvcGeometry(const ArmSetup& setup, const std::vector<double>& flexionDeg,
                            double rotationDeg = kNaN);

/// Scratch (data, not model) of the curve functions below for fits that call them many times: the
/// last steady state of every (angle, muscle) with what it was solved for. A call reuses a state when the
/// path length, the activation and the muscle's parameters other than F0's inputs are equal
/// (haveSameNormalizedStates), scaling it by the new F0: a fit's probe of one muscle's size or one
/// group's parameter solves only the muscles it moves. Results are bit-identical to a call without it.
/// One per curve (effort and activation pattern) and per thread.
class SteadyCurveCache {
public:
    /// Solves done and states reused since construction.
    long getNumSolved() const { return solved_; }
    long getNumReused() const { return reused_; }

private:
    friend struct SteadyCurveCacheAccess;
    struct Point {
        bool valid = false;
        double pathLength = 0, activation = 0, L = 0, normalizedForce = 0;
        bool haveSensitivity = false;
        SteadySensitivity sensitivity;
    };
    struct Muscle {
        bool valid = false;
        MuscleParameters params;     ///< what the points were solved with
        std::vector<Point> points;   ///< [angle]
    };
    std::vector<Muscle> muscles_;
    long solved_ = 0, reused_ = 0;
};

/// The curve of `muscles` (setup.muscles, or the same muscles with other parameters) on a geometry
/// computed for them; as calcSteadyMvcCurve below. A rotation effort's agonists are found per angle by
/// their forearm moment arm (isAgonistOf); without a forearm rotation it has none.
SteadyMvcCurve calcSteadyMvcCurve(const std::vector<MuscleSpec>& muscles, const MvcGeometry& geometry,
                                  Effort effort, const SubjectEffort& subject);
/// Which muscles are the effort's agonists at each angle of the geometry: [angle][muscle].
std::vector<std::vector<bool>> findAgonists(const std::vector<MuscleSpec>& muscles, const MvcGeometry& geometry,
                                            Effort effort);
/// The curve with the agonists given per angle (findAgonists, perhaps of another geometry: a fit that
/// scales the moment arms keeps its agonists).
/// `cache` (optional) holds this curve's earlier states (SteadyCurveCache); `sensitivities`: fill each
/// point's sensitivity (SteadyMusclePoint::sensitivity).
SteadyMvcCurve calcSteadyMvcCurve(const std::vector<MuscleSpec>& muscles, const MvcGeometry& geometry, Effort effort,
                                  const std::vector<std::vector<bool>>& agonists, const SubjectEffort& subject,
                                  SteadyCurveCache* cache = nullptr, bool sensitivities = false);
/// The same with the agonists of a muscle group: Flexor a flexion effort, Extensor an extension effort.
SteadyMvcCurve calcSteadyMvcCurve(const std::vector<MuscleSpec>& muscles, const MvcGeometry& geometry,
                                  MuscleGroup effort, const SubjectEffort& subject);
/// The effort that drives a group's muscles (Flexor: Flexion, Extensor: Extension; Forearm has none:
/// std::logic_error).
Effort getEffortOf(MuscleGroup group);

/// Every muscle of `setup` at its steady isometric state at each flexion angle [deg], the agonists of
/// `effort` at subject.voluntaryActivation and the others at subject.coContraction (both in [0, 1]; 0 and 0
/// give the passive torque). Net torque is the
/// muscles' alone (gravity tared, as the transducer protocol does). Throws InputError for an angle
/// outside the elbow's range and SimulationError (naming muscle and angle) when a muscle has no
/// equilibrium.
SteadyMvcCurve calcSteadyMvcCurve(const ArmSetup& setup, MuscleGroup effort, const SubjectEffort& subject,
                                  const std::vector<double>& flexionDeg);

/// The same for an effort (a rotation effort's agonists by their forearm moment arm) in forearm posture
/// rotationDeg (NaN: the model's).
SteadyMvcCurve calcSteadyMvcCurve(const ArmSetup& setup, Effort effort, const SubjectEffort& subject,
                                  const std::vector<double>& flexionDeg, double rotationDeg = kNaN);

}  // namespace armsim
