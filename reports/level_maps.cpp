// Level maps: positions, values, worst positions and images (reports/level_maps.h).
#include "reports/level_maps.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

#include "reports/font.h"
#include "reports/report_read.h"
#include "reports/text_format.h"

namespace va {

using Json = nlohmann::ordered_json;
using namespace rjson;

const std::vector<ViewMetric> &levelMapMetrics() {
    static const std::vector<ViewMetric> m = {
        {"triangles_drawn", "triangles drawn", "triangles the z-buffer drew after every culling stage", false},
        {"overdraw", "overdraw", "depth-test passes / covered pixels (best 1)", true},
        {"wasted_share", "wasted-draw share", "share of the drawn triangles visible nowhere (best 0)", true},
        {"false_cull_pixels", "false-cull pixels", "pixels of triangles a stage culled yet visible (best 0)", false},
    };
    return m;
}

std::string levelMapImageName(const std::string &metric, bool diff) {
    return std::string(diff ? "level-map-diff-" : "level-map-") + metric + ".png";
}

namespace {
constexpr Rgb8 kVoid{26, 30, 36}, kStrip{24, 24, 24}, kText{255, 255, 255}, kOutline{0, 0, 0}, kNoValue{150, 150, 150},
    kRouteInk{255, 255, 255};

Json vec3Json(Vec3 v) { return Json::array({v.x, v.y, v.z}); }

bool vec3Of(const Json *j, Vec3 *out) {
    if (!j || !j->is_array() || j->size() != 3) return false;
    for (int i = 0; i < 3; ++i) {
        if (!(*j)[size_t(i)].is_number()) return false;
        (*out)[i] = (*j)[size_t(i)].get<double>();
    }
    return true;
}

// The floor block's camera back as a CameraSpec.
bool floorCamera(const Json *floor, CameraSpec *c) {
    const Json *cam = get(floor, "camera");
    c->orthographic = true;
    if (!vec3Of(get(cam, "eye"), &c->eye) || !vec3Of(get(cam, "target"), &c->target) || !vec3Of(get(cam, "up"), &c->up))
        return false;
    const auto oh = num(cam, {"ortho_height"}), n = num(cam, {"near"}), f = num(cam, {"far"});
    const auto w = num(floor, {"width"}), h = num(floor, {"height"});
    if (!oh || !n || !f || !w || !h) return false;
    c->orthoHeight = *oh, c->nearZ = *n, c->farZ = *f, c->width = int(*w), c->height = int(*h);
    return true;
}

std::string valueText(double v, bool real) { return real ? fmtReal(v) : fmtCount(v); }
}  // namespace

Json floorPlanJson(const FloorPlan &f) {
    const CameraSpec &c = f.camera;
    return {{"image", kFloorPlanImage},
            {"width", f.width},
            {"height", f.height},
            {"up", std::string(1, f.up)},
            {"camera",
             {{"eye", vec3Json(c.eye)},
              {"target", vec3Json(c.target)},
              {"up", vec3Json(c.up)},
              {"ortho_height", c.orthoHeight},
              {"near", c.nearZ},
              {"far", c.farZ}}},
            {"world_per_pixel", f.worldPerPixel},
            {"step", f.step},
            {"drawn_pixels", f.drawnPixels},
            {"ms", std::isfinite(f.ms) ? Json(f.ms) : Json(nullptr)}};
}

Canvas floorPlanCanvas(const FloorPlan &f) {
    Canvas c(f.width, f.height, kVoid);
    for (int y = 0; y < f.height; ++y)
        for (int x = 0; x < f.width; ++x)
            if (const uint8_t g = f.gray[size_t(y) * size_t(f.width) + size_t(x)]) c.set(x, y, {g, g, g});
    return c;
}

bool writeFloorPlanPng(const FloorPlan &f, const std::string &dir, std::string *err) {
    return floorPlanCanvas(f).writePng(dir + "/" + kFloorPlanImage, err);
}

void addLevelMaps(Json *report) {
    if (!report->contains("level_maps") || !(*report)["level_maps"].is_object()) return;
    Json &lm = (*report)["level_maps"];
    const Json *floor = get(&lm, "floor");
    CameraSpec cam;
    if (!floorCamera(floor, &cam)) return;
    const Json &views = (*report)["views"];
    // Positions: the distinct eyes (in the order of their first view) that fall on the image.
    struct Position {
        Vec3 eye;
        double px = 0, py = 0;
        std::vector<size_t> views;
    };
    std::vector<Position> positions;
    std::map<std::tuple<double, double, double>, size_t> byEye;
    for (size_t i = 0; i < views.size(); ++i) {
        Vec3 e;
        if (!vec3Of(get(&views[i], {"camera", "eye"}), &e)) continue;
        double px = 0, py = 0;
        if (!floorPixelOf(cam, e, &px, &py) || !(px >= 0 && py >= 0 && px < cam.width && py < cam.height)) continue;
        auto [it, fresh] = byEye.emplace(std::tuple{e.x, e.y, e.z}, positions.size());
        if (fresh) positions.push_back({e, px, py, {}});
        positions[it->second].views.push_back(i);
    }
    Json pj = Json::array();
    for (const Position &p : positions)
        pj.push_back({{"x", p.px}, {"y", p.py}, {"eye", vec3Json(p.eye)}, {"views", p.views}});
    lm["positions"] = pj;
    // Per metric: each position's worst view, the range, the worst positions.
    Json maps = Json::array();
    for (const ViewMetric &m : levelMapMetrics()) {
        Json values = Json::array(), worstView = Json::array();
        std::vector<std::pair<double, size_t>> ranked;  // (value, position)
        for (size_t k = 0; k < positions.size(); ++k) {
            std::optional<double> best;
            size_t bestView = 0;
            for (size_t i : positions[k].views)
                if (const auto v = viewMetric(views[i], m.key); v && (!best || *v > *best)) best = v, bestView = i;
            // The value as the view holds it (counts stay integers).
            values.push_back(best ? *get(&views[bestView], {"findings", "score", m.key}) : Json(nullptr));
            worstView.push_back(best ? Json(bestView) : Json(nullptr));
            if (best) ranked.push_back({*best, k});
        }
        std::stable_sort(ranked.begin(), ranked.end(), [](const auto &a, const auto &b) { return a.first > b.first; });
        Json worst = Json::array();
        for (size_t r = 0; r < std::min(kLevelMapWorst, ranked.size()); ++r)
            worst.push_back({{"rank", r + 1},
                             {"position", ranked[r].second},
                             {"view", worstView[ranked[r].second]},
                             {"value", values[ranked[r].second]}});
        Json mj = {{"metric", m.key}, {"title", m.title}, {"meaning", m.meaning},
                   {"min", ranked.empty() ? Json(nullptr) : values[ranked.back().second]},
                   {"max", ranked.empty() ? Json(nullptr) : values[ranked[0].second]},
                   {"values", values}, {"view", worstView}, {"worst", worst}};
        maps.push_back(mj);
    }
    lm["maps"] = maps;
}

Canvas levelMapImage(const Json &lm, size_t mi, const Canvas &floor, const Json &views, bool diff) {
    const ViewMetric &metric = levelMapMetrics()[mi];
    const Json *map = get(&lm, "maps");
    map = map && map->is_array() && mi < map->size() ? &(*map)[mi] : nullptr;
    const Json *positions = get(&lm, "positions");
    const Json *values = get(map, "values");
    const size_t np = positions && positions->is_array() ? positions->size() : 0;
    const int W = floor.width, H = floor.height;
    const int s = W >= 1024 ? 2 : 1;
    const int r = std::max(2, W / 192);
    auto pixelOf = [&](size_t k, int *x, int *y) {
        *x = int(std::floor(numOr(&(*positions)[k], {"x"}, 0)));
        *y = int(std::floor(numOr(&(*positions)[k], {"y"}, 0)));
    };
    // The scale: [min, max] of the values; a change is symmetric about 0.
    const double lo = numOr(map, {"min"}, 0), hi = numOr(map, {"max"}, 0);
    const double span = diff ? std::max(std::fabs(lo), std::fabs(hi)) : hi - lo;
    auto colorOf = [&](std::optional<double> v) {
        if (!v) return kNoValue;
        if (diff) return divergingColor(span > 0 ? *v / span : 0);
        return rampColor(span > 0 ? (*v - lo) / span : 0.5);
    };

    // The legend strip: the title, then the colour bar with its ends, the grey of "no value".
    const int margin = 4 * s, rowH = textHeight(s) + 2 * margin, stripH = 2 * rowH + margin;
    Canvas c(W, H + stripH, kStrip);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) c.set(x, y, floor.at(x, y));

    // Routes: consecutive frames joined by a line, under the dots.
    std::map<std::string, std::vector<std::pair<double, size_t>>> routeFrames;  // route -> (frame, position)
    for (size_t k = 0; k < np; ++k) {
        const Json *vs = get(&(*positions)[k], "views");
        if (!vs || !vs->is_array()) continue;
        for (const Json &vi : *vs)
            if (vi.is_number_unsigned() && vi.get<size_t>() < views.size())
                if (const Json *rt = get(&views[vi.get<size_t>()], "route"); rt && rt->is_object())
                    routeFrames[str(rt, {"name"})].push_back({numOr(rt, {"frame"}, 0), k});
    }
    for (auto &[name, frames] : routeFrames) {
        std::stable_sort(frames.begin(), frames.end());
        for (size_t f = 1; f < frames.size(); ++f) {
            int x0, y0, x1, y1;
            pixelOf(frames[f - 1].second, &x0, &y0);
            pixelOf(frames[f].second, &x1, &y1);
            c.line(x0, y0, x1, y1, kRouteInk);
        }
    }
    // Dots, lowest value first so that the worst lie on top; positions without a value first of all.
    std::vector<std::pair<double, size_t>> order;
    for (size_t k = 0; k < np; ++k) {
        const auto v = values && values->is_array() && k < values->size() ? num(&(*values)[k]) : std::nullopt;
        order.push_back({v ? (diff ? std::fabs(*v) : *v) : -INFINITY, k});
    }
    std::stable_sort(order.begin(), order.end(), [](const auto &a, const auto &b) { return a.first < b.first; });
    for (const auto &[key, k] : order) {
        int x, y;
        pixelOf(k, &x, &y);
        const auto v = values && values->is_array() && k < values->size() ? num(&(*values)[k]) : std::nullopt;
        c.disc(x, y, r + 1, kOutline);
        c.disc(x, y, r, colorOf(v));
    }
    // The worst positions, numbered.
    if (const Json *worst = get(map, "worst"); worst && worst->is_array())
        for (const Json &w : *worst) {
            const size_t k = size_t(numOr(&w, {"position"}, 0));
            if (k >= np) continue;
            int x, y;
            pixelOf(k, &x, &y);
            const std::string label = fmtCount(numOr(&w, {"rank"}, 0));
            // Right of the dot, or left of it where the map ends.
            const int tw = textWidth(label, s);
            const int lx = x + r + 2 * s + tw + s <= W ? x + r + 2 * s : std::max(s, x - r - 2 * s - tw);
            const int ly = std::clamp(y - textHeight(s) / 2, s, H - textHeight(s) - s);
            c.label(lx, ly, label, kText, kOutline, s);
        }

    // Legend.
    int y = H + margin;
    const std::string title = std::string(diff ? "change in " : "") + metric.title +
                              (diff ? " (new - old), worst view of each position" : ", worst view of each position") +
                              "; numbers: the " + std::to_string(kLevelMapWorst) + " " + (diff ? "largest changes" : "worst");
    c.text(margin, y, title, kText, s);
    y += rowH;
    const bool hasValues = num(map, {"min"}).has_value();
    const std::string loText = diff ? "-" + valueText(span, metric.real) : valueText(lo, metric.real);
    const std::string hiText = diff ? "+" + valueText(span, metric.real) : valueText(hi, metric.real);
    int x = c.text(margin, y, hasValues ? loText : "no values", kText, s) + 2 * s;
    const int barW = 160 * s;
    for (int i = 0; i < barW; ++i) {
        const double t = double(i) / (barW - 1);
        c.rect(x + i, y, x + i + 1, y + textHeight(s), diff ? divergingColor(2 * t - 1) : rampColor(t));
    }
    x += barW + 2 * s;
    x = c.text(x, y, hasValues ? hiText : "", kText, s) + 8 * s;
    c.rect(x, y, x + textHeight(s), y + textHeight(s), kNoValue);
    c.text(x + textHeight(s) + 2 * s, y, "not analysed", kText, s);
    return c;
}

bool readCanvas(const std::string &path, Canvas *out, std::string *err) {
    ImageData im;
    if (!readImage(path, &im, err)) return false;
    if (im.pixelType != "uint8" || im.channels() < 1) {
        *err = path + ": expected an 8-bit PNG (gray or RGB), as visaudit writes them";
        return false;
    }
    Canvas c(im.width, im.height, {});
    const int ch = im.channels();
    // Gray (and gray + alpha) as three equal channels; RGB(A) as its first three.
    for (size_t p = 0; p < size_t(im.width) * size_t(im.height); ++p)
        for (int k = 0; k < 3; ++k) c.rgb[3 * p + size_t(k)] = im.u8[size_t(ch) * p + size_t(ch >= 3 ? k : 0)];
    *out = std::move(c);
    return true;
}

bool writeLevelMapImages(Json *report, const std::string &dir, std::string *err) {
    if (!report->contains("level_maps") || !(*report)["level_maps"].contains("maps")) return true;
    Json &lm = (*report)["level_maps"];
    Canvas floor;
    if (!readCanvas(dir + "/" + kFloorPlanImage, &floor, err)) return false;
    for (size_t m = 0; m < levelMapMetrics().size() && m < lm["maps"].size(); ++m) {
        const std::string name = levelMapImageName(levelMapMetrics()[m].key);
        if (!levelMapImage(lm, m, floor, (*report)["views"]).writePng(dir + "/" + name, err)) return false;
        lm["maps"][m]["image"] = name;
    }
    return true;
}

}  // namespace va
