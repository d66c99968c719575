// The BSP tree (analysis/audits/bsp_tree.h): exact plane classification, splits, the hard cases of the
// ordering issue (cyclic overlap, interpenetration, a vertex on a splitting plane, coplanar
// triangles, a scene far from the origin, a closed mesh from inside and outside), and traversal
// against the reference visibility. Suite BspTree*.
#include <gtest/gtest.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <filesystem>
#include <string>
#include <vector>

#include "tests/test_util.h"
#include "analysis/audits/audit.h"
#include "analysis/audits/bsp_tree.h"
#include "analysis/load/demo.h"
#include "analysis/load/load.h"
#include "analysis/audits/ordering.h"

namespace va {
namespace {

using testing_util::looseTriangles;

// Reproducible uniform doubles in [0, 1): a 64-bit LCG's high 53 bits.
struct Uniform01 {
    uint64_t state;
    double operator()() {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return double(state >> 11) * 0x1p-53;
    }
};

// CGAL's exact orientation predicate alone (Epick), as orient3d's sign.
int cgalOrient3d(Vec3 a, Vec3 b, Vec3 c, Vec3 d) {
    using K = CGAL::Exact_predicates_inexact_constructions_kernel;
    const CGAL::Orientation o = CGAL::orientation(K::Point_3(a.x, a.y, a.z), K::Point_3(b.x, b.y, b.z),
                                                  K::Point_3(c.x, c.y, c.z), K::Point_3(d.x, d.y, d.z));
    return o == CGAL::POSITIVE ? 1 : (o == CGAL::NEGATIVE ? -1 : 0);
}

// Three thin triangles ("sticks") around the z axis, each rotated 120 degrees from the last, each
// rising along its length (z = 0.3 x in its own frame). The sticks' lines are the sides of an
// equilateral triangle of inradius 1, so stick k's high end crosses over stick k+1's low end:
// 0 over 1, 1 over 2, 2 over 0 -- a cycle. Front faces point to +z (counter-clockwise from above).
// `scale` and `offset` move the whole scene (scale a power of two keeps the coordinates exact).
std::vector<std::array<Vec3, 3>> cyclicSticks(double scale = 1, Vec3 offset = {}) {
    std::vector<std::array<Vec3, 3>> out;
    const Vec3 base[3] = {{-4, -1.625, -1.25}, {4, -1, 1.25}, {-4, -0.375, -1.25}};
    for (int k = 0; k < 3; ++k) {
        const double a = 2 * kPi * k / 3, c = std::cos(a), s = std::sin(a);
        std::array<Vec3, 3> t;
        for (int i = 0; i < 3; ++i) {
            const Vec3 p = base[i];
            // Round the rotated coordinates to multiples of 2^-10 so that scaling and offsetting
            // stay exact in double.
            auto q = [](double v) { return std::round(v * 1024) / 1024; };
            const Vec3 r{q(c * p.x - s * p.y), q(s * p.x + c * p.y), p.z};
            t[i] = offset + r * scale;
        }
        out.push_back(t);
    }
    return out;
}

Camera topCamera(int size = 200, double height = 10, Vec3 center = {}) {
    CameraSpec cs;
    cs.eye = center + Vec3{0, 0, 10};
    cs.target = center;
    cs.up = {0, 1, 0};
    cs.orthographic = true;
    cs.orthoHeight = height;
    cs.nearZ = 0.5;
    cs.farZ = 100;
    cs.width = cs.height = size;
    Camera cam;
    std::string err;
    EXPECT_TRUE(makeCamera(cs, &cam, &err)) << err;
    return cam;
}

// The tree's structure as plain numbers, to compare two trees.
std::vector<int64_t> signature(const BspTree &t) {
    std::vector<int64_t> s;
    for (const BspTreeNode &n : t.nodes) {
        s.insert(s.end(), {n.planeSource, n.front, n.back, n.pieceCount});
        for (uint32_t i = 0; i < n.pieceCount; ++i) {
            const BspPiece &p = t.pieces[t.nodePieces[n.firstPiece + i]];
            s.insert(s.end(), {p.source, p.vertexCount, p.constraintCount});
        }
    }
    return s;
}

TEST(BspTree, Orient3dSignAndExactness) {
    EXPECT_EQ(orient3d({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}), 1);   // front of a CCW triangle
    EXPECT_EQ(orient3d({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, -1}), -1);
    EXPECT_EQ(orient3d({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {5, 7, 0}), 0);
    // A point on the plane far from the origin, where the double evaluation of n.p + k is not 0:
    // the plane through (1e5 + 0.1, ...) -- a decimal that double cannot hold -- and points on it.
    const Vec3 a{1e5 + 0.1, 1e5 + 0.2, 1e5 + 0.3}, b = a + Vec3{1, 0, 0}, c = a + Vec3{0, 1, 0};
    const Vec3 onPlane{1e5 + 1.7, 1e5 - 3.3, a.z};
    EXPECT_EQ(orient3d(a, b, c, onPlane), 0);
    EXPECT_EQ(orient3d(a, b, c, {onPlane.x, onPlane.y, std::nextafter(a.z, 2e5)}), 1);
    EXPECT_EQ(orient3d(a, b, c, {onPlane.x, onPlane.y, std::nextafter(a.z, 0.0)}), -1);
    // The exact zeros decided before CGAL (a corner repeated; four points on one axis-aligned
    // plane), against the truth, and one ulp off the plane the sign is still exact: random
    // level-sized coordinates on planes x, y or z = const.
    Uniform01 uniform{42};
    auto next = [&] { return uniform() * 2e4 - 1e4; };
    for (int i = 0; i < 2000; ++i) {
        const int axis = i % 3;
        const double k = next();
        auto onAxisPlane = [&] {
            Vec3 p{next(), next(), next()};
            p[axis] = k;
            return p;
        };
        const Vec3 p0 = onAxisPlane(), p1 = onAxisPlane(), p2 = onAxisPlane(), q = onAxisPlane();
        EXPECT_EQ(orient3d(p0, p1, p2, q), 0);
        EXPECT_EQ(orient3d(p0, p1, p2, p1), 0);
        EXPECT_EQ(orient3d(p0, p1, q, p0), 0);
        // Off the plane by one ulp: the sign of the normal's component times the offset's.
        const Vec3 n = cross(p1 - p0, p2 - p0);
        if (n[axis] == 0) continue;
        Vec3 up = q;
        up[axis] = std::nextafter(k, 1e30);
        EXPECT_EQ(orient3d(p0, p1, p2, up), n[axis] > 0 ? 1 : -1) << i;
    }
}

// orient3d's own stages (filter, exact zeros, 128-bit integers) against CGAL's exact predicate
// alone, on inputs that reach every stage: points on random planes through grid and float
// coordinates (coplanar up to rounding), snapped to grids of several sizes, and exact copies.
TEST(BspTree, Orient3dAgreesWithCgal) {
    Uniform01 next{7};
    int decided = 0;
    for (int i = 0; i < 20000; ++i) {
        const double grid = std::ldexp(1.0, int(next() * 12) - 6);  // 1/64 .. 32
        const double scale = std::ldexp(1.0, int(next() * 20));      // 1 .. 2^19
        auto snap = [&](double x) { return i % 4 == 0 ? x : std::round(x / grid) * grid; };
        const Vec3 o{snap(next() * scale), snap(next() * scale), snap(next() * scale)};
        const Vec3 u{snap(next() * 64 - 32), snap(next() * 64 - 32), snap(next() * 64 - 32)};
        const Vec3 w{snap(next() * 64 - 32), snap(next() * 64 - 32), snap(next() * 64 - 32)};
        const Vec3 a = o, b = o + u, c = o + w;
        const double s = next() * 4 - 2, t = next() * 4 - 2;
        Vec3 d = o + u * s + w * t;  // on the plane up to rounding
        d = {snap(d.x), snap(d.y), snap(d.z)};
        if (i % 3 == 0) d = i % 2 ? b : c;
        const int want = cgalOrient3d(a, b, c, d);
        ASSERT_EQ(orient3d(a, b, c, d), want) << i;
        decided += want == 0;
    }
    EXPECT_GT(decided, 5000);  // many exact zeros: the stages before CGAL were exercised
}

// orient3d's scaled-integer stage at its bounds: coordinates that are integer multiples of one power
// of two 2^e (e from 2^-40 to 2^20) whose integers reach 2^57 .. 2^63 (the stage takes those below
// 2^61, the others go on to the later stages), one corner an odd multiple so that 2^e is the
// common scale, and the fourth point on the plane up to rounding (the filter cannot tell), or
// moved by a few of its ulps, against CGAL's exact predicate alone.
TEST(BspTree, Orient3dScaledIntegersAgreeWithCgalAtTheirBounds) {
    Uniform01 next{13};
    int zeros = 0, nearPlane = 0;
    for (int i = 0; i < 30000; ++i) {
        const int e = int(next() * 60) - 40, bits = 57 + i % 7;
        auto coord = [&] { return std::ldexp(std::round((next() * 2 - 1) * std::ldexp(1.0, 52)), bits - 52 + e); };
        Vec3 a{coord(), coord(), coord()}, b{coord(), coord(), coord()}, c{coord(), coord(), coord()};
        a[i % 3] = std::ldexp(double(2 * int(next() * 1000) + 1), e);  // an odd multiple of 2^e
        Vec3 d = a + (b - a) * (next() * 2 - 1) + (c - a) * (next() * 2 - 1);
        if (i % 5 == 0) d = (a + b) * 0.5;  // on an edge
        if (i % 4 == 1) d[i % 3] = std::nextafter(d[i % 3], next() < 0.5 ? -INFINITY : INFINITY);
        const int want = cgalOrient3d(a, b, c, d);
        ASSERT_EQ(orient3d(a, b, c, d), want) << i;
        ASSERT_EQ(PlaneSide(a, b, c)(d), want) << i;
        zeros += want == 0;
        // Within the filter's bound of the plane (7 roundings of the permanent): the filter
        // cannot tell these, an exact stage does.
        const Vec3 r1 = b - a, r2 = c - a, r3 = d - a;
        const double permanent = std::fabs(r1.x) * (std::fabs(r2.y * r3.z) + std::fabs(r2.z * r3.y)) +
                                 std::fabs(r1.y) * (std::fabs(r2.z * r3.x) + std::fabs(r2.x * r3.z)) +
                                 std::fabs(r1.z) * (std::fabs(r2.x * r3.y) + std::fabs(r2.y * r3.x));
        nearPlane += want != 0 && std::fabs(dot(r1, cross(r2, r3))) <= 7 * 0x1p-53 * permanent;
    }
    EXPECT_GT(zeros, 50);
    EXPECT_GT(nearPlane, 10000);
    // A determinant of +-1 (in units of the scale) under a permanent near 2^80: rows r1 and r2 whose
    // x, y parts are consecutive Fibonacci numbers (F(n+1) F(n-1) - F(n)^2 = (-1)^n, so
    // (r1 x r2).z = +-1) and r3 = r1 + r2 + (0, 0, +-1 or 0), at large integer coordinates.
    for (int i = 0; i < 1000; ++i) {
        const int n = 30 + i % 10;
        double f0 = 0, f1 = 1;  // F(k), F(k + 1)
        for (int k = 0; k < n - 1; ++k) std::tie(f0, f1) = std::pair{f1, f0 + f1};  // F(n - 1), F(n)
        const double scale = std::ldexp(1.0, int(next() * 40) - 20);
        const Vec3 a = Vec3{std::round(next() * 0x1p30), std::round(next() * 0x1p30), std::round(next() * 0x1p30)} * scale;
        const Vec3 r1 = Vec3{f0 + f1, f1, std::round(next() * 0x1p28)} * scale;
        const Vec3 r2 = Vec3{f1, f0, std::round(next() * 0x1p28)} * scale;
        const int cross = n % 2 ? -1 : 1;  // (r1 x r2).z / scale^2 = F(n+1) F(n-1) - F(n)^2
        const int off = i % 3 - 1;
        const Vec3 d = a + r1 + r2 + Vec3{0, 0, off * scale};
        ASSERT_EQ(orient3d(a, a + r1, a + r2, d), off * cross) << i;
        ASSERT_EQ(PlaneSide(a, a + r1, a + r2)(d), off * cross) << i;
    }
}

// PlaneSide gives orient3d's sign for every point: on axis-aligned planes (its comparison path:
// level brushes) and general ones (its filter, then orient3d), at wide magnitudes, with points on,
// one ulp off and far from the plane, and for degenerate (collinear) triangles.
TEST(BspTree, PlaneSideAgreesWithOrient3d) {
    Uniform01 next{11};
    int axisPlanes = 0, zeros = 0, offByUlp = 0;
    for (int i = 0; i < 20000; ++i) {
        const double scale = std::ldexp(1.0, int(next() * 60) - 30);  // 2^-30 .. 2^30
        auto coord = [&] { return (next() * 2 - 1) * scale; };
        Vec3 a{coord(), coord(), coord()}, b{coord(), coord(), coord()}, c{coord(), coord(), coord()};
        const int axis = i % 4;  // 3: a general plane
        if (axis < 3) {
            b[axis] = c[axis] = a[axis];
            ++axisPlanes;
        }
        if (i % 17 == 0) c = a + (b - a) * 2.0;  // collinear (up to rounding)
        const PlaneSide side(a, b, c);
        for (int j = 0; j < 8; ++j) {
            Vec3 d;
            switch (j % 4) {
            case 0: d = {coord(), coord(), coord()}; break;
            case 1: d = a + (b - a) * next() + (c - a) * next(); break;  // on the plane up to rounding
            case 2: d = j < 4 ? b : c; break;
            default: {
                d = a + (b - a) * next() + (c - a) * next();
                const int k = axis < 3 ? axis : int(next() * 3);
                d[k] = std::nextafter(axis < 3 ? a[k] : d[k], next() < 0.5 ? -INFINITY : INFINITY);
                break;
            }
            }
            const int want = orient3d(a, b, c, d);
            ASSERT_EQ(side(d), want) << "triangle " << i << ", point " << j;
            zeros += want == 0;
            offByUlp += j % 4 == 3 && want != 0;
        }
    }
    EXPECT_EQ(axisPlanes, 15000);
    EXPECT_GT(zeros, 20000);     // points on planes: the exact stages were reached
    EXPECT_GT(offByUlp, 10000);  // one ulp off a plane: the signs the filter must not guess
}

TEST(BspTree, EmptyAndSingle) {
    const Scene empty = looseTriangles({});
    const BspTree t0 = buildBspTree(empty);
    EXPECT_EQ(t0.nodes.size(), 0u);
    EXPECT_TRUE(bspBackToFront(t0, empty, topCamera()).empty());
    const Scene one = looseTriangles({{Vec3{0, 0, 0}, Vec3{1, 0, 0}, Vec3{0, 1, 0}}});
    const BspTree t1 = buildBspTree(one);
    EXPECT_EQ(t1.stats.nodes, 1u);
    EXPECT_EQ(t1.stats.depth, 1u);
    EXPECT_EQ(t1.stats.pieces, 1u);
    EXPECT_EQ(t1.stats.splits, 0u);
}

// A vertex exactly on the splitter's plane: the triangle touching it goes whole to one side (no
// split, no sliver); a triangle straddling it through that vertex splits into two triangles, not
// a triangle and a quad.
TEST(BspTree, VertexOnSplittingPlane) {
    const std::array<Vec3, 3> floor{Vec3{-10, -10, 0}, Vec3{10, -10, 0}, Vec3{0, 10, 0}};
    {
        const Scene s = looseTriangles({floor, {Vec3{0, 0, 0}, Vec3{1, 0, 1}, Vec3{0, 1, 1}}});
        const BspTree t = buildBspTree(s);
        EXPECT_EQ(t.nodes[0].planeSource, 0u);
        EXPECT_EQ(t.stats.splits, 0u);
        EXPECT_EQ(t.stats.pieces, 2u);
        EXPECT_EQ(t.stats.nodes, 2u);
        EXPECT_EQ(t.nodes[0].front, 1);
        EXPECT_EQ(t.nodes[0].back, -1);
    }
    {
        const Scene s = looseTriangles({floor, {Vec3{0, 0, 0}, Vec3{1, 0, 1}, Vec3{1, 1, -1}}});
        const BspTree t = buildBspTree(s);
        EXPECT_EQ(t.nodes[0].planeSource, 0u);
        EXPECT_EQ(t.stats.splits, 1u);
        EXPECT_EQ(t.stats.pieces, 3u);
        EXPECT_EQ(t.stats.trianglesOut, 3u);  // both halves are triangles: the vertex on the plane is shared
        EXPECT_EQ(t.stats.degeneratePieces, 0u);
        EXPECT_EQ(t.stats.splitSources, 1u);
        // The new vertex lies on the plane z = 0 (computed in double: exactly here, the edge's z runs
        // from 1 to -1 and the crossing is at t = 1/2).
        for (uint32_t p : t.nodePieces) {
            const BspPiece &pc = t.pieces[p];
            if (pc.source != 1) continue;
            EXPECT_EQ(pc.vertexCount, 3u);
            EXPECT_EQ(pc.constraintCount, 1u);
            bool hasNew = false;
            for (uint32_t i = 0; i < pc.vertexCount; ++i) {
                const Vec3 v = t.vertices[pc.firstVertex + i];
                if (v == Vec3{1, 0.5, 0}) hasNew = true;
            }
            EXPECT_TRUE(hasNew);
        }
    }
}

// Coplanar overlapping triangles stay on one node; drawn back to front they tie exactly (same
// plane): 0 wrong pixels, every pixel both cover is a tie where the higher id was drawn last.
TEST(BspTree, CoplanarOverlapping) {
    const Scene s = looseTriangles({{Vec3{-3, -3, 0}, Vec3{3, -3, 0}, Vec3{0, 3, 0}},
                                   {Vec3{-3, 3, 0}, Vec3{0, -3, 0}, Vec3{3, 3, 0}}});
    const BspTree t = buildBspTree(s);
    EXPECT_EQ(t.stats.nodes, 1u);
    EXPECT_EQ(t.stats.splits, 0u);
    EXPECT_EQ(t.nodes[0].pieceCount, 2u);
    const Camera cam = topCamera(100);
    const ReferenceVisibility ref = referenceVisibility(s, cam);
    const OrderingView v = prepareOrderingView(s, cam);
    const BspViewResult r = bspForView(v, ref, t);
    EXPECT_EQ(r.wrongPixels, 0u);
    // Overlap pixels: covered by both (counted with the fragment core through the reference's own
    // counts: fragments - covered pixels = pixels covered twice, as each pixel has at most 2).
    EXPECT_EQ(r.tiePixels, ref.fragments - ref.coveredPixels);
    EXPECT_GT(r.tiePixels, 0u);
}

// The cycle: no order of the three triangles is right; the BSP splits and gets every pixel right.
TEST(BspTree, CyclicOverlapSplitsAndIsExact) {
    const Scene s = looseTriangles(cyclicSticks());
    const BspTree t = buildBspTree(s);
    EXPECT_GE(t.stats.splits, 1u);
    EXPECT_EQ(t.stats.pieces, 3 + t.stats.splits);
    EXPECT_EQ(t.stats.degeneratePieces, 0u);
    const Camera cam = topCamera();
    const ReferenceVisibility ref = referenceVisibility(s, cam);
    ASSERT_GT(ref.coveredPixels, 0u);
    const OrderingView v = prepareOrderingView(s, cam);
    const BspViewResult r = bspForView(v, ref, t);
    EXPECT_EQ(r.wrongPixels, 0u);
    EXPECT_EQ(r.tiePixels, 0u);
    // Pieces partition their sources: back to front writes exactly the reference's fragments.
    EXPECT_EQ(r.backToFront.fragments, ref.fragments);
    // Front to back with the depth test: every fragment passes exactly once per pixel (nothing is
    // drawn behind what is already there), the least possible overdraw.
    EXPECT_EQ(r.frontToBack.depthPasses, ref.coveredPixels);
    EXPECT_DOUBLE_EQ(r.frontToBack.overdraw, 1.0);
}

// Two triangles passing through each other: the BSP cuts one along the other's plane.
TEST(BspTree, Interpenetrating) {
    const Scene s = looseTriangles({{Vec3{-4, -3, -1}, Vec3{4, -3, -1}, Vec3{0, 3, 1}},
                                   {Vec3{-4, 3, -1}, Vec3{0, -3, 1}, Vec3{4, 3, -1}}});
    const BspTree t = buildBspTree(s);
    EXPECT_EQ(t.stats.splits, 1u);
    EXPECT_EQ(t.stats.pieces, 3u);
    const Camera cam = topCamera();
    const ReferenceVisibility ref = referenceVisibility(s, cam);
    const OrderingView v = prepareOrderingView(s, cam);
    const BspViewResult r = bspForView(v, ref, t);
    EXPECT_EQ(r.wrongPixels, 0u);
}

// Classification does not depend on where the scene is: the cyclic sticks and the vertex-on-plane
// case scaled to 1e-3 (2^-10) features and moved 1e5 from the origin (exactly: every coordinate
// is a multiple of 2^-20 below 2^17) build the same tree as at the origin.
TEST(BspTree, FarFromOriginSameClassification) {
    auto scene = [](double scale, Vec3 off) {
        std::vector<std::array<Vec3, 3>> tris = cyclicSticks(scale, off);
        tris.push_back({off + Vec3{-10, -10, 0} * scale, off + Vec3{10, -10, 0} * scale, off + Vec3{0, 10, 0} * scale});
        tris.push_back({off + Vec3{0, 0, 0} * scale, off + Vec3{1, 0, 1} * scale, off + Vec3{0, 1, 1} * scale});
        tris.push_back({off + Vec3{0, 0, 0} * scale, off + Vec3{1, 0, 1} * scale, off + Vec3{1, 1, -1} * scale});
        return looseTriangles(tris);
    };
    const BspTree near = buildBspTree(scene(1, {}));
    const double s = std::ldexp(1.0, -10);
    const BspTree far = buildBspTree(scene(s, {1e5, 1e5, 1e5}));
    EXPECT_EQ(signature(near), signature(far));
    EXPECT_EQ(near.stats.splits, far.stats.splits);
    EXPECT_EQ(near.stats.degeneratePieces, 0u);
    EXPECT_EQ(far.stats.degeneratePieces, 0u);
    // And drawn from above, the far scene is exact too.
    const Scene fs = scene(s, {1e5, 1e5, 1e5});
    const Camera cam = topCamera(200, 10 * s, {1e5, 1e5, 1e5});
    const ReferenceVisibility ref = referenceVisibility(fs, cam);
    ASSERT_GT(ref.coveredPixels, 0u);
    const BspViewResult r = bspForView(prepareOrderingView(fs, cam), ref, far);
    EXPECT_EQ(r.wrongPixels, 0u);
}

// A closed mesh: a convex one splits nothing; from outside (single-sided) and from inside
// (double-sided, so the inner faces show) back to front is exact.
TEST(BspTree, ClosedMeshInsideAndOutside) {
    for (bool doubleSided : {false, true}) {
        SceneBuildInput in;
        Material m;
        m.doubleSided = doubleSided;
        in.materials = {m};
        SceneBuildInput::Object o;
        o.name = "sphere";
        o.geometry = uvSphereMesh({0, 0, 0}, 2, 24, 12);
        in.objects.push_back(std::move(o));
        SceneBuildInput::Object b;
        b.name = "box";
        b.geometry = boxMesh({0, 0, 0}, {0.5, 0.5, 0.5});
        in.objects.push_back(std::move(b));
        const Scene s = buildScene(std::move(in));
        const BspTree t = buildBspTree(s);
        EXPECT_EQ(t.stats.trianglesIn, s.objectTriangles.size());
        CameraSpec cs;
        cs.eye = doubleSided ? Vec3{1.1, 0.3, 0.2} : Vec3{0.5, 1, 7};  // between the box and the sphere / outside
        cs.target = doubleSided ? Vec3{-1, -0.2, 0.1} : Vec3{0, 0, 0};
        cs.width = 160;
        cs.height = 120;
        cs.nearZ = 0.05;
        Camera cam;
        std::string err;
        ASSERT_TRUE(makeCamera(cs, &cam, &err)) << err;
        const ReferenceVisibility ref = referenceVisibility(s, cam);
        ASSERT_GT(ref.coveredPixels, 0u);
        const BspViewResult r = bspForView(prepareOrderingView(s, cam), ref, t);
        EXPECT_EQ(r.wrongPixels, 0u) << (doubleSided ? "inside" : "outside");
        EXPECT_EQ(r.tiePixels, 0u);
    }
}

// The heuristic's knobs do what they say: "fewest splits" never splits more than "balance", and the
// default sits between; all build valid trees with the same drawn result.
TEST(BspTree, HeuristicsOnDemo) {
    const Scene s = demoScene();
    const BspTree fewest = buildBspTree(s, {16, 1, 0});
    const BspTree balanced = buildBspTree(s, {16, 0, 1});
    const BspTree dflt = buildBspTree(s);
    EXPECT_LE(fewest.stats.splits, balanced.stats.splits);
    EXPECT_LE(fewest.stats.splits, dflt.stats.splits);
    std::printf("demo BSP (%llu triangles): fewest splits %llu (depth %u), balanced %llu (depth %u), default %llu "
                "(depth %u, %.1f ms)\n",
                (unsigned long long)dflt.stats.trianglesIn, (unsigned long long)fewest.stats.splits,
                fewest.stats.depth, (unsigned long long)balanced.stats.splits, balanced.stats.depth,
                (unsigned long long)dflt.stats.splits, dflt.stats.depth, dflt.stats.buildMs);
    for (const ViewSpec &vs : s.views) {
        Camera cam;
        std::string err;
        CameraSpec spec = vs.camera;
        spec.width = 320;
        spec.height = 180;
        ASSERT_TRUE(makeCamera(spec, &cam, &err)) << err;
        const ReferenceVisibility ref = referenceVisibility(s, cam);
        const OrderingView v = prepareOrderingView(s, cam);
        for (const BspTree *t : {&fewest, &balanced, &dflt}) {
            const BspViewResult r = bspForView(v, ref, *t);
            EXPECT_EQ(r.wrongPixels, 0u) << vs.name;
        }
    }
}

}  // namespace
}  // namespace va
