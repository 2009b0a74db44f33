// Tests of the OpenCV overlay: where text and plots land, where a trace is drawn, and clipping.
#include "basics/errors.h"
#include "render/overlay.h"
#include "tests/render/render_test_util.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

namespace armsim {
namespace {

using SimTK::Vec2;
using SimTK::Vec3;

constexpr int kTraceRowTolerancePx = 2;   // trace row vs mapped y (thickness 2 px, anti-aliased)
constexpr int kDominanceMargin = 80;      // (0-255)

const cv::Scalar kFill(90, 60, 30);       // a frame colour the overlay never uses

cv::Mat blankFrame() { return cv::Mat(480, 640, CV_8UC3, kFill); }

// Bounding box of pixels that differ between a and b.
cv::Rect changedRegion(const cv::Mat& a, const cv::Mat& b) {
    cv::Mat diff;
    cv::absdiff(a, b, diff);
    cv::Mat any;
    cv::transform(diff, any, cv::Matx13f(1, 1, 1));
    std::vector<cv::Point> pts;
    cv::findNonZero(any > 0, pts);
    return pts.empty() ? cv::Rect() : cv::boundingRect(pts);
}

bool isTraceBlue(const cv::Vec3b& p) { return test::dominates(p, 0, kDominanceMargin); }

TEST(Overlay, TextPanelSitsTopLeftAndPlotsTopRight) {
    const cv::Mat before = blankFrame();
    cv::Mat frame = before.clone();
    PlotTrace trace;
    trace.title = "force (N)";
    trace.samples = {Vec2(0, 0.2), Vec2(0.5, 0.8)};
    drawOverlay(frame, {{"time", "0.50 s"}, {"elbow angle", "92.4 deg"}}, {trace});

    const OverlayStyle style;
    const cv::Rect area = calcPlotAreas(frame.size(), 1, style)[0];
    cv::Mat textFrame = before.clone();
    drawOverlay(textFrame, {{"time", "0.50 s"}, {"elbow angle", "92.4 deg"}}, {});
    const cv::Rect text = changedRegion(before, textFrame);
    ASSERT_FALSE(text.empty());
    EXPECT_EQ(text.tl(), cv::Point(style.margin, style.margin));
    EXPECT_LT(text.br().x, frame.cols / 2);
    EXPECT_LT(text.br().y, frame.rows / 4);

    const cv::Rect all = changedRegion(before, frame);
    EXPECT_EQ(all.x, style.margin);
    EXPECT_EQ(all.y, style.margin);
    EXPECT_LE(all.br().x, frame.cols - style.margin);
    EXPECT_GE(area.x, frame.cols / 2);
    EXPECT_EQ(area.size(), cv::Size(style.plotWidth, style.plotHeight));
    // Nothing in the lower half of the frame.
    EXPECT_EQ(cv::norm(before.rowRange(frame.rows / 2, frame.rows), frame.rowRange(frame.rows / 2, frame.rows),
                       cv::NORM_INF), 0);
}

TEST(Overlay, TraceIsDrawnAtItsMappedHeight) {
    cv::Mat frame = blankFrame();
    PlotTrace trace;
    trace.color = Vec3(0, 0, 1);
    trace.tRange = Vec2(0, 2);
    trace.yRange = Vec2(-1, 3);
    trace.samples = {Vec2(0.2, 0), Vec2(1.0, 0), Vec2(1.6, 0)};   // flat at y = 0 up to t = 1.6
    drawOverlay(frame, {}, {trace});
    const cv::Rect area = calcPlotAreas(frame.size(), 1)[0];
    const int expectedRow = area.y + int(std::lround(0.75 * (area.height - 1)));   // y = 0 is 3/4 down
    const int tStart = area.x + int(0.1 * (area.width - 1)), tEnd = area.x + int(0.8 * (area.width - 1));
    for (int x = tStart + 2; x < tEnd - 2; x += 7) {
        int best = -1;
        for (int y = area.y; y < area.br().y; ++y)
            if (isTraceBlue(frame.at<cv::Vec3b>(y, x))) best = (best < 0 || std::abs(y - expectedRow) <
                                                                                std::abs(best - expectedRow))
                                                                   ? y
                                                                   : best;
        ASSERT_GE(best, 0) << "no trace at column " << x;
        EXPECT_LE(std::abs(best - expectedRow), kTraceRowTolerancePx) << "column " << x;
    }
    // No trace before the first sample, nor after the last sample's dot.
    for (int y = area.y; y < area.br().y; ++y) {
        EXPECT_FALSE(isTraceBlue(frame.at<cv::Vec3b>(y, tStart - 8)));
        EXPECT_FALSE(isTraceBlue(frame.at<cv::Vec3b>(y, tEnd + 8)));
    }
}

TEST(Overlay, OutOfRangeSamplesStayInsideThePlotArea) {
    PlotTrace inRange;
    inRange.samples = {Vec2(0.1, 0.5), Vec2(0.9, 0.5)};
    PlotTrace wild = inRange;
    wild.samples = {Vec2(-5, 1e9), Vec2(0.3, -1e12), Vec2(0.6, 0.5), Vec2(7, 1e300), Vec2(0.8, NAN)};
    cv::Mat a = blankFrame(), b = blankFrame();
    drawOverlay(a, {}, {inRange});
    drawOverlay(b, {}, {wild});
    const cv::Rect area = calcPlotAreas(a.size(), 1)[0];
    const cv::Rect changed = changedRegion(a, b);
    ASSERT_FALSE(changed.empty());
    EXPECT_EQ(changed & area, changed) << changed << " outside " << area;
}

TEST(Overlay, RejectsBadInput) {
    cv::Mat frame = blankFrame();
    PlotTrace t;
    t.title = "activation";
    t.yRange = Vec2(1, 1);
    try {
        drawOverlay(frame, {}, {t});
        ADD_FAILURE() << "empty y range accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("'activation'"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("yRange"), std::string::npos) << e.what();
    }
    cv::Mat gray(100, 100, CV_8UC1, cv::Scalar(0));
    EXPECT_THROW(drawOverlay(gray, {{"a", "b"}}, {}), InputError);
    OverlayStyle style;
    style.fontScale = 0;
    EXPECT_THROW(drawOverlay(frame, {{"a", "b"}}, {}, style), FieldError);
}

}  // namespace
}  // namespace armsim
