// The depth-resolution plot: log-log axes, decade grid, one curve per format, legend.
//
// Layout (pixels, 1200 x 800, font scale s = 2: glyphs 10 x 14, advance 12):
//   title                  y = 12
//   y-axis title           y = 42, above the plot area's left edge
//   plot area              [120, 900] x [70, 720]; tick labels left of it / below it
//   x-axis title           centered under the tick labels, y = 760
//   legend                 x = 920..1190, one 22-pixel row per format from y = 70
#include "reports/depth_plot.h"


#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>


#include "reports/font.h"
#include "reports/report.h"

namespace va {

namespace {

constexpr int kScale = 2;
constexpr Rgb8 kText{20, 20, 20};
constexpr Rgb8 kFrame{60, 60, 60};
constexpr Rgb8 kGrid{215, 215, 215};
constexpr Rgb8 kGapLine{150, 150, 150};
constexpr Rgb8 kGapText{110, 110, 110};

// "1CM", "1MM", "2.5CM", "1M": a gap in the unit that makes it a small number (upper case: the
// plot's titles are).
std::string gapText(double g) {
    char buf[32];
    if (g >= 1) std::snprintf(buf, sizeof buf, "%gM", g);
    else if (g >= 0.01) std::snprintf(buf, sizeof buf, "%gCM", g * 100);
    else std::snprintf(buf, sizeof buf, "%gMM", g * 1000);
    return buf;
}

// The same protocol as reports/images.cpp: write to PATH.tmp-PID-N, then rename over PATH (atomic
// within one folder), so a reader never sees half a PNG; the temporary file is removed on failure.

struct Canvas {
    int w, h;
    std::vector<uint8_t> rgb;
    Canvas(int w_, int h_, Rgb8 bg) : w(w_), h(h_), rgb(size_t(w_) * size_t(h_) * 3) {
        for (size_t i = 0; i < rgb.size(); i += 3) {
            rgb[i] = bg.r;
            rgb[i + 1] = bg.g;
            rgb[i + 2] = bg.b;
        }
    }
    void set(int x, int y, Rgb8 c) {
        if (x < 0 || y < 0 || x >= w || y >= h) return;
        uint8_t *p = &rgb[(size_t(y) * size_t(w) + size_t(x)) * 3];
        p[0] = c.r;
        p[1] = c.g;
        p[2] = c.b;
    }
    void rect(int x0, int y0, int x1, int y1, Rgb8 c) {  // inclusive
        for (int y = y0; y <= y1; ++y)
            for (int x = x0; x <= x1; ++x) set(x, y, c);
    }
    int text(int x, int y, const std::string &s, Rgb8 c) {
        return drawText(rgb.data(), w, h, x, y, s, {c.r, c.g, c.b}, kScale);
    }
};

// Bresenham's line from (x0,y0) to (x1,y1), each point stamped as a 3x3 square (a 3-pixel-wide
// curve), only inside the clip rectangle [cx0, cx1] x [cy0, cy1].
void thickLine(Canvas &c, int x0, int y0, int x1, int y1, Rgb8 col, int cx0, int cy0, int cx1, int cy1) {
    const int dx = std::abs(x1 - x0), dy = -std::abs(y1 - y0);
    const int sx = x0 < x1 ? 1 : -1, sy = y0 < y1 ? 1 : -1;
    int err = dx + dy;
    for (;;) {
        for (int oy = -1; oy <= 1; ++oy)
            for (int ox = -1; ox <= 1; ++ox) {
                const int x = x0 + ox, y = y0 + oy;
                if (x >= cx0 && x <= cx1 && y >= cy0 && y <= cy1) c.set(x, y, col);
            }
        if (x0 == x1 && y0 == y1) break;
        const int e2 = 2 * err;
        if (e2 >= dy) { err += dy; x0 += sx; }
        if (e2 <= dx) { err += dx; y0 += sy; }
    }
}

// A decade's tick label: plain decimals from 0.001 to 10000, "1E<k>" beyond (the font has no '^').
std::string decadeLabel(int k) {
    if (k >= -3 && k <= 4) {
        char buf[32];
        std::snprintf(buf, sizeof buf, "%.*f", k < 0 ? -k : 0, std::pow(10.0, k));
        return buf;
    }
    char buf[32];
    std::snprintf(buf, sizeof buf, "1E%d", k);
    return buf;
}

std::string shortNumber(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    return buf;
}

}  // namespace

Rgb8 depthPlotColor(DepthFormat format) {
    // Tableau's 10 categorical colors, then black and navy (the first twelve formats), then six
    // darker ones for the formats issue 19 added: all readable on white, pairwise distinct.
    static constexpr Rgb8 kPalette[kDepthFormatCount] = {
        {31, 119, 180}, {255, 127, 14}, {44, 160, 44},   {214, 39, 40},  {148, 103, 189}, {140, 86, 75},
        {227, 119, 194}, {127, 127, 127}, {188, 189, 34}, {23, 190, 207}, {0, 0, 0},       {0, 0, 150},
        {128, 0, 0},    {0, 100, 0},    {255, 0, 255},   {153, 102, 0},  {0, 128, 128},   {102, 0, 204},
    };
    return kPalette[int(format) % kDepthFormatCount];
}

Rgb8 depthPlotColor(const DepthFormatSpec &format) {
    if (format.format == DepthFormat::log24 && format.logC != kLogDepthC) return {90, 90, 0};  // log24:C=X
    return depthPlotColor(format.format);
}

int DepthPlotLayout::xOf(double d) const {
    const double t = (std::log10(d) - xLogMin) / (xLogMax - xLogMin);
    return int(std::lround(left + t * (right - left)));
}

int DepthPlotLayout::yOf(double r) const {
    const double t = (std::log10(r) - yDecadeMin) / double(yDecadeMax - yDecadeMin);
    return int(std::lround(bottom - t * (bottom - top)));
}

DepthPlotLayout depthPlotLayout(const DepthAuditResult &r) {
    DepthPlotLayout L;
    L.left = 120;
    L.right = 900;
    L.top = 70;
    L.bottom = 720;
    L.xLogMin = std::log10(r.nearZ);
    L.xLogMax = std::log10(r.farZ);
    // y: whole decades around every positive finite curve value.
    double lo = INFINITY, hi = -INFINITY;
    for (const DepthFormatAudit &a : r.formats)
        for (const std::optional<double> &v : a.curveResolution)
            if (v && std::isfinite(*v) && *v > 0) {
                lo = std::min(lo, *v);
                hi = std::max(hi, *v);
            }
    if (lo <= hi) {
        L.yDecadeMin = int(std::floor(std::log10(lo)));
        L.yDecadeMax = std::max(int(std::ceil(std::log10(hi))), L.yDecadeMin + 1);
    }
    return L;
}

bool writeDepthResolutionPlot(const DepthAuditResult &r, const std::string &path, std::string *err) {
    auto fail = [&](const std::string &m) {
        if (err) *err = "cannot write plot '" + path + "': " + m;
        return false;
    };
    if (!r.error.empty()) return fail("the audit failed: " + r.error);
    if (r.formats.empty()) return fail("the audit holds no formats; audit at least one");
    if (!(r.farZ > r.nearZ) || !(r.nearZ > 0)) return fail("near/far do not span a range; check --near and --far");
    bool anyValue = false;
    for (const DepthFormatAudit &a : r.formats)
        for (const std::optional<double> &v : a.curveResolution) anyValue |= v && std::isfinite(*v) && *v > 0;
    if (!anyValue) return fail("no format has a finite resolution inside [near, far] to plot");

    const DepthPlotLayout L = depthPlotLayout(r);
    Canvas c(L.width, L.height, kDepthPlotBackground);
    const int glyphH = textHeight(kScale);

    // Grid: x at every power of ten in [near, far], y at every decade.
    const int kx0 = int(std::floor(L.xLogMin)), kx1 = int(std::ceil(L.xLogMax));
    std::vector<int> xLabelled;
    for (int k = kx0; k <= kx1; ++k) {
        const double d = std::pow(10.0, k);
        if (!(d >= r.nearZ && d <= r.farZ)) continue;
        const int x = L.xOf(d);
        c.rect(x, L.top, x, L.bottom, kGrid);
        const std::string s = decadeLabel(k);
        const int w = textWidth(s, kScale);
        c.text(std::clamp(x - w / 2, 0, L.width - w), L.bottom + 10, s, kText);
        xLabelled.push_back(x);
    }
    // near and far themselves get a label when it does not run into a decade's.
    for (double d : {r.nearZ, r.farZ}) {
        const int x = L.xOf(d);
        const std::string s = shortNumber(d);
        const int w = textWidth(s, kScale);
        bool clear = true;
        for (int xl : xLabelled) clear &= std::abs(xl - x) > w + 16;  // also skips a labelled decade
        if (clear) c.text(std::clamp(x - w / 2, 0, L.width - w), L.bottom + 10, s, kText);
    }
    // Label every decade while they are at least two glyph heights apart, else every k-th one.
    const int decades = L.yDecadeMax - L.yDecadeMin;
    const int pxPerDecade = (L.bottom - L.top) / decades;
    const int every = std::max(1, (2 * glyphH + pxPerDecade - 1) / std::max(pxPerDecade, 1));
    for (int k = L.yDecadeMin; k <= L.yDecadeMax; ++k) {
        const int y = L.yOf(std::pow(10.0, k));
        c.rect(L.left, y, L.right, y, kGrid);
        if ((k - L.yDecadeMin) % every != 0) continue;
        const std::string s = decadeLabel(k);
        c.text(L.left - 10 - textWidth(s, kScale), y - glyphH / 2, s, kText);
    }
    // Frame.
    c.rect(L.left, L.top, L.right, L.top, kFrame);
    c.rect(L.left, L.bottom, L.right, L.bottom, kFrame);
    c.rect(L.left, L.top, L.left, L.bottom, kFrame);
    c.rect(L.right, L.top, L.right, L.bottom, kFrame);

    // The fight distances (analysis/audits/depth_audit.h), under the curves: a dashed line at each gap and
    // at twice each gap (where a curve crosses them, buckets get wider than the gap: the onset;
    // twice as wide: likely).
    auto dashed = [&](double value, const std::string &label) {
        if (!(value > 0)) return;
        const int y = L.yOf(value);
        if (y <= L.top || y >= L.bottom) return;
        for (int x = L.left + 1; x < L.right; ++x)
            if ((x / 6) % 2 == 0) c.set(x, y, kGapLine);
        c.text(L.left + 6, y - glyphH - 3, label, kGapText);
    };
    for (double g : r.fightGaps) {
        dashed(g, "GAP " + gapText(g));
        dashed(2 * g, "2 X GAP " + gapText(g));
    }
    // Curves, in the result's order (later ones over earlier ones where they coincide).
    for (const DepthFormatAudit &a : r.formats) {
        const Rgb8 col = depthPlotColor(a.format);
        bool havePrev = false;
        int px = 0, py = 0;
        for (size_t i = 0; i < a.curveResolution.size() && i < r.curveDepths.size(); ++i) {
            const std::optional<double> &v = a.curveResolution[i];
            if (!v || !std::isfinite(*v) || !(*v > 0)) {
                havePrev = false;
                continue;
            }
            const int x = L.xOf(r.curveDepths[i]), y = L.yOf(*v);
            thickLine(c, havePrev ? px : x, havePrev ? py : y, x, y, col, L.left + 1, L.top + 1, L.right - 1,
                      L.bottom - 1);
            px = x;
            py = y;
            havePrev = true;
        }
    }

    // Markers of the fight distances, over the curves: per format a filled square at (onset, gap)
    // and a hollow one at (likely, 2 x gap).
    auto square = [&](double d, double value, Rgb8 col, bool filled) {
        if (!(d >= r.nearZ && d <= r.farZ) || !(value > 0)) return;
        const int x = L.xOf(d), y = L.yOf(value);
        for (int oy = -4; oy <= 4; ++oy)
            for (int ox = -4; ox <= 4; ++ox) {
                const bool edge = std::abs(ox) >= 3 || std::abs(oy) >= 3;
                const int px = x + ox, py = y + oy;
                if ((filled || edge) && px > L.left && px < L.right && py > L.top && py < L.bottom) c.set(px, py, col);
            }
    };
    for (const DepthFormatAudit &a : r.formats)
        for (const DepthFightDistance &f : a.fights) {
            if (f.onset) square(*f.onset, f.gap, depthPlotColor(a.format), true);
            if (f.likely) square(*f.likely, 2 * f.gap, depthPlotColor(a.format), false);
        }

    // Legend: a colored bar and the name in the same color, one row per format.
    int ly = L.top;
    for (const DepthFormatAudit &a : r.formats) {
        const Rgb8 col = depthPlotColor(a.format);
        c.rect(L.right + 20, ly + glyphH / 2 - 2, L.right + 44, ly + glyphH / 2 + 1, col);
        c.text(L.right + 52, ly, a.name, col);
        ly += glyphH + 8;
    }

    // Titles.
    char title[160];
    std::snprintf(title, sizeof title, "DEPTH RESOLUTION BY FORMAT, NEAR %g M, FAR %g M", r.nearZ, r.farZ);
    c.text((L.width - textWidth(title, kScale)) / 2, 12, title, kText);
    c.text(L.left - 100, 42, "RESOLUTION: DEPTH STEP TO NEXT STORED VALUE (M), LOG", kText);
    const std::string xTitle = "VIEW DEPTH D (M), LOG";
    c.text((L.left + L.right - textWidth(xTitle, kScale)) / 2, L.bottom + 40, xTitle, kText);

    return writePngRgb8(path, L.width, L.height, c.rgb.data(), err);
}

}  // namespace va
