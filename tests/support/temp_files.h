// Scratch folders and whole-file reads for the tests of every folder.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace armsim::testing {

/// An empty folder under the system's temporary directory, unique per test process:
/// <tmp>/armsim_<prefix>_<name>_<pid>.
inline std::filesystem::path makeFreshDir(const std::string& prefix, const std::string& name) {
    const std::filesystem::path d =
        std::filesystem::temp_directory_path() / ("armsim_" + prefix + "_" + name + "_" + std::to_string(::getpid()));
    std::filesystem::remove_all(d);
    std::filesystem::create_directories(d);
    return d;
}

/// The file's bytes ("" when it cannot be read).
inline std::string readFileText(const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

}  // namespace armsim::testing
