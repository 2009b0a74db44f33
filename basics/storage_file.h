// OpenSim storage (.sto) text of a Table and a reader for .sto files (CSV is Table::toCsv).
// Framework-free.
#pragma once

#include "basics/table.h"

#include <string>

namespace armsim {

/// OpenSim 4 storage text of t (the format of OpenSim's STOFileAdapter / Storage version 1):
///   <name>
///   version=1
///   nRows=<rows>
///   nColumns=<columns, time included>
///   inDegrees=yes|no
///   endheader
///   time<TAB><column 2><TAB>...
///   <rows, tab-separated>
/// The first column of t must be the time (s); it is named "time" in the file, as OpenSim requires.
/// Throws std::invalid_argument for a table without columns.
std::string formatStorage(const Table& t, const std::string& name, bool inDegrees, int digits = 10);

/// What a storage file's header says.
struct StorageHeader {
    std::string name;         ///< first line
    int version = 0;          ///< "version="
    bool inDegrees = false;   ///< "inDegrees="
};

/// Reads a storage file in the form formatStorage writes: header lines up to "endheader" (nRows and
/// nColumns required and checked against the data), a tab-separated row of column labels whose first
/// is "time", then numeric rows. Throws InputError naming the file, line and what is wrong.
Table readStorage(const std::string& path, StorageHeader* header = nullptr);

}  // namespace armsim
