// visaudit diff OLD NEW --out DIR: two runs compared (reports/diff.h; docs/diff.md). Exit 1 when a
// regression exceeds the budget's "regressions" (--budget), 2 on bad input.
#include <cstdio>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli/command_table.h"
#include "cli/commands.h"
#include "cli/shared.h"
#include "reports/budget.h"
#include "reports/diff.h"
#include "reports/report.h"

namespace va {
namespace {

struct DiffOptions {
    std::string oldReport, newReport;  // report.json files or their folders
    std::string out = "visaudit-diff";
    std::string budget, junit;
    bool quiet = false;
    uint64_t maxJsonDepth = kDefaultMaxJsonDepth;
};

int cmdDiff(const DiffOptions &o) {
    installInterruptHandlers();
    std::string err;
    DiffSide oldSide, newSide;
    if (!readDiffSide(o.oldReport, "OLD", o.maxJsonDepth, &oldSide, &err) ||
        !readDiffSide(o.newReport, "NEW", o.maxJsonDepth, &newSide, &err)) {
        fail(err);
        return kExitBadInput;
    }
    // The budget, validated against NEW's views before anything is written.
    Budget budget;
    if (!o.budget.empty()) {
        std::vector<std::string> names;
        for (const auto &v : newSide.report["views"])
            if (v.contains("name") && v["name"].is_string()) names.push_back(v["name"]);
        if (!loadBudget(o.budget, names, &budget, &err, o.maxJsonDepth)) {
            fail(err);
            return kExitBadInput;
        }
    }
    OutputDir out;
    if (!out.open(o.out, &err)) {
        fail(err);
        return kExitBadInput;
    }
    nlohmann::ordered_json diff;
    if (!diffReports(oldSide, newSide, out.staging(), &diff, &err)) {
        fail(err);
        return kExitBadInput;
    }
    BudgetResult result;
    if (!o.budget.empty()) {
        // Only the regressions: diff judges change, check judges limits. Two versions of a level
        // differ in their triangles, so the baseline need only be of the same scene path.
        BudgetEvaluation how;
        how.limits = false;
        how.sameTriangles = false;
        if (!evaluateBudget(budget, newSide.report, &oldSide.report, &result, &err, how)) {
            fail(err);
            return kExitBadInput;
        }
        nlohmann::ordered_json checks = nlohmann::ordered_json::array();
        for (const BudgetCheck &c : result.checks)
            checks.push_back({{"view", c.view}, {"metric", c.metric}, {"value", c.value}, {"allowed", c.allowed},
                              {"pass", c.pass}, {"message", c.message}, {"frame", c.frame}});
        diff["regressions"] = {{"budget", o.budget}, {"checks", checks}, {"failed", result.failed}};
    }
    if (!writeFileAtomic(out.staging() + "/diff.json", diff.dump(2) + "\n", &err) ||
        !writeFileAtomic(out.staging() + "/diff.html", diffHtml(diff, out.staging()), &err)) {
        fail(err);
        return kExitBadInput;
    }
    if (const int code = commitOutput(out, o.out); code != kExitOk) return code;
    if (!o.junit.empty() && !o.budget.empty() &&
        !writeFileAtomic(o.junit, budgetJUnit(result, newSide.report["scene"].value("path", std::string())), &err)) {
        fail(err);
        return kExitBadInput;
    }
    if (!o.quiet) {
        std::printf("%s", diffSummary(diff).c_str());
        if (!o.budget.empty()) std::printf("%s", budgetTable(result).c_str());
        std::printf("diff: %s/diff.html\n", o.out.c_str());
    }
    return result.failed ? kExitBudgetFailed : kExitOk;
}

void addDiffOptions(CLI::App *c, DiffOptions &o) {
    c->add_option("old", o.oldReport, "The earlier run: its report.json or --out folder")->required();
    c->add_option("new", o.newReport, "The later run: its report.json or --out folder")->required();
    c->add_option("--out", o.out, "Output folder: diff.json, diff.html, image diffs, level maps of the change");
    c->add_option("--budget", o.budget,
                  "Budget file (visaudit-budget/1): exit 1 when a view or route frame rose more than its \"regressions\" allow");
    c->add_option("--junit", o.junit, "Write JUnit XML here (with --budget): one test case per view and regression");
    c->add_flag("--quiet", o.quiet, "No summary on the console");
    addJsonDepthOption(c, o.maxJsonDepth);
}

}  // namespace

CommandRun setupDiff(CLI::App *c) { return bindCommand<DiffOptions>(c, addDiffOptions, cmdDiff); }

}  // namespace va
