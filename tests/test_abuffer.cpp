// The A-buffer (render/abuffer.h): sub-sample coverage against the fragment core, an analytic
// half-covered pixel, transparency compositing, list statistics, and the planner's skip.
// Suite ABuffer*.
#include <gtest/gtest.h>

#include <random>
#include <set>
#include <string>
#include <vector>

#include "analysis/load/demo.h"
#include "analysis/effects_plan.h"
#include "analysis/load/load.h"
#include "analysis/audits/ordering.h"
#include "render/abuffer.h"
#include "render/raster_core.h"

namespace va {
namespace {

// Screen triangles straight in fixed point, one constant-depth plane each (orthographic d = c).
ScreenTriangles screen(const std::vector<std::array<int32_t, 6>> &xy, const std::vector<double> &depth) {
    ScreenTriangles st;
    for (size_t i = 0; i < xy.size(); ++i) {
        st.xy.insert(st.xy.end(), xy[i].begin(), xy[i].end());
        st.source.push_back(uint32_t(i));
        st.plane.push_back(uint32_t(i));
        DepthPlane p;
        p.c = depth[i];
        p.valid = true;
        st.planes.push_back(p);
    }
    return st;
}

struct PixelSet {
    std::set<size_t> pixels;
    bool beginTriangle(size_t, bool) { return true; }
    void fragment(size_t i, size_t, double) { pixels.insert(i); }
    void endTriangle(size_t, uint64_t) {}
};

// The center sample of coverageMasks is the fragment core's coverage, for random triangles of
// every size class (small SIMD blocks, narrow boxes, wide spans), both windings, edges through
// centers (coordinates on the half-pixel grid) and off it.
TEST(ABuffer, CenterSampleEqualsFragmentCore) {
    std::mt19937 rng(11);
    const int W = 64, H = 48;
    for (int iter = 0; iter < 3000; ++iter) {
        const int scale = iter % 3 == 0 ? 4 : (iter % 3 == 1 ? 20 : 90);
        std::uniform_int_distribution<int> U(-scale * 256, (W + scale) * 256);
        std::array<int32_t, 6> v;
        for (int k = 0; k < 6; ++k) v[k] = U(rng);
        if (iter % 2) {  // snap to the half-pixel grid: many centers exactly on edges
            for (int k = 0; k < 6; ++k) v[k] = (v[k] / 128) * 128;
        }
        const int cx = W / 2 * 256, cy = H / 2 * 256;
        if (iter % 5 == 0) {  // a small triangle near the middle
            for (int k = 0; k < 6; k += 2) v[k] = cx + (v[k] % (scale * 256)), v[k + 1] = cy + (v[k + 1] % (scale * 256));
        }
        const ScreenTriangles st = screen({v}, {1.0});
        PixelSet core;
        forEachFragment(st, W, H, true, core);
        std::set<size_t> mine;
        bool front = false;
        coverageMasks(st, 0, W, H, &kCenterSample, 1, &front, [&](size_t p, uint32_t mask) {
            EXPECT_EQ(mask, 1u);
            mine.insert(p);
        });
        ASSERT_EQ(mine, core.pixels) << "iteration " << iter;
    }
}

// A rectangle (two triangles) whose left edge is the vertical line x = 10.5: in pixel 10 the two
// sample columns at 10.125 and 10.375 are outside, those at 10.625 and 10.875 inside: 8 of 16.
// The shared diagonal is never double-covered (the fill rule per sample).
TEST(ABuffer, HalfCoveredPixel) {
    const int32_t x0 = 10 * 256 + 128, x1 = 30 * 256, y0 = 2 * 256, y1 = 20 * 256;
    const ScreenTriangles st = screen({{x0, y0, x1, y0, x1, y1}, {x0, y0, x1, y1, x0, y1}}, {5.0, 5.0});
    const float alpha[2] = {1, 1};
    const uint8_t rgb[6] = {200, 100, 0, 200, 100, 0};
    ABufferMaterials m;
    m.alpha = alpha;
    m.rgb = rgb;
    m.background[0] = m.background[1] = m.background[2] = 0;
    const ABufferResult r = resolveABuffer(st, 40, 24, true, m);
    const size_t p = size_t(10) * 40 + 10;
    EXPECT_EQ(r.rgb[3 * p + 0], 100);  // 200 * 8 / 16
    EXPECT_EQ(r.rgb[3 * p + 1], 50);
    const size_t inner = size_t(10) * 40 + 20;
    EXPECT_EQ(r.rgb[3 * inner], 200);
    // Pixel 10's center (10.5) lies on the left edge: a left edge owns it (top-left rule), so the
    // z-buffer shows the rectangle there while half the sub-samples show background: an edge pixel.
    EXPECT_EQ(r.edge[p], 1);
    EXPECT_EQ(r.edge[inner], 0);
    EXPECT_EQ(r.maxListLength, 2u);  // the diagonal's pixels hold both triangles
}

// Transparency: a half-transparent red square over an opaque blue one, resolved front to back:
// 0.5 red + 0.5 blue; the opaque one in front hides the other completely.
TEST(ABuffer, CompositeFrontToBack) {
    const int32_t a = 2 * 256, b = 12 * 256;
    const ScreenTriangles st = screen({{a, a, b, a, b, b}, {a, a, b, b, a, b}, {a, a, b, a, b, b}, {a, a, b, b, a, b}},
                                      {2.0, 2.0, 4.0, 4.0});
    const float alpha[4] = {0.5f, 0.5f, 1.0f, 1.0f};
    const uint8_t rgb[12] = {255, 0, 0, 255, 0, 0, 0, 0, 255, 0, 0, 255};
    ABufferMaterials m;
    m.alpha = alpha;
    m.rgb = rgb;
    const ABufferResult r = resolveABuffer(st, 16, 16, true, m);
    const size_t p = size_t(6) * 16 + 4;  // inside, off the diagonal
    EXPECT_EQ(r.rgb[3 * p + 0], 128);     // 0.5 * 255 = 127.5 -> 128
    EXPECT_EQ(r.rgb[3 * p + 2], 128);
    EXPECT_EQ(r.listHistogram[2], 100u - 10u);  // 10 x 10 pixels, the diagonal ones hold 4
    EXPECT_EQ(r.listHistogram[4], 10u);
    EXPECT_EQ(r.maxListLength, 4u);
    EXPECT_EQ(r.fragments, 90u * 2 + 10u * 4);
    EXPECT_EQ(r.transparentFragments, 90u + 10u * 2);
    EXPECT_DOUBLE_EQ(r.averageListLength, 220.0 / 100.0);
    EXPECT_EQ(r.memoryBytes, 220 * sizeof(ABufferFragment) + 256 * sizeof(uint32_t));
    // The squares' outer edges lie on pixel boundaries (no partial pixel); the 10 pixels on the
    // shared diagonal hold sub-samples of both triangles of a square (the diagonal runs through
    // their centers and through the samples with i == j): with every triangle its own surface they
    // are edge pixels; with one surface per square they are not.
    EXPECT_EQ(r.edgePixels, 10u);
    const uint32_t surface[4] = {0, 0, 1, 1};
    m.surface = surface;
    EXPECT_EQ(resolveABuffer(st, 16, 16, true, m).edgePixels, 0u);
}

// The planner: the hall has glass (the A-buffer runs), the demo has no transparent material.
TEST(ABuffer, PlannedByTransparency) {
    const Scene demo = demoScene();
    const EffectPlan dp = planEffects(demo, {});
    EXPECT_FALSE(dp.abuffer.run);
    Scene hall;
    std::string err;
    ASSERT_TRUE(loadScene(std::string(VISAUDIT_EXAMPLES) + "/hall.scene.json", {}, &hall, &err)) << err;
    const EffectPlan hp = planEffects(hall, {});
    ASSERT_TRUE(hp.abuffer.run);
    CameraSpec cs = hall.views[0].camera;
    cs.width = 160;
    cs.height = 90;
    Camera cam;
    ASSERT_TRUE(makeCamera(cs, &cam, &err)) << err;
    const OrderingView v = prepareOrderingView(hall, cam);
    const ABufferResult r = abufferForView(v);
    EXPECT_GT(r.fragments, 0u);
    EXPECT_GE(r.maxListLength, 1u);
    uint64_t hist = 0, weighted = 0;
    for (size_t k = 0; k < r.listHistogram.size(); ++k) hist += r.listHistogram[k], weighted += k * r.listHistogram[k];
    EXPECT_EQ(hist, uint64_t(160) * 90);
    EXPECT_EQ(weighted, r.fragments);  // no list reaches the last (clamped) bucket here
    EXPECT_GT(r.edgePixels, 0u);
    const ReferenceVisibility ref = referenceVisibility(hall, cam);
    const BspTree tree = buildBspTree(hall);
    const OrderingResult o = analyzeOrdering(hall, cam, ref, tree, hp.abuffer);
    EXPECT_TRUE(o.abufferRan);
    EXPECT_EQ(o.abuffer.fragments, r.fragments);
    const OrderingResult od = analyzeOrdering(demo, cam, referenceVisibility(demo, cam), buildBspTree(demo), dp.abuffer);
    EXPECT_FALSE(od.abufferRan);
    EXPECT_EQ(od.abufferReason, dp.abuffer.reason);
    EXPECT_FALSE(od.abufferReason.empty());
}

}  // namespace
}  // namespace va
