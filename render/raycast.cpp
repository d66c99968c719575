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
    rtcSetSceneFlags(m.scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(m.scene, RTC_BUILD_QUALITY_HIGH);
    m.primToSource = triangles;
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
    alignas(64) RTCRayHit16 rh;
    alignas(64) int valid[16];
    RaycastStats st;
    for (int ty = 0; ty < cam.height; ty += 4)
        for (int tx = 0; tx < cam.width; tx += 4) {
            fillPacket(gen, cam, tx, ty, rh, valid);
            rtcIntersect16(valid, m.scene, &ctx, &rh);
            ++st.packets;
            for (int i = 0; i < 16; ++i) {
                if (!valid[i]) continue;
                ++st.rays;
                if (rh.hit.geomID[i] == RTC_INVALID_GEOMETRY_ID) continue;
                ++st.hits;
                const size_t p = size_t(ty + (i >> 2)) * cam.width + (tx + (i & 3));
                img.id[p] = 1 + m.primToSource[rh.hit.primID[i]];
                img.depth[p] = rh.ray.tfar[i];
            }
        }
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

}  // namespace va
