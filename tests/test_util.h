// Small scene builders shared by the tests.
#pragma once

#include <array>
#include <cstring>
#include <string>
#include <vector>

#include "analysis/scene.h"
#include "render/camera.h"
#include "render/raster.h"

namespace va::testing_util {

// One source object per mesh, named "o0", "o1", ...; matOf[i] picks mesh i's material (default 0).
inline Scene sceneOf(std::vector<RawMesh> meshes, std::vector<Material> mats = {Material{}},
                     std::vector<uint32_t> matOf = {}) {
    SceneBuildInput in;
    in.materials = std::move(mats);
    for (size_t i = 0; i < meshes.size(); ++i) {
        SceneBuildInput::Object o;
        o.name = "o" + std::to_string(i);
        o.material = i < matOf.size() ? matOf[i] : 0;
        o.geometry = std::move(meshes[i]);
        in.objects.push_back(std::move(o));
    }
    return buildScene(std::move(in));
}

inline RawMesh triangleMesh(Vec3 a, Vec3 b, Vec3 c) {
    RawMesh m;
    m.positions = {a, b, c};
    m.indices = {0, 1, 2};
    m.facesRead = 1;
    return m;
}

// A perspective view named "v" from `eye` towards `target` (up +y).
inline ViewSpec viewOf(Vec3 eye, Vec3 target, int w = 64, int h = 48, double fov = 60, double nearZ = 0.1,
                       double farZ = 100) {
    ViewSpec v;
    v.name = "v";
    v.camera.eye = eye;
    v.camera.target = target;
    v.camera.fovYDegrees = fov;
    v.camera.nearZ = nearZ;
    v.camera.farZ = farZ;
    v.camera.width = w;
    v.camera.height = h;
    return v;
}

// Loose triangles, one object each, named "t0", "t1", ...; one material.
inline Scene looseTriangles(const std::vector<std::array<Vec3, 3>> &tris, bool doubleSided = false) {
    SceneBuildInput in;
    Material m;
    m.doubleSided = doubleSided;
    in.materials = {m};
    for (size_t i = 0; i < tris.size(); ++i) {
        SceneBuildInput::Object o;
        o.name = "t";
        o.name += std::to_string(i);  // not "t" + ...: a GCC 12 -Wrestrict false positive where inlined
        o.geometry.positions = {tris[i][0], tris[i][1], tris[i][2]};
        o.geometry.indices = {0, 1, 2};
        in.objects.push_back(std::move(o));
    }
    return buildScene(std::move(in));
}

// The first difference between two clip outputs, bit for bit (corners, sources, plane indices,
// every plane's three doubles and validity); empty when they are identical.
inline std::string screenTrianglesDifference(const ScreenTriangles &a, const ScreenTriangles &b) {
    if (a.xy != b.xy) return "corners (xy)";
    if (a.source != b.source) return "sources";
    if (a.plane != b.plane) return "plane indices";
    if (a.planes.size() != b.planes.size()) return "plane count";
    for (size_t i = 0; i < a.planes.size(); ++i) {
        const DepthPlane &p = a.planes[i], &q = b.planes[i];
        if (std::memcmp(&p.a, &q.a, 8) != 0 || std::memcmp(&p.b, &q.b, 8) != 0 || std::memcmp(&p.c, &q.c, 8) != 0 ||
            p.valid != q.valid)
            return "plane " + std::to_string(i);
    }
    return "";
}

// A camera from its eye, target, size and projection (perspective: 60 degrees; orthographic: 6
// units high), near 0.5 and far 40; false when makeCamera refuses it.
inline bool smallCamera(Vec3 eye, Vec3 target, int w, int h, bool orthographic, Camera *cam, std::string *err) {
    CameraSpec spec;
    spec.eye = eye;
    spec.target = target;
    spec.width = w, spec.height = h, spec.nearZ = 0.5, spec.farZ = 40;
    spec.orthographic = orthographic, spec.orthoHeight = 6;
    return makeCamera(spec, cam, err);
}

}  // namespace va::testing_util
