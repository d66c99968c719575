// visaudit diff: two reports compared (reports/diff.h; docs/diff.md).
#include "reports/diff.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>

#include "reports/level_maps.h"
#include "reports/report.h"
#include "reports/report_read.h"
#include "reports/text_format.h"

namespace va {

using Json = nlohmann::ordered_json;
using namespace rjson;
namespace fs = std::filesystem;

const std::vector<ViewMetric> &diffMetrics() {
    static const std::vector<ViewMetric> m = {
        {"false_cull_pixels", "false-cull pixels", "pixels of triangles a stage culled yet visible (best 0)", false},
        {"genuine_disagreements", "genuine disagreements", "pixels where the ray caster and the z-buffer disagree on the same triangles (best 0)", false},
        {"zfight_pixels", "z-fighting pixels", "pixels that z-fight in the view's own depth format (best 0)", false},
        {"zfight_hotspots", "z-fighting hotspots", "z-fighting hotspots in the view's own depth format (best 0)", false},
        {"overdraw", "overdraw", "depth-test passes / covered pixels (best 1)", true},
        {"depth_complexity", "depth complexity", "fragments / covered pixels (best 1)", true},
        {"wasted_share", "wasted-draw share", "share of the drawn triangles visible nowhere (best 0)", true},
        {"triangles_drawn", "triangles drawn", "triangles the z-buffer drew after every culling stage", false},
        {"total_ms", "ms", "the view's analysis time in milliseconds", true},
    };
    return m;
}

std::string imageDiffName(const std::string &file, const std::string &) {
    const std::string stem = file.size() > 4 && file.compare(file.size() - 4, 4, ".png") == 0 ? file.substr(0, file.size() - 4) : file;
    return stem + ".diff.png";
}

bool readDiffSide(const std::string &given, const char *which, uint64_t maxJsonDepth, DiffSide *out, std::string *err) {
    const bool isDir = fs::is_directory(given);
    const std::string path = isDir ? (fs::path(given) / "report.json").string() : given;
    std::string detail;
    Json j;
    switch (readJsonDocument(path, &j, &detail, maxJsonDepth)) {
    case JsonRead::unreadable:
        *err = std::string(which) + " " + path + ": cannot be read; give the report.json (or the --out folder) of an "
               "analyze or check run";
        return false;
    case JsonRead::invalid: *err = std::string(which) + " " + path + ": not valid JSON (" + detail + ")"; return false;
    case JsonRead::tooDeep: *err = std::string(which) + " " + detail; return false;
    case JsonRead::ok: break;
    }
    if (!j.is_object() || !j.contains("format") || j["format"] != kReportFormat) {
        *err = std::string(which) + " " + path + ": not a " + kReportFormat +
               " report; diff compares two reports written by this visaudit version (re-run analyze)";
        return false;
    }
    for (const char *key : {"scene", "views"})
        if (!j.contains(key) || (std::string(key) == "views" && !j[key].is_array())) {
            *err = std::string(which) + " " + path + ": has no \"" + key + "\"; was it written by visaudit analyze?";
            return false;
        }
    out->label = given;
    out->dir = fs::path(path).parent_path().string();
    if (out->dir.empty()) out->dir = ".";
    out->report = std::move(j);
    return true;
}

namespace {

// A metric's value as the view holds it (null when absent).
Json metricJson(const Json &view, const ViewMetric &m) {
    const Json *x = std::string_view(m.key) == "total_ms" ? get(&view, "total_ms") : get(&view, {"findings", "score", m.key});
    return x && x->is_number() ? *x : Json(nullptr);
}

// {old, new, delta, relative}: delta new - old (null unless both are numbers), relative delta / old
// (null when old is 0 or absent).
Json change(const Json &o, const Json &n) {
    Json c = {{"old", o}, {"new", n}, {"delta", nullptr}, {"relative", nullptr}};
    if (o.is_number() && n.is_number()) {
        const double a = o.get<double>(), b = n.get<double>();
        if (o.is_number_integer() && n.is_number_integer()) c["delta"] = n.get<int64_t>() - o.get<int64_t>();
        else c["delta"] = b - a;
        if (a != 0) c["relative"] = (b - a) / a;
    }
    return c;
}

std::map<std::string, size_t> viewsByName(const Json &views) {
    std::map<std::string, size_t> m;
    for (size_t i = 0; i < views.size(); ++i)
        if (views[i].contains("name") && views[i]["name"].is_string()) m.emplace(views[i]["name"].get<std::string>(), i);
    return m;
}

// The PNGs a view lists: (key, file) pairs, a list (shadows) flattened.
std::vector<std::pair<std::string, std::string>> pngsOf(const Json &view) {
    std::vector<std::pair<std::string, std::string>> out;
    const Json *im = get(&view, "images");
    if (!im || !im->is_object()) return out;
    for (auto it = im->begin(); it != im->end(); ++it) {
        const std::string &k = it.key();
        if (k.size() < 4 || k.compare(k.size() - 4, 4, "_png") != 0) continue;
        if (it.value().is_string()) out.push_back({k, it.value().get<std::string>()});
        if (it.value().is_array())
            for (const Json &f : it.value())
                if (f.is_string()) out.push_back({k, f.get<std::string>()});
    }
    return out;
}

// A name that is a plain file in its folder (no path, no parent), as report folders hold them.
bool plainFile(const std::string &n) { return !n.empty() && n.find('/') == std::string::npos && n != "." && n != ".."; }

// Compares one image of both runs; writes the change image when they differ.
bool diffImage(const std::string &key, const std::string &oldFile, const std::string &newFile, const DiffSide &o,
               const DiffSide &n, const std::string &outDir, Json *out, std::string *err) {
    Json e = {{"kind", key}, {"old", oldFile}, {"new", newFile}};
    const fs::path op = fs::path(o.dir) / oldFile, np = fs::path(n.dir) / newFile;
    if (!plainFile(oldFile) || !plainFile(newFile) || !fs::exists(op) || !fs::exists(np)) {
        e["compared"] = false;
        e["reason"] = "not in both folders (an --images setting, or a file removed)";
        *out = e;
        return true;
    }
    Canvas a, b;
    if (!readCanvas(op.string(), &a, err) || !readCanvas(np.string(), &b, err)) return false;
    e["compared"] = true;
    e["width"] = b.width;
    e["height"] = b.height;
    if (a.width != b.width || a.height != b.height) {
        e["size_differs"] = true;
        e["changed_pixels"] = nullptr;
        *out = e;
        return true;
    }
    e["size_differs"] = false;
    // Changed pixels in magenta over the new image's dimmed grey.
    Canvas d(b.width, b.height, {});
    uint64_t changed = 0;
    for (int y = 0; y < b.height; ++y)
        for (int x = 0; x < b.width; ++x) {
            const Rgb8 p = a.at(x, y), q = b.at(x, y);
            if (!(p == q)) {
                ++changed;
                d.set(x, y, {255, 40, 200});
            } else {
                const uint8_t g = uint8_t(30 + (299 * q.r + 587 * q.g + 114 * q.b) / 1000 * 35 / 100);
                d.set(x, y, {g, g, g});
            }
        }
    e["changed_pixels"] = changed;
    if (changed) {
        const std::string name = imageDiffName(newFile, key);
        if (!d.writePng((fs::path(outDir) / name).string(), err)) return false;
        e["diff"] = name;
    }
    *out = e;
    return true;
}

}  // namespace

bool diffReports(const DiffSide &o, const DiffSide &n, const std::string &outDir, Json *out, std::string *err) {
    const Json &or_ = o.report, &nr = n.report;
    // One scene: the same path (a level's two versions differ in their triangles, not their name).
    if (str(&or_, {"scene", "path"}) != str(&nr, {"scene", "path"})) {
        *err = "OLD and NEW are reports of different scenes: " + o.label + " is of '" + str(&or_, {"scene", "path"}) +
               "', " + n.label + " of '" + str(&nr, {"scene", "path"}) +
               "'; diff compares two runs of one scene (analyze both versions of the level under the same path)";
        return false;
    }
    Json d;
    d["format"] = kDiffFormat;
    d["tool"] = nr.contains("tool") ? nr["tool"] : Json();
    auto side = [](const DiffSide &s) {
        return Json{{"report", s.label},
                    {"scene", {{"path", str(&s.report, {"scene", "path"})},
                               {"triangles", s.report["scene"].contains("triangles") ? s.report["scene"]["triangles"] : Json()},
                               {"source_triangles", s.report["scene"].contains("source_triangles")
                                                        ? s.report["scene"]["source_triangles"] : Json()}}},
                    {"views", s.report["views"].size()}};
    };
    d["old"] = side(o);
    d["new"] = side(n);
    Json metrics = Json::array();
    for (const ViewMetric &m : diffMetrics())
        metrics.push_back({{"key", m.key}, {"title", m.title}, {"meaning", m.meaning}, {"real", m.real}});
    d["metrics"] = metrics;

    // Views matched by name, in NEW's order.
    const Json &ov = or_["views"], &nv = nr["views"];
    const std::map<std::string, size_t> oldByName = viewsByName(ov), newByName = viewsByName(nv);
    Json views = Json::array(), onlyOld = Json::array(), onlyNew = Json::array();
    uint64_t changedViews = 0, changedImages = 0, comparedImages = 0;
    Json rose = Json::object(), fell = Json::object();
    for (const ViewMetric &m : diffMetrics()) rose[m.key] = 0, fell[m.key] = 0;
    for (size_t j = 0; j < nv.size(); ++j) {
        const std::string name = str(&nv[j], {"name"});
        const auto it = oldByName.find(name);
        if (it == oldByName.end()) {
            onlyNew.push_back(name);
            continue;
        }
        const size_t i = it->second;
        Json vj = {{"name", name}, {"old_view", i}, {"new_view", j}};
        if (const Json *r = get(&nv[j], "route")) vj["route"] = *r;
        Json mj = Json::object();
        bool changed = false;
        for (const ViewMetric &m : diffMetrics()) {
            const Json c = change(metricJson(ov[i], m), metricJson(nv[j], m));
            if (c["delta"].is_number() && c["delta"].get<double>() != 0 && std::string_view(m.key) != "total_ms") {
                changed = true;
                Json &bucket = c["delta"].get<double>() > 0 ? rose : fell;
                bucket[m.key] = bucket[m.key].get<uint64_t>() + 1;
            }
            mj[m.key] = c;
        }
        vj["metrics"] = mj;
        vj["changed"] = changed;
        changedViews += changed;
        // Images: each PNG both runs list under the same key (in NEW's order; a list pairs by position).
        Json images = Json::array();
        const auto op = pngsOf(ov[i]), np = pngsOf(nv[j]);
        std::map<std::string, std::vector<std::string>> oldFiles;
        for (const auto &[k, f] : op) oldFiles[k].push_back(f);
        std::map<std::string, size_t> used;
        for (const auto &[k, f] : np) {
            auto of = oldFiles.find(k);
            const size_t u = used[k]++;
            if (of == oldFiles.end() || u >= of->second.size()) continue;
            Json e;
            if (!diffImage(k, of->second[u], f, o, n, outDir, &e, err)) return false;
            comparedImages += isTrue(get(&e, "compared"));
            changedImages += e.contains("diff") || isTrue(get(&e, "size_differs"));
            images.push_back(e);
        }
        vj["images"] = images;
        views.push_back(vj);
    }
    for (const auto &[name, i] : oldByName)
        if (!newByName.count(name)) onlyOld.push_back(name);
    // only_in_old in OLD's order.
    Json onlyOldOrdered = Json::array();
    for (const Json &v : ov)
        if (std::find(onlyOld.begin(), onlyOld.end(), v["name"]) != onlyOld.end()) onlyOldOrdered.push_back(v["name"]);
    d["views"] = views;
    d["only_in_old"] = onlyOldOrdered;
    d["only_in_new"] = onlyNew;

    // Routes: frames matched by number.
    Json routes = Json::array();
    if (const Json *nrs = get(&nr, "routes"); nrs && nrs->is_array())
        for (const Json &rt : *nrs) {
            const std::string name = str(&rt, {"name"});
            const Json *ors = get(&or_, "routes");
            const Json *old = nullptr;
            if (ors && ors->is_array())
                for (const Json &x : *ors)
                    if (str(&x, {"name"}) == name) old = &x;
            if (!old) continue;
            std::map<int64_t, size_t> oldFrame;  // frame -> OLD's view
            const Json *os = get(old, "series");
            for (size_t k = 0; os && get(os, "frame") && k < (*os)["frame"].size(); ++k)
                oldFrame[(*os)["frame"][k].get<int64_t>()] = (*os)["view"][k].get<size_t>();
            Json frames = Json::array();
            const Json *ns = get(&rt, "series");
            size_t newOnly = 0;
            for (size_t k = 0; ns && get(ns, "frame") && k < (*ns)["frame"].size(); ++k) {
                const int64_t f = (*ns)["frame"][k].get<int64_t>();
                const size_t nvi = (*ns)["view"][k].get<size_t>();
                auto it = oldFrame.find(f);
                if (it == oldFrame.end()) {
                    ++newOnly;
                    continue;
                }
                Json fj = {{"frame", f}, {"time", (*ns)["time"][k]}, {"old_view", it->second}, {"new_view", nvi}};
                Json mj = Json::object();
                for (const ViewMetric &m : routeMetrics())
                    mj[m.key] = change(it->second < ov.size() ? metricJson(ov[it->second], m) : Json(),
                                       nvi < nv.size() ? metricJson(nv[nvi], m) : Json());
                fj["metrics"] = mj;
                frames.push_back(fj);
                oldFrame.erase(it);
            }
            routes.push_back({{"name", name}, {"frames", frames}, {"only_in_old", oldFrame.size()}, {"only_in_new", newOnly}});
        }
    if (!routes.empty()) d["routes"] = routes;

    // The level maps of the change: NEW's positions, each coloured by how much its worst view's value
    // moved (NEW's value minus the highest of OLD's views of the same names).
    const Json *nlm = get(&nr, "level_maps");
    if (nlm && get(nlm, "positions") && get(nlm, "maps")) {
        Json lm = {{"floor", (*nlm)["floor"]}, {"positions", (*nlm)["positions"]}};
        Json maps = Json::array();
        for (size_t mi = 0; mi < levelMapMetrics().size(); ++mi) {
            const ViewMetric &m = levelMapMetrics()[mi];
            Json values = Json::array(), viewOf = Json::array();
            std::vector<std::pair<double, size_t>> ranked;
            double lo = 0, hi = 0;
            for (size_t k = 0; k < lm["positions"].size(); ++k) {
                std::optional<double> nvMax, ovMax;
                std::optional<size_t> at;
                for (const Json &vi : lm["positions"][k]["views"]) {
                    const size_t j = vi.get<size_t>();
                    if (j >= nv.size()) continue;
                    if (const auto v = viewMetric(nv[j], m.key); v && (!nvMax || *v > *nvMax)) nvMax = v, at = j;
                    if (auto it = oldByName.find(str(&nv[j], {"name"})); it != oldByName.end())
                        if (const auto v = viewMetric(ov[it->second], m.key); v && (!ovMax || *v > *ovMax)) ovMax = v;
                }
                if (nvMax && ovMax) {
                    const double delta = *nvMax - *ovMax;
                    values.push_back(delta);
                    viewOf.push_back(*at);
                    lo = std::min(lo, delta), hi = std::max(hi, delta);
                    if (delta > 0) ranked.push_back({delta, k});
                } else {
                    values.push_back(nullptr);
                    viewOf.push_back(nullptr);
                }
            }
            std::stable_sort(ranked.begin(), ranked.end(), [](const auto &a, const auto &b) { return a.first > b.first; });
            Json worst = Json::array();
            for (size_t r = 0; r < std::min(kLevelMapWorst, ranked.size()); ++r)
                worst.push_back({{"rank", r + 1}, {"position", ranked[r].second}, {"view", viewOf[ranked[r].second]},
                                 {"value", ranked[r].first}});
            maps.push_back({{"metric", m.key}, {"title", m.title}, {"meaning", std::string("change (new - old) of: ") + m.meaning},
                            {"min", lo}, {"max", hi}, {"values", values}, {"view", viewOf}, {"worst", worst}});
        }
        lm["maps"] = maps;
        const fs::path floor = fs::path(n.dir) / kFloorPlanImage;
        if (fs::exists(floor)) {
            Canvas fc;
            if (!readCanvas(floor.string(), &fc, err)) return false;
            for (size_t mi = 0; mi < maps.size(); ++mi) {
                const std::string name = levelMapImageName(levelMapMetrics()[mi].key, true);
                if (!levelMapImage(lm, mi, fc, nv, true).writePng((fs::path(outDir) / name).string(), err)) return false;
                lm["maps"][mi]["image"] = name;
            }
        }
        d["level_maps"] = lm;
    }
    d["totals"] = {{"views_compared", views.size()}, {"views_changed", changedViews}, {"images_compared", comparedImages},
                   {"images_changed", changedImages}, {"views_rose", rose}, {"views_fell", fell}};
    *out = std::move(d);
    return true;
}

std::string diffSummary(const Json &d) {
    std::string o;
    const Json *t = get(&d, "totals");
    o += "diff " + str(&d, {"old", "report"}) + " -> " + str(&d, {"new", "report"}) + ": " +
         fmtCount(numOr(t, {"views_compared"}, 0)) + " views compared, " + fmtCount(numOr(t, {"views_changed"}, 0)) +
         " changed; " + fmtCount(numOr(t, {"images_changed"}, 0)) + " of " + fmtCount(numOr(t, {"images_compared"}, 0)) +
         " images differ\n";
    for (const ViewMetric &m : diffMetrics()) {
        if (std::string_view(m.key) == "total_ms") continue;
        const double r = numOr(t, {"views_rose", m.key}, 0), f = numOr(t, {"views_fell", m.key}, 0);
        if (r || f) o += "  " + std::string(m.title) + ": rose in " + plural(r, "view", "views") + ", fell in " + fmtCount(f) + "\n";
    }
    const Json *oo = get(&d, "only_in_old"), *on = get(&d, "only_in_new");
    if (oo && !oo->empty()) o += "  only in OLD: " + plural(double(oo->size()), "view", "views") + "\n";
    if (on && !on->empty()) o += "  only in NEW: " + plural(double(on->size()), "view", "views") + "\n";
    return o;
}

}  // namespace va
