// Exact cases for the frustum, backface and clip stages and the pipeline that joins them.
#include <gtest/gtest.h>
#include <tbb/parallel_for.h>
#include <xmmintrin.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>
#include <random>
#include <set>

#include "analysis/stages/backface.h"
#include "analysis/load/demo.h"
#include "tests/test_util.h"
#include "analysis/stages/frustum.h"
#include "analysis/pipeline.h"
#include "common/fp_env.h"
#include "render/camera.h"
#include "render/clip_vertices.h"

using namespace va;
using namespace va::testing_util;

namespace {

// Settings with the frustum and backface stages off (clip and z-buffer only).
PipelineSettings noCulling() {
    PipelineSettings s;
    s.frustum = false;
    s.backface = false;
    return s;
}

ViewResult run(const Scene &scene, const ViewSpec &view, PipelineSettings s = {}) {
    ViewSpec resolved;
    Camera cam;
    std::string err;
    EXPECT_TRUE(resolveView(view, s, &resolved, &cam, &err)) << err;
    const PreparedScene ps = prepareScene(scene);
    return analyzeView(ps, resolved, cam, s);
}

const StageRecord &stage(const ViewResult &r, const std::string &name) {
    for (const StageRecord &s : r.stages)
        if (s.name == name) return s;
    static StageRecord none;
    ADD_FAILURE() << "no stage " << name;
    return none;
}

}  // namespace

TEST(Backface, CubeFromGenericEyeCullsExactlySixOfTwelve) {
    const Scene scene = sceneOf({boxMesh({0, 0, 0}, {1, 1, 1})});
    ASSERT_EQ(scene.objectTriangles.size(), 12u);
    // Generic eyes: each sees exactly three faces of the cube.
    for (Vec3 eye : {Vec3{3.1, 2.3, 4.7}, Vec3{-5.2, 1.9, -3.3}, Vec3{2.2, -4.1, 1.7}}) {
        const ViewResult r = run(scene, viewOf(eye, {0, 0, 0}));
        EXPECT_EQ(r.backface.trianglesTested, 12u);
        EXPECT_EQ(r.backface.trianglesCulled, 6u);
        EXPECT_EQ(stage(r, "backface").trianglesOut, 6u);
    }
    // An eye in the planes x = 1 and y = 1 of two faces: those four triangles are edge-on (plane
    // exactly 0 at the eye) and culled; only the +z face's two triangles survive.
    const ViewResult r = run(scene, viewOf({1, 1, 5}, {0, 0, 0}));
    EXPECT_EQ(r.backface.trianglesCulled, 10u);
    EXPECT_EQ(r.backface.edgeOn, 4u);
}

// The stage's float filter (scene.cpp) only decides where the exact sign is certain: over random
// triangles and eyes from 1e-6 to 1e7 in magnitude, with eyes on, next to and far from the planes,
// the stage keeps exactly the triangles the exact per-triangle test (isFrontFacing) calls front, and
// counts the same edge-on ones.
TEST(Backface, FloatFilterAgreesWithTheExactTestOverWideMagnitudes) {
    std::mt19937_64 rng(20261126);
    std::uniform_real_distribution<double> unit(-1, 1), expo(-6, 7);
    uint64_t decidedByFloat = 0, tested = 0;
    for (int round = 0; round < 40; ++round) {
        const double scale = std::pow(10.0, expo(rng));
        RawMesh m;
        const Vec3 offset{unit(rng) * scale * 10, unit(rng) * scale * 10, unit(rng) * scale * 10};
        for (int t = 0; t < 300; ++t) {
            for (int k = 0; k < 3; ++k)
                m.positions.push_back(offset + Vec3{unit(rng) * scale, unit(rng) * scale, unit(rng) * scale});
            m.indices.insert(m.indices.end(), {uint32_t(3 * t), uint32_t(3 * t + 1), uint32_t(3 * t + 2)});
        }
        const Scene scene = sceneOf({m});
        ASSERT_EQ(scene.backfacePlanes.size(), scene.objectTriangles.size());
        std::vector<uint32_t> objects(scene.objects.size());
        for (size_t o = 0; o < objects.size(); ++o) objects[o] = uint32_t(o);
        // Eyes: generic; on a triangle's plane (a vertex, the centroid); a hair off a vertex.
        const Vec3 v0 = m.positions[0], v1 = m.positions[1], v2 = m.positions[2];
        for (Vec3 eye : {offset + Vec3{unit(rng) * scale * 3, unit(rng) * scale * 3, unit(rng) * scale * 3}, v0,
                         (v0 + v1 + v2) / 3.0, Vec3{std::nextafter(v1.x, 1e300), v1.y, v1.z},
                         offset + Vec3{scale * 1e6, -scale * 1e6, scale * 1e6}}) {
            CameraSpec spec;
            spec.eye = eye;
            spec.target = eye + Vec3{0, 0, -1};
            spec.nearZ = 1e-3 * scale;
            spec.farZ = 1e9 * scale;
            Camera cam;
            std::string err;
            ASSERT_TRUE(makeCamera(spec, &cam, &err)) << err;
            const BackfaceResult r = cullBackfaces(scene, objects, cam);
            std::vector<uint32_t> kept, culled;
            uint64_t edgeOn = 0;
            for (uint32_t o : objects)
                for (uint32_t i = scene.objects[o].triBegin; i < scene.objects[o].triEnd; ++i) {
                    const uint32_t t = scene.objectTriangles[i];
                    bool on = false;
                    if (isFrontFacing(scene, t, cam, &on)) kept.push_back(t);
                    else edgeOn += on, culled.push_back(t);
                    const Scene::BackfacePlane q = scene.backfacePlanes[i];
                    const float sf = ((q.nx * float(eye.x) + q.ny * float(eye.y)) + q.nz * float(eye.z)) + q.k;
                    decidedByFloat +=
                        std::fabs(sf) > Scene::BackfacePlanes::boundOf(q, scene.backfacePlanes.bound(o, maxAbs(eye)));
                    ++tested;
                }
            EXPECT_EQ(r.kept.triangles, kept) << "scale " << scale << " eye " << eye.x << " " << eye.y << " " << eye.z;
            EXPECT_EQ(r.culled, culled);  // in order too (the eight-wide path packs both lists)
            EXPECT_EQ(r.stats.edgeOn, edgeOn);
            EXPECT_EQ(r.stats.trianglesCulled + kept.size(), scene.objectTriangles.size());
        }
    }
    // The filter decides nearly everything (else it would not pay for itself).
    EXPECT_GT(double(decidedByFloat), 0.9 * double(tested));
}

TEST(Backface, DoubleSidedMaterialIsExempt) {
    Material ds;
    ds.name = "ds";
    ds.doubleSided = true;
    const Scene scene = sceneOf({boxMesh({0, 0, 0}, {1, 1, 1}), boxMesh({3, 0, 0}, {1, 1, 1})}, {Material{}, ds},
                                {0, 1});
    const ViewResult r = run(scene, viewOf({1.5, 2.3, 9.7}, {1.5, 0, 0}));
    EXPECT_EQ(r.backface.trianglesTested, 12u);
    EXPECT_EQ(r.backface.doubleSidedExempt, 12u);
    EXPECT_EQ(r.backface.trianglesCulled, 6u);
}

TEST(Backface, EyeExactlyOnTrianglePlaneIsEdgeOnExactly) {
    // The eye lies exactly on the triangle's plane z = 0.1 + 0.2 (not representable: decided
    // exactly by the orientation predicate, never by a rounded dot product).
    const double z = 0.1 + 0.2;
    const Scene scene = sceneOf({triangleMesh({-1, -1, z}, {1, -1, z}, {0, 1, z})});
    bool edgeOn = false;
    Camera cam;
    std::string err;
    CameraSpec cs;
    cs.eye = {0.3, 0.7, z};
    cs.target = {0, 0, -5};
    ASSERT_TRUE(makeCamera(cs, &cam, &err)) << err;
    EXPECT_FALSE(isFrontFacing(scene, 0, cam, &edgeOn));
    EXPECT_TRUE(edgeOn);
}

TEST(Clip, TriangleCrossingNearPlaneIsClippedToAQuad) {
    // Camera at the origin looking down -z; near = 1. One vertex at d = 0.5 (in front of the eye,
    // behind near), two at d = 3.
    const Scene scene = sceneOf({triangleMesh({0, 0.2, -0.5}, {-1, -0.5, -3}, {1, -0.5, -3})});
    const ViewResult r = run(scene, viewOf({0, 0, 0}, {0, 0, -1}, 64, 48, 90, 1.0, 100));
    EXPECT_EQ(r.clip.clipped, 1u);
    EXPECT_EQ(r.clip.perPlane[kPlaneNear], 1u);
    EXPECT_EQ(r.clip.polygonVertices[4], 1u);
    EXPECT_EQ(r.clip.trianglesOut, 2u);
    EXPECT_GT(r.zbuffer.coveredPixels, 0u);
    // Every fragment lies at or beyond near (nothing from in front of the near plane is drawn).
    for (size_t i = 0; i < r.buffer.depth.size(); ++i) {
        if (r.buffer.id[i]) {
            EXPECT_GE(r.buffer.depth[i], 1.0 * (1 - 1e-12));
        }
    }
}

TEST(Clip, VertexBehindEyeNothingDrawnFromBehind) {
    // One vertex behind the eye (d = -2): the projected triangle would wrap around through infinity
    // if it were divided before clipping. Compare coverage with a ray-plane reference.
    const Vec3 a{0, 1.5, 2}, b{-2, -1, -4}, c{2, -1, -4};  // front-facing; eye not in its plane
    const Scene scene = sceneOf({triangleMesh(a, b, c)});
    const ViewSpec view = viewOf({0, 0, 0}, {0, 0, -1}, 64, 48, 90, 0.5, 100);
    const ViewResult r = run(scene, view);
    EXPECT_EQ(r.clip.perPlane[kPlaneNear], 1u);
    // Reference: the pixel-center ray hits the triangle at depth >= near. Pixels whose center lies
    // within 1e-3 pixel of the clipped polygon's boundary may go either way (snapping).
    const Camera &cam = r.camera;
    int mismatches = 0, covered = 0;
    for (int y = 0; y < cam.height; ++y)
        for (int x = 0; x < cam.width; ++x) {
            const ViewRay ray = viewRayThroughPixel(cam, x + 0.5, y + 0.5);
            const Vec3 dir = transformVector(transpose(cam.viewFromWorld), ray.direction);
            // Moller-Trumbore in world space from the eye.
            const Vec3 e1 = b - a, e2 = c - a, p = cross(dir, e2);
            const double det = dot(e1, p);
            const Vec3 s = cam.eye - a;
            const double u = dot(s, p) / det;
            const Vec3 q = cross(s, e1);
            const double v = dot(dir, q) / det, t = dot(e2, q) / det;
            const bool hit = u >= 0 && v >= 0 && u + v <= 1 && t >= 0.5;
            const bool margin = std::fabs(u) < 1e-3 || std::fabs(v) < 1e-3 || std::fabs(1 - u - v) < 1e-3 ||
                                std::fabs(t - 0.5) < 1e-3;
            const bool drawn = r.buffer.id[size_t(y) * cam.width + x] != 0;
            covered += drawn;
            if (hit != drawn && !margin) ++mismatches;
        }
    EXPECT_EQ(mismatches, 0);
    EXPECT_GT(covered, 100);
}

TEST(Clip, TriangleEntirelyBehindEyeIsTriviallyRejected) {
    const Scene scene = sceneOf({triangleMesh({-1, 0, 3}, {1, 0, 3}, {0, 1, 3})});
    const ViewResult r = run(scene, viewOf({0, 0, 0}, {0, 0, -1}), noCulling());
    EXPECT_EQ(r.clip.trianglesIn, 1u);
    EXPECT_EQ(r.clip.trivialRejected, 1u);
    EXPECT_EQ(r.zbuffer.fragments, 0u);
}

TEST(Clip, VertexExactlyOnNearPlaneIsInside) {
    // Camera at the origin looking down -z: view depth d = -z exactly, so d = near exactly.
    const Scene scene = sceneOf({triangleMesh({0, 0, -1}, {-1, -1, -3}, {1, -1, -3})});
    const ViewResult r = run(scene, viewOf({0, 0, 0}, {0, 0, -1}, 64, 48, 90, 1.0, 100));
    EXPECT_EQ(r.clip.inside, 1u);
    EXPECT_EQ(r.clip.clipped, 0u);
}

TEST(Clip, TriangleInAFrustumSidePlaneIsEdgeOn) {
    // All three vertices on the plane through the eye x = 0 (perspective): seen edge-on.
    const Scene scene = sceneOf({triangleMesh({0, 0, -2}, {0, 1, -3}, {0, -1, -4})});
    const ViewResult r = run(scene, viewOf({0, 0, 0}, {0, 0, -1}), noCulling());
    EXPECT_EQ(r.clip.edgeOn, 1u);
    EXPECT_EQ(r.zbuffer.fragments, 0u);
}

TEST(Clip, HugeTriangleIsClippedAtTheGuardBandAndCoversEverything) {
    // A triangle whose projection spans ~1e9 pixels: clipped against the guard band, it must still
    // cover every pixel of the view exactly once.
    const Scene scene = sceneOf({triangleMesh({-1e7, -1e7, -5}, {1e7, -1e7, -5}, {0, 1e7, -5})});
    const ViewResult r = run(scene, viewOf({0, 0, 0}, {0, 0, -1}), noCulling());
    EXPECT_EQ(r.clip.clipped, 1u);
    EXPECT_EQ(r.zbuffer.coveredPixels, 64u * 48u);
    EXPECT_EQ(r.zbuffer.fragments, 64u * 48u);
}

// The clipper's vertex pass with AVX2 (render/clip_avx2.cpp) gives the scalar pass's bits for
// every vertex: in front, behind the eye, on the near plane, at the guard band's edges, huge
// (saturating fixed point), infinite and NaN; perspective and orthographic; every batch length
// mod 4 (the AVX2 pass ends with the scalar one).
TEST(Clip, Avx2VertexPassEqualsScalarBitForBit) {
    if (!__builtin_cpu_supports("avx2")) GTEST_SKIP() << "no AVX2 on this CPU";
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(-1, 1);
    const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
    for (bool ortho : {false, true}) {
        clip_detail::VertexPassParams p{};
        const double m[3][4] = {{0.8, 0.1, -0.59, 3.25}, {-0.2, 0.97, 0.12, -1.5}, {0.56, 0.2, 0.8, -7.125}};
        std::memcpy(p.m, m, sizeof m);
        p.sx = 1.7320508075688772, p.sy = 3.0792014356780038, p.nearZ = 0.1, p.farZ = 1000;
        p.gx = 1 + 2048 / 960.0, p.gy = 1 + 2048 / 540.0, p.halfW = 960, p.halfH = 540, p.orthographic = ortho;
        std::vector<Vec3> pos;
        for (int i = 0; i < 4000; ++i) {
            const double scale = std::ldexp(1.0, int(rng() % 80) - 20);  // 2^-20 .. 2^59
            pos.push_back({u(rng) * scale, u(rng) * scale, u(rng) * scale});
        }
        for (double special : {0.0, -0.0, 0.1, 1e300, -1e300, inf, -inf, nan})
            for (int k = 0; k < 3; ++k) {
                Vec3 v{u(rng), u(rng), u(rng)};
                (k == 0 ? v.x : k == 1 ? v.y : v.z) = special;
                pos.push_back(v);
            }
        for (uint32_t n : {uint32_t(pos.size()), uint32_t(pos.size() - 1), uint32_t(pos.size() - 2),
                           uint32_t(pos.size() - 3), 3u, 0u}) {
            clip_detail::BatchVertices a, b;
            a.resize(n), b.resize(n);
            clip_detail::transformVerticesAvx2(p, pos.data(), n, a);
            if (ortho) clip_detail::transformVerticesBody<true>(p, pos.data(), 0, n, b);
            else clip_detail::transformVerticesBody<false>(p, pos.data(), 0, n, b);
            for (uint32_t i = 0; i < n; ++i) {
                ASSERT_EQ(std::memcmp(&a.x[i], &b.x[i], 8), 0) << i;
                ASSERT_EQ(std::memcmp(&a.y[i], &b.y[i], 8), 0) << i;
                ASSERT_EQ(std::memcmp(&a.z[i], &b.z[i], 8), 0) << i;
                ASSERT_EQ(a.code[i], b.code[i]) << i << " ortho " << ortho;
                ASSERT_EQ(a.sxy[2 * i], b.sxy[2 * i]) << i;
                ASSERT_EQ(a.sxy[2 * i + 1], b.sxy[2 * i + 1]) << i;
            }
        }
    }
    // The scalar pass's outcode and fixed point are the clipper's own (ClipSpace::outcode, toFixed):
    // a vertex inside the guard band projects as toFixed does.
    clip_detail::VertexPassParams p{};
    p.m[0][0] = p.m[1][1] = p.m[2][2] = 1;
    p.sx = p.sy = 1, p.nearZ = 0.5, p.farZ = 10, p.gx = p.gy = 2, p.halfW = 32, p.halfH = 24;
    clip_detail::BatchVertices b;
    b.resize(3);
    const Vec3 pos[3] = {{0.25, -0.5, -2}, {3, 0, -2}, {0, 0, -0.25}};
    clip_detail::transformVerticesBody<false>(p, pos, 0, 3, b);
    EXPECT_EQ(b.code[0], 0u);
    EXPECT_EQ(b.sxy[0], toFixed((0.25 / 2 + 1) * 32));
    EXPECT_EQ(b.sxy[1], toFixed((1 - -0.5 / 2) * 24));
    EXPECT_EQ(b.code[1], clip_detail::outBit(kPlaneRight));  // x/w = 1.5: outside the view, inside the band
    EXPECT_EQ(b.code[2], clip_detail::outBit(kPlaneNear));
}

// clipTriangles takes groups of four accepted triangles through the AVX2 accept path and every
// other group through clipOne; clipViewTriangles (the kit's entry) runs each triangle through
// clipOne. Mixed groups (inside, guard band, clipped, rejected, edge-on, degenerate, triangles
// whose depth plane overflows) in both projections: the same screen triangles and counts, bit for bit.
TEST(Clip, AcceptPathEqualsThePerTriangleClipperBitForBit) {
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(-1, 1);
    for (bool ortho : {false, true}) {
        Camera cam;
        std::string err;
        ASSERT_TRUE(smallCamera({0.3, 0.2, 6}, {0, 0, 0}, 320, 200, ortho, &cam, &err)) << err;
        std::vector<Vec3> pos;
        std::vector<uint32_t> indices;
        for (int t = 0; t < 3000; ++t) {
            const uint32_t base = uint32_t(pos.size());
            const int kind = int(rng() % 10);
            // Mostly small triangles inside the view (runs of accepted groups), some large ones
            // (guard band, clipped), some behind the eye or beyond far.
            const double scale = kind < 6 ? 0.2 : kind < 8 ? 30 : 4;
            const Vec3 c = kind == 9 ? Vec3{u(rng), u(rng), 8 + 50 * std::fabs(u(rng))}
                                     : Vec3{2 * u(rng), 2 * u(rng), u(rng)};
            for (int k = 0; k < 3; ++k) pos.push_back(c + scale * Vec3{u(rng), u(rng), u(rng)});
            if (rng() % 50 == 0) pos[base + 2] = pos[base] + 0.5 * (pos[base + 1] - pos[base]);  // collinear: edge-on
            if (rng() % 80 == 0) pos[base + 1] = pos[base];                                       // two corners shared
            if (rng() % 100 == 0) pos[base + 2] = pos[base] + Vec3{1e-300, 0, 0};                 // a sliver
            for (int k = 0; k < 3; ++k) indices.push_back(base + uint32_t(k));
        }
        // Triangles in a shuffled subset, so groups are not aligned with the index array.
        std::vector<uint32_t> tris;
        for (uint32_t t = 0; t < indices.size() / 3; ++t)
            if (rng() % 5) tris.push_back(t);
        std::shuffle(tris.begin() + tris.size() / 2, tris.end(), rng);
        const std::vector<ClipBatch> batches = {{0, uint32_t(pos.size()), tris.data(), uint32_t(tris.size())}};
        const ClipResult a = clipTriangles(cam, {pos.data(), indices.data()}, batches, {});

        std::vector<Vec3> view;
        for (uint32_t t : tris)
            for (int k = 0; k < 3; ++k) view.push_back(transformPoint(cam.viewFromWorld, pos[indices[3 * t + k]]));
        const ClipResult b = clipViewTriangles(cam, view, tris, {});

        EXPECT_GT(a.stats.inside, 1000u);
        EXPECT_GT(a.stats.guardBandAccepted + a.stats.clipped + a.stats.trivialRejected + a.stats.edgeOn, 100u);
        EXPECT_GT(a.stats.edgeOn, 0u);
        EXPECT_EQ(a.stats.trianglesIn, b.stats.trianglesIn);
        EXPECT_EQ(a.stats.trivialRejected, b.stats.trivialRejected);
        EXPECT_EQ(a.stats.inside, b.stats.inside);
        EXPECT_EQ(a.stats.guardBandAccepted, b.stats.guardBandAccepted);
        EXPECT_EQ(a.stats.clipped, b.stats.clipped);
        EXPECT_EQ(a.stats.clippedAway, b.stats.clippedAway);
        EXPECT_EQ(a.stats.edgeOn, b.stats.edgeOn);
        EXPECT_EQ(a.stats.trianglesOut, b.stats.trianglesOut);
        EXPECT_EQ(screenTrianglesDifference(a.out, b.out), "") << "ortho " << ortho;
    }
}

// Triangles inside the view whose depth plane overflows (a and c infinite, b finite): the eye at
// the origin looking down -z, so view space is world space exactly. Perspective: the plane
// x = 1e-320 passes 1e-320 from the eye; orthographic: a sliver 1e-320 wide seen along its plane.
// Each is edge-on for clipOne; placed at every position of a group of four otherwise accepted
// triangles, the accept path must drop it too.
TEST(Clip, AcceptPathDropsOverflowingPlanesAsEdgeOn) {
    for (bool ortho : {false, true}) {
        Camera cam;
        std::string err;
        ASSERT_TRUE(smallCamera({0, 0, 0}, {0, 0, -1}, 64, 48, ortho, &cam, &err)) << err;
        std::vector<Vec3> pos;
        std::vector<uint32_t> indices, tris;
        for (int g = 0; g < 4; ++g)
            for (int j = 0; j < 4; ++j) {
                const uint32_t base = uint32_t(pos.size());
                if (j == g && !ortho) pos.insert(pos.end(), {{1e-320, 0, -5}, {1e-320, 1, -5}, {1e-320, 0, -6}});
                else if (j == g) pos.insert(pos.end(), {{0, 0, -5}, {1e-320, 0, -4.5}, {0, 0.5, -5}});
                else pos.insert(pos.end(), {{0.1 * j, 0, -5}, {0.1 * j + 0.3, 0, -5}, {0.1 * j, 0.3, -5}});
                for (int k = 0; k < 3; ++k) indices.push_back(base + uint32_t(k));
                tris.push_back(uint32_t(tris.size()));
            }
        const std::vector<ClipBatch> batches = {{0, uint32_t(pos.size()), tris.data(), uint32_t(tris.size())}};
        const ClipResult a = clipTriangles(cam, {pos.data(), indices.data()}, batches, {});
        EXPECT_EQ(a.stats.edgeOn, 4u) << "ortho " << ortho;
        EXPECT_EQ(a.stats.inside, 12u);
        EXPECT_EQ(a.out.size(), 12u);
        for (const DepthPlane &p : a.out.planes) EXPECT_TRUE(std::isfinite(p.a) && std::isfinite(p.c));
    }
}

TEST(Pipeline, ClosedMeshWithBackfaceCullingCoversEachPixelOnce) {
    const Scene scene = sceneOf({uvSphereMesh({0.3, -0.2, 0}, 1, 64, 32)});
    for (Vec3 eye : {Vec3{0.5, 0.4, 4}, Vec3{-2.7, 1.1, 1.6}, Vec3{1.9, 0.4, 0.9}}) {
        const ViewResult r = run(scene, viewOf(eye, {0, 0, 0}, 160, 120));
        EXPECT_GT(r.zbuffer.coveredPixels, 1000u);
        EXPECT_EQ(r.zbuffer.fragments, r.zbuffer.coveredPixels);  // no crack, no double cover
        EXPECT_EQ(r.zbuffer.maxDepthComplexity, 1u);
        EXPECT_EQ(r.zbuffer.overdraw, 1.0);
    }
}

TEST(Pipeline, PowerOfTwoScalesGiveIdenticalImages) {
    // Scaling the scene, the eye and near/far by 2^k is exact in binary floating point, so every
    // computation scales exactly and the coverage must be identical at 1e-6 and 1e6 magnitudes.
    auto render = [&](double s) {
        RawMesh m = uvSphereMesh({0.3 * s, -0.2 * s, 0}, 1 * s, 32, 16);
        RawMesh t = triangleMesh(Vec3{-3, -2, -1} * s, Vec3{3, -2, -1} * s, Vec3{0, 3, -1.5} * s);
        const Scene scene = sceneOf({m, t});
        return run(scene, viewOf(Vec3{0.5, 0.4, 4} * s, {0, 0, 0}, 96, 64, 60, 0.1 * s, 100 * s));
    };
    const ViewResult ref = render(1);
    for (double s : {std::ldexp(1.0, -20), std::ldexp(1.0, 20)}) {
        const ViewResult r = render(s);
        EXPECT_EQ(r.buffer.id, ref.buffer.id) << "scale " << s;
        EXPECT_EQ(r.zbuffer.fragments, ref.zbuffer.fragments);
    }
}

TEST(Frustum, BvhWalkEqualsBruteForceAndTestsFewerPlanes) {
    // 20 x 20 boxes on a grid; several views; the BVH result equals testing each object.
    std::vector<RawMesh> boxes;
    for (int i = 0; i < 20; ++i)
        for (int j = 0; j < 20; ++j) boxes.push_back(boxMesh({i * 3.0, 0, j * 3.0}, {0.5, 0.5, 0.5}));
    const Scene scene = sceneOf(boxes);
    const ObjectBvh bvh = buildObjectBvh(scene);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-10, 70);
    for (int k = 0; k < 20; ++k) {
        CameraSpec cs;
        cs.eye = {u(rng), u(rng) * 0.2, u(rng)};
        cs.target = {u(rng), 0, u(rng)};
        cs.nearZ = 0.1;
        cs.farZ = 20 + k * 3;
        Camera cam;
        std::string err;
        ASSERT_TRUE(makeCamera(cs, &cam, &err)) << err;
        const FrustumResult f = cullFrustum(scene, bvh, cam);
        const FrustumPlanes fp = worldFrustumPlanes(cam);
        std::vector<uint32_t> brute;
        uint64_t tests = 0;
        for (uint32_t o = 0; o < scene.objects.size(); ++o) {
            uint32_t mask = 0x3F;
            if (classifySphere(fp, scene.objects[o].sphere, &mask, &tests) >= 0) brute.push_back(o);
        }
        EXPECT_EQ(f.visible, brute);
        EXPECT_EQ(f.stats.objectsCulled + f.stats.objectsInside + f.stats.objectsIntersecting, 400u);
        EXPECT_LT(f.stats.planeTests, f.stats.planeTestsBruteForce);
    }
}

TEST(Frustum, ObjectsBehindAndBesideTheCameraAreCulledInTheDemo) {
    const Scene scene = demoScene();
    const ViewResult r = run(scene, scene.views[0]);
    ASSERT_EQ(scene.views[0].name, "spawn");
    const PreparedScene ps = prepareScene(scene);
    const FrustumResult f = cullFrustum(scene, ps.bvh, r.camera);
    auto visible = [&](const std::string &src) {
        for (uint32_t o : f.visible)
            if (scene.sources[scene.objects[o].source].name == src) return true;
        return false;
    };
    EXPECT_FALSE(visible("behind"));
    EXPECT_FALSE(visible("offscreen"));
    EXPECT_TRUE(visible("ball"));
    EXPECT_TRUE(visible("wall"));
    EXPECT_GT(r.clip.perPlane[kPlaneNear], 0u);      // the wall crosses the near plane
    EXPECT_GT(r.backface.doubleSidedExempt, 0u);      // the banner
    // The funnel is consistent: each stage's input is the previous stage's output.
    EXPECT_EQ(stage(r, "backface").trianglesIn, stage(r, "frustum").trianglesOut);
    EXPECT_EQ(stage(r, "clip").trianglesIn, stage(r, "backface").trianglesOut);
    EXPECT_EQ(stage(r, "zbuffer").trianglesIn, stage(r, "clip").trianglesOut);
    EXPECT_FALSE(stage(r, "cells").ran);
}

TEST(Pipeline, CountsAndImagesAreIdenticalAcrossThreadCounts) {
    const Scene scene = demoScene();
    std::vector<AnalysisResult> results(3);
    const int threads[3] = {1, 2, 8};
    for (int k = 0; k < 3; ++k) {
        PipelineSettings s;
        s.threads = threads[k];
        std::string err;
        ASSERT_TRUE(analyzeScene(scene, scene.views, s, nullptr, &results[k], &err)) << err;
    }
    for (int k = 1; k < 3; ++k)
        for (size_t v = 0; v < scene.views.size(); ++v) {
            EXPECT_EQ(results[k].views[v].buffer.id, results[0].views[v].buffer.id);
            EXPECT_EQ(results[k].views[v].buffer.depth, results[0].views[v].buffer.depth);
            EXPECT_EQ(results[k].views[v].zbuffer.fragments, results[0].views[v].zbuffer.fragments);
            EXPECT_EQ(results[k].views[v].zbuffer.histogram, results[0].views[v].zbuffer.histogram);
        }
}

// The views compute under IEEE 754 defaults on every thread (common/fp_env.h) even when the
// process's first TBB user ran with flush-to-zero and denormals-are-zero on, as Embree's scene
// build does: TBB's default context keeps the first user's settings for every later loop.
TEST(Pipeline, ViewsRunUnderIeeeDefaultsWhateverUsedTbbFirst) {
    constexpr unsigned kFtzDaz = 0x8040u, kStatus = 0x3Fu;
    const unsigned saved = _mm_getcsr();
    _mm_setcsr(saved | kFtzDaz);
    std::atomic<unsigned> first{0};
    tbb::parallel_for(0, 4, [&](int) { first |= _mm_getcsr() & kFtzDaz; });  // this process's first TBB use
    _mm_setcsr(saved);
    EXPECT_EQ(first.load(), kFtzDaz);

    std::mutex m;
    std::set<unsigned> controls;  // MXCSR without its status flags, per task
    std::vector<double> halves;
    auto record = [&] {
        volatile double tiny = 0x1p-1070;  // subnormal
        const double half = tiny * 0.5;    // 0x1p-1071 under IEEE defaults, 0 flushed
        std::lock_guard<std::mutex> lock(m);
        controls.insert(_mm_getcsr() & ~kStatus);
        halves.push_back(half);
    };
    const Scene scene = demoScene();
    PipelineSettings s;
    s.threads = 2;
    AnalysisResult r;
    std::string err;
    ASSERT_TRUE(analyzeScene(
        scene, scene.views, s,
        [&](size_t, ViewResult &, std::string *) {
            record();
            return true;
        },
        &r, &err))
        << err;
    // Nested loops inside runWithIeeeFp too (the raycast's bands run nested in a view).
    runWithIeeeFp([&] { tbb::parallel_for(0, 8, [&](int) { tbb::parallel_for(0, 8, [&](int) { record(); }); }); });
    EXPECT_EQ(controls, std::set<unsigned>{kIeeeMxcsr});
    EXPECT_EQ(halves.size(), scene.views.size() + 64);
    for (double h : halves) EXPECT_EQ(h, 0x1p-1071);
    EXPECT_EQ(_mm_getcsr() & ~kStatus, saved & ~kStatus);  // the caller's settings back
}

TEST(Pipeline, InvalidViewsAreRefusedBeforeAnyWork) {
    const Scene scene = demoScene();
    PipelineSettings s;
    ViewSpec v = scene.views[0];
    ViewSpec out;
    Camera cam;
    std::string err;
    v.camera.width = 100000;
    EXPECT_FALSE(resolveView(v, s, &out, &cam, &err));
    EXPECT_EQ(err, "view 'spawn': resolution 100000x540 exceeds the limit of 16384 pixels per side; lower it "
                   "(--width/--height) or raise the limit with --max-resolution");
    v = scene.views[0];
    v.camera.nearZ = 0;
    EXPECT_FALSE(resolveView(v, s, &out, &cam, &err));
    EXPECT_EQ(err, "view 'spawn': \"near\" must be > 0 (perspective depth is undefined at the eye); try 0.1");
    v = scene.views[0];
    v.camera.farZ = v.camera.nearZ;
    EXPECT_FALSE(resolveView(v, s, &out, &cam, &err));
    EXPECT_EQ(err, "view 'spawn': \"far\" must be greater than \"near\"; try far = 1000 * near");
    v = scene.views[0];
    v.camera.eye.x = std::nan("");
    EXPECT_FALSE(resolveView(v, s, &out, &cam, &err));
    EXPECT_EQ(err, "view 'spawn': \"eye\" is not finite; give three finite numbers");
}
