// Secondary rays from the visible points of a primary cast (docs/architecture.md, "Effects: simulate only what the
// scene calls for"): shadow rays to each light, reflection rays from reflective materials, refraction
// rays (with their Fresnel reflection) from refractive ones, recursion bounded by a maximum depth.
// Plain data in (lights, a material table, a material index per source triangle); render/ never sees
// the scene model. What to enable is decided by analysis/effects_plan.h. The rules, the ray kinds, the
// origin offset and the Fresnel choice are written down in docs/effects.md.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "render/camera.h"
#include "render/raycast.h"

namespace va {

struct EffectLight {
    std::string name;
    bool directional = true;
    Vec3 direction{0, -1, 0};  // directional: the direction the light travels (world; any length > 0)
    Vec3 position;             // point: world position
};

// What secondary rays need of a material (analysis/scene.h's Material, as plain data).
struct SurfaceMaterial {
    bool doubleSided = false;
    double reflective = 0;  // 0..1: mirror reflectance; > 0 spawns a reflection ray
    double ior = 1;         // != 1: refractive (a refraction ray with Fresnel weighting)
    double alpha = 1;       // < 1: transparent (the A-buffer's business, not ray tracing's)
};

struct EffectsInput {
    std::vector<EffectLight> lights;
    std::vector<SurfaceMaterial> materials;     // the material table; empty: every triangle default
    std::span<const uint32_t> triangleMaterial; // per source triangle: index into materials
    bool shadows = true;       // shadow rays from each visible point to each light
    bool reflections = true;   // reflection rays from reflective materials
    bool refractions = true;   // refraction rays (and their Fresnel reflection) from refractive materials
    int maxDepth = 4;          // secondary rays of depth 1 .. maxDepth are traced (primary = depth 0)
};

struct LightShadowStats {
    std::string name;
    uint64_t shadowRays = 0;        // rays cast to this light (one per visible pixel not facing away)
    uint64_t litPixels = 0;         // visible pixels that see the light
    uint64_t shadowedPixels = 0;    // visible pixels whose shadow ray is blocked ("the tree is between
                                    //   the ground and the sun"); best case: what the level intends
    uint64_t facingAwayPixels = 0;  // visible pixels whose visible side faces away from the light, or
                                    //   whose plane contains it (within the point's error bound): unlit
                                    //   without a ray
};

struct EffectsStats {
    uint64_t primaryRays = 0;        // pixels of the primary cast (one ray each)
    uint64_t primaryHits = 0;        // of which hit a triangle (the visible points)
    uint64_t shadowRays = 0;         // all lights
    uint64_t reflectionRays = 0;     // mirror reflections and the Fresnel reflections of refractive surfaces
    uint64_t refractionRays = 0;     // transmitted rays
    uint64_t secondaryHits = 0;      // reflection and refraction rays that hit a triangle (others escape)
    uint64_t totalInternalReflections = 0;  // refractive hits where no ray can be transmitted (TIR)
    uint64_t terminatedByDepth = 0;  // rays a hit called for but not traced: they would exceed maxDepth
    int deepest = 0;                 // deepest secondary ray traced (0..maxDepth)
    double reflectionWeight = 0;     // sum of the throughput carried by reflection rays (Fresnel and
    double refractionWeight = 0;     //   reflectance products); a pixel's primary ray carries 1
    double ms = 0;                   // wall time
};

struct EffectsResult {
    bool ok = true;
    std::string error;               // when !ok: what was wrong with the input
    EffectsStats stats;
    std::vector<LightShadowStats> lights;  // one per input light, in order
    int width = 0, height = 0;
    // Per light, a bit per pixel: 1 = shadowed (its shadow ray was blocked). Rows are padded to whole
    // 64-bit words (maskStride words per row) so rows can be filled in parallel.
    size_t maskStride = 0;
    std::vector<std::vector<uint64_t>> shadowMask;
    std::vector<uint8_t> secondaryDepth;  // per pixel: deepest secondary ray traced (0 = none)
    std::vector<uint16_t> secondaryRays;  // per pixel: reflection + refraction rays traced (saturates)
    // Frees the per-pixel buffers once the images are written (the statistics stay).
    void releasePixels() {
        std::vector<std::vector<uint64_t>>().swap(shadowMask);
        std::vector<uint8_t>().swap(secondaryDepth);
        std::vector<uint16_t>().swap(secondaryRays);
    }

    bool shadowed(size_t light, int x, int y) const {
        return (shadowMask[light][size_t(y) * maskStride + size_t(x >> 6)] >> (x & 63)) & 1u;
    }
};

// Traces the effects enabled in `in` from every visible pixel of `primary`, which must come from
// scene.castPrimary(cam, {.keepBarycentrics = true}, ...). Deterministic: identical results for any
// number of threads (rows run in parallel with TBB; sums are reduced in row order).
EffectsResult traceEffects(const RayScene &scene, const Camera &cam, const RaycastImage &primary,
                           const EffectsInput &in);

// --- Robust secondary-ray origins (pbrt-v3, "Robust Spawned Ray Origins"), public for the tests ----

// A hit point on one of the scene's float triangles.
struct SurfacePoint {
    uint32_t prim = kNoHit;
    Vec3 p;              // the point, float frame, computed in double from Embree's barycentrics
    Vec3 n;              // unit geometric normal, front (counter-clockwise) side
    double offset = 0;   // distance along n that puts an origin safely off the surface (docs/effects.md)
};
SurfacePoint surfacePoint(const RayScene &scene, uint32_t prim, float u, float v);

// The float origin of a ray that leaves the surface in direction `dir`: p moved by sp.offset along n
// towards dir's side, each coordinate then rounded away from the surface. A ray from it in any
// direction on that side never hits the same triangle again (test: Effects.ReintersectProperty).
void offsetRayOrigin(const SurfacePoint &sp, Vec3 dir, float org[3]);

// Exact dielectric Fresnel reflectance (unpolarized) for incidence cosine cosI > 0 going from a medium
// of index etaI into etaT; 1 under total internal reflection.
double fresnelDielectric(double cosI, double etaI, double etaT);

}  // namespace va
