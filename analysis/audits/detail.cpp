// The detail audit: triangles drawn per visible pixel, per object (docs/coarse-stages.md).
#include "analysis/audits/detail.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/id_runs.h"
#include "render/stopwatch.h"

namespace va {

double projectedDiameterPx(const Camera &cam, const Sphere &s) {
    if (cam.orthographic) return s.radius * cam.sy * cam.height;
    const double dist = length(s.center - cam.eye);
    if (!(dist > s.radius)) return std::numeric_limits<double>::infinity();
    return cam.height * cam.sy * s.radius / std::sqrt((dist - s.radius) * (dist + s.radius));
}

DetailResult auditDetail(const Scene &scene, const Camera &cam, const std::vector<uint32_t> &drawnTriangles,
                         const std::vector<uint32_t> &fragmentsPerSource, const std::vector<uint32_t> &visibleIds,
                         const DetailSettings &settings) {
    const Stopwatch t0;
    DetailResult r;
    const size_t n = scene.objects.size();
    std::vector<DetailObject> per(n);
    std::vector<uint8_t> drawn(n, 0);
    for (uint32_t t : drawnTriangles) {
        const uint32_t o = scene.triangleObject[t];
        if (o == kExcludedTriangle) continue;
        DetailObject &d = per[o];
        drawn[o] = 1;
        ++d.trianglesDrawn;
        const uint32_t f = t < fragmentsPerSource.size() ? fragmentsPerSource[t] : 0;
        d.fragments += f;
        if (f == 0) ++d.trianglesNoCenter;
    }
    // Visible pixels per object, a run of equal ids at a time (common/id_runs.h).
    forEachIdRun(visibleIds, [&](uint32_t id, uint64_t count) {
        if (id == 0) return;
        const uint32_t o = scene.triangleObject[id - 1];
        if (o == kExcludedTriangle) return;
        per[o].pixelsVisible += count;
        r.pixelsVisible += count;
    });
    for (uint32_t o = 0; o < n; ++o) {
        if (!drawn[o]) continue;
        DetailObject &d = per[o];
        d.object = o;
        d.name = scene.objects[o].name;
        d.projectedPixels = projectedDiameterPx(cam, scene.objects[o].sphere);
        d.tooSmall = d.projectedPixels < settings.minPixels;
        d.overDetailed = double(d.trianglesDrawn) > double(d.pixelsVisible) * settings.trianglesPerPixel;
        if (d.tooSmall) {
            d.trianglesSaved = d.trianglesDrawn;  // a draw distance: not drawn at all
        } else if (d.overDetailed) {
            const uint64_t keep =
                std::max<uint64_t>((d.pixelsVisible + kLodPixelsPerTriangle - 1) / kLodPixelsPerTriangle, kLodTrianglesFloor);
            d.trianglesSaved = d.trianglesDrawn > keep ? d.trianglesDrawn - keep : 0;
        }
        ++r.objectsDrawn;
        r.trianglesDrawn += d.trianglesDrawn;
        r.trianglesNoCenter += d.trianglesNoCenter;
        r.objectsTooSmall += d.tooSmall;
        r.objectsOverDetailed += d.overDetailed;
        if (d.tooSmall || d.overDetailed) {
            r.trianglesSavable += d.trianglesSaved;
            r.flagged.push_back(d);
        }
    }
    r.trianglesPerVisiblePixel = r.pixelsVisible ? double(r.trianglesDrawn) / double(r.pixelsVisible) : 0;
    std::sort(r.flagged.begin(), r.flagged.end(), [](const DetailObject &a, const DetailObject &b) {
        return a.trianglesSaved > b.trianglesSaved || (a.trianglesSaved == b.trianglesSaved && a.object < b.object);
    });
    if (r.flagged.size() > settings.listed) r.flagged.resize(settings.listed);
    r.ms = t0.ms();
    return r;
}

}  // namespace va
