// The cells stage for scenes with cells and portals (docs/architecture.md, Stages: cells; docs/coarse-stages.md).
//
// From the cell(s) holding the eye, a depth-first traversal through the portals: each portal of the
// current cell is clipped (Sutherland-Hodgman, in 3D, against the current frustum's planes); when
// something is left, the frustum is narrowed to the planes through the eye and each edge of the
// clipped polygon plus the portal's own plane (the eye's side is outside), and the neighbour cell is
// entered with it. Objects whose cells are never reached are culled. Conservative throughout: plane
// tests keep what is within their derived error bound, an object in several cells stays when any of
// them is reached, objects in no cell stay, and a camera outside every cell culls nothing.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "analysis/scene.h"
#include "render/camera.h"

namespace va {

// Fills scene.objectCellsBegin / objectCells: each culling object belongs to every cell its AABB
// overlaps (closed: touching a face counts; conservative for plane cells: a box outside no single
// face counts as overlapping). Call after the objects exist (after buildScene) and whenever
// scene.cells changes. A scene without cells gets empty lists.
void assignObjectsToCells(Scene &scene);

// The cells that contain point p (closed, within the rounding bound of each face test), ascending.
std::vector<uint32_t> cellsContaining(const Scene &scene, Vec3 p);

struct PortalSettings {
    uint32_t maxDepth = 64;                 // portals along one path; deeper: every cell the portal
                                            //   graph reaches from there is visible (conservative)
    uint64_t maxPortalTests = 1000000;      // budget per view; exceeded: every cell the graph reaches
                                            //   from the camera's is visible (conservative)
};

struct PortalStats {
    int32_t cameraCell = -1;          // first (lowest-index) cell holding the eye; -1: outside every cell
    uint32_t cameraCells = 0;         // cells holding the eye: 2 when it stands on a shared face
                                      //   (e.g. in a doorway's plane); 0: outside every cell
    bool cameraOutside = false;       // the eye is in no cell: nothing was culled (conservative)
    uint64_t cellsTotal = 0;          // cells in the scene
    uint64_t cellsVisible = 0;        // cells reached (the camera's included); lower is better culling
    uint64_t cellsVisited = 0;        // cell entries: the camera's cells plus every portal passed (a
                                      //   cell reached along several portal paths counts each time)
    uint64_t portalsTested = 0;       // portal polygons clipped against a frustum
    uint64_t portalsPassed = 0;       // of them, something left: the neighbour was entered
    uint64_t portalsEdgeOn = 0;       // of the tested: the eye in the portal's plane outside the polygon:
                                      //   it shows no area, not passed
    uint64_t portalsInPortal = 0;     // of the passed: the eye in the portal's plane inside the polygon
                                      //   (standing in the doorway): passed with the frustum unchanged
    uint64_t depthLimitHits = 0;      // paths cut at PortalSettings::maxDepth; best 0
    bool budgetExceeded = false;      // maxPortalTests ran out (every reachable cell visible); best false
    uint64_t objectsIn = 0;           // culling objects entering the stage
    uint64_t objectsCulled = 0;       // no cell of the object reached
    uint64_t objectsNoCell = 0;       // kept: the object overlaps no cell; best 0
    uint64_t trianglesIn = 0;         // triangles of the objects entering
    uint64_t trianglesCulled = 0;     // triangles of the culled objects
};

struct PortalResult {
    std::vector<uint32_t> visible;    // kept objects, ascending (submission order)
    std::vector<uint32_t> culled;     // culled objects, ascending (for the audit's StageCulls)
    std::vector<uint8_t> cellVisible; // per cell: 1 when reached
    PortalStats stats;
    std::string note;                 // "camera outside every cell: ..." (or empty)
};

// Why the stage cannot run on this scene (nullptr: it can): the scene has no cells.
const char *portalsSkipReason(const Scene &scene);

// The stage; `candidates` (optional, ascending): the objects entering (null: every object).
// Call only when portalsSkipReason(scene) is nullptr.
PortalResult cullPortals(const Scene &scene, const Camera &cam, const PortalSettings &settings = {},
                         const std::vector<uint32_t> *candidates = nullptr);

// ---- Exposed for tests ----------------------------------------------------------------------

// A plane of a (narrowed) frustum, inside n.p + k >= 0 (|n| = 1), with the bound on the error of
// evaluating it at p: gamma(16) (|n.x p.x| + |n.y p.y| + |n.z p.z| + |k|) + tilt |p - anchor|,
// where `tilt` bounds the angle (radians) between the computed and the exact normal and `anchor`
// is the point the plane was built through (the eye for planes through the eye).
struct FrustumPlane {
    Vec3 n;
    double k = 0;
    double tilt = 0;
    Vec3 anchor;
};
double planeErrorBound(const FrustumPlane &pl, Vec3 p);
// The convex polygon `poly` clipped by every plane (a vertex within the error bound of a plane
// counts as inside it: the result can only be larger). Fewer than 3 vertices: nothing left.
std::vector<Vec3> clipPolygon(const std::vector<Vec3> &poly, const std::vector<FrustumPlane> &planes);

}  // namespace va
