// glTF 2.0 as today's exporters and optimizers write it, and what is refused (docs/scene-format.md,
// "glTF 2.0"; issue 16). Small files are written by each test into its own folder with the exact
// counts, positions and flags they must give; Draco and meshopt data in them is encoded by Debian's
// libdraco and libmeshoptimizer, the libraries the loader decodes with. The dungeon's Draco, meshopt
// and quantized variants come from real optimizers (scripts/make-gltf-variants.sh: gltfpack,
// gltf-transform) and must give the original's triangles within the quantization's error.
#include <gtest/gtest.h>

#include <draco/compression/encode.h>
#include <draco/mesh/triangle_soup_mesh_builder.h>
#include <meshoptimizer.h>
#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <tuple>

#include "analysis/load/load.h"
#include "tests/run_binary.h"
#include "tests/temp_dir_test.h"

namespace va {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;
using testing_util::runBinary;

// A glTF document and its one buffer, built up by the tests.
struct GltfFile {
    Json doc = {{"asset", {{"version", "2.0"}}}};
    std::string bin;  // buffer 0

    // A buffer view over `n` new bytes of buffer 0 (4-byte aligned, as vertex data must be).
    int view(const void *p, size_t n, size_t stride = 0) {
        while (bin.size() % 4 != 0) bin.push_back('\0');
        Json v = {{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", n}};
        if (stride) v["byteStride"] = stride;
        bin.append(static_cast<const char *>(p), n);
        doc["bufferViews"].push_back(v);
        return int(doc["bufferViews"].size()) - 1;
    }
    int accessor(Json a) {
        doc["accessors"].push_back(std::move(a));
        return int(doc["accessors"].size()) - 1;
    }
    int positions(const std::vector<float> &xyz) {
        const int v = view(xyz.data(), xyz.size() * 4);
        return accessor({{"bufferView", v}, {"componentType", 5126}, {"count", xyz.size() / 3}, {"type", "VEC3"}});
    }
    int indices(const std::vector<uint16_t> &ix) {
        const int v = view(ix.data(), ix.size() * 2);
        return accessor({{"bufferView", v}, {"componentType", 5123}, {"count", ix.size()}, {"type", "SCALAR"}});
    }
    int mesh(Json primitives) {
        doc["meshes"].push_back({{"primitives", std::move(primitives)}});
        return int(doc["meshes"].size()) - 1;
    }
    // One triangle (0,0,0) (1,0,0) (0,1,0), counter-clockwise seen from +z.
    int triangleMesh() {
        const int p = positions({0, 0, 0, 1, 0, 0, 0, 1, 0});
        return mesh(Json::array({{{"attributes", {{"POSITION", p}}}}}));
    }
    int node(Json n) {
        doc["nodes"].push_back(std::move(n));
        return int(doc["nodes"].size()) - 1;
    }
    void scene(Json roots) {
        doc["scenes"] = Json::array({{{"nodes", std::move(roots)}}});
        doc["scene"] = 0;
    }
    void require(const std::string &ext) {
        doc["extensionsUsed"].push_back(ext);
        doc["extensionsRequired"].push_back(ext);
    }
    // NAME.gltf with its buffer in NAME.bin beside it; returns the .gltf's path.
    std::string write(const fs::path &dir, const std::string &name) {
        if (!bin.empty()) {
            doc["buffers"][0] = {{"byteLength", bin.size()}, {"uri", name + ".bin"}};
            std::ofstream(dir / (name + ".bin"), std::ios::binary) << bin;
        }
        std::ofstream(dir / (name + ".gltf"), std::ios::binary) << doc.dump();
        return (dir / (name + ".gltf")).string();
    }
    // NAME.glb: buffer 0 is its BIN chunk; `version` is the container's version field.
    std::string writeGlb(const fs::path &dir, const std::string &name, uint32_t version = 2) {
        if (!bin.empty()) doc["buffers"][0] = {{"byteLength", bin.size()}};
        std::string json = doc.dump();
        while (json.size() % 4 != 0) json.push_back(' ');
        std::string b = bin;
        while (b.size() % 4 != 0) b.push_back('\0');
        std::string out;
        auto u32 = [&](uint32_t x) { out.append(reinterpret_cast<const char *>(&x), 4); };
        out += "glTF";
        u32(version);
        u32(uint32_t(12 + 8 + json.size() + (b.empty() ? 0 : 8 + b.size())));
        u32(uint32_t(json.size()));
        out += "JSON";
        out += json;
        if (!b.empty()) {
            u32(uint32_t(b.size()));
            out += std::string("BIN\0", 4);
            out += b;
        }
        std::ofstream(dir / (name + ".glb"), std::ios::binary) << out;
        return (dir / (name + ".glb")).string();
    }
};

class GltfTest : public testing_util::TempDirTest {
  protected:
    GltfTest() : TempDirTest("gltf") {}

    SceneBuildInput load(const std::string &path, uint64_t maxTriangles = kDefaultMaxTriangles) {
        SceneBuildInput in;
        std::string err;
        EXPECT_TRUE(loadGltf(path, &in, &err, maxTriangles)) << err;
        return in;
    }
    std::string refusal(const std::string &path, uint64_t maxTriangles = kDefaultMaxTriangles) {
        SceneBuildInput in;
        std::string err;
        EXPECT_FALSE(loadGltf(path, &in, &err, maxTriangles)) << path << " loaded";
        return err;
    }
};

using Tri = std::array<Vec3, 3>;
std::vector<Tri> trianglesOf(const RawMesh &m) {
    std::vector<Tri> t;
    for (size_t i = 0; i + 2 < m.indices.size(); i += 3)
        t.push_back({m.positions[m.indices[i]], m.positions[m.indices[i + 1]], m.positions[m.indices[i + 2]]});
    return t;
}
// The same triangle with the same winding: equal up to a rotation of its corners (index codecs may
// start a triangle at another corner).
bool sameTriangle(const Tri &a, const Tri &b) {
    for (int r = 0; r < 3; ++r)
        if (a[0] == b[size_t(r)] && a[1] == b[size_t((r + 1) % 3)] && a[2] == b[size_t((r + 2) % 3)]) return true;
    return false;
}
bool containsTriangle(const std::vector<Tri> &ts, const Tri &t) {
    for (const Tri &u : ts)
        if (sameTriangle(u, t)) return true;
    return false;
}

// ---- The node hierarchy ---------------------------------------------------------------------------

// Issue 16: a legal chain a few hundred thousand nodes deep crashed the recursive walk (exit 139 at
// 30000 levels already, the 8 MiB stack). 200000 nodes, each the only child of the one before and
// translated by (1, 0, 0); the last holds one triangle.
TEST_F(GltfTest, DeepNodeChainLoads) {
    constexpr int kDepth = 200000;
    GltfFile g;
    const int mesh = g.triangleMesh();
    Json nodes = Json::array();
    for (int i = 0; i + 1 < kDepth; ++i) nodes.push_back({{"children", {i + 1}}, {"translation", {1, 0, 0}}});
    nodes.push_back({{"mesh", mesh}, {"name", "leaf"}});
    g.doc["nodes"] = std::move(nodes);
    g.scene({0});
    const SceneBuildInput in = load(g.write(dir_, "chain"));
    ASSERT_EQ(in.objects.size(), 1u);
    EXPECT_EQ(in.objects[0].name, "leaf");
    // 199999 translations by exactly 1: integer sums, exact in double.
    const auto &p = in.objects[0].geometry.positions;
    EXPECT_EQ(p[0], (Vec3{kDepth - 1, 0, 0}));
    EXPECT_EQ(p[1], (Vec3{kDepth, 0, 0}));
    EXPECT_EQ(p[2], (Vec3{kDepth - 1, 1, 0}));
}

TEST_F(GltfTest, CyclesAndSecondParentsAreRefused) {
    GltfFile g;
    const int mesh = g.triangleMesh();
    g.doc["nodes"] = {{{"children", {1}}}, {{"children", {0}}, {"mesh", mesh}}};
    g.scene({0});
    std::string path = g.write(dir_, "cycle");
    EXPECT_EQ(refusal(path), path + ": node 'node0' is its own ancestor (a cycle in the node hierarchy)");

    // Two parents: glTF forbids it, and it would let a small file name exponentially many paths (a
    // chain of 64 nodes each listing the next twice has 2^64 of them; the recursive walk never ended).
    Json nodes = Json::array();
    for (int i = 0; i < 64; ++i) nodes.push_back({{"children", {i + 1, i + 1}}});
    nodes.push_back({{"mesh", mesh}});
    g.doc["nodes"] = nodes;
    path = g.write(dir_, "diamond");
    EXPECT_EQ(refusal(path), path + ": node 'node64' is reached a second time (as a child of node 'node63'); glTF 2.0 "
                                    "gives a node at most one parent and lists a scene's roots once");
    g.doc["nodes"] = {{{"mesh", mesh}}};
    g.scene({0, 0});
    path = g.write(dir_, "tworoots");
    EXPECT_EQ(refusal(path), path + ": node 'node0' is reached a second time (as a root of the scene); glTF 2.0 "
                                    "gives a node at most one parent and lists a scene's roots once");
}

// Scenes: the file's `scene` is loaded and a warning names what was left out; without one, scene 0.
TEST_F(GltfTest, DefaultSceneAndTheOthers) {
    GltfFile g;
    const int mesh = g.triangleMesh();
    g.doc["nodes"] = {{{"mesh", mesh}, {"name", "a"}}, {{"mesh", mesh}, {"name", "b"}}, {{"mesh", mesh}, {"name", "c"}}};
    g.doc["scenes"] = {{{"name", "day"}, {"nodes", {0}}}, {{"name", "night"}, {"nodes", {1, 2}}}, {{"nodes", {2}}}};
    g.doc["scene"] = 1;
    std::string path = g.write(dir_, "scenes");
    SceneBuildInput in = load(path);
    ASSERT_EQ(in.objects.size(), 2u);
    EXPECT_EQ(in.objects[0].name, "b");
    EXPECT_EQ(in.objects[1].name, "c");
    ASSERT_EQ(in.warnings.size(), 1u);
    EXPECT_EQ(in.warnings[0], path + ": loaded scene 1 'night' (the file's \"scene\") of 3; left out 2 other scene(s): "
                                     "0 'day', 2");

    g.doc.erase("scene");
    path = g.write(dir_, "noscene");
    in = load(path);
    ASSERT_EQ(in.objects.size(), 1u);
    EXPECT_EQ(in.objects[0].name, "a");
    ASSERT_EQ(in.warnings.size(), 1u);
    EXPECT_EQ(in.warnings[0], path + ": loaded scene 0 'day' (the file names no default \"scene\") of 3; left out 2 "
                                     "other scene(s): 1 'night', 2");

    g.doc["scene"] = 7;
    path = g.write(dir_, "badscene");
    EXPECT_EQ(refusal(path), path + ": \"scene\" is 7, but the file has 3 scene(s) (0..2); the file is damaged");
}

// ---- JSON nesting ---------------------------------------------------------------------------------

// glTF whose extras nest `levels` deep in all (the top-level object is level 1).
std::string nestedGltf(int levels) {
    return "{\"asset\":{\"version\":\"2.0\"},\"extras\":" + std::string(size_t(levels - 1), '[') +
           std::string(size_t(levels - 1), ']') + "}";
}

// Issue 16: tinygltf converts extras and extensions recursively; a few hundred thousand levels
// overflowed the stack (exit 139). The limit (--max-json-depth, default 512, at most 2048) is checked
// on the text before anything parses it.
TEST_F(GltfTest, JsonNestingLimit) {
    const std::string prefix = "{\"asset\":{\"version\":\"2.0\"},\"extras\":";
    auto write = [&](const std::string &name, const std::string &text) {
        std::ofstream(dir_ / name, std::ios::binary) << text;
        return (dir_ / name).string();
    };
    SceneBuildInput in;
    std::string err;
    const std::string at = write("at.gltf", nestedGltf(512));
    EXPECT_TRUE(loadGltf(at, &in, &err)) << err;
    const std::string over = write("over.gltf", nestedGltf(513));
    // The 512th '[' opens level 513.
    EXPECT_EQ(refusal(over), over + ":1:" + std::to_string(prefix.size() + 512) +
                                 ": arrays and objects nested 513 levels deep, more than the limit of 512; raise it "
                                 "with --max-json-depth 513 if the file is meant to nest so deep");
    EXPECT_TRUE(loadGltf(over, &in, &err, kDefaultMaxTriangles, 513)) << err;

    // The issue's file, through the program: exit 2, not 139.
    const std::string deep = write("deep.gltf", nestedGltf(300000));
    auto r = runBinary({"info", deep}, dir_);
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.err, "visaudit: error: " + deep + ":1:" + std::to_string(prefix.size() + 512) +
                         ": arrays and objects nested 300000 levels deep, more than the limit of 512; "
                         "--max-json-depth accepts at most 2048 (no scene, views, glTF, budget or report file nests "
                         "so deep): the file is damaged or was made to exhaust a parser's stack\n");
    r = runBinary({"info", over, "--max-json-depth", "513"}, dir_);
    EXPECT_EQ(r.code, 0) << r.err;

    // In a GLB the place is in its JSON chunk.
    GltfFile g;
    g.doc["extras"] = Json::array();
    Json *e = &g.doc["extras"];
    for (int i = 0; i < 600; ++i) {
        e->push_back(Json::array());
        e = &(*e)[0];
    }
    const std::string glb = g.writeGlb(dir_, "deep");
    const std::string err2 = refusal(glb);
    EXPECT_EQ(err2.rfind(glb + " (JSON chunk):1:", 0), 0u) << err2;
    EXPECT_NE(err2.find(": arrays and objects nested 602 levels deep, more than the limit of 512"), std::string::npos)
        << err2;
}

// ---- Indices, versions, extensions --------------------------------------------------------------

// Issue 16: an index past the vertices dropped the triangle and loaded an empty scene (exit 0); it
// is refused naming the mesh, the primitive, the accessor and the index, as OBJ and PLY indices are.
TEST_F(GltfTest, OutOfRangeIndexIsRefused) {
    GltfFile g;
    const int p = g.positions({0, 0, 0, 1, 0, 0, 0, 1, 0});
    const int ix = g.indices({0, 1, 2, 0, 2, 5});
    g.mesh(Json::array({{{"attributes", {{"POSITION", p}}}, {"indices", ix}}}));
    g.doc["nodes"] = {{{"mesh", 0}, {"name", "floor"}}};
    g.scene({0});
    const std::string path = g.write(dir_, "badindex");
    const std::string msg = path + ": mesh 0 primitive 0 (node 'floor'): indices accessor 1: index 5 (element 5) is out "
                                   "of range: POSITION accessor 0 has 3 vertices; the file is damaged";
    EXPECT_EQ(refusal(path), msg);
    const auto r = runBinary({"info", path}, dir_);
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.err, "visaudit: error: " + msg + "\n");
}

// Issue 16: glTF 1.0 loaded as an empty scene (exit 0). It is refused naming the version and a
// converter; so are 1.0 without "asset", a version-1 GLB, and versions a 2.0 loader may not read.
TEST_F(GltfTest, VersionsOtherThan2AreRefused) {
    const std::string convert =
        "visaudit reads glTF 2.0: convert the file first, e.g. with gltf-pipeline (npm: 'npx gltf-pipeline -i in.gltf "
        "-o out.gltf' upgrades glTF 1.0 to 2.0), or export it again as glTF 2.0";
    auto write = [&](const std::string &name, const std::string &text) {
        std::ofstream(dir_ / name, std::ios::binary) << text;
        return (dir_ / name).string();
    };
    std::string path = write("v1.gltf", R"({"asset": {"version": "1.0"}, "scene": "s", "scenes": {"s": {"nodes": []}}})");
    EXPECT_EQ(refusal(path), path + ": glTF 1.0 (asset.version \"1.0\") is not supported; " + convert);
    auto r = runBinary({"info", path}, dir_);
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.err, "visaudit: error: " + path + ": glTF 1.0 (asset.version \"1.0\") is not supported; " + convert + "\n");

    path = write("noasset.gltf", R"({"meshes": {"box": {"primitives": []}}})");
    EXPECT_EQ(refusal(path), path + ": this is glTF 1.0 (its \"meshes\" is an object keyed by id; glTF 2.0 has arrays "
                                    "and an \"asset\" with \"version\": \"2.0\"); " + convert);
    GltfFile g;
    path = g.writeGlb(dir_, "v1", 1);
    EXPECT_EQ(refusal(path), path + ": binary glTF version 1 (glTF 1.0 with KHR_binary_glTF) is not supported; " + convert);
    path = write("v3.gltf", R"({"asset": {"version": "3.0"}})");
    EXPECT_EQ(refusal(path), path + ": glTF 3.0 (asset.version \"3.0\") is newer than glTF 2.0, the version visaudit "
                                    "reads; export the file as glTF 2.0");
    path = write("min21.gltf", R"({"asset": {"version": "2.1", "minVersion": "2.1"}})");
    EXPECT_EQ(refusal(path), path + ": the file needs a glTF 2.1 loader (asset.minVersion \"2.1\"); visaudit reads "
                                    "glTF 2.0; export the file for glTF 2.0");
    // 2.1 without minVersion: a 2.0 loader reads it (glTF 2.0, "Versioning").
    g.doc["asset"]["version"] = "2.1";
    g.doc["nodes"] = {{{"mesh", g.triangleMesh()}}};
    g.scene({0});
    EXPECT_EQ(load(g.write(dir_, "v21")).objects.size(), 1u);
}

TEST_F(GltfTest, RequiredExtensions) {
    GltfFile g;
    g.doc["nodes"] = {{{"mesh", g.triangleMesh()}}};
    g.scene({0});
    // Appearance only: analysed as it is.
    g.require("KHR_texture_transform");
    g.require("KHR_materials_unlit");
    EXPECT_EQ(load(g.write(dir_, "appearance")).objects.size(), 1u);
    // Anything else is refused by name.
    g.require("MSFT_lod");
    const std::string path = g.write(dir_, "lod");
    EXPECT_EQ(refusal(path),
              path + ": the file requires the glTF extension 'MSFT_lod' (extensionsRequired), which visaudit cannot "
                     "honour; it may change the geometry, so the file is refused rather than analysed without it. "
                     "visaudit honours EXT_mesh_gpu_instancing, EXT_meshopt_compression, KHR_draco_mesh_compression, "
                     "KHR_lights_punctual, KHR_materials_ior, KHR_materials_transmission, KHR_mesh_quantization and "
                     "ignores extensions that change only textures and shading; export the file without 'MSFT_lod'");
}

// ---- Accessors: sparse, quantized --------------------------------------------------------------------

TEST_F(GltfTest, SparseAccessors) {
    GltfFile g;
    // A square (0,0,0) (1,0,0) (1,1,0) (0,1,0) whose vertices 1 and 3 are replaced by (5,0,0), (0,5,0).
    const std::vector<float> base = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    const std::vector<uint8_t> sparseIdx = {1, 3};
    const std::vector<float> sparseVal = {5, 0, 0, 0, 5, 0};
    const int bv = g.view(base.data(), base.size() * 4);
    const int iv = g.view(sparseIdx.data(), sparseIdx.size());
    const int vv = g.view(sparseVal.data(), sparseVal.size() * 4);
    Json sparse = {{"count", 2},
                   {"indices", {{"bufferView", iv}, {"componentType", 5121}}},
                   {"values", {{"bufferView", vv}}}};
    const int pa = g.accessor({{"bufferView", bv}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"}, {"sparse", sparse}});
    const int ix = g.indices({0, 1, 2, 0, 2, 3});
    // Without a buffer view the base is zeros: vertices 1 and 2 of three replaced.
    const std::vector<uint8_t> zIdx = {1, 2};
    const std::vector<float> zVal = {1, 0, 0, 0, 1, 0};
    Json zsparse = {{"count", 2},
                    {"indices", {{"bufferView", g.view(zIdx.data(), 2)}, {"componentType", 5121}}},
                    {"values", {{"bufferView", g.view(zVal.data(), zVal.size() * 4)}}}};
    const int za = g.accessor({{"componentType", 5126}, {"count", 3}, {"type", "VEC3"}, {"sparse", zsparse}});
    g.mesh(Json::array({{{"attributes", {{"POSITION", pa}}}, {"indices", ix}}}));
    g.mesh(Json::array({{{"attributes", {{"POSITION", za}}}}}));
    g.doc["nodes"] = {{{"mesh", 0}, {"name", "square"}}, {{"mesh", 1}, {"name", "zeros"}}};
    g.scene({0, 1});
    const SceneBuildInput in = load(g.write(dir_, "sparse"));
    ASSERT_EQ(in.objects.size(), 2u);
    EXPECT_EQ(in.objects[0].geometry.positions,
              (std::vector<Vec3>{{0, 0, 0}, {5, 0, 0}, {1, 1, 0}, {0, 5, 0}}));
    EXPECT_EQ(in.objects[0].geometry.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3}));
    EXPECT_EQ(in.objects[1].geometry.positions, (std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}));

    // A substitution past the accessor's count.
    g.doc["accessors"][size_t(pa)]["count"] = 2;
    g.doc["accessors"][size_t(ix)]["count"] = 3;
    const std::string path = g.write(dir_, "badsparse");
    EXPECT_EQ(refusal(path), path + ": mesh 0 primitive 0 (node 'square'): POSITION accessor 0: sparse index 3 "
                                    "(substitution 1) is out of range: the accessor has 2 elements; the file is damaged");
}

// KHR_mesh_quantization: integer positions, normalized or not, placed by the node's transform.
TEST_F(GltfTest, QuantizedPositions) {
    GltfFile g;
    g.require("KHR_mesh_quantization");
    // Unsigned shorts, not normalized, scaled by 2^-10 (exact): (0,0,0) (1,0,0) (0,2,0).
    const std::vector<uint16_t> us = {0, 0, 0, 0, 1024, 0, 0, 0, 0, 2048, 0, 0};  // 3 elements, stride 8
    const int uv = g.view(us.data(), us.size() * 2, 8);
    const int ua = g.accessor({{"bufferView", uv}, {"componentType", 5123}, {"count", 3}, {"type", "VEC3"}});
    // Normalized signed bytes: 127 -> 1, -128 -> -1 (clamped), 64 -> 64/127.
    const std::vector<int8_t> sb = {127, 0, 0, 0, -128, 0, 0, 0, 0, -127, 64, 0};  // stride 4
    const int sv = g.view(sb.data(), sb.size(), 4);
    const int sa = g.accessor({{"bufferView", sv}, {"componentType", 5120}, {"count", 3}, {"type", "VEC3"}, {"normalized", true}});
    g.mesh(Json::array({{{"attributes", {{"POSITION", ua}}}}}));
    g.mesh(Json::array({{{"attributes", {{"POSITION", sa}}}}}));
    const double s = 1.0 / 1024;
    g.doc["nodes"] = {{{"mesh", 0}, {"scale", {s, s, s}}}, {{"mesh", 1}}};
    g.scene({0, 1});
    const SceneBuildInput in = load(g.write(dir_, "quantized"));
    ASSERT_EQ(in.objects.size(), 2u);
    EXPECT_EQ(in.objects[0].geometry.positions, (std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {0, 2, 0}}));
    EXPECT_EQ(in.objects[1].geometry.positions, (std::vector<Vec3>{{1, 0, 0}, {-1, 0, 0}, {0, -1, 64 / 127.0}}));
}

// ---- EXT_mesh_gpu_instancing --------------------------------------------------------------------------

TEST_F(GltfTest, GpuInstancingMakesOneObjectPerInstance) {
    GltfFile g;
    g.require("EXT_mesh_gpu_instancing");
    g.require("KHR_mesh_quantization");  // normalized rotations
    const int mesh = g.triangleMesh();
    const std::vector<float> t = {0, 0, 0, 0, 5, 0, 0, 0, 7};
    // Rotations as normalized shorts: identity, 180 degrees about z (0,0,1,0), identity; exact.
    const std::vector<int16_t> r = {0, 0, 0, 32767, 0, 0, 32767, 0, 0, 0, 0, 32767};
    const std::vector<float> s = {1, 1, 1, 2, 2, 2, 1, 1, -1};
    const int ta = g.accessor({{"bufferView", g.view(t.data(), t.size() * 4)}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}});
    const int ra = g.accessor({{"bufferView", g.view(r.data(), r.size() * 2)}, {"componentType", 5122}, {"count", 3},
                               {"type", "VEC4"}, {"normalized", true}});
    const int sa = g.accessor({{"bufferView", g.view(s.data(), s.size() * 4)}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}});
    g.doc["nodes"] = {{{"name", "row"}, {"mesh", mesh}, {"translation", {10, 0, 0}},
                       {"extensions", {{"EXT_mesh_gpu_instancing",
                                        {{"attributes", {{"TRANSLATION", ta}, {"ROTATION", ra}, {"SCALE", sa}}}}}}}}};
    g.scene({0});
    const std::string path = g.write(dir_, "instances");
    const SceneBuildInput in = load(path);
    ASSERT_EQ(in.objects.size(), 3u);
    EXPECT_EQ(in.objects[0].name, "row[0]");
    EXPECT_EQ(in.objects[1].name, "row[1]");
    EXPECT_EQ(in.objects[2].name, "row[2]");
    // world_i = node (translate 10,0,0) * T_i * R_i * S_i.
    EXPECT_EQ(in.objects[0].geometry.positions, (std::vector<Vec3>{{10, 0, 0}, {11, 0, 0}, {10, 1, 0}}));
    EXPECT_EQ(in.objects[1].geometry.positions, (std::vector<Vec3>{{10, 5, 0}, {8, 5, 0}, {10, 3, 0}}));
    EXPECT_EQ(in.objects[2].geometry.positions, (std::vector<Vec3>{{10, 0, 7}, {11, 0, 7}, {10, 1, 7}}));
    EXPECT_EQ(in.objects[1].geometry.indices, (std::vector<uint32_t>{0, 1, 2}));  // rotation and scale 2: kept
    EXPECT_EQ(in.objects[2].geometry.indices, (std::vector<uint32_t>{0, 2, 1}));  // mirrored by z -1: swapped
    // Every instance counts toward the triangle limit, before anything is read.
    EXPECT_EQ(refusal(path, 2).rfind(path + ": mesh 0 primitive 0 (node 'row'): the scene up to this primitive needs 3 "
                                            "triangles, more than the limit of 2",
                                     0),
              0u);
}

// ---- Skins ---------------------------------------------------------------------------------------------

// Skinning at rest: a vertex is at sum_k w_k J_k B_k v and the skinned node's own transform is not used
// (glTF 2.0, "Skins"): gltf-transform's quantize moves a skinned mesh's dequantization into the
// inverse bind matrices, so a loader that placed it by the node would put quantized integers in
// the world. A vertex without weights (invalid) follows its first joint, as three.js does.
TEST_F(GltfTest, SkinsAtRest) {
    GltfFile g;
    const int p = g.positions({0, 0, 0, 1, 0, 0, 0, 1, 0});
    const std::vector<uint8_t> joints = {0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0};
    const std::vector<float> weights = {1, 0, 0, 0, 1, 0, 0, 0, 0.5f, 0.5f, 0, 0};
    const std::vector<float> none(12, 0.0f);
    const int ja = g.accessor({{"bufferView", g.view(joints.data(), joints.size())}, {"componentType", 5121},
                               {"count", 3}, {"type", "VEC4"}});
    const int wa = g.accessor({{"bufferView", g.view(weights.data(), weights.size() * 4)}, {"componentType", 5126},
                               {"count", 3}, {"type", "VEC4"}});
    const int na = g.accessor({{"bufferView", g.view(none.data(), none.size() * 4)}, {"componentType", 5126},
                               {"count", 3}, {"type", "VEC4"}});
    // Joint 0's inverse bind matrix undoes its translation (J B = identity); joint 1's is the identity.
    const std::vector<float> ibm = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, -10, 0, 1,
                                    1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    const int ia = g.accessor({{"bufferView", g.view(ibm.data(), ibm.size() * 4)}, {"componentType", 5126},
                               {"count", 2}, {"type", "MAT4"}});
    g.mesh(Json::array({{{"attributes", {{"POSITION", p}, {"JOINTS_0", ja}, {"WEIGHTS_0", wa}}}},
                        {{"attributes", {{"POSITION", p}, {"JOINTS_0", ja}, {"WEIGHTS_0", na}}}}}));
    // The skinned node comes first in the walk, its joints after it.
    g.doc["nodes"] = {{{"name", "door"}, {"mesh", 0}, {"skin", 0}, {"translation", {100, 0, 0}}},
                      {{"name", "hinge"}, {"translation", {0, 10, 0}}},
                      {{"name", "latch"}, {"translation", {0, 0, 20}}}};
    g.doc["skins"] = {{{"joints", {1, 2}}, {"inverseBindMatrices", ia}}};
    g.scene({0, 1, 2});
    std::string path = g.write(dir_, "skin");
    const SceneBuildInput in = load(path);
    ASSERT_EQ(in.objects.size(), 2u);
    EXPECT_EQ(in.objects[0].name, "door/0");
    // v0 all joint 0: (0,0,0); v1 all joint 1: (1,0,0) + (0,0,20); v2 half each: (0,1,0) / 2 + (0,1,20) / 2.
    EXPECT_EQ(in.objects[0].geometry.positions, (std::vector<Vec3>{{0, 0, 0}, {1, 0, 20}, {0, 1, 10}}));
    EXPECT_EQ(in.objects[0].geometry.indices, (std::vector<uint32_t>{0, 1, 2}));
    // No weights: each vertex follows its first joint (0, 1, 0), never the node's transform.
    EXPECT_EQ(in.objects[1].geometry.positions, (std::vector<Vec3>{{0, 0, 0}, {1, 0, 20}, {0, 1, 0}}));
    ASSERT_EQ(in.warnings.size(), 1u);
    EXPECT_EQ(in.warnings[0], path + ": mesh 0 primitive 1 (node 'door'): skin 0: 3 of 3 vertices have no joint weight "
                                     "(glTF requires weights summing to 1): each follows its first joint, as three.js "
                                     "does");

    // A joint index past the skin's joints.
    g.doc["skins"][0]["joints"] = {1};
    g.doc["accessors"][size_t(ia)]["count"] = 1;
    path = g.write(dir_, "badjoint");
    EXPECT_EQ(refusal(path), path + ": mesh 0 primitive 0 (node 'door'): skin 0: JOINTS_0 of vertex 1 is 1, not one "
                                    "of the skin's 1 joints; the file is damaged");
}

// The castle dungeon's switch: Blender wrote its skinned vertices in world space with J B = identity,
// and visaudit placed them by the node's transform as well, drawing the switch at a third of its size
// 7 units away. Skinned at rest, its bounds are its POSITION accessor's min/max (the raw vertices).
// J B is the identity up to the float32 roundings of the exporter's inverse B = A^-1 (|A| <= 19.1,
// |B| <= 78 entrywise): each of the 4 terms of a product entry is off by at most 8 float32 ulps,
// 4 * 19.1 * 78 * 8 * 2^-24 relative, times coordinates up to 20: 0.057 (measured: 7e-7).
TEST(LoadRealData, DungeonSwitchSkinnedAtRest) {
    const std::string path = std::string(VISAUDIT_TEST_DATA) + "/castle/level/level-dungeon.gltf";
    if (!fs::exists(path)) GTEST_SKIP() << path << " is absent: run scripts/fetch-data.sh to fetch it";
    SceneBuildInput in;
    std::string err;
    ASSERT_TRUE(loadGltf(path, &in, &err)) << err;
    const Json doc = Json::parse(std::ifstream(path));
    const auto &acc = doc["accessors"][doc["meshes"][21]["primitives"][0]["attributes"]["POSITION"].get<size_t>()];
    const double tol = 4 * 19.1 * 78 * 8 * std::ldexp(1.0, -24) * 20;
    size_t found = 0;
    for (const auto &o : in.objects) {
        if (o.name != "switch.001") continue;
        ++found;
        for (int k = 0; k < 3; ++k) {
            double lo = HUGE_VAL, hi = -HUGE_VAL;
            for (const Vec3 &p : o.geometry.positions) {
                const double c = k == 0 ? p.x : k == 1 ? p.y : p.z;
                lo = std::min(lo, c);
                hi = std::max(hi, c);
            }
            EXPECT_NEAR(lo, acc["min"][size_t(k)].get<double>(), tol) << "axis " << k;
            EXPECT_NEAR(hi, acc["max"][size_t(k)].get<double>(), tol) << "axis " << k;
        }
    }
    EXPECT_EQ(found, 1u);
    // 53 of its 88 vertices have no weight (the switch's base): they follow joint 0, with a warning.
    ASSERT_EQ(in.warnings.size(), 1u);
    EXPECT_NE(in.warnings[0].find("skin 0: 53 of 88 vertices have no joint weight"), std::string::npos) << in.warnings[0];
}

// ---- Materials ---------------------------------------------------------------------------------------

TEST_F(GltfTest, AlphaModesAndTransmission) {
    GltfFile g;
    const int p = g.positions({0, 0, 0, 1, 0, 0, 0, 1, 0});
    auto color = [](double a) { return Json{{"baseColorFactor", {1, 1, 1, a}}}; };
    g.doc["materials"] = {
        {{"name", "opaque"}},
        {{"name", "mask"}, {"alphaMode", "MASK"}, {"pbrMetallicRoughness", color(1)}},
        {{"name", "mask-cut"}, {"alphaMode", "MASK"}, {"pbrMetallicRoughness", color(0.25)}},  // cutoff 0.5
        {{"name", "mask-low"}, {"alphaMode", "MASK"}, {"alphaCutoff", 0.2}, {"pbrMetallicRoughness", color(0.25)}},
        {{"name", "blend"}, {"alphaMode", "BLEND"}, {"pbrMetallicRoughness", color(0.5)}},
        {{"name", "blend-tex"}, {"alphaMode", "BLEND"}},
        {{"name", "glass"}, {"extensions", {{"KHR_materials_transmission", {{"transmissionFactor", 0.8}}},
                                            {"KHR_materials_ior", {{"ior", 1.33}}}}}},
        {{"name", "thin"}, {"extensions", {{"KHR_materials_transmission", {{"transmissionFactor", 0.8}}}}}},
        {{"name", "none"}, {"extensions", {{"KHR_materials_transmission", {{"transmissionFactor", 0}}},
                                           {"KHR_materials_ior", {{"ior", 1.33}}}}}}};
    Json prims = Json::array();
    for (int m = 0; m < 9; ++m) prims.push_back({{"attributes", {{"POSITION", p}}}, {"material", m}});
    g.mesh(prims);
    g.doc["nodes"] = {{{"mesh", 0}}};
    g.scene({0});
    const std::string path = g.write(dir_, "materials");
    const SceneBuildInput in = load(path);
    ASSERT_EQ(in.materials.size(), 10u);  // the default and the file's 9
    struct Want {
        double alpha, ior;
    };
    const Want want[9] = {{1, 1}, {1, 1}, {0, 1}, {1, 1}, {0.5, 1}, {1, 1}, {1, 1.33}, {1, 1.5}, {1, 1}};
    for (size_t i = 0; i < 9; ++i) {
        const Material &m = in.materials[i + 1];
        EXPECT_EQ(m.alpha, want[i].alpha) << m.name;
        EXPECT_EQ(m.ior, want[i].ior) << m.name;
        EXPECT_EQ(m.transparent(), want[i].alpha < 1) << m.name;
        EXPECT_EQ(m.refractive(), want[i].ior != 1) << m.name;
        EXPECT_EQ(in.objects[i].material, i + 1);
    }
    ASSERT_EQ(in.warnings.size(), 1u);
    EXPECT_EQ(in.warnings[0], path + ": material 'blend-tex' is alphaMode BLEND with baseColorFactor alpha 1 (its "
                                     "transparency would come from a texture, which visaudit does not read): treated "
                                     "as opaque");
}

// ---- EXT_meshopt_compression ---------------------------------------------------------------------------

// A square's 4 float vertices (stride 12) and 2 triangles, encoded by libmeshoptimizer, in views
// whose own buffer is a fallback buffer without data (as gltfpack writes them).
struct MeshoptSquare {
    std::vector<float> vertices = {0, 0, 0, 2, 0, 0, 2, 3, 0, 0, 3, 0};
    std::vector<unsigned> indices = {0, 1, 2, 0, 2, 3};
    std::vector<unsigned char> vbuf, ibuf;

    MeshoptSquare() {
        vbuf.resize(meshopt_encodeVertexBufferBound(4, 12));
        vbuf.resize(meshopt_encodeVertexBuffer(vbuf.data(), vbuf.size(), vertices.data(), 4, 12));
        ibuf.resize(meshopt_encodeIndexBufferBound(6, 4));
        ibuf.resize(meshopt_encodeIndexBuffer(ibuf.data(), ibuf.size(), indices.data(), 6));
    }
    // `count` is the vertex view's declared count.
    GltfFile file(uint64_t count = 4) const {
        GltfFile g;
        g.require("EXT_meshopt_compression");
        g.bin.assign(vbuf.begin(), vbuf.end());
        while (g.bin.size() % 4 != 0) g.bin.push_back('\0');
        const size_t ioff = g.bin.size();
        g.bin.append(ibuf.begin(), ibuf.end());
        g.doc["bufferViews"] = {
            {{"buffer", 1}, {"byteLength", count * 12}, {"byteStride", 12},
             {"extensions", {{"EXT_meshopt_compression", {{"buffer", 0}, {"byteLength", vbuf.size()}, {"byteStride", 12},
                                                          {"count", count}, {"mode", "ATTRIBUTES"}}}}}},
            {{"buffer", 1}, {"byteOffset", count * 12}, {"byteLength", 12},
             {"extensions", {{"EXT_meshopt_compression", {{"buffer", 0}, {"byteOffset", ioff}, {"byteLength", ibuf.size()},
                                                          {"byteStride", 2}, {"count", 6}, {"mode", "TRIANGLES"}}}}}}};
        g.doc["buffers"] = {{},
                            {{"byteLength", count * 12 + 12}, {"extensions", {{"EXT_meshopt_compression", {{"fallback", true}}}}}}};
        g.accessor({{"bufferView", 0}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"}});
        g.accessor({{"bufferView", 1}, {"componentType", 5123}, {"count", 6}, {"type", "SCALAR"}});
        g.mesh(Json::array({{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}}));
        g.doc["nodes"] = {{{"mesh", 0}, {"name", "square"}}};
        g.scene({0});
        return g;
    }
};

TEST_F(GltfTest, MeshoptDecodedByLibmeshoptimizer) {
    const MeshoptSquare sq;
    const std::vector<Tri> want = {{Vec3{0, 0, 0}, Vec3{2, 0, 0}, Vec3{2, 3, 0}}, {Vec3{0, 0, 0}, Vec3{2, 3, 0}, Vec3{0, 3, 0}}};
    for (const bool glb : {false, true}) {
        GltfFile g = sq.file();
        const std::string path = glb ? g.writeGlb(dir_, "square") : g.write(dir_, "square");
        const SceneBuildInput in = load(path);
        ASSERT_EQ(in.objects.size(), 1u) << path;
        EXPECT_EQ(in.objects[0].geometry.positions, (std::vector<Vec3>{{0, 0, 0}, {2, 0, 0}, {2, 3, 0}, {0, 3, 0}}));
        const auto tris = trianglesOf(in.objects[0].geometry);
        ASSERT_EQ(tris.size(), 2u);
        for (const Tri &t : want) EXPECT_TRUE(containsTriangle(tris, t)) << path;
    }
    // A count the compressed bytes cannot hold is refused before anything is allocated: the vertex
    // codec needs at least 1 + 12 * ceil(count / 64) bytes.
    GltfFile g = sq.file(100000);
    std::string path = g.write(dir_, "hostile");
    EXPECT_EQ(refusal(path), path + ": mesh 0 primitive 0 (node 'square'): POSITION accessor 0: buffer view 0: "
                                    "EXT_meshopt_compression declares 100000 elements of 12 bytes (mode ATTRIBUTES), "
                                    "which need at least " + std::to_string(1 + 12 * ((100000 + 63) / 64)) +
                                    " compressed bytes; it has " + std::to_string(sq.vbuf.size()) + ": the file is damaged");
    // Damaged data: the library's error.
    g = sq.file();
    std::fill(g.bin.begin(), g.bin.begin() + std::ptrdiff_t(sq.vbuf.size()), '\0');
    path = g.write(dir_, "damaged");
    EXPECT_EQ(refusal(path), path + ": mesh 0 primitive 0 (node 'square'): POSITION accessor 0: buffer view 0: "
                                    "EXT_meshopt_compression libmeshoptimizer cannot decode it (mode ATTRIBUTES, error -1): "
                                    "the compressed data is damaged or in a codec version newer than Debian's "
                                    "meshoptimizer 0.18 reads");
}

// ---- KHR_draco_mesh_compression ---------------------------------------------------------------------------

// Two triangles encoded by libdraco without quantization (lossless), in a glTF whose accessors have no
// buffer views (as Draco exporters write them).
struct DracoSquare {
    std::vector<Tri> tris = {{Vec3{0, 0, 0}, Vec3{2, 0, 0}, Vec3{2, 3, 0}}, {Vec3{0, 0, 0}, Vec3{2, 3, 0}, Vec3{0, 3, 0}}};
    std::string data;
    int positionId = -1;
    size_t points = 0;

    DracoSquare() {
        draco::TriangleSoupMeshBuilder b;
        b.Start(2);
        const int att = b.AddAttribute(draco::GeometryAttribute::POSITION, 3, draco::DT_FLOAT32);
        for (int f = 0; f < 2; ++f) {
            float c[3][3];
            for (int k = 0; k < 3; ++k) {
                c[k][0] = float(tris[size_t(f)][size_t(k)].x);
                c[k][1] = float(tris[size_t(f)][size_t(k)].y);
                c[k][2] = float(tris[size_t(f)][size_t(k)].z);
            }
            b.SetAttributeValuesForFace(att, draco::FaceIndex(f), c[0], c[1], c[2]);
        }
        std::unique_ptr<draco::Mesh> mesh = b.Finalize();
        positionId = int(mesh->attribute(att)->unique_id());
        points = mesh->num_points();
        draco::Encoder enc;
        draco::EncoderBuffer out;
        const draco::Status st = enc.EncodeMeshToBuffer(*mesh, &out);
        EXPECT_TRUE(st.ok()) << st.error_msg_string();
        data.assign(out.data(), out.size());
    }
    GltfFile file(size_t pointCount) const {
        GltfFile g;
        g.require("KHR_draco_mesh_compression");
        g.view(data.data(), data.size());
        g.accessor({{"componentType", 5126}, {"count", pointCount}, {"type", "VEC3"}});
        g.accessor({{"componentType", 5123}, {"count", 6}, {"type", "SCALAR"}});
        g.mesh(Json::array({{{"attributes", {{"POSITION", 0}}},
                             {"indices", 1},
                             {"extensions", {{"KHR_draco_mesh_compression",
                                              {{"bufferView", 0}, {"attributes", {{"POSITION", positionId}}}}}}}}}));
        g.doc["nodes"] = {{{"mesh", 0}, {"name", "square"}}};
        g.scene({0});
        return g;
    }
};

TEST_F(GltfTest, DracoDecodedByLibdraco) {
    const DracoSquare sq;
    ASSERT_FALSE(sq.data.empty());
    for (const bool glb : {false, true}) {
        GltfFile g = sq.file(sq.points);
        const std::string path = glb ? g.writeGlb(dir_, "square") : g.write(dir_, "square");
        const SceneBuildInput in = load(path);
        ASSERT_EQ(in.objects.size(), 1u) << path;
        EXPECT_EQ(in.objects[0].geometry.positions.size(), sq.points);
        const auto tris = trianglesOf(in.objects[0].geometry);
        ASSERT_EQ(tris.size(), 2u);
        for (const Tri &t : sq.tris) EXPECT_TRUE(containsTriangle(tris, t)) << path;
    }
    // The accessors describe the decoded data: a count that disagrees is refused.
    GltfFile g = sq.file(sq.points + 1);
    std::string path = g.write(dir_, "miscount");
    EXPECT_EQ(refusal(path), path + ": mesh 0 primitive 0 (node 'square'): KHR_draco_mesh_compression decoded " +
                                 std::to_string(sq.points) + " points, but POSITION accessor 0 declares " +
                                 std::to_string(sq.points + 1) + "; the file is inconsistent");
    // Damaged data: libdraco's reason.
    g = sq.file(sq.points);
    std::fill(g.bin.begin(), g.bin.end(), 'x');
    path = g.write(dir_, "damaged");
    const std::string err = refusal(path);
    EXPECT_EQ(err.rfind(path + ": mesh 0 primitive 0 (node 'square'): KHR_draco_mesh_compression (buffer view 0): "
                               "libdraco cannot decode it: ",
                        0),
              0u)
        << err;
}

// ---- The dungeon's variants from real optimizers ----------------------------------------------------------

// Issue 16: every Draco, meshopt and quantized variant (scripts/make-gltf-variants.sh) loads with the
// original's 25038 triangles, each within the quantization's error of an original triangle.
//
// Tolerance, derived: every tool quantizes positions to 14 bits over a grid whose extent is at most
// E, the largest extent of the union of the meshes' local bounds (the POSITION accessors' min/max)
// and the scene's world bounds (gltfpack quantizes merged meshes in world space): a step of at most
// E / (2^14 - 2) (unsigned grids have 2^14 - 1 steps, gltf-transform's signed normalized grid
// 2 (2^13 - 1)), rounded to the nearest, so each coordinate moves at most half a step. The tools
// compute in float32 and store their dequantization transforms as float32: a few roundings of
// relative 2^-24 of coordinates at most M (the largest magnitude in those bounds); 16 of them
// covers it. The level's node transforms are rotations, translations and one scale of 0.34, which
// lengthen no error: a corner moves at most sqrt(3) (E / (2^14 - 2) / 2 + 16 * 2^-24 * M).
//
// The level's switch ('switch.001', 108 triangles) is a skinned mesh, and gltf-transform moves the
// dequantization of a skinned mesh into its inverse bind matrices (a skinned node's own transform
// does not place it): its variants match only because the loader skins at rest (GltfTest.SkinsAtRest).
TEST(LoadGltfVariants, DungeonVariantsKeepEveryTriangle) {
    const std::string data = std::string(VISAUDIT_TEST_DATA) + "/castle/";
    const std::string original = data + "level/level-dungeon.gltf";
    if (!fs::exists(data + "variants/STAMP"))
        GTEST_SKIP() << data << "variants is absent: run scripts/fetch-data.sh (it runs make-gltf-variants.sh)";
    SceneBuildInput base;
    std::string err;
    ASSERT_TRUE(loadGltf(original, &base, &err)) << err;

    // The bounds behind the tolerance.
    double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    auto grow = [&](double x, double y, double z) {
        const double v[3] = {x, y, z};
        for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], v[k]), hi[k] = std::max(hi[k], v[k]);
    };
    const Json doc = Json::parse(std::ifstream(original));
    for (const auto &m : doc["meshes"])
        for (const auto &p : m["primitives"]) {
            const auto &a = doc["accessors"][p["attributes"]["POSITION"].get<size_t>()];
            grow(a["min"][0], a["min"][1], a["min"][2]);
            grow(a["max"][0], a["max"][1], a["max"][2]);
        }
    std::vector<Tri> orig;
    for (const auto &o : base.objects)
        for (const Tri &t : trianglesOf(o.geometry)) {
            orig.push_back(t);
            for (const Vec3 &v : t) grow(v.x, v.y, v.z);
        }
    ASSERT_EQ(orig.size(), 25038u);
    double extent = 0, mag = 0;
    for (int k = 0; k < 3; ++k) {
        extent = std::max(extent, hi[k] - lo[k]);
        mag = std::max({mag, std::fabs(lo[k]), std::fabs(hi[k])});
    }
    const double tol = std::sqrt(3.0) * (extent / ((1 << 14) - 2) / 2 + 16 * std::ldexp(mag, -24));

    // The original's triangles hashed by centroid in cells of 2 tol: a match's centroid is within tol.
    const double cell = 2 * tol;
    auto key = [&](const Tri &t, int dx, int dy, int dz) {
        const Vec3 c = (t[0] + t[1] + t[2]) / 3;
        return std::make_tuple(int64_t(std::floor(c.x / cell)) + dx, int64_t(std::floor(c.y / cell)) + dy,
                               int64_t(std::floor(c.z / cell)) + dz);
    };
    std::map<std::tuple<int64_t, int64_t, int64_t>, std::vector<size_t>> grid;
    for (size_t i = 0; i < orig.size(); ++i) grid[key(orig[i], 0, 0, 0)].push_back(i);

    for (const char *name : {"level-dungeon.draco.glb", "level-dungeon.meshopt.glb", "level-dungeon.meshopt.gltf",
                             "level-dungeon.gt-meshopt.glb", "level-dungeon.quantized.glb",
                             "level-dungeon.quantized-norm.glb", "level-dungeon.gt-quantized.glb"}) {
        SCOPED_TRACE(name);
        SceneBuildInput in;
        ASSERT_TRUE(loadGltf(data + "variants/" + name, &in, &err)) << err;
        std::vector<Tri> tris;
        for (const auto &o : in.objects)
            for (const Tri &t : trianglesOf(o.geometry)) tris.push_back(t);
        EXPECT_EQ(tris.size(), orig.size());
        size_t unmatched = 0;
        double worst = 0;  // the largest corner distance of the matches
        for (const Tri &t : tris) {
            double best = HUGE_VAL;
            for (int dx = -1; dx <= 1; ++dx)
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dz = -1; dz <= 1; ++dz) {
                        auto it = grid.find(key(t, dx, dy, dz));
                        if (it == grid.end()) continue;
                        for (size_t i : it->second)
                            for (int r = 0; r < 3; ++r) {
                                double d = 0;
                                for (int k = 0; k < 3; ++k) d = std::max(d, length(t[size_t(k)] - orig[i][size_t((k + r) % 3)]));
                                best = std::min(best, d);
                            }
                    }
            if (best <= tol) worst = std::max(worst, best);
            else ++unmatched;
        }
        EXPECT_EQ(unmatched, 0u) << "of " << tris.size() << " triangles; tolerance " << tol;
        std::printf("%s: %zu triangles, largest corner error %.3g (tolerance %.3g)\n", name, tris.size(), worst, tol);
    }
}

}  // namespace
}  // namespace va
