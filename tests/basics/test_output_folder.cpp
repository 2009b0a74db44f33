#include "basics/errors.h"
#include "basics/files.h"
#include "basics/output_folder.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <unistd.h>
#include <fstream>

using namespace armsim;
namespace fs = std::filesystem;
// A manifest as armsim writes it (the marker names armsim's version).
constexpr const char* kManifest = "{\"armsim_version\": \"0.1.0\"}";

namespace {

struct OutputFolderTest : ::testing::Test {
    fs::path root = fs::temp_directory_path() / ("armsim_out_" + std::to_string(::getpid()));
    void SetUp() override { fs::remove_all(root); fs::create_directories(root); }
    void TearDown() override { fs::remove_all(root); }
    int countEntries(const fs::path& dir) const {
        int n = 0;
        for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++n;
        return n;
    }
};

}  // namespace

TEST_F(OutputFolderTest, NothingAppearsWithoutCommitAndNothingIsLeftBeside) {
    const fs::path target = root / "run";
    {
        OutputFolder out(target.string(), OutputFolder::Mode::ReplaceRun, "manifest.json");
        out.write("a.csv", "1\n");
        out.write("trials/b.csv", "2\n");
        EXPECT_FALSE(fs::exists(target));
    }
    EXPECT_FALSE(fs::exists(target));
    EXPECT_EQ(countEntries(root), 0);
}

TEST_F(OutputFolderTest, ReplaceRunSwapsTheWholeFolderAndRefusesAForeignOne) {
    const fs::path target = root / "run";
    {
        OutputFolder out(target.string(), OutputFolder::Mode::ReplaceRun, "manifest.json");
        out.write("old_only.csv", "x");
        out.write("manifest.json", kManifest);
        out.commit();
    }
    {
        OutputFolder out(target.string(), OutputFolder::Mode::ReplaceRun, "manifest.json");
        out.write("trials/t.csv", "y");
        out.write("manifest.json", kManifest);
        EXPECT_EQ(out.getFiles(), (std::vector<std::string>{"manifest.json", "trials/t.csv"}));
        out.commit();
    }
    EXPECT_FALSE(fs::exists(target / "old_only.csv"));
    EXPECT_EQ(readFileText((target / "trials/t.csv").string()), "y");
    EXPECT_EQ(countEntries(root), 1);  // no .old or .partial sibling
    const fs::path foreign = root / "mine";
    fs::create_directories(foreign);
    std::ofstream(foreign / "notes.txt") << "keep";
    EXPECT_THROW(OutputFolder(foreign.string(), OutputFolder::Mode::ReplaceRun, "manifest.json"), InputError);
    EXPECT_TRUE(fs::exists(foreign / "notes.txt"));
    std::ofstream(foreign / "manifest.json") << "{}";   // someone else's manifest: still not an armsim run
    EXPECT_THROW(OutputFolder(foreign.string(), OutputFolder::Mode::ReplaceRun, "manifest.json"), InputError);
    EXPECT_TRUE(fs::exists(foreign / "notes.txt"));
}

TEST_F(OutputFolderTest, AddFilesKeepsOtherFilesAndReplacesSameNames) {
    const fs::path target = root / "results";
    fs::create_directories(target);
    std::ofstream(target / "notes.txt") << "keep";
    std::ofstream(target / "estimates.json") << "old";
    {
        OutputFolder out(target.string(), OutputFolder::Mode::AddFiles);
        out.write("estimates.json", "new");
        out.write("plots/fit.png", "png");
        EXPECT_EQ(readFileText((target / "estimates.json").string()), "old");
        out.commit();
    }
    EXPECT_EQ(readFileText((target / "notes.txt").string()), "keep");
    EXPECT_EQ(readFileText((target / "estimates.json").string()), "new");
    EXPECT_EQ(readFileText((target / "plots/fit.png").string()), "png");
    EXPECT_EQ(countEntries(root), 1);
    std::ofstream(root / "file") << "x";
    EXPECT_THROW(OutputFolder((root / "file").string(), OutputFolder::Mode::AddFiles), InputError);
}

TEST_F(OutputFolderTest, LeftoversOfDeadProcessesAreCleanedAndTheEarlierRunRestored) {
    const fs::path target = root / "run";
    // pid 999999999 exceeds pid_max, so no process has it.
    fs::create_directories(root / ".run.partial.999999999");
    fs::create_directories(root / ".run.old.999999999");
    std::ofstream(root / ".run.old.999999999" / "manifest.json") << kManifest;
    {
        OutputFolder out(target.string(), OutputFolder::Mode::ReplaceRun, "manifest.json");
        EXPECT_FALSE(fs::exists(root / ".run.partial.999999999"));
        EXPECT_TRUE(fs::exists(target / "manifest.json"));  // the earlier run moved back
    }
    EXPECT_EQ(countEntries(root), 1);
}

TEST_F(OutputFolderTest, AddFilesIntoANewFolderCreatesItWhole) {
    const fs::path target = root / "new" / "results";
    {
        OutputFolder out(target.string(), OutputFolder::Mode::AddFiles);
        out.write("a.csv", "1");
        EXPECT_FALSE(fs::exists(target));
        out.commit();
    }
    EXPECT_EQ(readFileText((target / "a.csv").string()), "1");
    EXPECT_EQ(countEntries(root / "new"), 1);
}

TEST_F(OutputFolderTest, TwoFoldersOnOneTargetKeepTheirOwnFiles) {
    const fs::path target = root / "results";
    fs::create_directories(target);
    OutputFolder a(target.string(), OutputFolder::Mode::AddFiles);
    a.write("a.csv", "a");
    OutputFolder b(target.string(), OutputFolder::Mode::AddFiles);
    b.write("b.csv", "b");
    a.commit();
    b.commit();
    EXPECT_EQ(readFileText((target / "a.csv").string()), "a");
    EXPECT_EQ(readFileText((target / "b.csv").string()), "b");
}

TEST_F(OutputFolderTest, AFileThatCannotBeReplacedMovesNothing) {
    const fs::path target = root / "results";
    fs::create_directories(target / "z.csv");  // a folder where a file should go
    std::ofstream(target / "a.csv") << "old";
    {
        OutputFolder out(target.string(), OutputFolder::Mode::AddFiles);
        out.write("a.csv", "new");
        out.write("z.csv", "z");
        EXPECT_THROW(out.commit(), InputError);
    }
    EXPECT_EQ(readFileText((target / "a.csv").string()), "old");
    EXPECT_EQ(countEntries(target), 2);  // a.csv and the z.csv folder; no staging left
}

TEST_F(OutputFolderTest, ADisabledFolderWritesNothing) {
    OutputFolder out("", OutputFolder::Mode::AddFiles);
    EXPECT_FALSE(out.isEnabled());
    EXPECT_THROW(out.addFile("a.csv"), std::logic_error);
    EXPECT_NO_THROW(out.commit());
}

// A writer's error names the file where the user will look for it, not the hidden staging folder.
TEST_F(OutputFolderTest, AWritersErrorNamesTheFinalPath) {
    const fs::path target = root / "id";
    OutputFolder out(target.string(), OutputFolder::Mode::AddFiles);
    std::string staged;
    try {
        out.writeWith("plot.png", [&](const std::string& path) {
            staged = path;
            throw InputError(path + ": the plot could not be written");
        });
        ADD_FAILURE() << "no error";
    } catch (const InputError& e) {
        const std::string message = e.what();
        EXPECT_NE(message.find((target / "plot.png").string() + ": the plot could not be written"), std::string::npos)
            << message;
        EXPECT_EQ(message.find(".partial"), std::string::npos) << message;
    }
    EXPECT_NE(staged.find(".partial"), std::string::npos) << staged;  // the writer did get the staging path
    try {  // a message naming the staging folder itself (or a sub-folder) names the target folder
        out.writeWith("sub/plot.png", [&](const std::string& path) {
            throw InputError(std::filesystem::path(path).parent_path().string() + ": no space left");
        });
        ADD_FAILURE() << "no error";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find((target / "sub").string() + ": no space left"), std::string::npos)
            << e.what();
    }
    out.writeWith("ok.txt", [](const std::string& path) { writeFileAtomically(path, "x"); });
    out.commit();
    EXPECT_TRUE(fs::exists(target / "ok.txt"));
}

namespace {

std::string readAll(const fs::path& p) {
    std::ifstream in(p);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

}  // namespace

// OutputFiles: files named by several options appear together at commit(), in folders made then; none
// before; an uncommitted set leaves nothing, and a commit that fails part-way puts back what was there.
TEST_F(OutputFolderTest, OutputFilesAppearTogetherOrNotAtAll) {
    const fs::path csv = root / "new" / "t.csv", png = root / "p.png";
    {
        OutputFiles files;
        const std::string a = files.add("--out", csv.string(), true), b = files.add("--plot", png.string());
        std::ofstream(a) << "csv\n";
        std::ofstream(b) << "png\n";
        EXPECT_FALSE(fs::exists(root / "new"));  // folders are made at commit
        EXPECT_FALSE(fs::exists(png));
    }
    EXPECT_EQ(countEntries(root), 0);  // uncommitted: every staging file removed

    OutputFiles files;
    const std::string a = files.add("--out", csv.string()), b = files.add("--plot", png.string());
    EXPECT_THROW(files.add("--still", png.string()), InputError);  // one file, two options
    std::ofstream(a) << "csv\n";
    std::ofstream(b) << "png\n";
    files.commit();
    EXPECT_EQ(readAll(csv), "csv\n");
    EXPECT_EQ(readAll(png), "png\n");
    EXPECT_EQ(countEntries(root), 2);  // new/ and p.png: no staging file beside them
}

TEST_F(OutputFolderTest, OutputFilesCommitFailingPartWayPutsBackWhatWasThere) {
    const fs::path csv = root / "t.csv", png = root / "sub" / "p.png";
    std::ofstream(csv) << "earlier\n";
    {
        OutputFiles files;
        const std::string a = files.add("--out", csv.string()), b = files.add("--plot", png.string());
        std::ofstream(a) << "new\n";
        std::ofstream(b) << "png\n";
        std::ofstream(root / "sub") << "a file where the plot's folder would go\n";  // after the check
        EXPECT_THROW(files.commit(), InputError);  // t.csv was replaced, then p.png failed
    }
    EXPECT_EQ(readAll(csv), "earlier\n");
    EXPECT_EQ(countEntries(root), 2);  // t.csv and sub: no staging file, no moved-aside copy
    {
        OutputFiles files;  // a folder in the way of a file: refused before anything moves
        std::ofstream(files.add("--out", csv.string())) << "new\n";
        const std::string b = files.add("--plot", (root / "q.png").string());
        std::ofstream(b) << "png\n";
        fs::create_directories(root / "q.png" / "x");
        EXPECT_THROW(files.commit(), InputError);
    }
    EXPECT_EQ(readAll(csv), "earlier\n");
    EXPECT_TRUE(fs::is_directory(root / "q.png" / "x"));
    OutputFiles files;
    EXPECT_THROW(files.add("--out", "", true), InputError);
    EXPECT_EQ(files.add("--plot", ""), "");
}

// AddFiles with a marker (the main job): a staged folder holding the marker (a protocol run) replaces an
// earlier run there whole, so none of the earlier run's files stays beside the new one; a folder there
// that is not a run is refused and nothing moves; the folder's other files are kept.
TEST_F(OutputFolderTest, AddFilesReplacesARunInsideWhole) {
    const fs::path target = root / "out";
    fs::create_directories(target / "run");
    std::ofstream(target / "run" / "manifest.json") << kManifest;
    std::ofstream(target / "run" / "stale.csv") << "an earlier run's file\n";
    std::ofstream(target / "mine.txt") << "a user's file\n";
    {
        OutputFolder out(target.string(), OutputFolder::Mode::AddFiles, "manifest.json");
        out.write("run/manifest.json", std::string(kManifest) + "\n");
        out.write("run/a.csv", "1\n");
        out.write("top.csv", "2\n");
        out.commit();
    }
    EXPECT_TRUE(fs::exists(target / "run" / "a.csv"));
    EXPECT_FALSE(fs::exists(target / "run" / "stale.csv"));
    EXPECT_TRUE(fs::exists(target / "mine.txt"));
    EXPECT_TRUE(fs::exists(target / "top.csv"));
    EXPECT_EQ(countEntries(target), 3);  // run/, mine.txt, top.csv: nothing staged or moved aside left

    fs::remove(target / "run" / "manifest.json");  // now a folder that is not a run
    {
        OutputFolder out(target.string(), OutputFolder::Mode::AddFiles, "manifest.json");
        out.write("run/manifest.json", kManifest);
        out.write("top.csv", "3\n");
        EXPECT_THROW(out.commit(), InputError);
    }
    EXPECT_EQ(readAll(target / "top.csv"), "2\n");
    EXPECT_TRUE(fs::exists(target / "run" / "a.csv"));
    EXPECT_EQ(countEntries(target), 3);
}

// A new folder several levels down: the levels made for its staging folder go again when the output
// never appears (an error or a stop before commit), and stay when it does.
TEST_F(OutputFolderTest, FoldersMadeForAnOutputThatNeverAppearsAreRemoved) {
    {
        OutputFolder f((root / "a" / "b" / "run").string(), OutputFolder::Mode::ReplaceRun);
        f.write("x.txt", "x");
        EXPECT_TRUE(fs::is_directory(root / "a" / "b"));
    }   // not committed
    EXPECT_FALSE(fs::exists(root / "a")) << "the folders made for the staging folder were left";
    {
        OutputFolder f((root / "a" / "b" / "run").string(), OutputFolder::Mode::ReplaceRun);
        f.write("x.txt", "x");
        f.commit();
    }
    EXPECT_TRUE(fs::exists(root / "a" / "b" / "run" / "x.txt"));
    {   // a folder the user made, or that holds something else, is not removed
        fs::create_directories(root / "c");
        std::ofstream(root / "c" / "keep.txt") << "k";
        OutputFolder f((root / "c" / "d" / "run").string(), OutputFolder::Mode::ReplaceRun);
    }
    EXPECT_TRUE(fs::exists(root / "c" / "keep.txt"));
    EXPECT_FALSE(fs::exists(root / "c" / "d"));
}

// With input protection on (the armsim command): an earlier run replaced whole must not take an input
// of this command with it (a protocol file kept in the run's folder), and a file added to a folder must
// not replace an input by other bytes; both commits are refused and leave every file as it was. An
// input that comes back byte for byte passes.
TEST_F(OutputFolderTest, AnInputInsideTheTargetIsNeitherDeletedNorReplaced) {
    struct Protection {
        Protection() { setInputProtection(true); }
        ~Protection() { setInputProtection(false); }
    } on;
    const fs::path run = root / "run";
    fs::create_directories(run);
    std::ofstream(run / "manifest.json") << kManifest;
    std::ofstream(run / "my_edit.yaml") << "edited\n";
    EXPECT_EQ(readFileText((run / "my_edit.yaml").string()), "edited\n");   // read: an input now
    {
        OutputFolder out(run.string(), OutputFolder::Mode::ReplaceRun, "manifest.json");
        out.write("manifest.json", kManifest);
        EXPECT_THROW(out.commit(), InputError);
    }
    EXPECT_EQ(readAll(run / "my_edit.yaml"), "edited\n");
    {
        OutputFolder out(run.string(), OutputFolder::Mode::ReplaceRun, "manifest.json");
        out.write("manifest.json", kManifest);
        out.write("my_edit.yaml", "edited\n");   // the run copies its input: nothing is lost
        EXPECT_NO_THROW(out.commit());
    }
    const fs::path results = root / "results";
    fs::create_directories(results);
    std::ofstream(results / "data.csv") << "1\n";
    EXPECT_EQ(readFileText((results / "data.csv").string()), "1\n");
    {
        OutputFolder out(results.string(), OutputFolder::Mode::AddFiles);
        out.write("data.csv", "estimates\n");
        EXPECT_THROW(out.commit(), InputError);
    }
    EXPECT_EQ(readAll(results / "data.csv"), "1\n");
    EXPECT_EQ(countEntries(root), 2);   // run/ and results/: nothing staged or moved aside left
}

// Issue 34 (ninth sweep): a second result of the same kind in a folder leaves none of the first's files
// beside it (a design without validation used to keep the earlier design_validation.csv, linked from
// the page); a user's own files stay; an earlier result's file that this command read is not deleted.
TEST_F(OutputFolderTest, AnEarlierResultsFilesTheNewOneDoesNotHoldAreRemovedWithTheCommit) {
    const fs::path target = root / "design";
    fs::create_directories(target);
    std::ofstream(target / "notes.txt") << "keep";
    std::ofstream(target / "validation.csv") << "earlier";
    std::ofstream(target / "design.csv") << "earlier";
    {
        OutputFolder out(target.string(), OutputFolder::Mode::AddFiles);
        out.setResultFileNames({"design.csv", "validation.csv"});
        out.write("design.csv", "new");
        EXPECT_TRUE(fs::exists(target / "validation.csv"));   // nothing moves before the commit
        out.commit();
    }
    EXPECT_EQ(readFileText((target / "design.csv").string()), "new");
    EXPECT_FALSE(fs::exists(target / "validation.csv"));
    EXPECT_EQ(readFileText((target / "notes.txt").string()), "keep");
    EXPECT_EQ(countEntries(target), 2);   // no staging or moved-aside folder left inside
    std::ofstream(target / "validation.csv") << "read";
    setInputProtection(true);
    noteInputFile((target / "validation.csv").string());
    {
        OutputFolder out(target.string(), OutputFolder::Mode::AddFiles);
        out.setResultFileNames({"design.csv", "validation.csv"});
        out.write("design.csv", "newer");
        EXPECT_THROW(out.commit(), InputError);
    }
    setInputProtection(false);
    EXPECT_EQ(readFileText((target / "validation.csv").string()), "read");
    EXPECT_EQ(readFileText((target / "design.csv").string()), "new");
}

// A link to a run folder is written through: the run replaces the folder it points to, and the link
// stays a link (before, the link became a folder and the earlier run stayed where it pointed).
TEST_F(OutputFolderTest, ALinkToARunFolderIsWrittenThrough) {
    const fs::path real = root / "real", link = root / "link";
    {
        OutputFolder out(real.string(), OutputFolder::Mode::ReplaceRun, "manifest.json");
        out.write("old_only.csv", "x");
        out.write("manifest.json", kManifest);
        out.commit();
    }
    fs::create_directory_symlink(real, link);
    {
        OutputFolder out(link.string(), OutputFolder::Mode::ReplaceRun, "manifest.json");
        out.write("new.csv", "y");
        out.write("manifest.json", kManifest);
        out.commit();
    }
    EXPECT_TRUE(fs::is_symlink(link));
    EXPECT_FALSE(fs::exists(real / "old_only.csv"));
    EXPECT_EQ(readFileText((link / "new.csv").string()), "y");
}
