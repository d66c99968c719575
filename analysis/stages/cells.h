// The cells stage for Quake 3 maps: the camera's leaf (a walk down the BSP tree), its cluster, and
// the PVS row of that cluster (docs/architecture.md, Stages: cells). Objects in clusters the camera's cluster
// cannot see are culled. Conservative by construction: an object stays when ANY cluster holding one
// of its faces is visible, objects in no cluster always stay, and a camera outside every cluster
// (in the void, or inside a wall) culls nothing — as Quake 3's renderer, which then draws everything.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "analysis/scene.h"
#include "render/camera.h"

namespace va {

struct CellsStats {
    int32_t cameraLeaf = -1;          // leaf holding the eye (-1: the map has no leafs)
    int32_t cameraCluster = -1;       // its cluster; -1: the camera is outside every cluster
    bool cameraInVoid = false;        // cameraCluster < 0: nothing was culled (conservative)
    uint64_t clustersTotal = 0;       // clusters in the map
    uint64_t clustersVisible = 0;     // clusters the camera's cluster sees (its PVS row's set bits,
                                      //   itself included); in the void: all. Lower is better culling
    uint64_t objectsIn = 0;           // culling objects entering the stage
    uint64_t objectsCulled = 0;       // every cluster of the object is invisible from the camera's
    uint64_t objectsNoCluster = 0;    // kept: in no cluster (e.g. a door outside every leaf)
    uint64_t trianglesIn = 0;         // triangles of the objects entering
    uint64_t trianglesCulled = 0;     // triangles of the culled objects
};

struct CellsResult {
    std::vector<uint32_t> visible;    // kept objects, ascending (submission order)
    CellsStats stats;
    std::string note;                 // what a reader should know: "camera in the void: ..." (or empty)
};

// Why the stage cannot run on this scene (nullptr: it can): no Quake 3 map, or a map compiled
// without a PVS.
const char *cellsSkipReason(const Scene &scene);

// The stage. Call only when cellsSkipReason(scene) is nullptr.
CellsResult cullCells(const Scene &scene, const Camera &cam);

}  // namespace va
