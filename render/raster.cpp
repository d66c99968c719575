// The z-buffer rasterizer (raster.h; decisions in docs/rasterizer.md).
//
// Structure: rasterize() clears the buffers, then picks a path (RasterStrategy) and dispatches once
// on (depth format, projection, exactDepth) to a function of raster_kernel.h, so the per-fragment
// depth encoding is inlined and branch-free: the batched walk (AVX2, raster_avx2.cpp; in bands of
// rows on several threads), the plain walk of raster_core.h with the z-buffer as its sink (the
// reference), or the tiled path below (binning here, the tile kernel in raster_kernel.h). Each
// resolves a pixel's fragments in submission order with LESS written as selects; the audits'
// options (single-sided winding, per-source fragment counts) are tested once per triangle.
#include "render/raster.h"

#include <algorithm>
#include <cmath>
#include <limits>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "render/depth_format_impl.h"
#include "render/large_pages.h"
#include "render/raster_core.h"
#include "render/raster_kernel.h"
#include "render/recycle.h"

namespace va {

namespace {

// ---- The tiled path (docs/rasterizer.md: Tiles) ----
using namespace raster_detail;

// One binning chunk: a run of consecutive triangles and what it put into each tile.
struct BinChunk {
    std::vector<std::vector<BinEntry>> tiles;  // per tile, in submission order
    std::vector<uint32_t> multiCounts;         // per multi-tile triangle: fragments over all tiles
    uint64_t backWinding = 0;
};

struct TileGrid {
    int shift;
    int64_t cols, rows, width, height;
    size_t count() const { return size_t(cols * rows); }
};

// Setup and binning of triangles [t0, t1): the walk's steps 1-2 (setupTriangle, the depth plane,
// single-sided winding) once per triangle, then the triangle goes to every tile its
// box of centers meets. A triangle spanning several tiles is tested against each tile's part of its
// box: when one edge has all four corner centers of that part outside, the tile is skipped
// (whole-tile reject); when all three edges have all four inside, the tile is marked full (whole-
// tile accept: the kernel emits every center without edge tests). Both are exact: E + bias is
// affine in (x, y), so over a rectangle of centers its minimum and maximum are at corners.
void binChunk(const ScreenTriangles &tris, size_t t0, size_t t1, const TileGrid &g, const uint8_t *singleSided,
              BinChunk &chunk) {
    chunk.tiles.assign(g.count(), {});
    const int32_t *const xy = tris.xy.data();
    for (size_t t = t0; t < t1; ++t) {
        TriangleSetup ts;
        if (!setupTriangle(xy + 6 * t, g.width, g.height, &ts)) continue;
        if (!tris.planes[tris.plane[t]].valid) continue;
        if (singleSided && singleSided[tris.source[t]] && !ts.frontWinding) {
            ++chunk.backWinding;
            continue;
        }
        const int64_t bx0 = ts.bx0, bx1 = ts.bx1, by0 = ts.by0, by1 = ts.by1;
        const int64_t tx0 = bx0 >> g.shift, tx1 = bx1 >> g.shift, ty0 = by0 >> g.shift, ty1 = by1 >> g.shift;
        if (tx0 == tx1 && ty0 == ty1) {
            chunk.tiles[size_t(ty0 * g.cols + tx0)].push_back({uint32_t(t), 0, 0});
            continue;
        }
        const uint32_t multi = uint32_t(chunk.multiCounts.size());
        chunk.multiCounts.push_back(0);
        for (int64_t ty = ty0; ty <= ty1; ++ty)
            for (int64_t tx = tx0; tx <= tx1; ++tx) {
                const int64_t cx0 = std::max(bx0, tx << g.shift), cx1 = std::min(bx1, ((tx + 1) << g.shift) - 1);
                const int64_t cy0 = std::max(by0, ty << g.shift), cy1 = std::min(by1, ((ty + 1) << g.shift) - 1);
                const int64_t sx = cx0 * kSubpixelOne + kHalf, sy = cy0 * kSubpixelOne + kHalf;
                const EdgeSetup edges[3] = {setupEdge(ts.x1, ts.y1, ts.x2, ts.y2, sx, sy),
                                            setupEdge(ts.x2, ts.y2, ts.x0, ts.y0, sx, sy),
                                            setupEdge(ts.x0, ts.y0, ts.x1, ts.y1, sx, sy)};
                bool outside = false, inside = true;
                for (const EdgeSetup &e : edges) {
                    const int64_t right = e.stepX * (cx1 - cx0), down = e.stepY * (cy1 - cy0);
                    const int64_t lo = e.value + std::min<int64_t>(right, 0) + std::min<int64_t>(down, 0);
                    const int64_t hi = e.value + std::max<int64_t>(right, 0) + std::max<int64_t>(down, 0);
                    outside |= hi < 0;
                    inside &= lo >= 0;
                }
                if (outside) continue;
                chunk.tiles[size_t(ty * g.cols + tx)].push_back({uint32_t(t), multi, kMultiTile | (inside ? kFullTile : 0u)});
            }
    }
}

// The threads rasterize() may use: the arena's concurrency within the global_control limit.
int availableThreads() {
    const size_t global = tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism);
    return int(std::max<size_t>(1, std::min<size_t>(global, size_t(tbb::this_task_arena::max_concurrency()))));
}

void rasterizeTiled(const ScreenTriangles &tris, const ZBufferSettings &settings, const RasterStrategy &strategy,
                    int threads, ZBuffer &zb, ZBufferStats &st) {
    TileGrid g;
    g.shift = strategy.tileShift > 0 ? std::clamp(strategy.tileShift, 3, 16) : kDefaultTileShift;
    g.width = zb.width;
    g.height = zb.height;
    g.cols = (g.width + (int64_t(1) << g.shift) - 1) >> g.shift;
    g.rows = (g.height + (int64_t(1) << g.shift) - 1) >> g.shift;

    // Binning in chunks of consecutive triangles (in parallel; each chunk keeps submission order).
    const size_t n = tris.size();
    constexpr size_t kChunk = size_t(1) << 14;
    const size_t chunkCount = threads > 1 ? std::max<size_t>(1, (n + kChunk - 1) / kChunk) : 1;
    std::vector<BinChunk> chunks(chunkCount);
    auto bin = [&](size_t c) {
        binChunk(tris, n * c / chunkCount, n * (c + 1) / chunkCount, g, settings.singleSided, chunks[c]);
    };
    if (chunkCount > 1) tbb::parallel_for(size_t(0), chunkCount, bin);
    else bin(0);

    // Per tile, its lists from every chunk in chunk order.
    std::vector<BinList> lists(g.count() * chunkCount);
    for (size_t tile = 0; tile < g.count(); ++tile)
        for (size_t c = 0; c < chunkCount; ++c)
            lists[tile * chunkCount + c] = {chunks[c].tiles[tile].data(), chunks[c].tiles[tile].size(),
                                            chunks[c].multiCounts.data()};

    const bool perspective = !settings.orthographic;
    ShadeFn shade = nullptr;
#if defined(__x86_64__) || defined(__i386__)
    if (strategy.allowAvx2 && __builtin_cpu_supports("avx2"))
        shade = shadeFunctionAvx2(settings.encoder.format, perspective, settings.exactDepth);
#endif
    if (!shade) shade = shadeFunctionBase(settings.encoder.format, perspective, settings.exactDepth);
    const ShadeTarget target{tris.xy.data(),      tris.source.data(),          tris.plane.data(),
                             tris.planes.data(),  &settings.encoder,           settings.fragmentsPerSource,
                             threads > 1,         size_t(g.width),             PixelBuffers(zb)};
    std::vector<TileCounts> counts(g.count());
    auto shadeOne = [&](size_t tile) {
        const int64_t tx = int64_t(tile) % g.cols, ty = int64_t(tile) / g.cols;
        const TileWork work{tx << g.shift, std::min(((tx + 1) << g.shift) - 1, g.width - 1), ty << g.shift,
                            std::min(((ty + 1) << g.shift) - 1, g.height - 1), &lists[tile * chunkCount], chunkCount};
        shade(target, work, counts[tile]);
    };
    if (threads > 1) tbb::parallel_for(size_t(0), g.count(), shadeOne);
    else for (size_t tile = 0; tile < g.count(); ++tile) shadeOne(tile);

    // Integer sums: the same in any order, so the same for any thread count.
    uint64_t drawn = 0;
    for (const TileCounts &c : counts) {
        st.fragments += c.fragments;
        st.depthPasses += c.passes;
        st.outOfRangeFragments += c.outOfRange;
        drawn += c.drawnSingle;
    }
    for (const BinChunk &c : chunks) {
        for (uint32_t m : c.multiCounts) drawn += m != 0 ? 1 : 0;
        st.trianglesBackWinding += c.backWinding;
    }
    st.trianglesDrawn += drawn;
    st.trianglesEmpty += st.trianglesIn - drawn;
}

}  // namespace

namespace raster_detail {
ShadeFn shadeFunctionBase(DepthFormat format, bool perspective, bool exactDepth) {
    return selectShade(format, perspective, exactDepth);
}
WalkFn walkFunctionBase(DepthFormat format, bool exactDepth) { return selectWalk<false>(format, exactDepth); }
}  // namespace raster_detail

void recycleZBuffer(ZBuffer &zb) {
    ZBuffer kept = std::move(zb);
    zb = ZBuffer{};
    if (kept.key.capacity() + kept.id.capacity() + kept.depth.capacity() + kept.fragments.capacity() +
            kept.passes.capacity() == 0)
        return;
    kept.width = kept.height = 0;
    kept.key.clear(), kept.id.clear(), kept.depth.clear(), kept.fragments.clear(), kept.passes.clear();
    recyclerOf<ZBuffer>().give(std::move(kept));
}

void recycleScreenTriangles(ScreenTriangles &tris) {
    ScreenTriangles kept = std::move(tris);
    tris = ScreenTriangles{};
    if (kept.xy.capacity() == 0 && kept.planes.capacity() == 0) return;
    kept.clear();
    recyclerOf<ScreenTriangles>().give(std::move(kept));
}

ScreenTriangles takeRecycledScreenTriangles() { return recyclerOf<ScreenTriangles>().take(); }

ZBufferResult rasterize(const ScreenTriangles &tris, int width, int height, const ZBufferSettings &settings) {
    return rasterize(tris, width, height, settings, RasterStrategy{});
}

ZBufferResult rasterize(const ScreenTriangles &tris, int width, int height, const ZBufferSettings &settings,
                        const RasterStrategy &strategy) {
    ZBufferResult r;
    ZBuffer &zb = r.buffer;
    zb = recyclerOf<ZBuffer>().take();  // a finished view's buffers, when one gave them back
    zb.width = std::max(width, 0);
    zb.height = std::max(height, 0);
    const size_t pixels = size_t(zb.width) * size_t(zb.height);
    // Huge pages (render/large_pages.h): fragments land all over five 1080p buffers (40 MB).
    assignOnLargePages(zb.key, pixels, std::numeric_limits<uint32_t>::max());
    assignOnLargePages(zb.id, pixels, uint32_t(0));
    assignOnLargePages(zb.depth, pixels, std::numeric_limits<double>::infinity());
    assignOnLargePages(zb.fragments, pixels, uint16_t(0));
    assignOnLargePages(zb.passes, pixels, uint16_t(0));

    ZBufferStats &st = r.stats;
    st.trianglesIn = tris.size();
    const int threads = availableThreads();
    using Path = RasterStrategy::Path;
    WalkFn batched = nullptr;  // the AVX2 batched walk, when allowed and the CPU has it
#if defined(__x86_64__) || defined(__i386__)
    if (strategy.allowAvx2 && __builtin_cpu_supports("avx2"))
        batched = walkFunctionAvx2(settings.encoder.format, settings.exactDepth);
#endif
    const bool tiled =
        strategy.path == Path::tiled || (strategy.path == Path::automatic && threads > 1 && !batched);
    if (pixels > 0 && tiled) {
        rasterizeTiled(tris, settings, strategy, threads, zb, st);
    } else if (pixels > 0) {
        // The batched walk in bands of rows (in parallel): one per thread by default, since each
        // extra band scans every triangle again (docs/rasterizer.md: The batched walk). Otherwise
        // the plain walk over the whole viewport.
        WalkFn walk = strategy.path != Path::plainWalk ? batched : nullptr;
        int bands = 1;
        if (walk) bands = std::clamp(strategy.bands > 0 ? strategy.bands : kBandsPerThread * threads, 1, zb.height);
        else walk = walkFunctionBase(settings.encoder.format, settings.exactDepth);
        std::vector<WalkCounts> counts(static_cast<size_t>(bands));
        std::vector<uint8_t> sharedDrawn(bands > 1 ? tris.size() : 0, uint8_t(0));
        auto runBand = [&](size_t b) {
            const WalkBand band{int(int64_t(zb.height) * int64_t(b) / bands),
                                int(int64_t(zb.height) * int64_t(b + 1) / bands),
                                bands > 1 ? sharedDrawn.data() : nullptr, bands > 1 && threads > 1};
            walk(tris, settings, zb, band, counts[b]);
        };
        if (bands > 1 && threads > 1) tbb::parallel_for(size_t(0), size_t(bands), runBand);
        else for (size_t b = 0; b < size_t(bands); ++b) runBand(b);
        // Integer sums: the same in any order, so the same for any band count and thread count.
        uint64_t drawn = 0;
        for (const WalkCounts &c : counts) {
            st.fragments += c.fragments;
            st.depthPasses += c.passes;
            st.outOfRangeFragments += c.outOfRange;
            st.trianglesBackWinding += c.backWinding;
            drawn += c.drawn;
        }
        for (uint8_t d : sharedDrawn) drawn += d;
        st.trianglesDrawn += drawn;
        st.trianglesEmpty += st.trianglesIn - drawn;
    } else {
        st.trianglesEmpty = tris.size();
    }
    if (settings.exactDepth) {
        // The keys of the stored depths, so the buffer reads the same as a format-tested one.
        for (size_t i = 0; i < zb.id.size(); ++i)
            if (zb.id[i] != 0) zb.key[i] = depthKey(settings.encoder, zb.depth[i]);
    }
    finishZBufferStats(zb, &st);
    return r;
}

#if defined(__x86_64__) || defined(__i386__)
namespace {
// Adds the counts of f[0, n16) to hist (n16: n rounded down to 16), sixteen pixels at a time. Per
// count c below 8, one compare and one subtract add the vector's pixels holding c to sixteen 16-bit
// lane counters: eight independent registers, where one table's increments wait for each other
// through memory. The lanes are summed into hist every 4096 vectors (a lane gains at most one a
// vector); a vector holding a count of 8 or more adds those pixels to hist one by one.
__attribute__((target("avx2"))) size_t histogramAvx2(const uint16_t *f, size_t n, uint64_t *hist) {
    constexpr int kCounts = 8;
    constexpr size_t kBlock = 16 * 4096;
    const size_t n16 = n & ~size_t(15);
    const __m256i high = _mm256_set1_epi16(int16_t(~(kCounts - 1))), ones = _mm256_set1_epi16(1);
    for (size_t i = 0; i < n16;) {
        __m256i acc[kCounts];
        for (__m256i &a : acc) a = _mm256_setzero_si256();
        for (const size_t end = std::min(n16, i + kBlock); i < end; i += 16) {
            const __m256i v = _mm256_loadu_si256(reinterpret_cast<const __m256i *>(f + i));
            for (int c = 0; c < kCounts; ++c)
                acc[c] = _mm256_sub_epi16(acc[c], _mm256_cmpeq_epi16(v, _mm256_set1_epi16(int16_t(c))));
            const __m256i big = _mm256_and_si256(v, high);
            if (!_mm256_testz_si256(big, big))
                for (size_t k = i; k < i + 16; ++k)
                    if (f[k] >= kCounts) ++hist[f[k]];
        }
        for (int c = 0; c < kCounts; ++c) {
            // Lanes hold at most 4096: madd's signed pairs sum them exactly into eight 32-bit lanes.
            const __m256i s = _mm256_madd_epi16(acc[c], ones);
            alignas(32) int32_t lanes[8];
            _mm256_store_si256(reinterpret_cast<__m256i *>(lanes), s);
            for (int32_t l : lanes) hist[c] += uint64_t(l);
        }
    }
    return n16;
}
}  // namespace
#endif

void finishZBufferStats(const ZBuffer &zb, ZBufferStats *stats) {
    // Histogram over the (saturating) per-pixel fragment counts; [0] counts uncovered pixels.
    // Counted into a table for every uint16 value, then cut after the largest count seen.
    // Neighbouring pixels mostly hold the same small count, and one table's increments of one
    // entry wait for each other through memory: with AVX2, counts below 8 go to lane counters
    // (histogramAvx2); otherwise, or for the last few pixels, counts below 64 go to four small
    // tables in turn (independent chains), the rest to the full one.
    std::vector<uint64_t> hist(size_t(0xFFFF) + 1, 0);
    uint64_t small[4][64] = {};
    const uint16_t *f = zb.fragments.data();
    const size_t n = zb.fragments.size();
    size_t i = 0;
#if defined(__x86_64__) || defined(__i386__)
    if (__builtin_cpu_supports("avx2")) i = histogramAvx2(f, n, hist.data());
#endif
    for (; i + 4 <= n; i += 4)
        for (size_t k = 0; k < 4; ++k) {
            const uint16_t c = f[i + k];
            if (c < 64) ++small[k][c];
            else ++hist[c];
        }
    for (; i < n; ++i) ++hist[f[i]];
    for (size_t c = 0; c < 64; ++c) hist[c] += small[0][c] + small[1][c] + small[2][c] + small[3][c];
    uint32_t maxCount = 0xFFFF;
    while (maxCount > 0 && hist[maxCount] == 0) --maxCount;
    hist.resize(size_t(maxCount) + 1);
    const uint64_t pixels = zb.fragments.size();
    stats->coveredPixels = pixels - hist[0];
    stats->maxDepthComplexity = maxCount;
    stats->histogram = std::move(hist);
    if (stats->coveredPixels > 0) {
        stats->overdraw = double(stats->depthPasses) / double(stats->coveredPixels);
        stats->depthComplexity = double(stats->fragments) / double(stats->coveredPixels);
    } else {
        stats->overdraw = 0;
        stats->depthComplexity = 0;
    }
}

}  // namespace va
