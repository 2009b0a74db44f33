#include "identification/thesis_method.h"

#include "basics/bound.h"
#include "identification/identifier.h"
#include "model/geometry.h"
#include "model/mvc_curve.h"

#include <cmath>

namespace armsim {

MuscleEstimate identifyThesisMethod(const ArmSetup& assumed, const std::vector<TorqueObservation>& allData) {
    MuscleEstimate est;
    est.method = "thesis";
    std::vector<TorqueObservation> data;  // the method knows flexion MVCs in the model's posture only
    for (const TorqueObservation& o : allData)
        if (o.isThesisMvc()) data.push_back(o);
    if (data.empty()) throw InputError("thesis method: no flexion MVC in the data (it uses those only)");
    std::vector<double> angles;
    for (const TorqueObservation& o : data) angles.push_back(o.flexionDeg);
    const MvcGeometry g = calcMvcGeometry(assumed, angles);
    IdentificationProblem problem;
    problem.base = assumed.calcBicepsParameters();
    problem.data.source = "tared torque / biceps moment arm";
    for (std::size_t k = 0; k < data.size(); ++k) {
        Observation o;
        o.pathLength = g.pathLength[k][assumed.primary];
        o.activation = 1.0;  // the thesis assumes a maximal effort is full activation
        o.force = data[k].torque / g.momentArm[k][assumed.primary];
        o.angle = elbowAngleFromFlexion(degToRad(data[k].flexionDeg));
        o.trial = data[k].repetition;
        problem.data.points.push_back(o);
    }
    IdentificationOptions options;
    options.noise = NoiseModel::Relative;
    const IdentificationReport r = identify(problem, SteadyForceModel(), options);
    est.converged = r.isConverged();
    est.message = getStopReasonName(r.stopReason) + ": " + r.message;
    est.iterations = r.iterations;
    est.mass = r.parameters.at(0).value;
    est.tendonLength = r.parameters.at(1).value;
    est.massLower = r.parameters[0].ciLower;
    est.massUpper = r.parameters[0].ciUpper;
    est.tendonLower = r.parameters[1].ciLower;
    est.tendonUpper = r.parameters[1].ciUpper;
    est.noiseLevel = r.residualSd;
    if (r.hasUncertainty) est.massTendonCorrelation = r.correlation[0][1];
    est.rmsResidual = r.rmsResidual;
    est.numParameters = 2;
    std::size_t k = 0;
    for (const TorqueObservation& o : allData) {
        est.predictedTorque.push_back(o.isThesisMvc() ? r.modelForces[k] * g.momentArm[k][assumed.primary] : NAN);
        k += o.isThesisMvc();
    }
    return est;
}


}  // namespace armsim
