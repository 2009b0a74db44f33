#include "basics/files.h"

#include "basics/errors.h"
#include "basics/write_target.h"

#include <algorithm>
#include <cstdio>
#include <iterator>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <unistd.h>

namespace armsim {

namespace {
thread_local FileReadRecorder* tInnermostRecorder = nullptr;

std::mutex inputMutex;
bool inputProtection = false;   // guarded by inputMutex
std::set<std::string>& getInputs() {   // canonical paths; never destroyed (writers may run at exit)
    static auto* inputs = new std::set<std::string>;
    return *inputs;
}

std::string canonicalPath(const std::string& path) {
    std::error_code ec;
    const std::filesystem::path p = std::filesystem::weakly_canonical(path, ec);
    return ec ? std::filesystem::absolute(path, ec).lexically_normal().string() : p.string();
}

bool haveSameBytes(const std::string& a, const std::string& b) {
    std::error_code ec;
    if (std::filesystem::file_size(a, ec) != std::filesystem::file_size(b, ec) || ec) return false;
    std::ifstream x(a, std::ios::binary), y(b, std::ios::binary);
    return x && y && std::equal(std::istreambuf_iterator<char>(x), std::istreambuf_iterator<char>(),
                                std::istreambuf_iterator<char>(y), std::istreambuf_iterator<char>());
}
}  // namespace

WriteTarget findWriteTarget(const std::string& path) {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (!fs::is_symlink(path, ec)) return {path, true};
    const std::string resolved = fs::weakly_canonical(path, ec).string();
    if (ec) return {"", false};
    return {resolved, !fs::exists(resolved, ec) || fs::is_regular_file(resolved, ec)};
}

void setInputProtection(bool on) {
    std::lock_guard<std::mutex> lock(inputMutex);
    inputProtection = on;
    if (!on) getInputs().clear();
}

void noteInputFile(const std::string& path) {
    {
        std::lock_guard<std::mutex> lock(inputMutex);
        if (!inputProtection) return;
    }
    const std::string c = canonicalPath(path);
    std::lock_guard<std::mutex> lock(inputMutex);
    getInputs().insert(c);
}

void checkNotReplacingInput(const std::string& target, const std::string& replacement, const std::string& what) {
    const std::string c = canonicalPath(target);
    {
        std::lock_guard<std::mutex> lock(inputMutex);
        if (!getInputs().count(c)) return;
    }
    if (!replacement.empty() && haveSameBytes(target, replacement)) return;
    throw InputError(what + " would " + (replacement.empty() ? "delete " : "replace ") + target +
                     ", which this command read as input (nothing was written): expected an output apart from the inputs");
}

std::vector<std::string> findInputsInside(const std::string& folder) {
    std::string prefix = canonicalPath(folder);
    if (prefix.empty() || prefix.back() != '/') prefix += '/';
    std::vector<std::string> out;
    std::lock_guard<std::mutex> lock(inputMutex);
    for (const std::string& p : getInputs())
        if (p.rfind(prefix, 0) == 0) out.push_back(p);
    return out;
}

bool doesPathExist(const std::string& path) {
    std::error_code ec;
    const bool exists = std::filesystem::exists(path, ec) && !ec;
    for (FileReadRecorder* r = tInnermostRecorder; r; r = r->outer_) r->files_.push_back({path, exists, false, {}});
    return exists;
}

bool isRegularFile(const std::string& path) {
    std::error_code ec;
    return std::filesystem::is_regular_file(path, ec) && !ec;
}

void createFolder(const std::string& path) {
    std::error_code ec;
    std::filesystem::create_directories(path, ec);
    if (ec || !std::filesystem::is_directory(path, ec))
        throw InputError(path + ": cannot create the folder (" + (ec ? ec.message() : std::string("a file is in the way")) +
                         ")");
}

void checkInputFile(const std::string& path, std::uintmax_t maxBytes) {
    noteInputFile(path);
    std::error_code ec;
    if (std::filesystem::exists(path, ec) && !std::filesystem::is_regular_file(path, ec))
        throw InputError(path + ": not a regular file (a folder, device or pipe): expected a file");
    const std::uintmax_t size = std::filesystem::file_size(path, ec);
    if (!ec && size > maxBytes)
        throw InputError(path + ": " + std::to_string(size) + " bytes: expected at most " + std::to_string(maxBytes) +
                         " for this kind of file");
}

FileReadRecorder::FileReadRecorder() : outer_(tInnermostRecorder) { tInnermostRecorder = this; }

FileReadRecorder::~FileReadRecorder() {  // unlinks itself, also when recorders end out of order
    if (tInnermostRecorder == this) {
        tInnermostRecorder = outer_;
        return;
    }
    for (FileReadRecorder* r = tInnermostRecorder; r; r = r->outer_)
        if (r->outer_ == this) {
            r->outer_ = outer_;
            return;
        }
}

std::string readFileText(const std::string& path) {
    checkInputFile(path, 64 << 20);
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path + ": cannot open file (does it exist and is it readable?)");
    std::stringstream buf;
    buf << in.rdbuf();
    std::string text = buf.str();
    for (FileReadRecorder* r = tInnermostRecorder; r; r = r->outer_) r->files_.push_back({path, true, true, text});
    return text;
}

bool areFilesUnchanged(const std::vector<FileSnapshot>& files) {
    for (const FileSnapshot& f : files) {
        if (!f.read) {
            if (doesPathExist(f.path) != f.exists) return false;
            continue;
        }
        try {
            if (readFileText(f.path) != f.text) return false;
        } catch (const InputError&) {
            return false;
        }
    }
    return true;
}

namespace {
std::mutex shownMutex;
std::string shownStaging, shownTarget;
}  // namespace

ShownFolder::ShownFolder(const std::string& staging, const std::string& shown) {
    std::lock_guard<std::mutex> lock(shownMutex);
    shownStaging = staging;
    shownTarget = shown;
}

ShownFolder::~ShownFolder() {
    std::lock_guard<std::mutex> lock(shownMutex);
    shownStaging.clear();
    shownTarget.clear();
}

std::string showPath(const std::string& path) {
    std::lock_guard<std::mutex> lock(shownMutex);
    if (shownStaging.empty() || path.rfind(shownStaging, 0) != 0) return path;
    return shownTarget + path.substr(shownStaging.size());
}

void writeFileAtomically(const std::string& path, const std::string& text) {
    AtomicFileWriter out(path);
    out.write(text);
    out.commit();
}

AtomicFileWriter::AtomicFileWriter(const std::string& path) : path_(path), target_(path) {
    namespace fs = std::filesystem;
    std::error_code ec;
    const WriteTarget where = findWriteTarget(path);
    target_ = where.path;
    if (!where.isFile)
        throw InputError(path + ": a link to " + (target_.empty() ? std::string("nothing that can be resolved") : target_) +
                         ", which is not a regular file: expected a file to write");
    const fs::path target(target_);
    if (target.has_parent_path()) fs::create_directories(target.parent_path(), ec);
    tmp_ = target_ + ".tmp." + std::to_string(::getpid());
    file_ = std::fopen(tmp_.c_str(), "wb");
    if (!file_) throw InputError(path + ": cannot write (is the directory writable?)");
}

AtomicFileWriter::~AtomicFileWriter() {
    if (!file_) return;
    std::fclose(file_);
    std::remove(tmp_.c_str());
}

void AtomicFileWriter::write(const std::string& text) {
    if (!file_) throw std::logic_error("AtomicFileWriter: write after commit");
    if (std::fwrite(text.data(), 1, text.size(), file_) != text.size()) {
        std::fclose(file_);
        file_ = nullptr;
        std::remove(tmp_.c_str());
        throw InputError(path_ + ": write failed (disk full?)");
    }
}

void AtomicFileWriter::commit() {
    if (!file_) throw std::logic_error("AtomicFileWriter: commit twice");
    const bool flushed = std::fflush(file_) == 0;
    const bool closed = std::fclose(file_) == 0;
    file_ = nullptr;
    if (!flushed || !closed) {
        std::remove(tmp_.c_str());
        throw InputError(path_ + ": write failed (disk full?)");
    }
    try {
        checkNotReplacingInput(target_, tmp_, path_);
    } catch (...) {
        std::remove(tmp_.c_str());
        throw;
    }
    std::error_code ec;
    std::filesystem::rename(tmp_, target_, ec);
    if (ec) {
        std::remove(tmp_.c_str());
        throw InputError(path_ + ": cannot replace file: " + ec.message());
    }
}

}  // namespace armsim
