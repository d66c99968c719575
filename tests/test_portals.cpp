// The portal cells stage (analysis/stages/portals.h) and the scene file's "cells" and "portals" keys:
// the three-rooms example with exact visible cells and culled objects for four cameras, a portal
// seen edge-on, nested portals narrowing to nothing, a camera outside every cell, the clipper, the
// object-to-cell assignment, bad input with exact messages, and 0 false culls against the
// reference visibility.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "analysis/audits/audit.h"
#include "analysis/load/demo.h"
#include "analysis/load/load.h"
#include "analysis/stages/portals.h"

namespace va {
namespace {

const std::string kRooms = std::string(VISAUDIT_EXAMPLES) + "/rooms.scene.json";

Scene loadRooms() {
    Scene s;
    std::string err;
    EXPECT_TRUE(loadScene(kRooms, {}, &s, &err)) << err;
    return s;
}

Camera cameraOf(const Scene &s, const std::string &view) {
    for (const ViewSpec &v : s.views)
        if (v.name == view) {
            Camera c;
            std::string err;
            EXPECT_TRUE(makeCamera(v.camera, &c, &err)) << err;
            return c;
        }
    ADD_FAILURE() << "no view " << view;
    return {};
}

std::vector<std::string> names(const Scene &s, const std::vector<uint32_t> &objects) {
    std::vector<std::string> out;
    for (uint32_t o : objects) out.push_back(s.objects[o].name);
    std::sort(out.begin(), out.end());
    return out;
}

std::vector<std::string> visibleCells(const Scene &s, const PortalResult &r) {
    std::vector<std::string> out;
    for (size_t c = 0; c < s.cells.size(); ++c)
        if (r.cellVisible[c]) out.push_back(s.cells[c].name);
    return out;
}

// No object the stage culled shows a single pixel in the reference visibility (no culling at all).
void expectNoFalseCulls(const Scene &s, const Camera &cam, const PortalResult &r, const std::string &what) {
    const ReferenceVisibility ref = referenceVisibility(s, cam);
    std::vector<uint32_t> drawn;
    for (uint32_t o : r.visible)
        for (uint32_t i = s.objects[o].triBegin; i < s.objects[o].triEnd; ++i) drawn.push_back(s.objectTriangles[i]);
    const CullAudit a = auditCulling(s, ref, {{"cells", r.culled, {}}}, drawn, nullptr);
    EXPECT_EQ(a.stages[0].falseCullTriangles, 0u) << what;
    EXPECT_EQ(a.unaccountedPixels, 0u) << what;
}

// ---- The three rooms (examples/rooms.scene.json) ------------------------------------------------

const std::vector<std::string> kRoomC = {"ceilingC", "crateC", "eastC", "floorC", "northC", "southC"};

TEST(PortalRooms, LoadsCellsPortalsAndAssignsObjects) {
    const Scene s = loadRooms();
    ASSERT_EQ(s.cells.size(), 3u);
    ASSERT_EQ(s.portals.size(), 2u);
    EXPECT_EQ(s.cells[1].name, "B");
    EXPECT_EQ(s.portals[1].name, "doorBC");
    EXPECT_EQ(s.portals[1].cells[0], 1u);
    EXPECT_EQ(s.portals[1].cells[1], 2u);
    ASSERT_EQ(s.objects.size(), 23u);
    ASSERT_EQ(s.objectCellsBegin.size(), 24u);
    // Room pieces lie in their room only; the walls with the doors straddle two rooms.
    auto cellsOf = [&](const std::string &name) {
        std::vector<std::string> out;
        for (uint32_t o = 0; o < s.objects.size(); ++o)
            if (s.objects[o].name == name)
                for (uint32_t k = s.objectCellsBegin[o]; k < s.objectCellsBegin[o + 1]; ++k) out.push_back(s.cells[s.objectCells[k]].name);
        return out;
    };
    EXPECT_EQ(cellsOf("floorA"), (std::vector<std::string>{"A"}));
    EXPECT_EQ(cellsOf("crateB"), (std::vector<std::string>{"B"}));
    EXPECT_EQ(cellsOf("eastC"), (std::vector<std::string>{"C"}));
    EXPECT_EQ(cellsOf("wallAB-lintel"), (std::vector<std::string>{"A", "B"}));
    EXPECT_EQ(cellsOf("wallBC-north"), (std::vector<std::string>{"B", "C"}));
}

TEST(PortalRooms, SeesThroughBothDoors) {
    const Scene s = loadRooms();
    const Camera cam = cameraOf(s, "both-doors");
    const PortalResult r = cullPortals(s, cam);
    EXPECT_EQ(visibleCells(s, r), (std::vector<std::string>{"A", "B", "C"}));
    EXPECT_EQ(r.stats.cameraCell, 0);
    EXPECT_EQ(r.stats.cameraCells, 1u);
    EXPECT_EQ(r.stats.portalsTested, 2u);  // doorAB from A, doorBC from B (doorAB back from B is on the path)
    EXPECT_EQ(r.stats.portalsPassed, 2u);
    EXPECT_EQ(r.stats.cellsVisited, 3u);
    EXPECT_EQ(r.stats.objectsCulled, 0u);
    EXPECT_EQ(r.stats.objectsIn, 23u);
    EXPECT_TRUE(r.note.empty());
    expectNoFalseCulls(s, cam, r, "both-doors");
    // The far room really is visible through both doors: the reference shows its east wall.
    const ReferenceVisibility ref = referenceVisibility(s, cam);
    uint64_t eastPixels = 0;
    for (uint32_t id : ref.id)
        if (id && s.objects[s.triangleObject[id - 1]].name == "eastC") ++eastPixels;
    EXPECT_GT(eastPixels, 0u);
}

TEST(PortalRooms, SeesThroughOneDoor) {
    const Scene s = loadRooms();
    const Camera cam = cameraOf(s, "one-door");
    const PortalResult r = cullPortals(s, cam);
    // Through doorAB (z 4..6 at x = 10) from (2, 1.5, 1), the rays reach z >= 1 + 18 * 3/8 = 7.75 at
    // x = 20: doorBC (z 4..6) is clipped away.
    EXPECT_EQ(visibleCells(s, r), (std::vector<std::string>{"A", "B"}));
    EXPECT_EQ(r.stats.portalsTested, 2u);
    EXPECT_EQ(r.stats.portalsPassed, 1u);
    EXPECT_EQ(names(s, r.culled), kRoomC);
    EXPECT_EQ(r.stats.trianglesCulled, 6u * 12);
    expectNoFalseCulls(s, cam, r, "one-door");
}

TEST(PortalRooms, LooksAway) {
    const Scene s = loadRooms();
    const Camera cam = cameraOf(s, "away");
    const PortalResult r = cullPortals(s, cam);
    EXPECT_EQ(visibleCells(s, r), (std::vector<std::string>{"A"}));
    EXPECT_EQ(r.stats.portalsTested, 1u);
    EXPECT_EQ(r.stats.portalsPassed, 0u);
    std::vector<std::string> expected = {"ceilingB", "crateB", "floorB", "northB", "southB",
                                         "wallBC-lintel", "wallBC-north", "wallBC-south"};
    expected.insert(expected.end(), kRoomC.begin(), kRoomC.end());
    std::sort(expected.begin(), expected.end());
    EXPECT_EQ(names(s, r.culled), expected);
    EXPECT_EQ(r.stats.objectsCulled, 14u);
    expectNoFalseCulls(s, cam, r, "away");
}

// Standing in doorAB's plane (x = 10), inside the door: the eye is on the face A and B share, so
// both are the camera's cells, and each is also entered from the other with the whole frustum.
TEST(PortalRooms, CameraInThePortalPlaneSeesBothRooms) {
    const Scene s = loadRooms();
    const Camera cam = cameraOf(s, "doorway");
    const PortalResult r = cullPortals(s, cam);
    EXPECT_EQ(r.stats.cameraCells, 2u);
    EXPECT_EQ(r.stats.cameraCell, 0);
    EXPECT_EQ(visibleCells(s, r), (std::vector<std::string>{"A", "B"}));
    EXPECT_EQ(r.stats.portalsInPortal, 2u);
    EXPECT_EQ(r.stats.portalsTested, 4u);  // doorAB from A and from B; doorBC twice (clipped away)
    EXPECT_EQ(r.stats.portalsPassed, 2u);
    EXPECT_EQ(names(s, r.culled), kRoomC);
    expectNoFalseCulls(s, cam, r, "doorway");
}

TEST(PortalRooms, CandidatesAreTheInput) {
    const Scene s = loadRooms();
    const Camera cam = cameraOf(s, "one-door");
    auto index = [&](const std::string &name) {
        for (uint32_t o = 0; o < s.objects.size(); ++o)
            if (s.objects[o].name == name) return o;
        return uint32_t(-1);
    };
    const std::vector<uint32_t> some = {index("floorA"), index("ceilingA"), index("floorC"), index("ceilingC")};
    const PortalResult r = cullPortals(s, cam, {}, &some);
    EXPECT_EQ(r.stats.objectsIn, 4u);
    EXPECT_EQ(r.stats.objectsCulled, 2u);
    EXPECT_EQ(names(s, r.visible), (std::vector<std::string>{"ceilingA", "floorA"}));
    EXPECT_EQ(names(s, r.culled), (std::vector<std::string>{"ceilingC", "floorC"}));
}

// ---- Hand-made cells ----------------------------------------------------------------------------


// A portal in the plane x = X, over y in [y0, y1] and z in [z0, z1].
Portal xPortal(uint32_t a, uint32_t b, double x, double y0, double y1, double z0, double z1) {
    Portal p;
    p.name = "p" + std::to_string(a) + std::to_string(b);
    p.cells[0] = a;
    p.cells[1] = b;
    p.points = {{x, y0, z0}, {x, y0, z1}, {x, y1, z1}, {x, y1, z0}};
    return p;
}

Camera lookFrom(Vec3 eye, Vec3 target, Vec3 up = {0, 1, 0}) {
    CameraSpec cs;
    cs.eye = eye;
    cs.target = target;
    cs.up = up;
    cs.width = 320;
    cs.height = 180;
    cs.nearZ = 0.05;
    cs.farZ = 500;
    Camera c;
    std::string err;
    EXPECT_TRUE(makeCamera(cs, &c, &err)) << err;
    return c;
}

// Room A = [0,10]^3 and a narrower corridor B = [10,20] x [3,7] x [3,7] behind a window at x = 10
// (y, z in [4, 6]); one box in the corridor. An eye at (10, 8, 5) is on A's face x = 10 but outside
// B: it sees the window exactly edge-on (its plane holds the eye, the polygon does not).
Scene corridorScene() {
    SceneBuildInput in;
    in.materials.push_back(Material{});
    in.objects.push_back({"roomBox", "generated", 0, boxMesh({2, 1, 5}, {0.5, 0.5, 0.5})});
    in.objects.push_back({"corridorBox", "generated", 0, boxMesh({15, 5, 5}, {0.5, 0.5, 0.5})});
    Scene s = buildScene(std::move(in));
    s.cells = {boxCell("A", {0, 0, 0}, {10, 10, 10}), boxCell("B", {10, 3, 3}, {20, 7, 7})};
    s.portals = {xPortal(0, 1, 10, 4, 6, 4, 6)};
    assignObjectsToCells(s);
    return s;
}

TEST(PortalEdgeOn, PortalSeenEdgeOnShowsNothing) {
    const Scene s = corridorScene();
    const Camera cam = lookFrom({10, 8, 5}, {10, 0, 5.001}, {1, 0, 0});
    const PortalResult r = cullPortals(s, cam);
    EXPECT_EQ(r.stats.cameraCells, 1u);
    EXPECT_EQ(r.stats.portalsTested, 1u);
    EXPECT_EQ(r.stats.portalsEdgeOn, 1u);
    EXPECT_EQ(r.stats.portalsPassed, 0u);
    EXPECT_EQ(r.stats.cellsVisible, 1u);
    EXPECT_EQ(names(s, r.culled), (std::vector<std::string>{"corridorBox"}));
    // A hair off the plane, on A's side, the window shows a sliver and the corridor is entered.
    const Camera off = lookFrom({9.999, 8, 5}, {9.999, 0, 5.001}, {1, 0, 0});
    const PortalResult r2 = cullPortals(s, off);
    EXPECT_EQ(r2.stats.portalsEdgeOn, 0u);
    EXPECT_EQ(r2.stats.portalsPassed, 1u);
    EXPECT_EQ(r2.stats.cellsVisible, 2u);
    EXPECT_TRUE(r2.culled.empty());
}

// Six cells in a row along x, each [10i, 10i + 10] x [0, 10] x [0, 20]; portal i at x = 10i over
// y in [4, 6] and z in [a_i, a_i + 2], a = 4, 5.2, 6.4, 10, 10. From (5, 5, 5) looking down +x the
// slopes dz/dx seen through the portals are [-0.2, 0.2], [0.2/15, 2.2/15], [1.4/25, 3.4/25] and
// portal 4's [5/35, 7/35] no longer meets [0.056, 0.136]: the nested frustum has narrowed to
// nothing, although portal 4 is inside the camera's frustum and visible through portals 1 and 2.
Scene chainScene() {
    SceneBuildInput in;
    in.materials.push_back(Material{});
    for (int i = 0; i < 6; ++i)
        in.objects.push_back({"box" + std::to_string(i), "generated", 0, boxMesh({10.0 * i + 5, 5, 15}, {0.5, 0.5, 0.5})});
    Scene s = buildScene(std::move(in));
    for (int i = 0; i < 6; ++i) s.cells.push_back(boxCell("K" + std::to_string(i), {10.0 * i, 0, 0}, {10.0 * i + 10, 10, 20}));
    const double a[5] = {4, 5.2, 6.4, 10, 10};
    for (uint32_t i = 1; i <= 5; ++i) s.portals.push_back(xPortal(i - 1, i, 10.0 * i, 4, 6, a[i - 1], a[i - 1] + 2));
    assignObjectsToCells(s);
    return s;
}

TEST(PortalNested, NarrowingToNothing) {
    const Scene s = chainScene();
    const Camera cam = lookFrom({5, 5, 5}, {100, 5, 5});
    const PortalResult r = cullPortals(s, cam);
    EXPECT_EQ(visibleCells(s, r), (std::vector<std::string>{"K0", "K1", "K2", "K3"}));
    EXPECT_EQ(r.stats.portalsTested, 4u);
    EXPECT_EQ(r.stats.portalsPassed, 3u);
    EXPECT_EQ(r.stats.cellsVisited, 4u);
    EXPECT_EQ(names(s, r.culled), (std::vector<std::string>{"box4", "box5"}));
    EXPECT_EQ(r.stats.objectsNoCell, 0u);

    // The clipper itself: portal 4 survives the camera's frustum and portal 1's, and is clipped
    // away by portal 3's narrowed frustum (checked through a depth limit of 1 below).
    PortalSettings shallow;
    shallow.maxDepth = 1;
    const PortalResult cut = cullPortals(s, cam, shallow);
    EXPECT_EQ(cut.stats.depthLimitHits, 1u);
    EXPECT_EQ(cut.stats.cellsVisible, 6u);  // conservative: the graph beyond the limit is visible
    EXPECT_TRUE(cut.culled.empty());
}

TEST(PortalNested, BudgetExceededKeepsEverythingReachable) {
    const Scene s = chainScene();
    const Camera cam = lookFrom({5, 5, 5}, {100, 5, 5});
    PortalSettings tiny;
    tiny.maxPortalTests = 2;
    const PortalResult r = cullPortals(s, cam, tiny);
    EXPECT_TRUE(r.stats.budgetExceeded);
    EXPECT_EQ(r.stats.portalsTested, 2u);
    EXPECT_EQ(r.stats.cellsVisible, 6u);
    EXPECT_TRUE(r.culled.empty());
    EXPECT_EQ(r.note, "portal budget of 2 tests exceeded: every cell the portal graph reaches from the camera's is visible");
}

TEST(PortalOutside, CameraOutsideEveryCellCullsNothing) {
    const Scene s = chainScene();
    const Camera cam = lookFrom({-5, 5, 5}, {100, 5, 5});
    const PortalResult r = cullPortals(s, cam);
    EXPECT_TRUE(r.stats.cameraOutside);
    EXPECT_EQ(r.stats.cameraCell, -1);
    EXPECT_EQ(r.stats.cameraCells, 0u);
    EXPECT_EQ(r.stats.cellsVisible, 6u);
    EXPECT_EQ(r.stats.objectsCulled, 0u);
    EXPECT_EQ(r.visible.size(), 6u);
    EXPECT_EQ(r.note, "camera outside every cell: the eye (-5, 5, 5) is in none of the 6 cells; nothing culled");
}

TEST(PortalOutside, ObjectInNoCellIsKeptAndCounted) {
    SceneBuildInput in;
    in.materials.push_back(Material{});
    in.objects.push_back({"inside", "generated", 0, boxMesh({5, 5, 5}, {0.5, 0.5, 0.5})});
    in.objects.push_back({"outside", "generated", 0, boxMesh({50, 5, 5}, {0.5, 0.5, 0.5})});
    Scene s = buildScene(std::move(in));
    s.cells = {boxCell("A", {0, 0, 0}, {10, 10, 10}), boxCell("B", {10, 0, 0}, {20, 10, 10})};
    s.portals = {xPortal(0, 1, 10, 4, 6, 4, 6)};
    assignObjectsToCells(s);
    const Camera cam = lookFrom({5, 5, 5}, {5, 5, -10});  // looking away from the portal
    const PortalResult r = cullPortals(s, cam);
    EXPECT_EQ(r.stats.objectsNoCell, 1u);
    EXPECT_EQ(r.visible, (std::vector<uint32_t>{0, 1}));
}

// Plane cells: a wedge-shaped cell given by its planes holds exactly what its planes hold.
TEST(PortalCells, PlaneCellsContainmentAndOverlap) {
    SceneBuildInput in;
    in.materials.push_back(Material{});
    in.objects.push_back({"near", "generated", 0, boxMesh({1, 1, 1}, {0.25, 0.25, 0.25})});
    in.objects.push_back({"beyond", "generated", 0, boxMesh({4, 4, 1}, {0.25, 0.25, 0.25})});
    Scene s = buildScene(std::move(in));
    Cell wedge;  // x >= 0, y >= 0, z in [0, 2], x + y <= 4
    wedge.name = "wedge";
    wedge.faces = {{{1, 0, 0}, 0}, {{0, 1, 0}, 0}, {{0, 0, 1}, 0}, {{0, 0, -1}, 2}, {normalize({-1, -1, 0}), 4 / std::sqrt(2.0)}};
    s.cells = {wedge};
    assignObjectsToCells(s);
    EXPECT_EQ(s.objectCellsBegin, (std::vector<uint32_t>{0, 1, 1}));
    EXPECT_EQ(cellsContaining(s, {1, 1, 1}).size(), 1u);
    EXPECT_EQ(cellsContaining(s, {2, 2, 1}).size(), 1u);  // on the slanted face: closed
    EXPECT_TRUE(cellsContaining(s, {2.01, 2, 1}).empty());
}

TEST(PortalClip, SutherlandHodgmanExact) {
    // A unit square at z = 0 clipped by x >= 0.25 and y <= 0.5: the rectangle [0.25, 1] x [0, 0.5].
    const std::vector<Vec3> sq = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    const std::vector<FrustumPlane> planes = {{{1, 0, 0}, -0.25, 0, {0, 0, 0}}, {{0, -1, 0}, 0.5, 0, {0, 0, 0}}};
    const std::vector<Vec3> c = clipPolygon(sq, planes);
    ASSERT_EQ(c.size(), 4u);
    Aabb b;
    for (const Vec3 &v : c) b.extend(v);
    // Each plane keeps what lies within its rounding bound (about 1e-16 here): the clip can only be
    // larger than the exact one, by no more than that.
    EXPECT_LE(b.lo.x, 0.25);
    EXPECT_GT(b.lo.x, 0.25 - 1e-14);
    EXPECT_EQ(b.hi.x, 1);
    EXPECT_EQ(b.lo.y, 0);
    EXPECT_GE(b.hi.y, 0.5);
    EXPECT_LT(b.hi.y, 0.5 + 1e-14);
    // Entirely outside one plane: nothing; touching it exactly: kept (closed, conservative).
    EXPECT_TRUE(clipPolygon(sq, {{{1, 0, 0}, -2, 0, {0, 0, 0}}}).empty());
    EXPECT_GE(clipPolygon(sq, {{{1, 0, 0}, -1, 0, {0, 0, 0}}}).size(), 3u);
}

// ---- The scene file's "cells" and "portals" keys: exact messages -------------------------------

std::string writeScene(const std::string &name, const std::string &cellsAndPortals) {
    const std::filesystem::path dir = std::filesystem::temp_directory_path() / "visaudit-portals";
    std::filesystem::create_directories(dir);
    std::filesystem::copy_file(std::string(VISAUDIT_EXAMPLES) + "/meshes/crate.ply", dir / "crate.ply",
                               std::filesystem::copy_options::overwrite_existing);
    const std::string path = (dir / name).string();
    std::ofstream(path) << "{ \"format\": \"visaudit-scene/1\",\n"
                           "  \"objects\": [ { \"mesh\": \"crate.ply\" } ],\n"
                        << cellsAndPortals << "\n}\n";
    return path;
}

std::string loadError(const std::string &path) {
    Scene s;
    std::string err;
    EXPECT_FALSE(loadScene(path, {}, &s, &err));
    return err.substr(err.rfind('/') + 1);
}

TEST(PortalSceneFile, BadInputMessages) {
    EXPECT_EQ(loadError(writeScene("a.json", "  \"cells\": [ { \"name\": \"A\", \"min\": [0, 0, 0], \"max\": [1, 0, 1] } ]")),
              "a.json:3:58: cells[0].max[1]: must be greater than min[1] (0.0): a cell has a volume");
    EXPECT_EQ(loadError(writeScene("b.json", "  \"cells\": [ { \"name\": \"A\", \"min\": [0, 0, 0] } ]")),
              "b.json:3:14: cells[0]: missing \"max\": a box cell needs both corners, e.g. \"min\": [0, 0, 0], \"max\": [10, 4, 10]");
    EXPECT_EQ(loadError(writeScene("c.json", "  \"cells\": [ { \"name\": \"hall\", \"min\": [0, 0, 0], \"max\": [1, 1, 1] } ],\n"
                                             "  \"portals\": [ { \"cells\": [\"hall\", \"hal\"], \"points\": [[0,0,0],[1,0,0],[1,1,0]] } ]")),
              "c.json:4:36: portals[0].cells[1]: cell 'hal' is not defined in \"cells\"; did you mean 'hall'?");
    EXPECT_EQ(loadError(writeScene("d.json", "  \"cells\": [ { \"name\": \"A\", \"min\": [0, 0, 0], \"max\": [1, 1, 1] },\n"
                                             "             { \"name\": \"B\", \"min\": [1, 0, 0], \"max\": [2, 1, 1] } ],\n"
                                             "  \"portals\": [ { \"cells\": [\"A\", \"B\"], \"points\": [[1,0,0],[1,1,0],[1,1,1],[1.5,0,1]] } ]")),
              "d.json:5:50: portals[0].points[0]: is 0.117851 off the portal's plane; a portal is flat (points within 1e-06 of its size)");
    EXPECT_EQ(loadError(writeScene("e.json", "  \"cells\": [ { \"name\": \"A\", \"min\": [0, 0, 0], \"max\": [1, 1, 1] },\n"
                                             "             { \"name\": \"B\", \"min\": [1, 0, 0], \"max\": [2, 1, 1] } ],\n"
                                             "  \"portals\": [ { \"cells\": [\"A\", \"B\"], \"points\": [[1,0,0],[1,1,0],[1,0.2,0.2],[1,0,1]] } ]")),
              "e.json:5:66: portals[0].points[2]: bends the polygon inwards; a portal is convex (list its corners in order around it; "
              "split a concave opening into several portals)");
    EXPECT_EQ(loadError(writeScene("f.json", "  \"cells\": [ { \"name\": \"A\", \"min\": [0, 0, 0], \"max\": [1, 1, 1], \"plane\": [] } ]")),
              "f.json:3:65: unknown key 'plane' in cells[0]; did you mean 'planes'? (known keys: name, min, max, planes)");
    EXPECT_EQ(loadError(writeScene("g.json", "  \"portals\": [ ]\n, \"portal\": 1")),
              "g.json:4:3: unknown key 'portal' at the top level; did you mean 'portals'? (known keys: format, up, materials, objects, "
              "lights, views, cells, portals)");
}

}  // namespace
}  // namespace va
