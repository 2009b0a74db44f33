// Internal to experiments/: what the protocol runner (protocol.cpp, compute only) hands to the protocol
// writer (protocol_output.cpp: tables, fits, plots, protocol.yaml, manifest.json).
#pragma once

#include "basics/angles.h"
#include "basics/output_folder.h"
#include "experiments/emg.h"
#include "experiments/protocol.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace armsim {
class ParamNode;
}

namespace armsim::detail {

/// One arm trial of the protocol.
struct ArmTrialPlan {
    int index = 0;            ///< canonical index
    std::string id;           ///< file stem
    double angle = 0;         ///< [rad]
    double level = 1;         ///< fraction of MVC
    int repetition = 1;       ///< 1-based
    double activation = 1;    ///< U during the hold
    std::uint64_t seed = 0;   ///< trial seed
};

/// What an arm trial gives, per-trial metrics and (for the example plot) its time series.
struct ArmTrialOutcome {
    IsometricSummary summary;
    double muscleForce = NAN, activeForce = NAN, forceMeasured = NAN, forceFixedRatio = NAN, strapForce = NAN;
    bool saturated = false;
    EmgFeatures emg{NAN, NAN, NAN};
    std::vector<double> time, emgSignal, emgRms;
};

/// A computed protocol run.
struct ProtocolRun {
    ProtocolResult result;
    std::vector<ArmTrialPlan> plans;      ///< canonical order
    std::vector<int> runPosition;         ///< run order of each plan
    std::vector<std::string> muscleIds;   ///< file stems of the muscle-alone trials
    ArmTrialOutcome example;              ///< trial 0 with its series (the EMG example plot)
};

/// Sorted distinct values.
inline std::vector<double> uniqueSorted(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
    return v;
}

/// Significant digits of the numbers in result files.
constexpr int kCsvDigits = 10;

/// One protocol kind: its name in protocol files and what is particular to it. The table
/// (protocol_kinds.cpp) has one row per kind: a new kind is an enum value, its functions and a row.
struct ProtocolKindSpec {
    ProtocolKind kind;
    const char* name;        ///< `kind:` in protocol files
    bool armTrials;          ///< runs arm trials (false: the slow x fast unit grid)
    bool levelInTrialId;     ///< several levels per angle: trial files are named by level too
    /// Reads the `conditions` section c into p (angles, levels, ranges or the unit grid); InputError
    /// naming the file, line and field. arm: the subject's; pMax: its primary muscle's P_max [m].
    void (*readConditions)(const ParamNode& c, Protocol& p, const ArmParameters& arm, double pMax);
    /// The kind's fits of a computed run; nullptr: none.
    void (*fit)(const Protocol& p, ProtocolResult& result);
    /// The kind's own files in the run folder (its plots; the grid's tables).
    void (*write)(OutputFolder& dir, const Protocol& p, const ProtocolResult& result);
};

/// Every kind, in the order protocol files' `kind:` lists them.
const std::vector<ProtocolKindSpec>& getProtocolKindSpecs();
const ProtocolKindSpec& getProtocolKindSpec(ProtocolKind kind);

// The kinds' functions: conditions readers (protocol_file.cpp), fits (protocol.cpp), writers
// (protocol_output.cpp).
void readMvcConditions(const ParamNode& c, Protocol& p, const ArmParameters& arm, double pMax);
void readSubmaximalConditions(const ParamNode& c, Protocol& p, const ArmParameters& arm, double pMax);
void readForceLengthConditions(const ParamNode& c, Protocol& p, const ArmParameters& arm, double pMax);
void readCompositionConditions(const ParamNode& c, Protocol& p, const ArmParameters& arm, double pMax);
void fitMvc(const Protocol& p, ProtocolResult& result);
void fitSubmaximal(const Protocol& p, ProtocolResult& result);
void fitForceLength(const Protocol& p, ProtocolResult& result);
void writeMvcFiles(OutputFolder& dir, const Protocol& p, const ProtocolResult& result);
void writeSubmaximalFiles(OutputFolder& dir, const Protocol& p, const ProtocolResult& result);
void writeForceLengthFiles(OutputFolder& dir, const Protocol& p, const ProtocolResult& result);
void writeCompositionFiles(OutputFolder& dir, const Protocol& p, const ProtocolResult& result);

/// Writes the run's tables, fits, plots, protocol.yaml, what beforeCommit adds and manifest.json into
/// dir and commits it; fills run.result.files.
void writeProtocolFiles(OutputFolder& dir, const Protocol& protocol, const ArmSetup& subject,
                        const VirtualMuscle& muscle, ProtocolRun& run,
                        const std::function<void(OutputFolder&, const ProtocolResult&)>& beforeCommit);

}  // namespace armsim::detail
