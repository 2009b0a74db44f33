// PNG line plots of results (force-length curves, time courses, convergence) through PLplot's
// cairo driver. Framework-free apart from PLplot; safe to call from several threads (serialised).
#pragma once

#include <string>
#include <vector>

namespace armsim {

/// One curve of a plot.
struct PlotSeries {
    std::string label;           ///< legend text ("" = no legend entry)
    std::vector<double> x, y;    ///< data, same length
    bool markers = false;        ///< draw points instead of a line
    int color = 0;               ///< palette index 0..7 (blue, red, green, orange, purple, grey, cyan, black)
};

/// A 2-D line plot.
struct PlotSpec {
    std::string title;
    std::string xLabel, yLabel;  ///< axis labels with units, e.g. "path length (cm)"
    std::vector<PlotSeries> series;
    int width = 1000, height = 700;   ///< pixels
    bool logY = false;               ///< logarithmic y axis (convergence plots); y must be > 0
    enum class Legend { TopLeft, TopRight, BottomLeft, BottomRight } legend = Legend::TopLeft;
    /// Axis limits; NaN = from the data with a margin.
    double xMin = 0.0 / 0.0, xMax = 0.0 / 0.0, yMin = 0.0 / 0.0, yMax = 0.0 / 0.0;
};

/// Writes the plot as a PNG file, whole or not at all (temporary + rename). Throws InputError naming
/// the path if it cannot be written, std::invalid_argument for an empty or malformed spec.
void writePlotPng(const std::string& path, const PlotSpec& spec);

}  // namespace armsim
