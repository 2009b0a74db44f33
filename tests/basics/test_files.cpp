// Whole-file reads and the recorder that lets a result derived from files be reused (basics/files.h).
#include "basics/errors.h"
#include "basics/files.h"
#include "basics/param_node.h"
#include "tests/support/temp_files.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <memory>
#include <fstream>
#include <iterator>
#include <sys/stat.h>

using namespace armsim;

TEST(FileReadRecorder, NestedRecordersSeeTheReadsOfTheirLifetime) {
    const auto dir = armsim::testing::makeFreshDir("files", "recorder");
    const std::string a = (dir / "a.txt").string(), b = (dir / "b.txt").string();
    writeFileAtomically(a, "alpha");
    writeFileAtomically(b, "beta");
    readFileText(a);  // before any recorder: nobody sees it
    FileReadRecorder outer;
    EXPECT_EQ(readFileText(a), "alpha");
    std::vector<FileSnapshot> inner;
    {
        FileReadRecorder r;
        EXPECT_EQ(readFileText(b), "beta");
        inner = r.getFiles();
    }
    readFileText(a);  // after the inner one ended: the outer one only
    ASSERT_EQ(inner.size(), 1u);
    EXPECT_EQ(inner[0].path, b);
    EXPECT_EQ(inner[0].text, "beta");
    ASSERT_EQ(outer.getFiles().size(), 3u);
    EXPECT_EQ(outer.getFiles()[0].path, a);
    EXPECT_EQ(outer.getFiles()[1].path, b);
    EXPECT_EQ(outer.getFiles()[2].path, a);
    std::filesystem::remove_all(dir);
}

TEST(FileReadRecorder, SnapshotsGoStaleWhenAFileChangesOrGoes) {
    const auto dir = armsim::testing::makeFreshDir("files", "stale");
    const std::string a = (dir / "a.txt").string(), b = (dir / "b.txt").string();
    writeFileAtomically(a, "alpha");
    writeFileAtomically(b, "beta");
    std::vector<FileSnapshot> files;
    {
        FileReadRecorder r;
        readFileText(a);
        readFileText(b);
        files = r.releaseFiles();
        EXPECT_TRUE(r.getFiles().empty());
    }
    EXPECT_TRUE(areFilesUnchanged(files));
    writeFileAtomically(b, "betA");  // same size, one byte changed
    EXPECT_FALSE(areFilesUnchanged(files));
    writeFileAtomically(b, "beta");
    EXPECT_TRUE(areFilesUnchanged(files));
    std::filesystem::remove(a);
    EXPECT_FALSE(areFilesUnchanged(files));
    std::filesystem::remove_all(dir);
}

// Found by fuzzing the population and study loaders: a referenced file name longer than the system
// allows (ENAMETOOLONG) made std::filesystem::exists throw filesystem_error (an internal error).
TEST(Files, NamesThatCannotBeLookedUpDoNotExist) {
    const std::string tooLong = "/tmp/" + std::string(300, 'a') + "/b.yaml";
    EXPECT_FALSE(doesPathExist(tooLong));
    EXPECT_FALSE(isRegularFile(tooLong));
    EXPECT_TRUE(doesPathExist("/tmp"));
    EXPECT_FALSE(isRegularFile("/tmp"));
    try {
        ParamNode::loadString("model: " + tooLong + "\n", "p.yaml").findFile("model", "model file");
        ADD_FAILURE() << "no error";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("p.yaml:1"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("no such model file"), std::string::npos) << e.what();
    }
}

// A lookup is part of what a result depends on: a file that appears where one was looked for makes the
// snapshots stale; recorders ended out of order unlink themselves (no dangling chain).
TEST(FileReadRecorder, LookupsAreRecordedAndRecordersMayEndInAnyOrder) {
    const auto dir = armsim::testing::makeFreshDir("files", "lookups");
    const std::string absent = (dir / "later.yaml").string();
    std::vector<FileSnapshot> files;
    {
        FileReadRecorder r;
        EXPECT_FALSE(doesPathExist(absent));
        files = r.getFiles();
    }
    ASSERT_EQ(files.size(), 1u);
    EXPECT_FALSE(files[0].read);
    EXPECT_TRUE(areFilesUnchanged(files));
    writeFileAtomically(absent, "x");
    EXPECT_FALSE(areFilesUnchanged(files));

    auto outer = std::make_unique<FileReadRecorder>();
    auto inner = std::make_unique<FileReadRecorder>();
    outer.reset();  // the outer one ends first
    readFileText(absent);
    EXPECT_EQ(inner->getFiles().size(), 1u);
    inner.reset();
    readFileText(absent);  // no recorder left: nothing to write into
    std::filesystem::remove_all(dir);
}

TEST(Files, CreateFolderNamesThePathWhenItCannot) {
    const auto dir = armsim::testing::makeFreshDir("files", "folders");
    createFolder((dir / "a" / "b").string());
    EXPECT_TRUE(std::filesystem::is_directory(dir / "a" / "b"));
    createFolder((dir / "a").string());  // exists: nothing to do
    writeFileAtomically((dir / "f").string(), "x");
    for (const std::string& bad : {(dir / "f").string(), (dir / "f" / "sub").string(), (dir / std::string(300, 'n')).string()}) {
        try {
            createFolder(bad);
            ADD_FAILURE() << "no error for " << bad;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(bad + ": cannot create the folder"), std::string::npos) << e.what();
        }
    }
    std::filesystem::remove_all(dir);
}

// A path that is a symbolic link is written through: the link stays and its target gets the bytes; a
// link to something that is not a regular file (a pipe, as /dev/stdout often is) is refused with the
// path, and nothing is written.
TEST(Files, WritingALinkReplacesItsTargetAndKeepsTheLink) {
    namespace fs = std::filesystem;
    const fs::path d = armsim::testing::makeFreshDir("files", "link");
    std::ofstream(d / "target.csv") << "old\n";
    fs::create_symlink("target.csv", d / "link.csv");
    writeFileAtomically((d / "link.csv").string(), "new\n");
    EXPECT_TRUE(fs::is_symlink(d / "link.csv"));
    EXPECT_EQ(armsim::testing::readFileText(d / "target.csv"), "new\n");
    ASSERT_EQ(::mkfifo((d / "pipe").c_str(), 0600), 0);
    fs::create_symlink("pipe", d / "to_pipe.csv");
    const std::string message = armsim::testing::getInputErrorOf([&] { writeFileAtomically((d / "to_pipe.csv").string(), "x"); });
    EXPECT_NE(message.find("to_pipe.csv"), std::string::npos) << message;
    EXPECT_NE(message.find("not a regular file"), std::string::npos) << message;
    EXPECT_TRUE(fs::is_symlink(d / "to_pipe.csv"));
    fs::remove_all(d);
}

// With input protection on (the armsim command), a file a reader opened is never replaced by other
// bytes: the write is refused naming the file and the file keeps its bytes; the same bytes pass (a
// run that copies its input); with protection off nothing is checked.
TEST(Files, AnInputIsNotReplacedByOtherBytes) {
    namespace fs = std::filesystem;
    struct Protection {
        Protection() { setInputProtection(true); }
        ~Protection() { setInputProtection(false); }
    };
    const fs::path d = armsim::testing::makeFreshDir("files", "input");
    const std::string input = (d / "data.csv").string();
    std::ofstream(input) << "a,b\n1,2\n";
    {
        Protection on;
        EXPECT_EQ(readFileText(input), "a,b\n1,2\n");
        const std::string message = armsim::testing::getInputErrorOf([&] { writeFileAtomically(input, "results\n"); });
        EXPECT_NE(message.find("data.csv"), std::string::npos) << message;
        EXPECT_NE(message.find("read as input"), std::string::npos) << message;
        EXPECT_EQ(armsim::testing::readFileText(input), "a,b\n1,2\n");
        EXPECT_NO_THROW(writeFileAtomically(input, "a,b\n1,2\n"));   // the same bytes
        EXPECT_EQ(std::distance(fs::directory_iterator(d), fs::directory_iterator()), 1);   // no temporary left
    }
    EXPECT_NO_THROW(writeFileAtomically(input, "results\n"));   // protection off
    fs::remove_all(d);
}
