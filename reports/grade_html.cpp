// grade.html and the class's index.html (kit_grade.h): self-contained pages, as report.html is --
// the project's CSS inline (reports/assets/report.css), the diff PNGs next to the page, no script,
// no network. Every string from a submission or a kit is escaped (htmlEscape).
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>

#include "reports/html.h"
#include "reports/html_assets.h"
#include "reports/kit_grade.h"

namespace va::kit {

namespace {

using OJson = nlohmann::ordered_json;

std::string esc(const std::string &s) { return htmlEscape(s); }
// "kit" for "path/to/kit" and "path/to/kit/".
std::string folderName(const std::string &dir) {
    std::filesystem::path p(dir);
    if (p.filename().empty()) p = p.parent_path();
    return p.filename().string();
}
std::string pct(double share) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.1f%%", 100 * share);
    return buf;
}

// The page's own rules on top of report.css.
constexpr const char *kGradeCss = R"CSS(
td.pass { color: var(--good); font-weight: 600; }
td.fail { color: var(--bad); font-weight: 600; }
tr.failed td { background: color-mix(in srgb, var(--bad) 7%, transparent); }
.score { font-size: 2em; font-weight: 700; margin: 4px 0; }
.hint { border-left: 4px solid var(--warn); background: var(--card); padding: 8px 12px; margin: 8px 0; }
.hint b { color: var(--warn); }
.hint::after { content: ""; display: block; clear: both; }
.hint img.thumb { float: right; image-rendering: pixelated; margin: 0 0 4px 12px; border: 1px solid var(--border); }
figure.diff { display: inline-block; margin: 6px 12px 6px 0; vertical-align: top; }
figure.diff { max-width: 520px; }
figure.diff img { image-rendering: pixelated; max-width: 100%; height: auto; border: 1px solid var(--border); }
table.stages td.bar { width: 240px; }
.barbg { background: var(--skip); height: 10px; border-radius: 5px; overflow: hidden; }
.barfg { background: var(--good); height: 10px; }
)CSS";

std::string head(const std::string &title) {
    return "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><meta name=\"viewport\" "
           "content=\"width=device-width, initial-scale=1\"><title>" +
           esc(title) + "</title><style>" + std::string(html_assets::kCss) + kGradeCss + "</style></head><body>\n";
}

std::string bar(double share) {
    char w[32];
    std::snprintf(w, sizeof w, "%.1f", 100 * share);
    return "<div class=\"barbg\"><div class=\"barfg\" style=\"width:" + std::string(w) + "%\"></div></div>";
}

}  // namespace

std::string gradeHtml(const KitGrade &g, const Kit &kit) {
    std::string o = head("grade: " + g.student);
    o += "<header><h1>Grade: " + esc(g.student) + "</h1><div class=\"meta\">visaudit " VISAUDIT_VERSION
         " · kit folder " + esc(folderName(kit.dir)) + " · " + std::to_string(kit.views.size()) + " view" + (kit.views.size() == 1 ? "" : "s") +
         " · stages";
    for (Stage st : kit.stages) o += std::string(" ") + stageName(st);
    o += "</div><div class=\"score " + std::string(g.failed ? "bad" : "good") + "\" id=\"score\">" + pct(g.score) + "</div>";
    o += "<div class=\"meta\">" + std::to_string(g.passed) + " of " + std::to_string(g.passed + g.failed) +
         " checks passed; the score is the mean of the stage scores.</div></header>\n";
    if (!g.error.empty())
        o += "<p class=\"hint\" id=\"error\"><b>Your submission could not be read:</b> " + esc(g.error) +
             " Every check below is failed for that reason.</p>\n";

    // Stage scores.
    o += "<section class=\"block\"><h2>Stages</h2><table class=\"stages\"><tr><th>stage</th><th class=\"n\">score</th>"
         "<th class=\"n\">passed</th><th></th></tr>";
    for (const StageScore &s : g.stages)
        o += "<tr><td>" + esc(s.stage) + "</td><td class=\"n\">" + pct(s.score) + "</td><td class=\"n\">" +
             std::to_string(s.passed) + " / " + std::to_string(s.total) + "</td><td class=\"bar\">" + bar(s.score) +
             "</td></tr>";
    o += "</table></section>\n";

    // Hints first: what to fix. One entry per mistake, with where it shows and, for an image's
    // pattern, the diff picture with the most disagreeing pixels among them.
    if (!g.hints.empty()) {
        o += "<section class=\"block\" id=\"hints\"><h2>What to look at</h2>";
        std::vector<std::string> ids;
        for (const GradeHint &h : g.hints)
            if (std::find(ids.begin(), ids.end(), h.id) == ids.end()) ids.push_back(h.id);
        for (const std::string &id : ids) {
            std::string where;
            const GradeHint *first = nullptr;  // the hint shown: the one whose picture differs most
            const PixelGrade *pic = nullptr;
            for (const GradeHint &h : g.hints) {
                if (h.id != id) continue;
                if (!first) first = &h;
                where += (where.empty() ? "" : ", ") + h.view + " " + h.stage;
                for (const PixelGrade &p : g.images)
                    if (p.view == h.view && p.stage == h.stage && !p.diffFile.empty() &&
                        (!pic || p.pixels - p.agree > pic->pixels - pic->agree)) {
                        pic = &p;
                        first = &h;
                    }
            }
            o += "<div class=\"hint\">";
            if (pic && (id == "fill_rule" || id == "tie_rule" || id == "depth_test_greater"))
                o += "<img class=\"thumb\" src=\"" + esc(pic->diffFile) + "\" alt=\"" + esc(pic->view + " " + pic->stage) +
                     " compared with the reference\" width=\"" + std::to_string(pic->diffWidth) + "\">";
            o += "<b>" + esc(first->title) + "</b> <span class=\"muted\">(" + esc(where) + ")</span><br>" +
                 esc(first->text) + "</div>";
        }
        o += "</section>\n";
    }

    // Per view and stage: the checks, the diff images.
    for (size_t vi = 0; vi < kit.views.size(); ++vi) {
        const KitView &v = kit.views[vi];
        o += "<section class=\"view\" id=\"v" + std::to_string(vi) + "\"><h2>View " + esc(v.name) + "</h2><div class=\"meta\">" +
             std::to_string(v.cam.width) + " × " + std::to_string(v.cam.height) + ", " +
             (v.cam.orthographic ? "orthographic" : "perspective") + ", depth format " +
             esc(depthFormatName(v.spec.depthFormat)) + "</div>";
        for (Stage st : kit.stages) {
            const std::string sn = stageName(st);
            size_t passed = 0, total = 0;
            for (const GradeItem &it : g.items)
                if (it.view == v.name && it.stage == sn) ++total, passed += it.pass;
            o += "<h3>" + esc(sn) + " <span class=\"muted\">" + std::to_string(passed) + " of " + std::to_string(total) +
                 " passed</span></h3>";
            for (const GradeHint &h : g.hints)
                if (h.view == v.name && h.stage == sn) o += "<p class=\"hint\"><b>" + esc(h.title) + ":</b> " + esc(h.text) + "</p>";
            o += "<div class=\"scroll\"><table><tr><th>check</th><th>result</th><th>yours</th><th>reference</th>"
                 "<th>details</th></tr>";
            for (const GradeItem &it : g.items) {
                if (it.view != v.name || it.stage != sn) continue;
                o += std::string("<tr") + (it.pass ? "" : " class=\"failed\"") + "><td><code>" + esc(it.key) +
                     "</code></td><td class=\"" + (it.pass ? "pass\">pass" : "fail\">fail") + "</td><td>" +
                     esc(it.submitted) + "</td><td>" + esc(it.reference) + "</td><td class=\"note\">" + esc(it.note) +
                     "</td></tr>";
            }
            o += "</table></div>";
            for (const PixelGrade &p : g.images) {
                if (p.view != v.name || p.stage != sn || p.diffFile.empty()) continue;
                o += "<figure class=\"diff\"><img src=\"" + esc(p.diffFile) + "\" alt=\"" + esc(sn + " " + p.image) +
                     " compared with the reference\" width=\"" + std::to_string(p.diffWidth) + "\"><figcaption>" +
                     esc(sn + " " + p.image) + ": " + pct(p.share()) + " of the pixels agree. Dimmed gray: agrees (the "
                     "reference's depth); blue: edge (the pixel's centre is on a triangle's edge: the fill rule decides "
                     "it); yellow: tie (equal stored depth: the tie rule decides it); red: genuine (another surface, or "
                     "none).</figcaption></figure>";
            }
        }
        o += "</section>\n";
    }
    o += "<footer class=\"meta\">Made by visaudit grade. Every check compares your value with the reference "
         "implementation's on the same input; the tolerances are the instructor's (docs/grading.md).</footer>\n";
    o += "</body></html>\n";
    return o;
}

std::string classHtml(const std::vector<KitGrade> &grades, const OJson &summary, const std::vector<std::string> &pages) {
    std::string o = head("class grades");
    o += "<header><h1>Class grades</h1><div class=\"meta\">" + std::to_string(grades.size()) + " submissions · mean " +
         pct(summary["mean_score"].get<double>()) + " · " + std::to_string(summary["full_marks"].get<size_t>()) +
         " with full marks · " + std::to_string(summary["unreadable"].get<size_t>()) + " unreadable</div></header>\n";
    o += "<section class=\"block\"><h2>Checks most students fail</h2><table><tr><th class=\"n\">failed</th><th>check</th></tr>";
    size_t shown = 0;
    for (const OJson &c : summary["checks_failed"]) {
        if (++shown > 25) break;
        o += "<tr><td class=\"n\">" + std::to_string(c["failed"].get<size_t>()) + " of " + std::to_string(c["of"].get<size_t>()) +
             "</td><td><code>" + esc(c["check"].get<std::string>()) + "</code></td></tr>";
    }
    o += "</table>";
    if (!summary["hints"].empty()) {
        o += "<h3>Hints given</h3><table><tr><th>hint</th><th class=\"n\">students</th></tr>";
        for (const OJson &h : summary["hints"])
            o += "<tr><td><code>" + esc(h["hint"].get<std::string>()) + "</code></td><td class=\"n\">" +
                 std::to_string(h["students"].get<size_t>()) + "</td></tr>";
        o += "</table>";
    }
    o += "</section>\n<section class=\"block\"><h2>Students</h2><table><tr><th>student</th><th class=\"n\">score</th>";
    if (!grades.empty())
        for (const StageScore &s : grades.front().stages) o += "<th class=\"n\">" + esc(s.stage) + "</th>";
    o += "<th>failed</th></tr>";
    for (size_t i = 0; i < grades.size(); ++i) {
        const KitGrade &g = grades[i];
        o += "<tr><td><a href=\"" + esc(pages[i]) + "\">" + esc(g.student) + "</a></td><td class=\"n\">" + pct(g.score) + "</td>";
        for (const StageScore &s : g.stages) o += "<td class=\"n\">" + pct(s.score) + "</td>";
        o += "<td>" + (g.error.empty() ? std::to_string(g.failed) : "unreadable: " + esc(g.error)) + "</td></tr>";
    }
    o += "</table></section></body></html>\n";
    return o;
}

}  // namespace va::kit
