#include "cli/commands.h"

#include <cstdio>

namespace va {

int runCli(int argc, char **argv) {
    std::fprintf(stderr, "visaudit: under construction\n");
    return kExitInternal;
}

}  // namespace va
