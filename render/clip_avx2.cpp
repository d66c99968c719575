// The clip stage's per-vertex pass with AVX2, four vertices at a time (CMakeLists.txt: -mavx2;
// clip_vertices.h). Every lane does transformVerticesBody's operations in its order with the same
// IEEE double operations (multiplies and adds apart, never fused; ordered, quiet comparisons as
// C++'s < and >; the exact conversion of an integer-valued double), so the bits are the same; the
// last n % 4 vertices take the scalar body. clip.cpp calls it only when the CPU has AVX2.
#include "render/clip_vertices.h"

#if defined(__AVX2__)
#include <immintrin.h>

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
        _mm_storeu_si128(reinterpret_cast<__m128i *>(bv.sx.data() + i),
                         toFixed4(_mm256_mul_pd(_mm256_add_pd(_mm256_mul_pd(cx, inv), one), halfW)));
        _mm_storeu_si128(reinterpret_cast<__m128i *>(bv.sy.data() + i),
                         toFixed4(_mm256_mul_pd(_mm256_sub_pd(one, _mm256_mul_pd(cy, inv)), halfH)));
    }
    transformVerticesBody<kOrtho>(p, pos, n4, n, bv);  // the last n % 4
}

}  // namespace

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
}  // namespace va::clip_detail
#endif
