// The clip stage's per-vertex pass (clip.cpp), shared by its generic build and its AVX2 build
// (clip_avx2.cpp): a batch's vertices to view space, their outcodes and their projected
// fixed-point positions, as structure-of-arrays, without branches. Every operation is the scalar
// one in the scalar order (-ffp-contract=off: no fused multiply-add), so both give the same bits.
// Also the AVX2 build's accept path for the triangles (acceptGroupsAvx2, below), which reads the
// pass's output.
#pragma once

#include <cstdint>
#include <vector>

#include "render/clip.h"

namespace va::clip_detail {

// Outcode bits: the view frustum's six planes (bit = ClipPlane), then the guard band's four side
// planes (bit = side plane + 4).
constexpr uint32_t outBit(int plane) { return 1u << plane; }
constexpr uint32_t guardBit(int plane) { return 1u << (plane + 4); }  // planes 2..5 -> bits 6..9
constexpr uint32_t kFrustumBits = 0x3F;  // all three corners sharing one: trivially rejected
constexpr uint32_t kGuardBits = guardBit(kPlaneLeft) | guardBit(kPlaneRight) | guardBit(kPlaneBottom) |
                                guardBit(kPlaneTop);
// A corner with any of these sends its triangle to Sutherland-Hodgman; without them, the triangle
// is accepted whole (inside, or crossing a viewport side within the guard band).
constexpr uint32_t kClipBits = outBit(kPlaneNear) | outBit(kPlaneFar) | kGuardBits;

// What the pass needs of the camera and the clip space: the view matrix's top three rows, the
// clip-space scales, the near/far depths, the guard band's extents in NDC units, and the
// viewport's half size in pixels.
struct VertexPassParams {
    double m[3][4];
    double sx, sy, nearZ, farZ, gx, gy, halfW, halfH;
    bool orthographic;
};

// A batch's vertices: view-space position, outcode, projected fixed point (meaningful only where
// the outcode has no near, far or guard-band bit: elsewhere whatever the same expressions give),
// x and y interleaved as a screen triangle's corners are (sxy[2 i], sxy[2 i + 1]).
struct BatchVertices {
    std::vector<double> x, y, z;
    std::vector<uint32_t> code;
    std::vector<int32_t> sxy;
    void resize(size_t n) { x.resize(n), y.resize(n), z.resize(n), code.resize(n), sxy.resize(2 * n); }
};

// toFixed (raster.h) as selects instead of branches: the same value for every input (NaN and
// -inf to INT32_MIN, +inf and anything at or beyond 2^31 to the ends).
// (static, as the pass below: clip_avx2.cpp compiles this header with -mavx2, and an inline
// function shared by both files could be linked in its AVX2 build for the baseline's callers.)
[[gnu::always_inline]] static inline int32_t toFixedSelect(double pixelCoordinate) {
    const double x = pixelCoordinate * kSubpixelOne;
    constexpr double kRound = 0x1.8p52;
    const double r = (x + kRound) - kRound;
    double s = ((x < 0x1p51) & (x > -0x1p51)) ? r : x;
    s = s > -2147483648.0 ? s : -2147483648.0;
    s = s > 2147483647.0 ? 2147483647.0 : s;
    return int32_t(s);
}

// The pass over vertices [begin, end) of a batch (pos: the batch's first). Per vertex: transformPoint (math.h) with the
// same products and sums, clipVertexOf and ClipSpace::outcode and ClipSpace::project (clip.cpp).
template <bool kOrtho>
[[gnu::always_inline]] static inline void transformVerticesBody(const VertexPassParams &p, const Vec3 *pos, size_t begin,
                                                         size_t end, BatchVertices &bv) {
    const double m00 = p.m[0][0], m01 = p.m[0][1], m02 = p.m[0][2], m03 = p.m[0][3];
    const double m10 = p.m[1][0], m11 = p.m[1][1], m12 = p.m[1][2], m13 = p.m[1][3];
    const double m20 = p.m[2][0], m21 = p.m[2][1], m22 = p.m[2][2], m23 = p.m[2][3];
    const double sx = p.sx, sy = p.sy, nearZ = p.nearZ, farZ = p.farZ, gx = p.gx, gy = p.gy;
    const double halfW = p.halfW, halfH = p.halfH;
    double *__restrict X = bv.x.data(), *__restrict Y = bv.y.data(), *__restrict Z = bv.z.data();
    uint32_t *__restrict C = bv.code.data();
    int32_t *__restrict SXY = bv.sxy.data();
    for (size_t i = begin; i < end; ++i) {
        const double px = pos[i].x, py = pos[i].y, pz = pos[i].z;
        const double vx = m00 * px + m01 * py + m02 * pz + m03;
        const double vy = m10 * px + m11 * py + m12 * pz + m13;
        const double vz = m20 * px + m21 * py + m22 * pz + m23;
        X[i] = vx, Y[i] = vy, Z[i] = vz;
        const double d = -vz, cx = sx * vx, cy = sy * vy, w = kOrtho ? 1.0 : d;
        uint32_t c = uint32_t(d < nearZ) << kPlaneNear | uint32_t(d > farZ) << kPlaneFar |
                     uint32_t(cx < -w) << kPlaneLeft | uint32_t(cx > w) << kPlaneRight |
                     uint32_t(cy < -w) << kPlaneBottom | uint32_t(cy > w) << kPlaneTop;
        c |= uint32_t(cx < -gx * w) << (kPlaneLeft + 4) | uint32_t(cx > gx * w) << (kPlaneRight + 4) |
             uint32_t(cy < -gy * w) << (kPlaneBottom + 4) | uint32_t(cy > gy * w) << (kPlaneTop + 4);
        C[i] = c;
        const double inv = 1.0 / w;
        SXY[2 * i] = toFixedSelect((cx * inv + 1.0) * halfW);
        SXY[2 * i + 1] = toFixedSelect((1.0 - cy * inv) * halfH);
    }
}

// The same pass four vertices at a time with AVX2 intrinsics (clip_avx2.cpp, built with -mavx2),
// the same bits; call only when the CPU has AVX2. (GCC 12 does not vectorize the loop above: the
// three-double stride of the positions.)
void transformVerticesAvx2(const VertexPassParams &p, const Vec3 *pos, uint32_t n, BatchVertices &bv);

// Counts of the triangles the accept path took (ClipStats' fields of the same names).
struct AcceptCounts {
    uint64_t inside = 0, guardBandAccepted = 0;
};

// The clip stage's common case four triangles at a time with AVX2 (clip_avx2.cpp): from the
// batch's k-th triangle on, while all four triangles of a group are accepted whole (not trivially
// rejected, no corner outside near, far or the guard band, a valid depth plane), appends each
// one's plane, corners, source and plane index to `out` as clipOne does (the same operations in
// the same order, so the same bits) and counts it. Returns how many triangles it took: a multiple
// of 4, stopping before the first group that is not all accepted, or with fewer than 4 left (the
// caller runs those through clipOne, in order). Call only when the CPU has AVX2.
uint32_t acceptGroupsAvx2(const DepthPlaneMaker &p, const BatchVertices &bv, const uint32_t *indices,
                          const ClipBatch &batch, uint32_t k, ScreenTriangles &out, AcceptCounts &counts);

}  // namespace va::clip_detail
