// A tiny built-in 5x7 bitmap font for legends drawn into report images (no font files, no
// dependencies, identical pixels on every machine).
//
// Glyphs: digits, A-Z (lower case is drawn as upper case), space and . , : ; - + / % ( ) [ ] < > =
// _ # ! ? ' " * x. A character without a glyph is drawn as a hollow box, so a missing glyph is
// visible rather than silently dropped. Each glyph is kGlyphWidth x kGlyphHeight cells; the advance
// is kGlyphAdvance cells (one blank column between glyphs); every cell is scale x scale pixels.
#pragma once

#include <cstdint>
#include <string_view>

namespace va {

constexpr int kGlyphWidth = 5;
constexpr int kGlyphHeight = 7;
constexpr int kGlyphAdvance = kGlyphWidth + 1;

struct FontColor {
    uint8_t r = 255, g = 255, b = 255;
};

// Whether the font has a real glyph for c (letters in either case count).
bool hasGlyph(char c);

// Width and height in pixels of text drawn at scale (no trailing blank column).
int textWidth(std::string_view text, int scale = 1);
inline int textHeight(int scale = 1) { return kGlyphHeight * scale; }

// Draws text into an interleaved RGB8 image of w x h pixels (row-major, top-down) with its
// top-left corner at (x, y). Only the glyphs' set cells are written (the background shows
// through); pixels outside the image are skipped. Returns the x just past the drawn text.
int drawText(uint8_t *rgb, int w, int h, int x, int y, std::string_view text, FontColor color,
             int scale = 1);
// The same into an image of one color code per pixel (reports/palette_image.h).
int drawText(uint16_t *codes, int w, int h, int x, int y, std::string_view text, uint16_t code, int scale = 1);

}  // namespace va
