// Quake 3 BSP (IBSP v46) in memory: parseBsp, then what loadBspScene does with its result
// (buildScene, the spawn views). The triangle budget is lowered from 50 million to 2 million so a
// header that asks for many patches is refused (the same check) instead of exhausting the fuzzer's
// memory limit.
#include "analysis/load/level_views.h"
#include "analysis/load/load_bsp.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    const std::string name = "input.bsp";
    va::BspOptions opt;
    opt.maxTriangles = 2'000'000;
    va::SceneBuildInput in;
    va::BspLevel level;
    std::string err;
    const bool ok = va::parseBsp(data, size, name, opt, &in, &level, &err);
    va::fuzz::checkResult(ok, err, name);
    if (!ok) return 0;
    va::Scene scene;
    std::string e;
    if (!va::buildScene(std::move(in), {}, &scene, &e)) {
        va::fuzz::checkResult(false, e.empty() ? e : name + ": " + e, name);
        return 0;
    }
    scene.bsp = std::move(level);
    scene.views = va::spawnViews(scene);
    return 0;
}
