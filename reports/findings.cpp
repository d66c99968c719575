// Findings, computed once and stored in the report (reports/findings.h).
#include "reports/findings.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <tuple>
#include <vector>

#include "reports/report_read.h"
#include "reports/text_format.h"

namespace va {
namespace {

using namespace rjson;

// ---- The score of a view (the summary row, the order, the verdict) ------------------------------

// A number of the report as it is (an integer stays an integer), or null when absent.
Json numberOrNull(const Json *j) { return j && j->is_number() ? *j : Json(nullptr); }

Json scoreOf(const Json *v) {
    const Json *audit = get(v, "audit"), *depth = get(v, "depth");
    const bool auditRan = !ranFalse(audit), rayRan = !ranFalse(get(v, "raycast"));
    const bool depthRan = depth && !ranFalse(depth);
    const std::string format = str(v, {"depth_format"});
    const Json *z = stageNamed(v, "zbuffer");
    Json s;
    s["false_cull_pixels"] = auditRan ? numberOrNull(get(v, {"audit", "false_culls", "pixels"})) : Json(nullptr);
    s["genuine_disagreements"] = rayRan ? numberOrNull(get(v, {"raycast", "cross_check", "genuine"})) : Json(nullptr);
    const Json zf = depthRan ? numberOrNull(get(v, {"depth", "formats", format, "fighting_pixels"})) : Json(nullptr);
    s["zfight_pixels"] = zf;
    s["zfight_hotspots"] = zf.is_null() ? Json(nullptr) : numberOrNull(get(v, {"depth", "formats", format, "hotspots"}));
    s["overdraw"] = numberOrNull(get(v, {"zbuffer", "overdraw"}));
    s["depth_complexity"] = numberOrNull(get(v, {"zbuffer", "depth_complexity"}));
    s["wasted_share"] = auditRan ? numberOrNull(get(v, {"audit", "wasted_draws", "share"})) : Json(nullptr);
    s["triangles_drawn"] = stageRan(z) ? numberOrNull(get(z, "triangles_out")) : Json(nullptr);
    return s;
}

// Worst first: false-cull pixels, then genuine disagreements, then z-fighting pixels, then
// overdraw; absent values count as 0.
std::tuple<double, double, double, double> severity(const Json *score) {
    return {numOr(score, {"false_cull_pixels"}, 0), numOr(score, {"genuine_disagreements"}, 0),
            numOr(score, {"zfight_pixels"}, 0), numOr(score, {"overdraw"}, 0)};
}

// ---- The six questions ----------------------------------------------------------------------------

// An answer: sentences joined with "; " and ended with "."; a sentence may itself say that a part
// was not analysed, and why.
struct Answer {
    Json parts = Json::array();
    void add(std::string s) { parts.push_back(std::move(s)); }
    void addNotAnalysed(const std::string &why) { parts.push_back(Json{{"not_analysed", why}}); }
    bool empty() const { return parts.empty(); }
};

Json answered(const char *question, const Answer &a) { return {{"question", question}, {"answer", a.parts}}; }
Json notAnalysed(const char *question, const std::string &why) { return {{"question", question}, {"not_analysed", why}}; }

// What is off-screen: the frustum stage's culled objects and the clip stage's rejected triangles.
Json answerOffScreen(const Json *v) {
    const char *q = "What is off-screen?";
    const Json *fr = stageNamed(v, "frustum"), *cl = stageNamed(v, "clip");
    Answer a;
    if (stageRan(fr))
        a.add("frustum culling removed " + plural(numOr(fr, {"objects_culled"}, 0), "object", "objects") + " (" +
              plural(numOr(fr, {"triangles_culled"}, 0), "triangle", "triangles") + ") wholly outside the view");
    if (stageRan(cl)) {
        std::string s = "clipping rejected " + plural(numOr(cl, {"trivially_rejected"}, 0), "more triangle", "more triangles") +
                        " outside one frustum plane";
        if (const auto near = num(cl, {"per_plane", "near"}); near && *near > 0)
            s += ", and cut " + plural(*near, "triangle", "triangles") + " at the near plane";
        a.add(s);
    }
    if (const Json *c = stageNamed(v, "cells"); stageRan(c)) {
        if (auto vis = num(c, {"clusters_visible"}), tot = num(c, {"clusters_total"}); vis && tot)
            a.add("the PVS lets the camera see " + fmtCount(*vis) + " of " + fmtCount(*tot) + " clusters (" +
                  plural(numOr(c, {"triangles_culled"}, 0), "triangle", "triangles") + " culled)");
        if (auto visited = firstNum(c, {"cells_visited"}); visited)
            a.add("portal traversal visited " + plural(*visited, "cell", "cells"));
    }
    if (a.empty()) return notAnalysed(q, fr ? str(get(fr, "reason")) : "no frustum stage");
    return answered(q, a);
}

// What is too far to draw: the far plane's cut, the grid stage, and the detail audit's objects that
// project to a few pixels.
Json answerTooFar(const Json *v) {
    const char *q = "What is too far to draw?";
    const Json *cl = stageNamed(v, "clip");
    const auto farZ = num(v, {"camera", "far"});
    Answer a;
    if (stageRan(cl) && farZ) {
        const double cut = numOr(cl, {"per_plane", "far"}, 0);
        a.add(cut > 0 ? plural(cut, "triangle crosses", "triangles cross") + " the far plane at " + fmtReal(*farZ) + " and " +
                            (cut == 1 ? "is" : "are") + " cut there"
                      : "nothing crosses the far plane at " + fmtReal(*farZ));
    }
    if (const Json *g = stageNamed(v, "grid"); stageRan(g))
        a.add("the grid stage culled " + plural(numOr(g, {"triangles_culled"}, 0), "triangle", "triangles"));
    // The detail audit's "too small" objects: a draw distance would drop them.
    if (const Json *d = get(v, "detail"); d && !ranFalse(d))
        if (auto n = firstNum(d, {"objects_too_small", "too_small_objects", "objects_too_far"}))
            a.add(plural(*n, "drawn object projects", "drawn objects project") +
                  " to a few pixels at most: a draw distance would drop " + (*n == 1 ? "it" : "them"));
    if (a.empty()) return notAnalysed(q, cl ? "" : "no clip stage");
    return answered(q, a);
}

// What needs less detail: the detail audit when it ran; and the z-buffer's empty triangles (drawn,
// yet covering no pixel center: sub-pixel geometry a lower level of detail would drop).
Json answerLessDetail(const Json *v) {
    const char *q = "What needs less detail?";
    Answer a;
    const Json *d = get(v, "detail");
    if (d && !ranFalse(d)) {
        const auto over = firstNum(d, {"objects_over_detailed", "over_detailed_objects"}),
                   saved = firstNum(d, {"triangles_savable", "triangles_saved"}),
                   perPixel = firstNum(d, {"triangles_per_visible_pixel"});
        if (over) a.add(plural(*over, "object draws", "objects draw") + " more triangles than pixels it shows");
        if (perPixel) a.add(fmtReal(*perPixel) + " triangles drawn per visible pixel");
        if (saved) a.add("coarser detail or a draw distance would save " + plural(*saved, "triangle", "triangles"));
        if (a.empty()) a.add("see the level-of-detail section below");
    } else if (d && ranFalse(d)) {
        a.addNotAnalysed(str(get(d, "reason")));
    }
    if (const Json *z = stageNamed(v, "zbuffer"); stageRan(z)) {
        const double empty = numOr(z, {"triangles_empty"}, 0), in = numOr(z, {"triangles_in"}, 0);
        if (empty > 0)
            a.add(plural(empty, "triangle", "triangles") + " of " + fmtCount(in) + " reaching the z-buffer (" + pct(empty, in) +
                  ") cover no pixel center: sub-pixel detail");
        else
            a.add("every triangle reaching the z-buffer covers a pixel");
    }
    if (a.empty()) return notAnalysed(q, "no detail section, no z-buffer stage");
    return answered(q, a);
}

// What is obscured by what: the occlusion stage, the audit's wasted draws (drawn, visible nowhere)
// and the fragments hidden behind nearer ones.
Json answerObscured(const Json *v) {
    const char *q = "What is obscured by what?";
    Answer a;
    const bool occlusionRan = stageRan(stageNamed(v, "occlusion"));
    if (occlusionRan)
        a.add("occlusion culling removed " + plural(numOr(stageNamed(v, "occlusion"), {"triangles_culled"}, 0), "triangle", "triangles") +
              " behind occluders");
    const Json *w = get(v, {"audit", "wasted_draws"});
    if (w && !ranFalse(get(v, "audit")))
        a.add(fmtCount(numOr(w, {"triangles"}, 0)) + " of " + fmtCount(numOr(w, {"drawn_triangles"}, 0)) + " drawn triangles (" +
              pct(numOr(w, {"triangles"}, 0), numOr(w, {"drawn_triangles"}, 0)) +
              ") are visible nowhere, hidden behind others or sub-pixel, costing " +
              plural(numOr(w, {"fragments"}, 0), "fragment", "fragments"));
    if (const auto f = num(v, {"zbuffer", "fragments"}), c = num(v, {"zbuffer", "covered_pixels"}); f && c && *f >= *c)
        a.add(plural(*f - *c, "fragment", "fragments") + " lie behind the nearest surface (depth complexity " +
              fmtReal(numOr(v, {"zbuffer", "depth_complexity"}, NAN)) + ")");
    if (a.empty()) return notAnalysed(q, "");
    if (!occlusionRan) a.add("no occlusion stage ran");
    return answered(q, a);
}

// What is in front of what: the ordering methods' wrong pixels, and where the depth format cannot
// order two surfaces (z-fighting in the view's own format).
Json answerOrder(const Json *v) {
    const char *q = "What is in front of what?";
    const auto methods = orderingMethods(get(v, "ordering"));
    Answer a;
    for (const auto &[name, row] : methods)
        if (auto wrong = num(get(row, "wrong_pixels"))) a.add(name + " gets " + plural(*wrong, "pixel", "pixels") + " wrong");
    if (const auto z = zfightInOwnFormat(v)) {
        const std::string fmt = str(v, {"depth_format"});
        if (*z > 0) {
            std::string s = "the z-buffer (" + fmt + ") cannot order the two nearest surfaces at " + plural(*z, "pixel", "pixels");
            const Json *hs = get(v, {"depth", "hotspots"});
            if (hs && hs->is_array() && !hs->empty()) {
                const Json *objs = get(&hs->front(), "objects");
                const double area = numOr(&hs->front(), {"area"}, 0);
                if (objs && objs->is_array() && objs->size() == 2)
                    s += ", worst where " + str(&(*objs)[0]) + " and " + str(&(*objs)[1]) + " meet (hotspot 1, " +
                         plural(area, "pixel", "pixels") +
                         (area > 0 && numOr(&hs->front(), {"coplanar_pixels"}, -1) == area
                              ? ", coplanar: no depth format can order them; offset one or use a depth bias"
                              : "") +
                         ")";
            }
            a.add(s);
        } else {
            a.add("the z-buffer (" + fmt + ") orders every pixel's two nearest surfaces");
        }
    }
    if (a.empty()) return notAnalysed(q, "no ordering or depth section");
    if (methods.empty()) a.add("painter's and BSP ordering not analysed");
    return answered(q, a);
}

// What stands between a surface and a light: shadow rays per light, else the planner's reason for
// not tracing them.
Json answerShadows(const Json *v, const Json *report) {
    const char *q = "What stands between a surface and a light?";
    const Json *lights = get(v, {"raycast", "lights"});
    if (!lights || !lights->is_array()) lights = get(v, {"effects", "lights"});
    if (lights && lights->is_array() && !lights->empty()) {
        std::string s;
        for (const Json &l : *lights) {
            const double sh = numOr(&l, {"shadowed_pixels"}, 0), lit = numOr(&l, {"lit_pixels"}, 0);
            s += (s.empty() ? "" : "; ") + std::string("light ") + str(get(&l, "name")) + ": " +
                 plural(sh, "pixel is", "pixels are") + " shadowed (something stands between surface and light), " +
                 fmtCount(lit) + " lit (" + pct(sh, sh + lit) + " shadowed)";
        }
        Answer a;
        a.add(s);
        return answered(q, a);
    }
    const Json *decisions = get(report, {"effects", "decisions"});
    if (decisions && decisions->is_array())
        for (const Json &d : *decisions)
            if (str(get(&d, "name")).find("shadow") != std::string::npos && !isTrue(get(&d, "ran")))
                return notAnalysed(q, str(get(&d, "reason")));
    return notAnalysed(q, "no shadow rays in this report");
}

}  // namespace

Json viewFindings(const Json &view, const Json &report) {
    const Json *v = &view;
    return {{"score", scoreOf(v)},
            {"answers",
             {answerOffScreen(v), answerTooFar(v), answerLessDetail(v), answerObscured(v), answerOrder(v),
              answerShadows(v, &report)}}};
}

Json reportFindings(const Json &report) {
    const std::vector<const Json *> views = viewsOf(report);
    std::vector<size_t> order(views.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    auto score = [&](size_t i) { return get(views[i], {"findings", "score"}); };
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return severity(score(a)) > severity(score(b)); });

    // The verdict: each finding's sum over views and how many views have it.
    uint64_t fc = 0, gen = 0, zf = 0, coplanar = 0, fcViews = 0, genViews = 0, zfViews = 0;
    Json worstOverdraw = nullptr;
    std::optional<double> most;
    for (size_t i : order) {
        const Json *s = score(i);
        const double f = numOr(s, {"false_cull_pixels"}, 0), g = numOr(s, {"genuine_disagreements"}, 0),
                     z = numOr(s, {"zfight_pixels"}, 0);
        fc += uint64_t(f), fcViews += f > 0;
        gen += uint64_t(g), genViews += g > 0;
        zf += uint64_t(z), zfViews += z > 0;
        if (auto od = num(s, {"overdraw"}); od && (!most || *od > *most)) {
            most = od;
            worstOverdraw = {{"view", i}, {"overdraw", *od}};
        }
    }
    // Coplanar fights are a geometry problem (no depth format helps): how many of them there are.
    for (const Json *v : views)
        coplanar += uint64_t(num(v, {"depth", "formats", str(v, {"depth_format"}), "coplanar_pixels"}).value_or(0));
    return {{"worst_first", order},
            {"verdict",
             {{"false_cull_pixels", fc},
              {"false_cull_views", fcViews},
              {"genuine_disagreements", gen},
              {"genuine_views", genViews},
              {"zfight_pixels", zf},
              {"zfight_views", zfViews},
              {"zfight_coplanar_pixels", coplanar},
              {"worst_overdraw", worstOverdraw}}}};
}

void addFindings(Json *report) {
    if (!report->is_object() || !report->contains("views") || !(*report)["views"].is_array()) return;
    for (Json &v : (*report)["views"])
        if (v.is_object()) v["findings"] = viewFindings(v, *report);
    (*report)["findings"] = reportFindings(*report);
}

}  // namespace va
