#include "cli/cmd_pvs_audit.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <mutex>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "analysis/load/load.h"
#include "cli/command_table.h"
#include "cli/commands.h"
#include "common/fp_env.h"
#include "reports/pvs_audit_report.h"
#include "reports/report.h"

namespace va {
namespace {
// ---- pvs-audit (docs/pvs-audit.md) ------------------------------------------------------------

// --clusters "0-99,200,310-312" -> ascending, without repeats. False + message on bad text.
bool parseClusterList(const std::string &text, std::vector<int32_t> *out, std::string *err) {
    out->clear();
    std::stringstream ss(text);
    std::string part;
    auto whole = [](const std::string &t, int64_t *v) {
        if (t.empty() || t.size() > 9 || t.find_first_not_of("0123456789") != std::string::npos) return false;
        *v = std::stoll(t);
        return true;
    };
    while (std::getline(ss, part, ',')) {
        const size_t dash = part.find('-');
        int64_t a = 0, b = 0;
        const bool ok = dash == std::string::npos ? whole(part, &a) && whole(part, &b)
                                                  : whole(part.substr(0, dash), &a) && whole(part.substr(dash + 1), &b);
        if (!ok || b < a) {
            *err = "--clusters " + text + ": '" + part +
                   "' is not a cluster or a range A-B (A <= B); give e.g. --clusters 0-99,200";
            return false;
        }
        if (b >= (1 << 20)) {
            *err = "--clusters " + text + ": '" + part + "' goes past cluster 1048575, more than any map has "
                   "(Quake 3 allows 131072 leafs)";
            return false;
        }
        for (int64_t c = a; c <= b; ++c) out->push_back(int32_t(c));
    }
    if (out->empty()) {
        *err = "--clusters: empty; give clusters and ranges, e.g. --clusters 0-99,200";
        return false;
    }
    std::sort(out->begin(), out->end());
    out->erase(std::unique(out->begin(), out->end()), out->end());
    return true;
}

}  // namespace

bool pvsSettings(const PvsAuditOptions &o, PvsAuditSettings *s) {
    *s = o.pvs;
    s->threads = o.threads;
    s->cancel = &gInterrupt;
    if (o.pvsFar) s->farPlane = *o.pvsFar;
    std::string err;
    if (!o.pvsClusters.empty() && !parseClusterList(o.pvsClusters, &s->clusters, &err)) {
        fail(err);
        return false;
    }
    return true;
}

int runPvsAudit(const PvsAuditOptions &o, const Scene &scene, const PvsAuditSettings &settings, const std::string &dir,
                const std::string &outName, PvsAuditResult *result, nlohmann::ordered_json *json) {
    if (const char *why = pvsAuditSkipReason(scene)) {
        fail(scene.path + ": cannot audit the PVS: " + why +
             (scene.bsp ? "; compile the map with vis (q3map2 -vis)" : "; give a Quake 3 map (.bsp or pak.pk3:maps/x.bsp)"));
        return kExitBadInput;
    }
    PvsAuditSettings s = settings;
    const bool tty = isatty(fileno(stderr)) && !o.quiet;
    std::mutex printMutex;
    const auto t0 = std::chrono::steady_clock::now();
    if (tty)
        s.progress = [&](size_t done, size_t total) {
            if (done % 16 != 0 && done != total) return;
            std::lock_guard<std::mutex> lock(printMutex);
            const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            std::fprintf(stderr, "\r\033[K[%zu/%zu clusters] %.1f s, about %.0f s left", done, total, elapsed,
                         elapsed / double(done) * double(total - done));
        };
    std::string err;
    // Under IEEE defaults on every thread, whatever used TBB first (common/fp_env.h).
    bool ok = false;
    runWithIeeeFp([&] { ok = auditPvs(scene, s, result, &err); });
    if (tty) std::fprintf(stderr, "\n");
    if (!ok) {
        if (interrupted()) return interruptedExit(outName);
        fail(err);
        return kExitBadInput;
    }
    if (!writePvsAudit(*result, dir, json, &err)) {
        fail(err);
        return kExitBadInput;
    }
    return kExitOk;
}

namespace {
int cmdPvsAudit(const PvsAuditOptions &o) {
    installInterruptHandlers();
    PvsAuditSettings settings;
    if (!pvsSettings(o, &settings)) return kExitBadInput;
    Scene scene;
    LoadOptions lo;
    lo.bsp.patchLevel = o.patchLevel;
    lo.maxTriangles = o.maxTriangles;
    std::string err;
    if (!loadScene(o.scene, lo, &scene, &err)) {
        fail(err);
        return kExitBadInput;
    }
    if (interrupted()) return interruptedExit(o.pvsOut);
    if (const char *why = pvsAuditSkipReason(scene)) {
        fail(scene.path + ": cannot audit the PVS: " + why +
             (scene.bsp ? "; compile the map with vis (q3map2 -vis)" : "; give a Quake 3 map (.bsp or pak.pk3:maps/x.bsp)"));
        return kExitBadInput;
    }
    OutputDir out;
    if (!out.open(o.pvsOut, &err)) {
        fail(err);
        return kExitBadInput;
    }
    PvsAuditResult result;
    nlohmann::ordered_json json;
    const int code = runPvsAudit(o, scene, settings, out.staging(), o.pvsOut, &result, &json);
    if (code != kExitOk) return code;
    if (const int code = commitOutput(out, o.pvsOut); code != kExitOk) return code;
    if (o.json) {
        nlohmann::ordered_json summary;
        summary["report"] = o.pvsOut + "/pvs-audit.json";
        summary["map"] = json["map"];
        summary["far_plane"] = json["far_plane"];
        summary["totals"] = json["totals"];
        std::printf("%s\n", summary.dump(2).c_str());
    } else if (!o.quiet) {
        std::printf("%sreport: %s/pvs-audit.json, %s/pvs-audit.html\n", pvsAuditTable(result).c_str(), o.pvsOut.c_str(),
                    o.pvsOut.c_str());
    }
    return kExitOk;
}

void addPvsAuditOptions(CLI::App *c, PvsAuditOptions &o) {
    c->add_option("map", o.scene, "Quake 3 map: x.bsp or pak.pk3:maps/x.bsp")->required();
    c->add_option("--out", o.pvsOut, "Output folder for pvs-audit.json, .png and .html (written as a whole or not at all)");
    c->add_option("--samples", o.pvs.samples, "Eye points per cluster (default 32; time grows linearly)")
        ->check(CLI::Range(1, 1024));
    c->add_option("--resolution", o.pvs.resolution,
                  "Cube-face side: 6 x R^2 rays per eye point (default 12: 864 rays; time grows with R^2)")
        ->check(CLI::Range(1, 256));
    c->add_option("--seed", o.pvs.seed, "Seed of the eye points and ray rotations (default 1)");
    c->add_option_function<double>("--far-plane", [&o](double d) { o.pvsFar = d; },
                                   "Far plane distance (default: the map's _farplanedist; 0 = unlimited)")
        ->check(CLI::Range(0.0, 1e30));
    c->add_option("--clusters", o.pvsClusters, "Audit only these clusters, e.g. 0-99,200 (default: every cluster)");
    c->add_option("--image-size", o.pvs.imageSize, "Longest side of pvs-audit.png in pixels (default 1024; 0 = no image)")
        ->check(CLI::Range(0, 4096));
    c->add_option("--threads", o.threads, "Worker threads (0 = all cores)")->check(CLI::Range(0, 4096));
    c->add_option("--patch-level", o.patchLevel, "Segments per Bezier patch edge (patches occlude)")->check(CLI::Range(1, 64));
    c->add_option("--max-triangles", o.maxTriangles, "Largest map accepted, in triangles")
        ->check(CLI::Range(uint64_t(1), uint64_t(UINT32_MAX)));
    c->add_flag("--quiet", o.quiet, "No progress or summary on the console");
    c->add_flag("--json", o.json, "Print the totals as JSON on stdout");
}

}  // namespace

CommandRun setupPvsAudit(CLI::App *c) { return bindCommand<PvsAuditOptions>(c, addPvsAuditOptions, cmdPvsAudit); }

}  // namespace va
