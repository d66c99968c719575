// Views at sample positions covering a level: grid:N and clusters (analysis/level_samples.h).
#include "analysis/level_samples.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "analysis/level_map.h"
#include "analysis/load/level_views.h"
#include "analysis/load/route.h"

namespace va {

namespace {

// "90", "22.5": a yaw as a view name writes it.
std::string degreesText(double d) {
    char b[32];
    std::snprintf(b, sizeof b, "%g", d);
    return b;
}

// The views of one sample position: `dirs` horizontal directions, yaw 0 first.
void positionViews(const Scene &scene, const std::string &base, const std::string &origin, Vec3 eye, int dirs,
                   double eyeHeight, std::vector<ViewSpec> *out) {
    for (int d = 0; d < dirs; ++d) {
        const double yaw = 360.0 * d / dirs;
        ViewSpec v;
        v.name = dirs == 1 ? base : base + "-yaw" + degreesText(yaw);
        v.origin = origin;
        if (scene.bsp) {
            v.camera = quakeCamera(scene, eye, yaw);
        } else {
            // A player's lens where the scene has no game: 60 degrees, near a sixteenth of the eye
            // height, far past the whole level.
            CameraSpec &c = v.camera;
            c.eye = eye;
            c.target = eye + routeDirection(scene.up, yaw, 0);
            c.up = scene.up == 'z' ? Vec3{0, 0, 1} : scene.up == 'x' ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
            c.fovYDegrees = 60;
            c.nearZ = eyeHeight / 16;
            c.farZ = (scene.bounds.empty() ? 0 : length(scene.bounds.extent())) + eyeHeight * 2;
        }
        out->push_back(v);
    }
}

}  // namespace

std::vector<ViewSpec> gridViews(const Scene &scene, int n, int dirs, double eyeHeight, std::string *err) {
    std::vector<ViewSpec> views;
    if (eyeHeight <= 0) eyeHeight = levelEyeHeight(scene);
    FloorPlanSettings fs;
    fs.size = 1024;
    fs.eyeHeight = eyeHeight;
    FloorPlan plan;
    if (!renderFloorPlan(scene, fs, &plan, err)) return views;
    const int W = plan.width, H = plan.height;
    // A lattice point (its pixel) where a player can stand, and its eye.
    auto eyeAt = [&](int x, int y, Vec3 *eye) {
        const size_t p = size_t(y) * size_t(W) + size_t(x);
        if (!std::isfinite(plan.surface[p]) || plan.slope[p] < 0.7f) return false;
        *eye = floorWorldAt(plan, x, y, double(plan.surface[p]) + eyeHeight);
        if (scene.bsp) {
            const int32_t leaf = scene.bsp->leafAt(*eye);
            if (leaf < 0 || scene.bsp->leafs[size_t(leaf)].cluster < 0) return false;
        }
        return true;
    };
    auto lattice = [&](double spacing, std::vector<Vec3> *eyes) {
        size_t count = 0;
        for (int j = 0; (j + 0.5) * spacing < H; ++j)
            for (int i = 0; (i + 0.5) * spacing < W; ++i) {
                Vec3 e;
                if (!eyeAt(int((i + 0.5) * spacing), int((j + 0.5) * spacing), &e)) continue;
                ++count;
                if (eyes) eyes->push_back(e);
            }
        return count;
    };
    // The largest spacing (in pixels) with at least n points: bisection between one pixel and the
    // whole image (the count falls as the spacing grows, if not strictly).
    double lo = 1, hi = std::max(W, H) * 2.0;
    if (lattice(lo, nullptr) < size_t(n)) {
        *err = "--views grid:" + std::to_string(n) + ": '" + scene.path + "' has only " +
               std::to_string(lattice(lo, nullptr)) + " places to stand on its floor plan at " +
               std::to_string(W) + "x" + std::to_string(H) + " pixels; ask for fewer positions";
        return views;
    }
    for (int it = 0; it < 40; ++it) {
        const double mid = (lo + hi) * 0.5;
        (lattice(mid, nullptr) >= size_t(n) ? lo : hi) = mid;
    }
    std::vector<Vec3> eyes;
    lattice(lo, &eyes);
    const std::string origin = "grid:" + std::to_string(n) + ":" + std::to_string(dirs);
    for (int k = 0; k < n; ++k) {
        const size_t pick = size_t((unsigned __int128)k * eyes.size() / size_t(n));
        positionViews(scene, "grid" + std::to_string(k), origin, eyes[pick], dirs, eyeHeight, &views);
    }
    return views;
}

std::vector<ViewSpec> clusterViews(const Scene &scene, int dirs) {
    std::vector<ViewSpec> views;
    if (!scene.bsp) return views;
    const BspLevel &lv = *scene.bsp;
    // Each cluster's leafs, largest horizontal area first (ties: leaf order).
    std::vector<std::vector<uint32_t>> leafsOf(size_t(std::max(0, lv.clusterCount)));
    for (size_t i = 0; i < lv.leafs.size(); ++i) {
        const BspLeaf &l = lv.leafs[i];
        if (l.cluster >= 0 && l.cluster < lv.clusterCount && !l.bounds.empty() &&
            (lv.leafInTree.empty() || lv.leafInTree[i]))
            leafsOf[size_t(l.cluster)].push_back(uint32_t(i));
    }
    const std::string origin = "clusters:" + std::to_string(dirs);
    for (size_t c = 0; c < leafsOf.size(); ++c) {
        std::vector<uint32_t> &ls = leafsOf[c];
        auto area = [&](uint32_t i) {
            const Vec3 e = lv.leafs[i].bounds.extent();
            return e.x * e.y;
        };
        std::stable_sort(ls.begin(), ls.end(), [&](uint32_t a, uint32_t b) { return area(a) > area(b); });
        for (uint32_t i : ls) {
            const Aabb &b = lv.leafs[i].bounds;
            const Vec3 ctr = b.center();
            const Vec3 eye{ctr.x, ctr.y, b.lo.z + kQuakeFloorEye < b.hi.z ? b.lo.z + kQuakeFloorEye : ctr.z};
            const int32_t at = lv.leafAt(eye);
            if (at < 0 || lv.leafs[size_t(at)].cluster < 0) continue;
            positionViews(scene, "cluster" + std::to_string(c), origin, eye, dirs, kQuakeFloorEye, &views);
            break;
        }
    }
    return views;
}


bool levelSampleViews(const std::string &spec, const Scene &scene, std::vector<ViewSpec> *out, bool *handled,
                      std::string *err, double eyeHeight) {
    *handled = false;
    const bool grid = spec.rfind("grid:", 0) == 0, clusters = spec == "clusters" || spec.rfind("clusters:", 0) == 0;
    if (!grid && !clusters) return true;
    *handled = true;
    // The directions of grid:N:D and clusters:D, 1..8.
    auto directions = [&](const std::string &d, int *dirs) {
        if (d.empty()) return true;
        if (d.size() != 1 || d[0] < '1' || d[0] > '8') return false;
        *dirs = d[0] - '0';
        return true;
    };
    if (grid) {
        const std::string rest = spec.substr(5);
        const size_t colon = rest.find(':');
        const std::string ns = rest.substr(0, colon), ds = colon == std::string::npos ? "" : rest.substr(colon + 1);
        int dirs = 4;  // the four quarters of the horizon (Quake's 90-degree lens: a full panorama)
        if (ns.empty() || ns.size() > 6 || ns.find_first_not_of("0123456789") != std::string::npos ||
            std::stol(ns) < 1 || std::stol(ns) > 100000 || (colon != std::string::npos && ds.empty()) ||
            !directions(ds, &dirs)) {
            *err = "--views " + spec + ": expected grid:N or grid:N:D with N positions in 1..100000 and D directions "
                   "per position in 1..8 (default 4), e.g. grid:200 or grid:200:1";
            return false;
        }
        *out = gridViews(scene, int(std::stol(ns)), dirs, eyeHeight, err);
        return !out->empty();
    }
    if (!scene.bsp) {
        *err = "--views " + spec + ": needs a Quake 3 map (.bsp); '" + scene.path +
               "' is not one; use grid:N (positions over any level's floor plan)";
        return false;
    }
    if (clusters) {
        int dirs = 4;
        if (!directions(spec.size() > 9 ? spec.substr(9) : "", &dirs) || spec == "clusters:") {
            *err = "--views " + spec + ": expected clusters or clusters:D with D directions per position in 1..8 "
                   "(default 4), e.g. clusters:1";
            return false;
        }
        *out = clusterViews(scene, dirs);
        if (out->empty()) {
            *err = "--views " + spec + ": '" + scene.path + "' has no cluster with a leaf to stand in; use --views spawns";
            return false;
        }
        return true;
    }
    return true;
}

}  // namespace va
