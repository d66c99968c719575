#include "analysis/pipeline.h"

#include <atomic>
#include <chrono>
#include <mutex>

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include "analysis/backface.h"
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

    // Coarse stage: cells/PVS where the scene has them (not in this scene model yet).
    r.stages.push_back(skipped("cells", "scene has no cells, portals or PVS"));

    // Frustum: bounding spheres over the object BVH.
    std::vector<uint32_t> objects;
    std::vector<StageCulls> culls;  // what each culling stage removed, for the audit
    const uint64_t sceneTriangles = scene.objectTriangles.size();
    {
        StageRecord st;
        st.name = "frustum";
        if (s.frustum) {
            const auto t0 = Clock::now();
            FrustumResult f = cullFrustum(scene, ps.bvh, cam);
            st.ms = msSince(t0);
            st.ran = true;
            objects = std::move(f.visible);
            r.frustum = f.stats;
            if (s.audit) {
                StageCulls c{"frustum", {}, {}};
                size_t k = 0;
                for (uint32_t o = 0; o < scene.objects.size(); ++o) {
                    if (k < objects.size() && objects[k] == o)
                        ++k;
                    else
                        c.objects.push_back(o);
                }
                culls.push_back(std::move(c));
            }
            st.trianglesIn = sceneTriangles;
            st.trianglesOut = trianglesOf(scene, objects);
            st.trianglesCulled = st.trianglesIn - st.trianglesOut;
            r.stages.push_back(st);
        } else {
            objects.resize(scene.objects.size());
            for (uint32_t i = 0; i < objects.size(); ++i) objects[i] = i;
            r.stages.push_back(skipped("frustum", "turned off by --no-frustum"));
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
        if (s.audit) {
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

    const PreparedScene ps = prepareScene(scene);
    std::optional<tbb::global_control> threads;
    if (s.threads > 0) threads.emplace(tbb::global_control::max_allowed_parallelism, size_t(s.threads));
    std::mutex errMutex;
    std::string firstErr;
    std::atomic<bool> failed{false};
    tbb::parallel_for(size_t(0), views.size(), [&](size_t i) {
        if (failed) return;
        ViewResult v = analyzeView(ps, resolved[i], cams[i], s);
        std::string e;
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
