// The grid stage: the coarse stage of scenes without cells (docs/architecture.md, Stages: grid;
// docs/coarse-stages.md). A uniform grid over the scene's bounds; each culling object is registered
// in every grid cell its AABB overlaps. Per view, grid cells outside the frustum's bounding box are
// skipped at no cost, the others are tested box-against-planes (conservative), and an object is
// culled when every cell it is registered in is outside.
#pragma once

#include <cstdint>
#include <vector>

#include "analysis/scene.h"
#include "render/camera.h"

namespace va {

struct GridSettings {
    // Edge of the cubic grid cells in world units; 0: automatic, about one cell per
    // kObjectsPerCell objects: edge = (volume / max(1, objects / kObjectsPerCell))^(1/3) over the
    // scene bounds' non-flat axes (area and square root for a flat scene, length for a line), then
    // enlarged until the grid has at most kMaxCells cells.
    double cellSize = 0;
    static constexpr double kObjectsPerCell = 8;
    static constexpr uint64_t kMaxCells = uint64_t(1) << 21;
};

// View-independent: built once per scene.
struct Grid {
    Aabb bounds;                      // the scene's bounds (the grid's origin is bounds.lo)
    double cellSize = 0;
    int dims[3] = {0, 0, 0};          // cells per axis
    std::vector<uint32_t> cellBegin;  // size cells + 1: objects of cell c are cellObjects[cellBegin[c] ..)
    std::vector<uint32_t> cellObjects;
    std::vector<uint32_t> objectCellCount;  // per object: cells it is registered in
    uint64_t cellCount() const { return uint64_t(dims[0]) * uint64_t(dims[1]) * uint64_t(dims[2]); }
    uint64_t cellIndex(int x, int y, int z) const { return (uint64_t(z) * uint64_t(dims[1]) + uint64_t(y)) * uint64_t(dims[0]) + uint64_t(x); }
    // World box of grid cell (x, y, z).
    Aabb cellBox(int x, int y, int z) const;
};
Grid buildGrid(const Scene &scene, const GridSettings &settings = {});

struct GridStats {
    int dims[3] = {0, 0, 0};          // grid cells per axis
    double cellSize = 0;              // world units
    uint64_t cellsTotal = 0;          // dims product
    uint64_t registrations = 0;       // (object, cell) pairs: an object counts once per cell it overlaps
    uint64_t cellsSkipped = 0;        // outside the frustum's bounding box: never tested (cost 0)
    uint64_t cellsEmpty = 0;          // inside that box but holding no object: not tested (cost 0)
    uint64_t cellsTested = 0;         // cell boxes tested against the frustum's planes
    uint64_t cellsVisible = 0;        // of the tested: not outside any plane
    uint64_t planeTests = 0;          // box-plane tests done
    uint64_t objectsIn = 0;           // culling objects entering the stage
    uint64_t objectsCulled = 0;       // every cell of the object outside the frustum
    uint64_t trianglesIn = 0;
    uint64_t trianglesCulled = 0;
};

struct GridResult {
    std::vector<uint32_t> visible;    // kept objects, ascending
    std::vector<uint32_t> culled;     // culled objects, ascending (for the audit's StageCulls)
    GridStats stats;
};

// Why the stage does not run (nullptr: it does): the scene has cells or a PVS, whose stage is the
// coarse stage then.
const char *gridSkipReason(const Scene &scene);

// `candidates` (optional, ascending): the objects entering (null: every object).
GridResult cullGrid(const Scene &scene, const Grid &grid, const Camera &cam,
                    const std::vector<uint32_t> *candidates = nullptr);

}  // namespace va
