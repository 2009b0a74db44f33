// MVC sweeps over elbow angles for the main job (experiments/mvc_angles.h).
#include "experiments/mvc_angles.h"

#include "basics/angles.h"
#include "basics/format.h"

namespace armsim {

namespace {

std::vector<IsometricTrialResult> runAngles(const ArmSetup& setup, const std::vector<double>& anglesDeg,
                                            double agonist, double antagonist, int jobs,
                                            const std::function<void(int, int)>& progress) {
    std::vector<IsometricTrialSettings> settings;
    for (double a : anglesDeg) {
        IsometricTrialSettings s;
        s.elbowAngle = degToRad(a);
        s.activation = agonist;
        s.antagonistActivation = antagonist;
        settings.push_back(s);
    }
    return runIsometricTrials(setup, settings, jobs, progress);
}

}  // namespace

MvcAngleSweep runMvcAngleSweep(const ArmSetup& setup, const std::vector<double>& anglesDeg, int jobs,
                               const std::function<void(int, int)>& progress) {
    const IsometricTrialSettings defaults;
    const auto results = runAngles(setup, anglesDeg, defaults.activation, defaults.antagonistActivation, jobs, progress);
    MvcAngleSweep sweep{Table({"elbow_angle_deg", "path_length_m", "moment_arm_m", "muscle_force_N", "strap_force_N",
                               "force_moment_arm_N", "force_fixed_ratio_N", "rest_force_N"}),
                        {}};
    PlotSpec& spec = sweep.plot;
    spec.title = "MVC force vs elbow angle (3 s efforts, mean of the last second)";
    spec.xLabel = "elbow angle (deg, 180 = extended)";
    spec.yLabel = "force (N)";
    PlotSeries truth{"true muscle force", {}, {}, true, 0}, fixed{"thesis fixed-ratio estimate", {}, {}, true, 1},
        strap{"transducer (strap) force", {}, {}, true, 2};
    for (std::size_t k = 0; k < results.size(); ++k) {
        const IsometricSummary& s = results[k].summary;
        sweep.table.appendRow({anglesDeg[k], s.pathLength, s.momentArm, s.meanForce, s.meanStrapForce,
                               s.meanForceMomentArm, s.meanForceFixedRatio, s.restForce});
        truth.x.push_back(anglesDeg[k]);
        truth.y.push_back(s.meanForce);
        fixed.x.push_back(anglesDeg[k]);
        fixed.y.push_back(s.meanForceFixedRatio);
        strap.x.push_back(anglesDeg[k]);
        strap.y.push_back(s.meanStrapForce);
    }
    spec.series = {truth, fixed, strap};
    return sweep;
}

namespace {

Table makeSubjectTable(const ArmSetup& setup) {
    std::vector<std::string> columns{"elbow_angle_deg", "flexion_deg", "tared_torque_Nm", "strap_force_N",
                                     "primary_moment_arm_m", "primary_force_N", "biceps_both_heads_N",
                                     "thesis_estimate_N", "estimate_error_vs_both_heads_pct"};
    for (const MuscleSpec& m : setup.muscles) columns.push_back("force_" + m.params.name + "_N");
    for (const MuscleSpec& m : setup.muscles) columns.push_back("torque_" + m.params.name + "_Nm");
    return Table(columns);
}

}  // namespace

MvcAngleSweep runSubjectMvcAngleSweep(const ArmSetup& setup, const std::vector<double>& anglesDeg, int jobs,
                                      const std::function<void(int, int)>& progress) {
    const auto results = runAngles(setup, anglesDeg, setup.effort.voluntaryActivation, setup.effort.coContraction,
                                   jobs, progress);
    const int n = setup.getNumMuscles();
    const std::string biceps = setup.muscles[setup.primary].params.name;
    const std::vector<int> heads = setup.getBicepsHeads();
    MvcAngleSweep sweep{makeSubjectTable(setup), {}};
    PlotSpec& spec = sweep.plot;
    spec.title = "Anatomical twin: MVC at the thesis's angles (VA " + formatNumber(setup.effort.voluntaryActivation) +
                 ", co-contraction " + formatNumber(setup.effort.coContraction) + ")";
    spec.xLabel = "elbow angle (deg, thesis convention: 180 = extended)";
    spec.yLabel = "force (N)";
    PlotSeries estimated{"thesis estimate of " + biceps + " (torque / moment arm)", {}, {}, false, 1};
    std::vector<PlotSeries> forces;
    std::vector<int> flexors;
    for (int i = 0; i < n; ++i)
        if (setup.muscles[i].group == MuscleGroup::Flexor) {
            flexors.push_back(i);
            forces.push_back({"true force " + setup.muscles[i].params.name, {}, {}, false, int(forces.size() + 2) % 8});
        }
    PlotSeries bothHeads{"true force, biceps (both heads)", {}, {}, false, 7};
    for (std::size_t k = 0; k < results.size(); ++k) {
        const IsometricSummary& s = results[k].summary;
        const double estimate = s.meanForceMomentArm;
        double both = 0;
        for (int i : heads) both += s.meanForces[i];
        std::vector<double> row{anglesDeg[k], 180 - anglesDeg[k], s.meanMuscleTorque, s.meanStrapForce, s.momentArm,
                                s.meanForce, both, estimate, 100 * (estimate - both) / both};
        for (int i = 0; i < n; ++i) row.push_back(s.meanForces[i]);
        for (int i = 0; i < n; ++i) row.push_back(s.momentArms[i] * s.meanForces[i]);
        sweep.table.appendRow(row);
        bothHeads.x.push_back(anglesDeg[k]);
        bothHeads.y.push_back(both);
        estimated.x.push_back(anglesDeg[k]);
        estimated.y.push_back(estimate);
        for (std::size_t j = 0; j < flexors.size(); ++j) {
            forces[j].x.push_back(anglesDeg[k]);
            forces[j].y.push_back(s.meanForces[flexors[j]]);
        }
    }
    spec.series = forces;
    spec.series.push_back(bothHeads);
    spec.series.push_back(estimated);
    spec.yMin = 0;
    return sweep;
}

}  // namespace armsim
