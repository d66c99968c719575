// NAME.zfight.png (zfight_image.h). Layers, bottom to top:
//   1. the view: depthGray (reports/report.h, the depth PNG's log scale) of the z-buffer's visible
//      depth, halved so that colors stand out; background black;
//   2. shared-edge and intersection pixels in their neutral marker colors;
//   3. every hotspot's bounding box grown by two pixels, outlined in its color (largest first, so
//      the smaller ones' outlines stay on top), with its id above the box (below when no room);
//   4. the hotspot pixels, filled with their hotspot's color;
//   5. the legend strip below the view.
// Drawn as color codes (reports/palette_image.h) and written by writePngPalette.
#include "reports/zfight_image.h"


#include <algorithm>
#include <cmath>
#include <cstdio>


#include "reports/font.h"

namespace va {

namespace {

constexpr Rgb8 kPalette[12] = {
    {255, 64, 64},  {64, 220, 64},  {64, 128, 255}, {255, 220, 0},  {255, 64, 255}, {0, 230, 230},
    {255, 140, 0},  {170, 255, 0},  {255, 140, 190}, {160, 100, 255}, {0, 160, 140}, {200, 160, 0},
};
constexpr Rgb8 kLegendText{255, 255, 255};


// Legend layout, in multiples of the font scale s: a line is swatch 7s, gap 2s, label, gap 6s per
// entry; lines are margin 3s + text 7s apart by 3s; entries wrap at the view's width.
struct LegendEntry {
    Rgb8 color;
    std::string label;
};

}  // namespace

Rgb8 zfightHotspotColor(uint32_t id) { return kPalette[(id == 0 ? 0 : id - 1) % 12]; }

bool renderZFightImage(const ZFightResult &zf, const ZBuffer &zb, ZFightImage *out, std::string *err,
                       const std::vector<uint8_t> *grays) {
    const int W = zf.width, H = zf.height;
    const size_t n = size_t(std::max(W, 0)) * size_t(std::max(H, 0));
    if (W <= 0 || H <= 0 || zb.width != W || zb.height != H || zb.depth.size() != n || zf.pixelClass.size() != n ||
        zf.hotspotPixels.size() != zf.hotspotIds.size() ||
        (!zf.hotspotPixels.empty() && zf.hotspotPixels.back() >= n)) {
        if (err)
            *err = "z-fighting image: the analysis (" + std::to_string(W) + "x" + std::to_string(H) +
                   ") and the z-buffer (" + std::to_string(zb.width) + "x" + std::to_string(zb.height) +
                   ") do not describe the same view (or their per-pixel buffers were released)";
        return false;
    }

    // Legend entries and their wrapped lines.
    const int s = W >= 1024 ? 2 : 1;
    std::vector<LegendEntry> entries;
    for (const ZFightHotspot &h : zf.hotspots) entries.push_back({zfightHotspotColor(h.id), "#" + std::to_string(h.id)});
    if (zf.hotspotCount > zf.hotspots.size())
        entries.push_back({kZFightOtherHotspotColor, "more (" + std::to_string(zf.hotspotCount - zf.hotspots.size()) + ")"});
    if (zf.hotspotCount == 0) entries.push_back({kZFightStripBackground, "no hotspots"});
    entries.push_back({kZFightSharedEdgeColor, "shared edge"});
    entries.push_back({kZFightIntersectionColor, "intersection"});
    const int margin = 3 * s, swatch = 7 * s, lineH = textHeight(s) + 3 * s;
    auto entryWidth = [&](const LegendEntry &e) { return swatch + 2 * s + textWidth(e.label, s) + 6 * s; };
    int maxEntry = 0;
    for (const LegendEntry &e : entries) maxEntry = std::max(maxEntry, entryWidth(e));
    const int CW = std::max(W, maxEntry + 2 * margin);
    std::vector<int> lineOf(entries.size()), xOf(entries.size());
    int line = 0, x = margin;
    for (size_t i = 0; i < entries.size(); ++i) {
        if (x > margin && x + entryWidth(entries[i]) > CW - margin) ++line, x = margin;
        lineOf[i] = line;
        xOf[i] = x;
        x += entryWidth(entries[i]);
    }
    const int stripH = 2 * margin + (line + 1) * lineH;
    const int CH = H + stripH;

    ZFightImage img;
    static_cast<PaletteImage &>(img) = PaletteImage(CW, CH, kZFightStripBackground);
    img.viewWidth = W;
    img.viewHeight = H;
    const size_t cw = size_t(CW);

    // 1. Dimmed gray view; 2. markers (codes through tables).
    const PixelGrays gray(zb.depth, grays);
    uint16_t dimmed[256];
    for (int k = 0; k < 256; ++k) {
        const uint8_t g = uint8_t(k / 2);
        dimmed[k] = img.codeOf({g, g, g});
    }
    const uint16_t sharedEdge = img.codeOf(kZFightSharedEdgeColor), intersection = img.codeOf(kZFightIntersectionColor);
    for (int y = 0; y < H; ++y) {
        uint16_t *row = img.code.data() + size_t(y) * cw;
        for (int xx = 0; xx < W; ++xx) {
            const size_t p = size_t(y) * size_t(W) + size_t(xx);
            const auto cls = ZPixelClass(zf.pixelClass[p]);
            row[xx] = cls == ZPixelClass::shared_edge    ? sharedEdge
                      : cls == ZPixelClass::intersection ? intersection
                                                         : dimmed[gray[p]];
        }
    }

    // 3. Outlines and ids of the listed hotspots, largest (id 1) drawn first; only inside the view
    // (the canvas' rows above the strip and its first W columns: the loops stay within them).
    for (const ZFightHotspot &h : zf.hotspots) {
        const Rgb8 col = zfightHotspotColor(h.id);
        const uint16_t c = img.codeOf(col);
        const int x0 = h.minX - 2, y0 = h.minY - 2, x1 = h.maxX + 2, y1 = h.maxY + 2;
        for (int xx = std::max(x0, 0); xx <= std::min(x1, W - 1); ++xx) {
            if (y0 >= 0) img.set(xx, y0, c);
            if (y1 < H) img.set(xx, y1, c);
        }
        for (int y = std::max(y0, 0); y <= std::min(y1, H - 1); ++y) {
            if (x0 >= 0 && x0 < W) img.set(x0, y, c);
            if (x1 >= 0 && x1 < W) img.set(x1, y, c);
        }
        const std::string label = std::to_string(h.id);
        const int ly = y0 - 1 - textHeight(s) >= 0 ? y0 - 1 - textHeight(s) : std::min(y1 + 2, H - textHeight(s));
        // Only inside the view's rows: the text is clipped to the canvas' rows above the strip.
        if (ly >= 0) img.text(std::max(x0, 0), ly, label, col, s, H);
    }

    // 4. Hotspot pixels.
    std::vector<uint16_t> hotspotCode(zf.hotspots.size() + 1);
    for (size_t k = 1; k < hotspotCode.size(); ++k) hotspotCode[k] = img.codeOf(zfightHotspotColor(uint32_t(k)));
    const uint16_t other = img.codeOf(kZFightOtherHotspotColor);
    for (size_t k = 0; k < zf.hotspotPixels.size(); ++k) {
        const size_t p = zf.hotspotPixels[k], y = p / size_t(W), xx = p % size_t(W);
        const uint32_t id = zf.hotspotIds[k];
        img.code[y * cw + xx] = id < hotspotCode.size() ? hotspotCode[id] : other;
    }

    // 5. Legend.
    for (size_t i = 0; i < entries.size(); ++i) {
        const int ex = xOf[i], ey = H + margin + lineOf[i] * lineH;
        if (entries[i].label != "no hotspots") img.fill(ex, ey, ex + swatch, ey + swatch, entries[i].color);
        const int tx = entries[i].label == "no hotspots" ? ex : ex + swatch + 2 * s;
        img.text(tx, ey, entries[i].label, kLegendText, s);
    }
    *out = std::move(img);
    return true;
}

bool writeZFightImage(const ZFightResult &zf, const ZBuffer &zb, const std::string &path, std::string *err,
                      const std::vector<uint8_t> *grays) {
    ZFightImage img;
    std::string e;
    if (!renderZFightImage(zf, zb, &img, &e, grays)) {
        if (err) *err = "cannot write image '" + path + "': " + e;
        return false;
    }
    return writePngPalette(path, img, err);
}

}  // namespace va
