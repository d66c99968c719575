#include "render/raycast.h"

#include "render/large_pages.h"
#include "render/recycle.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <memory>
#include <mutex>

#include <embree3/rtcore.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#include <immintrin.h>
#endif
#include <tbb/parallel_for.h>

namespace va {

namespace {

// One Embree device for the process, with its error callback registered once.
void embreeError(void *, RTCError code, const char *str) {
    std::fprintf(stderr, "visaudit: embree error %d: %s\n", int(code), str ? str : "");
}

RTCDevice sharedDevice() {
    static RTCDevice device = [] {
        RTCDevice d = rtcNewDevice(nullptr);
        if (d) rtcSetDeviceErrorFunction(d, embreeError, nullptr);
        return d;
    }();
    return device;
}

// Ray setup shared by castPrimary, castPrimaryRaw and primaryRay: origin and direction in the
// scene's float frame (relative to the origin) for pixel (x, y). A ray is the sum of a column term
// (pixel x) and a row term (pixel y), both in double, so a packet can take them from per-view
// tables (PacketRays) and still produce bit-identical rays: the same double operations in the same
// order, then one rounding to float.
struct RayGen {
    Vec3 eyeRel;        // eye - origin
    Vec3 right, up, fw; // camera basis
    double ax, bx, ay, by;  // x_n/sx = ax px + bx, y_n/sy = ay py + by (camera.h)
    bool ortho;

    RayGen(const Camera &cam, Vec3 origin) {
        eyeRel = cam.eye - origin;
        right = cam.right;
        up = cam.up;
        fw = cam.forward;
        ax = 2.0 / (cam.width * cam.sx);
        bx = -1.0 / cam.sx;
        ay = -2.0 / (cam.height * cam.sy);
        by = 1.0 / cam.sy;
        ortho = cam.orthographic;
    }
    // Perspective: o = eye, dir = right*u + up*v + forward (view z = -1: t is the view depth).
    // Orthographic: o = eye + right*u + up*v, dir = forward.
    Vec3 column(int x) const {
        const double u = ax * (x + 0.5) + bx;
        return ortho ? eyeRel + right * u : right * u;
    }
    Vec3 row(int y) const {
        const double v = ay * (y + 0.5) + by;
        return up * v;
    }
    void combine(const Vec3 &col, const Vec3 &row, float o[3], float d[3]) const {
        if (ortho) {
            const Vec3 p = col + row;
            o[0] = float(p.x), o[1] = float(p.y), o[2] = float(p.z);
            d[0] = float(fw.x), d[1] = float(fw.y), d[2] = float(fw.z);
        } else {
            const Vec3 r = col + row + fw;
            o[0] = float(eyeRel.x), o[1] = float(eyeRel.y), o[2] = float(eyeRel.z);
            d[0] = float(r.x), d[1] = float(r.y), d[2] = float(r.z);
        }
    }
    void make(int x, int y, float o[3], float d[3]) const { combine(column(x), row(y), o, d); }
};

}  // namespace

struct RayScene::Impl {
    RTCScene scene = nullptr;
    std::vector<uint32_t> primToSource;  // Embree primID -> global triangle id
    std::vector<uint32_t> sourceToPrim;  // global triangle id -> Embree primID (kNoHit: not in the scene)
    const float *vb = nullptr;           // Embree's vertex buffer (owned by the scene's geometry)
    const unsigned *ib = nullptr;        // Embree's index buffer
    Vec3 origin;
    ~Impl() {
        if (scene) rtcReleaseScene(scene);
    }
};

RayScene::RayScene() : impl_(new Impl) {}
RayScene::~RayScene() = default;

bool RayScene::build(const MeshView &mesh, size_t vertexCount, const std::vector<uint32_t> &triangles, Vec3 origin,
                     std::string *err) {
    RTCDevice dev = sharedDevice();
    if (!dev) {
        *err = "could not create an Embree device (rtcNewDevice failed)";
        return false;
    }
    Impl &m = *impl_;
    if (m.scene) rtcReleaseScene(m.scene);
    m.origin = origin;
    m.scene = rtcNewScene(dev);
    // ROBUST: Embree's watertight intersection, so no ray slips between two triangles sharing an edge.
    // CONTEXT_FILTER_FUNCTION: lets castPrimary's back-face rejection install a per-call filter; a
    // context without a filter pays one pointer test per candidate hit.
    if (!rtcGetDeviceProperty(dev, RTC_DEVICE_PROPERTY_FILTER_FUNCTION_SUPPORTED)) {
        *err = "this Embree library was built without filter functions (EMBREE_FILTER_FUNCTION=OFF); "
               "visaudit needs them for back-face rejection";
        return false;
    }
    rtcSetSceneFlags(m.scene, RTCSceneFlags(RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION));
    rtcSetSceneBuildQuality(m.scene, RTC_BUILD_QUALITY_HIGH);
    m.primToSource = triangles;
    m.sourceToPrim.clear();
    m.vb = nullptr;
    m.ib = nullptr;
    for (size_t k = 0; k < triangles.size(); ++k) {
        if (triangles[k] >= m.sourceToPrim.size()) m.sourceToPrim.resize(size_t(triangles[k]) + 1, kNoHit);
        m.sourceToPrim[triangles[k]] = uint32_t(k);
    }
    if (!triangles.empty()) {
        RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
        float *vb = static_cast<float *>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                                 3 * sizeof(float), vertexCount));
        unsigned *ib = static_cast<unsigned *>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                       3 * sizeof(unsigned), triangles.size()));
        if (!vb || !ib) {
            rtcReleaseGeometry(g);
            *err = "Embree could not allocate geometry buffers";
            return false;
        }
        for (size_t i = 0; i < vertexCount; ++i) {
            const Vec3 p = mesh.positions[i] - origin;
            vb[3 * i] = float(p.x), vb[3 * i + 1] = float(p.y), vb[3 * i + 2] = float(p.z);
        }
        for (size_t k = 0; k < triangles.size(); ++k)
            for (int j = 0; j < 3; ++j) ib[3 * k + j] = mesh.indices[3 * size_t(triangles[k]) + j];
        m.vb = vb;
        m.ib = ib;
        rtcCommitGeometry(g);
        rtcAttachGeometry(m.scene, g);
        rtcReleaseGeometry(g);
    }
    rtcCommitScene(m.scene);
    if (rtcGetDeviceError(dev) != RTC_ERROR_NONE) {
        *err = "Embree failed to build the scene";
        return false;
    }
    return true;
}

namespace {
// dst[0 .. n) = src[0 .. n) for 4-byte elements, with non-temporal stores where the target is
// 16-byte aligned: a frame's output (16 MB and more) would otherwise pass through the caches and
// evict the BVH nodes the next packets need.
template <class T>
void streamCopy(const T *src, size_t n, T *dst) {
    static_assert(sizeof(T) == 4);
    size_t i = 0;
#if defined(__SSE2__)
    for (; i < n && (reinterpret_cast<uintptr_t>(dst + i) & 15); ++i) dst[i] = src[i];
    for (; i + 4 <= n; i += 4)
        _mm_stream_si128(reinterpret_cast<__m128i *>(dst + i), _mm_loadu_si128(reinterpret_cast<const __m128i *>(src + i)));
    _mm_sfence();
#endif
    for (; i < n; ++i) dst[i] = src[i];
}

// Primary rays are traced in 4x4 packets (rtcIntersect16), 16 packets to a 16x16 tile, tiles left to
// right in bands of 16 rows. A band is one contiguous range of every per-pixel buffer (16 whole
// rows), so bands run in parallel without two threads writing the same cache line (except the one
// line at each band's ends when a buffer does not start on a line boundary); each pixel's result
// depends on its ray alone, so the images are identical for any thread count. A 16x16 tile's rays
// stay within a small cone, so consecutive packets reuse the same BVH nodes and triangles in cache.
constexpr int kPacket = 4;  // packet side: 4x4 rays
constexpr int kTile = 16;   // tile side and band height, in pixels

// Per-view ray tables: RayGen's column and row terms for every pixel column and row, and one
// packet buffer per band with the lane constants set once; a packet then costs 3 + 3 double adds and
// 3 conversions per ray.
struct PacketRays {
    const RayGen &gen;
    const Camera &cam;
    std::vector<Vec3> cols, rows;
    // The same terms by component (perspective), for a whole packet's directions in loops the
    // compiler vectorizes: direction = (column + row) + forward per component, as RayGen::combine.
    std::vector<double> colX, colY, colZ, rowX, rowY, rowZ;

    PacketRays(const RayGen &g, const Camera &c) : gen(g), cam(c), cols(size_t(c.width)), rows(size_t(c.height)) {
        for (int x = 0; x < c.width; ++x) cols[size_t(x)] = g.column(x);
        for (int y = 0; y < c.height; ++y) rows[size_t(y)] = g.row(y);
        for (const Vec3 &v : cols) colX.push_back(v.x), colY.push_back(v.y), colZ.push_back(v.z);
        for (const Vec3 &v : rows) rowX.push_back(v.x), rowY.push_back(v.y), rowZ.push_back(v.z);
    }
    // The fields Embree never writes, and the perspective origin (the eye, for every ray).
    void init(RTCRayHit16 &rh) const {
        for (int i = 0; i < 16; ++i) {
            rh.ray.org_x[i] = float(gen.eyeRel.x), rh.ray.org_y[i] = float(gen.eyeRel.y);
            rh.ray.org_z[i] = float(gen.eyeRel.z);
            rh.ray.tnear[i] = float(cam.nearZ);
            rh.ray.time[i] = 0;
            rh.ray.mask[i] = 0xFFFFFFFFu;
            rh.ray.id[i] = unsigned(i);  // the lane, for primaryFilter's tie state
            rh.ray.flags[i] = 0;
            rh.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
            rh.hit.primID[i] = 0;
        }
    }
    // The rays of the packet whose top-left pixel is (px, py); lanes outside the image are invalid
    // (lane i is pixel (px + i % 4, py + i / 4)). True when every lane is valid.
    bool fill(int px, int py, RTCRayHit16 &rh, int valid[16]) const {
        const bool whole = px + kPacket <= cam.width && py + kPacket <= cam.height;
        if (!gen.ortho && whole) {
            // A whole perspective packet: the origin is init()'s eye; the same operations in the
            // same order as combine(), four rays of a packet row at a time.
            const float far = float(cam.farZ);
            for (int j = 0; j < kPacket; ++j) {
                const size_t y = size_t(py + j);
                const double rx = rowX[y], ry = rowY[y], rz = rowZ[y];
                const double *cx = colX.data() + px, *cy = colY.data() + px, *cz = colZ.data() + px;
                for (int i = 0; i < kPacket; ++i) {
                    const int l = kPacket * j + i;
                    rh.ray.dir_x[l] = float((cx[i] + rx) + gen.fw.x);
                    rh.ray.dir_y[l] = float((cy[i] + ry) + gen.fw.y);
                    rh.ray.dir_z[l] = float((cz[i] + rz) + gen.fw.z);
                    rh.ray.tfar[l] = far;
                    rh.hit.geomID[l] = RTC_INVALID_GEOMETRY_ID;
                    valid[l] = -1;
                }
            }
            return true;
        }
        for (int i = 0; i < 16; ++i) {
            const int x = px + (i & 3), y = py + (i >> 2);
            valid[i] = (x < cam.width && y < cam.height) ? -1 : 0;
            float o[3], d[3];
            gen.combine(cols[size_t(valid[i] ? x : 0)], rows[size_t(valid[i] ? y : 0)], o, d);
            if (gen.ortho) rh.ray.org_x[i] = o[0], rh.ray.org_y[i] = o[1], rh.ray.org_z[i] = o[2];
            rh.ray.dir_x[i] = d[0], rh.ray.dir_y[i] = d[1], rh.ray.dir_z[i] = d[2];
            rh.ray.tfar[i] = float(cam.farZ);
            rh.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
        }
        return whole;
    }
    int bands() const { return (cam.height + kTile - 1) / kTile; }
    // Calls fn(px, py) for the packets of band b in tracing order: tiles left to right, the 16
    // packets of a tile row by row; onTile(x0, y0, y1) before each tile whose pixels are columns
    // [x0, x0 + kTile) of rows [y0, y1).
    template <class TileFn, class Fn>
    void forEachPacket(int b, TileFn onTile, Fn fn) const {
        const int y0 = b * kTile, y1 = std::min(cam.height, y0 + kTile);
        for (int tx = 0; tx < cam.width; tx += kTile) {
            onTile(tx, y0, y1);
            for (int py = y0; py < y1; py += kPacket)
                for (int px = tx; px < std::min(cam.width, tx + kTile); px += kPacket) fn(px, py);
        }
    }
};
}  // namespace

namespace {
// castPrimary's options as an Embree context filter: an intersect context extended with what the
// filter needs (Embree passes the context it was given to the filter, so the cast is safe).
//  - Back-face rejection: a per-primitive table.
//  - Ties to the lowest id: Embree accepts a candidate hit when t <= the current tfar, so of two hits
//    at a bit-identical t (a ray exactly through a shared edge, coplanar overlap) the one found last
//    wins, and the order depends on the traversal (packet and single-ray kernels differ). Before the
//    filter runs Embree sets the ray's tfar to the candidate's t; the filter keeps, per packet lane
//    (the ray id), the t and source id it last accepted, and rejects a candidate at the same t with a
//    higher source id. Candidates farther than the accepted hit never reach the filter.
struct FilterContext {
    RTCIntersectContext ctx;
    const uint8_t *reject = nullptr;             // per Embree primitive: 1 = hits on it are rejected
    const uint32_t *primToSource = nullptr;      // non-null: break ties to the lowest source id
    float bestT[16];
    uint32_t bestSource[16];
    void resetLanes() {
        for (int i = 0; i < 16; ++i) bestT[i] = INFINITY, bestSource[i] = 0xFFFFFFFFu;
    }
};
void primaryFilter(const RTCFilterFunctionNArguments *args) {
    FilterContext &fc = *reinterpret_cast<FilterContext *>(args->context);
    int *valid = args->valid;
    auto lane = [&](unsigned i) {
        const unsigned prim = RTCHitN_primID(args->hit, args->N, i);
        if (fc.reject && fc.reject[prim]) {
            valid[i] = 0;
            return;
        }
        if (fc.primToSource) {
            const unsigned lane = RTCRayN_id(args->ray, args->N, i) & 15u;
            const float t = RTCRayN_tfar(args->ray, args->N, i);
            const uint32_t src = fc.primToSource[prim];
            if (t == fc.bestT[lane] && src > fc.bestSource[lane]) {
                valid[i] = 0;
                return;
            }
            fc.bestT[lane] = t;
            fc.bestSource[lane] = src;
        }
    };
    if (args->N == 16) {
        // A packet's call: a few of its 16 lanes are valid (3.4 on average on the benchmark scene),
        // so the valid ones are found as a bit mask and visited in ascending order, as the loop
        // over every lane below visits them, without a branch per lane.
        const __m128i on = _mm_set1_epi32(-1);
        const __m128i *v = reinterpret_cast<const __m128i *>(valid);
        const __m128i lo = _mm_packs_epi32(_mm_cmpeq_epi32(_mm_loadu_si128(v), on), _mm_cmpeq_epi32(_mm_loadu_si128(v + 1), on));
        const __m128i hi = _mm_packs_epi32(_mm_cmpeq_epi32(_mm_loadu_si128(v + 2), on), _mm_cmpeq_epi32(_mm_loadu_si128(v + 3), on));
        for (unsigned mask = unsigned(_mm_movemask_epi8(_mm_packs_epi16(lo, hi))); mask; mask &= mask - 1)
            lane(unsigned(std::countr_zero(mask)));
        return;
    }
    for (unsigned i = 0; i < args->N; ++i)
        if (valid[i] == -1) lane(i);
}

// A packet whose 16 lanes are all valid, stored as castBand's lane loop stores it, a packet row of
// four pixels at a time: id = 1 + source of the hit primitive (0 on a miss), depth = tfar (+inf on a
// miss), and with kBary Embree's u, v (0 on a miss). `at` is the packet's top-left pixel in the
// band's buffers of row length `w`. Returns the packet's hits. Against the lane loop (a branch and
// a store per lane) castPrimary gained about 1.5% of a coherent cast (bench_table --sections raycast).
template <bool kBary>
__attribute__((target("avx2"))) uint64_t storeWholePacketAvx2(const RTCRayHit16 &rh, const uint32_t *toSource, size_t at,
                                                               size_t w, uint32_t *id, float *depth, float *u, float *v) {
    const __m128i invalid = _mm_set1_epi32(int(RTC_INVALID_GEOMETRY_ID));
    const __m128i one = _mm_set1_epi32(1), ones = _mm_set1_epi32(-1);
    const __m128 inf = _mm_set1_ps(INFINITY);
    int misses = 0;
    for (int j = 0; j < kPacket; ++j) {
        const size_t p = at + size_t(j) * w;
        const __m128i miss = _mm_cmpeq_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i *>(rh.hit.geomID + 4 * j)), invalid);
        const __m128 missF = _mm_castsi128_ps(miss);
        const __m128i prim = _mm_loadu_si128(reinterpret_cast<const __m128i *>(rh.hit.primID + 4 * j));
        const __m128i src = _mm_mask_i32gather_epi32(_mm_setzero_si128(), reinterpret_cast<const int *>(toSource), prim,
                                                     _mm_xor_si128(miss, ones), 4);
        _mm_storeu_si128(reinterpret_cast<__m128i *>(id + p), _mm_andnot_si128(miss, _mm_add_epi32(src, one)));
        _mm_storeu_ps(depth + p, _mm_blendv_ps(_mm_loadu_ps(rh.ray.tfar + 4 * j), inf, missF));
        if constexpr (kBary) {
            _mm_storeu_ps(u + p, _mm_andnot_ps(missF, _mm_loadu_ps(rh.hit.u + 4 * j)));
            _mm_storeu_ps(v + p, _mm_andnot_ps(missF, _mm_loadu_ps(rh.hit.v + 4 * j)));
        }
        misses += std::popcount(unsigned(_mm_movemask_ps(missF)));
    }
    return uint64_t(16 - misses);
}

// One band of castPrimary (kBary: also write barycentrics; kTies: the context's filter tracks ties
// per lane, reset per packet). `fc` is this band's own copy of the context (tie state is per packet).
template <bool kBary, bool kTies>
void castBand(RTCScene scene, FilterContext &fc, const PacketRays &rays, int band,
              const std::vector<uint32_t> &primToSource, RaycastImage &img, RaycastStats &st) {
    alignas(64) RTCRayHit16 rh;
    alignas(64) int valid[16];
    rays.init(rh);
    const size_t w = size_t(img.width);
    const int y0 = band * kTile, y1 = std::min(img.height, y0 + kTile);
    const size_t begin = size_t(y0) * w, count = size_t(y1 - y0) * w;
    // The band is traced into buffers of its own, which stay in cache while its tiles write them
    // packet by packet, and then copied to its contiguous range of the image in one go. Every
    // pixel of the band is one valid lane of one packet, so the buffers need no clearing.
    const auto id = std::make_unique_for_overwrite<uint32_t[]>(count);
    const auto depth = std::make_unique_for_overwrite<float[]>(count);
    const auto u = std::make_unique_for_overwrite<float[]>(kBary ? count : 0);
    const auto v = std::make_unique_for_overwrite<float[]>(kBary ? count : 0);
    st.rays += count;
    uint64_t hits = 0, packets = 0;  // in registers, not through `st`
    const uint32_t *toSource = primToSource.data();
    // The gather indexes in signed 32 bits.
    const bool avx2 = __builtin_cpu_supports("avx2") && primToSource.size() <= size_t(INT32_MAX);
    rays.forEachPacket(band, [](int, int, int) {}, [&](int px, int py) {
        const bool whole = rays.fill(px, py, rh, valid);
        if constexpr (kTies) fc.resetLanes();
        rtcIntersect16(valid, scene, &fc.ctx, &rh);
        ++packets;
        if (avx2 && whole) {
            hits += storeWholePacketAvx2<kBary>(rh, toSource, size_t(py - y0) * w + size_t(px), w, id.get(), depth.get(),
                                                u.get(), v.get());
            return;
        }
        // Branch-free over the lanes: a miss keeps tfar = far and geomID invalid, and Embree leaves
        // primID as it was (init()'s 0 or an earlier hit), always a valid index.
        for (int i = 0; i < 16; ++i) {
            if (!valid[i]) continue;
            const bool hit = rh.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID;
            hits += hit;
            const size_t p = size_t(py - y0 + (i >> 2)) * w + size_t(px + (i & 3));
            id[p] = hit ? 1 + toSource[rh.hit.primID[i]] : 0;
            depth[p] = hit ? rh.ray.tfar[i] : float(INFINITY);
            if constexpr (kBary) {
                u[p] = hit ? rh.hit.u[i] : 0.0f;
                v[p] = hit ? rh.hit.v[i] : 0.0f;
            }
        }
    });
    st.hits += hits;
    st.packets += packets;
    streamCopy(id.get(), count, img.id.data() + begin);
    streamCopy(depth.get(), count, img.depth.data() + begin);
    if constexpr (kBary) {
        streamCopy(u.get(), count, img.u.data() + begin);
        streamCopy(v.get(), count, img.v.data() + begin);
    }
}

// Every band, in parallel (tbb; threads as tbb::global_control allows). Stats are summed per band
// in band order, so they too are identical for any thread count.
template <bool kBary, bool kTies>
void castBands(RTCScene scene, const FilterContext &proto, const PacketRays &rays,
               const std::vector<uint32_t> &primToSource, RaycastImage &img, RaycastStats &st) {
    std::vector<RaycastStats> perBand(size_t(rays.bands()));
    tbb::parallel_for(0, rays.bands(), [&](int b) {
        FilterContext fc = proto;
        castBand<kBary, kTies>(scene, fc, rays, b, primToSource, img, perBand[size_t(b)]);
    });
    for (const RaycastStats &s : perBand) {
        st.rays += s.rays;
        st.hits += s.hits;
        st.packets += s.packets;
    }
}
}  // namespace

void recycleRaycastImage(RaycastImage &img) {
    RaycastImage kept = std::move(img);
    img = RaycastImage{};
    if (kept.id.capacity() + kept.depth.capacity() + kept.u.capacity() + kept.v.capacity() == 0) return;
    kept.width = kept.height = 0;
    kept.id.clear(), kept.depth.clear(), kept.u.clear(), kept.v.clear();
    recyclerOf<RaycastImage>().give(std::move(kept));
}

RaycastImage RayScene::castPrimary(const Camera &cam, RaycastStats *stats) const {
    return castPrimary(cam, PrimaryOptions{}, stats);
}

RaycastImage RayScene::castPrimary(const Camera &cam, const PrimaryOptions &opt, RaycastStats *stats) const {
    const Impl &m = *impl_;
    RaycastImage img = recyclerOf<RaycastImage>().take();  // a finished view's, when one gave it back
    img.width = cam.width;
    img.height = cam.height;
    const size_t n = size_t(cam.width) * cam.height;
    assignOnLargePages(img.id, n, 0u);
    assignOnLargePages(img.depth, n, float(INFINITY));
    if (opt.keepBarycentrics) {
        assignOnLargePages(img.u, n, 0.0f);
        assignOnLargePages(img.v, n, 0.0f);
    }
    const RayGen gen(cam, m.origin);
    FilterContext rc;
    rtcInitIntersectContext(&rc.ctx);
    rc.ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    std::vector<uint8_t> reject;
    if (opt.rejectBackFaces) {
        // Which primitives are seen from their back, decided once per view with the backface stage's
        // rule (plane at the eye > 0 is front; orthographic: n . forward < 0 is front; 0 is back).
        const size_t prims = m.primToSource.size();
        reject.assign(prims, 0);
        for (size_t k = 0; k < prims; ++k) {
            const uint32_t src = m.primToSource[k];
            if (opt.doubleSided && opt.doubleSided[src]) continue;
            Vec3 nrm;
            double atEye;  // plane value at the eye (perspective)
            if (opt.planes) {
                const double *pl = opt.planes + 4 * size_t(src);
                nrm = {pl[0], pl[1], pl[2]};
                atEye = dot(nrm, cam.eye) + pl[3];
            } else {
                // The plane of Embree's own float triangle, in double, in the float frame.
                const unsigned *tri = m.ib + 3 * k;
                Vec3 v[3];
                for (int j = 0; j < 3; ++j)
                    v[j] = {m.vb[3 * size_t(tri[j])], m.vb[3 * size_t(tri[j]) + 1], m.vb[3 * size_t(tri[j]) + 2]};
                nrm = cross(v[1] - v[0], v[2] - v[0]);
                atEye = dot(nrm, gen.eyeRel - v[0]);
            }
            const bool front = cam.orthographic ? dot(nrm, cam.forward) < 0 : atEye > 0;
            reject[k] = front ? 0 : 1;
        }
        rc.reject = reject.data();
        rc.ctx.filter = primaryFilter;
    }
    if (opt.rejectSource) {
        // Triangles outside the cast's set: rejected like back faces.
        const size_t prims = m.primToSource.size();
        if (reject.empty()) reject.assign(prims, 0);
        for (size_t k = 0; k < prims; ++k) reject[k] |= opt.rejectSource[m.primToSource[k]] ? 1 : 0;
        rc.reject = reject.data();
        rc.ctx.filter = primaryFilter;
    }
    if (opt.tiesToLowestId && !m.primToSource.empty()) {
        rc.primToSource = m.primToSource.data();
        rc.ctx.filter = primaryFilter;
    }
    RaycastStats st;
    if (n) {
        const PacketRays rays(gen, cam);
        const bool ties = rc.primToSource != nullptr;
        if (opt.keepBarycentrics)
            ties ? castBands<true, true>(m.scene, rc, rays, m.primToSource, img, st)
                 : castBands<true, false>(m.scene, rc, rays, m.primToSource, img, st);
        else
            ties ? castBands<false, true>(m.scene, rc, rays, m.primToSource, img, st)
                 : castBands<false, false>(m.scene, rc, rays, m.primToSource, img, st);
    }
    if (stats) *stats = st;
    return img;
}

uint64_t RayScene::castPrimaryRaw(const Camera &cam) const {
    const Impl &m = *impl_;
    const RayGen gen(cam, m.origin);
    const PacketRays rays(gen, cam);
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    alignas(64) RTCRayHit16 rh;
    alignas(64) int valid[16];
    rays.init(rh);
    uint64_t hits = 0;
    for (int b = 0; b < rays.bands(); ++b)
        rays.forEachPacket(b, [](int, int, int) {}, [&](int px, int py) {
            rays.fill(px, py, rh, valid);
            rtcIntersect16(valid, m.scene, &ctx, &rh);
            for (int i = 0; i < 16; ++i) hits += valid[i] && rh.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID;
        });
    return hits;
}

LocalRay RayScene::primaryRay(const Camera &cam, int x, int y) const {
    const RayGen gen(cam, impl_->origin);
    LocalRay r;
    gen.make(x, y, r.org, r.dir);
    r.tnear = float(cam.nearZ);
    r.tfar = float(cam.farZ);
    return r;
}

LocalHit RayScene::intersect(const LocalRay &ray) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh;
    rh.ray.org_x = ray.org[0], rh.ray.org_y = ray.org[1], rh.ray.org_z = ray.org[2];
    rh.ray.dir_x = ray.dir[0], rh.ray.dir_y = ray.dir[1], rh.ray.dir_z = ray.dir[2];
    rh.ray.tnear = ray.tnear;
    rh.ray.tfar = ray.tfar;
    rh.ray.time = 0;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(impl_->scene, &ctx, &rh);
    LocalHit h;
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return h;
    h.prim = rh.hit.primID;
    h.t = rh.ray.tfar;
    h.u = rh.hit.u;
    h.v = rh.hit.v;
    h.ng[0] = rh.hit.Ng_x, h.ng[1] = rh.hit.Ng_y, h.ng[2] = rh.hit.Ng_z;
    return h;
}

namespace {
// intersectStream's back-face rejection: a candidate whose geometric normal does not face the ray
// (dot(Ng, dir) >= 0) is rejected, so the ray continues to what lies behind.
void streamBackFaceFilter(const RTCFilterFunctionNArguments *args) {
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        const float d = RTCHitN_Ng_x(args->hit, args->N, i) * RTCRayN_dir_x(args->ray, args->N, i) +
                        RTCHitN_Ng_y(args->hit, args->N, i) * RTCRayN_dir_y(args->ray, args->N, i) +
                        RTCHitN_Ng_z(args->hit, args->N, i) * RTCRayN_dir_z(args->ray, args->N, i);
        if (d >= 0) args->valid[i] = 0;
    }
}
}  // namespace

void RayScene::intersectStream(const LocalRay *rays, size_t n, bool rejectBackFaces, LocalHit *hits) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
    if (rejectBackFaces) ctx.filter = streamBackFaceFilter;
    alignas(64) RTCRayHit16 rh;
    alignas(64) int valid[16];
    for (size_t first = 0; first < n; first += 16) {
        const size_t count = std::min<size_t>(16, n - first);
        for (size_t i = 0; i < 16; ++i) {
            // Lanes past the end repeat the last ray, masked invalid.
            const LocalRay &r = rays[first + std::min(i, count - 1)];
            valid[i] = i < count ? -1 : 0;
            rh.ray.org_x[i] = r.org[0], rh.ray.org_y[i] = r.org[1], rh.ray.org_z[i] = r.org[2];
            rh.ray.dir_x[i] = r.dir[0], rh.ray.dir_y[i] = r.dir[1], rh.ray.dir_z[i] = r.dir[2];
            rh.ray.tnear[i] = r.tnear;
            rh.ray.tfar[i] = r.tfar;
            rh.ray.time[i] = 0;
            rh.ray.mask[i] = 0xFFFFFFFFu;
            rh.ray.id[i] = unsigned(i);
            rh.ray.flags[i] = 0;
            rh.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
            rh.hit.primID[i] = RTC_INVALID_GEOMETRY_ID;
            rh.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
        }
        rtcIntersect16(valid, impl_->scene, &ctx, &rh);
        for (size_t i = 0; i < count; ++i) {
            LocalHit &h = hits[first + i];
            h = LocalHit{};
            if (rh.hit.geomID[i] == RTC_INVALID_GEOMETRY_ID) continue;
            h.prim = rh.hit.primID[i];
            h.t = rh.ray.tfar[i];
            h.u = rh.hit.u[i];
            h.v = rh.hit.v[i];
            h.ng[0] = rh.hit.Ng_x[i], h.ng[1] = rh.hit.Ng_y[i], h.ng[2] = rh.hit.Ng_z[i];
        }
    }
}

bool RayScene::occluded(const LocalRay &ray) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRay r;
    r.org_x = ray.org[0], r.org_y = ray.org[1], r.org_z = ray.org[2];
    r.dir_x = ray.dir[0], r.dir_y = ray.dir[1], r.dir_z = ray.dir[2];
    r.tnear = ray.tnear;
    r.tfar = ray.tfar;
    r.time = 0;
    r.mask = 0xFFFFFFFFu;
    r.id = 0;
    r.flags = 0;
    rtcOccluded1(impl_->scene, &ctx, &r);
    return r.tfar == -INFINITY;  // Embree marks an occluded ray with tfar = -inf
}

Vec3 RayScene::origin() const { return impl_->origin; }
size_t RayScene::primitiveCount() const { return impl_->primToSource.size(); }
uint32_t RayScene::sourceOf(uint32_t prim) const { return impl_->primToSource[prim]; }
uint32_t RayScene::primitiveOf(uint32_t src) const {
    return src < impl_->sourceToPrim.size() ? impl_->sourceToPrim[src] : kNoHit;
}
void RayScene::vertices(uint32_t prim, float v[9]) const {
    const unsigned *tri = impl_->ib + 3 * size_t(prim);
    for (int j = 0; j < 3; ++j)
        for (int a = 0; a < 3; ++a) v[3 * j + a] = impl_->vb[3 * size_t(tri[j]) + a];
}

}  // namespace va
