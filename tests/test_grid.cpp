// The grid stage (analysis/stages/grid.h): exact counts on a hand-made lattice of boxes seen by a known
// orthographic frustum, the automatic cell size, and a seeded property test: every object the grid
// culls is entirely outside the frustum (no point of its box inside), over perspective views.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>

#include "analysis/audits/audit.h"
#include "analysis/load/load.h"

#include "analysis/load/demo.h"
#include "analysis/stages/frustum.h"  // worldFrustumPlanes
#include "analysis/stages/grid.h"

namespace va {
namespace {

// 10 x 10 unit boxes, box (i, j) = [2i, 2i + 1] x [0, 1] x [2j, 2j + 1]: scene bounds [0, 19] x
// [0, 1] x [0, 19].
Scene lattice() {
    SceneBuildInput in;
    in.materials.push_back(Material{});
    for (int j = 0; j < 10; ++j)
        for (int i = 0; i < 10; ++i)
            in.objects.push_back({"b" + std::to_string(i) + "_" + std::to_string(j), "generated", 0,
                                  boxMesh({2.0 * i + 0.5, 0.5, 2.0 * j + 0.5}, {0.5, 0.5, 0.5})});
    return buildScene(std::move(in));
}

Camera camera(const CameraSpec &cs) {
    Camera c;
    std::string err;
    EXPECT_TRUE(makeCamera(cs, &c, &err)) << err;
    return c;
}

TEST(GridBuild, ExplicitCellSize) {
    const Scene s = lattice();
    GridSettings gs;
    gs.cellSize = 2;
    const Grid g = buildGrid(s, gs);
    EXPECT_EQ(g.dims[0], 10);  // ceil(19 / 2)
    EXPECT_EQ(g.dims[1], 1);
    EXPECT_EQ(g.dims[2], 10);
    EXPECT_EQ(g.cellObjects.size(), 100u);  // box [2i, 2i + 1] lies in cell [2i, 2i + 2] only
    for (uint64_t c = 0; c < g.cellCount(); ++c) EXPECT_EQ(g.cellBegin[c + 1] - g.cellBegin[c], 1u);
}

TEST(GridBuild, AutomaticCellSize) {
    const Scene s = lattice();
    const Grid g = buildGrid(s);
    // 100 objects / 8 per cell = 12.5 cells over the bounds' volume 19 x 1 x 19:
    // edge = (361 / 12.5)^(1/3) = 3.07, so 7 x 1 x 7 cells.
    EXPECT_DOUBLE_EQ(g.cellSize, std::pow(361.0 / 12.5, 1.0 / 3));
    EXPECT_EQ(g.dims[0], 7);
    EXPECT_EQ(g.dims[1], 1);
    EXPECT_EQ(g.dims[2], 7);
}

// Looking straight down on the lattice, orthographic, 7 x 7 world units around (8, 10): the view
// box is x in [4.5, 11.5], z in [6.5, 13.5], which meets grid columns i = 2..5 and rows j = 3..6.
TEST(GridCull, ExactCountsFromAbove) {
    const Scene s = lattice();
    GridSettings gs;
    gs.cellSize = 2;
    const Grid g = buildGrid(s, gs);
    CameraSpec cs;
    cs.eye = {8, 10, 10};
    cs.target = {8, 0, 10};
    cs.up = {0, 0, -1};
    cs.orthographic = true;
    cs.orthoHeight = 7;
    cs.width = 100;
    cs.height = 100;
    cs.nearZ = 1;
    cs.farZ = 100;
    const GridResult r = cullGrid(s, g, camera(cs));
    EXPECT_EQ(r.stats.cellsTotal, 100u);
    // The frustum's box padded by one grid cell per side: columns 1..6 and rows 2..7 (36 cells).
    EXPECT_EQ(r.stats.cellsSkipped, 64u);
    EXPECT_EQ(r.stats.cellsTested, 36u);
    EXPECT_EQ(r.stats.cellsEmpty, 0u);
    EXPECT_EQ(r.stats.cellsVisible, 16u);
    EXPECT_EQ(r.stats.objectsIn, 100u);
    EXPECT_EQ(r.stats.objectsCulled, 84u);
    EXPECT_EQ(r.stats.trianglesCulled, 84u * 12);
    ASSERT_EQ(r.visible.size(), 16u);
    for (uint32_t o : r.visible) {
        const int i = int(o % 10), j = int(o / 10);
        EXPECT_TRUE(i >= 2 && i <= 5 && j >= 3 && j <= 6) << s.objects[o].name;
    }
    // Candidates: only those enter, and are counted.
    const std::vector<uint32_t> some = {0, 34, 99};
    const GridResult rc = cullGrid(s, g, camera(cs), &some);
    EXPECT_EQ(rc.stats.objectsIn, 3u);
    EXPECT_EQ(rc.visible, (std::vector<uint32_t>{34}));
    EXPECT_EQ(rc.culled, (std::vector<uint32_t>{0, 99}));
}

// An object spanning several cells stays while any of them is visible.
TEST(GridCull, ObjectInSeveralCells) {
    SceneBuildInput in;
    in.materials.push_back(Material{});
    in.objects.push_back({"long", "generated", 0, boxMesh({10, 0.5, 0.5}, {10, 0.5, 0.5})});  // x in [0, 20]
    in.objects.push_back({"far", "generated", 0, boxMesh({19.5, 0.5, 10.5}, {0.5, 0.5, 0.5})});
    const Scene s = buildScene(std::move(in));
    GridSettings gs;
    gs.cellSize = 2;
    const Grid g = buildGrid(s, gs);
    EXPECT_EQ(g.objectCellCount[0], 10u * 1 * 1);
    CameraSpec cs;  // sees only x in [17, 21], z in [-1, 3]: the long box's last cells
    cs.eye = {19, 10, 1};
    cs.target = {19, 0, 1};
    cs.up = {0, 0, -1};
    cs.orthographic = true;
    cs.orthoHeight = 4;
    cs.width = cs.height = 64;
    cs.nearZ = 1;
    cs.farZ = 100;
    const GridResult r = cullGrid(s, g, camera(cs));
    EXPECT_EQ(r.visible, (std::vector<uint32_t>{0}));
    EXPECT_EQ(r.culled, (std::vector<uint32_t>{1}));
}

// Seeded: random perspective cameras over a random scatter of boxes; whatever the grid culls has
// no sampled point (corners, edge and face midpoints, center) inside the frustum.
TEST(GridCull, CulledObjectsAreOutsideTheFrustum) {
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> U(-50, 50);
    SceneBuildInput in;
    in.materials.push_back(Material{});
    for (int k = 0; k < 400; ++k)
        in.objects.push_back({"o" + std::to_string(k), "generated", 0,
                              boxMesh({U(rng), U(rng) * 0.2, U(rng)}, {1 + std::fabs(U(rng)) * 0.04, 1, 1 + std::fabs(U(rng)) * 0.04})});
    const Scene s = buildScene(std::move(in));
    const Grid g = buildGrid(s);
    uint64_t culledTotal = 0;
    for (int v = 0; v < 40; ++v) {
        CameraSpec cs;
        cs.eye = {U(rng), U(rng) * 0.2, U(rng)};
        cs.target = {U(rng), 0, U(rng)};
        cs.width = 320;
        cs.height = 200;
        cs.nearZ = 0.1;
        cs.farZ = 10 + std::fabs(U(rng)) * 2;
        const Camera cam = camera(cs);
        const FrustumPlanes fp = worldFrustumPlanes(cam);
        const GridResult r = cullGrid(s, g, cam);
        culledTotal += r.culled.size();
        for (uint32_t o : r.culled) {
            const Aabb &b = s.objects[o].bounds;
            for (int i = 0; i < 27; ++i) {
                const Vec3 p{b.lo.x + (b.hi.x - b.lo.x) * (i % 3) / 2, b.lo.y + (b.hi.y - b.lo.y) * ((i / 3) % 3) / 2,
                             b.lo.z + (b.hi.z - b.lo.z) * (i / 9) / 2};
                bool inside = true;
                for (int pl = 0; pl < 6; ++pl) inside = inside && dot(fp.n[pl], p) + fp.k[pl] >= 0;
                EXPECT_FALSE(inside) << "view " << v << " object " << s.objects[o].name;
            }
        }
        EXPECT_EQ(r.stats.cellsSkipped + r.stats.cellsEmpty + r.stats.cellsTested, r.stats.cellsTotal);
    }
    EXPECT_GT(culledTotal, 1000u);  // the test culls something worth checking
}

// The castle dungeon from orbit views and from its center: no false culls against the reference.
TEST(GridScenes, CastleDungeonNoFalseCulls) {
    const std::string path = std::string(VISAUDIT_TEST_DATA) + "/castle/level/level-dungeon.gltf";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "not fetched: " << path << " (scripts/fetch-data.sh)";
    Scene s;
    std::string err;
    ASSERT_TRUE(loadScene(path, {}, &s, &err)) << err;
    const Grid g = buildGrid(s);
    std::vector<ViewSpec> views = orbitViews(s, 4);
    for (int k = 0; k < 4; ++k) {
        ViewSpec v;
        v.camera.eye = s.bounds.center();
        v.camera.target = s.bounds.center() + Vec3{std::cos(k * kPi / 2), 0, std::sin(k * kPi / 2)};
        v.camera.nearZ = 0.01;
        v.camera.farZ = 1000;
        views.push_back(v);
    }
    uint64_t culled = 0, in = 0, tested = 0, skipped = 0;
    for (ViewSpec &v : views) {
        v.camera.width = 320;
        v.camera.height = 180;
        const Camera cam = camera(v.camera);
        const GridResult r = cullGrid(s, g, cam);
        const ReferenceVisibility ref = referenceVisibility(s, cam);
        std::vector<uint32_t> drawn;
        for (uint32_t o : r.visible)
            for (uint32_t i = s.objects[o].triBegin; i < s.objects[o].triEnd; ++i) drawn.push_back(s.objectTriangles[i]);
        const CullAudit a = auditCulling(s, ref, {{"grid", r.culled, {}}}, drawn, nullptr);
        EXPECT_EQ(a.stages[0].falseCullTriangles, 0u) << v.name;
        culled += r.stats.objectsCulled;
        in += r.stats.objectsIn;
        tested += r.stats.cellsTested;
        skipped += r.stats.cellsSkipped;
    }
    std::printf("[ grid ] dungeon: %d x %d x %d cells of %.3g, %zu views: objects culled %llu of %llu, cells tested %llu, skipped %llu\n",
                g.dims[0], g.dims[1], g.dims[2], g.cellSize, views.size(), (unsigned long long)culled, (unsigned long long)in,
                (unsigned long long)tested, (unsigned long long)skipped);
    EXPECT_GT(culled, 0u);
}

TEST(GridSkip, Reasons) {
    Scene s = lattice();
    EXPECT_EQ(gridSkipReason(s), nullptr);
    s.cells.push_back(Cell{});
    EXPECT_STREQ(gridSkipReason(s), "scene has cells and portals (the cells stage is its coarse stage)");
    Scene empty;
    EXPECT_STREQ(gridSkipReason(empty), "scene has no objects");
    const Grid g = buildGrid(empty);
    EXPECT_EQ(g.cellCount(), 0u);
}

}  // namespace
}  // namespace va
