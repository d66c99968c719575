// Visibility budgets for CI (`visaudit check`): limits per scene and per view on a report's
// numbers, and relative regressions against a baseline report. Plain data in, plain result out.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "render/depth_format.h"
#include "common/limits.h"

namespace va {

constexpr const char *kBudgetFormat = "visaudit-budget/1";

// A metric a budget can limit: how to read it from one view of report.json, and what it means.
struct BudgetMetric {
    const char *name;
    const char *meaning;     // for messages and the README
    bool isFormat;           // min_depth_format: a depth format name, not a number
    bool higherIsWorse;      // every numeric metric: the limit is a maximum
    bool mapWide = false;    // one value for the whole map (the PVS audit's pvs_*), not per view: allowed
                             //   under "limits" and "regressions" only
};
const std::vector<BudgetMetric> &budgetMetrics();

struct Budget {
    std::string file;
    std::map<std::string, nlohmann::json> limits;                       // every view
    std::map<std::string, std::map<std::string, nlohmann::json>> views; // per view, overriding
    std::map<std::string, double> regressions;                         // metric -> allowed rise (0.1 = 10%)
};

// Reads and validates a budget file: format "visaudit-budget/1", known metric names, limit types,
// view names that exist in `viewNames`, depth format names. Messages: FILE:LINE:COL: place: what; fix.
bool loadBudget(const std::string &path, const std::vector<std::string> &viewNames, Budget *out, std::string *err,
                uint64_t maxJsonDepth = kDefaultMaxJsonDepth);

// The depth formats a budget's min_depth_format limits name (each once, in file order; with
// depth24plus also depth32float, WebGPU's other implementation of it): the z-fighting analysis
// must evaluate them for the budget to be checked.
std::vector<DepthFormatSpec> budgetDepthFormats(const Budget &budget);

// One budget applied to one view.
struct BudgetCheck {
    std::string view, metric;
    std::string kind;        // "limit" or "regression"
    std::string value;       // what the report says (formatted)
    std::string allowed;     // the limit (formatted)
    bool pass = true;
    std::string message;     // e.g. "overdraw in view 'atrium' rose 23%, allowed 10%"
    std::string frame;       // a route's frame: "frame 12 of route 'atrium-run' at 1.5 s" (else empty)
};
struct BudgetResult {
    std::vector<BudgetCheck> checks;  // views in report order, metrics in budgetMetrics() order
    size_t failed = 0;
};

// What evaluateBudget checks: `limits` (check: the limits and the regressions; diff: the
// regressions only), and whether a baseline must be of the same geometry (check: same scene path
// and source triangles; diff compares two versions of one level: the same scene path).
struct BudgetEvaluation {
    bool limits = true;
    bool sameTriangles = true;
};
// Checks the report (and, with a baseline report, the regressions). False + message when the
// report lacks what a budget needs, or the baseline is of another scene or report format.
bool evaluateBudget(const Budget &budget, const nlohmann::ordered_json &report,
                    const nlohmann::ordered_json *baseline, BudgetResult *out, std::string *err,
                    const BudgetEvaluation &how = {});

// Whether the budget names a map-wide metric (pvs_*): `check` then runs the PVS audit too.
bool budgetNeedsPvsAudit(const Budget &budget);

// Checks the map-wide limits (and regressions, with the baseline's pvs-audit.json) against a
// pvs-audit.json (reports/pvs_audit_report.h), appending one check per metric to *out (view
// "(map)"). False + message when the audit lacks a value the budget needs.
bool evaluatePvsBudget(const Budget &budget, const nlohmann::ordered_json &pvsAudit,
                       const nlohmann::ordered_json *baselinePvsAudit, BudgetResult *out, std::string *err);

// A console table of every check (failures first), and the summary line.
std::string budgetTable(const BudgetResult &r);
// JUnit XML: one test suite, one test case per view and budget, failures with their message; a
// route's frame names the frame and its time in the test case's name.
std::string budgetJUnit(const BudgetResult &r, const std::string &suiteName);

}  // namespace va
