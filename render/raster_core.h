// The fragment core of the rasterizer: which pixel centers each screen triangle covers, and the
// view depth of each such fragment. Every pass that needs fragments -- the z-buffer (raster.cpp),
// the reference visibility (analysis/audits/audit.cpp), the two-nearest-surfaces pass of the z-fighting
// audit, later an A-buffer and the painter's algorithm -- walks coverage through this one template,
// so all of them see exactly the same fragments (docs/rasterizer.md: Coverage, Depth).
//
// Contract of forEachFragment(tris, width, height, orthographic, sink):
//   * Triangles are visited in submission order t = 0 .. tris.size() - 1.
//   * A triangle that cannot produce a fragment is skipped without calling the sink: its box of
//     pixel centers is empty or outside the viewport, its coordinates lie outside +-kMaxFixed, its
//     snapped signed area is zero, or its DepthPlane is invalid.
//   * Otherwise `bool sink.beginTriangle(size_t t, bool frontWinding)` is called; frontWinding is
//     true when the triangle's projected winding is the front one: counter-clockwise as the viewer
//     sees it (y up), which is a *negative* signed area
//         A = (x1 - x0)(y2 - y0) - (y1 - y0)(x2 - x0)
//     in the y-down fixed-point pixel coordinates of ScreenTriangles. (A world triangle that is
//     counter-clockwise seen from its front keeps that orientation through the view transform, the
//     projection's divide by w > 0 -- the clipper guarantees w >= near > 0 -- and the viewport
//     scale by +W/2, -H/2; the y flip makes it negative. The same holds orthographically, w = 1.)
//     Returning false skips the triangle (no fragment, no endTriangle).
//   * Then `sink.fragment(size_t pixel, size_t t, double d)` for every covered center, pixel =
//     y * width + x, with d bit-identical to viewDepthAt(plane, x + 0.5, y + 0.5) (the same IEEE
//     operations, never stepped). Within a triangle fragments come in ascending pixel order (rows
//     downwards, each row left to right, on every coverage path); no pixel is visited twice for
//     one triangle. The ordering audit's banded draws rely on the order (analysis/audits/ordering.cpp).
//   * Then `sink.endTriangle(size_t t, uint64_t fragments)` with the number of fragment() calls
//     made for it (possibly 0: a sub-pixel triangle between centers).
//   Coverage is the top-left fill rule on pixel centers in fixed point (kSubpixelBits), exactly;
//   the three coverage paths (small SIMD block, per-row span, box scan) give the same set.
// The sink is a template parameter, so its calls inline: a sink costs what its body costs. A sink
// declaring `static constexpr bool kPlaneValue = true` receives, instead of d, the plane value v
// (d = 1 / v in perspective, v itself orthographically) and computes d itself, with the same IEEE
// operation (the z-buffer does it for a batch of fragments in SIMD lanes: raster_kernel.h).
#pragma once

#include <algorithm>
#include <bit>
#include <cassert>
#include <cstddef>
#include <cstdint>
#include <utility>

#if defined(__AVX2__)
#include <immintrin.h>
#elif defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "render/raster.h"

namespace va {

// The implementation lives in an inline namespace named after the instruction set the including
// translation unit is compiled for (raster_avx2.cpp defines VA_RASTER_ISA as avx2 before including
// this header): inline functions and template instantiations compiled with -mavx2 then have their
// own mangled names, so the linker can never hand an AVX2 body to a caller of the baseline build
// (Embree's `namespace isa` scheme). Callers write raster_detail::name as before.
#ifndef VA_RASTER_ISA
#define VA_RASTER_ISA base
#endif

namespace raster_detail {
inline namespace VA_RASTER_ISA {

// Range of fixed-point coordinates the int64 edge functions hold without overflow. With
// |x|, |y| <= 2^29 every vertex difference is below 2^30 + 2^29 < 2^31, each product of two
// differences below 2^62, and the edge function (difference of two products, plus the bias) below
// 2^63. That is 2^21 pixels (2 million) outside the viewport, far beyond the clipper's guard band
// (ClipSettings::guardBandPixels = 8192, i.e. 2^21 in fixed point). Triangles beyond it violate the
// clip stage's contract; they are skipped rather than risk a wrapped sign.
constexpr int64_t kMaxFixed = int64_t(1) << 29;

// Pixel x's sample (center) in fixed point is x * kSubpixelOne + kHalf.
constexpr int64_t kHalf = kSubpixelOne / 2;

// Small triangles: a box of at most 8 x 8 centers is tested as one block of 4 x 4 or 8 x 8 samples
// in 32-bit lanes, when the vertex extent is at most kBlockExtent in both axes. 32 bits suffice
// then: every sample of the block lies within the vertex box grown by 7 pixels (the box of centers
// lies inside the vertex box), so |E| = |dx (sy - ay) - dy (sx - ax)| <= 2 ext (ext + 7 px) with
// ext <= 64 px = 2^14: 2 * 2^14 * (2^14 + 1792) < 2^30; the bias and the steps stay below that.
constexpr int64_t kBlockExtent = int64_t(64) << kSubpixelBits;
constexpr uint64_t kRowStarts = 0x0101010101010101ull;  // bit 0 of each of 8 rows

// Coverage bits (bit 8 row + column) of the kRows x kCols block whose first center has the edge
// values r[k] (bias included), stepX/stepY as in EdgeSetup, all in int32 (see kBlockExtent).
// No data-dependent branch: the loops have constant trip counts and unroll.
template <int kRows, int kCols>
[[gnu::always_inline]] inline uint64_t blockCoverage(const int32_t r[3], const int32_t stepX[3], const int32_t stepY[3]) {
#if defined(__SSE2__)
    // Lanes are columns; a center is outside when any edge value is negative, i.e. when the sign
    // bit of e0 | e1 | e2 is set (movemask gathers four sign bits).
    constexpr int kVecs = kCols / 4;
    __m128i e[kVecs][3], dy[3];
    for (int k = 0; k < 3; ++k) {
        for (int v = 0; v < kVecs; ++v) {
            const int32_t c = r[k] + 4 * v * stepX[k];  // column 4v
            e[v][k] = _mm_set_epi32(c + 3 * stepX[k], c + 2 * stepX[k], c + stepX[k], c);
        }
        dy[k] = _mm_set1_epi32(stepY[k]);
    }
    uint64_t outside = 0;
    for (int row = 0; row < kRows; ++row)
        for (int v = 0; v < kVecs; ++v) {
            const __m128i any = _mm_or_si128(_mm_or_si128(e[v][0], e[v][1]), e[v][2]);
            outside |= uint64_t(_mm_movemask_ps(_mm_castsi128_ps(any))) << (8 * row + 4 * v);
            for (int k = 0; k < 3; ++k) e[v][k] = _mm_add_epi32(e[v][k], dy[k]);
        }
    return ~outside;
#else
    uint64_t inside = 0;
    for (int row = 0; row < kRows; ++row)
        for (int col = 0; col < kCols; ++col) {
            const int32_t e0 = r[0] + row * stepY[0] + col * stepX[0];
            const int32_t e1 = r[1] + row * stepY[1] + col * stepX[1];
            const int32_t e2 = r[2] + row * stepY[2] + col * stepX[2];
            inside |= uint64_t((e0 | e1 | e2) >= 0) << (8 * row + col);
        }
    return inside;
#endif
}

// Boxes at least this many pixels wide use the per-row span solver instead of scanning centers
// (narrower ones that are not small blocks scan every center of the box).
constexpr int64_t kSpanMinWidth = 12;

// floor(a / b) for b > 0 (C++ division truncates toward zero).
inline int64_t floorDiv(int64_t a, int64_t b) {
    const int64_t q = a / b;
    return q - ((a % b) < 0 ? 1 : 0);
}

// Top-left fill rule, for a triangle walked with positive signed area
//   A = (x1 - x0)(y2 - y0) - (y1 - y0)(x2 - x0) > 0   (fixed point, y down: clockwise on screen).
// The edge a -> b, with (dx, dy) = b - a, has the edge function
//   E(p) = dx (p.y - a.y) - dy (p.x - a.x),
// positive on the triangle's side (E_01(v2) = A > 0); its inward normal is (-dy, dx). A center with
// E > 0 on all three edges is inside. A center with E == 0 lies exactly on the edge's line and
// belongs to the triangle only if the edge is
//   a left edge:  the interior lies at larger x   <=> -dy > 0 <=> dy < 0, or
//   a top edge:   horizontal, interior below it (larger y on screen) <=> dy == 0 and dx > 0.
// A neighbour sharing the edge has it with the opposite direction (-dx, -dy) once it is walked with
// the same winding (both are oriented by the swap in forEachFragment), and exactly one of (dx, dy),
// (-dx, -dy) satisfies "dy < 0 or (dy == 0 and dx > 0)" when the edge is not a point. So a center on
// a shared edge goes to exactly one of the two triangles (no double coverage, no crack), for either
// input winding. The rule becomes an integer bias: inside <=> E + bias >= 0 with bias = 0 for
// top-left edges (E >= 0) and -1 otherwise (E > 0 <=> E - 1 >= 0 for integers).
inline bool isTopLeft(int64_t dx, int64_t dy) { return dy < 0 || (dy == 0 && dx > 0); }

struct EdgeSetup {
    int64_t value;  // E + bias at the first center of the box
    int64_t stepX;  // change of E from one pixel center to the next one to the right
    int64_t stepY;  // change of E from one row of centers to the next one down
};

inline EdgeSetup setupEdge(int64_t ax, int64_t ay, int64_t bx, int64_t by, int64_t sx, int64_t sy) {
    const int64_t dx = bx - ax, dy = by - ay;
    EdgeSetup e;
    // The bias without branches or flags: t = dy 2^32 - dx is negative exactly when the edge is
    // top-left (dy < 0, or dy == 0 and dx > 0; |dx| < 2^31 by kMaxFixed), so bias = ~(t >> 63)
    // is 0 for top-left edges and -1 otherwise (isTopLeft states the same rule plainly).
    const int64_t t = dy * (int64_t(1) << 32) - dx;
    const int64_t bias = ~(t >> 63);
    assert((bias == 0) == isTopLeft(dx, dy));
    e.value = dx * (sy - ay) - dy * (sx - ax) + bias;
    e.stepX = -dy * kSubpixelOne;
    e.stepY = dx * kSubpixelOne;
    return e;
}

// Pixel-center box of a triangle: the centers (x + 0.5, y + 0.5) inside its vertex box, before
// clamping. x*one + half >= minX <=> x >= ceil((minX - half) / one) = (minX - half + one - 1) >> bits
// (arithmetic shift floors, also for negatives), and x*one + half <= maxX <=> x <= (maxX - half) >> bits.
inline int64_t firstCenter(int64_t minCoord) { return (minCoord - kHalf + kSubpixelOne - 1) >> kSubpixelBits; }
inline int64_t lastCenter(int64_t maxCoord) { return (maxCoord - kHalf) >> kSubpixelBits; }

// Coverage of one oriented triangle (positive signed area; steps 3-4 of the walk below) over the
// pixel-center box [bx0, bx1] x [by0, by1], which must lie inside the triangle's own box of centers
// (a tile's part of it, or all of it): `frag(size_t pixel, int64_t x, int64_t y)` is called once
// for every covered center of the box, pixel = y * W + x. ext is the larger vertex extent
// (maxX - minX, maxY - minY) in fixed point. Exact integer tests: any sub-box of the triangle's box
// gets exactly the covered centers that lie in it, whichever of the three paths it takes.
template <class Frag>
inline void coverTriangle(int64_t x0, int64_t y0, int64_t x1, int64_t y1, int64_t x2, int64_t y2, int64_t ext,
                          int64_t bx0, int64_t bx1, int64_t by0, int64_t by1, size_t W, Frag &&frag) {
    // Edge functions at the box's first center; edge k is the one opposite vertex k.
    const int64_t sx = bx0 * kSubpixelOne + kHalf, sy = by0 * kSubpixelOne + kHalf;
    const EdgeSetup e0 = setupEdge(x1, y1, x2, y2, sx, sy);
    const EdgeSetup e1 = setupEdge(x2, y2, x0, y0, sx, sy);
    const EdgeSetup e2 = setupEdge(x0, y0, x1, y1, sx, sy);

    int64_t r0 = e0.value, r1 = e1.value, r2 = e2.value;
    const int64_t boxW = bx1 - bx0 + 1, boxH = by1 - by0 + 1;
    if (((boxW - 1) | (boxH - 1)) < 8 && ext <= kBlockExtent) {
        // Small (most triangles of a dense mesh): one 4 x 4 or 8 x 8 block of inside tests
        // ((w-1)|(h-1) < n <=> both sides <= n for n a power of two), then the set bits.
        const int32_t r[3] = {int32_t(r0), int32_t(r1), int32_t(r2)};
        const int32_t stepX[3] = {int32_t(e0.stepX), int32_t(e1.stepX), int32_t(e2.stepX)};
        const int32_t stepY[3] = {int32_t(e0.stepY), int32_t(e1.stepY), int32_t(e2.stepY)};
        const uint64_t cover = ((boxW - 1) | (boxH - 1)) < 4 ? blockCoverage<4, 4>(r, stepX, stepY)
                                                           : blockCoverage<8, 8>(r, stepX, stepY);
        // Bits of the block inside the box: boxW columns of each of the first boxH rows.
        const uint64_t boxBits = ((uint64_t(1) << boxW) - 1) * (kRowStarts >> (64 - 8 * boxH));
        uint64_t mask = cover & boxBits;
        while (mask) {
            const int bit = std::countr_zero(mask);
            mask &= mask - 1;
            const int64_t x = bx0 + (bit & 7), y = by0 + (bit >> 3);
            frag(size_t(y) * W + size_t(x), x, y);
        }
    } else if (boxW < kSpanMinWidth) {
        // Narrow box: test every center, stepping the edge functions exactly.
        for (int64_t y = by0; y <= by1; ++y) {
            const size_t row = size_t(y) * W;
            int64_t c0 = r0, c1 = r1, c2 = r2;
            for (int64_t x = bx0; x <= bx1; ++x) {
                if ((c0 | c1 | c2) >= 0) frag(row + size_t(x), x, y);
                c0 += e0.stepX;
                c1 += e1.stepX;
                c2 += e2.stepX;
            }
            r0 += e0.stepY;
            r1 += e1.stepY;
            r2 += e2.stepY;
        }
    } else {
        // Wide box: per row, edge k covers offset j (x = bx0 + j) iff r_k + j * stepX_k >= 0:
        //   stepX > 0: j >= ceil(-r / stepX) = -floor(r / stepX)
        //   stepX < 0: j <= floor(r / -stepX)
        //   stepX = 0: every j if r >= 0, none otherwise.
        const int64_t lastJ = bx1 - bx0;
        const EdgeSetup *edges[3] = {&e0, &e1, &e2};
        for (int64_t y = by0; y <= by1; ++y) {
            const int64_t r[3] = {r0, r1, r2};
            int64_t lo = 0, hi = lastJ;
            for (int k = 0; k < 3; ++k) {
                const int64_t s = edges[k]->stepX;
                if (s > 0) lo = std::max(lo, -floorDiv(r[k], s));
                else if (s < 0) hi = std::min(hi, floorDiv(r[k], -s));
                else if (r[k] < 0) hi = -1;
            }
            const size_t row = size_t(y) * W;
            // A callback that takes a whole row's span (frag.span) gets it in one call.
            if constexpr (requires { frag.span(row, bx0, bx1, y); }) {
                if (lo <= hi) frag.span(row, bx0 + lo, bx0 + hi, y);
            } else {
                for (int64_t x = bx0 + lo; x <= bx0 + hi; ++x) frag(row + size_t(x), x, y);
            }
            r0 += e0.stepY;
            r1 += e1.stepY;
            r2 += e2.stepY;
        }
    }
}

// Steps 1-2 of the walk for one triangle's fixed-point corners v[0..5] in a W x H viewport: false
// when it cannot produce a fragment (its box of pixel centers is empty or outside the viewport, a
// coordinate lies outside +-kMaxFixed -- a clip-stage contract violation -- or its snapped signed
// area is zero); otherwise the corners with v1, v2 swapped when the winding is the front one (so
// every triangle is walked with positive area), the box clamped to the viewport, the larger vertex
// extent. Shared by the walk and the tiled path's binning, so both see the same triangles.
struct TriangleSetup {
    int64_t x0, y0, x1, y1, x2, y2;
    int64_t bx0, bx1, by0, by1;
    int64_t ext;
    bool frontWinding;  // counter-clockwise as the viewer sees it: negative area before the swap
};
[[gnu::always_inline]] inline bool setupTriangle(const int32_t *v, int64_t W, int64_t H, TriangleSetup *s) {
    int64_t x0 = v[0], y0 = v[1], x1 = v[2], y1 = v[3], x2 = v[4], y2 = v[5];
    const int64_t minX = std::min(x0, std::min(x1, x2)), maxX = std::max(x0, std::max(x1, x2));
    const int64_t minY = std::min(y0, std::min(y1, y2)), maxY = std::max(y0, std::max(y1, y2));
    const int64_t bx0 = std::max<int64_t>(firstCenter(minX), 0), bx1 = std::min<int64_t>(lastCenter(maxX), W - 1);
    const int64_t by0 = std::max<int64_t>(firstCenter(minY), 0), by1 = std::min<int64_t>(lastCenter(maxY), H - 1);
    if (bx0 > bx1 || by0 > by1) return false;  // no center inside the box (or box outside the viewport)
    if (minX < -kMaxFixed || maxX > kMaxFixed || minY < -kMaxFixed || maxY > kMaxFixed) return false;
    // Orientation: twice the signed area; zero area draws nothing, negative (counter-clockwise as
    // the viewer sees it: the front winding) is swapped so one inside test serves both.
    const int64_t area = (x1 - x0) * (y2 - y0) - (y1 - y0) * (x2 - x0);
    if (area == 0) return false;
    if (area < 0) {
        std::swap(x1, x2);
        std::swap(y1, y2);
    }
    *s = {x0, y0, x1, y1, x2, y2, bx0, bx1, by0, by1, std::max(maxX - minX, maxY - minY), area < 0};
    return true;
}

// The fragment call of the contract above: v is the plane value at the center.
template <bool kPerspective, class Sink>
[[gnu::always_inline]] inline void emitFragment(Sink &sink, size_t idx, size_t t, double v) {
    if constexpr (requires { Sink::kPlaneValue; }) sink.fragment(idx, t, v);
    else sink.fragment(idx, t, kPerspective ? 1.0 / v : v);
}

// The fragment callback of shadeTriangle: the depth plane's value at each covered center. A sink
// with fragmentSpan(row, x0, x1, pa, rowTerm, pc) (and kPlaneValue) takes a row's span of centers
// x0..x1 in one call, to compute (pa * (x + 0.5) + rowTerm) + pc itself, rowTerm = pb * (y + 0.5):
// the same operations in the same order as per center, so the same values.
template <bool kPerspective, class Sink>
struct ShadeFragments {
    Sink &sink;
    size_t t;
    double pa, pb, pc;
    uint64_t count = 0;

    [[gnu::always_inline]] void operator()(size_t idx, int64_t x, int64_t y) {
        const double pv = (pa * (double(x) + 0.5) + pb * (double(y) + 0.5)) + pc;
        ++count;
        emitFragment<kPerspective>(sink, idx, t, pv);
    }
    [[gnu::always_inline]] void span(size_t row, int64_t x0, int64_t x1, int64_t y)
        requires requires(Sink &s) { s.fragmentSpan(size_t(0), int64_t(0), int64_t(0), 0.0, 0.0, 0.0); }
    {
        count += uint64_t(x1 - x0 + 1);
        sink.fragmentSpan(row, x0, x1, pa, pb * (double(y) + 0.5), pc);
    }
};

// Steps 2-5 of the walk below for triangle t once its coverage is known: the depth plane (invalid:
// nothing), beginTriangle, then for every covered center -- `cover(frag)` calls frag(pixel, x, y)
// once per center -- the depth straight from the plane exactly as evalDepthPlane writes it
// ((a*px + b*py) + c) to the sink, then endTriangle with the count.
template <bool kPerspective, class Sink, class Cover>
[[gnu::always_inline]] inline void shadeTriangle(const ScreenTriangles &tris, size_t t, bool frontWinding, Sink &sink,
                                                 Cover &&cover) {
    const DepthPlane &plane = tris.planes[tris.plane[t]];
    if (!plane.valid) return;
    if (!sink.beginTriangle(t, frontWinding)) return;
    ShadeFragments<kPerspective, Sink> frag{sink, t, plane.a, plane.b, plane.c};
    cover(frag);
    sink.endTriangle(t, frag.count);
}

// Steps 2-5 for triangle t, whose step 1 (setupTriangle) gave ts: coverage by coverTriangle.
template <bool kPerspective, class Sink>
[[gnu::always_inline]] inline void walkSetUpTriangle(const ScreenTriangles &tris, size_t t, const TriangleSetup &ts,
                                                     size_t W, Sink &sink) {
    shadeTriangle<kPerspective>(tris, t, ts.frontWinding, sink, [&](auto &&frag) {
        coverTriangle(ts.x0, ts.y0, ts.x1, ts.y1, ts.x2, ts.y2, ts.ext, ts.bx0, ts.bx1, ts.by0, ts.by1, W, frag);
    });
}

// The walk for one projection (see the contract above; the steps per triangle):
//   1. the bounding box of the *pixel centers* it may cover, clamped to the viewport; empty box ->
//      done (the common case for the benchmark scene's sub-pixel triangles: no edge setup at all);
//   2. orientation: twice the signed area in fixed point; zero -> skipped, negative (the front
//      winding) -> swap v1, v2 so every triangle is walked with the same inside test;
//   3. edge functions in int64 at the first center, stepped exactly by integer increments;
//   4. coverage (coverTriangle), by the size of the box (all give the same set of centers, exactly):
//      - small (box <= 8 x 8 centers, vertex extent <= 64 px): one 4 x 4 or 8 x 8 block of inside
//        tests in 32-bit SIMD lanes into a bit mask, without data-dependent branches;
//      - wide (box >= kSpanMinWidth): each row's covered span solved with integer floor division,
//        so large triangles cost per row, not per empty center of their box;
//      - otherwise: every center of the box, stepping the edge functions;
//   5. per covered center: view depth straight from the DepthPlane, then sink.fragment.
template <bool kPerspective, class Sink>
void walkFragments(const ScreenTriangles &tris, int width, int height, Sink &sink) {
    const int64_t W = width, H = height;
    if (W <= 0 || H <= 0) return;
    const int32_t *const xy = tris.xy.data();
    const size_t n = tris.size();
    for (size_t t = 0; t < n; ++t) {
        TriangleSetup ts;
        if (!setupTriangle(xy + 6 * t, W, H, &ts)) continue;
        walkSetUpTriangle<kPerspective>(tris, t, ts, size_t(W), sink);
    }
}

#if defined(__AVX2__)
// walkFragments with steps 1-4 done for 8 consecutive triangles at once in AVX2 int32 lanes, for
// the triangles that dominate dense meshes: a box of at most 4 x 4 centers and a vertex extent of at
// most kBlockExtent (the small-block case of coverTriangle, whose int32 bounds hold for it). Per
// group of 8: the box of centers, the empty-box and range exits, twice the signed area (exact in
// int32 when the extent is at most 2^14: each product is below 2^28), the swap to positive area, the
// three edge functions with the top-left bias at the box's first center and the 4 x 4 block of
// inside tests, all branch-free; then, in submission order, each small triangle's covered centers
// (bits of a 16-bit mask) go to the sink, and every other triangle takes the scalar walk
// (setupTriangle, walkSetUpTriangle). Same contract and the same fragments as walkFragments: the
// lanes compute the same integers (all exact, no overflow within the bounds above) and a triangle
// the lanes find empty (box, range, zero area) is one setupTriangle rejects.
//
// Bands: only the rows [rowBegin, rowEnd) are walked (every box is clamped to them), so bands of
// one viewport can run concurrently, each in submission order. Before each triangle's
// beginTriangle, sink.band(home, shared) says whether the band holds the first row of the
// triangle's box (home: count the triangle once) and whether its box reaches beyond the band
// (shared: whether it drew anything is known only over all bands).
template <bool kPerspective, class Sink>
void walkFragmentsBatched(const ScreenTriangles &tris, int width, int height, int rowBegin, int rowEnd, Sink &sink) {
    const int64_t W = width, H = height;
    if (W <= 0 || H <= 0 || rowBegin >= rowEnd) return;
    const int32_t *const xy = tris.xy.data();
    const uint32_t *const planeIndex = tris.plane.data();
    const DepthPlane *const planes = tris.planes.data();
    const size_t n = tris.size();
    auto scalar = [&](size_t t) {
        TriangleSetup ts;
        if (!setupTriangle(xy + 6 * t, W, H, &ts)) return;
        const bool home = ts.by0 >= rowBegin, shared = ts.by0 < rowBegin || ts.by1 >= rowEnd;
        ts.by0 = std::max<int64_t>(ts.by0, rowBegin);
        ts.by1 = std::min<int64_t>(ts.by1, rowEnd - 1);
        if (ts.by0 > ts.by1) return;
        sink.band(home, shared);
        walkSetUpTriangle<kPerspective>(tris, t, ts, size_t(W), sink);
    };

    const __m256i zero = _mm256_setzero_si256(), ones = _mm256_set1_epi32(-1);
    const __m256i lo = _mm256_set1_epi32(int32_t(-kMaxFixed - 1)), hi = _mm256_set1_epi32(int32_t(kMaxFixed + 1));
    const __m256i lastX = _mm256_set1_epi32(int32_t(W - 1)), lastY = _mm256_set1_epi32(int32_t(H - 1));
    const __m256i bandFirst = _mm256_set1_epi32(rowBegin), bandLast = _mm256_set1_epi32(rowEnd - 1);
    const __m256i three = _mm256_set1_epi32(3), extLimit = _mm256_set1_epi32(int32_t(kBlockExtent));
    const __m256i half = _mm256_set1_epi32(int32_t(kHalf));
    const __m256i rowPattern = _mm256_set1_epi32(0x1111);
    alignas(32) int32_t cover[8], boxX[8], boxY[8];
    constexpr size_t kPlaneAhead = 64;
    bool drawing = true;

    size_t t = 0;
    for (; t + 8 <= n; t += 8) {
        const int *base = xy + 6 * t;
        // The depth planes of the triangles kPlaneAhead later (their index is a dependent load that
        // the hardware prefetcher does not follow): four lines, two planes each when consecutive.
        // Only while the walk is drawing (the last group had a lane to draw): consecutive triangles
        // are mostly neighbours, and a band skips most groups of a mesh drawn elsewhere.
        if (drawing && t + kPlaneAhead + 8 <= n)
            for (size_t k = 0; k < 8; k += 2) __builtin_prefetch(planes + planeIndex[t + kPlaneAhead + k]);
        // Corners of the 8 triangles into lanes (a 4 x 4 transpose in each 128-bit half: triangle k
        // in lane k): per triangle k (and k + 4 in the upper half) the words x0 y0 x1 y1 and x1 y1 x2 y2.
        auto pair = [&](int k, int offset) {
            return _mm256_inserti128_si256(
                _mm256_castsi128_si256(_mm_loadu_si128(reinterpret_cast<const __m128i *>(base + 6 * k + offset))),
                _mm_loadu_si128(reinterpret_cast<const __m128i *>(base + 6 * (k + 4) + offset)), 1);
        };
        const __m256i a0 = pair(0, 0), a1 = pair(1, 0), a2 = pair(2, 0), a3 = pair(3, 0);
        const __m256i b0 = pair(0, 2), b1 = pair(1, 2), b2 = pair(2, 2), b3 = pair(3, 2);
        const __m256i a01 = _mm256_unpacklo_epi32(a0, a1), a23 = _mm256_unpacklo_epi32(a2, a3);  // x0 x0 y0 y0
        const __m256i c01 = _mm256_unpackhi_epi32(a0, a1), c23 = _mm256_unpackhi_epi32(a2, a3);  // x1 x1 y1 y1
        const __m256i d01 = _mm256_unpackhi_epi32(b0, b1), d23 = _mm256_unpackhi_epi32(b2, b3);  // x2 x2 y2 y2
        const __m256i x0 = _mm256_unpacklo_epi64(a01, a23), y0 = _mm256_unpackhi_epi64(a01, a23);
        __m256i x1 = _mm256_unpacklo_epi64(c01, c23), y1 = _mm256_unpackhi_epi64(c01, c23);
        __m256i x2 = _mm256_unpacklo_epi64(d01, d23), y2 = _mm256_unpackhi_epi64(d01, d23);
        const __m256i minX = _mm256_min_epi32(x0, _mm256_min_epi32(x1, x2));
        const __m256i maxX = _mm256_max_epi32(x0, _mm256_max_epi32(x1, x2));
        const __m256i minY = _mm256_min_epi32(y0, _mm256_min_epi32(y1, y2));
        const __m256i maxY = _mm256_max_epi32(y0, _mm256_max_epi32(y1, y2));
        // Outside +-kMaxFixed: setupTriangle rejects it, so the lane is skipped (its other values,
        // computed with wrapping int32 arithmetic, are not used).
        const __m256i outOfRange = _mm256_or_si256(_mm256_or_si256(_mm256_cmpgt_epi32(lo, minX), _mm256_cmpgt_epi32(maxX, hi)),
                                                   _mm256_or_si256(_mm256_cmpgt_epi32(lo, minY), _mm256_cmpgt_epi32(maxY, hi)));
        // Box of centers (firstCenter, lastCenter), clamped to the viewport.
        const __m256i up = _mm256_set1_epi32(int32_t(kSubpixelOne - 1 - kHalf));
        const __m256i bx0 = _mm256_max_epi32(_mm256_srai_epi32(_mm256_add_epi32(minX, up), kSubpixelBits), zero);
        const __m256i bx1 = _mm256_min_epi32(_mm256_srai_epi32(_mm256_sub_epi32(maxX, half), kSubpixelBits), lastX);
        const __m256i vy0 = _mm256_max_epi32(_mm256_srai_epi32(_mm256_add_epi32(minY, up), kSubpixelBits), zero);
        const __m256i vy1 = _mm256_min_epi32(_mm256_srai_epi32(_mm256_sub_epi32(maxY, half), kSubpixelBits), lastY);
        const __m256i by0 = _mm256_max_epi32(vy0, bandFirst), by1 = _mm256_min_epi32(vy1, bandLast);
        const __m256i notHome = _mm256_cmpgt_epi32(bandFirst, vy0);
        const unsigned notHomeBits = unsigned(_mm256_movemask_ps(_mm256_castsi256_ps(notHome)));
        const unsigned sharedBits =
            unsigned(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_or_si256(notHome, _mm256_cmpgt_epi32(vy1, bandLast)))));
        const __m256i boxW1 = _mm256_sub_epi32(bx1, bx0), boxH1 = _mm256_sub_epi32(by1, by0);  // width - 1, height - 1
        const __m256i emptyBox = _mm256_or_si256(_mm256_cmpgt_epi32(zero, boxW1), _mm256_cmpgt_epi32(zero, boxH1));
        const __m256i notSmall =
            _mm256_or_si256(_mm256_or_si256(_mm256_cmpgt_epi32(boxW1, three), _mm256_cmpgt_epi32(boxH1, three)),
                            _mm256_or_si256(_mm256_cmpgt_epi32(_mm256_sub_epi32(maxX, minX), extLimit),
                                            _mm256_cmpgt_epi32(_mm256_sub_epi32(maxY, minY), extLimit)));
        // Twice the signed area (exact for small lanes), the swap of v1 and v2 where it is negative.
        const __m256i area =
            _mm256_sub_epi32(_mm256_mullo_epi32(_mm256_sub_epi32(x1, x0), _mm256_sub_epi32(y2, y0)),
                             _mm256_mullo_epi32(_mm256_sub_epi32(y1, y0), _mm256_sub_epi32(x2, x0)));
        const __m256i front = _mm256_cmpgt_epi32(zero, area);
        const __m256i skip = _mm256_or_si256(_mm256_or_si256(outOfRange, emptyBox),
                                             _mm256_andnot_si256(notSmall, _mm256_cmpeq_epi32(area, zero)));
        const unsigned skipBits = unsigned(_mm256_movemask_ps(_mm256_castsi256_ps(skip)));
        const unsigned smallBits = unsigned(_mm256_movemask_ps(_mm256_castsi256_ps(notSmall))) ^ 0xFFu;
        const __m256i sx1 = _mm256_blendv_epi8(x1, x2, front), sy1 = _mm256_blendv_epi8(y1, y2, front);
        x2 = _mm256_blendv_epi8(x2, x1, front);
        y2 = _mm256_blendv_epi8(y2, y1, front);
        x1 = sx1;
        y1 = sy1;
        // Edge functions at the first center of the box, bias included (setupEdge): edge k is the
        // one opposite vertex k. Top-left <=> dy < 0 or (dy == 0 and dx > 0); bias 0 there, else -1.
        const __m256i sx = _mm256_add_epi32(_mm256_slli_epi32(bx0, kSubpixelBits), half);
        const __m256i sy = _mm256_add_epi32(_mm256_slli_epi32(by0, kSubpixelBits), half);
        __m256i e[3], stepX[3], stepY[3];
        auto edge = [&](int k, __m256i ax, __m256i ay, __m256i bx, __m256i by) {
            const __m256i dx = _mm256_sub_epi32(bx, ax), dy = _mm256_sub_epi32(by, ay);
            const __m256i topLeft = _mm256_or_si256(
                _mm256_cmpgt_epi32(zero, dy), _mm256_and_si256(_mm256_cmpeq_epi32(dy, zero), _mm256_cmpgt_epi32(dx, zero)));
            e[k] = _mm256_add_epi32(_mm256_sub_epi32(_mm256_mullo_epi32(dx, _mm256_sub_epi32(sy, ay)),
                                                     _mm256_mullo_epi32(dy, _mm256_sub_epi32(sx, ax))),
                                    _mm256_xor_si256(topLeft, ones));
            stepX[k] = _mm256_slli_epi32(_mm256_sub_epi32(zero, dy), kSubpixelBits);
            stepY[k] = _mm256_slli_epi32(dx, kSubpixelBits);
        };
        edge(0, x1, y1, x2, y2);
        edge(1, x2, y2, x0, y0);
        edge(2, x0, y0, x1, y1);
        // The 4 x 4 block: bit 4 row + column is set where a center is outside (some E + bias < 0).
        __m256i outside = zero;
        for (int row = 0; row < 4; ++row) {
            __m256i c0 = e[0], c1 = e[1], c2 = e[2];
            for (int col = 0; col < 4; ++col) {
                const __m256i any = _mm256_or_si256(_mm256_or_si256(c0, c1), c2);
                outside = _mm256_or_si256(outside, _mm256_slli_epi32(_mm256_srli_epi32(any, 31), 4 * row + col));
                c0 = _mm256_add_epi32(c0, stepX[0]);
                c1 = _mm256_add_epi32(c1, stepX[1]);
                c2 = _mm256_add_epi32(c2, stepX[2]);
            }
            for (int k = 0; k < 3; ++k) e[k] = _mm256_add_epi32(e[k], stepY[k]);
        }
        // Bits of the block inside the box: (2^width - 1) columns in each of the first height rows.
        const __m256i columns = _mm256_sub_epi32(_mm256_sllv_epi32(_mm256_set1_epi32(1), _mm256_sub_epi32(boxW1, ones)), _mm256_set1_epi32(1));
        const __m256i rows = _mm256_srlv_epi32(rowPattern, _mm256_slli_epi32(_mm256_sub_epi32(three, boxH1), 2));
        const __m256i inside = _mm256_andnot_si256(outside, _mm256_mullo_epi32(columns, rows));
        _mm256_store_si256(reinterpret_cast<__m256i *>(cover), inside);
        _mm256_store_si256(reinterpret_cast<__m256i *>(boxX), bx0);
        _mm256_store_si256(reinterpret_cast<__m256i *>(boxY), by0);
        const unsigned frontBits = unsigned(_mm256_movemask_ps(_mm256_castsi256_ps(front)));

        // In submission order: small triangles from their masks, the others through the scalar walk.
        unsigned todo = ~skipBits & 0xFFu;
        drawing = todo != 0;
        while (todo) {
            const int lane = std::countr_zero(todo);
            todo &= todo - 1;
            const size_t tl = t + size_t(lane);
            if (!((smallBits >> lane) & 1)) {
                scalar(tl);
                continue;
            }
            sink.band(!((notHomeBits >> lane) & 1), (sharedBits >> lane) & 1);
            const int64_t bx = boxX[lane], by = boxY[lane];
            shadeTriangle<kPerspective>(tris, tl, (frontBits >> lane) & 1, sink, [&](auto &&frag) {
                for (uint32_t mask = uint32_t(cover[lane]); mask; mask &= mask - 1) {
                    const int bit = std::countr_zero(mask);
                    const int64_t x = bx + (bit & 3), y = by + (bit >> 2);
                    frag(size_t(y) * size_t(W) + size_t(x), x, y);
                }
            });
        }
    }
    for (; t < n; ++t) scalar(t);
}
#endif

}  // namespace VA_RASTER_ISA
}  // namespace raster_detail

// Walks every fragment of `tris` in a width x height viewport into `sink` (contract above).
template <class Sink>
void forEachFragment(const ScreenTriangles &tris, int width, int height, bool orthographic, Sink &sink) {
    if (orthographic) raster_detail::walkFragments<false>(tris, width, height, sink);
    else raster_detail::walkFragments<true>(tris, width, height, sink);
}

}  // namespace va
