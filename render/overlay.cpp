#include "render/overlay.h"

#include "basics/bound.h"

#include <fmt/format.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace armsim {

namespace {

constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr int kPad = 8;                 // inner padding of panels (px)
constexpr int kShift = 4;               // fixed-point bits for sub-pixel trace drawing
constexpr double kTraceThickness = 2;   // (px)
constexpr int kLastSampleRadius = 3;    // (px)
constexpr double kTitleScale = 0.9;     // title and tick labels relative to fontScale

cv::Scalar toBgr(const SimTK::Vec3& rgb) {
    return cv::Scalar(255 * rgb[2], 255 * rgb[1], 255 * rgb[0]);
}

void checkColor(const std::string& field, const SimTK::Vec3& c) {
    for (int i = 0; i < 3; ++i)
        if (!(c[i] >= 0 && c[i] <= 1))
            throw FieldError(field, "= [" + std::to_string(c[0]) + ", " + std::to_string(c[1]) + ", " +
                                        std::to_string(c[2]) + "]: expected each of r, g, b in [0, 1]");
}

std::string formatTick(double v) { return fmt::format("{:.3g}", v); }

cv::Size textSize(const std::string& s, double scale, int* baseline = nullptr) {
    int b = 0;
    cv::Size sz = cv::getTextSize(s, kFont, scale, 1, &b);
    if (baseline) *baseline = b;
    return sz;
}

struct PlotPadding {
    int left, top, right, bottom;
};

PlotPadding calcPadding(const OverlayStyle& s) {
    const double small = kTitleScale * s.fontScale;
    const int h = textSize("Ag", small).height;
    return {textSize("-8.88e+88", small).width + 2 * kPad, h + 2 * kPad, kPad, h + 2 * kPad};
}

void blendPanel(cv::Mat& frame, const cv::Rect& rect, const OverlayStyle& s) {
    const cv::Rect r = rect & cv::Rect(0, 0, frame.cols, frame.rows);
    if (r.empty() || s.panelOpacity <= 0) return;
    cv::Mat roi = frame(r);
    const cv::Mat fill(roi.size(), roi.type(), toBgr(s.panelColor));
    cv::addWeighted(roi, 1 - s.panelOpacity, fill, s.panelOpacity, 0, roi);
}

// Liang-Barsky clipping of segment a-b to [xmin, xmax] x [ymin, ymax]; false if nothing is left.
bool clipSegment(cv::Point2d& a, cv::Point2d& b, double xmin, double xmax, double ymin, double ymax) {
    double t0 = 0, t1 = 1;
    const double dx = b.x - a.x, dy = b.y - a.y;
    const double p[4] = {-dx, dx, -dy, dy};
    const double q[4] = {a.x - xmin, xmax - a.x, a.y - ymin, ymax - a.y};
    for (int i = 0; i < 4; ++i) {
        if (p[i] == 0) {
            if (q[i] < 0) return false;
            continue;
        }
        const double t = q[i] / p[i];
        if (p[i] < 0) t0 = std::max(t0, t);
        else t1 = std::min(t1, t);
        if (t0 > t1) return false;
    }
    const cv::Point2d a0 = a;
    a = a0 + t0 * cv::Point2d(dx, dy);
    b = a0 + t1 * cv::Point2d(dx, dy);
    return true;
}

cv::Point toFixed(const cv::Point2d& p) {
    return {int(std::lround(p.x * (1 << kShift))), int(std::lround(p.y * (1 << kShift)))};
}

void checkTrace(const PlotTrace& t) {
    auto bad = [&](const char* what, const SimTK::Vec2& r, const char* unit) {
        throw InputError("plot '" + t.title + "': " + what + " = [" + std::to_string(r[0]) + ", " +
                         std::to_string(r[1]) + "]: expected finite numbers with end > start (" + unit + ")");
    };
    if (!(std::isfinite(t.tRange[0]) && std::isfinite(t.tRange[1]) && t.tRange[1] > t.tRange[0]))
        bad("tRange", t.tRange, "s");
    if (!(std::isfinite(t.yRange[0]) && std::isfinite(t.yRange[1]) && t.yRange[1] > t.yRange[0]))
        bad("yRange", t.yRange, "units of y");
    checkColor("plot '" + t.title + "' color", t.color);
}

void drawPlot(cv::Mat& frame, const cv::Rect& area, const PlotTrace& trace, const OverlayStyle& s) {
    const PlotPadding pad = calcPadding(s);
    const cv::Rect panel(area.x - pad.left, area.y - pad.top, area.width + pad.left + pad.right,
                         area.height + pad.top + pad.bottom);
    blendPanel(frame, panel, s);
    const cv::Scalar ink = toBgr(s.textColor);
    const double small = kTitleScale * s.fontScale;
    const int lineType = cv::LINE_AA;

    // Title, axis box and range labels.
    cv::putText(frame, trace.title, {area.x, area.y - kPad}, kFont, small, ink, 1, lineType);
    cv::rectangle(frame, area, ink, 1, cv::LINE_8);
    const int h = textSize("Ag", small).height;
    auto rightAligned = [&](const std::string& str, int xRight, int yBase) {
        cv::putText(frame, str, {xRight - textSize(str, small).width, yBase}, kFont, small, ink, 1, lineType);
    };
    rightAligned(formatTick(trace.yRange[1]), area.x - kPad / 2, area.y + h);
    rightAligned(formatTick(trace.yRange[0]), area.x - kPad / 2, area.br().y);
    cv::putText(frame, formatTick(trace.tRange[0]), {area.x, area.br().y + h + kPad / 2}, kFont, small, ink,
                1, lineType);
    rightAligned(formatTick(trace.tRange[1]) + " s", area.br().x, area.br().y + h + kPad / 2);

    // The trace, drawn into the area's sub-image so nothing spills outside it.
    const cv::Rect visible = area & cv::Rect(0, 0, frame.cols, frame.rows);
    if (visible.empty()) return;
    cv::Mat roi = frame(visible);
    const cv::Point2d origin(area.x - visible.x, area.y - visible.y);
    const double w = area.width - 1, hh = area.height - 1;
    auto map = [&](const SimTK::Vec2& sample) {
        return cv::Point2d(origin.x + (sample[0] - trace.tRange[0]) / (trace.tRange[1] - trace.tRange[0]) * w,
                           origin.y + (trace.yRange[1] - sample[1]) / (trace.yRange[1] - trace.yRange[0]) * hh);
    };
    if (trace.yRange[0] < 0 && trace.yRange[1] > 0) {
        const cv::Point2d z0 = map({trace.tRange[0], 0}), z1 = map({trace.tRange[1], 0});
        cv::line(roi, toFixed(z0), toFixed(z1), cv::Scalar(170, 170, 170), 1, lineType, kShift);
    }
    const cv::Scalar color = toBgr(trace.color);
    const double lo = -1.0, xhi = roi.cols, yhi = roi.rows;  // clip window (ROI clips the rest)
    const SimTK::Vec2* prev = nullptr;
    for (const SimTK::Vec2& sample : trace.samples) {
        if (!(std::isfinite(sample[0]) && std::isfinite(sample[1]))) {
            prev = nullptr;
            continue;
        }
        if (prev) {
            cv::Point2d a = map(*prev), b = map(sample);
            if (clipSegment(a, b, lo, xhi, lo, yhi))
                cv::line(roi, toFixed(a), toFixed(b), color, int(kTraceThickness), lineType, kShift);
        }
        prev = &sample;
    }
    if (prev) {
        const cv::Point2d last = map(*prev);
        if (last.x >= origin.x && last.x <= origin.x + w && last.y >= origin.y && last.y <= origin.y + hh)
            cv::circle(roi, toFixed(last), kLastSampleRadius << kShift, color, cv::FILLED, lineType, kShift);
    }
}

void drawTextPanel(cv::Mat& frame, const std::vector<OverlayText>& text, const OverlayStyle& s) {
    int baseline = 0;
    int labelWidth = 0, valueWidth = 0;
    const int lineHeight = int(std::lround(1.7 * textSize("Ag", s.fontScale, &baseline).height));
    for (const OverlayText& t : text) {
        labelWidth = std::max(labelWidth, textSize(t.label, s.fontScale).width);
        valueWidth = std::max(valueWidth, textSize(t.value, s.fontScale).width);
    }
    const int gap = textSize("  ", s.fontScale).width;
    const cv::Rect panel(s.margin, s.margin, labelWidth + gap + valueWidth + 2 * kPad,
                         int(text.size()) * lineHeight + 2 * kPad);
    blendPanel(frame, panel, s);
    const cv::Scalar ink = toBgr(s.textColor);
    for (size_t i = 0; i < text.size(); ++i) {
        const int y = panel.y + kPad + int(i + 1) * lineHeight - (lineHeight - baseline) / 3;
        cv::putText(frame, text[i].label, {panel.x + kPad, y}, kFont, s.fontScale, ink, 1, cv::LINE_AA);
        cv::putText(frame, text[i].value, {panel.x + kPad + labelWidth + gap, y}, kFont, s.fontScale, ink, 1,
                    cv::LINE_AA);
    }
}

}  // namespace

void OverlayStyle::validate() const {
    checkField("overlay.font_scale", fontScale, {0, 4, true, false, ""});
    checkField("overlay.margin", margin, Bound::closed(0, 400, "px"));
    checkField("overlay.plot_width", plotWidth, Bound::closed(40, 2000, "px"));
    checkField("overlay.plot_height", plotHeight, Bound::closed(30, 2000, "px"));
    checkColor("overlay.text_color", textColor);
    checkColor("overlay.panel_color", panelColor);
    checkField("overlay.panel_opacity", panelOpacity, Bound::closed(0, 1));
}

std::vector<cv::Rect> calcPlotAreas(cv::Size frameSize, int numPlots, const OverlayStyle& style) {
    const PlotPadding pad = calcPadding(style);
    const int panelHeight = style.plotHeight + pad.top + pad.bottom;
    std::vector<cv::Rect> areas;
    for (int i = 0; i < numPlots; ++i)
        areas.emplace_back(frameSize.width - style.margin - pad.right - style.plotWidth,
                           style.margin + i * (panelHeight + style.margin) + pad.top, style.plotWidth,
                           style.plotHeight);
    return areas;
}

void drawOverlay(cv::Mat& frame, const std::vector<OverlayText>& text, const std::vector<PlotTrace>& plots,
                 const OverlayStyle& style) {
    style.validate();
    if (frame.type() != CV_8UC3)
        throw InputError("overlay: frame has OpenCV type " + std::to_string(frame.type()) +
                         ": expected CV_8UC3 (BGR)");
    for (const PlotTrace& t : plots) checkTrace(t);
    if (!text.empty()) drawTextPanel(frame, text, style);
    const std::vector<cv::Rect> areas = calcPlotAreas(frame.size(), int(plots.size()), style);
    for (size_t i = 0; i < plots.size(); ++i) drawPlot(frame, areas[i], plots[i], style);
}

}  // namespace armsim
