// What tinygltf is given, and what is checked before it parses a glTF file (docs/scene-format.md,
// "glTF 2.0"): the loader reads the file itself, so that
//   - JSON nested deeper than the limit is refused before any recursive code sees it (tinygltf
//     converts extras and extensions to its Value type recursively);
//   - glTF 1.0 (asset.version "1.0", or a version-1 GLB) is refused by name instead of being read as
//     an empty 2.0 scene, and so is a file whose asset.minVersion is newer than 2.0;
//   - a required extension (extensionsRequired) that visaudit cannot honour is refused by name;
//   - what tinygltf 2.7 cannot parse in valid compressed files is moved out of its way: the index
//     accessor of a KHR_draco_mesh_compression primitive has no buffer view (tinygltf refuses
//     that: "accessor[N] invalid bufferView"), and an EXT_meshopt_compression fallback buffer has
//     no data (tinygltf reads a GLB's BIN chunk into it, or fails when it is larger).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace va::gltf {

struct Source {
    bool binary = false;               // a GLB container
    std::vector<unsigned char> bytes;  // what tinygltf parses: the file, or the file with its JSON
                                       //   rewritten as said above
    std::string baseDir;               // for external buffers, as tinygltf derives it
    // KHR_draco_mesh_compression primitives' index accessors, taken out of the JSON tinygltf reads:
    // (mesh, primitive) -> accessor.
    std::map<std::pair<int, int>, int> dracoIndices;
    std::vector<std::string> warnings;  // with the file name
};

// Reads `path` (.glb when `binary`) and prepares it for tinygltf. False with a message naming the file,
// the place and a fix.
bool prepareSource(const std::string &path, bool binary, uint64_t maxJsonDepth, Source *out, std::string *err);

}  // namespace va::gltf
