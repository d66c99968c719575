// What the commands share: errors and interrupts, loading a scene and its views, reading JSON
// inputs, committing a report folder, and the flags of every command that loads a scene.
#pragma once

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "analysis/load/route.h"
#include "analysis/scene.h"
#include "common/limits.h"
#include "render/depth_format.h"

namespace va {

class OutputDir;

// "visaudit: error: MSG" on stderr.
void fail(const std::string &msg);

// SIGINT and SIGTERM: the handler only records the signal (gInterrupt); the pipeline polls it
// between views and stages (PipelineSettings::cancel) and the commands before they write.
extern std::atomic<int> gInterrupt;
void installInterruptHandlers();
bool interrupted();
// The one line and the exit code (128 + signal, as a shell reports a signal) of a stopped run.
int interruptedExit(const std::string &out);

// The scene and its views: every command that loads a scene has these flags.
struct SceneOptions {
    std::string scene;          // empty: the built-in demo
    std::string views;          // views file, "orbit:N", "spawns", "walk:N", "route:FILE[:N|:Ts]", or empty (the scene's own)
    int patchLevel = 5;
    uint32_t chunk = 512;
    uint64_t maxTriangles = kDefaultMaxTriangles;
    uint64_t maxJsonDepth = kDefaultMaxJsonDepth;
    bool refuseEmptyScene = false;  // check: a scene with no triangle is exit 2, not an empty pass
    double eyeHeight = 0;           // grid:N's eyes above the floor (0: 50 on a Quake 3 map, else 1.7)
};
void addSceneOptions(CLI::App *c, SceneOptions &o);
// --max-json-depth: every command that reads JSON (docs/limits.md, "JSON nesting").
void addJsonDepthOption(CLI::App *c, uint64_t &maxJsonDepth);
// Loads the scene (or makes the demo) and its views as the options say; false after saying why.
// `routes` (optional) receives the route the views were sampled from (--views route:FILE).
bool loadInputs(const SceneOptions &o, Scene *scene, std::vector<ViewSpec> *views,
                std::vector<Route> *routes = nullptr);

// "a,b,log24:C=0.01" or "all" into depth formats (in the order given); false + message on an
// unknown or repeated name.
bool parseDepthFormatList(const std::string &list, std::vector<DepthFormatSpec> *out, std::string *err);
// Reads a JSON file for grade/check; false + message naming the file.
bool readJsonFile(const std::string &what, const std::string &path, uint64_t maxJsonDepth,
                  nlohmann::ordered_json *out, std::string *err);
// The last step of a command that writes a report folder: unless interrupted, the staging folder
// replaces `dir` as a whole. Returns the exit code (kExitOk: committed).
int commitOutput(OutputDir &out, const std::string &dir);

}  // namespace va
