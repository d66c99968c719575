// The level seen from above (docs/level-maps.md): an orthographic camera looking down the scene's up
// axis renders the whole scene through the project's own clipper and z-buffer (render/clip.h,
// render/raster.h) -- no other rasterizer -- and keeps, per pixel, the height and the slope of the
// topmost surface that faces up. The level maps draw their sample positions over it; grid:N places
// its eyes on it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "analysis/scene.h"
#include "render/camera.h"

namespace va {

struct FloorPlanSettings {
    int size = 768;          // pixels along the longer side of the scene's horizontal bounds
    double step = 0;         // a height jump (world units) that reads as a wall; 0: from the eye height
    double eyeHeight = 0;    // 0: the scene's default (levelEyeHeight)
};

struct FloorPlan {
    CameraSpec camera;               // orthographic, looking down -U; width x height pixels
    int width = 0, height = 0;
    double worldPerPixel = 0;        // world units per pixel (square pixels)
    char up = 'y';
    double step = 0;                 // the height jump drawn as an outline
    // Per pixel, row-major, (0,0) top-left (the camera's raster):
    std::vector<float> surface;      // height along U of the topmost up-facing surface; NaN: none
    std::vector<float> slope;        // |n . U| of that surface: 1 a floor, 0 a wall
    std::vector<uint8_t> gray;       // the floor plan as drawn: 0 where nothing faces up
    uint64_t drawnPixels = 0;        // pixels with a surface
    double ms = 0;                   // render and shading time
};

// The eye height a level's views stand at above their floor: a Quake 3 map's 50 units (the
// player's eye above its feet, kQuakeFloorEye), else 1.7 (metres: glTF's unit).
double levelEyeHeight(const Scene &scene);

// Renders the floor plan; false + message when the scene has no extent across the up axis.
bool renderFloorPlan(const Scene &scene, const FloorPlanSettings &settings, FloorPlan *out, std::string *err);

// Where a world point falls on the floor plan: continuous pixel coordinates (px, py) of the
// camera's raster (pixel (x, y) covers [x, x+1) x [y, y+1)), by the camera's own transform
// (viewFromWorld, then the orthographic scales). False when the camera cannot be made.
bool floorPixelOf(const CameraSpec &camera, Vec3 p, double *px, double *py);
// The world point at the centre of pixel (x, y) at height h along the up axis.
Vec3 floorWorldAt(const FloorPlan &plan, int x, int y, double h);

}  // namespace va
