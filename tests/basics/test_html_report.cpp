// The folder report (index.html): every file of the folder shown or linked by its relative path, names
// escaped, small tables shown whole and large ones in part, the facts and sentences as given, and a
// rewrite that replaces the page atomically. (A real browser opens it: report.MainJobReportOpensInChromium.)
#include "basics/html_report.h"

#include "tests/support/temp_files.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

using namespace armsim;
using armsim::testing::readFileText;
namespace fs = std::filesystem;

TEST(HtmlReport, ShowsEveryFileOfTheFolderByItsRelativePath) {
    const fs::path d = fs::path(::testing::TempDir()) / "armsim_html_report";
    fs::remove_all(d);
    fs::create_directories(d / "sub dir");
    std::ofstream(d / "plot.png") << "png";
    std::ofstream(d / "sub dir" / "v<1>.mp4") << "mp4";
    std::ofstream(d / "small.csv") << "# comment\na,b\n1,2.123456789\n";
    {
        std::ofstream big(d / "big.csv");
        big << "x\n";
        for (int i = 0; i < 100; ++i) big << i << "\n";
    }
    std::ofstream(d / "notes.json") << "{}";
    std::ofstream(d / ".hidden") << "x";
    FolderReport r;
    r.title = "armsim test & <check>";
    r.facts = {{"command", "armsim x --out 'a b'"}};
    r.describe = [](const std::string& rel) { return rel == "plot.png" ? std::string("a plot of <things>") : std::string(); };
    writeFolderReport(d.string(), r);
    const std::string html = readFileText(d / "index.html");
    EXPECT_NE(html.find("<title>armsim test &amp; &lt;check&gt;</title>"), std::string::npos);
    EXPECT_NE(html.find("<code>armsim x --out 'a b'</code>"), std::string::npos);   // quotes need no escape in text
    EXPECT_NE(html.find("<img src=\"plot.png\""), std::string::npos);
    EXPECT_NE(html.find("a plot of &lt;things&gt;"), std::string::npos);
    EXPECT_NE(html.find("<video controls muted preload=\"metadata\" src=\"sub%20dir/v%3C1%3E.mp4\""), std::string::npos);
    EXPECT_NE(html.find("<h2>sub dir/</h2>"), std::string::npos);
    EXPECT_NE(html.find("<td>2.123</td>"), std::string::npos);          // numbers to 4 digits
    EXPECT_EQ(html.find("comment"), std::string::npos);                // comment lines are not rows
    EXPECT_NE(html.find("(first 12 of 100 rows)"), std::string::npos);
    EXPECT_NE(html.find("href=\"notes.json\""), std::string::npos);
    EXPECT_EQ(html.find(".hidden"), std::string::npos);
    EXPECT_EQ(html.find("http"), std::string::npos);                   // nothing from the network
    // Written again, it replaces itself and does not list itself.
    writeFolderReport(d.string(), r);
    EXPECT_EQ(readFileText(d / "index.html").find("index.html"), std::string::npos);
    EXPECT_TRUE(isFolderReport((d / "index.html").string()));
    // Someone else's index.html is left as it is.
    std::ofstream(d / "index.html") << "<html>mine</html>";
    EXPECT_THROW(writeFolderReport(d.string(), r), std::runtime_error);
    EXPECT_EQ(readFileText(d / "index.html"), "<html>mine</html>");
    fs::remove_all(d);
}

// A folder of many files (a protocol of 5,000 trials writes 10,000): the page shows the first ones by
// name, says how many more there are and links the folder; the run keeps its exit 0.
TEST(HtmlReport, AFolderOfManyFilesShowsTheFirstAndCountsTheRest) {
    const fs::path d = fs::path(::testing::TempDir()) / "armsim_html_many";
    fs::remove_all(d);
    fs::create_directories(d / "trials");
    const long n = kMaxReportFilesPerFolder + 37;
    for (long i = 0; i < n; ++i) {
        char name[32];
        std::snprintf(name, sizeof name, "t%05ld.sto", i);
        std::ofstream(d / "trials" / name) << "x";
    }
    writeFolderReport(d.string(), FolderReport{});
    const std::string html = readFileText(d / "index.html");
    EXPECT_NE(html.find("href=\"trials/t00000.sto\""), std::string::npos);
    char last[32], first[32];
    std::snprintf(last, sizeof last, "t%05ld.sto", kMaxReportFilesPerFolder - 1);
    std::snprintf(first, sizeof first, "t%05ld.sto", kMaxReportFilesPerFolder);
    EXPECT_NE(html.find(last), std::string::npos);     // the last shown
    EXPECT_EQ(html.find(first), std::string::npos);    // the first not shown
    EXPECT_NE(html.find("and 37 more files in <a href=\"trials\">trials/</a>"), std::string::npos);
    fs::remove_all(d);
}
