// Quake 3 maps: the IBSP v46 loader (a tiny map written by the test itself, with exact counts),
// hostile and truncated files refused with exact messages, pk3 archives, the PVS cells stage, level
// views, and the OpenArena maps scripts/fetch-data.sh fetches (exact counts, a PVS row decoded by
// hand, winding checked against the map's own normals).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <algorithm>
#include <array>
#include <map>
#include <set>
#include <unistd.h>

#include "analysis/audits/audit.h"
#include "analysis/stages/backface.h"
#include "analysis/stages/cells.h"
#include "analysis/load/level_views.h"
#include "analysis/load/load.h"
#include "analysis/load/load_bsp.h"
#include "analysis/pipeline.h"
#include "analysis/audits/pvs_evidence.h"
#include "analysis/load/zip.h"

using namespace va;
namespace fs = std::filesystem;

namespace {

// ---- A writer for minimal IBSP v46 files -----------------------------------------------------------

enum { LEntities, LShaders, LPlanes, LNodes, LLeafs, LLeafFaces, LLeafBrushes, LModels, LBrushes,
       LBrushSides, LVertexes, LMeshVerts, LEffects, LFaces, LLightmaps, LLightVols, LVisData };

struct BspWriter {
    std::vector<uint8_t> lump[17];
    void i32(int l, int32_t v) {
        uint32_t u = uint32_t(v);
        for (int k = 0; k < 4; ++k) lump[l].push_back(uint8_t(u >> (8 * k)));
    }
    void f32(int l, float f) {
        int32_t v;
        std::memcpy(&v, &f, 4);
        i32(l, v);
    }
    void bytes(int l, const std::string &s, size_t n) {  // n = npos: all of s
        if (n == std::string::npos) n = s.size();
        for (size_t k = 0; k < n; ++k) lump[l].push_back(k < s.size() ? uint8_t(s[k]) : 0);
    }
    void shader(const std::string &name, int32_t flags, int32_t contents) {
        bytes(LShaders, name, 64);
        i32(LShaders, flags);
        i32(LShaders, contents);
    }
    void plane(Vec3 n, float d) {
        f32(LPlanes, float(n.x)), f32(LPlanes, float(n.y)), f32(LPlanes, float(n.z)), f32(LPlanes, d);
    }
    void node(int32_t plane, int32_t front, int32_t back) {
        i32(LNodes, plane), i32(LNodes, front), i32(LNodes, back);
        for (int k = 0; k < 6; ++k) i32(LNodes, 0);
    }
    void leaf(int32_t cluster, Vec3 lo, Vec3 hi, int32_t firstFace, int32_t nFaces) {
        i32(LLeafs, cluster), i32(LLeafs, 0);
        i32(LLeafs, int32_t(lo.x)), i32(LLeafs, int32_t(lo.y)), i32(LLeafs, int32_t(lo.z));
        i32(LLeafs, int32_t(hi.x)), i32(LLeafs, int32_t(hi.y)), i32(LLeafs, int32_t(hi.z));
        i32(LLeafs, firstFace), i32(LLeafs, nFaces), i32(LLeafs, 0), i32(LLeafs, 0);
    }
    void model(Vec3 lo, Vec3 hi, int32_t face, int32_t nFaces) {
        for (Vec3 v : {lo, hi}) f32(LModels, float(v.x)), f32(LModels, float(v.y)), f32(LModels, float(v.z));
        i32(LModels, face), i32(LModels, nFaces), i32(LModels, 0), i32(LModels, 0);
    }
    int32_t vertex(Vec3 p, Vec3 n = {0, 0, 1}) {
        const int32_t index = int32_t(lump[LVertexes].size() / 44);
        f32(LVertexes, float(p.x)), f32(LVertexes, float(p.y)), f32(LVertexes, float(p.z));
        for (int k = 0; k < 4; ++k) f32(LVertexes, 0);
        f32(LVertexes, float(n.x)), f32(LVertexes, float(n.y)), f32(LVertexes, float(n.z));
        i32(LVertexes, -1);
        return index;
    }
    int32_t meshverts(std::initializer_list<int32_t> l) {
        const int32_t first = int32_t(lump[LMeshVerts].size() / 4);
        for (int32_t v : l) i32(LMeshVerts, v);
        return first;
    }
    void face(int32_t shader, int32_t type, int32_t vertex, int32_t nVertexes, int32_t meshvert, int32_t nMeshverts,
              int32_t w = 0, int32_t h = 0) {
        i32(LFaces, shader), i32(LFaces, -1), i32(LFaces, type), i32(LFaces, vertex), i32(LFaces, nVertexes);
        i32(LFaces, meshvert), i32(LFaces, nMeshverts);
        for (int k = 0; k < 5; ++k) i32(LFaces, 0);     // lightmap index, start, size
        for (int k = 0; k < 12; ++k) f32(LFaces, 0);    // lightmap origin, vectors, normal
        i32(LFaces, w), i32(LFaces, h);
    }
    // Header + lumps in lump order; the last lump ends the file (no padding after it).
    std::vector<uint8_t> file() const {
        std::vector<uint8_t> out(8 + 8 * 17, 0);
        std::memcpy(out.data(), "IBSP", 4);
        out[4] = 46;
        for (int l = 0; l < 17; ++l) {
            while (out.size() % 4) out.push_back(0);
            const uint32_t off = uint32_t(out.size()), len = uint32_t(lump[l].size());
            for (int k = 0; k < 4; ++k) out[8 + 8 * l + k] = uint8_t(off >> (8 * k)), out[12 + 8 * l + k] = uint8_t(len >> (8 * k));
            out.insert(out.end(), lump[l].begin(), lump[l].end());
        }
        return out;
    }
};

void put32(std::vector<uint8_t> &f, size_t at, int32_t v) {
    for (int k = 0; k < 4; ++k) f[at + k] = uint8_t(uint32_t(v) >> (8 * k));
}
int32_t get32(const std::vector<uint8_t> &f, size_t at) {
    return int32_t(uint32_t(f[at]) | uint32_t(f[at + 1]) << 8 | uint32_t(f[at + 2]) << 16 | uint32_t(f[at + 3]) << 24);
}
size_t lumpOffset(const std::vector<uint8_t> &f, int l) { return size_t(get32(f, 8 + 8 * l)); }

// The tiny map (docs/quake3.md has the same picture):
//   plane 0: x = 0; plane 1: x = 100. Node 0 splits at x = 0: front (x >= 0) node 1, back leaf 1.
//   Node 1 splits at x = 100: front leaf 2 (cluster -1: the void), back leaf 0.
//   leaf 0: cluster 0, x in [0, 100]; leaf 1: cluster 1, x in [-100, 0]; leaf 2: the void.
//   PVS: cluster 0 sees only 0, cluster 1 sees only 1.
// Faces (shader 0 solid, 1 sky, 2 water):
//   0 polygon quad on z = 0, x 10..90 (leaf 0)           2 triangles
//   1 mesh triangle on z = 0, x -90..-10 (leaf 1)         1 triangle
//   2 patch 3x3, flat at z = 8, x 20..80 (leaf 0)         2 L^2 triangles
//   3 sky triangle (leaf 1)                               excluded
//   4 billboard (leaf 0)                                  skipped
//   5 water triangle (leaf 0)                             excluded (non-solid)
//   6 triangle listed by leaf 0 and leaf 1                owned by leaf 0, clusters {0, 1}
//   7 triangle no leaf lists (world)                      object "unleafed", no cluster
//   8 quad of brush model 1 (a func_door in leaf 0's space) object "model1", cluster 0 (its box)
// Every face is stored clockwise seen from its front (+z), as Quake 3 stores them.
BspWriter tinyWriter() {
    BspWriter w;
    w.bytes(LEntities,
            "{\n\"classname\" \"worldspawn\"\n}\n"
            "{\n\"classname\" \"info_player_deathmatch\"\n\"origin\" \"50 0 24\"\n\"angle\" \"90\"\n}\n"
            "{\n\"classname\" \"info_player_start\"\n\"origin\" \"-50 0 24\"\n\"angles\" \"10 180 0\"\n}\n"
            "// a comment\n"
            "{\n\"classname\" \"info_player_intermission\"\n\"origin\" \"0 0 200\"\n\"target\" \"t1\"\n}\n"
            "{\n\"classname\" \"target_position\"\n\"targetname\" \"t1\"\n\"origin\" \"50 0 0\"\n}\n"
            "{\n\"classname\" \"func_door\"\n\"model\" \"*1\"\n}\n",
            std::string::npos);
    w.lump[LEntities].push_back(0);
    w.shader("textures/base/floor", 0, 1);
    w.shader("textures/skies/sky", 0x4, 0);
    w.shader("textures/liquids/water", 0, 0x20 | 0x20000000);
    w.plane({1, 0, 0}, 0);
    w.plane({1, 0, 0}, 100);
    w.node(0, 1, -2);
    w.node(1, -3, -1);
    // leaffaces: leaf 0 -> 0, 2, 4, 5, 6; leaf 1 -> 1, 3, 6
    for (int32_t f : {0, 2, 4, 5, 6, 1, 3, 6}) w.i32(LLeafFaces, f);
    w.leaf(0, {0, -64, -16}, {100, 64, 128}, 0, 5);
    w.leaf(1, {-100, -64, -16}, {0, 64, 128}, 5, 3);
    w.leaf(-1, {100, -64, -16}, {200, 64, 128}, 8, 0);

    // Face 0: quad, clockwise seen from +z: (10,40) (90,40) (90,-40) (10,-40).
    int32_t v = w.vertex({10, 40, 0});
    w.vertex({90, 40, 0}), w.vertex({90, -40, 0}), w.vertex({10, -40, 0});
    w.face(0, 1, v, 4, w.meshverts({0, 1, 2, 0, 2, 3}), 6);
    // Face 1: mesh triangle, clockwise from +z.
    v = w.vertex({-90, 40, 0});
    w.vertex({-10, 40, 0}), w.vertex({-10, -40, 0});
    w.face(0, 3, v, 3, w.meshverts({0, 1, 2}), 3);
    // Face 2: patch; control point (row i, column j) at (20 + 30 j, -30 + 30 i, 8). Quake 3's grid
    // triangle (i,j) (i+1,j) (i,j+1) is then clockwise from +z: its front is +z.
    v = -1;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            const int32_t k = w.vertex({20.0 + 30 * j, -30.0 + 30 * i, 8});
            if (v < 0) v = k;
        }
    w.face(0, 2, v, 9, 0, 0, 3, 3);
    // Face 3: sky triangle.
    v = w.vertex({-90, 40, 120});
    w.vertex({-10, 40, 120}), w.vertex({-10, -40, 120});
    w.face(1, 1, v, 3, w.meshverts({0, 1, 2}), 3);
    // Face 4: billboard (a point).
    v = w.vertex({50, 0, 64});
    w.face(0, 4, v, 1, 0, 0);
    // Face 5: water triangle.
    v = w.vertex({10, 40, -8});
    w.vertex({90, 40, -8}), w.vertex({90, -40, -8});
    w.face(2, 1, v, 3, w.meshverts({0, 1, 2}), 3);
    // Face 6: a triangle across x = 0 (both leafs list it).
    v = w.vertex({-20, 50, 4});
    w.vertex({20, 50, 4}), w.vertex({20, 30, 4});
    w.face(0, 1, v, 3, w.meshverts({0, 1, 2}), 3);
    // Face 7: a world triangle no leaf lists.
    v = w.vertex({40, 60, 2});
    w.vertex({60, 60, 2}), w.vertex({60, 50, 2});
    w.face(0, 1, v, 3, w.meshverts({0, 1, 2}), 3);
    // Face 8: the door (model 1), a quad at x 20..30.
    v = w.vertex({20, 10, 30});
    w.vertex({30, 10, 30}), w.vertex({30, -10, 30}), w.vertex({20, -10, 30});
    w.face(0, 1, v, 4, w.meshverts({0, 1, 2, 0, 2, 3}), 6);

    w.model({-100, -64, -16}, {200, 64, 128}, 0, 8);
    w.model({20, -10, 30}, {30, 10, 30}, 8, 1);
    // PVS: 2 clusters, 1 byte per row: cluster 0 sees {0}, cluster 1 sees {1}.
    w.i32(LVisData, 2), w.i32(LVisData, 1);
    w.lump[LVisData].push_back(0x1);
    w.lump[LVisData].push_back(0x2);
    return w;
}

// A quad facing +z over x0..x1, y0..y1 at height z, stored clockwise seen from +z (as Quake 3).
void quadFace(BspWriter &w, double x0, double x1, double y0, double y1, double z) {
    const int32_t v = w.vertex({x0, y1, z});
    w.vertex({x1, y1, z}), w.vertex({x1, y0, z}), w.vertex({x0, y0, z});
    w.face(0, 1, v, 4, w.meshverts({0, 1, 2, 0, 2, 3}), 6);
}

// The tiny map with brush entities laid out as q3map2 writes them: each model's faces are listed
// only by a leaf of its own (cluster 0, zero bounds) that the world's tree never reaches.
//   face 9:  model 2, a trigger_teleport (ordinary shader): never drawn
//   face 10: model 3, a func_bobbing stored around 0 with "origin" "-50 0 40": drawn in leaf 1
//   face 11: model 4, which no entity spawns: never drawn
//   face 12: model 5, a func_door over x -30..-20 (leaf 1's side, cluster 1)
//   leafs 3..7: the models' own leafs, listing faces 8..12
BspWriter brushEntityWriter() {
    BspWriter w = tinyWriter();
    std::string text(w.lump[LEntities].begin(), w.lump[LEntities].end() - 1);  // without the NUL
    text += "{\n\"classname\" \"trigger_teleport\"\n\"model\" \"*2\"\n\"target\" \"t1\"\n}\n"
            "{\n\"classname\" \"func_bobbing\"\n\"model\" \"*3\"\n\"origin\" \"-50 0 40\"\n}\n"
            "{\n\"classname\" \"func_door\"\n\"model\" \"*5\"\n}\n";
    w.lump[LEntities].clear();
    w.bytes(LEntities, text, std::string::npos);
    w.lump[LEntities].push_back(0);
    quadFace(w, 60, 70, -5, 5, 10);     // face 9
    quadFace(w, -5, 5, -5, 5, 0);       // face 10
    quadFace(w, 40, 50, 20, 30, 20);    // face 11
    quadFace(w, -30, -20, -10, 10, 30); // face 12
    for (int32_t f : {8, 9, 10, 11, 12}) w.i32(LLeafFaces, f);
    for (int32_t k = 0; k < 5; ++k) w.leaf(0, {0, 0, 0}, {0, 0, 0}, 8 + k, 1);
    w.model({60, -5, 10}, {70, 5, 10}, 9, 1);
    w.model({-5, -5, 0}, {5, 5, 0}, 10, 1);
    w.model({40, 20, 20}, {50, 30, 20}, 11, 1);
    w.model({-30, -10, 30}, {-20, 10, 30}, 12, 1);
    return w;
}

std::string parseError(const std::vector<uint8_t> &f, BspOptions opt = {}) {
    SceneBuildInput in;
    BspLevel lv;
    std::string err;
    EXPECT_FALSE(parseBsp(f.data(), f.size(), "tiny.bsp", opt, &in, &lv, &err));
    return err;
}

std::string scratchDir() {
    const std::string d = (fs::temp_directory_path() / ("visaudit_bsp_" + std::to_string(getpid()))).string();
    fs::create_directories(d);
    return d;
}
std::string writeFile(const std::string &name, const std::vector<uint8_t> &bytes) {
    const std::string p = scratchDir() + "/" + name;
    std::ofstream(p, std::ios::binary).write(reinterpret_cast<const char *>(bytes.data()), std::streamsize(bytes.size()));
    return p;
}

Scene loadTiny(int patchLevel = 5) {
    const std::string p = writeFile("tiny" + std::to_string(patchLevel) + ".bsp", tinyWriter().file());
    Scene s;
    std::string err;
    BspOptions o;
    o.patchLevel = patchLevel;
    EXPECT_TRUE(loadBspScene(p, o, {}, &s, &err)) << err;
    return s;
}

Camera cameraAt(const Scene &s, Vec3 eye, double yaw = 0) {
    Camera c;
    std::string err;
    EXPECT_TRUE(makeCamera(quakeCamera(s, eye, yaw), &c, &err)) << err;
    return c;
}

const SourceObject *sourceNamed(const Scene &s, const std::string &name) {
    for (const auto &o : s.sources)
        if (o.name == name) return &o;
    return nullptr;
}

}  // namespace

// ---- The tiny map: exact counts ----------------------------------------------------------------------

TEST(Bsp, TinyMapObjectsAndCounts) {
    const Scene s = loadTiny(5);
    ASSERT_TRUE(s.bsp);
    const BspLevel &lv = *s.bsp;
    EXPECT_EQ(s.up, 'z');
    // Objects: leaf0 (faces 0, 2, 6), leaf1 (face 1), model1 (face 8), unleafed (face 7).
    ASSERT_EQ(s.sources.size(), 4u);
    EXPECT_EQ(s.sources[0].name, "leaf0");
    EXPECT_EQ(s.sources[1].name, "leaf1");
    EXPECT_EQ(s.sources[2].name, "model1");
    EXPECT_EQ(s.sources[3].name, "unleafed");
    EXPECT_EQ(s.sources[0].triangleCount, 2u + 2 * 5 * 5 + 1);
    EXPECT_EQ(s.sources[1].triangleCount, 1u);
    EXPECT_EQ(s.sources[2].triangleCount, 2u);
    EXPECT_EQ(s.sources[3].triangleCount, 1u);
    EXPECT_EQ(s.triangleCount(), 57u);
    EXPECT_EQ(s.stats.degenerateTriangles, 0u);
    // Clusters per object: leaf0 {0, 1} (face 6 is also in leaf 1), leaf1 {1}, model1 {0} (its box
    // lies in leaf 0), unleafed {}.
    EXPECT_EQ(lv.sourceCluster, (std::vector<int32_t>{0, 1, -1, -1}));
    EXPECT_EQ(lv.sourceClustersBegin, (std::vector<uint32_t>{0, 2, 3, 4, 4}));
    EXPECT_EQ(lv.sourceClusters, (std::vector<int32_t>{0, 1, 1, 0}));
    const BspFaceCounts &fc = lv.faceCounts;
    EXPECT_EQ(fc.faces, 9u);
    EXPECT_EQ(fc.polygons, 4u);
    EXPECT_EQ(fc.patches, 1u);
    EXPECT_EQ(fc.meshes, 1u);
    EXPECT_EQ(fc.billboards, 1u);
    EXPECT_EQ(fc.bad, 0u);
    EXPECT_EQ(fc.sky, 1u);
    EXPECT_EQ(fc.nodraw, 0u);
    EXPECT_EQ(fc.nonSolid, 1u);
    EXPECT_EQ(fc.polygonTriangles, 6u);
    EXPECT_EQ(fc.patchTriangles, 50u);
    EXPECT_EQ(fc.meshTriangles, 1u);
    EXPECT_EQ(fc.skyTriangles, 1u);
    EXPECT_EQ(fc.nonSolidTriangles, 1u);
    EXPECT_EQ(fc.unleafedFaces, 1u);
    EXPECT_EQ(fc.modelFaces, 1u);
    EXPECT_EQ(lv.clusterCount, 2);
    EXPECT_EQ(lv.pvsRowBytes, 1u);
    EXPECT_EQ(lv.leafs.size(), 3u);
    EXPECT_EQ(lv.nodes.size(), 2u);
    EXPECT_EQ(lv.entities.size(), 6u);
    ASSERT_EQ(lv.models.size(), 2u);
    EXPECT_EQ(lv.models[1].entity, 5);
    EXPECT_EQ(lv.models[1].classname, "func_door");
    EXPECT_TRUE(lv.models[1].drawn);
    EXPECT_EQ(lv.models[1].boxLeafs, (std::vector<int32_t>{0}));
    EXPECT_EQ(lv.sourceModel, (std::vector<uint32_t>{0, 0, 1, 0}));
    // Each triangle's face: leaf0 = faces 0 (2), 2 (50), 6 (1); leaf1 = 1; model1 = 8 (2); unleafed = 7.
    std::vector<uint32_t> faceOf;
    for (auto [f, n] : std::vector<std::pair<uint32_t, int>>{{0, 2}, {2, 50}, {6, 1}, {1, 1}, {8, 2}, {7, 1}})
        faceOf.insert(faceOf.end(), size_t(n), f);
    EXPECT_EQ(lv.triangleFace, faceOf);
    EXPECT_EQ(lv.leafInTree, (std::vector<uint8_t>{1, 1, 1}));
    EXPECT_EQ(lv.faceLeafsBegin, (std::vector<uint32_t>{0, 1, 2, 3, 4, 5, 6, 8, 8, 8}));
    EXPECT_EQ(lv.faceLeafs, (std::vector<uint32_t>{0, 1, 0, 1, 0, 0, 0, 1}));
    EXPECT_EQ(lv.farPlane.distance, 0);
    ASSERT_EQ(s.warnings.size(), 1u);
    EXPECT_EQ(s.warnings[0], s.path + ": kept out of the objects (docs/quake3.md): 1 sky, 0 nodraw, "
                                      "1 non-solid see-through, 1 billboard and 0 bad faces");
}

// Brush entities (issue 15): a model's faces get the clusters of its placed box walked through the
// world's tree, never the cluster 0 of the model's own leaf; triggers and models no entity spawns are
// not geometry. Before, face 12 (the door on cluster 1's side) took cluster {0} from leaf 7 and was
// culled from every view that could see it.
TEST(Bsp, TinyMapBrushEntities) {
    const std::string p = writeFile("entities.bsp", brushEntityWriter().file());
    Scene s;
    std::string err;
    ASSERT_TRUE(loadBspScene(p, {}, {}, &s, &err)) << err;
    const BspLevel &lv = *s.bsp;
    ASSERT_EQ(s.sources.size(), 6u);
    const char *names[] = {"leaf0", "leaf1", "model1", "model3", "model5", "unleafed"};
    for (size_t k = 0; k < 6; ++k) EXPECT_EQ(s.sources[k].name, names[k]);
    EXPECT_EQ(lv.sourceModel, (std::vector<uint32_t>{0, 0, 1, 3, 5, 0}));
    // Clusters: leaf0 {0, 1}, leaf1 {1}, model1 {0}, model3 {1} (placed at x -55..-45), model5 {1}.
    EXPECT_EQ(lv.sourceClustersBegin, (std::vector<uint32_t>{0, 2, 3, 4, 5, 6, 6}));
    EXPECT_EQ(lv.sourceClusters, (std::vector<int32_t>{0, 1, 1, 0, 1, 1}));
    EXPECT_EQ(lv.leafInTree, (std::vector<uint8_t>{1, 1, 1, 0, 0, 0, 0, 0}));
    ASSERT_EQ(lv.models.size(), 6u);
    EXPECT_FALSE(lv.models[2].drawn);
    EXPECT_EQ(lv.models[2].classname, "trigger_teleport");
    EXPECT_EQ(lv.models[2].entity, 6);
    EXPECT_EQ(lv.models[2].notDrawnFaces, 1u);
    EXPECT_EQ(lv.models[2].notDrawnTriangles, 2u);
    EXPECT_TRUE(lv.models[2].boxLeafs.empty());
    EXPECT_TRUE(lv.models[3].drawn);
    EXPECT_EQ(lv.models[3].offset, (Vec3{-50, 0, 40}));
    EXPECT_EQ(lv.models[3].bounds.lo, (Vec3{-55, -5, 40}));
    EXPECT_EQ(lv.models[3].boxLeafs, (std::vector<int32_t>{1}));
    EXPECT_FALSE(lv.models[4].drawn);
    EXPECT_EQ(lv.models[4].entity, -1);
    EXPECT_EQ(lv.models[4].notDrawnFaces, 1u);
    EXPECT_EQ(lv.models[5].boxLeafs, (std::vector<int32_t>{1}));
    const BspFaceCounts &fc = lv.faceCounts;
    EXPECT_EQ(fc.faces, 13u);
    EXPECT_EQ(fc.modelFaces, 3u);
    EXPECT_EQ(fc.notDrawnEntity, 2u);
    EXPECT_EQ(fc.notDrawnEntityTriangles, 4u);
    EXPECT_EQ(fc.polygons, 6u);
    EXPECT_EQ(fc.polygons + fc.patches + fc.meshes + fc.billboards + fc.bad + fc.sky + fc.nodraw + fc.nonSolid +
                  fc.notDrawnEntity, fc.faces);
    EXPECT_EQ(s.triangleCount(), 61u);
    // model3 is drawn where its entity's origin puts it.
    const SourceObject &bob = s.sources[3];
    const SceneObject &bobObj = s.objects[bob.firstChunk];
    for (uint32_t v = bobObj.vertexBegin; v < bobObj.vertexEnd; ++v) {
        EXPECT_GE(s.positions[v].x, -55);
        EXPECT_LE(s.positions[v].x, -45);
        EXPECT_EQ(s.positions[v].z, 40);
    }
    ASSERT_EQ(s.warnings.size(), 2u);
    EXPECT_EQ(s.warnings[1], p + ": not geometry (docs/quake3.md, \"Brush entities\"): 2 faces of 2 brush entities the "
                                 "engine never draws (trigger_*, models no entity spawns)");
    // From cluster 1 (x < 0) the door and the bobbing platform stay; from cluster 0 they are culled.
    CellsResult r = cullCells(s, cameraAt(s, {-25, 0, 80}));
    EXPECT_EQ(r.stats.cameraCluster, 1);
    EXPECT_EQ(r.visible, (std::vector<uint32_t>{0, 1, 3, 4, 5}));
    r = cullCells(s, cameraAt(s, {50, 0, 59}));
    EXPECT_EQ(r.stats.cameraCluster, 0);
    EXPECT_EQ(r.visible, (std::vector<uint32_t>{0, 2, 5}));
    // Looking down at the door from cluster 1: the reference shows it and the PVS keeps it.
    Camera cam;
    ASSERT_TRUE(makeCamera(quakeCamera(s, {-25, 0, 80}, 0, 89), &cam, &err)) << err;
    const ReferenceVisibility ref = referenceVisibility(s, cam);
    uint64_t doorPixels = 0;
    for (uint32_t t = s.sources[4].firstTriangle; t < s.sources[4].firstTriangle + s.sources[4].triangleCount; ++t)
        doorPixels += ref.pixelsOf[t];
    EXPECT_GT(doorPixels, 1000u);
    r = cullCells(s, cam);
    std::vector<uint32_t> culled;
    for (uint32_t o = 0; o < s.objects.size(); ++o)
        if (!std::binary_search(r.visible.begin(), r.visible.end(), o)) culled.push_back(o);
    std::vector<uint32_t> all;
    for (uint32_t t = 0; t < s.triangleCount(); ++t)
        if (s.triangleObject[t] != kExcludedTriangle) all.push_back(t);
    const CullAudit a = auditCulling(s, ref, {{"cells", culled, {}}}, all, nullptr);
    EXPECT_EQ(a.falseCullPixels, 0u);
}

// The evidence of a false cull, on the tiny map with brush entities: from cluster 0 (which sees only
// itself) looking towards -x, leaf 1's triangle, the door (model 5) and the bobbing platform (model
// 3) are all in cluster 1, visible, and culled by the PVS.
TEST(Audit, TinyMapPvsEvidence) {
    const std::string p = writeFile("evidence.bsp", brushEntityWriter().file());
    Scene s;
    std::string err;
    ASSERT_TRUE(loadBspScene(p, {}, {}, &s, &err)) << err;
    ViewSpec v;
    v.name = "look";
    v.camera = quakeCamera(s, {50, 0, 59}, 180, 20);
    PipelineSettings ps;
    ps.width = 160, ps.height = 90;
    ps.ordering = false, ps.zfight = false, ps.detail = false, ps.occlusion = false;
    AnalysisResult out;
    ASSERT_TRUE(analyzeScene(s, {v}, ps, nullptr, &out, &err)) << err;
    const ViewResult &r = out.views[0];
    const PvsEvidence &e = r.audit->pvsEvidence;
    ASSERT_TRUE(e.ran);
    EXPECT_EQ(e.cameraLeaf, 0);
    EXPECT_EQ(e.cameraCluster, 0);
    EXPECT_EQ(e.designFarPlane, 0);
    const StageCullAudit &cells = r.audit->cull.stages[0];
    ASSERT_EQ(cells.stage, "cells");
    EXPECT_EQ(e.falseCullPixels, cells.falseCullPixels);
    EXPECT_EQ(e.falseCullObjects, cells.falseCullObjects);
    ASSERT_EQ(e.objects.size(), 3u);
    EXPECT_EQ(e.objectsOmitted, 0u);
    std::map<std::string, const PvsObjectEvidence *> byName;
    uint64_t pixels = 0;
    for (size_t k = 0; k < e.objects.size(); ++k) {
        const PvsObjectEvidence &o = e.objects[k];
        byName[o.name] = &o;
        pixels += o.pixels;
        // Same order as the stage's worst offenders.
        EXPECT_EQ(o.object, cells.worst[k].object);
        EXPECT_EQ(o.pixels, cells.worst[k].pixels);
        EXPECT_EQ(o.triangles, cells.worst[k].triangles);
        ASSERT_EQ(o.clusters.size(), 1u);
        EXPECT_EQ(o.clusters[0].cluster, 1);
        EXPECT_EQ(o.clusters[0].pvsBit, 0);
        EXPECT_GT(o.nearest, 0);
    }
    EXPECT_EQ(pixels, cells.falseCullPixels);
    ASSERT_TRUE(byName.count("leaf1") && byName.count("model5") && byName.count("model3"));
    // World faces: face 1, listed by leaf 1 only (cluster 1, bit 0).
    const PvsObjectEvidence &leaf1 = *byName["leaf1"];
    EXPECT_EQ(leaf1.model, 0u);
    EXPECT_EQ(leaf1.entity, -1);
    EXPECT_TRUE(leaf1.boxLeafs.empty());
    ASSERT_EQ(leaf1.faces.size(), 1u);
    EXPECT_EQ(leaf1.faces[0].face, 1u);
    EXPECT_EQ(leaf1.faces[0].pixels, leaf1.pixels);
    ASSERT_EQ(leaf1.faces[0].leafs.size(), 1u);
    EXPECT_EQ(leaf1.faces[0].leafs[0].leaf, 1);
    EXPECT_EQ(leaf1.faces[0].leafs[0].cluster, 1);
    EXPECT_TRUE(leaf1.faces[0].leafs[0].inTree);
    EXPECT_EQ(leaf1.faces[0].leafs[0].pvsBit, 0);
    // The door: face 12, listed only by its own leaf 7 (cluster 0, out of the tree: bit 1, which
    // does not count); its box reaches leaf 1 (cluster 1, bit 0).
    const PvsObjectEvidence &door = *byName["model5"];
    EXPECT_EQ(door.model, 5u);
    EXPECT_EQ(door.classname, "func_door");
    EXPECT_EQ(door.entity, 8);
    ASSERT_EQ(door.boxLeafs.size(), 1u);
    EXPECT_EQ(door.boxLeafs[0].leaf, 1);
    EXPECT_EQ(door.boxLeafs[0].cluster, 1);
    EXPECT_EQ(door.boxLeafs[0].pvsBit, 0);
    ASSERT_EQ(door.faces.size(), 1u);
    EXPECT_EQ(door.faces[0].face, 12u);
    ASSERT_EQ(door.faces[0].leafs.size(), 1u);
    EXPECT_EQ(door.faces[0].leafs[0].leaf, 7);
    EXPECT_EQ(door.faces[0].leafs[0].cluster, 0);
    EXPECT_FALSE(door.faces[0].leafs[0].inTree);
    EXPECT_EQ(door.faces[0].leafs[0].pvsBit, 1);
    // Each face's pixel shows a triangle of that face, falsely culled by the cells stage, at the
    // distance given.
    for (const PvsObjectEvidence &o : e.objects)
        for (const PvsFaceEvidence &f : o.faces) {
            const size_t i = size_t(f.y) * 160 + size_t(f.x);
            ASSERT_GT(r.audit->reference.id[i], 0u);
            const uint32_t t = r.audit->reference.id[i] - 1;
            EXPECT_EQ(s.bsp->triangleFace[t], f.face);
            EXPECT_EQ(s.triangleObject[t], o.object);
            EXPECT_EQ(r.audit->cull.fate[i], kFateCulledFirst);
            EXPECT_EQ(pixelPointDistance(r.camera, i, r.audit->reference.depth[i]), f.nearest);
        }
}

TEST(Bsp, PatchLevelSetsTriangleCount) {
    for (int L : {1, 2, 3, 8}) {
        const Scene s = loadTiny(L);
        EXPECT_EQ(s.bsp->faceCounts.patchTriangles, uint64_t(2 * L * L)) << "level " << L;
        EXPECT_EQ(s.triangleCount(), uint64_t(2 + 2 * L * L + 1 + 1 + 2 + 1)) << "level " << L;
    }
    BspOptions o;
    o.patchLevel = 0;
    EXPECT_EQ(parseError(tinyWriter().file(), o), "tiny.bsp: patch level 0 is outside 1..64; choose e.g. 5 (--patch-level)");
}

// Quake 3 stores faces clockwise seen from the front; visaudit's front faces are counter-clockwise.
// Every face of the tiny map faces +z, so every plane normal (v1 - v0) x (v2 - v0) must point up.
TEST(Bsp, WindingReversedToCounterClockwise) {
    const Scene s = loadTiny(3);
    size_t checked = 0;
    for (uint32_t t = 0; t < s.triangleCount(); ++t) {
        if (s.triangleObject[t] == kExcludedTriangle) continue;
        // The patch's interior points are rounded (x = 20 + 60 t), so its normals may tilt by a few
        // ulps; the z component must dominate by far.
        const double *pl = &s.planes[4 * t];
        EXPECT_GT(pl[2], 0) << "triangle " << t;
        EXPECT_LT(std::abs(pl[0]) + std::abs(pl[1]), 1e-9 * pl[2]) << "triangle " << t;
        ++checked;
    }
    EXPECT_EQ(checked, s.triangleCount());
    // The patch is flat at z = 8 over x 20..80, y -30..30: tessellated vertices stay on it and the
    // corners are exactly the control points.
    const SceneObject &leaf0 = s.objects[s.sources[0].firstChunk];
    std::set<std::pair<double, double>> patchCorners;
    for (uint32_t v = leaf0.vertexBegin; v < leaf0.vertexEnd; ++v)
        if (std::abs(s.positions[v].z - 8) < 1e-12) patchCorners.insert({s.positions[v].x, s.positions[v].y});
    EXPECT_EQ(patchCorners.size(), 16u);  // (3 + 1)^2 grid points
    EXPECT_TRUE(patchCorners.count({20, -30}) && patchCorners.count({80, 30}) && patchCorners.count({20, 30}) &&
                patchCorners.count({80, -30}));
}

TEST(Bsp, LeafLookupWalksTheTree) {
    const Scene s = loadTiny();
    const BspLevel &lv = *s.bsp;
    EXPECT_EQ(lv.leafAt({50, 0, 0}), 0);
    EXPECT_EQ(lv.leafAt({-50, 0, 0}), 1);
    EXPECT_EQ(lv.leafAt({150, 0, 0}), 2);
    EXPECT_EQ(lv.leafAt({0, 0, 0}), 0);    // on plane 0: dot - dist = 0 >= 0 is the front
    EXPECT_EQ(lv.leafAt({100, 0, 0}), 2);  // on plane 1: front
    EXPECT_TRUE(lv.clusterVisible(0, 0));
    EXPECT_FALSE(lv.clusterVisible(0, 1));
    EXPECT_FALSE(lv.clusterVisible(1, 0));
    EXPECT_TRUE(lv.clusterVisible(1, 1));
}

TEST(Bsp, EntitiesParsed) {
    const Scene s = loadTiny();
    const auto &e = s.bsp->entities;
    ASSERT_EQ(e.size(), 6u);
    EXPECT_EQ(*e[1].get("classname"), "info_player_deathmatch");
    EXPECT_EQ(*e[1].get("origin"), "50 0 24");
    EXPECT_EQ(e[1].get("nothing"), nullptr);
    std::vector<BspEntity> out;
    std::string err;
    EXPECT_FALSE(parseBspEntities("{\n\"a\" \"b\"\n", &out, &err));
    EXPECT_EQ(err, "line 3: entity not closed with '}'; the entity text is truncated");
    EXPECT_FALSE(parseBspEntities("{\n\"a\" \"b\n", &out, &err));
    EXPECT_EQ(err, "line 3: unterminated string; the entity text is truncated");
    EXPECT_FALSE(parseBspEntities("\n\n x", &out, &err));
    EXPECT_EQ(err, "line 3: expected '{' to open an entity, got 'x'");
    EXPECT_FALSE(parseBspEntities("{ \"key\" }", &out, &err));
    EXPECT_EQ(err, "line 1: expected a quoted string, got '}'");
    EXPECT_TRUE(parseBspEntities("", &out, &err));
    EXPECT_TRUE(out.empty());
}

TEST(Bsp, LoadSceneDispatchesBspAndPk3) {
    const std::vector<uint8_t> bytes = tinyWriter().file();
    const std::string loose = writeFile("dispatch.bsp", bytes);
    Scene a, b, c;
    std::string err;
    ASSERT_TRUE(loadScene(loose, {}, &a, &err)) << err;
    EXPECT_EQ(a.triangleCount(), 57u);
    // The same map inside a pk3, deflated and stored; the member is found ignoring case.
    for (bool deflate : {true, false}) {
        const std::string pk3 = scratchDir() + (deflate ? "/deflated.pk3" : "/stored.pk3");
        ASSERT_TRUE(writeZipArchive(pk3, {{"maps/readme.txt", {'h', 'i'}}, {"maps/Tiny.bsp", bytes}}, deflate, &err)) << err;
        ASSERT_TRUE(loadScene(pk3 + ":maps/tiny.bsp", {}, &b, &err)) << err;
        EXPECT_EQ(b.triangleCount(), 57u);
        EXPECT_EQ(b.sources[0].mesh, pk3 + ":maps/tiny.bsp");
        EXPECT_FALSE(loadScene(pk3 + ":maps/other.bsp", {}, &c, &err));
        EXPECT_EQ(err, pk3 + ": no member 'maps/other.bsp' in the archive; members ending in '.bsp': maps/Tiny.bsp");
    }
    EXPECT_TRUE(isBspPath("a/b.BSP"));
    EXPECT_TRUE(isBspPath("x/pak0.PK3:maps/q3dm1.bsp"));
    EXPECT_FALSE(isBspPath("x/pak0.pk3:maps/q3dm1.aas"));
    EXPECT_FALSE(isBspPath("level.json"));
}

TEST(Bsp, ArchiveErrors) {
    std::string err;
    std::vector<uint8_t> out;
    const std::string notZip = writeFile("notzip.pk3", {'n', 'o', 't', ' ', 'a', ' ', 'z', 'i', 'p'});
    EXPECT_FALSE(readZipMember(notZip, "maps/x.bsp", 1 << 20, &out, &err));
    EXPECT_EQ(err, notZip + ": cannot open as a zip archive (Not a zip archive); a .pk3 must be a zip file: "
                            "check the path, or test it with 'unzip -t'");
    // A member larger than the limit is refused from the directory, before it is decompressed.
    const std::string big = scratchDir() + "/big.pk3";
    ASSERT_TRUE(writeZipArchive(big, {{"maps/big.bsp", std::vector<uint8_t>(5000, 7)}}, true, &err)) << err;
    EXPECT_FALSE(readZipMember(big, "maps/big.bsp", 4096, &out, &err));
    EXPECT_EQ(err, big + ":maps/big.bsp: member is 5000 bytes uncompressed, more than the limit of 4096 bytes; "
                         "this is not a map (or raise the limit)");
    // A corrupted deflate stream (bytes flipped inside the member's data) fails its read or CRC.
    std::vector<uint8_t> z;
    {
        std::ifstream in(big, std::ios::binary);
        z.assign(std::istreambuf_iterator<char>(in), {});
    }
    ASSERT_GT(z.size(), 60u);
    // The member's data starts after the 30-byte local header, its name and its extra field.
    const size_t data = 30 + size_t(z[26] | z[27] << 8) + size_t(z[28] | z[29] << 8);
    for (size_t k = data + 2; k < data + 12; ++k) z[k] ^= 0x5A;
    const std::string bad = writeFile("bad.pk3", z);
    EXPECT_FALSE(readZipMember(bad, "maps/big.bsp", 1 << 20, &out, &err));
    EXPECT_EQ(err.rfind(bad + ":maps/big.bsp: cannot decompress the member (", 0), 0u) << err;
    std::string archive, member;
    EXPECT_TRUE(splitArchivePath("C:/games/pak0.pk3:maps/q3dm1.bsp", &archive, &member));
    EXPECT_EQ(archive, "C:/games/pak0.pk3");
    EXPECT_EQ(member, "maps/q3dm1.bsp");
    EXPECT_FALSE(splitArchivePath("maps/q3dm1.bsp", &archive, &member));
}

// ---- Bad and hostile files: exact messages, refused before allocating -------------------------------

TEST(Bsp, HeaderRefusals) {
    std::vector<uint8_t> f = tinyWriter().file();
    EXPECT_EQ(parseError(std::vector<uint8_t>(f.begin(), f.begin() + 100)),
              "tiny.bsp: truncated: 100 bytes, but a Quake 3 map's header alone is 144 bytes; fetch the file again");
    std::vector<uint8_t> g = f;
    std::memcpy(g.data(), "VBSP", 4);
    EXPECT_EQ(parseError(g), "tiny.bsp: not a Quake 3 map: the file starts with 'VBSP' (a Source engine map), "
                             "expected 'IBSP'; visaudit reads Quake 3 maps (IBSP version 46)");
    g = f;
    put32(g, 4, 38);
    EXPECT_EQ(parseError(g), "tiny.bsp: IBSP version 38 (a Quake 2 map) is not supported; visaudit reads Quake 3's version 46");
    // A faces lump claiming 2 GB in a small file.
    g = f;
    const int32_t facesOff = get32(g, 8 + 8 * LFaces);
    put32(g, 12 + 8 * LFaces, 0x7FFFFFF8);
    EXPECT_EQ(parseError(g), "tiny.bsp: lump 'faces': bytes " + std::to_string(facesOff) + ".." +
                                 std::to_string(int64_t(facesOff) + 0x7FFFFFF8) + " lie past the end of the file (" +
                                 std::to_string(f.size()) + " bytes): the file is truncated or the header is damaged; fetch it again");
    g = f;
    put32(g, 8 + 8 * LPlanes, -4);
    EXPECT_EQ(parseError(g), "tiny.bsp: lump 'planes': offset -4 and length 32 in the header: negative values; the header is damaged");
    g = f;
    put32(g, 12 + 8 * LLeafs, 47);
    EXPECT_EQ(parseError(g), "tiny.bsp: lump 'leafs': length 47 is not a whole number of 48-byte records; the file is damaged");
}

// Every strict prefix of a valid file is refused (the last lump ends the file), without a crash.
TEST(Bsp, EveryTruncationRefused) {
    const std::vector<uint8_t> f = tinyWriter().file();
    for (size_t n = 0; n < f.size(); ++n) {
        SceneBuildInput in;
        BspLevel lv;
        std::string err;
        ASSERT_FALSE(parseBsp(f.data(), n, "tiny.bsp", {}, &in, &lv, &err)) << "prefix of " << n << " bytes";
        ASSERT_EQ(err.rfind("tiny.bsp: ", 0), 0u);
    }
    SceneBuildInput in;
    BspLevel lv;
    std::string err;
    EXPECT_TRUE(parseBsp(f.data(), f.size(), "tiny.bsp", {}, &in, &lv, &err)) << err;
}

TEST(Bsp, IndexRefusals) {
    const std::vector<uint8_t> f = tinyWriter().file();
    const size_t faces = lumpOffset(f, LFaces), leafs = lumpOffset(f, LLeafs), nodes = lumpOffset(f, LNodes);
    const size_t vis = lumpOffset(f, LVisData), leaffaces = lumpOffset(f, LLeafFaces), mv = lumpOffset(f, LMeshVerts);
    auto with = [&](size_t at, int32_t v) {
        std::vector<uint8_t> g = f;
        put32(g, at, v);
        return parseError(g);
    };
    // Face 0's vertex range (offset 12, count 16 in the record); the file has 38 vertices.
    EXPECT_EQ(with(faces + 16, 40), "tiny.bsp: lump 'faces': face 0 vertex range 0..40 exceeds 33 vertices; the file is damaged");
    EXPECT_EQ(with(faces + 12, -1), "tiny.bsp: lump 'faces': face 0 vertex range -1..3 exceeds 33 vertices; the file is damaged");
    EXPECT_EQ(with(faces + 24, 600000000),
              "tiny.bsp: lump 'faces': face 0 meshvert range 0..600000000 exceeds 27 meshverts; the file is damaged");
    EXPECT_EQ(with(mv + 4, 4), "tiny.bsp: lump 'faces': face 0 meshvert 1 = 4 is outside the face's 4 vertices; the file is damaged");
    EXPECT_EQ(with(faces + 8, 7), "tiny.bsp: lump 'faces': face 0 has type 7; Quake 3 knows 1 polygon, 2 patch, 3 mesh, "
                                  "4 billboard; the file is damaged");
    EXPECT_EQ(with(faces, 3), "tiny.bsp: lump 'faces': face 0 shader 3 is outside the 3 shaders; the file is damaged");
    // Face 2 is the patch: an even width, and a grid larger than its vertices.
    EXPECT_EQ(with(faces + 2 * 104 + 96, 4), "tiny.bsp: lump 'faces': face 2 is a patch of 4x3 control points; "
                                             "patches need odd sizes of at least 3; the file is damaged");
    EXPECT_EQ(with(faces + 2 * 104 + 96, 65535), "tiny.bsp: lump 'faces': face 2 is a patch of 65535x3 control points "
                                                 "but has only 9 vertices; the file is damaged");
    EXPECT_EQ(with(leaffaces + 4, 9), "tiny.bsp: lump 'leaffaces': leafface 1 names face 9, outside the 9 faces; the file is damaged");
    EXPECT_EQ(with(leafs + 36, 9), "tiny.bsp: lump 'leafs': leaf 0 leafface range 0..9 exceeds the 8 leaffaces; the file is damaged");
    EXPECT_EQ(with(leafs, 2), "tiny.bsp: lump 'visdata': leafs name cluster 2 but the PVS has 2 clusters; the file is damaged");
    EXPECT_EQ(with(leafs, -7), "tiny.bsp: lump 'leafs': leaf 0 cluster -7 is below -1; the file is damaged");
    EXPECT_EQ(with(nodes, 2), "tiny.bsp: lump 'nodes': node 0 plane 2 is outside the 2 planes; the file is damaged");
    EXPECT_EQ(with(nodes + 36 + 4, 0), "tiny.bsp: lump 'nodes': node 1 child 0 does not come after its parent (a cycle); the file is damaged");
    EXPECT_EQ(with(nodes + 36 + 4, 2), "tiny.bsp: lump 'nodes': node 1 child 2 is outside the 2 nodes; the file is damaged");
    EXPECT_EQ(with(nodes + 8, -4), "tiny.bsp: lump 'nodes': node 0 child -4 names leaf 3, outside the 3 leafs; the file is damaged");
    // Hostile PVS header: 2^31 - 1 clusters of 2^31 - 1 bytes would need 4.6 exabytes.
    {
        std::vector<uint8_t> g = f;
        put32(g, vis, 0x7FFFFFFF);
        put32(g, vis + 4, 0x7FFFFFFF);
        EXPECT_EQ(parseError(g), "tiny.bsp: lump 'visdata': 2147483647 clusters x 2147483647 bytes = 4611686014132420609 "
                                 "bytes of PVS, but the lump holds 2; the file is truncated or damaged");
    }
    EXPECT_EQ(with(vis, 9), "tiny.bsp: lump 'visdata': 9 clusters x 1 bytes = 9 bytes of PVS, but the lump holds 2; "
                            "the file is truncated or damaged");
    EXPECT_EQ(with(vis + 4, 0), "tiny.bsp: lump 'visdata': rows of 0 bytes cannot hold a bit for each of 2 clusters; the file is damaged");
    // Entities: an unterminated string.
    {
        std::vector<uint8_t> g = f;
        const size_t e = lumpOffset(g, LEntities);
        g[e + 2] = 'x';  // {\n"classname" -> {\nx...
        EXPECT_EQ(parseError(g), "tiny.bsp: lump 'entities': line 2: expected a quoted string, got 'x'");
    }
}

// Hostile patch sizes would tessellate into billions of triangles: refused from the counts, before
// a single triangle is allocated.
TEST(Bsp, TriangleBudgetRefusedBeforeAllocating) {
    BspOptions o;
    o.patchLevel = 64;
    o.maxTriangles = 1000;
    EXPECT_EQ(parseError(tinyWriter().file(), o),
              "tiny.bsp: the map's drawn faces would make 8199 triangles and 4242 vertices at patch level 64, more "
              "than the limit of 1000 triangles; lower the patch level (--patch-level) or raise the limit with "
              "--max-triangles 8199, or the file is damaged");
    // Many faces sharing one large patch grid: 200 faces x 31 x 31 patches x 2 x 64^2.
    BspWriter w = tinyWriter();
    const int32_t first = int32_t(w.lump[LVertexes].size() / 44);
    for (int k = 0; k < 63 * 63; ++k) w.vertex({double(k % 63), double(k / 63), 0});
    w.lump[LFaces].clear();
    for (int k = 0; k < 200; ++k) w.face(0, 2, first, 63 * 63, 0, 0, 63, 63);
    w.lump[LLeafFaces].assign(32, 0);
    w.lump[LModels].clear();
    w.model({0, 0, 0}, {1, 1, 1}, 0, 200);
    o.maxTriangles = BspOptions{}.maxTriangles;
    EXPECT_EQ(parseError(w.file(), o),
              "tiny.bsp: the map's drawn faces would make 1574502400 triangles and 788045000 vertices at patch level 64, "
              "more than the limit of 50000000 triangles; lower the patch level (--patch-level) or raise the limit with "
              "--max-triangles 1574502400, or the file is damaged");
}

// The brush models' box walks have a budget, all models together (a hostile file of a million
// models over a million nodes would walk 10^12 nodes): over it, the file is refused.
TEST(Bsp, BoxWalkBudgetRefusesHostileModels) {
    const std::vector<uint8_t> f = brushEntityWriter().file();
    BspOptions o;
    // Model 1's walk: node 0, node 1, leaf 0 (3 steps); model 3's and model 5's: node 0, leaf 1 (2 each).
    o.maxBoxWalkSteps = 6;
    EXPECT_EQ(parseError(f, o), "tiny.bsp: lump 'models': the brush models' boxes reach more than 6 nodes of the "
                                "tree (at model 5 of 6); the file is damaged");
    o.maxBoxWalkSteps = 7;
    SceneBuildInput in;
    BspLevel lv;
    std::string err;
    EXPECT_TRUE(parseBsp(f.data(), f.size(), "tiny.bsp", o, &in, &lv, &err)) << err;
}

// Seeded byte corruption: every file is either read or refused with a message, and nothing crashes.
// (The same kind of corruption of the real maps was run under AddressSanitizer and UBSan: docs/quake3.md.)
TEST(Bsp, CorruptedBytesNeverCrash) {
    const std::vector<uint8_t> f = tinyWriter().file();
    uint64_t state = 12345;
    auto next = [&] {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return uint32_t(state >> 33);
    };
    int refused = 0;
    for (int trial = 0; trial < 3000; ++trial) {
        std::vector<uint8_t> g = f;
        const int flips = 1 + int(next() % 4);
        for (int k = 0; k < flips; ++k) {
            const size_t at = next() % g.size();
            g[at] = uint8_t(next() % 3 == 0 ? 0xFF : next());
        }
        SceneBuildInput in;
        BspLevel lv;
        std::string err;
        BspOptions o;
        o.maxTriangles = 200000;
        if (!parseBsp(g.data(), g.size(), "fuzz.bsp", o, &in, &lv, &err)) {
            ++refused;
            ASSERT_EQ(err.rfind("fuzz.bsp: ", 0), 0u) << err;
        }
    }
    EXPECT_GT(refused, 100);
}

// ---- The cells stage ---------------------------------------------------------------------------------

TEST(Cells, CullsInvisibleClustersFromASpawnPoint) {
    const Scene s = loadTiny();
    ASSERT_EQ(cellsSkipReason(s), nullptr);
    // spawn0 stands in leaf 0 (cluster 0): leaf1 (cluster 1 only) is culled; leaf0, model1 and
    // unleafed stay.
    ASSERT_GE(s.views.size(), 1u);
    Camera cam;
    std::string err;
    ASSERT_TRUE(makeCamera(s.views[0].camera, &cam, &err)) << err;
    CellsResult r = cullCells(s, cam);
    EXPECT_EQ(r.stats.cameraLeaf, 0);
    EXPECT_EQ(r.stats.cameraCluster, 0);
    EXPECT_FALSE(r.stats.cameraInVoid);
    EXPECT_EQ(r.stats.clustersTotal, 2u);
    EXPECT_EQ(r.stats.clustersVisible, 1u);
    EXPECT_EQ(r.stats.objectsIn, 4u);
    EXPECT_EQ(r.stats.objectsCulled, 1u);
    EXPECT_EQ(r.stats.objectsNoCluster, 1u);
    EXPECT_EQ(r.stats.trianglesIn, 57u);
    EXPECT_EQ(r.stats.trianglesCulled, 1u);
    EXPECT_EQ(r.visible, (std::vector<uint32_t>{0, 2, 3}));
    EXPECT_TRUE(r.note.empty());
    // From leaf 1 (cluster 1): model1 (cluster 0 only) is culled; leaf0 stays because face 6 is
    // also in cluster 1 (conservative union).
    r = cullCells(s, cameraAt(s, {-50, 0, 40}));
    EXPECT_EQ(r.stats.cameraCluster, 1);
    EXPECT_EQ(r.stats.objectsCulled, 1u);
    EXPECT_EQ(r.stats.trianglesCulled, 2u);
    EXPECT_EQ(r.visible, (std::vector<uint32_t>{0, 1, 3}));
}

TEST(Cells, CameraInTheVoidCullsNothing) {
    const Scene s = loadTiny();
    const CellsResult r = cullCells(s, cameraAt(s, {150, 0, 40}));
    EXPECT_EQ(r.stats.cameraLeaf, 2);
    EXPECT_EQ(r.stats.cameraCluster, -1);
    EXPECT_TRUE(r.stats.cameraInVoid);
    EXPECT_EQ(r.stats.objectsCulled, 0u);
    EXPECT_EQ(r.stats.trianglesCulled, 0u);
    EXPECT_EQ(r.stats.clustersVisible, 2u);
    EXPECT_EQ(r.stats.objectsNoCluster, 1u);
    EXPECT_EQ(r.visible, (std::vector<uint32_t>{0, 1, 2, 3}));
    EXPECT_EQ(r.note, "camera in the void: leaf 2 is outside every cluster (outside the map or inside a wall); nothing culled");
}

TEST(Cells, SkipReasons) {
    Scene plain;
    EXPECT_STREQ(cellsSkipReason(plain), "scene has no cells, portals or PVS");
    BspWriter w = tinyWriter();
    w.lump[LVisData].clear();
    const std::string p = writeFile("novis.bsp", w.file());
    Scene s;
    std::string err;
    ASSERT_TRUE(loadBspScene(p, {}, {}, &s, &err)) << err;
    EXPECT_FALSE(s.bsp->hasPvs());
    EXPECT_EQ(s.bsp->clusterCount, 2);
    EXPECT_STREQ(cellsSkipReason(s), "map has no PVS (its visdata lump is empty: compiled without vis)");
}

// ---- Level views -------------------------------------------------------------------------------------

TEST(LevelViews, SpawnPointsAtEyeHeight) {
    const Scene s = loadTiny();
    const std::vector<ViewSpec> v = spawnViews(s);
    ASSERT_EQ(v.size(), 3u);
    EXPECT_EQ(v[0].name, "spawn0");
    EXPECT_EQ(v[0].origin, "spawns: info_player_deathmatch");
    EXPECT_EQ(v[0].camera.eye, (Vec3{50, 0, 24 + 35}));
    // angle 90: looking along +y.
    const Vec3 d0 = v[0].camera.target - v[0].camera.eye;
    EXPECT_NEAR(d0.x, 0, 1e-15);
    EXPECT_DOUBLE_EQ(d0.y, 1);
    EXPECT_EQ(d0.z, 0);
    EXPECT_EQ(v[0].camera.up, (Vec3{0, 0, 1}));
    EXPECT_NEAR(v[0].camera.fovYDegrees, 58.7155, 1e-4);
    EXPECT_EQ(v[0].camera.nearZ, 4);
    // angles "10 180 0": pitch 10 down, yaw 180.
    EXPECT_EQ(v[1].name, "spawn1");
    const Vec3 d1 = v[1].camera.target - v[1].camera.eye;
    EXPECT_NEAR(d1.x, -std::cos(10 * kPi / 180), 1e-13);  // (eye + d) - eye rounds at 59
    EXPECT_NEAR(d1.z, -std::sin(10 * kPi / 180), 1e-13);
    // The intermission camera sits at its origin and aims at its target.
    EXPECT_EQ(v[2].name, "intermission0");
    EXPECT_EQ(v[2].camera.eye, (Vec3{0, 0, 200}));
    EXPECT_EQ(v[2].camera.target, (Vec3{50, 0, 0}));
    // loadBspScene makes them the scene's views.
    ASSERT_EQ(s.views.size(), 3u);
    EXPECT_EQ(s.views[1].camera.eye, v[1].camera.eye);
}

TEST(LevelViews, WalkIsSeededAndInsideClusters) {
    const Scene s = loadTiny();
    const std::vector<ViewSpec> a = walkViews(s, 20, 7), b = walkViews(s, 20, 7), c = walkViews(s, 20, 8);
    ASSERT_EQ(a.size(), 20u);
    int inLeaf0 = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        EXPECT_EQ(a[i].name, "walk" + std::to_string(i));
        EXPECT_EQ(a[i].origin, "walk:20");
        EXPECT_EQ(a[i].camera.eye, b[i].camera.eye);
        EXPECT_EQ(a[i].camera.target, b[i].camera.target);
        // Leaf 0's box center at floor + 50, or leaf 1's.
        const Vec3 e = a[i].camera.eye;
        EXPECT_TRUE(e == (Vec3{50, 0, -16 + 50}) || e == (Vec3{-50, 0, -16 + 50})) << e.x;
        inLeaf0 += e.x > 0;
        EXPECT_GE(s.bsp->leafs[size_t(s.bsp->leafAt(e))].cluster, 0);
    }
    EXPECT_GT(inLeaf0, 0);
    EXPECT_LT(inLeaf0, 20);
    bool differs = false;
    for (size_t i = 0; i < a.size(); ++i) differs |= !(a[i].camera.target == c[i].camera.target);
    EXPECT_TRUE(differs);
}

// ---- The designed far plane (issue 15) ------------------------------------------------------------

namespace {
// The tiny map with its worldspawn's keys replaced.
Scene tinyWithWorldspawn(const std::string &keys) {
    BspWriter w = tinyWriter();
    std::string text(w.lump[LEntities].begin(), w.lump[LEntities].end() - 1);
    const std::string ws = "{\n\"classname\" \"worldspawn\"\n}\n";
    text.replace(text.find(ws), ws.size(), "{\n\"classname\" \"worldspawn\"\n" + keys + "}\n");
    w.lump[LEntities].clear();
    w.bytes(LEntities, text, std::string::npos);
    w.lump[LEntities].push_back(0);
    const std::string p = writeFile("farplane.bsp", w.file());
    Scene s;
    std::string err;
    EXPECT_TRUE(loadBspScene(p, {}, {}, &s, &err)) << err;
    return s;
}
}  // namespace

TEST(LevelViews, FarPlaneKeysAsQ3map2ReadsThem) {
    Scene s = tinyWithWorldspawn("\"_farplanedist\" \"150\"\n");
    EXPECT_EQ(s.bsp->farPlane.distance, 150);
    EXPECT_EQ(s.bsp->farPlane.key, "_farplanedist");
    EXPECT_EQ(s.bsp->farPlane.mode, 0);
    // The map's views use it as their far plane (the map's diagonal + 16 would be 225).
    ASSERT_FALSE(s.views.empty());
    EXPECT_EQ(s.views[0].camera.farZ, 150);
    EXPECT_EQ(quakeCamera(s, {50, 0, 40}, 0).farZ, 150);
    s = tinyWithWorldspawn("\"_farplanedist\" \"512o\"\n\"_fog\" \"textures/fog/murk\"\n");
    EXPECT_EQ(s.bsp->farPlane.distance, 512);
    EXPECT_EQ(s.bsp->farPlane.mode, 'o');
    EXPECT_EQ(s.bsp->fogShader, "textures/fog/murk");
    EXPECT_EQ(s.views[0].camera.farZ, 225);  // farther than the map: the diagonal's far plane stays
    s = tinyWithWorldspawn("\"fogclip\" \"96\"\n");
    EXPECT_EQ(s.bsp->farPlane.distance, 96);
    EXPECT_EQ(s.bsp->farPlane.key, "fogclip");
    // "_farplanedist" wins over the other games' keys; a value that is no positive number is none.
    s = tinyWithWorldspawn("\"distancecull\" \"64\"\n\"_farplanedist\" \"128\"\n");
    EXPECT_EQ(s.bsp->farPlane.distance, 128);
    s = tinyWithWorldspawn("\"_farplanedist\" \"-5\"\n");
    EXPECT_EQ(s.bsp->farPlane.distance, 0);
    s = tinyWithWorldspawn("\"_farplanedist\" \"far\"\n");
    EXPECT_EQ(s.bsp->farPlane.distance, 0);
    EXPECT_EQ(s.views[0].camera.farZ, 225);
}

// From cluster 0, looking at leaf 1's triangle (cluster 1, which cluster 0 cannot see): every pixel
// of it is culled by the PVS. With a design far plane, the pixels whose point lies farther than it
// from the eye are hidden by design, the others stay false culls.
TEST(Audit, DesignFarPlaneSplitsTheCulledPixels) {
    const Scene s = loadTiny();
    Camera cam;
    std::string err;
    ASSERT_TRUE(makeCamera(quakeCamera(s, {50, 0, 59}, 180, 30), &cam, &err)) << err;
    const ReferenceVisibility ref = referenceVisibility(s, cam);
    const CellsResult r = cullCells(s, cam);
    ASSERT_EQ(r.stats.cameraCluster, 0);
    std::vector<uint32_t> culled;
    for (uint32_t o = 0; o < s.objects.size(); ++o)
        if (!std::binary_search(r.visible.begin(), r.visible.end(), o)) culled.push_back(o);
    ASSERT_EQ(culled, (std::vector<uint32_t>{1}));  // leaf1
    std::vector<uint32_t> drawn;
    for (uint32_t t = 0; t < s.triangleCount(); ++t)
        if (s.triangleObject[t] != kExcludedTriangle && s.triangleObject[t] != 1) drawn.push_back(t);
    const uint32_t leaf1Tri = s.sources[1].firstTriangle;
    const uint64_t visible = ref.pixelsOf[leaf1Tri];
    ASSERT_GT(visible, 1000u);
    // The distances of its pixels, straight from the camera: pixel center ray times the depth.
    double nearest = 1e300, farthest = 0;
    for (size_t i = 0; i < ref.id.size(); ++i)
        if (ref.id[i] == leaf1Tri + 1) {
            const double d = pixelPointDistance(cam, i, ref.depth[i]);
            nearest = std::min(nearest, d), farthest = std::max(farthest, d);
        }
    const double limit = (nearest + farthest) / 2;
    for (double fp : {0.0, limit, nearest / 2, farthest * 2}) {
        StageCulls st{"cells", culled, {}};
        st.designFarPlane = fp;
        const CullAudit a = auditCulling(s, ref, {st}, drawn, nullptr, &cam);
        const StageCullAudit &c = a.stages[0];
        uint64_t beyondFate = 0, falseFate = 0, beyondCount = 0;
        for (size_t i = 0; i < ref.id.size(); ++i) {
            beyondFate += a.fate[i] == kFateBeyondFarPlane;
            falseFate += a.fate[i] == kFateCulledFirst;
            if (ref.id[i] == leaf1Tri + 1 && fp > 0) beyondCount += pixelPointDistance(cam, i, ref.depth[i]) > fp;
        }
        EXPECT_EQ(c.beyondFarPlanePixels, beyondCount) << fp;
        EXPECT_EQ(c.falseCullPixels + c.beyondFarPlanePixels, visible) << fp;
        EXPECT_EQ(beyondFate, c.beyondFarPlanePixels) << fp;
        EXPECT_EQ(falseFate, c.falseCullPixels) << fp;
        EXPECT_EQ(a.beyondFarPlanePixels, c.beyondFarPlanePixels);
        EXPECT_EQ(c.designFarPlane, fp);
        if (fp == 0 || fp >= farthest) {  // none, or farther than all of it: all false culls
            EXPECT_EQ(c.falseCullPixels, visible);
            EXPECT_EQ(c.falseCullTriangles, 1u);
            EXPECT_EQ(c.falseCullNearest, nearest);
        } else if (fp < nearest) {  // all beyond: hidden by design, no false cull
            EXPECT_EQ(c.falseCullPixels, 0u);
            EXPECT_EQ(c.falseCullTriangles, 0u);
            EXPECT_EQ(c.beyondFarPlaneTriangles, 1u);
            EXPECT_EQ(c.beyondFarPlaneNearest, nearest);
            EXPECT_TRUE(c.worst.empty());
        } else {  // split: the triangle is still a false cull, at its near pixels only
            EXPECT_GT(c.falseCullPixels, 0u);
            EXPECT_GT(c.beyondFarPlanePixels, 0u);
            EXPECT_EQ(c.falseCullTriangles, 1u);
            EXPECT_EQ(c.beyondFarPlaneTriangles, 0u);
            EXPECT_EQ(c.falseCullNearest, nearest);
            EXPECT_GT(c.beyondFarPlaneNearest, fp);
        }
    }
    // Without a camera there are no distances: the far plane is not applied.
    StageCulls st{"cells", culled, {}};
    st.designFarPlane = nearest / 2;
    EXPECT_EQ(auditCulling(s, ref, {st}, drawn, nullptr).stages[0].falseCullPixels, visible);
}

TEST(LevelViews, ViewsOptionValues) {
    const Scene s = loadTiny();
    std::vector<ViewSpec> v;
    bool handled = false;
    std::string err;
    EXPECT_TRUE(levelViews("spawns", s, &v, &handled, &err));
    EXPECT_TRUE(handled);
    EXPECT_EQ(v.size(), 3u);
    EXPECT_TRUE(levelViews("walk:5", s, &v, &handled, &err));
    EXPECT_EQ(v.size(), 5u);
    EXPECT_TRUE(levelViews("walk:5:99", s, &v, &handled, &err));
    EXPECT_EQ(v[0].camera.eye, walkViews(s, 5, 99)[0].camera.eye);
    EXPECT_TRUE(levelViews("orbit:4", s, &v, &handled, &err));
    EXPECT_FALSE(handled);
    EXPECT_FALSE(levelViews("walk:0", s, &v, &handled, &err));
    EXPECT_EQ(err, "--views walk:0: expected walk:N or walk:N:SEED with N in 1..100000 and SEED a whole number, e.g. walk:16 or walk:16:7");
    EXPECT_FALSE(levelViews("walk:3:x", s, &v, &handled, &err));
    Scene plain;
    plain.path = "box.obj";
    EXPECT_FALSE(levelViews("spawns", plain, &v, &handled, &err));
    EXPECT_EQ(err, "--views spawns: needs a Quake 3 map (.bsp); 'box.obj' is not one; use a views file, or orbit:N");
}

// ---- Real maps (scripts/fetch-data.sh) ---------------------------------------------------------------

namespace {

const std::string kOa = std::string(VISAUDIT_SOURCE_DIR) + "/data/openarena/";

// Reads a map's raw bytes from its pk3 (for the independent decoding below).
std::vector<uint8_t> rawMap(const std::string &pk3, const std::string &member) {
    std::vector<uint8_t> b;
    std::string err;
    EXPECT_TRUE(readZipMember(kOa + pk3, member, 1u << 30, &b, &err)) << err;
    return b;
}

}  // namespace

#define REQUIRE_OA(file) \
    if (!fs::exists(kOa + file)) GTEST_SKIP() << kOa << file << " is absent: run scripts/fetch-data.sh to fetch it"

// Counts of a real map, printed for the record and compared with the values measured when the
// test was written (docs/quake3.md lists them).
struct MapCounts {
    uint64_t triangles, degenerate, objects, sources, clusters, leafs, faces, polygons, patches, meshes,
        billboards, sky, nodraw, nonSolid, polygonTriangles, patchTriangles, meshTriangles, views;
};
MapCounts countsOf(const Scene &s) {
    const BspFaceCounts &fc = s.bsp->faceCounts;
    return {s.triangleCount(), s.stats.degenerateTriangles, s.objects.size(), s.sources.size(),
            uint64_t(s.bsp->clusterCount), s.bsp->leafs.size(), fc.faces, fc.polygons, fc.patches, fc.meshes,
            fc.billboards, fc.sky, fc.nodraw, fc.nonSolid, fc.polygonTriangles, fc.patchTriangles, fc.meshTriangles,
            s.views.size()};
}
void expectCounts(const Scene &s, const MapCounts &want) {
    const MapCounts got = countsOf(s);
    const char *names[] = {"triangles", "degenerate", "objects", "sources", "clusters", "leafs", "faces", "polygons",
                           "patches", "meshes", "billboards", "sky", "nodraw", "nonSolid", "polygonTriangles",
                           "patchTriangles", "meshTriangles", "views"};
    const uint64_t *g = &got.triangles, *w = &want.triangles;
    for (size_t k = 0; k < sizeof(names) / sizeof(names[0]); ++k) {
        std::printf("%s%s %llu", k ? ", " : "  ", names[k], (unsigned long long)g[k]);
        EXPECT_EQ(g[k], w[k]) << names[k];
    }
    std::printf("\n");
    const BspFaceCounts &fc = s.bsp->faceCounts;
    // Every face is counted under exactly one kind, and the drawn faces' triangles are the scene's.
    EXPECT_EQ(fc.polygons + fc.patches + fc.meshes + fc.billboards + fc.bad + fc.sky + fc.nodraw + fc.nonSolid +
                  fc.notDrawnEntity,
              fc.faces);
    EXPECT_EQ(fc.polygonTriangles + fc.patchTriangles + fc.meshTriangles, s.triangleCount());
}

Scene loadReal(const std::string &path) {
    Scene s;
    std::string err;
    EXPECT_TRUE(loadScene(path, {}, &s, &err)) << err;
    return s;
}

// The PVS as a test decodes it straight from the file's bytes: header -> lump 16 -> rows.
struct RawPvs {
    int32_t n = 0, sz = 0;
    std::vector<uint8_t> rows;
    bool sees(int32_t x, int32_t y) const { return rows[size_t(x) * size_t(sz) + size_t(y / 8)] & (1 << (y % 8)); }
};
RawPvs rawPvs(const std::vector<uint8_t> &f) {
    RawPvs p;
    const size_t off = size_t(get32(f, 8 + 8 * 16));
    p.n = get32(f, off), p.sz = get32(f, off + 4);
    p.rows.assign(f.begin() + long(off) + 8, f.begin() + long(off) + 8 + long(p.n) * p.sz);
    return p;
}

// OpenArena's aggressor (pak1-maps) names effect 0 on a face although its effects lump is empty; the
// engine loads it (ioquake3 does not check a face's fog number) and visaudit refused it as damaged.
// Effects are not geometry: read as none, and said.
TEST(Bsp, RealMapWithAnEffectItLacksLoads) {
    REQUIRE_OA("pak1-maps.pk3");
    const Scene s = loadReal(kOa + "pak1-maps.pk3:maps/aggressor.bsp");
    EXPECT_GT(s.triangleCount(), 0u);
    bool said = false;
    for (const std::string &w : s.warnings)
        said = said || w.find("faces name an effect (fog volume) outside the 0 effects of the file (the first: face "
                              "1209); read without one") != std::string::npos;
    EXPECT_TRUE(said);
}

TEST(Bsp, RealQ3dm6ishPvsRowDecodedByHand) {
    REQUIRE_OA("pak1-maps.pk3");
    const Scene s = loadReal(kOa + "pak1-maps.pk3:maps/q3dm6ish.bsp");
    ASSERT_TRUE(s.bsp && s.bsp->hasPvs());
    const BspLevel &lv = *s.bsp;
    ASSERT_EQ(lv.clusterCount, 247);
    ASSERT_EQ(lv.pvsRowBytes, 32u);
    // Cluster 10's row, read with a hex dump of the file (visdata at 8 + 10 * 32 bytes into lump 16):
    //   85 0c 10 09 a0 05 00 00 00 00 00 00 00 00 00 00 00 a4 be 17 20 00 18 a0 49 01 00 10 45 02 00 00
    // 0x85 = bits 0, 2, 7 -> clusters 0, 2, 7; 0x0c -> 10, 11; 0x10 -> 20; 0x09 -> 24, 27; ...
    const std::vector<int32_t> row10 = {0,   2,   7,   10,  11,  20,  24,  27,  37,  39,  40,  42,  138,
                                        141, 143, 145, 146, 147, 148, 149, 151, 152, 153, 154, 156, 165,
                                        179, 180, 189, 191, 192, 195, 198, 200, 220, 224, 226, 230, 233};
    std::vector<int32_t> seen;
    for (int32_t y = 0; y < lv.clusterCount; ++y)
        if (lv.clusterVisible(10, y)) seen.push_back(y);
    EXPECT_EQ(seen, row10);
    // Every row, against the test's own decoding of the raw bytes.
    const RawPvs raw = rawPvs(rawMap("pak1-maps.pk3", "maps/q3dm6ish.bsp"));
    ASSERT_EQ(raw.n, lv.clusterCount);
    uint64_t mismatches = 0, visible = 0;
    for (int32_t x = 0; x < raw.n; ++x)
        for (int32_t y = 0; y < raw.n; ++y) {
            mismatches += raw.sees(x, y) != lv.clusterVisible(x, y);
            visible += raw.sees(x, y);
        }
    EXPECT_EQ(mismatches, 0u);
    EXPECT_GT(visible, 0u);
}

TEST(Bsp, RealQ3dm6ish) {
    REQUIRE_OA("pak1-maps.pk3");
    const Scene s = loadReal(kOa + "pak1-maps.pk3:maps/q3dm6ish.bsp");
    // triangles, degenerate, objects, sources, clusters, leafs, faces, polygons, patches, meshes,
    // billboards, sky, nodraw, nonSolid, polygon/patch/mesh triangles, views (10 deathmatch + 1 start)
    expectCounts(s, {2621, 0, 231, 231, 247, 650, 907, 907, 0, 0, 0, 0, 0, 0, 2621, 0, 0, 11});
}

TEST(Bsp, RealOaDm1) {
    REQUIRE_OA("pak1-maps.pk3");
    const Scene s = loadReal(kOa + "pak1-maps.pk3:maps/oa_dm1.bsp");
    // 7 deathmatch + 1 start + 1 intermission views; 30 non-solid (beams, lava); 10 meshes, 10 flares.
    expectCounts(s, {7448, 26, 241, 240, 422, 1123, 902, 852, 0, 10, 10, 0, 0, 30, 4348, 0, 3100, 9});
}

TEST(Bsp, RealOaThor) {
    REQUIRE_OA("pak6-patch088.pk3");
    const Scene s = loadReal(kOa + "pak6-patch088.pk3:maps/oa_thor.bsp");
    // 170 player spawns (58 info_player_start, 2 x 17 team_CTF_*player, 2 x 39 team_CTF_*spawn) and 1
    // intermission; 1292 non-solid faces (light beams), 6 sky faces; patches at level 5. Face 11210
    // (2 triangles, an ordinary texture) is model 5, a trigger_push: not geometry (it was, before
    // issue 15: 43185 triangles, 2297 objects, 9831 polygons).
    expectCounts(s, {43183, 205, 2296, 2268, 2825, 5373, 11211, 9830, 82, 0, 0, 6, 0, 1292, 26783, 16400, 0, 171});
    const BspLevel &lv = *s.bsp;
    EXPECT_EQ(lv.faceCounts.notDrawnEntity, 1u);
    EXPECT_EQ(lv.faceCounts.notDrawnEntityTriangles, 2u);
    EXPECT_EQ(lv.faceCounts.modelFaces, 0u);
    ASSERT_EQ(lv.models.size(), 17u);
    for (size_t k = 1; k < lv.models.size(); ++k) {
        EXPECT_FALSE(lv.models[k].drawn) << k;  // all 16 brush entities are triggers
        EXPECT_EQ(lv.models[k].classname.rfind("trigger_", 0), 0u) << k;
    }
    EXPECT_EQ(lv.models[5].classname, "trigger_push");
    EXPECT_EQ(lv.models[5].firstFace, 11210u);
    EXPECT_EQ(lv.models[5].notDrawnFaces, 1u);
    EXPECT_EQ(s.bsp->pvsRowBytes, 360u);
    EXPECT_EQ(s.bsp->nodes.size(), 5355u);
    // The same map read loose (written out of the archive) gives the same scene.
    const std::vector<uint8_t> bytes = rawMap("pak6-patch088.pk3", "maps/oa_thor.bsp");
    const Scene loose = loadReal(writeFile("oa_thor.bsp", bytes));
    EXPECT_EQ(loose.triangleCount(), s.triangleCount());
    EXPECT_EQ(loose.positions, s.positions);
    EXPECT_EQ(loose.bsp->pvs, s.bsp->pvs);
}

// Brush entities on real maps (issue 15). The leafs a model's box reaches are checked against an
// independent enumeration: a leaf is reached when, on its path from the root, the widened box lies
// (at least partly) on the side of each node's plane that the path takes.
namespace {
std::vector<int32_t> leafsByPaths(const BspLevel &lv, const Aabb &box) {
    std::vector<int32_t> out;
    struct Step {
        int32_t node;
        bool ok;
    };
    std::vector<Step> todo{{0, true}};
    while (!todo.empty()) {
        const Step st = todo.back();
        todo.pop_back();
        if (st.node < 0) {
            if (st.ok) out.push_back(-(st.node + 1));
            continue;
        }
        const BspNode &n = lv.nodes[size_t(st.node)];
        const BspPlane &pl = lv.planes[n.plane];
        // The box's corner farthest along the normal and the one farthest against it.
        Vec3 far, near;
        for (int a = 0; a < 3; ++a) {
            far[a] = pl.normal[a] >= 0 ? box.hi[a] : box.lo[a];
            near[a] = pl.normal[a] >= 0 ? box.lo[a] : box.hi[a];
        }
        todo.push_back({n.children[0], st.ok && dot(pl.normal, far) - pl.dist >= 0});
        todo.push_back({n.children[1], st.ok && dot(pl.normal, near) - pl.dist < 0});
    }
    std::sort(out.begin(), out.end());
    return out;
}
}  // namespace

TEST(Bsp, RealBrushEntityClusters) {
    REQUIRE_OA("pak1-maps.pk3");
    REQUIRE_OA("pak6-patch088.pk3");
    struct Want {
        std::string path;
        uint64_t modelFaces, notDrawn, modelObjects;
    };
    // oa_dm1: 4 func_door + 2 func_button (6 faces each), a trigger_teleport and a trigger_hurt
    // without faces; q3dm6ish: 6 func_illusionary, 3 trigger_push; cbctf1: a func_bobbing placed by
    // its "origin" and 14 trigger_push, 4 trigger_teleport, a trigger_hurt (no faces).
    for (const Want &w : std::vector<Want>{{"pak1-maps.pk3:maps/oa_dm1.bsp", 36, 0, 6},
                                           {"pak1-maps.pk3:maps/q3dm6ish.bsp", 36, 0, 6},
                                           {"pak6-patch088.pk3:maps/cbctf1.bsp", 26, 0, 1}}) {
        const Scene s = loadReal(kOa + w.path);
        const BspLevel &lv = *s.bsp;
        EXPECT_EQ(lv.faceCounts.modelFaces, w.modelFaces) << w.path;
        EXPECT_EQ(lv.faceCounts.notDrawnEntity, w.notDrawn) << w.path;
        uint64_t modelObjects = 0;
        for (size_t src = 0; src < s.sources.size(); ++src) {
            const uint32_t k = lv.sourceModel[src];
            if (k == 0) continue;
            ++modelObjects;
            const BspModel &m = lv.models[k];
            ASSERT_TRUE(m.drawn) << w.path << " model " << k;
            EXPECT_EQ(s.sources[src].name, "model" + std::to_string(k));
            EXPECT_EQ(m.boxLeafs, leafsByPaths(lv, {m.bounds.lo - Vec3{1, 1, 1}, m.bounds.hi + Vec3{1, 1, 1}}))
                << w.path << " model " << k;
            // The object's clusters are its box leafs' (never the model's own leaf's cluster 0).
            std::set<int32_t> want;
            for (int32_t l : m.boxLeafs)
                if (lv.leafs[size_t(l)].cluster >= 0) want.insert(lv.leafs[size_t(l)].cluster);
            const std::set<int32_t> got(lv.sourceClusters.begin() + lv.sourceClustersBegin[src],
                                        lv.sourceClusters.begin() + lv.sourceClustersBegin[src + 1]);
            EXPECT_EQ(got, want) << w.path << " model " << k;
            EXPECT_FALSE(want.empty()) << w.path << " model " << k;
            const int32_t centerLeaf = lv.leafAt(m.bounds.center());
            if (lv.leafs[size_t(centerLeaf)].cluster >= 0)
                EXPECT_TRUE(want.count(lv.leafs[size_t(centerLeaf)].cluster)) << w.path << " model " << k;
        }
        EXPECT_EQ(modelObjects, w.modelObjects) << w.path;
    }
    // cbctf1's func_bobbing (model 19) is stored around 0 and drawn at its "origin".
    const Scene s = loadReal(kOa + "pak6-patch088.pk3:maps/cbctf1.bsp");
    const BspModel &bob = s.bsp->models[19];
    EXPECT_EQ(bob.classname, "func_bobbing");
    EXPECT_EQ(bob.offset, (Vec3{3488, 0, 1749.5}));
    const SourceObject *o = sourceNamed(s, "model19");
    ASSERT_NE(o, nullptr);
    const SceneObject &ob = s.objects[o->firstChunk];
    EXPECT_TRUE(ob.bounds.lo.x >= bob.bounds.lo.x && ob.bounds.hi.x <= bob.bounds.hi.x) << ob.bounds.lo.x;
    EXPECT_GT(ob.bounds.lo.x, 3000);
}

// Trigger volumes drawn with ordinary textures are not geometry (issue 15): pak1's czest2ctf has 42
// such faces (84 triangles) in its trigger_push / trigger_teleport / trigger_hurt / trigger_multiple
// brushes; before, they were objects, and from the spawn points the PVS culled 16,309 of their
// pixels at 160x90 (the report's false culls).
TEST(Bsp, RealTriggerVolumesAreNotGeometry) {
    REQUIRE_OA("pak1-maps.pk3");
    const Scene s = loadReal(kOa + "pak1-maps.pk3:maps/czest2ctf.bsp");
    const BspLevel &lv = *s.bsp;
    EXPECT_EQ(lv.faceCounts.notDrawnEntity, 42u);
    EXPECT_EQ(lv.faceCounts.notDrawnEntityTriangles, 84u);
    EXPECT_EQ(lv.faceCounts.modelFaces, 20u);  // two func_plat, 10 faces each
    uint64_t faces = 0, triggers = 0;
    for (size_t k = 1; k < lv.models.size(); ++k) {
        const BspModel &m = lv.models[k];
        EXPECT_EQ(m.drawn, m.classname.rfind("trigger_", 0) != 0) << k;
        if (!m.drawn) ++triggers, faces += m.notDrawnFaces;
    }
    EXPECT_EQ(triggers, 7u);
    EXPECT_EQ(faces, 42u);
    for (const SourceObject &o : s.sources)
        for (size_t k = 1; k < lv.models.size(); ++k)
            if (!lv.models[k].drawn) EXPECT_NE(o.name, "model" + std::to_string(k));
    // No triangle comes from a trigger's face.
    for (uint32_t f : lv.triangleFace)
        for (size_t k = 1; k < lv.models.size(); ++k)
            if (!lv.models[k].drawn)
                ASSERT_FALSE(f >= lv.models[k].firstFace && f < lv.models[k].firstFace + lv.models[k].faceCount);
}

// The whole pipeline from every spawn point of maps with doors, movers and trigger volumes (issue
// 15), at 160x90: no false cull is left. Before, the brush models' faces sat in cluster 0 and the
// triggers' faces were geometry: q3dm6ish had 16 false-cull pixels, oa_dm1 144, pak1's czest2ctf
// 16,309 -- all of them counted a second time as "genuine" z-buffer/ray-cast disagreements.
TEST(Audit, RealMapsBrushEntitiesLeaveNoFalseCulls) {
    REQUIRE_OA("pak1-maps.pk3");
    for (const char *path : {"pak1-maps.pk3:maps/q3dm6ish.bsp", "pak1-maps.pk3:maps/oa_dm1.bsp",
                             "pak1-maps.pk3:maps/czest2ctf.bsp"}) {
        const Scene s = loadReal(kOa + path);
        PipelineSettings ps;
        ps.width = 160, ps.height = 90;
        ps.ordering = false, ps.zfight = false, ps.detail = false, ps.occlusion = false;
        AnalysisResult out;
        std::string err;
        ASSERT_TRUE(analyzeScene(s, s.views, ps, nullptr, &out, &err)) << err;
        uint64_t falsePixels = 0, cellsCulled = 0, genuine = 0;
        for (const ViewResult &v : out.views) {
            falsePixels += v.audit->cull.falseCullPixels;
            cellsCulled += v.cells.objectsCulled;
            genuine += v.raycast->crossCheck.genuine;
        }
        std::printf("  %s: %zu views, PVS culled %llu objects, false-cull pixels %llu, genuine %llu\n", path,
                    out.views.size(), (unsigned long long)cellsCulled, (unsigned long long)falsePixels,
                    (unsigned long long)genuine);
        EXPECT_GT(cellsCulled, 0u) << path;
        EXPECT_EQ(falsePixels, 0u) << path;
        EXPECT_EQ(genuine, 0u) << path;
    }
}

// Real maps with a designed far plane (issue 15): pak6's czest2ctf ("_farplanedist" "4096") and
// pak1's ctf_compromise ("2048", with a "_foghull"). The spawn views use it as their far plane; with
// the far plane the views had before (the map's diagonal: 25,297 and 7,317 units), the PVS's
// omissions are all beyond it -- hidden by design, not the false culls they were reported as.
TEST(Audit, RealMapsFarPlaneHiddenByDesign) {
    REQUIRE_OA("pak1-maps.pk3");
    REQUIRE_OA("pak6-patch088.pk3");
    struct Want {
        std::string path;
        double farPlane, oldFar;
        uint64_t beyondPixels;
    };
    // At 160x90 from every spawn point: 5 and 6 pixels, all farther than the far plane from the eye.
    for (const Want &w : std::vector<Want>{{"pak6-patch088.pk3:maps/czest2ctf.bsp", 4096, 25297, 5},
                                           {"pak1-maps.pk3:maps/ctf_compromise.bsp", 2048, 7317, 6}}) {
        const Scene s = loadReal(kOa + w.path);
        EXPECT_EQ(s.bsp->farPlane.distance, w.farPlane) << w.path;
        EXPECT_EQ(s.bsp->farPlane.key, "_farplanedist");
        ASSERT_FALSE(s.views.empty());
        uint64_t falseDesign = 0, beyondDesign = 0, falseOld = 0, beyondOld = 0, falseNoPlane = 0;
        double nearestBeyond = 0;
        for (const ViewSpec &v0 : s.views) {
            EXPECT_EQ(v0.camera.farZ, w.farPlane) << w.path << " " << v0.name;
            for (double far : {w.farPlane, w.oldFar}) {
                CameraSpec spec = v0.camera;
                spec.width = 160, spec.height = 90, spec.farZ = far;
                Camera cam;
                std::string err;
                ASSERT_TRUE(makeCamera(spec, &cam, &err)) << err;
                const ReferenceVisibility ref = referenceVisibility(s, cam);
                const CellsResult r = cullCells(s, cam);
                std::vector<uint32_t> culled;
                for (uint32_t o = 0; o < s.objects.size(); ++o)
                    if (!std::binary_search(r.visible.begin(), r.visible.end(), o)) culled.push_back(o);
                StageCulls st{"cells", culled, {}};
                st.designFarPlane = s.bsp->farPlane.distance;
                const CullAudit a = auditCulling(s, ref, {st}, {}, nullptr, &cam);
                (far == w.farPlane ? falseDesign : falseOld) += a.falseCullPixels;
                (far == w.farPlane ? beyondDesign : beyondOld) += a.beyondFarPlanePixels;
                if (a.beyondFarPlanePixels) {
                    EXPECT_GT(a.stages[0].beyondFarPlaneNearest, w.farPlane);
                    if (nearestBeyond == 0 || a.stages[0].beyondFarPlaneNearest < nearestBeyond)
                        nearestBeyond = a.stages[0].beyondFarPlaneNearest;
                }
                if (far == w.oldFar) {
                    st.designFarPlane = 0;  // what the audit said before: every such pixel a false cull
                    falseNoPlane += auditCulling(s, ref, {st}, {}, nullptr, &cam).falseCullPixels;
                }
            }
        }
        std::printf("  %s: far plane %g: false %llu, beyond %llu; far %g: false %llu, beyond %llu (nearest %.1f), "
                    "without the rule %llu false\n",
                    w.path.c_str(), w.farPlane, (unsigned long long)falseDesign, (unsigned long long)beyondDesign,
                    w.oldFar, (unsigned long long)falseOld, (unsigned long long)beyondOld, nearestBeyond,
                    (unsigned long long)falseNoPlane);
        EXPECT_EQ(falseDesign, 0u) << w.path;
        EXPECT_EQ(falseOld, 0u) << w.path;
        EXPECT_EQ(beyondOld, w.beyondPixels) << w.path;
        EXPECT_EQ(falseNoPlane, beyondOld) << w.path;
        // The whole pipeline with the old far plane: the cross-check compares like with like, so the
        // hidden-by-design pixels are "culled", not genuine disagreements (before: 3 and 6 genuine).
        std::vector<ViewSpec> views = s.views;
        for (ViewSpec &v : views) v.camera.farZ = w.oldFar;
        PipelineSettings ps;
        ps.width = 160, ps.height = 90;
        ps.ordering = false, ps.zfight = false, ps.detail = false, ps.occlusion = false;
        AnalysisResult out;
        std::string err;
        ASSERT_TRUE(analyzeScene(s, views, ps, nullptr, &out, &err)) << err;
        uint64_t genuine = 0, culled = 0, beyond = 0, falsePx = 0;
        for (const ViewResult &v : out.views) {
            genuine += v.raycast->crossCheck.genuine, culled += v.raycast->crossCheck.culled;
            beyond += v.audit->cull.beyondFarPlanePixels, falsePx += v.audit->cull.falseCullPixels;
            EXPECT_EQ(v.raycast->crossCheck.recast, v.raycast->crossCheck.culled > 0);
        }
        EXPECT_EQ(genuine, 0u) << w.path;
        EXPECT_EQ(falsePx, 0u) << w.path;
        EXPECT_EQ(beyond, w.beyondPixels) << w.path;
        EXPECT_EQ(culled, w.beyondPixels) << w.path;
    }
    // A map without one keeps the diagonal's far plane.
    const Scene thor = loadReal(kOa + "pak6-patch088.pk3:maps/oa_thor.bsp");
    EXPECT_EQ(thor.bsp->farPlane.distance, 0);
    EXPECT_EQ(thor.views[0].camera.farZ, 6915);
}

// The evidence of the false culls left on a real map, checked against the map's bytes by a reader
// of the test's own: the header's lump table; planes, nodes (the eye's leaf, and which leafs the
// tree reaches), leafs (cluster, leafface range), leaffaces (every leaf listing a face), models (a
// brush model's box leafs) and visdata (every PVS bit). oa_thor has 16 brush entities (all
// triggers); from spawn34 and spawn76 (mirror images of each other) at 320x180 the PVS culls one
// visible pixel each: a face 3,541 units away at the far edge of the floor, in clusters the PVS
// rows of the camera's clusters leave out (docs/quake3.md, "Reading the evidence").
namespace {
struct RawBsp {
    std::vector<uint8_t> f;
    int32_t i32(size_t at) const { return get32(f, at); }
    float f32(size_t at) const {
        const int32_t v = get32(f, at);
        float x;
        std::memcpy(&x, &v, 4);
        return x;
    }
    size_t lump(int l) const { return size_t(get32(f, 8 + 8 * l)); }
    size_t count(int l, size_t rec) const { return size_t(get32(f, 12 + 8 * l)) / rec; }
    int32_t leafCluster(int32_t l) const { return i32(lump(LLeafs) + 48 * size_t(l)); }
    // The eye's leaf: down the tree, front when dot(normal, p) - dist >= 0.
    int32_t leafAt(Vec3 p) const {
        int32_t n = 0;
        while (n >= 0) {
            const size_t node = lump(LNodes) + 36 * size_t(n), pl = lump(LPlanes) + 16 * size_t(i32(node));
            const double d = f32(pl) * p.x + f32(pl + 4) * p.y + f32(pl + 8) * p.z - f32(pl + 12);
            n = i32(node + (d >= 0 ? 4 : 8));
        }
        return -(n + 1);
    }
    std::set<int32_t> treeLeafs() const {
        std::set<int32_t> out;
        std::vector<int32_t> todo{0};
        while (!todo.empty()) {
            const int32_t n = todo.back();
            todo.pop_back();
            if (n < 0) out.insert(-(n + 1));
            else todo.push_back(i32(lump(LNodes) + 36 * size_t(n) + 4)), todo.push_back(i32(lump(LNodes) + 36 * size_t(n) + 8));
        }
        return out;
    }
    std::vector<int32_t> leafsListing(uint32_t face) const {
        std::vector<int32_t> out;
        for (size_t l = 0; l < count(LLeafs, 48); ++l) {
            const size_t r = lump(LLeafs) + 48 * l;
            for (int32_t k = 0; k < i32(r + 36); ++k)
                if (uint32_t(i32(lump(LLeafFaces) + 4 * size_t(i32(r + 32) + k))) == face) out.push_back(int32_t(l));
        }
        return out;
    }
    int bit(int32_t from, int32_t to) const {
        const size_t v = lump(LVisData);
        return (f[v + 8 + size_t(from) * size_t(i32(v + 4)) + size_t(to / 8)] >> (to % 8)) & 1;
    }
};
}  // namespace

TEST(Audit, RealMapEvidenceAgreesWithTheFile) {
    REQUIRE_OA("pak6-patch088.pk3");
    const Scene s = loadReal(kOa + "pak6-patch088.pk3:maps/oa_thor.bsp");
    const RawBsp raw{rawMap("pak6-patch088.pk3", "maps/oa_thor.bsp")};
    const std::set<int32_t> inTree = raw.treeLeafs();
    std::vector<ViewSpec> views;
    for (const ViewSpec &v : s.views)
        if (v.name == "spawn34" || v.name == "spawn76") views.push_back(v);
    ASSERT_EQ(views.size(), 2u);
    PipelineSettings ps;
    ps.width = 320, ps.height = 180;
    ps.ordering = false, ps.zfight = false, ps.detail = false;
    AnalysisResult out;
    std::string err;
    ASSERT_TRUE(analyzeScene(s, views, ps, nullptr, &out, &err)) << err;
    uint64_t faces = 0, leafs = 0, bits = 0, falsePixels = 0;
    for (const ViewResult &r : out.views) {
        const PvsEvidence &e = r.audit->pvsEvidence;
        ASSERT_TRUE(e.ran);
        falsePixels += r.audit->cull.falseCullPixels;
        // The camera: its leaf by the file's tree, its cluster by the file's leafs.
        EXPECT_EQ(e.cameraLeaf, raw.leafAt(r.camera.eye)) << r.spec.name;
        EXPECT_EQ(e.cameraCluster, raw.leafCluster(e.cameraLeaf)) << r.spec.name;
        EXPECT_EQ(e.falseCullPixels, r.audit->cull.falseCullPixels);  // every false cull is the PVS's
        EXPECT_EQ(e.objectsOmitted, 0u);
        ASSERT_FALSE(e.objects.empty()) << r.spec.name;
        for (const PvsObjectEvidence &o : e.objects) {
            // Every cluster of the object: bit 0 in the camera cluster's row, read from the file.
            for (const PvsClusterBit &c : o.clusters) {
                EXPECT_EQ(c.pvsBit, raw.bit(e.cameraCluster, c.cluster));
                EXPECT_EQ(c.pvsBit, 0) << o.name;
                ++bits;
            }
            for (const PvsFaceEvidence &f : o.faces) {
                ++faces;
                // Every leaf listing the face, by the file's leaffaces; its cluster, whether the tree
                // reaches it, its bit.
                const std::vector<int32_t> listing = raw.leafsListing(f.face);
                ASSERT_EQ(f.leafs.size() + f.leafsOmitted, listing.size());
                for (size_t k = 0; k < f.leafs.size(); ++k) {
                    const PvsLeafBit &l = f.leafs[k];
                    EXPECT_EQ(l.leaf, listing[k]);
                    EXPECT_EQ(l.cluster, raw.leafCluster(l.leaf));
                    EXPECT_EQ(l.inTree, inTree.count(l.leaf) > 0);
                    EXPECT_EQ(l.pvsBit, l.cluster < 0 ? -1 : raw.bit(e.cameraCluster, l.cluster));
                    // A leaf of the tree listing the face: its cluster is one of the object's, bit 0.
                    if (l.inTree && l.cluster >= 0) {
                        EXPECT_EQ(l.pvsBit, 0) << o.name << " face " << f.face;
                        bool listed = false;
                        for (const PvsClusterBit &c : o.clusters) listed |= c.cluster == l.cluster;
                        EXPECT_TRUE(listed) << o.name << " face " << f.face << " leaf " << l.leaf;
                    }
                    ++leafs;
                }
                // The face is seen at its pixel, culled falsely, no farther than the map allows.
                const size_t i = size_t(f.y) * size_t(r.camera.width) + size_t(f.x);
                ASSERT_GT(r.audit->reference.id[i], 0u);
                EXPECT_EQ(s.bsp->triangleFace[r.audit->reference.id[i] - 1], f.face);
                EXPECT_EQ(r.audit->cull.fate[i], kFateCulledFirst);
                EXPECT_EQ(pixelPointDistance(r.camera, i, r.audit->reference.depth[i]), f.nearest);
            }
        }
        std::printf("  %s: camera leaf %d cluster %d; %zu object(s), first %s face %u at %.1f units\n",
                    r.spec.name.c_str(), e.cameraLeaf, e.cameraCluster, e.objects.size(), e.objects[0].name.c_str(),
                    e.objects[0].faces.empty() ? 0u : e.objects[0].faces[0].face, e.objects[0].nearest);
    }
    EXPECT_EQ(falsePixels, 2u);
    EXPECT_EQ(faces, 2u);
    EXPECT_GE(leafs, 3u);
    EXPECT_GE(bits, 6u);
}

// Quake 3's winding, checked against the map's own normals: each polygon face stores its plane's
// normal; the triangles as the file stores them, reversed, must face the same way (their normal's
// dot product with it positive). The scene must then hold exactly those reversed triangles.
TEST(Bsp, RealWindingAgreesWithStoredNormals) {
    REQUIRE_OA("pak6-patch088.pk3");
    const std::vector<uint8_t> f = rawMap("pak6-patch088.pk3", "maps/oa_thor.bsp");
    const size_t faces = lumpOffset(f, LFaces), verts = lumpOffset(f, LVertexes), mv = lumpOffset(f, LMeshVerts);
    const size_t nFaces = size_t(get32(f, 12 + 8 * LFaces)) / 104;
    auto fl = [&](size_t at) {
        float x;
        int32_t i = get32(f, at);
        std::memcpy(&x, &i, 4);
        return double(x);
    };
    auto pos = [&](int32_t v) { return Vec3{fl(verts + 44 * size_t(v)), fl(verts + 44 * size_t(v) + 4), fl(verts + 44 * size_t(v) + 8)}; };
    auto nrm = [&](int32_t v) { return Vec3{fl(verts + 44 * size_t(v) + 28), fl(verts + 44 * size_t(v) + 32), fl(verts + 44 * size_t(v) + 36)}; };
    // Rotation-normalized triangle keys of the scene's triangles.
    const Scene s = loadReal(kOa + "pak6-patch088.pk3:maps/oa_thor.bsp");
    auto key = [](Vec3 a, Vec3 b, Vec3 c) {
        std::array<std::array<double, 3>, 3> k = {{{a.x, a.y, a.z}, {b.x, b.y, b.z}, {c.x, c.y, c.z}}};
        while (!(k[0] <= k[1] && k[0] <= k[2])) std::rotate(k.begin(), k.begin() + 1, k.end());
        return k;
    };
    std::multiset<std::array<std::array<double, 3>, 3>> scene;
    for (uint32_t t = 0; t < s.triangleCount(); ++t)
        if (s.triangleObject[t] != kExcludedTriangle) {
            const uint32_t *ix = &s.indices[3 * t];
            scene.insert(key(s.positions[ix[0]], s.positions[ix[1]], s.positions[ix[2]]));
        }
    uint64_t agree = 0, disagree = 0, found = 0, polygonTris = 0, drawnTris = 0, patchAgree = 0, patchDisagree = 0;
    double worstSliver = 0;  // |cross| / longest edge^2 of the disagreeing triangles (0.43 for equilateral)
    for (size_t i = 0; i < nFaces; ++i) {
        const size_t r = faces + 104 * i;
        const int32_t type = get32(f, r + 8), v0 = get32(f, r + 12), m0 = get32(f, r + 20), nm = get32(f, r + 24);
        if (type == 2) {
            // Patches: the surface's du x dv at each 3x3 block's center (the orientation the loader's
            // reversed grid triangles have) against the control points' stored normals.
            const int32_t w = get32(f, r + 96), h = get32(f, r + 100);
            for (int32_t py = 0; py + 2 < h; py += 2)
                for (int32_t px = 0; px + 2 < w; px += 2) {
                    auto P = [&](int i2, int j2) { return pos(v0 + (py + i2) * w + px + j2); };
                    const Vec3 du = (P(1, 2) - P(1, 0)), dv = (P(2, 1) - P(0, 1));
                    Vec3 n{0, 0, 0};
                    for (int a = 0; a < 3; ++a)
                        for (int b = 0; b < 3; ++b) n = n + nrm(v0 + (py + a) * w + px + b);
                    const double d = dot(cross(du, dv), n);
                    if (d > 0) ++patchAgree;
                    else if (d < 0) ++patchDisagree;
                }
            continue;
        }
        if (type != 1) continue;
        // Drawn, by docs/quake3.md's rule: not sky, nodraw/hint/skip, area portal, liquid, fog or non-solid
        // translucent; and a world face (model 0's range): oa_thor's 16 brush entities are all triggers.
        const size_t sh = lumpOffset(f, LShaders) + 72 * size_t(get32(f, r));
        const uint32_t flags = uint32_t(get32(f, sh + 64)), contents = uint32_t(get32(f, sh + 68));
        const size_t model0 = lumpOffset(f, LModels);
        const bool world = int32_t(i) >= get32(f, model0 + 24) && int32_t(i) < get32(f, model0 + 24) + get32(f, model0 + 28);
        const bool drawn = world && !(flags & 0x384) && !(contents & 0x8078) &&
                           !((flags & 0x4000) && (contents & 0x20000000));
        const Vec3 faceNormal{fl(r + 84), fl(r + 88), fl(r + 92)};
        for (int32_t k = 0; k < nm; k += 3) {
            const Vec3 a = pos(v0 + get32(f, mv + 4 * size_t(m0 + k))), b = pos(v0 + get32(f, mv + 4 * size_t(m0 + k + 1))),
                       c = pos(v0 + get32(f, mv + 4 * size_t(m0 + k + 2)));
            const Vec3 n = cross(c - a, b - a);  // reversed: a, c, b
            const double d = dot(n, faceNormal);
            if (d > 0) ++agree;
            if (d < 0) {
                // The few that disagree are slivers (q3map's triangulations leave near-collinear
                // triangles whose float corners flip them): area tiny next to the longest edge.
                ++disagree;
                const double e = std::max({dot(b - a, b - a), dot(c - a, c - a), dot(c - b, c - b)});
                worstSliver = std::max(worstSliver, length(n) / e);
            }
            ++polygonTris;
            if (drawn && !(n == Vec3{0, 0, 0})) {
                ++drawnTris;
                found += scene.count(key(a, c, b)) > 0;
            }
        }
    }
    std::printf("  polygon triangles %llu: reversed winding agrees with the face normal %llu, disagrees %llu "
                "(worst sliver %.3g); drawn %llu, found reversed in the scene %llu; patch blocks agree %llu, "
                "disagree %llu\n",
                (unsigned long long)polygonTris, (unsigned long long)agree, (unsigned long long)disagree, worstSliver,
                (unsigned long long)drawnTris, (unsigned long long)found, (unsigned long long)patchAgree,
                (unsigned long long)patchDisagree);
    EXPECT_EQ(polygonTris, 29519u);
    EXPECT_EQ(agree, 29189u);
    EXPECT_EQ(disagree, 126u);
    EXPECT_LT(worstSliver, 0.01);
    EXPECT_EQ(patchAgree, 360u);
    EXPECT_EQ(patchDisagree, 0u);
    // Every drawn, non-degenerate polygon triangle is in the scene, reversed.
    EXPECT_EQ(found, drawnTris);
    EXPECT_GT(drawnTris, 26000u);
}

// The cells stage on a real map: from every spawn point the camera is inside a cluster, some
// objects are culled, and no object visible from the camera's cluster is culled.
TEST(Cells, RealQ3dm6ishFromSpawnPoints) {
    REQUIRE_OA("pak1-maps.pk3");
    const Scene s = loadReal(kOa + "pak1-maps.pk3:maps/q3dm6ish.bsp");
    ASSERT_EQ(cellsSkipReason(s), nullptr);
    const BspLevel &lv = *s.bsp;
    ASSERT_GT(s.views.size(), 0u);
    for (const ViewSpec &v : s.views) {
        Camera cam;
        std::string err;
        ASSERT_TRUE(makeCamera(v.camera, &cam, &err)) << err;
        const CellsResult r = cullCells(s, cam);
        EXPECT_FALSE(r.stats.cameraInVoid) << v.name;
        EXPECT_GT(r.stats.objectsCulled, 0u) << v.name;
        EXPECT_LT(r.stats.clustersVisible, r.stats.clustersTotal) << v.name;
        EXPECT_EQ(r.visible.size() + r.stats.objectsCulled, s.objects.size());
        // Independent check: an object is kept iff one of its clusters is visible (or it has none).
        std::set<uint32_t> kept(r.visible.begin(), r.visible.end());
        for (uint32_t o = 0; o < s.objects.size(); ++o) {
            const uint32_t src = s.objects[o].source;
            bool want = lv.sourceClustersBegin[src] == lv.sourceClustersBegin[src + 1];
            for (uint32_t k = lv.sourceClustersBegin[src]; k < lv.sourceClustersBegin[src + 1]; ++k)
                want |= lv.clusterVisible(r.stats.cameraCluster, lv.sourceClusters[k]);
            ASSERT_EQ(kept.count(o) > 0, want) << v.name << " object " << s.objects[o].name;
        }
    }
    // Far outside the map: the void; nothing culled.
    Camera cam;
    std::string err;
    ASSERT_TRUE(makeCamera(quakeCamera(s, s.bounds.hi + Vec3{1000, 1000, 1000}, 0), &cam, &err)) << err;
    const CellsResult r = cullCells(s, cam);
    EXPECT_TRUE(r.stats.cameraInVoid);
    EXPECT_EQ(r.stats.objectsCulled, 0u);
    EXPECT_EQ(r.visible.size(), s.objects.size());
}

TEST(LevelViews, RealWalkViewsInsideClusters) {
    REQUIRE_OA("pak6-patch088.pk3");
    const Scene s = loadReal(kOa + "pak6-patch088.pk3:maps/oa_thor.bsp");
    const std::vector<ViewSpec> v = walkViews(s, 32, 5);
    ASSERT_EQ(v.size(), 32u);
    for (const ViewSpec &w : v) {
        const int32_t leaf = s.bsp->leafAt(w.camera.eye);
        ASSERT_GE(leaf, 0);
        EXPECT_GE(s.bsp->leafs[size_t(leaf)].cluster, 0) << w.name;
    }
    const std::vector<ViewSpec> again = walkViews(s, 32, 5);
    for (size_t i = 0; i < v.size(); ++i) EXPECT_EQ(v[i].camera.eye, again[i].camera.eye);
}

// Exact cells numbers from the first spawn point of each real map (docs/quake3.md quotes them).
TEST(Cells, RealMapsFirstSpawnExactCounts) {
    REQUIRE_OA("pak6-patch088.pk3");
    REQUIRE_OA("pak1-maps.pk3");
    struct Want {
        std::string path;
        int32_t leaf, cluster;
        uint64_t clustersVisible, clustersTotal, objectsCulled, objectsIn, trianglesCulled, trianglesIn;
    };
    for (const Want &w : std::vector<Want>{
             // Before issue 15 the brush models took cluster 0 from their own leafs: q3dm6ish culled
             // 53 objects / 404 triangles, oa_dm1 151 / 3215 (three doors and buttons falsely).
             {"pak1-maps.pk3:maps/q3dm6ish.bsp", 238, 97, 176, 247, 55, 231, 428, 2621},
             {"pak1-maps.pk3:maps/oa_dm1.bsp", 327, 120, 90, 422, 148, 241, 3179, 7422},
             {"pak6-patch088.pk3:maps/oa_thor.bsp", 4828, 2539, 1191, 2825, 1166, 2296, 18980, 42978}}) {
        const Scene s = loadReal(kOa + w.path);
        ASSERT_GT(s.views.size(), 0u);
        Camera cam;
        std::string err;
        ASSERT_TRUE(makeCamera(s.views[0].camera, &cam, &err)) << err;
        const CellsResult r = cullCells(s, cam);
        const CellsStats &c = r.stats;
        std::printf("  %s %s: leaf %d cluster %d, clusters %llu / %llu, objects culled %llu / %llu, triangles culled "
                    "%llu / %llu\n", w.path.c_str(), s.views[0].name.c_str(), c.cameraLeaf, c.cameraCluster,
                    (unsigned long long)c.clustersVisible, (unsigned long long)c.clustersTotal,
                    (unsigned long long)c.objectsCulled, (unsigned long long)c.objectsIn,
                    (unsigned long long)c.trianglesCulled, (unsigned long long)c.trianglesIn);
        EXPECT_EQ(c.cameraLeaf, w.leaf) << w.path;
        EXPECT_EQ(c.cameraCluster, w.cluster) << w.path;
        EXPECT_EQ(c.clustersVisible, w.clustersVisible) << w.path;
        EXPECT_EQ(c.clustersTotal, w.clustersTotal) << w.path;
        EXPECT_EQ(c.objectsCulled, w.objectsCulled) << w.path;
        EXPECT_EQ(c.objectsIn, w.objectsIn) << w.path;
        EXPECT_EQ(c.trianglesCulled, w.trianglesCulled) << w.path;
        EXPECT_EQ(c.trianglesIn, w.trianglesIn) << w.path;
    }
}


// A 1-pixel sliver of oa_thor seen from spawn120 is back-facing by the exact plane test, so the
// backface stage culls it, but its corners snapped to the 1/256-pixel grid wind to the front, so
// the reference shows it. The audit counts it as a snapped sliver, not a false cull (docs/audits.md,
// "Snapped slivers"); without the stage's byFacing flag it is the false cull it used to be.
TEST(Audit, RealMapSnappedSliverIsNotAFalseCull) {
    REQUIRE_OA("pak6-patch088.pk3");
    const Scene s = loadReal(kOa + "pak6-patch088.pk3:maps/oa_thor.bsp");
    const std::vector<ViewSpec> views = spawnViews(s);
    ASSERT_GT(views.size(), 120u);
    Camera cam;
    std::string err;
    ASSERT_TRUE(makeCamera(views[120].camera, &cam, &err)) << err;
    const ReferenceVisibility ref = referenceVisibility(s, cam);
    EXPECT_GE(ref.snappedFrontTriangles, 1u);
    std::vector<uint32_t> objects(s.objects.size());
    for (uint32_t i = 0; i < objects.size(); ++i) objects[i] = i;
    const BackfaceResult b = cullBackfaces(s, objects, cam);
    for (bool byFacing : {true, false}) {
        const CullAudit a = auditCulling(s, ref, {{"backface", {}, b.culled, byFacing}}, b.kept.triangles, nullptr);
        ASSERT_EQ(a.stages.size(), 1u);
        const StageCullAudit &st = a.stages[0];
        EXPECT_EQ(st.falseCullTriangles, byFacing ? 0u : 1u);
        EXPECT_EQ(st.falseCullPixels, byFacing ? 0u : 1u);
        EXPECT_EQ(st.snappedTriangles, byFacing ? 1u : 0u);
        EXPECT_EQ(st.snappedPixels, byFacing ? 1u : 0u);
        uint64_t snappedFate = 0, culledFate = 0;
        for (uint8_t f : a.fate) snappedFate += f == kFateSnapped, culledFate += f == kFateCulledFirst;
        EXPECT_EQ(snappedFate, byFacing ? 1u : 0u);
        EXPECT_EQ(culledFate, byFacing ? 0u : 1u);
    }
}

