#include "basics/errors.h"
#include "basics/files.h"
#include "basics/output_folder.h"
#include "cli/commands.h"

#include <malloc.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <unistd.h>
#include <vector>

namespace armsim::cli {

namespace {

struct Command {
    int order;
    std::function<void(CLI::App&)> add;
};
struct Step {
    int order;
    std::string name;
    std::function<void(const MainJobContext&)> run;
};

std::vector<Command>& commands() {
    static std::vector<Command> c;
    return c;
}
std::vector<Step>& steps() {
    static std::vector<Step> s;
    return s;
}

}  // namespace

CommandRegistrar::CommandRegistrar(int order, std::function<void(CLI::App&)> add) {
    commands().push_back({order, std::move(add)});
}

MainJobStepRegistrar::MainJobStepRegistrar(int order, std::string name,
                                           std::function<void(const MainJobContext&)> run) {
    steps().push_back({order, std::move(name), std::move(run)});
}

double parseNumber(const std::string& option, const std::string& text) {
    std::size_t used = 0;
    double v = 0;
    try {
        v = std::stod(text, &used);
    } catch (const std::exception&) {
        used = 0;
    }
    if (used != text.size() || text.empty() || !std::isfinite(v))
        throw InputError(option + " '" + text + "': expected a finite number");
    return v;
}

CLI::Option* addNumberListOption(CLI::App& app, const std::string& name, std::vector<double>& values,
                                 const std::string& description) {
    const CLI::Validator finite(
        [](std::string& item) -> std::string {
            if (item.empty()) return "'': expected a finite number (for no values, leave the option out)";
            try {
                parseNumber("", item);
            } catch (const InputError&) {
                return "'" + item + "': expected a finite number";
            }
            return "";
        },
        "");
    return app.add_option(name, values, description)
        ->delimiter(',')
        ->check(finite)
        ->allow_extra_args(false)
        ->type_name("NUMBERS");
}

CLI::Option* addNameListOption(CLI::App& app, const std::string& name, std::vector<std::string>& values,
                               const std::string& description) {
    return app.add_option(name, values, description)->delimiter(',')->allow_extra_args(false)->type_name("NAMES");
}

void runNamingOptions(const std::map<std::string, std::string>& optionOfField, const std::function<void()>& f) {
    try {
        f();
    } catch (const FieldError& e) {
        const auto it = optionOfField.find(e.getField());
        if (it == optionOfField.end()) throw;
        throw InputError(it->second + " " + e.getDetail());
    }
}

void checkOutputFolder(const std::string& option, const std::string& dir) {
    namespace fs = std::filesystem;
    if (dir.empty()) throw InputError(option + " is empty: expected a folder path");
    std::error_code ec;
    fs::path p = fs::absolute(dir, ec).lexically_normal();
    if (p.filename().empty() && p.has_parent_path()) p = p.parent_path();  // "out/" and "." name "out", the cwd
    const fs::path given = p;
    // A new folder is staged in a sibling ".NAME.partial.<pid>-<n>": its name needs room for the suffix
    // (an existing folder stages inside itself).
    constexpr std::size_t kNameMax = 255, kStagingExtra = OutputFolder::kStagingNameExtra;
    for (const fs::path& part : given)
        if (part.string().size() > kNameMax)
            throw InputError(option + " '" + dir + "': a folder name of " + std::to_string(part.string().size()) +
                             " characters: expected at most " + std::to_string(kNameMax));
    if (!fs::is_directory(given, ec) && given.filename().string().size() > kNameMax - kStagingExtra)
        throw InputError(option + " '" + dir + "': a folder name of " + std::to_string(given.filename().string().size()) +
                         " characters: expected at most " + std::to_string(kNameMax - kStagingExtra) +
                         " (the output is staged in a hidden sibling with a longer name)");
    while (!fs::exists(p, ec) && p.has_parent_path() && p != p.parent_path()) p = p.parent_path();
    if (!fs::is_directory(p, ec))
        throw InputError(option + " '" + dir + "': cannot create the folder (" + p.string() + " is not a folder)");
    if (::access(p.c_str(), W_OK | X_OK) != 0)
        throw InputError(option + " '" + dir + "': cannot write in " + p.string() + " (" + (p == given ? "the folder" : "its parent") +
                         " is not writable)");
}

namespace {
std::atomic<bool> gQuiet{false};
}

void setQuiet(bool quiet) { gQuiet = quiet; }
bool isQuiet() { return gQuiet; }

void printProgress(const std::string& label, int done, int total) {
    if (isQuiet()) return;
    std::fflush(stdout);  // keep results and progress in order when both go to one log
    if (!isatty(fileno(stderr))) {  // a log file gets one line, not a stream of carriage returns
        if (done >= total) std::fprintf(stderr, "%s: %d/%d done\n", label.c_str(), done, total);
        return;
    }
    constexpr int kWidth = 30;
    const int filled = total > 0 ? done * kWidth / total : kWidth;
    std::fprintf(stderr, "\r%-28s [%s%s] %d/%d", label.c_str(), std::string(filled, '#').c_str(),
                 std::string(kWidth - filled, ' ').c_str(), done, total);
    if (done >= total) std::fprintf(stderr, "\n");
    std::fflush(stderr);
}

void addRegisteredCommands(CLI::App& app) {
    auto& c = commands();
    std::stable_sort(c.begin(), c.end(), [](const Command& a, const Command& b) { return a.order < b.order; });
    for (const auto& cmd : c) cmd.add(app);

    // armsim run: every registered main-job step, in order.
    auto ctx = std::make_shared<MainJobContext>();
    CLI::App* run = app.add_subcommand("run", "the main job on built-in defaults (results and plots in --out)");
    run->add_option("--out", ctx->outDir, "output directory")->capture_default_str();
    run->add_option("--jobs", ctx->jobs, "worker threads")->capture_default_str()->check(CLI::Range(1, 64));
    ctx->muscle.add(*run);
    run->callback([ctx] {
        // glibc raises its mmap threshold (to 32 MB) each time a large block is freed, after which
        // large temporaries (trial tables, frames) come from the heap, which then stays resident.
        // Fixed thresholds give them back: the job's peak is ~180 MiB with them, ~190 without
        // (docs/benchmarks.md, issue 30).
        ::mallopt(M_MMAP_THRESHOLD, 1 << 20);
        ::mallopt(M_TRIM_THRESHOLD, 1 << 20);
        auto& s = steps();
        std::stable_sort(s.begin(), s.end(), [](const Step& a, const Step& b) { return a.order < b.order; });
        // Every step writes into a staging folder; the results join --out together at the end, or (an
        // error, an interruption) none of them does and the staging folder is removed.
        checkOutputFolder("--out", ctx->outDir);
        ctx->muscle.loadSetup();   // the model and its options checked before any step prints or writes
        OutputFolder folder(ctx->outDir, OutputFolder::Mode::AddFiles, "manifest.json");  // protocol runs whole
        MainJobContext staged = *ctx;
        staged.outDir = folder.getStagingPath();
        const ShownFolder shown(staged.outDir, ctx->outDir);  // messages name where the files will be
        try {
            for (const auto& step : s) {
                std::printf("\n== %s ==\n", step.name.c_str());
                std::fflush(stdout);
                step.run(staged);
            }
        } catch (const InputError& e) {  // files named where they would have been
            throw InputError(folder.showPaths(e.what()));
        } catch (const SimulationError& e) {
            throw SimulationError(folder.showPaths(e.what()));
        } catch (const std::filesystem::filesystem_error& e) {
            throw InputError(folder.showPaths(e.what()));
        }
        folder.addStagedFiles();
        folder.commit();
        std::printf("\nAll results are in %s/\n", ctx->outDir.c_str());
    });
}

}  // namespace armsim::cli
