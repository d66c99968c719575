// diff.html: the comparison of two runs as one self-contained page (reports/diff.h). Presents
// diff.json; computes nothing.
#include <cmath>

#include "reports/diff.h"
#include "reports/html.h"
#include "reports/html_assets.h"
#include "reports/html_parts.h"
#include "reports/level_maps.h"

namespace va {

namespace {

using namespace html;

// A change as a table cell: "old → new (+delta)", red when it rose (every metric here is better
// lower but for time, which is only shown), green when it fell.
std::string changeCell(const Json *c, bool real) {
    if (!c) return "<td class=\"n muted\">—</td>";
    auto text = [&](const Json *x) {
        const auto v = num(x);
        return v ? (real ? fmtReal(*v) : fmtCount(*v)) : std::string("—");
    };
    const auto delta = num(get(c, "delta"));
    const std::string cls = delta && *delta > 0 ? " bad" : delta && *delta < 0 ? " good" : "";
    std::string o = "<td class=\"n" + cls + "\">" + text(get(c, "old")) + " → " + text(get(c, "new"));
    if (delta && *delta != 0) o += " (" + std::string(*delta > 0 ? "+" : "−") + (real ? fmtReal(std::fabs(*delta)) : fmtCount(std::fabs(*delta))) + ")";
    return o + "</td>";
}

// A route's frames: per metric the old (dashed) and the new (solid) series against time.
std::string routeDiffSvg(const Json &r, const std::string &id) {
    const Json *frames = get(&r, "frames");
    const size_t n = frames && frames->is_array() ? frames->size() : 0;
    const std::vector<ViewMetric> &metrics = routeMetrics();
    const int W = 900, left = 150, right = 20, panelH = 60, gap = 16, top = 8;
    const int H = top + int(metrics.size()) * (panelH + gap) + 20, plotW = W - left - right;
    double t0 = 0, t1 = 1;
    if (n) t0 = numOr(&(*frames)[0], {"time"}, 0), t1 = numOr(&(*frames)[n - 1], {"time"}, 1);
    auto xOf = [&](double t) { return left + (t1 > t0 ? (t - t0) / (t1 - t0) * plotW : 0.0); };
    std::string o = "<svg class=\"chart\" id=\"" + id + "\" viewBox=\"0 0 " + std::to_string(W) + " " + std::to_string(H) +
                    "\" role=\"img\" aria-label=\"the route's metrics per frame, old dashed, new solid\">";
    for (size_t mi = 0; mi < metrics.size(); ++mi) {
        const ViewMetric &m = metrics[mi];
        const int y0 = top + int(mi) * (panelH + gap), yb = y0 + panelH;
        double hi = 0;
        for (size_t k = 0; k < n; ++k)
            for (const char *w : {"old", "new"})
                if (const auto v = num(&(*frames)[k], {"metrics", m.key, w})) hi = std::max(hi, *v);
        o += "<text x=\"0\" y=\"" + std::to_string(y0 + 14) + "\">" + esc(m.title) + "</text><text class=\"muted\" x=\"0\" y=\"" +
             std::to_string(y0 + 30) + "\">max " + (m.real ? fmtReal(hi) : fmtCount(hi)) + "</text><line class=\"axis\" x1=\"" +
             std::to_string(left) + "\" y1=\"" + std::to_string(yb) + "\" x2=\"" + std::to_string(left + plotW) + "\" y2=\"" +
             std::to_string(yb) + "\"/>";
        for (const char *w : {"old", "new"}) {
            std::string pts;
            for (size_t k = 0; k < n; ++k)
                if (const auto v = num(&(*frames)[k], {"metrics", m.key, w}))
                    pts += (pts.empty() ? "" : " ") + fx(xOf(numOr(&(*frames)[k], {"time"}, 0))) + "," +
                           fx(yb - (hi > 0 ? *v / hi * (panelH - 4) : 0.0));
            o += std::string("<polyline fill=\"none\" style=\"stroke:var(") + (w[0] == 'o' ? "--muted" : "--accent") +
                 ");stroke-width:1.5" + (w[0] == 'o' ? ";stroke-dasharray:4 3" : "") + "\" points=\"" + pts + "\"><title>" + w +
                 "</title></polyline>";
        }
    }
    const int ya = top + int(metrics.size()) * (panelH + gap) + 10;
    o += "<text x=\"" + std::to_string(left) + "\" y=\"" + std::to_string(ya) + "\">" + fmtReal(t0) + " s</text><text x=\"" +
         std::to_string(left + plotW) + "\" y=\"" + std::to_string(ya) + "\" text-anchor=\"end\">" + fmtReal(t1) +
         " s</text></svg>";
    return o;
}

}  // namespace

std::string diffHtml(const Json &d, const std::string &dir) {
    const Folder folder{dir};
    const std::string scene = str(&d, {"new", "scene", "path"});
    std::string o;
    o += "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
         "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
         "<meta name=\"color-scheme\" content=\"light dark\">"
         "<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; img-src 'self' file: data:; "
         "style-src 'unsafe-inline'; script-src 'unsafe-inline'\">"
         "<title>visaudit diff: " + esc(scene) + "</title><style>" + std::string(html_assets::kCss) + "</style></head><body>\n";
    const Json *t = get(&d, "totals");
    o += "<header><h1>visaudit diff: " + esc(scene) + "</h1><div class=\"meta\"><code>" + esc(str(&d, {"old", "report"})) +
         "</code> (" + fmtCount(numOr(&d, {"old", "scene", "triangles"}, 0)) + " triangles, " +
         plural(numOr(&d, {"old", "views"}, 0), "view", "views") + ") → <code>" + esc(str(&d, {"new", "report"})) + "</code> (" +
         fmtCount(numOr(&d, {"new", "scene", "triangles"}, 0)) + " triangles, " +
         plural(numOr(&d, {"new", "views"}, 0), "view", "views") + ") · " + esc(str(&d, {"format"})) + "</div>";
    const Json *reg = get(&d, "regressions");
    const double failed = numOr(reg, {"failed"}, 0);
    o += std::string("<p class=\"verdict ") + (failed > 0 ? "bad" : "good") + "\" id=\"verdict\">";
    if (reg) o += "<b>" + plural(failed, "regression", "regressions") + "</b> beyond the budget's allowance · ";
    o += fmtCount(numOr(t, {"views_changed"}, 0)) + " of " + plural(numOr(t, {"views_compared"}, 0), "view", "views") +
         " changed · " + fmtCount(numOr(t, {"images_changed"}, 0)) + " of " + plural(numOr(t, {"images_compared"}, 0), "image", "images") +
         " differ</p></header>\n";

    // Regressions against the budget.
    if (reg) {
        o += "<section class=\"block\" id=\"regressions\"><h2>Regressions (budget <code>" + esc(str(reg, {"budget"})) +
             "</code>)</h2><div class=\"scroll\"><table><tr><th>status</th><th>view</th><th>metric</th><th>old → new</th>"
             "<th>allowed</th><th>what</th></tr>";
        if (const Json *cs = get(reg, "checks"); cs && cs->is_array())
            for (int pass = 0; pass < 2; ++pass)
                for (const Json &c : *cs) {
                    if (isTrue(get(&c, "pass")) != bool(pass)) continue;
                    o += std::string("<tr><td class=\"") + (pass ? "good\">ok" : "bad\">FAIL") + "</td><td>" + esc(str(&c, {"view"})) +
                         "</td><td>" + esc(str(&c, {"metric"})) + "</td><td>" + esc(str(&c, {"value"})) + "</td><td>" +
                         esc(str(&c, {"allowed"})) + "</td><td>" + esc(str(&c, {"message"})) + "</td></tr>";
                }
        o += "</table></div></section>\n";
    }

    // Views: changed ones first (in NEW's order), then the unchanged.
    const std::vector<ViewMetric> &metrics = diffMetrics();
    o += "<section class=\"block\" id=\"views\"><h2>Views, matched by name</h2><p class=\"note\">old → new (change); red "
         "rose, green fell. Every metric here is better lower, but the time, which depends on the machine.</p>"
         "<div class=\"scroll\"><table id=\"diff-table\"><tr><th>view</th>";
    for (const ViewMetric &m : metrics) o += "<th class=\"n\" title=\"" + esc(m.meaning) + "\">" + esc(m.title) + "</th>";
    o += "<th class=\"n\">images differing</th></tr>";
    const Json *views = get(&d, "views");
    for (int changed = 1; changed >= 0 && views && views->is_array(); --changed)
        for (const Json &v : *views) {
            if (isTrue(get(&v, "changed")) != bool(changed)) continue;
            o += std::string("<tr") + (changed ? "" : " class=\"skipped\"") + "><td>" + esc(str(&v, {"name"})) + "</td>";
            for (const ViewMetric &m : metrics) o += changeCell(get(&v, {"metrics", m.key}), m.real);
            size_t differ = 0;
            if (const Json *im = get(&v, "images"); im && im->is_array())
                for (const Json &e : *im) differ += e.contains("diff") || isTrue(get(&e, "size_differs"));
            o += "<td class=\"n\">" + (differ ? "<a href=\"#img-" + slug(str(&v, {"name"})) + "\">" + fmtCount(double(differ)) + "</a>"
                                              : std::string("0")) +
                 "</td></tr>";
        }
    o += "</table></div>";
    for (const char *side : {"only_in_old", "only_in_new"}) {
        const Json *names = get(&d, side);
        if (!names || !names->is_array() || names->empty()) continue;
        o += std::string("<p>") + (side[8] == 'o' ? "Only in OLD" : "Only in NEW") + " (not compared): ";
        for (size_t i = 0; i < names->size(); ++i) o += (i ? ", " : "") + esc(str(&(*names)[i]));
        o += "</p>";
    }
    o += "</section>\n";

    // Routes.
    if (const Json *rs = get(&d, "routes"); rs && rs->is_array() && !rs->empty()) {
        o += "<section class=\"block\" id=\"routes\"><h2>Routes, frame by frame</h2><p class=\"note\">Old dashed, new solid; "
             "frames matched by number.</p>";
        for (const Json &r : *rs) {
            o += "<h3 id=\"route-" + slug(str(&r, {"name"})) + "\">" + esc(str(&r, {"name"})) + "</h3>";
            o += routeDiffSvg(r, "route-" + slug(str(&r, {"name"})) + "-plot");
            const double oo = numOr(&r, {"only_in_old"}, 0), on = numOr(&r, {"only_in_new"}, 0);
            if (oo || on) o += "<p class=\"note\">" + plural(oo, "frame", "frames") + " only in OLD, " + fmtCount(on) + " only in NEW.</p>";
        }
        o += "</section>\n";
    }

    // The level maps of the change.
    if (const Json *maps = get(&d, {"level_maps", "maps"}); maps && maps->is_array()) {
        o += "<section class=\"block\" id=\"level-maps\"><h2>Where it changed: the level from above</h2><p class=\"note\">Each "
             "sample position of NEW coloured by the change of its worst view's value (new − old): blue fell, red rose, "
             "white unchanged; numbered: the largest rises.</p><div class=\"gallery\">";
        for (const Json &m : *maps) {
            const std::string image = str(&m, {"image"});
            if (image.empty() || !folder.exists(image)) continue;
            o += "<figure><a class=\"enlarge imgwrap\" href=\"" + urlOf(image) + "\" data-title=\"" + esc(image) + "\"><img src=\"" +
                 urlOf(image) + "\" alt=\"change of " + esc(str(&m, {"title"})) + "\"";
            if (auto sz = folder.png(image)) o += " width=\"" + std::to_string(sz->first) + "\" height=\"" + std::to_string(sz->second) + "\"";
            o += "></a><figcaption><b>" + esc(str(&m, {"title"})) + "</b>: from " + fmtReal(numOr(&m, {"min"}, 0)) + " to +" +
                 fmtReal(numOr(&m, {"max"}, 0)) + "</figcaption></figure>";
        }
        o += "</div></section>\n";
    }

    // Image diffs.
    o += "<section class=\"block\" id=\"images\"><h2>Images that differ</h2><p class=\"note\">Changed pixels in magenta over "
         "the new image, dimmed.</p>";
    bool any = false;
    for (int pass = 0; pass < 1 && views && views->is_array(); ++pass)
        for (const Json &v : *views) {
            std::string figs;
            if (const Json *im = get(&v, "images"); im && im->is_array())
                for (const Json &e : *im) {
                    if (isTrue(get(&e, "size_differs"))) {
                        figs += "<p>" + esc(str(&e, {"kind"})) + ": the image sizes differ.</p>";
                        continue;
                    }
                    const std::string file = str(&e, {"diff"});
                    if (file.empty() || !folder.exists(file)) continue;
                    figs += "<figure><a class=\"enlarge imgwrap\" href=\"" + urlOf(file) + "\" data-title=\"" + esc(file) +
                            "\"><img loading=\"lazy\" src=\"" + urlOf(file) + "\" alt=\"" + esc(str(&e, {"kind"})) + " changes\"";
                    if (auto sz = folder.png(file)) figs += " width=\"" + std::to_string(sz->first) + "\" height=\"" + std::to_string(sz->second) + "\"";
                    figs += "></a><figcaption><b>" + esc(str(&e, {"kind"})) + "</b>: " +
                            pct(numOr(&e, {"changed_pixels"}, 0), numOr(&e, {"width"}, 0) * numOr(&e, {"height"}, 0)) + " of the pixels (" +
                            fmtCount(numOr(&e, {"changed_pixels"}, 0)) + ") changed</figcaption></figure>";
                }
            if (figs.empty()) continue;
            any = true;
            o += "<h3 id=\"img-" + slug(str(&v, {"name"})) + "\">" + esc(str(&v, {"name"})) + "</h3><div class=\"gallery\">" + figs + "</div>";
        }
    if (!any) o += "<p>None: every image both runs wrote is the same, pixel for pixel.</p>";
    o += "</section>\n";
    o += "<dialog id=\"enlarge\"><img alt=\"\"><p></p></dialog><script>" + std::string(html_assets::kScript) +
         "</script></body></html>\n";
    return o;
}

}  // namespace va
