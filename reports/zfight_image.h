// NAME.zfight.png: where a view z-fights (docs/architecture.md, Outputs; docs/zfighting.md, "The image").
//
// The view as dimmed gray depth (the depth PNG's log-scale gray at half brightness, background
// black); every hotspot pixel filled with its hotspot's color and its bounding box outlined in that
// color two pixels out (so a one-pixel hotspot is still visible), its id written above the box;
// shared-edge and intersection pixels (fights that are no hotspots) in two neutral marker colors;
// below the image a legend strip: a swatch and "#id" per listed hotspot, then the two markers.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "analysis/audits/zfight.h"
#include "render/raster.h"
#include "reports/palette_image.h"
#include "reports/report.h"

namespace va {

// Hotspot id k (1-based) gets kZFightPalette[(k - 1) % 12]: saturated colors, none of them gray,
// so they stand out on the gray view and from the two neutral markers.
Rgb8 zfightHotspotColor(uint32_t id);
constexpr Rgb8 kZFightSharedEdgeColor{110, 140, 170};    // slate: fights along a shared edge
constexpr Rgb8 kZFightIntersectionColor{170, 150, 100};  // khaki: fights on an intersection line
constexpr Rgb8 kZFightOtherHotspotColor{255, 255, 255};  // hotspots beyond the listed ones
constexpr Rgb8 kZFightStripBackground{24, 24, 24};

// The image in memory (a color code per pixel, rows top-down): the view occupies rows
// [0, viewHeight) and columns [0, viewWidth); the legend strip is rows [viewHeight, height). The canvas is wider than
// the view only when the legend's longest line needs it (filled with the strip color).
struct ZFightImage : PaletteImage {
    int viewWidth = 0, viewHeight = 0;
};

// Composes the image from the analysis and the view's z-buffer (its visible depth is the gray
// background). Returns false with *err when the two do not have the same width x height.
bool renderZFightImage(const ZFightResult &zf, const ZBuffer &zb, ZFightImage *out, std::string *err,
                       const std::vector<uint8_t> *grays = nullptr);

// BASE.zfight.png
inline std::string zfightImageName(const std::string &baseName) { return baseName + ".zfight.png"; }

// Renders and writes the PNG at `path` (temporary name in the same folder, then renamed). On
// failure returns false with the path and the reason.
// grays: the z-buffer depth's depthGrays when the caller has them (else computed here).
bool writeZFightImage(const ZFightResult &zf, const ZBuffer &zb, const std::string &path, std::string *err,
                      const std::vector<uint8_t> *grays = nullptr);

}  // namespace va
