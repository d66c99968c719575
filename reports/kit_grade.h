// Grading a student's submission against an assignment kit's reference answers (docs/grading.md):
// `visaudit grade --kit KIT --reference ANSWERS --submission DIR` (one student) or
// `--submissions DIR...` (a class). Every stage is graded on the kit's own input for it, so a
// mistake in one stage never fails another; per view and stage: the counts, the output lists
// (backface's kept ids, the clipped polygons, the painter's order) with the tolerances the
// tolerance file states, and the per-pixel images pixel by pixel, each disagreeing pixel classified
// as the ray-cast cross-check classifies its own (edge, tie, genuine). Known patterns of mistakes
// give a hint. Reads files and result structs only; never runs a stage (the answers hold what the
// stages gave, analysis/kit.h).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "analysis/audits/audit.h"
#include "analysis/kit.h"
#include "reports/grade.h"

namespace va::kit {

// The reference answers, read back (answers.json, each view's STAGE.json and id images).
struct AnswerSet {
    std::string dir;
    // Per kit view (the kit's order), per kit stage (the kit's order).
    std::vector<std::vector<StageAnswer>> views;
};
// Reads the answers folder and checks that it belongs to `kit` (answers.json lists the
// fingerprints of the kit's input files). False + message naming the file and the fix.
bool readAnswers(const std::string &dir, const Kit &kit, AnswerSet *out, std::string *err,
                 uint64_t maxJsonDepth = kDefaultMaxJsonDepth);

// One per-pixel image of a submission compared with the reference.
struct PixelGrade {
    std::string view, viewDir, stage, image;  // image: "ids" or "depth"
    int width = 0, height = 0;
    std::vector<uint8_t> cls;     // per pixel: Disagreement (none = agrees)
    std::vector<uint8_t> gray;    // per pixel: the reference's depth as depth.png's gray (0 background)
    uint64_t pixels = 0, agree = 0, edge = 0, tie = 0, genuine = 0;
    uint64_t unknownIds = 0;      // of genuine: pixels showing an id the stage's input does not hold
    uint64_t fartherPixels = 0;   // of genuine with both a reference and a submitted surface: the
    uint64_t comparedDepths = 0;  //   submitted one is farther (fartherPixels) of comparedDepths
    std::string diffFile;         // the diff image's file name (set when written)
    int diffWidth = 0;            // its width: the view's, enlarged by a whole factor when small
    double share() const { return pixels ? double(agree) / double(pixels) : 0; }
};

// A hint: the likely mistake behind a recognisable pattern of failures.
struct GradeHint {
    std::string id;    // fill_rule, tie_rule, depth_test_greater, near_not_clipped, winding_reversed,
                       // painter_key_nearest, painter_key_farthest, painter_front_to_back
    std::string view, stage;
    std::string title;  // the mistake in a few words ("Fill rule: the top-left rule inverted")
    std::string text;   // what the pattern is, with this view's numbers, and what to check
};
// A hint's title (the painter's hints name the kit's key).
std::string hintTitle(const std::string &id, PainterKey kitKey);

struct StageScore {
    std::string stage;
    size_t passed = 0, total = 0;
    double score = 0;  // passed / total over every view (0 when nothing to grade)
};

struct KitGrade {
    std::string student;  // the submission folder's name
    std::string dir;      // the submission folder
    std::string error;    // why the submission as a whole could not be read ("" when it could)
    std::vector<GradeItem> items;  // views in kit order, stages in kit order, keys in answer order
    std::vector<GradeHint> hints;
    std::vector<StageScore> stages;  // the kit's stages, in order
    std::vector<PixelGrade> images;
    size_t passed = 0, failed = 0;
    double score = 0;  // the mean of the stage scores, in [0, 1]
};

// Grades one submission folder (its submission.json and the images it names). Never fails: an
// unreadable or malformed submission is graded, each item failing with the reason.
KitGrade gradeSubmission(const Kit &kit, const AnswerSet &answers, const ToleranceRules &tol, const std::string &dir,
                         uint64_t maxJsonDepth = kDefaultMaxJsonDepth);

// The built-in tolerance of a metric when no rule of the tolerance file covers it (docs/grading.md):
// integers exact; real numbers rel 1e-9; "clip.polygons" abs and rel 1e-9 per coordinate;
// "zbuffer.depth_values" / "painter.depth_values" rel 1e-6 per pixel; image shares ("zbuffer.ids",
// "zbuffer.depth", "painter.ids") abs 0 (every pixel must agree).
Tolerance kitTolerance(const ToleranceRules &t, const std::string &metric, bool integer);

// ---- Outputs ------------------------------------------------------------------------------------

// grade.json (visaudit-grade/2): score, stages, items (with notes), hints, images.
nlohmann::ordered_json kitGradeJson(const KitGrade &g);
// The console table: per view and stage passed/total, every failure with both values, the hints,
// the score.
std::string kitGradeTable(const KitGrade &g);
// Writes each image's diff picture (VIEWDIR.STAGE.IMAGE.diff.png: the reference's depth dimmed,
// disagreeing pixels colored by class, a legend with the counts; a view under 256 pixels wide
// enlarged by a whole factor) into dir; sets diffFile and diffWidth.
bool writeGradeImages(KitGrade &g, const std::string &dir, std::string *err);
// grade.html: self-contained (inline CSS, the diff PNGs next to it), as report.html is.
std::string gradeHtml(const KitGrade &g, const Kit &kit);

// A class: grades.csv (one row per student: score, per-stage scores, failures, hints), the class
// summary (which checks most students fail, which hints), and index.html linking each student's page.
// `pages[i]`: the relative path of student i's grade.html.
std::string gradesCsv(const std::vector<KitGrade> &grades, const Kit &kit);
nlohmann::ordered_json classSummary(const std::vector<KitGrade> &grades, const Kit &kit);
std::string classTable(const nlohmann::ordered_json &summary);
std::string classHtml(const std::vector<KitGrade> &grades, const nlohmann::ordered_json &summary,
                      const std::vector<std::string> &pages);

}  // namespace va::kit
