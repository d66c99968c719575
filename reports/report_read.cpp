// Reading a report without exceptions (reports/report_read.h).
#include "reports/report_read.h"

namespace va::rjson {

const Json *get(const Json *j, std::string_view key) {
    if (!j || !j->is_object()) return nullptr;
    auto it = j->find(std::string(key));
    return it == j->end() ? nullptr : &*it;
}

const Json *get(const Json *j, std::initializer_list<std::string_view> keys) {
    for (std::string_view k : keys) j = get(j, k);
    return j;
}

std::optional<double> num(const Json *j) {
    if (!j || !j->is_number()) return std::nullopt;
    return j->get<double>();
}

std::optional<double> num(const Json *j, std::initializer_list<std::string_view> keys) { return num(get(j, keys)); }

double numOr(const Json *j, std::initializer_list<std::string_view> keys, double fallback) {
    return num(get(j, keys)).value_or(fallback);
}

std::string str(const Json *j) { return j && j->is_string() ? j->get<std::string>() : std::string(); }

std::string str(const Json *j, std::initializer_list<std::string_view> keys) { return str(get(j, keys)); }

std::optional<double> firstNum(const Json *j, std::initializer_list<std::string_view> keys) {
    for (std::string_view k : keys)
        if (auto v = num(get(j, k))) return v;
    return std::nullopt;
}

bool isTrue(const Json *j) { return j && j->is_boolean() && j->get<bool>(); }

bool ranFalse(const Json *j) {
    const Json *r = get(j, "ran");
    return r && r->is_boolean() && !r->get<bool>();
}

std::optional<double> zfightInOwnFormat(const Json *v) {
    if (!get(v, "depth") || ranFalse(get(v, "depth"))) return std::nullopt;
    return num(v, {"depth", "formats", str(v, {"depth_format"}), "fighting_pixels"});
}

const Json *stageNamed(const Json *v, std::string_view name) {
    const Json *stages = get(v, "stages");
    if (!stages || !stages->is_array()) return nullptr;
    for (const Json &s : *stages)
        if (str(get(&s, "name")) == name) return &s;
    return nullptr;
}

bool stageRan(const Json *s) { return s && isTrue(get(s, "ran")); }

std::vector<const Json *> viewsOf(const Json &report) {
    std::vector<const Json *> vs;
    const Json *views = get(&report, "views");
    if (views && views->is_array())
        for (const Json &v : *views) vs.push_back(&v);
    return vs;
}

std::vector<std::pair<std::string, const Json *>> orderingMethods(const Json *ordering) {
    std::vector<std::pair<std::string, const Json *>> out;
    if (!ordering || ranFalse(ordering)) return out;
    // The rows: the array itself; else the member "table" or "methods"; else the first array of
    // objects that name a "method"; else the first array of objects.
    const Json *rows = nullptr;
    const auto tableLike = [](const Json &a) { return a.is_array() && !a.empty() && a.front().is_object(); };
    if (ordering->is_array()) {
        rows = ordering;
    } else if (ordering->is_object()) {
        for (const char *k : {"table", "methods"})
            if (const Json *t = get(ordering, k); t && tableLike(*t) && !rows) rows = t;
        for (auto it = ordering->begin(); it != ordering->end() && !rows; ++it)
            if (tableLike(it.value()) && get(&it.value().front(), "method")) rows = &it.value();
        for (auto it = ordering->begin(); it != ordering->end() && !rows; ++it)
            if (tableLike(it.value())) rows = &it.value();
    }
    if (rows) {
        for (const Json &r : *rows) {
            if (!r.is_object()) continue;
            std::string name = str(get(&r, "method"));
            if (name.empty()) name = str(get(&r, "name"));
            out.emplace_back(name.empty() ? "method " + std::to_string(out.size() + 1) : name, &r);
        }
    } else if (ordering->is_object()) {
        for (auto it = ordering->begin(); it != ordering->end(); ++it)
            if (it.value().is_object()) out.emplace_back(it.key(), &it.value());
    }
    return out;
}

std::optional<double> methodMs(const Json *row) {
    if (auto ms = num(get(row, "ms"))) return ms;
    std::optional<double> sum;
    for (auto it = row->begin(); it != row->end(); ++it) {
        const std::string &k = it.key();
        if (k.size() > 3 && k.compare(k.size() - 3, 3, "_ms") == 0 && it.value().is_number())
            sum = sum.value_or(0) + it.value().get<double>();
    }
    return sum;
}

}  // namespace va::rjson
