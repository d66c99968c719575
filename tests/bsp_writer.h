// A writer for minimal IBSP v46 files, for tests that build maps by hand (test_pvs_audit.cpp; the
// same records as test_bsp.cpp's writer, plus brushes, brush sides and leaf brushes).
#pragma once

#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <string>
#include <vector>

#include "render/math.h"

namespace va::testing_util {

enum BspLump {
    LEntities, LShaders, LPlanes, LNodes, LLeafs, LLeafFaces, LLeafBrushes, LModels, LBrushes, LBrushSides,
    LVertexes, LMeshVerts, LEffects, LFaces, LLightmaps, LLightVols, LVisData
};

struct BspWriter {
    std::vector<uint8_t> lump[17];
    void i32(int l, int32_t v) {
        uint32_t u = uint32_t(v);
        for (int k = 0; k < 4; ++k) lump[l].push_back(uint8_t(u >> (8 * k)));
    }
    void f32(int l, float f) {
        int32_t v;
        std::memcpy(&v, &f, 4);
        i32(l, v);
    }
    // Records are appended; each returns its index.
    int32_t count(int l, size_t bytes) const { return int32_t(lump[l].size() / bytes); }
    void entities(const std::string &text) {
        lump[LEntities].assign(text.begin(), text.end());
        lump[LEntities].push_back(0);
    }
    int32_t shader(const std::string &name, int32_t flags, int32_t contents) {
        const int32_t i = count(LShaders, 72);
        for (size_t k = 0; k < 64; ++k) lump[LShaders].push_back(k < name.size() ? uint8_t(name[k]) : 0);
        i32(LShaders, flags), i32(LShaders, contents);
        return i;
    }
    int32_t plane(Vec3 n, double d) {
        const int32_t i = count(LPlanes, 16);
        f32(LPlanes, float(n.x)), f32(LPlanes, float(n.y)), f32(LPlanes, float(n.z)), f32(LPlanes, float(d));
        return i;
    }
    // front: the side where dot(n, p) - d >= 0. A child >= 0 is a node, < 0 leaf -(child + 1).
    int32_t node(int32_t plane, int32_t front, int32_t back) {
        const int32_t i = count(LNodes, 36);
        i32(LNodes, plane), i32(LNodes, front), i32(LNodes, back);
        for (int k = 0; k < 6; ++k) i32(LNodes, 0);
        return i;
    }
    int32_t leaf(int32_t cluster, Vec3 lo, Vec3 hi, int32_t firstFace, int32_t nFaces, int32_t firstBrush = 0,
                 int32_t nBrushes = 0) {
        const int32_t i = count(LLeafs, 48);
        i32(LLeafs, cluster), i32(LLeafs, 0);
        i32(LLeafs, int32_t(lo.x)), i32(LLeafs, int32_t(lo.y)), i32(LLeafs, int32_t(lo.z));
        i32(LLeafs, int32_t(hi.x)), i32(LLeafs, int32_t(hi.y)), i32(LLeafs, int32_t(hi.z));
        i32(LLeafs, firstFace), i32(LLeafs, nFaces), i32(LLeafs, firstBrush), i32(LLeafs, nBrushes);
        return i;
    }
    void model(Vec3 lo, Vec3 hi, int32_t face, int32_t nFaces) {
        for (Vec3 v : {lo, hi}) f32(LModels, float(v.x)), f32(LModels, float(v.y)), f32(LModels, float(v.z));
        i32(LModels, face), i32(LModels, nFaces), i32(LModels, 0), i32(LModels, 0);
    }
    // An axis-aligned box brush: six sides with outward normals (each a new plane).
    int32_t boxBrush(Vec3 lo, Vec3 hi, int32_t shader) {
        const int32_t first = count(LBrushSides, 8);
        const std::pair<Vec3, double> sides[6] = {{{1, 0, 0}, hi.x},  {{-1, 0, 0}, -lo.x}, {{0, 1, 0}, hi.y},
                                                  {{0, -1, 0}, -lo.y}, {{0, 0, 1}, hi.z},  {{0, 0, -1}, -lo.z}};
        for (const auto &[n, d] : sides) i32(LBrushSides, plane(n, d)), i32(LBrushSides, shader);
        const int32_t i = count(LBrushes, 12);
        i32(LBrushes, first), i32(LBrushes, 6), i32(LBrushes, shader);
        return i;
    }
    int32_t vertex(Vec3 p, Vec3 n = {0, 0, 1}) {
        const int32_t index = count(LVertexes, 44);
        f32(LVertexes, float(p.x)), f32(LVertexes, float(p.y)), f32(LVertexes, float(p.z));
        for (int k = 0; k < 4; ++k) f32(LVertexes, 0);
        f32(LVertexes, float(n.x)), f32(LVertexes, float(n.y)), f32(LVertexes, float(n.z));
        i32(LVertexes, -1);
        return index;
    }
    int32_t meshverts(std::initializer_list<int32_t> l) {
        const int32_t first = count(LMeshVerts, 4);
        for (int32_t v : l) i32(LMeshVerts, v);
        return first;
    }
    // A polygon face (type 1) from its vertices and meshverts (3 per triangle, Quake 3's clockwise).
    int32_t face(int32_t shader, int32_t type, int32_t vertex, int32_t nVertexes, int32_t meshvert, int32_t nMeshverts) {
        const int32_t i = count(LFaces, 104);
        i32(LFaces, shader), i32(LFaces, -1), i32(LFaces, type), i32(LFaces, vertex), i32(LFaces, nVertexes);
        i32(LFaces, meshvert), i32(LFaces, nMeshverts);
        for (int k = 0; k < 5; ++k) i32(LFaces, 0);
        for (int k = 0; k < 12; ++k) f32(LFaces, 0);
        i32(LFaces, 0), i32(LFaces, 0);
        return i;
    }
    // The PVS: rows[c] lists the clusters c sees.
    void pvs(const std::vector<std::vector<int>> &rows) {
        const int n = int(rows.size()), bytes = (n + 7) / 8;
        i32(LVisData, n), i32(LVisData, bytes);
        for (const auto &row : rows) {
            std::vector<uint8_t> r(size_t(bytes), 0);
            for (int c : row) r[size_t(c >> 3)] |= uint8_t(1 << (c & 7));
            lump[LVisData].insert(lump[LVisData].end(), r.begin(), r.end());
        }
    }
    // Header + lumps in lump order, each 4-byte aligned.
    std::vector<uint8_t> file() const {
        std::vector<uint8_t> out(8 + 8 * 17, 0);
        std::memcpy(out.data(), "IBSP", 4);
        out[4] = 46;
        for (int l = 0; l < 17; ++l) {
            while (out.size() % 4) out.push_back(0);
            const uint32_t off = uint32_t(out.size()), len = uint32_t(lump[l].size());
            for (int k = 0; k < 4; ++k) out[8 + 8 * l + k] = uint8_t(off >> (8 * k)), out[12 + 8 * l + k] = uint8_t(len >> (8 * k));
            out.insert(out.end(), lump[l].begin(), lump[l].end());
        }
        return out;
    }
};

}  // namespace va::testing_util
