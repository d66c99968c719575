#include "reports/legend.h"

#include <algorithm>

#include "reports/font.h"

namespace va {

namespace {
constexpr Rgb8 kStrip{24, 24, 24};
constexpr Rgb8 kText{255, 255, 255};

// Where the legend puts each entry below an image W wide: (x, row) per entry, and the font scale,
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
    const PaletteImage canvas = legendCanvas(W, H, entries);
    *canvasH = canvas.height;
    std::vector<uint8_t> rgb = canvas.rgb();
    std::copy(image.begin(), image.begin() + ptrdiff_t(std::min(image.size(), size_t(W) * size_t(H) * 3)), rgb.begin());
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
