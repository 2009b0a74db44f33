// Scratch folders and whole-file reads for the tests of every folder.
#pragma once

#include "basics/errors.h"

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

/// Writes text to <tmp>/name and returns its path (input files for the loaders' tests).
inline std::string writeTempFile(const std::string& name, const std::string& text) {
    const auto path = std::filesystem::temp_directory_path() / name;
    std::ofstream(path) << text;
    return path.string();
}

/// The message of the InputError f throws ("" when it throws none).
template <class F> std::string getInputErrorOf(F&& f) {
    try {
        f();
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}

}  // namespace armsim::testing
