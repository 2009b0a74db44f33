#include "experiments/model_check.h"

#include "basics/output_folder.h"

#include "basics/csv.h"
#include "basics/files.h"
#include "basics/plot.h"
#include "model/mvc_curve.h"
#include "model/osim_anatomy.h"
#include "model/osim_arm.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace armsim {

namespace {

std::vector<double> sweepAngles(const ArmSetup& setup) {
    std::vector<double> a;
    for (double d = setup.arm.getMinFlexionDeg(); d <= setup.arm.getMaxFlexionDeg() + 1e-9; d += 2) a.push_back(d);
    return a;
}

// Band edges (with tolerance) of the targets of one kind, as two marker series.
void addBands(PlotSpec& spec, const std::vector<TargetScore>& scores, TargetKind kind, const std::string& muscle,
              MuscleGroup direction, double scale, int color, const std::string& label) {
    PlotSeries lo{label, {}, {}, true, color}, hi{"", {}, {}, true, color};
    std::map<double, bool> seen;
    for (const TargetScore& s : scores) {
        const AnatomyTarget& t = s.target;
        if (t.kind != kind || (kind == TargetKind::MomentArm && s.muscle != muscle) ||
            (kind == TargetKind::Mvc && t.direction != direction) || seen[t.flexionDeg])
            continue;
        seen[t.flexionDeg] = true;
        lo.x.push_back(t.flexionDeg), lo.y.push_back(scale * (t.lower - t.tolerance));
        hi.x.push_back(t.flexionDeg), hi.y.push_back(scale * (t.upper + t.tolerance));
    }
    if (lo.x.empty()) return;
    spec.series.push_back(lo);
    spec.series.push_back(hi);
}

}  // namespace

namespace {

// The scorecard, its summary and the two plots (curves over the range) into outDir.
ModelCheckResult writeCheckFiles(std::vector<TargetScore> scores, const AnatomyCurves& curves, const std::string& xLabel,
                                 const std::string& outDir) {
    ModelCheckResult r;
    r.scores = std::move(scores);
    // A target file none of whose targets the model has anything for would give an empty scorecard.
    if (r.scores.empty())
        throw InputError("none of the targets names something the model has (its muscles, share families, volumes "
                         "or forearm): expected at least one target to score");
    r.summary = summarizeScores(r.scores);
    OutputFolder folder(outDir, OutputFolder::Mode::AddFiles);  // every file appears at the end, or none
    auto path = [&](const std::string& f) { return folder.getTargetPath(f); };

    CsvText card({"kind", "muscle", "direction", "flexion_deg", "value", "lower", "upper", "tolerance", "unit", "pass",
                  "source", "where"});
    for (const TargetScore& s : r.scores) {
        const AnatomyTarget& t = s.target;
        CsvRow row;
        row.addText(getTargetKindName(t.kind)).addText(s.muscle);
        row.addText(describeTargetCondition(t));
        row.addNumber(t.flexionDeg).addNumber(s.value).addNumber(t.lower).addNumber(t.upper).addNumber(t.tolerance);
        row.addText(getTargetSiUnit(t.kind)).addInteger(s.pass ? 1 : 0).addText(t.source).addText(t.where);
        card.addRow(row);
    }
    folder.write("scorecard.csv", card.getText());
    CsvText summary({"kind", "muscle", "passed", "scored", "fraction"});
    for (const ScoreSummary& s : r.summary) {
        CsvRow row;
        row.addText(getTargetKindName(s.kind)).addText(s.muscle).addInteger(s.passed).addInteger(s.scored);
        row.addNumber(double(s.passed) / s.scored);
        summary.addRow(row);
    }
    folder.write("score_summary.csv", summary.getText());
    r.files = {path("scorecard.csv"), path("score_summary.csv")};

    // Moment arms: every muscle's curve, the bands of its targets in the same colour.
    const std::vector<double>& angles = curves.flexionDeg;
    PlotSpec arms;
    arms.title = "Moment arms; markers: published band +/- tolerance";
    arms.xLabel = xLabel;
    arms.yLabel = "moment arm (mm), + = flexor";
    for (int m = 0; m < int(curves.muscles.size()); ++m) {
        PlotSeries c{curves.muscles[m], angles, {}, false, m % 8};
        for (std::size_t a = 0; a < angles.size(); ++a) c.y.push_back(1000 * curves.momentArm[a][m]);
        arms.series.push_back(c);
        addBands(arms, r.scores, TargetKind::MomentArm, curves.muscles[m], MuscleGroup::Flexor, 1000, m % 8, "");
    }
    folder.writeWith("check_moment_arms.png", [&](const std::string& p) { writePlotPng(p, arms); });

    PlotSpec mvc;
    mvc.title = "Steady MVC torque; markers: published band +/- tolerance";
    mvc.xLabel = xLabel;
    mvc.yLabel = "net torque magnitude (N m)";
    const MuscleGroup groups[2] = {MuscleGroup::Flexor, MuscleGroup::Extensor};
    for (int k = 0; k < 2; ++k) {
        const SteadyMvcCurve& c = k == 0 ? curves.flexion : curves.extension;
        PlotSeries s{std::string(k == 0 ? "flexion" : "extension") + " MVC (model)", angles, {}, false, k};
        for (double t : c.totalTorque) s.y.push_back(std::abs(t));
        mvc.series.push_back(s);
        addBands(mvc, r.scores, TargetKind::Mvc, "", groups[k], 1, k, k == 0 ? "flexion band" : "extension band");
    }
    folder.writeWith("check_mvc.png", [&](const std::string& p) { writePlotPng(p, mvc); });
    r.files.push_back(path("check_moment_arms.png"));
    r.files.push_back(path("check_mvc.png"));
    folder.commit();
    return r;
}

}  // namespace

ModelCheckResult writeModelCheck(const ArmSetup& setup, const std::vector<AnatomyTarget>& targets,
                                 const std::string& outDir) {
    return writeCheckFiles(scoreAnatomy(setup, targets), calcAnatomyCurves(setup, sweepAngles(setup)), "elbow flexion (deg)",
                           outDir);
}

ModelCheckResult writeOsimModelCheck(const OsimModel& model, const std::string& coordinate, const std::string& muscleModel,
                                     const std::vector<AnatomyTarget>& targets, const std::string& outDir) {
    const OsimArm arm(model, {}, muscleModel);
    const int j = findOsimSweptCoordinate(arm, coordinate);
    const auto [lo, hi] = getOsimCoordinateRangeDeg(arm, j);
    const AnatomyCurves scored = calcOsimAnatomyCurves(arm, j, findAnatomyAngles(targets, lo, hi));
    std::vector<double> angles;
    for (double d = lo; d <= hi + 1e-9; d += 2) angles.push_back(std::min(d, hi));
    const AnatomyCurves drawn = calcOsimAnatomyCurves(arm, j, angles);
    return writeCheckFiles(scoreAnatomyCurves(scored, targets), drawn,
                           (coordinate.empty() ? std::string("the coordinate") : coordinate) + " (deg, as elbow flexion)", outDir);
}

}  // namespace armsim
