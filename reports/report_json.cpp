// report.json: the analysis result as JSON (schema: docs/report-schema.json).
//
// Layout: format and tool first, then the scene, then one object per view (camera, stage funnel
// with each stage's own counts, z-buffer summary, image file names), then totals over all views.
// Keys are emitted in a fixed order (ordered_json) and only deterministic values are written, so
// two runs on the same input give byte-identical JSON except for the timing fields ("ms", "*_ms").
#include <cctype>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "reports/findings.h"
#include "reports/ordering_images.h"
#include "reports/report.h"
#include "reports/report_model.h"
#include "reports/level_maps.h"
#include "reports/routes.h"

namespace va {

using Json = nlohmann::ordered_json;

// ---- Image file names -------------------------------------------------------------------------

std::string sanitizeFileName(const std::string &viewName) {
    std::string s;
    s.reserve(viewName.size());
    for (unsigned char c : viewName) {
        const bool keep = std::isalnum(c) && c < 128;  // ASCII letters and digits only (no locale)
        s += (keep || c == '.' || c == '_' || c == '-') ? char(c) : '_';
    }
    if (s.empty()) s = "view";
    if (s[0] == '.') s[0] = '_';  // no hidden files, no "." or ".."
    if (s.size() > kMaxImageBaseName) s.resize(kMaxImageBaseName);
    return s;
}

namespace {
std::vector<std::string> uniqueBaseNames(const std::vector<const std::string *> &names) {
    // Names are compared in lower case: "Hall" and "hall" would be one file on a case-insensitive
    // file system (macOS, Windows), so they count as a collision.
    auto lower = [](std::string s) {
        for (char &c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
        return s;
    };
    std::set<std::string> taken;
    std::vector<std::string> out;
    out.reserve(names.size());
    for (const std::string *viewName : names) {
        const std::string base = sanitizeFileName(*viewName);
        std::string name = base;
        for (int k = 2; taken.count(lower(name)); ++k) name = base + "-" + std::to_string(k);
        taken.insert(lower(name));
        out.push_back(name);
    }
    return out;
}
}  // namespace

std::vector<std::string> imageBaseNames(const std::vector<ViewResult> &views) {
    std::vector<const std::string *> names;
    for (const ViewResult &v : views) names.push_back(&v.spec.name);
    return uniqueBaseNames(names);
}

std::vector<std::string> imageBaseNames(const std::vector<ViewSpec> &views) {
    std::vector<const std::string *> names;
    for (const ViewSpec &v : views) names.push_back(&v.name);
    return uniqueBaseNames(names);
}

ViewImageNames viewImageNames(const std::string &baseName) {
    return {baseName + ".depth.exr", baseName + ".depth.png", baseName + ".overdraw.png", baseName + ".ids.exr",
            baseName + ".zfight.png", baseName + ".culling.png", baseName + ".raycast.ids.exr",
            baseName + ".raycast_diff.png", baseName + ".secondary.png", baseName};
}

std::string shadowImageName(const ViewImageNames &names, size_t light, const ViewResult &view) {
    const std::vector<LightShadowStats> &lights = view.effects->lights;
    std::string name = lights[light].name.empty() ? std::string() : sanitizeFileName(lights[light].name);
    bool repeated = false;
    for (size_t k = 0; k < lights.size(); ++k)
        if (k != light && !lights[k].name.empty() && sanitizeFileName(lights[k].name) == name) repeated = true;
    if (name.empty() || repeated) name = "light" + std::to_string(light);
    return names.base + ".shadow." + name + ".png";
}

// ---- JSON -------------------------------------------------------------------------------------

namespace {

// JSON has no NaN or infinity: a non-finite double is written as null.
Json num(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

// A 3-vector as [x, y, z], or null when a coordinate is not finite (an empty scene's bounds).
Json vec3(Vec3 v) { return isFinite(v) ? Json::array({v.x, v.y, v.z}) : Json(nullptr); }

// The cells stage's row: a map's PVS or the scene's portals, and the view's note.
Json cellsJson(const ViewResult &v) {
    Json j = v.cellsArePortals ? json::write(v.portals) : json::write(v.cells);
    j["note"] = v.cellsNote;
    return j;
}

// Draw orders and exact orders (analysis/audits/ordering.h; docs/ordering.md).
Json orderingJson(const OrderingResult &o) {
    Json j;
    j["ran"] = true;
    j["table"] = json::value(o.table);
    j["painter"] = json::write(o.painter);
    j["bsp"] = json::write(o.bsp);
    Json byOrder = Json::array();
    for (const OrderOverdraw &d : o.overdrawByOrder) {
        Json e = json::write(d.stats);
        e["order"] = d.order;
        byOrder.push_back(e);
    }
    j["overdraw_by_order"] = byOrder;
    const ScanlineResult &sc = o.scanline;
    j["scanline"] = {{"wrong_pixels", o.scanlineWrongPixels},
                     {"tie_pixels", o.scanlineTiePixels},
                     {"edge_pixels", o.scanlineEdgePixels},
                     {"spans", sc.spans},
                     {"max_active_triangles", sc.maxActiveTriangles},
                     {"memory_bytes", sc.memoryBytes},
                     {"zbuffer_bytes", sc.zbufferBytes}};
    j["abuffer"] = o.abufferRan ? json::write(o.abuffer) : Json{{"ran", false}, {"reason", o.abufferReason}};
    j["ms"] = num(o.ms);
    return j;
}

// The raycast stage's cross-check with the z-buffer and the secondary rays (docs/audits.md,
// docs/effects.md).
Json raycastJson(const ViewResult &v, const std::vector<std::string> &lightNames) {
    Json j;
    j["ran"] = true;
    j["cross_check"] = json::write(v.raycast->crossCheck);
    if (v.effects.ran()) {
        j["effects"] = json::write(v.effects->stats);
        j["lights"] = json::value(v.effects->lights);
    }
    (void)lightNames;
    return j;
}

Json stageJson(const StageRecord &s, const ViewResult &v) {
    Json j;
    j["name"] = s.name;
    j["ran"] = s.ran;
    if (!s.ran) j["reason"] = s.reason;
    j["triangles_in"] = s.trianglesIn;
    j["triangles_culled"] = s.trianglesCulled;
    j["triangles_out"] = s.trianglesOut;
    j["ms"] = num(s.ms);
    // The stage's own counts, only when it ran (a skipped stage has none).
    if (s.ran) {
        Json own;
        if (s.name == "frustum") own = json::write(v.frustum);
        else if (s.name == "backface") own = json::write(v.backface);
        else if (s.name == "clip") own = json::write(v.clip);
        else if (s.name == "zbuffer") own = json::write(v.zbuffer, json::kZBufferStageKeys);
        else if (s.name == "cells") own = cellsJson(v);
        else if (s.name == "grid") own = json::write(v.grid);
        else if (s.name == "occlusion") own = json::write(v.occlusion);
        else if (s.name == "raycast") own = json::write(v.raycast->stats);
        for (auto it = own.begin(); it != own.end(); ++it) j[it.key()] = it.value();
    }
    return j;
}

Json cameraJson(const CameraSpec &c) {
    Json j;
    j["eye"] = vec3(c.eye);
    j["target"] = vec3(c.target);
    j["up"] = vec3(c.up);
    if (c.orthographic) j["ortho_height"] = num(c.orthoHeight);
    else j["fov_y"] = num(c.fovYDegrees);
    j["near"] = num(c.nearZ);
    j["far"] = num(c.farZ);
    return j;
}

// The evidence of a map's PVS false culls (analysis/audits/pvs_evidence.h; docs/quake3.md, "Reading the
// evidence"). Bounded by the kEvidence* limits; every list says what it left out.
Json pvsEvidenceJson(const PvsEvidence &e) {
    auto leafs = [](const std::vector<PvsLeafBit> &ls) {
        Json a = Json::array();
        for (const PvsLeafBit &l : ls)
            a.push_back({{"leaf", l.leaf},
                         {"cluster", l.cluster},
                         {"in_tree", l.inTree},
                         {"pvs_bit", l.pvsBit < 0 ? Json(nullptr) : Json(l.pvsBit)}});
        return a;
    };
    Json objects = Json::array();
    for (const PvsObjectEvidence &o : e.objects) {
        Json clusters = Json::array();
        for (const PvsClusterBit &c : o.clusters) clusters.push_back({{"cluster", c.cluster}, {"pvs_bit", c.pvsBit}});
        Json faces = Json::array();
        for (const PvsFaceEvidence &f : o.faces)
            faces.push_back({{"face", f.face},
                             {"pixels", f.pixels},
                             {"nearest", num(f.nearest)},
                             {"pixel", {f.x, f.y}},
                             {"leafs", leafs(f.leafs)},
                             {"leafs_omitted", f.leafsOmitted}});
        Json oj = {{"object", o.object},
                   {"name", o.name},
                   {"model", o.model},
                   {"entity", o.entity},
                   {"classname", o.classname},
                   {"triangles", o.triangles},
                   {"pixels", o.pixels},
                   {"nearest", num(o.nearest)},
                   {"clusters", clusters},
                   {"clusters_omitted", o.clustersOmitted}};
        if (o.model > 0) {
            oj["box_leafs"] = leafs(o.boxLeafs);
            oj["box_leafs_omitted"] = o.boxLeafsOmitted;
        }
        oj["faces"] = faces;
        oj["faces_omitted"] = o.facesOmitted;
        objects.push_back(oj);
    }
    return {{"camera_leaf", e.cameraLeaf},
            {"camera_cluster", e.cameraCluster},
            {"design_far_plane", e.designFarPlane > 0 ? num(e.designFarPlane) : Json(nullptr)},
            {"false_cull_objects", e.falseCullObjects},
            {"false_cull_pixels", e.falseCullPixels},
            {"objects", objects},
            {"objects_omitted", e.objectsOmitted}};
}

// The audit against the reference visibility (analysis/audits/audit.h; docs/audits.md).
Json auditJson(const ViewResult &v) {
    const ReferenceVisibility &ref = v.audit->reference;
    const CullAudit &a = v.audit->cull;
    Json j;
    j["ran"] = true;
    j["reference"] = json::write(ref);
    Json byStage = Json::object();
    uint64_t falseObjects = 0;
    for (const StageCullAudit &s : a.stages) {
        byStage[s.stage] = json::write(s);
        falseObjects += s.falseCullObjects;
    }
    j["false_culls"] = {{"triangles", a.falseCullTriangles},
                        {"objects", falseObjects},
                        {"pixels", a.falseCullPixels},
                        {"beyond_far_plane_triangles", a.beyondFarPlaneTriangles},
                        {"beyond_far_plane_pixels", a.beyondFarPlanePixels},
                        {"by_stage", byStage}};
    if (v.audit->pvsEvidence.ran) j["pvs_evidence"] = pvsEvidenceJson(v.audit->pvsEvidence);
    j["wasted_draws"] = {{"drawn_triangles", a.drawnTriangles},
                         {"drawn_objects", a.drawnObjects},
                         {"triangles", a.wastedTriangles},
                         {"objects", a.wastedObjects},
                         {"drawn_fragments", a.drawnFragments},
                         {"fragments", a.wastedFragments},
                         {"share", a.drawnTriangles ? double(a.wastedTriangles) / double(a.drawnTriangles) : 0.0}};
    j["unaccounted_pixels"] = a.unaccountedPixels;
    j["ms"] = num(v.audit->ms);
    return j;
}

// The per-view z-fighting analysis (analysis/audits/zfight.h; docs/zfighting.md).
Json depthJson(const ZFightResult &z) {
    Json j;
    j["ran"] = true;
    j["covered_pixels"] = z.coveredPixels;
    j["two_surface_pixels"] = z.twoSurfacePixels;
    j["fighting_pixels_any_format"] = z.fightingPixelsAnyFormat;
    j["classes"] = {{"separated", z.separatedPixels},
                    {"coplanar", z.coplanarPixels},
                    {"shared_edge", z.sharedEdgePixels},
                    {"intersection", z.intersectionPixels}};
    Json formats = Json::object();
    for (const ZFightFormatStats &f : z.perFormat) {
        formats[f.name] = json::write(f);
    }
    j["formats"] = formats;
    j["recommended_format"] = z.recommended ? Json(depthFormatName(*z.recommended)) : Json(nullptr);
    j["recommendation"] = z.recommendation;
    j["hotspot_count"] = z.hotspotCount;
    Json hs = Json::array();
    for (const ZFightHotspot &h : z.hotspots) {
        Json fj = Json::array();
        for (const ZFightHotspotFormat &f : h.formats)
            fj.push_back({{"name", depthFormatName(f.format)}, {"pixels", f.pixels}});
        hs.push_back({{"id", h.id},
                      {"area", h.area},
                      {"bbox", {h.minX, h.minY, h.maxX, h.maxY}},
                      {"centroid", vec3(h.centroid)},
                      {"depth", num(h.depth)},
                      {"depth_gap", num(h.depthGap)},
                      {"depth_gap_max", num(h.depthGapMax)},
                      {"coplanar_pixels", h.coplanarPixels},
                      {"objects", {h.objectA, h.objectB}},
                      {"triangles", {h.triangleA, h.triangleB}},
                      {"pair_pixels", h.pairPixels},
                      {"pairs", h.pairs},
                      {"formats", fj},
                      // Why it fights (analysis/audits/zfight.h explainHotspot; docs/zfighting.md).
                      {"view_bucket_width", h.viewBucketWidth ? num(*h.viewBucketWidth) : Json(nullptr)},
                      {"cheapest_format",
                       h.cheapestFormat ? Json(depthFormatInfo(*h.cheapestFormat).name) : Json(nullptr)},
                      {"cheapest_bucket_width", h.cheapestBucketWidth ? num(*h.cheapestBucketWidth) : Json(nullptr)},
                      {"why", h.why}});
    }
    j["hotspots"] = hs;
    j["ms"] = num(z.ms);
    return j;
}

// "scene": what was loaded, and a Quake 3 map's structure.
Json sceneJson(const AnalysisResult &r) {
    Json scene;
    scene["path"] = r.scenePath;
    scene["triangles"] = r.triangles;
    scene["source_triangles"] = r.sceneStats.sourceTriangles;
    scene["objects"] = r.objects;
    scene["source_objects"] = r.sourceObjects;
    scene["degenerate_triangles"] = r.sceneStats.degenerateTriangles;
    scene["non_finite_triangles"] = r.sceneStats.nonFiniteTriangles;
    scene["faces_dropped"] = r.sceneStats.facesDropped;
    scene["polygons_triangulated"] = r.sceneStats.polygonsTriangulated;
    scene["bounds"] = {{"min", vec3(r.bounds.lo)}, {"max", vec3(r.bounds.hi)}};
    if (!r.sceneWarnings.empty()) scene["warnings"] = r.sceneWarnings;
    if (r.bsp) {
        const BspFaceCounts &f = r.bsp->faces;
        scene["bsp"] = {{"faces", f.faces},
                        {"polygons", f.polygons},
                        {"patches", f.patches},
                        {"meshes", f.meshes},
                        {"billboards", f.billboards},
                        {"bad", f.bad},
                        {"sky", f.sky},
                        {"nodraw", f.nodraw},
                        {"non_solid", f.nonSolid},
                        {"polygon_triangles", f.polygonTriangles},
                        {"patch_triangles", f.patchTriangles},
                        {"mesh_triangles", f.meshTriangles},
                        {"sky_triangles", f.skyTriangles},
                        {"nodraw_triangles", f.nodrawTriangles},
                        {"non_solid_triangles", f.nonSolidTriangles},
                        {"unleafed_faces", f.unleafedFaces},
                        {"model_faces", f.modelFaces},
                        {"brush_entities_drawn", r.bsp->drawnBrushEntities},
                        {"brush_entities_not_drawn", r.bsp->notDrawnBrushEntities},
                        {"not_drawn_entity_faces", f.notDrawnEntity},
                        {"not_drawn_entity_triangles", f.notDrawnEntityTriangles},
                        {"leafs", r.bsp->leafs},
                        {"clusters", r.bsp->clusters},
                        {"patch_level", r.bsp->patchLevel},
                        {"has_pvs", r.bsp->hasPvs},
                        {"spawn_points", r.bsp->spawnPoints}};
        Json notDrawn = Json::array();
        for (const auto &e : r.bsp->notDrawn)
            notDrawn.push_back({{"model", e.model},
                                {"entity", e.entity},
                                {"classname", e.classname},
                                {"reason", e.reason},
                                {"faces", e.faces},
                                {"triangles", e.triangles}});
        scene["bsp"]["not_drawn_entities"] = notDrawn;
        const BspFarPlane &fp = r.bsp->farPlane;
        scene["bsp"]["far_plane"] = fp.distance > 0 ? Json{{"distance", fp.distance},
                                                           {"mode", fp.mode ? std::string(1, fp.mode) : std::string()},
                                                           {"key", fp.key},
                                                           {"value", fp.value}}
                                                     : Json(nullptr);
        scene["bsp"]["fog_shader"] = r.bsp->fogShader.empty() ? Json(nullptr) : Json(r.bsp->fogShader);
    }
    return scene;
}

// "bsp_tree" (the ordering audit's tree, built once) and "effects" (what the scene called for).
void preparedJson(const AnalysisResult &r, Json &j) {
    Json decisions = Json::array();
    for (const EffectDecision &d : r.effects.all())
        decisions.push_back({{"name", d.name},
                             {"ran", d.run && (d.name == "abuffer" ? r.bspTreeBuilt : r.raycast)},
                             {"called_for", d.run},
                             {"forced", d.forced}, {"reason", d.reason}, {"triangles", d.triangles}});
    if (r.bspTreeBuilt) {
        j["bsp_tree"] = json::write(r.bspTree);
    } else {
        j["bsp_tree"] = {{"ran", false}, {"reason", r.orderingReason}};
    }
    j["effects"] = {{"raycast", r.raycast},
                    {"ray_scene_build_ms", num(r.raySceneBuildMs)},
                    {"max_depth", r.effects.maxDepth},
                    {"decisions", decisions}};
}

// A view's "images": the file of each image it has, of those --images wrote.
Json viewImagesJson(const ViewResult &v, const ViewImageNames &names, ImageSet images) {
    Json im = {{"depth_exr", names.depthExr},
               {"depth_png", names.depthPng},
               {"overdraw_png", names.overdrawPng},
               {"ids_exr", names.idsExr}};
    if (v.zfight.ran()) im["zfight_png"] = names.zfightPng;
    if (v.audit.ran()) im["culling_png"] = names.cullingPng;
    if (v.ordering.ran()) {
        const OrderingImageNames on = orderingImageNames(names.base);
        im["painter_errors_png"] = on.painterErrorsPng;
        im["overdraw_order_png"] = on.overdrawOrderPng;
        if (v.ordering->abufferRan) im["abuffer_png"] = on.abufferPng;
    }
    if (v.raycast.ran()) {
        im["raycast_ids_exr"] = names.raycastIdsExr;
        im["raycast_diff_png"] = names.raycastDiffPng;
    }
    if (v.effects.ran()) {
        if (!v.effects->lights.empty()) {
            Json shadows = Json::array();
            for (size_t l = 0; l < v.effects->lights.size(); ++l) shadows.push_back(shadowImageName(names, l, v));
            im["shadow_png"] = shadows;
        }
        im["secondary_png"] = names.secondaryPng;
    }
    // Only the images the run wrote (--images).
    if (images != ImageSet::all) {
        Json kept = Json::object();
        for (auto it = im.begin(); it != im.end(); ++it)
            if (imageWritten(images, it.key())) kept[it.key()] = it.value();
        im = kept;
    }
    return im;
}

// "depth_curves": resolution against view depth per format, for the page's plot of each view's
// near and far (analysis/pipeline.cpp addDepthCurves; docs/depth-formats.md).
Json depthCurvesJson(const std::vector<DepthAuditResult> &curves) {
    Json a = Json::array();
    for (const DepthAuditResult &c : curves) {
        Json formats = Json::array();
        for (const DepthFormatAudit &f : c.formats) formats.push_back({{"name", f.name}, {"resolution", json::value(f.curveResolution)}});
        a.push_back({{"near", num(c.nearZ)}, {"far", num(c.farZ)}, {"depths", json::value(c.curveDepths)}, {"formats", formats}});
    }
    return a;
}

// One view's entry of "views".
Json viewJson(const ViewResult &v, const std::string &base, const std::vector<std::string> &lightNames,
              ImageSet images) {
    Json vj;
    vj["name"] = v.spec.name;
    vj["index"] = v.index;
    vj["origin"] = v.spec.origin;
    // A route's frame (docs/routes.md): only on views sampled from a route.
    if (v.spec.route.onRoute())
        vj["route"] = {{"name", v.spec.route.route}, {"frame", v.spec.route.frame}, {"time", num(v.spec.route.time)}};
    vj["width"] = v.spec.camera.width;
    vj["height"] = v.spec.camera.height;
    vj["depth_format"] = depthFormatName(v.spec.depthFormat);
    vj["projection"] = v.spec.camera.orthographic ? "orthographic" : "perspective";
    vj["camera"] = cameraJson(v.spec.camera);
    Json stages = Json::array();
    for (const StageRecord &s : v.stages) {
        stages.push_back(stageJson(s, v));
    }
    vj["stages"] = stages;
    vj["zbuffer"] = json::write(v.zbuffer);
    const ViewImageNames names = viewImageNames(v.imageBase.empty() ? base : v.imageBase);
    // A section that ran is written whole; one that did not says why.
    auto section = [](const auto &ran, auto write) {
        return ran.ran() ? write(*ran) : Json{{"ran", false}, {"reason", ran.reason()}};
    };
    vj["raycast"] = section(v.raycast, [&](const RaycastResult &) { return raycastJson(v, lightNames); });
    vj["ordering"] = section(v.ordering, orderingJson);
    vj["detail"] = section(v.detail, [](const DetailResult &d) { return json::write(d); });
    vj["audit"] = section(v.audit, [&](const CullingAuditResult &) { return auditJson(v); });
    vj["depth"] = section(v.zfight, depthJson);
    vj["images"] = viewImagesJson(v, names, images);
    vj["depth_curve"] = v.depthCurve >= 0 ? Json(uint64_t(v.depthCurve)) : Json(nullptr);
    vj["total_ms"] = num(v.totalMs);
    return vj;
}

}  // namespace

nlohmann::ordered_json reportJson(const AnalysisResult &r, ImageSet images) {
    Json j;
    j["format"] = kReportFormat;
    j["tool"] = {{"name", "visaudit"}, {"version", VISAUDIT_VERSION}};
    j["scene"] = sceneJson(r);
    j["load_ms"] = num(r.loadMs);
    preparedJson(r, j);
    j["shard"] = {{"index", r.shard.index}, {"count", r.shard.count},
                  {"views_total", r.shard.viewsTotal ? r.shard.viewsTotal : r.views.size()}};
    j["depth_curves"] = depthCurvesJson(r.depthCurves);
    const std::vector<std::string> bases = imageBaseNames(r.views);
    // One view after the other, each moved in. Not in parallel: the JSON's small blocks all come
    // from the process's one malloc arena (common/process_heap.h), and two threads building at once
    // took turns on its lock: 487 ms for the 171 views of the oa_thor level run against 75 ms here.
    Json views = Json::array();
    for (size_t i = 0; i < r.views.size(); ++i) views.push_back(viewJson(r.views[i], bases[i], r.lightNames, images));
    j["views"] = std::move(views);
    j["totals"] = reportTotals(j["views"]);
    addFindings(&j);
    // Routes (docs/routes.md): their definitions, then their series from the views.
    if (!r.routes.empty()) {
        Json routes = Json::array();
        for (const Route &route : r.routes) routes.push_back(routeDefinitionJson(route));
        j["routes"] = routes;
        addRouteSeries(&j);
    }
    // Level maps (docs/level-maps.md): the floor plan, then the positions and values from the views.
    if (r.floorPlan) {
        j["level_maps"] = {{"floor", floorPlanJson(*r.floorPlan)}};
        addLevelMaps(&j);
    }
    return j;
}

void addOutputTimings(nlohmann::ordered_json *report, const OutputTimings &t) {
    (*report)["output"] = {{"images_ms", num(t.imagesMs)}, {"report_ms", num(t.reportMs)}, {"html_ms", num(t.htmlMs)}};
}

// Totals over views, computed from the views' JSON alone, so that `merge` recomputes exactly what a
// single run writes: per-stage culled triangles (stages in order of first appearance, which is
// docs/architecture.md's fixed order), z-buffer sums.
nlohmann::ordered_json reportTotals(const nlohmann::ordered_json &views) {
    std::vector<std::string> stageOrder;
    std::map<std::string, uint64_t> culled;
    uint64_t covered = 0, fragments = 0, passes = 0;
    uint64_t falseTris = 0, falsePixels = 0, beyondPixels = 0, wastedTris = 0, wastedFragments = 0, genuine = 0,
             hotspots = 0;
    std::map<std::string, uint64_t> falseByStage;
    double totalMs = 0;
    // A count of a section that may be absent (a stage or audit that did not run) reads as 0.
    auto count = [](const Json &j, std::initializer_list<const char *> path) -> uint64_t {
        const Json *x = &j;
        for (const char *k : path) {
            if (!x->is_object() || !x->contains(k)) return 0;
            x = &(*x)[k];
        }
        return x->is_number_unsigned() ? x->get<uint64_t>() : 0;
    };
    for (const Json &v : views) {
        falseTris += count(v, {"audit", "false_culls", "triangles"});
        falsePixels += count(v, {"audit", "false_culls", "pixels"});
        beyondPixels += count(v, {"audit", "false_culls", "beyond_far_plane_pixels"});
        if (v.contains("audit") && v["audit"].contains("false_culls"))
            for (const auto &[stage, st] : v["audit"]["false_culls"]["by_stage"].items())
                falseByStage[stage] += count(st, {"false_cull_triangles"});
        wastedTris += count(v, {"audit", "wasted_draws", "triangles"});
        wastedFragments += count(v, {"audit", "wasted_draws", "fragments"});
        genuine += count(v, {"raycast", "cross_check", "genuine"});
        hotspots += count(v, {"depth", "hotspot_count"});
        for (const Json &s : v["stages"]) {
            const std::string name = s["name"];
            if (!culled.count(name)) stageOrder.push_back(name);
            culled[name] += s["triangles_culled"].get<uint64_t>();
        }
        covered += v["zbuffer"]["covered_pixels"].get<uint64_t>();
        fragments += v["zbuffer"]["fragments"].get<uint64_t>();
        passes += v["zbuffer"]["depth_passes"].get<uint64_t>();
        if (v["total_ms"].is_number()) totalMs += v["total_ms"].get<double>();
    }
    Json totals;
    totals["views"] = views.size();
    Json culledJson = Json::object();
    for (const std::string &name : stageOrder) culledJson[name] = culled[name];
    totals["triangles_culled"] = culledJson;
    totals["covered_pixels"] = covered;
    totals["fragments"] = fragments;
    totals["depth_passes"] = passes;
    Json falseStages = Json::object();
    for (const std::string &name : stageOrder)
        if (falseByStage.count(name)) falseStages[name] = falseByStage[name];
    totals["false_cull_triangles"] = falseTris;
    totals["false_cull_pixels"] = falsePixels;
    totals["false_cull_triangles_by_stage"] = falseStages;
    totals["beyond_far_plane_pixels"] = beyondPixels;
    totals["wasted_triangles"] = wastedTris;
    totals["wasted_fragments"] = wastedFragments;
    totals["genuine_disagreements"] = genuine;
    totals["zfight_hotspots"] = hotspots;
    totals["total_ms"] = num(totalMs);
    return totals;
}

}  // namespace va
