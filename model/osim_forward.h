// Forward dynamics of an .osim model as OpenSim's Forward tool runs it: the free model driven by the
// excitations of a controls file (each muscle's column as ControlLinear reads it: linear between rows, a
// row repeating a time replacing the earlier one, extrapolated linearly beyond the first and last rows,
// clamped to [0, 1]), from the initial states of a states file (the row at or before the initial time,
// or the first row, the run starting at that row's time, as the tool does) or from the model's defaults
// with every muscle in equilibrium, integrated by CPodes (BDF) and sampled at a fixed rate into a states
// table with OpenSim's column names: each coordinate (rad), then `<coordinate>_u` (rad/s), then each
// muscle's `<muscle>.<state>` (`activation`; `fiber_length` in metres; De Groote:
// `normalized_tendon_force`). Also reads a Forward tool setup file (<ForwardTool>).
#pragma once

#include "basics/numbers.h"

#include "basics/storage_file.h"
#include "model/osim_file.h"
#include "numerics/stiff_ode.h"

#include <functional>
#include <string>
#include <vector>

namespace armsim {

/// A storage file (basics/storage_file.h) with where it came from, for messages.
struct OsimStorage {
    std::string file;
    StorageHeader header;
    Table table;
};
/// readStorage(path) kept with its path.
OsimStorage readOsimStorage(const std::string& path);
/// The .osim file a user named: a path, or a shipped model's name (assets/models/NAME.osim). InputError
/// naming `option` and the text when there is none.
std::string findOsimModelFile(const std::string& nameOrFile, const std::string& option = "--model");
/// true when a --model value names an OpenSim model: a file ending .osim, or a shipped name with an
/// assets/models/NAME.osim and no NAME.yaml.
bool isOsimModel(const std::string& nameOrFile);

/// What to run.
struct OsimForwardSettings {
    double initialTime = kNaN;   ///< [s]; NaN: the controls' first time
    double finalTime = 1.0;           ///< [s]
    double sampleRate = 200;          ///< rows of the states table per second [Hz]
    std::string muscleModel;          ///< "" = each muscle's file type (model/osim_arm.h)
    /// CPodes; accuracy 1e-5 (OpenSim's Forward tool default integrator_error_tolerance).
    IntegrationSettings integration = [] {
        IntegrationSettings i;
        i.accuracy = 1e-5;
        return i;
    }();
    /// Optional: called at every row with the time run so far and the run's length [s] (progress).
    std::function<void(double, double)> progress;
    /// InputError naming the field for a bad value.
    void validate() const;
};

/// A run's states and what it cost.
struct OsimForwardResult {
    Table states;                       ///< time, coordinates, speeds, muscle states (OpenSim's names)
    IntegrationStats stats;
    std::vector<std::string> notes;     ///< e.g. muscles without a control column (excitation 0)
};

/// Runs the model. Controls columns name muscles (`<muscle>` or `/forceset/<muscle>`); a column naming no
/// muscle is an InputError naming it and the file. States columns: coordinates by name or
/// `/jointset/<joint>/<coordinate>/value`, speeds `<coordinate>_u` or `.../speed`, muscle states
/// `<muscle>.<state>` or `/forceset/<muscle>/<state>`; columns it does not know are ignored.
OsimForwardResult runOsimForward(const OsimModel& model, const OsimStorage& controls, const OsimStorage* initialStates,
                                 const OsimForwardSettings& settings);

/// A Forward tool setup file: the model, controls and states files (resolved against the setup's
/// folder), the time span, the integrator tolerance and the results folder.
struct OsimForwardSetup {
    std::string modelFile, controlsFile, statesFile, resultsDirectory;
    double initialTime = 0, finalTime = 1;
    double tolerance = 1e-5;
    double maxStepSize = 1;  ///< maximum_integrator_step_size [s] (OpenSim's default 1)
};
/// Reads <ForwardTool>; OsimError naming the file and line for a missing element, a controls file that
/// is not a storage file (an XML ControlSet: not supported yet), an element that is not the tool's, or
/// force sets, external loads or use_specified_dt given (not supported yet). Output precision, step
/// counts, analyses and the auxiliary-state equilibrium flag cannot change the states and are skipped.
OsimForwardSetup readOsimForwardSetup(const std::string& path);

}  // namespace armsim
