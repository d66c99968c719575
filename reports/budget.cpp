#include "reports/budget.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "common/json_util.h"
#include "render/depth_format.h"

namespace va {

using OJson = nlohmann::ordered_json;

const std::vector<BudgetMetric> &budgetMetrics() {
    static const std::vector<BudgetMetric> m = {
        {"zbuffer_triangles", "triangles the z-buffer drew (after every culling stage)", false, true},
        {"overdraw", "depth-test passes / covered pixels", false, true},
        {"depth_complexity", "fragments / covered pixels", false, true},
        {"zfight_pixels", "pixels that z-fight in the view's depth format", false, true},
        {"zfight_hotspots", "z-fighting hotspots in the view's depth format", false, true},
        {"false_culls", "triangles culled by a stage yet visible in the reference (default limit 0)", false, true},
        {"wasted_draw_share", "share of drawn triangles visible nowhere (0..1)", false, true},
        {"min_depth_format", "the cheapest depth format the view must not z-fight in", true, false},
        // Map-wide, from `visaudit pvs-audit` (docs/pvs-audit.md): check runs the audit when one is named.
        {"pvs_misses", "cluster pairs a player's eye sees although the map's PVS hides them", false, true, true},
        {"pvs_slack_share", "share of PVS-visible cluster pairs no eye point sees (0..1)", false, true, true},
    };
    return m;
}

namespace {

std::vector<std::string> metricNames(bool numericOnly) {
    std::vector<std::string> v;
    for (const BudgetMetric &m : budgetMetrics())
        if (!numericOnly || !m.isFormat) v.push_back(m.name);
    return v;
}

const BudgetMetric *findMetric(const std::string &name) {
    for (const BudgetMetric &m : budgetMetrics())
        if (name == m.name) return &m;
    return nullptr;
}

std::string fmt(double v) {
    char b[64];
    if (v == std::floor(v) && std::fabs(v) < 1e15)
        std::snprintf(b, sizeof b, "%.0f", v);
    else
        std::snprintf(b, sizeof b, "%.4g", v);
    return b;
}

// Validates one "metric: limit" object at path p (perView: a view's own limits, where map-wide
// metrics have no place).
bool readLimits(const json::Doc &doc, const json::Path &p, const json::Json &obj,
                std::map<std::string, nlohmann::json> *out, std::string *err, bool perView = false) {
    if (!obj.is_object()) {
        *err = json::where(doc, p) + ": " + json::pathString(p) + ": expected an object of limits, got " +
               json::typeName(obj);
        return false;
    }
    for (const auto &[key, value] : obj.items()) {
        const BudgetMetric *m = findMetric(key);
        if (!m) {
            const std::string near = json::closest(key, metricNames(false));
            *err = json::where(doc, p / key, true) + ": " + json::pathString(p) + ": unknown metric '" + key + "'" +
                   (near.empty() ? "" : ", did you mean '" + near + "'?") +
                   " (known: " + json::joinList(metricNames(false)) + ")";
            return false;
        }
        if (perView && m->mapWide) {
            *err = json::where(doc, p / key, true) + ": " + json::pathString(p) + ": '" + key +
                   "' is one number for the whole map (the PVS audit), not per view; put it under \"limits\"";
            return false;
        }
        if (m->isFormat) {
            DepthFormatSpec f;
            std::string e;
            if (!value.is_string() || !parseDepthFormat(value.get<std::string>(), &f, &e)) {
                *err = json::where(doc, p / key) + ": " + json::pathString(p / key) + ": " +
                       (value.is_string() ? e : "expected a depth format name, got " + json::typeName(value));
                return false;
            }
        } else if (!value.is_number() || !(value.get<double>() >= 0)) {
            *err = json::where(doc, p / key) + ": " + json::pathString(p / key) +
                   ": expected a number >= 0, got " + json::typeName(value);
            return false;
        }
        (*out)[key] = value;
    }
    return true;
}

// The value of a numeric metric in one view of a report; nullopt when the report has no such data.
std::optional<double> metricValue(const std::string &metric, const OJson &view) {
    auto at = [&](std::initializer_list<const char *> path) -> const OJson * {
        const OJson *x = &view;
        for (const char *k : path) {
            if (!x->is_object() || !x->contains(k)) return nullptr;
            x = &(*x)[k];
        }
        return x;
    };
    if (metric == "zbuffer_triangles") {
        for (const OJson &s : view["stages"])
            if (s["name"] == "zbuffer" && s["ran"] == true) return s["triangles_out"].get<double>();
        return std::nullopt;
    }
    const OJson *x = nullptr;
    if (metric == "overdraw") x = at({"zbuffer", "overdraw"});
    if (metric == "depth_complexity") x = at({"zbuffer", "depth_complexity"});
    if (metric == "false_culls") x = at({"audit", "false_culls", "triangles"});
    if (metric == "wasted_draw_share") x = at({"audit", "wasted_draws", "share"});
    if (metric == "zfight_pixels" || metric == "zfight_hotspots") {
        const OJson *formats = at({"depth", "formats"});
        const std::string f = view["depth_format"];
        if (formats && formats->contains(f))
            x = &(*formats)[f][metric == "zfight_pixels" ? "fighting_pixels" : "hotspots"];
    }
    if (!x) return std::nullopt;
    if (x->is_null()) return 0.0;  // JSON null for a non-finite ratio (nothing covered): no load
    return x->get<double>();
}

const char *sectionFor(const std::string &metric) {
    if (metric == "false_culls" || metric == "wasted_draw_share") return "the reference-visibility audit";
    if (metric == "zfight_pixels" || metric == "zfight_hotspots" || metric == "min_depth_format")
        return "the z-fighting analysis";
    return "the z-buffer stage";
}

}  // namespace

bool loadBudget(const std::string &path, const std::vector<std::string> &viewNames, Budget *out, std::string *err,
                uint64_t maxJsonDepth) {
    json::Doc doc;
    if (!json::parseFile(path, &doc, err, maxJsonDepth)) return false;
    const json::Json &root = doc.root;
    const json::Path top;
    if (!root.is_object()) {
        *err = path + ": expected a JSON object {\"format\": \"" + kBudgetFormat + "\", \"limits\": {...}}";
        return false;
    }
    if (!root.contains("format") || root["format"] != kBudgetFormat) {
        *err = json::where(doc, top / "format") + ": \"format\" must be \"" + kBudgetFormat + "\"";
        return false;
    }
    Budget b;
    b.file = path;
    for (const auto &[key, value] : root.items()) {
        if (key == "format") continue;
        if (key == "limits") {
            if (!readLimits(doc, top / key, value, &b.limits, err)) return false;
        } else if (key == "views") {
            if (!value.is_object()) {
                *err = json::where(doc, top / key) + ": views: expected an object {\"VIEW\": {limits}}";
                return false;
            }
            for (const auto &[view, limits] : value.items()) {
                if (std::find(viewNames.begin(), viewNames.end(), view) == viewNames.end()) {
                    const std::string near = json::closest(view, viewNames);
                    *err = json::where(doc, top / "views" / view, true) + ": views: no view named '" + view + "'" +
                           (near.empty() ? "" : ", did you mean '" + near + "'?") +
                           " (views: " + json::joinList(viewNames) + ")";
                    return false;
                }
                if (!readLimits(doc, top / "views" / view, limits, &b.views[view], err, true)) return false;
            }
        } else if (key == "regressions") {
            if (!value.is_object()) {
                *err = json::where(doc, top / key) + ": regressions: expected an object {\"metric\": allowed rise}";
                return false;
            }
            for (const auto &[metric, rise] : value.items()) {
                const BudgetMetric *m = findMetric(metric);
                if (!m || m->isFormat) {
                    const std::string near = json::closest(metric, metricNames(true));
                    *err = json::where(doc, top / "regressions" / metric, true) + ": regressions: unknown metric '" +
                           metric + "'" + (near.empty() ? "" : ", did you mean '" + near + "'?") +
                           " (known: " + json::joinList(metricNames(true)) + ")";
                    return false;
                }
                if (!rise.is_number() || !(rise.get<double>() >= 0)) {
                    *err = json::where(doc, top / "regressions" / metric) + ": regressions." + metric +
                           ": expected the allowed relative rise as a number >= 0 (0.1 = 10%)";
                    return false;
                }
                b.regressions[metric] = rise.get<double>();
            }
        } else {
            const std::string near = json::closest(key, {"format", "limits", "views", "regressions"});
            *err = json::where(doc, top / key, true) + ": unknown key '" + key + "'" +
                   (near.empty() ? "" : ", did you mean '" + near + "'?") +
                   " (known: format, limits, views, regressions)";
            return false;
        }
    }
    *out = std::move(b);
    return true;
}

std::vector<DepthFormatSpec> budgetDepthFormats(const Budget &budget) {
    std::vector<DepthFormatSpec> out;
    auto add = [&](const DepthFormatSpec &f) {
        if (std::find(out.begin(), out.end(), f) == out.end()) out.push_back(f);
    };
    auto scan = [&](const std::map<std::string, nlohmann::json> &limits) {
        for (const auto &[metric, value] : limits) {
            const BudgetMetric *m = findMetric(metric);
            DepthFormatSpec f;
            if (!m || !m->isFormat || !value.is_string() || !parseDepthFormat(value.get<std::string>(), &f, nullptr))
                continue;
            add(f);
            if (f.format == DepthFormat::depth24plus) add(DepthFormat::depth32float);
        }
    };
    scan(budget.limits);
    for (const auto &[view, limits] : budget.views) scan(limits);
    return out;
}

bool evaluateBudget(const Budget &budget, const OJson &report, const OJson *baseline, BudgetResult *out,
                    std::string *err, const BudgetEvaluation &how) {
    BudgetResult r;
    if (baseline) {
        if (!baseline->contains("format") || (*baseline)["format"] != report["format"]) {
            *err = "the baseline is not a " + report["format"].get<std::string>() +
                   " report; make a new baseline with this visaudit version";
            return false;
        }
        if ((*baseline)["scene"]["path"] != report["scene"]["path"] ||
            (how.sameTriangles && (*baseline)["scene"]["source_triangles"] != report["scene"]["source_triangles"])) {
            *err = "the baseline is a report of another scene (" + (*baseline)["scene"]["path"].get<std::string>() +
                   ", " + std::to_string((*baseline)["scene"]["source_triangles"].get<uint64_t>()) +
                   " triangles); give the baseline of " + report["scene"]["path"].get<std::string>();
            return false;
        }
    }
    std::map<std::string, std::string> frames;  // view name -> its frame of a route
    for (const OJson &view : report["views"]) {
        const std::string name = view["name"];
        // A route's frame (docs/routes.md): its checks say which frame of which route, and when.
        std::string frame;
        if (view.contains("route") && view["route"].is_object()) {
            const OJson &rt = view["route"];
            frame = "frame " + (rt["frame"].is_number() ? fmt(rt["frame"].get<double>()) : std::string("?")) +
                    " of route '" + (rt["name"].is_string() ? rt["name"].get<std::string>() : std::string()) + "' at " +
                    (rt["time"].is_number() ? fmt(rt["time"].get<double>()) : std::string("?")) + " s";
        }
        if (!frame.empty()) frames[name] = frame;
        // Limits: the scene-wide ones, overridden per view; false_culls defaults to 0 where the
        // report has the audit.
        std::map<std::string, nlohmann::json> limits;
        if (how.limits) {
            limits = budget.limits;
            if (auto it = budget.views.find(name); it != budget.views.end())
                for (const auto &[k, v] : it->second) limits[k] = v;
            if (!limits.count("false_culls") && metricValue("false_culls", view)) limits["false_culls"] = 0;
        }

        for (const BudgetMetric &m : budgetMetrics()) {
            auto lim = limits.find(m.name);
            if (lim == limits.end() || m.mapWide) continue;
            BudgetCheck c;
            c.view = name;
            c.metric = m.name;
            c.kind = "limit";
            if (m.isFormat) {
                // The view must fight nowhere in the named format (read under its canonical name:
                // "log24:C=1" is log24). depth24plus must hold on every implementation WebGPU allows:
                // its 24-bit one (the depth24plus row) and depth32float.
                DepthFormatSpec spec;
                parseDepthFormat(lim->second.get<std::string>(), &spec, nullptr);  // validated by loadBudget
                const std::string f = depthFormatName(spec);
                std::vector<std::string> rows = {f};
                if (spec.format == DepthFormat::depth24plus) rows.push_back("depth32float");
                const OJson *formats = view.contains("depth") ? &view["depth"]["formats"] : nullptr;
                double px = 0;
                for (const std::string &row : rows) {
                    if (!formats || !formats->contains(row)) {
                        *err = budget.file + ": min_depth_format needs " + std::string(sectionFor(m.name)) +
                               " with " + row + ", which the report of view '" + name +
                               "' does not have (run check with this budget, or analyze with --zfight-formats " +
                               row + ")";
                        return false;
                    }
                    px = std::max(px, (*formats)[row]["fighting_pixels"].get<double>());
                }
                const std::string in = rows.size() > 1 ? f + " (24-bit and depth32float)" : f;
                c.value = fmt(px) + " fighting pixels in " + in;
                c.allowed = "0 in " + f;
                c.pass = px == 0;
                if (!c.pass)
                    c.message = "view '" + name + "' z-fights in " + in + " at " + fmt(px) + " pixels; it needs " +
                                (view["depth"]["recommended_format"].is_string()
                                     ? "at least " + view["depth"]["recommended_format"].get<std::string>()
                                     : std::string("a depth bias (it fights in every format)"));
            } else {
                const std::optional<double> v = metricValue(m.name, view);
                if (!v) {
                    *err = budget.file + ": '" + m.name + "' needs " + sectionFor(m.name) +
                           ", which the report of view '" + name + "' does not have (did that stage run?)";
                    return false;
                }
                const double limit = lim->second.get<double>();
                c.value = fmt(*v);
                c.allowed = "<= " + fmt(limit);
                c.pass = *v <= limit;
                if (!c.pass)
                    c.message = std::string(m.name) + " in view '" + name + "' is " + fmt(*v) + ", allowed " +
                                fmt(limit) + " (" + m.meaning + ")";
            }
            r.checks.push_back(c);
        }
        // Regressions against the baseline's view of the same name.
        if (!baseline) continue;
        const OJson *old = nullptr;
        for (const OJson &bv : (*baseline)["views"])
            if (bv["name"] == name) old = &bv;
        for (const auto &[metric, rise] : budget.regressions) {
            if (findMetric(metric)->mapWide) continue;
            BudgetCheck c;
            c.view = name;
            c.metric = metric;
            c.kind = "regression";
            c.allowed = "+" + fmt(rise * 100) + "%";
            const std::optional<double> now = metricValue(metric, view);
            const std::optional<double> before = old ? metricValue(metric, *old) : std::nullopt;
            if (!now) {
                *err = budget.file + ": regressions." + metric + " needs " + sectionFor(metric) +
                       ", which the report of view '" + name + "' does not have";
                return false;
            }
            if (!before) {
                c.value = fmt(*now) + " (no baseline)";
                c.pass = true;
            } else {
                // Relative rise; from a baseline of 0, any rise is infinite.
                const double rel = *before > 0 ? (*now - *before) / *before : (*now > 0 ? INFINITY : 0);
                c.value = fmt(*before) + " -> " + fmt(*now);
                c.pass = rel <= rise;
                if (!c.pass) {
                    char pct[32];
                    std::snprintf(pct, sizeof pct, "%.0f%%", rel * 100);
                    c.message = metric + " in view '" + name + "' rose " +
                                (std::isfinite(rel) ? std::string(pct) : "from 0 to " + fmt(*now)) + ", allowed " +
                                fmt(rise * 100) + "%";
                }
            }
            r.checks.push_back(c);
        }
    }
    for (BudgetCheck &c : r.checks)
        if (auto it = frames.find(c.view); it != frames.end()) {
            c.frame = it->second;
            if (!c.message.empty()) c.message += " (" + c.frame + ")";
        }
    for (const BudgetCheck &c : r.checks) r.failed += !c.pass;
    *out = std::move(r);
    return true;
}

bool budgetNeedsPvsAudit(const Budget &budget) {
    for (const BudgetMetric &m : budgetMetrics())
        if (m.mapWide && (budget.limits.count(m.name) || budget.regressions.count(m.name))) return true;
    return false;
}

namespace {
// A map-wide metric's value in a pvs-audit.json: totals.misses or totals.slack_share.
std::optional<double> pvsMetricValue(const std::string &metric, const OJson &audit) {
    const char *key = metric == "pvs_misses" ? "misses" : "slack_share";
    if (!audit.is_object() || !audit.contains("totals") || !audit["totals"].is_object() ||
        !audit["totals"].contains(key) || !audit["totals"][key].is_number())
        return std::nullopt;
    return audit["totals"][key].get<double>();
}
}  // namespace

bool evaluatePvsBudget(const Budget &budget, const OJson &audit, const OJson *baseline, BudgetResult *out,
                       std::string *err) {
    for (const BudgetMetric &m : budgetMetrics()) {
        if (!m.mapWide) continue;
        const std::optional<double> v = pvsMetricValue(m.name, audit);
        const bool limited = budget.limits.count(m.name) > 0, regressed = budget.regressions.count(m.name) > 0;
        if ((limited || regressed) && !v) {
            *err = budget.file + ": '" + m.name + "' needs the PVS audit's totals, which pvs-audit.json does not have";
            return false;
        }
        if (limited) {
            BudgetCheck c;
            c.view = "(map)";
            c.metric = m.name;
            c.kind = "limit";
            const double limit = budget.limits.at(m.name).get<double>();
            c.value = fmt(*v);
            c.allowed = "<= " + fmt(limit);
            c.pass = *v <= limit;
            if (!c.pass)
                c.message = std::string(m.name) + " of the map is " + fmt(*v) + ", allowed " + fmt(limit) + " (" +
                            m.meaning + "; pvs-audit.html lists the evidence)";
            out->checks.push_back(c);
        }
        if (regressed) {
            const double rise = budget.regressions.at(m.name);
            BudgetCheck c;
            c.view = "(map)";
            c.metric = m.name;
            c.kind = "regression";
            c.allowed = "+" + fmt(rise * 100) + "%";
            const std::optional<double> before = baseline ? pvsMetricValue(m.name, *baseline) : std::nullopt;
            if (!before) {
                c.value = fmt(*v) + " (no baseline)";
            } else {
                const double rel = *before > 0 ? (*v - *before) / *before : (*v > 0 ? INFINITY : 0);
                c.value = fmt(*before) + " -> " + fmt(*v);
                c.pass = rel <= rise;
                if (!c.pass) {
                    char pct[32];
                    std::snprintf(pct, sizeof pct, "%.0f%%", rel * 100);
                    c.message = std::string(m.name) + " of the map rose " +
                                (std::isfinite(rel) ? std::string(pct) : "from 0 to " + fmt(*v)) + ", allowed " +
                                fmt(rise * 100) + "%";
                }
            }
            out->checks.push_back(c);
        }
    }
    out->failed = 0;
    for (const BudgetCheck &c : out->checks) out->failed += !c.pass;
    return true;
}

std::string budgetTable(const BudgetResult &r) {
    std::ostringstream s;
    char line[512];
    std::snprintf(line, sizeof line, "%-6s %-20s %-20s %-11s %-24s %s\n", "status", "view", "metric", "kind", "value",
                  "allowed");
    s << line;
    for (int pass = 0; pass < 2; ++pass)
        for (const BudgetCheck &c : r.checks) {
            if (c.pass != bool(pass)) continue;
            std::snprintf(line, sizeof line, "%-6s %-20s %-20s %-11s %-24s %s\n", c.pass ? "ok" : "FAIL",
                          c.view.c_str(), c.metric.c_str(), c.kind.c_str(), c.value.c_str(), c.allowed.c_str());
            s << line;
        }
    for (const BudgetCheck &c : r.checks)
        if (!c.pass) s << "FAIL: " << c.message << "\n";
    s << r.checks.size() - r.failed << " passed, " << r.failed << " failed\n";
    return s.str();
}

namespace {
std::string xmlEscape(const std::string &t) {
    std::string o;
    for (char c : t) {
        switch (c) {
        case '&': o += "&amp;"; break;
        case '<': o += "&lt;"; break;
        case '>': o += "&gt;"; break;
        case '"': o += "&quot;"; break;
        case '\'': o += "&apos;"; break;
        default: o += c;
        }
    }
    return o;
}
}  // namespace

std::string budgetJUnit(const BudgetResult &r, const std::string &suite) {
    std::ostringstream s;
    s << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
    s << "<testsuites name=\"visaudit check\" tests=\"" << r.checks.size() << "\" failures=\"" << r.failed << "\">\n";
    s << "  <testsuite name=\"" << xmlEscape(suite) << "\" tests=\"" << r.checks.size() << "\" failures=\""
      << r.failed << "\" errors=\"0\" skipped=\"0\">\n";
    for (const BudgetCheck &c : r.checks) {
        s << "    <testcase classname=\"" << xmlEscape(suite + "." + c.view) << "\" name=\""
          << xmlEscape(c.kind + " " + c.metric + (c.frame.empty() ? "" : ", " + c.frame)) << "\"";
        if (c.pass) {
            s << "/>\n";
        } else {
            s << ">\n      <failure message=\"" << xmlEscape(c.message) << "\" type=\"budget\">"
              << xmlEscape("value " + c.value + ", allowed " + c.allowed) << "</failure>\n    </testcase>\n";
        }
    }
    s << "  </testsuite>\n</testsuites>\n";
    return s.str();
}

}  // namespace va
