// The A-buffer (Carpenter 1984): per pixel a list of fragments, each with a coverage mask of 4 x 4
// sub-samples, its depth and alpha, resolved front to back per sub-sample into an antialiased
// composite. Runs only where the scene has transparent materials (the effects planner decides).
//
// Sub-sample coverage uses the rasterizer's conventions exactly (docs/rasterizer.md): vertices in
// fixed point (kSubpixelBits), int64 edge functions, the top-left fill rule as the integer bias, a
// zero snapped area covers nothing, both windings drawn. Samples sit at fixed-point offsets inside
// the pixel; with the single offset (128, 128) -- the pixel center -- coverageMasks gives exactly
// forEachFragment's pixels (tested: ABuffer.CenterSampleEqualsFragmentCore).
#pragma once

#include <algorithm>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "render/raster.h"
#include "render/raster_core.h"

namespace va {

// A sample position inside a pixel in fixed point: pixel (x, y)'s sample is
// (x * kSubpixelOne + dx, y * kSubpixelOne + dy), 0 <= dx, dy < kSubpixelOne.
struct SampleOffset {
    int32_t dx = 0, dy = 0;
};

// The 4 x 4 grid: offsets 32, 96, 160, 224 (the centers of the 16 cells of a 256 x 256 pixel),
// sample index 4 * row + column. kCenterSample is the pixel center (the z-buffer's one sample).
constexpr int kABufferGrid = 4;
constexpr int kABufferSamples = kABufferGrid * kABufferGrid;
const SampleOffset *abufferSampleOffsets();  // kABufferSamples entries
constexpr SampleOffset kCenterSample{kSubpixelOne / 2, kSubpixelOne / 2};

// Coverage of screen triangle t over `count` (<= 32) sample offsets: calls fn(pixel, mask) for every
// pixel of the viewport with a nonzero mask (bit i = sample i covered), pixel = y * width + x.
// Returns false (no call) when the triangle covers nothing by the core's rules (zero snapped area,
// outside the viewport or kMaxFixed); *frontWinding is set as raster_core.h defines it.
template <class Fn>
bool coverageMasks(const ScreenTriangles &tris, size_t t, int width, int height, const SampleOffset *offsets, int count,
                   bool *frontWinding, Fn &&fn);

// Per source triangle: what the A-buffer needs to shade and composite it.
struct ABufferMaterials {
    const float *alpha = nullptr;        // per source triangle, 0..1 (1 opaque)
    const uint8_t *rgb = nullptr;        // per source triangle, 3 bytes
    const uint8_t *singleSided = nullptr;// per source triangle: drawn only with the front winding
    const uint32_t *surface = nullptr;   // per source triangle: the surface it belongs to (edge pixels
                                         //   compare surfaces, so a mesh's inner edges do not count);
                                         //   null: every triangle is its own surface
    uint8_t background[3] = {0, 0, 0};
};

struct ABufferFragment {
    uint32_t source = 0;   // source triangle
    uint32_t plane = 0;    // ScreenTriangles::plane of it: depth at any sample from the plane
    uint32_t next = 0;     // next fragment of the pixel's list (UINT32_MAX ends it)
    uint16_t mask = 0;     // covered sub-samples
    float alpha = 1;
};

constexpr size_t kABufferHistogramMax = 64;  // list lengths >= this share the last bucket
// The longest list accepted by default (--max-abuffer-list; docs/limits.md): a level's depth
// complexity is tens; a thousand stacked transparent layers in one pixel is a bug or hostile input.
constexpr uint32_t kABufferDefaultMaxList = 1024;

struct ABufferResult {
    // Not empty: the A-buffer was refused (a pixel's list would exceed the limit, or the pool its
    // 32-bit indices); nothing below is set and nothing was allocated for the fragments.
    std::string error;
    int width = 0, height = 0;
    uint64_t fragments = 0;           // fragments stored (a triangle covering >= 1 sub-sample of a pixel)
    uint64_t coveredPixels = 0;       // pixels with a non-empty list
    double averageListLength = 0;     // fragments / covered pixels
    uint32_t maxListLength = 0;
    std::vector<uint64_t> listHistogram;  // [k] = pixels with k fragments (k < kABufferHistogramMax; last: >=)
    uint64_t memoryBytes = 0;         // fragment pool + per-pixel list heads
    uint64_t transparentFragments = 0;// fragments with alpha < 1
    // Edge pixels: the z-buffer's single center sample shows one surface (that of the nearest
    // triangle covering the center; ABufferMaterials::surface), while the A-buffer's visible surface
    // (nearest at each sub-sample) is a different one -- or background -- at one sub-sample or more:
    // the pixel's coverage is partial, and the z-buffer's one sample misrepresents it.
    uint64_t edgePixels = 0;
    std::vector<uint8_t> edge;        // per pixel, 1 for an edge pixel
    std::vector<uint8_t> rgb;         // the composite (interleaved RGB8, row-major)
    double ms = 0;
};

// Builds the per-pixel lists (every triangle, submission order; single-sided ones only with the
// front winding) and resolves them: at each sub-sample the covering fragments sorted by their depth
// there (double, from their planes; ties by lowest source), composited front to back
// (color += T alpha c, T *= 1 - alpha, stopping when T reaches 0), the background under what is
// left, and the 16 sub-samples averaged. A first pass counts each pixel's fragments, so a list
// longer than maxListLength is refused (ABufferResult::error) before the pool is allocated.
ABufferResult resolveABuffer(const ScreenTriangles &tris, int width, int height, bool orthographic,
                             const ABufferMaterials &materials, uint32_t maxListLength = kABufferDefaultMaxList);

// ---- coverageMasks --------------------------------------------------------------------------------
// The pixel box is every pixel any of whose samples may lie in the vertex box (a sample of pixel x
// has the fixed-point x in [x one, x one + one - 1]: x from floor(minX / one) to floor(maxX / one)),
// clamped to the viewport. Per sample offset, the three edge functions (with the top-left bias,
// raster_detail::setupEdge) are set up at the box's first pixel and stepped by exact integer
// increments per pixel, exactly as the core steps them per center.
template <class Fn>
bool coverageMasks(const ScreenTriangles &tris, size_t t, int width, int height, const SampleOffset *offsets, int count,
                   bool *frontWinding, Fn &&fn) {
    using namespace raster_detail;
    if (width <= 0 || height <= 0 || count <= 0 || count > 32) return false;
    const int32_t *v = tris.xy.data() + 6 * t;
    int64_t x0 = v[0], y0 = v[1], x1 = v[2], y1 = v[3], x2 = v[4], y2 = v[5];
    const int64_t minX = std::min(x0, std::min(x1, x2)), maxX = std::max(x0, std::max(x1, x2));
    const int64_t minY = std::min(y0, std::min(y1, y2)), maxY = std::max(y0, std::max(y1, y2));
    if (minX < -kMaxFixed || maxX > kMaxFixed || minY < -kMaxFixed || maxY > kMaxFixed) return false;
    const int64_t bx0 = std::max<int64_t>(minX >> kSubpixelBits, 0);
    const int64_t bx1 = std::min<int64_t>(maxX >> kSubpixelBits, int64_t(width) - 1);
    const int64_t by0 = std::max<int64_t>(minY >> kSubpixelBits, 0);
    const int64_t by1 = std::min<int64_t>(maxY >> kSubpixelBits, int64_t(height) - 1);
    if (bx0 > bx1 || by0 > by1) return false;
    const int64_t area = (x1 - x0) * (y2 - y0) - (y1 - y0) * (x2 - x0);
    if (area == 0) return false;
    if (frontWinding) *frontWinding = area < 0;
    if (area < 0) {
        std::swap(x1, x2);
        std::swap(y1, y2);
    }
    // Per sample: edge values at the box's first pixel; the per-pixel steps do not depend on the sample.
    int64_t row[32][3];
    int64_t stepX[3] = {}, stepY[3] = {};
    for (int s = 0; s < count; ++s) {
        const int64_t sx = bx0 * kSubpixelOne + offsets[s].dx, sy = by0 * kSubpixelOne + offsets[s].dy;
        const EdgeSetup e0 = setupEdge(x1, y1, x2, y2, sx, sy);
        const EdgeSetup e1 = setupEdge(x2, y2, x0, y0, sx, sy);
        const EdgeSetup e2 = setupEdge(x0, y0, x1, y1, sx, sy);
        row[s][0] = e0.value;
        row[s][1] = e1.value;
        row[s][2] = e2.value;
        stepX[0] = e0.stepX, stepX[1] = e1.stepX, stepX[2] = e2.stepX;
        stepY[0] = e0.stepY, stepY[1] = e1.stepY, stepY[2] = e2.stepY;
    }
    for (int64_t y = by0; y <= by1; ++y) {
        int64_t c[32][3];
        for (int s = 0; s < count; ++s)
            for (int k = 0; k < 3; ++k) c[s][k] = row[s][k];
        for (int64_t x = bx0; x <= bx1; ++x) {
            uint32_t mask = 0;
            for (int s = 0; s < count; ++s) {
                mask |= uint32_t((c[s][0] | c[s][1] | c[s][2]) >= 0) << s;
                for (int k = 0; k < 3; ++k) c[s][k] += stepX[k];
            }
            if (mask) fn(size_t(y) * size_t(width) + size_t(x), mask);
        }
        for (int s = 0; s < count; ++s)
            for (int k = 0; k < 3; ++k) row[s][k] += stepY[k];
    }
    return true;
}

}  // namespace va
