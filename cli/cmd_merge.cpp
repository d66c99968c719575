// visaudit merge: the reports of analyze --shard K/N runs joined into one.
#include <cstdio>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli/command_table.h"
#include "cli/commands.h"
#include "cli/shared.h"
#include "reports/html.h"
#include "reports/merge.h"
#include "reports/report.h"

namespace va {
namespace {

struct MergeOptions {
    std::vector<std::string> mergeDirs;  // the shards' --out folders
    std::string out = "visaudit-report";
    bool quiet = false;
    uint64_t maxJsonDepth = kDefaultMaxJsonDepth;
};

int cmdMerge(const MergeOptions &o) {
    installInterruptHandlers();
    std::string err;
    OutputDir out;
    if (!out.open(o.out, &err)) {
        fail(err);
        return kExitBadInput;
    }
    nlohmann::ordered_json merged;
    if (!mergeReports(o.mergeDirs, out.staging(), &merged, &err, o.maxJsonDepth)) {
        fail(err);
        return kExitBadInput;
    }
    if (!writeFileAtomic(out.staging() + "/report.json", merged.dump(2) + "\n", &err) ||
        !writeReportHtml(merged, out.staging(), &err)) {
        fail(err);
        return kExitBadInput;
    }
    if (const int code = commitOutput(out, o.out); code != kExitOk) return code;
    if (!o.quiet)
        std::printf("merged %zu shards, %zu views: %s/report.json\n", o.mergeDirs.size(), merged["views"].size(),
                    o.out.c_str());
    return kExitOk;
}

void addMergeOptions(CLI::App *c, MergeOptions &o) {
    c->add_option("shards", o.mergeDirs, "The --out folders of every analyze --shard K/N run")->required();
    c->add_option("--out", o.out, "Output folder for the merged report (written as a whole or not at all)");
    c->add_flag("--quiet", o.quiet, "No summary on the console");
    addJsonDepthOption(c, o.maxJsonDepth);
}

}  // namespace

CommandRun setupMerge(CLI::App *c) { return bindCommand<MergeOptions>(c, addMergeOptions, cmdMerge); }

}  // namespace va
