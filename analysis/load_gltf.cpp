// glTF 2.0 (.gltf, .glb) through tinygltf: nodes -> source objects, cameras -> views,
// materials -> flags. The mapping is documented in docs/scene-format.md ("glTF").
//
// tinygltf is compiled here, in this one translation unit, without its stb_image dependency:
// visaudit never needs texels, so images are neither decoded (a custom loader callback accepts
// and ignores them) nor read from disk (TINYGLTF_NO_EXTERNAL_IMAGE): a level whose textures are
// missing still loads.
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
#include <set>

#include "analysis/load.h"

namespace va {
namespace {

bool ignoreImage(tinygltf::Image *, const int, std::string *, std::string *, int, int, const unsigned char *, int,
                 void *) {
    return true;
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
    if (n.rotation.size() == 4) {
        // Unit quaternion (x, y, z, w) to a rotation matrix.
        const double x = n.rotation[0], y = n.rotation[1], z = n.rotation[2], w = n.rotation[3];
        r.m[0][0] = 1 - 2 * (y * y + z * z); r.m[0][1] = 2 * (x * y - z * w);     r.m[0][2] = 2 * (x * z + y * w);
        r.m[1][0] = 2 * (x * y + z * w);     r.m[1][1] = 1 - 2 * (x * x + z * z); r.m[1][2] = 2 * (y * z - x * w);
        r.m[2][0] = 2 * (x * z - y * w);     r.m[2][1] = 2 * (y * z + x * w);     r.m[2][2] = 1 - 2 * (x * x + y * y);
    }
    return t * r * s;
}

double det3(const Mat4 &m) {
    return m.m[0][0] * (m.m[1][1] * m.m[2][2] - m.m[1][2] * m.m[2][1]) -
           m.m[0][1] * (m.m[1][0] * m.m[2][2] - m.m[1][2] * m.m[2][0]) +
           m.m[0][2] * (m.m[1][0] * m.m[2][1] - m.m[1][1] * m.m[2][0]);
}

// Reads accessor `index` as `count` elements of `comps` components each, converted to double
// (normalized integers mapped to [0, 1] or [-1, 1] as the glTF spec says). Every byte read is
// bounds-checked against its buffer view and buffer, and the count against maxElements, before the
// output is allocated: a hostile count is refused, not trusted.
bool readAccessor(const tinygltf::Model &model, int index, int comps, uint64_t maxElements, std::vector<double> *out,
                  std::string *err) {
    if (index < 0 || size_t(index) >= model.accessors.size()) {
        *err = "accessor " + std::to_string(index) + " does not exist";
        return false;
    }
    const auto &a = model.accessors[size_t(index)];
    const std::string what = "accessor " + std::to_string(index);
    if (a.sparse.isSparse) {
        *err = what + " is sparse, which visaudit does not support; export without sparse accessors";
        return false;
    }
    const int ncomp = tinygltf::GetNumComponentsInType(uint32_t(a.type));
    if (ncomp != comps) {
        *err = what + " has " + std::to_string(ncomp) + " components per element; expected " + std::to_string(comps);
        return false;
    }
    const int csize = tinygltf::GetComponentSizeInBytes(uint32_t(a.componentType));
    if (csize <= 0) {
        *err = what + " has an unknown component type " + std::to_string(a.componentType);
        return false;
    }
    // Without a buffer view an accessor is all zeros (glTF 2.0): no byte of the file bounds its
    // count, only the triangle limit does.
    if (a.count > maxElements) {
        *err = what + " has " + std::to_string(a.count) + " elements, more than the " + std::to_string(maxElements) +
               " that the triangle limit allows (3 per triangle); raise it with --max-triangles, or the file is damaged";
        return false;
    }
    if (a.bufferView < 0) {
        out->assign(a.count * size_t(comps), 0.0);
        return true;
    }
    if (size_t(a.bufferView) >= model.bufferViews.size()) {
        *err = what + " refers to buffer view " + std::to_string(a.bufferView) + ", which does not exist";
        return false;
    }
    const auto &bv = model.bufferViews[size_t(a.bufferView)];
    if (bv.buffer < 0 || size_t(bv.buffer) >= model.buffers.size()) {
        *err = what + ": buffer view " + std::to_string(a.bufferView) + " refers to a missing buffer";
        return false;
    }
    const auto &buf = model.buffers[size_t(bv.buffer)].data;
    const int strideInt = a.ByteStride(bv);
    if (strideInt <= 0) {
        *err = what + " has an invalid byte stride";
        return false;
    }
    const size_t stride = size_t(strideInt), elem = size_t(csize) * size_t(comps);
    if (a.count == 0) {
        out->clear();
        return true;
    }
    const size_t begin = bv.byteOffset + a.byteOffset;
    // need = byteOffset + stride (count - 1) + elem, compared without overflowing.
    const bool fits = a.byteOffset <= bv.byteLength && elem <= bv.byteLength - a.byteOffset &&
                      a.count - 1 <= (bv.byteLength - a.byteOffset - elem) / stride;
    if (!fits || bv.byteOffset > buf.size() || bv.byteLength > buf.size() - bv.byteOffset) {
        *err = what + " reads past the end of its buffer view or buffer (" + std::to_string(a.count) +
               " elements); the file is truncated or inconsistent";
        return false;
    }
    out->assign(a.count * size_t(comps), 0.0);
    const unsigned char *base = buf.data() + begin;
    for (size_t i = 0; i < a.count; ++i) {
        const unsigned char *p = base + i * stride;
        for (int c = 0; c < comps; ++c) {
            const unsigned char *q = p + size_t(c) * size_t(csize);
            double v = 0;
            switch (a.componentType) {
            case TINYGLTF_COMPONENT_TYPE_FLOAT: { float f; std::memcpy(&f, q, 4); v = f; break; }
            case TINYGLTF_COMPONENT_TYPE_DOUBLE: { double d; std::memcpy(&d, q, 8); v = d; break; }
            case TINYGLTF_COMPONENT_TYPE_BYTE: { int8_t x; std::memcpy(&x, q, 1); v = a.normalized ? std::max(x / 127.0, -1.0) : x; break; }
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: { uint8_t x = *q; v = a.normalized ? x / 255.0 : x; break; }
            case TINYGLTF_COMPONENT_TYPE_SHORT: { int16_t x; std::memcpy(&x, q, 2); v = a.normalized ? std::max(x / 32767.0, -1.0) : x; break; }
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: { uint16_t x; std::memcpy(&x, q, 2); v = a.normalized ? x / 65535.0 : x; break; }
            case TINYGLTF_COMPONENT_TYPE_INT: { int32_t x; std::memcpy(&x, q, 4); v = x; break; }
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: { uint32_t x; std::memcpy(&x, q, 4); v = x; break; }
            default: *err = what + " has an unsupported component type"; return false;
            }
            (*out)[i * size_t(comps) + size_t(c)] = v;
        }
    }
    return true;
}

struct GltfLoader {
    const std::string &path;
    const tinygltf::Model &model;
    SceneBuildInput *out;
    std::string err;
    std::vector<uint32_t> materialIndex;  // glTF material -> our material
    std::set<std::string> viewNames;
    uint64_t skippedPrimitives = 0;       // POINTS / LINES primitives
    uint64_t spotLights = 0;              // KHR_lights_punctual spot lights, read as point lights
    uint64_t maxTriangles = kDefaultMaxTriangles;  // --max-triangles, over every node's instances
    uint64_t triangles = 0;               // of the primitives added so far

    // Accessor elements a primitive may need within the triangle limit: 3 per triangle (a strip or
    // fan needs fewer).
    uint64_t maxElements() const { return maxTriangles > (UINT64_MAX - 2) / 3 ? UINT64_MAX : 3 * maxTriangles + 2; }

    std::string nodeName(int i) const {
        const auto &n = model.nodes[size_t(i)];
        return n.name.empty() ? "node" + std::to_string(i) : n.name;
    }

    void mapMaterials() {
        out->materials.push_back(Material{});  // 0: default, for primitives without a material
        for (size_t i = 0; i < model.materials.size(); ++i) {
            const auto &gm = model.materials[i];
            Material m;
            m.name = gm.name.empty() ? "material" + std::to_string(i) : gm.name;
            m.doubleSided = gm.doubleSided;
            const auto &pbr = gm.pbrMetallicRoughness;
            // Transparency: only BLEND is transparent, with alpha = baseColorFactor[3]. A BLEND material
            // whose factor is 1 takes its transparency from a texture, which visaudit does not read: it
            // stays opaque (alpha 1) and a warning says so. MASK is alpha-tested, which writes depth like
            // opaque geometry: opaque.
            if (gm.alphaMode == "BLEND") {
                const double a = pbr.baseColorFactor.size() == 4 ? pbr.baseColorFactor[3] : 1.0;
                m.alpha = std::clamp(a, 0.0, 1.0);
                if (!(m.alpha < 1))
                    out->warnings.push_back(path + ": material '" + m.name +
                                            "' is alphaMode BLEND with baseColorFactor alpha 1 (its transparency "
                                            "would come from a texture, which visaudit does not read): treated as opaque");
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

    // Appends the triangles of one primitive (world-space positions) as a source object.
    bool addPrimitive(int nodeIdx, const Mat4 &world, int meshIdx, size_t primIdx, const std::string &name) {
        const auto &prim = model.meshes[size_t(meshIdx)].primitives[primIdx];
        const std::string where = path + ": mesh " + std::to_string(meshIdx) + " primitive " + std::to_string(primIdx) +
                                  " (node '" + nodeName(nodeIdx) + "'): ";
        const int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
        if (mode == TINYGLTF_MODE_POINTS || mode == TINYGLTF_MODE_LINE || mode == TINYGLTF_MODE_LINE_LOOP ||
            mode == TINYGLTF_MODE_LINE_STRIP) {
            ++skippedPrimitives;
            return true;
        }
        if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP && mode != TINYGLTF_MODE_TRIANGLE_FAN) {
            err = where + "unknown primitive mode " + std::to_string(mode);
            return false;
        }
        auto pos = prim.attributes.find("POSITION");
        if (pos == prim.attributes.end()) {
            err = where + "has no POSITION attribute";
            return false;
        }
        // The primitive's triangles from its accessors' declared counts, checked with every instance
        // so far before anything is read: a small file may instance a large mesh many times.
        const int countedAccessor = prim.indices >= 0 ? prim.indices : pos->second;
        if (countedAccessor >= 0 && size_t(countedAccessor) < model.accessors.size()) {
            const uint64_t n = model.accessors[size_t(countedAccessor)].count;
            const uint64_t tris = mode == TINYGLTF_MODE_TRIANGLES ? n / 3 : n >= 3 ? n - 2 : 0;
            triangles += std::min<uint64_t>(tris, UINT64_MAX - triangles);
            if (!checkTriangleLimit(triangles, maxTriangles, where + "the scene up to this primitive", &err))
                return false;
        }
        std::vector<double> p, idx;
        std::string e;
        if (!readAccessor(model, pos->second, 3, maxElements(), &p, &e)) {
            err = where + "POSITION " + e;
            return false;
        }
        const size_t nv = p.size() / 3;
        if (nv > std::numeric_limits<uint32_t>::max()) {
            err = where + "more than 2^32 - 1 vertices";
            return false;
        }
        std::vector<uint32_t> order;  // vertex indices in primitive order
        if (prim.indices >= 0) {
            const auto &ia = model.accessors.size() > size_t(prim.indices) ? model.accessors[size_t(prim.indices)]
                                                                            : tinygltf::Accessor();
            if (ia.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
                ia.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
                ia.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT) {
                err = where + "indices must be unsigned byte, short or int";
                return false;
            }
            if (!readAccessor(model, prim.indices, 1, maxElements(), &idx, &e)) {
                err = where + "indices " + e;
                return false;
            }
            order.reserve(idx.size());
            for (double v : idx) order.push_back(uint32_t(v));
        } else {
            order.resize(nv);
            for (size_t i = 0; i < nv; ++i) order[i] = uint32_t(i);
        }

        SceneBuildInput::Object o;
        o.name = name;
        o.mesh = path;
        o.material = prim.material >= 0 && size_t(prim.material) < materialIndex.size() ? materialIndex[size_t(prim.material)] : 0;
        RawMesh &m = o.geometry;
        m.positions.resize(nv);
        for (size_t i = 0; i < nv; ++i) m.positions[i] = transformPoint(world, {p[3 * i], p[3 * i + 1], p[3 * i + 2]});
        // A mirroring world transform (negative determinant) turns counter-clockwise into clockwise:
        // swap two corners so the front face stays counter-clockwise (glTF 2.0, "Transformations").
        const bool flip = det3(world) < 0;
        uint64_t badIndex = 0;
        auto addTri = [&](uint32_t a, uint32_t b, uint32_t c) {
            ++m.facesRead;
            if (a >= nv || b >= nv || c >= nv) {
                ++m.facesDropped;
                ++badIndex;
                return;
            }
            m.indices.push_back(a);
            m.indices.push_back(flip ? c : b);
            m.indices.push_back(flip ? b : c);
        };
        // Triangle lists, strips and fans as glTF 2.0 defines their triangles.
        if (mode == TINYGLTF_MODE_TRIANGLES) {
            for (size_t i = 0; i + 2 < order.size(); i += 3) addTri(order[i], order[i + 1], order[i + 2]);
            if (order.size() % 3 != 0) {
                ++m.facesDropped;
                m.warnings.push_back(where + std::to_string(order.size() % 3) + " trailing index(es) ignored");
            }
        } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
            for (size_t i = 0; i + 2 < order.size(); ++i)
                addTri(order[i], order[i + 1 + i % 2], order[i + 2 - i % 2]);
        } else {
            for (size_t i = 1; i + 1 < order.size(); ++i) addTri(order[i], order[i + 1], order[0]);
        }
        if (badIndex > 0)
            m.warnings.push_back(where + std::to_string(badIndex) + " triangle(s) with out-of-range indices dropped");
        out->objects.push_back(std::move(o));
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

    // Depth-first over the node hierarchy in file order; world = parent * local.
    bool visit(int nodeIdx, const Mat4 &parent, std::vector<char> &onPath) {
        if (nodeIdx < 0 || size_t(nodeIdx) >= model.nodes.size()) {
            err = path + ": node " + std::to_string(nodeIdx) + " does not exist";
            return false;
        }
        if (onPath[size_t(nodeIdx)]) {
            err = path + ": node '" + nodeName(nodeIdx) + "' is its own ancestor (a cycle in the node hierarchy)";
            return false;
        }
        onPath[size_t(nodeIdx)] = 1;
        const auto &n = model.nodes[size_t(nodeIdx)];
        const Mat4 world = parent * nodeLocalMatrix(n);
        if (n.mesh >= 0) {
            if (size_t(n.mesh) >= model.meshes.size()) {
                err = path + ": node '" + nodeName(nodeIdx) + "' refers to mesh " + std::to_string(n.mesh) + ", which does not exist";
                return false;
            }
            const auto &mesh = model.meshes[size_t(n.mesh)];
            for (size_t p = 0; p < mesh.primitives.size(); ++p) {
                std::string name = nodeName(nodeIdx);
                if (mesh.primitives.size() > 1) name += "/" + std::to_string(p);
                if (!addPrimitive(nodeIdx, world, n.mesh, p, name)) return false;
            }
        }
        if (n.camera >= 0 && !addCamera(nodeIdx, world)) return false;
        if (!addLight(nodeIdx, world)) return false;
        for (int c : n.children)
            if (!visit(c, world, onPath)) return false;
        onPath[size_t(nodeIdx)] = 0;
        return true;
    }

    bool run() {
        mapMaterials();
        std::vector<int> roots;
        if (!model.scenes.empty()) {
            const int si = model.defaultScene >= 0 && size_t(model.defaultScene) < model.scenes.size() ? model.defaultScene : 0;
            roots = model.scenes[size_t(si)].nodes;
        } else {
            // No scenes: every node that is nobody's child is a root.
            std::vector<char> isChild(model.nodes.size(), 0);
            for (const auto &n : model.nodes)
                for (int c : n.children)
                    if (c >= 0 && size_t(c) < isChild.size()) isChild[size_t(c)] = 1;
            for (size_t i = 0; i < model.nodes.size(); ++i)
                if (!isChild[i]) roots.push_back(int(i));
        }
        std::vector<char> onPath(model.nodes.size(), 0);
        for (int r : roots)
            if (!visit(r, Mat4::identity(), onPath)) return false;
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

bool loadGltf(const std::string &path, SceneBuildInput *out, std::string *err, uint64_t maxTriangles) {
    auto fail = [&](const std::string &m) {
        if (err) *err = m;
        return false;
    };
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) return fail(path + ": file not found");
    std::string ext = std::filesystem::path(path).extension().string();
    for (auto &c : ext) c = char(std::tolower((unsigned char)c));

    tinygltf::Model model;
    tinygltf::TinyGLTF gltf;
    gltf.SetImageLoader(ignoreImage, nullptr);
    std::string gerr, gwarn;
    bool ok = false;
    try {
        ok = ext == ".glb" ? gltf.LoadBinaryFromFile(&model, &gerr, &gwarn, path)
                           : gltf.LoadASCIIFromFile(&model, &gerr, &gwarn, path);
    } catch (const std::exception &e) {
        ok = false;
        gerr += e.what();
    }
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
    if (!gwarn.empty()) in.warnings.push_back(path + ": tinygltf: " + oneLine(gwarn));
    GltfLoader loader{path, model, &in, {}, {}, {}, 0, 0, maxTriangles, 0};
    if (!loader.run()) return fail(loader.err);
    *out = std::move(in);
    return true;
}

}  // namespace va
