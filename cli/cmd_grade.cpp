// visaudit grade: a student's per-stage counts against a reference report.
#include <cstdio>
#include <string>

#include <nlohmann/json.hpp>

#include "cli/command_table.h"
#include "cli/commands.h"
#include "cli/shared.h"
#include "reports/grade.h"
#include "reports/report.h"

namespace va {
namespace {

struct GradeOptions {
    std::string reference, submission, tolerance;
    std::string gradeOut;  // --out: the result as JSON
    uint64_t maxJsonDepth = kDefaultMaxJsonDepth;
};

int cmdGrade(const GradeOptions &o) {
    std::string err;
    nlohmann::ordered_json ref, sub;
    ToleranceRules tol;
    if (!readJsonFile("--reference", o.reference, o.maxJsonDepth, &ref, &err) ||
        !readJsonFile("--submission", o.submission, o.maxJsonDepth, &sub, &err) ||
        (!o.tolerance.empty() && !loadTolerances(o.tolerance, &tol, &err, o.maxJsonDepth))) {
        fail(err);
        return kExitBadInput;
    }
    GradeResult g;
    if (!gradeReports(ref, sub, tol, &g, &err)) {
        fail(err);
        return kExitBadInput;
    }
    std::printf("%s", gradeTable(g).c_str());
    if (!o.gradeOut.empty() && !writeFileAtomic(o.gradeOut, gradeJson(g).dump(2) + "\n", &err)) {
        fail(err);
        return kExitBadInput;
    }
    return g.failed ? kExitBudgetFailed : kExitOk;
}


void addGradeOptions(CLI::App *c, GradeOptions &o) {
    c->add_option("--reference", o.reference, "The reference report.json")->required();
    c->add_option("--submission", o.submission, "The student's report.json (the same keys)")->required();
    c->add_option("--tolerance", o.tolerance, "Tolerances per metric (visaudit-tolerance/1)");
    c->add_option("--out", o.gradeOut, "Write the result as JSON here");
    addJsonDepthOption(c, o.maxJsonDepth);
}

}  // namespace

CommandRun setupGrade(CLI::App *c) { return bindCommand<GradeOptions>(c, addGradeOptions, cmdGrade); }

}  // namespace va
