// The z-buffer rasterizer (raster.h; decisions in docs/rasterizer.md).
//
// Structure: rasterize() clears the buffers, then dispatches once on (depth format, projection,
// exactDepth) to the coverage walk of raster_core.h (forEachFragment) with the z-buffer as its
// sink, so the per-fragment depth encoding is inlined and branch-free. The walk does orientation,
// the box of pixel centers, int64 edge functions and the three coverage paths; the sink does, per
// covered center, encode and LESS written as selects (no branch on the depth test's outcome), and
// the per-triangle counts. The audits' options (single-sided winding, per-source fragment counts)
// are tested once per triangle, never per fragment.
#include "render/raster.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "render/depth_format_impl.h"
#include "render/raster_core.h"

namespace va {

int32_t toFixed(double pixelCoordinate) {
    // Scaling by 2^kSubpixelBits is exact; nearbyint rounds half to even in the default mode.
    const double s = std::nearbyint(pixelCoordinate * kSubpixelOne);
    // Saturate (NaN goes to the minimum): the rasterizer rejects such coordinates (kMaxFixed, raster_core.h).
    if (!(s > -2147483648.0)) return std::numeric_limits<int32_t>::min();
    if (s > 2147483647.0) return std::numeric_limits<int32_t>::max();
    return int32_t(s);
}

namespace {

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
    uint32_t *keyBuf;
    uint32_t *idBuf;
    double *depthBuf;
    uint16_t *fragBuf;
    uint16_t *passBuf;
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

    void fragment(size_t idx, size_t, double d) {
        fragBuf[idx] += fragBuf[idx] != 0xFFFF ? 1 : 0;
        // LESS: on equal keys (or equal depths) the first drawn fragment stays. Written as selects,
        // not a branch: about half the fragments pass, in no predictable pattern.
        bool pass;
        if constexpr (kExact) {
            pass = d < depthBuf[idx];
        } else {
            uint32_t key;
            bool oor = false;
            encodeDepth<F>(enc, d, key, oor);
            outOfRange += oor ? 1 : 0;
            const uint32_t oldKey = keyBuf[idx];
            pass = key < oldKey;
            keyBuf[idx] = pass ? key : oldKey;
        }
        idBuf[idx] = pass ? uint32_t(idValue) : idBuf[idx];
        depthBuf[idx] = pass ? d : depthBuf[idx];
        passBuf[idx] += (pass && passBuf[idx] != 0xFFFF) ? 1 : 0;
        passes += pass ? 1 : 0;
    }

    void endTriangle(size_t t, uint64_t n) {
        fragments += n;
        drawn += n != 0 ? 1 : 0;
        if (fragmentsPerSource) fragmentsPerSource[source[t]] += uint32_t(n);
    }
};

template <DepthFormat F, bool kExact>
void rasterizeWith(const ScreenTriangles &tris, const ZBufferSettings &settings, ZBuffer &zb, ZBufferStats &st) {
    ZBufferSink<F, kExact> sink{settings.encoder,    tris.source.data(), settings.singleSided,
                                settings.fragmentsPerSource, zb.key.data(), zb.id.data(),
                                zb.depth.data(),     zb.fragments.data(), zb.passes.data()};
    forEachFragment(tris, zb.width, zb.height, settings.orthographic, sink);
    st.fragments += sink.fragments;
    st.depthPasses += sink.passes;
    st.outOfRangeFragments += sink.outOfRange;
    st.trianglesDrawn += sink.drawn;
    st.trianglesEmpty += st.trianglesIn - sink.drawn;
    st.trianglesBackWinding += sink.backWinding;
    if constexpr (kExact) {
        // The keys of the stored depths, so the buffer reads the same as a format-tested one.
        for (size_t i = 0; i < zb.id.size(); ++i)
            if (zb.id[i] != 0) zb.key[i] = depthKey(settings.encoder, zb.depth[i]);
    }
}

}  // namespace

ZBufferResult rasterize(const ScreenTriangles &tris, int width, int height, const ZBufferSettings &settings) {
    ZBufferResult r;
    ZBuffer &zb = r.buffer;
    zb.width = std::max(width, 0);
    zb.height = std::max(height, 0);
    const size_t pixels = size_t(zb.width) * size_t(zb.height);
    zb.key.assign(pixels, std::numeric_limits<uint32_t>::max());
    zb.id.assign(pixels, 0);
    zb.depth.assign(pixels, std::numeric_limits<double>::infinity());
    zb.fragments.assign(pixels, 0);
    zb.passes.assign(pixels, 0);

    ZBufferStats &st = r.stats;
    st.trianglesIn = tris.size();
    if (pixels > 0) {
        if (settings.exactDepth) {
            rasterizeWith<DepthFormat::f32, true>(tris, settings, zb, st);  // the format is not used per fragment
        } else {
            dispatchDepthFormat(settings.encoder.format,
                                [&]<DepthFormat F>() { rasterizeWith<F, false>(tris, settings, zb, st); });
        }
    } else {
        st.trianglesEmpty = tris.size();
    }
    finishZBufferStats(zb, &st);
    return r;
}

void finishZBufferStats(const ZBuffer &zb, ZBufferStats *stats) {
    // Histogram over the (saturating) per-pixel fragment counts; [0] counts uncovered pixels.
    // Counted into a table for every uint16 value, then cut after the largest count seen.
    std::vector<uint64_t> hist(size_t(0xFFFF) + 1, 0);
    for (uint16_t c : zb.fragments) ++hist[c];
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
