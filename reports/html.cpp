// report.html from report.json (reports/html.h; docs/html-report.md describes the page).
//
// Structure of the page, top to bottom:
//   header       scene, tool, one-line verdict, links to every view
//   summary      one row per view, worst first, each linking to its section
//   planner      the report-level "effects" decisions (when present)
//   depth audit  depth-audit.png when the folder holds one
//   PVS audit    a link to pvs-audit.html and its image when the folder holds them (check, pvs_*)
//   per view     camera line; the six questions of visibility; the stage funnel (SVG) and stage
//                table; images with legends (click to enlarge); z-fighting hotspots (rows link to
//                boxes over the z-fight image); false culls; ray-cast cross-check; depth formats
//                and a resolution plot (SVG) for the view's near/far; accuracy against time (table
//                and SVG scatter); every other section of the view as a generic table.
//
// Everything reads the report through the accessors below, which never throw: a missing key or a
// value of another type reads as absent, and the part of the page that needs it is left out or
// says "not analysed". Known parts are table-driven (kImageKinds, kQuestionOrder, kSectionTitles),
// so a new image or section shows up without new code.
#include "reports/html.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <string_view>
#include <vector>

#include "analysis/audits/depth_audit.h"
#include "render/depth_format.h"
#include "reports/depth_plot.h"
#include "reports/html_assets.h"
#include "reports/report.h"

namespace va {
namespace {

using Json = nlohmann::ordered_json;

// ---- Reading the report without exceptions ------------------------------------------------------

const Json *get(const Json *j, std::string_view key) {
    if (!j || !j->is_object()) return nullptr;
    auto it = j->find(std::string(key));
    return it == j->end() ? nullptr : &*it;
}
// A path of keys: get(&v, {"audit", "false_culls", "pixels"}).
const Json *get(const Json *j, std::initializer_list<std::string_view> keys) {
    for (std::string_view k : keys) j = get(j, k);
    return j;
}
std::optional<double> num(const Json *j) {
    if (!j || !j->is_number()) return std::nullopt;
    return j->get<double>();
}
std::optional<double> num(const Json *j, std::initializer_list<std::string_view> keys) { return num(get(j, keys)); }
double numOr(const Json *j, std::initializer_list<std::string_view> keys, double fallback) {
    return num(get(j, keys)).value_or(fallback);
}
std::string str(const Json *j) { return j && j->is_string() ? j->get<std::string>() : std::string(); }
std::string str(const Json *j, std::initializer_list<std::string_view> keys) { return str(get(j, keys)); }
// The first of several names a field may have (sections still being designed use either).
std::optional<double> firstNum(const Json *j, std::initializer_list<std::string_view> keys) {
    for (std::string_view k : keys)
        if (auto v = num(get(j, k))) return v;
    return std::nullopt;
}
bool isTrue(const Json *j) { return j && j->is_boolean() && j->get<bool>(); }
// A section that says it did not run: {"ran": false, "reason": ...}.
bool ranFalse(const Json *j) {
    const Json *r = get(j, "ran");
    return r && r->is_boolean() && !r->get<bool>();
}

// ---- Escaping and formatting --------------------------------------------------------------------

// Length of the valid UTF-8 sequence at s[i], or 0 when the bytes there are not one.
size_t utf8Length(std::string_view s, size_t i) {
    const auto b = [&](size_t k) { return static_cast<unsigned char>(s[k]); };
    const unsigned char c = b(i);
    size_t n = c < 0x80 ? 1 : (c >> 5) == 0x6 ? 2 : (c >> 4) == 0xE ? 3 : (c >> 3) == 0x1E ? 4 : 0;
    if (n == 0 || i + n > s.size()) return 0;
    for (size_t k = 1; k < n; ++k)
        if ((b(i + k) & 0xC0) != 0x80) return 0;
    if (n == 2 && c < 0xC2) return 0;                                   // overlong
    if (n == 3 && c == 0xE0 && b(i + 1) < 0xA0) return 0;               // overlong
    if (n == 3 && c == 0xED && b(i + 1) >= 0xA0) return 0;              // surrogates
    if (n == 4 && ((c == 0xF0 && b(i + 1) < 0x90) || c > 0xF4 || (c == 0xF4 && b(i + 1) >= 0x90))) return 0;
    return n;
}

// Text for HTML content and quoted attribute values: the five markup characters become entities,
// control characters (but tab and newline) and invalid UTF-8 become U+FFFD. A report string can
// therefore never open a tag, close an attribute or break the page's encoding.
std::string esc(std::string_view s) {
    std::string o;
    o.reserve(s.size() + 8);
    for (size_t i = 0; i < s.size();) {
        const unsigned char c = static_cast<unsigned char>(s[i]);
        const size_t n = utf8Length(s, i);
        if (n == 0) {
            o += "\xEF\xBF\xBD";
            ++i;
            continue;
        }
        if (n > 1) {
            o.append(s.substr(i, n));
            i += n;
            continue;
        }
        switch (c) {
        case '&': o += "&amp;"; break;
        case '<': o += "&lt;"; break;
        case '>': o += "&gt;"; break;
        case '"': o += "&quot;"; break;
        case '\'': o += "&#39;"; break;
        default:
            if ((c < 0x20 && c != '\t' && c != '\n') || c == 0x7F) o += "\xEF\xBF\xBD";
            else o += char(c);
        }
        ++i;
    }
    return o;
}

// A name made safe for an id or class: [a-z0-9_-] kept (upper case lowered), others -> '_'.
std::string slug(std::string_view s) {
    std::string o;
    for (char ch : s) {
        const unsigned char c = static_cast<unsigned char>(ch);
        if (std::isalnum(c) && c < 0x80) o += char(std::tolower(c));
        else if (c == '-' || c == '_') o += char(c);
        else o += '_';
    }
    return o.empty() ? "_" : o;
}

// A whole number with thousands separators: 462881 -> "462,881".
std::string fmtCount(double v) {
    if (!std::isfinite(v)) return "—";
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.0f", std::fabs(v));
    std::string digits = buf, o;
    for (size_t i = 0; i < digits.size(); ++i) {
        if (i > 0 && (digits.size() - i) % 3 == 0) o += ',';
        o += digits[i];
    }
    return (v < 0 && o != "0" ? "-" : "") + o;
}
// A real number, 4 significant digits (large values as counts): 1.27776 -> "1.278".
std::string fmtReal(double v) {
    if (!std::isfinite(v)) return "—";
    if (v == 0) return "0";
    if (std::fabs(v) >= 1e4 && std::fabs(v) < 1e15) return fmtCount(std::round(v));
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.4g", v);
    return buf;
}
// A JSON value as table text: integers as counts, reals with 4 digits, null as an em dash.
std::string fmtValue(const Json *j) {
    if (!j || j->is_null()) return "—";
    if (j->is_number_integer() || j->is_number_unsigned()) return fmtCount(j->get<double>());
    if (j->is_number()) return fmtReal(j->get<double>());
    if (j->is_boolean()) return j->get<bool>() ? "yes" : "no";
    if (j->is_string()) return esc(j->get<std::string>());
    if (j->is_array()) {
        std::string o;
        for (const Json &e : *j) {
            if (!o.empty()) o += ", ";
            o += e.is_structured() ? std::string("…") : fmtValue(&e);
        }
        return "[" + o + "]";
    }
    return "…";
}
std::string fmtMs(std::optional<double> ms) { return ms ? fmtReal(*ms) + " ms" : "—"; }
std::string pct(double part, double whole) {
    if (!(whole > 0)) return "—";
    char buf[32];
    const double p = 100.0 * part / whole;
    // Small shares keep two significant digits, shares just short of 100% two decimals, so that
    // neither rounds to 0.0% or 100.0%.
    const char *f = p != 0 && p < 0.1 ? "%.2g%%" : (p > 99.9 && part < whole) ? "%.2f%%" : "%.1f%%";
    std::snprintf(buf, sizeof buf, f, p);
    return buf;
}
// A percentage for SVG/CSS geometry (fixed decimals: deterministic and short).
std::string fx(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.2f", v);
    return buf;
}
// A report key as a column header: "false_cull_pixels" -> "false cull pixels".
std::string label(std::string_view key) {
    std::string o(key);
    std::replace(o.begin(), o.end(), '_', ' ');
    return esc(o);
}
std::string plural(double n, const char *one, const char *many) { return fmtCount(n) + " " + (n == 1 ? one : many); }

// ---- Files next to the page -----------------------------------------------------------------------

// Pixel size of a PNG from its IHDR chunk (bytes 16..23, big-endian); nullopt if not a PNG.
std::optional<std::pair<int, int>> pngSize(const std::string &path) {
    std::ifstream f(path, std::ios::binary);
    unsigned char h[24];
    if (!f.read(reinterpret_cast<char *>(h), 24)) return std::nullopt;
    static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    if (std::memcmp(h, sig, 8) != 0 || std::memcmp(h + 12, "IHDR", 4) != 0) return std::nullopt;
    const auto be = [&](int o) { return (uint32_t(h[o]) << 24) | (uint32_t(h[o + 1]) << 16) | (uint32_t(h[o + 2]) << 8) | h[o + 3]; };
    const uint32_t w = be(16), hh = be(20);
    if (w == 0 || hh == 0 || w > (1u << 24) || hh > (1u << 24)) return std::nullopt;
    return std::make_pair(int(w), int(hh));
}

// A relative file name from the report that may be linked: one path component, no "..", no
// scheme. (The report's image names are sanitized already; this guards hand-edited reports.)
bool safeFileName(const std::string &name) {
    if (name.empty() || name == "." || name == "..") return false;
    return name.find_first_of("/\\:") == std::string::npos && utf8Length(name, 0) != 0;
}

// URL path of a file in the page's folder: percent-encode everything outside [A-Za-z0-9._-].
std::string urlOf(const std::string &name) {
    std::string o;
    for (unsigned char c : name) {
        if (std::isalnum(c) && c < 0x80) o += char(c);
        else if (c == '.' || c == '_' || c == '-') o += char(c);
        else {
            char buf[4];
            std::snprintf(buf, sizeof buf, "%%%02X", c);
            o += buf;
        }
    }
    return o;
}

struct Folder {
    std::string dir;
    bool exists(const std::string &name) const {
        if (dir.empty() || !safeFileName(name)) return false;
        std::error_code ec;
        return std::filesystem::is_regular_file(std::filesystem::path(dir) / name, ec);
    }
    std::optional<std::pair<int, int>> png(const std::string &name) const {
        if (!exists(name)) return std::nullopt;
        return pngSize((std::filesystem::path(dir) / name).string());
    }
};

// ---- Images (table-driven) ---------------------------------------------------------------------

// The images a view can have, in page order. `key` is the view's "images" key (a file name or an
// array of them); `suffix` finds the file by the view's base name when the key is absent (images
// that a later stage writes before its report key exists). `legend` says how to read the colors;
// the PNGs carry their own legend strip below the picture.
struct ImageKind {
    const char *key;
    const char *suffix;
    const char *slug;
    const char *title;
    const char *legend;
};
constexpr ImageKind kImageKinds[] = {
    {"depth_png", ".depth.png", "depth", "Depth",
     "View depth of the visible surface on a log scale: nearest white, farthest dark grey, background black."},
    {"overdraw_png", ".overdraw.png", "overdraw", "Overdraw (depth complexity)",
     "Fragments per pixel: 0 black, 1 blue, then cyan, green, yellow, red up to white; the strip below gives "
     "each color's count."},
    {"zfight_png", ".zfight.png", "zfight", "Z-fighting",
     "Hotspots filled and outlined, one color each, numbered by hotspot id (table below); shared edges and "
     "intersection lines in their own colors are not hotspots."},
    {"culling_png", ".culling.png", "culling", "Culling fates",
     "The reference visibility (no culling), each pixel colored by its triangle's fate: drawn (grey), or "
     "falsely culled by the stage the legend strip names, with its pixel count."},
    {"painter_errors_png", ".painter_errors.png", "painter", "Painter's errors",
     "Pixels where the painter's algorithm (centroid sort) shows another triangle than the reference."},
    {"abuffer_png", ".abuffer.png", "abuffer", "A-buffer composite",
     "Transparent surfaces composited in depth order (A-buffer)."},
    {"raycast_diff_png", ".raycast_diff.png", "raycast", "Ray casting against the z-buffer",
     "Pixels where the ray caster and the z-buffer see different triangles, by class (legend strip): "
     "edge, depth tie, genuine."},
    {"shadow_png", nullptr, "shadow", "Shadows",
     "Per light: pixels whose surface point is shadowed (a surface stands between it and the light), lit, or "
     "facing away."},
    {"secondary_png", ".secondary.png", "secondary", "Secondary rays",
     "Reflection and refraction rays where materials call for them."},
};

struct ViewImage {
    std::string file, slug, title, legend;
    int width = 0, height = 0;  // of the PNG (0 when not a readable PNG)
};

// The base name of a view's images (BASE of BASE.depth.png), or empty.
std::string imageBase(const Json *view) {
    const std::string depth = str(view, {"images", "depth_png"});
    const std::string suffix = ".depth.png";
    if (depth.size() > suffix.size() && depth.compare(depth.size() - suffix.size(), suffix.size(), suffix) == 0)
        return depth.substr(0, depth.size() - suffix.size());
    return {};
}

std::vector<ViewImage> viewImages(const Json *view, const Folder &folder) {
    std::vector<ViewImage> out;
    std::set<std::string> keysSeen, filesSeen;
    const Json *images = get(view, "images");
    const std::string base = imageBase(view);
    auto add = [&](const std::string &file, const std::string &slugName, const std::string &title,
                   const std::string &legend) {
        if (filesSeen.count(file) || !folder.exists(file)) return;
        filesSeen.insert(file);
        ViewImage im{file, slugName, title, legend};
        if (auto s = folder.png(file)) std::tie(im.width, im.height) = *s;
        out.push_back(im);
    };
    auto addValue = [&](const Json *value, const std::string &slugName, const std::string &title,
                        const std::string &legend) {
        if (!value) return;
        if (value->is_string()) add(value->get<std::string>(), slugName, title, legend);
        if (value->is_array()) {
            size_t k = 0;
            for (const Json &e : *value) {
                if (!e.is_string()) continue;
                ++k;
                add(e.get<std::string>(), slugName + "-" + std::to_string(k), title + " — " + e.get<std::string>(),
                    legend);
            }
        }
    };
    for (const ImageKind &kind : kImageKinds) {
        keysSeen.insert(kind.key);
        if (const Json *value = get(images, kind.key)) addValue(value, kind.slug, kind.title, kind.legend);
        else if (kind.suffix && !base.empty()) add(base + kind.suffix, kind.slug, kind.title, kind.legend);
    }
    // Any other PNG the report lists, titled by its key.
    if (images && images->is_object())
        for (auto it = images->begin(); it != images->end(); ++it) {
            const std::string &key = it.key();
            if (keysSeen.count(key) || key.size() < 4 || key.compare(key.size() - 4, 4, "_png") != 0) continue;
            addValue(&it.value(), slug(key), key.substr(0, key.size() - 4), "");
        }
    return out;
}

// ---- Summary metrics of a view (sorting and the verdict) -----------------------------------------

struct ViewScore {
    size_t pos = 0;                  // position in report.views
    std::string name;
    std::optional<double> falseCullPixels, genuine, zfightPixels, hotspots, overdraw, complexity, wastedShare,
        drawn, ms;
};

// Z-fighting pixels in the view's own depth format (what the z-buffer really shows).
std::optional<double> zfightInOwnFormat(const Json *v) {
    if (!get(v, "depth") || ranFalse(get(v, "depth"))) return std::nullopt;
    return num(v, {"depth", "formats", str(v, {"depth_format"}), "fighting_pixels"});
}

const Json *stageNamed(const Json *v, std::string_view name) {
    const Json *stages = get(v, "stages");
    if (!stages || !stages->is_array()) return nullptr;
    for (const Json &s : *stages)
        if (str(get(&s, "name")) == name) return &s;
    return nullptr;
}
bool stageRan(const Json *s) { return s && isTrue(get(s, "ran")); }

ViewScore scoreView(const Json *v, size_t pos) {
    ViewScore s;
    s.pos = pos;
    s.name = str(v, {"name"});
    if (!ranFalse(get(v, "audit"))) {
        s.falseCullPixels = num(v, {"audit", "false_culls", "pixels"});
        s.wastedShare = num(v, {"audit", "wasted_draws", "share"});
    }
    if (!ranFalse(get(v, "raycast"))) s.genuine = num(v, {"raycast", "cross_check", "genuine"});
    s.zfightPixels = zfightInOwnFormat(v);
    if (s.zfightPixels)
        s.hotspots = num(v, {"depth", "formats", str(v, {"depth_format"}), "hotspots"});
    s.overdraw = num(v, {"zbuffer", "overdraw"});
    s.complexity = num(v, {"zbuffer", "depth_complexity"});
    if (const Json *z = stageNamed(v, "zbuffer"); stageRan(z)) s.drawn = num(z, {"triangles_out"});
    s.ms = num(v, {"total_ms"});
    return s;
}

// Worst first: false-cull pixels, then genuine ray-cast disagreements, then z-fighting pixels,
// then overdraw; ties keep the view order. Absent values count as 0.
bool worseThan(const ViewScore &a, const ViewScore &b) {
    const auto key = [](const ViewScore &s) {
        return std::make_tuple(s.falseCullPixels.value_or(0), s.genuine.value_or(0), s.zfightPixels.value_or(0),
                               s.overdraw.value_or(0));
    };
    if (key(a) != key(b)) return key(a) > key(b);
    return a.pos < b.pos;
}

std::vector<const Json *> viewsOf(const Json &report) {
    std::vector<const Json *> vs;
    const Json *views = get(&report, "views");
    if (views && views->is_array())
        for (const Json &v : *views) vs.push_back(&v);
    return vs;
}

// Views whose images load with the page; later views' images load when scrolled near.
constexpr size_t kEagerViews = 8;

std::string viewId(size_t pos) { return "v" + std::to_string(pos); }

// ---- SVG charts -----------------------------------------------------------------------------------

// The stage funnel: one row per stage, a pale bar for triangles in and a solid bar for triangles
// out on one scale (the largest count of any stage), the culled count and share to the right.
// A skipped stage is a grey bar with its reason as the tooltip (<title>).
std::string funnelSvg(const Json *v, const std::string &id) {
    const Json *stages = get(v, "stages");
    if (!stages || !stages->is_array() || stages->empty()) return "<p class=\"note\">No stages in this view.</p>";
    double maxCount = 1;
    for (const Json &s : *stages)
        maxCount = std::max({maxCount, numOr(&s, {"triangles_in"}, 0), numOr(&s, {"triangles_out"}, 0)});
    const int rowH = 30, labelW = 92, barW = 520, width = 900, top = 24;
    const int height = top + rowH * int(stages->size()) + 8;
    std::string o = "<svg class=\"chart funnel\" id=\"" + id + "\" viewBox=\"0 0 " + std::to_string(width) + " " +
                    std::to_string(height) + "\" role=\"img\" aria-label=\"Stage funnel: triangles in and out of every stage\">";
    o += "<text x=\"" + std::to_string(labelW) + "\" y=\"14\" class=\"muted\">triangles in (pale) and out (solid) "
         "per stage, on one scale</text>";
    int row = 0;
    for (const Json &s : *stages) {
        const std::string name = str(get(&s, "name"));
        const int y = top + rowH * row++;
        const double in = numOr(&s, {"triangles_in"}, 0), out = numOr(&s, {"triangles_out"}, 0),
                     culled = numOr(&s, {"triangles_culled"}, 0);
        o += "<g class=\"stage\" data-stage=\"" + esc(name) + "\">";
        o += "<text x=\"0\" y=\"" + std::to_string(y + 18) + "\">" + esc(name) + "</text>";
        if (!stageRan(&s)) {
            const std::string reason = str(get(&s, "reason"));
            o += "<title>" + esc(name) + " skipped: " + esc(reason.empty() ? "did not run" : reason) + "</title>";
            o += "<rect class=\"skip\" x=\"" + std::to_string(labelW) + "\" y=\"" + std::to_string(y + 4) + "\" width=\"" +
                 std::to_string(barW) + "\" height=\"20\" rx=\"3\"/>";
            o += "<text class=\"muted\" x=\"" + std::to_string(labelW + 8) + "\" y=\"" + std::to_string(y + 18) +
                 "\">skipped: " + esc(reason.empty() ? "did not run" : reason) + "</text>";
        } else {
            o += "<title>" + esc(name) + ": " + fmtCount(in) + " in, " + fmtCount(culled) + " culled, " + fmtCount(out) +
                 " out, " + fmtMs(num(get(&s, "ms"))) + "</title>";
            const double wIn = std::max(1.0, barW * in / maxCount), wOut = out > 0 ? std::max(1.0, barW * out / maxCount) : 0;
            o += "<rect class=\"in\" x=\"" + std::to_string(labelW) + "\" y=\"" + std::to_string(y + 4) + "\" width=\"" +
                 fx(wIn) + "\" height=\"20\" rx=\"3\"/>";
            o += "<rect class=\"out\" x=\"" + std::to_string(labelW) + "\" y=\"" + std::to_string(y + 9) + "\" width=\"" +
                 fx(wOut) + "\" height=\"10\" rx=\"2\"/>";
            o += "<text x=\"" + std::to_string(labelW + barW + 10) + "\" y=\"" + std::to_string(y + 18) + "\">" +
                 fmtCount(in) + " → " + fmtCount(out) + "  (−" + fmtCount(culled) + ", " + pct(culled, in) + ")</text>";
        }
        o += "</g>";
    }
    o += "</svg>";
    return o;
}

// "Nice" axis ticks over [lo, hi] (1, 2, 5 times a power of ten), at least two.
std::vector<double> niceTicks(double lo, double hi, int target) {
    if (!(hi > lo)) hi = lo + 1;
    const double raw = (hi - lo) / std::max(1, target);
    const double mag = std::pow(10.0, std::floor(std::log10(raw)));
    double step = mag;
    for (double m : {1.0, 2.0, 5.0, 10.0})
        if (raw <= m * mag) {
            step = m * mag;
            break;
        }
    std::vector<double> t;
    for (double x = std::ceil(lo / step) * step; x <= hi + step * 1e-9; x += step) t.push_back(std::fabs(x) < step * 1e-9 ? 0 : x);
    return t;
}

struct ScatterPoint {
    std::string label;
    double x = 0, y = 0;
};

// A scatter of time (x, ms) against error (y, pixels), linear axes from 0, labelled points.
std::string scatterSvg(const std::vector<ScatterPoint> &pts, const std::string &id, const std::string &xTitle,
                       const std::string &yTitle) {
    double xMax = 0, yMax = 0;
    for (const ScatterPoint &p : pts) {
        xMax = std::max(xMax, p.x);
        yMax = std::max(yMax, p.y);
    }
    const std::vector<double> xt = niceTicks(0, xMax > 0 ? xMax * 1.1 : 1, 5), yt = niceTicks(0, yMax > 0 ? yMax * 1.1 : 1, 4);
    const double xHi = xt.back(), yHi = yt.back();
    const double L = 70, R = 600, T = 14, B = 220;
    const auto X = [&](double x) { return L + (R - L) * x / xHi; };
    const auto Y = [&](double y) { return B - (B - T) * y / yHi; };
    std::string o = "<svg class=\"chart scatter\" id=\"" + id + "\" viewBox=\"0 0 760 262\" role=\"img\" aria-label=\"" +
                    esc(yTitle) + " against " + esc(xTitle) + "\">";
    for (double t : xt)
        o += "<line class=\"grid\" x1=\"" + fx(X(t)) + "\" y1=\"" + fx(T) + "\" x2=\"" + fx(X(t)) + "\" y2=\"" + fx(B) +
             "\"/><text class=\"muted\" text-anchor=\"middle\" x=\"" + fx(X(t)) + "\" y=\"" + fx(B + 16) + "\">" +
             fmtReal(t) + "</text>";
    for (double t : yt)
        o += "<line class=\"grid\" x1=\"" + fx(L) + "\" y1=\"" + fx(Y(t)) + "\" x2=\"" + fx(R) + "\" y2=\"" + fx(Y(t)) +
             "\"/><text class=\"muted\" text-anchor=\"end\" x=\"" + fx(L - 6) + "\" y=\"" + fx(Y(t) + 4) + "\">" +
             fmtReal(t) + "</text>";
    o += "<line class=\"axis\" x1=\"" + fx(L) + "\" y1=\"" + fx(B) + "\" x2=\"" + fx(R) + "\" y2=\"" + fx(B) + "\"/>";
    o += "<line class=\"axis\" x1=\"" + fx(L) + "\" y1=\"" + fx(T) + "\" x2=\"" + fx(L) + "\" y2=\"" + fx(B) + "\"/>";
    o += "<text text-anchor=\"middle\" x=\"" + fx((L + R) / 2) + "\" y=\"" + fx(B + 36) + "\">" + esc(xTitle) + "</text>";
    o += "<text text-anchor=\"middle\" transform=\"translate(14 " + fx((T + B) / 2) + ") rotate(-90)\">" + esc(yTitle) +
         "</text>";
    for (const ScatterPoint &p : pts) {
        o += "<g><title>" + esc(p.label) + ": " + fmtReal(p.x) + " ms, " + fmtCount(p.y) + " px</title>";
        o += "<circle class=\"pt\" cx=\"" + fx(X(p.x)) + "\" cy=\"" + fx(Y(p.y)) + "\" r=\"5\"/>";
        o += "<text x=\"" + fx(X(p.x) + 8) + "\" y=\"" + fx(Y(p.y) - 6) + "\">" + esc(p.label) + "</text></g>";
    }
    o += "</svg>";
    return o;
}

// Depth resolution (m) against view depth (m), log-log, one curve per depth format for this view's
// near/far (analysis/audits/depth_audit.h: the formats' exact arithmetic, the same curves as
// `visaudit depth-audit`); the view's own format drawn thick, dashed markers at the hotspots'
// depths. Colors are depthPlotColor's (the same as depth-audit.png).
std::string resolutionSvg(const DepthAuditResult &r, const std::string &ownFormat,
                          const std::vector<std::pair<std::string, double>> &markers, const std::string &id) {
    double yLo = INFINITY, yHi = 0;
    for (const DepthFormatAudit &f : r.formats)
        for (const auto &v : f.curveResolution)
            if (v && *v > 0 && std::isfinite(*v)) {
                yLo = std::min(yLo, *v);
                yHi = std::max(yHi, *v);
            }
    if (!(yHi > 0) || r.curveDepths.empty()) return {};
    const double dLo = std::floor(std::log10(yLo)), dHi = std::max(dLo + 1, std::ceil(std::log10(yHi)));
    const double xLo = std::log10(r.nearZ), xHi = std::log10(r.farZ);
    const double L = 70, R = 640, T = 12, B = 300;
    const auto X = [&](double d) { return L + (R - L) * (std::log10(d) - xLo) / (xHi - xLo); };
    const auto Y = [&](double res) { return B - (B - T) * (std::log10(res) - dLo) / (dHi - dLo); };
    // Drawn on a light panel in both color schemes: the format colors are depth-audit.png's,
    // chosen for a white background.
    std::string o = "<svg class=\"chart resolution lightpanel\" id=\"" + id +
                    "\" viewBox=\"0 0 860 340\" role=\"img\" aria-label=\"Depth resolution against view depth per format\">"
                    "<rect class=\"panel\" x=\"0\" y=\"0\" width=\"860\" height=\"340\" rx=\"6\"/>";
    // Decade grid lines (both axes).
    for (double e = std::ceil(xLo); e <= std::floor(xHi); e += 1)
        o += "<line class=\"grid\" x1=\"" + fx(X(std::pow(10, e))) + "\" y1=\"" + fx(T) + "\" x2=\"" + fx(X(std::pow(10, e))) +
             "\" y2=\"" + fx(B) + "\"/><text class=\"muted\" text-anchor=\"middle\" x=\"" + fx(X(std::pow(10, e))) +
             "\" y=\"" + fx(B + 15) + "\">1e" + std::to_string(int(e)) + "</text>";
    const int yStep = std::max(1, int((dHi - dLo) / 8));
    for (double e = dLo; e <= dHi; e += yStep)
        o += "<line class=\"grid\" x1=\"" + fx(L) + "\" y1=\"" + fx(Y(std::pow(10, e))) + "\" x2=\"" + fx(R) + "\" y2=\"" +
             fx(Y(std::pow(10, e))) + "\"/><text class=\"muted\" text-anchor=\"end\" x=\"" + fx(L - 5) + "\" y=\"" +
             fx(Y(std::pow(10, e)) + 4) + "\">1e" + std::to_string(int(e)) + "</text>";
    o += "<text text-anchor=\"middle\" x=\"" + fx((L + R) / 2) + "\" y=\"" + fx(B + 34) + "\">view depth (m), near " +
         fmtReal(r.nearZ) + " to far " + fmtReal(r.farZ) + "</text>";
    o += "<text text-anchor=\"middle\" transform=\"translate(14 " + fx((T + B) / 2) + ") rotate(-90)\">resolution (m)</text>";
    for (const auto &[name, depth] : markers) {
        if (!(depth >= r.nearZ && depth <= r.farZ)) continue;
        o += "<line class=\"mark\" x1=\"" + fx(X(depth)) + "\" y1=\"" + fx(T) + "\" x2=\"" + fx(X(depth)) + "\" y2=\"" +
             fx(B) + "\"><title>hotspot " + esc(name) + " at " + fmtReal(depth) + " m</title></line>";
        o += "<text class=\"marklabel\" x=\"" + fx(X(depth) + 3) + "\" y=\"" + fx(T + 10) + "\">" + esc(name) + "</text>";
    }
    int legendRow = 0;
    for (const DepthFormatAudit &f : r.formats) {
        const Rgb8 c = depthPlotColor(f.format);
        char color[16];
        std::snprintf(color, sizeof color, "#%02x%02x%02x", c.r, c.g, c.b);
        const bool own = f.name == ownFormat;
        std::string d;  // one path, broken ("M") where a sample is absent
        bool pen = false;
        for (size_t i = 0; i < r.curveDepths.size() && i < f.curveResolution.size(); ++i) {
            const auto &v = f.curveResolution[i];
            if (!v || !(*v > 0) || !std::isfinite(*v)) {
                pen = false;
                continue;
            }
            d += (pen ? "L" : "M") + fx(X(r.curveDepths[i])) + " " + fx(Y(*v));
            pen = true;
        }
        o += "<path fill=\"none\" stroke=\"" + std::string(color) + "\" stroke-width=\"" + (own ? "3.5" : "1.5") + "\" d=\"" +
             d + "\"><title>" + esc(f.name) + (own ? " (this view's format)" : "") + "</title></path>";
        const double ly = T + 6 + 17 * legendRow++;
        o += "<rect x=\"660\" y=\"" + fx(ly) + "\" width=\"14\" height=\"" + (own ? "6" : "3") + "\" fill=\"" + color + "\"/>";
        o += "<text x=\"680\" y=\"" + fx(ly + 6) + "\"" + (own ? " font-weight=\"bold\"" : "") + ">" + esc(f.name) +
             (own ? " (this view)" : "") + "</text>";
    }
    o += "</svg>";
    return o;
}

// ---- Generic tables ---------------------------------------------------------------------------------

// Column keys of an array of row objects: the scalar members, in first-seen order.
std::vector<std::string> scalarColumns(const std::vector<const Json *> &rows) {
    std::vector<std::string> cols;
    for (const Json *r : rows)
        if (r && r->is_object())
            for (auto it = r->begin(); it != r->end(); ++it)
                if (!it.value().is_object() &&
                    !(it.value().is_array() && !it.value().empty() && it.value().front().is_structured()) &&
                    std::find(cols.begin(), cols.end(), it.key()) == cols.end())
                    cols.push_back(it.key());
    return cols;
}

std::string rowsTable(const std::vector<const Json *> &rows, const std::string &firstHeader = "",
                      const std::vector<std::string> &firstColumn = {}) {
    const std::vector<std::string> cols = scalarColumns(rows);
    std::string o = "<div class=\"scroll\"><table><tr>";
    if (!firstColumn.empty()) o += "<th>" + esc(firstHeader) + "</th>";
    for (const std::string &c : cols) o += "<th>" + label(c) + "</th>";
    o += "</tr>";
    for (size_t i = 0; i < rows.size(); ++i) {
        o += "<tr>";
        if (!firstColumn.empty()) o += "<td>" + esc(firstColumn[i]) + "</td>";
        for (const std::string &c : cols) {
            const Json *v = get(rows[i], c);
            o += std::string(v && v->is_number() ? "<td class=\"n\">" : "<td>") + fmtValue(v) + "</td>";
        }
        o += "</tr>";
    }
    return o + "</table></div>";
}

// Any JSON object as nested tables: scalars as key/value rows, arrays of objects and objects of
// objects as tables, other objects recursively. The fallback for sections this page does not
// know by name (and for the known ones' detail).
std::string genericJson(const Json *j, int depth = 0) {
    if (!j) return {};
    if (j->is_array()) {
        std::vector<const Json *> rows;
        for (const Json &e : *j)
            if (e.is_object()) rows.push_back(&e);
        if (!rows.empty()) return rowsTable(rows);
        return "<p>" + fmtValue(j) + "</p>";
    }
    if (!j->is_object()) return "<p>" + fmtValue(j) + "</p>";
    std::string scalars, nested;
    for (auto it = j->begin(); it != j->end(); ++it) {
        const Json &v = it.value();
        const bool tableArray = v.is_array() && !v.empty() && v.front().is_object();
        if (!v.is_object() && !tableArray) {
            scalars += "<tr><th>" + label(it.key()) + "</th><td" + (v.is_number() ? " class=\"n\"" : "") + ">" +
                       fmtValue(&v) + "</td></tr>";
            continue;
        }
        // An object whose members are all objects reads best as one table (rows = members).
        bool allObjects = v.is_object() && !v.empty();
        if (v.is_object())
            for (auto m = v.begin(); m != v.end(); ++m) allObjects = allObjects && m.value().is_object();
        nested += "<h4>" + label(it.key()) + "</h4>";
        if (allObjects) {
            std::vector<const Json *> rows;
            std::vector<std::string> names;
            for (auto m = v.begin(); m != v.end(); ++m) {
                rows.push_back(&m.value());
                names.push_back(m.key());
            }
            nested += rowsTable(rows, "name", names);
        } else if (depth < 4) {
            nested += genericJson(&v, depth + 1);
        }
    }
    std::string o;
    if (!scalars.empty()) o += "<div class=\"scroll\"><table>" + scalars + "</table></div>";
    return o + nested;
}

// ---- The six questions -----------------------------------------------------------------------------

struct Answer {
    const char *question;
    std::string text;  // HTML (escaped parts)
};

const char *kNotAnalysed = "<span class=\"muted\">not analysed</span>";

std::string notAnalysed(const std::string &why) { return std::string(kNotAnalysed) + (why.empty() ? "" : " (" + why + ")"); }

// What is off-screen: the frustum stage's culled objects and the clip stage's rejected triangles.
std::string answerOffScreen(const Json *v) {
    const Json *fr = stageNamed(v, "frustum"), *cl = stageNamed(v, "clip");
    std::vector<std::string> parts;
    if (stageRan(fr))
        parts.push_back("frustum culling removed " + plural(numOr(fr, {"objects_culled"}, 0), "object", "objects") + " (" +
                        plural(numOr(fr, {"triangles_culled"}, 0), "triangle", "triangles") + ") wholly outside the view");
    if (stageRan(cl)) {
        std::string s = "clipping rejected " + plural(numOr(cl, {"trivially_rejected"}, 0), "more triangle", "more triangles") +
                        " outside one frustum plane";
        if (const auto near = num(cl, {"per_plane", "near"}); near && *near > 0)
            s += ", and cut " + plural(*near, "triangle", "triangles") + " at the near plane";
        parts.push_back(s);
    }
    if (const Json *c = stageNamed(v, "cells"); stageRan(c)) {
        if (auto vis = num(c, {"clusters_visible"}), tot = num(c, {"clusters_total"}); vis && tot)
            parts.push_back("the PVS lets the camera see " + fmtCount(*vis) + " of " + fmtCount(*tot) + " clusters (" +
                            plural(numOr(c, {"triangles_culled"}, 0), "triangle", "triangles") + " culled)");
    }
    if (const Json *c = stageNamed(v, "cells"); stageRan(c))
        if (auto visited = firstNum(c, {"cells_visited"}); visited)
            parts.push_back("portal traversal visited " + plural(*visited, "cell", "cells"));
    if (parts.empty()) {
        std::string why = fr ? str(get(fr, "reason")) : "no frustum stage";
        return notAnalysed(esc(why));
    }
    std::string o;
    for (size_t i = 0; i < parts.size(); ++i) o += (i ? "; " : "") + parts[i];
    return o + ".";
}

// What is too far to draw: the far plane's cut, the grid stage, and the detail section's far
// objects when present.
std::string answerTooFar(const Json *v) {
    const Json *cl = stageNamed(v, "clip");
    const auto farZ = num(v, {"camera", "far"});
    std::vector<std::string> parts;
    if (stageRan(cl) && farZ) {
        const double cut = numOr(cl, {"per_plane", "far"}, 0);
        parts.push_back(cut > 0 ? plural(cut, "triangle crosses", "triangles cross") + " the far plane at " + fmtReal(*farZ) +
                                      " and " + (cut == 1 ? "is" : "are") + " cut there"
                                : "nothing crosses the far plane at " + fmtReal(*farZ));
    }
    if (const Json *g = stageNamed(v, "grid"); stageRan(g))
        parts.push_back("the grid stage culled " + plural(numOr(g, {"triangles_culled"}, 0), "triangle", "triangles"));
    // The detail audit's "too small" objects: projected smaller than a few pixels, a draw distance
    // would drop them.
    if (const Json *d = get(v, "detail"); d && !ranFalse(d))
        if (auto n = firstNum(d, {"objects_too_small", "too_small_objects", "objects_too_far"}))
            parts.push_back(plural(*n, "drawn object projects", "drawn objects project") +
                            " to a few pixels at most: a draw distance would drop " + (*n == 1 ? "it" : "them"));
    if (parts.empty()) return notAnalysed(cl ? "" : "no clip stage");
    std::string o;
    for (size_t i = 0; i < parts.size(); ++i) o += (i ? "; " : "") + parts[i];
    return o + ".";
}

// What needs less detail: the detail section when present; else the z-buffer's empty triangles
// (drawn, yet covering no pixel center: sub-pixel geometry a lower level of detail would drop).
std::string answerLessDetail(const Json *v) {
    std::vector<std::string> parts;
    const Json *d = get(v, "detail");
    if (d && !ranFalse(d)) {
        const auto over = firstNum(d, {"objects_over_detailed", "over_detailed_objects"}),
                   saved = firstNum(d, {"triangles_savable", "triangles_saved"}),
                   perPixel = firstNum(d, {"triangles_per_visible_pixel"});
        if (over) parts.push_back(plural(*over, "object draws", "objects draw") + " more triangles than pixels it shows");
        if (perPixel) parts.push_back(fmtReal(*perPixel) + " triangles drawn per visible pixel");
        if (saved) parts.push_back("coarser detail or a draw distance would save " + plural(*saved, "triangle", "triangles"));
        if (parts.empty()) parts.push_back("see the level-of-detail section below");
    } else if (d && ranFalse(d)) {
        parts.push_back(notAnalysed(esc(str(get(d, "reason")))));
    }
    if (const Json *z = stageNamed(v, "zbuffer"); stageRan(z)) {
        const double empty = numOr(z, {"triangles_empty"}, 0), in = numOr(z, {"triangles_in"}, 0);
        if (empty > 0)
            parts.push_back(plural(empty, "triangle", "triangles") + " of " + fmtCount(in) + " reaching the z-buffer (" +
                            pct(empty, in) + ") cover no pixel center: sub-pixel detail");
        else
            parts.push_back("every triangle reaching the z-buffer covers a pixel");
    }
    if (parts.empty()) return notAnalysed("no detail section, no z-buffer stage");
    std::string o;
    for (size_t i = 0; i < parts.size(); ++i) o += (i ? "; " : "") + parts[i];
    return o + ".";
}

// What is obscured by what: the occlusion stage, the audit's wasted draws (drawn, visible nowhere)
// and the overdraw (fragments hidden behind nearer ones).
std::string answerObscured(const Json *v) {
    std::vector<std::string> parts;
    if (const Json *oc = stageNamed(v, "occlusion"); stageRan(oc))
        parts.push_back("occlusion culling removed " + plural(numOr(oc, {"triangles_culled"}, 0), "triangle", "triangles") +
                        " behind occluders");
    const Json *w = get(v, {"audit", "wasted_draws"});
    if (w && !ranFalse(get(v, "audit"))) {
        parts.push_back(fmtCount(numOr(w, {"triangles"}, 0)) + " of " + fmtCount(numOr(w, {"drawn_triangles"}, 0)) +
                        " drawn triangles (" + pct(numOr(w, {"triangles"}, 0), numOr(w, {"drawn_triangles"}, 0)) +
                        ") are visible nowhere, hidden behind others or sub-pixel, costing " +
                        plural(numOr(w, {"fragments"}, 0), "fragment", "fragments"));
    }
    if (const auto f = num(v, {"zbuffer", "fragments"}), c = num(v, {"zbuffer", "covered_pixels"}); f && c && *f >= *c)
        parts.push_back(plural(*f - *c, "fragment", "fragments") + " lie behind the nearest surface (depth complexity " +
                        fmtReal(numOr(v, {"zbuffer", "depth_complexity"}, NAN)) + ")");
    if (parts.empty()) return notAnalysed("");
    if (!stageRan(stageNamed(v, "occlusion"))) parts.push_back("no occlusion stage ran");
    std::string o;
    for (size_t i = 0; i < parts.size(); ++i) o += (i ? "; " : "") + parts[i];
    return o + ".";
}

// What is in front of what: the ordering methods' wrong pixels, and where the depth format
// cannot order two surfaces (z-fighting in the view's own format).
std::string answerOrder(const Json *v, const std::vector<std::pair<std::string, const Json *>> &methods) {
    std::vector<std::string> parts;
    for (const auto &[name, row] : methods)
        if (auto wrong = num(get(row, "wrong_pixels")))
            parts.push_back(esc(name) + " gets " + plural(*wrong, "pixel", "pixels") + " wrong");
    if (const auto z = zfightInOwnFormat(v)) {
        const std::string fmt = esc(str(v, {"depth_format"}));
        if (*z > 0) {
            std::string s = "the z-buffer (" + fmt + ") cannot order the two nearest surfaces at " + plural(*z, "pixel", "pixels");
            const Json *hs = get(v, {"depth", "hotspots"});
            if (hs && hs->is_array() && !hs->empty()) {
                const Json *objs = get(&hs->front(), "objects");
                const double area = numOr(&hs->front(), {"area"}, 0);
                if (objs && objs->is_array() && objs->size() == 2)
                    s += ", worst where " + esc(str(&(*objs)[0])) + " and " + esc(str(&(*objs)[1])) + " meet (hotspot 1, " +
                         plural(area, "pixel", "pixels") +
                         (area > 0 && numOr(&hs->front(), {"coplanar_pixels"}, -1) == area
                              ? ", coplanar: no depth format can order them; offset one or use a depth bias"
                              : "") +
                         ")";
            }
            parts.push_back(s);
        } else {
            parts.push_back("the z-buffer (" + fmt + ") orders every pixel's two nearest surfaces");
        }
    }
    if (parts.empty()) return notAnalysed("no ordering or depth section");
    if (methods.empty()) parts.push_back("painter's and BSP ordering not analysed");
    std::string o;
    for (size_t i = 0; i < parts.size(); ++i) o += (i ? "; " : "") + parts[i];
    return o + ".";
}

// What stands between a surface and a light: shadow rays per light (raycast.lights or
// effects.lights), else the planner's reason for not tracing them.
std::string answerShadows(const Json *v, const Json *report) {
    const Json *lights = get(v, {"raycast", "lights"});
    if (!lights || !lights->is_array()) lights = get(v, {"effects", "lights"});
    if (lights && lights->is_array() && !lights->empty()) {
        std::string o;
        for (const Json &l : *lights) {
            const double sh = numOr(&l, {"shadowed_pixels"}, 0), lit = numOr(&l, {"lit_pixels"}, 0);
            o += (o.empty() ? "" : "; ") + std::string("light ") + esc(str(get(&l, "name"))) + ": " +
                 plural(sh, "pixel is", "pixels are") + " shadowed (something stands between surface and light), " +
                 fmtCount(lit) + " lit (" + pct(sh, sh + lit) + " shadowed)";
        }
        return o + ".";
    }
    const Json *decisions = get(report, {"effects", "decisions"});
    if (decisions && decisions->is_array())
        for (const Json &d : *decisions) {
            const std::string name = str(get(&d, "name"));
            if (name.find("shadow") != std::string::npos && !isTrue(get(&d, "ran")))
                return notAnalysed(esc(str(get(&d, "reason"))));
        }
    return notAnalysed("no shadow rays in this report");
}

// ---- Per-view sections -------------------------------------------------------------------------------

// An ordering section in any of the shapes it may take: an array of rows, an object holding such
// an array, or an object of per-method objects. Each method: (name, row).
std::vector<std::pair<std::string, const Json *>> orderingMethods(const Json *ordering) {
    std::vector<std::pair<std::string, const Json *>> out;
    if (!ordering || ranFalse(ordering)) return out;
    // The rows: the array itself; else the member "table" or "methods"; else the first array of
    // objects that name a "method"; else the first array of objects.
    const Json *rows = nullptr;
    const auto tableLike = [](const Json &a) { return a.is_array() && !a.empty() && a.front().is_object(); };
    if (ordering->is_array()) {
        rows = ordering;
    } else if (ordering->is_object()) {
        for (const char *k : {"table", "methods"})
            if (const Json *t = get(ordering, k); t && tableLike(*t) && !rows) rows = t;
        for (auto it = ordering->begin(); it != ordering->end() && !rows; ++it)
            if (tableLike(it.value()) && get(&it.value().front(), "method")) rows = &it.value();
        for (auto it = ordering->begin(); it != ordering->end() && !rows; ++it)
            if (tableLike(it.value())) rows = &it.value();
    }
    if (rows) {
        for (const Json &r : *rows) {
            if (!r.is_object()) continue;
            std::string name = str(get(&r, "method"));
            if (name.empty()) name = str(get(&r, "name"));
            out.emplace_back(name.empty() ? "method " + std::to_string(out.size() + 1) : name, &r);
        }
    } else if (ordering->is_object()) {
        for (auto it = ordering->begin(); it != ordering->end(); ++it)
            if (it.value().is_object()) out.emplace_back(it.key(), &it.value());
    }
    return out;
}

// A method's time: its "ms", else the sum of its "*_ms" fields (build + draw).
std::optional<double> methodMs(const Json *row) {
    if (auto ms = num(get(row, "ms"))) return ms;
    std::optional<double> sum;
    for (auto it = row->begin(); it != row->end(); ++it) {
        const std::string &k = it.key();
        if (k.size() > 3 && k.compare(k.size() - 3, 3, "_ms") == 0 && it.value().is_number())
            sum = sum.value_or(0) + it.value().get<double>();
    }
    return sum;
}

struct HtmlWriter {
    const Json &report;
    Folder folder;
    std::map<std::pair<std::pair<double, double>, std::string>, DepthAuditResult> audits;  // by (near, far), formats
    std::string o;

    void header(const std::vector<ViewScore> &worstFirst);
    void summary(const std::vector<ViewScore> &worstFirst);
    void planner();
    void quakeMap();
    void depthAuditImage();
    void pvsAuditLink();
    void view(const Json *v, size_t pos);
    // eager: load with the page (the first views); else lazily, when scrolled near (reports of
    // hundreds of views would otherwise load thousands of PNGs at once).
    void images(const Json *v, const std::string &id, const std::vector<ViewImage> &imgs, bool eager);
    void hotspots(const Json *v, const std::string &id, const std::vector<ViewImage> &imgs);
    void falseCulls(const Json *v, const std::string &id, const std::vector<ViewImage> &imgs);
    void pvsEvidence(const Json *v, const std::string &id, const std::vector<ViewImage> &imgs);
    void raycast(const Json *v, const std::string &id, const std::vector<ViewImage> &imgs);
    void depthFormats(const Json *v, const std::string &id);
    void accuracy(const Json *v, const std::string &id,
                  const std::vector<std::pair<std::string, const Json *>> &methods);
    void stageTable(const Json *v);
};

// Finds the image with this slug (or slug prefix "shadow" for shadow-1, ...).
const ViewImage *findImage(const std::vector<ViewImage> &imgs, std::string_view slugName) {
    for (const ViewImage &im : imgs)
        if (im.slug == slugName) return &im;
    return nullptr;
}

// A highlight box over an image: an element hidden until it is the :target. (x0, y0, x1, y1) are
// inclusive pixel bounds in the view; the PNG's own size scales them (the legend strip lies below
// the view's rows, so y keeps its origin at the top).
std::string highlightBox(const std::string &boxId, const ViewImage &im, double x0, double y0, double x1, double y1,
                         const std::string &title) {
    if (im.width <= 0 || im.height <= 0) return {};
    x0 = std::clamp(x0, 0.0, double(im.width - 1));
    x1 = std::clamp(x1, x0, double(im.width - 1));
    y0 = std::clamp(y0, 0.0, double(im.height - 1));
    y1 = std::clamp(y1, y0, double(im.height - 1));
    return "<span class=\"hl\" id=\"" + boxId + "\" title=\"" + esc(title) + "\" style=\"left:" + fx(100.0 * x0 / im.width) +
           "%;top:" + fx(100.0 * y0 / im.height) + "%;width:" + fx(100.0 * (x1 - x0 + 1) / im.width) + "%;height:" +
           fx(100.0 * (y1 - y0 + 1) / im.height) + "%\"></span>";
}

void HtmlWriter::header(const std::vector<ViewScore> &worstFirst) {
    const Json *r = &report;
    const std::string scenePath = str(r, {"scene", "path"});
    o += "<header><h1>visaudit report: " + esc(scenePath.empty() ? "(unnamed scene)" : scenePath) + "</h1>";
    o += "<div class=\"meta\">" + esc(str(r, {"tool", "name"})) + " " + esc(str(r, {"tool", "version"})) + " · " +
         esc(str(r, {"format"})) + " · " + fmtCount(numOr(r, {"scene", "triangles"}, 0)) + " triangles in " +
         fmtCount(numOr(r, {"scene", "objects"}, 0)) + " culling objects (" +
         fmtCount(numOr(r, {"scene", "source_objects"}, 0)) + " source objects)";
    if (auto k = num(r, {"shard", "index"}), n = num(r, {"shard", "count"}); k && n && *n > 1)
        o += " · shard " + fmtCount(*k) + "/" + fmtCount(*n);
    o += " · " + plural(double(worstFirst.size()), "view", "views") + "</div>";

    // The verdict: the worst findings over all views, in the summary's order of severity.
    double fc = 0, gen = 0, zf = 0;
    size_t fcViews = 0, genViews = 0, zfViews = 0;
    const ViewScore *worstOverdraw = nullptr;
    for (const ViewScore &s : worstFirst) {
        fc += s.falseCullPixels.value_or(0), fcViews += s.falseCullPixels.value_or(0) > 0;
        gen += s.genuine.value_or(0), genViews += s.genuine.value_or(0) > 0;
        zf += s.zfightPixels.value_or(0), zfViews += s.zfightPixels.value_or(0) > 0;
        if (s.overdraw && (!worstOverdraw || *s.overdraw > *worstOverdraw->overdraw)) worstOverdraw = &s;
    }
    std::vector<std::string> findings;
    if (fc > 0) findings.push_back("<b>" + plural(fc, "falsely culled pixel", "falsely culled pixels") + "</b> in " + plural(double(fcViews), "view", "views"));
    if (gen > 0) findings.push_back("<b>" + plural(gen, "genuine ray-cast disagreement", "genuine ray-cast disagreements") + "</b> in " + plural(double(genViews), "view", "views"));
    if (zf > 0) {
        // Coplanar fights are a geometry problem (no format helps); say how many there are.
        double coplanar = 0;
        for (const Json *v : viewsOf(report))
            coplanar += num(v, {"depth", "formats", str(v, {"depth_format"}), "coplanar_pixels"}).value_or(0);
        findings.push_back("<b>" + plural(zf, "z-fighting pixel", "z-fighting pixels") + "</b> in " +
                           plural(double(zfViews), "view", "views") + " (in their own depth format; " +
                           fmtCount(coplanar) + " of them coplanar)");
    }
    const bool bad = !findings.empty();
    if (!bad) findings.push_back("<b>no false culls, ray-cast disagreements or z-fighting found</b>");
    if (worstOverdraw)
        findings.push_back("overdraw up to " + fmtReal(*worstOverdraw->overdraw) + " (" + esc(worstOverdraw->name) + ")");
    o += "<p class=\"verdict " + std::string(bad ? "bad" : "good") + "\" id=\"verdict\">";
    for (size_t i = 0; i < findings.size(); ++i) o += (i ? " · " : "") + findings[i];
    o += "</p><nav class=\"toc\">Views: ";
    for (const ViewScore &s : worstFirst) o += "<a href=\"#" + viewId(s.pos) + "\">" + esc(s.name) + "</a>";
    o += "</nav></header>";
}

void HtmlWriter::summary(const std::vector<ViewScore> &worstFirst) {
    o += "<section class=\"block\" id=\"summary\"><h2>Summary across views, worst first</h2>";
    o += "<p class=\"note\">Ordered by false-cull pixels, then genuine ray-cast disagreements, then z-fighting pixels in "
         "the view's depth format, then overdraw. — means the report has no such analysis for the view.</p>";
    o += "<div class=\"scroll\"><table id=\"summary-table\"><tr><th>view</th><th class=\"n\">false-cull px</th>"
         "<th class=\"n\">genuine disagreements</th><th class=\"n\">z-fight px</th><th class=\"n\">hotspots</th>"
         "<th class=\"n\">overdraw</th><th class=\"n\">depth complexity</th><th class=\"n\">wasted draws</th>"
         "<th class=\"n\">triangles drawn</th><th class=\"n\">time</th></tr>";
    const auto cell = [](const std::optional<double> &v, bool flag, bool real = false) {
        if (!v) return std::string("<td class=\"n muted\">—</td>");
        return std::string("<td class=\"n") + (flag && *v > 0 ? " bad" : "") + "\">" + (real ? fmtReal(*v) : fmtCount(*v)) +
               "</td>";
    };
    for (const ViewScore &s : worstFirst) {
        o += "<tr><td><a href=\"#" + viewId(s.pos) + "\">" + esc(s.name) + "</a></td>";
        o += cell(s.falseCullPixels, true) + cell(s.genuine, true) + cell(s.zfightPixels, true) + cell(s.hotspots, true);
        o += cell(s.overdraw, false, true) + cell(s.complexity, false, true);
        o += s.wastedShare ? "<td class=\"n\">" + pct(*s.wastedShare, 1) + "</td>" : "<td class=\"n muted\">—</td>";
        o += cell(s.drawn, false) + "<td class=\"n\">" + fmtMs(s.ms) + "</td></tr>";
    }
    o += "</table></div></section>";
}

// The planner's decisions (report-level "effects": which effects ran and why).
void HtmlWriter::planner() {
    const Json *fx = get(&report, "effects");
    if (!fx || !fx->is_object()) return;
    o += "<section class=\"block\" id=\"planner\"><h2>Planner: what the scene calls for</h2>";
    // One line of decisions ("shadows: no (scene has no lights)"), the whole section folded below.
    const Json *decisions = get(fx, "decisions");
    std::string line;
    if (decisions && decisions->is_array())
        for (const Json &d : *decisions) {
            const std::string reason = str(get(&d, "reason"));
            line += (line.empty() ? "" : " · ") + std::string("<b>") + esc(str(get(&d, "name"))) + "</b>: " +
                    (isTrue(get(&d, "ran")) ? "runs" : "does not run") + (reason.empty() ? "" : " (" + esc(reason) + ")");
        }
    if (!line.empty()) o += "<p id=\"planner-decisions\">" + line + "</p>";
    o += "<details><summary>all values</summary>" + genericJson(fx) + "</details></section>";
}

// A Quake 3 map's structure: clusters, the designed far plane, and the brush entities the engine
// never draws (docs/quake3.md, "Brush entities" and "The far plane").
void HtmlWriter::quakeMap() {
    const Json *b = get(&report, {"scene", "bsp"});
    if (!b || !b->is_object()) return;
    o += "<section class=\"block\" id=\"quake-map\"><h2>Quake 3 map</h2><p>" + fmtCount(numOr(b, {"leafs"}, 0)) +
         " leafs in " + fmtCount(numOr(b, {"clusters"}, 0)) + " clusters, " +
         (isTrue(get(b, "has_pvs")) ? "with a PVS" : "<b>no PVS</b> (compiled without vis)") + "; " +
         plural(numOr(b, {"brush_entities_drawn"}, 0), "drawn brush entity", "drawn brush entities") + " (" +
         plural(numOr(b, {"model_faces"}, 0), "face", "faces") +
         ", clustered by their box through the world's tree).</p>";
    const Json *fp = get(b, "far_plane");
    if (fp && fp->is_object())
        o += "<p id=\"far-plane\">Designed far plane: <code>" + esc(str(get(fp, "key"))) + " " + esc(str(get(fp, "value"))) +
             "</code> = " + fmtReal(numOr(fp, {"distance"}, 0)) +
             " units. The compiler leaves portal pairs farther apart out of the PVS on purpose: views made from the map "
             "use it as their far plane, and a surface the PVS leaves out that lies farther than it from the eye is "
             "reported as hidden by design, not as a false cull.</p>";
    else
        o += "<p id=\"far-plane\" class=\"note\">No designed far plane (<code>_farplanedist</code>).</p>";
    o += "<h3 id=\"not-drawn-entities\">Brush entities the engine never draws (not geometry)</h3>";
    const Json *nd = get(b, "not_drawn_entities");
    const double ndCount = numOr(b, {"brush_entities_not_drawn"}, 0);
    if (nd && nd->is_array() && !nd->empty()) {
        o += "<p>" + plural(numOr(b, {"not_drawn_entity_faces"}, 0), "face", "faces") + " (" +
             plural(numOr(b, {"not_drawn_entity_triangles"}, 0), "triangle", "triangles") + ") of " +
             plural(ndCount, "brush entity", "brush entities") +
             " the game never draws (triggers, models no entity spawns) are kept out of the scene:</p>";
        o += "<div class=\"scroll\"><table id=\"not-drawn-table\"><tr><th class=\"n\">model</th><th class=\"n\">entity</th>"
             "<th>classname</th><th>why</th><th class=\"n\">faces</th><th class=\"n\">triangles</th></tr>";
        for (const Json &e : *nd)
            o += "<tr><td class=\"n\">*" + fmtValue(get(&e, "model")) + "</td><td class=\"n\">" + fmtValue(get(&e, "entity")) +
                 "</td><td>" + esc(str(get(&e, "classname"))) + "</td><td>" + esc(str(get(&e, "reason"))) +
                 "</td><td class=\"n\">" + fmtValue(get(&e, "faces")) + "</td><td class=\"n\">" +
                 fmtValue(get(&e, "triangles")) + "</td></tr>";
        o += "</table></div>";
    } else {
        o += "<p class=\"note\">" + plural(ndCount, "brush entity", "brush entities") +
             " the game never draws, none with faces.</p>";
    }
    o += "</section>\n";
}

void HtmlWriter::depthAuditImage() {
    const std::string name = "depth-audit.png";
    if (!folder.exists(name)) return;
    o += "<section class=\"block\" id=\"depth-audit\"><h2>Depth-format resolution (depth-audit)</h2>";
    o += "<figure id=\"depth-audit-img\"><a class=\"enlarge imgwrap\" href=\"" + urlOf(name) +
         "\" data-title=\"depth-audit.png\"><img src=\"" + urlOf(name) + "\" alt=\"depth resolution per format\"";
    if (auto s = folder.png(name)) o += " width=\"" + std::to_string(s->first) + "\" height=\"" + std::to_string(s->second) + "\"";
    o += "></a><figcaption>Resolution (m) against view depth (m) per depth format, log-log, from "
         "<code>visaudit depth-audit</code>.</figcaption></figure></section>";
}

// check writes the PVS audit (pvs-audit.html, .png) next to report.json when its budget names a
// pvs_* metric: its map image and a link to its page.
void HtmlWriter::pvsAuditLink() {
    if (!folder.exists("pvs-audit.html")) return;
    o += "<section class=\"block\" id=\"pvs-audit\"><h2>PVS audit of every cluster</h2><p><a href=\"" +
         urlOf("pvs-audit.html") + "\">pvs-audit.html</a>: misses, slack and their evidence per cluster.</p>";
    const std::string name = "pvs-audit.png";
    if (folder.exists(name)) {
        o += "<figure id=\"pvs-audit-img\"><a class=\"enlarge imgwrap\" href=\"" + urlOf(name) +
             "\" data-title=\"pvs-audit.png\"><img src=\"" + urlOf(name) + "\" alt=\"the level from above, colored by slack and misses\"";
        if (auto sz = folder.png(name)) o += " width=\"" + std::to_string(sz->first) + "\" height=\"" + std::to_string(sz->second) + "\"";
        o += "></a><figcaption>The level from above, each floor colored by its cluster's misses and slack.</figcaption></figure>";
    }
    o += "</section>";
}

void HtmlWriter::stageTable(const Json *v) {
    const Json *stages = get(v, "stages");
    if (!stages || !stages->is_array()) return;
    o += "<details><summary>Stage details</summary><div class=\"scroll\"><table><tr><th>stage</th><th class=\"n\">in</th>"
         "<th class=\"n\">culled</th><th class=\"n\">out</th><th class=\"n\">time</th><th>more</th></tr>";
    static const std::set<std::string> common = {"name", "ran", "reason", "triangles_in", "triangles_culled", "triangles_out", "ms"};
    for (const Json &s : *stages) {
        const bool ran = stageRan(&s);
        o += std::string("<tr") + (ran ? "" : " class=\"skipped\"") + "><td>" + esc(str(get(&s, "name"))) + "</td>";
        if (!ran) {
            o += "<td colspan=\"4\">skipped: " + esc(str(get(&s, "reason"))) + "</td><td></td></tr>";
            continue;
        }
        o += "<td class=\"n\">" + fmtValue(get(&s, "triangles_in")) + "</td><td class=\"n\">" +
             fmtValue(get(&s, "triangles_culled")) + "</td><td class=\"n\">" + fmtValue(get(&s, "triangles_out")) +
             "</td><td class=\"n\">" + fmtMs(num(get(&s, "ms"))) + "</td><td class=\"mono\">";
        std::string more;
        for (auto it = s.begin(); it != s.end(); ++it) {
            if (common.count(it.key())) continue;
            more += (more.empty() ? "" : ", ") + esc(it.key()) + " ";
            if (it.value().is_object()) {
                std::string inner;
                for (auto m = it.value().begin(); m != it.value().end(); ++m)
                    inner += (inner.empty() ? "" : " ") + esc(m.key()) + ":" + fmtValue(&m.value());
                more += "{" + inner + "}";
            } else {
                more += fmtValue(&it.value());
            }
        }
        o += more + "</td></tr>";
    }
    o += "</table></div></details>";
}

void HtmlWriter::images(const Json *v, const std::string &id, const std::vector<ViewImage> &imgs, bool eager) {
    if (imgs.empty()) {
        o += "<p class=\"note\">No images in the report folder for this view.</p>";
        return;
    }
    o += "<div class=\"gallery\">";
    for (const ViewImage &im : imgs) {
        o += "<figure id=\"" + id + "-img-" + im.slug + "\"><a class=\"enlarge imgwrap\" href=\"" + urlOf(im.file) +
             "\" data-title=\"" + esc(im.title + " — " + im.file) + "\"><img src=\"" + urlOf(im.file) + "\" alt=\"" +
             esc(im.title) + "\" loading=\"" + (eager ? "eager" : "lazy") + "\"";
        if (im.width > 0) o += " width=\"" + std::to_string(im.width) + "\" height=\"" + std::to_string(im.height) + "\"";
        o += ">";
        // Highlight boxes belong to the image they mark (see hotspots / raycast).
        if (im.slug == "zfight") {
            const Json *hs = get(v, {"depth", "hotspots"});
            if (hs && hs->is_array())
                for (const Json &h : *hs) {
                    const Json *bb = get(&h, "bbox");
                    if (!bb || !bb->is_array() || bb->size() != 4 || !(*bb)[0].is_number()) continue;
                    const std::string hid = fmtValue(get(&h, "id"));
                    o += highlightBox(id + "-hs" + slug(hid), im, (*bb)[0].get<double>(), (*bb)[1].get<double>(),
                                      (*bb)[2].get<double>(), (*bb)[3].get<double>(), "hotspot " + hid);
                }
        }
        if (im.slug == "raycast") {
            const Json *ex = get(v, {"raycast", "cross_check", "genuine_examples"});
            size_t k = 0;
            if (ex && ex->is_array())
                for (const Json &e : *ex) {
                    ++k;
                    const auto x = num(get(&e, "x")), y = num(get(&e, "y"));
                    if (x && y)
                        o += highlightBox(id + "-gx" + std::to_string(k), im, *x - 4, *y - 4, *x + 4, *y + 4,
                                          "pixel (" + fmtCount(*x) + ", " + fmtCount(*y) + ")");
                }
        }
        o += "</a><figcaption><b>" + esc(im.title) + "</b> <code>" + esc(im.file) + "</code>";
        if (!im.legend.empty()) o += "<br>" + esc(im.legend);
        o += "</figcaption></figure>";
    }
    o += "</div>";
    // Data files (EXR) are listed as links; a browser cannot show them.
    const Json *images = get(v, "images");
    std::string data;
    if (images && images->is_object())
        for (auto it = images->begin(); it != images->end(); ++it)
            if (it.value().is_string() && it.key().size() > 4 && it.key().compare(it.key().size() - 4, 4, "_exr") == 0 &&
                folder.exists(it.value().get<std::string>()))
                data += " <a href=\"" + urlOf(it.value().get<std::string>()) + "\">" + esc(it.value().get<std::string>()) + "</a>";
    if (!data.empty()) o += "<p class=\"note\">Data files (OpenEXR):" + data + "</p>";
}

void HtmlWriter::hotspots(const Json *v, const std::string &id, const std::vector<ViewImage> &imgs) {
    const Json *d = get(v, "depth");
    if (!d) return;
    o += "<h3 id=\"" + id + "-hotspots\">Z-fighting hotspots</h3>";
    if (ranFalse(d)) {
        o += "<p class=\"note\">Not analysed: " + esc(str(get(d, "reason"))) + "</p>";
        return;
    }
    const Json *hs = get(d, "hotspots");
    const double count = numOr(d, {"hotspot_count"}, hs && hs->is_array() ? double(hs->size()) : 0);
    if (!hs || !hs->is_array() || hs->empty()) {
        o += "<p class=\"good\">No hotspots: no two surfaces fight in any depth format.</p>";
        return;
    }
    const ViewImage *zimg = findImage(imgs, "zfight");
    o += "<p class=\"note\">" + plural(count, "hotspot", "hotspots") + (count > double(hs->size()) ? " (the largest " + fmtCount(double(hs->size())) + " listed)" : "") +
         ". Click a row's “show” to outline its pixels on the z-fighting image. Classes of fighting pixels: ";
    const Json *classes = get(d, "classes");
    if (classes && classes->is_object()) {
        std::string c;
        for (auto it = classes->begin(); it != classes->end(); ++it)
            c += (c.empty() ? "" : ", ") + label(it.key()) + " " + fmtValue(&it.value());
        o += c;
    }
    o += ".</p><div class=\"scroll\"><table class=\"hotspots\"><tr><th>id</th><th class=\"n\">area (px)</th>"
         "<th>pixels (bbox)</th><th>world position</th><th class=\"n\">depth</th><th>objects</th><th class=\"n\">gap</th>"
         "<th>fights in</th><th>why</th></tr>";
    for (const Json &h : *hs) {
        const std::string hid = fmtValue(get(&h, "id"));
        o += "<tr><td>" + hid + "</td><td class=\"n\">" + fmtValue(get(&h, "area")) + "</td><td>";
        const Json *bb = get(&h, "bbox");
        std::string bbText = fmtValue(bb);
        if (zimg && bb && bb->is_array() && bb->size() == 4 && zimg->width > 0)
            o += "<a class=\"px\" href=\"#" + id + "-hs" + slug(hid) + "\">show " + bbText + "</a>";
        else
            o += bbText;
        o += "</td><td class=\"mono\">" + fmtValue(get(&h, "centroid")) + "</td><td class=\"n\">" + fmtValue(get(&h, "depth")) +
             "</td><td>" + fmtValue(get(&h, "objects")) + "</td><td class=\"n\">";
        const double gap = numOr(&h, {"depth_gap"}, NAN);
        const double area = numOr(&h, {"area"}, 0), cop = numOr(&h, {"coplanar_pixels"}, -1);
        o += (cop >= 0 && cop == area && area > 0) ? "coplanar" : fmtReal(gap);
        o += "</td><td>";
        const Json *fmts = get(&h, "formats");
        if (fmts && fmts->is_array()) {
            if (const Json *all = get(d, "formats"); all && all->is_object() && fmts->size() == all->size()) {
                o += "every format";
            } else {
                std::string f;
                for (const Json &e : *fmts)
                    f += (f.empty() ? "" : ", ") + esc(str(get(&e, "name"))) + " (" + fmtValue(get(&e, "pixels")) + ")";
                o += f;
            }
        }
        // Why: the gap against the view format's bucket there, and the cheapest format that orders it.
        o += "</td><td>" + esc(str(&h, {"why"})) + "</td></tr>";
    }
    o += "</table></div>";
}

void HtmlWriter::falseCulls(const Json *v, const std::string &id, const std::vector<ViewImage> &imgs) {
    const Json *a = get(v, "audit");
    if (!a) return;
    o += "<h3 id=\"" + id + "-falsecull\">False culls and wasted draws</h3>";
    if (ranFalse(a)) {
        o += "<p class=\"note\">Not analysed: " + esc(str(get(a, "reason"))) + "</p>";
        return;
    }
    const Json *fc = get(a, "false_culls");
    const bool haveImg = findImage(imgs, "culling") != nullptr;
    const std::string imgLink = "#" + id + "-img-culling";
    o += "<p>Against the reference visibility (" + fmtCount(numOr(a, {"reference", "visible_triangles"}, 0)) +
         " visible triangles, " + fmtCount(numOr(a, {"reference", "covered_pixels"}, 0)) + " covered pixels): ";
    const double fcPx = numOr(fc, {"pixels"}, 0);
    o += fcPx > 0 ? "<b class=\"bad\">" + plural(numOr(fc, {"triangles"}, 0), "triangle", "triangles") +
                        " culled yet visible, at " + plural(fcPx, "pixel", "pixels") + "</b>"
                  : "<span class=\"good\">no visible triangle was culled</span>";
    if (const auto un = num(a, {"unaccounted_pixels"}); un && *un > 0)
        o += "; <b class=\"bad\">" + plural(*un, "pixel", "pixels") + " unaccounted for</b>";
    o += ".</p>";
    const Json *byStage = get(fc, "by_stage");
    if (byStage && byStage->is_object() && !byStage->empty()) {
        o += "<div class=\"scroll\"><table class=\"falsecull\"><tr><th>stage</th><th class=\"n\">triangles culled</th>"
             "<th class=\"n\">objects culled</th><th class=\"n\">false-cull triangles</th><th class=\"n\">objects</th>"
             "<th class=\"n\">pixels</th><th>worst offenders (object: triangles, pixels)</th></tr>";
        for (auto it = byStage->begin(); it != byStage->end(); ++it) {
            const Json *s = &it.value();
            const double px = numOr(s, {"false_cull_pixels"}, 0);
            o += "<tr><td>" + esc(it.key()) + "</td><td class=\"n\">" + fmtValue(get(s, "triangles_culled")) +
                 "</td><td class=\"n\">" + fmtValue(get(s, "objects_culled")) + "</td><td class=\"n" +
                 (numOr(s, {"false_cull_triangles"}, 0) > 0 ? " bad" : "") + "\">" + fmtValue(get(s, "false_cull_triangles")) +
                 "</td><td class=\"n\">" + fmtValue(get(s, "false_cull_objects")) + "</td><td class=\"n\">";
            o += px > 0 && haveImg ? "<a class=\"px\" href=\"" + imgLink + "\">" + fmtCount(px) + "</a>" : fmtValue(get(s, "false_cull_pixels"));
            o += "</td><td>";
            const Json *worst = get(s, "worst");
            if (worst && worst->is_array() && !worst->empty()) {
                std::string w;
                for (const Json &e : *worst) {
                    std::string one = esc(str(get(&e, "name"))) + " (#" + fmtValue(get(&e, "object")) + "): " +
                                      fmtValue(get(&e, "triangles")) + ", " + fmtValue(get(&e, "pixels")) + " px";
                    if (haveImg) one = "<a class=\"px\" href=\"" + imgLink + "\">" + one + "</a>";
                    w += (w.empty() ? "" : "; ") + one;
                }
                o += w;
            } else {
                o += "<span class=\"muted\">none</span>";
            }
            o += "</td></tr>";
        }
        o += "</table></div>";
        if (haveImg && fcPx > 0)
            o += "<p class=\"note\">Pixel links go to the culling-fates image, where each stage's false culls have the color "
                 "its legend strip names.</p>";
        double snappedTris = 0, snappedPx = 0;
        for (auto it = byStage->begin(); it != byStage->end(); ++it) {
            snappedTris += numOr(&it.value(), {"snapped_triangles"}, 0);
            snappedPx += numOr(&it.value(), {"snapped_pixels"}, 0);
        }
        if (snappedTris > 0)
            o += "<p class=\"note\">Not counted above: " + plural(snappedTris, "back-facing sliver", "back-facing slivers") +
                 " (" + plural(snappedPx, "pixel", "pixels") + ") culled rightly by the backface stage: the reference "
                 "sees a front winding only because snapping to the 1/256-pixel grid flipped it.</p>";
        for (auto it = byStage->begin(); it != byStage->end(); ++it) {
            const Json *st = &it.value();
            const double bpx = numOr(st, {"beyond_far_plane_pixels"}, 0);
            if (bpx <= 0) continue;
            o += "<p class=\"note\" id=\"" + id + "-beyond\">Not counted above: " + plural(bpx, "pixel", "pixels") +
                 " of surfaces the " + esc(it.key()) + " stage left out lie beyond the map's far plane (" +
                 fmtReal(numOr(st, {"design_far_plane"}, 0)) + " units; the nearest " +
                 fmtReal(numOr(st, {"beyond_far_plane_nearest"}, 0)) +
                 " units from the eye): hidden by design, as the compiler's distance rule leaves them out (" +
                 plural(numOr(st, {"beyond_far_plane_triangles"}, 0), "triangle", "triangles") +
                 " visible only there).</p>";
        }
    }
    pvsEvidence(v, id, imgs);
    if (const Json *w = get(a, "wasted_draws"); w && w->is_object())
        o += "<p>Wasted draws: " + fmtCount(numOr(w, {"triangles"}, 0)) + " of " + fmtCount(numOr(w, {"drawn_triangles"}, 0)) +
             " drawn triangles (" + pct(numOr(w, {"share"}, 0), 1) + ") and " + fmtCount(numOr(w, {"objects"}, 0)) + " of " +
             fmtCount(numOr(w, {"drawn_objects"}, 0)) + " drawn objects are visible nowhere; they cost " +
             fmtCount(numOr(w, {"fragments"}, 0)) + " of " + fmtCount(numOr(w, {"drawn_fragments"}, 0)) + " fragments.</p>";
}

// An index (leaf, cluster, face, object) as written, without thousands separators; "—" if absent.
std::string rawInt(const Json *j) {
    if (!j || !j->is_number_integer()) return "—";
    return j->is_number_unsigned() ? std::to_string(j->get<uint64_t>()) : std::to_string(j->get<int64_t>());
}

// The evidence of the PVS's false culls (audit.pvs_evidence; docs/quake3.md, "Reading the evidence"),
// next to the culling-fates image with a box on each face's nearest pixel.
void HtmlWriter::pvsEvidence(const Json *v, const std::string &id, const std::vector<ViewImage> &imgs) {
    const Json *e = get(v, {"audit", "pvs_evidence"});
    const Json *objs = get(e, "objects");
    if (!objs || !objs->is_array() || objs->empty()) return;
    o += "<h4 id=\"" + id + "-evidence\">Evidence of the PVS's false culls</h4><p>The eye is in leaf " +
         rawInt(get(e, "camera_leaf")) + ", cluster <b>" + rawInt(get(e, "camera_cluster")) +
         "</b>. Each face below is visible in the reference, yet every cluster of its object has bit 0 in that "
         "cluster's PVS row: the map's PVS says the eye cannot see it. Each leaf listing the face is shown with its "
         "cluster and that bit (a leaf the world's tree never reaches is a brush model's own); a brush model's "
         "clusters are those of the leafs its box reaches. Distances are from the eye to the nearest visible point";
    if (const auto fp = num(get(e, "design_far_plane"))) o += ", all within the map's far plane of " + fmtReal(*fp);
    o += ".";
    if (const auto om = num(get(e, "objects_omitted")); om && *om > 0)
        o += " " + plural(*om, "more object is", "more objects are") + " left out (the list keeps the worst " +
             std::to_string(objs->size()) + ").";
    o += "</p><div class=\"evidence\">";
    const ViewImage *cull = findImage(imgs, "culling");
    if (cull) {
        o += "<figure id=\"" + id + "-ev-img\"><a class=\"enlarge imgwrap\" href=\"" + urlOf(cull->file) +
             "\" data-title=\"" + esc(cull->title + " — " + cull->file) + "\"><img src=\"" + urlOf(cull->file) +
             "\" alt=\"" + esc(cull->title) + "\" loading=\"lazy\"";
        if (cull->width > 0)
            o += " width=\"" + std::to_string(cull->width) + "\" height=\"" + std::to_string(cull->height) + "\"";
        o += ">";
        size_t k = 0;
        for (const Json &ob : *objs)
            if (const Json *fs = get(&ob, "faces"); fs && fs->is_array())
                for (const Json &f : *fs) {
                    ++k;
                    const Json *px = get(&f, "pixel");
                    if (px && px->is_array() && px->size() == 2 && (*px)[0].is_number() && (*px)[1].is_number())
                        o += highlightBox(id + "-ev" + std::to_string(k), *cull, (*px)[0].get<double>() - 4,
                                          (*px)[1].get<double>() - 4, (*px)[0].get<double>() + 4,
                                          (*px)[1].get<double>() + 4, "face " + rawInt(get(&f, "face")));
                }
        o += "</a><figcaption><b>" + esc(cull->title) + "</b> <code>" + esc(cull->file) + "</code></figcaption></figure>";
    }
    o += "<div class=\"scroll\"><table class=\"evidence-table\"><tr><th>object</th><th>its clusters (PVS bit)</th>"
         "<th>face</th><th class=\"n\">px</th><th class=\"n\">nearest</th><th>leafs listing the face: cluster, PVS bit</th></tr>";
    auto leafList = [&](const Json *ls, const Json *omitted) {
        std::string t;
        if (ls && ls->is_array())
            for (const Json &l : *ls) {
                const Json *bit = get(&l, "pvs_bit");
                t += (t.empty() ? "" : "; ") + std::string("leaf ") + rawInt(get(&l, "leaf")) + ": " +
                     (num(get(&l, "cluster")).value_or(-1) < 0 ? std::string("no cluster")
                                                               : "cluster " + rawInt(get(&l, "cluster")) + ", bit " +
                                                                     (bit && bit->is_number() ? fmtValue(bit) : "—")) +
                     (isTrue(get(&l, "in_tree")) ? "" : " (not in the tree)");
            }
        if (const auto om = num(omitted); om && *om > 0) t += " … " + fmtCount(*om) + " more";
        return t.empty() ? std::string("<span class=\"muted\">none</span>") : esc(t);
    };
    size_t k = 0;
    for (const Json &ob : *objs) {
        const Json *fs = get(&ob, "faces");
        const size_t rows = fs && fs->is_array() && !fs->empty() ? fs->size() : 1;
        std::string clusters;
        if (const Json *cs = get(&ob, "clusters"); cs && cs->is_array())
            for (const Json &c : *cs)
                clusters += (clusters.empty() ? "" : ", ") + rawInt(get(&c, "cluster")) + " (" + fmtValue(get(&c, "pvs_bit")) + ")";
        if (const auto om = num(get(&ob, "clusters_omitted")); om && *om > 0) clusters += " … " + fmtCount(*om) + " more";
        std::string who = "<b>" + esc(str(get(&ob, "name"))) + "</b> (#" + rawInt(get(&ob, "object")) + ")<br>" +
                          plural(numOr(&ob, {"triangles"}, 0), "triangle", "triangles") + ", " +
                          plural(numOr(&ob, {"pixels"}, 0), "pixel", "pixels");
        if (numOr(&ob, {"model"}, 0) > 0)
            who += "<br>model *" + rawInt(get(&ob, "model")) + " " + esc(str(get(&ob, "classname"))) +
                   "; box leafs: " + leafList(get(&ob, "box_leafs"), get(&ob, "box_leafs_omitted"));
        if (const auto om = num(get(&ob, "faces_omitted")); om && *om > 0)
            who += "<br>" + plural(*om, "more face", "more faces") + " not listed";
        o += "<tr><td rowspan=\"" + std::to_string(rows) + "\">" + who + "</td><td rowspan=\"" + std::to_string(rows) +
             "\">" + (clusters.empty() ? "<span class=\"muted\">none</span>" : esc(clusters)) + "</td>";
        if (!fs || !fs->is_array() || fs->empty()) {
            o += "<td colspan=\"4\" class=\"muted\">no face recorded</td></tr>";
            continue;
        }
        bool first = true;
        for (const Json &f : *fs) {
            ++k;
            if (!first) o += "<tr>";
            first = false;
            std::string face = "face " + rawInt(get(&f, "face"));
            if (cull) face = "<a class=\"px\" href=\"#" + id + "-ev" + std::to_string(k) + "\">" + face + "</a>";
            o += "<td>" + face + "</td><td class=\"n\">" + fmtValue(get(&f, "pixels")) + "</td><td class=\"n\">" +
                 fmtReal(numOr(&f, {"nearest"}, 0)) + "</td><td>" + leafList(get(&f, "leafs"), get(&f, "leafs_omitted")) +
                 "</td></tr>";
        }
    }
    o += "</table></div></div>";
}

void HtmlWriter::raycast(const Json *v, const std::string &id, const std::vector<ViewImage> &imgs) {
    const Json *r = get(v, "raycast");
    if (!r) return;
    o += "<h3 id=\"" + id + "-raycast\">Ray casting against the z-buffer</h3>";
    if (ranFalse(r)) {
        o += "<p class=\"note\">Not analysed: " + esc(str(get(r, "reason"))) + "</p>";
        return;
    }
    const Json *cc = get(r, "cross_check");
    if (cc && cc->is_object()) {
        const double px = numOr(cc, {"pixels"}, 0);
        o += "<div class=\"scroll\"><table class=\"crosscheck\"><tr><th>class</th><th class=\"n\">pixels</th><th class=\"n\">share</th></tr>";
        for (const char *k : {"agree", "edge", "tie", "genuine", "one_sided_background"})
            if (const auto n = num(get(cc, k)))
                o += std::string("<tr><td>") + label(k) + "</td><td class=\"n" + (std::string(k) == "genuine" && *n > 0 ? " bad" : "") +
                     "\">" + fmtCount(*n) + "</td><td class=\"n\">" + pct(*n, px) + "</td></tr>";
        o += "</table></div>";
        if (const auto culled = num(get(cc, "culled")); culled && *culled > 0)
            o += "<p class=\"note\" id=\"" + id + "-culled\">Compared like with like: at " + plural(*culled, "pixel", "pixels") +
                 " the ray caster over the whole scene hits a triangle a culling stage removed; the culling audit judges "
                 "those (false culls, hidden by design), and there the z-buffer was compared with the ray caster over "
                 "its own triangles. A genuine disagreement is one renderer disagreeing with the other on the same "
                 "triangles: 0 means no renderer bug.</p>";
        const Json *ex = get(cc, "genuine_examples");
        const ViewImage *diff = findImage(imgs, "raycast");
        if (ex && ex->is_array() && !ex->empty()) {
            o += "<p>Genuine disagreements (examples): ";
            size_t k = 0;
            std::string list;
            for (const Json &e : *ex) {
                ++k;
                std::string t = "(" + fmtValue(get(&e, "x")) + ", " + fmtValue(get(&e, "y")) + ") z-buffer id " +
                                fmtValue(get(&e, "zbuffer_id")) + " vs ray id " + fmtValue(get(&e, "raycast_id"));
                if (diff && diff->width > 0) t = "<a class=\"px\" href=\"#" + id + "-gx" + std::to_string(k) + "\">" + t + "</a>";
                list += (list.empty() ? "" : "; ") + t;
            }
            o += list + "</p>";
        }
    }
    // The rest of the section (effects rays, lights) as tables.
    Json rest = Json::object();
    for (auto it = r->begin(); it != r->end(); ++it)
        if (it.key() != "cross_check" && it.key() != "ran") rest[it.key()] = it.value();
    if (!rest.empty()) o += "<details><summary>Ray-casting details</summary>" + genericJson(&rest) + "</details>";
}

void HtmlWriter::depthFormats(const Json *v, const std::string &id) {
    const Json *d = get(v, "depth");
    const std::string own = str(v, {"depth_format"});
    o += "<h3 id=\"" + id + "-formats\">Depth formats</h3>";
    const Json *fmts = get(d, "formats");
    if (d && !ranFalse(d) && fmts && fmts->is_object()) {
        const std::string rec = str(d, {"recommended_format"});
        o += "<p>This view uses <b>" + esc(own) + "</b>; recommended: <b>" + (rec.empty() ? "none (every format fights)" : esc(rec)) +
             "</b>. " + esc(str(d, {"recommendation"})) + "</p>";
        std::vector<const Json *> rows;
        std::vector<std::string> names;
        for (auto it = fmts->begin(); it != fmts->end(); ++it) {
            rows.push_back(&it.value());
            names.push_back(it.key() + (it.key() == own ? " (this view)" : "") + (it.key() == rec ? " ✓ recommended" : ""));
        }
        o += rowsTable(rows, "format", names);
    } else {
        o += "<p class=\"note\">Z-fighting per format not analysed" + (d ? ": " + esc(str(get(d, "reason"))) : std::string()) + ".</p>";
    }
    // The resolution plot for this view's near/far.
    const auto nearZ = num(v, {"camera", "near"}), farZ = num(v, {"camera", "far"});
    std::string err;
    if (!nearZ || !farZ || !validateDepthAuditRange(*nearZ, *farZ, &err)) return;
    // The formats the view's z-fighting table holds (default: the classic twelve), in its order.
    std::vector<DepthFormatSpec> specs;
    std::string names;
    if (fmts && fmts->is_object())
        for (auto f = fmts->begin(); f != fmts->end(); ++f) {
            DepthFormatSpec spec;
            if (parseDepthFormat(f.key(), &spec, nullptr)) specs.push_back(spec), names += f.key() + ",";
        }
    if (specs.empty()) specs.assign(defaultZFightFormats().begin(), defaultZFightFormats().end());
    auto key = std::make_pair(std::make_pair(*nearZ, *farZ), names);
    auto it = audits.find(key);
    if (it == audits.end()) it = audits.emplace(key, auditDepthFormats(*nearZ, *farZ, specs)).first;
    if (!it->second.error.empty()) return;
    std::vector<std::pair<std::string, double>> markers;
    if (const Json *hs = get(d, "hotspots"); hs && hs->is_array())
        for (const Json &h : *hs)
            if (auto dep = num(get(&h, "depth")); dep && markers.size() < 12) markers.emplace_back("#" + fmtValue(get(&h, "id")), *dep);
    const std::string svg = resolutionSvg(it->second, own, markers, id + "-resolution");
    if (svg.empty()) return;
    o += "<p class=\"note\">Depth resolution (the distance between two adjacent stored values) against view depth for "
         "this view's near and far planes, every format; lower is finer. Dashed lines: the hotspots' depths.</p>" + svg;
}

void HtmlWriter::accuracy(const Json *v, const std::string &id,
                          const std::vector<std::pair<std::string, const Json *>> &methods) {
    const Json *ordering = get(v, "ordering");
    const Json *r = get(v, "raycast");
    const bool haveRay = r && !ranFalse(r) && get(r, "cross_check");
    if (!ordering && !haveRay) return;
    o += "<h3 id=\"" + id + "-accuracy\">Accuracy against time</h3>";
    if (ordering && ranFalse(ordering)) o += "<p class=\"note\">Ordering not analysed: " + esc(str(get(ordering, "reason"))) + "</p>";
    std::vector<ScatterPoint> pts;
    if (!methods.empty()) {
        std::vector<const Json *> rows;
        std::vector<std::string> names;
        for (const auto &[name, row] : methods) {
            rows.push_back(row);
            names.push_back(name);
            const auto ms = methodMs(row);
            const auto wrong = num(get(row, "wrong_pixels"));
            if (ms && wrong) pts.push_back({name, *ms, *wrong});
        }
        o += rowsTable(rows, "method", names);
    }
    if (haveRay) {
        // Visibility by ray casting next to the z-buffer: time of each stage, pixels where it
        // disagrees for real with the other (genuine) or where the z-buffer's format cannot order
        // the nearest surfaces (z-fighting).
        const Json *rs = stageNamed(v, "raycast"), *zs = stageNamed(v, "zbuffer");
        const auto rayMs = stageRan(rs) ? num(get(rs, "ms")) : num(v, {"raycast", "cross_check", "ms"});
        const auto zMs = stageRan(zs) ? num(get(zs, "ms")) : std::nullopt;
        const double genuine = numOr(r, {"cross_check", "genuine"}, 0);
        const auto zf = zfightInOwnFormat(v);
        o += "<div class=\"scroll\"><table class=\"accuracy\"><tr><th>visibility by</th><th class=\"n\">time</th>"
             "<th class=\"n\">wrong or undecided pixels</th><th>counted as</th></tr>";
        if (zMs) {
            o += "<tr><td>z-buffer (" + esc(str(v, {"depth_format"})) + ")</td><td class=\"n\">" + fmtMs(zMs) + "</td><td class=\"n\">" +
                 (zf ? fmtCount(*zf) : std::string("—")) + "</td><td>z-fighting pixels in its format</td></tr>";
            if (zf && methods.empty()) pts.push_back({"z-buffer", *zMs, *zf});
        }
        o += "<tr><td>ray casting</td><td class=\"n\">" + fmtMs(rayMs) + "</td><td class=\"n\">" + fmtCount(genuine) +
             "</td><td>genuine disagreements with the z-buffer</td></tr></table></div>";
        if (rayMs && methods.empty()) pts.push_back({"ray casting", *rayMs, genuine});
    }
    if (!pts.empty())
        o += scatterSvg(pts, id + "-scatter", "time (ms)", "wrong pixels");
}

void HtmlWriter::view(const Json *v, size_t pos) {
    const std::string id = viewId(pos);
    const std::string name = str(v, {"name"});
    o += "<section class=\"view\" id=\"" + id + "\"><h2>" + esc(name.empty() ? "(unnamed view)" : name) + "</h2>";
    // Camera line.
    o += "<div class=\"meta\">" + fmtValue(get(v, "width")) + "×" + fmtValue(get(v, "height")) + " · " +
         esc(str(v, {"projection"})) + " · " + esc(str(v, {"depth_format"})) + " · eye " + fmtValue(get(v, {"camera", "eye"})) +
         " → target " + fmtValue(get(v, {"camera", "target"})) + " · near " + fmtValue(get(v, {"camera", "near"})) + ", far " +
         fmtValue(get(v, {"camera", "far"}));
    if (const Json *fov = get(v, {"camera", "fov_y"})) o += " · fov " + fmtValue(fov) + "°";
    o += " · from " + esc(str(v, {"origin"})) + " · " + fmtMs(num(v, {"total_ms"})) + "</div>";

    const auto methods = orderingMethods(get(v, "ordering"));
    // The six questions of visibility, answered from the numbers.
    const Answer answers[] = {
        {"What is off-screen?", answerOffScreen(v)},
        {"What is too far to draw?", answerTooFar(v)},
        {"What needs less detail?", answerLessDetail(v)},
        {"What is obscured by what?", answerObscured(v)},
        {"What is in front of what?", answerOrder(v, methods)},
        {"What stands between a surface and a light?", answerShadows(v, &report)},
    };
    o += "<h3>The six questions</h3><ul class=\"questions\">";
    for (const Answer &a : answers) o += std::string("<li><span class=\"q\">") + a.question + "</span> " + a.text + "</li>";
    o += "</ul>";

    o += "<h3>Stage funnel</h3>" + funnelSvg(v, id + "-funnel");
    stageTable(v);

    const std::vector<ViewImage> imgs = viewImages(v, folder);
    o += "<h3>Images</h3>";
    images(v, id, imgs, pos < kEagerViews);
    hotspots(v, id, imgs);
    falseCulls(v, id, imgs);
    raycast(v, id, imgs);
    depthFormats(v, id);
    accuracy(v, id, methods);

    // Every other section of the view, by its key, as generic tables.
    static const std::set<std::string> handled = {"name",  "index",  "origin", "width", "height", "depth_format",
                                                  "projection", "camera", "stages", "zbuffer", "images", "total_ms",
                                                  "depth", "audit", "raycast"};
    if (v && v->is_object())
        for (auto it = v->begin(); it != v->end(); ++it) {
            if (handled.count(it.key()) || !it.value().is_structured()) continue;
            o += "<h3 id=\"" + id + "-" + slug(it.key()) + "\">" + label(it.key()) + "</h3>";
            if (ranFalse(&it.value())) o += "<p class=\"note\">Not analysed: " + esc(str(get(&it.value(), "reason"))) + "</p>";
            else o += "<details open><summary>all values</summary>" + genericJson(&it.value()) + "</details>";
        }
    o += "<details><summary>Z-buffer summary</summary>" + genericJson(get(v, "zbuffer")) + "</details>";
    o += "</section>";
}

}  // namespace

std::string reportHtml(const nlohmann::ordered_json &report, const std::string &dir) {
    HtmlWriter w{report, Folder{dir}, {}, {}};
    std::string &o = w.o;
    const std::vector<const Json *> vs = viewsOf(report);
    std::vector<ViewScore> scores;
    for (size_t i = 0; i < vs.size(); ++i) scores.push_back(scoreView(vs[i], i));
    std::vector<ViewScore> worstFirst = scores;
    std::stable_sort(worstFirst.begin(), worstFirst.end(), worseThan);

    const std::string scenePath = str(&report, {"scene", "path"});
    o += "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
         "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
         "<meta name=\"color-scheme\" content=\"light dark\">"
         // Nothing may load from elsewhere: images from this folder only, inline style and script.
         "<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; img-src 'self' file: data:; "
         "style-src 'unsafe-inline'; script-src 'unsafe-inline'\">"
         "<title>visaudit: " + esc(scenePath) + "</title><style>" + html_assets::kCss + "</style></head><body>\n";
    w.header(worstFirst);
    w.summary(worstFirst);
    w.planner();
    w.quakeMap();
    if (const Json *scene = get(&report, "scene"))
        o += "<section class=\"block\" id=\"scene\"><h2>Scene</h2><details><summary>as loaded</summary>" + genericJson(scene) +
             "</details></section>\n";
    w.depthAuditImage();
    w.pvsAuditLink();
    for (size_t i = 0; i < vs.size(); ++i) {
        w.view(vs[i], i);
        o += "\n";
    }
    o += "<dialog id=\"enlarge\"><img alt=\"\"><p></p></dialog><script>" + std::string(html_assets::kScript) +
         "</script></body></html>\n";
    return o;
}

bool writeReportHtml(const nlohmann::ordered_json &report, const std::string &dir, std::string *err) {
    return writeFileAtomic(dir + "/report.html", reportHtml(report, dir), err);
}

std::string htmlEscape(std::string_view text) { return esc(text); }

}  // namespace va
