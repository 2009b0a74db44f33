#include "basics/plot.h"

#include "basics/errors.h"

#include <fmt/format.h>

#include <plplot/plplot.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <unistd.h>

namespace armsim {

namespace {

std::mutex plplotMutex;  // PLplot keeps global state

// Palette (colour map 0): 0 background, 1 axes/text, then the series colours.
constexpr int kPalette[][3] = {{255, 255, 255}, {0, 0, 0},     {31, 119, 180}, {214, 39, 40},
                               {44, 160, 44},   {255, 127, 14}, {148, 103, 189}, {127, 127, 127},
                               {23, 190, 207},  {0, 0, 0}};

void dataRange(const std::vector<double>& v, bool log, double& lo, double& hi) {
    for (double a : v)
        if (std::isfinite(a) && (!log || a > 0)) {
            const double b = log ? std::log10(a) : a;
            lo = std::min(lo, b);
            hi = std::max(hi, b);
        }
}

/// Temporary PNG path beside `path`, created empty (PLplot exits the process on a file it cannot open,
/// so writability is checked here first).
std::string beginPng(const std::string& path) {
    namespace fs = std::filesystem;
    const fs::path target(path);
    std::error_code ec;
    if (target.has_parent_path()) fs::create_directories(target.parent_path(), ec);
    const std::string tmp = path + ".tmp." + std::to_string(::getpid()) + ".png";
    if (!std::ofstream(tmp)) throw InputError(path + ": cannot write plot (is the directory writable?)");
    return tmp;
}

/// Renames the finished temporary PNG into place, or removes it and throws.
void finishPng(const std::string& tmp, const std::string& path) {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (!fs::exists(tmp, ec) || fs::file_size(tmp, ec) == 0) {
        fs::remove(tmp, ec);
        throw InputError(path + ": the plot could not be written (PLplot pngcairo driver failed)");
    }
    if (!isWholePng(tmp)) {  // cairo does not report a failed write: a full disk leaves a cut-off file
        fs::remove(tmp, ec);
        throw InputError(path + ": the plot was cut off while being written (is the disk full?); no file written");
    }
    fs::rename(tmp, path, ec);
    if (ec) {
        fs::remove(tmp, ec);
        throw InputError(path + ": cannot write plot: " + ec.message());
    }
}

/// A PLplot stream's report of a refused call. PLplot reports a bad argument by skipping the call and
/// printing to stderr; with this buffer set on the stream (plsError) it keeps the message instead, and
/// the plot fails with it rather than being written blank beside lines of PLplot's own.
struct PlplotErrors {
    PLINT code = 0;
    char message[2048] = {};
    /// Throws, naming the plot, when a call was refused; removes tmp.
    void throwIfAny(const std::string& tmp, const std::string& path, const std::string& title) const {
        if (code == 0) return;
        std::error_code ec;
        std::filesystem::remove(tmp, ec);
        std::string text(message);
        text.erase(0, text.find_first_not_of("\n *"));
        std::replace(text.begin(), text.end(), '\n', ' ');
        throw std::logic_error(path + ": plot '" + title + "' not written: PLplot refused a call: " + text);
    }
};

/// Starts a PLplot stream on the pngcairo device writing tmp, with the series palette; refused calls
/// are kept in errors.
void startStream(const std::string& tmp, int width, int height, PlplotErrors& errors) {
    PLINT stream = 0;
    plmkstrm(&stream);
    plsError(&errors.code, errors.message);
    plsdev("pngcairo");
    plsfnam(tmp.c_str());
    plspage(0, 0, width, height, 0, 0);
    for (int i = 0; i < 10; ++i) plscol0(i, kPalette[i][0], kPalette[i][1], kPalette[i][2]);
}

// Two series draw the same curve: the same kind and the same points, y within tol (a small part of the
// plot's y range: closer curves cannot be told apart at any resolution).
bool isSameCurve(const PlotSeries& a, const PlotSeries& b, double tol) {
    if (a.markers != b.markers || a.x.size() != b.x.size() || a.y.size() != b.y.size() || a.x.empty()) return false;
    for (std::size_t i = 0; i < a.x.size(); ++i) {
        if (a.x[i] != b.x[i]) return false;
        const bool fa = std::isfinite(a.y[i]), fb = std::isfinite(b.y[i]);
        if (fa != fb || (fa && std::abs(a.y[i] - b.y[i]) > tol)) return false;
    }
    return true;
}

}  // namespace

bool isWholePng(const std::string& path) {
    std::ifstream in(path, std::ios::binary | std::ios::ate);
    const std::streamoff size = in ? std::streamoff(in.tellg()) : 0;
    if (size < 8 + 12) return false;
    char head[8], tail[12];
    in.seekg(0);
    in.read(head, 8);
    in.seekg(size - 12);
    in.read(tail, 12);
    static const char signature[8] = {'\x89', 'P', 'N', 'G', '\r', '\n', '\x1a', '\n'};
    static const char iend[12] = {0, 0, 0, 0, 'I', 'E', 'N', 'D', '\xae', '\x42', '\x60', '\x82'};
    return in && std::equal(head, head + 8, signature) && std::equal(tail, tail + 12, iend);
}

namespace {

// The axes' limits: the data's (padded 4 %) unless the spec fixes them; y in log10 with logY.
struct PlotLimits {
    double x0, x1, y0, y1;
    double dataY0, dataY1;   ///< the data's padded y range (for the identical-curve tolerance)
};

PlotLimits calcPlotLimits(const PlotSpec& spec) {
    double x0 = std::numeric_limits<double>::infinity(), x1 = -x0, y0 = x0, y1 = -x0;
    for (const auto& s : spec.series) {
        if (s.x.size() != s.y.size())
            throw std::invalid_argument("plot series '" + s.label + "': x and y differ in length");
        dataRange(s.x, false, x0, x1);
        dataRange(s.y, spec.logY, y0, y1);
    }
    if (!(x1 >= x0) || !(y1 >= y0)) throw std::invalid_argument("plot '" + spec.title + "': no finite data");
    auto pad = [](double& lo, double& hi) {
        const double span = hi > lo ? hi - lo : std::max(1.0, std::abs(lo));
        lo -= 0.04 * span;
        hi += 0.04 * span;
    };
    pad(x0, x1);
    pad(y0, y1);
    const double dataX0 = x0, dataX1 = x1, dataY0 = y0, dataY1 = y1;
    auto limit = [](double given, double fallback, bool log) {
        return std::isnan(given) ? fallback : (log ? std::log10(given) : given);
    };
    x0 = limit(spec.xMin, x0, false);
    x1 = limit(spec.xMax, x1, false);
    y0 = limit(spec.yMin, y0, spec.logY);
    y1 = limit(spec.yMax, y1, spec.logY);
    // Fixed limits that leave an empty or inverted range (yMin = yMax = 0 from a caller scaling to an
    // all-zero curve; data wholly beyond a fixed limit) give way to the data's own range.
    if (!(x1 > x0)) x0 = dataX0, x1 = dataX1;
    if (!(y1 > y0)) y0 = dataY0, y1 = dataY1;
    return {x0, x1, y0, y1, dataY0, dataY1};
}

// How each curve is drawn. Identical curves hide each other: a series equal to an earlier one is dashed
// and its legend says which it equals; a colour used again by another curve (more curves than the
// palette has colours) changes the dashes.
struct CurveStyle {
    int sameAs = -1;         ///< the earlier series it repeats, or -1
    PLINT lineStyle = 1;     ///< PLplot's pllsty
    std::string label;       ///< the legend's text ("" = not in the legend)
};

std::vector<CurveStyle> calcCurveStyles(const PlotSpec& spec, double sameTol) {
    const std::size_t ns = spec.series.size();
    std::vector<CurveStyle> styles(ns);
    for (std::size_t i = 1; i < ns; ++i)
        for (std::size_t j = 0; j < i && styles[i].sameAs < 0; ++j)
            if (styles[j].sameAs < 0 && isSameCurve(spec.series[i], spec.series[j], sameTol)) styles[i].sameAs = int(j);
    std::vector<int> uses(8, 0);
    const PLINT reuseStyles[] = {1, 4, 5, 8};
    for (std::size_t i = 0; i < ns; ++i) {
        CurveStyle& c = styles[i];
        const PlotSeries& s = spec.series[i];
        c.label = s.label;
        if (!c.label.empty() && c.sameAs >= 0)
            c.label += " (= " + (spec.series[c.sameAs].label.empty() ? std::string("another") : spec.series[c.sameAs].label) + ")";
        if (c.sameAs >= 0) {
            c.lineStyle = 3;   // dashed over the curve it repeats
            continue;
        }
        if (s.markers) continue;
        const int colour = s.color % 8;
        c.lineStyle = reuseStyles[std::min(uses[colour], 3)];
        ++uses[colour];
    }
    return styles;
}

struct LegendEntry {
    bool marker;
    PLINT color, lineStyle;
    std::string text;
    const char* symbol;
};

// Hand-drawn (pllegend sizes its text with metrics the cairo driver does not use): a line or a marker and
// the text per entry, top down, in a viewport right of the axes (from plotRight to the page's edge).
void drawLegend(const std::vector<LegendEntry>& entries, double plotRight, PLFLT vy0, PLFLT vy1, double pageMm,
                double pageHeightMm, double charHeight, double legendScale) {
    plvpor(plotRight + 0.01, 0.995, vy0, vy1);
    plwind(0, 1, 0, 1);
    const double boxMm = (0.995 - plotRight - 0.01) * pageMm;
    const double rowMm = 1.9 * charHeight * std::max(0.75, legendScale);
    const double heightMm = (vy1 - vy0) * pageHeightMm;
    const double row = rowMm / heightMm, symbolEnd = 2.6 * charHeight / boxMm, textAt = 3.2 * charHeight / boxMm;
    plschr(0, 1.1 * legendScale);
    for (std::size_t i = 0; i < entries.size(); ++i) {
        const PLFLT y = 1.0 - (double(i) + 0.6) * row;
        if (y < 0) break;   // more entries than fit: the rest are left out
        const LegendEntry& e = entries[i];
        plcol0(e.color);
        plwidth(2.0);
        if (e.marker) {
            const PLFLT sx = 0.5 * symbolEnd, sy = y;
            plstring(1, &sx, &sy, e.symbol);
        } else {
            const PLFLT lx[2] = {0.2 * symbolEnd, symbolEnd}, ly[2] = {y, y};
            pllsty(e.lineStyle);
            plline(2, lx, ly);
            pllsty(1);
        }
        plcol0(1);
        plptex(textAt, y, 1.0, 0.0, 0.0, e.text.c_str());
    }
    plschr(0, 1.1);
}

}  // namespace

void writePlotPng(const std::string& path, const PlotSpec& spec) {
    if (spec.series.empty()) throw std::invalid_argument("plot '" + spec.title + "': no series");
    if (spec.width < 100 || spec.height < 100) throw std::invalid_argument("plot size below 100 pixels");
    const PlotLimits lim = calcPlotLimits(spec);
    const double x0 = lim.x0, x1 = lim.x1, y0 = lim.y0, y1 = lim.y1;

    const std::string tmp = beginPng(path);
    {
        std::lock_guard<std::mutex> lock(plplotMutex);
        PlplotErrors errors;
        startStream(tmp, spec.width, spec.height, errors);
        plinit();
        plcol0(1);
        plschr(0, 1.1);
        const std::size_t ns = spec.series.size();
        const std::vector<CurveStyle> styles = calcCurveStyles(spec, 1e-4 * (spec.logY ? 0.0 : (lim.dataY1 - lim.dataY0)));
        std::size_t longest = 0;
        for (const CurveStyle& c : styles) longest = std::max(longest, c.label.size());
        // The legend stands right of the data, outside the axes: the viewport (plenv's standard one) is
        // narrowed by the legend's width, estimated from its longest text (drawn smaller if it is long).
        pladv(0);
        plvsta();
        PLFLT vx0, vx1, vy0, vy1, defaultHeight, charHeight, px0, px1, py0, py1;
        plgvpd(&vx0, &vx1, &vy0, &vy1);
        plgchr(&defaultHeight, &charHeight);   // mm
        plgspa(&px0, &px1, &py0, &py1);         // mm
        const double pageMm = px1 - px0;
        constexpr double kCharWidth = 0.70;     // glyph advance / character height (cairo's sans font, measured)
        double legendScale = 1.0, legendMm = 0.0;
        if (longest > 0) {
            const double maxMm = 0.38 * pageMm;
            legendScale = std::min(1.0, std::max(0.55, (maxMm / charHeight - 4.0) / (kCharWidth * double(longest))));
            legendMm = charHeight * (4.0 + legendScale * kCharWidth * double(longest));
        }
        // The axes keep at least 30 % of the page: a longer label runs past the page's edge instead.
        const double plotRight = longest > 0 ? std::min(vx1, std::max(vx0 + 0.3, 0.985 - legendMm / pageMm)) : vx1;
        plvpor(vx0, plotRight, vy0, vy1);
        plwind(x0, x1, y0, y1);
        plcol0(1);
        plbox("bcgnst", 0, 0, spec.logY ? "bcgnstlv" : "bcgnstv", 0, 0);
        plvpor(vx0, vx1, vy0, vy1);   // title and x label centred on the page, not on the narrowed axes
        plwind(x0, x1, y0, y1);
        plmtex("t", 2.0, 0.5, 0.5, spec.title.c_str());
        plmtex("b", 3.2, 0.5, 0.5, spec.xLabel.c_str());
        plvpor(vx0, plotRight, vy0, vy1);
        plwind(x0, x1, y0, y1);
        plmtex("l", 5.0, 0.5, 0.5, spec.yLabel.c_str());

        std::vector<LegendEntry> legend;
        for (std::size_t i = 0; i < ns; ++i) {
            const PlotSeries& s = spec.series[i];
            const int color = 2 + (s.color % 8);
            const PLINT style = styles[i].lineStyle;
            const char* symbol = styles[i].sameAs >= 0 ? "#(727)" : "#(728)";   // open circle for a repeat
            std::vector<PLFLT> xs, ys;
            for (std::size_t k = 0; k < s.x.size(); ++k)
                if (std::isfinite(s.x[k]) && std::isfinite(s.y[k]) && (!spec.logY || s.y[k] > 0)) {
                    xs.push_back(s.x[k]);
                    ys.push_back(spec.logY ? std::log10(s.y[k]) : s.y[k]);
                }
            plcol0(color);
            plwidth(2.0);
            pllsty(style);
            if (s.markers) plstring(PLINT(xs.size()), xs.data(), ys.data(), symbol);
            else if (xs.size() > 1) plline(PLINT(xs.size()), xs.data(), ys.data());
            pllsty(1);
            if (!styles[i].label.empty()) legend.push_back({s.markers, color, style, styles[i].label, symbol});
        }
        if (!legend.empty()) drawLegend(legend, plotRight, vy0, vy1, pageMm, py1 - py0, charHeight, legendScale);
        plend1();
        errors.throwIfAny(tmp, path, spec.title);
    }
    finishPng(tmp, path);
}

void writeHeatMapPng(const std::string& path, const HeatMapSpec& spec) {
    const std::size_t nx = spec.x.size(), ny = spec.y.size();
    if (nx == 0 || ny == 0 || spec.z.size() != nx * ny)
        throw std::invalid_argument("heat map '" + spec.title + "': need nx, ny >= 1 and nx * ny values");
    if (spec.width < 100 || spec.height < 100) throw std::invalid_argument("plot size below 100 pixels");
    if ((!spec.xNames.empty() && spec.xNames.size() != nx) || (!spec.yNames.empty() && spec.yNames.size() != ny))
        throw std::invalid_argument("heat map '" + spec.title + "': need one name per column and row (or none)");
    auto spacing = [&](const std::vector<double>& v, const char* axis) {
        const double d = v.size() > 1 ? (v.back() - v.front()) / double(v.size() - 1) : 1.0;
        for (std::size_t i = 1; i < v.size(); ++i)
            if (!(std::abs(v[i] - v[i - 1] - d) <= 1e-9 * std::max(1.0, std::abs(d))) || !(d > 0))
                throw std::invalid_argument(std::string("heat map: ") + axis + " centres must be increasing and evenly spaced");
        return d;
    };
    const double dx = spacing(spec.x, "x"), dy = spacing(spec.y, "y");
    double zmin = std::numeric_limits<double>::infinity(), zmax = -zmin;
    for (double v : spec.z)
        if (std::isfinite(v)) {
            zmin = std::min(zmin, v);
            zmax = std::max(zmax, v);
        }
    if (!(zmax >= zmin)) throw std::invalid_argument("heat map '" + spec.title + "': no finite data");
    if (zmax == zmin) zmax = zmin + 1;
    const double x0 = spec.x.front() - dx / 2, x1 = spec.x.back() + dx / 2;
    const double y0 = spec.y.front() - dy / 2, y1 = spec.y.back() + dy / 2;

    // plimagefr maps idata[0][0] and idata[nx-1][ny-1] to the corners (xmin, ymin), (xmax, ymax) and
    // colours the (nx-1) x (ny-1) quads between points by their lower-left point: cell (i, j) is point
    // [i][j] of an (nx+1) x (ny+1) image whose last row and column repeat (and are never seen).
    // Blank (NaN) cells get a value outside [zmin, zmax], which plimagefr skips.
    std::vector<std::vector<PLFLT>> rows(nx + 1, std::vector<PLFLT>(ny + 1));
    std::vector<PLFLT*> image(nx + 1);
    for (std::size_t i = 0; i <= nx; ++i) {
        for (std::size_t j = 0; j <= ny; ++j) {
            const double v = spec.z[std::min(i, nx - 1) * ny + std::min(j, ny - 1)];
            rows[i][j] = std::isfinite(v) ? v : zmax + 10 * (zmax - zmin);
        }
        image[i] = rows[i].data();
    }

    const std::string tmp = beginPng(path);
    {
        std::lock_guard<std::mutex> lock(plplotMutex);
        PlplotErrors errors;
        startStream(tmp, spec.width, spec.height, errors);
        // Colour map 1: dark blue -> teal -> yellow (viridis-like), linear in RGB.
        PLFLT pos[] = {0.0, 0.5, 1.0}, r[] = {0.27, 0.13, 0.99}, g[] = {0.00, 0.57, 0.91}, b[] = {0.33, 0.55, 0.14};
        plscmap1n(256);
        plscmap1l(1, 3, pos, r, g, b, nullptr);
        plinit();
        plcol0(1);
        plschr(0, 1.1);
        pladv(0);
        // Names need room: the left margin grows with the longest row name (about 14.5 px a character).
        std::size_t longest = 0;
        for (const std::string& name : spec.yNames) longest = std::max(longest, name.size());
        const double left = spec.yNames.empty() ? 0.12 : std::min(0.45, 0.05 + 0.0145 * double(longest) * 1000.0 / spec.width);
        plvpor(left, 0.80, 0.12, 0.90);
        plwind(x0, x1, y0, y1);
        plimagefr(image.data(), PLINT(nx + 1), PLINT(ny + 1), x0, x1, y0, y1, zmin, zmax, zmin, zmax, nullptr, nullptr);
        plcol0(1);
        plbox(spec.xNames.empty() ? "bcnst" : "bc", 0, 0, spec.yNames.empty() ? "bcnstv" : "bc", 0, 0);
        pllab(spec.xLabel.c_str(), spec.yLabel.c_str(), spec.title.c_str());
        for (std::size_t i = 0; i < spec.xNames.size(); ++i)
            plmtex("b", 1.5, (spec.x[i] - x0) / (x1 - x0), 0.5, spec.xNames[i].c_str());
        for (std::size_t j = 0; j < spec.yNames.size(); ++j)
            plmtex("lv", 0.8, (spec.y[j] - y0) / (y1 - y0), 1.0, spec.yNames[j].c_str());
        if (spec.cellLabels) {
            plschr(0, 0.75);
            for (std::size_t i = 0; i < nx; ++i)
                for (std::size_t j = 0; j < ny; ++j) {
                    const double v = spec.z[i * ny + j];
                    if (!std::isfinite(v)) continue;
                    const std::string text = fmt::format("{:.{}f}", v, spec.labelDecimals);
                    plcol0((v - zmin) / (zmax - zmin) > 0.6 ? 9 : 0);  // black on light cells, white on dark
                    plptex(spec.x[i], spec.y[j], 1, 0, 0.5, text.c_str());
                }
            plschr(0, 1.1);
        }
        plcol0(1);
        PLFLT barWidth, barHeight;
        const char* axisOpts[] = {"bcvtm"};
        const char* labels[] = {spec.zLabel.c_str()};
        PLINT labelOpts[] = {PL_COLORBAR_LABEL_RIGHT};
        PLFLT ticks[] = {0.0};
        PLINT subTicks[] = {0};
        constexpr int kBarValues = 101;
        PLFLT values[kBarValues];
        for (int k = 0; k < kBarValues; ++k) values[k] = zmin + (zmax - zmin) * k / (kBarValues - 1);
        const PLFLT* valueRows[] = {values};
        PLINT nValues[] = {kBarValues};
        plcolorbar(&barWidth, &barHeight, PL_COLORBAR_IMAGE | PL_COLORBAR_LABEL_RIGHT,
                   PL_POSITION_RIGHT | PL_POSITION_OUTSIDE | PL_POSITION_VIEWPORT, 0.02, 0.0, 0.04, 1.0, 0, 1, 1,
                   0.0, 0.0, 0, 0.0, 1, labelOpts, labels, 1, axisOpts, ticks, subTicks, nValues, valueRows);
        plend1();
        errors.throwIfAny(tmp, path, spec.title);
    }
    finishPng(tmp, path);
}

}  // namespace armsim
