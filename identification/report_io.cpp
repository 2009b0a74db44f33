#include "identification/report_io.h"

#include "basics/files.h"
#include "basics/output_folder.h"
#include "basics/plot.h"
#include "basics/table.h"

#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

namespace armsim {

namespace {

std::string columnName(const ParameterEstimate& e) { return e.unit == "1" ? e.name : e.name + "_" + e.unit; }

nlohmann::json number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

nlohmann::json numbers(const std::vector<double>& v) {
    nlohmann::json a = nlohmann::json::array();
    for (double x : v) a.push_back(number(x));
    return a;
}

}  // namespace

nlohmann::json toJson(const IdentificationReport& r) {
    nlohmann::json j;
    j["method"] = r.method;
    j["force_model"] = r.forceModel;
    j["data_source"] = r.dataSource;
    j["stop_reason"] = getStopReasonName(r.stopReason);
    j["converged"] = r.isConverged();
    j["message"] = r.message;
    j["iterations"] = r.iterations;
    j["forward_evaluations"] = r.forwardEvaluations;
    j["wall_time_s"] = r.wallTime;
    j["cost_N2"] = number(r.cost);
    j["rms_residual_N"] = number(r.rmsResidual);
    nlohmann::json params = nlohmann::json::array();
    for (const ParameterEstimate& e : r.parameters)
        params.push_back({{"name", e.name},
                          {"unit", e.unit},
                          {"value", number(e.value)},
                          {"start", number(e.start)},
                          {"lower", number(e.lower)},
                          {"upper", number(e.upper)},
                          {"at_bound", e.atBound},
                          {"standard_error", number(e.standardError)},
                          {"interval", {number(e.ciLower), number(e.ciUpper)}}});
    j["parameters"] = params;
    nlohmann::json obs = nlohmann::json::array();
    for (std::size_t k = 0; k < r.observations.size(); ++k) {
        const Observation& o = r.observations[k];
        obs.push_back({{"path_m", o.pathLength},
                       {"angle_rad", number(o.angle)},
                       {"activation", o.activation},
                       {"trial", o.trial},
                       {"subject", o.subject},
                       {"line", o.line},
                       {"measured_N", o.force},
                       {"model_N", number(k < r.modelForces.size() ? r.modelForces[k] : NAN)},
                       {"residual_N", number(k < r.residuals.size() ? r.residuals[k] : NAN)}});
    }
    j["observations"] = obs;
    nlohmann::json u;
    u["available"] = r.hasUncertainty;
    u["note"] = r.uncertaintyNote;
    u["degrees_of_freedom"] = r.degreesOfFreedom;
    u["residual_sd_N"] = number(r.residualSd);
    u["interval_quantile"] = number(r.intervalQuantile);
    nlohmann::json cov = nlohmann::json::array(), cor = nlohmann::json::array();
    for (const auto& row : r.covariance) cov.push_back(numbers(row));
    for (const auto& row : r.correlation) cor.push_back(numbers(row));
    u["covariance"] = cov;
    u["correlation"] = cor;
    j["uncertainty"] = u;
    j["start_costs_N2"] = numbers(r.startCosts);
    nlohmann::json checks = nlohmann::json::array();
    for (const ModelCheck& c : r.checks)
        checks.push_back({{"model", c.model},
                          {"note", c.note},
                          {"forces_N", numbers(c.forces)},
                          {"residuals_N", numbers(c.residuals)},
                          {"rms_residual_N", number(c.rmsResidual)},
                          {"failure", c.failure}});
    j["model_checks"] = checks;
    j["history_length"] = r.history.size();
    return j;
}

void writeReportJson(const std::string& path, const IdentificationReport& report) {
    writeFileAtomically(path, toJson(report).dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) + "\n");
}

Table makeHistoryTable(const IdentificationReport& r) {
    std::vector<std::string> names = {"iteration", "evaluations"};
    for (const ParameterEstimate& e : r.parameters) names.push_back(columnName(e));
    for (std::size_t k = 0; k < r.observations.size(); ++k) names.push_back("residual_" + std::to_string(k + 1) + "_N");
    names.push_back("cost_N2");
    Table t(names);
    for (const IterationRecord& h : r.history) {
        std::vector<double> row = {double(h.iteration), double(h.evaluations)};
        row.insert(row.end(), h.parameters.begin(), h.parameters.end());
        std::vector<double> res = h.residuals;
        res.resize(r.observations.size(), NAN);
        row.insert(row.end(), res.begin(), res.end());
        row.push_back(h.cost);
        t.appendRow(row);
    }
    return t;
}

void writeHistoryCsv(const std::string& path, const IdentificationReport& report) {
    makeHistoryTable(report).writeCsv(path, 12);
}

void writeConvergencePlot(const std::string& path, const IdentificationReport& r) {
    PlotSpec spec;
    spec.title = "identification: " + r.method + " (" + getStopReasonName(r.stopReason) + ")";
    spec.xLabel = "iteration";
    spec.yLabel = "residual norm ||r|| (N)";
    spec.logY = true;
    PlotSeries s;
    s.label = "||model - measured||";
    for (std::size_t i = 0; i < r.history.size(); ++i) {
        s.x.push_back(r.history[i].iteration);
        s.y.push_back(std::max(std::sqrt(2.0 * r.history[i].cost), 1e-12));
    }
    s.markers = s.x.size() == 1;
    spec.series.push_back(s);
    writePlotPng(path, spec);
}

std::vector<std::string> addReportFiles(const IdentificationReport& report, OutputFolder& out, const std::string& stem) {
    std::vector<std::string> names = {stem + ".json", stem + "_history.csv"};
    out.writeWith(names[0], [&](const std::string& p) { writeReportJson(p, report); });
    out.writeWith(names[1], [&](const std::string& p) { writeHistoryCsv(p, report); });
    // A run whose forward model failed from the start has no finite cost to plot: no plot, the report says why.
    bool finite = false;
    for (const IterationRecord& h : report.history) finite = finite || std::isfinite(h.cost);
    if (finite) {
        names.push_back(stem + "_convergence.png");
        out.writeWith(names.back(), [&](const std::string& p) { writeConvergencePlot(p, report); });
    }
    std::vector<std::string> paths;
    for (const std::string& n : names) paths.push_back(out.getTargetPath(n));
    return paths;
}

std::vector<std::string> writeReportFiles(const IdentificationReport& report, const std::string& dir,
                                          const std::string& stem) {
    OutputFolder out(dir, OutputFolder::Mode::AddFiles);
    std::vector<std::string> paths = addReportFiles(report, out, stem);
    out.commit();
    return paths;
}

std::string formatReport(const IdentificationReport& r) {
    std::ostringstream s;
    s << "method " << r.method << " (" << r.forceModel << " model), data " << r.dataSource << "\n";
    s << "stop: " << getStopReasonName(r.stopReason) << ": " << r.message << "\n";
    for (const ParameterEstimate& e : r.parameters) {
        s << fmt::format("  {:<24} {:.6g} {}", e.name, e.value, e.unit);
        if (std::isfinite(e.standardError))
            s << fmt::format("  (se {:.3g}, interval [{:.6g}, {:.6g}])", e.standardError, e.ciLower, e.ciUpper);
        s << (e.atBound ? "  AT BOUND" : "") << "\n";
    }
    if (!r.uncertaintyNote.empty()) s << "uncertainty: " << r.uncertaintyNote << "\n";
    if (r.correlation.size() == 2) {
        s << fmt::format("correlation {} / {}: {:.4f}\n", r.parameters[0].name, r.parameters[1].name,
                         r.correlation[0][1]);
    }
    for (std::size_t k = 0; k < r.observations.size(); ++k)
        s << fmt::format("  path {:.4f} m  U {:.3g}  measured {:.2f} N  model {:.2f} N  residual {:+.3f} N\n",
                         r.observations[k].pathLength, r.observations[k].activation, r.observations[k].force,
                         r.modelForces[k], r.residuals[k]);
    s << fmt::format("rms residual {:.4g} N, {} iterations, {} forward evaluations, {:.3g} s\n", r.rmsResidual,
                     r.iterations, r.forwardEvaluations, r.wallTime);
    for (const ModelCheck& c : r.checks) {
        s << "re-check with the " << (c.note.empty() ? c.model + " model" : c.note) << ": ";
        if (!c.failure.empty()) {
            s << "failed: " << c.failure << "\n";
            continue;
        }
        s << fmt::format("rms residual {:.4g} N; residuals", c.rmsResidual);
        for (double v : c.residuals) s << fmt::format(" {:+.3f}", v);
        s << " N\n";
    }
    return s.str();
}

}  // namespace armsim
