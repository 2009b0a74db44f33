#include "basics/errors.h"
#include "basics/plot.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

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
