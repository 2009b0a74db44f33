#include "basics/output_folder.h"

#include "basics/errors.h"
#include "basics/files.h"
#include "basics/write_target.h"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <stdexcept>

namespace fs = std::filesystem;

namespace armsim {

namespace {

std::atomic<int> folderCounter{0};
std::mutex liveMutex;
std::set<std::string> liveStaging;  // staging folders of this process's OutputFolders still alive

bool isLive(const fs::path& p) {
    std::lock_guard<std::mutex> lock(liveMutex);
    return liveStaging.count(p.lexically_normal().string()) > 0;
}

std::string replaceAll(std::string text, const std::string& from, const std::string& to) {
    for (std::size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size()))
        text.replace(at, from.size(), to);
    return text;
}

// One output put in place: `from` renamed to `to`; what is at `to` first moved to `aside`. `name` is how
// messages call it.
struct Placement {
    fs::path from, to, aside;
    std::string name;
};

// Every placement or none: a rename failing part-way puts back everything moved so far and throws
// InputError naming the place. The moved-aside files stay for the caller to remove.
void placeAllOrNone(const std::vector<Placement>& placements) {
    std::error_code ec;
    std::vector<std::pair<fs::path, fs::path>> moved, aside;  // (from, to)
    auto fail = [&](const std::string& message) {
        std::error_code ignored;
        for (auto it = moved.rbegin(); it != moved.rend(); ++it) fs::rename(it->second, it->first, ignored);
        for (auto it = aside.rbegin(); it != aside.rend(); ++it) fs::rename(it->second, it->first, ignored);
        throw InputError(message);
    };
    for (const Placement& p : placements) {
        if (p.from.empty()) {   // a file of an earlier result the new one does not hold: moved aside only
            if (!fs::exists(p.to, ec)) continue;
            if (p.aside.has_parent_path()) fs::create_directories(p.aside.parent_path(), ec);
            fs::rename(p.to, p.aside, ec);
            if (ec) fail(p.name + ": cannot remove the earlier result's file: " + ec.message());
            aside.push_back({p.to, p.aside});
            continue;
        }
        if (p.to.has_parent_path()) fs::create_directories(p.to.parent_path(), ec);
        if (fs::exists(p.to, ec)) {
            if (p.aside.has_parent_path()) fs::create_directories(p.aside.parent_path(), ec);
            fs::rename(p.to, p.aside, ec);
            if (ec) fail(p.name + ": cannot move the earlier file aside: " + ec.message());
            aside.push_back({p.to, p.aside});
        }
        fs::rename(p.from, p.to, ec);
        if (ec) fail(p.name + ": cannot move the file into place: " + ec.message());
        moved.push_back({p.from, p.to});
    }
}

// A folder holding `marker` as armsim writes it: a manifest whose text names armsim's version (a
// stranger's manifest.json does not make a folder an armsim run).
bool holdsMarker(const fs::path& dir, const std::string& marker) {
    std::error_code ec;
    if (marker.empty() || !fs::is_regular_file(dir / marker, ec)) return false;
    std::ifstream in(dir / marker);
    std::string head(4096, '\0');
    in.read(head.data(), std::streamsize(head.size()));
    head.resize(std::size_t(in.gcount()));
    return head.find("\"armsim_version\"") != std::string::npos;
}

// The inputs of this command inside `target` (a folder about to be replaced whole by `staged`): each
// must come back byte for byte in the staged folder, or the replacement would lose it.
void checkInputsKept(const fs::path& target, const fs::path& staged) {
    std::error_code ec;
    const fs::path base = fs::weakly_canonical(target, ec);
    for (const std::string& input : findInputsInside(target.string())) {
        const fs::path twin = staged / fs::path(input).lexically_relative(base);
        checkNotReplacingInput(input, fs::is_regular_file(twin, ec) ? twin.string() : std::string(), target.string());
    }
}

}  // namespace

OutputFolder::OutputFolder(const std::string& outDir, Mode mode, std::string marker)
    : mode_(mode), marker_(std::move(marker)) {
    if (outDir.empty()) return;
    target_ = fs::path(outDir).lexically_normal();
    if (target_.filename().empty()) target_ = target_.parent_path();
    if (std::error_code e; fs::is_symlink(target_, e) && fs::is_directory(target_, e))
        target_ = fs::canonical(target_, e);   // a link to a folder is written through, not replaced
    checkReplaceable();
    std::error_code ec;
    // AddFiles into an existing folder stages inside it (same file system, no write access to its parent
    // needed); a new folder or a whole run is staged beside the target and renamed into place.
    const bool inside = mode_ == Mode::AddFiles && fs::is_directory(target_, ec);
    const fs::path parent = inside ? target_ : target_.has_parent_path() ? target_.parent_path() : fs::path(".");
    // Folders made here for the staging folder are removed again if the output never appears.
    for (fs::path p = parent; !p.empty() && !fs::exists(p, ec); p = p.parent_path()) {
        madeParents_.push_back(p);
        if (p == p.parent_path()) break;
    }
    fs::create_directories(parent, ec);
    const std::string stem = inside ? ".armsim" : "." + target_.filename().string();
    removeStaleLeftovers(parent, stem);
    const std::string id = std::to_string(::getpid()) + "-" + std::to_string(folderCounter++);
    temp_ = (parent / (stem + ".partial." + id)).lexically_normal();
    old_ = (parent / (stem + ".old." + id)).lexically_normal();
    fs::remove_all(temp_, ec);
    if (!fs::create_directories(temp_, ec) || ec)
        throw InputError(outDir + ": cannot create the output folder's staging folder " + temp_.string() + " (" +
                         ec.message() + ")");
    std::lock_guard<std::mutex> lock(liveMutex);
    liveStaging.insert(temp_.string());
}

OutputFolder::~OutputFolder() {
    if (temp_.empty()) return;
    std::error_code ec;
    if (!committed_) {
        fs::remove_all(temp_, ec);
        for (const fs::path& p : madeParents_) fs::remove(p, ec);   // innermost first; only while empty
    }
    std::lock_guard<std::mutex> lock(liveMutex);
    liveStaging.erase(temp_.string());
}

std::string OutputFolder::addFile(const std::string& relative) {
    if (temp_.empty()) throw std::logic_error("OutputFolder::addFile('" + relative + "') on a disabled folder");
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

void OutputFolder::writeWith(const std::string& relative,
                             const std::function<void(const std::string& path)>& writer) {
    const std::string path = addFile(relative);
    try {
        writer(path);
    } catch (const InputError& e) {  // the staging folder, or anything in it, named as the target
        throw InputError(showPaths(e.what()));
    }
}

std::vector<std::string> OutputFolder::getFiles() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return {files_.begin(), files_.end()};
}

std::string OutputFolder::showPaths(std::string message) const {
    return temp_.empty() ? message : replaceAll(std::move(message), temp_.string(), target_.string());
}

std::string OutputFolder::getStagingPath() const {
    if (temp_.empty()) throw std::logic_error("OutputFolder::getStagingPath on a disabled folder");
    return temp_.string();
}

void OutputFolder::addStagedFiles() {
    if (temp_.empty()) throw std::logic_error("OutputFolder::addStagedFiles on a disabled folder");
    std::error_code ec;
    std::vector<std::string> found;
    for (auto it = fs::recursive_directory_iterator(temp_, ec); !ec && it != fs::recursive_directory_iterator();
         it.increment(ec))
        if (it->is_regular_file(ec)) found.push_back(fs::relative(it->path(), temp_, ec).string());
    if (ec) throw InputError(target_.string() + ": cannot list the results staged in " + temp_.string() + ": " + ec.message());
    std::lock_guard<std::mutex> lock(mutex_);
    files_.insert(found.begin(), found.end());
}

void OutputFolder::commit() {
    if (temp_.empty() || committed_) return;
    checkReplaceable();
    std::error_code ec;
    const bool exists = fs::exists(target_, ec);
    if (mode_ == Mode::AddFiles && exists) return commitInto();
    if (exists) checkInputsKept(target_, temp_);
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

// Every destination is checked first; files replaced are moved aside (into old_) so that a rename
// failing part-way puts everything back: the folder ends with all the new files or none.
void OutputFolder::commitInto() {
    std::error_code ec;
    // A staged top-level folder holding the marker is a run of its own (the main job's protocol run):
    // it replaces an earlier run there as a whole, as ReplaceRun would, so no file of the earlier run
    // stays beside the new one. Every other file joins the folder on its own.
    std::set<std::string> runs;
    if (!marker_.empty())
        for (const fs::directory_entry& e : fs::directory_iterator(temp_, ec))
            if (e.is_directory(ec) && fs::exists(e.path() / marker_, ec)) runs.insert(e.path().filename().string());
    std::vector<std::string> files;  // a writer may decline to write (a plot without data)
    for (const std::string& run : runs) files.push_back(run);
    for (const std::string& f : getFiles()) {
        const std::string top = fs::path(f).begin()->string();
        if (!runs.count(top) && fs::exists(temp_ / f, ec)) files.push_back(f);
    }
    for (const std::string& f : files) {
        const fs::path to = target_ / f;
        if (runs.count(f)) {
            if (fs::exists(to, ec) && !(fs::is_directory(to, ec) && holdsMarker(to, marker_)))
                throw InputError(to.string() + ": exists and is not an armsim run (no " + marker_ +
                                 " of armsim's): cannot replace it with the output folder");
            if (fs::exists(to, ec)) checkInputsKept(to, temp_ / f);
        } else if (fs::exists(to, ec) && !fs::is_regular_file(to, ec)) {
            throw InputError(to.string() + ": exists and is not a file: cannot replace it with the output file");
        } else if (fs::exists(to, ec)) {
            checkNotReplacingInput(to.string(), (temp_ / f).string(), target_.string());
        }
    }
    std::vector<Placement> placements;
    for (const std::string& f : files)
        placements.push_back({temp_ / f, target_ / f, old_ / f, (target_ / f).string()});
    for (const std::string& f : resultFileNames_)
        if (std::find(files.begin(), files.end(), f) == files.end() && fs::is_regular_file(target_ / f, ec)) {
            checkNotReplacingInput((target_ / f).string(), "", target_.string());
            placements.push_back({fs::path(), target_ / f, old_ / f, (target_ / f).string()});
        }
    placeAllOrNone(placements);
    committed_ = true;
    fs::remove_all(temp_, ec);
    fs::remove_all(old_, ec);
}

// What a run killed before its cleanup (SIGKILL, a second Ctrl-C) left: <stem>.partial.<pid>-<n> folders
// of processes that no longer exist are removed (this process's own only when no live OutputFolder
// uses them: pids repeat in containers); a <stem>.old.<pid>-<n> folder holds the earlier run, moved aside
// just before the kill: moved back when the target is missing (ReplaceRun), removed otherwise.
void OutputFolder::removeStaleLeftovers(const fs::path& parent, const std::string& stem) const {
    std::error_code ec;
    std::vector<fs::path> entries;
    for (const fs::directory_entry& e : fs::directory_iterator(parent, ec)) entries.push_back(e.path());
    for (const fs::path& p : entries) {
        const std::string name = p.filename().string();
        for (const std::string kind : {".partial.", ".old."}) {
            const std::string prefix = stem + kind;
            if (name.rfind(prefix, 0) != 0) continue;
            const std::string id = name.substr(prefix.size());
            const std::string digits = id.substr(0, id.find('-'));
            if (digits.empty() || digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos)
                continue;
            const pid_t pid = pid_t(std::stol(digits));
            // Ours count as stale unless a live OutputFolder stages there (pids repeat in containers).
            const bool inUse = pid == ::getpid() ? isLive(parent / (stem + ".partial." + id))
                                                 : (::kill(pid, 0) == 0 || errno == EPERM);
            if (inUse) continue;
            if (kind == ".old." && mode_ == Mode::ReplaceRun && !fs::exists(target_, ec)) fs::rename(p, target_, ec);
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
    if (isFolder && (fs::is_empty(target_, ec) || holdsMarker(target_, marker_))) return;
    throw InputError(target_.string() + ": exists and is not an armsim run (no " + marker_ +
                     " of armsim's): refusing to replace it; choose another output folder");
}

namespace {

constexpr const char* kFilePrefix = ".armsim-partial-";
std::atomic<int> fileCounter{0};

// Staging files ".armsim-partial-<pid>-<n>-NAME" in `dir` of processes that are gone.
void removeStaleFiles(const fs::path& dir) {
    std::error_code ec;
    std::vector<fs::path> stale;
    const std::string prefix = kFilePrefix;
    for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) {
        const std::string name = e.path().filename().string();
        if (name.rfind(prefix, 0) != 0) continue;
        const std::string digits = name.substr(prefix.size(), name.find('-', prefix.size()) - prefix.size());
        if (digits.empty() || digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) continue;
        const pid_t pid = pid_t(std::stol(digits));
        if (pid != ::getpid() && ::kill(pid, 0) != 0 && errno == ESRCH) stale.push_back(e.path());
    }
    for (const fs::path& p : stale) fs::remove(p, ec);
}

}  // namespace

OutputFiles::~OutputFiles() {
    if (committed_) return;
    std::error_code ec;
    for (const Entry& e : entries_) fs::remove(e.staging, ec);
}

namespace {

// The same file: one path's file system object is the other's (links, ".."), or both name one path.
bool isSameFile(const std::string& a, const std::string& b) {
    std::error_code ec;
    if (fs::exists(a, ec) && fs::exists(b, ec)) return fs::equivalent(a, b, ec);
    return fs::absolute(a, ec).lexically_normal() == fs::absolute(b, ec).lexically_normal();
}

}  // namespace

void OutputFiles::checkNotInput(const std::string& option, const std::string& path) const {
    for (const Entry& in : inputs_)
        if (isSameFile(in.target, path))
            throw InputError(option + " '" + path + "' is the file " + in.option +
                             " reads: expected a path of its own (the input would be overwritten)");
}

void OutputFiles::addInput(const std::string& option, const std::string& path) {
    if (path.empty()) return;
    for (const Entry& out : entries_)
        if (isSameFile(out.target, path))
            throw InputError(out.option + " '" + out.target + "' is the file " + option +
                             " reads: expected a path of its own (the input would be overwritten)");
    inputs_.push_back({option, path, ""});
}

std::string OutputFiles::add(const std::string& option, const std::string& path, bool required) {
    if (path.empty() && required) throw InputError(option + " is empty: expected a file path");
    if (path.empty()) return "";
    if (committed_) throw std::logic_error("OutputFiles::add after commit");
    checkNotInput(option, path);
    fs::path target = fs::path(path).lexically_normal();
    std::error_code ec;
    const WriteTarget where = findWriteTarget(target.string());   // a link is written through
    if (!where.isFile)
        throw InputError(option + " '" + path + "': a link to '" + where.path +
                         "', which is not a regular file: expected a file path");
    target = where.path;
    const fs::path absolute = fs::absolute(target, ec).lexically_normal();
    for (const Entry& e : entries_)
        if (fs::absolute(e.target, ec).lexically_normal() == absolute)
            throw InputError(option + " '" + path + "' is the file " + e.option +
                             " writes: expected a path of its own");
    if (target.filename().empty() || fs::is_directory(target, ec))
        throw InputError(option + " '" + path + "' is a folder: expected a file path");
    // Its folder may not exist yet: made at commit(), not now (a failed run leaves no empty folder).
    // The staging file goes to the nearest folder that exists.
    const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
    fs::path existing = dir;
    while (!fs::exists(existing, ec) && existing.has_parent_path() && existing.parent_path() != existing)
        existing = existing.parent_path();
    if (!fs::exists(existing, ec)) existing = ".";
    if (!fs::is_directory(existing, ec))
        throw InputError(option + " '" + path + "': cannot create its folder '" + dir.string() + "': '" +
                         existing.string() + "' is a file");
    if (::access(existing.c_str(), W_OK) != 0)
        throw InputError(option + " '" + path + "': folder '" + existing.string() + "' is not writable");
    removeStaleFiles(existing);
    const std::string staging = (existing / (std::string(kFilePrefix) + std::to_string(::getpid()) + "-" +
                                             std::to_string(fileCounter++) + "-" + target.filename().string()))
                                    .string();
    // A probe: the folder takes a new file (access() says yes to root in /proc, say).
    std::FILE* probe = std::fopen(staging.c_str(), "wb");
    if (!probe)
        throw InputError(option + " '" + path + "': cannot write a file in folder '" + existing.string() + "' (" +
                         std::strerror(errno) + ")");
    std::fclose(probe);
    fs::remove(staging, ec);
    entries_.push_back({option, target.string(), staging});
    return staging;
}

void OutputFiles::writeWith(const std::string& staging, const std::function<void(const std::string& path)>& writer) {
    if (std::none_of(entries_.begin(), entries_.end(), [&](const Entry& e) { return e.staging == staging; }))
        throw std::logic_error("OutputFiles::writeWith: '" + staging + "' was not added");
    try {
        writer(staging);
    } catch (const InputError& e) {  // any staging file named as the option and the file typed
        std::string message = e.what();
        for (const Entry& x : entries_) {   // a quoted staging path loses its own quotes
            message = replaceAll(std::move(message), "'" + x.staging + "'", x.option + " '" + x.target + "'");
            message = replaceAll(std::move(message), x.staging, x.option + " '" + x.target + "'");
        }
        throw InputError(message);
    }
}

void OutputFiles::commit() {
    if (committed_) throw std::logic_error("OutputFiles::commit twice");
    std::error_code ec;
    // Files a writer left out (it may decline) are skipped; every destination is checked first.
    std::vector<Placement> placements;
    for (const Entry& e : entries_) {
        if (!fs::exists(e.staging, ec)) continue;
        if (fs::exists(e.target, ec) && !fs::is_regular_file(e.target, ec))
            throw InputError(e.option + " '" + e.target + "': exists and is not a file: cannot replace it");
        if (fs::exists(e.target, ec)) checkNotReplacingInput(e.target, e.staging, e.option + " '" + e.target + "'");
        placements.push_back({e.staging, e.target, e.staging + ".old", e.option + " '" + e.target + "'"});
    }
    placeAllOrNone(placements);
    committed_ = true;
    for (const Placement& p : placements) fs::remove(p.aside, ec);
}

}  // namespace armsim
