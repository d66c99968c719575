// glTF 2.0 through loadScene (tinygltf, our node and accessor walk, then buildScene). Included by
// fuzz_gltf.cpp (.gltf) and fuzz_glb.cpp (.glb) with VISAUDIT_FUZZ_EXT. The castle level's buffer
// sits next to the input, so the level-dungeon seed loads whole (data/ must be fetched; without it
// the seed stops at the missing buffer).
#include "analysis/load.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerInitialize(int *, char ***) {
    va::fuzz::provide("data/castle/level/level-dungeon.bin", "level-dungeon.bin");
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    const std::string path = va::fuzz::writeInput(std::string("input") + VISAUDIT_FUZZ_EXT, data, size);
    va::Scene scene;
    std::string err;
    const bool ok = va::loadScene(path, {}, &scene, &err);
    va::fuzz::checkResult(ok, err, path);
    return 0;
}
