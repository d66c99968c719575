// Binary glTF (GLB) files: see fuzz_gltf.h.
#define VISAUDIT_FUZZ_EXT ".glb"
#include "fuzz/fuzz_gltf.h"
