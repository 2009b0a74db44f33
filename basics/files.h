// Whole-file reading with size guards and atomic whole-file writing. Framework-free.
#pragma once

#include <cstdint>
#include <string>

namespace armsim {

/// The whole file as bytes. Throws InputError naming the path when it cannot be read.
std::string readFileText(const std::string& path);
/// InputError unless `path` (when it exists) is a regular file of at most maxBytes (a folder, a device
/// such as /dev/zero or a pipe would make a reader block or grow without bound).
void checkInputFile(const std::string& path, std::uintmax_t maxBytes);

/// Writes text to path atomically: to a temporary beside it, then rename. Throws InputError naming
/// the path when it cannot be written. Parent directories are created.
void writeFileAtomically(const std::string& path, const std::string& text);

}  // namespace armsim
