#include "render/math.h"

namespace va {

Mat4 Mat4::translate(Vec3 t) {
    Mat4 r;
    r.m[0][3] = t.x;
    r.m[1][3] = t.y;
    r.m[2][3] = t.z;
    return r;
}

Mat4 Mat4::scale(Vec3 s) {
    Mat4 r;
    r.m[0][0] = s.x;
    r.m[1][1] = s.y;
    r.m[2][2] = s.z;
    return r;
}

Mat4 Mat4::rotateXYZDegrees(Vec3 deg) {
    const double rx = deg.x * kPi / 180, ry = deg.y * kPi / 180, rz = deg.z * kPi / 180;
    Mat4 x, y, z;
    x.m[1][1] = std::cos(rx); x.m[1][2] = -std::sin(rx);
    x.m[2][1] = std::sin(rx); x.m[2][2] = std::cos(rx);
    y.m[0][0] = std::cos(ry); y.m[0][2] = std::sin(ry);
    y.m[2][0] = -std::sin(ry); y.m[2][2] = std::cos(ry);
    z.m[0][0] = std::cos(rz); z.m[0][1] = -std::sin(rz);
    z.m[1][0] = std::sin(rz); z.m[1][1] = std::cos(rz);
    return z * y * x;
}

Mat4 operator*(const Mat4 &a, const Mat4 &b) {
    Mat4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
            double s = 0;
            for (int k = 0; k < 4; ++k) s += a.m[i][k] * b.m[k][j];
            r.m[i][j] = s;
        }
    return r;
}

Mat4 transpose(const Mat4 &a) {
    Mat4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) r.m[i][j] = a.m[j][i];
    return r;
}

// Gauss-Jordan elimination with partial pivoting.
Mat4 inverse(const Mat4 &a, bool *ok) {
    double t[4][8];
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
            t[i][j] = a.m[i][j];
            t[i][j + 4] = i == j ? 1 : 0;
        }
    for (int c = 0; c < 4; ++c) {
        int p = c;
        for (int r = c + 1; r < 4; ++r)
            if (std::fabs(t[r][c]) > std::fabs(t[p][c])) p = r;
        if (t[p][c] == 0) {
            if (ok) *ok = false;
            return Mat4{};
        }
        if (p != c)
            for (int j = 0; j < 8; ++j) std::swap(t[p][j], t[c][j]);
        const double inv = 1 / t[c][c];
        for (int j = 0; j < 8; ++j) t[c][j] *= inv;
        for (int r = 0; r < 4; ++r) {
            if (r == c) continue;
            const double f = t[r][c];
            if (f != 0)
                for (int j = 0; j < 8; ++j) t[r][j] -= f * t[c][j];
        }
    }
    Mat4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) r.m[i][j] = t[i][j + 4];
    if (ok) *ok = true;
    return r;
}

}  // namespace va
