#include "model/mvc_curve.h"

#include "basics/bound.h"
#include "basics/errors.h"
#include "model/geometry.h"
#include "model/muscle_arm.h"

#include <cmath>
#include <map>
#include <memory>
#include <stdexcept>

namespace armsim {

double SteadyMvcCurve::calcFlexorShare(int a, int m) const {
    double flexion = 0;
    for (const SteadyMusclePoint& p : points.at(a)) flexion += std::max(0.0, p.torque);
    const double t = points.at(a).at(m).torque;
    return flexion > 0 ? std::max(0.0, t) / flexion : 0.0;
}

MvcGeometry calcMvcGeometry(const ArmSetup& setup, const std::vector<double>& flexionDeg, double rotationDeg) {
    MvcGeometry g;
    g.flexionDeg = flexionDeg;
    ArmGeometry geometry(setup);
    const ArmParameters::ForearmRotation& rot = setup.arm.forearmRotation;
    if (rot.enabled) {
        g.rotationDeg = std::isnan(rotationDeg) ? rot.postureDeg : rotationDeg;
        if (!(g.rotationDeg >= rot.minDeg - 1e-9 && g.rotationDeg <= rot.maxDeg + 1e-9))
            throw InputError("forearm rotation " + formatNumber(g.rotationDeg) + " deg is outside the range [" +
                             formatNumber(rot.minDeg) + ", " + formatNumber(rot.maxDeg) + "] deg of model '" +
                             setup.name + "'");
        geometry.setForearmRotation(degToRad(g.rotationDeg));
    }
    const double lo = setup.arm.getMinFlexionDeg(), hi = setup.arm.getMaxFlexionDeg();
    std::map<double, std::size_t> done;  // an angle met before: its row again (data repeat a few angles)
    for (double q : flexionDeg) {
        if (!(q >= lo - 1e-9 && q <= hi + 1e-9))
            throw InputError("flexion angle " + formatNumber(q) + " deg is outside the elbow's range [" +
                             formatNumber(lo) + ", " + formatNumber(hi) + "] deg of model '" + setup.name + "'");
        if (const auto it = done.find(q); it != done.end()) {
            g.pathLength.push_back(g.pathLength[it->second]);
            g.momentArm.push_back(g.momentArm[it->second]);
            g.forearmMomentArm.push_back(g.forearmMomentArm[it->second]);
            continue;
        }
        if ((done.size() & 63) == 63) checkInterruption();
        done.emplace(q, g.pathLength.size());
        geometry.setElbowAngle(elbowAngleFromFlexion(degToRad(q)));
        std::vector<double> P, h, r;
        for (int i = 0; i < setup.getNumMuscles(); ++i) {
            const PathGeometry path = geometry.calcPathGeometry(i);
            P.push_back(path.length);
            h.push_back(geometry.calcMomentArm(path));
            r.push_back(geometry.calcForearmMomentArm(path));
        }
        g.pathLength.push_back(std::move(P));
        g.momentArm.push_back(std::move(h));
        g.forearmMomentArm.push_back(std::move(r));
    }
    return g;
}

struct SteadyCurveCacheAccess {
    using Muscle = SteadyCurveCache::Muscle;
    static std::vector<Muscle>& getMuscles(SteadyCurveCache& c) { return c.muscles_; }
    static void count(SteadyCurveCache& c, bool reused) { ++(reused ? c.reused_ : c.solved_); }
};

namespace {

// Every muscle at its steady state at each angle, at the activation agonist(a, i) ? VA : CC; states
// from the cache where their inputs are unchanged.
template <class IsAgonist>
SteadyMvcCurve calcSteadyCurve(const std::vector<MuscleSpec>& muscles, const MvcGeometry& geometry,
                               const SubjectEffort& subject, IsAgonist isAgonist, SteadyCurveCache* cache,
                               bool sensitivities = false) {
    checkField("voluntary activation", subject.voluntaryActivation, Bound::closed(0, 1));
    checkField("co-contraction", subject.coContraction, Bound::closed(0, 1));
    const std::size_t nm = muscles.size(), na = geometry.flexionDeg.size();
    SteadyMvcCurve curve;
    curve.flexionDeg = geometry.flexionDeg;
    for (const MuscleSpec& m : muscles) curve.muscles.push_back(m.params.name);
    curve.points.assign(na, std::vector<SteadyMusclePoint>(nm));
    std::vector<SteadyCurveCacheAccess::Muscle> local;
    std::vector<SteadyCurveCacheAccess::Muscle>& memory = cache ? SteadyCurveCacheAccess::getMuscles(*cache) : local;
    memory.resize(nm);
    // Every muscle is validated before any is solved (a muscle built afresh, or a cached one whose F0
    // inputs changed); a cached muscle is built only when one of its states must be solved.
    // Muscles of another model than Virtual Muscle are built afresh and never reuse cached states.
    std::vector<std::shared_ptr<const MuscleModel>> model(nm);
    auto build = [&](std::size_t i) { model[i] = buildMuscleModel(muscles[i]); };
    std::vector<double> F0(nm);
    for (std::size_t i = 0; i < nm; ++i) {
        const MuscleParameters& params = muscles[i].params;
        auto& mem = memory[i];
        const bool virtualMuscle = muscles[i].muscleModel == kDefaultMuscleModel;
        if (!cache || !virtualMuscle || !mem.valid || mem.points.size() != na || !haveSameNormalizedStates(mem.params, params)) {
            mem.valid = false;
            mem.points.assign(na, {});
            build(i);
        } else if (params.mass != mem.params.mass || params.coefficients.sigma != mem.params.coefficients.sigma ||
                   params.coefficients.density != mem.params.coefficients.density) {
            params.validate();
        }
        F0[i] = virtualMuscle ? calcMaxIsometricForce(params) : model[i]->getF0();
    }
    for (std::size_t a = 0; a < na; ++a)
        for (std::size_t i = 0; i < nm; ++i) {
            if (i == 0 && (a & 63) == 63) checkInterruption();   // a fine sweep (18,001 angles) stops promptly
            SteadyMusclePoint& p = curve.points[a][i];
            p.pathLength = geometry.pathLength[a][i];
            p.momentArm = geometry.momentArm[a][i];
            p.forearmMomentArm = geometry.forearmMomentArm.empty() ? 0.0 : geometry.forearmMomentArm[a][i];
            p.activation = isAgonist(a, i) ? subject.voluntaryActivation : subject.coContraction;
            auto& q = memory[i].points[a];
            const bool reuse = q.valid && q.pathLength == p.pathLength && q.activation == p.activation;
            if (!reuse) {
                if (!model[i]) build(i);
                const SteadyState st = model[i]->calcSteadyState(p.pathLength, p.activation);
                if (!st.converged)
                    throw SimulationError("muscle '" + curve.muscles[i] + "' at " + formatNumber(geometry.flexionDeg[a]) +
                                          " deg flexion: " + st.message);
                q = {true, p.pathLength, p.activation, st.L, st.normalizedForce, false, {}};
            }
            if (sensitivities) {
                if (!q.haveSensitivity) {
                    if (!model[i]) build(i);
                    q.sensitivity = model[i]->calcSteadySensitivity(p.pathLength, p.activation, q.L);
                    q.haveSensitivity = true;
                }
                p.sensitivity = q.sensitivity;
            }
            if (cache) SteadyCurveCacheAccess::count(*cache, reuse);
            p.fibreLength = q.L;
            p.force = F0[i] * q.normalizedForce;
            p.torque = p.momentArm * p.force;
            p.forearmTorque = p.forearmMomentArm * p.force;
        }
    for (std::size_t i = 0; i < nm; ++i) {
        memory[i].params = muscles[i].params;
        memory[i].valid = muscles[i].muscleModel == kDefaultMuscleModel;
    }
    for (std::size_t a = 0; a < na; ++a) {
        double total = 0, forearm = 0;
        for (std::size_t i = 0; i < nm; ++i) {
            total += curve.points[a][i].torque;
            forearm += curve.points[a][i].forearmTorque;
        }
        curve.totalTorque.push_back(total);
        curve.totalForearmTorque.push_back(forearm);
    }
    return curve;
}

}  // namespace

Effort getEffortOf(MuscleGroup group) {
    if (group == MuscleGroup::Forearm) throw std::logic_error("getEffortOf: the forearm group drives no elbow effort");
    return group == MuscleGroup::Flexor ? Effort::Flexion : Effort::Extension;
}

std::vector<std::vector<bool>> findAgonists(const std::vector<MuscleSpec>& muscles, const MvcGeometry& geometry,
                                            Effort effort) {
    std::vector<std::vector<bool>> out(geometry.flexionDeg.size());
    for (std::size_t a = 0; a < out.size(); ++a)
        for (std::size_t i = 0; i < muscles.size(); ++i) {
            const double r = geometry.forearmMomentArm.empty() || geometry.forearmMomentArm[a].empty()
                                 ? 0.0 : geometry.forearmMomentArm[a][i];
            out[a].push_back(isAgonistOf(effort, muscles[i].group, r));
        }
    return out;
}

SteadyMvcCurve calcSteadyMvcCurve(const std::vector<MuscleSpec>& muscles, const MvcGeometry& geometry, Effort effort,
                                  const std::vector<std::vector<bool>>& agonists, const SubjectEffort& subject,
                                  SteadyCurveCache* cache, bool sensitivities) {
    if (agonists.size() != geometry.flexionDeg.size())
        throw std::logic_error("calcSteadyMvcCurve: one agonist row per angle expected");
    SteadyMvcCurve c = calcSteadyCurve(muscles, geometry, subject,
                                       [&](std::size_t a, std::size_t i) { return bool(agonists[a].at(i)); }, cache,
                                       sensitivities);
    c.effort = effort;
    return c;
}

SteadyMvcCurve calcSteadyMvcCurve(const std::vector<MuscleSpec>& muscles, const MvcGeometry& geometry, Effort effort,
                                  const SubjectEffort& subject) {
    return calcSteadyMvcCurve(muscles, geometry, effort, findAgonists(muscles, geometry, effort), subject);
}

SteadyMvcCurve calcSteadyMvcCurve(const std::vector<MuscleSpec>& muscles, const MvcGeometry& geometry,
                                  MuscleGroup effort, const SubjectEffort& subject) {
    return calcSteadyMvcCurve(muscles, geometry, getEffortOf(effort), subject);
}

SteadyMvcCurve calcSteadyMvcCurve(const ArmSetup& setup, Effort effort, const SubjectEffort& subject,
                                  const std::vector<double>& flexionDeg, double rotationDeg) {
    return calcSteadyMvcCurve(setup.muscles, calcMvcGeometry(setup, flexionDeg, rotationDeg), effort, subject);
}

SteadyMvcCurve calcSteadyMvcCurve(const ArmSetup& setup, MuscleGroup effort, const SubjectEffort& subject,
                                  const std::vector<double>& flexionDeg) {
    return calcSteadyMvcCurve(setup.muscles, calcMvcGeometry(setup, flexionDeg), effort, subject);
}

}  // namespace armsim
