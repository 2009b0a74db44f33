// The index.html every command that writes a folder leaves in it (basics/html_report.h): what ran and a
// sentence per file, from the file names armsim writes.
#pragma once

#include <CLI/CLI.hpp>

namespace armsim::cli {

/// After a successful command: when the command that ran has an --out that names a folder, writes
/// FOLDER/index.html (command line, version, time, the command's settings, every plot, video and table
/// of the folder). A study's page only from rank 0 under mpirun or srun (its ranks share the folder). Throws std::runtime_error when it cannot write
/// (the caller warns: the command's own files stand).
void writeCommandReport(const CLI::App& app, int argc, char** argv);
/// The folder a command wrote when it is not its --out as typed (a study's `output:` from its file, a
/// protocol's default out/NAME): writeCommandReport writes the page there.
void setReportFolder(const std::string& dir);

/// From now on, what the program writes through C's stdout also goes into a buffer (at most
/// kMaxCapturedStdout bytes; the rest is noted as cut), which writeCommandReport shows. Standard output
/// itself is unchanged: the same bytes, buffering and write errors (ferror(stdout)). Call once, first.
void startStdoutCapture();
/// The buffer so far.
std::string getCapturedStdout();
/// errno of the first write to standard output that failed (0: none), for the message at exit.
int getStdoutWriteError();
constexpr std::size_t kMaxCapturedStdout = 1 << 20;

/// One sentence on what an armsim output file shows, from its path relative to its folder ("" : not
/// an armsim name).
std::string describeOutputFile(const std::string& relativePath);

}  // namespace armsim::cli
