// Sub-commands of the armsim command. Each cli/*_command.cpp registers its sub-command and, if it
// contributes to the main job (`armsim run`), a main-job step, with the registrars below; main()
// needs no edit when a command is added. Callbacks throw InputError / SimulationError, which main()
// turns into a message and an exit code.
#pragma once

#include "muscles/virtual_muscle.h"

#include <CLI/CLI.hpp>

#include <functional>
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
    /// Loads the file and applies the overrides, validated.
    MuscleParameters loadParameters() const;
    /// loadParameters() built into a VirtualMuscle.
    VirtualMuscle build() const;
};

/// Adds a sub-command to the armsim app. Registered at static-initialisation time.
struct CommandRegistrar {
    CommandRegistrar(int order, std::function<void(CLI::App&)> add);
};

/// Settings every main-job step receives.
struct MainJobContext {
    std::string outDir = "out";  ///< where results go
    int jobs = 2;                ///< worker threads
    MuscleOptions muscle;        ///< the subject's biceps
};

/// A step of `armsim run`; steps run in ascending order.
struct MainJobStepRegistrar {
    MainJobStepRegistrar(int order, std::string name, std::function<void(const MainJobContext&)> run);
};

/// Adds every registered command to app (called by main).
void addRegisteredCommands(CLI::App& app);

/// Prints a one-line progress bar to stderr ("label [#####     ] 5/10").
void printProgress(const std::string& label, int done, int total);

}  // namespace armsim::cli
