// A picture of few colors drawn as one color code per pixel: the audits' per-pixel images (culling,
// ray-cast differences, painter's errors, z-fighting, overdraw) are a few hundred colors at most,
// which a PNG stores with a palette. Drawing codes writes a third of an RGB canvas' bytes, and the
// palette comes from the codes through a table instead of hashing every RGB pixel again
// (writePngPalette). The file is byte for byte the one writePngRgb8 writes for the same pixels.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "reports/report.h"

namespace va {

struct PaletteImage {
    int width = 0, height = 0;
    std::vector<uint16_t> code;  // per pixel, rows top-down: an index into colors
    std::vector<Rgb8> colors;    // distinct colors, in the order they were first asked for

    PaletteImage() = default;
    // Every pixel `background`. The codes' storage is taken from the last image destroyed (render/
    // recycle.h): a 1080p image's 4 MB would otherwise be faulted in and cleared by the kernel for
    // every picture of every view.
    PaletteImage(int w, int h, Rgb8 background);
    PaletteImage(const PaletteImage &) = default;
    PaletteImage(PaletteImage &&) = default;
    PaletteImage &operator=(const PaletteImage &) = default;
    PaletteImage &operator=(PaletteImage &&) = default;
    ~PaletteImage();
    // The code of c, added to the colors when new (at most 65,536 colors).
    uint16_t codeOf(Rgb8 c);
    // One pixel; nothing outside the image.
    void set(int x, int y, uint16_t c) {
        if (x >= 0 && y >= 0 && x < width && y < height) code[size_t(y) * size_t(width) + size_t(x)] = c;
    }
    // [x0, x1) x [y0, y1), clipped to the image.
    void fill(int x0, int y0, int x1, int y1, uint16_t c);
    void fill(int x0, int y0, int x1, int y1, Rgb8 c) { fill(x0, y0, x1, y1, codeOf(c)); }
    // Text in the built-in font (reports/font.h) with its top-left corner at (x, y), clipped to the
    // image's first `rows` rows (all when negative); returns the x past it.
    int text(int x, int y, std::string_view s, Rgb8 c, int scale = 1, int rows = -1);
    Rgb8 at(int x, int y) const { return colors[code[size_t(y) * size_t(width) + size_t(x)]]; }
    // Interleaved RGB8, rows top-down.
    std::vector<uint8_t> rgb() const;
};

// Writes the image as writePngRgb8 writes its RGB pixels (the same bytes): a palette in order of
// first appearance when at most 256 colors appear, else RGB.
bool writePngPalette(const std::string &path, const PaletteImage &image, std::string *err);

}  // namespace va
