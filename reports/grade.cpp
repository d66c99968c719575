#include "reports/grade.h"

#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>

#include "common/json_util.h"

namespace va {

using OJson = nlohmann::ordered_json;

bool loadTolerances(const std::string &path, ToleranceRules *out, std::string *err, uint64_t maxJsonDepth) {
    json::Doc doc;
    if (!json::parseFile(path, &doc, err, maxJsonDepth)) return false;
    const json::Path top;
    const json::Json &root = doc.root;
    if (!root.is_object() || !root.contains("format") || root["format"] != kToleranceFormat) {
        *err = json::where(doc, top / "format") + ": \"format\" must be \"" + kToleranceFormat + "\"";
        return false;
    }
    auto readTol = [&](const json::Path &p, const json::Json &j, Tolerance *t) {
        if (!j.is_object()) {
            *err = json::where(doc, p) + ": " + json::pathString(p) + ": expected {\"abs\": number, \"rel\": number}";
            return false;
        }
        for (const auto &[k, v] : j.items()) {
            if (k != "abs" && k != "rel") {
                *err = json::where(doc, p / k, true) + ": " + json::pathString(p) + ": unknown key '" + k +
                       "' (known: abs, rel)";
                return false;
            }
            if (!v.is_number() || !(v.get<double>() >= 0)) {
                *err = json::where(doc, p / k) + ": " + json::pathString(p / k) + ": expected a number >= 0";
                return false;
            }
            (k == "abs" ? t->abs : t->rel) = v.get<double>();
        }
        return true;
    };
    ToleranceRules r;
    for (const auto &[key, value] : root.items()) {
        if (key == "format") continue;
        if (key == "default") {
            if (!readTol(top / key, value, &r.defaults)) return false;
            r.hasDefault = true;
        } else if (key == "metrics") {
            if (!value.is_object()) {
                *err = json::where(doc, top / key) + ": metrics: expected an object {\"stage.key\": {abs, rel}}";
                return false;
            }
            for (const auto &[metric, tol] : value.items()) {
                Tolerance t;
                if (!readTol(top / "metrics" / metric, tol, &t)) return false;
                r.rules.push_back({metric, t});
            }
        } else {
            const std::string near = json::closest(key, {"format", "default", "metrics"});
            *err = json::where(doc, top / key, true) + ": unknown key '" + key + "'" +
                   (near.empty() ? "" : ", did you mean '" + near + "'?") + " (known: format, default, metrics)";
            return false;
        }
    }
    *out = std::move(r);
    return true;
}

Tolerance toleranceFor(const ToleranceRules &t, const std::string &metric, Tolerance builtin) {
    Tolerance tol = t.hasDefault ? t.defaults : builtin;
    for (const auto &[rule, value] : t.rules) {
        const bool wildcard = rule.size() >= 2 && rule.compare(rule.size() - 2, 2, ".*") == 0;
        if (rule == metric || (wildcard && metric.compare(0, rule.size() - 1, rule, 0, rule.size() - 1) == 0) ||
            (metric.compare(0, rule.size() + 1, rule + ".") == 0))
            tol = value;
    }
    return tol;
}

namespace {

bool isTiming(const std::string &k) { return k == "ms" || (k.size() > 3 && k.compare(k.size() - 3, 3, "_ms") == 0); }

// The numbers of one view a student must reproduce, as "stage.key" -> value, in report order.
// Arrays and nested objects of numbers flatten with their index or key ("clip.per_plane.near",
// "zbuffer_summary.histogram.3"). A submission is the student's file: the walk keeps its own stack
// (depth-first, children in document order), never the call stack, whatever the nesting. A node
// keeps its key and its parent's index, and a name is joined only at a number: building every
// inner node's full name would cost the square of the depth.
void flatten(const std::string &prefix, const OJson &root, std::vector<std::pair<std::string, OJson>> *out) {
    struct Node {
        std::string key;  // "" for the root (the prefix)
        size_t parent;    // index into `nodes`
        const OJson *j;
    };
    std::vector<Node> nodes{{"", 0, &root}};
    std::vector<size_t> todo{0}, children;
    std::vector<const std::string *> keys;
    while (!todo.empty()) {
        const size_t n = todo.back();
        todo.pop_back();
        const OJson *j = nodes[n].j;
        children.clear();
        if (j->is_object()) {
            for (const auto &[k, v] : j->items())
                if (!isTiming(k) && k != "name" && k != "ran" && k != "reason") {
                    children.push_back(nodes.size());
                    nodes.push_back({k, n, &v});
                }
        } else if (j->is_array()) {
            for (size_t i = 0; i < j->size(); ++i) {
                children.push_back(nodes.size());
                nodes.push_back({std::to_string(i), n, &(*j)[i]});
            }
        } else if (j->is_number() || j->is_null()) {
            keys.clear();
            for (size_t a = n; a != 0; a = nodes[a].parent) keys.push_back(&nodes[a].key);
            std::string name = prefix;
            for (auto k = keys.rbegin(); k != keys.rend(); ++k) {
                name += '.';
                name += **k;
            }
            out->push_back({std::move(name), *j});
        }
        todo.insert(todo.end(), children.rbegin(), children.rend());
    }
}

std::vector<std::pair<std::string, OJson>> viewMetrics(const OJson &view) {
    std::vector<std::pair<std::string, OJson>> m;
    for (const OJson &s : view["stages"])
        if (s["ran"] == true) flatten(s["name"].get<std::string>(), s, &m);
    if (view.contains("zbuffer")) flatten("zbuffer_summary", view["zbuffer"], &m);
    return m;
}

Tolerance toleranceFor(const ToleranceRules &t, const std::string &metric, bool integer) {
    return va::toleranceFor(t, metric, Tolerance{0, integer ? 0 : 1e-9});
}

std::string show(const OJson &v) { return v.is_null() ? "null" : v.dump(); }

}  // namespace

bool gradeReports(const OJson &ref, const OJson &sub, const ToleranceRules &tol, GradeResult *out, std::string *err) {
    for (const auto *r : {&ref, &sub}) {
        if (!r->is_object() || !r->contains("views") || !(*r)["views"].is_array()) {
            *err = std::string(r == &ref ? "the reference" : "the submission") +
                   " is not a report: it needs a \"views\" array as report.json has (docs/report-schema.json)";
            return false;
        }
    }
    GradeResult g;
    for (const OJson &rv : ref["views"]) {
        const std::string name = rv["name"];
        const OJson *sv = nullptr;
        for (const OJson &v : sub["views"])
            if (v.contains("name") && v["name"] == name) sv = &v;
        std::map<std::string, OJson> submitted;
        if (sv && sv->contains("stages") && (*sv)["stages"].is_array())
            for (auto &[k, v] : viewMetrics(*sv)) submitted[k] = v;
        for (auto &[metric, value] : viewMetrics(rv)) {
            GradeItem it;
            it.view = name;
            const size_t dot = metric.find('.');
            it.stage = metric.substr(0, dot);
            it.key = metric.substr(dot + 1);
            it.reference = show(value);
            auto s = submitted.find(metric);
            if (s == submitted.end()) {
                it.submitted = "missing";
                it.pass = false;
            } else {
                it.submitted = show(s->second);
                if (value.is_null() || s->second.is_null()) {
                    it.pass = value.is_null() && s->second.is_null();
                } else {
                    const Tolerance t = toleranceFor(tol, metric, value.is_number_integer());
                    const double a = value.get<double>(), b = s->second.get<double>();
                    const double diff = std::fabs(a - b);
                    it.pass = diff <= t.abs || diff <= t.rel * std::fabs(a);
                }
            }
            g.items.push_back(it);
        }
    }
    for (const GradeItem &it : g.items) (it.pass ? g.passed : g.failed)++;
    g.score = g.items.empty() ? 0 : double(g.passed) / double(g.items.size());
    *out = std::move(g);
    return true;
}

std::string gradeTable(const GradeResult &r) {
    std::ostringstream s;
    // Per view and stage, in order of first appearance.
    std::vector<std::pair<std::string, std::string>> order;
    std::map<std::pair<std::string, std::string>, std::pair<int, int>> counts;  // passed, total
    for (const GradeItem &it : r.items) {
        const auto key = std::make_pair(it.view, it.stage);
        if (!counts.count(key)) order.push_back(key);
        counts[key].first += it.pass;
        counts[key].second += 1;
    }
    char line[256];
    std::snprintf(line, sizeof line, "%-20s %-16s %8s %8s\n", "view", "stage", "passed", "of");
    s << line;
    for (const auto &k : order) {
        std::snprintf(line, sizeof line, "%-20s %-16s %8d %8d\n", k.first.c_str(), k.second.c_str(),
                      counts[k].first, counts[k].second);
        s << line;
    }
    for (const GradeItem &it : r.items)
        if (!it.pass)
            s << "FAIL " << it.view << " " << it.stage << "." << it.key << ": submitted " << it.submitted
              << ", reference " << it.reference << "\n";
    std::snprintf(line, sizeof line, "score %.1f%% (%zu of %zu)\n", 100 * r.score, r.passed, r.items.size());
    s << line;
    return s.str();
}

OJson gradeJson(const GradeResult &r) {
    OJson j;
    j["format"] = "visaudit-grade/1";
    j["score"] = r.score;
    j["passed"] = r.passed;
    j["failed"] = r.failed;
    OJson items = OJson::array();
    for (const GradeItem &it : r.items)
        items.push_back({{"view", it.view}, {"stage", it.stage}, {"key", it.key}, {"reference", it.reference},
                         {"submitted", it.submitted}, {"pass", it.pass}});
    j["items"] = items;
    return j;
}

}  // namespace va
