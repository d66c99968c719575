#include "render/raycast.h"

#include <cmath>
#include <cstdio>
#include <mutex>

#include <embree3/rtcore.h>

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

// Ray setup shared by castPrimary and castPrimaryRaw: origin and direction in the scene's
// float frame (relative to the origin) for pixel (x, y).
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
    void make(int x, int y, float o[3], float d[3]) const {
        const double u = ax * (x + 0.5) + bx, v = ay * (y + 0.5) + by;
        if (ortho) {
            const Vec3 p = eyeRel + right * u + up * v;
            o[0] = float(p.x), o[1] = float(p.y), o[2] = float(p.z);
            d[0] = float(fw.x), d[1] = float(fw.y), d[2] = float(fw.z);
        } else {
            const Vec3 r = right * u + up * v + fw;
            o[0] = float(eyeRel.x), o[1] = float(eyeRel.y), o[2] = float(eyeRel.z);
            d[0] = float(r.x), d[1] = float(r.y), d[2] = float(r.z);
        }
    }
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
// Fills a 16-ray packet for the 4x4 tile at (tx, ty); lanes outside the image are invalid.
void fillPacket(const RayGen &gen, const Camera &cam, int tx, int ty, RTCRayHit16 &rh, int valid[16]) {
    for (int i = 0; i < 16; ++i) {
        const int x = tx + (i & 3), y = ty + (i >> 2);
        valid[i] = (x < cam.width && y < cam.height) ? -1 : 0;
        float o[3] = {0, 0, 0}, d[3] = {0, 0, -1};
        if (valid[i]) gen.make(x, y, o, d);
        rh.ray.org_x[i] = o[0], rh.ray.org_y[i] = o[1], rh.ray.org_z[i] = o[2];
        rh.ray.dir_x[i] = d[0], rh.ray.dir_y[i] = d[1], rh.ray.dir_z[i] = d[2];
        rh.ray.tnear[i] = float(cam.nearZ);
        rh.ray.tfar[i] = float(cam.farZ);
        rh.ray.time[i] = 0;
        rh.ray.mask[i] = 0xFFFFFFFFu;
        rh.ray.id[i] = unsigned(i);
        rh.ray.flags[i] = 0;
        rh.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
        rh.hit.primID[i] = RTC_INVALID_GEOMETRY_ID;
    }
}
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
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        const unsigned prim = RTCHitN_primID(args->hit, args->N, i);
        if (fc.reject && fc.reject[prim]) {
            args->valid[i] = 0;
            continue;
        }
        if (fc.primToSource) {
            const unsigned lane = RTCRayN_id(args->ray, args->N, i) & 15u;
            const float t = RTCRayN_tfar(args->ray, args->N, i);
            const uint32_t src = fc.primToSource[prim];
            if (t == fc.bestT[lane] && src > fc.bestSource[lane]) {
                args->valid[i] = 0;
                continue;
            }
            fc.bestT[lane] = t;
            fc.bestSource[lane] = src;
        }
    }
}

// The tile loop shared by both castPrimary overloads (kBary: also write barycentrics).
// kTies: ctx is a FilterContext that tracks ties per lane (reset per packet).
template <bool kBary, bool kTies>
void castTiles(RTCScene scene, RTCIntersectContext *ctx, const RayGen &gen, const Camera &cam,
               const std::vector<uint32_t> &primToSource, RaycastImage &img, RaycastStats &st) {
    alignas(64) RTCRayHit16 rh;
    alignas(64) int valid[16];
    for (int ty = 0; ty < cam.height; ty += 4)
        for (int tx = 0; tx < cam.width; tx += 4) {
            fillPacket(gen, cam, tx, ty, rh, valid);
            if constexpr (kTies) reinterpret_cast<FilterContext *>(ctx)->resetLanes();
            rtcIntersect16(valid, scene, ctx, &rh);
            ++st.packets;
            for (int i = 0; i < 16; ++i) {
                if (!valid[i]) continue;
                ++st.rays;
                if (rh.hit.geomID[i] == RTC_INVALID_GEOMETRY_ID) continue;
                ++st.hits;
                const size_t p = size_t(ty + (i >> 2)) * cam.width + (tx + (i & 3));
                img.id[p] = 1 + primToSource[rh.hit.primID[i]];
                img.depth[p] = rh.ray.tfar[i];
                if constexpr (kBary) {
                    img.u[p] = rh.hit.u[i];
                    img.v[p] = rh.hit.v[i];
                }
            }
        }
}
}  // namespace

RaycastImage RayScene::castPrimary(const Camera &cam, RaycastStats *stats) const {
    const Impl &m = *impl_;
    RaycastImage img;
    img.width = cam.width;
    img.height = cam.height;
    img.id.assign(size_t(cam.width) * cam.height, 0);
    img.depth.assign(size_t(cam.width) * cam.height, INFINITY);
    const RayGen gen(cam, m.origin);
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    RaycastStats st;
    castTiles<false, false>(m.scene, &ctx, gen, cam, m.primToSource, img, st);
    if (stats) *stats = st;
    return img;
}

RaycastImage RayScene::castPrimary(const Camera &cam, const PrimaryOptions &opt, RaycastStats *stats) const {
    const Impl &m = *impl_;
    RaycastImage img;
    img.width = cam.width;
    img.height = cam.height;
    const size_t n = size_t(cam.width) * cam.height;
    img.id.assign(n, 0);
    img.depth.assign(n, INFINITY);
    if (opt.keepBarycentrics) {
        img.u.assign(n, 0.0f);
        img.v.assign(n, 0.0f);
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
    if (opt.tiesToLowestId && !m.primToSource.empty()) {
        rc.primToSource = m.primToSource.data();
        rc.ctx.filter = primaryFilter;
    }
    RaycastStats st;
    const bool ties = rc.primToSource != nullptr;
    if (opt.keepBarycentrics)
        ties ? castTiles<true, true>(m.scene, &rc.ctx, gen, cam, m.primToSource, img, st)
             : castTiles<true, false>(m.scene, &rc.ctx, gen, cam, m.primToSource, img, st);
    else
        ties ? castTiles<false, true>(m.scene, &rc.ctx, gen, cam, m.primToSource, img, st)
             : castTiles<false, false>(m.scene, &rc.ctx, gen, cam, m.primToSource, img, st);
    if (stats) *stats = st;
    return img;
}

uint64_t RayScene::castPrimaryRaw(const Camera &cam) const {
    const Impl &m = *impl_;
    const RayGen gen(cam, m.origin);
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    alignas(64) RTCRayHit16 rh;
    alignas(64) int valid[16];
    uint64_t hits = 0;
    for (int ty = 0; ty < cam.height; ty += 4)
        for (int tx = 0; tx < cam.width; tx += 4) {
            fillPacket(gen, cam, tx, ty, rh, valid);
            rtcIntersect16(valid, m.scene, &ctx, &rh);
            for (int i = 0; i < 16; ++i) hits += valid[i] && rh.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID;
        }
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
