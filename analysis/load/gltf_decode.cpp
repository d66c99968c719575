// Compressed glTF geometry through Debian's libdraco and libmeshoptimizer (see gltf_decode.h).
#include "analysis/load/gltf_decode.h"

#include <draco/compression/decode.h>
#include <meshoptimizer.h>

#include <algorithm>
#include <cstring>
#include <exception>

namespace va::gltf {

bool decodeDraco(const unsigned char *data, size_t size, const std::map<std::string, std::pair<int, int>> &ids,
                 DracoMesh *out, std::string *err) {
    // libdraco reports bad data through its status, and may throw std::bad_alloc on a hostile header
    // (its own counts decide its allocations): both end here as a reason.
    try {
        draco::DecoderBuffer buffer;
        buffer.Init(reinterpret_cast<const char *>(data), size);
        draco::Decoder decoder;
        auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
        if (!decoded.ok()) {
            *err = "libdraco cannot decode it: " + decoded.status().error_msg_string();
            return false;
        }
        const std::unique_ptr<draco::Mesh> mesh = std::move(decoded).value();
        if (!mesh) {
            *err = "libdraco decoded no mesh";
            return false;
        }
        out->points = mesh->num_points();
        for (const auto &[name, idComps] : ids) {
            const auto [id, comps] = idComps;
            const draco::PointAttribute *att = id >= 0 ? mesh->GetAttributeByUniqueId(uint32_t(id)) : nullptr;
            if (!att) {
                *err = "the Draco data has no attribute with the id " + std::to_string(id) + " that the extension's attributes." +
                       name + " names";
                return false;
            }
            if (att->num_components() != comps) {
                *err = "the Draco " + name + " attribute has " + std::to_string(int(att->num_components())) +
                       " components; " + name + " needs " + std::to_string(comps);
                return false;
            }
            DracoAttribute &a = out->attributes[name];
            a.components = comps;
            a.integer = att->data_type() != draco::DT_FLOAT32 && att->data_type() != draco::DT_FLOAT64;
            a.values.assign(out->points * size_t(comps), 0.0);
            double v[4];
            for (draco::PointIndex i(0); i < mesh->num_points(); ++i) {
                if (!att->ConvertValue<double>(att->mapped_index(i), int8_t(comps), v)) {
                    *err = "libdraco cannot convert point " + std::to_string(i.value()) + "'s " + name;
                    return false;
                }
                std::copy(v, v + comps, a.values.begin() + std::ptrdiff_t(size_t(i.value()) * size_t(comps)));
            }
        }
        out->indices.resize(size_t(mesh->num_faces()) * 3);
        for (draco::FaceIndex f(0); f < mesh->num_faces(); ++f) {
            const draco::Mesh::Face &face = mesh->face(f);
            for (int c = 0; c < 3; ++c) out->indices[size_t(f.value()) * 3 + size_t(c)] = face[c].value();
        }
        return true;
    } catch (const std::exception &e) {
        *err = std::string("libdraco failed: ") + e.what();
        return false;
    }
}

namespace {
const char *modeName(MeshoptMode m) {
    return m == MeshoptMode::Attributes ? "ATTRIBUTES" : m == MeshoptMode::Triangles ? "TRIANGLES" : "INDICES";
}
}  // namespace

bool decodeMeshopt(const unsigned char *data, size_t size, const MeshoptView &v, uint64_t maxElements,
                   std::vector<unsigned char> *out, std::string *err) {
    const std::string mode = modeName(v.mode);
    // Strides the codecs take (EXT_meshopt_compression, "Compressed data"): vertex data in multiples
    // of 4 bytes up to 256, indices 2 or 4 bytes; filters need the layouts they decode.
    if (v.mode == MeshoptMode::Attributes ? (v.stride == 0 || v.stride % 4 != 0 || v.stride > 256)
                                          : (v.stride != 2 && v.stride != 4)) {
        *err = "byteStride " + std::to_string(v.stride) + " is not valid for mode " + mode +
               (v.mode == MeshoptMode::Attributes ? " (a multiple of 4, at most 256)" : " (2 or 4)");
        return false;
    }
    if (v.mode != MeshoptMode::Attributes && v.filter != MeshoptFilter::None) {
        *err = "a filter is only valid for mode ATTRIBUTES, not " + mode;
        return false;
    }
    if ((v.filter == MeshoptFilter::Octahedral && v.stride != 4 && v.stride != 8) ||
        (v.filter == MeshoptFilter::Quaternion && v.stride != 8)) {
        *err = "byteStride " + std::to_string(v.stride) + " does not fit its filter (OCTAHEDRAL: 4 or 8, QUATERNION: 8)";
        return false;
    }
    if (v.mode == MeshoptMode::Triangles && v.count % 3 != 0) {
        *err = "mode TRIANGLES needs a count that is a multiple of 3, not " + std::to_string(v.count);
        return false;
    }
    if (v.count > maxElements) {
        *err = "declares " + std::to_string(v.count) + " elements, more than the " + std::to_string(maxElements) +
               " that the triangle limit allows (3 per triangle); raise it with --max-triangles, or the file is damaged";
        return false;
    }
    // The fewest compressed bytes that can hold `count` elements, from the codecs' formats:
    //   ATTRIBUTES (vertex codec version 0, the one EXT_meshopt_compression specifies): a header byte,
    //     then per block and per byte of the vertex 2 header bits per group of 16 vertices, so at
    //     least stride * ceil(count / 64) bytes (a block holds at most 256 vertices);
    //   TRIANGLES: a header byte, one code byte per triangle and a 16-byte table;
    //   INDICES: a header byte and at least one byte per index.
    const uint64_t least = v.mode == MeshoptMode::Attributes ? 1 + v.stride * ((v.count + 63) / 64)
                           : v.mode == MeshoptMode::Triangles ? 1 + v.count / 3 + 16
                                                               : 1 + v.count;
    if (v.count > 0 && size < least) {
        *err = "declares " + std::to_string(v.count) + " elements of " + std::to_string(v.stride) + " bytes (mode " +
               mode + "), which need at least " + std::to_string(least) + " compressed bytes; it has " +
               std::to_string(size) + ": the file is damaged";
        return false;
    }
    out->assign(size_t(v.count * v.stride), 0);
    if (v.count == 0) return true;
    int rc = 0;
    if (v.mode == MeshoptMode::Attributes) {
        rc = meshopt_decodeVertexBuffer(out->data(), size_t(v.count), size_t(v.stride), data, size);
    } else if (v.mode == MeshoptMode::Triangles) {
        rc = meshopt_decodeIndexBuffer(out->data(), size_t(v.count), size_t(v.stride), data, size);
    } else {
        // meshoptimizer's index sequence decoder does not check the end of its input (each index is a
        // varint of at most 5 bytes): give it a copy padded with zeros to 1 + 5 * count bytes, so
        // damaged data decodes to wrong indices (checked against the vertices later), never reads
        // past the buffer. The padded copy is at most 5 times the compressed size (count <= size).
        std::vector<unsigned char> padded(std::max<size_t>(size, size_t(1 + 5 * v.count)), 0);
        std::memcpy(padded.data(), data, size);
        rc = meshopt_decodeIndexSequence(out->data(), size_t(v.count), size_t(v.stride), padded.data(), padded.size());
    }
    if (rc != 0) {
        *err = "libmeshoptimizer cannot decode it (mode " + mode + ", error " + std::to_string(rc) +
               "): the compressed data is damaged or in a codec version newer than Debian's meshoptimizer " +
               std::to_string(MESHOPTIMIZER_VERSION / 1000) + "." + std::to_string(MESHOPTIMIZER_VERSION % 1000 / 10) +
               " reads";
        out->clear();
        return false;
    }
    switch (v.filter) {
    case MeshoptFilter::None: break;
    case MeshoptFilter::Octahedral: meshopt_decodeFilterOct(out->data(), size_t(v.count), size_t(v.stride)); break;
    case MeshoptFilter::Quaternion: meshopt_decodeFilterQuat(out->data(), size_t(v.count), size_t(v.stride)); break;
    case MeshoptFilter::Exponential: meshopt_decodeFilterExp(out->data(), size_t(v.count), size_t(v.stride)); break;
    }
    return true;
}

}  // namespace va::gltf
