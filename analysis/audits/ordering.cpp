// Draw order and exact order (ordering.h; docs/ordering.md).
#include "analysis/audits/ordering.h"

#include <algorithm>
#include <cmath>
#include <immintrin.h>
#include <limits>
#include <numeric>
#include <span>
#include <unordered_map>

#include "render/clip.h"
#include "render/raster_core.h"
#include "render/stopwatch.h"

namespace va {

namespace {

Vec3 vertexOf(const Scene &s, uint32_t t, int i) { return s.positions[s.indices[3 * size_t(t) + i]]; }

// View depth d = -z_view of a world point (perspective and orthographic alike).
double viewDepth(const Camera &cam, Vec3 p) { return dot(p - cam.eye, cam.forward); }

const DepthPlane &planeOfSource(const OrderingView &v, uint32_t s) { return v.all.planes[v.all.plane[v.screenBegin[s]]]; }

// Signed area (twice, fixed point) of screen triangle t: < 0 is the front winding (raster_core.h).
int64_t screenArea(const ScreenTriangles &st, size_t t) {
    const int32_t *p = st.xy.data() + 6 * t;
    return (int64_t(p[2]) - p[0]) * (int64_t(p[5]) - p[1]) - (int64_t(p[3]) - p[1]) * (int64_t(p[4]) - p[0]);
}

// The surface point at pixel (x, y)'s center at view depth d, origin + direction * d of
// viewRayThroughPixel(x + 0.5, y + 0.5) component by component (the same IEEE operations, so the
// same bits), with the ray's x parts per column and y parts per row computed once per view
// instead of two divisions per fragment.
struct PixelRays {
    std::vector<double> ox, dx, oy, dy;
    double oz = 0, dz = 0;
    size_t width = 0;

    explicit PixelRays(const Camera &cam) {
        const int W = std::max(cam.width, 0), H = std::max(cam.height, 0);
        width = size_t(W);
        ox.resize(size_t(W)), dx.resize(size_t(W)), oy.resize(size_t(H)), dy.resize(size_t(H));
        for (int x = 0; x < W; ++x) {
            const ViewRay r = viewRayThroughPixel(cam, double(x) + 0.5, 0.5);
            ox[size_t(x)] = r.origin.x, dx[size_t(x)] = r.direction.x;
            oz = r.origin.z, dz = r.direction.z;
        }
        for (int y = 0; y < H; ++y) {
            const ViewRay r = viewRayThroughPixel(cam, 0.5, double(y) + 0.5);
            oy[size_t(y)] = r.origin.y, dy[size_t(y)] = r.direction.y;
        }
    }
    Vec3 point(size_t pixel, double d) const { return point(pixel % width, pixel / width, d); }
    Vec3 point(size_t x, size_t y, double d) const { return {ox[x] + dx[x] * d, oy[y] + dy[y] * d, oz + dz * d}; }
};

// The drawing sink: optional depth test (LESS on the double depth), optional piece filter.
struct OrderSink {
    const OrderingView &v;
    const PixelRays &rays;
    const std::vector<uint32_t> &itemOf;  // per screen triangle of the draw list: its item
    const std::vector<DrawItem> &items;
    const BspTree *tree;
    const BspViewPlanes *planes;
    bool depthTest;
    std::vector<double> &depth;
    UninitVector<uint32_t> &id;
    uint32_t current = 0;
    uint32_t piece = UINT32_MAX;
    uint64_t fragments = 0, passes = 0;

    bool beginTriangle(size_t t, bool frontWinding) {
        const DrawItem &it = items[itemOf[t]];
        if (v.singleSided[it.source] && !frontWinding) return false;
        current = it.source + 1;
        piece = (it.piece != UINT32_MAX && tree->pieces[it.piece].constraintCount) ? it.piece : UINT32_MAX;
        return true;
    }
    void fragment(size_t i, size_t, double d) {
        // The surface point at the pixel center: on the ray through it at view depth d.
        if (piece != UINT32_MAX && !bspPieceContains(*tree, *planes, piece, rays.point(i, d))) return;
        ++fragments;
        if (!depthTest) {
            id[i] = current;
            ++passes;
        } else if (d < depth[i]) {
            depth[i] = d;
            id[i] = current;
            ++passes;
        }
    }
    void endTriangle(size_t, uint64_t) {}
};

}  // namespace

OrderingView prepareOrderingView(const Scene &scene, const Camera &cam, const ReferenceVisibility *ref) {
    OrderingView v;
    v.scene = &scene;
    v.cam = cam;
    if (ref) {
        // The reference clipped the same batches with the same settings (referenceVisibility).
        v.all = ref->screen;
        if (ref->fragmentCache.complete()) v.fragments = &ref->fragmentCache;
    } else {
        std::vector<ClipBatch> batches;
        for (const SceneObject &o : scene.objects)
            if (o.triEnd > o.triBegin)
                batches.push_back(
                    {o.vertexBegin, o.vertexEnd, scene.objectTriangles.data() + o.triBegin, o.triEnd - o.triBegin});
        v.all = clipTriangles(cam, MeshView{scene.positions.data(), scene.indices.data()}, batches, ClipSettings{}).out;
    }
    v.screenBegin.assign(scene.triangleCount(), 0);
    v.screenEnd.assign(scene.triangleCount(), 0);
    // The clipper emits a source's fan pieces consecutively.
    for (size_t t = 0; t < v.all.size(); ++t) {
        const uint32_t s = v.all.source[t];
        if (v.screenEnd[s] == v.screenBegin[s]) v.screenBegin[s] = uint32_t(t);
        v.screenEnd[s] = uint32_t(t + 1);
    }
    v.singleSided = singleSidedTriangles(scene);
    return v;
}

namespace {
// The class of pixel p, where a method shows id a and the reference id b != a (both 1 + source, 0
// for the background): a tie when both are triangles at exactly the same depth there, an edge
// pixel within the coverage uncertainty of either one's boundary, wrong otherwise.
uint8_t classifyDifferingPixel(const OrderingView &v, EdgeDistanceMemo &edgeAt, size_t p, uint32_t a, uint32_t b) {
    const size_t w = size_t(std::max(v.cam.width, 1));
    const double px = double(p % w) + 0.5, py = double(p / w) + 0.5;
    if (a && b && viewDepthAt(v.cam, planeOfSource(v, a - 1), px, py) == viewDepthAt(v.cam, planeOfSource(v, b - 1), px, py))
        return kOrderTie;
    // Within the coverage uncertainty of either triangle's boundary (the float frame of the
    // edge bound at the eye: the rasterizer's snapping dominates).
    const bool edge = (a && edgeAt.nearEdge(a - 1, px, py)) || (b && edgeAt.nearEdge(b - 1, px, py));
    return edge ? kOrderEdge : kOrderWrong;
}
void countClass(PixelComparison &c, uint8_t k) {
    (k == kOrderTie ? c.tiePixels : k == kOrderEdge ? c.edgePixels : c.wrongPixels)++;
}
}  // namespace

PixelComparison compareWithReference(const OrderingView &v, const ReferenceVisibility &ref,
                                     std::span<const uint32_t> ids, bool keepClasses) {
    PixelComparison c;
    if (keepClasses) c.cls.assign(ids.size(), kOrderRight);
    const size_t n = std::min(ids.size(), ref.id.size());
    const uint32_t *A = ids.data(), *B = ref.id.data();
    EdgeDistanceMemo edgeAt(*v.scene, v.cam, v.cam.eye);
    for (size_t p = 0; p < n; ++p) {
        // Most pixels agree: blocks of 16 that agree whole are skipped by one vectorizable test.
        if ((p & 15) == 0 && p + 16 <= n) {
            uint32_t x = 0;
            for (size_t k = 0; k < 16; ++k) x |= A[p + k] ^ B[p + k];
            if (x == 0) {
                p += 15;
                continue;
            }
        }
        const uint32_t a = A[p], b = B[p];
        if (a == b) continue;
        const uint8_t k = classifyDifferingPixel(v, edgeAt, p, a, b);
        if (keepClasses) c.cls[p] = k;
        countClass(c, k);
    }
    return c;
}

PixelComparison compareWithReference(const OrderingView &v, const ReferenceVisibility &ref,
                                     std::span<const std::pair<uint32_t, uint32_t>> differs) {
    PixelComparison c;
    EdgeDistanceMemo edgeAt(*v.scene, v.cam, v.cam.eye);
    for (const auto &[p, a] : differs) countClass(c, classifyDifferingPixel(v, edgeAt, p, a, ref.id[p]));
    return c;
}

const char *painterKeyName(PainterKey k) {
    switch (k) {
        case PainterKey::centroid: return "centroid";
        case PainterKey::nearestVertex: return "nearest_vertex";
        case PainterKey::farthestVertex: return "farthest_vertex";
    }
    return "?";
}

std::vector<PainterCandidate> painterCandidates(const OrderingView &v) {
    const Scene &scene = *v.scene;
    std::vector<PainterCandidate> out;
    for (uint32_t s = 0; s < scene.triangleCount(); ++s) {
        if (v.screenEnd[s] == v.screenBegin[s]) continue;
        out.push_back({s,
                       {viewDepth(v.cam, vertexOf(scene, s, 0)), viewDepth(v.cam, vertexOf(scene, s, 1)),
                        viewDepth(v.cam, vertexOf(scene, s, 2))}});
    }
    return out;
}

std::vector<uint32_t> painterOrder(const std::vector<PainterCandidate> &candidates, PainterKey key) {
    std::vector<std::pair<double, uint32_t>> keyed;
    keyed.reserve(candidates.size());
    for (const PainterCandidate &c : candidates) {
        const double d0 = c.depth[0], d1 = c.depth[1], d2 = c.depth[2];
        double k = 0;
        switch (key) {
            case PainterKey::centroid: k = (d0 + d1 + d2) / 3; break;  // depth is affine: the centroid's depth
            case PainterKey::nearestVertex: k = std::min(d0, std::min(d1, d2)); break;
            case PainterKey::farthestVertex: k = std::max(d0, std::max(d1, d2)); break;
        }
        keyed.push_back({k, c.source});
    }
    // Back to front: largest key first; equal keys by descending id, so the lowest id is drawn
    // last and shows (the reference's tie rule).
    std::sort(keyed.begin(), keyed.end(), [](const auto &a, const auto &b) {
        return a.first > b.first || (a.first == b.first && a.second > b.second);
    });
    std::vector<uint32_t> order(keyed.size());
    for (size_t i = 0; i < keyed.size(); ++i) order[i] = keyed[i].second;
    return order;
}

std::vector<uint32_t> painterOrder(const OrderingView &v, PainterKey key) {
    return painterOrder(painterCandidates(v), key);
}

namespace {

// Per drawn item, its fragments in the view's fragment cache: a whole triangle's (and an unsplit
// piece's) are its source's screen triangles' contiguous ranges, read in place; a split piece's are
// those of its source whose surface point the piece contains (the test the uncached sink makes per
// fragment, on the same values), as stretches of consecutive cache fragments (`range`), each
// within one screen triangle (so its pixels ascend) and in ascending order: a piece's boundary
// crosses a row once or twice, so a split triangle's pieces each take a stretch per row, and a
// draw reads them in place like whole triangles (no per-fragment index to write and gather).
struct FragmentRange {
    uint64_t at, end;
};
struct ItemFragments {
    std::vector<uint8_t> listed;       // per item: 1 when its fragments are range[begin[k], begin[k + 1])
    std::vector<uint64_t> begin;       // per item, + 1 entry (listed items only advance it)
    std::vector<FragmentRange> range;
};

// A split source's pieces partition it by the planes of the splits that cut it, and each piece's
// constraints run from the first split to the last (buildBspTree appends a split's constraint to
// its parent piece's). So the pieces of one source are the leaves of a binary trie: the first
// split's plane at the root, the side of it selecting the subtree. A fragment descends it,
// evaluating each plane on its path once (the expression of bspPieceContains, so the same side),
// and lands in the one piece whose constraints all hold, or in none -- instead of every piece
// testing its constraints on every fragment of the source. A source whose pieces do not form such
// a trie (never from buildBspTree) has its pieces test their fragments directly.
struct PieceTrie {
    struct Node {
        uint32_t plane = UINT32_MAX;  // the BSP node whose plane decides here; UINT32_MAX: a leaf
        int32_t child[2] = {-1, -1};  // behind, front
        uint32_t item = UINT32_MAX;   // at a leaf: the draw item (piece) that owns it
    };
    std::vector<Node> nodes{Node{}};
    bool direct = false;

    void insert(const BspTree &tree, uint32_t piece, uint32_t item) {
        const BspPiece &p = tree.pieces[piece];
        int32_t at = 0;
        for (uint32_t i = 0; i < p.constraintCount && !direct; ++i) {
            const BspConstraint &c = tree.constraints[p.firstConstraint + i];
            Node &n = nodes[size_t(at)];
            if (n.item != UINT32_MAX || (n.plane != UINT32_MAX && n.plane != c.node)) {
                direct = true;
                return;
            }
            n.plane = c.node;
            const int side = c.front ? 1 : 0;
            if (nodes[size_t(at)].child[side] < 0) {
                nodes[size_t(at)].child[side] = int32_t(nodes.size());
                nodes.push_back(Node{});
            }
            at = nodes[size_t(at)].child[side];
        }
        Node &leaf = nodes[size_t(at)];
        if (leaf.plane != UINT32_MAX || leaf.item != UINT32_MAX) direct = true;
        leaf.item = item;
    }
    // After the last insert: a missing child becomes a leaf owned by no item, so that a descent
    // needs no test for it.
    void seal() {
        const int32_t none = int32_t(nodes.size());
        nodes.push_back(Node{});
        for (Node &n : nodes)
            if (n.plane != UINT32_MAX)
                for (int32_t &c : n.child)
                    if (c < 0) c = none;
    }
    // The last descent's path: its planes and sides, and the piece it reached.
    static constexpr int kMaxPath = 24;
    struct Path {
        const double *q[kMaxPath];
        bool side[kMaxPath];
        int length = -1;  // -1: none (or longer than kMaxPath)
        uint32_t owner = UINT32_MAX;
        // Whether p takes the same path: every plane on it gives the same side, so the descent
        // would end in the same leaf. The planes are evaluated independently of one another (no
        // chain of node loads), so they overlap in the pipeline.
        bool holds(Vec3 p) const {
            bool same = length >= 0;
            for (int i = 0; i < length; ++i) same &= ((q[i][0] * p.x + q[i][1] * p.y + q[i][2] * p.z) + q[i][3] >= 0) == side[i];
            return same;
        }
        // Whether the four pixels of row y from column x, at view depths d[0..3], all take the
        // path: the same expressions as holds (each point's coordinates, then each plane's value
        // and its sign), two points to an SSE2 register.
        bool holds4(const PixelRays &r, size_t x, size_t y, const double *d) const {
            if (length < 0) return false;
            const __m128d d01 = _mm_loadu_pd(d), d23 = _mm_loadu_pd(d + 2);
            const __m128d oy = _mm_set1_pd(r.oy[y]), dy = _mm_set1_pd(r.dy[y]);
            const __m128d oz = _mm_set1_pd(r.oz), dz = _mm_set1_pd(r.dz);
            const __m128d x01 = _mm_add_pd(_mm_loadu_pd(&r.ox[x]), _mm_mul_pd(_mm_loadu_pd(&r.dx[x]), d01));
            const __m128d x23 = _mm_add_pd(_mm_loadu_pd(&r.ox[x + 2]), _mm_mul_pd(_mm_loadu_pd(&r.dx[x + 2]), d23));
            const __m128d y01 = _mm_add_pd(oy, _mm_mul_pd(dy, d01)), y23 = _mm_add_pd(oy, _mm_mul_pd(dy, d23));
            const __m128d z01 = _mm_add_pd(oz, _mm_mul_pd(dz, d01)), z23 = _mm_add_pd(oz, _mm_mul_pd(dz, d23));
            const __m128d zero = _mm_setzero_pd();
            __m128d differ = zero;
            for (int i = 0; i < length; ++i) {
                const double *q = this->q[i];
                const __m128d q0 = _mm_set1_pd(q[0]), q1 = _mm_set1_pd(q[1]), q2 = _mm_set1_pd(q[2]), q3 = _mm_set1_pd(q[3]);
                const __m128d side = _mm_castsi128_pd(_mm_set1_epi64x(this->side[i] ? -1 : 0));
                const __m128d v01 = _mm_add_pd(_mm_add_pd(_mm_add_pd(_mm_mul_pd(q0, x01), _mm_mul_pd(q1, y01)), _mm_mul_pd(q2, z01)), q3);
                const __m128d v23 = _mm_add_pd(_mm_add_pd(_mm_add_pd(_mm_mul_pd(q0, x23), _mm_mul_pd(q1, y23)), _mm_mul_pd(q2, z23)), q3);
                differ = _mm_or_pd(differ, _mm_xor_pd(_mm_cmpge_pd(v01, zero), side));
                differ = _mm_or_pd(differ, _mm_xor_pd(_mm_cmpge_pd(v23, zero), side));
            }
            return _mm_movemask_pd(differ) == 0;
        }
    };
    // The piece owning point p (sealed tries; UINT32_MAX: none): the last path's piece when p takes
    // that path, else a descent from the root with the sign of (q0 x + q1 y + q2 z) + q3 of each
    // plane on its way (the expression of bspPieceContains), recorded in `path`. Consecutive
    // fragments mostly land in the same piece, and checking the known path's planes side by side
    // costs less than the descent's chain of dependent loads and sums.
    uint32_t owner(const BspViewPlanes &planes, Vec3 p, Path &path) const {
        if (path.holds(p)) return path.owner;
        int32_t a = 0;
        int length = 0;
        for (;;) {
            const Node &n = nodes[size_t(a)];
            if (n.plane == UINT32_MAX) break;
            const double *q = &planes.plane[4 * size_t(n.plane)];
            const bool side = (q[0] * p.x + q[1] * p.y + q[2] * p.z) + q[3] >= 0;
            if (length < kMaxPath) {
                path.q[length] = q;
                path.side[length] = side;
            }
            ++length;
            a = n.child[side ? 1 : 0];
        }
        path.length = length <= kMaxPath ? length : -1;
        path.owner = nodes[size_t(a)].item;
        return path.owner;
    }
};

// `sel` is filled (its storage reused: the callers keep one per thread, so a view's lists do not
// fault fresh pages in).
void selectFragments(const OrderingView &v, const std::vector<DrawItem> &items, const BspTree *tree,
                     const BspViewPlanes *planes, ItemFragments &sel) {
    const FragmentCache &fc = *v.fragments;
    const PixelRays rays(v.cam);
    auto fragmentsOf = [&](uint32_t s) { return std::pair{fc.begin[v.screenBegin[s]], fc.begin[v.screenEnd[s]]}; };
    auto constrained = [&](const DrawItem &it) { return it.piece != UINT32_MAX && tree->pieces[it.piece].constraintCount; };

    // Per split source, the trie of its drawn pieces.
    std::unordered_map<uint32_t, PieceTrie> tries;
    for (size_t k = 0; k < items.size(); ++k)
        if (constrained(items[k]) && fragmentsOf(items[k].source).first < fragmentsOf(items[k].source).second)
            tries[items[k].source].insert(*tree, items[k].piece, uint32_t(k));  // sources with fragments only

    // Every source's stretches of one owner, each source's in ascending order (per-thread storage),
    // then per item its count, and its stretches in item order (a counting sort, which keeps each
    // item's ascending).
    struct Owned {
        uint64_t at, end;
        uint32_t item;
    };
    thread_local std::vector<Owned> owned;
    owned.clear();
    std::vector<uint64_t> count(items.size(), 0);
    // Fragments [t's first, its last) of screen triangle t as stretches of one owner (UINT32_MAX:
    // none, not kept). ownerOf(f, x, y) gives the owner of fragment f and of how many fragments from
    // it (the pixel's column and row, stepped along a row: a division only where a row starts).
    auto stretches = [&](uint32_t t, auto &&ownerOf) {
        uint64_t runAt = fc.begin[t];
        uint32_t runOwner = UINT32_MAX;
        size_t x = 0, y = 0, last = SIZE_MAX - 1;
        for (uint64_t f = fc.begin[t]; f < fc.begin[t + 1];) {
            const size_t pixel = fc.pixel[f];
            if (pixel == last + 1 && x + 1 < rays.width) {
                ++x;
            } else {
                x = pixel % rays.width;
                y = pixel / rays.width;
            }
            const auto [k, n] = ownerOf(f, x, y);
            x += n - 1;
            last = pixel + n - 1;
            if (k != runOwner) {
                if (runOwner != UINT32_MAX) owned.push_back({runAt, f, runOwner});
                runAt = f;
                runOwner = k;
            }
            f += n;
        }
        if (runOwner != UINT32_MAX) owned.push_back({runAt, fc.begin[t + 1], runOwner});
    };
    for (auto &[s, trie] : tries) {
        if (trie.direct) continue;
        trie.seal();
        PieceTrie::Path path;
        for (uint32_t t = v.screenBegin[s]; t < v.screenEnd[s]; ++t) {
            const uint64_t end = fc.begin[t + 1];
            // Four pixels of a row at once when the last path holds for all of them (nearly always).
            stretches(t, [&](uint64_t f, size_t x, size_t y) {
                if (f + 4 <= end && fc.pixel[f + 3] == fc.pixel[f] + 3 && x + 3 < rays.width &&
                    path.holds4(rays, x, y, &fc.depth[f]))
                    return std::pair<uint32_t, size_t>{path.owner, 4};
                return std::pair<uint32_t, size_t>{trie.owner(*planes, rays.point(x, y, fc.depth[f]), path), 1};
            });
        }
    }
    sel.listed.assign(items.size(), 0);
    for (size_t k = 0; k < items.size(); ++k) {
        const DrawItem &it = items[k];
        if (!constrained(it)) continue;
        sel.listed[k] = 1;
        const auto trie = tries.find(it.source);
        if (trie != tries.end() && trie->second.direct)
            for (uint32_t t = v.screenBegin[it.source]; t < v.screenEnd[it.source]; ++t)
                stretches(t, [&](uint64_t f, size_t x, size_t y) {
                    const bool in = bspPieceContains(*tree, *planes, it.piece, rays.point(x, y, fc.depth[f]));
                    return std::pair<uint32_t, size_t>{in ? uint32_t(k) : UINT32_MAX, 1};
                });
    }
    for (const Owned &o : owned) ++count[o.item];
    sel.begin.assign(items.size() + 1, 0);
    for (size_t k = 0; k < items.size(); ++k) sel.begin[k + 1] = sel.begin[k] + count[k];
    sel.range.resize(sel.begin.back());
    std::vector<uint64_t> next(sel.begin.begin(), sel.begin.end() - 1);
    for (const Owned &o : owned) sel.range[next[o.item]++] = {o.at, o.end};
}

// Draws from the fragment cache, one band of rows at a time. Within a screen triangle the cache
// holds fragments in ascending pixel order (forEachFragment's contract), so a band's fragments of a
// triangle are a contiguous stretch of its range, and a triangle resumes in the next band where it
// stopped. Each band draws its triangles in item order: a pixel sees its fragments in the same
// order as a whole-screen draw, so the same counts and ids, while the band's depth buffer
// (kBandRows rows of doubles) stays in the core's L2 instead of the random access into a 16 MB
// buffer a whole-screen draw makes. Several draws of one view run band by band together, so the
// band's fragments come from memory once for all of them (a view's cache is tens of megabytes,
// and streaming it was the draws' cost once the depth buffer stayed near). With the depth test a
// pixel counts as covered when its first fragment passes (from +inf every finite depth passes);
// the id buffer is kept only when the caller wants it. Without the depth test every fragment
// writes, and the ids count the covered pixels.
constexpr size_t kBandRows = kFragmentBandRows;

// A draw's overdraw (passes per covered pixel) and depth complexity (fragments per covered pixel).
void setRatios(DrawStats &st) {
    st.overdraw = st.coveredPixels ? double(st.depthPasses) / double(st.coveredPixels) : 0;
    st.depthComplexity = st.coveredPixels ? double(st.fragments) / double(st.coveredPixels) : 0;
}

struct DrawJob {
    const std::vector<DrawItem> *items = nullptr;
    const ItemFragments *sel = nullptr;  // its listed items' fragments; null: every item whole
    bool depthTest = false;
    bool reverse = false;                // the items from the last to the first
    UninitVector<uint32_t> *idsOut = nullptr;
    DrawStats stats;                     // out; stats.ms is this draw's own time
    // With depthTest: the same pass is also the draw without the depth test in the same order
    // (every fragment writes its id: the painter's draw), its ids in idsOut (the depth-tested
    // draw's are not kept) and its counts in paintStats; both stats' ms are the one pass's.
    bool paint = false;
    DrawStats paintStats;                // out, with paint
};
DrawJob drawJob(const std::vector<DrawItem> &items, const ItemFragments *sel, bool depthTest, bool reverse,
                UninitVector<uint32_t> *idsOut) {
    DrawJob job;
    job.items = &items;
    job.sel = sel;
    job.depthTest = depthTest;
    job.reverse = reverse;
    job.idsOut = idsOut;
    return job;
}

// A stretch of one item's fragments whose pixels ascend: cache indices at..end, a screen
// triangle's range or a split piece's stretch of one (ItemFragments::range).
struct DrawRun {
    uint64_t at, end;
    uint32_t current;   // 1 + source
    uint32_t lastBand;  // the band of its last fragment
};

// One draw's runs, per band the runs reaching it (in draw order), its band depth buffer and counts.
struct BandedDraw {
    std::vector<DrawRun> runs;
    std::vector<uint32_t> firstBand, bandBegin, bandRuns;
    std::vector<double> depth;  // one band's, indexed by pixel - the band's first pixel
    // Whole-screen ids, each band's rows cleared when that band is drawn (in the core's cache, not
    // in a pass over 8 MB before the draw); empty when neither the caller nor the counts need them.
    UninitVector<uint32_t> id;
    uint64_t fragments = 0, passes = 0, covered = 0;
    uint64_t painted = 0;       // pixels with an id, counted band by band (without the depth test)
    double ms = 0;

    void prepare(const OrderingView &v, const DrawJob &job, size_t pixels, size_t bandPixels, size_t bands) {
        const FragmentCache &fc = *v.fragments;
        const std::vector<DrawItem> &items = *job.items;
        runs.clear();
        firstBand.clear();
        fragments = passes = covered = painted = 0;
        auto addRun = [&](uint64_t at, uint64_t end, uint32_t current, uint32_t firstPixel, uint32_t lastPixel) {
            runs.push_back({at, end, current, uint32_t(lastPixel / bandPixels)});
            firstBand.push_back(uint32_t(firstPixel / bandPixels));
        };
        for (size_t j = 0; j < items.size(); ++j) {
            const size_t k = job.reverse ? items.size() - 1 - j : j;
            const uint32_t s = items[k].source, current = s + 1;
            if (job.sel && job.sel->listed[k]) {
                for (uint64_t r = job.sel->begin[k]; r < job.sel->begin[k + 1]; ++r) {
                    const FragmentRange &g = job.sel->range[r];
                    addRun(g.at, g.end, current, fc.pixel[g.at], fc.pixel[g.end - 1]);
                }
            } else {
                for (uint32_t t = v.screenBegin[s]; t < v.screenEnd[s]; ++t)
                    if (fc.begin[t + 1] > fc.begin[t])
                        addRun(fc.begin[t], fc.begin[t + 1], current, fc.pixel[fc.begin[t]], fc.pixel[fc.begin[t + 1] - 1]);
            }
        }
        bandLists(runs.size(), bands, [&](size_t r) { return std::pair<size_t, size_t>{firstBand[r], runs[r].lastBand}; },
                  bandBegin, bandRuns);
        if (job.depthTest) depth.resize(bandPixels);
        id.clear();
        if (!job.depthTest || job.idsOut) id.resize(pixels);  // uninitialized: drawBand clears its rows
    }

    // kPaint (with kDepthTest): every fragment also writes its id, as the draw without the test.
    template <bool kDepthTest, bool kPaint = false>
    void drawBand(const FragmentCache &fc, bool keepIds, uint32_t b, size_t p0, uint32_t p1) {
        const uint32_t *pixelOf = fc.pixel.data();
        const double *depthOf = fc.depth.data();
        uint32_t *ids = id.data();
        double *z = depth.data();  // the band's: pixel - p0
        if constexpr (kDepthTest) std::fill(depth.begin(), depth.end(), std::numeric_limits<double>::infinity());
        if (!id.empty()) std::fill(ids + p0, ids + p1, 0u);
        uint64_t n = 0, pass = 0, cover = 0;
        auto write = [&](uint32_t pixel, double d, uint32_t current) {
            if constexpr (kPaint || !kDepthTest) ids[pixel] = current;
            if constexpr (kDepthTest) {
                if (double &old = z[pixel - p0]; d < old) {
                    cover += old == std::numeric_limits<double>::infinity();
                    old = d;
                    if (keepIds) ids[pixel] = current;
                    ++pass;
                }
            }
        };
        const uint32_t end = bandBegin[b + 1];
        for (uint32_t i = bandBegin[b]; i < end; ++i) {
            // A band's runs jump about the cache (each a short stretch of one triangle's
            // fragments): the one two ahead has its first fragments' lines fetched meanwhile.
            if (i + 2 < end) {
                const uint64_t at = runs[bandRuns[i + 2]].at;
                __builtin_prefetch(pixelOf + at);
                __builtin_prefetch(depthOf + at);
                __builtin_prefetch(depthOf + at + 8);
            }
            DrawRun &run = runs[bandRuns[i]];
            uint64_t f = run.at;
            const uint64_t f0 = f;
            const uint32_t current = run.current;
            if (run.lastBand == b) {
                for (; f < run.end; ++f) write(pixelOf[f], depthOf[f], current);
            } else {
                for (; pixelOf[f] < p1; ++f) write(pixelOf[f], depthOf[f], current);
            }
            n += f - f0;
            run.at = f;
        }
        fragments += n;
        passes += pass;
        covered += cover;
        if constexpr (kPaint || !kDepthTest) {
            uint64_t with = 0;
            for (size_t p = p0; p < p1; ++p) with += ids[p] != 0;
            painted += with;
        }
    }

    // The job's stats (and, with paint, job.paintStats); ms is left to the caller.
    DrawStats finish(DrawJob &job) {
        // Without the depth test every fragment writes, and the ids count the covered pixels.
        auto paintedStats = [&]() {
            DrawStats st;
            st.fragments = st.depthPasses = fragments;
            st.coveredPixels = painted;
            setRatios(st);
            return st;
        };
        DrawStats st;
        if (job.depthTest) {
            st.fragments = fragments;
            st.depthPasses = passes;
            st.coveredPixels = covered;
            setRatios(st);
            if (job.paint) job.paintStats = paintedStats();
        } else {
            st = paintedStats();
        }
        if (job.idsOut) *job.idsOut = std::move(id);
        return st;
    }
};

// The jobs' draws, band by band together; each job's stats.ms is the time of its own work.
void drawCached(const OrderingView &v, std::span<DrawJob> jobs) {
    const FragmentCache &fc = *v.fragments;
    const size_t width = size_t(std::max(v.cam.width, 0)), height = size_t(std::max(v.cam.height, 0));
    const size_t pixels = width * height, bandPixels = kBandRows * width;
    const size_t bands = width ? (height + kBandRows - 1) / kBandRows : 0;
    thread_local std::vector<BandedDraw> draws;  // per job, storage reused from view to view
    if (draws.size() < jobs.size()) draws.resize(jobs.size());
    for (size_t j = 0; j < jobs.size(); ++j) {
        const Stopwatch t;
        draws[j].prepare(v, jobs[j], pixels, bandPixels, bands);
        draws[j].ms = t.ms();
    }
    for (size_t b = 0; b < bands; ++b) {
        const size_t p0 = b * bandPixels;
        const uint32_t p1 = uint32_t(std::min(pixels, p0 + bandPixels));
        for (size_t j = 0; j < jobs.size(); ++j) {
            const Stopwatch t;
            const bool keepIds = jobs[j].idsOut != nullptr && !jobs[j].paint;
            if (!jobs[j].depthTest) draws[j].drawBand<false>(fc, keepIds, uint32_t(b), p0, p1);
            else if (jobs[j].paint) draws[j].drawBand<true, true>(fc, false, uint32_t(b), p0, p1);
            else draws[j].drawBand<true>(fc, keepIds, uint32_t(b), p0, p1);
            draws[j].ms += t.ms();
        }
    }
    for (size_t j = 0; j < jobs.size(); ++j) {
        const Stopwatch t;
        jobs[j].stats = draws[j].finish(jobs[j]);
        jobs[j].stats.ms = draws[j].ms + t.ms();
        jobs[j].paintStats.ms = jobs[j].stats.ms;
    }
}

// The submitted draw's stats, as BandedDraw::finish gives them, from the reference's resolve.
DrawStats submittedStats(const FragmentCache &fc) {
    DrawStats st;
    st.fragments = fc.submitted.fragments;
    st.depthPasses = fc.submitted.passes;
    st.coveredPixels = fc.submitted.covered;
    setRatios(st);
    st.ms = fc.submitted.ms + fc.rasterMs;
    return st;
}

// One draw: the items in order, or (reverse) from the last to the first.
DrawStats drawCached(const OrderingView &v, const std::vector<DrawItem> &items, bool depthTest,
                     const ItemFragments *sel, UninitVector<uint32_t> *idsOut, bool reverse = false) {
    DrawJob job = drawJob(items, sel, depthTest, reverse, idsOut);
    drawCached(v, std::span<DrawJob>(&job, 1));
    return job.stats;
}

bool hasConstrainedPiece(const std::vector<DrawItem> &items, const BspTree *tree) {
    for (const DrawItem &it : items)
        if (it.piece != UINT32_MAX && tree->pieces[it.piece].constraintCount) return true;
    return false;
}

}  // namespace

DrawStats drawInOrder(const OrderingView &v, const std::vector<DrawItem> &items, bool depthTest, const BspTree *tree,
                      const BspViewPlanes *planes, UninitVector<uint32_t> *idsOut) {
    const Stopwatch t0;
    if (v.fragments) {
        thread_local ItemFragments sel;
        const bool pieces = hasConstrainedPiece(items, tree);
        if (pieces) selectFragments(v, items, tree, planes, sel);
        DrawStats st = drawCached(v, items, depthTest, pieces ? &sel : nullptr, idsOut);
        st.ms = t0.ms() + v.fragments->rasterMs;
        return st;
    }
    DrawStats st;
    // The draw list: each item's screen triangles, in item order (depth planes shared with `all`).
    ScreenTriangles list;
    std::vector<uint32_t> itemOf;
    list.planes = v.all.planes;
    for (size_t k = 0; k < items.size(); ++k) {
        const uint32_t s = items[k].source;
        for (uint32_t t = v.screenBegin[s]; t < v.screenEnd[s]; ++t) {
            list.xy.insert(list.xy.end(), v.all.xy.begin() + 6 * size_t(t), v.all.xy.begin() + 6 * size_t(t) + 6);
            list.source.push_back(s);
            list.plane.push_back(v.all.plane[t]);
            itemOf.push_back(uint32_t(k));
        }
    }
    const size_t pixels = size_t(std::max(v.cam.width, 0)) * size_t(std::max(v.cam.height, 0));
    std::vector<double> depth(depthTest ? pixels : 0, std::numeric_limits<double>::infinity());
    UninitVector<uint32_t> id(pixels, 0);
    const PixelRays rays(v.cam);
    OrderSink sink{v, rays, itemOf, items, tree, planes, depthTest, depth, id};
    forEachFragment(list, v.cam.width, v.cam.height, v.cam.orthographic, sink);
    st.fragments = sink.fragments;
    st.depthPasses = sink.passes;
    for (uint32_t i : id) st.coveredPixels += i != 0;
    setRatios(st);
    st.ms = t0.ms();
    if (idsOut) *idsOut = std::move(id);
    return st;
}

// ---- Painter's overlap tests --------------------------------------------------------------------

namespace {

struct PairTri {
    double zmin, zmax;            // view depth range over its clipped screen vertices
    double bx0, by0, bx1, by1;    // screen bounding rectangle (pixels)
    uint32_t src, rank;           // rank: position in the painter's order (lower = drawn first)
    Vec3 v[3];                    // its world-space corners (the pair tests read them, not the scene)
};

// Projections disjoint: every screen triangle of a against every one of b separated by one of the
// six edge normals (integer fixed point, exact in int64: |coordinate| <= 2^29 by the core's range,
// normals below 2^31, dot products below 2^61). Touching (max == min) counts as separated.
bool projectionsDisjoint(const ScreenTriangles &st, uint32_t a0, uint32_t a1, uint32_t b0, uint32_t b1) {
    auto separated = [&](const int32_t *A, const int32_t *B) {
        const int32_t *T[2] = {A, B};
        for (int w = 0; w < 2; ++w)
            for (int e = 0; e < 3; ++e) {
                const int32_t *p = T[w];
                const int64_t nx = -(int64_t(p[2 * ((e + 1) % 3) + 1]) - p[2 * e + 1]);
                const int64_t ny = int64_t(p[2 * ((e + 1) % 3)]) - p[2 * e];
                int64_t minA = INT64_MAX, maxA = INT64_MIN, minB = INT64_MAX, maxB = INT64_MIN;
                for (int i = 0; i < 3; ++i) {
                    const int64_t pa = nx * A[2 * i] + ny * A[2 * i + 1], pb = nx * B[2 * i] + ny * B[2 * i + 1];
                    minA = std::min(minA, pa), maxA = std::max(maxA, pa);
                    minB = std::min(minB, pb), maxB = std::max(maxB, pb);
                }
                if (maxA <= minB || maxB <= minA) return true;
            }
        return false;
    };
    for (uint32_t a = a0; a < a1; ++a)
        for (uint32_t b = b0; b < b1; ++b)
            if (!separated(st.xy.data() + 6 * size_t(a), st.xy.data() + 6 * size_t(b))) return false;
    return true;
}

// Every vertex of triangle p on Q's plane or on the side `side` of it (side = +-1: the eye's side,
// or the side away from it); false when the eye is in Q's plane (side 0).
bool allOnSide(const PlaneSide &planeOfQ, const PairTri &p, int side) {
    if (side == 0) return false;
    for (int i = 0; i < 3; ++i)
        if (planeOfQ(p.v[i]) * side < 0) return false;
    return true;
}

// The closed boxes of forEachIntersectingBox, in ascending zmin, one array per side.
struct SweepBoxes {
    std::vector<double> z0, z1, x0, x1, y0, y1;
};

// The boxes j in [from, end) meeting box i on the five sides the sweep does not order (z1, and x
// and y both ways), appended to hit[k...] in ascending j; the new count.
size_t sweepHits(const SweepBoxes &b, size_t i, size_t from, size_t end, uint32_t *hit, size_t k) {
    const double zl = b.z0[i], xl = b.x0[i], xh = b.x1[i], yl = b.y0[i], yh = b.y1[i];
    for (size_t j = from; j < end; ++j) {
        hit[k] = uint32_t(j);
        k += (b.z1[j] >= zl) & (b.x0[j] <= xh) & (b.x1[j] >= xl) & (b.y0[j] <= yh) & (b.y1[j] >= yl);
    }
    return k;
}

// The same, four boxes at a time (ordered comparisons: false on NaN, as above), the rest by
// sweepHits.
__attribute__((target("avx2"))) size_t sweepHitsAvx2(const SweepBoxes &b, size_t i, size_t end, uint32_t *hit) {
    const __m256d zl = _mm256_set1_pd(b.z0[i]), xl = _mm256_set1_pd(b.x0[i]), xh = _mm256_set1_pd(b.x1[i]),
                  yl = _mm256_set1_pd(b.y0[i]), yh = _mm256_set1_pd(b.y1[i]);
    size_t k = 0, j = i + 1;
    for (; j + 4 <= end; j += 4) {
        __m256d m = _mm256_cmp_pd(_mm256_loadu_pd(&b.z1[j]), zl, _CMP_GE_OQ);
        m = _mm256_and_pd(m, _mm256_cmp_pd(_mm256_loadu_pd(&b.x0[j]), xh, _CMP_LE_OQ));
        m = _mm256_and_pd(m, _mm256_cmp_pd(_mm256_loadu_pd(&b.x1[j]), xl, _CMP_GE_OQ));
        m = _mm256_and_pd(m, _mm256_cmp_pd(_mm256_loadu_pd(&b.y0[j]), yh, _CMP_LE_OQ));
        m = _mm256_and_pd(m, _mm256_cmp_pd(_mm256_loadu_pd(&b.y1[j]), yl, _CMP_GE_OQ));
        for (unsigned bits = unsigned(_mm256_movemask_pd(m)); bits; bits &= bits - 1)
            hit[k++] = uint32_t(j + unsigned(__builtin_ctz(bits)));
    }
    return sweepHits(b, i, j, end, hit, k);
}

// Calls f(i, j) once for every pair of boxes that intersect as closed boxes (bx0..bx1 x by0..by1 x
// zmin..zmax; touching counts), in no particular order. `tris` ascends in zmin, so the boxes a box
// meets lie just after it in the array (a pair's two triangles are read from nearby memory).
template <class F>
void forEachIntersectingBox(const std::vector<PairTri> &tris, F &&f) {
    const size_t n = tris.size();
    SweepBoxes b;
    for (std::vector<double> *side : {&b.z0, &b.z1, &b.x0, &b.x1, &b.y0, &b.y1}) side->resize(n);
    for (size_t i = 0; i < n; ++i) {
        const PairTri &t = tris[i];
        b.z0[i] = t.zmin, b.z1[i] = t.zmax, b.x0[i] = t.bx0, b.x1[i] = t.bx1, b.y0[i] = t.by0, b.y1[i] = t.by1;
    }
    const bool avx2 = __builtin_cpu_supports("avx2");
    std::vector<uint32_t> hit(n);
    for (size_t i = 0; i < n; ++i) {
        // z0 ascends: the boxes after i starting at or below its top end at `end`.
        const size_t end = size_t(std::upper_bound(b.z0.begin() + ptrdiff_t(i) + 1, b.z0.end(), b.z1[i]) - b.z0.begin());
        const size_t k = avx2 ? sweepHitsAvx2(b, i, end, hit.data()) : sweepHits(b, i, i + 1, end, hit.data(), 0);
        for (size_t m = 0; m < k; ++m) f(i, size_t(hit[m]));
    }
}

int eyeSide(const Scene &s, const Camera &cam, uint32_t q) {
    const Vec3 a = vertexOf(s, q, 0), b = vertexOf(s, q, 1), c = vertexOf(s, q, 2);
    if (!cam.orthographic) return orient3d(a, b, c, cam.eye);
    const double v = -dot(cross(b - a, c - a), cam.forward);
    return v > 0 ? 1 : (v < 0 ? -1 : 0);
}

}  // namespace

OverlapTests painterOverlapTests(const OrderingView &v, PainterKey key) {
    const Stopwatch t0;
    const std::vector<uint32_t> order = painterOrder(v, key);
    OverlapTests r = painterOverlapTests(v, order);
    r.ms = t0.ms();
    return r;
}

OverlapTests painterOverlapTests(const OrderingView &v, const std::vector<uint32_t> &order) {
    const Stopwatch t0;
    OverlapTests r;
    const Scene &scene = *v.scene;
    std::vector<PairTri> tris;
    for (uint32_t rank = 0; rank < order.size(); ++rank) {
        const uint32_t s = order[rank];
        // Drawn: some screen triangle with nonzero area, and the front winding when single-sided.
        bool drawn = false;
        for (uint32_t t = v.screenBegin[s]; t < v.screenEnd[s]; ++t) {
            const int64_t a = screenArea(v.all, t);
            drawn = drawn || (a != 0 && (!v.singleSided[s] || a < 0));
        }
        if (!drawn) continue;
        PairTri p{std::numeric_limits<double>::infinity(),
                  -std::numeric_limits<double>::infinity(),
                  std::numeric_limits<double>::infinity(),
                  std::numeric_limits<double>::infinity(),
                  -std::numeric_limits<double>::infinity(),
                  -std::numeric_limits<double>::infinity(),
                  s,
                  rank,
                  {vertexOf(scene, s, 0), vertexOf(scene, s, 1), vertexOf(scene, s, 2)}};
        const DepthPlane &pl = planeOfSource(v, s);
        for (uint32_t t = v.screenBegin[s]; t < v.screenEnd[s]; ++t)
            for (int i = 0; i < 3; ++i) {
                const double px = double(v.all.xy[6 * size_t(t) + 2 * i]) / kSubpixelOne;
                const double py = double(v.all.xy[6 * size_t(t) + 2 * i + 1]) / kSubpixelOne;
                const double d = viewDepthAt(v.cam, pl, px, py);
                p.zmin = std::min(p.zmin, d), p.zmax = std::max(p.zmax, d);
                p.bx0 = std::min(p.bx0, px), p.bx1 = std::max(p.bx1, px);
                p.by0 = std::min(p.by0, py), p.by1 = std::max(p.by1, py);
            }
        tris.push_back(p);
    }
    // In ascending zmin for the sweep below (the counts do not depend on the order).
    std::sort(tris.begin(), tris.end(), [](const PairTri &a, const PairTri &b) { return a.zmin < b.zmin; });
    const size_t n = tris.size();
    r.trianglesTested = n;

    // Pairs whose closed depth ranges overlap: all pairs minus those with a entirely nearer than b
    // (a.zmax < b.zmin), counted with a binary search over tris' zmin (ascending).
    uint64_t disjoint = 0;
    for (const PairTri &t : tris)
        disjoint += uint64_t(tris.end() - std::upper_bound(tris.begin(), tris.end(), t.zmax,
                                                            [](double z, const PairTri &p) { return z < p.zmin; }));
    r.pairs = uint64_t(n) * (n - (n > 0)) / 2 - disjoint;

    // Per drawn triangle (as tris), its plane's side test and the eye's side of it, once per
    // triangle instead of once per pair.
    std::vector<PlaneSide> planeOf;
    planeOf.reserve(n);
    for (const PairTri &t : tris) planeOf.emplace_back(t.v[0], t.v[1], t.v[2]);
    std::vector<int8_t> eyeSideOf(scene.triangleCount(), 0);
    for (const PairTri &t : tris) eyeSideOf[t.src] = int8_t(eyeSide(scene, v.cam, t.src));
    uint64_t boundsOverlap = 0;
    auto classify = [&](size_t a, size_t b) {
        ++boundsOverlap;
        const size_t p = tris[a].rank < tris[b].rank ? a : b;  // drawn first: the farther by the sort
        const size_t q = p == a ? b : a;
        const PairTri &Pt = tris[p], &Qt = tris[q];
        const uint32_t P = Pt.src, Q = Qt.src;
        const PlaneSide &planeP = planeOf[p], &planeQ = planeOf[q];
        const int eyeQ = eyeSideOf[Q], eyeP = eyeSideOf[P];
        if (allOnSide(planeQ, Pt, -eyeQ)) {
            ++r.behindPlane;
        } else if (allOnSide(planeP, Qt, eyeP)) {
            ++r.inFrontOfPlane;
        } else if (projectionsDisjoint(v.all, v.screenBegin[P], v.screenEnd[P], v.screenBegin[Q], v.screenEnd[Q])) {
            ++r.projectionsDisjoint;
        } else if (allOnSide(planeP, Qt, -eyeP)) {  // Newell's swap: Q is the farther one
            ++r.behindPlane;
            ++r.swapped;
        } else if (allOnSide(planeQ, Pt, eyeQ)) {
            ++r.inFrontOfPlane;
            ++r.swapped;
        } else {
            ++r.unresolved;
        }
    };
    // Pairs whose bounding rectangles overlap too: their closed boxes (screen rectangle x depth
    // range) intersect. A sweep along depth: in order of zmin, the triangles after triangle i whose
    // zmin <= its zmax are those whose depth ranges meet its own from above (each pair of `pairs`
    // once: a few million on a 1080p oa_thor view, where the boxes that meet are about 4% of them),
    // and among them a branch-free test of the other four sides keeps the boxes that intersect.
    // Each pair's outcome depends on the pair alone and the counts are sums, so the order does not
    // matter. (CGAL's box intersection, a segment tree, took about three times as long here.)
    forEachIntersectingBox(tris, classify);
    r.boundsDisjoint = r.pairs - boundsOverlap;
    r.ms = t0.ms();
    return r;
}

namespace {

// The painter's draw of its `drawn` triangles done (its stats; its ids in r.id): the counts, the
// comparison with the reference and, when asked, the overlap tests.
void finishPainter(const OrderingView &v, const ReferenceVisibility &ref, const std::vector<uint32_t> &order,
                   bool overlapTests, const DrawStats &st, PainterResult &r) {
    const size_t drawn = order.size();
    r.trianglesDrawn = drawn;
    r.drawMs = st.ms;
    r.fragments = st.fragments;
    r.coveredPixels = st.coveredPixels;
    r.overdraw = st.overdraw;
    PixelComparison c = compareWithReference(v, ref, r.id);
    r.wrongPixels = c.wrongPixels;
    r.tiePixels = c.tiePixels;
    r.edgePixels = c.edgePixels;
    r.cls = std::move(c.cls);
    r.memoryBytes = r.id.size() * sizeof(uint32_t) + drawn * (sizeof(double) + sizeof(uint32_t));
    if (overlapTests) {
        // Its own time includes the sort it shares with the draw.
        const double sortMs = r.sortMs;
        r.overlaps = painterOverlapTests(v, order);
        r.overlaps.ms += sortMs;
    }
}

}  // namespace

PainterResult paintersAlgorithm(const OrderingView &v, const ReferenceVisibility &ref, PainterKey key,
                                bool overlapTests) {
    PainterResult r;
    r.key = key;
    const Stopwatch t0;
    const std::vector<uint32_t> order = painterOrder(v, key);
    r.sortMs = t0.ms();
    std::vector<DrawItem> items(order.size());
    for (size_t i = 0; i < order.size(); ++i) items[i].source = order[i];
    const DrawStats st = drawInOrder(v, items, false, nullptr, nullptr, &r.id);
    finishPainter(v, ref, order, overlapTests, st, r);
    return r;
}

namespace {

// The BSP's draw list for the view: the pieces back to front that have screen triangles (r gets
// the traversal's time and the count); the planes of the view for the piece tests.
BspViewPlanes bspItems(const OrderingView &v, const BspTree &tree, std::vector<DrawItem> &items, BspViewResult &r) {
    const Stopwatch t0;
    const std::vector<uint32_t> order = bspBackToFront(tree, *v.scene, v.cam);
    BspViewPlanes planes = bspViewPlanes(tree, *v.scene, v.cam);
    r.traverseMs = t0.ms();
    items.reserve(order.size());
    for (uint32_t p : order)
        if (v.screenEnd[tree.pieces[p].source] > v.screenBegin[tree.pieces[p].source])
            items.push_back({tree.pieces[p].source, p});
    r.piecesDrawn = items.size();
    return planes;
}

// With the fragment cache, both orders draw the same pieces' fragments: the piece test runs once
// (its time and the rasterization's that recorded the fragments are returned, each order's time
// being its own pass plus them), and front to back reads the same lists from the last item.
double bspSelect(const OrderingView &v, const BspTree &tree, const BspViewPlanes &planes,
                 const std::vector<DrawItem> &items, ItemFragments &sel) {
    const Stopwatch ts;
    selectFragments(v, items, &tree, &planes, sel);
    return ts.ms() + v.fragments->rasterMs;
}
void bspJobs(const std::vector<DrawItem> &items, const ItemFragments &sel, BspViewResult &r, DrawJob *jobs) {
    jobs[0] = drawJob(items, &sel, false, false, &r.id);
    jobs[1] = drawJob(items, &sel, true, true, nullptr);
}
void bspTakeDraws(const DrawJob *jobs, double selectMs, BspViewResult &r) {
    r.backToFront = jobs[0].stats;
    r.backToFront.ms += selectMs;
    r.frontToBack = jobs[1].stats;
    r.frontToBack.ms += selectMs;
}

void bspCompare(const OrderingView &v, const ReferenceVisibility &ref, BspViewResult &r) {
    PixelComparison c = compareWithReference(v, ref, r.id);
    r.wrongPixels = c.wrongPixels;
    r.tiePixels = c.tiePixels;
    r.edgePixels = c.edgePixels;
    r.cls = std::move(c.cls);
}

}  // namespace

BspFragmentOwners bspFragmentOwners(const OrderingView &v, const BspTree &tree) {
    BspFragmentOwners o;
    if (!v.fragments) return o;
    const FragmentCache &fc = *v.fragments;
    std::vector<DrawItem> items;
    BspViewResult r;
    const BspViewPlanes planes = bspItems(v, tree, items, r);
    ItemFragments sel;
    selectFragments(v, items, &tree, &planes, sel);
    o.selected.assign(fc.pixel.size(), UINT32_MAX);
    o.direct.assign(fc.pixel.size(), UINT32_MAX);
    const PixelRays rays(v.cam);
    for (size_t k = 0; k < items.size(); ++k) {
        if (!sel.listed[k]) continue;
        for (uint64_t i = sel.begin[k]; i < sel.begin[k + 1]; ++i)
            for (uint64_t f = sel.range[i].at; f < sel.range[i].end; ++f) o.selected[f] = uint32_t(k);
        const uint32_t s = items[k].source;
        for (uint64_t f = fc.begin[v.screenBegin[s]]; f < fc.begin[v.screenEnd[s]]; ++f)
            if (bspPieceContains(tree, planes, items[k].piece, rays.point(fc.pixel[f], fc.depth[f])))
                o.direct[f] = uint32_t(k);
    }
    return o;
}

BspViewResult bspForView(const OrderingView &v, const ReferenceVisibility &ref, const BspTree &tree) {
    BspViewResult r;
    std::vector<DrawItem> items;
    const BspViewPlanes planes = bspItems(v, tree, items, r);
    if (v.fragments) {
        thread_local ItemFragments sel;
        const double selectMs = bspSelect(v, tree, planes, items, sel);
        DrawJob jobs[2];
        bspJobs(items, sel, r, jobs);
        drawCached(v, jobs);
        bspTakeDraws(jobs, selectMs, r);
    } else {
        r.backToFront = drawInOrder(v, items, false, &tree, &planes, &r.id);
        std::reverse(items.begin(), items.end());
        r.frontToBack = drawInOrder(v, items, true, &tree, &planes, nullptr);
    }
    bspCompare(v, ref, r);
    return r;
}

ABufferResult abufferForView(const OrderingView &v, uint32_t maxListLength) {
    const Scene &scene = *v.scene;
    const size_t n = scene.triangleCount();
    std::vector<float> alpha(n, 1.0f);
    std::vector<uint8_t> rgb(3 * n, 255);
    std::vector<uint32_t> surface(n, UINT32_MAX);
    for (size_t t = 0; t < n; ++t) {
        const uint32_t o = scene.triangleObject[t];
        if (o == kExcludedTriangle) continue;
        const SceneObject &ob = scene.objects[o];
        surface[t] = ob.source;  // a source object (one mesh, one material) is one surface
        alpha[t] = float(std::clamp(scene.materials[ob.material].alpha, 0.0, 1.0));
        // A fixed color per source object: a multiplicative hash of its index, kept bright.
        const uint32_t h = (ob.source + 1) * 2654435761u;
        rgb[3 * t + 0] = uint8_t(64 + (h >> 24) % 192);
        rgb[3 * t + 1] = uint8_t(64 + (h >> 16) % 192);
        rgb[3 * t + 2] = uint8_t(64 + (h >> 8) % 192);
    }
    ABufferMaterials m;
    m.alpha = alpha.data();
    m.rgb = rgb.data();
    m.singleSided = v.singleSided.data();
    m.surface = surface.data();
    m.background[0] = m.background[1] = m.background[2] = 24;
    return resolveABuffer(v.all, v.cam.width, v.cam.height, v.cam.orthographic, m, maxListLength);
}

OrderingResult analyzeOrdering(const Scene &scene, const Camera &cam, const ReferenceVisibility &ref,
                               const BspTree &tree, const EffectDecision &abuffer, const OrderingSettings &settings) {
    const Stopwatch t0;
    OrderingResult r;
    const OrderingView v = prepareOrderingView(scene, cam, &ref);
    const size_t pixels = size_t(std::max(cam.width, 0)) * size_t(std::max(cam.height, 0));

    // The painter's draw, the overdraw by draw order (each with the depth test; the painter's
    // order is also the back-to-front one) and the BSP's two draws. With the fragment cache the
    // six draws run band by band together in five passes (the painter's and the back-to-front
    // one are one pass over the same fragments), and the submitted draw is also the z-buffer row
    // below (kept ids).
    {
        std::vector<DrawItem> backToFront;
        std::vector<uint32_t> painterSorted;
        if (v.fragments) {
            r.painter.key = settings.painterKey;
            const Stopwatch ts;
            painterSorted = painterOrder(v, settings.painterKey);
            r.painter.sortMs = ts.ms();
            for (uint32_t s : painterSorted) backToFront.push_back({s});
        } else {
            r.painter = paintersAlgorithm(v, ref, settings.painterKey, settings.overlapTests);
            for (uint32_t s : painterOrder(v, settings.painterKey)) backToFront.push_back({s});
        }

        std::vector<DrawItem> submitted;
        for (size_t t = 0; t < v.all.size(); ++t)
            if (submitted.empty() || submitted.back().source != v.all.source[t]) submitted.push_back({v.all.source[t]});

        // Front to back by object: objects by the view depth of their bounding sphere's center
        // (nearest first, ties by index), triangles of an object in submission order.
        std::vector<uint32_t> objs(scene.objects.size());
        std::iota(objs.begin(), objs.end(), 0u);
        std::vector<double> od(objs.size());
        for (uint32_t o : objs) od[o] = viewDepth(cam, scene.objects[o].sphere.center);
        std::stable_sort(objs.begin(), objs.end(), [&](uint32_t a, uint32_t b) { return od[a] < od[b]; });
        std::vector<DrawItem> frontToBack;
        for (uint32_t o : objs)
            for (uint32_t i = scene.objects[o].triBegin; i < scene.objects[o].triEnd; ++i) {
                const uint32_t s = scene.objectTriangles[i];
                if (v.screenEnd[s] > v.screenBegin[s]) frontToBack.push_back({s});
            }

        const char *names[3] = {"submitted", "back_to_front", "front_to_back_objects"};
        const std::vector<DrawItem> *orders[3] = {&submitted, &backToFront, &frontToBack};
        if (v.fragments) {
            std::vector<DrawItem> bspItemList;
            thread_local ItemFragments bspSel;
            double bspSelectMs;
            {
                const BspViewPlanes planes = bspItems(v, tree, bspItemList, r.bsp);
                bspSelectMs = bspSelect(v, tree, planes, bspItemList, bspSel);
            }
            // The submitted draw was drawn by the reference's resolve (FragmentCache::SubmittedDraw).
            // The painter's draw is back_to_front's pass (paint): the same items in the same order.
            DrawJob jobs[4];
            for (int k = 1; k < 3; ++k) jobs[k - 1] = drawJob(*orders[k], nullptr, true, false, nullptr);
            jobs[0].paint = true;
            jobs[0].idsOut = &r.painter.id;
            bspJobs(bspItemList, bspSel, r.bsp, jobs + 2);
            drawCached(v, jobs);
            for (int k = 0; k < 2; ++k) jobs[k].stats.ms += v.fragments->rasterMs;
            jobs[0].paintStats.ms += v.fragments->rasterMs;
            finishPainter(v, ref, painterSorted, settings.overlapTests, jobs[0].paintStats, r.painter);
            r.overdrawByOrder.push_back({names[0], submittedStats(*v.fragments)});
            for (int k = 1; k < 3; ++k) r.overdrawByOrder.push_back({names[k], jobs[k - 1].stats});
            bspTakeDraws(jobs + 2, bspSelectMs, r.bsp);
            bspCompare(v, ref, r.bsp);
        } else {
            for (int k = 0; k < 3; ++k)
                r.overdrawByOrder.push_back({names[k], drawInOrder(v, *orders[k], true, nullptr, nullptr, nullptr)});
            r.bsp = bspForView(v, ref, tree);
        }
    }
    r.overdrawByOrder.push_back({"bsp_front_to_back", r.bsp.frontToBack});

    // Scanline.
    r.scanline = scanlineVisibility(v.all, cam.width, cam.height, cam.orthographic, v.singleSided.data());
    {
        const PixelComparison c = compareWithReference(v, ref, r.scanline.id, false);
        r.scanlineWrongPixels = c.wrongPixels;
        r.scanlineTiePixels = c.tiePixels;
        r.scanlineEdgePixels = c.edgePixels;
    }

    // The z-buffer as the pipeline's audit runs it (double depth, single-sided, submission order).
    OrderingRow zrow;
    zrow.method = "zbuffer";
    if (v.fragments) {
        // The z-buffer with exact depth (rasterize's exactDepth: LESS on the double view depth, the
        // first drawn of equal depths stays) in submission order is the "submitted" draw above:
        // the same fragments through the same test, so the same ids and passes. Its overdraw
        // divides by the pixels holding a fragment, as the z-buffer's statistics do.
        // The pixels holding a fragment are those the painter's draw covered: it draws every
        // cached fragment, without the depth test.
        const uint64_t covered = r.painter.coveredPixels;
        const DrawStats &sub = r.overdrawByOrder[0].stats;
        zrow.drawMs = sub.ms;
        const PixelComparison c = compareWithReference(v, ref, v.fragments->submitted.differs);
        zrow.wrongPixels = c.wrongPixels;
        zrow.tiePixels = c.tiePixels;
        zrow.edgePixels = c.edgePixels;
        zrow.overdraw = covered ? double(sub.depthPasses) / double(covered) : 0;
        zrow.memoryBytes = pixels * (sizeof(uint32_t) + sizeof(double));  // ids and depths
    } else {
        ZBufferSettings zs;
        zs.encoder = makeDepthEncoder(DepthFormat::f32, cam.nearZ, cam.farZ);
        zs.orthographic = cam.orthographic;
        zs.exactDepth = true;
        zs.singleSided = v.singleSided.data();
        const Stopwatch tz;
        const ZBufferResult z = rasterize(v.all, cam.width, cam.height, zs);
        zrow.drawMs = tz.ms();
        const PixelComparison c = compareWithReference(v, ref, z.buffer.id, false);
        zrow.wrongPixels = c.wrongPixels;
        zrow.tiePixels = c.tiePixels;
        zrow.edgePixels = c.edgePixels;
        zrow.overdraw = z.stats.overdraw;
        zrow.memoryBytes = pixels * (sizeof(uint32_t) + sizeof(double));  // ids and depths
    }

    OrderingRow painter{"painter",           r.painter.sortMs,      r.painter.drawMs,
                        r.painter.wrongPixels, r.painter.tiePixels, r.painter.edgePixels,
                        r.painter.overdraw,    r.painter.memoryBytes};
    OrderingRow bsp{"bsp",
                    tree.stats.buildMs,
                    r.bsp.traverseMs + r.bsp.backToFront.ms,
                    r.bsp.wrongPixels,
                    r.bsp.tiePixels,
                    r.bsp.edgePixels,
                    r.bsp.backToFront.overdraw,
                    pixels * sizeof(uint32_t) + tree.stats.memoryBytes};
    OrderingRow scan{"scanline",         r.scanline.buildMs,     r.scanline.ms,      r.scanlineWrongPixels,
                     r.scanlineTiePixels, r.scanlineEdgePixels, r.scanline.overdraw, r.scanline.memoryBytes};
    r.table = {painter, bsp, scan, zrow};

    r.abufferReason = abuffer.reason;
    if (abuffer.run) {
        r.abuffer = abufferForView(v, settings.abufferMaxList);
        r.abufferRan = true;
    }
    r.ms = t0.ms();
    return r;
}

}  // namespace va
