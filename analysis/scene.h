// The scene model (docs/architecture.md, Scene model). Owned by analysis/; render/ never sees it.
#pragma once

#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "render/camera.h"
#include "render/depth_format.h"
#include "render/math.h"

namespace va {

struct Material {
    std::string name = "default";
    bool doubleSided = false;  // never backface-culled
    double alpha = 1;          // < 1: transparent
    double reflective = 0;     // 0..1
    double ior = 1;            // != 1: refractive
    bool transparent() const { return alpha < 1; }
    bool refractive() const { return ior != 1; }
};

struct Light {
    std::string name;
    bool directional = true;
    Vec3 direction{0, -1, 0};  // directional: direction the light travels
    Vec3 position;             // point
};

// A view that is a frame of a route (analysis/load/route.h): which route, which frame, when.
struct RouteStop {
    std::string route;      // the route's name; empty: the view is on no route
    uint32_t frame = 0;     // 0-based, in the route's order
    double time = 0;        // seconds on the route's timeline
    bool onRoute() const { return !route.empty(); }
};

struct ViewSpec {
    std::string name;
    CameraSpec camera;
    DepthFormatSpec depthFormat = DepthFormat::f32;
    std::string origin;  // where it came from: "scene", a views file, "orbit:N", "gltf camera", "route:FILE"
    RouteStop route;     // a route's frame (route:FILE); empty otherwise
};

// What a mesh file held, as read: every face kept, polygons fan-triangulated.
struct RawMesh {
    std::vector<Vec3> positions;
    std::vector<uint32_t> indices;  // 3 per triangle, in file order (a polygon's fan in order)
    uint64_t facesRead = 0;         // faces in the file (polygons count once)
    uint64_t polygonsTriangulated = 0;  // faces with more than 3 vertices
    uint64_t facesDropped = 0;      // faces that could not be used (fewer than 3 valid vertices)
    std::vector<std::string> warnings;  // what the reader noticed but could read past (never silent)
};

// An object as the scene file names it (one mesh instance, one material).
struct SourceObject {
    std::string name;
    std::string mesh;             // file it came from
    uint32_t material = 0;
    uint32_t firstTriangle = 0;   // its triangles are [firstTriangle, firstTriangle + triangleCount)
    uint32_t triangleCount = 0;   //   in the scene's source order
    uint32_t firstChunk = 0, chunkCount = 0;  // culling objects made from it
};

// A culling object: a spatially coherent chunk of one source object (or all of a small one).
struct SceneObject {
    std::string name;             // source name, with "#k" for chunk k when split
    uint32_t source = 0;          // index into Scene::sources
    uint32_t material = 0;
    uint32_t vertexBegin = 0, vertexEnd = 0;  // its vertices in Scene::positions
    uint32_t triBegin = 0, triEnd = 0;        // its triangles in Scene::objectTriangles
    Aabb bounds;
    Sphere sphere;
};

constexpr uint32_t kExcludedTriangle = 0xFFFFFFFFu;

// ---- Quake 3 maps: the BSP tree, leafs, clusters and the PVS (docs/quake3.md) ---------------------

// An entity of the map's entity lump: its "key" "value" pairs in file order.
struct BspEntity {
    std::vector<std::pair<std::string, std::string>> keys;
    // The value of `key` (first occurrence), or nullptr.
    const std::string *get(const std::string &key) const {
        for (const auto &kv : keys)
            if (kv.first == key) return &kv.second;
        return nullptr;
    }
};

struct BspPlane {
    Vec3 normal;      // as stored (float, converted exactly)
    double dist = 0;  // points p with dot(normal, p) == dist lie on the plane
};

struct BspNode {
    uint32_t plane = 0;
    // dot(normal, p) - dist >= 0: children[0] (front), else children[1] (back).
    // A child >= 0 is a node (always after its parent: the loader checks it, so a walk ends);
    // a child < 0 is leaf -(child + 1).
    int32_t children[2] = {0, 0};
};

struct BspLeaf {
    int32_t cluster = -1;  // -1: outside every cluster (solid, or the void outside the map)
    int32_t area = -1;
    Aabb bounds;           // as stored (integers)
    uint32_t firstLeafFace = 0, leafFaceCount = 0;  // its faces: BspLevel::leafFaces[first, first + count)
    uint32_t firstLeafBrush = 0, leafBrushCount = 0;  // its brushes: BspLevel::leafBrushes[first, first + count)
};

// What the PVS audit (analysis/audits/pvs_audit.h) reads besides the tree: shaders' flags, the brushes a
// leaf holds (a detail brush does not split the tree, so a point in a leaf with a cluster can still
// be inside solid), and where each triangle came from.
struct BspShader {
    std::string name;
    uint32_t surfaceFlags = 0;  // SURF_* (Quake 3's surfaceflags.h): 0x4 sky, 0x80 nodraw, ...
    uint32_t contents = 0;      // CONTENTS_*: 0x1 solid, 0x20 water, 0x20000000 translucent, ...
};
// A convex brush: the points behind (dot(normal, p) - dist <= 0) every side's plane.
struct BspBrush {
    uint32_t firstSide = 0, sideCount = 0;  // BspLevel::brushSides[first, first + count)
    uint32_t shader = 0;                    // its contents are this shader's
};

// What the map's faces were, counted by kind (a face counts once, under the first rule that holds:
// bad type, billboard, a brush entity the engine never draws, sky, nodraw, non-solid, else drawn by
// type).
struct BspFaceCounts {
    uint64_t faces = 0;         // faces in the file
    uint64_t polygons = 0;      // drawn type-1 faces (planar polygons, triangles from meshverts)
    uint64_t patches = 0;       // drawn type-2 faces (Bezier patches, tessellated)
    uint64_t meshes = 0;        // drawn type-3 faces (triangle soups: models baked into the map)
    uint64_t billboards = 0;    // type-4 faces (flares: a point, no geometry), skipped
    uint64_t bad = 0;           // type-0 faces (MST_BAD: no geometry), skipped
    uint64_t notDrawnEntity = 0;// faces of brush models the engine never draws (a trigger_* entity's, or a
                                //   model no entity spawns): not geometry, excluded (BspModel lists them)
    uint64_t sky = 0;           // SURF_SKY (0x4): the sky box, excluded from objects
    uint64_t nodraw = 0;        // tool surfaces: SURF_NODRAW (0x80), SURF_HINT (0x100), SURF_SKIP (0x200), or
                                //   CONTENTS_AREAPORTAL (0x8000): never drawn, excluded
    uint64_t nonSolid = 0;      // water, slime, lava, fog volumes (contents 0x8/0x10/0x20/0x40): excluded
    uint64_t polygonTriangles = 0, patchTriangles = 0, meshTriangles = 0;  // triangles of drawn faces by type
    uint64_t skyTriangles = 0, nodrawTriangles = 0, nonSolidTriangles = 0;  // triangles of excluded faces
    uint64_t notDrawnEntityTriangles = 0;  // triangles of the notDrawnEntity faces
    uint64_t unleafedFaces = 0; // drawn world faces no leaf of the world's tree lists (object "unleafed", no cluster)
    uint64_t modelFaces = 0;    // drawn faces of brush models 1.. the engine draws (doors, platforms, movers):
                                //   objects "modelK", clustered by their box through the world's tree
};

// A brush model (the models lump; model 0 is the world) and the entity the game spawns for it.
struct BspModel {
    Aabb bounds;                 // as stored, moved by `offset` (where the game draws it)
    Vec3 offset;                 // the placing entity's "origin" (a func_train: its first path_corner's,
                                 //   where it starts); 0 for the world and entities without one
    int32_t entity = -1;         // the first entity with "model" "*K" (index into BspLevel::entities);
                                 //   -1: none (always for model 0)
    std::string classname;       // that entity's classname ("" when none)
    bool drawn = true;           // false: the engine never draws it: a trigger_* entity (the game sends
                                 //   triggers to no client, or the client draws nothing for them), or no
                                 //   entity spawns the model
    uint32_t firstFace = 0, faceCount = 0;  // its faces in the faces lump
    uint64_t notDrawnFaces = 0, notDrawnTriangles = 0;  // !drawn: its faces with geometry (not bad or
                                 //   billboard: BspFaceCounts::notDrawnEntity), and their triangles
    // K >= 1: the leafs its box (`bounds` widened by 1 unit per side, as the server links entities)
    // reaches walking the world's tree, as the engine's CM_BoxLeafnums: the leafs whose clusters
    // decide whether the entity is in the PVS. Ascending. Empty for the world.
    std::vector<int32_t> boxLeafs;
};

// The map's designed far plane: the worldspawn key q3map2's vis reads ("_farplanedist", or Wolfenstein's
// "fogclip", Soldier of Fortune 2's "distancecull"), a distance and an optional mode letter. Portal
// pairs farther apart than it are left out of the PVS on purpose (docs/quake3.md, "The far plane").
struct BspFarPlane {
    double distance = 0;         // > 0: the map has one
    char mode = 0;               // q3map2's mode letter after the number: 'o', 'e', 'r'; 0: default rule
    std::string key, value;      // the key that set it and its text
};

// A Quake 3 map's visibility structure. Present only for scenes loaded from a .bsp.
struct BspLevel {
    std::vector<BspPlane> planes;
    std::vector<BspNode> nodes;             // nodes[0] is the root (no nodes: the map is leaf 0)
    std::vector<BspLeaf> leafs;
    std::vector<uint32_t> leafFaces;        // face indices, ranges of it per leaf
    int32_t clusterCount = 0;               // clusters: the PVS's rows (n_vecs), or 1 + the largest leaf cluster
    uint32_t pvsRowBytes = 0;               // sz_vecs: bytes per PVS row
    std::vector<uint8_t> pvs;               // clusterCount x pvsRowBytes; empty: no visdata (compiled without vis)
    // Per source object (Scene::sources): its primary cluster (the leaf's; -1 none) and the set of
    // every cluster any leaf holding one of its faces is in (sorted; empty: no cluster, always kept).
    std::vector<int32_t> sourceCluster;
    std::vector<uint32_t> sourceClustersBegin;  // size sources + 1: ranges into sourceClusters
    std::vector<int32_t> sourceClusters;
    std::vector<BspEntity> entities;
    // For the PVS audit: every shader, brush and brush side (each side: its plane), the brushes of
    // each leaf (ranges of leafBrushes), each face's shader, the world's faces (model 0:
    // [worldFirstFace, worldFirstFace + worldFaceCount)), and per source triangle the face it came
    // from (faces lump index; triangles in the scene's source order).
    std::vector<BspShader> shaders;
    std::vector<BspBrush> brushes;
    std::vector<uint32_t> brushSides;       // per side: its plane
    std::vector<uint32_t> leafBrushes;      // brush indices, ranges of it per leaf
    std::vector<uint32_t> faceShader;
    uint32_t worldFirstFace = 0, worldFaceCount = 0;
    std::vector<uint32_t> triangleFace;
    std::vector<BspModel> models;           // every model; [0] is the world
    std::vector<uint8_t> leafInTree;        // per leaf: 1 when the world's tree reaches it (the models'
                                            //   own leafs, cluster 0 with zero bounds, it never reaches)
    // Every leaf listing each face (the leaffaces lump inverted, ascending per face):
    // faceLeafs[faceLeafsBegin[f] .. faceLeafsBegin[f + 1]).
    std::vector<uint32_t> faceLeafsBegin, faceLeafs;
    std::vector<uint32_t> sourceModel;      // per source object: its model (0: world faces)
    BspFarPlane farPlane;
    std::string fogShader;                  // worldspawn "_fog" / "fog": a map-wide fog shader (q3map2; not
                                            //   drawn by ioquake3, its range is in a shader script)
    BspFaceCounts faceCounts;
    int patchLevel = 0;                     // the tessellation level used (segments per patch edge)

    bool hasPvs() const { return !pvs.empty(); }
    // Cluster `from` sees cluster `to`: bit (to & 7) of byte pvs[from * rowBytes + to / 8]. Both must
    // be in [0, clusterCount) and the map must have a PVS.
    bool clusterVisible(int32_t from, int32_t to) const {
        return (pvs[size_t(from) * pvsRowBytes + size_t(to >> 3)] >> (to & 7)) & 1;
    }
    // The leaf containing p: walk from the root, front (dot(n, p) - dist >= 0) or back child.
    // Ends: children always come after their parent (checked when loading). -1 when there is no leaf.
    int32_t leafAt(Vec3 p) const {
        if (leafs.empty()) return -1;
        if (nodes.empty()) return 0;
        int32_t i = 0;
        while (i >= 0) {
            const BspNode &n = nodes[size_t(i)];
            const BspPlane &pl = planes[n.plane];
            i = n.children[dot(pl.normal, p) - pl.dist >= 0 ? 0 : 1];
        }
        return -(i + 1);
    }
};

// ---- Cells and portals from a scene file (docs/scene-format.md, docs/coarse-stages.md) ----------

// A half-space n.p + k >= 0 (the inside of a cell's face).
struct HalfSpace {
    Vec3 n;
    double k = 0;
};

// A convex cell: the intersection of its half-spaces, closed (a point on a face is inside). Given
// as a box ("min"/"max": six axis-aligned half-spaces, `box` holds it) or as planes ("planes":
// [a, b, c, d] with a x + b y + c z + d >= 0 inside; `box` is then empty).
struct Cell {
    std::string name;
    std::vector<HalfSpace> faces;
    Aabb box;                          // the box of a "min"/"max" cell; empty for a "planes" cell
};
// A box cell: its six half-spaces n.p + k >= 0 (x - lo.x >= 0, hi.x - x >= 0, ...); lo < hi.
Cell boxCell(const std::string &name, Vec3 lo, Vec3 hi);

// A convex polygon (3+ coplanar points, in order) joining two cells; seen from either side.
struct Portal {
    std::string name;
    uint32_t cells[2] = {0, 0};        // indices into Scene::cells
    std::vector<Vec3> points;
};

struct SceneStats {
    uint64_t sourceTriangles = 0;     // triangles in source order (ids 0 .. n-1)
    uint64_t degenerateTriangles = 0; // zero area (two equal vertices or collinear): excluded
    uint64_t nonFiniteTriangles = 0;  // a NaN or infinite coordinate: excluded
    uint64_t facesDropped = 0;        // faces the loaders could not turn into triangles
    uint64_t polygonsTriangulated = 0;
};

struct Scene {
    std::string path;
    char up = 'y';
    std::vector<Vec3> positions;          // world space, grouped by culling object
    std::vector<uint32_t> indices;        // 3 per source triangle, source order
    std::vector<uint32_t> triangleObject; // per source triangle: its culling object or kExcludedTriangle
    std::vector<uint32_t> objectTriangles;// triangles of each culling object, contiguous per object
    std::vector<double> planes;           // 4 per source triangle: world plane n.x n.y n.z k, n.p + k = 0,
                                          //   n = (v1 - v0) x (v2 - v0) (front = CCW side)
    std::vector<double> planeBounds;      // 2 per source triangle: |n.x| + |n.y| + |n.z| and the
                                          //   largest |coordinate| of its vertices (the backface
                                          //   test's rounding bound, isFrontFacing); 0 when excluded
    // The backface stage's streaming filter, one per Scene::objectTriangles entry (in that order,
    // so the stage reads it front to back): the plane rounded to float, 16 bytes a triangle; and per
    // culling object the largest |coordinate| of its triangles' vertices. With them a bound on the
    // error of evaluating a plane in float at an eye e (scene.cpp derives it). Empty: the stage uses
    // only the double test.
    struct BackfacePlane {
        float nx, ny, nz, k;  // the plane, each coordinate rounded to float
    };
    // The bound's two factors for one object at one eye: |s_float(e) - side| <= (|nx| + |ny| + |nz|)
    // * perNormal + |k| * perOffset, each product and the sum in float (scene.cpp).
    struct BackfaceBound {
        float perNormal, perOffset;
    };
    // Stored as four float arrays (structure of arrays: the stage's loop runs four or eight
    // triangles per instruction); operator[] reads one entry.
    struct BackfacePlanes {
        std::vector<float> nx, ny, nz, k;
        std::vector<float> objectV;  // per culling object, rounded up
        size_t size() const { return nx.size(); }
        void resize(size_t n) { nx.resize(n), ny.resize(n), nz.resize(n), k.resize(n); }
        void set(size_t i, const BackfacePlane &p) { nx[i] = p.nx, ny[i] = p.ny, nz[i] = p.nz, k[i] = p.k; }
        BackfacePlane operator[](size_t i) const { return {nx[i], ny[i], nz[i], k[i]}; }
        // The factors for culling object `object` seen from an eye with maxAbs(e) = eyeMax.
        BackfaceBound bound(uint32_t object, double eyeMax) const;
        // The bound of entry i (of that object) at that eye: what the stage compares with.
        static float boundOf(const BackfacePlane &p, BackfaceBound b) {
            return ((std::fabs(p.nx) + std::fabs(p.ny)) + std::fabs(p.nz)) * b.perNormal + std::fabs(p.k) * b.perOffset;
        }
        uint64_t bytes() const { return 4 * sizeof(float) * nx.capacity() + sizeof(float) * objectV.capacity(); }
    };
    BackfacePlanes backfacePlanes;
    std::vector<SceneObject> objects;
    std::vector<SourceObject> sources;
    std::vector<Material> materials;
    std::vector<Light> lights;
    std::vector<ViewSpec> views;
    Aabb bounds;
    SceneStats stats;
    std::vector<std::string> warnings;    // loader notes: dropped faces, ignored glTF features, ...
    std::optional<BspLevel> bsp;          // Quake 3 maps: BSP tree, leafs, clusters, PVS, entities
    // Cells and portals (scene files only; empty: none). Per culling object, the cells its bounds
    // overlap: objectCells[objectCellsBegin[o] .. objectCellsBegin[o + 1]) (ascending; empty: in no
    // cell, always kept). Filled by assignObjectsToCells (analysis/stages/portals.h) once objects exist.
    std::vector<Cell> cells;
    std::vector<Portal> portals;
    std::vector<uint32_t> objectCellsBegin;
    std::vector<uint32_t> objectCells;

    size_t triangleCount() const { return triangleObject.size(); }
    const Material &materialOf(const SceneObject &o) const { return materials[o.material]; }
};

// Builds a scene from source objects. Each entry is a source object with its world-space mesh.
struct SceneBuildInput {
    struct Object {
        std::string name, mesh;
        uint32_t material = 0;
        RawMesh geometry;  // world space
    };
    std::vector<Object> objects;
    std::vector<Material> materials;  // at least one; index 0 is the default
    std::vector<Light> lights;
    std::vector<ViewSpec> views;
    char up = 'y';
    std::string path;
    std::vector<std::string> warnings;  // copied to Scene::warnings (after each mesh's own warnings)
};
struct ChunkSettings {
    uint32_t maxTriangles = 512;  // source objects larger than this are split into chunks
};
// Fails (false + message) only on input that cannot be represented: more than 2^32 - 1 vertices or
// triangles after chunking, an index outside its object's positions, a material index out of range.
bool buildScene(SceneBuildInput &&in, const ChunkSettings &chunks, Scene *out, std::string *err);
// Convenience for trusted input (tests, generated scenes): throws std::runtime_error where the
// overload above returns false. Loaders use the overload above.
Scene buildScene(SceneBuildInput &&in, const ChunkSettings &chunks = {});

}  // namespace va
