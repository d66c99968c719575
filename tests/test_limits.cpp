// Resource limits (common/limits.h, docs/limits.md): each limit refuses input that would exceed it
// with the number it needed, the limit and the flag that raises it, before the memory is allocated
// (the program's peak memory, from wait4, proves "before"); the flag lets the input through.
// Suite Limits*.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "analysis/load/demo.h"
#include "common/limits.h"
#include "analysis/load/load.h"
#include "analysis/pipeline.h"
#include "render/abuffer.h"
#include "tests/run_binary.h"
#include "tests/temp_dir_test.h"
#include "tests/test_util.h"

namespace va {
namespace {

namespace fs = std::filesystem;
using testing_util::runBinary;

class LimitsTest : public testing_util::TempDirTest {
  protected:
    LimitsTest() : TempDirTest("limits") {}

    void write(const std::string &name, const std::string &text) { std::ofstream(dir_ / name, std::ios::binary) << text; }
    std::string path(const std::string &name) const { return (dir_ / name).string(); }
};

// A process that refused its input before allocating stays near the program's own size: the peak
// of `visaudit --version` (code, libraries, TBB's pools; about 135 MiB, 225 MiB under ASan, whose
// shadow memory counts) plus 100 MiB. The refused inputs below would need gigabytes.
long refusedPeakKiB() {
    static const long peak = [] {
        const fs::path dir = fs::temp_directory_path() / ("visaudit-limits-baseline-" + std::to_string(getpid()));
        fs::create_directories(dir);
        const long baseline = runBinary({"--version"}, dir).maxRssKiB;
        fs::remove_all(dir);
        return baseline + 100 * 1024;
    }();
    return peak;
}

TEST(Limits, ParseByteSize) {
    uint64_t b = 0;
    std::string err;
    ASSERT_TRUE(parseByteSize("8G", &b, &err));
    EXPECT_EQ(b, uint64_t(8) << 30);
    ASSERT_TRUE(parseByteSize("1.5g", &b, &err));
    EXPECT_EQ(b, uint64_t(3) << 29);
    ASSERT_TRUE(parseByteSize("512MiB", &b, &err));
    EXPECT_EQ(b, uint64_t(512) << 20);
    ASSERT_TRUE(parseByteSize("100", &b, &err));
    EXPECT_EQ(b, 100u);
    ASSERT_TRUE(parseByteSize("2TB", &b, &err));
    EXPECT_EQ(b, uint64_t(2) << 40);
    EXPECT_FALSE(parseByteSize("lots", &b, &err));
    EXPECT_EQ(err, "'lots' is not a size; give bytes or a number with K, M, G or T (binary units), e.g. 8G or 1.5G");
    EXPECT_FALSE(parseByteSize("-1G", &b, &err));
    EXPECT_FALSE(parseByteSize("8X", &b, &err));
    EXPECT_FALSE(parseByteSize("99999999T", &b, &err));  // more than 2^64 bytes
    EXPECT_EQ(formatBytes(100), "100 B");
    EXPECT_EQ(formatBytes(uint64_t(3) << 29), "1.50 GiB");
    EXPECT_GT(defaultMaxMemory(), uint64_t(0));
}

// A 1e9-pixel view (40000 x 25000) is refused by the resolution limit at once, before any buffer.
TEST_F(LimitsTest, ResolutionRefusedBeforeAllocating) {
    const auto r = runBinary({"analyze", "--quiet", "--width", "40000", "--height", "25000", "--out", path("out")}, dir_);
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.err, "visaudit: error: view 'spawn': resolution 40000x25000 exceeds the limit of 16384 pixels per side; "
                     "lower it (--width/--height) or raise the limit with --max-resolution\n");
    EXPECT_LT(r.maxRssKiB, refusedPeakKiB());
    EXPECT_FALSE(fs::exists(dir_ / "out"));
}

// With the resolution limit raised, the same view meets the memory limit: about 200 GB of buffers
// for 1e9 pixels, refused from the estimate before anything is built.
TEST_F(LimitsTest, RaisedResolutionMeetsTheMemoryEstimate) {
    const auto r = runBinary({"analyze", "--quiet", "--width", "40000", "--height", "25000", "--max-resolution", "40000",
                              "--max-memory", "16G", "--out", path("out")},
                             dir_);
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find("visaudit: error: the analysis needs about "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("more than the limit of 16.00 GiB; lower the resolution (--width/--height) or --threads, or "
                         "raise the limit with --max-memory "),
              std::string::npos)
        << r.err;
    EXPECT_LT(r.maxRssKiB, refusedPeakKiB());
    EXPECT_FALSE(fs::exists(dir_ / "out"));
}

// Where it is feasible, raising the flag lets the input through: a 20000 x 2 view.
TEST_F(LimitsTest, RaisedResolutionRuns) {
    const std::vector<std::string> args = {"analyze", "--quiet", "--width", "20000", "--height", "2", "--views", "orbit:1",
                                           "--out", path("out")};
    auto r = runBinary(args, dir_);
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find("resolution 20000x2 exceeds the limit of 16384 pixels per side"), std::string::npos) << r.err;
    auto raised = args;
    raised.insert(raised.end(), {"--max-resolution", "20000"});
    r = runBinary(raised, dir_);
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_TRUE(fs::exists(dir_ / "out" / "report.json"));
}

// Memory: the refusal names the estimate and its parts; --max-memory 0 turns the check off.
TEST(Limits, MemoryEstimateRefusesAndScales) {
    const Scene scene = demoScene();
    std::vector<ViewSpec> views = scene.views;
    views.resize(1);
    PipelineSettings s;
    s.limits.maxMemory = 1 << 20;
    AnalysisResult result;
    std::string err;
    EXPECT_FALSE(analyzeScene(scene, views, s, nullptr, &result, &err));
    EXPECT_EQ(err.rfind("the analysis needs about ", 0), 0u) << err;
    EXPECT_NE(err.find(" view(s) at once of "), std::string::npos) << err;
    EXPECT_NE(err.find("more than the limit of 1.00 MiB"), std::string::npos) << err;
    EXPECT_TRUE(result.views.empty());  // refused before any view ran

    // The per-view term is linear in the pixels; views in flight are bounded by threads and views.
    Camera small, big;
    CameraSpec spec = views[0].camera;
    spec.width = 100, spec.height = 100;
    ASSERT_TRUE(makeCamera(spec, &small, &err));
    spec.width = 200, spec.height = 200;
    ASSERT_TRUE(makeCamera(spec, &big, &err));
    s.threads = 3;
    const MemoryEstimate a = estimateMemory(scene, {small}, s), b = estimateMemory(scene, {big}, s);
    const uint64_t perTri = a.perView - (b.perView - a.perView) / 3;  // perView = pixels * k + triangles * t
    EXPECT_EQ(b.perView - perTri, 4 * (a.perView - perTri));
    EXPECT_EQ(a.viewsInFlight, 1u);
    EXPECT_EQ(estimateMemory(scene, {small, small, small, small}, s).viewsInFlight, 3u);
    EXPECT_EQ(b.finishedViews, a.finishedViews);  // a finished view keeps no per-pixel buffer
    EXPECT_EQ(a.total - a.scene - a.prepared - a.perView - a.finishedViews,
              b.total - b.scene - b.prepared - b.perView - b.finishedViews);  // the baseline

    s.limits.maxMemory = 0;
    s.threads = 0;
    EXPECT_TRUE(analyzeScene(scene, views, s, nullptr, &result, &err)) << err;
}

// A finished view keeps no per-pixel buffer (releasePixelBuffers, analysis/results.h): on one
// thread the peak does not grow with the number of views. Before, `v = {}` emptied the buffers but
// kept their capacity, and every finished 768 x 768 view held about 23 MB more (40 B a pixel).
TEST_F(LimitsTest, PeakDoesNotGrowWithFinishedViews) {
#if defined(__SANITIZE_ADDRESS__)
    GTEST_SKIP() << "AddressSanitizer's quarantine keeps freed memory resident";
#endif
    auto peakOf = [&](const std::string &views) {
        const auto r = runBinary({"analyze", "--quiet", "--views", views, "--width", "768", "--height", "768",
                                  "--threads", "1", "--out", path("out-" + views.substr(6))},
                                 dir_);
        EXPECT_EQ(r.code, 0) << r.err;
        return r.maxRssKiB;
    };
    const long one = peakOf("orbit:1"), five = peakOf("orbit:5");
    EXPECT_LT(five, one + 40 * 1024) << "1 view: " << one << " KiB, 5 views: " << five << " KiB";
}

// Triangles: a scene file instancing one mesh many times is refused from the running count,
// before the instances are copied; a mesh file alone, before the scene is built.
TEST_F(LimitsTest, TrianglesOfInstancedMesh) {
    write("quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n");
    write("s.json", R"({"format": "visaudit-scene/1", "objects": [
        {"name": "a", "mesh": "quad.obj"}, {"name": "b", "mesh": "quad.obj"}, {"name": "c", "mesh": "quad.obj"}]})");
    LoadOptions lo;
    lo.maxTriangles = 5;
    Scene scene;
    std::string err;
    EXPECT_FALSE(loadScene(path("s.json"), lo, &scene, &err));
    EXPECT_EQ(err, path("s.json") + ":2:79: the scene up to object 'c' needs 6 triangles, more than the limit of 5; "
                   "raise it with --max-triangles 6 if the machine has the memory (about 1.50 KiB), or the file is damaged");
    lo.maxTriangles = 6;
    ASSERT_TRUE(loadScene(path("s.json"), lo, &scene, &err)) << err;
    EXPECT_EQ(scene.triangleCount(), 6u);

    lo.maxTriangles = 1;
    EXPECT_FALSE(loadScene(path("quad.obj"), lo, &scene, &err));
    EXPECT_EQ(err, path("quad.obj") + " needs 2 triangles, more than the limit of 1; raise it with --max-triangles 2 "
                   "if the machine has the memory (about 512 B), or the file is damaged");
}

// The flag reaches the loaders through the program (info loads the scene and nothing else).
TEST_F(LimitsTest, TrianglesFlag) {
    write("quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n");
    auto r = runBinary({"info", path("quad.obj"), "--max-triangles", "1"}, dir_);
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find("needs 2 triangles, more than the limit of 1; raise it with --max-triangles 2"),
              std::string::npos)
        << r.err;
    r = runBinary({"info", path("quad.obj"), "--max-triangles", "2"}, dir_);
    EXPECT_EQ(r.code, 0) << r.err;
}

// glTF 2.0 with one triangle in tri.bin (3 float positions); `accessor` is the POSITION accessor.
std::string gltfWith(const std::string &accessor, const std::string &nodes = R"([{"mesh": 0}])",
                     const std::string &rootNodes = "[0]") {
    return R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": )" + rootNodes + R"(}], "nodes": )" + nodes +
           R"(, "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
             "buffers": [{"uri": "tri.bin", "byteLength": 36}],
             "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}],
             "accessors": [)" + accessor + "]}";
}
void writeTriangleBin(const fs::path &p) {
    const float v[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    std::ofstream(p, std::ios::binary).write(reinterpret_cast<const char *>(v), sizeof v);
}

// Hostile glTF: an accessor claiming 1e12 elements with no buffer view behind it (glTF reads that
// as zeros, so no byte of the file bounds it) needed 24 TB before; now the triangle limit refuses it.
TEST_F(LimitsTest, HostileGltfAccessorWithoutBuffer) {
    writeTriangleBin(dir_ / "tri.bin");
    write("h.gltf", gltfWith(R"({"componentType": 5126, "count": 1000000000000, "type": "VEC3"})"));
    const auto r = runBinary({"info", path("h.gltf")}, dir_);
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.err, "visaudit: error: " + path("h.gltf") + ": mesh 0 primitive 0 (node 'node0'): the scene up to "
                     "this primitive needs 333333333333 triangles, more than the limit of 100000000; raise it with "
                     "--max-triangles 333333333333 if the machine has the memory (about 77.61 TiB), or the file is damaged\n");
    EXPECT_LT(r.maxRssKiB, refusedPeakKiB());
}

// Hostile glTF: a count within the limits but far past its 36-byte buffer was allocated (7.2 GB of
// doubles) before the bounds check; now the bounds are checked first.
TEST_F(LimitsTest, HostileGltfAccessorPastItsBuffer) {
    writeTriangleBin(dir_ / "tri.bin");
    write("h.gltf", gltfWith(R"({"bufferView": 0, "componentType": 5126, "count": 299999999, "type": "VEC3"})"));
    const auto r = runBinary({"info", path("h.gltf")}, dir_);
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.err, "visaudit: error: " + path("h.gltf") + ": mesh 0 primitive 0 (node 'node0'): POSITION accessor 0 "
                     "reads past the end of its buffer view or buffer (299999999 elements); the file is truncated or "
                     "inconsistent\n");
    EXPECT_LT(r.maxRssKiB, refusedPeakKiB());
}

// Every node instancing the mesh counts: three nodes of one triangle under a limit of 2.
TEST_F(LimitsTest, GltfInstancesCount) {
    writeTriangleBin(dir_ / "tri.bin");
    write("i.gltf", gltfWith(R"({"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                                  "min": [0, 0, 0], "max": [1, 1, 0]})",
                             R"([{"mesh": 0}, {"mesh": 0}, {"mesh": 0}])", "[0, 1, 2]"));
    SceneBuildInput in;
    std::string err;
    ASSERT_TRUE(loadGltf(path("i.gltf"), &in, &err, 3)) << err;
    EXPECT_EQ(in.objects.size(), 3u);
    EXPECT_FALSE(loadGltf(path("i.gltf"), &in, &err, 2));
    EXPECT_EQ(err, path("i.gltf") + ": mesh 0 primitive 0 (node 'node2'): the scene up to this primitive needs 3 "
                   "triangles, more than the limit of 2; raise it with --max-triangles 3 if the machine has the memory "
                   "(about 768 B), or the file is damaged");
}

// A glass slab: refraction doubles the rays at every level, so --max-depth is bounded by
// --max-recursion when refraction runs, and not when nothing traces secondary rays.
TEST(Limits, RecursionDepth) {
    Material glass;
    glass.name = "glass";
    glass.ior = 1.5;
    const Scene scene = testing_util::sceneOf({testing_util::triangleMesh({-1, -1, 0}, {1, -1, 0}, {0, 1, 0})},
                                              {Material{}, glass}, {1});
    ViewSpec v;
    v.name = "v";
    v.camera.width = 8;
    v.camera.height = 8;
    PipelineSettings s;
    s.effects.maxDepth = 20;
    AnalysisResult result;
    std::string err;
    EXPECT_FALSE(analyzeScene(scene, {v}, s, nullptr, &result, &err));
    EXPECT_EQ(err, "--max-depth 20 needs a recursion depth of 20, more than the limit of 16 (with refraction a pixel "
                   "may trace 2^21 - 2 secondary rays); lower --max-depth or raise the limit with --max-recursion 20");
    s.limits.maxRecursion = 20;
    ASSERT_TRUE(analyzeScene(scene, {v}, s, nullptr, &result, &err)) << err;
    EXPECT_TRUE(result.views[0].effects.ran());

    // Without a refractive or reflective material no secondary ray is traced: no limit applies.
    const Scene plain = testing_util::sceneOf({testing_util::triangleMesh({-1, -1, 0}, {1, -1, 0}, {0, 1, 0})});
    s.limits.maxRecursion = 16;
    EXPECT_TRUE(analyzeScene(plain, {v}, s, nullptr, &result, &err)) << err;
}

// Screen triangles covering a whole w x h viewport `layers` times: one triangle per layer,
// (0, 0), (2w, 0), (0, 2h), whose hypotenuse passes the viewport's far corner, constant depth.
ScreenTriangles layersOverViewport(int layers, int w, int h) {
    ScreenTriangles st;
    const int32_t X = 2 * w * kSubpixelOne, Y = 2 * h * kSubpixelOne;
    for (int k = 0; k < layers; ++k) {
        const std::array<int32_t, 6> xy = {0, 0, X, 0, 0, Y};
        st.xy.insert(st.xy.end(), xy.begin(), xy.end());
        st.source.push_back(uint32_t(k));
        st.plane.push_back(uint32_t(k));
        DepthPlane p;
        p.c = 1 + k;
        p.valid = true;
        st.planes.push_back(p);
    }
    return st;
}

// Ten layers make lists of 10 in every pixel, (0, 0) the first: refused at 9 with nothing built,
// resolved at 10.
TEST(Limits, ABufferListLength) {
    const ScreenTriangles st = layersOverViewport(10, 4, 3);
    std::vector<float> alpha(10, 0.5f);
    ABufferMaterials m;
    m.alpha = alpha.data();
    ABufferResult r = resolveABuffer(st, 4, 3, true, m, 9);
    EXPECT_EQ(r.error, "A-buffer: pixel (0, 0) needs a list of 10 fragments, more than the limit of 9; raise it with "
                       "--max-abuffer-list 10 (or turn the A-buffer off with --no-abuffer)");
    EXPECT_EQ(r.fragments, 0u);
    EXPECT_TRUE(r.rgb.empty());
    r = resolveABuffer(st, 4, 3, true, m, 10);
    EXPECT_TRUE(r.error.empty());
    EXPECT_EQ(r.maxListLength, 10u);
    EXPECT_EQ(r.fragments, 120u);
}

// Through the pipeline: the A-buffer's refusal stops the run with the view's name.
TEST(Limits, ABufferLimitStopsTheRun) {
    Material glass;
    glass.name = "glass";
    glass.alpha = 0.5;
    std::vector<RawMesh> meshes;
    for (int k = 0; k < 3; ++k)
        meshes.push_back(testing_util::triangleMesh({-5, -5, -double(k)}, {5, -5, -double(k)}, {0, 5, -double(k)}));
    const Scene scene = testing_util::sceneOf(meshes, {Material{}, glass}, {1, 1, 1});
    ViewSpec v;
    v.name = "v";
    v.camera.width = 16;
    v.camera.height = 16;
    PipelineSettings s;
    s.limits.maxABufferList = 2;
    AnalysisResult result;
    std::string err;
    EXPECT_FALSE(analyzeScene(scene, {v}, s, nullptr, &result, &err));
    EXPECT_EQ(err.rfind("view 'v': A-buffer: pixel (", 0), 0u) << err;
    EXPECT_NE(err.find(") needs a list of 3 fragments, more than the limit of 2; raise it with --max-abuffer-list 3"),
              std::string::npos)
        << err;
    s.limits.maxABufferList = 3;
    ASSERT_TRUE(analyzeScene(scene, {v}, s, nullptr, &result, &err)) << err;
    ASSERT_TRUE(result.views[0].ordering->abufferRan);
    EXPECT_EQ(result.views[0].ordering->abuffer.maxListLength, 3u);
}

}  // namespace
}  // namespace va
