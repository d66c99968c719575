// The audits (analysis/audits/audit.h): reference visibility, false culls and wasted draws, and the
// z-buffer against the ray caster, on the demo scene, the example hall, the fetched levels and
// analytic scenes; plus ray-casting watertightness.
//
// Every view here runs the pipeline's stages the way analysis/pipeline.cpp does (frustum over the
// object BVH, backface, clip with one batch per object, z-buffer in the view's format), keeping
// what each stage culled, which analyzeView does not return.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "tests/test_util.h"
#include "analysis/audits/audit.h"
#include "analysis/stages/backface.h"
#include "analysis/load/demo.h"
#include "analysis/stages/frustum.h"
#include "analysis/load/load.h"
#include "render/clip.h"
#include "render/raster.h"
#include "render/raycast.h"
#include "reports/audit_images.h"

namespace va {
namespace {

struct ViewRun {
    std::vector<uint32_t> frustumCulled;   // objects
    std::vector<uint32_t> backfaceCulled;  // triangles
    TriangleLists kept;                    // reached the z-buffer
    ZBufferResult z;
    std::vector<uint32_t> fragmentsPerSource;
};

using FrustumFn = std::vector<uint32_t> (*)(const Scene &, const ObjectBvh &, const Camera &);

std::vector<uint32_t> realFrustum(const Scene &scene, const ObjectBvh &bvh, const Camera &cam) {
    return cullFrustum(scene, bvh, cam).visible;
}

// A broken frustum stage for the audit to catch: the four side planes pushed inwards by 2 world
// units (a sphere must be inside by its radius + 2 to count as inside... and is culled as soon as
// it is outside the pushed plane by its radius), no BVH.
std::vector<uint32_t> cullFrustumBroken(const Scene &scene, const ObjectBvh &, const Camera &cam) {
    FrustumPlanes fp = worldFrustumPlanes(cam);
    for (int p = 2; p < 6; ++p) fp.k[p] -= 2.0;  // n.x + k >= 2 is the new inside
    std::vector<uint32_t> visible;
    for (uint32_t o = 0; o < scene.objects.size(); ++o) {
        const Sphere &s = scene.objects[o].sphere;
        bool out = false;
        for (int p = 0; p < 6; ++p) out = out || dot(fp.n[p], s.center) + fp.k[p] < -s.radius;
        if (!out) visible.push_back(o);
    }
    return visible;
}

ViewRun runView(const Scene &scene, const ObjectBvh &bvh, const Camera &cam, DepthFormat format,
                FrustumFn frustum = realFrustum) {
    ViewRun r;
    const std::vector<uint32_t> visible = frustum(scene, bvh, cam);
    std::vector<uint8_t> isVisible(scene.objects.size(), 0);
    for (uint32_t o : visible) isVisible[o] = 1;
    for (uint32_t o = 0; o < scene.objects.size(); ++o)
        if (!isVisible[o]) r.frustumCulled.push_back(o);
    BackfaceResult b = cullBackfaces(scene, visible, cam);
    r.kept = std::move(b.kept);
    std::vector<uint8_t> isKept(scene.triangleCount(), 0);
    for (uint32_t t : r.kept.triangles) isKept[t] = 1;
    for (uint32_t o : visible)
        for (uint32_t i = scene.objects[o].triBegin; i < scene.objects[o].triEnd; ++i)
            if (!isKept[scene.objectTriangles[i]]) r.backfaceCulled.push_back(scene.objectTriangles[i]);
    std::vector<ClipBatch> batches;
    for (size_t g = 0; g < r.kept.objects.size(); ++g) {
        const SceneObject &ob = scene.objects[r.kept.objects[g]];
        const uint32_t count = r.kept.groupBegin[g + 1] - r.kept.groupBegin[g];
        if (count) batches.push_back({ob.vertexBegin, ob.vertexEnd, r.kept.triangles.data() + r.kept.groupBegin[g], count});
    }
    const ClipResult clip = clipTriangles(cam, {scene.positions.data(), scene.indices.data()}, batches, {});
    r.fragmentsPerSource.assign(scene.triangleCount(), 0);
    ZBufferSettings zs;
    zs.encoder = makeDepthEncoder(format, cam.nearZ, cam.farZ);
    zs.orthographic = cam.orthographic;
    zs.fragmentsPerSource = r.fragmentsPerSource.data();
    r.z = rasterize(clip.out, cam.width, cam.height, zs);
    return r;
}

// The ray caster over the triangles the z-buffer's input effectively holds: every triangle the
// backface rule keeps (double-sided ones always), over *all* objects -- the same set as a ray
// scene of the whole scene with single-sided back faces rejected by the plane test (the
// raycast owner's PrimaryOptions::rejectBackFaces). The frustum stage is not applied: what it
// culls lies outside the view, unless it is broken, which is what the cross-check then shows.
RaycastImage castEffective(const Scene &scene, const Camera &cam, Vec3 origin) {
    std::vector<uint32_t> all(scene.objects.size());
    for (uint32_t o = 0; o < all.size(); ++o) all[o] = o;
    const BackfaceResult b = cullBackfaces(scene, all, cam);
    RayScene rs;
    std::string err;
    EXPECT_TRUE(rs.build({scene.positions.data(), scene.indices.data()}, scene.positions.size(), b.kept.triangles, origin,
                         &err))
        << err;
    return rs.castPrimary(cam, nullptr);
}

// Every audit of one view, with the expectations that hold for a correct pipeline.
void auditView(const Scene &scene, const ObjectBvh &bvh, const ViewSpec &spec, const std::string &what) {
    Camera cam;
    std::string err;
    ASSERT_TRUE(makeCamera(spec.camera, &cam, &err)) << what << ": " << err;
    const ReferenceVisibility ref = referenceVisibility(scene, cam);
    const ViewRun run = runView(scene, bvh, cam, spec.depthFormat.format);
    const CullAudit a = auditCulling(scene, ref, {{"frustum", run.frustumCulled, {}}, {"backface", {}, run.backfaceCulled}},
                                     run.kept.triangles, &run.fragmentsPerSource);
    ASSERT_EQ(a.stages.size(), 2u);
    EXPECT_GT(ref.visibleTriangles, 0u) << what;
    EXPECT_EQ(a.stages[0].falseCullTriangles, 0u) << what << ": frustum false culls";
    EXPECT_EQ(a.stages[1].falseCullTriangles, 0u) << what << ": backface false culls";
    EXPECT_EQ(a.unaccountedPixels, 0u) << what;
    EXPECT_EQ(a.stages[0].trianglesCulled + a.stages[1].trianglesCulled + a.drawnTriangles, ref.trianglesIn) << what;
    EXPECT_EQ(a.drawnFragments, run.z.stats.fragments) << what;
    // Every visible triangle was drawn, so wasted = drawn - visible.
    EXPECT_EQ(a.wastedTriangles, a.drawnTriangles - ref.visibleTriangles) << what;
    EXPECT_EQ(a.wastedObjects, a.drawnObjects - ref.visibleObjects) << what;

    // The z-buffer and the reference see the same pixels covered, apart from format ties (where the
    // format keeps the first drawn): every pixel where ids differ has equal keys.
    const DepthEncoder enc = makeDepthEncoder(spec.depthFormat, cam.nearZ, cam.farZ);
    uint64_t idDiff = 0;
    for (size_t i = 0; i < ref.id.size(); ++i) {
        if (ref.id[i] == run.z.buffer.id[i]) continue;
        ++idDiff;
        ASSERT_TRUE(ref.id[i] && run.z.buffer.id[i]) << what << ": coverage differs at pixel " << i;
        ASSERT_EQ(depthKey(enc, ref.depth[i]), run.z.buffer.key[i]) << what << ": pixel " << i;
    }

    const Vec3 origin = scene.bounds.center();
    const RaycastImage img = castEffective(scene, cam, origin);
    const CrossCheck c = crossCheck(run.z.buffer.id, run.z.buffer.depth, img.id, img.depth, scene, cam, enc, origin);
    EXPECT_EQ(c.agree + c.edge + c.tie + c.genuine, c.pixels) << what;
    EXPECT_EQ(c.genuine, 0u) << what << ": first genuine pixel ("
                             << (c.genuineExamples.empty() ? -1 : c.genuineExamples[0].x) << ", "
                             << (c.genuineExamples.empty() ? -1 : c.genuineExamples[0].y) << ")";
    EXPECT_GT(c.agree, c.pixels * 9 / 10) << what;
    EXPECT_LT(c.maxRelativeDepthDifference, 1e-4) << what;
    std::printf("[ audit    ] %s: visible %llu tris, drawn %llu, wasted %llu (%llu fragments); id diffs vs z-buffer %llu; "
                "raycast: agree %llu, edge %llu, tie %llu, genuine %llu\n",
                what.c_str(), (unsigned long long)ref.visibleTriangles, (unsigned long long)a.drawnTriangles,
                (unsigned long long)a.wastedTriangles, (unsigned long long)a.wastedFragments,
                (unsigned long long)idDiff, (unsigned long long)c.agree, (unsigned long long)c.edge,
                (unsigned long long)c.tie, (unsigned long long)c.genuine);
}

void auditScene(const Scene &scene, const std::vector<ViewSpec> &views, const std::string &name) {
    const ObjectBvh bvh = buildObjectBvh(scene);
    ASSERT_FALSE(views.empty());
    for (const ViewSpec &v : views) auditView(scene, bvh, v, name + "/" + v.name);
}

TEST(AuditScenes, Demo) {
    const Scene scene = demoScene();
    auditScene(scene, scene.views, "demo");
}

TEST(AuditScenes, Hall) {
    Scene scene;
    std::string err;
    ASSERT_TRUE(loadScene(std::string(VISAUDIT_EXAMPLES) + "/hall.scene.json", {}, &scene, &err)) << err;
    std::vector<ViewSpec> views = scene.views;
    for (ViewSpec &v : views) {  // smaller images keep the test fast; the geometry is the same
        v.camera.width = std::min(v.camera.width, 640);
        v.camera.height = std::min(v.camera.height, 360);
    }
    auditScene(scene, views, "hall");
}

// Views around a scene's bounds (for meshes without views): 4 perspective, 1 orthographic.
std::vector<ViewSpec> orbitViews(const Scene &scene, char up) {
    const Vec3 c = scene.bounds.center();
    const double r = 0.5 * length(scene.bounds.hi - scene.bounds.lo);
    std::vector<ViewSpec> out;
    const Vec3 upv = up == 'z' ? Vec3{0, 0, 1} : Vec3{0, 1, 0};
    for (int k = 0; k < 5; ++k) {
        ViewSpec v;
        v.name = "orbit" + std::to_string(k);
        const double a = 2 * M_PI * k / 5;
        const Vec3 dir = up == 'z' ? Vec3{std::cos(a), std::sin(a), 0.4} : Vec3{std::cos(a), 0.4, std::sin(a)};
        v.camera.eye = c + normalize(dir) * (2.2 * r);
        v.camera.target = c;
        v.camera.up = upv;
        v.camera.width = 320;
        v.camera.height = 200;
        v.camera.nearZ = 0.05 * r;
        v.camera.farZ = 10 * r;
        v.camera.orthographic = k == 4;
        v.camera.orthoHeight = 2.2 * r;
        v.depthFormat = k % 2 ? DepthFormat::unorm24 : DepthFormat::f32;
        out.push_back(v);
    }
    return out;
}

TEST(AuditScenes, CastleDungeon) {
    const std::string path = std::string(VISAUDIT_TEST_DATA) + "/castle/level/level-dungeon.gltf";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "not fetched: " << path << " (scripts/fetch-data.sh)";
    Scene scene;
    std::string err;
    ASSERT_TRUE(loadScene(path, {}, &scene, &err)) << err;
    std::vector<ViewSpec> views = scene.views;
    for (ViewSpec &v : views) {
        v.camera.width = std::min(v.camera.width, 480);
        v.camera.height = std::min(v.camera.height, 270);
    }
    for (const ViewSpec &v : orbitViews(scene, scene.up)) views.push_back(v);
    auditScene(scene, views, "dungeon");
}

TEST(AuditScenes, Elephant) {
    const std::string path = std::string(VISAUDIT_TEST_DATA) + "/cgal/elephant.off";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "not fetched: " << path << " (scripts/fetch-data.sh)";
    Scene scene;
    std::string err;
    ASSERT_TRUE(loadScene(path, {}, &scene, &err)) << err;
    auditScene(scene, orbitViews(scene, 'y'), "elephant");
}

// ---- A broken stage is caught with the exact count ----------------------------------------------

// Seven unit boxes in a row along x, seen straight on by an orthographic camera 6 units half-wide:
// each box on screen shows exactly its 2 front triangles (the side, top and bottom faces are seen
// exactly edge-on and cover nothing; the back faces are single-sided and face away). The broken
// frustum (side planes 2 units inwards) culls the boxes at x = +-5 (on screen) and +-10 (off
// screen): the expected false culls are 2 triangles per culled box that lies on screen, counted
// here from the geometry alone.
TEST(AuditBroken, FrustumPushedInwardsIsCaughtExactly) {
    const std::vector<double> xs = {-10, -5, -2.5, 0, 2.5, 5, 10};
    SceneBuildInput in;
    in.materials.push_back(Material{});
    for (size_t i = 0; i < xs.size(); ++i)
        in.objects.push_back({"box" + std::to_string(i), "generated", 0, boxMesh({xs[i], 0, 0}, {0.5, 0.5, 0.5})});
    const Scene scene = buildScene(std::move(in));
    const ObjectBvh bvh = buildObjectBvh(scene);
    CameraSpec spec;
    spec.eye = {0, 0, 10};
    spec.target = {0, 0, 0};
    spec.orthographic = true;
    spec.orthoHeight = 6;  // 100 px high: 1 world unit = 100/6 px
    spec.width = 200;      // half-width 6 world units
    spec.height = 100;
    spec.nearZ = 1;
    spec.farZ = 100;
    Camera cam;
    std::string err;
    ASSERT_TRUE(makeCamera(spec, &cam, &err)) << err;
    const double halfWidth = 0.5 * spec.orthoHeight * spec.width / spec.height;

    const ReferenceVisibility ref = referenceVisibility(scene, cam);
    EXPECT_EQ(ref.visibleTriangles, 2u * 5);  // five boxes on screen, 2 front triangles each

    const ViewRun broken = runView(scene, bvh, cam, DepthFormat::f32, cullFrustumBroken);
    uint64_t expected = 0;
    std::vector<std::string> expectedNames;
    for (uint32_t o : broken.frustumCulled) {
        const Sphere &s = scene.objects[o].sphere;
        const bool onScreen = std::fabs(s.center.x) + 0.5 <= halfWidth;
        if (onScreen) {
            expected += 2;
            expectedNames.push_back(scene.objects[o].name);
        }
    }
    ASSERT_EQ(broken.frustumCulled.size(), 4u);  // +-5 and +-10
    ASSERT_EQ(expected, 4u);
    const CullAudit a = auditCulling(scene, ref, {{"frustum", broken.frustumCulled, {}}, {"backface", {}, broken.backfaceCulled}},
                                     broken.kept.triangles, &broken.fragmentsPerSource);
    EXPECT_EQ(a.stages[0].falseCullTriangles, expected);
    EXPECT_EQ(a.stages[0].falseCullObjects, 2u);
    EXPECT_EQ(a.stages[1].falseCullTriangles, 0u);
    ASSERT_EQ(a.stages[0].worst.size(), 2u);
    std::vector<std::string> names = {a.stages[0].worst[0].name, a.stages[0].worst[1].name};
    std::sort(names.begin(), names.end());
    std::sort(expectedNames.begin(), expectedNames.end());
    EXPECT_EQ(names, expectedNames);
    uint64_t px = 0;
    for (const FalseCullOffender &w : a.stages[0].worst) {
        EXPECT_EQ(w.triangles, 2u);
        px += w.pixels;
    }
    EXPECT_EQ(px, a.stages[0].falseCullPixels);
    // Each box face is 1 x 1 world unit = 16.67 x 16.67 px: 16 or 17 centers per axis.
    EXPECT_GE(a.stages[0].falseCullPixels, 2u * 16 * 16);
    EXPECT_LE(a.stages[0].falseCullPixels, 2u * 17 * 17);
    // The fate image marks exactly those pixels as culled by stage 0.
    uint64_t fatePx = 0;
    for (uint8_t f : a.fate) fatePx += f == kFateCulledFirst;
    EXPECT_EQ(fatePx, a.stages[0].falseCullPixels);

    // The real frustum culls only the off-screen boxes: no false cull; and the cross-check of the
    // broken pipeline's z-buffer against the ray caster shows the missing boxes as genuine.
    const ViewRun good = runView(scene, bvh, cam, DepthFormat::f32);
    const CullAudit g = auditCulling(scene, ref, {{"frustum", good.frustumCulled, {}}, {"backface", {}, good.backfaceCulled}},
                                     good.kept.triangles, &good.fragmentsPerSource);
    EXPECT_EQ(good.frustumCulled.size(), 2u);
    EXPECT_EQ(g.stages[0].falseCullTriangles, 0u);
    const Vec3 origin = scene.bounds.center();
    const RaycastImage img = castEffective(scene, cam, origin);
    const DepthEncoder enc = makeDepthEncoder(DepthFormat::f32, cam.nearZ, cam.farZ);
    const CrossCheck cb = crossCheck(broken.z.buffer.id, broken.z.buffer.depth, img.id, img.depth, scene, cam, enc, origin);
    const CrossCheck cg = crossCheck(good.z.buffer.id, good.z.buffer.depth, img.id, img.depth, scene, cam, enc, origin);
    EXPECT_EQ(cg.genuine, 0u);
    // Every genuine disagreement of the broken pipeline is a culled box that the ray caster sees
    // (the edge class also holds the surviving boxes' diagonals, whose centers lie exactly on the
    // shared edge); nearly all of the falsely culled pixels show up as genuine.
    std::vector<uint8_t> culledBox(scene.triangleCount(), 0);
    for (uint32_t o : broken.frustumCulled)
        for (uint32_t i = scene.objects[o].triBegin; i < scene.objects[o].triEnd; ++i) culledBox[scene.objectTriangles[i]] = 1;
    for (size_t i = 0; i < cb.cls.size(); ++i)
        if (cb.cls[i] == uint8_t(Disagreement::genuine)) {
            ASSERT_EQ(broken.z.buffer.id[i], 0u) << i;
            ASSERT_TRUE(img.id[i] && culledBox[img.id[i] - 1]) << i;
        }
    EXPECT_GT(cb.genuine, a.stages[0].falseCullPixels * 9 / 10);
    EXPECT_LE(cb.genuine, a.stages[0].falseCullPixels);
    // Like with like, as the pipeline compares (issue 15): the ray caster over the broken pipeline's
    // own triangles agrees with its z-buffer (no genuine disagreement); the culled boxes are the
    // audit's false culls, and the pixels where the whole-scene rays hit them are the "culled" count.
    {
        std::vector<uint32_t> all(scene.objects.size());
        for (uint32_t o = 0; o < all.size(); ++o) all[o] = o;
        RayScene rs;
        std::string err;
        ASSERT_TRUE(rs.build({scene.positions.data(), scene.indices.data()}, scene.positions.size(),
                             cullBackfaces(scene, all, cam).kept.triangles, origin, &err))
            << err;
        std::vector<uint8_t> outOfSet(scene.triangleCount(), 1);
        for (uint32_t t : broken.kept.triangles) outOfSet[t] = 0;
        PrimaryOptions opt;
        opt.rejectSource = outOfSet.data();
        const RaycastImage same = rs.castPrimary(cam, opt, nullptr);
        const CrossCheck cs = crossCheck(broken.z.buffer.id, broken.z.buffer.depth, same.id, same.depth, scene, cam, enc, origin);
        EXPECT_EQ(cs.genuine, 0u);
        uint64_t culled = 0;
        for (uint32_t id : img.id) culled += id && outOfSet[id - 1];
        EXPECT_GE(culled, cb.genuine);
        EXPECT_LE(culled, a.stages[0].falseCullPixels + 2 * 17 * 4);  // + the boxes' edge pixels
    }

    // The images, read back: the culling image shows exactly the false-cull pixels in stage 0's
    // color above its legend; the diff image the genuine pixels in red; the ids round-trip.
    const std::string dir = ::testing::TempDir() + "/audit_images";
    std::filesystem::create_directories(dir);
    const AuditImageNames files = auditImageNames(dir + "/boxes");
    ASSERT_TRUE(writeCullingImage(ref, a, files.cullingPng, &err)) << err;
    ASSERT_TRUE(writeRaycastDiffImage(broken.z.buffer, cb, files.raycastDiffPng, &err)) << err;
    ASSERT_TRUE(writeRaycastIds(cam.width, cam.height, img.id, files.raycastIdsExr, &err)) << err;
    auto countColor = [&](const ImageData &im, Rgb8 c) {
        uint64_t k = 0;
        for (int y = 0; y < cam.height; ++y)  // the image area, above the legend
            for (int x = 0; x < cam.width; ++x) {
                const uint8_t *p = &im.u8[(size_t(y) * im.width + x) * 3];
                k += p[0] == c.r && p[1] == c.g && p[2] == c.b;
            }
        return k;
    };
    ImageData culling, diff, ids;
    ASSERT_TRUE(readImage(files.cullingPng, &culling, &err)) << err;
    EXPECT_EQ(culling.width, cam.width);
    EXPECT_GT(culling.height, cam.height);  // the legend strip
    EXPECT_EQ(countColor(culling, cullStageColor(0)), a.stages[0].falseCullPixels);
    ASSERT_TRUE(readImage(files.raycastDiffPng, &diff, &err)) << err;
    EXPECT_EQ(countColor(diff, disagreementColor(Disagreement::genuine)), cb.genuine);
    EXPECT_EQ(countColor(diff, disagreementColor(Disagreement::edge)), cb.edge);
    ASSERT_TRUE(readImage(files.raycastIdsExr, &ids, &err)) << err;
    EXPECT_EQ(ids.pixelType, "uint");
    EXPECT_EQ(ids.u32, img.id);
    for (const auto &e : std::filesystem::directory_iterator(dir))
        EXPECT_EQ(e.path().string().find(".tmp-"), std::string::npos) << "temporary file left: " << e.path();
}

// ---- Reference details ------------------------------------------------------------------------

// Camera inside a closed box: single-sided, all its faces are seen from behind and the reference
// shows what lies outside (an object in front); double-sided, its inner walls cover every pixel.
TEST(AuditReference, CameraInsideObject) {
    for (bool doubleSided : {false, true}) {
        SceneBuildInput in;
        Material m;
        m.doubleSided = doubleSided;
        in.materials.push_back(m);
        in.materials.push_back(Material{});
        in.objects.push_back({"room", "generated", 0, boxMesh({0, 0, 0}, {1, 1, 1})});
        in.objects.push_back({"outside", "generated", 1, boxMesh({0, 0, -5}, {1, 1, 1})});
        const Scene scene = buildScene(std::move(in));
        const ObjectBvh bvh = buildObjectBvh(scene);
        ViewSpec v;
        v.name = doubleSided ? "inside-double" : "inside-single";
        v.camera.eye = {0.1, 0.05, 0.2};
        v.camera.target = {0, 0, -5};
        v.camera.width = 96;
        v.camera.height = 64;
        v.camera.nearZ = 0.01;
        v.camera.farZ = 50;
        Camera cam;
        std::string err;
        ASSERT_TRUE(makeCamera(v.camera, &cam, &err)) << err;
        const ReferenceVisibility ref = referenceVisibility(scene, cam);
        const uint32_t roomTris = 12;
        uint64_t roomPixels = 0, outsidePixels = 0;
        for (uint32_t id : ref.id) {
            if (!id) continue;
            (id - 1 < roomTris ? roomPixels : outsidePixels) += 1;
        }
        if (doubleSided) {
            EXPECT_EQ(ref.coveredPixels, uint64_t(96 * 64));
            EXPECT_EQ(roomPixels, uint64_t(96 * 64));
        } else {
            EXPECT_EQ(roomPixels, 0u);
            EXPECT_GT(outsidePixels, 500u);
        }
        auditView(scene, bvh, v, v.name);
    }
}

// Without any culling, the z-buffer with the reference's options (exact depth, single-sided by
// winding, every object, triangles submitted in ascending id) reproduces the reference exactly;
// in the view's format it differs only where keys tie.
TEST(AuditReference, EqualsUnculledZBufferApartFromTies) {
    const Scene scene = demoScene();
    for (const ViewSpec &spec : scene.views) {
        Camera cam;
        std::string err;
        ASSERT_TRUE(makeCamera(spec.camera, &cam, &err)) << err;
        const ReferenceVisibility ref = referenceVisibility(scene, cam);
        // All triangles in ascending id, one batch over every vertex (first drawn = lowest id).
        std::vector<uint32_t> tris;
        for (uint32_t t = 0; t < scene.triangleCount(); ++t)
            if (scene.triangleObject[t] != kExcludedTriangle) tris.push_back(t);
        const std::vector<ClipBatch> batches = {{0, uint32_t(scene.positions.size()), tris.data(), uint32_t(tris.size())}};
        const ClipResult clip = clipTriangles(cam, {scene.positions.data(), scene.indices.data()}, batches, {});
        const std::vector<uint8_t> single = singleSidedTriangles(scene);
        ZBufferSettings zs;
        zs.encoder = makeDepthEncoder(spec.depthFormat, cam.nearZ, cam.farZ);
        zs.orthographic = cam.orthographic;
        zs.singleSided = single.data();
        zs.exactDepth = true;
        const ZBufferResult exact = rasterize(clip.out, cam.width, cam.height, zs);
        EXPECT_EQ(exact.buffer.id, ref.id) << spec.name;
        EXPECT_EQ(exact.buffer.depth, ref.depth) << spec.name;
        EXPECT_EQ(exact.stats.trianglesBackWinding, ref.backWinding) << spec.name;
        zs.exactDepth = false;
        const ZBufferResult fmt = rasterize(clip.out, cam.width, cam.height, zs);
        uint64_t ties = 0;
        for (size_t i = 0; i < ref.id.size(); ++i) {
            if (fmt.buffer.id[i] == ref.id[i]) continue;
            ASSERT_TRUE(ref.id[i] && fmt.buffer.id[i]) << spec.name << " pixel " << i;
            ASSERT_EQ(depthKey(zs.encoder, ref.depth[i]), fmt.buffer.key[i]) << spec.name << " pixel " << i;
            ++ties;
        }
        std::printf("[ audit    ] demo/%s: reference vs format z-buffer: %llu tie pixels\n", spec.name.c_str(),
                    (unsigned long long)ties);
    }
}

// Ties go to the lowest id whatever the submission order: two coplanar overlapping squares in two
// objects listed in both orders. Where the first-listed object (ids 0..7) covers a pixel alone, it
// covers it in the pair too: its pixels are exactly those of a reference of it alone.
TEST(AuditReference, TiesToLowestId) {
    const RawMesh a = gridMesh({-1, -1, 0}, {1, 0, 0}, {0, 1, 0}, 2, 2);      // [-1, 1]^2, 8 triangles
    const RawMesh b = gridMesh({-0.5, -0.5, 0}, {1, 0, 0}, {0, 1, 0}, 2, 2);  // [-0.5, 1.5]^2
    CameraSpec spec;
    spec.eye = {0.1, 0.1, 5};
    spec.target = {0.1, 0.1, 0};
    spec.width = 64;
    spec.height = 64;
    Camera cam;
    std::string err;
    ASSERT_TRUE(makeCamera(spec, &cam, &err)) << err;
    for (bool swap : {false, true}) {
        SceneBuildInput in, alone;
        in.materials.push_back(Material{});
        alone.materials.push_back(Material{});
        in.objects.push_back({"first", "generated", 0, swap ? b : a});
        in.objects.push_back({"second", "generated", 0, swap ? a : b});
        alone.objects.push_back({"first", "generated", 0, swap ? b : a});
        const Scene scene = buildScene(std::move(in)), firstOnly = buildScene(std::move(alone));
        const ReferenceVisibility ref = referenceVisibility(scene, cam), ref1 = referenceVisibility(firstOnly, cam);
        uint64_t overlapWon = 0, secondPx = 0;
        for (size_t i = 0; i < ref.id.size(); ++i) {
            if (ref1.id[i]) {
                ASSERT_EQ(ref.id[i], ref1.id[i]) << "pixel " << i << " swap " << swap;  // same triangle wins
                ++overlapWon;
            } else if (ref.id[i]) {
                ASSERT_GE(ref.id[i] - 1, 8u);
                ++secondPx;
            }
        }
        EXPECT_GT(overlapWon, 100u);
        EXPECT_GT(secondPx, 50u);
    }
}

// ---- Cross-check classification ----------------------------------------------------------------

// edgeDistance on a known square seen straight on (orthographic, 1 world unit = 10 px): the signed
// distance to the boundary in pixels at chosen points, and triangles crossing the near plane.
TEST(AuditCrossCheck, EdgeDistanceAnalytic) {
    SceneBuildInput in;
    in.materials.push_back(Material{});
    RawMesh tri;
    tri.positions = {{-2, -2, 0}, {2, -2, 0}, {-2, 2, 0}};  // right angle at (-2, -2), CCW from +z
    tri.indices = {0, 1, 2};
    in.objects.push_back({"tri", "generated", 0, tri});
    const Scene scene = buildScene(std::move(in));
    for (bool ortho : {true, false}) {
        CameraSpec spec;
        spec.eye = {0, 0, 10};
        spec.target = {0, 0, 0};
        spec.orthographic = ortho;
        spec.orthoHeight = 10;  // 100 px: 10 px per unit
        spec.fovYDegrees = 2 * std::atan(0.5) * 180 / M_PI;  // at depth 10 the view is 10 units high
        spec.width = 100;
        spec.height = 100;
        spec.nearZ = 1;
        spec.farZ = 100;
        Camera cam;
        std::string err;
        ASSERT_TRUE(makeCamera(spec, &cam, &err)) << err;
        // Pixel coordinates of world (x, y) on the plane z = 0: px = 50 + 10 x, py = 50 - 10 y.
        auto at = [&](double x, double y) { return edgeDistance(scene, cam, {0, 0, 0}, 0, 50 + 10 * x, 50 - 10 * y); };
        EXPECT_NEAR(at(-1, -1.5).signedPx, 5.0, 1e-9) << ortho;    // 0.5 above the bottom edge
        EXPECT_NEAR(at(-2.3, 0).signedPx, -3.0, 1e-9) << ortho;    // 0.3 left of the left edge
        EXPECT_NEAR(at(0.5, 0.5).signedPx, -10 * 1 / std::sqrt(2.0), 1e-9) << ortho;  // beyond x + y = 0
        EXPECT_FALSE(at(-1, -1.5).nearEdge);
        EXPECT_TRUE(at(-1, -2 + 1e-4).nearEdge);    // 0.001 px inside the bottom edge
        EXPECT_TRUE(at(-1, -2 - 1e-4).nearEdge);    // 0.001 px outside
        EXPECT_FALSE(at(-1, -2 - 1e-2).nearEdge);   // 0.1 px outside
        EXPECT_LT(at(-1, -1.5).tolerancePx, 0.01);
        EXPECT_GT(at(-1, -1.5).tolerancePx, kSnapEdgeTolerancePx);
    }
    // A triangle crossing the near plane with a vertex behind the eye: the edge planes through the
    // eye still give the distance; the near plane adds its own line.
    SceneBuildInput in2;
    in2.materials.push_back(Material{});
    RawMesh floorTri;
    floorTri.positions = {{-500, -1, 5}, {500, -1, 5}, {0, -1, -500}};  // y = -1, CCW from above; eye at z = 0
    floorTri.indices = {0, 1, 2};
    in2.objects.push_back({"floor", "generated", 0, floorTri});
    const Scene s2 = buildScene(std::move(in2));
    CameraSpec spec;
    spec.eye = {0, 0, 0};
    spec.target = {0, 0, -1};
    spec.fovYDegrees = 90;
    spec.width = 200;
    spec.height = 200;
    spec.nearZ = 0.5;
    spec.farZ = 100;
    Camera cam;
    std::string err;
    ASSERT_TRUE(makeCamera(spec, &cam, &err)) << err;
    // Row py: view ray (x_n, y_n, -1) with y_n = 1 - py / 100 hits y = -1 at depth d = 1 / -y_n
    // (y_n < 0). The near line d = 0.5 is y_n = -2: off screen (the view reaches y_n = -1 at the
    // bottom); the bottom rows see the floor at d = 1 and it is inside by far.
    const EdgeDistance bottom = edgeDistance(s2, cam, {0, 0, 0}, 0, 100.5, 199.5);
    EXPECT_GT(bottom.signedPx, 5) << bottom.signedPx;
    EXPECT_FALSE(bottom.nearEdge);
    // The horizon row (y_n = 0+) sees no floor (d -> infinity beyond far = 100: d = 100 at y_n = -0.01,
    // py = 101): signed distance to the far line is 0 there.
    const EdgeDistance farLine = edgeDistance(s2, cam, {0, 0, 0}, 0, 100.5, 101);
    EXPECT_NEAR(farLine.signedPx, 0, 1e-6);
    EXPECT_TRUE(farLine.nearEdge);
}

// Classification of hand-made disagreements: a pixel well inside two triangles at different
// depths is genuine; at equal depth a tie; at the shared edge of two triangles an edge.
// The agreeing pixels' largest relative depth difference is the largest |ray - z| / z over every
// agreeing pixel with an id and z > 0 (finite quotients only), whichever pixels the cross-check
// skips the division for (one at a time or four at a time): ids agree everywhere, the depths
// cover zero, negative, NaN, infinite and subnormal values and differences that grow and shrink
// along the row, and the image's width leaves a partial group of four at the end.
TEST(AuditCrossCheck, LargestRelativeDepthDifferenceOverEveryAgreeingPixel) {
    Camera cam;
    cam.width = 37;
    cam.height = 29;
    const size_t n = size_t(cam.width) * size_t(cam.height);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> depth(0.1, 500.0), rel(-1e-6, 1e-6);
    for (int trial = 0; trial < 40; ++trial) {
        std::vector<uint32_t> ids(n);
        std::vector<double> z(n);
        std::vector<float> ray(n);
        for (size_t i = 0; i < n; ++i) {
            ids[i] = rng() % 5 == 0 ? 0u : 1 + uint32_t(rng() % 1000);
            z[i] = depth(rng);
            // A difference that rises across the image now and then, so the maximum moves late too.
            const double scale = (rng() % 50 == 0) ? 1e3 * double(i) / double(n) : 1.0;
            ray[i] = float(z[i] * (1 + scale * rel(rng)));
            switch (rng() % 64) {
            case 0: z[i] = 0; break;
            case 1: z[i] = -z[i]; break;
            case 2: z[i] = std::numeric_limits<double>::quiet_NaN(); break;
            case 3: z[i] = INFINITY; break;
            case 4: z[i] = 1e-310; break;
            case 5: ray[i] = std::numeric_limits<float>::quiet_NaN(); break;
            case 6: ray[i] = float(z[i]); z[i] = double(ray[i]); break;  // no difference at all
            default: break;
            }
        }
        double want = 0;
        for (size_t i = 0; i < n; ++i) {
            if (!ids[i] || !(z[i] > 0)) continue;
            const double q = std::fabs(double(ray[i]) - z[i]) / z[i];
            if (std::isfinite(q)) want = std::max(want, q);
        }
        const Scene scene;
        const CrossCheck c = crossCheck(ids, z, ids, ray, scene, cam, makeDepthEncoder(DepthFormat::f32, 0.1, 1000),
                                        Vec3{0, 0, 0});
        EXPECT_EQ(c.agree, n) << "trial " << trial;
        EXPECT_EQ(c.maxRelativeDepthDifference, want) << "trial " << trial;
    }
    // A difference that rises by a hundred-thousandth of itself from pixel to pixel up to pixel 601
    // and drops back after it (exact floats at depth 1): every pixel up to the peak raises the
    // maximum, and the peak, inside a group of four, holds it.
    std::vector<uint32_t> ids(n, 1);
    std::vector<double> z(n, 1.0);
    std::vector<float> ray(n);
    for (size_t i = 0; i < n; ++i) ray[i] = float(1 + double(100000 + (i <= 601 ? i : 0)) * 0x1p-23);
    const Scene scene;
    const CrossCheck c = crossCheck(ids, z, ids, ray, scene, cam, makeDepthEncoder(DepthFormat::f32, 0.1, 1000), Vec3{0, 0, 0});
    EXPECT_EQ(c.maxRelativeDepthDifference, double(100000 + 601) * 0x1p-23);
}

TEST(AuditCrossCheck, ClassifyHandMade) {
    SceneBuildInput in;
    in.materials.push_back(Material{});
    RawMesh m;
    // A: square [-2, 2]^2 at z = 0 (2 triangles, ids 0, 1); B: the same square at z = -1 (ids 2, 3);
    // C: the same square at z = 0 again (ids 4, 5: coplanar with A).
    for (double z : {0.0, -1.0, 0.0}) {
        const uint32_t base = uint32_t(m.positions.size());
        m.positions.insert(m.positions.end(), {{-2, -2, z}, {2, -2, z}, {2, 2, z}, {-2, 2, z}});
        m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
    }
    in.objects.push_back({"squares", "generated", 0, m});
    const Scene scene = buildScene(std::move(in));
    CameraSpec spec;
    spec.eye = {0.01, 0.02, 10};
    spec.target = {0.01, 0.02, 0};
    spec.width = 64;
    spec.height = 64;
    spec.nearZ = 1;
    spec.farZ = 100;
    Camera cam;
    std::string err;
    ASSERT_TRUE(makeCamera(spec, &cam, &err)) << err;
    const DepthEncoder enc = makeDepthEncoder(DepthFormat::f32, 1, 100);
    const Vec3 o{0, 0, 0};
    // The pixel of world (1.2, -0.8, 0): inside triangle 0 (the x > y half of A), 0.8 units or more
    // from its edges (several pixels).
    const Vec4 clip = mul(cam.clipFromWorld, Vec4{1.2, -0.8, 0, 1});
    const int x = int((clip.x / clip.w + 1) * 32), y = int((1 - clip.y / clip.w) * 32);
    ASSERT_GT(edgeDistance(scene, cam, o, 0, x + 0.5, y + 0.5).signedPx, 3.0);
    EXPECT_EQ(classifyDisagreement(scene, cam, enc, o, x, y, 1, 3), Disagreement::genuine);  // A vs B
    EXPECT_EQ(classifyDisagreement(scene, cam, enc, o, x, y, 1, 5), Disagreement::tie);      // A vs C
    EXPECT_EQ(classifyDisagreement(scene, cam, enc, o, x, y, 1, 0), Disagreement::genuine);  // A vs nothing
    EXPECT_EQ(classifyDisagreement(scene, cam, enc, o, x, y, 1, 1), Disagreement::none);
    // A pixel whose center lies on the diagonal of A (shared by ids 0 and 1): the square diagonal
    // through (-2,-2) and (2,2) passes through pixel centers only if the view is symmetric; find the
    // center nearest the diagonal and check it is classified edge when its distance is tiny.
    int best = -1;
    double bestD = 1e9;
    for (int i = 0; i < 64; ++i) {
        const EdgeDistance e = edgeDistance(scene, cam, o, 0, i + 0.5, 63 - i + 0.5);
        if (std::fabs(e.signedPx) < bestD) {
            bestD = std::fabs(e.signedPx);
            best = i;
        }
    }
    ASSERT_GE(best, 0);
    const EdgeDistance e = edgeDistance(scene, cam, o, 0, best + 0.5, 63 - best + 0.5);
    EXPECT_EQ(classifyDisagreement(scene, cam, enc, o, best, 63 - best, 1, 2),
              e.nearEdge ? Disagreement::edge : Disagreement::tie);
}

// edgeDistance as it was written before its per-triangle terms were kept (every part per pixel):
// the reference the memo and the plain call are compared with, bit for bit.
EdgeDistance edgeDistanceFromScratch(const ViewTriangle &v, const Camera &cam, double px, double py) {
    constexpr double u = 0x1p-24;
    const double gamma = kEmbreeEdgeOps * u / (1 - kEmbreeEdgeOps * u);
    EdgeDistance out;
    double sigma;
    if (cam.orthographic) {
        const double a2 = (v.P[1].x - v.P[0].x) * (v.P[2].y - v.P[0].y) - (v.P[1].y - v.P[0].y) * (v.P[2].x - v.P[0].x);
        sigma = a2 > 0 ? -1 : (a2 < 0 ? 1 : 0);
    } else {
        const double det = dot(v.P[0], cross(v.P[1], v.P[2]));
        sigma = det > 0 ? 1 : (det < 0 ? -1 : 0);
    }
    if (sigma == 0 || !v.plane.valid) {
        out.nearEdge = true;
        out.tolerancePx = kSnapEdgeTolerancePx;
        return out;
    }
    auto edgeF = [&](int i, int j, const ViewRay &r) {
        return dot(cross(v.P[i] - r.origin, v.P[j] - r.origin), r.direction);
    };
    const ViewRay r = viewRayThroughPixel(cam, px, py);
    const ViewRay rx = viewRayThroughPixel(cam, px + 1, py), ry = viewRayThroughPixel(cam, px, py + 1);
    const double q[3] = {length(v.P[0] - r.origin), length(v.P[1] - r.origin), length(v.P[2] - r.origin)};
    const double dl = length(r.direction);
    double minS = INFINITY, minTol = kSnapEdgeTolerancePx;
    bool allAbove = true, anyWithin = false;
    auto take = [&](double s, double tol) {
        if (s < -tol) allAbove = false;
        if (s <= tol) anyWithin = true;
        if (s < minS) minS = s, minTol = tol;
    };
    for (int k = 0; k < 3; ++k) {
        const int i = k, j = (k + 1) % 3;
        const double f = edgeF(i, j, r);
        const double gx = edgeF(i, j, rx) - f, gy = edgeF(i, j, ry) - f;
        const double g = std::hypot(gx, gy);
        const double df = (gamma * q[i] * q[j] + std::sqrt(3.0) * u * (v.M[i] * q[j] + v.M[j] * q[i])) * dl;
        if (g > 0) take(sigma * f / g, kSnapEdgeTolerancePx + df / g);
        else take(sigma * f > 0 ? INFINITY : -INFINITY, kSnapEdgeTolerancePx);
    }
    const double pv = evalDepthPlane(v.plane, px, py);
    const double gp = std::hypot(v.plane.a, v.plane.b);
    const double d = cam.orthographic ? pv : 1 / pv;
    double dErr = 0;
    if (std::isfinite(d) && d > 0) {
        const Vec3 n = cross(v.P[1] - v.P[0], v.P[2] - v.P[0]);
        const double nl = length(n);
        double maxM = 0, maxQ = 0;
        for (int i = 0; i < 3; ++i) maxM = std::max(maxM, v.M[i]), maxQ = std::max(maxQ, q[i]);
        const double across = std::sqrt(3.0) * u * maxM + gamma * (d * length(r.direction) + maxQ);
        const double cosine = nl > 0 ? std::fabs(dot(n, r.direction)) / nl : 0;
        dErr = cosine > 0 ? across / cosine + u * d : INFINITY;
    }
    for (int side = 0; side < 2; ++side) {
        const double limit = side == 0 ? cam.nearZ : cam.farZ;
        double s, tolValue;
        if (cam.orthographic) {
            s = side == 0 ? pv - limit : limit - pv;
            tolValue = dErr + u * limit;
        } else {
            s = side == 0 ? 1 / limit - pv : pv - 1 / limit;
            tolValue = (dErr + u * limit) / (limit * limit);
        }
        if (gp > 0) take(s / gp, kSnapEdgeTolerancePx + tolValue / gp);
        else take(s >= 0 ? INFINITY : -INFINITY, kSnapEdgeTolerancePx);
    }
    out.signedPx = minS;
    out.tolerancePx = minTol;
    out.nearEdge = allAbove && anyWithin;
    return out;
}

// Random triangles a few units in front of the eye of edgeTestCamera, some reaching behind it
// (every fifth), some edge-on (every seventh: no area).
std::vector<std::array<Vec3, 3>> edgeTestTriangles(unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> U(-4, 4);
    std::vector<std::array<Vec3, 3>> tris;
    for (int i = 0; i < 40; ++i) {
        const Vec3 c{U(rng), U(rng), U(rng) - 6};
        std::array<Vec3, 3> t;
        for (auto &p : t) p = c + Vec3{U(rng), U(rng), U(rng) * (i % 5 == 0 ? 3 : 0.5)};
        if (i % 7 == 0) t[2] = t[0] + (t[1] - t[0]) * 0.5;  // degenerate: no area
        tris.push_back(t);
    }
    return tris;
}
// A 64 x 48 camera at (0.3, -0.2, 1) looking at (0, 0, -6), near 0.1, far 1000.
void edgeTestCamera(bool orthographic, CameraSpec &cs, Camera &cam) {
    cs.eye = {0.3, -0.2, 1};
    cs.target = {0, 0, -6};
    cs.orthographic = orthographic;
    cs.width = 64;
    cs.height = 48;
    std::string err;
    ASSERT_TRUE(makeCamera(cs, &cam, &err)) << err;
}

// The memo (per-triangle terms kept, a pixel's rays shared by the triangles asked there) and the
// plain call give edgeDistanceFromScratch's values bit for bit: random triangles, some reaching
// behind the eye, some edge-on, both projections, the memo asked in runs along rows, alternating
// between two triangles at a pixel and switching among more than it keeps.
TEST(AuditEdgeDistance, MemoEqualsFromScratchBitForBit) {
    const std::vector<std::array<Vec3, 3>> tris = edgeTestTriangles(11);
    const Scene scene = testing_util::looseTriangles(tris, true);
    for (bool ortho : {false, true}) {
        CameraSpec cs;
        Camera cam;
        ASSERT_NO_FATAL_FAILURE(edgeTestCamera(ortho, cs, cam));
        const Vec3 origin{0.5, 0.25, -2};
        EdgeDistanceMemo memo(scene, cam, origin);
        uint64_t compared = 0, near = 0;
        auto same = [&](const EdgeDistance &a, const EdgeDistance &b) {
            return std::memcmp(&a.signedPx, &b.signedPx, sizeof(double)) == 0 &&
                   std::memcmp(&a.tolerancePx, &b.tolerancePx, sizeof(double)) == 0 && a.nearEdge == b.nearEdge;
        };
        // Along rows, then down columns (the same column at the next row: only py changes).
        std::vector<std::pair<int, int>> pixels;
        for (int y = 0; y < cs.height; y += 3)
            for (int x = 0; x < cs.width; ++x) pixels.push_back({x, y});
        for (int x = 1; x < cs.width; x += 5)
            for (int y = 0; y < cs.height; ++y) pixels.push_back({x, y});
        for (const auto &[x, y] : pixels) {
                const double px = x + 0.5, py = y + 0.5;
                // Two triangles at each pixel, a third one every few pixels (the memo keeps two).
                const uint32_t ts[3] = {uint32_t((x / 8 + y) % 40), uint32_t((x / 8 + y + 13) % 40), uint32_t(x * 7 % 40)};
                for (int k = 0; k < (x % 5 == 0 ? 3 : 2); ++k) {
                    const ViewTriangle v = viewTriangle(scene, cam, origin, ts[k]);
                    const EdgeDistance expect = edgeDistanceFromScratch(v, cam, px, py);
                    ASSERT_TRUE(same(memo(ts[k], px, py), expect)) << ortho << " " << x << " " << y << " " << ts[k];
                    ASSERT_TRUE(same(edgeDistance(v, cam, px, py), expect));
                    ++compared;
                    near += expect.nearEdge;
                }
            }
        EXPECT_GT(compared, 1000u);
        EXPECT_GT(near, 0u);
    }
}

// EdgeDistanceMemo::nearEdge gives operator()'s nearEdge for every input: at the pixel centers of
// random triangles (some reaching behind the eye, some edge-on; both projections), and at points
// bisected onto the line where the answer flips between "inside" and "near an edge", where the
// bounds of its shortcut must leave the answer to operator(). Mutations: dropping the slack or the
// tolerance's factor, or answering false once the edges pass, fail it.
TEST(AuditEdgeDistance, NearEdgeShortcutGivesTheFullAnswer) {
    std::vector<std::array<Vec3, 3>> tris = edgeTestTriangles(23);
    // Four cut by the near plane (0.1 in front of the eye at z = 1) and four by the far one (1000).
    for (int i = 0; i < 4; ++i) {
        const double a = 0.4 * i;
        tris.push_back({Vec3{-3 + a, -2, 0.95}, Vec3{3, -2 + a, 0.85}, Vec3{a, 3, -9}});
        tris.push_back({Vec3{-400 - 50 * a, -300, -900}, Vec3{500, -350 + a, -1100}, Vec3{a, 450, -950 - 100 * a}});
    }
    const Scene scene = testing_util::looseTriangles(tris, true);
    for (bool ortho : {false, true}) {
        CameraSpec cs;
        Camera cam;
        ASSERT_NO_FATAL_FAILURE(edgeTestCamera(ortho, cs, cam));
        const Vec3 origin{0.5, 0.25, -2};
        EdgeDistanceMemo shortcut(scene, cam, origin), full(scene, cam, origin);
        uint64_t inside = 0, near = 0, flips = 0;
        auto clearlyInside = [&](uint32_t t, double px, double py) {
            const EdgeDistance e = full(t, px, py);
            return e.signedPx > e.tolerancePx;
        };
        for (uint32_t t = 0; t < tris.size(); ++t)
            for (int y = 0; y < cs.height; ++y) {
                const double py = y + 0.5;
                bool last = false;
                for (int x = 0; x < cs.width; ++x) {
                    const double px = x + 0.5;
                    const bool expect = full(t, px, py).nearEdge;
                    ASSERT_EQ(shortcut.nearEdge(t, px, py), expect) << ortho << " " << t << " " << px << " " << py;
                    const bool in = clearlyInside(t, px, py);
                    inside += in;
                    near += expect;
                    if (x > 0 && in != last) {
                        // Bisect between the two centers onto where "clearly inside" ends (the
                        // answer flips there), then ask on both sides of it.
                        double lo = px - 1, hi = px;
                        for (int i = 0; i < 80 && std::nextafter(lo, hi) < hi; ++i) {
                            const double mid = lo + (hi - lo) / 2;
                            (clearlyInside(t, mid, py) == last ? lo : hi) = mid;
                        }
                        for (double q : {lo, hi, std::nextafter(lo, -1e300), std::nextafter(hi, 1e300)}) {
                            const bool e = full(t, q, py).nearEdge;
                            near += e;
                            ASSERT_EQ(shortcut.nearEdge(t, q, py), e) << ortho << " " << t << " " << q << " " << py;
                            // Another triangle at the same point in between (the memo keeps two).
                            const uint32_t o = uint32_t((t + 1) % tris.size());
                            ASSERT_EQ(shortcut.nearEdge(o, q, py), full(o, q, py).nearEdge);
                        }
                        ++flips;
                    }
                    last = in;
                }
            }
        EXPECT_GT(inside, 1000u) << ortho;
        EXPECT_GT(near, 100u) << ortho;
        EXPECT_GT(flips, 100u) << ortho;
    }
}

// ---- Watertightness ----------------------------------------------------------------------------

// Dense random rays through a closed UV sphere from outside never miss when their line passes the
// center closer than the tessellation's inradius bound (with a 10% margin): every face's vertices
// lie on the sphere within an angular distance alpha = 2 pi / S + pi / B of each other (one azimuth
// step plus one polar step), so every face plane is at least r cos(alpha) from the center, and a
// line closer than that enters the solid. The z-buffer of the same views has no background pixel
// on such rays either (no crack), and covers every one of them exactly once with backface culling
// (closed mesh: one front face per ray).
TEST(AuditWatertight, ClosedSphereRandomRays) {
    const int S = 48, B = 24;
    const double radius = 3;
    const Vec3 center{1, -2, 0.5};
    SceneBuildInput in;
    in.materials.push_back(Material{});
    in.objects.push_back({"sphere", "generated", 0, uvSphereMesh(center, radius, S, B)});
    const Scene scene = buildScene(std::move(in), ChunkSettings{512});
    const double inradius = radius * std::cos(2 * M_PI / S + M_PI / B);
    const double margin = 0.9 * inradius;
    std::vector<uint32_t> all;
    for (uint32_t t = 0; t < scene.triangleCount(); ++t)
        if (scene.triangleObject[t] != kExcludedTriangle) all.push_back(t);
    RayScene rs;
    std::string err;
    ASSERT_TRUE(rs.build({scene.positions.data(), scene.indices.data()}, scene.positions.size(), all, center, &err)) << err;
    const ObjectBvh bvh = buildObjectBvh(scene);
    std::mt19937 rng(12345);
    std::uniform_real_distribution<double> U(-1, 1);
    uint64_t tested = 0, missed = 0, cracks = 0, doubles = 0;
    for (int cam_i = 0; cam_i < 40; ++cam_i) {
        Vec3 dir;
        do dir = {U(rng), U(rng), U(rng)}; while (length(dir) < 0.1 || length(dir) > 1);
        CameraSpec spec;
        spec.eye = center + normalize(dir) * (radius * (1.5 + 3 * (U(rng) + 1)));  // 1.5 r .. 7.5 r away
        spec.target = center + Vec3{U(rng), U(rng), U(rng)} * (0.5 * inradius);
        spec.up = std::fabs(normalize(dir).y) > 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
        spec.fovYDegrees = 20 + 50 * (U(rng) + 1) / 2;
        spec.width = 80;
        spec.height = 60;
        spec.nearZ = 0.01;
        spec.farZ = 100;
        Camera cam;
        ASSERT_TRUE(makeCamera(spec, &cam, &err)) << err;
        const RaycastImage img = rs.castPrimary(cam, nullptr);
        const ViewRun run = runView(scene, bvh, cam, DepthFormat::f32);
        for (int y = 0; y < cam.height; ++y)
            for (int x = 0; x < cam.width; ++x) {
                // The ray's line in world space and its distance to the center.
                const ViewRay vr = viewRayThroughPixel(cam, x + 0.5, y + 0.5);
                const Vec3 d = normalize(cam.right * vr.direction.x + cam.up * vr.direction.y - cam.forward * vr.direction.z);
                const Vec3 toC = center - spec.eye;
                const double dist = length(toC - d * dot(toC, d));
                if (dist >= margin || dot(toC, d) <= 0) continue;
                ++tested;
                const size_t i = size_t(y) * cam.width + x;
                missed += img.id[i] == 0;
                cracks += run.z.buffer.id[i] == 0;
                doubles += run.z.buffer.fragments[i] != 1;
            }
    }
    EXPECT_GT(tested, 40000u);
    EXPECT_EQ(missed, 0u);
    EXPECT_EQ(cracks, 0u);
    EXPECT_EQ(doubles, 0u);
}

// The elephant (a closed mesh from CGAL's data), same property for rays through points well inside:
// targets are vertices' centroid pulled towards ... not analytic, so only for the fetched file: rays
// aimed at random vertices of the mesh from outside its bounds must hit (a ray towards a vertex meets
// the surface at or before it).
TEST(AuditWatertight, ElephantRaysTowardsVertices) {
    const std::string path = std::string(VISAUDIT_TEST_DATA) + "/cgal/elephant.off";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "not fetched: " << path;
    Scene scene;
    std::string err;
    ASSERT_TRUE(loadScene(path, {}, &scene, &err)) << err;
    std::vector<uint32_t> all;
    for (uint32_t t = 0; t < scene.triangleCount(); ++t)
        if (scene.triangleObject[t] != kExcludedTriangle) all.push_back(t);
    RayScene rs;
    const Vec3 c = scene.bounds.center();
    ASSERT_TRUE(rs.build({scene.positions.data(), scene.indices.data()}, scene.positions.size(), all, c, &err)) << err;
    // Orthographic cameras from random directions; every pixel whose ray passes through a vertex's
    // neighbourhood... a vertex lies on the surface, so pixels whose center projects within the
    // projection of a front triangle are hit: compare to the z-buffer without culling (its coverage
    // is exact): no pixel covered by the z-buffer may be missed by the ray caster except at edges.
    std::mt19937 rng(777);
    std::uniform_real_distribution<double> U(-1, 1);
    const ObjectBvh bvh = buildObjectBvh(scene);
    const double r = 0.5 * length(scene.bounds.hi - scene.bounds.lo);
    uint64_t genuine = 0, pixels = 0;
    for (int k = 0; k < 12; ++k) {
        Vec3 dir;
        do dir = {U(rng), U(rng), U(rng)}; while (length(dir) < 0.1 || length(dir) > 1);
        ViewSpec v;
        v.camera.eye = c + normalize(dir) * (3 * r);
        v.camera.target = c;
        v.camera.up = std::fabs(normalize(dir).y) > 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
        v.camera.orthographic = k % 2;
        v.camera.orthoHeight = 2.2 * r;
        v.camera.fovYDegrees = 45;
        v.camera.width = 160;
        v.camera.height = 120;
        v.camera.nearZ = 0.1 * r;
        v.camera.farZ = 10 * r;
        Camera cam;
        ASSERT_TRUE(makeCamera(v.camera, &cam, &err)) << err;
        const RaycastImage img = rs.castPrimary(cam, nullptr);
        // Against the unculled z-buffer of every triangle (both sides): coverage differences are
        // edges only.
        const ClipResult clip = clipTriangles(
            cam, {scene.positions.data(), scene.indices.data()},
            {{0, uint32_t(scene.positions.size()), all.data(), uint32_t(all.size())}}, {});
        ZBufferSettings zs;
        zs.encoder = makeDepthEncoder(DepthFormat::f32, cam.nearZ, cam.farZ);
        zs.orthographic = cam.orthographic;
        const ZBufferResult z = rasterize(clip.out, cam.width, cam.height, zs);
        const CrossCheck cc = crossCheck(z.buffer.id, z.buffer.depth, img.id, img.depth, scene, cam, zs.encoder, c);
        genuine += cc.genuine;
        pixels += z.stats.coveredPixels;
    }
    EXPECT_GT(pixels, 10000u);
    EXPECT_EQ(genuine, 0u);
}

// Rays exactly along a shared edge (pixel centers on the diagonal of a square split in two) and
// through a vertex shared by six triangles: the ray caster never misses, the z-buffer covers each
// center exactly once.
TEST(AuditWatertight, GrazingSharedEdgeAndVertex) {
    SceneBuildInput in;
    in.materials.push_back(Material{});
    RawMesh m;
    // Orthographic, 16 x 16 px over 16 x 16 world units: pixel (i, j) center is world
    // (i + 0.5 - 8, 8 - j - 0.5). The square [-4.5, 4.5]^2 split along y = x: the diagonal passes
    // through the centers with i + j = 15. A hexagon fan around (0.5, 0.5) (a pixel center).
    m.positions = {{-4.5, -4.5, 0}, {4.5, -4.5, 0}, {4.5, 4.5, 0}, {-4.5, 4.5, 0}};
    m.indices = {0, 1, 2, 0, 2, 3};
    in.objects.push_back({"square", "generated", 0, m});
    RawMesh hex;
    hex.positions.push_back({0.5, 0.5, -3});
    for (int k = 0; k < 6; ++k)
        hex.positions.push_back({0.5 + 2 * std::cos(k * M_PI / 3), 0.5 + 2 * std::sin(k * M_PI / 3), -3});
    for (uint32_t k = 0; k < 6; ++k) hex.indices.insert(hex.indices.end(), {0, 1 + k, 1 + (k + 1) % 6});
    in.objects.push_back({"hexagon", "generated", 0, hex});
    for (int which = 0; which < 2; ++which) {
        SceneBuildInput copy = in;
        copy.objects.erase(copy.objects.begin() + (1 - which));
        const Scene scene = buildScene(std::move(copy));
        CameraSpec spec;
        spec.eye = {0, 0, 10};
        spec.target = {0, 0, 0};
        spec.orthographic = true;
        spec.orthoHeight = 16;
        spec.width = 16;
        spec.height = 16;
        spec.nearZ = 1;
        spec.farZ = 100;
        Camera cam;
        std::string err;
        ASSERT_TRUE(makeCamera(spec, &cam, &err)) << err;
        std::vector<uint32_t> all;
        for (uint32_t t = 0; t < scene.triangleCount(); ++t) all.push_back(t);
        RayScene rs;
        ASSERT_TRUE(rs.build({scene.positions.data(), scene.indices.data()}, scene.positions.size(), all, {0, 0, 0}, &err));
        const RaycastImage img = rs.castPrimary(cam, nullptr);
        const ClipResult clip = clipTriangles(
            cam, {scene.positions.data(), scene.indices.data()},
            {{0, uint32_t(scene.positions.size()), all.data(), uint32_t(all.size())}}, {});
        ZBufferSettings zs;
        zs.encoder = makeDepthEncoder(DepthFormat::f32, 1, 100);
        zs.orthographic = true;
        const ZBufferResult z = rasterize(clip.out, 16, 16, zs);
        if (which == 0) {
            for (int i = 4; i <= 11; ++i) {  // diagonal centers inside the square
                const size_t p = size_t(15 - i) * 16 + i;
                EXPECT_NE(img.id[p], 0u) << "ray along the shared edge missed at pixel " << i;
                EXPECT_EQ(z.buffer.fragments[p], 1) << i;
            }
        } else {
            const size_t p = size_t(8 - 1) * 16 + 8;  // world (0.5, 0.5): i = 8, j = 7
            EXPECT_NE(img.id[p], 0u);
            EXPECT_EQ(z.buffer.fragments[p], 1);
        }
    }
}

}  // namespace
}  // namespace va
