#include "analysis/load/demo.h"

#include <cmath>

namespace va {

RawMesh boxMesh(Vec3 c, Vec3 h) {
    RawMesh m;
    for (int i = 0; i < 8; ++i)
        m.positions.push_back({c.x + (i & 1 ? h.x : -h.x), c.y + (i & 2 ? h.y : -h.y), c.z + (i & 4 ? h.z : -h.z)});
    // Faces as quads (CCW from outside), each split along its first diagonal.
    const uint32_t q[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
    for (const auto &f : q) {
        m.indices.insert(m.indices.end(), {f[0], f[1], f[2], f[0], f[2], f[3]});
        m.facesRead += 1;
        m.polygonsTriangulated += 1;
    }
    return m;
}

RawMesh uvSphereMesh(Vec3 c, double r, int segments, int bands) {
    RawMesh m;
    // Rings 1..bands-1 of `segments` vertices, plus the two poles.
    m.positions.push_back({c.x, c.y + r, c.z});  // north pole: index 0
    for (int b = 1; b < bands; ++b) {
        const double th = kPi * b / bands;
        for (int s = 0; s < segments; ++s) {
            const double ph = 2 * kPi * s / segments;
            m.positions.push_back({c.x + r * std::sin(th) * std::cos(ph), c.y + r * std::cos(th),
                                   c.z - r * std::sin(th) * std::sin(ph)});
        }
    }
    const uint32_t south = uint32_t(m.positions.size());
    m.positions.push_back({c.x, c.y - r, c.z});
    auto ring = [&](int b, int s) { return uint32_t(1 + (b - 1) * segments + (s % segments)); };
    for (int s = 0; s < segments; ++s) m.indices.insert(m.indices.end(), {0u, ring(1, s), ring(1, s + 1)});
    for (int b = 1; b < bands - 1; ++b)
        for (int s = 0; s < segments; ++s) {
            const uint32_t a = ring(b, s), bb = ring(b + 1, s), cc = ring(b + 1, s + 1), d = ring(b, s + 1);
            m.indices.insert(m.indices.end(), {a, bb, cc, a, cc, d});
        }
    for (int s = 0; s < segments; ++s)
        m.indices.insert(m.indices.end(), {ring(bands - 1, s), south, ring(bands - 1, s + 1)});
    m.facesRead = m.indices.size() / 3;
    return m;
}

RawMesh gridMesh(Vec3 o, Vec3 u, Vec3 v, int w, int h) {
    RawMesh m;
    for (int j = 0; j <= h; ++j)
        for (int i = 0; i <= w; ++i) m.positions.push_back(o + u * (double(i) / w) + v * (double(j) / h));
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) {
            const uint32_t a = uint32_t(j * (w + 1) + i), b = a + 1, c = a + uint32_t(w + 1) + 1, d = a + uint32_t(w + 1);
            m.indices.insert(m.indices.end(), {a, b, c, a, c, d});
        }
    m.facesRead = m.indices.size() / 3;
    return m;
}

SceneBuildInput demoSceneInput() {
    SceneBuildInput in;
    in.path = "(built-in demo)";
    in.up = 'y';
    Material def;
    Material banner;
    banner.name = "banner";
    banner.doubleSided = true;
    Material decal;
    decal.name = "decal";
    in.materials = {def, banner, decal};

    auto add = [&](const char *name, RawMesh m, uint32_t material = 0) {
        SceneBuildInput::Object o;
        o.name = name;
        o.mesh = "(generated)";
        o.material = material;
        o.geometry = std::move(m);
        in.objects.push_back(std::move(o));
    };
    // Floor y = 0, 40 x 40 units in 32 x 32 quads, facing up (u = +x, v = -z: u x v = +y).
    add("floor", gridMesh({-20, 0, 20}, {40, 0, 0}, {0, 0, -40}, 32, 32));
    // A decal exactly on the floor's plane: coplanar, it fights the floor in every depth format.
    add("decal", gridMesh({-1, 0, 5}, {2, 0, 0}, {0, 0, -2}, 1, 1), 2);
    add("crate", boxMesh({-3, 0.5, 2}, {0.5, 0.5, 0.5}));
    add("ball", uvSphereMesh({0, 1, 0}, 1, 48, 24));
    // A banner facing away from the spawn view (front towards -z): drawn only because it is double-sided.
    add("banner", gridMesh({4, 0.5, 0}, {-2, 0, 0}, {0, 2, 0}, 2, 2), 1);
    // A long wall beside the spawn camera, from in front of it to behind it: crosses the near plane.
    add("wall", boxMesh({1.6, 1.5, 9}, {0.1, 1.5, 5}));
    add("behind", boxMesh({0, 1, 18}, {1, 1, 1}));    // behind the spawn camera
    add("offscreen", boxMesh({40, 1, 0}, {1, 1, 1})); // far to the right of every view
    add("pillar", uvSphereMesh({-6, 2, -6}, 2, 64, 32));

    auto view = [&](const char *name, Vec3 eye, Vec3 target) {
        ViewSpec v;
        v.name = name;
        v.camera.eye = eye;
        v.camera.target = target;
        v.camera.up = {0, 1, 0};
        v.camera.fovYDegrees = 60;
        v.camera.nearZ = 0.1;
        v.camera.farZ = 200;
        v.camera.width = 960;
        v.camera.height = 540;
        v.depthFormat = DepthFormat::f32;
        v.origin = "demo";
        in.views.push_back(v);
    };
    view("spawn", {0, 1.7, 12}, {0, 1, 0});
    view("overview", {14, 9, 14}, {0, 0, 0});
    return in;
}

Scene demoScene() { return buildScene(demoSceneInput()); }

}  // namespace va
