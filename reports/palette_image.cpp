#include "reports/palette_image.h"

#include <algorithm>

#include "render/recycle.h"
#include "reports/font.h"

namespace va {

namespace {
// Storage worth handing on: what glibc maps on its own (above its 128 KB threshold) and unmaps on free.
constexpr size_t kRecycledCodes = size_t(1) << 16;
}  // namespace

PaletteImage::PaletteImage(int w, int h, Rgb8 background)
    : width(std::max(w, 0)), height(std::max(h, 0)), code(recyclerOf<std::vector<uint16_t>>().take()), colors{background} {
    code.assign(size_t(width) * size_t(height), 0);
}

PaletteImage::~PaletteImage() {
    if (code.capacity() >= kRecycledCodes) {
        code.clear();
        recyclerOf<std::vector<uint16_t>>().give(std::move(code));
    }
}

uint16_t PaletteImage::codeOf(Rgb8 c) {
    // A linear search: a renderer asks once per color it uses (its tables are built before the
    // pixel loops), a few hundred times an image.
    for (size_t k = 0; k < colors.size(); ++k)
        if (colors[k] == c) return uint16_t(k);
    if (colors.size() > UINT16_MAX) return 0;  // not reached: no picture here has that many
    colors.push_back(c);
    return uint16_t(colors.size() - 1);
}

void PaletteImage::fill(int x0, int y0, int x1, int y1, uint16_t c) {
    x0 = std::max(x0, 0), y0 = std::max(y0, 0), x1 = std::min(x1, width), y1 = std::min(y1, height);
    for (int y = y0; y < y1; ++y)
        std::fill_n(code.begin() + ptrdiff_t(size_t(y) * size_t(width) + size_t(x0)), std::max(x1 - x0, 0), c);
}

int PaletteImage::text(int x, int y, std::string_view s, Rgb8 c, int scale, int rows) {
    return drawText(code.data(), width, rows < 0 ? height : std::min(rows, height), x, y, s, codeOf(c), scale);
}

std::vector<uint8_t> PaletteImage::rgb() const {
    std::vector<uint8_t> out(3 * code.size());
    for (size_t i = 0; i < code.size(); ++i) {
        const Rgb8 c = colors[code[i]];
        out[3 * i] = c.r, out[3 * i + 1] = c.g, out[3 * i + 2] = c.b;
    }
    return out;
}

}  // namespace va
