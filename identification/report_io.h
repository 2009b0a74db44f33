// Output of an identification run: JSON report, iteration history CSV, convergence plot, text summary.
// Every file is written whole or not at all.
#pragma once

#include "basics/table.h"
#include "identification/identifier.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace armsim {

class OutputFolder;

/// The whole report as JSON (SI units; NaN -> null).
nlohmann::json toJson(const IdentificationReport& report);
/// Writes toJson(report) (indented) atomically.
void writeReportJson(const std::string& path, const IdentificationReport& report);
/// The history as a table: iteration, evaluations, one column per parameter ("mass_kg",
/// "optimal_tendon_length_m"), one per residual ("residual_1_N", ...), "cost_N2".
Table makeHistoryTable(const IdentificationReport& report);
/// Writes makeHistoryTable(report) as CSV atomically.
void writeHistoryCsv(const std::string& path, const IdentificationReport& report);
/// PNG of the residual norm ||r|| [N] against the iteration, log y (zeros drawn at 1e-12 N).
void writeConvergencePlot(const std::string& path, const IdentificationReport& report);
/// Adds <stem>.json, <stem>_history.csv and <stem>_convergence.png to `out` (the plot is left out when no
/// iteration has a finite cost); returns their final paths.
std::vector<std::string> addReportFiles(const IdentificationReport& report, OutputFolder& out,
                                        const std::string& stem = "identification");
/// The same files written to `dir` together (OutputFolder, Mode::AddFiles: all of them or none); returns
/// their paths.
std::vector<std::string> writeReportFiles(const IdentificationReport& report, const std::string& dir,
                                          const std::string& stem = "identification");
/// A few lines for a terminal: stop reason, estimate with intervals, residuals, cost, counts (SI).
std::string formatReport(const IdentificationReport& report);

}  // namespace armsim
