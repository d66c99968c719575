// The texts of an assignment kit (analysis/kit.h): the scene as an OBJ file, the README a student
// starts from, and the conventions every count and image follows, in the project's own words
// (docs/conventions.md, docs/rasterizer.md, render/clip.h, render/raster_core.h).
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "analysis/kit.h"

namespace va::kit {

// Every source triangle in id order, world coordinates: the k-th "f" line is triangle k (each
// triangle has its own three "v" lines); an "o" line per source object, its material in a comment.
std::string sceneObj(const Scene &scene, const std::string &label);
// README.md: the task, the files, each stage's input and what to hand in. `assignment` is the
// assignment.json document.
std::string kitReadme(const nlohmann::ordered_json &assignment, const KitSettings &ks);
// CONVENTIONS.md; `formats`: the depth formats the kit's views use (each once).
std::string kitConventions(const KitSettings &ks, const std::vector<DepthFormatSpec> &formats);

}  // namespace va::kit
