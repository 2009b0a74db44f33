// Text and live-plot overlays drawn with OpenCV onto rendered frames. Generic: the caller supplies
// the strings (already formatted, with units) and the traces.
#pragma once

#include "muscles/simbody.h"

#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace armsim {

/// One line of the text panel, printed as "label  value", e.g. {"elbow angle", "92.4 deg"}.
struct OverlayText {
    std::string label;
    std::string value;
};

/// A time series drawn as a small plot: the samples so far as a polyline with a dot at the last one.
/// Samples outside the axis ranges are clipped to the plot area.
struct PlotTrace {
    std::string title;                         ///< shown above the plot, e.g. "biceps force (N)"
    std::vector<SimTK::Vec2> samples;          ///< (t, y) pairs up to the current time (s, units of y)
    SimTK::Vec2 tRange{0, 1};                  ///< horizontal axis [start, end] (s), end > start
    SimTK::Vec2 yRange{0, 1};                  ///< vertical axis [bottom, top] (units of y), top > bottom
    SimTK::Vec3 color{0.85, 0.25, 0.1};        ///< trace colour, RGB each in [0, 1]
};

/// Placement and look of the overlay. The text panel sits in the top-left corner; plots are stacked
/// in the top-right corner, each with a data area of plotWidth x plotHeight.
struct OverlayStyle {
    double fontScale = 0.55;                   ///< OpenCV Hershey-simplex scale (1: ~22 px capitals), in (0, 4]
    int margin = 12;                           ///< gap between panels and the frame edge (px), in [0, 400]
    int plotWidth = 300;                       ///< width of each plot's data area (px), in [40, 2000]
    int plotHeight = 110;                      ///< height of each plot's data area (px), in [30, 2000]
    SimTK::Vec3 textColor{0.08, 0.08, 0.08};   ///< text and axes, RGB each in [0, 1]
    SimTK::Vec3 panelColor{1, 1, 1};           ///< panel background, RGB each in [0, 1]
    double panelOpacity = 0.75;                ///< panel background opacity (-), in [0, 1]

    /// Throws FieldError naming the field ("overlay.font_scale", ...), value and bound.
    void validate() const;
};

/// The data areas (pixel rectangles) where drawOverlay puts numPlots plots on a frame of frameSize.
std::vector<cv::Rect> calcPlotAreas(cv::Size frameSize, int numPlots, const OverlayStyle& style = {});

/// Draws the text panel (skipped when text is empty) and the plots onto frame (CV_8UC3, BGR).
/// Throws InputError for a frame of another type or a trace with an empty or reversed range.
void drawOverlay(cv::Mat& frame, const std::vector<OverlayText>& text, const std::vector<PlotTrace>& plots,
                 const OverlayStyle& style = {});

}  // namespace armsim
