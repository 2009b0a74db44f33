// Where a write to a path lands: the path itself, or the file a symbolic link at it points to (written
// through: the link stays). One rule for every writer (AtomicFileWriter, OutputFiles).
#pragma once

#include <string>

namespace armsim {

struct WriteTarget {
    std::string path;        ///< where the bytes go ("" when a link cannot be resolved)
    bool isFile = true;      ///< false: a link to something that is not a regular file (a pipe, a folder) or to nothing
};

/// `path` when it is not a symbolic link; else the link's resolved target.
WriteTarget findWriteTarget(const std::string& path);

}  // namespace armsim
