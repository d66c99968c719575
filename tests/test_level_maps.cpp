// Level maps (analysis/level_map.h, reports/level_maps.h; docs/level-maps.md): the floor plan drawn
// by the project's rasterizer from above agrees with the world positions it claims (every pixel),
// each sample position lands on the map image at the pixel its eye projects to and takes the colour
// of its value, grid:N stands on floors, and shards of a grid merge into the single run's maps.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "analysis/level_map.h"
#include "analysis/level_samples.h"
#include "reports/level_maps.h"
#include "tests/temp_dir_test.h"

namespace fs = std::filesystem;

namespace va {
namespace {

using Json = nlohmann::ordered_json;

// A quad (a, b, c, d), counter-clockwise seen from the side its normal points to.
void addQuad(RawMesh &m, Vec3 a, Vec3 b, Vec3 c, Vec3 d) {
    const uint32_t k = uint32_t(m.positions.size());
    m.positions.insert(m.positions.end(), {a, b, c, d});
    m.indices.insert(m.indices.end(), {k, k + 1, k + 2, k, k + 2, k + 3});
    m.facesRead += 2;
}

// z up: a floor [0, 16] x [0, 8] at z = 0 facing up; a platform [4, 6] x [2, 4] at z = 2 facing up;
// a ceiling [10, 14] x [2, 6] at z = 5 facing down (seen from above: its back, so not drawn).
Scene levelScene() {
    RawMesh m;
    addQuad(m, {0, 0, 0}, {16, 0, 0}, {16, 8, 0}, {0, 8, 0});
    addQuad(m, {4, 2, 2}, {6, 2, 2}, {6, 4, 2}, {4, 4, 2});
    addQuad(m, {10, 2, 5}, {10, 6, 5}, {14, 6, 5}, {14, 2, 5});
    SceneBuildInput in;
    in.up = 'z';
    in.materials = {Material{}};
    SceneBuildInput::Object o;
    o.name = "level";
    o.geometry = std::move(m);
    in.objects.push_back(std::move(o));
    return buildScene(std::move(in));
}

TEST(LevelMap, FloorPlanPixelsAgreeWithTheWorldPositionsTheyClaim) {
    const Scene s = levelScene();
    FloorPlanSettings fs;
    fs.size = 64;
    FloorPlan plan;
    std::string err;
    ASSERT_TRUE(renderFloorPlan(s, fs, &plan, &err)) << err;
    // 16 units plus 2% margins on 64 pixels: 0.26 units per pixel; 8.64 / 0.26 rounds up to 34 rows.
    EXPECT_DOUBLE_EQ(plan.worldPerPixel, 16.64 / 64);
    EXPECT_EQ(plan.width, 64);
    EXPECT_EQ(plan.height, 34);
    EXPECT_TRUE(plan.camera.orthographic);
    EXPECT_EQ(plan.camera.up, (Vec3{0, 1, 0}));  // z up: the map's top is +y
    // The camera's raster, by the formula docs/level-maps.md gives: column = (x - left) / pixel,
    // row = (top - y) / pixel, with left and top the image's edges around the camera's eye.
    const double px = plan.worldPerPixel, left = plan.camera.eye.x - plan.width * px / 2,
                 top = plan.camera.eye.y + plan.height * px / 2;
    size_t platform = 0, floor = 0, none = 0;
    for (int y = 0; y < plan.height; ++y)
        for (int x = 0; x < plan.width; ++x) {
            const Vec3 w = floorWorldAt(plan, x, y, 0);
            EXPECT_NEAR(w.x, left + (x + 0.5) * px, 1e-12);
            EXPECT_NEAR(w.y, top - (y + 0.5) * px, 1e-12);
            double cx = 0, cy = 0;
            ASSERT_TRUE(floorPixelOf(plan.camera, w, &cx, &cy));
            EXPECT_NEAR(cx, x + 0.5, 1e-9);
            EXPECT_NEAR(cy, y + 0.5, 1e-9);
            // Away from the edges by a pixel: what the renderer must have drawn there.
            auto inside = [&](double x0, double y0, double x1, double y1) {
                return w.x > x0 + px && w.x < x1 - px && w.y > y0 + px && w.y < y1 - px;
            };
            auto outside = [&](double x0, double y0, double x1, double y1) {
                return w.x < x0 - px || w.x > x1 + px || w.y < y0 - px || w.y > y1 + px;
            };
            const float h = plan.surface[size_t(y) * plan.width + x];
            if (inside(4, 2, 6, 4)) {
                EXPECT_EQ(h, 2.0f) << x << "," << y;
                ++platform;
            } else if (inside(0, 0, 16, 8) && outside(4, 2, 6, 4)) {
                EXPECT_EQ(h, 0.0f) << x << "," << y;  // the ceiling faces down: the floor shows
                ++floor;
            } else if (outside(0, 0, 16, 8)) {
                EXPECT_TRUE(std::isnan(h)) << x << "," << y;
                EXPECT_EQ(plan.gray[size_t(y) * plan.width + x], 0);
                ++none;
            }
        }
    EXPECT_GT(platform, 20u);
    EXPECT_GT(floor, 1000u);
    EXPECT_GT(none, 50u);
}

// A report of views at known eyes with known scores over the floor plan: the positions are the
// eyes' pixels, views at one eye are one position with the highest value, and the map image has
// each position's colour at its pixel.
TEST(LevelMap, PositionsLandOnTheirPixelsInTheirColour) {
    const Scene s = levelScene();
    FloorPlanSettings fs;
    fs.size = 64;
    FloorPlan plan;
    std::string err;
    ASSERT_TRUE(renderFloorPlan(s, fs, &plan, &err)) << err;
    Json report;
    report["views"] = Json::array();
    struct V {
        Vec3 eye;
        Json triangles;
    };
    const std::vector<V> vs = {{{2, 2, 1.7}, 10}, {{8, 6, 1.7}, 40}, {{8, 6, 1.7}, 70}, {{13, 1, 1.7}, nullptr},
                               {{15, 7, 1.7}, 25}, {{40, 40, 1.7}, 99}};  // the last is off the map
    for (size_t i = 0; i < vs.size(); ++i)
        report["views"].push_back({{"name", "v" + std::to_string(i)},
                                   {"camera", {{"eye", {vs[i].eye.x, vs[i].eye.y, vs[i].eye.z}}}},
                                   {"findings", {{"score", {{"triangles_drawn", vs[i].triangles}}}}}});
    report["level_maps"] = {{"floor", floorPlanJson(plan)}};
    addLevelMaps(&report);
    const Json &lm = report["level_maps"];
    ASSERT_EQ(lm["positions"].size(), 4u);  // v1 and v2 share an eye; v5 is off the map
    EXPECT_EQ(lm["positions"][1]["views"], (Json{1, 2}));
    const double px = plan.worldPerPixel, left = plan.camera.eye.x - plan.width * px / 2,
                 top = plan.camera.eye.y + plan.height * px / 2;
    const Json &map = lm["maps"][0];
    EXPECT_EQ(map["metric"], "triangles_drawn");
    EXPECT_EQ(map["values"], (Json{10, 70, nullptr, 25}));
    EXPECT_EQ(map["view"], (Json{0, 2, nullptr, 4}));
    EXPECT_EQ(map["min"], 10);
    EXPECT_EQ(map["max"], 70);
    ASSERT_EQ(map["worst"].size(), 3u);
    EXPECT_EQ(map["worst"][0], (Json{{"rank", 1}, {"position", 1}, {"view", 2}, {"value", 70}}));
    const Canvas floor = floorPlanCanvas(plan);
    const Canvas img = levelMapImage(lm, 0, floor, report["views"]);
    EXPECT_EQ(img.width, plan.width);
    EXPECT_GT(img.height, plan.height);  // the legend strip below
    const std::vector<Rgb8> want = {rampColor(0), rampColor(1), {150, 150, 150}, rampColor(15.0 / 60)};
    const std::vector<size_t> eyeOf = {0, 1, 3, 4};
    for (size_t k = 0; k < 4; ++k) {
        const Vec3 e = vs[eyeOf[k]].eye;
        EXPECT_NEAR(lm["positions"][k]["x"].get<double>(), (e.x - left) / px, 1e-9) << k;
        EXPECT_NEAR(lm["positions"][k]["y"].get<double>(), (top - e.y) / px, 1e-9) << k;
        const int x = int(std::floor((e.x - left) / px)), y = int(std::floor((top - e.y) / px));
        EXPECT_EQ(img.at(x, y), want[k]) << k;
        // Away from the dot (radius 2 at this size; labels to its side) the floor shows through.
        const int away = y < plan.height / 2 ? y + 6 : y - 6;
        EXPECT_EQ(img.at(x, away), floor.at(x, away)) << k;
    }
    // rampColor's ends: the worst red, the best dark blue.
    EXPECT_EQ(rampColor(1), (Rgb8{220, 40, 30}));
    EXPECT_EQ(rampColor(0), (Rgb8{30, 40, 140}));
}

TEST(LevelMap, GridViewsStandOnFloorsAtEyeHeight) {
    const Scene s = levelScene();
    std::string err;
    const std::vector<ViewSpec> views = gridViews(s, 12, 4, 1.7, &err);
    ASSERT_EQ(views.size(), 48u) << err;
    for (size_t i = 0; i < views.size(); ++i) {
        const ViewSpec &v = views[i];
        const size_t k = i / 4, d = i % 4;
        EXPECT_EQ(v.name, "grid" + std::to_string(k) + "-yaw" + std::to_string(90 * d));
        EXPECT_EQ(v.origin, "grid:12:4");
        EXPECT_EQ(v.camera.eye, views[4 * k].camera.eye);
        const Vec3 e = v.camera.eye;
        EXPECT_TRUE(e.x > 0 && e.x < 16 && e.y > 0 && e.y < 8) << e.x << "," << e.y;
        // On the platform 2 + 1.7 above the floor, elsewhere 1.7.
        const bool onPlatform = e.x > 4 && e.x < 6 && e.y > 2 && e.y < 4;
        EXPECT_NEAR(e.z, onPlatform ? 3.7 : 1.7, 1e-6);
        // Yaw d * 90 from +x about z.
        const Vec3 dir = v.camera.target - v.camera.eye;
        EXPECT_NEAR(dir.x, std::cos(d * kPi / 2), 1e-12);
        EXPECT_NEAR(dir.y, std::sin(d * kPi / 2), 1e-12);
    }
    // Nothing to stand on (a ceiling only, facing down): refused with the count and a fix.
    RawMesh m;
    addQuad(m, {10, 2, 5}, {10, 6, 5}, {14, 6, 5}, {14, 2, 5});
    SceneBuildInput in;
    in.up = 'z';
    in.path = "ceiling.obj";
    in.materials = {Material{}};
    in.objects.push_back({"ceiling", "", 0, std::move(m)});
    EXPECT_TRUE(gridViews(buildScene(std::move(in)), 5, 1, 1.7, &err).empty());
    EXPECT_EQ(err, "--views grid:5: 'ceiling.obj' has only 0 places to stand on its floor plan at 1024x1024 pixels; "
                   "ask for fewer positions");
}

// The command line: a grid over a scene file, the maps written; two shards merge into the single
// run's level maps, images byte for byte.
class LevelMapCliTest : public testing_util::TempDirTest {
  protected:
    LevelMapCliTest() : TempDirTest("level-maps") {}
    int run(const std::string &args) {
        const int status = std::system((std::string(VISAUDIT_BINARY) + " " + args + " </dev/null >" +
                                        (dir_ / "out.txt").string() + " 2>" + (dir_ / "err.txt").string())
                                           .c_str());
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    }
    std::string slurp(const fs::path &p) {
        std::ifstream f(p, std::ios::binary);
        std::stringstream s;
        s << f.rdbuf();
        return s.str();
    }
};

TEST_F(LevelMapCliTest, GridMapsAreWrittenDeterministicallyAndShardsMergeIntoTheSameMaps) {
    std::ofstream(dir_ / "level.obj") << "v 0 0 0\nv 16 0 0\nv 16 8 0\nv 0 8 0\nv 4 2 2\nv 6 2 2\nv 6 4 2\nv 4 4 2\n"
                                         "f 1 2 3 4\nf 5 6 7 8\n";
    std::ofstream(dir_ / "level.scene.json")
        << "{\"format\": \"visaudit-scene/1\", \"up\": \"z\", \"objects\": [{\"name\": \"level\", \"mesh\": \"level.obj\"}]}\n";
    ::setenv("VISAUDIT_FIXED_TIMINGS", "1", 1);
    const std::string common = (dir_ / "level.scene.json").string() +
                               " --views grid:6:2 --width 32 --height 18 --map-size 96 --no-ordering --images key --quiet";
    ASSERT_EQ(run("analyze " + common + " --out " + (dir_ / "single").string()), 0) << slurp(dir_ / "err.txt");
    ASSERT_EQ(run("analyze " + common + " --threads 1 --out " + (dir_ / "one").string()), 0);
    ASSERT_EQ(run("analyze " + common + " --shard 1/2 --out " + (dir_ / "s1").string()), 0);
    ASSERT_EQ(run("analyze " + common + " --shard 2/2 --out " + (dir_ / "s2").string()), 0);
    ASSERT_EQ(run("merge " + (dir_ / "s1").string() + " " + (dir_ / "s2").string() + " --out " + (dir_ / "merged").string() +
                  " --quiet"),
              0)
        << slurp(dir_ / "err.txt");
    ::unsetenv("VISAUDIT_FIXED_TIMINGS");
    const Json single = Json::parse(slurp(dir_ / "single" / "report.json"));
    const Json merged = Json::parse(slurp(dir_ / "merged" / "report.json"));
    ASSERT_TRUE(single.contains("level_maps"));
    EXPECT_EQ(single["level_maps"]["positions"].size(), 6u);
    for (const Json &p : single["level_maps"]["positions"]) EXPECT_EQ(p["views"].size(), 2u);
    EXPECT_EQ(merged["level_maps"], single["level_maps"]);
    EXPECT_EQ(Json::parse(slurp(dir_ / "one" / "report.json"))["level_maps"], single["level_maps"]);
    for (const char *m : {"floor", "triangles_drawn", "overdraw", "wasted_share", "false_cull_pixels"}) {
        const std::string name = std::string("level-map-") + m + ".png";
        ASSERT_TRUE(fs::exists(dir_ / "single" / name)) << name;
        EXPECT_TRUE(slurp(dir_ / "single" / name) == slurp(dir_ / "merged" / name)) << name << " differs";
        // The same bytes on one thread as on all (the views' results do not depend on it).
        EXPECT_TRUE(slurp(dir_ / "single" / name) == slurp(dir_ / "one" / name)) << name << " differs on one thread";
    }
    // The page shows the maps with their worst positions linked to the views.
    const std::string html = slurp(dir_ / "single" / "report.html");
    EXPECT_NE(html.find("<section class=\"block\" id=\"level-maps\">"), std::string::npos);
    EXPECT_NE(html.find("class=\"lm-pin\" href=\"#v"), std::string::npos);
}

}  // namespace
}  // namespace va
