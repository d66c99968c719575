// The occlusion stage: occluder selection, depth pre-pass through the fragment core, max-depth
// pyramid, conservative box tests (docs/coarse-stages.md).
#include "analysis/stages/occlusion.h"
#include "analysis/stage.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "render/clip.h"
#include "render/raster.h"
#include "render/raster_core.h"
#include "render/stopwatch.h"

namespace va {

namespace {


constexpr double kInf = std::numeric_limits<double>::infinity();

// Depth-only sink: the nearest occluder depth per pixel. Single-sided triangles count from their
// front winding only, exactly as the reference visibility draws them (audit.h): a back face of a
// single-sided occluder hides nothing there.
struct DepthSink {
    const Scene &scene;
    const uint32_t *source;
    double *depth;
    uint64_t fragments = 0;
    bool beginTriangle(size_t t, bool frontWinding) {
        const uint32_t src = source[t];
        return frontWinding || scene.materialOf(scene.objects[scene.triangleObject[src]]).doubleSided;
    }
    void fragment(size_t pixel, size_t, double d) {
        ++fragments;
        if (d < depth[pixel]) depth[pixel] = d;
    }
    void endTriangle(size_t, uint64_t) {}
};

}  // namespace

HiZ buildHiZ(std::vector<double> depth, int width, int height) {
    HiZ h;
    h.width.push_back(width);
    h.height.push_back(height);
    h.depth.push_back(std::move(depth));
    while (h.width.back() > 1 || h.height.back() > 1) {
        const int w = h.width.back(), ht = h.height.back();
        const int nw = (w + 1) / 2, nh = (ht + 1) / 2;
        std::vector<double> next(size_t(nw) * size_t(nh));
        const std::vector<double> &prev = h.depth.back();
        // A texel is the maximum of the (up to 4) texels it covers: past an odd edge there are
        // fewer children, never an invented value.
        for (int y = 0; y < nh; ++y)
            for (int x = 0; x < nw; ++x) {
                double m = -kInf;
                for (int dy = 0; dy < 2; ++dy)
                    for (int dx = 0; dx < 2; ++dx) {
                        const int sx = 2 * x + dx, sy = 2 * y + dy;
                        if (sx < w && sy < ht) m = std::max(m, prev[size_t(sy) * size_t(w) + size_t(sx)]);
                    }
                next[size_t(y) * size_t(nw) + size_t(x)] = m;
            }
        h.width.push_back(nw);
        h.height.push_back(nh);
        h.depth.push_back(std::move(next));
    }
    return h;
}

double hizMaxDepth(const HiZ &h, int x0, int y0, int x1, int y1, uint64_t *texelsRead) {
    // The finest level where the rectangle spans at most 4 texels per axis: texel (x >> L, y >> L)
    // covers pixels [x, x + 2^L) of level 0, so the texels read cover the rectangle.
    size_t L = 0;
    while (L + 1 < h.levels() && (((x1 >> L) - (x0 >> L)) > 3 || ((y1 >> L) - (y0 >> L)) > 3)) ++L;
    const int w = h.width[L];
    double m = -kInf;
    for (int y = y0 >> L; y <= (y1 >> L); ++y)
        for (int x = x0 >> L; x <= (x1 >> L); ++x) {
            ++*texelsRead;
            m = std::max(m, h.depth[L][size_t(y) * size_t(w) + size_t(x)]);
        }
    return m;
}

std::vector<uint32_t> selectOccluders(const Scene &scene, const Camera &cam, const std::vector<uint32_t> &objects,
                                      uint32_t maxOccluders) {
    struct Cand {
        double score;
        uint32_t o;
    };
    std::vector<Cand> c;
    for (uint32_t o : objects) {
        const SceneObject &ob = scene.objects[o];
        if (ob.triEnd == ob.triBegin || scene.materialOf(ob).transparent()) continue;
        const Vec3 rel = ob.sphere.center - cam.eye;
        if (!(dot(rel, cam.forward) > 0)) continue;  // center behind the eye
        const double dist = std::max(length(rel), cam.nearZ);
        c.push_back({ob.sphere.radius / dist, o});
    }
    std::sort(c.begin(), c.end(), [](const Cand &a, const Cand &b) { return a.score > b.score || (a.score == b.score && a.o < b.o); });
    std::vector<uint32_t> out;
    for (size_t i = 0; i < c.size() && i < maxOccluders; ++i) out.push_back(c[i].o);
    return out;
}

OcclusionResult cullOcclusion(const Scene &scene, const Camera &cam, const std::vector<uint32_t> &objects,
                              const OcclusionSettings &settings) {
    OcclusionResult r;
    OcclusionStats &st = r.stats;
    const Stopwatch t0;
    const int W = std::max(cam.width, 0), H = std::max(cam.height, 0);

    // 1. Occluders and their depth pre-pass, through the pipeline's clipper and fragment core.
    r.occluders = selectOccluders(scene, cam, objects, settings.maxOccluders);
    std::vector<uint8_t> isOccluder(scene.objects.size(), 0);
    std::vector<ClipBatch> batches;
    for (uint32_t o : r.occluders) {
        const SceneObject &ob = scene.objects[o];
        isOccluder[o] = 1;
        batches.push_back({ob.vertexBegin, ob.vertexEnd, scene.objectTriangles.data() + ob.triBegin, ob.triEnd - ob.triBegin});
        st.occluderTriangles += ob.triEnd - ob.triBegin;
    }
    st.occludersUsed = r.occluders.size();
    std::vector<double> depth(size_t(W) * size_t(H), kInf);
    if (!batches.empty()) {
        const ClipResult clip = clipTriangles(cam, MeshView{scene.positions.data(), scene.indices.data()}, batches, ClipSettings{});
        DepthSink sink{scene, clip.out.source.data(), depth.data()};
        forEachFragment(clip.out, W, H, cam.orthographic, sink);
        st.prepassFragments = sink.fragments;
    }
    for (double d : depth) st.prepassPixels += d < kInf;
    const HiZ hiz = buildHiZ(std::move(depth), W, H);
    st.hizLevels = hiz.levels();
    st.prepassMs = t0.ms();

    // 2. Every other object's box against the pyramid.
    const Stopwatch t1;
    const double margin = 1.0 / 256;  // px: twice the rasterizer's vertex snapping (1/512 px per axis)
    for (uint32_t o : objects) {
        const SceneObject &ob = scene.objects[o];
        ++st.objectsIn;
        st.trianglesIn += ob.triEnd - ob.triBegin;
        bool cull = false;
        if (!isOccluder[o] && W > 0 && H > 0) {
            // Nearest view depth of the box (view depth is linear in the world point, so a corner
            // holds it), rounded down by the dot product's bound; its projected corners bound the
            // projection of the whole box when every corner is in front of the near plane.
            double nearest = kInf;
            double px0 = kInf, px1 = -kInf, py0 = kInf, py1 = -kInf, mag = 0;
            for (int i = 0; i < 8; ++i) {
                const Vec3 p{i & 1 ? ob.bounds.hi.x : ob.bounds.lo.x, i & 2 ? ob.bounds.hi.y : ob.bounds.lo.y,
                             i & 4 ? ob.bounds.hi.z : ob.bounds.lo.z};
                const Vec3 rel = p - cam.eye;
                const double err = gamma(8) * (maxAbs(p) + maxAbs(cam.eye)) * 3;
                const double d = dot(rel, cam.forward);
                nearest = std::min(nearest, d - err);
                const Vec4 c = mul(cam.clipFromWorld, Vec4{p.x, p.y, p.z, 1});
                const double w = cam.orthographic ? 1.0 : c.w;
                const double px = (c.x / w + 1) * 0.5 * W, py = (1 - c.y / w) * 0.5 * H;
                px0 = std::min(px0, px);
                px1 = std::max(px1, px);
                py0 = std::min(py0, py);
                py1 = std::max(py1, py);
                mag = std::max(mag, std::max(std::fabs(px), std::fabs(py)));
            }
            if (!(nearest > cam.nearZ)) {
                ++st.objectsNearPlane;  // reaches the near plane or behind the eye: never culled
            } else {
                // Pixel centers (x + 0.5) the widened rectangle holds: the snapped triangles lie
                // within 1/512 px of their exact projection, inside the box's projection; the
                // projection's own rounding is bounded by gamma(32) of the magnitudes.
                const double m = margin + gamma(32) * (mag + W + H);
                const double fx0 = std::ceil(px0 - m - 0.5), fx1 = std::floor(px1 + m - 0.5);
                const double fy0 = std::ceil(py0 - m - 0.5), fy1 = std::floor(py1 + m - 0.5);
                const double cx0 = std::max(fx0, 0.0), cx1 = std::min(fx1, double(W - 1));
                const double cy0 = std::max(fy0, 0.0), cy1 = std::min(fy1, double(H - 1));
                if (cx0 > cx1 || cy0 > cy1) {
                    cull = true;  // no pixel center of the view: no fragment at all
                    ++st.objectsNoPixel;
                } else {
                    ++st.objectsTested;
                    const double occ = hizMaxDepth(hiz, int(cx0), int(cy0), int(cx1), int(cy1), &st.texelsRead);
                    // Strictly behind the farthest occluder depth there, with a relative margin for
                    // the depth-plane evaluation of its fragments (gamma(64) of the depth).
                    if (occ < kInf && nearest * (1 - gamma(64)) > occ) {
                        cull = true;
                        ++st.objectsHidden;
                    }
                }
            }
        }
        if (cull) {
            r.culled.push_back(o);
            ++st.objectsCulled;
            st.trianglesCulled += ob.triEnd - ob.triBegin;
        } else {
            r.visible.push_back(o);
        }
    }
    st.testMs = t1.ms();
    return r;
}


// The pipeline's row (analysis/stage.h). Its time is the pre-pass and the tests, without set-up.
namespace {
std::string occlusionSkip(const ViewContext &c) { return c.s.occlusion ? "" : "turned off by --no-occlusion"; }
ObjectCull occlusionRun(ViewContext &c, const std::vector<uint32_t> &objects) {
    OcclusionResult oc = cullOcclusion(c.scene, c.cam, objects, c.s.occlusionSettings);
    c.r.occlusion = oc.stats;
    return {std::move(oc.visible), std::move(oc.culled), oc.stats.prepassMs + oc.stats.testMs, 0};
}
}  // namespace
extern const ObjectStage kOcclusionStage = {"occlusion", occlusionSkip, occlusionRun};

}  // namespace va
