#include "model/osim_trial.h"

#include "model/osim_anatomy.h"

#include "basics/bound.h"
#include "basics/errors.h"
#include "basics/format.h"
#include "model/osim_arm.h"
#include "model/trial.h"
#include "muscles/simbody_isometric.h"

#include <cmath>
#include <map>
#include <utility>

namespace armsim {

namespace {

constexpr double kDeg = 3.14159265358979323846 / 180;

int findTrialCoordinate(const OsimArm& arm, const std::string& name) {
    if (arm.getNumMuscles() == 0)
        throw InputError("model " + arm.getModel().name + " (" + arm.getModel().file + ") has no muscles: a trial excites "
                         "muscles (`armsim forward` runs a model without them)");
    std::string names;
    for (int i = 0; i < arm.getNumCoordinates(); ++i) names += (i ? ", " : "") + arm.getCoordinate(i).name;
    if (arm.getNumCoordinates() == 0) throw InputError("model " + arm.getModel().name + " has no moving coordinate");
    if (name.empty()) {
        if (arm.getNumCoordinates() == 1) {
            if (!arm.getCoordinate(0).rotational)
                throw FieldError("coordinate", "'" + arm.getCoordinate(0).name + "' (the model's only one): translational; "
                                               "expected a rotational coordinate");
            return 0;
        }
        if (arm.getNumCoordinates() == 0) throw InputError("model " + arm.getModel().name + " has no moving coordinate");
        throw FieldError("coordinate", "not given: model " + arm.getModel().name + " has " +
                                           std::to_string(arm.getNumCoordinates()) + " coordinates (" + names +
                                           "): name the one to lock and act about");
    }
    const int i = arm.findCoordinate(name);
    if (i < 0) throw FieldError("coordinate", "'" + name + "': not a coordinate of " + arm.getModel().name + " (" + names + ")");
    if (!arm.getCoordinate(i).rotational)
        throw FieldError("coordinate", "'" + name + "': translational; expected a rotational coordinate");
    return i;
}

double mean(const std::vector<double>& v, std::size_t first) {
    double s = 0;
    for (std::size_t i = first; i < v.size(); ++i) s += v[i];
    return s / double(v.size() - first);
}

}  // namespace

void OsimIsometricTrialSettings::validate(const OsimArm& arm) const {
    const int j = findTrialCoordinate(arm, coordinate);
    const auto [lo, hi] = getOsimCoordinateRangeDeg(arm, j);
    checkField("angle_deg", angleDeg, Bound::closed(lo, hi, "deg"));
    if (direction != 1 && direction != -1)
        throw FieldError("direction", "= " + std::to_string(direction) + ": expected +1 or -1");
    checkIsometricEffort(activation, antagonistActivation, restDuration, riseTime, holdDuration, sampleRate, averagingWindow);
    integration.validate();
}

OsimIsometricTrialResult runOsimIsometricTrial(const OsimModel& file, const OsimIsometricTrialSettings& settings) {
    // Every coordinate held: the trial's at the angle, the others at their defaults; the paths are then
    // fixed and the System is only needed for the geometry.
    const OsimArm probe(file, {}, settings.muscleModel);
    settings.validate(probe);
    const int j = findTrialCoordinate(probe, settings.coordinate);
    const std::string coordinate = probe.getCoordinate(j).name;
    const int n = probe.getNumMuscles();

    OsimIsometricTrialResult result;
    OsimIsometricSummary& sum = result.summary;
    sum.coordinate = coordinate;
    sum.angleDeg = settings.angleDeg;
    SimTK::State s = probe.getDefaultState();
    probe.setCoordinateValue(s, j, settings.angleDeg * kDeg);
    probe.getSystem().realize(s, SimTK::Stage::Position);
    std::vector<const MuscleModel*> muscles;
    for (int i = 0; i < n; ++i) {
        sum.muscles.push_back(probe.getMuscleName(i));
        sum.pathLengths.push_back(probe.calcPathLength(s, i));
        sum.momentArms.push_back(probe.calcMomentArm(s, i, j));
        sum.agonists.push_back(isOsimAgonist(settings.direction, sum.momentArms[i]));
        muscles.push_back(&probe.getMuscleForce(i).getMuscle());
        muscles[i]->checkPathLength(sum.pathLengths[i]);
    }

    // Excitations: 0 at rest, then each muscle to its level (a step, or a ramp over riseTime).
    const double onset = settings.restDuration;
    auto riseTo = [&](double U) {
        return settings.riseTime > 0 ? ActivationProfile::ramp(onset, onset + settings.riseTime, 0.0, U)
                                     : ActivationProfile::step(onset, 0.0, U);
    };
    std::vector<ActivationProfile> excitation;
    for (int i = 0; i < n; ++i) excitation.push_back(riseTo(sum.agonists[i] ? settings.activation : settings.antagonistActivation));
    const ActivationProfile agonistProfile = riseTo(settings.activation);

    // y: each muscle's states in turn, from its rest state at its path length.
    OdeBlocks f;
    std::vector<double> y;
    for (int i = 0; i < n; ++i) {
        f.first.push_back(int(y.size()));
        f.size.push_back(muscles[i]->getNumStates());
        const std::vector<double> y0 = muscles[i]->calcInitialState(sum.pathLengths[i]);
        y.insert(y.end(), y0.begin(), y0.end());
    }
    f.banded = n > 1;
    const std::vector<double>& P = sum.pathLengths;
    f.calcBlock = [&](int b, double t, const double* yIn, double* ydot) {
        muscles[b]->calcStateDerivative(P[b], excitation[b].getValue(t), yIn + f.first[b], ydot + f.first[b]);
    };

    std::vector<std::string> columns{"time_s", "excitation", coordinate + "_deg", "muscle_torque_Nm", "tared_torque_Nm"};
    const std::pair<const char*, const char*> perMuscle[] = {
        {"force_", "_N"}, {"torque_", "_Nm"}, {"excitation_", ""}, {"activation_", ""}, {"fiber_length_", "_m"}};
    for (const auto& [prefix, unit] : perMuscle)
        for (int i = 0; i < n; ++i) columns.push_back(prefix + sum.muscles[i] + unit);
    result.series = Table(columns);
    result.series.reserveRows(int(std::lround(settings.getDuration() * settings.sampleRate)) + 1);
    std::vector<double> row, F(n), torque(n), U(n), a(n), L(n);
    bool haveTare = false;
    auto sample = [&](double t, const double* yIn) {
        double total = 0;
        for (int i = 0; i < n; ++i) {
            const double* yi = yIn + f.first[i];
            U[i] = excitation[i].getValue(t);
            F[i] = muscles[i]->calcForce(P[i], yi);
            torque[i] = sum.momentArms[i] * F[i];
            a[i] = muscles[i]->calcOutputs(P[i], U[i], yi).activeFraction;
            L[i] = muscles[i]->calcFascicleLength(P[i], yi);
            total += torque[i];
        }
        if (!haveTare) sum.restTorque = total, haveTare = true;
        row.assign({t, agonistProfile.getValue(t), settings.angleDeg, total, total - sum.restTorque});
        for (const std::vector<double>* v : {&F, &torque, &U, &a, &L}) row.insert(row.end(), v->begin(), v->end());
        result.series.appendRow(row);
    };
    std::vector<double> restarts;
    for (int i = 0; i < n; ++i) {
        const std::vector<double> r = findRestartTimes(*muscles[i], excitation[i]);
        restarts.insert(restarts.end(), r.begin(), r.end());
    }
    sum.stats = integrateSampled(f, 0.0, y, settings.getDuration(), settings.sampleRate, restarts,
                                 settings.integration, sample, [&](double t, const double* yIn) {
                                     for (int i = 0; i < n; ++i) muscles[i]->checkStates(t, yIn + f.first[i]);
                                 });

    const Table& t = result.series;
    const std::vector<double> time = t.getColumn("time_s");
    const double from = time.back() - settings.averagingWindow - 1e-9;
    std::size_t first = 0;
    while (first < time.size() && time[first] < from) ++first;
    sum.meanMuscleTorque = mean(t.getColumn("muscle_torque_Nm"), first);
    sum.meanTaredTorque = mean(t.getColumn("tared_torque_Nm"), first);
    for (int i = 0; i < n; ++i) sum.meanForces.push_back(mean(t.getColumn("force_" + sum.muscles[i] + "_N"), first));
    return result;
}

void OsimFreeMovementSettings::validate(const OsimArm& arm) const {
    const int j = findTrialCoordinate(arm, coordinate);
    const OsimCoordinate& c = arm.getCoordinate(j);
    if (c.locked)
        throw FieldError("coordinate", "'" + c.name + "' is locked in " + arm.getModel().file + " (line " + std::to_string(c.line) +
                                           "): a free movement needs it free (an isometric trial holds it at an angle)");
    const auto [lo, hi] = getOsimCoordinateRangeDeg(arm, j);
    if (!std::isnan(initialAngleDeg)) checkField("initial_angle_deg", initialAngleDeg, Bound::closed(lo, hi, "deg"));
    checkField("initial_velocity_degps", initialVelocityDegps, Bound::closed(-2000, 2000, "deg/s"));
    if (direction != 1 && direction != -1)
        throw FieldError("direction", "= " + std::to_string(direction) + ": expected +1 or -1");
    checkField("activation", activation, Bound::closed(0, 1));
    checkField("onset", onset, Bound::nonNegative("s"));
    checkField("rise", rise, Bound::nonNegative("s"));
    checkField("duration", duration, Bound::positive("s"));
    if (activation > 0 && !(onset < duration))
        throw FieldError("onset", "= " + formatNumber(onset) + " s is not before the end of the movement (duration " +
                                      formatNumber(duration) + " s): expected an onset before the end (the excitation "
                                      "would never start)");
    checkField("sample_rate", sampleRate, Bound::positive("Hz"));
    calcNumSamples(duration, sampleRate);
    integration.validate();
}

Table runOsimFreeMovement(const OsimModel& file, const OsimFreeMovementSettings& settings, IntegrationStats* stats) {
    OsimModel model = file;
    std::string coordinate;
    std::vector<bool> agonists;
    {   // the settings checked, and the agonists found at the start pose
        const OsimArm probe(model, {}, settings.muscleModel);
        settings.validate(probe);
        const int j = findTrialCoordinate(probe, settings.coordinate);
        coordinate = probe.getCoordinate(j).name;
        SimTK::State s = probe.getDefaultState();
        if (!std::isnan(settings.initialAngleDeg)) probe.setCoordinateValue(s, j, settings.initialAngleDeg * kDeg);
        probe.getSystem().realize(s, SimTK::Stage::Position);
        for (int i = 0; i < probe.getNumMuscles(); ++i)
            agonists.push_back(isOsimAgonist(settings.direction, probe.calcMomentArm(s, i, j)));
    }
    // The other coordinates held at their defaults (the model's default pose, which also places the
    // wraps, is unchanged); the free one starts where asked, in the state.
    for (OsimJoint& joint : model.joints)
        for (OsimCoordinate& c : joint.coordinates)
            if (c.name != coordinate) c.locked = true;
    const ActivationProfile agonist = settings.rise > 0
        ? ActivationProfile::ramp(settings.onset, settings.onset + settings.rise, 0.0, settings.activation)
        : ActivationProfile::step(settings.onset, 0.0, settings.activation);
    std::map<std::string, ActivationProfile> excitations;
    for (std::size_t i = 0; i < model.muscles.size(); ++i)
        excitations[model.muscles[i].name] = agonists[i] ? agonist : ActivationProfile::constant(0.0);
    const OsimArm arm(model, excitations, settings.muscleModel);
    const int free = arm.findCoordinate(coordinate);
    const int n = arm.getNumMuscles();
    SimTK::State s = arm.getDefaultState();
    if (!std::isnan(settings.initialAngleDeg)) arm.setCoordinateValue(s, free, settings.initialAngleDeg * kDeg);
    arm.setCoordinateSpeed(s, free, settings.initialVelocityDegps * kDeg);
    arm.getSystem().realize(s, SimTK::Stage::Velocity);
    for (int i = 0; i < n; ++i) arm.getMuscleForce(i).setSteadyMuscleStates(s);   // equilibrium at U(0)

    std::vector<std::string> columns{"time_s", "excitation", coordinate + "_deg", coordinate + "_speed_degps"};
    const std::pair<const char*, const char*> perMuscle[] = {{"force_", "_N"}, {"activation_", ""}, {"fiber_length_", "_m"}};
    for (const auto& [prefix, unit] : perMuscle)
        for (int i = 0; i < n; ++i) columns.push_back(prefix + arm.getMuscleName(i) + unit);
    Table t(columns);
    t.reserveRows(int(std::lround(settings.duration * settings.sampleRate)) + 1);
    std::vector<double> row;
    auto sample = [&](const SimTK::State& x) {
        arm.getSystem().realize(x, SimTK::Stage::Dynamics);
        row.assign({x.getTime(), agonist.getValue(x.getTime()), arm.getCoordinateValue(x, free) / kDeg,
                    arm.getCoordinateSpeed(x, free) / kDeg});
        for (int i = 0; i < n; ++i) row.push_back(arm.getMuscleForce(i).getForce(x));
        for (int i = 0; i < n; ++i) row.push_back(arm.getMuscleForce(i).calcOutputs(x).activeFraction);
        for (int i = 0; i < n; ++i) row.push_back(arm.getMuscleForce(i).getFascicleLength(x));
        t.appendRow(row);
        if (settings.progress) settings.progress(x.getTime());
    };
    auto check = [&](const SimTK::State& x) {
        for (int i = 0; i < n; ++i) {
            const MuscleForce& f = arm.getMuscleForce(i);
            const std::vector<double> y = f.getMuscleStates(x);
            f.getMuscle().checkStates(x.getTime(), y.data());
        }
    };
    std::vector<double> restarts;
    for (int i = 0; i < n; ++i) {
        const MuscleForce& f = arm.getMuscleForce(i);
        const std::vector<double> r = findRestartTimes(f.getMuscle(), f.getActivationProfile());
        restarts.insert(restarts.end(), r.begin(), r.end());
    }
    const IntegrationStats st = simulateSampled(arm.getSystem(), s, settings.duration, settings.sampleRate, restarts,
                                                settings.integration, sample, check);
    // The sample grid may end short of the duration (duration x rate rounded): the run is done all the same.
    if (settings.progress && t.get(t.getNumRows() - 1, 0) < settings.duration) settings.progress(settings.duration);
    if (stats) *stats = st;
    return t;
}

}  // namespace armsim
