// index.html of an output folder: what ran, every plot and video embedded with a sentence on what it
// shows, the small tables shown and every file linked. Self-contained: no network, no external script
// or style; the files it shows are the folder's own (relative links).
#pragma once

#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace armsim {

/// What the report says about the run.
struct FolderReport {
    std::string title;                                        ///< e.g. "armsim run"
    std::vector<std::pair<std::string, std::string>> facts;   ///< (label, value): command line, version, time, settings
    /// What the command printed (its results and key numbers), shown under the facts; "" : nothing.
    std::string printed;
    /// One sentence on what a file shows, from its path relative to the folder ("" : none known).
    std::function<std::string(const std::string& relativePath)> describe;
};

/// Writes DIR/index.html (atomically) for every file under DIR, by folder: .png images and .mp4 / .avi
/// videos embedded with their sentence; .csv tables of at most kPreviewRows rows and 12 columns shown
/// (larger ones: their first rows), every file linked. The page checks on load that each image and
/// video loaded and records the result in its body's data-resources attribute ("ok" or the missing
/// files: what the tests read in a real browser). An index.html that armsim did not write is left
/// alone, and a folder of more than kMaxReportFiles files gets none: both throw std::runtime_error, as
/// does a failed write. A folder of more than kMaxReportFilesPerFolder files shows its first ones by
/// name and says how many more there are.
void writeFolderReport(const std::string& dir, const FolderReport& report);
/// Whether the file at path is a page writeFolderReport wrote.
bool isFolderReport(const std::string& path);

constexpr int kPreviewRows = 12;
constexpr long kMaxReportFiles = 200000;
constexpr long kMaxReportFilesPerFolder = 200;

}  // namespace armsim
