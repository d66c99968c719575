// Per-view z-fighting analysis (zfight.h; definitions and rules in docs/zfighting.md).
//
// Structure of analyzeZFighting:
//   1. findTwoNearest: one pass over the z-buffer's fragments (forEachFragment) keeping, per pixel,
//      the two nearest surfaces from distinct source triangles;
//   2. per format (dispatched once, so encodeDepth<F> inlines): keys of both depths, fight bit,
//      out-of-range count;
//   3. classification of the pixels that fight in at least one format, from a per-triangle-pair
//      cache (common vertices, shared edge in screen space, coplanarity) and the two depth planes at
//      the pixel's corners;
//   4. 8-connected components of the hotspot pixels (separated or coplanar) with their statistics,
//      sorted into hotspot ids;
//   5. per-format counts and the recommendation;
//   6. per listed hotspot, why it fights (explainHotspot).
#include "analysis/audits/zfight.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <cstdio>
#include <immintrin.h>
#include <limits>
#include <optional>
#include <unordered_map>

#include "analysis/audits/audit.h"
#include "analysis/audits/depth_audit.h"
#include "render/depth_format_impl.h"
#include "render/raster_core.h"

namespace va {

const char *zPixelClassName(ZPixelClass c) {
    switch (c) {
    case ZPixelClass::none: return "none";
    case ZPixelClass::separated: return "separated";
    case ZPixelClass::coplanar: return "coplanar";
    case ZPixelClass::shared_edge: return "shared_edge";
    case ZPixelClass::intersection: return "intersection";
    }
    return "none";
}

const ZFightFormatStats *zfightStatsOf(const ZFightResult &r, const DepthFormatSpec &format) {
    for (const ZFightFormatStats &s : r.perFormat)
        if (s.format == format) return &s;
    return nullptr;
}

// ---- Pass 1: two nearest surfaces -------------------------------------------------------------

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Keeps fragment (pixel, depth d) of screen triangle t among the pixel's two nearest surfaces.
// Fragments arrive in submission order, so "strictly nearer" comparisons keep the first drawn in
// front on equal depths, exactly like the z-buffer's LESS test on equal keys. `first` is the first
// screen triangle of t's source: a source's clipped pieces are consecutive, so a kept triangle
// from `first` on is one of them (nothing after them has arrived yet), and kNoFragment + 1 wraps
// to 0, below every `first`.
inline void keepTwoNearest(TwoNearest &out, size_t pixel, uint32_t t, uint32_t first, double d) {
    double &d1 = out.depth1[pixel], &d2 = out.depth2[pixel];
    uint32_t &t1 = out.screen1[pixel], &t2 = out.screen2[pixel];
    static_assert(uint32_t(kNoFragment + 1) == 0);
    // Same surface as a kept one (another clipped piece of the same source triangle): keep the
    // nearer depth of that surface, never a second slot for it.
    if (uint32_t(t1 + 1) > first) {
        if (d < d1) d1 = d, t1 = t;
        return;
    }
    if (uint32_t(t2 + 1) > first) {
        if (d < d2) {
            d2 = d, t2 = t;
            if (d2 < d1) std::swap(d1, d2), std::swap(t1, t2);
        }
        return;
    }
    if (d < d1) {
        d2 = d1, t2 = t1;
        d1 = d, t1 = t;
    } else if (d < d2) {
        d2 = d, t2 = t;
    }
}

// Four 64-bit lane masks as four 32-bit ones, and back. (Functions, not lambdas: a lambda does not
// take its enclosing function's target.)
__attribute__((target("avx2"))) inline __m128i to32(__m256d m) {
    return _mm256_castsi256_si128(_mm256_permutevar8x32_epi32(_mm256_castpd_si256(m), _mm256_setr_epi32(0, 2, 4, 6, 0, 2, 4, 6)));
}
__attribute__((target("avx2"))) inline __m256d to64(__m128i m) { return _mm256_castsi256_pd(_mm256_cvtepi32_epi64(m)); }

// keepTwoNearest for a run's fragments from f on, of screen triangle t (its source's first: `first`),
// up to `end` or the first pixel at or past p1; pixel p at index p - base of `out`. Where four
// fragments are four consecutive pixels (a row's inside), the four updates at once, branch-free:
// with s1 / s2 "the first / second kept surface is this source" (s2 only without s1), lt1 = d < d1,
// lt2 = d < d2, keepTwoNearest's cases come to
//   slot 1 takes (d, t)            when lt1 and (s1, or neither, or s2 and lt2),
//   slot 2 takes slot 1's old pair when that holds and not s1,
//   slot 2 takes (d, t)            when lt2, not lt1 and not s1,
// the same comparisons on the same values. Elsewhere keepTwoNearest itself. Returns the first
// fragment not taken.
__attribute__((target("avx2"))) uint64_t keepTwoNearestRunAvx2(TwoNearest &out, size_t base, const uint32_t *pixelOf,
                                                               const double *depthOf, uint64_t f, uint64_t end,
                                                               size_t p1, uint32_t t, uint32_t first) {
    const __m128i sign = _mm_set1_epi32(INT32_MIN), one = _mm_set1_epi32(1);
    const __m128i firstB = _mm_xor_si128(_mm_set1_epi32(int32_t(first)), sign), tv = _mm_set1_epi32(int32_t(t));
    while (f < end && pixelOf[f] < p1) {
        const size_t p = pixelOf[f];
        if (f + 4 <= end && pixelOf[f + 3] == p + 3 && p + 3 < p1) {
            const size_t i = p - base;
            double *d1p = out.depth1.data() + i, *d2p = out.depth2.data() + i;
            __m128i *t1p = reinterpret_cast<__m128i *>(out.screen1.data() + i);
            __m128i *t2p = reinterpret_cast<__m128i *>(out.screen2.data() + i);
            const __m256d d = _mm256_loadu_pd(depthOf + f), d1 = _mm256_loadu_pd(d1p), d2 = _mm256_loadu_pd(d2p);
            const __m128i t1 = _mm_loadu_si128(t1p), t2 = _mm_loadu_si128(t2p);
            // (t + 1) > first, unsigned (kNoFragment + 1 wraps to 0): both biased by 2^31, then signed.
            const __m128i s1 = _mm_cmpgt_epi32(_mm_xor_si128(_mm_add_epi32(t1, one), sign), firstB);
            const __m128i s2 = _mm_andnot_si128(s1, _mm_cmpgt_epi32(_mm_xor_si128(_mm_add_epi32(t2, one), sign), firstB));
            const __m128i neither = _mm_andnot_si128(_mm_or_si128(s1, s2), _mm_set1_epi32(-1));
            const __m128i lt1 = to32(_mm256_cmp_pd(d, d1, _CMP_LT_OQ)), lt2 = to32(_mm256_cmp_pd(d, d2, _CMP_LT_OQ));
            const __m128i a = _mm_and_si128(lt1, _mm_or_si128(_mm_or_si128(s1, neither), _mm_and_si128(s2, lt2)));
            const __m128i b = _mm_andnot_si128(s1, a);
            const __m128i c = _mm_andnot_si128(_mm_or_si128(lt1, s1), lt2);
            _mm256_storeu_pd(d1p, _mm256_blendv_pd(d1, d, to64(a)));
            _mm256_storeu_pd(d2p, _mm256_blendv_pd(_mm256_blendv_pd(d2, d, to64(c)), d1, to64(b)));
            _mm_storeu_si128(t1p, _mm_blendv_epi8(t1, tv, a));
            _mm_storeu_si128(t2p, _mm_blendv_epi8(_mm_blendv_epi8(t2, tv, c), t1, b));
            f += 4;
            continue;
        }
        keepTwoNearest(out, p - base, t, first, depthOf[f]);
        ++f;
    }
    return f;
}

// The z-buffer's single-sided rule (ZBufferSettings::singleSided): a triangle of source s is drawn
// unless s is single-sided and its projected winding is the back one.
inline bool drawn(const uint8_t *singleSided, uint32_t s, bool frontWinding) {
    return !(singleSided && singleSided[s] && !frontWinding);
}

// The walk's fragments into keepTwoNearest.
struct TwoNearestSink {
    TwoNearest *out;
    const uint32_t *source;       // ScreenTriangles::source
    const uint8_t *singleSided;   // as ZBufferSettings::singleSided (may be null)
    uint32_t first = 0;           // first screen triangle of the walked triangle's source

    bool beginTriangle(size_t t, bool frontWinding) {
        const uint32_t current = source[t];
        for (first = uint32_t(t); first > 0 && source[first - 1] == current;) --first;
        return drawn(singleSided, current, frontWinding);
    }
    void fragment(size_t pixel, size_t t, double d) { keepTwoNearest(*out, pixel, uint32_t(t), first, d); }
    void endTriangle(size_t, uint64_t) {}
};

}  // namespace

TwoNearest findTwoNearest(const ScreenTriangles &tris, int width, int height, bool orthographic,
                          const uint8_t *singleSided) {
    TwoNearest r;
    findTwoNearest(tris, width, height, orthographic, singleSided, r);
    return r;
}

void findTwoNearest(const ScreenTriangles &tris, int width, int height, bool orthographic, const uint8_t *singleSided,
                    TwoNearest &r) {
    r.width = std::max(width, 0);
    r.height = std::max(height, 0);
    const size_t n = size_t(r.width) * size_t(r.height);
    r.depth1.assign(n, kInf);
    r.depth2.assign(n, kInf);
    r.screen1.assign(n, kNoFragment);
    r.screen2.assign(n, kNoFragment);
    if (n == 0) return;
    TwoNearestSink sink{&r, tris.source.data(), singleSided};
    forEachFragment(tris, r.width, r.height, orthographic, sink);
}

namespace {

// Records a walk's fragments and each triangle's range, with the z-fighting pass's single-sided
// rule (TwoNearestSink's).
struct RecordingSink {
    FragmentCache *cache;
    const uint32_t *source;
    const uint8_t *singleSided;
    bool beginTriangle(size_t t, bool frontWinding) { return drawn(singleSided, source[t], frontWinding); }
    void fragment(size_t pixel, size_t, double d) {
        cache->pixel.push_back(uint32_t(pixel));
        cache->depth.push_back(d);
    }
    void endTriangle(size_t t, uint64_t) { cache->begin[t + 1] = cache->pixel.size(); }
};

// forEachFragment's frontWinding of a screen triangle: a negative snapped signed area.
bool frontWinding(const int32_t *v) {
    const int64_t e1x = int64_t(v[2]) - v[0], e1y = int64_t(v[3]) - v[1];
    const int64_t e2x = int64_t(v[4]) - v[0], e2y = int64_t(v[5]) - v[1];
    return e1x * e2y - e1y * e2x < 0;
}

bool samePlane(const DepthPlane &a, const DepthPlane &b) {
    return a.valid == b.valid && std::memcmp(&a.a, &b.a, sizeof a.a) == 0 && std::memcmp(&a.b, &b.b, sizeof a.b) == 0 &&
           std::memcmp(&a.c, &b.c, sizeof a.c) == 0;
}

// findTwoNearestFromReference; with `bandLocal`, r holds one band at a time (pixel p of band
// [p0, p1) at index p - p0, final when bandDone(p0, p1) is called): a band's state stays in the
// core's cache instead of streaming a whole view's (48 MB at 1080p) through memory.
bool twoNearestFromReference(const Scene &scene, const ReferenceVisibility &ref, const ScreenTriangles &tris, int width,
                             int height, bool orthographic, const uint8_t *singleSided, TwoNearest &r, bool bandLocal,
                             const std::function<void(size_t, size_t)> &bandDone) {
    const FragmentCache &cache = ref.fragmentCache;
    const ScreenTriangles &rs = ref.screen;
    if (!cache.complete() || cache.begin.size() != rs.size() + 1 || ref.width != width || ref.height != height)
        return false;
    r.width = std::max(width, 0);
    r.height = std::max(height, 0);
    const size_t W = size_t(r.width), n = W * size_t(r.height);
    // Every pixel is set band by band below.
    const size_t held = bandLocal ? std::min(n, kFragmentBandRows * W) : n;
    r.depth1.resize(held);
    r.depth2.resize(held);
    r.screen1.resize(held);
    r.screen2.resize(held);
    if (n == 0) return true;

    // Per source triangle, its first screen triangle in the reference (a source's pieces are
    // consecutive there, as in `tris`); the rule the reference's walk drew by.
    const size_t sources = scene.triangleCount();
    thread_local std::vector<uint32_t> firstOf;
    firstOf.assign(sources, UINT32_MAX);
    for (size_t t = rs.size(); t-- > 0;)
        if (rs.source[t] < sources) firstOf[rs.source[t]] = uint32_t(t);
    const std::vector<uint8_t> refSingleSided = singleSidedTriangles(scene);

    // Per screen triangle of `tris` that draws, in submission order, its fragments: a range of the
    // reference's cache, or (side) of the fragments walked here.
    struct Run {
        uint64_t at, end;
        uint32_t tri, first;  // the screen triangle and its source's first (keepTwoNearest)
        uint32_t side;        // 0: the reference's cache; else 1 + index into `walk`
    };
    thread_local std::vector<Run> runs;
    thread_local ScreenTriangles walk;
    thread_local FragmentCache walked;
    runs.clear();
    walk.clear();
    uint32_t piece = 0;
    for (size_t j = 0; j < tris.size(); ++j) {
        const uint32_t s = tris.source[j];
        piece = j > 0 && tris.source[j - 1] == s ? piece + 1 : 0;
        const int32_t *xy = &tris.xy[6 * j];
        const bool front = frontWinding(xy);
        if (!drawn(singleSided, s, front)) continue;
        const DepthPlane &plane = tris.planes[tris.plane[j]];
        const size_t t = s < sources && firstOf[s] != UINT32_MAX ? size_t(firstOf[s]) + piece : SIZE_MAX;
        if (t < rs.size() && rs.source[t] == s && std::memcmp(xy, &rs.xy[6 * t], 6 * sizeof(int32_t)) == 0 &&
            samePlane(plane, rs.planes[rs.plane[t]]) && drawn(refSingleSided.data(), s, front)) {
            if (cache.begin[t + 1] > cache.begin[t])
                runs.push_back({cache.begin[t], cache.begin[t + 1], uint32_t(j), uint32_t(j - piece), 0});
            continue;
        }
        runs.push_back({0, 0, uint32_t(j), uint32_t(j - piece), uint32_t(walk.size()) + 1});
        walk.xy.insert(walk.xy.end(), xy, xy + 6);
        walk.source.push_back(s);
        walk.plane.push_back(uint32_t(walk.planes.size()));
        walk.planes.push_back(plane);
    }
    if (walk.size()) {
        walked.begin.assign(walk.size() + 1, 0);
        walked.pixel.clear();
        walked.depth.clear();
        RecordingSink sink{&walked, walk.source.data(), singleSided};
        forEachFragment(walk, r.width, r.height, orthographic, sink);
        // Triangles the walk skipped (no endTriangle) hold no fragment.
        for (size_t i = 0; i < walk.size(); ++i) walked.begin[i + 1] = std::max(walked.begin[i + 1], walked.begin[i]);
        for (Run &u : runs)
            if (u.side) u.at = walked.begin[u.side - 1], u.end = walked.begin[u.side];
    }

    const size_t bandPixels = kFragmentBandRows * W, bands = (size_t(r.height) + kFragmentBandRows - 1) / kFragmentBandRows;
    auto pixelsOf = [&](const Run &u) { return u.side ? walked.pixel.data() : cache.pixel.data(); };
    thread_local std::vector<uint32_t> bandBegin, bandRuns;
    bandLists(runs.size(), bands, [&](size_t k) {
        const Run &u = runs[k];
        if (u.end == u.at) return std::pair<size_t, size_t>{1, 0};
        const uint32_t *px = pixelsOf(u);
        return std::pair<size_t, size_t>{px[u.at] / bandPixels, px[u.end - 1] / bandPixels};
    }, bandBegin, bandRuns);
    const bool avx2 = __builtin_cpu_supports("avx2");
    for (size_t b = 0; b < bands; ++b) {
        const size_t p0 = b * bandPixels, p1 = std::min(p0 + bandPixels, n);
        const size_t base = bandLocal ? p0 : 0;  // r's index of pixel p: p - base
        std::fill(r.depth1.begin() + ptrdiff_t(p0 - base), r.depth1.begin() + ptrdiff_t(p1 - base), kInf);
        std::fill(r.depth2.begin() + ptrdiff_t(p0 - base), r.depth2.begin() + ptrdiff_t(p1 - base), kInf);
        std::fill(r.screen1.begin() + ptrdiff_t(p0 - base), r.screen1.begin() + ptrdiff_t(p1 - base), kNoFragment);
        std::fill(r.screen2.begin() + ptrdiff_t(p0 - base), r.screen2.begin() + ptrdiff_t(p1 - base), kNoFragment);
        for (uint32_t k = bandBegin[b]; k < bandBegin[b + 1]; ++k) {
            Run &u = runs[bandRuns[k]];
            const uint32_t *pixelOf = pixelsOf(u);
            const double *depthOf = u.side ? walked.depth.data() : cache.depth.data();
            uint64_t f = u.at;
            if (avx2) f = keepTwoNearestRunAvx2(r, base, pixelOf, depthOf, f, u.end, p1, u.tri, u.first);
            for (; f < u.end && pixelOf[f] < p1; ++f) keepTwoNearest(r, pixelOf[f] - base, u.tri, u.first, depthOf[f]);
            u.at = f;
        }
        if (bandDone) bandDone(p0, p1);
    }
    return true;
}

}  // namespace

bool findTwoNearestFromReference(const Scene &scene, const ReferenceVisibility &ref, const ScreenTriangles &tris,
                                 int width, int height, bool orthographic, const uint8_t *singleSided, TwoNearest &r,
                                 const std::function<void(size_t, size_t)> &bandDone) {
    return twoNearestFromReference(scene, ref, tris, width, height, orthographic, singleSided, r, false, bandDone);
}

// ---- Triangle pairs: common vertices, shared edge, coplanarity --------------------------------

namespace {

struct PairInfo {
    bool coplanar = false;
    bool sharedEdge = false;       // exactly two common vertex positions
    bool edgeOnScreen = false;     // the shared edge has a part in front of the near plane
    double ex0 = 0, ey0 = 0, ex1 = 0, ey1 = 0;  // that part, projected, in pixel coordinates
};

void triangleVertices(const Scene &scene, uint32_t t, Vec3 v[3]) {
    for (int k = 0; k < 3; ++k) v[k] = scene.positions[scene.indices[3 * size_t(t) + k]];
}

// Coplanar up to the precision of the coordinates: every vertex of the smaller triangle lies within
//   tol = 64 * u * M     (u = 2^-53 the unit roundoff, M = largest |coordinate| of the six vertices)
// of the larger triangle's plane (the larger one's normal is the better conditioned). A coordinate
// is stored to within u*M, and the distance n.(p - v0)/|n| is computed with about ten roundings of
// quantities bounded by M, so exactly coplanar triangles pass with a wide margin; two surfaces that
// are apart by more than 64 half-ulps of the scene's coordinates (a 1 mm decal at 200 m: 1e-3 vs
// 1.4e-12) are not coplanar. Scales with the scene as STYLE.md asks where no exact rule exists.
bool coplanarTriangles(const Vec3 a[3], const Vec3 b[3]) {
    double M = 0;
    for (int k = 0; k < 3; ++k) M = std::max({M, maxAbs(a[k]), maxAbs(b[k])});
    const Vec3 na = cross(a[1] - a[0], a[2] - a[0]), nb = cross(b[1] - b[0], b[2] - b[0]);
    const bool aLarger = dot(na, na) >= dot(nb, nb);
    const Vec3 *ref = aLarger ? a : b, *other = aLarger ? b : a;
    const Vec3 n = aLarger ? na : nb;
    const double nl = length(n);
    if (!(nl > 0)) return false;
    const double tol = 64 * kDoubleEps * M;
    for (int k = 0; k < 3; ++k)
        if (!(std::fabs(dot(n, other[k] - ref[0])) / nl <= tol)) return false;
    return true;
}

struct PairCache {
    const Scene &scene;
    const Camera &cam;
    std::unordered_map<uint64_t, PairInfo> cache;

    static uint64_t key(uint32_t a, uint32_t b) {
        if (a > b) std::swap(a, b);
        return (uint64_t(a) << 32) | b;
    }

    // Pixel coordinates of a view-space point in front of the eye (the clipper's projection).
    void project(Vec3 v, double *px, double *py) const {
        const double w = cam.orthographic ? 1.0 : -v.z;
        *px = (cam.sx * v.x / w + 1.0) * (cam.width * 0.5);
        *py = (1.0 - cam.sy * v.y / w) * (cam.height * 0.5);
    }

    const PairInfo &get(uint32_t a, uint32_t b) {
        auto [it, inserted] = cache.try_emplace(key(a, b));
        if (!inserted) return it->second;
        PairInfo &info = it->second;
        Vec3 va[3], vb[3];
        triangleVertices(scene, a, va);
        triangleVertices(scene, b, vb);
        info.coplanar = coplanarTriangles(va, vb);
        // Common vertex positions (exact equality: a closed mesh's neighbours index the same vertex
        // or a bit-identical copy). Two -> a shared edge; three is a duplicate triangle (coplanar).
        Vec3 common[3];
        int nc = 0;
        for (int i = 0; i < 3; ++i) {
            bool dup = false;
            for (int k = 0; k < nc; ++k) dup = dup || common[k] == va[i];
            if (dup) continue;
            for (int j = 0; j < 3; ++j)
                if (va[i] == vb[j]) {
                    common[nc++] = va[i];
                    break;
                }
        }
        info.sharedEdge = nc == 2;
        if (info.sharedEdge) {
            // The edge in view space, cut to the part in front of the near plane (d >= near) so its
            // projection is finite, then projected to pixel coordinates.
            Vec3 p = transformPoint(cam.viewFromWorld, common[0]), q = transformPoint(cam.viewFromWorld, common[1]);
            const double n = cam.nearZ;
            const double dp = -p.z, dq = -q.z;
            bool visible = true;
            if (!cam.orthographic) {
                if (dp < n && dq < n) visible = false;
                else if (dp < n) p = p + (q - p) * ((n - dp) / (dq - dp));
                else if (dq < n) q = q + (p - q) * ((n - dq) / (dp - dq));
            }
            if (visible) {
                project(p, &info.ex0, &info.ey0);
                project(q, &info.ex1, &info.ey1);
                info.edgeOnScreen = std::isfinite(info.ex0) && std::isfinite(info.ey0) && std::isfinite(info.ex1) &&
                                    std::isfinite(info.ey1);
            }
        }
        return info;
    }
};

// Distance from (x, y) to the segment (x0, y0)-(x1, y1).
double distanceToSegment(double x, double y, double x0, double y0, double x1, double y1) {
    const double dx = x1 - x0, dy = y1 - y0;
    const double len2 = dx * dx + dy * dy;
    double t = len2 > 0 ? ((x - x0) * dx + (y - y0) * dy) / len2 : 0.0;
    t = std::clamp(t, 0.0, 1.0);
    return std::hypot(x - (x0 + t * dx), y - (y0 + t * dy));
}

// Does the line where the two depth planes give equal depth cross the pixel's square
// [x, x+1] x [y, y+1]? Both planes are evaluated at the four corners exactly as the rasterizer
// evaluates them ((a px + b py) + c); the difference is
//   Delta = vA - vB,  |error| <= gamma(4) (sA + sB),  s = |a px| + |b py| + |c|
// (three roundings in each evaluation, one in the subtraction; the coefficients are taken as
// exact: they are the surfaces the z-buffer draws). A corner whose |Delta| is within the bound is
// "on the line". Crossing: corners strictly on both sides, or at least one on the line and one
// strictly off it. All four within the bound: the planes are indistinguishable at this pixel, so
// there is no line to speak of (not an intersection). Perspective planes hold 1/d, so the sign of
// Delta is the depth order only where both values are positive: any corner at or behind the eye
// plane (plane value <= 0) makes the test say no.
bool planesCrossInPixel(const DepthPlane &A, const DepthPlane &B, int x, int y, bool orthographic) {
    bool pos = false, neg = false, on = false;
    for (int c = 0; c < 4; ++c) {
        const double px = double(x + (c & 1)), py = double(y + (c >> 1));
        const double vA = evalDepthPlane(A, px, py), vB = evalDepthPlane(B, px, py);
        if (!orthographic && !(vA > 0 && vB > 0)) return false;
        if (!std::isfinite(vA) || !std::isfinite(vB)) return false;
        const double sA = std::fabs(A.a * px) + std::fabs(A.b * py) + std::fabs(A.c);
        const double sB = std::fabs(B.a * px) + std::fabs(B.b * py) + std::fabs(B.c);
        const double bound = gamma(4) * (sA + sB);
        const double delta = vA - vB;
        if (delta > bound) pos = true;
        else if (delta < -bound) neg = true;
        else on = true;
    }
    return (pos && neg) || (on && (pos || neg));
}

// Name of the source object a triangle id belongs to (sources are contiguous in source order).
std::string sourceObjectName(const Scene &scene, uint32_t tri) {
    const auto &src = scene.sources;
    auto it = std::upper_bound(src.begin(), src.end(), tri,
                               [](uint32_t t, const SourceObject &s) { return t < s.firstTriangle; });
    if (it == src.begin()) return std::string();
    --it;
    return tri < it->firstTriangle + it->triangleCount ? it->name : std::string();
}

// Median of v (upper median for even sizes, so it is always one of the values); v is reordered.
double median(std::vector<double> &v) {
    if (v.empty()) return 0;
    const size_t m = v.size() / 2;
    std::nth_element(v.begin(), v.begin() + ptrdiff_t(m), v.end());
    return v[m];
}

// World-space point of view depth d on the ray through pixel coordinates (px, py).
Vec3 worldPointAt(const Camera &cam, double px, double py, double d) {
    const ViewRay r = viewRayThroughPixel(cam, px, py);
    // View point o + d * dir (dir.z = -1, so the parameter is the view depth); view axes are
    // (right, up, -forward) in world space.
    const Vec3 v = r.origin + r.direction * d;
    return cam.eye + cam.right * v.x + cam.up * v.y - cam.forward * v.z;
}

bool validate(const ZFightSettings &s, const Camera &cam, std::string *err) {
    if (s.formats.empty()) {
        *err = "no depth formats to evaluate; pass at least one (e.g. all of allDepthFormats())";
        return false;
    }
    if (s.formats.size() > 32) {
        *err = "at most 32 depth formats can be evaluated at once (the per-pixel fight mask has 32 bits)";
        return false;
    }
    for (size_t i = 0; i < s.formats.size(); ++i)
        for (size_t j = 0; j < i; ++j)
            if (s.formats[i] == s.formats[j]) {
                *err = "depth format '" + depthFormatName(s.formats[i]) + "' is listed twice; list each format once";
                return false;
            }
    for (const DepthFormatSpec &f : s.formats)
        if (!validateDepthFormatRange(f, cam.nearZ, cam.farZ, err)) return false;
    if (!(std::isfinite(s.sharedEdgePixels) && s.sharedEdgePixels >= 0)) {
        *err = "sharedEdgePixels must be a finite distance >= 0 (pixels); the default is 1";
        return false;
    }
    return true;
}

}  // namespace

// ---- Why a hotspot fights ------------------------------------------------------------------------

void explainHotspot(double nearZ, double farZ, const std::optional<DepthFormatSpec> &viewFormat, bool coplanar,
                    ZFightHotspot *h) {
    auto m = [](double v) {
        char b[32];
        std::snprintf(b, sizeof b, "%.3g m", v);
        return std::string(b);
    };
    h->coplanar = coplanar;
    h->viewBucketWidth.reset();
    h->cheapestFormat.reset();
    h->cheapestBucketWidth.reset();
    std::string view;
    if (viewFormat)
        if (const auto b = depthBucketAt(makeDepthEncoder(*viewFormat, nearZ, farZ), h->depth)) {
            h->viewBucketWidth = b->width;
            view = depthFormatName(*viewFormat) + "'s stored-value bucket there is " + m(b->width) + " wide, " +
                   (b->width > h->depthGap ? "wider than the gap"
                                            : "no wider than the gap (its fighting pixels lie at other depths or gaps "
                                              "than these medians)");
        }
    if (coplanar) {
        h->why = "coplanar surfaces: no depth format can order them; offset one surface or use a depth bias";
        return;
    }
    // The cheapest format whose bucket at the hotspot's depth is no wider than the gap: then the
    // surface the gap behind lies in a later bucket, whatever the position inside this one.
    for (DepthFormat f : depthFormatsCheapestFirst()) {
        const auto b = depthBucketAt(makeDepthEncoder(f, nearZ, farZ), h->depth);
        if (b && b->width <= h->depthGap) {
            h->cheapestFormat = f;
            h->cheapestBucketWidth = b->width;
            break;
        }
    }
    h->why = "surfaces " + m(h->depthGap) + " apart at " + m(h->depth) + (view.empty() ? "" : "; " + view) + "; ";
    if (h->cheapestFormat)
        h->why += "the cheapest format that orders them there: " +
                  std::string(depthFormatInfo(*h->cheapestFormat).name) + " (" +
                  std::to_string(depthFormatInfo(*h->cheapestFormat).bits) + " bits, bucket " +
                  m(*h->cheapestBucketWidth) + ")";
    else
        h->why += "every format's bucket there is wider than the gap: move the surfaces apart or pull the near "
                  "plane out";
}

// ---- The analysis -----------------------------------------------------------------------------

namespace {

// ---- 2a. Pixels that cannot fight, decided without encoding --------------------------------------
//
// A two-surface pixel fights in a format when key(d1) >= key(d2) (d1 <= d2). Most such pixels hold
// surfaces far apart in depth (a wall and the room behind it), whose keys differ in every format:
// they need no encoding if that can be proven cheaply. The proof uses monotonicity: where a
// format's computed key never decreases as d grows, any depth in an interval has a key between the
// keys of the interval's ends. The view's depth range is cut into cells (equal steps of the
// doubles' bit patterns: 256 per octave, so a cell spans 0.4% of its depth); per format and cell,
// kmax bounds the keys of the cell's depths from above and kmin from below, and a pixel whose
// nearer depth's cell has kmax below the farther depth's cell's kmin cannot fight -- keys
// kmax(c1) >= key(d1) and key(d2) >= kmin(c2) > kmax(c1). Per cell c1 the first cell c2 from which
// that holds is precomputed, for every format at once, so the common pixel costs two cell indices
// and one comparison instead of 24 encodings. The others are encoded exactly, as before.
//
// Monotonicity, per format, for depths inside [minValidDepth, far] (no clamping; cells outside
// that range are unknown, and their pixels are encoded):
//   * exactly monotone: every operation is monotone in d and IEEE rounding preserves order:
//     float(d), float(1/d), (int)(C/d), (int)(C/(d+1)), float(n/d); unorm24_gl and the reversed
//     quotients n(f-d)/(d(f-n)) (a non-increasing numerator over a non-decreasing denominator);
//   * monotone beyond a relative window rho: the quotient f(d-n)/(d(f-n)) of unorm16/24 and f32
//     has a numerator and a denominator that both grow with d, so the rounded quotient may step
//     back by an ulp. It is g(d)(1 + t), |t| <= gamma(4) (d - n, f * that, d * fl(f - n), the
//     division), with g(d) = (f / fl(f-n))(1 - n/d) increasing; for d' = d(1 + r),
//     g(d')/g(d) - 1 = (n/d) r / ((1 + r)(1 - n/d)) >= (n/f) r / 2 (r <= 1), so the computed values
//     keep their order once (n/f) r / 2 >= E = 2 gamma(4) / (1 - gamma(4)), i.e. r >= rho = 2 E f / n;
//   * log24: log(C d + 1) / log(C f + 1) computed as fl(log(fl(fl(C d) + 1)) / D): the argument is
//     (1 + C d)(1 + eta), |eta| <= gamma(2), moving the logarithm by at most delta = 1.01 gamma(2);
//     glibc's log is within 0.52 ulp (its implementation's stated bound), taken here as 4 ulps
//     (8u relative), and the division adds u: eps = gamma(9) relative. With h(d) = log(1 + C d),
//     h(d') - h(d) >= log(1 + s r) >= s r / 2 for s r <= 1, s = C n / (1 + C n); order is kept once
//     s r / 2 >= 2 delta + 2 eps (h(f) + delta), i.e. r >= rho = (4 delta + 4 eps (h(f) + delta)) / s;
//   * f32_gl and f32_gl_reversed (opt-in): not filtered (their window value can cross zero).
// With rho > 0, kmax of a cell is the key at its upper end times (1 + 2 rho), rounded up, and kmin
// the key at its lower end divided by (1 + 2 rho), rounded down: every depth d of the cell lies a
// full window below the first and above the second.
constexpr uint32_t kCellBits = 12;  // at most 4096 cells over the view's depth range

}  // namespace

double monotoneWindow(const DepthEncoder &e) {
    const double n = e.nearZ, f = e.farZ;
    switch (e.format) {
    case DepthFormat::linear_f32:
    case DepthFormat::inv_f32:
    case DepthFormat::int31_inv:
    case DepthFormat::uint32_inv:
    case DepthFormat::uint32_inv1:
    case DepthFormat::unorm24_gl:
    case DepthFormat::f32_reversed:
    case DepthFormat::f32_reversed_inf:
    case DepthFormat::unorm16_reversed:
    case DepthFormat::unorm24_reversed: return 0;
    case DepthFormat::unorm16:
    case DepthFormat::unorm24:
    case DepthFormat::depth24plus:
    case DepthFormat::f32:
    case DepthFormat::depth32float: {
        const double E = 2 * gamma(4) / (1 - gamma(4));
        const double rho = 2 * E * f / n;
        return rho <= 0.25 ? rho : -1;
    }
    case DepthFormat::log24: {
        const double delta = 1.01 * gamma(2), eps = gamma(9);
        const double s = e.logC * n / (1 + e.logC * n);
        const double rho = (4 * delta + 4 * eps * (std::log(e.logC * f + 1) + delta)) / s;
        return std::isfinite(rho) && rho > 0 && rho <= 0.25 ? rho : -1;
    }
    case DepthFormat::f32_gl:
    case DepthFormat::f32_gl_reversed: return -1;
    }
    return -1;
}

namespace {

uint64_t doubleBits(double d) {
    uint64_t b;
    std::memcpy(&b, &d, sizeof b);
    return b;
}
double bitsDouble(uint64_t b) {
    double d;
    std::memcpy(&d, &b, sizeof d);
    return d;
}

template <DepthFormat F>
FightFilter::Cells safeCells(const DepthEncoder &enc, uint64_t base, int shift, uint32_t C, double rho) {
    const uint32_t kNever = C + 1;
    FightFilter::Cells out;
    out.firstSafe.assign(C + 1, kNever);
    const double lo = enc.minValidDepth, hi = enc.farZ;
    auto key = [&](double d) {
        uint32_t k = 0;
        bool oor = false;
        encodeDepth<F>(enc, d, k, oor);
        return k;
    };
    auto lower = [&](uint32_t c) { return bitsDouble(base + (uint64_t(c) << shift)); };
    // Known cells: the whole cell and its windows inside [lo, hi]. The conditions grow with c, so
    // the known cells are one run [first, last].
    std::vector<uint32_t> kmax(C, UINT32_MAX), kmin(C, 0);
    uint32_t first = C, last = 0;
    for (uint32_t c = 0; c < C; ++c) {
        const double g0 = lower(c), g1 = lower(c + 1);
        double up = g1, down = g0;
        if (rho > 0) {
            up = std::nextafter(g1 * (1 + 2 * rho), INFINITY);
            down = std::nextafter(g0 / (1 + 2 * rho), 0.0);
        }
        if (!(down >= lo && up <= hi)) continue;
        kmax[c] = key(up);
        kmin[c] = key(down);
        first = std::min(first, c);
        last = c;
    }
    if (first == C) return out;
    out.last = last;
    // Suffix minima of kmin over [c, last] (sorted), then per c1 the smallest c2 in (c1, last]
    // with sufMin[c2] > kmax[c1], by binary search.
    std::vector<uint32_t> sufMin(C, 0);
    sufMin[last] = kmin[last];
    for (uint32_t c = last; c-- > first;) sufMin[c] = std::min(kmin[c], sufMin[c + 1]);
    for (uint32_t c1 = first; c1 <= last; ++c1) {
        uint32_t a = c1 + 1, b = last + 1;
        while (a < b) {
            const uint32_t m = a + (b - a) / 2;
            if (sufMin[m] > kmax[c1]) b = m;
            else a = m + 1;
        }
        out.firstSafe[c1] = a <= last ? a : kNever;
    }
    return out;
}

}  // namespace

FightFilter::FightFilter(const std::vector<DepthEncoder> &encoders, double dMin, double dMax) {
    windows.assign(encoders.size(), -1);
    perFormat.resize(encoders.size());
    if (!(dMin > 0 && dMin <= dMax && std::isfinite(dMax))) return;
    base = doubleBits(dMin);
    const uint64_t span = doubleBits(dMax) - base + 1;
    shift = std::max(0, int(std::bit_width(span)) - int(kCellBits));
    count = uint32_t(((span - 1) >> shift) + 1);
    firstSafeAll.assign(count + 1, 0);
    lastAll = count;
    for (size_t i = 0; i < encoders.size(); ++i) {
        windows[i] = monotoneWindow(encoders[i]);
        if (windows[i] < 0) continue;
        perFormat[i] = dispatchDepthFormat(encoders[i].format, [&]<DepthFormat Fmt>() {
            return safeCells<Fmt>(encoders[i], base, shift, count, windows[i]);
        });
        for (uint32_t c = 0; c <= count; ++c) firstSafeAll[c] = std::max(firstSafeAll[c], perFormat[i].firstSafe[c]);
        lastAll = std::min(lastAll, perFormat[i].last);
        anyFiltered = true;
    }
}

uint32_t FightFilter::cell(double d) const {
    if (!(d > 0) || !std::isfinite(d) || count == 0) return count;
    const uint64_t b = doubleBits(d);
    return b < base || ((b - base) >> shift) >= count ? count : uint32_t((b - base) >> shift);
}

namespace {

// The pixels with two surfaces that may fight as lists (pixel, nearer and farther depth and screen
// triangle, ascending in pixel), the range of the depths of the pixels with one surface, those of
// their depths outside some format's valid range, and the counts; gathered a stretch of pixels at a
// time (the thread's storage, kept from view to view: only the first n entries are this view's).
// A pixel the filter decides cannot fight in any format (2a) is counted, not listed; every
// two-surface pixel is listed when a format is not filtered. Everything after the gathering reads
// the lists, so the two nearest surfaces need to be held only a band at a time.
struct TwoSurfaces {
    std::vector<uint32_t> pixel;
    std::vector<double> near1, near2;
    std::vector<uint32_t> screen1, screen2;
    size_t n = 0;        // listed
    uint64_t two = 0;    // pixels with two surfaces (listed or not)
    double oneMin = kInf, oneMax = -kInf;
    bool oneUnordered = false;  // a NaN depth: decided pixel by pixel
    // The one-surface depths outside [validLo, validHi], the range valid in every format (in that
    // range no format clamps, FilterForView): the only ones markFights may need to encode.
    std::vector<double> oneOutside;
    uint64_t covered = 0;  // pixels with a surface

    void clear() {
        n = 0;
        two = 0;
        oneMin = kInf, oneMax = -kInf;
        oneUnordered = false;
        oneOutside.clear();
        covered = 0;
    }
    // Pixels [p0, p1) of the view, after those gathered before; `twoNearest` holds pixel p at
    // p - base. [validLo, validHi]: FilterForView's.
    void gather(const TwoNearest &twoNearest, size_t base, const FightFilter &filter, double validLo, double validHi,
                size_t p0, size_t p1) {
        const bool listAll = !filter.filteredAll();
        const uint32_t *s1 = twoNearest.screen1.data(), *s2 = twoNearest.screen2.data();
        const double *d1s = twoNearest.depth1.data(), *d2s = twoNearest.depth2.data();
        const size_t viewPixels = size_t(twoNearest.width) * size_t(twoNearest.height);
        uint64_t cov = 0, pairs = 0;
        double lo = oneMin, hi = oneMax;
        bool unordered = oneUnordered;
        for (size_t p = p0; p < p1; ++p) {
            const size_t i = p - base;
            if (s1[i] == kNoFragment) continue;
            ++cov;
            const double d1 = d1s[i];
            if (s2[i] != kNoFragment) {
                ++pairs;
                const double d2 = d2s[i];
                if (!listAll && filter.cannotFightAny(filter.cell(d1), filter.cell(d2))) continue;
                if (n == pixel.size()) {
                    // Grown by half, never beyond the view's pixels (estimateMemory's bound).
                    const size_t size = std::min(std::max<size_t>(n + 1024, n + n / 2), viewPixels);
                    pixel.resize(size);
                    near1.resize(size);
                    near2.resize(size);
                    screen1.resize(size);
                    screen2.resize(size);
                }
                pixel[n] = uint32_t(p);
                near1[n] = d1;
                near2[n] = d2;
                screen1[n] = s1[i];
                screen2[n] = s2[i];
                ++n;
            } else {
                lo = std::min(lo, d1);
                hi = std::max(hi, d1);
                unordered |= d1 != d1;
                if (!(d1 >= validLo && d1 <= validHi)) oneOutside.push_back(d1);
            }
        }
        covered += cov;
        two += pairs;
        oneMin = lo, oneMax = hi, oneUnordered = unordered;
    }
    // The listed entry of pixel p (listed: the fighting pixels are).
    size_t entryOf(size_t p) const {
        return size_t(std::lower_bound(pixel.begin(), pixel.begin() + ptrdiff_t(n), uint32_t(p)) - pixel.begin());
    }
};

// 2a's cells over the camera's depth range [near, far] (what the clip keeps; a depth outside is never
// decided) and the formats' encoders: the thread's, kept while the camera's range and the formats
// stay (every view of a run, usually).
struct FilterForView {
    double nearZ = std::numeric_limits<double>::quiet_NaN(), farZ = nearZ;
    std::vector<DepthFormatSpec> formats;
    std::vector<DepthEncoder> enc;
    std::optional<FightFilter> filter;
    // The depths every format stores unclamped: [max minValidDepth, min far] over the encoders.
    double validLo = -kInf, validHi = kInf;

    const FightFilter &get(const Camera &cam, const std::vector<DepthFormatSpec> &specs) {
        if (filter && doubleBits(nearZ) == doubleBits(cam.nearZ) && doubleBits(farZ) == doubleBits(cam.farZ) &&
            formats == specs)
            return *filter;
        nearZ = cam.nearZ, farZ = cam.farZ, formats = specs;
        enc.resize(specs.size());
        validLo = -kInf, validHi = kInf;
        for (size_t i = 0; i < specs.size(); ++i) {
            enc[i] = makeDepthEncoder(specs[i], cam.nearZ, cam.farZ);
            validLo = std::max(validLo, enc[i].minValidDepth);
            validHi = std::min(validHi, enc[i].farZ);
        }
        filter.emplace(enc, cam.nearZ, cam.farZ);
        return *filter;
    }
};

// 2. Per format: the fight bit (key(d1) >= key(d2), d1 <= d2: equal stored values or swapped order)
//    and out-of-range pixels (either surface clamped by the encoder). The two-surface pixels that
//    cannot fight in any filtered format (2a) were left out of the lists while gathering; every
//    format encodes the listed pixels it does not filter out (every one, for a format not filtered).
//    A one-surface pixel needs no encoding when its depth is in [minValidDepth, far] (every format
//    clamps d into [minValidDepth, hi] with hi = far or +inf, render/depth_format_impl.h), which the
//    one-surface depths' range decides for all of them at once, per format; otherwise they are
//    encoded one by one.
void markFights(const TwoSurfaces &lists, const FilterForView &view, const ZFightSettings &settings, ZFightResult &r) {
    const size_t F = settings.formats.size();
    const std::vector<uint32_t> &pixel = lists.pixel;
    const std::vector<double> &near1 = lists.near1, &near2 = lists.near2;
    const size_t n2 = lists.n;
    const double oneMin = lists.oneMin, oneMax = lists.oneMax;
    const bool oneUnordered = lists.oneUnordered;
    const FightFilter &filter = *view.filter;
    thread_local std::vector<uint32_t> mask, cell1, cell2;  // per listed pixel
    if (mask.size() < n2) mask.resize(n2), cell1.resize(n2), cell2.resize(n2);
    std::fill_n(mask.begin(), n2, 0u);
    for (size_t k = 0; k < n2; ++k) {
        cell1[k] = filter.cell(near1[k]);
        cell2[k] = filter.cell(near2[k]);
    }

    for (size_t i = 0; i < F; ++i) {
        const DepthEncoder &e = view.enc[i];
        const uint32_t bit = uint32_t(1) << i;
        const double lo = e.minValidDepth, hi = e.farZ;
        const bool oneInRange = !oneUnordered && oneMin >= lo && oneMax <= hi;
        uint64_t oor = 0;
        dispatchDepthFormat(e.format, [&]<DepthFormat Fmt>() {
            // The others cannot fight here and lie in the format's range (FightFilter).
            for (size_t k = 0; k < n2; ++k) {
                if (filter.cannotFight(i, cell1[k], cell2[k])) continue;
                uint32_t k1 = 0, k2 = 0;
                bool o1 = false, o2 = false;
                encodeDepth<Fmt>(e, near1[k], k1, o1);
                encodeDepth<Fmt>(e, near2[k], k2, o2);
                mask[k] |= k1 >= k2 ? bit : 0;
                oor += (o1 || o2) ? 1 : 0;
            }
            if (oneInRange) return;
            // The one-surface depths in every format's range are in this one's.
            for (const double d1 : lists.oneOutside) {
                if (d1 >= lo && d1 <= hi) continue;
                uint32_t k1 = 0;
                bool o1 = false;
                encodeDepth<Fmt>(e, d1, k1, o1);
                oor += o1 ? 1 : 0;
            }
        });
        r.perFormat[i].outOfRangePixels = oor;
    }
    r.fightPixels.clear();
    r.fightMasks.clear();
    for (size_t k = 0; k < n2; ++k)
        if (mask[k]) r.fightPixels.push_back(pixel[k]), r.fightMasks.push_back(mask[k]);
}

// 3. Classify the pixels that fight somewhere: shared_edge, then intersection (never for coplanar
//    triangles: they have no intersection line), then coplanar, else separated. Returns the smallest
//    d2 - d1 over separated fighting pixels (for the recommendation's text).
//    The fighting pixels are r.fightPixels, in scan order, and in the lists (markFights).
double classifyFights(const Scene &scene, const Camera &cam, const ScreenTriangles &tris, const TwoSurfaces &lists,
                      const ZFightSettings &settings, ZFightResult &r) {
    const size_t W = size_t(r.width);
    const size_t F = settings.formats.size();
    PairCache pairs{scene, cam, {}};
    double minSeparatedGap = kInf;  // smallest d2 - d1 over separated fighting pixels (for the text)
    for (size_t j = 0, k = 0; j < r.fightPixels.size(); ++j) {
        const size_t p = r.fightPixels[j];
        const uint32_t mask = r.fightMasks[j];
        while (lists.pixel[k] != p) ++k;  // both ascend, and every fighting pixel is listed
        const int x = int(p % W), y = int(p / W);
        const uint32_t t1 = lists.screen1[k], t2 = lists.screen2[k];
        const uint32_t s1 = tris.source[t1], s2 = tris.source[t2];
        const PairInfo &info = pairs.get(s1, s2);
        ZPixelClass c = ZPixelClass::separated;
        if (info.sharedEdge && info.edgeOnScreen &&
            distanceToSegment(x + 0.5, y + 0.5, info.ex0, info.ey0, info.ex1, info.ey1) <=
                settings.sharedEdgePixels)
            c = ZPixelClass::shared_edge;
        else if (!info.coplanar && planesCrossInPixel(tris.planes[tris.plane[t1]], tris.planes[tris.plane[t2]], x,
                                                      y, cam.orthographic))
            c = ZPixelClass::intersection;
        else if (info.coplanar)
            c = ZPixelClass::coplanar;
        r.pixelClass[p] = uint8_t(c);
        if (c == ZPixelClass::separated) minSeparatedGap = std::min(minSeparatedGap, lists.near2[k] - lists.near1[k]);
        ++r.fightingPixelsAnyFormat;
        switch (c) {
        case ZPixelClass::separated: ++r.separatedPixels; break;
        case ZPixelClass::coplanar: ++r.coplanarPixels; break;
        case ZPixelClass::shared_edge: ++r.sharedEdgePixels; break;
        case ZPixelClass::intersection: ++r.intersectionPixels; break;
        case ZPixelClass::none: break;
        }
        for (size_t i = 0; i < F; ++i) {
            if (!(mask >> i & 1)) continue;
            ZFightFormatStats &st = r.perFormat[i];
            switch (c) {
            case ZPixelClass::coplanar: ++st.coplanarPixels; [[fallthrough]];
            case ZPixelClass::separated: ++st.fightingPixels; break;
            case ZPixelClass::shared_edge: ++st.sharedEdgePixels; break;
            case ZPixelClass::intersection: ++st.intersectionPixels; break;
            case ZPixelClass::none: break;
            }
        }
    }

    return minSeparatedGap;
}

// 4. Hotspots: 8-connected components of separated/coplanar fighting pixels, flood-filled from seeds
//    in scan order (component k's seed is its first pixel in scan order); those of at least
//    minHotspotArea pixels, area descending, ties by seed, each explained (6.).
void findHotspots(const Scene &scene, const Camera &cam, const ScreenTriangles &tris, const TwoSurfaces &lists,
                  const ZFightSettings &settings, ZFightResult &r) {
    const int W = r.width, H = r.height;
    const size_t N = size_t(W) * size_t(H), F = settings.formats.size();
    auto isHotspotPixel = [&](size_t p) {
        const auto c = ZPixelClass(r.pixelClass[p]);
        return c == ZPixelClass::separated || c == ZPixelClass::coplanar;
    };
    struct Component {
        size_t seed = 0;
        uint64_t area = 0;
        ZFightHotspot h;
        std::vector<uint64_t> formatPixels;
    };
    std::vector<Component> comps;
    // The components' labels (1-based component index; 0 = none): the thread's, all 0 between
    // calls (the labeled pixels are cleared at the end).
    thread_local std::vector<uint32_t> label;
    if (label.size() != N) label.assign(N, 0);
    std::vector<size_t> stack, members;
    std::vector<double> depths, gaps;
    // Seeds in scan order: a hotspot pixel fights, and the fighting pixels ascend.
    for (const uint32_t seed : r.fightPixels) {
        if (!isHotspotPixel(seed) || label[seed]) continue;
        comps.emplace_back();
        const uint32_t id = uint32_t(comps.size());
        Component &cp = comps.back();
        cp.seed = seed;
        cp.formatPixels.assign(F, 0);
        ZFightHotspot &h = cp.h;
        h.minX = W, h.minY = H, h.maxX = -1, h.maxY = -1;
        members.clear();
        stack.assign(1, seed);
        label[seed] = id;
        while (!stack.empty()) {
            const size_t p = stack.back();
            stack.pop_back();
            members.push_back(p);
            const int x = int(p % size_t(W)), y = int(p / size_t(W));
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int nx = x + dx, ny = y + dy;
                    if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= W || ny >= H) continue;
                    const size_t q = size_t(ny) * size_t(W) + size_t(nx);
                    if (label[q] || !isHotspotPixel(q)) continue;
                    label[q] = id;
                    stack.push_back(q);
                }
        }
        // Statistics over the members.
        depths.clear();
        gaps.clear();
        std::unordered_map<uint64_t, uint64_t> pairCount;
        Vec3 sum;
        for (size_t p : members) {
            const int x = int(p % size_t(W)), y = int(p / size_t(W));
            h.minX = std::min(h.minX, x), h.maxX = std::max(h.maxX, x);
            h.minY = std::min(h.minY, y), h.maxY = std::max(h.maxY, y);
            const size_t k = lists.entryOf(p);
            const double d1 = lists.near1[k], d2 = lists.near2[k];
            sum = sum + worldPointAt(cam, x + 0.5, y + 0.5, d1);
            depths.push_back(d1);
            gaps.push_back(d2 - d1);  // >= 0: d1 <= d2 by construction
            h.depthGapMax = std::max(h.depthGapMax, d2 - d1);
            if (ZPixelClass(r.pixelClass[p]) == ZPixelClass::coplanar) ++h.coplanarPixels;
            ++pairCount[PairCache::key(tris.source[lists.screen1[k]], tris.source[lists.screen2[k]])];
            const uint32_t mask = r.fightMaskAt(p);
            for (size_t i = 0; i < F; ++i) cp.formatPixels[i] += mask >> i & 1;
        }
        cp.area = members.size();
        h.area = cp.area;
        h.centroid = sum / double(cp.area);
        h.depth = median(depths);
        h.depthGap = median(gaps);
        uint64_t bestKey = 0, bestCount = 0;
        for (const auto &[k, c] : pairCount)
            if (c > bestCount || (c == bestCount && k < bestKey)) bestKey = k, bestCount = c;
        h.triangleA = uint32_t(bestKey >> 32);
        h.triangleB = uint32_t(bestKey & 0xFFFFFFFFu);
        h.pairPixels = bestCount;
        h.pairs = pairCount.size();
    }

    // Hotspots: components of at least minHotspotArea pixels, area descending, ties by seed.
    std::vector<uint32_t> order;
    for (uint32_t k = 0; k < comps.size(); ++k)
        if (comps[k].area >= std::max<uint64_t>(settings.minHotspotArea, 1)) order.push_back(k);
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
        return comps[a].area != comps[b].area ? comps[a].area > comps[b].area : comps[a].seed < comps[b].seed;
    });
    r.hotspotCount = order.size();
    std::vector<uint32_t> idOfComp(comps.size(), 0);
    for (size_t rank = 0; rank < order.size(); ++rank) {
        Component &cp = comps[order[rank]];
        idOfComp[order[rank]] = uint32_t(rank + 1);
        for (size_t i = 0; i < F; ++i)
            if (cp.formatPixels[i]) ++r.perFormat[i].hotspots;
        if (rank >= settings.maxHotspotsListed) continue;
        ZFightHotspot h = std::move(cp.h);
        h.id = uint32_t(rank + 1);
        h.objectA = sourceObjectName(scene, h.triangleA);
        h.objectB = sourceObjectName(scene, h.triangleB);
        for (size_t i = 0; i < F; ++i)
            if (cp.formatPixels[i]) h.formats.push_back({settings.formats[i], cp.formatPixels[i]});
        // 6. Why it fights, at its median depth and gap.
        explainHotspot(cam.nearZ, cam.farZ, settings.viewFormat, h.coplanarPixels == h.area, &h);
        r.hotspots.push_back(std::move(h));
    }
    // Every hotspot pixel has a label, and only they.
    r.hotspotPixels.clear();
    r.hotspotIds.clear();
    for (const uint32_t p : r.fightPixels) {
        if (!isHotspotPixel(p)) continue;
        if (const uint32_t id = idOfComp[label[p] - 1]) r.hotspotPixels.push_back(p), r.hotspotIds.push_back(id);
        label[p] = 0;
    }
}

// 5. Recommendation: fewest bits with no non-coplanar fighting pixel; ties in settings order.
void recommend(double minSeparatedGap, ZFightResult &r) {
    const ZFightFormatStats *best = nullptr, *leastFighting = nullptr;
    for (const ZFightFormatStats &st : r.perFormat) {
        const uint64_t genuine = st.fightingPixels - st.coplanarPixels;
        if (genuine == 0 && (!best || st.bits < best->bits)) best = &st;
        if (!leastFighting || genuine < leastFighting->fightingPixels - leastFighting->coplanarPixels)
            leastFighting = &st;
    }
    if (best) {
        r.recommended = best->format;
        r.recommendation = best->name + std::string(": the fewest bits (") + std::to_string(best->bits) +
                           ") with no fighting pixels in this view";
    } else {
        const uint64_t n = leastFighting->fightingPixels - leastFighting->coplanarPixels;
        char gap[32];
        std::snprintf(gap, sizeof gap, "%.3g", minSeparatedGap);
        r.recommendation = "every format fights at surfaces that are not coplanar (fewest: " + leastFighting->name +
                           ", " + std::to_string(n) + " pixels; surfaces down to " + gap +
                           " m apart): move the surfaces apart, push the near plane out or pull the far plane in";
    }
    if (r.coplanarPixels > 0)
        r.recommendation += "; coplanar surfaces fight in every format: offset the decal or use a depth bias (" +
                            std::to_string(r.coplanarPixels) + " pixels, not counted here)";
}

}  // namespace

ZFightResult analyzeZFighting(const Scene &scene, const Camera &cam, const ScreenTriangles &tris,
                              const ZFightSettings &settings) {
    ZFightResult r;
    if (!validate(settings, cam, &r.error)) return r;
    const int W = std::max(cam.width, 0), H = std::max(cam.height, 0);
    const size_t N = size_t(W) * size_t(H);
    const size_t F = settings.formats.size();
    r.width = W;
    r.height = H;
    r.nearZ = cam.nearZ;
    r.farZ = cam.farZ;
    r.formats = settings.formats;
    r.pixelClass.assign(N, uint8_t(ZPixelClass::none));
    r.perFormat.resize(F);
    for (size_t i = 0; i < F; ++i) {
        const DepthFormatInfo &info = depthFormatInfo(settings.formats[i].format);
        r.perFormat[i].format = settings.formats[i];
        r.perFormat[i].name = depthFormatName(settings.formats[i]);
        r.perFormat[i].bits = info.bits;
    }

    // 1. Two nearest surfaces.
    // This thread's buffers, reused from view to view (fresh ones cost more in page faults than
    // filling them). From the reference, the two nearest surfaces are held a band at a time.
    thread_local TwoNearest two;
    thread_local TwoSurfaces lists;
    thread_local FilterForView filter;
    const FightFilter &cells = filter.get(cam, settings.formats);
    lists.clear();
    if (!settings.reference ||
        !twoNearestFromReference(scene, *settings.reference, tris, W, H, cam.orthographic, settings.singleSided, two,
                                 true, [&](size_t p0, size_t p1) {
                                     lists.gather(two, p0, cells, filter.validLo, filter.validHi, p0, p1);
                                 })) {
        findTwoNearest(tris, W, H, cam.orthographic, settings.singleSided, two);
        lists.gather(two, 0, cells, filter.validLo, filter.validHi, 0, N);
    }
    r.coveredPixels = lists.covered;
    r.twoSurfacePixels = lists.two;

    markFights(lists, filter, settings, r);
    const double minSeparatedGap = classifyFights(scene, cam, tris, lists, settings, r);
    findHotspots(scene, cam, tris, lists, settings, r);
    recommend(minSeparatedGap, r);
    return r;
}

}  // namespace va
