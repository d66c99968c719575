// report.html (reports/html.h): escaping, links that resolve, highlight boxes where the pixels are,
// sections that are absent or malformed, ordering of views, determinism. The page in a real
// browser is tests/browser/report.test.mjs (CTest: browser_report).
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "reports/findings.h"
#include "reports/html.h"

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

namespace {

std::string slurp(const fs::path &p) {
    std::ifstream f(p, std::ios::binary);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
}

size_t count(const std::string &s, const std::string &what) {
    size_t n = 0;
    for (size_t p = s.find(what); p != std::string::npos; p = s.find(what, p + 1)) ++n;
    return n;
}

// Values of an attribute anywhere in the page, in order.
std::vector<std::string> attributes(const std::string &html, const std::string &name) {
    std::vector<std::string> out;
    const std::regex re(" " + name + "=\"([^\"]*)\"");
    for (auto it = std::sregex_iterator(html.begin(), html.end(), re); it != std::sregex_iterator(); ++it)
        out.push_back((*it)[1].str());
    return out;
}

std::string percentDecode(const std::string &s) {
    std::string o;
    for (size_t i = 0; i < s.size(); ++i) {
        if (s[i] == '%' && i + 2 < s.size()) {
            o += char(std::stoi(s.substr(i + 1, 2), nullptr, 16));
            i += 2;
        } else {
            o += s[i];
        }
    }
    return o;
}

// A temporary folder, removed at the end.
struct TempDir {
    fs::path path;
    TempDir() {
        std::string t = (fs::temp_directory_path() / "visaudit-html-XXXXXX").string();
        path = ::mkdtemp(t.data()) ? fs::path(t) : fs::path();
    }
    ~TempDir() {
        std::error_code ec;
        if (!path.empty()) fs::remove_all(path, ec);
    }
};

// The smallest PNG header reportHtml reads: signature and IHDR with width and height.
void writePngHeader(const fs::path &p, uint32_t w, uint32_t h) {
    std::string b = "\x89PNG\r\n\x1a\n";
    b += std::string("\0\0\0\x0d", 4) + "IHDR";
    for (uint32_t v : {w, h})
        for (int s = 24; s >= 0; s -= 8) b += char((v >> s) & 0xFF);
    b += std::string("\x08\x02\0\0\0", 5);
    std::ofstream(p, std::ios::binary) << b;
}

// A view with the fields the page reads, small numbers that can be checked by hand.
Json makeView(const std::string &name, double falseCullPixels, double genuine, double zfight, double overdraw) {
    Json v;
    v["name"] = name;
    v["index"] = 0;
    v["origin"] = "test";
    v["width"] = 200;
    v["height"] = 100;
    v["depth_format"] = "f32";
    v["projection"] = "perspective";
    v["camera"] = {{"eye", {0, 0, 5}}, {"target", {0, 0, 0}}, {"up", {0, 1, 0}}, {"fov_y", 60}, {"near", 0.1}, {"far", 100}};
    v["stages"] = Json::array(
        {{{"name", "cells"}, {"ran", false}, {"reason", "scene has no cells"}, {"triangles_in", 0}, {"triangles_culled", 0},
          {"triangles_out", 0}, {"ms", 0}},
         {{"name", "frustum"}, {"ran", true}, {"triangles_in", 200}, {"triangles_culled", 100}, {"triangles_out", 100},
          {"ms", 0.5}, {"objects_culled", 3}},
         {{"name", "zbuffer"}, {"ran", true}, {"triangles_in", 100}, {"triangles_culled", 10}, {"triangles_out", 90},
          {"ms", 2.0}, {"triangles_empty", 10}}});
    v["zbuffer"] = {{"covered_pixels", 1000}, {"fragments", 1500}, {"depth_passes", 1200}, {"overdraw", overdraw},
                    {"depth_complexity", 1.5}};
    v["audit"] = {{"ran", true},
                  {"false_culls", {{"triangles", falseCullPixels > 0 ? 2 : 0}, {"pixels", falseCullPixels}, {"by_stage", Json::object()}}},
                  {"wasted_draws", {{"drawn_triangles", 100}, {"triangles", 25}, {"share", 0.25}}}};
    v["raycast"] = {{"ran", true}, {"cross_check", {{"pixels", 20000}, {"agree", 20000 - genuine}, {"genuine", genuine}}}};
    v["depth"] = {{"ran", true}, {"formats", {{"f32", {{"bits", 32}, {"fighting_pixels", zfight}, {"hotspots", zfight > 0 ? 1 : 0}}}}}};
    v["images"] = Json::object();
    v["total_ms"] = 3.0;
    return v;
}

Json makeReport(std::vector<Json> views) {
    Json r;
    r["format"] = "visaudit-report/1";
    r["tool"] = {{"name", "visaudit"}, {"version", "0.1.0"}};
    r["scene"] = {{"path", "test.scene.json"}, {"triangles", 200}, {"objects", 4}, {"source_objects", 2}};
    r["views"] = Json::array();
    for (Json &v : views) r["views"].push_back(v);
    return r;
}

// Position of the summary table's link to view `pos` (the summary comes before the sections).
size_t summaryPos(const std::string &html, size_t pos) {
    const size_t table = html.find("id=\"summary-table\"");
    return html.find("href=\"#v" + std::to_string(pos) + "\"", table);
}

}  // namespace

// A view or scene named like markup is shown as text: it opens no tag and closes no attribute.
TEST(Html, EscapesEveryReportString) {
    Json v = makeView("<script>alert(1)</script>", 0, 0, 0, 1.0);
    v["stages"][0]["reason"] = "\"><img src=x onerror=alert(2)>";
    v["origin"] = "a & b 'c'";
    Json r = makeReport({v});
    r["scene"]["path"] = "</title><script>alert(3)</script>";
    const std::string html = va::reportHtml(r, "");
    EXPECT_EQ(count(html, "<script"), 1u) << "only the page's own script";
    EXPECT_EQ(html.find("alert(1)</script>"), std::string::npos);
    EXPECT_NE(html.find("&lt;script&gt;alert(1)&lt;/script&gt;"), std::string::npos);
    EXPECT_EQ(html.find("<img src=x"), std::string::npos);
    EXPECT_NE(html.find("&quot;&gt;&lt;img src=x onerror=alert(2)&gt;"), std::string::npos);
    EXPECT_NE(html.find("<title>visaudit: &lt;/title&gt;&lt;script&gt;alert(3)"), std::string::npos);
    EXPECT_NE(html.find("a &amp; b &#39;c&#39;"), std::string::npos);
}

// Invalid UTF-8 and control characters become U+FFFD; valid multi-byte characters stay.
TEST(Html, ReplacesInvalidUtf8AndControlCharacters) {
    Json r = makeReport({makeView(std::string("caf\xC3\xA9 \xFF\xFE x\x01y"), 0, 0, 0, 1.0)});
    const std::string html = va::reportHtml(r, "");
    EXPECT_NE(html.find("caf\xC3\xA9 \xEF\xBF\xBD\xEF\xBF\xBD x\xEF\xBF\xBDy"), std::string::npos);
    EXPECT_EQ(html.find('\x01'), std::string::npos);
    EXPECT_EQ(html.find('\xFF'), std::string::npos);
}

// Worst first: false-cull pixels, then genuine disagreements, then z-fighting, then overdraw.
TEST(Html, SummaryListsWorstViewsFirst) {
    Json r = makeReport({makeView("clean", 0, 0, 0, 1.1), makeView("zfight", 0, 0, 50, 1.0),
                         makeView("falsecull", 7, 0, 0, 1.0), makeView("genuine", 0, 3, 0, 1.0),
                         makeView("overdraw", 0, 0, 0, 2.0)});
    const std::string html = va::reportHtml(r, "");
    // Expected order: falsecull (2), genuine (3), zfight (1), overdraw (4), clean (0).
    const std::vector<size_t> order = {2, 3, 1, 4, 0};
    for (size_t k = 0; k + 1 < order.size(); ++k)
        EXPECT_LT(summaryPos(html, order[k]), summaryPos(html, order[k + 1])) << "k=" << k;
    // The verdict names the worst findings.
    EXPECT_NE(html.find("<b>7 falsely culled pixels</b> in 1 view"), std::string::npos);
    EXPECT_NE(html.find("<b>3 genuine ray-cast disagreements</b>"), std::string::npos);
    EXPECT_NE(html.find("overdraw up to 2 (overdraw)"), std::string::npos);
}

// The funnel: one row per stage, bars on one scale (200 triangles = 520 px), a skipped stage grey
// with its reason as a tooltip.
TEST(Html, FunnelChartHasOneRowPerStage) {
    const std::string html = va::reportHtml(makeReport({makeView("a", 0, 0, 0, 1.0)}), "");
    const size_t svg = html.find("<svg class=\"chart funnel\" id=\"v0-funnel\"");
    ASSERT_NE(svg, std::string::npos);
    const std::string funnel = html.substr(svg, html.find("</svg>", svg) - svg);
    EXPECT_EQ(count(funnel, "<g class=\"stage\""), 3u);
    EXPECT_NE(funnel.find("<title>cells skipped: scene has no cells</title><rect class=\"skip\""), std::string::npos);
    EXPECT_NE(funnel.find("<rect class=\"in\" x=\"92\" y=\"58\" width=\"520.00\""), std::string::npos);   // frustum in 200
    EXPECT_NE(funnel.find("<rect class=\"out\" x=\"92\" y=\"63\" width=\"260.00\""), std::string::npos);  // frustum out 100
    EXPECT_NE(funnel.find("<rect class=\"out\" x=\"92\" y=\"93\" width=\"234.00\""), std::string::npos);  // zbuffer out 90
    EXPECT_NE(funnel.find("200 → 100  (−100, 50.0%)"), std::string::npos);
}

// A report with nothing but names, or of the wrong shape, still gives a whole page.
TEST(Html, MissingAndMalformedSectionsDoNotBreakThePage) {
    Json bare = {{"views", Json::array({{{"name", "only"}}})}};
    std::string html = va::reportHtml(bare, "");
    EXPECT_NE(html.find("<h2>only</h2>"), std::string::npos);
    EXPECT_NE(html.find("No stages in this view."), std::string::npos);
    EXPECT_GE(count(html, "not analysed"), 5u);
    EXPECT_NE(html.find("</html>\n"), std::string::npos);

    Json wrong = makeReport({makeView("w", 0, 0, 0, 1.0)});
    wrong["views"][0]["stages"] = "not an array";
    wrong["views"][0]["depth"] = 5;
    wrong["views"][0]["audit"] = Json::array({1, 2});
    wrong["views"][0]["camera"]["far"] = "far";
    wrong["views"][0]["zbuffer"]["overdraw"] = nullptr;
    html = va::reportHtml(wrong, "");
    EXPECT_NE(html.find("<h2>w</h2>"), std::string::npos);
    EXPECT_NE(html.find("</html>\n"), std::string::npos);

    for (const Json &j : {Json(), Json::array(), Json("text"), Json({{"views", 3}})})
        EXPECT_NE(va::reportHtml(j, "").find("</html>\n"), std::string::npos) << j.dump();
}

// The six questions say "not analysed" only where the section they need is absent, and use the
// sections being added (ordering, detail, occlusion, lights) when present.
TEST(Html, SixQuestionsAnswerFromTheSectionsPresent) {
    Json v = makeView("q", 0, 0, 0, 1.0);
    std::string html = va::reportHtml(makeReport({v}), "");
    EXPECT_NE(html.find("frustum culling removed 3 objects (100 triangles) wholly outside the view"), std::string::npos);
    EXPECT_NE(html.find("10 triangles of 100 reaching the z-buffer (10.0%) cover no pixel center"), std::string::npos);
    EXPECT_NE(html.find("What stands between a surface and a light?</span> <span class=\"muted\">not analysed"),
              std::string::npos);
    // The page escapes every answer whole (the findings are plain text in report.json).
    EXPECT_NE(html.find("painter&#39;s and BSP ordering not analysed"), std::string::npos);

    v["stages"].push_back({{"name", "occlusion"}, {"ran", true}, {"triangles_in", 90}, {"triangles_culled", 40},
                           {"triangles_out", 50}, {"ms", 1}});
    v["ordering"] = {{"table", {{{"method", "painter"}, {"build_ms", 1.0}, {"draw_ms", 2.0}, {"wrong_pixels", 40}},
                                {{"method", "bsp"}, {"build_ms", 5.0}, {"draw_ms", 1.0}, {"wrong_pixels", 0}}}}};
    v["detail"] = {{"objects_too_small", 2}, {"objects_over_detailed", 1}, {"triangles_savable", 77}};
    v["raycast"]["lights"] = {{{"name", "sun"}, {"shadowed_pixels", 300}, {"lit_pixels", 700}}};
    html = va::reportHtml(makeReport({v}), "");
    EXPECT_NE(html.find("occlusion culling removed 40 triangles behind occluders"), std::string::npos);
    EXPECT_NE(html.find("painter gets 40 pixels wrong; bsp gets 0 pixels wrong"), std::string::npos);
    EXPECT_NE(html.find("2 drawn objects project to a few pixels at most"), std::string::npos);
    EXPECT_NE(html.find("would save 77 triangles"), std::string::npos);
    EXPECT_NE(html.find("light sun: 300 pixels are shadowed"), std::string::npos);
    EXPECT_NE(html.find("(30.0% shadowed)"), std::string::npos);
    // Accuracy against time: one point per method at (build + draw, wrong pixels).
    const size_t sc = html.find("id=\"v0-scatter\"");
    ASSERT_NE(sc, std::string::npos);
    const std::string scatter = html.substr(sc, html.find("</svg>", sc) - sc);
    EXPECT_EQ(count(scatter, "<circle"), 2u);
    EXPECT_NE(scatter.find("<title>painter: 3 ms, 40 px</title>"), std::string::npos);
    EXPECT_NE(scatter.find("<title>bsp: 6 ms, 0 px</title>"), std::string::npos);

    // The planner's reason when no shadow rays ran.
    Json r = makeReport({makeView("p", 0, 0, 0, 1.0)});
    r["effects"] = {{"decisions", {{{"name", "shadows"}, {"ran", false}, {"reason", "scene has no lights"}}}}};
    const std::string planned = va::reportHtml(r, "");
    EXPECT_NE(planned.find("not analysed</span> (scene has no lights)"), std::string::npos);
    EXPECT_NE(planned.find("<b>shadows</b>: does not run (scene has no lights)"), std::string::npos);
}

// An unknown section of a view is shown by its key as a table, not dropped.
TEST(Html, UnknownSectionsAreShownGenerically) {
    Json v = makeView("g", 0, 0, 0, 1.0);
    v["grid_stats"] = {{"cells_total", 64}, {"per_cell", {{{"cell", 1}, {"objects", 9}}}}};
    const std::string html = va::reportHtml(makeReport({v}), "");
    EXPECT_NE(html.find("<h3 id=\"v0-grid_stats\">grid stats</h3>"), std::string::npos);
    EXPECT_NE(html.find("<th>cells total</th><td class=\"n\">64</td>"), std::string::npos);
    EXPECT_NE(html.find("<th>cell</th><th>objects</th>"), std::string::npos);
}

// Images: referenced only when the file exists; found by the view's base name when the report
// does not list them yet (painter's errors); hotspot boxes placed from the bbox and PNG size.
TEST(Html, ImagesExistAndHotspotBoxesCoverTheirPixels) {
    TempDir dir;
    ASSERT_FALSE(dir.path.empty());
    Json v = makeView("img", 0, 0, 10, 1.0);
    v["images"] = {{"depth_png", "img.depth.png"}, {"zfight_png", "img.zfight.png"}, {"overdraw_png", "missing.png"}};
    v["depth"]["hotspots"] = {{{"id", 1}, {"area", 10}, {"bbox", {50, 20, 99, 39}}, {"objects", {"floor", "decal"}}}};
    writePngHeader(dir.path / "img.depth.png", 200, 100);
    writePngHeader(dir.path / "img.zfight.png", 200, 125);  // a legend strip of 25 rows below
    writePngHeader(dir.path / "img.painter_errors.png", 200, 110);
    const std::string html = va::reportHtml(makeReport({v}), dir.path.string());

    // Every file the page references exists, and every in-page link has its target.
    std::set<std::string> ids;
    for (const std::string &id : attributes(html, "id")) EXPECT_TRUE(ids.insert(id).second) << "duplicate id " << id;
    for (const std::string &src : attributes(html, "src")) EXPECT_TRUE(fs::exists(dir.path / percentDecode(src))) << src;
    for (const std::string &href : attributes(html, "href")) {
        if (href.rfind("#", 0) == 0) {
            EXPECT_TRUE(ids.count(href.substr(1))) << href;
        } else {
            EXPECT_TRUE(fs::exists(dir.path / percentDecode(href))) << href;
        }
    }
    EXPECT_EQ(html.find("missing.png"), std::string::npos);
    EXPECT_NE(html.find("<img src=\"img.painter_errors.png\""), std::string::npos);
    EXPECT_NE(html.find("width=\"200\" height=\"125\""), std::string::npos);

    // The hotspot row links to a box inside the z-fight figure: x 50..99 of 200 -> 25%, 25%;
    // y 20..39 of 125 rows -> 16%, 16%.
    EXPECT_NE(html.find("<a class=\"px\" href=\"#v0-hs1\">show [50, 20, 99, 39]</a>"), std::string::npos);
    const size_t fig = html.find("<figure id=\"v0-img-zfight\">"), box = html.find("id=\"v0-hs1\"");
    ASSERT_NE(fig, std::string::npos);
    EXPECT_GT(box, fig);
    EXPECT_LT(box, html.find("</figure>", fig));
    EXPECT_NE(html.find("style=\"left:25.00%;top:16.00%;width:25.00%;height:16.00%\"", box), std::string::npos);
}

// The built-in demo end to end: the binary's report folder gives a page whose references all
// exist, with a hotspot box per listed hotspot, the same bytes twice, written atomically.
TEST(Html, DemoReportPageIsCompleteAndDeterministic) {
    TempDir dir;
    ASSERT_FALSE(dir.path.empty());
    const fs::path out = dir.path / "demo";
    const std::string cmd = std::string(VISAUDIT_BINARY) + " analyze --quiet --out " + out.string() + " >/dev/null 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    const Json report = Json::parse(slurp(out / "report.json"));
    const std::string html = va::reportHtml(report, out.string());
    EXPECT_EQ(html, va::reportHtml(Json::parse(slurp(out / "report.json")), out.string()));

    size_t listed = 0, boxes = 0;
    for (const Json &v : report["views"]) {
        for (auto it = v["images"].begin(); it != v["images"].end(); ++it) {
            const std::string key = it.key();
            if (key.size() > 4 && key.compare(key.size() - 4, 4, "_png") == 0 && it.value().is_string()) {
                ++listed;
                EXPECT_NE(html.find("<img src=\"" + it.value().get<std::string>() + "\""), std::string::npos) << key;
            }
        }
        // One box per hotspot (z-fight image) and per genuine ray-cast example (difference image).
        if (v["depth"].contains("hotspots")) boxes += v["depth"]["hotspots"].size();
        if (v.contains("raycast") && v["raycast"].contains("cross_check") && v["images"].contains("raycast_diff_png"))
            boxes += v["raycast"]["cross_check"]["genuine_examples"].size();
    }
    EXPECT_GE(listed, 4u * report["views"].size());  // depth, overdraw, zfight, culling
    EXPECT_GT(boxes, 0u) << "the demo's decal z-fights the floor";
    EXPECT_EQ(count(html, "<span class=\"hl\" id=\"v"), boxes);
    for (const std::string &src : attributes(html, "src")) EXPECT_TRUE(fs::exists(out / percentDecode(src))) << src;
    std::set<std::string> ids;
    for (const std::string &id : attributes(html, "id")) ids.insert(id);
    for (const std::string &href : attributes(html, "href")) {
        if (href.rfind("#", 0) == 0) {
            EXPECT_TRUE(ids.count(href.substr(1))) << href;
        }
    }
    EXPECT_EQ(count(html, "<section class=\"view\""), report["views"].size());
    EXPECT_EQ(count(html, "<svg class=\"chart funnel\""), report["views"].size());

    std::string err;
    ASSERT_TRUE(va::writeReportHtml(report, out.string(), &err)) << err;
    EXPECT_EQ(slurp(out / "report.html"), html);
    for (const auto &e : fs::directory_iterator(out)) EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos);
}

TEST(Html, WriteFailureNamesThePath) {
    std::string err;
    EXPECT_FALSE(va::writeReportHtml(makeReport({}), "/nonexistent-visaudit-dir", &err));
    EXPECT_NE(err.find("/nonexistent-visaudit-dir/report.html"), std::string::npos) << err;
}

// ---- Findings (reports/findings.h): computed once, stored in the report, presented by the page ----

// Worst first by false-cull pixels, then genuine disagreements, then z-fighting, then overdraw (ties
// keep the view order); the verdict sums each over views and counts the views that have it.
TEST(Findings, WorstFirstAndVerdictAreExact) {
    Json r = makeReport({makeView("calm", 0, 0, 0, 1.1), makeView("culls", 7, 0, 0, 1.0), makeView("fights", 0, 0, 5, 1.9),
                         makeView("rays", 0, 3, 0, 1.0), makeView("also-culls", 7, 1, 0, 1.0)});
    va::addFindings(&r);
    EXPECT_EQ(r["findings"]["worst_first"].dump(), "[4,1,3,2,0]");
    EXPECT_EQ(r["findings"]["verdict"].dump(),
              "{\"false_cull_pixels\":14,\"false_cull_views\":2,\"genuine_disagreements\":4,\"genuine_views\":2,"
              "\"zfight_pixels\":5,\"zfight_views\":1,\"zfight_coplanar_pixels\":0,"
              "\"worst_overdraw\":{\"view\":2,\"overdraw\":1.9}}");
    EXPECT_EQ(r["views"][2]["findings"]["score"].dump(),
              "{\"false_cull_pixels\":0.0,\"genuine_disagreements\":0.0,\"zfight_pixels\":5.0,\"zfight_hotspots\":1,"
              "\"overdraw\":1.9,\"depth_complexity\":1.5,\"wasted_share\":0.25,\"triangles_drawn\":90}");
    // The page shows the stored order and verdict: views in the summary worst first.
    const std::string html = va::reportHtml(r, "");
    EXPECT_LT(summaryPos(html, 4), summaryPos(html, 1));
    EXPECT_LT(summaryPos(html, 1), summaryPos(html, 3));
    EXPECT_NE(html.find("<b>14 falsely culled pixels</b> in 2 views"), std::string::npos);
    EXPECT_NE(html.find("overdraw up to 1.9 (fights)"), std::string::npos);
}

// The answers are plain text in the report; a part that was not analysed says why, and the page
// presents the stored answers rather than computing its own.
TEST(Findings, AnswersArePlainTextThePagePresents) {
    Json v = makeView("q", 0, 0, 0, 1.0);
    v["detail"] = {{"ran", false}, {"reason", "turned off by --no-detail"}};
    Json r = makeReport({v});
    va::addFindings(&r);
    const Json &answers = r["views"][0]["findings"]["answers"];
    ASSERT_EQ(answers.size(), 6u);
    EXPECT_EQ(answers[0].dump(),
              "{\"question\":\"What is off-screen?\",\"answer\":[\"frustum culling removed 3 objects (100 triangles) "
              "wholly outside the view\"]}");
    EXPECT_EQ(answers[2]["answer"][0].dump(), "{\"not_analysed\":\"turned off by --no-detail\"}");
    EXPECT_EQ(answers[5].dump(),
              "{\"question\":\"What stands between a surface and a light?\",\"not_analysed\":\"no shadow rays in this report\"}");
    // Change the stored answer: the page shows the report's words.
    r["views"][0]["findings"]["answers"][0]["answer"][0] = "a <stored> answer";
    const std::string html = va::reportHtml(r, "");
    EXPECT_NE(html.find("What is off-screen?</span> a &lt;stored&gt; answer.</li>"), std::string::npos);
    EXPECT_NE(html.find("What needs less detail?</span> <span class=\"muted\">not analysed</span> (turned off by "
                        "--no-detail); 10 triangles of 100"),
              std::string::npos);
}

// Views of one near/far share the resolution plot's grid and curves: drawn once, in the first view
// that uses the set, and referenced (<use>) by the others, each with its own format drawn bold.
TEST(Html, DepthCurvesAreDrawnOncePerSet) {
    Json a = makeView("a", 0, 0, 0, 1.0), b = makeView("b", 0, 0, 0, 1.0), c = makeView("c", 0, 0, 0, 1.0);
    a["depth_curve"] = 0, b["depth_curve"] = 0, c["depth_curve"] = nullptr;
    b["depth_format"] = "unorm24";
    Json r = makeReport({a, b, c});
    r["depth_curves"] = Json::array({{{"near", 0.1},
                                      {"far", 100.0},
                                      {"depths", {0.2, 2.0, 20.0}},
                                      {"formats",
                                       {{{"name", "f32"}, {"resolution", {1e-7, 1e-5, nullptr}}},
                                        {{"name", "unorm24"}, {"resolution", {1e-6, 1e-4, 1e-2}}}}}}});
    const std::string html = va::reportHtml(r, "");
    auto count = [&](const std::string &s) {
        size_t n = 0;
        for (size_t p = html.find(s); p != std::string::npos; p = html.find(s, p + 1)) ++n;
        return n;
    };
    EXPECT_EQ(count("<g id=\"depth-curves-0\">"), 1u);
    EXPECT_EQ(count("<use href=\"#depth-curves-0\"/>"), 1u);
    EXPECT_EQ(count("id=\"v2-resolution\""), 0u);  // no curve set: no plot
    // Each view's own format is drawn bold over the shared curves, and marked in its legend.
    const size_t va = html.find("id=\"v0-resolution\""), vb = html.find("id=\"v1-resolution\"");
    ASSERT_NE(va, std::string::npos);
    ASSERT_NE(vb, std::string::npos);
    EXPECT_NE(html.find("<title>f32 (this view's format)</title>", va), std::string::npos);
    EXPECT_LT(html.find("<title>f32 (this view's format)</title>", va), vb);
    EXPECT_NE(html.find("<title>unorm24 (this view's format)</title>", vb), std::string::npos);
    // f32's curve breaks where it has no value: one segment, M then L.
    EXPECT_EQ(count("stroke-width=\"1.5\" d=\"M"), 2u);
}
