// Images of the ordering analysis (ordering_images.h).
#include "reports/ordering_images.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "reports/font.h"

namespace va {

namespace {

void fill(std::vector<uint8_t> &rgb, int w, int x0, int y0, int x1, int y1, Rgb8 c) {
    const int h = int(rgb.size() / 3 / size_t(std::max(w, 1)));
    for (int y = std::max(y0, 0); y < std::min(y1, h); ++y)
        for (int x = std::max(x0, 0); x < std::min(x1, w); ++x) {
            uint8_t *p = &rgb[(size_t(y) * size_t(w) + size_t(x)) * 3];
            p[0] = c.r, p[1] = c.g, p[2] = c.b;
        }
}

std::string fixed2(double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.2f", v);
    return b;
}

}  // namespace

OrderingImageNames orderingImageNames(const std::string &baseName) {
    return {baseName + ".painter_errors.png", baseName + ".overdraw_order.png", baseName + ".abuffer.png"};
}

PaletteImage renderPainterErrors(const ReferenceVisibility &ref, const PainterResult &painter,
                                 const std::vector<uint8_t> *grays) {
    const int W = ref.width, H = ref.height;
    const size_t n = size_t(std::max(W, 0)) * size_t(std::max(H, 0));
    const int scale = W >= 1024 ? 2 : 1;
    const int strip = 13 * scale;
    PaletteImage img(W, H + strip, {0, 0, 0});
    // The reference's depths as the dimmed gray background (log scale, as depth.png); the classes'
    // colors over it. Codes through tables: pixel i of the image is code i (the canvas is W wide).
    const PixelGrays gray(ref.depth, grays);
    uint16_t dimmed[256];
    for (int k = 0; k < 256; ++k) {
        const uint8_t g = uint8_t(k / 2);
        dimmed[k] = img.codeOf({g, g, g});
    }
    const uint16_t black = img.codeOf({0, 0, 0}), wrong = img.codeOf(kOrderWrongColor),
                   tie = img.codeOf(kOrderTieColor), edge = img.codeOf(kOrderEdgeColor);
    for (size_t i = 0; i < n && i < painter.cls.size(); ++i) {
        const uint8_t c = painter.cls[i];
        img.code[i] = c == kOrderWrong ? wrong : c == kOrderTie ? tie : c == kOrderEdge ? edge : ref.id[i] ? dimmed[gray[i]] : black;
    }
    // Legend: swatch + text, in one row below the image.
    int x = 3 * scale;
    const int y = H + 3 * scale;
    auto entry = [&](Rgb8 c, const std::string &label) {
        img.fill(x, y, x + 7 * scale, y + 7 * scale, c);
        x = img.text(x + 10 * scale, y, label, {230, 230, 230}, scale) + 8 * scale;
    };
    entry(kOrderWrongColor, "painter wrong: " + std::to_string(painter.wrongPixels) + " px");
    entry(kOrderTieColor, "depth tie: " + std::to_string(painter.tiePixels) + " px");
    entry(kOrderEdgeColor, "edge: " + std::to_string(painter.edgePixels) + " px");
    entry({128, 128, 128}, std::string("key: ") + painterKeyName(painter.key));
    return img;
}

bool writePainterErrorsImage(const ReferenceVisibility &ref, const PainterResult &painter, const std::string &path,
                             std::string *err, const std::vector<uint8_t> *grays) {
    const size_t n = size_t(std::max(ref.width, 0)) * size_t(std::max(ref.height, 0));
    if (n == 0 || ref.id.size() != n || painter.cls.size() != n) {
        if (err) *err = "cannot write image '" + path + "': the painter's per-pixel classes do not match the reference";
        return false;
    }
    return writePngPalette(path, renderPainterErrors(ref, painter, grays), err);
}

std::vector<uint8_t> renderOverdrawByOrder(const std::vector<OrderOverdraw> &orders, int *canvasH) {
    // Layout: a title row, then one row per order: its name (left column), a bar whose length is
    // proportional to the overdraw on a scale from 0 to the largest value (at least 1), the value
    // after the bar. A thin line marks overdraw 1 (the best).
    constexpr int W = kOverdrawChartWidth, kRow = 22, kTop = 20, kLabel = 150, kBarMax = W - kLabel - 60;
    *canvasH = kTop + kRow * int(orders.size()) + 8;
    std::vector<uint8_t> rgb(size_t(W) * size_t(*canvasH) * 3, 24);
    drawText(rgb.data(), W, *canvasH, 6, 6, "overdraw by draw order (passes / covered px)", {230, 230, 230});
    double top = 1;
    for (const OrderOverdraw &o : orders) top = std::max(top, o.stats.overdraw);
    static constexpr Rgb8 kColors[] = {{120, 120, 120}, {255, 128, 0}, {64, 160, 255}, {64, 220, 64}};
    for (size_t k = 0; k < orders.size(); ++k) {
        const int y = kTop + kRow * int(k);
        drawText(rgb.data(), W, *canvasH, 6, y + 6, orders[k].order, {230, 230, 230});
        const int len = int(std::lround(kBarMax * orders[k].stats.overdraw / top));
        fill(rgb, W, kLabel, y + 3, kLabel + len, y + kRow - 3, kColors[k % std::size(kColors)]);
        drawText(rgb.data(), W, *canvasH, kLabel + len + 4, y + 6, fixed2(orders[k].stats.overdraw), {230, 230, 230});
    }
    const int one = kLabel + int(std::lround(kBarMax / top));
    fill(rgb, W, one, kTop, one + 1, *canvasH - 4, {255, 255, 255});
    return rgb;
}

bool writeOverdrawByOrderChart(const std::vector<OrderOverdraw> &orders, const std::string &path, std::string *err) {
    if (orders.empty()) {
        if (err) *err = "cannot write image '" + path + "': no draw orders were measured";
        return false;
    }
    int h = 0;
    const std::vector<uint8_t> rgb = renderOverdrawByOrder(orders, &h);
    return writePngRgb8(path, kOverdrawChartWidth, h, rgb.data(), err);
}

bool writeABufferImage(const ABufferResult &a, const std::string &path, std::string *err) {
    const size_t n = size_t(std::max(a.width, 0)) * size_t(std::max(a.height, 0));
    if (n == 0 || a.rgb.size() != 3 * n) {
        if (err) *err = "cannot write image '" + path + "': the A-buffer did not run for this view";
        return false;
    }
    return writePngRgb8(path, a.width, a.height, a.rgb.data(), err);
}

}  // namespace va
