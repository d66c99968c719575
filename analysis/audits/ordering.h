// Draw order and exact order (docs/architecture.md, Audits: Ordering; docs/ordering.md): the painter's
// algorithm and the ambiguities it cannot resolve, BSP traversal, overdraw under each draw order,
// the scanline and A-buffer methods, and the per-view `ordering` table of what each method costs in
// time next to what it gets wrong.
//
// Every method sees the same triangles as the reference visibility (analysis/audits/audit.h): every
// non-excluded triangle, clipped once per view (one batch per object), single-sided ones drawn
// only with the front projected winding, through the rasterizer's own coverage (raster_core.h).
// So a wrong pixel is the method's ordering error, never a coverage difference.
// "Wrong pixels" compare the visible source triangle per pixel with the reference. Two kinds of
// difference are counted apart, because no ordering of whole primitives can decide them:
//   * a depth tie: the two triangles' depths at the pixel center (double, from their depth
//     planes) are equal -- either may show;
//   * an edge pixel: the center lies within the coverage uncertainty of the boundary of either
//     triangle (audit.h edgeDistance: the rasterizer's vertex snapping, sqrt(2)/512 px, and the
//     float bound it adds). There the snapped coverage can put the center inside a triangle it is
//     outside of, and the reference's depth is its plane *extrapolated* past the triangle: two
//     faces meeting at a fold seen from the side overlap by a sliver of snapped coverage in which
//     the extrapolated planes can order them the other way round from the geometry (measured on
//     the castle dungeon: 1 pixel in each of two views, depth gap 1e-3 at 75 units).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "analysis/audits/audit.h"
#include "analysis/audits/bsp_tree.h"
#include "analysis/effects_plan.h"
#include "analysis/scene.h"
#include "common/uninit_vector.h"
#include "render/abuffer.h"
#include "render/camera.h"
#include "render/raster.h"
#include "render/scanline.h"

namespace va {

// One view's input to every ordering method: all non-excluded triangles clipped (submission order:
// objects ascending, triangles ascending), and per source triangle its screen triangles.
struct OrderingView {
    const Scene *scene = nullptr;
    Camera cam;
    ScreenTriangles all;                  // the clip's output, submission order
    std::vector<uint32_t> screenBegin;    // per source triangle: its screen triangles are
    std::vector<uint32_t> screenEnd;      //   all[screenBegin, screenEnd) (empty when clipped away)
    std::vector<uint8_t> singleSided;     // per source triangle (singleSidedTriangles)
    // The reference's fragments of `all` (the same clip, the same drawing rule), when it kept them:
    // the draws below then walk each triangle's fragments from it instead of rasterizing it again
    // (same fragments, same depths, so the same results); null: they rasterize.
    const FragmentCache *fragments = nullptr;
};
// The pipeline keeps the reference's fragments for the ordering audit up to this many per pixel
// (a level's depth complexity is a few layers; oa_thor's spawns 1.2-2.5); beyond, it rasterizes again.
constexpr uint64_t kOrderingCachedFragmentsPerPixel = 4;

// With `ref`, its clip (the same batches and settings) and its fragment cache are reused: the
// scene is clipped and rasterized once per view for the reference and every ordering method.
OrderingView prepareOrderingView(const Scene &scene, const Camera &cam, const ReferenceVisibility *ref = nullptr);

// Pixel-by-pixel comparison of a method's visible ids (1 + source, 0 background) with the reference.
enum : uint8_t { kOrderRight = 0, kOrderWrong = 1, kOrderTie = 2, kOrderEdge = 3 };
struct PixelComparison {
    uint64_t wrongPixels = 0;  // a different triangle (or background) than the reference, neither a
                               //   tie nor an edge pixel; best 0
    uint64_t tiePixels = 0;    // a different triangle at exactly the reference's depth (either may show)
    uint64_t edgePixels = 0;   // a different triangle, the center within coverage uncertainty of an edge
    std::vector<uint8_t> cls;  // per pixel: kOrderRight / kOrderWrong / kOrderTie / kOrderEdge
                               //   (empty when the caller asked for the counts only)
};
PixelComparison compareWithReference(const OrderingView &v, const ReferenceVisibility &ref,
                                     std::span<const uint32_t> ids, bool keepClasses = true);
// The same counts for a method whose ids differ from the reference's only at `differs` (pixel,
// the method's id; FragmentCache::SubmittedDraw::differs), without classes.
PixelComparison compareWithReference(const OrderingView &v, const ReferenceVisibility &ref,
                                     std::span<const std::pair<uint32_t, uint32_t>> differs);

// ---- Painter's algorithm ------------------------------------------------------------------------

// The sort key: a source triangle's view depth (d = -z_view, of its unclipped world vertices) at its
// centroid, its nearest vertex, or its farthest vertex. Drawn largest key first (back to front),
// ties by descending id (so the lowest id is drawn last and shows, as in the reference).
enum class PainterKey { centroid, nearestVertex, farthestVertex };
const char *painterKeyName(PainterKey k);

// Newell, Newell & Sancha's tests on every pair of drawn triangles whose view-depth ranges overlap
// (closed intervals over their clipped screen vertices, depths from their planes). P is the one the
// sort draws first (farther), Q the other; the first test that holds resolves the pair:
//   1. boundsDisjoint:       screen bounding rectangles disjoint;
//   2. behindPlane:          P entirely behind Q's plane (every vertex on Q's plane or on the side
//                            away from the eye);
//   3. inFrontOfPlane:       Q entirely on the eye's side of P's plane (or on it);
//   4. projectionsDisjoint:  the projections do not overlap (separating axis on the screen
//                            triangles; touching edges count as disjoint: the fill rule gives no
//                            pixel to both);
//   then Newell's swap -- the sort had them the wrong way round: Q entirely behind P's plane
//   (behindPlane) or P entirely in front of Q's (inFrontOfPlane), also counted in `swapped`;
//   none: `unresolved` -- cyclic overlap or interpenetration: no order of the two is right
//   everywhere, and a painter must split one of them.
// Plane sides use the exact orientation predicate (orient3d) on the world vertices and the eye.
struct OverlapTests {
    uint64_t trianglesTested = 0;     // drawn source triangles (clipped, front-wound when single-sided)
    uint64_t pairs = 0;               // pairs whose depth ranges overlap
    uint64_t boundsDisjoint = 0;
    uint64_t behindPlane = 0;
    uint64_t inFrontOfPlane = 0;
    uint64_t projectionsDisjoint = 0;
    uint64_t unresolved = 0;          // best 0
    uint64_t swapped = 0;             // of behindPlane + inFrontOfPlane: resolved only the other way round
    double ms = 0;
};
OverlapTests painterOverlapTests(const OrderingView &v, PainterKey key);
// The same for the painter's order already sorted (painterOrder(v, key)); ms without the sort.
OverlapTests painterOverlapTests(const OrderingView &v, const std::vector<uint32_t> &order);

struct PainterResult {
    PainterKey key = PainterKey::centroid;
    uint64_t trianglesDrawn = 0;      // source triangles drawn (with at least one screen triangle)
    uint64_t fragments = 0;           // fragments written (no depth test: every one is written)
    uint64_t coveredPixels = 0;
    double overdraw = 0;              // fragments / covered pixels (all pass without a depth test); best 1
    uint64_t wrongPixels = 0;         // vs the reference, ties and edge pixels apart; best 0
    uint64_t tiePixels = 0;
    uint64_t edgePixels = 0;
    double sortMs = 0, drawMs = 0;    // sorting (O(n log n)), drawing
    uint64_t memoryBytes = 0;         // id buffer + sort keys
    UninitVector<uint32_t> id;        // per pixel, 1 + source (the painter's picture)
    std::vector<uint8_t> cls;         // per pixel, kOrder* (NAME.painter_errors.png)
    OverlapTests overlaps;            // filled when requested
};
PainterResult paintersAlgorithm(const OrderingView &v, const ReferenceVisibility &ref, PainterKey key,
                                bool overlapTests = true);

// Source triangles in the painter's draw order (back to front by `key`) among those with screen
// triangles. O(n log n).
std::vector<uint32_t> painterOrder(const OrderingView &v, PainterKey key);

// What the sort reads of one source triangle: the view depth d = -z_view of each of its unclipped
// world vertices (dot(vertex - eye, forward)). An assignment kit's painter input (analysis/kit.h).
struct PainterCandidate {
    uint32_t source = 0;
    double depth[3] = {0, 0, 0};
};
// The candidates of painterOrder(v, key): the source triangles with screen triangles, ascending.
std::vector<PainterCandidate> painterCandidates(const OrderingView &v);
// The sort itself: keys from the depths (centroid: (d0 + d1 + d2) / 3; nearest: the least; farthest:
// the greatest), largest key first, equal keys by descending id. painterOrder(v, key) is
// painterOrder(painterCandidates(v), key).
std::vector<uint32_t> painterOrder(const std::vector<PainterCandidate> &candidates, PainterKey key);

// ---- Draw orders and overdraw -------------------------------------------------------------------

// One drawn item: a whole source triangle, or one piece of it from a BSP tree (its fragments are
// those of the source's screen triangles whose surface point lies in the piece: bspPieceContains).
struct DrawItem {
    uint32_t source = 0;
    uint32_t piece = UINT32_MAX;  // UINT32_MAX: the whole triangle
};

struct DrawStats {
    uint64_t fragments = 0;      // fragments rasterized (pixel centers covered by drawn items)
    uint64_t depthPasses = 0;    // fragments written (every one without a depth test)
    uint64_t coveredPixels = 0;
    double overdraw = 0;         // depthPasses / coveredPixels; best 1
    double depthComplexity = 0;  // fragments / coveredPixels
    double ms = 0;               // the draw; from the fragment cache: its pass plus the one
                                 //   rasterization that recorded the fragments (what drawing alone costs)
};

// Draws items in order: with the depth test (LESS on the double view depth: the first drawn of
// equal depths stays) or without (the last drawn shows). `tree`/`planes` are needed when an item is
// a piece. `ids` (optional) receives 1 + source per pixel.
DrawStats drawInOrder(const OrderingView &v, const std::vector<DrawItem> &items, bool depthTest, const BspTree *tree,
                      const BspViewPlanes *planes, UninitVector<uint32_t> *ids);

struct OrderOverdraw {
    std::string order;  // "submitted", "back_to_front", "front_to_back_objects", "bsp_front_to_back"
    DrawStats stats;    // with the depth test
};

// ---- BSP per view -------------------------------------------------------------------------------

struct BspViewResult {
    uint64_t piecesDrawn = 0;
    DrawStats backToFront;            // no depth test
    uint64_t wrongPixels = 0;         // back to front without depth test, vs the reference; best 0
    uint64_t tiePixels = 0;
    uint64_t edgePixels = 0;
    DrawStats frontToBack;            // with the depth test: the least overdraw
    double traverseMs = 0;            // one traversal (eye side at each node, exact)
    std::vector<uint8_t> cls;         // per pixel, kOrder*
    UninitVector<uint32_t> id;        // per pixel, 1 + source, back to front without depth test
};
BspViewResult bspForView(const OrderingView &v, const ReferenceVisibility &ref, const BspTree &tree);
// For tests, on a view with the fragment cache: per cached fragment, the BSP draw item (a piece of
// a split source) that the draws' selection gives it (`selected`), and the one whose constraints
// hold at its surface point tested fragment by fragment (bspPieceContains: `direct`); UINT32_MAX
// where no piece of a split source holds it, and for the fragments of sources that are not split.
struct BspFragmentOwners {
    std::vector<uint32_t> selected, direct;
};
BspFragmentOwners bspFragmentOwners(const OrderingView &v, const BspTree &tree);

// ---- The ordering table -------------------------------------------------------------------------

struct OrderingRow {
    std::string method;        // "painter", "bsp", "scanline", "zbuffer"
    double buildMs = 0;        // painter: sort; bsp: tree build (once per scene, view-independent);
                               //   scanline: edge table; zbuffer: 0 (clears are in drawMs)
    double drawMs = 0;         // drawing / resolving the view
    uint64_t wrongPixels = 0;  // vs the reference, ties and edge pixels apart; best 0
    uint64_t tiePixels = 0;
    uint64_t edgePixels = 0;
    double overdraw = 0;       // depth-test passes (writes) / covered pixels; best 1
    uint64_t memoryBytes = 0;  // what the method holds at once for the view (buffers, keys, tree)
};

struct OrderingSettings {
    PainterKey painterKey = PainterKey::centroid;
    bool overlapTests = true;      // the painter's pair tests (costs a tile sweep)
    uint32_t abufferMaxList = kABufferDefaultMaxList;  // longest A-buffer list (--max-abuffer-list)
};

struct OrderingResult {
    PainterResult painter;
    BspViewResult bsp;
    std::vector<OrderOverdraw> overdrawByOrder;  // submitted, back to front, front to back (objects), BSP
    ScanlineResult scanline;
    uint64_t scanlineWrongPixels = 0, scanlineTiePixels = 0, scanlineEdgePixels = 0;
    std::vector<OrderingRow> table;              // painter, bsp, scanline, zbuffer
    bool abufferRan = false;
    std::string abufferReason;                   // the planner's reason (run or skipped)
    ABufferResult abuffer;
    double ms = 0;
    // Frees the per-pixel buffers once the images are written (the statistics stay).
    void releasePixels() {
        UninitVector<uint32_t>().swap(painter.id);
        std::vector<uint8_t>().swap(painter.cls);
        UninitVector<uint32_t>().swap(bsp.id);
        std::vector<uint8_t>().swap(bsp.cls);
        std::vector<uint32_t>().swap(scanline.id);
        std::vector<uint8_t>().swap(abuffer.rgb);
        std::vector<uint8_t>().swap(abuffer.edge);
    }
};

// Everything for one view. `tree` is the scene's BSP tree (built once: buildBspTree); `abuffer`
// is the planner's decision (EffectPlan::abuffer).
OrderingResult analyzeOrdering(const Scene &scene, const Camera &cam, const ReferenceVisibility &ref,
                               const BspTree &tree, const EffectDecision &abuffer, const OrderingSettings &settings = {});

// The A-buffer's per-source-triangle inputs from the scene: material alpha, a color per source
// object (a fixed hash of its index), single-sided flags.
ABufferResult abufferForView(const OrderingView &v, uint32_t maxListLength = kABufferDefaultMaxList);

}  // namespace va
