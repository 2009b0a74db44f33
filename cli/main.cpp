// armsim: musculoskeletal arm simulation with a Virtual Muscle biceps.
#include "cli/commands.h"
#include "muscles/param_file.h"

#include <iostream>

int main(int argc, char** argv) {
    CLI::App app{"armsim: a Simbody elbow with a Virtual Muscle biceps (simulate, identify, render)"};
    app.require_subcommand(1);
    armsim::cli::addRegisteredCommands(app);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e);
    } catch (const armsim::InputError& e) {
        std::cerr << "armsim: error: " << e.what() << "\n";
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
