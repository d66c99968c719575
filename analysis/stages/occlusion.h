// The occlusion stage (docs/architecture.md, Stages: occlusion; docs/coarse-stages.md): a depth pre-pass of a
// few selected occluders at the view's full resolution, a hierarchical max-depth pyramid (HiZ) over
// it, and a conservative test of every other object's bounding box against it.
//
// Conservative by construction:
//   * the pre-pass draws the occluders' triangles through the z-buffer's own clipper and fragment
//     core (same coverage, same double depth per pixel center as the reference visibility), with the
//     reference's rule for single-sided materials (front winding only), so every pre-pass depth is
//     a depth the reference also has at that pixel;
//   * a pixel with no occluder fragment has depth +inf, and a pyramid texel is the maximum of its
//     children, so a texel's value is the farthest occluder depth over its whole footprint;
//   * an object is culled only when the nearest view depth of its box (rounded down) is strictly
//     farther than the texels covering every pixel center its projected box (widened by the vertex
//     snapping) can reach; boxes reaching the near plane are never culled; occluders never are.
#pragma once

#include <cstdint>
#include <vector>

#include "analysis/scene.h"
#include "render/camera.h"

namespace va {

struct OcclusionSettings {
    uint32_t maxOccluders = 16;  // occluders drawn in the pre-pass (the best-ranked candidates)
};

// Max-depth pyramid: level 0 is the pre-pass depth per pixel (+inf: no occluder), level k + 1 the
// maximum of (up to) 2 x 2 texels of level k; the last level is 1 x 1.
struct HiZ {
    std::vector<int> width, height;           // per level
    std::vector<std::vector<double>> depth;   // per level, row-major
    size_t levels() const { return depth.size(); }
};
HiZ buildHiZ(std::vector<double> depth, int width, int height);
// The maximum depth over the pixels [x0, x1] x [y0, y1] (inclusive, inside level 0), read from the
// finest level where the rectangle spans at most 4 x 4 texels; texelsRead counts the reads.
double hizMaxDepth(const HiZ &h, int x0, int y0, int x1, int y1, uint64_t *texelsRead);

struct OcclusionStats {
    uint64_t occludersUsed = 0;       // objects drawn in the depth pre-pass (never culled)
    uint64_t occluderTriangles = 0;   // their triangles
    uint64_t prepassFragments = 0;    // fragments the pre-pass rasterized
    uint64_t prepassPixels = 0;       // pixels the occluders cover
    uint64_t hizLevels = 0;           // pyramid levels (level 0 = full resolution)
    uint64_t objectsIn = 0;           // culling objects entering the stage
    uint64_t objectsTested = 0;       // objects tested against the pyramid
    uint64_t objectsCulled = 0;       // hidden behind the occluders + covering no pixel center; higher is better
    uint64_t objectsHidden = 0;       // of the culled: nearest box depth behind the pyramid's depth
    uint64_t objectsNoPixel = 0;      // of the culled: the projected box holds no pixel center of the view
    uint64_t objectsNearPlane = 0;    // kept untested: the box reaches the near plane (or behind the eye)
    uint64_t texelsRead = 0;          // pyramid texels read by the tests
    uint64_t trianglesIn = 0;
    uint64_t trianglesCulled = 0;
    double prepassMs = 0;             // occluder selection, clip, depth pre-pass, pyramid
    double testMs = 0;                // the object tests
};

struct OcclusionResult {
    std::vector<uint32_t> visible;    // kept objects, ascending
    std::vector<uint32_t> culled;     // culled objects, ascending (for the audit's StageCulls)
    std::vector<uint32_t> occluders;  // the occluders used, best-ranked first
    OcclusionStats stats;
};

// Occluder candidates among `objects`: opaque materials (alpha 1), bounding-sphere center in front
// of the eye; ranked by radius / distance from the eye (distance at least the near plane's), ties by
// lower index; the first maxOccluders.
std::vector<uint32_t> selectOccluders(const Scene &scene, const Camera &cam, const std::vector<uint32_t> &objects,
                                      uint32_t maxOccluders);

// `objects`: the objects entering (ascending; the frustum stage's output).
OcclusionResult cullOcclusion(const Scene &scene, const Camera &cam, const std::vector<uint32_t> &objects,
                              const OcclusionSettings &settings = {});

}  // namespace va
