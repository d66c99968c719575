// A legend strip below an image: colored swatches with their labels (the culling, ray-cast and
// shadow images use it; reports/font.h draws the text).
#pragma once

#include <string>
#include <vector>

#include "reports/palette_image.h"
#include "reports/report.h"

namespace va {

struct LegendEntry {
    Rgb8 color;
    std::string label;
};

// The W x H RGB8 image with a legend strip appended below: swatches with their labels in one row,
// left-aligned, wrapping onto more rows when wider than the canvas. Sizes scale with the font
// scale s (2 from 1024 pixels wide): row height = margin 3s + text 7s (swatch as tall as the
// text) + margin 3s. *canvasH receives the new height.
std::vector<uint8_t> withLegend(const std::vector<uint8_t> &image, int W, int H, const std::vector<LegendEntry> &entries,
                                int *canvasH);

// The same canvas as codes (W x (H + the strip)): the legend strip drawn as withLegend draws it,
// rows [0, H) the strip's background for the caller to draw the image over.
PaletteImage legendCanvas(int W, int H, const std::vector<LegendEntry> &entries);

}  // namespace va
