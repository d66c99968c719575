#include "reports/canvas.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "reports/font.h"

namespace va {

Canvas::Canvas(int w, int h, Rgb8 fill) : width(w), height(h), rgb(size_t(w) * size_t(h) * 3) {
    for (size_t i = 0; i < size_t(w) * size_t(h); ++i) rgb[3 * i] = fill.r, rgb[3 * i + 1] = fill.g, rgb[3 * i + 2] = fill.b;
}

void Canvas::set(int x, int y, Rgb8 c) {
    if (!inside(x, y)) return;
    uint8_t *p = &rgb[(size_t(y) * size_t(width) + size_t(x)) * 3];
    p[0] = c.r, p[1] = c.g, p[2] = c.b;
}

Rgb8 Canvas::at(int x, int y) const {
    if (!inside(x, y)) return {};
    const uint8_t *p = &rgb[(size_t(y) * size_t(width) + size_t(x)) * 3];
    return {p[0], p[1], p[2]};
}

void Canvas::rect(int x0, int y0, int x1, int y1, Rgb8 c) {
    x0 = std::max(x0, 0), y0 = std::max(y0, 0), x1 = std::min(x1, width), y1 = std::min(y1, height);
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) set(x, y, c);
}

void Canvas::line(int x0, int y0, int x1, int y1, Rgb8 c) {
    const int dx = std::abs(x1 - x0), dy = -std::abs(y1 - y0), sx = x0 < x1 ? 1 : -1, sy = y0 < y1 ? 1 : -1;
    int e = dx + dy;
    for (int guard = 0; guard <= dx - dy; ++guard) {  // at most dx + |dy| + 1 steps
        set(x0, y0, c);
        if (x0 == x1 && y0 == y1) break;
        const int e2 = 2 * e;
        if (e2 >= dy) e += dy, x0 += sx;
        if (e2 <= dx) e += dx, y0 += sy;
    }
}

void Canvas::disc(int cx, int cy, int r, Rgb8 c) {
    for (int dy = -r; dy <= r; ++dy)
        for (int dx = -r; dx <= r; ++dx)
            if (dx * dx + dy * dy <= r * r) set(cx + dx, cy + dy, c);
}

int Canvas::text(int x, int y, std::string_view s, Rgb8 c, int scale) {
    // The font draws lower case as upper case but for 'x', which is its multiplication sign.
    std::string t(s);
    std::replace(t.begin(), t.end(), 'x', 'X');
    return drawText(rgb.data(), width, height, x, y, t, {c.r, c.g, c.b}, scale);
}

void Canvas::label(int x, int y, std::string_view s, Rgb8 fg, Rgb8 bg, int scale) {
    const int p = scale;
    rect(x - p, y - p, x + textWidth(s, scale) + p, y + textHeight(scale) + p, bg);
    text(x, y, s, fg, scale);
}

Rgb8 rampColor(double t) {
    if (!std::isfinite(t)) return {128, 128, 128};
    t = std::clamp(t, 0.0, 1.0);
    // Five stops, linear between them, rounded to nearest.
    static const Rgb8 stops[] = {{30, 40, 140}, {20, 140, 160}, {60, 180, 60}, {240, 210, 40}, {220, 40, 30}};
    const double f = t * 4;
    const int i = std::min(3, int(f));
    const double u = f - i;
    auto mix = [&](uint8_t a, uint8_t b) { return uint8_t(std::lround(a + (double(b) - a) * u)); };
    return {mix(stops[i].r, stops[i + 1].r), mix(stops[i].g, stops[i + 1].g), mix(stops[i].b, stops[i + 1].b)};
}

Rgb8 divergingColor(double t) {
    if (!std::isfinite(t)) return {128, 128, 128};
    t = std::clamp(t, -1.0, 1.0);
    const Rgb8 lo{40, 90, 220}, mid{245, 245, 245}, hi{220, 40, 30};
    const Rgb8 &end = t < 0 ? lo : hi;
    const double u = std::fabs(t);
    auto mix = [&](uint8_t a, uint8_t b) { return uint8_t(std::lround(a + (double(b) - a) * u)); };
    return {mix(mid.r, end.r), mix(mid.g, end.g), mix(mid.b, end.b)};
}

}  // namespace va
