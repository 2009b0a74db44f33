// armsim run's muscle steps: the force-length curve (steady solve vs integration) and a step activation.
#include "basics/errors.h"
#include "basics/plot.h"
#include "cli/commands.h"
#include "experiments/muscle_curves.h"
#include "muscles/muscle_file.h"

#include <cstdio>
#include <vector>

namespace armsim::cli {

namespace {

// The thesis's sweep from 27 cm to P_max, checked by integration at its paths up to 43 cm that the muscle
// reaches (the elbow's biceps long head ends at 42.6 cm).
void runForceLength(const VirtualMuscle& m, const std::string& outDir) {
    std::vector<double> checks;
    for (double P : {0.33, 0.36, 0.375, 0.40, 0.41, 0.43})
        if (P <= m.getMaxPathLength()) checks.push_back(P);
    const ForceLengthSweep sweep = calcForceLengthSweep(m, 0.27, 0.0025, checks, [](int d, int n) {
        printProgress("force-length: integrations", d, n);
    });
    sweep.table.writeCsv(outDir + "/force_length.csv");
    writePlotPng(outDir + "/force_length.png", sweep.plot);
    const auto& p = m.getParameters();
    std::printf("\nForce-length (%s, M = %.2f g, L0 = %.1f cm, L0T = %.1f cm, F0 = %.1f N)\n", p.name.c_str(),
                1000 * p.mass, 100 * p.optimalFascicleLength, 100 * p.optimalTendonLength, m.getF0());
    std::printf("  path (cm)   steady F (N)   integrated F (N)   difference\n");
    for (std::size_t i = 0; i < sweep.checkPaths.size(); ++i) {
        const double fs = sweep.steadyForces[i], fi = sweep.integratedForces[i];
        std::printf("  %8.2f   %12.3f   %16.3f   %9.4f %%\n", 100 * sweep.checkPaths[i], fs, fi, 100 * (fi - fs) / fs);
    }
    std::printf("  peak %.1f N at %.2f cm (thesis: near 600 N at 40-41 cm)\n", sweep.peakForce, 100 * sweep.peakPath);
}

void runStep(const VirtualMuscle& m, const std::string& outDir) {
    const StepResponse r = runStepActivation(m, 0.375, 0.1, 1.0);
    r.table.writeCsv(outDir + "/step_activation.csv");
    writePlotPng(outDir + "/step_activation.png", r.plot);
    std::printf("\nStep activation at 37.5 cm: final force %.2f N (steady solve %.2f N), 90 %% rise in %.0f ms, "
                "%d integrator steps\n",
                r.finalForce, r.steadyForce, 1000 * r.riseTime, r.steps);
}

const MainJobStepRegistrar registerForceLength(10, "Muscle force-length (steady solve vs integration)",
                                                [](const MainJobContext& c) { runForceLength(VirtualMuscle(c.muscle.loadParameters()), c.outDir); });
const MainJobStepRegistrar registerStep(20, "Muscle step activation",
                                        [](const MainJobContext& c) { runStep(VirtualMuscle(c.muscle.loadParameters()), c.outDir); });

}  // namespace

}  // namespace armsim::cli
