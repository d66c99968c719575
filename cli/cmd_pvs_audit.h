// visaudit pvs-audit, and what check uses of it when its budget names a pvs_* metric.
#pragma once

#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "analysis/audits/pvs_audit.h"
#include "cli/shared.h"

namespace va {

struct PvsAuditOptions : SceneOptions {  // scene: the map (pvs-audit's positional argument)
    PvsAuditSettings pvs;
    std::string pvsClusters;       // --clusters: "0-99,200"
    std::optional<double> pvsFar;  // --far-plane
    std::string pvsOut = "visaudit-pvs-audit";
    int threads = 0;
    bool quiet = false;
    bool json = false;  // --json: the totals on stdout
};

// The audit's settings from the options (pvs-audit's flags; check uses the defaults); false after
// saying why.
bool pvsSettings(const PvsAuditOptions &o, PvsAuditSettings *s);
// Runs the audit on a loaded scene and writes its three files into `dir`; exit code. `outName`:
// the folder named to the user when interrupted.
int runPvsAudit(const PvsAuditOptions &o, const Scene &scene, const PvsAuditSettings &settings, const std::string &dir,
                const std::string &outName, PvsAuditResult *result, nlohmann::ordered_json *json);

}  // namespace va
