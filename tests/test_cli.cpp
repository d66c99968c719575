// End to end: the program as a user runs it. Exit codes, messages, outputs, and that bad input
// never leaves a partial report or damages an existing one.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "reports/report.h"
#include "tests/temp_dir_test.h"

namespace fs = std::filesystem;

namespace {

struct RunResult {
    int code = -1;
    std::string out, err;
};

std::string slurp(const fs::path &p) {
    std::ifstream f(p, std::ios::binary);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
}

class CliTest : public va::testing_util::TempDirTest {
  protected:
    CliTest() : TempDirTest("cli") {}

    // Runs the program with `args` (already shell-quoted where needed), no stdin.
    RunResult run(const std::string &args) {
        const fs::path o = dir_ / "stdout.txt", e = dir_ / "stderr.txt";
        const std::string cmd = std::string(VISAUDIT_BINARY) + " " + args + " </dev/null >" + o.string() + " 2>" +
                                e.string();
        const int status = std::system(cmd.c_str());
        RunResult r;
        r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
        r.out = slurp(o);
        r.err = slurp(e);
        return r;
    }
};

// The report without its timings ("ms" and "*_ms" keys), which differ between runs.
nlohmann::json withoutTimings(nlohmann::json j) {
    std::function<void(nlohmann::json &)> rec = [&](nlohmann::json &x) {
        if (x.is_object()) {
            for (auto it = x.begin(); it != x.end();) {
                const std::string k = it.key();
                if (k == "ms" || (k.size() > 3 && k.compare(k.size() - 3, 3, "_ms") == 0))
                    it = x.erase(it);
                else
                    rec(*it++);
            }
        } else if (x.is_array()) {
            for (auto &e : x) rec(e);
        }
    };
    rec(j);
    return j;
}

// The index of the stage named `name` in a view's "stages" (docs/architecture.md's fixed order), or -1.
int stageIndex(const nlohmann::json &view, const std::string &name) {
    for (size_t i = 0; i < view["stages"].size(); ++i)
        if (view["stages"][i]["name"] == name) return int(i);
    return -1;
}

const std::string kExamples = VISAUDIT_EXAMPLES;
const std::string kData = VISAUDIT_TEST_DATA;

}  // namespace

TEST_F(CliTest, AnalyzeDemoWritesReportAndImages) {
    const fs::path out = dir_ / "report";
    const RunResult r = run("analyze --quiet --out " + out.string());
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(slurp(out / "report.json"));
    EXPECT_EQ(j["format"], "visaudit-report/1");
    EXPECT_EQ(j["tool"]["version"], VISAUDIT_VERSION);
    ASSERT_EQ(j["views"].size(), 2u);
    for (const char *v : {"spawn", "overview"})
        for (const char *ext : {".depth.exr", ".depth.png", ".overdraw.png", ".ids.exr"})
            EXPECT_TRUE(fs::exists(out / (std::string(v) + ext))) << v << ext;
    // The ids image agrees with the report: covered pixels = pixels with a non-zero id.
    va::ImageData img;
    std::string err;
    ASSERT_TRUE(va::readImage((out / "spawn.ids.exr").string(), &img, &err)) << err;
    ASSERT_EQ(img.width, 960);
    uint64_t covered = 0;
    for (uint32_t v : img.u32) covered += v != 0;
    EXPECT_EQ(covered, j["views"][0]["zbuffer"]["covered_pixels"].get<uint64_t>());
    // The output phase is timed (issue 8: no hidden overhead): eight images and an HTML page take
    // more than zero milliseconds.
    ASSERT_TRUE(j.contains("output"));
    EXPECT_GT(j["output"]["images_ms"].get<double>(), 0.0);
    EXPECT_GE(j["output"]["report_ms"].get<double>(), 0.0);
    EXPECT_GT(j["output"]["html_ms"].get<double>(), 0.0);
    // No staging folder is left behind.
    for (const auto &e : fs::directory_iterator(dir_))
        EXPECT_EQ(e.path().filename().string().find("report.tmp"), std::string::npos) << e.path();
}

// Issue 8: every count, image and report (timings aside) is byte-identical with 1, 2 and 8 threads
// (views and the rasterizer's tiles run in parallel). Every file of the output folder is compared:
// images byte for byte, report.json without its timings; report.html embeds timings, so it is
// compared with them masked.
static void expectSameOutputs(const fs::path &a, const fs::path &b) {
    size_t files = 0;
    for (const auto &e : fs::directory_iterator(a)) {
        const std::string name = e.path().filename().string();
        ASSERT_TRUE(fs::exists(b / name)) << name;
        ++files;
        if (name == "report.json") {
            EXPECT_EQ(withoutTimings(nlohmann::json::parse(slurp(e.path()))),
                      withoutTimings(nlohmann::json::parse(slurp(b / name))));
        } else if (name != "report.html") {
            EXPECT_TRUE(slurp(e.path()) == slurp(b / name)) << name << " differs between thread counts";
        }
    }
    size_t filesB = 0;
    for ([[maybe_unused]] const auto &e : fs::directory_iterator(b)) ++filesB;
    EXPECT_EQ(files, filesB);
    EXPECT_GT(files, 4u);
}

TEST_F(CliTest, AnalyzeIsDeterministicAcrossThreadCounts) {
    ASSERT_EQ(run("analyze --quiet --threads 1 --out " + (dir_ / "t1").string()).code, 0);
    for (const char *n : {"2", "8"}) {
        const fs::path o = dir_ / (std::string("t") + n);
        ASSERT_EQ(run(std::string("analyze --quiet --threads ") + n + " --out " + o.string()).code, 0);
        expectSameOutputs(dir_ / "t1", o);
    }
}

// The same on a real level at full HD, where one view's triangles spread over many tiles.
TEST_F(CliTest, AnalyzeRealLevelIsDeterministicAcrossThreadCounts) {
    const std::string dungeon = kData + "/castle/level/level-dungeon.gltf";
    if (!fs::exists(dungeon)) GTEST_SKIP() << "real data not fetched (run scripts/fetch-data.sh)";
    const std::string args = "analyze " + dungeon + " --views orbit:3 --quiet --width 1920 --height 1080 --out ";
    ASSERT_EQ(run(args + (dir_ / "t1").string() + " --threads 1").code, 0);
    for (const char *n : {"2", "8"}) {
        const fs::path o = dir_ / (std::string("t") + n);
        const RunResult r = run(args + o.string() + " --threads " + n);
        ASSERT_EQ(r.code, 0) << r.err;
        expectSameOutputs(dir_ / "t1", o);
    }
}

TEST_F(CliTest, AnalyzeExampleSceneObjAndViewsFile) {
    RunResult r = run("analyze " + kExamples + "/hall.scene.json --quiet --width 320 --height 180 --out " +
                (dir_ / "hall").string());
    EXPECT_EQ(r.code, 0) << r.err;
    r = run("analyze " + kExamples + "/hall.scene.json --views " + kExamples +
            "/hall.views.json --quiet --width 320 --height 180 --out " + (dir_ / "hall2").string());
    EXPECT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(slurp(dir_ / "hall2" / "report.json"));
    EXPECT_EQ(j["views"].size(), 3u);
    // A mesh file analysed directly, with generated views.
    r = run("analyze " + kExamples + "/meshes/hall.obj --views orbit:3 --quiet --width 320 --height 180 --out " +
            (dir_ / "obj").string());
    EXPECT_EQ(r.code, 0) << r.err;
    const auto k = nlohmann::json::parse(slurp(dir_ / "obj" / "report.json"));
    EXPECT_EQ(k["views"].size(), 3u);
    EXPECT_GT(k["views"][0]["zbuffer"]["covered_pixels"].get<uint64_t>(), 0u);
}

TEST_F(CliTest, AnalyzeRealLevels) {
    const std::string dungeon = kData + "/castle/level/level-dungeon.gltf";
    const std::string elephant = kData + "/cgal/elephant.off";
    if (!fs::exists(dungeon) || !fs::exists(elephant))
        GTEST_SKIP() << "real data not fetched (run scripts/fetch-data.sh)";
    RunResult r = run("analyze " + dungeon + " --views orbit:2 --quiet --width 640 --height 360 --out " +
                (dir_ / "d").string());
    ASSERT_EQ(r.code, 0) << r.err;
    auto j = nlohmann::json::parse(slurp(dir_ / "d" / "report.json"));
    EXPECT_EQ(j["scene"]["triangles"], 25038);
    EXPECT_GT(j["views"][0]["zbuffer"]["covered_pixels"].get<uint64_t>(), 1000u);
    r = run("analyze " + elephant + " --views orbit:2 --quiet --width 640 --height 360 --out " +
            (dir_ / "e").string());
    ASSERT_EQ(r.code, 0) << r.err;
    j = nlohmann::json::parse(slurp(dir_ / "e" / "report.json"));
    EXPECT_EQ(j["scene"]["triangles"], 5558);
    // A closed mesh: without backface culling every back face covers the silhouette again, so
    // the fragments grow by more than half.
    r = run("analyze " + elephant + " --views orbit:2 --quiet --width 640 --height 360 --no-backface --out " +
            (dir_ / "e2").string());
    ASSERT_EQ(r.code, 0) << r.err;
    const auto k = nlohmann::json::parse(slurp(dir_ / "e2" / "report.json"));
    const uint64_t culled = j["views"][0]["zbuffer"]["fragments"], all = k["views"][0]["zbuffer"]["fragments"];
    EXPECT_GT(double(all), 1.5 * double(culled));
    EXPECT_EQ(j["views"][0]["zbuffer"]["covered_pixels"], k["views"][0]["zbuffer"]["covered_pixels"]);
}

TEST_F(CliTest, BadInputExitsTwoWithAClearMessageAndNoReport) {
    const fs::path out = dir_ / "out";
    struct Case {
        std::string args, message;
    };
    const std::vector<Case> cases = {
        {"analyze /nonexistent/level.json", "/nonexistent/level.json"},
        {"analyze --views orbit:0", "--views orbit:0: expected orbit:N with N a whole number from 1 to 100000"},
        {"analyze --width 100000", "exceeds the limit of 16384 pixels per side"},
        {"analyze --depth-format f16", "unknown depth format 'f16'; known formats: linear_f32"},
        {"analyze --views /nonexistent/views.json", "/nonexistent/views.json"},
        {"analyse", "unknown command 'analyse', did you mean 'analyze'?"},
    };
    for (const Case &c : cases) {
        const RunResult r = run(c.args + " --out " + out.string());
        EXPECT_EQ(r.code, 2) << c.args << "\n" << r.err;
        EXPECT_NE(r.err.find(c.message), std::string::npos) << c.args << "\nstderr: " << r.err;
        EXPECT_FALSE(fs::exists(out)) << c.args;
    }
    // Malformed JSON: the file, line and column.
    const fs::path bad = dir_ / "bad.scene.json";
    std::ofstream(bad) << "{\n  \"format\": \"visaudit-scene/1\",\n  \"objects\": [ }\n";
    const RunResult r = run("analyze " + bad.string() + " --out " + out.string());
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find(bad.string() + ":3:"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
}

TEST_F(CliTest, FailedRunKeepsTheExistingReportAndOtherFoldersAreNeverReplaced) {
    const fs::path out = dir_ / "out";
    ASSERT_EQ(run("analyze --quiet --out " + out.string()).code, 0);
    const std::string before = slurp(out / "report.json");
    // A run that fails on bad input leaves the previous report exactly as it was.
    EXPECT_EQ(run("analyze --width 100000 --out " + out.string()).code, 2);
    EXPECT_EQ(slurp(out / "report.json"), before);
    // A folder that is not a visaudit report is refused, untouched.
    const fs::path mine = dir_ / "mine";
    fs::create_directories(mine);
    std::ofstream(mine / "notes.txt") << "precious";
    const RunResult r = run("analyze --quiet --out " + mine.string());
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find(mine.string()), std::string::npos) << r.err;
    EXPECT_EQ(slurp(mine / "notes.txt"), "precious");
    EXPECT_FALSE(fs::exists(mine / "report.json"));
}

TEST_F(CliTest, InfoSummarizesTheExampleScene) {
    const RunResult r = run("info " + kExamples + "/hall.scene.json");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("materials"), std::string::npos);
    EXPECT_NE(r.out.find("spawn"), std::string::npos);
    EXPECT_NE(r.out.find("double-sided"), std::string::npos);
}

TEST_F(CliTest, DepthAuditPrintsTheTableAndWritesJsonAndPlot) {
    const fs::path out = dir_ / "audit";
    const RunResult r = run("depth-audit --near 0.1 --far 10000 --out " + out.string());
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("unorm16             16        65536"), std::string::npos) << r.out;
    const auto j = nlohmann::json::parse(slurp(out / "depth-audit.json"));
    EXPECT_EQ(j["format"], "visaudit-depth-audit/1");
    va::ImageData img;
    std::string err;
    ASSERT_TRUE(va::readImage((out / "depth-audit.png").string(), &img, &err)) << err;
    EXPECT_EQ(img.width, 1200);
    // Bad ranges and names: exit 2 with the value named.
    RunResult b = run("depth-audit --near 0 --far 10");
    EXPECT_EQ(b.code, 2);
    EXPECT_NE(b.err.find("near plane 0"), std::string::npos) << b.err;
    b = run("depth-audit --near 10 --far 1");
    EXPECT_EQ(b.code, 2);
    b = run("depth-audit --near 1 --far 10 --formats f32,f16");
    EXPECT_EQ(b.code, 2);
    EXPECT_NE(b.err.find("unknown depth format 'f16'"), std::string::npos) << b.err;
}

TEST_F(CliTest, FourShardsThroughGnuParallelMergeIntoTheSingleRunsReport) {
    if (std::system("command -v parallel >/dev/null 2>&1") != 0)
        GTEST_SKIP() << "GNU parallel is not installed (scripts/install-deps.sh installs it)";
    const std::string common = " analyze " + kExamples + "/hall.scene.json --views orbit:9 --width 160 --height 90 --quiet";
    ASSERT_EQ(run(common + " --out " + (dir_ / "single").string()).code, 0);
    // The README's recipe: one job per shard, any order, two at a time.
    const std::string cmd = "parallel -j2 --halt now,fail=1 " + std::string(VISAUDIT_BINARY) + common +
                            " --shard {}/4 --out " + (dir_ / "shard{}").string() + " ::: 1 2 3 4";
    ASSERT_EQ(std::system((cmd + " </dev/null >/dev/null 2>&1").c_str()), 0) << cmd;
    const RunResult m = run("merge " + (dir_ / "shard1").string() + " " + (dir_ / "shard3").string() + " " +
                            (dir_ / "shard2").string() + " " + (dir_ / "shard4").string() + " --out " +
                            (dir_ / "merged").string());
    ASSERT_EQ(m.code, 0) << m.err;
    const auto single = withoutTimings(nlohmann::json::parse(slurp(dir_ / "single" / "report.json")));
    const auto merged = withoutTimings(nlohmann::json::parse(slurp(dir_ / "merged" / "report.json")));
    EXPECT_EQ(single, merged);
    // The merged report's output timings are the shards' summed.
    double imagesMs = 0;
    for (const char *k : {"shard1", "shard2", "shard3", "shard4"})
        imagesMs += nlohmann::json::parse(slurp(dir_ / k / "report.json"))["output"]["images_ms"].get<double>();
    EXPECT_DOUBLE_EQ(nlohmann::json::parse(slurp(dir_ / "merged" / "report.json"))["output"]["images_ms"].get<double>(),
                     imagesMs);
    // Every image is byte-identical too.
    size_t images = 0;
    for (const auto &e : fs::directory_iterator(dir_ / "single")) {
        // report.json was compared above; report.html shows timings, which differ between runs.
        if (e.path().filename() == "report.json" || e.path().filename() == "report.html") continue;
        ++images;
        EXPECT_EQ(slurp(e.path()), slurp(dir_ / "merged" / e.path().filename())) << e.path();
    }
    // Exactly the images the report lists: per view depth.exr, depth.png, overdraw.png, ids.exr,
    // zfight.png, culling.png, raycast.ids.exr, raycast_diff.png, secondary.png, one shadow image
    // per light (the hall has two lights), painter_errors.png, overdraw_order.png and abuffer.png
    // (the hall has glass).
    size_t listed = 0;
    for (const auto &v : single["views"])
        for (const auto &[k, x] : v["images"].items()) listed += x.is_array() ? x.size() : 1;
    EXPECT_EQ(listed, 9u * 14u);
    EXPECT_EQ(images, listed);
    // Missing and overlapping shards are refused.
    RunResult bad = run("merge " + (dir_ / "shard1").string() + " " + (dir_ / "shard2").string() + " --out " +
                        (dir_ / "bad").string());
    EXPECT_EQ(bad.code, 2);
    EXPECT_NE(bad.err.find("shard 3/4 is missing"), std::string::npos) << bad.err;
    bad = run("merge " + (dir_ / "shard1").string() + " " + (dir_ / "shard1").string() + " --out " +
              (dir_ / "bad").string());
    EXPECT_EQ(bad.code, 2);
    EXPECT_NE(bad.err.find("shards overlap"), std::string::npos) << bad.err;
    EXPECT_FALSE(fs::exists(dir_ / "bad"));
}

TEST_F(CliTest, CheckPassesALooseBudgetAndFailsATightOneWithJUnit) {
    const fs::path loose = dir_ / "loose.json", tight = dir_ / "tight.json";
    std::ofstream(loose) << R"({"format": "visaudit-budget/1", "limits": {"overdraw": 3, "zbuffer_triangles": 1000000}})";
    std::ofstream(tight) << R"({"format": "visaudit-budget/1", "limits": {"overdraw": 3},
                               "views": {"spawn": {"zbuffer_triangles": 100}}})";
    RunResult r = run("check --budget " + loose.string() + " --quiet --out " + (dir_ / "a").string() + " --junit " +
                      (dir_ / "a.xml").string());
    EXPECT_EQ(r.code, 0) << r.err << r.out;
    // 2 views x (2 limits + false_culls, checked with limit 0 by default where the audit ran)
    EXPECT_NE(r.out.find("6 passed, 0 failed"), std::string::npos) << r.out;
    r = run("check --budget " + tight.string() + " --quiet --out " + (dir_ / "b").string() + " --junit " +
            (dir_ / "b.xml").string());
    EXPECT_EQ(r.code, 1) << r.err << r.out;
    const auto report = nlohmann::json::parse(slurp(dir_ / "b" / "report.json"));
    const int zi = stageIndex(report["views"][0], "zbuffer");
    ASSERT_GE(zi, 0);
    const uint64_t drawn = report["views"][0]["stages"][zi]["triangles_out"];
    EXPECT_NE(r.out.find("FAIL: zbuffer_triangles in view 'spawn' is " + std::to_string(drawn) + ", allowed 100"),
              std::string::npos)
        << r.out;
    const std::string xml = slurp(dir_ / "b.xml");
    EXPECT_NE(xml.find("<testsuites name=\"visaudit check\" tests=\"5\" failures=\"1\">"), std::string::npos) << xml;
    EXPECT_NE(xml.find("<failure message=\"zbuffer_triangles in view &apos;spawn&apos; is"), std::string::npos) << xml;
    // Well-formed: every opened testcase with a failure is closed; the document closes.
    EXPECT_EQ(xml.substr(xml.size() - 14), "</testsuites>\n");
}

TEST_F(CliTest, CheckRegressionsAgainstABaseline) {
    const fs::path budget = dir_ / "budget.json";
    std::ofstream(budget) << R"({"format": "visaudit-budget/1", "regressions": {"zbuffer_triangles": 0.1}})";
    ASSERT_EQ(run("analyze --quiet --out " + (dir_ / "base").string()).code, 0);
    // Without backface culling the z-buffer draws far more triangles: a regression.
    const RunResult r = run("check --budget " + budget.string() + " --baseline " +
                            (dir_ / "base" / "report.json").string() + " --no-backface --quiet --out " +
                            (dir_ / "new").string());
    EXPECT_EQ(r.code, 1) << r.err;
    EXPECT_NE(r.out.find("zbuffer_triangles in view 'spawn' rose "), std::string::npos) << r.out;
    EXPECT_NE(r.out.find(", allowed 10%"), std::string::npos) << r.out;
    // The same settings: no regression.
    EXPECT_EQ(run("check --budget " + budget.string() + " --baseline " + (dir_ / "base" / "report.json").string() +
                  " --quiet --out " + (dir_ / "same").string())
                  .code,
              0);
}

TEST_F(CliTest, CheckRefusesBadBudgetsAndBaselinesBeforeAnalysing) {
    struct Case {
        std::string budget, message;
    };
    const std::vector<Case> cases = {
        {R"({"format": "visaudit-budget/1", "limits": {"overdrew": 2}})",
         ":1:44: limits: unknown metric 'overdrew', did you mean 'overdraw'?"},
        {R"({"format": "visaudit-budget/1", "views": {"spwan": {}}})",
         "views: no view named 'spwan', did you mean 'spawn'? (views: spawn, overview)"},
        {R"({"format": "visaudit-budget/1", "limits": {"min_depth_format": "f16"}})",
         "limits.min_depth_format: unknown depth format 'f16'"},
        {R"({"format": "visaudit-budget/1", "limits": {"overdraw": "low"}})",
         "limits.overdraw: expected a number >= 0, got a string"},
        {R"({"format": "visaudit-budget/2"})", "\"format\" must be \"visaudit-budget/1\""},
    };
    for (const Case &c : cases) {
        const fs::path b = dir_ / "b.json";
        std::ofstream(b) << c.budget;
        const RunResult r = run("check --budget " + b.string() + " --quiet --out " + (dir_ / "out").string());
        EXPECT_EQ(r.code, 2) << c.budget;
        EXPECT_NE(r.err.find(c.message), std::string::npos) << c.budget << "\n" << r.err;
        EXPECT_FALSE(fs::exists(dir_ / "out")) << "nothing is analysed or written for a bad budget";
    }
    // A baseline of another scene.
    const fs::path b = dir_ / "ok.json";
    std::ofstream(b) << R"({"format": "visaudit-budget/1", "regressions": {"overdraw": 0.1}})";
    ASSERT_EQ(run("analyze " + kExamples + "/hall.scene.json --quiet --width 64 --height 36 --out " +
                  (dir_ / "hall").string())
                  .code,
              0);
    const RunResult r = run("check --budget " + b.string() + " --baseline " + (dir_ / "hall" / "report.json").string() +
                            " --quiet --out " + (dir_ / "demo").string());
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find("the baseline is a report of another scene"), std::string::npos) << r.err;
}

TEST_F(CliTest, GradeScoresADeliberatelyAlteredReport) {
    ASSERT_EQ(run("analyze --quiet --out " + (dir_ / "ref").string()).code, 0);
    const fs::path refPath = dir_ / "ref" / "report.json";
    auto sub = nlohmann::json::parse(slurp(refPath));
    // The same report grades 100%.
    RunResult r = run("grade --reference " + refPath.string() + " --submission " + refPath.string());
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("score 100.0%"), std::string::npos) << r.out;
    // Three alterations: a clip count off by one, a ratio off by 1%, a stage left out.
    const int ci = stageIndex(sub["views"][0], "clip");
    ASSERT_GE(ci, 0);
    const uint64_t rejected = sub["views"][0]["stages"][ci]["trivially_rejected"];
    sub["views"][0]["stages"][ci]["trivially_rejected"] = rejected + 1;
    const double overdraw = sub["views"][1]["zbuffer"]["overdraw"];
    sub["views"][1]["zbuffer"]["overdraw"] = overdraw * 1.01;
    const int bi = stageIndex(sub["views"][1], "backface");
    ASSERT_GE(bi, 0);
    const size_t backfaceKeys = 6;  // triangles_in/culled/out, tested, double_sided_exempt, edge_on
    sub["views"][1]["stages"].erase(size_t(bi));
    const fs::path subPath = dir_ / "sub.json";
    std::ofstream(subPath) << sub.dump();
    r = run("grade --reference " + refPath.string() + " --submission " + subPath.string() + " --out " +
            (dir_ / "grade.json").string());
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.out.find("FAIL spawn clip.trivially_rejected: submitted " + std::to_string(rejected + 1) +
                         ", reference " + std::to_string(rejected)),
              std::string::npos)
        << r.out;
    EXPECT_NE(r.out.find("FAIL overview zbuffer_summary.overdraw"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("FAIL overview backface.triangles_tested: submitted missing"), std::string::npos) << r.out;
    const auto g = nlohmann::json::parse(slurp(dir_ / "grade.json"));
    EXPECT_EQ(g["failed"], 2 + backfaceKeys);
    // Tolerances forgive the first two, not the missing stage.
    const fs::path tol = dir_ / "tol.json";
    std::ofstream(tol) << R"({"format": "visaudit-tolerance/1",
                              "metrics": {"clip.*": {"abs": 1}, "zbuffer_summary.overdraw": {"rel": 0.02}}})";
    r = run("grade --reference " + refPath.string() + " --submission " + subPath.string() + " --tolerance " +
            tol.string() + " --out " + (dir_ / "grade2.json").string());
    EXPECT_EQ(r.code, 1);
    EXPECT_EQ(nlohmann::json::parse(slurp(dir_ / "grade2.json"))["failed"], backfaceKeys);
    // A bad tolerance file: exit 2 with the place.
    std::ofstream(tol) << R"({"format": "visaudit-tolerance/1", "metrics": {"clip.*": {"absolute": 1}}})";
    r = run("grade --reference " + refPath.string() + " --submission " + subPath.string() + " --tolerance " +
            tol.string());
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find("unknown key 'absolute' (known: abs, rel)"), std::string::npos) << r.err;
}

TEST_F(CliTest, JsonSummaryOnStdoutAndPlainProgressLinesWithoutATerminal) {
    const RunResult r = run("analyze --json --out " + (dir_ / "out").string());
    ASSERT_EQ(r.code, 0) << r.err;
    const auto summary = nlohmann::json::parse(r.out);  // stdout is exactly one JSON document
    const auto report = nlohmann::json::parse(slurp(dir_ / "out" / "report.json"));
    EXPECT_EQ(summary["totals"]["fragments"], report["totals"]["fragments"]);
    EXPECT_EQ(summary["views"][1]["stages"][2]["triangles_out"], report["views"][1]["stages"][2]["triangles_out"]);
    // No terminal: one plain progress line per view on stderr, no carriage returns.
    EXPECT_EQ(r.err.find('\r'), std::string::npos);
    EXPECT_NE(r.err.find("[1/2] "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("[2/2] "), std::string::npos) << r.err;
}

TEST_F(CliTest, DepthAuditSceneRecommendsAFormatPerView) {
    // A floor and a decal 1 mm above it, seen from 100 m (near 0.1, far 1000): unorm16 cannot
    // separate them there, so the recommendation needs more bits; the hall fights nowhere.
    std::ofstream(dir_ / "floor.obj") << "v -60 0 -60\nv 60 0 -60\nv 60 0 60\nv -60 0 60\nf 1 4 3 2\n";
    std::ofstream(dir_ / "decal.obj") << "v -20 0.001 -20\nv 20 0.001 -20\nv 20 0.001 20\nv -20 0.001 20\nf 1 4 3 2\n";
    std::ofstream(dir_ / "decal.scene.json") << R"({"format": "visaudit-scene/1",
      "objects": [{"name": "floor", "mesh": "floor.obj"}, {"name": "decal", "mesh": "decal.obj"}],
      "views": [{"name": "far", "eye": [0, 60, 80], "target": [0, 0, 0], "near": 0.1, "far": 1000,
                 "width": 160, "height": 90, "depth_format": "unorm16"}]})";
    const RunResult r = run("depth-audit --scene " + (dir_ / "decal.scene.json").string());
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("view 'far' 160x90, near 0.1, far 1000, its format unorm16"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("hotspot 1: "), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("'floor' vs 'decal'"), std::string::npos) << r.out;
    EXPECT_EQ(r.out.find("unorm16            16 bits          0 fighting"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("f32_reversed       32 bits          0 fighting [0]"), std::string::npos) << r.out;
    // Neither a range nor a scene: exit 2.
    const RunResult bad = run("depth-audit");
    EXPECT_EQ(bad.code, 2);
    EXPECT_NE(bad.err.find("depth-audit needs --near N --far F"), std::string::npos) << bad.err;
}
