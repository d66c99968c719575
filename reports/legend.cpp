#include "reports/legend.h"

#include <algorithm>

#include "reports/font.h"

namespace va {

namespace {
constexpr Rgb8 kStrip{24, 24, 24};
constexpr Rgb8 kText{255, 255, 255};
}  // namespace

void fillRect(std::vector<uint8_t> &rgb, int w, int x0, int y0, int x1, int y1, Rgb8 c) {
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
            uint8_t *p = &rgb[(size_t(y) * size_t(w) + size_t(x)) * 3];
            p[0] = c.r;
            p[1] = c.g;
            p[2] = c.b;
        }
}

namespace {

// Where withLegend puts each entry below an image W wide: (x, row) per entry, and the font scale,
// margin, row height, swatch side and the strip's height.
struct LegendPlaces {
    int s = 1, margin = 0, rowH = 0, swatch = 0, strip = 0;
    std::vector<std::pair<int, int>> at;  // (x, row)
};
LegendPlaces placeLegend(int W, const std::vector<LegendEntry> &entries) {
    LegendPlaces L;
    L.s = W >= 1024 ? 2 : 1;
    const int s = L.s;
    L.margin = 3 * s, L.rowH = L.margin + textHeight(s) + L.margin, L.swatch = textHeight(s);
    // Lay out the entries: swatch, gap 2s, label, gap 6s.
    int x = L.margin, row = 0;
    for (const LegendEntry &e : entries) {
        const int ew = L.swatch + 2 * s + textWidth(e.label, s);
        if (x > L.margin && x + ew > W - L.margin) {
            x = L.margin;
            ++row;
        }
        L.at.push_back({x, row});
        x += ew + 6 * s;
    }
    L.strip = (row + 1) * L.rowH;
    return L;
}

}  // namespace

std::vector<uint8_t> withLegend(const std::vector<uint8_t> &image, int W, int H, const std::vector<LegendEntry> &entries,
                                int *canvasH) {
    const LegendPlaces L = placeLegend(W, entries);
    *canvasH = H + L.strip;
    std::vector<uint8_t> rgb(size_t(W) * size_t(*canvasH) * 3);
    std::copy(image.begin(), image.end(), rgb.begin());
    fillRect(rgb, W, 0, H, W, *canvasH, kStrip);
    for (size_t i = 0; i < entries.size(); ++i) {
        const int ex = L.at[i].first, ey = H + L.at[i].second * L.rowH + L.margin;
        fillRect(rgb, W, ex, ey, std::min(ex + L.swatch, W), std::min(ey + L.swatch, *canvasH), entries[i].color);
        drawText(rgb.data(), W, *canvasH, ex + L.swatch + 2 * L.s, ey, entries[i].label, {kText.r, kText.g, kText.b}, L.s);
    }
    return rgb;
}

PaletteImage legendCanvas(int W, int H, const std::vector<LegendEntry> &entries) {
    const LegendPlaces L = placeLegend(W, entries);
    PaletteImage img(W, H + L.strip, kStrip);
    for (size_t i = 0; i < entries.size(); ++i) {
        const int ex = L.at[i].first, ey = H + L.at[i].second * L.rowH + L.margin;
        img.fill(ex, ey, ex + L.swatch, ey + L.swatch, entries[i].color);
        img.text(ex + L.swatch + 2 * L.s, ey, entries[i].label, kText, L.s);
    }
    return img;
}

}  // namespace va
