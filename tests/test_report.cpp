// report.json against docs/report-schema.json, exact JSON values of a synthetic result, image
// files read back (readImage), the bitmap font and the console funnel table.
#include <gtest/gtest.h>
#include <png.h>
#include <zlib.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <ctime>
#include <iterator>
#include <regex>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "reports/console.h"
#include "reports/font.h"
#include "reports/html.h"
#include "reports/palette_image.h"
#include "reports/report.h"

namespace va {
namespace {

using Json = nlohmann::ordered_json;
namespace fs = std::filesystem;

// ---- A small JSON Schema validator (the subset docs/report-schema.json uses) ------------------
// Keywords: $ref (local "#/$defs/NAME"), type (string or array), const, enum, pattern (ECMAScript,
// searched), minimum, maximum, required, properties, additionalProperties (false or a schema),
// items, minItems, maxItems, oneOf (exactly one alternative matches).

bool typeMatches(const std::string &t, const Json &v) {
    if (t == "object") return v.is_object();
    if (t == "array") return v.is_array();
    if (t == "string") return v.is_string();
    if (t == "boolean") return v.is_boolean();
    if (t == "null") return v.is_null();
    if (t == "integer") return v.is_number_integer();
    if (t == "number") return v.is_number();
    ADD_FAILURE() << "schema uses unknown type '" << t << "'";
    return false;
}

void validate(const Json &root, const Json &schema, const Json &v, const std::string &where,
              std::vector<std::string> *errors) {
    static const std::vector<std::string> kKnown = {
        "$schema", "$id", "title", "description", "$ref", "type", "const", "enum", "minimum", "maximum", "required",
        "properties", "additionalProperties", "items", "minItems", "maxItems", "$defs", "pattern", "oneOf"};
    for (auto it = schema.begin(); it != schema.end(); ++it)
        if (std::find(kKnown.begin(), kKnown.end(), it.key()) == kKnown.end())
            errors->push_back(where + ": validator does not know keyword '" + it.key() + "'");
    // oneOf: the value matches exactly one of the alternatives.
    if (schema.contains("oneOf")) {
        int matches = 0;
        for (const Json &alt : schema["oneOf"]) {
            std::vector<std::string> altErrors;
            validate(root, alt, v, where, &altErrors);
            matches += altErrors.empty();
        }
        if (matches != 1)
            errors->push_back(where + ": matches " + std::to_string(matches) + " of oneOf's alternatives, not exactly one");
    }
    if (schema.contains("$ref")) {
        const std::string ref = schema["$ref"];
        const std::string prefix = "#/$defs/";
        if (ref.rfind(prefix, 0) != 0 || !root["$defs"].contains(ref.substr(prefix.size()))) {
            errors->push_back(where + ": unresolvable $ref " + ref);
            return;
        }
        validate(root, root["$defs"][ref.substr(prefix.size())], v, where, errors);
    }
    if (schema.contains("type")) {
        bool ok = false;
        if (schema["type"].is_string()) ok = typeMatches(schema["type"], v);
        else
            for (const auto &t : schema["type"]) ok = ok || typeMatches(t, v);
        if (!ok) {
            errors->push_back(where + ": expected type " + schema["type"].dump() + ", got " + v.dump());
            return;
        }
    }
    if (schema.contains("const") && v != schema["const"])
        errors->push_back(where + ": expected " + schema["const"].dump() + ", got " + v.dump());
    if (schema.contains("enum") && std::find(schema["enum"].begin(), schema["enum"].end(), v) == schema["enum"].end())
        errors->push_back(where + ": " + v.dump() + " not in enum");
    if (schema.contains("pattern") && v.is_string() &&
        !std::regex_search(v.get<std::string>(), std::regex(schema["pattern"].get<std::string>())))
        errors->push_back(where + ": " + v.dump() + " does not match " + schema["pattern"].dump());
    if (schema.contains("minimum") && v.is_number() && v.get<double>() < schema["minimum"].get<double>())
        errors->push_back(where + ": " + v.dump() + " below minimum");
    if (schema.contains("maximum") && v.is_number() && v.get<double>() > schema["maximum"].get<double>())
        errors->push_back(where + ": " + v.dump() + " above maximum");
    if (v.is_object()) {
        if (schema.contains("required"))
            for (const auto &r : schema["required"])
                if (!v.contains(r.get<std::string>())) errors->push_back(where + ": missing required '" + r.get<std::string>() + "'");
        for (auto it = v.begin(); it != v.end(); ++it) {
            const std::string at = where + "/" + it.key();
            if (schema.contains("properties") && schema["properties"].contains(it.key()))
                validate(root, schema["properties"][it.key()], it.value(), at, errors);
            else if (schema.contains("additionalProperties")) {
                const Json &ap = schema["additionalProperties"];
                if (ap.is_boolean() && !ap.get<bool>()) errors->push_back(at + ": property not allowed by the schema");
                else if (ap.is_object()) validate(root, ap, it.value(), at, errors);
            }
        }
    }
    if (v.is_array()) {
        if (schema.contains("minItems") && v.size() < schema["minItems"].get<size_t>())
            errors->push_back(where + ": fewer than minItems");
        if (schema.contains("maxItems") && v.size() > schema["maxItems"].get<size_t>())
            errors->push_back(where + ": more than maxItems");
        if (schema.contains("items"))
            for (size_t i = 0; i < v.size(); ++i)
                validate(root, schema["items"], v[i], where + "/" + std::to_string(i), errors);
    }
}

std::vector<std::string> validateReport(const Json &schema, const Json &report) {
    std::vector<std::string> errors;
    validate(schema, schema, report, "", &errors);
    return errors;
}

// Every schema a property, an item or a definition is described by must carry a description
// (STYLE.md rule 2: every field says what it counts and its best value).
void collectUndescribed(const Json &schema, const std::string &where, std::vector<std::string> *out) {
    if (!schema.is_object()) return;
    auto need = [&](const Json &s, const std::string &at) {
        if (!s.is_object() || !s.contains("description") || !s["description"].is_string() ||
            s["description"].get<std::string>().size() < 5)
            out->push_back(at);
        collectUndescribed(s, at, out);
    };
    if (schema.contains("properties"))
        for (auto it = schema["properties"].begin(); it != schema["properties"].end(); ++it)
            need(it.value(), where + "/properties/" + it.key());
    if (schema.contains("items")) need(schema["items"], where + "/items");
    if (schema.contains("additionalProperties") && schema["additionalProperties"].is_object())
        need(schema["additionalProperties"], where + "/additionalProperties");
    if (schema.contains("$defs"))
        for (auto it = schema["$defs"].begin(); it != schema["$defs"].end(); ++it)
            need(it.value(), where + "/$defs/" + it.key());
}

Json loadSchema() {
    std::ifstream f(std::string(VISAUDIT_SOURCE_DIR) + "/docs/report-schema.json");
    EXPECT_TRUE(f.good()) << "cannot open docs/report-schema.json";
    return Json::parse(f);
}

// ---- A synthetic analysis result -------------------------------------------------------------

constexpr auto stage = ranStage;
constexpr auto skipped = skippedStage;

ViewResult spawnView() {
    ViewResult v;
    v.spec.name = "spawn";
    v.spec.origin = "scene";
    v.spec.depthFormat = DepthFormat::unorm24;
    v.spec.camera.eye = {0, 1.5, 8};
    v.spec.camera.target = {0, 1.5, 0};
    v.spec.camera.fovYDegrees = 60;
    v.spec.camera.nearZ = 0.25;
    v.spec.camera.farZ = 500;
    v.spec.camera.width = 4;
    v.spec.camera.height = 3;
    v.stages = {skipped("cells", "scene has no cells"), stage("grid", 1200, 200, 1000, 0.04),
                stage("frustum", 1000, 400, 600, 0.25), skipped("occlusion", "no occluders selected"),
                stage("backface", 600, 280, 320, 0.5), stage("clip", 320, 20, 310, 1.25),
                stage("zbuffer", 310, 0, 310, 3.0)};
    v.frustum = {40, 16, 20, 4, 31, 150, 240};
    v.backface = {580, 280, 20, 3};
    v.clip.trianglesIn = 320;
    v.clip.trivialRejected = 18;
    v.clip.inside = 250;
    v.clip.guardBandAccepted = 40;
    v.clip.clipped = 12;
    v.clip.clippedAway = 2;
    v.clip.edgeOn = 0;
    v.clip.perPlane = {12, 1, 0, 0, 0, 2};
    v.clip.polygonVertices = {0, 0, 0, 3, 6, 1, 0, 0, 0, 0};
    v.clip.trianglesOut = 310;
    v.zbuffer.trianglesIn = 310;
    v.zbuffer.trianglesDrawn = 300;
    v.zbuffer.trianglesEmpty = 10;
    v.zbuffer.fragments = 15;
    v.zbuffer.depthPasses = 12;
    v.zbuffer.outOfRangeFragments = 1;
    v.zbuffer.coveredPixels = 9;
    v.zbuffer.overdraw = 12.0 / 9.0;
    v.zbuffer.depthComplexity = 15.0 / 9.0;
    v.zbuffer.maxDepthComplexity = 3;
    v.zbuffer.histogram = {3, 5, 2, 2};
    v.totalMs = 5.5;
    return v;
}

ViewResult orthoView(const char *name) {
    ViewResult v;
    v.spec.name = name;
    v.spec.origin = "views.json";
    v.spec.depthFormat = DepthFormat::f32_reversed;
    v.spec.camera.orthographic = true;
    v.spec.camera.orthoHeight = 20;
    v.spec.camera.eye = {0, 50, 0};
    v.spec.camera.target = {0, 0, 0};
    v.spec.camera.up = {0, 0, -1};
    v.spec.camera.nearZ = 1;
    v.spec.camera.farZ = 100;
    v.spec.camera.width = 2;
    v.spec.camera.height = 2;
    v.stages = {skipped("cells", "scene has no cells"), stage("frustum", 1200, 100, 1100, 0.1),
                skipped("backface", "disabled by --no-backface"), stage("zbuffer", 1100, 0, 1100, 0.5)};
    v.frustum = {40, 2, 30, 8, 10, 60, 240};
    v.zbuffer.fragments = 7;
    v.zbuffer.depthPasses = 5;
    v.zbuffer.coveredPixels = 4;
    v.zbuffer.overdraw = 1.25;
    v.zbuffer.depthComplexity = 1.75;
    v.zbuffer.maxDepthComplexity = 2;
    v.zbuffer.histogram = {0, 1, 3};
    v.totalMs = 1.0;
    return v;
}

AnalysisResult syntheticResult() {
    AnalysisResult r;
    r.scenePath = "examples/hall.scene.json";
    r.sceneStats = {1210, 6, 4, 2, 17};
    r.triangles = 1200;
    r.objects = 40;
    r.sourceObjects = 3;
    r.bounds.lo = {-10, 0, -20};
    r.bounds.hi = {10, 5.5, 20};
    r.loadMs = 12.5;
    r.views = {spawnView(), orthoView("Hall/East"), orthoView("hall_east"), orthoView(""), orthoView("..")};
    return r;
}

// Drops every timing field ("ms", "*_ms") so that two reports can be compared for determinism.
void stripTimes(Json &j) {
    if (j.is_object()) {
        std::vector<std::string> drop;
        for (auto it = j.begin(); it != j.end(); ++it) {
            const std::string &k = it.key();
            if (k == "ms" || (k.size() > 3 && k.compare(k.size() - 3, 3, "_ms") == 0)) drop.push_back(k);
            else stripTimes(it.value());
        }
        for (const auto &k : drop) j.erase(k);
    } else if (j.is_array()) {
        for (auto &e : j) stripTimes(e);
    }
}

// ---- report.json -------------------------------------------------------------------------------

TEST(ReportJson, ValidatesAgainstSchema) {
    const Json schema = loadSchema();
    const Json report = reportJson(syntheticResult());
    const auto errors = validateReport(schema, report);
    for (const auto &e : errors) ADD_FAILURE() << e;
    EXPECT_TRUE(errors.empty());
}

TEST(ReportJson, EverySchemaFieldHasADescription) {
    std::vector<std::string> missing;
    collectUndescribed(loadSchema(), "", &missing);
    for (const auto &m : missing) ADD_FAILURE() << "no description at " << m;
    EXPECT_TRUE(missing.empty());
}

// A Quake 3 map's sections (issue 15): the brush entities never drawn, the far plane, the culling
// audit's hidden-by-design counts and the PVS evidence, valid against the schema and as written.
TEST(ReportJson, QuakeMapSectionsValidate) {
    AnalysisResult r = syntheticResult();
    AnalysisResult::BspSummary b;
    b.leafs = 8, b.clusters = 2, b.hasPvs = true, b.drawnBrushEntities = 2, b.notDrawnBrushEntities = 2;
    b.faces.notDrawnEntity = 2, b.faces.notDrawnEntityTriangles = 4;
    b.notDrawn = {{2, 6, "trigger_teleport", "trigger", 1, 2}, {4, -1, "", "no entity", 1, 2}};
    b.farPlane = {2048, 'o', "_farplanedist", "2048o"};
    r.bsp = b;
    ViewResult &v = r.views[0];
    v.audit = CullingAuditResult{};
    StageCullAudit cells;
    cells.stage = "cells";
    cells.falseCullTriangles = 1, cells.falseCullObjects = 1, cells.falseCullPixels = 3, cells.falseCullNearest = 100.5;
    cells.designFarPlane = 2048, cells.beyondFarPlaneTriangles = 2, cells.beyondFarPlanePixels = 7;
    cells.beyondFarPlaneNearest = 2050.25;
    cells.worst = {{5, "model5", 1, 3}};
    v.audit->cull.stages = {cells};
    v.audit->cull.falseCullTriangles = 1, v.audit->cull.falseCullPixels = 3;
    v.audit->cull.beyondFarPlaneTriangles = 2, v.audit->cull.beyondFarPlanePixels = 7;
    PvsEvidence &e = v.audit->pvsEvidence;
    e.ran = true, e.cameraLeaf = 0, e.cameraCluster = 0, e.designFarPlane = 2048;
    e.falseCullObjects = 1, e.falseCullPixels = 3;
    PvsObjectEvidence o;
    o.object = 5, o.name = "model5", o.model = 5, o.entity = 8, o.classname = "func_door";
    o.triangles = 1, o.pixels = 3, o.nearest = 100.5;
    o.clusters = {{1, 0}};
    o.boxLeafs = {{1, 1, true, 0}};
    PvsFaceEvidence f;
    f.face = 12, f.pixels = 3, f.nearest = 100.5, f.x = 2, f.y = 1;
    f.leafs = {{7, 0, false, 1}, {9, -1, true, -1}};
    o.faces = {f};
    e.objects = {o};
    const Json j = reportJson(r);
    const auto errors = validateReport(loadSchema(), j);
    for (const auto &err : errors) ADD_FAILURE() << err;
    EXPECT_TRUE(errors.empty());
    const Json &bsp = j["scene"]["bsp"];
    EXPECT_EQ(bsp["not_drawn_entities"].dump(),
              R"([{"model":2,"entity":6,"classname":"trigger_teleport","reason":"trigger","faces":1,"triangles":2},)"
              R"({"model":4,"entity":-1,"classname":"","reason":"no entity","faces":1,"triangles":2}])");
    EXPECT_EQ(bsp["far_plane"].dump(), R"({"distance":2048.0,"mode":"o","key":"_farplanedist","value":"2048o"})");
    EXPECT_TRUE(bsp["fog_shader"].is_null());
    const Json &a = j["views"][0]["audit"];
    EXPECT_EQ(a["false_culls"]["beyond_far_plane_pixels"], 7);
    EXPECT_EQ(a["false_culls"]["by_stage"]["cells"]["design_far_plane"], 2048.0);
    EXPECT_EQ(a["false_culls"]["by_stage"]["cells"]["beyond_far_plane_nearest"], 2050.25);
    EXPECT_EQ(a["pvs_evidence"]["objects"][0]["box_leafs"].dump(),
              R"([{"leaf":1,"cluster":1,"in_tree":true,"pvs_bit":0}])");
    EXPECT_EQ(a["pvs_evidence"]["objects"][0]["faces"][0]["leafs"].dump(),
              R"([{"leaf":7,"cluster":0,"in_tree":false,"pvs_bit":1},{"leaf":9,"cluster":-1,"in_tree":true,"pvs_bit":null}])");
    EXPECT_EQ(j["totals"]["beyond_far_plane_pixels"], 7);
    // The page shows the evidence and the entities the engine never draws.
    const std::string html = reportHtml(j, "");
    EXPECT_NE(html.find("Evidence of the PVS's false culls"), std::string::npos);
    EXPECT_NE(html.find("leaf 7: cluster 0, bit 1 (not in the tree)"), std::string::npos);
    EXPECT_NE(html.find("id=\"not-drawn-table\""), std::string::npos);
    EXPECT_NE(html.find("trigger_teleport"), std::string::npos);
    EXPECT_NE(html.find("<code>_farplanedist 2048o</code>"), std::string::npos);
    EXPECT_NE(html.find("hidden by design"), std::string::npos);
}

// The validator must be able to fail, or the test above proves nothing.
// Routes and level maps (docs/routes.md, docs/level-maps.md): a route's definition, its frames'
// "route" and series, and the level maps' floor, positions and maps, valid against the schema.
TEST(ReportJson, RoutesAndLevelMapsValidate) {
    AnalysisResult r = syntheticResult();
    Route route;
    route.name = "walk";
    route.file = "walk.route.json";
    route.keyframes.resize(2);
    route.keyframes[0].target = Vec3{0, 0, 0};
    route.keyframes[1].time = 2;
    route.sampling.kind = RouteSampling::Kind::every;
    route.sampling.every = 0.5;
    r.routes = {route};
    r.views[0].spec.route = {"walk", 0, 0.0};
    r.views[1].spec.route = {"walk", 1, 0.5};
    FloorPlan f;
    f.width = 40, f.height = 20, f.up = 'y', f.worldPerPixel = 0.5, f.drawnPixels = 7;
    f.camera.orthographic = true, f.camera.eye = {0, 60, 0}, f.camera.target = {0, 59, 0}, f.camera.up = {0, 0, -1};
    f.camera.orthoHeight = 10, f.camera.nearZ = 1, f.camera.farZ = 80, f.camera.width = 40, f.camera.height = 20;
    r.floorPlan = f;
    const Json report = reportJson(r);
    ASSERT_TRUE(report.contains("routes"));
    ASSERT_TRUE(report.contains("level_maps"));
    EXPECT_EQ(report["routes"][0]["series"]["view"], (Json{0, 1}));
    EXPECT_EQ(report["routes"][0]["sampling"], (Json{{"every_seconds", 0.5}}));
    // The orthographic views stand at (0, 50, 0): on the plan, one position of four views.
    ASSERT_EQ(report["level_maps"]["positions"].size(), 1u);
    EXPECT_EQ(report["level_maps"]["positions"][0]["views"], (Json{1, 2, 3, 4}));
    const auto errors = validateReport(loadSchema(), report);
    for (const auto &e : errors) ADD_FAILURE() << e;
    EXPECT_TRUE(errors.empty());
}

TEST(ReportJson, ValidatorRejectsBrokenReports) {
    const Json schema = loadSchema();
    const Json good = reportJson(syntheticResult());
    {
        Json bad = good;
        bad["views"][0]["stages"][2]["plane_testz"] = 3;  // a typo'd key
        const auto e = validateReport(schema, bad);
        ASSERT_EQ(e.size(), 1u);
        EXPECT_EQ(e[0], "/views/0/stages/2/plane_testz: property not allowed by the schema");
    }
    {
        Json bad = good;
        bad["views"][1]["zbuffer"].erase("histogram");
        const auto e = validateReport(schema, bad);
        ASSERT_EQ(e.size(), 1u);
        EXPECT_EQ(e[0], "/views/1/zbuffer: missing required 'histogram'");
    }
    {
        Json bad = good;
        bad["scene"]["triangles"] = -1;
        bad["views"][0]["camera"]["eye"] = Json::array({1, 2});
        bad["format"] = "visaudit-report/2";
        EXPECT_EQ(validateReport(schema, bad).size(), 3u);
    }
    {
        Json bad = good;
        bad["views"][0]["zbuffer"]["overdraw"] = "1.3";
        EXPECT_EQ(validateReport(schema, bad).size(), 1u);
    }
}

TEST(ReportJson, ExactValues) {
    const Json j = reportJson(syntheticResult());
    EXPECT_EQ(j["format"], "visaudit-report/1");
    EXPECT_EQ(j["tool"]["name"], "visaudit");
    EXPECT_EQ(j["tool"]["version"], VISAUDIT_VERSION);

    const Json &s = j["scene"];
    EXPECT_EQ(s["path"], "examples/hall.scene.json");
    EXPECT_EQ(s["triangles"], 1200);
    EXPECT_EQ(s["source_triangles"], 1210);
    EXPECT_EQ(s["objects"], 40);
    EXPECT_EQ(s["source_objects"], 3);
    EXPECT_EQ(s["degenerate_triangles"], 6);
    EXPECT_EQ(s["non_finite_triangles"], 4);
    EXPECT_EQ(s["faces_dropped"], 2);
    EXPECT_EQ(s["polygons_triangulated"], 17);
    EXPECT_EQ(s["bounds"].dump(), R"({"min":[-10.0,0.0,-20.0],"max":[10.0,5.5,20.0]})");
    EXPECT_EQ(j["load_ms"], 12.5);

    ASSERT_EQ(j["views"].size(), 5u);
    const Json &v = j["views"][0];
    EXPECT_EQ(v["name"], "spawn");
    EXPECT_EQ(v["width"], 4);
    EXPECT_EQ(v["height"], 3);
    EXPECT_EQ(v["depth_format"], "unorm24");
    EXPECT_EQ(v["projection"], "perspective");
    EXPECT_EQ(v["camera"].dump(),
              R"({"eye":[0.0,1.5,8.0],"target":[0.0,1.5,0.0],"up":[0.0,1.0,0.0],"fov_y":60.0,"near":0.25,"far":500.0})");

    // The funnel: skipped stages carry a reason and no counts of their own.
    const Json &st = v["stages"];
    ASSERT_EQ(st.size(), 7u);
    EXPECT_EQ(st[0].dump(),
              R"({"name":"cells","ran":false,"reason":"scene has no cells","triangles_in":0,"triangles_culled":0,"triangles_out":0,"ms":0.0})");
    EXPECT_EQ(st[1].dump(),
              R"({"name":"grid","ran":true,"triangles_in":1200,"triangles_culled":200,"triangles_out":1000,"ms":0.04,)"
              R"("dims":[0,0,0],"cell_size":0.0,"cells_total":0,"registrations":0,"cells_skipped":0,"cells_empty":0,)"
              R"("cells_tested":0,"cells_visible":0,"plane_tests":0,"objects_in":0,"objects_culled":0})");
    EXPECT_EQ(st[2].dump(),
              R"({"name":"frustum","ran":true,"triangles_in":1000,"triangles_culled":400,"triangles_out":600,"ms":0.25,)"
              R"("objects_in":40,"objects_culled":16,"objects_inside":20,"objects_intersecting":4,"nodes_visited":31,)"
              R"("plane_tests":150,"plane_tests_brute_force":240})");
    EXPECT_FALSE(st[3]["ran"]);
    EXPECT_EQ(st[3]["reason"], "no occluders selected");
    EXPECT_EQ(st[4].dump(),
              R"({"name":"backface","ran":true,"triangles_in":600,"triangles_culled":280,"triangles_out":320,"ms":0.5,)"
              R"("triangles_tested":580,"double_sided_exempt":20,"edge_on":3})");
    EXPECT_EQ(st[5].dump(),
              R"({"name":"clip","ran":true,"triangles_in":320,"triangles_culled":20,"triangles_out":310,"ms":1.25,)"
              R"("trivially_rejected":18,"inside":250,"guard_band_accepted":40,"clipped":12,"clipped_away":2,"edge_on":0,)"
              R"("per_plane":{"near":12,"far":1,"left":0,"right":0,"bottom":0,"top":2},)"
              R"("polygon_vertices":{"3":3,"4":6,"5":1,"6":0,"7":0,"8":0,"9+":0}})");
    EXPECT_EQ(st[6].dump(),
              R"({"name":"zbuffer","ran":true,"triangles_in":310,"triangles_culled":0,"triangles_out":310,"ms":3.0,)"
              R"("triangles_drawn":300,"triangles_empty":10,"fragments":15,"depth_passes":12,"out_of_range_fragments":1})");

    const Json &z = v["zbuffer"];
    EXPECT_EQ(z["covered_pixels"], 9);
    EXPECT_EQ(z["fragments"], 15);
    EXPECT_EQ(z["depth_passes"], 12);
    EXPECT_EQ(z["overdraw"], 12.0 / 9.0);
    EXPECT_EQ(z["depth_complexity"], 15.0 / 9.0);
    EXPECT_EQ(z["max_depth_complexity"], 3);
    EXPECT_EQ(z["histogram"].dump(), "[3,5,2,2]");
    EXPECT_EQ(v["images"].dump(),
              R"({"depth_exr":"spawn.depth.exr","depth_png":"spawn.depth.png","overdraw_png":"spawn.overdraw.png","ids_exr":"spawn.ids.exr"})");
    EXPECT_EQ(v["total_ms"], 5.5);

    // Orthographic camera: ortho_height instead of fov_y.
    EXPECT_EQ(j["views"][1]["projection"], "orthographic");
    EXPECT_EQ(j["views"][1]["camera"]["ortho_height"], 20.0);
    EXPECT_FALSE(j["views"][1]["camera"].contains("fov_y"));
    EXPECT_EQ(j["views"][1]["depth_format"], "f32_reversed");

    // Sanitized, disambiguated image names: '/' -> '_'; "hall_east" collides with "Hall_East"
    // case-insensitively and gets "-2"; "" -> "view"; ".." -> "_." (no leading dot).
    EXPECT_EQ(j["views"][1]["name"], "Hall/East");
    EXPECT_EQ(j["views"][1]["images"]["depth_exr"], "Hall_East.depth.exr");
    EXPECT_EQ(j["views"][2]["images"]["depth_png"], "hall_east-2.depth.png");
    EXPECT_EQ(j["views"][3]["images"]["overdraw_png"], "view.overdraw.png");
    EXPECT_EQ(j["views"][4]["images"]["ids_exr"], "_..ids.exr");

    // Totals: culled per stage summed over the 5 views (grid only in view 0; frustum 400 + 4 x 100).
    const Json &t = j["totals"];
    EXPECT_EQ(t["views"], 5);
    EXPECT_EQ(t["triangles_culled"].dump(),
              R"({"cells":0,"grid":200,"frustum":800,"occlusion":0,"backface":280,"clip":20,"zbuffer":0})");
    EXPECT_EQ(t["covered_pixels"], 9 + 4 * 4);
    EXPECT_EQ(t["fragments"], 15 + 4 * 7);
    EXPECT_EQ(t["depth_passes"], 12 + 4 * 5);
    EXPECT_EQ(t["total_ms"], 5.5 + 4 * 1.0);
}

TEST(ReportJson, DeterministicApartFromTimes) {
    AnalysisResult a = syntheticResult(), b = syntheticResult();
    EXPECT_EQ(reportJson(a).dump(2), reportJson(b).dump(2));
    b.loadMs = 99;
    b.views[0].stages[2].ms = 7.25;
    b.views[1].totalMs = 3;
    Json ja = reportJson(a), jb = reportJson(b);
    EXPECT_NE(ja.dump(), jb.dump());
    stripTimes(ja);
    stripTimes(jb);
    EXPECT_EQ(ja.dump(2), jb.dump(2));
    // A count change is not masked by stripping times.
    b.views[0].frustum.planeTests = 151;
    jb = reportJson(b);
    stripTimes(jb);
    EXPECT_NE(ja.dump(), jb.dump());
}

TEST(ReportJson, NonFiniteNumbersBecomeNull) {
    AnalysisResult r = syntheticResult();
    r.bounds = Aabb{};  // empty scene: lo = +inf, hi = -inf
    r.views[0].zbuffer.overdraw = std::numeric_limits<double>::quiet_NaN();
    r.views[0].zbuffer.depthComplexity = std::numeric_limits<double>::infinity();
    const Json j = reportJson(r);
    EXPECT_TRUE(j["scene"]["bounds"]["min"].is_null());
    EXPECT_TRUE(j["scene"]["bounds"]["max"].is_null());
    EXPECT_TRUE(j["views"][0]["zbuffer"]["overdraw"].is_null());
    EXPECT_TRUE(j["views"][0]["zbuffer"]["depth_complexity"].is_null());
    EXPECT_EQ(j.dump().find("NaN"), std::string::npos);
    EXPECT_TRUE(validateReport(loadSchema(), j).empty());
}

// The output phase's timings: appended as "output", null when not finite, valid against the
// schema, and stripped with the other timings (the determinism comparisons ignore them).
TEST(ReportJson, OutputTimings) {
    Json j = reportJson(syntheticResult());
    EXPECT_FALSE(j.contains("output"));
    const Json before = j;
    addOutputTimings(&j, {1250.5, 0.75, std::numeric_limits<double>::infinity()});
    EXPECT_EQ(j["output"].dump(), R"({"images_ms":1250.5,"report_ms":0.75,"html_ms":null})");
    EXPECT_EQ(j.items().begin().key(), "format");  // appended, the rest keeps its order
    const auto errors = validateReport(loadSchema(), j);
    for (const auto &e : errors) ADD_FAILURE() << e;
    EXPECT_TRUE(errors.empty());
    Json bad = j;
    bad["output"]["encode_ms"] = 1;
    EXPECT_EQ(validateReport(loadSchema(), bad).size(), 1u);
    stripTimes(j);
    EXPECT_EQ(j["output"].dump(), "{}");
    j.erase("output");
    Json b = before;
    stripTimes(b);
    EXPECT_EQ(j.dump(), b.dump());
}

TEST(ReportJson, EmptyResult) {
    const Json j = reportJson(AnalysisResult{});
    EXPECT_EQ(j["views"].dump(), "[]");
    EXPECT_EQ(j["totals"].dump(),
              R"({"views":0,"triangles_culled":{},"covered_pixels":0,"fragments":0,"depth_passes":0,)"
              R"("false_cull_triangles":0,"false_cull_pixels":0,"false_cull_triangles_by_stage":{},)"
              R"("beyond_far_plane_pixels":0,)"
              R"("wasted_triangles":0,"wasted_fragments":0,"genuine_disagreements":0,"zfight_hotspots":0,"total_ms":0.0})");
    EXPECT_TRUE(validateReport(loadSchema(), j).empty());
}

TEST(ReportNames, Sanitize) {
    EXPECT_EQ(sanitizeFileName("spawn"), "spawn");
    EXPECT_EQ(sanitizeFileName("a-b_c.D9"), "a-b_c.D9");
    EXPECT_EQ(sanitizeFileName("../../etc/passwd"), "_._.._etc_passwd");
    EXPECT_EQ(sanitizeFileName("hall east:1"), "hall_east_1");
    EXPECT_EQ(sanitizeFileName("caf\xC3\xA9"), "caf__");  // two UTF-8 bytes, two '_'
    EXPECT_EQ(sanitizeFileName(""), "view");
    EXPECT_EQ(sanitizeFileName(".hidden"), "_hidden");
    EXPECT_EQ(sanitizeFileName(std::string(300, 'a')), std::string(kMaxImageBaseName, 'a'));
}

TEST(ReportNames, CollisionsResolvedInViewOrder) {
    std::vector<ViewResult> views(6);
    const char *names[] = {"a b", "a_b", "A_B", "a_b-2", "x", "a?b"};
    for (int i = 0; i < 6; ++i) views[size_t(i)].spec.name = names[i];
    const std::vector<std::string> expected = {"a_b", "a_b-2", "A_B-3", "a_b-2-2", "x", "a_b-4"};
    EXPECT_EQ(imageBaseNames(views), expected);
    std::vector<ViewSpec> specs;
    for (const auto &v : views) specs.push_back(v.spec);
    EXPECT_EQ(imageBaseNames(specs), expected);
}

// ---- Images ------------------------------------------------------------------------------------

struct TempDir {
    std::string path;
    TempDir() {
        std::string t = (fs::temp_directory_path() / "visaudit-report-XXXXXX").string();
        path = ::mkdtemp(t.data()) ? t : "";
    }
    ~TempDir() {
        std::error_code ec;
        if (!path.empty()) fs::remove_all(path, ec);
    }
};

// A 4 x 3 view:
//   depth      1      10     1000    inf          fragments  1  5  9  0        ids  1  2  0xFFFFFFF0  0
//              10     0.1f*  inf     inf                     2  3  0  0             3  4  0           0
//              1000   1      1      10                      1  1  1  1             5  6  7           8
// (* the double nearest 0.1, written to EXR as float(0.1); it is the view's minimum depth).
ViewResult imageView() {
    ViewResult v;
    v.spec.name = "img test";
    const double inf = std::numeric_limits<double>::infinity();
    v.buffer.width = 4;
    v.buffer.height = 3;
    v.buffer.depth = {1, 10, 1000, inf, 10, 0.1, inf, inf, 1000, 1, 1, 10};
    v.buffer.fragments = {1, 5, 9, 0, 2, 3, 0, 0, 1, 1, 1, 1};
    v.buffer.id = {1, 2, 0xFFFFFFF0u, 0, 3, 4, 0, 0, 5, 6, 7, 8};
    v.buffer.key.assign(12, 0);
    v.buffer.passes.assign(12, 1);
    return v;
}

std::vector<uint8_t> rgbAt(const ImageData &im, int x, int y) {
    const size_t i = (size_t(y) * size_t(im.width) + size_t(x)) * 3;
    return {im.u8[i], im.u8[i + 1], im.u8[i + 2]};
}
using Px = std::vector<uint8_t>;

TEST(ReportImages, ColorMappings) {
    // Overdraw ramp, cap 9: t = (v - 1) / 8. v = 5 -> t = 0.5, exactly the green stop.
    EXPECT_EQ(overdrawColor(0, 9), (Rgb8{0, 0, 0}));
    EXPECT_EQ(overdrawColor(1, 9), (Rgb8{32, 64, 255}));
    EXPECT_EQ(overdrawColor(5, 9), (Rgb8{48, 220, 48}));
    EXPECT_EQ(overdrawColor(9, 9), (Rgb8{255, 255, 255}));
    EXPECT_EQ(overdrawColor(200, 9), (Rgb8{255, 255, 255}));  // above the cap: top color
    // v = 2 of 9: t = 0.125, halfway from blue (32,64,255) to cyan (0,200,255): (16, 132, 255).
    EXPECT_EQ(overdrawColor(2, 9), (Rgb8{16, 132, 255}));
    // Depth gray, dMin 1, dMax 1000: 10 is a third of the way in log scale: 255 - 215/3 = 183.3.
    EXPECT_EQ(depthGray(1, 1, 1000), 255);
    EXPECT_EQ(depthGray(10, 1, 1000), 183);
    EXPECT_EQ(depthGray(1000, 1, 1000), kDepthPngFarGray);
    EXPECT_EQ(depthGray(std::numeric_limits<double>::infinity(), 1, 1000), 0);
    EXPECT_EQ(depthGray(5, 5, 5), 255);  // one depth only: white
}

// depthGrays (a bucket table, a logarithm only near a gray's boundary) gives every pixel the gray
// DepthGrayScale computes for it: depth ranges from 1e-6 to 1e7, random depths, and depths one
// ulp either side of every gray boundary (found by bisection on the doubles), plus background,
// +inf, NaN, 0 and negative depths.
TEST(ReportImages, DepthGraysMatchTheScaleAtEveryBoundary) {
    uint64_t state = 3;
    auto next = [&] {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return double(state >> 11) * 0x1p-53;
    };
    const double ranges[][2] = {{1e-6, 1e-5}, {0.1, 1000}, {4, 8192}, {1, 1.0000001}, {3, 1e7}};
    uint64_t checked = 0;
    for (const auto &r : ranges) {
        const DepthGrayScale scale(r[0], r[1]);
        std::vector<double> depth = {r[0], r[1], 0.0, -1.0, INFINITY, NAN};
        for (int i = 0; i < 20000; ++i) depth.push_back(r[0] * std::pow(r[1] / r[0], next()));
        // Boundaries: bisect between depths whose grays differ, down to neighbouring doubles.
        for (int i = 0; i < 300; ++i) {
            double a = r[0] * std::pow(r[1] / r[0], next()), b = std::min(r[1], a * (1 + next() * 0.05));
            if (scale(a) == scale(b)) continue;
            while (std::nextafter(a, b) < b) {
                const double m = a + (b - a) / 2;
                if (m <= a || m >= b) break;
                (scale(m) == scale(a) ? a : b) = m;
            }
            depth.insert(depth.end(), {std::nextafter(a, 0.0), a, b, std::nextafter(b, INFINITY)});
        }
        const std::vector<uint8_t> g = depthGrays(depth);
        ASSERT_EQ(g.size(), depth.size());
        for (size_t i = 0; i < depth.size(); ++i) {
            ASSERT_EQ(int(g[i]), int(scale(depth[i]))) << "range " << r[0] << ".." << r[1] << ", depth " << depth[i];
            ++checked;
        }
    }
    EXPECT_GT(checked, 100000u);
}

// depthGraysFrom gives depthGrays's grays: for a buffer that differs from the known one at some
// pixels (other depths in the range, background, +inf, NaN, 0, negative depths where the known
// buffer has depths and the reverse), for one whose changes move its range (a new nearest or
// farthest depth, or the known nearest or farthest one changed to a depth inside: every gray
// changes), and for a known buffer of another size.
TEST(ReportImages, DepthGraysFromAMostlyEqualBufferAreItsOwn) {
    uint64_t state = 11;
    auto next = [&] {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return double(state >> 11) * 0x1p-53;
    };
    std::vector<double> known(50000);
    for (double &d : known) d = next() < 0.1 ? INFINITY : 0.5 * std::pow(4000.0, next());
    known[7] = 0.5, known[8] = 2000;  // the range's ends, kept by every variant but the last
    double kMin, kMax;
    const std::vector<uint8_t> knownGrays = depthGrays(known, &kMin, &kMax);
    EXPECT_EQ(kMin, 0.5);
    EXPECT_EQ(kMax, 2000);
    const double odd[] = {INFINITY, NAN, 0.0, -3.0, -INFINITY, 0.75, 1999.0, std::nextafter(0.5, 1.0)};
    for (int variant = 0; variant < 3; ++variant) {
        std::vector<double> depth = known;
        for (int k = 0; k < 300; ++k) {
            const size_t p = 9 + size_t(next() * double(depth.size() - 9));
            depth[p] = k % 3 == 0 ? odd[k % std::size(odd)] : 0.5 * std::pow(4000.0, next());
        }
        if (variant == 1) depth[100] = 0.25;   // a nearer depth: another range
        if (variant == 2) depth[200] = 4000;   // a farther one
        const std::vector<uint8_t> want = depthGrays(depth);
        EXPECT_TRUE(depthGraysFrom(depth, known, knownGrays, kMin, kMax) == want) << variant;
        if (variant == 0) EXPECT_FALSE(want == knownGrays);  // the changed pixels changed grays
        // The other range moved the grays (the old nearest is no longer white, the old farthest
        // no longer the farthest gray).
        if (variant == 1) EXPECT_NE(want[7], knownGrays[7]);
        if (variant == 2) EXPECT_NE(want[8], knownGrays[8]);
    }
    for (const size_t end : {size_t(7), size_t(8)}) {  // the known range's ends, moved inside it
        std::vector<double> depth = known;
        depth[end] = 3.0;
        EXPECT_TRUE(depthGraysFrom(depth, known, knownGrays, kMin, kMax) == depthGrays(depth)) << end;
        EXPECT_FALSE(depthGrays(depth) == knownGrays) << end;
    }
    const std::vector<double> shorter(known.begin(), known.end() - 1);
    EXPECT_TRUE(depthGraysFrom(shorter, known, knownGrays, kMin, kMax) == depthGrays(shorter));
}

TEST(ReportImages, WriteAndReadBack) {
    TempDir dir;
    ASSERT_FALSE(dir.path.empty());
    const ViewResult v = imageView();
    std::string err;
    ASSERT_TRUE(writeViewImages(v, dir.path, "img_test", &err)) << err;

    // Only the four images remain (temporaries renamed away).
    std::vector<std::string> files;
    for (const auto &e : fs::directory_iterator(dir.path)) files.push_back(e.path().filename().string());
    std::sort(files.begin(), files.end());
    EXPECT_EQ(files, (std::vector<std::string>{"img_test.depth.exr", "img_test.depth.png", "img_test.ids.exr",
                                               "img_test.overdraw.png"}));

    // depth.exr: one float channel "Z", bit-exactly float(depth), +inf background.
    ImageData z;
    ASSERT_TRUE(readImage(dir.path + "/img_test.depth.exr", &z, &err)) << err;
    EXPECT_EQ(z.width, 4);
    EXPECT_EQ(z.height, 3);
    EXPECT_EQ(z.channelNames, std::vector<std::string>{"Z"});
    EXPECT_EQ(z.pixelType, "float");
    ASSERT_EQ(z.f32.size(), 12u);
    for (size_t i = 0; i < 12; ++i) {
        const float expected = float(v.buffer.depth[i]);
        EXPECT_EQ(std::memcmp(&z.f32[i], &expected, sizeof(float)), 0) << "pixel " << i << ": " << z.f32[i];
    }
    EXPECT_TRUE(std::isinf(z.f32[3]) && z.f32[3] > 0);

    // ids.exr: one UINT32 channel "id", exact (0xFFFFFFF0 would not survive a float channel).
    ImageData ids;
    ASSERT_TRUE(readImage(dir.path + "/img_test.ids.exr", &ids, &err)) << err;
    EXPECT_EQ(ids.channelNames, std::vector<std::string>{"id"});
    EXPECT_EQ(ids.pixelType, "uint");
    EXPECT_EQ(ids.u32, v.buffer.id);

    // depth.png: gray, dMin = 0.1, dMax = 1000 (4 decades): 1 -> t = 1/4 -> 255 - 53.75 = 201.25;
    // 10 -> t = 1/2 -> 147.5 computed in floating point; the exact mapping is depthGray.
    ImageData g;
    ASSERT_TRUE(readImage(dir.path + "/img_test.depth.png", &g, &err)) << err;
    EXPECT_EQ(g.width, 4);
    EXPECT_EQ(g.height, 3);
    ASSERT_EQ(g.channels(), 1);
    ASSERT_EQ(g.u8.size(), 12u);
    EXPECT_EQ(g.u8[5], 255);               // 0.1: nearest, white
    EXPECT_EQ(g.u8[0], 201);               // 1.0
    EXPECT_EQ(g.u8[2], kDepthPngFarGray);  // 1000: farthest
    EXPECT_EQ(g.u8[3], 0);                 // background
    for (size_t i = 0; i < 12; ++i) EXPECT_EQ(g.u8[i], depthGray(v.buffer.depth[i], 0.1, 1000)) << i;

    // overdraw.png: cap = max(8, 9) = 9, legend values 0..9 (10 swatches). Layout at scale 1:
    //   cell width = max(label width 5, 7) + gap 4 = 11; legend width = 10 * 11 - 4 = 106;
    //   canvas width = max(4, 106 + 2 * 3) = 112; strip height = 3 + 6 + 2 + 7 + 3 = 21 -> 3 + 21 = 24.
    ImageData o;
    ASSERT_TRUE(readImage(dir.path + "/img_test.overdraw.png", &o, &err)) << err;
    EXPECT_EQ(o.width, 112);
    EXPECT_EQ(o.height, 24);
    ASSERT_EQ(o.channels(), 3);
    EXPECT_EQ(rgbAt(o, 0, 0), (Px{32, 64, 255}));     // 1 fragment: blue
    EXPECT_EQ(rgbAt(o, 1, 0), (Px{48, 220, 48}));     // 5: green
    EXPECT_EQ(rgbAt(o, 2, 0), (Px{255, 255, 255}));   // 9: white
    EXPECT_EQ(rgbAt(o, 3, 0), (Px{0, 0, 0}));         // 0: black
    EXPECT_EQ(rgbAt(o, 0, 1), (Px{16, 132, 255}));    // 2
    EXPECT_EQ(rgbAt(o, 4, 0), (Px{24, 24, 24}));      // canvas widened right of the image: strip color
    EXPECT_EQ(rgbAt(o, 0, 3), (Px{24, 24, 24}));      // strip below the image
    // Legend: x0 = 112 - 3 - 106 = 3, swatches at y 6..11 (outline) with interior y 7..10.
    EXPECT_EQ(rgbAt(o, 3, 6), (Px{160, 160, 160}));   // swatch "0" outline
    EXPECT_EQ(rgbAt(o, 5, 8), (Px{0, 0, 0}));         // swatch "0" interior
    EXPECT_EQ(rgbAt(o, 3 + 11 + 3, 8), (Px{32, 64, 255}));       // swatch "1"
    EXPECT_EQ(rgbAt(o, 3 + 9 * 11 + 3, 8), (Px{255, 255, 255})); // swatch "9"
    // Label "0" at x = 3 + (7 - 5) / 2 = 4, y = 6 + 6 + 2 = 14: glyph row 0 is .###. -> x 5..7.
    EXPECT_EQ(rgbAt(o, 4, 14), (Px{24, 24, 24}));
    EXPECT_EQ(rgbAt(o, 5, 14), (Px{255, 255, 255}));
    EXPECT_EQ(rgbAt(o, 7, 14), (Px{255, 255, 255}));
    EXPECT_EQ(rgbAt(o, 8, 14), (Px{24, 24, 24}));
}

std::string fileBytes(const std::string &p) {
    std::ifstream f(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), {});
}

// Images are byte-identical across runs: no timestamps (OpenEXR's capDate has one-second
// resolution, so the second write waits for the clock's second to change).
TEST(ReportImages, ByteIdenticalAcrossRuns) {
    TempDir a, b;
    std::string err;
    ASSERT_TRUE(writeViewImages(imageView(), a.path, "v", &err)) << err;
    const std::time_t t0 = std::time(nullptr);
    while (std::time(nullptr) == t0) ::usleep(20000);
    ASSERT_TRUE(writeViewImages(imageView(), b.path, "v", &err)) << err;
    for (const char *f : {"v.depth.exr", "v.depth.png", "v.overdraw.png", "v.ids.exr"}) {
        const std::string x = fileBytes(a.path + "/" + f), y = fileBytes(b.path + "/" + f);
        EXPECT_FALSE(x.empty()) << f;
        EXPECT_TRUE(x == y) << f << " differs between two writes";
    }
}

TEST(ReportImages, LargeImageKeepsWidthAndScalesLegend) {
    TempDir dir;
    ViewResult v;
    v.spec.name = "wide";
    v.buffer.width = 1100;
    v.buffer.height = 2;
    const size_t n = 2200;
    v.buffer.depth.assign(n, 2.0);
    v.buffer.id.assign(n, 1);
    v.buffer.fragments.assign(n, 1);
    v.buffer.fragments[0] = 40;  // cap 40 -> 0, 1 and 8 spaced values (6, 11, ..., 40)
    std::string err;
    ASSERT_TRUE(writeViewImages(v, dir.path, &err)) << err;
    ImageData o;
    ASSERT_TRUE(readImage(dir.path + "/wide.overdraw.png", &o, &err)) << err;
    EXPECT_EQ(o.width, 1100);     // the legend fits: the canvas keeps the image width
    EXPECT_EQ(o.height, 2 + 42);  // scale 2 for images 1024+ wide: strip 21 * 2
    EXPECT_EQ(rgbAt(o, 0, 0), (Px{255, 255, 255}));
    EXPECT_EQ(rgbAt(o, 1, 0), (Px{32, 64, 255}));
}

// PNGs with at most 256 colors are stored with a palette (IHDR color type 3), others as RGB
// (type 2); either reads back as the same RGB pixels. 256 colors is the last palette image, 257
// the first RGB one; identical rows (copied indices) and colors in scattered order included.
TEST(ReportImages, PngPaletteUpTo256Colors) {
    TempDir dir;
    for (const int colors : {1, 5, 256, 257, 4096}) {
        const int W = 97, H = 61;
        std::vector<uint8_t> rgb(size_t(W) * H * 3);
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                // Rows 10..19 repeat row 9; colors spread over all channels by a multiplicative hash.
                const int yy = (y >= 10 && y < 20) ? 9 : y;
                const uint32_t c = uint32_t((yy * W + x) * 2654435761u % uint32_t(colors)) * 40503u;
                uint8_t *p = &rgb[(size_t(y) * W + x) * 3];
                p[0] = uint8_t(c), p[1] = uint8_t(c >> 8), p[2] = uint8_t(c >> 16);
            }
        const std::string path = dir.path + "/c" + std::to_string(colors) + ".png";
        std::string err;
        ASSERT_TRUE(writePngRgb8(path, W, H, rgb.data(), &err)) << err;
        const std::string bytes = fileBytes(path);
        ASSERT_GT(bytes.size(), 26u);
        EXPECT_EQ(int(uint8_t(bytes[25])), colors <= 256 ? 3 : 2) << colors << " colors";
        ImageData d;
        ASSERT_TRUE(readImage(path, &d, &err)) << err;
        ASSERT_EQ(d.channels(), 3);
        EXPECT_EQ(d.width, W);
        EXPECT_EQ(d.height, H);
        EXPECT_TRUE(d.u8 == rgb) << colors << " colors: pixels differ after reading back";
    }
}

// The PNG writer's own IDAT path (images above 16 KB of filtered rows) gives the bytes libpng
// gives row by row with the same settings (filter "up", level 1, run-length strategy): palette
// images (colors in order of first appearance, as the writer indexes them) and RGB ones, one-row,
// one-column and wide images among them. Fails if a filter byte, the first row's filter, the zlib
// header or trailer, or the IDAT chunking differs from libpng's.
std::string libpngRows(int W, int H, const std::vector<uint8_t> &rgb) {
    std::vector<png_color> palette;
    std::map<uint32_t, uint8_t> indexOf;
    std::vector<uint8_t> index;
    bool usePalette = true;
    for (size_t i = 0; i < size_t(W) * H && usePalette; ++i) {
        const uint32_t k = uint32_t(rgb[3 * i]) | uint32_t(rgb[3 * i + 1]) << 8 | uint32_t(rgb[3 * i + 2]) << 16;
        auto it = indexOf.find(k);
        if (it == indexOf.end()) {
            if (palette.size() == 256) {
                usePalette = false;
                break;
            }
            it = indexOf.emplace(k, uint8_t(palette.size())).first;
            palette.push_back({rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]});
        }
        index.push_back(it->second);
    }
    std::string out;
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
    png_infop info = png_create_info_struct(png);
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        return {};
    }
    png_set_write_fn(
        png, &out,
        [](png_structp p, png_bytep d, png_size_t n) {
            static_cast<std::string *>(png_get_io_ptr(p))->append(reinterpret_cast<const char *>(d), n);
        },
        [](png_structp) {});
    png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_UP);
    png_set_compression_strategy(png, Z_RLE);
    png_set_compression_level(png, 1);
    const int type = usePalette ? PNG_COLOR_TYPE_PALETTE : PNG_COLOR_TYPE_RGB;
    png_set_IHDR(png, info, png_uint_32(W), png_uint_32(H), 8, type, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
                 PNG_FILTER_TYPE_DEFAULT);
    if (usePalette) png_set_PLTE(png, info, palette.data(), int(palette.size()));
    png_write_info(png, info);
    for (int y = 0; y < H; ++y)
        png_write_row(png, usePalette ? &index[size_t(y) * W] : &rgb[size_t(y) * W * 3]);
    png_write_end(png, info);
    png_destroy_write_struct(&png, &info);
    return out;
}

TEST(ReportImages, PngDirectIdatEqualsLibpngRows) {
    TempDir dir;
    struct Case {
        int W, H, colors;
    };
    for (const Case c : {Case{300, 200, 6}, Case{300, 200, 100000}, Case{20000, 1, 12}, Case{1, 20000, 12},
                         Case{1920, 1080, 40}, Case{641, 480, 256}, Case{641, 480, 257}}) {
        std::vector<uint8_t> rgb(size_t(c.W) * c.H * 3);
        for (int y = 0; y < c.H; ++y)
            for (int x = 0; x < c.W; ++x) {
                // Bands of repeated rows and runs along each row, as the visualizations have.
                const int yy = y - y % 7, xx = x - x % 13;
                const uint32_t v = uint32_t((yy * 31 + xx * 17) * 2654435761u % uint32_t(c.colors)) * 40503u;
                uint8_t *p = &rgb[(size_t(y) * c.W + x) * 3];
                p[0] = uint8_t(v), p[1] = uint8_t(v >> 8), p[2] = uint8_t(v >> 16);
            }
        const std::string path = dir.path + "/d.png";
        std::string err;
        ASSERT_TRUE(writePngRgb8(path, c.W, c.H, rgb.data(), &err)) << err;
        const std::string want = libpngRows(c.W, c.H, rgb);
        ASSERT_FALSE(want.empty());
        EXPECT_TRUE(fileBytes(path) == want) << c.W << "x" << c.H << ", " << c.colors << " colors";
    }
}

// A picture drawn as color codes (PaletteImage) is written byte for byte as its RGB pixels are by
// writePngRgb8: the palette in order of first appearance whatever order the codes were made in
// (colors asked for and never drawn leave no entry), RGB past 256 colors, and the legend's text.
TEST(ReportImages, PaletteImageWritesTheBytesOfItsRgbPixels) {
    TempDir dir;
    struct Case {
        int W, H, colors;
    };
    for (const Case c : {Case{300, 200, 6}, Case{300, 200, 255}, Case{300, 200, 256}, Case{300, 200, 257},
                         Case{641, 480, 2000}, Case{1, 20000, 12}, Case{20000, 1, 12}, Case{1920, 1080, 40},
                         Case{800, 60, 200}, Case{800, 60, 300}}) {
        PaletteImage img(c.W, c.H, {24, 24, 24});
        // Codes asked for in reverse order of use, plus some never drawn.
        std::vector<uint16_t> code(size_t(c.colors));
        for (int k = c.colors - 1; k >= 0; --k) {
            const uint32_t v = uint32_t(k) * 40503u + 7u;
            code[size_t(k)] = img.codeOf({uint8_t(v), uint8_t(v >> 8), uint8_t(v >> 16)});
            if (k % 5 == 0) img.codeOf({uint8_t(k), 1, 2});  // never drawn (unless equal to a drawn one)
        }
        for (int y = 0; y < c.H; ++y)
            for (int x = 0; x < c.W; ++x) {
                // Bands of repeated rows and runs (800 wide: runs of 37, longer than the 16 codes
                // the index pass compares at once, and new colors where they end).
                const int run = c.W == 800 ? 37 : 13;
                const int yy = y - y % 7, xx = x - x % run;
                img.code[size_t(y) * size_t(c.W) + size_t(x)] = code[size_t((yy * 31 + xx * 17) * 2654435761u % uint32_t(c.colors))];
            }
        img.fill(2, 2, 40, 9, Rgb8{255, 0, 255});
        img.text(3, 3, "legend 0123", {255, 255, 255}, 1, c.H / 2);
        const std::vector<uint8_t> rgb = img.rgb();
        ASSERT_EQ(rgb.size(), size_t(c.W) * size_t(c.H) * 3);
        std::string err;
        ASSERT_TRUE(writePngRgb8(dir.path + "/rgb.png", c.W, c.H, rgb.data(), &err)) << err;
        ASSERT_TRUE(writePngPalette(dir.path + "/codes.png", img, &err)) << err;
        EXPECT_TRUE(fileBytes(dir.path + "/codes.png") == fileBytes(dir.path + "/rgb.png"))
            << c.W << "x" << c.H << ", " << c.colors << " colors";
    }
}

// An EXR written with the chunks of one written before reuses the chunks whose rows are the same
// and compresses the others: byte for byte the file written without them (one changed pixel in
// chunk 2, a different size, and a float image of the same size do not take the stale chunks).
TEST(ReportImages, ExrChunksReusedOnlyWhereRowsAgree) {
    TempDir dir;
    const int W = 200, H = 90;  // 6 chunks of 16 rows
    std::vector<uint32_t> a(size_t(W) * H), b;
    for (size_t i = 0; i < a.size(); ++i) a[i] = uint32_t(i / 37 % 11 + 1);
    b = a;
    b[size_t(40) * W + 17] += 5;  // row 40: chunk 2
    std::string err;
    ExrChunks chunks;
    ASSERT_TRUE(writeExrUint32(dir.path + "/a.exr", W, H, a.data(), "id", &err, &chunks)) << err;
    EXPECT_EQ(chunks.bytes.size(), 6u);
    ASSERT_TRUE(writeExrUint32(dir.path + "/b.exr", W, H, b.data(), "id", &err, &chunks)) << err;
    ASSERT_TRUE(writeExrUint32(dir.path + "/b-alone.exr", W, H, b.data(), "id", &err)) << err;
    EXPECT_TRUE(fileBytes(dir.path + "/b.exr") == fileBytes(dir.path + "/b-alone.exr"));
    // Reusing b's chunks for a: chunk 2 differs again.
    ASSERT_TRUE(writeExrUint32(dir.path + "/a2.exr", W, H, a.data(), "id", &err, &chunks)) << err;
    EXPECT_TRUE(fileBytes(dir.path + "/a2.exr") == fileBytes(dir.path + "/a.exr"));
    // A different height: nothing reused.
    ASSERT_TRUE(writeExrUint32(dir.path + "/short.exr", W, H - 20, a.data(), "id", &err, &chunks)) << err;
    ASSERT_TRUE(writeExrUint32(dir.path + "/short-alone.exr", W, H - 20, a.data(), "id", &err)) << err;
    EXPECT_TRUE(fileBytes(dir.path + "/short.exr") == fileBytes(dir.path + "/short-alone.exr"));
    ImageData d;
    ASSERT_TRUE(readImage(dir.path + "/b.exr", &d, &err)) << err;
    ASSERT_EQ(d.u32.size(), b.size());
    EXPECT_TRUE(d.u32 == b);
}

TEST(ReportImages, Errors) {
    TempDir dir;
    std::string err;
    const std::string missing = dir.path + "/no/such/folder";
    EXPECT_FALSE(writeViewImages(imageView(), missing, "x", &err));
    EXPECT_NE(err.find("cannot write image '" + missing + "/x.depth.exr'"), std::string::npos) << err;

    ViewResult released = imageView();
    released.buffer = ZBuffer{};
    EXPECT_FALSE(writeViewImages(released, dir.path, &err));
    EXPECT_EQ(err, "view 'img test': no per-pixel buffers of 0x0 pixels to write images from (were they released "
                   "before writing?)");
    EXPECT_TRUE(fs::is_empty(dir.path));

    ImageData d;
    EXPECT_FALSE(readImage(dir.path + "/absent.exr", &d, &err));
    EXPECT_NE(err.find(dir.path + "/absent.exr"), std::string::npos) << err;
}

TEST(ReportImages, AllViewsUseDisambiguatedNames) {
    TempDir dir;
    AnalysisResult r;
    r.views = {imageView(), imageView()};
    r.views[1].spec.name = "img_test";  // sanitized, "img test" is "img_test" too
    std::string err;
    ASSERT_TRUE(writeAllViewImages(r, dir.path, &err)) << err;
    const Json j = reportJson(r);
    for (const auto &v : j["views"])
        for (const auto &f : v["images"]) EXPECT_TRUE(fs::exists(dir.path + "/" + f.get<std::string>())) << f;
    EXPECT_EQ(j["views"][1]["images"]["ids_exr"], "img_test-2.ids.exr");
}

// ---- Font --------------------------------------------------------------------------------------

TEST(ReportFont, DrawsGlyphCells) {
    const int w = 20, h = 16;
    std::vector<uint8_t> img(w * h * 3, 0);
    const int end = drawText(img.data(), w, h, 1, 1, "1", {255, 0, 0}, 2);
    EXPECT_EQ(end, 1 + 10);
    // '1' row 0 = ..#.. : column 2 -> pixels x 1 + 4 .. 1 + 5, y 1 .. 2 at scale 2.
    auto red = [&](int x, int y) { return img[(y * w + x) * 3] == 255 && img[(y * w + x) * 3 + 1] == 0; };
    EXPECT_TRUE(red(5, 1) && red(6, 1) && red(5, 2) && red(6, 2));
    EXPECT_FALSE(red(4, 1));
    EXPECT_FALSE(red(7, 1));
    // Bottom row 6 = .###. -> x 3 .. 8, y 13 .. 14.
    EXPECT_TRUE(red(3, 13) && red(8, 14));
    EXPECT_FALSE(red(2, 13));
    int set = 0;
    for (int i = 0; i < w * h; ++i) set += img[size_t(i) * 3] == 255;
    EXPECT_EQ(set, (1 + 2 + 1 + 1 + 1 + 1 + 3) * 4);  // cells of '1' times 2x2
}

TEST(ReportFont, MetricsCaseAndMissingGlyphs) {
    EXPECT_EQ(textWidth("", 1), 0);
    EXPECT_EQ(textWidth("10", 1), 11);
    EXPECT_EQ(textWidth("10", 3), 33);
    EXPECT_TRUE(hasGlyph('a'));
    EXPECT_TRUE(hasGlyph('Z'));
    EXPECT_TRUE(hasGlyph('%'));
    EXPECT_FALSE(hasGlyph('~'));
    // Lower case draws the upper-case glyph.
    std::vector<uint8_t> a(6 * 7 * 3, 0), b(6 * 7 * 3, 0), box(6 * 7 * 3, 0);
    drawText(a.data(), 6, 7, 0, 0, "k", {9, 9, 9});
    drawText(b.data(), 6, 7, 0, 0, "K", {9, 9, 9});
    EXPECT_EQ(a, b);
    // A missing glyph is a hollow 5x7 box: 5 + 5 + 2 * 5 = 20 cells.
    drawText(box.data(), 6, 7, 0, 0, "~", {9, 9, 9});
    int set = 0;
    for (size_t i = 0; i < box.size(); i += 3) set += box[i] == 9;
    EXPECT_EQ(set, 20);
    // Drawing outside the image is clipped, not a crash.
    drawText(box.data(), 6, 7, -3, 5, "888", {1, 1, 1}, 4);
    drawText(box.data(), 6, 7, 100, 100, "8", {1, 1, 1});
}

// ---- Console -----------------------------------------------------------------------------------

TEST(ReportConsole, FunnelTable) {
    const std::string expected =
        "view 'spawn' 4x3 unorm24 perspective\n"
        "  stage      status      tris in      culled         out        ms\n"
        "  cells      skipped scene has no cells\n"
        "  grid       ran            1200         200        1000       0.0\n"
        "  frustum    ran            1000         400         600       0.2\n"
        "  occlusion  skipped no occluders selected\n"
        "  backface   ran             600         280         320       0.5\n"
        "  clip       ran             320          20         310       1.2\n"
        "  zbuffer    ran             310           0         310       3.0\n"
        "  zbuffer: 9 covered pixels, overdraw 1.33, depth complexity 1.67 (max 3)\n";
    EXPECT_EQ(funnelTable(spawnView()), expected);
}

TEST(ReportConsole, WideNumbersAndNonFinite) {
    ViewResult v = orthoView("top");
    v.stages = {stage("frustum", 123456789012ull, 1, 123456789011ull, 1234.56)};
    v.zbuffer.overdraw = std::numeric_limits<double>::quiet_NaN();
    const std::string t = funnelTable(v);
    EXPECT_NE(t.find("  frustum    ran     123456789012           1 123456789011    1234.6\n"), std::string::npos) << t;
    EXPECT_NE(t.find("overdraw n/a, depth complexity 1.75 (max 2)"), std::string::npos) << t;
}

// DepthGrayScale rounds with x + 0.5 instead of calling lround: the same gray for every depth. The
// values where the two could part are the half-integers x = k + 0.5 and their neighbours; each is
// reached through the depth that lands on it (and the doubles around that depth), plus a sweep.
TEST(DepthGray, RoundsAsLroundDoes) {
    const double dMin = 0.37, dMax = 4211.5;
    const DepthGrayScale gray(dMin, dMax);
    const double logMin = std::log(dMin), logSpan = std::log(dMax) - logMin;
    auto reference = [&](double d) {
        const double t = std::clamp((std::log(d) - logMin) / logSpan, 0.0, 1.0);
        return uint8_t(std::lround(255.0 - t * (255.0 - kDepthPngFarGray)));
    };
    uint64_t checked = 0;
    for (int k = kDepthPngFarGray; k < 255; ++k) {
        const double t = (255.0 - (k + 0.5)) / (255.0 - kDepthPngFarGray);
        double d = std::exp(logMin + t * logSpan);
        for (int step = 0; step < 64; ++step) d = std::nextafter(d, 0.0);
        for (int step = 0; step < 128; ++step, d = std::nextafter(d, INFINITY), ++checked)
            ASSERT_EQ(gray(d), reference(d)) << "depth " << d;
    }
    for (double d = dMin; d <= dMax; d *= 1.0001, ++checked) ASSERT_EQ(gray(d), reference(d)) << "depth " << d;
    EXPECT_EQ(gray(dMin), 255);
    EXPECT_EQ(gray(dMax), kDepthPngFarGray);
    EXPECT_EQ(gray(INFINITY), 0);
    EXPECT_GT(checked, 100000u);
}

}  // namespace
}  // namespace va
