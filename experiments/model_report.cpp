#include "experiments/model_report.h"

#include "basics/output_folder.h"

#include "muscles/muscle_models.h"

#include "basics/files.h"
#include "basics/param_node.h"
#include "basics/plot.h"
#include "model/anatomy_targets.h"
#include "model/geometry.h"
#include "model/muscle_arm.h"
#include "muscles/muscle_file.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace armsim {

namespace {

std::vector<MvcTorqueReference> readMvcReferences(const ParamNode& root, const std::string& key) {
    std::vector<MvcTorqueReference> out;
    if (!root.has(key)) return out;
    for (const ParamNode& n : root.children(key)) {
        MvcTorqueReference r;
        r.flexionDeg = n.getNumber("flexion_deg", Bound::closed(0, 180));
        r.torque = n.getNumber("torque", Bound::any("N m"));
        r.sd = n.getNumber("sd", Bound{0, 1e300, false, false, "N m"}, 0.0);
        r.source = n.getString("source");
        n.finish();
        out.push_back(r);
    }
    return out;
}

std::vector<double> calcAngles(const ArmSetup& setup, double stepDeg) {
    if (!(stepDeg >= 0.01 && stepDeg <= 90))
        throw InputError("--step = " + formatNumber(stepDeg) + " deg: expected in [0.01, 90] (the angle step)");
    const double lo = setup.arm.getMinFlexionDeg(), hi = setup.arm.getMaxFlexionDeg();
    std::vector<double> q;
    for (int k = 0; lo + k * stepDeg < hi - 1e-9; ++k) q.push_back(lo + k * stepDeg);
    q.push_back(hi);
    return q;
}

double interpolate(const std::vector<double>& x, const std::vector<double>& y, double at) {
    for (std::size_t k = 1; k < x.size(); ++k)
        if (at <= x[k]) {
            const double w = (at - x[k - 1]) / (x[k] - x[k - 1]);
            return y[k - 1] + w * (y[k] - y[k - 1]);
        }
    return y.back();
}

}  // namespace

ElbowReference loadElbowReference(const std::string& path) {
    const ParamNode root = ParamNode::loadFile(path);
    ElbowReference ref;
    if (root.has("moment_arms"))
        for (const ParamNode& n : root.children("moment_arms")) {
            MomentArmReference r;
            r.muscle = n.getString("muscle");
            r.flexionDeg = n.getNumber("flexion_deg", Bound::closed(0, 180));
            r.min = n.getNumber("min", Bound::closed(-0.2, 0.2));
            r.max = n.getNumber("max", Bound::closed(-0.2, 0.2));
            r.source = n.getString("source");
            if (r.min > r.max)
                throw InputError(n.where("max") + ": moment arm max = " + formatNumber(r.max) +
                                 " m is below min = " + formatNumber(r.min) + " m");
            n.finish();
            ref.momentArms.push_back(r);
        }
    ref.mvcFlexion = readMvcReferences(root, "mvc_flexion");
    ref.mvcExtension = readMvcReferences(root, "mvc_extension");
    return ref;
}

ElbowReference loadDefaultElbowReference() {
    return loadElbowReference(getAssetDirectory() + "/measured/elbow_reference.yaml");
}

Table calcMuscleTable(const ArmSetup& setup) {
    Table t({"F0_N", "L0_m", "L0T_m", "mass_kg", "max_path_m", "slow_fraction", "flexor", "force_scale",
             "fascicle_length_scale", "tendon_length_scale", "specific_tension_N_per_m2", "volume_m3",
             "max_firing_rate_f05"});
    for (int i = 0; i < setup.getNumMuscles(); ++i) {
        const MuscleParameters p = setup.calcMuscleParameters(i);
        const VirtualMuscle m(p);
        const MuscleCalibration& c = setup.muscles[i].calibration;
        t.appendRow({m.getF0(), p.optimalFascicleLength, p.optimalTendonLength, p.mass, p.maxPathLength,
                     p.slowFraction, setup.muscles[i].group == MuscleGroup::Flexor ? 1.0 : 0.0, c.forceScale,
                     c.fascicleLengthScale, c.tendonLengthScale, p.coefficients.sigma, p.mass / p.coefficients.density,
                     p.coefficients.fmax});
    }
    return t;
}

Table calcMomentArmTable(const ArmSetup& setup, double stepDeg) {
    std::vector<std::string> cols = {"flexion_deg", "elbow_angle_deg"};
    for (const MuscleSpec& m : setup.muscles) cols.push_back("path_" + m.params.name + "_m");
    for (const MuscleSpec& m : setup.muscles) cols.push_back("moment_arm_" + m.params.name + "_m");
    Table t(cols);
    ArmGeometry g(setup);
    for (double q : calcAngles(setup, stepDeg)) {
        g.setElbowAngle(elbowAngleFromFlexion(degToRad(q)));
        std::vector<PathGeometry> paths;
        for (int i = 0; i < g.getNumMuscles(); ++i) paths.push_back(g.calcPathGeometry(i));
        std::vector<double> row = {q, 180.0 - q};
        for (const PathGeometry& p : paths) row.push_back(p.length);
        for (const PathGeometry& p : paths) row.push_back(g.calcMomentArm(p));
        t.appendRow(row);
    }
    return t;
}

namespace {

// One series per muscle from a moment-arm table's <prefix><muscle>_m columns [cm], against column x;
// skipZero leaves out muscles whose moment arm is 0 throughout.
void addMomentArmSeries(PlotSpec& plot, const ArmSetup& setup, const Table& t, const std::string& x,
                        const std::string& prefix, bool skipZero) {
    const std::vector<double> xs = t.getColumn(x);
    int color = 0;
    for (const MuscleSpec& m : setup.muscles) {
        PlotSeries ps{m.params.name, xs, {}, false, color % 8};
        for (double h : t.getColumn(prefix + m.params.name + "_m")) ps.y.push_back(100 * h);
        if (skipZero && std::all_of(ps.y.begin(), ps.y.end(), [](double v) { return v == 0; })) continue;
        plot.series.push_back(ps);
        ++color;
    }
}

}  // namespace

Table calcForearmMomentArmTable(const ArmSetup& setup, double flexionDeg, double stepDeg) {
    const ArmParameters::ForearmRotation& rot = setup.arm.forearmRotation;
    if (!rot.enabled) throw InputError("model '" + setup.name + "' has no forearm rotation");
    std::vector<std::string> cols = {"rotation_deg"};
    for (const MuscleSpec& m : setup.muscles) cols.push_back("forearm_moment_arm_" + m.params.name + "_m");
    for (const MuscleSpec& m : setup.muscles) cols.push_back("moment_arm_" + m.params.name + "_m");
    Table t(cols);
    ArmGeometry g(setup);
    g.setElbowAngle(elbowAngleFromFlexion(degToRad(flexionDeg)));
    std::vector<double> phis;
    for (double phi = rot.minDeg; phi < rot.maxDeg - 1e-9; phi += stepDeg) phis.push_back(phi);
    phis.push_back(rot.maxDeg);
    for (double phi : phis) {
        g.setForearmRotation(degToRad(phi));
        std::vector<double> row = {phi};
        std::vector<PathGeometry> paths;
        for (int i = 0; i < g.getNumMuscles(); ++i) paths.push_back(g.calcPathGeometry(i));
        for (const PathGeometry& p : paths) row.push_back(g.calcForearmMomentArm(p));
        for (const PathGeometry& p : paths) row.push_back(g.calcMomentArm(p));
        t.appendRow(row);
    }
    return t;
}

Table formatMvcCurve(const ArmSetup& setup, const SteadyMvcCurve& curve) {
    std::vector<std::string> cols = {"flexion_deg", "elbow_angle_deg", "torque_total_Nm"};
    for (const std::string& m : curve.muscles) cols.push_back("torque_" + m + "_Nm");
    for (const std::string& m : curve.muscles) cols.push_back("force_" + m + "_N");
    for (const std::string& m : curve.muscles) cols.push_back("fibre_length_" + m);
    const bool flexion = curve.effort == Effort::Flexion;
    if (flexion) cols.push_back("primary_share");
    Table t(cols);
    for (std::size_t a = 0; a < curve.flexionDeg.size(); ++a) {
        std::vector<double> row = {curve.flexionDeg[a], 180.0 - curve.flexionDeg[a], curve.totalTorque[a]};
        for (const SteadyMusclePoint& p : curve.points[a]) row.push_back(p.torque);
        for (const SteadyMusclePoint& p : curve.points[a]) row.push_back(p.force);
        for (const SteadyMusclePoint& p : curve.points[a]) row.push_back(p.fibreLength);
        if (flexion) row.push_back(curve.calcFlexorShare(int(a), setup.primary));
        t.appendRow(row);
    }
    return t;
}

MvcCurveSummary summarizeMvcCurve(const SteadyMvcCurve& curve) {
    MvcCurveSummary s;
    std::vector<double> mag;
    for (double t : curve.totalTorque) mag.push_back(std::abs(t));
    const std::size_t k = std::max_element(mag.begin(), mag.end()) - mag.begin();
    s.peakTorque = mag[k];
    s.peakFlexionDeg = curve.flexionDeg[k];
    if (k > 0 && k + 1 < mag.size()) {  // vertex of the parabola through three samples
        const double x0 = curve.flexionDeg[k - 1], x1 = curve.flexionDeg[k], x2 = curve.flexionDeg[k + 1];
        const double y0 = mag[k - 1], y1 = mag[k], y2 = mag[k + 1];
        const double d = (x0 - x1) * (x0 - x2) * (x1 - x2);
        const double a = (x2 * (y1 - y0) + x1 * (y0 - y2) + x0 * (y2 - y1)) / d;
        const double b = (x2 * x2 * (y0 - y1) + x1 * x1 * (y2 - y0) + x0 * x0 * (y1 - y2)) / d;
        if (a < 0) {
            s.peakFlexionDeg = -b / (2 * a);
            s.peakTorque = y1 - a * (s.peakFlexionDeg - x1) * (s.peakFlexionDeg - x1);  // y' = 0 at the vertex
        }
    }
    s.torqueAt90 = interpolate(curve.flexionDeg, mag, 90.0);
    return s;
}

namespace {

// The steady MVC curve of an effort (g's agonists): the net torque, each agonist's and the published
// means +/- sd, the effort's torque positive.
PlotSpec makeMvcPlot(const ArmSetup& setup, const SteadyMvcCurve& curve, const Table& t, MuscleGroup g,
                     const ElbowReference& reference) {
    const bool flexion = g == MuscleGroup::Flexor;
    const std::string name = flexion ? "flexion" : "extension";
    const double sign = flexion ? 1.0 : -1.0;
    PlotSpec plot;
    plot.title = "Steady " + name + " MVC, model " + setup.name + " (agonists U " +
                 formatNumber(setup.effort.voluntaryActivation) + ", antagonists " +
                 formatNumber(setup.effort.coContraction) + ")";
    plot.xLabel = "flexion angle (deg, 0 = extended)";
    plot.yLabel = name + " torque (N m)";
    PlotSeries total;
    total.label = "net (all muscles)";
    total.x = curve.flexionDeg;
    for (double v : curve.totalTorque) total.y.push_back(sign * v);
    plot.series.push_back(total);
    int color = 1;
    for (int i = 0; i < setup.getNumMuscles(); ++i) {
        if (setup.muscles[i].group != g) continue;
        PlotSeries m;
        m.label = curve.muscles[i];
        m.x = curve.flexionDeg;
        for (double v : t.getColumn("torque_" + curve.muscles[i] + "_Nm")) m.y.push_back(sign * v);
        m.color = color++ % 7;
        plot.series.push_back(m);
    }
    PlotSeries pub;
    pub.label = "published mean, +/- SD";
    pub.markers = true;
    pub.color = 7;
    for (const MvcTorqueReference& r : flexion ? reference.mvcFlexion : reference.mvcExtension)
        for (double v : {r.torque - r.sd, r.torque, r.torque + r.sd}) {
            pub.x.push_back(r.flexionDeg);
            pub.y.push_back(sign * v);
        }
    if (!pub.x.empty()) plot.series.push_back(pub);
    plot.yMin = 0;
    return plot;
}

}  // namespace

ModelReportFiles writeModelReport(const ArmSetup& setup, const std::string& outDir, double stepDeg,
                                  const ElbowReference& reference) {
    namespace fs = std::filesystem;
    OutputFolder folder(outDir, OutputFolder::Mode::AddFiles);  // every file appears at the end, or none
    ModelReportFiles out;
    auto path = [&](const std::string& f) { return folder.getTargetPath(f); };

    out.muscles = calcMuscleTable(setup);
    const Table& muscles = out.muscles;
    std::string text = "muscle,muscle_model";
    for (const std::string& c : muscles.getColumnNames()) text += "," + c;
    text += "\n";
    for (int i = 0; i < muscles.getNumRows(); ++i) {
        const std::string& model = setup.muscles[i].muscleModel;
        text += setup.muscles[i].params.name + "," + (model.empty() ? std::string(kDefaultMuscleModel) : model);
        for (double v : muscles.getRow(i)) text += "," + formatNumber(v);
        text += "\n";
    }
    folder.write("muscles.csv", text);
    out.files.push_back(path("muscles.csv"));

    const Table arms = calcMomentArmTable(setup, stepDeg);
    folder.write("moment_arms.csv", arms.toCsv());
    out.files.push_back(path("moment_arms.csv"));
    PlotSpec armPlot;
    armPlot.title = "Moment arms, model " + setup.name + " (virtual work); markers: published ranges";
    armPlot.xLabel = "flexion angle (deg, 0 = extended)";
    armPlot.yLabel = "moment arm (cm, + = flexion)";
    addMomentArmSeries(armPlot, setup, arms, "flexion_deg", "moment_arm_", false);
    PlotSeries refs;
    refs.label = "published min/max";
    refs.markers = true;
    refs.color = 7;
    for (const MomentArmReference& r : reference.momentArms) {
        bool covered = false;
        for (const MuscleSpec& m : setup.muscles) covered = covered || doesFamilyCoverMuscle(r.muscle, m.params.name);
        if (!covered) continue;
        for (double v : {r.min, r.max}) {
            refs.x.push_back(r.flexionDeg);
            refs.y.push_back(100 * v);
        }
    }
    if (!refs.x.empty()) armPlot.series.push_back(refs);
    folder.writeWith("moment_arms.png", [&](const std::string& p) { writePlotPng(p, armPlot); });
    out.files.push_back(path("moment_arms.png"));

    if (setup.arm.forearmRotation.enabled) {
        constexpr double kForearmFlexionDeg = 90;  // the usual forearm-rotation test posture (elbow at a right angle)
        const Table fa = calcForearmMomentArmTable(setup, kForearmFlexionDeg, stepDeg);
        folder.write("forearm_moment_arms.csv", fa.toCsv());
        out.files.push_back(path("forearm_moment_arms.csv"));
        PlotSpec plot;
        plot.title = "Forearm-rotation moment arms at 90 deg flexion, model " + setup.name + " (virtual work)";
        plot.xLabel = "forearm rotation (deg, - pronated, + supinated)";
        plot.yLabel = "moment arm (cm, + = supination)";
        addMomentArmSeries(plot, setup, fa, "rotation_deg", "forearm_moment_arm_", true);  // those that rotate it
        folder.writeWith("forearm_moment_arms.png", [&](const std::string& p) { writePlotPng(p, plot); });
        out.files.push_back(path("forearm_moment_arms.png"));
    }

    const std::vector<double> angles = calcAngles(setup, stepDeg);
    for (MuscleGroup g : {MuscleGroup::Flexor, MuscleGroup::Extensor}) {
        const bool flexion = g == MuscleGroup::Flexor;
        const std::string name = flexion ? "flexion" : "extension";
        const SteadyMvcCurve curve = calcSteadyMvcCurve(setup, g, setup.effort, angles);
        const Table t = formatMvcCurve(setup, curve);
        folder.write("mvc_" + name + ".csv", t.toCsv());
        out.files.push_back(path("mvc_" + name + ".csv"));
        (flexion ? out.flexion : out.extension) = summarizeMvcCurve(curve);
        if (flexion)
            out.primaryShareAt90 = interpolate(t.getColumn("flexion_deg"), t.getColumn("primary_share"), 90.0);

        const PlotSpec plot = makeMvcPlot(setup, curve, t, g, reference);
        folder.writeWith("mvc_" + name + ".png", [&](const std::string& p) { writePlotPng(p, plot); });
        out.files.push_back(path("mvc_" + name + ".png"));
    }
    folder.commit();
    return out;
}

}  // namespace armsim
