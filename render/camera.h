// The camera model shared by the z-buffer, the clipper and the ray caster (docs/architecture.md, Conventions).
//
// View space: the camera looks down -z, +y up, +x right; view depth d = -z_view > 0.
// Clip space (D3D-style depth range): x_c in [-w, w], y_c in [-w, w], z_c in [0, w], with
//   perspective:  x_c = x_v / (tanHalfY * aspect),  y_c = y_v / tanHalfY,  w = d,
//                 z_c = f (d - n) / (f - n)            (z_c >= 0 <=> d >= n;  z_c <= w <=> d <= f)
//   orthographic: x_c = x_v / (halfHeight * aspect),  y_c = y_v / halfHeight,  w = 1,
//                 z_c = (d - n) / (f - n)
// Raster: NDC (x_c/w, y_c/w) maps to pixels px = (x_n + 1) W / 2, py = (1 - y_n) H / 2;
// pixel (0,0) is top-left and pixel (x, y) is sampled at its center (x + 0.5, y + 0.5).
#pragma once

#include <string>

#include "render/math.h"

namespace va {

struct CameraSpec {
    Vec3 eye{0, 0, 5};
    Vec3 target{0, 0, 0};
    Vec3 up{0, 1, 0};
    bool orthographic = false;
    double fovYDegrees = 60;  // perspective: vertical field of view
    double orthoHeight = 10;  // orthographic: world-space height of the view
    double nearZ = 0.1, farZ = 1000;
    int width = 1920, height = 1080;
};

struct Camera {
    CameraSpec spec;
    Vec3 eye;
    Vec3 right, up, forward;  // orthonormal world-space basis; forward = view direction
    int width = 0, height = 0;
    double nearZ = 0, farZ = 0;
    bool orthographic = false;
    double sx = 1, sy = 1;  // view-to-NDC scales: 1/(tanHalfY*aspect), 1/tanHalfY (or ortho halves)
    Mat4 viewFromWorld;
    Mat4 clipFromView;
    Mat4 clipFromWorld;
};

// Builds the camera; returns false with a message when the spec cannot make one (eye == target,
// up parallel to the view direction, near <= 0, far <= near, fov outside (0, 180), empty or
// non-finite values). The message names the field and the fix, not the file (the caller adds that).
bool makeCamera(const CameraSpec &spec, Camera *cam, std::string *err);

// The view-space ray direction through pixel coordinates (px, py) (perspective: origin at the eye,
// direction with z = -1, so the ray parameter equals view depth; orthographic: the origin offset in
// the view plane, direction (0, 0, -1)).
struct ViewRay {
    Vec3 origin;     // view space
    Vec3 direction;  // view space, z = -1
};
ViewRay viewRayThroughPixel(const Camera &cam, double px, double py);

// Depth plane of a triangle: the view depth of the triangle's plane at pixel coordinates (px, py):
//   perspective:  1/d = a*px + b*py + c      orthographic:  d = a*px + b*py + c
// evaluated exactly as written ((a*px + b*py) + c, no FMA), which is the canonical per-fragment
// depth that the z-buffer, the audits and the tests all share. `valid` is false when the plane
// passes through the eye (perspective) or contains the view direction (orthographic): such a
// triangle is seen edge-on and covers no area.
struct DepthPlane {
    double a = 0, b = 0, c = 0;
    bool valid = false;
};
DepthPlane depthPlaneFromView(const Camera &cam, Vec3 v0, Vec3 v1, Vec3 v2);  // view-space vertices
// The same for many triangles of one camera: the pixel-to-view-plane constants (four divisions)
// computed once, the plane of each triangle inline; bit-identical to depthPlaneFromView.
struct DepthPlaneMaker {
    explicit DepthPlaneMaker(const Camera &cam)
        : orthographic(cam.orthographic), ax(2 / (double(cam.width) * cam.sx)), bx(-1 / cam.sx),
          ay(-2 / (double(cam.height) * cam.sy)), by(1 / cam.sy) {}
    DepthPlane operator()(Vec3 v0, Vec3 v1, Vec3 v2) const {
        const Vec3 n = cross(v1 - v0, v2 - v0);
        const double k = -dot(n, v0);
        DepthPlane p;
        if (orthographic) {
            if (!(n.z != 0) || !std::isfinite(k)) return p;
            p.a = n.x * ax / n.z;
            p.b = n.y * ay / n.z;
            p.c = (n.x * bx + n.y * by + k) / n.z;
        } else {
            if (!(k != 0) || !std::isfinite(k)) return p;
            p.a = -n.x * ax / k;
            p.b = -n.y * ay / k;
            p.c = -(n.x * bx + n.y * by - n.z) / k;
        }
        p.valid = std::isfinite(p.a) && std::isfinite(p.b) && std::isfinite(p.c);
        return p;
    }
    bool orthographic;
    double ax, bx, ay, by;  // x_n/sx = ax px + bx, y_n/sy = ay py + by
};
inline double evalDepthPlane(const DepthPlane &p, double px, double py) { return (p.a * px + p.b * py) + p.c; }
inline double viewDepthAt(const Camera &cam, const DepthPlane &p, double px, double py) {
    const double v = evalDepthPlane(p, px, py);
    return cam.orthographic ? v : 1.0 / v;
}

}  // namespace va
