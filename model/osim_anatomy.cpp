#include "model/osim_anatomy.h"

#include "basics/errors.h"
#include "basics/format.h"
#include "model/osim_arm.h"
#include "model/osim_trial.h"

#include <algorithm>
#include <cmath>

namespace armsim {

namespace {

constexpr double kDeg = 3.14159265358979323846 / 180;

double roundDeg(double rad) { return std::round(rad / kDeg * 1e6) / 1e6; }

}  // namespace

int findOsimSweptCoordinate(const OsimArm& arm, const std::string& name) {
    std::string names;
    for (int i = 0; i < arm.getNumCoordinates(); ++i) names += (i ? ", " : "") + arm.getCoordinate(i).name;
    if (name.empty() && arm.getNumCoordinates() != 1) {
        throw InputError("--coordinate: model " + arm.getModel().name + " has " + std::to_string(arm.getNumCoordinates()) +
                         " coordinates (" + names + "): name the one to sweep");
    }
    const int i = name.empty() ? 0 : arm.findCoordinate(name);
    if (i < 0) throw InputError("--coordinate '" + name + "': not a coordinate of " + arm.getModel().name + " (" + names + ")");
    if (!arm.getCoordinate(i).rotational)
        throw InputError("--coordinate '" + arm.getCoordinate(i).name + "': translational; expected a rotational coordinate");
    return i;
}

std::array<double, 2> getOsimCoordinateRangeDeg(const OsimArm& arm, int j) {
    const auto range = arm.getCoordinate(j).range;
    return {roundDeg(range[0]), roundDeg(range[1])};
}

std::array<double, 2> getOsimCoordinateRangeDeg(const OsimModel& model, const std::string& coordinate,
                                                const std::string& muscleModel) {
    const OsimArm arm(model, {}, muscleModel);
    return getOsimCoordinateRangeDeg(arm, findOsimSweptCoordinate(arm, coordinate));
}

AnatomyCurves calcOsimAnatomyCurves(const OsimArm& arm, int j, const std::vector<double>& flexionDeg) {
    const int n = arm.getNumMuscles();
    if (n == 0) throw InputError("model " + arm.getModel().name + " (" + arm.getModel().file + ") has no muscles");
    AnatomyCurves c;
    for (int i = 0; i < n; ++i) c.muscles.push_back(arm.getMuscleName(i));
    c.volume.assign(n, kNaN);
    const auto [lo, hi] = getOsimCoordinateRangeDeg(arm, j);
    c.minFlexionDeg = lo;
    c.maxFlexionDeg = hi;
    c.flexionDeg = flexionDeg;
    SteadyMvcCurve* curves[2] = {&c.flexion, &c.extension};
    for (int k = 0; k < 2; ++k) {
        curves[k]->effort = k == 0 ? Effort::Flexion : Effort::Extension;
        curves[k]->muscles = c.muscles;
        curves[k]->flexionDeg = flexionDeg;
    }
    SimTK::State s = arm.getDefaultState();
    for (double deg : flexionDeg) {
        arm.setCoordinateValue(s, j, deg * kDeg);
        arm.getSystem().realize(s, SimTK::Stage::Position);
        std::vector<double> R(n), P(n);
        for (int i = 0; i < n; ++i) R[i] = arm.calcMomentArm(s, i, j), P[i] = arm.calcPathLength(s, i);
        c.momentArm.push_back(R);
        for (int k = 0; k < 2; ++k) {
            const int direction = k == 0 ? 1 : -1;
            std::vector<SteadyMusclePoint> row(n);
            double total = 0;
            for (int i = 0; i < n; ++i) {
                const MuscleModel& m = arm.getMuscleForce(i).getMuscle();
                const double u = isOsimAgonist(direction, R[i]) ? 1.0 : 0.0;
                const SteadyState ss = m.calcSteadyState(P[i], u);
                if (!ss.converged)
                    throw SimulationError("muscle " + arm.getMuscleName(i) + " at " + arm.getCoordinate(j).name + " = " +
                                          formatNumber(deg) + " deg: " + ss.message);
                row[i] = {P[i], R[i], u, ss.fascicleLength / m.getOptimalFascicleLength(), ss.force, ss.force * R[i], 0, 0, {}};
                total += row[i].torque;
            }
            curves[k]->points.push_back(row);
            curves[k]->totalTorque.push_back(total);
            curves[k]->totalForearmTorque.push_back(0);
        }
    }
    c.full = c.flexion;   // the flexion MVC is already at full excitation
    return c;
}

AnatomyCurves calcOsimAnatomyCurves(const OsimModel& model, const std::string& coordinate,
                                    const std::vector<double>& flexionDeg, const std::string& muscleModel) {
    const OsimArm arm(model, {}, muscleModel);
    const int j = findOsimSweptCoordinate(arm, coordinate);
    const auto [lo, hi] = getOsimCoordinateRangeDeg(arm, j);
    std::vector<double> angles;
    for (double deg : flexionDeg) {
        constexpr double kGridSlack = 1e-9;   // deg: a grid's last step may land a rounding error past the end
        if (!(deg >= lo - kGridSlack && deg <= hi + kGridSlack))
            throw InputError("angle " + formatNumber(deg) + " deg: outside " + arm.getCoordinate(j).name + "'s range [" +
                             formatNumber(lo) + ", " + formatNumber(hi) + "] deg");
        angles.push_back(std::clamp(deg, lo, hi));
    }
    AnatomyCurves c = calcOsimAnatomyCurves(arm, j, angles);
    c.flexionDeg = flexionDeg;
    c.flexion.flexionDeg = c.extension.flexionDeg = c.full.flexionDeg = flexionDeg;
    return c;
}

}  // namespace armsim
