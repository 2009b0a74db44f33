// The numbers the Python tests compare the module with, computed by the C++ API directly (not through
// pybind11) and printed with 17 significant digits: steady state, a muscle trial, geometry, an arm trial.
#include "model/mvc_curve.h"
#include "model/trial.h"
#include "muscles/simbody_isometric.h"

#include <cmath>
#include <cstdio>

using namespace armsim;

int main() {
    const ArmSetup thesis = loadModel("thesis"), elbow = loadModel("elbow");
    const VirtualMuscle biceps(thesis.calcBicepsParameters());
    std::printf("{\n\"steady_force\": %.17g,\n", biceps.calcSteadyState(0.40, 1.0).force);

    MuscleIsometricSettings m;
    m.pathLength = 0.375;
    m.activation = ActivationProfile::ramp(0.1, 0.1 + 0.05, 0.0, 0.8);  // onset + rise, as the CLI and the module build it
    m.duration = 1.0;
    const Table t = runMuscleIsometric(biceps, m);
    std::printf("\"muscle_trial_force\": [");
    for (int r = 0; r < t.getNumRows(); r += 100) std::printf("%s%.17g", r ? ", " : "", t.get(r, "force_N"));
    std::printf("],\n");

    const MvcGeometry g = calcMvcGeometry(elbow, {30, 90, 120});
    std::printf("\"moment_arms\": [");
    for (std::size_t a = 0; a < g.momentArm.size(); ++a)
        for (std::size_t i = 0; i < g.momentArm[a].size(); ++i) std::printf("%s%.17g", a + i ? ", " : "", g.momentArm[a][i]);
    std::printf("],\n");

    IsometricTrialSettings s;
    s.elbowAngle = 100 * M_PI / 180;
    s.activation = 0.7;
    s.antagonistActivation = 0.05;
    s.holdDuration = 1.0;
    s.sampleRate = 200;
    const IsometricTrialResult r = runIsometricTrial(elbow, s);
    std::printf("\"arm_trial_torque\": [");
    for (int i = 0; i < r.series.getNumRows(); i += 20)
        std::printf("%s%.17g", i ? ", " : "", r.series.get(i, "muscle_torque_Nm"));
    std::printf("],\n\"arm_trial_mean_torque\": %.17g\n}\n", r.summary.meanMuscleTorque);
}
