// One muscle's force-length sweep and step response (experiments/muscle_curves.h).
#include "experiments/muscle_curves.h"

#include "basics/format.h"
#include "basics/numbers.h"
#include "muscles/simbody_isometric.h"

#include <algorithm>
#include <cmath>

namespace armsim {

ForceLengthSweep calcForceLengthSweep(const VirtualMuscle& m, double from, double step,
                                      const std::vector<double>& checkPaths,
                                      const std::function<void(int, int)>& progress) {
    const auto& p = m.getParameters();
    const double to = p.maxPathLength;
    const int n = int(std::floor((to - from) / step + 1e-9)) + 1;
    ForceLengthSweep sweep{Table({"path_length_m", "force_U1_N", "force_U05_N", "force_passive_N", "fascicle_length_U1_m"}),
                           {}, checkPaths, {}, {}, 0, 0};
    PlotSpec& spec = sweep.plot;
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
        double L1 = kNaN;
        for (int k = 0; k < 3; ++k) {
            const SteadyState s = m.calcSteadyState(P, U[k]);
            row.push_back(s.converged ? s.force : kNaN);
            if (k == 0) L1 = s.converged ? s.fascicleLength : kNaN;
            if (s.converged) {
                series[k].x.push_back(100 * P);
                series[k].y.push_back(s.force);
            }
        }
        row.push_back(L1);
        sweep.table.appendRow(row);
        if (row[1] > sweep.peakForce) {
            sweep.peakForce = row[1];
            sweep.peakPath = P;
        }
    }
    PlotSeries integrated{"U = 1, 3 s CPodes integration", {}, {}, true, 1};
    MuscleIsometricSettings trial;
    for (std::size_t i = 0; i < checkPaths.size(); ++i) {
        trial.pathLength = checkPaths[i];
        const Table r = runMuscleIsometric(m, trial);
        const double F = r.get(r.getNumRows() - 1, "force_N");
        sweep.integratedForces.push_back(F);
        sweep.steadyForces.push_back(m.calcSteadyState(checkPaths[i], 1.0).force);
        integrated.x.push_back(100 * checkPaths[i]);
        integrated.y.push_back(F);
        if (progress) progress(int(i) + 1, int(checkPaths.size()));
    }
    series.push_back(integrated);
    spec.series = series;
    return sweep;
}

StepResponse runStepActivation(const VirtualMuscle& m, double pathLength, double onset, double duration) {
    MuscleIsometricSettings s;
    s.pathLength = pathLength;
    s.activation = ActivationProfile::step(onset, 0.0, 1.0);
    s.duration = duration;
    IntegrationStats stats;
    StepResponse out{runMuscleIsometric(m, s, &stats), {}, 0, 0, kNaN, 0};
    const Table& t = out.table;
    out.plot.title = m.getParameters().name + ": step 0 -> 1 at " + formatNumber(onset) + " s, path " +
                     formatNumber(100 * pathLength) + " cm";
    out.plot.xLabel = "time (s)";
    out.plot.yLabel = "force (N)";
    out.plot.series.push_back({"Fse (output)", t.getColumn("time_s"), t.getColumn("force_N")});
    out.plot.series.push_back({"Fce (contractile)", t.getColumn("time_s"), t.getColumn("fce_N"), false, 1});
    const auto F = t.getColumn("force_N"), time = t.getColumn("time_s");
    out.finalForce = F.back();
    for (std::size_t i = 0; i < F.size(); ++i)
        if (time[i] >= onset && F[i] >= 0.9 * out.finalForce) {
            out.riseTime = time[i] - onset;
            break;
        }
    out.steadyForce = m.calcSteadyState(pathLength, 1.0).force;
    out.steps = stats.steps;
    return out;
}

}  // namespace armsim
