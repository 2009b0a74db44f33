#include "basics/errors.h"
#include "basics/plot.h"

#include <gtest/gtest.h>

#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

using namespace armsim;
namespace fs = std::filesystem;

namespace {

/// Width and height from a PNG's IHDR chunk (0, 0 if not a PNG).
std::pair<int, int> pngSize(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    unsigned char h[24] = {};
    in.read(reinterpret_cast<char*>(h), 24);
    const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    if (!std::equal(sig, sig + 8, h)) return {0, 0};
    auto be32 = [&](int o) { return (h[o] << 24) | (h[o + 1] << 16) | (h[o + 2] << 8) | h[o + 3]; };
    return {be32(16), be32(20)};
}

}  // namespace

TEST(Plot, WritesAPngOfTheRequestedSize) {
    const fs::path p = fs::temp_directory_path() / ("armsim_plot_" + std::to_string(::getpid()) + ".png");
    PlotSpec spec;
    spec.title = "test";
    spec.xLabel = "x";
    spec.yLabel = "y";
    spec.width = 640;
    spec.height = 480;
    spec.series.push_back({"line", {0, 1, 2}, {0, 1, 4}});
    spec.series.push_back({"points", {0, 1, 2}, {1, 2, 3}, true, 1});
    writePlotPng(p.string(), spec);
    EXPECT_EQ(pngSize(p), std::make_pair(640, 480));
    fs::remove(p);
}

TEST(Plot, UnwritablePathOrEmptySpecFailsAndLeavesNoFile) {
    PlotSpec spec;
    spec.series.push_back({"line", {0, 1}, {0, 1}});
    EXPECT_THROW(writePlotPng("/proc/armsim/none.png", spec), std::exception);
    EXPECT_FALSE(fs::exists("/proc/armsim/none.png"));
    PlotSpec empty;
    EXPECT_THROW(writePlotPng("/tmp/armsim_empty.png", empty), std::invalid_argument);
    EXPECT_FALSE(fs::exists("/tmp/armsim_empty.png"));
}

TEST(Plot, ACutOffPngIsNotAWholePng) {
    const fs::path p = fs::temp_directory_path() / ("armsim_whole_" + std::to_string(::getpid()) + ".png");
    PlotSpec spec;
    spec.series.push_back({"line", {0, 1, 2}, {0, 1, 4}});
    writePlotPng(p.string(), spec);
    EXPECT_TRUE(isWholePng(p.string()));
    const auto size = fs::file_size(p);
    fs::resize_file(p, size / 2);
    EXPECT_FALSE(isWholePng(p.string()));
    fs::remove(p);
    EXPECT_FALSE(isWholePng(p.string()));  // no file
}

// A full disk, simulated by a file-size limit of 4 kB on a child process: the plot's write is cut off;
// the error names this plot and no file is left (the check of isWholePng, not PLplot, catches it).
TEST(Plot, AWriteCutOffByAFullDiskLeavesNoFileAndNamesThePlot) {
    const fs::path p = fs::temp_directory_path() / ("armsim_full_" + std::to_string(::getpid()) + ".png");
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
        std::signal(SIGXFSZ, SIG_IGN);  // writes past the limit fail with EFBIG, as on a full disk
        const rlimit limit{4096, 4096};
        setrlimit(RLIMIT_FSIZE, &limit);
        PlotSpec spec;
        spec.series.push_back({"line", {0, 1, 2}, {0, 1, 4}});
        int code = 1;
        try {
            writePlotPng(p.string(), spec);
            code = 2;  // no error: the cut-off file was taken for a plot
        } catch (const InputError& e) {
            const std::string what = e.what();
            code = what.find(p.string()) != std::string::npos && what.find("cut off") != std::string::npos ? 0 : 3;
        } catch (...) {
            code = 4;
        }
        _exit(code);
    }
    int status = 0;
    ASSERT_EQ(waitpid(child, &status, 0), child);
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 0) << "2: no error (a cut-off file left), 3: another message, 4: another error";
    EXPECT_FALSE(fs::exists(p));
    for (const auto& e : fs::directory_iterator(fs::temp_directory_path()))  // nor its temporary
        EXPECT_EQ(e.path().filename().string().find(p.filename().string() + ".tmp"), std::string::npos) << e.path();
}

// Fixed axis limits that leave an empty range (yMin = yMax = 0 from a caller scaling to an all-zero
// torque: the thesis model's extension MVC) made PLplot refuse the plot with lines on stderr and a blank
// PNG: the range falls back to the data's, the plot is whole and PLplot prints nothing.
TEST(Plot, FixedLimitsThatLeaveAnEmptyRangeGiveAWholePlotAndNoPlplotLines) {
    const fs::path p = fs::temp_directory_path() / ("armsim_plot_flat_" + std::to_string(::getpid()) + ".png");
    PlotSpec spec;
    spec.title = "flat";
    spec.yMin = 0;
    spec.yMax = 0;
    spec.series.push_back({"flat", {0, 1, 2}, {0, 0, 0}});
    testing::internal::CaptureStderr();
    EXPECT_NO_THROW(writePlotPng(p.string(), spec));
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
    EXPECT_TRUE(isWholePng(p.string()));
    fs::remove(p);
}
