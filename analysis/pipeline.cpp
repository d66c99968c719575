#include "analysis/pipeline.h"

#include <algorithm>
#include <atomic>
#include <future>
#include <map>
#include <mutex>

#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "analysis/stage.h"
#include "common/fp_env.h"
#include "common/id_runs.h"
#include "analysis/stages/backface.h"
#include "analysis/stages/cells.h"
#include "analysis/load/level_views.h"
#include "render/raster.h"
#include "render/stopwatch.h"

namespace va {

namespace {
uint64_t trianglesOf(const Scene &scene, const std::vector<uint32_t> &objects) {
    uint64_t n = 0;
    for (uint32_t o : objects) n += scene.objects[o].triEnd - scene.objects[o].triBegin;
    return n;
}

// The objects of `before` missing from `after` (both ascending).
std::vector<uint32_t> removed(const std::vector<uint32_t> &before, const std::vector<uint32_t> &after) {
    std::vector<uint32_t> out;
    size_t k = 0;
    for (uint32_t o : before) {
        if (k < after.size() && after[k] == o)
            ++k;
        else
            out.push_back(o);
    }
    return out;
}

}  // namespace

// The object stages in the pipeline's fixed coarse-to-fine order: the rows that
// analysis/stages/object_stages.def lists, each defined in its stage's file (analysis/stage.h).
#define VA_OBJECT_STAGE(row) extern const ObjectStage row;
#include "analysis/stages/object_stages.def"
#undef VA_OBJECT_STAGE
namespace {
constexpr const ObjectStage *kObjectStages[] = {
#define VA_OBJECT_STAGE(row) &row,
#include "analysis/stages/object_stages.def"
#undef VA_OBJECT_STAGE
};

void runObjectStage(ViewContext &c, const ObjectStage &stage, std::vector<uint32_t> &objects) {
    const std::string why = stage.skip(c);
    if (!why.empty()) {
        c.r.stages.push_back(skippedStage(stage.name, why));
        return;
    }
    const uint64_t in = trianglesOf(c.scene, objects);
    const Stopwatch t0;
    ObjectCull out = stage.run(c, objects);
    const double ms = out.ms ? *out.ms : t0.ms();
    if (c.s.audit) {
        StageCulls sc;
        sc.stage = stage.name;
        sc.objects = out.culled ? std::move(*out.culled) : removed(objects, out.kept);
        sc.designFarPlane = out.designFarPlane;
        c.culls.push_back(std::move(sc));
    }
    objects = std::move(out.kept);
    const uint64_t kept = trianglesOf(c.scene, objects);
    c.r.stages.push_back(ranStage(stage.name, in, in - kept, kept, ms));
}

// ---- Triangle stages ----------------------------------------------------------------------------
// Backface: plane at the eye, per triangle. Returns the triangles kept, per object.
TriangleLists runBackface(ViewContext &c, const std::vector<uint32_t> &objects) {
    if (!c.s.backface) {
        c.r.stages.push_back(skippedStage("backface", "turned off by --no-backface"));
        return allTriangles(c.scene, objects);
    }
    const Stopwatch t0;
    BackfaceResult b = cullBackfaces(c.scene, objects, c.cam);
    const double ms = t0.ms();
    c.r.backface = b.stats;
    if (c.s.audit) c.culls.push_back({"backface", {}, std::move(b.culled), true});
    const uint64_t in = trianglesOf(c.scene, objects), out = b.kept.size();
    c.r.stages.push_back(ranStage("backface", in, in - out, out, ms));
    return std::move(b.kept);
}

// Clip: one batch per object (its vertex range is transformed once).
ClipResult runClip(ViewContext &c, const TriangleLists &lists) {
    const Stopwatch t0;
    const std::vector<ClipBatch> batches = clipBatches(c.scene, lists);
    ClipResult clip = clipTriangles(c.cam, MeshView{c.scene.positions.data(), c.scene.indices.data()}, batches, c.s.clip);
    const double ms = t0.ms();
    c.r.clip = clip.stats;
    const ClipStats &cs = clip.stats;
    // Out: screen triangles, after fan triangulation.
    c.r.stages.push_back(ranStage("clip", lists.size(), cs.trivialRejected + cs.clippedAway + cs.edgeOn, cs.trianglesOut, ms));
    return clip;
}

// Z-buffer: rasterize in the view's depth format. Returns the fragments per source triangle when an
// audit needs them (wasted fragments), else empty.
std::vector<uint32_t> runZBuffer(ViewContext &c, const ClipResult &clip) {
    std::vector<uint32_t> fragmentsPerSource;
    ZBufferSettings zs;
    zs.encoder = makeDepthEncoder(c.view.depthFormat, c.cam.nearZ, c.cam.farZ);
    zs.orthographic = c.cam.orthographic;
    if (c.s.audit || c.s.detail) {
        fragmentsPerSource.assign(c.scene.triangleCount(), 0);
        zs.fragmentsPerSource = fragmentsPerSource.data();
    }
    const Stopwatch t0;
    ZBufferResult z = rasterize(clip.out, c.cam.width, c.cam.height, zs);
    const double ms = t0.ms();
    c.r.zbuffer = z.stats;
    c.r.buffer = std::move(z.buffer);
    c.r.stages.push_back(ranStage("zbuffer", z.stats.trianglesIn, z.stats.trianglesEmpty, z.stats.trianglesDrawn, ms));
    return fragmentsPerSource;
}

// Raycast: Embree primary rays over the whole scene with no culling (single-sided triangles seen
// from their front only, as the reference sees them; ties to the lowest id), compared pixel by
// pixel with the z-buffer; then the secondary rays the effects plan calls for.
void runRaycast(ViewContext &c, const TriangleLists &lists) {
    const PreparedScene &ps = c.ps;
    const Scene &scene = c.scene;
    ViewResult &r = c.r;
    if (!ps.rays) {
        r.stages.push_back(skippedStage("raycast", "turned off by --no-raycast"));
        r.raycast.skip("turned off by --no-raycast");
        return;
    }
    const Stopwatch t0;
    PrimaryOptions opt;
    opt.rejectBackFaces = c.s.backface;
    opt.doubleSided = ps.effectsData.doubleSided.data();
    opt.planes = scene.planes.data();
    opt.tiesToLowestId = true;
    opt.keepBarycentrics = ps.effects.tracesRays();
    r.raycast = RaycastResult{};
    RaycastResult &ray = *r.raycast;
    ray.image = ps.rays->castPrimary(c.cam, opt, &ray.stats);
    const uint64_t in = scene.objectTriangles.size();
    // Like with like: the z-buffer drew only what the culling stages kept (lists.triangles). Where
    // the whole-scene rays hit a triangle outside that set, cast again over the set itself, so
    // that a cull (judged by the culling audit) is never also counted as a disagreement.
    std::vector<uint8_t> outOfSet(scene.triangleCount(), 1);
    for (uint32_t t : lists.triangles) outOfSet[t] = 0;
    // The triangles the rays hit, and the pixels whose triangle is out of the set, in one pass over
    // the ids, a run of equal ids at a time (common/id_runs.h).
    uint64_t hit = 0, culledPixels = 0;
    std::vector<uint8_t> seen(scene.triangleCount(), 0);
    forEachIdRun(ray.image.id, [&](uint32_t id, uint64_t count) {
        if (!id) return;
        hit += seen[id - 1] ^ 1;
        seen[id - 1] = 1;
        culledPixels += outOfSet[id - 1] * count;
    });
    RaycastImage sameSet;
    if (culledPixels > 0) {
        PrimaryOptions same = opt;
        same.keepBarycentrics = false;
        same.rejectSource = outOfSet.data();
        sameSet = ps.rays->castPrimary(c.cam, same, nullptr);
    }
    // Triangles no ray hit: "culled" in the sense of this stage's funnel (not visible).
    r.stages.push_back(ranStage("raycast", in, in - hit, hit, t0.ms()));
    const RaycastImage &compared = culledPixels > 0 ? sameSet : ray.image;
    ray.crossCheck = crossCheck(r.buffer.id, r.buffer.depth, compared.id, compared.depth, scene, c.cam,
                              makeDepthEncoder(c.view.depthFormat, c.cam.nearZ, c.cam.farZ), ps.rays->origin());
    ray.crossCheck.culled = culledPixels;
    ray.crossCheck.recast = culledPixels > 0;
    recycleRaycastImage(sameSet);
    if (!ps.effects.tracesRays()) r.effects.skip("the scene calls for no secondary rays");
    else if (!c.stopped()) r.effects = traceEffects(*ps.rays, c.cam, ray.image, effectsInputFor(ps.effectsData, ps.effects));
}

// ---- Audits -------------------------------------------------------------------------------------
// The reference visibility (no culling at all), and what each culling stage removed that is in fact
// visible (false culls) or kept that is visible nowhere (wasted draws).
void runCullingAudit(ViewContext &c, const TriangleLists &lists, std::vector<uint32_t> &fragmentsPerSource) {
    ViewResult &r = c.r;
    if (!c.s.audit) {
        r.audit.skip("turned off by --no-audit");
        return;
    }
    const Stopwatch t0;
    // The ordering audit walks the reference's fragments again in other orders, and the z-fighting
    // pass reads those of the triangles the z-buffer drew: kept for them, up to 4 per pixel (48
    // bytes a pixel; estimateMemory), above which they rasterize again. Without the ordering audit
    // (a scene over --ordering-max-triangles) the z-fighting pass alone is worth it: on the
    // benchmark scene's orbit views (1M triangles, 1080p) its time fell from 196-208 to 93 ms for
    // eight views, the reference's from 421-581 to 374-377, and the peak memory by 24 MB (a
    // band of the two nearest surfaces instead of a whole view's).
    const uint64_t pixels = uint64_t(std::max(c.cam.width, 0)) * uint64_t(std::max(c.cam.height, 0));
    const uint64_t cache =
        c.ps.hasBspTree() || c.s.zfight ? std::min<uint64_t>(kOrderingCachedFragmentsPerPixel * pixels, 1ull << 31) : 0;
    r.audit = CullingAuditResult{};
    CullingAuditResult &a = *r.audit;
    a.reference = referenceVisibility(c.scene, c.cam, cache);
    a.cull = auditCulling(c.scene, a.reference, c.culls, lists.triangles, &fragmentsPerSource, &c.cam);
    // A map's PVS: the evidence of each false cull it made (camera leaf and cluster, faces, leafs,
    // clusters, PVS bits, distances), for a reader to check against the map's bytes.
    if (hasPvs(c.scene) && !hasPortals(c.scene) && c.s.cells)
        for (size_t k = 0; k < c.culls.size(); ++k)
            if (c.culls[k].stage == "cells") a.pvsEvidence = pvsEvidence(c.scene, c.cam, r.cells, a.reference, a.cull, k);
    a.ms = t0.ms();
}

// Draw orders against the reference -- painter's, BSP, scanline, overdraw by order, and the
// A-buffer where the scene has transparency.
void runOrderingAudit(ViewContext &c) {
    ViewResult &r = c.r;
    const BspTree *tree = c.ps.hasBspTree() && r.audit.ran() ? c.ps.bsp() : nullptr;
    if (tree) {
        OrderingSettings os = c.s.orderingSettings;
        os.abufferMaxList = c.s.limits.maxABufferList;
        r.ordering = analyzeOrdering(c.scene, c.cam, r.audit->reference, *tree, c.ps.effects.abuffer, os);
    } else {
        r.ordering.skip(c.ps.orderingReason.empty() ? "needs the reference visibility" : c.ps.orderingReason);
    }
}

// Z-fighting of the two nearest surfaces per pixel, in every depth format, over exactly the
// triangles the z-buffer drew.
void runZFightAudit(ViewContext &c, const ClipResult &clip) {
    ViewResult &r = c.r;
    if (!c.s.zfight) {
        r.zfight.skip("turned off by --no-zfight");
        return;
    }
    const Stopwatch t0;
    // The view's own format is always evaluated (budgets read its row) and explains hotspots.
    ZFightSettings zs = c.s.zfightSettings;
    zs.viewFormat = c.view.depthFormat;
    if (std::find(zs.formats.begin(), zs.formats.end(), c.view.depthFormat) == zs.formats.end() &&
        zs.formats.size() < 32)
        zs.formats.push_back(c.view.depthFormat);
    // The fragments the reference recorded, when it did (the same fragments as a walk of clip.out).
    if (r.audit.ran()) zs.reference = &r.audit->reference;
    r.zfight = analyzeZFighting(c.scene, c.cam, clip.out, zs);
    r.zfight->ms = t0.ms();
}
}  // namespace

// The depth-resolution curves the report plots for each view's near and far (docs/depth-formats.md):
// one audit per distinct (near, far, formats), in the order the views first use them.
static void addDepthCurves(AnalysisResult *out) {
    std::map<std::pair<std::pair<double, double>, std::string>, int> seen;
    for (ViewResult &v : out->views) {
        const double nearZ = v.spec.camera.nearZ, farZ = v.spec.camera.farZ;
        std::string err;
        if (!validateDepthAuditRange(nearZ, farZ, &err)) continue;
        // The formats of the view's z-fighting table, in its order (the default twelve without one).
        std::vector<DepthFormatSpec> specs;
        if (v.zfight.ran())
            for (const ZFightFormatStats &f : v.zfight->perFormat) specs.push_back(f.format);
        if (specs.empty()) specs.assign(defaultZFightFormats().begin(), defaultZFightFormats().end());
        std::string names;
        for (const DepthFormatSpec &f : specs) names += depthFormatName(f) + ",";
        const auto key = std::make_pair(std::make_pair(nearZ, farZ), names);
        auto it = seen.find(key);
        if (it == seen.end()) {
            DepthAuditResult curves = auditDepthFormats(nearZ, farZ, specs);
            if (!curves.error.empty()) continue;
            it = seen.emplace(key, int(out->depthCurves.size())).first;
            out->depthCurves.push_back(std::move(curves));
        }
        v.depthCurve = it->second;
    }
}

PreparedScene prepareScene(const Scene &scene) {
    PreparedScene ps;
    ps.scene = &scene;
    ps.bvh = buildObjectBvh(scene);
    return ps;
}

bool prepareScene(const Scene &scene, const PipelineSettings &s, PreparedScene *out, std::string *err,
                  bool *bspWanted) {
    PreparedScene ps = prepareScene(scene);
    if (bspWanted) *bspWanted = false;
    ps.effects = planEffects(scene, s.effects);
    if (s.grid && !gridSkipReason(scene)) ps.grid = buildGrid(scene, s.gridSettings);
    const uint64_t tris = scene.objectTriangles.size();
    if (!s.ordering || !s.audit) {
        ps.orderingReason = !s.ordering ? "turned off by --no-ordering" : "needs the reference visibility (--no-audit)";
    } else if (tris > s.orderingMaxTriangles) {
        ps.orderingReason = "scene has " + std::to_string(tris) + " triangles, more than --ordering-max-triangles " +
                            std::to_string(s.orderingMaxTriangles) + " (the BSP tree can grow quadratically)";
    } else if (bspWanted) {
        *bspWanted = true;
    } else {
        ps.bspTree = std::make_unique<BspTree>(buildBspTree(scene));
    }
    if (s.raycast) {
        const Stopwatch t0;
        ps.rays = std::make_unique<RayScene>();
        // The float frame's origin at the scene's center keeps float precision where the geometry is.
        const Vec3 origin = scene.bounds.empty() ? Vec3{} : scene.bounds.center();
        if (!ps.rays->build(MeshView{scene.positions.data(), scene.indices.data()}, scene.positions.size(),
                            scene.objectTriangles, origin, err))
            return false;
        ps.raySceneBuildMs = t0.ms();
        ps.effectsData = effectsDataFor(scene);
    }
    *out = std::move(ps);
    return true;
}

bool resolveView(const ViewSpec &in, const PipelineSettings &s, ViewSpec *out, Camera *cam, std::string *err) {
    ViewSpec v = in;
    if (s.width > 0) v.camera.width = s.width;
    if (s.height > 0) v.camera.height = s.height;
    if (s.depthFormat) v.depthFormat = *s.depthFormat;
    const int lim = s.limits.maxResolution;
    if (v.camera.width > lim || v.camera.height > lim) {
        *err = "view '" + v.name + "': resolution " + std::to_string(v.camera.width) + "x" +
               std::to_string(v.camera.height) + " exceeds the limit of " + std::to_string(lim) +
               " pixels per side; lower it (--width/--height) or raise the limit with --max-resolution";
        return false;
    }
    std::string m;
    if (!makeCamera(v.camera, cam, &m)) {
        *err = "view '" + v.name + "': " + m;
        return false;
    }
    if (!validateDepthFormatRange(v.depthFormat, cam->nearZ, cam->farZ, &m)) {
        *err = "view '" + v.name + "': " + m;
        return false;
    }
    *out = v;
    return true;
}

std::vector<uint32_t> objectStagesKept(const PreparedScene &ps, const ViewSpec &view, const Camera &cam,
                                       const PipelineSettings &s) {
    ViewResult r;
    r.spec = view;
    r.camera = cam;
    ViewContext c{ps, *ps.scene, view, cam, s, r, {}};
    std::vector<uint32_t> objects(c.scene.objects.size());
    for (uint32_t i = 0; i < objects.size(); ++i) objects[i] = i;
    for (const ObjectStage *stage : kObjectStages) runObjectStage(c, *stage, objects);
    return objects;
}

ViewResult analyzeView(const PreparedScene &ps, const ViewSpec &view, const Camera &cam, const PipelineSettings &s) {
    const Stopwatch tView;
    ViewResult r;
    r.spec = view;
    r.camera = cam;
    ViewContext c{ps, *ps.scene, view, cam, s, r, {}};
    // Checked between stages: an interrupted view returns what it has, and analyzeScene discards it.
    std::vector<uint32_t> objects(c.scene.objects.size());  // the objects still in, ascending
    for (uint32_t i = 0; i < objects.size(); ++i) objects[i] = i;
    for (const ObjectStage *stage : kObjectStages) runObjectStage(c, *stage, objects);
    if (c.stopped()) return r;
    const TriangleLists lists = runBackface(c, objects);
    ClipResult clip = runClip(c, lists);
    if (c.stopped()) return r;
    std::vector<uint32_t> fragmentsPerSource = runZBuffer(c, clip);
    if (c.stopped()) return r;
    runRaycast(c, lists);
    if (c.stopped()) return r;
    runCullingAudit(c, lists, fragmentsPerSource);
    if (c.stopped()) return r;
    runOrderingAudit(c);
    // Detail: triangles drawn against the pixels they show, too small, over-detailed.
    if (!c.stopped()) {
        if (s.detail) r.detail = auditDetail(c.scene, cam, lists.triangles, fragmentsPerSource, r.buffer.id, s.detailSettings);
        else r.detail.skip("turned off by --no-detail");
    }
    if (!c.stopped()) runZFightAudit(c, clip);
    // The reference's screen triangles and fragments served the ordering and z-fighting audits
    // only: a finished view keeps neither (estimateMemory's finishedViews).
    if (r.audit.ran()) {
        recycleFragmentCache(r.audit->reference.fragmentCache);  // their storage, for the next view
        recycleScreenTriangles(r.audit->reference.screen);
    }
    if (c.stopped()) return r;
    recycleScreenTriangles(clip.out);  // for the next view's clip
    r.totalMs = tView.ms();
    return r;
}

MemoryEstimate estimateMemory(const Scene &scene, const std::vector<Camera> &cams, const PipelineSettings &s) {
    // Terms of the form "bytes per pixel" and "bytes per triangle" add up the buffers a stage keeps
    // (their element sizes), plus the temporaries alive next to them at the stage's peak. The
    // constants were checked against peak RSS (docs/limits.md, "Memory"); the estimate is meant to
    // err high, since an estimate that errs low lets the kernel's OOM killer end the run unreported.
    MemoryEstimate m;
    auto bytesOf = [](const auto &v) { return uint64_t(v.capacity()) * sizeof(v[0]); };
    const uint64_t tris = scene.triangleCount();
    m.scene = bytesOf(scene.positions) + bytesOf(scene.indices) + bytesOf(scene.triangleObject) +
              bytesOf(scene.objectTriangles) + bytesOf(scene.planes) + bytesOf(scene.planeBounds) + scene.backfacePlanes.bytes() +
              uint64_t(scene.objects.size()) * (sizeof(SceneObject) + 32) +
              uint64_t(scene.sources.size()) * (sizeof(SourceObject) + 64);
    if (scene.bsp) m.scene += bytesOf(scene.bsp->pvs) + bytesOf(scene.bsp->leafFaces) + bytesOf(scene.bsp->nodes) +
                              bytesOf(scene.bsp->leafs) + bytesOf(scene.bsp->planes) +
                              bytesOf(scene.bsp->triangleFace) + bytesOf(scene.bsp->faceLeafs) +
                              bytesOf(scene.bsp->faceLeafsBegin);

    // Built once: the object BVH and grid (per object), Embree's float copy and BVH (about 100
    // bytes per triangle with the build's temporaries), per-triangle effect data, the ordering
    // audit's BSP tree (its splits are bounded by orderingMaxTriangles; a few pieces per triangle).
    const uint64_t objects = scene.objects.size();
    m.prepared = objects * 256;
    if (s.raycast) m.prepared += tris * 112 + uint64_t(scene.positions.size()) * 12;
    if (s.ordering && s.audit && tris <= s.orderingMaxTriangles) m.prepared += tris * 400;

    // Per view, per pixel. Kept in ViewResult until onView has written the images:
    //   z-buffer key, id, depth, fragments, passes        4 + 4 + 8 + 2 + 2 = 20
    //   reference id, depth; culling fate                  4 + 8 + 1 = 13
    //   raycast id, depth (+ u, v with effects); disagreements   8 (+ 8) + 1
    //   z-fighting: class, fight mask, hotspot ids (+ 2 nearest depths and triangles while it runs:
    //     a band of them from the reference's fragments, the whole view without the audit)
    //     + the two-surface pixels' lists its thread keeps (pixel, two depths, two triangles, fight
    //     mask, two depth cells, an index: at most one entry per pixel)   9 (+ 24) + 44
    //   the reference's fragment cache, for the z-fighting pass and the ordering audit
    //     (12 bytes a fragment)                            12 * kOrderingCachedFragmentsPerPixel
    //   ordering: painter and BSP id + class, scanline id, per-order overdraw, A-buffer composite,
    //     edges, heads, lengths and center depth          5 + 5 + 4 + 8 + 4 + 24
    //   occlusion's pre-pass depth and Hi-Z pyramid (freed before the z-buffer)   not added
    //   writing images (one 8-bit RGBA or float image at a time, and the PNG encoder)   16
    uint64_t perPixel = 20 + 16;
    if (s.audit) perPixel += 13;
    if (s.raycast) perPixel += 17;  // + the cross-check's recast over the z-buffer's set (id, depth)
    const bool ordering = s.ordering && s.audit && tris <= s.orderingMaxTriangles;
    const bool cached = s.audit && (s.zfight || ordering);  // runCullingAudit
    if (cached) perPixel += 12 * kOrderingCachedFragmentsPerPixel;
    if (s.zfight) perPixel += 9 + (s.audit ? 0 : 24) + 44;
    const EffectPlan plan = planEffects(scene, s.effects);
    if (s.raycast && plan.tracesRays()) perPixel += 8 + 3 + (scene.lights.size() + 7) / 8;
    if (ordering) {
        // + the ordering's per-thread scratch: a depth buffer (8) and the BSP's piece lists and
        // owners (4 bytes a fragment, 3x).
        perPixel += 22 + 8 + 12 * kOrderingCachedFragmentsPerPixel;
        // The A-buffer's fragments: a level's depth complexity is a few layers; the pool itself is
        // counted before it is allocated (--max-abuffer-list), 20 bytes a fragment.
        if (plan.abuffer.run) perPixel += 36 + 4 * sizeof(ABufferFragment);
    }
    // Per view, per triangle (any triangle may be in view): fragments per source, the raycast's
    // seen flags, the audit's pixels per source, the backface lists, the clipped screen triangles
    // (fixed-point corners, source, plane) and depth planes, the ordering's screen ranges.
    uint64_t perTriangle = 4 + 8 + 6 * 4 + 4 + 4 + sizeof(DepthPlane);
    if (s.audit) perTriangle += 4 + 8;
    if (s.raycast) perTriangle += 1;
    if (s.ordering && s.audit && tris <= s.orderingMaxTriangles) perTriangle += 8 + 1 + 12;
    uint64_t pixels = 0;
    for (const Camera &c : cams) pixels = std::max(pixels, uint64_t(c.width) * uint64_t(c.height));
    m.perView = pixels * perPixel + tris * perTriangle;

    const uint64_t threads = s.threads > 0 ? uint64_t(s.threads) : uint64_t(tbb::info::default_concurrency());
    m.viewsInFlight = std::min<uint64_t>(threads, cams.size());
    constexpr uint64_t kBaseline = 128ull << 20;  // the program, its libraries, TBB's and Embree's pools
    // What a finished view still holds once its images are written (releasePixelBuffers): its
    // result -- statistics, hotspot and offender lists -- about 64 KiB whatever its resolution.
    m.finishedViews = uint64_t(cams.size()) * (64ull << 10);
    m.total = kBaseline + m.scene + m.prepared + m.perView * m.viewsInFlight + m.finishedViews;
    return m;
}

namespace {
// Every limit of docs/limits.md that can be checked before work starts (resolution is checked per
// view by resolveView; triangles by the loaders; the A-buffer's lists by the A-buffer itself).
bool checkLimits(const Scene &scene, const std::vector<Camera> &cams, const PipelineSettings &s, std::string *err) {
    const EffectPlan plan = planEffects(scene, s.effects);
    if (s.raycast && (plan.reflections.run || plan.refractions.run) && s.effects.maxDepth > s.limits.maxRecursion) {
        // With a refractive surface every hit spawns a reflection and a refraction: 2^(d+1) - 2
        // secondary rays per pixel at depth d.
        *err = "--max-depth " + std::to_string(s.effects.maxDepth) + " needs a recursion depth of " +
               std::to_string(s.effects.maxDepth) + ", more than the limit of " + std::to_string(s.limits.maxRecursion) +
               (plan.refractions.run ? " (with refraction a pixel may trace 2^" + std::to_string(s.effects.maxDepth + 1) +
                                           " - 2 secondary rays)"
                                     : std::string()) +
               "; lower --max-depth or raise the limit with --max-recursion " + std::to_string(s.effects.maxDepth);
        return false;
    }
    if (s.limits.maxMemory > 0) {
        const MemoryEstimate m = estimateMemory(scene, cams, s);
        if (m.total > s.limits.maxMemory) {
            *err = "the analysis needs about " + formatBytes(m.total) + " of memory (scene " + formatBytes(m.scene) +
                   ", acceleration structures " + formatBytes(m.prepared) + ", " + std::to_string(m.viewsInFlight) +
                   " view(s) at once of " + formatBytes(m.perView) + " each, finished views " +
                   formatBytes(m.finishedViews) + "), more than the limit of " +
                   formatBytes(s.limits.maxMemory) + "; lower the resolution (--width/--height) or --threads, or "
                   "raise the limit with --max-memory " + std::to_string((m.total + (1 << 20) - 1) >> 20) + "M";
            return false;
        }
    }
    return true;
}
}  // namespace

bool analyzeScene(const Scene &scene, const std::vector<ViewSpec> &views, const PipelineSettings &s,
                  const std::function<bool(size_t index, ViewResult &, std::string *)> &onView, AnalysisResult *out,
                  std::string *err) {
    auto stopped = [&] { return s.cancel && s.cancel->load(std::memory_order_relaxed) != 0; };
    // Validate every view and the limits before any work, so bad input never leaves a partial
    // report and a run the machine cannot hold is refused before it allocates.
    std::vector<ViewSpec> resolved(views.size());
    std::vector<Camera> cams(views.size());
    for (size_t i = 0; i < views.size(); ++i)
        if (!resolveView(views[i], s, &resolved[i], &cams[i], err)) return false;
    if (!checkLimits(scene, cams, s, err)) return false;
    if (stopped()) {
        *err = kInterrupted;
        return false;
    }

    out->scenePath = scene.path;
    out->sceneStats = scene.stats;
    out->sceneWarnings = scene.warnings;
    out->triangles = scene.objectTriangles.size();
    out->objects = scene.objects.size();
    out->sourceObjects = scene.sources.size();
    out->bounds = scene.bounds;
    out->views.assign(views.size(), ViewResult{});

    std::optional<tbb::global_control> threads;
    if (s.threads > 0) threads.emplace(tbb::global_control::max_allowed_parallelism, size_t(s.threads));
    PreparedScene ps;
    bool bspWanted = false;
    if (!prepareScene(scene, s, &ps, err, &bspWanted)) return false;
    if (stopped()) {
        *err = kInterrupted;
        return false;
    }
    // The ordering audit's BSP tree is built on a thread of its own while the views start: a view
    // needs it only at its ordering audit, most of the way through, and the build is mostly serial
    // (one core idle for its ~0.4 s on oa_thor otherwise). The tree does not depend on the timing,
    // so neither do the results. Isolated: while its loops wait, the building thread takes only
    // their tasks, never a view's (a view waiting for the tree on the thread that builds it would
    // never return). The future's last copy waits for the build when it goes, so ps and the scene
    // outlive it on every return path.
    if (bspWanted)
        ps.bspBuilding = std::async(std::launch::async, [&ps, &scene] {
                             tbb::this_task_arena::isolate([&] {
                                 runWithIeeeFp([&] { ps.bspTree = std::make_unique<BspTree>(buildBspTree(scene)); });
                             });
                         }).share();
    out->effects = ps.effects;
    out->raycast = ps.rays != nullptr;
    out->raySceneBuildMs = ps.raySceneBuildMs;
    out->orderingReason = ps.orderingReason;
    for (const Light &l : scene.lights) out->lightNames.push_back(l.name);
    if (scene.bsp) {
        AnalysisResult::BspSummary b;
        b.faces = scene.bsp->faceCounts;
        b.leafs = scene.bsp->leafs.size();
        b.clusters = scene.bsp->clusterCount;
        b.patchLevel = scene.bsp->patchLevel;
        b.hasPvs = scene.bsp->hasPvs();
        b.spawnPoints = spawnViews(scene).size();
        for (size_t k = 1; k < scene.bsp->models.size(); ++k) {
            const BspModel &m = scene.bsp->models[k];
            if (m.drawn) {
                b.drawnBrushEntities += m.entity >= 0;
                continue;
            }
            ++b.notDrawnBrushEntities;
            if (m.notDrawnFaces > 0)
                b.notDrawn.push_back({uint32_t(k), m.entity, m.classname, m.entity >= 0 ? "trigger" : "no entity",
                                      m.notDrawnFaces, m.notDrawnTriangles});
        }
        b.farPlane = scene.bsp->farPlane;
        b.fogShader = scene.bsp->fogShader;
        out->bsp = b;
    }
    std::mutex errMutex;
    std::string firstErr;
    std::atomic<bool> failed{false};
    auto failWith = [&](const std::string &e) {
        std::lock_guard<std::mutex> lock(errMutex);
        if (!failed.exchange(true)) firstErr = e;
    };
    auto runView = [&](size_t i) {
        if (failed) return;
        if (stopped()) return failWith(kInterrupted);
        ViewResult v = analyzeView(ps, resolved[i], cams[i], s);
        if (stopped()) return failWith(kInterrupted);
        std::string e;
        if (v.effects.ran() && !v.effects->ok) return failWith("view '" + v.spec.name + "': effects: " + v.effects->error);
        if (v.ordering.ran() && !v.ordering->abuffer.error.empty())
            return failWith("view '" + v.spec.name + "': " + v.ordering->abuffer.error);
        if (onView && !onView(i, v, &e)) return failWith(e);
        out->views[i] = std::move(v);
    };
    // Under IEEE defaults on every thread, whatever used TBB first (common/fp_env.h).
    runWithIeeeFp([&] { tbb::parallel_for(size_t(0), views.size(), runView); });
    if (failed) {
        *err = firstErr;
        return false;
    }
    if (ps.bspBuilding.valid()) ps.bspBuilding.get();  // done; a failed build's exception surfaces here
    if (ps.bspTree) {
        out->bspTreeBuilt = true;
        out->bspTree = ps.bspTree->stats;
    }
    addDepthCurves(out);
    return true;
}

}  // namespace va
