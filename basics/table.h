// A numeric results table (time series, sweeps) with CSV output. Framework-free.
#pragma once

#include <string>
#include <vector>

namespace armsim {

/// Throws InputError "<where>: column 'x' appears twice in the header (columns i and j)" when a name
/// repeats (a reader would silently take one of them).
void checkUniqueColumnNames(const std::vector<std::string>& names, const std::string& where);
/// InputError (at `where`) when a CSV header's cells hold a tab or a semicolon: the file is tab- or
/// semicolon-separated, which a comma split reads as one column.
void checkCommaSeparatedHeader(const std::vector<std::string>& cells, const std::string& where);

/// Named columns of doubles, one row per sample. Column names carry their unit as a suffix
/// ("time_s", "force_N", "activation"), so a CSV header is self-describing.
class Table {
public:
    Table() = default;
    explicit Table(std::vector<std::string> columnNames);

    const std::vector<std::string>& getColumnNames() const { return names_; }
    int getNumColumns() const { return int(names_.size()); }
    int getNumRows() const { return numRows_; }
    /// Index of a column; throws std::invalid_argument naming the column if absent.
    int findColumn(const std::string& name) const;
    bool hasColumn(const std::string& name) const;
    /// Appends a row; throws std::invalid_argument if its size differs from the column count.
    void appendRow(const std::vector<double>& row);
    /// Makes room for n rows in all (no reallocation while appending up to n).
    void reserveRows(int n) { data_.reserve(std::size_t(n) * names_.size()); }
    /// Keeps the first n rows (n <= getNumRows()): undoes appends that must not stay.
    void truncateRows(int n);
    std::vector<double> getRow(int i) const;
    double get(int row, int column) const { return data_[std::size_t(row) * names_.size() + column]; }
    double get(int row, const std::string& column) const { return get(row, findColumn(column)); }
    std::vector<double> getColumn(const std::string& name) const;
    /// Moves the values out (row-major, rows x columns) and leaves the table without rows: for
    /// handing a large table to another owner without a copy (the Python module's arrays).
    std::vector<double> releaseData() {
        numRows_ = 0;
        lines_.clear();
        return std::move(data_);
    }
    /// CSV text: a header line of column names, then rows with `digits` significant digits (1..17;
    /// 17 round-trips every double). Numbers are locale-free; NaN is written "NaN".
    std::string toCsv(int digits = 10) const;
    /// The data rows only, cells joined by `separator`, formatted as in toCsv (for other file formats).
    std::string formatRows(char separator, int digits) const;
    /// Writes toCsv() to path atomically (temporary + rename).
    void writeCsv(const std::string& path, int digits = 10) const;
    /// Reads a CSV file with a header line and numeric cells (empty lines and lines starting with
    /// '#' are skipped). Throws InputError naming file, line and column for a malformed cell or a
    /// column name the header repeats.
    static Table readCsv(const std::string& path);
    /// Line in the source file of data row i (1-based), for messages; 0 when not read from a file.
    int getSourceLine(int row) const { return row < int(lines_.size()) ? lines_[row] : 0; }
    /// Where data row i came from, for messages: "source:line" when read from a file, else
    /// "source row i+1".
    std::string describeRow(const std::string& source, int row) const {
        const int line = getSourceLine(row);
        return line > 0 ? source + ":" + std::to_string(line) : source + " row " + std::to_string(row + 1);
    }

private:
    std::vector<std::string> names_;
    std::vector<double> data_;  // row-major
    int numRows_ = 0;
    std::vector<int> lines_;
};

/// InputError naming `source` and the line unless column `column` of t (a trial table's time_s)
/// increases from row to row with no interval over twice the median one: rows missing from the middle
/// of a table would otherwise be bridged by interpolation.
void checkSampleTimes(const Table& t, const std::string& column, const std::string& source);

}  // namespace armsim
