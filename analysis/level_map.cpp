// The level seen from above, through the project's own renderer (analysis/level_map.h).
#include "analysis/level_map.h"

#include <algorithm>
#include <cmath>

#include "analysis/load/json_reader.h"
#include "analysis/load/level_views.h"
#include "analysis/stages/backface.h"
#include "render/clip.h"
#include "render/raster.h"
#include "render/stopwatch.h"

namespace va {

namespace {
// The floor plan's screen axes: right R and screen-up S span the ground plane, (R, S, U) right-handed
// so that the camera looking down -U with up S has R as its right: z up -> x right, y up the map's
// top; y up -> x right, -z up; x up -> y right, z up.
void screenAxes(char up, Vec3 *R, Vec3 *S) {
    if (up == 'z') *R = {1, 0, 0}, *S = {0, 1, 0};
    else if (up == 'y') *R = {1, 0, 0}, *S = {0, 0, -1};
    else *R = {0, 1, 0}, *S = {0, 0, 1};
}
}  // namespace

double levelEyeHeight(const Scene &scene) { return scene.bsp ? kQuakeFloorEye : 1.7; }

bool renderFloorPlan(const Scene &scene, const FloorPlanSettings &s, FloorPlan *out, std::string *err) {
    const Stopwatch t0;
    const Vec3 U = load::upVector(scene.up);
    Vec3 R, S;
    screenAxes(scene.up, &R, &S);
    if (scene.bounds.empty() || !isFinite(scene.bounds.lo) || !isFinite(scene.bounds.hi)) {
        *err = scene.path + ": the scene has no bounds to draw a level map of (no triangles)";
        return false;
    }
    // The box's extent along R, S and U (the axes are coordinate axes or their negatives).
    double lo[3], hi[3];
    const Vec3 axes[3] = {R, S, U};
    for (int a = 0; a < 3; ++a) {
        const double p = dot(scene.bounds.lo, axes[a]), q = dot(scene.bounds.hi, axes[a]);
        lo[a] = std::min(p, q), hi[a] = std::max(p, q);
    }
    const double ext = std::max(hi[0] - lo[0], hi[1] - lo[1]);
    if (!(ext > 0) || !std::isfinite(ext)) {
        *err = scene.path + ": the scene has no extent across its up axis (" + std::string(1, scene.up) +
               "); a level map needs a floor to draw";
        return false;
    }
    const int size = std::max(16, s.size);
    // A 2% margin around the box, square pixels.
    const double margin = ext * 0.02, pixel = (ext + 2 * margin) / size;
    const int W = std::max(1, int(std::ceil((hi[0] - lo[0] + 2 * margin) / pixel)));
    const int H = std::max(1, int(std::ceil((hi[1] - lo[1] + 2 * margin) / pixel)));
    // Above the box by 1% of its size, looking down; near and far hold the whole box.
    const double mu = std::max(hi[2] - lo[2], ext) * 0.01;
    const double eyeU = hi[2] + mu;
    FloorPlan f;
    f.up = scene.up;
    f.width = W;
    f.height = H;
    f.worldPerPixel = pixel;
    f.step = s.step > 0 ? s.step : 0.36 * (s.eyeHeight > 0 ? s.eyeHeight : levelEyeHeight(scene));
    CameraSpec &c = f.camera;
    c.orthographic = true;
    c.eye = R * ((lo[0] + hi[0]) * 0.5) + S * ((lo[1] + hi[1]) * 0.5) + U * eyeU;
    c.target = c.eye - U;
    c.up = S;
    c.orthoHeight = H * pixel;
    c.nearZ = mu * 0.5;
    c.farZ = hi[2] - lo[2] + 2 * mu;
    c.width = W;
    c.height = H;
    Camera cam;
    if (!makeCamera(c, &cam, err)) {
        *err = scene.path + ": the level map's camera: " + *err;
        return false;
    }

    // Every triangle, single-sided: only what faces up (floors, slopes; not ceilings) is drawn, the
    // depth test in double (exactDepth): the topmost such surface wins.
    std::vector<uint32_t> objects(scene.objects.size());
    for (size_t i = 0; i < objects.size(); ++i) objects[i] = uint32_t(i);
    const TriangleLists lists = allTriangles(scene, objects);
    const ClipResult clip = clipTriangles(cam, MeshView{scene.positions.data(), scene.indices.data()},
                                          clipBatches(scene, lists), ClipSettings{});
    const std::vector<uint8_t> singleSided(scene.triangleCount(), 1);
    ZBufferSettings zs;
    zs.encoder = makeDepthEncoder(DepthFormat::f32, cam.nearZ, cam.farZ);
    zs.orthographic = true;
    zs.exactDepth = true;
    zs.singleSided = singleSided.data();
    const ZBufferResult z = rasterize(clip.out, W, H, zs);

    const size_t n = size_t(W) * size_t(H);
    f.surface.assign(n, NAN);
    f.slope.assign(n, 0.0f);
    f.gray.assign(n, 0);
    double hLo = INFINITY, hHi = -INFINITY;
    for (size_t p = 0; p < n; ++p) {
        if (!z.buffer.id[p]) continue;
        const uint32_t t = z.buffer.id[p] - 1;
        const double h = eyeU - z.buffer.depth[p];
        f.surface[p] = float(h);
        const Vec3 nrm{scene.planes[4 * size_t(t)], scene.planes[4 * size_t(t) + 1], scene.planes[4 * size_t(t) + 2]};
        const double len = length(nrm);
        f.slope[p] = len > 0 ? float(std::fabs(dot(nrm, U)) / len) : 0.0f;
        hLo = std::min(hLo, h), hHi = std::max(hHi, h);
        ++f.drawnPixels;
    }
    // The gray: higher is lighter, floors lighter than slopes, darkened where the surface ends or
    // its height jumps by more than a step (a wall's outline). 0 stays "nothing faces up here".
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const size_t p = size_t(y) * size_t(W) + size_t(x);
            const float h = f.surface[p];
            if (!std::isfinite(h)) continue;
            const double hf = hHi > hLo ? (h - hLo) / (hHi - hLo) : 1.0;
            double shade = 0.45 + 0.3 * hf + 0.2 * f.slope[p];
            for (const auto &[dx, dy] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
                const int nx = x + dx, ny = y + dy;
                if (nx < 0 || ny < 0 || nx >= W || ny >= H) continue;
                const float q = f.surface[size_t(ny) * size_t(W) + size_t(nx)];
                if (!std::isfinite(q) || std::fabs(double(q) - h) > f.step) {
                    shade *= 0.6;
                    break;
                }
            }
            f.gray[p] = uint8_t(std::clamp(std::lround(255 * shade), 1l, 255l));
        }
    f.ms = t0.ms();
    *out = std::move(f);
    return true;
}

bool floorPixelOf(const CameraSpec &spec, Vec3 p, double *px, double *py) {
    Camera cam;
    if (!makeCamera(spec, &cam, nullptr)) return false;
    const Mat4 &v = cam.viewFromWorld;
    const double xv = v.m[0][0] * p.x + v.m[0][1] * p.y + v.m[0][2] * p.z + v.m[0][3];
    const double yv = v.m[1][0] * p.x + v.m[1][1] * p.y + v.m[1][2] * p.z + v.m[1][3];
    *px = (xv * cam.sx + 1) * cam.width * 0.5;
    *py = (1 - yv * cam.sy) * cam.height * 0.5;
    return true;
}

Vec3 floorWorldAt(const FloorPlan &plan, int x, int y, double h) {
    const Vec3 U = load::upVector(plan.up);
    Vec3 R, S;
    screenAxes(plan.up, &R, &S);
    // Pixel centre -> view-plane offsets (the inverse of floorPixelOf's mapping).
    const double halfH = plan.camera.orthoHeight * 0.5, halfW = halfH * plan.width / plan.height;
    const double xv = ((x + 0.5) * 2 / plan.width - 1) * halfW, yv = (1 - (y + 0.5) * 2 / plan.height) * halfH;
    const Vec3 e = plan.camera.eye;
    const Vec3 p = e + R * xv + S * yv;
    return p - U * dot(p, U) + U * h;
}

}  // namespace va
