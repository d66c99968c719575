// Real-world and hostile files (issue 16): every input loads whole or is refused clearly.
//   JsonNesting*  every JSON input is checked for its nesting depth before it is parsed, and no walk
//                 of a parsed document recurses (inputs a few hundred thousand levels deep, made here)
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/json_util.h"
#include "common/limits.h"
#include "reports/grade.h"
#include "reports/report.h"
#include "tests/run_binary.h"
#include "tests/temp_dir_test.h"

namespace va {
namespace {

namespace fs = std::filesystem;
using testing_util::runBinary;

// Deeper than any stack: nlohmann's dump, copy and comparison, and the recursive walks this project
// had, overflowed the 8 MiB main-thread stack at about 70 000 levels (Release).
constexpr size_t kHostileDepth = 300000;

std::string nested(size_t depth, const std::string &inner = "") {
    return std::string(depth, '[') + inner + std::string(depth, ']');
}

class JsonNestingTest : public testing_util::TempDirTest {
  protected:
    JsonNestingTest() : TempDirTest("jsonnest") {}
    std::string write(const std::string &name, const std::string &text) {
        const fs::path p = dir_ / name;
        fs::create_directories(p.parent_path());
        std::ofstream(p, std::ios::binary) << text;
        return p.string();
    }
};

TEST(JsonNesting, CheckDepthCountsArraysAndObjectsNotStrings) {
    std::string err;
    EXPECT_TRUE(json::checkDepth("1", "f", 1, &err));
    EXPECT_TRUE(json::checkDepth("[[1]]", "f", 2, &err));
    EXPECT_TRUE(json::checkDepth(R"({"a": [1, {"b": 2}], "c": [3]})", "f", 3, &err));
    // Brackets in strings, escaped quotes and backslashes included, open nothing.
    EXPECT_TRUE(json::checkDepth(R"(["[[[{{", "\"[[", "\\", "{"])", "f", 1, &err));
    // A truncated text still gets its depth counted (its syntax error comes from the parser).
    EXPECT_TRUE(json::checkDepth("[[[", "f", 3, &err));

    ASSERT_FALSE(json::checkDepth("[[1]]", "f.json", 1, &err));
    EXPECT_EQ(err, "f.json:1:2: arrays and objects nested 2 levels deep, more than the limit of 1; "
                   "raise it with --max-json-depth 2 if the file is meant to nest so deep");
    // Placed at the first bracket past the limit; the depth is the text's deepest point.
    ASSERT_FALSE(json::checkDepth("{\n  \"a\": [1],\n  \"b\": [[[2]]]\n}", "g.json", 2, &err));
    EXPECT_EQ(err, "g.json:3:9: arrays and objects nested 4 levels deep, more than the limit of 2; "
                   "raise it with --max-json-depth 4 if the file is meant to nest so deep");
    // Beyond what the flag accepts, the message says the flag cannot help.
    ASSERT_FALSE(json::checkDepth(nested(kHostileDepth), "h.json", kDefaultMaxJsonDepth, &err));
    EXPECT_EQ(err, "h.json:1:513: arrays and objects nested 300000 levels deep, more than the limit of 512; "
                   "--max-json-depth accepts at most 2048 (no scene, views, glTF, budget or report file nests so "
                   "deep): the file is damaged or was made to exhaust a parser's stack");
}

// json::locate (the FILE:LINE:COL of an error) skipped sibling values recursively: a views file
// whose first view held a deep array crashed when the error was placed after it. It now counts
// brackets; called here on a text no recursion survives.
TEST(JsonNesting, LocateSkipsDeepValuesWithoutRecursion) {
    const std::string text = "{\"a\": " + nested(kHostileDepth) + ",\n\"b\": [7, 8]}";
    const size_t at = json::locate(text, json::Path{} / "b" / 1);
    EXPECT_EQ(text.substr(at, 2), "8]");
    size_t line = 0, col = 0;
    json::lineCol(text, at, &line, &col);
    EXPECT_EQ(line, 2u);
    EXPECT_EQ(col, 10u);
}

// grade flattened a view's stages recursively: a submission with a deep value in a stage crashed.
// nlohmann parses and destroys without recursion, so the document is made here; the walk keeps its
// own stack now.
TEST(JsonNesting, GradeWalksADeepSubmissionWithoutRecursion) {
    const auto ref = nlohmann::ordered_json::parse(
        R"({"views": [{"name": "v", "stages": [{"name": "frustum", "ran": true, "triangles_out": 3}]}]})");
    auto sub = ref;
    sub["views"][0]["stages"][0]["deep"] = nlohmann::ordered_json::parse(nested(kHostileDepth, "1"));
    GradeResult g;
    std::string err;
    ASSERT_TRUE(gradeReports(ref, sub, {}, &g, &err)) << err;
    EXPECT_EQ(g.passed, 1u);
    EXPECT_EQ(g.failed, 0u);
    // The submission's deep number is flattened with its full path and ignored (not in the reference).
    ASSERT_EQ(g.items.size(), 1u);
    EXPECT_EQ(g.items[0].key, "triangles_out");
    // Document order is kept by the explicit stack.
    auto two = nlohmann::ordered_json::parse(
        R"({"views": [{"name": "v", "stages": [{"name": "clip", "ran": true, "a": [1, [2, 3]], "b": {"c": 4}}]}]})");
    ASSERT_TRUE(gradeReports(two, two, {}, &g, &err)) << err;
    std::vector<std::string> keys;
    for (const GradeItem &it : g.items) keys.push_back(it.key);
    EXPECT_EQ(keys, (std::vector<std::string>{"a.0", "a.1.0", "a.1.1", "b.c"}));
}

// Every JSON input of every command, nested 300 000 levels deep where each used to be walked
// (before: exit 139 for the views file, the scene's and budget's error placement, the grade
// submission and the merged shard): exit 2, the file, the place, the depth, the limit and the flag.
TEST_F(JsonNestingTest, EveryInputRefusesHostileNesting) {
    const std::string deep = nested(kHostileDepth);
    const std::string tail = " levels deep, more than the limit of 512; --max-json-depth accepts at most 2048 (no "
                             "scene, views, glTF, budget or report file nests so deep): the file is damaged or was "
                             "made to exhaust a parser's stack\n";
    // What each file holds; the column of the first bracket past the limit follows from the prefix
    // (`{"a": ` opens one level in 6 characters: the 512th '[' is at column 518, 300001 levels deep).
    const std::string scene = write("deep.scene.json", "{\"a\": " + deep + ", \"format\": \"visaudit-scene/1\"}");
    const std::string views = write("deep.views.json", "{\"views\": [{\"x\": " + deep + "}]}");
    const std::string budget = write("deep.budget.json", "{\"a\": " + deep + ", \"format\": \"x\"}");
    const std::string tol = write("deep.tol.json", "{\"a\": " + deep + ", \"format\": \"x\"}");
    const std::string report = "{\"format\": \"visaudit-report/1\", \"views\": [{\"name\": \"v\", \"stages\": [{\"name\": "
                               "\"clip\", \"ran\": true, \"x\": " + deep + "}]}]}";
    const std::string sub = write("deep.report.json", report);
    write("shard/report.json", report);
    const std::string shard = (dir_ / "shard").string();
    const std::string demoViews = write("ok.views.json", R"({"views": [{"eye": [0, 2, 8], "target": [0, 0, 0]}]})");

    struct Case {
        std::vector<std::string> args;
        std::string message;  // up to the depth
    };
    const std::vector<Case> cases = {
        {{"info", scene}, scene + ":1:518: arrays and objects nested 300001"},
        {{"info", "--views", views}, views + ":1:527: arrays and objects nested 300003"},
        {{"check", "--budget", budget, "--views", demoViews, "--out", (dir_ / "c").string()},
         budget + ":1:518: arrays and objects nested 300001"},
        {{"check", "--budget", budget, "--baseline", sub, "--views", demoViews, "--out", (dir_ / "c").string()},
         "--baseline " + sub + ":1:610: arrays and objects nested 300005"},
        {{"grade", "--reference", sub, "--submission", sub}, "--reference " + sub + ":1:610: arrays and objects nested 300005"},
        {{"grade", "--reference", demoViews, "--submission", demoViews, "--tolerance", tol},
         tol + ":1:518: arrays and objects nested 300001"},
        {{"merge", shard, "--out", (dir_ / "m").string()},
         (dir_ / "shard" / "report.json").string() + ":1:610: arrays and objects nested 300005"},
        {{"depth-audit", "--scene", scene}, scene + ":1:518: arrays and objects nested 300001"},
    };
    for (const Case &c : cases) {
        const auto r = runBinary(c.args, dir_);
        EXPECT_EQ(r.signal, 0) << c.args[0] << " " << c.args[1];
        EXPECT_EQ(r.code, 2) << c.args[0] << " " << c.args[1];
        EXPECT_EQ(r.err, "visaudit: error: " + c.message + tail) << c.args[0] << " " << c.args[1];
        EXPECT_FALSE(fs::exists(dir_ / "c") || fs::exists(dir_ / "m"));
    }
}

// The limit is exact: 512 levels pass the depth check (and meet the file's own schema check), 513
// are refused, and --max-json-depth lets them through; the flag's range ends at the ceiling.
TEST_F(JsonNestingTest, LimitIsExactAndTheFlagRaisesIt) {
    // {"views": [{"eye": [...]}]}: 3 levels around the eye's array, whose nesting makes the rest.
    auto viewsAt = [&](size_t depth) {
        return write("v" + std::to_string(depth) + ".json",
                     "{\"views\": [{\"eye\": " + nested(depth - 3, "0") + ", \"target\": [0, 0, 0]}]}");
    };
    const std::string v512 = viewsAt(512), v513 = viewsAt(513);
    const std::string schema = ":1:20: views[0].eye: expected an array of 3 numbers, got an array of 1\n";
    auto r = runBinary({"info", "--views", v512}, dir_);
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.err.substr(r.err.find(v512) + v512.size()), schema) << r.err;
    r = runBinary({"info", "--views", v513}, dir_);
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.err, "visaudit: error: " + v513 + ":1:529: arrays and objects nested 513 levels deep, more than the "
                     "limit of 512; raise it with --max-json-depth 513 if the file is meant to nest so deep\n");
    r = runBinary({"info", "--views", v513, "--max-json-depth", "513"}, dir_);
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.err.substr(r.err.find(v513) + v513.size()), schema) << r.err;
    r = runBinary({"info", "--max-json-depth", "2049"}, dir_);
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find("--max-json-depth: Value 2049 not in range 1 to 2048"), std::string::npos) << r.err;
}

// At the ceiling (2048 levels, --max-json-depth 2048) nothing after the check overflows a stack, the
// sanitized build included: merge copies, compares and dumps the shard's views and writes the HTML
// page; grade walks the submission. Shard reports come from a real run with a deep value added.
TEST_F(JsonNestingTest, TheCeilingIsSafeForEveryLaterWalk) {
    const fs::path shard = dir_ / "s";
    auto r = runBinary({"analyze", "--quiet", "--views", "orbit:1", "--width", "32", "--height", "24", "--out",
                        shard.string()},
                       dir_);
    ASSERT_EQ(r.code, 0) << r.err;
    auto report = nlohmann::ordered_json::parse(testing_util::slurpFile(shard / "report.json"));
    // The report's own depth at views[0].deep: top object, "views" array, the view object, then the value.
    report["views"][0]["deep"] = nlohmann::ordered_json::parse(nested(json::kMaxJsonDepthCeiling - 3, "1"));
    std::ofstream(shard / "report.json") << report.dump(1);
    r = runBinary({"merge", shard.string(), "--out", (dir_ / "m").string(), "--max-json-depth", "2048"}, dir_);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.signal, 0);
    EXPECT_TRUE(fs::exists(dir_ / "m" / "report.html"));
    r = runBinary({"grade", "--reference", (shard / "report.json").string(), "--submission",
                   (dir_ / "m" / "report.json").string(), "--max-json-depth", "2048"},
                  dir_);
    EXPECT_EQ(r.code, 0) << r.err;
    // One level more is refused by merge's default and by the ceiling.
    report["views"][0]["deep"] = nlohmann::ordered_json::parse(nested(json::kMaxJsonDepthCeiling - 2, "1"));
    std::ofstream(shard / "report.json") << report.dump(1);
    r = runBinary({"merge", shard.string(), "--out", (dir_ / "m2").string(), "--max-json-depth", "2048"}, dir_);
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find("arrays and objects nested 2049 levels deep, more than the limit of 2048; --max-json-depth "
                         "accepts at most 2048"),
              std::string::npos)
        << r.err;
}

// Issue 16, silent loss: a file whose faces a loader drops says so on stderr (count, reason, first
// place) and in the report; a scene left with no triangle is refused by check (exit 2: an empty
// scene passes every budget) and flagged by analyze and info --json.
TEST_F(JsonNestingTest, DroppedFacesAreSaidAndAnEmptySceneIsRefusedByCheck) {
    const std::string one = write("one.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 1 2\nf 1 2 4\n");
    const std::string none = write("none.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 1 2\n");
    const std::string budget = write("b.json", R"({"format": "visaudit-budget/1", "views": {"*": {}}})");
    const std::string dropped = ": 1 face(s) with fewer than 3 distinct vertices dropped (the first: face 1, counting from 0)";

    auto r = runBinary({"analyze", one, "--views", "orbit:1", "--width", "16", "--height", "16", "--quiet", "--out",
                        (dir_ / "a").string()},
                       dir_);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.err.find("visaudit: warning: " + one + dropped), std::string::npos) << r.err;
    auto report = nlohmann::ordered_json::parse(testing_util::slurpFile(dir_ / "a" / "report.json"));
    EXPECT_EQ(report["scene"]["faces_dropped"], 1);
    EXPECT_EQ(report["scene"]["warnings"], nlohmann::ordered_json::array({one + dropped}));

    const std::string empty = none + ": the scene has no triangle to analyse (0 in the source, 1 faces dropped by the "
                                     "loader, 0 degenerate, 0 non-finite)";
    r = runBinary({"check", none, "--budget", budget, "--views", "orbit:1", "--out", (dir_ / "c").string()}, dir_);
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find("visaudit: error: " + empty + "; check needs geometry to judge: fix the file or its export"),
              std::string::npos)
        << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "c"));

    r = runBinary({"analyze", none, "--views", "orbit:1", "--width", "16", "--height", "16", "--quiet", "--out",
                   (dir_ / "e").string()},
                  dir_);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.err.find("visaudit: warning: " + empty), std::string::npos) << r.err;
    report = nlohmann::ordered_json::parse(testing_util::slurpFile(dir_ / "e" / "report.json"));
    EXPECT_EQ(report["scene"]["triangles"], 0);
    EXPECT_EQ(report["scene"]["warnings"].back(), empty);

    r = runBinary({"info", none, "--json"}, dir_);
    ASSERT_EQ(r.code, 0) << r.err;
    const auto info = nlohmann::ordered_json::parse(r.out);
    EXPECT_EQ(info["triangles"], 0);
    EXPECT_EQ(info["faces_dropped"], 1);
    EXPECT_EQ(info["warnings"].size(), 2u);
}

// --images (issue 18): key writes per view the four PNGs the page shows first, none no image;
// report.json lists exactly the files written and report.html refers to no missing file.
TEST_F(JsonNestingTest, ImagesFlagWritesWhatTheReportLists) {
    for (const std::string mode : {"all", "key", "none"}) {
        const fs::path out = dir_ / ("img-" + mode);
        const auto r = runBinary({"analyze", "--views", "orbit:2", "--width", "40", "--height", "30", "--quiet",
                                  "--images", mode, "--out", out.string()},
                                 dir_);
        ASSERT_EQ(r.code, 0) << r.err;
        const auto report = nlohmann::ordered_json::parse(testing_util::slurpFile(out / "report.json"));
        std::set<std::string> listed, written;
        for (const auto &v : report["views"])
            for (auto it = v["images"].begin(); it != v["images"].end(); ++it) {
                if (it.value().is_string()) listed.insert(it.value().get<std::string>());
                else
                    for (const auto &f : it.value()) listed.insert(f.get<std::string>());
            }
        for (const auto &e : fs::directory_iterator(out))
            if (e.path().extension() == ".png" || e.path().extension() == ".exr") written.insert(e.path().filename().string());
        EXPECT_EQ(listed, written) << mode;
        const std::string html = testing_util::slurpFile(out / "report.html");
        for (const std::string f : {"orbit0.ids.exr", "orbit0.painter_errors.png", "orbit0.depth.png"})
            EXPECT_EQ(html.find("\"" + f + "\"") != std::string::npos && !written.count(f), false) << mode << " " << f;
        if (mode == "all") EXPECT_EQ(written.size(), 20u);
        if (mode == "key")
            EXPECT_EQ(written, (std::set<std::string>{"orbit0.culling.png", "orbit0.depth.png", "orbit0.overdraw.png",
                                                      "orbit0.zfight.png", "orbit1.culling.png", "orbit1.depth.png",
                                                      "orbit1.overdraw.png", "orbit1.zfight.png"}));
        if (mode == "none") EXPECT_TRUE(written.empty());
    }
    EXPECT_EQ(runBinary({"analyze", "--images", "some", "--out", (dir_ / "x").string()}, dir_).code, 2);
}

}  // namespace
}  // namespace va
