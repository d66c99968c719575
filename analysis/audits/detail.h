// The detail audit ("too far away to draw", "requires little detail"; docs/coarse-stages.md): per
// view and per drawn object, the triangles drawn against the pixels they end up showing, the
// triangles that covered no pixel center at all, and the projected size of the object. Objects that
// would gain from a draw distance or a coarser level of detail are listed with the triangles it
// would save. Reads the pipeline's z-buffer pass; runs no stage.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "analysis/scene.h"
#include "render/camera.h"

namespace va {

struct DetailSettings {
    double minPixels = 4;          // "too small": projected bounding-sphere diameter below this (pixels)
    double trianglesPerPixel = 1;  // "over-detailed": triangles drawn > visible pixels x this
    size_t listed = 20;            // flagged objects listed (most triangles saved first)
};

// The triangles a coarser version would keep: one per 4 visible pixels (a triangle spanning about
// 2 x 2 pixels is as fine as the pixels can show), and never fewer than 12 (a box): so
// saved = triangles drawn - max(ceil(visible pixels / 4), 12), at least 0. A "too small" object
// would instead stop being drawn past a draw distance: saved = all its triangles drawn.
constexpr uint64_t kLodTrianglesFloor = 12;
constexpr uint64_t kLodPixelsPerTriangle = 4;

struct DetailObject {
    uint32_t object = 0;           // culling object
    std::string name;
    uint64_t trianglesDrawn = 0;   // its triangles that reached the z-buffer
    uint64_t trianglesNoCenter = 0;// of them: covered no pixel center at all (0 fragments)
    uint64_t fragments = 0;        // fragments its triangles rasterized
    uint64_t pixelsVisible = 0;    // pixels where it is the visible surface in the z-buffer
    double projectedPixels = 0;    // projected bounding-sphere diameter, pixels (+inf: eye inside it)
    bool tooSmall = false;         // projectedPixels < minPixels: a draw distance would drop it
    bool overDetailed = false;     // trianglesDrawn > pixelsVisible x trianglesPerPixel
    uint64_t trianglesSaved = 0;   // by the remedy (header comment): draw distance or coarser LOD
};

struct DetailResult {
    uint64_t objectsDrawn = 0;         // objects with a triangle that reached the z-buffer
    uint64_t trianglesDrawn = 0;       // triangles that reached the z-buffer
    uint64_t trianglesNoCenter = 0;    // of them: no pixel center covered; best 0
    uint64_t pixelsVisible = 0;        // pixels showing a drawn object
    double trianglesPerVisiblePixel = 0;  // trianglesDrawn / pixelsVisible; best <= 1
    uint64_t objectsTooSmall = 0;      // best 0
    uint64_t objectsOverDetailed = 0;  // best 0
    uint64_t trianglesSavable = 0;     // over every flagged object; best 0
    std::vector<DetailObject> flagged; // up to DetailSettings::listed, most triangles saved first
                                       //   (ties: lower object index)
    double ms = 0;
};

// `drawnTriangles`: the source triangles that reached the z-buffer (the last culling stage's
// output); `fragmentsPerSource`: per source triangle, the z-buffer pass's fragments
// (ZBufferSettings::fragmentsPerSource); `visibleIds`: the z-buffer's id image (1 + source
// triangle, 0 background), cam.width x cam.height.
DetailResult auditDetail(const Scene &scene, const Camera &cam, const std::vector<uint32_t> &drawnTriangles,
                         const std::vector<uint32_t> &fragmentsPerSource, const std::vector<uint32_t> &visibleIds,
                         const DetailSettings &settings = {});

// Projected diameter in pixels of a sphere seen by the camera: perspective, the angular diameter
// 2 asin(r / dist) as a length on the image plane at the screen's center, H sy tan(asin(r / dist))
// = H sy r / sqrt(dist^2 - r^2) (+inf when the eye is inside); orthographic, 2 r (H / 2) sy.
double projectedDiameterPx(const Camera &cam, const Sphere &s);

}  // namespace va
