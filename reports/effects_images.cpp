// Images of the secondary rays (effects_images.h).
#include "reports/effects_images.h"

#include <algorithm>
#include <cmath>

#include "reports/legend.h"
#include "reports/report.h"

namespace va {

namespace {

constexpr Rgb8 kShadowed{40, 90, 220};
constexpr Rgb8 kFacingAway{70, 70, 70};

bool sizesMatch(const EffectsResult &fx, const ZBuffer &zb, const std::string &path, std::string *err) {
    if (fx.width == zb.width && fx.height == zb.height && zb.depth.size() == size_t(zb.width) * size_t(zb.height))
        return true;
    *err = path + ": the effects (" + std::to_string(fx.width) + "x" + std::to_string(fx.height) +
           ") and the z-buffer (" + std::to_string(zb.width) + "x" + std::to_string(zb.height) + ") differ in size";
    return false;
}

}  // namespace

bool writeShadowImage(const EffectsResult &fx, size_t light, const ZBuffer &zb, const std::string &path,
                      std::string *err, const std::vector<uint8_t> *grays) {
    if (!sizesMatch(fx, zb, path, err)) return false;
    const int W = zb.width, H = zb.height;
    const PixelGrays gray(zb.depth, grays);
    std::vector<uint8_t> img(size_t(W) * size_t(H) * 3, 0);
    // A visible pixel is lit, shadowed or facing away; the ray caster's visibility decides which
    // pixels are visible, so lit = visible and neither of the other two.
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const size_t i = size_t(y) * size_t(W) + size_t(x);
            if (!std::isfinite(zb.depth[i])) continue;
            Rgb8 c;
            if (fx.shadowed(light, x, y)) {
                c = kShadowed;
            } else {
                const uint8_t g = gray[i];
                c = {g, g, g};
            }
            img[3 * i] = c.r, img[3 * i + 1] = c.g, img[3 * i + 2] = c.b;
        }
    const LightShadowStats &l = fx.lights[light];
    const std::vector<LegendEntry> legend = {
        {{200, 200, 200}, "lit " + std::to_string(l.litPixels)},
        {kShadowed, "shadowed " + std::to_string(l.shadowedPixels) + " (light '" + l.name + "')"},
        {kFacingAway, "facing away " + std::to_string(l.facingAwayPixels) + " (shown lit)"}};
    int CH = 0;
    const std::vector<uint8_t> rgb = withLegend(img, W, H, legend, &CH);
    return writePngRgb8(path, W, CH, rgb.data(), err);
}

bool writeSecondaryImage(const EffectsResult &fx, const ZBuffer &zb, const std::string &path, std::string *err,
                         const std::vector<uint8_t> *grays) {
    if (!sizesMatch(fx, zb, path, err)) return false;
    const int W = zb.width, H = zb.height;
    const PixelGrays gray(zb.depth, grays);
    // Depth 1..8+ on the overdraw ramp; 0 (no secondary ray) shows the depth image dimmed.
    std::vector<uint8_t> img(size_t(W) * size_t(H) * 3, 0);
    int deepest = 0;
    for (size_t i = 0; i < img.size() / 3; ++i) {
        const int k = i < fx.secondaryDepth.size() ? fx.secondaryDepth[i] : 0;
        deepest = std::max(deepest, k);
        Rgb8 c;
        if (k > 0) {
            c = overdrawColor(uint32_t(k), 8);
        } else {
            const uint8_t g = uint8_t(gray[i] / 3);
            c = {g, g, g};
        }
        img[3 * i] = c.r, img[3 * i + 1] = c.g, img[3 * i + 2] = c.b;
    }
    std::vector<LegendEntry> legend = {{{60, 60, 60}, "no secondary ray"}};
    for (int k = 1; k <= std::max(deepest, 1); ++k)
        legend.push_back({overdrawColor(uint32_t(k), 8), "depth " + std::to_string(k)});
    int CH = 0;
    const std::vector<uint8_t> rgb = withLegend(img, W, H, legend, &CH);
    return writePngRgb8(path, W, CH, rgb.data(), err);
}

}  // namespace va
