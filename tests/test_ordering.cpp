// Draw order (analysis/audits/ordering.h): the painter's algorithm against the reference, Newell's pair
// tests, overdraw under each draw order, the ordering table on the demo and the dungeon, and the
// ordering images. Suite Ordering*.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <limits>
#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "tests/test_util.h"
#include "analysis/load/demo.h"
#include "analysis/effects_plan.h"
#include "analysis/load/load.h"
#include "analysis/audits/ordering.h"
#include "render/raster_core.h"
#include "reports/ordering_images.h"

namespace va {
namespace {

using testing_util::looseTriangles;

// The cyclic sticks of test_bsp_tree.cpp (three thin triangles, each over the next), counter-
// clockwise from above.
std::vector<std::array<Vec3, 3>> sticks() {
    std::vector<std::array<Vec3, 3>> out;
    const Vec3 base[3] = {{-4, -1.625, -1.25}, {4, -1, 1.25}, {-4, -0.375, -1.25}};
    for (int k = 0; k < 3; ++k) {
        const double a = 2 * kPi * k / 3, c = std::cos(a), s = std::sin(a);
        std::array<Vec3, 3> t;
        for (int i = 0; i < 3; ++i)
            t[i] = {std::round((c * base[i].x - s * base[i].y) * 1024) / 1024,
                    std::round((s * base[i].x + c * base[i].y) * 1024) / 1024, base[i].z};
        out.push_back(t);
    }
    return out;
}

Camera orthoTop(int size = 200) {
    CameraSpec cs;
    cs.eye = {0, 0, 10};
    cs.target = {0, 0, 0};
    cs.orthographic = true;
    cs.orthoHeight = 10;
    cs.nearZ = 0.5;
    cs.farZ = 100;
    cs.width = cs.height = size;
    Camera cam;
    std::string err;
    EXPECT_TRUE(makeCamera(cs, &cam, &err)) << err;
    return cam;
}

// Every fragment of every drawn triangle, per pixel (source, depth), through the shared coverage
// core: the expectations below are computed from these independently of ordering.cpp.
struct AllFragments {
    const OrderingView &v;
    std::vector<std::vector<std::pair<uint32_t, double>>> perPixel;
    uint32_t cur = 0;
    bool beginTriangle(size_t t, bool front) {
        cur = v.all.source[t];
        return !v.singleSided[cur] || front;
    }
    void fragment(size_t i, size_t, double d) { perPixel[i].push_back({cur, d}); }
    void endTriangle(size_t, uint64_t) {}
};

// The painter on the cycle: all three centroids are at the same depth (the sticks are rotations
// of one another about the view axis), so the order is by descending id: 2, 1, 0; the last drawn
// covering a pixel shows. 0 over 1 and 1 over 2 are right; 2 under 0 is wrong wherever 2 is in
// front of 0.
TEST(Ordering, PainterOnCyclicOverlap) {
    const Scene s = looseTriangles(sticks());
    const Camera cam = orthoTop();
    const ReferenceVisibility ref = referenceVisibility(s, cam);
    const OrderingView v = prepareOrderingView(s, cam);
    EXPECT_EQ(painterOrder(v, PainterKey::centroid), (std::vector<uint32_t>{2, 1, 0}));

    AllFragments all{v, std::vector<std::vector<std::pair<uint32_t, double>>>(200 * 200)};
    forEachFragment(v.all, 200, 200, true, all);
    uint64_t expectWrong = 0;
    for (const auto &frags : all.perPixel) {
        if (frags.size() < 2) continue;
        uint32_t last = UINT32_MAX, nearest = 0;
        double dn = INFINITY;
        for (const auto &[src, d] : frags) {
            last = std::min(last, src);  // drawn 2, 1, 0: the lowest id is drawn last
            if (d < dn) dn = d, nearest = src;
        }
        expectWrong += last != nearest;
    }
    const PainterResult p = paintersAlgorithm(v, ref, PainterKey::centroid);
    EXPECT_EQ(p.wrongPixels + p.edgePixels, expectWrong);
    EXPECT_EQ(p.wrongPixels, 143u);  // the literal, as measured: the 0-2 crossing
    EXPECT_EQ(p.edgePixels, 0u);     // no wrong pixel within snapping distance of an edge
    EXPECT_EQ(p.tiePixels, 0u);
    EXPECT_EQ(p.fragments, ref.fragments);
    // No classic test resolves any of the three pairs: each pair's projections overlap and each
    // triangle has vertices on both sides of the other's plane.
    EXPECT_EQ(p.overlaps.trianglesTested, 3u);
    EXPECT_EQ(p.overlaps.pairs, 3u);
    EXPECT_EQ(p.overlaps.unresolved, 3u);
    EXPECT_EQ(p.overlaps.boundsDisjoint + p.overlaps.behindPlane + p.overlaps.inFrontOfPlane +
                  p.overlaps.projectionsDisjoint, 0u);
}

// Interpenetration: two triangles crossing along a line; whichever is drawn last is wrong on the
// other's side of the line. No test resolves the pair.
TEST(Ordering, PainterOnInterpenetration) {
    const Scene s = looseTriangles({{Vec3{-4, -3, -1}, Vec3{4, -3, -1}, Vec3{0, 3, 1}},
                                    {Vec3{-4, 3, -1}, Vec3{0, -3, 1}, Vec3{4, 3, -1}}});
    const Camera cam = orthoTop();
    const ReferenceVisibility ref = referenceVisibility(s, cam);
    const OrderingView v = prepareOrderingView(s, cam);
    const PainterResult p = paintersAlgorithm(v, ref, PainterKey::centroid);
    EXPECT_EQ(p.overlaps.pairs, 1u);
    EXPECT_EQ(p.overlaps.unresolved, 1u);
    // Centroid depths: t0 (z = y/3) has centroid z = -1/3, t1 (z = -y/3) +1/3: t1 is nearer and is
    // drawn last; it is wrong where t0 is in front of it (y > 0) and both cover.
    uint64_t expect = 0;
    AllFragments all{v, std::vector<std::vector<std::pair<uint32_t, double>>>(200 * 200)};
    forEachFragment(v.all, 200, 200, true, all);
    for (const auto &f : all.perPixel)
        if (f.size() == 2) {
            const uint32_t nearest = f[0].second < f[1].second ? f[0].first : f[1].first;
            expect += nearest != 1 && f[0].second != f[1].second;
        }
    EXPECT_EQ(p.wrongPixels + p.edgePixels, expect);
    EXPECT_GT(p.wrongPixels, 0u);
}

// The pair counts of painterOverlapTests against a brute force over all pairs (depth ranges and
// rectangles from the same screen vertices, closed: touching counts as overlapping).
OverlapTests expectOverlapCountsMatchBruteForce(const Scene &s, const CameraSpec &cs) {
    Camera cam;
    std::string err;
    EXPECT_TRUE(makeCamera(cs, &cam, &err)) << err;
    const OrderingView v = prepareOrderingView(s, cam);
    const OverlapTests o = painterOverlapTests(v, PainterKey::centroid);

    struct R {
        double z0 = INFINITY, z1 = -INFINITY, x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
    };
    std::vector<R> rs;
    for (uint32_t t = 0; t < s.triangleCount(); ++t) {
        if (v.screenEnd[t] == v.screenBegin[t]) continue;
        bool area = false;
        for (uint32_t k = v.screenBegin[t]; k < v.screenEnd[t]; ++k) {
            const int32_t *p = &v.all.xy[6 * k];
            area = area || (int64_t(p[2]) - p[0]) * (int64_t(p[5]) - p[1]) - (int64_t(p[3]) - p[1]) * (int64_t(p[4]) - p[0]);
        }
        if (!area) continue;
        R r;
        const DepthPlane &pl = v.all.planes[v.all.plane[v.screenBegin[t]]];
        for (uint32_t k = v.screenBegin[t]; k < v.screenEnd[t]; ++k)
            for (int i = 0; i < 3; ++i) {
                const double x = v.all.xy[6 * k + 2 * i] / 256.0, y = v.all.xy[6 * k + 2 * i + 1] / 256.0;
                const double d = viewDepthAt(cam, pl, x, y);
                r.z0 = std::min(r.z0, d), r.z1 = std::max(r.z1, d);
                r.x0 = std::min(r.x0, x), r.x1 = std::max(r.x1, x);
                r.y0 = std::min(r.y0, y), r.y1 = std::max(r.y1, y);
            }
        rs.push_back(r);
    }
    uint64_t pairs = 0, rectDisjoint = 0;
    for (size_t i = 0; i < rs.size(); ++i)
        for (size_t j = i + 1; j < rs.size(); ++j) {
            if (!(rs[i].z0 <= rs[j].z1 && rs[j].z0 <= rs[i].z1)) continue;
            ++pairs;
            rectDisjoint += rs[i].x1 < rs[j].x0 || rs[j].x1 < rs[i].x0 || rs[i].y1 < rs[j].y0 || rs[j].y1 < rs[i].y0;
        }
    EXPECT_EQ(o.trianglesTested, rs.size());
    EXPECT_EQ(o.pairs, pairs);
    EXPECT_EQ(o.boundsDisjoint, rectDisjoint);
    EXPECT_EQ(o.boundsDisjoint + o.behindPlane + o.inFrontOfPlane + o.projectionsDisjoint + o.unresolved, o.pairs);
    return o;
}

// Random triangles in a perspective view.
TEST(Ordering, OverlapPairsMatchBruteForce) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> U(-5, 5);
    std::vector<std::array<Vec3, 3>> tris;
    for (int i = 0; i < 300; ++i) {
        const Vec3 c{U(rng), U(rng), U(rng) - 10};
        std::array<Vec3, 3> t;
        for (auto &p : t) p = c + Vec3{U(rng), U(rng), U(rng)} * 0.3;
        tris.push_back(t);
    }
    CameraSpec cs;
    cs.eye = {0, 0, 2};
    cs.target = {0, 0, -10};
    cs.width = 160;
    cs.height = 120;
    const OverlapTests o = expectOverlapCountsMatchBruteForce(looseTriangles(tris, true), cs);
    EXPECT_GT(o.unresolved, 0u);  // random overlapping triangles interpenetrate
}

// Boxes that only touch: grids of squares (two triangles each) on three planes facing an
// orthographic camera, whose neighbours share edges on screen and, on one plane, their whole
// (single-valued) depth range; a slanted triangle's depth range ends exactly at two planes' depths.
TEST(Ordering, OverlapPairsMatchBruteForceOnTouchingBoxes) {
    std::vector<std::array<Vec3, 3>> tris;
    for (int layer = 0; layer < 3; ++layer)
        for (int i = 0; i < 6; ++i)
            for (int j = 0; j < 6; ++j) {
                const double x0 = i - 3 + 0.5 * layer, y0 = j - 3, z = -5 - layer;
                tris.push_back({Vec3{x0, y0, z}, Vec3{x0 + 1, y0, z}, Vec3{x0 + 1, y0 + 1, z}});
                tris.push_back({Vec3{x0, y0, z}, Vec3{x0 + 1, y0 + 1, z}, Vec3{x0, y0 + 1, z}});
            }
    tris.push_back({Vec3{-3, -3, -5}, Vec3{3, -3, -6}, Vec3{3, 3, -6}});  // from layer 0's depth to layer 1's
    CameraSpec cs;
    cs.eye = {0, 0, 0};
    cs.target = {0, 0, -1};
    cs.orthographic = true;
    cs.orthoHeight = 8;
    cs.width = 128;
    cs.height = 128;
    const OverlapTests o = expectOverlapCountsMatchBruteForce(looseTriangles(tris, true), cs);
    EXPECT_EQ(o.trianglesTested, tris.size());
    EXPECT_GT(o.pairs - o.boundsDisjoint, 3u * 6 * 6 * 8);  // at least each square's touching neighbours
}

// The three sort keys differ on a case made for it: a long triangle whose far end is farther than
// a small one's, but whose near vertex is nearer.
TEST(Ordering, PainterKeys) {
    const Scene s = looseTriangles({{Vec3{-1, -1, -5}, Vec3{1, -1, -5}, Vec3{0, 1, -5}},       // small, z = -5
                                    {Vec3{-3, -3, -9}, Vec3{3, -3, -9}, Vec3{0, 3, -4}}});   // long: -9 .. -4
    CameraSpec cs;
    cs.eye = {0, 0, 0};
    cs.target = {0, 0, -1};
    cs.width = cs.height = 64;
    Camera cam;
    std::string err;
    ASSERT_TRUE(makeCamera(cs, &cam, &err)) << err;
    const OrderingView v = prepareOrderingView(s, cam);
    // Centroid: small 5, long (9 + 9 + 4) / 3 = 7.33 -> long first. Farthest: 5 vs 9 -> long first.
    // Nearest: 5 vs 4 -> small first (the long one is "nearer").
    EXPECT_EQ(painterOrder(v, PainterKey::centroid), (std::vector<uint32_t>{1, 0}));
    EXPECT_EQ(painterOrder(v, PainterKey::farthestVertex), (std::vector<uint32_t>{1, 0}));
    EXPECT_EQ(painterOrder(v, PainterKey::nearestVertex), (std::vector<uint32_t>{0, 1}));
}

void printTable(const std::string &what, const OrderingResult &r) {
    std::printf("%s ordering (painter key %s):\n", what.c_str(), painterKeyName(r.painter.key));
    std::printf("  %-9s %10s %10s %8s %6s %6s %9s %12s\n", "method", "build_ms", "draw_ms", "wrong", "ties", "edge",
                "overdraw", "memory_B");
    for (const OrderingRow &row : r.table)
        std::printf("  %-9s %10.2f %10.2f %8llu %6llu %6llu %9.3f %12llu\n", row.method.c_str(), row.buildMs, row.drawMs,
                    (unsigned long long)row.wrongPixels, (unsigned long long)row.tiePixels,
                    (unsigned long long)row.edgePixels, row.overdraw, (unsigned long long)row.memoryBytes);
    for (const OrderOverdraw &o : r.overdrawByOrder)
        std::printf("  overdraw %-22s %.3f (%llu passes, %llu fragments)\n", o.order.c_str(), o.stats.overdraw,
                    (unsigned long long)o.stats.depthPasses, (unsigned long long)o.stats.fragments);
    const OverlapTests &t = r.painter.overlaps;
    std::printf("  painter pairs %llu: bounds %llu, behind %llu, in front %llu, projections %llu, unresolved %llu "
                "(swapped %llu)\n",
                (unsigned long long)t.pairs, (unsigned long long)t.boundsDisjoint, (unsigned long long)t.behindPlane,
                (unsigned long long)t.inFrontOfPlane, (unsigned long long)t.projectionsDisjoint,
                (unsigned long long)t.unresolved, (unsigned long long)t.swapped);
    if (r.abufferRan)
        std::printf("  abuffer: %llu fragments, avg list %.2f, max %u, %llu bytes, %llu edge px\n",
                    (unsigned long long)r.abuffer.fragments, r.abuffer.averageListLength, r.abuffer.maxListLength,
                    (unsigned long long)r.abuffer.memoryBytes, (unsigned long long)r.abuffer.edgePixels);
    else
        std::printf("  abuffer skipped: %s\n", r.abufferReason.c_str());
}

// The whole analysis on a scene's views: what must hold for every correct method.
void checkScene(const Scene &s, const std::vector<ViewSpec> &views, const std::string &what) {
    const BspTree tree = buildBspTree(s);
    std::printf("%s: BSP over %llu triangles: %llu nodes, depth %u, %llu splits, %llu triangles after, %.1f ms\n",
                what.c_str(), (unsigned long long)tree.stats.trianglesIn, (unsigned long long)tree.stats.nodes,
                tree.stats.depth, (unsigned long long)tree.stats.splits, (unsigned long long)tree.stats.trianglesOut,
                tree.stats.buildMs);
    const EffectPlan plan = planEffects(s, {});
    uint64_t splitFragments = 0;  // fragments of split triangles, over the views
    for (const ViewSpec &vs : views) {
        Camera cam;
        std::string err;
        ASSERT_TRUE(makeCamera(vs.camera, &cam, &err)) << err;
        const ReferenceVisibility ref = referenceVisibility(s, cam);
        const OrderingResult r = analyzeOrdering(s, cam, ref, tree, plan.abuffer);
        printTable(what + "/" + vs.name, r);
        ASSERT_EQ(r.table.size(), 4u);
        EXPECT_EQ(r.table[1].method, "bsp");
        EXPECT_EQ(r.table[1].wrongPixels, 0u) << what << "/" << vs.name << ": BSP";
        EXPECT_EQ(r.table[2].wrongPixels, 0u) << what << "/" << vs.name << ": scanline";
        EXPECT_EQ(r.table[2].tiePixels + r.table[2].edgePixels, 0u) << "scanline: the reference's coverage and ties";
        EXPECT_EQ(r.table[3].tiePixels + r.table[3].edgePixels, 0u) << "z-buffer in ascending id: the reference";
        EXPECT_EQ(r.table[3].wrongPixels, 0u) << what << "/" << vs.name << ": z-buffer";
        EXPECT_LT(r.scanline.memoryBytes, r.scanline.zbufferBytes);
        // Every order draws the same fragments; front to back over the BSP has the least overdraw.
        ASSERT_EQ(r.overdrawByOrder.size(), 4u);
        for (const OrderOverdraw &o : r.overdrawByOrder) {
            EXPECT_EQ(o.stats.fragments, ref.fragments) << o.order;
            EXPECT_EQ(o.stats.coveredPixels, ref.coveredPixels) << o.order;
            EXPECT_LE(r.bsp.frontToBack.depthPasses, o.stats.depthPasses) << o.order;
        }
        // Back to front is the worst order for a depth test: every fragment nearer than all before.
        EXPECT_GE(r.overdrawByOrder[1].stats.depthPasses, r.overdrawByOrder[2].stats.depthPasses);
        EXPECT_EQ(r.abufferRan, plan.abuffer.run);

        // From the reference's fragment cache (the pipeline's way): the same results as drawing
        // by rasterizing again (above); with a cache too small to hold the view, it is dropped and
        // the draws rasterize.
        const ReferenceVisibility cached = referenceVisibility(s, cam, uint64_t(1) << 30);
        ASSERT_TRUE(cached.fragmentCache.complete());
        EXPECT_EQ(cached.fragmentCache.pixel.size(), ref.fragments);
        const ReferenceVisibility overflowed = referenceVisibility(s, cam, ref.fragments - 1);
        EXPECT_FALSE(overflowed.fragmentCache.complete());
        EXPECT_TRUE(referenceVisibility(s, cam, ref.fragments).fragmentCache.complete());
        // With the cache the depth test runs afterwards over it, band by band; past its bound the
        // walk runs again with the test inline: the same visibility either way.
        for (const ReferenceVisibility *v : {&cached, &overflowed}) {
            EXPECT_EQ(v->id, ref.id);
            EXPECT_EQ(v->depth, ref.depth);
            EXPECT_EQ(v->pixelsOf, ref.pixelsOf);
            EXPECT_EQ(v->fragments, ref.fragments);
            EXPECT_EQ(v->backWinding, ref.backWinding);
            EXPECT_EQ(v->snappedFront, ref.snappedFront);
        }
        // A cache given back (recycleFragmentCache, as the pipeline does when a view is done) is
        // the next view's storage: the same memory, emptied, and the same fragments recorded.
        {
            ReferenceVisibility first = referenceVisibility(s, cam, uint64_t(1) << 30);
            const uint32_t *storage = first.fragmentCache.pixel.data();
            recycleFragmentCache(first.fragmentCache);
            EXPECT_FALSE(first.fragmentCache.complete());
            EXPECT_EQ(first.fragmentCache.pixel.capacity(), 0u);
            const ReferenceVisibility again = referenceVisibility(s, cam, uint64_t(1) << 30);
            EXPECT_EQ(again.fragmentCache.pixel.data(), storage);
            EXPECT_EQ(again.fragmentCache.begin, cached.fragmentCache.begin);
            EXPECT_EQ(again.fragmentCache.pixel, cached.fragmentCache.pixel);
            EXPECT_EQ(again.fragmentCache.depth, cached.fragmentCache.depth);
            EXPECT_EQ(again.id, ref.id);
            EXPECT_EQ(again.depth, ref.depth);
        }
        // The BSP draws' piece of every fragment of a split source, as the selection decides it
        // (a trie path checked four pixels at once, the last path first), is the piece that holds the
        // fragment's point tested one by one.
        {
            const OrderingView ov = prepareOrderingView(s, cam, &cached);
            const BspFragmentOwners owners = bspFragmentOwners(ov, tree);
            ASSERT_EQ(owners.selected.size(), cached.fragmentCache.pixel.size());
            for (size_t f = 0; f < owners.selected.size(); ++f) {
                ASSERT_EQ(owners.selected[f], owners.direct[f]) << what << "/" << vs.name << ": fragment " << f;
                splitFragments += owners.direct[f] != UINT32_MAX;
            }
        }
        const OrderingResult c = analyzeOrdering(s, cam, cached, tree, plan.abuffer);
        auto same = [&](const DrawStats &a, const DrawStats &b, const std::string &name) {
            EXPECT_EQ(a.fragments, b.fragments) << name;
            EXPECT_EQ(a.depthPasses, b.depthPasses) << name;
            EXPECT_EQ(a.coveredPixels, b.coveredPixels) << name;
        };
        EXPECT_EQ(c.painter.id, r.painter.id);
        EXPECT_EQ(c.painter.fragments, r.painter.fragments);
        EXPECT_EQ(c.painter.cls, r.painter.cls);
        EXPECT_EQ(c.bsp.id, r.bsp.id);
        EXPECT_EQ(c.bsp.cls, r.bsp.cls);
        same(c.bsp.backToFront, r.bsp.backToFront, "bsp back to front");
        same(c.bsp.frontToBack, r.bsp.frontToBack, "bsp front to back");
        ASSERT_EQ(c.overdrawByOrder.size(), r.overdrawByOrder.size());
        for (size_t k = 0; k < r.overdrawByOrder.size(); ++k)
            same(c.overdrawByOrder[k].stats, r.overdrawByOrder[k].stats, r.overdrawByOrder[k].order);
        // The table too (with the cache, the z-buffer row is the submitted draw, not a rasterize()).
        ASSERT_EQ(c.table.size(), r.table.size());
        for (size_t k = 0; k < r.table.size(); ++k) {
            EXPECT_EQ(c.table[k].wrongPixels, r.table[k].wrongPixels) << r.table[k].method;
            EXPECT_EQ(c.table[k].tiePixels, r.table[k].tiePixels) << r.table[k].method;
            EXPECT_EQ(c.table[k].edgePixels, r.table[k].edgePixels) << r.table[k].method;
            EXPECT_EQ(c.table[k].overdraw, r.table[k].overdraw) << r.table[k].method;
            EXPECT_EQ(c.table[k].memoryBytes, r.table[k].memoryBytes) << r.table[k].method;
        }
    }
    if (tree.stats.splits) EXPECT_GT(splitFragments, 0u) << what << ": no view saw a split triangle";
}

// The reference's resolve also draws the submitted order (FragmentCache::SubmittedDraw): on random
// fragments whose sources do not ascend with the screen triangles and whose depths tie often (and
// include +inf and NaN), its ids, depths, passes, covered pixels and the pixels where the submitted
// ids differ are those of drawing every fragment in order, pixel by pixel, under both rules.
TEST(Ordering, SubmittedDrawFromTheResolveMatchesDrawingInOrder) {
    std::mt19937 rng(20261129);
    const double depths[] = {1.0, 2.0, 2.0, 3.0, 0.5, std::numeric_limits<double>::infinity(),
                             std::numeric_limits<double>::quiet_NaN()};
    uint64_t differing = 0;
    for (int round = 0; round < 40; ++round) {
        const size_t width = 5 + rng() % 40, height = 1 + rng() % 70, pixels = width * height;
        const size_t tris = 1 + rng() % 80;
        FragmentCache cache;
        std::vector<uint32_t> source(tris);
        cache.begin.push_back(0);
        for (size_t t = 0; t < tris; ++t) {
            source[t] = uint32_t(rng() % 50);
            std::vector<uint32_t> px;
            const size_t n = rng() % 3 == 0 ? 0 : rng() % (pixels / 2 + 1);
            for (size_t k = 0; k < n; ++k) px.push_back(uint32_t(rng() % pixels));
            std::sort(px.begin(), px.end());
            px.erase(std::unique(px.begin(), px.end()), px.end());
            for (uint32_t p : px) {
                cache.pixel.push_back(p);
                cache.depth.push_back(depths[rng() % std::size(depths)]);
            }
            cache.begin.push_back(cache.pixel.size());
        }
        // Every fragment in order, per pixel: the reference's rule and the submitted draw's.
        std::vector<uint32_t> refId(pixels, 0), subId(pixels, 0);
        std::vector<double> refDepth(pixels, std::numeric_limits<double>::infinity());
        uint64_t passes = 0, covered = 0;
        for (size_t t = 0; t < tris; ++t)
            for (uint64_t f = cache.begin[t]; f < cache.begin[t + 1]; ++f) {
                const uint32_t p = cache.pixel[f], cur = source[t] + 1;
                const double d = cache.depth[f], old = refDepth[p];
                if (d < old) {
                    ++passes;
                    covered += old == std::numeric_limits<double>::infinity();
                    subId[p] = cur;
                }
                if (d < old || (d == old && cur < refId[p])) refDepth[p] = d, refId[p] = cur;
            }
        std::vector<std::pair<uint32_t, uint32_t>> differs;
        for (size_t p = 0; p < pixels; ++p)
            if (subId[p] != refId[p]) differs.push_back({uint32_t(p), subId[p]});

        std::vector<uint32_t> id(pixels, 0);
        std::vector<double> depth(pixels, std::numeric_limits<double>::infinity());
        resolveFromCache(cache, source.data(), width, height, id.data(), depth.data());
        EXPECT_EQ(id, refId) << "round " << round;
        for (size_t p = 0; p < pixels; ++p)
            ASSERT_EQ(std::bit_cast<uint64_t>(depth[p]), std::bit_cast<uint64_t>(refDepth[p])) << "round " << round;
        EXPECT_EQ(cache.submitted.fragments, cache.pixel.size());
        EXPECT_EQ(cache.submitted.passes, passes) << "round " << round;
        EXPECT_EQ(cache.submitted.covered, covered) << "round " << round;
        EXPECT_EQ(cache.submitted.differs, differs) << "round " << round;
        differing += differs.size();
    }
    EXPECT_GT(differing, 0u) << "no round made the two rules differ";
}

TEST(OrderingScenes, Demo) {
    const Scene s = demoScene();
    std::vector<ViewSpec> views = s.views;
    for (ViewSpec &v : views) v.camera.width = 480, v.camera.height = 270;
    checkScene(s, views, "demo");
}

TEST(OrderingScenes, Hall) {
    Scene s;
    std::string err;
    ASSERT_TRUE(loadScene(std::string(VISAUDIT_EXAMPLES) + "/hall.scene.json", {}, &s, &err)) << err;
    std::vector<ViewSpec> views = s.views;
    for (ViewSpec &v : views) v.camera.width = 320, v.camera.height = 180;
    checkScene(s, views, "hall");
}

TEST(OrderingScenes, CastleDungeon) {
    const std::string path = std::string(VISAUDIT_TEST_DATA) + "/castle/level/level-dungeon.gltf";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "not fetched: " << path << " (scripts/fetch-data.sh)";
    Scene s;
    std::string err;
    ASSERT_TRUE(loadScene(path, {}, &s, &err)) << err;
    std::vector<ViewSpec> views = s.views;
    for (const ViewSpec &v : orbitViews(s, 3)) views.push_back(v);
    for (ViewSpec &v : views) v.camera.width = 480, v.camera.height = 270;
    checkScene(s, views, "dungeon");
}

TEST(Ordering, Images) {
    const Scene s = looseTriangles(sticks());
    const Camera cam = orthoTop(120);
    const ReferenceVisibility ref = referenceVisibility(s, cam);
    const OrderingView v = prepareOrderingView(s, cam);
    const PainterResult p = paintersAlgorithm(v, ref, PainterKey::centroid);
    ASSERT_GT(p.wrongPixels, 0u);
    const PaletteImage pic = renderPainterErrors(ref, p);
    ASSERT_EQ(pic.width, 120);
    ASSERT_GT(pic.height, 120);
    const std::vector<uint8_t> img = pic.rgb();
    uint64_t red = 0;
    for (size_t i = 0; i < size_t(120) * 120; ++i)
        red += img[3 * i] == kOrderWrongColor.r && img[3 * i + 1] == kOrderWrongColor.g && img[3 * i + 2] == kOrderWrongColor.b;
    EXPECT_EQ(red, p.wrongPixels);

    std::vector<OrderOverdraw> orders = {{"submitted", {}}, {"back_to_front", {}}};
    orders[0].stats.overdraw = 1.5;
    orders[1].stats.overdraw = 3.0;
    int ch = 0;
    const std::vector<uint8_t> chart = renderOverdrawByOrder(orders, &ch);
    EXPECT_EQ(chart.size(), size_t(kOverdrawChartWidth) * size_t(ch) * 3);

    const std::filesystem::path dir = std::filesystem::temp_directory_path() / "visaudit_ordering_images";
    std::filesystem::create_directories(dir);
    const OrderingImageNames names = orderingImageNames((dir / "v").string());
    std::string err;
    EXPECT_TRUE(writePainterErrorsImage(ref, p, names.painterErrorsPng, &err)) << err;
    EXPECT_TRUE(writeOverdrawByOrderChart(orders, names.overdrawOrderPng, &err)) << err;
    EXPECT_TRUE(std::filesystem::file_size(names.painterErrorsPng) > 0);
    EXPECT_FALSE(writeABufferImage(ABufferResult{}, names.abufferPng, &err));
    EXPECT_EQ(err, "cannot write image '" + names.abufferPng + "': the A-buffer did not run for this view");
    std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace va
