// An isometric trial of an OpenSim model (model/osim_arm.h): one coordinate locked at a value, the
// others at their defaults (locked too, as a dynamometer holds the limb), the muscles that move the
// coordinate one way excited to a target after a rest, and the torque they put on it recorded, raw and
// tared at rest as a dynamometer reads it; and a free movement of one coordinate with the others held.
// `armsim trial --model FILE.osim` and Python's `armsim.isometric_trial` run them.
//
// With every coordinate locked the paths are fixed, so each muscle's states evolve alone at its path
// length (numerics/stiff_ode.h OdeBlocks, a band Newton matrix: cost linear in the muscles), and the
// torque is sum_i r_i F_i with r_i the moment arm by virtual work (OsimArm::calcMomentArm). The tests
// check this against the whole Simbody System integrated with the coordinates locked, and the end of a
// long hold against the steady isometric solve `model show` uses.
#pragma once

#include "basics/numbers.h"

#include "basics/table.h"
#include "model/osim_file.h"
#include "muscles/activation.h"
#include "numerics/stiff_ode.h"

#include <functional>
#include <string>
#include <vector>

namespace armsim {

class OsimArm;

/// What an osim isometric trial does.
struct OsimIsometricTrialSettings {
    std::string coordinate;        ///< the locked coordinate the effort acts about; "" = the model's only one
    double angleDeg = 90;          ///< its value [deg] (OpenSim's convention: arm26's r_elbow_flex 0 = straight)
    /// The effort's direction: +1 the coordinate's positive direction (arm26's elbow: flexion), -1 negative.
    int direction = 1;
    double activation = 1.0;            ///< excitation of the agonists during the hold [1]
    double antagonistActivation = 0.0;  ///< excitation of the other muscles during the hold [1]
    double restDuration = 0.5;     ///< muscles at rest, the torque tared at its start [s]
    double riseTime = 0.0;         ///< ramp from 0 to the target; 0 = step [s]
    double holdDuration = 3.0;     ///< time at the target [s]
    double sampleRate = 1000.0;    ///< output rate [Hz]
    double averagingWindow = 1.0;  ///< end of the hold averaged for the summary [s]
    std::string muscleModel;       ///< "" = each muscle's type in the file (model/osim_arm.h)
    IntegrationSettings integration;

    double getDuration() const { return restDuration + riseTime + holdDuration; }
    /// Throws InputError naming the field (its CLI option in runNamingOptions) for a bad value, an
    /// angle outside the coordinate's range, a coordinate that is not there, or a model without muscles.
    void validate(const OsimArm& arm) const;
};

/// Smallest moment arm that makes a muscle an agonist [m]: a muscle that does not cross the coordinate
/// has a moment arm of rounding size (1e-17 m), not zero.
inline constexpr double kOsimAgonistMomentArm = 1e-4;
/// true when a muscle with moment arm r [m] about the coordinate is an agonist of an effort in
/// `direction` (+1/-1): it pulls that way by more than kOsimAgonistMomentArm. `model show`'s MVC curves
/// use the same rule.
inline bool isOsimAgonist(int direction, double momentArm) { return direction * momentArm > kOsimAgonistMomentArm; }

/// Summary of an osim isometric trial (window means over the last averagingWindow of the hold).
struct OsimIsometricSummary {
    std::string coordinate;              ///< the locked coordinate
    double angleDeg = 0;                 ///< its value [deg]
    std::vector<std::string> muscles;    ///< names, file order
    std::vector<bool> agonists;          ///< per muscle
    std::vector<double> pathLengths;     ///< per muscle [m]
    std::vector<double> momentArms;      ///< per muscle about the coordinate [m] (+ = its positive direction)
    std::vector<double> meanForces;      ///< per muscle, window mean [N]
    double restTorque = 0;               ///< muscle torque at the first sample (passive), the tare [N m]
    double meanMuscleTorque = 0;         ///< sum_i r_i F_i, window mean [N m]
    double meanTaredTorque = 0;          ///< meanMuscleTorque - restTorque [N m]
    IntegrationStats stats;
};

struct OsimIsometricTrialResult {
    /// Columns: time_s, excitation (of the agonists), <coordinate>_deg, muscle_torque_Nm (sum_i r_i F_i,
    /// + = the coordinate's positive direction), tared_torque_Nm (less its value at the first sample),
    /// then per muscle force_<m>_N, torque_<m>_Nm, excitation_<m>, activation_<m> (the model's active
    /// fraction) and fiber_length_<m>_m.
    Table series;
    OsimIsometricSummary summary;
};

/// Runs the trial (its own Simbody System). muscleModel as OsimArm's. Throws InputError for bad
/// settings, SimulationError when the integration fails.
OsimIsometricTrialResult runOsimIsometricTrial(const OsimModel& model, const OsimIsometricTrialSettings& settings);

/// A free movement of an OpenSim model: one coordinate free from initialAngleDeg, the others held at
/// their defaults, the muscles that pull it the `direction` way (at the start pose) excited from
/// `onset` (a step, or a ramp over `rise`), the others at rest; from every muscle in equilibrium at
/// the start. OpenSim's ranges are not forces (its forward dynamics ignore them too): the coordinate
/// may leave its range.
struct OsimFreeMovementSettings {
    std::string coordinate;        ///< the free coordinate; "" = the model's only one
    double initialAngleDeg = kNaN; ///< its value at t = 0 [deg]; NaN: its default
    double initialVelocityDegps = 0;  ///< [deg/s]
    int direction = 1;             ///< +1: the agonists pull the positive way, -1 the negative
    double activation = 0.5;       ///< the agonists' excitation after the onset [1]
    double onset = 0.2;            ///< [s]
    double rise = 0.0;             ///< ramp time from 0; 0 = a step [s]
    double duration = 2.0;         ///< [s]
    double sampleRate = 200.0;     ///< [Hz]
    std::string muscleModel;       ///< "" = each muscle's type in the file
    /// CPodes; accuracy 1e-5 as OpenSim's Forward tool.
    IntegrationSettings integration = [] {
        IntegrationSettings i;
        i.accuracy = 1e-5;
        return i;
    }();
    /// Optional: called with the time of every sample [s] (a long run's progress).
    std::function<void(double)> progress;
    /// InputError naming the field for a bad value, a start outside the coordinate's range, a
    /// coordinate that is not there or that the file locks, or a model without muscles.
    void validate(const OsimArm& arm) const;
};

/// Columns: time_s, excitation (of the agonists), <coordinate>_deg, <coordinate>_speed_degps, then per
/// muscle force_<m>_N, activation_<m>, fiber_length_<m>_m. stats: what the integration cost.
Table runOsimFreeMovement(const OsimModel& model, const OsimFreeMovementSettings& settings,
                          IntegrationStats* stats = nullptr);

}  // namespace armsim
