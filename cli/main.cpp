// armsim: musculoskeletal arm simulation with a Virtual Muscle biceps.
// Exit codes: 0 done, 2 bad input (options, files; the message names the option or file, the value and
// what was expected; also an output that cannot be written, standard output included), 3 a simulation
// that cannot go on, 4 an internal error, 128 + signal when stopped by SIGINT, SIGTERM or SIGHUP (after
// removing the partial output of the run in progress).
#include "basics/errors.h"
#include "basics/files.h"
#include "estimation/ceres_logging.h"
#include "cli/commands.h"
#include "cli/report.h"
#include "cli/plugins.h"

#include <pthread.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <thread>

namespace {

/// SIGINT, SIGTERM and SIGHUP (a closed terminal) are taken by a thread of their own (they are blocked in every other thread): the
/// first asks the run to stop at its next task boundary (checkInterruption), whose writers then remove
/// their partial output; a second signal, or a run that has not stopped after 10 s, ends the process
/// at once (a protocol run's leftover temporary folder is removed by the next run).
void startSignalThread() {
    sigset_t set;
    sigemptyset(&set);
    for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
        struct sigaction old {};
        sigaction(sig, nullptr, &old);
        if (old.sa_handler != SIG_IGN) sigaddset(&set, sig);  // ignored (a script's background job): keep it so
    }
    pthread_sigmask(SIG_BLOCK, &set, nullptr);
    std::thread([set] {
        int sig = 0;
        if (sigwait(&set, &sig) != 0) return;
        armsim::requestInterruption(sig);
        armsim::cli::forwardInterruption(sig);
        std::fprintf(stderr, "\narmsim: interrupted: stopping at the next step (again to stop at once)\n");
        timespec wait{10, 0};
        siginfo_t info;
        const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
        while (sigtimedwait(&set, &info, &wait) < 0 && errno == EINTR) {
            const auto left = std::chrono::duration<double>(end - std::chrono::steady_clock::now()).count();
            if (left <= 0) break;
            wait = timespec{time_t(left), long((left - double(time_t(left))) * 1e9)};
        }
        std::signal(sig, SIG_DFL);
        pthread_sigmask(SIG_UNBLOCK, &set, nullptr);
        std::raise(sig);
    }).detach();
}

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

// CLI11's "Could not convert: --rate = abc" with what the option expected: "--rate = 'abc': expected a
// number"; the message as CLI11 gave it when the option is not found.
std::string explainConversion(const CLI::App& app, const std::string& what) {
    const std::string prefix = "Could not convert: ";
    const std::size_t eq = what.find(" = ");
    if (what.rfind(prefix, 0) != 0 || eq == std::string::npos) return what;
    const std::string name = what.substr(prefix.size(), eq - prefix.size()), value = what.substr(eq + 3);
    // The command line's own chain of commands (the parsed ones), innermost last.
    std::vector<const CLI::App*> apps{&app};
    for (std::size_t k = 0; k < apps.size(); ++k)
        for (const CLI::App* sub : apps[k]->get_subcommands()) apps.push_back(sub);
    std::reverse(apps.begin(), apps.end());
    for (const CLI::App* a : apps)
        for (const CLI::Option* o : a->get_options()) {
            if (o->get_name() != name && !o->check_name(name)) continue;
            // "INT", or "INT:NUMBER in [1, 64]" with a range check (cli/commands.h: inRange); "UINT"
            // options are the seeds, 32-bit unsigned.
            const std::string type = o->get_type_name();
            const std::string base = type.substr(0, type.find(':'));
            const std::size_t in = type.find(" in [");
            const std::string range = in == std::string::npos ? "" : type.substr(in);
            const std::string expected = base == "FLOAT"  ? "a number"
                                         : base == "INT"  ? "an integer"
                                         : base == "UINT" ? "a whole number in [0, 4294967295]"
                                                          : base;
            return name + " = '" + value + "': expected " + expected + range;
        }
    return what;
}

// What went to standard output must have arrived (a full disk, /dev/full, a closed pipe): `status`
// when it did, else 2 with a message.
int finishStdout(int status) {
    errno = 0;
    std::cout.flush();
    const bool flushed = std::fflush(stdout) == 0 && !std::ferror(stdout) && std::cout.good();
    if (flushed) return status;
    const int error = errno ? errno : armsim::cli::getStdoutWriteError();
    std::cerr << "armsim: error: cannot write to standard output" << (error ? std::string(": ") + std::strerror(error) : "")
              << " (the results printed there are incomplete)\n";
    return status == 0 ? 2 : status;
}

// The command typed, with its subcommand ("model show"), for messages; "COMMAND" before one is known.
std::string getCommandPath(const CLI::App& app) {
    std::string path;
    for (const CLI::App* a = &app; !a->get_subcommands().empty();) {
        a = a->get_subcommands().front();
        path += (path.empty() ? "" : " ") + a->get_name();
    }
    return path.empty() ? "COMMAND" : path;
}

// "armsim muscle needs a command: expected one of steady, sweep, trial" for CLI11's "A subcommand is
// required" (which names neither the command nor its choices).
std::string explainMissingSubcommand(const CLI::App& app, const std::string& what) {
    if (what.find("subcommand is required") == std::string::npos) return what;
    const CLI::App* innermost = &app;
    while (!innermost->get_subcommands().empty()) innermost = innermost->get_subcommands().front();
    std::string names;
    for (const CLI::App* s : innermost->get_subcommands({})) names += (names.empty() ? "" : ", ") + s->get_name();
    if (names.empty()) return what;
    const std::string path = getCommandPath(app);
    return (path == "COMMAND" ? std::string("armsim") : "armsim " + path) + " needs a command: expected one of " + names;
}

// What stopped the run, for its last message.
std::string describeStop(int sig) {
    if (sig == SIGPIPE) return "standard output was closed (the reader of its pipe ended)";
    return "interrupted by signal " + std::to_string(sig);
}

}  // namespace

int main(int argc, char** argv) {
    armsim::cli::startStdoutCapture();   // the report shows what the command printed
    armsim::setInputProtection(true);     // no output replaces or deletes a file the command read
    std::signal(SIGPIPE, SIG_IGN);        // a closed pipe is an EPIPE on write: the run stops (cli/report.cpp)
    startSignalThread();
    armsim::quietCeresLogging();  // once, before any thread: armsim reports what Ceres would log
    CLI::App app{"armsim: a Simbody elbow with a Virtual Muscle biceps (simulate, identify, render)"};
    app.require_subcommand(1);
    app.set_version_flag("--version", std::string("armsim ") + ARMSIM_VERSION);
    app.add_flag_function(
        "--quiet,-q", [](std::int64_t) { armsim::cli::setQuiet(true); },
        "no progress lines on stderr (results and errors as always); before or after the command");
    app.fallthrough();  // a command's unknown option may be one of these (armsim study s.yaml --quiet)
    armsim::cli::addRegisteredCommands(app);
    try {
        armsim::cli::checkEnvironment();
        app.parse(argc, argv);
        // A stop that arrives once the command has returned finds its output committed, whole: the
        // overview page (a bounded, quick write) still joins it, and the message says the files are there.
        if (const char* raise = std::getenv("ARMSIM_TEST_STOP_AFTER_COMMAND"))   // tests reach this window
            armsim::requestInterruption(std::atoi(raise));
        const int stoppedAfter = armsim::getInterruption();
        try {   // FOLDER/index.html of a command that wrote a folder; the command's own files stand either way
            armsim::cli::writeCommandReport(app, argc, argv);
        } catch (const std::exception& e) {
            // Not a silent success: a script sees the exit status; the message says what is there.
            std::cerr << "armsim: error: index.html (the folder's overview) not written: " << e.what()
                      << " (the command's other files are complete)\n";
            return stoppedAfter ? 128 + stoppedAfter : 2;
        }
        if (stoppedAfter) {
            std::cerr << "armsim: " << describeStop(stoppedAfter) << " after the command had finished: its output is complete\n";
            finishStdout(0);
            return 128 + stoppedAfter;
        }
    } catch (const CLI::CallForHelp& e) {
        return finishStdout(app.exit(e));
    } catch (const CLI::CallForAllHelp& e) {
        return finishStdout(app.exit(e));
    } catch (const CLI::CallForVersion& e) {
        return finishStdout(app.exit(e));
    } catch (const CLI::ConversionError& e) {
        std::cerr << "armsim: error: " << explainConversion(app, e.what()) << " (armsim " << getCommandPath(app) << " --help lists its options)\n";
        return 2;
    } catch (const CLI::ValidationError& e) {
        // CLI11's "--rate: = 0: expected ..." (inRange's message after the option's name) as "--rate = 0: ...".
        std::string what = e.what();
        if (const std::size_t at = what.find(": = "); at != std::string::npos && what.rfind("--", 0) == 0)
            what.replace(at, 4, " = ");
        std::cerr << "armsim: error: " << what << " (armsim " << getCommandPath(app) << " --help lists its options)\n";
        return 2;
    } catch (const CLI::ParseError& e) {
        const std::string unknown = findUnknownCommand(app, argc, argv);
        std::string what = unknown.empty() ? explainMissingSubcommand(app, e.what()) : unknown;
        if (const std::size_t at = what.find(": At Most 1 required but received "); at != std::string::npos) {
            const std::string option = what.substr(0, at);
            std::string values;   // as typed, in order
            for (int i = 1; i < argc; ++i) {
                const std::string a = argv[i];
                if (a == option && i + 1 < argc) values += (values.empty() ? "" : ", ") + std::string(argv[i + 1]);
                else if (a.rfind(option + "=", 0) == 0) values += (values.empty() ? "" : ", ") + a.substr(option.size() + 1);
            }
            what = option + " is given " + what.substr(at + 34) + " times" + (values.empty() ? "" : " (" + values + ")") +
                   ": expected it once";
        }
        std::cerr << "armsim: error: " << what
                  << " (armsim --help lists the commands and options)\n";
        return 2;
    } catch (const armsim::InputError& e) {
        std::cerr << "armsim: error: " << e.what() << "\n";
        return 2;
    } catch (const std::filesystem::filesystem_error& e) {
        std::cerr << "armsim: error: cannot use '" << e.path1().string() << "': " << e.code().message() << "\n";
        return 2;
    } catch (const armsim::InterruptedError& e) {
        // Only the study keeps work across a stop (its journal); every other command leaves nothing.
        const bool study = getCommandPath(app) == "study";
        std::cerr << "armsim: " << describeStop(armsim::getInterruption()) << ": stopped ("
                  << (study ? "unfinished output removed; the study resumes from its journal when run again"
                            : "unfinished output removed") << ")\n";
        return 128 + armsim::getInterruption();
    } catch (const armsim::SimulationError& e) {
        std::cerr << "armsim: simulation failed: " << e.what() << "\n";
        return 3;
    } catch (const std::exception& e) {
        std::cerr << "armsim: internal error: " << e.what() << "\n";
        return 4;
    }
    return finishStdout(0);
}
