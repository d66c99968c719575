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

std::vector<uint8_t> withLegend(const std::vector<uint8_t> &image, int W, int H, const std::vector<LegendEntry> &entries,
                                int *canvasH) {
    const int s = W >= 1024 ? 2 : 1;
    const int margin = 3 * s, rowH = margin + textHeight(s) + margin, swatch = textHeight(s);
    // Lay out the entries: swatch, gap 2s, label, gap 6s.
    std::vector<std::pair<int, int>> at;  // (x, row)
    int x = margin, row = 0;
    for (const LegendEntry &e : entries) {
        const int ew = swatch + 2 * s + textWidth(e.label, s);
        if (x > margin && x + ew > W - margin) {
            x = margin;
            ++row;
        }
        at.push_back({x, row});
        x += ew + 6 * s;
    }
    const int strip = (row + 1) * rowH;
    *canvasH = H + strip;
    std::vector<uint8_t> rgb(size_t(W) * size_t(*canvasH) * 3);
    std::copy(image.begin(), image.end(), rgb.begin());
    fillRect(rgb, W, 0, H, W, *canvasH, kStrip);
    for (size_t i = 0; i < entries.size(); ++i) {
        const int ex = at[i].first, ey = H + at[i].second * rowH + margin;
        fillRect(rgb, W, ex, ey, std::min(ex + swatch, W), std::min(ey + swatch, *canvasH), entries[i].color);
        drawText(rgb.data(), W, *canvasH, ex + swatch + 2 * s, ey, entries[i].label, {kText.r, kText.g, kText.b}, s);
    }
    return rgb;
}


}  // namespace va
