#include "identification/thesis_cases.h"

#include "basics/csv.h"
#include "muscles/muscle_file.h"

#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <sstream>

namespace armsim {

namespace {

ObservationSet onlyPath(const ObservationSet& set, double path) {
    ObservationSet out;
    out.source = set.source;
    for (const Observation& o : set.points)
        if (std::abs(o.pathLength - path) < 1e-9) out.points.push_back(o);
    return out;
}

std::vector<Unknown> unknownsFrom(double mass, double tendon) {
    std::vector<Unknown> u = makeDefaultUnknowns();
    u[0].start = mass;
    u[1].start = tendon;
    return u;
}

/// Rows M, L0T, one force per observation, iterations.
std::vector<ThesisComparisonRow> resultRows(const std::string& name, const IdentificationReport& r,
                                            const std::vector<double>& thesisParams,
                                            const std::vector<double>& thesisForces, double thesisIterations) {
    std::vector<ThesisComparisonRow> rows;
    const char* labels[] = {"M", "L0T"};
    for (std::size_t j = 0; j < r.parameters.size(); ++j) {
        const bool isMass = r.parameters[j].name == "mass";
        rows.push_back({name, r.parameters.size() == 2 ? labels[j] : (isMass ? "M" : "L0T"), r.parameters[j].unit,
                        r.parameters[j].value, j < thesisParams.size() ? thesisParams[j] : kNaN});
    }
    for (std::size_t k = 0; k < r.observations.size(); ++k) {
        const std::string q = fmt::format("Y{} ({:.1f} cm)", k + 1, r.observations[k].pathLength * 100);
        rows.push_back({name, q, "N", r.modelForces[k], k < thesisForces.size() ? thesisForces[k] : kNaN});
    }
    rows.push_back({name, "iterations", "", double(r.iterations), thesisIterations});
    return rows;
}

/// Rows with the model's forces at the start (thesis "initial value" column).
std::vector<ThesisComparisonRow> startRows(const std::string& name, const MuscleParameters& start,
                                           const ForceModel& model, const ObservationSet& data,
                                           const std::vector<double>& thesisForces) {
    const std::vector<double> y = model.calcForces(start, data.points);
    std::vector<ThesisComparisonRow> rows;
    for (std::size_t k = 0; k < y.size(); ++k) {
        const std::string q = fmt::format("Y{} at start ({:.1f} cm)", k + 1, data.points[k].pathLength * 100);
        rows.push_back({name, q, "N", y[k], k < thesisForces.size() ? thesisForces[k] : kNaN});
    }
    return rows;
}

}  // namespace

std::vector<ThesisCase> reproduceThesisCases(const MuscleParameters& base, const ForceModel& model) {
    const ObservationSet synthetic = readObservations(findAsset("measured/thesis_synthetic.csv"));
    const ObservationSet measured = readObservations(findAsset("measured/thesis_measured.csv"));
    std::vector<ThesisCase> cases;

    {  // 4.5.1 false position
        IdentificationProblem pr;
        pr.base = base;
        pr.base.mass = 0.336;
        pr.data = onlyPath(synthetic, 0.375);
        Unknown u = makeUnknown(ParameterId::OptimalTendonLength);
        u.lower = 0.22, u.upper = 0.30, u.start = 0.26, u.tolerance = 1e-5;
        pr.unknowns = {u};
        IdentificationOptions o;
        o.method = Method::FalsePosition;
        ThesisCase c{"4.5.1 false-position", identify(pr, model, o), {}};
        c.rows = resultRows(c.name, c.report, {0.2401}, {448}, kNaN);
        cases.push_back(std::move(c));
    }
    {  // Table 7.1 one output
        IdentificationProblem pr;
        pr.base = base;
        pr.data = onlyPath(synthetic, 0.40);
        pr.unknowns = unknownsFrom(kThesisStartMass, 0.26);
        IdentificationOptions o;
        o.method = Method::IlcStandard;
        ThesisCase c{"Table 7.1 ilc-standard", identify(pr, model, o), {}};
        c.rows = resultRows(c.name, c.report, {0.3462, 0.2524}, {595.6}, kNaN);
        cases.push_back(std::move(c));
    }
    {  // 7.2.1 constant gain matrix
        IdentificationProblem pr;
        pr.base = base;
        pr.data = synthetic;
        pr.unknowns = unknownsFrom(kThesisStartMass, kThesisStartTendonLength);
        IdentificationOptions o;
        o.method = Method::IlcConstant;
        ThesisCase c{"7.2.1 ilc-constant", identify(pr, model, o), {}};
        c.rows = resultRows(c.name, c.report, {0.3298, 0.2426}, {}, kNaN);
        cases.push_back(std::move(c));
    }
    struct TwoOutput {
        const char* table;
        const ObservationSet* data;
        std::vector<double> params, forces, startForces;
        double iterations;
    };
    const TwoOutput twoOutput[] = {
        {"Table 7.2", &synthetic, {0.3359, 0.245}, {595.9, 448}, {575.3, 513.1}, 52},
        {"Table 7.3", &measured, {kThesisMeasuredMass, kThesisMeasuredTendonLength}, {599.8, 457.9}, {575.3, 513.1}, 49}};
    for (const TwoOutput& t : twoOutput)
        for (Method m : {Method::IlcSignSearch, Method::LevenbergMarquardt}) {
            IdentificationProblem pr;
            pr.base = base;
            pr.data = *t.data;
            pr.unknowns = unknownsFrom(kThesisStartMass, kThesisStartTendonLength);
            IdentificationOptions o;
            o.method = m;
            ThesisCase c{std::string(t.table) + " " + getMethodName(m), identify(pr, model, o), {}};
            c.rows = resultRows(c.name, c.report, t.params, t.forces, t.iterations);
            const auto s = startRows(c.name, ParameterMap(pr.base, pr.unknowns).toMuscle({kThesisStartMass, kThesisStartTendonLength}), model,
                                     pr.data, t.startForces);
            c.rows.insert(c.rows.end(), s.begin(), s.end());
            cases.push_back(std::move(c));
        }
    return cases;
}

std::vector<ThesisComparisonRow> collectRows(const std::vector<ThesisCase>& cases) {
    std::vector<ThesisComparisonRow> rows;
    for (const ThesisCase& c : cases) rows.insert(rows.end(), c.rows.begin(), c.rows.end());
    return rows;
}

std::string formatThesisComparison(const std::vector<ThesisCase>& cases) {
    std::ostringstream s;
    s << fmt::format("{:<30} {:<22} {:>12} {:>12}  {}\n", "case", "quantity", "ours", "thesis", "unit");
    for (const ThesisCase& c : cases) {
        for (const ThesisComparisonRow& r : c.rows) {
            double k = 1;
            std::string unit = r.unit;
            if (unit == "kg") k = 1000, unit = "g";
            if (unit == "m") k = 100, unit = "cm";
            const std::string thesis = std::isfinite(r.thesis) ? fmt::format("{:.2f}", r.thesis * k) : "-";
            s << fmt::format("{:<30} {:<22} {:12.2f} {:>12}  {}\n", r.caseName, r.quantity, r.ours * k, thesis, unit);
        }
        s << "    -> " << getStopReasonName(c.report.stopReason) << ", " << c.report.forwardEvaluations
          << " forward evaluations: " << c.report.message << "\n";
    }
    return s.str();
}

std::string formatThesisCasesCsv(const std::vector<ThesisCase>& cases) {
    CsvText csv({"case", "quantity", "unit", "ours", "thesis"});
    for (const ThesisComparisonRow& r : collectRows(cases)) {
        CsvRow row;
        row.addText(r.caseName).addText(r.quantity).addText(r.unit).addNumber(r.ours, 10).addNumber(r.thesis, 10);
        csv.addRow(row);
    }
    return csv.getText();
}

}  // namespace armsim
