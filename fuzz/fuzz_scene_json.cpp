// Scene JSON (visaudit-scene/1) through loadScene: the JSON reader, the meshes it names and
// buildScene. The example meshes sit next to the input as meshes/*, so the seeds
// (examples/*.scene.json) load whole and mutations reach every key.
#include "analysis/load/load.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerInitialize(int *, char ***) {
    for (const char *m : {"hall.obj", "crate.ply", "pane.stl", "banner.off"})
        va::fuzz::provide(std::string("examples/meshes/") + m, std::string("meshes/") + m);
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    const std::string path = va::fuzz::writeInput("input.scene.json", data, size);
    va::Scene scene;
    std::string err;
    const bool ok = va::loadScene(path, {}, &scene, &err);
    va::fuzz::checkResult(ok, err, path);
    return 0;
}
