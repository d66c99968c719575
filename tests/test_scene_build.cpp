// buildScene: triangle ids, exclusion of degenerate and non-finite triangles, chunking invariants.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <set>

#include "analysis/scene.h"

using namespace va;

namespace {

SceneBuildInput::Object makeObject(const std::string &name, std::vector<Vec3> p, std::vector<uint32_t> idx,
                                   uint32_t material = 0) {
    SceneBuildInput::Object o;
    o.name = name;
    o.mesh = name + ".obj";
    o.material = material;
    o.geometry.positions = std::move(p);
    o.geometry.indices = std::move(idx);
    o.geometry.facesRead = o.geometry.indices.size() / 3;
    return o;
}

// A height-field grid of (n x n) quads = 2 n^2 triangles with seeded random heights over wide
// magnitudes: vertices are shared between neighbouring triangles, so chunk boundaries must duplicate.
SceneBuildInput::Object gridObject(const std::string &name, int n, uint32_t seed, double scale) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> h(-1, 1);
    std::vector<Vec3> p;
    std::vector<uint32_t> idx;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) p.push_back(Vec3{i * scale, h(rng) * scale, j * scale});
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const uint32_t a = uint32_t(j * (n + 1) + i), b = a + 1, c = a + uint32_t(n) + 1, d = c + 1;
            idx.insert(idx.end(), {a, c, b, b, c, d});
        }
    return makeObject(name, std::move(p), std::move(idx));
}

// Checks every invariant scene.h promises about a built scene against the input it came from.
void expectSceneInvariants(const Scene &s, const std::vector<SceneBuildInput::Object> &input) {
    ASSERT_EQ(s.indices.size(), 3 * s.triangleCount());
    ASSERT_EQ(s.planes.size(), 4 * s.triangleCount());
    // Every valid triangle lies in exactly one object, and the object's list holds it.
    std::vector<int> seen(s.triangleCount(), 0);
    for (uint32_t oi = 0; oi < s.objects.size(); ++oi) {
        const SceneObject &o = s.objects[oi];
        ASSERT_LE(o.vertexBegin, o.vertexEnd);
        ASSERT_LE(o.vertexEnd, s.positions.size());
        ASSERT_LT(o.triBegin, o.triEnd) << "objects without triangles must not exist";
        if (oi > 0) {
            EXPECT_EQ(o.vertexBegin, s.objects[oi - 1].vertexEnd) << "vertex ranges are contiguous and ordered";
            EXPECT_EQ(o.triBegin, s.objects[oi - 1].triEnd);
        }
        for (uint32_t k = o.triBegin; k < o.triEnd; ++k) {
            const uint32_t t = s.objectTriangles[k];
            if (k > o.triBegin) EXPECT_LT(s.objectTriangles[k - 1], t) << "source order within an object";
            EXPECT_EQ(s.triangleObject[t], oi);
            ++seen[t];
            for (int c = 0; c < 3; ++c) {
                const uint32_t v = s.indices[3 * t + c];
                EXPECT_GE(v, o.vertexBegin);
                EXPECT_LT(v, o.vertexEnd);
                const Vec3 p = s.positions[v];
                EXPECT_TRUE(p.x >= o.bounds.lo.x && p.x <= o.bounds.hi.x && p.y >= o.bounds.lo.y &&
                            p.y <= o.bounds.hi.y && p.z >= o.bounds.lo.z && p.z <= o.bounds.hi.z);
                EXPECT_LE(length(p - o.sphere.center), o.sphere.radius);
            }
        }
    }
    // Ids are source order: triangle t of input object k is id firstTriangle + t, with the same
    // corner positions as in the input.
    uint64_t id = 0;
    for (size_t k = 0; k < input.size(); ++k) {
        const RawMesh &g = input[k].geometry;
        EXPECT_EQ(s.sources[k].firstTriangle, id);
        EXPECT_EQ(s.sources[k].triangleCount, g.indices.size() / 3);
        for (size_t t = 0; t < g.indices.size() / 3; ++t, ++id) {
            if (s.triangleObject[id] == kExcludedTriangle) {
                EXPECT_EQ(seen[id], 0);
                continue;
            }
            EXPECT_EQ(seen[id], 1) << "triangle " << id;
            EXPECT_EQ(s.objects[s.triangleObject[id]].source, k);
            for (int c = 0; c < 3; ++c) EXPECT_EQ(s.positions[s.indices[3 * id + c]], g.positions[g.indices[3 * t + c]]);
        }
    }
    EXPECT_EQ(id, s.triangleCount());
}

}  // namespace

TEST(SceneBuild, PlaneIsCrossProductOfEdges) {
    SceneBuildInput in;
    in.objects.push_back(makeObject("t", {{1, 0, 0}, {3, 0, 0}, {1, 4, 0}}, {0, 1, 2}));
    Scene s = buildScene(std::move(in));
    ASSERT_EQ(s.triangleCount(), 1u);
    // n = (2,0,0) x (0,4,0) = (0,0,8); k = -n.v0 = 0.
    EXPECT_EQ(s.planes[0], 0);
    EXPECT_EQ(s.planes[1], 0);
    EXPECT_EQ(s.planes[2], 8);
    EXPECT_EQ(s.planes[3], 0);
    ASSERT_EQ(s.objects.size(), 1u);
    EXPECT_EQ(s.objects[0].name, "t");  // small objects keep their name (no "#0")
    EXPECT_EQ(s.materials.size(), 1u);  // the default material is supplied
    EXPECT_EQ(s.bounds.lo, (Vec3{1, 0, 0}));
    EXPECT_EQ(s.bounds.hi, (Vec3{3, 4, 0}));
}

TEST(SceneBuild, DegenerateAndNonFiniteAreCountedAndExcluded) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double inf = std::numeric_limits<double>::infinity();
    SceneBuildInput in;
    // 0: valid, 1: two equal positions at different indices, 2: collinear, 3: NaN, 4: infinity,
    // 5: valid, 6: repeated index.
    in.objects.push_back(makeObject("a",
                                    {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 0, 0}, {2, 0, 0}, {nan, 0, 0}, {0, inf, 0}, {0, 0, 1}},
                                    {0, 1, 2, 0, 1, 3, 0, 1, 4, 0, 5, 2, 6, 1, 2, 0, 1, 7, 0, 0, 2}));
    in.objects.back().geometry.facesDropped = 2;  // summed into the stats
    in.objects.back().geometry.polygonsTriangulated = 1;
    const auto copy = in.objects;
    Scene s = buildScene(std::move(in));
    EXPECT_EQ(s.stats.sourceTriangles, 7u);
    EXPECT_EQ(s.stats.degenerateTriangles, 3u);
    EXPECT_EQ(s.stats.nonFiniteTriangles, 2u);
    EXPECT_EQ(s.stats.facesDropped, 2u);
    EXPECT_EQ(s.stats.polygonsTriangulated, 1u);
    const std::vector<uint32_t> expectObject{0, kExcludedTriangle, kExcludedTriangle, kExcludedTriangle,
                                             kExcludedTriangle, 0, kExcludedTriangle};
    EXPECT_EQ(s.triangleObject, expectObject);
    // Excluded triangles: indices {0,0,0} and plane (0,0,0,0); NaN never reaches positions or bounds.
    for (uint32_t t : {1u, 2u, 3u, 4u, 6u}) {
        EXPECT_EQ(s.indices[3 * t] + s.indices[3 * t + 1] + s.indices[3 * t + 2], 0u);
        for (int k = 0; k < 4; ++k) EXPECT_EQ(s.planes[4 * t + k], 0);
    }
    for (const auto &p : s.positions) EXPECT_TRUE(isFinite(p));
    EXPECT_EQ(s.positions.size(), 4u);  // only vertices of valid triangles: 0, 1, 2, 7
    expectSceneInvariants(s, copy);
}

TEST(SceneBuild, ObjectWithoutValidTrianglesMakesNoCullingObject) {
    SceneBuildInput in;
    in.objects.push_back(makeObject("flat", {{0, 0, 0}, {1, 1, 1}, {2, 2, 2}}, {0, 1, 2}));
    in.objects.push_back(makeObject("empty", {}, {}));
    in.objects.push_back(makeObject("ok", {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {0, 1, 2}));
    Scene s = buildScene(std::move(in));
    ASSERT_EQ(s.sources.size(), 3u);
    EXPECT_EQ(s.sources[0].chunkCount, 0u);
    EXPECT_EQ(s.sources[1].chunkCount, 0u);
    EXPECT_EQ(s.sources[1].triangleCount, 0u);
    EXPECT_EQ(s.sources[2].chunkCount, 1u);
    EXPECT_EQ(s.sources[2].firstTriangle, 1u);
    ASSERT_EQ(s.objects.size(), 1u);
    EXPECT_EQ(s.objects[0].source, 2u);
    EXPECT_EQ(s.triangleObject, (std::vector<uint32_t>{kExcludedTriangle, 0}));
}

TEST(SceneBuild, EmptyInput) {
    Scene s = buildScene(SceneBuildInput{});
    EXPECT_EQ(s.triangleCount(), 0u);
    EXPECT_TRUE(s.objects.empty());
    EXPECT_TRUE(s.bounds.empty());
}

TEST(SceneBuild, ChunkingInvariantsOverWideMagnitudes) {
    for (double scale : {1e-6, 1.0, 1e6}) {
        SceneBuildInput in;
        in.objects.push_back(gridObject("small", 3, 1, scale));   // 18 triangles: not split
        in.objects.push_back(gridObject("level", 40, 2, scale));  // 3200 triangles: split
        in.materials = {Material{}, Material{"stone", false, 1, 0, 1}};
        in.objects.back().material = 1;
        const auto copy = in.objects;
        ChunkSettings cs;
        cs.maxTriangles = 100;
        Scene s = buildScene(std::move(in), cs);
        expectSceneInvariants(s, copy);
        EXPECT_EQ(s.sources[0].chunkCount, 1u);
        EXPECT_EQ(s.objects[0].name, "small");
        // 3200 triangles halved until <= 100: 5 levels of median splits, 32 chunks of 100.
        EXPECT_EQ(s.sources[1].chunkCount, 32u);
        for (uint32_t c = 0; c < s.sources[1].chunkCount; ++c) {
            const SceneObject &o = s.objects[s.sources[1].firstChunk + c];
            EXPECT_EQ(o.name, "level#" + std::to_string(c));
            EXPECT_EQ(o.triEnd - o.triBegin, 100u);
            EXPECT_EQ(o.material, 1u);
        }
        // Spatial coherence: chunks of a 40 x 40 grid cover about 1/32 of its area each, so their
        // bounds are much smaller than the whole grid in x or z.
        const double full = 40 * scale;
        for (uint32_t c = 0; c < 32; ++c) {
            const Aabb &b = s.objects[1 + c].bounds;
            EXPECT_LE(std::min(b.extent().x, b.extent().z), full / 3);
        }
    }
}

TEST(SceneBuild, Deterministic) {
    auto make = [] {
        SceneBuildInput in;
        in.objects.push_back(gridObject("g", 30, 7, 1));
        ChunkSettings cs;
        cs.maxTriangles = 37;
        return buildScene(std::move(in), cs);
    };
    const Scene a = make(), b = make();
    EXPECT_EQ(a.positions.size(), b.positions.size());
    EXPECT_EQ(a.indices, b.indices);
    EXPECT_EQ(a.objectTriangles, b.objectTriangles);
    EXPECT_EQ(a.triangleObject, b.triangleObject);
    ASSERT_EQ(a.objects.size(), b.objects.size());
    for (size_t i = 0; i < a.objects.size(); ++i) EXPECT_EQ(a.objects[i].sphere.radius, b.objects[i].sphere.radius);
}

TEST(SceneBuild, RefusesBadInputWithAMessage) {
    SceneBuildInput in;
    in.objects.push_back(makeObject("broken", {{0, 0, 0}}, {0, 0, 5}));
    Scene s;
    std::string err;
    EXPECT_FALSE(buildScene(std::move(in), {}, &s, &err));
    EXPECT_EQ(err, "object 'broken': triangle 0 has a vertex index outside its 1 positions (internal error in the loader)");
    SceneBuildInput in2;
    in2.objects.push_back(makeObject("m", {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {0, 1, 2}, 3));
    EXPECT_FALSE(buildScene(std::move(in2), {}, &s, &err));
    EXPECT_EQ(err, "object 'm': material index 3 out of range (1 materials)");
    SceneBuildInput in3;
    in3.objects.push_back(makeObject("m", {{0, 0, 0}}, {0, 0}));
    EXPECT_THROW(buildScene(std::move(in3)), std::runtime_error);
}
