// Scanline visibility (render/scanline.h): equal to a z-buffer with the reference's tie rule on
// random triangles of every size, single-sided winding, memory of one row. Suite Scanline*.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "render/raster_core.h"
#include "render/scanline.h"

namespace va {
namespace {

// The expectation: every fragment through the core, LESS on the double depth, ties to the lowest id.
struct Nearest {
    const ScreenTriangles &st;
    const uint8_t *single;
    std::vector<uint32_t> id;
    std::vector<double> depth;
    uint32_t cur = 0;
    bool beginTriangle(size_t t, bool front) {
        cur = st.source[t] + 1;
        return !(single && single[st.source[t]] && !front);
    }
    void fragment(size_t i, size_t, double d) {
        if (d < depth[i] || (d == depth[i] && cur < id[i])) depth[i] = d, id[i] = cur;
    }
    void endTriangle(size_t, uint64_t) {}
};

ScreenTriangles randomTriangles(uint32_t seed, int n, int W, int H, bool equalDepths) {
    std::mt19937 rng(seed);
    ScreenTriangles st;
    std::uniform_real_distribution<double> U(0, 1);
    for (int i = 0; i < n; ++i) {
        const double size = i % 3 == 0 ? 3 : (i % 3 == 1 ? 15 : 60);
        const double cx = U(rng) * W, cy = U(rng) * H;
        for (int k = 0; k < 3; ++k) {
            st.xy.push_back(toFixed(cx + (U(rng) - 0.5) * 2 * size));
            st.xy.push_back(toFixed(cy + (U(rng) - 0.5) * 2 * size));
        }
        st.source.push_back(uint32_t(i));
        st.plane.push_back(uint32_t(i));
        // Perspective planes 1/d = a px + b py + c with d in [2, 50]; equalDepths: some share one.
        DepthPlane p;
        p.a = (U(rng) - 0.5) * 1e-3;
        p.b = (U(rng) - 0.5) * 1e-3;
        p.c = equalDepths && i % 4 == 0 ? 0.25 : 0.02 + U(rng) * 0.4;
        if (equalDepths && i % 4 == 0) p.a = p.b = 0;
        p.valid = true;
        st.planes.push_back(p);
    }
    return st;
}

TEST(Scanline, EqualsNearestFragment) {
    for (uint32_t seed = 1; seed <= 8; ++seed) {
        const int W = 200, H = 150;
        const bool orthographic = seed > 6;  // the plane's value is the depth
        const ScreenTriangles st = randomTriangles(seed, 400, W, H, seed % 2 == 0);
        std::vector<uint8_t> single(st.size(), 0);
        for (size_t i = 0; i < single.size(); i += 2) single[i] = 1;
        Nearest ref{st, single.data(), std::vector<uint32_t>(W * H, 0),
                    std::vector<double>(W * H, std::numeric_limits<double>::infinity())};
        forEachFragment(st, W, H, orthographic, ref);
        const ScanlineResult r = scanlineVisibility(st, W, H, orthographic, single.data());
        ASSERT_EQ(r.id, ref.id) << "seed " << seed;
        uint64_t covered = 0;
        for (uint32_t i : ref.id) covered += i != 0;
        EXPECT_EQ(r.coveredPixels, covered);
        EXPECT_GT(r.backWinding, 0u);
        EXPECT_LT(r.memoryBytes, r.zbufferBytes);
        EXPECT_EQ(r.zbufferBytes, uint64_t(W) * H * 12);
        EXPECT_GE(r.writes, r.coveredPixels);
    }
}

// Depths within a few ulps of one another (where the comparison of plane values needs the
// division), equal ones (ties to the lowest id), and plane values beyond 2^1000 (tiny depths, also
// decided by the division): the same ids as the per-fragment expectation. (Not a plane value whose
// reciprocal is +inf: a center inside one span alone takes it without a depth evaluation, where
// the z-buffer's LESS against +inf would not write it; the clip's far plane keeps such depths out.)
TEST(Scanline, EqualsNearestFragmentOnNearTies) {
    for (uint32_t seed = 1; seed <= 4; ++seed) {
        const int W = 120, H = 90;
        ScreenTriangles st = randomTriangles(seed, 300, W, H, false);
        for (size_t i = 0; i < st.planes.size(); ++i) {
            DepthPlane &p = st.planes[i];
            // Every second plane constant at 1 minus 0..15 ulps (the values the rasterizer's
            // expression gives exactly: 0 * px + 0 * py + c = c), whose reciprocals fall on doubles
            // twice as far apart (neighbours share one depth), some of them sloped by a hair.
            if (i % 2 == 0) {
                p.a = p.b = 0;
                p.c = 1 - double(i % 16) * 0x1p-53;
                if (i % 6 == 0) p.a = 0x1p-60;
            }
            if (i % 13 == 0) p.a = p.b = 0, p.c = std::ldexp(1.0, 1001);  // above 2^1000
        }
        Nearest ref{st, nullptr, std::vector<uint32_t>(W * H, 0),
                    std::vector<double>(W * H, std::numeric_limits<double>::infinity())};
        forEachFragment(st, W, H, false, ref);
        const ScanlineResult r = scanlineVisibility(st, W, H, false, nullptr);
        ASSERT_EQ(r.id, ref.id) << "seed " << seed;
        EXPECT_GT(r.depthEvaluations, 0u);
    }
}

// One triangle: one span per covered row, no depth evaluation, every center written once.
TEST(Scanline, SingleTriangleSpans) {
    ScreenTriangles st;
    st.xy = {toFixed(2), toFixed(1), toFixed(18), toFixed(1), toFixed(2), toFixed(17)};
    st.source = {0};
    st.plane = {0};
    DepthPlane p;
    p.c = 3;
    p.valid = true;
    st.planes = {p};
    const ScanlineResult r = scanlineVisibility(st, 20, 20, true, nullptr);
    EXPECT_EQ(r.spans, 15u);           // rows 1..15 (row 16's center 16.5 leaves no room: below)
    EXPECT_EQ(r.depthEvaluations, 0u);
    EXPECT_EQ(r.writes, r.fragments);
    EXPECT_EQ(r.maxActiveTriangles, 1u);
    EXPECT_DOUBLE_EQ(r.overdraw, 1.0);
    // Right triangle with legs of 16 px from (2, 1): row y (center y + 0.5) covers the centers
    // x + 0.5 in [2.5, 18.5 - y) (the left edge x = 2 holds no center; the hypotenuse
    // (x + 0.5 - 2) + (y + 0.5 - 1) < 16 is strict at the centers it passes through: it is not a
    // top-left edge), 16 - y centers for y = 1..15: 15 + 14 + ... + 1 = 120.
    EXPECT_EQ(r.fragments, 120u);
}

// Two copies of one right triangle (legs of 16 px, 120 centers, rows of 1 to 15 centers: the
// four-at-a-time resolve and its tails), every center under both spans: each center's depth is
// evaluated twice, and the second span writes it only when nearer. Exact counts, both projections.
TEST(Scanline, OverlapCountsOfTwoCopies) {
    struct Case {
        double first, second;  // the two copies' depths, in drawing (span) order
        uint64_t writes;
        uint32_t id;           // every covered center's
    };
    const Case cases[] = {
        {4, 2, 240, 2},  // the second nearer: both write
        {2, 4, 120, 1},  // the second farther: written once
        {4, 4, 120, 1},  // a tie: the lowest id stays
    };
    for (const bool orthographic : {false, true})
        for (const Case &c : cases) {
            ScreenTriangles st;
            for (int k = 0; k < 2; ++k) {
                st.xy.insert(st.xy.end(), {toFixed(2), toFixed(1), toFixed(18), toFixed(1), toFixed(2), toFixed(17)});
                st.source.push_back(uint32_t(k));
                st.plane.push_back(uint32_t(k));
                DepthPlane p;
                const double d = k == 0 ? c.first : c.second;
                p.c = orthographic ? d : 1 / d;  // exact: 1/2 and 1/4
                p.valid = true;
                st.planes.push_back(p);
            }
            const ScanlineResult r = scanlineVisibility(st, 20, 20, orthographic, nullptr);
            const std::string what = std::string(orthographic ? "orthographic " : "perspective ") +
                                     std::to_string(c.first) + " then " + std::to_string(c.second);
            EXPECT_EQ(r.fragments, 240u) << what;
            EXPECT_EQ(r.depthEvaluations, 240u) << what;
            EXPECT_EQ(r.writes, c.writes) << what;
            EXPECT_EQ(r.coveredPixels, 120u) << what;
            for (uint32_t id : r.id) ASSERT_TRUE(id == 0 || id == c.id) << what;
        }
}

TEST(Scanline, Empty) {
    const ScanlineResult r = scanlineVisibility(ScreenTriangles{}, 10, 10, false, nullptr);
    EXPECT_EQ(r.coveredPixels, 0u);
    EXPECT_EQ(r.spans, 0u);
    const ScanlineResult z = scanlineVisibility(ScreenTriangles{}, 0, 0, false, nullptr);
    EXPECT_TRUE(z.id.empty());
}

}  // namespace
}  // namespace va
