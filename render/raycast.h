// Ray casting with Embree 3 (docs/architecture.md, Stages: raycast). Plain data in: world positions and
// triangles; the same camera model as the z-buffer (camera.h): one primary ray per pixel center,
// direction with view-space z = -1 so the hit distance t is the view depth, t in [near, far].
//
// Two kinds of queries:
//  - primary rays, whole images, as 4x4 rtcIntersect16 packets over 16x16 tiles, bands of tiles in
//    parallel (castPrimary; identical results for any thread count);
//  - single rays in the scene's float frame (intersect / occluded), for secondary rays
//    (render/effects.h) and tests.
//
// Embree's geometric normal: for a triangle (v0, v1, v2) Embree reports Ng = (v1 - v0) x (v2 - v0)
// (unnormalized; Embree's Pluecker test computes it as cross(v2 - v0, v0 - v1)), i.e. the same
// orientation as Scene::planes: Ng points to the front (counter-clockwise) side. A ray hits the front
// of a triangle when dot(Ng, dir) < 0. (Test: Raycast.EmbreeNgIsCounterClockwiseFront.)
#pragma once

#include <cmath>
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
    // Only with PrimaryOptions::keepBarycentrics (secondary rays start from these): Embree's
    // barycentric coordinates of the hit, point = (1 - u - v) v0 + u v1 + v v2; 0 at background.
    std::vector<float> u, v;
};

// Storage handed to the next view (render/recycle.h): a finished view gives its ray-cast image
// back, emptied, and the next castPrimary fills it instead of faulting fresh pages in (img is left
// empty).
void recycleRaycastImage(RaycastImage &img);

struct RaycastStats {
    uint64_t rays = 0;     // primary rays cast (one per pixel)
    uint64_t hits = 0;     // rays that hit a triangle
    uint64_t packets = 0;  // 16-wide packets traced
};

// Options of the primary cast beyond the plain ray-casting default.
struct PrimaryOptions {
    // Reference-visibility mode: a single-sided triangle is visible from its front only, so hits on the
    // back of single-sided triangles are rejected (the ray goes on to what lies behind). Front is
    // decided per triangle with docs/architecture.md's backface rule: the plane at the eye > 0 (perspective), or
    // the plane normal against the view direction < 0 (orthographic); exactly 0 (edge-on) is back.
    bool rejectBackFaces = false;
    // Per source triangle: nonzero = double-sided (never rejected). Null: every triangle single-sided.
    const uint8_t *doubleSided = nullptr;
    // Per source triangle: the world plane (nx, ny, nz, k), n = (v1 - v0) x (v2 - v0), as in
    // Scene::planes, so the facing decision is the backface stage's own (in double). Null: computed
    // in double from the float vertices Embree holds.
    const double *planes = nullptr;
    // Of two hits at a bit-identical distance (a ray exactly through a shared edge, coplanar
    // triangles) keep the lower source id, as the reference visibility does (docs/architecture.md, Ties).
    // Without it Embree keeps whichever it found last, which depends on the traversal: packet and
    // single-ray kernels can differ there.
    bool tiesToLowestId = false;
    // Fill RaycastImage::u and v (render/effects.h needs them).
    bool keepBarycentrics = false;
    // Per source triangle: nonzero = not in this cast's triangle set (hits on it are rejected, the
    // ray goes on to what lies behind). Null: every triangle of the scene. The cross-check casts the
    // z-buffer's own triangle set this way (docs/audits.md, "Like with like").
    const uint8_t *rejectSource = nullptr;
};

// A single ray in the scene's float frame (world position minus RayScene::origin()).
struct LocalRay {
    float org[3] = {0, 0, 0};
    float dir[3] = {0, 0, -1};
    float tnear = 0;
    float tfar = INFINITY;
};
constexpr uint32_t kNoHit = 0xFFFFFFFFu;
struct LocalHit {
    uint32_t prim = kNoHit;  // Embree primitive index (see RayScene::sourceOf); kNoHit = miss
    float t = INFINITY;
    float u = 0, v = 0;      // barycentrics: point = (1 - u - v) v0 + u v1 + v v2
    float ng[3] = {0, 0, 0}; // Embree's unnormalized geometric normal (v1 - v0) x (v2 - v0)
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

    // One ray per pixel center, traced as 4x4 rtcIntersect16 packets over 16x16 tiles; bands of 16
    // rows run in parallel (oneTBB, as many threads as tbb::global_control allows). The result does not
    // depend on the thread count.
    RaycastImage castPrimary(const Camera &cam, RaycastStats *stats) const;
    // The same rays with options (back-face rejection, barycentrics). With default options the
    // result equals castPrimary(cam, stats).
    RaycastImage castPrimary(const Camera &cam, const PrimaryOptions &opt, RaycastStats *stats) const;

    // The raw anchor for benchmarks: the same rays and packets in the same order, rtcIntersect16 on the
    // calling thread, no id mapping or depth output; returns the hits.
    uint64_t castPrimaryRaw(const Camera &cam) const;

    // The primary ray of pixel (x, y) exactly as castPrimary traces it (float frame; tnear = near,
    // tfar = far).
    LocalRay primaryRay(const Camera &cam, int x, int y) const;

    // Closest hit / any hit along one ray (rtcIntersect1 / rtcOccluded1). Thread-safe.
    LocalHit intersect(const LocalRay &ray) const;
    // Closest hits of n rays of any directions (a ray stream: the PVS audit's rays from one eye),
    // traced in order as 16-wide packets (rtcIntersect16) on the calling thread; hits[i] is ray
    // i's, as intersect() would give it (barycentrics and normal included). With rejectBackFaces a
    // hit on a triangle's back, dot(Ng, dir) >= 0 in float (edge-on counts as back), is passed
    // through and the ray goes on. Thread-safe; the same rays in the same order give the same hits.
    void intersectStream(const LocalRay *rays, size_t n, bool rejectBackFaces, LocalHit *hits) const;
    bool occluded(const LocalRay &ray) const;

    Vec3 origin() const;
    size_t primitiveCount() const;
    uint32_t sourceOf(uint32_t prim) const;             // global (source) triangle id of a primitive
    uint32_t primitiveOf(uint32_t sourceTriangle) const; // kNoHit when the triangle is not in the scene
    // The float vertices Embree intersects (float frame), v[3 * corner + axis].
    void vertices(uint32_t prim, float v[9]) const;

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace va
