// The A-buffer (abuffer.h; docs/ordering.md).
#include "render/abuffer.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "render/stopwatch.h"

namespace va {

namespace {
// The 16 offsets: cell centers (32 + 64 i) of a 256 x 256 fixed-point pixel, row-major.
constexpr SampleOffset kGrid[kABufferSamples] = {
    {32, 32},  {96, 32},  {160, 32},  {224, 32},  {32, 96},  {96, 96},  {160, 96},  {224, 96},
    {32, 160}, {96, 160}, {160, 160}, {224, 160}, {32, 224}, {96, 224}, {160, 224}, {224, 224}};
static_assert(kSubpixelOne == 256, "the 4 x 4 grid offsets assume 8 sub-pixel bits");
constexpr uint32_t kEnd = std::numeric_limits<uint32_t>::max();
}  // namespace

const SampleOffset *abufferSampleOffsets() { return kGrid; }

ABufferResult resolveABuffer(const ScreenTriangles &tris, int width, int height, bool orthographic,
                             const ABufferMaterials &mat, uint32_t maxListLength) {
    const Stopwatch t0;
    ABufferResult r;
    r.width = std::max(width, 0);
    r.height = std::max(height, 0);
    const size_t pixels = size_t(r.width) * size_t(r.height);

    // 17 samples per triangle: the 4 x 4 grid (bits 0..15) and the pixel center (bit 16), which is
    // the z-buffer's single sample (for the edge pixels).
    SampleOffset offsets[kABufferSamples + 1];
    for (int i = 0; i < kABufferSamples; ++i) offsets[i] = kGrid[i];
    offsets[kABufferSamples] = kCenterSample;
    constexpr uint32_t kCenterBit = 1u << kABufferSamples;
    // fn(triangle, source, pixel, mask) for every pixel a drawn triangle covers at a sample.
    auto forEachCoverage = [&](auto &&fn) {
        for (size_t t = 0; t < tris.size(); ++t) {
            const uint32_t src = tris.source[t];
            if (!tris.planes[tris.plane[t]].valid) continue;
            bool front = false;
            coverageMasks(tris, t, r.width, r.height, offsets, kABufferSamples + 1, &front, [&](size_t p, uint32_t mask) {
                if (mat.singleSided && mat.singleSided[src] && !front) return;
                fn(t, src, p, mask);
            });
        }
    };

    // Pass 1: each pixel's list length, so a hostile pile of layers is refused before the pool is
    // allocated; and the z-buffer's view for the comparison (not part of the A-buffer's memory): the
    // nearest triangle covering each pixel center, depth at the center, ties to the lowest source.
    std::vector<uint32_t> length(pixels, 0);
    std::vector<uint32_t> centerId(pixels, 0);
    std::vector<double> centerD(pixels, std::numeric_limits<double>::infinity());
    uint64_t total = 0;
    size_t longest = 0;  // a pixel with the longest list
    forEachCoverage([&](size_t t, uint32_t src, size_t p, uint32_t mask) {
        if (mask & kCenterBit) {
            const DepthPlane &pl = tris.planes[tris.plane[t]];
            const double v = evalDepthPlane(pl, double(p % size_t(r.width)) + 0.5, double(p / size_t(r.width)) + 0.5);
            const double d = orthographic ? v : 1.0 / v;
            if (d < centerD[p] || (d == centerD[p] && src + 1 < centerId[p])) {
                centerD[p] = d;
                centerId[p] = src + 1;
            }
        }
        if ((mask & 0xFFFF) == 0) return;  // only the center: no sub-sample, no A-buffer fragment
        if (length[p] != UINT32_MAX) ++length[p];  // saturates: it is refused anyway
        if (length[p] > length[longest]) longest = p;
        ++total;
    });
    if (pixels && length[longest] > maxListLength) {
        r.error = "A-buffer: pixel (" + std::to_string(longest % size_t(r.width)) + ", " +
                  std::to_string(longest / size_t(r.width)) + ") needs a list of " + std::to_string(length[longest]) +
                  " fragments, more than the limit of " + std::to_string(maxListLength) +
                  "; raise it with --max-abuffer-list " + std::to_string(length[longest]) +
                  " (or turn the A-buffer off with --no-abuffer)";
        return r;
    }
    if (total >= kEnd) {  // list links are 32-bit; kEnd ends a list
        r.error = "A-buffer: " + std::to_string(total) + " fragments, more than its 32-bit lists hold (" +
                  std::to_string(kEnd - 1) + "); lower the resolution or turn the A-buffer off with --no-abuffer";
        return r;
    }

    // Pass 2: a fragment pool with per-pixel singly linked lists (head per pixel), as Carpenter's.
    std::vector<uint32_t> head(pixels, kEnd);
    std::vector<ABufferFragment> pool;
    pool.reserve(size_t(total));
    forEachCoverage([&](size_t t, uint32_t src, size_t p, uint32_t mask) {
        if ((mask & 0xFFFF) == 0) return;
        ABufferFragment f;
        f.source = src;
        f.plane = tris.plane[t];
        f.mask = uint16_t(mask & 0xFFFF);
        f.alpha = mat.alpha ? mat.alpha[src] : 1.0f;
        f.next = head[p];
        head[p] = uint32_t(pool.size());
        pool.push_back(f);
        if (f.alpha < 1) ++r.transparentFragments;
    });
    r.fragments = pool.size();
    r.memoryBytes = pool.size() * sizeof(ABufferFragment) + pixels * sizeof(uint32_t);
    r.listHistogram.assign(kABufferHistogramMax, 0);
    r.rgb.assign(pixels * 3, 0);
    r.edge.assign(pixels, 0);

    // Surface of a visible id (1 + source; 0 background -> a value no surface has).
    auto surfaceOf = [&](uint32_t id) -> uint64_t {
        if (id == 0) return UINT64_MAX;
        return mat.surface ? mat.surface[id - 1] : id - 1;
    };

    // Resolve per pixel.
    struct Entry {
        double d;
        uint32_t source;
        uint32_t frag;
    };
    std::vector<Entry> list;
    for (size_t p = 0; p < pixels; ++p) {
        const size_t x = p % size_t(r.width), y = p / size_t(r.width);
        const uint32_t len = length[p];
        ++r.listHistogram[std::min<size_t>(len, kABufferHistogramMax - 1)];
        uint8_t *out = &r.rgb[3 * p];
        if (len == 0) {
            for (int c = 0; c < 3; ++c) out[c] = mat.background[c];
            if (centerId[p]) {  // the center is covered, no sub-sample is: the z-buffer shows a sliver
                r.edge[p] = 1;
                ++r.edgePixels;
            }
            continue;
        }
        ++r.coveredPixels;
        r.maxListLength = std::max(r.maxListLength, len);

        // Per sub-sample: sort the covering fragments by depth there, composite front to back.
        double acc[3] = {0, 0, 0};
        bool edge = false;
        for (int s = 0; s < kABufferSamples; ++s) {
            const double px = double(x) + double(kGrid[s].dx) / kSubpixelOne;
            const double py = double(y) + double(kGrid[s].dy) / kSubpixelOne;
            list.clear();
            for (uint32_t f = head[p]; f != kEnd; f = pool[f].next) {
                if (!(pool[f].mask >> s & 1)) continue;
                const double v = evalDepthPlane(tris.planes[pool[f].plane], px, py);
                list.push_back({orthographic ? v : 1.0 / v, pool[f].source, f});
            }
            std::sort(list.begin(), list.end(), [](const Entry &a, const Entry &b) {
                return a.d < b.d || (a.d == b.d && a.source < b.source);
            });
            const uint32_t visible = list.empty() ? 0 : list.front().source + 1;
            if (surfaceOf(visible) != surfaceOf(centerId[p])) edge = true;
            double T = 1;
            for (const Entry &e : list) {
                const ABufferFragment &f = pool[e.frag];
                const double a = std::clamp(double(f.alpha), 0.0, 1.0);
                for (int c = 0; c < 3; ++c) acc[c] += T * a * (mat.rgb ? mat.rgb[3 * size_t(e.source) + c] : 255);
                T *= 1 - a;
                if (T <= 0) break;
            }
            for (int c = 0; c < 3; ++c) acc[c] += T * mat.background[c];
        }
        for (int c = 0; c < 3; ++c) out[c] = uint8_t(std::lround(std::clamp(acc[c] / kABufferSamples, 0.0, 255.0)));
        if (edge) {
            r.edge[p] = 1;
            ++r.edgePixels;
        }
    }
    r.averageListLength = r.coveredPixels ? double(r.fragments) / double(r.coveredPixels) : 0;
    r.ms = t0.ms();
    return r;
}

}  // namespace va
