// report.html: routes and level maps (reports/html_parts.h). Both sections appear only in reports
// that have them, with their own few style rules, so every other page stays as it was.
#include <algorithm>
#include <cmath>

#include "reports/html_parts.h"
#include "reports/level_maps.h"
#include "reports/routes.h"

namespace va::html {

namespace {

// The rules these sections use (the page's stylesheet is shared by every report).
constexpr const char *kStyle =
    "<style>svg.routeplot .line{fill:none;stroke:var(--accent);stroke-width:1.5}"
    "svg.routeplot .worst{fill:var(--bad)}svg.routeplot .frame{fill:transparent}"
    "svg.routeplot a:hover .frame{fill:var(--accent)}"
    // A pin is a ring over a numbered position (the number is the image's own): clickable, outlined
    // on hover and when it is the target.
    ".lm-pin{position:absolute;transform:translate(-50%,-50%);width:20px;height:20px;border-radius:50%;"
    "border:2px solid transparent;color:transparent;font-size:0;overflow:hidden}"
    ".lm-pin:hover,.lm-pin:focus{border-color:var(--mark);box-shadow:0 0 0 2px #000a}"
    ".levelmaps{display:grid;grid-template-columns:repeat(auto-fill,minmax(420px,1fr));gap:14px}</style>";

std::string viewLink(const std::vector<const Json *> &views, size_t pos) {
    if (pos >= views.size()) return "—";
    return "<a href=\"#" + viewId(pos) + "\">" + esc(str(views[pos], {"name"})) + "</a>";
}

std::string valueText(const Json *v, bool real) {
    const auto x = num(v);
    return x ? (real ? fmtReal(*x) : fmtCount(*x)) : "—";
}

// One route's series: a panel per metric against time, the worst frames marked and linked, every
// frame a link to its view (its values in the tooltip).
std::string routeSvg(const Json *route, const std::vector<const Json *> &views, const std::string &id) {
    const Json *series = get(route, "series");
    const Json *times = get(series, "time"), *frames = get(series, "view");
    const size_t n = times && times->is_array() ? times->size() : 0;
    const std::vector<ViewMetric> &metrics = routeMetrics();
    const int W = 900, left = 150, right = 20, top = 10, panelH = 70, gap = 16;
    const int H = top + int(metrics.size()) * (panelH + gap) + 22;
    const int plotW = W - left - right;
    double t0 = 0, t1 = 1;
    if (n) t0 = num(&(*times)[0]).value_or(0), t1 = num(&(*times)[n - 1]).value_or(1);
    auto xOf = [&](double t) { return left + (t1 > t0 ? (t - t0) / (t1 - t0) * plotW : 0.0); };
    std::string o = "<svg class=\"chart routeplot\" id=\"" + id + "\" viewBox=\"0 0 " + std::to_string(W) + " " +
                    std::to_string(H) + "\" role=\"img\" aria-label=\"the route's metrics per frame against time\">";
    for (size_t mi = 0; mi < metrics.size(); ++mi) {
        const ViewMetric &m = metrics[mi];
        const int y0 = top + int(mi) * (panelH + gap), yb = y0 + panelH;
        const Json *vals = get(series, m.key);
        double hi = 0;
        bool any = false;
        for (size_t k = 0; k < n; ++k)
            if (const auto v = num(vals && vals->is_array() && k < vals->size() ? &(*vals)[k] : nullptr))
                hi = std::max(hi, *v), any = true;
        auto yOf = [&](double v) { return yb - (hi > 0 ? v / hi * (panelH - 4) : 0.0); };
        o += "<g data-metric=\"" + std::string(m.key) + "\"><text x=\"0\" y=\"" + std::to_string(y0 + 14) + "\">" +
             esc(m.title) + "</text><text class=\"muted\" x=\"0\" y=\"" + std::to_string(y0 + 30) + "\">" +
             (any ? "max " + (m.real ? fmtReal(hi) : fmtCount(hi)) : std::string()) + "</text>";
        o += "<line class=\"axis\" x1=\"" + std::to_string(left) + "\" y1=\"" + std::to_string(yb) + "\" x2=\"" +
             std::to_string(left + plotW) + "\" y2=\"" + std::to_string(yb) + "\"/>";
        if (!any) {
            o += "<text class=\"muted\" x=\"" + std::to_string(left + 8) + "\" y=\"" + std::to_string(y0 + 40) +
                 "\">not analysed</text></g>";
            continue;
        }
        std::string pts;
        for (size_t k = 0; k < n; ++k)
            if (const auto v = num(k < vals->size() ? &(*vals)[k] : nullptr))
                pts += (pts.empty() ? "" : " ") + fx(xOf(num(&(*times)[k]).value_or(0))) + "," + fx(yOf(*v));
        o += "<polyline class=\"line\" points=\"" + pts + "\"/>";
        // Every frame a link to its view (few enough frames only: the page stays light).
        if (n <= 400)
            for (size_t k = 0; k < n; ++k) {
                const auto v = num(k < vals->size() ? &(*vals)[k] : nullptr);
                const auto pos = num(frames && k < frames->size() ? &(*frames)[k] : nullptr);
                if (!v || !pos) continue;
                o += "<a href=\"#" + viewId(size_t(*pos)) + "\"><circle class=\"frame\" cx=\"" +
                     fx(xOf(num(&(*times)[k]).value_or(0))) + "\" cy=\"" + fx(yOf(*v)) + "\" r=\"3\"><title>" +
                     esc(size_t(*pos) < views.size() ? str(views[size_t(*pos)], {"name"}) : "") + " at " +
                     fmtReal(num(&(*times)[k]).value_or(0)) + " s: " + (m.real ? fmtReal(*v) : fmtCount(*v)) + " " +
                     esc(m.title) + "</title></circle></a>";
            }
        // The worst frames, numbered and linked.
        if (const Json *worst = get(route, {"worst", m.key}); worst && worst->is_array())
            for (size_t w = 0; w < worst->size(); ++w) {
                const Json &e = (*worst)[w];
                const double x = xOf(numOr(&e, {"time"}, 0)), y = yOf(numOr(&e, {"value"}, 0));
                const size_t pos = size_t(numOr(&e, {"view"}, 0));
                o += "<a class=\"worstframe\" href=\"#" + viewId(pos) + "\"><circle class=\"worst\" cx=\"" + fx(x) +
                     "\" cy=\"" + fx(y) + "\" r=\"4.5\"><title>worst " + std::to_string(w + 1) + ": " +
                     esc(pos < views.size() ? str(views[pos], {"name"}) : "") + ", " +
                     valueText(get(&e, "value"), m.real) + " " + esc(m.title) + "</title></circle><text x=\"" +
                     fx(x + 6) + "\" y=\"" + fx(std::max(double(y0 + 10), y - 5)) + "\">" + std::to_string(w + 1) +
                     "</text></a>";
            }
        o += "</g>";
    }
    const int ya = top + int(metrics.size()) * (panelH + gap) + 12;
    o += "<text x=\"" + std::to_string(left) + "\" y=\"" + std::to_string(ya) + "\">" + fmtReal(t0) +
         " s</text><text x=\"" + std::to_string(left + plotW) + "\" y=\"" + std::to_string(ya) +
         "\" text-anchor=\"end\">" + fmtReal(t1) + " s</text><text class=\"muted\" x=\"" +
         std::to_string(left + plotW / 2) + "\" y=\"" + std::to_string(ya) + "\" text-anchor=\"middle\">time</text></svg>";
    return o;
}

}  // namespace

void HtmlWriter::routes() {
    const Json *rs = get(&report, "routes");
    if (!rs || !rs->is_array() || rs->empty()) return;
    o += "<section class=\"block\" id=\"routes\"><h2>Routes</h2>";
    o += kStyle;
    o += "<p class=\"note\">Each frame of a route is a view (ROUTE@K); per frame the triangles the z-buffer drew, the "
         "overdraw, the pixels of falsely culled triangles, the z-fighting pixels in the view's own depth format and "
         "the time the frame took. The red points are each metric's worst frames; a point links to its view.</p>";
    for (const Json &r : *rs) {
        const std::string name = str(&r, {"name"});
        const std::string rid = "route-" + slug(name);
        const Json *series = get(&r, "series");
        const Json *times = get(series, "time");
        const size_t n = times && times->is_array() ? times->size() : 0;
        o += "<h3 id=\"" + rid + "\">" + esc(name) + "</h3><p class=\"meta\"><code>" + esc(str(&r, {"file"})) + "</code> · " +
             plural(double(n), "frame", "frames") + " over " + fmtReal(numOr(&r, {"duration"}, 0)) + " s · " +
             fmtReal(numOr(&r, {"length"}, 0)) + " units long · " +
             plural(double(get(&r, "keyframes") && get(&r, "keyframes")->is_array() ? get(&r, "keyframes")->size() : 0),
                    "keyframe", "keyframes") +
             " · " + esc(str(&r, {"interpolation"})) + " interpolation</p>";
        o += routeSvg(&r, views, rid + "-plot");
        const std::string image = str(&r, {"image"});
        if (!image.empty() && folder.exists(image))
            o += "<p class=\"note\">As an image: <a href=\"" + urlOf(image) + "\">" + esc(image) + "</a>.</p>";
        // The worst frames per metric, as a table of links.
        o += "<div class=\"scroll\"><table class=\"worst-frames\"><tr><th>metric</th><th>worst frames</th></tr>";
        for (const ViewMetric &m : routeMetrics()) {
            o += "<tr><td>" + esc(m.title) + "</td><td>";
            const Json *worst = get(&r, {"worst", m.key});
            std::string cells;
            if (worst && worst->is_array())
                for (const Json &e : *worst)
                    cells += (cells.empty() ? "" : " · ") + viewLink(views, size_t(numOr(&e, {"view"}, 0))) + " (" +
                             fmtReal(numOr(&e, {"time"}, 0)) + " s: " + valueText(get(&e, "value"), m.real) + ")";
            o += (cells.empty() ? std::string("—") : cells) + "</td></tr>";
        }
        o += "</table></div>";
    }
    o += "</section>\n";
}

void HtmlWriter::levelMaps() {
    const Json *lm = get(&report, "level_maps");
    const Json *maps = get(lm, "maps"), *positions = get(lm, "positions");
    if (!maps || !maps->is_array() || !positions || !positions->is_array()) return;
    o += "<section class=\"block\" id=\"level-maps\"><h2>Level maps</h2>";
    if (!get(&report, "routes")) o += kStyle;
    o += "<p class=\"note\">The level from above (its floor plan, drawn by visaudit's own rasterizer looking down the up "
         "axis), each of the " + plural(double(positions->size()), "sample position", "sample positions") +
         " coloured by the worst of its views. The numbers mark the worst positions; each links to its view.</p>";
    o += "<div class=\"levelmaps\">";
    for (size_t mi = 0; mi < maps->size(); ++mi) {
        const Json &m = (*maps)[mi];
        const std::string metric = str(&m, {"metric"}), image = str(&m, {"image"});
        const bool real = metric == "overdraw" || metric == "wasted_share";
        const std::string fid = "level-map-" + slug(metric);
        o += "<figure id=\"" + fid + "\">";
        const auto size = image.empty() ? std::nullopt : folder.png(image);
        const std::string imageLink =
            size ? "<a class=\"enlarge\" href=\"" + urlOf(image) + "\" data-title=\"" + esc(str(&m, {"title"}) + " — " + image) +
                       "\"><img src=\"" + urlOf(image) + "\" alt=\"" + esc(str(&m, {"title"})) +
                       " per position, from above\" width=\"" + std::to_string(size->first) + "\" height=\"" +
                       std::to_string(size->second) + "\"></a>"
                 : std::string();
        // The numbered worst positions as links over the image (placed in percent of the PNG, legend included).
        std::string pins, rows;
        if (const Json *worst = get(&m, "worst"); worst && worst->is_array())
            for (const Json &w : *worst) {
                const size_t k = size_t(numOr(&w, {"position"}, 0));
                const Json *p = k < positions->size() ? &(*positions)[k] : nullptr;
                const size_t pos = size_t(numOr(&w, {"view"}, 0));
                const std::string rank = fmtCount(numOr(&w, {"rank"}, 0));
                if (size && p)
                    pins += "<a class=\"lm-pin\" href=\"#" + viewId(pos) + "\" style=\"left:" +
                            fx(100.0 * (std::floor(numOr(p, {"x"}, 0)) + 0.5) / size->first) + "%;top:" +
                            fx(100.0 * (std::floor(numOr(p, {"y"}, 0)) + 0.5) / size->second) + "%\" title=\"" +
                            esc(pos < views.size() ? str(views[pos], {"name"}) : "") + ": " +
                            valueText(get(&w, "value"), real) + "\" aria-label=\"worst " + rank + "\">" + rank + "</a>";
                rows += "<tr><td class=\"n\">" + rank + "</td><td>" + viewLink(views, pos) + "</td><td class=\"n\">" +
                        valueText(get(&w, "value"), real) + "</td></tr>";
            }
        // The pins sit in the image's box (position: relative), beside the enlarging link, not in it.
        if (size) o += "<div class=\"imgwrap lm-wrap\">" + imageLink + pins + "</div>";
        o += "<figcaption><b>" + esc(str(&m, {"title"})) + "</b>: " + esc(str(&m, {"meaning"})) + "; from " +
             valueText(get(&m, "min"), real) + " to " + valueText(get(&m, "max"), real) + ".";
        if (!rows.empty())
            o += "<details><summary>worst positions</summary><table><tr><th class=\"n\">#</th><th>view</th><th class=\"n\">" +
                 esc(str(&m, {"title"})) + "</th></tr>" + rows + "</table></details>";
        o += "</figcaption></figure>";
    }
    o += "</div></section>\n";
}

}  // namespace va::html
