#include "basics/table.h"

#include "basics/numbers.h"
#include "basics/errors.h"
#include "basics/files.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace armsim {

Table::Table(std::vector<std::string> columnNames) : names_(std::move(columnNames)) {}

void checkUniqueColumnNames(const std::vector<std::string>& names, const std::string& where) {
    for (std::size_t i = 0; i < names.size(); ++i)
        for (std::size_t j = 0; j < i; ++j)
            if (names[i] == names[j])
                throw InputError(where + ": column '" + names[i] + "' appears twice in the header (columns " +
                                 std::to_string(j + 1) + " and " + std::to_string(i + 1) + "): expected each name once");
}

void checkCommaSeparatedHeader(const std::vector<std::string>& cells, const std::string& where) {
    for (const std::string& c : cells)
        for (const auto& [sep, name] : {std::pair<char, const char*>{'\t', "a tab"}, {';', "a semicolon"}})
            if (c.find(sep) != std::string::npos)
                throw InputError(where + ": the header's '" + c.substr(0, 60) + (c.size() > 60 ? "..." : "") +
                                 "' holds " + name + ": expected comma-separated columns (save the file as CSV "
                                 "with commas)");
}

int Table::findColumn(const std::string& name) const {
    for (int i = 0; i < getNumColumns(); ++i)
        if (names_[i] == name) return i;
    throw std::invalid_argument("table has no column '" + name + "'");
}

bool Table::hasColumn(const std::string& name) const {
    for (const auto& n : names_)
        if (n == name) return true;
    return false;
}

void Table::appendRow(const std::vector<double>& row) {
    if (row.size() != names_.size())
        throw std::invalid_argument("table row has " + std::to_string(row.size()) + " values, expected " +
                                    std::to_string(names_.size()));
    if ((numRows_ & 255) == 0) checkInterruption();  // long recordings, sweeps and reads stop promptly
    data_.insert(data_.end(), row.begin(), row.end());
    ++numRows_;
}

void Table::truncateRows(int n) {
    if (n < 0 || n > numRows_) throw std::invalid_argument("truncateRows: " + std::to_string(n) + " of " + std::to_string(numRows_) + " rows");
    data_.resize(std::size_t(n) * names_.size());
    if (int(lines_.size()) > n) lines_.resize(n);
    numRows_ = n;
}

std::vector<double> Table::getRow(int i) const {
    const auto first = data_.begin() + std::ptrdiff_t(i) * std::ptrdiff_t(names_.size());
    return std::vector<double>(first, first + std::ptrdiff_t(names_.size()));
}

std::vector<double> Table::getColumn(const std::string& name) const {
    const int c = findColumn(name);
    std::vector<double> out;
    out.reserve(std::size_t(numRows_));
    for (int i = 0; i < numRows_; ++i) out.push_back(get(i, c));
    return out;
}

namespace {

void checkDigits(int digits) {
    if (digits < 1 || digits > 17) throw std::invalid_argument("CSV digits must be in [1, 17]");
}

void appendNumber(std::string& out, double v, int digits) {
    if (std::isnan(v)) {
        out += "NaN";
        return;
    }
    char buf[40];
    const auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general, digits);
    out.append(buf, r.ptr);
}

}  // namespace

std::string Table::formatRows(char separator, int digits) const {
    checkDigits(digits);
    std::string out;
    out.reserve(data_.size() * std::size_t(digits + 7));
    for (int i = 0; i < numRows_; ++i) {
        if ((i & 4095) == 0) checkInterruption();  // millions of rows take seconds
        for (int c = 0; c < getNumColumns(); ++c) {
            if (c) out += separator;
            appendNumber(out, get(i, c), digits);
        }
        out += '\n';
    }
    return out;
}

std::string Table::toCsv(int digits) const {
    std::string out;
    for (int i = 0; i < getNumColumns(); ++i) out += (i ? "," : "") + names_[i];
    out += '\n';
    return out + formatRows(',', digits);
}

void Table::writeCsv(const std::string& path, int digits) const { writeFileAtomically(path, toCsv(digits)); }

void checkSampleTimes(const Table& t, const std::string& column, const std::string& source) {
    const std::vector<double> time = t.getColumn(column);
    const auto number = [](double x) {
        std::ostringstream s;
        s.precision(10);
        s << x;
        return s.str();
    };
    std::vector<double> steps;
    for (std::size_t i = 1; i < time.size(); ++i) {
        if (!(time[i] > time[i - 1]))
            throw InputError(t.describeRow(source, int(i)) + ": " + column + " = " + number(time[i]) +
                             ": expected a time after the previous row's " + number(time[i - 1]) + " s");
        steps.push_back(time[i] - time[i - 1]);
    }
    if (steps.empty()) return;
    std::vector<double> sorted = steps;
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    const double interval = sorted[sorted.size() / 2];
    constexpr double kMaxGap = 2;   // intervals per row; a trial table's are equal, the last may be shorter
    for (std::size_t i = 0; i < steps.size(); ++i)
        if (steps[i] > kMaxGap * interval * (1 + 1e-9))
            throw InputError(t.describeRow(source, int(i + 1)) + ": " + column + " jumps from " + number(time[i]) +
                             " to " + number(time[i + 1]) + " s, " + number(steps[i] / interval) +
                             " times the table's sample interval of " + number(interval) +
                             " s: rows are missing; expected evenly spaced rows, as armsim trial writes them");
}

namespace {

// The cells of one CSV line, trimmed of blanks; a cell in double quotes (RFC 4180: "" is a quote)
// keeps its commas and loses its quotes.
std::vector<std::string> splitCsvLine(const std::string& line, const std::string& at) {
    std::vector<std::string> cells;
    std::string cell;
    bool quoted = false;
    const auto push = [&] {
        const auto b = cell.find_first_not_of(" \t\r"), e = cell.find_last_not_of(" \t\r");
        cells.push_back(b == std::string::npos ? "" : cell.substr(b, e - b + 1));
        cell.clear();
    };
    for (std::size_t i = 0; i < line.size(); ++i) {
        const char c = line[i];
        if (quoted) {
            if (c != '"') cell += c;
            else if (i + 1 < line.size() && line[i + 1] == '"') cell += '"', ++i;
            else quoted = false;
        } else if (c == '"' && cell.find_first_not_of(" \t") == std::string::npos) {
            quoted = true;
            cell.clear();
        } else if (c == ',') {
            push();
        } else {
            cell += c;
        }
    }
    if (quoted) throw InputError(at + ": a double quote is opened and not closed: expected \"...\" around a cell");
    push();
    return cells;
}

}  // namespace

Table Table::readCsv(const std::string& path) {
    checkInputFile(path, std::uintmax_t(4) << 30);
    std::ifstream in(path);
    if (!in) throw InputError(path + ": cannot open file (does it exist and is it readable?)");
    Table t;
    std::string line;
    int lineNo = 0;
    int trailingEmpty = 0;   // empty names after the header's last column (trailing commas)
    bool header = true;
    while (std::getline(in, line)) {
        ++lineNo;
        if (lineNo == 1 && line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);   // a UTF-8 byte-order mark
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (line.find_first_not_of(" \t") == std::string::npos || line[line.find_first_not_of(" \t")] == '#')
            continue;
        std::vector<std::string> cells = splitCsvLine(line, path + ":" + std::to_string(lineNo));
        if (header) {
            // Trailing commas (a spreadsheet's empty last columns) are no columns; an empty name inside is.
            while (cells.size() > 1 && cells.back().empty()) cells.pop_back(), ++trailingEmpty;
            for (std::size_t i = 0; i < cells.size(); ++i)
                if (cells[i].empty())
                    throw InputError(path + ":" + std::to_string(lineNo) + ": the header's column " + std::to_string(i + 1) +
                                     " has no name: expected a name for every column");
            checkCommaSeparatedHeader(cells, path + ":" + std::to_string(lineNo));
            checkUniqueColumnNames(cells, path + ":" + std::to_string(lineNo));
            t.names_ = cells;
            header = false;
            continue;
        }
        const std::string at = path + ":" + std::to_string(lineNo);
        for (int k = 0; k < trailingEmpty && cells.size() > t.names_.size() && cells.back().empty(); ++k) cells.pop_back();
        if (cells.size() != t.names_.size())
            throw InputError(at + ": " + std::to_string(cells.size()) + " values, expected " +
                             std::to_string(t.names_.size()) + " (one per header column)");
        std::vector<double> row;
        row.reserve(cells.size());
        for (std::size_t i = 0; i < cells.size(); ++i) {
            char* end = nullptr;
            errno = 0;
            const double v = std::strtod(cells[i].c_str(), &end);
            if (cells[i].empty() || end != cells[i].c_str() + cells[i].size() || isHexadecimalText(cells[i].c_str()))
                throw InputError(at + ": column '" + t.names_[i] + "' = '" + cells[i] + "': expected a number");
            if (errno == ERANGE && std::abs(v) > 1)   // read as inf otherwise, and reported as "inf"
                throw InputError(at + ": column '" + t.names_[i] + "' = '" + cells[i] +
                                 "': beyond the largest number (1.8e+308): expected a finite number");
            row.push_back(v);
        }
        t.appendRow(row);
        t.lines_.push_back(lineNo);
    }
    if (header) throw InputError(path + ": empty file (expected a header line of column names)");
    return t;
}

}  // namespace armsim
