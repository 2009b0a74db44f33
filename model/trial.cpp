#include "model/trial.h"

#include "basics/parallel.h"
#include "basics/param_node.h"
#include "model/geometry.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

using namespace SimTK;

namespace armsim {

namespace {

void checkElbowAngle(const std::string& field, double theta, const ArmParameters& arm) {
    checkField(field, cleanDegrees(theta), Bound::closed(arm.minElbowAngleDeg, arm.maxElbowAngleDeg, "deg"));
}

// Per-muscle force and activation columns (models with several muscles), then the state columns.
std::vector<std::string> withMuscleColumns(std::vector<std::string> names, const MuscleArm& model) {
    if (model.getNumMuscles() > 1) {
        for (int i = 0; i < model.getNumMuscles(); ++i) names.push_back("force_" + model.getMuscleName(i) + "_N");
        for (int i = 0; i < model.getNumMuscles(); ++i) names.push_back("activation_" + model.getMuscleName(i));
    }
    for (const std::string& n : model.getStateColumnNames()) names.push_back(n);
    return names;
}

// The muscles' activation profiles, looked up once (each lookup is a Simbody handle downcast).
std::vector<const ActivationProfile*> getActivationProfiles(const MuscleArm& model) {
    std::vector<const ActivationProfile*> profiles;
    for (int i = 0; i < model.getNumMuscles(); ++i) profiles.push_back(&model.getMuscleForce(i).getActivationProfile());
    return profiles;
}

// Where each muscle's states sit in y = [q u z] (their first index); std::logic_error naming `caller`
// when some z belongs to no muscle (the trials' ODEs hold q, u and the muscles' states only).
std::vector<int> findMuscleStates(const MuscleArm& model, const State& state, const char* caller) {
    const int nqu = state.getNQ() + state.getNU();
    std::vector<int> first;
    int numMuscleStates = 0;
    for (int i = 0; i < model.getNumMuscles(); ++i) {
        first.push_back(nqu + model.getMuscleForce(i).getFirstStateIndex(state));
        numMuscleStates += model.getMuscle(i).getNumStates();
    }
    if (numMuscleStates != state.getNZ())
        throw std::logic_error(std::string(caller) + ": the arm has z states that belong to no muscle");
    return first;
}

void appendMuscleForces(std::vector<double>& row, const std::vector<const ActivationProfile*>& activations,
                        const std::vector<double>& forces, double t) {
    if (forces.size() == 1) return;
    row.insert(row.end(), forces.begin(), forces.end());
    for (const ActivationProfile* a : activations) row.push_back(a->getValue(t));
}

double mean(const std::vector<double>& v, std::size_t from) {
    double s = 0;
    for (std::size_t i = from; i < v.size(); ++i) s += v[i];
    return v.size() > from ? s / double(v.size() - from) : NAN;
}

}  // namespace

void setStateFromTrialRow(const MuscleArm& model, const Table& table, int row, State& state) {
    const ArmModel& arm = model.getArm();
    state.setTime(table.get(row, "time_s"));
    arm.setElbowAngle(state, degToRad(table.get(row, "elbow_angle_deg")));
    arm.setElbowAngularVelocity(state, degToRad(table.get(row, "elbow_velocity_degps")));
    std::vector<double> y;
    for (const std::string& column : model.getStateColumnNames()) {
        if (!table.hasColumn(column))
            throw InputError("trial table has no column '" + column + "': it was not written by armsim trial for "
                             "model '" + model.getSetup().name + "', or for another muscle composition");
        y.push_back(table.get(row, column));
    }
    model.setMuscleStates(state, y);
}

std::vector<ActivationProfile> readActivationProfiles(const ArmSetup& setup, const Table& table,
                                                      const std::string& tableName) {
    const std::vector<double> time = table.getColumn("time_s");
    std::vector<ActivationProfile> profiles;
    for (const MuscleSpec& m : setup.muscles) {
        const std::string column = setup.getNumMuscles() == 1 ? "activation" : "activation_" + m.params.name;
        if (!table.hasColumn(column))
            throw InputError(tableName + " has no column '" + column + "' (model '" + setup.name +
                             "'): was it written for another model?");
        const std::vector<double> values = table.getColumn(column);
        for (std::size_t i = 0; i < values.size(); ++i)   // named by the file's line, as typed
            if (!(values[i] >= 0 && values[i] <= 1)) {
                const int line = table.getSourceLine(int(i));
                throw InputError(tableName + " " + (line > 0 ? "line " + std::to_string(line) : "row " + std::to_string(i + 1)) +
                                 ": column '" + column + "' = " + formatNumber(values[i]) + ": expected in [0, 1]");
            }
        profiles.emplace_back(time, values, tableName + " " + column);
    }
    return profiles;
}

// ---- Isometric ----------------------------------------------------------------------------------

void checkForearmRotationDeg(const std::string& field, double deg, const ArmParameters& arm) {
    if (std::isnan(deg)) return;
    if (!arm.forearmRotation.enabled)
        throw FieldError(field, "= " + formatNumber(deg) + ": the model's arm has no forearm rotation (expected none)");
    checkField(field, deg, Bound::closed(arm.forearmRotation.minDeg, arm.forearmRotation.maxDeg, "deg, + = supination"));
}

void IsometricTrialSettings::validate(const ArmParameters& arm) const {
    checkElbowAngle("elbow_angle_deg", elbowAngle, arm);
    checkForearmRotationDeg("forearm_rotation_deg", forearmRotationDeg, arm);
    const double angleDeg = cleanDegrees(elbowAngle);
    if (angleDeg >= 180)  // the straight-line biceps passes through the joint there
        throw FieldError("elbow_angle_deg", "= " + formatNumber(angleDeg) +
                                                ": an isometric trial reads the biceps force as torque / moment arm, and the "
                                                "moment arm vanishes at full extension: expected an angle below 180 deg");
    if (isForearmEffort(effort) && !arm.forearmRotation.enabled)
        throw FieldError("effort", std::string("= ") + getEffortName(effort) +
                                       ": the model's arm has no forearm rotation (expected flexion or extension)");
    checkIsometricEffort(activation, antagonistActivation, restDuration, riseTime, holdDuration, sampleRate, averagingWindow);
    checkField("accuracy", integration.accuracy, bounds::kTrialAccuracy);
    integration.validate();
}

void checkIsometricEffort(double activation, double antagonistActivation, double rest, double rise, double hold,
                          double sampleRate, double averagingWindow) {
    checkField("activation", activation, Bound::closed(0, 1));
    checkField("antagonist_activation", antagonistActivation, Bound::closed(0, 1));
    checkField("rest", rest, Bound::positive("s"));
    checkField("rise", rise, Bound::nonNegative("s"));
    checkField("hold", hold, Bound::positive("s"));
    checkField("sample_rate", sampleRate, Bound::positive("Hz"));
    checkField("averaging_window", averagingWindow, {0, hold, true, false, "s, within the hold"});
    calcNumSamples(rest + rise + hold, sampleRate);
}

namespace {

ActivationProfile riseTo(const IsometricTrialSettings& s, double U) {
    if (s.riseTime > 0) return ActivationProfile::ramp(s.restDuration, s.restDuration + s.riseTime, 0.0, U);
    return ActivationProfile::step(s.restDuration, 0.0, U);
}

}  // namespace

ActivationProfile IsometricTrialSettings::calcActivationProfile() const { return riseTo(*this, activation); }

std::vector<bool> IsometricTrialSettings::findAgonists(const ArmSetup& setup) const {
    std::vector<double> r(setup.muscles.size(), 0.0);
    if (isForearmEffort(effort)) {
        if (!setup.arm.forearmRotation.enabled)
            throw FieldError("effort", std::string("= ") + getEffortName(effort) + ": model '" + setup.name +
                                           "' has no forearm rotation (expected flexion or extension)");
        ArmGeometry g(setup);
        g.setForearmRotation(degToRad(std::isnan(forearmRotationDeg) ? setup.arm.forearmRotation.postureDeg
                                                                     : forearmRotationDeg));
        g.setElbowAngle(elbowAngle);
        for (int i = 0; i < setup.getNumMuscles(); ++i) r[i] = g.calcForearmMomentArm(i);
    }
    std::vector<bool> agonist;
    for (std::size_t i = 0; i < setup.muscles.size(); ++i) agonist.push_back(isAgonistOf(effort, setup.muscles[i].group, r[i]));
    return agonist;
}

std::vector<ActivationProfile> IsometricTrialSettings::calcActivationProfiles(const ArmSetup& setup) const {
    const std::vector<bool> agonist = findAgonists(setup);
    // An effort no muscle makes (an extension on a biceps-only arm), or a co-contraction no muscle can
    // give, would read zero or change nothing: refused, as a rotation effort without a forearm is.
    const long agonists = std::count(agonist.begin(), agonist.end(), true);
    if (agonists == 0 && activation > 0)
        throw FieldError("effort", std::string("= ") + getEffortName(effort) + ": model '" + setup.name + "' has no muscle "
                                       "that makes it (expected an effort of the model's muscles)");
    if (agonists == long(agonist.size()) && antagonistActivation > 0)
        throw FieldError("antagonist_activation", "= " + formatNumber(antagonistActivation) + ": model '" + setup.name +
                                                      "' has no antagonist of a " + getEffortName(effort) +
                                                      " effort (expected 0)");
    std::vector<ActivationProfile> profiles;
    for (std::size_t i = 0; i < setup.muscles.size(); ++i)
        profiles.push_back(riseTo(*this, agonist[i] ? activation : antagonistActivation));
    return profiles;
}

TransducerAtAngle::TransducerAtAngle(const ArmParameters& arm, double elbowAngle, double momentArm)
    : range_(arm.transducerRange), strapDistance_(arm.strapDistance), momentArm_(momentArm),
      fixedRatioPerNewton_(calcBicepsForceFixedRatio(1.0, elbowAngle, kPi / 2)) {
    calcBicepsForceFromTorque(0.0, momentArm);   // checks the moment arm
}

TransducerReading TransducerAtAngle::read(double strapForce, double muscleForce) const {
    TransducerReading r;
    r.saturated = std::abs(strapForce) > range_;
    r.strapForce = r.saturated ? std::copysign(range_, strapForce) : strapForce;
    r.forceMomentArm = r.strapForce * strapDistance_ / momentArm_;
    r.forceFixedRatio = r.strapForce * fixedRatioPerNewton_;
    const double F = muscleForce;
    r.errorMomentArmPct = F > 0 ? 100 * (r.forceMomentArm - F) / F : NAN;
    r.errorFixedRatioPct = F > 0 ? 100 * (r.forceFixedRatio - F) / F : NAN;
    return r;
}

TransducerReading calcTransducerReading(const ArmParameters& arm, double strapForce, double elbowAngle,
                                        double momentArm, double muscleForce) {
    return TransducerAtAngle(arm, elbowAngle, momentArm).read(strapForce, muscleForce);
}

namespace {

// TrialSolver::LockedOde: the locked arm's ODE on Simbody's own state vector (see runIsometricTrial).
IntegrationStats integrateLockedArm(const State& state, const std::vector<int>& firstState,
                                    const std::vector<const MuscleModel*>& muscles,
                                    const std::vector<const ActivationProfile*>& activations, const std::vector<double>& P,
                                    const IsometricTrialSettings& settings, const std::vector<double>& breakpoints,
                                    const OdeVisitor& sample) {
    const int n = int(muscles.size()), nqu = state.getNQ() + state.getNU();
    // The locked arm's ODE on Simbody's own state vector: q' = u = 0 and u' = 0 (locked), each
    // muscle's z' from its pure model at its fixed path length and its own activation. Blocks:
    // [q u], then one per muscle (a Jacobian column evaluates one muscle).
    std::vector<double> y(state.getNY());
    for (int i = 0; i < state.getNY(); ++i) y[i] = state.getY()[i];
    OdeBlocks f;
    f.first.push_back(0);
    f.size.push_back(nqu);
    for (int i = 0; i < n; ++i) {
        f.first.push_back(firstState[i]);
        f.size.push_back(muscles[i]->getNumStates());
    }
    const bool analytic = settings.bandedNewton && settings.analyticJacobian;
    f.banded = settings.bandedNewton && (n > 1 || analytic);
    f.calcBlock = [&](int b, double t, const double* yIn, double* ydot) {
        if (b == 0) {
            std::fill(ydot, ydot + nqu, 0.0);
            return;
        }
        const int i = b - 1;
        muscles[i]->calcStateDerivative(P[i], activations[i]->getValue(t), yIn + firstState[i],
                                        ydot + firstState[i]);
    };
    if (analytic)
        f.calcBlockJacobian = [&](int b, double t, const double* yIn, double* J) {
            if (b == 0) return true;   // q' = u' = 0: the zero block
            const int i = b - 1;
            return muscles[i]->calcStateJacobian(P[i], activations[i]->getValue(t), yIn + firstState[i], J);
        };
    return integrateSampled(
        f, state.getTime(), y, settings.getDuration(), settings.sampleRate, breakpoints, settings.integration, sample,
        [&](double t, const double* yIn) {
            for (int i = 0; i < n; ++i) muscles[i]->checkStates(t, yIn + firstState[i]);
        });
}

// An isometric trial table's columns (IsometricTrialResult::series).
std::vector<std::string> getIsometricColumns(const MuscleArm& model, bool forearm) {
    std::vector<std::string> columns = {"time_s", "activation", "elbow_angle_deg", "elbow_velocity_degps", "muscle_force_N",
                                        "fascicle_length_m", "fascicle_velocity_mps", "holding_torque_Nm",
                                        "muscle_torque_Nm", "strap_force_N", "saturated", "force_moment_arm_N",
                                        "force_fixed_ratio_N", "error_moment_arm_pct", "error_fixed_ratio_pct"};
    if (forearm) columns.push_back("forearm_torque_Nm");
    return withMuscleColumns(columns, model);
}

// The summary's window means from the trial's table.
void summarizeIsometricSeries(const MuscleArm& model, const IsometricTrialSettings& settings, bool forearm,
                              IsometricTrialResult& result) {
    IsometricSummary& sum = result.summary;
    const int n = model.getNumMuscles();
    const Table& t = result.series;
    const std::vector<double> time = t.getColumn("time_s");
    const double from = time.back() - settings.averagingWindow - 1e-9;
    std::size_t first = 0;
    while (first < time.size() && time[first] < from) ++first;
    sum.finalForce = t.get(t.getNumRows() - 1, "muscle_force_N");
    sum.meanForce = mean(t.getColumn("muscle_force_N"), first);
    const std::vector<double> fascicle = t.getColumn("fascicle_length_m");
    sum.restFascicleLength = fascicle.front();
    sum.meanFascicleLength = mean(fascicle, first);
    sum.meanStrapForce = mean(t.getColumn("strap_force_N"), first);
    sum.meanForceMomentArm = mean(t.getColumn("force_moment_arm_N"), first);
    sum.meanForceFixedRatio = mean(t.getColumn("force_fixed_ratio_N"), first);
    sum.meanMuscleTorque = mean(t.getColumn("muscle_torque_Nm"), first);
    if (forearm) sum.meanForearmTorque = mean(t.getColumn("forearm_torque_Nm"), first);
    for (int i = 0; i < n; ++i)
        sum.meanForces.push_back(n == 1 ? sum.meanForce : mean(t.getColumn("force_" + model.getMuscleName(i) + "_N"), first));
}

}  // namespace

namespace {

// The estimate divides the torque by h: near full extension a vanishing h turns noise into force.
void checkEstimateMomentArm(double h, double elbowAngle, const std::string& muscle) {
    constexpr double kMinEstimateMomentArm = 1e-3;   // m
    if (h < kMinEstimateMomentArm)
        throw FieldError("elbow_angle_deg", "= " + formatNumber(cleanDegrees(elbowAngle)) + ": the " + muscle +
                                                "'s moment arm there is " + formatNumber(1000 * h, 3) +
                                                " mm, and the force estimate (torque / moment arm) needs at least 1 mm: "
                                                "expected an angle further from full extension");
}

}  // namespace

IsometricTrialResult runIsometricTrial(const ArmSetup& setup, const IsometricTrialSettings& settings) {
    settings.validate(setup.arm);
    const ActivationProfile profile = settings.calcActivationProfile();
    const MuscleArm model(setup, settings.calcActivationProfiles(setup));
    const ArmModel& arm = model.getArm();
    const MultibodySystem& system = model.getSystem();
    const ArmParameters& ap = setup.arm;
    const int n = model.getNumMuscles(), primary = setup.primary;

    State state = model.getDefaultState();
    arm.lockElbow(state, settings.elbowAngle);
    if (!std::isnan(settings.forearmRotationDeg)) arm.lockForearmRotation(state, degToRad(settings.forearmRotationDeg));
    model.setSteadyMuscleStates(state);  // passive equilibrium at U(0) = 0
    system.realize(state, Stage::Acceleration);

    IsometricTrialResult result;
    IsometricSummary& sum = result.summary;
    sum.elbowAngle = settings.elbowAngle;
    std::vector<double> restForces(n);
    const bool forearm = ap.forearmRotation.enabled;
    for (int i = 0; i < n; ++i) {
        sum.pathLengths.push_back(model.calcPathLength(state, i));
        sum.momentArms.push_back(model.calcMomentArm(state, i));
        sum.forearmMomentArms.push_back(forearm ? model.calcForearmMomentArm(state, i) : 0.0);
        restForces[i] = model.getMuscleForce(i).getForce(state);
    }
    sum.pathLength = sum.pathLengths[primary];
    sum.momentArm = sum.momentArms[primary];
    sum.tareTorque = arm.calcHoldingTorque(state);
    sum.restForce = restForces[primary];
    // Locked: gravity and the stop are constant, so the lock's torque is G - sum_i h_i F_i exactly.
    double G = sum.tareTorque;
    for (int i = 0; i < n; ++i) G += sum.momentArms[i] * restForces[i];
    // The same about the forearm axis (the radius is locked too): its lock holds Gf - sum_i r_i F_i.
    const double forearmTare = forearm ? arm.calcForearmHoldingTorque(state) : 0.0;
    double Gf = forearmTare;
    for (int i = 0; i < n; ++i) Gf += sum.forearmMomentArms[i] * restForces[i];
    result.series = Table(getIsometricColumns(model, forearm));
    result.series.reserveRows(int(std::lround(settings.getDuration() * settings.sampleRate)) + 1);
    const double h = sum.momentArm;
    std::vector<const MuscleModel*> muscles;
    for (int i = 0; i < n; ++i) muscles.push_back(&model.getMuscle(i));
    const std::vector<const ActivationProfile*> activations = getActivationProfiles(model);
    const std::vector<int> firstState = findMuscleStates(model, state, "runIsometricTrial");
    std::vector<double> forces(n), row;

    const bool primaryVelocityIsState = muscles[primary]->hasFascicleVelocityState();
    checkEstimateMomentArm(h, settings.elbowAngle, model.getMuscleName(primary));
    const TransducerAtAngle transducer(ap, settings.elbowAngle, h);
    // One sample from y = [q u z]; s is the realized-per-sample reference's State (else null).
    auto sample = [&](double t, const double* y, const State* s) {
        double torque, forearmTorque = 0;
        if (s) {
            system.realize(*s, Stage::Acceleration);
            for (int i = 0; i < n; ++i) forces[i] = model.getMuscleForce(i).getForce(*s);
            torque = arm.calcHoldingTorque(*s);
            if (forearm) forearmTorque = arm.calcForearmHoldingTorque(*s);
        } else {  // the paths are fixed: the pure model gives Fse from the interpolated states
            torque = G;
            forearmTorque = Gf;
            for (int i = 0; i < n; ++i) {
                forces[i] = muscles[i]->calcForce(sum.pathLengths[i], y + firstState[i]);
                torque -= sum.momentArms[i] * forces[i];
                forearmTorque -= sum.forearmMomentArms[i] * forces[i];
            }
        }
        const double F = forces[primary];
        const double muscleTorque = sum.tareTorque - torque;  // tared, + = flexion
        const TransducerReading r = transducer.read(muscleTorque / ap.strapDistance, F);
        sum.saturated = sum.saturated || r.saturated;
        const double* yp = y + firstState[primary];
        const double Pp = sum.pathLengths[primary];
        const double Up = primaryVelocityIsState ? 0.0 : activations[primary]->getValue(t);
        row.assign({t, profile.getValue(t), radToDeg(settings.elbowAngle), 0.0, F,
                    muscles[primary]->calcFascicleLength(Pp, yp), muscles[primary]->calcFascicleVelocity(Pp, Up, yp),
                    torque, muscleTorque, r.strapForce, r.saturated ? 1.0 : 0.0, r.forceMomentArm, r.forceFixedRatio, r.errorMomentArmPct, r.errorFixedRatioPct});
        if (forearm) row.push_back(forearmTare - forearmTorque);  // tared, + = supination
        appendMuscleForces(row, activations, forces, t);
        for (int i = 0; i < n; ++i) row.insert(row.end(), y + firstState[i], y + firstState[i] + muscles[i]->getNumStates());
        result.series.appendRow(row);
        if (settings.progress) settings.progress(t);
    };

    if (settings.solver == TrialSolver::LockedOde) {
        sum.stats = integrateLockedArm(state, firstState, muscles, activations, sum.pathLengths, settings,
                                       findRestartTimes(model), [&](double t, const double* y) { sample(t, y, nullptr); });
    } else {
        const bool perSample = settings.solver == TrialSolver::SimbodyPerSample;
        sum.stats = simulateSampled(
            system, state, settings.getDuration(), settings.sampleRate, findRestartTimes(model),
            settings.integration,
            [&](const State& s) { sample(s.getTime(), &s.getY()[0], perSample ? &s : nullptr); },
            [&](const State& s) { model.checkMuscleStates(s); });
    }

    summarizeIsometricSeries(model, settings, forearm, result);
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
    checkField("initial_velocity_degps", cleanDegrees(initialVelocity), Bound::closed(-2000, 2000, "deg/s"));
    checkField("duration", duration, Bound::positive("s"));
    checkField("hand_load", handLoad, bounds::kHandLoad);
    checkField("sample_rate", sampleRate, Bound::positive("Hz"));
    calcNumSamples(duration, sampleRate);
    checkField("accuracy", integration.accuracy, bounds::kTrialAccuracy);
    integration.validate();
    const std::vector<double>& t = activation.getBreakpoints();
    if (activation.getValue(0) == 0 && activation.getMaxValue() > 0 && !t.empty() && t.front() >= duration)
        throw FieldError("onset", "= " + formatNumber(t.front()) + " s is not before the end of the movement (duration " +
                                      formatNumber(duration) + " s): expected an onset before the end (the activation "
                                      "would never start)");
}

namespace {

// FreeMovementSolver::MuscleBlocks (trial.h): the free arm's ODE y' = f(t, y), y = [q u z], for CPodes.
// A full evaluation realizes the System. The last full evaluation that was not a Jacobian column of
// the joint (a state moved in q or u alone) is the base; a call at its time whose y differs from the
// base's in muscle states only is a Jacobian column of those muscles: they are evaluated alone at the
// base's path length and lengthening speed (-h u), and the elbow's acceleration changes by
// sum h_i dF_i / M_ee (exact: given q and u the accelerations are linear in the tensions; the radius,
// if any, is locked). Everything else is the base's.
class CoupledMuscleOde {
public:
    CoupledMuscleOde(const MuscleArm& model, const State& initial, bool checkPartial)
        : model_(model), system_(model.getSystem()), state_(initial), n_(model.getNumMuscles()),
          checkPartial_(checkPartial) {
        nq_ = state_.getNQ();
        nqu_ = nq_ + state_.getNU();
        ny_ = state_.getNY();
        elbowU_ = nq_ + int(model.getArm().getForearm().getFirstUIndex(state_));
        first_ = findMuscleStates(model, state_, "FreeMovementSolver::MuscleBlocks");
        for (int i = 0; i < n_; ++i) muscles_.push_back(&model.getMuscle(i));
        // What the one-muscle evaluation assumes besides: the elbow is the only free mobility (the
        // radius, if any, locked: its acceleration is 0 and the elbow's is its generalized force over M_ee).
        const ArmModel& arm = model.getArm();
        if (state_.getNU() != (arm.hasForearmRotation() ? 2 : 1) ||
            (arm.hasForearmRotation() && !arm.getRadius().isLocked(state_)))
            throw std::logic_error("FreeMovementSolver::MuscleBlocks: the arm has a free mobility besides the elbow; "
                                   "use SimbodySystem");
        activations_ = getActivationProfiles(model);
        base_.resize(ny_);
        baseYdot_.resize(ny_);
        length_.resize(n_);
        speed_.resize(n_);
        momentArm_.resize(n_);
        force_.resize(n_);
    }

    int getNumPartialEvaluations() const { return partial_; }

    /// Newton's systems as an arrow: [q u], then each muscle's states, in state order.
    OdeArrow makeArrow() {
        OdeArrow arrow;
        arrow.f = [this](double t, const double* y, double* ydot) { (*this)(t, y, ydot); };
        arrow.numCoupled = nqu_;
        std::vector<std::pair<int, int>> blocks;
        for (int i = 0; i < n_; ++i) blocks.emplace_back(first_[i], muscles_[i]->getNumStates());
        std::sort(blocks.begin(), blocks.end());
        for (const auto& [first, size] : blocks) {
            arrow.first.push_back(first);
            arrow.size.push_back(size);
        }
        return arrow;
    }

    void operator()(double t, const double* y, double* ydot) {
        if (haveBase_ && t == baseTime_) {
            const bool jointMoved = !std::equal(y, y + nqu_, base_.data());
            moved_.clear();
            for (int i = 0; i < n_; ++i) {
                const int a = first_[i], b = a + muscles_[i]->getNumStates();
                if (!std::equal(y + a, y + b, base_.data() + a)) moved_.push_back(i);
            }
            if (!jointMoved && !moved_.empty()) {
                evaluateMuscles(t, y, ydot, moved_);
                if (checkPartial_) checkPartial(t, y, ydot);
                return;
            }
            if (jointMoved && moved_.empty()) {   // a joint column: the base stays
                realize(t, y, ydot);
                return;
            }
        }
        realize(t, y, ydot);
        std::copy(y, y + ny_, base_.begin());
        std::copy(ydot, ydot + ny_, baseYdot_.begin());
        baseTime_ = t;
        haveBase_ = true;
        haveGeometry_ = false;
    }

private:
    // FreeMovementSettings::checkPartialEvaluations: the realized derivative must be the same.
    void checkPartial(double t, const double* y, const double* ydot) {
        std::vector<double> full(ny_);
        realize(t, y, full.data());
        for (int k = 0; k < ny_; ++k)
            if (!(std::abs(full[k] - ydot[k]) <= 1e-9 * std::max(1.0, std::abs(full[k]))))
            {
                char text[200];
                std::snprintf(text, sizeof text, "free movement: a one-muscle evaluation at t = %.17g differs from "
                              "the realized derivative in entry %d: %.17g against %.17g", t, k, ydot[k], full[k]);
                throw std::logic_error(text);
            }
    }
    void realize(double t, const double* y, double* ydot) {
        state_.setTime(t);
        Vector& Y = state_.updY();
        for (int k = 0; k < ny_; ++k) Y[k] = y[k];
        system_.realize(state_, Stage::Acceleration);
        const Vector& Yd = state_.getYDot();
        for (int k = 0; k < ny_; ++k) ydot[k] = Yd[k];
    }
    // The base's path lengths, speeds, moment arms, tensions and the elbow's inertia.
    void computeGeometry() {
        realizeBase();
        Matrix M;
        system_.getMatterSubsystem().calcM(state_, M);
        const int e = elbowU_ - nq_;
        elbowInertia_ = M(e, e);
        for (int i = 0; i < n_; ++i) {
            length_[i] = model_.calcPathLength(state_, i);
            momentArm_[i] = model_.calcMomentArm(state_, i);
            speed_[i] = -momentArm_[i] * base_[elbowU_];
            force_[i] = muscles_[i]->calcForce(length_[i], base_.data() + first_[i]);
        }
        haveGeometry_ = true;
    }
    void realizeBase() {
        state_.setTime(baseTime_);
        Vector& Y = state_.updY();
        for (int k = 0; k < ny_; ++k) Y[k] = base_[k];
        system_.realize(state_, Stage::Position);
    }
    void evaluateMuscles(double t, const double* y, double* ydot, const std::vector<int>& moved) {
        if (!haveGeometry_) computeGeometry();
        std::copy(baseYdot_.begin(), baseYdot_.end(), ydot);
        double torque = 0;
        for (int i : moved) {
            const double* yi = y + first_[i];
            muscles_[i]->calcMovingStateDerivative(length_[i], speed_[i], activations_[i]->getValue(t), yi,
                                                   ydot + first_[i]);
            torque += momentArm_[i] * (muscles_[i]->calcForce(length_[i], yi) - force_[i]);
        }
        ydot[elbowU_] += torque / elbowInertia_;
        ++partial_;
    }

    const MuscleArm& model_;
    const MultibodySystem& system_;
    State state_;
    int n_, nq_ = 0, nqu_ = 0, ny_ = 0, elbowU_ = 0;
    bool checkPartial_;
    std::vector<const MuscleModel*> muscles_;
    std::vector<int> first_;
    std::vector<const ActivationProfile*> activations_;
    bool haveBase_ = false, haveGeometry_ = false;
    double baseTime_ = 0, elbowInertia_ = 1;
    std::vector<double> base_, baseYdot_, length_, speed_, momentArm_, force_;
    std::vector<int> moved_;
    int partial_ = 0;
};

}  // namespace

IntegrationStats integrateCoupledMuscles(const MuscleArm& model, State& state, double duration, double sampleRate,
                                         const std::vector<double>& breakpoints, const IntegrationSettings& integration,
                                         bool checkPartial, const std::function<void(const State&)>& sample) {
    const MultibodySystem& system = model.getSystem();
    system.realize(state, Stage::Time);
    CoupledMuscleOde f(model, state, checkPartial);
    std::vector<double> y(state.getNY());
    for (int k = 0; k < state.getNY(); ++k) y[k] = state.getY()[k];
    State out = state;
    auto toState = [&](double t, const double* yIn) -> const State& {
        out.setTime(t);
        Vector& Y = out.updY();
        for (int k = 0; k < out.getNY(); ++k) Y[k] = yIn[k];
        system.realize(out, Stage::Time);
        return out;
    };
    IntegrationStats st = integrateSampled(
        f.makeArrow(), state.getTime(), y, duration, sampleRate, breakpoints, integration,
        [&](double t, const double* yIn) { sample(toState(t, yIn)); },
        [&](double t, const double* yIn) { model.checkMuscleStates(toState(t, yIn)); });
    st.partialEvaluations = f.getNumPartialEvaluations();
    state = toState(state.getTime() + duration, y.data());
    return st;
}


Table runFreeMovement(const ArmSetup& setup, const FreeMovementSettings& settings, IntegrationStats* stats) {
    settings.validate(setup.arm);
    ArmSetup loaded = setup;
    loaded.arm.handLoad = settings.handLoad;
    std::vector<ActivationProfile> profiles;
    for (const MuscleSpec& m : setup.muscles)
        profiles.push_back(m.group == MuscleGroup::Flexor ? settings.activation : ActivationProfile::constant(0.0));
    const MuscleArm model(loaded, profiles);
    const ArmModel& arm = model.getArm();
    const MultibodySystem& system = model.getSystem();
    const int primary = setup.primary, n = model.getNumMuscles();
    const MuscleForce& biceps = model.getBiceps();

    State state = model.getDefaultState();
    arm.setElbowAngle(state, settings.initialAngle);
    arm.setElbowAngularVelocity(state, settings.initialVelocity);
    if (settings.startSteady) model.setSteadyMuscleStates(state);
    else model.setInitialMuscleStates(state);

    Table t(withMuscleColumns({"time_s", "activation", "elbow_angle_deg", "elbow_velocity_degps", "path_length_m",
                               "moment_arm_m", "muscle_force_N", "fascicle_length_m", "fascicle_velocity_mps",
                               "active_fraction"},
                              model));
    const double L0 = model.getMuscle(primary).getOptimalFascicleLength();
    std::vector<double> forces(n);
    const std::vector<const ActivationProfile*> activations = getActivationProfiles(model);
    auto sample = [&](const State& s) {
        system.realize(s, Stage::Position);
        const MuscleOutputs o = biceps.calcOutputs(s);
        for (int i = 0; i < n; ++i) forces[i] = model.getMuscleForce(i).getForce(s);
        std::vector<double> row{s.getTime(), biceps.getActivation(s), radToDeg(arm.getElbowAngle(s)),
                                radToDeg(arm.getElbowAngularVelocity(s)), model.calcPathLength(s, primary),
                                model.calcMomentArm(s, primary), o.Fse, o.L * L0, o.V * L0, o.activeFraction};
        appendMuscleForces(row, activations, forces, s.getTime());
        model.appendMuscleStates(s, row);
        t.appendRow(std::move(row));
        if (settings.progress) settings.progress(s.getTime());
    };
    IntegrationStats st;
    if (settings.solver == FreeMovementSolver::SimbodySystem) {
        st = simulateSampled(system, state, settings.duration, settings.sampleRate, findRestartTimes(model),
                             settings.integration, sample, [&](const State& s) { model.checkMuscleStates(s); });
    } else {
        st = integrateCoupledMuscles(model, state, settings.duration, settings.sampleRate,
                                     findRestartTimes(model), settings.integration,
                                     settings.checkPartialEvaluations, sample);
    }
    if (stats) *stats = st;
    return t;
}

// ---- Settings files -----------------------------------------------------------------------------

namespace {

// s.validate(arm) with the file's lines, the sample count in the file's keys (durationKeys, sample_rate).
template <class Settings>
void validateSettingsFile(const ParamNode& n, const Settings& s, const ArmParameters& arm, const std::string& durationKeys) {
    try {
        n.rethrowWithLocation([&] { s.validate(arm); });
    } catch (const SampleCountError& e) {
        throw InputError(n.where("sample_rate") + ": " + durationKeys + " = " + formatNumber(e.getDuration()) + " s x sample_rate " +
                         formatNumber(e.getSampleRate()) + " Hz " + e.getDetail());
    }
}

}  // namespace

IsometricTrialSettings readIsometricTrialSettings(const ParamNode& n, const ArmParameters& arm) {
    IsometricTrialSettings s;
    const Bound any = Bound::any();
    s.elbowAngle = degToRad(n.getNumber("elbow_angle_deg", any, radToDeg(s.elbowAngle)));
    s.activation = n.getNumber("activation", any, s.activation);
    s.effort = parseEffortName(n.getChoice("effort", {"flexion", "extension", "supination", "pronation"}, "flexion"));
    s.antagonistActivation = n.getNumber("antagonist_activation", any, s.antagonistActivation);
    s.restDuration = n.getNumber("rest", any, s.restDuration);
    s.riseTime = n.getNumber("rise", any, s.riseTime);
    s.holdDuration = n.getNumber("hold", any, s.holdDuration);
    s.sampleRate = n.getNumber("sample_rate", any, s.sampleRate);
    s.averagingWindow = n.getNumber("averaging_window", any, std::min(s.averagingWindow, s.holdDuration));
    s.integration.accuracy = n.getNumber("accuracy", any, s.integration.accuracy);
    n.finish();
    validateSettingsFile(n, s, arm, "rest + rise + hold");
    return s;
}

FreeMovementSettings readFreeMovementSettings(const ParamNode& n, const ArmParameters& arm) {
    FreeMovementSettings s;
    const Bound any = Bound::any();
    s.initialAngle = degToRad(n.getNumber("initial_angle_deg", any, radToDeg(s.initialAngle)));
    s.initialVelocity = degToRad(n.getNumber("initial_velocity_degps", any, 0.0));
    const double U = n.getNumber("activation", Bound::closed(0, 1), 1.0);   // as `trial --activation`
    const double onset = n.getNumber("onset", Bound::nonNegative("s"), 0.2);
    const double rise = n.getNumber("rise", Bound::nonNegative("s"), 0.0);
    s.activation = rise > 0 ? ActivationProfile::ramp(onset, onset + rise, 0.0, U) : ActivationProfile::step(onset, 0.0, U);
    s.duration = n.getNumber("duration", any, s.duration);
    s.handLoad = n.getNumber("hand_load", any, arm.handLoad);   // the arm file's load unless the trial gives one
    s.sampleRate = n.getNumber("sample_rate", any, s.sampleRate);
    s.integration.accuracy = n.getNumber("accuracy", any, s.integration.accuracy);
    n.finish();
    validateSettingsFile(n, s, arm, "duration");
    return s;
}

}  // namespace armsim
