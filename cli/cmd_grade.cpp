// visaudit grade: a student's per-stage counts against a reference report, or submissions against
// an assignment kit's reference answers (--kit: reports/kit_grade.h, docs/grading.md).
#include <cstdio>
#include <filesystem>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include "cli/command_table.h"
#include "cli/commands.h"
#include "cli/shared.h"
#include "reports/grade.h"
#include "reports/kit_grade.h"
#include "reports/report.h"

namespace va {
namespace {

namespace fs = std::filesystem;

struct GradeOptions {
    std::string reference, submission, tolerance;
    std::vector<std::string> submissions;  // --submissions DIR...: a class
    std::string kit;                       // --kit: grade against an assignment kit
    std::string gradeOut;  // --out: the result as JSON (report mode) or a folder (kit mode)
    int threads = 0;
    bool quiet = false;
    uint64_t maxJsonDepth = kDefaultMaxJsonDepth;
};

int cmdGradeReport(const GradeOptions &o) {
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

// One student's folder of outputs: grade.json, the diff images, grade.html.
bool writeStudent(kit::KitGrade &g, const kit::Kit &kit, const std::string &dir, std::string *err) {
    return kit::writeGradeImages(g, dir, err) &&
           writeFileAtomic((fs::path(dir) / "grade.json").string(), kit::kitGradeJson(g).dump(2) + "\n", err) &&
           writeFileAtomic((fs::path(dir) / "grade.html").string(), kit::gradeHtml(g, kit), err);
}

int cmdGradeKit(const GradeOptions &o) {
    std::string err;
    if (o.reference.empty()) {
        fail("--kit needs --reference ANSWERS: the answers folder `visaudit assignment` wrote next to the kit");
        return kExitBadInput;
    }
    if (o.submission.empty() == o.submissions.empty()) {
        fail("--kit needs either --submission DIR (one student's folder) or --submissions DIR... (a class), not " +
             std::string(o.submission.empty() ? "neither" : "both"));
        return kExitBadInput;
    }
    if (!o.submissions.empty() && o.gradeOut.empty()) {
        fail("--submissions needs --out FOLDER for grades.csv, the class summary and each student's grade.html");
        return kExitBadInput;
    }
    kit::Kit kit;
    kit::AnswerSet answers;
    ToleranceRules tol;
    if (!kit::readKit(o.kit, &kit, &err, o.maxJsonDepth) || !kit::readAnswers(o.reference, kit, &answers, &err, o.maxJsonDepth) ||
        (!o.tolerance.empty() && !loadTolerances(o.tolerance, &tol, &err, o.maxJsonDepth))) {
        fail(err);
        return kExitBadInput;
    }
    OutputDir out;
    if (!o.gradeOut.empty() && !out.open(o.gradeOut, &err)) {
        fail(err);
        return kExitBadInput;
    }
    std::optional<tbb::global_control> threads;
    if (o.threads > 0) threads.emplace(tbb::global_control::max_allowed_parallelism, size_t(o.threads));

    if (!o.submission.empty()) {
        kit::KitGrade g = kit::gradeSubmission(kit, answers, tol, o.submission, o.maxJsonDepth);
        if (!o.gradeOut.empty()) {
            if (!writeStudent(g, kit, out.staging(), &err)) {
                fail(err);
                return kExitBadInput;
            }
            if (const int rc = commitOutput(out, o.gradeOut); rc != kExitOk) return rc;
        }
        if (!o.quiet) std::printf("%s", kit::kitGradeTable(g).c_str());
        return g.failed ? kExitBudgetFailed : kExitOk;
    }

    // A class: every submission graded in parallel into its own folder under students/, results in
    // the order given (deterministic for any thread count); one submission's trouble is its grade.
    std::vector<std::string> names;
    std::set<std::string> taken;
    for (const std::string &dir : o.submissions) {
        std::string base = fs::path(dir).filename().string();
        if (base.empty()) base = fs::path(dir).parent_path().filename().string();
        std::string name = sanitizeFileName(base);
        for (int k = 2; taken.count(name); ++k) name = sanitizeFileName(base) + "-" + std::to_string(k);
        taken.insert(name);
        names.push_back(name);
    }
    std::vector<kit::KitGrade> grades(o.submissions.size());
    std::vector<std::string> errors(o.submissions.size());
    tbb::parallel_for(size_t(0), o.submissions.size(), [&](size_t i) {
        if (interrupted()) return;
        grades[i] = kit::gradeSubmission(kit, answers, tol, o.submissions[i], o.maxJsonDepth);
        const fs::path dir = fs::path(out.staging()) / "students" / names[i];
        std::error_code ec;
        fs::create_directories(dir, ec);
        if (ec) errors[i] = "cannot create folder '" + dir.string() + "': " + ec.message();
        else writeStudent(grades[i], kit, dir.string(), &errors[i]);
        std::vector<kit::PixelGrade>().swap(grades[i].images);  // their pictures are written
    });
    if (interrupted()) return interruptedExit(o.gradeOut);
    for (const std::string &e : errors)
        if (!e.empty()) {
            fail(e);
            return kExitBadInput;
        }
    const nlohmann::ordered_json summary = kit::classSummary(grades, kit);
    std::vector<std::string> pages;
    for (const std::string &n : names) pages.push_back("students/" + n + "/grade.html");
    if (!writeFileAtomic((fs::path(out.staging()) / "grades.csv").string(), kit::gradesCsv(grades, kit), &err) ||
        !writeFileAtomic((fs::path(out.staging()) / "class.json").string(), summary.dump(2) + "\n", &err) ||
        !writeFileAtomic((fs::path(out.staging()) / "index.html").string(), kit::classHtml(grades, summary, pages), &err)) {
        fail(err);
        return kExitBadInput;
    }
    if (const int rc = commitOutput(out, o.gradeOut); rc != kExitOk) return rc;
    if (!o.quiet) std::printf("%s", kit::classTable(summary).c_str());
    return kExitOk;
}

int cmdGrade(const GradeOptions &o) {
    installInterruptHandlers();
    if (!o.kit.empty()) return cmdGradeKit(o);
    if (!o.submissions.empty()) {
        fail("--submissions grades against an assignment kit: give --kit KIT and --reference ANSWERS too");
        return kExitBadInput;
    }
    if (o.reference.empty() || o.submission.empty()) {
        fail("grade needs --reference R.json --submission S.json (reports), or --kit KIT --reference ANSWERS "
             "--submission DIR (an assignment kit); see visaudit grade --help");
        return kExitBadInput;
    }
    return cmdGradeReport(o);
}

void addGradeOptions(CLI::App *c, GradeOptions &o) {
    c->add_option("--reference", o.reference,
                  "The reference report.json; with --kit, the answers folder `visaudit assignment` wrote");
    c->add_option("--submission", o.submission,
                  "The student's report.json (the same keys); with --kit, the student's folder (submission.json)");
    c->add_option("--submissions", o.submissions, "With --kit: every student's folder (a class), e.g. subs/*")
        ->expected(1, -1);
    c->add_option("--kit", o.kit, "Grade against this assignment kit (visaudit assignment --out)");
    c->add_option("--tolerance", o.tolerance, "Tolerances per metric (visaudit-tolerance/1)");
    c->add_option("--out", o.gradeOut,
                  "Write the result as JSON here; with --kit, a folder: grade.html, grade.json and diff images "
                  "(a class: grades.csv, class.json, index.html, students/NAME/)");
    c->add_option("--threads", o.threads, "With --submissions: worker threads (0 = all cores); grades do not depend on it")
        ->check(CLI::Range(0, 4096));
    c->add_flag("--quiet", o.quiet, "With --kit: print nothing");
    addJsonDepthOption(c, o.maxJsonDepth);
}

}  // namespace

CommandRun setupGrade(CLI::App *c) { return bindCommand<GradeOptions>(c, addGradeOptions, cmdGrade); }

}  // namespace va
