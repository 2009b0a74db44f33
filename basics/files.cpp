#include "basics/files.h"

#include "basics/errors.h"

#include <filesystem>
#include <fstream>
#include <sstream>
#include <unistd.h>

namespace armsim {

bool doesPathExist(const std::string& path) {
    std::error_code ec;
    return std::filesystem::exists(path, ec) && !ec;
}

bool isRegularFile(const std::string& path) {
    std::error_code ec;
    return std::filesystem::is_regular_file(path, ec) && !ec;
}

void checkInputFile(const std::string& path, std::uintmax_t maxBytes) {
    std::error_code ec;
    if (std::filesystem::exists(path, ec) && !std::filesystem::is_regular_file(path, ec))
        throw InputError(path + ": not a regular file (a folder, device or pipe): expected a file");
    const std::uintmax_t size = std::filesystem::file_size(path, ec);
    if (!ec && size > maxBytes)
        throw InputError(path + ": " + std::to_string(size) + " bytes: expected at most " + std::to_string(maxBytes) +
                         " for this kind of file");
}

namespace {
thread_local FileReadRecorder* tInnermostRecorder = nullptr;
}

FileReadRecorder::FileReadRecorder() : outer_(tInnermostRecorder) { tInnermostRecorder = this; }

FileReadRecorder::~FileReadRecorder() { tInnermostRecorder = outer_; }

std::string readFileText(const std::string& path) {
    checkInputFile(path, 64 << 20);
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path + ": cannot open file (does it exist and is it readable?)");
    std::stringstream buf;
    buf << in.rdbuf();
    std::string text = buf.str();
    for (FileReadRecorder* r = tInnermostRecorder; r; r = r->outer_) r->files_.push_back({path, text});
    return text;
}

bool areFilesUnchanged(const std::vector<FileSnapshot>& files) {
    for (const FileSnapshot& f : files) {
        try {
            if (readFileText(f.path) != f.text) return false;
        } catch (const InputError&) {
            return false;
        }
    }
    return true;
}

void writeFileAtomically(const std::string& path, const std::string& text) {
    namespace fs = std::filesystem;
    const fs::path target(path);
    std::error_code ec;
    if (target.has_parent_path()) fs::create_directories(target.parent_path(), ec);
    const fs::path tmp = target.string() + ".tmp." + std::to_string(::getpid());
    {
        std::ofstream out(tmp, std::ios::binary);
        if (!out) throw InputError(path + ": cannot write (is the directory writable?)");
        out << text;
        out.flush();
        if (!out) {
            fs::remove(tmp, ec);
            throw InputError(path + ": write failed (disk full?)");
        }
    }
    fs::rename(tmp, target, ec);
    if (ec) {
        fs::remove(tmp, ec);
        throw InputError(path + ": cannot replace file: " + ec.message());
    }
}

}  // namespace armsim
