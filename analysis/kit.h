// Assignment kits (docs/grading.md): for a scene and its views, what a student needs to implement
// one visibility stage at a time -- each stage's exact input per view, as the pipeline feeds it --
// and, apart, the reference answers the project's own stage functions give on exactly those inputs.
//
// Stage isolation: each stage's input is built from the *reference* answer of the stage before it
// (the clip input is what the reference backface stage kept, the z-buffer input is what the
// reference clipper emitted), so a student's mistake in one stage never reaches the grading of the
// next. Round trip: every input file is written as text, parsed back from that text, and the
// answers are computed from the parsed values; the doubles are written as the shortest decimal that
// reads back as the same double (nlohmann's dump), so the files alone reproduce the answers bit
// for bit (tests/test_assignment.cpp reads a kit from disk and checks it).
//
// This file builds kits (it runs stages) and reads them back; reports/kit_grade.h grades a
// student's submission against the answers and never runs a stage.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "analysis/audits/ordering.h"
#include "analysis/pipeline.h"
#include "analysis/scene.h"
#include "render/clip.h"
#include "render/raster.h"

namespace va::kit {

constexpr const char *kAssignmentFormat = "visaudit-assignment/1";
constexpr const char *kAnswersFormat = "visaudit-answers/1";
constexpr const char *kSubmissionFormat = "visaudit-submission/1";
constexpr const char *kBackfaceFormat = "visaudit-kit-backface/1";
constexpr const char *kClipFormat = "visaudit-kit-clip/1";
constexpr const char *kZBufferFormat = "visaudit-kit-zbuffer/1";
constexpr const char *kPainterFormat = "visaudit-kit-painter/1";
constexpr const char *kAnswerFormat = "visaudit-answer/1";

// The stages a kit can hold, in the pipeline's order.
enum class Stage : uint8_t { backface, clip, zbuffer, painter };
constexpr Stage kAllStages[] = {Stage::backface, Stage::clip, Stage::zbuffer, Stage::painter};
const char *stageName(Stage s);
// "clip,zbuffer" or "all" into stages in the pipeline's order; false + message naming the unknown
// or repeated name and the known ones.
bool parseStageList(const std::string &list, std::vector<Stage> *out, std::string *err);

// ---- Inputs ---------------------------------------------------------------------------------------

// backface: the world triangles of the culling objects the coarse stages (cells or grid, frustum,
// occlusion) kept, in submission order, and the eye (the view direction when orthographic).
struct BackfaceInput {
    struct Triangle {
        uint32_t id = 0;
        bool doubleSided = false;
        Vec3 v[3];
    };
    std::vector<Triangle> triangles;
};
// clip: the triangles the reference backface stage kept, in submission order, by their view-space
// corners (view[3 t + k]); the camera's numbers come from the view.
struct ClipInput {
    std::vector<uint32_t> ids;
    std::vector<Vec3> view;
    double guardBandPixels = 8192;
};
// zbuffer: the reference clipper's screen triangles (fixed point, source id, depth plane each).
struct ZBufferInput {
    ScreenTriangles triangles;
};
// painter: every analysed triangle that reaches the screen with no culling (as the ordering audit
// sees the view): its vertices' view depths (the sort key's input), whether it is single-sided, and
// its screen triangles with its depth plane.
struct PainterInput {
    std::vector<PainterCandidate> candidates;  // ascending id
    std::vector<uint8_t> singleSided;          // per candidate
    ScreenTriangles screen;                    // each candidate's pieces, consecutive, in candidate order
};

struct KitView {
    std::string name;  // the view's name
    std::string dir;   // its folder under views/ in the kit and the answers (a safe file name)
    ViewSpec spec;     // as analysed (overrides applied)
    Camera cam;        // makeCamera(spec.camera)
    std::optional<BackfaceInput> backface;
    std::optional<ClipInput> clip;
    std::optional<ZBufferInput> zbuffer;
    std::optional<PainterInput> painter;
};

// What a kit holds, read back (readKit).
struct Kit {
    std::string dir;
    std::vector<Stage> stages;
    PainterKey painterKey = PainterKey::centroid;
    std::vector<std::string> images;  // per-pixel images the zbuffer stage hands in: "ids", "depth"
    uint64_t sourceTriangles = 0;     // triangle ids are below this
    std::vector<KitView> views;
    // Every input file (path relative to the kit) and its fingerprint (fingerprint()); the answers
    // list the same, so a kit and answers made apart are refused.
    std::map<std::string, std::string> fingerprints;
    bool has(Stage s) const;
};

// "fnv1a64:" and the 16 hex digits of the FNV-1a 64-bit hash of the bytes.
std::string fingerprint(const std::string &bytes);

// ---- Reference answers ----------------------------------------------------------------------------

// One stage's reference for one view. `answer` has exactly the shape a submission's block for the
// stage has (docs/grading.md), with the reference's values; `extra` is what the grader's hints read
// (backface: the culled ids; painter: the order under every sort key).
struct StageAnswer {
    Stage stage = Stage::backface;
    nlohmann::ordered_json answer;
    nlohmann::ordered_json extra;
    std::vector<uint32_t> ids;  // zbuffer, painter: 1 + visible id per pixel, 0 = background
    int width = 0, height = 0;
};
StageAnswer answerBackface(const KitView &v, const BackfaceInput &in);
// `polygons` receives the clip's polygons and `screen` its screen triangles when not null.
StageAnswer answerClip(const KitView &v, const ClipInput &in, ScreenTriangles *screen = nullptr);
StageAnswer answerZBuffer(const KitView &v, const ZBufferInput &in);
StageAnswer answerPainter(const KitView &v, const PainterInput &in, PainterKey key);

// ---- Building a kit -------------------------------------------------------------------------------

struct KitSettings {
    std::vector<Stage> stages{std::begin(kAllStages), std::end(kAllStages)};
    PainterKey painterKey = PainterKey::centroid;
    std::vector<std::string> images{"ids", "depth"};
    ClipSettings clip;
};

// Files as relative paths and contents; the caller writes them (cli/cmd_assignment.cpp).
struct KitFiles {
    std::vector<std::pair<std::string, std::string>> kit;      // for the students
    std::vector<std::pair<std::string, std::string>> answers;  // for the instructor
    struct IdImage {
        std::string path;  // relative to the answers folder
        int width = 0, height = 0;
        std::vector<uint32_t> ids;
    };
    std::vector<IdImage> answerImages;  // one-channel uint32 EXR files
};

// Builds the kit and its answers for every view (dirs[i]: view i's folder name, unique and safe).
// `sceneLabel` names the scene in the texts. Stages the kit leaves out still run when a later
// stage's input needs their reference answer. False + message when a view cannot be analysed.
bool buildKit(const Scene &scene, const std::vector<ViewSpec> &views, const std::vector<std::string> &dirs,
              const PipelineSettings &s, const KitSettings &ks, const std::string &sceneLabel, KitFiles *out,
              std::string *err);

// ---- Reading --------------------------------------------------------------------------------------

// Reads a kit folder back: assignment.json and every input file it lists (JSON nested deeper than
// maxJsonDepth refused before parsing). Messages name the file, FILE:LINE:COL and the JSON path.
bool readKit(const std::string &dir, Kit *out, std::string *err, uint64_t maxJsonDepth = kDefaultMaxJsonDepth);

// The same from texts in memory (path -> contents, as KitFiles::kit holds them), for the round trip.
bool readKitFiles(const std::string &dir, const std::map<std::string, std::string> &files, Kit *out,
                  std::string *err, uint64_t maxJsonDepth = kDefaultMaxJsonDepth);

// A view as the views files and assignment.json write it: every camera number given (eye, target,
// up, fov_y or ortho_height, near, far, width, height, depth_format).
nlohmann::ordered_json viewSpecJson(const ViewSpec &v);

}  // namespace va::kit
