// Compressed glTF geometry through Debian's decoders: KHR_draco_mesh_compression with libdraco,
// EXT_meshopt_compression with libmeshoptimizer. No codec is implemented here: these functions
// check what a file declares against what the codec's format allows before anything is allocated,
// call the library, and check what it returns.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace va::gltf {

// A KHR_draco_mesh_compression primitive, decoded: the attributes asked for, by glTF name (POSITION,
// JOINTS_0, ...), each as its values in the codec (dequantized by libdraco when the encoder quantized
// them; raw integers when the attribute is an integer type), and the faces' point indices (3 per face).
struct DracoAttribute {
    int components = 0;
    bool integer = false;        // an integer type (the accessor says whether it is normalized)
    std::vector<double> values;  // components per point
};
struct DracoMesh {
    size_t points = 0;
    std::map<std::string, DracoAttribute> attributes;
    std::vector<uint32_t> indices;
};

// Decodes `size` bytes of Draco mesh data and takes the attributes `ids` names (glTF name -> the
// unique id the extension's `attributes` gives it). False with a reason (no file name) when libdraco
// refuses the data, it is a point cloud, or an attribute is missing or has other than `components`.
bool decodeDraco(const unsigned char *data, size_t size, const std::map<std::string, std::pair<int, int>> &ids,
                 DracoMesh *out, std::string *err);

// EXT_meshopt_compression's bufferView extension (the decoded bytes are the buffer view's data).
enum class MeshoptMode { Attributes, Triangles, Indices };
enum class MeshoptFilter { None, Octahedral, Quaternion, Exponential };
struct MeshoptView {
    uint64_t count = 0;   // elements (vertices or indices)
    uint64_t stride = 0;  // bytes per element in the decoded data
    MeshoptMode mode = MeshoptMode::Attributes;
    MeshoptFilter filter = MeshoptFilter::None;
};

// Decodes `size` compressed bytes into count * stride bytes. Before allocating, the stride is checked
// against the mode (attributes: a multiple of 4 up to 256; indices: 2 or 4), the count against
// maxElements, and the count against the compressed size: each codec needs at least a known number
// of bytes per element (the decoders' own first checks), so a short buffer cannot declare a huge count.
bool decodeMeshopt(const unsigned char *data, size_t size, const MeshoptView &view, uint64_t maxElements,
                   std::vector<unsigned char> *out, std::string *err);

}  // namespace va::gltf
