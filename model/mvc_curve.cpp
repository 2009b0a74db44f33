#include "model/mvc_curve.h"

#include "model/geometry.h"
#include "model/muscle_arm.h"
#include "muscles/param_file.h"

#include <cmath>

namespace armsim {

double SteadyMvcCurve::calcFlexorShare(int a, int m) const {
    double flexion = 0;
    for (const SteadyMusclePoint& p : points.at(a)) flexion += std::max(0.0, p.torque);
    const double t = points.at(a).at(m).torque;
    return flexion > 0 ? std::max(0.0, t) / flexion : 0.0;
}

SteadyMvcCurve calcSteadyMvcCurve(const ArmSetup& setup, MuscleGroup effort, const SubjectEffort& subject,
                                  const std::vector<double>& flexionDeg) {
    checkField("voluntary activation", subject.voluntaryActivation, Bound::closed(0, 1));
    checkField("co-contraction", subject.coContraction, Bound::closed(0, 1));
    SteadyMvcCurve curve;
    curve.effort = effort;
    curve.flexionDeg = flexionDeg;
    ArmGeometry geometry(setup);
    std::vector<VirtualMuscle> muscles;
    for (int i = 0; i < setup.getNumMuscles(); ++i) {
        muscles.emplace_back(setup.calcMuscleParameters(i));
        curve.muscles.push_back(setup.muscles[i].params.name);
    }
    const double lo = setup.arm.getMinFlexionDeg(), hi = setup.arm.getMaxFlexionDeg();
    for (double q : flexionDeg) {
        if (!(q >= lo - 1e-9 && q <= hi + 1e-9))
            throw InputError("flexion angle " + formatNumber(q) + " deg is outside the elbow's range [" +
                             formatNumber(lo) + ", " + formatNumber(hi) + "] deg of model '" + setup.name + "'");
        geometry.setElbowAngle(elbowAngleFromFlexion(degToRad(q)));
        std::vector<SteadyMusclePoint> row;
        double total = 0;
        for (int i = 0; i < setup.getNumMuscles(); ++i) {
            SteadyMusclePoint p;
            const PathGeometry path = geometry.calcPathGeometry(i);
            p.pathLength = path.length;
            p.momentArm = geometry.calcMomentArm(path);
            p.activation = setup.muscles[i].group == effort ? subject.voluntaryActivation : subject.coContraction;
            const SteadyState st = muscles[i].calcSteadyState(p.pathLength, p.activation);
            if (!st.converged)
                throw SimulationError("muscle '" + curve.muscles[i] + "' at " + formatNumber(q) +
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

}  // namespace armsim
