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

/// Runs a shell command and waits for it, once.
inline CommandResult runCommandOnce(const std::string& command) {
    const std::string cmd = command + " 2>&1";
    std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(cmd.c_str(), "r"), pclose);
    std::string out;
    std::array<char, 4096> buf;
    while (std::fgets(buf.data(), int(buf.size()), pipe.get())) out += buf.data();
    const int status = pclose(pipe.release());
    return {WEXITSTATUS(status), out};
}

/// true when a run failed only because LeakSanitizer's own stop-the-world tracer crashed at exit
/// ("Tracer caught signal 11 ... LeakSanitizer has encountered a fatal error"): a known intermittent
/// fault of the sanitizer runtime under load (google/sanitizers#1170), not a leak and not armsim's.
inline bool isLeakSanitizerTracerCrash(const CommandResult& r) {
    return r.exitCode != 0 && r.output.find("Tracer caught signal") != std::string::npos &&
           r.output.find("LeakSanitizer has encountered a fatal error") != std::string::npos;
}

/// Runs a shell command and waits for it; in the sanitizer build a run whose only fault is the leak
/// checker's tracer crash is run once more (a leak report, an ASan or UBSan error fails as always).
inline CommandResult runCommand(const std::string& command) {
    CommandResult r = runCommandOnce(command);
    if (isLeakSanitizerTracerCrash(r)) {
        std::fprintf(stderr, "note: LeakSanitizer's tracer crashed at exit (a sanitizer-runtime fault); running again: %s\n",
                     command.c_str());
        r = runCommandOnce(command);
    }
    return r;
}

/// Runs `armsim <args>` through the shell and waits for it.
inline CommandResult runArmsim(const std::string& args) { return runCommand(std::string(ARMSIM_EXE) + " " + args); }

}  // namespace armsim::testing
