// The z-buffer rasterizer (render/raster.h): exact coverage, fill rule, depth and counts.
//
// The reference used throughout is written independently of the rasterizer: no winding swap, no
// bias, no bounding box, no stepping and no span solving. It evaluates each edge function at each
// pixel center in int64 and resolves a center lying exactly on an edge by *symbolic perturbation*:
// the sample is moved to (x + eps, y + eps^2) for an infinitesimal eps > 0, so an edge's sign is the
// lexicographic sign of (E, -dy, dx) (the first order terms of E(p + (eps, eps^2))). A perturbed
// point never lies on a (non-degenerate) edge, so it is inside a triangle exactly when all three
// signs agree, for either winding. This is the top-left rule seen from another side: a center on a
// left edge (-dy > 0) or a top edge (dy == 0, dx > 0) is nudged into the triangle.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "bench/bench_scene.h"
#include "render/clip.h"
#include "render/depth_format.h"
#include "render/raster.h"
#include "render/raster_core.h"

namespace va {
namespace {

constexpr int32_t kOne = kSubpixelOne;
constexpr int32_t kHalfPx = kSubpixelOne / 2;

// Lexicographic sign of (E, -dy, dx) for the edge a -> b at p (see the file comment).
int perturbedSign(int64_t ax, int64_t ay, int64_t bx, int64_t by, int64_t px, int64_t py) {
    const int64_t dx = bx - ax, dy = by - ay;
    const int64_t e = dx * (py - ay) - dy * (px - ax);
    if (e != 0) return e > 0 ? 1 : -1;
    if (dy != 0) return -dy > 0 ? 1 : -1;
    return dx > 0 ? 1 : (dx < 0 ? -1 : 0);
}

bool refCovers(const int32_t *v, int px, int py) {
    const int64_t sx = int64_t(px) * kOne + kHalfPx, sy = int64_t(py) * kOne + kHalfPx;
    const int64_t area = int64_t(v[2] - v[0]) * (v[5] - v[1]) - int64_t(v[3] - v[1]) * (v[4] - v[0]);
    if (area == 0) return false;
    const int s0 = perturbedSign(v[0], v[1], v[2], v[3], sx, sy);
    const int s1 = perturbedSign(v[2], v[3], v[4], v[5], sx, sy);
    const int s2 = perturbedSign(v[4], v[5], v[0], v[1], sx, sy);
    return s0 == s1 && s1 == s2;
}

// Crossing-number point-in-polygon for the perturbed center: a horizontal ray towards +x crosses
// the edge a -> b when the edge straddles y + eps^2 (a.y > y <=> a.y > y + eps^2 for integers) and
// the perturbed point lies on the edge's left (upward edge: E > 0; downward edge: E < 0).
bool refInsidePolygon(const std::vector<int64_t> &poly, int px, int py) {
    const int64_t sx = int64_t(px) * kOne + kHalfPx, sy = int64_t(py) * kOne + kHalfPx;
    const size_t n = poly.size() / 2;
    bool inside = false;
    for (size_t i = 0; i < n; ++i) {
        const int64_t ax = poly[2 * i], ay = poly[2 * i + 1];
        const int64_t bx = poly[2 * ((i + 1) % n)], by = poly[2 * ((i + 1) % n) + 1];
        if ((ay > sy) == (by > sy)) continue;
        const int s = perturbedSign(ax, ay, bx, by, sx, sy);
        if (by > ay ? s > 0 : s < 0) inside = !inside;
    }
    return inside;
}

struct Builder {
    ScreenTriangles tris;
    uint32_t addPlane(double a, double b, double c) {
        tris.planes.push_back({a, b, c, true});
        return uint32_t(tris.planes.size() - 1);
    }
    void add(int64_t x0, int64_t y0, int64_t x1, int64_t y1, int64_t x2, int64_t y2, uint32_t plane,
             uint32_t source = ~0u) {
        for (int64_t c : {x0, y0, x1, y1, x2, y2}) tris.xy.push_back(int32_t(c));
        tris.source.push_back(source == ~0u ? uint32_t(tris.source.size()) : source);
        tris.plane.push_back(plane);
    }
};

ZBufferSettings settingsFor(DepthFormat f, bool ortho, double n = 0.5, double fa = 200) {
    ZBufferSettings s;
    s.encoder = makeDepthEncoder(f, n, fa);
    s.orthographic = ortho;
    return s;
}

// The reference z-buffer: every triangle at every pixel center, in submission order.
ZBufferResult referenceRasterize(const ScreenTriangles &tris, int W, int H, const ZBufferSettings &s) {
    ZBufferResult r;
    ZBuffer &b = r.buffer;
    b.width = W;
    b.height = H;
    const size_t np = size_t(W) * H;
    b.key.assign(np, 0xFFFFFFFFu);
    b.id.assign(np, 0);
    b.depth.assign(np, INFINITY);
    b.fragments.assign(np, 0);
    b.passes.assign(np, 0);
    Camera cam;
    cam.orthographic = s.orthographic;
    r.stats.trianglesIn = tris.size();
    for (size_t t = 0; t < tris.size(); ++t) {
        const DepthPlane &p = tris.planes[tris.plane[t]];
        uint64_t count = 0;
        for (int y = 0; y < H && p.valid; ++y)
            for (int x = 0; x < W; ++x) {
                if (!refCovers(&tris.xy[6 * t], x, y)) continue;
                const size_t i = size_t(y) * W + x;
                const double d = viewDepthAt(cam, p, x + 0.5, y + 0.5);
                bool oor = false;
                const uint32_t k = depthKey(s.encoder, d, &oor);
                ++count;
                ++b.fragments[i];
                r.stats.outOfRangeFragments += oor;
                if (k < b.key[i]) {
                    b.key[i] = k;
                    b.id[i] = tris.source[t] + 1;
                    b.depth[i] = d;
                    ++b.passes[i];
                    ++r.stats.depthPasses;
                }
            }
        r.stats.fragments += count;
        if (count) ++r.stats.trianglesDrawn;
        else ++r.stats.trianglesEmpty;
    }
    finishZBufferStats(b, &r.stats);
    return r;
}

// Compares every buffer bit for bit; reports the first differing pixel.
void expectSameBuffers(const ZBufferResult &got, const ZBufferResult &want, const std::string &what) {
    const ZBuffer &g = got.buffer, &w = want.buffer;
    ASSERT_EQ(g.width, w.width);
    ASSERT_EQ(g.height, w.height);
    for (size_t i = 0; i < w.key.size(); ++i) {
        const int x = int(i % w.width), y = int(i / w.width);
        ASSERT_EQ(g.fragments[i], w.fragments[i]) << what << " fragments at pixel (" << x << ", " << y << ")";
        ASSERT_EQ(g.passes[i], w.passes[i]) << what << " passes at pixel (" << x << ", " << y << ")";
        ASSERT_EQ(g.id[i], w.id[i]) << what << " id at pixel (" << x << ", " << y << ")";
        ASSERT_EQ(g.key[i], w.key[i]) << what << " key at pixel (" << x << ", " << y << ")";
        ASSERT_EQ(std::memcmp(&g.depth[i], &w.depth[i], sizeof(double)), 0)
            << what << " depth at pixel (" << x << ", " << y << "): " << g.depth[i] << " vs " << w.depth[i];
    }
    const ZBufferStats &a = got.stats, &b = want.stats;
    EXPECT_EQ(a.trianglesIn, b.trianglesIn) << what;
    EXPECT_EQ(a.trianglesDrawn, b.trianglesDrawn) << what;
    EXPECT_EQ(a.trianglesEmpty, b.trianglesEmpty) << what;
    EXPECT_EQ(a.fragments, b.fragments) << what;
    EXPECT_EQ(a.depthPasses, b.depthPasses) << what;
    EXPECT_EQ(a.outOfRangeFragments, b.outOfRangeFragments) << what;
    EXPECT_EQ(a.coveredPixels, b.coveredPixels) << what;
    EXPECT_EQ(a.histogram, b.histogram) << what;
    EXPECT_EQ(a.maxDepthComplexity, b.maxDepthComplexity) << what;
}

// Number of pixel centers c = k*one + half with lo <= c < hi (the top-left rule on an axis-aligned
// rectangle [lo, hi): left/top edges included, right/bottom excluded), clamped to [0, size).
int64_t centersInHalfOpen(int64_t lo, int64_t hi, int64_t size) {
    int64_t n = 0;
    for (int64_t k = 0; k < size; ++k) {
        const int64_t c = k * kOne + kHalfPx;
        n += (lo <= c && c < hi);
    }
    return n;
}

TEST(RasterFixed, ToFixedRoundsHalfToEven) {
    EXPECT_EQ(toFixed(0), 0);
    EXPECT_EQ(toFixed(1), 256);
    EXPECT_EQ(toFixed(-3.5), -896);
    EXPECT_EQ(toFixed(1.5 / 256), 2);   // 1.5 units -> 2 (even)
    EXPECT_EQ(toFixed(2.5 / 256), 2);   // 2.5 units -> 2 (even)
    EXPECT_EQ(toFixed(-2.5 / 256), -2);
    EXPECT_EQ(toFixed(0.6 / 256), 1);
    EXPECT_EQ(toFixed(1e12), 2147483647);
    EXPECT_EQ(toFixed(-1e12), -2147483647 - 1);
    EXPECT_EQ(toFixed(NAN), -2147483647 - 1);
    EXPECT_EQ(toFixed(INFINITY), 2147483647);
    EXPECT_EQ(toFixed(-INFINITY), -2147483647 - 1);
    // The inline rounding against nearbyint (round half to even in the default mode): random
    // pixel coordinates over the clipper's range, and every tie of a few thousand units.
    uint64_t state = 3;
    auto reference = [](double p) {
        const double s = std::nearbyint(p * kSubpixelOne);
        if (!(s > -2147483648.0)) return int32_t(INT32_MIN);
        if (s > 2147483647.0) return int32_t(INT32_MAX);
        return int32_t(s);
    };
    for (int i = 0; i < 200000; ++i) {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        const double p = (double(state >> 11) * 0x1p-53 - 0.5) * std::ldexp(1.0, int(state % 40));
        ASSERT_EQ(toFixed(p), reference(p)) << p;
    }
    for (int u = -5000; u <= 5000; ++u) {
        const double tie = (u + 0.5) / kSubpixelOne;
        ASSERT_EQ(toFixed(tie), reference(tie)) << tie;
        ASSERT_EQ(toFixed(std::nextafter(tie, 1e9)), reference(std::nextafter(tie, 1e9)));
        ASSERT_EQ(toFixed(std::nextafter(tie, -1e9)), reference(std::nextafter(tie, -1e9)));
    }
}

// (a) Two triangles forming a quad: both diagonals, every winding of each half and every rotation
// of the vertex order. Every pixel is covered exactly once inside and never outside.
TEST(RasterCoverage, QuadAllSplitsAndWindings) {
    const int W = 24, H = 20;
    // Rectangles in fixed point: edges on pixel edges, on pixel centers, and in between.
    const int64_t rects[][4] = {
        {2 * kOne, 3 * kOne, 10 * kOne, 9 * kOne},                                  // pixel edges
        {2 * kOne + kHalfPx, 3 * kOne + kHalfPx, 10 * kOne + kHalfPx, 9 * kOne + kHalfPx},  // centers
        {517, 300, 4001, 2999},                                                     // arbitrary
        {-5 * kOne, -7 * kOne + 1, 30 * kOne - 1, 12 * kOne + kHalfPx},             // past the viewport
        {kHalfPx, kHalfPx, kHalfPx + kOne, kHalfPx + kOne},                         // one pixel
    };
    for (const auto &r : rects) {
        const int64_t x0 = r[0], y0 = r[1], x1 = r[2], y1 = r[3];
        const int64_t expected = centersInHalfOpen(x0, x1, W) * centersInHalfOpen(y0, y1, H);
        const int64_t corners[4][2] = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
        for (int diag = 0; diag < 2; ++diag)
            for (int wind = 0; wind < 4; ++wind)
                for (int rot = 0; rot < 3; ++rot) {
                    // Halves: (c0, c1, c2) and (c0, c2, c3) or, for the other diagonal, starting at c1.
                    const int64_t *q[4] = {corners[diag], corners[diag + 1], corners[diag + 2],
                                           corners[(diag + 3) % 4]};
                    const int64_t *t1[3] = {q[0], q[1], q[2]}, *t2[3] = {q[0], q[2], q[3]};
                    if (wind & 1) std::swap(t1[1], t1[2]);
                    if (wind & 2) std::swap(t2[1], t2[2]);
                    std::rotate(t1, t1 + rot, t1 + 3);
                    std::rotate(t2, t2 + (2 - rot), t2 + 3);
                    Builder b;
                    const uint32_t p = b.addPlane(0, 0, 0.1);
                    b.add(t1[0][0], t1[0][1], t1[1][0], t1[1][1], t1[2][0], t1[2][1], p);
                    b.add(t2[0][0], t2[0][1], t2[1][0], t2[1][1], t2[2][0], t2[2][1], p);
                    const ZBufferResult z = rasterize(b.tris, W, H, settingsFor(DepthFormat::f32, false));
                    for (int y = 0; y < H; ++y)
                        for (int x = 0; x < W; ++x) {
                            const int64_t cx = int64_t(x) * kOne + kHalfPx, cy = int64_t(y) * kOne + kHalfPx;
                            const bool in = x0 <= cx && cx < x1 && y0 <= cy && cy < y1;
                            ASSERT_EQ(z.buffer.fragments[size_t(y) * W + x], in ? 1 : 0)
                                << "rect " << x0 << "," << y0 << "," << x1 << "," << y1 << " diag " << diag
                                << " wind " << wind << " rot " << rot << " pixel " << x << "," << y;
                        }
                    EXPECT_EQ(int64_t(z.stats.fragments), expected);
                    EXPECT_EQ(int64_t(z.stats.coveredPixels), expected);
                    EXPECT_EQ(int64_t(z.stats.depthPasses), expected);
                }
    }
    // A literal case: centers (1.5 .. 4.5) x (2.5, 3.5) inside [1.5, 5.5) x [2.5, 4.5): 4 x 2 pixels.
    EXPECT_EQ(centersInHalfOpen(kOne + kHalfPx, 5 * kOne + kHalfPx, 24) *
                  centersInHalfOpen(2 * kOne + kHalfPx, 4 * kOne + kHalfPx, 20),
              8);
}

// Random fixed-point coordinate generator over wide magnitudes, snapping some values to pixel
// centers and pixel edges (multiples of half a pixel in fixed point).
struct CoordGen {
    std::mt19937 rng;
    explicit CoordGen(uint32_t seed) : rng(seed) {}
    double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }
    int pick(int n) { return std::uniform_int_distribution<int>(0, n - 1)(rng); }
    int64_t snap(double fixedValue) {
        switch (pick(3)) {
        case 0: return int64_t(std::floor(fixedValue / kHalfPx)) * kHalfPx;  // a pixel edge or center
        default: return int64_t(std::llround(fixedValue));
        }
    }
    // A length in fixed point, log-uniform from 1/16 pixel to `maxPixels`.
    double length(double maxPixels) { return kOne * std::exp(uniform(std::log(1.0 / 16), std::log(maxPixels))); }
};

// (b) Closed fans: triangles (center, v_i, v_{i+1}) around a star-shaped polygon, each with a
// random winding. Every pixel inside the outline is covered exactly once and none outside.
TEST(RasterCoverage, RandomFansNoCracksNoDoubleCoverage) {
    const int W = 48, H = 40;
    CoordGen g(20261122);
    int fansTested = 0;
    for (int iter = 0; iter < 1000; ++iter) {
        const int K = 3 + g.pick(30);
        const double radius = g.length(iter % 4 == 0 ? 9000 : 60);
        const int64_t cx = g.snap(g.uniform(-8, W + 8) * kOne), cy = g.snap(g.uniform(-8, H + 8) * kOne);
        std::vector<double> angles(K);
        for (double &a : angles) a = g.uniform(0, 2 * kPi);
        std::sort(angles.begin(), angles.end());
        std::vector<int64_t> ring;
        for (double a : angles) {
            const double r = radius * g.uniform(0.3, 1.0);
            ring.push_back(g.snap(double(cx) + r * std::cos(a)));
            ring.push_back(g.snap(double(cy) + r * std::sin(a)));
        }
        // Valid fan: every triangle (c, v_i, v_{i+1}) strictly positively oriented (angles sorted,
        // after snapping) and the turns summing to one full turn; otherwise draw another.
        bool ok = true;
        double turn = 0;
        for (int i = 0; i < K && ok; ++i) {
            const int j = (i + 1) % K;
            const int64_t ax = ring[2 * i] - cx, ay = ring[2 * i + 1] - cy, bx = ring[2 * j] - cx,
                          by = ring[2 * j + 1] - cy;
            ok = ax * by - ay * bx > 0;
            turn += std::atan2(double(ax * by - ay * bx), double(ax * bx + ay * by));
        }
        if (!ok || std::fabs(turn - 2 * kPi) > 1e-6) continue;
        ++fansTested;
        Builder b;
        const uint32_t p = b.addPlane(0, 0, 0.2);
        for (int i = 0; i < K; ++i) {
            const int j = (i + 1) % K;
            if (g.pick(2)) b.add(cx, cy, ring[2 * i], ring[2 * i + 1], ring[2 * j], ring[2 * j + 1], p);
            else b.add(ring[2 * j], ring[2 * j + 1], ring[2 * i], ring[2 * i + 1], cx, cy, p);
        }
        const ZBufferResult z = rasterize(b.tris, W, H, settingsFor(DepthFormat::f32, false));
        uint64_t inside = 0;
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                const bool in = refInsidePolygon(ring, x, y);
                inside += in;
                ASSERT_EQ(z.buffer.fragments[size_t(y) * W + x], in ? 1 : 0)
                    << "fan " << iter << " K " << K << " pixel " << x << "," << y;
            }
        EXPECT_EQ(z.stats.fragments, inside);
        EXPECT_EQ(z.stats.coveredPixels, inside);
    }
    EXPECT_GT(fansTested, 300);  // about a third of random angle sets leave a gap >= pi
}

// (b) Jittered grids: each cell split along a random diagonal, each triangle with a random winding.
TEST(RasterCoverage, RandomGridsNoCracksNoDoubleCoverage) {
    const int W = 48, H = 40;
    CoordGen g(7);
    for (int iter = 0; iter < 300; ++iter) {
        const int nx = 2 + g.pick(9), ny = 2 + g.pick(9);
        // Cell size from 1/16 pixel to tens of pixels (or thousands, reaching into the guard band);
        // jitter below a fifth of the cell keeps every cell convex, so both splits are valid.
        const double cell = g.length(iter % 5 == 0 ? 2000 : 12);
        const double ox = g.uniform(-0.5, 0.8) * W * kOne, oy = g.uniform(-0.5, 0.8) * H * kOne;
        const bool snapOnly = g.pick(3) == 0;  // whole grid on pixel centers / edges
        std::vector<int64_t> vx((nx + 1) * (ny + 1)), vy((nx + 1) * (ny + 1));
        for (int j = 0; j <= ny; ++j)
            for (int i = 0; i <= nx; ++i) {
                const double jx = g.uniform(-0.2, 0.2) * cell, jy = g.uniform(-0.2, 0.2) * cell;
                double px = ox + i * cell + jx, py = oy + j * cell + jy;
                const int v = j * (nx + 1) + i;
                if (snapOnly) {
                    vx[v] = int64_t(std::floor(px / kHalfPx)) * kHalfPx;
                    vy[v] = int64_t(std::floor(py / kHalfPx)) * kHalfPx;
                } else {
                    vx[v] = g.snap(px);
                    vy[v] = g.snap(py);
                }
            }
        // Snapping can fold a tiny cell; keep grids whose every cell is still strictly convex
        // (counter-clockwise in the y-down frame is a negative cross product here).
        auto V = [&](int i, int j) { return j * (nx + 1) + i; };
        bool ok = true;
        for (int j = 0; j < ny && ok; ++j)
            for (int i = 0; i < nx && ok; ++i) {
                const int q[4] = {V(i, j), V(i + 1, j), V(i + 1, j + 1), V(i, j + 1)};
                for (int k = 0; k < 4 && ok; ++k) {
                    const int a = q[k], b2 = q[(k + 1) % 4], c = q[(k + 2) % 4];
                    ok = (vx[b2] - vx[a]) * (vy[c] - vy[b2]) - (vy[b2] - vy[a]) * (vx[c] - vx[b2]) > 0;
                }
            }
        if (!ok) continue;
        Builder b;
        const uint32_t p = b.addPlane(0, 0, 0.2);
        auto emit = [&](int a, int b1, int c) {
            if (g.pick(2)) b.add(vx[a], vy[a], vx[b1], vy[b1], vx[c], vy[c], p);
            else b.add(vx[c], vy[c], vx[b1], vy[b1], vx[a], vy[a], p);
        };
        for (int j = 0; j < ny; ++j)
            for (int i = 0; i < nx; ++i) {
                if (g.pick(2)) {
                    emit(V(i, j), V(i + 1, j), V(i + 1, j + 1));
                    emit(V(i, j), V(i + 1, j + 1), V(i, j + 1));
                } else {
                    emit(V(i, j), V(i + 1, j), V(i, j + 1));
                    emit(V(i + 1, j), V(i + 1, j + 1), V(i, j + 1));
                }
            }
        // The outline: along the top row, down the right column, back the bottom row, up the left.
        std::vector<int64_t> outline;
        auto push = [&](int v) { outline.push_back(vx[v]); outline.push_back(vy[v]); };
        for (int i = 0; i < nx; ++i) push(V(i, 0));
        for (int j = 0; j < ny; ++j) push(V(nx, j));
        for (int i = nx; i > 0; --i) push(V(i, ny));
        for (int j = ny; j > 0; --j) push(V(0, j));
        const ZBufferResult z = rasterize(b.tris, W, H, settingsFor(DepthFormat::f32, false));
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x)
                ASSERT_EQ(z.buffer.fragments[size_t(y) * W + x], refInsidePolygon(outline, x, y) ? 1 : 0)
                    << "grid " << iter << " (" << nx << "x" << ny << ", cell " << cell / kOne << " px) pixel " << x
                    << "," << y;
    }
}

// A random soup over wide magnitudes with vertices on centers and edges, some degenerate
// triangles, planes shared between triangles (depth ties) and depths partly outside [near, far].
ScreenTriangles randomSoup(uint32_t seed, int W, int H, int count, bool ortho) {
    CoordGen g(seed);
    Builder b;
    // Plane pool: depth d0 at the viewport center, gentle slopes; a few constant planes shared.
    std::vector<uint32_t> pool;
    for (int k = 0; k < 12; ++k) {
        const double d0 = std::exp(g.uniform(std::log(0.3), std::log(300.0)));
        const double slope = k < 4 ? 0 : g.uniform(-0.3, 0.3);
        if (ortho) {
            const double a = slope * d0 / W, bb = g.uniform(-0.3, 0.3) * d0 / H * (k >= 4);
            pool.push_back(b.addPlane(a, bb, d0 - a * W / 2 - bb * H / 2));
        } else {
            const double inv = 1 / d0, a = slope * inv / W, bb = g.uniform(-0.3, 0.3) * inv / H * (k >= 4);
            pool.push_back(b.addPlane(a, bb, inv - a * W / 2 - bb * H / 2));
        }
    }
    for (int t = 0; t < count; ++t) {
        const double maxPx = (t % 10 == 0) ? 9000 : (t % 3 == 0 ? 40 : 3);
        const double cx = g.uniform(-4, W + 4) * kOne, cy = g.uniform(-4, H + 4) * kOne;
        int64_t v[6];
        for (int i = 0; i < 3; ++i) {
            v[2 * i] = g.snap(cx + g.uniform(-1, 1) * g.length(maxPx));
            v[2 * i + 1] = g.snap(cy + g.uniform(-1, 1) * g.length(maxPx));
        }
        if (t % 17 == 5) {  // collinear: v2 = v0 + 2 (v1 - v0)
            v[4] = v[0] + 2 * (v[2] - v[0]);
            v[5] = v[1] + 2 * (v[3] - v[1]);
        }
        if (t % 19 == 7) { v[4] = v[2]; v[5] = v[3]; }  // repeated vertex
        const uint32_t plane = t % 7 == 3 ? pool[g.pick(4)] : pool[g.pick(int(pool.size()))];
        b.add(v[0], v[1], v[2], v[3], v[4], v[5], plane, uint32_t(1000 + 3 * t));
    }
    // One more plane that is not valid: its triangle is skipped.
    b.tris.planes.push_back({0, 0, 1, false});
    b.add(0, 0, W * kOne, 0, 0, H * kOne, uint32_t(b.tris.planes.size() - 1), 7);
    return b.tris;
}

// (c) Brute force: every format, both projections, random soups; every buffer bit-exact.
TEST(RasterReference, RandomSoupsMatchBruteForceAllFormats) {
    const int W = 53, H = 37;
    uint32_t seed = 1;
    for (DepthFormat f : allDepthFormats())
        for (bool ortho : {false, true}) {
            const ScreenTriangles tris = randomSoup(seed++, W, H, 160, ortho);
            const ZBufferSettings s = settingsFor(f, ortho);
            const ZBufferResult got = rasterize(tris, W, H, s);
            const ZBufferResult want = referenceRasterize(tris, W, H, s);
            const std::string what = std::string(depthFormatInfo(f).name) + (ortho ? " ortho" : " persp");
            expectSameBuffers(got, want, what);
            EXPECT_GT(want.stats.fragments, 1000u) << what;  // the soup covers something
            EXPECT_GT(want.stats.trianglesEmpty, 10u) << what;   // and has empty triangles
        }
}

// (c) Many seeds with the two most common formats, a wider viewport.
TEST(RasterReference, ManySeedsMatchBruteForce) {
    const int W = 96, H = 64;
    for (uint32_t seed = 100; seed < 124; ++seed) {
        const bool ortho = seed % 2;
        const ScreenTriangles tris = randomSoup(seed, W, H, 300, ortho);
        const DepthFormat f = seed % 3 == 0 ? DepthFormat::unorm16 : DepthFormat::f32;
        const ZBufferSettings s = settingsFor(f, ortho);
        expectSameBuffers(rasterize(tris, W, H, s), referenceRasterize(tris, W, H, s),
                          "seed " + std::to_string(seed));
    }
}

// (d) Vertices exactly on pixel centers: the fill rule decides, literally.
TEST(RasterFillRule, VerticesOnPixelCenters) {
    const int W = 8, H = 8;
    // Right triangle with its legs through pixel centers: (1.5,1.5) (5.5,1.5) (1.5,5.5).
    // Top edge y = 1.5 included, left edge x = 1.5 included, hypotenuse x + y = 7 excluded.
    const int64_t c = kHalfPx;
    Builder b;
    const uint32_t p = b.addPlane(0, 0, 0.5);
    b.add(1 * kOne + c, 1 * kOne + c, 5 * kOne + c, 1 * kOne + c, 1 * kOne + c, 5 * kOne + c, p);
    const ZBufferResult z = rasterize(b.tris, W, H, settingsFor(DepthFormat::f32, false));
    int covered = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const bool want = x >= 1 && y >= 1 && (x + y) < 6;  // centers with (x+.5)+(y+.5) < 7
            EXPECT_EQ(z.buffer.fragments[y * W + x], want ? 1 : 0) << x << "," << y;
            covered += want;
        }
    EXPECT_EQ(covered, 10);  // 4 + 3 + 2 + 1
    EXPECT_EQ(z.stats.fragments, 10u);
    // The mirrored triangle (sharing the hypotenuse) takes exactly the hypotenuse's centers.
    Builder m;
    const uint32_t q = m.addPlane(0, 0, 0.5);
    m.add(5 * kOne + c, 1 * kOne + c, 5 * kOne + c, 5 * kOne + c, 1 * kOne + c, 5 * kOne + c, q);
    const ZBufferResult zm = rasterize(m.tris, W, H, settingsFor(DepthFormat::f32, false));
    // Centers with x+y >= 6 (hypotenuse included: it is this triangle's top-left edge), x <= 4 (the
    // right edge x = 5.5 excluded), y <= 4 (the bottom edge y = 5.5 excluded): 5 + 4 + 3 + 2 + 1 = 15 ... of
    // which only those with x >= 1, y >= 1 lie in the square: 1 + 2 + 3 + 4 = 10? count directly.
    int mirrored = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const bool want = x <= 4 && y <= 4 && x + y >= 6;
            EXPECT_EQ(zm.buffer.fragments[y * W + x], want ? 1 : 0) << x << "," << y;
            mirrored += want;
        }
    EXPECT_EQ(mirrored, 6);  // (2,4) (3,3) (3,4) (4,2) (4,3) (4,4)
    // Together: the square [1.5, 5.5)^2 holds 4 x 4 = 16 centers, each exactly once.
    EXPECT_EQ(covered + mirrored, 16);
}

// (d) Vertices on pixel edges: a triangle whose edges pass between centers covers the obvious set.
TEST(RasterFillRule, VerticesOnPixelEdgesAndSubpixel) {
    const int W = 8, H = 8;
    Builder b;
    const uint32_t p = b.addPlane(0, 0, 0.5);
    // Horizontal top edge at y = 2 (a pixel edge), bottom vertex at (4, 6); centers strictly inside.
    b.add(2 * kOne, 2 * kOne, 6 * kOne, 2 * kOne, 4 * kOne, 6 * kOne, p);
    // A triangle entirely between centers (within pixel (0, 6)'s lower right quarter): covers nothing.
    b.add(kHalfPx + 1, 6 * kOne + kHalfPx + 1, kOne - 1, 6 * kOne + kHalfPx + 1, kOne - 1, 7 * kOne - 1, p);
    const ZBufferResult z = rasterize(b.tris, W, H, settingsFor(DepthFormat::f32, false));
    // Row y (center y+.5 in [2, 6)): half width at that height = 2 * (6 - (y+.5)) / 4.
    int n = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const double cy = y + 0.5, cx = x + 0.5, hw = (6 - cy) / 2;
            const bool want = cy >= 2 && cy < 6 && std::fabs(cx - 4) < hw;  // no center on the slanted edges
            EXPECT_EQ(z.buffer.fragments[y * W + x], want ? 1 : 0) << x << "," << y;
            n += want;
        }
    EXPECT_EQ(n, 4 + 2 + 2);  // rows 2.5: |cx-4|<1.75 -> 2.5..5.5 = 4; 3.5: <1.25 -> 2; 4.5: <0.75 -> 2; 5.5: <.25 -> 0
    EXPECT_EQ(z.stats.trianglesDrawn, 1u);
    EXPECT_EQ(z.stats.trianglesEmpty, 1u);
}

// (d) Zero-area triangles (after snapping) draw nothing and are counted as empty.
TEST(RasterFillRule, ZeroAreaDrawsNothing) {
    const int W = 16, H = 16;
    Builder b;
    const uint32_t p = b.addPlane(0, 0, 0.5);
    b.add(kHalfPx, kHalfPx, 10 * kOne + kHalfPx, 10 * kOne + kHalfPx, 5 * kOne + kHalfPx, 5 * kOne + kHalfPx, p);  // through centers
    b.add(0, 3 * kOne + kHalfPx, 16 * kOne, 3 * kOne + kHalfPx, 8 * kOne, 3 * kOne + kHalfPx, p);  // horizontal, on a row of centers
    b.add(5 * kOne, 5 * kOne, 5 * kOne, 5 * kOne, 9 * kOne, 9 * kOne, p);  // repeated vertex
    b.add(7 * kOne, 7 * kOne, 7 * kOne, 7 * kOne, 7 * kOne, 7 * kOne, p);  // a point
    // Distinct doubles that snap to the same fixed point collapse to zero area.
    b.add(toFixed(2.0), toFixed(2.0), toFixed(9.0), toFixed(2.0), toFixed(5.0), toFixed(2.0 + 1e-4), p);
    const ZBufferResult z = rasterize(b.tris, W, H, settingsFor(DepthFormat::f32, false));
    EXPECT_EQ(z.stats.fragments, 0u);
    EXPECT_EQ(z.stats.trianglesEmpty, 5u);
    EXPECT_EQ(z.stats.trianglesDrawn, 0u);
    EXPECT_EQ(z.stats.coveredPixels, 0u);
    ASSERT_EQ(z.stats.histogram.size(), 1u);
    EXPECT_EQ(z.stats.histogram[0], uint64_t(W * H));
    EXPECT_EQ(z.stats.overdraw, 0.0);
    EXPECT_EQ(z.stats.depthComplexity, 0.0);
}

// (d) Guard band: vertices 8192 pixels outside the viewport on every side.
TEST(RasterFillRule, GuardBandCoordinates) {
    const int W = 64, H = 48;
    const int64_t g = 8192 * int64_t(kOne);
    const int64_t L = -g, T = -g, R = W * int64_t(kOne) + g, B = H * int64_t(kOne) + g;
    for (int split = 0; split < 2; ++split) {
        Builder b;
        const uint32_t p = b.addPlane(1e-6, -2e-6, 0.1);
        if (split == 0) {
            b.add(L, T, R, T, R, B, p);
            b.add(L, T, L, B, R, B, p);  // other winding
        } else {
            b.add(R, T, L, B, L, T, p);
            b.add(R, T, R, B, L, B, p);
        }
        // Slivers far outside the viewport, on every side: no fragment, counted empty.
        b.add(L, T, L + kOne, T, L, B, p);
        b.add(R, B, R - 3, T, R - 100, B, p);
        const ZBufferResult z = rasterize(b.tris, W, H, settingsFor(DepthFormat::f32, false));
        for (int i = 0; i < W * H; ++i) ASSERT_EQ(z.buffer.fragments[i], 1) << "pixel " << i;
        EXPECT_EQ(z.stats.fragments, uint64_t(W * H));
        EXPECT_EQ(z.stats.trianglesDrawn, 2u);
        EXPECT_EQ(z.stats.trianglesEmpty, 2u);
        expectSameBuffers(z, referenceRasterize(b.tris, W, H, settingsFor(DepthFormat::f32, false)),
                          "guard band split " + std::to_string(split));
    }
}

// Coordinates beyond the representable range (raster.cpp, kMaxFixed) are rejected, not wrapped.
TEST(RasterFillRule, BeyondRangeIsRejected) {
    Builder b;
    const uint32_t p = b.addPlane(0, 0, 0.5);
    b.add(-2147483647, -2147483647, 2147483647, -2147483647, 0, 2147483647, p);
    const ZBufferResult z = rasterize(b.tris, 8, 8, settingsFor(DepthFormat::f32, false));
    EXPECT_EQ(z.stats.fragments, 0u);
    EXPECT_EQ(z.stats.trianglesEmpty, 1u);
}

Builder twoRects(bool frontFirst, double nearDepth, double farDepth) {
    // A = [0, 8)^2 pixels at nearDepth, B = [4, 12)^2 at farDepth (perspective: 1/d constant).
    Builder b;
    const uint32_t pa = b.addPlane(0, 0, 1 / nearDepth), pb = b.addPlane(0, 0, 1 / farDepth);
    auto rect = [&](int64_t x0, int64_t y0, int64_t x1, int64_t y1, uint32_t p, uint32_t src) {
        b.add(x0, y0, x1, y0, x1, y1, p, src);
        b.add(x0, y0, x1, y1, x0, y1, p, src);
    };
    if (frontFirst) {
        rect(0, 0, 8 * kOne, 8 * kOne, pa, 10);
        rect(4 * kOne, 4 * kOne, 12 * kOne, 12 * kOne, pb, 20);
    } else {
        rect(4 * kOne, 4 * kOne, 12 * kOne, 12 * kOne, pb, 20);
        rect(0, 0, 8 * kOne, 8 * kOne, pa, 10);
    }
    return b;
}

// (e) Counts on a hand-computed case: 64 + 64 fragments, 112 covered pixels, 16 overlapping.
TEST(RasterCounts, OverlappingRectanglesBothOrders) {
    const int W = 16, H = 16;
    const ZBufferSettings s = settingsFor(DepthFormat::f32, false);
    const ZBufferResult ftb = rasterize(twoRects(true, 2, 5).tris, W, H, s);
    const ZBufferResult btf = rasterize(twoRects(false, 2, 5).tris, W, H, s);
    for (const ZBufferResult *z : {&ftb, &btf}) {
        EXPECT_EQ(z->stats.trianglesIn, 4u);
        EXPECT_EQ(z->stats.trianglesDrawn, 4u);
        EXPECT_EQ(z->stats.fragments, 128u);
        EXPECT_EQ(z->stats.coveredPixels, 112u);
        EXPECT_EQ(z->stats.maxDepthComplexity, 2u);
        EXPECT_EQ(z->stats.histogram, (std::vector<uint64_t>{144, 96, 16}));
        EXPECT_DOUBLE_EQ(z->stats.depthComplexity, 128.0 / 112.0);
        EXPECT_EQ(z->stats.outOfRangeFragments, 0u);
        // The overlap shows A (source 10) in both orders, at depth 1 / (1 / 2) = 2.
        EXPECT_EQ(z->buffer.id[5 * W + 5], 11u);
        EXPECT_EQ(z->buffer.depth[5 * W + 5], 2.0);
        EXPECT_EQ(z->buffer.id[10 * W + 10], 21u);
        EXPECT_EQ(z->buffer.id[14 * W + 14], 0u);
        EXPECT_EQ(z->buffer.depth[14 * W + 14], INFINITY);
        EXPECT_EQ(z->buffer.key[14 * W + 14], 0xFFFFFFFFu);
    }
    // Front to back: the 16 farther fragments of the overlap fail; back to front: all pass.
    EXPECT_EQ(ftb.stats.depthPasses, 112u);
    EXPECT_EQ(ftb.stats.overdraw, 1.0);
    EXPECT_EQ(ftb.buffer.passes[5 * W + 5], 1);
    EXPECT_EQ(btf.stats.depthPasses, 128u);
    EXPECT_DOUBLE_EQ(btf.stats.overdraw, 128.0 / 112.0);
    EXPECT_EQ(btf.buffer.passes[5 * W + 5], 2);
    EXPECT_EQ(btf.buffer.fragments[5 * W + 5], 2);
}

// Equal stored depth: the first drawn fragment wins (LESS), in either submission order.
TEST(RasterCounts, EqualDepthFirstDrawnWins) {
    const int W = 16, H = 16;
    const ZBufferSettings s = settingsFor(DepthFormat::f32, false);
    for (bool order : {true, false}) {
        const ZBufferResult z = rasterize(twoRects(order, 3, 3).tris, W, H, s);
        EXPECT_EQ(z.stats.depthPasses, 112u);  // the second drawn's overlap fragments tie and fail
        EXPECT_EQ(z.buffer.id[5 * W + 5], order ? 11u : 21u);
    }
    // Different depths with equal keys (unorm16 near the far plane) tie too: the first drawn wins.
    const ZBufferSettings s16 = settingsFor(DepthFormat::unorm16, false, 0.5, 200);
    ASSERT_EQ(depthKey(s16.encoder, 199.9), depthKey(s16.encoder, 199.8));
    const ZBufferResult z = rasterize(twoRects(false, 199.8, 199.9).tris, W, H, s16);
    EXPECT_EQ(z.buffer.id[5 * W + 5], 21u);  // B (farther, drawn first) keeps the pixel
    EXPECT_EQ(z.buffer.depth[5 * W + 5], 1 / (1 / 199.9));
}

// Per-pixel counters saturate at 65535; the totals do not.
TEST(RasterCounts, PerPixelCountsSaturate) {
    Builder b;
    const uint32_t p = b.addPlane(0, 0, 0.5);
    const int n = 70000;
    // Centers with x + y < 3 (the hypotenuse x + y = 3 is a bottom-right edge): (0,0) (1,0) (0,1).
    for (int i = 0; i < n; ++i) b.add(0, 0, 3 * kOne, 0, 0, 3 * kOne, p);
    const ZBufferResult z = rasterize(b.tris, 4, 4, settingsFor(DepthFormat::f32, false));
    EXPECT_EQ(z.buffer.fragments[0], 65535);
    EXPECT_EQ(z.buffer.passes[0], 1);
    EXPECT_EQ(z.stats.fragments, uint64_t(3 * n));
    EXPECT_EQ(z.stats.depthPasses, 3u);
    EXPECT_EQ(z.stats.maxDepthComplexity, 65535u);
    ASSERT_EQ(z.stats.histogram.size(), 65536u);
    EXPECT_EQ(z.stats.histogram[65535], 3u);
    EXPECT_EQ(z.stats.histogram[0], 13u);
}

// Every format goes through the rasterizer's dispatch: near triangle over far, both projections,
// keys equal to depthKey() of the plane's depth, and the formats' out-of-range counting.
TEST(RasterFormats, AllFormatsDispatch) {
    const int W = 12, H = 10;
    for (DepthFormat f : allDepthFormats())
        for (bool ortho : {false, true}) {
            const double n = 2, fa = 100;
            Builder b;
            // Far: a tilted plane between 40 and 60; near: constant 5; then one at 150 (beyond far).
            const double dFar0 = 40, dFar1 = 60;
            uint32_t pFar, pNear, pOut;
            if (ortho) {
                pFar = b.addPlane((dFar1 - dFar0) / W, 0, dFar0);
                pNear = b.addPlane(0, 0, 5);
                pOut = b.addPlane(0, 0, 150);
            } else {
                pFar = b.addPlane((1 / dFar1 - 1 / dFar0) / W, 0, 1 / dFar0);
                pNear = b.addPlane(0, 0, 1 / 5.0);
                pOut = b.addPlane(0, 0, 1 / 150.0);
            }
            b.add(0, 0, W * kOne, 0, 0, H * kOne, pFar, 0);
            b.add(W * kOne, 0, W * kOne, H * kOne, 0, H * kOne, pFar, 1);
            b.add(0, 0, 6 * kOne, 0, 0, 6 * kOne, pNear, 2);
            b.add(0, 0, 6 * kOne, 0, 0, 6 * kOne, pOut, 3);
            const ZBufferSettings s = settingsFor(f, ortho, n, fa);
            const ZBufferResult z = rasterize(b.tris, W, H, s);
            const std::string what = std::string(depthFormatInfo(f).name) + (ortho ? " ortho" : " persp");
            Camera cam;
            cam.orthographic = ortho;
            for (int y = 0; y < H; ++y)
                for (int x = 0; x < W; ++x) {
                    const size_t i = size_t(y) * W + x;
                    const bool nearCovers = (x + 0.5) + (y + 0.5) < 6;
                    const DepthPlane &pl = b.tris.planes[nearCovers ? pNear : pFar];
                    const double d = viewDepthAt(cam, pl, x + 0.5, y + 0.5);
                    ASSERT_EQ(z.buffer.key[i], depthKey(s.encoder, d)) << what << " " << x << "," << y;
                    ASSERT_EQ(z.buffer.depth[i], d) << what;
                    if (nearCovers) ASSERT_EQ(z.buffer.id[i], 3u) << what;
                    else ASSERT_TRUE(z.buffer.id[i] == 1 || z.buffer.id[i] == 2) << what;
                }
            const uint64_t nearFrags = 15;  // centers with x + y < 5: 5 + 4 + 3 + 2 + 1
            EXPECT_EQ(z.stats.fragments, uint64_t(W * H) + 2 * nearFrags) << what;
            // 150 lies beyond far = 100 for the formats bounded by far; the others hold it.
            const bool boundedByFar = f != DepthFormat::linear_f32 && f != DepthFormat::inv_f32 &&
                                      f != DepthFormat::int31_inv && f != DepthFormat::uint32_inv &&
                                      f != DepthFormat::uint32_inv1 && f != DepthFormat::f32_reversed_inf;
            EXPECT_EQ(z.stats.outOfRangeFragments, boundedByFar ? nearFrags : 0) << what;
        }
}

TEST(RasterFormats, EmptyInputAndViewport) {
    ScreenTriangles none;
    const ZBufferResult z = rasterize(none, 5, 3, settingsFor(DepthFormat::f32, false));
    EXPECT_EQ(z.buffer.key.size(), 15u);
    EXPECT_EQ(z.stats.coveredPixels, 0u);
    EXPECT_EQ(z.stats.histogram, (std::vector<uint64_t>{15}));
    Builder b;
    b.add(0, 0, kOne * 4, 0, 0, kOne * 4, b.addPlane(0, 0, 0.5));
    const ZBufferResult e = rasterize(b.tris, 0, 0, settingsFor(DepthFormat::f32, false));
    EXPECT_EQ(e.stats.trianglesEmpty, 1u);
    EXPECT_EQ(e.stats.fragments, 0u);
}

// The benchmark scene: exact triangle count, no zero-area triangle, fronts facing out (spheres) and
// up (ground), everything in front of the benchmark camera's near plane.
TEST(RasterBenchScene, SphereGridMesh) {
    const RawMesh m = sphereGridMesh();
    ASSERT_EQ(m.indices.size(), 3 * size_t(1000002));
    EXPECT_EQ(kBenchSceneTriangles, 1000002u);
    EXPECT_EQ(m.positions.size(), size_t(100 * 5002 + 4));
    Camera cam;
    std::string err;
    ASSERT_TRUE(makeCamera(benchmarkCamera(), &cam, &err)) << err;
    EXPECT_EQ(cam.width, 1920);
    EXPECT_EQ(cam.height, 1080);
    for (const Vec3 &p : m.positions) ASSERT_GT(-transformPoint(cam.viewFromWorld, p).z, cam.nearZ);
    const uint32_t perSphere = 10000;
    for (size_t t = 0; t < m.indices.size() / 3; ++t) {
        const uint32_t i0 = m.indices[3 * t], i1 = m.indices[3 * t + 1], i2 = m.indices[3 * t + 2];
        ASSERT_LT(std::max(i0, std::max(i1, i2)), m.positions.size());
        ASSERT_TRUE(i0 != i1 && i1 != i2 && i0 != i2) << t;
        const Vec3 &a = m.positions[i0], &b = m.positions[i1], &c = m.positions[i2];
        const Vec3 nrm = cross(b - a, c - a);
        ASSERT_GT(length(nrm), 0) << "zero-area triangle " << t;
        if (t < 100 * perSphere) {
            const uint32_t s = uint32_t(t / perSphere);
            const Vec3 center(2.5 * (s / 10), 0, 2.5 * (s % 10));
            ASSERT_GT(dot(nrm, (a + b + c) / 3 - center), 0) << "inward triangle " << t;
        } else {
            ASSERT_GT(nrm.y, 0) << "ground triangle " << t << " faces down";
            ASSERT_EQ(a.y, -1);
        }
    }
}

// The whole benchmark through clip and rasterize: the stats agree with the per-pixel buffers, and
// a second run is bit-identical (determinism).
TEST(RasterBenchScene, RasterizeIsConsistentAndDeterministic) {
    const RawMesh m = sphereGridMesh();
    Camera cam;
    std::string err;
    ASSERT_TRUE(makeCamera(benchmarkCamera(), &cam, &err)) << err;
    std::vector<uint32_t> all(m.indices.size() / 3);
    for (uint32_t t = 0; t < all.size(); ++t) all[t] = t;
    const std::vector<ClipBatch> batches = {{0, uint32_t(m.positions.size()), all.data(), uint32_t(all.size())}};
    const ClipResult clip = clipTriangles(cam, {m.positions.data(), m.indices.data()}, batches, {});
    const ZBufferSettings s = settingsFor(DepthFormat::f32, false, cam.nearZ, cam.farZ);
    const ZBufferResult a = rasterize(clip.out, cam.width, cam.height, s);
    const ZBufferResult b = rasterize(clip.out, cam.width, cam.height, s);
    EXPECT_EQ(a.stats.trianglesDrawn + a.stats.trianglesEmpty, a.stats.trianglesIn);
    uint64_t frags = 0, passes = 0;
    for (size_t i = 0; i < a.buffer.fragments.size(); ++i) {
        frags += a.buffer.fragments[i];
        passes += a.buffer.passes[i];
    }
    EXPECT_EQ(frags, a.stats.fragments);
    EXPECT_EQ(passes, a.stats.depthPasses);
    EXPECT_GT(a.stats.coveredPixels, 1000000u);  // the ground and the spheres fill most of the view
    EXPECT_EQ(a.buffer.id, b.buffer.id);
    EXPECT_EQ(a.buffer.key, b.buffer.key);
    EXPECT_EQ(a.buffer.fragments, b.buffer.fragments);
}

// ---- The fragment core (raster_core.h) and the audit options --------------------------------

// A sink recording every call, to check forEachFragment's contract against the brute force.
struct RecordingSink {
    int W = 0;
    std::vector<std::vector<std::pair<size_t, double>>> frags;  // per triangle: (pixel, depth)
    std::vector<int> begun, ended;                               // calls per triangle
    std::vector<uint64_t> endCount;
    size_t current = ~size_t(0);
    bool beginTriangle(size_t t, bool) {
        ++begun[t];
        current = t;
        return true;
    }
    void fragment(size_t pixel, size_t t, double d) {
        EXPECT_EQ(t, current);
        frags[t].push_back({pixel, d});
    }
    void endTriangle(size_t t, uint64_t n) {
        ++ended[t];
        endCount[t] = n;
    }
};

// forEachFragment visits exactly the brute-force reference's covered centers, once each and in
// ascending pixel order, with the depth of viewDepthAt bit for bit, and calls begin/end once per
// triangle that has an area. The soup has triangles for each coverage path (small block, narrow
// box, per-row spans).
TEST(RasterCore, FragmentsMatchBruteForce) {
    const int W = 61, H = 43;
    for (uint32_t seed = 300; seed < 306; ++seed) {
        const bool ortho = seed % 2;
        const ScreenTriangles tris = randomSoup(seed, W, H, 250, ortho);
        RecordingSink sink;
        sink.W = W;
        sink.frags.resize(tris.size());
        sink.begun.assign(tris.size(), 0);
        sink.ended.assign(tris.size(), 0);
        sink.endCount.assign(tris.size(), 0);
        forEachFragment(tris, W, H, ortho, sink);
        Camera cam;
        cam.orthographic = ortho;
        uint64_t total = 0;
        for (size_t t = 0; t < tris.size(); ++t) {
            const DepthPlane &p = tris.planes[tris.plane[t]];
            std::vector<std::pair<size_t, double>> want;
            for (int y = 0; y < H && p.valid; ++y)
                for (int x = 0; x < W; ++x)
                    if (refCovers(&tris.xy[6 * t], x, y))
                        want.push_back({size_t(y) * W + x, viewDepthAt(cam, p, x + 0.5, y + 0.5)});
            // In ascending pixel order, each pixel once (the contract the ordering audit's banded
            // draws rely on): `want` is in that order, so the lists compare as they come.
            const std::vector<std::pair<size_t, double>> &got = sink.frags[t];
            ASSERT_EQ(got.size(), want.size()) << "seed " << seed << " triangle " << t;
            for (size_t i = 0; i < want.size(); ++i) {
                ASSERT_EQ(got[i].first, want[i].first) << "seed " << seed << " triangle " << t;
                ASSERT_EQ(std::memcmp(&got[i].second, &want[i].second, sizeof(double)), 0);
            }
            EXPECT_EQ(sink.begun[t], sink.ended[t]);
            EXPECT_LE(sink.begun[t], 1);
            if (!want.empty()) {
                EXPECT_EQ(sink.begun[t], 1);
            }
            EXPECT_EQ(sink.endCount[t], want.size());
            total += want.size();
        }
        EXPECT_GT(total, 1000u);
    }
}

// beginTriangle returning false skips the triangle: no fragment, no endTriangle.
TEST(RasterCore, BeginFalseSkips) {
    struct Sink {
        uint64_t frags = 0, ends = 0;
        bool beginTriangle(size_t t, bool) { return t % 2 == 0; }
        void fragment(size_t, size_t t, double) { EXPECT_EQ(t % 2, 0u); ++frags; }
        void endTriangle(size_t t, uint64_t) { EXPECT_EQ(t % 2, 0u); ++ends; }
    } sink;
    Builder b;
    const uint32_t p = b.addPlane(0, 0, 0.5);
    // Centers with x + y < 3 (the hypotenuse x + y = 3 is a bottom-right edge): 6 each.
    for (int i = 0; i < 4; ++i) b.add(0, 0, 4 * kOne, 0, 0, 4 * kOne, p);
    forEachFragment(b.tris, 8, 8, false, sink);
    EXPECT_EQ(sink.frags, 12u);
    EXPECT_EQ(sink.ends, 2u);
}

// A world triangle through the clip stage; returns its screen triangles.
ScreenTriangles clipOne(const Camera &cam, const std::vector<Vec3> &pos, const std::vector<uint32_t> &idx) {
    std::vector<uint32_t> tri(idx.size() / 3);
    for (uint32_t t = 0; t < tri.size(); ++t) tri[t] = t;
    const std::vector<ClipBatch> batches = {{0, uint32_t(pos.size()), tri.data(), uint32_t(tri.size())}};
    return clipTriangles(cam, {pos.data(), idx.data()}, batches, {}).out;
}

// The front winding on screen: a triangle counter-clockwise seen from its front is front-wound
// (negative signed area in y-down pixels) from the front and back-wound from behind, for
// perspective and orthographic views and for a triangle cut by the near plane (its clipped
// pieces keep the winding); singleSided draws exactly the front-wound ones.
TEST(RasterWinding, FrontWindingPerspectiveOrthoAndNearClipped) {
    // In the plane z = 0, counter-clockwise seen from +z (normal (v1-v0) x (v2-v0) = +z).
    const std::vector<Vec3> pos = {{-1, -1, 0}, {1, -1, 0}, {0, 1, 0}};
    const std::vector<uint32_t> idx = {0, 1, 2};
    for (bool ortho : {false, true})
        for (double side : {1.0, -1.0}) {
            CameraSpec spec;
            spec.eye = {0.1, 0.2, 4 * side};
            spec.target = {0, 0, 0};
            spec.orthographic = ortho;
            spec.orthoHeight = 4;
            spec.width = 40;
            spec.height = 30;
            spec.nearZ = 0.5;
            spec.farZ = 100;
            Camera cam;
            std::string err;
            ASSERT_TRUE(makeCamera(spec, &cam, &err)) << err;
            const ScreenTriangles st = clipOne(cam, pos, idx);
            ASSERT_EQ(st.size(), 1u);
            const int32_t *v = st.xy.data();
            const int64_t area = int64_t(v[2] - v[0]) * (v[5] - v[1]) - int64_t(v[3] - v[1]) * (v[4] - v[0]);
            EXPECT_EQ(area < 0, side > 0) << (ortho ? "ortho" : "persp") << " side " << side;

            struct Sink {
                std::vector<int> front;
                bool beginTriangle(size_t, bool f) { front.push_back(f); return true; }
                void fragment(size_t, size_t, double) {}
                void endTriangle(size_t, uint64_t) {}
            } sink;
            forEachFragment(st, cam.width, cam.height, ortho, sink);
            ASSERT_EQ(sink.front.size(), 1u);
            EXPECT_EQ(sink.front[0] != 0, side > 0);

            const uint8_t single[1] = {1}, dbl[1] = {0};
            ZBufferSettings s = settingsFor(DepthFormat::f32, ortho, cam.nearZ, cam.farZ);
            s.singleSided = single;
            const ZBufferResult z1 = rasterize(st, cam.width, cam.height, s);
            s.singleSided = dbl;
            const ZBufferResult z2 = rasterize(st, cam.width, cam.height, s);
            EXPECT_GT(z2.stats.fragments, 50u);
            EXPECT_EQ(z1.stats.fragments, side > 0 ? z2.stats.fragments : 0u);
            EXPECT_EQ(z1.stats.trianglesBackWinding, side > 0 ? 0u : 1u);
            EXPECT_EQ(z1.stats.trianglesDrawn + z1.stats.trianglesEmpty, z1.stats.trianglesIn);
        }
    // Cut by the near plane (perspective): a large floor triangle under the eye, seen from above
    // (front) and from below (back). Every clipped piece has the same winding as the source.
    const std::vector<Vec3> floorPos = {{-50, -1, 50}, {50, -1, 50}, {0, -1, -50}};  // CCW from +y
    for (double up : {1.0, -1.0}) {
        CameraSpec spec;
        spec.eye = {0, -1 + up, 0};
        spec.target = {0, -1 + 0.5 * up, -3};
        spec.width = 64;
        spec.height = 48;
        spec.nearZ = 0.5;
        spec.farZ = 30;
        Camera cam;
        std::string err;
        ASSERT_TRUE(makeCamera(spec, &cam, &err)) << err;
        const ScreenTriangles st = clipOne(cam, floorPos, idx);
        ASSERT_GE(st.size(), 2u);  // clipped into a polygon with 4+ vertices
        for (size_t t = 0; t < st.size(); ++t) {
            const int32_t *v = &st.xy[6 * t];
            const int64_t area = int64_t(v[2] - v[0]) * (v[5] - v[1]) - int64_t(v[3] - v[1]) * (v[4] - v[0]);
            EXPECT_EQ(area < 0, up > 0) << "piece " << t << " up " << up;
        }
    }
}

// exactDepth: the double depth decides where a format's keys tie; equal doubles keep the first
// drawn; the key buffer holds the format's key of the stored depth.
TEST(RasterOptions, ExactDepth) {
    const int W = 16, H = 16;
    ZBufferSettings s16 = settingsFor(DepthFormat::unorm16, false, 0.5, 200);
    ASSERT_EQ(depthKey(s16.encoder, 199.9), depthKey(s16.encoder, 199.8));
    s16.exactDepth = true;
    // B (farther, drawn first) loses the overlap to A in exact depth, unlike the format test.
    const ZBufferResult z = rasterize(twoRects(false, 199.8, 199.9).tris, W, H, s16);
    EXPECT_EQ(z.buffer.id[5 * W + 5], 11u);
    EXPECT_EQ(z.buffer.depth[5 * W + 5], 1 / (1 / 199.8));
    EXPECT_EQ(z.buffer.key[5 * W + 5], depthKey(s16.encoder, 1 / (1 / 199.8)));
    EXPECT_EQ(z.buffer.key[14 * W + 14], 0xFFFFFFFFu);
    EXPECT_EQ(z.stats.depthPasses, 128u);
    EXPECT_EQ(z.stats.outOfRangeFragments, 0u);
    for (bool order : {true, false}) {
        ZBufferSettings s = settingsFor(DepthFormat::f32, false);
        s.exactDepth = true;
        const ZBufferResult e = rasterize(twoRects(order, 3, 3).tris, W, H, s);
        EXPECT_EQ(e.buffer.id[5 * W + 5], order ? 11u : 21u);
        EXPECT_EQ(e.stats.depthPasses, 112u);
    }
    // On random soups, exact depth equals the brute force with the key replaced by the depth.
    for (uint32_t seed = 400; seed < 404; ++seed) {
        const bool ortho = seed % 2;
        const ScreenTriangles tris = randomSoup(seed, 50, 40, 200, ortho);
        ZBufferSettings s = settingsFor(DepthFormat::inv_f32, ortho);
        s.exactDepth = true;
        const ZBufferResult got = rasterize(tris, 50, 40, s);
        // Reference: a double z-buffer (LESS, first drawn wins) over the brute-force coverage.
        std::vector<double> depth(50 * 40, INFINITY);
        std::vector<uint32_t> id(50 * 40, 0);
        Camera cam;
        cam.orthographic = ortho;
        for (size_t t = 0; t < tris.size(); ++t) {
            const DepthPlane &p = tris.planes[tris.plane[t]];
            for (int y = 0; y < 40 && p.valid; ++y)
                for (int x = 0; x < 50; ++x)
                    if (refCovers(&tris.xy[6 * t], x, y)) {
                        const double d = viewDepthAt(cam, p, x + 0.5, y + 0.5);
                        if (d < depth[size_t(y) * 50 + x]) {
                            depth[size_t(y) * 50 + x] = d;
                            id[size_t(y) * 50 + x] = tris.source[t] + 1;
                        }
                    }
        }
        EXPECT_EQ(got.buffer.id, id) << "seed " << seed;
        for (size_t i = 0; i < depth.size(); ++i) ASSERT_EQ(std::memcmp(&got.buffer.depth[i], &depth[i], 8), 0);
    }
}

// fragmentsPerSource: per source triangle, the fragments of all its pieces; the default path's
// buffers are unchanged by the counter.
TEST(RasterOptions, FragmentsPerSource) {
    const int W = 53, H = 37;
    const ScreenTriangles tris = randomSoup(77, W, H, 200, false);
    const uint32_t maxSource = *std::max_element(tris.source.begin(), tris.source.end());
    std::vector<uint32_t> per(maxSource + 1, 0);
    ZBufferSettings s = settingsFor(DepthFormat::f32, false);
    const ZBufferResult plain = rasterize(tris, W, H, s);
    s.fragmentsPerSource = per.data();
    const ZBufferResult counted = rasterize(tris, W, H, s);
    expectSameBuffers(counted, plain, "with fragmentsPerSource");
    std::vector<uint32_t> want(maxSource + 1, 0);
    for (size_t t = 0; t < tris.size(); ++t) {
        if (!tris.planes[tris.plane[t]].valid) continue;
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) want[tris.source[t]] += refCovers(&tris.xy[6 * t], x, y);
    }
    EXPECT_EQ(per, want);
    uint64_t sum = 0;
    for (uint32_t c : per) sum += c;
    EXPECT_EQ(sum, plain.stats.fragments);
}

// The depth-complexity histogram counts small counts in four tables in turn and the rest in the
// full one: against a plain count, with counts below and above 64, the saturated 65535, and a
// pixel count that is not a multiple of four.
TEST(ZBufferStats, HistogramEqualsAPlainCount) {
    std::mt19937 rng(5);
    // Sizes around the AVX2 path's 16-pixel vectors and its 65,536-pixel blocks (finishZBufferStats'
    // histogramAvx2); mixed counts, and counts below 8 only (every vector on the lane counters,
    // which reach their most, 4096, in a block of one count) with a few larger ones in long runs.
    for (int mode : {0, 1, 2}) {
        for (size_t pixels : {size_t(0), size_t(1), size_t(7), size_t(4099), size_t(65536), size_t(200003)}) {
            ZBuffer zb;
            zb.width = int(pixels), zb.height = 1;
            zb.fragments.resize(pixels);
            for (size_t i = 0; i < pixels; ++i) {
                uint16_t &c = zb.fragments[i];
                const uint32_t r = rng() % 100;
                if (mode == 0)
                    c = r < 60   ? uint16_t(r % 4)
                        : r < 90 ? uint16_t(60 + rng() % 10)
                        : r < 99 ? uint16_t(rng() % 3000)
                                 : uint16_t(0xFFFF);
                else if (mode == 1)
                    c = uint16_t(r % 8);
                else
                    c = i < 70000 ? uint16_t(5) : (i / 977) % 7 == 0 ? uint16_t(8 + r % 3) : uint16_t(r % 8);
            }
            std::vector<uint64_t> plain(65536, 0);
            for (uint16_t c : zb.fragments) ++plain[c];
            size_t top = 65535;
            while (top > 0 && plain[top] == 0) --top;
            plain.resize(top + 1);
            ZBufferStats st;
            finishZBufferStats(zb, &st);
            EXPECT_EQ(st.histogram, plain) << "mode " << mode << ", " << pixels << " pixels";
            EXPECT_EQ(st.coveredPixels, pixels - plain[0]);
            EXPECT_EQ(st.maxDepthComplexity, uint32_t(top));
        }
    }
}

}  // namespace
}  // namespace va
