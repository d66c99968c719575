// Images of the secondary rays (render/effects.h), next to each view's other images:
//   BASE.shadow.LIGHT.png  per light: visible pixels lit (light grey, shaded by depth), in shadow
//                          (blue), facing away from the light (dark grey); background black;
//                          a legend strip below.
//   BASE.secondary.png     per pixel, the deepest secondary ray traced (0 = none: dimmed depth),
//                          one color per depth 1..max, with a legend.
#pragma once

#include <string>

#include "render/effects.h"
#include "render/raster.h"

namespace va {

// grays (both): the z-buffer depth's depthGrays when the caller has them (else computed here).
bool writeShadowImage(const EffectsResult &fx, size_t light, const ZBuffer &zb, const std::string &path,
                      std::string *err, const std::vector<uint8_t> *grays = nullptr);
bool writeSecondaryImage(const EffectsResult &fx, const ZBuffer &zb, const std::string &path, std::string *err,
                         const std::vector<uint8_t> *grays = nullptr);

}  // namespace va
