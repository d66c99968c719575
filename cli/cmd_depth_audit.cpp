// visaudit depth-audit: what each depth format resolves over a depth range, and (--scene) where
// each format z-fights in a scene's views.
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "analysis/audits/depth_audit.h"
#include "analysis/pipeline.h"
#include "cli/command_table.h"
#include "cli/commands.h"
#include "cli/shared.h"
#include "reports/console.h"
#include "reports/depth_audit_report.h"
#include "reports/depth_plot.h"
#include "reports/report.h"

namespace va {
namespace {

// --scene (SceneOptions::scene) and --views: also the per-view z-fighting over a scene's views.
struct DepthAuditOptions : SceneOptions {
    double nearZ = 0, farZ = 0;
    std::string formats;   // comma-separated; empty = all
    std::string auditOut;  // --out; empty = console only
    int threads = 0;
};

// depth-audit --scene: the per-view z-fighting analysis over a scene's views, with the formats'
// verdicts and the recommendation per view (no images, no report folder).
int depthAuditScene(const DepthAuditOptions &o, const std::vector<DepthFormatSpec> &formats) {
    installInterruptHandlers();
    Scene scene;
    std::vector<ViewSpec> views;
    if (!loadInputs(o, &scene, &views)) return kExitBadInput;
    PipelineSettings s;
    s.audit = s.raycast = s.detail = s.occlusion = false;
    s.zfightSettings.formats = formats;
    s.threads = o.threads;
    s.limits.maxMemory = defaultMaxMemory();
    s.cancel = &gInterrupt;
    AnalysisResult result;
    std::string err;
    if (!analyzeScene(scene, views, s, nullptr, &result, &err)) {
        if (interrupted()) return interruptedExit("");
        fail(err);
        return kExitBadInput;
    }
    std::printf("%s", zfightViewsTable(scene.path, result).c_str());
    return kExitOk;
}

int cmdDepthAudit(const DepthAuditOptions &o) {
    std::string err;
    const bool range = o.nearZ != 0 || o.farZ != 0;
    if (!range && o.scene.empty()) {
        fail("depth-audit needs --near N --far F (the formats over a depth range), --scene SCENE (its views), or both");
        return kExitBadInput;
    }
    if (range && !validateDepthAuditRange(o.nearZ, o.farZ, &err)) {
        fail(err);
        return kExitBadInput;
    }
    std::vector<DepthFormatSpec> formats(allDepthFormats().begin(), allDepthFormats().end());
    if (!o.formats.empty() && !parseDepthFormatList(o.formats, &formats, &err)) {
        fail("--formats: " + err);
        return kExitBadInput;
    }
    if (!range) return depthAuditScene(o, formats);
    const DepthAuditResult r = auditDepthFormats(o.nearZ, o.farZ, formats);
    if (!r.error.empty()) {
        fail(r.error);
        return kExitBadInput;
    }
    std::printf("%s", depthAuditTable(r).c_str());
    if (!o.auditOut.empty()) {
        // The two files go into DIR one by one, each written atomically; DIR may hold a report.
        std::error_code ec;
        std::filesystem::create_directories(o.auditOut, ec);
        if (ec) {
            fail("cannot create --out folder '" + o.auditOut + "': " + ec.message());
            return kExitBadInput;
        }
        if (!writeFileAtomic(o.auditOut + "/depth-audit.json", depthAuditJson(r).dump(2) + "\n", &err) ||
            !writeDepthResolutionPlot(r, o.auditOut + "/depth-audit.png", &err)) {
            fail(err);
            return kExitBadInput;
        }
        std::printf("wrote %s/depth-audit.json and %s/depth-audit.png\n", o.auditOut.c_str(), o.auditOut.c_str());
    }
    if (!o.scene.empty()) return depthAuditScene(o, formats);
    return kExitOk;
}

void addDepthAuditOptions(CLI::App *c, DepthAuditOptions &o) {
    c->add_option("--near", o.nearZ, "Near plane distance (> 0)");
    c->add_option("--far", o.farZ, "Far plane distance (> near)");
    c->add_option("--scene", o.scene, "Also analyse this scene's views: per view, where each format z-fights "
                                           "and the recommended format");
    c->add_option("--views", o.views, "With --scene: a views file, orbit:N, spawns or walk:N");
    c->add_option("--formats", o.formats, "Comma-separated depth formats, log24:C=X for log24 with constant C, or "
                                          "all (default: all)");
    c->add_option("--out", o.auditOut, "Folder for depth-audit.json and depth-audit.png");
    addJsonDepthOption(c, o.maxJsonDepth);
}

}  // namespace

CommandRun setupDepthAudit(CLI::App *c) {
    return bindCommand<DepthAuditOptions>(c, addDepthAuditOptions, cmdDepthAudit);
}

}  // namespace va
