// Result structs of an analysis: what each stage did, per view. reports/ reads these and never runs
// a stage. Every field says what it counts and its best value; the JSON schema and the README use
// the same words (docs/report-schema.json, README "What the numbers mean").
#pragma once

#include <cstdint>
#include <optional>
#include <variant>
#include <string>
#include <vector>

#include "analysis/audits/audit.h"
#include "analysis/audits/depth_audit.h"
#include "analysis/stages/cells.h"
#include "analysis/audits/detail.h"
#include "analysis/stages/grid.h"
#include "analysis/stages/occlusion.h"
#include "analysis/audits/ordering.h"
#include "analysis/stages/portals.h"
#include "analysis/audits/pvs_evidence.h"
#include "analysis/effects_plan.h"
#include "analysis/level_map.h"
#include "analysis/load/route.h"
#include "analysis/scene.h"
#include "analysis/audits/zfight.h"
#include "render/clip.h"
#include "render/raster.h"
#include "render/effects.h"
#include "render/raycast.h"

namespace va {

// One row of the stage funnel.
struct StageRecord {
    std::string name;          // cells, grid, frustum, occlusion, backface, clip, zbuffer, raycast
    bool ran = false;
    std::string reason;        // why it did not run (empty when it ran)
    uint64_t trianglesIn = 0;  // triangles entering the stage
    uint64_t trianglesCulled = 0;
    uint64_t trianglesOut = 0; // triangles leaving it (clip: screen triangles after fan triangulation)
    double ms = 0;             // wall time of the stage for this view
};
// A funnel row of a stage that ran, and of one that did not (and why).
inline StageRecord ranStage(const char *name, uint64_t in, uint64_t culled, uint64_t out, double ms) {
    return {name, true, {}, in, culled, out, ms};
}
inline StageRecord skippedStage(const char *name, std::string reason) { return {name, false, std::move(reason), 0, 0, 0, 0}; }

struct FrustumStats {
    uint64_t objectsIn = 0;           // culling objects entering the stage
    uint64_t objectsCulled = 0;       // bounding sphere entirely outside a plane
    uint64_t objectsInside = 0;       // bounding sphere entirely inside all six planes
    uint64_t objectsIntersecting = 0; // kept, touching or crossing a plane
    uint64_t nodesVisited = 0;        // BVH nodes whose bounding sphere was tested
    uint64_t planeTests = 0;          // sphere-plane dot products done (BVH walk)
    uint64_t planeTestsBruteForce = 0;// 6 x objects: what testing every object would cost; best: planeTests << this
};

struct BackfaceStats {
    uint64_t trianglesTested = 0;     // triangles whose plane was evaluated at the eye
    uint64_t trianglesCulled = 0;     // plane <= 0 at the eye: facing away (or edge-on)
    uint64_t doubleSidedExempt = 0;   // triangles of double-sided materials, never culled
    uint64_t edgeOn = 0;              // plane exactly 0 at the eye (counted among culled)
};

// A stage or audit that may not run for a view: its result when it ran, else why it did not
// (docs/architecture.md, "The stage contract"). One value: never a flag and a reason kept apart.
template <class T>
class Ran {
public:
    Ran() = default;
    Ran &operator=(T result) {
        v_ = std::move(result);
        return *this;
    }
    void skip(std::string reason) { v_ = Skipped{std::move(reason)}; }
    bool ran() const { return std::holds_alternative<T>(v_); }
    // Why it did not run ("" when it ran).
    const std::string &reason() const {
        static const std::string none;
        const Skipped *s = std::get_if<Skipped>(&v_);
        return s ? s->reason : none;
    }
    // The result; only when ran().
    T &operator*() { return std::get<T>(v_); }
    const T &operator*() const { return std::get<T>(v_); }
    T *operator->() { return &std::get<T>(v_); }
    const T *operator->() const { return &std::get<T>(v_); }

private:
    struct Skipped {
        std::string reason;
    };
    std::variant<Skipped, T> v_{Skipped{"not run"}};
};

// The raycast stage: Embree primary rays at pixel centers over the whole scene (no culling),
// cross-checked pixel by pixel against the z-buffer (docs/audits.md).
struct RaycastResult {
    RaycastStats stats;
    CrossCheck crossCheck;
    RaycastImage image;               // ids/depths for NAME.raycast.ids.exr (released after writing)
    void releasePixels() {
        recycleRaycastImage(image);  // for a later view's cast
        std::vector<uint8_t>().swap(crossCheck.cls);
    }
};

// The audit against the reference visibility (docs/audits.md).
struct CullingAuditResult {
    ReferenceVisibility reference;
    CullAudit cull;
    PvsEvidence pvsEvidence;          // a map's PVS: the evidence of its false culls (pvs_evidence.h)
    double ms = 0;
    void releasePixels() {
        std::vector<uint32_t>().swap(reference.id);
        std::vector<double>().swap(reference.depth);
        std::vector<uint32_t>().swap(reference.pixelsOf);
        std::vector<uint8_t>().swap(cull.fate);
    }
};

struct ViewResult {
    size_t index = 0;                 // position in the full view list (before --shard selection)
    std::string imageBase;            // file-name base of its images (empty: derived from the name)
    ViewSpec spec;
    Camera camera;
    std::vector<StageRecord> stages;  // in docs/architecture.md's fixed order
    FrustumStats frustum;
    BackfaceStats backface;
    ClipStats clip;
    ZBufferStats zbuffer;
    ZBuffer buffer;                   // per-pixel buffers, for the images (may be released after writing)
    CellsStats cells;                 // the cells stage (PVS), when it ran
    bool cellsArePortals = false;     // the cells stage traversed the scene's portals (not a PVS)
    PortalStats portals;              // the cells stage (portals), when it ran
    std::string cellsNote;            // e.g. the camera is in the void
    GridStats grid;                   // the grid stage, when it ran
    OcclusionStats occlusion;         // the occlusion stage, when it ran
    Ran<RaycastResult> raycast;       // and its secondary rays where the plan says (effects)
    Ran<EffectsResult> effects;
    Ran<CullingAuditResult> audit;
    Ran<OrderingResult> ordering;     // draw orders and exact orders (docs/ordering.md)
    Ran<DetailResult> detail;         // the detail audit (docs/coarse-stages.md)
    Ran<ZFightResult> zfight;         // the per-view z-fighting analysis (docs/zfighting.md)
    // The depth-resolution curves of this view's near and far (AnalysisResult::depthCurves; the
    // page's plot), for the formats of its z-fighting table (the default twelve when it did not run);
    // -1: none (a near/far the depth audit refuses).
    int depthCurve = -1;
    double totalMs = 0;

    // Frees every per-pixel buffer once the images are written; what the report reads (the
    // statistics, hotspot and offender lists) stays. Each result frees its own buffers.
    void releasePixelBuffers() {
        recycleZBuffer(buffer);  // for a later view's z-buffer
        if (raycast.ran()) raycast->releasePixels();
        if (effects.ran()) effects->releasePixels();
        if (audit.ran()) audit->releasePixels();
        if (ordering.ran()) ordering->releasePixels();
        if (zfight.ran()) zfight->releasePixels();
    }
};

struct AnalysisResult {
    std::string scenePath;
    SceneStats sceneStats;
    std::vector<std::string> sceneWarnings;  // the loaders' (dropped faces, ignored features) and
                                             //   "no triangles to analyse"; also printed on stderr
    uint64_t triangles = 0;           // triangles analysed (source triangles minus excluded)
    uint64_t objects = 0;             // culling objects
    uint64_t sourceObjects = 0;
    Aabb bounds;
    double loadMs = 0;
    EffectPlan effects;               // which effects the scene calls for, and why (docs/effects.md)
    std::vector<std::string> lightNames;
    // A Quake 3 map's structure, summarized (scenes loaded from a .bsp; docs/quake3.md).
    struct BspSummary {
        BspFaceCounts faces;
        uint64_t leafs = 0;
        int32_t clusters = 0;
        int patchLevel = 0;
        bool hasPvs = false;
        uint64_t spawnPoints = 0;     // views --views spawns makes (spawn and intermission points)
        // Brush entities the engine never draws (docs/quake3.md, "Brush entities"): every one whose
        // model has faces with geometry, in model order; their faces are not geometry.
        struct NotDrawn {
            uint32_t model = 0;       // K of "*K"
            int32_t entity = -1;      // index in the entity lump; -1: no entity spawns the model
            std::string classname;    // "" when no entity
            std::string reason;       // "trigger" (trigger_* entities) or "no entity"
            uint64_t faces = 0, triangles = 0;
        };
        std::vector<NotDrawn> notDrawn;
        uint64_t drawnBrushEntities = 0;   // brush models 1.. some entity spawns and the engine draws
        uint64_t notDrawnBrushEntities = 0;// brush models 1.. never drawn (with or without faces)
        BspFarPlane farPlane;         // the map's designed far plane (distance 0: none)
        std::string fogShader;        // worldspawn "_fog" / "fog" ("" none)
    };
    std::optional<BspSummary> bsp;
    bool raycast = false;             // whether the raycast stage ran
    double raySceneBuildMs = 0;       // Embree BVH build over the scene (once, for every view)
    bool bspTreeBuilt = false;        // the ordering audit's BSP tree (once, view-independent)
    BspStats bspTree;
    std::string orderingReason;       // why the ordering audit did not run (empty: it ran)
    // --shard K/N: this report holds the views whose index i has i % N == K - 1.
    struct Shard {
        int index = 1, count = 1;     // K and N (1-based K); 1/1 = every view
        size_t viewsTotal = 0;        // views before the selection
    } shard;
    std::vector<ViewResult> views;
    // The routes the views were sampled from (--views route:FILE): their definitions; the frames
    // are views whose spec.route names the route (docs/routes.md).
    std::vector<Route> routes;
    // The level's floor plan when the run draws level maps (--level-maps; docs/level-maps.md): the
    // report's level_maps are the views' positions over it.
    std::optional<FloorPlan> floorPlan;
    // Depth resolution against view depth per format, one set per distinct (near, far, formats), in
    // the order the views first use them (ViewResult::depthCurve); computed once per set.
    std::vector<DepthAuditResult> depthCurves;
};

}  // namespace va
