#include "reports/depth_audit_report.h"

#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <optional>

namespace va {

namespace {

using Json = nlohmann::ordered_json;

std::string format(const char *fmt, auto... args) {
    const int n = std::snprintf(nullptr, 0, fmt, args...);
    std::string s(size_t(n > 0 ? n : 0), '\0');
    if (n > 0) std::snprintf(s.data(), s.size() + 1, fmt, args...);
    return s;
}

std::string g3(double v) { return format("%.3g", v); }
std::string g5(double v) { return format("%.5g", v); }  // the exact fight distances: 129.53
std::string g6(double v) { return format("%.6g", v); }  // depths in headers: 10000, not 1e+04

// "1cm", "1mm", "2.5cm", "1m": the gap in the unit that makes it a small number.
std::string gapLabel(double g) {
    if (g >= 1) return format("%gm", g);
    if (g >= 0.01) return format("%gcm", g * 100);
    return format("%gmm", g * 1000);
}

// The representable part of [near, far], compact: "all", "d>=1", "d<=X", "[a, b]".
std::string rangeLabel(const DepthAuditResult &r, const DepthFormatAudit &a) {
    const bool cutNear = a.representableNear > r.nearZ, cutFar = a.representableFar < r.farZ;
    if (!cutNear && !cutFar) return "all";
    // (format() throughout: GCC 12 warns falsely, -Wrestrict, on "literal" + std::string&&.)
    if (cutNear && !cutFar) return format("d>=%s", g3(a.representableNear).c_str());
    if (!cutNear) return format("d<=%s", g3(a.representableFar).c_str());
    return format("[%s,%s]", g3(a.representableNear).c_str(), g3(a.representableFar).c_str());
}

// JSON has no NaN or infinity: absent or non-finite is null.
Json num(std::optional<double> v) { return v && std::isfinite(*v) ? Json(*v) : Json(nullptr); }
Json num(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

Json tool() { return {{"name", "visaudit"}, {"version", VISAUDIT_VERSION}}; }

}  // namespace

std::string depthAuditTable(const DepthAuditResult &r) {
    if (!r.error.empty()) return "error: " + r.error + "\n";
    std::string out = format("depth formats over [%s, %s] m: resolution = depth step to the next stored value (m) at d\n",
                             g6(r.nearZ).c_str(), g6(r.farZ).c_str());
    // Columns: format (17, left), bits (4), distinct (12), range (left, as wide as the widest), then
    // one 9-wide column per decade depth and one 10-wide per fight gap (all right-aligned).
    size_t rangeW = 5;
    for (const DepthFormatAudit &a : r.formats) rangeW = std::max(rangeW, rangeLabel(r, a).size());
    out += format("%-17s %4s %12s  %-*s", "format", "bits", "distinct", int(rangeW), "range");
    for (double d : r.decadeDepths) out += format(" %9s", format("d=%s", g6(d).c_str()).c_str());
    for (double g : r.fightGaps) {
        out += format(" %11s", format("onset %s", gapLabel(g).c_str()).c_str());
        out += format(" %11s", format("likely %s", gapLabel(g).c_str()).c_str());
    }
    out += "\n";
    bool anySkip = false, anyOut = false;
    for (const DepthFormatAudit &a : r.formats) {
        out += format("%-17s %4d %12" PRIu64 "  %-*s", a.name.c_str(), a.bits, a.distinctValues, int(rangeW),
                      rangeLabel(r, a).c_str());
        for (const DepthResolutionSample &s : a.decades) {
            std::string cell = "-";
            if (s.inRange && s.resolution) cell = g3(*s.resolution) + (s.skipsValues ? "*" : "");
            anySkip |= s.skipsValues;
            anyOut |= !s.inRange;
            out += format(" %9s", cell.c_str());
        }
        for (const DepthFightDistance &f : a.fights) {
            out += format(" %11s", f.onset ? g5(*f.onset).c_str() : "never");
            out += format(" %11s", f.likely ? g5(*f.likely).c_str() : "never");
        }
        out += "\n";
    }
    out += "onset <gap>: smallest depth (m) where a stored value's bucket is wider than <gap>, so two surfaces <gap> "
           "apart can store the same value (exact)\n";
    out += "likely <gap>: smallest depth (m) where a bucket is at least 2 x <gap> wide: a pair <gap> apart there "
           "shares a value with probability >= 50%\n";
    out += "never: no bucket up to far is that wide\n";
    if (anyOut) out += "-: depth outside the format's range (range column); it clamps to the range's end\n";
    if (anySkip)
        out += "*: the next value produced is more than one stored value away: the floats there are denser than what "
               "feeds them (the double depth, or the OpenGL formats' float z_ndc), which sets the step\n";
    for (const DepthFormatAudit &a : r.formats)
        if (!a.rangeNote.empty()) out += a.name + ": " + a.rangeNote + "\n";
    return out;
}

Json depthAuditJson(const DepthAuditResult &r) {
    Json j;
    j["format"] = kDepthAuditFormat;
    j["tool"] = tool();
    if (!r.error.empty()) {
        j["error"] = r.error;
        return j;
    }
    j["near"] = num(r.nearZ);
    j["far"] = num(r.farZ);
    j["units"] = "m";
    Json decades = Json::array(), gaps = Json::array(), curve = Json::array();
    for (double d : r.decadeDepths) decades.push_back(num(d));
    for (double g : r.fightGaps) gaps.push_back(num(g));
    for (double d : r.curveDepths) curve.push_back(num(d));
    j["decade_depths"] = decades;
    j["fight_gaps"] = gaps;
    j["curve_depths"] = curve;
    Json formats = Json::array();
    for (const DepthFormatAudit &a : r.formats) {
        const DepthFormatInfo &info = depthFormatInfo(a.format.format);
        Json f;
        f["name"] = a.name;
        f["bits"] = a.bits;
        f["nearer_is"] = a.nearerIsLarger ? "larger" : "smaller";
        f["stored"] = info.stored;
        if (a.format.format == DepthFormat::log24) f["log_c"] = num(a.format.logC);
        f["distinct_values"] = a.distinctValues;
        f["representable"] = {{"near", num(a.representableNear)},
                              {"far", num(a.representableFar)},
                              {"note", a.rangeNote.empty() ? Json(nullptr) : Json(a.rangeNote)}};
        Json res = Json::array();
        for (const DepthResolutionSample &s : a.decades) {
            Json x;
            x["depth"] = num(s.depth);
            x["in_range"] = s.inRange;
            x["stored"] = num(s.stored);
            x["key"] = s.key;
            x["resolution"] = num(s.resolution);
            x["step_to_next"] = num(s.stepToNext);
            x["step_to_prev"] = num(s.stepToPrev);
            x["skips_values"] = s.skipsValues;
            x["bucket_width"] = num(s.bucketWidth);
            x["closed_form"] = num(s.closedForm);
            x["relative_difference"] = num(s.relativeDifference);
            res.push_back(std::move(x));
        }
        f["resolution"] = std::move(res);
        Json fights = Json::array();
        for (const DepthFightDistance &d : a.fights)
            fights.push_back({{"gap", num(d.gap)},
                              {"onset", num(d.onset)},
                              {"onset_bucket_width", num(d.onsetBucket)},
                              {"likely", num(d.likely)}});
        f["fight_distances"] = std::move(fights);
        Json c = Json::array();
        for (const std::optional<double> &v : a.curveResolution) c.push_back(num(v));
        f["curve_resolution"] = std::move(c);
        formats.push_back(std::move(f));
    }
    j["formats"] = std::move(formats);
    return j;
}

}  // namespace va
