// The scene model (DESIGN.md, Scene model). Owned by analysis/; render/ never sees it.
#pragma once

#include <cstdint>
#include <string>
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

struct ViewSpec {
    std::string name;
    CameraSpec camera;
    DepthFormat depthFormat = DepthFormat::f32;
    std::string origin;  // where it came from: "scene", a views file, "orbit:N", "gltf camera"
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
    std::vector<SceneObject> objects;
    std::vector<SourceObject> sources;
    std::vector<Material> materials;
    std::vector<Light> lights;
    std::vector<ViewSpec> views;
    Aabb bounds;
    SceneStats stats;
    std::vector<std::string> warnings;    // loader notes: dropped faces, ignored glTF features, ...

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
