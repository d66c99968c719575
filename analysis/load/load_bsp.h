// Quake 3 maps: IBSP version 46 (.bsp, loose or inside a .pk3 zip archive as "pak.pk3:maps/x.bsp").
// World faces become triangles (front faces counter-clockwise; Quake 3 stores them clockwise),
// Bezier patches are tessellated at a fixed level, and the BSP tree, leafs, clusters, PVS and
// entities are kept in Scene::bsp for the cells stage and the level views. The format subset and
// every decision are in docs/quake3.md.
//
// Every offset, length, count and index is checked against the file before it is used; a bad file
// is refused with "FILE: lump 'faces': face 12 ...: what is wrong; a fix" (STYLE 9, 10), and
// nothing is allocated from a count the file's size does not bound.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "analysis/scene.h"

namespace va {

constexpr int kMaxPatchLevel = 64;

struct BspOptions {
    int patchLevel = 5;                  // segments per edge of each 3x3 Bezier patch (1..kMaxPatchLevel):
                                         //   2 * level^2 triangles per patch; --patch-level
    uint64_t maxTriangles = 50'000'000;  // refused before allocating when the faces would make more
    uint64_t maxFileBytes = 1ull << 30;  // a .bsp (or .pk3 member) larger than this is refused unread
    uint64_t maxBoxWalkSteps = 1ull << 27;  // nodes the brush models' box walks may visit, all together:
                                            //   a real map's visit well under a million; above, refused
};

// True for "x.bsp" and "x.pk3:maps/y.bsp" (extensions case-insensitive).
bool isBspPath(const std::string &path);

// Reads the bytes of a loose .bsp or of an archive member ("pak.pk3:maps/y.bsp").
bool readBspBytes(const std::string &path, uint64_t maxBytes, std::vector<uint8_t> *out, std::string *err);

// Parses an IBSP v46 file held in memory. `name` is used in messages and as the objects' mesh.
// Fills `out` with one source object per leaf that holds drawn faces ("leafN"), then one per brush
// model with drawn faces ("modelK", K >= 1), then "unleafed" for drawn world faces no leaf holds;
// fills `level` (its sourceCluster* arrays index those source objects in that order).
bool parseBsp(const uint8_t *data, size_t size, const std::string &name, const BspOptions &opt,
              SceneBuildInput *out, BspLevel *level, std::string *err);

// readBspBytes + parseBsp + buildScene; the scene's views are the map's spawn points
// (spawnViews, analysis/load/level_views.h) and its up axis is z.
bool loadBspScene(const std::string &path, const BspOptions &opt, const ChunkSettings &chunks, Scene *out,
                  std::string *err);

// The entity lump's text as a list of entities: { "key" "value" ... } blocks; `//` comments are
// skipped. False with "lump 'entities': line L: ..." on malformed text.
bool parseBspEntities(const std::string &text, std::vector<BspEntity> *out, std::string *err);

}  // namespace va
