// Audits against the truth (audit.h; the definitions and constants are derived in docs/audits.md).
#include "analysis/audits/audit.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <unordered_map>

#include <immintrin.h>

#include "analysis/stages/backface.h"
#include "common/id_runs.h"
#include "render/raster.h"
#include "render/raster_core.h"
#include "render/recycle.h"
#include "render/stopwatch.h"

namespace va {

namespace {


// The reference as a fragment sink: single-sided triangles only with the front winding, LESS on
// the double depth with ties to the lowest id (so the order of submission does not matter).
struct ReferenceSink {
    const Scene &scene;
    const Camera &cam;
    const int32_t *xy;  // the screen triangles' fixed-point corners
    const uint32_t *source;
    const uint8_t *singleSided;
    uint32_t *id;
    double *depth;
    uint8_t *snappedFront;
    FragmentCache *cache;  // null: not recorded
    uint64_t cacheMax = 0;
    uint32_t current = 0;  // 1 + source of the triangle being walked
    uint64_t backWinding = 0, fragments = 0;
    bool overflow = false;

    bool beginTriangle(size_t t, bool frontWinding) {
        const uint32_t s = source[t];
        if (singleSided[s] && !frontWinding) {
            ++backWinding;
            return false;
        }
        if (singleSided[s] && isSnappedSliver(t) && !isFrontFacing(scene, s, cam)) snappedFront[s] = 1;
        current = s + 1;
        return true;
    }
    // Whether snapping can have flipped the winding of front-wound screen triangle t. Each corner
    // is the projected point rounded to the nearest fixed-point unit (toFixed), so each component
    // of the edges e1 = v1 - v0, e2 = v2 - v0 is off by at most 1 unit, and twice the area
    // A = e1.x e2.y - e1.y e2.x by at most |e1.x| + |e1.y| + |e2.x| + |e2.y| + 2 (the projection's
    // own rounding, relative 2^-50 of coordinates below 2^30, adds far less than the + 2 more of
    // slack). The exact winding can only differ from the snapped one (A < 0: front) when |A| is
    // within that bound. The exact test runs only then: slivers are rare, so it costs nothing.
    bool isSnappedSliver(size_t t) const {
        const int32_t *v = xy + 6 * t;
        const int64_t e1x = int64_t(v[2]) - v[0], e1y = int64_t(v[3]) - v[1];
        const int64_t e2x = int64_t(v[4]) - v[0], e2y = int64_t(v[5]) - v[1];
        const int64_t area = e1x * e2y - e1y * e2x;
        return -area <= std::abs(e1x) + std::abs(e1y) + std::abs(e2x) + std::abs(e2y) + 4;
    }
    void fragment(size_t i, size_t, double d) {
        if (cache) {
            // Recorded only: the depth test runs afterwards from the cache, band by band
            // (resolveFromCache). When the cache is full the walk runs again without it.
            if (cache->pixel.size() == cacheMax) {
                overflow = true;
            } else {
                cache->pixel.push_back(uint32_t(i));
                cache->depth.push_back(d);
            }
            return;
        }
        const double old = depth[i];
        if (d < old || (d == old && current < id[i])) {
            depth[i] = d;
            id[i] = current;
        }
    }
    void endTriangle(size_t t, uint64_t n) {
        fragments += n;
        if (cache) cache->begin[t + 1] = cache->pixel.size();
    }
};

// Unit roundoff of float (Embree's arithmetic) and pbrt's gamma(n) = n u / (1 - n u): a bound on
// the relative error of n successive roundings.
constexpr double kFloatU = 0x1p-24;
constexpr double gammaF(int n) { return n * kFloatU / (1 - n * kFloatU); }

}  // namespace

// The reference's depth test (LESS on the double depth, ties to the lowest id) over the cached
// fragments, band by band (forEachCachedFragmentByBand): the band's slice of the depth and id
// buffers (370 KB at 1080p) stays in the core's L2 instead of the walk's random access into 24 MB.
// The rule does not depend on the order of the fragments, so the result is the walk's. The same
// pass draws the submitted order (FragmentCache::SubmittedDraw): its passes are the fragments
// strictly nearer than the pixel's depth so far, which both rules keep; its ids are kept for the
// band only and compared with the reference's when the band is done.
void resolveFromCache(FragmentCache &cache, const uint32_t *source, size_t width, size_t height, uint32_t *id,
                      double *depth) {
    const Stopwatch t0;
    FragmentCache::SubmittedDraw &sub = cache.submitted;
    sub.differs.clear();
    thread_local std::vector<uint32_t> bandIds;  // the submitted ids of the band: pixel - p0
    bandIds.assign(kFragmentBandRows * width, 0);
    size_t p0 = 0;
    uint64_t passes = 0, covered = 0;
    uint32_t *subId = bandIds.data();
    uint32_t lastT = UINT32_MAX, current = 0;
    forEachCachedFragmentByBand(
        cache, width, height,
        [&](uint32_t i, uint32_t t, double d) {
            // A triangle's fragments come in runs: its source is read once per run (per fragment,
            // the id stores could alias it).
            if (t != lastT) lastT = t, current = source[t] + 1;
            const double old = depth[i];
            if (d < old) {
                ++passes;
                covered += old == std::numeric_limits<double>::infinity();
                subId[i - p0] = current;
                depth[i] = d;
                id[i] = current;
            } else if (d == old && current < id[i]) {
                id[i] = current;
            }
        },
        [&](size_t b0, size_t b1) {
            // Mostly equal: eight pixels at a time are compared in one vectorizable test.
            const size_t n = b1 - b0;
            for (size_t k = 0; k < n; k += 8) {
                const size_t e = std::min(n, k + 8);
                uint32_t x = 0;
                for (size_t j = k; j < e; ++j) x |= subId[j] ^ id[b0 + j];
                if (x)
                    for (size_t j = k; j < e; ++j)
                        if (subId[j] != id[b0 + j]) sub.differs.push_back({uint32_t(b0 + j), subId[j]});
            }
            std::fill(subId, subId + n, 0u);
            p0 = b1;
        });
    sub.fragments = cache.pixel.size();
    sub.passes = passes;
    sub.covered = covered;
    sub.ms = t0.ms();
}

ViewTriangle viewTriangle(const Scene &scene, const Camera &cam, Vec3 rayOrigin, uint32_t t) {
    ViewTriangle v;
    const double eyeFrame = length(cam.eye - rayOrigin);
    for (int i = 0; i < 3; ++i) {
        const Vec3 w = scene.positions[scene.indices[3 * size_t(t) + i]];
        v.P[i] = transformPoint(cam.viewFromWorld, w);
        v.M[i] = length(w - rayOrigin) + eyeFrame;
    }
    v.plane = depthPlaneFromView(cam, v.P[0], v.P[1], v.P[2]);
    return v;
}

// The ray caster's depth error for triangle v at (px, py), depth d: the hit point's error across
// the plane (vertices and ray origin rounded to float: sqrt(3) u M each; the intersection's own
// arithmetic: gamma(kEmbreeEdgeOps) of the magnitudes, t |D| and |Q|), turned into an error along
// the ray by 1 / |n.D| (a grazing ray moves far along itself for a small move across the plane).
// Its terms that depend on neither the ray's direction nor the depth, from q[i] = |P[i] - the ray's
// origin| (edgeDistance has them at hand):
struct RayDepthTerms {
    Vec3 n;  // the triangle's (unnormalized) normal
    double nl = 0, maxM = 0, maxQ = 0;
};

namespace {

RayDepthTerms rayDepthTerms(const ViewTriangle &v, const double q[3]) {
    RayDepthTerms t;
    t.n = cross(v.P[1] - v.P[0], v.P[2] - v.P[0]);
    t.nl = length(t.n);
    for (int i = 0; i < 3; ++i) {
        t.maxM = std::max(t.maxM, v.M[i]);
        t.maxQ = std::max(t.maxQ, q[i]);
    }
    return t;
}
// r: the ray through (px, py).
double rayDepthError(const RayDepthTerms &t, const ViewRay &r, double d) {
    const double across =
        std::sqrt(3.0) * kFloatU * t.maxM + gammaF(kEmbreeEdgeOps) * (d * length(r.direction) + t.maxQ);
    const double cosine = t.nl > 0 ? std::fabs(dot(t.n, r.direction)) / t.nl : 0;
    return cosine > 0 ? across / cosine + kFloatU * d : std::numeric_limits<double>::infinity();
}

double rayDepthError(const Camera &cam, const ViewTriangle &v, double px, double py, double d) {
    const ViewRay r = viewRayThroughPixel(cam, px, py);
    const double q[3] = {length(v.P[0] - r.origin), length(v.P[1] - r.origin), length(v.P[2] - r.origin)};
    return rayDepthError(rayDepthTerms(v, q), r, d);
}

}  // namespace

// ---- Reference visibility ----------------------------------------------------------------------

std::vector<uint8_t> singleSidedTriangles(const Scene &scene) {
    std::vector<uint8_t> s(scene.triangleCount(), 0);
    for (const SceneObject &o : scene.objects) {
        if (scene.materialOf(o).doubleSided) continue;
        for (uint32_t k = o.triBegin; k < o.triEnd; ++k) s[scene.objectTriangles[k]] = 1;
    }
    return s;
}

void recycleFragmentCache(FragmentCache &c) {
    FragmentCache kept = std::move(c);
    c = FragmentCache{};
    if (kept.pixel.capacity() == 0 && kept.depth.capacity() == 0) return;
    kept.begin.clear();
    kept.pixel.clear();
    kept.depth.clear();
    kept.rasterMs = 0;
    kept.submitted.differs.clear();
    recyclerOf<FragmentCache>().give(std::move(kept));
}

ReferenceVisibility referenceVisibility(const Scene &scene, const Camera &cam, uint64_t maxCachedFragments) {
    const Stopwatch t0;
    ReferenceVisibility r;
    r.width = std::max(cam.width, 0);
    r.height = std::max(cam.height, 0);
    const size_t pixels = size_t(r.width) * size_t(r.height);

    // Every object's triangles, one clip batch per object (its vertex range is transformed once).
    std::vector<ClipBatch> batches;
    batches.reserve(scene.objects.size());
    for (const SceneObject &o : scene.objects) {
        if (o.triEnd == o.triBegin) continue;
        batches.push_back({o.vertexBegin, o.vertexEnd, scene.objectTriangles.data() + o.triBegin, o.triEnd - o.triBegin});
        r.trianglesIn += o.triEnd - o.triBegin;
    }
    r.screen = clipTriangles(cam, MeshView{scene.positions.data(), scene.indices.data()}, batches, ClipSettings{}).out;
    const ScreenTriangles &screen = r.screen;
    r.screenTriangles = screen.size();

    r.id.assign(pixels, 0);
    r.depth.assign(pixels, std::numeric_limits<double>::infinity());
    const std::vector<uint8_t> single = singleSidedTriangles(scene);
    r.snappedFront.assign(scene.triangleCount(), 0);
    FragmentCache &cache = r.fragmentCache;
    if (maxCachedFragments) {
        cache = recyclerOf<FragmentCache>().take();  // a previous view's storage, when one was given back
        cache.begin.assign(screen.size() + 1, 0);
        // Reserved whole, so it never reallocates (pages are touched only as fragments arrive).
        cache.pixel.reserve(maxCachedFragments);
        cache.depth.reserve(maxCachedFragments);
    }
    const Stopwatch tr;
    ReferenceSink sink{scene,        cam,           screen.xy.data(),       screen.source.data(),
                       single.data(), r.id.data(),  r.depth.data(),         r.snappedFront.data(),
                       maxCachedFragments ? &cache : nullptr, maxCachedFragments};
    forEachFragment(screen, r.width, r.height, cam.orthographic, sink);
    if (sink.overflow) {
        // More fragments than the cache holds: walk again with the depth test inline.
        recycleFragmentCache(cache);
        ReferenceSink again{scene,        cam,           screen.xy.data(),       screen.source.data(),
                            single.data(), r.id.data(),  r.depth.data(),         r.snappedFront.data(),
                            nullptr,       0};
        forEachFragment(screen, r.width, r.height, cam.orthographic, again);
    } else if (maxCachedFragments) {
        // Triangles the walk skipped (no endTriangle) hold no fragment: begin[t + 1] = begin[t].
        for (size_t t = 0; t < screen.size(); ++t) cache.begin[t + 1] = std::max(cache.begin[t + 1], cache.begin[t]);
        cache.rasterMs = tr.ms();
        resolveFromCache(cache, screen.source.data(), size_t(r.width), size_t(r.height), r.id.data(), r.depth.data());
    }
    r.backWinding = sink.backWinding;
    r.fragments = sink.fragments;
    for (uint8_t f : r.snappedFront) r.snappedFrontTriangles += f;

    // Pixels per triangle, a run of equal ids at a time (common/id_runs.h).
    r.pixelsOf.assign(scene.triangleCount(), 0);
    forEachIdRun(r.id, [&](uint32_t id, uint64_t count) {
        if (id) r.pixelsOf[id - 1] += uint32_t(count), r.coveredPixels += count;
    });
    std::vector<uint8_t> objectVisible(scene.objects.size(), 0);
    for (size_t t = 0; t < r.pixelsOf.size(); ++t)
        if (r.pixelsOf[t]) {
            ++r.visibleTriangles;
            objectVisible[scene.triangleObject[t]] = 1;
        }
    for (uint8_t v : objectVisible) r.visibleObjects += v;
    r.ms = t0.ms();
    return r;
}

// ---- False culls and wasted draws ---------------------------------------------------------------

double pixelPointDistance(const Camera &cam, size_t pixel, double depth) {
    const size_t w = size_t(std::max(cam.width, 1));
    const ViewRay r = viewRayThroughPixel(cam, double(pixel % w) + 0.5, double(pixel / w) + 0.5);
    return length(r.origin + r.direction * depth);
}

CullAudit auditCulling(const Scene &scene, const ReferenceVisibility &ref, const std::vector<StageCulls> &stages,
                       const std::vector<uint32_t> &drawnTriangles, const std::vector<uint32_t> *fragmentsPerSource,
                       const Camera *cam) {
    const Stopwatch t0;
    CullAudit a;
    const size_t nt = scene.triangleCount();

    // The stage that culled each triangle first (1 + index; 0 = none). A per-pixel fate is a byte,
    // 5 + k, so at most 251 stages (the pipeline has 5 culling stages).
    const size_t nStages = std::min<size_t>(stages.size(), 255 - kFateCulledFirst + 1);
    std::vector<uint8_t> culledBy(nt, 0);
    a.stages.resize(nStages);
    for (size_t k = 0; k < nStages; ++k) {
        StageCullAudit &sa = a.stages[k];
        sa.stage = stages[k].stage;
        sa.objectsCulled = stages[k].objects.size();
        auto cull = [&](uint32_t t) {
            if (t < nt && culledBy[t] == 0 && scene.triangleObject[t] != kExcludedTriangle) {
                culledBy[t] = uint8_t(k + 1);
                ++sa.trianglesCulled;
            }
        };
        for (uint32_t o : stages[k].objects) {
            if (o >= scene.objects.size()) continue;
            const SceneObject &ob = scene.objects[o];
            for (uint32_t i = ob.triBegin; i < ob.triEnd; ++i) cull(scene.objectTriangles[i]);
        }
        for (uint32_t t : stages[k].triangles) cull(t);
    }

    // A triangle culled by a facing stage that the reference shows only through snapping.
    auto isSnapped = [&](size_t t, size_t k) {
        return stages[k].byFacing && t < ref.snappedFront.size() && ref.snappedFront[t];
    };

    // Pixels of culled triangles: their point's distance from the eye, for the nearest false cull,
    // and beyond a stage's design far plane, hidden by design (beyondPx: per triangle, such pixels;
    // beyond: per pixel). One pass over the pixels, only with a camera.
    std::vector<uint32_t> beyondPx;
    std::vector<uint8_t> beyond;
    bool anyFarPlane = false;
    for (size_t k = 0; k < nStages; ++k) {
        a.stages[k].designFarPlane = cam ? std::max(stages[k].designFarPlane, 0.0) : 0.0;
        anyFarPlane |= a.stages[k].designFarPlane > 0;
    }
    if (cam && !ref.pixelsOf.empty()) {
        if (anyFarPlane) beyondPx.assign(nt, 0), beyond.assign(ref.id.size(), 0);
        for (size_t i = 0; i < ref.id.size(); ++i) {
            const uint32_t id = ref.id[i];
            if (!id || !culledBy[id - 1] || isSnapped(id - 1, culledBy[id - 1] - 1)) continue;
            StageCullAudit &sa = a.stages[culledBy[id - 1] - 1];
            const double d = pixelPointDistance(*cam, i, ref.depth[i]);
            if (sa.designFarPlane > 0 && d > sa.designFarPlane) {
                ++beyondPx[id - 1];
                beyond[i] = 1;
                if (sa.beyondFarPlaneNearest == 0 || d < sa.beyondFarPlaneNearest) sa.beyondFarPlaneNearest = d;
            } else if (sa.falseCullNearest == 0 || d < sa.falseCullNearest) {
                sa.falseCullNearest = d;
            }
        }
    }

    // False culls: culled triangles that the reference shows (at a pixel within the stage's design
    // far plane, when it has one); aggregated per object for the worst-offender lists.
    struct Agg {
        uint64_t triangles = 0, pixels = 0;
    };
    std::vector<std::unordered_map<uint32_t, Agg>> perObject(nStages);
    for (size_t t = 0; t < nt; ++t) {
        if (!culledBy[t] || !ref.pixelsOf.size() || ref.pixelsOf[t] == 0) continue;
        const size_t k = culledBy[t] - 1;
        StageCullAudit &sa = a.stages[k];
        if (isSnapped(t, k)) {
            ++sa.snappedTriangles;
            sa.snappedPixels += ref.pixelsOf[t];
            continue;
        }
        const uint64_t far = beyondPx.empty() ? 0 : beyondPx[t], near = ref.pixelsOf[t] - far;
        sa.beyondFarPlanePixels += far;
        if (near == 0) {
            ++sa.beyondFarPlaneTriangles;
            continue;
        }
        ++sa.falseCullTriangles;
        sa.falseCullPixels += near;
        Agg &g = perObject[k][scene.triangleObject[t]];
        ++g.triangles;
        g.pixels += near;
    }
    for (size_t k = 0; k < nStages; ++k) {
        StageCullAudit &sa = a.stages[k];
        sa.falseCullObjects = perObject[k].size();
        for (const auto &[o, g] : perObject[k]) sa.worst.push_back({o, scene.objects[o].name, g.triangles, g.pixels});
        std::sort(sa.worst.begin(), sa.worst.end(), [](const FalseCullOffender &x, const FalseCullOffender &y) {
            if (x.pixels != y.pixels) return x.pixels > y.pixels;
            if (x.triangles != y.triangles) return x.triangles > y.triangles;
            return x.object < y.object;
        });
        if (sa.worst.size() > kWorstOffenders) sa.worst.resize(kWorstOffenders);
        a.falseCullTriangles += sa.falseCullTriangles;
        a.falseCullPixels += sa.falseCullPixels;
        a.beyondFarPlaneTriangles += sa.beyondFarPlaneTriangles;
        a.beyondFarPlanePixels += sa.beyondFarPlanePixels;
    }

    // Wasted draws: reached the z-buffer, visible nowhere in the reference.
    std::vector<uint8_t> drawn(nt, 0);
    std::vector<uint8_t> objectDrawn(scene.objects.size(), 0), objectVisible(scene.objects.size(), 0);
    for (uint32_t t : drawnTriangles) {
        if (t >= nt || drawn[t] || scene.triangleObject[t] == kExcludedTriangle) continue;
        drawn[t] = 1;
        ++a.drawnTriangles;
        objectDrawn[scene.triangleObject[t]] = 1;
        const uint64_t f = fragmentsPerSource && t < fragmentsPerSource->size() ? (*fragmentsPerSource)[t] : 0;
        a.drawnFragments += f;
        if (ref.pixelsOf[t] == 0) {
            ++a.wastedTriangles;
            a.wastedFragments += f;
        }
    }
    for (size_t t = 0; t < nt; ++t)
        if (ref.pixelsOf[t]) objectVisible[scene.triangleObject[t]] = 1;
    for (size_t o = 0; o < scene.objects.size(); ++o) {
        a.drawnObjects += objectDrawn[o];
        a.wastedObjects += objectDrawn[o] && !objectVisible[o];
    }

    // Per-pixel fate of the reference's triangle (what reached the z-buffer shows as drawn even if
    // a stage also listed it: the z-buffer drew it).
    a.width = ref.width;
    a.height = ref.height;
    // Decided per triangle first; per pixel, only a falsely culled triangle's pixel beyond its
    // stage's design far plane differs from its triangle's fate.
    std::vector<uint8_t> fateOf(nt);
    for (size_t t = 0; t < nt; ++t) {
        if (drawn[t]) fateOf[t] = kFateDrawn;
        else if (culledBy[t] && isSnapped(t, culledBy[t] - 1)) fateOf[t] = kFateSnapped;
        else if (culledBy[t]) fateOf[t] = uint8_t(kFateCulledFirst + culledBy[t] - 1);
        else fateOf[t] = kFateUnaccounted;
    }
    a.fate.resize(ref.id.size());
    const uint8_t *__restrict fateOfT = fateOf.data();
    const uint32_t *__restrict ids = ref.id.data();
    uint8_t *__restrict fate = a.fate.data();
    uint64_t unaccounted = 0;
    for (size_t i = 0, n = ref.id.size(); i < n; ++i) {
        const uint32_t id = ids[i];
        uint8_t f = id ? fateOfT[id - 1] : uint8_t(kFateBackground);
        if (f >= kFateCulledFirst && !beyond.empty() && beyond[i]) f = kFateBeyondFarPlane;
        unaccounted += f == kFateUnaccounted;
        fate[i] = f;
    }
    a.unaccountedPixels += unaccounted;
    a.ms = t0.ms();
    return a;
}

// ---- Z-buffer against ray casting ---------------------------------------------------------------

EdgeDistance edgeDistance(const Scene &scene, const Camera &cam, Vec3 rayOrigin, uint32_t t, double px, double py) {
    return edgeDistance(viewTriangle(scene, cam, rayOrigin, t), cam, px, py);
}

// The rays edgeDistance evaluates at pixel (px, py): through it and its right and lower neighbours.
struct PixelRayTriple {
    ViewRay r, rx, ry;
};

namespace {

PixelRayTriple pixelRays(const Camera &cam, double px, double py) {
    return {viewRayThroughPixel(cam, px, py), viewRayThroughPixel(cam, px + 1, py), viewRayThroughPixel(cam, px, py + 1)};
}

}  // namespace

// The parts of edgeDistance that depend on the triangle alone. In perspective every ray starts at
// the eye (O = 0), so an edge's cross product (Pi - O) x (Pj - O), the distances |Pi - O|, the
// edge's error factor and rayDepthError's terms are the same at every pixel: computed once here,
// from the same expressions, they are the same values.
struct EdgeTerms {
    double sigma = 0;
    bool perspective = false;
    Vec3 C[3];        // perspective: edge k's (Pi - O) x (Pj - O), i = k, j = k + 1 mod 3
    double q[3] = {}; // perspective: |Pi - O|
    double E[3] = {}; // perspective: edge k's float error of f before the factor |D|
    double gp = 0;    // |gradient| of the depth plane
    RayDepthTerms depth;  // perspective
    // Perspective, for EdgeDistanceMemo::nearEdge: edge k's f(p) = C . D(p) is affine in the pixel,
    // f = fa px + fb py + f0 exactly, so its gradient is (fa, fb) and g = |(fa, fb)| (the value the
    // three rays' differences approximate); |Cx| |Dx(p)| + |Cy| |Dy(p)| + |Cz| <= mA |px| + mB |py| + mC
    // bounds the terms of f's dot product (its rounding). fast: these are usable (finite, g > 0).
    double g[3] = {}, mA[3] = {}, mB[3] = {}, mC[3] = {};
    bool fast = false;
};

namespace {

constexpr Vec3 kEye{0, 0, 0};  // a perspective ray's origin (viewRayThroughPixel)

double edgeErrorFactor(const ViewTriangle &v, const double q[3], int i, int j) {
    return gammaF(kEmbreeEdgeOps) * q[i] * q[j] + std::sqrt(3.0) * kFloatU * (v.M[i] * q[j] + v.M[j] * q[i]);
}

EdgeTerms edgeTerms(const ViewTriangle &v, const Camera &cam) {
    EdgeTerms e;
    // Orientation sign so that inside is positive: perspective, the sign of det[P0, P1, P2] (the
    // edge function of edge 01 at the ray towards P2 is det); orthographic, minus the sign of the
    // 2D area (the edge function below is -cross2). Zero: the triangle is seen edge-on, covers no
    // area, and every point of it is on its boundary.
    if (cam.orthographic) {
        const double a2 = (v.P[1].x - v.P[0].x) * (v.P[2].y - v.P[0].y) - (v.P[1].y - v.P[0].y) * (v.P[2].x - v.P[0].x);
        e.sigma = a2 > 0 ? -1 : (a2 < 0 ? 1 : 0);
    } else {
        const double det = dot(v.P[0], cross(v.P[1], v.P[2]));
        e.sigma = det > 0 ? 1 : (det < 0 ? -1 : 0);
        e.perspective = true;
        for (int i = 0; i < 3; ++i) e.q[i] = length(v.P[i] - kEye);
        for (int k = 0; k < 3; ++k) {
            const int i = k, j = (k + 1) % 3;
            e.C[k] = cross(v.P[i] - kEye, v.P[j] - kEye);
            e.E[k] = edgeErrorFactor(v, e.q, i, j);
        }
        e.depth = rayDepthTerms(v, e.q);
        // D(p) = ((2 px / W - 1) / sx, (1 - 2 py / H) / sy, -1) (viewRayThroughPixel).
        const double W = double(cam.width), H = double(cam.height);
        e.fast = e.sigma != 0 && v.plane.valid && W > 0 && H > 0;
        for (int k = 0; k < 3; ++k) {
            const Vec3 &C = e.C[k];
            const double fa = 2 * C.x / (W * cam.sx), fb = -2 * C.y / (H * cam.sy);
            e.g[k] = std::hypot(fa, fb);
            e.mA[k] = std::fabs(fa);
            e.mB[k] = std::fabs(fb);
            e.mC[k] = std::fabs(C.x / cam.sx) + std::fabs(C.y / cam.sy) + std::fabs(C.z);
            e.fast = e.fast && e.g[k] > 0 && std::isfinite(e.g[k]) && std::isfinite(e.mC[k]) &&
                     std::isfinite(e.E[k]) && std::isfinite(e.mA[k] + e.mB[k]);
        }
    }
    e.gp = std::hypot(v.plane.a, v.plane.b);
    return e;
}

// The near and far plane constraints of edgeDistance (below), each given to take(s, tolerance).
template <class Take>
void nearFarConstraints(const ViewTriangle &v, const EdgeTerms &e, const Camera &cam, const ViewRay &r, double px,
                        double py, const double *q, Take &&take) {
    // The near and far planes cut the triangle along lines of constant depth: perspective
    // 1/d = plane(p) (near: 1/near - plane >= 0, far: plane - 1/far >= 0), orthographic d = plane(p).
    // The z-buffer clips exactly in double and snaps (kSnapEdgeTolerancePx); the ray caster limits
    // t to [float(near), float(far)] and computes t in float (rayDepthError).
    const double pv = evalDepthPlane(v.plane, px, py);
    const double gp = e.gp;
    const double d = cam.orthographic ? pv : 1 / pv;
    const double dErr =
        std::isfinite(d) && d > 0 ? rayDepthError(e.perspective ? e.depth : rayDepthTerms(v, q), r, d) : 0;
    for (int side = 0; side < 2; ++side) {
        const double limit = side == 0 ? cam.nearZ : cam.farZ;
        double s, tolValue;
        if (cam.orthographic) {
            s = side == 0 ? pv - limit : limit - pv;
            tolValue = dErr + kFloatU * limit;
        } else {
            s = side == 0 ? 1 / limit - pv : pv - 1 / limit;
            tolValue = (dErr + kFloatU * limit) / (limit * limit);  // d(1/d) = dd / d^2
        }
        if (gp > 0) take(s / gp, kSnapEdgeTolerancePx + tolValue / gp);
        else take(s >= 0 ? std::numeric_limits<double>::infinity() : -std::numeric_limits<double>::infinity(),
                  kSnapEdgeTolerancePx);
    }
}

EdgeDistance edgeDistance(const ViewTriangle &v, const EdgeTerms &e, const Camera &cam, const PixelRayTriple &rays,
                          double px, double py) {
    EdgeDistance out;
    if (e.sigma == 0 || !v.plane.valid) {
        out.nearEdge = true;
        out.tolerancePx = kSnapEdgeTolerancePx;
        return out;
    }
    const double sigma = e.sigma;

    // Edge i -> j as a function of the pixel: f(p) = ((Pi - O(p)) x (Pj - O(p))) . D(p), with the
    // ray O + t D through p (camera.h: perspective O = 0, D affine in p; orthographic O affine in
    // p, D = -z). f is zero where the ray meets the line through the edge (perspective: the ray
    // lies in the plane through the eye and the edge, so no vertex is projected and vertices
    // behind the eye need no care), and affine in p, so its gradient is an exact difference and
    // f / |grad f| is the signed distance in pixels to the projected edge.
    // The rays through the pixel and its right and lower neighbours, and the vertices' distances
    // from the pixel's ray origin, each computed once for the three edges (in perspective, once
    // per triangle: EdgeTerms).
    const ViewRay &r = rays.r, &rx = rays.rx, &ry = rays.ry;
    auto edgeF = [&](int k, const ViewRay &ray) {
        if (e.perspective) return dot(e.C[k], ray.direction);
        const int i = k, j = (k + 1) % 3;
        return dot(cross(v.P[i] - ray.origin, v.P[j] - ray.origin), ray.direction);
    };
    double qOrtho[3];
    if (!e.perspective)
        for (int i = 0; i < 3; ++i) qOrtho[i] = length(v.P[i] - r.origin);
    const double *q = e.perspective ? e.q : qOrtho;
    const double dl = length(r.direction);
    double minS = std::numeric_limits<double>::infinity(), minTol = kSnapEdgeTolerancePx;
    bool allAbove = true;  // every constraint >= -tolerance
    bool anyWithin = false;
    auto take = [&](double s, double tol) {
        if (s < -tol) allAbove = false;
        if (s <= tol) anyWithin = true;
        if (s < minS) {
            minS = s;
            minTol = tol;
        }
    };
    for (int k = 0; k < 3; ++k) {
        const double f = edgeF(k, r);
        const double gx = edgeF(k, rx) - f, gy = edgeF(k, ry) - f;
        const double g = std::hypot(gx, gy);
        // The float ray caster's uncertainty of f (audit.h, kEmbreeEdgeOps).
        const double df = (e.perspective ? e.E[k] : edgeErrorFactor(v, q, k, (k + 1) % 3)) * dl;
        if (g > 0) take(sigma * f / g, kSnapEdgeTolerancePx + df / g);
        else take(sigma * f > 0 ? std::numeric_limits<double>::infinity() : -std::numeric_limits<double>::infinity(),
                  kSnapEdgeTolerancePx);
    }

    nearFarConstraints(v, e, cam, r, px, py, q, take);
    out.signedPx = minS;
    out.tolerancePx = minTol;
    out.nearEdge = allAbove && anyWithin;
    return out;
}

}  // namespace

EdgeDistance edgeDistance(const ViewTriangle &v, const Camera &cam, double px, double py) {
    return edgeDistance(v, edgeTerms(v, cam), cam, pixelRays(cam, px, py), px, py);
}

EdgeDistanceMemo::EdgeDistanceMemo(const Scene &scene, const Camera &cam, Vec3 rayOrigin)
    : scene_(scene), cam_(cam), rayOrigin_(rayOrigin), terms_(std::make_unique<EdgeTerms[]>(2)),
      rays_(std::make_unique<PixelRayTriple>()) {}
EdgeDistanceMemo::~EdgeDistanceMemo() = default;

int EdgeDistanceMemo::slot(uint32_t t) {
    if (id_[0] == t) return 0;
    if (id_[1] == t) return 1;
    const int slot = next_;
    next_ ^= 1;
    id_[slot] = t;
    tri_[slot] = viewTriangle(scene_, cam_, rayOrigin_, t);
    terms_[size_t(slot)] = edgeTerms(tri_[slot], cam_);
    return slot;
}

const ViewTriangle &EdgeDistanceMemo::triangle(uint32_t t) { return tri_[slot(t)]; }

EdgeDistance EdgeDistanceMemo::operator()(uint32_t t, double px, double py) {
    const int k = slot(t);
    // The two triangles of a disagreeing pixel are asked at the same center: its rays once.
    if (px != rayPx_ || py != rayPy_) {
        *rays_ = pixelRays(cam_, px, py);
        rayPx_ = px, rayPy_ = py;
    }
    return edgeDistance(tri_[k], terms_[size_t(k)], cam_, *rays_, px, py);
}

bool EdgeDistanceMemo::nearEdge(uint32_t t, double px, double py) {
    const int k = slot(t);
    const EdgeTerms &e = terms_[size_t(k)];
    if (!e.fast) return (*this)(t, px, py).nearEdge;
    if (px != onePx_ || py != onePy_) {
        ray_ = viewRayThroughPixel(cam_, px, py);  // operator()'s r, the same bits
        rayLength_ = length(ray_.direction);
        onePx_ = px, onePy_ = py;
    }
    // operator() takes, per edge, s = sigma f / g' with f = C . D(p) (these very operations, so
    // the same f) and g' = |(f(p + x) - f(p), f(p + y) - f(p))| from two more rays, against the
    // tolerance kSnap + E |D| / g'. Exactly, f is affine with gradient (fa, fb), so g' differs from
    // g = |(fa, fb)| only by rounding: each f is a three-term dot product of computed ray
    // components, within 64 u (mA |px| + mB |py| + mC) of its exact value (u = 2^-53; some 10 u
    // would do), so |g' - g| <= eG = 3 * 64 u (M + mA + mB) + 8 u g with M = mA |px| + mB |py| + mC
    // (the neighbours' M is at most M + mA + mB). With eG < g / 4, s' = sigma f / g' is within
    // |s| (4/3) eG / g + 2 u |s| of s = sigma f / g, and the tolerance is at most kSnap +
    // E |D| / g (1 + 2 eG / g + 8 u). An edge whose s exceeds that tolerance by 4 |s| eG / g +
    // 4 u |s| has s' > its tolerance in operator() too: neither below -tolerance nor within it.
    constexpr double u = 0x1p-53;
    const double sigma = e.sigma;
    for (int j = 0; j < 3; ++j) {
        const double f = dot(e.C[j], ray_.direction);
        const double g = e.g[j];
        const double M = e.mA[j] * std::fabs(px) + e.mB[j] * std::fabs(py) + e.mC[j];
        const double eG = 3 * 64 * u * (M + e.mA[j] + e.mB[j]) + 8 * u * g;
        if (!(eG < g / 4)) return (*this)(t, px, py).nearEdge;
        const double s = sigma * f / g;
        const double slack = 4 * std::fabs(s) * eG / g + 4 * u * std::fabs(s);
        const double tolUp = kSnapEdgeTolerancePx + e.E[j] * rayLength_ / g * (1 + 2 * eG / g + 8 * u);
        if (!(s - slack > tolUp)) return (*this)(t, px, py).nearEdge;
    }
    // Every edge's constraint is above its tolerance: the answer is the near and far planes'.
    bool allAbove = true, anyWithin = false;
    nearFarConstraints(tri_[k], e, cam_, ray_, px, py, e.q, [&](double s, double tol) {
        if (s < -tol) allAbove = false;
        if (s <= tol) anyWithin = true;
    });
    return allAbove && anyWithin;
}

Disagreement classifyDisagreement(const Scene &scene, const Camera &cam, const DepthEncoder &encoder, Vec3 rayOrigin,
                                  int x, int y, uint32_t idA, uint32_t idB) {
    EdgeDistanceMemo memo(scene, cam, rayOrigin);
    return classifyDisagreement(memo, encoder, x, y, idA, idB);
}

Disagreement classifyDisagreement(EdgeDistanceMemo &memo, const DepthEncoder &encoder, int x, int y, uint32_t idA,
                                  uint32_t idB) {
    if (idA == idB) return Disagreement::none;
    const Camera &cam = memo.camera();
    const double px = x + 0.5, py = y + 0.5;
    // Edge: who covers this center is decided by rounding, in either method, for either triangle.
    for (uint32_t id : {idA, idB})
        if (id && memo(id - 1, px, py).nearEdge) return Disagreement::edge;
    if (!idA || !idB) return Disagreement::genuine;
    // Tie: both triangles' depths at the center, from their depth planes in double.
    const ViewTriangle a = memo.triangle(idA - 1);
    const ViewTriangle b = memo.triangle(idB - 1);
    if (!a.plane.valid || !b.plane.valid) return Disagreement::genuine;
    const double da = viewDepthAt(cam, a.plane, px, py), db = viewDepthAt(cam, b.plane, px, py);
    if (depthKey(encoder, da) == depthKey(encoder, db)) return Disagreement::tie;
    if (std::fabs(da - db) <= rayDepthError(cam, a, px, py, da) + rayDepthError(cam, b, px, py, db))
        return Disagreement::tie;
    return Disagreement::genuine;
}

namespace {
// crossCheck's common case four pixels at a time: from pixel i, whole groups of four in which the
// two ids agree and no depth difference can raise the maximum M, each lane tested as crossCheck's
// loop tests it (the same operations, so the same verdict), with M as it stands before the group:
// M only grows, so a lane skipped against it is skipped against any later M too. Returns the first
// pixel of the first group that needs the loop (or of the last partial group); *agree counts the
// skipped pixels.
__attribute__((target("avx2"))) size_t skipAgreeingAvx2(const uint32_t *za, const uint32_t *ra, const double *zd,
                                                        const float *rd, size_t i, size_t n, double M, uint64_t *agree) {
    const __m256d zero = _mm256_setzero_pd(), signless = _mm256_castsi256_pd(_mm256_set1_epi64x(INT64_MAX));
    const __m256d tiny = _mm256_set1_pd(std::numeric_limits<double>::min()), shrink = _mm256_set1_pd(1 - 0x1p-50);
    const __m256d max = _mm256_set1_pd(M);
    const size_t start = i;
    for (; i + 4 <= n; i += 4) {
        const __m128i a = _mm_loadu_si128(reinterpret_cast<const __m128i *>(za + i));
        const __m128i b = _mm_loadu_si128(reinterpret_cast<const __m128i *>(ra + i));
        if (_mm_movemask_epi8(_mm_cmpeq_epi32(a, b)) != 0xFFFF) break;
        const __m256d z = _mm256_loadu_pd(zd + i);
        const __m256d diff = _mm256_and_pd(_mm256_sub_pd(_mm256_cvtps_pd(_mm_loadu_ps(rd + i)), z), signless);
        const __m256d bound = _mm256_mul_pd(_mm256_mul_pd(max, z), shrink);
        // Skipped: no id, or not z > 0, or diff == 0, or (bound >= the smallest normal and diff <= bound).
        const __m256d noId = _mm256_castsi256_pd(_mm256_cvtepi32_epi64(_mm_cmpeq_epi32(a, _mm_setzero_si128())));
        const __m256d skip = _mm256_or_pd(
            _mm256_or_pd(noId, _mm256_cmp_pd(z, zero, _CMP_NGT_UQ)),
            _mm256_or_pd(_mm256_cmp_pd(diff, zero, _CMP_EQ_OQ),
                         _mm256_and_pd(_mm256_cmp_pd(bound, tiny, _CMP_GE_OQ), _mm256_cmp_pd(diff, bound, _CMP_LE_OQ))));
        if (_mm256_movemask_pd(skip) != 0xF) break;
    }
    *agree += i - start;
    return i;
}
}  // namespace

CrossCheck crossCheck(const std::vector<uint32_t> &zbufferIds, const std::vector<double> &zbufferDepth,
                      const std::vector<uint32_t> &raycastIds, const std::vector<float> &raycastDepth,
                      const Scene &scene, const Camera &cam, const DepthEncoder &encoder, Vec3 rayOrigin) {
    const Stopwatch t0;
    CrossCheck c;
    c.width = cam.width;
    c.height = cam.height;
    const size_t n = std::min({zbufferIds.size(), raycastIds.size(), size_t(cam.width) * size_t(cam.height)});
    c.pixels = n;
    c.cls.assign(n, uint8_t(Disagreement::none));
    constexpr size_t kExamples = 16;
    EdgeDistanceMemo memo(scene, cam, rayOrigin);
    // Where the next whole groups of four may be skipped (n: never); the group the skip stops at
    // runs one pixel at a time.
    const bool avx2 = __builtin_cpu_supports("avx2") && zbufferDepth.size() >= n && raycastDepth.size() >= n;
    size_t skipFrom = avx2 ? 0 : n;
    for (size_t i = 0; i < n; ++i) {
        if (i == skipFrom) {
            i = skipAgreeingAvx2(zbufferIds.data(), raycastIds.data(), zbufferDepth.data(), raycastDepth.data(), i, n,
                                 c.maxRelativeDepthDifference, &c.agree);
            if (i == n) break;
            skipFrom = i + 4;
        }
        const uint32_t a = zbufferIds[i], b = raycastIds[i];
        if (a == b) {
            ++c.agree;
            if (a && i < zbufferDepth.size() && i < raycastDepth.size() && zbufferDepth[i] > 0) {
                // The quotient only where it can raise the maximum M: a <= s = (M z)(1 - 2^-50), both
                // products rounded, is below M z exactly (s <= M z (1 + u)^2 (1 - 4u) < M z when s is
                // normal), so a / z < M and its rounding cannot exceed M. Most pixels skip the division.
                const double z = zbufferDepth[i], diff = std::fabs(double(raycastDepth[i]) - z);
                const double bound = (c.maxRelativeDepthDifference * z) * (1 - 0x1p-50);
                if (diff == 0 || (bound >= std::numeric_limits<double>::min() && diff <= bound)) continue;
                const double rel = diff / z;
                if (std::isfinite(rel)) c.maxRelativeDepthDifference = std::max(c.maxRelativeDepthDifference, rel);
            }
            continue;
        }
        const int x = int(i % size_t(cam.width)), y = int(i / size_t(cam.width));
        const Disagreement k = classifyDisagreement(memo, encoder, x, y, a, b);
        c.cls[i] = uint8_t(k);
        if (!a || !b) ++c.oneSidedBackground;
        switch (k) {
        case Disagreement::edge: ++c.edge; break;
        case Disagreement::tie: ++c.tie; break;
        case Disagreement::genuine:
            ++c.genuine;
            if (c.genuineExamples.size() < kExamples) c.genuineExamples.push_back({x, y, a, b});
            break;
        case Disagreement::none: break;
        }
    }
    c.ms = t0.ms();
    return c;
}

}  // namespace va
