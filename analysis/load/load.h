// Loaders: scene JSON, mesh files (OBJ, PLY, OFF, STL), glTF 2.0, views files.
// Expected failures return false with a message naming the file, the place and a fix (STYLE 9, 10).
#pragma once

#include <string>
#include <vector>

#include "common/limits.h"
#include "analysis/load/load_bsp.h"
#include "analysis/scene.h"

namespace va {

struct LoadOptions {
    ChunkSettings chunks;
    BspOptions bsp;  // Quake 3 maps: patch tessellation level
    uint64_t maxTriangles = kDefaultMaxTriangles;  // refused before allocating (--max-triangles;
                                                   //   also caps bsp.maxTriangles)
    uint64_t maxJsonDepth = kDefaultMaxJsonDepth;  // deepest JSON nesting accepted (--max-json-depth)
};

// Loads any supported input: *.json (visaudit-scene/1), .obj .ply .off .stl, .gltf .glb.
bool loadScene(const std::string &path, const LoadOptions &opt, Scene *out, std::string *err);

// Reads a mesh file keeping every face (OpenMesh's readers, our own importer: no half-edge mesh).
bool loadMeshFile(const std::string &path, RawMesh *out, std::string *err);

// Reads a glTF 2.0 file: nodes become objects (world transforms applied; EXT_mesh_gpu_instancing
// instances one object each), cameras become views, materials become flags. Draco, meshopt, quantized
// and sparse geometry is decoded (docs/scene-format.md, "glTF 2.0"); glTF 1.0, JSON nested deeper than
// maxJsonDepth, out-of-range indices and required extensions it cannot honour are refused.
// Accessor counts and the triangles all nodes instance are checked against maxTriangles before
// anything is allocated for them.
bool loadGltf(const std::string &path, SceneBuildInput *out, std::string *err,
              uint64_t maxTriangles = kDefaultMaxTriangles, uint64_t maxJsonDepth = kDefaultMaxJsonDepth);

// Reads a views file: { "views": [ ... ] } with docs/scene-format.md's view keys.
// Views without "up" get the file's top-level "up" axis if it has one, else the y axis.
bool loadViewsFile(const std::string &path, std::vector<ViewSpec> *out, std::string *err,
                   uint64_t maxJsonDepth = kDefaultMaxJsonDepth);
// The same, with views lacking "up" (and a file without "up") defaulting to the scene's up axis.
bool loadViewsFile(const std::string &path, char sceneUp, std::vector<ViewSpec> *out, std::string *err,
                   uint64_t maxJsonDepth = kDefaultMaxJsonDepth);

// N cameras around the scene's bounds looking at its center (deterministic).
std::vector<ViewSpec> orbitViews(const Scene &scene, int n);

}  // namespace va
