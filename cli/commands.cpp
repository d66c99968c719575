// Subcommands: one table (ninja's kTools[]); --help and the README's command list come from it.
#include "cli/commands.h"

#include <atomic>
#include <chrono>
#include <cstdio>
#include <algorithm>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <sstream>
#include <mutex>
#include <string>
#include <vector>

#include <signal.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "analysis/load/demo.h"
#include "analysis/audits/depth_audit.h"
#include "common/json_util.h"
#include "analysis/load/level_views.h"
#include "common/limits.h"
#include "analysis/load/load.h"
#include "analysis/pipeline.h"
#include "analysis/audits/pvs_audit.h"
#include "reports/console.h"
#include "reports/depth_audit_report.h"
#include "reports/depth_plot.h"
#include "reports/budget.h"
#include "reports/grade.h"
#include "reports/html.h"
#include "reports/merge.h"
#include "reports/pvs_audit_report.h"
#include "reports/report.h"
#include "render/stopwatch.h"

namespace va {

namespace {

struct Options {
    bool refuseEmptyScene = false;  // check: a scene with no triangle is exit 2, not an empty pass
    std::string images = "all";     // --images all|key|none
    std::string scene;          // empty: the built-in demo
    std::string views;          // views file, "orbit:N", or empty (the scene's own)
    std::string out = "visaudit-report";
    std::string depthFormat;
    int width = 0, height = 0;
    int threads = 0;
    // Resource limits (docs/limits.md)
    int maxResolution = kDefaultMaxResolution;
    uint64_t maxTriangles = kDefaultMaxTriangles;
    uint64_t maxJsonDepth = kDefaultMaxJsonDepth;
    int maxRecursion = kDefaultMaxRecursion;
    uint32_t maxABufferList = kDefaultMaxABufferList;
    std::string maxMemory;  // empty: defaultMaxMemory()
    uint32_t chunk = 512;
    bool noBackface = false, noFrustum = false, noZFight = false, noAudit = false, noCells = false, noRaycast = false;
    int patchLevel = 5;
    bool noGrid = false, noOcclusion = false, noDetail = false, noOrdering = false;
    uint64_t orderingMaxTriangles = 200000;
    std::string painterKey = "centroid";
    double gridCell = 0, detailMinPixels = 4, detailTrianglesPerPixel = 1;
    uint32_t occluders = 16, portalDepth = 64;
    // Effects: unset = the scene decides.
    std::optional<bool> shadows, reflections, refractions, abuffer;
    int maxDepth = 4;
    uint64_t zfightMinArea = 1;
    std::string zfightFormats;  // --zfight-formats: comma-separated or "all"; empty = the classic twelve
    bool quiet = false;
    bool json = false;  // --json: the summary on stdout
    // depth-audit
    double nearZ = 0, farZ = 0;
    std::string formats;  // comma-separated; empty = all
    std::string auditOut; // empty = console only
    std::string auditScene; // depth-audit --scene
    std::string shard;    // analyze --shard K/N
    std::vector<std::string> mergeDirs;
    // check
    std::string budget, baseline, junit;
    // grade
    std::string reference, submission, tolerance, gradeOut;
    // pvs-audit (and check, when its budget names a pvs_* metric)
    PvsAuditSettings pvs;
    std::string pvsClusters;       // --clusters: "0-99,200"
    std::optional<double> pvsFar;  // --far-plane
    std::string pvsOut = "visaudit-pvs-audit";
};

void fail(const std::string &msg) { std::fprintf(stderr, "visaudit: error: %s\n", msg.c_str()); }

// SIGINT and SIGTERM: the handler only records the signal; the pipeline polls it between views
// and stages (PipelineSettings::cancel) and the commands before they write, so a stopped run
// leaves no half-written report and the old output folder as it was (docs/limits.md).
std::atomic<int> gInterrupt{0};
static_assert(std::atomic<int>::is_always_lock_free, "a signal handler may only touch lock-free atomics");

void onInterruptSignal(int sig) { gInterrupt.store(sig, std::memory_order_relaxed); }

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

// --max-memory, or the default (a fraction of the machine's memory).
bool memoryLimit(const Options &o, uint64_t *bytes) {
    if (o.maxMemory.empty()) {
        *bytes = defaultMaxMemory();
        return true;
    }
    std::string err;
    if (!parseByteSize(o.maxMemory, bytes, &err)) {
        fail("--max-memory: " + err);
        return false;
    }
    return true;
}

// Loads the scene (or makes the demo) and its views as the options say.
bool loadInputs(const Options &o, Scene *scene, std::vector<ViewSpec> *views) {
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
    if (handled) {
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

// "a,b,log24:C=0.01" or "all" into depth formats (in the order given); false + message on an
// unknown or repeated name.
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

bool makeSettings(const Options &o, PipelineSettings *s) {
    s->frustum = !o.noFrustum;
    s->backface = !o.noBackface;
    s->zfight = !o.noZFight;
    s->audit = !o.noAudit;
    s->cells = !o.noCells;
    s->grid = !o.noGrid;
    s->gridSettings.cellSize = o.gridCell;
    s->portals.maxDepth = o.portalDepth;
    s->occlusion = !o.noOcclusion;
    s->occlusionSettings.maxOccluders = o.occluders;
    s->detail = !o.noDetail;
    s->ordering = !o.noOrdering;
    s->orderingMaxTriangles = o.orderingMaxTriangles;
    s->orderingSettings.painterKey = o.painterKey == "nearest"    ? PainterKey::nearestVertex
                                     : o.painterKey == "farthest" ? PainterKey::farthestVertex
                                                                  : PainterKey::centroid;
    s->detailSettings.minPixels = o.detailMinPixels;
    s->detailSettings.trianglesPerPixel = o.detailTrianglesPerPixel;
    s->raycast = !o.noRaycast;
    s->effects.shadows = o.shadows;
    s->effects.reflections = o.reflections;
    s->effects.refractions = o.refractions;
    s->effects.abuffer = o.abuffer;
    s->effects.maxDepth = o.maxDepth;
    s->zfightSettings.minHotspotArea = o.zfightMinArea;
    s->width = o.width;
    s->height = o.height;
    s->threads = o.threads;
    s->limits.maxResolution = o.maxResolution;
    s->limits.maxRecursion = o.maxRecursion;
    s->limits.maxABufferList = o.maxABufferList;
    if (!memoryLimit(o, &s->limits.maxMemory)) return false;
    s->cancel = &gInterrupt;
    if (!o.zfightFormats.empty()) {
        std::string err;
        if (!parseDepthFormatList(o.zfightFormats, &s->zfightSettings.formats, &err)) {
            fail("--zfight-formats: " + err);
            return false;
        }
    }
    if (!o.depthFormat.empty()) {
        DepthFormatSpec f;
        std::string err;
        if (!parseDepthFormat(o.depthFormat, &f, &err)) {
            fail("--depth-format: " + err);
            return false;
        }
        s->depthFormat = f;
    }
    return true;
}

int cmdInfo(const Options &o) {
    Scene scene;
    std::vector<ViewSpec> views;
    if (!loadInputs(o, &scene, &views)) return kExitBadInput;
    if (o.json) {
        nlohmann::ordered_json j;
        j["scene"] = scene.path;
        j["triangles"] = scene.objectTriangles.size();
        j["source_triangles"] = scene.stats.sourceTriangles;
        j["degenerate_triangles"] = scene.stats.degenerateTriangles;
        j["non_finite_triangles"] = scene.stats.nonFiniteTriangles;
        j["faces_dropped"] = scene.stats.facesDropped;
        j["polygons_triangulated"] = scene.stats.polygonsTriangulated;
        j["objects"] = scene.sources.size();
        j["culling_objects"] = scene.objects.size();
        if (scene.bounds.empty())
            j["bounds"] = nullptr;
        else
            j["bounds"] = {{"min", {scene.bounds.lo.x, scene.bounds.lo.y, scene.bounds.lo.z}},
                           {"max", {scene.bounds.hi.x, scene.bounds.hi.y, scene.bounds.hi.z}}};
        j["up"] = std::string(1, scene.up);
        nlohmann::ordered_json mats = nlohmann::ordered_json::array();
        for (const Material &m : scene.materials)
            mats.push_back({{"name", m.name},
                            {"double_sided", m.doubleSided},
                            {"transparent", m.transparent()},
                            {"reflective", m.reflective > 0},
                            {"refractive", m.refractive()}});
        j["materials"] = mats;
        j["lights"] = scene.lights.size();
        nlohmann::ordered_json vs = nlohmann::ordered_json::array();
        for (const ViewSpec &v : views)
            vs.push_back({{"name", v.name},
                          {"width", v.camera.width},
                          {"height", v.camera.height},
                          {"projection", v.camera.orthographic ? "orthographic" : "perspective"},
                          {"eye", {v.camera.eye.x, v.camera.eye.y, v.camera.eye.z}},
                          {"depth_format", depthFormatName(v.depthFormat)}});
        j["views"] = vs;
        j["warnings"] = scene.warnings;
        std::printf("%s\n", j.dump(2).c_str());
        return kExitOk;
    }
    std::printf("scene       %s\n", scene.path.c_str());
    std::printf("triangles   %llu analysed of %llu in the source (%llu degenerate, %llu non-finite excluded)\n",
                (unsigned long long)scene.objectTriangles.size(), (unsigned long long)scene.stats.sourceTriangles,
                (unsigned long long)scene.stats.degenerateTriangles, (unsigned long long)scene.stats.nonFiniteTriangles);
    std::printf("faces       %llu dropped by the loaders, %llu polygons triangulated\n",
                (unsigned long long)scene.stats.facesDropped, (unsigned long long)scene.stats.polygonsTriangulated);
    std::printf("objects     %zu in the scene, %zu culling objects after chunking\n", scene.sources.size(),
                scene.objects.size());
    if (scene.bounds.empty())
        std::printf("bounds      (empty)\n");
    else
        std::printf("bounds      [%g, %g, %g] .. [%g, %g, %g]\n", scene.bounds.lo.x, scene.bounds.lo.y,
                    scene.bounds.lo.z, scene.bounds.hi.x, scene.bounds.hi.y, scene.bounds.hi.z);
    std::printf("up axis     %c\n", scene.up);
    std::printf("materials   %zu\n", scene.materials.size());
    for (const Material &m : scene.materials)
        std::printf("  %-16s%s%s%s%s\n", m.name.c_str(), m.doubleSided ? " double-sided" : "",
                    m.transparent() ? " transparent" : "", m.reflective > 0 ? " reflective" : "",
                    m.refractive() ? " refractive" : "");
    std::printf("lights      %zu\n", scene.lights.size());
    std::printf("views       %zu\n", views.size());
    for (const ViewSpec &v : views)
        std::printf("  %-16s%dx%d %s eye [%g, %g, %g] %s\n", v.name.c_str(), v.camera.width, v.camera.height,
                    v.camera.orthographic ? "ortho" : "persp", v.camera.eye.x, v.camera.eye.y, v.camera.eye.z,
                    depthFormatName(v.depthFormat).c_str());
    return kExitOk;
}

// Runs `analyze` as the options say and writes the report folder. `beforeRun` (optional) sees the
// views after loading and may refuse them (check validates its budget there, before any work) or
// add to the settings (check: the depth formats its budget names); `afterRun` (optional) gets the
// scene and the staging folder once the views are analysed, before the report is written, and
// returns an exit code (check runs the PVS audit there); `report` receives the report JSON.
// Returns an exit code.
using AfterRun = std::function<int(const Scene &, const std::string &staging)>;
int analyzeToReport(const Options &o,
                    const std::function<bool(const std::vector<ViewSpec> &, PipelineSettings *, std::string *)> &beforeRun,
                    nlohmann::ordered_json *report, const AfterRun &afterRun = nullptr) {
    using Clock = std::chrono::steady_clock;
    const auto t0 = Clock::now();  // progress lines (real time)
    const Stopwatch loadTime;       // the report's load_ms
    installInterruptHandlers();
    PipelineSettings settings;
    if (!makeSettings(o, &settings)) return kExitBadInput;
    Scene scene;
    std::vector<ViewSpec> views;
    if (!loadInputs(o, &scene, &views)) return kExitBadInput;
    if (interrupted()) return interruptedExit(o.out);
    const double loadMs = loadTime.ms();

    std::string err;
    // Image names are fixed over the full view list before any selection or parallel run, so
    // colliding view names stay distinct and every shard names a view's images the same way.
    const std::vector<std::string> allBases = imageBaseNames(views);
    AnalysisResult result;
    result.shard.viewsTotal = views.size();
    std::vector<size_t> indices;  // positions in the full list of the views this run analyses
    if (!o.shard.empty()) {
        if (!parseShard(o.shard, &result.shard.index, &result.shard.count, &err)) {
            fail(err);
            return kExitBadInput;
        }
        for (size_t i = size_t(result.shard.index - 1); i < views.size(); i += size_t(result.shard.count))
            indices.push_back(i);
    } else {
        for (size_t i = 0; i < views.size(); ++i) indices.push_back(i);
    }
    std::vector<ViewSpec> selected;
    std::vector<std::string> bases;
    for (size_t i : indices) {
        selected.push_back(views[i]);
        bases.push_back(allBases[i]);
    }
    views = std::move(selected);
    if (beforeRun && !beforeRun(views, &settings, &err)) {
        fail(err);
        return kExitBadInput;
    }

    OutputDir out;
    if (!out.open(o.out, &err)) {
        fail(err);
        return kExitBadInput;
    }
    setImageThreads(o.threads);
    const bool tty = isatty(fileno(stderr));
    std::atomic<int> done{0};
    std::mutex printMutex;
    std::vector<double> imagesMs(views.size(), 0.0);  // per view: each slot written by one worker
    const ImageSet imageSet = o.images == "none" ? ImageSet::none : o.images == "key" ? ImageSet::key : ImageSet::all;
    auto onView = [&](size_t i, ViewResult &v, std::string *e) {
        v.index = indices[i];
        v.imageBase = bases[i];
        const Stopwatch w0;
        if (!writeViewImages(v, out.staging(), bases[i], e, imageSet)) return false;
        imagesMs[i] = w0.ms();
        releasePixelBuffers(v);  // the images hold them now
        const int k = ++done;
        if (!o.quiet) {
            // A terminal gets one line rewritten in place with an estimate of the time left; a log
            // (CI) gets one plain line per view.
            std::lock_guard<std::mutex> lock(printMutex);
            const double elapsed = std::chrono::duration<double>(Clock::now() - t0).count();
            const double eta = elapsed / k * double(views.size() - size_t(k));
            if (tty)
                std::fprintf(stderr, "\r\033[K[%d/%zu] %s (%.1f s, about %.0f s left)", k, views.size(),
                             v.spec.name.c_str(), elapsed, eta);
            else
                std::fprintf(stderr, "[%d/%zu] %s %.1f ms\n", k, views.size(), v.spec.name.c_str(), v.totalMs);
        }
        return true;
    };
    if (!analyzeScene(scene, views, settings, onView, &result, &err)) {
        if (tty && !o.quiet) std::fprintf(stderr, "\n");
        // out's destructor removes the staging folder; the target was never touched.
        if (interrupted()) return interruptedExit(o.out);
        fail(err);
        return kExitBadInput;
    }
    if (tty && !o.quiet) std::fprintf(stderr, "\n");
    if (afterRun)
        if (const int code = afterRun(scene, out.staging()); code != kExitOk) return code;
    result.loadMs = loadMs;
    OutputTimings outputMs;
    for (double ms : imagesMs) outputMs.imagesMs += ms;
    const Stopwatch r0;
    *report = reportJson(result, imageSet);
    outputMs.reportMs = r0.ms();
    // A failure to write (disk full, read-only folder) is the output location's problem: exit 2
    // with the path, and the previous report stays as it was. A signal is honoured up to the
    // commit; the swap itself is not interrupted (the handler only sets a flag), and a run whose
    // report is in place has finished. report.html is written first so that report.json can say
    // how long it took.
    const Stopwatch h0;
    if (!writeReportHtml(*report, out.staging(), &err)) {
        fail(err);
        return kExitBadInput;
    }
    outputMs.htmlMs = h0.ms();
    addOutputTimings(report, outputMs);
    if (!writeFileAtomic(out.staging() + "/report.json", report->dump(2) + "\n", &err)) {
        fail(err);
        return kExitBadInput;
    }
    if (interrupted()) return interruptedExit(o.out);
    if (!out.commit(&err)) {
        fail(err);
        return kExitBadInput;
    }
    if (!err.empty()) std::fprintf(stderr, "visaudit: warning: %s\n", err.c_str());
    if (o.json) {
        // For piping: the summary as one JSON document on stdout (the report minus nothing but
        // per-stage detail: name, funnel and z-buffer summary per view, and the totals).
        nlohmann::ordered_json summary;
        summary["report"] = o.out + "/report.json";
        summary["scene"] = (*report)["scene"];
        nlohmann::ordered_json vs = nlohmann::ordered_json::array();
        for (const auto &v : (*report)["views"]) {
            nlohmann::ordered_json sv;
            sv["name"] = v["name"];
            nlohmann::ordered_json funnel = nlohmann::ordered_json::array();
            for (const auto &st : v["stages"])
                funnel.push_back({{"name", st["name"]}, {"ran", st["ran"]}, {"triangles_in", st["triangles_in"]},
                                  {"triangles_culled", st["triangles_culled"]}, {"triangles_out", st["triangles_out"]}});
            sv["stages"] = funnel;
            sv["zbuffer"] = v["zbuffer"];
            sv["zbuffer"].erase("histogram");
            vs.push_back(sv);
        }
        summary["views"] = vs;
        summary["totals"] = (*report)["totals"];
        std::printf("%s\n", summary.dump(2).c_str());
    } else if (!o.quiet) {
        for (const ViewResult &v : result.views) std::printf("%s\n", funnelTable(v).c_str());
        std::printf("report: %s/report.json\n", o.out.c_str());
    }
    return kExitOk;
}

int cmdAnalyze(const Options &o) {
    nlohmann::ordered_json report;
    return analyzeToReport(o, nullptr, &report);
}

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

// The audit's settings from the options (pvs-audit's flags; check uses the defaults).
bool pvsSettings(const Options &o, PvsAuditSettings *s) {
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

// Runs the audit on a loaded scene and writes its three files into `dir`; exit code.
int runPvsAudit(const Options &o, const Scene &scene, const PvsAuditSettings &settings, const std::string &dir,
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
    const bool ok = auditPvs(scene, s, result, &err);
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

int cmdPvsAudit(const Options &o) {
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
    setImageThreads(o.threads);
    PvsAuditResult result;
    nlohmann::ordered_json json;
    const int code = runPvsAudit(o, scene, settings, out.staging(), o.pvsOut, &result, &json);
    if (code != kExitOk) return code;
    if (interrupted()) return interruptedExit(o.pvsOut);
    if (!out.commit(&err)) {
        fail(err);
        return kExitBadInput;
    }
    if (!err.empty()) std::fprintf(stderr, "visaudit: warning: %s\n", err.c_str());
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

void addPvsAuditOptions(CLI::App *c, Options &o) {
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

int cmdCheck(const Options &in) {
    Options o = in;
    o.refuseEmptyScene = true;
    Budget budget;
    nlohmann::ordered_json baseline;
    std::string err;
    if (!o.baseline.empty()) {
        std::string detail;
        const JsonRead r = readJsonDocument(o.baseline, &baseline, &detail, o.maxJsonDepth);
        if (r == JsonRead::unreadable) {
            fail("--baseline " + o.baseline + ": cannot be read; give the report.json of an earlier analyze run");
            return kExitBadInput;
        }
        if (r == JsonRead::invalid) {
            fail("--baseline " + o.baseline + ": not valid JSON (" + detail + ")");
            return kExitBadInput;
        }
        if (r == JsonRead::tooDeep) {
            fail("--baseline " + detail);
            return kExitBadInput;
        }
    }
    // The budget is validated against the views before anything is analysed.
    auto validate = [&](const std::vector<ViewSpec> &views, PipelineSettings *s, std::string *e) {
        std::vector<std::string> names;
        for (const ViewSpec &v : views) names.push_back(v.name);
        if (!loadBudget(o.budget, names, &budget, e, o.maxJsonDepth)) return false;
        // The formats its min_depth_format limits name join the z-fighting analysis (opt-in ones too).
        for (const DepthFormatSpec &f : budgetDepthFormats(budget))
            if (std::find(s->zfightSettings.formats.begin(), s->zfightSettings.formats.end(), f) ==
                s->zfightSettings.formats.end())
                s->zfightSettings.formats.push_back(f);
        return true;
    };
    // A budget naming pvs_* runs the PVS audit on the map too; its files go next to report.json.
    nlohmann::ordered_json pvsAudit;
    auto pvs = [&](const Scene &scene, const std::string &staging) {
        if (!budgetNeedsPvsAudit(budget)) return int(kExitOk);
        if (const char *why = pvsAuditSkipReason(scene)) {
            fail("--budget " + o.budget + " names a pvs_* metric, which needs the PVS audit: " + scene.path + ": " + why +
                 "; check a Quake 3 map, or leave pvs_* out of the budget");
            return int(kExitBadInput);
        }
        PvsAuditSettings s;
        if (!pvsSettings(o, &s)) return int(kExitBadInput);
        PvsAuditResult r;
        return runPvsAudit(o, scene, s, staging, o.out, &r, &pvsAudit);
    };
    nlohmann::ordered_json report;
    const int code = analyzeToReport(o, validate, &report, pvs);
    if (code != kExitOk) return code;
    BudgetResult result;
    if (!evaluateBudget(budget, report, o.baseline.empty() ? nullptr : &baseline, &result, &err)) {
        fail(err);
        return kExitBadInput;
    }
    if (budgetNeedsPvsAudit(budget)) {
        // The baseline's audit: pvs-audit.json next to the baseline's report.json (absent: no baseline).
        nlohmann::ordered_json basePvs;
        bool haveBase = false;
        if (!o.baseline.empty()) {
            const std::string p = (std::filesystem::path(o.baseline).parent_path() / "pvs-audit.json").string();
            haveBase = readJsonDocument(p, &basePvs, nullptr) == JsonRead::ok;
        }
        if (!evaluatePvsBudget(budget, pvsAudit, haveBase ? &basePvs : nullptr, &result, &err)) {
            fail(err);
            return kExitBadInput;
        }
    }
    std::printf("%s", budgetTable(result).c_str());
    if (!o.junit.empty() && !writeFileAtomic(o.junit, budgetJUnit(result, report["scene"]["path"]), &err)) {
        fail(err);
        return kExitBadInput;
    }
    return result.failed ? kExitBudgetFailed : kExitOk;
}

void addAnalyzeOptions(CLI::App *c, Options &o);

void addCheckOptions(CLI::App *c, Options &o) {
    addAnalyzeOptions(c, o);
    c->add_option("--budget", o.budget, "Budget file (visaudit-budget/1): limits per scene and per view")->required();
    c->add_option("--baseline", o.baseline, "An earlier report.json: fail on relative regressions the budget forbids");
    c->add_option("--junit", o.junit, "Write JUnit XML here: one test case per view and budget");
}

// Reads a JSON file for grade/check; false + message naming the file.
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

int cmdGrade(const Options &o) {
    std::string err;
    nlohmann::ordered_json ref, sub;
    ToleranceRules tol;
    if (!readJsonFile("--reference", o.reference, o.maxJsonDepth, &ref, &err) ||
        !readJsonFile("--submission", o.submission, o.maxJsonDepth, &sub, &err) ||
        (!o.tolerance.empty() && !loadTolerances(o.tolerance, &tol, &err, o.maxJsonDepth))) {
        fail(err);
        return kExitBadInput;
    }
    GradeResult g;
    if (!gradeReports(ref, sub, tol, &g, &err)) {
        fail(err);
        return kExitBadInput;
    }
    std::printf("%s", gradeTable(g).c_str());
    if (!o.gradeOut.empty() && !writeFileAtomic(o.gradeOut, gradeJson(g).dump(2) + "\n", &err)) {
        fail(err);
        return kExitBadInput;
    }
    return g.failed ? kExitBudgetFailed : kExitOk;
}

// --max-json-depth: every command that reads JSON (docs/limits.md, "JSON nesting").
void addJsonDepthOption(CLI::App *c, Options &o) {
    c->add_option("--max-json-depth", o.maxJsonDepth,
                  "Deepest nesting of arrays and objects accepted in a JSON input (default " +
                      std::to_string(kDefaultMaxJsonDepth) + "; at most " + std::to_string(json::kMaxJsonDepthCeiling) +
                      ")")
        ->check(CLI::Range(uint64_t(1), json::kMaxJsonDepthCeiling));
}

void addGradeOptions(CLI::App *c, Options &o) {
    c->add_option("--reference", o.reference, "The reference report.json")->required();
    c->add_option("--submission", o.submission, "The student's report.json (the same keys)")->required();
    c->add_option("--tolerance", o.tolerance, "Tolerances per metric (visaudit-tolerance/1)");
    c->add_option("--out", o.gradeOut, "Write the result as JSON here");
    addJsonDepthOption(c, o);
}

int cmdMerge(const Options &o) {
    installInterruptHandlers();
    std::string err;
    OutputDir out;
    if (!out.open(o.out, &err)) {
        fail(err);
        return kExitBadInput;
    }
    nlohmann::ordered_json merged;
    if (!mergeReports(o.mergeDirs, out.staging(), &merged, &err, o.maxJsonDepth)) {
        fail(err);
        return kExitBadInput;
    }
    if (!writeFileAtomic(out.staging() + "/report.json", merged.dump(2) + "\n", &err) ||
        !writeReportHtml(merged, out.staging(), &err)) {
        fail(err);
        return kExitBadInput;
    }
    if (interrupted()) return interruptedExit(o.out);
    if (!out.commit(&err)) {
        fail(err);
        return kExitBadInput;
    }
    if (!err.empty()) std::fprintf(stderr, "visaudit: warning: %s\n", err.c_str());
    if (!o.quiet)
        std::printf("merged %zu shards, %zu views: %s/report.json\n", o.mergeDirs.size(), merged["views"].size(),
                    o.out.c_str());
    return kExitOk;
}

void addMergeOptions(CLI::App *c, Options &o) {
    c->add_option("shards", o.mergeDirs, "The --out folders of every analyze --shard K/N run")->required();
    c->add_option("--out", o.out, "Output folder for the merged report (written as a whole or not at all)");
    c->add_flag("--quiet", o.quiet, "No summary on the console");
    addJsonDepthOption(c, o);
}

// depth-audit --scene: the per-view z-fighting analysis over a scene's views, with the formats'
// verdicts and the recommendation per view (no images, no report folder).
int depthAuditScene(const Options &o, const std::vector<DepthFormatSpec> &formats) {
    Options lo = o;
    lo.scene = o.auditScene;
    installInterruptHandlers();
    Scene scene;
    std::vector<ViewSpec> views;
    if (!loadInputs(lo, &scene, &views)) return kExitBadInput;
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
    std::printf("z-fighting per view of %s (pixels whose two nearest surfaces fight; coplanar ones in brackets)\n",
                scene.path.c_str());
    for (const ViewResult &v : result.views) {
        const ZFightResult &z = v.zfight;
        std::printf("view '%s' %dx%d, near %g, far %g, its format %s: %llu hotspots\n", v.spec.name.c_str(),
                    v.camera.width, v.camera.height, v.camera.nearZ, v.camera.farZ,
                    depthFormatName(v.spec.depthFormat).c_str(), (unsigned long long)z.hotspotCount);
        for (const ZFightFormatStats &f : z.perFormat)
            std::printf("  %-18s %2d bits %10llu fighting [%llu]%s\n", f.name.c_str(), f.bits,
                        (unsigned long long)f.fightingPixels, (unsigned long long)f.coplanarPixels,
                        z.recommended && *z.recommended == f.format ? "   <- recommended" : "");
        for (size_t k = 0; k < z.hotspots.size() && k < 3; ++k) {
            const ZFightHotspot &h = z.hotspots[k];
            std::printf("  hotspot %u: %llu px at world (%.3g, %.3g, %.3g), '%s' vs '%s', gap %.3g\n", h.id,
                        (unsigned long long)h.area, h.centroid.x, h.centroid.y, h.centroid.z, h.objectA.c_str(),
                        h.objectB.c_str(), h.depthGap);
            std::printf("    why: %s\n", h.why.c_str());
        }
        std::printf("  %s\n", z.recommendation.c_str());
    }
    return kExitOk;
}

int cmdDepthAudit(const Options &o) {
    std::string err;
    const bool range = o.nearZ != 0 || o.farZ != 0;
    if (!range && o.auditScene.empty()) {
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
    if (!o.auditScene.empty()) return depthAuditScene(o, formats);
    return kExitOk;
}

void addDepthAuditOptions(CLI::App *c, Options &o) {
    c->add_option("--near", o.nearZ, "Near plane distance (> 0)");
    c->add_option("--far", o.farZ, "Far plane distance (> near)");
    c->add_option("--scene", o.auditScene, "Also analyse this scene's views: per view, where each format z-fights "
                                           "and the recommended format");
    c->add_option("--views", o.views, "With --scene: a views file, orbit:N, spawns or walk:N");
    c->add_option("--formats", o.formats, "Comma-separated depth formats, log24:C=X for log24 with constant C, or "
                                          "all (default: all)");
    c->add_option("--out", o.auditOut, "Folder for depth-audit.json and depth-audit.png");
    addJsonDepthOption(c, o);
}

void addSceneOptions(CLI::App *c, Options &o) {
    c->add_option("scene", o.scene, "Scene file: .json (visaudit-scene/1), .obj .ply .off .stl, .gltf .glb; "
                                    "none = the built-in demo");
    c->add_option("--views", o.views, "Views: a views file (.json); orbit:N (N cameras around the scene); for a "
                                      "Quake 3 map, spawns (its spawn points) or walk:N[:SEED] (N points inside its clusters)");
    c->add_option("--patch-level", o.patchLevel, "Quake 3 maps: segments per Bezier patch edge")->check(CLI::Range(1, 64));
    c->add_option("--chunk", o.chunk, "Split meshes into culling objects of at most this many triangles")
        ->check(CLI::Range(1u, 1u << 30));
    c->add_option("--max-triangles", o.maxTriangles,
                  "Largest scene accepted, in triangles (default 100000000; at most 4294967295, the 32-bit ids)")
        ->check(CLI::Range(uint64_t(1), uint64_t(UINT32_MAX)));
    addJsonDepthOption(c, o);
}

void addInfoOptions(CLI::App *c, Options &o) {
    addSceneOptions(c, o);
    c->add_flag("--json", o.json, "Print the summary as JSON on stdout (the same fields; for scripts and tests)");
}

void addAnalyzeOptions(CLI::App *c, Options &o) {
    addSceneOptions(c, o);
    c->add_option("--out", o.out, "Output folder (written as a whole or not at all)");
    c->add_option("--images", o.images,
                  "Images written: all (default), key (per view the depth, overdraw, z-fighting and culling PNGs the "
                  "page shows first), none (numbers only: report.json and report.html)")
        ->check(CLI::IsMember({"all", "key", "none"}));
    c->add_option("--width", o.width, "Override every view's width in pixels")->check(CLI::Range(1, 1 << 30));
    c->add_option("--height", o.height, "Override every view's height in pixels")->check(CLI::Range(1, 1 << 30));
    c->add_option("--depth-format", o.depthFormat,
                  "Override every view's depth format (e.g. f32, unorm24, f32_reversed, log24:C=0.001)");
    c->add_option("--threads", o.threads, "Worker threads (0 = all cores)")->check(CLI::Range(0, 4096));
    c->add_option("--max-resolution", o.maxResolution, "Largest width or height accepted (default 16384)")
        ->check(CLI::Range(1, 1 << 20));
    c->add_option("--max-recursion", o.maxRecursion,
                  "Deepest --max-depth accepted when reflection or refraction rays are traced (default 16; "
                  "at most 255)")
        ->check(CLI::Range(0, 255));
    c->add_option("--max-abuffer-list", o.maxABufferList, "Most fragments in one pixel's A-buffer list (default 1024)")
        ->check(CLI::Range(1u, UINT32_MAX - 1));
    c->add_option("--max-memory", o.maxMemory,
                  "Most memory the analysis may need at its peak, estimated before it starts: bytes or K/M/G/T "
                  "(default three quarters of the RAM or the container's limit; 0 = no check)");
    c->add_flag("--no-backface", o.noBackface, "Turn the backface stage off");
    c->add_flag("--no-frustum", o.noFrustum, "Turn the frustum stage off");
    c->add_flag("--no-zfight", o.noZFight, "Turn the z-fighting analysis off");
    c->add_flag("--no-audit", o.noAudit, "Turn the reference-visibility audit (false culls, wasted draws) off");
    c->add_flag("--no-cells", o.noCells, "Turn the cells stage (a map's PVS, portals) off");
    c->add_flag("--no-grid", o.noGrid, "Turn the grid stage (scenes without cells) off");
    c->add_option("--grid-cell", o.gridCell, "Grid cell size in world units (0 = about one cell per 8 objects)")
        ->check(CLI::Range(0.0, 1e30));
    c->add_option("--portal-depth", o.portalDepth, "Most portals along one path of the portal traversal")
        ->check(CLI::Range(1u, 100000u));
    c->add_flag("--no-occlusion", o.noOcclusion, "Turn the occlusion stage off");
    c->add_option("--occluders", o.occluders, "Occluders drawn in the occlusion pre-pass")->check(CLI::Range(0u, 100000u));
    c->add_flag("--no-detail", o.noDetail, "Turn the detail audit off");
    c->add_option("--painter-key", o.painterKey, "Painter's algorithm sort key: centroid, nearest or farthest (vertex)")
        ->check(CLI::IsMember({"centroid", "nearest", "farthest"}));
    c->add_flag("--no-ordering", o.noOrdering, "Turn the draw-order audit (painter's, BSP tree, scanline, A-buffer) off");
    c->add_option("--ordering-max-triangles", o.orderingMaxTriangles,
                  "Largest scene the draw-order audit runs on (its BSP tree can grow quadratically)")
        ->check(CLI::Range(uint64_t(0), uint64_t(1) << 40));
    c->add_option("--detail-min-pixels", o.detailMinPixels, "Detail audit: objects projected smaller are too small")
        ->check(CLI::Range(0.0, 1e9));
    c->add_option("--detail-triangles-per-pixel", o.detailTrianglesPerPixel,
                  "Detail audit: more triangles than visible pixels times this is over-detailed")
        ->check(CLI::Range(1e-9, 1e9));
    c->add_flag("--no-raycast", o.noRaycast, "Turn the raycast stage (Embree cross-check, secondary rays) off");
    // Effects: the scene decides (lights, reflective, refractive, transparent materials); a flag forces.
    auto effect = [&](const char *on, const char *off, std::optional<bool> &v, const char *what) {
        c->add_flag_callback(on, [&v] { v = true; }, std::string("Force ") + what + " on");
        c->add_flag_callback(off, [&v] { v = false; }, std::string("Force ") + what + " off");
    };
    effect("--shadows", "--no-shadows", o.shadows, "shadow rays");
    effect("--reflections", "--no-reflections", o.reflections, "reflection rays");
    effect("--refractions", "--no-refractions", o.refractions, "refraction rays");
    effect("--abuffer", "--no-abuffer", o.abuffer, "the A-buffer");
    c->add_option("--max-depth", o.maxDepth, "Deepest secondary ray (reflection/refraction recursion)")
        ->check(CLI::Range(0, 255));
    c->add_option("--zfight-formats", o.zfightFormats,
                  "Depth formats the z-fighting analysis evaluates per view: comma-separated, or all (default: the "
                  "twelve classic formats; each view's own format is always added)");
    c->add_option("--zfight-min-area", o.zfightMinArea, "Smallest hotspot, in pixels (smaller clusters still count as fighting pixels)")
        ->check(CLI::Range(uint64_t(1), uint64_t(1) << 40));
    c->add_flag("--quiet", o.quiet, "No progress or summary on the console");
    c->add_flag("--json", o.json, "Print the summary as JSON on stdout (for piping); progress stays on stderr");
    c->add_option("--shard", o.shard, "Analyse only shard K of N: the views whose index i has i % N == K - 1 "
                                      "(join the shards with visaudit merge)");
}

struct Command {
    const char *name;
    const char *help;
    void (*setup)(CLI::App *, Options &);
    int (*run)(const Options &);
};

const Command kCommands[] = {
    {"info", "Summarize a scene: triangles, objects, bounds, materials, views, degenerate faces", addInfoOptions,
     cmdInfo},
    {"analyze", "Run every stage for every view; write report.json and images to --out", addAnalyzeOptions,
     cmdAnalyze},
    {"check", "Analyze, then fail (exit 1) when a view exceeds its budget or regresses against a baseline",
     addCheckOptions, cmdCheck},
    {"grade", "Score a student's per-stage counts against a reference report (exit 1 on any failure)",
     addGradeOptions, cmdGrade},
    {"merge", "Join the reports of analyze --shard K/N runs into one report", addMergeOptions, cmdMerge},
    {"depth-audit", "Per depth format: resolution against distance, distinct values, from where 1 cm / 1 mm can fight",
     addDepthAuditOptions, cmdDepthAudit},
    {"pvs-audit", "Audit every cluster of a Quake 3 map's PVS: clusters seen yet hidden (misses), visible yet never seen "
                  "(slack)",
     addPvsAuditOptions, cmdPvsAudit},
};

// Levenshtein distance, for "did you mean" suggestions.
size_t editDistance(const std::string &a, const std::string &b) {
    std::vector<size_t> prev(b.size() + 1), cur(b.size() + 1);
    for (size_t j = 0; j <= b.size(); ++j) prev[j] = j;
    for (size_t i = 1; i <= a.size(); ++i) {
        cur[0] = i;
        for (size_t j = 1; j <= b.size(); ++j)
            cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] != b[j - 1])});
        std::swap(prev, cur);
    }
    return prev[b.size()];
}

}  // namespace

int runCli(int argc, char **argv) {
    // An unknown command gets ninja's treatment: name it, and suggest the nearest one.
    if (argc > 1 && argv[1][0] != '-') {
        const std::string name = argv[1];
        const Command *best = nullptr;
        size_t bestDistance = 3;  // suggest only close matches
        bool known = false;
        for (const Command &c : kCommands) {
            known |= name == c.name;
            const size_t d = editDistance(name, c.name);
            if (d < bestDistance) bestDistance = d, best = &c;
        }
        if (!known) {
            std::string msg = "unknown command '" + name + "'";
            if (best) msg += ", did you mean '" + std::string(best->name) + "'?";
            msg += " (commands:";
            for (const Command &c : kCommands) msg += std::string(" ") + c.name;
            fail(msg + "; see visaudit --help)");
            return kExitBadInput;
        }
    }
    CLI::App app{"visaudit " VISAUDIT_VERSION " - scene-visibility analyzer and report generator"};
    app.set_version_flag("--version", "visaudit " VISAUDIT_VERSION);
    app.require_subcommand(1);
    Options opt;
    std::vector<std::pair<CLI::App *, const Command *>> subs;
    for (const Command &c : kCommands) {
        CLI::App *s = app.add_subcommand(c.name, c.help);
        c.setup(s, opt);
        subs.push_back({s, &c});
    }
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError &e) {
        const int code = app.exit(e);
        return code == 0 ? kExitOk : kExitBadInput;
    }
    try {
        for (auto &[s, c] : subs)
            if (s->parsed()) return c->run(opt);
    } catch (const std::bad_alloc &) {
        fail("out of memory; lower the resolution or the number of views");
        return kExitInternal;
    } catch (const std::exception &e) {
        fail(std::string("internal error: ") + e.what());
        return kExitInternal;
    }
    return kExitBadInput;
}

}  // namespace va
