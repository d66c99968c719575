// Routes: route files (visaudit-route/1), their interpolation and their frames (analysis/load/route.h;
// docs/routes.md). Every error names the file, the line:column, the JSON path and a fix.
#include "analysis/load/route.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "analysis/load/json_reader.h"
#include "analysis/load/level_views.h"

namespace va {

using json::Json;
using json::Path;
using load::Reader;

const char *routeInterpolationName(RouteInterpolation i) {
    return i == RouteInterpolation::linear ? "linear" : "catmull-rom";
}

namespace {

// The horizontal frame of yaw: (A, B, U) right-handed, as orbit:N's (analysis/load/load_scene.cpp).
void yawAxes(char up, Vec3 *A, Vec3 *B, Vec3 *U) {
    *U = load::upVector(up);
    *A = up == 'z' ? Vec3{1, 0, 0} : up == 'x' ? Vec3{0, 1, 0} : Vec3{0, 0, 1};
    *B = cross(*U, *A);
}

constexpr double kDegrees = 180 / kPi;

// A number as a message writes it: the shortest of %.15g and %.17g that reads back the same.
std::string numberText(double v) {
    char b[40];
    std::snprintf(b, sizeof b, "%.15g", v);
    if (std::strtod(b, nullptr) != v) std::snprintf(b, sizeof b, "%.17g", v);
    return b;
}

// Yaw and pitch (degrees) of a direction; false when it is along the up axis (no yaw).
bool yawPitchOf(char up, Vec3 d, double *yaw, double *pitch) {
    Vec3 A, B, U;
    yawAxes(up, &A, &B, &U);
    const double a = dot(d, A), b = dot(d, B), u = dot(d, U);
    const double h = std::hypot(a, b);
    if (!(h > 0)) return false;
    *yaw = std::atan2(b, a) * kDegrees;
    *pitch = std::atan2(u, h) * kDegrees;
    return std::fabs(*pitch) < 90;
}

// The keyframes' yaws unwrapped so that each is within 180 degrees of the one before: linear
// interpolation then turns the shorter way.
std::vector<double> unwrappedYaws(const Route &r) {
    std::vector<double> y(r.keyframes.size());
    for (size_t k = 0; k < y.size(); ++k)
        y[k] = k == 0 ? r.keyframes[0].yaw
                      : y[k - 1] + std::remainder(r.keyframes[k].yaw - r.keyframes[k - 1].yaw, 360.0);
    return y;
}

// Catmull-Rom tangent at keyframe k (one-sided at the ends), units per second.
Vec3 tangent(const Route &r, size_t k) {
    const std::vector<RouteKeyframe> &f = r.keyframes;
    const size_t a = k == 0 ? 0 : k - 1, b = k + 1 == f.size() ? k : k + 1;
    return (f[b].eye - f[a].eye) / (f[b].time - f[a].time);
}

}  // namespace

Vec3 routeDirection(char up, double yawDeg, double pitchDeg) {
    Vec3 A, B, U;
    yawAxes(up, &A, &B, &U);
    const double y = yawDeg / kDegrees, p = pitchDeg / kDegrees;
    return (A * std::cos(y) + B * std::sin(y)) * std::cos(p) + U * std::sin(p);
}

RoutePose routePoseAt(const Route &r, double t) {
    const std::vector<RouteKeyframe> &f = r.keyframes;
    const std::vector<double> yaws = unwrappedYaws(r);
    // The segment [t_k, t_k+1) holding t; at or past the last keyframe, the last keyframe.
    const auto after = std::upper_bound(f.begin(), f.end(), t, [](double x, const RouteKeyframe &k) { return x < k.time; });
    if (after == f.begin()) return {f.front().eye, yaws.front(), f.front().pitch};
    const size_t k = size_t(after - f.begin()) - 1;
    if (k + 1 == f.size() || t == f[k].time) return {f[k].eye, yaws[k], f[k].pitch};
    const double h = f[k + 1].time - f[k].time, u = (t - f[k].time) / h;
    RoutePose p;
    if (r.interpolation == RouteInterpolation::linear) {
        p.eye = f[k].eye + (f[k + 1].eye - f[k].eye) * u;
    } else {
        // Cubic Hermite basis on u in [0, 1].
        const double u2 = u * u, u3 = u2 * u;
        const double h00 = 2 * u3 - 3 * u2 + 1, h10 = u3 - 2 * u2 + u, h01 = -2 * u3 + 3 * u2, h11 = u3 - u2;
        p.eye = f[k].eye * h00 + tangent(r, k) * (h10 * h) + f[k + 1].eye * h01 + tangent(r, k + 1) * (h11 * h);
    }
    p.yaw = yaws[k] + (yaws[k + 1] - yaws[k]) * u;
    p.pitch = f[k].pitch + (f[k + 1].pitch - f[k].pitch) * u;
    return p;
}

std::vector<double> routeFrameTimes(const Route &r) {
    std::vector<double> times;
    if (r.keyframes.empty()) return times;
    const double t0 = r.keyframes.front().time, t1 = r.keyframes.back().time, d = t1 - t0;
    switch (r.sampling.kind) {
    case RouteSampling::Kind::keyframes:
        for (const RouteKeyframe &k : r.keyframes) times.push_back(k.time);
        break;
    case RouteSampling::Kind::count: {
        const uint64_t n = std::min(r.sampling.count, kMaxRouteFrames);
        for (uint64_t i = 0; i < n; ++i)
            times.push_back(i + 1 == n && n > 1 ? t1 : t0 + d * double(i) / double(std::max<uint64_t>(n - 1, 1)));
        break;
    }
    case RouteSampling::Kind::every: {
        // Steps of T from t0 while t0 + i T <= t1. The duration and T carry rounding from their
        // decimal text (each time and T rounded once, the difference and the quotient once more):
        // |q - q*| <= gamma(3) q + 2u (|t0| + |t1|) / T, so a quotient within that of a whole
        // number counts as that number and "every 0.1 s over 0.3 s" gives 4 frames, not 3.
        const double T = r.sampling.every, q = d / T;
        const double slack = gamma(3) * q + 2 * kDoubleEps * (std::fabs(t0) + std::fabs(t1)) / T;
        const uint64_t n = uint64_t(std::floor(q + slack)) + 1;
        for (uint64_t i = 0; i < std::min(n, kMaxRouteFrames); ++i) times.push_back(std::min(t1, t0 + double(i) * T));
        break;
    }
    }
    return times;
}

std::vector<ViewSpec> routeViews(const Route &r) {
    const std::vector<double> times = routeFrameTimes(r);
    std::vector<ViewSpec> views;
    const size_t width = std::to_string(times.empty() ? 0 : times.size() - 1).size();
    const Vec3 U = load::upVector(r.up);
    for (size_t i = 0; i < times.size(); ++i) {
        const RoutePose p = routePoseAt(r, times[i]);
        ViewSpec v;
        std::string k = std::to_string(i);
        v.name = r.name + "@" + std::string(width - k.size(), '0') + k;
        v.origin = "route:" + r.file;
        v.camera = r.camera;
        v.camera.eye = p.eye;
        v.camera.target = p.eye + routeDirection(r.up, p.yaw, p.pitch);
        v.camera.up = U;
        v.depthFormat = r.depthFormat;
        v.route = {r.name, uint32_t(i), times[i]};
        views.push_back(v);
    }
    return views;
}

bool loadRouteFile(const std::string &path, const Scene &scene, Route *out, std::string *err, uint64_t maxJsonDepth) {
    json::Doc doc;
    if (!json::parseFile(path, &doc, err, maxJsonDepth)) return false;
    Reader r{doc, {}};
    auto failed = [&] {
        *err = r.err;
        return false;
    };
    const Json &root = doc.root;
    const Path top;
    if (!root.is_object()) {
        *err = json::where(doc, top) + ": expected a JSON object {\"format\": \"" + kRouteFormat +
               "\", \"keyframes\": [...]}, got " + json::typeName(root);
        return false;
    }
    if (!r.checkKeys(root, top, {"format", "name", "interpolation", "speed", "camera", "keyframes"})) return failed();
    if (!root.contains("format")) {
        *err = json::where(doc, top) + ": missing \"format\": add \"format\": \"" + kRouteFormat + "\"";
        return false;
    }
    std::string format;
    if (!r.string(root["format"], top / "format", &format)) return failed();
    if (format != kRouteFormat) {
        r.fail(top / "format", "unsupported format \"" + format + "\"; this visaudit reads \"" + kRouteFormat + "\"");
        return failed();
    }
    Route route;
    route.file = path;
    route.up = scene.up;
    route.name = std::filesystem::path(path).stem().string();
    if (root.contains("name") && !r.string(root["name"], top / "name", &route.name)) return failed();
    if (route.name.empty()) {
        r.fail(top / "name", "a route name cannot be empty; it names the route's views (NAME@0, NAME@1, ...)");
        return failed();
    }
    if (root.contains("interpolation")) {
        std::string i;
        if (!r.string(root["interpolation"], top / "interpolation", &i)) return failed();
        if (i == "linear") route.interpolation = RouteInterpolation::linear;
        else if (i == "catmull-rom") route.interpolation = RouteInterpolation::catmullRom;
        else {
            r.fail(top / "interpolation", "unknown interpolation \"" + i + "\"; use \"linear\" or \"catmull-rom\"");
            return failed();
        }
    }
    if (root.contains("speed")) {
        if (!r.number(root["speed"], top / "speed", &route.speed)) return failed();
        if (!(route.speed > 0)) {
            r.fail(top / "speed", "must be > 0 (world units per second)");
            return failed();
        }
    }

    // The lens: Quake 3's default camera for a map, else a views file's defaults; "camera" overrides.
    if (scene.bsp) {
        route.camera = quakeCamera(scene, {0, 0, 0}, 0);
        route.quakeCamera = true;
    }
    if (root.contains("camera")) {
        const Path cp = top / "camera";
        const Json &c = root["camera"];
        if (!r.object(c, cp) || !r.checkKeys(c, cp, {"fov_y", "near", "far", "width", "height", "depth_format"}))
            return failed();
        route.quakeCamera = false;
        if (c.contains("fov_y") && !r.number(c["fov_y"], cp / "fov_y", &route.camera.fovYDegrees)) return failed();
        if (c.contains("near") && !r.number(c["near"], cp / "near", &route.camera.nearZ)) return failed();
        if (c.contains("far") && !r.number(c["far"], cp / "far", &route.camera.farZ)) return failed();
        if (c.contains("width") && !r.size(c["width"], cp / "width", &route.camera.width)) return failed();
        if (c.contains("height") && !r.size(c["height"], cp / "height", &route.camera.height)) return failed();
        if (c.contains("depth_format")) {
            std::string f, e;
            if (!r.string(c["depth_format"], cp / "depth_format", &f)) return failed();
            if (!parseDepthFormat(f, &route.depthFormat, &e)) {
                r.fail(cp / "depth_format", e);
                return failed();
            }
        }
        // The lens on its own (eye and target are each frame's): fov, near, far.
        CameraSpec probe = route.camera;
        probe.eye = {0, 0, 0};
        probe.target = routeDirection(route.up, 0, 0);
        probe.up = load::upVector(route.up);
        Camera cam;
        std::string e;
        if (!makeCamera(probe, &cam, &e)) {
            Path at = cp;
            if (e.size() > 2 && e[0] == '"') {
                const std::string k = e.substr(1, e.find('"', 1) - 1);
                if (c.contains(k)) at = cp / k;
            }
            *err = json::where(doc, at) + ": " + json::pathString(cp) + ": " + e;
            return false;
        }
    }

    // Keyframes.
    const Path kp = top / "keyframes";
    if (!root.contains("keyframes")) {
        *err = json::where(doc, top) + ": missing \"keyframes\": a route is {\"keyframes\": [{\"eye\": [...], "
               "\"target\": [...]}, ...]} with at least 2 keyframes";
        return false;
    }
    const Json &ks = root["keyframes"];
    if (!ks.is_array()) {
        r.fail(kp, "expected an array of keyframes, got " + json::typeName(ks));
        return failed();
    }
    if (ks.size() < 2) {
        r.fail(kp, "a route needs at least 2 keyframes, got " + std::to_string(ks.size()) +
                       "; add the point where the route ends");
        return failed();
    }
    size_t timed = 0;
    for (size_t i = 0; i < ks.size(); ++i) {
        const Path p = kp / i;
        const Json &j = ks[i];
        if (!r.object(j, p) || !r.checkKeys(j, p, {"eye", "target", "yaw", "pitch", "time"})) return failed();
        RouteKeyframe k;
        if (!j.contains("eye")) {
            r.fail(p, "missing \"eye\": give the camera position, e.g. \"eye\": [0, 1.7, 8]");
            return failed();
        }
        if (!r.vec3(j["eye"], p / "eye", &k.eye)) return failed();
        if (!(maxAbs(k.eye) <= kRouteMaxCoordinate)) {
            r.fail(p / "eye", "has a coordinate beyond +-" + numberText(kRouteMaxCoordinate) +
                                  ", where a frame's camera cannot resolve its view direction; move the route "
                                  "(and its scene) nearer the origin");
            return failed();
        }
        const bool hasTarget = j.contains("target"), hasYaw = j.contains("yaw");
        if (hasTarget && (hasYaw || j.contains("pitch"))) {
            r.fail(p / (hasYaw ? "yaw" : "pitch"), "give either \"target\" or \"yaw\" and \"pitch\", not both", true);
            return failed();
        }
        if (!hasTarget && !hasYaw) {
            r.fail(p, "missing \"target\" (a point to look at) or \"yaw\" (degrees about the up axis; \"pitch\" optional)");
            return failed();
        }
        if (hasTarget) {
            Vec3 t;
            if (!r.vec3(j["target"], p / "target", &t)) return failed();
            if (t == k.eye) {
                r.fail(p / "target", "equals \"eye\"; the keyframe has no direction");
                return failed();
            }
            if (!yawPitchOf(route.up, t - k.eye, &k.yaw, &k.pitch)) {
                r.fail(p / "target", std::string("looks straight along the up axis (") + route.up +
                                         "); no yaw follows from it: move the target sideways");
                return failed();
            }
            k.target = t;
        } else {
            if (!r.number(j["yaw"], p / "yaw", &k.yaw)) return failed();
            if (j.contains("pitch") && !r.number(j["pitch"], p / "pitch", &k.pitch)) return failed();
            if (!(std::fabs(k.pitch) < 90)) {
                r.fail(p / "pitch", "must be between -90 and 90 degrees (exclusive): the elevation above the horizon");
                return failed();
            }
        }
        // A camera can look this way at every frame: a frame's pitch lies between its keyframes'
        // and its eye within kRouteMaxCoordinate * 1.6 (route.h), where target - eye is off the
        // direction by at most 2^-26 per coordinate, so a tilt off the up axis of kRouteMinTilt
        // at the keyframes keeps the camera model's 1e-9 (makeCamera's test) at every frame.
        {
            const Vec3 d = routeDirection(route.up, k.yaw, k.pitch);
            if (!(length(cross(d, load::upVector(route.up))) > kRouteMinTilt)) {
                r.fail(p / (hasTarget ? "target" : "pitch"),
                       "looks too nearly along the up axis for a camera; tilt it less (pitch " + numberText(k.pitch) + ")");
                return failed();
            }
        }
        if (j.contains("time")) {
            if (!r.number(j["time"], p / "time", &k.time)) return failed();
            ++timed;
        }
        route.keyframes.push_back(k);
    }
    // Times: on every keyframe, or on none (then from "speed", or one second apart).
    if (timed != 0 && timed != ks.size()) {
        for (size_t i = 0; i < ks.size(); ++i)
            if (!ks[i].contains("time")) {
                r.fail(kp / i, "missing \"time\": give a time on every keyframe or on none (then they are one "
                               "second apart, or spaced by \"speed\")");
                return failed();
            }
    }
    route.timesGiven = timed == ks.size();
    if (route.timesGiven && route.speed > 0) {
        r.fail(top / "speed", "the keyframes give their times; leave \"speed\" out (or the times)", true);
        return failed();
    }
    for (size_t i = 1; i < route.keyframes.size(); ++i)
        route.length += length(route.keyframes[i].eye - route.keyframes[i - 1].eye);
    if (route.timesGiven) {
        for (size_t i = 1; i < route.keyframes.size(); ++i)
            if (!(route.keyframes[i].time > route.keyframes[i - 1].time)) {
                r.fail(kp / i / "time", numberText(route.keyframes[i].time) + " is not after " +
                                            json::pathString(kp / (i - 1) / "time") + " (" +
                                            numberText(route.keyframes[i - 1].time) + "); times must increase");
                return failed();
            }
    } else if (route.speed > 0) {
        double t = 0;
        for (size_t i = 0; i < route.keyframes.size(); ++i) {
            if (i > 0) {
                const double step = length(route.keyframes[i].eye - route.keyframes[i - 1].eye) / route.speed;
                if (!(step > 0)) {
                    r.fail(kp / i / "eye", "is where " + json::pathString(kp / (i - 1)) +
                                               " is: with \"speed\" the route would stand still; give times instead");
                    return failed();
                }
                t += step;
            }
            route.keyframes[i].time = t;
        }
    } else {
        for (size_t i = 0; i < route.keyframes.size(); ++i) route.keyframes[i].time = double(i);
    }
    if (!std::isfinite(route.duration())) {
        r.fail(kp, "the route's duration overflows a double; give smaller times");
        return failed();
    }
    *out = std::move(route);
    return true;
}

bool spawnRoute(const Scene &scene, Route *out, std::string *err) {
    if (!scene.bsp) {
        *err = "'" + scene.path + "' is not a Quake 3 map; route:spawns walks a map's spawn points (write a route file instead)";
        return false;
    }
    std::vector<ViewSpec> spawns;
    for (const ViewSpec &v : spawnViews(scene))
        if (v.name.rfind("spawn", 0) == 0) spawns.push_back(v);
    if (spawns.size() < 2) {
        *err = "'" + scene.path + "' has " + std::to_string(spawns.size()) +
               " spawn points; a route needs at least 2 (write a route file instead)";
        return false;
    }
    // Nearest neighbour from the first spawn point (ties: entity order): fewer walls crossed than in
    // entity order, deterministic.
    std::vector<size_t> order = {0};
    std::vector<bool> used(spawns.size(), false);
    used[0] = true;
    for (size_t step = 1; step < spawns.size(); ++step) {
        const Vec3 at = spawns[order.back()].camera.eye;
        size_t best = 0;
        double bestD = INFINITY;
        for (size_t k = 0; k < spawns.size(); ++k)
            if (!used[k] && length(spawns[k].camera.eye - at) < bestD) bestD = length(spawns[k].camera.eye - at), best = k;
        used[best] = true;
        order.push_back(best);
    }
    Route r;
    r.name = "spawns";
    r.file = "spawns";
    r.up = scene.up;
    r.interpolation = RouteInterpolation::linear;
    r.speed = kQuakeRunSpeed;
    r.camera = quakeCamera(scene, {0, 0, 0}, 0);
    r.quakeCamera = true;
    double t = 0;
    for (size_t i = 0; i < order.size(); ++i) {
        const ViewSpec &v = spawns[order[i]];
        RouteKeyframe k;
        k.eye = v.camera.eye;
        if (!yawPitchOf(scene.up, v.camera.target - v.camera.eye, &k.yaw, &k.pitch)) k.yaw = 0, k.pitch = 0;
        if (i > 0) {
            const double step = length(k.eye - r.keyframes.back().eye) / r.speed;
            if (!(step > 0)) continue;  // two spawn points at one place: one keyframe
            t += step;
        }
        k.time = t;
        r.length += i > 0 ? length(k.eye - r.keyframes.back().eye) : 0;
        r.keyframes.push_back(k);
    }
    if (r.keyframes.size() < 2) {
        *err = "'" + scene.path + "' has its spawn points at one place; write a route file instead";
        return false;
    }
    *out = std::move(r);
    return true;
}

namespace {

// "12" -> count 12; "0.5s" -> every 0.5 s. False when the text is neither.
bool parseSampling(const std::string &s, RouteSampling *out) {
    if (s.empty()) return false;
    if (s.find_first_not_of("0123456789") == std::string::npos) {
        if (s.size() > 12) return false;
        out->kind = RouteSampling::Kind::count;
        out->count = std::stoull(s);
        out->text = s;
        return true;
    }
    if (s.back() == 's' && s.size() > 1 && s.find_first_not_of("0123456789.") == s.size() - 1 &&
        std::count(s.begin(), s.end(), '.') <= 1 && s[0] != '.' && s[s.size() - 2] != '.') {
        out->kind = RouteSampling::Kind::every;
        out->every = std::strtod(s.c_str(), nullptr);
        out->text = s;
        return true;
    }
    return false;
}

}  // namespace

bool routeViewsFromSpec(const std::string &spec, const Scene &scene, uint64_t maxJsonDepth,
                        std::vector<ViewSpec> *views, Route *route, bool *handled, std::string *err) {
    *handled = false;
    if (spec.rfind("route:", 0) != 0) return true;
    *handled = true;
    std::string file = spec.substr(6);
    RouteSampling sampling;
    const size_t colon = file.rfind(':');
    if (colon != std::string::npos && parseSampling(file.substr(colon + 1), &sampling)) file = file.substr(0, colon);
    const std::string usage = "; use route:FILE (a frame per keyframe), route:FILE:N (N frames) or route:FILE:Ts "
                              "(a frame every T seconds), e.g. route:walk.route.json:60";
    if (file.empty()) {
        *err = "--views " + spec + ": no route file given" + usage;
        return false;
    }
    if (sampling.kind == RouteSampling::Kind::count && (sampling.count < 1 || sampling.count > kMaxRouteFrames)) {
        *err = "--views " + spec + ": N must be a whole number from 1 to " + std::to_string(kMaxRouteFrames) + usage;
        return false;
    }
    if (sampling.kind == RouteSampling::Kind::every && !(sampling.every > 0 && std::isfinite(sampling.every))) {
        *err = "--views " + spec + ": T must be a number of seconds above 0" + usage;
        return false;
    }
    Route r;
    if (file == "spawns" && !std::filesystem::exists(file)) {
        if (!spawnRoute(scene, &r, err)) {
            *err = "--views " + spec + ": " + *err;
            return false;
        }
    } else if (!loadRouteFile(file, scene, &r, err, maxJsonDepth)) {
        return false;
    }
    r.sampling = sampling;
    if (sampling.kind == RouteSampling::Kind::every) {
        const double frames = std::floor(r.duration() / sampling.every) + 1;
        if (frames > double(kMaxRouteFrames)) {
            *err = "--views " + spec + ": a frame every " + sampling.text + " over the route's " +
                   numberText(r.duration()) + " s makes " + numberText(frames) + " frames, more than " +
                   std::to_string(kMaxRouteFrames) + "; sample a longer step, or give N frames (route:FILE:N)";
            return false;
        }
    }
    *views = routeViews(r);
    *route = std::move(r);
    return true;
}

}  // namespace va
