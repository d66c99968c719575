// BSP build on a real level (docs/ordering.md, "Speed"): OpenArena's oa_thor (scripts/fetch-data.sh
// puts pak6-patch088.pk3 in data/openarena/), or any scene given as the first argument.
//
//   build-order/bench/bench_bsp [SCENE] [--reps N] [--views N] [--tile N]
//
// --tile N: the scene's triangles N times side by side along x (each copy a source object of its
// own, a gap of a tenth of the level's width between copies): a level of N times the triangles for
// the BSP build's floor (issue 18: at most 1 s for 100k triangles; --tile 3 of oa_thor is 129k).
//
// Per heuristic (default, fewest splits, balance, and the default with every piece scored): build
// time (best and median of N), splits next to the worst case (a BSP of n triangles can need
// Theta(n^2) pieces: Paterson & Yao), nodes, depth, pieces; then the ordering table of the first
// views (640 x 360) with the default tree.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "analysis/audits/ordering.h"
#include "analysis/effects_plan.h"
#include "analysis/load/load.h"
#include "common/process_heap.h"

using namespace va;

namespace {

// The scene's source objects `copies` times side by side along x (materials kept; views, lights
// and the map's BSP data dropped).
Scene tiled(const Scene &scene, int copies) {
    SceneBuildInput in;
    in.up = scene.up;
    in.materials = scene.materials;
    const double width = scene.bounds.hi.x - scene.bounds.lo.x, step = width * 1.1;
    for (int k = 0; k < copies; ++k)
        for (const SourceObject &src : scene.sources) {
            SceneBuildInput::Object o;
            o.name = src.name + "@" + std::to_string(k);
            o.mesh = src.mesh;
            o.material = src.material;
            for (uint32_t t = src.firstTriangle; t < src.firstTriangle + src.triangleCount; ++t)
                for (int j = 0; j < 3; ++j) {
                    o.geometry.indices.push_back(uint32_t(o.geometry.positions.size()));
                    o.geometry.positions.push_back(scene.positions[scene.indices[3 * size_t(t) + size_t(j)]] +
                                                   Vec3{step * k, 0, 0});
                }
            in.objects.push_back(std::move(o));
        }
    return buildScene(std::move(in));
}

}  // namespace

int main(int argc, char **argv) {
    va::setUpProcessHeap();  // the allocator visaudit runs with
    std::string path = std::string(VISAUDIT_SOURCE_DIR) + "/data/openarena/pak6-patch088.pk3:maps/oa_thor.bsp";
    int reps = 3, nViews = 2, tile = 1;
    for (int i = 1; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--reps") && i + 1 < argc) reps = std::max(1, std::atoi(argv[++i]));
        else if (!std::strcmp(argv[i], "--tile") && i + 1 < argc) tile = std::clamp(std::atoi(argv[++i]), 1, 64);
        else if (!std::strcmp(argv[i], "--views") && i + 1 < argc) nViews = std::max(0, std::atoi(argv[++i]));
        else path = argv[i];
    }
    const std::string file = path.substr(0, path.find(".pk3:") == std::string::npos ? path.size() : path.find(".pk3:") + 4);
    if (!std::filesystem::exists(file)) {
        std::printf("bench_bsp: %s not fetched (scripts/fetch-data.sh); nothing to measure\n", file.c_str());
        return 0;
    }
    Scene scene;
    std::string err;
    if (!loadScene(path, {}, &scene, &err)) {
        std::fprintf(stderr, "bench_bsp: %s\n", err.c_str());
        return 2;
    }
    if (tile > 1) scene = tiled(scene, tile);
    std::printf("%s%s: %zu source triangles, %zu objects\n", path.c_str(),
                tile > 1 ? (" x" + std::to_string(tile)).c_str() : "", scene.triangleCount(), scene.objects.size());

    struct Config {
        const char *name;
        BspSettings s;
    };
    const Config configs[] = {{"default (16 cand, 8 split + 1 balance, 256 sampled)", {}},
                              {"fewest splits (16 cand, 1 split + 0)", {16, 1, 0, 256}},
                              {"balance (16 cand, 0 + 1 balance)", {16, 0, 1, 256}},
                              {"default, every piece scored", {16, 8, 1, 0}}};
    BspTree keep;
    for (const Config &c : configs) {
        std::vector<double> ms;
        BspTree t;
        for (int r = 0; r < reps; ++r) {
            t = buildBspTree(scene, c.s);
            ms.push_back(t.stats.buildMs);
        }
        std::sort(ms.begin(), ms.end());
        const BspStats &st = t.stats;
        const double n = double(st.trianglesIn);
        std::printf("%-52s build %8.1f ms (median %8.1f) | splits %7llu (worst case O(n^2) ~ %.2e) | pieces %7llu, "
                    "triangles after %7llu | nodes %7llu, depth %5u, mean leaf depth %.1f | predicates %llu | %.1f MB\n",
                    c.name, ms.front(), ms[ms.size() / 2], (unsigned long long)st.splits, n * n,
                    (unsigned long long)st.pieces, (unsigned long long)st.trianglesOut, (unsigned long long)st.nodes,
                    st.depth, st.averageLeafDepth, (unsigned long long)st.predicateCalls, st.memoryBytes / 1e6);
        if (&c == &configs[0]) keep = std::move(t);
    }

    const EffectPlan plan = planEffects(scene, {});
    for (int i = 0; i < nViews && i < int(scene.views.size()); ++i) {
        CameraSpec cs = scene.views[size_t(i)].camera;
        cs.width = 640;
        cs.height = 360;
        Camera cam;
        if (!makeCamera(cs, &cam, &err)) continue;
        const ReferenceVisibility ref = referenceVisibility(scene, cam);
        const OrderingResult r = analyzeOrdering(scene, cam, ref, keep, plan.abuffer);
        std::printf("view %s (640x360):\n  %-9s %10s %10s %8s %6s %6s %9s %12s\n", scene.views[size_t(i)].name.c_str(),
                    "method", "build_ms", "draw_ms", "wrong", "ties", "edge", "overdraw", "memory_B");
        for (const OrderingRow &row : r.table)
            std::printf("  %-9s %10.2f %10.2f %8llu %6llu %6llu %9.3f %12llu\n", row.method.c_str(), row.buildMs,
                        row.drawMs, (unsigned long long)row.wrongPixels, (unsigned long long)row.tiePixels,
                        (unsigned long long)row.edgePixels, row.overdraw, (unsigned long long)row.memoryBytes);
        for (const OrderOverdraw &o : r.overdrawByOrder)
            std::printf("  overdraw %-22s %.3f\n", o.order.c_str(), o.stats.overdraw);
        const OverlapTests &t = r.painter.overlaps;
        std::printf("  painter pairs %llu: bounds %llu, behind %llu, in front %llu, projections %llu, unresolved %llu "
                    "(%.0f ms)\n",
                    (unsigned long long)t.pairs, (unsigned long long)t.boundsDisjoint, (unsigned long long)t.behindPlane,
                    (unsigned long long)t.inFrontOfPlane, (unsigned long long)t.projectionsDisjoint,
                    (unsigned long long)t.unresolved, t.ms);
    }
    return 0;
}
