// Grading a student's per-stage statistics against the reference report (`visaudit grade`).
// Every count of every stage and of the z-buffer summary is compared per view, with absolute and
// relative tolerances per metric. Plain data in, plain result out.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/limits.h"

namespace va {

constexpr const char *kToleranceFormat = "visaudit-tolerance/1";

// Tolerances: a metric passes when |submitted - reference| <= abs or <= rel * |reference|.
// Metric names are "STAGE.KEY" (e.g. "clip.triangles_out", "frustum.plane_tests") or
// "zbuffer_summary.KEY" (e.g. "zbuffer_summary.overdraw", "zbuffer_summary.histogram"); a rule
// "clip.*" covers every key of a stage. Defaults: integers exact, real numbers rel 1e-9.
struct Tolerance {
    double abs = 0, rel = 0;
};
struct ToleranceRules {
    std::vector<std::pair<std::string, Tolerance>> rules;  // in file order; the last match wins
    bool hasDefault = false;
    Tolerance defaults;
};
bool loadTolerances(const std::string &path, ToleranceRules *out, std::string *err,
                    uint64_t maxJsonDepth = kDefaultMaxJsonDepth);

struct GradeItem {
    std::string view, stage, key;
    std::string reference, submitted;  // formatted; "missing" when the submission lacks it
    bool pass = true;
    std::string note;                  // kit grading: what a list or image comparison found (or "")
};
struct GradeResult {
    std::vector<GradeItem> items;  // views in reference order, stages in reference order
    size_t passed = 0, failed = 0;
    double score = 0;              // passed / items, in [0, 1]
};

// The tolerance of `metric` under the rules: the last rule naming it ("clip.triangles_out"), a
// wildcard covering it ("clip.*") or a prefix of it ("clip.per_plane" covers "clip.per_plane.near");
// else the file's default; else `builtin`.
Tolerance toleranceFor(const ToleranceRules &t, const std::string &metric, Tolerance builtin);

// Compares the submission with the reference. False + message when either is not a report.
bool gradeReports(const nlohmann::ordered_json &reference, const nlohmann::ordered_json &submission,
                  const ToleranceRules &tol, GradeResult *out, std::string *err);

// Score table: per view and stage, passed/total, then every failed item.
std::string gradeTable(const GradeResult &r);
nlohmann::ordered_json gradeJson(const GradeResult &r);

}  // namespace va
