// visaudit analyze (every stage for every view, the report folder) and visaudit check (analyze, then
// the budget: exit 1 when a view exceeds it or regresses against a baseline).
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <unistd.h>

#include <nlohmann/json.hpp>

#include "analysis/level_map.h"
#include "analysis/pipeline.h"
#include "cli/cmd_pvs_audit.h"
#include "cli/command_table.h"
#include "cli/commands.h"
#include "cli/shared.h"
#include "reports/budget.h"
#include "reports/console.h"
#include "reports/html.h"
#include "reports/level_maps.h"
#include "reports/merge.h"
#include "reports/report.h"
#include "reports/routes.h"
#include "render/stopwatch.h"

namespace va {
namespace {

struct AnalyzeOptions : SceneOptions {
    std::string images = "all";  // --images all|key|none
    std::string levelMaps = "auto";  // --level-maps auto|on|off
    int mapSize = 768;               // --map-size
    std::string out = "visaudit-report";
    std::string depthFormat;
    int width = 0, height = 0;
    int threads = 0;
    // Resource limits (docs/limits.md)
    int maxResolution = kDefaultMaxResolution;
    int maxRecursion = kDefaultMaxRecursion;
    uint32_t maxABufferList = kDefaultMaxABufferList;
    std::string maxMemory;  // empty: defaultMaxMemory()
    bool noBackface = false, noFrustum = false, noZFight = false, noAudit = false, noCells = false, noRaycast = false;
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
    std::string shard;  // --shard K/N
};

struct CheckOptions : AnalyzeOptions {
    std::string budget, baseline, junit;
};

void addAnalyzeOptions(CLI::App *c, AnalyzeOptions &o);

// --max-memory, or the default (a fraction of the machine's memory).
bool memoryLimit(const AnalyzeOptions &o, uint64_t *bytes) {
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


// Whether the run draws level maps: "on", "off", or "auto": when every view is a level sample
// (walk:N, grid:N, clusters), the view sets made to cover a level.
bool wantLevelMaps(const std::string &mode, const std::vector<ViewSpec> &views) {
    if (mode == "on") return !views.empty();
    if (mode == "off" || views.empty()) return false;
    for (const ViewSpec &v : views)
        if (v.origin.rfind("walk:", 0) != 0 && v.origin.rfind("grid:", 0) != 0 && v.origin.rfind("clusters", 0) != 0)
            return false;
    return true;
}

bool makeSettings(const AnalyzeOptions &o, PipelineSettings *s) {
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

// Runs `analyze` as the options say and writes the report folder. `beforeRun` (optional) sees the
// views after loading and may refuse them (check validates its budget there, before any work) or
// add to the settings (check: the depth formats its budget names); `afterRun` (optional) gets the
// scene and the staging folder once the views are analysed, before the report is written, and
// returns an exit code (check runs the PVS audit there); `report` receives the report JSON.
// Returns an exit code.
using AfterRun = std::function<int(const Scene &, const std::string &staging)>;
int analyzeToReport(const AnalyzeOptions &o,
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
    std::vector<Route> routes;
    if (!loadInputs(o, &scene, &views, &routes)) return kExitBadInput;
    if (interrupted()) return interruptedExit(o.out);
    const double loadMs = loadTime.ms();
    const bool levelMaps = wantLevelMaps(o.levelMaps, views);  // decided on every view, before --shard

    std::string err;
    // Image names are fixed over the full view list before any selection or parallel run, so
    // colliding view names stay distinct and every shard names a view's images the same way.
    const std::vector<std::string> allBases = imageBaseNames(views);
    AnalysisResult result;
    result.shard.viewsTotal = views.size();
    result.routes = std::move(routes);
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
    // Level maps (docs/level-maps.md): for views that cover the level (walk:N, grid:N, clusters), or
    // any views with --level-maps on. The floor plan is rendered once, before the views.
    if (levelMaps) {
        FloorPlanSettings fs;
        fs.size = o.mapSize;
        fs.eyeHeight = o.eyeHeight;
        FloorPlan plan;
        if (!renderFloorPlan(scene, fs, &plan, &err)) {
            fail(err + " (--level-maps)");
            return kExitBadInput;
        }
        result.floorPlan = std::move(plan);
    }
    if (beforeRun && !beforeRun(views, &settings, &err)) {
        fail(err);
        return kExitBadInput;
    }

    OutputDir out;
    if (!out.open(o.out, &err)) {
        fail(err);
        return kExitBadInput;
    }
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
        v.releasePixelBuffers();  // the images hold them now
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
    // The report's own pictures -- a route's plot (route-NAME.png), the level maps -- are a few
    // files whatever --images says (it chooses the views' images): a level-map run of thousands of
    // views writes its maps without a PNG per view.
    if (!writeRoutePlots(report, out.staging(), &err) ||
        (result.floorPlan && (!writeFloorPlanPng(*result.floorPlan, out.staging(), &err) ||
                              !writeLevelMapImages(report, out.staging(), &err)))) {
        fail(err);
        return kExitBadInput;
    }
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
    if (const int code = commitOutput(out, o.out); code != kExitOk) return code;
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

int cmdAnalyze(const AnalyzeOptions &o) {
    nlohmann::ordered_json report;
    return analyzeToReport(o, nullptr, &report);
}

int cmdCheck(const CheckOptions &in) {
    CheckOptions o = in;
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
        // pvs-audit's defaults, with check's threads and console.
        PvsAuditOptions po;
        po.threads = o.threads;
        po.quiet = o.quiet;
        PvsAuditSettings s;
        if (!pvsSettings(po, &s)) return int(kExitBadInput);
        PvsAuditResult r;
        return runPvsAudit(po, scene, s, staging, o.out, &r, &pvsAudit);
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

void addCheckOptions(CLI::App *c, CheckOptions &o) {
    addAnalyzeOptions(c, o);
    c->add_option("--budget", o.budget, "Budget file (visaudit-budget/1): limits per scene and per view")->required();
    c->add_option("--baseline", o.baseline, "An earlier report.json: fail on relative regressions the budget forbids");
    c->add_option("--junit", o.junit, "Write JUnit XML here: one test case per view and budget");
}

void addAnalyzeOptions(CLI::App *c, AnalyzeOptions &o) {
    addSceneOptions(c, o);
    c->add_option("--out", o.out, "Output folder (written as a whole or not at all)");
    c->add_option("--images", o.images,
                  "Images written per view: all (default), key (the depth, overdraw, z-fighting and culling PNGs the "
                  "page shows first), none (numbers only; route plots and level maps are still drawn)")
        ->check(CLI::IsMember({"all", "key", "none"}));
    c->add_option("--level-maps", o.levelMaps,
                  "Top-down level maps of triangles drawn, overdraw, wasted draws and false culls per position: auto "
                  "(default: for walk:N, grid:N and clusters), on (any views), off")
        ->check(CLI::IsMember({"auto", "on", "off"}));
    c->add_option("--map-size", o.mapSize, "Level maps: pixels along the level's longer side (default 768)")
        ->check(CLI::Range(16, 8192));
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

}  // namespace

CommandRun setupAnalyze(CLI::App *c) { return bindCommand<AnalyzeOptions>(c, addAnalyzeOptions, cmdAnalyze); }
CommandRun setupCheck(CLI::App *c) { return bindCommand<CheckOptions>(c, addCheckOptions, cmdCheck); }

}  // namespace va
