#include "analysis/pipeline.h"

#include <atomic>
#include <chrono>
#include <mutex>

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include "analysis/backface.h"
#include "analysis/cells.h"
#include "analysis/level_views.h"
#include "render/raster.h"

namespace va {

namespace {
using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

uint64_t trianglesOf(const Scene &scene, const std::vector<uint32_t> &objects) {
    uint64_t n = 0;
    for (uint32_t o : objects) n += scene.objects[o].triEnd - scene.objects[o].triBegin;
    return n;
}

StageRecord skipped(const char *name, const std::string &reason) {
    StageRecord r;
    r.name = name;
    r.ran = false;
    r.reason = reason;
    return r;
}
}  // namespace

PreparedScene prepareScene(const Scene &scene) {
    PreparedScene ps;
    ps.scene = &scene;
    ps.bvh = buildObjectBvh(scene);
    return ps;
}

bool prepareScene(const Scene &scene, const PipelineSettings &s, PreparedScene *out, std::string *err) {
    PreparedScene ps = prepareScene(scene);
    ps.effects = planEffects(scene, s.effects);
    if (s.grid && !gridSkipReason(scene)) ps.grid = buildGrid(scene, s.gridSettings);
    const uint64_t tris = scene.objectTriangles.size();
    if (!s.ordering || !s.audit) {
        ps.orderingReason = !s.ordering ? "turned off by --no-ordering" : "needs the reference visibility (--no-audit)";
    } else if (tris > s.orderingMaxTriangles) {
        ps.orderingReason = "scene has " + std::to_string(tris) + " triangles, more than --ordering-max-triangles " +
                            std::to_string(s.orderingMaxTriangles) + " (the BSP tree can grow quadratically)";
    } else {
        ps.bspTree = std::make_unique<BspTree>(buildBspTree(scene));
    }
    if (s.raycast) {
        const auto t0 = Clock::now();
        ps.rays = std::make_unique<RayScene>();
        // The float frame's origin at the scene's center keeps float precision where the geometry is.
        const Vec3 origin = scene.bounds.empty() ? Vec3{} : scene.bounds.center();
        if (!ps.rays->build(MeshView{scene.positions.data(), scene.indices.data()}, scene.positions.size(),
                            scene.objectTriangles, origin, err))
            return false;
        ps.raySceneBuildMs = msSince(t0);
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
    *out = v;
    return true;
}

ViewResult analyzeView(const PreparedScene &ps, const ViewSpec &view, const Camera &cam, const PipelineSettings &s) {
    const Scene &scene = *ps.scene;
    const auto tView = Clock::now();
    ViewResult r;
    r.spec = view;
    r.camera = cam;

    std::vector<uint32_t> objects(scene.objects.size());  // the objects still in, ascending
    for (uint32_t i = 0; i < objects.size(); ++i) objects[i] = i;
    std::vector<StageCulls> culls;  // what each culling stage removed, for the audit
    // The objects of `before` missing from `after` (both ascending).
    auto removed = [](const std::vector<uint32_t> &before, const std::vector<uint32_t> &after) {
        std::vector<uint32_t> out;
        size_t k = 0;
        for (uint32_t o : before) {
            if (k < after.size() && after[k] == o)
                ++k;
            else
                out.push_back(o);
        }
        return out;
    };

    // Coarse stage: cells where the scene has them (portals from the scene file, or a map's PVS),
    // the grid otherwise.
    const bool hasPortals = !portalsSkipReason(scene), hasPvs = !cellsSkipReason(scene);
    {
        StageRecord st;
        st.name = "cells";
        if (!hasPortals && !hasPvs) {
            r.stages.push_back(skipped("cells", "scene has no cells, portals or PVS"));
        } else if (!s.cells) {
            r.stages.push_back(skipped("cells", "turned off by --no-cells"));
        } else {
            const auto t0 = Clock::now();
            st.trianglesIn = trianglesOf(scene, objects);
            std::vector<uint32_t> visible;
            if (hasPortals) {
                PortalResult p = cullPortals(scene, cam, s.portals);
                r.cellsArePortals = true;
                r.portals = p.stats;
                r.cellsNote = p.note;
                visible = std::move(p.visible);
            } else {
                CellsResult c = cullCells(scene, cam);
                r.cells = c.stats;
                r.cellsNote = c.note;
                visible = std::move(c.visible);
            }
            st.ms = msSince(t0);
            st.ran = true;
            if (s.audit) culls.push_back({"cells", removed(objects, visible), {}});
            objects = std::move(visible);
            st.trianglesOut = trianglesOf(scene, objects);
            st.trianglesCulled = st.trianglesIn - st.trianglesOut;
            r.stages.push_back(st);
        }
    }
    {
        StageRecord st;
        st.name = "grid";
        if (const char *why = gridSkipReason(scene)) {
            r.stages.push_back(skipped("grid", why));
        } else if (!s.grid) {
            r.stages.push_back(skipped("grid", "turned off by --no-grid"));
        } else {
            const auto t0 = Clock::now();
            GridResult g = cullGrid(scene, ps.grid, cam, &objects);
            st.ms = msSince(t0);
            st.ran = true;
            st.trianglesIn = trianglesOf(scene, objects);
            if (s.audit) culls.push_back({"grid", g.culled, {}});
            objects = std::move(g.visible);
            st.trianglesOut = trianglesOf(scene, objects);
            st.trianglesCulled = st.trianglesIn - st.trianglesOut;
            r.grid = g.stats;
            r.stages.push_back(st);
        }
    }

    // Frustum: bounding spheres over the object BVH, of the objects the coarse stage kept.
    {
        StageRecord st;
        st.name = "frustum";
        if (s.frustum) {
            const auto t0 = Clock::now();
            FrustumResult f = cullFrustum(scene, ps.bvh, cam, &objects);
            st.ms = msSince(t0);
            st.ran = true;
            r.frustum = f.stats;
            st.trianglesIn = trianglesOf(scene, objects);
            if (s.audit) culls.push_back({"frustum", removed(objects, f.visible), {}});
            objects = std::move(f.visible);
            st.trianglesOut = trianglesOf(scene, objects);
            st.trianglesCulled = st.trianglesIn - st.trianglesOut;
            r.stages.push_back(st);
        } else {
            r.stages.push_back(skipped("frustum", "turned off by --no-frustum"));
        }
    }

    // Occlusion: a depth pre-pass of the best occluders, a max-depth pyramid, conservative box tests.
    {
        StageRecord st;
        st.name = "occlusion";
        if (s.occlusion) {
            OcclusionResult oc = cullOcclusion(scene, cam, objects, s.occlusionSettings);
            st.ran = true;
            st.ms = oc.stats.prepassMs + oc.stats.testMs;
            st.trianglesIn = trianglesOf(scene, objects);
            if (s.audit) culls.push_back({"occlusion", oc.culled, {}});
            objects = std::move(oc.visible);
            st.trianglesOut = trianglesOf(scene, objects);
            st.trianglesCulled = st.trianglesIn - st.trianglesOut;
            r.occlusion = oc.stats;
            r.stages.push_back(st);
        } else {
            r.stages.push_back(skipped("occlusion", "turned off by --no-occlusion"));
        }
    }

    // Backface: plane at the eye, per triangle.
    TriangleLists lists;
    {
        StageRecord st;
        st.name = "backface";
        if (s.backface) {
            const auto t0 = Clock::now();
            BackfaceResult b = cullBackfaces(scene, objects, cam);
            st.ms = msSince(t0);
            st.ran = true;
            r.backface = b.stats;
            lists = std::move(b.kept);
            if (s.audit) culls.push_back({"backface", {}, std::move(b.culled)});
            st.trianglesIn = trianglesOf(scene, objects);
            st.trianglesOut = lists.size();
            st.trianglesCulled = st.trianglesIn - st.trianglesOut;
            r.stages.push_back(st);
        } else {
            lists = allTriangles(scene, objects);
            r.stages.push_back(skipped("backface", "turned off by --no-backface"));
        }
    }

    // Clip: one batch per object (its vertex range is transformed once).
    ClipResult clip;
    {
        StageRecord st;
        st.name = "clip";
        const auto t0 = Clock::now();
        std::vector<ClipBatch> batches;
        batches.reserve(lists.objects.size());
        for (size_t g = 0; g < lists.objects.size(); ++g) {
            const SceneObject &ob = scene.objects[lists.objects[g]];
            ClipBatch b;
            b.vertexBegin = ob.vertexBegin;
            b.vertexEnd = ob.vertexEnd;
            b.triangles = lists.triangles.data() + lists.groupBegin[g];
            b.count = lists.groupBegin[g + 1] - lists.groupBegin[g];
            if (b.count) batches.push_back(b);
        }
        clip = clipTriangles(cam, MeshView{scene.positions.data(), scene.indices.data()}, batches, s.clip);
        st.ms = msSince(t0);
        st.ran = true;
        r.clip = clip.stats;
        st.trianglesIn = lists.size();
        st.trianglesCulled = clip.stats.trivialRejected + clip.stats.clippedAway + clip.stats.edgeOn;
        st.trianglesOut = clip.stats.trianglesOut;  // screen triangles, after fan triangulation
        r.stages.push_back(st);
    }

    // Z-buffer: rasterize in the view's depth format.
    std::vector<uint32_t> fragmentsPerSource;  // per source triangle (audit: wasted fragments)
    {
        StageRecord st;
        st.name = "zbuffer";
        ZBufferSettings zs;
        zs.encoder = makeDepthEncoder(view.depthFormat, cam.nearZ, cam.farZ);
        zs.orthographic = cam.orthographic;
        if (s.audit || s.detail) {
            fragmentsPerSource.assign(scene.triangleCount(), 0);
            zs.fragmentsPerSource = fragmentsPerSource.data();
        }
        const auto t0 = Clock::now();
        ZBufferResult z = rasterize(clip.out, cam.width, cam.height, zs);
        st.ms = msSince(t0);
        st.ran = true;
        r.zbuffer = z.stats;
        r.buffer = std::move(z.buffer);
        st.trianglesIn = z.stats.trianglesIn;
        st.trianglesCulled = z.stats.trianglesEmpty;
        st.trianglesOut = z.stats.trianglesDrawn;
        r.stages.push_back(st);
    }

    // Raycast: Embree primary rays over the whole scene with no culling (single-sided triangles seen
    // from their front only, as the reference sees them; ties to the lowest id), compared pixel by
    // pixel with the z-buffer; then the secondary rays the effects plan calls for.
    if (ps.rays) {
        StageRecord st;
        st.name = "raycast";
        const auto t0 = Clock::now();
        PrimaryOptions opt;
        opt.rejectBackFaces = s.backface;
        opt.doubleSided = ps.effectsData.doubleSided.data();
        opt.planes = scene.planes.data();
        opt.tiesToLowestId = true;
        opt.keepBarycentrics = ps.effects.tracesRays();
        r.raycastImage = ps.rays->castPrimary(cam, opt, &r.raycast);
        st.ms = msSince(t0);
        st.ran = true;
        r.raycastRan = true;
        st.trianglesIn = scene.objectTriangles.size();
        std::vector<uint8_t> seen(scene.triangleCount(), 0);
        for (uint32_t id : r.raycastImage.id)
            if (id && !seen[id - 1]) {
                seen[id - 1] = 1;
                ++st.trianglesOut;
            }
        // Triangles no ray hit: "culled" in the sense of this stage's funnel (not visible).
        st.trianglesCulled = st.trianglesIn - st.trianglesOut;
        r.stages.push_back(st);
        r.crossCheck = crossCheck(r.buffer.id, r.buffer.depth, r.raycastImage.id, r.raycastImage.depth, scene, cam,
                                  makeDepthEncoder(view.depthFormat, cam.nearZ, cam.farZ), ps.rays->origin());
        if (ps.effects.tracesRays()) {
            r.effects = traceEffects(*ps.rays, cam, r.raycastImage, effectsInputFor(ps.effectsData, ps.effects));
            r.effectsRan = true;
        }
    } else {
        r.stages.push_back(skipped("raycast", "turned off by --no-raycast"));
    }

    // Audit: the reference visibility (no culling at all), and what each culling stage removed
    // that is in fact visible (false culls) or kept that is visible nowhere (wasted draws).
    if (s.audit) {
        const auto t0 = Clock::now();
        r.reference = referenceVisibility(scene, cam);
        r.cullAudit = auditCulling(scene, r.reference, culls, lists.triangles, &fragmentsPerSource);
        r.auditMs = msSince(t0);
        r.auditRan = true;
    } else {
        r.auditReason = "turned off by --no-audit";
    }

    // Audit: draw orders against the reference -- painter's, BSP, scanline, overdraw by order, and
    // the A-buffer where the scene has transparency.
    if (ps.bspTree && r.auditRan) {
        r.ordering = analyzeOrdering(scene, cam, r.reference, *ps.bspTree, ps.effects.abuffer, s.orderingSettings);
        r.orderingRan = true;
    } else {
        r.orderingReason = ps.orderingReason.empty() ? "needs the reference visibility" : ps.orderingReason;
    }

    // Audit: detail -- triangles drawn against the pixels they show, too small, over-detailed.
    if (s.detail) {
        r.detail = auditDetail(scene, cam, lists.triangles, fragmentsPerSource, r.buffer.id, s.detailSettings);
        r.detailRan = true;
    }

    // Audit: z-fighting of the two nearest surfaces per pixel, in every depth format, over exactly
    // the triangles the z-buffer drew.
    if (s.zfight) {
        const auto t0 = Clock::now();
        r.zfight = analyzeZFighting(scene, cam, clip.out, s.zfightSettings);
        r.zfightMs = msSince(t0);
        r.zfightRan = true;
    } else {
        r.zfightReason = "turned off by --no-zfight";
    }
    r.totalMs = msSince(tView);
    return r;
}

bool analyzeScene(const Scene &scene, const std::vector<ViewSpec> &views, const PipelineSettings &s,
                  const std::function<bool(size_t index, ViewResult &, std::string *)> &onView, AnalysisResult *out,
                  std::string *err) {
    // Validate every view before any work, so bad input never leaves a partial report.
    std::vector<ViewSpec> resolved(views.size());
    std::vector<Camera> cams(views.size());
    for (size_t i = 0; i < views.size(); ++i)
        if (!resolveView(views[i], s, &resolved[i], &cams[i], err)) return false;

    out->scenePath = scene.path;
    out->sceneStats = scene.stats;
    out->triangles = scene.objectTriangles.size();
    out->objects = scene.objects.size();
    out->sourceObjects = scene.sources.size();
    out->bounds = scene.bounds;
    out->views.assign(views.size(), ViewResult{});

    std::optional<tbb::global_control> threads;
    if (s.threads > 0) threads.emplace(tbb::global_control::max_allowed_parallelism, size_t(s.threads));
    PreparedScene ps;
    if (!prepareScene(scene, s, &ps, err)) return false;
    out->effects = ps.effects;
    out->raycast = ps.rays != nullptr;
    out->raySceneBuildMs = ps.raySceneBuildMs;
    out->orderingReason = ps.orderingReason;
    if (ps.bspTree) {
        out->bspTreeBuilt = true;
        out->bspTree = ps.bspTree->stats;
    }
    for (const Light &l : scene.lights) out->lightNames.push_back(l.name);
    if (scene.bsp) {
        AnalysisResult::BspSummary b;
        b.faces = scene.bsp->faceCounts;
        b.leafs = scene.bsp->leafs.size();
        b.clusters = scene.bsp->clusterCount;
        b.patchLevel = scene.bsp->patchLevel;
        b.hasPvs = scene.bsp->hasPvs();
        b.spawnPoints = spawnViews(scene).size();
        out->bsp = b;
    }
    std::mutex errMutex;
    std::string firstErr;
    std::atomic<bool> failed{false};
    tbb::parallel_for(size_t(0), views.size(), [&](size_t i) {
        if (failed) return;
        ViewResult v = analyzeView(ps, resolved[i], cams[i], s);
        std::string e;
        if (v.effectsRan && !v.effects.ok) {
            std::lock_guard<std::mutex> lock(errMutex);
            if (!failed.exchange(true)) firstErr = "view '" + v.spec.name + "': effects: " + v.effects.error;
            return;
        }
        if (onView && !onView(i, v, &e)) {
            std::lock_guard<std::mutex> lock(errMutex);
            if (!failed.exchange(true)) firstErr = e;
            return;
        }
        out->views[i] = std::move(v);
    });
    if (failed) {
        *err = firstErr;
        return false;
    }
    return true;
}

}  // namespace va
