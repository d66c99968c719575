// Views for Quake 3 levels (docs/quake3.md, "Views"): the map's spawn points, and N points sampled
// inside its clusters ("walk:N"), both at a player's eye height, deterministic.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "analysis/scene.h"

namespace va {

// Quake 3's player geometry (game code, bg_public.h and g_client.c):
constexpr double kQuakeSpawnLift = 9;         // a player spawns 9 units above the spawn point's origin
constexpr double kQuakeViewHeight = 26;       // DEFAULT_VIEWHEIGHT: the eye, above the player's origin
constexpr double kQuakeOriginAboveFeet = 24;  // MINS_Z = -24: the player's origin, above its feet
// Spawn point origin -> eye: 9 + 26 = 35 units. Floor -> eye: 24 + 26 = 50 units.
constexpr double kQuakeSpawnEye = kQuakeSpawnLift + kQuakeViewHeight;
constexpr double kQuakeFloorEye = kQuakeOriginAboveFeet + kQuakeViewHeight;

// The camera Quake 3 uses by default, looking from `eye` along yaw (degrees about +z, 0 = +x) and
// pitch (degrees, positive looks down): horizontal fov 90 (cg_fov) at 1920x1080, so
// fov_y = 2 atan(tan 45 deg * 1080/1920) = 58.7155 deg; near 4 (r_znear); far = the map's bounding
// box diagonal rounded up plus 16, so nothing in the map is clipped by far -- or the map's designed
// far plane (BspFarPlane, "_farplanedist") when it has one nearer than that.
CameraSpec quakeCamera(const Scene &scene, Vec3 eye, double yawDeg, double pitchDeg = 0);

// Views at the map's spawn points, in entity order: info_player_deathmatch, info_player_start,
// team_CTF_redplayer/blueplayer/redspawn/bluespawn ("spawnK": eye 35 units above the origin,
// facing "angle"/"angles"), then info_player_intermission ("intermissionK": eye at the origin,
// aimed at its "target" entity when it has one, as the engine does). Empty for non-Quake scenes.
std::vector<ViewSpec> spawnViews(const Scene &scene);

// N views "walk0".."walkN-1" inside the map's clusters: each picks a leaf with a cluster (uniformly
// among such leafs, seeded splitmix64), stands at its bounding box's center in x and y, 50 units
// (eye height) above its floor (or at its center when it is lower than that), looks along a seeded
// yaw; a point whose leaf (walking the BSP) has no cluster is redrawn (at most 64 draws per view).
// Identical for the same scene, n and seed on every platform. Empty without a Quake 3 map.
std::vector<ViewSpec> walkViews(const Scene &scene, int n, uint64_t seed = 1);

// Parses a --views value naming level views: "spawns", "walk:N" or "walk:N:SEED". Returns false
// with a message when the value is malformed or the scene cannot give such views (not a map, no
// spawn points, no clusters). `handled` is false (and nothing else happens) for other values.
bool levelViews(const std::string &spec, const Scene &scene, std::vector<ViewSpec> *out, bool *handled,
                std::string *err);

}  // namespace va
