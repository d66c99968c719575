// report.html: the image files next to the page and highlight boxes over them (reports/html_parts.h).
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>

#include "reports/html_parts.h"

namespace va::html {

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

bool Folder::exists(const std::string &name) const {
    if (dir.empty() || !safeFileName(name)) return false;
    std::error_code ec;
    return std::filesystem::is_regular_file(std::filesystem::path(dir) / name, ec);
}
std::optional<std::pair<int, int>> Folder::png(const std::string &name) const {
    if (!exists(name)) return std::nullopt;
    return pngSize((std::filesystem::path(dir) / name).string());
}

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

}  // namespace va::html
