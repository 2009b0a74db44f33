#include "model/trial.h"

#include "model/geometry.h"
#include "model/parallel.h"
#include "muscles/param_file.h"

#include <cmath>

using namespace SimTK;

namespace armsim {

namespace {

void checkElbowAngle(const std::string& field, double theta, const ArmParameters& arm) {
    checkField(field, radToDeg(theta), Bound::closed(arm.minElbowAngleDeg, arm.maxElbowAngleDeg, "deg"));
}

std::vector<std::string> withStateColumns(std::vector<std::string> names, const VirtualMuscle& m) {
    for (const std::string& n : m.getStateNames()) names.push_back(kStateColumnPrefix + n);
    return names;
}

void appendMuscleStates(std::vector<double>& row, const VirtualMuscleForce& biceps, const State& s) {
    const std::vector<double> y = biceps.getMuscleStates(s);
    row.insert(row.end(), y.begin(), y.end());
}

double mean(const std::vector<double>& v, std::size_t from) {
    double s = 0;
    for (std::size_t i = from; i < v.size(); ++i) s += v[i];
    return v.size() > from ? s / double(v.size() - from) : NAN;
}

}  // namespace

void setStateFromTrialRow(const BicepsArm& model, const Table& table, int row, State& state) {
    const ArmModel& arm = model.getArm();
    state.setTime(table.get(row, "time_s"));
    arm.setElbowAngle(state, degToRad(table.get(row, "elbow_angle_deg")));
    arm.setElbowAngularVelocity(state, degToRad(table.get(row, "elbow_velocity_degps")));
    std::vector<double> y;
    for (const std::string& n : model.getMuscle().getStateNames()) {
        const std::string column = kStateColumnPrefix + n;
        if (!table.hasColumn(column))
            throw InputError("trial table has no column '" + column +
                             "': it was not written by armsim trial, or for another muscle composition");
        y.push_back(table.get(row, column));
    }
    model.getBiceps().setMuscleStates(state, y);
}

// ---- Isometric ----------------------------------------------------------------------------------

void IsometricTrialSettings::validate(const ArmParameters& arm) const {
    checkElbowAngle("elbow_angle_deg", elbowAngle, arm);
    checkField("activation", activation, Bound::closed(0, 1));
    checkField("rest", restDuration, Bound::positive("s"));
    checkField("rise", riseTime, Bound::nonNegative("s"));
    checkField("hold", holdDuration, Bound::positive("s"));
    checkField("sample_rate", sampleRate, Bound::positive("Hz"));
    checkField("averaging_window", averagingWindow, {0, holdDuration, true, false, "s, within the hold"});
    integration.validate();
}

ActivationProfile IsometricTrialSettings::calcActivationProfile() const {
    if (riseTime > 0) return ActivationProfile::ramp(restDuration, restDuration + riseTime, 0.0, activation);
    return ActivationProfile::step(restDuration, 0.0, activation);
}

IsometricTrialResult runIsometricTrial(const ArmSetup& setup, const IsometricTrialSettings& settings) {
    settings.validate(setup.arm);
    const ActivationProfile profile = settings.calcActivationProfile();
    const BicepsArm model(setup, profile);
    const ArmModel& arm = model.getArm();
    const VirtualMuscleForce& biceps = model.getBiceps();
    const MultibodySystem& system = model.getSystem();
    const ArmParameters& ap = setup.arm;

    State state = model.getDefaultState();
    arm.lockElbow(state, settings.elbowAngle);
    biceps.setSteadyMuscleStates(state);  // passive equilibrium at U(0) = 0
    system.realize(state, Stage::Acceleration);

    IsometricTrialResult result;
    IsometricSummary& sum = result.summary;
    sum.elbowAngle = settings.elbowAngle;
    sum.pathLength = arm.calcPathLength(state);
    sum.momentArm = arm.calcMomentArm(state);
    sum.tareTorque = arm.calcHoldingTorque(state);
    sum.restForce = biceps.getForce(state);

    result.series = Table(withStateColumns(
        {"time_s", "activation", "elbow_angle_deg", "elbow_velocity_degps", "muscle_force_N", "fascicle_length_m",
         "fascicle_velocity_mps", "holding_torque_Nm", "muscle_torque_Nm", "strap_force_N", "saturated",
         "force_moment_arm_N", "force_fixed_ratio_N", "error_moment_arm_pct", "error_fixed_ratio_pct"},
        model.getMuscle()));
    const double h = sum.momentArm;
    const VirtualMuscle& muscle = model.getMuscle();
    const double L0 = muscle.getParameters().optimalFascicleLength;

    // Holding torque measured (findMotionForces) at every step end; see realizeEverySample.
    struct StepTorque { double t, F, torque; };
    StepTorque prev{}, cur{};
    bool haveStep = false;
    auto onStep = [&](const State& s) {
        prev = cur;
        cur = {s.getTime(), biceps.getForce(s), arm.calcHoldingTorque(s)};
        if (!haveStep) prev = cur;
        haveStep = true;
    };
    auto torqueAt = [&](double t, double F) {
        const double dF = cur.F - prev.F;
        if (std::abs(dF) > 1e-9 * (1.0 + std::abs(cur.F))) return prev.torque + (F - prev.F) / dF * (cur.torque - prev.torque);
        const double dt = cur.t - prev.t;
        return dt > 0 ? prev.torque + (t - prev.t) / dt * (cur.torque - prev.torque) : cur.torque;
    };

    sum.stats = simulateSampled(
        system, state, settings.getDuration(), settings.sampleRate, profile.getBreakpoints(), settings.integration,
        [&](const State& s) {
            const double t = s.getTime();
            const std::vector<double> y = biceps.getMuscleStates(s);
            double F, torque;
            if (settings.realizeEverySample) {
                system.realize(s, Stage::Acceleration);
                F = biceps.getForce(s);
                torque = arm.calcHoldingTorque(s);
            } else {  // the path is fixed: the pure model gives Fse from the interpolated states
                F = muscle.calcForce(sum.pathLength, y.data());
                torque = torqueAt(t, F);
            }
            const double muscleTorque = sum.tareTorque - torque;  // tared, + = flexion
            double strap = muscleTorque / ap.strapDistance;          // perpendicular strap at d1
            const bool saturated = std::abs(strap) > ap.transducerRange;
            if (saturated) strap = std::copysign(ap.transducerRange, strap);
            sum.saturated = sum.saturated || saturated;
            const double byMomentArm = calcBicepsForceFromTorque(strap * ap.strapDistance, h);
            const double byFixedRatio = calcBicepsForceFixedRatio(strap, settings.elbowAngle, kPi / 2);
            auto pct = [F](double estimate) { return F > 0 ? 100 * (estimate - F) / F : NAN; };
            std::vector<double> row{t, profile.getValue(t), radToDeg(settings.elbowAngle), 0.0, F,
                                    y[VirtualMuscle::kL] * L0, y[VirtualMuscle::kV] * L0, torque, muscleTorque,
                                    strap, saturated ? 1.0 : 0.0, byMomentArm, byFixedRatio, pct(byMomentArm),
                                    pct(byFixedRatio)};
            row.insert(row.end(), y.begin(), y.end());
            result.series.appendRow(std::move(row));
        },
        [&](const State& s) { biceps.checkMuscleStates(s); }, onStep);

    const Table& t = result.series;
    const std::vector<double> time = t.getColumn("time_s");
    const double from = time.back() - settings.averagingWindow - 1e-9;
    std::size_t first = 0;
    while (first < time.size() && time[first] < from) ++first;
    sum.finalForce = t.get(t.getNumRows() - 1, "muscle_force_N");
    sum.meanForce = mean(t.getColumn("muscle_force_N"), first);
    sum.meanStrapForce = mean(t.getColumn("strap_force_N"), first);
    sum.meanForceMomentArm = mean(t.getColumn("force_moment_arm_N"), first);
    sum.meanForceFixedRatio = mean(t.getColumn("force_fixed_ratio_N"), first);
    return result;
}

std::vector<IsometricTrialResult> runIsometricTrials(const ArmSetup& setup,
                                                     const std::vector<IsometricTrialSettings>& settings, int jobs,
                                                     const std::function<void(int, int)>& progress) {
    for (const auto& s : settings) s.validate(setup.arm);  // fail before any work starts
    std::vector<IsometricTrialResult> results(settings.size());
    runParallel(int(settings.size()), jobs, [&](int i) { results[i] = runIsometricTrial(setup, settings[i]); },
                progress);
    return results;
}

// ---- Free movement ------------------------------------------------------------------------------

void FreeMovementSettings::validate(const ArmParameters& arm) const {
    checkElbowAngle("initial_angle_deg", initialAngle, arm);
    checkField("initial_velocity_degps", radToDeg(initialVelocity), Bound::closed(-2000, 2000, "deg/s"));
    checkField("duration", duration, Bound::positive("s"));
    checkField("hand_load", handLoad, Bound::closed(0, 50, "kg"));
    checkField("sample_rate", sampleRate, Bound::positive("Hz"));
    integration.validate();
}

Table runFreeMovement(const ArmSetup& setup, const FreeMovementSettings& settings, IntegrationStats* stats) {
    settings.validate(setup.arm);
    ArmSetup loaded = setup;
    loaded.arm.handLoad = settings.handLoad;
    const BicepsArm model(loaded, settings.activation);
    const ArmModel& arm = model.getArm();
    const VirtualMuscleForce& biceps = model.getBiceps();
    const MultibodySystem& system = model.getSystem();

    State state = model.getDefaultState();
    arm.setElbowAngle(state, settings.initialAngle);
    arm.setElbowAngularVelocity(state, settings.initialVelocity);
    if (settings.startSteady) biceps.setSteadyMuscleStates(state);
    else biceps.setInitialMuscleStates(state);

    Table t(withStateColumns({"time_s", "activation", "elbow_angle_deg", "elbow_velocity_degps", "path_length_m",
                              "moment_arm_m", "muscle_force_N", "fascicle_length_m", "fascicle_velocity_mps",
                              "active_fraction"},
                             model.getMuscle()));
    const IntegrationStats st = simulateSampled(
        system, state, settings.duration, settings.sampleRate, settings.activation.getBreakpoints(),
        settings.integration,
        [&](const State& s) {
            system.realize(s, Stage::Position);
            const MuscleOutputs o = biceps.calcOutputs(s);
            const double L0 = model.getMuscle().getParameters().optimalFascicleLength;
            std::vector<double> row{s.getTime(), biceps.getActivation(s), radToDeg(arm.getElbowAngle(s)),
                                    radToDeg(arm.getElbowAngularVelocity(s)), arm.calcPathLength(s),
                                    arm.calcMomentArm(s), o.Fse, o.L * L0, o.V * L0, o.activeFraction};
            appendMuscleStates(row, biceps, s);
            t.appendRow(std::move(row));
        },
        [&](const State& s) { biceps.checkMuscleStates(s); });
    if (stats) *stats = st;
    return t;
}

// ---- Settings files -----------------------------------------------------------------------------

IsometricTrialSettings readIsometricTrialSettings(const ParamNode& n, const ArmParameters& arm) {
    IsometricTrialSettings s;
    const Bound any = Bound::any();
    s.elbowAngle = degToRad(n.getNumber("elbow_angle_deg", any, radToDeg(s.elbowAngle)));
    s.activation = n.getNumber("activation", any, s.activation);
    s.restDuration = n.getNumber("rest", any, s.restDuration);
    s.riseTime = n.getNumber("rise", any, s.riseTime);
    s.holdDuration = n.getNumber("hold", any, s.holdDuration);
    s.sampleRate = n.getNumber("sample_rate", any, s.sampleRate);
    s.averagingWindow = n.getNumber("averaging_window", any, std::min(s.averagingWindow, s.holdDuration));
    s.integration.accuracy = n.getNumber("accuracy", any, s.integration.accuracy);
    n.finish();
    n.rethrowWithLocation([&] { s.validate(arm); });
    return s;
}

FreeMovementSettings readFreeMovementSettings(const ParamNode& n, const ArmParameters& arm) {
    FreeMovementSettings s;
    const Bound any = Bound::any();
    s.initialAngle = degToRad(n.getNumber("initial_angle_deg", any, radToDeg(s.initialAngle)));
    s.initialVelocity = degToRad(n.getNumber("initial_velocity_degps", any, 0.0));
    const double U = n.getNumber("activation", Bound::closed(0, 1), 0.5);
    const double onset = n.getNumber("onset", Bound::nonNegative("s"), 0.2);
    const double rise = n.getNumber("rise", Bound::nonNegative("s"), 0.0);
    s.activation = rise > 0 ? ActivationProfile::ramp(onset, onset + rise, 0.0, U) : ActivationProfile::step(onset, 0.0, U);
    s.duration = n.getNumber("duration", any, s.duration);
    s.handLoad = n.getNumber("hand_load", any, s.handLoad);
    s.sampleRate = n.getNumber("sample_rate", any, s.sampleRate);
    s.integration.accuracy = n.getNumber("accuracy", any, s.integration.accuracy);
    n.finish();
    n.rethrowWithLocation([&] { s.validate(arm); });
    return s;
}

}  // namespace armsim
