// Reading a report (report.json as nlohmann::ordered_json) without exceptions: a missing key or a
// value of another type reads as absent, so a reader of a report of an older or unexpected shape
// leaves out what it cannot find instead of failing. report.html and the findings read through these.
#pragma once

#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

namespace va::rjson {

using Json = nlohmann::ordered_json;

const Json *get(const Json *j, std::string_view key);
// A path of keys: get(&v, {"audit", "false_culls", "pixels"}).
const Json *get(const Json *j, std::initializer_list<std::string_view> keys);
std::optional<double> num(const Json *j);
std::optional<double> num(const Json *j, std::initializer_list<std::string_view> keys);
double numOr(const Json *j, std::initializer_list<std::string_view> keys, double fallback);
std::string str(const Json *j);
std::string str(const Json *j, std::initializer_list<std::string_view> keys);
// The first of several names a field may have (sections still being designed use either).
std::optional<double> firstNum(const Json *j, std::initializer_list<std::string_view> keys);
bool isTrue(const Json *j);
// A section that says it did not run: {"ran": false, "reason": ...}.
bool ranFalse(const Json *j);

// The view's funnel row of this stage (nullptr: none), and whether it ran.
const Json *stageNamed(const Json *v, std::string_view name);
bool stageRan(const Json *s);
// Z-fighting pixels in the view's own depth format (what the z-buffer really shows).
std::optional<double> zfightInOwnFormat(const Json *v);
// report.views, in order.
std::vector<const Json *> viewsOf(const Json &report);
// An ordering section in any of the shapes it may take: an array of rows, an object holding such
// an array, or an object of per-method objects. Each method: (name, row).
std::vector<std::pair<std::string, const Json *>> orderingMethods(const Json *ordering);
// A method's time: its "ms", else the sum of its "*_ms" fields (build + draw).
std::optional<double> methodMs(const Json *row);

}  // namespace va::rjson
