// CSV text of result files whose columns are not all numbers (method names, reasons, flags): one
// builder, so every such file quotes, spells numbers and marks missing values the same way. Numeric
// time series use Table::toCsv. Framework-free.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace armsim {

/// One CSV record, built cell by cell, without the line end. Text is quoted (RFC 4180) when it holds a
/// comma, a quote or leading/trailing spaces; line breaks and tabs in text become spaces, so a record is
/// always one line. Numbers are locale-free: by default the shortest form that reads back as the same
/// double; a missing value (NaN) is an empty cell, as spreadsheets and pandas read it; infinities are
/// "inf" and "-inf".
class CsvRow {
public:
    CsvRow& addText(std::string_view text);
    CsvRow& addNumber(double v);
    /// With `significantDigits` significant digits (1..17), e.g. wall times.
    CsvRow& addNumber(double v, int significantDigits);
    CsvRow& addInteger(long long v);
    CsvRow& addEmpty();
    int getNumCells() const { return numCells_; }
    const std::string& getText() const { return text_; }

private:
    void startCell();
    std::string text_;
    int numCells_ = 0;
};

/// A whole CSV file: a header line, then records of the header's width.
class CsvText {
public:
    explicit CsvText(const std::vector<std::string>& header);
    /// Appends a record; std::invalid_argument naming both counts if its width differs from the header's.
    void addRow(const CsvRow& row);
    const std::string& getText() const { return text_; }

private:
    int numColumns_;
    std::string text_;
};

/// The cells of one CSV record (quoted cells unquoted, "" inside quotes read as ").
std::vector<std::string> splitCsvRecord(std::string_view line);

}  // namespace armsim
