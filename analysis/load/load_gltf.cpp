// glTF 2.0 (.gltf, .glb) through tinygltf: nodes -> source objects, cameras -> views,
// materials -> flags. The mapping is documented in docs/scene-format.md ("glTF 2.0").
//
// tinygltf is compiled here, in this one translation unit, without its stb_image dependency:
// visaudit never needs texels, so images are neither decoded (a custom loader callback accepts
// and ignores them) nor read from disk (TINYGLTF_NO_EXTERNAL_IMAGE): a level whose textures are
// missing still loads. Its Draco support (TINYGLTF_ENABLE_DRACO) stays off: it indexes buffer views,
// accessors and attributes unchecked, so a hostile file would crash it. Draco and meshopt data are
// decoded here instead, through Debian's libdraco and libmeshoptimizer (gltf_decode.h), after the
// file's declarations are checked. gltf_file.h is what happens before tinygltf parses: the JSON
// nesting limit, glTF 1.0, required extensions.
//
// Nothing here recurses on the file's structure: the node hierarchy is walked with an explicit
// stack (a chain of a few hundred thousand nodes is a legal file).
#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#define TINYGLTF_USE_CPP14
#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <set>

#include "analysis/load/gltf_decode.h"
#include "analysis/load/gltf_file.h"
#include "analysis/load/load.h"

namespace va {
namespace {

using tinygltf::Value;

bool ignoreImage(tinygltf::Image *, const int, std::string *, std::string *, int, int, const unsigned char *, int,
                 void *) {
    return true;
}

// A unit quaternion (x, y, z, w) as a rotation matrix.
Mat4 rotationMatrix(double x, double y, double z, double w) {
    Mat4 r;
    r.m[0][0] = 1 - 2 * (y * y + z * z); r.m[0][1] = 2 * (x * y - z * w);     r.m[0][2] = 2 * (x * z + y * w);
    r.m[1][0] = 2 * (x * y + z * w);     r.m[1][1] = 1 - 2 * (x * x + z * z); r.m[1][2] = 2 * (y * z - x * w);
    r.m[2][0] = 2 * (x * z - y * w);     r.m[2][1] = 2 * (y * z + x * w);     r.m[2][2] = 1 - 2 * (x * x + y * y);
    return r;
}

// glTF matrices are column-major; Mat4 is row-major (acting on column vectors).
Mat4 nodeLocalMatrix(const tinygltf::Node &n) {
    Mat4 m;
    if (n.matrix.size() == 16) {
        for (int c = 0; c < 4; ++c)
            for (int r = 0; r < 4; ++r) m.m[r][c] = n.matrix[size_t(c * 4 + r)];
        return m;
    }
    // local = T * R * S (glTF 2.0, section "Transformations").
    Mat4 t, r, s;
    if (n.translation.size() == 3) t = Mat4::translate({n.translation[0], n.translation[1], n.translation[2]});
    if (n.scale.size() == 3) s = Mat4::scale({n.scale[0], n.scale[1], n.scale[2]});
    if (n.rotation.size() == 4) r = rotationMatrix(n.rotation[0], n.rotation[1], n.rotation[2], n.rotation[3]);
    return t * r * s;
}

double det3(const Mat4 &m) {
    return m.m[0][0] * (m.m[1][1] * m.m[2][2] - m.m[1][2] * m.m[2][1]) -
           m.m[0][1] * (m.m[1][0] * m.m[2][2] - m.m[1][2] * m.m[2][0]) +
           m.m[0][2] * (m.m[1][0] * m.m[2][1] - m.m[1][1] * m.m[2][0]);
}

// An extension's object in an extensions map, or nullptr.
const Value *extension(const tinygltf::ExtensionMap &m, const char *name) {
    auto it = m.find(name);
    return it != m.end() && it->second.IsObject() ? &it->second : nullptr;
}
// An integer member of a JSON object (tinygltf keeps integral numbers as INT or REAL); false when
// it is absent or not an integer.
bool intMember(const Value &o, const char *key, int64_t *out) {
    if (!o.IsObject() || !o.Has(key)) return false;
    const Value &v = o.Get(key);
    if (v.IsInt()) {
        *out = v.Get<int>();
        return true;
    }
    if (v.IsReal()) {
        const double d = v.Get<double>();
        if (!(std::floor(d) == d) || std::fabs(d) > 9.0e15) return false;
        *out = int64_t(d);
        return true;
    }
    return false;
}
std::string stringMember(const Value &o, const char *key) {
    if (!o.IsObject() || !o.Has(key) || !o.Get(key).IsString()) return "";
    return o.Get(key).Get<std::string>();
}

// One component of an accessor element as a number: normalized integers mapped to [0, 1] or [-1, 1]
// as the glTF spec says (signed: max(c / (2^(n-1) - 1), -1)).
double componentValue(int componentType, bool normalized, const unsigned char *q) {
    switch (componentType) {
    case TINYGLTF_COMPONENT_TYPE_FLOAT: { float f; std::memcpy(&f, q, 4); return f; }
    case TINYGLTF_COMPONENT_TYPE_DOUBLE: { double d; std::memcpy(&d, q, 8); return d; }
    case TINYGLTF_COMPONENT_TYPE_BYTE: { int8_t x; std::memcpy(&x, q, 1); return normalized ? std::max(x / 127.0, -1.0) : x; }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: { uint8_t x = *q; return normalized ? x / 255.0 : x; }
    case TINYGLTF_COMPONENT_TYPE_SHORT: { int16_t x; std::memcpy(&x, q, 2); return normalized ? std::max(x / 32767.0, -1.0) : x; }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: { uint16_t x; std::memcpy(&x, q, 2); return normalized ? x / 65535.0 : x; }
    case TINYGLTF_COMPONENT_TYPE_INT: { int32_t x; std::memcpy(&x, q, 4); return x; }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: { uint32_t x; std::memcpy(&x, q, 4); return x; }
    default: return 0;
    }
}
// The same mapping for a value libdraco decoded as a number of the accessor's component type.
double normalizedValue(int componentType, double v) {
    switch (componentType) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: return std::max(v / 127.0, -1.0);
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return v / 255.0;
    case TINYGLTF_COMPONENT_TYPE_SHORT: return std::max(v / 32767.0, -1.0);
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return v / 65535.0;
    default: return v;
    }
}

// One mesh primitive's geometry in its mesh's space, read once per node (once for all the instances
// of an EXT_mesh_gpu_instancing node).
struct PrimitiveGeometry {
    std::vector<Vec3> positions;
    std::vector<uint32_t> order;  // vertex indices in primitive order (every one < positions.size())
    int mode = TINYGLTF_MODE_TRIANGLES;  // triangles, strip or fan
    // A skinned node's primitive: its JOINTS_n and WEIGHTS_n sets, 4 values per vertex each.
    std::vector<std::vector<double>> joints, weights;
};

// A skinned node's primitive, placed after the walk (its joints may come later in node order) into
// the object reserved for it at its place in the walk.
struct SkinnedPrimitive {
    size_t object;
    int node, skin;
    std::shared_ptr<const PrimitiveGeometry> geometry;
    std::string where;
};

// What a node puts in the scene: its world transform, one per EXT_mesh_gpu_instancing instance.
struct Placement {
    Mat4 world;
    std::string name;
};

struct GltfLoader {
    const std::string &path;
    const tinygltf::Model &model;
    const gltf::Source &source;
    SceneBuildInput *out;
    uint64_t maxTriangles = kDefaultMaxTriangles;  // --max-triangles, over every node's instances
    std::string err;
    std::vector<uint32_t> materialIndex;  // glTF material -> our material
    std::set<std::string> viewNames;
    uint64_t skippedPrimitives = 0;       // POINTS / LINES primitives
    uint64_t spotLights = 0;              // KHR_lights_punctual spot lights, read as point lights
    uint64_t triangles = 0;               // of the primitives added so far
    std::map<int, std::vector<unsigned char>> meshoptViews;  // decoded EXT_meshopt_compression views
    std::map<int, gltf::DracoMesh> dracoViews;               // decoded KHR_draco_mesh_compression views
    std::vector<SkinnedPrimitive> skinnedPrimitives;          // placed after the walk (applySkins)
    std::set<int> jointNodes;                                 // every skin's joints
    std::map<int, Mat4> jointWorlds;                          // their world transforms, from the walk
    std::vector<int> parents;                                 // for joints outside the walk (worldOf)

    // Accessor elements a primitive may need within the triangle limit: 3 per triangle (a strip or
    // fan needs fewer).
    uint64_t maxElements() const { return maxTriangles > (UINT64_MAX - 2) / 3 ? UINT64_MAX : 3 * maxTriangles + 2; }

    std::string nodeName(int i) const {
        const auto &n = model.nodes[size_t(i)];
        return n.name.empty() ? "node" + std::to_string(i) : n.name;
    }

    // The bytes of buffer view `bv`: a slice of its buffer, checked against it, or the decoded data
    // of an EXT_meshopt_compression view (decoded once).
    bool viewData(int bv, const std::string &what, const unsigned char **data, size_t *size, std::string *e) {
        if (bv < 0 || size_t(bv) >= model.bufferViews.size()) {
            *e = what + " refers to buffer view " + std::to_string(bv) + ", which does not exist";
            return false;
        }
        const auto &view = model.bufferViews[size_t(bv)];
        const std::string vw = what + ": buffer view " + std::to_string(bv);
        if (const Value *mo = extension(view.extensions, "EXT_meshopt_compression")) {
            auto cached = meshoptViews.find(bv);
            if (cached == meshoptViews.end()) {
                int64_t buffer = -1, offset = 0, length = -1, stride = -1, count = -1;
                intMember(*mo, "byteOffset", &offset);
                if (!intMember(*mo, "buffer", &buffer) || !intMember(*mo, "byteLength", &length) ||
                    !intMember(*mo, "byteStride", &stride) || !intMember(*mo, "count", &count) || offset < 0 ||
                    length < 0 || stride < 0 || count < 0) {
                    *e = vw + ": EXT_meshopt_compression needs buffer, byteLength, byteStride and count (non-negative integers)";
                    return false;
                }
                if (buffer >= int64_t(model.buffers.size())) {
                    *e = vw + ": EXT_meshopt_compression refers to buffer " + std::to_string(buffer) + ", which does not exist";
                    return false;
                }
                const auto &buf = model.buffers[size_t(buffer)].data;
                if (uint64_t(offset) > buf.size() || uint64_t(length) > buf.size() - uint64_t(offset)) {
                    *e = vw + ": EXT_meshopt_compression's " + std::to_string(length) + " bytes at offset " +
                         std::to_string(offset) + " lie past the end of buffer " + std::to_string(buffer) + " (" +
                         std::to_string(buf.size()) + " bytes); the file is truncated or inconsistent";
                    return false;
                }
                gltf::MeshoptView mv;
                mv.count = uint64_t(count);
                mv.stride = uint64_t(stride);
                const std::string mode = stringMember(*mo, "mode"), filter = stringMember(*mo, "filter");
                if (mode == "ATTRIBUTES") mv.mode = gltf::MeshoptMode::Attributes;
                else if (mode == "TRIANGLES") mv.mode = gltf::MeshoptMode::Triangles;
                else if (mode == "INDICES") mv.mode = gltf::MeshoptMode::Indices;
                else {
                    *e = vw + ": EXT_meshopt_compression mode '" + mode + "' is not ATTRIBUTES, TRIANGLES or INDICES";
                    return false;
                }
                if (filter.empty() || filter == "NONE") mv.filter = gltf::MeshoptFilter::None;
                else if (filter == "OCTAHEDRAL") mv.filter = gltf::MeshoptFilter::Octahedral;
                else if (filter == "QUATERNION") mv.filter = gltf::MeshoptFilter::Quaternion;
                else if (filter == "EXPONENTIAL") mv.filter = gltf::MeshoptFilter::Exponential;
                else {
                    *e = vw + ": EXT_meshopt_compression filter '" + filter +
                         "' is not NONE, OCTAHEDRAL, QUATERNION or EXPONENTIAL";
                    return false;
                }
                // The decoded data is the view's data: it must fit the view's declared length.
                if (mv.stride > 0 && mv.count > view.byteLength / mv.stride) {
                    *e = vw + ": EXT_meshopt_compression decodes " + std::to_string(mv.count) + " x " +
                         std::to_string(mv.stride) + " bytes, more than the view's byteLength " +
                         std::to_string(view.byteLength) + "; the file is inconsistent";
                    return false;
                }
                std::vector<unsigned char> decoded;
                std::string de;
                if (!gltf::decodeMeshopt(buf.data() + offset, size_t(length), mv, maxElements(), &decoded, &de)) {
                    *e = vw + ": EXT_meshopt_compression " + de;
                    return false;
                }
                cached = meshoptViews.emplace(bv, std::move(decoded)).first;
            }
            *data = cached->second.data();
            *size = cached->second.size();
            return true;
        }
        if (view.buffer < 0 || size_t(view.buffer) >= model.buffers.size()) {
            *e = vw + " refers to buffer " + std::to_string(view.buffer) + ", which does not exist";
            return false;
        }
        // A view that does not lie inside its buffer holds nothing: whatever reads it reads past its end
        // (the reader's message says how many elements it wanted).
        const auto &buf = model.buffers[size_t(view.buffer)].data;
        const bool inside = view.byteOffset <= buf.size() && view.byteLength <= buf.size() - view.byteOffset;
        *data = inside ? buf.data() + view.byteOffset : buf.data();
        *size = inside ? view.byteLength : 0;
        return true;
    }

    // Reads accessor `index` as its elements of `comps` components each, converted to double
    // (componentValue). Every byte read is bounds-checked against its buffer view, and the count
    // against maxElements, before the output is allocated: a hostile count is refused, not trusted.
    // A sparse accessor is its base (its buffer view, or zeros) with the listed elements replaced.
    bool readAccessor(int index, int comps, std::vector<double> *out, std::string *e) {
        if (index < 0 || size_t(index) >= model.accessors.size()) {
            *e = "accessor " + std::to_string(index) + " does not exist";
            return false;
        }
        const auto &a = model.accessors[size_t(index)];
        const std::string what = "accessor " + std::to_string(index);
        const int ncomp = tinygltf::GetNumComponentsInType(uint32_t(a.type));
        if (ncomp != comps) {
            *e = what + " has " + std::to_string(ncomp) + " components per element; expected " + std::to_string(comps);
            return false;
        }
        const int csize = tinygltf::GetComponentSizeInBytes(uint32_t(a.componentType));
        if (csize <= 0) {
            *e = what + " has an unknown component type " + std::to_string(a.componentType);
            return false;
        }
        // Without a buffer view an accessor is all zeros (glTF 2.0): no byte of the file bounds its
        // count, only the triangle limit does.
        if (a.count > maxElements()) {
            *e = what + " has " + std::to_string(a.count) + " elements, more than the " + std::to_string(maxElements()) +
                 " that the triangle limit allows (3 per triangle); raise it with --max-triangles, or the file is damaged";
            return false;
        }
        const size_t elem = size_t(csize) * size_t(comps);
        if (a.bufferView >= 0 && a.count > 0) {
            const unsigned char *data = nullptr;
            size_t size = 0;
            if (!viewData(a.bufferView, what, &data, &size, e)) return false;
            const int strideInt = a.ByteStride(model.bufferViews[size_t(a.bufferView)]);
            if (strideInt <= 0) {
                *e = what + " has an invalid byte stride";
                return false;
            }
            const size_t stride = size_t(strideInt);
            // need = byteOffset + stride (count - 1) + elem, compared without overflowing.
            const bool fits = a.byteOffset <= size && elem <= size - a.byteOffset &&
                              a.count - 1 <= (size - a.byteOffset - elem) / stride;
            if (!fits) {
                *e = what + " reads past the end of its buffer view or buffer (" + std::to_string(a.count) +
                     " elements); the file is truncated or inconsistent";
                return false;
            }
            out->assign(a.count * size_t(comps), 0.0);
            const unsigned char *base = data + a.byteOffset;
            for (size_t i = 0; i < a.count; ++i)
                for (int c = 0; c < comps; ++c)
                    (*out)[i * size_t(comps) + size_t(c)] =
                        componentValue(a.componentType, a.normalized, base + i * stride + size_t(c) * size_t(csize));
        } else {
            out->assign(a.count * size_t(comps), 0.0);
        }
        if (!a.sparse.isSparse) return true;

        // Sparse substitution (glTF 2.0, "Sparse Accessors"): `count` indices (unsigned, tightly
        // packed) and as many elements (tightly packed, the accessor's type), each index < a.count.
        const auto &sp = a.sparse;
        if (sp.count < 0 || size_t(sp.count) > a.count) {
            *e = what + " is sparse with " + std::to_string(sp.count) + " substituted elements, outside 0.." +
                 std::to_string(a.count) + " (its count); the file is damaged";
            return false;
        }
        const int isize = tinygltf::GetComponentSizeInBytes(uint32_t(sp.indices.componentType));
        if (sp.indices.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
            sp.indices.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
            sp.indices.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT) {
            *e = what + ": sparse indices must be unsigned byte, short or int";
            return false;
        }
        const unsigned char *idata = nullptr, *vdata = nullptr;
        size_t isz = 0, vsz = 0;
        if (!viewData(sp.indices.bufferView, what + " sparse indices", &idata, &isz, e) ||
            !viewData(sp.values.bufferView, what + " sparse values", &vdata, &vsz, e))
            return false;
        const size_t n = size_t(sp.count);
        if (sp.indices.byteOffset < 0 || size_t(sp.indices.byteOffset) > isz ||
            n > (isz - size_t(sp.indices.byteOffset)) / size_t(isize) || sp.values.byteOffset < 0 ||
            size_t(sp.values.byteOffset) > vsz || n > (vsz - size_t(sp.values.byteOffset)) / elem) {
            *e = what + ": its sparse indices or values (" + std::to_string(n) +
                 ") read past the end of their buffer views; the file is truncated or inconsistent";
            return false;
        }
        idata += sp.indices.byteOffset;
        vdata += sp.values.byteOffset;
        for (size_t k = 0; k < n; ++k) {
            const uint64_t i = uint64_t(componentValue(sp.indices.componentType, false, idata + k * size_t(isize)));
            if (i >= a.count) {
                *e = what + ": sparse index " + std::to_string(i) + " (substitution " + std::to_string(k) +
                     ") is out of range: the accessor has " + std::to_string(a.count) + " elements; the file is damaged";
                return false;
            }
            for (int c = 0; c < comps; ++c)
                (*out)[i * size_t(comps) + size_t(c)] =
                    componentValue(a.componentType, a.normalized, vdata + k * elem + size_t(c) * size_t(csize));
        }
        return true;
    }

    void mapMaterials() {
        out->materials.push_back(Material{});  // 0: default, for primitives without a material
        for (size_t i = 0; i < model.materials.size(); ++i) {
            const auto &gm = model.materials[i];
            Material m;
            m.name = gm.name.empty() ? "material" + std::to_string(i) : gm.name;
            m.doubleSided = gm.doubleSided;
            const auto &pbr = gm.pbrMetallicRoughness;
            const double factorAlpha = pbr.baseColorFactor.size() == 4 ? pbr.baseColorFactor[3] : 1.0;
            // Transparency: BLEND is transparent, with alpha = baseColorFactor[3]. A BLEND material
            // whose factor is 1 takes its transparency from a texture, which visaudit does not read: it
            // stays opaque (alpha 1) and a warning says so. MASK is alpha-tested, which writes depth like
            // opaque geometry: opaque -- unless its factor alone is below alphaCutoff, when every
            // fragment is discarded whatever the texture (alpha = factor * texel <= factor): the surface
            // is drawn and never seen, alpha 0.
            if (gm.alphaMode == "BLEND") {
                m.alpha = std::clamp(factorAlpha, 0.0, 1.0);
                if (!(m.alpha < 1))
                    out->warnings.push_back(path + ": material '" + m.name +
                                            "' is alphaMode BLEND with baseColorFactor alpha 1 (its transparency "
                                            "would come from a texture, which visaudit does not read): treated as opaque");
            } else if (gm.alphaMode == "MASK" && factorAlpha < gm.alphaCutoff) {
                m.alpha = 0;
            }
            // Mirror-like reflection needs a metallic and smooth surface: reflective =
            // metallicFactor * (1 - roughnessFactor). (glTF's defaults, metallic 1 and roughness 1, give 0.)
            m.reflective = std::clamp(pbr.metallicFactor * (1 - pbr.roughnessFactor), 0.0, 1.0);
            // Refraction: KHR_materials_transmission with transmissionFactor > 0; the ior comes from
            // KHR_materials_ior (its default is 1.5). An ior without transmission only changes the
            // specular reflectance, so it does not make the material refractive.
            auto tr = gm.extensions.find("KHR_materials_transmission");
            if (tr != gm.extensions.end() && tr->second.Has("transmissionFactor") &&
                tr->second.Get("transmissionFactor").GetNumberAsDouble() > 0) {
                m.ior = 1.5;
                auto io = gm.extensions.find("KHR_materials_ior");
                if (io != gm.extensions.end() && io->second.Has("ior")) m.ior = io->second.Get("ior").GetNumberAsDouble();
            }
            materialIndex.push_back(uint32_t(out->materials.size()));
            out->materials.push_back(m);
        }
    }

    // The triangles a primitive declares (from its index accessor's count, or its vertices' without
    // one), before anything is read.
    uint64_t declaredTriangles(int meshIdx, size_t primIdx, int mode) const {
        const auto &prim = model.meshes[size_t(meshIdx)].primitives[primIdx];
        int counted = prim.indices;
        auto draco = source.dracoIndices.find({meshIdx, int(primIdx)});
        if (draco != source.dracoIndices.end()) counted = draco->second;
        if (counted < 0) {
            auto pos = prim.attributes.find("POSITION");
            counted = pos == prim.attributes.end() ? -1 : pos->second;
        }
        if (counted < 0 || size_t(counted) >= model.accessors.size()) return 0;
        const uint64_t n = model.accessors[size_t(counted)].count;
        return mode == TINYGLTF_MODE_TRIANGLES ? n / 3 : n >= 3 ? n - 2 : 0;
    }

    // A KHR_draco_mesh_compression primitive's positions, skin attributes and faces (decoded once per
    // buffer view).
    bool readDraco(const tinygltf::Primitive &prim, const Value &ext, int meshIdx, size_t primIdx, int posAccessor,
                   PrimitiveGeometry *g, std::string *e) {
        int64_t bv = -1, posId = -1;
        const bool hasAttributes = ext.Has("attributes") && ext.Get("attributes").IsObject();
        if (!intMember(ext, "bufferView", &bv) || !hasAttributes ||
            !intMember(ext.Get("attributes"), "POSITION", &posId)) {
            *e = "KHR_draco_mesh_compression needs bufferView and attributes.POSITION (integers)";
            return false;
        }
        if (bv < 0 || bv > INT32_MAX) bv = -1;
        // What to take from the Draco data: POSITION, and the skin's JOINTS_n / WEIGHTS_n it holds.
        const Value &attrs = ext.Get("attributes");
        std::map<std::string, std::pair<int, int>> ids;
        ids["POSITION"] = {int(std::clamp<int64_t>(posId, -1, INT32_MAX)), 3};
        for (const std::string &name : attrs.Keys()) {
            int64_t id = -1;
            if ((name.rfind("JOINTS_", 0) == 0 || name.rfind("WEIGHTS_", 0) == 0) && intMember(attrs, name.c_str(), &id))
                ids[name] = {int(std::clamp<int64_t>(id, -1, INT32_MAX)), 4};
        }
        auto cached = dracoViews.find(int(bv));
        if (cached == dracoViews.end()) {
            const unsigned char *data = nullptr;
            size_t size = 0;
            if (!viewData(int(bv), "KHR_draco_mesh_compression", &data, &size, e)) return false;
            if (size < model.bufferViews[size_t(bv)].byteLength) {
                *e = "KHR_draco_mesh_compression: buffer view " + std::to_string(bv) +
                     " lies past the end of its buffer; the file is truncated or inconsistent";
                return false;
            }
            gltf::DracoMesh dm;
            std::string de;
            if (!gltf::decodeDraco(data, size, ids, &dm, &de)) {
                *e = "KHR_draco_mesh_compression (buffer view " + std::to_string(bv) + "): " + de;
                return false;
            }
            cached = dracoViews.emplace(int(bv), std::move(dm)).first;
        }
        const gltf::DracoMesh &dm = cached->second;
        // The accessors describe the decoded data (KHR_draco_mesh_compression, "Conformance"): their
        // counts must be what libdraco decoded.
        const auto &pa = model.accessors[size_t(posAccessor)];
        const size_t points = dm.points, corners = dm.indices.size();
        if (pa.count != points) {
            *e = "KHR_draco_mesh_compression decoded " + std::to_string(points) + " points, but POSITION accessor " +
                 std::to_string(posAccessor) + " declares " + std::to_string(pa.count) + "; the file is inconsistent";
            return false;
        }
        auto ind = source.dracoIndices.find({meshIdx, int(primIdx)});
        if (ind != source.dracoIndices.end() && size_t(ind->second) < model.accessors.size() &&
            model.accessors[size_t(ind->second)].count != corners) {
            *e = "KHR_draco_mesh_compression decoded " + std::to_string(corners / 3) + " triangles (" +
                 std::to_string(corners) + " indices), but indices accessor " + std::to_string(ind->second) +
                 " declares " + std::to_string(model.accessors[size_t(ind->second)].count) +
                 " indices; the file is inconsistent";
            return false;
        }
        // An attribute's values as its accessor reads them: normalized integers mapped as componentValue.
        auto values = [&](const std::string &name, int accessor, std::vector<double> *out) {
            const gltf::DracoAttribute &da = dm.attributes.at(name);
            *out = da.values;
            const tinygltf::Accessor *acc =
                accessor >= 0 && size_t(accessor) < model.accessors.size() ? &model.accessors[size_t(accessor)] : nullptr;
            if (da.integer && acc && acc->normalized)
                for (double &v : *out) v = normalizedValue(acc->componentType, v);
        };
        std::vector<double> p;
        values("POSITION", posAccessor, &p);
        g->positions.resize(points);
        for (size_t i = 0; i < points; ++i) g->positions[i] = {p[3 * i], p[3 * i + 1], p[3 * i + 2]};
        for (int set = 0;; ++set) {
            const std::string j = "JOINTS_" + std::to_string(set), w = "WEIGHTS_" + std::to_string(set);
            if (!dm.attributes.count(j) || !dm.attributes.count(w)) break;
            g->joints.emplace_back();
            g->weights.emplace_back();
            auto ja = prim.attributes.find(j), wa = prim.attributes.find(w);
            values(j, ja == prim.attributes.end() ? -1 : ja->second, &g->joints.back());
            values(w, wa == prim.attributes.end() ? -1 : wa->second, &g->weights.back());
        }
        g->order = dm.indices;
        g->mode = TINYGLTF_MODE_TRIANGLES;  // Draco holds faces, whatever the primitive's mode
        return true;
    }

    // Reads one primitive's geometry in mesh space. Out-of-range indices are refused (the file is
    // damaged), as OBJ and PLY indices are, naming the first one.
    bool readPrimitive(int meshIdx, size_t primIdx, int mode, bool skinned, const std::string &where,
                       PrimitiveGeometry *g) {
        const auto &prim = model.meshes[size_t(meshIdx)].primitives[primIdx];
        auto pos = prim.attributes.find("POSITION");
        if (pos == prim.attributes.end()) {
            err = where + "has no POSITION attribute";
            return false;
        }
        std::string e;
        if (const Value *draco = extension(prim.extensions, "KHR_draco_mesh_compression")) {
            if (pos->second < 0 || size_t(pos->second) >= model.accessors.size()) {
                err = where + "POSITION accessor " + std::to_string(pos->second) + " does not exist";
                return false;
            }
            if (!readDraco(prim, *draco, meshIdx, primIdx, pos->second, g, &e)) {
                err = where + e;
                return false;
            }
        } else {
            std::vector<double> p;
            if (!readAccessor(pos->second, 3, &p, &e)) {
                err = where + "POSITION " + e;
                return false;
            }
            g->positions.resize(p.size() / 3);
            for (size_t i = 0; i < g->positions.size(); ++i) g->positions[i] = {p[3 * i], p[3 * i + 1], p[3 * i + 2]};
            g->mode = mode;
            if (prim.indices >= 0) {
                const auto &ia = model.accessors.size() > size_t(prim.indices) ? model.accessors[size_t(prim.indices)]
                                                                                : tinygltf::Accessor();
                if (ia.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
                    ia.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
                    ia.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT) {
                    err = where + "indices must be unsigned byte, short or int";
                    return false;
                }
                std::vector<double> idx;
                if (!readAccessor(prim.indices, 1, &idx, &e)) {
                    err = where + "indices " + e;
                    return false;
                }
                g->order.resize(idx.size());
                for (size_t i = 0; i < idx.size(); ++i) g->order[i] = uint32_t(idx[i]);
            } else {
                g->order.resize(g->positions.size());
                for (size_t i = 0; i < g->order.size(); ++i) g->order[i] = uint32_t(i);
            }
            // A skinned node's joints and weights: JOINTS_0 / WEIGHTS_0, then _1, ... while both exist.
            for (int set = 0; skinned; ++set) {
                auto ja = prim.attributes.find("JOINTS_" + std::to_string(set));
                auto wa = prim.attributes.find("WEIGHTS_" + std::to_string(set));
                if (ja == prim.attributes.end() || wa == prim.attributes.end()) break;
                g->joints.emplace_back();
                g->weights.emplace_back();
                if (!readAccessor(ja->second, 4, &g->joints.back(), &e)) {
                    err = where + "JOINTS_" + std::to_string(set) + " " + e;
                    return false;
                }
                if (!readAccessor(wa->second, 4, &g->weights.back(), &e)) {
                    err = where + "WEIGHTS_" + std::to_string(set) + " " + e;
                    return false;
                }
            }
        }
        const size_t nv = g->positions.size();
        for (size_t set = 0; set < g->joints.size(); ++set)
            if (g->joints[set].size() != 4 * nv || g->weights[set].size() != 4 * nv) {
                err = where + "JOINTS_" + std::to_string(set) + " or WEIGHTS_" + std::to_string(set) +
                      " does not have one element per vertex (" + std::to_string(nv) + "); the file is inconsistent";
                return false;
            }
        if (nv > std::numeric_limits<uint32_t>::max()) {
            err = where + "more than 2^32 - 1 vertices";
            return false;
        }
        for (size_t i = 0; i < g->order.size(); ++i)
            if (g->order[i] >= nv) {
                const auto draco = source.dracoIndices.find({meshIdx, int(primIdx)});
                const std::string acc = draco != source.dracoIndices.end() ? "the Draco data"
                                        : prim.indices >= 0 ? "indices accessor " + std::to_string(prim.indices)
                                                            : "the vertex order";
                err = where + acc + ": index " + std::to_string(g->order[i]) + " (element " + std::to_string(i) +
                      ") is out of range: POSITION accessor " + std::to_string(pos->second) + " has " +
                      std::to_string(nv) + " vertices; the file is damaged";
                return false;
            }
        return true;
    }

    // Fills `m` with a primitive's triangles over `positions` (world space, one per vertex). A
    // mirroring transform (negative determinant) turns counter-clockwise into clockwise: where
    // `mirrored` says so at a triangle's first corner, two corners are swapped so the front face stays
    // counter-clockwise (glTF 2.0, "Transformations").
    void fillTriangles(const PrimitiveGeometry &g, std::vector<Vec3> positions, const std::vector<char> &mirrored,
                       const std::string &where, RawMesh *m) {
        m->positions = std::move(positions);
        const auto &order = g.order;
        auto addTri = [&](uint32_t a, uint32_t b, uint32_t c) {
            const bool flip = mirrored[a];
            ++m->facesRead;
            m->indices.push_back(a);
            m->indices.push_back(flip ? c : b);
            m->indices.push_back(flip ? b : c);
        };
        // Triangle lists, strips and fans as glTF 2.0 defines their triangles.
        if (g.mode == TINYGLTF_MODE_TRIANGLES) {
            m->indices.reserve(order.size() / 3 * 3);
            for (size_t i = 0; i + 2 < order.size(); i += 3) addTri(order[i], order[i + 1], order[i + 2]);
            if (order.size() % 3 != 0) {
                ++m->facesDropped;
                m->warnings.push_back(where + std::to_string(order.size() % 3) + " trailing index(es) ignored");
            }
        } else if (g.mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
            for (size_t i = 0; i + 2 < order.size(); ++i)
                addTri(order[i], order[i + 1 + i % 2], order[i + 2 - i % 2]);
        } else {
            for (size_t i = 1; i + 1 < order.size(); ++i) addTri(order[i], order[i + 1], order[0]);
        }
    }

    // Appends a primitive's triangles, placed by `world`, as a source object.
    void emit(const PrimitiveGeometry &g, const Mat4 &world, const std::string &name, uint32_t material,
              const std::string &where) {
        SceneBuildInput::Object o;
        o.name = name;
        o.mesh = path;
        o.material = material;
        std::vector<Vec3> positions(g.positions.size());
        for (size_t i = 0; i < g.positions.size(); ++i) positions[i] = transformPoint(world, g.positions[i]);
        fillTriangles(g, std::move(positions), std::vector<char>(g.positions.size(), det3(world) < 0), where, &o.geometry);
        out->objects.push_back(std::move(o));
    }

    // EXT_mesh_gpu_instancing: the node's instances, world_i = node world * T_i * R_i * S_i (the
    // instance transform acts in the node's space), each named NODE[i]. Without the extension, the
    // node itself.
    bool placements(int nodeIdx, const Mat4 &world, std::vector<Placement> *pl) {
        const auto &n = model.nodes[size_t(nodeIdx)];
        const Value *inst = extension(n.extensions, "EXT_mesh_gpu_instancing");
        if (!inst) {
            pl->push_back({world, nodeName(nodeIdx)});
            return true;
        }
        const std::string where = path + ": node '" + nodeName(nodeIdx) + "': EXT_mesh_gpu_instancing ";
        if (!inst->Has("attributes") || !inst->Get("attributes").IsObject()) {
            err = where + "has no attributes object";
            return false;
        }
        const Value &attrs = inst->Get("attributes");
        std::vector<double> t, r, s;
        const char *names[3] = {"TRANSLATION", "ROTATION", "SCALE"};
        std::vector<double> *vals[3] = {&t, &r, &s};
        const int comps[3] = {3, 4, 3};
        int64_t count = -1;
        std::string e;
        for (int k = 0; k < 3; ++k) {
            int64_t a = -1;
            if (!attrs.Has(names[k])) continue;
            if (!intMember(attrs, names[k], &a) || a < 0 || a > INT32_MAX) {
                err = where + names[k] + " is not an accessor index";
                return false;
            }
            if (!readAccessor(int(a), comps[k], vals[k], &e)) {
                err = where + names[k] + " " + e;
                return false;
            }
            const int64_t c = int64_t(vals[k]->size() / size_t(comps[k]));
            if (count >= 0 && c != count) {
                err = where + names[k] + " has " + std::to_string(c) + " elements, the other attributes " +
                      std::to_string(count) + "; every attribute has one element per instance";
                return false;
            }
            count = c;
        }
        if (count < 0) {
            err = where + "has none of TRANSLATION, ROTATION, SCALE";
            return false;
        }
        const std::string base = nodeName(nodeIdx);
        pl->reserve(size_t(count));
        for (int64_t i = 0; i < count; ++i) {
            const size_t k = size_t(i);
            Mat4 ti, ri, si;
            if (!t.empty()) ti = Mat4::translate({t[3 * k], t[3 * k + 1], t[3 * k + 2]});
            if (!r.empty()) ri = rotationMatrix(r[4 * k], r[4 * k + 1], r[4 * k + 2], r[4 * k + 3]);
            if (!s.empty()) si = Mat4::scale({s[3 * k], s[3 * k + 1], s[3 * k + 2]});
            pl->push_back({world * (ti * ri * si), base + "[" + std::to_string(i) + "]"});
        }
        return true;
    }

    // A node's mesh: every primitive, at every placement.
    bool addMesh(int nodeIdx, const Mat4 &world) {
        const auto &n = model.nodes[size_t(nodeIdx)];
        if (size_t(n.mesh) >= model.meshes.size()) {
            err = path + ": node '" + nodeName(nodeIdx) + "' refers to mesh " + std::to_string(n.mesh) + ", which does not exist";
            return false;
        }
        const bool skinned = n.skin >= 0;
        if (skinned && (size_t(n.skin) >= model.skins.size())) {
            err = path + ": node '" + nodeName(nodeIdx) + "' refers to skin " + std::to_string(n.skin) + ", which does not exist";
            return false;
        }
        if (skinned && extension(n.extensions, "EXT_mesh_gpu_instancing")) {
            err = path + ": node '" + nodeName(nodeIdx) +
                  "' has both a skin and EXT_mesh_gpu_instancing, which visaudit does not combine; export the "
                  "instances as nodes of their own";
            return false;
        }
        std::vector<Placement> pl;
        if (!placements(nodeIdx, world, &pl)) return false;
        const auto &mesh = model.meshes[size_t(n.mesh)];
        for (size_t p = 0; p < mesh.primitives.size(); ++p) {
            const auto &prim = mesh.primitives[p];
            const std::string where = path + ": mesh " + std::to_string(n.mesh) + " primitive " + std::to_string(p) +
                                      " (node '" + nodeName(nodeIdx) + "'): ";
            const int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
            if (mode == TINYGLTF_MODE_POINTS || mode == TINYGLTF_MODE_LINE || mode == TINYGLTF_MODE_LINE_LOOP ||
                mode == TINYGLTF_MODE_LINE_STRIP) {
                skippedPrimitives += pl.size();
                continue;
            }
            if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
                mode != TINYGLTF_MODE_TRIANGLE_FAN) {
                err = where + "unknown primitive mode " + std::to_string(mode);
                return false;
            }
            // The primitive's triangles from its accessors' declared counts, times its instances,
            // checked with every primitive so far before anything is read: a small file may instance
            // a large mesh many times.
            const uint64_t tris = declaredTriangles(n.mesh, p, mode);
            const uint64_t all = pl.size() > 0 && tris > UINT64_MAX / pl.size() ? UINT64_MAX : tris * pl.size();
            triangles += std::min<uint64_t>(all, UINT64_MAX - triangles);
            if (!checkTriangleLimit(triangles, maxTriangles, where + "the scene up to this primitive", &err))
                return false;
            PrimitiveGeometry g;
            if (!readPrimitive(n.mesh, p, mode, skinned, where, &g)) return false;
            // Draco data without an index accessor declares no triangle count: count what it decoded.
            const uint64_t decoded = g.mode == TINYGLTF_MODE_TRIANGLES ? g.order.size() / 3
                                     : g.order.size() >= 3 ? g.order.size() - 2 : 0;
            if (decoded > tris) {
                const uint64_t more = (decoded - tris) * pl.size();
                triangles += std::min<uint64_t>(more, UINT64_MAX - triangles);
                if (!checkTriangleLimit(triangles, maxTriangles, where + "the scene up to this primitive", &err))
                    return false;
            }
            const uint32_t material =
                prim.material >= 0 && size_t(prim.material) < materialIndex.size() ? materialIndex[size_t(prim.material)] : 0;
            if (skinned) {
                // Its object now, at its place in the walk; its triangles once every joint is placed.
                SceneBuildInput::Object o;
                o.name = mesh.primitives.size() > 1 ? pl[0].name + "/" + std::to_string(p) : pl[0].name;
                o.mesh = path;
                o.material = material;
                skinnedPrimitives.push_back({out->objects.size(), nodeIdx, n.skin,
                                             std::make_shared<const PrimitiveGeometry>(std::move(g)), where});
                out->objects.push_back(std::move(o));
                continue;
            }
            for (const Placement &at : pl)
                emit(g, at.world, mesh.primitives.size() > 1 ? at.name + "/" + std::to_string(p) : at.name, material, where);
        }
        return true;
    }

    // A node's world transform outside the walk (a joint not in the loaded scene): its ancestors'
    // local transforms up to a root, climbed without recursion.
    bool worldOf(int nodeIdx, Mat4 *world) {
        if (parents.empty()) {
            parents.assign(model.nodes.size(), -1);
            for (size_t i = 0; i < model.nodes.size(); ++i)
                for (int c : model.nodes[i].children)
                    if (c >= 0 && size_t(c) < parents.size() && parents[size_t(c)] < 0) parents[size_t(c)] = int(i);
        }
        Mat4 w = Mat4::identity();
        size_t steps = 0;
        for (int i = nodeIdx; i >= 0; i = parents[size_t(i)]) {
            if (++steps > model.nodes.size()) {
                err = path + ": node '" + nodeName(nodeIdx) + "' has a cycle among its ancestors";
                return false;
            }
            w = nodeLocalMatrix(model.nodes[size_t(i)]) * w;
        }
        *world = w;
        return true;
    }

    // Skinning at rest (glTF 2.0, "Skins"): a vertex is at sum_k w_k J_k B_k v, J_k the world transform
    // of its k-th joint, B_k that joint's inverse bind matrix; the node's own transform is not used.
    // Weights are divided by their sum (glTF requires it to be 1; three.js divides too). A vertex whose
    // weights are all zero (an invalid file) follows its first joint (JOINTS_0's first) with weight 1,
    // as three.js does, and a warning counts such vertices. (Blender's exporter writes skinned vertices
    // in world space with J B = identity, so the node's transform would place them twice: the castle
    // dungeon's switch, whose base has no weights, was drawn a third of its size 7 units away.)
    bool applySkins() {
        std::map<int, std::vector<Mat4>> skinMatrices;  // skin -> J_k B_k
        for (const SkinnedPrimitive &sp : skinnedPrimitives) {
            const auto &skin = model.skins[size_t(sp.skin)];
            const std::string sw = sp.where + "skin " + std::to_string(sp.skin) + ": ";
            auto sm = skinMatrices.find(sp.skin);
            if (sm == skinMatrices.end()) {
                std::vector<double> ibm;
                std::string e;
                if (skin.inverseBindMatrices >= 0 && !readAccessor(skin.inverseBindMatrices, 16, &ibm, &e)) {
                    err = sw + "inverseBindMatrices " + e;
                    return false;
                }
                if (skin.inverseBindMatrices >= 0 && ibm.size() < 16 * skin.joints.size()) {
                    err = sw + "inverseBindMatrices has " + std::to_string(ibm.size() / 16) + " matrices for " +
                          std::to_string(skin.joints.size()) + " joints; the file is inconsistent";
                    return false;
                }
                std::vector<Mat4> m(skin.joints.size());
                for (size_t k = 0; k < skin.joints.size(); ++k) {
                    const int j = skin.joints[k];
                    if (j < 0 || size_t(j) >= model.nodes.size()) {
                        err = sw + "joint " + std::to_string(k) + " is node " + std::to_string(j) + ", which does not exist";
                        return false;
                    }
                    Mat4 jw;
                    auto walked = jointWorlds.find(j);
                    if (walked != jointWorlds.end()) jw = walked->second;
                    else if (!worldOf(j, &jw)) return false;
                    Mat4 b;  // column-major in the file
                    if (!ibm.empty())
                        for (int c = 0; c < 4; ++c)
                            for (int r = 0; r < 4; ++r) b.m[r][c] = ibm[16 * k + size_t(c * 4 + r)];
                    m[k] = jw * b;
                }
                sm = skinMatrices.emplace(sp.skin, std::move(m)).first;
            }
            const std::vector<Mat4> &jm = sm->second;
            const PrimitiveGeometry &g = *sp.geometry;
            const size_t nv = g.positions.size();
            std::vector<Vec3> positions(nv);
            std::vector<char> mirrored(nv);
            uint64_t unweighted = 0;
            for (size_t v = 0; v < nv; ++v) {
                Mat4 sum;
                for (auto &row : sum.m)
                    for (double &x : row) x = 0;
                double total = 0;
                for (size_t set = 0; set < g.joints.size(); ++set)
                    for (size_t c = 0; c < 4; ++c) {
                        const double w = g.weights[set][4 * v + c], j = g.joints[set][4 * v + c];
                        if (w == 0) continue;
                        if (!(j >= 0 && j < double(jm.size()) && std::floor(j) == j)) {
                            const bool integral = std::floor(j) == j && std::fabs(j) < 9.0e15;
                            err = sw + "JOINTS_" + std::to_string(set) + " of vertex " + std::to_string(v) + " is " +
                                  (integral ? std::to_string(int64_t(j)) : std::to_string(j)) +
                                  ", not one of the skin's " + std::to_string(jm.size()) +
                                  " joints; the file is damaged";
                            return false;
                        }
                        total += w;
                        for (int r = 0; r < 4; ++r)
                            for (int k = 0; k < 4; ++k) sum.m[r][k] += w * jm[size_t(j)].m[r][k];
                    }
                if (total > 0 && std::isfinite(total)) {
                    for (auto &row : sum.m)
                        for (double &x : row) x /= total;
                } else {
                    const double j = g.joints.empty() ? 0 : g.joints[0][4 * v];
                    if (!(j >= 0 && j < double(jm.size()) && std::floor(j) == j)) {
                        err = sw + "vertex " + std::to_string(v) + " has no joint weight and no valid first joint; "
                                   "the file is damaged";
                        return false;
                    }
                    sum = jm[size_t(j)];
                    ++unweighted;
                }
                positions[v] = transformPoint(sum, g.positions[v]);
                mirrored[v] = det3(sum) < 0;
            }
            if (unweighted > 0)
                out->warnings.push_back(sw + std::to_string(unweighted) + " of " + std::to_string(nv) +
                                        " vertices have no joint weight (glTF requires weights summing to 1): each "
                                        "follows its first joint, as three.js does");
            fillTriangles(g, std::move(positions), mirrored, sp.where, &out->objects[sp.object].geometry);
        }
        return true;
    }

    bool addCamera(int nodeIdx, const Mat4 &world) {
        const int ci = model.nodes[size_t(nodeIdx)].camera;
        if (ci < 0 || size_t(ci) >= model.cameras.size()) {
            err = path + ": node '" + nodeName(nodeIdx) + "' refers to camera " + std::to_string(ci) + ", which does not exist";
            return false;
        }
        const auto &c = model.cameras[size_t(ci)];
        ViewSpec v;
        v.origin = "gltf camera";
        std::string base = !c.name.empty() ? c.name : nodeName(nodeIdx);
        v.name = base;
        for (int k = 2; viewNames.count(v.name); ++k) v.name = base + "_" + std::to_string(k);
        viewNames.insert(v.name);
        // The camera looks down its node's -Z with +Y up (glTF 2.0, "Cameras").
        CameraSpec &s = v.camera;
        s.eye = transformPoint(world, {0, 0, 0});
        const Vec3 dir = transformVector(world, {0, 0, -1});
        s.target = s.eye + dir;
        s.up = transformVector(world, {0, 1, 0});
        s.height = 1080;
        s.width = 1920;
        double aspect = 0;
        if (c.type == "orthographic") {
            s.orthographic = true;
            s.orthoHeight = 2 * c.orthographic.ymag;
            s.nearZ = c.orthographic.znear;
            s.farZ = c.orthographic.zfar;
            if (c.orthographic.ymag != 0) aspect = c.orthographic.xmag / c.orthographic.ymag;
            // An orthographic depth range may start at 0; visaudit's cameras need near > 0.
            if (s.nearZ == 0) s.nearZ = s.farZ * 1e-6;
        } else {
            s.fovYDegrees = c.perspective.yfov * 180 / kPi;
            s.nearZ = c.perspective.znear;
            // zfar absent means an infinite projection; visaudit's depth formats need a finite far:
            // use 1e6 * near, the far/near ratio beyond which 24-bit depth resolves nothing more.
            s.farZ = c.perspective.zfar > 0 ? c.perspective.zfar : s.nearZ * 1e6;
            aspect = c.perspective.aspectRatio;
        }
        if (aspect > 0 && std::isfinite(aspect)) s.width = std::clamp(int(std::lround(1080 * aspect)), 1, 16384);
        Camera cam;
        std::string e;
        if (!makeCamera(s, &cam, &e)) {
            err = path + ": camera " + std::to_string(ci) + " ('" + v.name + "') on node '" + nodeName(nodeIdx) + "': " + e;
            return false;
        }
        out->views.push_back(v);
        return true;
    }

    // KHR_lights_punctual: a node's light, placed by the node's world transform. A light shines down
    // its node's -Z (directional and spot); a point light sits at the node's origin. visaudit's lights
    // are directional or point: a spot light becomes a point light (its cone is ignored: it could only
    // make fewer points lit, never more), counted in a warning. Color, intensity and range are ignored
    // (shadow visibility does not depend on them; a finite range is noted in the docs).
    bool addLight(int nodeIdx, const Mat4 &world) {
        const auto &n = model.nodes[size_t(nodeIdx)];
        auto ext = n.extensions.find("KHR_lights_punctual");
        if (ext == n.extensions.end() || !ext->second.Has("light")) return true;
        const auto &lv = ext->second.Get("light");
        const int li = lv.IsNumber() || lv.IsInt() ? lv.GetNumberAsInt() : -1;
        if (li < 0 || size_t(li) >= model.lights.size()) {
            err = path + ": node '" + nodeName(nodeIdx) + "' refers to light " + std::to_string(li) +
                  ", which does not exist (KHR_lights_punctual.lights has " + std::to_string(model.lights.size()) + ")";
            return false;
        }
        const auto &gl = model.lights[size_t(li)];
        Light l;
        l.name = !gl.name.empty() ? gl.name : "light" + std::to_string(li);
        if (gl.type == "directional") {
            l.directional = true;
            const Vec3 d = transformVector(world, {0, 0, -1});
            if (!(length(d) > 0) || !isFinite(d)) {
                err = path + ": node '" + nodeName(nodeIdx) + "': directional light '" + l.name +
                      "' has a degenerate transform (its -Z axis maps to a zero or non-finite direction)";
                return false;
            }
            l.direction = normalize(d);
        } else if (gl.type == "point" || gl.type == "spot") {
            l.directional = false;
            l.position = transformPoint(world, {0, 0, 0});
            spotLights += gl.type == "spot";
        } else {
            err = path + ": light " + std::to_string(li) + " ('" + l.name + "') has unknown type '" + gl.type +
                  "'; KHR_lights_punctual defines directional, point and spot";
            return false;
        }
        out->lights.push_back(l);
        return true;
    }

    // Depth-first over the node hierarchy in file order, world = parent * local, with an explicit
    // stack (no recursion: a legal chain may be hundreds of thousands of nodes deep). A node is
    // entered at most once: a second entry is a cycle (it is its own ancestor) or a second parent,
    // which glTF 2.0 forbids and which would let a small file name exponentially many paths.
    bool walk(const std::vector<int> &roots) {
        struct Frame {
            int node;
            Mat4 world;
            size_t next = 0;  // the next child to enter
        };
        std::vector<char> entered(model.nodes.size(), 0), onPath(model.nodes.size(), 0);
        std::vector<Frame> stack;
        auto enter = [&](int nodeIdx, const Mat4 &parentWorld, int parent) {
            if (nodeIdx < 0 || size_t(nodeIdx) >= model.nodes.size()) {
                err = path + ": node " + std::to_string(nodeIdx) + " does not exist" +
                      (parent >= 0 ? " (a child of node '" + nodeName(parent) + "')" : " (a root of the scene)");
                return false;
            }
            if (onPath[size_t(nodeIdx)]) {
                err = path + ": node '" + nodeName(nodeIdx) + "' is its own ancestor (a cycle in the node hierarchy)";
                return false;
            }
            if (entered[size_t(nodeIdx)]) {
                err = path + ": node '" + nodeName(nodeIdx) + "' is reached a second time" +
                      (parent >= 0 ? " (as a child of node '" + nodeName(parent) + "')" : " (as a root of the scene)") +
                      "; glTF 2.0 gives a node at most one parent and lists a scene's roots once";
                return false;
            }
            entered[size_t(nodeIdx)] = onPath[size_t(nodeIdx)] = 1;
            const auto &n = model.nodes[size_t(nodeIdx)];
            const Mat4 world = parentWorld * nodeLocalMatrix(n);
            if (jointNodes.count(nodeIdx)) jointWorlds[nodeIdx] = world;
            if (n.mesh >= 0 && !addMesh(nodeIdx, world)) return false;
            if (n.camera >= 0 && !addCamera(nodeIdx, world)) return false;
            if (!addLight(nodeIdx, world)) return false;
            stack.push_back({nodeIdx, world, 0});
            return true;
        };
        for (int r : roots) {
            if (!enter(r, Mat4::identity(), -1)) return false;
            while (!stack.empty()) {
                Frame &f = stack.back();
                const auto &children = model.nodes[size_t(f.node)].children;
                if (f.next < children.size()) {
                    const int child = children[f.next++];
                    const Mat4 world = f.world;  // `f` may move when the stack grows
                    if (!enter(child, world, f.node)) return false;
                } else {
                    onPath[size_t(f.node)] = 0;
                    stack.pop_back();
                }
            }
        }
        return true;
    }

    std::string sceneName(size_t i) const {
        return model.scenes[i].name.empty() ? std::to_string(i) : std::to_string(i) + " '" + model.scenes[i].name + "'";
    }

    bool run() {
        mapMaterials();
        std::vector<int> roots;
        if (!model.scenes.empty()) {
            // The file's `scene`, else scene 0 (glTF 2.0 leaves the choice to the loader); the other
            // scenes are left out and a warning names them.
            const size_t ns = model.scenes.size();
            if (model.defaultScene < -1 || (model.defaultScene >= 0 && size_t(model.defaultScene) >= ns)) {
                err = path + ": \"scene\" is " + std::to_string(model.defaultScene) + ", but the file has " +
                      std::to_string(ns) + " scene(s) (0.." + std::to_string(ns - 1) + "); the file is damaged";
                return false;
            }
            const size_t si = model.defaultScene >= 0 ? size_t(model.defaultScene) : 0;
            roots = model.scenes[si].nodes;
            if (ns > 1) {
                std::string others;
                size_t listed = 0;
                for (size_t i = 0; i < ns; ++i) {
                    if (i == si) continue;
                    if (listed == 5) {
                        others += ", ...";
                        break;
                    }
                    others += (listed++ ? ", " : "") + sceneName(i);
                }
                out->warnings.push_back(path + ": loaded scene " + sceneName(si) +
                                        (model.defaultScene >= 0 ? " (the file's \"scene\")"
                                                                 : " (the file names no default \"scene\")") +
                                        " of " + std::to_string(ns) + "; left out " + std::to_string(ns - 1) +
                                        " other scene(s): " + others);
            }
        } else {
            // No scenes: every node that is nobody's child is a root.
            std::vector<char> isChild(model.nodes.size(), 0);
            for (const auto &n : model.nodes)
                for (int c : n.children)
                    if (c >= 0 && size_t(c) < isChild.size()) isChild[size_t(c)] = 1;
            for (size_t i = 0; i < model.nodes.size(); ++i)
                if (!isChild[i]) roots.push_back(int(i));
        }
        for (const auto &skin : model.skins) jointNodes.insert(skin.joints.begin(), skin.joints.end());
        if (!walk(roots)) return false;
        if (!applySkins()) return false;
        if (skippedPrimitives)
            out->warnings.push_back(path + ": " + std::to_string(skippedPrimitives) +
                                    " point/line primitive(s) skipped (they have no area)");
        if (spotLights)
            out->warnings.push_back(path + ": " + std::to_string(spotLights) +
                                    " KHR_lights_punctual spot light(s) read as point light(s) (the cone is ignored)");
        return true;
    }
};

}  // namespace

bool loadGltf(const std::string &path, SceneBuildInput *out, std::string *err, uint64_t maxTriangles,
              uint64_t maxJsonDepth) {
    auto fail = [&](const std::string &m) {
        if (err) *err = m;
        return false;
    };
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) return fail(path + ": file not found");
    std::string ext = std::filesystem::path(path).extension().string();
    for (auto &c : ext) c = char(std::tolower((unsigned char)c));

    // The file as tinygltf should see it, after the checks that must come before it parses.
    gltf::Source source;
    std::string e;
    if (!gltf::prepareSource(path, ext == ".glb", maxJsonDepth, &source, &e)) return fail(e);

    tinygltf::Model model;
    tinygltf::TinyGLTF gltf;
    gltf.SetImageLoader(ignoreImage, nullptr);
    std::string gerr, gwarn;
    bool ok = false;
    try {
        if (source.bytes.empty()) {
            gerr = "the file is empty";
        } else if (source.binary) {
            ok = gltf.LoadBinaryFromMemory(&model, &gerr, &gwarn, source.bytes.data(), unsigned(source.bytes.size()),
                                           source.baseDir);
        } else {
            ok = gltf.LoadASCIIFromString(&model, &gerr, &gwarn, reinterpret_cast<const char *>(source.bytes.data()),
                                          unsigned(source.bytes.size()), source.baseDir);
        }
    } catch (const std::exception &ex) {
        ok = false;
        gerr += ex.what();
    }
    source.bytes = {};  // tinygltf copied the buffers
    auto oneLine = [](std::string s) {
        for (auto &c : s)
            if (c == '\n' || c == '\r') c = ' ';
        while (!s.empty() && s.back() == ' ') s.pop_back();
        return s;
    };
    if (!ok)
        return fail(path + ": not a readable glTF 2.0 file: " + (gerr.empty() ? std::string("(tinygltf gave no reason)") : oneLine(gerr)));

    SceneBuildInput in;
    in.path = path;
    in.up = 'y';  // glTF is y-up
    for (auto &w : source.warnings) in.warnings.push_back(std::move(w));
    if (!gwarn.empty()) in.warnings.push_back(path + ": tinygltf: " + oneLine(gwarn));
    GltfLoader loader{path, model, source, &in, maxTriangles, {}, {}, {}, 0, 0, 0, {}, {}, {}, {}, {}, {}};
    if (!loader.run()) return fail(loader.err);
    *out = std::move(in);
    return true;
}

}  // namespace va
