// Single-thread z-buffer throughput on the benchmark scene (analysis/bench_scene.h).
//
//   bench_zbuffer [--reps N] [--format NAME]
//
// Builds the 1,000,002-triangle sphere grid, clips and projects it once with the clip stage
// (va::clipTriangles), then times va::rasterize() alone -- buffer allocation and clearing included,
// since they are part of every call -- over N repetitions on the calling thread, and reports the
// best and the median.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <ctime>
#include <vector>

#include "analysis/bench_scene.h"
#include "render/clip.h"
#include "render/raster.h"

int main(int argc, char **argv) {
    int reps = 9;
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
        } else {
            std::fprintf(stderr, "usage: bench_zbuffer [--reps N] [--format NAME]\n");
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

    // Wall time, and the thread's CPU time (CLOCK_THREAD_CPUTIME_ID): on a shared machine the
    // latter excludes the time the thread waited for a core, the former is what a user sees.
    auto cpuNow = [] {
        timespec ts;
        clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
        return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
    };
    std::vector<double> seconds, cpuSeconds;
    va::ZBufferStats stats;
    for (int r = 0; r < reps; ++r) {
        const double c0cpu = cpuNow();
        const auto t0 = std::chrono::steady_clock::now();
        va::ZBufferResult res = va::rasterize(tris, cam.width, cam.height, settings);
        const auto t1 = std::chrono::steady_clock::now();
        cpuSeconds.push_back(cpuNow() - c0cpu);
        seconds.push_back(std::chrono::duration<double>(t1 - t0).count());
        stats = std::move(res.stats);
    }
    std::sort(cpuSeconds.begin(), cpuSeconds.end());
    // The fixed cost of a call: allocating and clearing the five per-pixel buffers, and the
    // histogram pass of finishZBufferStats, measured on an empty triangle list.
    std::vector<double> overhead;
    for (int r = 0; r < reps; ++r) {
        const auto t0 = std::chrono::steady_clock::now();
        va::ZBufferResult res = va::rasterize(va::ScreenTriangles{}, cam.width, cam.height, settings);
        const auto t1 = std::chrono::steady_clock::now();
        overhead.push_back(std::chrono::duration<double>(t1 - t0).count());
    }
    std::sort(overhead.begin(), overhead.end());
    std::vector<double> sorted = seconds;
    std::sort(sorted.begin(), sorted.end());
    const double best = sorted.front(), median = sorted[sorted.size() / 2];
    const double n = double(tris.size());

    std::printf("scene: %u triangles, %zu screen triangles after clipping (clip %.1f ms)\n", triCount,
                tris.size(), 1e3 * std::chrono::duration<double>(c1 - c0).count());
    std::printf("view: %dx%d, format %s, %d repetitions\n", cam.width, cam.height,
                va::depthFormatInfo(format).name, reps);
    std::printf("rasterize: best %.2f ms, median %.2f ms\n", 1e3 * best, 1e3 * median);
    std::printf("rasterize thread CPU time: best %.2f ms, median %.2f ms (%.2f M triangles/s)\n",
                1e3 * cpuSeconds.front(), 1e3 * cpuSeconds[cpuSeconds.size() / 2], n / cpuSeconds.front() * 1e-6);
    std::printf("of which buffers and stats (empty input): best %.2f ms\n", 1e3 * overhead.front());
    std::printf("triangles drawn %llu, empty %llu; fragments %llu, depth passes %llu\n",
                (unsigned long long)stats.trianglesDrawn, (unsigned long long)stats.trianglesEmpty,
                (unsigned long long)stats.fragments, (unsigned long long)stats.depthPasses);
    std::printf("covered pixels %llu, overdraw %.4f, depth complexity %.4f, max %u\n",
                (unsigned long long)stats.coveredPixels, stats.overdraw, stats.depthComplexity,
                stats.maxDepthComplexity);
    std::printf("fragments/s: best %.1f M, median %.1f M\n", double(stats.fragments) / best * 1e-6,
                double(stats.fragments) / median * 1e-6);
    std::printf("triangles/s: best %.2f M, median %.2f M\n", n / best * 1e-6, n / median * 1e-6);
    std::printf("zbuffer: %.2f M triangles/s (one thread)\n", n / best * 1e-6);
    return 0;
}
