// glTF 2.0 through loadScene (tinygltf, our node and accessor walk, then buildScene): the mesh
// harness (fuzz_mesh.h) plus the castle level's buffer placed next to the input, so the
// level-dungeon seed loads whole (data/ must be fetched; without it the seed stops at the missing
// buffer). Included by fuzz_gltf.cpp (.gltf) and fuzz_glb.cpp (.glb) with VISAUDIT_FUZZ_EXT.
#include "fuzz/fuzz_mesh.h"

extern "C" int LLVMFuzzerInitialize(int *, char ***) {
    va::fuzz::provide("data/castle/level/level-dungeon.bin", "level-dungeon.bin");
    return 0;
}
