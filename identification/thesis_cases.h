// The thesis's identification cases rerun with armsim's model: ours vs the thesis's numbers.
#pragma once

#include "basics/numbers.h"

#include "identification/identifier.h"

#include <string>
#include <vector>

namespace armsim {

/// The thesis's start of its two-output identifications (Tables 7.2, 7.3): M = 330 g, L0T = 22 cm.
constexpr double kThesisStartMass = 0.330;           ///< [kg]
constexpr double kThesisStartTendonLength = 0.22;    ///< [m]
/// The thesis's estimate from its measured forces (Table 7.3): M = 337.7 g, L0T = 24.4 cm.
constexpr double kThesisMeasuredMass = 0.3377;       ///< [kg]
constexpr double kThesisMeasuredTendonLength = 0.244;  ///< [m]

/// One compared quantity. Values are SI (kg, m, N; counts unitless); NaN thesis = not reported.
struct ThesisComparisonRow {
    std::string caseName;   ///< e.g. "Table 7.2 ilc-sign-search"
    std::string quantity;   ///< "M", "L0T", "Y1 (40 cm)", "iterations", ...
    std::string unit;       ///< "kg", "m", "N" or "" (count)
    double ours = 0;
    double thesis = kNaN;
};

/// A rerun case: its report and its rows.
struct ThesisCase {
    std::string name;
    IdentificationReport report;
    std::vector<ThesisComparisonRow> rows;
};

/// Reruns, from assets measured/thesis_synthetic.csv (596 N at 40 cm, 448 N at 37.5 cm) and
/// measured/thesis_measured.csv (600 N at 41 cm, 458 N at 37.5 cm), with the muscle `base`:
///  - 4.5.1 false position: L0T for 448 N at 37.5 cm with M = 336 g, bracket [22, 30] cm, tolerance
///    1e-3 cm (thesis: 24.01 cm);
///  - Table 7.1 ilc-standard: 596 N at 40 cm from 330 g / 26 cm, gains 0.5 g/N and -0.01 cm/N,
///    tolerance 0.1 N (thesis: 346.2 g, 25.24 cm, 595.6 N);
///  - 7.2.1 ilc-constant: both forces from 330 g / 22 cm with the thesis matrix (thesis: 329.8 g, 24.26 cm);
///  - Table 7.2 ilc-sign-search and lm: both synthetic forces from 330 g / 22 cm (thesis: 335.9 g,
///    24.5 cm, 595.9 N, 448 N, 52 iterations; start forces 575.3 N, 513.1 N);
///  - Table 7.3 ilc-sign-search and lm: the measured forces from 330 g / 22 cm (thesis: 337.7 g,
///    24.4 cm, 599.8 N, 457.9 N, 49 iterations).
std::vector<ThesisCase> reproduceThesisCases(const MuscleParameters& base, const ForceModel& model);
/// All rows of all cases.
std::vector<ThesisComparisonRow> collectRows(const std::vector<ThesisCase>& cases);
/// A fixed-width table in thesis units (g, cm, N), with the stop reason of each case.
std::string formatThesisComparison(const std::vector<ThesisCase>& cases);
/// CSV of collectRows in SI units: case, quantity, unit, ours, thesis (empty when not reported).
std::string formatThesisCasesCsv(const std::vector<ThesisCase>& cases);

}  // namespace armsim
