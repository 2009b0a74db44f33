#include "model/mvc_curve.h"

#include "basics/bound.h"
#include "model/geometry.h"
#include "model/muscle_arm.h"

#include <cmath>

namespace armsim {

double SteadyMvcCurve::calcFlexorShare(int a, int m) const {
    double flexion = 0;
    for (const SteadyMusclePoint& p : points.at(a)) flexion += std::max(0.0, p.torque);
    const double t = points.at(a).at(m).torque;
    return flexion > 0 ? std::max(0.0, t) / flexion : 0.0;
}

MvcGeometry calcMvcGeometry(const ArmSetup& setup, const std::vector<double>& flexionDeg) {
    MvcGeometry g;
    g.flexionDeg = flexionDeg;
    ArmGeometry geometry(setup);
    const double lo = setup.arm.getMinFlexionDeg(), hi = setup.arm.getMaxFlexionDeg();
    for (double q : flexionDeg) {
        if (!(q >= lo - 1e-9 && q <= hi + 1e-9))
            throw InputError("flexion angle " + formatNumber(q) + " deg is outside the elbow's range [" +
                             formatNumber(lo) + ", " + formatNumber(hi) + "] deg of model '" + setup.name + "'");
        geometry.setElbowAngle(elbowAngleFromFlexion(degToRad(q)));
        std::vector<double> P, h;
        for (int i = 0; i < setup.getNumMuscles(); ++i) {
            const PathGeometry path = geometry.calcPathGeometry(i);
            P.push_back(path.length);
            h.push_back(geometry.calcMomentArm(path));
        }
        g.pathLength.push_back(std::move(P));
        g.momentArm.push_back(std::move(h));
    }
    return g;
}

SteadyMvcCurve calcSteadyMvcCurve(const std::vector<MuscleSpec>& muscles, const MvcGeometry& geometry,
                                  MuscleGroup effort, const SubjectEffort& subject) {
    checkField("voluntary activation", subject.voluntaryActivation, Bound::closed(0, 1));
    checkField("co-contraction", subject.coContraction, Bound::closed(0, 1));
    SteadyMvcCurve curve;
    curve.effort = effort;
    curve.flexionDeg = geometry.flexionDeg;
    std::vector<VirtualMuscle> vm;
    for (const MuscleSpec& m : muscles) {
        vm.emplace_back(m.params);
        curve.muscles.push_back(m.params.name);
    }
    for (std::size_t a = 0; a < geometry.flexionDeg.size(); ++a) {
        std::vector<SteadyMusclePoint> row;
        double total = 0;
        for (std::size_t i = 0; i < muscles.size(); ++i) {
            SteadyMusclePoint p;
            p.pathLength = geometry.pathLength[a][i];
            p.momentArm = geometry.momentArm[a][i];
            p.activation = muscles[i].group == effort ? subject.voluntaryActivation : subject.coContraction;
            const SteadyState st = vm[i].calcSteadyState(p.pathLength, p.activation);
            if (!st.converged)
                throw SimulationError("muscle '" + curve.muscles[i] + "' at " + formatNumber(geometry.flexionDeg[a]) +
                                      " deg flexion: " + st.message);
            p.fibreLength = st.L;
            p.force = st.force;
            p.torque = p.momentArm * p.force;
            total += p.torque;
            row.push_back(p);
        }
        curve.points.push_back(std::move(row));
        curve.totalTorque.push_back(total);
    }
    return curve;
}

SteadyMvcCurve calcSteadyMvcCurve(const ArmSetup& setup, MuscleGroup effort, const SubjectEffort& subject,
                                  const std::vector<double>& flexionDeg) {
    return calcSteadyMvcCurve(setup.muscles, calcMvcGeometry(setup, flexionDeg), effort, subject);
}

}  // namespace armsim
