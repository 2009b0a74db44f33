// armsim run: the main job on built-in defaults. Writes its results to --out (default out/).
#include "basics/errors.h"
#include "basics/plot.h"
#include "cli/commands.h"
#include "muscles/muscle_file.h"
#include "muscles/simbody_isometric.h"

#include <cmath>
#include <cstdio>
#include <memory>

namespace armsim::cli {

namespace {

/// Force-length: steady solve over the path range at U = 1, 0.5 and 0 (passive), with full time
/// integrations at a few paths as the second method.
void runForceLength(const VirtualMuscle& m, const std::string& outDir) {
    const auto& p = m.getParameters();
    const double from = 0.27, to = p.maxPathLength, step = 0.0025;
    const int n = int(std::floor((to - from) / step + 1e-9)) + 1;
    Table t({"path_length_m", "force_U1_N", "force_U05_N", "force_passive_N", "fascicle_length_U1_m"});
    PlotSpec spec;
    spec.title = p.name + ": steady isometric force vs path length";
    spec.xLabel = "musculotendon path length (cm)";
    spec.yLabel = "force Fse (N)";
    std::vector<PlotSeries> series(3);
    series[0].label = "U = 1 (steady solve)";
    series[1].label = "U = 0.5";
    series[1].color = 2;
    series[2].label = "passive, U = 0";
    series[2].color = 5;
    for (int i = 0; i < n; ++i) {
        const double P = std::min(to, from + i * step);
        const double U[3] = {1.0, 0.5, 0.0};
        std::vector<double> row{P};
        double L1 = NAN;
        for (int k = 0; k < 3; ++k) {
            const SteadyState s = m.calcSteadyState(P, U[k]);
            row.push_back(s.converged ? s.force : NAN);
            if (k == 0) L1 = s.converged ? s.fascicleLength : NAN;
            if (s.converged) {
                series[k].x.push_back(100 * P);
                series[k].y.push_back(s.force);
            }
        }
        row.push_back(L1);
        t.appendRow(row);
    }
    PlotSeries integrated{"U = 1, 3 s CPodes integration", {}, {}, true, 1};
    MuscleIsometricSettings trial;
    const double checks[] = {0.33, 0.36, 0.375, 0.40, 0.41, 0.43};
    int done = 0;
    for (double P : checks) {
        trial.pathLength = P;
        const Table r = runMuscleIsometric(m, trial);
        integrated.x.push_back(100 * P);
        integrated.y.push_back(r.get(r.getNumRows() - 1, "force_N"));
        printProgress("force-length: integrations", ++done, int(std::size(checks)));
    }
    series.push_back(integrated);
    spec.series = series;
    t.writeCsv(outDir + "/force_length.csv");
    writePlotPng(outDir + "/force_length.png", spec);

    std::printf("\nForce-length (%s, M = %.2f g, L0 = %.1f cm, L0T = %.1f cm, F0 = %.1f N)\n", p.name.c_str(),
                1000 * p.mass, 100 * p.optimalFascicleLength, 100 * p.optimalTendonLength, m.getF0());
    std::printf("  path (cm)   steady F (N)   integrated F (N)   difference\n");
    for (std::size_t i = 0; i < integrated.x.size(); ++i) {
        const double fs = m.calcSteadyState(checks[i], 1.0).force;
        std::printf("  %8.2f   %12.3f   %16.3f   %9.4f %%\n", 100 * checks[i], fs, integrated.y[i],
                    100 * (integrated.y[i] - fs) / fs);
    }
    double peak = 0, peakP = 0;
    for (int i = 0; i < t.getNumRows(); ++i)
        if (t.getRow(i)[1] > peak) {
            peak = t.getRow(i)[1];
            peakP = t.getRow(i)[0];
        }
    std::printf("  peak %.1f N at %.2f cm (thesis: near 600 N at 40-41 cm)\n", peak, 100 * peakP);
}

/// One step-activation time course at the thesis's 37.5 cm.
void runStep(const VirtualMuscle& m, const std::string& outDir) {
    MuscleIsometricSettings s;
    s.pathLength = 0.375;
    s.activation = ActivationProfile::step(0.1, 0.0, 1.0);
    s.duration = 1.0;
    IntegrationStats stats;
    const Table t = runMuscleIsometric(m, s, &stats);
    t.writeCsv(outDir + "/step_activation.csv");
    PlotSpec spec;
    spec.title = m.getParameters().name + ": step 0 -> 1 at 0.1 s, path 37.5 cm";
    spec.xLabel = "time (s)";
    spec.yLabel = "force (N)";
    spec.series.push_back({"Fse (output)", t.getColumn("time_s"), t.getColumn("force_N")});
    spec.series.push_back({"Fce (contractile)", t.getColumn("time_s"), t.getColumn("fce_N"), false, 1});
    writePlotPng(outDir + "/step_activation.png", spec);
    const auto F = t.getColumn("force_N"), time = t.getColumn("time_s");
    const double final = F.back();
    double t90 = NAN;
    for (std::size_t i = 0; i < F.size(); ++i)
        if (time[i] >= 0.1 && F[i] >= 0.9 * final) {
            t90 = time[i] - 0.1;
            break;
        }
    std::printf("\nStep activation at 37.5 cm: final force %.2f N (steady solve %.2f N), 90 %% rise in %.0f ms, "
                "%d integrator steps\n",
                final, m.calcSteadyState(0.375, 1.0).force, 1000 * t90, stats.steps);
}

const MainJobStepRegistrar registerForceLength(10, "Muscle force-length (steady solve vs integration)",
                                                [](const MainJobContext& c) { runForceLength(VirtualMuscle(c.muscle.loadParameters()), c.outDir); });
const MainJobStepRegistrar registerStep(20, "Muscle step activation",
                                        [](const MainJobContext& c) { runStep(VirtualMuscle(c.muscle.loadParameters()), c.outDir); });

}  // namespace

}  // namespace armsim::cli
