// visaudit info: a scene's summary (triangles, objects, bounds, materials, views, warnings).
#include <cstdio>

#include <nlohmann/json.hpp>

#include "cli/command_table.h"
#include "cli/commands.h"
#include "cli/shared.h"
#include "reports/console.h"

namespace va {
namespace {

struct InfoOptions : SceneOptions {
    bool json = false;  // --json: the summary as JSON on stdout
};

int cmdInfo(const InfoOptions &o) {
    Scene scene;
    std::vector<ViewSpec> views;
    if (!loadInputs(o, &scene, &views)) return kExitBadInput;
    if (o.json)
        std::printf("%s\n", sceneSummaryJson(scene, views).dump(2).c_str());
    else
        std::printf("%s", sceneSummaryTable(scene, views).c_str());
    return kExitOk;
}

void addInfoOptions(CLI::App *c, InfoOptions &o) {
    addSceneOptions(c, o);
    c->add_flag("--json", o.json, "Print the summary as JSON on stdout (the same fields; for scripts and tests)");
}

}  // namespace

CommandRun setupInfo(CLI::App *c) { return bindCommand<InfoOptions>(c, addInfoOptions, cmdInfo); }

}  // namespace va
