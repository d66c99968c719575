// Routes in the report (report.json "routes"; docs/routes.md): per route its definition (the
// keyframes, the interpolation, the sampling) and its series -- per frame the metrics a level
// designer follows along a camera path -- with its worst frames, and a plot of the series
// (route-NAME.png). The series are computed from the views alone (each frame is a view whose
// "route" names the route), so `merge` recomputes exactly what a single run writes.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "analysis/load/route.h"
#include "reports/canvas.h"

namespace va {

// A per-view number a route's series or a level map follows: read from the view's findings.score
// (triangles_drawn, overdraw, false_cull_pixels, zfight_pixels, wasted_share) or its total_ms.
struct ViewMetric {
    const char *key;      // report key (findings.score's, or "total_ms")
    const char *title;    // for plots and tables
    const char *meaning;  // one line, for the page and the README
    bool real;            // a ratio (printed with decimals), not a count
};
// The route series' metrics, in plot order: triangles drawn, overdraw, false-cull pixels,
// z-fighting pixels, milliseconds per frame.
const std::vector<ViewMetric> &routeMetrics();
// A view's value of a metric: nullopt when the report has no such analysis for the view.
std::optional<double> viewMetric(const nlohmann::ordered_json &view, std::string_view key);

// How many worst frames each metric lists.
constexpr size_t kRouteWorstFrames = 3;

// A route's definition as report.json writes it ("routes"[i] before its series).
nlohmann::ordered_json routeDefinitionJson(const Route &route);
// Sets each route's "series" and "worst" from the report's views (replacing any there).
void addRouteSeries(nlohmann::ordered_json *report);
// The file name of a route's plot: "route-NAME.png" (NAME sanitized, '.' as '_', so it never
// takes the form of a view's BASE.KIND.png).
std::string routePlotName(const std::string &routeName);
// The plot of one route's series (report.json "routes"[i] with its series): one panel per metric
// against time, the worst frames numbered.
Canvas routePlot(const nlohmann::ordered_json &route);
// Writes every route's plot into dir and sets its "image". False + message naming the file.
bool writeRoutePlots(nlohmann::ordered_json *report, const std::string &dir, std::string *err);

}  // namespace va
