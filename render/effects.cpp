#include "render/effects.h"

#include <algorithm>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "render/stopwatch.h"

namespace va {

namespace {

// Float rounding: Embree intersects in single precision.
constexpr double kFloatEps = 0x1p-24;  // unit roundoff of float (half an ulp of 1)
constexpr double gammaF(int n) { return (n * kFloatEps) / (1 - n * kFloatEps); }

Vec3 toVec(const float a[3]) { return {a[0], a[1], a[2]}; }
Vec3 vabs(Vec3 a) { return {std::fabs(a.x), std::fabs(a.y), std::fabs(a.z)}; }

// The end of a shadow ray towards a point light: o + t d with d = light - o reaches the light at t = 1.
// Embree's computed t for a surface through the light carries a relative error of a few float
// roundings (Pluecker T and den: differences, an FMA cross product, two dot products, a refined
// reciprocal: fewer than 16 roundings), and d itself is rounded to float (one more). Ending at
// 1 - gamma(16), rounded down, keeps a surface containing the light from shadowing it; an occluder
// closer to the light than that fraction of the distance is not seen (docs/effects.md).
const float kShadowTfar = std::nextafter(float(1 - gammaF(16)), 0.0f);

}  // namespace

double fresnelDielectric(double cosI, double etaI, double etaT) {
    // Snell: sinT = etaI / etaT * sinI. No transmitted direction when sinT >= 1 (TIR).
    cosI = std::clamp(cosI, 0.0, 1.0);
    const double sinI = std::sqrt(std::max(0.0, 1 - cosI * cosI));
    const double sinT = etaI / etaT * sinI;
    if (sinT >= 1) return 1;
    const double cosT = std::sqrt(std::max(0.0, 1 - sinT * sinT));
    // Fresnel equations for the parallel and perpendicular polarizations; unpolarized light is their mean.
    const double rParl = (etaT * cosI - etaI * cosT) / (etaT * cosI + etaI * cosT);
    const double rPerp = (etaI * cosI - etaT * cosT) / (etaI * cosI + etaT * cosT);
    return (rParl * rParl + rPerp * rPerp) / 2;
}

SurfacePoint surfacePoint(const RayScene &scene, uint32_t prim, float u, float v) {
    SurfacePoint sp;
    sp.prim = prim;
    float f[9];
    scene.vertices(prim, f);
    const Vec3 p0 = toVec(f), p1 = toVec(f + 3), p2 = toVec(f + 6);

    // Hit point from barycentrics, in double from Embree's float vertices (pbrt-v3, 3.9.4):
    // p = b0 p0 + b1 p1 + b2 p2. b0 = 1 - u - v is exact to one double rounding, so p lies on the
    // triangle's plane up to the rounding of this sum: per component at most
    //   gamma_d(5) * (|b0 p0| + |b1 p1| + |b2 p2|)      (two roundings of b0, three of the sum).
    const double b1 = u, b2 = v, b0 = 1.0 - b1 - b2;
    sp.p = p0 * b0 + p1 * b1 + p2 * b2;
    const Vec3 pErr = (vabs(p0 * b0) + vabs(p1 * b1) + vabs(p2 * b2)) * gamma(5);

    const Vec3 ng = cross(p1 - p0, p2 - p0);  // (v1 - v0) x (v2 - v0): Embree's Ng orientation
    const double ngLen = length(ng);
    sp.n = ngLen > 0 ? ng / ngLen : Vec3{0, 0, 1};

    // (1) pbrt's offset: the hit point's error box projected on the normal.
    const double dPoint = dot(vabs(sp.n), pErr);

    // (2) Embree's own float arithmetic. For a ray from O, Embree's Pluecker test computes in float
    // w_i = p_i - O (one rounding each), edges e = w_a - w_b, Ng = an FMA cross product of two edges,
    // and T = 2 w0 . Ng, whose sign decides on which side of the plane O lies (the hit needs
    // T / den >= tnear = 0). With W = max_i |p_i - p|_inf (so |w0|_1 <= 3W, O being p plus a tiny
    // offset) and E = the longest edge's |e|_inf, the rounding errors add up to
    //   |dT| <= gamma_f(12) |w0|_1 (|Ng|_inf + 6 E^2),
    // while the exact T = |Ng| dist(O, plane). T keeps its sign when
    //   dist > gamma_f(12) * 3W * (1 + 6 E^2 / |Ng|),
    // which scales with the triangle's size around the hit point and its shape (slivers need more).
    double W = 0, E = 0;
    for (const Vec3 &q : {p0, p1, p2}) W = std::max(W, maxAbs(q - sp.p));
    for (const Vec3 &e : {p1 - p0, p2 - p1, p0 - p2}) E = std::max(E, maxAbs(e));
    const double dEmbree = ngLen > 0 ? gammaF(12) * 3 * W * (1 + 6 * E * E / ngLen) : 0;

    sp.offset = dPoint + dEmbree;
    return sp;
}

void offsetRayOrigin(const SurfacePoint &sp, Vec3 dir, float org[3]) {
    // Leave on the side dir points to; a direction in the plane leaves on the front side.
    const double side = dot(dir, sp.n) < 0 ? -1.0 : 1.0;
    const Vec3 o = sp.p + sp.n * (side * sp.offset);
    // Round each coordinate away from the surface (pbrt's NextFloatUp/Down after the offset): the
    // float origin is then at least as far from the plane as o.
    for (int a = 0; a < 3; ++a) {
        const double away = side * sp.n[a];
        float f = float(o[a]);
        if (away > 0 && double(f) < o[a]) f = std::nextafter(f, INFINITY);
        if (away < 0 && double(f) > o[a]) f = std::nextafter(f, -INFINITY);
        org[a] = f;
    }
}

namespace {

// What one row of pixels found; rows are reduced in order, so sums do not depend on the schedule.
struct RowTally {
    EffectsStats s;
    std::vector<LightShadowStats> lights;
};

struct Tracer {
    const RayScene &scene;
    const EffectsInput &in;
    const SurfaceMaterial kDefault{};

    const SurfaceMaterial &materialOf(uint32_t prim) const {
        if (in.materials.empty() || in.triangleMaterial.empty()) return kDefault;
        return in.materials[in.triangleMaterial[scene.sourceOf(prim)]];
    }

    struct Pending {  // a secondary ray waiting to be traced
        float org[3];
        Vec3 dir;
        int depth;
        double weight;
        bool refraction;
    };

    // The rays a hit at `sp` calls for, arriving along `d` (unit) with throughput `w`; the new rays
    // have depth `depth`. Rays beyond maxDepth are counted, not traced.
    void spawn(const SurfacePoint &sp, Vec3 d, int depth, double w, std::vector<Pending> &stack, EffectsStats &s) const {
        const SurfaceMaterial &m = materialOf(sp.prim);
        const bool reflective = in.reflections && m.reflective > 0;
        const bool refractive = in.refractions && m.ior != 1;
        if (!reflective && !refractive) return;
        double wRefl = 0, wRefr = 0;
        Vec3 refrDir;
        if (refractive) {
            // Entering through the front (d . n < 0) goes from air (1) into the material (ior);
            // through the back, from the material out into air.
            const double cosD = dot(d, sp.n);
            const bool entering = cosD < 0;
            const double etaI = entering ? 1.0 : m.ior, etaT = entering ? m.ior : 1.0;
            const Vec3 nIn = entering ? sp.n : -sp.n;  // normal on the incoming side
            const double cosI = std::fabs(cosD);
            const double F = fresnelDielectric(cosI, etaI, etaT);
            if (F >= 1) {
                ++s.totalInternalReflections;
            } else {
                // Snell's law in vector form (pbrt's Refract): t = eta d + (eta cosI - cosT) nIn.
                const double eta = etaI / etaT;
                const double sin2T = eta * eta * std::max(0.0, 1 - cosI * cosI);
                const double cosT = std::sqrt(1 - sin2T);
                refrDir = normalize(d * eta + nIn * (eta * cosI - cosT));
                wRefr = 1 - F;
            }
            wRefl = F;
        }
        // A mirror's reflectance and a dielectric's Fresnel reflectance combine as layers: the mirror
        // reflects R, the rest meets the interface.
        if (reflective) {
            const double R = m.reflective;
            wRefl = refractive ? R + (1 - R) * wRefl : R;
            wRefr = (1 - R) * wRefr;
        }
        const bool wantRefl = wRefl > 0, wantRefr = wRefr > 0;
        if (depth > in.maxDepth) {
            s.terminatedByDepth += uint64_t(wantRefl) + uint64_t(wantRefr);
            return;
        }
        if (wantRefl) {
            Pending p;
            p.dir = normalize(d - sp.n * (2 * dot(d, sp.n)));
            offsetRayOrigin(sp, p.dir, p.org);
            p.depth = depth;
            p.weight = w * wRefl;
            p.refraction = false;
            stack.push_back(p);
        }
        if (wantRefr) {
            Pending p;
            p.dir = refrDir;
            offsetRayOrigin(sp, p.dir, p.org);
            p.depth = depth;
            p.weight = w * wRefr;
            p.refraction = true;
            stack.push_back(p);
        }
    }

    // Everything of one row.
    void row(int y, const Camera &cam, const RaycastImage &primary, EffectsResult &out, RowTally &t,
             const std::vector<Vec3> &lightDir, const std::vector<Vec3> &lightPos) const {
        std::vector<Pending> stack;
        const size_t nl = in.lights.size();
        for (int x = 0; x < primary.width; ++x) {
            const size_t px = size_t(y) * primary.width + x;
            ++t.s.primaryRays;
            if (primary.id[px] == 0) continue;
            ++t.s.primaryHits;
            const uint32_t prim = scene.primitiveOf(primary.id[px] - 1);
            const SurfacePoint sp = surfacePoint(scene, prim, primary.u[px], primary.v[px]);
            const LocalRay pr = scene.primaryRay(cam, x, y);
            const Vec3 d0 = normalize(toVec(pr.dir));
            // The side of the surface the viewer is on (+1: front).
            const double viewSide = dot(d0, sp.n) < 0 ? 1.0 : -1.0;

            // Shadow rays, one per light, from the visible side.
            if (in.shadows)
                for (size_t l = 0; l < nl; ++l) {
                    LightShadowStats &ls = t.lights[l];
                    LocalRay r;
                    Vec3 towards;
                    bool facing;
                    if (in.lights[l].directional) {
                        towards = lightDir[l];
                        facing = viewSide * dot(sp.n, towards) > 0;
                    } else {
                        towards = lightPos[l] - sp.p;
                        // A light closer to the plane than the point's own error bound is in the plane.
                        facing = viewSide * dot(sp.n, towards) > sp.offset;
                    }
                    if (!facing) {
                        ++ls.facingAwayPixels;
                        continue;
                    }
                    offsetRayOrigin(sp, towards, r.org);
                    if (in.lights[l].directional) {
                        for (int a = 0; a < 3; ++a) r.dir[a] = float(towards[a]);
                        r.tfar = INFINITY;
                    } else {
                        for (int a = 0; a < 3; ++a) r.dir[a] = float(lightPos[l][a] - double(r.org[a]));
                        r.tfar = kShadowTfar;
                    }
                    r.tnear = 0;
                    ++ls.shadowRays;
                    ++t.s.shadowRays;
                    if (scene.occluded(r)) {
                        ++ls.shadowedPixels;
                        out.shadowMask[l][size_t(y) * out.maskStride + size_t(x >> 6)] |= uint64_t(1) << (x & 63);
                    } else {
                        ++ls.litPixels;
                    }
                }

            // Reflection and refraction, depth first, bounded by maxDepth.
            stack.clear();
            spawn(sp, d0, 1, 1.0, stack, t.s);
            int deepest = 0;
            unsigned rays = 0;
            while (!stack.empty()) {
                const Pending p = stack.back();
                stack.pop_back();
                ++rays;
                deepest = std::max(deepest, p.depth);
                if (p.refraction) {
                    ++t.s.refractionRays;
                    t.s.refractionWeight += p.weight;
                } else {
                    ++t.s.reflectionRays;
                    t.s.reflectionWeight += p.weight;
                }
                LocalRay r;
                std::copy(p.org, p.org + 3, r.org);
                for (int a = 0; a < 3; ++a) r.dir[a] = float(p.dir[a]);
                r.tnear = 0;
                r.tfar = INFINITY;
                const LocalHit h = scene.intersect(r);
                if (h.prim == kNoHit) continue;
                ++t.s.secondaryHits;
                spawn(surfacePoint(scene, h.prim, h.u, h.v), p.dir, p.depth + 1, p.weight, stack, t.s);
            }
            out.secondaryDepth[px] = uint8_t(deepest);
            out.secondaryRays[px] = uint16_t(std::min(rays, 65535u));
            t.s.deepest = std::max(t.s.deepest, deepest);
        }
    }
};

}  // namespace

EffectsResult traceEffects(const RayScene &scene, const Camera &cam, const RaycastImage &primary,
                           const EffectsInput &in) {
    const Stopwatch t0;
    EffectsResult out;
    auto fail = [&](std::string msg) {
        out.ok = false;
        out.error = std::move(msg);
        return out;
    };
    // Input checks: what a caller can get wrong.
    const size_t npx = size_t(primary.width) * size_t(primary.height);
    if (primary.width != cam.width || primary.height != cam.height || primary.id.size() != npx)
        return fail("effects: the primary image (" + std::to_string(primary.width) + "x" +
                    std::to_string(primary.height) + ") does not match the camera (" + std::to_string(cam.width) +
                    "x" + std::to_string(cam.height) + ")");
    if (primary.u.size() != npx || primary.v.size() != npx)
        return fail("effects: the primary image has no barycentrics; cast it with PrimaryOptions::keepBarycentrics");
    if (in.maxDepth < 0 || in.maxDepth > 255)
        return fail("effects: maximum depth " + std::to_string(in.maxDepth) + " is outside 0..255");
    if (!in.materials.empty() || !in.triangleMaterial.empty()) {
        for (size_t k = 0; k < scene.primitiveCount(); ++k) {
            const uint32_t src = scene.sourceOf(uint32_t(k));
            if (src >= in.triangleMaterial.size())
                return fail("effects: no material for triangle " + std::to_string(src) + " (triangleMaterial has " +
                            std::to_string(in.triangleMaterial.size()) + " entries)");
            if (in.triangleMaterial[src] >= in.materials.size())
                return fail("effects: triangle " + std::to_string(src) + " names material " +
                            std::to_string(in.triangleMaterial[src]) + "; the table has " +
                            std::to_string(in.materials.size()));
        }
        for (size_t i = 0; i < in.materials.size(); ++i)
            if (!(in.materials[i].ior > 0) || !std::isfinite(in.materials[i].ior))
                return fail("effects: material " + std::to_string(i) + " has ior " +
                            std::to_string(in.materials[i].ior) + "; it must be a finite number > 0");
    }
    // Lights in the float frame: unit directions towards directional lights, positions of point lights.
    const size_t nl = in.lights.size();
    std::vector<Vec3> lightDir(nl), lightPos(nl);
    for (size_t l = 0; l < nl; ++l) {
        const EffectLight &L = in.lights[l];
        if (L.directional) {
            if (!isFinite(L.direction) || length(L.direction) == 0)
                return fail("effects: light '" + L.name + "' has no direction (zero or not finite)");
            lightDir[l] = -normalize(L.direction);
        } else {
            if (!isFinite(L.position)) return fail("effects: light '" + L.name + "' has a non-finite position");
            lightPos[l] = L.position - scene.origin();
        }
    }

    out.width = primary.width;
    out.height = primary.height;
    out.maskStride = (size_t(primary.width) + 63) / 64;
    out.shadowMask.assign(nl, std::vector<uint64_t>(out.maskStride * size_t(primary.height), 0));
    out.secondaryDepth.assign(npx, 0);
    out.secondaryRays.assign(npx, 0);

    std::vector<RowTally> rows(size_t(primary.height));
    for (RowTally &r : rows) {
        r.lights.resize(nl);
    }
    const Tracer tracer{scene, in};
    tbb::parallel_for(tbb::blocked_range<int>(0, primary.height), [&](const tbb::blocked_range<int> &range) {
        for (int y = range.begin(); y < range.end(); ++y)
            tracer.row(y, cam, primary, out, rows[size_t(y)], lightDir, lightPos);
    });

    // Reduce in row order (the double sums then do not depend on the thread count).
    EffectsStats &s = out.stats;
    out.lights.resize(nl);
    for (size_t l = 0; l < nl; ++l) out.lights[l].name = in.lights[l].name;
    for (const RowTally &r : rows) {
        s.primaryRays += r.s.primaryRays;
        s.primaryHits += r.s.primaryHits;
        s.shadowRays += r.s.shadowRays;
        s.reflectionRays += r.s.reflectionRays;
        s.refractionRays += r.s.refractionRays;
        s.secondaryHits += r.s.secondaryHits;
        s.totalInternalReflections += r.s.totalInternalReflections;
        s.terminatedByDepth += r.s.terminatedByDepth;
        s.deepest = std::max(s.deepest, r.s.deepest);
        s.reflectionWeight += r.s.reflectionWeight;
        s.refractionWeight += r.s.refractionWeight;
        for (size_t l = 0; l < nl; ++l) {
            out.lights[l].shadowRays += r.lights[l].shadowRays;
            out.lights[l].litPixels += r.lights[l].litPixels;
            out.lights[l].shadowedPixels += r.lights[l].shadowedPixels;
            out.lights[l].facingAwayPixels += r.lights[l].facingAwayPixels;
        }
    }
    s.ms = t0.ms();
    return out;
}

}  // namespace va
