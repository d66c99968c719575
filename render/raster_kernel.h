// The z-buffer's tile kernel (docs/rasterizer.md: Tiles, SIMD). Private to the rasterizer: included
// by raster.cpp (baseline instruction set) and raster_avx2.cpp (-mavx2); each compiles its own copy
// inside raster_core.h's instruction-set namespace and hands out function pointers through
// shadeFunctionBase / shadeFunctionAvx2.
//
// A kernel call shades the triangles binned into one tile (a pixel rectangle), in submission order,
// into the shared z-buffer; tiles are disjoint, so calls for different tiles may run concurrently.
// Per triangle it does what walkFragments does (orientation, coverTriangle over the triangle's box
// clipped to the tile, the depth plane at each covered center), but instead of testing each
// fragment as it comes it collects them in a batch:
//   1. coverage pushes (pixel, plane value, id) per covered center and counts fragments per pixel;
//   2. at kBatch fragments (and at the end), the view depths d = 1 / v (or v) and the format's keys
//      are computed for the whole batch in loops without branches, which the compiler turns into
//      SIMD lanes (4 doubles with AVX2): IEEE division, conversion and comparison per lane give
//      the same bits as the scalar code, so d and the keys are bit-identical to walkFragments';
//   3. the depth test (LESS on the keys, selects) and the writes run in batch order, which is
//      submission order: a pixel sees its fragments in the same order as in the plain walk.
// Results are therefore byte-identical to the plain walk (raster.cpp's ZBufferSink) for any tiling.
#pragma once

#include <atomic>
#include <memory>
#include <cstddef>
#include <cstdint>

#if defined(__AVX2__)
#include <immintrin.h>
#endif

#include "render/depth_format_impl.h"
#include "render/raster_core.h"

namespace va::raster_detail {

// One triangle binned into a tile. flags: kMultiTile set when the triangle's box of centers spans
// more than one tile (its fragment count is then summed over tiles in multiCounts[multi]);
// kFullTile set when every center of the tile is inside the triangle (whole-tile accept, decided
// at binning from the tile's corner centers).
struct BinEntry {
    uint32_t t;      // triangle index (submission order)
    uint32_t multi;  // index into the chunk's multiCounts when kMultiTile
    uint32_t flags;
};
constexpr uint32_t kMultiTile = 1, kFullTile = 2;

// The triangles one binning chunk (a run of consecutive triangles) put into one tile.
struct BinList {
    const BinEntry *entries = nullptr;
    size_t count = 0;
    uint32_t *multiCounts = nullptr;  // the chunk's per-multi-tile-triangle fragment counts (atomic adds)
};

// The z-buffer's five per-pixel buffers (ZBuffer's vectors' data) and the one place a fragment is
// resolved into them: resolve() counts the fragment at the pixel, runs LESS on the keys (kExact: on
// the double depths; on equal values the first drawn fragment stays) and on a pass writes key, id
// and depth and counts the pass. Written as selects, not branches: about half the fragments pass,
// in no predictable pattern. Counters saturate at 0xFFFF. FragmentBatch::resolveEight is the same
// rule for eight consecutive pixels in AVX2 lanes (it lives in the instruction-set namespace, where
// AVX2 code may differ between the two builds of this header).
struct PixelBuffers {
    uint32_t *key;
    uint32_t *id;
    double *depth;
    uint16_t *fragments;
    uint16_t *passes;

    explicit PixelBuffers(ZBuffer &zb)
        : key(zb.key.data()), id(zb.id.data()), depth(zb.depth.data()), fragments(zb.fragments.data()),
          passes(zb.passes.data()) {}

    template <bool kExact>
    [[gnu::always_inline]] bool resolve(size_t idx, uint32_t newKey, double d, uint32_t newId) const {
        fragments[idx] += fragments[idx] != 0xFFFF ? 1 : 0;
        bool pass;
        if constexpr (kExact) {
            pass = d < depth[idx];
        } else {
            const uint32_t oldKey = key[idx];
            pass = newKey < oldKey;
            key[idx] = pass ? newKey : oldKey;
        }
        id[idx] = pass ? newId : id[idx];
        depth[idx] = pass ? d : depth[idx];
        passes[idx] += (pass && passes[idx] != 0xFFFF) ? 1 : 0;
        return pass;
    }
};

// Everything a kernel call reads and writes besides its tile's bins.
struct ShadeTarget {
    const int32_t *xy;
    const uint32_t *source;
    const uint32_t *planeIndex;
    const DepthPlane *planes;
    const DepthEncoder *encoder;
    uint32_t *fragmentsPerSource;  // may be null
    bool concurrent;               // tiles run concurrently: shared counters take atomic adds
    size_t width;
    PixelBuffers buffers;
};

// A tile: inclusive pixel rectangle, its bin lists in submission order (chunk order).
struct TileWork {
    int64_t x0, x1, y0, y1;
    const BinList *lists;
    size_t listCount;
};

// Sums over a tile; multi-tile triangles are counted as drawn after all tiles (multiCounts).
struct TileCounts {
    uint64_t fragments = 0, passes = 0, outOfRange = 0, drawnSingle = 0;
};

using ShadeFn = void (*)(const ShadeTarget &, const TileWork &, TileCounts &);
// One call of the in-order walk (rasterizeWalk below): the rows [rowBegin, rowEnd) of the z-buffer
// (the whole viewport for the plain walk; any band for the batched one, bands may run concurrently).
struct WalkBand {
    int rowBegin = 0, rowEnd = 0;
    // Per triangle, set to 1 when a triangle whose box reaches beyond the band drew a fragment in
    // it (whether it drew at all is known over all bands); null when the band is the whole viewport.
    uint8_t *sharedDrawn = nullptr;
    bool concurrent = false;  // other bands run at the same time: per-source counts take atomic adds
};
// What a walk call counts (drawn: triangles that drew, those of sharedDrawn aside).
struct WalkCounts {
    uint64_t fragments = 0, passes = 0, outOfRange = 0, drawn = 0, backWinding = 0;
};
using WalkFn = void (*)(const ScreenTriangles &, const ZBufferSettings &, ZBuffer &, const WalkBand &, WalkCounts &);
// The kernel for a depth format, projection and exactDepth, per instruction set.
ShadeFn shadeFunctionBase(DepthFormat format, bool perspective, bool exactDepth);
ShadeFn shadeFunctionAvx2(DepthFormat format, bool perspective, bool exactDepth);
// The walk for a depth format and exactDepth: the baseline one (walkFragments) and the AVX2 one
// (walkFragmentsBatched; null when not built for x86-64).
WalkFn walkFunctionBase(DepthFormat format, bool exactDepth);
WalkFn walkFunctionAvx2(DepthFormat format, bool exactDepth);

inline namespace VA_RASTER_ISA {

constexpr size_t kBatch = 256;

// Fragments collected for the z-buffer and resolved kBatch at a time (steps 1-3 of the header
// comment): push() takes a covered center's pixel, plane value and id and fetches the pixel's five
// buffer lines; flush() computes the view depths and keys of the whole batch in branch-free loops
// (SIMD lanes), then runs the LESS tests and writes in push order.
template <DepthFormat F, bool kPerspective, bool kExact>
struct FragmentBatch {
    alignas(64) double value[kBatch];  // plane value, then view depth
    alignas(64) uint32_t keys[kBatch];
    alignas(64) uint32_t pixel[kBatch];
    alignas(64) uint32_t ids[kBatch];
    size_t n = 0;
    uint64_t passes = 0, outOfRange = 0;
    DepthEncoder enc;  // a copy: loads through a pointer keep GCC from vectorizing the encode loop
    PixelBuffers buf;

    FragmentBatch(const DepthEncoder &encoder, const PixelBuffers &buffers) : enc(encoder), buf(buffers) {}

    [[gnu::always_inline]] void push(size_t idx, double planeValue, uint32_t id) {
        // The flush reads and writes these kBatch fragments later: fetch their lines now.
        __builtin_prefetch(buf.key + idx, 1);
        __builtin_prefetch(buf.id + idx, 1);
        __builtin_prefetch(buf.depth + idx, 1);
        __builtin_prefetch(buf.fragments + idx, 1);
        __builtin_prefetch(buf.passes + idx, 1);
        value[n] = planeValue;
        pixel[n] = uint32_t(idx);
        ids[n] = id;
        if (++n == kBatch) flush();
    }

    // The centers x0..x1 of one row (row = y * width) of one triangle: plane values
    // (pa * (x + 0.5) + rowTerm) + pc, as push() receives them per center, in vectorizable loops,
    // and the buffers' lines fetched once per eight pixels rather than per fragment.
    [[gnu::always_inline]] void pushSpan(size_t row, int64_t x0, int64_t x1, double pa, double rowTerm, double pc,
                                         uint32_t id) {
        while (x0 <= x1) {
            const size_t k = std::min(kBatch - n, size_t(x1 - x0 + 1));
            const size_t at = row + size_t(x0);
            for (size_t j = 0; j < k; j += 8) {
                __builtin_prefetch(buf.key + at + j, 1);
                __builtin_prefetch(buf.id + at + j, 1);
                __builtin_prefetch(buf.depth + at + j, 1);
                __builtin_prefetch(buf.fragments + at + j, 1);
                __builtin_prefetch(buf.passes + at + j, 1);
            }
            __builtin_prefetch(buf.depth + at + k - 1, 1);
            double *val = value + n;
            uint32_t *pix = pixel + n, *idv = ids + n;
            const int32_t xi = int32_t(x0);  // below the viewport width: exact as int32 and as double
            for (size_t j = 0; j < k; ++j) {
                val[j] = (pa * (double(xi + int32_t(j)) + 0.5) + rowTerm) + pc;
                pix[j] = uint32_t(at + j);
                idv[j] = id;
            }
            n += k;
            x0 += int64_t(k);
            if (n == kBatch) flush();
        }
    }

    void flush() {
        if constexpr (kPerspective)
            for (size_t i = 0; i < n; ++i) value[i] = 1.0 / value[i];
        if constexpr (!kExact) {
            const DepthEncoder e = enc;
            uint32_t oor = 0;
            for (size_t i = 0; i < n; ++i) {
                bool o = false;
                uint32_t k;
                encodeDepth<F>(e, value[i], k, o);
                keys[i] = k;
                oor += o ? 1 : 0;
            }
            outOfRange += oor;
        }
        const PixelBuffers b = buf;
        uint64_t p = 0;
        for (size_t i = 0; i < n;) {
#if defined(__AVX2__)
            // Eight fragments on eight consecutive pixels (a span's, mostly) are eight different
            // pixels: resolved side by side, each as resolve() does it.
            if (i + 8 <= n && pixel[i + 7] == pixel[i] + 7) {
                const __m256i px = _mm256_loadu_si256(reinterpret_cast<const __m256i *>(pixel + i));
                const __m256i steps = _mm256_sub_epi32(px, _mm256_set1_epi32(int32_t(pixel[i])));
                if (_mm256_movemask_epi8(_mm256_cmpeq_epi32(steps, _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7))) == -1) {
                    p += resolveEight(b, pixel[i], i);
                    i += 8;
                    continue;
                }
            }
#endif
            p += b.resolve<kExact>(pixel[i], kExact ? 0 : keys[i], value[i], ids[i]) ? 1 : 0;
            ++i;
        }
        passes += p;
        n = 0;
    }

#if defined(__AVX2__)
    // Fragments i..i+7 of the batch, on pixels at..at+7: PixelBuffers::resolve for each, in AVX2
    // lanes (saturating adds for the 16-bit counters, unsigned LESS on the keys by flipping the sign
    // bit, or LESS on the doubles with kExact, false on NaN as the scalar test). Returns the passes.
    [[gnu::always_inline]] unsigned resolveEight(const PixelBuffers &b, size_t at, size_t i) const {
        const __m128i one16 = _mm_set1_epi16(1);
        __m128i *frags = reinterpret_cast<__m128i *>(b.fragments + at);
        _mm_storeu_si128(frags, _mm_adds_epu16(_mm_loadu_si128(frags), one16));
        const __m256d d0 = _mm256_loadu_pd(value + i), d1 = _mm256_loadu_pd(value + i + 4);
        const __m256d od0 = _mm256_loadu_pd(b.depth + at), od1 = _mm256_loadu_pd(b.depth + at + 4);
        __m256i pass;
        if constexpr (kExact) {
            // The low halves of the 64-bit masks, in lane order.
            const __m256i low = _mm256_setr_epi32(0, 2, 4, 6, 0, 2, 4, 6);
            const __m256i m0 = _mm256_permutevar8x32_epi32(_mm256_castpd_si256(_mm256_cmp_pd(d0, od0, _CMP_LT_OQ)), low);
            const __m256i m1 = _mm256_permutevar8x32_epi32(_mm256_castpd_si256(_mm256_cmp_pd(d1, od1, _CMP_LT_OQ)), low);
            pass = _mm256_blend_epi32(m0, m1, 0xF0);
        } else {
            const __m256i sign = _mm256_set1_epi32(INT32_MIN);
            __m256i *key = reinterpret_cast<__m256i *>(b.key + at);
            const __m256i oldKey = _mm256_loadu_si256(key), newKey = _mm256_loadu_si256(reinterpret_cast<const __m256i *>(keys + i));
            pass = _mm256_cmpgt_epi32(_mm256_xor_si256(oldKey, sign), _mm256_xor_si256(newKey, sign));
            _mm256_storeu_si256(key, _mm256_blendv_epi8(oldKey, newKey, pass));
        }
        __m256i *id = reinterpret_cast<__m256i *>(b.id + at);
        _mm256_storeu_si256(id, _mm256_blendv_epi8(_mm256_loadu_si256(id),
                                                   _mm256_loadu_si256(reinterpret_cast<const __m256i *>(ids + i)), pass));
        const __m256d pass0 = _mm256_castsi256_pd(_mm256_cvtepi32_epi64(_mm256_castsi256_si128(pass)));
        const __m256d pass1 = _mm256_castsi256_pd(_mm256_cvtepi32_epi64(_mm256_extracti128_si256(pass, 1)));
        _mm256_storeu_pd(b.depth + at, _mm256_blendv_pd(od0, d0, pass0));
        _mm256_storeu_pd(b.depth + at + 4, _mm256_blendv_pd(od1, d1, pass1));
        // The pass mask as eight 16-bit lanes of 1 or 0.
        const __m128i pass16 = _mm_packs_epi32(_mm256_castsi256_si128(pass), _mm256_extracti128_si256(pass, 1));
        __m128i *passes16 = reinterpret_cast<__m128i *>(b.passes + at);
        _mm_storeu_si128(passes16, _mm_adds_epu16(_mm_loadu_si128(passes16), _mm_and_si128(pass16, one16)));
        return unsigned(std::popcount(unsigned(_mm256_movemask_ps(_mm256_castsi256_ps(pass)))));
    }
#endif
};

// The batched walk's z-buffer sink: ZBufferSink's counts, fragments through a FragmentBatch
// (kPlaneValue: the walk hands over plane values, the batch divides).
template <DepthFormat F, bool kPerspective, bool kExact>
struct ZBufferBatchSink {
    static constexpr bool kPlaneValue = true;
    const uint32_t *source;
    const uint8_t *singleSided;
    uint32_t *fragmentsPerSource;
    FragmentBatch<F, kPerspective, kExact> &batch;
    const WalkBand &walkBand;
    uint64_t idValue = 0;  // 1 + source (uint64_t: see ZBufferSink)
    bool home = true, shared = false;  // the current triangle's band flags (walkFragmentsBatched)
    uint64_t fragments = 0, drawn = 0, backWinding = 0;

    void band(bool homeBand, bool sharedBox) {
        home = homeBand;
        shared = sharedBox;
    }
    bool beginTriangle(size_t t, bool frontWinding) {
        const uint32_t src = source[t];
        if (singleSided && singleSided[src] && !frontWinding) {
            backWinding += home ? 1 : 0;
            return false;
        }
        idValue = src + 1;
        return true;
    }
    [[gnu::always_inline]] void fragment(size_t idx, size_t, double planeValue) {
        batch.push(idx, planeValue, uint32_t(idValue));
    }
    [[gnu::always_inline]] void fragmentSpan(size_t row, int64_t x0, int64_t x1, double pa, double rowTerm, double pc) {
        batch.pushSpan(row, x0, x1, pa, rowTerm, pc, uint32_t(idValue));
    }
    void endTriangle(size_t t, uint64_t n) {
        fragments += n;
        if (shared) {
            if (n) std::atomic_ref<uint8_t>(walkBand.sharedDrawn[t]).store(1, std::memory_order_relaxed);
        } else {
            drawn += n != 0 ? 1 : 0;
        }
        if (fragmentsPerSource && n) {
            uint32_t &slot = fragmentsPerSource[source[t]];
            if (walkBand.concurrent) std::atomic_ref<uint32_t>(slot).fetch_add(uint32_t(n), std::memory_order_relaxed);
            else slot += uint32_t(n);
        }
    }
};

// The z-buffer as a fragment sink (raster_core.h). Instantiated per depth format and projection
// (dispatchDepthFormat once per call), so encodeDepth<F> inlines; kExact compares the double depth
// instead (the format is then not used per fragment). Accumulators live in the sink and are added
// to the stats once at the end.
template <DepthFormat F, bool kExact>
struct ZBufferSink {
    const DepthEncoder &enc;
    const uint32_t *source;           // ScreenTriangles::source
    const uint8_t *singleSided;       // settings.singleSided (may be null)
    uint32_t *fragmentsPerSource;     // settings.fragmentsPerSource (may be null)
    PixelBuffers buf;
    // 1 + source of the current triangle, held as uint64_t: a uint32_t member could alias the
    // uint32_t buffers written per fragment, forcing a reload after every store.
    uint64_t idValue = 0;
    uint64_t fragments = 0, passes = 0, outOfRange = 0, drawn = 0, backWinding = 0;

    bool beginTriangle(size_t t, bool frontWinding) {
        const uint32_t src = source[t];
        if (singleSided && singleSided[src] && !frontWinding) {
            ++backWinding;
            return false;
        }
        idValue = src + 1;
        return true;
    }

    [[gnu::always_inline]] void fragment(size_t idx, size_t, double d) {
        uint32_t key = 0;
        if constexpr (!kExact) {
            bool oor = false;
            encodeDepth<F>(enc, d, key, oor);
            outOfRange += oor ? 1 : 0;
        }
        passes += buf.resolve<kExact>(idx, key, d, uint32_t(idValue)) ? 1 : 0;
    }

    void endTriangle(size_t t, uint64_t n) {
        fragments += n;
        drawn += n != 0 ? 1 : 0;
        if (fragmentsPerSource) fragmentsPerSource[source[t]] += uint32_t(n);
    }
};

// The in-order walk into the z-buffer: walkFragments, or with kBatched (AVX2 builds only)
// walkFragmentsBatched, which gives the same fragments in the same triangle order.
template <DepthFormat F, bool kExact, bool kBatched>
void rasterizeWalk(const ScreenTriangles &tris, const ZBufferSettings &settings, ZBuffer &zb, const WalkBand &band,
                   WalkCounts &counts) {
    if constexpr (kBatched) {
#if defined(__AVX2__)
        auto run = [&]<bool kPerspective>() {
            auto batch = std::make_unique<FragmentBatch<F, kPerspective, kExact>>(settings.encoder, PixelBuffers(zb));
            ZBufferBatchSink<F, kPerspective, kExact> sink{tris.source.data(), settings.singleSided,
                                                           settings.fragmentsPerSource, *batch, band};
            walkFragmentsBatched<kPerspective>(tris, zb.width, zb.height, band.rowBegin, band.rowEnd, sink);
            batch->flush();
            counts.fragments += sink.fragments;
            counts.drawn += sink.drawn;
            counts.backWinding += sink.backWinding;
            counts.passes += batch->passes;
            counts.outOfRange += batch->outOfRange;
        };
        if (settings.orthographic) run.template operator()<false>();
        else run.template operator()<true>();
#endif
    } else {
        ZBufferSink<F, kExact> sink{settings.encoder, tris.source.data(), settings.singleSided,
                                    settings.fragmentsPerSource, PixelBuffers(zb)};
        if (settings.orthographic) walkFragments<false>(tris, zb.width, zb.height, sink);
        else walkFragments<true>(tris, zb.width, zb.height, sink);
        counts.fragments += sink.fragments;
        counts.drawn += sink.drawn;
        counts.backWinding += sink.backWinding;
        counts.passes += sink.passes;
        counts.outOfRange += sink.outOfRange;
    }
}

template <bool kBatched>
inline WalkFn selectWalk(DepthFormat format, bool exactDepth) {
    if (exactDepth) return &rasterizeWalk<DepthFormat::f32, true, kBatched>;  // the format is not used per fragment
    return dispatchDepthFormat(format, [&]<DepthFormat F>() -> WalkFn { return &rasterizeWalk<F, false, kBatched>; });
}

template <DepthFormat F, bool kPerspective, bool kExact>
void shadeTile(const ShadeTarget &s, const TileWork &w, TileCounts &counts) {
    FragmentBatch<F, kPerspective, kExact> batch(*s.encoder, s.buffers);
    const size_t W = s.width;
    uint64_t fragments = 0, drawnSingle = 0;
    for (size_t l = 0; l < w.listCount; ++l) {
        const BinList &list = w.lists[l];
        for (size_t b = 0; b < list.count; ++b) {
            const BinEntry e = list.entries[b];
            const size_t t = e.t;
            const int32_t *v = s.xy + 6 * t;
            int64_t x0 = v[0], y0 = v[1], x1 = v[2], y1 = v[3], x2 = v[4], y2 = v[5];
            const int64_t minX = std::min(x0, std::min(x1, x2)), maxX = std::max(x0, std::max(x1, x2));
            const int64_t minY = std::min(y0, std::min(y1, y2)), maxY = std::max(y0, std::max(y1, y2));
            // The triangle's box of centers clipped to the tile (binning guarantees it is not empty).
            const int64_t bx0 = std::max(firstCenter(minX), w.x0), bx1 = std::min(lastCenter(maxX), w.x1);
            const int64_t by0 = std::max(firstCenter(minY), w.y0), by1 = std::min(lastCenter(maxY), w.y1);
            // Orientation as in walkFragments (binning dropped zero areas).
            if ((x1 - x0) * (y2 - y0) - (y1 - y0) * (x2 - x0) < 0) {
                std::swap(x1, x2);
                std::swap(y1, y2);
            }
            const DepthPlane &plane = s.planes[s.planeIndex[t]];
            const double pa = plane.a, pb = plane.b, pc = plane.c;
            const uint32_t idValue = s.source[t] + 1;
            uint64_t triFragments = 0;
            auto frag = [&](size_t idx, int64_t x, int64_t y) {
                ++triFragments;
                batch.push(idx, (pa * (double(x) + 0.5) + pb * (double(y) + 0.5)) + pc, idValue);
            };
            if (e.flags & kFullTile) {
                for (int64_t y = by0; y <= by1; ++y)
                    for (int64_t x = bx0; x <= bx1; ++x) frag(size_t(y) * W + size_t(x), x, y);
            } else {
                coverTriangle(x0, y0, x1, y1, x2, y2, std::max(maxX - minX, maxY - minY), bx0, bx1, by0, by1, W,
                              frag);
            }

            fragments += triFragments;
            if (e.flags & kMultiTile) {
                if (triFragments)
                    std::atomic_ref<uint32_t>(list.multiCounts[e.multi]).fetch_add(uint32_t(triFragments),
                                                                                    std::memory_order_relaxed);
            } else {
                drawnSingle += triFragments != 0 ? 1 : 0;
            }
            if (s.fragmentsPerSource && triFragments) {
                // Sums modulo 2^32 in any order: the same result for any tiling and thread count.
                uint32_t &slot = s.fragmentsPerSource[s.source[t]];
                if (s.concurrent) std::atomic_ref<uint32_t>(slot).fetch_add(uint32_t(triFragments), std::memory_order_relaxed);
                else slot += uint32_t(triFragments);
            }
        }
    }
    batch.flush();
    counts.fragments += fragments;
    counts.passes += batch.passes;
    counts.outOfRange += batch.outOfRange;
    counts.drawnSingle += drawnSingle;
}

// The kernel for a format, projection and exactDepth (exactDepth ignores the format per fragment).
inline ShadeFn selectShade(DepthFormat format, bool perspective, bool exactDepth) {
    if (exactDepth)
        return perspective ? &shadeTile<DepthFormat::f32, true, true> : &shadeTile<DepthFormat::f32, false, true>;
    return dispatchDepthFormat(format, [&]<DepthFormat F>() -> ShadeFn {
        return perspective ? &shadeTile<F, true, false> : &shadeTile<F, false, false>;
    });
}

}  // namespace VA_RASTER_ISA

}  // namespace va::raster_detail
