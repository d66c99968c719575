// STL files: see fuzz_mesh.h.
#define VISAUDIT_FUZZ_EXT ".stl"
#include "fuzz/fuzz_mesh.h"
