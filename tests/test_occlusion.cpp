// The occlusion stage (analysis/stages/occlusion.h): the max-depth pyramid, a big wall that hides exactly
// the boxes behind it and none beside or peeking past it, and 0 false culls against the reference
// visibility on the demo, the example hall, the three rooms and the castle dungeon (orbit and
// inside views).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>

#include "analysis/audits/audit.h"
#include "analysis/load/demo.h"
#include "analysis/stages/frustum.h"
#include "analysis/load/load.h"
#include "analysis/stages/occlusion.h"

namespace va {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(OcclusionHiZ, PyramidIsTheMaximumOfItsFootprint) {
    // 5 x 3 pixels; +inf = no occluder.
    const std::vector<double> d = {1, 2, 3, 4, 5,  //
                                   6, 7, 8, 9, 1,  //
                                   2, 3, kInf, 1, 1};
    const HiZ h = buildHiZ(d, 5, 3);
    ASSERT_EQ(h.levels(), 4u);  // 5x3, 3x2, 2x1, 1x1
    EXPECT_EQ(h.width[1], 3);
    EXPECT_EQ(h.height[1], 2);
    EXPECT_EQ(h.depth[1], (std::vector<double>{7, 9, 5, 3, kInf, 1}));
    EXPECT_EQ(h.depth[2], (std::vector<double>{kInf, 5}));
    EXPECT_EQ(h.depth[3], (std::vector<double>{kInf}));
    uint64_t reads = 0;
    EXPECT_EQ(hizMaxDepth(h, 0, 0, 1, 1, &reads), 7);  // 2 x 2 pixels: read at level 0
    EXPECT_EQ(reads, 4u);
    EXPECT_EQ(hizMaxDepth(h, 3, 0, 4, 2, &reads), 9);
    EXPECT_EQ(hizMaxDepth(h, 0, 0, 4, 2, &reads), kInf);  // one uncovered pixel: never hidden
}

Camera camera(const CameraSpec &cs) {
    Camera c;
    std::string err;
    EXPECT_TRUE(makeCamera(cs, &c, &err)) << err;
    return c;
}

std::vector<uint32_t> allObjects(const Scene &s) {
    std::vector<uint32_t> v(s.objects.size());
    for (uint32_t o = 0; o < v.size(); ++o) v[o] = o;
    return v;
}

// False culls of the occlusion stage run after the frustum stage, against the reference.
struct Audited {
    uint64_t falseCulls = 0, culled = 0, trianglesCulled = 0, objectsIn = 0, occluders = 0, referenceVisibleObjects = 0;
};
Audited auditOcclusion(const Scene &s, const ObjectBvh &bvh, const Camera &cam, const OcclusionSettings &os = {}) {
    const FrustumResult f = cullFrustum(s, bvh, cam);
    const OcclusionResult oc = cullOcclusion(s, cam, f.visible, os);
    std::vector<uint8_t> kept(s.objects.size(), 0);
    for (uint32_t o : f.visible) kept[o] = 1;
    std::vector<uint32_t> frustumCulled;
    for (uint32_t o = 0; o < s.objects.size(); ++o)
        if (!kept[o]) frustumCulled.push_back(o);
    std::vector<uint32_t> drawn;
    for (uint32_t o : oc.visible)
        for (uint32_t i = s.objects[o].triBegin; i < s.objects[o].triEnd; ++i) drawn.push_back(s.objectTriangles[i]);
    const ReferenceVisibility ref = referenceVisibility(s, cam);
    const CullAudit a = auditCulling(s, ref, {{"frustum", frustumCulled, {}}, {"occlusion", oc.culled, {}}}, drawn, nullptr);
    EXPECT_EQ(a.stages[0].falseCullTriangles, 0u);
    Audited r;
    r.falseCulls = a.stages[1].falseCullTriangles;
    r.culled = oc.stats.objectsCulled;
    r.trianglesCulled = oc.stats.trianglesCulled;
    r.objectsIn = oc.stats.objectsIn;
    r.occluders = oc.stats.occludersUsed;
    r.referenceVisibleObjects = ref.visibleObjects;
    EXPECT_EQ(oc.visible.size() + oc.culled.size(), f.visible.size());
    return r;
}

// A wall 10 wide and 4 high at z = 0 (0.2 thick); unit boxes on the floor 5 behind it at x = -3, 0,
// 3 (hidden: their projections fall inside the wall's), one at x = 7.5 peeking past its edge (its
// near face projects to x in [4.78, 5.46] on the wall's plane, past the wall's 5) and two beside
// it at x = +-11; the eye at (0, 2, 10).
TEST(OcclusionWall, HidesExactlyTheBoxesBehindIt) {
    SceneBuildInput in;
    in.materials.push_back(Material{});
    in.objects.push_back({"wall", "generated", 0, boxMesh({0, 2, 0}, {5, 2, 0.1})});
    for (double x : {-3.0, 0.0, 3.0}) in.objects.push_back({"hidden" + std::to_string(int(x)), "generated", 0, boxMesh({x, 0.5, -5}, {0.5, 0.5, 0.5})});
    in.objects.push_back({"peek", "generated", 0, boxMesh({7.5, 0.5, -5}, {0.5, 0.5, 0.5})});
    in.objects.push_back({"left", "generated", 0, boxMesh({-11, 0.5, -5}, {0.5, 0.5, 0.5})});
    in.objects.push_back({"right", "generated", 0, boxMesh({11, 0.5, -5}, {0.5, 0.5, 0.5})});
    const Scene s = buildScene(std::move(in));
    CameraSpec cs;
    cs.eye = {0, 2, 10};
    cs.target = {0, 2, 0};
    cs.width = 640;
    cs.height = 360;
    cs.nearZ = 0.1;
    cs.farZ = 100;
    const Camera cam = camera(cs);
    OcclusionSettings os;
    os.maxOccluders = 1;
    const OcclusionResult r = cullOcclusion(s, cam, allObjects(s), os);
    EXPECT_EQ(r.occluders, (std::vector<uint32_t>{0}));  // the wall ranks first (radius / distance)
    EXPECT_EQ(r.stats.occluderTriangles, 12u);
    EXPECT_EQ(r.culled, (std::vector<uint32_t>{1, 2, 3}));
    EXPECT_EQ(r.visible, (std::vector<uint32_t>{0, 4, 5, 6}));
    EXPECT_EQ(r.stats.objectsTested, 6u);
    EXPECT_EQ(r.stats.objectsHidden, 3u);
    EXPECT_EQ(r.stats.objectsNoPixel, 0u);
    EXPECT_EQ(r.stats.trianglesCulled, 36u);
    EXPECT_EQ(r.stats.hizLevels, 11u);  // 640x360 .. 1x1
    // The peeking box is really visible, the hidden ones really are not.
    const ReferenceVisibility ref = referenceVisibility(s, cam);
    std::vector<uint64_t> px(s.objects.size(), 0);
    for (uint32_t id : ref.id)
        if (id) ++px[s.triangleObject[id - 1]];
    EXPECT_GT(px[4], 0u);
    EXPECT_EQ(px[1] + px[2] + px[3], 0u);
    const ObjectBvh bvh = buildObjectBvh(s);
    EXPECT_EQ(auditOcclusion(s, bvh, cam, os).falseCulls, 0u);

    // With no occluder nothing is hidden; a box reaching the near plane is never tested.
    os.maxOccluders = 0;
    EXPECT_TRUE(cullOcclusion(s, cam, allObjects(s), os).culled.empty());
}

// The wall's back face is single-sided: seen from behind it hides nothing, as in the reference.
TEST(OcclusionWall, SingleSidedBackFacesHideNothing) {
    SceneBuildInput in;
    in.materials.push_back(Material{});
    RawMesh quad = gridMesh({-5, 0, 0}, {10, 0, 0}, {0, 4, 0}, 1, 1);  // front towards +z
    in.objects.push_back({"quad", "generated", 0, quad});
    in.objects.push_back({"box", "generated", 0, boxMesh({0, 1, 5}, {0.5, 0.5, 0.5})});
    const Scene s = buildScene(std::move(in));
    CameraSpec cs;
    cs.eye = {0, 2, -10};  // behind the quad
    cs.target = {0, 2, 0};
    cs.width = 320;
    cs.height = 180;
    const Camera cam = camera(cs);
    OcclusionSettings os;
    os.maxOccluders = 1;
    const OcclusionResult r = cullOcclusion(s, cam, allObjects(s), os);
    EXPECT_EQ(r.occluders, (std::vector<uint32_t>{0}));
    EXPECT_EQ(r.stats.prepassFragments, 0u);
    EXPECT_TRUE(r.culled.empty());
    // Double-sided, the same quad hides the box.
    SceneBuildInput in2;
    Material banner;
    banner.name = "banner";
    banner.doubleSided = true;
    in2.materials = {Material{}, banner};
    in2.objects.push_back({"quad", "generated", 1, quad});
    in2.objects.push_back({"box", "generated", 0, boxMesh({0, 1, 5}, {0.5, 0.5, 0.5})});
    const Scene s2 = buildScene(std::move(in2));
    const OcclusionResult r2 = cullOcclusion(s2, cam, allObjects(s2), os);
    EXPECT_GT(r2.stats.prepassFragments, 0u);
    EXPECT_EQ(r2.culled, (std::vector<uint32_t>{1}));
}

// Views of a scene for the false-cull runs: its own (reduced to 320 x 180), 4 orbit views and 4
// inside views from the bounds' center, looking along the horizontal axes.
std::vector<ViewSpec> testViews(const Scene &s) {
    std::vector<ViewSpec> v = s.views;
    for (const ViewSpec &o : orbitViews(s, 4)) v.push_back(o);
    const Vec3 c = s.bounds.center();
    const Vec3 up = s.up == 'z' ? Vec3{0, 0, 1} : Vec3{0, 1, 0};
    const Vec3 dirs[4] = {{1, 0, 0}, {-1, 0, 0}, s.up == 'z' ? Vec3{0, 1, 0} : Vec3{0, 0, 1}, s.up == 'z' ? Vec3{0, -1, 0} : Vec3{0, 0, -1}};
    const double r = 0.5 * length(s.bounds.extent());
    for (int k = 0; k < 4; ++k) {
        ViewSpec in;
        in.name = "inside" + std::to_string(k);
        in.camera.eye = c;
        in.camera.target = c + dirs[k];
        in.camera.up = up;
        in.camera.nearZ = r * 1e-3;
        in.camera.farZ = r * 4;
        v.push_back(in);
    }
    for (ViewSpec &x : v) {
        x.camera.width = 320;
        x.camera.height = 180;
    }
    return v;
}

void expectNoFalseCulls(const Scene &s, const std::string &what) {
    const ObjectBvh bvh = buildObjectBvh(s);
    Audited total;
    for (const ViewSpec &v : testViews(s)) {
        const Audited a = auditOcclusion(s, bvh, camera(v.camera));
        EXPECT_EQ(a.falseCulls, 0u) << what << " " << v.name;
        total.culled += a.culled;
        total.trianglesCulled += a.trianglesCulled;
        total.objectsIn += a.objectsIn;
        total.occluders += a.occluders;
    }
    std::printf("[ occlusion ] %s: %zu views, objects culled %llu of %llu entering, triangles culled %llu, false culls 0\n",
                what.c_str(), testViews(s).size(), (unsigned long long)total.culled, (unsigned long long)total.objectsIn,
                (unsigned long long)total.trianglesCulled);
}

TEST(OcclusionScenes, DemoNoFalseCulls) { expectNoFalseCulls(demoScene(), "demo"); }

TEST(OcclusionScenes, HallNoFalseCulls) {
    Scene s;
    std::string err;
    ASSERT_TRUE(loadScene(std::string(VISAUDIT_EXAMPLES) + "/hall.scene.json", {}, &s, &err)) << err;
    expectNoFalseCulls(s, "hall");
}

TEST(OcclusionScenes, RoomsNoFalseCulls) {
    Scene s;
    std::string err;
    ASSERT_TRUE(loadScene(std::string(VISAUDIT_EXAMPLES) + "/rooms.scene.json", {}, &s, &err)) << err;
    expectNoFalseCulls(s, "rooms");
    // From the 'away' view (room A, looking at its west wall), the west wall hides nothing behind
    // it, but from 'one-door' the divider hides room C's crate: the stage culls something real.
    const ObjectBvh bvh = buildObjectBvh(s);
    uint64_t culled = 0;
    for (const ViewSpec &v : s.views) culled += auditOcclusion(s, bvh, camera(v.camera)).culled;
    EXPECT_GT(culled, 0u);
}

TEST(OcclusionScenes, CastleDungeonNoFalseCulls) {
    const std::string path = std::string(VISAUDIT_TEST_DATA) + "/castle/level/level-dungeon.gltf";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "not fetched: " << path << " (scripts/fetch-data.sh)";
    Scene s;
    std::string err;
    ASSERT_TRUE(loadScene(path, {}, &s, &err)) << err;
    expectNoFalseCulls(s, "dungeon");
}

// A Quake 3 map from its spawn points: walls everywhere, the case occlusion culling is for.
TEST(OcclusionScenes, Q3dm6ishSpawnsNoFalseCulls) {
    const std::string pk3 = std::string(VISAUDIT_TEST_DATA) + "/openarena/pak1-maps.pk3";
    if (!std::filesystem::exists(pk3)) GTEST_SKIP() << "not fetched: " << pk3 << " (scripts/fetch-data.sh)";
    Scene s;
    std::string err;
    ASSERT_TRUE(loadScene(pk3 + ":maps/q3dm6ish.bsp", {}, &s, &err)) << err;
    const ObjectBvh bvh = buildObjectBvh(s);
    Audited total;
    for (ViewSpec v : s.views) {
        v.camera.width = 480;
        v.camera.height = 270;
        const Audited a = auditOcclusion(s, bvh, camera(v.camera));
        EXPECT_EQ(a.falseCulls, 0u) << v.name;
        total.culled += a.culled;
        total.objectsIn += a.objectsIn;
        total.trianglesCulled += a.trianglesCulled;
    }
    std::printf("[ occlusion ] q3dm6ish: %zu spawn views, objects culled %llu of %llu entering, triangles culled %llu, false culls 0\n",
                s.views.size(), (unsigned long long)total.culled, (unsigned long long)total.objectsIn,
                (unsigned long long)total.trianglesCulled);
    EXPECT_GT(total.culled, 0u);
}

}  // namespace
}  // namespace va
