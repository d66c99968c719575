// The z-buffer rasterizer (docs/architecture.md: Raster, Depth). Plain data in, plain data out.
//
// Coverage: vertices in fixed point with kSubpixelBits fractional bits; edge functions in 64-bit
// integers; a pixel is covered when its center (x + 0.5, y + 0.5) is inside the triangle, with the
// top-left fill rule deciding samples exactly on an edge, so two triangles sharing an edge never
// both cover a pixel and a closed mesh has no cracks. Both windings are drawn (culling is the
// backface stage's job); triangles whose snapped area is zero draw nothing.
// Depth: per covered pixel the fragment's view depth is computed in double from the triangle's
// DepthPlane at the pixel center (viewDepthAt), encoded in the view's depth format, and tested with
// LESS on the format's ordering key: on equal stored values the first drawn fragment wins.
// The coverage walk itself is render/raster_core.h (forEachFragment), shared with the audits.
#pragma once

#include <cstdint>
#include <vector>

#include "render/camera.h"
#include "render/depth_format.h"
#include "render/raw_vector.h"

namespace va {

constexpr int kSubpixelBits = 8;
constexpr int32_t kSubpixelOne = 1 << kSubpixelBits;

// Screen-space triangles ready to rasterize (the clip stage's output), in submission order.
struct ScreenTriangles {
    // RawVector (raw_vector.h): resize adds elements unwritten, so the clipper resizes and writes
    // accepted triangles in place.
    RawVector<int32_t> xy;          // 6 per triangle: x0 y0 x1 y1 x2 y2, pixel units * 2^kSubpixelBits
    RawVector<uint32_t> source;     // per triangle: the scene's global source triangle index
    RawVector<uint32_t> plane;      // per triangle: index into planes (pieces of one source share one)
    RawVector<DepthPlane> planes;   // depth planes, one per source triangle that produced output

    size_t size() const { return source.size(); }
    void clear() { xy.clear(); source.clear(); plane.clear(); planes.clear(); }
};

// Converts pixel coordinates to the rasterizer's fixed point (round to nearest, ties to even),
// saturating to int32 (NaN to the minimum). Inline: the clipper calls it twice per vertex.
// For |x| < 2^51, (x + 1.5 2^52) - 1.5 2^52 is x rounded to an integer in the default rounding
// mode (the sum lies in [2^52, 2^53), where the spacing of doubles is 1, and 1.5 2^52 is even, so
// ties go to even as for x itself; the subtraction is exact): nearbyint's result without its call.
// Larger magnitudes are integers already and saturate below.
inline int32_t toFixed(double pixelCoordinate) {
    const double x = pixelCoordinate * kSubpixelOne;  // exact: a power of two
    constexpr double kRound = 0x1.8p52;
    const double s = (x < 0x1p51 && x > -0x1p51) ? (x + kRound) - kRound : x;
    if (!(s > -2147483648.0)) return INT32_MIN;
    if (s > 2147483647.0) return INT32_MAX;
    return int32_t(s);
}

struct ZBufferSettings {
    DepthEncoder encoder;       // the view's depth format bound to its near/far
    bool orthographic = false;  // how DepthPlane values turn into view depth

    // Options for the audits (analysis/audits/audit.h); the defaults are the plain z-buffer and cost
    // nothing (exactDepth selects another instantiation; the pointers are tested once a triangle).
    //
    // exactDepth: the depth test compares the double view depth (LESS: on equal depths the first
    // drawn fragment wins) instead of the format's key. `key` is then filled after the pass with
    // the format's key of each pixel's stored depth, and outOfRangeFragments stays 0 (no fragment
    // goes through the format).
    bool exactDepth = false;
    // singleSided: per *source* triangle (indexed by ScreenTriangles::source); where non-null and
    // nonzero, the triangle is drawn only when its projected winding is the front one
    // (counter-clockwise as the viewer sees it; raster_core.h). Others are counted in
    // trianglesBackWinding (and among trianglesEmpty).
    const uint8_t *singleSided = nullptr;
    // fragmentsPerSource: optional, per source triangle: += the fragments rasterized for it (every
    // covered center, whether it passed the depth test or not). The caller sizes and zeroes it.
    uint32_t *fragmentsPerSource = nullptr;
};

// Per-pixel buffers, row-major, pixel (0,0) top-left.
struct ZBuffer {
    int width = 0, height = 0;
    std::vector<uint32_t> key;        // ordering key of the stored depth; UINT32_MAX = cleared
    std::vector<uint32_t> id;         // 1 + source triangle index of the visible fragment; 0 = background
    std::vector<double> depth;        // view depth (double) of the visible fragment; +inf = background
    std::vector<uint16_t> fragments;  // fragments rasterized at the pixel (depth complexity), saturating
    std::vector<uint16_t> passes;     // fragments that passed the depth test (overdraw), saturating
};

struct ZBufferStats {
    uint64_t trianglesIn = 0;         // triangles submitted
    uint64_t trianglesDrawn = 0;      // triangles that produced at least one fragment
    uint64_t trianglesEmpty = 0;      // triangles that cover no pixel center (zero area or tiny); best 0
    uint64_t trianglesBackWinding = 0;// single-sided (settings.singleSided) with the back winding on screen:
                                      //   not drawn (counted among trianglesEmpty); 0 without singleSided
    uint64_t fragments = 0;           // pixel centers covered, summed over triangles
    uint64_t depthPasses = 0;         // fragments that passed the depth test and were written
    uint64_t outOfRangeFragments = 0; // fragments whose depth the format cannot represent (clamped)
    uint64_t coveredPixels = 0;       // pixels with at least one fragment
    double overdraw = 0;              // depthPasses / coveredPixels; best case 1.0
    double depthComplexity = 0;       // fragments / coveredPixels; best case 1.0
    uint32_t maxDepthComplexity = 0;  // most fragments at one pixel
    std::vector<uint64_t> histogram;  // histogram[k] = pixels with exactly k fragments (k >= 1; [0] = uncovered)
};

struct ZBufferResult {
    ZBuffer buffer;
    ZBufferStats stats;
};

// Rasterizes every triangle in submission order into a cleared width x height buffer. Runs on the
// calling thread's oneTBB arena, within its tbb::global_control limit (docs/rasterizer.md: Tiles).
ZBufferResult rasterize(const ScreenTriangles &tris, int width, int height, const ZBufferSettings &settings);

// How rasterize() runs. Every choice gives byte-identical results (tests/test_raster_tiles.cpp);
// the defaults are what the benchmark measured fastest, the others exist for tests and benchmarks.
struct RasterStrategy {
    enum class Path : uint8_t {
        automatic,  // batchedWalk (in bands when threads > 1); without AVX2: plainWalk / tiled
        plainWalk,  // the reference: one in-order walk through forEachFragment (raster_core.h)
        batchedWalk,// the in-order walk setting up 8 triangles at once in AVX2 lanes (plainWalk without
                    // AVX2 or allowAvx2)
        tiled,      // binned into tiles, each tile's triangles in submission order, tiles in parallel
    };
    Path path = Path::automatic;
    bool allowAvx2 = true;  // tiled, batchedWalk: AVX2 code when the CPU has it (else the baseline SSE2 one)
    int tileShift = 0;      // tiled: tiles of 2^tileShift pixels square; 0 = default (kDefaultTileShift)
    int bands = 0;          // batchedWalk: bands of rows (run in parallel when threads > 1);
                            // 0 = one on one thread, kBandsPerThread per thread otherwise
};
constexpr int kDefaultTileShift = 7;
constexpr int kBandsPerThread = 1;
ZBufferResult rasterize(const ScreenTriangles &tris, int width, int height, const ZBufferSettings &settings,
                        const RasterStrategy &strategy);

// Fills the stats that follow from the per-pixel counts (covered pixels, ratios, histogram).
void finishZBufferStats(const ZBuffer &zb, ZBufferStats *stats);

// Storage handed to the next view (render/recycle.h): a finished view gives its z-buffer's
// per-pixel buffers and its screen triangles back, and the next rasterize() and clipTriangles()
// fill them instead of faulting fresh pages in. Each leaves its argument empty.
void recycleZBuffer(ZBuffer &zb);
void recycleScreenTriangles(ScreenTriangles &tris);
// Storage given back, emptied (a fresh ScreenTriangles when there is none): clipTriangles' output.
ScreenTriangles takeRecycledScreenTriangles();

}  // namespace va
