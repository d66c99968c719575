// The benchmark scene behind every performance figure of the project (docs/rasterizer.md).
//
// A 10 x 10 grid of UV spheres (radius 1, centers (2.5 i, 0, 2.5 j), i, j in 0..9), each with
// 100 segments x 51 bands = 10,000 triangles (pole bands are fans of 100 proper triangles; the 49
// inner bands are 100 quads of 2 triangles), plus a 2-triangle ground quad at y = -1:
// 1,000,002 triangles. Fronts are counter-clockwise seen from outside (from above, for the ground).
#pragma once

#include "analysis/scene.h"
#include "render/camera.h"

namespace va {

constexpr int kBenchSphereGrid = 10;       // spheres per side of the grid
constexpr int kBenchSphereSegments = 100;  // around the y axis
constexpr int kBenchSphereBands = 51;      // from pole to pole
constexpr double kBenchSphereSpacing = 2.5;
constexpr uint64_t kBenchSceneTriangles =
    uint64_t(kBenchSphereGrid) * kBenchSphereGrid * (2 * kBenchSphereSegments * (kBenchSphereBands - 1)) + 2;

// The geometry in world space (y up), spheres first (sphere (i, j) is number 10 i + j), ground last.
RawMesh sphereGridMesh();
// The same grid with each sphere tessellated in `segments` x `bands` (bench/'s scaling table):
// 100 * 2 * segments * (bands - 1) + 2 triangles; segments >= 3, bands >= 2.
RawMesh sphereGridMesh(int segments, int bands);

// The view of the benchmark: eye (11.25, 13, -9) looking at (11.25, -1, 10.5), fov_y 55 degrees,
// 1920 x 1080, near 0.5, far 200. Every triangle lies in front of the near plane.
CameraSpec benchmarkCamera();

}  // namespace va
