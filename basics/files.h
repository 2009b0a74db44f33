// Whole-file reading with size guards and atomic whole-file writing. Framework-free.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace armsim {

/// Whether something exists at path; false also when the name cannot be looked up (too long, a
/// component that is a file, no permission), where std::filesystem::exists would throw.
bool doesPathExist(const std::string& path);
/// Whether path is a regular file (or a link to one); false also when it cannot be looked up.
bool isRegularFile(const std::string& path);

/// Creates the folder and its parents (nothing when it exists). InputError naming the path and the
/// reason when it cannot (a file in the way, no permission, a name too long).
void createFolder(const std::string& path);

/// The whole file as bytes. Throws InputError naming the path when it cannot be read.
std::string readFileText(const std::string& path);
/// InputError unless `path` (when it exists) is a regular file of at most maxBytes (a folder, a device
/// such as /dev/zero or a pipe would make a reader block or grow without bound). Notes the file as an
/// input of this process (noteInputFile).
void checkInputFile(const std::string& path, std::uintmax_t maxBytes);

/// Turns the protection of inputs on or off for this process (off by default; the armsim command turns
/// it on): while on, every file a reader opens is noted (noteInputFile) and an output that would
/// replace or delete it with other bytes is refused (checkNotReplacingInput), so a command never
/// overwrites or deletes what it read. Turning it off forgets the noted files.
void setInputProtection(bool on);
/// Notes `path` as an input of this process (every reader does, through checkInputFile). Thread-safe.
void noteInputFile(const std::string& path);
/// InputError when `target` (a file about to be replaced by `replacement`, or "" for a removal) is a
/// noted input and the replacement is not byte for byte the same. `what` names the output in the message.
void checkNotReplacingInput(const std::string& target, const std::string& replacement, const std::string& what);
/// The noted inputs inside the folder `folder` (for an output that replaces the folder whole).
std::vector<std::string> findInputsInside(const std::string& folder);

/// One file as readFileText read it, or a lookup as doesPathExist answered it.
struct FileSnapshot {
    std::string path;     ///< as given
    bool exists = true;   ///< a lookup's answer (true for a read)
    bool read = true;     ///< a read (text holds the bytes) or only a lookup
    std::string text;     ///< the bytes read
};

/// While alive, records every file readFileText reads and every doesPathExist lookup on this thread
/// (nested recorders all see each), so that a result derived from files can be reused while none of
/// them has changed and no file it looked for has appeared or gone (the model cache of loadModel).
/// Not copyable: it registers itself for its thread.
class FileReadRecorder {
public:
    FileReadRecorder();
    ~FileReadRecorder();
    FileReadRecorder(const FileReadRecorder&) = delete;
    FileReadRecorder& operator=(const FileReadRecorder&) = delete;
    /// The files read so far, in order (a file read twice appears twice).
    const std::vector<FileSnapshot>& getFiles() const { return files_; }
    /// Takes the files read so far (the recorder goes on recording into an empty list).
    std::vector<FileSnapshot> releaseFiles() { return std::move(files_); }

private:
    friend std::string readFileText(const std::string& path);
    friend bool doesPathExist(const std::string& path);
    std::vector<FileSnapshot> files_;
    FileReadRecorder* outer_;
};

/// true when every file still reads as in its snapshot (false when one is missing or unreadable) and
/// every lookup gives the same answer.
bool areFilesUnchanged(const std::vector<FileSnapshot>& files);

/// While alive, messages name files written under `staging` (a folder that will become `shown`) by
/// where they will be: showPath maps them. One at a time per process (the main job's).
class ShownFolder {
public:
    ShownFolder(const std::string& staging, const std::string& shown);
    ~ShownFolder();
    ShownFolder(const ShownFolder&) = delete;
    ShownFolder& operator=(const ShownFolder&) = delete;
};
/// `path` as messages should name it (see ShownFolder); unchanged outside one.
std::string showPath(const std::string& path);

/// Writes text to path atomically: to a temporary beside it, then rename. Throws InputError naming
/// the path when it cannot be written. Parent directories are created. A path that is a symbolic link
/// is written through: its target is replaced (InputError when the target exists and is not a regular
/// file, such as /dev/stdout on a pipe); an input of the command is not replaced by other bytes.
void writeFileAtomically(const std::string& path, const std::string& text);

/// A file written piece by piece and put in place whole: the pieces go to a temporary beside the
/// target, commit() renames it over the target; destroyed uncommitted, the temporary is removed and
/// the target is untouched. Throws InputError naming the path when a write fails (disk full).
class AtomicFileWriter {
public:
    explicit AtomicFileWriter(const std::string& path);
    ~AtomicFileWriter();
    AtomicFileWriter(const AtomicFileWriter&) = delete;
    AtomicFileWriter& operator=(const AtomicFileWriter&) = delete;
    void write(const std::string& text);
    void commit();

private:
    std::string path_, target_, tmp_;   // as given; where it goes (a link's target); the temporary
    std::FILE* file_ = nullptr;
};

}  // namespace armsim
