// glTF JSON files: see fuzz_gltf.h.
#define VISAUDIT_FUZZ_EXT ".gltf"
#include "fuzz/fuzz_gltf.h"
