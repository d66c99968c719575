// The catalogue of hard numeric cases (issue 9; docs/hard-cases.md lists them). Each case runs the
// real code path -- the loaders and the program where input is involved, the pipeline's stages
// otherwise -- and asserts an exact result derived by hand in its comment, with a sentence on why
// the case is hard.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "analysis/stages/backface.h"
#include "analysis/load/demo.h"
#include "analysis/load/load.h"
#include "analysis/pipeline.h"
#include "render/depth_format.h"
#include "tests/temp_dir_test.h"
#include "tests/test_util.h"

using namespace va;
using namespace va::testing_util;
namespace fs = std::filesystem;

namespace {

// ---- Shared set-up ------------------------------------------------------------------------------

// Orthographic view along -z from `eye`, 64 x 64 pixels, 64 world units high: the view's pixel
// coordinates are exactly px = x - eye.x + 32, py = 32 - (y - eye.y) (sx = sy = 1/32, halfW = halfH
// = 32: every step is a power-of-two scale of a dyadic number, so nothing rounds).
ViewSpec orthoView(Vec3 eye = {0, 0, 10}) {
    ViewSpec v;
    v.name = "ortho";
    v.camera.eye = eye;
    v.camera.target = eye - Vec3{0, 0, 1};
    v.camera.orthographic = true;
    v.camera.orthoHeight = 64;
    v.camera.nearZ = 0.5;
    v.camera.farZ = 100;
    v.camera.width = 64;
    v.camera.height = 64;
    return v;
}

// Perspective view from the origin along -z (up +y): view space is world space, exactly.
ViewSpec axisView(int w, int h, double fov, double nearZ, double farZ) {
    ViewSpec v = viewOf({0, 0, 0}, {0, 0, -1}, w, h, fov, nearZ, farZ);
    v.name = "axis";
    return v;
}

// Runs one view through the pipeline (with the Embree stage when s.raycast).
ViewResult run(const Scene &scene, const ViewSpec &view, const PipelineSettings &s = {}) {
    ViewSpec resolved;
    Camera cam;
    std::string err;
    EXPECT_TRUE(resolveView(view, s, &resolved, &cam, &err)) << err;
    PreparedScene ps;
    EXPECT_TRUE(prepareScene(scene, s, &ps, &err)) << err;
    return analyzeView(ps, resolved, cam, s);
}

PipelineSettings withoutBackface() {
    PipelineSettings s;
    s.backface = false;
    return s;
}

// The pixels of an id image equal to `id` (1 + source triangle; 0 = background).
uint64_t pixelsWithId(const std::vector<uint32_t> &ids, uint32_t id) {
    uint64_t n = 0;
    for (uint32_t v : ids) n += v == id;
    return n;
}

// A square (two CCW triangles seen from +z) at height z, half-size h, centered on the z axis.
RawMesh squareAt(double z, double h) {
    RawMesh m;
    m.positions = {{-h, -h, z}, {h, -h, z}, {h, h, z}, {-h, h, z}};
    m.indices = {0, 1, 2, 0, 2, 3};
    return m;
}

// ---- Files and the program ----------------------------------------------------------------------

class HardInput : public testing_util::TempDirTest {
  protected:
    HardInput() : TempDirTest("hard") {}

    std::string write(const std::string &name, const std::string &bytes) {
        const std::string p = (dir_ / name).string();
        std::ofstream(p, std::ios::binary) << bytes;
        return p;
    }
    std::string loadError(const std::string &path) {
        Scene s;
        std::string err;
        EXPECT_FALSE(loadScene(path, {}, &s, &err)) << path;
        return err;
    }
    // The program as a user runs it: exit code and stderr.
    struct Run {
        int code = -1;
        std::string err;
    };
    Run program(const std::string &args) {
        const std::string e = (dir_ / "stderr.txt").string();
        const std::string cmd = std::string(VISAUDIT_BINARY) + " " + args + " </dev/null >/dev/null 2>" + e;
        const int status = std::system(cmd.c_str());
        Run r;
        r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;  // a crash (signal) is never 2
        std::ifstream f(e);
        std::stringstream ss;
        ss << f.rdbuf();
        r.err = ss.str();
        return r;
    }
    // "FILE:LINE:COL" of the first occurrence of `needle` in `text` (1-based, as json::where).
    static std::string at(const std::string &file, const std::string &text, const std::string &needle) {
        const size_t off = text.find(needle);
        size_t line = 1, start = 0;
        for (size_t i = 0; i < off; ++i)
            if (text[i] == '\n') ++line, start = i + 1;
        return file + ":" + std::to_string(line) + ":" + std::to_string(off - start + 1);
    }
};

std::string le32(uint32_t v) {
    char b[4];
    std::memcpy(b, &v, 4);
    return std::string(b, 4);
}
std::string f32(float v) {
    char b[4];
    std::memcpy(b, &v, 4);
    return std::string(b, 4);
}

}  // namespace

// ---- Slivers below 1e-6 rad ---------------------------------------------------------------------

// Hard: at an angle of 6.5e-7 rad the sliver is 1/256 px wide at its wide end, so every covered
// sample lies on (or within a rounding error of) an edge; only exact fixed-point edge functions
// with the fill rule decide coverage deterministically, and float ray casting decides it by
// rounding. In pixel coordinates (orthoView: px = x + 32, py = 32 - y):
//   t0 = A (-3000, 31.5), C (3000, 31.5 + 1/256), B (3000, 31.5): interior below AB (larger y);
//   t1 = A, B, D (3000, 31.5 - 1/256): interior above AB;
//   t2 = E (-3000, 20.5), F (3000, 20.5 + 1/1024), G (3000, 20.5): 1.6e-7 rad.
// Each is counter-clockwise seen from +z (the eye), so front-facing. AB is a horizontal edge with
// the interior below for t0: a top edge, so the 64 centers (x + 0.5, 31.5) on it are covered by t0
// (strictly inside its other two edges, since 31.5 < AC's y for x > -3000 and x < 3000); for t1 it
// is a bottom edge: no center. t1 covers no other center (its interior is within 1/256 px of row
// 31's centers). t2's apex snaps to 20.5 * 256 + 0.25 -> 5248 = its base: snapped area 0, nothing.
// So: fragments 64, covered 64 (row 31), each once; t0 drawn, t1 and t2 empty. All vertices lie
// within the 8192-px guard band: three guard-band accepts. Embree's float test may or may not
// count the centers on AB (and on t2's base row 20) as hits, but each such pixel is within the
// coverage tolerance of an edge: the cross-check classes it edge, never genuine, and agrees
// everywhere else.
TEST(HardCases, SliversBelowOneMicroradianCoverExactlyByTheFillRule) {
    const Vec3 A{-3032, 0.5, 0}, B{2968, 0.5, 0}, C{2968, 0.5 - 1.0 / 256, 0}, D{2968, 0.5 + 1.0 / 256, 0};
    const Vec3 E{-3032, 11.5, 0}, F{2968, 11.5 - 1.0 / 1024, 0}, G{2968, 11.5, 0};
    // Angles at A and E, well below 1e-6 rad.
    EXPECT_LT(std::atan((1.0 / 256) / 6000), 1e-6);
    const Scene scene = looseTriangles({{A, C, B}, {A, B, D}, {E, F, G}});
    ASSERT_EQ(scene.stats.degenerateTriangles, 0u);  // their world cross products are not zero
    const ViewResult r = run(scene, orthoView());

    EXPECT_EQ(r.backface.trianglesCulled, 0u);
    EXPECT_EQ(r.clip.guardBandAccepted, 3u);
    EXPECT_EQ(r.clip.clipped, 0u);
    EXPECT_EQ(r.zbuffer.trianglesIn, 3u);
    EXPECT_EQ(r.zbuffer.trianglesDrawn, 1u);
    EXPECT_EQ(r.zbuffer.trianglesEmpty, 2u);
    EXPECT_EQ(r.zbuffer.fragments, 64u);
    EXPECT_EQ(r.zbuffer.coveredPixels, 64u);
    EXPECT_EQ(r.zbuffer.maxDepthComplexity, 1u);
    for (int x = 0; x < 64; ++x) EXPECT_EQ(r.buffer.id[31 * 64 + x], 1u) << "x " << x;  // t0 on row 31
    EXPECT_EQ(pixelsWithId(r.buffer.id, 1), 64u);
    // The reference visibility walks the same fragment core: the same 64 pixels.
    EXPECT_EQ(r.audit->reference.coveredPixels, 64u);
    EXPECT_EQ(r.audit->reference.id, r.buffer.id);

    ASSERT_TRUE(r.raycast.ran());
    const CrossCheck &c = r.raycast->crossCheck;
    EXPECT_EQ(c.genuine, 0u);
    EXPECT_EQ(c.tie, 0u);
    EXPECT_EQ(c.agree + c.edge, 64u * 64u);
    for (size_t i = 0; i < c.cls.size(); ++i)
        if (c.cls[i] != uint8_t(Disagreement::none)) {
            const size_t y = i / 64;
            EXPECT_TRUE(y == 31 || y == 20) << "disagreement off the sliver rows at pixel " << i;
        }
}

// ---- Triangles with all three vertices on one frustum plane --------------------------------------

// Hard: a vertex exactly on a clip plane is neither in nor out by a margin; the clipper must treat
// "on" as inside (d >= near, d <= far) without cutting, and the depth format must accept d = n and
// d = f exactly. axisView: view space = world space, so the vertices lie on the planes exactly.
//   near (z = -1, n = 1): the triangle (-10,-10), (10,-10), (0,10) projects to about 10 NDC units
//   on each side (sx = sy = 1/tan(45 deg) = 1 + 2^-52): it contains the NDC square [-1,1]^2 (its
//   slanted edges cross y = +-1 at |x| >= 4.5), so all 16 x 16 = 256 centers are covered; its
//   vertices stay inside the guard band (|x_n| <= 10.1 < 1 + 8192/8): one guard-band accept, no
//   clipping. Its depth plane is 1/d = c with c = -(0 + 0 - 400)/400 = 1 exactly: depth 1.0 at
//   every pixel, f32 value f(d - n)/(d(f - n)) = 0, in range.
//   far (z = -100, f = 100): the same triangle scaled by 100; c = 4e6/4e8 = fl(0.01) and
//   1/fl(0.01) rounds to 100 exactly (|1/fl(0.01) - 100| = 2.1e-15 < ulp(100)/2 = 7.1e-15); the
//   f32 value is 100 * 99 / (100 * 99) = 1.0f, in range and below the cleared key.
TEST(HardCases, TrianglesOnTheNearAndFarPlanesAreDrawnWhole) {
    for (const double z : {-1.0, -100.0}) {
        const double k = -z * 10;
        const Scene scene = looseTriangles({{Vec3{-k, -k, z}, Vec3{k, -k, z}, Vec3{0, k, z}}});
        const ViewResult r = run(scene, axisView(16, 16, 90, 1, 100));
        EXPECT_EQ(r.frustum.objectsCulled, 0u) << z;
        EXPECT_EQ(r.clip.trivialRejected, 0u) << z;
        EXPECT_EQ(r.clip.guardBandAccepted, 1u) << z;
        EXPECT_EQ(r.clip.clipped, 0u) << z;
        EXPECT_EQ(r.clip.trianglesOut, 1u) << z;
        EXPECT_EQ(r.zbuffer.fragments, 256u) << z;
        EXPECT_EQ(r.zbuffer.coveredPixels, 256u) << z;
        EXPECT_EQ(r.zbuffer.outOfRangeFragments, 0u) << z;
        for (double d : r.buffer.depth) ASSERT_EQ(d, -z);
        const DepthEncoder e = makeDepthEncoder(DepthFormat::f32, 1, 100);
        for (uint32_t key : r.buffer.key) ASSERT_EQ(key, depthKey(e, -z));
        EXPECT_EQ(depthStoredValue(e, -z), z == -1.0 ? 0.0 : 1.0);
    }
}

// Hard: a side plane of the frustum contains the view direction (orthographic) or the eye
// (perspective), so a triangle on it is seen edge-on: it must be dropped as such, not trivially
// rejected by an outcode that rounding could flip, nor drawn as a line of pixels.
// orthoView from (0,0,0): the left plane is x = -32 exactly (x_c = -32/32 = -1 = -w, not < -w).
// The triangle's normal is (-70, 0, 0): the backface stage finds n . forward == 0 (edge-on,
// culled); without it, the clipper finds n.z == 0 (no depth plane: edge-on). Nothing is drawn.
TEST(HardCases, TriangleOnASidePlaneIsEdgeOn) {
    const Scene scene = looseTriangles({{Vec3{-32, -10, -1}, Vec3{-32, 10, -2}, Vec3{-32, 0, -5}}});
    const ViewSpec view = orthoView({0, 0, 0});
    const ViewResult r = run(scene, view);
    EXPECT_EQ(r.backface.trianglesCulled, 1u);
    EXPECT_EQ(r.backface.edgeOn, 1u);
    EXPECT_EQ(r.zbuffer.fragments, 0u);
    const ViewResult nb = run(scene, view, withoutBackface());
    EXPECT_EQ(nb.clip.trivialRejected, 0u);
    EXPECT_EQ(nb.clip.edgeOn, 1u);
    EXPECT_EQ(nb.clip.trianglesOut, 0u);
    EXPECT_EQ(nb.zbuffer.fragments, 0u);
    EXPECT_EQ(nb.audit->reference.coveredPixels, 0u);
}

// Hard: two vertices on the near plane and one behind it: Sutherland-Hodgman computes both
// intersections at t = 0/(0 - dq) = 0, i.e. the on-plane vertices themselves, so the output is the
// zero-area quadrilateral (a, b, b, a): nothing behind the eye is projected and nothing is drawn.
// axisView(16, 16, 90, 1, 100): a = (-1,-1,-1), b = (1,-1,-1) on near (d = 1), c = (0,1,-0.5)
// behind it. Only the near bit is a clipping bit (the side bits of a and c are viewport bits
// inside the guard band): one clipped triangle, one cut against near, a 4-vertex polygon, two fan
// triangles, both empty. The plane (0,-1,4).p + 3 is > 0 at the eye: front-facing.
TEST(HardCases, TriangleTouchingNearFromBehindClipsToZeroArea) {
    const Scene scene = looseTriangles({{Vec3{-1, -1, -1}, Vec3{1, -1, -1}, Vec3{0, 1, -0.5}}});
    const ViewResult r = run(scene, axisView(16, 16, 90, 1, 100));
    EXPECT_EQ(r.backface.trianglesCulled, 0u);
    EXPECT_EQ(r.clip.clipped, 1u);
    EXPECT_EQ(r.clip.perPlane, (std::array<uint64_t, kClipPlaneCount>{1, 0, 0, 0, 0, 0}));
    EXPECT_EQ(r.clip.polygonVertices[4], 1u);
    EXPECT_EQ(r.clip.clippedAway, 0u);
    EXPECT_EQ(r.clip.trianglesOut, 2u);
    EXPECT_EQ(r.zbuffer.trianglesEmpty, 2u);
    EXPECT_EQ(r.zbuffer.fragments, 0u);
}

// ---- The eye exactly on a triangle's plane -----------------------------------------------------

// Hard: the plane's value at the eye is exactly 0, so its sign is pure rounding unless decided
// exactly. Axis-aligned: the triangle lies in y = 0 and the eye (0,0,0) too; its plane value is 0
// in double as well, inside the filter's error bound, so CGAL's orientation decides: 0, edge-on,
// culled. Without the backface stage the clipper's view-space plane has k = -n.v0 = -(4 * 0) = 0
// exactly: edge-on, dropped.
TEST(HardCases, EyeOnTheTrianglePlaneAxisAligned) {
    const Scene scene = looseTriangles({{Vec3{-1, 0, -2}, Vec3{1, 0, -2}, Vec3{0, 0, -4}}});
    const ViewSpec view = axisView(32, 32, 60, 0.1, 100);
    const ViewResult r = run(scene, view);
    EXPECT_EQ(r.backface.edgeOn, 1u);
    EXPECT_EQ(r.backface.trianglesCulled, 1u);
    EXPECT_EQ(r.zbuffer.fragments, 0u);
    const ViewResult nb = run(scene, view, withoutBackface());
    EXPECT_EQ(nb.clip.edgeOn, 1u);
    EXPECT_EQ(nb.zbuffer.fragments, 0u);
}

// Hard: here the double evaluation of the plane at the eye is -2^-51, not 0 -- only the exact
// predicate knows the eye is on the plane. v1 = 4 v0 (exact in binary), so the eye (the origin)
// lies on the line v0 v1 and hence on the plane, exactly. Projected, v0 and v1 coincide bit for bit
// (view space = world space; x_c, w and x_c / w all scale by 4 exactly), so the screen triangle has
// zero snapped area: whatever the clipper's rounded view-space plane says, nothing is drawn, in the
// z-buffer and in the reference visibility alike. The ray caster must not report a genuine
// disagreement either.
TEST(HardCases, EyeOnTheTrianglePlaneNeedsTheExactPredicate) {
    const Vec3 v0{0.1, 0.7, -1.3}, v1 = v0 * 4, v2{-0.37, 0.21, -2.9};
    const Scene scene = looseTriangles({{v0, v1, v2}});
    EXPECT_EQ(scene.planes[3], -std::ldexp(1.0, -51));  // n . eye + k with eye = 0: k, rounded
    Camera cam;
    std::string err;
    const ViewSpec view = axisView(32, 32, 60, 0.1, 100);
    ASSERT_TRUE(makeCamera(view.camera, &cam, &err)) << err;
    bool edgeOn = false;
    EXPECT_FALSE(isFrontFacing(scene, 0, cam, &edgeOn));
    EXPECT_TRUE(edgeOn);

    const ViewResult r = run(scene, view);
    EXPECT_EQ(r.backface.edgeOn, 1u);
    EXPECT_EQ(r.zbuffer.fragments, 0u);
    EXPECT_EQ(r.audit->reference.coveredPixels, 0u);
    EXPECT_EQ(r.audit->cull.falseCullTriangles, 0u);
    EXPECT_EQ(r.raycast->crossCheck.genuine, 0u);
    const ViewResult nb = run(scene, view, withoutBackface());
    EXPECT_EQ(nb.clip.edgeOn + nb.clip.trianglesOut, 1u);
    EXPECT_EQ(nb.zbuffer.trianglesEmpty, nb.clip.trianglesOut);
    EXPECT_EQ(nb.zbuffer.fragments, 0u);
    EXPECT_EQ(nb.raycast->crossCheck.genuine, 0u);
}

// ---- near = 1e-6, far = 1e9 -------------------------------------------------------------------

// Hard: a ratio f/n = 1e15 leaves the standard projective formats no precision past a few tens of
// units, while the 1/d integer formats cannot even represent depths below 1. Keys by hand
// (n = 1e-6, f = 1e9, z = f (d - n)/(d (f - n)), 1 - z = n (f - d)/(d (f - n)) ~ n/d):
//  * d = 40 vs 50: 1 - z = 2.5e-8 and 2e-8, both below 2^-25 (half a float ulp under 1): f32 stores
//    1.0f (key 0x3F800000) for both; 16777215 z = 16777215 - 0.42 and - 0.34 round to 16777215 for
//    unorm24 (65535 for unorm16); unorm24_gl's float z_ndc = 1 - 5e-8 and 1 - 4e-8 round to
//    1 - 2^-24, and 0.5 z_ndc + 0.5 = 1 - 2^-25 ties to 1.0f: 16777215 too. Every other format
//    separates them: float(d), float(1/d), floor((2^31-1)/d) = 53687091 vs 42949672, and so on;
//    f32_reversed's n (f - d)/(d (f - n)) ~ 2.5e-8 vs 2e-8 are distinct floats; log24's
//    16777215 log(d + 1)/log(f + 1) = 3006446.8 vs 3183141.3.
//  * d = 2e-6 vs 3e-6: int31_inv and uint32_inv need d >= 1 (their value (2^N - 1)/d overflows
//    otherwise): both clamp to d = 1, keys 0 (the nearest), out of range; log24 gives 1.62 and 2.43,
//    both round to key 2. The others separate them (z = 1/2 vs 2/3; uint32_inv1 = 4294958705 vs
//    4294954410; n/d = 0.5 vs 0.33).
TEST(HardCases, NearOneMicroFarOneBillionResolvesExactlyTheseSeparations) {
    using F = DepthFormat;
    // The formats issue 19 added collapse 40 and 50 with their models: reversed-Z on an integer
    // buffer moves no bucket (unorm*_reversed: the keys of unorm*, reversed), WebGPU's
    // depth32float and depth24plus are f32 and unorm24, and OpenGL's [-1, 1] range keeps float's
    // rounding of z_ndc near 1 whether reversed or not (f32_gl, f32_gl_reversed: no clip control).
    const std::vector<F> collapseFar = {F::unorm16,          F::unorm24,     F::unorm24_gl,  F::f32,
                                        F::unorm16_reversed, F::unorm24_reversed, F::f32_gl, F::f32_gl_reversed,
                                        F::depth32float,     F::depth24plus};
    const std::vector<F> collapseNear = {F::int31_inv, F::uint32_inv, F::log24};
    auto in = [](const std::vector<F> &l, F f) { return std::find(l.begin(), l.end(), f) != l.end(); };
    for (F f : allDepthFormats()) {
        const DepthEncoder e = makeDepthEncoder(f, 1e-6, 1e9);
        const char *name = depthFormatInfo(f).name;
        bool oor40 = false, oor50 = false;
        const uint32_t k40 = depthKey(e, 40, &oor40), k50 = depthKey(e, 50, &oor50);
        EXPECT_FALSE(oor40 || oor50) << name;
        if (in(collapseFar, f))
            EXPECT_EQ(k40, k50) << name;
        else
            EXPECT_LT(k40, k50) << name;
        bool oor2 = false, oor3 = false;
        const uint32_t k2 = depthKey(e, 2e-6, &oor2), k3 = depthKey(e, 3e-6, &oor3);
        EXPECT_EQ(oor2, f == F::int31_inv || f == F::uint32_inv) << name;
        EXPECT_EQ(oor3, f == F::int31_inv || f == F::uint32_inv) << name;
        if (in(collapseNear, f))
            EXPECT_EQ(k2, k3) << name;
        else
            EXPECT_LT(k2, k3) << name;
    }
    EXPECT_EQ(depthKey(makeDepthEncoder(F::f32, 1e-6, 1e9), 40), 0x3F800000u);
    EXPECT_EQ(depthKey(makeDepthEncoder(F::unorm24, 1e-6, 1e9), 40), 16777215u);
    EXPECT_EQ(depthKey(makeDepthEncoder(F::unorm24_gl, 1e-6, 1e9), 50), 16777215u);
    EXPECT_EQ(depthKey(makeDepthEncoder(F::int31_inv, 1e-6, 1e9), 2e-6), 0u);
    EXPECT_EQ(depthKey(makeDepthEncoder(F::uint32_inv, 1e-6, 1e9), 3e-6), 0u);
    EXPECT_EQ(depthKey(makeDepthEncoder(F::log24, 1e-6, 1e9), 2e-6), 2u);
    EXPECT_EQ(depthKey(makeDepthEncoder(F::log24, 1e-6, 1e9), 3e-6), 2u);
}

// The same through the z-buffer: a full-screen square at d = 50 (object 0, drawn first) and one at
// d = 40 (object 1). The squares (half-size 100) cover the 90-degree view at both depths (40 and 50
// < 100). Where the format separates 40 from 50, the nearer square wins all 64 pixels (128
// fragments, 128 depth passes); where it collapses them, the keys tie and LESS keeps the first
// drawn, the far square, everywhere (64 passes).
TEST(HardCases, NearOneMicroFarOneBillionThroughTheZBuffer) {
    const Scene scene = sceneOf({squareAt(-50, 100), squareAt(-40, 100)});
    for (DepthFormat f : allDepthFormats()) {
        using F = DepthFormat;  // as the test above: the issue-19 formats collapse 40 and 50 too
        const bool collapses = f == F::unorm16 || f == F::unorm24 || f == F::unorm24_gl || f == F::f32 ||
                               f == F::unorm16_reversed || f == F::unorm24_reversed || f == F::f32_gl ||
                               f == F::f32_gl_reversed || f == F::depth32float || f == F::depth24plus;
        ViewSpec view = axisView(8, 8, 90, 1e-6, 1e9);
        view.depthFormat = f;
        PipelineSettings s;
        s.raycast = false;
        const ViewResult r = run(scene, view, s);
        const char *name = depthFormatInfo(f).name;
        EXPECT_EQ(r.zbuffer.fragments, 128u) << name;
        EXPECT_EQ(r.zbuffer.depthPasses, collapses ? 64u : 128u) << name;
        EXPECT_EQ(pixelsWithId(r.buffer.id, 1) + pixelsWithId(r.buffer.id, 2), collapses ? 64u : 0u) << name;
        EXPECT_EQ(pixelsWithId(r.buffer.id, 3) + pixelsWithId(r.buffer.id, 4), collapses ? 0u : 64u) << name;
        EXPECT_EQ(r.zbuffer.outOfRangeFragments, 0u) << name;
    }
}

// ---- A scene 1e7 units from the origin ---------------------------------------------------------

// Hard: at 1e7 a double's ulp is 1.9e-9, so world-to-view (r.p + (-r.eye), the view matrix) loses
// the low bits of both products before they cancel. Every coordinate here and T = 1e7 are dyadic
// with few bits, so the shifted scene and camera are exact and the basis is the same (it depends
// on target - eye only). A view-space coordinate is then off by at most ~7 roundings at magnitudes
// <= 3.5e7 (half-ulp 1.9e-9 each): 1.3e-8 absolute, i.e. 1.3e-8 / 8 = 1.7e-9 relative at the
// scene's view depths (>= 8): far below a snapping step (1/256 px = 1.1e-3 units here), so every
// snapped vertex, fragment, id and count is identical to the scene at the origin, and each depth
// agrees within a relative 1e-8. The ray caster's float frame is the scene's bounds center
// ((lo + hi)/2, exact here), so its rays are identical too.
TEST(HardCases, SceneTenMillionUnitsAwayMatchesTheSceneAtTheOrigin) {
    const Vec3 T{1e7, 1e7, 1e7};
    auto meshes = [](Vec3 t) {
        std::vector<RawMesh> m = {boxMesh(Vec3{0, 0, 0} + t, {1, 1, 1}), boxMesh(Vec3{3, 0.5, -2} + t, {0.5, 1.5, 0.75}),
                                  boxMesh(Vec3{-2.5, -0.25, 1.5} + t, {1, 0.5, 1}),
                                  boxMesh(Vec3{0.25, -1.5, 0} + t, {6, 0.125, 6})};
        return m;
    };
    const Scene near = sceneOf(meshes({0, 0, 0})), far = sceneOf(meshes(T));
    ViewSpec v = axisView(64, 48, 60, 0.1, 100);
    v.camera.eye = {6.5, 4.25, 9.75};
    v.camera.target = {0.5, 0.25, -0.125};
    ViewSpec vf = v;
    vf.camera.eye = v.camera.eye + T;
    vf.camera.target = v.camera.target + T;
    const ViewResult a = run(near, v), b = run(far, vf);
    ASSERT_EQ(a.stages.size(), b.stages.size());
    for (size_t i = 0; i < a.stages.size(); ++i) {
        EXPECT_EQ(a.stages[i].trianglesIn, b.stages[i].trianglesIn) << a.stages[i].name;
        EXPECT_EQ(a.stages[i].trianglesOut, b.stages[i].trianglesOut) << a.stages[i].name;
    }
    EXPECT_EQ(a.backface.trianglesCulled, b.backface.trianglesCulled);
    EXPECT_EQ(a.clip.trianglesOut, b.clip.trianglesOut);
    EXPECT_EQ(a.zbuffer.fragments, b.zbuffer.fragments);
    EXPECT_EQ(a.zbuffer.depthPasses, b.zbuffer.depthPasses);
    EXPECT_EQ(a.zbuffer.coveredPixels, b.zbuffer.coveredPixels);
    EXPECT_GT(a.zbuffer.coveredPixels, 0u);
    EXPECT_TRUE(a.buffer.id == b.buffer.id) << "id images differ";
    double worst = 0;
    for (size_t i = 0; i < a.buffer.depth.size(); ++i)
        if (a.buffer.id[i]) worst = std::max(worst, std::fabs(a.buffer.depth[i] - b.buffer.depth[i]) / a.buffer.depth[i]);
    EXPECT_LE(worst, 1e-8);
    EXPECT_TRUE(a.audit->reference.id == b.audit->reference.id) << "reference id images differ";
    EXPECT_TRUE(a.raycast->image.id == b.raycast->image.id) << "raycast id images differ";
    EXPECT_EQ(a.raycast->crossCheck.genuine, 0u);
    EXPECT_EQ(b.raycast->crossCheck.genuine, 0u);
    EXPECT_EQ(a.audit->cull.falseCullTriangles, b.audit->cull.falseCullTriangles);
    EXPECT_EQ(b.audit->cull.falseCullTriangles, 0u);
}

// ---- A triangle whose projection spans 1e9 pixels ----------------------------------------------

// Hard: 1e9 px in 8-bit fixed point is 2^38, past the rasterizer's 32-bit range; only clipping at
// the guard band keeps it drawable, and the cut must not move the edge that crosses the viewport.
// orthoView: A (-1e9, 0), B (1e9, 0), C (0, -1e9) (world) are 1e9 px away; AB is the line py = 32,
// between pixel rows 31 and 32. A is beyond the left guard plane, B the right, C the bottom:
// clipped against those three (the top guard plane is never crossed). The cuts of AB interpolate
// two vertices with y = 0, so y stays 0; inside the guard square [-257, 257]^2 (NDC) the triangle
// is the rectangle [-257, 257] x [-257, 0] (its slanted edges, |x| + |y| = 3.1e7 NDC, are far
// outside): Sutherland-Hodgman ends with its 4 corners, fanned into 2 triangles sharing a diagonal
// (drawn once, fill rule). Covered: rows 32..63, all 64 columns: 32 * 64 = 2048 pixels, once each.
// Perspective: the triangle (-1e8,-1e8,-1), (1e8,-1e8,-1), (0,1e8,-1) spans 3.2e9 px at 64 x 64
// and contains the whole view: all 4096 pixels, once each.
TEST(HardCases, BillionPixelTriangleIsClippedToTheGuardBand) {
    {
        const Scene scene = looseTriangles({{Vec3{-1e9, 0, 0}, Vec3{0, -1e9, 0}, Vec3{1e9, 0, 0}}});
        const ViewResult r = run(scene, orthoView());
        EXPECT_EQ(r.clip.clipped, 1u);
        EXPECT_EQ(r.clip.perPlane, (std::array<uint64_t, kClipPlaneCount>{0, 0, 1, 1, 1, 0}));
        EXPECT_EQ(r.clip.polygonVertices[4], 1u);
        EXPECT_EQ(r.clip.trianglesOut, 2u);
        EXPECT_EQ(r.zbuffer.fragments, 2048u);
        EXPECT_EQ(r.zbuffer.coveredPixels, 2048u);
        EXPECT_EQ(r.zbuffer.maxDepthComplexity, 1u);
        for (int y = 0; y < 64; ++y)
            for (int x = 0; x < 64; ++x) ASSERT_EQ(r.buffer.id[y * 64 + x], y >= 32 ? 1u : 0u) << x << "," << y;
        EXPECT_EQ(r.raycast->crossCheck.genuine, 0u);
    }
    {
        const Scene scene = looseTriangles({{Vec3{-1e8, -1e8, -1}, Vec3{1e8, -1e8, -1}, Vec3{0, 1e8, -1}}});
        const ViewResult r = run(scene, axisView(64, 64, 90, 0.5, 100));
        EXPECT_EQ(r.clip.clipped, 1u);
        EXPECT_EQ(r.zbuffer.fragments, 4096u);
        EXPECT_EQ(r.zbuffer.coveredPixels, 4096u);
        EXPECT_EQ(r.zbuffer.maxDepthComplexity, 1u);
        EXPECT_EQ(r.raycast->crossCheck.genuine, 0u);
    }
}

// ---- NaN and infinity in vertex data, transforms and views -------------------------------------

// Hard: NaN compares false with everything, so a NaN vertex slips through every range test
// (bounds, outcodes, spheres) and poisons whatever it touches; binary formats can hold it
// directly. A non-finite coordinate means a damaged file: refused, naming the file and the vertex
// (OBJ: its line), exit 2 from the program -- never a crash, never a silently smaller scene.
TEST_F(HardInput, NonFiniteVertexDataIsRefusedNamingFileAndVertex) {
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    // Binary PLY: vertex 1 (0-based, as the faces index it) has y = NaN.
    std::string ply =
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    for (float v : {0.f, 0.f, 0.f, 1.f, nan, 0.f, 0.f, 1.f, 0.f}) ply += f32(v);
    ply += std::string(1, '\3') + le32(0) + le32(1) + le32(2);
    const std::string plyPath = write("nan.ply", ply);
    EXPECT_EQ(loadError(plyPath), plyPath + ": vertex 1 (counting from 0) has a non-finite coordinate (1, nan, 0); "
                                            "the file is damaged: write finite numbers");
    // Binary STL: facet 1 (0-based) has an infinite x in its third vertex.
    std::string stl(80, ' ');
    stl += le32(2);
    const float facets[2][9] = {{0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 0, 1, 1, 0, 1, inf, 1, 1}};
    for (const auto &f : facets) {
        for (int k = 0; k < 3; ++k) stl += f32(0);  // normal
        for (float v : f) stl += f32(v);
        stl += std::string(2, '\0');
    }
    const std::string stlPath = write("inf.stl", stl);
    const std::string stlErr = loadError(stlPath);
    EXPECT_EQ(stlErr.rfind(stlPath + ": vertex ", 0), 0u) << stlErr;
    EXPECT_NE(stlErr.find("has a non-finite coordinate (inf, 1, 1)"), std::string::npos) << stlErr;
    // OBJ (OpenMesh skips the vertex; the line is named).
    const std::string objPath = write("nan.obj", "v 0 0 0\nv 1 0 0\nv 0 inf 0\nf 1 2 3\n");
    EXPECT_EQ(loadError(objPath).rfind(objPath + ":3: vertex 'v 0 inf 0': coordinate is not a finite number", 0), 0u);
    for (const std::string &p : {plyPath, stlPath, objPath}) {
        const Run r = program("analyze " + p + " --width 32 --height 24 --out " + (dir_ / "out").string());
        EXPECT_EQ(r.code, 2) << p << "\n" << r.err;
        EXPECT_NE(r.err.find(p), std::string::npos) << r.err;
        EXPECT_FALSE(fs::exists(dir_ / "out"));
    }
}

// Hard: finite inputs can still overflow: a JSON literal beyond the double range parses as
// infinity in most parsers, and a finite scale times a finite coordinate can exceed 1.8e308. Either
// is refused with the scene file's line and column: the literal by the JSON parser, at itself; the
// overflowing product at the object's "scale" (1e300 * 1e10 = 1e310 > DBL_MAX), naming the vertex.
TEST_F(HardInput, NonFiniteTransformIsRefusedAtTheObject) {
    write("tri.obj", "v 0 0 0\nv 1e10 0 0\nv 0 1 0\nf 1 2 3\n");
    const std::string lit = "{\"format\": \"visaudit-scene/1\",\n \"objects\": [{\"mesh\": \"tri.obj\", \"translate\": [0, 1e999, 0]}]}\n";
    const std::string litPath = write("lit.scene.json", lit);
    EXPECT_EQ(loadError(litPath), at(litPath, lit, "1e999") + ": JSON error: number overflow parsing '1e999' (the number "
                                                             "does not fit a double)");
    const std::string big = "{\"format\": \"visaudit-scene/1\",\n \"objects\": [{\"mesh\": \"tri.obj\", \"scale\": 1e300}]}\n";
    const std::string bigPath = write("big.scene.json", big);
    EXPECT_EQ(loadError(bigPath), at(bigPath, big, "1e300") + ": objects[0].scale: the transform maps vertex 1 of 'tri.obj' "
                                                             "(counting from 0) to a non-finite position; use a smaller "
                                                             "scale or translation");
    for (const std::string &p : {litPath, bigPath}) {
        const Run r = program("analyze " + p + " --width 32 --height 24 --out " + (dir_ / "out").string());
        EXPECT_EQ(r.code, 2) << p << "\n" << r.err;
        EXPECT_NE(r.err.find(p + ":"), std::string::npos) << r.err;
    }
}

// Hard: a view's vectors feed a normalization; an infinite component (a literal), or two finite
// points whose difference overflows (1e308 - (-1e308)), turns the basis into NaN, which every
// later test would silently pass. Refused at the view's key, with the file's line and column.
TEST_F(HardInput, NonFiniteViewIsRefusedAtTheKey) {
    const std::string text = "{\"views\": [\n"
                             "{\"name\": \"a\", \"eye\": [0, 0, 1e999], \"target\": [0, 0, 0]}]}\n";
    const std::string p = write("inf.views.json", text);
    std::vector<ViewSpec> views;
    std::string err;
    EXPECT_FALSE(loadViewsFile(p, &views, &err));
    EXPECT_EQ(err, at(p, text, "1e999") + ": JSON error: number overflow parsing '1e999' (the number does not fit a double)");

    const std::string far = "{\"views\": [\n"
                            "{\"name\": \"a\", \"eye\": [1e308, 0, 0], \"target\": [-1e308, 0, 0]}]}\n";
    const std::string q = write("far.views.json", far);
    EXPECT_FALSE(loadViewsFile(q, &views, &err));
    EXPECT_EQ(err, at(q, far, "[-1e308") + ": views[0]: \"target\" - \"eye\" overflows a double; bring the camera "
                                           "and its target closer together");
    const Run r = program("analyze --views " + q + " --width 32 --height 24 --out " + (dir_ / "out").string());
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find(q + ":2:"), std::string::npos) << r.err;
}

// ---- Degenerate cameras -------------------------------------------------------------------------

// Hard: a camera basis is two normalizations and a cross product; a zero or parallel up vector,
// or eye == target, divides 0 by 0. Each is refused at its key: up [0,0,0] has length 0; up
// [0,0,-3] is parallel to the view direction (0,0,-1) (|f x u| = 0); eye == target leaves no
// direction; "direction": [0,0,0] likewise. Through the program: exit 2 and the same place.
TEST_F(HardInput, DegenerateCameraIsRefusedAtTheKey) {
    const std::string text = "{\"views\": [\n"
                             "{\"eye\": [0, 0, 5], \"target\": [0, 0, 0], \"up\": [0, 0, 0]},\n"
                             "{\"eye\": [0, 0, 5], \"target\": [0, 0, 0], \"up\": [0, 0, -3]},\n"
                             "{\"eye\": [1, 2, 3], \"target\": [1, 2, 3]},\n"
                             "{\"eye\": [1, 2, 3], \"direction\": [0, 0, 0]}]}\n";
    struct Case {
        std::string line, needle, message;
    };
    const std::vector<Case> cases = {
        {"{\"eye\": [0, 0, 5], \"target\": [0, 0, 0], \"up\": [0, 0, 0]}", "[0, 0, 0]}",
         "views[0]: \"up\" has zero length; try [0, 1, 0]"},
        {"{\"eye\": [0, 0, 5], \"target\": [0, 0, 0], \"up\": [0, 0, -3]}", "[0, 0, -3]",
         "views[0]: \"up\" is parallel to the view direction; choose another up vector"},
        {"{\"eye\": [1, 2, 3], \"target\": [1, 2, 3]}", "[1, 2, 3]",
         "views[0]: \"eye\" equals \"target\"; the view has no direction"},
        {"{\"eye\": [1, 2, 3], \"direction\": [0, 0, 0]}", "[0, 0, 0]",
         "views[0].direction: has zero length; give the direction to look in"},
    };
    for (size_t i = 0; i < cases.size(); ++i) {
        const std::string t = "{\"views\": [\n" + cases[i].line + "]}\n";
        const std::string p = write("cam" + std::to_string(i) + ".views.json", t);
        std::vector<ViewSpec> views;
        std::string err;
        EXPECT_FALSE(loadViewsFile(p, &views, &err));
        EXPECT_EQ(err, at(p, t, cases[i].needle) + ": " + cases[i].message);
        const Run r = program("analyze --views " + p + " --width 32 --height 24 --out " + (dir_ / "out").string());
        EXPECT_EQ(r.code, 2) << r.err;
        EXPECT_NE(r.err.find(err), std::string::npos) << r.err;
    }
    // The camera model itself (views made in code, e.g. by a generator) says the same.
    Camera cam;
    std::string err;
    CameraSpec s;
    s.up = {0, 0, 0};
    EXPECT_FALSE(makeCamera(s, &cam, &err));
    EXPECT_EQ(err, "\"up\" has zero length; try [0, 1, 0]");
    s.up = {0, 1e-300, 0};  // tiny but not zero: a valid direction
    EXPECT_TRUE(makeCamera(s, &cam, &err)) << err;
    EXPECT_EQ(cam.up, (Vec3{0, 1, 0}));
    s.up = {0, 1e308, 1e308};  // huge: |up| overflows, yet it is a valid direction (0, 1, 1)/sqrt(2)
    EXPECT_TRUE(makeCamera(s, &cam, &err)) << err;
    EXPECT_EQ(cam.right, (Vec3{1, 0, 0}));
}

// ---- Duplicate vertices and degenerate indices --------------------------------------------------

// Hard: a mesh whose quad diagonal uses two copies of the same positions is not indexed-shared,
// so nothing but exact fixed point guarantees the two triangles meet without a crack or an
// overlap. Same coordinates -> same snapped vertices -> the fill rule gives the diagonal's centers
// to exactly one triangle: the square [-16, 16]^2 (orthoView: pixels 16..47) covers 32 x 32 = 1024
// pixels, each once, exactly as the indexed square does.
TEST_F(HardInput, DuplicateVerticesDrawLikeSharedOnes) {
    const std::string dup = write("dup.obj", "v -16 -16 0\nv 16 -16 0\nv 16 16 0\nv -16 -16 0\nv 16 16 0\nv -16 16 0\n"
                                             "f 1 2 3\nf 4 5 6\n");
    const std::string shared = write("shared.obj", "v -16 -16 0\nv 16 -16 0\nv 16 16 0\nv -16 16 0\nf 1 2 3\nf 1 3 4\n");
    std::vector<uint32_t> ids[2];
    for (int k = 0; k < 2; ++k) {
        Scene s;
        std::string err;
        ASSERT_TRUE(loadScene(k ? shared : dup, {}, &s, &err)) << err;
        EXPECT_EQ(s.stats.degenerateTriangles, 0u);
        const ViewResult r = run(s, orthoView());
        EXPECT_EQ(r.zbuffer.fragments, 1024u);
        EXPECT_EQ(r.zbuffer.coveredPixels, 1024u);
        EXPECT_EQ(r.zbuffer.maxDepthComplexity, 1u);
        ids[k] = r.buffer.id;
    }
    EXPECT_TRUE(ids[0] == ids[1]);
}

// Hard: an index past the vertex list is where a reader either reads out of bounds or silently
// drops geometry. Refused, naming the face: OBJ and OFF by its line (and OFF's face number), PLY by
// the face's number (counting from 0, like its indices).
TEST_F(HardInput, OutOfRangeIndexIsAnErrorNamingTheFace) {
    const std::string obj = write("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\n");
    EXPECT_EQ(loadError(obj), obj + ":5: face 'f 1 2 9': vertex index 9 is out of range (the file has 3 vertices, "
                                    "counting from 1); fix the index or add the vertex");
    const std::string off = write("bad.off", "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 7\n");
    EXPECT_EQ(loadError(off), off + ":7: face 1 '3 0 1 7': expected the number of corners N, then N vertex indices below 3 "
                                    "and nothing else on the line (a face color needs a C header: COFF); fix the face (or the counts line)");
    std::string ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                      "element face 2\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n"
                      "3 0 1 2\n3 5 1 2\n";
    const std::string plyPath = write("bad.ply", ply);
    EXPECT_EQ(loadError(plyPath), plyPath + ": face 1 (counting from 0) has vertex index 5, out of range (the file has 3 "
                                            "vertices); fix the index or add the vertex");
    for (const std::string &p : {obj, off, plyPath}) {
        const Run r = program("analyze " + p + " --width 32 --height 24 --out " + (dir_ / "out").string());
        EXPECT_EQ(r.code, 2) << p << "\n" << r.err;
        EXPECT_NE(r.err.find(p), std::string::npos) << r.err;
    }
}

// Hard: a repeated index makes a triangle of zero area, whose plane is (0, 0, 0, 0): every sign
// test on it is 0. It is counted and never drawn. In an OFF polygon, "4 0 1 1 2" fans into (0,1,1)
// and (0,1,2): the first is a degenerate triangle (counted in degenerate_triangles, excluded), the
// second is drawn. A triangle "3 0 0 1" has 2 distinct vertices: the face is dropped (counted in
// faces_dropped, with a warning). The drawn triangle (0,0), (16,0), (0,16) is, in orthoView's
// pixels, (32,32), (48,32), (32,16): centers (x + 0.5, y + 0.5) with x >= 32, y <= 31 and, on the
// hypotenuse px - py = 16 (a right edge: excluded by the fill rule), strictly x - y < 16. With
// i = x - 32 and j = 31 - y that is i + j <= 14: 15 * 16 / 2 = 120 pixels.
TEST_F(HardInput, RepeatedIndexIsCountedNotDrawn) {
    RawMesh m;
    m.positions = {{0, 0, 0}, {16, 0, 0}, {0, 16, 0}};
    m.indices = {0, 0, 1, 0, 1, 2};
    Scene s = sceneOf({m});
    EXPECT_EQ(s.stats.sourceTriangles, 2u);
    EXPECT_EQ(s.stats.degenerateTriangles, 1u);
    EXPECT_EQ(s.triangleObject[0], kExcludedTriangle);
    const ViewResult r = run(s, orthoView());
    EXPECT_EQ(r.zbuffer.trianglesIn, 1u);
    EXPECT_EQ(r.zbuffer.fragments, 120u);

    const std::string p = write("rep.off", "OFF\n3 2 0\n0 0 0\n16 0 0\n0 16 0\n4 0 1 1 2\n3 0 0 1\n");
    Scene f;
    std::string err;
    ASSERT_TRUE(loadScene(p, {}, &f, &err)) << err;
    EXPECT_EQ(f.stats.facesDropped, 1u);
    EXPECT_EQ(f.stats.degenerateTriangles, 1u);
    EXPECT_EQ(f.stats.sourceTriangles, 2u);
    EXPECT_EQ(f.objectTriangles.size(), 1u);
    EXPECT_EQ(run(f, orthoView()).zbuffer.fragments, 120u);
}

// ---- Empty input --------------------------------------------------------------------------------

// Hard: every stage divides by or allocates from its input size; zero triangles is where a ratio
// becomes 0/0 and a BVH or an Embree scene is built over nothing. Decision (docs/hard-cases.md): a
// mesh with vertices but no faces is a valid, empty level: a report with zero counts (every stage
// 0 in, 0 out; coverage 0; overdraw 0, not NaN) and exit 0.
TEST_F(HardInput, MeshWithZeroTrianglesGivesAReportWithZeroCounts) {
    const std::string p = write("empty.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
    Scene s;
    std::string err;
    ASSERT_TRUE(loadScene(p, {}, &s, &err)) << err;
    EXPECT_EQ(s.triangleCount(), 0u);
    AnalysisResult out;
    ASSERT_TRUE(analyzeScene(s, orbitViews(s, 2), PipelineSettings{}, nullptr, &out, &err)) << err;
    ASSERT_EQ(out.views.size(), 2u);
    for (const ViewResult &v : out.views) {
        for (const StageRecord &st : v.stages) {
            EXPECT_EQ(st.trianglesIn, 0u) << st.name;
            EXPECT_EQ(st.trianglesOut, 0u) << st.name;
        }
        EXPECT_EQ(v.zbuffer.coveredPixels, 0u);
        EXPECT_EQ(v.zbuffer.overdraw, 0.0);
        EXPECT_EQ(v.zbuffer.depthComplexity, 0.0);
        EXPECT_EQ(v.raycast->crossCheck.agree, v.raycast->crossCheck.pixels);
    }
    const fs::path outDir = dir_ / "out";
    const Run r = program("analyze " + p + " --views orbit:2 --width 32 --height 24 --out " + outDir.string());
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_TRUE(fs::exists(outDir / "report.json"));
}

// Hard: "no views" can mean "use a default" or "nothing to do". Decision (docs/hard-cases.md):
//  * analyzeScene with 0 views is defined: true, a result with 0 views (a shard can be empty);
//  * a scene file without views, run without --views: orbit:4, said on stderr (the README's
//    default);
//  * an explicit views file with "views": [] is a mistake the user must hear about: exit 2,
//    naming the file -- never silently replaced by orbit views.
TEST_F(HardInput, SceneWithZeroViews) {
    Scene s = sceneOf({boxMesh({0, 0, 0}, {1, 1, 1})});
    AnalysisResult out;
    std::string err;
    ASSERT_TRUE(analyzeScene(s, {}, PipelineSettings{}, nullptr, &out, &err)) << err;
    EXPECT_TRUE(out.views.empty());
    EXPECT_EQ(out.triangles, 12u);

    write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    const std::string scene = write("noviews.scene.json", "{\"format\": \"visaudit-scene/1\", \"objects\": [{\"mesh\": \"tri.obj\"}]}\n");
    const Run a = program("analyze " + scene + " --width 32 --height 24 --out " + (dir_ / "a").string());
    EXPECT_EQ(a.code, 0) << a.err;
    EXPECT_NE(a.err.find(scene + " has no views; using --views orbit:4"), std::string::npos) << a.err;

    const std::string views = write("empty.views.json", "{\"views\": []}\n");
    const Run b = program("analyze " + scene + " --views " + views + " --out " + (dir_ / "b").string());
    EXPECT_EQ(b.code, 2) << b.err;
    EXPECT_NE(b.err.find("--views " + views + ": the file has no views; give at least one view"), std::string::npos)
        << b.err;
    EXPECT_FALSE(fs::exists(dir_ / "b"));
}
