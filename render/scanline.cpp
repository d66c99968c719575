// Scanline visibility (scanline.h; docs/ordering.md).
#include "render/scanline.h"

#include <algorithm>
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
        for (int64_t x = 1; x < W; ++x) cover[size_t(x)] += cover[size_t(x) - 1];
        std::fill(rowId.begin(), rowId.end(), 0);
        std::fill(rowD.begin(), rowD.end(), std::numeric_limits<double>::infinity());
        const double py = double(y) + 0.5;
        for (const Span &s : spans) {
            const Prepared &p = prepared[s.tri];
            const DepthPlane &pl = tris.planes[p.plane];
            const double bpy = pl.b * py;
            const uint32_t id = p.source + 1;
            for (int64_t x = s.x0; x <= s.x1; ++x) {
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
        std::copy(rowId.begin(), rowId.end(), r.id.begin() + y * W);
    }
    for (uint32_t id : r.id) r.coveredPixels += id != 0;
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
