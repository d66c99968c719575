// Console summaries: short fixed-width text for a terminal or a CI log.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "analysis/results.h"

namespace va {

// One view's stage funnel as a fixed-width table, one row per stage in pipeline order:
//
//   view 'spawn' 1920x1080 f32 perspective
//     stage      status      tris in      culled         out        ms
//     cells      skipped scene has no cells
//     frustum    ran            1200         400         800       0.3
//     zbuffer    ran             800           0         800       2.5
//     zbuffer: 12345 covered pixels, overdraw 1.23, depth complexity 1.50 (max 4)
//
// Counts are right-aligned in 11 columns (wider numbers push the row, never truncate), ms have one
// decimal, ratios two ("n/a" when not finite). Every line ends with '\n'.
std::string funnelTable(const ViewResult &view);

// visaudit info: a scene's summary (triangles, faces, objects, bounds, up axis, materials, lights,
// views) as aligned text, and the same fields as JSON (info --json).
std::string sceneSummaryTable(const Scene &scene, const std::vector<ViewSpec> &views);
nlohmann::ordered_json sceneSummaryJson(const Scene &scene, const std::vector<ViewSpec> &views);

// depth-audit --scene: per view, each format's fighting pixels (coplanar ones in brackets), the
// recommended format, the three largest hotspots and why they fight.
std::string zfightViewsTable(const std::string &scenePath, const AnalysisResult &result);

}  // namespace va
