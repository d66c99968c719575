// Scanline visibility (scanline.h; docs/ordering.md).
#include "render/scanline.h"

#include <algorithm>
#include <bit>
#include <immintrin.h>
#include <limits>

#include "render/raster_core.h"
#include "render/stopwatch.h"

namespace va {

namespace {

// A triangle ready for the row sweep: oriented (positive area), its box of centers, its plane.
struct Prepared {
    int64_t x[3], y[3];
    int64_t bx0, bx1, by0, by1;
    uint32_t plane, source;
};

// One span's centers x .. x1 of a row, resolved against the row so far: where `cover` says the
// span alone holds a center it takes it; elsewhere the depth v = (a (x + 0.5) + bpy) + c, or 1 / v
// in perspective, decides (LESS, ties to the lowest id). `writes` counts the centers taken,
// `evaluations` the depths computed. Returns where it stopped: four centers at a time, the same
// IEEE operations per center as the scalar loop (scanlineVisibility), branch-free, so the rows'
// unpredictable winners cost no mispredictions and four divisions issue as one.
__attribute__((target("avx2"))) int64_t resolveSpanAvx2(const int32_t *cover, uint32_t *rowId, double *rowD, int64_t x,
                                                        int64_t x1, double a, double bpy, double c, bool orthographic,
                                                        uint32_t id, uint64_t &writes, uint64_t &evaluations) {
    const __m256d va = _mm256_set1_pd(a), vb = _mm256_set1_pd(bpy), vc = _mm256_set1_pd(c);
    const __m256d one = _mm256_set1_pd(1.0), half = _mm256_set1_pd(0.5);
    const __m256d step = _mm256_set_pd(3, 2, 1, 0), four = _mm256_set1_pd(4);
    const __m128i sign = _mm_set1_epi32(INT32_MIN), ones = _mm_set1_epi32(1);
    const __m128i idBiased = _mm_xor_si128(_mm_set1_epi32(int32_t(id)), sign);
    const __m256i ids = _mm256_set1_epi64x(int64_t(id));
    __m256d xd = _mm256_add_pd(_mm256_set1_pd(double(x)), step);  // exact: x < 2^53
    uint64_t w = 0, e = 0;
    for (; x + 3 <= x1; x += 4, xd = _mm256_add_pd(xd, four)) {
        const __m128i cov = _mm_loadu_si128(reinterpret_cast<const __m128i *>(cover + x));
        const __m128i alone32 = _mm_cmpeq_epi32(cov, ones);
        if (_mm_movemask_ps(_mm_castsi128_ps(alone32)) == 0xF) {
            // The span alone holds all four centers (most of a row): they take its id, and no
            // depth is computed or stored (as the blends below would do for them).
            _mm_storeu_si128(reinterpret_cast<__m128i *>(rowId + x), _mm_set1_epi32(int32_t(id)));
            w += 4;
            continue;
        }
        const __m256d alone = _mm256_castsi256_pd(_mm256_cvtepi32_epi64(alone32));
        const __m256d v = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(va, _mm256_add_pd(xd, half)), vb), vc);
        const __m256d d = orthographic ? v : _mm256_div_pd(one, v);
        const __m256d old = _mm256_loadu_pd(rowD + x);
        const __m128i oldId = _mm_loadu_si128(reinterpret_cast<const __m128i *>(rowId + x));
        // id < oldId, unsigned: both biased by 2^31, then signed.
        const __m256d idLess = _mm256_castsi256_pd(_mm256_cvtepi32_epi64(_mm_cmpgt_epi32(_mm_xor_si128(oldId, sign), idBiased)));
        const __m256d wins = _mm256_or_pd(_mm256_cmp_pd(d, old, _CMP_LT_OQ),
                                          _mm256_and_pd(_mm256_cmp_pd(d, old, _CMP_EQ_OQ), idLess));
        const __m256d nearer = _mm256_andnot_pd(alone, wins);
        const __m256d taken = _mm256_or_pd(alone, nearer);
        _mm256_storeu_pd(rowD + x, _mm256_blendv_pd(old, d, nearer));
        const __m256i newId = _mm256_castpd_si256(_mm256_blendv_pd(
            _mm256_castsi256_pd(_mm256_cvtepu32_epi64(oldId)), _mm256_castsi256_pd(ids), taken));
        const __m256i packed = _mm256_permutevar8x32_epi32(newId, _mm256_setr_epi32(0, 2, 4, 6, 0, 2, 4, 6));
        _mm_storeu_si128(reinterpret_cast<__m128i *>(rowId + x), _mm256_castsi256_si128(packed));
        w += unsigned(std::popcount(unsigned(_mm256_movemask_pd(taken))));
        e += 4 - unsigned(std::popcount(unsigned(_mm256_movemask_pd(alone))));
    }
    writes += w;
    evaluations += e;
    return x;
}
// c[0..n) replaced by its prefix sums, four at a time (SSE2: two shifted adds within the
// register, then the carry of the sums before it), the same integers as the running sum.
void prefixSums(int32_t *c, size_t n) {
    __m128i carry = _mm_setzero_si128();
    size_t x = 0;
    for (; x + 4 <= n; x += 4) {
        __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i *>(c + x));
        v = _mm_add_epi32(v, _mm_slli_si128(v, 4));
        v = _mm_add_epi32(v, _mm_slli_si128(v, 8));
        v = _mm_add_epi32(v, carry);
        _mm_storeu_si128(reinterpret_cast<__m128i *>(c + x), v);
        carry = _mm_shuffle_epi32(v, _MM_SHUFFLE(3, 3, 3, 3));
    }
    for (int32_t run = x ? c[x - 1] : 0; x < n; ++x) c[x] = run += c[x];
}
}  // namespace

ScanlineResult scanlineVisibility(const ScreenTriangles &tris, int width, int height, bool orthographic,
                                  const uint8_t *singleSided) {
    using namespace raster_detail;
    ScanlineResult r;
    r.width = std::max(width, 0);
    r.height = std::max(height, 0);
    const int64_t W = r.width, H = r.height;
    r.id.assign(size_t(W) * size_t(H), 0);
    r.trianglesIn = tris.size();
    r.zbufferBytes = uint64_t(W) * uint64_t(H) * (sizeof(uint32_t) + sizeof(double));
    if (W == 0 || H == 0) return r;

    // Edge table: every triangle that can cover a center, bucketed by its first row (the same
    // skips as raster_core.h's walk, in its order: empty box, range, zero area, invalid plane).
    const Stopwatch t0;
    std::vector<Prepared> prepared;
    for (size_t t = 0; t < tris.size(); ++t) {
        const int32_t *v = tris.xy.data() + 6 * t;
        Prepared p;
        int64_t x0 = v[0], y0 = v[1], x1 = v[2], y1 = v[3], x2 = v[4], y2 = v[5];
        const int64_t minX = std::min(x0, std::min(x1, x2)), maxX = std::max(x0, std::max(x1, x2));
        const int64_t minY = std::min(y0, std::min(y1, y2)), maxY = std::max(y0, std::max(y1, y2));
        p.bx0 = std::max<int64_t>((minX - kHalf + kSubpixelOne - 1) >> kSubpixelBits, 0);
        p.bx1 = std::min<int64_t>((maxX - kHalf) >> kSubpixelBits, W - 1);
        p.by0 = std::max<int64_t>((minY - kHalf + kSubpixelOne - 1) >> kSubpixelBits, 0);
        p.by1 = std::min<int64_t>((maxY - kHalf) >> kSubpixelBits, H - 1);
        if (p.bx0 > p.bx1 || p.by0 > p.by1) continue;
        if (minX < -kMaxFixed || maxX > kMaxFixed || minY < -kMaxFixed || maxY > kMaxFixed) continue;
        const int64_t area = (x1 - x0) * (y2 - y0) - (y1 - y0) * (x2 - x0);
        if (area == 0) continue;
        if (area < 0) {
            std::swap(x1, x2);
            std::swap(y1, y2);
        }
        if (!tris.planes[tris.plane[t]].valid) continue;
        if (singleSided && singleSided[tris.source[t]] && !(area < 0)) {
            ++r.backWinding;
            continue;
        }
        p.x[0] = x0, p.x[1] = x1, p.x[2] = x2;
        p.y[0] = y0, p.y[1] = y1, p.y[2] = y2;
        p.plane = tris.plane[t];
        p.source = tris.source[t];
        prepared.push_back(p);
    }
    // Counting sort by first row: rowStart[y] .. rowStart[y + 1] are the triangles starting on row y.
    std::vector<uint32_t> rowStart(size_t(H) + 1, 0), byRow(prepared.size());
    for (const Prepared &p : prepared) ++rowStart[size_t(p.by0) + 1];
    for (int64_t y = 0; y < H; ++y) rowStart[size_t(y) + 1] += rowStart[size_t(y)];
    {
        std::vector<uint32_t> fill(rowStart.begin(), rowStart.end() - 1);
        for (uint32_t i = 0; i < prepared.size(); ++i) byRow[fill[size_t(prepared[i].by0)]++] = i;
    }
    r.trianglesActive = prepared.size();
    r.buildMs = t0.ms();

    // The sweep. Per row: add the triangles starting here, drop those that ended, solve each
    // active triangle's span of covered centers, then resolve: a center inside one span takes it
    // without a depth evaluation; where spans overlap, the depths at the center decide (LESS, ties
    // to the lowest source id).
    const Stopwatch t1;
    std::vector<uint32_t> active;
    struct Span {
        int64_t x0, x1;
        uint32_t tri;
    };
    std::vector<Span> spans;
    std::vector<uint32_t> rowId(static_cast<size_t>(W));
    std::vector<double> rowD(static_cast<size_t>(W));
    std::vector<int32_t> cover(size_t(W) + 1);
    size_t maxActive = 0, maxSpans = 0;
    const bool avx2 = __builtin_cpu_supports("avx2");
    for (int64_t y = 0; y < H; ++y) {
        for (uint32_t k = rowStart[size_t(y)]; k < rowStart[size_t(y) + 1]; ++k) active.push_back(byRow[k]);
        active.erase(std::remove_if(active.begin(), active.end(), [&](uint32_t i) { return prepared[i].by1 < y; }),
                     active.end());
        maxActive = std::max(maxActive, active.size());

        // Spans: edge k covers offset j (x = bx0 + j) iff E_k + bias + j stepX_k >= 0 (raster_core's
        // wide path, the same integer arithmetic).
        spans.clear();
        const int64_t sy = y * kSubpixelOne + kHalf;
        for (uint32_t i : active) {
            const Prepared &p = prepared[i];
            const int64_t sx = p.bx0 * kSubpixelOne + kHalf;
            const EdgeSetup e[3] = {setupEdge(p.x[1], p.y[1], p.x[2], p.y[2], sx, sy),
                                    setupEdge(p.x[2], p.y[2], p.x[0], p.y[0], sx, sy),
                                    setupEdge(p.x[0], p.y[0], p.x[1], p.y[1], sx, sy)};
            int64_t lo = 0, hi = p.bx1 - p.bx0;
            for (int k = 0; k < 3; ++k) {
                const int64_t s = e[k].stepX;
                if (s > 0) lo = std::max(lo, -floorDiv(e[k].value, s));
                else if (s < 0) hi = std::min(hi, floorDiv(e[k].value, -s));
                else if (e[k].value < 0) hi = -1;
            }
            if (lo <= hi) spans.push_back({p.bx0 + lo, p.bx0 + hi, i});
        }
        maxSpans = std::max(maxSpans, spans.size());
        r.spans += spans.size();
        if (spans.empty()) continue;

        // How many spans hold each center (a difference array over the row).
        std::fill(cover.begin(), cover.end(), 0);
        for (const Span &s : spans) {
            ++cover[size_t(s.x0)];
            --cover[size_t(s.x1) + 1];
            r.fragments += uint64_t(s.x1 - s.x0 + 1);
        }
        prefixSums(cover.data(), size_t(W));
        std::fill(rowId.begin(), rowId.end(), 0);
        std::fill(rowD.begin(), rowD.end(), std::numeric_limits<double>::infinity());
        const double py = double(y) + 0.5;
        for (const Span &s : spans) {
            const Prepared &p = prepared[s.tri];
            const DepthPlane &pl = tris.planes[p.plane];
            const double bpy = pl.b * py;
            const uint32_t id = p.source + 1;
            int64_t x = s.x0;
            if (avx2)
                x = resolveSpanAvx2(cover.data(), rowId.data(), rowD.data(), x, s.x1, pl.a, bpy, pl.c, orthographic, id,
                                    r.writes, r.depthEvaluations);
            for (; x <= s.x1; ++x) {
                if (cover[size_t(x)] == 1) {
                    rowId[size_t(x)] = id;
                    ++r.writes;
                    continue;
                }
                ++r.depthEvaluations;
                // The same IEEE operations as viewDepthAt (b py shared by the row, as in the core).
                const double v = (pl.a * (double(x) + 0.5) + bpy) + pl.c;
                const double d = orthographic ? v : 1.0 / v;
                if (d < rowD[size_t(x)] || (d == rowD[size_t(x)] && id < rowId[size_t(x)])) {
                    rowD[size_t(x)] = d;
                    rowId[size_t(x)] = id;
                    ++r.writes;
                }
            }
        }
        // Copied out and counted while the row is in cache (a row without spans stays 0).
        uint64_t covered = 0;
        for (int64_t x = 0; x < W; ++x) covered += rowId[size_t(x)] != 0;
        r.coveredPixels += covered;
        std::copy(rowId.begin(), rowId.end(), r.id.begin() + y * W);
    }
    r.overdraw = r.coveredPixels ? double(r.writes) / double(r.coveredPixels) : 0;
    r.maxActiveTriangles = uint32_t(maxActive);
    r.maxSpansPerRow = uint32_t(maxSpans);
    r.memoryBytes = prepared.size() * sizeof(Prepared) + rowStart.size() * sizeof(uint32_t) +
                    byRow.size() * sizeof(uint32_t) + maxActive * sizeof(uint32_t) + maxSpans * sizeof(Span) +
                    rowId.size() * sizeof(uint32_t) + rowD.size() * sizeof(double) + cover.size() * sizeof(int32_t);
    r.ms = t1.ms();
    return r;
}

}  // namespace va
