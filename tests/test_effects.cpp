// Secondary rays (render/effects.h), the effects planner (analysis/effects_plan.h) and the glTF
// mapping of KHR_lights_punctual: exact counts on analytic scenes, the Reintersect property over wide
// magnitudes, hard cases (a point light on a surface, mirror facing mirror, total internal reflection)
// and determinism across thread counts.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>

#include <tbb/global_control.h>

#include "analysis/load/demo.h"
#include "analysis/effects_plan.h"
#include "analysis/load/load.h"
#include "render/effects.h"

using namespace va;

namespace {

struct Obj {
    RawMesh mesh;
    uint32_t material = 0;
};

Scene sceneOf(std::vector<Obj> objs, std::vector<Material> mats = {Material{}}, std::vector<Light> lights = {}) {
    SceneBuildInput in;
    in.materials = std::move(mats);
    in.lights = std::move(lights);
    for (size_t i = 0; i < objs.size(); ++i) {
        SceneBuildInput::Object o;
        o.name = "o" + std::to_string(i);
        o.material = objs[i].material;
        o.geometry = std::move(objs[i].mesh);
        in.objects.push_back(std::move(o));
    }
    return buildScene(std::move(in));
}

std::unique_ptr<RayScene> rayScene(const Scene &s) {
    std::vector<uint32_t> tris;
    for (uint32_t i = 0; i < s.triangleCount(); ++i)
        if (s.triangleObject[i] != kExcludedTriangle) tris.push_back(i);
    auto rs = std::make_unique<RayScene>();
    std::string err;
    EXPECT_TRUE(rs->build(MeshView{s.positions.data(), s.indices.data()}, s.positions.size(), tris, s.bounds.center(), &err))
        << err;
    return rs;
}

Camera cameraOf(Vec3 eye, Vec3 target, Vec3 up, int w, int h, bool ortho, double orthoHeight, double fov = 60) {
    CameraSpec spec;
    spec.eye = eye;
    spec.target = target;
    spec.up = up;
    spec.width = w;
    spec.height = h;
    spec.orthographic = ortho;
    spec.orthoHeight = orthoHeight;
    spec.fovYDegrees = fov;
    spec.nearZ = 0.1;
    spec.farZ = 1000;
    Camera cam;
    std::string err;
    EXPECT_TRUE(makeCamera(spec, &cam, &err)) << err;
    return cam;
}

Light directional(const char *name, Vec3 d) {
    Light l;
    l.name = name;
    l.directional = true;
    l.direction = d;
    return l;
}
Light point(const char *name, Vec3 p) {
    Light l;
    l.name = name;
    l.directional = false;
    l.position = p;
    return l;
}

// Everything one analysis needs: the primary cast with barycentrics and the traced effects.
struct Traced {
    RaycastImage primary;
    EffectsResult fx;
};
Traced trace(const Scene &s, const RayScene &rs, const Camera &cam, int maxDepth = 4, EffectFlags flags = {}) {
    flags.maxDepth = maxDepth;
    const SceneEffectsData data = effectsDataFor(s);
    const EffectPlan plan = planEffects(s, flags);
    PrimaryOptions opt;
    opt.keepBarycentrics = true;
    Traced r;
    r.primary = rs.castPrimary(cam, opt, nullptr);
    r.fx = traceEffects(rs, cam, r.primary, effectsInputFor(data, plan));
    EXPECT_TRUE(r.fx.ok) << r.fx.error;
    return r;
}

// A quad through `center` with front normal n (unit), half size h.
RawMesh quadFacing(Vec3 center, Vec3 n, double h) {
    const Vec3 u = normalize(std::fabs(n.x) < 0.9 ? cross(Vec3{1, 0, 0}, n) : cross(Vec3{0, 1, 0}, n));
    const Vec3 v = cross(n, u);  // u x v = n: front towards n
    return gridMesh(center - u * h - v * h, u * (2 * h), v * (2 * h), 1, 1);
}

}  // namespace

// ---- Fresnel ------------------------------------------------------------------------------------

TEST(Effects, FresnelDielectricValues) {
    // Normal incidence: ((n1 - n2) / (n1 + n2))^2 = 0.04 for air/glass, either way.
    EXPECT_NEAR(fresnelDielectric(1, 1, 1.5), 0.04, 1e-15);
    EXPECT_NEAR(fresnelDielectric(1, 1.5, 1), 0.04, 1e-15);
    // Total internal reflection beyond the critical angle asin(1/1.5) = 41.81 degrees.
    EXPECT_EQ(fresnelDielectric(std::cos(60 * kPi / 180), 1.5, 1), 1.0);
    EXPECT_EQ(fresnelDielectric(std::cos(42 * kPi / 180), 1.5, 1), 1.0);
    EXPECT_LT(fresnelDielectric(std::cos(41.5 * kPi / 180), 1.5, 1), 1.0);
    // Reciprocity: the same pair of angles gives the same reflectance from either side.
    for (double deg : {10.0, 30.0, 60.0, 85.0}) {
        const double ci = std::cos(deg * kPi / 180), si = std::sin(deg * kPi / 180);
        const double ct = std::sqrt(1 - si * si / (1.5 * 1.5));
        EXPECT_NEAR(fresnelDielectric(ci, 1, 1.5), fresnelDielectric(ct, 1.5, 1), 1e-14) << deg;
    }
    // Brewster's angle atan(1.5): the parallel polarization vanishes, F = rPerp^2 / 2.
    const double b = std::atan(1.5), ci = std::cos(b), ct = std::cos(std::asin(std::sin(b) / 1.5));
    const double rPerp = (ci - 1.5 * ct) / (ci + 1.5 * ct);
    EXPECT_NEAR(fresnelDielectric(ci, 1, 1.5), rPerp * rPerp / 2, 1e-15);
    EXPECT_EQ(fresnelDielectric(0, 1, 1.5), 1.0);  // grazing
}

// ---- Robust origins: pbrt's Reintersect ---------------------------------------------------------

// A ray leaving a surface, in any direction on the side it leaves, never hits the same triangle again.
// Seeded random triangles with sizes from 1e-4 to 1e6, placed 1e-4 to 1e6 from the world origin, stored
// relative to either the world origin or their own centroid (the RayScene frame), hit by a real Embree
// ray at a random point (barycentrics anywhere, including near edges and corners), then 64 directions
// per hit. Also: the offset stays tiny against the triangle (at most 1e-3 of its longest edge), and a
// ray from the offset origin straight back hits the triangle (the origin did not jump away).
TEST(Effects, ReintersectProperty) {
    std::mt19937 rng(20240611);
    std::uniform_real_distribution<double> U(0, 1);
    std::normal_distribution<double> N(0, 1);
    auto sphere = [&] { return normalize(Vec3{N(rng), N(rng), N(rng)}); };
    uint64_t leaving = 0, rehits = 0, backHits = 0, backTried = 0, trials = 0;
    double worstOffset = 0;
    for (int trial = 0; trial < 3000; ++trial) {
        const double scale = std::pow(10.0, -4 + 10 * U(rng));
        const double dist = std::pow(10.0, -4 + 10 * U(rng));
        const Vec3 where = sphere() * dist;
        Vec3 v[3];
        const int shape = trial % 3;  // 0: random, 1: a sliver, 2: one corner at the frame's origin
        for (int j = 0; j < 3; ++j) v[j] = where + sphere() * scale;
        if (shape == 1) v[2] = v[0] + (v[1] - v[0]) * U(rng) + sphere() * (scale * 1e-3);
        const Vec3 n = cross(v[1] - v[0], v[2] - v[0]);
        if (!(length(n) > 0)) continue;
        std::vector<Vec3> pos(v, v + 3);
        std::vector<uint32_t> idx = {0, 1, 2};
        const bool centered = trial % 2 == 0;
        Vec3 origin = centered ? (v[0] + v[1] + v[2]) / 3 : Vec3{0, 0, 0};
        if (shape == 2) origin = v[0];
        RayScene rs;
        std::string err;
        ASSERT_TRUE(rs.build(MeshView{pos.data(), idx.data()}, 3, {0}, origin, &err)) << err;
        float f[9];
        rs.vertices(0, f);
        const Vec3 a{f[0], f[1], f[2]}, b{f[3], f[4], f[5]}, c{f[6], f[7], f[8]};
        const Vec3 fn = cross(b - a, c - a);
        if (!(length(fn) > 0)) continue;  // collapsed by the float conversion
        // A point on the triangle: barycentrics uniform, or pushed towards an edge or a corner.
        double b1 = U(rng), b2 = U(rng);
        if (b1 + b2 > 1) b1 = 1 - b1, b2 = 1 - b2;
        if (trial % 5 == 1) b1 *= 1e-6;
        if (trial % 5 == 2) b1 *= 1e-6, b2 *= 1e-6;
        const Vec3 target = a * (1 - b1 - b2) + b * b1 + c * b2;
        const Vec3 from = target + normalize(normalize(fn) * (U(rng) < 0.5 ? 1 : -1) + sphere() * 0.5) *
                                       (maxAbs(b - a) + maxAbs(c - a));
        LocalRay in;
        for (int k = 0; k < 3; ++k) in.org[k] = float(from[k]), in.dir[k] = float(target[k] - double(in.org[k]));
        const LocalHit h = rs.intersect(in);
        if (h.prim == kNoHit) continue;  // the aimed ray slipped past a corner: nothing to leave from
        ++trials;
        const SurfacePoint sp = surfacePoint(rs, h.prim, h.u, h.v);
        const double longest = std::max({length(b - a), length(c - b), length(a - c)});
        if (shape != 1) worstOffset = std::max(worstOffset, sp.offset / longest);
        if (shape != 1) EXPECT_LE(sp.offset, 1e-3 * longest) << "trial " << trial;
        for (int k = 0; k < 64; ++k) {
            Vec3 d = sphere();
            LocalRay r;
            offsetRayOrigin(sp, d, r.org);
            for (int j = 0; j < 3; ++j) r.dir[j] = float(d[j]);
            ++leaving;
            if (rs.intersect(r).prim != kNoHit || rs.occluded(r)) {
                ++rehits;
                ADD_FAILURE() << "trial " << trial << " scale " << scale << " dist " << dist << " shape " << shape
                              << " dir " << d.x << "," << d.y << "," << d.z;
            }
        }
        // Straight back to the surface from an interior point of a well-shaped triangle.
        if (shape == 0 && trial % 5 == 0 && std::min({h.u, h.v, 1 - h.u - h.v}) > 0.05f) {
            LocalRay r;
            offsetRayOrigin(sp, sp.n, r.org);
            for (int j = 0; j < 3; ++j) r.dir[j] = float(-sp.n[j]);
            ++backTried;
            backHits += rs.intersect(r).prim == 0;
        }
    }
    EXPECT_EQ(rehits, 0u) << "of " << leaving << " leaving rays";
    EXPECT_GT(trials, 2500u);
    EXPECT_GT(backTried, 100u);
    EXPECT_EQ(backHits, backTried);
    std::printf("[ info ] %llu leaving rays from %llu hits: 0 re-hits; worst offset / longest edge %.3g\n",
                (unsigned long long)leaving, (unsigned long long)trials, worstOffset);
}

// ---- Shadows ------------------------------------------------------------------------------------

// "Is the slab between the ground and the sun?" An orthographic camera looks straight down on a floor
// with a slab (x, z in [-1, 1], y in [0.9, 1]) at 8 pixels per unit. The sun travels along (1, -1, 0):
// the slab's shadow on the floor spans x in [-0.1, 2]; the visible shadowed floor is x in (1, 2),
// |z| < 1: 8 x 16 = 128 pixels, exactly those. A point light at (0, 5, 0) casts the shadow
// |x|, |z| <= 1.25: its visible part is 20 x 20 - 16 x 16 = 144 pixels.
TEST(Effects, ShadowOfASlabExactPixels) {
    const Scene s = sceneOf({{gridMesh({-10, 0, 10}, {20, 0, 0}, {0, 0, -20}, 4, 4)},
                             {boxMesh({0, 0.95, 0}, {1, 0.05, 1})}},
                            {Material{}}, {directional("sun", {1, -1, 0}), point("lamp", {0, 5, 0})});
    auto rs = rayScene(s);
    const Camera cam = cameraOf({0, 10, 0}, {0, 0, 0}, {0, 0, -1}, 64, 64, true, 8);
    const Traced r = trace(s, *rs, cam);
    const EffectsResult &fx = r.fx;
    ASSERT_EQ(fx.lights.size(), 2u);
    EXPECT_EQ(fx.stats.primaryHits, 4096u);
    EXPECT_EQ(fx.lights[0].shadowedPixels, 128u);
    EXPECT_EQ(fx.lights[0].litPixels, 4096u - 128u);
    EXPECT_EQ(fx.lights[0].facingAwayPixels, 0u);
    EXPECT_EQ(fx.lights[1].shadowedPixels, 144u);
    EXPECT_EQ(fx.lights[1].litPixels, 4096u - 144u);
    EXPECT_EQ(fx.stats.shadowRays, 2u * 4096u);
    EXPECT_EQ(fx.stats.reflectionRays + fx.stats.refractionRays, 0u);
    uint64_t slab = 0;
    for (int y = 0; y < 64; ++y)
        for (int x = 0; x < 64; ++x) {
            // Pixel (x, y) is world (x + 0.5) / 8 - 4, z = (y + 0.5) / 8 - 4 (camera up = -z).
            const bool sunShadow = x >= 40 && x <= 47 && y >= 24 && y <= 39;
            const bool underSlab = x >= 24 && x <= 39 && y >= 24 && y <= 39;
            const bool lampShadow = x >= 22 && x <= 41 && y >= 22 && y <= 41 && !underSlab;
            EXPECT_EQ(fx.shadowed(0, x, y), sunShadow) << x << "," << y;
            EXPECT_EQ(fx.shadowed(1, x, y), lampShadow) << x << "," << y;
            const bool slabHit = r.primary.id[size_t(y) * 64 + x] > 32;  // the floor is triangles 0..31
            EXPECT_EQ(slabHit, underSlab) << x << "," << y;
            slab += slabHit;
        }
    EXPECT_EQ(slab, 256u);
}

// A point light exactly on a surface (the floor, at the world origin) next to a box (x, z in [1, 2]).
// No NaN, no ray through the floor's own plane: every visible floor point has the light in its plane
// (facing away, no ray); the box's -x and -z faces face the light and are lit (their shadow rays end at
// the floor exactly where the light is, which must not count as a blocker); its +x, +z and top faces
// face away. Counts derive from the primary ids.
TEST(Effects, PointLightExactlyOnASurface) {
    const Scene s = sceneOf({{gridMesh({-10, 0, 10}, {20, 0, 0}, {0, 0, -20}, 4, 4)}, {boxMesh({1.5, 0.5, 1.5}, {0.5, 0.5, 0.5})}},
                            {Material{}}, {point("candle", {0, 0, 0})});
    auto rs = rayScene(s);
    const Camera cam = cameraOf({-4, 5, -4}, {1.5, 0.5, 1.5}, {0, 1, 0}, 192, 128, false, 0, 50);
    const Traced r = trace(s, *rs, cam);
    uint64_t hits = 0, facingLight = 0, floor = 0;
    for (uint32_t id : r.primary.id) {
        if (!id) continue;
        ++hits;
        const uint32_t t = id - 1;
        floor += t < 32;
        // Box triangles 32..43, two per face: -x (32, 33), +x, -y, +y, -z (40, 41), +z.
        facingLight += t == 32 || t == 33 || t == 40 || t == 41;
    }
    const LightShadowStats &L = r.fx.lights[0];
    EXPECT_GT(facingLight, 200u);
    EXPECT_GT(floor, 1000u);
    EXPECT_EQ(L.litPixels, facingLight);
    EXPECT_EQ(L.shadowedPixels, 0u);
    EXPECT_EQ(L.facingAwayPixels, hits - facingLight);
    EXPECT_EQ(L.shadowRays, facingLight);
    EXPECT_TRUE(std::isfinite(r.fx.stats.reflectionWeight));
}

// ---- Reflection and refraction ------------------------------------------------------------------

// Two parallel mirrors facing each other 10 apart, the camera between them looking straight at one:
// every pixel's chain bounces between them until the depth bound. With maximum depth D each pixel
// traces exactly D reflection rays, all hitting, and one more is called for and cut (terminated).
TEST(Effects, MirrorFacingMirrorEndsAtMaxDepth) {
    Material mirror;
    mirror.name = "mirror";
    mirror.reflective = 1;
    const Scene s = sceneOf({{quadFacing({0, 0, 0}, {0, 0, 1}, 100), 1}, {quadFacing({0, 0, 10}, {0, 0, -1}, 100), 1}},
                            {Material{}, mirror});
    auto rs = rayScene(s);
    const Camera cam = cameraOf({0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 24, 16, false, 0, 20);
    const uint64_t px = 24 * 16;
    for (int depth : {0, 1, 2, 4, 7}) {
        const Traced r = trace(s, *rs, cam, depth);
        const EffectsStats &st = r.fx.stats;
        EXPECT_EQ(st.primaryHits, px);
        EXPECT_EQ(st.reflectionRays, uint64_t(depth) * px) << depth;
        EXPECT_EQ(st.secondaryHits, uint64_t(depth) * px) << depth;
        EXPECT_EQ(st.terminatedByDepth, px) << depth;
        EXPECT_EQ(st.refractionRays, 0u);
        EXPECT_EQ(st.deepest, depth);
        EXPECT_DOUBLE_EQ(st.reflectionWeight, double(depth) * px);  // reflectance 1: every ray carries 1
        for (size_t p = 0; p < px; ++p) {
            ASSERT_EQ(r.fx.secondaryDepth[p], depth) << p;
            ASSERT_EQ(r.fx.secondaryRays[p], depth) << p;
        }
    }
    // Forced off: the plan says so and no ray is traced.
    EffectFlags off;
    off.reflections = false;
    const Traced r = trace(s, *rs, cam, 4, off);
    EXPECT_EQ(r.fx.stats.reflectionRays, 0u);
    EXPECT_EQ(r.fx.stats.terminatedByDepth, 0u);
}

// A glass pane seen by an orthographic camera, so every ray meets it at the same angle.
// From inside the glass (its back) at 60 degrees: total internal reflection at every hit, one
// reflection ray of weight 1, no refraction. At 30 degrees from inside: both rays, weights F and 1 - F
// with F the exact dielectric Fresnel. Head-on from outside: F = 0.04.
TEST(Effects, GlassTotalInternalReflectionAndFresnelWeights) {
    Material glass;
    glass.name = "glass";
    glass.ior = 1.5;
    const double deg = kPi / 180;
    struct Case {
        Vec3 n;           // front normal of the pane
        bool tir;
        double F;         // expected Fresnel reflectance
    };
    const Case cases[] = {
        {{0, std::sin(60 * deg), -std::cos(60 * deg)}, true, 1.0},
        {{0, std::sin(30 * deg), -std::cos(30 * deg)}, false, fresnelDielectric(std::cos(30 * deg), 1.5, 1)},
        {{0, 0, 1}, false, 0.04},
    };
    for (const Case &c : cases) {
        const Scene s = sceneOf({{quadFacing({0, 0, 0}, c.n, 3), 1}}, {Material{}, glass});
        auto rs = rayScene(s);
        const Camera cam = cameraOf({0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 32, 32, true, 4);
        const Traced r = trace(s, *rs, cam);
        const EffectsStats &st = r.fx.stats;
        const uint64_t hits = st.primaryHits;
        ASSERT_GT(hits, 300u);
        EXPECT_EQ(st.totalInternalReflections, c.tir ? hits : 0u);
        EXPECT_EQ(st.reflectionRays, hits);
        EXPECT_EQ(st.refractionRays, c.tir ? 0u : hits);
        EXPECT_EQ(st.secondaryHits, 0u);  // nothing else in the scene: every secondary ray escapes
        // The pane's normal comes from float vertices and the rays' directions are floats: the incidence
        // angle is off by ~1e-7 rad, which moves F by less than 1e-6 (exact for the axis-aligned pane).
        EXPECT_NEAR(st.reflectionWeight, c.F * double(hits), 1e-6 * double(hits));
        EXPECT_NEAR(st.refractionWeight, (1 - c.F) * double(hits), 1e-6 * double(hits));
        EXPECT_EQ(st.terminatedByDepth, 0u);
    }
}

// A glass slab (a closed box) seen head-on: the ray enters (Fresnel split), crosses, leaves through the
// back face (split again): per pixel, depth 1 has a reflection and a refraction ray, the refraction
// ray hits the back face from inside and spawns two rays of depth 2; one of those (the internal
// reflection) comes back to the front face from inside and spawns two of depth 3, and so on. With
// maximum depth D there are exactly 2 rays per level (the escaping reflection does not spawn), so
// 2D rays per pixel and 2 terminated.
TEST(Effects, GlassSlabRayTreeIsExact) {
    Material glass;
    glass.name = "glass";
    glass.ior = 1.5;
    const Scene s = sceneOf({{boxMesh({0, 0, 0}, {5, 5, 0.5}), 1}}, {Material{}, glass});
    auto rs = rayScene(s);
    const Camera cam = cameraOf({0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 16, 16, true, 4);
    for (int depth : {1, 2, 3, 5}) {
        const Traced r = trace(s, *rs, cam, depth);
        const EffectsStats &st = r.fx.stats;
        const uint64_t px = 256;
        ASSERT_EQ(st.primaryHits, px);
        EXPECT_EQ(st.reflectionRays + st.refractionRays, 2u * depth * px) << depth;
        EXPECT_EQ(st.refractionRays, uint64_t(depth) * px) << depth;
        EXPECT_EQ(st.terminatedByDepth, 2u * px) << depth;
        EXPECT_EQ(st.totalInternalReflections, 0u);
        // Weights: the ray inside the glass carries 0.96 after entering and 0.04 of that after each
        // internal reflection; at every level after the first it splits into 0.04 (reflected, stays
        // inside) and 0.96 (transmitted, escapes). F = 0.04 at normal incidence.
        double refl = 0.04, refr = 0.96, inside = 0.96;
        for (int k = 2; k <= depth; ++k) {
            refl += inside * 0.04;
            refr += inside * 0.96;
            inside *= 0.04;
        }
        EXPECT_NEAR(st.reflectionWeight / double(px), refl, 1e-12) << depth;
        EXPECT_NEAR(st.refractionWeight / double(px), refr, 1e-12) << depth;
    }
}

// ---- Determinism, bad input ---------------------------------------------------------------------

// The demo with a mirror crate, a glass ball and two lights: identical results with 1 and 2 threads.
TEST(Effects, DeterministicAcrossThreadCounts) {
    SceneBuildInput in = demoSceneInput();
    Material mirror, glass;
    mirror.name = "mirror";
    mirror.reflective = 0.8;
    glass.name = "glass";
    glass.ior = 1.5;
    glass.alpha = 0.3;
    in.materials.push_back(mirror);
    in.materials.push_back(glass);
    for (auto &o : in.objects) {
        if (o.name == "crate" || o.name == "wall") o.material = uint32_t(in.materials.size() - 2);
        if (o.name == "ball") o.material = uint32_t(in.materials.size() - 1);
    }
    in.lights = {directional("sun", {-1, -2, -1}), point("lamp", {2, 3, 4})};
    const Scene s = buildScene(std::move(in));
    auto rs = rayScene(s);
    CameraSpec spec = s.views[0].camera;
    spec.width = 160;
    spec.height = 90;
    Camera cam;
    std::string err;
    ASSERT_TRUE(makeCamera(spec, &cam, &err)) << err;
    Traced one, two;
    {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
        one = trace(s, *rs, cam);
    }
    {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
        two = trace(s, *rs, cam);
    }
    EXPECT_GT(one.fx.stats.reflectionRays, 0u);
    EXPECT_GT(one.fx.stats.refractionRays, 0u);
    EXPECT_GT(one.fx.lights[0].shadowedPixels, 0u);
    EXPECT_EQ(one.fx.stats.shadowRays, two.fx.stats.shadowRays);
    EXPECT_EQ(one.fx.stats.reflectionRays, two.fx.stats.reflectionRays);
    EXPECT_EQ(one.fx.stats.refractionRays, two.fx.stats.refractionRays);
    EXPECT_EQ(one.fx.stats.totalInternalReflections, two.fx.stats.totalInternalReflections);
    EXPECT_EQ(one.fx.stats.terminatedByDepth, two.fx.stats.terminatedByDepth);
    EXPECT_EQ(one.fx.stats.reflectionWeight, two.fx.stats.reflectionWeight);  // bitwise: row-ordered sums
    EXPECT_EQ(one.fx.stats.refractionWeight, two.fx.stats.refractionWeight);
    EXPECT_EQ(one.fx.shadowMask, two.fx.shadowMask);
    EXPECT_EQ(one.fx.secondaryDepth, two.fx.secondaryDepth);
    EXPECT_EQ(one.fx.secondaryRays, two.fx.secondaryRays);
    for (size_t l = 0; l < 2; ++l) {
        EXPECT_EQ(one.fx.lights[l].shadowedPixels, two.fx.lights[l].shadowedPixels);
        EXPECT_EQ(one.fx.lights[l].litPixels + one.fx.lights[l].shadowedPixels + one.fx.lights[l].facingAwayPixels,
                  one.fx.stats.primaryHits);
    }
}

TEST(Effects, BadInputIsRefusedWithAMessage) {
    const Scene s = sceneOf({{quadFacing({0, 0, 0}, {0, 0, 1}, 1)}});
    auto rs = rayScene(s);
    const Camera cam = cameraOf({0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 8, 8, false, 0);
    const RaycastImage noBary = rs->castPrimary(cam, nullptr);
    EffectsInput in;
    EffectsResult r = traceEffects(*rs, cam, noBary, in);
    EXPECT_FALSE(r.ok);
    EXPECT_EQ(r.error, "effects: the primary image has no barycentrics; cast it with PrimaryOptions::keepBarycentrics");
    PrimaryOptions opt;
    opt.keepBarycentrics = true;
    const RaycastImage img = rs->castPrimary(cam, opt, nullptr);
    const std::vector<uint32_t> mats = {0, 3};
    in.materials = {SurfaceMaterial{}};
    in.triangleMaterial = mats;
    r = traceEffects(*rs, cam, img, in);
    EXPECT_EQ(r.error, "effects: triangle 1 names material 3; the table has 1");
    in = {};
    in.lights = {EffectLight{"dark", true, {0, 0, 0}, {}}};
    r = traceEffects(*rs, cam, img, in);
    EXPECT_EQ(r.error, "effects: light 'dark' has no direction (zero or not finite)");
    in = {};
    in.maxDepth = -1;
    r = traceEffects(*rs, cam, img, in);
    EXPECT_EQ(r.error, "effects: maximum depth -1 is outside 0..255");
}

// ---- The planner --------------------------------------------------------------------------------

TEST(EffectsPlan, EachEffectRunsExactlyWhenTheSceneCallsForIt) {
    // The demo has no lights, no mirror, no glass: nothing runs.
    {
        const EffectPlan p = planEffects(demoScene(), {});
        EXPECT_FALSE(p.shadows.run);
        EXPECT_EQ(p.shadows.reason, "scene has no lights");
        EXPECT_FALSE(p.reflections.run);
        EXPECT_EQ(p.reflections.reason, "no reflective material");
        EXPECT_FALSE(p.refractions.run);
        EXPECT_EQ(p.refractions.reason, "no refractive material");
        EXPECT_FALSE(p.abuffer.run);
        EXPECT_EQ(p.abuffer.reason, "no transparent material");
        EXPECT_FALSE(p.tracesRays());
    }
    Material mirror, glass, unusedChrome;
    mirror.name = "mirror";
    mirror.reflective = 0.9;
    glass.name = "glass";
    glass.ior = 1.5;
    glass.alpha = 0.4;
    unusedChrome.name = "chrome";
    unusedChrome.reflective = 1;
    const RawMesh quad = gridMesh({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 1, 1);
    // Lights only.
    {
        const Scene s = sceneOf({{quad}}, {Material{}}, {directional("sun", {0, -1, 0}), point("lamp", {0, 1, 0})});
        const EffectPlan p = planEffects(s, {});
        EXPECT_TRUE(p.shadows.run);
        EXPECT_EQ(p.shadows.reason, "scene has 2 lights 'sun', 'lamp'");
        EXPECT_FALSE(p.reflections.run);
        EXPECT_TRUE(p.tracesRays());
    }
    // A mirror in use, a reflective material defined but unused, glass (refractive and transparent).
    {
        const Scene s = sceneOf({{quad, 1}, {quad, 1}, {quad, 2}}, {Material{}, mirror, glass, unusedChrome});
        const EffectPlan p = planEffects(s, {});
        EXPECT_FALSE(p.shadows.run);
        EXPECT_TRUE(p.reflections.run);
        EXPECT_EQ(p.reflections.triangles, 4u);
        EXPECT_EQ(p.reflections.reason, "4 triangles use reflective material 'mirror'");
        EXPECT_TRUE(p.refractions.run);
        EXPECT_EQ(p.refractions.reason, "2 triangles use refractive material 'glass'");
        EXPECT_TRUE(p.abuffer.run);
        EXPECT_EQ(p.abuffer.reason, "2 triangles use transparent material 'glass'");
    }
    // Only the unused one: defined but unused does not call for reflections.
    {
        const Scene s = sceneOf({{quad}}, {Material{}, unusedChrome});
        const EffectPlan p = planEffects(s, {});
        EXPECT_FALSE(p.reflections.run);
        EXPECT_EQ(p.reflections.reason, "no triangle uses a reflective material ('chrome' is defined but unused)");
    }
}

TEST(EffectsPlan, FlagsOverrideTheScene) {
    Material mirror;
    mirror.name = "mirror";
    mirror.reflective = 0.5;
    const RawMesh quad = gridMesh({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 1, 1);
    const Scene s = sceneOf({{quad, 1}}, {Material{}, mirror}, {directional("sun", {0, -1, 0})});
    EffectFlags f;
    f.shadows = false;
    f.reflections = false;
    f.refractions = true;
    f.abuffer = true;
    f.maxDepth = 2;
    const EffectPlan p = planEffects(s, f);
    EXPECT_FALSE(p.shadows.run);
    EXPECT_TRUE(p.shadows.forced);
    EXPECT_EQ(p.shadows.reason, "forced off by --no-shadows (scene has 1 light 'sun')");
    EXPECT_FALSE(p.reflections.run);
    EXPECT_EQ(p.reflections.reason, "forced off by --no-reflections (scene: 2 triangles use reflective material 'mirror')");
    EXPECT_TRUE(p.refractions.run);
    EXPECT_EQ(p.refractions.reason, "forced on by --refractions (scene: no refractive material)");
    EXPECT_TRUE(p.abuffer.run);
    EXPECT_EQ(p.abuffer.reason, "forced on by --abuffer (scene: no transparent material)");
    EXPECT_EQ(p.maxDepth, 2);
    const Scene dark = sceneOf({{quad}});
    EffectFlags on;
    on.shadows = true;
    const EffectPlan q = planEffects(dark, on);
    EXPECT_TRUE(q.shadows.run);
    EXPECT_EQ(q.shadows.reason, "forced on by --shadows (scene has no lights: no shadow rays to cast)");
    // The input handed to traceEffects follows the plan.
    const SceneEffectsData data = effectsDataFor(s);
    const EffectsInput in = effectsInputFor(data, p);
    EXPECT_FALSE(in.shadows);
    EXPECT_FALSE(in.reflections);
    EXPECT_TRUE(in.refractions);
    EXPECT_EQ(in.maxDepth, 2);
    ASSERT_EQ(in.triangleMaterial.size(), 2u);
    EXPECT_EQ(in.triangleMaterial[0], 1u);
    EXPECT_EQ(in.materials[1].reflective, 0.5);
}

// ---- glTF: KHR_lights_punctual, KHR_materials_transmission + KHR_materials_ior --------------------

TEST(EffectsGltf, LightsAndTransmissionMapToTheScene) {
    const std::filesystem::path dir = std::filesystem::temp_directory_path() / "visaudit_effects_gltf";
    std::filesystem::create_directories(dir);
    const std::string path = (dir / "lights.gltf").string();
    // One triangle (positions in a base64 buffer), a glass material, and three lights: a directional
    // light on a node rotated 90 degrees about x (its -Z becomes -Y... see below), a point light on a
    // translated child node, and a spot light.
    // Buffer: 3 float3 positions (0,0,0) (1,0,0) (0,1,0) = 36 bytes.
    const char *b64 = "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA";
    std::ofstream(path) << R"({
  "asset": {"version": "2.0"},
  "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_transmission", "KHR_materials_ior"],
  "extensions": {"KHR_lights_punctual": {"lights": [
     {"name": "sun", "type": "directional"},
     {"name": "bulb", "type": "point"},
     {"type": "spot", "spot": {"outerConeAngle": 0.5}}]}},
  "buffers": [{"byteLength": 36, "uri": "data:application/octet-stream;base64,)" << b64 << R"("}],
  "bufferViews": [{"buffer": 0, "byteLength": 36}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                 "min": [0,0,0], "max": [1,1,0]}],
  "materials": [{"name": "glass", "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1},
                                                  "KHR_materials_ior": {"ior": 1.33}}},
                {"name": "thin", "extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.5}}}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]},
             {"primitives": [{"attributes": {"POSITION": 0}, "material": 1}]}],
  "nodes": [{"mesh": 0}, {"mesh": 1},
            {"name": "sunNode", "rotation": [-0.7071067811865476, 0, 0, 0.7071067811865476],
             "extensions": {"KHR_lights_punctual": {"light": 0}}},
            {"translation": [1, 2, 3], "children": [4]},
            {"translation": [0, 1, 0], "extensions": {"KHR_lights_punctual": {"light": 1}}},
            {"translation": [5, 0, 0], "extensions": {"KHR_lights_punctual": {"light": 2}}}],
  "scenes": [{"nodes": [0, 1, 2, 3, 5]}]
})";
    SceneBuildInput in;
    std::string err;
    ASSERT_TRUE(loadGltf(path, &in, &err)) << err;
    ASSERT_EQ(in.lights.size(), 3u);
    // Rotation -90 degrees about x maps -Z to -Y: the sun shines straight down.
    EXPECT_EQ(in.lights[0].name, "sun");
    EXPECT_TRUE(in.lights[0].directional);
    EXPECT_NEAR(in.lights[0].direction.x, 0, 1e-12);
    EXPECT_NEAR(in.lights[0].direction.y, -1, 1e-12);
    EXPECT_NEAR(in.lights[0].direction.z, 0, 1e-12);
    // The point light: parent translation (1,2,3) then its own (0,1,0).
    EXPECT_EQ(in.lights[1].name, "bulb");
    EXPECT_FALSE(in.lights[1].directional);
    EXPECT_EQ(in.lights[1].position, (Vec3{1, 3, 3}));
    // The spot: a point light at its node, named after its index, with a warning.
    EXPECT_EQ(in.lights[2].name, "light2");
    EXPECT_FALSE(in.lights[2].directional);
    EXPECT_EQ(in.lights[2].position, (Vec3{5, 0, 0}));
    bool warned = false;
    for (const auto &w : in.warnings)
        warned |= w == path + ": 1 KHR_lights_punctual spot light(s) read as point light(s) (the cone is ignored)";
    EXPECT_TRUE(warned);
    // Transmission: refractive with KHR_materials_ior's ior, or glTF's default 1.5.
    ASSERT_EQ(in.materials.size(), 3u);
    EXPECT_EQ(in.materials[1].ior, 1.33);
    EXPECT_EQ(in.materials[2].ior, 1.5);
    // The planner sees them through the scene.
    const Scene s = buildScene(std::move(in));
    const EffectPlan p = planEffects(s, {});
    EXPECT_TRUE(p.shadows.run);
    EXPECT_EQ(p.shadows.reason, "scene has 3 lights 'sun', 'bulb', 'light2'");
    EXPECT_TRUE(p.refractions.run);
    EXPECT_EQ(p.refractions.reason, "2 triangles use refractive materials 'glass', 'thin'");

    // A node naming a light that does not exist is refused with the node and the count.
    const std::string bad = (dir / "badlight.gltf").string();
    std::ofstream(bad) << R"({"asset": {"version": "2.0"},
  "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point"}]}},
  "nodes": [{"name": "lamp", "extensions": {"KHR_lights_punctual": {"light": 4}}}],
  "scenes": [{"nodes": [0]}]})";
    SceneBuildInput in2;
    EXPECT_FALSE(loadGltf(bad, &in2, &err));
    EXPECT_EQ(err, bad + ": node 'lamp' refers to light 4, which does not exist (KHR_lights_punctual.lights has 1)");
    std::filesystem::remove_all(dir);
}
