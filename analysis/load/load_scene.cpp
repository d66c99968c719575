// Scene JSON (visaudit-scene/1), views files, loadScene's dispatch by extension, and orbit views.
// The format is documented key by key in docs/scene-format.md; every error names the file, the
// line:column, the JSON path and a fix (STYLE 10).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <set>

#include "common/json_util.h"
#include "analysis/load/json_reader.h"
#include "analysis/load/load.h"
#include "analysis/load/load_bsp.h"
#include "analysis/stages/portals.h"

namespace va {
namespace {

using json::Json;
using json::Path;
using load::Reader;
using load::upVector;
using load::kMaxViewSize;

constexpr const char *kSceneFormat = "visaudit-scene/1";

std::string lowerExt(const std::string &path) {
    std::string e = std::filesystem::path(path).extension().string();
    for (auto &c : e) c = char(std::tolower((unsigned char)c));
    return e;
}


// Relative flatness and convexity tolerance of a portal polygon: points may stray from its plane
// (and a corner bend inwards) by this fraction of the polygon's size. An input tolerance, not a
// rounding bound: typed coordinates of a slanted portal carry a few digits, and the stage itself
// treats the deviation conservatively (docs/coarse-stages.md).
constexpr double kPortalFlatness = 1e-6;

// "cells": [{ "name", "min", "max" } or { "name", "planes": [[a, b, c, d], ...] }] and
// "portals": [{ "name", "cells": [A, B], "points": [[x, y, z], ...] }] (docs/scene-format.md).
bool readCellsAndPortals(Reader &r, const Json &root, std::vector<Cell> *cellsOut, std::vector<Portal> *portalsOut) {
    const Path top;
    std::vector<Cell> cells;
    std::map<std::string, uint32_t> cellIndex;
    if (root.contains("cells")) {
        const Path cp = top / "cells";
        if (!root["cells"].is_array()) return r.fail(cp, "expected an array of cells, got " + json::typeName(root["cells"]));
        for (size_t i = 0; i < root["cells"].size(); ++i) {
            const Path p = cp / i;
            const Json &j = root["cells"][i];
            if (!r.object(j, p) || !r.checkKeys(j, p, {"name", "min", "max", "planes"})) return false;
            Cell c;
            c.name = "cell" + std::to_string(i);
            if (j.contains("name") && !r.string(j["name"], p / "name", &c.name)) return false;
            if (c.name.empty()) return r.fail(p / "name", "a cell name cannot be empty");
            const bool hasBox = j.contains("min") || j.contains("max");
            if (hasBox && j.contains("planes"))
                return r.fail(p / "planes", "give either \"min\" and \"max\" (a box) or \"planes\" (a convex cell), not both", true);
            if (hasBox) {
                if (!j.contains("min") || !j.contains("max"))
                    return r.fail(p, std::string("missing \"") + (j.contains("min") ? "max" : "min") +
                                         "\": a box cell needs both corners, e.g. \"min\": [0, 0, 0], \"max\": [10, 4, 10]");
                Vec3 lo, hi;
                if (!r.vec3(j["min"], p / "min", &lo) || !r.vec3(j["max"], p / "max", &hi)) return false;
                for (int a = 0; a < 3; ++a)
                    if (!(lo[a] < hi[a]))
                        return r.fail(p / "max" / size_t(a), "must be greater than min[" + std::to_string(a) + "] (" +
                                                                  json::Json(lo[a]).dump() + "): a cell has a volume");
                c = boxCell(c.name, lo, hi);
            } else if (j.contains("planes")) {
                const Path pp = p / "planes";
                const Json &pl = j["planes"];
                if (!pl.is_array() || pl.size() < 4)
                    return r.fail(pp, "expected an array of at least 4 planes [a, b, c, d] (a x + b y + c z + d >= 0 inside), got " +
                                          (pl.is_array() ? "an array of " + std::to_string(pl.size()) : json::typeName(pl)));
                for (size_t k = 0; k < pl.size(); ++k) {
                    const Json &q = pl[k];
                    if (!q.is_array() || q.size() != 4)
                        return r.fail(pp / k, "expected a plane [a, b, c, d] (a x + b y + c z + d >= 0 inside), got " +
                                                  (q.is_array() ? "an array of " + std::to_string(q.size()) : json::typeName(q)));
                    double v[4];
                    for (size_t m = 0; m < 4; ++m)
                        if (!r.number(q[m], pp / k / m, &v[m])) return false;
                    const Vec3 n{v[0], v[1], v[2]};
                    const double len = length(n);
                    if (!(len > 0)) return r.fail(pp / k, "has a zero normal (a, b, c); give the direction pointing into the cell");
                    c.faces.push_back({n / len, v[3] / len});
                }
            } else {
                return r.fail(p, "missing the cell's shape: \"min\" and \"max\" (a box) or \"planes\" (a convex cell)");
            }
            auto [it, fresh] = cellIndex.insert({c.name, uint32_t(i)});
            if (!fresh)
                return r.fail(j.contains("name") ? p / "name" : p,
                              "duplicate cell name '" + c.name + "' (also " + json::pathString(cp / it->second) + "); cell names must be unique");
            cells.push_back(std::move(c));
        }
    }
    std::vector<Portal> portals;
    if (root.contains("portals")) {
        const Path pp = top / "portals";
        if (!root["portals"].is_array()) return r.fail(pp, "expected an array of portals, got " + json::typeName(root["portals"]));
        if (cells.empty() && !root["portals"].empty())
            return r.fail(pp, "portals join cells, but the scene has no \"cells\"; add the cells they join");
        std::vector<std::string> names;
        for (const Cell &c : cells) names.push_back(c.name);
        for (size_t i = 0; i < root["portals"].size(); ++i) {
            const Path p = pp / i;
            const Json &j = root["portals"][i];
            if (!r.object(j, p) || !r.checkKeys(j, p, {"name", "cells", "points"})) return false;
            Portal po;
            po.name = "portal" + std::to_string(i);
            if (j.contains("name") && !r.string(j["name"], p / "name", &po.name)) return false;
            if (!j.contains("cells")) return r.fail(p, "missing \"cells\": the two cells it joins, e.g. \"cells\": [\"hall\", \"kitchen\"]");
            const Json &cj = j["cells"];
            if (!cj.is_array() || cj.size() != 2)
                return r.fail(p / "cells", "expected the names of the 2 cells it joins, got " +
                                               (cj.is_array() ? "an array of " + std::to_string(cj.size()) : json::typeName(cj)));
            for (size_t k = 0; k < 2; ++k) {
                std::string n;
                if (!r.string(cj[k], p / "cells" / k, &n)) return false;
                auto it = cellIndex.find(n);
                if (it == cellIndex.end()) {
                    const std::string near = json::closest(n, names);
                    return r.fail(p / "cells" / k, "cell '" + n + "' is not defined in \"cells\"" +
                                                       (near.empty() ? "; defined: " + json::joinList(names) : "; did you mean '" + near + "'?"));
                }
                po.cells[k] = it->second;
            }
            if (po.cells[0] == po.cells[1])
                return r.fail(p / "cells" / size_t(1), "a portal joins two different cells; both are '" + cells[po.cells[0]].name + "'");
            if (!j.contains("points")) return r.fail(p, "missing \"points\": the portal polygon's corners in order (3 or more, coplanar, convex)");
            const Json &pj = j["points"];
            if (!pj.is_array() || pj.size() < 3)
                return r.fail(p / "points", "expected an array of 3 or more points (the polygon's corners in order), got " +
                                                (pj.is_array() ? "an array of " + std::to_string(pj.size()) : json::typeName(pj)));
            for (size_t k = 0; k < pj.size(); ++k) {
                Vec3 v;
                if (!r.vec3(pj[k], p / "points" / k, &v)) return false;
                po.points.push_back(v);
            }
            // Shape: non-zero area, flat and convex within kPortalFlatness of its size.
            const size_t m = po.points.size();
            Vec3 N{0, 0, 0}, c{0, 0, 0};
            double size = 0;
            for (size_t k = 0; k < m; ++k) {
                const Vec3 &a = po.points[k], &b = po.points[(k + 1) % m];
                N = N + cross(a, b);
                c = c + a;
                size = std::max(size, length(b - a));
            }
            c = c / double(m);
            if (!(length(N) > kPortalFlatness * size * size))
                return r.fail(p / "points", "the polygon has no area (its points are collinear or repeated)");
            N = normalize(N);
            for (size_t k = 0; k < m; ++k) {
                const double off = std::fabs(dot(N, po.points[k] - c));
                if (off > kPortalFlatness * size)
                {
                    char buf[96];
                    std::snprintf(buf, sizeof buf, "is %g off the portal's plane; a portal is flat (points within %g of its size)", off,
                                  kPortalFlatness);
                    return r.fail(p / "points" / k, buf);
                }
                const Vec3 &a = po.points[k], &b = po.points[(k + 1) % m], &d = po.points[(k + 2) % m];
                if (dot(N, cross(b - a, d - b)) < -kPortalFlatness * size * size)
                    return r.fail(p / "points" / ((k + 1) % m), "bends the polygon inwards; a portal is convex (list its corners in order "
                                                                "around it; split a concave opening into several portals)");
            }
            portals.push_back(std::move(po));
        }
    }
    *cellsOut = std::move(cells);
    *portalsOut = std::move(portals);
    return true;
}

// "materials": index 0 is "default"; a material named "default" redefines it.
bool readMaterials(Reader &r, const Json &root, const Path &top, std::vector<Material> *materials,
                   std::map<std::string, uint32_t> *materialIndex, std::string *err) {
    auto failed = [&] {
        *err = r.err;
        return false;
    };
    materials->push_back(Material{});
    (*materialIndex)["default"] = 0;
    if (root.contains("materials")) {
        const Path mp = top / "materials";
        if (!r.object(root["materials"], mp)) return failed();
        for (auto it = root["materials"].begin(); it != root["materials"].end(); ++it) {
            const Path p = mp / it.key();
            const Json &j = it.value();
            if (!r.object(j, p) || !r.checkKeys(j, p, {"double_sided", "alpha", "reflective", "ior"})) return failed();
            Material m;
            m.name = it.key();
            if (j.contains("double_sided") && !r.boolean(j["double_sided"], p / "double_sided", &m.doubleSided)) return failed();
            if (j.contains("alpha")) {
                if (!r.number(j["alpha"], p / "alpha", &m.alpha)) return failed();
                if (m.alpha < 0 || m.alpha > 1) {
                    r.fail(p / "alpha", "must be between 0 (invisible) and 1 (opaque)");
                    return failed();
                }
            }
            if (j.contains("reflective")) {
                if (!r.number(j["reflective"], p / "reflective", &m.reflective)) return failed();
                if (m.reflective < 0 || m.reflective > 1) {
                    r.fail(p / "reflective", "must be between 0 (not reflective) and 1 (a mirror)");
                    return failed();
                }
            }
            if (j.contains("ior")) {
                if (!r.number(j["ior"], p / "ior", &m.ior)) return failed();
                if (!(m.ior > 0)) {
                    r.fail(p / "ior", "must be > 0 (1 = not refractive; glass is about 1.5)");
                    return failed();
                }
            }
            if (m.name == "default") {
                (*materials)[0] = m;
            } else {
                (*materialIndex)[m.name] = uint32_t(materials->size());
                materials->push_back(m);
            }
        }
    }
    return true;
}

// One object of "objects" (at `p`): its mesh loaded (relative to the scene file's folder; each file
// read once, through `meshCache`) and world = T * R * S applied. `triangles` counts the objects' so
// far: each object copies its mesh, so a small file instancing a large mesh many times is refused
// before the copies.
bool readObject(Reader &r, const json::Doc &doc, const Json &j, const Path &p, const std::filesystem::path &folder,
                const LoadOptions &opt, const std::map<std::string, uint32_t> &materialIndex,
                std::map<std::string, RawMesh> &meshCache, uint64_t *trianglesSoFar, SceneBuildInput::Object *out,
                std::string *err) {
    auto failed = [&] {
        *err = r.err;
        return false;
    };
    if (!r.object(j, p) ||
        !r.checkKeys(j, p, {"name", "mesh", "material", "translate", "rotate_deg", "scale"}))
        return failed();
    SceneBuildInput::Object &o = *out;
    if (!j.contains("mesh")) {
        r.fail(p, "missing \"mesh\": give the mesh file (relative to the scene file), e.g. \"mesh\": \"meshes/hall.obj\"");
        return failed();
    }
    if (!r.string(j["mesh"], p / "mesh", &o.mesh)) return failed();
    o.name = std::filesystem::path(o.mesh).stem().string();
    if (j.contains("name") && !r.string(j["name"], p / "name", &o.name)) return failed();
    if (j.contains("material")) {
        std::string mn;
        if (!r.string(j["material"], p / "material", &mn)) return failed();
        auto it = materialIndex.find(mn);
        if (it == materialIndex.end()) {
            std::vector<std::string> names;
            for (const auto &[n, _] : materialIndex) names.push_back(n);
            const std::string near = json::closest(mn, names);
            r.fail(p / "material", "material '" + mn + "' is not defined in \"materials\"" +
                                       (near.empty() ? "; defined: " + json::joinList(names)
                                                     : "; did you mean '" + near + "'?"));
            return failed();
        }
        o.material = it->second;
    }
    Vec3 t{0, 0, 0}, rot{0, 0, 0}, s{1, 1, 1};
    if (j.contains("translate") && !r.vec3(j["translate"], p / "translate", &t)) return failed();
    if (j.contains("rotate_deg") && !r.vec3(j["rotate_deg"], p / "rotate_deg", &rot)) return failed();
    if (j.contains("scale")) {
        const Json &sj = j["scale"];
        if (sj.is_number()) {
            double k = 0;
            if (!r.number(sj, p / "scale", &k)) return failed();
            s = {k, k, k};
        } else if (sj.is_array()) {
            if (!r.vec3(sj, p / "scale", &s)) return failed();
        } else {
            r.fail(p / "scale", "expected a number or an array of 3 numbers, got " + json::typeName(sj));
            return failed();
        }
    }
    // Load (or reuse) the mesh.
    std::filesystem::path mp(o.mesh);
    const std::string file = (mp.is_absolute() ? mp : folder / mp).lexically_normal().string();
    auto cached = meshCache.find(file);
    const bool firstUse = cached == meshCache.end();
    if (firstUse) {
        RawMesh m;
        std::string e;
        if (!loadMeshFile(file, &m, &e)) {
            *err = json::where(doc, p / "mesh") + ": " + json::pathString(p / "mesh") + ": cannot load mesh '" +
                   o.mesh + "' of object '" + o.name + "': " + e;
            return false;
        }
        cached = meshCache.emplace(file, std::move(m)).first;
    }
    *trianglesSoFar += cached->second.indices.size() / 3;
    if (!checkTriangleLimit(*trianglesSoFar, opt.maxTriangles,
                            json::where(doc, p) + ": the scene up to object '" + o.name + "'", err))
        return false;
    o.geometry = cached->second;
    if (!firstUse) o.geometry.warnings.clear();  // reported once, with the first object using the mesh
    const Mat4 worldFromObject = Mat4::translate(t) * Mat4::rotateXYZDegrees(rot) * Mat4::scale(s);
    for (auto &v : o.geometry.positions) v = transformPoint(worldFromObject, v);
    // The mesh's own coordinates are finite (loadMeshFile refuses others): a non-finite one now
    // comes from the transform overflowing. Point at the key that scales or moves the most.
    for (size_t k = 0; k < o.geometry.positions.size(); ++k) {
        if (isFinite(o.geometry.positions[k])) continue;
        const char *key = j.contains("scale") ? "scale" : j.contains("translate") ? "translate" : "rotate_deg";
        r.fail(p / key, "the transform maps vertex " + std::to_string(k) + " of '" + o.mesh +
                            "' (counting from 0) to a non-finite position; use a smaller scale or translation");
        return failed();
    }
    // An odd number of negative scale factors mirrors the mesh, turning counter-clockwise into
    // clockwise: swap two corners so the front face stays counter-clockwise.
    if (s.x * s.y * s.z < 0)
        for (size_t k = 0; k + 2 < o.geometry.indices.size(); k += 3) std::swap(o.geometry.indices[k + 1], o.geometry.indices[k + 2]);
    return true;
}

// "objects": every object, in order.
bool readObjects(Reader &r, const json::Doc &doc, const Json &root, const Path &top, const std::string &path,
                 const LoadOptions &opt, const std::map<std::string, uint32_t> &materialIndex,
                 std::vector<SceneBuildInput::Object> *objects, std::string *err) {
    auto failed = [&] {
        *err = r.err;
        return false;
    };
    if (!root.contains("objects")) {
        *err = json::where(doc, top) + ": missing \"objects\": list the scene's meshes, e.g. \"objects\": "
               "[{ \"name\": \"hall\", \"mesh\": \"meshes/hall.obj\" }]";
        return false;
    }
    const Path op = top / "objects";
    if (!root["objects"].is_array()) {
        r.fail(op, "expected an array of objects, got " + json::typeName(root["objects"]));
        return failed();
    }
    const std::filesystem::path folder = std::filesystem::path(path).parent_path();
    std::map<std::string, RawMesh> meshCache;
    uint64_t triangles = 0;  // of the objects so far: each object copies its mesh, so a small file
                             //   instancing a large mesh many times is refused before the copies
    for (size_t i = 0; i < root["objects"].size(); ++i) {
        SceneBuildInput::Object o;
        if (!readObject(r, doc, root["objects"][i], op / i, folder, opt, materialIndex, meshCache, &triangles, &o, err))
            return false;
        objects->push_back(std::move(o));
    }
    return true;
}

// "lights": directional (a direction) or point (a position).
bool readLights(Reader &r, const Json &root, const Path &top, std::vector<Light> *lights, std::string *err) {
    auto failed = [&] {
        *err = r.err;
        return false;
    };
    if (root.contains("lights")) {
        const Path lp = top / "lights";
        if (!root["lights"].is_array()) {
            r.fail(lp, "expected an array of lights, got " + json::typeName(root["lights"]));
            return failed();
        }
        for (size_t i = 0; i < root["lights"].size(); ++i) {
            const Path p = lp / i;
            const Json &j = root["lights"][i];
            if (!r.object(j, p) || !r.checkKeys(j, p, {"name", "type", "direction", "position"})) return failed();
            Light l;
            l.name = "light" + std::to_string(i);
            if (j.contains("name") && !r.string(j["name"], p / "name", &l.name)) return failed();
            std::string type;
            if (!j.contains("type")) {
                r.fail(p, "missing \"type\": \"directional\" or \"point\"");
                return failed();
            }
            if (!r.string(j["type"], p / "type", &type)) return failed();
            if (type == "directional") {
                if (j.contains("position")) {
                    r.fail(p / "position", "a directional light has no position; use \"direction\" (or \"type\": \"point\")", true);
                    return failed();
                }
                if (!j.contains("direction")) {
                    r.fail(p, "missing \"direction\" (the direction the light travels, e.g. [-1, -2, -1])");
                    return failed();
                }
                if (!r.vec3(j["direction"], p / "direction", &l.direction)) return failed();
                if (l.direction == Vec3{0, 0, 0}) {
                    r.fail(p / "direction", "has zero length");
                    return failed();
                }
            } else if (type == "point") {
                l.directional = false;
                if (j.contains("direction")) {
                    r.fail(p / "direction", "a point light has no direction; use \"position\" (or \"type\": \"directional\")", true);
                    return failed();
                }
                if (!j.contains("position")) {
                    r.fail(p, "missing \"position\" of the point light");
                    return failed();
                }
                if (!r.vec3(j["position"], p / "position", &l.position)) return failed();
            } else {
                r.fail(p / "type", "unknown light type \"" + type + "\"; use \"directional\" or \"point\"");
                return failed();
            }
            lights->push_back(l);
        }
    }
    return true;
}

bool loadSceneJson(const std::string &path, const LoadOptions &opt, Scene *out, std::string *err) {
    json::Doc doc;
    if (!json::parseFile(path, &doc, err, opt.maxJsonDepth)) return false;
    Reader r{doc, {}};
    auto failed = [&] {
        *err = r.err;
        return false;
    };
    const Json &root = doc.root;
    const Path top;
    if (!root.is_object()) {
        *err = json::where(doc, top) + ": expected a JSON object with \"format\": \"" + kSceneFormat + "\", got " + json::typeName(root);
        return false;
    }
    if (!r.checkKeys(root, top, {"format", "up", "materials", "objects", "lights", "views", "cells", "portals"}))
        return failed();
    if (!root.contains("format")) {
        *err = json::where(doc, top) + ": missing \"format\": add \"format\": \"" + kSceneFormat + "\"";
        return false;
    }
    std::string format;
    if (!r.string(root["format"], top / "format", &format)) return failed();
    if (format != kSceneFormat) {
        r.fail(top / "format", "unsupported format \"" + format + "\"; this visaudit reads \"" + kSceneFormat + "\"");
        return failed();
    }

    SceneBuildInput in;
    in.path = path;
    if (root.contains("up") && !r.upAxis(root["up"], top / "up", &in.up)) return failed();

    std::map<std::string, uint32_t> materialIndex;
    if (!readMaterials(r, root, top, &in.materials, &materialIndex, err)) return false;
    if (!readObjects(r, doc, root, top, path, opt, materialIndex, &in.objects, err)) return false;
    if (!readLights(r, root, top, &in.lights, err)) return false;
    if (root.contains("views") && !r.views(root["views"], top / "views", upVector(in.up), "scene", &in.views))
        return failed();

    std::vector<Cell> cells;
    std::vector<Portal> portals;
    if (!readCellsAndPortals(r, root, &cells, &portals)) return failed();

    Scene s;
    std::string e;
    if (!buildScene(std::move(in), opt.chunks, &s, &e)) {
        *err = path + ": " + e;
        return false;
    }
    // Cells need the culling objects (chunks) to exist: each belongs to every cell it overlaps.
    s.cells = std::move(cells);
    s.portals = std::move(portals);
    assignObjectsToCells(s);
    *out = std::move(s);
    return true;
}

}  // namespace

bool loadViewsFile(const std::string &path, char sceneUp, std::vector<ViewSpec> *out, std::string *err,
                   uint64_t maxJsonDepth) {
    json::Doc doc;
    if (!json::parseFile(path, &doc, err, maxJsonDepth)) return false;
    Reader r{doc, {}};
    const Path top;
    if (!doc.root.is_object()) {
        *err = json::where(doc, top) + ": expected a JSON object { \"views\": [ ... ] }, got " + json::typeName(doc.root);
        return false;
    }
    if (!r.checkKeys(doc.root, top, {"up", "views"})) {
        *err = r.err;
        return false;
    }
    char up = sceneUp;
    if (doc.root.contains("up") && !r.upAxis(doc.root["up"], top / "up", &up)) {
        *err = r.err;
        return false;
    }
    if (!doc.root.contains("views")) {
        *err = json::where(doc, top) + ": missing \"views\": a views file is { \"views\": [ { \"eye\": [...], \"target\": [...] } ] }";
        return false;
    }
    std::vector<ViewSpec> views;
    if (!r.views(doc.root["views"], top / "views", upVector(up), path, &views)) {
        *err = r.err;
        return false;
    }
    *out = std::move(views);
    return true;
}

bool loadViewsFile(const std::string &path, std::vector<ViewSpec> *out, std::string *err, uint64_t maxJsonDepth) {
    return loadViewsFile(path, 'y', out, err, maxJsonDepth);
}

bool loadScene(const std::string &path, const LoadOptions &opt, Scene *out, std::string *err) {
    // Quake 3 maps: "x.bsp", or a member of a .pk3 archive, "pak.pk3:maps/x.bsp" (analysis/load/load_bsp.h).
    if (isBspPath(path)) {
        BspOptions bsp = opt.bsp;
        bsp.maxTriangles = opt.maxTriangles;
        return loadBspScene(path, bsp, opt.chunks, out, err);
    }
    const std::string ext = lowerExt(path);
    if (ext == ".json") {
        // Every expected failure returns false; this only turns a library exception we did not
        // foresee into a message instead of letting it cross the loader.
        try {
            return loadSceneJson(path, opt, out, err);
        } catch (const std::exception &e) {
            *err = path + ": internal error while reading the scene: " + e.what();
            return false;
        }
    }
    SceneBuildInput in;
    if (ext == ".obj" || ext == ".ply" || ext == ".off" || ext == ".stl") {
        SceneBuildInput::Object o;
        o.name = std::filesystem::path(path).stem().string();
        o.mesh = path;
        if (!loadMeshFile(path, &o.geometry, err)) return false;
        if (!checkTriangleLimit(o.geometry.indices.size() / 3, opt.maxTriangles, path, err)) return false;
        in.objects.push_back(std::move(o));
        in.path = path;
    } else if (ext == ".gltf" || ext == ".glb") {
        if (!loadGltf(path, &in, err, opt.maxTriangles, opt.maxJsonDepth)) return false;
    } else {
        *err = path + ": unsupported input '" + ext +
               "'; supported: .json (visaudit-scene/1), .obj .ply .off .stl (one mesh), .gltf .glb (glTF 2.0)";
        return false;
    }
    Scene s;
    std::string e;
    if (!buildScene(std::move(in), opt.chunks, &s, &e)) {
        *err = path + ": " + e;
        return false;
    }
    *out = std::move(s);
    return true;
}

std::vector<ViewSpec> orbitViews(const Scene &scene, int n) {
    std::vector<ViewSpec> views;
    if (n < 1) return views;
    // Bounding sphere of the scene's bounds: center and half diagonal (unit sphere at the origin for
    // an empty scene).
    Vec3 c{0, 0, 0};
    double r = 1;
    if (!scene.bounds.empty()) {
        c = scene.bounds.center();
        r = length(scene.bounds.extent()) * 0.5;
        if (!(r > 0)) r = 1;
    }
    // A sphere of radius r fills a vertical fov of 60 degrees at distance r / sin(30 deg); 10% margin.
    const double fov = 60;
    const double dist = r / std::sin(fov * 0.5 * kPi / 180) * 1.1;
    // Horizontal axes (A, B) with (A, B, U) right-handed, so azimuth runs counter-clockwise seen from
    // above: y up -> (z, x), z up -> (x, y), x up -> (y, z).
    const Vec3 U = upVector(scene.up);
    const Vec3 A = scene.up == 'z' ? Vec3{1, 0, 0} : scene.up == 'x' ? Vec3{0, 1, 0} : Vec3{0, 0, 1};
    const Vec3 B = cross(U, A);
    const double elev = 30 * kPi / 180;
    for (int i = 0; i < n; ++i) {
        const double az = 2 * kPi * i / n;
        const Vec3 h = A * std::cos(az) + B * std::sin(az);
        ViewSpec v;
        v.name = "orbit" + std::to_string(i);
        v.origin = "orbit:" + std::to_string(n);
        CameraSpec &s = v.camera;
        s.eye = c + (h * std::cos(elev) + U * std::sin(elev)) * dist;
        s.target = c;
        s.up = U;
        s.fovYDegrees = fov;
        // Everything in the sphere lies at view depth >= dist - r and <= dist + r: near at half the
        // nearest possible depth, far with a margin of r, so nothing in the scene is clipped.
        s.nearZ = (dist - r) * 0.5;
        s.farZ = dist + 2 * r;
        s.width = 1920;
        s.height = 1080;
        views.push_back(v);
    }
    return views;
}

}  // namespace va
