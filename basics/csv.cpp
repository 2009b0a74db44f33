#include "basics/csv.h"

#include "basics/format.h"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

namespace armsim {

void CsvRow::startCell() {
    if (numCells_++ > 0) text_ += ',';
}

CsvRow& CsvRow::addText(std::string_view text) {
    startCell();
    std::string clean(text);
    for (char& c : clean)
        if (c == '\n' || c == '\r' || c == '\t') c = ' ';
    const bool quote = clean.find_first_of(",\"") != std::string::npos ||
                       (!clean.empty() && (clean.front() == ' ' || clean.back() == ' '));
    if (quote) text_ += '"';
    for (char c : clean) {
        if (c == '"') text_ += '"';
        text_ += c;
    }
    if (quote) text_ += '"';
    return *this;
}

CsvRow& CsvRow::addNumber(double v) {
    startCell();
    if (std::isinf(v)) text_ += v > 0 ? "inf" : "-inf";
    else if (!std::isnan(v)) text_ += formatNumber(v);
    return *this;
}

CsvRow& CsvRow::addNumber(double v, int significantDigits) {
    if (significantDigits < 1 || significantDigits > 17)
        throw std::invalid_argument("CSV significant digits " + std::to_string(significantDigits) + ": expected 1..17");
    startCell();
    if (std::isinf(v)) text_ += v > 0 ? "inf" : "-inf";
    else if (!std::isnan(v)) text_ += fmt::format("{:.{}g}", v, significantDigits);
    return *this;
}

CsvRow& CsvRow::addInteger(long long v) {
    startCell();
    text_ += std::to_string(v);
    return *this;
}

CsvRow& CsvRow::addEmpty() {
    startCell();
    return *this;
}

CsvText::CsvText(const std::vector<std::string>& header) : numColumns_(int(header.size())) {
    CsvRow names;
    for (const std::string& h : header) names.addText(h);
    text_ = names.getText() + '\n';
}

void CsvText::addRow(const CsvRow& row) {
    if (row.getNumCells() != numColumns_)
        throw std::invalid_argument("CSV record has " + std::to_string(row.getNumCells()) + " cells, expected " +
                                    std::to_string(numColumns_) + " (the header's)");
    text_ += row.getText();
    text_ += '\n';
}

std::vector<std::string> splitCsvRecord(std::string_view line) {
    std::vector<std::string> cells(1);
    bool quoted = false;
    for (std::size_t i = 0; i < line.size(); ++i) {
        const char c = line[i];
        if (quoted) {
            if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') cells.back() += '"', ++i;
            else if (c == '"') quoted = false;
            else cells.back() += c;
        } else if (c == '"') {
            quoted = true;
        } else if (c == ',') {
            cells.emplace_back();
        } else {
            cells.back() += c;
        }
    }
    return cells;
}

}  // namespace armsim
