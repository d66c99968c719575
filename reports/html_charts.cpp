// report.html: inline SVG charts (reports/html_parts.h).
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "render/depth_format.h"
#include "reports/depth_plot.h"
#include "reports/html_parts.h"

namespace va::html {

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
static std::vector<double> niceTicks(double lo, double hi, int target) {
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
std::string resolutionSvg(const Json *curve, const std::string &ownFormat,
                          const std::vector<std::pair<std::string, double>> &markers, const std::string &id,
                          const std::string &sharedId, bool defineShared) {
    // The curve set as the report stores it: depths, and per format its resolution at each depth
    // (null where the format does not represent the depth).
    const Json *depthsJson = get(curve, "depths"), *formats = get(curve, "formats");
    const auto nearZ = num(curve, {"near"}), farZ = num(curve, {"far"});
    if (!depthsJson || !depthsJson->is_array() || !formats || !formats->is_array() || !nearZ || !farZ) return {};
    std::vector<double> depths;
    for (const Json &d : *depthsJson) depths.push_back(d.is_number() ? d.get<double>() : NAN);
    struct Series {
        std::string name;
        std::vector<std::optional<double>> resolution;
    };
    std::vector<Series> series;
    for (const Json &f : *formats) {
        Series s{str(get(&f, "name")), {}};
        if (const Json *res = get(&f, "resolution"); res && res->is_array())
            for (const Json &v : *res) s.resolution.push_back(num(&v));
        series.push_back(std::move(s));
    }
    double yLo = INFINITY, yHi = 0;
    for (const Series &f : series)
        for (const auto &v : f.resolution)
            if (v && *v > 0 && std::isfinite(*v)) {
                yLo = std::min(yLo, *v);
                yHi = std::max(yHi, *v);
            }
    if (!(yHi > 0) || depths.empty()) return {};
    const double dLo = std::floor(std::log10(yLo)), dHi = std::max(dLo + 1, std::ceil(std::log10(yHi)));
    const double xLo = std::log10(*nearZ), xHi = std::log10(*farZ);
    const double L = 70, R = 640, T = 12, B = 300;
    const auto X = [&](double d) { return L + (R - L) * (std::log10(d) - xLo) / (xHi - xLo); };
    const auto Y = [&](double res) { return B - (B - T) * (std::log10(res) - dLo) / (dHi - dLo); };
    // Drawn on a light panel in both color schemes: the format colors are depth-audit.png's,
    // chosen for a white background.
    std::string o = "<svg class=\"chart resolution lightpanel\" id=\"" + id +
                    "\" viewBox=\"0 0 860 340\" role=\"img\" aria-label=\"Depth resolution against view depth per format\">"
                    "<rect class=\"panel\" x=\"0\" y=\"0\" width=\"860\" height=\"340\" rx=\"6\"/>";
    // What every view of this curve set shares -- the decade grid (both axes), the axis titles and
    // every format's curve -- is drawn once, in the first view that uses the set, and referenced by
    // the others (<use>): a report of hundreds of views of one near/far carries the curves once.
    auto curvePath = [&](const Series &f) {
        std::string d;  // one path, broken ("M") where a sample is absent
        bool pen = false;
        for (size_t i = 0; i < depths.size() && i < f.resolution.size(); ++i) {
            const auto &v = f.resolution[i];
            if (!v || !(*v > 0) || !std::isfinite(*v)) {
                pen = false;
                continue;
            }
            d += (pen ? "L" : "M") + fx(X(depths[i])) + " " + fx(Y(*v));
            pen = true;
        }
        return d;
    };
    auto colorOf = [](const Series &f) {
        DepthFormatSpec spec;
        const Rgb8 c = parseDepthFormat(f.name, &spec, nullptr) ? depthPlotColor(spec) : Rgb8{128, 128, 128};
        char color[16];
        std::snprintf(color, sizeof color, "#%02x%02x%02x", c.r, c.g, c.b);
        return std::string(color);
    };
    if (defineShared) {
        o += "<g id=\"" + sharedId + "\">";
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
             fmtReal(*nearZ) + " to far " + fmtReal(*farZ) + "</text>";
        o += "<text text-anchor=\"middle\" transform=\"translate(14 " + fx((T + B) / 2) + ") rotate(-90)\">resolution (m)</text>";
        for (const Series &f : series)
            o += "<path fill=\"none\" stroke=\"" + colorOf(f) + "\" stroke-width=\"1.5\" d=\"" + curvePath(f) + "\"><title>" +
                 esc(f.name) + "</title></path>";
        o += "</g>";
    } else {
        o += "<use href=\"#" + sharedId + "\"/>";
    }
    for (const auto &[name, depth] : markers) {
        if (!(depth >= *nearZ && depth <= *farZ)) continue;
        o += "<line class=\"mark\" x1=\"" + fx(X(depth)) + "\" y1=\"" + fx(T) + "\" x2=\"" + fx(X(depth)) + "\" y2=\"" +
             fx(B) + "\"><title>hotspot " + esc(name) + " at " + fmtReal(depth) + " m</title></line>";
        o += "<text class=\"marklabel\" x=\"" + fx(X(depth) + 3) + "\" y=\"" + fx(T + 10) + "\">" + esc(name) + "</text>";
    }
    // This view's own format drawn bold over its thin curve, and the legend with it marked.
    int legendRow = 0;
    for (const Series &f : series) {
        const std::string color = colorOf(f);
        const bool own = f.name == ownFormat;
        if (own)
            o += "<path fill=\"none\" stroke=\"" + color + "\" stroke-width=\"3.5\" d=\"" + curvePath(f) + "\"><title>" +
                 esc(f.name) + " (this view's format)</title></path>";
        const double ly = T + 6 + 17 * legendRow++;
        o += "<rect x=\"660\" y=\"" + fx(ly) + "\" width=\"14\" height=\"" + (own ? "6" : "3") + "\" fill=\"" + color + "\"/>";
        o += "<text x=\"680\" y=\"" + fx(ly + 6) + "\"" + (own ? " font-weight=\"bold\"" : "") + ">" + esc(f.name) +
             (own ? " (this view)" : "") + "</text>";
    }
    o += "</svg>";
    return o;
}

}  // namespace va::html
