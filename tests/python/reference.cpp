// The numbers the Python tests compare the module with, computed by the C++ API directly (not through
// pybind11) and printed with 17 significant digits: steady state, a muscle trial, geometry, an arm
// trial, identification (steady lm with intervals; torque data with every elbow method), the elbow
// validation, experiment design, a torque protocol, and a rendered frame.
#include "experiments/protocol.h"
#include "studies/torque_validation.h"
#include "studies/experiment_design.h"
#include "identification/forward_choice.h"
#include "model/geometry.h"
#include "model/mvc_curve.h"
#include "model/trial.h"
#include "muscles/muscle_file.h"
#include "muscles/simbody_isometric.h"

#ifdef ARMSIM_WITH_RENDER
#include "render/trial_video.h"
#endif

#include <cmath>
#include <cstdio>
#include <string>

using namespace armsim;

namespace {

void printList(const char* key, const std::vector<double>& v, bool last = false) {
    std::printf("\"%s\": [", key);
    for (std::size_t i = 0; i < v.size(); ++i) std::printf("%s%.17g", i ? ", " : "", v[i]);
    std::printf("]%s\n", last ? "" : ",");
}

void printNumber(const char* key, double v) { std::printf("\"%s\": %.17g,\n", key, v); }

}  // namespace

int main() {
    const ArmSetup thesis = loadModel("thesis"), elbow = loadModel("elbow");
    const VirtualMuscle biceps(thesis.calcBicepsParameters());
    std::printf("{\n");
    printNumber("steady_force", biceps.calcSteadyState(0.40, 1.0).force);

    MuscleIsometricSettings m;
    m.pathLength = 0.375;
    m.activation = ActivationProfile::ramp(0.1, 0.1 + 0.05, 0.0, 0.8);  // onset + rise, as the CLI and the module build it
    m.duration = 1.0;
    const Table t = runMuscleIsometric(biceps, m);
    std::vector<double> samples;
    for (int r = 0; r < t.getNumRows(); r += 100) samples.push_back(t.get(r, "force_N"));
    printList("muscle_trial_force", samples);

    const MvcGeometry g = calcMvcGeometry(elbow, {30, 90, 120});
    std::vector<double> arms;
    for (const auto& row : g.momentArm) arms.insert(arms.end(), row.begin(), row.end());
    printList("moment_arms", arms);

    IsometricTrialSettings s;
    s.elbowAngle = degToRad(100);
    s.activation = 0.7;
    s.antagonistActivation = 0.05;
    s.holdDuration = 1.0;
    s.sampleRate = 200;
    const IsometricTrialResult r = runIsometricTrial(elbow, s);
    std::vector<double> torque;
    for (int i = 0; i < r.series.getNumRows(); i += 20) torque.push_back(r.series.get(i, "muscle_torque_Nm"));
    printList("arm_trial_torque", torque);
    printNumber("arm_trial_mean_torque", r.summary.meanMuscleTorque);

    // Identification: five angles, the steady model's forces at the default biceps with fixed
    // perturbations, identified by lm from 330 g / 22 cm (the module gets the same angles and forces).
    IdentificationProblem pr;
    pr.base = thesis.calcBicepsParameters();
    const std::vector<double> anglesDeg = {45, 60, 90, 120, 150}, factors = {1.01, 0.99, 1.02, 0.985, 1.0};
    for (double deg : anglesDeg) {
        Observation o;
        o.angle = degToRad(deg);
        o.pathLength = makeArmPathFromAngle(thesis.arm)(o.angle);
        pr.data.points.push_back(o);
    }
    const std::vector<double> clean = SteadyForceModel().calcForces(pr.base, pr.data.points);
    std::vector<double> forces;
    for (std::size_t k = 0; k < clean.size(); ++k) forces.push_back(pr.data.points[k].force = clean[k] * factors[k]);
    pr.data.source = "data";
    pr.unknowns[0].start = 0.330;
    pr.unknowns[1].start = 0.22;
    const IdentificationReport id = identifyAndRecheck(pr, {}, thesis.arm, {});
    printList("identify_angles_deg", anglesDeg);
    printList("identify_forces", forces);
    printList("identify_estimate", {id.parameters[0].value, id.parameters[1].value});
    printList("identify_interval", {id.parameters[0].ciLower, id.parameters[0].ciUpper, id.parameters[1].ciLower,
                                    id.parameters[1].ciUpper});
    printNumber("identify_correlation", id.correlation[0][1]);
    printNumber("identify_faithful_check_rms", id.checks[1].rmsResidual);
    printNumber("identify_history_length", double(id.history.size()));

    // Torque data with every elbow method (measured VA 0.95).
    TorqueIdentificationOptions to;
    to.activation = 0.95;
    const std::vector<MuscleEstimate> torqueEstimates =
        identifyTorqueData(loadDefaultPopulation(), readTorqueData(findAsset("measured/thesis_mvc_torque.csv")), to);
    std::vector<double> torqueMasses;
    for (const MuscleEstimate& e : torqueEstimates) torqueMasses.push_back(e.mass);
    printList("identify_torque_masses", torqueMasses);

    ElbowValidationSettings v;
    v.subjects = 2;
    v.noiseLevels = {0.02};
    const std::vector<ElbowValidationRow> rows = runElbowValidation(loadDefaultPopulation(), v);
    std::vector<double> validationMasses;
    for (const ElbowValidationRow& row : rows) validationMasses.push_back(row.estimate.mass);
    printList("validate_elbow_masses", validationMasses);

    DesignSettings d;
    d.draws = 4;
    d.trials = 6;
    TorqueProtocol reference;
    reference.name = "thesis";
    const DesignResult design = designProtocol(loadDefaultPopulation(), d, reference);
    printNumber("design_mass_sd", design.predicted.massSd);
    printNumber("design_reference_mass_sd", design.reference.massSd);

    const TorqueProtocol tp = readTorqueProtocol(findAsset("protocols/designed_emg_torque.yaml"));
    std::vector<double> protocolTorque;
    for (const TorqueObservation& o : synthesizeTorqueData(loadTorqueProtocolSubject(tp), tp, tp.seed, 2))
        protocolTorque.push_back(o.torque);
    printList("torque_protocol_torque", protocolTorque);

#ifdef ARMSIM_WITH_RENDER
    // A frame of the arm trial above at t = 1.0 s, 160 x 90: channel sums in RGB order.
    TrialVideoSettings tv;
    tv.render.width = 160;
    tv.render.height = 90;
    tv.tableName = "series";
    TrialRenderer renderer(elbow, r.series, tv);
    const cv::Mat frame = renderer.renderRow(renderer.findRow(1.0));
    const cv::Scalar sum = cv::sum(frame);
    printList("frame_rgb_sums", {sum[2], sum[1], sum[0]});
#else
    printList("frame_rgb_sums", {});
#endif
    std::printf("\"end\": 0\n}\n");
}
