#include "model/muscle_arm.h"

#include "basics/errors.h"
#include "model/geometry.h"

#include <cmath>

using namespace SimTK;

namespace armsim {

namespace {

Vec3 toVec3(const std::array<double, 3>& a) { return Vec3(a[0], a[1], a[2]); }

}  // namespace

MusclePath buildMusclePath(const ArmModel& arm, const MuscleSpec& muscle) {
    std::vector<PathElement> elements;
    for (const PathElementSpec& s : muscle.path) {
        PathElement e;
        e.kind = s.kind == PathElementSpec::Kind::Point      ? PathElement::Kind::Point
                 : s.kind == PathElementSpec::Kind::Cylinder ? PathElement::Kind::Cylinder
                                                             : PathElement::Kind::Sphere;
        e.body = s.body == ArmBody::UpperArm ? MobilizedBody(arm.getUpperArm())
                 : s.body == ArmBody::Forearm ? MobilizedBody(arm.getForearm())
                                              : MobilizedBody(arm.getRadius());
        e.location = toVec3(s.location);
        e.axis = UnitVec3(toVec3(s.axis));
        e.radius = s.radius;
        e.side = toVec3(s.side);
        e.winds = s.winds;
        if (s.isConditional()) {
            if (!arm.hasForearmRotation())
                throw InputError("muscle '" + muscle.params.name + "': " + s.label +
                                 " has active_rotation_deg but the arm has no forearm_rotation");
            e.joint = arm.getRadius();
            e.activeMin = degToRad(s.activeRotationDeg[0]);
            e.activeMax = degToRad(s.activeRotationDeg[1]);
        }
        e.label = s.label;
        elements.push_back(e);
    }
    try {
        return MusclePath(std::move(elements));
    } catch (const InputError& e) {
        throw InputError("muscle '" + muscle.params.name + "': " + e.what());
    }
}

double calcPathMomentArm(const SimbodyMatterSubsystem& matter, const MobilizedBody& joint, const State& s,
                         const PathGeometry& g) {
    return calcPathGeneralizedForces(matter, s, g)[joint.getFirstUIndex(s)];
}

// ---- MuscleArm ----------------------------------------------------------------------------------

MuscleArm::MuscleArm(const ArmSetup& setup, std::vector<ActivationProfile> activations)
    : setup_(setup), arm_(std::make_unique<ArmModel>(setup.arm)) {
    if (int(activations.size()) != setup_.getNumMuscles())
        throw std::logic_error("MuscleArm: " + std::to_string(activations.size()) + " activation profiles for " +
                               std::to_string(setup_.getNumMuscles()) + " muscles");
    for (int i = 0; i < setup_.getNumMuscles(); ++i) {
        forces_.emplace_back(arm_->updForces(), setup_.buildMuscleModel(i), buildMusclePath(*arm_, setup_.muscles[i]),
                             std::move(activations[i]));
    }
    arm_->finalize();
}

MuscleArm::MuscleArm(const ArmSetup& setup, const ActivationProfile& activation)
    : MuscleArm(setup, std::vector<ActivationProfile>(setup.muscles.size(), activation)) {}

double MuscleArm::calcPathLength(const State& s, int i) const { return forces_.at(i).getPathLength(s); }

double MuscleArm::calcMomentArm(const State& s, int i) const {
    return calcPathMomentArm(arm_->getMatter(), arm_->getForearm(), s, forces_.at(i).calcPathGeometry(s));
}

double MuscleArm::calcForearmMomentArm(const State& s, int i) const {
    if (!arm_->hasForearmRotation()) return 0;
    return calcPathMomentArm(arm_->getMatter(), arm_->getRadius(), s, forces_.at(i).calcPathGeometry(s));
}

void MuscleArm::setSteadyMuscleStates(State& s) const {
    for (const MuscleForce& f : forces_) {
        try {
            f.setSteadyMuscleStates(s);
        } catch (const SimulationError& e) {
            throw SimulationError("muscle '" + f.getMuscle().getName() + "': " + e.what());
        }
    }
}

void MuscleArm::setInitialMuscleStates(State& s) const {
    for (const MuscleForce& f : forces_) f.setInitialMuscleStates(s);
}

void MuscleArm::checkMuscleStates(const State& s) const {
    for (const MuscleForce& f : forces_) f.checkMuscleStates(s);
}

std::vector<std::string> MuscleArm::getStateColumnNames() const {
    std::vector<std::string> names;
    for (int i = 0; i < getNumMuscles(); ++i)
        for (const std::string& n : getMuscle(i).getStateNames())
            names.push_back(getNumMuscles() == 1 ? "state_" + n : "state_" + getMuscleName(i) + "_" + n);
    return names;
}

void MuscleArm::appendMuscleStates(const State& s, std::vector<double>& row) const {
    for (const MuscleForce& f : forces_) {
        const std::vector<double> y = f.getMuscleStates(s);
        row.insert(row.end(), y.begin(), y.end());
    }
}

void MuscleArm::setMuscleStates(State& s, const std::vector<double>& y) const {
    std::size_t at = 0;
    for (const MuscleForce& f : forces_) {
        const std::size_t n = std::size_t(f.getMuscle().getNumStates());
        if (at + n > y.size()) throw std::logic_error("MuscleArm::setMuscleStates: too few values");
        f.setMuscleStates(s, std::vector<double>(y.begin() + at, y.begin() + at + n));
        at += n;
    }
}

// ---- ArmGeometry --------------------------------------------------------------------------------

ArmGeometry::ArmGeometry(const ArmSetup& setup) : arm_(setup.arm) {
    for (const MuscleSpec& m : setup.muscles) {
        paths_.push_back(buildMusclePath(arm_, m));
        names_.push_back(m.params.name);
    }
    state_ = arm_.finalize();
    arm_.getSystem().realize(state_, Stage::Position);
}

void ArmGeometry::setElbowAngle(double theta) {
    arm_.setElbowAngle(state_, theta);
    arm_.getSystem().realize(state_, Stage::Position);
}

PathGeometry ArmGeometry::calcPathGeometry(int i) const { return paths_.at(i).calcGeometry(state_, names_.at(i)); }

double ArmGeometry::calcMomentArm(const PathGeometry& g) const {
    return calcPathMomentArm(arm_.getMatter(), arm_.getForearm(), state_, g);
}

void ArmGeometry::setForearmRotation(double phi) {
    arm_.lockForearmRotation(state_, phi);
    arm_.getSystem().realize(state_, Stage::Position);
}

double ArmGeometry::calcForearmMomentArm(const PathGeometry& g) const {
    if (!arm_.hasForearmRotation()) return 0;
    return calcPathMomentArm(arm_.getMatter(), arm_.getRadius(), state_, g);
}

std::vector<double> findRestartTimes(const MuscleArm& model, bool stepsOnly) {
    std::vector<double> times;
    for (int i = 0; i < model.getNumMuscles(); ++i) {
        const std::vector<double> t =
            findRestartTimes(model.getMuscle(i), model.getMuscleForce(i).getActivationProfile(), stepsOnly);
        times.insert(times.end(), t.begin(), t.end());
    }
    return times;
}

void resolveMaxPathLengths(ArmSetup& setup) {
    bool any = false;
    for (const MuscleSpec& m : setup.muscles) any = any || m.maxPathFromRange;
    if (!any) return;
    ArmGeometry geometry(setup);
    const double lo = degToRad(setup.arm.minElbowAngleDeg), hi = degToRad(setup.arm.maxElbowAngleDeg);
    const int n = std::max(2, int(std::ceil(radToDeg(hi - lo))) + 1);
    auto lengthAt = [&](int i, double theta) {
        geometry.setElbowAngle(theta);
        return geometry.calcPathLength(i);
    };
    // With a forearm rotation: the longest over the elbow's range at each end of the rotation's range
    // and at the posture (the longest of the three).
    std::vector<double> postures = {0};
    const ArmParameters::ForearmRotation& rot = setup.arm.forearmRotation;
    if (rot.enabled) postures = {degToRad(rot.minDeg), degToRad(rot.postureDeg), degToRad(rot.maxDeg)};
    std::vector<double> longest(setup.muscles.size(), -1);
    for (double phi : postures) {
        if (rot.enabled) geometry.setForearmRotation(phi);
        for (int i = 0; i < setup.getNumMuscles(); ++i) {
            if (!setup.muscles[i].maxPathFromRange) continue;
            int best = 0;
            double bestLength = -1;
            for (int k = 0; k < n; ++k) {
                const double len = lengthAt(i, k + 1 == n ? hi : lo + k * (hi - lo) / (n - 1));
                if (len > bestLength) bestLength = len, best = k;
            }
            // Golden-section refinement around the best sample (the maximum may be inside the range).
            double a = lo + std::max(0, best - 1) * (hi - lo) / (n - 1);
            double b = best + 1 >= n ? hi : lo + (best + 1) * (hi - lo) / (n - 1);
            const double g = (std::sqrt(5.0) - 1) / 2;
            double c = b - g * (b - a), d = a + g * (b - a);
            double fc = lengthAt(i, c), fd = lengthAt(i, d);
            while (b - a > 1e-10) {
                if (fc > fd) { b = d; d = c; fd = fc; c = b - g * (b - a); fc = lengthAt(i, c); }
                else { a = c; c = d; fc = fd; d = a + g * (b - a); fd = lengthAt(i, d); }
            }
            longest[i] = std::max({longest[i], bestLength, fc, fd});
        }
    }
    for (int i = 0; i < setup.getNumMuscles(); ++i)
        if (setup.muscles[i].maxPathFromRange) setup.muscles[i].params.maxPathLength = longest[i];
}

}  // namespace armsim
