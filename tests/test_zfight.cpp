// Z-fighting analysis (analysis/audits/zfight.h, reports/zfight_image.h; rules in docs/zfighting.md).
//
// Most cases look straight down (-y) at horizontal quads from a camera at height h with a 90 degree
// field of view on a 64 x 64 image, up = -z. Then:
//   * the view basis is exact: right = +x, screen up = -z, view depth d = h - y for every point, so
//     a horizontal plane has one depth over the whole image;
//   * at depth d a pixel is 2 d / 64 = d / 32 world units wide, pixel column c spans
//     x in [(c - 32) d/32, (c - 31) d/32] and pixel row r spans z in [(r - 32) d/32, (r - 31) d/32];
//   * a quad whose edges lie on pixel boundaries covers exactly the pixels between them (every
//     center is half a pixel from the edges; tan(45 deg) = 1 - 2^-53 moves them by 1e-14 px).
// So the expected pixel counts below are areas of pixel rectangles, and the expected fights follow
// from the formats' formulas at the two depths (the stored values are written in each test).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <set>

#include <unistd.h>

#include "analysis/audits/audit.h"
#include "analysis/stages/backface.h"
#include "analysis/load/demo.h"
#include "analysis/stages/frustum.h"
#include "analysis/load/load.h"
#include "analysis/audits/zfight.h"
#include "render/raster_core.h"
#include "render/clip.h"
#include "reports/zfight_image.h"

using namespace va;
namespace fs = std::filesystem;

namespace {

// A horizontal quad (2 triangles) x in [x0, x1], z in [z0, z1] at height y, facing +y.
RawMesh quadY(double x0, double x1, double z0, double z1, double y) {
    return gridMesh({x0, y, z1}, {x1 - x0, 0, 0}, {0, 0, -(z1 - z0)}, 1, 1);
}

RawMesh triangleMesh(Vec3 a, Vec3 b, Vec3 c) {
    RawMesh m;
    m.positions = {a, b, c};
    m.indices = {0, 1, 2};
    m.facesRead = 1;
    return m;
}

Scene sceneOf(std::vector<std::pair<std::string, RawMesh>> objects) {
    SceneBuildInput in;
    in.materials = {Material{}};
    for (auto &[name, mesh] : objects) {
        SceneBuildInput::Object o;
        o.name = name;
        o.mesh = "(test)";
        o.geometry = std::move(mesh);
        in.objects.push_back(std::move(o));
    }
    return buildScene(std::move(in));
}

Camera downCamera(double height, double nearZ, double farZ, int size = 64) {
    CameraSpec s;
    s.eye = {0, height, 0};
    s.target = {0, 0, 0};
    s.up = {0, 0, -1};
    s.fovYDegrees = 90;
    s.nearZ = nearZ;
    s.farZ = farZ;
    s.width = size;
    s.height = size;
    Camera cam;
    std::string err;
    EXPECT_TRUE(makeCamera(s, &cam, &err)) << err;
    return cam;
}

// The pipeline's geometry stages for one view: frustum, backface (optional), clip. The result is
// what the z-buffer draws.
ScreenTriangles screenTriangles(const Scene &scene, const Camera &cam, bool backface = true) {
    const FrustumResult fr = cullFrustum(scene, buildObjectBvh(scene), cam);
    const TriangleLists lists = backface ? cullBackfaces(scene, fr.visible, cam).kept : allTriangles(scene, fr.visible);
    return clipTriangles(cam, MeshView{scene.positions.data(), scene.indices.data()}, clipBatches(scene, lists),
                         ClipSettings{})
        .out;
}

const ZFightFormatStats &stats(const ZFightResult &r, DepthFormat f) {
    const ZFightFormatStats *s = zfightStatsOf(r, f);
    if (!s) {
        ADD_FAILURE() << "format not evaluated";
        static ZFightFormatStats none;
        return none;
    }
    return *s;
}

std::set<DepthFormat> formatsOf(const ZFightHotspot &h) {
    std::set<DepthFormat> s;
    for (const ZFightHotspotFormat &f : h.formats) s.insert(f.format.format);
    return s;
}

// Every per-pixel and per-format number is consistent, finite and within bounds.
void expectConsistent(const ZFightResult &r) {
    EXPECT_TRUE(r.error.empty()) << r.error;
    EXPECT_EQ(r.separatedPixels + r.coplanarPixels + r.sharedEdgePixels + r.intersectionPixels,
              r.fightingPixelsAnyFormat);
    EXPECT_LE(r.fightingPixelsAnyFormat, r.twoSurfacePixels);
    EXPECT_LE(r.twoSurfacePixels, r.coveredPixels);
    for (const ZFightFormatStats &s : r.perFormat) {
        EXPECT_LE(s.fightingPixels + s.sharedEdgePixels + s.intersectionPixels, r.fightingPixelsAnyFormat) << s.name;
        EXPECT_LE(s.coplanarPixels, s.fightingPixels) << s.name;
        EXPECT_LE(s.hotspots, r.hotspotCount) << s.name;
        EXPECT_LE(s.outOfRangePixels, r.coveredPixels) << s.name;
    }
    uint64_t prevArea = UINT64_MAX;
    for (size_t i = 0; i < r.hotspots.size(); ++i) {
        const ZFightHotspot &h = r.hotspots[i];
        EXPECT_EQ(h.id, i + 1);
        EXPECT_LE(h.area, prevArea);
        prevArea = h.area;
        EXPECT_TRUE(isFinite(h.centroid)) << "hotspot " << h.id;
        EXPECT_TRUE(std::isfinite(h.depth) && std::isfinite(h.depthGap) && std::isfinite(h.depthGapMax));
        EXPECT_GE(h.depthGap, 0);
        EXPECT_LE(h.depthGap, h.depthGapMax);
        EXPECT_FALSE(h.formats.empty());
        EXPECT_LE(h.pairPixels, h.area);
        uint64_t counted = 0;
        for (uint32_t id : r.hotspotIds) counted += id == h.id;
        EXPECT_EQ(counted, h.area) << "hotspot " << h.id;
    }
}

}  // namespace

// ---- The two-nearest pass -----------------------------------------------------------------------

TEST(ZFightTwoNearest, ExactDepthsAndDistinctSourcesOnly) {
    // Floor at y = 0 seen from h = 10: d = 10 everywhere. A tile at y = 1 (d = 9) over pixel columns
    // and rows 28..35 (x, z in [-1.25, 1.25]: 4 pixels of 0.3125 each side of the center).
    const Scene scene = sceneOf({{"floor", quadY(-20, 20, -20, 20, 0)}, {"tile", quadY(-1.25, 1.25, -1.25, 1.25, 1)}});
    const Camera cam = downCamera(10, 0.1, 100);
    const ScreenTriangles tris = screenTriangles(scene, cam);
    const TwoNearest two = findTwoNearest(tris, 64, 64, false);
    ASSERT_EQ(two.pixels(), 64u * 64u);
    uint64_t twoSurfaces = 0;
    for (int y = 0; y < 64; ++y)
        for (int x = 0; x < 64; ++x) {
            const size_t p = size_t(y) * 64 + size_t(x);
            ASSERT_NE(two.screen1[p], kNoFragment);
            const bool inTile = x >= 28 && x <= 35 && y >= 28 && y <= 35;
            if (!inTile) {
                EXPECT_EQ(two.screen2[p], kNoFragment) << x << "," << y;
                EXPECT_NEAR(two.depth1[p], 10.0, 1e-12);
                EXPECT_EQ(two.depth2[p], INFINITY);
                continue;
            }
            ++twoSurfaces;
            EXPECT_NEAR(two.depth1[p], 9.0, 1e-12);
            EXPECT_NEAR(two.depth2[p], 10.0, 1e-12);
            EXPECT_GE(tris.source[two.screen1[p]], 2u);  // the tile's triangles are ids 2, 3
            EXPECT_LT(tris.source[two.screen2[p]], 2u);
            // Bit-identical to the canonical per-fragment depth.
            const DepthPlane &pl = tris.planes[tris.plane[two.screen1[p]]];
            EXPECT_EQ(two.depth1[p], viewDepthAt(cam, pl, x + 0.5, y + 0.5));
        }
    EXPECT_EQ(twoSurfaces, 64u);
}

TEST(ZFightTwoNearest, ClippedPiecesOfOneTriangleAreOneSurface) {
    // A triangle crossing the near plane (near = 1) with one vertex in front of it (d = 0.5) and two
    // behind (d = 2) is clipped into a quad: two screen triangles of one source. Behind it a floor.
    // No pixel may list the same source twice.
    const Scene scene = sceneOf({{"slab", triangleMesh({-3, 9.5, -3}, {3, 8, -3}, {0, 8, 3})},
                                 {"floor", quadY(-20, 20, -20, 20, 0)}});
    const Camera cam = downCamera(10, 1, 100);
    const ScreenTriangles tris = screenTriangles(scene, cam, false);
    uint64_t slabPieces = 0;
    for (size_t t = 0; t < tris.size(); ++t) slabPieces += tris.source[t] == 0;
    ASSERT_EQ(slabPieces, 2u) << "the slab should be clipped into two screen triangles";
    const TwoNearest two = findTwoNearest(tris, 64, 64, false);
    std::set<uint32_t> piecesSeen;
    uint64_t slabOverFloor = 0;
    for (size_t p = 0; p < two.pixels(); ++p) {
        if (two.screen2[p] == kNoFragment) continue;
        EXPECT_NE(tris.source[two.screen1[p]], tris.source[two.screen2[p]]);
        EXPECT_LT(two.depth1[p], two.depth2[p]);
        if (tris.source[two.screen1[p]] == 0) ++slabOverFloor, piecesSeen.insert(two.screen1[p]);
    }
    EXPECT_EQ(piecesSeen.size(), 2u);
    EXPECT_GT(slabOverFloor, 100u);

    // The rule itself, on hand-made screen triangles (orthographic planes d = c): two overlapping
    // pieces of source 7 at d = 5 (overlap is a contract violation of the clipper, but the rule
    // must hold) and source 9 at d = 6 over the same pixels. Every covered pixel keeps source 7
    // once, then source 9.
    ScreenTriangles hand;
    const int32_t one = kSubpixelOne;
    hand.xy = {0, 0, 8 * one, 0, 0, 8 * one,            // piece A of source 7
               0, 0, 8 * one, 0, 8 * one, 8 * one,      // piece B of source 7, overlapping A
               0, 0, 8 * one, 0, 0, 8 * one};           // source 9, below both
    hand.source = {7, 7, 9};
    hand.plane = {0, 0, 1};
    hand.planes = {DepthPlane{0, 0, 5, true}, DepthPlane{0, 0, 6, true}};
    const TwoNearest h = findTwoNearest(hand, 8, 8, true);
    uint64_t both = 0;
    for (size_t p = 0; p < h.pixels(); ++p) {
        if (h.screen1[p] == kNoFragment) continue;
        EXPECT_EQ(hand.source[h.screen1[p]], 7u);
        EXPECT_EQ(h.depth1[p], 5.0);
        if (h.screen2[p] != kNoFragment) {
            ++both;
            EXPECT_EQ(hand.source[h.screen2[p]], 9u);
            EXPECT_EQ(h.depth2[p], 6.0);
        }
    }
    // Source 9's triangle (0,0), (8,0), (0,8) lies entirely under piece A: its centers
    // (x + 0.5, y + 0.5) with x + y <= 6 are inside (1 + 2 + ... + 7 = 28); the 8 with x + y = 7
    // lie on the hypotenuse, whose interior side is towards smaller x (a right edge): excluded.
    EXPECT_EQ(both, 28u);
}

// findTwoNearest gives what its rule gives applied in the walk's order, here written out again
// over forEachFragment: random soups with shared sources (clipped pieces), equal depths (ties keep
// the first drawn) and light and heavy overdraw. (A recorded, band-by-band replay of the walk was
// measured slower here than the walk's own random access, unlike the reference's resolve.)
TEST(ZFightTwoNearest, EqualsTheRuleInTheWalksOrder) {
    struct Rule {
        const ScreenTriangles &tris;
        std::vector<double> d1, d2;
        std::vector<uint32_t> t1, t2;
        uint32_t current = 0;
        // How often each case arose: the first kept surface's source, nearer or not than it but
        // nearer than the second; the second's, nearer than both, or than the second only.
        uint64_t firstsFarther = 0, secondsNearest = 0, secondsNearer = 0;
        bool beginTriangle(size_t t, bool) {
            current = tris.source[t];
            return true;
        }
        void fragment(size_t p, size_t t, double d) {
            if (t1[p] != kNoFragment && tris.source[t1[p]] == current) {
                firstsFarther += !(d < d1[p]) && d < d2[p];
                if (d < d1[p]) d1[p] = d, t1[p] = uint32_t(t);
                return;
            }
            if (t2[p] != kNoFragment && tris.source[t2[p]] == current) {
                secondsNearest += d < d2[p] && d < d1[p];
                secondsNearer += d < d2[p] && !(d < d1[p]);
                if (d < d2[p]) {
                    d2[p] = d, t2[p] = uint32_t(t);
                    if (d2[p] < d1[p]) std::swap(d1[p], d2[p]), std::swap(t1[p], t2[p]);
                }
                return;
            }
            if (d < d1[p]) {
                d2[p] = d1[p], t2[p] = t1[p];
                d1[p] = d, t1[p] = uint32_t(t);
            } else if (d < d2[p]) {
                d2[p] = d, t2[p] = uint32_t(t);
            }
        }
        void endTriangle(size_t, uint64_t) {}
    };
    const int W = 97, H = 70;
    // Fewer and more than 4 fragments a pixel; and (150) 50 sources of three pieces each around one
    // center, at depths of their own: every case of the rule arises along whole rows, and with few
    // surfaces a pixel the end state still shows each step (with five shared depths, or heavy
    // overdraw, most pixels end at two of the nearest whatever came before: a wrong step went unseen).
    for (const int count : {60, 400, 150}) {
        const bool pieces = count == 150;  // sources of three pieces around one center
        uint64_t state = 0x9E3779B97F4A7C15ull * uint64_t(count);
        auto next = [&](int64_t lo, int64_t hi) {
            state = state * 6364136223846793005ull + 1442695040888963407ull;
            return lo + int64_t((state >> 33) % uint64_t(hi - lo + 1));
        };
        ScreenTriangles tris;
        for (int k = 0; k < 5; ++k) tris.planes.push_back(DepthPlane{0, 0, double(1 + k), true});  // shared: ties
        int64_t cx = 0, cy = 0;
        for (int t = 0; t < count; ++t) {
            const int64_t size = pieces ? 30 : t % 4 == 0 ? 120 : 30;
            if (!pieces || t % 3 == 0) cx = next(-10, W + 10), cy = next(-10, H + 10);
            for (int i = 0; i < 3; ++i) {
                tris.xy.push_back(int32_t((cx + next(-size, size)) * kSubpixelOne + next(0, kSubpixelOne - 1)));
                tris.xy.push_back(int32_t((cy + next(-size, size)) * kSubpixelOne + next(0, kSubpixelOne - 1)));
            }
            // Every third a piece of the one before; or three pieces to a source.
            tris.source.push_back(uint32_t(pieces ? t / 3 * 3 : t % 3 == 1 ? t - 1 : t));
            if (pieces) {  // a depth of its own, so that the end state still shows every step
                tris.plane.push_back(uint32_t(tris.planes.size()));
                tris.planes.push_back(DepthPlane{0, 0, 1 + double(next(0, 4000)) / 64, true});
            } else {
                tris.plane.push_back(uint32_t(next(0, 4)));
            }
        }
        Rule rule{tris, std::vector<double>(size_t(W) * H, INFINITY), std::vector<double>(size_t(W) * H, INFINITY),
                  std::vector<uint32_t>(size_t(W) * H, kNoFragment), std::vector<uint32_t>(size_t(W) * H, kNoFragment)};
        uint64_t fragments = 0;
        struct Count {
            Rule &r;
            uint64_t &n;
            bool beginTriangle(size_t t, bool f) { return r.beginTriangle(t, f); }
            void fragment(size_t p, size_t t, double d) {
                ++n;
                r.fragment(p, t, d);
            }
            void endTriangle(size_t, uint64_t) {}
        } counted{rule, fragments};
        forEachFragment(tris, W, H, true, counted);
        if (count == 60) EXPECT_LT(fragments, 4u * W * H);
        else if (count == 400) EXPECT_GT(fragments, 4u * W * H);
        const TwoNearest two = findTwoNearest(tris, W, H, true);
        EXPECT_TRUE(two.depth1 == rule.d1) << count;
        EXPECT_TRUE(two.depth2 == rule.d2) << count;
        EXPECT_TRUE(two.screen1 == rule.t1) << count;
        EXPECT_TRUE(two.screen2 == rule.t2) << count;
        // The same from a reference holding none of these triangles: each is walked, recorded and
        // replayed band by band (the pipeline's path, four pixels of a row at a time where it can),
        // with every case of the rule (a source's pieces overlapping as first and as second surface).
        ReferenceVisibility none;
        none.width = W;
        none.height = H;
        none.fragmentCache.begin = {0};
        TwoNearest replayed;
        ASSERT_TRUE(findTwoNearestFromReference(Scene{}, none, tris, W, H, true, nullptr, replayed, {}));
        EXPECT_TRUE(replayed.depth1 == rule.d1) << count;
        EXPECT_TRUE(replayed.depth2 == rule.d2) << count;
        EXPECT_TRUE(replayed.screen1 == rule.t1) << count;
        EXPECT_TRUE(replayed.screen2 == rule.t2) << count;
        if (pieces)
            EXPECT_TRUE(rule.firstsFarther > 50 && rule.secondsNearest > 50 && rule.secondsNearer > 50)
                << rule.firstsFarther << " " << rule.secondsNearest << " " << rule.secondsNearer;
    }
}

// findTwoNearestFromReference gives findTwoNearest's result on every demo view: for the pipeline's
// screen triangles (each piece also the reference's), for every triangle without the backface
// stage (single-sided ones seen from behind, which the reference did not record: walked here),
// with and without the single-sided rule, and for a clip without a guard band (pieces the
// reference does not have: walked here). Its bands cover the view once, in order.
TEST(ZFightTwoNearest, FromTheReferenceCacheEqualsTheWalk) {
    const Scene scene = demoScene();
    const std::vector<uint8_t> single = singleSidedTriangles(scene);
    auto same = [](const auto &a, const auto &b) {
        return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof a[0]) == 0;
    };
    ASSERT_FALSE(scene.views.empty());
    for (const ViewSpec &view : scene.views) {
        Camera cam;
        std::string err;
        ASSERT_TRUE(makeCamera(view.camera, &cam, &err)) << err;
        const int W = cam.width, H = cam.height;
        const ReferenceVisibility ref = referenceVisibility(scene, cam, uint64_t(1) << 26);
        ASSERT_TRUE(ref.fragmentCache.complete()) << view.name;
        const FrustumResult fr = cullFrustum(scene, buildObjectBvh(scene), cam);
        TwoNearest bothSides;  // every triangle, no single-sided rule
        for (int variant = 0; variant < 4; ++variant) {
            const TriangleLists lists =
                variant == 0 ? cullBackfaces(scene, fr.visible, cam).kept : allTriangles(scene, fr.visible);
            ClipSettings cs;
            if (variant == 3) cs.guardBandPixels = 0;
            const ClipResult clip =
                clipTriangles(cam, MeshView{scene.positions.data(), scene.indices.data()}, clipBatches(scene, lists), cs);
            if (variant == 3) EXPECT_GT(clip.stats.clipped, 0u) << view.name;  // pieces the reference lacks
            const uint8_t *ss = variant == 2 ? single.data() : nullptr;
            TwoNearest walked, cached;
            findTwoNearest(clip.out, W, H, cam.orthographic, ss, walked);
            size_t next = 0;
            bool ordered = true;
            ASSERT_TRUE(findTwoNearestFromReference(scene, ref, clip.out, W, H, cam.orthographic, ss, cached,
                                                    [&](size_t p0, size_t p1) {
                                                        ordered = ordered && p0 == next && p1 > p0;
                                                        next = p1;
                                                    }));
            EXPECT_TRUE(ordered) << view.name << " " << variant;
            EXPECT_EQ(next, size_t(W) * size_t(H)) << view.name << " " << variant;
            EXPECT_TRUE(same(cached.depth1, walked.depth1)) << view.name << " " << variant;
            EXPECT_TRUE(same(cached.depth2, walked.depth2)) << view.name << " " << variant;
            EXPECT_TRUE(same(cached.screen1, walked.screen1)) << view.name << " " << variant;
            EXPECT_TRUE(same(cached.screen2, walked.screen2)) << view.name << " " << variant;
            if (variant == 1) bothSides = walked;
            // Single-sided triangles seen from behind are among the nearest two somewhere: the
            // fragments the reference did not record matter.
            if (variant == 2) EXPECT_FALSE(same(walked.screen2, bothSides.screen2)) << view.name;
        }
    }
}

// ---- Hard cases --------------------------------------------------------------------------------

// FightFilter's claim (no fight, both depths in range) against the exact encoders: every format
// (opt-in ones too), near/far from 1e-3/1 to 10/1e7, depth pairs equal, an ulp apart, a relative
// 1e-9..1e-1 apart and far apart, at wide magnitudes and both ends of the range. A pair the filter
// decides must have key(d1) < key(d2) and no out-of-range depth; it must also decide most pairs
// that are 1% or more apart (it is meant to spare their encoding).
TEST(ZFightFilter, DecidesOnlyPairsThatCannotFightAndMostFarApartOnes) {
    uint64_t state = 5;
    auto next = [&] {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return double(state >> 11) * 0x1p-53;
    };
    const double ranges[][2] = {{1e-3, 1}, {0.1, 1000}, {0.5, 5000}, {4, 8192}, {1, 1e5}, {10, 1e7}};
    uint64_t decided = 0, farPairs = 0, farDecided = 0;
    for (const auto &nf : ranges) {
        const double n = nf[0], f = nf[1];
        std::vector<DepthEncoder> enc;
        for (const DepthFormat fmt : allDepthFormats()) enc.push_back(makeDepthEncoder(fmt, n, f));
        const double dMin = n * 0.5, dMax = f * 1.5;  // pixels beyond the range too
        const FightFilter filter(enc, dMin, dMax);
        for (int i = 0; i < 40000; ++i) {
            const double d1 = dMin * std::pow(dMax / dMin, next());
            double d2 = d1;
            switch (i % 5) {
            case 0: break;
            case 1: d2 = std::nextafter(d1, INFINITY); break;
            case 2: d2 = d1 * (1 + std::pow(10.0, -9 + 8 * next())); break;
            default: d2 = d1 * (1 + 0.01 + next() * 3); break;
            }
            if (!(d2 <= dMax)) continue;
            const uint32_t c1 = filter.cell(d1), c2 = filter.cell(d2);
            const bool far = d2 >= d1 * 1.01;
            for (size_t k = 0; k < enc.size(); ++k) {
                bool o1 = false, o2 = false;
                const uint32_t k1 = depthKey(enc[k], d1, &o1), k2 = depthKey(enc[k], d2, &o2);
                const bool inRange = d1 >= n && d2 <= f;
                if (far && inRange && filter.filtered(k)) ++farPairs;
                if (!filter.cannotFight(k, c1, c2)) continue;
                ++decided;
                farDecided += far && inRange;
                ASSERT_LT(k1, k2) << depthFormatName(enc[k].format) << " n " << n << " f " << f << " d1 " << d1
                                  << " d2 " << d2;
                ASSERT_FALSE(o1 || o2) << depthFormatName(enc[k].format) << " d1 " << d1 << " d2 " << d2;
            }
            if (filter.cannotFightAny(c1, c2))
                for (size_t k = 0; k < enc.size(); ++k) EXPECT_TRUE(!filter.filtered(k) || filter.cannotFight(k, c1, c2));
        }
    }
    EXPECT_GT(decided, 1000000u);
    EXPECT_GT(double(farDecided), 0.8 * double(farPairs)) << farDecided << " of " << farPairs;
}

// The windows the filter relies on, checked where they are tightest: for the quotient formats and
// log24, depths a window apart keep their keys' order (one-ulp steps at the low end of the range,
// where the quotient's rounding is largest relative to its growth).
TEST(ZFightFilter, WindowsHoldAtTheirTightestDepths) {
    for (const double n : {1e-3, 0.1, 4.0})
        for (const double f : {100.0, 1e4, 1e6}) {
            for (const DepthFormat fmt : {DepthFormat::unorm16, DepthFormat::unorm24, DepthFormat::f32, DepthFormat::log24}) {
                const DepthEncoder e = makeDepthEncoder(fmt, n, f);
                const double rho = monotoneWindow(e);
                ASSERT_GE(rho, 0) << depthFormatName(fmt);
                for (double d = n; d < f; d *= 1.37) {
                    const double d2 = d * (1 + rho);
                    if (d2 > f) break;
                    EXPECT_LE(depthKey(e, d), depthKey(e, d2)) << depthFormatName(fmt) << " d " << d;
                }
            }
            EXPECT_LT(monotoneWindow(makeDepthEncoder(DepthFormat::f32_gl, n, f)), 0);
            EXPECT_EQ(monotoneWindow(makeDepthEncoder(DepthFormat::f32_reversed, n, f)), 0);
        }
}

TEST(ZFightCases, CoplanarDuplicateFightsInEveryFormat) {
    // "tile" and "copy": the same two triangles, vertex for vertex. Their depth planes are
    // bit-identical, so both depths are equal at each of the tile's 8 x 8 = 64 pixels (columns and
    // rows 28..35, see the file comment), and equal depths fight in every format.
    const RawMesh tile = quadY(-1.25, 1.25, -1.25, 1.25, 0);
    const Scene scene = sceneOf({{"tile", tile}, {"copy", tile}});
    const Camera cam = downCamera(10, 0.1, 1000);
    const ScreenTriangles tris = screenTriangles(scene, cam);
    const ZFightResult r = analyzeZFighting(scene, cam, tris);
    expectConsistent(r);
    EXPECT_EQ(r.coveredPixels, 64u);
    EXPECT_EQ(r.twoSurfacePixels, 64u);
    EXPECT_EQ(r.coplanarPixels, 64u);
    ASSERT_EQ(r.perFormat.size(), size_t(kClassicDepthFormatCount));  // the default set
    for (const ZFightFormatStats &s : r.perFormat) {
        EXPECT_EQ(s.fightingPixels, 64u) << s.name;
        EXPECT_EQ(s.coplanarPixels, 64u) << s.name;
        EXPECT_EQ(s.hotspots, 1u) << s.name;
        EXPECT_EQ(s.sharedEdgePixels + s.intersectionPixels, 0u) << s.name;
    }
    ASSERT_EQ(r.hotspotCount, 1u);
    const ZFightHotspot &h = r.hotspots.at(0);
    EXPECT_EQ(h.area, 64u);
    EXPECT_EQ(h.coplanarPixels, 64u);
    EXPECT_EQ(h.minX, 28);
    EXPECT_EQ(h.maxX, 35);
    EXPECT_EQ(h.minY, 28);
    EXPECT_EQ(h.maxY, 35);
    EXPECT_EQ(h.depthGap, 0.0);  // bit-identical depths
    EXPECT_NEAR(h.depth, 10.0, 1e-12);
    // Pixel centers 28.5 .. 35.5 are symmetric about 32: the mean point is the tile's center.
    EXPECT_NEAR(h.centroid.x, 0, 1e-12);
    EXPECT_NEAR(h.centroid.y, 0, 1e-12);
    EXPECT_NEAR(h.centroid.z, 0, 1e-12);
    EXPECT_EQ(h.formats.size(), size_t(kClassicDepthFormatCount));
    EXPECT_EQ(std::set<std::string>({h.objectA, h.objectB}), std::set<std::string>({"tile", "copy"}));
    EXPECT_EQ(h.pairs, 2u);  // tile triangle k over copy triangle k, k = 0, 1
    // Coplanar surfaces do not decide the format (no format orders them): nothing else fights, so
    // the fewest bits win, and the recommendation names the coplanar pixels.
    ASSERT_TRUE(r.recommended.has_value());
    EXPECT_EQ(*r.recommended, DepthFormat::unorm16);
    EXPECT_EQ(r.recommendation,
              "unorm16: the fewest bits (16) with no fighting pixels in this view; coplanar surfaces fight in every "
              "format: offset the decal or use a depth bias (64 pixels, not counted here)");
}

TEST(ZFightCases, DecalOneMillimeterAboveFloorAt100m) {
    // Near 0.1, far 1000, eye 100 above the floor: floor d2 = 100, decal (y = 0.001) d1 = 99.999.
    // Decal x, z in [-12.5, 12.5]: 4 pixels of 100/32 = 3.125 each side (its own depth makes the
    // pixels 1e-5 smaller: edges at 27.99996 and 36.00004, centers 28.5 .. 35.5 inside): 64 pixels.
    // Stored values (z = f(d-n)/(d(f-n)), S = 2^N - 1; float(x) rounds to float):
    //   unorm16:  S z(99.999) = 65476.0119, S z(100) = 65476.0126  -> both 65476: fight
    //   unorm24:  16762113.829, 16762113.996                       -> both 16762114: fight
    //   unorm24_gl: float window depths 16762114.0009 both          -> fight
    //   f32:      float(z) = 0.99909991 for both                     -> fight
    //   f32_reversed: float(n(f-d)/(d(f-n))) = 9.000999853e-4 vs 9.000900318e-4 (the nearer larger):
    //             172 float steps apart, in order                    -> no fight
    //   f32_reversed_inf 1.00000994e-3 vs 1.00000005e-3; linear_f32 99.9990005 vs 100;
    //   inv_f32 0.0100001004 vs 0.0099999998; int31_inv 21475051 vs 21474836; uint32_inv 42950102 vs
    //   42949672; uint32_inv1 42524849 vs 42524428; log24 11207331 vs 11207355  -> no fight.
    const Scene scene = sceneOf({{"floor", quadY(-400, 400, -400, 400, 0)},
                                 {"decal", quadY(-12.5, 12.5, -12.5, 12.5, 0.001)}});
    const Camera cam = downCamera(100, 0.1, 1000);
    const ZFightResult r = analyzeZFighting(scene, cam, screenTriangles(scene, cam));
    expectConsistent(r);
    EXPECT_EQ(r.coveredPixels, 64u * 64u);
    EXPECT_EQ(r.twoSurfacePixels, 64u);
    const std::set<DepthFormat> fighting = {DepthFormat::unorm16, DepthFormat::unorm24, DepthFormat::unorm24_gl,
                                            DepthFormat::f32};
    for (const ZFightFormatStats &s : r.perFormat) {
        const uint64_t expected = fighting.count(s.format.format) ? 64 : 0;
        EXPECT_EQ(s.fightingPixels, expected) << s.name;
        EXPECT_EQ(s.coplanarPixels, 0u) << s.name;
        EXPECT_EQ(s.hotspots, expected ? 1u : 0u) << s.name;
        EXPECT_EQ(s.outOfRangePixels, 0u) << s.name;
    }
    EXPECT_EQ(stats(r, DepthFormat::unorm16).fightingPixels, 64u);
    EXPECT_EQ(stats(r, DepthFormat::f32_reversed).fightingPixels, 0u);
    ASSERT_EQ(r.hotspotCount, 1u);
    const ZFightHotspot &h = r.hotspots[0];
    EXPECT_EQ(h.area, 64u);
    EXPECT_EQ(h.coplanarPixels, 0u);
    EXPECT_EQ(formatsOf(h), fighting);
    EXPECT_NEAR(h.depthGap, 0.001, 1e-9);
    EXPECT_NEAR(h.depth, 99.999, 1e-9);
    EXPECT_NEAR(h.centroid.x, 0, 1e-9);
    EXPECT_NEAR(h.centroid.y, 0.001, 1e-9);  // on the decal (the nearer surface)
    EXPECT_NEAR(h.centroid.z, 0, 1e-9);
    EXPECT_EQ(h.objectA, "floor");  // floor triangles have the lower ids
    EXPECT_EQ(h.objectB, "decal");
    // Fewest bits that do not fight: 16 fights; of the 24-bit formats unorm24 and unorm24_gl fight,
    // log24 does not -> log24.
    ASSERT_TRUE(r.recommended.has_value());
    EXPECT_EQ(*r.recommended, DepthFormat::log24);
    EXPECT_EQ(r.recommendation, "log24: the fewest bits (24) with no fighting pixels in this view");
}

TEST(ZFightCases, ExactHotspotCountsAndEightConnectivity) {
    // The decal of the previous case (1 mm above the floor at 100 m: fights in unorm16) as four
    // decals on pixel rectangles (pixel column c starts at x = (c - 32) * 3.125, row r at
    // z = (r - 32) * 3.125):
    //   A: columns 4..11, rows 4..11          8 x 8 = 64 pixels
    //   B: columns 40..43, rows 20..21        4 x 2 =  8 pixels
    //   C: columns 50..52, rows 50..52        3 x 3 =  9 pixels
    //   D: columns 53..54, rows 53..54        2 x 2 =  4 pixels, touching C only at a corner:
    // with 8-connectivity C and D are one hotspot of 13 pixels. Expected: 64, 13, 8.
    auto px = [](int c) { return (c - 32) * 3.125; };
    const double y = 0.001;
    const Scene scene = sceneOf({{"floor", quadY(-400, 400, -400, 400, 0)},
                                 {"A", quadY(px(4), px(12), px(4), px(12), y)},
                                 {"B", quadY(px(40), px(44), px(20), px(22), y)},
                                 {"C", quadY(px(50), px(53), px(50), px(53), y)},
                                 {"D", quadY(px(53), px(55), px(53), px(55), y)}});
    const Camera cam = downCamera(100, 0.1, 1000);
    const ScreenTriangles tris = screenTriangles(scene, cam);
    const ZFightResult r = analyzeZFighting(scene, cam, tris);
    expectConsistent(r);
    EXPECT_EQ(r.twoSurfacePixels, 85u);
    EXPECT_EQ(stats(r, DepthFormat::unorm16).fightingPixels, 85u);
    EXPECT_EQ(stats(r, DepthFormat::unorm16).hotspots, 3u);
    EXPECT_EQ(stats(r, DepthFormat::f32_reversed).fightingPixels, 0u);
    EXPECT_EQ(stats(r, DepthFormat::f32_reversed).hotspots, 0u);
    ASSERT_EQ(r.hotspotCount, 3u);
    ASSERT_EQ(r.hotspots.size(), 3u);
    EXPECT_EQ(r.hotspots[0].area, 64u);
    EXPECT_EQ(r.hotspots[1].area, 13u);
    EXPECT_EQ(r.hotspots[2].area, 8u);
    EXPECT_EQ(r.hotspots[0].objectB, "A");
    EXPECT_EQ(r.hotspots[1].objectB, "C");  // C's 9 pixels outnumber D's 4
    // C's quad is 2 triangles split by a diagonal through 3 pixel centers, which the fill rule gives
    // to one of them: 3 + 3 of its 9 pixels over the same floor triangle.
    EXPECT_EQ(r.hotspots[1].pairPixels, 6u);
    EXPECT_EQ(r.hotspots[2].objectB, "B");
    const ZFightHotspot &cd = r.hotspots[1];
    EXPECT_EQ(cd.minX, 50);
    EXPECT_EQ(cd.minY, 50);
    EXPECT_EQ(cd.maxX, 54);
    EXPECT_EQ(cd.maxY, 54);
    const ZFightHotspot &b = r.hotspots[2];
    EXPECT_EQ(b.minX, 40);
    EXPECT_EQ(b.maxX, 43);
    EXPECT_EQ(b.minY, 20);
    EXPECT_EQ(b.maxY, 21);
    // B's centroid: pixel centers 40.5 .. 43.5 and 20.5, 21.5 at d = 99.999 (1e-5 closer than
    // 100): x = (42 - 32) * 99.999 / 32, z = (21 - 32) * 99.999 / 32.
    EXPECT_NEAR(b.centroid.x, 10 * 99.999 / 32, 1e-9);
    EXPECT_NEAR(b.centroid.z, -11 * 99.999 / 32, 1e-9);

    // Minimum area 9: B (8 pixels) is no hotspot; its pixels still fight.
    ZFightSettings s;
    s.minHotspotArea = 9;
    const ZFightResult r9 = analyzeZFighting(scene, cam, tris, s);
    EXPECT_EQ(r9.hotspotCount, 2u);
    EXPECT_EQ(stats(r9, DepthFormat::unorm16).hotspots, 2u);
    EXPECT_EQ(stats(r9, DepthFormat::unorm16).fightingPixels, 85u);
    EXPECT_EQ(r9.hotspotAt(size_t(20) * 64 + 40), 0u);
    // Listing only one: all three counted, one described.
    s.minHotspotArea = 1;
    s.maxHotspotsListed = 1;
    const ZFightResult r1 = analyzeZFighting(scene, cam, tris, s);
    EXPECT_EQ(r1.hotspotCount, 3u);
    EXPECT_EQ(r1.hotspots.size(), 1u);
    EXPECT_EQ(stats(r1, DepthFormat::unorm16).hotspots, 3u);
    EXPECT_EQ(r1.hotspotAt(size_t(20) * 64 + 40), 3u);  // ids also beyond the listed ones
}

TEST(ZFightCases, InterpenetratingTrianglesGiveAnIntersectionLineNotAHotspot) {
    // Floor y = 0 (d = 10 from h = 10) and a tilted plane y = (x - 0.15625) / 2 crossing it along
    // x = 0.15625: the centers of pixel column 32 (x = 0.5 * 10/32). There both depths are 10 (up to
    // the rounding of the tilted plane's depth), so every format stores equal values and fights;
    // the corners of those pixels (x = 0 and x = 0.3125) lie on opposite sides of the line:
    // intersection, all 64 rows. One column away the depths differ by 0.15 m, more than unorm16's
    // step at d = 10 (d^2 (f - n)/(S f n) = 0.015 m): nothing else fights.
    const double x0 = 0.15625;
    auto tiltedY = [&](double x) { return (x - x0) / 2; };
    RawMesh tilted;
    tilted.positions = {{-24, tiltedY(-24), 40}, {12, tiltedY(12), 40}, {12, tiltedY(12), -40}, {-24, tiltedY(-24), -40}};
    tilted.indices = {0, 1, 2, 0, 2, 3};
    tilted.facesRead = 2;
    const Scene scene = sceneOf({{"floor", quadY(-40, 40, -40, 40, 0)}, {"ramp", tilted}});
    const Camera cam = downCamera(10, 0.1, 100);
    const ZFightResult r = analyzeZFighting(scene, cam, screenTriangles(scene, cam));
    expectConsistent(r);
    EXPECT_EQ(r.hotspotCount, 0u);
    EXPECT_EQ(r.intersectionPixels, 64u);
    EXPECT_EQ(r.separatedPixels + r.coplanarPixels + r.sharedEdgePixels, 0u);
    for (const ZFightFormatStats &s : r.perFormat) {
        EXPECT_EQ(s.fightingPixels, 0u) << s.name;
        EXPECT_EQ(s.hotspots, 0u) << s.name;
    }
    EXPECT_EQ(stats(r, DepthFormat::unorm16).intersectionPixels, 64u);
    for (int y = 0; y < 64; ++y)
        EXPECT_EQ(ZPixelClass(r.pixelClass[size_t(y) * 64 + 32]), ZPixelClass::intersection) << "row " << y;
    // Everything fights nowhere else: the recommendation is the fewest bits.
    ASSERT_TRUE(r.recommended.has_value());
    EXPECT_EQ(*r.recommended, DepthFormat::unorm16);
}

TEST(ZFightCases, ClosedMeshSharedEdgesAreNoHotspots) {
    // A closed box drawn with all its faces (no backface culling), top face at y = 0 seen from
    // h = 10 (d = 10). Half width h = 1.09375 = 3.5 pixels of 0.3125: the top face's edges project
    // through pixel centers (x = -h at column 28's centers, x = +h at column 35's; z likewise for
    // rows). The box's side faces are seen from inside (back faces): each projects inside the top
    // face, from the top face's edge inwards, sharing that edge.
    // Where a center lies exactly on a projected top edge, both the top face and the side face
    // below it contain it or both exclude it (they lie on the same side of the edge in screen
    // space, so the fill rule treats the edge alike for both): left edge (column 28) and top edge
    // (row 28) are included, right (column 35) and bottom (row 35) excluded. At those centers the
    // two depths are equal (the point is on both planes), so every format fights:
    //   column 28, rows 28..34 (top face + side x = -h)   7 pixels
    //   row 28, columns 29..34 (top face + side z = -h)   6 pixels
    // The corner center (28, 28) is the vertex itself; the side x = -h face excludes it (its
    // slanted edge there is a right edge), the side z = -h face includes it. 13 pixels, each within
    // 0 pixels of a shared edge: shared_edge, no hotspot. Elsewhere the side faces fall away from
    // the top face at 3 m of depth per pixel.
    const double h = 1.09375;
    const Scene scene = sceneOf({{"box", boxMesh({0, -1, 0}, {h, 1, h})}});
    const Camera cam = downCamera(10, 0.1, 100);
    const ZFightResult r = analyzeZFighting(scene, cam, screenTriangles(scene, cam, false));
    expectConsistent(r);
    EXPECT_EQ(r.hotspotCount, 0u);
    EXPECT_EQ(r.sharedEdgePixels, 13u);
    EXPECT_EQ(r.fightingPixelsAnyFormat, 13u);
    for (const ZFightFormatStats &s : r.perFormat) {
        EXPECT_EQ(s.sharedEdgePixels, 13u) << s.name;
        EXPECT_EQ(s.fightingPixels, 0u) << s.name;
        EXPECT_EQ(s.hotspots, 0u) << s.name;
    }
    for (int k = 28; k <= 34; ++k) {
        EXPECT_EQ(ZPixelClass(r.pixelClass[size_t(k) * 64 + 28]), ZPixelClass::shared_edge) << "row " << k;
        EXPECT_EQ(ZPixelClass(r.pixelClass[size_t(28) * 64 + size_t(k)]), ZPixelClass::shared_edge) << "col " << k;
    }
    // With backface culling (the pipeline's default) the side faces are not drawn at all; nor when
    // every triangle is single-sided and only the projected winding decides (as the z-buffer's
    // singleSided option does).
    const ZFightResult culled = analyzeZFighting(scene, cam, screenTriangles(scene, cam, true));
    EXPECT_EQ(culled.twoSurfacePixels, 0u);
    EXPECT_EQ(culled.fightingPixelsAnyFormat, 0u);
    const std::vector<uint8_t> single(scene.triangleCount(), 1);
    ZFightSettings ss;
    ss.singleSided = single.data();
    const ZFightResult winding = analyzeZFighting(scene, cam, screenTriangles(scene, cam, false), ss);
    EXPECT_EQ(winding.coveredPixels, 49u);  // the top face: columns and rows 28..34
    EXPECT_EQ(winding.twoSurfacePixels, 0u);
}

TEST(ZFightCases, WideRangeNear1e3Far1e6FormatsFollowTheirMath) {
    // Near 1e-3, far 1e6 (a 1e9 ratio). Every number finite; each format fights where its formula
    // says (stored values computed by hand below).
    const Camera cam100 = downCamera(100, 1e-3, 1e6);
    {
        // Decal 1 mm above the floor at 100 m (d 99.999 / 100), 64 pixels as before:
        //   unorm16 65534.3447 / 65534.3447, unorm24 16777047.2429 / 16777047.2446, unorm24_gl equal
        //   floats, f32 float 0.99998999 both: fight (z is within 1e-5 of 1, where these formats
        //   have almost no values left). f32_reversed 9.9991003e-6 vs 9.9990002e-6 (110 floats
        //   apart), f32_reversed_inf, log24 5604476 vs 5604488, the inverse integer formats and the
        //   linear/inverse floats: apart, in order.
        const Scene scene = sceneOf({{"floor", quadY(-400, 400, -400, 400, 0)},
                                     {"decal", quadY(-12.5, 12.5, -12.5, 12.5, 0.001)}});
        const ZFightResult r = analyzeZFighting(scene, cam100, screenTriangles(scene, cam100));
        expectConsistent(r);
        const std::set<DepthFormat> fighting = {DepthFormat::unorm16, DepthFormat::unorm24, DepthFormat::unorm24_gl,
                                                DepthFormat::f32};
        for (const ZFightFormatStats &s : r.perFormat) {
            EXPECT_EQ(s.fightingPixels, fighting.count(s.format.format) ? 64u : 0u) << s.name;
            EXPECT_EQ(s.outOfRangePixels, 0u) << s.name;
        }
        ASSERT_EQ(r.hotspots.size(), 1u);
        EXPECT_NEAR(r.hotspots[0].depthGap, 0.001, 1e-9);
        EXPECT_EQ(r.recommended, DepthFormat::log24);
    }
    {
        // The same at 0.5 m (decal d = 0.499, floor 0.5; pixels 1/64 m: decal x, z in
        // [-0.0625, 0.0625]). int31_inv and uint32_inv cannot hold d < 1: both clamp to the value at
        // d = 1 and fight, and all 4096 covered pixels are out of range for them. unorm16:
        // 65403.667 / 65403.930, both 65404: fight. unorm24: 16743593 vs 16743661: apart; so the
        // recommendation is unorm24 (24 bits, listed before unorm24_gl and log24).
        const Scene scene = sceneOf({{"floor", quadY(-4, 4, -4, 4, 0)},
                                     {"decal", quadY(-0.0625, 0.0625, -0.0625, 0.0625, 0.001)}});
        const Camera cam = downCamera(0.5, 1e-3, 1e6);
        const ZFightResult r = analyzeZFighting(scene, cam, screenTriangles(scene, cam));
        expectConsistent(r);
        EXPECT_EQ(r.coveredPixels, 4096u);
        const std::set<DepthFormat> fighting = {DepthFormat::int31_inv, DepthFormat::uint32_inv, DepthFormat::unorm16};
        for (const ZFightFormatStats &s : r.perFormat) {
            EXPECT_EQ(s.fightingPixels, fighting.count(s.format.format) ? 64u : 0u) << s.name;
            const bool clampsBelow1 = s.format == DepthFormat::int31_inv || s.format == DepthFormat::uint32_inv;
            EXPECT_EQ(s.outOfRangePixels, clampsBelow1 ? 4096u : 0u) << s.name;
        }
        EXPECT_EQ(r.recommended, DepthFormat::unorm24);
    }
}

// The fight bits and out-of-range counts against every pixel's two surfaces encoded in every format:
// the pixels the filter leaves out while gathering (2a) change nothing. Every demo view, with the
// default formats (all filtered: only the pixels that may fight are listed) and with every format
// (f32_gl is never filtered: every two-surface pixel is listed), walked and from the reference.
TEST(ZFightCases, FightBitsEqualEncodingEveryPixel) {
    std::vector<DepthFormatSpec> every;
    for (const DepthFormat fmt : allDepthFormats()) every.push_back(fmt);
    uint64_t fighting = 0, outOfRange = 0;
    auto check = [&](const Scene &scene, const Camera &cam, const std::string &name) {
        const ScreenTriangles tris = screenTriangles(scene, cam);
        const ReferenceVisibility ref = referenceVisibility(scene, cam, uint64_t(1) << 26);
        TwoNearest two;
        findTwoNearest(tris, cam.width, cam.height, cam.orthographic, nullptr, two);
        for (const bool all : {false, true})
            for (const bool fromReference : {false, true}) {
                ZFightSettings settings;
                if (all) settings.formats = every;
                if (fromReference) settings.reference = &ref;
                const ZFightResult r = analyzeZFighting(scene, cam, tris, settings);
                ASSERT_TRUE(r.error.empty()) << r.error;
                const std::string what = name + (all ? " every format" : " default formats") +
                                         (fromReference ? ", from the reference" : ", walked");
                uint64_t twoSurfaces = 0;
                std::vector<uint64_t> oor(settings.formats.size(), 0);
                for (size_t p = 0; p < two.pixels(); ++p) {
                    if (two.screen1[p] == kNoFragment) continue;
                    const bool second = two.screen2[p] != kNoFragment;
                    twoSurfaces += second;
                    uint32_t mask = 0;
                    for (size_t i = 0; i < settings.formats.size(); ++i) {
                        const DepthEncoder e = makeDepthEncoder(settings.formats[i], cam.nearZ, cam.farZ);
                        bool o1 = false, o2 = false;
                        const uint32_t k1 = depthKey(e, two.depth1[p], &o1);
                        const uint32_t k2 = second ? depthKey(e, two.depth2[p], &o2) : 0;
                        mask |= second && k1 >= k2 ? uint32_t(1) << i : 0;
                        oor[i] += o1 || o2;
                    }
                    ASSERT_EQ(r.fightMaskAt(p), mask) << what << " pixel " << p;
                    fighting += mask != 0;
                }
                EXPECT_EQ(r.twoSurfacePixels, twoSurfaces) << what;
                for (size_t i = 0; i < settings.formats.size(); ++i) {
                    EXPECT_EQ(r.perFormat[i].outOfRangePixels, oor[i]) << what << " " << r.perFormat[i].name;
                    outOfRange += oor[i];
                }
            }
    };
    const Scene demo = demoScene();
    ASSERT_FALSE(demo.views.empty());
    for (const ViewSpec &view : demo.views) {
        Camera cam;
        std::string err;
        ASSERT_TRUE(makeCamera(view.camera, &cam, &err)) << err;
        check(demo, cam, view.name);
    }
    // The decal at 0.5 m of WideRangeNear1e3Far1e6FormatsFollowTheirMath: every pixel out of range
    // for the formats that cannot hold d < 1.
    const Scene decal = sceneOf({{"floor", quadY(-4, 4, -4, 4, 0)},
                                 {"decal", quadY(-0.0625, 0.0625, -0.0625, 0.0625, 0.001)}});
    check(decal, downCamera(0.5, 1e-3, 1e6), "decal at 0.5 m");
    EXPECT_GT(fighting, 0u);  // the demo's decal and the formats' limits: bits to get wrong
    EXPECT_GT(outOfRange, 0u);
}

TEST(ZFightCases, EveryFormatFightingMeansNoRecommendation) {
    // Two parallel planes 1e-11 apart at d = 10: farther apart than coplanar allows
    // (64 * 2^-53 * 40 = 2.8e-13 for coordinates up to 40) but closer than any format resolves
    // (the finest, linear_f32, has 9.5e-7 at 10): every format fights at the sheet's 64 pixels.
    const Scene scene = sceneOf({{"floor", quadY(-40, 40, -40, 40, 0)},
                                 {"sheet", quadY(-1.25, 1.25, -1.25, 1.25, 1e-11)}});
    const Camera cam = downCamera(10, 0.1, 100);
    const ZFightResult r = analyzeZFighting(scene, cam, screenTriangles(scene, cam));
    expectConsistent(r);
    for (const ZFightFormatStats &s : r.perFormat) {
        EXPECT_EQ(s.fightingPixels, 64u) << s.name;
        EXPECT_EQ(s.coplanarPixels, 0u) << s.name;
    }
    EXPECT_FALSE(r.recommended.has_value());
    EXPECT_EQ(r.recommendation,
              "every format fights at surfaces that are not coplanar (fewest: linear_f32, 64 pixels; surfaces down "
              "to 1e-11 m apart): move the surfaces apart, push the near plane out or pull the far plane in");
}

TEST(ZFightCases, EmptyViewAndBadSettings) {
    const Scene scene = sceneOf({{"floor", quadY(-1, 1, -1, 1, 0)}});
    const Camera cam = downCamera(10, 0.1, 100);
    const ZFightResult empty = analyzeZFighting(scene, cam, ScreenTriangles{});
    expectConsistent(empty);
    EXPECT_EQ(empty.coveredPixels, 0u);
    EXPECT_EQ(empty.hotspotCount, 0u);
    EXPECT_EQ(empty.recommended, DepthFormat::unorm16);

    ZFightSettings s;
    s.formats = {};
    EXPECT_EQ(analyzeZFighting(scene, cam, ScreenTriangles{}, s).error,
              "no depth formats to evaluate; pass at least one (e.g. all of allDepthFormats())");
    s.formats = {DepthFormat::f32, DepthFormat::unorm16, DepthFormat::f32};
    EXPECT_EQ(analyzeZFighting(scene, cam, ScreenTriangles{}, s).error,
              "depth format 'f32' is listed twice; list each format once");
    s.formats = {DepthFormat::f32};
    s.sharedEdgePixels = -1;
    EXPECT_EQ(analyzeZFighting(scene, cam, ScreenTriangles{}, s).error,
              "sharedEdgePixels must be a finite distance >= 0 (pixels); the default is 1");
    // A subset of formats: the recommendation is chosen among them.
    s.sharedEdgePixels = 1;
    s.formats = {DepthFormat::f32_reversed, DepthFormat::unorm24};
    const ZFightResult sub = analyzeZFighting(scene, cam, screenTriangles(scene, cam), s);
    ASSERT_EQ(sub.perFormat.size(), 2u);
    EXPECT_EQ(sub.recommended, DepthFormat::unorm24);
}

// ---- The demo scene ---------------------------------------------------------------------------------

TEST(ZFightDemo, CoplanarDecalIsAHotspotAtItsWorldPosition) {
    const Scene scene = demoScene();
    const ViewSpec &spawn = scene.views.at(0);
    ASSERT_EQ(spawn.name, "spawn");
    Camera cam;
    std::string err;
    ASSERT_TRUE(makeCamera(spawn.camera, &cam, &err)) << err;
    const ScreenTriangles tris = screenTriangles(scene, cam);
    const ZFightResult r = analyzeZFighting(scene, cam, tris);
    expectConsistent(r);
    // The decal (x in [-1, 1], z in [3, 5], y = 0, exactly in the floor's plane) over the floor.
    const ZFightHotspot *decal = nullptr;
    for (const ZFightHotspot &h : r.hotspots)
        if (std::set<std::string>({h.objectA, h.objectB}) == std::set<std::string>({"decal", "floor"})) decal = &h;
    ASSERT_NE(decal, nullptr) << "no decal/floor hotspot among " << r.hotspots.size();
    EXPECT_EQ(decal->id, 1u);  // the largest
    EXPECT_EQ(decal->coplanarPixels, decal->area);
    EXPECT_GE(decal->centroid.x, -1);
    EXPECT_LE(decal->centroid.x, 1);
    EXPECT_GE(decal->centroid.z, 3);
    EXPECT_LE(decal->centroid.z, 5);
    EXPECT_NEAR(decal->centroid.y, 0, 1e-9);
    // Every pixel where the decal and the floor are the two nearest surfaces fights (their depths
    // differ by rounding only) and belongs to that one hotspot.
    const TwoNearest two = findTwoNearest(tris, cam.width, cam.height, false);
    const uint32_t decalFirst = scene.sources[1].firstTriangle;
    uint64_t decalOverFloor = 0;
    for (size_t p = 0; p < two.pixels(); ++p) {
        if (two.screen2[p] == kNoFragment) continue;
        const uint32_t a = tris.source[two.screen1[p]], b = tris.source[two.screen2[p]];
        const bool aDecal = a >= decalFirst && a < decalFirst + 2, bDecal = b >= decalFirst && b < decalFirst + 2;
        const bool aFloor = a < scene.sources[0].triangleCount, bFloor = b < scene.sources[0].triangleCount;
        if ((aDecal && bFloor) || (bDecal && aFloor)) {
            ++decalOverFloor;
            EXPECT_EQ(r.hotspotAt(p), decal->id);
        }
    }
    EXPECT_EQ(decal->area, decalOverFloor);
    EXPECT_GT(decalOverFloor, 1000u);
    // The recommendation ignores the coplanar decal and says so.
    ASSERT_TRUE(r.recommended.has_value());
    EXPECT_NE(r.recommendation.find("coplanar surfaces fight in every format"), std::string::npos);
    std::cout << "[ demo spawn ] hotspots " << r.hotspotCount << ", decal #" << decal->id << " area " << decal->area
              << " at (" << decal->centroid.x << ", " << decal->centroid.y << ", " << decal->centroid.z
              << "), recommended " << depthFormatName(*r.recommended) << ": " << r.recommendation << "\n";
    for (const ZFightFormatStats &s : r.perFormat)
        std::cout << "  " << s.name << " fighting " << s.fightingPixels << " (coplanar " << s.coplanarPixels
                  << ") hotspots " << s.hotspots << " edge " << s.sharedEdgePixels << " intersection "
                  << s.intersectionPixels << " out of range " << s.outOfRangePixels << "\n";
}

// ---- The image ----------------------------------------------------------------------------------

TEST(ZFightImage, HotspotsInTheirColorsMarkersAndLegend) {
    auto px = [](int c) { return (c - 32) * 3.125; };
    const Scene scene = sceneOf({{"floor", quadY(-400, 400, -400, 400, 0)},
                                 {"A", quadY(px(4), px(12), px(4), px(12), 0.001)},
                                 {"B", quadY(px(40), px(44), px(20), px(22), 0.001)}});
    const Camera cam = downCamera(100, 0.1, 1000);
    const ScreenTriangles tris = screenTriangles(scene, cam);
    const ZFightResult r = analyzeZFighting(scene, cam, tris);
    ASSERT_EQ(r.hotspotCount, 2u);
    ZBufferSettings zs;
    zs.encoder = makeDepthEncoder(DepthFormat::unorm16, cam.nearZ, cam.farZ);
    const ZBufferResult zb = rasterize(tris, 64, 64, zs);
    ZFightImage img;
    std::string err;
    ASSERT_TRUE(renderZFightImage(r, zb.buffer, &img, &err)) << err;
    EXPECT_EQ(img.viewWidth, 64);
    EXPECT_EQ(img.viewHeight, 64);
    EXPECT_GT(img.height, 64);
    EXPECT_GE(img.width, 64);
    // Hotspot pixels in their colors; the outline two pixels outside the box; elsewhere dimmed gray
    // (the floor: one depth, the nearest, so depthGray 255 halved).
    EXPECT_EQ(img.at(4, 4), zfightHotspotColor(1));
    EXPECT_EQ(img.at(11, 11), zfightHotspotColor(1));
    EXPECT_EQ(img.at(2, 8), zfightHotspotColor(1));    // outline column x = 4 - 2
    EXPECT_EQ(img.at(13, 8), zfightHotspotColor(1));   // outline column x = 11 + 2
    EXPECT_EQ(img.at(40, 20), zfightHotspotColor(2));
    EXPECT_NE(zfightHotspotColor(1), zfightHotspotColor(2));
    const Rgb8 gray = img.at(30, 50);
    EXPECT_EQ(gray.r, gray.g);
    EXPECT_EQ(gray.g, gray.b);
    EXPECT_GT(gray.r, 0);
    // Legend: the first swatch (hotspot #1's color) at the strip's top-left margin.
    EXPECT_EQ(img.at(4, 64 + 4), zfightHotspotColor(1));

    // Written and read back byte for byte.
    const fs::path dir = fs::temp_directory_path() / ("zfight-" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const std::string path = (dir / zfightImageName("view")).string();
    ASSERT_TRUE(writeZFightImage(r, zb.buffer, path, &err)) << err;
    ImageData back;
    ASSERT_TRUE(readImage(path, &back, &err)) << err;
    EXPECT_EQ(back.width, img.width);
    EXPECT_EQ(back.height, img.height);
    EXPECT_EQ(back.u8, img.rgb());
    for (const auto &e : fs::directory_iterator(dir)) EXPECT_EQ(e.path().filename().string(), "view.zfight.png");
    fs::remove_all(dir);
    // A folder that does not exist: an error naming the path, no file.
    const std::string bad = (dir / "missing" / "v.zfight.png").string();
    EXPECT_FALSE(writeZFightImage(r, zb.buffer, bad, &err));
    EXPECT_EQ(err.rfind("cannot write image '" + bad + "': ", 0), 0u) << err;
    // Mismatched buffers are refused.
    const ZBufferResult small = rasterize(tris, 32, 32, zs);
    EXPECT_FALSE(renderZFightImage(r, small.buffer, &img, &err));
    EXPECT_NE(err.find("do not describe the same view"), std::string::npos);
}

// ---- Real data ------------------------------------------------------------------------------------

TEST(ZFightRealData, CastleDungeonOrbitViews) {
    const std::string path = std::string(VISAUDIT_TEST_DATA) + "/castle/level/level-dungeon.gltf";
    if (!fs::exists(path)) GTEST_SKIP() << path << " is absent: run scripts/fetch-data.sh to fetch it";
    Scene scene;
    std::string err;
    ASSERT_TRUE(loadScene(path, {}, &scene, &err)) << err;
    for (ViewSpec v : orbitViews(scene, 4)) {
        v.camera.width = 640;
        v.camera.height = 360;
        Camera cam;
        ASSERT_TRUE(makeCamera(v.camera, &cam, &err)) << err;
        const ZFightResult r = analyzeZFighting(scene, cam, screenTriangles(scene, cam));
        expectConsistent(r);
        std::cout << "[ " << v.name << " ] near " << cam.nearZ << " far " << cam.farZ << ": two surfaces "
                  << r.twoSurfacePixels << ", fighting (any format) " << r.fightingPixelsAnyFormat << " = separated "
                  << r.separatedPixels << " + coplanar " << r.coplanarPixels << " + shared edge " << r.sharedEdgePixels
                  << " + intersection " << r.intersectionPixels << "; hotspots " << r.hotspotCount << "; recommended "
                  << (r.recommended ? depthFormatName(*r.recommended) : std::string("none")) << " (" << r.recommendation
                  << ")\n";
        for (const ZFightFormatStats &s : r.perFormat)
            std::cout << "    " << s.name << ": fighting " << s.fightingPixels << " (coplanar " << s.coplanarPixels
                      << "), hotspots " << s.hotspots << ", edge " << s.sharedEdgePixels << ", intersection "
                      << s.intersectionPixels << ", out of range " << s.outOfRangePixels << "\n";
        for (size_t i = 0; i < std::min<size_t>(r.hotspots.size(), 3); ++i) {
            const ZFightHotspot &h = r.hotspots[i];
            std::cout << "    #" << h.id << " " << h.area << " px at (" << h.centroid.x << ", " << h.centroid.y << ", "
                      << h.centroid.z << ") d " << h.depth << " gap " << h.depthGap << " " << h.objectA << "/"
                      << h.objectB << " tris " << h.triangleA << "/" << h.triangleB << " coplanar " << h.coplanarPixels
                      << " formats " << h.formats.size() << "\n";
        }
    }
}
