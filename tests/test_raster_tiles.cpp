// The tiled rasterizer (render/raster_kernel.h, docs/rasterizer.md: Tiles) and the batched walk
// (raster_core.h's walkFragmentsBatched, in bands of rows) against the plain walk: byte-identical
// buffers and identical stats for every tiling, band count, instruction set and thread count.
//
// The plain walk itself is checked against an independent brute force in test_raster.cpp; here it
// is the reference (RasterStrategy::Path::plainWalk). Soups mix every size class the kernel treats
// differently: sub-pixel, small-block, narrow, wide, guard-band sized (whole-tile accept and
// reject), slivers, off-screen, meshes with shared edges, both windings, zero areas.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include <tbb/task_arena.h>

#include "bench/bench_scene.h"
#include "render/clip.h"
#include "render/raster.h"
#include "tests/test_util.h"

namespace va {
namespace {

using Path = RasterStrategy::Path;

// Random triangles of every class, source = 5 * t (so ids and per-source counts are not indices).
ScreenTriangles tileSoup(uint32_t seed, int W, int H, int count, bool ortho) {
    std::mt19937 rng(seed);
    auto uni = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
    ScreenTriangles tris;
    for (int k = 0; k < 16; ++k) {
        const double d0 = std::exp(uni(std::log(0.3), std::log(300.0)));
        const double inv = ortho ? d0 : 1 / d0;
        const double a = uni(-0.3, 0.3) * inv / W, b = uni(-0.3, 0.3) * inv / H;
        tris.planes.push_back({a, b, inv - a * W / 2 - b * H / 2, true});
    }
    tris.planes.push_back({0, 0, 1, false});  // an invalid plane: its triangles draw nothing
    auto add = [&](double x0, double y0, double x1, double y1, double x2, double y2) {
        for (double c : {x0, y0, x1, y1, x2, y2}) tris.xy.push_back(toFixed(c));
        tris.source.push_back(uint32_t(5 * tris.source.size()));
        const uint32_t p = uint32_t(rng() % 64);
        tris.plane.push_back(p == 0 ? 16 : p % 16);
    };
    const double pad = 8192 - 16;  // within the clipper's guard band
    while (int(tris.size()) < count) {
        const int cls = int(rng() % 18);
        const double cx = uni(-20, W + 20), cy = uni(-20, H + 20);
        if (cls == 0) {  // guard-band sized: covers the viewport and beyond
            add(uni(-pad, 0), uni(-pad, 0), uni(W, W + pad), uni(-pad, H), uni(-pad, W + pad), uni(H, H + pad));
        } else if (cls == 1) {  // sliver across the viewport
            const double dx = uni(-1.5, 1.5);
            add(uni(-50, W + 50), -30, uni(-50, W + 50), H + 30, cx + dx, cy);
        } else if (cls == 2) {  // a small mesh: a grid of quads, shared edges, one winding per grid
            const double s = uni(0.3, 12);
            const bool flip = rng() % 2;
            for (int j = 0; j < 3; ++j)
                for (int i = 0; i < 3; ++i) {
                    const double x = cx + i * s, y = cy + j * s;
                    if (flip) {
                        add(x, y, x + s, y, x + s, y + s);
                        add(x, y, x + s, y + s, x, y + s);
                    } else {
                        add(x, y, x + s, y + s, x + s, y);
                        add(x, y, x, y + s, x + s, y + s);
                    }
                }
        } else if (cls == 3) {  // off-screen or zero area
            const bool off = rng() % 2;
            const double ox = off ? -W - 100 : cx;
            add(ox, cy, ox + 5, cy + 3, ox + 10, cy + 6);
        } else if (cls == 16) {  // a corner beyond the rasterizer's range (kMaxFixed), or NaN: skipped
            const double far = rng() % 2 ? uni(2.2e6, 8e6) : std::nan("");
            add(cx, cy, cx + 3, cy + 1, rng() % 2 ? far : -far, cy + 2);
        } else if (cls == 17) {  // long (up to ~80 px) but clamped by the viewport to a box of a few centers
            const double ex = uni(40, 80), ey = uni(0.5, 4);
            const double x = rng() % 2 ? uni(-ex, -ex + 4) : uni(W - 4, W), y = uni(-2, H);
            add(x, y, x + ex, y + uni(-ey, ey), x + uni(0, ex), y + ey);
        } else {  // sizes from sub-pixel to a few tiles
            const double r = cls < 8 ? uni(0.1, 1.5) : cls < 12 ? uni(1.5, 9) : cls < 15 ? uni(9, 70) : uni(70, 400);
            add(cx + uni(-r, r), cy + uni(-r, r), cx + uni(-r, r), cy + uni(-r, r), cx + uni(-r, r), cy + uni(-r, r));
        }
    }
    return tris;
}

void expectIdentical(const ZBufferResult &got, const ZBufferResult &want, const std::string &what) {
    const ZBuffer &g = got.buffer, &w = want.buffer;
    ASSERT_EQ(g.width, w.width) << what;
    ASSERT_EQ(g.height, w.height) << what;
    EXPECT_TRUE(g.key == w.key) << what << ": key";
    EXPECT_TRUE(g.id == w.id) << what << ": id";
    EXPECT_TRUE(g.fragments == w.fragments) << what << ": fragments";
    EXPECT_TRUE(g.passes == w.passes) << what << ": passes";
    ASSERT_EQ(g.depth.size(), w.depth.size()) << what;
    EXPECT_EQ(std::memcmp(g.depth.data(), w.depth.data(), w.depth.size() * sizeof(double)), 0) << what << ": depth";
    const ZBufferStats &a = got.stats, &b = want.stats;
    EXPECT_EQ(a.trianglesIn, b.trianglesIn) << what;
    EXPECT_EQ(a.trianglesDrawn, b.trianglesDrawn) << what;
    EXPECT_EQ(a.trianglesEmpty, b.trianglesEmpty) << what;
    EXPECT_EQ(a.trianglesBackWinding, b.trianglesBackWinding) << what;
    EXPECT_EQ(a.fragments, b.fragments) << what;
    EXPECT_EQ(a.depthPasses, b.depthPasses) << what;
    EXPECT_EQ(a.outOfRangeFragments, b.outOfRangeFragments) << what;
    EXPECT_EQ(a.coveredPixels, b.coveredPixels) << what;
    EXPECT_EQ(a.maxDepthComplexity, b.maxDepthComplexity) << what;
    EXPECT_EQ(a.histogram, b.histogram) << what;
    EXPECT_EQ(std::memcmp(&a.overdraw, &b.overdraw, sizeof(double)), 0) << what;
    EXPECT_EQ(std::memcmp(&a.depthComplexity, &b.depthComplexity, sizeof(double)), 0) << what;
}

ZBufferResult rasterizeOn(int threads, const ScreenTriangles &tris, int W, int H, const ZBufferSettings &s,
                          const RasterStrategy &strategy) {
    tbb::task_arena arena(threads);
    return arena.execute([&] { return rasterize(tris, W, H, s, strategy); });
}

// Every depth format, both projections: tiles of 8, 16 and 128 pixels (8-pixel tiles make most
// triangles span several tiles and the big ones accept whole tiles), AVX2 and baseline kernels,
// 1, 2 and 8 threads; the default strategy too.
TEST(RasterTiles, RandomSoupsAllFormatsMatchPlainWalk) {
    const int W = 203, H = 117;
    uint32_t seed = 11;
    for (DepthFormat f : allDepthFormats())
        for (bool ortho : {false, true}) {
            const ScreenTriangles tris = tileSoup(seed++, W, H, 700, ortho);
            ZBufferSettings s;
            s.encoder = makeDepthEncoder(f, 0.5, 200);
            s.orthographic = ortho;
            const ZBufferResult want = rasterizeOn(1, tris, W, H, s, {Path::plainWalk, true, 0});
            ASSERT_GT(want.stats.fragments, 20000u);
            ASSERT_GT(want.stats.trianglesEmpty, 50u);
            ASSERT_GT(want.stats.depthPasses, want.stats.coveredPixels);  // the test order matters
            const std::string name = std::string(depthFormatInfo(f).name) + (ortho ? " ortho" : " persp");
            for (int shift : {3, 4, 7})
                for (bool avx2 : {true, false})
                    for (int threads : {1, 2, 8})
                        expectIdentical(rasterizeOn(threads, tris, W, H, s, {Path::tiled, avx2, shift}), want,
                                        name + " tiles " + std::to_string(1 << shift) + (avx2 ? " avx2 " : " base ") +
                                            std::to_string(threads) + " threads");
            for (bool avx2 : {true, false})
                expectIdentical(rasterizeOn(1, tris, W, H, s, {Path::batchedWalk, avx2, 0}), want,
                                name + (avx2 ? " batched walk avx2" : " batched walk base"));
            // Bands of rows: one row each, uneven heights, on 1, 2 and 8 threads.
            for (int bands : {2, 7, H})
                for (int threads : {1, 2, 8})
                    expectIdentical(rasterizeOn(threads, tris, W, H, s, {Path::batchedWalk, true, 0, bands}), want,
                                    name + " batched walk, " + std::to_string(bands) + " bands, " +
                                        std::to_string(threads) + " threads");
            for (int threads : {1, 2, 8})
                expectIdentical(rasterizeOn(threads, tris, W, H, s, {}), want,
                                name + " default " + std::to_string(threads) + " threads");
        }
}

// The audits' options: exactDepth, single-sided sources and per-source fragment counts, over a
// soup big enough to be binned in several chunks (tiles in parallel add to shared counters).
TEST(RasterTiles, OptionsMatchPlainWalk) {
    const int W = 256, H = 160;
    const ScreenTriangles tris = tileSoup(7, W, H, 24000, false);
    const size_t sources = 5 * tris.size();
    std::vector<uint8_t> singleSided(sources);
    std::mt19937 rng(3);
    for (uint8_t &v : singleSided) v = uint8_t(rng() % 2);
    for (bool exact : {false, true})
        for (bool oneSided : {false, true}) {
            ZBufferSettings s;
            s.encoder = makeDepthEncoder(DepthFormat::unorm16, 0.5, 200);
            s.exactDepth = exact;
            s.singleSided = oneSided ? singleSided.data() : nullptr;
            std::vector<uint32_t> wantPerSource(sources, 0);
            s.fragmentsPerSource = wantPerSource.data();
            const ZBufferResult want = rasterizeOn(1, tris, W, H, s, {Path::plainWalk, true, 0});
            if (oneSided) {
                EXPECT_GT(want.stats.trianglesBackWinding, 1000u);
            }
            // A strategy on a thread count: the same buffers, stats and per-source counts.
            auto check = [&](const RasterStrategy &strategy, int threads, const std::string &label) {
                std::vector<uint32_t> perSource(sources, 0);
                s.fragmentsPerSource = perSource.data();
                const std::string what = std::string(exact ? "exact" : "keyed") + (oneSided ? " single-sided " : " ") +
                                         label + ", " + std::to_string(threads) + " threads";
                expectIdentical(rasterizeOn(threads, tris, W, H, s, strategy), want, what);
                EXPECT_TRUE(perSource == wantPerSource) << what;
            };
            check({Path::batchedWalk, true, 0}, 1, "batched walk");
            for (int threads : {1, 2, 8}) {
                for (int bands : {3, 16})
                    check({Path::batchedWalk, true, 0, bands}, threads, "batched walk, " + std::to_string(bands) + " bands");
                for (int shift : {4, 7})
                    check({Path::tiled, true, shift}, threads, "tiles " + std::to_string(1 << shift));
            }
        }
}

// Wide spans resolved eight pixels at a time (FragmentBatch::resolveEight) keep the per-pixel
// counters saturating at 65535: 70,000 copies of a triangle over rows of 20 to 40 centers, each copy
// nearer than the last (every fragment passes) or all at one depth (only the first does), keyed and
// exact, against the plain walk.
TEST(RasterTiles, WideSpansSaturateAsThePlainWalk) {
    const int W = 48, H = 6, n = 70000;
    for (bool nearer : {true, false}) {
        ScreenTriangles tris;
        for (int i = 0; i < n; ++i) {
            for (double c : {2.0, 0.0, 46.0, 0.0, 2.0, 6.0}) tris.xy.push_back(toFixed(c));
            tris.source.push_back(uint32_t(3 * i));
            tris.plane.push_back(uint32_t(tris.planes.size()));
            tris.planes.push_back({0.01, 0.02, nearer ? 150.0 - 0.001 * i : 90.0, true});
        }
        for (bool exact : {false, true}) {
            ZBufferSettings s;
            s.encoder = makeDepthEncoder(DepthFormat::f32, 0.5, 200);
            s.orthographic = true;
            s.exactDepth = exact;
            const ZBufferResult want = rasterizeOn(1, tris, W, H, s, {Path::plainWalk, true, 0});
            ASSERT_EQ(want.stats.maxDepthComplexity, 65535u);
            // Exact: every nearer double passes. Keyed: f32 keys of depths 0.001 apart tie at times.
            if (exact || !nearer) EXPECT_EQ(want.buffer.passes[2 * W + 10], nearer ? 65535 : 1);
            else EXPECT_GT(want.buffer.passes[2 * W + 10], 40000);
            const std::string what = std::string(nearer ? "nearer" : "equal") + (exact ? " exact" : " keyed");
            expectIdentical(rasterizeOn(1, tris, W, H, s, {Path::batchedWalk, true, 0}), want, what + " batched walk");
            expectIdentical(rasterizeOn(2, tris, W, H, s, {}), want, what + " default");
        }
    }
}

// The benchmark scene (1,000,002 triangles), its camera and every triangle in order.
struct BenchInput {
    RawMesh mesh = sphereGridMesh();
    Camera cam;
    std::vector<uint32_t> order;
    BenchInput() {
        std::string err;
        EXPECT_TRUE(makeCamera(benchmarkCamera(), &cam, &err)) << err;
        order.resize(mesh.indices.size() / 3);
        for (uint32_t t = 0; t < order.size(); ++t) order[t] = t;
    }
    MeshView view() const { return {mesh.positions.data(), mesh.indices.data()}; }
    ClipBatch first(size_t n) const { return {0, uint32_t(mesh.positions.size()), order.data(), uint32_t(n)}; }
};

// The benchmark scene: the default strategy on 2 threads against the plain walk.
TEST(RasterTiles, BenchSceneMatchesPlainWalk) {
    const BenchInput in;
    const Camera &cam = in.cam;
    const ClipResult clip = clipTriangles(cam, in.view(), {in.first(in.order.size())}, {});
    ZBufferSettings s;
    s.encoder = makeDepthEncoder(DepthFormat::f32, cam.nearZ, cam.farZ);
    const ZBufferResult want = rasterizeOn(1, clip.out, cam.width, cam.height, s, {Path::plainWalk, true, 0});
    EXPECT_EQ(want.stats.trianglesIn, 1000002u);
    expectIdentical(rasterizeOn(2, clip.out, cam.width, cam.height, s, {}), want, "bench scene, default, 2 threads");
    expectIdentical(rasterizeOn(1, clip.out, cam.width, cam.height, s, {}), want, "bench scene, default, 1 thread");
    expectIdentical(rasterizeOn(2, clip.out, cam.width, cam.height, s, {Path::tiled, true, 0}), want,
                    "bench scene, tiled, 2 threads");
}

// Storage given back (recycleZBuffer, recycleScreenTriangles: a finished view's) is what the next
// rasterize() and clipTriangles() fill: the same memory, and the same results as fresh storage,
// also when the previous use was larger (stale contents must not show) or of another size.
TEST(RasterTiles, RecycledStorageGivesTheSameResults) {
    const int W = 203, H = 117;
    ZBufferSettings s;
    s.encoder = makeDepthEncoder(DepthFormat::unorm24, 0.5, 200);
    const ScreenTriangles small = tileSoup(5, W, H, 200, false), large = tileSoup(6, 2 * W, 2 * H, 900, false);
    const ZBufferResult wantSmall = rasterizeOn(1, small, W, H, s, {});
    ZBufferResult big = rasterizeOn(1, large, 2 * W, 2 * H, s, {});
    const uint32_t *idStorage = big.buffer.id.data();
    recycleZBuffer(big.buffer);
    EXPECT_EQ(big.buffer.id.capacity(), 0u);
    EXPECT_EQ(big.buffer.width, 0);
    const ZBufferResult again = rasterizeOn(1, small, W, H, s, {});
    EXPECT_EQ(again.buffer.id.data(), idStorage);
    expectIdentical(again, wantSmall, "recycled z-buffer");

    const BenchInput in;
    const Camera &cam = in.cam;
    const ClipBatch all = in.first(in.order.size()), half = in.first(in.order.size() / 2);
    const MeshView view = in.view();
    const ClipResult wantHalf = clipTriangles(cam, view, {half}, {});
    ClipResult first = clipTriangles(cam, view, {all}, {});
    const int32_t *xyStorage = first.out.xy.data();
    recycleScreenTriangles(first.out);
    EXPECT_EQ(first.out.size(), 0u);
    const ClipResult second = clipTriangles(cam, view, {half}, {});
    EXPECT_EQ(second.out.xy.data(), xyStorage);
    EXPECT_EQ(testing_util::screenTrianglesDifference(second.out, wantHalf.out), "");
}

}  // namespace
}  // namespace va
