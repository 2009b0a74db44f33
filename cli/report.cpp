#include "cli/report.h"

#include "basics/errors.h"
#include "basics/html_report.h"

#include <cerrno>
#include <csignal>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <unistd.h>
#include <ctime>
#include <filesystem>
#include <regex>
#include <utility>
#include <vector>

namespace armsim::cli {

namespace {

// (pattern on the file name, sentence): the first match describes the file.
const std::vector<std::pair<std::regex, std::string>>& getCaptions() {
    static const std::vector<std::pair<std::regex, std::string>> captions = [] {
        std::vector<std::pair<std::string, std::string>> t = {
            {"force_length\\.png", "steady isometric force against path length (or angle) at full, half and no activation, with integrated trials as a second method"},
            {"step_activation\\.png", "muscle force after a 0 to 1 activation step"},
            {"mvc_angles\\.png", "isometric MVC at the thesis's five elbow angles: true muscle force, the transducer's reading and the biceps-force estimates"},
            {"mvc_angles_twin\\.png", "the twin's five-angle MVC: tared torque, every muscle's force and the thesis's biceps estimate beside the heads' true force"},
            {"moment_arms\\.png", "every muscle's moment arm against elbow flexion, with the published ranges"},
            {"coordinates\\.png", "an OpenSim model's coordinates against time in the forward run (rotations in degrees)"},
            {"activations\\.png", "every muscle's activation against time in the forward run"},
            {"states\\.sto", "the forward run's states in OpenSim's storage format and column names (coordinates in rad, speeds, muscle states)"},
            {"states\\.csv", "the same states as CSV"},
            {"forearm_moment_arms\\.png", "every muscle's moment arm about the forearm rotation axis (and the elbow) against forearm rotation"},
            {"mvc_flexion\\.png", "steady flexion MVC torque against angle, per muscle and net, with the published points"},
            {"mvc_extension\\.png", "steady extension MVC torque against angle, per muscle and net, with the published points"},
            {"check_moment_arms\\.png", "the model's moment arms with the target file's bands drawn"},
            {"check_mvc\\.png", "the model's MVC torque-angle curves with the measured bands drawn"},
            {"force_angle\\.png", "force against elbow angle over the protocol's trials, with the quadratic fit"},
            {"emg_trial\\.png", "one trial's synthetic surface EMG and its features"},
            {".*_convergence\\.png", "an identification's convergence: cost and parameters per iteration"},
            {"design_criterion\\.png", "the design's criterion after each greedy pick"},
            {"torque_angle\\.png", "measured (synthesized) torque against angle with each method's fitted curve"},
            {"fascicle_length\\.png", "ultrasound fascicle lengths at rest and at the plateau against angle, truth and fits"},
            {"emg\\.png", "normalised EMG amplitudes per muscle and condition, measured and predicted"},
            {"mass_estimates\\.png", "the biceps long head's mass by every method with its 95 % interval, beside the truth"},
            {"mass_identified_vs_true\\.png", "the biceps long head's identified mass against the true one over the virtual subjects, per method (fits that did not converge in grey)"},
            {"mass_error_vs_activation\\.png", "the mass error against the subject's voluntary activation, per method"},
            {"mass_error_vs_synergists\\.png", "the mass error against the synergists' strength relative to the biceps, per method"},
            {"mass_rmse_vs_noise\\.png", "the study's mass RMSE against transducer noise, per protocol and method"},
            {"mass_coverage_vs_noise\\.png", "the study's mass-interval coverage against transducer noise, per protocol and method"},
            {"tendon_rmse_vs_noise\\.png", "the study's tendon-length RMSE against transducer noise, per protocol and method"},
            {"mass_bias_by_truth\\.png", "the study's mass bias, a row per truth population and a column per protocol and method"},
            {"mass_rmse_by_truth\\.png", "the study's mass RMSE, a row per truth population and a column per protocol and method"},
            {"mass_coverage_by_truth\\.png", "the study's mass-interval coverage, a row per truth and a column per protocol and method"},
            {"tendon_rmse_by_truth\\.png", "the study's tendon-length RMSE, a row per truth and a column per protocol and method"},
            {"max_force_rmse_by_truth\\.png", "the study's F0 RMSE, a row per truth and a column per protocol and method"},
            {"torque_fit\\.png", "the torque data with each method's fitted curve"},
            {"composition_heatmap\\.png", "force against the numbers of slow and fast motor units"},
            {"force_emg\\.png", "force against normalised EMG over the submaximal trials"},
            {"force_activation\\.png", "force against activation over the submaximal trials"},
            {"emg_activation\\.png", "normalised EMG against activation, with the fitted EMG-to-activation map"},
            {".*\\.(mp4|avi)", "an offscreen rendering of a recorded trial (muscles on their paths, coloured by activation)"},
            {"still_.*\\.png", "a still of the rendered trial"},
            {"scorecard\\.csv", "every anatomy target: the model's value, the band, pass or fail"},
            {"score_summary\\.csv", "targets passed per kind and muscle"},
            {"muscles\\.csv", "the model's muscle table (SI units)"},
            {"summary\\.csv", "per condition means and sds of the protocol's trials"},
            {"fits\\.csv", "quadratic fits of force against angle"},
            {"trials\\.csv", "every trial's summary"},
            {"elbow_validation_summary\\.csv", "per method and noise level: bias, RMSE, coverage and interval widths with their standard errors"},
            {"elbow_validation\\.csv", "every virtual subject's estimates, intervals and truths"},
            {"estimates\\.csv", "every method's estimate and interval beside the truth"},
            {"torque_estimates\\.csv", "every method's estimate, interval and fit check"},
            {"channel_fits\\.csv", "each channel's chi-square check and worst measurement"},
            {"design_predictions\\.csv", "predicted widths (own model and with what the fit shares) and posterior correlations per protocol"},
            {"design_steps\\.csv", "the greedy picks in order, with the criterion after each"},
            {"torque_data\\.csv", "the tared torque of every trial, as identify-torque reads it"},
            {"channel_data\\.csv", "ultrasound, EMG, volume and anthropometry measurements, as identify-torque reads them"},
            {"results\\.csv", "every cell of the study: subject, protocol, noise, method, estimates and truths"},
            {".*_history\\.csv", "an identification's iterations: cost and parameters"},
            {".*\\.json", "a report (machine-readable)"},
            {".*\\.yaml", "the settings of the run (readable by armsim again)"},
            {".*\\.sto", "the trial in OpenSim's storage format"},
        };
        std::vector<std::pair<std::regex, std::string>> out;
        for (auto& [pattern, sentence] : t) out.emplace_back(std::regex(pattern), sentence);
        return out;
    }();
    return captions;
}

struct Captured {
    std::mutex mutex;
    std::string text;
    bool cut = false;
    int writeError = 0;   // errno of the first failed write
};
// Never destroyed: stdio flushes the stream at exit after the static destructors have run, and a
// command that returns early (an error) leaves its printed lines in the buffer until then.
Captured& getCaptured() {
    static Captured* c = new Captured;
    return *c;
}

// The stdout stream's writer: every byte to file descriptor 1 (a failure is the stream's error, as
// for the real stdout), and a copy into the buffer. As fopencookie(3) asks: the bytes written, 0 on an
// error (never negative), and nothing thrown through the C library.
ssize_t writeTee(void*, const char* data, std::size_t size) noexcept {
    std::size_t done = 0;
    while (done < size) {
        const ssize_t n = ::write(STDOUT_FILENO, data + done, size - done);
        if (n < 0) {
            if (errno == EINTR) continue;
            const int error = errno;
            // The reader of a pipe has ended (`armsim run | head`): SIGPIPE is ignored (main), so the run
            // stops as after SIGTERM, its unfinished output removed, instead of dying with a staging folder.
            if (error == EPIPE && !getInterruption()) requestInterruption(SIGPIPE);
            try {
                Captured& c = getCaptured();
                std::lock_guard<std::mutex> lock(c.mutex);
                if (!c.writeError) c.writeError = error;
            } catch (...) {
            }
            errno = error;
            return 0;
        }
        done += std::size_t(n);
    }
    try {
        Captured& c = getCaptured();
        std::lock_guard<std::mutex> lock(c.mutex);
        const std::size_t room = kMaxCapturedStdout - std::min(kMaxCapturedStdout, c.text.size());
        c.text.append(data, std::min(room, size));
        if (size > room) c.cut = true;
    } catch (...) {   // the copy is for the report only: standard output got every byte
    }
    return ssize_t(size);
}

std::string quote(const std::string& a) {
    if (!a.empty() && a.find_first_of(" \t\"'\\$`*?;&|<>()") == std::string::npos) return a;
    std::string q = "'";
    for (char c : a) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

}  // namespace

void startStdoutCapture() {
    cookie_io_functions_t io{};
    io.write = writeTee;
    FILE* tee = fopencookie(nullptr, "w", io);
    if (!tee) return;   // no capture: the report shows no printed text
    // The real stdout's buffering: by line to a terminal, in blocks otherwise.
    std::setvbuf(tee, nullptr, isatty(STDOUT_FILENO) ? _IOLBF : _IOFBF, BUFSIZ);
    std::fflush(stdout);
    stdout = tee;
}

int getStdoutWriteError() {
    Captured& c = getCaptured();
    std::lock_guard<std::mutex> lock(c.mutex);
    return c.writeError;
}

std::string getCapturedStdout() {
    Captured& c = getCaptured();
    std::lock_guard<std::mutex> lock(c.mutex);
    return c.cut ? c.text + "\n[... cut at " + std::to_string(kMaxCapturedStdout / 1024) + " kB]\n" : c.text;
}

std::string describeOutputFile(const std::string& relativePath) {
    const std::string name = std::filesystem::path(relativePath).filename().string();
    for (const auto& [pattern, sentence] : getCaptions())
        if (std::regex_match(name, pattern)) return sentence;
    return "";
}

namespace {
std::string& reportFolder() {
    static std::string folder;
    return folder;
}
}  // namespace

void setReportFolder(const std::string& dir) { reportFolder() = dir; }

void writeCommandReport(const CLI::App& app, int argc, char** argv) {
    const CLI::App* ran = &app;
    for (;;) {
        const std::vector<const CLI::App*> subs = ran->get_subcommands([](const CLI::App* s) { return s->parsed(); });
        if (subs.empty()) break;
        ran = subs.front();
    }
    if (ran == &app) return;
    // A study's ranks share one folder, which rank 0 writes; every other command writes its own output
    // in each process that runs it, so its page too (a rank variable alone is no MPI run).
    if (ran->get_name() == "study")
        for (const char* rank : {"OMPI_COMM_WORLD_RANK", "PMI_RANK", "SLURM_PROCID"})
            if (const char* v = std::getenv(rank); v && std::string(v) != "0") return;
    const CLI::Option* out = ran->get_option_no_throw("--out");
    if (!out && reportFolder().empty()) return;
    const std::string dir = !reportFolder().empty() ? reportFolder() : out->as<std::string>();
    std::error_code ec;
    if (dir.empty() || !std::filesystem::is_directory(dir, ec)) return;

    FolderReport r;
    std::string name = ran->get_name();
    for (const CLI::App* p = ran->get_parent(); p && p != &app; p = p->get_parent()) name = p->get_name() + " " + name;
    r.title = "armsim " + name;
    std::string line;
    for (int i = 0; i < argc; ++i) line += (i ? " " : "") + quote(argv[i]);
    const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
    char when[32];
    std::strftime(when, sizeof when, "%Y-%m-%d %H:%M:%S UTC", std::gmtime(&now));
    r.facts = {{"command", line}, {"armsim", ARMSIM_VERSION}, {"finished", when},
               {"working directory", std::filesystem::current_path(ec).string()}};
    if (const char* quick = std::getenv("ARMSIM_QUICK"); quick && std::string(quick) == "1")
        r.facts.emplace_back("ARMSIM_QUICK", "1: population sizes capped (a quick try, not a result)");
    for (const CLI::Option* o : ran->get_options()) {
        if (o->get_name().empty() || o->get_name() == "--help" || o->get_name() == "-h") continue;
        std::string v;
        if (o->count() > 0)
            for (const std::string& x : o->results()) v += (v.empty() ? "" : " ") + x;
        else
            v = o->get_default_str();
        if (v.empty() && o->get_type_size() == 0) v = o->count() > 0 ? "yes" : "no";   // flags
        r.facts.emplace_back(o->get_name(), v.empty() ? "-" : v);
    }
    r.describe = describeOutputFile;
    std::fflush(stdout);
    r.printed = getCapturedStdout();
    writeFolderReport(dir, r);
}

}  // namespace armsim::cli
