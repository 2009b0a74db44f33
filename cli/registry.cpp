#include "basics/errors.h"
#include "basics/files.h"
#include "basics/format.h"
#include "basics/numbers.h"
#include "basics/output_folder.h"
#include "basics/quick_run.h"
#include "cli/commands.h"
#include "muscles/muscle_file.h"
#include "numerics/stiff_ode.h"

#include <fmt/format.h>
#include <malloc.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <regex>
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
    std::function<void(const MainJobContext&)> check;
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
                                           std::function<void(const MainJobContext&)> run,
                                           std::function<void(const MainJobContext&)> check) {
    steps().push_back({order, std::move(name), std::move(run), std::move(check)});
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

namespace {
// The items of a list option's occurrences (each one comma-separated text; repeated occurrences add
// up: --noise 1 --noise 2). Split here, not by CLI11, whose delimiter drops empty items ("1,,2" would
// read as 1,2). `what`: "a finite number" or "a name".
std::vector<std::string> splitListOption(const std::string& name, const std::vector<std::string>& texts, const char* what) {
    std::vector<std::string> items;
    for (const std::string& text : texts) {
        if (text.empty())
            throw InputError(name + " '': expected " + what + " (for no values, leave the option out)");
        std::size_t begin = 0;
        for (int item = 1;; ++item) {
            const std::size_t comma = text.find(',', begin);
            std::string part = text.substr(begin, comma == std::string::npos ? std::string::npos : comma - begin);
            if (part.empty())
                throw InputError(name + " '" + text + "': item " + std::to_string(item) + " is empty: expected " + what);
            items.push_back(std::move(part));
            if (comma == std::string::npos) break;
            begin = comma + 1;
        }
    }
    return items;
}
}  // namespace

CLI::Validator inRange(double lo, double hi) {
    const std::string range = "[" + formatNumber(lo) + ", " + formatNumber(hi) + "]";
    return CLI::Validator(
        [lo, hi, range](std::string& text) -> std::string {
            char* end = nullptr;
            const double v = std::strtod(text.c_str(), &end);
            if (text.empty() || end == text.c_str() || *end != '\0' || !std::isfinite(v))
                return "= '" + text + "': expected a number in " + range;
            if (v < lo || v > hi) return "= " + text + ": expected a number in " + range;
            if (v == std::floor(v) && std::abs(v) < 9.0e15) text = std::to_string(static_cast<long long>(v));
            return "";
        },
        "NUMBER in " + range);
}

CLI::Option* addNumberListOption(CLI::App& app, const std::string& name, std::vector<double>& values,
                                 const std::string& description) {
    CLI::Option* option = app.add_option_function<std::vector<std::string>>(
        name,
        [&values, name](const std::vector<std::string>& texts) {
            std::vector<double> parsed;
            for (const std::string& item : splitListOption(name, texts, "a finite number")) {
                const double v = parseNumber(name, item);
                if (std::find(parsed.begin(), parsed.end(), v) != parsed.end())
                    throw InputError(name + " = " + formatNumber(v) + " is listed twice: expected each value once");
                parsed.push_back(v);
            }
            values = std::move(parsed);
        },
        description);
    option->default_function([&values] { return formatList(values); });
    return option->allow_extra_args(false)->type_name("NUMBERS");
}

CLI::Option* addNameListOption(CLI::App& app, const std::string& name, std::vector<std::string>& values,
                               const std::string& description) {
    CLI::Option* option = app.add_option_function<std::vector<std::string>>(
        name,
        [&values, name](const std::vector<std::string>& texts) {
            std::vector<std::string> parsed;
            for (std::string item : splitListOption(name, texts, "a name")) {
                // Spaces around a name are not part of it ("--methods 'lm, ilc'").
                item.erase(0, item.find_first_not_of(" \t"));
                item.erase(item.find_last_not_of(" \t") + 1);
                if (item.empty()) throw InputError(name + ": an item of spaces only: expected a name");
                if (std::find(parsed.begin(), parsed.end(), item) != parsed.end())
                    throw InputError(name + " '" + item + "' is listed twice: expected each name once");
                parsed.push_back(std::move(item));
            }
            values = std::move(parsed);
        },
        description);
    option->default_function([&values] { return formatList(values); });
    return option->allow_extra_args(false)->type_name("NAMES");
}

void runNamingOptions(const std::map<std::string, std::string>& optionOfField, const std::function<void()>& f) {
    try {
        f();
    } catch (const SampleCountError& e) {
        // The run's length and rate as the options that set them: --duration, or --rest + --rise + --hold.
        const auto rate = optionOfField.find("sample_rate");
        std::string duration;
        if (const auto d = optionOfField.find("duration"); d != optionOfField.end()) duration = d->second;
        else
            for (const char* part : {"rest", "rise", "hold"})
                if (const auto p = optionOfField.find(part); p != optionOfField.end())
                    duration += (duration.empty() ? "" : " + ") + p->second;
        if (rate == optionOfField.end() || duration.empty()) throw;
        throw InputError(duration + " = " + formatNumber(e.getDuration()) + " s x " + rate->second + " " +
                         formatNumber(e.getSampleRate()) + " Hz " + e.getDetail());
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
    // access() passes root on file systems that refuse new entries all the same (sysfs, procfs): make
    // and remove a folder there, as the output's staging will, before any work.
    std::string probe = (p / ".armsim-probe-XXXXXX").string();
    if (::mkdtemp(probe.data()) == nullptr) {
        const int err = errno;
        throw InputError(option + " '" + dir + "': cannot make a folder in " + p.string() + " (" + std::strerror(err) + ")");
    }
    ::rmdir(probe.c_str());
}

namespace {
std::atomic<bool> gQuiet{false};
}

void setQuiet(bool quiet) { gQuiet = quiet; }
bool isQuiet() { return gQuiet; }

namespace {
// One label's progress (a run prints a handful of labels).
struct LabelProgress {
    std::chrono::steady_clock::time_point start, lastPrinted;
    double startFraction = 0;   // the share done at the label's first report
    bool estimated = false;     // its early estimate of the whole is out
};
struct LogProgress {
    std::mutex mutex;
    std::map<std::string, LabelProgress> labels;
};
LogProgress& logProgress() {
    static LogProgress p;
    return p;
}
}  // namespace

namespace {
// One progress report: `amount` is "5/10" or "12.3/100 s"; fraction in [0, 1].
// A log's progress interval [s]: ARMSIM_PROGRESS_SECONDS (a batch system's cadence; the tests' short one),
// else 10 s.
// ARMSIM_PROGRESS_SECONDS as seconds in [1e-3, 86400]; NaN when it is not (10 s when unset).
double readProgressSeconds() {
    const char* v = std::getenv("ARMSIM_PROGRESS_SECONDS");
    if (!v) return 10.0;
    char* end = nullptr;
    const double x = std::strtod(v, &end);
    return end != v && *end == '\0' && x >= 1e-3 && x <= 86400 ? x : kNaN;
}

double getLogProgressInterval() {
    static const double interval = [] {
        const double x = readProgressSeconds();   // checkEnvironment refused a bad value before the command
        return std::isnan(x) ? 10.0 : x;
    }();
    return interval;
}

// The time left [s] at the rate since a label's first report (done `from` then; the clock starts there).
double calcTimeLeft(double fraction, double from, double elapsed) {
    return fraction > from ? elapsed * (1 - fraction) / (fraction - from) : kNaN;
}

// Long work says early how long it will take: once, kEstimateAfter into it (or the log's interval, if
// shorter), a line with the time left at the rate so far, when that is kLongWork or more (a terminal's bar
// or a log's 10 s cadence alone would leave a user of a week-long run guessing). True if printed.
bool printEarlyEstimate(const std::string& label, double fraction, const std::string& amount, double elapsed,
                        LabelProgress& l) {
    constexpr double kEstimateAfter = 2, kLongWork = 60;   // [s]
    if (l.estimated || fraction <= l.startFraction || elapsed < std::min(kEstimateAfter, getLogProgressInterval()))
        return false;
    l.estimated = true;
    const double left = calcTimeLeft(fraction, l.startFraction, elapsed);
    if (!(left >= kLongWork)) return false;
    std::fprintf(stderr, "%s%s: %s after %s: about %s left at this rate (stop with Ctrl-C)\n",
                 isatty(fileno(stderr)) ? "\r\x1b[K" : "", label.c_str(), amount.c_str(), formatDuration(elapsed).c_str(),
                 formatDuration(left).c_str());
    std::fflush(stderr);
    return true;
}

// quickEndSilent: on a log, no end line for work that ended before its first periodic line.
void printProgressLine(const std::string& label, double fraction, const std::string& amount, bool finished,
                       bool quickEndSilent = false) {
    if (isQuiet()) return;
    std::fflush(stdout);  // keep results and progress in order when both go to one log
    // A log file gets lines, not a stream of carriage returns: the end, and for long work a line at most
    // every kLogInterval with the share done and the time left at the rate so far (so a batch job's log
    // shows it is alive). A terminal's line is redrawn at most every kTerminalInterval.
    const double kLogInterval = getLogProgressInterval();
    constexpr double kTerminalInterval = 0.1;  // [s]
    using Clock = std::chrono::steady_clock;
    const bool tty = isatty(fileno(stderr));
    LogProgress& p = logProgress();
    const std::lock_guard<std::mutex> lock(p.mutex);
    const Clock::time_point now = Clock::now();
    auto [at, inserted] = p.labels.try_emplace(label, LabelProgress{now, now, fraction, false});
    LabelProgress& l = at->second;
    const double sinceLast = std::chrono::duration<double>(now - l.lastPrinted).count();
    const double elapsed = std::chrono::duration<double>(now - l.start).count();
    const double left = calcTimeLeft(fraction, l.startFraction, elapsed);
    if (finished) {
        p.labels.erase(at);
    } else if (printEarlyEstimate(label, fraction, amount, elapsed, l)) {
        l.lastPrinted = now;
        return;
    }
    if (!tty) {
        if (finished) {
            if (!quickEndSilent || elapsed >= kLogInterval) std::fprintf(stderr, "%s: %s done\n", label.c_str(), amount.c_str());
        } else if (!inserted && sinceLast >= kLogInterval) {
            l.lastPrinted = now;
            const std::string leftText = std::isfinite(left) ? "about " + formatDuration(left) + " left" : "time left unknown";
            std::fprintf(stderr, "%s: %s (%.0f %%) after %s, %s\n", label.c_str(), amount.c_str(), 100 * fraction,
                         formatDuration(elapsed).c_str(), leftText.c_str());
        }
        std::fflush(stderr);
        return;
    }
    if (!finished && !inserted && sinceLast < kTerminalInterval) return;
    if (!finished) l.lastPrinted = now;
    constexpr int kWidth = 30;
    const int filled = int(std::clamp(fraction, 0.0, 1.0) * kWidth);
    const std::string leftText = !finished && std::isfinite(left) && elapsed >= 1 ? ", ~" + formatDuration(left) + " left" : "";
    std::fprintf(stderr, "\r%-28s [%s%s] %s%s\x1b[K", label.c_str(), std::string(filled, '#').c_str(),
                 std::string(kWidth - filled, ' ').c_str(), amount.c_str(), leftText.c_str());
    if (finished) std::fprintf(stderr, "\n");
    std::fflush(stderr);
}
}  // namespace

std::string findAssetFor(const std::string& option, const std::string& name) {
    try {
        return findAsset(name);
    } catch (const InputError& e) {
        std::string what = e.what();
        if (what.rfind(name + ": ", 0) == 0) what.erase(0, name.size() + 2);   // the name is said once
        throw InputError(option + " '" + name + "': " + what);
    }
}

const std::string& checkPngPath(const std::string& option, const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& ch : ext) ch = char(std::tolower(static_cast<unsigned char>(ch)));
    if (!path.empty() && ext != ".png")
        throw InputError(option + " '" + path + "': " + (ext.empty() ? "no extension" : "extension '" + ext + "'") +
                         ": expected .png (plots are PNG images)");
    return path;
}

void noteUnreachedActivation(const ActivationProfile& activation, double duration) {
    const std::vector<double>& t = activation.getBreakpoints();
    const std::vector<double>& U = activation.getValues();
    const double peak = activation.getMaxValue();
    const std::size_t k = std::size_t(std::find(U.begin(), U.end(), peak) - U.begin());
    if (peak > 0 && k < t.size() && t[k] > duration)
        std::fprintf(stderr, "note: the activation reaches its largest value, %s, at %s s, after the trial ends at %s s "
                     "(U = %s there)\n", formatNumber(peak).c_str(), formatNumber(t[k]).c_str(), formatNumber(duration).c_str(),
                     formatNumber(activation.getValue(duration), 4).c_str());
}

void checkEnvironment() {
    if (std::isnan(readProgressSeconds()))
        throw InputError(std::string("environment variable ARMSIM_PROGRESS_SECONDS=") + std::getenv("ARMSIM_PROGRESS_SECONDS") +
                         ": expected seconds between progress lines on a log, in [0.001, 86400] (unset: 10)");
    isQuickRun();   // ARMSIM_QUICK: 1 or 0
}

void printProgress(const std::string& label, int done, int total) {
    printProgressLine(label, total > 0 ? double(done) / total : 1.0, std::to_string(done) + "/" + std::to_string(total),
                      done >= total);
}

void printTimeProgress(const std::string& label, double t, double duration) {
    // Called at every sample (up to 1e7): most calls return here, before any formatting or locking.
    using Clock = std::chrono::steady_clock;
    static std::atomic<Clock::rep> last{0};
    const bool finished = t >= duration * (1 - 1e-12);
    const Clock::rep now = Clock::now().time_since_epoch().count();
    const double throttle = std::min(0.05, getLogProgressInterval() / 10);   // [s], well below the log's interval
    if (!finished && now - last.load() < std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(throttle)).count())
        return;
    last = now;
    printProgressLine(label, duration > 0 ? t / duration : 1.0, fmt::format("{:.1f}/{} s", t, formatNumber(duration)),
                      t >= duration * (1 - 1e-12), true);
}

namespace {
// An option given '' is refused by name: CLI11 reads a number's '' as 0 ("--fps = 0" blamed a value
// never typed), and a text option's '' read as not given (`--plot ''` made no plot, silently).
void refuseEmptyValues(CLI::App& app) {
    for (CLI::Option* option : app.get_options()) {
        const std::string type = option->get_type_name();
        const bool integer = type.rfind("INT", 0) == 0 || type.rfind("UINT", 0) == 0;
        const bool number = integer || type.rfind("FLOAT", 0) == 0 || type.rfind("NUMBER", 0) == 0;
        // CLI11 reads 0x5A as 90 and an integer's 010 as octal 8, while every file reader refuses them:
        // a number is decimal wherever it is typed.
        if (number)
            option->check(CLI::Validator(
                [integer](std::string& text) {
                    static const std::regex prefixed(R"(\s*[+-]?0[xXoObB].*)"), octal(R"(\s*[+-]?0[0-9]+\s*)");
                    if (std::regex_match(text, prefixed))
                        return "= '" + text + "': expected a decimal number (hexadecimal, octal and binary literals are not read)";
                    if (integer && std::regex_match(text, octal))
                        return "= '" + text + "': expected a decimal integer without leading zeros (it would read as octal)";
                    return std::string();
                },
                "", "decimal number"));
        if (option->get_items_expected_max() != 1) continue;   // lists say which item is empty
        if (number)
            option->check(CLI::Validator(
                [](std::string& text) {
                    if (text.empty()) return std::string("is empty: expected a number");
                    errno = 0;
                    char* end = nullptr;
                    const double x = std::strtod(text.c_str(), &end);
                    if (end != text.c_str() && errno == ERANGE && std::abs(x) > 1)   // 1e309: read as inf otherwise
                        return "'" + text + "' is beyond the largest number (1.8e+308): expected a finite number";
                    return std::string();
                },
                "", "non-empty number"));
        else if (type.rfind("TEXT", 0) == 0 && option->get_expected_min() > 0) {   // '' would read as "not given"
            const std::string expected = option->nonpositional() ? "a value (leave the option out for its default)"
                                                                 : "a file name";
            option->check(CLI::Validator(
                [expected](std::string& text) { return text.empty() ? "is empty: expected " + expected : std::string(); },
                "", "non-empty text"));
        }
    }
    for (CLI::App* sub : app.get_subcommands({})) refuseEmptyValues(*sub);
}
}  // namespace

void addRegisteredCommands(CLI::App& app) {
    auto& c = commands();
    std::stable_sort(c.begin(), c.end(), [](const Command& a, const Command& b) { return a.order < b.order; });
    for (const auto& cmd : c) cmd.add(app);

    // armsim run: every registered main-job step, in order.
    auto ctx = std::make_shared<MainJobContext>();
    CLI::App* run = app.add_subcommand("run", "the main job on built-in defaults (results and plots in --out)");
    run->add_option("--out", ctx->outDir, "output directory")->capture_default_str();
    run->add_option("--jobs", ctx->jobs, "worker threads")->capture_default_str()->transform(inRange(1, 64));
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
        for (const auto& step : s)
            if (step.check) step.check(*ctx);   // what a step needs (the renderer's plugin), before any work
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
    refuseEmptyValues(app);
}

}  // namespace armsim::cli
