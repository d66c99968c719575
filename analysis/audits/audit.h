// Audits against the truth (docs/architecture.md, Audits; docs/audits.md): reference visibility with no
// culling at all, the false culls and wasted draws of every culling stage, and the pixel-by-pixel
// cross-check of the z-buffer against ray casting. Free functions over plain data; the pipeline
// calls them per view (docs/audits.md, "Integration").
#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "analysis/scene.h"
#include "render/camera.h"
#include "render/clip.h"
#include "render/depth_format.h"

namespace va {

// ---- Reference visibility ----------------------------------------------------------------------

// Per source triangle: 1 when its material is single-sided (visible from its front only), 0 when
// double-sided or excluded (degenerate, non-finite: in no object).
std::vector<uint8_t> singleSidedTriangles(const Scene &scene);

// The visible triangle at each pixel with no culling stage at all: every non-excluded triangle of
// the scene is clipped (one batch per object) and rasterized through the z-buffer's own fragment
// core (render/raster_core.h: same coverage, same double depth per pixel center), the depth test
// in double (no depth format), ties to the lowest source id (explicitly, so submission order does
// not matter). Single-sided triangles are seen from their front only -- that is what the material
// means, not a culling decision -- and the front is decided by the projected winding on screen, as
// hardware does, independently of the backface stage's plane test: so that stage is really audited.
// Every fragment of one rasterization of a view's screen triangles, kept for the passes that walk
// the same fragments again in another order (the ordering audit: painter's, BSP, overdraw by
// order). Per screen triangle t its fragments are [begin[t], begin[t + 1]) of `pixel` and `depth`,
// exactly those forEachFragment gave the drawing sink (single-sided triangles with the back winding
// have none), each with its view depth d bit-identical to the walk's.
struct FragmentCache {
    std::vector<uint64_t> begin;    // per screen triangle, + 1 entry
    std::vector<uint32_t> pixel;    // y * width + x
    std::vector<double> depth;
    double rasterMs = 0;            // the rasterization that recorded them (walk + record)
    bool complete() const { return !begin.empty(); }

    // Every fragment drawn in submission order (ascending t) with LESS on the double depth, the
    // first drawn of equal depths staying: the ordering audit's "submitted" draw and its z-buffer
    // row. The reference's resolve runs it in the same pass over the fragments, because the two
    // keep the same depth at every pixel (the nearest) and differ in the id only where a later
    // fragment ties the nearest depth with a lower id (the reference keeps the lowest id).
    struct SubmittedDraw {
        uint64_t fragments = 0, passes = 0, covered = 0;
        // The pixels whose submitted id differs from the reference's, ascending, with that id.
        std::vector<std::pair<uint32_t, uint32_t>> differs;
        double ms = 0;  // its share of the resolve's pass (the resolve's whole time)
    } submitted;
};

// Fragments are replayed 16 rows at a time (forEachCachedFragmentByBand; the ordering audit's
// draws): a band's per-pixel state (16 rows of doubles and ids at 1080p: 370 KB) stays in a core's
// L2, where a whole view's (24 MB) is touched at random.
constexpr size_t kFragmentBandRows = 16;

// Per band, the runs reaching it in run order (a counting sort): band b's are
// list[begin[b] .. begin[b + 1]); run r spans bands bandsOf(r).first .. .second (first > second:
// none). Storage reused.
template <class BandsOf>
void bandLists(size_t runs, size_t bands, BandsOf &&bandsOf, std::vector<uint32_t> &begin, std::vector<uint32_t> &list) {
    begin.assign(bands + 1, 0);
    for (size_t r = 0; r < runs; ++r) {
        const auto [b0, b1] = bandsOf(r);
        for (size_t b = b0; b <= b1; ++b) ++begin[b + 1];
    }
    for (size_t b = 0; b < bands; ++b) begin[b + 1] += begin[b];
    list.resize(begin[bands]);
    std::vector<uint32_t> next(begin.begin(), begin.end() - 1);
    for (size_t r = 0; r < runs; ++r) {
        const auto [b0, b1] = bandsOf(r);
        for (size_t b = b0; b <= b1; ++b) list[next[b]++] = uint32_t(r);
    }
}

// Calls fn(pixel, t, d) for every fragment of a complete cache of a width x height view, band by
// band, and within a band triangle by triangle in ascending t: each pixel sees its fragments in the
// walk's order. A triangle's fragments come in ascending pixel order (raster_core.h), so a band's
// are a stretch of its range, resumed in the next band.
// bandDone(p0, p1) follows the last fragment of the band of pixels [p0, p1).
template <class Fn, class BandDone>
void forEachCachedFragmentByBand(const FragmentCache &cache, size_t width, size_t height, Fn &&fn, BandDone &&bandDone) {
    const size_t bandPixels = kFragmentBandRows * width;
    const size_t bands = width ? (height + kFragmentBandRows - 1) / kFragmentBandRows : 0;
    if (bands == 0 || cache.begin.empty()) return;
    std::vector<uint32_t> bandBegin, bandTris;
    bandLists(cache.begin.size() - 1, bands, [&](size_t t) {
        if (cache.begin[t + 1] == cache.begin[t]) return std::pair<size_t, size_t>{1, 0};
        return std::pair<size_t, size_t>{cache.pixel[cache.begin[t]] / bandPixels, cache.pixel[cache.begin[t + 1] - 1] / bandPixels};
    }, bandBegin, bandTris);
    std::vector<uint64_t> at(cache.begin.begin(), cache.begin.end() - 1);
    const uint32_t *pixelOf = cache.pixel.data();
    const double *depthOf = cache.depth.data();
    for (size_t b = 0; b < bands; ++b) {
        const uint32_t p1 = uint32_t(std::min((b + 1) * bandPixels, width * height));
        for (uint32_t k = bandBegin[b]; k < bandBegin[b + 1]; ++k) {
            const uint32_t t = bandTris[k];
            const uint64_t end = cache.begin[t + 1];
            uint64_t f = at[t];
            for (; f < end && pixelOf[f] < p1; ++f) fn(pixelOf[f], t, depthOf[f]);
            at[t] = f;
        }
        bandDone(b * bandPixels, size_t(p1));
    }
}

struct ReferenceVisibility {
    int width = 0, height = 0;
    std::vector<uint32_t> id;         // per pixel: 1 + visible source triangle, 0 = background
    std::vector<double> depth;        // per pixel: its view depth (double), +inf = background
    std::vector<uint32_t> pixelsOf;   // per source triangle: pixels where it is visible
    uint64_t trianglesIn = 0;         // source triangles submitted (every non-excluded one)
    uint64_t screenTriangles = 0;     // after clipping (fan pieces)
    uint64_t backWinding = 0;         // single-sided screen triangles seen from behind: not drawn
    uint64_t fragments = 0;           // pixel centers covered by drawn screen triangles
    uint64_t visibleTriangles = 0;    // source triangles visible at one pixel or more
    uint64_t visibleObjects = 0;      // culling objects with a visible triangle
    uint64_t coveredPixels = 0;       // pixels showing a triangle
    // Per source triangle: 1 when the reference drew it only because snapping to the fixed-point
    // grid turned a sliver's winding to the front, while its exact orientation (isFrontFacing, the
    // backface stage's test) is back or edge-on (docs/audits.md, "Snapped slivers").
    std::vector<uint8_t> snappedFront;
    uint64_t snappedFrontTriangles = 0;
    double ms = 0;                    // wall time (clip + rasterize + counts)
    ScreenTriangles screen;           // the clip's output (every object's batch, submission order)
    FragmentCache fragmentCache;      // when asked for and within its bound (else empty)
};
// `maxCachedFragments` > 0 keeps every fragment in `fragments` as long as there are at most that
// many (12 bytes each); more, and fragmentCache stays empty (its users rasterize again: same results).
ReferenceVisibility referenceVisibility(const Scene &scene, const Camera &cam, uint64_t maxCachedFragments = 0);
// The reference's depth test over a complete cache of a width x height view: id and depth (its
// buffers, 0 and +inf before) get the nearest fragment of each pixel, ties to the lowest source
// (source[t]: screen triangle t's); cache.submitted gets the submitted draw, in the same pass.
void resolveFromCache(FragmentCache &cache, const uint32_t *source, size_t width, size_t height, uint32_t *id,
                      double *depth);
// Gives a fragment cache's storage back for the next referenceVisibility to record into
// (render/recycle.h): a 1080p view's cache is ~100 MB, and faulting fresh pages in for every view
// cost the walk as much as recording into them. `c` is left empty.
void recycleFragmentCache(FragmentCache &c);

// ---- False culls and wasted draws ---------------------------------------------------------------

// What one culling stage removed, as the pipeline ran it: whole culling objects (object-level
// stages: cells, grid, frustum, occlusion) and/or single triangles (backface). A triangle of a
// culled object need not be listed again.
struct StageCulls {
    std::string stage;                // "frustum", "backface", ...
    std::vector<uint32_t> objects;    // culling objects culled as a whole
    std::vector<uint32_t> triangles;  // source triangles culled individually
    bool byFacing = false;            // culls by the side facing the eye (backface): its culled
                                      //   triangles the reference shows only as snapped slivers
                                      //   (ReferenceVisibility::snappedFront) are not false culls
    // > 0: the stage's data was built to leave out what lies farther than this from the eye on
    // purpose (a Quake 3 map's designed far plane, BspFarPlane: its PVS drops portal pairs farther
    // apart). A culled triangle's pixel whose visible point lies farther than this from the eye
    // (Euclidean, in double) is "beyond the far plane, hidden by design", not a false cull; a pixel
    // at or within it is a false cull, since such a point cannot have been dropped by the distance
    // rule (docs/quake3.md, "The far plane"). Needs auditCulling's camera.
    double designFarPlane = 0;
};

constexpr size_t kWorstOffenders = 20;

struct FalseCullOffender {
    uint32_t object = 0;              // culling object
    std::string name;                 // its name (source name, "#k" for chunk k)
    uint64_t triangles = 0;           // its falsely culled triangles (visible in the reference)
    uint64_t pixels = 0;              // reference pixels they cover
};

struct StageCullAudit {
    std::string stage;
    uint64_t trianglesCulled = 0;     // triangles the stage removed (objects' triangles included)
    uint64_t objectsCulled = 0;       // objects it removed as a whole
    uint64_t falseCullTriangles = 0;  // culled, yet visible in the reference; best 0
    uint64_t falseCullObjects = 0;    // objects with a falsely culled triangle; best 0
    uint64_t falseCullPixels = 0;     // reference pixels showing a falsely culled triangle; best 0
    uint64_t snappedTriangles = 0;    // byFacing: culled triangles the reference shows only as
    uint64_t snappedPixels = 0;       //   snapped slivers, and their pixels (rounding, not false culls)
    double designFarPlane = 0;        // StageCulls::designFarPlane (0: none)
    uint64_t beyondFarPlaneTriangles = 0;  // culled triangles visible only at pixels beyond the design far
                                           //   plane: hidden by design, not false culls
    uint64_t beyondFarPlanePixels = 0;     // reference pixels of culled triangles beyond it (not false culls)
    double beyondFarPlaneNearest = 0;      // the nearest of those pixels' points from the eye (0: none);
                                           //   always > designFarPlane
    double falseCullNearest = 0;      // the nearest false-cull pixel's point from the eye (0: none or no camera)
    std::vector<FalseCullOffender> worst;  // up to kWorstOffenders, most pixels first (ties: more
                                           //   triangles, then lower object index)
};

// Per-pixel fate of the reference's visible triangle (CullAudit::fate).
enum : uint8_t {
    kFateBackground = 0,     // no triangle in the reference
    kFateDrawn = 1,          // its triangle reached the z-buffer
    kFateUnaccounted = 2,    // its triangle neither reached the z-buffer nor was culled by a listed
                             //   stage (dropped elsewhere: a pipeline bug); best: no such pixel
    kFateSnapped = 3,        // culled by facing, shown by the reference only as a snapped sliver
    kFateBeyondFarPlane = 4, // culled by a stage with a design far plane, the point beyond it: by design
    kFateCulledFirst = 5,    // 5 + k: falsely culled by stages[k]
};

struct CullAudit {
    std::vector<StageCullAudit> stages;   // in the order given (the pipeline's stage order)
    uint64_t falseCullTriangles = 0;      // sums over the stages; best 0
    uint64_t falseCullPixels = 0;         // best 0
    uint64_t unaccountedPixels = 0;       // pixels of kFateUnaccounted; best 0
    uint64_t beyondFarPlanePixels = 0;    // sums over the stages: pixels hidden by design (not false culls)
    uint64_t beyondFarPlaneTriangles = 0;
    // Wasted draws: what reached the z-buffer (passed every culling stage) yet is visible nowhere
    // in the reference. Best 0; the floor is set by what conservative object-level tests can know.
    uint64_t drawnTriangles = 0;          // triangles that reached the z-buffer
    uint64_t drawnObjects = 0;            // objects with a triangle that reached it
    uint64_t wastedTriangles = 0;         // of drawnTriangles: invisible in the reference
    uint64_t wastedObjects = 0;           // of drawnObjects: no triangle visible in the reference
    uint64_t drawnFragments = 0;          // fragments the z-buffer rasterized (fragmentsPerSource)
    uint64_t wastedFragments = 0;         // of them, of wasted triangles
    std::vector<uint8_t> fate;            // per pixel, kFate*; for NAME.culling.png
    int width = 0, height = 0;
    double ms = 0;
};

// `drawnTriangles`: the source triangles that reached the z-buffer (the last culling stage's
// output, TriangleLists::triangles). `fragmentsPerSource`: per source triangle, the fragments of
// the pipeline's z-buffer pass (ZBufferSettings::fragmentsPerSource), or null (fragments 0).
// `cam`: the reference's camera, for the distances (a stage's designFarPlane, falseCullNearest);
// null: no distances, and designFarPlane is ignored.
CullAudit auditCulling(const Scene &scene, const ReferenceVisibility &ref, const std::vector<StageCulls> &stages,
                       const std::vector<uint32_t> &drawnTriangles, const std::vector<uint32_t> *fragmentsPerSource,
                       const Camera *cam = nullptr);

// The distance from the eye to the point a pixel center's ray meets at view depth `depth`
// (perspective: depth |D| with D the view ray through the center, z = -1; orthographic: the point's
// distance from the eye, the ray starting in the view plane).
double pixelPointDistance(const Camera &cam, size_t pixel, double depth);

// ---- Z-buffer against ray casting ---------------------------------------------------------------

enum class Disagreement : uint8_t {
    none = 0,     // same triangle (or both background)
    edge = 1,     // the pixel center is within the two methods' coverage error of an edge of either
                  //   triangle (edgeTolerance below): who covers it is decided by rounding
    tie = 2,      // both cover it and their depths at the center are equal in the view's depth
                  //   format, or within the ray caster's float depth error: a depth tie
    genuine = 3,  // neither: the two renderers disagree on the same triangles -- a bug in the
                  //   rasterizer or the ray caster (a culling stage's error is a false cull instead)
};

// The coverage uncertainty, in pixels, of the two methods at an edge (docs/audits.md derives it):
//  - the rasterizer snaps vertices to 1/2^kSubpixelBits px, round to nearest: each vertex moves at
//    most 1/512 px per axis, sqrt(2)/512 px in all, and so does every point of a snapped edge
//    (a convex combination of its endpoints);
//  - Embree intersects in float: vertices rounded to float relative to the ray scene's origin,
//    the ray's origin and direction rounded to float, and the edge test (a cross product and a dot
//    product of float vectors) rounded; bounded per edge and pixel from the magnitudes involved as
//    gamma(kEmbreeEdgeOps) |Qi| |Qj| |D| + u sqrt(3) (Mi |Qj| + Mj |Qi|) |D|, divided by the edge
//    function's gradient in pixels (Qi: vertex relative to the ray origin, D: ray direction,
//    Mi = |vertex - frame origin| + |ray origin - frame origin|).
constexpr double kSnapEdgeTolerancePx = 1.4142135623730951 / 512;
constexpr int kEmbreeEdgeOps = 16;

// Like with like (docs/audits.md): the z-buffer draws what the culling stages kept, so it is compared
// with the ray caster over the same triangles. A pixel where the ray caster over the whole scene
// sees a triangle a culling stage removed is counted in `culled` (the culling audit judges it: a
// false cull, hidden by design, a snapped sliver, or a cull the reference does not see at that
// center), never as a disagreement; the two renderers are compared there too, on the same triangles.
struct CrossCheck {
    int width = 0, height = 0;
    uint64_t pixels = 0;            // pixels compared
    uint64_t agree = 0;             // same visible triangle (or both background)
    uint64_t edge = 0, tie = 0, genuine = 0;  // disagreements by class; best genuine == 0
    uint64_t oneSidedBackground = 0;  // of the disagreements: one method saw background
    uint64_t culled = 0;            // pixels where the whole-scene ray caster hits a triangle a culling
                                    //   stage removed (set by the pipeline; not a disagreement class)
    bool recast = false;            // the ray caster ran again over the z-buffer's triangle set for the
                                    //   comparison (culled > 0); else its whole-scene image was that set's
    double maxRelativeDepthDifference = 0;  // over agreeing covered pixels: |d_ray - d_z| / d_z (measured)
    std::vector<uint8_t> cls;       // per pixel, Disagreement
    struct Example {
        int x = 0, y = 0;
        uint32_t zbufferId = 0, raycastId = 0;  // 1 + id, 0 = background
    };
    std::vector<Example> genuineExamples;  // the first few genuine pixels (row-major), for messages
    double ms = 0;
};

// Compares two id images of the same view (1 + source id, 0 = background), row-major
// cam.width x cam.height: the z-buffer's (ids and double depths) and the ray caster's (ids and
// float hit distances). `encoder`: the view's depth format (ties); `rayOrigin`: the float frame of
// the ray scene (RayScene::build's origin), which the float error bound depends on.
CrossCheck crossCheck(const std::vector<uint32_t> &zbufferIds, const std::vector<double> &zbufferDepth,
                      const std::vector<uint32_t> &raycastIds, const std::vector<float> &raycastDepth,
                      const Scene &scene, const Camera &cam, const DepthEncoder &encoder, Vec3 rayOrigin);

// The classification of one pixel (exposed for tests): idA, idB are 1 + source id (0 background),
// idA != idB.
Disagreement classifyDisagreement(const Scene &scene, const Camera &cam, const DepthEncoder &encoder, Vec3 rayOrigin,
                                  int x, int y, uint32_t idA, uint32_t idB);

// Signed distance in pixels from pixel coordinates (px, py) to the boundary of the region where
// source triangle t is seen in front of the near plane and behind the far plane (positive inside),
// and the coverage tolerance there (see above); exposed for tests. Robust for triangles crossing
// the near plane or with vertices behind the eye: each edge is the plane through the eye and the
// edge (perspective), so no vertex is ever projected.
struct EdgeDistance {
    double signedPx = 0;     // min over the constraints of their signed distance
    double tolerancePx = 0;  // tolerance of that constraint
    bool nearEdge = false;   // every constraint >= -its tolerance and one <= its tolerance
};
EdgeDistance edgeDistance(const Scene &scene, const Camera &cam, Vec3 rayOrigin, uint32_t t, double px, double py);

// A triangle seen from the camera: view-space vertices and the float-frame magnitudes the ray
// caster's error depends on (rayOrigin: the ray caster's frame origin).
struct ViewTriangle {
    Vec3 P[3];    // view space
    double M[3];  // |vertex - frame origin| + |eye - frame origin| (world units)
    DepthPlane plane;
};
ViewTriangle viewTriangle(const Scene &scene, const Camera &cam, Vec3 rayOrigin, uint32_t t);
// edgeDistance from a triangle's view-space data (the same value as the call above).
EdgeDistance edgeDistance(const ViewTriangle &v, const Camera &cam, double px, double py);

struct EdgeTerms;       // audit.cpp: the parts of edgeDistance that depend on the triangle alone
struct PixelRayTriple;  // audit.cpp: the rays through a pixel and its right and lower neighbours

// edgeDistance over the disagreeing pixels of a view, which come in runs on the same one or two
// triangles: the view-space data of the last two triangles asked is kept (the same values).
class EdgeDistanceMemo {
public:
    EdgeDistanceMemo(const Scene &scene, const Camera &cam, Vec3 rayOrigin);
    ~EdgeDistanceMemo();
    EdgeDistanceMemo(const EdgeDistanceMemo &) = delete;
    EdgeDistanceMemo &operator=(const EdgeDistanceMemo &) = delete;
    // edgeDistance(triangle(t), camera(), px, py), with the parts of it that depend on the
    // triangle alone kept with the triangle, and the pixel's rays kept for the next call at the
    // same pixel.
    EdgeDistance operator()(uint32_t t, double px, double py);
    // operator()(t, px, py).nearEdge, the same answer for every input. In perspective a pixel well
    // inside the triangle's three edges is told from the edges' affine functions and their
    // rounding bounds (audit.cpp), with one ray through the pixel instead of three and no hypot;
    // the near and far planes' constraints are evaluated as operator() does. Any pixel the bounds
    // cannot decide goes to operator().
    bool nearEdge(uint32_t t, double px, double py);
    const ViewTriangle &triangle(uint32_t t);
    const Camera &camera() const { return cam_; }

private:
    int slot(uint32_t t);
    const Scene &scene_;
    const Camera &cam_;
    Vec3 rayOrigin_;
    uint32_t id_[2] = {UINT32_MAX, UINT32_MAX};
    ViewTriangle tri_[2];
    std::unique_ptr<EdgeTerms[]> terms_;  // per slot
    std::unique_ptr<PixelRayTriple> rays_;
    double rayPx_ = std::numeric_limits<double>::quiet_NaN(), rayPy_ = std::numeric_limits<double>::quiet_NaN();
    // nearEdge's ray through its last pixel and that ray's |direction|.
    ViewRay ray_;
    double rayLength_ = 0;
    double onePx_ = std::numeric_limits<double>::quiet_NaN(), onePy_ = std::numeric_limits<double>::quiet_NaN();
    int next_ = 0;
};
// classifyDisagreement through a memo (crossCheck's loop).
Disagreement classifyDisagreement(EdgeDistanceMemo &memo, const DepthEncoder &encoder, int x, int y, uint32_t idA,
                                  uint32_t idB);

}  // namespace va
