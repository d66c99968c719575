// Primary-ray throughput on the benchmark scene (analysis/bench_scene.h), one thread.
//
//   bench_raycast [--reps N]
//
// Builds the 1,000,002-triangle sphere grid into a RayScene (Embree's BVH build uses TBB: it is
// timed separately), then times, in the same run and interleaved rep by rep, RayScene::castPrimary
// (ids and depths written per pixel) against castPrimaryRaw (the same rays through rtcIntersect16,
// nothing written): the ratio is what the image output costs. Tracing is single-threaded.
// Floor: castPrimary >= 0.8x raw (the next issue asks 0.9x).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>
#include <vector>

#include "analysis/bench_scene.h"
#include "render/raycast.h"

namespace {
double cpuNow() {
    timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}
}  // namespace

int main(int argc, char **argv) {
    int reps = 7;
    for (int i = 1; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--reps") && i + 1 < argc) {
            reps = std::max(1, std::atoi(argv[++i]));
        } else {
            std::fprintf(stderr, "usage: bench_raycast [--reps N]\n");
            return 2;
        }
    }
    const va::RawMesh mesh = va::sphereGridMesh();
    va::Camera cam;
    std::string err;
    if (!va::makeCamera(va::benchmarkCamera(), &cam, &err)) {
        std::fprintf(stderr, "bench_raycast: camera: %s\n", err.c_str());
        return 3;
    }
    std::vector<uint32_t> all(mesh.indices.size() / 3);
    for (uint32_t t = 0; t < all.size(); ++t) all[t] = t;
    va::Aabb bounds;
    for (const va::Vec3 &p : mesh.positions) bounds.extend(p);

    va::RayScene rs;
    const auto b0 = std::chrono::steady_clock::now();
    if (!rs.build({mesh.positions.data(), mesh.indices.data()}, mesh.positions.size(), all, bounds.center(), &err)) {
        std::fprintf(stderr, "bench_raycast: %s\n", err.c_str());
        return 3;
    }
    const double buildMs = 1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - b0).count();

    // Interleaved reps (raw, full, raw, full, ...) so that both see the same machine load.
    std::vector<double> rawCpu, fullCpu, rawWall, fullWall;
    uint64_t rawHits = 0;
    va::RaycastStats st;
    for (int r = 0; r < reps; ++r) {
        double c0 = cpuNow();
        auto t0 = std::chrono::steady_clock::now();
        rawHits = rs.castPrimaryRaw(cam);
        rawWall.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
        rawCpu.push_back(cpuNow() - c0);
        c0 = cpuNow();
        t0 = std::chrono::steady_clock::now();
        va::RaycastImage img = rs.castPrimary(cam, &st);
        fullWall.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
        fullCpu.push_back(cpuNow() - c0);
        if (img.id.size() != size_t(cam.width) * cam.height) return 3;
    }
    for (auto *v : {&rawCpu, &fullCpu, &rawWall, &fullWall}) std::sort(v->begin(), v->end());
    const double rays = double(cam.width) * cam.height;
    std::printf("scene: %zu triangles, %dx%d rays, %d repetitions\n", all.size(), cam.width, cam.height, reps);
    std::printf("BVH build (Embree, TBB threads): %.1f ms\n", buildMs);
    std::printf("hits: raw %llu, castPrimary %llu of %llu rays\n", (unsigned long long)rawHits,
                (unsigned long long)st.hits, (unsigned long long)st.rays);
    std::printf("castPrimaryRaw: best %.2f ms CPU (median %.2f), %.2f M rays/s; wall best %.2f ms\n",
                1e3 * rawCpu.front(), 1e3 * rawCpu[rawCpu.size() / 2], rays / rawCpu.front() * 1e-6,
                1e3 * rawWall.front());
    std::printf("castPrimary:    best %.2f ms CPU (median %.2f), %.2f M rays/s; wall best %.2f ms\n",
                1e3 * fullCpu.front(), 1e3 * fullCpu[fullCpu.size() / 2], rays / fullCpu.front() * 1e-6,
                1e3 * fullWall.front());
    const double ratio = rawCpu.front() / fullCpu.front();
    std::printf("castPrimary / raw throughput: %.3fx (floor 0.8x, next issue 0.9x)\n", ratio);
    return ratio >= 0.8 ? 0 : 1;
}
