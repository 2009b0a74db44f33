// Experiment protocols (thesis 6.1, 6.2, 7.3): YAML data files in assets/protocols/ that list the
// trials, their order, repetitions, durations, sensors and noise; a runner that executes them in
// parallel and deterministically for a seed; and the result files of a run (per-trial time series as
// CSV and OpenSim .sto, trial and summary tables, fits, plots, a JSON manifest), written into a
// temporary directory that is renamed into place only when the whole run succeeded.
//
// Protocol kinds:
//   mvc           maximal efforts (U = 1) at elbow angles x repetitions; quadratic force-angle fit.
//   submaximal    efforts at % MVC levels x angles x repetitions. The 100 % trials run first; every
//                 other level is resolved to the activation whose steady active force (muscle force
//                 minus passive rest force) is that fraction of the subject's simulated MVC at the same
//                 angle. EMG is normalised to the mean EMG RMS of the 100 % trials at that angle, so
//                 the mean normalised EMG at 100 % MVC is 1 by construction. Fits the EMG-to-
//                 activation map (thesis 6.2.3).
//   force_length  full activation over elbow angles in the arm and over path lengths with the muscle
//                 alone (thesis 6.1.3.2).
//   composition   steady force at one activation and path for every slow x fast unit count (7.3).
#pragma once

#include "basics/table.h"
#include "experiments/emg.h"
#include "experiments/fit.h"
#include "model/trial.h"

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace armsim {

class OutputFolder;
struct ProtocolResult;

enum class ProtocolKind { Mvc, Submaximal, ForceLength, Composition };

/// "mvc", "submaximal", "force_length", "composition".
std::string getProtocolKindName(ProtocolKind kind);

/// A protocol, as read from its file. Angles are radians, lengths metres, times seconds.
struct Protocol {
    std::string name;                  ///< short name (default run directory out/<name>)
    std::string description;           ///< free text
    ProtocolKind kind = ProtocolKind::Mvc;
    std::string sourcePath;            ///< the file it was read from
    std::string sourceText;            ///< that file's text (copied into the run directory)

    std::uint64_t seed = 1;            ///< seeds the run order, EMG and sensor noise of every trial
    bool randomOrder = true;           ///< true: run order shuffled with the seed; false: as listed
    int repetitions = 1;               ///< repetitions of every condition
    /// Rest between efforts [s] (thesis: 5 min). Recorded only: no fatigue is modelled, so the rest
    /// costs no simulated time.
    double interTrialRest = 0;

    std::string model = "thesis";      ///< subject: model name or file (model/model_file.h)
    std::string armFile;               ///< subject: arm file replacing the model's ("" = the model's)
    std::string muscleFile;            ///< subject: muscle file replacing the primary's ("" = the model's)
    /// Overrides of the model's subject effort (voluntary activation, co-contraction, trial CV,
    /// fatigue per repetition); unset = the model file's values.
    std::optional<double> voluntaryActivation, coContraction, trialCv, fatigue;

    /// Template of every arm trial (rest with tare, rise, hold, sample rate, averaging window,
    /// integrator accuracy); elbow angle and activation are set per trial.
    IsometricTrialSettings trial;
    std::vector<double> elbowAngles;   ///< [rad] arm trials (mvc, submaximal, force_length)
    std::vector<double> levels;        ///< fractions of MVC in (0, 1], 1 included (submaximal)
    std::vector<double> pathLengths;   ///< [m] muscle-alone trials at U = 1 (force_length)
    /// [m] P_max of the muscle-alone trials (force_length; 0 = the muscle file's). Raising it also moves
    /// the passive element's rest length (Lr1 is relative to Lmax), i.e. changes the muscle.
    double maxPathLength = 0;

    int slowUnitsFrom = 0, slowUnitsTo = 10;   ///< composition: slow unit counts
    int fastUnitsFrom = 0, fastUnitsTo = 10;   ///< composition: fast unit counts
    double compositionActivation = 0.9;        ///< composition: U [1] (thesis 7.3)
    double compositionPath = 0.375;            ///< composition: path length [m] (thesis 7.3)

    double transducerNoiseRms = 0;     ///< [N] white noise on every transducer (strap) sample
    bool emgEnabled = true;            ///< synthesise surface EMG for every arm trial
    SurfaceEmgSettings emg;            ///< EMG settings (acquisition output rate = trial sample rate)
    double emgRmsWindow = 0.25;        ///< [s] window of the moving-RMS column emg_rms_V
};

/// Reads a protocol file strictly: unknown keys, bad YAML, out-of-range values (negative durations,
/// angles outside the subject's elbow range), empty condition lists and bad combinations are
/// InputErrors naming the file, the line and the key. Relative subject files resolve like assets.
Protocol readProtocol(const std::string& path);

/// The subject the protocol names (its arm and muscle files).
ArmSetup loadProtocolSubject(const Protocol& protocol);

/// How to run a protocol.
struct ProtocolRunOptions {
    /// Run directory. It is written as a whole: into a temporary sibling directory renamed into
    /// place at the end, replacing an earlier run (a directory holding manifest.json) or an empty
    /// directory; any other existing path is refused. "" = compute only, write nothing.
    std::string outDir;
    int jobs = 1;                                         ///< worker threads (results do not depend on it)
    std::function<void(int done, int total)> progress;    ///< called from the caller's thread
    /// Extra files written into the run before it is put in place (the trials' videos): they appear
    /// with the run or not at all, and manifest.json lists them. Called only when outDir is set.
    std::function<void(OutputFolder& dir, const ProtocolResult& result)> beforeCommit = {};
};

/// What a run gives (also written to the run directory).
struct ProtocolResult {
    /// One row per trial in canonical order (condition-major, then repetition): trial, run_order,
    /// elbow_angle_deg, level_pct_mvc, repetition, activation, path_length_m, moment_arm_m, rest_force_N,
    /// muscle_force_N (true, window mean), active_force_N (minus rest force), force_measured_N (tared
    /// transducer torque / moment arm), force_fixed_ratio_N (thesis estimate), strap_force_N, saturated,
    /// emg_rms_V, emg_mnf_Hz, emg_mdf_Hz, emg_norm (RMS / mean RMS at 100 % MVC, same angle),
    /// force_norm (active force / mean active force at 100 % MVC, same angle). Arm kinds only.
    Table trials;
    std::vector<std::string> trialIds;  ///< file stem of each trial's time series, canonical order
    /// Per condition (angle, level): n and <column>_mean, <column>_sd (sample sd over repetitions) of
    /// the trial metrics. Arm kinds only.
    Table summary;
    std::map<std::string, QuadraticFit> quadraticFits;  ///< mvc: per force measure; force_length: peak
    std::optional<PolynomialFit> emgToActivation;       ///< submaximal: U = poly(emg_norm), degree 2
    Table muscleSweep;   ///< force_length: path_length_m, muscle_force_N, steady_force_N, passive_force_N
    Table composition;   ///< composition: slow_units, fast_units, force_N
    std::vector<std::string> files;  ///< files written, relative to the run directory, sorted
};

/// Runs the protocol on the subject. Deterministic for a protocol (seed included) and subject,
/// whatever options.jobs. Throws InputError / SimulationError; on any error (including one thrown by
/// options.progress) nothing is left in options.outDir's parent.
ProtocolResult runProtocol(const Protocol& protocol, const ArmSetup& subject, const ProtocolRunOptions& options);

/// The activation at which the steady active force (Fse(U) - Fse(0)) at path P equals targetForce,
/// by bisection to 1e-12; 1 if even U = 1 does not reach it. Throws SimulationError if the steady
/// solve fails.
double calcActivationForActiveForce(const VirtualMuscle& muscle, double pathLength, double targetForce);

}  // namespace armsim
