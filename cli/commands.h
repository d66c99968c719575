// The command-line front end: one table of subcommands (ninja's kTools[]).
#pragma once

namespace va {

// Exit codes (docs/architecture.md, Errors).
enum ExitCode { kExitOk = 0, kExitBudgetFailed = 1, kExitBadInput = 2, kExitInternal = 3 };

int runCli(int argc, char **argv);

}  // namespace va
