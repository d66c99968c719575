// Subcommands: one table (ninja's kTools[]); --help and the README's command list come from it.
// Each command lives in its own file (cli/cmd_*.cpp) with its own options struct; what they share
// is in cli/shared.h.
#include "cli/commands.h"

#include <algorithm>
#include <exception>
#include <new>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>

#include "cli/command_table.h"
#include "cli/shared.h"

namespace va {

namespace {

struct Command {
    const char *name;
    const char *help;
    CommandRun (*setup)(CLI::App *);  // the command's flags; returns the command bound to them
};

const Command kCommands[] = {
    {"info", "Summarize a scene: triangles, objects, bounds, materials, views, degenerate faces", setupInfo},
    {"analyze", "Run every stage for every view; write report.json and images to --out", setupAnalyze},
    {"check", "Analyze, then fail (exit 1) when a view exceeds its budget or regresses against a baseline",
     setupCheck},
    {"grade", "Score a student's per-stage counts against a reference report, or submissions against an assignment kit's "
              "answers (--kit): grade.html, grades.csv",
     setupGrade},
    {"assignment", "Make an assignment kit (each stage's exact input per view, the conventions, a submission template) "
                   "and its reference answers",
     setupAssignment},
    {"merge", "Join the reports of analyze --shard K/N runs into one report", setupMerge},
    {"diff", "Compare two runs: per view and route frame the metric deltas, the level maps of the change, image "
             "diffs; exit 1 when a regression exceeds the budget",
     setupDiff},
    {"depth-audit", "Per depth format: resolution against distance, distinct values, from where 1 cm / 1 mm can fight",
     setupDepthAudit},
    {"pvs-audit", "Audit every cluster of a Quake 3 map's PVS: clusters seen yet hidden (misses), visible yet never seen "
                  "(slack)",
     setupPvsAudit},
};

// Levenshtein distance, for "did you mean" suggestions.
size_t editDistance(const std::string &a, const std::string &b) {
    std::vector<size_t> prev(b.size() + 1), cur(b.size() + 1);
    for (size_t j = 0; j <= b.size(); ++j) prev[j] = j;
    for (size_t i = 1; i <= a.size(); ++i) {
        cur[0] = i;
        for (size_t j = 1; j <= b.size(); ++j)
            cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] != b[j - 1])});
        std::swap(prev, cur);
    }
    return prev[b.size()];
}

}  // namespace

int runCli(int argc, char **argv) {
    // An unknown command gets ninja's treatment: name it, and suggest the nearest one.
    if (argc > 1 && argv[1][0] != '-') {
        const std::string name = argv[1];
        const Command *best = nullptr;
        size_t bestDistance = 3;  // suggest only close matches
        bool known = false;
        for (const Command &c : kCommands) {
            known |= name == c.name;
            const size_t d = editDistance(name, c.name);
            if (d < bestDistance) bestDistance = d, best = &c;
        }
        if (!known) {
            std::string msg = "unknown command '" + name + "'";
            if (best) msg += ", did you mean '" + std::string(best->name) + "'?";
            msg += " (commands:";
            for (const Command &c : kCommands) msg += std::string(" ") + c.name;
            fail(msg + "; see visaudit --help)");
            return kExitBadInput;
        }
    }
    CLI::App app{"visaudit " VISAUDIT_VERSION " - scene-visibility analyzer and report generator"};
    app.set_version_flag("--version", "visaudit " VISAUDIT_VERSION);
    app.require_subcommand(1);
    std::vector<std::pair<CLI::App *, CommandRun>> subs;
    for (const Command &c : kCommands) {
        CLI::App *s = app.add_subcommand(c.name, c.help);
        subs.push_back({s, c.setup(s)});
    }
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError &e) {
        const int code = app.exit(e);
        return code == 0 ? kExitOk : kExitBadInput;
    }
    try {
        for (auto &[s, run] : subs)
            if (s->parsed()) return run();
    } catch (const std::bad_alloc &) {
        fail("out of memory; lower the resolution or the number of views");
        return kExitInternal;
    } catch (const std::exception &e) {
        fail(std::string("internal error: ") + e.what());
        return kExitInternal;
    }
    return kExitBadInput;
}

}  // namespace va
