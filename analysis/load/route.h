// Routes (docs/routes.md): a camera path through a level, given as keyframes in a route file
// (visaudit-route/1), sampled into views ("--views route:FILE[:N | :Ts]"). Each view is a frame of
// the route: named ROUTE@K, it carries its route, frame number and time (ViewSpec::route), so the
// report can draw the route's series and `check` can name the frame that broke a budget.
//
// Interpolation (fixed, documented; the same frames on every platform):
//   times     every keyframe has "time" (seconds, strictly increasing), or none has: then keyframe k
//             is at the route's length along the eye polyline up to it divided by "speed" (units per
//             second), or at k seconds without a speed.
//   eye       "linear": P_k + (P_k+1 - P_k) u with u = (t - t_k) / (t_k+1 - t_k); "catmull-rom"
//             (default): the cubic Hermite curve through every keyframe with Catmull-Rom tangents
//             m_k = (P_k+1 - P_k-1) / (t_k+1 - t_k-1) (one-sided at the two ends).
//   direction yaw and pitch, linear in u whatever the eye's interpolation (no overshoot past
//             straight up or down); yaw turns the shorter way between keyframes (a turn of more than
//             180 degrees needs a keyframe between). A keyframe's "target" sets its yaw and pitch.
//   at a keyframe's time a frame has exactly that keyframe's eye (no rounding from u = 0 or 1).
// Yaw is in degrees about the scene's up axis U, counter-clockwise seen from above, from the
// horizontal axis A of orbit:N's frame ((A, B, U) right-handed: z up -> A = +x, B = +y, as Quake's
// yaw; y up -> A = +z, B = +x; x up -> A = +y, B = +z); pitch is the elevation above the horizon
// (positive looks up), within (-90, 90).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "analysis/scene.h"
#include "common/limits.h"

namespace va {

constexpr const char *kRouteFormat = "visaudit-route/1";
// Most frames one route may be sampled into (as walk:N and orbit:N).
constexpr uint64_t kMaxRouteFrames = 100000;

enum class RouteInterpolation { linear, catmullRom };
const char *routeInterpolationName(RouteInterpolation i);  // "linear", "catmull-rom"

struct RouteKeyframe {
    Vec3 eye;
    double yaw = 0, pitch = 0;     // degrees (see above); from "target" when the keyframe gives one
    double time = 0;               // seconds on the route's timeline
    std::optional<Vec3> target;    // as the file gives it (the report repeats it)
};

// How a route is sampled: at its keyframes (route:FILE), at N frames evenly spread over its
// timeline, first and last keyframe included (route:FILE:N), or every T seconds from its start
// (route:FILE:Ts; the end is included when it falls on a step).
struct RouteSampling {
    enum class Kind { keyframes, count, every } kind = Kind::keyframes;
    uint64_t count = 0;
    double every = 0;
    std::string text;              // as given: "", "12", "0.5s"
};

struct Route {
    std::string name;              // "name" in the file, else the file's stem
    std::string file;              // as given on the command line
    char up = 'y';                 // the scene's up axis
    RouteInterpolation interpolation = RouteInterpolation::catmullRom;
    std::vector<RouteKeyframe> keyframes;  // at least 2, times strictly increasing
    bool timesGiven = false;       // the file gave the times (else from "speed" or one per second)
    double speed = 0;              // units per second when the file gives "speed" (0: none)
    CameraSpec camera;             // every frame's lens and size (eye and target are the frame's)
    DepthFormatSpec depthFormat = DepthFormat::f32;
    bool quakeCamera = false;      // the lens is Quake 3's default camera (a .bsp scene without "camera")
    RouteSampling sampling;
    double length = 0;             // along the keyframes' eye polyline, world units
    double duration() const { return keyframes.empty() ? 0 : keyframes.back().time - keyframes.front().time; }
};

// The camera at time t of the timeline (clamped to its ends): eye, yaw and pitch.
struct RoutePose {
    Vec3 eye;
    double yaw = 0, pitch = 0;
};
RoutePose routePoseAt(const Route &route, double t);
// The view direction of a yaw and pitch (degrees) about the up axis (unit length).
Vec3 routeDirection(char up, double yawDeg, double pitchDeg);

// What a route file may hold so that every frame has a camera (fuzz/fuzz_route_json.cpp). Keyframe
// eyes lie within +-2^26 per coordinate: a frame's eye, linear or Catmull-Rom, stays within 1.6
// times that (each tangent term is at most 4/27 of a difference of keyframe eyes, since a segment's
// duration is at most its tangent's span), where eye + direction rounds by at most 2^-26 per
// coordinate. Keyframe directions tilt at least kRouteMinTilt (|direction x up|, about 0.00006
// degrees from vertical) off the up axis, far above the camera model's 1e-9 after that rounding.
constexpr double kRouteMaxCoordinate = 67108864;  // 2^26
constexpr double kRouteMinTilt = 1e-6;

// The frames' times for the route's sampling (at most kMaxRouteFrames).
std::vector<double> routeFrameTimes(const Route &route);
// The route's views: ROUTE@K (K zero-padded to the width of the last frame's number), origin
// "route:FILE", the route's lens, each with its RouteStop.
std::vector<ViewSpec> routeViews(const Route &route);

// Reads a route file for `scene` (its up axis; a Quake 3 map's default camera). False + message
// "FILE:LINE:COL: path: what; fix" on bad input: too few keyframes, unknown keys, non-finite
// numbers, times that do not increase, a keyframe with both or neither of target and yaw, a view
// straight along the up axis.
bool loadRouteFile(const std::string &path, const Scene &scene, Route *out, std::string *err,
                   uint64_t maxJsonDepth = kDefaultMaxJsonDepth);

// Quake 3's run speed (g_speed, units per second): route:spawns moves at it.
constexpr double kQuakeRunSpeed = 320;
// route:spawns -- a Quake 3 map's spawn points (info_player_*, team_CTF_*; not the intermissions)
// as a route: straight lines at the run speed, from the first spawn point to the nearest one not
// yet visited, and so on; each keyframe faces its spawn point's angle. The lines may pass through
// walls (frames there see the void): for a real path, write a route file. False + message on a
// scene that is not a map or has fewer than 2 spawn points.
bool spawnRoute(const Scene &scene, Route *out, std::string *err);

// A --views value naming a route: "route:FILE", "route:FILE:N", "route:FILE:Ts", or
// "route:spawns[:N|:Ts]" on a Quake 3 map (unless a file named "spawns" exists). `handled` is
// false (and nothing else happens) for other values. On success *views holds the frames and
// *route the route.
bool routeViewsFromSpec(const std::string &spec, const Scene &scene, uint64_t maxJsonDepth,
                        std::vector<ViewSpec> *views, Route *route, bool *handled, std::string *err);

}  // namespace va
