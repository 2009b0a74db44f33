// Sub-commands of the armsim command. Each add* function registers its CLI11 sub-command; the
// callbacks throw InputError / SimulationError, which main() turns into a message and exit code.
#pragma once

#include "muscles/virtual_muscle.h"

#include <CLI/CLI.hpp>

#include <string>

namespace armsim::cli {

/// Muscle options shared by several commands.
struct MuscleOptions {
    std::string file = "muscles/biceps_long_head.yaml";  ///< muscle file (path or asset name)
    int slowUnits = -1;                                   ///< override Ns (-1: from the file)
    int fastUnits = -1;                                   ///< override Nf (-1: from the file)
    double mass = 0;                                      ///< override M [kg] (0: from the file)
    double tendonLength = 0;                              ///< override L0T [m] (0: from the file)
    double maxPathLength = 0;                             ///< override P_max [m] (0: from the file)
    void add(CLI::App& app);
    /// Loads the file and applies the overrides (validated by the VirtualMuscle constructor).
    VirtualMuscle build() const;
};

void addMuscleCommands(CLI::App& app);
void addRunCommand(CLI::App& app);

/// Prints a one-line progress bar to stderr ("label [#####     ] 5/10").
void printProgress(const std::string& label, int done, int total);

}  // namespace armsim::cli
