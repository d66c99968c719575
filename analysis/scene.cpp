// buildScene: source objects (world-space meshes, file order) -> the culling scene.
//
// Structure:
//   1. Classify every source triangle (ids assigned objects-in-file-order, faces-in-file-order):
//      non-finite, degenerate (zero area) or valid; compute its plane.
//   2. Per source object, split its valid triangles into spatially coherent chunks (recursive median
//      split of centroids along the longest axis) of at most ChunkSettings::maxTriangles.
//   3. Per chunk (= culling object), copy the vertices its triangles use into one contiguous range of
//      Scene::positions (vertices shared with another chunk are duplicated), rewrite the triangles'
//      indices into that range, and compute its AABB and a conservative bounding sphere.
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "analysis/scene.h"

namespace va {
namespace {

// A valid triangle awaiting chunking: its centroid (times 3: only ordering matters) and its id.
struct ChunkItem {
    Vec3 centroid3;
    uint32_t id;
};

// Recursive median split of items[b, e) until each range holds <= maxTris triangles; appends the
// leaf ranges in left-to-right order. Deterministic: the median is an exact order statistic under a
// total order (coordinate along the axis, then triangle id), so the partition does not depend on the
// standard library's nth_element strategy.
void splitChunks(std::vector<ChunkItem> &items, size_t b, size_t e, uint32_t maxTris,
                 std::vector<std::pair<size_t, size_t>> *leaves) {
    // Iterative with an explicit stack (right pushed first so leaves come out left to right).
    std::vector<std::pair<size_t, size_t>> stack{{b, e}};
    while (!stack.empty()) {
        auto [lo, hi] = stack.back();
        stack.pop_back();
        if (hi - lo <= maxTris) {
            leaves->push_back({lo, hi});
            continue;
        }
        // Longest axis of the centroid bounds (ties: x before y before z).
        Aabb cb;
        for (size_t i = lo; i < hi; ++i) cb.extend(items[i].centroid3);
        const Vec3 ext = cb.extent();
        int axis = 0;
        if (ext.y > ext[axis]) axis = 1;
        if (ext.z > ext[axis]) axis = 2;
        const size_t mid = lo + (hi - lo) / 2;
        std::nth_element(items.begin() + lo, items.begin() + mid, items.begin() + hi,
                         [axis](const ChunkItem &a, const ChunkItem &c) {
                             const double ka = a.centroid3[axis], kc = c.centroid3[axis];
                             return ka < kc || (ka == kc && a.id < c.id);
                         });
        stack.push_back({mid, hi});
        stack.push_back({lo, mid});
    }
}

bool fail(std::string *err, const std::string &m) {
    if (err) *err = m;
    return false;
}

}  // namespace

namespace {
// 1. A source object's triangles (ids tri..): non-finite and degenerate ones counted and left out,
// the others' planes computed and listed in `items` for chunking.
bool classifyTriangles(const SceneBuildInput::Object &o, uint64_t tri, Scene &s, std::vector<ChunkItem> &items,
                       std::string *err) {
    const RawMesh &g = o.geometry;
    const uint32_t triangleCount = uint32_t(g.indices.size() / 3);
    items.clear();
    const size_t nv = g.positions.size();
    for (uint32_t t = 0; t < triangleCount; ++t) {
        const uint32_t i0 = g.indices[3 * t], i1 = g.indices[3 * t + 1], i2 = g.indices[3 * t + 2];
        if (i0 >= nv || i1 >= nv || i2 >= nv)
            return fail(err, "object '" + o.name + "': triangle " + std::to_string(t) +
                                 " has a vertex index outside its " + std::to_string(nv) +
                                 " positions (internal error in the loader)");
        const Vec3 v0 = g.positions[i0], v1 = g.positions[i1], v2 = g.positions[i2];
        const uint64_t id = tri + t;
        if (!isFinite(v0) || !isFinite(v1) || !isFinite(v2)) {
            ++s.stats.nonFiniteTriangles;
            continue;
        }
        // Zero area, decided exactly as far as double allows: equal vertices, or a cross product
        // that is exactly zero (collinear, or so thin that every component underflows).
        const Vec3 n = cross(v1 - v0, v2 - v0);
        if (v0 == v1 || v1 == v2 || v0 == v2 || (n.x == 0 && n.y == 0 && n.z == 0)) {
            ++s.stats.degenerateTriangles;
            continue;
        }
        // Finite coordinates can still overflow the cross product (|coordinates| > ~1e154); such a
        // plane is not representable, so the triangle is counted as non-finite.
        const double k = -dot(n, v0);
        if (!isFinite(n) || !std::isfinite(k)) {
            ++s.stats.nonFiniteTriangles;
            continue;
        }
        double *p = &s.planes[4 * id];
        p[0] = n.x, p[1] = n.y, p[2] = n.z, p[3] = k;
        s.planeBounds[2 * id] = std::fabs(n.x) + std::fabs(n.y) + std::fabs(n.z);
        s.planeBounds[2 * id + 1] = std::fmax(maxAbs(v0), std::fmax(maxAbs(v1), maxAbs(v2)));
        items.push_back({v0 + v1 + v2, uint32_t(id)});
    }

    return true;
}

// Conservative bounding sphere: center = AABB center, radius = the largest computed distance to a
// vertex, rounded up. A computed dot(d, d) has at most 5 rounded operations along any path
// (subtraction, square, two additions; all terms are >= 0), so it is within a relative gamma(5) of the
// true squared distance; the sqrt halves that and adds half an ulp, leaving the distance within a
// relative gamma(4). Scaling by (1 + gamma(6)) (itself rounded by at most half an ulp, covered by the
// slack) makes the radius an upper bound.
void boundingSphere(const Scene &s, SceneObject &so) {
    so.sphere.center = so.bounds.center();
    double r2 = 0;
    for (uint32_t v = so.vertexBegin; v < so.vertexEnd; ++v) {
        const Vec3 d = s.positions[v] - so.sphere.center;
        r2 = std::max(r2, dot(d, d));
    }
    so.sphere.radius = std::sqrt(r2) * (1 + gamma(6));
}

}  // namespace

// ---- The backface stage's float filter ------------------------------------------------------------
// The backface stage (analysis/stages/backface.cpp) decides most triangles with the plane rounded to
// float, read in objectTriangles order (sequential, 16 bytes a triangle instead of a gather of 48).
// The bound, pbrt-style, with u = 2^-24 (float's unit roundoff), the double plane (n, k), A = |n|_1,
// V = the largest |coordinate| of the triangle's vertices, M = maxAbs(eye) and D the exact
// orientation value at the eye, whose sign is the answer:
//   - the double filter's bound (backface.cpp filteredSide): |n.e + k - D| <= gamma(12) A (M + V);
//   - n', k', e' rounded to float: |n' - n| <= u|n| (per coordinate), likewise k' and e'; so
//     |n'.e' + k' - (n.e + k)| <= u|n|.|e'| + u|n|.|e| + u|k| <= (2u + u^2) A M + u|k|;
//   - s' = ((n'x e'x + n'y e'y) + n'z e'z) + k' in float: |s' - (n'.e' + k')| <= gamma_f(4)
//     (|n'|.|e'| + |k'|) <= gamma_f(4) (1 + u)^2 (A M + |k|);
//   so |s' - D| <= 8u (A M + |k|) + gamma(12) A (M + V) = A ((8u + gamma(12)) M + gamma(12) V) + 8u |k|.
// The stage has n' and k', not A and |k|: A <= A' (1 + 4u) with A' = (|n'x| + |n'y|) + |n'z| summed
// in float (each |n'| within u of |n|, two roundings of the sum), |k| <= |k'| (1 + 2u); and V is
// bounded by the largest V of the triangle's culling object (objectV, rounded up). So
//   |s' - D| <= A' P + |k'| K,  P = (1 + 4u) ((8u + gamma(12)) M + gamma(12) V_object),  K = 8u (1 + 2u),
// both doubled and rounded up to float (BackfacePlanes::bound), which covers evaluating A' P +
// |k'| K in float (three roundings, a relative error of a few u) with M rounded up. The stage
// decides front when s' > that bound, back when s' < -bound, and leaves every other triangle -- NaN
// and overflow to infinity included, where no comparison holds -- to the double test.
static float roundUpToFloat(double x) {
    const float f = float(x);
    return double(f) < x ? std::nextafter(f, std::numeric_limits<float>::infinity()) : f;
}

Scene::BackfaceBound Scene::BackfacePlanes::bound(uint32_t object, double eyeMax) const {
    constexpr double u = 0x1p-24;
    const double M = double(roundUpToFloat(eyeMax)), V = double(objectV[object]);
    return {roundUpToFloat(2 * (1 + 4 * u) * ((8 * u + gamma(12)) * M + gamma(12) * V)),
            roundUpToFloat(2 * 8 * u * (1 + 2 * u))};
}

// Per objectTriangles entry, the plane rounded to float; per culling object, the largest |coordinate|
// of its triangles' vertices (planeBounds), rounded up.
static void buildBackfacePlanes(Scene &s) {
    Scene::BackfacePlanes &q = s.backfacePlanes;
    q.resize(s.objectTriangles.size());
    for (size_t i = 0; i < s.objectTriangles.size(); ++i) {
        const double *p = &s.planes[4 * size_t(s.objectTriangles[i])];
        q.set(i, {float(p[0]), float(p[1]), float(p[2]), float(p[3])});
    }
    q.objectV.assign(s.objects.size(), 0.0f);
    for (size_t o = 0; o < s.objects.size(); ++o) {
        double V = 0;
        for (uint32_t i = s.objects[o].triBegin; i < s.objects[o].triEnd; ++i)
            V = std::max(V, s.planeBounds[2 * size_t(s.objectTriangles[i]) + 1]);
        q.objectV[o] = roundUpToFloat(V);
    }
}

bool buildScene(SceneBuildInput &&in, const ChunkSettings &chunks, Scene *outScene, std::string *err) {
    Scene s;
    s.path = std::move(in.path);
    s.up = in.up;
    s.materials = std::move(in.materials);
    if (s.materials.empty()) s.materials.push_back(Material{});
    s.lights = std::move(in.lights);
    s.views = std::move(in.views);
    const uint32_t maxTris = std::max<uint32_t>(1, chunks.maxTriangles);

    // Count source triangles; ids are uint32 and kExcludedTriangle is reserved for object ids only,
    // so up to 2^32 - 1 triangles fit.
    uint64_t total = 0;
    for (const auto &o : in.objects) {
        if (o.geometry.indices.size() % 3 != 0)
            return fail(err, "object '" + o.name + "': index count " + std::to_string(o.geometry.indices.size()) +
                                 " is not a multiple of 3 (internal error in the loader)");
        if (o.material >= s.materials.size())
            return fail(err, "object '" + o.name + "': material index " + std::to_string(o.material) +
                                 " out of range (" + std::to_string(s.materials.size()) + " materials)");
        total += o.geometry.indices.size() / 3;
    }
    if (total > std::numeric_limits<uint32_t>::max())
        return fail(err, "the scene has " + std::to_string(total) +
                             " triangles; at most 4294967295 fit visaudit's 32-bit triangle ids");

    s.stats.sourceTriangles = total;
    s.indices.assign(total * 3, 0);  // excluded triangles keep {0, 0, 0} (see scene.h)
    s.triangleObject.assign(total, kExcludedTriangle);
    s.planes.assign(total * 4, 0.0);  // excluded triangles keep the plane (0, 0, 0, 0)
    s.planeBounds.assign(total * 2, 0.0);
    s.objectTriangles.reserve(total);
    s.positions.reserve(total / 2 + 16);  // a closed mesh has about half as many vertices as triangles

    std::vector<ChunkItem> items;
    std::vector<std::pair<size_t, size_t>> leaves;
    std::vector<uint32_t> remap, stamp;  // per source vertex: new index, and the chunk that set it
    uint64_t tri = 0;                    // global id of the object's first triangle

    for (auto &o : in.objects) {
        const RawMesh &g = o.geometry;
        SourceObject src;
        src.name = o.name;
        src.mesh = o.mesh;
        src.material = o.material;
        src.firstTriangle = uint32_t(tri);
        src.triangleCount = uint32_t(g.indices.size() / 3);
        src.firstChunk = uint32_t(s.objects.size());
        s.stats.facesDropped += g.facesDropped;
        s.stats.polygonsTriangulated += g.polygonsTriangulated;
        for (const auto &w : g.warnings) s.warnings.push_back(w);

        // 1. Classify and compute planes.
        if (!classifyTriangles(o, tri, s, items, err)) return false;
        const size_t nv = g.positions.size();

        // 2. Chunks. A source object small enough stays one object (named without "#k").
        leaves.clear();
        if (!items.empty()) splitChunks(items, 0, items.size(), maxTris, &leaves);
        const bool split = leaves.size() > 1;

        // 3. Vertex ranges, index rewrite, bounds.
        remap.assign(nv, 0);
        stamp.assign(nv, kExcludedTriangle);
        for (size_t c = 0; c < leaves.size(); ++c) {
            auto [lo, hi] = leaves[c];
            // Source order within the object.
            std::sort(items.begin() + lo, items.begin() + hi,
                      [](const ChunkItem &a, const ChunkItem &b) { return a.id < b.id; });
            if (s.objects.size() >= kExcludedTriangle - 1)
                return fail(err, "the scene would have more than 2^32 - 2 culling objects; raise the chunk size");
            const uint32_t objIndex = uint32_t(s.objects.size());
            SceneObject so;
            so.name = split ? o.name + "#" + std::to_string(c) : o.name;
            so.source = uint32_t(s.sources.size());
            so.material = o.material;
            so.vertexBegin = uint32_t(s.positions.size());
            so.triBegin = uint32_t(s.objectTriangles.size());
            for (size_t i = lo; i < hi; ++i) {
                const uint32_t id = items[i].id;
                const uint32_t t = uint32_t(id - tri);
                for (int k = 0; k < 3; ++k) {
                    const uint32_t v = g.indices[3 * t + k];
                    if (stamp[v] != objIndex) {
                        if (s.positions.size() >= std::numeric_limits<uint32_t>::max())
                            return fail(err, "the scene needs more than 4294967295 vertices after chunking "
                                             "(visaudit's indices are 32-bit); split the level into smaller files");
                        stamp[v] = objIndex;
                        remap[v] = uint32_t(s.positions.size());
                        s.positions.push_back(g.positions[v]);
                        so.bounds.extend(g.positions[v]);
                    }
                    s.indices[3 * size_t(id) + k] = remap[v];
                }
                s.triangleObject[id] = objIndex;
                s.objectTriangles.push_back(id);
            }
            so.vertexEnd = uint32_t(s.positions.size());
            so.triEnd = uint32_t(s.objectTriangles.size());

            boundingSphere(s, so);
            s.bounds.extend(so.bounds);
            s.objects.push_back(std::move(so));
        }
        src.chunkCount = uint32_t(leaves.size());
        s.sources.push_back(std::move(src));
        tri += g.indices.size() / 3;
        o.geometry = RawMesh{};  // release the source mesh as soon as it has been copied
    }
    for (auto &w : in.warnings) s.warnings.push_back(std::move(w));
    s.positions.shrink_to_fit();
    buildBackfacePlanes(s);
    *outScene = std::move(s);
    return true;
}

Scene buildScene(SceneBuildInput &&in, const ChunkSettings &chunks) {
    Scene s;
    std::string err;
    if (!buildScene(std::move(in), chunks, &s, &err)) throw std::runtime_error("buildScene: " + err);
    return s;
}

Cell boxCell(const std::string &name, Vec3 lo, Vec3 hi) {
    Cell c;
    c.name = name;
    c.box.lo = lo;
    c.box.hi = hi;
    for (int a = 0; a < 3; ++a) {
        Vec3 n{0, 0, 0};
        n[a] = 1;
        c.faces.push_back({n, -lo[a]});
        n[a] = -1;
        c.faces.push_back({n, hi[a]});
    }
    return c;
}

}  // namespace va
