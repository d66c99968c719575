#include "cli/commands.h"
#include "common/process_heap.h"

int main(int argc, char **argv) {
    va::setUpProcessHeap();
    return va::runCli(argc, argv);
}
