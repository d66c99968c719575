#include "analysis/effects_plan.h"

namespace va {

namespace {

// "a, b, c" (at most three names, then "and N more").
std::string nameList(const std::vector<std::string> &names) {
    std::string s;
    for (size_t i = 0; i < names.size() && i < 3; ++i) s += (i ? ", " : "") + ("'" + names[i] + "'");
    if (names.size() > 3) s += " and " + std::to_string(names.size() - 3) + " more";
    return s;
}

std::string plural(uint64_t n, const char *one, const char *many) {
    return std::to_string(n) + " " + (n == 1 ? one : many);
}

// A material-driven effect: run when some triangle (not excluded) uses a material with the property.
// `adjective` names the property ("reflective"), `why` says what the material makes it do.
EffectDecision materialEffect(const Scene &scene, const char *name, const char *flag, const char *adjective,
                              const std::vector<uint64_t> &trianglesOfMaterial, bool (*has)(const Material &),
                              std::optional<bool> force) {
    EffectDecision d;
    d.name = name;
    std::vector<std::string> used, unused;
    for (size_t m = 0; m < scene.materials.size(); ++m) {
        if (!has(scene.materials[m])) continue;
        if (trianglesOfMaterial[m] > 0) {
            used.push_back(scene.materials[m].name);
            d.triangles += trianglesOfMaterial[m];
        } else {
            unused.push_back(scene.materials[m].name);
        }
    }
    std::string sceneSays;
    if (d.triangles > 0)
        sceneSays = plural(d.triangles, "triangle uses", "triangles use") + " " + adjective + " material" +
                    (used.size() == 1 ? " " : "s ") + nameList(used);
    else if (!unused.empty())
        sceneSays = std::string("no triangle uses a ") + adjective + " material (" + nameList(unused) +
                    (unused.size() == 1 ? " is" : " are") + " defined but unused)";
    else
        sceneSays = std::string("no ") + adjective + " material";
    if (force) {
        d.forced = true;
        d.run = *force;
        d.reason = std::string("forced ") + (*force ? "on by --" : "off by --no-") + flag + " (scene: " + sceneSays + ")";
    } else {
        d.run = d.triangles > 0;
        d.reason = sceneSays;
    }
    return d;
}

}  // namespace

EffectPlan planEffects(const Scene &scene, const EffectFlags &flags) {
    EffectPlan plan;
    plan.maxDepth = flags.maxDepth;

    // Shadows: one shadow ray per visible point and light, so lights call for them.
    EffectDecision &sh = plan.shadows;
    sh.name = "shadows";
    std::vector<std::string> lightNames;
    for (const Light &l : scene.lights) lightNames.push_back(l.name);
    const std::string lightsSay =
        scene.lights.empty() ? "scene has no lights" : "scene has " + plural(scene.lights.size(), "light", "lights") + " " + nameList(lightNames);
    if (flags.shadows) {
        sh.forced = true;
        sh.run = *flags.shadows;
        sh.reason = std::string("forced ") + (sh.run ? "on by --shadows" : "off by --no-shadows") + " (" + lightsSay +
                    (sh.run && scene.lights.empty() ? ": no shadow rays to cast" : "") + ")";
    } else {
        sh.run = !scene.lights.empty();
        sh.reason = lightsSay;
    }

    // Materials: triangles per material (excluded triangles belong to no object and count nowhere).
    std::vector<uint64_t> tris(scene.materials.size(), 0);
    for (const SceneObject &o : scene.objects) tris[o.material] += o.triEnd - o.triBegin;
    plan.reflections = materialEffect(scene, "reflections", "reflections", "reflective", tris,
                                      [](const Material &m) { return m.reflective > 0; }, flags.reflections);
    plan.refractions = materialEffect(scene, "refractions", "refractions", "refractive", tris,
                                      [](const Material &m) { return m.refractive(); }, flags.refractions);
    plan.abuffer = materialEffect(scene, "abuffer", "abuffer", "transparent", tris,
                                  [](const Material &m) { return m.transparent(); }, flags.abuffer);
    return plan;
}

SceneEffectsData effectsDataFor(const Scene &scene) {
    SceneEffectsData d;
    for (const Light &l : scene.lights) {
        EffectLight e;
        e.name = l.name;
        e.directional = l.directional;
        e.direction = l.direction;
        e.position = l.position;
        d.lights.push_back(e);
    }
    for (const Material &m : scene.materials) d.materials.push_back({m.doubleSided, m.reflective, m.ior, m.alpha});
    d.triangleMaterial.assign(scene.triangleCount(), 0);
    d.doubleSided.assign(scene.triangleCount(), 0);
    for (const SceneObject &o : scene.objects)
        for (uint32_t k = o.triBegin; k < o.triEnd; ++k) {
            const uint32_t t = scene.objectTriangles[k];
            d.triangleMaterial[t] = o.material;
            d.doubleSided[t] = scene.materials[o.material].doubleSided ? 1 : 0;
        }
    return d;
}

EffectsInput effectsInputFor(const SceneEffectsData &data, const EffectPlan &plan) {
    EffectsInput in;
    in.lights = data.lights;
    in.materials = data.materials;
    in.triangleMaterial = data.triangleMaterial;
    in.shadows = plan.shadows.run;
    in.reflections = plan.reflections.run;
    in.refractions = plan.refractions.run;
    in.maxDepth = plan.maxDepth;
    return in;
}

}  // namespace va
