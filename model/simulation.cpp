#include "model/simulation.h"

#include "basics/bound.h"
#include "basics/errors.h"
#include "model/trial.h"
#include "muscles/simbody_isometric.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

using namespace SimTK;

namespace armsim {

void SimulationSettings::validate(const ArmParameters& arm) const {
    checkField("elbow_angle_deg", cleanDegrees(elbowAngle),
               Bound::closed(arm.minElbowAngleDeg, arm.maxElbowAngleDeg, "deg"));
    checkField("elbow_velocity_degps", cleanDegrees(elbowVelocity), Bound::closed(-2000, 2000, "deg/s"));
    if (lockedElbow && elbowVelocity != 0)
        throw FieldError("elbow_velocity_degps", "= " + formatNumber(cleanDegrees(elbowVelocity)) +
                                                     " deg/s on a locked elbow: expected 0");
    checkForearmRotationDeg("rotation_deg", forearmRotationDeg, arm);
    checkField("hand_load", handLoad, bounds::kHandLoad);
    checkField("sample_rate", sampleRate, Bound::closed(1e-3, 1e6, "Hz"));
    integration.validate();
}

ArmSimulation::ArmSimulation(const ArmSetup& setup, const SimulationSettings& settings,
                             std::vector<ActivationProfile> excitations)
    : setup_(setup), settings_(settings) {
    settings_.validate(setup.arm);
    setup_.arm.handLoad = settings_.handLoad;
    const int n = setup_.getNumMuscles();
    if (excitations.empty()) excitations.assign(n, ActivationProfile::constant(0.0));
    if (int(excitations.size()) != n)
        throw InputError("excitation: " + std::to_string(excitations.size()) + " profiles for a model with " +
                         std::to_string(n) + " muscles: expected one per muscle");
    model_ = std::make_unique<MuscleArm>(setup_, std::move(excitations));
    const ArmModel& arm = model_->getArm();
    state_ = std::make_unique<State>(model_->getDefaultState());
    State& s = *state_;
    if (!std::isnan(settings_.forearmRotationDeg)) arm.lockForearmRotation(s, degToRad(settings_.forearmRotationDeg));
    if (settings_.lockedElbow) {
        arm.lockElbow(s, settings_.elbowAngle);
    } else {
        arm.setElbowAngle(s, settings_.elbowAngle);
        arm.setElbowAngularVelocity(s, settings_.elbowVelocity);
    }
    if (settings_.startSteady) model_->setSteadyMuscleStates(s);
    else model_->setInitialMuscleStates(s);
    t0_ = s.getTime();

    std::vector<std::string> columns = {"time_s", "elbow_angle_deg", "elbow_velocity_degps", "holding_torque_Nm"};
    if (setup_.arm.forearmRotation.enabled) columns.push_back("forearm_holding_torque_Nm");
    for (const char* what : {"excitation_", "active_fraction_"})
        for (int i = 0; i < n; ++i) columns.push_back(what + model_->getMuscleName(i));
    for (int i = 0; i < n; ++i) columns.push_back("force_" + model_->getMuscleName(i) + "_N");
    for (int i = 0; i < n; ++i) columns.push_back("fascicle_length_" + model_->getMuscleName(i) + "_m");
    for (const std::string& c : model_->getStateColumnNames()) columns.push_back(c);
    samples_ = Table(columns);
    recordSample(s);
    lastSample_ = 0;
}

ArmSimulation::~ArmSimulation() = default;

double ArmSimulation::getTime() const { return state_->getTime(); }
double ArmSimulation::getElbowAngle() const { return model_->getArm().getElbowAngle(*state_); }
double ArmSimulation::getElbowVelocity() const { return model_->getArm().getElbowAngularVelocity(*state_); }

void ArmSimulation::setElbowAngle(double theta) {
    const ArmParameters& a = setup_.arm;
    checkField("elbow_angle_deg", cleanDegrees(theta), Bound::closed(a.minElbowAngleDeg, a.maxElbowAngleDeg, "deg"));
    if (settings_.lockedElbow) model_->getArm().lockElbow(*state_, theta);
    else model_->getArm().setElbowAngle(*state_, theta);
}

void ArmSimulation::setElbowVelocity(double thetaDot) {
    checkField("elbow_velocity_degps", cleanDegrees(thetaDot), Bound::closed(-2000, 2000, "deg/s"));
    if (settings_.lockedElbow && thetaDot != 0)
        throw FieldError("elbow_velocity_degps", "= " + formatNumber(cleanDegrees(thetaDot)) +
                                                     " deg/s on a locked elbow: expected 0");
    if (!settings_.lockedElbow) model_->getArm().setElbowAngularVelocity(*state_, thetaDot);
}

std::vector<double> ArmSimulation::getMuscleStates() const {
    std::vector<double> y;
    model_->appendMuscleStates(*state_, y);
    return y;
}

std::vector<std::string> ArmSimulation::getMuscleStateNames() const {
    std::vector<std::string> names = model_->getStateColumnNames();
    for (std::string& n : names) n = n.substr(kStateColumnPrefix.size());
    return names;
}

void ArmSimulation::setState(const double* theta, const double* thetaDot, const std::vector<double>* muscleStates) {
    const State saved = *state_;
    try {
        if (theta) setElbowAngle(*theta);
        if (thetaDot) setElbowVelocity(*thetaDot);
        if (muscleStates) setMuscleStates(*muscleStates);
    } catch (...) {
        *state_ = saved;   // the state as it was, whatever the checks allowed it to be
        throw;
    }
}

void ArmSimulation::setMuscleStates(const std::vector<double>& y) {
    const std::vector<std::string> names = getMuscleStateNames();
    if (y.size() != names.size())
        throw InputError("muscle states: " + std::to_string(y.size()) + " values: expected " +
                         std::to_string(names.size()) + " (" + names.front() + " .. " + names.back() + ")");
    for (std::size_t k = 0; k < y.size(); ++k)
        if (!std::isfinite(y[k])) throw InputError("muscle state " + names[k] + " = " + formatNumber(y[k]) + ": expected a finite value");
    State trial = *state_;
    model_->setMuscleStates(trial, y);
    try {
        model_->getSystem().realize(trial, Stage::Position);
        model_->checkMuscleStates(trial);
    } catch (const SimulationError& e) {
        throw InputError(std::string("muscle states: ") + e.what());
    }
    *state_ = std::move(trial);
}

std::vector<double> ArmSimulation::calcMuscleForces() const {
    model_->getSystem().realize(*state_, Stage::Position);
    std::vector<double> f;
    for (int i = 0; i < getNumMuscles(); ++i) f.push_back(model_->getMuscleForce(i).getForce(*state_));
    return f;
}

void ArmSimulation::setExcitations(std::vector<ActivationProfile> excitations) {
    if (int(excitations.size()) != getNumMuscles())
        throw InputError("excitation: " + std::to_string(excitations.size()) + " profiles for a model with " +
                         std::to_string(getNumMuscles()) + " muscles: expected one per muscle");
    for (int i = 0; i < getNumMuscles(); ++i) model_->updMuscleForce(i).setActivationProfile(std::move(excitations[i]));
    state_->invalidateAllCacheAtOrAbove(Stage::Dynamics);  // U enters the derivatives only
}

const ActivationProfile& ArmSimulation::getExcitation(int muscle) const {
    return model_->getMuscleForce(muscle).getActivationProfile();
}

void ArmSimulation::recordSample(const State& s) {
    const MultibodySystem& system = model_->getSystem();
    const ArmModel& arm = model_->getArm();
    const int n = getNumMuscles();
    const bool forearm = setup_.arm.forearmRotation.enabled;
    system.realize(s, settings_.lockedElbow ? Stage::Acceleration : Stage::Position);
    std::vector<double> row{s.getTime(), radToDeg(arm.getElbowAngle(s)), radToDeg(arm.getElbowAngularVelocity(s)),
                            settings_.lockedElbow ? arm.calcHoldingTorque(s) : NAN};
    if (forearm) row.push_back(settings_.lockedElbow ? arm.calcForearmHoldingTorque(s) : NAN);
    std::vector<MuscleOutputs> out;
    for (int i = 0; i < n; ++i) out.push_back(model_->getMuscleForce(i).calcOutputs(s));
    for (int i = 0; i < n; ++i) row.push_back(model_->getMuscleForce(i).getActivation(s));
    for (int i = 0; i < n; ++i) row.push_back(out[i].activeFraction);
    for (int i = 0; i < n; ++i) row.push_back(out[i].Fse);
    for (int i = 0; i < n; ++i) row.push_back(out[i].L * model_->getMuscle(i).getOptimalFascicleLength());
    model_->appendMuscleStates(s, row);
    samples_.appendRow(row);
}

// Times on the grid agree to this: a billionth of a sample interval, or a few ulps of t when that is more.
double ArmSimulation::calcGridTolerance(double t) const {
    return std::max(1e-9 / settings_.sampleRate, 64 * std::numeric_limits<double>::epsilon() * std::max(std::abs(t), std::abs(t0_)));
}

void ArmSimulation::integrate(double duration, double sampleRate) {
    const auto sample = [&](const State& s) {
        const double k = std::round((s.getTime() - t0_) * settings_.sampleRate);
        if (long(k) <= lastSample_ ||
            std::abs(s.getTime() - (t0_ + k / settings_.sampleRate)) > calcGridTolerance(s.getTime()))
            return;
        recordSample(s);
        lastSample_ = long(k);
    };
    // Steps and threshold passings; kinks of a piecewise-linear trace are left to the error control (a
    // restart at every row of a dense trace costs more than it gains).
    const std::vector<double> steps = findRestartTimes(*model_, true);
    IntegrationStats st;
    if (settings_.lockedElbow) {
        st = simulateSampled(model_->getSystem(), *state_, duration, sampleRate, steps, settings_.integration, sample,
                             [&](const State& s) { model_->checkMuscleStates(s); });
    } else {
        st = integrateCoupledMuscles(*model_, *state_, duration, sampleRate, steps, settings_.integration, false, sample);
    }
    stats_.steps += st.steps;
    stats_.restarts += st.restarts + 1;
    stats_.realizations += st.realizations;
    stats_.partialEvaluations += st.partialEvaluations;
    stats_.newtonIterations += st.newtonIterations;
    stats_.krylovIterations += st.krylovIterations;
}

void ArmSimulation::checkAdvance(double t) const {
    const double now = getTime();
    if (!(t >= now) || !std::isfinite(t))
        throw FieldError("time_s", "= " + formatNumber(t) + " s: expected a finite time at or after the simulation's (" +
                                     formatNumber(now) + " s)");
    if ((t - now) * settings_.sampleRate >= 1) calcNumSamples(t - now, settings_.sampleRate);  // at most a table's rows
}

IntegrationStats ArmSimulation::advanceTo(double t) {
    checkAdvance(t);
    const double now = getTime();
    const double rate = settings_.sampleRate, eps = calcGridTolerance(t);
    const IntegrationStats before = stats_;
    const State start = *state_;
    const int rows = samples_.getNumRows();
    const long last = lastSample_;
    try {
        // First to the next grid point t0 + k / rate (if the start is off the grid), then along the grid:
        // samples stay at t0 + k / rate however the calls cut the time.
        const double k = (now - t0_) * rate;
        const bool onGrid = std::abs(now - (t0_ + std::round(k) / rate)) <= eps;
        const double next = t0_ + std::ceil(k) / rate;
        double at = now;
        if (!onGrid && t - at > eps) {
            const double end = std::min(next, t);
            integrate(end - at, 1.0 / (end - at));
            at = getTime();
        }
        // Shorter than half a sample interval: no grid point inside, one step to t (its end is not recorded).
        if (t - at > eps) integrate(t - at, (t - at) * rate < 1 ? 1.0 / (t - at) : rate);
    } catch (...) {
        *state_ = start;
        samples_.truncateRows(rows);
        lastSample_ = last;
        stats_ = before;
        throw;
    }
    IntegrationStats delta;
    delta.steps = stats_.steps - before.steps;
    delta.restarts = stats_.restarts - before.restarts;
    delta.realizations = stats_.realizations - before.realizations;
    delta.partialEvaluations = stats_.partialEvaluations - before.partialEvaluations;
    delta.newtonIterations = stats_.newtonIterations - before.newtonIterations;
    delta.krylovIterations = stats_.krylovIterations - before.krylovIterations;
    return delta;
}

}  // namespace armsim
