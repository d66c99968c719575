// The clip stage: world triangles to screen triangles (docs/architecture.md, Stages: clip).
//
// Each triangle is classified against the six clip planes in homogeneous clip space (camera.h):
// trivially rejected (all three vertices outside one plane), inside (inside all planes of the view
// frustum), guard-band accepted (inside near and far and inside the guard band, so the rasterizer's
// fixed point can hold it without clipping), or clipped: Sutherland-Hodgman against the planes it
// crosses, in clip space, before the divide (the near plane always, so nothing behind the eye is
// ever projected), then fan triangulation of the output polygon.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "render/camera.h"
#include "render/raster.h"

namespace va {

// Geometry as plain arrays: world-space positions and three vertex indices per triangle.
struct MeshView {
    const Vec3 *positions = nullptr;
    const uint32_t *indices = nullptr;  // 3 per triangle, indexed by global triangle index
};

// A batch of triangles whose vertices all lie in [vertexBegin, vertexEnd) (one scene object): the
// clipper transforms that range once and reuses the results for every triangle of the batch.
struct ClipBatch {
    uint32_t vertexBegin = 0, vertexEnd = 0;
    const uint32_t *triangles = nullptr;  // global triangle indices
    uint32_t count = 0;
};

struct ClipSettings {
    // Guard band: triangles are accepted without clipping while their vertices stay within this many
    // pixels outside the viewport on every side; fixed-point coordinates then stay far below 2^31.
    double guardBandPixels = 8192;
};

enum ClipPlane { kPlaneNear, kPlaneFar, kPlaneLeft, kPlaneRight, kPlaneBottom, kPlaneTop, kClipPlaneCount };
extern const char *const kClipPlaneNames[kClipPlaneCount];

struct ClipStats {
    uint64_t trianglesIn = 0;
    uint64_t trivialRejected = 0;   // all vertices outside one plane (frustum or guard band)
    uint64_t inside = 0;            // entirely inside the view frustum
    uint64_t guardBandAccepted = 0; // crosses a side of the viewport but stays in the guard band
    uint64_t clipped = 0;           // went through Sutherland-Hodgman
    uint64_t clippedAway = 0;       // clipped to nothing (fewer than 3 vertices left)
    uint64_t edgeOn = 0;            // plane through the eye (perspective): covers no area, dropped
    std::array<uint64_t, kClipPlaneCount> perPlane{};  // triangles clipped against each plane
    std::array<uint64_t, 10> polygonVertices{};  // clipped polygons by vertex count (index 9 = 9+)
    uint64_t trianglesOut = 0;      // screen triangles emitted (after fan triangulation)
};

struct ClipResult {
    ScreenTriangles out;
    ClipStats stats;
};

ClipResult clipTriangles(const Camera &cam, const MeshView &mesh, const std::vector<ClipBatch> &batches,
                         const ClipSettings &settings);

// A vertex in the clipper's space: clip-space x, y, w and the view depth d (camera.h). From a
// view-space point (x, y, z): (sx x, sy y, w, -z) with w = -z (perspective) or 1 (orthographic).
struct ClipVertex {
    double x, y, w, d;
};
// A polygon that reaches the rasterizer: a triangle accepted whole (its three corners), or what
// Sutherland-Hodgman left of a clipped one (3 to 9 vertices, fanned from the first).
struct ClipPolygon {
    uint32_t source = 0;
    std::vector<ClipVertex> vertices;
};

// The clip stage on triangles given by their view-space corners (an assignment kit's clip input,
// analysis/kit.h): view[3 t + k] is corner k of triangle t, source[t] its id, in submission order.
// clipTriangles is this after transforming each vertex with cam.viewFromWorld: the same
// classification, clipping, depth plane and projection, so the same screen triangles and counts.
// `polygons` (optional) receives, in order, the polygon of every triangle that reaches the
// rasterizer (inside, guard-band accepted, or clipped to 3 or more vertices).
ClipResult clipViewTriangles(const Camera &cam, const std::vector<Vec3> &view, const std::vector<uint32_t> &source,
                             const ClipSettings &settings, std::vector<ClipPolygon> *polygons = nullptr);

}  // namespace va
