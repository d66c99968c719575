// Findings: what a reader of a report looks at first, computed once from the report's numbers and
// stored in it (report.json "findings", per view and for the whole report), so that report.html,
// the console and any other reader present the same judgement without computing it again.
//
// Per view ("views[i].findings"):
//   score    the summary row: false-cull pixels, genuine ray-cast disagreements, z-fighting pixels
//            and hotspots in the view's own depth format, overdraw, depth complexity, wasted-draw
//            share, triangles drawn (null: the report has no such analysis for the view)
//   answers  the six questions of visibility (off-screen, too far, less detail, obscured, in front,
//            between a surface and a light), each answered from the view's numbers in plain text:
//            {"question", "answer": [part, ...]} with a part a sentence or {"not_analysed": why},
//            or {"question", "not_analysed": why} when nothing in the report answers it
// For the report ("findings"):
//   worst_first  view positions, worst first: false-cull pixels, then genuine disagreements, then
//                z-fighting pixels, then overdraw (ties keep the view order)
//   verdict      those sums over views and how many views have each, coplanar z-fighting pixels,
//                and the view with the highest overdraw
//
// Computed from report.json alone, so `merge` recomputes exactly what a single run writes.
#pragma once

#include <nlohmann/json.hpp>

namespace va {

// A view's findings (score and answers); `report` gives what views share (the planner's decisions).
nlohmann::ordered_json viewFindings(const nlohmann::ordered_json &view, const nlohmann::ordered_json &report);
// The report's findings (worst_first, verdict) from its views' findings.
nlohmann::ordered_json reportFindings(const nlohmann::ordered_json &report);
// Sets "findings" in every view and in the report (replacing any there).
void addFindings(nlohmann::ordered_json *report);

}  // namespace va
