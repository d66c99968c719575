// Assignment kits (kit.h; docs/grading.md): the stage inputs, their files, and the reference answers.
#include "analysis/kit.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>

#include <tbb/parallel_for.h>

#include "analysis/audits/audit.h"
#include "analysis/kit_text.h"
#include "analysis/stages/backface.h"
#include "common/json_util.h"

namespace va::kit {

using OJson = nlohmann::ordered_json;
using json::Json;
using json::Path;

const char *stageName(Stage s) {
    switch (s) {
    case Stage::backface: return "backface";
    case Stage::clip: return "clip";
    case Stage::zbuffer: return "zbuffer";
    case Stage::painter: return "painter";
    }
    return "?";
}

bool parseStageList(const std::string &list, std::vector<Stage> *out, std::string *err) {
    std::vector<std::string> known;
    for (Stage s : kAllStages) known.push_back(stageName(s));
    std::vector<bool> seen(std::size(kAllStages), false);
    if (list == "all") {
        out->assign(std::begin(kAllStages), std::end(kAllStages));
        return true;
    }
    std::stringstream ss(list);
    std::string name;
    while (std::getline(ss, name, ',')) {
        size_t k = 0;
        while (k < known.size() && known[k] != name) ++k;
        if (k == known.size()) {
            const std::string near = json::closest(name, known);
            *err = "unknown stage '" + name + "'" + (near.empty() ? "" : ", did you mean '" + near + "'?") +
                   " (stages: " + json::joinList(known) + ", or all)";
            return false;
        }
        if (seen[k]) {
            *err = "stage '" + name + "' is listed twice; list it once";
            return false;
        }
        seen[k] = true;
    }
    out->clear();
    for (size_t k = 0; k < seen.size(); ++k)
        if (seen[k]) out->push_back(kAllStages[k]);
    if (out->empty()) {
        *err = "no stages given; name at least one of " + json::joinList(known) + ", or all";
        return false;
    }
    return true;
}

bool Kit::has(Stage s) const { return std::find(stages.begin(), stages.end(), s) != stages.end(); }

std::string fingerprint(const std::string &bytes) {
    uint64_t h = 0xcbf29ce484222325ull;
    for (unsigned char c : bytes) {
        h ^= c;
        h *= 0x100000001b3ull;
    }
    char buf[40];
    std::snprintf(buf, sizeof buf, "fnv1a64:%016llx", static_cast<unsigned long long>(h));
    return buf;
}

namespace {

// ---- Writing ----------------------------------------------------------------------------------------

// Compact JSON text; invalid UTF-8 (a view name from a file) becomes U+FFFD instead of throwing.
std::string dumps(const OJson &j) { return j.dump(-1, ' ', false, OJson::error_handler_t::replace); }

// The files' layout: objects at the top two levels have a member per line, and an array of objects
// or arrays has an element per line (each element compact), so a reader sees one triangle, polygon
// or view per line. Doubles are nlohmann's shortest decimal that reads back as the same double.
void pretty(const OJson &j, int depth, std::string &o) {
    const std::string pad(size_t(2 * (depth + 1)), ' ');
    if (j.is_object() && !j.empty() && depth < 2) {
        o += "{\n";
        bool first = true;
        for (auto it = j.begin(); it != j.end(); ++it) {
            if (!first) o += ",\n";
            first = false;
            o += pad + dumps(OJson(it.key())) + ": ";
            pretty(it.value(), depth + 1, o);
        }
        o += "\n" + std::string(size_t(2 * depth), ' ') + "}";
    } else if (j.is_array() && !j.empty() && (j.front().is_object() || j.front().is_array())) {
        o += "[\n";
        for (size_t i = 0; i < j.size(); ++i) o += pad + dumps(j[i]) + (i + 1 < j.size() ? ",\n" : "\n");
        o += std::string(size_t(2 * depth), ' ') + "]";
    } else {
        o += dumps(j);
    }
}
std::string prettyText(const OJson &j) {
    std::string o;
    pretty(j, 0, o);
    return o + "\n";
}

OJson vec(Vec3 v) { return OJson::array({v.x, v.y, v.z}); }
OJson planeJson(const DepthPlane &p) { return OJson::array({p.a, p.b, p.c}); }
OJson xyJson(const ScreenTriangles &st, size_t t) {
    OJson a = OJson::array();
    for (int k = 0; k < 6; ++k) a.push_back(st.xy[6 * t + size_t(k)]);
    return a;
}
const char *projectionName(const Camera &cam) { return cam.orthographic ? "orthographic" : "perspective"; }

// The view's header every input file starts with (the format, the view, the camera numbers the stage needs).
OJson header(const char *format, const KitView &v) {
    OJson h;
    h["format"] = format;
    h["view"] = v.name;
    h["projection"] = projectionName(v.cam);
    return h;
}

std::string backfaceText(const KitView &v, const BackfaceInput &in) {
    OJson h = header(kBackfaceFormat, v);
    h["eye"] = vec(v.cam.eye);
    h["forward"] = vec(v.cam.forward);
    OJson rows = OJson::array();
    for (const BackfaceInput::Triangle &t : in.triangles)
        rows.push_back({{"id", t.id}, {"double_sided", t.doubleSided}, {"v", {vec(t.v[0]), vec(t.v[1]), vec(t.v[2])}}});
    h["triangles"] = std::move(rows);
    return prettyText(h);
}

std::string clipText(const KitView &v, const ClipInput &in) {
    OJson h = header(kClipFormat, v);
    h["width"] = v.cam.width;
    h["height"] = v.cam.height;
    h["near"] = v.cam.nearZ;
    h["far"] = v.cam.farZ;
    h["sx"] = v.cam.sx;
    h["sy"] = v.cam.sy;
    h["guard_band_px"] = in.guardBandPixels;
    OJson rows = OJson::array();
    for (size_t t = 0; t < in.ids.size(); ++t)
        rows.push_back({{"id", in.ids[t]}, {"v", {vec(in.view[3 * t]), vec(in.view[3 * t + 1]), vec(in.view[3 * t + 2])}}});
    h["triangles"] = std::move(rows);
    return prettyText(h);
}

void depthFormatHeader(const KitView &v, OJson &h) {
    h["depth_format"] = depthFormatName(v.spec.depthFormat);
    const DepthFormatInfo &info = depthFormatInfo(v.spec.depthFormat.format);
    h["depth_stored"] = info.stored;
    h["nearer_is"] = info.nearerIsLarger ? "larger" : "smaller";
}

std::string zbufferText(const KitView &v, const ZBufferInput &in) {
    OJson h = header(kZBufferFormat, v);
    h["width"] = v.cam.width;
    h["height"] = v.cam.height;
    h["near"] = v.cam.nearZ;
    h["far"] = v.cam.farZ;
    depthFormatHeader(v, h);
    h["subpixel_bits"] = kSubpixelBits;
    OJson rows = OJson::array();
    const ScreenTriangles &st = in.triangles;
    for (size_t t = 0; t < st.size(); ++t)
        rows.push_back({{"id", st.source[t]}, {"xy", xyJson(st, t)}, {"plane", planeJson(st.planes[st.plane[t]])}});
    h["triangles"] = std::move(rows);
    return prettyText(h);
}

std::string painterText(const KitView &v, const PainterInput &in, PainterKey key) {
    OJson h = header(kPainterFormat, v);
    h["width"] = v.cam.width;
    h["height"] = v.cam.height;
    h["key"] = painterKeyName(key);
    h["subpixel_bits"] = kSubpixelBits;
    OJson rows = OJson::array();
    const ScreenTriangles &st = in.screen;
    size_t t = 0;
    for (size_t c = 0; c < in.candidates.size(); ++c) {
        const PainterCandidate &pc = in.candidates[c];
        OJson screen = OJson::array();
        DepthPlane plane;
        for (; t < st.size() && st.source[t] == pc.source; ++t) {
            screen.push_back(xyJson(st, t));
            plane = st.planes[st.plane[t]];
        }
        rows.push_back({{"id", pc.source},
                        {"depths", {pc.depth[0], pc.depth[1], pc.depth[2]}},
                        {"single_sided", in.singleSided[c] != 0},
                        {"plane", planeJson(plane)},
                        {"screen", std::move(screen)}});
    }
    h["triangles"] = std::move(rows);
    return prettyText(h);
}

// ---- Reading --------------------------------------------------------------------------------------

// Typed reads with messages naming FILE:LINE:COL and the JSON path (STYLE 10).
struct Reader {
    const json::Doc &doc;
    std::string *err;

    bool fail(const Path &p, const std::string &msg, bool key = false) const {
        *err = json::where(doc, p, key) + ": " + json::pathString(p) + ": " + msg;
        return false;
    }
    bool object(const Json &j, const Path &p) const {
        return j.is_object() || fail(p, "expected an object, got " + json::typeName(j));
    }
    const Json *member(const Json &j, const Path &p, const char *key) const {
        if (!j.contains(key)) {
            fail(p, std::string("missing \"") + key + "\"");
            return nullptr;
        }
        return &j[key];
    }
    bool array(const Json &j, const Path &p, size_t n = 0) const {
        if (!j.is_array()) return fail(p, "expected an array, got " + json::typeName(j));
        if (n && j.size() != n) return fail(p, "expected an array of " + std::to_string(n) + ", got " + std::to_string(j.size()));
        return true;
    }
    bool number(const Json &j, const Path &p, double *out) const {
        if (!j.is_number()) return fail(p, "expected a number, got " + json::typeName(j));
        *out = j.get<double>();
        return true;
    }
    bool u32(const Json &j, const Path &p, uint32_t *out) const {
        if (!j.is_number_unsigned() || j.get<uint64_t>() > UINT32_MAX)
            return fail(p, "expected a whole number from 0 to 4294967295, got " + j.dump());
        *out = uint32_t(j.get<uint64_t>());
        return true;
    }
    bool i32(const Json &j, const Path &p, int32_t *out) const {
        if (!j.is_number_integer() || j.get<int64_t>() < INT32_MIN || j.get<int64_t>() > INT32_MAX)
            return fail(p, "expected a whole number that fits 32 bits, got " + j.dump());
        *out = int32_t(j.get<int64_t>());
        return true;
    }
    bool boolean(const Json &j, const Path &p, bool *out) const {
        if (!j.is_boolean()) return fail(p, "expected true or false, got " + json::typeName(j));
        *out = j.get<bool>();
        return true;
    }
    bool string(const Json &j, const Path &p, std::string *out) const {
        if (!j.is_string()) return fail(p, "expected a string, got " + json::typeName(j));
        *out = j.get<std::string>();
        return true;
    }
    bool vec3(const Json &j, const Path &p, Vec3 *out) const {
        if (!array(j, p, 3)) return false;
        for (size_t k = 0; k < 3; ++k)
            if (!number(j[k], p / k, &(*out)[int(k)])) return false;
        return true;
    }
    bool format(const Json &root, const char *expected) const {
        if (!object(root, {})) return false;
        const Json *f = member(root, {}, "format");
        if (!f) return false;
        if (!f->is_string() || f->get<std::string>() != expected)
            return fail(Path{} / "format", std::string("expected \"") + expected + "\", got " + f->dump());
        return true;
    }
    // The triangles array of an input file.
    const Json *triangles(const Json &root) const {
        const Json *t = member(root, {}, "triangles");
        if (!t || !array(*t, Path{} / "triangles")) return nullptr;
        return t;
    }
};

bool parseBackface(const json::Doc &doc, BackfaceInput *out, std::string *err) {
    const Reader r{doc, err};
    if (!r.format(doc.root, kBackfaceFormat)) return false;
    const Json *tris = r.triangles(doc.root);
    if (!tris) return false;
    BackfaceInput in;
    for (size_t i = 0; i < tris->size(); ++i) {
        const Json &j = (*tris)[i];
        const Path p = Path{} / "triangles" / i;
        BackfaceInput::Triangle t;
        const Json *id = nullptr, *ds = nullptr, *v = nullptr;
        if (!r.object(j, p) || !(id = r.member(j, p, "id")) || !r.u32(*id, p / "id", &t.id) ||
            !(ds = r.member(j, p, "double_sided")) || !r.boolean(*ds, p / "double_sided", &t.doubleSided) ||
            !(v = r.member(j, p, "v")) || !r.array(*v, p / "v", 3))
            return false;
        for (size_t k = 0; k < 3; ++k)
            if (!r.vec3((*v)[k], p / "v" / k, &t.v[k])) return false;
        in.triangles.push_back(t);
    }
    *out = std::move(in);
    return true;
}

bool parseClip(const json::Doc &doc, ClipInput *out, std::string *err) {
    const Reader r{doc, err};
    if (!r.format(doc.root, kClipFormat)) return false;
    ClipInput in;
    const Json *g = r.member(doc.root, {}, "guard_band_px");
    if (!g || !r.number(*g, Path{} / "guard_band_px", &in.guardBandPixels)) return false;
    const Json *tris = r.triangles(doc.root);
    if (!tris) return false;
    for (size_t i = 0; i < tris->size(); ++i) {
        const Json &j = (*tris)[i];
        const Path p = Path{} / "triangles" / i;
        uint32_t id = 0;
        const Json *idj = nullptr, *v = nullptr;
        if (!r.object(j, p) || !(idj = r.member(j, p, "id")) || !r.u32(*idj, p / "id", &id) ||
            !(v = r.member(j, p, "v")) || !r.array(*v, p / "v", 3))
            return false;
        in.ids.push_back(id);
        for (size_t k = 0; k < 3; ++k) {
            Vec3 c;
            if (!r.vec3((*v)[k], p / "v" / k, &c)) return false;
            in.view.push_back(c);
        }
    }
    *out = std::move(in);
    return true;
}

// A screen triangle's six fixed-point coordinates.
bool readXy(const Reader &r, const Json &j, const Path &p, ScreenTriangles &st) {
    if (!r.array(j, p, 6)) return false;
    for (size_t k = 0; k < 6; ++k) {
        int32_t c = 0;
        if (!r.i32(j[k], p / k, &c)) return false;
        st.xy.push_back(c);
    }
    return true;
}
bool readPlane(const Reader &r, const Json &j, const Path &p, DepthPlane *out) {
    if (!r.array(j, p, 3) || !r.number(j[0], p / 0, &out->a) || !r.number(j[1], p / 1, &out->b) ||
        !r.number(j[2], p / 2, &out->c))
        return false;
    out->valid = true;
    return true;
}

bool parseZBuffer(const json::Doc &doc, ZBufferInput *out, std::string *err) {
    const Reader r{doc, err};
    if (!r.format(doc.root, kZBufferFormat)) return false;
    const Json *tris = r.triangles(doc.root);
    if (!tris) return false;
    ZBufferInput in;
    ScreenTriangles &st = in.triangles;
    for (size_t i = 0; i < tris->size(); ++i) {
        const Json &j = (*tris)[i];
        const Path p = Path{} / "triangles" / i;
        uint32_t id = 0;
        DepthPlane plane;
        const Json *idj = nullptr, *xy = nullptr, *pl = nullptr;
        if (!r.object(j, p) || !(idj = r.member(j, p, "id")) || !r.u32(*idj, p / "id", &id) ||
            !(xy = r.member(j, p, "xy")) || !readXy(r, *xy, p / "xy", st) || !(pl = r.member(j, p, "plane")) ||
            !readPlane(r, *pl, p / "plane", &plane))
            return false;
        st.source.push_back(id);
        st.plane.push_back(uint32_t(st.planes.size()));
        st.planes.push_back(plane);
    }
    *out = std::move(in);
    return true;
}

bool parsePainter(const json::Doc &doc, PainterInput *out, std::string *err) {
    const Reader r{doc, err};
    if (!r.format(doc.root, kPainterFormat)) return false;
    const Json *tris = r.triangles(doc.root);
    if (!tris) return false;
    PainterInput in;
    for (size_t i = 0; i < tris->size(); ++i) {
        const Json &j = (*tris)[i];
        const Path p = Path{} / "triangles" / i;
        PainterCandidate c;
        bool single = false;
        DepthPlane plane;
        const Json *idj = nullptr, *dj = nullptr, *sj = nullptr, *pl = nullptr, *sc = nullptr;
        if (!r.object(j, p) || !(idj = r.member(j, p, "id")) || !r.u32(*idj, p / "id", &c.source) ||
            !(dj = r.member(j, p, "depths")) || !r.array(*dj, p / "depths", 3) ||
            !(sj = r.member(j, p, "single_sided")) || !r.boolean(*sj, p / "single_sided", &single) ||
            !(pl = r.member(j, p, "plane")) || !readPlane(r, *pl, p / "plane", &plane) ||
            !(sc = r.member(j, p, "screen")) || !r.array(*sc, p / "screen"))
            return false;
        for (size_t k = 0; k < 3; ++k)
            if (!r.number((*dj)[k], p / "depths" / k, &c.depth[k])) return false;
        if (!in.candidates.empty() && c.source <= in.candidates.back().source)
            return r.fail(p / "id", "ids must ascend (this one follows " + std::to_string(in.candidates.back().source) + ")");
        if (sc->empty()) return r.fail(p / "screen", "a triangle here has at least one screen triangle");
        const uint32_t pi = uint32_t(in.screen.planes.size());
        in.screen.planes.push_back(plane);
        for (size_t k = 0; k < sc->size(); ++k) {
            if (!readXy(r, (*sc)[k], p / "screen" / k, in.screen)) return false;
            in.screen.source.push_back(c.source);
            in.screen.plane.push_back(pi);
        }
        in.candidates.push_back(c);
        in.singleSided.push_back(single ? 1 : 0);
    }
    *out = std::move(in);
    return true;
}

// A view object of assignment.json back into a ViewSpec (the keys viewSpecJson writes).
bool parseView(const Reader &r, const Json &j, const Path &p, ViewSpec *out, std::string *dir) {
    if (!r.object(j, p)) return false;
    ViewSpec v;
    CameraSpec &c = v.camera;
    const Json *m;
    if (!(m = r.member(j, p, "name")) || !r.string(*m, p / "name", &v.name)) return false;
    if (!(m = r.member(j, p, "dir")) || !r.string(*m, p / "dir", dir)) return false;
    if (dir->empty() || dir->find('/') != std::string::npos || *dir == "." || *dir == "..")
        return r.fail(p / "dir", "expected a plain folder name");
    if (!(m = r.member(j, p, "eye")) || !r.vec3(*m, p / "eye", &c.eye)) return false;
    if (!(m = r.member(j, p, "target")) || !r.vec3(*m, p / "target", &c.target)) return false;
    if (!(m = r.member(j, p, "up")) || !r.vec3(*m, p / "up", &c.up)) return false;
    if (j.contains("ortho_height")) {
        c.orthographic = true;
        if (!r.number(j["ortho_height"], p / "ortho_height", &c.orthoHeight)) return false;
    } else if (!(m = r.member(j, p, "fov_y")) || !r.number(*m, p / "fov_y", &c.fovYDegrees)) {
        return false;
    }
    if (!(m = r.member(j, p, "near")) || !r.number(*m, p / "near", &c.nearZ)) return false;
    if (!(m = r.member(j, p, "far")) || !r.number(*m, p / "far", &c.farZ)) return false;
    uint32_t w = 0, h = 0;
    if (!(m = r.member(j, p, "width")) || !r.u32(*m, p / "width", &w)) return false;
    if (!(m = r.member(j, p, "height")) || !r.u32(*m, p / "height", &h)) return false;
    if (w < 1 || h < 1 || w > 65536 || h > 65536) return r.fail(p / "width", "width and height must be 1 to 65536");
    c.width = int(w), c.height = int(h);
    std::string f, e;
    if (!(m = r.member(j, p, "depth_format")) || !r.string(*m, p / "depth_format", &f)) return false;
    if (!parseDepthFormat(f, &v.depthFormat, &e)) return r.fail(p / "depth_format", e);
    *out = std::move(v);
    return true;
}

// ---- Answers ----------------------------------------------------------------------------------------

OJson idList(const std::vector<uint32_t> &ids) {
    OJson a = OJson::array();
    for (uint32_t id : ids) a.push_back(id);
    return a;
}

// A Scene holding exactly the input's triangles: one source object for the single-sided ones
// (material 0) and one for the double-sided ones (material 1), each triangle with its own three
// corners. The world planes and the float filter's planes come from the corners alone, so the
// backface stage decides each triangle as it does in the scene the kit was made from.
Scene backfaceScene(const BackfaceInput &in, std::vector<uint32_t> *idOf) {
    SceneBuildInput b;
    Material two;
    two.name = "double_sided";
    two.doubleSided = true;
    b.materials = {Material{}, two};
    b.path = "backface input";
    SceneBuildInput::Object single, both;
    single.name = "single_sided";
    both.name = "double_sided";
    both.material = 1;
    std::vector<uint32_t> singleIds, bothIds;
    for (const BackfaceInput::Triangle &t : in.triangles) {
        SceneBuildInput::Object &o = t.doubleSided ? both : single;
        const uint32_t base = uint32_t(o.geometry.positions.size());
        for (int k = 0; k < 3; ++k) o.geometry.positions.push_back(t.v[k]);
        o.geometry.indices.insert(o.geometry.indices.end(), {base, base + 1, base + 2});
        (t.doubleSided ? bothIds : singleIds).push_back(t.id);
    }
    idOf->assign(singleIds.begin(), singleIds.end());
    idOf->insert(idOf->end(), bothIds.begin(), bothIds.end());
    b.objects.push_back(std::move(single));
    b.objects.push_back(std::move(both));
    return buildScene(std::move(b));
}

}  // namespace

StageAnswer answerBackface(const KitView &v, const BackfaceInput &in) {
    std::vector<uint32_t> idOf;
    const Scene scene = backfaceScene(in, &idOf);
    std::vector<uint32_t> objects(scene.objects.size());
    for (uint32_t i = 0; i < objects.size(); ++i) objects[i] = i;
    const BackfaceResult b = cullBackfaces(scene, objects, v.cam);
    std::vector<uint32_t> kept, culled, edgeOn;
    for (uint32_t t : b.kept.triangles) kept.push_back(idOf[t]);
    for (uint32_t t : b.culled) {
        culled.push_back(idOf[t]);
        bool e = false;
        isFrontFacing(scene, t, v.cam, &e);
        if (e) edgeOn.push_back(idOf[t]);
    }
    std::sort(kept.begin(), kept.end());
    std::sort(culled.begin(), culled.end());
    std::sort(edgeOn.begin(), edgeOn.end());
    StageAnswer a;
    a.stage = Stage::backface;
    OJson &j = a.answer;
    j["triangles_in"] = in.triangles.size();
    j["triangles_tested"] = b.stats.trianglesTested;
    j["triangles_culled"] = b.stats.trianglesCulled;
    j["double_sided_exempt"] = b.stats.doubleSidedExempt;
    j["edge_on"] = b.stats.edgeOn;
    j["triangles_out"] = kept.size();
    j["kept"] = idList(kept);
    a.extra["culled"] = idList(culled);
    a.extra["edge_on"] = idList(edgeOn);
    return a;
}

StageAnswer answerClip(const KitView &v, const ClipInput &in, ScreenTriangles *screen) {
    ClipSettings cs;
    cs.guardBandPixels = in.guardBandPixels;
    std::vector<ClipPolygon> polygons;
    ClipResult c = clipViewTriangles(v.cam, in.view, in.ids, cs, &polygons);
    const ClipStats &s = c.stats;
    StageAnswer a;
    a.stage = Stage::clip;
    OJson &j = a.answer;
    j["triangles_in"] = s.trianglesIn;
    j["trivially_rejected"] = s.trivialRejected;
    j["inside"] = s.inside;
    j["guard_band_accepted"] = s.guardBandAccepted;
    j["clipped"] = s.clipped;
    j["clipped_away"] = s.clippedAway;
    j["edge_on"] = s.edgeOn;
    OJson planes;
    for (int p = 0; p < kClipPlaneCount; ++p) planes[kClipPlaneNames[p]] = s.perPlane[size_t(p)];
    j["per_plane"] = planes;
    OJson poly;
    for (int k = 3; k <= 9; ++k) poly[k == 9 ? std::string("9+") : std::to_string(k)] = s.polygonVertices[size_t(k)];
    j["polygon_vertices"] = poly;
    j["triangles_out"] = s.trianglesOut;
    OJson list = OJson::array();
    for (const ClipPolygon &p : polygons) {
        OJson vs = OJson::array();
        for (const ClipVertex &cv : p.vertices) vs.push_back({cv.x, cv.y, cv.w, cv.d});
        list.push_back({{"id", p.source}, {"vertices", std::move(vs)}});
    }
    j["polygons"] = std::move(list);
    if (screen) *screen = std::move(c.out);
    return a;
}

StageAnswer answerZBuffer(const KitView &v, const ZBufferInput &in) {
    ZBufferSettings zs;
    zs.encoder = makeDepthEncoder(v.spec.depthFormat, v.cam.nearZ, v.cam.farZ);
    zs.orthographic = v.cam.orthographic;
    ZBufferResult z = rasterize(in.triangles, v.cam.width, v.cam.height, zs);
    const ZBufferStats &s = z.stats;
    StageAnswer a;
    a.stage = Stage::zbuffer;
    OJson &j = a.answer;
    j["triangles_in"] = s.trianglesIn;
    j["triangles_drawn"] = s.trianglesDrawn;
    j["triangles_empty"] = s.trianglesEmpty;
    j["fragments"] = s.fragments;
    j["depth_passes"] = s.depthPasses;
    j["out_of_range_fragments"] = s.outOfRangeFragments;
    j["covered_pixels"] = s.coveredPixels;
    j["overdraw"] = s.overdraw;
    j["depth_complexity"] = s.depthComplexity;
    j["max_depth_complexity"] = s.maxDepthComplexity;
    OJson h = OJson::array();
    for (uint64_t c : s.histogram) h.push_back(c);
    j["histogram"] = std::move(h);
    a.ids = std::move(z.buffer.id);
    a.width = v.cam.width;
    a.height = v.cam.height;
    return a;
}

StageAnswer answerPainter(const KitView &v, const PainterInput &in, PainterKey key) {
    // The ordering audit's view of these triangles: their screen triangles, per source id.
    OrderingView ov;
    ov.cam = v.cam;
    ov.all = in.screen;
    uint32_t n = 0;
    for (const PainterCandidate &c : in.candidates) n = std::max(n, c.source + 1);
    ov.screenBegin.assign(n, 0);
    ov.screenEnd.assign(n, 0);
    ov.singleSided.assign(n, 0);
    for (size_t t = 0; t < ov.all.size(); ++t) {
        const uint32_t s = ov.all.source[t];
        if (ov.screenEnd[s] == ov.screenBegin[s]) ov.screenBegin[s] = uint32_t(t);
        ov.screenEnd[s] = uint32_t(t + 1);
    }
    for (size_t c = 0; c < in.candidates.size(); ++c) ov.singleSided[in.candidates[c].source] = in.singleSided[c];

    const std::vector<uint32_t> order = painterOrder(in.candidates, key);
    std::vector<DrawItem> items(order.size());
    for (size_t i = 0; i < order.size(); ++i) items[i].source = order[i];
    StageAnswer a;
    a.stage = Stage::painter;
    UninitVector<uint32_t> ids;
    const DrawStats st = drawInOrder(ov, items, false, nullptr, nullptr, &ids);
    a.ids.assign(ids.begin(), ids.end());
    OJson &j = a.answer;
    j["triangles_drawn"] = order.size();
    j["fragments"] = st.fragments;
    j["covered_pixels"] = st.coveredPixels;
    j["overdraw"] = st.overdraw;
    j["order"] = idList(order);
    OJson orders;
    for (PainterKey k : {PainterKey::centroid, PainterKey::nearestVertex, PainterKey::farthestVertex})
        orders[painterKeyName(k)] = idList(painterOrder(in.candidates, k));
    a.extra["orders"] = std::move(orders);
    a.width = v.cam.width;
    a.height = v.cam.height;
    return a;
}

OJson viewSpecJson(const ViewSpec &v) {
    const CameraSpec &c = v.camera;
    OJson j;
    j["name"] = v.name;
    j["eye"] = vec(c.eye);
    j["target"] = vec(c.target);
    j["up"] = vec(c.up);
    if (c.orthographic) j["ortho_height"] = c.orthoHeight;
    else j["fov_y"] = c.fovYDegrees;
    j["near"] = c.nearZ;
    j["far"] = c.farZ;
    j["width"] = c.width;
    j["height"] = c.height;
    j["depth_format"] = depthFormatName(v.depthFormat);
    return j;
}

namespace {

std::string inputPath(const std::string &dir, Stage s) { return "views/" + dir + "/" + stageName(s) + ".json"; }

// Parses a text written above and checks that writing the parsed input gives the same text: every
// value read back is the value written, bit for bit (the kit's round trip).
template <class Input, class Parse, class Write>
bool roundTrip(const std::string &file, const std::string &text, Parse parse, Write write, Input *out, std::string *err) {
    json::Doc doc;
    if (!json::parseText(file, text, &doc, err, json::kMaxJsonDepthCeiling) || !parse(doc, out, err)) {
        *err = "internal error: the kit's own " + file + " does not read back: " + *err;
        return false;
    }
    if (write(*out) != text) {
        *err = "internal error: " + file + " read back differs from what was written";
        return false;
    }
    return true;
}

std::string answerText(const KitView &v, const StageAnswer &a, const std::string &image) {
    OJson j;
    j["format"] = kAnswerFormat;
    j["view"] = v.name;
    j["stage"] = stageName(a.stage);
    j["answer"] = a.answer;
    if (!image.empty()) j["images"] = {{"ids", image}};
    if (!a.extra.empty()) j["extra"] = a.extra;
    return prettyText(j);
}

// The submission template's block for a stage: the answer's keys, with null for every number,
// empty lists, and suggested file names for the images.
OJson templateBlock(const StageAnswer &a, const KitView &v, const std::vector<std::string> &images) {
    OJson t;
    for (auto it = a.answer.begin(); it != a.answer.end(); ++it) {
        const OJson &x = it.value();
        if (x.is_object()) {
            OJson o;
            for (auto jt = x.begin(); jt != x.end(); ++jt) o[jt.key()] = nullptr;
            t[it.key()] = o;
        } else if (x.is_array()) {
            t[it.key()] = OJson::array();
        } else {
            t[it.key()] = nullptr;
        }
    }
    if (a.stage == Stage::zbuffer) {
        for (const std::string &im : images) t[im] = v.dir + ".zbuffer." + im + (im == "ids" ? ".png" : ".pfm");
    } else if (a.stage == Stage::painter) {
        t["ids"] = v.dir + ".painter.ids.png";
    }
    return t;
}

struct ViewBuild {
    std::vector<std::pair<std::string, std::string>> kit, answers;
    std::vector<KitFiles::IdImage> images;
    OJson templ;
    std::string err;
    bool ok = false;
};

bool buildView(const Scene &scene, const PreparedScene &ps, const ViewSpec &view, const std::string &dir,
               const PipelineSettings &s, const KitSettings &ks, ViewBuild *out, std::string *err) {
    KitView kv;
    if (!resolveView(view, s, &kv.spec, &kv.cam, err)) return false;
    kv.name = kv.spec.name;
    kv.dir = dir;
    auto wanted = [&](Stage st) { return std::find(ks.stages.begin(), ks.stages.end(), st) != ks.stages.end(); };
    const bool needClip = wanted(Stage::clip) || wanted(Stage::zbuffer);
    const bool needBackface = wanted(Stage::backface) || needClip;
    OJson templ;
    auto emit = [&](Stage st, const std::string &inputText, const StageAnswer &a) {
        if (!wanted(st)) return;
        out->kit.push_back({inputPath(dir, st), inputText});
        std::string image;
        if (!a.ids.empty()) {
            image = std::string(stageName(st)) + ".ids.exr";
            out->images.push_back({"views/" + dir + "/" + image, a.width, a.height, a.ids});
        }
        out->answers.push_back({inputPath(dir, st), answerText(kv, a, image)});
        templ[stageName(st)] = templateBlock(a, kv, ks.images);
    };

    ScreenTriangles screen;
    if (needBackface) {
        // backface: the objects the coarse stages kept, their triangles in submission order.
        BackfaceInput bi;
        for (uint32_t o : objectStagesKept(ps, kv.spec, kv.cam, s)) {
            const SceneObject &ob = scene.objects[o];
            const bool two = scene.materialOf(ob).doubleSided;
            for (uint32_t k = ob.triBegin; k < ob.triEnd; ++k) {
                const uint32_t t = scene.objectTriangles[k];
                BackfaceInput::Triangle tri;
                tri.id = t;
                tri.doubleSided = two;
                for (int c = 0; c < 3; ++c) tri.v[c] = scene.positions[scene.indices[3 * size_t(t) + size_t(c)]];
                bi.triangles.push_back(tri);
            }
        }
        const std::string bt = backfaceText(kv, bi);
        BackfaceInput b2;
        if (!roundTrip(inputPath(dir, Stage::backface), bt, parseBackface,
                       [&](const BackfaceInput &x) { return backfaceText(kv, x); }, &b2, err))
            return false;
        const StageAnswer ba = answerBackface(kv, b2);
        emit(Stage::backface, bt, ba);

        if (needClip) {
            // clip: what the reference backface stage kept, in submission order, in view space.
            std::set<uint32_t> kept;
            for (const OJson &id : ba.answer["kept"]) kept.insert(id.get<uint32_t>());
            ClipInput ci;
            ci.guardBandPixels = ks.clip.guardBandPixels;
            for (const BackfaceInput::Triangle &t : b2.triangles) {
                if (!kept.count(t.id)) continue;
                ci.ids.push_back(t.id);
                for (int c = 0; c < 3; ++c) ci.view.push_back(transformPoint(kv.cam.viewFromWorld, t.v[c]));
            }
            const std::string ct = clipText(kv, ci);
            ClipInput c2;
            if (!roundTrip(inputPath(dir, Stage::clip), ct, parseClip, [&](const ClipInput &x) { return clipText(kv, x); },
                           &c2, err))
                return false;
            emit(Stage::clip, ct, answerClip(kv, c2, &screen));
        }
    }
    if (wanted(Stage::zbuffer)) {
        // zbuffer: the reference clipper's screen triangles.
        ZBufferInput zi;
        zi.triangles = std::move(screen);
        const std::string zt = zbufferText(kv, zi);
        ZBufferInput z2;
        if (!roundTrip(inputPath(dir, Stage::zbuffer), zt, parseZBuffer,
                       [&](const ZBufferInput &x) { return zbufferText(kv, x); }, &z2, err))
            return false;
        emit(Stage::zbuffer, zt, answerZBuffer(kv, z2));
    }
    if (wanted(Stage::painter)) {
        // painter: every analysed triangle clipped with no culling (the ordering audit's view).
        const OrderingView ov = prepareOrderingView(scene, kv.cam);
        PainterInput pi;
        pi.candidates = painterCandidates(ov);
        for (const PainterCandidate &c : pi.candidates) {
            pi.singleSided.push_back(ov.singleSided[c.source]);
            for (uint32_t t = ov.screenBegin[c.source]; t < ov.screenEnd[c.source]; ++t) {
                pi.screen.xy.insert(pi.screen.xy.end(), ov.all.xy.begin() + 6 * size_t(t), ov.all.xy.begin() + 6 * size_t(t) + 6);
                pi.screen.source.push_back(c.source);
                pi.screen.plane.push_back(ov.all.plane[t]);
            }
        }
        pi.screen.planes = ov.all.planes;
        const std::string pt = painterText(kv, pi, ks.painterKey);
        PainterInput p2;
        if (!roundTrip(inputPath(dir, Stage::painter), pt, parsePainter,
                       [&](const PainterInput &x) { return painterText(kv, x, ks.painterKey); }, &p2, err))
            return false;
        emit(Stage::painter, pt, answerPainter(kv, p2, ks.painterKey));
    }
    out->templ = std::move(templ);
    return true;
}

}  // namespace

bool buildKit(const Scene &scene, const std::vector<ViewSpec> &views, const std::vector<std::string> &dirs,
              const PipelineSettings &s, const KitSettings &ks, const std::string &sceneLabel, KitFiles *out,
              std::string *err) {
    if (views.empty()) {
        *err = "no views to make a kit for";
        return false;
    }
    // Validate every view before any work (resolveView names the view and the fix).
    for (const ViewSpec &v : views) {
        ViewSpec rv;
        Camera cam;
        if (!resolveView(v, s, &rv, &cam, err)) return false;
    }
    const PreparedScene ps = prepareScene(scene);
    std::vector<ViewBuild> built(views.size());
    tbb::parallel_for(size_t(0), views.size(), [&](size_t i) {
        built[i].ok = buildView(scene, ps, views[i], dirs[i], s, ks, &built[i], &built[i].err);
    });
    for (const ViewBuild &b : built)
        if (!b.ok) {
            *err = b.err;
            return false;
        }

    KitFiles files;
    OJson viewList = OJson::array(), templViews, views1 = OJson::array();
    OJson fingerprints;
    for (size_t i = 0; i < views.size(); ++i) {
        ViewSpec rv;
        Camera cam;
        resolveView(views[i], s, &rv, &cam, err);
        OJson vj = viewSpecJson(rv);
        views1.push_back(vj);
        OJson full;
        full["name"] = rv.name;
        full["dir"] = dirs[i];
        for (auto it = vj.begin(); it != vj.end(); ++it)
            if (it.key() != "name") full[it.key()] = it.value();
        OJson camj;
        camj["right"] = vec(cam.right);
        camj["up"] = vec(cam.up);
        camj["forward"] = vec(cam.forward);
        camj["sx"] = cam.sx;
        camj["sy"] = cam.sy;
        OJson m = OJson::array();
        for (int r = 0; r < 4; ++r) m.push_back({cam.viewFromWorld.m[r][0], cam.viewFromWorld.m[r][1],
                                                 cam.viewFromWorld.m[r][2], cam.viewFromWorld.m[r][3]});
        camj["view_from_world"] = m;
        full["camera"] = camj;
        OJson inputs;
        for (Stage st : ks.stages) inputs[stageName(st)] = inputPath(dirs[i], st);
        full["inputs"] = inputs;
        viewList.push_back(full);
        for (auto &f : built[i].kit) {
            fingerprints[f.first] = fingerprint(f.second);
            files.kit.push_back(std::move(f));
        }
        for (auto &f : built[i].answers) files.answers.push_back(std::move(f));
        for (auto &im : built[i].images) files.answerImages.push_back(std::move(im));
        templViews[rv.name] = built[i].templ;
    }
    OJson stages = OJson::array();
    for (Stage st : ks.stages) stages.push_back(stageName(st));
    OJson images = OJson::array();
    for (const std::string &im : ks.images) images.push_back(im);

    OJson a;
    a["format"] = kAssignmentFormat;
    a["tool"] = {{"name", "visaudit"}, {"version", VISAUDIT_VERSION}};
    a["scene"] = {{"source", sceneLabel},
                  {"file", "scene.obj"},
                  {"source_triangles", scene.triangleCount()},
                  {"triangles", scene.objectTriangles.size()}};
    a["stages"] = stages;
    a["painter_key"] = painterKeyName(ks.painterKey);
    a["images"] = images;
    a["views"] = viewList;
    a["submission_template"] = "template/submission.json";
    const std::string assignment = prettyText(a);

    OJson templ;
    templ["format"] = kSubmissionFormat;
    templ["student"] = "";
    templ["views"] = templViews;

    OJson answers;
    answers["format"] = kAnswersFormat;
    answers["tool"] = a["tool"];
    answers["assignment"] = fingerprint(assignment);
    answers["stages"] = stages;
    answers["kit_files"] = fingerprints;
    // The answer files' own fingerprints: the grader trusts their shape only as written here.
    OJson answerPrints;
    for (const auto &f : files.answers) answerPrints[f.first] = fingerprint(f.second);
    answers["answer_files"] = answerPrints;

    std::vector<std::pair<std::string, std::string>> kitFiles;
    kitFiles.push_back({"assignment.json", assignment});
    kitFiles.push_back({"README.md", kitReadme(a, ks)});
    std::vector<DepthFormatSpec> formats;
    for (const ViewSpec &v : views) {
        ViewSpec rv;
        Camera cam;
        resolveView(v, s, &rv, &cam, err);
        if (std::find(formats.begin(), formats.end(), rv.depthFormat) == formats.end()) formats.push_back(rv.depthFormat);
    }
    kitFiles.push_back({"CONVENTIONS.md", kitConventions(ks, formats)});
    kitFiles.push_back({"scene.obj", sceneObj(scene, sceneLabel)});
    kitFiles.push_back({"views.json", prettyText(OJson{{"views", views1}})});
    kitFiles.push_back({"template/submission.json", templ.dump(2, ' ', false, OJson::error_handler_t::replace) + "\n"});
    for (auto &f : files.kit) kitFiles.push_back(std::move(f));
    files.kit = std::move(kitFiles);
    files.answers.insert(files.answers.begin(), {"answers.json", prettyText(answers)});
    *out = std::move(files);
    return true;
}

// ---- Reading a kit ----------------------------------------------------------------------------------

namespace {
using Loader = std::function<bool(const std::string &rel, std::string *text)>;

bool readKitWith(const std::string &dir, const Loader &load, Kit *out, std::string *err, uint64_t maxJsonDepth) {
    auto fileName = [&](const std::string &rel) { return (std::filesystem::path(dir) / rel).string(); };
    auto text = [&](const std::string &rel, json::Doc *doc) -> bool {
        std::string t;
        if (!load(rel, &t)) {
            *err = fileName(rel) + ": file not found; the kit is incomplete (make it again with visaudit assignment)";
            return false;
        }
        return json::parseText(fileName(rel), std::move(t), doc, err, maxJsonDepth);
    };
    json::Doc doc;
    if (!text("assignment.json", &doc)) return false;
    const Reader r{doc, err};
    if (!r.format(doc.root, kAssignmentFormat)) return false;
    Kit kit;
    kit.dir = dir;
    const Json *m;
    if (!(m = r.member(doc.root, {}, "stages")) || !r.array(*m, Path{} / "stages")) return false;
    for (size_t i = 0; i < m->size(); ++i) {
        std::string name;
        if (!r.string((*m)[i], Path{} / "stages" / i, &name)) return false;
        std::vector<Stage> one;
        std::string e;
        if (!parseStageList(name, &one, &e) || one.size() != 1) return r.fail(Path{} / "stages" / i, e);
        if (kit.has(one[0])) return r.fail(Path{} / "stages" / i, "stage listed twice");
        kit.stages.push_back(one[0]);
    }
    std::string key;
    if (!(m = r.member(doc.root, {}, "painter_key")) || !r.string(*m, Path{} / "painter_key", &key)) return false;
    if (key == "centroid") kit.painterKey = PainterKey::centroid;
    else if (key == "nearest_vertex") kit.painterKey = PainterKey::nearestVertex;
    else if (key == "farthest_vertex") kit.painterKey = PainterKey::farthestVertex;
    else return r.fail(Path{} / "painter_key", "expected centroid, nearest_vertex or farthest_vertex");
    if (!(m = r.member(doc.root, {}, "images")) || !r.array(*m, Path{} / "images")) return false;
    for (size_t i = 0; i < m->size(); ++i) {
        std::string im;
        if (!r.string((*m)[i], Path{} / "images" / i, &im)) return false;
        if (im != "ids" && im != "depth") return r.fail(Path{} / "images" / i, "expected \"ids\" or \"depth\"");
        kit.images.push_back(im);
    }
    const Json *sc = r.member(doc.root, {}, "scene");
    if (!sc || !r.object(*sc, Path{} / "scene")) return false;
    uint32_t src = 0;
    if (!(m = r.member(*sc, Path{} / "scene", "source_triangles")) || !r.u32(*m, Path{} / "scene" / "source_triangles", &src))
        return false;
    kit.sourceTriangles = src;
    if (!(m = r.member(doc.root, {}, "views")) || !r.array(*m, Path{} / "views")) return false;
    std::set<std::string> dirs;
    for (size_t i = 0; i < m->size(); ++i) {
        KitView kv;
        const Path p = Path{} / "views" / i;
        if (!parseView(r, (*m)[i], p, &kv.spec, &kv.dir)) return false;
        if (!dirs.insert(kv.dir).second) return r.fail(p / "dir", "two views share the folder '" + kv.dir + "'");
        kv.name = kv.spec.name;
        std::string e;
        if (!makeCamera(kv.spec.camera, &kv.cam, &e)) return r.fail(p, e);
        kit.views.push_back(std::move(kv));
    }
    kit.fingerprints.clear();
    for (KitView &kv : kit.views) {
        for (Stage st : kit.stages) {
            const std::string rel = inputPath(kv.dir, st);
            json::Doc d;
            if (!text(rel, &d)) return false;
            kit.fingerprints[rel] = fingerprint(d.text);
            bool ok = false;
            switch (st) {
            case Stage::backface: ok = parseBackface(d, &kv.backface.emplace(), err); break;
            case Stage::clip: ok = parseClip(d, &kv.clip.emplace(), err); break;
            case Stage::zbuffer: ok = parseZBuffer(d, &kv.zbuffer.emplace(), err); break;
            case Stage::painter: ok = parsePainter(d, &kv.painter.emplace(), err); break;
            }
            if (!ok) return false;
        }
    }
    // Ids past the scene's triangles would index past the grader's per-triangle tables.
    for (const KitView &kv : kit.views) {
        auto bad = [&](uint32_t id, Stage st) {
            *err = fileName(inputPath(kv.dir, st)) + ": triangle id " + std::to_string(id) +
                   " is not below the scene's " + std::to_string(kit.sourceTriangles) +
                   " triangles (assignment.json scene.source_triangles); the kit was edited: make it again";
            return false;
        };
        if (kv.backface)
            for (const auto &t : kv.backface->triangles)
                if (t.id >= kit.sourceTriangles) return bad(t.id, Stage::backface);
        if (kv.clip)
            for (uint32_t id : kv.clip->ids)
                if (id >= kit.sourceTriangles) return bad(id, Stage::clip);
        if (kv.zbuffer)
            for (uint32_t id : kv.zbuffer->triangles.source)
                if (id >= kit.sourceTriangles) return bad(id, Stage::zbuffer);
        if (kv.painter)
            for (const PainterCandidate &c : kv.painter->candidates)
                if (c.source >= kit.sourceTriangles) return bad(c.source, Stage::painter);
    }
    *out = std::move(kit);
    return true;
}

}  // namespace

bool readKitFiles(const std::string &dir, const std::map<std::string, std::string> &files, Kit *out, std::string *err,
                  uint64_t maxJsonDepth) {
    return readKitWith(
        dir,
        [&](const std::string &rel, std::string *t) {
            auto it = files.find(rel);
            if (it == files.end()) return false;
            *t = it->second;
            return true;
        },
        out, err, maxJsonDepth);
}

bool readKit(const std::string &dir, Kit *out, std::string *err, uint64_t maxJsonDepth) {
    std::error_code ec;
    if (!std::filesystem::is_directory(dir, ec)) {
        *err = dir + ": not a folder; --kit names the folder `visaudit assignment --out` wrote";
        return false;
    }
    if (!std::filesystem::is_regular_file(std::filesystem::path(dir) / "assignment.json", ec)) {
        *err = (std::filesystem::path(dir) / "assignment.json").string() +
               ": file not found; --kit names the folder `visaudit assignment --out` wrote";
        return false;
    }
    return readKitWith(
        dir,
        [&](const std::string &rel, std::string *t) {
            std::ifstream f(std::filesystem::path(dir) / rel, std::ios::binary);
            if (!f) return false;
            std::ostringstream ss;
            ss << f.rdbuf();
            *t = std::move(ss).str();
            return true;
        },
        out, err, maxJsonDepth);
}

}  // namespace va::kit
