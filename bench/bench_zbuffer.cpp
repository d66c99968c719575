// z-buffer throughput on the benchmark scene (bench/bench_scene.h), one thread and all threads.
//
//   bench_zbuffer [--reps N] [--format NAME] [--tile-shift S] [--only K]
//
// Builds the 1,000,002-triangle sphere grid, clips and projects it once with the clip stage
// (va::clipTriangles), then times va::rasterize() alone -- buffer allocation and clearing included,
// since they are part of every call -- over N repetitions per configuration (the plain walk, the
// default strategy and the tiled kernels on one thread; the default on all threads), and reports
// the best and the median, M triangles/s and M fragments/s (from the best wall time), and whether
// every configuration produced the same stats (the exit status is 1 if not).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <ctime>
#include <thread>
#include <vector>

#include <tbb/global_control.h>

#include "bench/bench_scene.h"
#include "common/process_heap.h"
#include "render/clip.h"
#include "render/raster.h"

int main(int argc, char **argv) {
    va::setUpProcessHeap();  // the allocator visaudit runs with
    int reps = 9;
    int tileShift = 0;
    int only = -1;  // --only K: just configuration K (0-based, table order), e.g. for a profiler
    va::DepthFormat format = va::DepthFormat::f32;
    for (int i = 1; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--reps") && i + 1 < argc) {
            reps = std::max(1, std::atoi(argv[++i]));
        } else if (!std::strcmp(argv[i], "--format") && i + 1 < argc) {
            std::string err;
            if (!va::parseDepthFormat(argv[++i], &format, &err)) {
                std::fprintf(stderr, "bench_zbuffer: %s\n", err.c_str());
                return 2;
            }
        } else if (!std::strcmp(argv[i], "--tile-shift") && i + 1 < argc) {
            tileShift = std::atoi(argv[++i]);
        } else if (!std::strcmp(argv[i], "--only") && i + 1 < argc) {
            only = std::atoi(argv[++i]);
        } else {
            std::fprintf(stderr, "usage: bench_zbuffer [--reps N] [--format NAME] [--tile-shift S] [--only K]\n");
            return 2;
        }
    }

    const va::RawMesh mesh = va::sphereGridMesh();
    va::Camera cam;
    std::string err;
    if (!va::makeCamera(va::benchmarkCamera(), &cam, &err)) {
        std::fprintf(stderr, "bench_zbuffer: camera: %s\n", err.c_str());
        return 3;
    }

    // One clip batch per sphere (its 10,000 triangles and their vertex range), one for the ground.
    const uint32_t triCount = uint32_t(mesh.indices.size() / 3);
    std::vector<uint32_t> order(triCount);
    for (uint32_t t = 0; t < triCount; ++t) order[t] = t;
    std::vector<va::ClipBatch> batches;
    const uint32_t perSphereTris = 2 * va::kBenchSphereSegments * (va::kBenchSphereBands - 1);
    const uint32_t perSphereVerts = va::kBenchSphereSegments * (va::kBenchSphereBands - 1) + 2;
    const uint32_t spheres = va::kBenchSphereGrid * va::kBenchSphereGrid;
    for (uint32_t s = 0; s < spheres; ++s)
        batches.push_back({s * perSphereVerts, (s + 1) * perSphereVerts, &order[s * perSphereTris], perSphereTris});
    batches.push_back({spheres * perSphereVerts, uint32_t(mesh.positions.size()), &order[spheres * perSphereTris],
                       triCount - spheres * perSphereTris});

    const auto c0 = std::chrono::steady_clock::now();
    const va::ClipResult clip = va::clipTriangles(cam, {mesh.positions.data(), mesh.indices.data()}, batches, {});
    const auto c1 = std::chrono::steady_clock::now();
    const va::ScreenTriangles &tris = clip.out;

    va::ZBufferSettings settings;
    settings.encoder = va::makeDepthEncoder(format, cam.nearZ, cam.farZ);
    settings.orthographic = cam.orthographic;

    // Wall time, and the process's CPU time: on a shared machine CPU time excludes the time the
    // threads waited for a core (with one thread it is the thread's own time), wall time is what a
    // user sees. Each configuration runs under its own tbb::global_control, as the CLI's --threads.
    auto cpuNow = [] {
        timespec ts;
        clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
        return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
    };
    struct Timing {
        double best = 0, median = 0, cpuBest = 0;
        va::ZBufferStats stats;
    };
    auto run = [&](const va::ScreenTriangles &input, int threads, const va::RasterStrategy &strategy) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
        std::vector<double> seconds, cpuSeconds;
        Timing timing;
        for (int r = 0; r < reps; ++r) {
            const double c0cpu = cpuNow();
            const auto t0 = std::chrono::steady_clock::now();
            va::ZBufferResult res = va::rasterize(input, cam.width, cam.height, settings, strategy);
            const auto t1 = std::chrono::steady_clock::now();
            cpuSeconds.push_back(cpuNow() - c0cpu);
            seconds.push_back(std::chrono::duration<double>(t1 - t0).count());
            timing.stats = std::move(res.stats);
        }
        std::sort(seconds.begin(), seconds.end());
        std::sort(cpuSeconds.begin(), cpuSeconds.end());
        timing.best = seconds.front();
        timing.median = seconds[seconds.size() / 2];
        timing.cpuBest = cpuSeconds.front();
        return timing;
    };

    const int allThreads = std::max(1, int(std::thread::hardware_concurrency()));
    const double n = double(tris.size());
    std::printf("scene: %u triangles, %zu screen triangles after clipping (clip %.1f ms)\n", triCount,
                tris.size(), 1e3 * std::chrono::duration<double>(c1 - c0).count());
    std::printf("view: %dx%d, format %s, %d repetitions, %d hardware threads\n", cam.width, cam.height,
                va::depthFormatInfo(format).name, reps, allThreads);
    const Timing empty = run(va::ScreenTriangles{}, 1, {});
    std::printf("fixed cost of a call (buffers and stats, empty input, one thread): best %.2f ms\n\n", 1e3 * empty.best);

    struct Config {
        const char *name;
        int threads;
        va::RasterStrategy strategy;
    };
    using Path = va::RasterStrategy::Path;
    std::vector<Config> configs = {
        {"plain walk (reference)", 1, {Path::plainWalk, true, 0}},
        {"default (batched walk)", 1, {}},
        {"tiled, baseline SSE2", 1, {Path::tiled, false, 0}},
        {"tiled, AVX2 if present", 1, {Path::tiled, true, 0}},
        {"default", allThreads, {}},
    };
    if (only >= int(configs.size())) {
        std::fprintf(stderr, "bench_zbuffer: --only %d: there are %zu configurations (0 to %zu)\n", only,
                     configs.size(), configs.size() - 1);
        return 2;
    }
    if (tileShift > 0)
        for (Config &c : configs) c.strategy.tileShift = tileShift;
    std::printf("%-24s %7s %10s %10s %10s %12s %12s\n", "rasterize", "threads", "best ms", "median ms", "CPU ms",
                "M tri/s", "M frag/s");
    va::ZBufferStats reference;
    bool identical = true;
    for (size_t i = 0; i < configs.size(); ++i) {
        const Config &c = configs[i];
        if (only >= 0 && size_t(only) != i) continue;
        const Timing t = run(tris, c.threads, c.strategy);
        std::printf("%-24s %7d %10.2f %10.2f %10.2f %12.2f %12.1f\n", c.name, c.threads, 1e3 * t.best,
                    1e3 * t.median, 1e3 * t.cpuBest, n / t.best * 1e-6, double(t.stats.fragments) / t.best * 1e-6);
        if (i == 0 || (only >= 0 && size_t(only) == i)) reference = t.stats;
        identical = identical && t.stats.fragments == reference.fragments &&
                    t.stats.depthPasses == reference.depthPasses && t.stats.histogram == reference.histogram &&
                    t.stats.trianglesDrawn == reference.trianglesDrawn;
    }
    std::printf("\ntriangles drawn %llu, empty %llu; fragments %llu, depth passes %llu\n",
                (unsigned long long)reference.trianglesDrawn, (unsigned long long)reference.trianglesEmpty,
                (unsigned long long)reference.fragments, (unsigned long long)reference.depthPasses);
    std::printf("covered pixels %llu, overdraw %.4f, depth complexity %.4f, max %u\n",
                (unsigned long long)reference.coveredPixels, reference.overdraw, reference.depthComplexity,
                reference.maxDepthComplexity);
    std::printf("stats identical across configurations: %s\n", identical ? "yes" : "NO");
    return identical ? 0 : 1;
}
