// The benchmark table of issue 8: every figure beside its peer, measured in the same run, on the
// benchmark scene (bench/bench_scene.h: 1,000,002 triangles, benchmarkCamera, 1920x1080).
//
//   bash bench/run.sh [--quick] [--sections LIST] [--reps N] [--keep]      (builds, then runs this)
//   bench_table --visaudit PATH [same options] [--baseline PATH] [--level-reps N]
//   bash bench/run.sh --baseline [...]   (also builds issue 18's start: bench/issue18_baseline.sh)
//
// Sections (LIST is comma-separated; default all):
//   zbuffer   rasterize() on one thread (tbb::global_control 1) and on all threads, without and with
//             the backface stage before it; M triangles/s over the 1,000,002 input triangles
//   llvmpipe  Mesa's llvmpipe drawing the same triangles (bench/llvmpipe.h), one thread
//   raycast   RayScene::castPrimary against raw rtcIntersect16 packets over the same rays
//   load      the scene written once as OBJ, glTF and binary PLY, read by loadScene (the real loaders)
//   analyze   `visaudit analyze` on 16 orbit views, end to end, against the sum of report.json's timings
//   scaling   `visaudit analyze` on 10k..10M triangles x 1..64 views: wall time and peak memory
//   pipeline  the game's pipeline on one thread, stage by stage (frustum, backface, clip, z-buffer),
//             in M scene triangles/s against issue 18's floors
//   level     `visaudit analyze` on a real level (data/openarena oa_thor, --views spawns, 1920x1080,
//             2 threads): wall time against issue 18's baseline and where the time goes, per part
// Floors are printed as PASS/FAIL beside their figures; the exit status is 0 whatever they say (the
// benchmark never gates CI). One-thread figures are CPU time of the working thread (the machine is
// shared), all-thread figures wall time; every figure is the best of N repetitions.
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include "analysis/load/load.h"
#include "analysis/stages/backface.h"
#include "analysis/stages/frustum.h"
#include "bench/bench_scene.h"
#include "common/process_heap.h"
#include "render/clip.h"
#include "render/raster.h"
#include "render/raycast.h"
#ifdef VISAUDIT_BENCH_LLVMPIPE
#include "bench/llvmpipe.h"
#endif

namespace fs = std::filesystem;
using namespace va;

namespace {

double threadCpu() {
    timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}
double wallNow() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }
double best(std::vector<double> v) { return v.empty() ? NAN : *std::min_element(v.begin(), v.end()); }

std::string fmt(const char *f, ...) __attribute__((format(printf, 1, 2)));
std::string fmt(const char *f, ...) {
    char b[512];
    va_list ap;
    va_start(ap, f);
    std::vsnprintf(b, sizeof b, f, ap);
    va_end(ap);
    return b;
}
void progress(const std::string &s) { std::fprintf(stderr, "bench: %s\n", s.c_str()); }

// The one table: rows of (figure, value, peer, ratio, floor, verdict), printed at the end.
struct Table {
    struct Row {
        std::string figure, value, peer, ratio, floor, verdict;
    };
    std::vector<Row> rows;
    std::vector<std::string> notes;
    void add(Row r) { rows.push_back(std::move(r)); }
    void rule(const std::string &title) { rows.push_back({"## " + title, "", "", "", "", ""}); }
    void print() const {
        size_t w[6] = {6, 5, 15, 5, 5, 7};  // at least the headings
        auto cols = [](const Row &r) { return std::vector<const std::string *>{&r.figure, &r.value, &r.peer, &r.ratio, &r.floor, &r.verdict}; };
        for (const Row &r : rows)
            if (r.figure.rfind("## ", 0) != 0) {
                const auto c = cols(r);
                for (int k = 0; k < 6; ++k) w[k] = std::max(w[k], c[size_t(k)]->size());
            }
        const Row head{"figure", "value", "peer (same run)", "ratio", "floor", "verdict"};
        auto line = [&](const Row &r) {
            const auto c = cols(r);
            std::string s = "|";
            for (int k = 0; k < 6; ++k) s += " " + *c[size_t(k)] + std::string(w[k] - c[size_t(k)]->size(), ' ') + " |";
            std::printf("%s\n", s.c_str());
        };
        line(head);
        std::string sep = "|";
        for (int k = 0; k < 6; ++k) sep += std::string(w[k] + 2, '-') + "|";
        std::printf("%s\n", sep.c_str());
        for (const Row &r : rows) {
            if (r.figure.rfind("## ", 0) == 0) {  // a section heading: one cell, not padded
                std::printf("| **%s** |  |  |  |  |  |\n", r.figure.substr(3).c_str());
                continue;
            }
            line(r);
        }
        for (const std::string &n : notes) std::printf("%s\n", n.c_str());
    }
};
std::string verdict(bool ok) { return ok ? "PASS" : "FAIL"; }

struct Options {
    std::set<std::string> sections;
    bool quick = false, keep = false;
    int reps = 7;
    std::string visaudit;
    fs::path work;
    fs::path data;  // the project's fetched data (scripts/fetch-data.sh): the level section's map
    // A visaudit built at issue 18's start (bench/issue18_baseline.sh): the level section runs it
    // too, in the same run, and compares with that instead of the 118 s measured on another machine.
    std::string baseline;
    int levelReps = 1;  // runs of each build in the level section (--level-reps), the fastest kept
    bool on(const std::string &s) const { return sections.count(s) > 0; }
};

// ---- Scene files -------------------------------------------------------------------------------

void appendFloat(std::string &s, double x) {
    char b[32];
    const auto r = std::to_chars(b, b + sizeof b, float(x));  // shortest text that reads back as the float
    s.append(b, r.ptr);
}

bool writeObj(const fs::path &p, const RawMesh &m) {
    std::string s;
    s.reserve(m.positions.size() * 36 + m.indices.size() * 9);
    for (const Vec3 &v : m.positions) {
        s += "v ";
        appendFloat(s, v.x), s += ' ', appendFloat(s, v.y), s += ' ', appendFloat(s, v.z), s += '\n';
    }
    char b[16];
    for (size_t t = 0; t < m.indices.size(); t += 3) {
        s += 'f';
        for (int k = 0; k < 3; ++k) {
            s += ' ';
            s.append(b, std::to_chars(b, b + sizeof b, m.indices[t + size_t(k)] + 1).ptr);
        }
        s += '\n';
    }
    std::ofstream f(p, std::ios::binary);
    f.write(s.data(), std::streamsize(s.size()));
    return bool(f);
}

bool writePly(const fs::path &p, const RawMesh &m) {
    std::ofstream f(p, std::ios::binary);
    f << "ply\nformat binary_little_endian 1.0\nelement vertex " << m.positions.size()
      << "\nproperty float x\nproperty float y\nproperty float z\nelement face " << m.indices.size() / 3
      << "\nproperty list uchar int vertex_indices\nend_header\n";
    std::vector<char> buf;
    buf.reserve(m.positions.size() * 12 + m.indices.size() / 3 * 13);
    auto put = [&](const void *d, size_t n) { buf.insert(buf.end(), (const char *)d, (const char *)d + n); };
    for (const Vec3 &v : m.positions) {
        const float x[3] = {float(v.x), float(v.y), float(v.z)};
        put(x, 12);
    }
    for (size_t t = 0; t < m.indices.size(); t += 3) {
        const uint8_t n = 3;
        put(&n, 1);
        put(&m.indices[t], 12);
    }
    f.write(buf.data(), std::streamsize(buf.size()));
    return bool(f);
}

// glTF 2.0: one mesh, one node, positions (float VEC3) and indices (uint32) in one .bin buffer.
bool writeGltf(const fs::path &p, const RawMesh &m) {
    std::vector<float> pos;
    pos.reserve(m.positions.size() * 3);
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (const Vec3 &v : m.positions)
        for (int a = 0; a < 3; ++a) {
            const float x = float(v[a]);
            pos.push_back(x);
            lo[a] = std::min(lo[a], x), hi[a] = std::max(hi[a], x);
        }
    const size_t posBytes = pos.size() * 4, idxBytes = m.indices.size() * 4;
    const fs::path bin = fs::path(p).replace_extension(".bin");
    {
        std::ofstream f(bin, std::ios::binary);
        f.write((const char *)pos.data(), std::streamsize(posBytes));
        f.write((const char *)m.indices.data(), std::streamsize(idxBytes));
        if (!f) return false;
    }
    nlohmann::json j = {
        {"asset", {{"version", "2.0"}}},
        {"scene", 0},
        {"scenes", {{{"nodes", {0}}}}},
        {"nodes", {{{"mesh", 0}, {"name", "sphere_grid"}}}},
        {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}}}}}},
        {"buffers", {{{"uri", bin.filename().string()}, {"byteLength", posBytes + idxBytes}}}},
        {"bufferViews",
         {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", posBytes}, {"target", 34962}},
          {{"buffer", 0}, {"byteOffset", posBytes}, {"byteLength", idxBytes}, {"target", 34963}}}},
        {"accessors",
         {{{"bufferView", 0}, {"componentType", 5126}, {"count", m.positions.size()}, {"type", "VEC3"},
           {"min", {lo[0], lo[1], lo[2]}}, {"max", {hi[0], hi[1], hi[2]}}},
          {{"bufferView", 1}, {"componentType", 5125}, {"count", m.indices.size()}, {"type", "SCALAR"}}}}};
    std::ofstream f(p);
    f << j.dump();
    return bool(f);
}

Scene sceneOfMesh(RawMesh mesh) {
    SceneBuildInput in;
    in.materials.push_back(Material{});
    in.objects.push_back({"sphere_grid", "sphere_grid", 0, std::move(mesh)});
    return buildScene(std::move(in));
}

// One clip batch per object group, as the pipeline's clip stage makes them.
ClipResult clipLists(const Scene &s, const Camera &cam, const TriangleLists &lists) {
    return clipTriangles(cam, MeshView{s.positions.data(), s.indices.data()}, clipBatches(s, lists), {});
}

// ---- Child processes ---------------------------------------------------------------------------

struct ChildRun {
    int status = -1;
    double wallS = 0;
    double peakMiB = 0;  // ru_maxrss of the child
};
ChildRun runChild(const std::vector<std::string> &argv, const fs::path &log) {
    ChildRun r;
    const double w0 = wallNow();
    const pid_t pid = fork();
    if (pid == 0) {
        FILE *f = std::fopen(log.c_str(), "w");
        if (f) dup2(fileno(f), 1), dup2(fileno(f), 2);
        std::vector<char *> a;
        for (const std::string &s : argv) a.push_back(const_cast<char *>(s.c_str()));
        a.push_back(nullptr);
        execv(a[0], a.data());
        _exit(127);
    }
    int st = 0;
    rusage ru{};
    wait4(pid, &st, 0, &ru);
    r.wallS = wallNow() - w0;
    r.status = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
    r.peakMiB = double(ru.ru_maxrss) / 1024.0;  // Linux: kilobytes
    return r;
}

// report.json: load + ray scene build + BSP tree + every view's stages and audits + the output
// phase (images, the report in memory, report.html): the timed parts.
struct ReportTimes {
    double loadMs = 0, raySceneMs = 0, bspMs = 0, stagesMs = 0, auditsMs = 0, viewsTotalMs = 0;
    double imagesMs = 0, reportMs = 0, htmlMs = 0;
    size_t views = 0;
    double outputMs() const { return imagesMs + reportMs + htmlMs; }
    double sum() const { return loadMs + raySceneMs + bspMs + stagesMs + auditsMs + outputMs(); }
};
// A report.json read whole; false with the reason when it is missing or not JSON.
bool readReportJson(const fs::path &p, nlohmann::json *j, std::string *err) {
    std::ifstream f(p);
    if (!f) {
        *err = p.string() + ": not written";
        return false;
    }
    try {
        f >> *j;
    } catch (const std::exception &e) {
        *err = p.string() + ": " + e.what();
        return false;
    }
    return true;
}
// A report's number field, 0 when the object or the key is absent.
double num(const nlohmann::json &o, const char *k) {
    return o.is_object() && o.contains(k) && o[k].is_number() ? o[k].get<double>() : 0.0;
}
bool readReportTimes(const fs::path &p, ReportTimes *t, std::string *err) {
    nlohmann::json j;
    if (!readReportJson(p, &j, err)) return false;
    t->loadMs = num(j, "load_ms");
    if (j.contains("effects")) t->raySceneMs = num(j["effects"], "ray_scene_build_ms");
    if (j.contains("bsp_tree") && j["bsp_tree"].is_object()) t->bspMs = num(j["bsp_tree"], "build_ms");
    if (j.contains("output") && j["output"].is_object()) {
        t->imagesMs = num(j["output"], "images_ms");
        t->reportMs = num(j["output"], "report_ms");
        t->htmlMs = num(j["output"], "html_ms");
    }
    for (const auto &v : j["views"]) {
        ++t->views;
        t->viewsTotalMs += num(v, "total_ms");
        for (const auto &s : v["stages"]) t->stagesMs += num(s, "ms");
        // The audits outside the stage list (docs/report-schema.json: their "ms" fields).
        for (const char *k : {"audit", "depth", "ordering", "detail"})
            if (v.contains(k) && v[k].is_object()) t->auditsMs += num(v[k], "ms");
        if (v.contains("raycast") && v["raycast"].is_object())
            for (const char *k : {"cross_check", "effects"})
                if (v["raycast"].contains(k) && v["raycast"][k].is_object()) t->auditsMs += num(v["raycast"][k], "ms");
    }
    return true;
}

// ---- Sections ----------------------------------------------------------------------------------

struct ZbufferFigures {
    double oneS = NAN, allS = NAN, oneCullS = NAN, allCullS = NAN, clipS = NAN;
    uint64_t fragments = 0, depthPasses = 0, fragmentsCulled = 0, kept = 0;
};

ZbufferFigures runZbuffer(const Options &o, const Scene &scene, const Camera &cam) {
    ZbufferFigures z;
    std::vector<uint32_t> objects(scene.objects.size());
    for (uint32_t i = 0; i < objects.size(); ++i) objects[i] = i;
    const TriangleLists all = allTriangles(scene, objects);
    ZBufferSettings zs;
    zs.encoder = makeDepthEncoder(DepthFormat::f32, cam.nearZ, cam.farZ);
    zs.orthographic = cam.orthographic;
    ClipResult clip;
    {
        tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
        std::vector<double> t;
        for (int r = 0; r < std::max(1, o.reps / 2); ++r) {
            recycleScreenTriangles(clip.out);  // the previous repetition's, as a finished view's
            const double c0 = threadCpu();
            clip = clipLists(scene, cam, all);
            t.push_back(threadCpu() - c0);
        }
        z.clipS = best(t);
    }
    // With the backface stage: it culls, the survivors are clipped (untimed, like the plain run's
    // clip), and rasterize() draws them; the figure times the stage and rasterize().
    const BackfaceResult bf = cullBackfaces(scene, objects, cam);
    const ClipResult keptClip = clipLists(scene, cam, bf.kept);
    z.kept = bf.kept.size();
    for (int threads : {1, 0}) {
        std::optional<tbb::global_control> limit;
        if (threads) limit.emplace(tbb::global_control::max_allowed_parallelism, size_t(threads));
        auto now = [&] { return threads ? threadCpu() : wallNow(); };
        std::vector<double> plain, culled;
        for (int r = 0; r < o.reps; ++r) {
            // Each buffer given back after its repetition, as a finished view's (render/recycle.h;
            // llvmpipe's framebuffer, too, is made once and drawn into again).
            double t0 = now();
            ZBufferResult res = rasterize(clip.out, cam.width, cam.height, zs);
            plain.push_back(now() - t0);
            z.fragments = res.stats.fragments;
            z.depthPasses = res.stats.depthPasses;
            recycleZBuffer(res.buffer);
            t0 = now();
            const BackfaceResult b = cullBackfaces(scene, objects, cam);
            ZBufferResult rc = rasterize(keptClip.out, cam.width, cam.height, zs);
            culled.push_back(now() - t0);
            z.fragmentsCulled = rc.stats.fragments;
            recycleZBuffer(rc.buffer);
            if (b.kept.size() != z.kept) std::abort();
        }
        (threads ? z.oneS : z.allS) = best(plain);
        (threads ? z.oneCullS : z.allCullS) = best(culled);
    }
    return z;
}

// The game's pipeline, one thread, stage by stage as analysis/pipeline.cpp runs them: thread CPU
// time of each, best of N (each stage's input is the previous stage's output of the same run).
struct PipelineFigures {
    double frustumS = NAN, backfaceS = NAN, clipS = NAN, zbufferS = NAN, totalS = NAN;
    uint64_t objects = 0, visibleObjects = 0, kept = 0, screenTriangles = 0;
};

PipelineFigures runPipeline(const Options &o, const Scene &scene, const Camera &cam) {
    PipelineFigures f;
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    const ObjectBvh bvh = buildObjectBvh(scene);
    ZBufferSettings zs;
    zs.encoder = makeDepthEncoder(DepthFormat::f32, cam.nearZ, cam.farZ);
    zs.orthographic = cam.orthographic;
    std::vector<double> tf, tb, tc, tz, tt;
    for (int r = 0; r < o.reps; ++r) {
        double c0 = threadCpu();
        const FrustumResult fr = cullFrustum(scene, bvh, cam);
        const double c1 = threadCpu();
        const BackfaceResult bf = cullBackfaces(scene, fr.visible, cam);
        const double c2 = threadCpu();
        ClipResult clip = clipLists(scene, cam, bf.kept);
        const double c3 = threadCpu();
        ZBufferResult z = rasterize(clip.out, cam.width, cam.height, zs);
        const double c4 = threadCpu();
        tf.push_back(c1 - c0), tb.push_back(c2 - c1), tc.push_back(c3 - c2), tz.push_back(c4 - c3), tt.push_back(c4 - c0);
        f.objects = scene.objects.size(), f.visibleObjects = fr.visible.size(), f.kept = bf.kept.size();
        f.screenTriangles = clip.out.size();
        // Given back as analyzeView gives a finished view's (render/recycle.h): the next repetition
        // is the next view, filling the same memory.
        recycleScreenTriangles(clip.out);
        recycleZBuffer(z.buffer);
    }
    f.frustumS = best(tf), f.backfaceS = best(tb), f.clipS = best(tc), f.zbufferS = best(tz), f.totalS = best(tt);
    return f;
}

// Per part of a real level's analyze run, summed over its views from report.json (CPU time of the
// view's thread; the parts of issue 18's table).
struct LevelParts {
    double ordering = 0, images = 0, reportHtml = 0, zfight = 0, raycast = 0, referenceAndCross = 0, pipeline = 0,
           detail = 0, viewsTotal = 0, load = 0, raySceneBuild = 0, bspBuild = 0;
    size_t views = 0;
    uint64_t triangles = 0;
    int width = 0, height = 0;
    bool orderingRan = false;  // in some view
};
bool readLevelParts(const fs::path &p, LevelParts *t, std::string *err) {
    nlohmann::json j;
    if (!readReportJson(p, &j, err)) return false;
    t->load = num(j, "load_ms");
    if (j.contains("effects")) t->raySceneBuild = num(j["effects"], "ray_scene_build_ms");
    if (j.contains("bsp_tree")) t->bspBuild = num(j["bsp_tree"], "build_ms");
    if (j.contains("scene")) t->triangles = uint64_t(num(j["scene"], "triangles"));
    if (j.contains("output")) {
        t->images = num(j["output"], "images_ms");
        t->reportHtml = num(j["output"], "report_ms") + num(j["output"], "html_ms");
    }
    for (const auto &v : j["views"]) {
        ++t->views;
        t->width = int(num(v, "width")), t->height = int(num(v, "height"));
        t->viewsTotal += num(v, "total_ms");
        for (const auto &s : v["stages"]) {
            const std::string name = s.value("name", "");
            (name == "raycast" ? t->raycast : t->pipeline) += num(s, "ms");
        }
        if (v.contains("ordering")) {
            t->ordering += num(v["ordering"], "ms");
            t->orderingRan = t->orderingRan || v["ordering"].value("ran", false);
        }
        if (v.contains("depth")) t->zfight += num(v["depth"], "ms");
        if (v.contains("detail")) t->detail += num(v["detail"], "ms");
        if (v.contains("audit")) t->referenceAndCross += num(v["audit"], "ms");
        if (v.contains("raycast") && v["raycast"].contains("cross_check"))
            t->referenceAndCross += num(v["raycast"]["cross_check"], "ms");
    }
    return true;
}

}  // namespace

// What the sections share: the options, the table they fill, the benchmark scene and its camera,
// the z-buffer figures (zbuffer and llvmpipe), llvmpipe's (pipeline compares with them), and the
// scene written as files (load, analyze).
struct Bench {
    explicit Bench(const Options &options) : o(options) {}
    const Options &o;
    Table table;
    unsigned cores = 0;
    RawMesh mesh;
    Camera cam;
    double tris = 0;
    ZbufferFigures z;
    double lpOne = NAN, lpCull = NAN;
    std::string lpNote;
    fs::path objPath, gltfPath, plyPath;
    std::string err;
    // The sections; each returns 0 or the exit code of a failure it has reported.
    int sectionLlvmpipe();
    int sectionZbuffer();
    int sectionRaycast();
    int sectionPipeline();
    int sectionLevel();
    int sectionLoad();
    int sectionAnalyze();
    int sectionScaling();
    // The per-part rows of an analyze run's report (issue 18's table): each audit's share of the
    // views' CPU time, the output phase's of the run's, with their floors; `start` (may be null):
    // the same parts of issue 18's start in this run, in the peer column.
    void partRows(const LevelParts &L, const LevelParts *start = nullptr);
};

// The "llvmpipe" section of the table (README, "Benchmarks": what it measures).
int Bench::sectionLlvmpipe() {
#ifdef VISAUDIT_BENCH_LLVMPIPE
    progress("llvmpipe");
    std::vector<float> pos;
    for (const Vec3 &p : mesh.positions) pos.insert(pos.end(), {float(p.x), float(p.y), float(p.z)});
    float m[16];
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) m[4 * r + c] = float(cam.clipFromWorld.m[r][c]);
    const bench::LlvmpipeRun lp = bench::drawWithLlvmpipe(pos, mesh.indices, m, cam.width, cam.height, o.reps);
    if (lp.ok) {
        lpOne = best(lp.cpuSeconds);
        lpCull = best(lp.cullCpuSeconds);
        lpNote = fmt("llvmpipe: renderer \"%s\", LP_NUM_THREADS=0, D24S8 FBO, color writes off, depth LESS; "
                     "samples covered %llu (ours: %llu fragments), depth passes %llu (ours: %llu); "
                     "process CPU time of clear + draw + glFinish (wall best %.1f ms)",
                     lp.renderer.c_str(), (unsigned long long)lp.samplesCovered, (unsigned long long)z.fragments,
                     (unsigned long long)lp.samplesPassed, (unsigned long long)z.depthPasses,
                     1e3 * best(lp.wallSeconds));
    } else {
        lpNote = "llvmpipe: not measured: " + lp.error;
    }
#else
    lpNote = "llvmpipe: not measured: bench_table was built without EGL/OpenGL (scripts/install-deps.sh)";
#endif
    return 0;
}

// The "zbuffer" section of the table (README, "Benchmarks": what it measures).
int Bench::sectionZbuffer() {
    table.rule("zbuffer (f32, 1920x1080, 1,000,002 triangles in; rasterize() on clipped triangles)");
    const bool havePeer = std::isfinite(lpOne);
    const std::string peer = havePeer ? fmt("llvmpipe 1 thread: %.2f M tri/s", tris / lpOne * 1e-6) : "llvmpipe: n/a";
    const double mOne = tris / z.oneS * 1e-6;
    table.add({"zbuffer, 1 thread, no backface", fmt("%.2f M tri/s, %.1f M frag/s", mOne, z.fragments / z.oneS * 1e-6),
               peer, havePeer ? fmt("%.2fx", lpOne / z.oneS) : "",
               ">= 30 M tri/s, >= 3x llvmpipe",
               verdict(mOne >= 30 && (!havePeer || lpOne / z.oneS >= 3))});
    table.add({fmt("zbuffer, all threads (%u), no backface", cores),
               fmt("%.2f M tri/s, %.1f M frag/s", tris / z.allS * 1e-6, z.fragments / z.allS * 1e-6),
               fmt("1 thread: %.2f M tri/s", mOne), fmt("%.2fx", z.oneS / z.allS), "", ""});
    const std::string cullPeer = std::isfinite(lpCull) ? fmt("llvmpipe 1 thread, GL_CULL_FACE: %.2f M tri/s", tris / lpCull * 1e-6) : "";
    table.add({"zbuffer, 1 thread, backface stage + rasterize",
               fmt("%.2f M tri/s, %.1f M frag/s", tris / z.oneCullS * 1e-6, z.fragmentsCulled / z.oneCullS * 1e-6),
               cullPeer, std::isfinite(lpCull) ? fmt("%.2fx", lpCull / z.oneCullS) : "", "", ""});
    table.add({fmt("zbuffer, all threads (%u), backface stage + rasterize", cores),
               fmt("%.2f M tri/s, %.1f M frag/s", tris / z.allCullS * 1e-6, z.fragmentsCulled / z.allCullS * 1e-6),
               fmt("1 thread: %.2f M tri/s", tris / z.oneCullS * 1e-6), fmt("%.2fx", z.oneCullS / z.allCullS), "", ""});
    table.add({"clip + zbuffer, 1 thread, no backface (what llvmpipe's draw includes)",
               fmt("%.2f M tri/s (clip %.1f ms)", tris / (z.clipS + z.oneS) * 1e-6, 1e3 * z.clipS), peer,
               havePeer ? fmt("%.2fx", lpOne / (z.clipS + z.oneS)) : "", "", ""});
    table.notes.push_back(fmt("zbuffer: %llu fragments, %llu depth passes; backface stage keeps %llu of %.0f triangles "
                              "(%llu fragments)", (unsigned long long)z.fragments, (unsigned long long)z.depthPasses,
                              (unsigned long long)z.kept, tris, (unsigned long long)z.fragmentsCulled));
    return 0;
}

// The "raycast" section of the table (README, "Benchmarks": what it measures).
int Bench::sectionRaycast() {
    progress("raycast: BVH build");
    std::vector<uint32_t> ids(mesh.indices.size() / 3);
    for (uint32_t t = 0; t < ids.size(); ++t) ids[t] = t;
    Aabb bounds;
    for (const Vec3 &p : mesh.positions) bounds.extend(p);
    RayScene rs;
    const double b0 = wallNow();
    if (!rs.build({mesh.positions.data(), mesh.indices.data()}, mesh.positions.size(), ids, bounds.center(), &err)) {
        std::fprintf(stderr, "bench_table: %s\n", err.c_str());
        return 3;
    }
    const double buildS = wallNow() - b0;
    progress("raycast");
    // The raycast stage's own options (analysis/pipeline.cpp): back-face rejection, ties to the lowest id.
    const Scene scene = sceneOfMesh(mesh);
    PrimaryOptions stage;
    stage.rejectBackFaces = true;
    stage.planes = scene.planes.data();
    stage.tiesToLowestId = true;
    std::vector<double> raw, one, all, stageOne;
    uint64_t rawHits = 0;
    RaycastStats st;
    for (int r = 0; r < o.reps; ++r) {  // interleaved, so that all see the same machine load
        double c0 = threadCpu();
        rawHits = rs.castPrimaryRaw(cam);
        raw.push_back(threadCpu() - c0);
        {
            tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
            // Each image given back after its cast, as a finished view's (render/recycle.h): the
            // next cast fills it instead of faulting fresh pages in.
            c0 = threadCpu();
            RaycastImage img = rs.castPrimary(cam, &st);
            one.push_back(threadCpu() - c0);
            recycleRaycastImage(img);
            c0 = threadCpu();
            RaycastImage img2 = rs.castPrimary(cam, stage, nullptr);
            stageOne.push_back(threadCpu() - c0);
            recycleRaycastImage(img2);
        }
        const double w0 = wallNow();
        RaycastImage img = rs.castPrimary(cam, nullptr);
        all.push_back(wallNow() - w0);
        recycleRaycastImage(img);
    }
    const double rays = double(cam.width) * cam.height;
    table.rule(fmt("raycast (Embree BVH build %.2f s; %.0f rays, %llu hits)", buildS, rays, (unsigned long long)st.hits));
    const double ratio = best(raw) / best(one);
    table.add({"castPrimary, 1 thread (ids + depths written)", fmt("%.2f M rays/s", rays / best(one) * 1e-6),
               fmt("raw rtcIntersect16, 1 thread: %.2f M rays/s", rays / best(raw) * 1e-6), fmt("%.3fx", ratio),
               ">= 0.9x raw", verdict(ratio >= 0.9 && rawHits == st.hits)});
    table.add({fmt("castPrimary, all threads (%u)", cores), fmt("%.2f M rays/s", rays / best(all) * 1e-6),
               fmt("raw, 1 thread: %.2f M rays/s", rays / best(raw) * 1e-6), fmt("%.2fx", best(raw) / best(all)), "", ""});
    table.add({"castPrimary as the raycast stage calls it (back-face rejection, ties), 1 thread",
               fmt("%.2f M rays/s", rays / best(stageOne) * 1e-6),
               fmt("raw, 1 thread: %.2f M rays/s", rays / best(raw) * 1e-6), fmt("%.3fx", best(raw) / best(stageOne)),
               "", ""});
    return 0;
}

// The "pipeline" section of the table (README, "Benchmarks": what it measures).
int Bench::sectionPipeline() {
    progress("pipeline: frustum, backface, clip, z-buffer on one thread");
    const Scene scene = sceneOfMesh(mesh);
    const PipelineFigures f = runPipeline(o, scene, cam);
    table.rule(fmt("the game's pipeline, 1 thread (1,000,002 triangles, %llu object(s), 1920x1080, f32; M scene "
                   "triangles/s: the 1,000,002 input triangles over each stage's time)",
                   (unsigned long long)f.objects));
    auto mtri = [&](double sec) { return tris / sec * 1e-6; };
    // The floors are M tri/s on the machine where the anchors were measured (llvmpipe 13 M tri/s
    // with GL_CULL_FACE there). With the llvmpipe section in the same run, each floor is also shown
    // scaled by llvmpipe's pace here over its anchor, and judged on that too: a machine's speed is
    // then taken out by a peer measured beside the figure.
    constexpr double kLlvmpipeCullAnchor = 13;
    const double scale = std::isfinite(lpCull) ? mtri(lpCull) / kLlvmpipeCullAnchor : NAN;
    auto floorText = [&](double floor) {
        return std::isfinite(scale) ? fmt(">= %.0f M tri/s; x %.2f here: >= %.1f", floor, scale, floor * scale)
                                    : fmt(">= %.0f M tri/s", floor);
    };
    auto judge = [&](double sec, double floor) {
        const std::string v = verdict(mtri(sec) >= floor);
        return std::isfinite(scale) ? v + "; here " + verdict(mtri(sec) >= floor * scale) : v;
    };
    table.add({"frustum + backface + clip + z-buffer", fmt("%.2f M tri/s (%.1f ms)", mtri(f.totalS), 1e3 * f.totalS),
               "Masked Occlusion Culling 1 thread, backface on: ~49 M tri/s (anchor, approximate)",
               std::isfinite(lpCull) ? fmt("%.2fx llvmpipe GL_CULL_FACE here", lpCull / f.totalS) : "",
               floorText(40), judge(f.totalS, 40)});
    table.add({"frustum", fmt("%.1f M tri/s (%.2f ms; %llu of %llu objects kept)", mtri(f.frustumS), 1e3 * f.frustumS,
                              (unsigned long long)f.visibleObjects, (unsigned long long)f.objects),
               "", "", "", ""});
    table.add({"backface", fmt("%.1f M tri/s (%.1f ms; keeps %llu)", mtri(f.backfaceS), 1e3 * f.backfaceS,
                               (unsigned long long)f.kept),
               "", "", floorText(300), judge(f.backfaceS, 300)});
    table.add({"clip", fmt("%.1f M tri/s (%.1f ms; %llu screen triangles out)", mtri(f.clipS), 1e3 * f.clipS,
                           (unsigned long long)f.screenTriangles),
               "", "", floorText(150), judge(f.clipS, 150)});
    const std::string lpPeer = std::isfinite(lpCull) ? fmt("llvmpipe 1 thread here: %.2f M tri/s, %.2f with GL_CULL_FACE "
                                                           "(anchors 7.4 and 13)", mtri(lpOne), mtri(lpCull))
                                                     : "Mesa llvmpipe 1 thread: 7.4 M tri/s, 13 with GL_CULL_FACE (anchors)";
    table.add({"z-buffer (after backface)", fmt("%.1f M tri/s (%.1f ms)", mtri(f.zbufferS), 1e3 * f.zbufferS), lpPeer,
               "", floorText(40), judge(f.zbufferS, 40)});
    if (std::isfinite(scale))
        table.notes.push_back(fmt("pipeline: 'here' floors are the issue's floors x %.2f, llvmpipe's pace with "
                                  "GL_CULL_FACE in this run (%.2f M tri/s) over its anchor (13 M tri/s, the machine "
                                  "the floors were set on)", scale, mtri(lpCull)));
    return 0;
}

// The per-part rows (README, "Benchmarks"): a part of the views, its share of the views' time; the
// output phase, of the run's CPU time (views + output).
void Bench::partRows(const LevelParts &L, const LevelParts *start) {
    const double cpu = L.viewsTotal + L.images + L.reportHtml;
    const double startCpu = start ? start->viewsTotal + start->images + start->reportHtml : 0;
    // The same part of the start's run: its CPU s and share (what the member picks out of a LevelParts).
    auto peer = [&](double LevelParts::*m, double LevelParts::*m2, bool ofRun) {
        if (!start) return std::string();
        const double ms = start->*m + (m2 ? start->*m2 : 0);
        return fmt("start, this run: %.1f CPU s, %.0f%%", ms / 1e3, 100 * ms / (ofRun ? startCpu : start->viewsTotal));
    };
    auto part = [&](const char *name, double ms, const std::string &floor, bool pass, bool ofRun = false,
                    double LevelParts::*m = nullptr, double LevelParts::*m2 = nullptr) {
        table.add({name, fmt("%.1f CPU s", ms / 1e3), m ? peer(m, m2, ofRun) : "",
                   fmt("%.0f%% of the %s", 100 * ms / (ofRun ? cpu : L.viewsTotal), ofRun ? "run" : "views"),
                   floor, floor.empty() ? "" : verdict(pass)});
    };
    if (L.orderingRan)
        part("ordering audit (painter's, BSP, scanline, overdraw by order)", L.ordering, "<= 20% of a view's time",
             L.ordering <= 0.2 * L.viewsTotal, false, &LevelParts::ordering);
    else
        table.add({"ordering audit", "not run (report.json: views[].ordering.reason)", "", "", "", ""});
    part("images (output.images_ms) + report + HTML", L.images + L.reportHtml, "<= 15% of the run",
         L.images + L.reportHtml <= 0.15 * cpu, true, &LevelParts::images, &LevelParts::reportHtml);
    part("z-fighting in every format (depth.ms)", L.zfight, "<= 10% of a view's time",
         L.zfight <= 0.1 * L.viewsTotal, false, &LevelParts::zfight);
    part("raycast stage", L.raycast, "", true, false, &LevelParts::raycast);
    part("reference visibility audit + cross-check", L.referenceAndCross, "", true, false,
         &LevelParts::referenceAndCross);
    part("the game's pipeline: cells, frustum, occlusion, backface, clip, z-buffer", L.pipeline, "", true, false,
         &LevelParts::pipeline);
    part("detail audit", L.detail, "", true, false, &LevelParts::detail);
    part("rest of the views' time (bookkeeping, freeing)",
         L.viewsTotal - L.ordering - L.zfight - L.raycast - L.referenceAndCross - L.pipeline - L.detail, "",
         true);
}

// The "level" section of the table (README, "Benchmarks": what it measures).
int Bench::sectionLevel() {
    const fs::path map = o.data / "openarena" / "pak6-patch088.pk3";
    if (o.data.empty() || !fs::exists(map)) {
        table.rule("real level: not measured (no data/openarena: run scripts/fetch-data.sh, pass --data DIR)");
    } else {
        progress("level: visaudit analyze oa_thor --views spawns, 1920x1080, 2 threads (a minute or two)");
        const fs::path out = o.work / "level";
        auto analyzeArgs = [&](const std::string &bin, const fs::path &dir) {
            return std::vector<std::string>{bin, "analyze", map.string() + ":maps/oa_thor.bsp", "--views", "spawns",
                                            "--width", "1920", "--height", "1080", "--threads", "2", "--out",
                                            dir.string(), "--quiet"};
        };
        // Issue 18's baseline: its start (kBaselineCommit) took 118 s wall on 2 cores for this run,
        // on the machine of 2026-11-24. With --baseline that build runs here first, in this run.
        constexpr double kBaselineS = 118;
        constexpr const char *kBaselineCommit = "b9c9599";
        // o.levelReps runs of each build, alternating (the start first), and the fastest of each:
        // a shared machine's minute moves one run by a third, and alternating gives both builds
        // the same minutes. A part's figures are its fastest run's.
        ChildRun base, c;
        LevelParts baseParts, L;
        bool haveBaseParts = false, haveParts = false;
        std::string baseWhy;  // why no baseline run could be read, when none could
        for (int rep = 0; rep < o.levelReps; ++rep) {
            if (!o.baseline.empty()) {
                progress(fmt("level: the start's run %d of %d (--baseline; a few minutes)", rep + 1, o.levelReps));
                const fs::path baseOut = o.work / "level-baseline";
                fs::remove_all(baseOut);
                const ChildRun b = runChild(analyzeArgs(o.baseline, baseOut), o.work / "level-baseline.log");
                LevelParts parts;
                if (b.status != 0) {
                    if (!haveBaseParts) base = b, baseWhy = fmt("exit %d", b.status);
                } else if (!readLevelParts(baseOut / "report.json", &parts, &baseWhy)) {
                    if (!haveBaseParts) base = b;
                } else if (!haveBaseParts || b.wallS < base.wallS) {
                    base = b, baseParts = parts, haveBaseParts = true;
                }
                if (!o.keep) fs::remove_all(baseOut);
            }
            if (o.levelReps > 1) progress(fmt("level: this build's run %d of %d", rep + 1, o.levelReps));
            fs::remove_all(out);
            const ChildRun r = runChild(analyzeArgs(o.visaudit, out), o.work / "level.log");
            LevelParts parts;
            if (r.status != 0 || !readLevelParts(out / "report.json", &parts, &err)) {
                c = r, haveParts = false;
                break;  // a failing build: reported below
            }
            if (!haveParts || r.wallS < c.wallS) c = r, L = parts, haveParts = true;
        }
        if (!haveParts) {
            table.rule(fmt("real level: analyze failed (exit %d; see %s)", c.status, (o.work / "level.log").c_str()));
        } else {
            table.rule(fmt("real level (visaudit analyze pak6-patch088.pk3:maps/oa_thor.bsp --views spawns "
                           "--width 1920 --height 1080 --threads 2; %llu triangles, %zu views)",
                           (unsigned long long)L.triangles, L.views));
            const std::string value = fmt("%.1f s, peak %.0f MiB%s", c.wallS, c.peakMiB,
                                          o.levelReps > 1 ? fmt(" (best of %d)", o.levelReps).c_str() : "");
            if (o.baseline.empty()) {
                table.add({"analyze, 2 threads: process wall time", value,
                           fmt("issue 18's baseline: %.0f s (another machine; --baseline runs it here)", kBaselineS),
                           fmt("%.2fx faster", kBaselineS / c.wallS), ">= 5x faster", verdict(kBaselineS / c.wallS >= 5)});
            } else if (!haveBaseParts) {
                table.add({"analyze, 2 threads: process wall time", value,
                           fmt("--baseline: failed, %s (see %s)", baseWhy.c_str(),
                               (o.work / "level-baseline.log").c_str()),
                           "", ">= 5x faster", ""});
            } else {
                table.add({"analyze, 2 threads: process wall time", value,
                           fmt("--baseline (issue 18's start, %s, from run.sh), this run: %.1f s, peak %.0f MiB%s",
                               kBaselineCommit, base.wallS, base.peakMiB,
                               o.levelReps > 1 ? fmt(" (best of %d, alternating)", o.levelReps).c_str() : ""),
                           fmt("%.2fx faster", base.wallS / c.wallS), ">= 5x faster", verdict(base.wallS / c.wallS >= 5)});
            }
            partRows(L, haveBaseParts ? &baseParts : nullptr);
            table.notes.push_back(fmt("level: shares are of the CPU time summed over views (views' total_ms %.1f s) "
                                      "plus the output phase; once per scene: load %.0f ms, ray scene %.0f ms, "
                                      "BSP tree %.0f ms", L.viewsTotal / 1e3, L.load, L.raySceneBuild, L.bspBuild));
            if (!o.baseline.empty()) table.notes.push_back("level: --baseline is " + o.baseline);
        }
        if (!o.keep) fs::remove_all(out);
    }
    return 0;
}

// The "load" section of the table (README, "Benchmarks": what it measures).
int Bench::sectionLoad() {
    progress("load");
    table.rule("load (loadScene: the file's reader, then the scene build; 1,000,002 triangles)");
    for (const fs::path &p : {objPath, gltfPath, plyPath}) {
        std::vector<double> t;
        size_t got = 0;
        for (int r = 0; r < std::max(1, o.reps / 2); ++r) {
            Scene s;
            const double w0 = wallNow();
            if (!loadScene(p.string(), {}, &s, &err)) {
                std::fprintf(stderr, "bench_table: %s\n", err.c_str());
                return 3;
            }
            t.push_back(wallNow() - w0);
            got = s.triangleCount();
        }
        uintmax_t bytes = fs::file_size(p);
        if (p.extension() == ".gltf") bytes += fs::file_size(fs::path(p).replace_extension(".bin"));
        const bool isPly = p.extension() == ".ply";
        table.add({"load " + p.extension().string().substr(1) + fmt(" (%.0f MB)", bytes / 1e6),
                   fmt("%.2f s, %.2f M tri/s", best(t), got / best(t) * 1e-6), "", "",
                   isPly ? "" : "about 1 s (<= 1.5 s)", isPly ? "" : verdict(best(t) <= 1.5 && got == size_t(tris))});
    }
    return 0;
}

// The "analyze" section of the table (README, "Benchmarks": what it measures).
int Bench::sectionAnalyze() {
    progress("analyze: 16 orbit views, 1920x1080, one thread");
    table.rule("analyze end to end (visaudit analyze bench_scene.obj --views orbit:16 --width 1920 --height 1080)");
    for (int threads : {1, 0}) {
        const fs::path out = o.work / fmt("analyze-t%d", threads);
        fs::remove_all(out);
        const ChildRun c = runChild({o.visaudit, "analyze", objPath.string(), "--views", "orbit:16", "--width", "1920",
                                     "--height", "1080", "--threads", std::to_string(threads), "--out",
                                     out.string(), "--quiet"},
                                    o.work / fmt("analyze-t%d.log", threads));
        ReportTimes rt;
        if (c.status != 0 || !readReportTimes(out / "report.json", &rt, &err)) {
            table.add({fmt("analyze, %s", threads ? "1 thread" : "all threads"),
                       fmt("failed (exit %d; see %s)", c.status, (o.work / fmt("analyze-t%d.log", threads)).c_str()),
                       "", "", "", "FAIL"});
            continue;
        }
        const double sumS = rt.sum() / 1e3;
        if (threads == 1) {
            table.add({"analyze, 1 thread: process wall time", fmt("%.2f s, peak %.0f MiB", c.wallS, c.peakMiB),
                       fmt("sum of report timings: %.2f s", sumS), fmt("%.3fx", c.wallS / sumS), "<= 1.3x",
                       verdict(c.wallS / sumS <= 1.3)});
            table.notes.push_back(fmt("analyze timings (report.json, 1 thread): load_ms %.0f, ray_scene_build_ms %.0f, "
                                      "bsp_tree.build_ms %.0f, stages[].ms %.0f, audits' ms (audit, depth, ordering, "
                                      "detail, raycast.cross_check, raycast.effects) %.0f; views' total_ms %.0f; "
                                      "output.images_ms %.0f, output.report_ms %.0f, output.html_ms %.0f; process "
                                      "wall time not inside load, ray scene, BSP tree, a view's total_ms or the output "
                                      "phase (start-up and dynamic linking, writing report.json, the folder swap, "
                                      "freeing at exit): %.0f ms",
                                      rt.loadMs, rt.raySceneMs, rt.bspMs, rt.stagesMs, rt.auditsMs, rt.viewsTotalMs,
                                      rt.imagesMs, rt.reportMs, rt.htmlMs,
                                      1e3 * c.wallS - rt.loadMs - rt.raySceneMs - rt.bspMs - rt.viewsTotalMs -
                                          rt.outputMs()));
            // Issue 18's per-part table for these views too (the level section's rows).
            LevelParts L;
            if (readLevelParts(out / "report.json", &L, &err)) partRows(L);
        } else {
            table.add({fmt("analyze, all threads (%u): process wall time", cores),
                       fmt("%.2f s, peak %.0f MiB", c.wallS, c.peakMiB),
                       fmt("sum of report timings: %.2f s", sumS), fmt("%.3fx", c.wallS / sumS), "", ""});
        }
    }
    return 0;
}

// The "scaling" section of the table (README, "Benchmarks": what it measures).
int Bench::sectionScaling() {
    // Spheres of segments x bands: 100 * 2 * S * (B - 1) + 2 triangles.
    struct Size {
        const char *name;
        int S, B;
    };
    std::vector<Size> sizes = {{"10k", 10, 6}, {"100k", 20, 26}, {"1M", 100, 51}, {"10M", 500, 101}};
    std::vector<int> views = {1, 4, 16, 64};
    if (o.quick) sizes.pop_back(), views.pop_back();
    const int sw = 640, sh = 360;
    // --no-ordering: the draw-order audit runs only below --ordering-max-triangles (200k; its BSP tree
    // can grow quadratically), so with it on, 10k and 100k would pay for a stage 1M and 10M skip.
    table.rule(fmt("scaling (visaudit analyze SCENE.ply --views orbit:V --width %d --height %d --no-ordering, "
                   "every other default stage, all threads; wall s / peak MiB; ratio vs linear from the previous "
                   "row / column)", sw, sh));
    std::vector<std::vector<ChildRun>> runs(sizes.size());
    std::vector<double> triCount(sizes.size());
    for (size_t i = 0; i < sizes.size(); ++i) {
        progress(fmt("scaling: writing %s", sizes[i].name));
        RawMesh m = sphereGridMesh(sizes[i].S, sizes[i].B);
        triCount[i] = double(m.indices.size() / 3);
        const fs::path ply = o.work / fmt("grid_%s.ply", sizes[i].name);
        if (!writePly(ply, m)) {
            std::fprintf(stderr, "bench_table: cannot write %s\n", ply.c_str());
            return 3;
        }
        m = RawMesh{};
        for (int v : views) {
            progress(fmt("scaling: %s triangles, %d views", sizes[i].name, v));
            const fs::path out = o.work / fmt("scale-%s-%d", sizes[i].name, v);
            runs[i].push_back(runChild({o.visaudit, "analyze", ply.string(), "--views", "orbit:" + std::to_string(v),
                                        "--width", std::to_string(sw), "--height", std::to_string(sh),
                                        "--no-ordering", "--out", out.string(), "--quiet"},
                                       o.work / fmt("scale-%s-%d.log", sizes[i].name, v)));
            fs::remove_all(out);
        }
        fs::remove(ply);
    }
    double worstT = 0, worstV = 0, worstM = 0;
    for (size_t i = 0; i < sizes.size(); ++i)
        for (size_t k = 0; k < views.size(); ++k) {
            const ChildRun &c = runs[i][k];
            std::string lin;
            if (i > 0) {
                const double rt = c.wallS / runs[i - 1][k].wallS / (triCount[i] / triCount[i - 1]);
                const double rm = c.peakMiB / runs[i - 1][k].peakMiB / (triCount[i] / triCount[i - 1]);
                worstT = std::max(worstT, rt), worstM = std::max(worstM, rm);
                lin += fmt("x%.0f tri: time %.2f, mem %.2f", triCount[i] / triCount[i - 1], rt, rm);
            }
            if (k > 0) {
                const double rv = c.wallS / runs[i][k - 1].wallS / (double(views[k]) / views[k - 1]);
                worstV = std::max(worstV, rv);
                lin += fmt("%sx%d views: time %.2f", lin.empty() ? "" : "; ", views[k] / views[k - 1], rv);
            }
            const bool big = i + 1 == sizes.size() && sizes[i].S == 500;
            table.add({fmt("%s triangles x %d views", sizes[i].name, views[k]),
                       c.status ? fmt("failed (exit %d)", c.status) : fmt("%.2f s / %.0f MiB", c.wallS, c.peakMiB),
                       "", lin, big ? "fits in 8 GiB" : "", big ? verdict(c.status == 0 && c.peakMiB <= 8192) : ""});
        }
    table.add({"scaling: worst ratio vs linear", fmt("time x tri %.2f, time x views %.2f, memory x tri %.2f", worstT, worstV, worstM),
               "", "", "<= 1.25 (linear, 25% noise)", verdict(worstT <= 1.25 && worstV <= 1.25 && worstM <= 1.25)});
    return 0;
}

int main(int argc, char **argv) {
    va::setUpProcessHeap();  // the allocator visaudit runs with
    Options o;
    const std::vector<std::string> allSections = {"zbuffer", "llvmpipe", "raycast", "pipeline", "load",
                                                  "analyze",  "level",    "scaling"};
    o.visaudit = (fs::path(argv[0]).parent_path().parent_path() / "visaudit").string();
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto next = [&]() -> std::string {
            if (i + 1 >= argc) {
                std::fprintf(stderr, "bench_table: %s needs a value\n", a.c_str());
                std::exit(2);
            }
            return argv[++i];
        };
        if (a == "--quick") o.quick = true;
        else if (a == "--keep") o.keep = true;
        else if (a == "--reps") o.reps = std::max(1, std::atoi(next().c_str()));
        else if (a == "--visaudit") o.visaudit = next();
        else if (a == "--work") o.work = next();
        else if (a == "--data") o.data = next();
        else if (a == "--baseline") o.baseline = next();
        else if (a == "--level-reps") o.levelReps = std::max(1, std::atoi(next().c_str()));
        else if (a == "--sections") {
            std::stringstream ss(next());
            for (std::string s; std::getline(ss, s, ',');) {
                if (std::find(allSections.begin(), allSections.end(), s) == allSections.end()) {
                    std::fprintf(stderr, "bench_table: unknown section '%s'; sections: zbuffer, llvmpipe, raycast, "
                                         "pipeline, load, analyze, level, scaling\n", s.c_str());
                    return 2;
                }
                o.sections.insert(s);
            }
        } else {
            std::fprintf(stderr, "usage: bench_table [--quick] [--sections LIST] [--reps N] [--visaudit PATH] "
                                 "[--work DIR] [--data DIR] [--baseline PATH] [--level-reps N] [--keep]\n");
            return 2;
        }
    }
    if (o.sections.empty()) o.sections.insert(allSections.begin(), allSections.end());
    if (o.quick) o.reps = std::min(o.reps, 3);
    bool madeWork = false;
    if (o.work.empty()) {
        char tmpl[] = "/tmp/visaudit-bench-XXXXXX";
        if (!mkdtemp(tmpl)) {
            std::perror("bench_table: mkdtemp");
            return 2;
        }
        o.work = tmpl;
        madeWork = true;
    }
    fs::create_directories(o.work);
    const bool needsCli = o.on("analyze") || o.on("scaling");
    if (needsCli && !fs::exists(o.visaudit)) {
        std::fprintf(stderr, "bench_table: %s not found; build the visaudit target or pass --visaudit PATH\n",
                     o.visaudit.c_str());
        return 2;
    }

    Bench b(o);
    b.cores = std::thread::hardware_concurrency();
    progress("building the benchmark scene");
    b.mesh = sphereGridMesh();
    std::string err;
    if (!makeCamera(benchmarkCamera(), &b.cam, &err)) {
        std::fprintf(stderr, "bench_table: camera: %s\n", err.c_str());
        return 3;
    }
    b.tris = double(b.mesh.indices.size() / 3);

    // zbuffer and its peer.
    if (o.on("zbuffer") || o.on("llvmpipe")) {
        const Scene scene = sceneOfMesh(b.mesh);
        progress("zbuffer");
        b.z = runZbuffer(o, scene, b.cam);
    }
    if (o.on("llvmpipe"))
        if (const int code = b.sectionLlvmpipe()) return code;
    if (o.on("zbuffer"))
        if (const int code = b.sectionZbuffer()) return code;
    if (!b.lpNote.empty()) b.table.notes.push_back(b.lpNote);

    if (o.on("raycast"))
        if (const int code = b.sectionRaycast()) return code;

    if (o.on("pipeline"))
        if (const int code = b.sectionPipeline()) return code;

    if (o.on("level"))
        if (const int code = b.sectionLevel()) return code;

    b.objPath = o.work / "bench_scene.obj", b.gltfPath = o.work / "bench_scene.gltf", b.plyPath = o.work / "bench_scene.ply";
    if (o.on("load") || o.on("analyze")) {
        progress("writing the scene as OBJ, glTF and PLY");
        if (!writeObj(b.objPath, b.mesh) || !writeGltf(b.gltfPath, b.mesh) || !writePly(b.plyPath, b.mesh)) {
            std::fprintf(stderr, "bench_table: cannot write the scene files into %s\n", o.work.c_str());
            return 3;
        }
    }
    if (o.on("load"))
        if (const int code = b.sectionLoad()) return code;

    if (o.on("analyze"))
        if (const int code = b.sectionAnalyze()) return code;

    if (o.on("scaling"))
        if (const int code = b.sectionScaling()) return code;

    std::printf("visaudit benchmark (bench/run.sh): %u cores, best of %d; one-thread figures are thread CPU time "
                "(llvmpipe: process CPU time), all-thread figures wall time\n", b.cores, o.reps);
    b.table.print();
    if (madeWork && !o.keep) fs::remove_all(o.work);
    return 0;
}
