// The backface stage (docs/architecture.md, Stages: backface): the plane of each triangle evaluated at the
// eye (perspective) or against the view direction (orthographic); > 0 is front-facing.
// Double-sided materials are exempt. Where the double-precision sign is not certain (|value| within
// its error bound) the exact orientation predicate decides, so the result is exact.
#pragma once

#include <cstdint>
#include <vector>

#include "analysis/results.h"
#include "analysis/scene.h"
#include "render/camera.h"
#include "render/clip.h"

namespace va {

// Triangles grouped by object, in submission order (objects ascending, triangles in object order).
struct TriangleLists {
    std::vector<uint32_t> objects;      // object of each group
    std::vector<uint32_t> groupBegin;   // group g's triangles: triangles[groupBegin[g] .. groupBegin[g+1])
    std::vector<uint32_t> triangles;    // global source triangle indices
    uint64_t size() const { return triangles.size(); }
};

// All triangles of the given objects, unculled.
TriangleLists allTriangles(const Scene &scene, const std::vector<uint32_t> &objects);

// The clip stage's input: one batch per non-empty group, pointing into `lists` (which must outlive it).
std::vector<ClipBatch> clipBatches(const Scene &scene, const TriangleLists &lists);

struct BackfaceResult {
    TriangleLists kept;
    std::vector<uint32_t> culled;  // the triangles it culled, in submission order (for the audits)
    BackfaceStats stats;
};
BackfaceResult cullBackfaces(const Scene &scene, const std::vector<uint32_t> &objects, const Camera &cam);

// True when triangle t faces the camera (exact; see above).
bool isFrontFacing(const Scene &scene, uint32_t t, const Camera &cam, bool *edgeOn = nullptr);

}  // namespace va
