// Level views: spawn points and seeded walks through a Quake 3 map's clusters.
#include "analysis/load/level_views.h"

#include <cmath>
#include <cstdlib>
#include <sstream>

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

bool levelViews(const std::string &spec, const Scene &scene, std::vector<ViewSpec> *out, bool *handled,
                std::string *err) {
    *handled = false;
    const bool spawns = spec == "spawns", walk = spec.rfind("walk:", 0) == 0;
    if (!spawns && !walk) return true;
    *handled = true;
    if (!scene.bsp) {
        *err = "--views " + spec + ": needs a Quake 3 map (.bsp); '" + scene.path +
               "' is not one; use a views file, or orbit:N";
        return false;
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
