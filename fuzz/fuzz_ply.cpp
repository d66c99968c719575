// PLY files: see fuzz_mesh.h.
#define VISAUDIT_FUZZ_EXT ".ply"
#include "fuzz/fuzz_mesh.h"
