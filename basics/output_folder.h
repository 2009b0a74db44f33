// Output folders that appear whole or not at all. Framework-free.
//
// Every command that writes several result files writes them through an OutputFolder: the files go to
// a hidden staging folder (".NAME.partial.<pid>-<n>" beside the target, or ".armsim.partial.<pid>-<n>"
// inside a folder that files are added to), and commit() moves them into place once the whole result
// exists. An exception, an interruption or a failing writer before commit() leaves the
// target untouched and the sibling removed (destructor). A run killed outright (SIGKILL) leaves the
// sibling behind; the next OutputFolder on the same target removes it (its process is gone).
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <mutex>
#include <set>
#include <string>
#include <vector>

namespace armsim {

class OutputFolder {
public:
    /// Characters a new target's staging sibling (".NAME.partial.<pid>-<n>") adds to NAME, with room
    /// to spare: a target name must leave this much below the system's 255.
    static constexpr std::size_t kStagingNameExtra = 40;

    /// How commit() treats a target that exists.
    enum class Mode {
        /// The folder is one run: an earlier run (an empty folder or one holding `marker` as armsim writes
        /// it: a manifest whose text names "armsim_version") is replaced
        /// as a whole by one rename; any other existing folder or file is refused (InputError).
        ReplaceRun,
        /// The files join the folder: each replaces a file of the same name by a rename; other files in
        /// the folder are kept (a user's own results folder). With a `marker`, a staged top-level folder
        /// holding it is a run of its own and replaces an earlier run (a folder holding the marker) whole.
        AddFiles,
    };

    /// outDir empty: a disabled folder (isEnabled() false, commit() does nothing). Throws InputError
    /// naming outDir when the target cannot be replaced or the sibling cannot be made.
    OutputFolder(const std::string& outDir, Mode mode, std::string marker = "");
    OutputFolder(const OutputFolder&) = delete;
    OutputFolder& operator=(const OutputFolder&) = delete;
    ~OutputFolder();

    bool isEnabled() const { return !temp_.empty(); }
    /// The final path of a file of the folder (for messages and reports).
    std::string getTargetPath(const std::string& relative) const { return (target_ / relative).string(); }
    /// The path to write a file to before commit(); records the file; creates its sub-folders.
    /// Thread-safe. std::logic_error on a disabled folder.
    std::string addFile(const std::string& relative);
    /// Writes a whole file (thread-safe for distinct names). InputError naming the final path on failure.
    void write(const std::string& relative, const std::string& text);
    /// Runs writer(path) with addFile(relative)'s path (a plot, a JSON report); an InputError it throws
    /// names the final path instead of the staging one.
    void writeWith(const std::string& relative, const std::function<void(const std::string& path)>& writer);
    /// Relative names of the files added so far, sorted.
    std::vector<std::string> getFiles() const;
    /// The staging folder (for writers that take a folder: the main job's steps). std::logic_error on a
    /// disabled folder.
    std::string getStagingPath() const;
    /// `message` with the staging folder named as the target (for errors of writers given addFile paths).
    std::string showPaths(std::string message) const;
    /// Adds every regular file found under the staging folder (written there without addFile).
    void addStagedFiles();
    /// AddFiles: the names of every file this kind of result may hold. commit() removes those of them the
    /// new result does not hold, with the rest (all or none), so no earlier result's file stays beside
    /// it (an earlier design's design_validation.csv beside a design without validation).
    void setResultFileNames(std::vector<std::string> names) { resultFileNames_ = std::move(names); }
    /// Moves the files into place, all or none: InputError naming the path when a rename fails, after
    /// restoring what was there (the earlier run, or the files the new ones were replacing).
    void commit();

private:
    void removeStaleLeftovers(const std::filesystem::path& parent, const std::string& stem) const;
    std::vector<std::filesystem::path> madeParents_;   ///< folders the constructor made, innermost first
    void checkReplaceable() const;
    void commitInto();

    Mode mode_;
    std::string marker_;
    std::vector<std::string> resultFileNames_;
    std::filesystem::path target_, temp_, old_;
    bool committed_ = false;
    mutable std::mutex mutex_;
    std::set<std::string> files_;
};

/// Several result files named by options (`trial --out T.csv --plot P.png --video V.mp4`), put in place
/// together: each is checked when added (before the work: distinct from the others, no folder in the
/// way, its folder creatable), written to a staging file ".armsim-partial-<pid>-<n>-NAME" in the nearest
/// existing folder of its path (the name keeps its extension, which writers may read), and commit()
/// makes the missing folders and renames them all into place. Destroyed
/// uncommitted (an error, an interruption), every staging file is removed and the targets are
/// untouched. Leftovers of a process that no longer exists are removed by the next add() there.
class OutputFiles {
public:
    OutputFiles() = default;
    OutputFiles(const OutputFiles&) = delete;
    OutputFiles& operator=(const OutputFiles&) = delete;
    ~OutputFiles();
    /// Registers the file `path` given with `option` (named in messages) and returns the path to write
    /// it to. An empty path registers nothing and returns "" (InputError when `required`). InputError
    /// naming both options when two give the same file, and naming the option when a folder is in the
    /// way or its folder cannot be made.
    std::string add(const std::string& option, const std::string& path, bool required = false);
    /// Declares a file the command reads (given with `option`): an output on the same file is refused
    /// (InputError naming both options), before or after this call. An empty path is ignored.
    void addInput(const std::string& option, const std::string& path);
    /// Runs writer(staging) for a path add() returned; an InputError it throws is reported naming the
    /// option and the file as typed instead of any staging file.
    void writeWith(const std::string& staging, const std::function<void(const std::string& path)>& writer);
    /// Renames every staged file that was written into place (a registered file its writer never wrote
    /// is left out). InputError naming the path when a rename fails.
    void commit();

private:
    struct Entry {
        std::string option, target, staging;
    };
    std::vector<Entry> entries_, inputs_;
    void checkNotInput(const std::string& option, const std::string& path) const;
    bool committed_ = false;
};

}  // namespace armsim
