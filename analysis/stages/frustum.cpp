#include "analysis/stages/frustum.h"
#include "analysis/stage.h"

#include <algorithm>
#include <cmath>

namespace va {

namespace {

// Smallest sphere (conservatively) enclosing two spheres.
Sphere enclose(const Sphere &a, const Sphere &b) {
    const Vec3 d = b.center - a.center;
    const double dist = length(d);
    if (dist + b.radius <= a.radius) return a;
    if (dist + a.radius <= b.radius) return b;
    const double r = 0.5 * (dist + a.radius + b.radius);
    const Vec3 c = a.center + d * ((r - a.radius) / dist);
    // Rounded up: the center and the radius carry a few ulps of error each.
    return {c, r * (1 + gamma(8)) + gamma(8) * maxAbs(c)};
}

void buildNode(const Scene &scene, ObjectBvh &bvh, uint32_t nodeIndex, uint32_t first, uint32_t count) {
    constexpr uint32_t kLeafSize = 4;
    if (count <= kLeafSize) {
        Sphere s = scene.objects[bvh.order[first]].sphere;
        for (uint32_t i = 1; i < count; ++i) s = enclose(s, scene.objects[bvh.order[first + i]].sphere);
        bvh.nodes[nodeIndex] = {s, first, count};
        return;
    }
    // Median split of sphere centers along the longest axis of their bounds; ties broken by index,
    // so the tree is the same on every run.
    Aabb cb;
    for (uint32_t i = 0; i < count; ++i) cb.extend(scene.objects[bvh.order[first + i]].sphere.center);
    const Vec3 e = cb.extent();
    const int axis = e.x >= e.y && e.x >= e.z ? 0 : (e.y >= e.z ? 1 : 2);
    const uint32_t mid = count / 2;
    auto begin = bvh.order.begin() + first;
    std::nth_element(begin, begin + mid, begin + count, [&](uint32_t a, uint32_t b) {
        const double ca = scene.objects[a].sphere.center[axis], cb2 = scene.objects[b].sphere.center[axis];
        return ca < cb2 || (ca == cb2 && a < b);
    });
    const uint32_t left = uint32_t(bvh.nodes.size());
    bvh.nodes.resize(bvh.nodes.size() + 2);
    buildNode(scene, bvh, left, first, mid);
    buildNode(scene, bvh, left + 1, first + mid, count - mid);
    bvh.nodes[nodeIndex] = {enclose(bvh.nodes[left].sphere, bvh.nodes[left + 1].sphere), left, 0};
}

}  // namespace

ObjectBvh buildObjectBvh(const Scene &scene) {
    ObjectBvh bvh;
    const uint32_t n = uint32_t(scene.objects.size());
    if (n == 0) return bvh;
    bvh.order.resize(n);
    for (uint32_t i = 0; i < n; ++i) bvh.order[i] = i;
    bvh.nodes.reserve(2 * n);
    bvh.nodes.resize(1);
    buildNode(scene, bvh, 0, 0, n);
    return bvh;
}

FrustumPlanes worldFrustumPlanes(const Camera &cam) {
    // View-space planes (x_v, y_v, z_v), inside >= 0, with d = -z_v (camera.h):
    //   near: d - n   far: f - d   left: sx x + w   right: -sx x + w   bottom: sy y + w   top: -sy y + w
    // where w = d (perspective) or 1 (orthographic).
    struct P { Vec3 n; double k; };
    P v[6];
    v[kPlaneNear] = {{0, 0, -1}, -cam.nearZ};
    v[kPlaneFar] = {{0, 0, 1}, cam.farZ};
    if (cam.orthographic) {
        v[kPlaneLeft] = {{cam.sx, 0, 0}, 1};
        v[kPlaneRight] = {{-cam.sx, 0, 0}, 1};
        v[kPlaneBottom] = {{0, cam.sy, 0}, 1};
        v[kPlaneTop] = {{0, -cam.sy, 0}, 1};
    } else {
        v[kPlaneLeft] = {{cam.sx, 0, -1}, 0};
        v[kPlaneRight] = {{-cam.sx, 0, -1}, 0};
        v[kPlaneBottom] = {{0, cam.sy, -1}, 0};
        v[kPlaneTop] = {{0, -cam.sy, -1}, 0};
    }
    // To world: p_v = R (p_w - eye) with R's rows (right, up, -forward), so
    // n.p_v + k = (R^T n).p_w - (R^T n).eye + k.
    FrustumPlanes fp;
    for (int i = 0; i < 6; ++i) {
        const double len = length(v[i].n);
        const Vec3 nv = v[i].n / len;
        const Vec3 nw = cam.right * nv.x + cam.up * nv.y - cam.forward * nv.z;
        fp.n[i] = nw;
        fp.k[i] = v[i].k / len - dot(nw, cam.eye);
    }
    return fp;
}

int classifySphere(const FrustumPlanes &fp, const Sphere &s, uint32_t *mask, uint64_t *planeTests) {
    int result = 1;
    for (int i = 0; i < 6; ++i) {
        if (!(*mask & (1u << i))) continue;
        ++*planeTests;
        const Vec3 &n = fp.n[i];
        const double dist = dot(n, s.center) + fp.k[i];
        // Conservative margin: the dot product and the sum carry at most gamma(4) relative error
        // of the magnitudes involved; the planes themselves were built with a few more operations.
        const double err = gamma(16) * (std::fabs(n.x * s.center.x) + std::fabs(n.y * s.center.y) +
                                        std::fabs(n.z * s.center.z) + std::fabs(fp.k[i]) + s.radius);
        if (dist < -(s.radius + err)) return -1;   // entirely outside this plane
        if (dist > s.radius + err)
            *mask &= ~(1u << i);                   // entirely inside: children need not test it
        else
            result = 0;
    }
    return result;
}

FrustumResult cullFrustum(const Scene &scene, const ObjectBvh &bvh, const Camera &cam,
                          const std::vector<uint32_t> *candidates) {
    FrustumResult r;
    FrustumStats &st = r.stats;
    st.objectsIn = candidates ? candidates->size() : scene.objects.size();
    st.planeTestsBruteForce = 6 * st.objectsIn;
    if (bvh.nodes.empty()) return r;
    const FrustumPlanes fp = worldFrustumPlanes(cam);

    // Depth-first walk; a subtree inside all planes is accepted whole, one outside a plane is
    // rejected whole, with no further tests.
    struct Item { uint32_t node, mask; };
    std::vector<Item> stack{{0, 0x3F}};
    std::vector<uint8_t> state(scene.objects.size(), 0);  // 0 culled, 1 intersecting, 2 inside
    auto markRange = [&](uint32_t node, uint8_t value, auto &&self) -> void {
        const ObjectBvh::Node &nd = bvh.nodes[node];
        if (nd.count) {
            for (uint32_t i = 0; i < nd.count; ++i) state[bvh.order[nd.first + i]] = value;
        } else {
            self(nd.first, value, self);
            self(nd.first + 1, value, self);
        }
    };
    while (!stack.empty()) {
        const Item it = stack.back();
        stack.pop_back();
        const ObjectBvh::Node &nd = bvh.nodes[it.node];
        ++st.nodesVisited;
        uint32_t mask = it.mask;
        const int c = mask ? classifySphere(fp, nd.sphere, &mask, &st.planeTests) : 1;
        if (c < 0) continue;  // outside: everything below stays culled
        if (c > 0 || mask == 0) {
            markRange(it.node, 2, markRange);
            continue;
        }
        if (nd.count) {
            // Leaf: test each object's own sphere with the planes still undecided.
            for (uint32_t i = 0; i < nd.count; ++i) {
                const uint32_t o = bvh.order[nd.first + i];
                uint32_t m = mask;
                const int oc = classifySphere(fp, scene.objects[o].sphere, &m, &st.planeTests);
                state[o] = oc < 0 ? 0 : (oc > 0 || m == 0 ? 2 : 1);
            }
        } else {
            stack.push_back({nd.first + 1, mask});
            stack.push_back({nd.first, mask});
        }
    }
    std::vector<uint8_t> input(scene.objects.size(), candidates ? 0 : 1);
    if (candidates)
        for (uint32_t o : *candidates) input[o] = 1;
    for (uint32_t o = 0; o < state.size(); ++o) {
        if (!input[o]) continue;
        if (state[o] == 0) {
            ++st.objectsCulled;
        } else {
            r.visible.push_back(o);
            if (state[o] == 2)
                ++st.objectsInside;
            else
                ++st.objectsIntersecting;
        }
    }
    return r;
}


// The pipeline's row (analysis/stage.h): bounding spheres over the object BVH, of the objects the
// coarse stage kept.
namespace {
std::string frustumSkip(const ViewContext &c) { return c.s.frustum ? "" : "turned off by --no-frustum"; }
ObjectCull frustumRun(ViewContext &c, const std::vector<uint32_t> &objects) {
    FrustumResult f = cullFrustum(c.scene, c.ps.bvh, c.cam, &objects);
    c.r.frustum = f.stats;
    return {std::move(f.visible), {}, {}, 0};
}
}  // namespace
extern const ObjectStage kFrustumStage = {"frustum", frustumSkip, frustumRun};

}  // namespace va
