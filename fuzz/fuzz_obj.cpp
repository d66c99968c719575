// OBJ files: see fuzz_mesh.h.
#define VISAUDIT_FUZZ_EXT ".obj"
#include "fuzz/fuzz_mesh.h"
