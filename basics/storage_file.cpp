#include "basics/storage_file.h"

#include "basics/numbers.h"
#include "basics/errors.h"
#include "basics/files.h"

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <stdexcept>

namespace armsim {

std::string formatStorage(const Table& t, const std::string& name, bool inDegrees, int digits) {
    if (t.getNumColumns() == 0) throw std::invalid_argument("storage '" + name + "': table has no columns");
    std::string out = name + "\nversion=1\nnRows=" + std::to_string(t.getNumRows()) +
           "\nnColumns=" + std::to_string(t.getNumColumns()) + "\ninDegrees=" + (inDegrees ? "yes" : "no") +
           "\nendheader\ntime";
    for (int c = 1; c < t.getNumColumns(); ++c) out += "\t" + t.getColumnNames()[c];
    out += '\n';
    return out + t.formatRows('\t', digits);
}

Table readStorage(const std::string& path, StorageHeader* header) {
    checkInputFile(path, std::uintmax_t(4) << 30);
    std::ifstream in(path);
    if (!in) throw InputError(path + ": cannot open file (does it exist and is it readable?)");
    StorageHeader h;
    std::string line;
    int lineNo = 0;
    long nRows = -1, nColumns = -1;
    bool ended = false;
    auto at = [&] { return path + ":" + std::to_string(lineNo); };
    auto integer = [&](const std::string& key, const std::string& value) {
        char* end = nullptr;
        const long v = std::strtol(value.c_str(), &end, 10);
        if (value.empty() || *end || v < 0)
            throw InputError(at() + ": header '" + key + "=" + value + "': expected a whole number >= 0");
        return v;
    };
    while (std::getline(in, line)) {
        ++lineNo;
        if (lineNo == 1 && line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);   // a UTF-8 byte-order mark
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (lineNo == 1) {
            h.name = line;
            continue;
        }
        if (line == "endheader") {
            ended = true;
            break;
        }
        const auto eq = line.find('=');
        if (eq == std::string::npos) continue;  // free-text header lines are allowed
        const std::string key = line.substr(0, eq), value = line.substr(eq + 1);
        if (key == "version") h.version = int(integer(key, value));
        else if (key == "nRows") nRows = integer(key, value);
        else if (key == "nColumns") nColumns = integer(key, value);
        else if (key == "inDegrees") {
            if (value != "yes" && value != "no")
                throw InputError(at() + ": header 'inDegrees=" + value + "': expected yes or no");
            h.inDegrees = value == "yes";
        }
    }
    if (!ended) throw InputError(path + ": no 'endheader' line: not an OpenSim storage file");
    if (nRows < 0 || nColumns < 0)
        throw InputError(path + ": header lacks nRows= or nColumns= (required before endheader)");
    if (!std::getline(in, line)) throw InputError(path + ": no column labels after endheader");
    ++lineNo;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::vector<std::string> names;
    for (std::size_t b = 0;;) {
        const std::size_t e = line.find('\t', b);
        names.push_back(line.substr(b, e == std::string::npos ? std::string::npos : e - b));
        if (e == std::string::npos) break;
        b = e + 1;
    }
    if (names.front() != "time")
        throw InputError(at() + ": first column label is '" + names.front() + "': expected 'time'");
    checkUniqueColumnNames(names, at());
    if (long(names.size()) != nColumns)
        throw InputError(at() + ": " + std::to_string(names.size()) + " column labels, header says nColumns=" +
                         std::to_string(nColumns));
    Table t(names);
    while (std::getline(in, line)) {
        ++lineNo;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (line.empty()) continue;
        std::vector<double> row;
        const char* p = line.c_str();
        for (std::size_t c = 0; c < names.size(); ++c) {
            char* end = nullptr;
            const double v = std::strtod(p, &end);
            if (end == p || (*end && *end != '\t') || isHexadecimalText(p))
                throw InputError(at() + ": column '" + names[c] + "': expected a number");
            row.push_back(v);
            p = *end ? end + 1 : end;
            if (c + 1 < names.size() && end == p)
                throw InputError(at() + ": " + std::to_string(c + 1) + " values, expected " +
                                 std::to_string(names.size()));
        }
        if (*p) throw InputError(at() + ": more values than the " + std::to_string(names.size()) + " columns");
        t.appendRow(std::move(row));
    }
    if (t.getNumRows() != nRows)
        throw InputError(path + ": " + std::to_string(t.getNumRows()) + " data rows, header says nRows=" +
                         std::to_string(nRows));
    if (header) *header = h;
    return t;
}

}  // namespace armsim
