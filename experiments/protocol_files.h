// Every kind of protocol file in one table (getProtocolFileKinds): the arm kinds (mvc, submaximal,
// force_length, composition: experiments/protocol.h, one runner with a row per kind in
// protocol_kinds.cpp) and torque (experiments/torque_protocol.h). A row reads a file of its kind, runs
// it on the subject the file names, writes the run folder and says what it found in a few lines of
// text. `armsim protocol` and Python's run_protocol go through runProtocolFile; a new kind is a row.
#pragma once

#include "experiments/channels.h"
#include "experiments/protocol.h"
#include "experiments/torque_protocol.h"

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace armsim {

class OutputFolder;

/// How to run a protocol file.
struct ProtocolFileOptions {
    std::string outDir;   ///< run folder, written whole (ProtocolRunOptions::outDir); "" = the kind's default
    bool write = true;    ///< false: compute only
    int jobs = 1;
    std::function<void(int done, int total)> progress;
    /// Called once the file is read, before the run: the protocol's name and what it is (kind,
    /// description, conditions) for a person.
    std::function<void(const std::string& name, const std::string& text)> onStart;
    /// Arm kinds: extra files written into the run before it is put in place (the trials' videos).
    /// Kinds without per-trial series refuse it (InputError).
    std::function<void(OutputFolder& dir, const ArmSetup& subject, const ProtocolResult& result)> beforeCommit;
};

/// What a protocol file's run gives: the kind's own result, the files and a summary for a person.
struct ProtocolFileRun {
    std::string kind;                         ///< the file's `kind:`
    std::string name;                         ///< the protocol's name
    std::string outDir;                       ///< where it was written ("" when compute only)
    std::string text;                         ///< results, fits and what was written, for a person
    std::optional<Protocol> armProtocol;      ///< arm kinds: the protocol read
    std::optional<ProtocolResult> armResult;  ///< arm kinds: the run
    std::optional<TorqueProtocol> torqueProtocol;  ///< torque: the protocol read
    std::optional<TorqueProtocolRun> torqueRun;    ///< torque: the run
    std::vector<std::string> files;           ///< written
};

/// One kind of protocol file.
struct ProtocolFileKind {
    std::string name;   ///< `kind:` in the file
    ProtocolFileRun (*run)(const std::string& path, const ProtocolFileOptions& options);
};

/// Every kind, in the order error messages list them: the arm kinds' rows come from their own table
/// (protocol_kinds.cpp: a new arm kind is a row there), then the kinds with runners of their own.
const std::vector<ProtocolFileKind>& getProtocolFileKinds();

/// An arm protocol's results for a person: the summary per condition, the fits and what was written
/// (outDir; "" = nothing).
std::string formatProtocolResult(const Protocol& protocol, const ProtocolResult& result, const std::string& outDir);

/// Reads the file's `kind:` and runs it through its row; InputError naming the file, line and the kinds
/// for a kind no row has.
ProtocolFileRun runProtocolFile(const std::string& path, const ProtocolFileOptions& options);

}  // namespace armsim
