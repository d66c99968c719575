// visaudit diff (reports/diff.h; docs/diff.md): two runs of a level with a known change -- a
// second cube hidden behind the first, a wall added to a floor plan -- give exactly the deltas the
// two reports hold, image diffs of exactly the pixels that changed, the level map of the change,
// and exit 1 with the regression named; bad input is exit 2 with the reason.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "reports/level_maps.h"
#include "reports/report.h"
#include "tests/temp_dir_test.h"

namespace fs = std::filesystem;

namespace va {
namespace {

using Json = nlohmann::ordered_json;

// Cubes [-1, 1]^3 moved by (dx, 0, 0), faces counter-clockwise from outside, as OBJ text.
std::string cubesObj(const std::vector<double> &dxs) {
    std::ostringstream s;
    const int q[6][4] = {{1, 3, 7, 5}, {0, 4, 6, 2}, {2, 6, 7, 3}, {0, 1, 5, 4}, {4, 5, 7, 6}, {0, 2, 3, 1}};
    for (size_t c = 0; c < dxs.size(); ++c) {
        s << "o cube" << c << "\n";
        for (int i = 0; i < 8; ++i)
            s << "v " << (i & 1 ? 1 : -1) + dxs[c] << " " << (i & 2 ? 1 : -1) << " " << (i & 4 ? 1 : -1) << "\n";
        const int base = int(c) * 8 + 1;
        for (const auto &f : q) s << "f " << f[0] + base << " " << f[1] + base << " " << f[2] + base << " " << f[3] + base << "\n";
    }
    return s.str();
}

class DiffTest : public testing_util::TempDirTest {
  protected:
    DiffTest() : TempDirTest("diff") {}
    struct Run {
        int code = -1;
        std::string out, err;
    };
    Run run(const std::string &args) {
        const fs::path o = dir_ / "stdout.txt", e = dir_ / "stderr.txt";
        const int status = std::system((std::string(VISAUDIT_BINARY) + " " + args + " </dev/null >" + o.string() + " 2>" +
                                        e.string()).c_str());
        return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(o), slurp(e)};
    }
    static std::string slurp(const fs::path &p) {
        std::ifstream f(p, std::ios::binary);
        std::stringstream s;
        s << f.rdbuf();
        return s.str();
    }
    static Json json(const fs::path &p) { return Json::parse(slurp(p)); }
};

// OLD: one cube seen from +x; NEW: the same file with a second cube hidden behind it (a level's
// change that adds geometry nobody sees). Exactly: triangles drawn 2 -> 4, wasted-draw share 0 ->
// 0.5, overdraw 1 -> 1 (the hidden cube is drawn after and fails the depth test), false culls 0 ->
// 0; the overdraw image changes at exactly the pixels where two fragments now land, the depth
// image nowhere.
TEST_F(DiffTest, AHiddenCubeIsExactlyTheChangeAndARegression) {
    const fs::path scene = dir_ / "level.obj";
    std::ofstream(dir_ / "views.json")
        << "{\"views\": [{\"name\": \"front\", \"eye\": [5, 0, 0], \"target\": [0, 0, 0], \"width\": 64, \"height\": 36}]}\n";
    const std::string args = scene.string() + " --views " + (dir_ / "views.json").string() + " --quiet --images key";
    std::ofstream(scene) << cubesObj({0});
    ASSERT_EQ(run("analyze " + args + " --out " + (dir_ / "old").string()).code, 0);
    std::ofstream(scene) << cubesObj({0, -4});
    ASSERT_EQ(run("analyze " + args + " --out " + (dir_ / "new").string()).code, 0);
    std::ofstream(dir_ / "budget.json") << "{\"format\": \"visaudit-budget/1\", \"limits\": {\"overdraw\": 0.5},\n"
                                           " \"regressions\": {\"zbuffer_triangles\": 0.5, \"overdraw\": 0}}\n";
    const Run r = run("diff " + (dir_ / "old").string() + " " + (dir_ / "new" / "report.json").string() + " --out " +
                      (dir_ / "diff").string() + " --budget " + (dir_ / "budget.json").string() + " --junit " +
                      (dir_ / "junit.xml").string());
    // The budget's regressions only (its overdraw limit of 0.5 is check's business): zbuffer_triangles
    // rose 100%, overdraw did not rise.
    EXPECT_EQ(r.code, 1) << r.err;
    EXPECT_NE(r.out.find("FAIL: zbuffer_triangles in view 'front' rose 100%, allowed 50%\n1 passed, 1 failed\n"),
              std::string::npos)
        << r.out;
    EXPECT_NE(slurp(dir_ / "junit.xml").find("name=\"regression zbuffer_triangles\">"), std::string::npos);

    const Json d = json(dir_ / "diff" / "diff.json");
    EXPECT_EQ(d["format"], "visaudit-diff/1");
    EXPECT_EQ(d["old"]["scene"]["source_triangles"], 12);
    EXPECT_EQ(d["new"]["scene"]["source_triangles"], 24);
    ASSERT_EQ(d["views"].size(), 1u);
    const Json &m = d["views"][0]["metrics"];
    EXPECT_EQ(m["triangles_drawn"], (Json{{"old", 2}, {"new", 4}, {"delta", 2}, {"relative", 1.0}}));
    EXPECT_EQ(m["wasted_share"], (Json{{"old", 0.0}, {"new", 0.5}, {"delta", 0.5}, {"relative", nullptr}}));
    EXPECT_EQ(m["overdraw"]["delta"], 0.0);
    EXPECT_EQ(m["false_cull_pixels"]["delta"], 0);
    EXPECT_TRUE(d["views"][0]["changed"]);
    EXPECT_EQ(d["totals"]["views_rose"]["triangles_drawn"], 1);
    EXPECT_EQ(d["regressions"]["failed"], 1);
    // Image diffs: the depth image is the same; the overdraw image changed at the pixels holding two
    // fragments in NEW (its histogram[2]), and nowhere else.
    const Json newReport = json(dir_ / "new" / "report.json");
    const uint64_t twoFragments = newReport["views"][0]["zbuffer"]["histogram"][2];
    ASSERT_GT(twoFragments, 0u);
    bool sawDepth = false, sawOverdraw = false;
    for (const Json &e : d["views"][0]["images"]) {
        if (e["kind"] == "depth_png") {
            sawDepth = true;
            EXPECT_EQ(e["changed_pixels"], 0);
            EXPECT_FALSE(e.contains("diff"));
        }
        if (e["kind"] == "overdraw_png") {
            sawOverdraw = true;
            EXPECT_EQ(e["changed_pixels"], twoFragments);
            ASSERT_EQ(e["diff"], "front.overdraw.diff.png");
            // The diff image marks exactly those pixels (magenta), the legend strip aside.
            ImageData im;
            std::string err;
            ASSERT_TRUE(readImage((dir_ / "diff" / "front.overdraw.diff.png").string(), &im, &err)) << err;
            uint64_t magenta = 0;
            for (size_t p = 0; p < size_t(im.width) * im.height; ++p)
                magenta += im.u8[3 * p] == 255 && im.u8[3 * p + 1] == 40 && im.u8[3 * p + 2] == 200;
            EXPECT_EQ(magenta, twoFragments);
        }
    }
    EXPECT_TRUE(sawDepth && sawOverdraw);
    const std::string html = slurp(dir_ / "diff" / "diff.html");
    EXPECT_NE(html.find("<b>1 regression</b>"), std::string::npos);
    EXPECT_NE(html.find("src=\"front.overdraw.diff.png\""), std::string::npos);
}

// A wall added to a level (edge-on from above: the floor plan and the grid's positions stay): the
// level maps of the change hold, per position, NEW's value minus OLD's.
TEST_F(DiffTest, LevelMapOfTheChangeIsNewMinusOldPerPosition) {
    const fs::path scene = dir_ / "level.obj";
    std::ofstream(dir_ / "level.scene.json")
        << "{\"format\": \"visaudit-scene/1\", \"up\": \"z\", \"objects\": [{\"name\": \"level\", \"mesh\": \"level.obj\"}]}\n";
    const std::string floor = "v 0 0 0\nv 16 0 0\nv 16 8 0\nv 0 8 0\nv 4 2 2\nv 6 2 2\nv 6 4 2\nv 4 4 2\nf 1 2 3 4\nf 5 6 7 8\n";
    const std::string args = (dir_ / "level.scene.json").string() +
                             " --views grid:8:4 --width 32 --height 18 --map-size 96 --no-ordering --images key --quiet";
    std::ofstream(scene) << floor;
    ASSERT_EQ(run("analyze " + args + " --out " + (dir_ / "old").string()).code, 0);
    // A wall at x = 12 facing -x (towards most positions), 3 high.
    std::ofstream(scene) << floor << "v 12 1 0\nv 12 7 0\nv 12 7 3\nv 12 1 3\nf 9 12 11 10\n";
    ASSERT_EQ(run("analyze " + args + " --out " + (dir_ / "new").string()).code, 0);
    const Run r = run("diff " + (dir_ / "old").string() + " " + (dir_ / "new").string() + " --out " + (dir_ / "diff").string());
    ASSERT_EQ(r.code, 0) << r.err;
    const Json o = json(dir_ / "old" / "report.json"), n = json(dir_ / "new" / "report.json");
    ASSERT_EQ(o["level_maps"]["positions"], n["level_maps"]["positions"]);
    const Json d = json(dir_ / "diff" / "diff.json");
    ASSERT_TRUE(d.contains("level_maps"));
    const Json &dm = d["level_maps"]["maps"][0];
    ASSERT_EQ(dm["metric"], "triangles_drawn");
    const Json &ov = o["level_maps"]["maps"][0]["values"], &nv = n["level_maps"]["maps"][0]["values"];
    ASSERT_EQ(dm["values"].size(), nv.size());
    bool rose = false;
    for (size_t k = 0; k < nv.size(); ++k) {
        EXPECT_EQ(dm["values"][k].get<double>(), nv[k].get<double>() - ov[k].get<double>()) << k;
        rose |= dm["values"][k].get<double>() > 0;
    }
    EXPECT_TRUE(rose);
    EXPECT_GT(dm["worst"][0]["value"].get<double>(), 0);
    EXPECT_TRUE(fs::exists(dir_ / "diff" / "level-map-diff-triangles_drawn.png"));
}

TEST_F(DiffTest, BadInputIsExitTwoWithTheReason) {
    std::ofstream(dir_ / "a.obj") << cubesObj({0});
    std::ofstream(dir_ / "b.obj") << cubesObj({0});
    ASSERT_EQ(run("analyze " + (dir_ / "a.obj").string() + " --views orbit:1 --width 32 --height 18 --quiet --images none --out " +
                  (dir_ / "a").string()).code, 0);
    ASSERT_EQ(run("analyze " + (dir_ / "b.obj").string() + " --views orbit:1 --width 32 --height 18 --quiet --images none --out " +
                  (dir_ / "b").string()).code, 0);
    const fs::path out = dir_ / "diff";
    Run r = run("diff " + (dir_ / "a").string() + " " + (dir_ / "b").string() + " --out " + out.string());
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.err, "visaudit: error: OLD and NEW are reports of different scenes: " + (dir_ / "a").string() + " is of '" +
                         (dir_ / "a.obj").string() + "', " + (dir_ / "b").string() + " of '" + (dir_ / "b.obj").string() +
                         "'; diff compares two runs of one scene (analyze both versions of the level under the same path)\n");
    EXPECT_FALSE(fs::exists(out));
    r = run("diff " + (dir_ / "a").string() + " " + (dir_ / "nothing").string() + " --out " + out.string());
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.err, "visaudit: error: NEW " + (dir_ / "nothing").string() +
                         ": cannot be read; give the report.json (or the --out folder) of an analyze or check run\n");
    std::ofstream(dir_ / "other.json") << "{\"format\": \"visaudit-budget/1\"}\n";
    r = run("diff " + (dir_ / "other.json").string() + " " + (dir_ / "b").string() + " --out " + out.string());
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.err, "visaudit: error: OLD " + (dir_ / "other.json").string() +
                         ": not a visaudit-report/1 report; diff compares two reports written by this visaudit version "
                         "(re-run analyze)\n");
    EXPECT_FALSE(fs::exists(out));
}

}  // namespace
}  // namespace va
