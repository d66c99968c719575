#include "render/camera.h"

#include <cmath>

namespace va {

namespace {
// v / |v| for any finite non-zero v. |v|^2 overflows for components above ~1e154 and underflows
// below ~1e-154 (a valid direction would then read as infinite or zero): there only, v is first
// scaled by its largest component, so ordinary vectors keep their usual rounding.
Vec3 direction(Vec3 v) {
    const double l2 = dot(v, v);
    if (std::isnormal(l2)) return v / std::sqrt(l2);
    return normalize(v / maxAbs(v));
}
}  // namespace

bool makeCamera(const CameraSpec &s, Camera *cam, std::string *err) {
    auto fail = [&](const std::string &m) {
        if (err) *err = m;
        return false;
    };
    if (!isFinite(s.eye)) return fail("\"eye\" is not finite; give three finite numbers");
    if (!isFinite(s.target)) return fail("\"target\" is not finite; give three finite numbers");
    if (!isFinite(s.up)) return fail("\"up\" is not finite; give three finite numbers");
    if (!(std::isfinite(s.nearZ) && s.nearZ > 0))
        return fail("\"near\" must be > 0 (perspective depth is undefined at the eye); try 0.1");
    if (!(std::isfinite(s.farZ) && s.farZ > s.nearZ))
        return fail("\"far\" must be greater than \"near\"; try far = 1000 * near");
    if (s.orthographic) {
        if (!(std::isfinite(s.orthoHeight) && s.orthoHeight > 0))
            return fail("\"ortho_height\" must be > 0");
    } else if (!(std::isfinite(s.fovYDegrees) && s.fovYDegrees > 0 && s.fovYDegrees < 180)) {
        return fail("\"fov_y\" must be between 0 and 180 degrees (exclusive); try 60");
    }
    if (s.width <= 0 || s.height <= 0) return fail("\"width\" and \"height\" must be at least 1");

    const Vec3 fwd = s.target - s.eye;
    if (!isFinite(fwd))
        return fail("\"target\" - \"eye\" overflows a double; bring the camera and its target closer together");
    if (fwd == Vec3{0, 0, 0}) return fail("\"eye\" equals \"target\"; the view has no direction");
    const Vec3 f = direction(fwd);
    if (s.up == Vec3{0, 0, 0}) return fail("\"up\" has zero length; try [0, 1, 0]");
    Vec3 r = cross(f, direction(s.up));
    const double rl = length(r);
    // |f x u| is the sine of their angle: below ~1e-9 the basis is numerically meaningless.
    if (!(rl > 1e-9)) return fail("\"up\" is parallel to the view direction; choose another up vector");
    r = r / rl;
    const Vec3 u = cross(r, f);

    Camera c;
    c.spec = s;
    c.eye = s.eye;
    c.right = r;
    c.up = u;
    c.forward = f;
    c.width = s.width;
    c.height = s.height;
    c.nearZ = s.nearZ;
    c.farZ = s.farZ;
    c.orthographic = s.orthographic;
    const double aspect = double(s.width) / double(s.height);
    if (s.orthographic) {
        const double hh = s.orthoHeight * 0.5;
        c.sy = 1 / hh;
        c.sx = 1 / (hh * aspect);
    } else {
        const double t = std::tan(s.fovYDegrees * kPi / 360);
        c.sy = 1 / t;
        c.sx = 1 / (t * aspect);
    }
    // viewFromWorld: rows are the basis (right, up, -forward), then translate by -eye.
    Mat4 v;
    const Vec3 b = -f;
    v.m[0][0] = r.x; v.m[0][1] = r.y; v.m[0][2] = r.z; v.m[0][3] = -dot(r, s.eye);
    v.m[1][0] = u.x; v.m[1][1] = u.y; v.m[1][2] = u.z; v.m[1][3] = -dot(u, s.eye);
    v.m[2][0] = b.x; v.m[2][1] = b.y; v.m[2][2] = b.z; v.m[2][3] = -dot(b, s.eye);
    c.viewFromWorld = v;
    Mat4 p;
    const double n = s.nearZ, fa = s.farZ;
    p.m[0][0] = c.sx;
    p.m[1][1] = c.sy;
    if (s.orthographic) {
        // z_c = (d - n)/(f - n) with d = -z_v
        p.m[2][2] = -1 / (fa - n);
        p.m[2][3] = -n / (fa - n);
        p.m[3][3] = 1;
    } else {
        // z_c = f (d - n)/(f - n), w = d = -z_v
        p.m[2][2] = -fa / (fa - n);
        p.m[2][3] = -fa * n / (fa - n);
        p.m[3][2] = -1;
        p.m[3][3] = 0;
    }
    c.clipFromView = p;
    c.clipFromWorld = p * v;
    *cam = c;
    return true;
}

ViewRay viewRayThroughPixel(const Camera &cam, double px, double py) {
    const double xn = 2 * px / cam.width - 1;
    const double yn = 1 - 2 * py / cam.height;
    if (cam.orthographic) return {{xn / cam.sx, yn / cam.sy, 0}, {0, 0, -1}};
    return {{0, 0, 0}, {xn / cam.sx, yn / cam.sy, -1}};
}

// Derivation. A view-space point on the ray through (px, py) is p = o + t*r with r.z = -1, so t is
// the view depth d (o.z = 0). With x_n = 2 px / W - 1 and y_n = 1 - 2 py / H:
//   perspective: r = (x_n/sx, y_n/sy, -1), o = 0. The plane n.p + k = 0 gives d = -k / (n.r), so
//     1/d = -(n.r)/k = -(nx x_n/sx + ny y_n/sy - nz)/k, which is affine in (px, py).
//   orthographic: o = (x_n/sx, y_n/sy, 0), r = (0,0,-1): n.o - nz d + k = 0, so
//     d = (nx x_n/sx + ny y_n/sy + k)/nz, affine in (px, py).
DepthPlane depthPlaneFromView(const Camera &cam, Vec3 v0, Vec3 v1, Vec3 v2) {
    // x_n/sx = (2/W px - 1)/sx; y_n/sy = (1 - 2/H py)/sy (DepthPlaneMaker, camera.h).
    return DepthPlaneMaker(cam)(v0, v1, v2);
}

}  // namespace va
