// Reading visaudit's JSON inputs with places (scene files, views files, route files): typed access to
// a parsed document where every failure is "FILE:LINE:COL: path: message" with a fix (STYLE 10), and
// the view object every input shares (docs/scene-format.md's view keys).
#pragma once

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "analysis/scene.h"
#include "common/json_util.h"
#include "render/camera.h"
#include "render/depth_format.h"

namespace va::load {

using json::Json;
using json::Path;

// Largest width or height a view may ask for. Checked before anything is allocated; the per-view
// buffers scale with width * height, so this is a guard against typos (width: 100000), not a
// limit of the method: it can be raised here later.
constexpr int kMaxViewSize = 16384;

inline Vec3 upVector(char up) { return up == 'x' ? Vec3{1, 0, 0} : up == 'z' ? Vec3{0, 0, 1} : Vec3{0, 1, 0}; }

// Typed access to a parsed document; every failure sets `err` to "FILE:LINE:COL: path: message".
struct Reader {
    const json::Doc &doc;
    std::string err;

    bool fail(const Path &p, const std::string &msg, bool atKey = false) {
        err = json::where(doc, p, atKey) + ": " + json::pathString(p) + ": " + msg;
        return false;
    }

    // Every key of `obj` must be one of `known`.
    bool checkKeys(const Json &obj, const Path &p, const std::vector<std::string> &known) {
        for (auto it = obj.begin(); it != obj.end(); ++it) {
            if (std::find(known.begin(), known.end(), it.key()) != known.end()) continue;
            const std::string in = p.empty() ? "at the top level" : "in " + json::pathString(p);
            const std::string near = json::closest(it.key(), known);
            err = json::where(doc, p / it.key(), true) + ": unknown key '" + it.key() + "' " + in + "; " +
                  (near.empty() ? "known keys: " + json::joinList(known)
                                : "did you mean '" + near + "'? (known keys: " + json::joinList(known) + ")");
            return false;
        }
        return true;
    }

    bool object(const Json &j, const Path &p) {
        return j.is_object() || fail(p, "expected an object, got " + json::typeName(j));
    }
    bool number(const Json &j, const Path &p, double *out) {
        if (!j.is_number()) return fail(p, "expected a number, got " + json::typeName(j));
        *out = j.get<double>();
        // JSON has no NaN or infinity literal, but a literal too large for a double (1e999) parses
        // as infinity.
        if (!std::isfinite(*out)) return fail(p, "expected a finite number; this one overflows a double");
        return true;
    }
    bool boolean(const Json &j, const Path &p, bool *out) {
        if (!j.is_boolean()) return fail(p, "expected true or false, got " + json::typeName(j));
        *out = j.get<bool>();
        return true;
    }
    bool string(const Json &j, const Path &p, std::string *out) {
        if (!j.is_string()) return fail(p, "expected a string, got " + json::typeName(j));
        *out = j.get<std::string>();
        return true;
    }
    bool vec3(const Json &j, const Path &p, Vec3 *out) {
        if (!j.is_array() || j.size() != 3)
            return fail(p, "expected an array of 3 numbers, got " +
                               (j.is_array() ? "an array of " + std::to_string(j.size()) : json::typeName(j)));
        for (size_t i = 0; i < 3; ++i) {
            if (!j[i].is_number())
                return fail(p / i, "expected an array of 3 numbers, element " + std::to_string(i) + " is " + json::typeName(j[i]));
            double v = 0;
            if (!number(j[i], p / i, &v)) return false;
            (*out)[int(i)] = v;
        }
        return true;
    }
    bool size(const Json &j, const Path &p, int *out) {
        if (!j.is_number_integer() && !j.is_number_unsigned())
            return fail(p, "expected a whole number of pixels, got " + (j.is_number() ? j.dump() : json::typeName(j)));
        if (j.is_number_integer() && j.get<int64_t>() < 1)
            return fail(p, "must be at least 1, got " + j.dump());
        if (j.get<uint64_t>() > uint64_t(kMaxViewSize))
            return fail(p, j.dump() + " exceeds the limit of " + std::to_string(kMaxViewSize) +
                               " pixels (kMaxViewSize in analysis/load/json_reader.h; it can be raised there)");
        *out = int(j.get<int64_t>());
        return true;
    }
    bool upAxis(const Json &j, const Path &p, char *out) {
        std::string s;
        if (!string(j, p, &s)) return false;
        if (s != "x" && s != "y" && s != "z") return fail(p, "expected \"x\", \"y\" or \"z\", got \"" + s + "\"");
        *out = s[0];
        return true;
    }

    // One view object (docs/scene-format.md's view keys). `index` names unnamed views "view<index>".
    bool view(const Json &j, const Path &p, size_t index, Vec3 defaultUp, ViewSpec *out) {
        if (!object(j, p)) return false;
        if (!checkKeys(j, p, {"name", "eye", "target", "direction", "up", "fov_y", "ortho_height", "near", "far",
                              "width", "height", "depth_format"}))
            return false;
        ViewSpec v;
        CameraSpec &c = v.camera;
        c.up = defaultUp;
        v.name = "view" + std::to_string(index);
        if (j.contains("name") && !string(j["name"], p / "name", &v.name)) return false;
        if (v.name.empty()) return fail(p / "name", "a view name cannot be empty");
        if (!j.contains("eye")) return fail(p, "missing \"eye\": give the camera position, e.g. \"eye\": [0, 1.7, 8]");
        if (!vec3(j["eye"], p / "eye", &c.eye)) return false;
        const bool hasTarget = j.contains("target"), hasDir = j.contains("direction");
        if (hasTarget && hasDir) return fail(p / "direction", "give either \"target\" or \"direction\", not both", true);
        if (!hasTarget && !hasDir)
            return fail(p, "missing \"target\" (a point to look at) or \"direction\" (a direction to look in)");
        if (hasTarget && !vec3(j["target"], p / "target", &c.target)) return false;
        if (hasDir) {
            Vec3 d;
            if (!vec3(j["direction"], p / "direction", &d)) return false;
            if (d == Vec3{0, 0, 0}) return fail(p / "direction", "has zero length; give the direction to look in");
            c.target = c.eye + d;
        }
        if (j.contains("up") && !vec3(j["up"], p / "up", &c.up)) return false;
        if (j.contains("fov_y") && j.contains("ortho_height"))
            return fail(p / "ortho_height", "give either \"fov_y\" (perspective) or \"ortho_height\" (orthographic), not both", true);
        if (j.contains("fov_y") && !number(j["fov_y"], p / "fov_y", &c.fovYDegrees)) return false;
        if (j.contains("ortho_height")) {
            c.orthographic = true;
            if (!number(j["ortho_height"], p / "ortho_height", &c.orthoHeight)) return false;
        }
        if (j.contains("near") && !number(j["near"], p / "near", &c.nearZ)) return false;
        if (j.contains("far") && !number(j["far"], p / "far", &c.farZ)) return false;
        if (j.contains("width") && !size(j["width"], p / "width", &c.width)) return false;
        if (j.contains("height") && !size(j["height"], p / "height", &c.height)) return false;
        if (j.contains("depth_format")) {
            std::string f, e;
            if (!string(j["depth_format"], p / "depth_format", &f)) return false;
            if (!parseDepthFormat(f, &v.depthFormat, &e)) return fail(p / "depth_format", e);
        }
        // The camera model's own checks (near > 0, far > near, fov in (0, 180), eye != target, up not
        // parallel to the view direction). Its message starts with the quoted key it is about: point
        // at that key when the view gives it, else at the view.
        Camera cam;
        std::string e;
        if (!makeCamera(c, &cam, &e)) {
            Path at = p;
            if (e.size() > 2 && e[0] == '"') {
                const std::string k = e.substr(1, e.find('"', 1) - 1);
                if (j.contains(k)) at = p / k;
                else if (k == "target" && hasDir) at = p / "direction";
            }
            err = json::where(doc, at) + ": " + json::pathString(p) + ": " + e;
            return false;
        }
        *out = std::move(v);
        return true;
    }

    // The "views" array: names must be unique.
    bool views(const Json &j, const Path &p, Vec3 defaultUp, const std::string &origin, std::vector<ViewSpec> *out) {
        if (!j.is_array()) return fail(p, "expected an array of views, got " + json::typeName(j));
        std::map<std::string, size_t> seen;
        for (size_t i = 0; i < j.size(); ++i) {
            ViewSpec v;
            if (!view(j[i], p / i, i, defaultUp, &v)) return false;
            v.origin = origin;
            auto [it, fresh] = seen.insert({v.name, i});
            if (!fresh) {
                const bool named = j[i].contains("name");
                return fail(named ? p / i / "name" : p / i,
                            "duplicate view name '" + v.name + "' (also " + json::pathString(p / it->second) + ")" +
                                (named ? "; view names must be unique" : "; it was given to this unnamed view: add a \"name\""));
            }
            out->push_back(std::move(v));
        }
        return true;
    }
};

}  // namespace va::load
