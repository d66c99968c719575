// Console table and JSON of the depth-format audit (analysis/depth_audit.h), for the
// `visaudit depth-audit` command. Field meanings: docs/depth-formats.md.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "analysis/depth_audit.h"

namespace va {

constexpr const char *kDepthAuditFormat = "visaudit-depth-audit/1";

// A fixed-width console table, one row per format in the result's order:
//
//   depth formats over [0.1, 10000] m: resolution = depth step to the next stored value (m) at d
//   format            bits     distinct  range     d=0.1       d=1      d=10  ...  fight 1cm  fight 1mm
//   unorm24             24     16777216  all     5.96e-09  5.96e-07  5.96e-05  ...       138       44.3
//   uint32_inv          32   4294537800  d>=1           -  2.33e-10  2.33e-08  ...  6.82e+03  2.23e+03
//
// Numbers are printf %.3g; "-" is a depth outside the format's range, "never" a gap that does not
// fight up to far, a trailing '*' a step limited by the double input (skipsValues). A legend
// follows the rows; every line ends with '\n'. A result with `error` set gives "error: ...\n".
std::string depthAuditTable(const DepthAuditResult &result);

// depth-audit.json: {"format": "visaudit-depth-audit/1", "tool": {"name", "version"}, "near",
// "far", "units": "m", "decade_depths", "fight_gaps", "curve_depths", "formats": [...]}; per
// format the DepthFormatAudit fields in snake_case (docs/depth-formats.md lists them). No NaN or
// infinity: an absent or non-finite value is null (a fight distance of null means "never").
// A result with `error` set gives {"format", "tool", "error": message}.
nlohmann::ordered_json depthAuditJson(const DepthAuditResult &result);

}  // namespace va
