#include "analysis/stages/backface.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

namespace va {

namespace {
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;

// Sign of the triangle's plane at point e, exactly: +1 when e is on the side from which
// (v0, v1, v2) appear counter-clockwise (the front), -1 behind, 0 on the plane.
int exactSide(Vec3 v0, Vec3 v1, Vec3 v2, Vec3 e) {
    const CGAL::Orientation o = CGAL::orientation(Kernel::Point_3(v0.x, v0.y, v0.z), Kernel::Point_3(v1.x, v1.y, v1.z),
                                                  Kernel::Point_3(v2.x, v2.y, v2.z), Kernel::Point_3(e.x, e.y, e.z));
    // CGAL: POSITIVE when det[v1 - v0, v2 - v0, e - v0] > 0, i.e. when v0, v1, v2 appear
    // counter-clockwise seen from e (checked: (0,0,0), (1,0,0), (0,1,0) from (0,0,1) is POSITIVE).
    return o == CGAL::POSITIVE ? 1 : (o == CGAL::NEGATIVE ? -1 : 0);
}
// The perspective filter: n.e + k in double, against a bound on its rounding error that covers the
// computation of n and k from the vertices too (pbrt-style gamma bound, generous factor). The
// magnitudes come precomputed per triangle (Scene::planeBounds), so the common case reads the plane
// and two numbers, never the vertices. +1 front, -1 back, 0 undecided (the exact test decides).
// eyeMax = maxAbs(eye).
inline int filteredSide(const Scene &scene, uint32_t t, Vec3 eye, double eyeMax) {
    const double *p = &scene.planes[4 * size_t(t)];
    const double *b = &scene.planeBounds[2 * size_t(t)];
    const double s = dot(Vec3{p[0], p[1], p[2]}, eye) + p[3];
    const double err = gamma(12) * (b[0] * (eyeMax + b[1]));
    return s > err ? 1 : (s < -err ? -1 : 0);
}

#if defined(__x86_64__) || defined(__i386__)
// For each 8-bit mask, the positions of its set bits in ascending order, then the rest (a
// permutation that packs the lanes a mask selects to the front, keeping their order).
struct PackTable {
    uint8_t lane[256][8];
    constexpr PackTable() : lane{} {
        for (int m = 0; m < 256; ++m) {
            int k = 0;
            for (int i = 0; i < 8; ++i)
                if (m >> i & 1) lane[m][k++] = uint8_t(i);
            for (int i = 0; i < 8; ++i)
                if (!(m >> i & 1)) lane[m][k++] = uint8_t(i);
        }
    }
};
constexpr PackTable kPack;

// The float filter over an object's triangles [0, n8) (n8: n rounded down to 8), eight at a time,
// with the loop's arithmetic in the same order (so the same verdicts), and the triangles it decides
// packed into kept and culled in order (8 lanes stored, the count advanced by those taken: both
// have 8 entries of room past their end). A group with an undecided triangle goes to `one` (the
// double and exact tests) triangle by triangle with its verdict (+1, -1, 0), in order.
template <class One>
__attribute__((target("avx2"))) uint32_t frontOrBackAvx2(const float *qx, const float *qy, const float *qz,
                                                          const float *qk, Scene::BackfaceBound b, float ex, float ey,
                                                          float ez, const uint32_t *tris, uint32_t n, uint32_t *kept,
                                                          size_t &nk, uint32_t *culled, size_t &nc, One &&one) {
    const __m256 vx = _mm256_set1_ps(ex), vy = _mm256_set1_ps(ey), vz = _mm256_set1_ps(ez);
    const __m256 pn = _mm256_set1_ps(b.perNormal), pk = _mm256_set1_ps(b.perOffset);
    const __m256 absMask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7FFFFFFF)), negZero = _mm256_set1_ps(-0.0f);
    uint32_t j = 0;
    for (; j + 8 <= n; j += 8) {
        const __m256 x = _mm256_loadu_ps(qx + j), y = _mm256_loadu_ps(qy + j), z = _mm256_loadu_ps(qz + j),
                     k = _mm256_loadu_ps(qk + j);
        const __m256 sf = _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(x, vx), _mm256_mul_ps(y, vy)),
                                                      _mm256_mul_ps(z, vz)),
                                        k);
        const __m256 sum = _mm256_add_ps(_mm256_add_ps(_mm256_and_ps(x, absMask), _mm256_and_ps(y, absMask)),
                                         _mm256_and_ps(z, absMask));
        const __m256 bound = _mm256_add_ps(_mm256_mul_ps(sum, pn), _mm256_mul_ps(_mm256_and_ps(k, absMask), pk));
        const unsigned front = unsigned(_mm256_movemask_ps(_mm256_cmp_ps(sf, bound, _CMP_GT_OQ)));
        const unsigned back = unsigned(_mm256_movemask_ps(_mm256_cmp_ps(sf, _mm256_xor_ps(bound, negZero), _CMP_LT_OQ)));
        if ((front | back) != 0xFF) [[unlikely]] {
            for (int i = 0; i < 8; ++i) one(j + uint32_t(i), int(front >> i & 1) - int(back >> i & 1));
            continue;
        }
        const __m256i t = _mm256_loadu_si256(reinterpret_cast<const __m256i *>(tris + j));
        const __m256i toFront = _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i *>(kPack.lane[front])));
        const __m256i toBack = _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i *>(kPack.lane[back])));
        _mm256_storeu_si256(reinterpret_cast<__m256i *>(kept + nk), _mm256_permutevar8x32_epi32(t, toFront));
        _mm256_storeu_si256(reinterpret_cast<__m256i *>(culled + nc), _mm256_permutevar8x32_epi32(t, toBack));
        nk += unsigned(std::popcount(front));
        nc += unsigned(std::popcount(back));
    }
    return j;
}
#endif
}  // namespace

bool isFrontFacing(const Scene &scene, uint32_t t, const Camera &cam, bool *edgeOn) {
    const double *p = &scene.planes[4 * size_t(t)];
    const Vec3 n{p[0], p[1], p[2]};
    if (edgeOn) *edgeOn = false;
    if (cam.orthographic) {
        // Front when the normal points against the view direction: n . (-forward) > 0. Where the
        // sign is within the rounding of the dot product, keep the triangle (conservative).
        const double s = -dot(n, cam.forward);
        const double err = gamma(4) * (std::fabs(n.x * cam.forward.x) + std::fabs(n.y * cam.forward.y) +
                                       std::fabs(n.z * cam.forward.z));
        if (s == 0 && edgeOn) *edgeOn = true;
        return s > -err;
    }
    const Vec3 &e = cam.eye;
    if (const int side = filteredSide(scene, t, e, maxAbs(e)); side != 0) return side > 0;
    const uint32_t *ix = &scene.indices[3 * size_t(t)];
    const Vec3 v0 = scene.positions[ix[0]], v1 = scene.positions[ix[1]], v2 = scene.positions[ix[2]];
    const int side = exactSide(v0, v1, v2, e);
    if (side == 0 && edgeOn) *edgeOn = true;
    return side > 0;
}

std::vector<ClipBatch> clipBatches(const Scene &scene, const TriangleLists &lists) {
    std::vector<ClipBatch> batches;
    batches.reserve(lists.objects.size());
    for (size_t g = 0; g < lists.objects.size(); ++g) {
        const SceneObject &ob = scene.objects[lists.objects[g]];
        ClipBatch b;
        b.vertexBegin = ob.vertexBegin;
        b.vertexEnd = ob.vertexEnd;
        b.triangles = lists.triangles.data() + lists.groupBegin[g];
        b.count = lists.groupBegin[g + 1] - lists.groupBegin[g];
        if (b.count) batches.push_back(b);
    }
    return batches;
}

TriangleLists allTriangles(const Scene &scene, const std::vector<uint32_t> &objects) {
    TriangleLists l;
    l.objects = objects;
    l.groupBegin.reserve(objects.size() + 1);
    for (uint32_t o : objects) {
        l.groupBegin.push_back(uint32_t(l.triangles.size()));
        const SceneObject &ob = scene.objects[o];
        l.triangles.insert(l.triangles.end(), scene.objectTriangles.begin() + ob.triBegin,
                           scene.objectTriangles.begin() + ob.triEnd);
    }
    l.groupBegin.push_back(uint32_t(l.triangles.size()));
    return l;
}

BackfaceResult cullBackfaces(const Scene &scene, const std::vector<uint32_t> &objects, const Camera &cam) {
    BackfaceResult r;
    TriangleLists &l = r.kept;
    BackfaceStats &st = r.stats;
    l.objects.reserve(objects.size());
    uint64_t total = 0;
    for (uint32_t o : objects) total += scene.objects[o].triEnd - scene.objects[o].triBegin;
    const double eyeMax = maxAbs(cam.eye);
    // The float filter (scene.cpp, "The backface stage's float filter") decides a triangle from its
    // plane in float, read in object order; what it cannot decide goes to the double filter and the
    // exact test. Outputs are written branch-free into room for every triangle, then trimmed.
    const bool floatFilter = !cam.orthographic && scene.backfacePlanes.size() == scene.objectTriangles.size() &&
                             scene.backfacePlanes.objectV.size() == scene.objects.size();
    const float ex = float(cam.eye.x), ey = float(cam.eye.y), ez = float(cam.eye.z);
    l.triangles.resize(total + 8);  // 8 past the end: frontOrBackAvx2 stores eight lanes at a time
    r.culled.resize(total + 8);
#if defined(__x86_64__) || defined(__i386__)
    const bool avx2 = floatFilter && __builtin_cpu_supports("avx2");
#endif
    uint32_t *kept = l.triangles.data(), *culled = r.culled.data();
    size_t nk = 0, nc = 0;
    for (uint32_t o : objects) {
        const SceneObject &ob = scene.objects[o];
        const size_t begin = nk;
        const uint32_t n = ob.triEnd - ob.triBegin;
        const uint32_t *tris = scene.objectTriangles.data() + ob.triBegin;
        if (scene.materialOf(ob).doubleSided) {
            st.doubleSidedExempt += n;
            std::copy(tris, tris + n, kept + nk);
            nk += n;
        } else {
            st.trianglesTested += n;
            // One triangle with the float filter's verdict sd (+1 front, -1 back, 0 undecided): the
            // undecided by isFrontFacing's double filter, then the exact test where that cannot
            // decide; then the output, branch-free.
            auto one = [&](uint32_t j, int sd) {
                const uint32_t t = tris[j];
                bool edgeOn = false;
                if (sd == 0) sd = isFrontFacing(scene, t, cam, &edgeOn) ? 1 : -1;
                kept[nk] = t;
                culled[nc] = t;
                nk += sd > 0;
                nc += sd < 0;
                st.edgeOn += edgeOn && sd < 0;  // an edge-on triangle kept (orthographic) is not counted
            };
            const Scene::BackfacePlanes &q = scene.backfacePlanes;
            const Scene::BackfaceBound b = floatFilter ? q.bound(o, eyeMax) : Scene::BackfaceBound{};
            uint32_t from = 0;
#if defined(__x86_64__) || defined(__i386__)
            if (avx2)
                from = frontOrBackAvx2(q.nx.data() + ob.triBegin, q.ny.data() + ob.triBegin, q.nz.data() + ob.triBegin,
                                       q.k.data() + ob.triBegin, b, ex, ey, ez, tris, n, kept, nk, culled, nc, one);
#endif
            // The rest (all of them without AVX2) one at a time, with the same float arithmetic.
            for (uint32_t j = from; j < n; ++j) {
                int sd = 0;
                if (floatFilter) {
                    const Scene::BackfacePlane p = q[ob.triBegin + j];
                    const float sf = ((p.nx * ex + p.ny * ey) + p.nz * ez) + p.k;
                    const float bound = Scene::BackfacePlanes::boundOf(p, b);
                    sd = (sf > bound) - (sf < -bound);
                }
                one(j, sd);
            }
        }
        if (nk > begin) {  // objects with every triangle culled leave no group
            l.objects.push_back(o);
            l.groupBegin.push_back(uint32_t(begin));
        }
    }
    st.trianglesCulled = nc;
    l.triangles.resize(nk);
    r.culled.resize(nc);
    l.groupBegin.push_back(uint32_t(l.triangles.size()));
    return r;
}

}  // namespace va
