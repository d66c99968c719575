// The frustum stage: bounding spheres of culling objects against the six view-frustum planes,
// over a BVH of objects (docs/architecture.md, Stages: frustum). Conservative: an object is culled only when
// its sphere is outside a plane by more than the arithmetic's error bound.
#pragma once

#include <cstdint>
#include <vector>

#include "analysis/results.h"
#include "analysis/scene.h"
#include "render/camera.h"

namespace va {

// A bounding-sphere BVH over culling objects (view-independent; built once per scene).
struct ObjectBvh {
    struct Node {
        Sphere sphere;
        uint32_t first = 0;   // leaf: first entry in `order`; inner: index of the left child
        uint32_t count = 0;   // leaf: number of objects (> 0); inner: 0 (right child = left + 1)
    };
    std::vector<Node> nodes;     // nodes[0] is the root (when there is any object)
    std::vector<uint32_t> order; // object indices, leaves reference ranges of it
};
ObjectBvh buildObjectBvh(const Scene &scene);

// World-space planes n.p + k >= 0 inside, |n| = 1: near, far, left, right, bottom, top.
struct FrustumPlanes {
    Vec3 n[6];
    double k[6];
};
FrustumPlanes worldFrustumPlanes(const Camera &cam);

struct FrustumResult {
    std::vector<uint32_t> visible;  // kept objects, ascending (submission order)
    FrustumStats stats;
};
// `candidates` (optional, ascending): the objects a coarser stage kept; the others are not this
// stage's input (neither counted nor returned). Null: every object.
FrustumResult cullFrustum(const Scene &scene, const ObjectBvh &bvh, const Camera &cam,
                          const std::vector<uint32_t> *candidates = nullptr);

// Sphere against planes with a conservative margin: -1 outside some plane, +1 inside all, 0 else.
// `mask` holds the planes still to test (bit i = plane i); planes the sphere is inside are cleared.
int classifySphere(const FrustumPlanes &fp, const Sphere &s, uint32_t *mask, uint64_t *planeTests);

}  // namespace va
