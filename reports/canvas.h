// A small RGB8 canvas for the charts and maps drawn into PNGs (route plots, level maps): integer
// lines, filled discs and rectangles, text in the built-in font (reports/font.h). Everything is
// integer arithmetic on pixel centres, so the same inputs give the same bytes on every machine.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "reports/report.h"

namespace va {

struct Canvas {
    int width = 0, height = 0;
    std::vector<uint8_t> rgb;  // interleaved, rows top-down

    Canvas() = default;
    Canvas(int w, int h, Rgb8 fill);
    bool inside(int x, int y) const { return x >= 0 && y >= 0 && x < width && y < height; }
    void set(int x, int y, Rgb8 c);
    Rgb8 at(int x, int y) const;
    // [x0, x1) x [y0, y1), clipped to the canvas.
    void rect(int x0, int y0, int x1, int y1, Rgb8 c);
    // Bresenham's line from (x0, y0) to (x1, y1), both ends drawn.
    void line(int x0, int y0, int x1, int y1, Rgb8 c);
    // Every pixel whose centre offset (dx, dy) from (cx, cy) has dx^2 + dy^2 <= r^2.
    void disc(int cx, int cy, int r, Rgb8 c);
    // Text with its top-left corner at (x, y); returns the x past it.
    int text(int x, int y, std::string_view s, Rgb8 c, int scale = 1);
    // Text on a filled box (padding p around it), for labels over an image.
    void label(int x, int y, std::string_view s, Rgb8 fg, Rgb8 bg, int scale = 1);
    bool writePng(const std::string &path, std::string *err) const { return writePngRgb8(path, width, height, rgb.data(), err); }
};

// A colour on the maps' and plots' sequential ramp, t in [0, 1]: dark blue (low) through teal,
// green and yellow to red (high). Not finite: grey.
Rgb8 rampColor(double t);
// A diverging colour for changes, t in [-1, 1]: blue (lower, better for every metric here) through
// white (0) to red (higher).
Rgb8 divergingColor(double t);

}  // namespace va
