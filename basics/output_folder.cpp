#include "basics/output_folder.h"

#include "basics/errors.h"

#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <fstream>

namespace fs = std::filesystem;

namespace armsim {

OutputFolder::OutputFolder(const std::string& outDir, Mode mode, std::string marker)
    : mode_(mode), marker_(std::move(marker)) {
    if (outDir.empty()) return;
    target_ = fs::path(outDir).lexically_normal();
    if (target_.filename().empty()) target_ = target_.parent_path();
    checkReplaceable();
    const fs::path parent = target_.has_parent_path() ? target_.parent_path() : fs::path(".");
    std::error_code ec;
    fs::create_directories(parent, ec);
    const std::string stem = "." + target_.filename().string();
    removeStaleLeftovers(parent, stem);
    temp_ = parent / (stem + ".partial." + std::to_string(::getpid()));
    old_ = parent / (stem + ".old." + std::to_string(::getpid()));
    fs::remove_all(temp_, ec);
    if (!fs::create_directories(temp_, ec) || ec)
        throw InputError(outDir + ": cannot create the output folder next to it (" + ec.message() + ")");
}

OutputFolder::~OutputFolder() {
    std::error_code ec;
    if (!temp_.empty() && !committed_) fs::remove_all(temp_, ec);
}

std::string OutputFolder::addFile(const std::string& relative) {
    const fs::path path = temp_ / relative;
    std::lock_guard<std::mutex> lock(mutex_);
    files_.insert(relative);
    std::error_code ec;
    if (path.has_parent_path()) fs::create_directories(path.parent_path(), ec);
    return path.string();
}

void OutputFolder::write(const std::string& relative, const std::string& text) {
    const std::string path = addFile(relative);
    std::ofstream out(path, std::ios::binary);
    out << text;
    out.flush();
    if (!out) throw InputError(getTargetPath(relative) + ": write failed (disk full?)");
}

std::vector<std::string> OutputFolder::getFiles() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return {files_.begin(), files_.end()};
}

void OutputFolder::commit() {
    if (temp_.empty() || committed_) return;
    checkReplaceable();
    std::error_code ec;
    const bool exists = fs::exists(target_, ec);
    if (mode_ == Mode::AddFiles && exists) {
        for (const std::string& f : getFiles()) {
            const fs::path to = target_ / f;
            fs::create_directories(to.parent_path(), ec);
            fs::rename(temp_ / f, to, ec);
            if (ec) throw InputError(to.string() + ": cannot move the file into place: " + ec.message());
        }
        committed_ = true;
        fs::remove_all(temp_, ec);
        return;
    }
    if (exists) {
        fs::rename(target_, old_, ec);
        if (ec) throw InputError(target_.string() + ": cannot move the earlier run aside: " + ec.message());
    }
    fs::rename(temp_, target_, ec);
    if (ec) {
        std::error_code ignored;
        if (exists) fs::rename(old_, target_, ignored);
        throw InputError(target_.string() + ": cannot move the output into place: " + ec.message());
    }
    committed_ = true;
    if (exists) fs::remove_all(old_, ec);
}

// What a run killed before its cleanup (SIGKILL, a second Ctrl-C) left beside the target:
// <stem>.partial.<pid> folders of processes that no longer exist are removed; a <stem>.old.<pid> folder
// holds the earlier run, moved aside just before the kill: moved back when the target is missing,
// removed otherwise.
void OutputFolder::removeStaleLeftovers(const fs::path& parent, const std::string& stem) const {
    std::error_code ec;
    std::vector<fs::path> entries;
    for (const fs::directory_entry& e : fs::directory_iterator(parent, ec)) entries.push_back(e.path());
    for (const fs::path& p : entries) {
        const std::string name = p.filename().string();
        for (const std::string kind : {".partial.", ".old."}) {
            const std::string prefix = stem + kind;
            if (name.rfind(prefix, 0) != 0) continue;
            const std::string digits = name.substr(prefix.size());
            if (digits.empty() || digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos)
                continue;
            const pid_t pid = pid_t(std::stol(digits));
            // Ours are stale too: this run has not made its folders yet (pids repeat in containers).
            if (pid != ::getpid() && (::kill(pid, 0) == 0 || errno == EPERM)) continue;  // its process still runs
            if (kind == ".old." && !fs::exists(target_, ec)) fs::rename(p, target_, ec);
            else fs::remove_all(p, ec);
        }
    }
}

void OutputFolder::checkReplaceable() const {
    std::error_code ec;
    if (!fs::exists(target_, ec)) return;
    const bool isFolder = fs::is_directory(target_, ec);
    if (mode_ == Mode::AddFiles) {
        if (isFolder) return;
        throw InputError(target_.string() + ": exists and is not a folder: expected a folder for the output files");
    }
    if (isFolder && (fs::is_empty(target_, ec) || (!marker_.empty() && fs::exists(target_ / marker_, ec)))) return;
    throw InputError(target_.string() + ": exists and is not an armsim run (no " + marker_ +
                     "): refusing to replace it; choose another output folder");
}

}  // namespace armsim
