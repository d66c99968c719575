// Ray casting with Embree 3 (DESIGN.md, Stages: raycast). Plain data in: world positions and
// triangles; the same camera model as the z-buffer (camera.h): one primary ray per pixel center,
// direction with view-space z = -1 so the hit distance t is the view depth, t in [near, far].
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "render/camera.h"
#include "render/clip.h"

namespace va {

struct RaycastImage {
    int width = 0, height = 0;
    std::vector<uint32_t> id;  // 1 + source triangle index of the first hit; 0 = background
    std::vector<float> depth;  // hit distance t (= view depth); +inf = background
};

struct RaycastStats {
    uint64_t rays = 0;     // primary rays cast (one per pixel)
    uint64_t hits = 0;     // rays that hit a triangle
    uint64_t packets = 0;  // 16-wide packets traced
};

// An Embree scene over a set of triangles. Vertices are stored in float relative to `origin`
// (the scene's center) so that scenes far from the world origin keep their precision.
class RayScene {
  public:
    RayScene();
    ~RayScene();
    RayScene(const RayScene &) = delete;
    RayScene &operator=(const RayScene &) = delete;

    // Builds over `triangles` (global ids) of mesh, whose vertices are positions[0 .. vertexCount).
    bool build(const MeshView &mesh, size_t vertexCount, const std::vector<uint32_t> &triangles, Vec3 origin,
               std::string *err);

    // One ray per pixel center, in 4x4 tiles traced as rtcIntersect16 packets.
    RaycastImage castPrimary(const Camera &cam, RaycastStats *stats) const;

    // The raw anchor for benchmarks: the same rays, rtcIntersect16, no id mapping or depth output.
    uint64_t castPrimaryRaw(const Camera &cam) const;

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace va
