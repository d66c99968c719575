// Level views: spawn points and seeded walks through a Quake 3 map's clusters.
#include "analysis/load/level_views.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "analysis/level_map.h"
#include "analysis/load/route.h"
#include "analysis/splitmix.h"

namespace va {
namespace {

bool parseVec3(const std::string &s, Vec3 *out) {
    std::istringstream in(s);
    double a, b, c;
    if (!(in >> a >> b >> c)) return false;
    *out = {a, b, c};
    return isFinite(*out);
}

bool parseNumber(const std::string &s, double *out) {
    char *end = nullptr;
    *out = std::strtod(s.c_str(), &end);
    return end != s.c_str() && std::isfinite(*out);
}

// Pitch and yaw of an entity in key order, as Quake 3 spawns them: "angles" sets (pitch, yaw, roll),
// "angle" sets (0, yaw, 0); the later key wins.
void entityAngles(const BspEntity &e, double *pitch, double *yaw) {
    for (const auto &[k, v] : e.keys) {
        if (k == "angles") {
            Vec3 a;
            if (parseVec3(v, &a)) *pitch = a.x, *yaw = a.y;
        } else if (k == "angle") {
            double y;
            if (parseNumber(v, &y)) *pitch = 0, *yaw = y;
        }
    }
}

bool isPlayerSpawn(const std::string &c) {
    return c == "info_player_deathmatch" || c == "info_player_start" || c == "team_CTF_redplayer" ||
           c == "team_CTF_blueplayer" || c == "team_CTF_redspawn" || c == "team_CTF_bluespawn";
}

}  // namespace

CameraSpec quakeCamera(const Scene &scene, Vec3 eye, double yawDeg, double pitchDeg) {
    CameraSpec c;
    const double yaw = yawDeg * kPi / 180, pitch = pitchDeg * kPi / 180;
    // Quake 3's AngleVectors: forward = (cos p cos y, cos p sin y, -sin p).
    const Vec3 fwd{std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw), -std::sin(pitch)};
    c.eye = eye;
    c.target = eye + fwd;
    c.up = {0, 0, 1};
    c.width = 1920;
    c.height = 1080;
    c.fovYDegrees = 2 * std::atan(std::tan(45 * kPi / 180) * c.height / c.width) * 180 / kPi;
    c.nearZ = 4;
    const double diag = scene.bounds.empty() ? 0 : length(scene.bounds.extent());
    c.farZ = std::max(std::ceil(diag), 64.0) + 16;
    // A map with a designed far plane (_farplanedist) is meant to be seen up to it: its PVS leaves
    // out what lies farther on purpose, and the game hides it (fog, a fog hull).
    if (scene.bsp && scene.bsp->farPlane.distance > c.nearZ) c.farZ = std::min(c.farZ, scene.bsp->farPlane.distance);
    return c;
}

std::vector<ViewSpec> spawnViews(const Scene &scene) {
    std::vector<ViewSpec> views, intermissions;
    if (!scene.bsp) return views;
    for (const BspEntity &e : scene.bsp->entities) {
        const std::string *cls = e.get("classname"), *org = e.get("origin");
        Vec3 o;
        if (!cls || !org || !parseVec3(*org, &o)) continue;
        double pitch = 0, yaw = 0;
        entityAngles(e, &pitch, &yaw);
        if (isPlayerSpawn(*cls)) {
            ViewSpec v;
            v.name = "spawn" + std::to_string(views.size());
            v.origin = "spawns: " + *cls;
            v.camera = quakeCamera(scene, o + Vec3{0, 0, kQuakeSpawnEye}, yaw, pitch);
            views.push_back(v);
        } else if (*cls == "info_player_intermission") {
            ViewSpec v;
            v.name = "intermission" + std::to_string(intermissions.size());
            v.origin = "spawns: " + *cls;
            v.camera = quakeCamera(scene, o, yaw, pitch);
            // Aimed at its target entity, when it names one that exists.
            if (const std::string *t = e.get("target"))
                for (const BspEntity &d : scene.bsp->entities) {
                    const std::string *tn = d.get("targetname"), *to = d.get("origin");
                    Vec3 p;
                    if (tn && *tn == *t && to && parseVec3(*to, &p) && !(p == o)) {
                        v.camera.target = p;
                        break;
                    }
                }
            intermissions.push_back(v);
        }
    }
    views.insert(views.end(), intermissions.begin(), intermissions.end());
    return views;
}

std::vector<ViewSpec> walkViews(const Scene &scene, int n, uint64_t seed) {
    std::vector<ViewSpec> views;
    if (!scene.bsp || n < 1) return views;
    const BspLevel &lv = *scene.bsp;
    std::vector<uint32_t> candidates;
    for (size_t i = 0; i < lv.leafs.size(); ++i)
        if (lv.leafs[i].cluster >= 0 && !lv.leafs[i].bounds.empty()) candidates.push_back(uint32_t(i));
    if (candidates.empty()) return views;
    SplitMix64 rng{seed};
    const std::string origin = "walk:" + std::to_string(n);
    for (int i = 0; i < n; ++i) {
        for (int attempt = 0; attempt < 64; ++attempt) {
            const BspLeaf &leaf = lv.leafs[candidates[rng.below(candidates.size())]];
            const double yaw = 360 * rng.unit();
            const Vec3 c = leaf.bounds.center();
            const double z = leaf.bounds.lo.z + kQuakeFloorEye < leaf.bounds.hi.z ? leaf.bounds.lo.z + kQuakeFloorEye : c.z;
            const Vec3 eye{c.x, c.y, z};
            const int32_t at = lv.leafAt(eye);
            if (at < 0 || lv.leafs[size_t(at)].cluster < 0) continue;
            ViewSpec v;
            v.name = "walk" + std::to_string(i);
            v.origin = origin;
            v.camera = quakeCamera(scene, eye, yaw);
            views.push_back(v);
            break;
        }
    }
    return views;
}

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

bool levelViews(const std::string &spec, const Scene &scene, std::vector<ViewSpec> *out, bool *handled,
                std::string *err, double eyeHeight) {
    *handled = false;
    const bool spawns = spec == "spawns", walk = spec.rfind("walk:", 0) == 0;
    const bool grid = spec.rfind("grid:", 0) == 0, clusters = spec == "clusters" || spec.rfind("clusters:", 0) == 0;
    if (!spawns && !walk && !grid && !clusters) return true;
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
               "' is not one; use a views file, or orbit:N";
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
    if (spawns) {
        *out = spawnViews(scene);
        if (out->empty()) {
            *err = "--views spawns: '" + scene.path +
                   "' has no spawn points (info_player_deathmatch, info_player_start, team_CTF_*, "
                   "info_player_intermission); use --views walk:N";
            return false;
        }
        return true;
    }
    // walk:N or walk:N:SEED, N in 1..100000.
    const std::string rest = spec.substr(5);
    const size_t colon = rest.find(':');
    const std::string ns = rest.substr(0, colon), ss = colon == std::string::npos ? "" : rest.substr(colon + 1);
    auto whole = [](const std::string &s, uint64_t *v) {
        if (s.empty() || s.size() > 19 || s.find_first_not_of("0123456789") != std::string::npos) return false;
        *v = std::stoull(s);
        return true;
    };
    uint64_t n = 0, seed = 1;
    if (!whole(ns, &n) || n < 1 || n > 100000 || (colon != std::string::npos && !whole(ss, &seed))) {
        *err = "--views " + spec + ": expected walk:N or walk:N:SEED with N in 1..100000 and SEED a whole number, "
               "e.g. walk:16 or walk:16:7";
        return false;
    }
    *out = walkViews(scene, int(n), seed);
    if (out->size() < n) {
        *err = "--views " + spec + ": '" + scene.path + "' has " +
               (out->empty() ? std::string("no leaf inside a cluster to stand in")
                             : "too few points inside clusters (found " + std::to_string(out->size()) + ")") +
               "; use --views spawns";
        return false;
    }
    return true;
}

}  // namespace va
