#include "reports/merge.h"

#include "reports/findings.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "reports/report.h"
#include "reports/level_maps.h"
#include "reports/routes.h"

namespace va {

using Json = nlohmann::ordered_json;
namespace fs = std::filesystem;

bool parseShard(const std::string &text, int *index, int *count, std::string *err) {
    const size_t slash = text.find('/');
    auto whole = [](const std::string &s, long *v) {
        if (s.empty() || s.size() > 6 || s.find_first_not_of("0123456789") != std::string::npos) return false;
        *v = std::stol(s);
        return true;
    };
    long k = 0, n = 0;
    if (slash == std::string::npos || !whole(text.substr(0, slash), &k) || !whole(text.substr(slash + 1), &n) ||
        n < 1 || n > 100000 || k < 1 || k > n) {
        *err = "--shard " + text + ": expected K/N with 1 <= K <= N <= 100000, e.g. --shard 2/4 (shard 2 of 4)";
        return false;
    }
    *index = int(k);
    *count = int(n);
    return true;
}

namespace {

bool readReport(const std::string &dir, Json *out, std::string *err, uint64_t maxJsonDepth) {
    const std::string path = (fs::path(dir) / "report.json").string();
    std::string detail;
    switch (readJsonDocument(path, out, &detail, maxJsonDepth)) {
    case JsonRead::unreadable:
        *err = path + ": cannot be read; give the --out folder of an `analyze --shard K/N` run";
        return false;
    case JsonRead::invalid: *err = path + ": not valid JSON (" + detail + ")"; return false;
    case JsonRead::tooDeep: *err = detail; return false;
    case JsonRead::ok: break;
    }
    if (!out->is_object() || !out->contains("format") || (*out)["format"] != kReportFormat) {
        *err = path + ": not a " + std::string(kReportFormat) + " report; merge joins reports of this visaudit version";
        return false;
    }
    for (const char *key : {"tool", "scene", "shard", "views"})
        if (!out->contains(key)) {
            *err = path + ": has no \"" + key + "\"; was it written by visaudit analyze?";
            return false;
        }
    return true;
}

}  // namespace

bool mergeReports(const std::vector<std::string> &dirs, const std::string &outDir, Json *merged, std::string *err,
                  uint64_t maxJsonDepth) {
    if (dirs.empty()) {
        *err = "merge needs the folders of the shard reports, e.g. visaudit merge shard1 shard2 --out merged";
        return false;
    }
    std::vector<Json> reports(dirs.size());
    for (size_t i = 0; i < dirs.size(); ++i)
        if (!readReport(dirs[i], &reports[i], err, maxJsonDepth)) return false;

    // One analysis: same tool version, same scene, same shard count and view count.
    const Json &first = reports[0];
    const int count = first["shard"]["count"];
    const size_t total = first["shard"]["views_total"];
    std::map<int, size_t> byIndex;  // shard K -> folder
    for (size_t i = 0; i < reports.size(); ++i) {
        const Json &r = reports[i];
        auto mismatch = [&](const char *what) {
            *err = dirs[i] + ": " + what + " differs from " + dirs[0] + "'s; merge only shards of one analysis";
            return false;
        };
        if (r["tool"] != first["tool"]) return mismatch("the visaudit version");
        if (r["scene"] != first["scene"]) return mismatch("the scene");
        if (r["shard"]["count"] != count) return mismatch("the shard count N");
        if (r["shard"]["views_total"] != total) return mismatch("the number of views");
        const int k = r["shard"]["index"];
        if (byIndex.count(k)) {
            *err = "shards overlap: " + dirs[byIndex[k]] + " and " + dirs[i] + " are both shard " + std::to_string(k) +
                   "/" + std::to_string(count) + "; give each shard once";
            return false;
        }
        byIndex[k] = i;
    }
    for (int k = 1; k <= count; ++k)
        if (!byIndex.count(k)) {
            *err = "shard " + std::to_string(k) + "/" + std::to_string(count) +
                   " is missing; run analyze --shard " + std::to_string(k) + "/" + std::to_string(count) +
                   " and give its folder too";
            return false;
        }

    // Every view exactly once, each in the shard that owns its index.
    std::vector<const Json *> views(total, nullptr);
    std::vector<size_t> owner(total, 0);
    for (size_t i = 0; i < reports.size(); ++i)
        for (const Json &v : reports[i]["views"]) {
            const size_t idx = v["index"];
            const int k = reports[i]["shard"]["index"];
            if (idx >= total || int(idx % size_t(count)) != k - 1 || views[idx]) {
                *err = dirs[i] + "/report.json: view '" + v["name"].get<std::string>() + "' (index " +
                       std::to_string(idx) + ") does not belong to shard " + std::to_string(k) + "/" +
                       std::to_string(count) + " or appears twice";
                return false;
            }
            views[idx] = &v;
            owner[idx] = i;
        }
    for (size_t idx = 0; idx < total; ++idx)
        if (!views[idx]) {
            *err = "view " + std::to_string(idx) + " is in no shard report; re-run its shard";
            return false;
        }

    // Images: copy every file a view lists.
    for (size_t idx = 0; idx < total; ++idx)
        for (const auto &[key, value] : (*views[idx])["images"].items()) {
            // A name, or a list of names (one shadow image per light).
            std::vector<std::string> names;
            if (value.is_string()) names.push_back(value);
            if (value.is_array())
                for (const Json &n : value)
                    if (n.is_string()) names.push_back(n);
            for (const std::string &name : names) {
                const fs::path src = fs::path(dirs[owner[idx]]) / name;
                std::error_code ec;
                fs::copy_file(src, fs::path(outDir) / name, fs::copy_options::overwrite_existing, ec);
                if (ec) {
                    *err = src.string() + ": cannot copy (" + ec.message() + ")";
                    return false;
                }
            }
        }

    Json m;
    for (const auto &[key, value] : first.items()) {
        if (key == "views" || key == "totals" || key == "findings" || key == "depth_curves" || key == "routes" ||
            key == "level_maps")
            continue;
        m[key] = value;
    }
    m["shard"] = {{"index", 1}, {"count", 1}, {"views_total", total}};
    // "output": what every shard spent writing its files, summed (the copy above is shard 1's).
    if (m.contains("output") && m["output"].is_object())
        for (auto &[key, value] : m["output"].items()) {
            double sum = 0;
            bool finite = true;
            for (const Json &r : reports) {
                const Json *x = r.contains("output") && r["output"].contains(key) ? &r["output"][key] : nullptr;
                if (x && x->is_number()) sum += x->get<double>();
                else finite = false;
            }
            value = finite ? Json(sum) : Json(nullptr);
        }
    // The depth curves: each view's set from its shard, renumbered in the order the merged views
    // first use them (what a single run numbers).
    Json curves = Json::array(), list = Json::array();
    std::map<std::string, size_t> curveIndex;  // a set's JSON text -> its merged index
    for (size_t idx = 0; idx < total; ++idx) {
        Json v = *views[idx];
        const Json &shardCurves = reports[owner[idx]]["depth_curves"];
        if (v.contains("depth_curve") && v["depth_curve"].is_number_unsigned() && shardCurves.is_array() &&
            v["depth_curve"].get<size_t>() < shardCurves.size()) {
            const Json &c = shardCurves[v["depth_curve"].get<size_t>()];
            auto [it, added] = curveIndex.emplace(c.dump(), curves.size());
            if (added) curves.push_back(c);
            v["depth_curve"] = it->second;
        } else if (v.contains("depth_curve")) {
            v["depth_curve"] = nullptr;  // an index into no set of its shard: no plot, never another set's
        }
        list.push_back(std::move(v));
    }
    if (first.contains("depth_curves")) m["depth_curves"] = curves;
    m["views"] = list;
    m["totals"] = reportTotals(m["views"]);
    addFindings(&m);
    // Routes: one definition in every shard; the series come from the merged views, and so do the
    // plots when the shards wrote them.
    if (first.contains("routes") && first["routes"].is_array()) {
        auto definitions = [](const Json &routes) {
            Json d = Json::array();
            for (const Json &r : routes) {
                Json x = r;
                for (const char *k : {"series", "worst", "image"}) x.erase(k);
                d.push_back(x);
            }
            return d;
        };
        const Json defs = definitions(first["routes"]);
        for (size_t i = 0; i < reports.size(); ++i)
            if (!reports[i].contains("routes") || definitions(reports[i]["routes"]) != defs) {
                *err = dirs[i] + ": the routes differ from " + dirs[0] + "'s; merge only shards of one analysis";
                return false;
            }
        m["routes"] = defs;
        addRouteSeries(&m);
        bool plotted = false;
        for (const Json &r : first["routes"]) plotted |= r.contains("image");
        if (plotted && !writeRoutePlots(&m, outDir, err)) return false;
    }
    // Level maps: one floor plan in every shard (the same render); positions and values from the
    // merged views, the images redrawn over shard 1's floor plan when the shards wrote them.
    if (first.contains("level_maps") && first["level_maps"].is_object()) {
        auto floorOf = [](const Json &r) {
            Json f = r.contains("level_maps") && r["level_maps"].contains("floor") ? r["level_maps"]["floor"] : Json();
            if (f.is_object()) f.erase("ms");
            return f;
        };
        for (size_t i = 0; i < reports.size(); ++i)
            if (floorOf(reports[i]) != floorOf(first)) {
                *err = dirs[i] + ": the level map's floor plan differs from " + dirs[0] +
                       "'s; merge only shards of one analysis";
                return false;
            }
        m["level_maps"] = {{"floor", first["level_maps"]["floor"]}};
        addLevelMaps(&m);
        const fs::path floor = fs::path(dirs[0]) / kFloorPlanImage;
        if (fs::exists(floor)) {
            std::error_code ec;
            fs::copy_file(floor, fs::path(outDir) / kFloorPlanImage, fs::copy_options::overwrite_existing, ec);
            if (ec) {
                *err = floor.string() + ": cannot copy (" + ec.message() + ")";
                return false;
            }
            if (!writeLevelMapImages(&m, outDir, err)) return false;
        }
    }
    *merged = std::move(m);
    return true;
}

}  // namespace va
