#include "experiments/osim_report.h"

#include "model/osim_anatomy.h"

#include "basics/errors.h"
#include "basics/files.h"
#include "basics/format.h"
#include "basics/output_folder.h"
#include "basics/plot.h"
#include "basics/table.h"
#include "model/osim_arm.h"

#include <cmath>

namespace armsim {

namespace {

constexpr double kDeg = 3.14159265358979323846 / 180;

}  // namespace

OsimReportFiles writeOsimModelReport(const OsimModel& model, const OsimReportSettings& settings, const std::string& outDir) {
    if (!(settings.stepDeg > 0 && settings.stepDeg <= 90))
        throw InputError("--step " + formatNumber(settings.stepDeg) + ": expected in (0, 90] deg");
    const OsimArm arm(model, {}, settings.muscleModel);
    if (arm.getNumMuscles() == 0)
        throw InputError("model " + model.name + " (" + model.file + ") has no muscles: `model show` reports muscles "
                         "(`armsim forward` runs a model without them)");
    const int j = findOsimSweptCoordinate(arm, settings.coordinate);
    OsimReportFiles r;
    r.coordinate = arm.getCoordinate(j).name;
    const int n = arm.getNumMuscles();

    std::string text = "muscle,muscle_model,F0_N,optimal_fiber_length_m,tendon_slack_length_m,pennation_angle_rad\n";
    for (int i = 0; i < n; ++i) {
        const OsimMuscle& m = model.muscles[i];
        text += m.name + "," + arm.getMuscleForce(i).getMuscle().getModelName() + "," + formatNumber(m.maxIsometricForce) + "," +
                formatNumber(m.optimalFiberLength) + "," + formatNumber(m.tendonSlackLength) + "," +
                formatNumber(m.pennationAngleAtOptimal) + "\n";
    }

    // The sweep over the coordinate's range (whole steps from its lower end, and its upper end).
    const auto range = arm.getCoordinate(j).range;
    std::vector<double> anglesDeg;
    for (double a = range[0] / kDeg; a < range[1] / kDeg - 1e-9; a += settings.stepDeg) anglesDeg.push_back(a);
    anglesDeg.push_back(range[1] / kDeg);
    std::vector<std::string> armCols = {"flexion_deg"}, mvcCols = {"flexion_deg", "torque_total_Nm"};
    for (int i = 0; i < n; ++i) armCols.push_back("moment_arm_" + arm.getMuscleName(i) + "_m");
    for (int i = 0; i < n; ++i) armCols.push_back("path_length_" + arm.getMuscleName(i) + "_m");
    for (int i = 0; i < n; ++i) mvcCols.push_back("torque_" + arm.getMuscleName(i) + "_Nm");
    for (int i = 0; i < n; ++i) mvcCols.push_back("fibre_length_" + arm.getMuscleName(i));
    Table arms(armCols), positive(mvcCols), negative(mvcCols);
    const AnatomyCurves curves = calcOsimAnatomyCurves(arm, j, anglesDeg);   // each direction's agonists fully excited
    for (std::size_t a = 0; a < anglesDeg.size(); ++a) {
        const double deg = anglesDeg[a];
        std::vector<double> row = {deg};
        for (int i = 0; i < n; ++i) row.push_back(curves.flexion.points[a][i].momentArm);
        for (int i = 0; i < n; ++i) row.push_back(curves.flexion.points[a][i].pathLength);
        arms.appendRow(row);
        for (int direction : {1, -1}) {
            const SteadyMvcCurve& c = direction > 0 ? curves.flexion : curves.extension;
            const double total = c.totalTorque[a];
            std::vector<double> mvc = {deg, total};
            for (int i = 0; i < n; ++i) mvc.push_back(c.points[a][i].torque);
            for (int i = 0; i < n; ++i) mvc.push_back(c.points[a][i].fibreLength);
            (direction > 0 ? positive : negative).appendRow(mvc);
            if (direction > 0 && total > r.peakPositive) r.peakPositive = total, r.peakPositiveDeg = deg;
            if (direction < 0 && -total > r.peakNegative) r.peakNegative = -total, r.peakNegativeDeg = deg;
        }
    }

    OutputFolder out(outDir, OutputFolder::Mode::AddFiles);
    out.write("muscles.csv", text);
    out.write("moment_arms.csv", arms.toCsv(12));
    out.write("mvc_flexion.csv", positive.toCsv(12));
    out.write("mvc_extension.csv", negative.toCsv(12));
    auto plotColumns = [&](const Table& t, const std::string& prefix, double scale, const std::string& title,
                           const std::string& yLabel, bool total) {
        PlotSpec p;
        p.title = title;
        p.xLabel = r.coordinate + " (deg)";
        p.yLabel = yLabel;
        const std::vector<double> x = t.getColumn("flexion_deg");
        if (total) {
            std::vector<double> y = t.getColumn("torque_total_Nm");
            for (double& v : y) v = std::abs(v);
            p.series.push_back({"total", x, y, false, 7});
        }
        for (int i = 0; i < n; ++i) {
            std::vector<double> y = t.getColumn(prefix + arm.getMuscleName(i) + (prefix == "moment_arm_" ? "_m" : "_Nm"));
            for (double& v : y) v *= scale;
            p.series.push_back({arm.getMuscleName(i), x, y, false, int(i % 7)});
        }
        return p;
    };
    const PlotSpec armPlot = plotColumns(arms, "moment_arm_", 100, "Moment arms about " + r.coordinate + ", " + model.name +
                                         " (virtual work)", "moment arm (cm, + = positive direction)", false);
    out.writeWith("moment_arms.png", [&](const std::string& p) { writePlotPng(p, armPlot); });
    const PlotSpec flex = plotColumns(positive, "torque_", 1, "Steady torque, + " + r.coordinate + " muscles fully excited, " +
                                      model.name, "torque (N m)", true);
    out.writeWith("mvc_flexion.png", [&](const std::string& p) { writePlotPng(p, flex); });
    const PlotSpec ext = plotColumns(negative, "torque_", 1, "Steady torque, - " + r.coordinate + " muscles fully excited, " +
                                     model.name, "torque (N m)", true);
    out.writeWith("mvc_extension.png", [&](const std::string& p) { writePlotPng(p, ext); });
    out.commit();
    for (const std::string& f : out.getFiles()) r.files.push_back(out.getTargetPath(f));
    return r;
}

}  // namespace armsim
