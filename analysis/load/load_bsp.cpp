// Quake 3 BSP (IBSP v46) loader. Structure:
//   1. Header: magic, version, 17 lumps; every lump inside the file and a whole number of records.
//   2. Records decoded lump by lump, every index checked (planes, nodes, leafs, leaffaces, models,
//      shaders, vertexes, meshverts, faces, visdata, entities); the brush models matched with the
//      entities that spawn them ("model" "*K"), placed at their origin, and walked through the
//      world's tree with their box (the engine's CM_BoxLeafnums); the worldspawn's far plane.
//   3. Faces classified (drawn, faces of entities the engine never draws, sky, nodraw, non-solid,
//      billboard, bad) and counted; the triangles the drawn faces will make counted, and refused
//      over the limit, before anything is allocated.
//   4. Faces assigned to objects: a world face goes to the first leaf of the world's tree that
//      lists it; a brush model's faces to "modelK" (the leafs listing them are the model's own,
//      which the tree never reaches); drawn world faces no such leaf lists to "unleafed". Each object
//      records every cluster holding one of its faces (a face listed by leafs of several clusters is
//      visible from any of them: keeping the union is what keeps the cells stage conservative); a
//      model, the clusters of the leafs its box reaches.
//   5. Geometry emitted per object: polygons and meshes from meshverts (offset by the face's first
//      vertex) with each triangle's winding reversed; patches tessellated on one grid per face; a
//      brush model's moved to where its entity draws it. Each triangle remembers its face.
// Byte layout (little-endian) per lump is written next to its decoder; docs/quake3.md has the table.
#include "analysis/load/load_bsp.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "analysis/load/level_views.h"
#include "analysis/load/zip.h"

namespace va {
namespace {

enum LumpId {
    kEntities, kShaders, kPlanes, kNodes, kLeafs, kLeafFaces, kLeafBrushes, kModels, kBrushes,
    kBrushSides, kVertexes, kMeshVerts, kEffects, kFaces, kLightmaps, kLightVols, kVisData, kLumpCount
};
struct LumpDesc {
    const char *name;
    uint32_t record;  // bytes per record (1: a byte stream, or a lump visaudit only bounds-checks)
};
constexpr LumpDesc kLumps[kLumpCount] = {
    {"entities", 1}, {"shaders", 72}, {"planes", 16}, {"nodes", 36}, {"leafs", 48}, {"leaffaces", 4},
    {"leafbrushes", 4}, {"models", 40}, {"brushes", 12}, {"brushsides", 8}, {"vertexes", 44},
    {"meshverts", 4}, {"effects", 72}, {"faces", 104}, {"lightmaps", 1}, {"lightvols", 1}, {"visdata", 1}};
constexpr uint32_t kHeaderBytes = 8 + 8 * kLumpCount;

// Shader surface flags and content flags (Quake 3's surfaceflags.h).
constexpr uint32_t kSurfSky = 0x4, kSurfNodraw = 0x80, kSurfHint = 0x100, kSurfSkip = 0x200,
                   kSurfNonSolid = 0x4000;
constexpr uint32_t kContentsLava = 0x8, kContentsSlime = 0x10, kContentsWater = 0x20, kContentsFog = 0x40,
                   kContentsAreaPortal = 0x8000, kContentsTranslucent = 0x20000000;

// Face types (MST_*).
enum FaceType { kBad = 0, kPolygon = 1, kPatch = 2, kMesh = 3, kBillboard = 4 };
enum FaceKind : uint8_t { kDrawn, kKindBad, kKindBillboard, kKindEntity, kKindSky, kKindNodraw, kKindNonSolid };

uint32_t u32(const uint8_t *p) { return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24; }
int32_t i32(const uint8_t *p) { return int32_t(u32(p)); }
float f32(const uint8_t *p) {
    const uint32_t u = u32(p);
    float f;
    std::memcpy(&f, &u, 4);
    return f;
}
Vec3 vec3f(const uint8_t *p) { return {f32(p), f32(p + 4), f32(p + 8)}; }
std::string str(int64_t v) { return std::to_string(v); }
std::string range(int64_t first, int64_t count) { return str(first) + ".." + str(first + count); }

struct Face {
    int32_t shader, effect, type, vertex, nVertexes, meshvert, nMeshverts, width, height;
};

struct BspObj;  // a culling object before its geometry is read (Parser::run)

class Parser {
public:
    Parser(const uint8_t *d, size_t n, const std::string &name, const BspOptions &o, std::string *e)
        : data_(d), size_(n), name_(name), opt_(o), err_(e) {}

    bool run(SceneBuildInput *out, BspLevel *level);

private:
    const uint8_t *data_;
    size_t size_;
    const std::string &name_;
    const BspOptions &opt_;
    std::string *err_;
    const uint8_t *lump_[kLumpCount] = {};
    uint64_t count_[kLumpCount] = {};  // records (bytes for byte lumps)
    uint64_t badEffects_ = 0;          // faces naming an effect (fog volume) the file does not have
    int64_t firstBadEffect_ = -1;      //   and the first of them

    bool fail(const std::string &m) {
        *err_ = name_ + ": " + m;
        return false;
    }
    bool lumpFail(int l, const std::string &m) { return fail(std::string("lump '") + kLumps[l].name + "': " + m); }
    const uint8_t *rec(int l, uint64_t i) const { return lump_[l] + i * kLumps[l].record; }
    // [first, first + count) inside [0, limit); the sum is taken in 64 bits, so no overflow.
    static bool inRange(int64_t first, int64_t count, uint64_t limit) {
        return first >= 0 && count >= 0 && uint64_t(first) + uint64_t(count) <= limit;
    }

    bool header();
    bool entities(BspLevel *level);
    bool planes(BspLevel *level);
    bool nodes(BspLevel *level);
    bool leafs(BspLevel *level);
    bool visdata(BspLevel *level);
    bool faces(std::vector<Face> *out);
    bool brushes(BspLevel *level);
    bool models(BspLevel *level, uint64_t nFaces);
    void worldspawnKeys(BspLevel *level);
    bool classify(const std::vector<Face> &fs, const std::vector<uint32_t> &modelOf, BspLevel *level,
                  std::vector<FaceKind> *kind, uint64_t *drawnTriangles);
    void geometry(const std::vector<Face> &fs, std::vector<BspObj> &objs, const std::vector<uint32_t> &order,
                  uint64_t drawnTriangles, BspLevel *level, SceneBuildInput *out);
    void warnings(const BspLevel &level, SceneBuildInput *out);
};

// ---- 1. Header --------------------------------------------------------------------------------------

bool Parser::header() {
    if (size_ < kHeaderBytes)
        return fail("truncated: " + str(int64_t(size_)) + " bytes, but a Quake 3 map's header alone is " +
                    str(kHeaderBytes) + " bytes; fetch the file again");
    if (std::memcmp(data_, "IBSP", 4) != 0) {
        std::string magic;
        for (int i = 0; i < 4; ++i) magic += std::isprint(data_[i]) ? char(data_[i]) : '?';
        const std::string hint = magic == "VBSP"   ? " (a Source engine map)"
                                 : magic == "RBSP" ? " (a Raven map: Jedi Knight, Soldier of Fortune)"
                                 : magic == "FBSP" ? " (a Quake Live/Warsow map)"
                                                   : "";
        return fail("not a Quake 3 map: the file starts with '" + magic + "'" + hint +
                    ", expected 'IBSP'; visaudit reads Quake 3 maps (IBSP version 46)");
    }
    const int32_t version = i32(data_ + 4);
    if (version != 46) {
        const std::string hint = version == 38 ? " (a Quake 2 map)" : version == 47 ? " (Return to Castle Wolfenstein or Quake Live)" : "";
        return fail("IBSP version " + str(version) + hint + " is not supported; visaudit reads Quake 3's version 46");
    }
    for (int l = 0; l < kLumpCount; ++l) {
        const int32_t off = i32(data_ + 8 + 8 * l), len = i32(data_ + 12 + 8 * l);
        if (off < 0 || len < 0)
            return lumpFail(l, "offset " + str(off) + " and length " + str(len) +
                                   " in the header: negative values; the header is damaged");
        if (uint64_t(off) + uint64_t(len) > size_)
            return lumpFail(l, "bytes " + range(off, len) + " lie past the end of the file (" + str(int64_t(size_)) +
                                   " bytes): the file is truncated or the header is damaged; fetch it again");
        if (len % kLumps[l].record != 0)
            return lumpFail(l, "length " + str(len) + " is not a whole number of " + str(kLumps[l].record) +
                                   "-byte records; the file is damaged");
        lump_[l] = data_ + off;
        count_[l] = uint64_t(len) / kLumps[l].record;
    }
    return true;
}

// ---- 2. Records -------------------------------------------------------------------------------------

bool Parser::entities(BspLevel *level) {
    // A NUL-terminated text; anything after the first NUL is ignored.
    const char *t = reinterpret_cast<const char *>(lump_[kEntities]);
    const size_t n = size_t(count_[kEntities]);
    const size_t len = std::find(t, t + n, '\0') - t;
    std::string e;
    if (!parseBspEntities(std::string(t, len), &level->entities, &e)) return lumpFail(kEntities, e);
    return true;
}

bool Parser::planes(BspLevel *level) {
    // plane: float normal[3], float dist (16 bytes)
    level->planes.resize(count_[kPlanes]);
    for (uint64_t i = 0; i < count_[kPlanes]; ++i) {
        const uint8_t *p = rec(kPlanes, i);
        BspPlane &pl = level->planes[i];
        pl.normal = vec3f(p);
        pl.dist = f32(p + 12);
        if (!isFinite(pl.normal) || !std::isfinite(pl.dist))
            return lumpFail(kPlanes, "plane " + str(int64_t(i)) + " is not finite (NaN or infinity); the file is damaged");
    }
    return true;
}

bool Parser::nodes(BspLevel *level) {
    // node: int plane, int children[2], int mins[3], int maxs[3] (36 bytes)
    const uint64_t nn = count_[kNodes], nl = count_[kLeafs];
    level->nodes.resize(nn);
    for (uint64_t i = 0; i < nn; ++i) {
        const uint8_t *p = rec(kNodes, i);
        BspNode &n = level->nodes[i];
        const int32_t plane = i32(p);
        if (plane < 0 || uint64_t(plane) >= count_[kPlanes])
            return lumpFail(kNodes, "node " + str(int64_t(i)) + " plane " + str(plane) + " is outside the " +
                                        str(int64_t(count_[kPlanes])) + " planes; the file is damaged");
        n.plane = uint32_t(plane);
        for (int c = 0; c < 2; ++c) {
            const int32_t ch = i32(p + 4 + 4 * c);
            n.children[c] = ch;
            if (ch >= 0) {
                // Quake 3's compiler writes nodes in pre-order, so a child always follows its parent;
                // requiring it rules out cycles, and every walk from the root ends.
                if (uint64_t(ch) >= nn || uint64_t(ch) <= i)
                    return lumpFail(kNodes, "node " + str(int64_t(i)) + " child " + str(ch) +
                                                (uint64_t(ch) >= nn ? " is outside the " + str(int64_t(nn)) + " nodes"
                                                                    : " does not come after its parent (a cycle)") +
                                                "; the file is damaged");
            } else if (uint64_t(-(int64_t(ch) + 1)) >= nl) {
                return lumpFail(kNodes, "node " + str(int64_t(i)) + " child " + str(ch) + " names leaf " +
                                            str(-(int64_t(ch) + 1)) + ", outside the " + str(int64_t(nl)) +
                                            " leafs; the file is damaged");
            }
        }
    }
    if (nn == 0 && nl > 1)
        return lumpFail(kNodes, "empty, but the map has " + str(int64_t(nl)) + " leafs; the file is damaged");
    return true;
}

bool Parser::leafs(BspLevel *level) {
    // leaf: int cluster, int area, int mins[3], int maxs[3], int leafface, int n_leaffaces,
    //       int leafbrush, int n_leafbrushes (48 bytes)
    level->leafs.resize(count_[kLeafs]);
    for (uint64_t i = 0; i < count_[kLeafs]; ++i) {
        const uint8_t *p = rec(kLeafs, i);
        BspLeaf &l = level->leafs[i];
        l.cluster = i32(p);
        l.area = i32(p + 4);
        l.bounds.lo = {double(i32(p + 8)), double(i32(p + 12)), double(i32(p + 16))};
        l.bounds.hi = {double(i32(p + 20)), double(i32(p + 24)), double(i32(p + 28))};
        const int32_t lf = i32(p + 32), nlf = i32(p + 36), lb = i32(p + 40), nlb = i32(p + 44);
        const std::string leaf = "leaf " + str(int64_t(i));
        if (l.cluster < -1)
            return lumpFail(kLeafs, leaf + " cluster " + str(l.cluster) + " is below -1; the file is damaged");
        if (!inRange(lf, nlf, count_[kLeafFaces]))
            return lumpFail(kLeafs, leaf + " leafface range " + range(lf, nlf) + " exceeds the " +
                                        str(int64_t(count_[kLeafFaces])) + " leaffaces; the file is damaged");
        if (!inRange(lb, nlb, count_[kLeafBrushes]))
            return lumpFail(kLeafs, leaf + " leafbrush range " + range(lb, nlb) + " exceeds the " +
                                        str(int64_t(count_[kLeafBrushes])) + " leafbrushes; the file is damaged");
        l.firstLeafFace = uint32_t(lf);
        l.leafFaceCount = uint32_t(nlf);
        l.firstLeafBrush = uint32_t(lb);
        l.leafBrushCount = uint32_t(nlb);
    }
    // leafface: int face (4 bytes)
    level->leafFaces.resize(count_[kLeafFaces]);
    for (uint64_t i = 0; i < count_[kLeafFaces]; ++i) {
        const int32_t f = i32(rec(kLeafFaces, i));
        if (f < 0 || uint64_t(f) >= count_[kFaces])
            return lumpFail(kLeafFaces, "leafface " + str(int64_t(i)) + " names face " + str(f) + ", outside the " +
                                            str(int64_t(count_[kFaces])) + " faces; the file is damaged");
        level->leafFaces[i] = uint32_t(f);
    }
    return true;
}

bool Parser::visdata(BspLevel *level) {
    // visdata: int n_vecs, int sz_vecs, ubyte vecs[n_vecs * sz_vecs]; cluster x sees y when bit
    // (y & 7) of vecs[x * sz_vecs + y / 8] is set. An empty lump: the map was compiled without vis.
    int32_t maxCluster = -1;
    for (const auto &l : level->leafs) maxCluster = std::max(maxCluster, l.cluster);
    const uint64_t bytes = count_[kVisData];
    if (bytes == 0) {
        level->clusterCount = maxCluster + 1;
        return true;
    }
    if (bytes < 8)
        return lumpFail(kVisData, str(int64_t(bytes)) + " bytes, less than its 8-byte header; the file is damaged");
    const uint8_t *p = lump_[kVisData];
    const int32_t n = i32(p), sz = i32(p + 4);
    if (n < 0 || sz < 0)
        return lumpFail(kVisData, "n_vecs " + str(n) + ", sz_vecs " + str(sz) + ": negative; the file is damaged");
    // Checked in 64 bits before anything is allocated (hostile counts would need gigabytes).
    const uint64_t need = uint64_t(n) * uint64_t(sz);
    if (8 + need > bytes)
        return lumpFail(kVisData, str(n) + " clusters x " + str(sz) + " bytes = " + str(int64_t(need)) +
                                      " bytes of PVS, but the lump holds " + str(int64_t(bytes - 8)) +
                                      "; the file is truncated or damaged");
    if (uint64_t(sz) * 8 < uint64_t(n))
        return lumpFail(kVisData, "rows of " + str(sz) + " bytes cannot hold a bit for each of " + str(n) +
                                      " clusters; the file is damaged");
    if (maxCluster >= n)
        return lumpFail(kVisData, "leafs name cluster " + str(maxCluster) + " but the PVS has " + str(n) +
                                      " clusters; the file is damaged");
    level->clusterCount = n;
    level->pvsRowBytes = uint32_t(sz);
    level->pvs.assign(p + 8, p + 8 + need);
    return true;
}

// Shaders, leafbrushes, brushes and brush sides, kept for the PVS audit (a point inside a detail
// brush is inside solid although its leaf has a cluster).
bool Parser::brushes(BspLevel *level) {
    // shader: char name[64], int surfaceFlags, int contents (72 bytes)
    level->shaders.resize(count_[kShaders]);
    for (uint64_t i = 0; i < count_[kShaders]; ++i) {
        const uint8_t *p = rec(kShaders, i);
        BspShader &sh = level->shaders[i];
        const char *name = reinterpret_cast<const char *>(p);
        sh.name.assign(name, std::find(name, name + 64, '\0'));
        sh.surfaceFlags = u32(p + 64);
        sh.contents = u32(p + 68);
    }
    // brushside: int plane, int shader (8 bytes)
    level->brushSides.resize(count_[kBrushSides]);
    for (uint64_t i = 0; i < count_[kBrushSides]; ++i) {
        const int32_t plane = i32(rec(kBrushSides, i)), shader = i32(rec(kBrushSides, i) + 4);
        if (plane < 0 || uint64_t(plane) >= count_[kPlanes])
            return lumpFail(kBrushSides, "brush side " + str(int64_t(i)) + " plane " + str(plane) + " is outside the " +
                                             str(int64_t(count_[kPlanes])) + " planes; the file is damaged");
        if (shader < 0 || uint64_t(shader) >= count_[kShaders])
            return lumpFail(kBrushSides, "brush side " + str(int64_t(i)) + " shader " + str(shader) +
                                             " is outside the " + str(int64_t(count_[kShaders])) +
                                             " shaders; the file is damaged");
        level->brushSides[i] = uint32_t(plane);
    }
    // brush: int brushside, int n_brushsides, int shader (12 bytes)
    level->brushes.resize(count_[kBrushes]);
    for (uint64_t i = 0; i < count_[kBrushes]; ++i) {
        const uint8_t *p = rec(kBrushes, i);
        const int32_t side = i32(p), n = i32(p + 4), shader = i32(p + 8);
        if (!inRange(side, n, count_[kBrushSides]))
            return lumpFail(kBrushes, "brush " + str(int64_t(i)) + " side range " + range(side, n) + " exceeds the " +
                                          str(int64_t(count_[kBrushSides])) + " brush sides; the file is damaged");
        if (shader < 0 || uint64_t(shader) >= count_[kShaders])
            return lumpFail(kBrushes, "brush " + str(int64_t(i)) + " shader " + str(shader) + " is outside the " +
                                          str(int64_t(count_[kShaders])) + " shaders; the file is damaged");
        level->brushes[i] = {uint32_t(side), uint32_t(n), uint32_t(shader)};
    }
    // leafbrush: int brush (4 bytes)
    level->leafBrushes.resize(count_[kLeafBrushes]);
    for (uint64_t i = 0; i < count_[kLeafBrushes]; ++i) {
        const int32_t b = i32(rec(kLeafBrushes, i));
        if (b < 0 || uint64_t(b) >= count_[kBrushes])
            return lumpFail(kLeafBrushes, "leafbrush " + str(int64_t(i)) + " names brush " + str(b) + ", outside the " +
                                              str(int64_t(count_[kBrushes])) + " brushes; the file is damaged");
        level->leafBrushes[i] = uint32_t(b);
    }
    return true;
}

bool Parser::faces(std::vector<Face> *out) {
    // face: int texture, effect, type, vertex, n_vertexes, meshvert, n_meshverts, lm_index,
    //       lm_start[2], lm_size[2]; float lm_origin[3], lm_vecs[2][3], normal[3]; int size[2]
    //       (104 bytes; size = the patch's control-point grid)
    out->resize(count_[kFaces]);
    for (uint64_t i = 0; i < count_[kFaces]; ++i) {
        const uint8_t *p = rec(kFaces, i);
        Face &f = (*out)[i];
        f.shader = i32(p), f.effect = i32(p + 4), f.type = i32(p + 8), f.vertex = i32(p + 12);
        f.nVertexes = i32(p + 16), f.meshvert = i32(p + 20), f.nMeshverts = i32(p + 24);
        f.width = i32(p + 96), f.height = i32(p + 100);
        const std::string face = "face " + str(int64_t(i));
        if (f.type < kBad || f.type > kBillboard)
            return lumpFail(kFaces, face + " has type " + str(f.type) +
                                        "; Quake 3 knows 1 polygon, 2 patch, 3 mesh, 4 billboard; the file is damaged");
        if (f.shader < 0 || uint64_t(f.shader) >= count_[kShaders])
            return lumpFail(kFaces, face + " shader " + str(f.shader) + " is outside the " +
                                        str(int64_t(count_[kShaders])) + " shaders; the file is damaged");
        // The effect (a fog volume) is not geometry, and visaudit reads none; the engine does not
        // check it either (ioquake3's R_LoadSurfaces takes fogNum + 1 as is), and shipped maps name
        // effects their file lacks (OpenArena's aggressor: effect 0 of 0). Read as none, and said.
        if (f.effect < -1 || (f.effect >= 0 && uint64_t(f.effect) >= count_[kEffects])) {
            if (!badEffects_++) firstBadEffect_ = int64_t(i);
            f.effect = -1;
        }
        if (f.type == kBad || f.type == kBillboard) continue;  // no geometry is read from these
        if (!inRange(f.vertex, f.nVertexes, count_[kVertexes]))
            return lumpFail(kFaces, face + " vertex range " + range(f.vertex, f.nVertexes) + " exceeds " +
                                        str(int64_t(count_[kVertexes])) + " vertices; the file is damaged");
        if (f.type == kPatch) {
            if (f.width < 3 || f.height < 3 || f.width % 2 == 0 || f.height % 2 == 0)
                return lumpFail(kFaces, face + " is a patch of " + str(f.width) + "x" + str(f.height) +
                                            " control points; patches need odd sizes of at least 3; the file is damaged");
            if (int64_t(f.width) * int64_t(f.height) > int64_t(f.nVertexes))
                return lumpFail(kFaces, face + " is a patch of " + str(f.width) + "x" + str(f.height) +
                                            " control points but has only " + str(f.nVertexes) +
                                            " vertices; the file is damaged");
        } else {
            if (!inRange(f.meshvert, f.nMeshverts, count_[kMeshVerts]))
                return lumpFail(kFaces, face + " meshvert range " + range(f.meshvert, f.nMeshverts) + " exceeds " +
                                            str(int64_t(count_[kMeshVerts])) + " meshverts; the file is damaged");
            if (f.nMeshverts % 3 != 0)
                return lumpFail(kFaces, face + " has " + str(f.nMeshverts) +
                                            " meshverts, not a multiple of 3 (triangles); the file is damaged");
            for (int32_t k = 0; k < f.nMeshverts; ++k) {
                const int32_t v = i32(rec(kMeshVerts, uint64_t(f.meshvert) + uint64_t(k)));
                if (v < 0 || v >= f.nVertexes)
                    return lumpFail(kFaces, face + " meshvert " + str(int64_t(f.meshvert) + k) + " = " + str(v) +
                                                " is outside the face's " + str(f.nVertexes) +
                                                " vertices; the file is damaged");
            }
        }
    }
    return true;
}

// ---- Brush models and their entities ------------------------------------------------------------------

// Three numbers, as an entity's "origin" holds them; false (and *out untouched) otherwise.
bool entityVec3(const std::string &s, Vec3 *out) {
    const char *p = s.c_str();
    double v[3];
    for (double &x : v) {
        char *end = nullptr;
        x = std::strtod(p, &end);
        if (end == p || !std::isfinite(x)) return false;
        p = end;
    }
    *out = {v[0], v[1], v[2]};
    return true;
}

// The leafs a box reaches walking the tree from the root (Quake 3's CM_BoxLeafnums): a node sends
// the walk to its front child when the box's farthest corner along the normal is on the front
// (dot >= dist) and to its back child when its nearest corner is behind (dot < dist) -- both when it
// straddles. In double from the float planes and box, and ties go both ways, so a box touching a
// plane is never cut off (conservative). An explicit stack: nothing recurses on the file's depth.
// Every node is reached at most once (each has one parent: children come after their parents).
// `steps`: what the walks may still visit, all models together; false when it runs out.
bool boxLeafs(const BspLevel &level, const Aabb &box, uint64_t *steps, std::vector<int32_t> *out) {
    std::vector<int32_t> &leafs = *out;
    leafs.clear();
    if (level.leafs.empty()) return true;
    if (level.nodes.empty()) {
        leafs.push_back(0);
        return true;
    }
    std::vector<int32_t> stack{0};
    while (!stack.empty()) {
        if (*steps == 0) return false;
        --*steps;
        const int32_t i = stack.back();
        stack.pop_back();
        if (i < 0) {
            leafs.push_back(-(i + 1));
            continue;
        }
        const BspNode &n = level.nodes[size_t(i)];
        const BspPlane &pl = level.planes[n.plane];
        double lo = -pl.dist, hi = -pl.dist;
        for (int a = 0; a < 3; ++a) {
            const double x0 = pl.normal[a] * box.lo[a], x1 = pl.normal[a] * box.hi[a];
            lo += std::min(x0, x1), hi += std::max(x0, x1);
        }
        if (hi >= 0) stack.push_back(n.children[0]);
        if (lo < 0) stack.push_back(n.children[1]);
    }
    std::sort(leafs.begin(), leafs.end());
    leafs.erase(std::unique(leafs.begin(), leafs.end()), leafs.end());
    return true;
}


bool Parser::models(BspLevel *level, uint64_t nFaces) {
    level->models.assign(count_[kModels], BspModel{});
    for (uint64_t i = 0; i < count_[kModels]; ++i) {
        const uint8_t *p = rec(kModels, i);
        BspModel &m = level->models[i];
        m.bounds.lo = vec3f(p), m.bounds.hi = vec3f(p + 12);
        const int32_t face = i32(p + 24), n = i32(p + 28);
        if (!inRange(face, n, nFaces))
            return lumpFail(kModels, "model " + str(int64_t(i)) + " face range " + range(face, n) + " exceeds the " +
                                         str(int64_t(nFaces)) + " faces; the file is damaged");
        if (!isFinite(m.bounds.lo) || !isFinite(m.bounds.hi))
            return lumpFail(kModels, "model " + str(int64_t(i)) + " bounds are not finite (NaN or infinity); the file is damaged");
        m.firstFace = uint32_t(face), m.faceCount = uint32_t(n);
    }
    // The entity spawning each model: the first with "model" "*K" (the game's G_SpawnEntitiesFromString
    // reads every entity; two naming one model would draw it twice, at the first's place here).
    for (size_t e = 0; e < level->entities.size(); ++e) {
        const std::string *mv = level->entities[e].get("model");
        if (!mv || mv->size() < 2 || (*mv)[0] != '*' || mv->size() > 11 ||
            mv->find_first_not_of("0123456789", 1) != std::string::npos)
            continue;
        const uint64_t k = std::stoull(mv->substr(1));
        if (k == 0 || k >= level->models.size() || level->models[k].entity >= 0) continue;
        BspModel &m = level->models[k];
        m.entity = int32_t(e);
        const BspEntity &ent = level->entities[e];
        if (const std::string *c = ent.get("classname")) m.classname = *c;
        // Where the game draws it: at the entity's origin (the model's vertices are relative to its
        // origin brush when it had one, else world positions and no "origin"). A func_train starts
        // at its first path_corner (g_mover.c: Reached_Train copies the target's origin to pos1).
        Vec3 o;
        if (const std::string *os = ent.get("origin"); os && entityVec3(*os, &o)) m.offset = o;
        if (m.classname == "func_train")
            if (const std::string *t = ent.get("target"))
                for (const BspEntity &d : level->entities) {
                    const std::string *tn = d.get("targetname"), *to = d.get("origin");
                    if (tn && *tn == *t && to && entityVec3(*to, &o)) {
                        m.offset = o;
                        break;
                    }
                }
    }
    // The walks' budget (BspOptions::maxBoxWalkSteps), all models together: a real map's walks visit
    // well under a million nodes (oa_thor's tree has 5,355); a hostile file with a million models
    // over a million nodes would otherwise walk 10^12 (docs/limits.md, "Hostile files").
    uint64_t steps = opt_.maxBoxWalkSteps;
    for (size_t k = 1; k < level->models.size(); ++k) {
        BspModel &m = level->models[k];
        // Never drawn: triggers (g_trigger.c's InitTrigger marks them SVF_NOCLIENT; trigger_push
        // and trigger_teleport go to clients for prediction only, and cg_ents.c draws nothing for
        // ET_PUSH_TRIGGER / ET_TELEPORT_TRIGGER), and models no entity spawns.
        m.drawn = m.entity >= 0 && m.classname.rfind("trigger_", 0) != 0;
        m.bounds.lo = m.bounds.lo + m.offset;
        m.bounds.hi = m.bounds.hi + m.offset;
        // The server links an entity with its box widened by 1 unit per side (sv_world.c,
        // SV_LinkEntity: "movement is clipped an epsilon away from an actual edge"). Only models
        // with faces need their leafs (their faces become objects).
        if (m.drawn && m.faceCount > 0 &&
            !boxLeafs(*level, {m.bounds.lo - Vec3{1, 1, 1}, m.bounds.hi + Vec3{1, 1, 1}}, &steps, &m.boxLeafs))
            return lumpFail(kModels, "the brush models' boxes reach more than " + str(int64_t(opt_.maxBoxWalkSteps)) +
                                         " nodes of the tree (at model " + str(int64_t(k)) + " of " +
                                         str(int64_t(level->models.size())) + "); the file is damaged");
    }
    return true;
}

// The worldspawn's far plane (q3map2's vis.cpp reads "_farplanedist", or "fogclip" / "distancecull"
// of other games: atof of the value, its last character the mode) and a map-wide fog shader
// ("_fog" / "fog", q3map2's fog.cpp).
void Parser::worldspawnKeys(BspLevel *level) {
    const BspEntity *ws = nullptr;
    for (const BspEntity &e : level->entities)
        if (const std::string *c = e.get("classname"); c && *c == "worldspawn") {
            ws = &e;
            break;
        }
    if (!ws) return;
    for (const char *key : {"_farplanedist", "fogclip", "distancecull"}) {
        const std::string *v = ws->get(key);
        if (!v) continue;
        const double d = std::strtod(v->c_str(), nullptr);
        if (std::isfinite(d) && d > 0) {
            level->farPlane.distance = d;
            level->farPlane.key = key;
            level->farPlane.value = *v;
            const char last = v->empty() ? 0 : v->back();
            level->farPlane.mode = (last == 'o' || last == 'e' || last == 'r') ? last : 0;
        }
        break;
    }
    for (const char *key : {"_fog", "fog"})
        if (const std::string *v = ws->get(key)) {
            level->fogShader = *v;
            break;
        }
}

// ---- Patches: biquadratic Bezier, one grid per face -----------------------------------------------

// B(t) = (1-t)^2 P0 + 2t(1-t) P1 + t^2 P2; at t = 0 and t = 1 it is exactly P0 and P2, so
// neighbouring 3x3 patches meet at bit-identical points.
Vec3 bezier(Vec3 a, Vec3 b, Vec3 c, double t) {
    const double s = 1 - t;
    return a * (s * s) + b * (2 * t * s) + c * (t * t);
}

// Tessellates a width x height control grid (rows of `width` points) into
// ((width-1)/2 * L + 1) x ((height-1)/2 * L + 1) vertices and 2 triangles per grid cell, appended to
// `m`. Quake 3's renderer draws cell (row i, column j) as (v2, v3, v1), (v1, v3, v4) with
// v1 = i*W + j + 1, v2 = v1 - 1, v3 = v2 + W, v4 = v3 + 1: clockwise seen from the front, like its
// other faces. Reversed here: (v2, v1, v3), (v1, v4, v3).
void tessellatePatch(const std::vector<Vec3> &ctrl, int width, int height, int L, RawMesh *m) {
    const int sx = (width - 1) / 2, sy = (height - 1) / 2;
    const int W = sx * L + 1, H = sy * L + 1;
    const uint32_t base = uint32_t(m->positions.size());
    for (int r = 0; r < H; ++r) {
        const int py = std::min(r / L, sy - 1);
        const double v = double(r - py * L) / L;
        for (int c = 0; c < W; ++c) {
            const int px = std::min(c / L, sx - 1);
            const double u = double(c - px * L) / L;
            Vec3 row[3];
            for (int k = 0; k < 3; ++k) {
                const size_t o = size_t(2 * py + k) * width + 2 * px;
                row[k] = bezier(ctrl[o], ctrl[o + 1], ctrl[o + 2], u);
            }
            m->positions.push_back(bezier(row[0], row[1], row[2], v));
        }
    }
    for (int i = 0; i + 1 < H; ++i)
        for (int j = 0; j + 1 < W; ++j) {
            const uint32_t v1 = base + uint32_t(i * W + j + 1), v2 = v1 - 1, v3 = v2 + uint32_t(W), v4 = v3 + 1;
            m->indices.insert(m->indices.end(), {v2, v1, v3, v1, v4, v3});
        }
}

uint64_t patchTriangles(const Face &f, int L) {
    return uint64_t((f.width - 1) / 2) * uint64_t((f.height - 1) / 2) * 2 * uint64_t(L) * uint64_t(L);
}
uint64_t patchVertices(const Face &f, int L) {
    return (uint64_t((f.width - 1) / 2) * L + 1) * (uint64_t((f.height - 1) / 2) * L + 1);
}

// ---- The whole file ---------------------------------------------------------------------------------

// modelOf[f], owner[f], leafObj[l]...: no model, leaf or object.
constexpr uint32_t kNone = 0xFFFFFFFFu;

// A culling object of the map before its geometry is read.
struct BspObj {
    std::string name;
    int32_t cluster = -1;
    uint32_t model = 0;
    std::vector<uint32_t> faces;     // ascending
};

// 3. Classify, count, and bound the output before allocating it: each face's kind, the counts by
// kind, and the drawn faces' triangles (false when they exceed the limit).
bool Parser::classify(const std::vector<Face> &fs, const std::vector<uint32_t> &modelOf, BspLevel *level,
                      std::vector<FaceKind> *kindOut, uint64_t *drawnTrianglesOut) {
    const int L = opt_.patchLevel;
    const uint64_t nf = fs.size();
    // Shaders: char name[64], int surfaceFlags, int contents (72 bytes).
    auto flagsOf = [&](const Face &f) { return u32(rec(kShaders, uint64_t(f.shader)) + 64); };
    auto contentsOf = [&](const Face &f) { return u32(rec(kShaders, uint64_t(f.shader)) + 68); };

    BspFaceCounts &fc = level->faceCounts;
    fc.faces = nf;
    std::vector<FaceKind> kind(nf, kDrawn);
    uint64_t drawnTriangles = 0, drawnVertices = 0;
    for (uint64_t i = 0; i < nf; ++i) {
        const Face &f = fs[i];
        const uint32_t flags = flagsOf(f), contents = contentsOf(f);
        const uint64_t tris = f.type == kPatch ? patchTriangles(f, L)
                              : (f.type == kPolygon || f.type == kMesh) ? uint64_t(f.nMeshverts / 3) : 0;
        BspModel *model = modelOf[i] != kNone ? &level->models[modelOf[i]] : nullptr;
        FaceKind k = kDrawn;
        if (f.type == kBad) k = kKindBad;
        else if (f.type == kBillboard) k = kKindBillboard;
        else if (model && !model->drawn) k = kKindEntity;  // the whole entity is never drawn
        else if (flags & kSurfSky) k = kKindSky;
        // Tool surfaces: nodraw (clip and trigger brushes' shaders carry it), hint, skip, area portals.
        else if ((flags & (kSurfNodraw | kSurfHint | kSurfSkip)) || (contents & kContentsAreaPortal)) k = kKindNodraw;
        // Non-solid and see-through: liquid and fog volumes, and non-solid translucent shaders
        // (light beams, flares of glass). They are blended over the scene and hide nothing.
        else if ((contents & (kContentsLava | kContentsSlime | kContentsWater | kContentsFog)) ||
                 ((flags & kSurfNonSolid) && (contents & kContentsTranslucent)))
            k = kKindNonSolid;
        kind[i] = k;
        switch (k) {
        case kKindBad: ++fc.bad; break;
        case kKindBillboard: ++fc.billboards; break;
        case kKindEntity:
            ++fc.notDrawnEntity, fc.notDrawnEntityTriangles += tris;
            ++model->notDrawnFaces, model->notDrawnTriangles += tris;
            break;
        case kKindSky: ++fc.sky, fc.skyTriangles += tris; break;
        case kKindNodraw: ++fc.nodraw, fc.nodrawTriangles += tris; break;
        case kKindNonSolid: ++fc.nonSolid, fc.nonSolidTriangles += tris; break;
        case kDrawn:
            if (f.type == kPolygon) ++fc.polygons, fc.polygonTriangles += tris;
            else if (f.type == kPatch) ++fc.patches, fc.patchTriangles += tris;
            else ++fc.meshes, fc.meshTriangles += tris;
            drawnTriangles += tris;
            drawnVertices += f.type == kPatch ? patchVertices(f, L) : uint64_t(f.nVertexes);
            break;
        }
    }
    if (drawnTriangles > opt_.maxTriangles || drawnVertices > (uint64_t(1) << 32) - 1)
        return fail("the map's drawn faces would make " + str(int64_t(drawnTriangles)) + " triangles and " +
                    str(int64_t(drawnVertices)) + " vertices at patch level " + str(L) + ", more than the limit of " +
                    str(int64_t(opt_.maxTriangles)) +
                    " triangles; lower the patch level (--patch-level) or raise the limit with --max-triangles " +
                    str(int64_t(drawnTriangles)) + ", or the file is damaged");

    *kindOut = std::move(kind);
    *drawnTrianglesOut = drawnTriangles;
    return true;
}

// 4a. The leafs the world's tree reaches, every leaf listing each face, and each face's owner.
void indexFaceLeafs(BspLevel *level, uint64_t nf, std::vector<uint32_t> *ownerOut) {
    // The leafs the world's tree reaches: the nodes are in pre-order (children after
    // their parents, checked by nodes()), so one pass in order marks every reachable node and leaf.
    const size_t nl = level->leafs.size();
    level->leafInTree.assign(nl, 0);
    if (level->nodes.empty()) {
        if (nl > 0) level->leafInTree[0] = 1;
    } else {
        std::vector<uint8_t> nodeInTree(level->nodes.size(), 0);
        nodeInTree[0] = 1;
        for (size_t i = 0; i < level->nodes.size(); ++i) {
            if (!nodeInTree[i]) continue;
            for (int32_t ch : level->nodes[i].children) {
                if (ch >= 0) nodeInTree[size_t(ch)] = 1;
                else level->leafInTree[size_t(-(int64_t(ch) + 1))] = 1;
            }
        }
    }
    // Every leaf listing each face, ascending (CSR), and owner[f]: the first leaf of the world's tree
    // listing face f. A model's faces are listed only by leafs of its own (cluster 0, zero bounds)
    // that the tree never reaches: they say nothing about where the model is.
    level->faceLeafsBegin.assign(nf + 1, 0);
    for (const BspLeaf &lf : level->leafs)
        for (uint32_t k = 0; k < lf.leafFaceCount; ++k) ++level->faceLeafsBegin[level->leafFaces[lf.firstLeafFace + k] + 1];
    for (uint64_t f = 0; f < nf; ++f) level->faceLeafsBegin[f + 1] += level->faceLeafsBegin[f];
    level->faceLeafs.assign(level->faceLeafsBegin[nf], 0);
    {
        std::vector<uint32_t> fill(level->faceLeafsBegin.begin(), level->faceLeafsBegin.end() - 1);
        for (size_t l = 0; l < nl; ++l) {
            const BspLeaf &lf = level->leafs[l];
            for (uint32_t k = 0; k < lf.leafFaceCount; ++k) level->faceLeafs[fill[level->leafFaces[lf.firstLeafFace + k]]++] = uint32_t(l);
        }
    }
    std::vector<uint32_t> owner(nf, kNone);
    for (uint64_t f = 0; f < nf; ++f)
        for (uint32_t k = level->faceLeafsBegin[f]; k < level->faceLeafsBegin[f + 1] && owner[f] == kNone; ++k)
            if (level->leafInTree[level->faceLeafs[k]]) owner[f] = level->faceLeafs[k];
    *ownerOut = std::move(owner);
}

// The clusters of the leafs of the world's tree listing face f (a face straddling clusters is
// visible from any of them: keeping the union keeps the cells stage conservative).
void faceClusters(const BspLevel &level, uint64_t f, std::vector<int32_t> *cl) {
    for (uint32_t k = level.faceLeafsBegin[f]; k < level.faceLeafsBegin[f + 1]; ++k) {
        const uint32_t l = level.faceLeafs[k];
        if (level.leafInTree[l] && level.leafs[l].cluster >= 0) cl->push_back(level.leafs[l].cluster);
    }
}

// 4b. The object list: leafs in order, then the drawn brush models 1.., then the unleafed world faces
// (`order` is the source order).
void groupObjects(BspLevel *level, const std::vector<FaceKind> &kind, const std::vector<uint32_t> &modelOf,
                  const std::vector<uint32_t> &owner, std::vector<BspObj> *objsOut, std::vector<uint32_t> *orderOut) {
    const uint64_t nf = kind.size();
    const size_t nl = level->leafs.size();
    BspFaceCounts &fc = level->faceCounts;
    // A brush model's faces go to "modelK" whatever leafs list them; its clusters are those of the
    // leafs its placed box reaches (BspModel::boxLeafs), the engine's own rule.
    std::vector<BspObj> objs;
    std::vector<uint32_t> leafObj(nl, kNone);
    std::vector<uint32_t> modelObj(level->models.size(), kNone);
    uint32_t unleafedObj = kNone;
    for (uint64_t f = 0; f < nf; ++f) {
        if (kind[f] != kDrawn) continue;
        uint32_t *slot;
        std::string nm;
        int32_t cl = -1;
        const uint32_t m = modelOf[f] == kNone ? 0 : modelOf[f];
        if (m > 0) {
            slot = &modelObj[m];
            nm = "model" + str(m);
            ++fc.modelFaces;
        } else if (owner[f] != kNone) {
            slot = &leafObj[owner[f]];
            nm = "leaf" + str(owner[f]);
            cl = level->leafs[owner[f]].cluster;
        } else {
            slot = &unleafedObj;
            nm = "unleafed";
            ++fc.unleafedFaces;
        }
        if (*slot == kNone) {
            *slot = uint32_t(objs.size());
            objs.push_back({nm, cl, m, {}});
        }
        objs[*slot].faces.push_back(uint32_t(f));
    }
    // Source order: leaf objects by leaf index, then models by index, then "unleafed".
    std::vector<uint32_t> order;
    for (uint32_t o : leafObj)
        if (o != kNone) order.push_back(o);
    for (uint32_t o : modelObj)
        if (o != kNone) order.push_back(o);
    if (unleafedObj != kNone) order.push_back(unleafedObj);

    *objsOut = std::move(objs);
    *orderOut = std::move(order);
}

// 5. Geometry, object by object in source order, with each triangle's face and each object's clusters.
void Parser::geometry(const std::vector<Face> &fs, std::vector<BspObj> &objs, const std::vector<uint32_t> &order,
                      uint64_t drawnTriangles, BspLevel *level, SceneBuildInput *out) {
    const int L = opt_.patchLevel;
    // Vertex: float position[3], texcoord[2][2], normal[3]; ubyte color[4] (44 bytes).
    auto position = [&](uint64_t v) { return vec3f(rec(kVertexes, v)); };
    out->objects.clear();
    out->objects.reserve(order.size());
    level->sourceCluster.clear();
    level->sourceClustersBegin.assign(1, 0);
    level->sourceClusters.clear();
    level->sourceModel.clear();
    level->triangleFace.clear();
    level->triangleFace.reserve(drawnTriangles);
    std::vector<Vec3> ctrl;
    for (uint32_t oi : order) {
        BspObj &o = objs[oi];
        SceneBuildInput::Object so;
        so.name = o.name;
        so.mesh = name_;
        RawMesh &m = so.geometry;
        std::vector<int32_t> cl;
        if (o.cluster >= 0) cl.push_back(o.cluster);
        static const BspModel kNoModel;
        const BspModel &model = o.model < level->models.size() ? level->models[o.model] : kNoModel;
        for (int32_t l : model.boxLeafs)
            if (level->leafs[size_t(l)].cluster >= 0) cl.push_back(level->leafs[size_t(l)].cluster);
        // A brush model is drawn where its entity puts it (BspModel::offset); the world at 0.
        const Vec3 offset = model.offset;
        for (uint32_t fi : o.faces) {
            const Face &f = fs[fi];
            faceClusters(*level, fi, &cl);
            ++m.facesRead;
            const size_t trianglesBefore = m.indices.size() / 3;
            if (f.type == kPatch) {
                ctrl.resize(size_t(f.width) * size_t(f.height));
                for (size_t k = 0; k < ctrl.size(); ++k) ctrl[k] = position(uint64_t(f.vertex) + k) + offset;
                tessellatePatch(ctrl, f.width, f.height, L, &m);
            } else {
                // Polygons and meshes: meshverts index the face's own vertices (offset by its first
                // vertex); each triangle is stored clockwise seen from the front, so two corners swap.
                const uint32_t base = uint32_t(m.positions.size());
                for (int32_t k = 0; k < f.nVertexes; ++k)
                    m.positions.push_back(position(uint64_t(f.vertex) + uint64_t(k)) + offset);
                for (int32_t k = 0; k < f.nMeshverts; k += 3) {
                    const uint8_t *mv = rec(kMeshVerts, uint64_t(f.meshvert) + uint64_t(k));
                    const uint32_t a = u32(mv), b = u32(mv + 4), c = u32(mv + 8);
                    m.indices.insert(m.indices.end(), {base + a, base + c, base + b});
                }
            }
            level->triangleFace.insert(level->triangleFace.end(), m.indices.size() / 3 - trianglesBefore, fi);
        }
        std::sort(cl.begin(), cl.end());
        cl.erase(std::unique(cl.begin(), cl.end()), cl.end());
        level->sourceModel.push_back(o.model);
        level->sourceCluster.push_back(o.cluster);
        level->sourceClusters.insert(level->sourceClusters.end(), cl.begin(), cl.end());
        level->sourceClustersBegin.push_back(uint32_t(level->sourceClusters.size()));
        out->objects.push_back(std::move(so));
    }

}

// The loader's warnings: faces kept out of the objects, bad effects, brush entities never drawn.
void Parser::warnings(const BspLevel &level, SceneBuildInput *out) {
    const BspFaceCounts &fc = level.faceCounts;
    if (fc.sky + fc.nodraw + fc.nonSolid + fc.billboards + fc.bad > 0)
        out->warnings.push_back(name_ + ": kept out of the objects (docs/quake3.md): " + str(int64_t(fc.sky)) +
                                " sky, " + str(int64_t(fc.nodraw)) + " nodraw, " + str(int64_t(fc.nonSolid)) +
                                " non-solid see-through, " + str(int64_t(fc.billboards)) + " billboard and " +
                                str(int64_t(fc.bad)) + " bad faces");
    if (badEffects_ > 0)
        out->warnings.push_back(name_ + ": " + str(int64_t(badEffects_)) + " faces name an effect (fog volume) outside the " +
                                str(int64_t(count_[kEffects])) + " effects of the file (the first: face " +
                                str(firstBadEffect_) + "); read without one (effects are not geometry; the engine "
                                "loads such maps)");
    if (fc.notDrawnEntity > 0) {
        uint64_t entities = 0;
        for (const BspModel &md : level.models) entities += md.notDrawnFaces > 0;
        out->warnings.push_back(name_ + ": not geometry (docs/quake3.md, \"Brush entities\"): " +
                                str(int64_t(fc.notDrawnEntity)) + " faces of " + str(int64_t(entities)) +
                                " brush entities the engine never draws (trigger_*, models no entity spawns)");
    }
}

bool Parser::run(SceneBuildInput *out, BspLevel *level) {
    const int L = opt_.patchLevel;
    if (L < 1 || L > kMaxPatchLevel)
        return fail("patch level " + str(L) + " is outside 1.." + str(kMaxPatchLevel) + "; choose e.g. 5 (--patch-level)");
    if (!header()) return false;
    std::vector<Face> fs;
    if (!entities(level) || !planes(level) || !nodes(level) || !leafs(level) || !visdata(level) || !faces(&fs) ||
        !brushes(level))
        return false;
    level->faceShader.resize(fs.size());
    for (size_t i = 0; i < fs.size(); ++i) level->faceShader[i] = uint32_t(fs[i].shader);
    level->patchLevel = L;
    const uint64_t nf = fs.size();
    worldspawnKeys(level);

    // Models: float mins[3], maxs[3]; int face, n_faces, brush, n_brushes (40 bytes). Model 0 is the
    // world; the others are brush entities (doors, platforms, movers, triggers).
    if (!models(level, nf)) return false;
    if (!level->models.empty())
        level->worldFirstFace = level->models[0].firstFace, level->worldFaceCount = level->models[0].faceCount;
    // modelOf[f]: the first model holding face f (kNone: none).
    std::vector<uint32_t> modelOf(nf, kNone);
    for (size_t m = 0; m < level->models.size(); ++m) {
        const BspModel &md = level->models[m];
        for (uint32_t k = 0; k < md.faceCount; ++k)
            if (modelOf[md.firstFace + k] == kNone) modelOf[md.firstFace + k] = uint32_t(m);
    }
    std::vector<FaceKind> kind;
    uint64_t drawnTriangles = 0;
    if (!classify(fs, modelOf, level, &kind, &drawnTriangles)) return false;
    std::vector<uint32_t> owner, order;
    indexFaceLeafs(level, nf, &owner);
    std::vector<BspObj> objs;
    groupObjects(level, kind, modelOf, owner, &objs, &order);
    geometry(fs, objs, order, drawnTriangles, level, out);
    out->up = 'z';
    out->path = name_;
    out->materials = {Material{}};
    warnings(*level, out);
    return true;
}

std::string lowerExt(const std::string &path) {
    std::string e = std::filesystem::path(path).extension().string();
    for (auto &c : e) c = char(std::tolower((unsigned char)c));
    return e;
}

}  // namespace

bool isBspPath(const std::string &path) {
    std::string archive, member;
    if (splitArchivePath(path, &archive, &member)) return lowerExt(member) == ".bsp";
    return lowerExt(path) == ".bsp";
}

bool readBspBytes(const std::string &path, uint64_t maxBytes, std::vector<uint8_t> *out, std::string *err) {
    std::string archive, member;
    if (splitArchivePath(path, &archive, &member)) return readZipMember(archive, member, maxBytes, out, err);
    std::error_code ec;
    const uint64_t size = std::filesystem::file_size(path, ec);
    if (ec) {
        *err = path + ": cannot read (" + ec.message() + "); check the path";
        return false;
    }
    if (size > maxBytes) {
        *err = path + ": " + std::to_string(size) + " bytes, more than the limit of " + std::to_string(maxBytes) +
               " bytes for a map; this is not a Quake 3 map (or raise the limit)";
        return false;
    }
    std::ifstream in(path, std::ios::binary);
    out->assign(size_t(size), 0);
    if (!in || !in.read(reinterpret_cast<char *>(out->data()), std::streamsize(size))) {
        *err = path + ": cannot read all " + std::to_string(size) + " bytes; check the file's permissions";
        return false;
    }
    return true;
}

bool parseBsp(const uint8_t *data, size_t size, const std::string &name, const BspOptions &opt,
              SceneBuildInput *out, BspLevel *level, std::string *err) {
    Parser p(data, size, name, opt, err);
    return p.run(out, level);
}

bool loadBspScene(const std::string &path, const BspOptions &opt, const ChunkSettings &chunks, Scene *out,
                  std::string *err) {
    std::vector<uint8_t> bytes;
    if (!readBspBytes(path, opt.maxFileBytes, &bytes, err)) return false;
    SceneBuildInput in;
    BspLevel level;
    if (!parseBsp(bytes.data(), bytes.size(), path, opt, &in, &level, err)) return false;
    std::vector<uint8_t>().swap(bytes);  // the file's bytes are parsed: free them before the scene build
    Scene s;
    std::string e;
    if (!buildScene(std::move(in), chunks, &s, &e)) {
        *err = path + ": " + e;
        return false;
    }
    s.bsp = std::move(level);
    s.views = spawnViews(s);
    *out = std::move(s);
    return true;
}

bool parseBspEntities(const std::string &text, std::vector<BspEntity> *out, std::string *err) {
    out->clear();
    size_t i = 0;
    int line = 1;
    auto fail = [&](const std::string &m) {
        *err = "line " + std::to_string(line) + ": " + m;
        return false;
    };
    // Skips white space and // comments; false at the end of the text.
    auto skip = [&]() {
        while (i < text.size()) {
            const char c = text[i];
            if (c == '\n') ++line, ++i;
            else if (std::isspace((unsigned char)c)) ++i;
            else if (c == '/' && i + 1 < text.size() && text[i + 1] == '/') {
                while (i < text.size() && text[i] != '\n') ++i;
            } else return true;
        }
        return false;
    };
    auto quoted = [&](std::string *s) {
        if (text[i] != '"') return fail(std::string("expected a quoted string, got '") + text[i] + "'");
        const size_t start = ++i;
        while (i < text.size() && text[i] != '"') {
            if (text[i] == '\n') ++line;
            ++i;
        }
        if (i >= text.size()) return fail("unterminated string; the entity text is truncated");
        *s = text.substr(start, i - start);
        ++i;
        return true;
    };
    while (skip()) {
        if (text[i] != '{') return fail(std::string("expected '{' to open an entity, got '") + text[i] + "'");
        ++i;
        BspEntity e;
        for (;;) {
            if (!skip()) return fail("entity not closed with '}'; the entity text is truncated");
            if (text[i] == '}') {
                ++i;
                break;
            }
            std::string k, v;
            if (!quoted(&k)) return false;
            if (!skip()) return fail("key \"" + k + "\" has no value; the entity text is truncated");
            if (!quoted(&v)) return false;
            e.keys.emplace_back(std::move(k), std::move(v));
        }
        out->push_back(std::move(e));
    }
    return true;
}

}  // namespace va
