// Runs the built armsim command (ARMSIM_EXE, set by the test target) and captures its output, for the
// end-to-end CLI tests of every folder.
#pragma once

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <memory>
#include <string>

namespace armsim::testing {

struct CommandResult {
    int exitCode;        ///< the process's exit status
    std::string output;  ///< stdout and stderr, interleaved
};

/// Runs a shell command and waits for it.
inline CommandResult runCommand(const std::string& command) {
    const std::string cmd = command + " 2>&1";
    std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(cmd.c_str(), "r"), pclose);
    std::string out;
    std::array<char, 4096> buf;
    while (std::fgets(buf.data(), int(buf.size()), pipe.get())) out += buf.data();
    const int status = pclose(pipe.release());
    return {WEXITSTATUS(status), out};
}

/// Runs `armsim <args>` through the shell and waits for it.
inline CommandResult runArmsim(const std::string& args) { return runCommand(std::string(ARMSIM_EXE) + " " + args); }

}  // namespace armsim::testing
