// visaudit assignment: an assignment kit for students and, apart, its reference answers
// (analysis/kit.h; docs/grading.md).
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>

#include <tbb/global_control.h>

#include "analysis/kit.h"
#include "cli/command_table.h"
#include "cli/commands.h"
#include "cli/shared.h"
#include "reports/report.h"

namespace va {
namespace {

namespace fs = std::filesystem;

struct AssignmentOptions {
    SceneOptions scene;
    std::string stages = "all";
    std::string out, answers;
    int width = 0, height = 0;
    std::string depthFormat;
    std::string painterKey = "centroid";
    std::string images = "ids,depth";
    int threads = 0;
    bool quiet = false;
};

// The files of one folder, written into its staging folder (subfolders made as needed).
bool writeFiles(const std::string &root, const std::vector<std::pair<std::string, std::string>> &files, std::string *err) {
    for (const auto &[rel, text] : files) {
        const fs::path p = fs::path(root) / rel;
        std::error_code ec;
        fs::create_directories(p.parent_path(), ec);
        if (ec) {
            *err = "cannot create folder '" + p.parent_path().string() + "': " + ec.message();
            return false;
        }
        if (!writeFileAtomic(p.string(), text, err)) return false;
    }
    return true;
}

// Whether `inner` is `outer` or lies inside it (both made absolute and normal).
bool within(const std::string &inner, const std::string &outer) {
    const fs::path a = fs::absolute(inner).lexically_normal(), b = fs::absolute(outer).lexically_normal();
    auto ai = a.begin(), bi = b.begin();
    for (; bi != b.end() && !bi->empty(); ++ai, ++bi)
        if (ai == a.end() || *ai != *bi) return false;
    return true;
}

int cmdAssignment(const AssignmentOptions &o) {
    installInterruptHandlers();
    std::string err;
    kit::KitSettings ks;
    if (!kit::parseStageList(o.stages, &ks.stages, &err)) {
        fail("--stages " + o.stages + ": " + err);
        return kExitBadInput;
    }
    if (o.painterKey == "centroid") ks.painterKey = PainterKey::centroid;
    else if (o.painterKey == "nearest" || o.painterKey == "nearest_vertex") ks.painterKey = PainterKey::nearestVertex;
    else if (o.painterKey == "farthest" || o.painterKey == "farthest_vertex") ks.painterKey = PainterKey::farthestVertex;
    else {
        fail("--painter-key " + o.painterKey + ": expected centroid, nearest or farthest");
        return kExitBadInput;
    }
    if (o.images == "ids,depth" || o.images == "depth,ids") ks.images = {"ids", "depth"};
    else if (o.images == "ids" || o.images == "depth") ks.images = {o.images};
    else {
        fail("--images " + o.images + ": expected ids, depth or ids,depth (what the z-buffer stage hands in)");
        return kExitBadInput;
    }
    std::string outName = o.out;  // "kit/" names the folder "kit": its answers are "kit-answers"
    while (outName.size() > 1 && outName.back() == '/') outName.pop_back();
    const std::string answers = o.answers.empty() ? outName + "-answers" : o.answers;
    if (within(answers, o.out) || within(o.out, answers)) {
        fail("--answers " + answers + " and --out " + o.out + " overlap; the answers go to a folder of their own that "
             "the students never get (e.g. --answers " + outName + "-answers)");
        return kExitBadInput;
    }
    PipelineSettings s;
    s.width = o.width;
    s.height = o.height;
    s.threads = o.threads;
    if (!o.depthFormat.empty()) {
        DepthFormatSpec f;
        if (!parseDepthFormat(o.depthFormat, &f, &err)) {
            fail("--depth-format " + o.depthFormat + ": " + err);
            return kExitBadInput;
        }
        s.depthFormat = f;
    }
    // Refuse an output folder that is not ours before the work (OutputDir::open checks it).
    OutputDir kitOut, answersOut;
    if (!kitOut.open(o.out, &err) || !answersOut.open(answers, &err)) {
        fail(err);
        return kExitBadInput;
    }
    Scene scene;
    std::vector<ViewSpec> views;
    if (!loadInputs(o.scene, &scene, &views)) return kExitBadInput;
    std::optional<tbb::global_control> threads;
    if (o.threads > 0) threads.emplace(tbb::global_control::max_allowed_parallelism, size_t(o.threads));
    kit::KitFiles files;
    const std::string label = o.scene.scene.empty() ? "the built-in demo" : o.scene.scene;
    if (!kit::buildKit(scene, views, imageBaseNames(views), s, ks, label, &files, &err)) {
        fail(err);
        return kExitBadInput;
    }
    if (interrupted()) return interruptedExit(o.out);
    if (!writeFiles(kitOut.staging(), files.kit, &err) || !writeFiles(answersOut.staging(), files.answers, &err)) {
        fail(err);
        return kExitBadInput;
    }
    for (const kit::KitFiles::IdImage &im : files.answerImages)
        if (!writeExrUint32((fs::path(answersOut.staging()) / im.path).string(), im.width, im.height, im.ids.data(), "id",
                            &err)) {
            fail(err);
            return kExitBadInput;
        }
    // The instructor's answers first: a kit is never handed out without them.
    if (const int rc = commitOutput(answersOut, answers); rc != kExitOk) return rc;
    if (const int rc = commitOutput(kitOut, o.out); rc != kExitOk) return rc;
    if (!o.quiet)
        std::printf("kit: %s (%zu files, for the students)\nanswers: %s (%zu files, keep them)\n", o.out.c_str(),
                    files.kit.size(), answers.c_str(), files.answers.size() + files.answerImages.size());
    return kExitOk;
}

void addAssignmentOptions(CLI::App *c, AssignmentOptions &o) {
    addSceneOptions(c, o.scene);
    c->add_option("--scene", o.scene.scene, "The scene (the same as the positional SCENE)");
    c->add_option("--stages", o.stages, "Stages the students implement: backface, clip, zbuffer, painter, comma-separated, "
                                        "or all (default)");
    c->add_option("--out", o.out, "The kit's folder (for the students)")->required();
    c->add_option("--answers", o.answers, "The reference answers' folder (for the instructor; default OUT-answers)");
    c->add_option("--width", o.width, "Override every view's width (small images keep a kit light)")->check(CLI::Range(1, 16384));
    c->add_option("--height", o.height, "Override every view's height")->check(CLI::Range(1, 16384));
    c->add_option("--depth-format", o.depthFormat, "Override every view's depth format");
    c->add_option("--painter-key", o.painterKey, "The painter's sort key the students use: centroid (default), nearest, "
                                                 "farthest");
    c->add_option("--images", o.images, "What the z-buffer stage hands in per pixel: ids,depth (default), ids or depth");
    c->add_option("--threads", o.threads, "Worker threads (0 = all cores); the kit does not depend on it")
        ->check(CLI::Range(0, 4096));
    c->add_flag("--quiet", o.quiet, "Print nothing on success");
}

}  // namespace

CommandRun setupAssignment(CLI::App *c) { return bindCommand<AssignmentOptions>(c, addAssignmentOptions, cmdAssignment); }

}  // namespace va
