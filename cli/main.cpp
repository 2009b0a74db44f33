// armsim: musculoskeletal arm simulation with a Virtual Muscle biceps.
// Exit codes: 0 done, 2 bad input (options, files; the message names the option or file, the value and
// what was expected), 3 a simulation that cannot go on, 4 an internal error.
#include "cli/commands.h"
#include "muscles/param_file.h"

#include <filesystem>
#include <iostream>

namespace {

/// "unknown command 'x': expected one of ..." when the first argument that is not an option names no
/// subcommand (CLI11 would say only that a subcommand is required).
std::string findUnknownCommand(const CLI::App& app, int argc, char** argv) {
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a.empty() || a[0] == '-') continue;
        std::string names;
        for (const CLI::App* s : app.get_subcommands({})) {
            if (s->get_name() == a) return "";
            names += (names.empty() ? "" : ", ") + s->get_name();
        }
        return "unknown command '" + a + "': expected one of " + names;
    }
    return "";
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"armsim: a Simbody elbow with a Virtual Muscle biceps (simulate, identify, render)"};
    app.require_subcommand(1);
    app.set_version_flag("--version", std::string("armsim ") + ARMSIM_VERSION);
    armsim::cli::addRegisteredCommands(app);
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        const std::string unknown = findUnknownCommand(app, argc, argv);
        std::cerr << "armsim: error: " << (unknown.empty() ? std::string(e.what()) : unknown)
                  << " (armsim --help lists the commands and options)\n";
        return 2;
    } catch (const armsim::InputError& e) {
        std::cerr << "armsim: error: " << e.what() << "\n";
        return 2;
    } catch (const std::filesystem::filesystem_error& e) {
        std::cerr << "armsim: error: cannot use '" << e.path1().string() << "': " << e.code().message() << "\n";
        return 2;
    } catch (const armsim::SimulationError& e) {
        std::cerr << "armsim: simulation failed: " << e.what() << "\n";
        return 3;
    } catch (const std::exception& e) {
        std::cerr << "armsim: internal error: " << e.what() << "\n";
        return 4;
    }
    return 0;
}
