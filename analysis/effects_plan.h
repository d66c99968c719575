// The effects planner (docs/architecture.md, "Effects: simulate only what the scene calls for"): from the scene,
// which effects run and why; a flag forces any of them on or off. The plan goes into the report, so
// the promise "only the effects a scene calls for" is visible. Rules: docs/effects.md.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "analysis/scene.h"
#include "render/effects.h"

namespace va {

// Command-line overrides: nullopt lets the scene decide; true/false force the effect on/off.
struct EffectFlags {
    std::optional<bool> shadows;      // --shadows / --no-shadows
    std::optional<bool> reflections;  // --reflections / --no-reflections
    std::optional<bool> refractions;  // --refractions / --no-refractions
    std::optional<bool> abuffer;      // --abuffer / --no-abuffer
    int maxDepth = 4;                 // --max-depth: secondary rays of depth 1..maxDepth
};

struct EffectDecision {
    std::string name;     // "shadows", "reflections", "refractions", "abuffer"
    bool run = false;     // the effect runs
    bool forced = false;  // a flag decided (reason says which), not the scene
    std::string reason;   // why it runs or not, e.g. "scene has no lights", "forced off by --no-shadows"
    uint64_t triangles = 0;  // triangles whose material calls for it (0 for shadows)
};

struct EffectPlan {
    EffectDecision shadows, reflections, refractions, abuffer;
    int maxDepth = 4;
    // Whether any ray-traced effect runs (the raycast stage then keeps barycentrics for traceEffects).
    bool tracesRays() const { return shadows.run || reflections.run || refractions.run; }
    std::vector<EffectDecision> all() const { return {shadows, reflections, refractions, abuffer}; }
};

EffectPlan planEffects(const Scene &scene, const EffectFlags &flags);

// The plain data render/ needs from the scene for secondary rays, built once per scene.
struct SceneEffectsData {
    std::vector<EffectLight> lights;
    std::vector<SurfaceMaterial> materials;  // Scene::materials, in order
    std::vector<uint32_t> triangleMaterial;  // per source triangle (excluded triangles: 0)
    std::vector<uint8_t> doubleSided;        // per source triangle (PrimaryOptions::doubleSided)
};
SceneEffectsData effectsDataFor(const Scene &scene);

// The input of traceEffects for this plan (refers to `data`, which must outlive it).
EffectsInput effectsInputFor(const SceneEffectsData &data, const EffectPlan &plan);

}  // namespace va
