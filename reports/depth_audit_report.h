// Console table and JSON of the depth-format audit (analysis/audits/depth_audit.h), for the
// `visaudit depth-audit` command. Field meanings: docs/depth-formats.md.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "analysis/audits/depth_audit.h"

namespace va {

constexpr const char *kDepthAuditFormat = "visaudit-depth-audit/1";

// A fixed-width console table, one row per format in the result's order:
//
//   depth formats over [0.1, 10000] m: resolution = depth step to the next stored value (m) at d
//   format            bits     distinct  range     d=0.1  ...   onset 1cm  likely 1cm   onset 1mm  likely 1mm
//   unorm24             24     16777216  all     5.96e-09  ...      129.53      183.18      40.963       57.93
//
// Resolutions are printf %.3g, the fight distances (onset, likely: exact) %.5g; "-" is a depth
// outside the format's range, "never" a gap no bucket up to far is as wide as, a trailing '*' a
// step limited by the double input (skipsValues). A legend follows the rows; every line ends
// with '\n'. A result with `error` set gives "error: ...\n".
std::string depthAuditTable(const DepthAuditResult &result);

// depth-audit.json: {"format": "visaudit-depth-audit/1", "tool": {"name", "version"}, "near",
// "far", "units": "m", "decade_depths", "fight_gaps", "curve_depths", "formats": [...]}; per
// format the DepthFormatAudit fields in snake_case (docs/depth-formats.md lists them; fight_distances
// are {gap, onset, onset_bucket_width, likely}, log24 has log_c). No NaN or infinity: an absent or
// non-finite value is null (a fight distance of null means "never").
// A result with `error` set gives {"format", "tool", "error": message}.
nlohmann::ordered_json depthAuditJson(const DepthAuditResult &result);

}  // namespace va
