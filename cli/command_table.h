// Each subcommand's flags, bound to an options struct of its own; the function returned runs the
// command with them once the command line is parsed. cli/commands.cpp lists them in kCommands.
#pragma once

#include <functional>

#include <CLI/CLI.hpp>

namespace va {

using CommandRun = std::function<int()>;
CommandRun setupInfo(CLI::App *c);        // cli/cmd_info.cpp
CommandRun setupAnalyze(CLI::App *c);     // cli/cmd_analyze.cpp
CommandRun setupCheck(CLI::App *c);       // cli/cmd_analyze.cpp
CommandRun setupGrade(CLI::App *c);       // cli/cmd_grade.cpp
CommandRun setupAssignment(CLI::App *c);  // cli/cmd_assignment.cpp
CommandRun setupMerge(CLI::App *c);       // cli/cmd_merge.cpp
CommandRun setupDiff(CLI::App *c);        // cli/cmd_diff.cpp
CommandRun setupDepthAudit(CLI::App *c);  // cli/cmd_depth_audit.cpp
CommandRun setupPvsAudit(CLI::App *c);    // cli/cmd_pvs_audit.cpp

// The usual setup: a fresh options struct, its flags, and the command bound to it.
template <class Options>
CommandRun bindCommand(CLI::App *c, void (*addOptions)(CLI::App *, Options &), int (*run)(const Options &)) {
    auto o = std::make_shared<Options>();
    addOptions(c, *o);
    return [o, run] { return run(*o); };
}

}  // namespace va
