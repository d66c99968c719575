// The clip stage's per-vertex pass with AVX2, four vertices at a time (CMakeLists.txt: -mavx2;
// clip_vertices.h). Every lane does transformVerticesBody's operations in its order with the same
// IEEE double operations (multiplies and adds apart, never fused; ordered, quiet comparisons as
// C++'s < and >; the exact conversion of an integer-valued double), so the bits are the same; the
// last n % 4 vertices take the scalar body. Then the common case of the triangle loop four
// triangles at a time (acceptGroupsAvx2: their depth planes as DepthPlaneMaker computes them, lane
// by lane). clip.cpp calls both only when the CPU has AVX2.
#include "render/clip_vertices.h"

#if defined(__AVX2__)
#include <immintrin.h>

#include <cmath>
#include <cstddef>
#include <cstring>

namespace va::clip_detail {

namespace {

// toFixedSelect on four lanes.
inline __m128i toFixed4(__m256d pixelCoordinate) {
    const __m256d x = _mm256_mul_pd(pixelCoordinate, _mm256_set1_pd(double(kSubpixelOne)));
    const __m256d kRound = _mm256_set1_pd(0x1.8p52);
    const __m256d r = _mm256_sub_pd(_mm256_add_pd(x, kRound), kRound);
    const __m256d small = _mm256_and_pd(_mm256_cmp_pd(x, _mm256_set1_pd(0x1p51), _CMP_LT_OQ),
                                        _mm256_cmp_pd(x, _mm256_set1_pd(-0x1p51), _CMP_GT_OQ));
    __m256d s = _mm256_blendv_pd(x, r, small);
    const __m256d lo = _mm256_set1_pd(-2147483648.0), hi = _mm256_set1_pd(2147483647.0);
    s = _mm256_blendv_pd(lo, s, _mm256_cmp_pd(s, lo, _CMP_GT_OQ));
    s = _mm256_blendv_pd(s, hi, _mm256_cmp_pd(s, hi, _CMP_GT_OQ));
    return _mm256_cvttpd_epi32(s);
}

// The lanes of a comparison as an outcode bit (64-bit lanes).
inline __m256i bitIf(__m256d mask, uint32_t bit) {
    return _mm256_and_si256(_mm256_castpd_si256(mask), _mm256_set1_epi64x(int64_t(bit)));
}

template <bool kOrtho>
void transform4(const VertexPassParams &p, const Vec3 *pos, uint32_t n, BatchVertices &bv) {
    const __m256d m00 = _mm256_set1_pd(p.m[0][0]), m01 = _mm256_set1_pd(p.m[0][1]), m02 = _mm256_set1_pd(p.m[0][2]),
                  m03 = _mm256_set1_pd(p.m[0][3]);
    const __m256d m10 = _mm256_set1_pd(p.m[1][0]), m11 = _mm256_set1_pd(p.m[1][1]), m12 = _mm256_set1_pd(p.m[1][2]),
                  m13 = _mm256_set1_pd(p.m[1][3]);
    const __m256d m20 = _mm256_set1_pd(p.m[2][0]), m21 = _mm256_set1_pd(p.m[2][1]), m22 = _mm256_set1_pd(p.m[2][2]),
                  m23 = _mm256_set1_pd(p.m[2][3]);
    const __m256d sx = _mm256_set1_pd(p.sx), sy = _mm256_set1_pd(p.sy), nearZ = _mm256_set1_pd(p.nearZ),
                  farZ = _mm256_set1_pd(p.farZ), gx = _mm256_set1_pd(p.gx), gy = _mm256_set1_pd(p.gy);
    const __m256d halfW = _mm256_set1_pd(p.halfW), halfH = _mm256_set1_pd(p.halfH), one = _mm256_set1_pd(1.0);
    const __m256d negZero = _mm256_set1_pd(-0.0);
    // Gathers the low 32 bits of the four 64-bit lanes into the low 128 bits.
    const __m256i low32 = _mm256_setr_epi32(0, 2, 4, 6, 0, 2, 4, 6);
    const size_t n4 = size_t(n) & ~size_t(3);
    for (size_t i = 0; i < n4; i += 4) {
        const Vec3 *q = pos + i;
        __builtin_prefetch(q + 64);  // 1.5 KB ahead: the positions stream from memory
        const __m256d px = _mm256_setr_pd(q[0].x, q[1].x, q[2].x, q[3].x);
        const __m256d py = _mm256_setr_pd(q[0].y, q[1].y, q[2].y, q[3].y);
        const __m256d pz = _mm256_setr_pd(q[0].z, q[1].z, q[2].z, q[3].z);
        // ((m0 px + m1 py) + m2 pz) + m3, as transformPoint's expression associates.
        const __m256d vx = _mm256_add_pd(
            _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(m00, px), _mm256_mul_pd(m01, py)), _mm256_mul_pd(m02, pz)), m03);
        const __m256d vy = _mm256_add_pd(
            _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(m10, px), _mm256_mul_pd(m11, py)), _mm256_mul_pd(m12, pz)), m13);
        const __m256d vz = _mm256_add_pd(
            _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(m20, px), _mm256_mul_pd(m21, py)), _mm256_mul_pd(m22, pz)), m23);
        _mm256_storeu_pd(bv.x.data() + i, vx);
        _mm256_storeu_pd(bv.y.data() + i, vy);
        _mm256_storeu_pd(bv.z.data() + i, vz);
        const __m256d d = _mm256_xor_pd(vz, negZero);  // -vz
        const __m256d cx = _mm256_mul_pd(sx, vx), cy = _mm256_mul_pd(sy, vy);
        const __m256d w = kOrtho ? one : d;
        const __m256d negW = _mm256_xor_pd(w, negZero);
        const __m256d gxw = _mm256_mul_pd(gx, w), gyw = _mm256_mul_pd(gy, w);
        // -gx * w is (-gx) * w: the same magnitude as gx * w with the sign flipped, exactly.
        const __m256d negGxw = _mm256_xor_pd(gxw, negZero), negGyw = _mm256_xor_pd(gyw, negZero);
        __m256i c = bitIf(_mm256_cmp_pd(d, nearZ, _CMP_LT_OQ), outBit(kPlaneNear));
        c = _mm256_or_si256(c, bitIf(_mm256_cmp_pd(d, farZ, _CMP_GT_OQ), outBit(kPlaneFar)));
        c = _mm256_or_si256(c, bitIf(_mm256_cmp_pd(cx, negW, _CMP_LT_OQ), outBit(kPlaneLeft)));
        c = _mm256_or_si256(c, bitIf(_mm256_cmp_pd(cx, w, _CMP_GT_OQ), outBit(kPlaneRight)));
        c = _mm256_or_si256(c, bitIf(_mm256_cmp_pd(cy, negW, _CMP_LT_OQ), outBit(kPlaneBottom)));
        c = _mm256_or_si256(c, bitIf(_mm256_cmp_pd(cy, w, _CMP_GT_OQ), outBit(kPlaneTop)));
        c = _mm256_or_si256(c, bitIf(_mm256_cmp_pd(cx, negGxw, _CMP_LT_OQ), guardBit(kPlaneLeft)));
        c = _mm256_or_si256(c, bitIf(_mm256_cmp_pd(cx, gxw, _CMP_GT_OQ), guardBit(kPlaneRight)));
        c = _mm256_or_si256(c, bitIf(_mm256_cmp_pd(cy, negGyw, _CMP_LT_OQ), guardBit(kPlaneBottom)));
        c = _mm256_or_si256(c, bitIf(_mm256_cmp_pd(cy, gyw, _CMP_GT_OQ), guardBit(kPlaneTop)));
        _mm_storeu_si128(reinterpret_cast<__m128i *>(bv.code.data() + i),
                         _mm256_castsi256_si128(_mm256_permutevar8x32_epi32(c, low32)));
        const __m256d inv = _mm256_div_pd(one, w);
        const __m128i sx4 = toFixed4(_mm256_mul_pd(_mm256_add_pd(_mm256_mul_pd(cx, inv), one), halfW));
        const __m128i sy4 = toFixed4(_mm256_mul_pd(_mm256_sub_pd(one, _mm256_mul_pd(cy, inv)), halfH));
        _mm_storeu_si128(reinterpret_cast<__m128i *>(bv.sxy.data() + 2 * i), _mm_unpacklo_epi32(sx4, sy4));
        _mm_storeu_si128(reinterpret_cast<__m128i *>(bv.sxy.data() + 2 * i + 4), _mm_unpackhi_epi32(sx4, sy4));
    }
    transformVerticesBody<kOrtho>(p, pos, n4, n, bv);  // the last n % 4
}

inline __m256d isFinite4(__m256d v) {
    const __m256d absMask = _mm256_castsi256_pd(_mm256_set1_epi64x(0x7FFFFFFFFFFFFFFF));
    return _mm256_cmp_pd(_mm256_and_pd(v, absMask), _mm256_set1_pd(INFINITY), _CMP_LT_OQ);
}

}  // namespace

uint32_t acceptGroupsAvx2(const DepthPlaneMaker &p, const BatchVertices &bv, const uint32_t *indices,
                          const ClipBatch &batch, uint32_t k, ScreenTriangles &out, AcceptCounts &counts) {
    // A group is taken when no triangle has all three corners outside one frustum plane and no
    // corner is outside near, far or the guard band.
    const __m256d ax = _mm256_set1_pd(p.ax), bx = _mm256_set1_pd(p.bx), ay = _mm256_set1_pd(p.ay),
                  by = _mm256_set1_pd(p.by);
    const __m256d negZero = _mm256_set1_pd(-0.0), zero = _mm256_setzero_pd();
    const double *X = bv.x.data(), *Y = bv.y.data(), *Z = bv.z.data();
    const uint32_t *code = bv.code.data();
    const int32_t *sxy = bv.sxy.data();
    const uint32_t *tri = batch.triangles;
    // The fourth double of each plane row: the bytes of `valid = true` and zero padding.
    const __m256d validWord = _mm256_castsi256_pd(_mm256_set1_epi64x(1));
    static_assert(sizeof(DepthPlane) == 32 && offsetof(DepthPlane, valid) == 24, "DepthPlane's layout");

    // Room for every group left in the batch, written in place (ScreenTriangles' vectors add
    // elements unwritten: render/raw_vector.h) and cut back to what was taken at the end.
    const uint32_t begin = k, vb = batch.vertexBegin;
    const size_t room = (batch.count - k) & ~size_t(3);
    const size_t t0 = out.source.size(), p0 = out.planes.size();
    out.planes.resize(p0 + room);
    out.xy.resize(6 * (t0 + room));
    out.source.resize(t0 + room);
    out.plane.resize(t0 + room);
    DepthPlane *planesOut = out.planes.data() + p0;
    int32_t *xyOut = out.xy.data() + 6 * t0;
    uint32_t *sourceOut = out.source.data() + t0, *planeOut = out.plane.data() + t0;
    uint64_t inside = 0;
    for (; k + 4 <= batch.count; k += 4) {
        if (k + 20 <= batch.count)
            for (int j = 16; j < 20; ++j) __builtin_prefetch(indices + 3 * size_t(tri[k + j]));
        // Indices and outcodes in scalar registers (vector gathers of them measured slower here).
        uint32_t i0[4], i1[4], i2[4], bad = 0, insideHere = 0;
        for (int j = 0; j < 4; ++j) {
            const uint32_t *t = indices + 3 * size_t(tri[k + j]);
            i0[j] = t[0] - vb, i1[j] = t[1] - vb, i2[j] = t[2] - vb;
            const uint32_t c0 = code[i0[j]], c1 = code[i1[j]], c2 = code[i2[j]];
            const uint32_t any = c0 | c1 | c2;
            bad |= (c0 & c1 & c2 & kFrustumBits) | (any & kClipBits);
            insideHere += any == 0;
        }
        if (bad) break;

        // DepthPlaneMaker::operator() (camera.h) on four triangles: n = (v1 - v0) x (v2 - v0),
        // k = -(n . v0), then the plane's three coefficients, each operation as there.
        auto load4 = [](const double *a, const uint32_t *i) {
            return _mm256_setr_pd(a[i[0]], a[i[1]], a[i[2]], a[i[3]]);
        };
        const __m256d x0 = load4(X, i0), y0 = load4(Y, i0), z0 = load4(Z, i0);
        const __m256d x1 = load4(X, i1), y1 = load4(Y, i1), z1 = load4(Z, i1);
        const __m256d x2 = load4(X, i2), y2 = load4(Y, i2), z2 = load4(Z, i2);
        const __m256d ex = _mm256_sub_pd(x1, x0), ey = _mm256_sub_pd(y1, y0), ez = _mm256_sub_pd(z1, z0);
        const __m256d fx = _mm256_sub_pd(x2, x0), fy = _mm256_sub_pd(y2, y0), fz = _mm256_sub_pd(z2, z0);
        const __m256d nx = _mm256_sub_pd(_mm256_mul_pd(ey, fz), _mm256_mul_pd(ez, fy));
        const __m256d ny = _mm256_sub_pd(_mm256_mul_pd(ez, fx), _mm256_mul_pd(ex, fz));
        const __m256d nz = _mm256_sub_pd(_mm256_mul_pd(ex, fy), _mm256_mul_pd(ey, fx));
        const __m256d dot = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(nx, x0), _mm256_mul_pd(ny, y0)),
                                          _mm256_mul_pd(nz, z0));
        const __m256d kk = _mm256_xor_pd(dot, negZero);
        const __m256d nb = _mm256_add_pd(_mm256_mul_pd(nx, bx), _mm256_mul_pd(ny, by));  // n.x bx + n.y by
        __m256d a, b, c, ok;
        if (p.orthographic) {
            ok = _mm256_and_pd(_mm256_cmp_pd(nz, zero, _CMP_NEQ_OQ), isFinite4(kk));
            a = _mm256_div_pd(_mm256_mul_pd(nx, ax), nz);
            b = _mm256_div_pd(_mm256_mul_pd(ny, ay), nz);
            c = _mm256_div_pd(_mm256_add_pd(nb, kk), nz);
        } else {
            ok = _mm256_and_pd(_mm256_cmp_pd(kk, zero, _CMP_NEQ_OQ), isFinite4(kk));
            a = _mm256_div_pd(_mm256_mul_pd(_mm256_xor_pd(nx, negZero), ax), kk);
            b = _mm256_div_pd(_mm256_mul_pd(_mm256_xor_pd(ny, negZero), ay), kk);
            c = _mm256_div_pd(_mm256_xor_pd(_mm256_sub_pd(nb, nz), negZero), kk);
        }
        ok = _mm256_and_pd(ok, _mm256_and_pd(isFinite4(a), _mm256_and_pd(isFinite4(b), isFinite4(c))));
        if (_mm256_movemask_pd(ok) != 0xF) break;

        // Taken: the planes as four rows (a, b, c, valid), the corners, sources and plane indices.
        const size_t j0 = k - begin;  // the group's first output slot
        // ab01 = a0 b0 | a2 b2, ab23 = a1 b1 | a3 b3; cv01, cv23 likewise: rows from their halves.
        const __m256d ab01 = _mm256_unpacklo_pd(a, b), ab23 = _mm256_unpackhi_pd(a, b);
        const __m256d cv01 = _mm256_unpacklo_pd(c, validWord), cv23 = _mm256_unpackhi_pd(c, validWord);
        double *dst = reinterpret_cast<double *>(planesOut + j0);
        _mm256_storeu_pd(dst + 0, _mm256_permute2f128_pd(ab01, cv01, 0x20));
        _mm256_storeu_pd(dst + 4, _mm256_permute2f128_pd(ab23, cv23, 0x20));
        _mm256_storeu_pd(dst + 8, _mm256_permute2f128_pd(ab01, cv01, 0x31));
        _mm256_storeu_pd(dst + 12, _mm256_permute2f128_pd(ab23, cv23, 0x31));
        int32_t *xy = xyOut + 6 * j0;
        for (int j = 0; j < 4; ++j) {
            std::memcpy(xy + 6 * j, sxy + 2 * size_t(i0[j]), 8);
            std::memcpy(xy + 6 * j + 2, sxy + 2 * size_t(i1[j]), 8);
            std::memcpy(xy + 6 * j + 4, sxy + 2 * size_t(i2[j]), 8);
        }
        _mm_storeu_si128(reinterpret_cast<__m128i *>(sourceOut + j0),
                         _mm_loadu_si128(reinterpret_cast<const __m128i *>(tri + k)));
        const int32_t pi = int32_t(p0 + j0);
        _mm_storeu_si128(reinterpret_cast<__m128i *>(planeOut + j0),
                         _mm_add_epi32(_mm_set1_epi32(pi), _mm_setr_epi32(0, 1, 2, 3)));
        inside += insideHere;
    }
    const uint32_t taken = k - begin;
    out.planes.resize(p0 + taken);
    out.xy.resize(6 * (t0 + taken));
    out.source.resize(t0 + taken);
    out.plane.resize(t0 + taken);
    counts.inside += inside;
    counts.guardBandAccepted += taken - inside;
    return taken;
}

void transformVerticesAvx2(const VertexPassParams &p, const Vec3 *pos, uint32_t n, BatchVertices &bv) {
    if (p.orthographic) transform4<true>(p, pos, n, bv);
    else transform4<false>(p, pos, n, bv);
}

}  // namespace va::clip_detail
#else
namespace va::clip_detail {
// Built without -mavx2 (not an x86-64 compiler): the scalar pass.
void transformVerticesAvx2(const VertexPassParams &p, const Vec3 *pos, uint32_t n, BatchVertices &bv) {
    if (p.orthographic) transformVerticesBody<true>(p, pos, 0, n, bv);
    else transformVerticesBody<false>(p, pos, 0, n, bv);
}
uint32_t acceptGroupsAvx2(const DepthPlaneMaker &, const BatchVertices &, const uint32_t *, const ClipBatch &, uint32_t,
                          ScreenTriangles &, AcceptCounts &) {
    return 0;  // every triangle through clipOne
}
}  // namespace va::clip_detail
#endif
