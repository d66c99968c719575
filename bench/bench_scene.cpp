#include "bench/bench_scene.h"

#include <cmath>

namespace va {

namespace {

// One UV sphere appended to m. Vertex layout: north pole, rings 1..B-1 of S vertices each (ring k
// at polar angle theta_k = pi k / B from +y), south pole. Bands 0 and B-1 are fans around the
// poles (S triangles each, never a collapsed quad); bands 1..B-2 are quads split in two.
// Winding: with phi increasing from +x toward -z (counter-clockwise seen from +y), the triangle
// (upper ring phi_s, lower ring phi_s, lower ring phi_s+1) is counter-clockwise seen from outside.
void appendSphere(RawMesh &m, Vec3 center, double radius, int S, int B) {
    const uint32_t base = uint32_t(m.positions.size());
    m.positions.push_back(center + Vec3(0, radius, 0));
    for (int k = 1; k < B; ++k) {
        const double theta = kPi * k / B;
        const double st = std::sin(theta), ct = std::cos(theta);
        for (int s = 0; s < S; ++s) {
            const double phi = 2 * kPi * s / S;
            m.positions.push_back(center + Vec3(radius * st * std::cos(phi), radius * ct, -radius * st * std::sin(phi)));
        }
    }
    m.positions.push_back(center + Vec3(0, -radius, 0));
    const uint32_t north = base, south = base + 1 + uint32_t((B - 1) * S);
    auto ring = [&](int k, int s) { return base + 1 + uint32_t((k - 1) * S + (s % S)); };  // k in 1..B-1
    auto tri = [&](uint32_t a, uint32_t b, uint32_t c) {
        m.indices.push_back(a);
        m.indices.push_back(b);
        m.indices.push_back(c);
        ++m.facesRead;
    };
    for (int s = 0; s < S; ++s) tri(north, ring(1, s), ring(1, s + 1));
    for (int k = 1; k < B - 1; ++k)
        for (int s = 0; s < S; ++s) {
            tri(ring(k, s), ring(k + 1, s), ring(k + 1, s + 1));
            tri(ring(k, s), ring(k + 1, s + 1), ring(k, s + 1));
        }
    for (int s = 0; s < S; ++s) tri(ring(B - 1, s), south, ring(B - 1, s + 1));
}

}  // namespace

RawMesh sphereGridMesh() { return sphereGridMesh(kBenchSphereSegments, kBenchSphereBands); }

RawMesh sphereGridMesh(int S, int B) {
    RawMesh m;
    m.positions.reserve(size_t(kBenchSphereGrid) * kBenchSphereGrid * (size_t((B - 1) * S) + 2) + 4);
    m.indices.reserve(3 * (size_t(kBenchSphereGrid) * kBenchSphereGrid * 2 * S * (B - 1) + 2));
    for (int i = 0; i < kBenchSphereGrid; ++i)
        for (int j = 0; j < kBenchSphereGrid; ++j)
            appendSphere(m, Vec3(kBenchSphereSpacing * i, 0, kBenchSphereSpacing * j), 1.0, S, B);

    // Ground: the grid spans [-1, 23.5] in x and z; the quad extends 10 units past it on every side.
    // Seen from above (+y), (lo,lo) -> (lo,hi) -> (hi,hi) is counter-clockwise: with x right, the
    // +z axis points down the page when looking down -y, so increasing z first turns left.
    const double lo = -11, hi = 33.5, y = -1;
    const uint32_t g = uint32_t(m.positions.size());
    m.positions.push_back(Vec3(lo, y, lo));
    m.positions.push_back(Vec3(lo, y, hi));
    m.positions.push_back(Vec3(hi, y, hi));
    m.positions.push_back(Vec3(hi, y, lo));
    for (uint32_t idx : {g, g + 1, g + 2, g, g + 2, g + 3}) m.indices.push_back(idx);
    m.facesRead += 2;
    return m;
}

CameraSpec benchmarkCamera() {
    CameraSpec c;
    c.eye = Vec3(11.25, 13, -9);
    c.target = Vec3(11.25, -1, 10.5);
    c.up = Vec3(0, 1, 0);
    c.orthographic = false;
    c.fovYDegrees = 55;
    c.width = 1920;
    c.height = 1080;
    c.nearZ = 0.5;
    c.farZ = 200;
    return c;
}

}  // namespace va
