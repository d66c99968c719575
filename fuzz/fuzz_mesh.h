// One mesh file through loadScene (loadMeshFile, then buildScene), as `visaudit analyze x.EXT` reads
// it (glTF and GLB through fuzz_gltf.h). Included by fuzz_obj.cpp, fuzz_ply.cpp, fuzz_off.cpp and
// fuzz_stl.cpp with VISAUDIT_FUZZ_EXT.
#include "analysis/load/load.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    const std::string path = va::fuzz::writeInput(std::string("input") + VISAUDIT_FUZZ_EXT, data, size);
    va::Scene scene;
    std::string err;
    const bool ok = va::loadScene(path, {}, &scene, &err);
    va::fuzz::checkResult(ok, err, path);
    return 0;
}
