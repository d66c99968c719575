// Comparing two runs (`visaudit diff OLD NEW`; docs/diff.md): per view matched by name and per
// route frame the metric deltas, the level maps of the change, and image diffs where the views'
// images differ. Reads two report folders, writes diff.json (visaudit-diff/1), diff.html and the
// images; `budget` regressions (reports/budget.h) decide the exit code. Reports only, never a stage.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "reports/routes.h"

namespace va {

constexpr const char *kDiffFormat = "visaudit-diff/1";

// One side of the comparison: a report and the folder holding its images.
struct DiffSide {
    std::string label;              // as given on the command line
    std::string dir;                // the report's folder
    nlohmann::ordered_json report;
};

// Reads a report given as its report.json or its folder; false + message naming it and a fix.
bool readDiffSide(const std::string &given, const char *which, uint64_t maxJsonDepth, DiffSide *out, std::string *err);

// The metrics compared per view, in table order: each view's findings.score (false-cull pixels,
// genuine disagreements, z-fighting pixels and hotspots, overdraw, depth complexity, wasted-draw
// share, triangles drawn) and its total_ms.
const std::vector<ViewMetric> &diffMetrics();
// The change image's name of one image of a view: BASE.KIND.diff.png (KIND from the image's key:
// overdraw_png -> overdraw).
std::string imageDiffName(const std::string &newImageFile, const std::string &key);

// Compares the two reports and writes the image diffs and the level maps of the change into
// outDir; *out receives diff.json's document. False + message when the reports cannot be
// compared (another report format, another scene) or a file cannot be written.
bool diffReports(const DiffSide &oldSide, const DiffSide &newSide, const std::string &outDir, nlohmann::ordered_json *out,
                 std::string *err);

// diff.html: the document as one self-contained page (the images next to it).
std::string diffHtml(const nlohmann::ordered_json &diff, const std::string &dir);
// A console summary: views compared and changed, the largest changes, images that differ.
std::string diffSummary(const nlohmann::ordered_json &diff);

}  // namespace va
