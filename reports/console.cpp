#include "reports/console.h"

#include <cinttypes>
#include <cmath>
#include <cstdio>

#include "render/depth_format.h"

namespace va {

namespace {

std::string format(const char *fmt, auto... args) {
    const int n = std::snprintf(nullptr, 0, fmt, args...);
    std::string s(size_t(n > 0 ? n : 0), '\0');
    if (n > 0) std::snprintf(s.data(), s.size() + 1, fmt, args...);
    return s;
}

std::string ratio(double v) { return std::isfinite(v) ? format("%.2f", v) : std::string("n/a"); }
std::string millis(double v) { return std::isfinite(v) ? format("%.1f", v) : std::string("n/a"); }

}  // namespace

std::string funnelTable(const ViewResult &v) {
    const CameraSpec &c = v.spec.camera;
    std::string out = format("view '%s' %dx%d %s %s\n", v.spec.name.c_str(), c.width, c.height,
                             depthFormatName(v.spec.depthFormat).c_str(), c.orthographic ? "orthographic" : "perspective");
    // Columns: stage (10, left), status (7, left), three counts (11, right), ms (9, right).
    out += format("  %-10s %-7s %11s %11s %11s %9s\n", "stage", "status", "tris in", "culled", "out", "ms");
    for (const StageRecord &s : v.stages) {
        if (s.ran)
            out += format("  %-10s %-7s %11" PRIu64 " %11" PRIu64 " %11" PRIu64 " %9s\n", s.name.c_str(), "ran",
                          s.trianglesIn, s.trianglesCulled, s.trianglesOut, millis(s.ms).c_str());
        else
            out += format("  %-10s %-7s %s\n", s.name.c_str(), "skipped", s.reason.empty() ? "(no reason given)" : s.reason.c_str());
    }
    const ZBufferStats &z = v.zbuffer;
    out += format("  zbuffer: %" PRIu64 " covered pixels, overdraw %s, depth complexity %s (max %u)\n", z.coveredPixels,
                  ratio(z.overdraw).c_str(), ratio(z.depthComplexity).c_str(), unsigned(z.maxDepthComplexity));
    return out;
}


nlohmann::ordered_json sceneSummaryJson(const Scene &scene, const std::vector<ViewSpec> &views) {
    nlohmann::ordered_json j;
    j["scene"] = scene.path;
    j["triangles"] = scene.objectTriangles.size();
    j["source_triangles"] = scene.stats.sourceTriangles;
    j["degenerate_triangles"] = scene.stats.degenerateTriangles;
    j["non_finite_triangles"] = scene.stats.nonFiniteTriangles;
    j["faces_dropped"] = scene.stats.facesDropped;
    j["polygons_triangulated"] = scene.stats.polygonsTriangulated;
    j["objects"] = scene.sources.size();
    j["culling_objects"] = scene.objects.size();
    if (scene.bounds.empty())
        j["bounds"] = nullptr;
    else
        j["bounds"] = {{"min", {scene.bounds.lo.x, scene.bounds.lo.y, scene.bounds.lo.z}},
                       {"max", {scene.bounds.hi.x, scene.bounds.hi.y, scene.bounds.hi.z}}};
    j["up"] = std::string(1, scene.up);
    nlohmann::ordered_json mats = nlohmann::ordered_json::array();
    for (const Material &m : scene.materials)
        mats.push_back({{"name", m.name},
                        {"double_sided", m.doubleSided},
                        {"transparent", m.transparent()},
                        {"reflective", m.reflective > 0},
                        {"refractive", m.refractive()}});
    j["materials"] = mats;
    j["lights"] = scene.lights.size();
    nlohmann::ordered_json vs = nlohmann::ordered_json::array();
    for (const ViewSpec &v : views)
        vs.push_back({{"name", v.name},
                      {"width", v.camera.width},
                      {"height", v.camera.height},
                      {"projection", v.camera.orthographic ? "orthographic" : "perspective"},
                      {"eye", {v.camera.eye.x, v.camera.eye.y, v.camera.eye.z}},
                      {"depth_format", depthFormatName(v.depthFormat)}});
    j["views"] = vs;
    j["warnings"] = scene.warnings;
    return j;
}

std::string sceneSummaryTable(const Scene &scene, const std::vector<ViewSpec> &views) {
    std::string s;
    s += format("scene       %s\n", scene.path.c_str());
    s += format("triangles   %llu analysed of %llu in the source (%llu degenerate, %llu non-finite excluded)\n",
                (unsigned long long)scene.objectTriangles.size(), (unsigned long long)scene.stats.sourceTriangles,
                (unsigned long long)scene.stats.degenerateTriangles, (unsigned long long)scene.stats.nonFiniteTriangles);
    s += format("faces       %llu dropped by the loaders, %llu polygons triangulated\n",
                (unsigned long long)scene.stats.facesDropped, (unsigned long long)scene.stats.polygonsTriangulated);
    s += format("objects     %zu in the scene, %zu culling objects after chunking\n", scene.sources.size(),
                scene.objects.size());
    if (scene.bounds.empty())
        s += format("bounds      (empty)\n");
    else
        s += format("bounds      [%g, %g, %g] .. [%g, %g, %g]\n", scene.bounds.lo.x, scene.bounds.lo.y,
                    scene.bounds.lo.z, scene.bounds.hi.x, scene.bounds.hi.y, scene.bounds.hi.z);
    s += format("up axis     %c\n", scene.up);
    s += format("materials   %zu\n", scene.materials.size());
    for (const Material &m : scene.materials)
        s += format("  %-16s%s%s%s%s\n", m.name.c_str(), m.doubleSided ? " double-sided" : "",
                    m.transparent() ? " transparent" : "", m.reflective > 0 ? " reflective" : "",
                    m.refractive() ? " refractive" : "");
    s += format("lights      %zu\n", scene.lights.size());
    s += format("views       %zu\n", views.size());
    for (const ViewSpec &v : views)
        s += format("  %-16s%dx%d %s eye [%g, %g, %g] %s\n", v.name.c_str(), v.camera.width, v.camera.height,
                    v.camera.orthographic ? "ortho" : "persp", v.camera.eye.x, v.camera.eye.y, v.camera.eye.z,
                    depthFormatName(v.depthFormat).c_str());
    return s;
}

std::string zfightViewsTable(const std::string &scenePath, const AnalysisResult &result) {
    std::string s;
    s += format("z-fighting per view of %s (pixels whose two nearest surfaces fight; coplanar ones in brackets)\n",
                scenePath.c_str());
    for (const ViewResult &v : result.views) {
        if (!v.zfight.ran()) continue;
        const ZFightResult &z = *v.zfight;
        s += format("view '%s' %dx%d, near %g, far %g, its format %s: %llu hotspots\n", v.spec.name.c_str(),
                    v.camera.width, v.camera.height, v.camera.nearZ, v.camera.farZ,
                    depthFormatName(v.spec.depthFormat).c_str(), (unsigned long long)z.hotspotCount);
        for (const ZFightFormatStats &f : z.perFormat)
            s += format("  %-18s %2d bits %10llu fighting [%llu]%s\n", f.name.c_str(), f.bits,
                        (unsigned long long)f.fightingPixels, (unsigned long long)f.coplanarPixels,
                        z.recommended && *z.recommended == f.format ? "   <- recommended" : "");
        for (size_t k = 0; k < z.hotspots.size() && k < 3; ++k) {
            const ZFightHotspot &h = z.hotspots[k];
            s += format("  hotspot %u: %llu px at world (%.3g, %.3g, %.3g), '%s' vs '%s', gap %.3g\n", h.id,
                        (unsigned long long)h.area, h.centroid.x, h.centroid.y, h.centroid.z, h.objectA.c_str(),
                        h.objectB.c_str(), h.depthGap);
            s += format("    why: %s\n", h.why.c_str());
        }
        s += format("  %s\n", z.recommendation.c_str());
    }
    return s;
}

}  // namespace va
