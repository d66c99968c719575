#include "cli/shared.h"

#include <cstdio>
#include <cstdlib>
#include <sstream>

#include <signal.h>

#include "analysis/load/demo.h"
#include "analysis/level_samples.h"
#include "analysis/load/level_views.h"
#include "analysis/load/load.h"
#include "cli/commands.h"
#include "common/json_util.h"
#include "reports/report.h"

namespace va {

void fail(const std::string &msg) { std::fprintf(stderr, "visaudit: error: %s\n", msg.c_str()); }

// SIGINT and SIGTERM: the handler only records the signal; the pipeline polls it between views
// and stages (PipelineSettings::cancel) and the commands before they write, so a stopped run
// leaves no half-written report and the old output folder as it was (docs/limits.md).
std::atomic<int> gInterrupt{0};
static_assert(std::atomic<int>::is_always_lock_free, "a signal handler may only touch lock-free atomics");

namespace {
void onInterruptSignal(int sig) { gInterrupt.store(sig, std::memory_order_relaxed); }
}  // namespace

void installInterruptHandlers() {
    struct sigaction sa = {};
    sa.sa_handler = onInterruptSignal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESTART;  // blocking calls resume; the flag is polled, not an EINTR
    sigaction(SIGINT, &sa, nullptr);
    sigaction(SIGTERM, &sa, nullptr);
}

bool interrupted() { return gInterrupt.load(std::memory_order_relaxed) != 0; }

// The one line and the exit code (128 + signal, as a shell reports a signal) of a stopped run.
int interruptedExit(const std::string &out) {
    const int sig = gInterrupt.load(std::memory_order_relaxed);
    std::fprintf(stderr, "visaudit: interrupted by %s; nothing was written%s\n", sig == SIGINT ? "SIGINT" : "SIGTERM",
                 out.empty() ? "" : ("; '" + out + "' is as it was").c_str());
    return 128 + sig;
}


bool loadInputs(const SceneOptions &o, Scene *scene, std::vector<ViewSpec> *views, std::vector<Route> *routes) {
    std::string err;
    if (o.scene.empty()) {
        *scene = demoScene();
    } else {
        LoadOptions lo;
        lo.chunks.maxTriangles = o.chunk;
        lo.bsp.patchLevel = o.patchLevel;
        lo.maxTriangles = o.maxTriangles;
        lo.maxJsonDepth = o.maxJsonDepth;
        if (!loadScene(o.scene, lo, scene, &err)) {
            fail(err);
            return false;
        }
    }
    // A scene with no triangle passes every budget: the worst result a CI gate can give. check
    // refuses it; the other commands say so (stderr and the report's scene.warnings).
    if (scene->objectTriangles.empty()) {
        const std::string why =
            scene->path + ": the scene has no triangle to analyse (" + std::to_string(scene->stats.sourceTriangles) +
            " in the source, " + std::to_string(scene->stats.facesDropped) + " faces dropped by the loader, " +
            std::to_string(scene->stats.degenerateTriangles) + " degenerate, " +
            std::to_string(scene->stats.nonFiniteTriangles) + " non-finite)";
        if (o.refuseEmptyScene) {
            for (const std::string &w : scene->warnings) std::fprintf(stderr, "visaudit: warning: %s\n", w.c_str());
            fail(why + "; check needs geometry to judge: fix the file or its export");
            return false;
        }
        scene->warnings.push_back(why);
    }
    // Whatever a loader dropped or ignored is said, even with --quiet (it changes what is analysed).
    for (const std::string &w : scene->warnings) std::fprintf(stderr, "visaudit: warning: %s\n", w.c_str());
    bool handled = false;
    if (!o.views.empty() && !levelViews(o.views, *scene, views, &handled, &err)) {
        fail(err);
        return false;
    }
    if (!handled && !o.views.empty() && !levelSampleViews(o.views, *scene, views, &handled, &err, o.eyeHeight)) {
        fail(err);
        return false;
    }
    Route route;
    if (!handled && !o.views.empty() && !routeViewsFromSpec(o.views, *scene, o.maxJsonDepth, views, &route, &handled, &err)) {
        fail(err);
        return false;
    }
    if (handled && !route.keyframes.empty()) {
        // route:FILE: its frames
        if (routes) routes->push_back(std::move(route));
    } else if (handled) {
        // spawns, walk:N: the map's own views
    } else if (o.views.empty()) {
        *views = scene->views;
    } else if (o.views.rfind("orbit:", 0) == 0) {
        const std::string n = o.views.substr(6);
        char *end = nullptr;
        const long k = std::strtol(n.c_str(), &end, 10);
        if (n.empty() || *end || k < 1 || k > 100000) {
            fail("--views " + o.views + ": expected orbit:N with N a whole number from 1 to 100000, e.g. orbit:8");
            return false;
        }
        *views = orbitViews(*scene, int(k));
    } else if (!loadViewsFile(o.views, views, &err, o.maxJsonDepth)) {
        fail(err);
        return false;
    }
    // An explicit views file with no views is a mistake to report, not a reason to pick others.
    if (views->empty() && !o.views.empty()) {
        fail("--views " + o.views + ": the file has no views; give at least one view");
        return false;
    }
    if (views->empty()) {
        *views = orbitViews(*scene, 4);
        std::fprintf(stderr, "visaudit: %s has no views; using --views orbit:4\n",
                     o.scene.empty() ? "the demo" : o.scene.c_str());
    }
    return true;
}

bool parseDepthFormatList(const std::string &list, std::vector<DepthFormatSpec> *out, std::string *err) {
    std::vector<DepthFormatSpec> formats;
    if (list == "all") {
        formats.assign(allDepthFormats().begin(), allDepthFormats().end());
    } else {
        std::stringstream ss(list);
        std::string name;
        while (std::getline(ss, name, ',')) {
            DepthFormatSpec f;
            if (!parseDepthFormat(name, &f, err)) return false;
            if (std::find(formats.begin(), formats.end(), f) != formats.end()) {
                *err = "depth format '" + depthFormatName(f) + "' is listed twice; list it once";
                return false;
            }
            formats.push_back(f);
        }
    }
    if (formats.empty()) {
        *err = "no depth formats given; name at least one, e.g. f32,f32_reversed, or all";
        return false;
    }
    *out = std::move(formats);
    return true;
}

bool readJsonFile(const std::string &what, const std::string &path, uint64_t maxJsonDepth,
                  nlohmann::ordered_json *out, std::string *err) {
    std::string detail;
    switch (readJsonDocument(path, out, &detail, maxJsonDepth)) {
    case JsonRead::unreadable: *err = what + " " + path + ": cannot be read"; return false;
    case JsonRead::invalid: *err = what + " " + path + ": not valid JSON (" + detail + ")"; return false;
    case JsonRead::tooDeep: *err = what + " " + detail; return false;
    case JsonRead::ok: break;
    }
    return true;
}

void addJsonDepthOption(CLI::App *c, uint64_t &maxJsonDepth) {
    c->add_option("--max-json-depth", maxJsonDepth,
                  "Deepest nesting of arrays and objects accepted in a JSON input (default " +
                      std::to_string(kDefaultMaxJsonDepth) + "; at most " + std::to_string(json::kMaxJsonDepthCeiling) +
                      ")")
        ->check(CLI::Range(uint64_t(1), json::kMaxJsonDepthCeiling));
}

void addSceneOptions(CLI::App *c, SceneOptions &o) {
    c->add_option("scene", o.scene, "Scene file: .json (visaudit-scene/1), .obj .ply .off .stl, .gltf .glb; "
                                    "none = the built-in demo");
    c->add_option("--views", o.views, "Views: a views file (.json); orbit:N (N cameras around the scene); "
                                      "route:FILE[:N|:Ts] (a route file's keyframes, N frames, or a frame every T "
                                      "seconds); grid:N[:D] (N positions over the floor plan, D directions each, default 4); for a "
                                      "Quake 3 map, spawns (its spawn points), walk:N[:SEED] (N points inside its "
                                      "clusters) or clusters[:D] (one position per cluster)");
    c->add_option("--eye-height", o.eyeHeight,
                  "grid:N: the eye's height above the floor (default 50 on a Quake 3 map, else 1.7)")
        ->check(CLI::Range(0.0, 1e30));
    c->add_option("--patch-level", o.patchLevel, "Quake 3 maps: segments per Bezier patch edge")->check(CLI::Range(1, 64));
    c->add_option("--chunk", o.chunk, "Split meshes into culling objects of at most this many triangles")
        ->check(CLI::Range(1u, 1u << 30));
    c->add_option("--max-triangles", o.maxTriangles,
                  "Largest scene accepted, in triangles (default 100000000; at most 4294967295, the 32-bit ids)")
        ->check(CLI::Range(uint64_t(1), uint64_t(UINT32_MAX)));
    addJsonDepthOption(c, o.maxJsonDepth);
}

int commitOutput(OutputDir &out, const std::string &dir) {
    if (interrupted()) return interruptedExit(dir);
    std::string err;
    if (!out.commit(&err)) {
        fail(err);
        return kExitBadInput;
    }
    if (!err.empty()) std::fprintf(stderr, "visaudit: warning: %s\n", err.c_str());
    return kExitOk;
}

}  // namespace va
