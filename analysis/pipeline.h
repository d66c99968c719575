// The pipeline: which stages a view runs, in docs/architecture.md's fixed coarse-to-fine order, and the
// glue that turns the scene model into the plain data render/ works on.
#pragma once

#include <atomic>
#include <functional>
#include <future>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "analysis/stages/frustum.h"
#include "analysis/results.h"
#include "analysis/scene.h"
#include "analysis/audits/zfight.h"
#include "analysis/audits/detail.h"
#include "analysis/stages/grid.h"
#include "common/limits.h"
#include "analysis/stages/occlusion.h"
#include "analysis/audits/bsp_tree.h"
#include "analysis/audits/ordering.h"
#include "analysis/stages/portals.h"
#include "analysis/effects_plan.h"
#include "render/raycast.h"
#include "render/clip.h"

namespace va {

struct PipelineSettings {
    bool cells = true;     // --no-cells turns the stage off (where the scene has cells or a PVS)
    bool grid = true;      // --no-grid turns the stage off (scenes without cells)
    GridSettings gridSettings;          // --grid-cell
    PortalSettings portals;             // --portal-depth
    bool frustum = true;   // --no-frustum turns the stage off
    bool occlusion = true; // --no-occlusion turns the stage off
    OcclusionSettings occlusionSettings; // --occluders
    bool ordering = true;  // --no-ordering turns the draw-order audit (painter's, BSP, scanline, A-buffer) off
    OrderingSettings orderingSettings;  // --painter-key
    uint64_t orderingMaxTriangles = 200000;  // above it the ordering audit is skipped (the BSP tree can
                                             // grow quadratically): --ordering-max-triangles
    bool detail = true;    // --no-detail turns the detail audit off
    DetailSettings detailSettings;      // --detail-min-pixels, --detail-triangles-per-pixel
    bool backface = true;  // --no-backface turns the stage off
    int width = 0, height = 0;                 // > 0: override every view's resolution
    std::optional<DepthFormatSpec> depthFormat;  // override every view's depth format
    ClipSettings clip;
    bool zfight = true;    // --no-zfight turns the z-fighting analysis off
    bool audit = true;     // --no-audit turns the reference-visibility audit off
    bool raycast = true;   // --no-raycast turns the raycast stage (and the effects) off
    EffectFlags effects;   // --shadows/--no-shadows, ..., --max-depth
    ZFightSettings zfightSettings;  // its formats: --zfight-formats (each view's own is added)
    Limits limits;                             // refused before allocating (docs/limits.md)
    int threads = 0;                           // 0: all cores
    // Not null: analyzeScene stops between views and stages once it holds a nonzero value (the CLI's
    // SIGINT/SIGTERM handler stores the signal number) and returns false with kInterrupted.
    const std::atomic<int> *cancel = nullptr;
};

// analyzeScene's *err when settings.cancel stopped it.
inline constexpr const char *kInterrupted = "interrupted";

// What a run needs at its peak, estimated from the scene and the resolved views before anything
// is built (docs/limits.md has the terms and their measured error).
struct MemoryEstimate {
    uint64_t scene = 0;     // the loaded scene model (its arrays, as allocated)
    uint64_t prepared = 0;  // built once per scene: Embree's BVH, the object BVH and grid, the BSP tree
    uint64_t perView = 0;   // the largest view's buffers (per pixel and per triangle)
    uint64_t viewsInFlight = 0;  // views analysed at once (threads, at most the number of views)
    uint64_t finishedViews = 0;  // what the finished views still hold (their results), all views
    uint64_t total = 0;     // baseline + scene + prepared + perView * viewsInFlight + finishedViews
};
MemoryEstimate estimateMemory(const Scene &scene, const std::vector<Camera> &cams, const PipelineSettings &s);

// View-independent acceleration data, built once per scene.
struct PreparedScene {
    const Scene *scene = nullptr;
    ObjectBvh bvh;
    Grid grid;                       // when the grid stage can run (gridSkipReason is null)
    std::unique_ptr<BspTree> bspTree; // the ordering audit's BSP tree (view-independent)
    // While valid, bspTree is being built on another thread (analyzeScene starts the views
    // alongside it): read the tree through bsp(), which waits for it.
    std::shared_future<void> bspBuilding;
    std::string orderingReason;      // why the ordering audit does not run (empty: it does)
    std::unique_ptr<RayScene> rays;  // Embree scene over every analysed triangle (raycast on)
    double raySceneBuildMs = 0;
    SceneEffectsData effectsData;
    EffectPlan effects;

    // Whether the ordering audit has a tree (built or being built).
    bool hasBspTree() const { return bspTree || bspBuilding.valid(); }
    // The tree once built (null: none, or its build failed: analyzeScene reports why).
    const BspTree *bsp() const {
        if (bspBuilding.valid()) bspBuilding.wait();
        return bspTree.get();
    }
};
// Without ray casting (tests of the rasterizing stages).
PreparedScene prepareScene(const Scene &scene);
// As the settings say: the Embree scene and the effects plan when raycast is on. False + message
// when Embree fails.
// With bspWanted, the BSP tree is not built: *bspWanted says whether it is wanted (the caller builds
// it, as analyzeScene does alongside the first views).
bool prepareScene(const Scene &scene, const PipelineSettings &s, PreparedScene *out, std::string *err,
                  bool *bspWanted = nullptr);

// The view after settings' overrides, validated; false with a message naming the view and a fix.
bool resolveView(const ViewSpec &in, const PipelineSettings &s, ViewSpec *out, Camera *cam, std::string *err);

// The culling objects the object stages (cells or grid, frustum, occlusion) keep for one (resolved)
// view, ascending: the backface stage's input, as analyzeView runs it (assignment kits).
std::vector<uint32_t> objectStagesKept(const PreparedScene &ps, const ViewSpec &view, const Camera &cam,
                                       const PipelineSettings &s);

// Runs every stage for one (resolved) view.
ViewResult analyzeView(const PreparedScene &ps, const ViewSpec &view, const Camera &cam, const PipelineSettings &s);

// Runs every view (in parallel); `onView` is called once per finished view (with its index in
// `views`), from worker threads,
// and may write images and release the view's buffers. Results keep the views' order.
// Returns false (with *err) when a view is invalid or onView fails; nothing is half-reported.
bool analyzeScene(const Scene &scene, const std::vector<ViewSpec> &views, const PipelineSettings &s,
                  const std::function<bool(size_t index, ViewResult &, std::string *)> &onView, AnalysisResult *out,
                  std::string *err);

}  // namespace va
