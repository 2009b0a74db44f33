// PNG line plots of results (force-length curves, time courses, convergence) and heat maps through
// PLplot's cairo driver. Framework-free apart from PLplot; safe to call from several threads (serialised).
#pragma once

#include "basics/numbers.h"

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

/// A 2-D line plot. The legend (the labelled series) stands right of the axes, outside the data; a series
/// that draws the same curve as an earlier one is dashed (open markers) and its label says which it equals.
struct PlotSpec {
    std::string title;
    std::string xLabel, yLabel;  ///< axis labels with units, e.g. "path length (cm)"
    std::vector<PlotSeries> series;
    int width = 1000, height = 700;   ///< pixels
    bool logY = false;               ///< logarithmic y axis (convergence plots); y must be > 0
    /// Axis limits; NaN = from the data with a margin.
    double xMin = kNaN, xMax = kNaN, yMin = kNaN, yMax = kNaN;
};

/// Writes the plot as a PNG file, whole or not at all (temporary + rename). Throws InputError naming
/// the path if it cannot be written, std::invalid_argument for an empty or malformed spec.
void writePlotPng(const std::string& path, const PlotSpec& spec);

/// true when the file is a PNG written to its end: the PNG signature first, the IEND chunk last. A
/// write cut off by a full disk fails it.
bool isWholePng(const std::string& path);

/// A heat map of z over a regular grid of cells (e.g. force over slow x fast motor-unit counts).
struct HeatMapSpec {
    std::string title;
    std::string xLabel, yLabel;   ///< axis labels with units
    std::string zLabel;           ///< colour-bar label with units, e.g. "force (N)"
    std::vector<double> x;        ///< cell centres along x: nx >= 1 values, increasing, evenly spaced
    std::vector<double> y;        ///< cell centres along y: ny >= 1 values, increasing, evenly spaced
    std::vector<double> z;        ///< nx * ny values, z[i * ny + j] at (x[i], y[j]); NaN = blank cell
    /// Names of the columns / rows (empty, or one per cell centre): drawn instead of the numbers.
    std::vector<std::string> xNames, yNames;
    bool cellLabels = true;       ///< print each cell's value in it
    int labelDecimals = 0;        ///< decimals of the cell labels
    int width = 1000, height = 800;   ///< pixels
};

/// Writes the heat map (colour map: dark blue -> yellow, with a colour bar) as a PNG file, whole or not
/// at all. Throws like writePlotPng.
void writeHeatMapPng(const std::string& path, const HeatMapSpec& spec);

}  // namespace armsim
