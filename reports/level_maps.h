// Level maps (report.json "level_maps"; docs/level-maps.md): the level's floor plan seen from above
// (analysis/level_map.h) with every sample position coloured by a metric -- triangles drawn,
// overdraw, wasted-draw share, false-cull pixels -- a legend with the scale, and the worst
// positions numbered (the page links each number to its view). One image per metric.
//
// A position is the eye of one or more views (grid:N:D's directions share it); its value is the
// worst (highest) of its views'. Positions, values and the worst are computed from the report's
// views and its floor block alone, so `merge` recomputes exactly what a single run writes, and
// `diff` draws the change between two runs over the same floor plan.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "analysis/level_map.h"
#include "reports/canvas.h"
#include "reports/routes.h"

namespace va {

constexpr const char *kFloorPlanImage = "level-map-floor.png";
// How many worst positions each map numbers.
constexpr size_t kLevelMapWorst = 10;

// The level maps' metrics, one image each: triangles drawn, overdraw, wasted-draw share,
// false-cull pixels (views' findings.score).
const std::vector<ViewMetric> &levelMapMetrics();
// "level-map-METRIC.png"; the change between two runs: "level-map-diff-METRIC.png".
std::string levelMapImageName(const std::string &metric, bool diff = false);

// The "floor" block: the image, its size, the up axis, the orthographic camera (its raster is the
// image's pixels), world units per pixel, pixels with a surface, the render time.
nlohmann::ordered_json floorPlanJson(const FloorPlan &plan);
// The floor plan as an RGB PNG (dir/level-map-floor.png): its gray, and a dark blue-gray where no
// surface faces up.
Canvas floorPlanCanvas(const FloorPlan &plan);
bool writeFloorPlanPng(const FloorPlan &plan, const std::string &dir, std::string *err);

// Sets level_maps.positions and level_maps.maps (values, range, worst) from the report's views and
// level_maps.floor (nothing when the report has no floor block).
void addLevelMaps(nlohmann::ordered_json *report);
// The map of metric `m` over the floor canvas: dots coloured by value on one scale, routes as
// lines, the worst positions numbered, the legend strip below. `diff`: the values are changes
// (diverging scale, symmetric about 0) and the title says so.
Canvas levelMapImage(const nlohmann::ordered_json &levelMaps, size_t m, const Canvas &floor,
                     const nlohmann::ordered_json &views, bool diff = false);
// Reads dir/level-map-floor.png and writes every map into dir, setting each map's "image".
bool writeLevelMapImages(nlohmann::ordered_json *report, const std::string &dir, std::string *err);
// An 8-bit PNG read back as an RGB canvas (the floor plan, a view's image; gray replicated);
// false + message naming the file.
bool readCanvas(const std::string &path, Canvas *out, std::string *err);

}  // namespace va
