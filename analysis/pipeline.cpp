#include "analysis/pipeline.h"

#include <algorithm>
#include <atomic>
#include <mutex>

#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>

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

ViewResult analyzeView(const PreparedScene &ps, const ViewSpec &view, const Camera &cam, const PipelineSettings &s) {
    const Scene &scene = *ps.scene;
    const Stopwatch tView;
    ViewResult r;
    r.spec = view;
    r.camera = cam;
    // Checked between stages: an interrupted view returns what it has, and analyzeScene discards it.
    auto stopped = [&] { return s.cancel && s.cancel->load(std::memory_order_relaxed) != 0; };

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
            const Stopwatch t0;
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
            st.ms = t0.ms();
            st.ran = true;
            if (s.audit) {
                culls.push_back({"cells", removed(objects, visible), {}});
                // A map's PVS leaves out on purpose what lies beyond its designed far plane.
                if (!hasPortals && scene.bsp) culls.back().designFarPlane = scene.bsp->farPlane.distance;
            }
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
            const Stopwatch t0;
            GridResult g = cullGrid(scene, ps.grid, cam, &objects);
            st.ms = t0.ms();
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
            const Stopwatch t0;
            FrustumResult f = cullFrustum(scene, ps.bvh, cam, &objects);
            st.ms = t0.ms();
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

    if (stopped()) return r;
    // Backface: plane at the eye, per triangle.
    TriangleLists lists;
    {
        StageRecord st;
        st.name = "backface";
        if (s.backface) {
            const Stopwatch t0;
            BackfaceResult b = cullBackfaces(scene, objects, cam);
            st.ms = t0.ms();
            st.ran = true;
            r.backface = b.stats;
            lists = std::move(b.kept);
            if (s.audit) culls.push_back({"backface", {}, std::move(b.culled), true});
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
        const Stopwatch t0;
        const std::vector<ClipBatch> batches = clipBatches(scene, lists);
        clip = clipTriangles(cam, MeshView{scene.positions.data(), scene.indices.data()}, batches, s.clip);
        st.ms = t0.ms();
        st.ran = true;
        r.clip = clip.stats;
        st.trianglesIn = lists.size();
        st.trianglesCulled = clip.stats.trivialRejected + clip.stats.clippedAway + clip.stats.edgeOn;
        st.trianglesOut = clip.stats.trianglesOut;  // screen triangles, after fan triangulation
        r.stages.push_back(st);
    }

    if (stopped()) return r;
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
        const Stopwatch t0;
        ZBufferResult z = rasterize(clip.out, cam.width, cam.height, zs);
        st.ms = t0.ms();
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
    if (stopped()) return r;
    if (ps.rays) {
        StageRecord st;
        st.name = "raycast";
        const Stopwatch t0;
        PrimaryOptions opt;
        opt.rejectBackFaces = s.backface;
        opt.doubleSided = ps.effectsData.doubleSided.data();
        opt.planes = scene.planes.data();
        opt.tiesToLowestId = true;
        opt.keepBarycentrics = ps.effects.tracesRays();
        r.raycastImage = ps.rays->castPrimary(cam, opt, &r.raycast);
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
        // Like with like: the z-buffer drew only what the culling stages kept (lists.triangles). Where
        // the whole-scene rays hit a triangle outside that set, cast again over the set itself, so
        // that a cull (judged by the culling audit) is never also counted as a disagreement.
        std::vector<uint8_t> outOfSet(scene.triangleCount(), 1);
        for (uint32_t t : lists.triangles) outOfSet[t] = 0;
        uint64_t culledPixels = 0;
        for (uint32_t id : r.raycastImage.id) culledPixels += id && outOfSet[id - 1];
        RaycastImage sameSet;
        if (culledPixels > 0) {
            PrimaryOptions same = opt;
            same.keepBarycentrics = false;
            same.rejectSource = outOfSet.data();
            sameSet = ps.rays->castPrimary(cam, same, nullptr);
        }
        st.ms = t0.ms();
        r.stages.push_back(st);
        const RaycastImage &compared = culledPixels > 0 ? sameSet : r.raycastImage;
        r.crossCheck = crossCheck(r.buffer.id, r.buffer.depth, compared.id, compared.depth, scene, cam,
                                  makeDepthEncoder(view.depthFormat, cam.nearZ, cam.farZ), ps.rays->origin());
        r.crossCheck.culled = culledPixels;
        r.crossCheck.recast = culledPixels > 0;
        if (ps.effects.tracesRays() && !stopped()) {
            r.effects = traceEffects(*ps.rays, cam, r.raycastImage, effectsInputFor(ps.effectsData, ps.effects));
            r.effectsRan = true;
        }
    } else {
        r.stages.push_back(skipped("raycast", "turned off by --no-raycast"));
    }

    // Audit: the reference visibility (no culling at all), and what each culling stage removed
    // that is in fact visible (false culls) or kept that is visible nowhere (wasted draws).
    if (stopped()) return r;
    if (s.audit) {
        const Stopwatch t0;
        // The ordering audit walks the reference's fragments again in other orders: kept for it,
        // up to 4 per pixel (48 bytes a pixel; estimateMemory), above which it rasterizes again.
        const uint64_t pixels = uint64_t(std::max(cam.width, 0)) * uint64_t(std::max(cam.height, 0));
        const uint64_t cache = ps.bspTree ? std::min<uint64_t>(kOrderingCachedFragmentsPerPixel * pixels, 1ull << 31) : 0;
        r.reference = referenceVisibility(scene, cam, cache);
        r.cullAudit = auditCulling(scene, r.reference, culls, lists.triangles, &fragmentsPerSource, &cam);
        // A map's PVS: the evidence of each false cull it made (camera leaf and cluster, faces, leafs,
        // clusters, PVS bits, distances), for a reader to check against the map's bytes.
        if (hasPvs && !hasPortals && s.cells)
            for (size_t k = 0; k < culls.size(); ++k)
                if (culls[k].stage == "cells") r.pvsEvidence = pvsEvidence(scene, cam, r.cells, r.reference, r.cullAudit, k);
        r.auditMs = t0.ms();
        r.auditRan = true;
    } else {
        r.auditReason = "turned off by --no-audit";
    }

    // Audit: draw orders against the reference -- painter's, BSP, scanline, overdraw by order, and
    // the A-buffer where the scene has transparency.
    if (stopped()) return r;
    if (ps.bspTree && r.auditRan) {
        OrderingSettings os = s.orderingSettings;
        os.abufferMaxList = s.limits.maxABufferList;
        r.ordering = analyzeOrdering(scene, cam, r.reference, *ps.bspTree, ps.effects.abuffer, os);
        r.orderingRan = true;
    } else {
        r.orderingReason = ps.orderingReason.empty() ? "needs the reference visibility" : ps.orderingReason;
    }
    // The reference's screen triangles and fragments served the ordering audit only: a finished
    // view keeps neither (estimateMemory's finishedViews).
    r.reference.fragmentCache = FragmentCache{};
    r.reference.screen = ScreenTriangles{};

    // Audit: detail -- triangles drawn against the pixels they show, too small, over-detailed.
    if (stopped()) return r;
    if (s.detail) {
        r.detail = auditDetail(scene, cam, lists.triangles, fragmentsPerSource, r.buffer.id, s.detailSettings);
        r.detailRan = true;
    }

    // Audit: z-fighting of the two nearest surfaces per pixel, in every depth format, over exactly
    // the triangles the z-buffer drew.
    if (stopped()) return r;
    if (s.zfight) {
        const Stopwatch t0;
        // The view's own format is always evaluated (budgets read its row) and explains hotspots.
        ZFightSettings zs = s.zfightSettings;
        zs.viewFormat = view.depthFormat;
        if (std::find(zs.formats.begin(), zs.formats.end(), view.depthFormat) == zs.formats.end() &&
            zs.formats.size() < 32)
            zs.formats.push_back(view.depthFormat);
        r.zfight = analyzeZFighting(scene, cam, clip.out, zs);
        r.zfightMs = t0.ms();
        r.zfightRan = true;
    } else {
        r.zfightReason = "turned off by --no-zfight";
    }
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
              bytesOf(scene.objectTriangles) + bytesOf(scene.planes) + bytesOf(scene.planeBounds) +
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
    //   z-fighting: class, fight mask, hotspot ids (+ 2 nearest depths and triangles while it runs)
    //                                                      9 + 24
    //   ordering: painter and BSP id + class, scanline id, per-order overdraw, A-buffer composite,
    //     edges, heads, lengths and center depth          5 + 5 + 4 + 8 + 4 + 24
    //   occlusion's pre-pass depth and Hi-Z pyramid (freed before the z-buffer)   not added
    //   writing images (one 8-bit RGBA or float image at a time, and the PNG encoder)   16
    uint64_t perPixel = 20 + 16;
    if (s.audit) perPixel += 13;
    if (s.raycast) perPixel += 17;  // + the cross-check's recast over the z-buffer's set (id, depth)
    if (s.zfight) perPixel += 33;
    const EffectPlan plan = planEffects(scene, s.effects);
    if (s.raycast && plan.tracesRays()) perPixel += 8 + 3 + (scene.lights.size() + 7) / 8;
    if (s.ordering && s.audit && tris <= s.orderingMaxTriangles) {
        // + the reference's fragment cache (12 bytes a fragment), and the ordering's per-thread
        // scratch: a depth buffer (8) and the BSP's piece lists and owners (4 bytes a fragment, 3x).
        perPixel += 22 + 12 * kOrderingCachedFragmentsPerPixel + 8 + 12 * kOrderingCachedFragmentsPerPixel;
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
    if (!prepareScene(scene, s, &ps, err)) return false;
    if (stopped()) {
        *err = kInterrupted;
        return false;
    }
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
    tbb::parallel_for(size_t(0), views.size(), [&](size_t i) {
        if (failed) return;
        if (stopped()) return failWith(kInterrupted);
        ViewResult v = analyzeView(ps, resolved[i], cams[i], s);
        if (stopped()) return failWith(kInterrupted);
        std::string e;
        if (v.effectsRan && !v.effects.ok) return failWith("view '" + v.spec.name + "': effects: " + v.effects.error);
        if (v.orderingRan && !v.ordering.abuffer.error.empty())
            return failWith("view '" + v.spec.name + "': " + v.ordering.abuffer.error);
        if (onView && !onView(i, v, &e)) return failWith(e);
        out->views[i] = std::move(v);
    });
    if (failed) {
        *err = firstErr;
        return false;
    }
    return true;
}

}  // namespace va
