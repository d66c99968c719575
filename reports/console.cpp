#include "reports/console.h"

#include <cinttypes>
#include <cmath>
#include <cstdio>

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

}  // namespace va
