#include "cli/commands.h"

int main(int argc, char **argv) { return va::runCli(argc, argv); }
