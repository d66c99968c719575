// The detail audit (analysis/audits/detail.h): exact counts on a box seen face-on orthographically, a
// dense far sphere flagged "too small", a dense mid-distance sphere flagged "over-detailed" with
// the triangles a coarser level of detail saves, computed here from the reference visibility.
#include <gtest/gtest.h>

#include <cmath>

#include "analysis/audits/audit.h"
#include "analysis/load/demo.h"
#include "analysis/audits/detail.h"
#include "render/clip.h"
#include "render/raster.h"

namespace va {
namespace {

struct Drawn {
    std::vector<uint32_t> triangles;
    std::vector<uint32_t> fragments;
    ZBufferResult z;
};

// Every triangle of every object through the clipper and the z-buffer (no culling stage).
Drawn drawAll(const Scene &s, const Camera &cam) {
    Drawn d;
    std::vector<ClipBatch> batches;
    for (const SceneObject &o : s.objects) {
        batches.push_back({o.vertexBegin, o.vertexEnd, s.objectTriangles.data() + o.triBegin, o.triEnd - o.triBegin});
        for (uint32_t i = o.triBegin; i < o.triEnd; ++i) d.triangles.push_back(s.objectTriangles[i]);
    }
    const ClipResult clip = clipTriangles(cam, {s.positions.data(), s.indices.data()}, batches, {});
    d.fragments.assign(s.triangleCount(), 0);
    ZBufferSettings zs;
    zs.encoder = makeDepthEncoder(DepthFormat::f32, cam.nearZ, cam.farZ);
    zs.orthographic = cam.orthographic;
    zs.fragmentsPerSource = d.fragments.data();
    d.z = rasterize(clip.out, cam.width, cam.height, zs);
    return d;
}

Camera camera(const CameraSpec &cs) {
    Camera c;
    std::string err;
    EXPECT_TRUE(makeCamera(cs, &c, &err)) << err;
    return c;
}

// A unit box face-on, orthographic, 100 px per world unit: its front face covers exactly
// 100 x 100 pixel centers (edges at pixel boundaries 50 and 150, centers at .5); its four side
// faces are seen exactly edge-on (8 triangles, no center); its back face is hidden.
TEST(DetailExact, BoxFaceOn) {
    SceneBuildInput in;
    in.materials.push_back(Material{});
    in.objects.push_back({"box", "generated", 0, boxMesh({0, 0, 0}, {0.5, 0.5, 0.5})});
    const Scene s = buildScene(std::move(in));
    CameraSpec cs;
    cs.eye = {0, 0, 10};
    cs.target = {0, 0, 0};
    cs.orthographic = true;
    cs.orthoHeight = 2;
    cs.width = cs.height = 200;
    cs.nearZ = 1;
    cs.farZ = 20;
    const Camera cam = camera(cs);
    const Drawn d = drawAll(s, cam);
    const DetailResult r = auditDetail(s, cam, d.triangles, d.fragments, d.z.buffer.id);
    EXPECT_EQ(r.objectsDrawn, 1u);
    EXPECT_EQ(r.trianglesDrawn, 12u);
    EXPECT_EQ(r.trianglesNoCenter, 8u);
    EXPECT_EQ(r.pixelsVisible, 10000u);
    EXPECT_DOUBLE_EQ(r.trianglesPerVisiblePixel, 12.0 / 10000);
    EXPECT_EQ(r.objectsTooSmall, 0u);
    EXPECT_EQ(r.objectsOverDetailed, 0u);
    EXPECT_TRUE(r.flagged.empty());
    // Orthographic projected size: 2 r (H / 2) sy with sy = 1 / (orthoHeight / 2) = 1.
    EXPECT_DOUBLE_EQ(projectedDiameterPx(cam, s.objects[0].sphere), s.objects[0].sphere.radius * 200);
}

// Perspective, 320 x 200, fov 60: a box at 5 (fine), a 48 x 24 sphere of radius 1 about 204 away
// (its projection is 200 sy / sqrt(204^2 - 1) = 1.7 px: too small), and a 64 x 32 sphere of
// radius 0.5 about 20 away (8.6 px across, about 60 visible pixels for 3,968 triangles:
// over-detailed); none hides another.
TEST(DetailFlags, FarSphereTooSmallDenseSphereOverDetailed) {
    SceneBuildInput in;
    in.materials.push_back(Material{});
    in.objects.push_back({"box", "generated", 0, boxMesh({0, 0, -5}, {0.5, 0.5, 0.5})});
    in.objects.push_back({"far", "generated", 0, uvSphereMesh({40, 0, -200}, 1, 48, 24)});
    in.objects.push_back({"dense", "generated", 0, uvSphereMesh({-3, 0, -20}, 0.5, 64, 32)});
    ChunkSettings chunks;
    chunks.maxTriangles = 100000;  // one culling object per sphere
    const Scene s = buildScene(std::move(in), chunks);
    ASSERT_EQ(s.objects.size(), 3u);
    const uint64_t farTris = s.objects[1].triEnd - s.objects[1].triBegin, denseTris = s.objects[2].triEnd - s.objects[2].triBegin;
    ASSERT_EQ(farTris, 48u * 2 + 48u * 22 * 2);
    ASSERT_EQ(denseTris, 64u * 2 + 64u * 30 * 2);
    CameraSpec cs;
    cs.eye = {0, 0, 0};
    cs.target = {0, 0, -1};
    cs.width = 320;
    cs.height = 200;
    cs.nearZ = 0.5;
    cs.farZ = 500;
    const Camera cam = camera(cs);
    const Drawn d = drawAll(s, cam);
    const DetailResult r = auditDetail(s, cam, d.triangles, d.fragments, d.z.buffer.id);

    // Visible pixels per object, counted independently from the reference visibility.
    const ReferenceVisibility ref = referenceVisibility(s, cam);
    std::vector<uint64_t> px(3, 0);
    for (uint32_t id : ref.id)
        if (id) ++px[s.triangleObject[id - 1]];
    EXPECT_EQ(r.pixelsVisible, px[0] + px[1] + px[2]);
    EXPECT_GT(px[2], 30u);
    EXPECT_LT(px[2], 100u);

    EXPECT_EQ(r.objectsDrawn, 3u);
    EXPECT_EQ(r.objectsTooSmall, 1u);
    EXPECT_EQ(r.objectsOverDetailed, 2u);  // the far sphere is both
    ASSERT_EQ(r.flagged.size(), 2u);
    // Most triangles saved first: the dense sphere's LOD saves denseTris - max(ceil(px / 4), 12).
    EXPECT_EQ(r.flagged[0].name, "dense");
    EXPECT_FALSE(r.flagged[0].tooSmall);
    EXPECT_TRUE(r.flagged[0].overDetailed);
    EXPECT_EQ(r.flagged[0].pixelsVisible, px[2]);
    EXPECT_EQ(r.flagged[0].trianglesSaved, denseTris - std::max<uint64_t>((px[2] + 3) / 4, 12));
    // Against the ideal sphere (the object's bounding sphere is rounded up by a few ulps).
    EXPECT_NEAR(r.flagged[0].projectedPixels, 200 / std::tan(kPi / 6) * 0.5 / std::sqrt(20.0 * 20 + 9 - 0.25), 1e-6);
    // The far sphere: a draw distance saves all of it; almost none of its triangles covers a center
    // (a closed mesh covers each center at most twice, front and back, and it covers a few).
    EXPECT_EQ(r.flagged[1].name, "far");
    EXPECT_TRUE(r.flagged[1].tooSmall);
    EXPECT_EQ(r.flagged[1].trianglesSaved, farTris);
    EXPECT_LT(r.flagged[1].projectedPixels, 4.0);
    EXPECT_GE(r.flagged[1].trianglesNoCenter, farTris - 2 * 8);
    EXPECT_EQ(r.trianglesSavable, r.flagged[0].trianglesSaved + farTris);

    // Listing fewer keeps the best.
    DetailSettings one;
    one.listed = 1;
    const DetailResult r1 = auditDetail(s, cam, d.triangles, d.fragments, d.z.buffer.id, one);
    ASSERT_EQ(r1.flagged.size(), 1u);
    EXPECT_EQ(r1.flagged[0].name, "dense");
    EXPECT_EQ(r1.trianglesSavable, r.trianglesSavable);
}

TEST(DetailExact, NothingDrawn) {
    const Scene s = demoScene();
    CameraSpec cs;
    const Camera cam = camera(cs);
    const DetailResult r = auditDetail(s, cam, {}, std::vector<uint32_t>(s.triangleCount(), 0),
                                       std::vector<uint32_t>(size_t(cam.width) * size_t(cam.height), 0));
    EXPECT_EQ(r.objectsDrawn, 0u);
    EXPECT_EQ(r.trianglesPerVisiblePixel, 0);
    EXPECT_TRUE(r.flagged.empty());
}

}  // namespace
}  // namespace va
