// The outputs of `visaudit pvs-audit` (analysis/audits/pvs_audit.h; docs/pvs-audit.md): pvs-audit.json
// (versioned), pvs-audit.png (the level from above, colored by slack and misses, with a legend),
// pvs-audit.html (one self-contained page) and a console summary. `check` writes the same three
// files next to report.json when its budget names a pvs_* metric.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "analysis/audits/pvs_audit.h"

namespace va {

constexpr const char *kPvsAuditFormat = "visaudit-pvs-audit/1";
constexpr size_t kPvsAuditMaxListedMisses = 1000;  // evidence records written to the JSON (all are counted)
constexpr size_t kPvsAuditWorst = 20;              // clusters in each "worst" list

// pvs-audit.json: format, tool, map, settings, far_plane, definition, occluders, totals,
// histograms, worst, misses (evidence, the first kPvsAuditMaxListedMisses in cluster order),
// clusters (one entry per audited or requested cluster), image, timings_ms. No NaN or infinity.
nlohmann::ordered_json pvsAuditJson(const PvsAuditResult &result, const std::string &imageName);

// The console summary: totals, far plane, cost, the worst clusters, the first misses.
std::string pvsAuditTable(const PvsAuditResult &result);

// The top-down image with its legend (RGB8); false when the result has no top view.
bool pvsAuditImage(const PvsAuditResult &result, std::vector<uint8_t> *rgb, int *width, int *height);

// pvs-audit.html from pvs-audit.json alone (the image referenced when `dir` holds it).
std::string pvsAuditHtml(const nlohmann::ordered_json &audit, const std::string &dir);

// Writes pvs-audit.png (when there is a top view), pvs-audit.json and pvs-audit.html into dir, each
// atomically; *json receives the JSON. False + *err naming the file.
bool writePvsAudit(const PvsAuditResult &result, const std::string &dir, nlohmann::ordered_json *json,
                   std::string *err);

}  // namespace va
