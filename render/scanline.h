// Scanline visibility (Watkins' family): one row of pixel centers at a time, an active triangle
// list fed by an edge table (triangles bucketed by their first row), each active triangle's covered
// span on the row, and the spans resolved by depth. It holds one row of ids and depths, never a
// full-screen depth buffer.
//
// Coverage is the rasterizer's, exactly (docs/rasterizer.md): the same box of centers, the same
// int64 edge functions with the top-left bias, the span solved per row with integer floor
// division as raster_core.h's wide path does; depths at pixel centers are the same IEEE operations
// (viewDepthAt). Ties go to the lowest source id, as in the reference visibility, so with the same
// single-sided rule the result equals the reference pixel for pixel.
#pragma once

#include <cstdint>
#include <vector>

#include "render/raster.h"

namespace va {

struct ScanlineResult {
    int width = 0, height = 0;
    std::vector<uint32_t> id;          // per pixel: 1 + visible source, 0 background
    uint64_t trianglesIn = 0;          // screen triangles submitted
    uint64_t trianglesActive = 0;      // entered the active list (non-empty box, nonzero area, drawn winding)
    uint64_t backWinding = 0;          // single-sided with the back winding: never activated
    uint64_t spans = 0;                // non-empty (triangle, row) spans
    uint64_t fragments = 0;            // pixel centers inside spans
    uint64_t depthEvaluations = 0;     // centers where two or more spans overlapped (depth evaluated)
    uint64_t writes = 0;               // row-buffer writes: a lone span's centers, and depth-test passes
    uint64_t coveredPixels = 0;        // pixels showing a triangle
    double overdraw = 0;               // writes / covered pixels; best 1
    uint32_t maxActiveTriangles = 0;   // largest active list on one row
    uint32_t maxSpansPerRow = 0;
    uint64_t memoryBytes = 0;          // held at once: edge table + active list + one row's buffers
    uint64_t zbufferBytes = 0;         // what a full z-buffer of ids and depths holds: W H (4 + 8)
    double buildMs = 0;                // edge table (bucketing by first row)
    double ms = 0;                     // the row sweep
};

// `singleSided`: per source triangle (ScreenTriangles::source), nonzero = drawn only with the front
// projected winding (raster_core.h); may be null (every triangle drawn).
ScanlineResult scanlineVisibility(const ScreenTriangles &tris, int width, int height, bool orthographic,
                                  const uint8_t *singleSided);

}  // namespace va
