// Ray casting (render/raycast.h): Embree's normal orientation, back-face rejection for the reference
// visibility, t = view depth, watertightness on closed meshes and shared edges, a camera inside an
// object, and the options overload agreeing with the plain cast.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <tuple>

#include <tbb/global_control.h>

#include "analysis/load/demo.h"
#include "tests/test_util.h"
#include "analysis/scene.h"
#include "render/raycast.h"

using namespace va;
using namespace va::testing_util;

namespace {

// Every triangle of the scene that is not excluded, in source order.
std::vector<uint32_t> sceneTriangles(const Scene &s) {
    std::vector<uint32_t> t;
    for (uint32_t i = 0; i < s.triangleCount(); ++i)
        if (s.triangleObject[i] != kExcludedTriangle) t.push_back(i);
    return t;
}

std::unique_ptr<RayScene> rayScene(const Scene &s, Vec3 origin) {
    auto rs = std::make_unique<RayScene>();
    std::string err;
    EXPECT_TRUE(rs->build(MeshView{s.positions.data(), s.indices.data()}, s.positions.size(), sceneTriangles(s), origin,
                          &err))
        << err;
    return rs;
}
std::unique_ptr<RayScene> rayScene(const Scene &s) { return rayScene(s, s.bounds.center()); }

Camera cameraOf(Vec3 eye, Vec3 target, int w, int h, bool ortho = false, double orthoHeight = 10, double fov = 60,
                double nearZ = 0.1, double farZ = 1000) {
    CameraSpec spec;
    spec.eye = eye;
    spec.target = target;
    spec.up = {0, 1, 0};
    spec.width = w;
    spec.height = h;
    spec.orthographic = ortho;
    spec.orthoHeight = orthoHeight;
    spec.fovYDegrees = fov;
    spec.nearZ = nearZ;
    spec.farZ = farZ;
    Camera cam;
    std::string err;
    EXPECT_TRUE(makeCamera(spec, &cam, &err)) << err;
    return cam;
}

LocalRay rayFromTo(const RayScene &rs, Vec3 from, Vec3 to) {
    LocalRay r;
    const Vec3 o = from - rs.origin(), d = to - from;
    for (int a = 0; a < 3; ++a) r.org[a] = float(o[a]), r.dir[a] = float(d[a]);
    return r;
}

// A w x h quad (two triangles) in the plane z = z0 spanning [-s, s]^2, front towards +z or -z.
RawMesh quadZ(double z0, double s, bool frontPlusZ) {
    return frontPlusZ ? gridMesh({-s, -s, z0}, {2 * s, 0, 0}, {0, 2 * s, 0}, 1, 1)
                      : gridMesh({-s, -s, z0}, {0, 2 * s, 0}, {2 * s, 0, 0}, 1, 1);
}

}  // namespace

// Embree's Ng for (v0, v1, v2) is (v1 - v0) x (v2 - v0): the counter-clockwise (front) side, the same
// orientation as Scene::planes. Checked exactly on an axis-aligned triangle and by sign on random ones.
TEST(Raycast, EmbreeNgIsCounterClockwiseFront) {
    const Scene s = sceneOf({triangleMesh({0, 0, 0}, {1, 0, 0}, {0, 1, 0})});
    auto rs = rayScene(s, {0, 0, 0});
    for (double z : {5.0, -5.0}) {  // from the front, then from the back: the same Ng
        const LocalHit h = rs->intersect(rayFromTo(*rs, {0.25, 0.25, z}, {0.25, 0.25, 0}));
        ASSERT_NE(h.prim, kNoHit);
        EXPECT_EQ(h.ng[0], 0.0f);
        EXPECT_EQ(h.ng[1], 0.0f);
        EXPECT_EQ(h.ng[2], 1.0f);  // (1,0,0) x (0,1,0), unnormalized
        EXPECT_FLOAT_EQ(h.t, 1.0f);
    }
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> U(-1, 1);
    int checked = 0;
    for (int i = 0; i < 500; ++i) {
        const Vec3 a{U(rng), U(rng), U(rng)}, b{U(rng), U(rng), U(rng)}, c{U(rng), U(rng), U(rng)};
        const Vec3 n = cross(b - a, c - a);
        if (length(n) < 1e-3) continue;
        const Scene t = sceneOf({triangleMesh(a, b, c)});
        auto r = rayScene(t, {0, 0, 0});
        const Vec3 centroid = (a + b + c) / 3;
        const LocalHit h = r->intersect(rayFromTo(*r, centroid + normalize(n) * 3, centroid));
        ASSERT_NE(h.prim, kNoHit) << i;
        EXPECT_GT(h.ng[0] * n.x + h.ng[1] * n.y + h.ng[2] * n.z, 0) << i;
        ++checked;
    }
    EXPECT_GT(checked, 400);
}

// Back-face rejection: a single-sided quad facing away from the camera in front of a quad facing it.
// Plain ray casting sees the near quad (its back); rejection sees through it to the far quad; a
// double-sided near quad is seen again. Perspective and orthographic, with and without given planes.
TEST(Raycast, BackFaceRejection) {
    const Scene s = sceneOf({quadZ(0, 1, false), quadZ(-2, 10, true)});  // triangles 0,1: near; 2,3: far
    auto rs = rayScene(s);
    for (bool ortho : {false, true}) {
        const Camera cam = cameraOf({0, 0, 5}, {0, 0, 0}, 32, 32, ortho, 3, 30);
        const RaycastImage plain = rs->castPrimary(cam, nullptr);
        PrimaryOptions opt;
        opt.rejectBackFaces = true;
        RaycastStats st;
        const RaycastImage rej = rs->castPrimary(cam, opt, &st);
        opt.planes = s.planes.data();
        const RaycastImage rejPlanes = rs->castPrimary(cam, opt, nullptr);
        const std::vector<uint8_t> ds = {1, 1, 0, 0};
        opt.doubleSided = ds.data();
        const RaycastImage dsImg = rs->castPrimary(cam, opt, nullptr);
        uint64_t nearPixels = 0;
        for (size_t p = 0; p < plain.id.size(); ++p) {
            ASSERT_NE(plain.id[p], 0u) << "the far quad fills the view";
            const bool nearQuad = plain.id[p] <= 2;
            nearPixels += nearQuad;
            if (nearQuad) {
                EXPECT_GE(rej.id[p], 3u) << p;  // seen through the rejected back face
                EXPECT_FLOAT_EQ(rej.depth[p], 7.0f) << p;  // the far quad's view depth
            } else {
                EXPECT_EQ(rej.id[p], plain.id[p]) << p;
            }
            EXPECT_EQ(rejPlanes.id[p], rej.id[p]) << p;
            EXPECT_EQ(dsImg.id[p], plain.id[p]) << p;
            EXPECT_EQ(dsImg.depth[p], plain.depth[p]) << p;
        }
        EXPECT_GT(nearPixels, 200u);
        EXPECT_LT(nearPixels, 32u * 32u);
        EXPECT_EQ(st.hits, st.rays);
    }
}

// A cast over a subset of the triangles (PrimaryOptions::rejectSource, the cross-check's "like with
// like"): a near quad facing the camera in front of a far quad. Rejecting the near quad's triangles
// sees the far quad exactly where the plain cast saw the near one, at the far quad's depth; the
// rest of the image is unchanged; with back-face rejection too, both rules apply.
TEST(Raycast, RejectSourceCastsASubset) {
    const Scene s = sceneOf({quadZ(0, 1, true), quadZ(-2, 10, true)});  // triangles 0,1: near; 2,3: far
    auto rs = rayScene(s);
    for (bool ortho : {false, true}) {
        const Camera cam = cameraOf({0, 0, 5}, {0, 0, 0}, 32, 32, ortho, 3, 30);
        const RaycastImage plain = rs->castPrimary(cam, nullptr);
        const std::vector<uint8_t> outOfSet = {1, 1, 0, 0};
        PrimaryOptions opt;
        opt.rejectSource = outOfSet.data();
        const RaycastImage sub = rs->castPrimary(cam, opt, nullptr);
        opt.rejectBackFaces = true;
        opt.planes = s.planes.data();
        const RaycastImage both = rs->castPrimary(cam, opt, nullptr);
        uint64_t nearPixels = 0;
        for (size_t p = 0; p < plain.id.size(); ++p) {
            ASSERT_NE(plain.id[p], 0u);
            if (plain.id[p] <= 2) {
                ++nearPixels;
                EXPECT_GE(sub.id[p], 3u) << p;
                EXPECT_FLOAT_EQ(sub.depth[p], 7.0f) << p;
            } else {
                EXPECT_EQ(sub.id[p], plain.id[p]) << p;
                EXPECT_EQ(sub.depth[p], plain.depth[p]) << p;
            }
            EXPECT_EQ(both.id[p], sub.id[p]) << p;
        }
        EXPECT_GT(nearPixels, 200u);
    }
}

// A camera inside a closed box: every primary ray hits (the inside is the boxes' back faces);
// with back-face rejection none does.
TEST(Raycast, CameraInsideClosedBox) {
    const Scene s = sceneOf({boxMesh({0.3, -0.2, 0.1}, {2, 1.5, 3})});
    auto rs = rayScene(s);
    for (bool ortho : {false, true}) {
        const Camera cam = cameraOf({0, 0, 0}, {1, 0.2, -3}, 97, 61, ortho, 1.0, 120, 0.01, 100);
        RaycastStats st;
        const RaycastImage img = rs->castPrimary(cam, &st);
        EXPECT_EQ(st.rays, uint64_t(97 * 61));
        EXPECT_EQ(st.hits, st.rays);
        PrimaryOptions opt;
        opt.rejectBackFaces = true;
        rs->castPrimary(cam, opt, &st);
        EXPECT_EQ(st.hits, 0u);
    }
}

// t is the view depth. At every pixel center hit, Embree's t matches the z-buffer's canonical depth
// (camera.h viewDepthAt, double) within |t - d| <= 2^-17 d. Where that bound comes from: the ray's
// float origin and direction and the float vertices carry one rounding each (relative 2^-24), and
// Embree's Pluecker t = T / den adds at most ~16 roundings, amplified by the conditioning
// |Ng| |w0| / |T| (<= ~4 for these triangles, which face the camera within 60 degrees): about
// 4 * 20 * 2^-24 < 2^-17.
TEST(Raycast, DepthEqualsViewDepthAtPixelCenters) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> U(-1, 1);
    double worst = 0;
    uint64_t compared = 0;
    for (int trial = 0; trial < 40; ++trial) {
        const bool ortho = trial % 2 == 1;
        const Vec3 eye{U(rng) * 100, U(rng) * 100, U(rng) * 100};
        const Vec3 fwd = normalize(Vec3{U(rng), U(rng) * 0.3, U(rng)});
        const double dist = 2 + 20 * (U(rng) + 1);
        const Vec3 c = eye + fwd * dist;
        // A triangle around c whose normal is within 60 degrees of -fwd.
        Vec3 n;
        do n = normalize(-fwd + Vec3{U(rng), U(rng), U(rng)} * 0.8);
        while (dot(n, -fwd) < 0.5);
        const Vec3 t1 = normalize(cross(n, Vec3{0.3, 1, 0.1})), t2 = cross(n, t1);
        const double r = dist * 0.4;
        const Vec3 a = c + t1 * r, b = c + (t1 * -0.5 + t2 * 0.866) * r, d = c + (t1 * -0.5 - t2 * 0.866) * r;
        const Scene s = sceneOf({triangleMesh(a, b, d)});
        auto rs = rayScene(s);
        const Camera cam = cameraOf(eye, c, 48, 40, ortho, dist, 60, 0.5, 1000);
        const RaycastImage img = rs->castPrimary(cam, nullptr);
        const DepthPlane plane = depthPlaneFromView(cam, transformPoint(cam.viewFromWorld, a),
                                                    transformPoint(cam.viewFromWorld, b),
                                                    transformPoint(cam.viewFromWorld, d));
        ASSERT_TRUE(plane.valid);
        for (int y = 0; y < cam.height; ++y)
            for (int x = 0; x < cam.width; ++x) {
                const size_t p = size_t(y) * cam.width + x;
                if (!img.id[p]) continue;
                const double ref = viewDepthAt(cam, plane, x + 0.5, y + 0.5);
                const double rel = std::fabs(img.depth[p] - ref) / ref;
                worst = std::max(worst, rel);
                EXPECT_LE(rel, 0x1p-17) << "trial " << trial << " pixel " << x << "," << y;
                ++compared;
            }
    }
    EXPECT_GT(compared, 5000u);
    std::printf("[ info ] worst relative |t - view depth| over %llu pixels: %.3g (bound 2^-17 = %.3g)\n",
                (unsigned long long)compared, worst, 0x1p-17);
}

// Watertight: dense seeded rays from outside a closed UV sphere. Every ray whose line passes within
// 0.99 r of the center must hit (the mesh's inradius is checked to exceed 0.99 r first), near the
// world origin and far from it.
TEST(Raycast, WatertightClosedSphere) {
    for (const Vec3 center : {Vec3{0, 0, 0}, Vec3{3e4, -1e4, 2e4}}) {
        const double r = 5;
        const Scene s = sceneOf({uvSphereMesh(center, r, 64, 32)});
        // Inradius: the smallest distance from the center to a face's plane.
        double inradius = INFINITY;
        for (size_t t = 0; t < s.triangleCount(); ++t) {
            const double *pl = &s.planes[4 * t];
            if (s.triangleObject[t] == kExcludedTriangle) continue;
            const Vec3 n{pl[0], pl[1], pl[2]};
            inradius = std::min(inradius, (dot(n, center) + pl[3]) / -length(n));
        }
        ASSERT_GT(inradius, 0.99 * r);
        auto rs = rayScene(s);
        std::mt19937 rng(1234);
        std::normal_distribution<double> N(0, 1);
        std::uniform_real_distribution<double> U(0, 1);
        uint64_t misses = 0, rays = 0;
        for (int i = 0; i < 200000; ++i) {
            const Vec3 from = center + normalize(Vec3{N(rng), N(rng), N(rng)}) * (r * (1.2 + 8 * U(rng)));
            // A point uniform in the ball of radius 0.99 r: the line passes within 0.99 r of the center.
            const Vec3 aim = center + normalize(Vec3{N(rng), N(rng), N(rng)}) * (0.99 * r * std::cbrt(U(rng)));
            const LocalHit h = rs->intersect(rayFromTo(*rs, from, aim));
            ++rays;
            misses += h.prim == kNoHit;
        }
        EXPECT_EQ(misses, 0u) << "of " << rays << " rays, center " << center.x;
    }
}

// Rays aimed exactly at the midpoint of every shared edge of a closed sphere hit one of the edge's two
// triangles, never slipping through the crack between them.
TEST(Raycast, SharedEdgeMidpointsHitOneOfTwoTriangles) {
    const Vec3 center{7, -3, 2};
    const Scene s = sceneOf({uvSphereMesh(center, 2, 48, 24)});
    auto rs = rayScene(s);
    // Edge -> the triangles (primitives) sharing it. Keyed by corner positions: the sphere is split
    // into culling chunks, each with its own copy of the seam's vertices.
    using P = std::tuple<double, double, double>;
    auto key = [&](uint32_t i) { return P{s.positions[i].x, s.positions[i].y, s.positions[i].z}; };
    std::map<std::pair<P, P>, std::vector<uint32_t>> edges;
    std::map<std::pair<P, P>, std::pair<uint32_t, uint32_t>> edgeVertices;
    for (uint32_t k = 0; k < rs->primitiveCount(); ++k) {
        const uint32_t t = rs->sourceOf(k);
        for (int j = 0; j < 3; ++j) {
            const uint32_t a = s.indices[3 * t + j], b = s.indices[3 * t + (j + 1) % 3];
            const auto e = key(a) < key(b) ? std::make_pair(key(a), key(b)) : std::make_pair(key(b), key(a));
            edges[e].push_back(k);
            edgeVertices[e] = {a, b};
        }
    }
    std::mt19937 rng(99);
    std::uniform_real_distribution<double> U(-1, 1);
    uint64_t aimed = 0;
    for (const auto &[e, tris] : edges) {
        ASSERT_EQ(tris.size(), 2u) << "closed mesh";
        // The midpoint of the float edge as Embree stores it (exact in double).
        const auto [ia, ib] = edgeVertices[e];
        const Vec3 pa = s.positions[ia] - rs->origin(), pb = s.positions[ib] - rs->origin();
        const Vec3 fa{float(pa.x), float(pa.y), float(pa.z)}, fb{float(pb.x), float(pb.y), float(pb.z)};
        const Vec3 mid = (fa + fb) * 0.5;
        const Vec3 out = normalize(mid - (center - rs->origin()));
        for (int k = 0; k < 8; ++k) {
            const Vec3 from = mid + (out + Vec3{U(rng), U(rng), U(rng)} * 0.3) * 3.0;
            LocalRay r;
            for (int a = 0; a < 3; ++a) r.org[a] = float(from[a]), r.dir[a] = float(mid[a] - double(r.org[a]));
            const LocalHit h = rs->intersect(r);
            ASSERT_NE(h.prim, kNoHit) << "edge " << ia << "-" << ib;
            EXPECT_TRUE(h.prim == tris[0] || h.prim == tris[1]) << "edge " << ia << "-" << ib;
            EXPECT_NEAR(h.t, 1.0, 1e-5);
            ++aimed;
        }
    }
    EXPECT_EQ(aimed, 8 * edges.size());
}

// The options overload with default options is the plain cast; barycentrics change nothing else; and
// single rays (intersect on primaryRay) reproduce the packets' hits.
TEST(Raycast, OptionsOverloadAndSingleRaysAgreeWithPackets) {
    const Scene s = demoScene();
    auto rs = rayScene(s);
    for (const ViewSpec &v : s.views) {
        CameraSpec spec = v.camera;
        spec.width = 240;
        spec.height = 135;
        Camera cam;
        std::string err;
        ASSERT_TRUE(makeCamera(spec, &cam, &err)) << err;
        RaycastStats a, b;
        const RaycastImage plain = rs->castPrimary(cam, &a);
        PrimaryOptions opt;
        const RaycastImage same = rs->castPrimary(cam, opt, &b);
        opt.keepBarycentrics = true;
        const RaycastImage bary = rs->castPrimary(cam, opt, nullptr);
        EXPECT_EQ(plain.id, same.id);
        EXPECT_EQ(plain.depth, same.depth);
        EXPECT_EQ(plain.id, bary.id);
        EXPECT_EQ(plain.depth, bary.depth);
        EXPECT_EQ(a.hits, b.hits);
        EXPECT_EQ(a.hits, rs->castPrimaryRaw(cam));
        // Embree's single-ray and packet kernels visit triangles in different orders, and its hit test
        // accepts t <= tfar: where two triangles are hit at a bit-identical t (a ray exactly through a
        // shared edge, or coplanar overlap) the later one found wins, so the two kernels may name
        // different triangles there. Everywhere else they agree exactly; at ties, t is identical.
        uint64_t ties = 0;
        for (int y = 0; y < cam.height; ++y)
            for (int x = 0; x < cam.width; ++x) {
                const size_t p = size_t(y) * cam.width + x;
                const LocalHit h = rs->intersect(rs->primaryRay(cam, x, y));
                const uint32_t id = h.prim == kNoHit ? 0 : 1 + rs->sourceOf(h.prim);
                ASSERT_EQ(id == 0, plain.id[p] == 0) << x << "," << y;
                if (!id) continue;
                EXPECT_EQ(h.t, plain.depth[p]) << x << "," << y;
                if (id != plain.id[p]) {
                    ++ties;
                    continue;
                }
                EXPECT_EQ(h.u, bary.u[p]);
                EXPECT_EQ(h.v, bary.v[p]);
            }
        EXPECT_LT(ties, uint64_t(cam.width) * cam.height / 1000) << v.name;
    }
}

// castPrimary traces bands of tiles in parallel; each pixel's result depends on its ray alone, so ids,
// depths, barycentrics and stats are identical with 1, 2 and 8 threads. An odd resolution puts
// partial packets, tiles and bands at the right and bottom edges; ties and back-face rejection run
// the per-band filter state.
TEST(Raycast, IdenticalForAnyThreadCount) {
    const Scene s = demoScene();
    auto rs = rayScene(s);
    for (const ViewSpec &v : s.views) {
        CameraSpec spec = v.camera;
        spec.width = 203;
        spec.height = 117;
        Camera cam;
        std::string err;
        ASSERT_TRUE(makeCamera(spec, &cam, &err)) << err;
        PrimaryOptions opt;
        opt.rejectBackFaces = true;
        opt.planes = s.planes.data();
        opt.tiesToLowestId = true;
        opt.keepBarycentrics = true;
        std::vector<RaycastImage> images;
        std::vector<RaycastStats> stats;
        for (int threads : {1, 2, 8}) {
            tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
            RaycastStats st;
            images.push_back(rs->castPrimary(cam, opt, &st));
            stats.push_back(st);
        }
        ASSERT_GT(stats[0].hits, 0u) << v.name;
        EXPECT_EQ(stats[0].rays, uint64_t(203 * 117));
        EXPECT_EQ(stats[0].packets, uint64_t(51 * 30));  // ceil(203 / 4) x ceil(117 / 4)
        for (size_t k = 1; k < images.size(); ++k) {
            EXPECT_EQ(images[k].id, images[0].id) << v.name << " " << k;
            EXPECT_EQ(images[k].depth, images[0].depth) << v.name << " " << k;
            EXPECT_EQ(images[k].u, images[0].u) << v.name << " " << k;
            EXPECT_EQ(images[k].v, images[0].v) << v.name << " " << k;
            EXPECT_EQ(stats[k].rays, stats[0].rays);
            EXPECT_EQ(stats[k].hits, stats[0].hits);
            EXPECT_EQ(stats[k].packets, stats[0].packets);
        }
    }
}

// Empty input: a scene without triangles builds and every ray misses.
TEST(Raycast, EmptySceneMissesEverything) {
    RayScene rs;
    std::string err;
    const std::vector<Vec3> pos;
    const std::vector<uint32_t> idx;
    ASSERT_TRUE(rs.build(MeshView{pos.data(), idx.data()}, 0, {}, {0, 0, 0}, &err)) << err;
    const Camera cam = cameraOf({0, 0, 5}, {0, 0, 0}, 8, 8);
    RaycastStats st;
    PrimaryOptions opt;
    opt.rejectBackFaces = true;
    const RaycastImage img = rs.castPrimary(cam, opt, &st);
    EXPECT_EQ(st.rays, 64u);
    EXPECT_EQ(st.hits, 0u);
    EXPECT_EQ(rs.intersect(LocalRay{}).prim, kNoHit);
    EXPECT_FALSE(rs.occluded(LocalRay{}));
    EXPECT_EQ(rs.primitiveOf(0), kNoHit);
}

// Ties to the lowest id (PrimaryOptions::tiesToLowestId): two coplanar copies of a quad, triangulated
// along opposite diagonals, seen by an orthographic camera whose pixel centers lie exactly on both
// diagonals. Every hit is a bit-identical tie between the copies (and on a diagonal, between the two
// triangles of a copy): the lowest source id must win at every pixel, for packets of any layout.
TEST(Raycast, TiesToLowestId) {
    RawMesh first = gridMesh({-1, -1, 0}, {2, 0, 0}, {0, 2, 0}, 1, 1);  // triangles 0 (y <= x), 1 (y >= x)
    RawMesh second = first;
    second.indices = {1, 3, 2, 1, 2, 0};  // the same quad along the other diagonal (positions a, b, d, c)
    for (int order = 0; order < 2; ++order) {
        const Scene s = sceneOf(order == 0 ? std::vector<RawMesh>{first, second} : std::vector<RawMesh>{second, first});
        auto rs = rayScene(s);
        const Camera cam = cameraOf({0, 0, 5}, {0, 0, 0}, 16, 16, true, 2);
        PrimaryOptions opt;
        opt.tiesToLowestId = true;
        const RaycastImage img = rs->castPrimary(cam, opt, nullptr);
        const RaycastImage plain = rs->castPrimary(cam, nullptr);
        uint64_t plainDiffers = 0;
        for (int y = 0; y < 16; ++y)
            for (int x = 0; x < 16; ++x) {
                const double X = -1 + (x + 0.5) / 8, Y = 1 - (y + 0.5) / 8;
                // first: triangle 0 = (a, b, c) covers y <= x, triangle 1 = (a, c, d) covers y >= x;
                // second: triangle 0 = (b, c, d) covers y >= -x, triangle 1 = (b, d, a) covers y <= -x
                // (a..d = the quad's corners (-1,-1), (1,-1), (1,1), (-1,1)). On a diagonal: triangle 0.
                const uint32_t expect = order == 0 ? (Y <= X ? 1 : 2) : (Y >= -X ? 1 : 2);
                const size_t p = size_t(y) * 16 + x;
                EXPECT_EQ(img.id[p], expect) << "order " << order << " pixel " << x << "," << y;
                EXPECT_EQ(img.depth[p], 5.0f);
                plainDiffers += plain.id[p] != expect;
            }
        std::printf("[ info ] order %d: without tiesToLowestId, %llu of 256 pixels name a higher id\n", order,
                    (unsigned long long)plainDiffers);
    }
}
