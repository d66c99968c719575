#include "render/clip.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>

#include "render/clip_vertices.h"
#include "render/large_pages.h"

namespace va {

const char *const kClipPlaneNames[kClipPlaneCount] = {"near", "far", "left", "right", "bottom", "top"};

namespace {

// ClipVertex (clip.h): clip-space x, y, w and the view depth d. All four are linear
// (perspective: w = d) or affine (orthographic: w = 1) functions of the view-space position, so
// linear interpolation between two vertices is exactly interpolation of the view-space segment,
// and every clip plane below is a linear function of (x, y, w, d).

// Outcode bits (clip_vertices.h): the view frustum's planes, then the guard band's side planes.
using clip_detail::guardBit, clip_detail::kClipBits, clip_detail::kFrustumBits;
constexpr uint32_t kOutNear = clip_detail::outBit(kPlaneNear), kOutFar = clip_detail::outBit(kPlaneFar),
                   kOutLeft = clip_detail::outBit(kPlaneLeft), kOutRight = clip_detail::outBit(kPlaneRight),
                   kOutBottom = clip_detail::outBit(kPlaneBottom), kOutTop = clip_detail::outBit(kPlaneTop);

struct ClipSpace {
    double nearZ, farZ, gx, gy;  // gx, gy: guard-band extents in NDC units (>= 1)
    double halfW, halfH;

    // Signed distance-like value of v to a plane; >= 0 is inside. For the side planes this is the
    // guard-band plane: the clipper only ever cuts at the guard band, never at the viewport.
    double dist(const ClipVertex &v, int plane) const {
        switch (plane) {
        case kPlaneNear: return v.d - nearZ;
        case kPlaneFar: return farZ - v.d;
        case kPlaneLeft: return v.x + gx * v.w;
        case kPlaneRight: return gx * v.w - v.x;
        case kPlaneBottom: return v.y + gy * v.w;
        default: return gy * v.w - v.y;
        }
    }

    uint32_t outcode(const ClipVertex &v) const {
        uint32_t c = 0;
        if (v.d < nearZ) c |= kOutNear;
        if (v.d > farZ) c |= kOutFar;
        if (v.x < -v.w) c |= kOutLeft;
        if (v.x > v.w) c |= kOutRight;
        if (v.y < -v.w) c |= kOutBottom;
        if (v.y > v.w) c |= kOutTop;
        if (v.x < -gx * v.w) c |= guardBit(kPlaneLeft);
        if (v.x > gx * v.w) c |= guardBit(kPlaneRight);
        if (v.y < -gy * v.w) c |= guardBit(kPlaneBottom);
        if (v.y > gy * v.w) c |= guardBit(kPlaneTop);
        return c;
    }

    // Perspective divide and viewport transform to fixed point. Only called for vertices inside
    // near (w >= n > 0) and inside the guard band, so the result is bounded by the guard band.
    void project(const ClipVertex &v, int32_t *xy) const {
        const double inv = 1.0 / v.w;
        xy[0] = toFixed((v.x * inv + 1.0) * halfW);
        xy[1] = toFixed((1.0 - v.y * inv) * halfH);
    }
};

// Sutherland-Hodgman against one plane. The intersection is always computed from the inside
// vertex towards the outside one, so the two triangles sharing a clipped edge get bit-identical
// new vertices, whichever direction each walks the edge: no cracks along clip boundaries.
int clipPolygon(const ClipSpace &cs, int plane, const ClipVertex *in, int n, ClipVertex *out) {
    int m = 0;
    for (int i = 0; i < n; ++i) {
        const ClipVertex &a = in[i];
        const ClipVertex &b = in[(i + 1) % n];
        const double da = cs.dist(a, plane), db = cs.dist(b, plane);
        const bool ina = da >= 0, inb = db >= 0;
        if (ina) out[m++] = a;
        if (ina != inb) {
            const ClipVertex &p = ina ? a : b;  // inside
            const ClipVertex &q = ina ? b : a;  // outside
            const double dp = ina ? da : db, dq = ina ? db : da;
            const double t = dp / (dp - dq);  // in [0, 1]: dp >= 0 > dq
            out[m++] = {p.x + t * (q.x - p.x), p.y + t * (q.y - p.y), p.w + t * (q.w - p.w),
                        p.d + t * (q.d - p.d)};
        }
    }
    return m;
}

// Appends a valid plane field by field. (push_back(plane) copied the struct through the stack in
// two 16-byte halves, the second spanning the 8-byte store of c and the 1-byte store of valid: a
// failed store-to-load forward on every accepted triangle, about a quarter of the stage's time.)
[[gnu::always_inline]] inline void appendPlane(RawVector<DepthPlane> &planes, const DepthPlane &p) {
    DepthPlane &d = planes.emplace_back();  // unwritten (raw_vector.h): every byte is stored below
    d.a = p.a;
    d.b = p.b;
    d.c = p.c;
    // valid = true and the padding after it zero, as one 8-byte word (clip_avx2.cpp's plane rows
    // write the same word).
    static_assert(sizeof(DepthPlane) == 32 && offsetof(DepthPlane, valid) == 24, "DepthPlane's layout");
    const uint64_t validWord = 1;
    std::memcpy(reinterpret_cast<unsigned char *>(&d) + 24, &validWord, 8);
}

// One triangle through the stage: trivial reject, depth plane, accept or Sutherland-Hodgman, fan
// triangulation, projection. v*: its corners in view space; c*: in the clipper's space; code*:
// their outcodes; s*: their projected fixed-point positions (read only when the triangle is
// accepted whole, i.e. every corner is inside near, far and the guard band). Inlined into both
// entry points, so clipTriangles' loop is what it was.
[[gnu::always_inline]] inline void clipOne(const DepthPlaneMaker &planeOf, const ClipSpace &cs, uint32_t t, const Vec3 &v0,
                                           const Vec3 &v1, const Vec3 &v2, const ClipVertex *cv0,
                                           const ClipVertex *cv1, const ClipVertex *cv2, uint32_t c0, uint32_t c1,
                                           uint32_t c2, const int32_t *s0, const int32_t *s1, const int32_t *s2,
                                           ClipStats &st, ScreenTriangles &out, std::vector<ClipPolygon> *polygons) {
    // Trivial reject: all three vertices outside one plane of the view frustum.
    if ((c0 & c1 & c2 & kFrustumBits) != 0) {
        ++st.trivialRejected;
        return;
    }
    const DepthPlane plane = planeOf(v0, v1, v2);
    if (!plane.valid) {
        ++st.edgeOn;
        return;
    }
    const uint32_t any = c0 | c1 | c2;
    if ((any & kClipBits) == 0) {
        // Inside, or crossing a viewport side while staying in the guard band: the
        // rasterizer's bounding box and edge functions do the 2D clipping.
        if (any == 0)
            ++st.inside;
        else
            ++st.guardBandAccepted;
        const uint32_t pi = uint32_t(out.planes.size());
        appendPlane(out.planes, plane);
        out.xy.insert(out.xy.end(), {s0[0], s0[1], s1[0], s1[1], s2[0], s2[1]});
        out.source.push_back(t);
        out.plane.push_back(pi);
        ++st.trianglesOut;
        if (polygons) polygons->push_back({t, {*cv0, *cv1, *cv2}});
        return;
    }

    // Sutherland-Hodgman in homogeneous clip space, before the divide. Near is clipped
    // first (whenever any vertex is behind it), so nothing behind the eye is projected.
    ++st.clipped;
    ClipVertex bufA[16], bufB[16];
    ClipVertex *src = bufA, *dst = bufB;
    src[0] = *cv0;
    src[1] = *cv1;
    src[2] = *cv2;
    int n = 3;
    for (int p = 0; p < kClipPlaneCount && n >= 3; ++p) {
        const uint32_t bit = p < 2 ? (1u << p) : guardBit(p);
        if (!(any & bit)) continue;
        ++st.perPlane[p];
        n = clipPolygon(cs, p, src, n, dst);  // each plane adds at most one vertex: n <= 9
        std::swap(src, dst);
    }
    if (n < 3) {
        ++st.clippedAway;
        return;
    }
    ++st.polygonVertices[n < 9 ? n : 9];
    const uint32_t pi = uint32_t(out.planes.size());
    appendPlane(out.planes, plane);
    int32_t p0[2], pa[2], pb[2];
    cs.project(src[0], p0);
    cs.project(src[1], pb);
    for (int v = 2; v < n; ++v) {  // fan from the first vertex
        pa[0] = pb[0];
        pa[1] = pb[1];
        cs.project(src[v], pb);
        out.xy.insert(out.xy.end(), {p0[0], p0[1], pa[0], pa[1], pb[0], pb[1]});
        out.source.push_back(t);
        out.plane.push_back(pi);
        ++st.trianglesOut;
    }
    if (polygons) polygons->push_back({t, std::vector<ClipVertex>(src, src + n)});
}

ClipSpace clipSpaceOf(const Camera &cam, const ClipSettings &settings) {
    ClipSpace cs;
    cs.nearZ = cam.nearZ;
    cs.farZ = cam.farZ;
    cs.halfW = 0.5 * cam.width;
    cs.halfH = 0.5 * cam.height;
    cs.gx = 1 + settings.guardBandPixels / cs.halfW;
    cs.gy = 1 + settings.guardBandPixels / cs.halfH;
    return cs;
}

// A view-space point in the clipper's space (camera.h).
ClipVertex clipVertexOf(const Camera &cam, const Vec3 &v) {
    const double d = -v.z;
    return {cam.sx * v.x, cam.sy * v.y, cam.orthographic ? 1.0 : d, d};
}

}  // namespace

ClipResult clipTriangles(const Camera &cam, const MeshView &mesh, const std::vector<ClipBatch> &batches,
                         const ClipSettings &settings) {
    ClipResult r;
    ClipStats &st = r.stats;
    ScreenTriangles &out = r.out;
    out = takeRecycledScreenTriangles();  // a finished view's storage, when one gave it back

    const ClipSpace cs = clipSpaceOf(cam, settings);
    const DepthPlaneMaker planeOf(cam);

    size_t total = 0;
    for (const ClipBatch &b : batches) total += b.count;
    // The output's room on huge pages (render/large_pages.h): 60 bytes a triangle, faulted in as
    // triangles arrive; in 4 KiB pages the faults of a 1M-triangle view cost a third of the clip.
    reserveOnLargePages(out.xy, total * 6);
    reserveOnLargePages(out.source, total);
    reserveOnLargePages(out.plane, total);
    reserveOnLargePages(out.planes, total);

    // Per batch, every vertex of its range through the vertex pass (clip_vertices.h: view-space
    // position, outcode, projected fixed point; AVX2 where the CPU has it), then its triangles. A
    // batch's triangles are scattered over the index array: each one's indices are prefetched 16
    // ahead. (clipViewTriangles keeps the per-vertex ClipSpace::outcode and project: the vertex pass
    // does their operations in their order; AssignmentKit.AnswersEqualThePipelinesNumbers checks.)
    clip_detail::VertexPassParams vp;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) vp.m[r][c] = cam.viewFromWorld.m[r][c];
    vp.sx = cam.sx, vp.sy = cam.sy, vp.nearZ = cs.nearZ, vp.farZ = cs.farZ, vp.gx = cs.gx, vp.gy = cs.gy;
    vp.halfW = cs.halfW, vp.halfH = cs.halfH, vp.orthographic = cam.orthographic;
    const bool avx2 = __builtin_cpu_supports("avx2");
    clip_detail::BatchVertices bv;
    clip_detail::AcceptCounts accepted;

    for (const ClipBatch &b : batches) {
        const uint32_t nv = b.vertexEnd - b.vertexBegin;
        bv.resize(nv);
        const Vec3 *pos = mesh.positions + b.vertexBegin;
        if (avx2) clip_detail::transformVerticesAvx2(vp, pos, nv, bv);
        else if (vp.orthographic) clip_detail::transformVerticesBody<true>(vp, pos, 0, nv, bv);
        else clip_detail::transformVerticesBody<false>(vp, pos, 0, nv, bv);

        st.trianglesIn += b.count;
        const uint32_t *idx = mesh.indices;
        uint32_t k = 0;
        while (k < b.count) {
            // The common case four at a time (clip_vertices.h); the group it stops at, or the last
            // few, through clipOne.
            if (avx2) {
                const uint32_t taken = clip_detail::acceptGroupsAvx2(planeOf, bv, idx, b, k, out, accepted);
                k += taken;
                st.trianglesOut += taken;
            }
            for (const uint32_t end = std::min(b.count, k + 4); k < end; ++k) {
                const uint32_t t = b.triangles[k];
                if (k + 16 < b.count) __builtin_prefetch(idx + 3 * size_t(b.triangles[k + 16]));
                const uint32_t i0 = idx[3 * size_t(t)] - b.vertexBegin;
                const uint32_t i1 = idx[3 * size_t(t) + 1] - b.vertexBegin;
                const uint32_t i2 = idx[3 * size_t(t) + 2] - b.vertexBegin;
                const Vec3 v0{bv.x[i0], bv.y[i0], bv.z[i0]}, v1{bv.x[i1], bv.y[i1], bv.z[i1]};
                const Vec3 v2{bv.x[i2], bv.y[i2], bv.z[i2]};
                // The clip-space corners are read only when the triangle is clipped (clipOne inlined).
                const ClipVertex c0 = clipVertexOf(cam, v0), c1 = clipVertexOf(cam, v1);
                const ClipVertex c2 = clipVertexOf(cam, v2);
                const int32_t *s0 = &bv.sxy[2 * size_t(i0)], *s1 = &bv.sxy[2 * size_t(i1)];
                const int32_t *s2 = &bv.sxy[2 * size_t(i2)];
                clipOne(planeOf, cs, t, v0, v1, v2, &c0, &c1, &c2, bv.code[i0], bv.code[i1], bv.code[i2], s0, s1,
                        s2, st, out, nullptr);
            }
        }
    }
    st.inside += accepted.inside;
    st.guardBandAccepted += accepted.guardBandAccepted;
    return r;
}

ClipResult clipViewTriangles(const Camera &cam, const std::vector<Vec3> &view, const std::vector<uint32_t> &source,
                             const ClipSettings &settings, std::vector<ClipPolygon> *polygons) {
    ClipResult r;
    const ClipSpace cs = clipSpaceOf(cam, settings);
    const DepthPlaneMaker planeOf(cam);
    const size_t n = std::min(view.size() / 3, source.size());
    r.stats.trianglesIn = n;
    for (size_t t = 0; t < n; ++t) {
        const Vec3 *v = &view[3 * t];
        ClipVertex cv[3];
        uint32_t code[3];
        int32_t screen[6] = {};
        for (int k = 0; k < 3; ++k) {
            cv[k] = clipVertexOf(cam, v[k]);
            code[k] = cs.outcode(cv[k]);
            if ((code[k] & kClipBits) == 0) cs.project(cv[k], &screen[2 * k]);
        }
        clipOne(planeOf, cs, source[t], v[0], v[1], v[2], &cv[0], &cv[1], &cv[2], code[0], code[1], code[2], &screen[0],
                &screen[2], &screen[4], r.stats, r.out, polygons);
    }
    return r;
}

}  // namespace va
