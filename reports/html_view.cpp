// report.html: a view's sections (reports/html_parts.h).
#include <algorithm>
#include <cmath>
#include <set>

#include "reports/html_parts.h"

namespace va::html {

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
    // The resolution plot for this view's near/far (report.depth_curves, computed by the analysis).
    const Json *curves = get(&report, "depth_curves");
    const auto k = num(v, {"depth_curve"});
    if (!curves || !curves->is_array() || !k || !(*k >= 0 && *k < double(curves->size()))) return;
    const size_t set = size_t(*k);
    const Json *curve = &(*curves)[set];
    std::vector<std::pair<std::string, double>> markers;
    if (const Json *hs = get(d, "hotspots"); hs && hs->is_array())
        for (const Json &h : *hs)
            if (auto dep = num(get(&h, "depth")); dep && markers.size() < 12) markers.emplace_back("#" + fmtValue(get(&h, "id")), *dep);
    const std::string svg = resolutionSvg(curve, own, markers, id + "-resolution", "depth-curves-" + std::to_string(set),
                                          curvesDrawn.insert(set).second);
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

// The six questions of visibility, as the view's findings answer them: sentences joined with "; "
// and ended with "."; a part that was not analysed says so, muted, with its reason.
void HtmlWriter::answers(const Json *v) {
    const auto notAnalysed = [](const std::string &why) {
        return "<span class=\"muted\">not analysed</span>" + (why.empty() ? std::string() : " (" + esc(why) + ")");
    };
    o += "<h3>The six questions</h3><ul class=\"questions\">";
    if (const Json *as = get(v, {"findings", "answers"}); as && as->is_array())
        for (const Json &a : *as) {
            o += "<li><span class=\"q\">" + esc(str(get(&a, "question"))) + "</span> ";
            if (const Json *why = get(&a, "not_analysed")) {
                o += notAnalysed(str(why));
            } else if (const Json *parts = get(&a, "answer"); parts && parts->is_array()) {
                for (size_t i = 0; i < parts->size(); ++i) {
                    const Json &p = (*parts)[i];
                    o += (i ? "; " : "") + (p.is_string() ? esc(p.get<std::string>()) : notAnalysed(str(get(&p, "not_analysed"))));
                }
                o += ".";
            }
            o += "</li>";
        }
    o += "</ul>";
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
    // A route's frame: which one, when, and a link to the route's plot.
    if (const Json *r = get(v, "route"); r && r->is_object())
        o += "<div class=\"meta route-frame\">frame " + fmtValue(get(r, "frame")) + " of route <a href=\"#route-" +
             slug(str(r, {"name"})) + "\">" + esc(str(r, {"name"})) + "</a> at " + fmtReal(numOr(r, {"time"}, 0)) + " s</div>";

    const auto methods = orderingMethods(get(v, "ordering"));
    answers(v);

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
                                                  "depth", "audit", "raycast", "findings", "route"};
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

}  // namespace va::html
