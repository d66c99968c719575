// Views at sample positions covering a level (docs/level-maps.md): grid:N over the floor plan
// (analysis/level_map.h) and clusters (a Quake 3 map's), each position seen in several directions;
// the level maps colour each position by the worst of its views. Kept out of analysis/load/ (whose
// loaders the fuzz targets link alone): grid:N renders the level through render/.
#pragma once

#include <string>
#include <vector>

#include "analysis/scene.h"

namespace va {

// Views at sample positions covering a level, each position seen in `dirs` directions (yaws 0,
// 360/dirs, ...; horizontal, as route.h's yaw; 4 by default: the four quarters of the horizon, a
// full panorama with Quake 3's 90-degree lens). Positions "gridK" / "clusterC", views "gridK" (one
// direction) or "gridK-yawD"; origin "grid:N:D" / "clusters:D".
//
// grid:N -- N positions on a square lattice over the level's floor plan (rendered from above
// through the project's rasterizer at 1024 pixels): lattice points on a surface a player can stand
// on (|n . up| >= 0.7, Quake 3's MIN_WALK_NORMAL), the eye `eyeHeight` above it; on a Quake 3 map
// only where the eye is inside a cluster. The lattice spacing is the largest that gives at least N
// such points; when it gives more, N are kept evenly along the raster order. Any scene. Empty with
// *err when there are fewer than N places to stand.
std::vector<ViewSpec> gridViews(const Scene &scene, int n, int dirs, double eyeHeight, std::string *err);
// clusters -- one position per cluster of a Quake 3 map: in the cluster's largest leaf (by its
// horizontal area; the next largest when the eye would stand in solid there), placed as walk:N
// places its points (analysis/load/level_views.h).
std::vector<ViewSpec> clusterViews(const Scene &scene, int dirs);

// Parses a --views value naming level samples: "grid:N", "grid:N:D", "clusters", "clusters:D" (D
// directions per position, 1..8, default 4). False with a message when the value is malformed or
// the scene cannot give such views. `handled` is false (and nothing else happens) for other values.
// `eyeHeight` (grid:N): 0 for the scene's default (levelEyeHeight).
bool levelSampleViews(const std::string &spec, const Scene &scene, std::vector<ViewSpec> *out, bool *handled,
                      std::string *err, double eyeHeight = 0);

}  // namespace va
