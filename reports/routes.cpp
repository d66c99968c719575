// Routes in the report: definitions, series, worst frames and plots (reports/routes.h).
#include "reports/routes.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "reports/font.h"
#include "reports/report_read.h"
#include "reports/text_format.h"

namespace va {

using Json = nlohmann::ordered_json;
using namespace rjson;

const std::vector<ViewMetric> &routeMetrics() {
    static const std::vector<ViewMetric> m = {
        {"triangles_drawn", "triangles drawn", "triangles the z-buffer drew after every culling stage", false},
        {"overdraw", "overdraw", "depth-test passes / covered pixels (best 1)", true},
        {"false_cull_pixels", "false-cull pixels", "pixels of triangles a stage culled yet visible (best 0)", false},
        {"zfight_pixels", "z-fighting pixels", "pixels that z-fight in the view's own depth format (best 0)", false},
        {"total_ms", "ms per frame", "the view's analysis time in milliseconds (every stage and audit)", true},
    };
    return m;
}

std::optional<double> viewMetric(const Json &view, std::string_view key) {
    if (key == "total_ms") return num(&view, {"total_ms"});
    return num(&view, {"findings", "score", key});
}

namespace {
Json num3(Vec3 v) { return Json::array({v.x, v.y, v.z}); }
}  // namespace

Json routeDefinitionJson(const Route &r) {
    Json j;
    j["name"] = r.name;
    j["file"] = r.file;
    j["interpolation"] = routeInterpolationName(r.interpolation);
    j["sampling"] = r.sampling.kind == RouteSampling::Kind::keyframes ? Json("keyframes")
                    : r.sampling.kind == RouteSampling::Kind::count   ? Json{{"frames", r.sampling.count}}
                                                                      : Json{{"every_seconds", r.sampling.every}};
    j["times"] = r.timesGiven ? "given" : r.speed > 0 ? "speed" : "one_per_second";
    j["speed"] = r.speed > 0 ? Json(r.speed) : Json(nullptr);
    j["duration"] = r.duration();
    j["length"] = r.length;
    Json ks = Json::array();
    for (const RouteKeyframe &k : r.keyframes) {
        Json kj = {{"eye", num3(k.eye)}, {"yaw", k.yaw}, {"pitch", k.pitch}, {"time", k.time}};
        kj["target"] = k.target ? num3(*k.target) : Json(nullptr);
        ks.push_back(kj);
    }
    j["keyframes"] = ks;
    return j;
}

void addRouteSeries(Json *report) {
    if (!report->contains("routes") || !(*report)["routes"].is_array()) return;
    const Json &views = (*report)["views"];
    for (Json &route : (*report)["routes"]) {
        const std::string name = str(&route, {"name"});
        Json series;
        series["view"] = Json::array();
        series["frame"] = Json::array();
        series["time"] = Json::array();
        for (const ViewMetric &m : routeMetrics()) series[m.key] = Json::array();
        std::vector<size_t> positions;
        for (size_t i = 0; i < views.size(); ++i) {
            const Json *r = get(&views[i], "route");
            if (!r || str(r, {"name"}) != name) continue;
            positions.push_back(i);
            series["view"].push_back(i);
            // Values as the views hold them (counts stay integers).
            auto value = [](const Json *x) { return x && x->is_number() ? *x : Json(nullptr); };
            series["frame"].push_back(value(get(r, "frame")));
            series["time"].push_back(value(get(r, "time")));
            for (const ViewMetric &m : routeMetrics())
                series[m.key].push_back(value(std::string_view(m.key) == "total_ms"
                                                  ? get(&views[i], "total_ms")
                                                  : get(&views[i], {"findings", "score", m.key})));
        }
        // The worst frames per metric: highest first, ties in frame order; frames without the value, or
        // with 0 (nothing to fix), left out.
        Json worst = Json::object();
        for (const ViewMetric &m : routeMetrics()) {
            std::vector<std::pair<double, size_t>> vals;  // (value, index in the series)
            for (size_t k = 0; k < positions.size(); ++k)
                if (series[m.key][k].is_number() && series[m.key][k].get<double>() > 0)
                    vals.push_back({series[m.key][k].get<double>(), k});
            std::stable_sort(vals.begin(), vals.end(), [](const auto &a, const auto &b) { return a.first > b.first; });
            Json list = Json::array();
            for (size_t w = 0; w < std::min(kRouteWorstFrames, vals.size()); ++w) {
                const size_t k = vals[w].second;
                list.push_back({{"view", positions[k]}, {"frame", series["frame"][k]}, {"time", series["time"][k]},
                                {"value", series[m.key][k]}});
            }
            worst[m.key] = list;
        }
        route["series"] = series;
        route["worst"] = worst;
    }
}

std::string routePlotName(const std::string &routeName) {
    std::string s = sanitizeFileName(routeName);
    std::replace(s.begin(), s.end(), '.', '_');
    return "route-" + s + ".png";
}

namespace {

constexpr Rgb8 kPaper{255, 255, 255}, kInk{30, 30, 30}, kGridInk{215, 215, 215}, kLineInk{40, 70, 170},
    kWorstInk{210, 40, 30}, kMuted{110, 110, 110};

std::string shortNumber(double v, bool real) { return real ? fmtReal(v) : fmtCount(v); }

}  // namespace

Canvas routePlot(const Json &route) {
    const Json *series = get(&route, "series");
    const Json *times = get(series, "time");
    const size_t n = times && times->is_array() ? times->size() : 0;
    const std::vector<ViewMetric> &metrics = routeMetrics();
    const int W = 960, left = 170, right = 24, top = 34, panelH = 84, gap = 14, bottom = 30;
    const int H = top + int(metrics.size()) * (panelH + gap) + bottom;
    Canvas c(W, H, kPaper);
    const std::string title = "route " + str(&route, {"name"}) + ": " + fmtCount(double(n)) + " frames over " +
                              fmtReal(numOr(&route, {"duration"}, 0)) + " s (" + str(&route, {"interpolation"}) + ")";
    c.text(8, 10, title, kInk, 2);
    const double t0 = n ? num(&(*times)[0]).value_or(0) : 0, t1 = n ? num(&(*times)[n - 1]).value_or(1) : 1;
    const int plotW = W - left - right;
    auto xOf = [&](double t) { return left + int(std::lround(t1 > t0 ? (t - t0) / (t1 - t0) * (plotW - 1) : 0)); };
    for (size_t mi = 0; mi < metrics.size(); ++mi) {
        const ViewMetric &m = metrics[mi];
        const int y0 = top + int(mi) * (panelH + gap), yb = y0 + panelH - 1;
        const Json *vals = get(series, m.key);
        double hi = 0;
        bool any = false;
        for (size_t k = 0; k < n; ++k)
            if (const auto v = num(vals && vals->is_array() && k < vals->size() ? &(*vals)[k] : nullptr)) {
                hi = std::max(hi, *v);
                any = true;
            }
        c.text(8, y0 + 4, m.title, kInk, 1);
        c.text(8, y0 + 16, any ? "max " + shortNumber(hi, m.real) : "not analysed", kMuted, 1);
        c.rect(left, y0, left + plotW, y0 + 1, kGridInk);
        c.rect(left, yb, left + plotW, yb + 1, kGridInk);
        c.rect(left, y0, left + 1, yb, kGridInk);
        if (!any) continue;
        auto yOf = [&](double v) { return yb - int(std::lround(hi > 0 ? v / hi * (panelH - 6) : 0)); };
        int px = -1, py = -1;
        for (size_t k = 0; k < n; ++k) {
            const auto v = num(k < vals->size() ? &(*vals)[k] : nullptr);
            if (!v) {
                px = -1;
                continue;
            }
            const int x = xOf(num(&(*times)[k]).value_or(0)), y = yOf(*v);
            if (px >= 0) c.line(px, py, x, y, kLineInk);
            if (n <= 200) c.disc(x, y, 1, kLineInk);
            px = x, py = y;
        }
        // The worst frames, numbered 1.. at their points.
        const Json *worst = get(&route, {"worst", m.key});
        if (worst && worst->is_array()) {
            for (size_t w = 0; w < worst->size(); ++w) {
                const Json &e = (*worst)[w];
                const int x = xOf(numOr(&e, {"time"}, 0)), y = yOf(numOr(&e, {"value"}, 0));
                c.disc(x, y, 3, kWorstInk);
                c.label(x + 5, std::max(y0 + 2, y - 10), std::to_string(w + 1), kPaper, kWorstInk);
            }
        }
    }
    // The time axis.
    const int ya = top + int(metrics.size()) * (panelH + gap) + 2;
    c.text(left, ya, fmtReal(t0) + " s", kInk);
    const std::string end = fmtReal(t1) + " s";
    c.text(left + plotW - textWidth(end), ya, end, kInk);
    c.text(left + plotW / 2 - textWidth("time") / 2, ya, "time", kMuted);
    return c;
}

bool writeRoutePlots(Json *report, const std::string &dir, std::string *err) {
    if (!report->contains("routes") || !(*report)["routes"].is_array()) return true;
    for (Json &route : (*report)["routes"]) {
        const std::string name = routePlotName(str(&route, {"name"}));
        if (!routePlot(route).writePng(dir + "/" + name, err)) return false;
        route["image"] = name;
    }
    return true;
}

}  // namespace va
