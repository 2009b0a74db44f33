// Heat maps read back from their PNG: each cell is drawn in the colour of its own value.
#include "basics/plot.h"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <filesystem>
#include <stdexcept>

namespace fs = std::filesystem;
using namespace armsim;

namespace {

// The pixel (BGR) at the centre of cell (i, j) of a heat map drawn with writeHeatMapPng's viewport
// (x from `left` to 0.80 of the width, y from 0.12 to 0.90 of the height, from the bottom).
cv::Vec3b cellCentre(const cv::Mat& png, const HeatMapSpec& spec, std::size_t i, std::size_t j, double left) {
    const double fx = left + (0.80 - left) * (double(i) + 0.5) / double(spec.x.size());
    const double fy = 0.12 + 0.78 * (double(j) + 0.5) / double(spec.y.size());
    return png.at<cv::Vec3b>(int((1 - fy) * spec.height), int(fx * spec.width));
}

}  // namespace

// One hot cell in a 3 x 2 grid: only that cell is yellow (the colour map's top), every other cell dark
// blue (its bottom). PLplot's plimagefr colours quads between points, so a grid passed as points shifts
// and stretches the cells: the hot value then spreads over the wrong cells (tried: the whole first column).
TEST(PlotPixels, EveryHeatMapCellHasTheColourOfItsValue) {
    const fs::path dir = fs::temp_directory_path() / ("armsim_plot_pixels_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    for (const bool named : {false, true}) {
        for (std::size_t hot = 0; hot < 6; ++hot) {
            HeatMapSpec spec;
            spec.title = "one hot cell";
            spec.x = {0, 1, 2};
            spec.y = {10, 20};
            spec.z.assign(6, 0.0);
            spec.z[hot] = 1.0;
            spec.cellLabels = false;
            double left = 0.12;
            if (named) {
                spec.xNames = {"a", "b", "c"};
                spec.yNames = {"first row", "second"};
                left = 0.05 + 0.0145 * 9 * 1000.0 / spec.width;  // writeHeatMapPng's margin for 9 characters
            }
            const std::string path = (dir / "hot.png").string();
            writeHeatMapPng(path, spec);
            const cv::Mat png = cv::imread(path, cv::IMREAD_COLOR);
            ASSERT_FALSE(png.empty());
            for (std::size_t i = 0; i < 3; ++i)
                for (std::size_t j = 0; j < 2; ++j) {
                    const cv::Vec3b c = cellCentre(png, spec, i, j, left);  // B, G, R
                    const bool yellow = c[2] > 200 && c[1] > 180 && c[0] < 80;
                    const bool dark = c[2] < 110 && c[1] < 60;
                    if (i * 2 + j == hot)
                        EXPECT_TRUE(yellow) << "hot cell " << hot << " named " << named << ": " << c;
                    else
                        EXPECT_TRUE(dark) << "cell " << i << "," << j << " with hot " << hot << " named " << named << ": " << c;
                }
        }
    }
    HeatMapSpec bad;
    bad.x = {0, 1};
    bad.y = {0};
    bad.z = {1, 2};
    bad.xNames = {"only one"};
    EXPECT_THROW(writeHeatMapPng((dir / "bad.png").string(), bad), std::invalid_argument);
    fs::remove_all(dir);
}

namespace {

bool isBlue(const cv::Vec3b& c) { return c[0] > 140 && c[2] < 110; }            // B, G, R
bool isRed(const cv::Vec3b& c) { return c[2] > 150 && c[0] < 110 && c[1] < 110; }

// The columns of the longest run of `colour` pixels in any row: a horizontal data line.
std::pair<int, int> findLongestRun(const cv::Mat& png, bool (*colour)(const cv::Vec3b&)) {
    std::pair<int, int> best{0, -1};
    for (int r = 0; r < png.rows; ++r)
        for (int c = 0; c < png.cols;) {
            int e = c;
            while (e < png.cols && colour(png.at<cv::Vec3b>(r, e))) ++e;
            if (e - c > best.second - best.first) best = {c, e - 1};
            c = e + 1;
        }
    return best;
}

cv::Mat drawLines(const PlotSpec& spec, const std::string& path) {
    writePlotPng(path, spec);
    return cv::imread(path, cv::IMREAD_COLOR);
}

}  // namespace

// The legend stands right of the data: the legend's blue sample line lies right of the whole blue data
// line, which spans the x range (the legend used to sit inside a corner of the axes, over the data).
TEST(PlotPixels, TheLegendStandsRightOfTheData) {
    const fs::path dir = fs::temp_directory_path() / ("armsim_plot_legend_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    PlotSpec spec;
    spec.title = "legend outside";
    spec.series = {{"a level line with a long label", {0, 10}, {1, 1}, false, 0},
                   {"another", {0, 10}, {0, 0}, false, 1}};
    const cv::Mat png = drawLines(spec, (dir / "legend.png").string());
    ASSERT_FALSE(png.empty());
    const auto [first, last] = findLongestRun(png, isBlue);
    ASSERT_GT(last - first, spec.width / 3);   // the data line
    int legendBlue = 0;
    for (int r = 0; r < png.rows; ++r)
        for (int c = last + 5; c < png.cols; ++c) legendBlue += isBlue(png.at<cv::Vec3b>(r, c));
    EXPECT_GT(legendBlue, 10);   // the legend's sample, right of the data
    fs::remove_all(dir);
}

// Two series on the same points: the later one is dashed, so the earlier shows between its dashes (a
// solid line over it hid it: blue pixels on the line were under 5 % of red ones).
TEST(PlotPixels, IdenticalCurvesStayVisible) {
    const fs::path dir = fs::temp_directory_path() / ("armsim_plot_same_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    PlotSpec spec;
    spec.title = "two heads on one path";
    spec.series = {{"first", {0, 5, 10}, {0, 3, 1}, false, 0}, {"second", {0, 5, 10}, {0, 3, 1}, false, 1}};
    const cv::Mat png = drawLines(spec, (dir / "same.png").string());
    ASSERT_FALSE(png.empty());
    const int plotRight = int(0.55 * spec.width);   // the data; the legend is right of it
    int blue = 0, red = 0;
    for (int r = 0; r < png.rows; ++r)
        for (int c = 0; c < plotRight; ++c) {
            const cv::Vec3b p = png.at<cv::Vec3b>(r, c);
            blue += isBlue(p);
            red += isRed(p);
        }
    EXPECT_GT(red, 200);
    EXPECT_GT(blue, red / 5) << "blue " << blue << ", red " << red;
    fs::remove_all(dir);
}
