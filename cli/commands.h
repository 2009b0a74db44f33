// Sub-commands of the armsim command. Each cli/*_command.cpp registers its sub-command and, if it
// contributes to the main job (`armsim run`), a main-job step, with the registrars below; main()
// needs no edit when a command is added. Callbacks throw InputError / SimulationError, which main()
// turns into a message and an exit code.
#pragma once

#include "basics/output_folder.h"
#include "model/model_file.h"
#include "muscles/virtual_muscle.h"

#include <CLI/CLI.hpp>

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace armsim::cli {

/// Model and muscle options shared by every command that simulates. The muscle overrides apply to
/// the model's primary muscle (the thesis's biceps); an option not given leaves the model's value.
/// loadModel(name) with every muscle given muscle model `muscleModel` unless it is empty (the
/// --muscle-model option; errors name the option and value).
ArmSetup loadModelWithMuscles(const std::string& name, const std::string& muscleModel);

struct MuscleOptions {
    std::string model = "thesis";          ///< model name under assets/models/ or a model file
    std::string file;                      ///< muscle file replacing the primary muscle's parameters
    std::string armFile;                   ///< arm file replacing the model's arm
    std::optional<int> slowUnits;          ///< override Ns
    std::optional<int> fastUnits;          ///< override Nf
    std::optional<double> mass;            ///< override M [kg]
    std::optional<double> tendonLength;    ///< override L0T [m]
    std::optional<double> maxPathLength;   ///< override P_max [m]
    std::string muscleModel;               ///< --muscle-model: every muscle's model ("" = the model file's)
    void add(CLI::App& app);
    /// Declares the files these options read (--muscle, --arm, a --model file) as `files`' inputs.
    void declareInputs(OutputFiles& files) const;
    /// Adds --muscle-model (only to commands that honour it).
    void addMuscleModel(CLI::App& app);
    /// The model with the overrides applied, validated (errors name the option and value).
    ArmSetup loadSetup() const;
    /// The primary muscle's parameters from loadSetup().
    MuscleParameters loadParameters() const;
    /// The primary muscle built with its muscle model (Virtual Muscle unless --muscle-model).
    std::shared_ptr<const MuscleModel> build() const;
};

/// Adds a sub-command to the armsim app. Registered at static-initialisation time.
struct CommandRegistrar {
    CommandRegistrar(int order, std::function<void(CLI::App&)> add);
};

/// Settings every main-job step receives.
struct MainJobContext {
    std::string outDir = "out";  ///< where results go (while the job runs: a staging folder; messages showPath)
    int jobs = 2;                ///< worker threads
    MuscleOptions muscle;        ///< the subject's biceps
};

/// A step of `armsim run`; steps run in ascending order. `check` (optional) runs before any step does
/// work: what the step needs that could be missing (an InputError then stops the job before it starts).
struct MainJobStepRegistrar {
    MainJobStepRegistrar(int order, std::string name, std::function<void(const MainJobContext&)> run,
                         std::function<void(const MainJobContext&)> check = {});
};

/// Adds every registered command to app (called by main).
void addRegisteredCommands(CLI::App& app);

/// A finite number given to `option`; InputError naming the option and the text otherwise.
double parseNumber(const std::string& option, const std::string& text);
/// A CLI11 option taking a comma-separated list of finite numbers ("--angles 30,60,90"); an item that is
/// not one is refused with the option and the item named.
CLI::Option* addNumberListOption(CLI::App& app, const std::string& name, std::vector<double>& values,
                                 const std::string& description);
/// A CLI11 option taking a comma-separated list of names ("--methods lm,ilc-sign-search").
CLI::Option* addNameListOption(CLI::App& app, const std::string& name, std::vector<std::string>& values,
                               const std::string& description);

/// findAsset(name) for an option's value: a path, or a name under the assets folder; else InputError
/// naming the option ("--population 'nope': no such file (looked here and in ...)").
std::string findAssetFor(const std::string& option, const std::string& name);

/// A plot's path as typed ends in .png (any case; empty: no plot): else InputError naming the option
/// ("--plot 'p.svg': extension '.svg': expected .png (plots are PNG images)").
const std::string& checkPngPath(const std::string& option, const std::string& path);

/// Checks, before any work and without creating anything, that the output folder given to `option`
/// can be created or written (it, or its nearest existing ancestor, is a writable folder): InputError
/// naming the option, the path and the reason.
void checkOutputFolder(const std::string& option, const std::string& dir);

/// Runs f; a FieldError whose field the user set through an option (`optionOfField`: field -> option) is
/// reported naming that option ("--fps = 0: expected in [1, 240] (1/s)"); other errors pass unchanged.
void runNamingOptions(const std::map<std::string, std::string>& optionOfField, const std::function<void()>& f);

/// A range check for a numeric option, in place of CLI::Range: "'abc': expected a number in [1, 64]" for
/// text that is no number (CLI::Range says "not in range"), the bounds as typed (1e-12, not 0.000000);
/// an integral value is passed on in integer form, so an integer option takes 1e3 and 2.0 too.
CLI::Validator inRange(double lo, double hi);

/// Checks the environment variables armsim reads (ARMSIM_PROGRESS_SECONDS, ARMSIM_QUICK): InputError
/// naming the variable and its value unless valid. Called once, before the command.
void checkEnvironment();
/// Prints a one-line progress bar to stderr ("label [#####     ] 5/10"); nothing with --quiet. When
/// stderr is not a terminal (a log): the end ("label: 10/10 done") and, for long work, a line every 10 s
/// (ARMSIM_PROGRESS_SECONDS) with the share done and the time left at the rate so far.
void printProgress(const std::string& label, int done, int total);
/// A note on stderr when the activation reaches its largest value only after the trial's end (a ramp
/// longer than the trial, a trace in ms): "note: the activation reaches its largest value, 1, at 100 s,
/// after the trial ends at 0.5 s (U = 0.005 there)". Nothing otherwise.
void noteUnreachedActivation(const ActivationProfile& activation, double duration);
/// The same for a simulation at time t [s] of `duration` (a long forward or free run): "12.3/100 s"; on
/// a log only for runs that last (a line every 10 s and the end).
void printTimeProgress(const std::string& label, double t, double duration);
/// --quiet (any command): progress lines are left out; results and errors are printed as always.
void setQuiet(bool quiet);
bool isQuiet();

}  // namespace armsim::cli
