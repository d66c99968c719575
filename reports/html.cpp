// report.html from report.json (reports/html.h; docs/html-report.md describes the page).
//
// Structure of the page, top to bottom:
//   header       scene, tool, the verdict (findings.verdict), links to every view
//   routes       each route's series as a plot, worst frames linked (only with routes)
//   level maps   the level from above per metric, worst positions linked (only with level maps)
//   summary      one row per view, worst first (findings.worst_first, each view's findings.score)
//   planner      the report-level "effects" decisions (when present)
//   depth audit  depth-audit.png when the folder holds one
//   PVS audit    a link to pvs-audit.html and its image when the folder holds them (check, pvs_*)
//   per view     (html_view.cpp) camera line; the six questions (the view's findings.answers); the
//                stage funnel (SVG) and stage table; images with legends (click to enlarge);
//                z-fighting hotspots (rows link to boxes over the z-fight image); false culls;
//                ray-cast cross-check; depth formats and a resolution plot (SVG) for the view's
//                near/far; accuracy against time (table and SVG scatter); every other section of
//                the view as a generic table.
//
// The page presents; it judges nothing itself: the verdict, the order and the answers are the
// report's findings (reports/findings.h). Everything reads the report through reports/report_read.h,
// which never throws: a missing key or a value of another type reads as absent, and the part of the
// page that needs it is left out or says "not analysed". Known parts are table-driven
// (kImageKinds), so a new image or section shows up without new code. The page's parts are
// listed in reports/html_parts.h.
#include "reports/html.h"

#include <optional>

#include "reports/findings.h"
#include "reports/html_assets.h"
#include "reports/html_parts.h"
#include "reports/report.h"

namespace va {
namespace html {

std::vector<size_t> worstFirstOf(const Json &report, size_t views) {
    std::vector<size_t> order;
    if (const Json *w = get(&report, {"findings", "worst_first"}); w && w->is_array())
        for (const Json &p : *w)
            if (p.is_number_unsigned() && p.get<uint64_t>() < views) order.push_back(size_t(p.get<uint64_t>()));
    return order;
}

void HtmlWriter::header() {
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

    // The verdict (findings.verdict): the worst findings over all views, in the summary's order of
    // severity.
    const Json *vd = get(r, {"findings", "verdict"});
    const double fc = numOr(vd, {"false_cull_pixels"}, 0), gen = numOr(vd, {"genuine_disagreements"}, 0),
                 zf = numOr(vd, {"zfight_pixels"}, 0);
    std::vector<std::string> findings;
    if (fc > 0)
        findings.push_back("<b>" + plural(fc, "falsely culled pixel", "falsely culled pixels") + "</b> in " +
                           plural(numOr(vd, {"false_cull_views"}, 0), "view", "views"));
    if (gen > 0)
        findings.push_back("<b>" + plural(gen, "genuine ray-cast disagreement", "genuine ray-cast disagreements") + "</b> in " +
                           plural(numOr(vd, {"genuine_views"}, 0), "view", "views"));
    if (zf > 0)
        findings.push_back("<b>" + plural(zf, "z-fighting pixel", "z-fighting pixels") + "</b> in " +
                           plural(numOr(vd, {"zfight_views"}, 0), "view", "views") + " (in their own depth format; " +
                           fmtCount(numOr(vd, {"zfight_coplanar_pixels"}, 0)) + " of them coplanar)");
    const bool bad = !findings.empty();
    if (!bad) findings.push_back("<b>no false culls, ray-cast disagreements or z-fighting found</b>");
    if (const Json *w = get(vd, "worst_overdraw"); w && w->is_object()) {
        const size_t pos = size_t(numOr(w, {"view"}, 0));
        if (pos < views.size())
            findings.push_back("overdraw up to " + fmtReal(numOr(w, {"overdraw"}, NAN)) + " (" + esc(str(views[pos], {"name"})) + ")");
    }
    o += "<p class=\"verdict " + std::string(bad ? "bad" : "good") + "\" id=\"verdict\">";
    for (size_t i = 0; i < findings.size(); ++i) o += (i ? " · " : "") + findings[i];
    o += "</p><nav class=\"toc\">Views: ";
    for (size_t pos : worstFirst) o += "<a href=\"#" + viewId(pos) + "\">" + esc(str(views[pos], {"name"})) + "</a>";
    o += "</nav></header>";
}

// The summary table: one row per view, worst first, from each view's findings.score.
void HtmlWriter::summary() {
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
    for (size_t pos : worstFirst) {
        const Json *v = views[pos], *s = get(v, {"findings", "score"});
        o += "<tr><td><a href=\"#" + viewId(pos) + "\">" + esc(str(v, {"name"})) + "</a></td>";
        o += cell(num(s, {"false_cull_pixels"}), true) + cell(num(s, {"genuine_disagreements"}), true) +
             cell(num(s, {"zfight_pixels"}), true) + cell(num(s, {"zfight_hotspots"}), true);
        o += cell(num(s, {"overdraw"}), false, true) + cell(num(s, {"depth_complexity"}), false, true);
        const auto wasted = num(s, {"wasted_share"});
        o += wasted ? "<td class=\"n\">" + pct(*wasted, 1) + "</td>" : "<td class=\"n muted\">—</td>";
        o += cell(num(s, {"triangles_drawn"}), false) + "<td class=\"n\">" + fmtMs(num(v, {"total_ms"})) + "</td></tr>";
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

}  // namespace html


std::string reportHtml(const nlohmann::ordered_json &reportIn, const std::string &dir) {
    using namespace html;
    // A report written before findings existed gets them here (reports/findings.h); analyze, check
    // and merge store them in report.json.
    std::optional<Json> withFindings;
    if (!get(&reportIn, "findings")) {
        withFindings = reportIn;
        addFindings(&*withFindings);
    }
    const Json &report = withFindings ? *withFindings : reportIn;
    HtmlWriter w{report, Folder{dir}};
    std::string &o = w.o;
    const std::vector<const Json *> &vs = w.views;
    const std::string scenePath = str(&report, {"scene", "path"});
    o += "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
         "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
         "<meta name=\"color-scheme\" content=\"light dark\">"
         // Nothing may load from elsewhere: images from this folder only, inline style and script.
         "<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; img-src 'self' file: data:; "
         "style-src 'unsafe-inline'; script-src 'unsafe-inline'\">"
         "<title>visaudit: " + esc(scenePath) + "</title><style>" + html_assets::kCss + "</style></head><body>\n";
    w.header();
    // What a level designer reads first: where along the routes and where in the level it costs.
    w.routes();
    w.levelMaps();
    w.summary();
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

std::string htmlEscape(std::string_view text) { return html::esc(text); }

}  // namespace va
