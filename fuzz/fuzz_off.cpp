// OFF files: see fuzz_mesh.h.
#define VISAUDIT_FUZZ_EXT ".off"
#include "fuzz/fuzz_mesh.h"
