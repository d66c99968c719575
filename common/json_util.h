// JSON input with places: parse a file with nlohmann::json, and map a JSON path (objects[1].translate)
// back to FILE:LINE:COL for error messages (STYLE 10).
//
// nlohmann's DOM keeps no source positions, so `locate` re-scans the (already validated) text along the
// path with a small skipping tokenizer: it costs one pass over the text per error message, nothing on
// the success path.
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "common/limits.h"

namespace va::json {

using Json = nlohmann::json;

// One step of a path: an object key or an array index.
struct Step {
    std::string key;
    size_t index = 0;
    bool isIndex = false;
};
using Path = std::vector<Step>;

inline Path operator/(Path p, const std::string &key) { p.push_back({key, 0, false}); return p; }
inline Path operator/(Path p, size_t index) { p.push_back({{}, index, true}); return p; }

// "objects[1].translate"; the empty path is "the top level".
std::string pathString(const Path &p);

struct Doc {
    std::string file;  // as given, for messages
    std::string text;
    Json root;
};

// ---- Nesting depth (docs/limits.md, "JSON nesting") ----------------------------------------------
// nlohmann's parser and destructor walk a document without recursion, but copying, comparing and
// dumping a value recurse once per level, and so do tinygltf's conversion of a glTF's extras and
// extensions and its destructors: a document nested a few hundred thousand levels deep overflows the
// stack (exit 139). Every JSON input is therefore checked by checkDepth before it is parsed.
//
// The highest limit --max-json-depth accepts. Measured on this project's toolchain (GCC 12, 8 MiB
// main-thread stack): nlohmann's dump overflows at about 2800 levels in the AddressSanitizer build
// (about 2.7 KiB of stack per level there) and past 70 000 in Release; 2048 keeps a quarter of the
// sanitized stack spare for the frames below the dump.
constexpr uint64_t kMaxJsonDepthCeiling = 2048;

// The depth of `[[1]]` is 2, of `{"a": [1]}` 2, of `1` 0: arrays and objects open around a point.
// Scans `text` once, without recursion (brackets inside strings do not count), and refuses it when
// the depth passes maxDepth: "FILE:LINE:COL: arrays and objects nested D levels deep, more than the
// limit of M; raise it with --max-json-depth D ..." placed at the first bracket past the limit, D the
// text's deepest point. Runs before the text is parsed, so a malformed text may be refused for its
// depth first. `file` names the input in the message (a glTF's path; for a .glb its JSON chunk).
bool checkDepth(std::string_view text, const std::string &file, uint64_t maxDepth, std::string *err);

// Reads and parses `file`, after checkDepth. Syntax errors: "FILE:LINE:COL: JSON syntax error: ...".
bool parseFile(const std::string &file, Doc *doc, std::string *err, uint64_t maxDepth = kDefaultMaxJsonDepth);
// The same for a text already in memory (`file` names it in messages).
bool parseText(const std::string &file, std::string text, Doc *doc, std::string *err,
               uint64_t maxDepth = kDefaultMaxJsonDepth);

// Byte offset of the value at `p` (or of its key's opening quote when `key` is true); the offset of
// the deepest existing ancestor when the path does not exist.
size_t locate(const std::string &text, const Path &p, bool key = false);
// 1-based line and column (in bytes) of a byte offset.
void lineCol(std::string_view text, size_t offset, size_t *line, size_t *col);
// "FILE:LINE:COL" of the value (or key) at p.
std::string where(const Doc &doc, const Path &p, bool key = false);

// "a string", "a number", "an object", "an array", "true/false", "null".
std::string typeName(const Json &j);
// The closest known word within edit distance 2 (or a third of its length), or "".
std::string closest(const std::string &word, const std::vector<std::string> &known);
// "a, b, c"
std::string joinList(const std::vector<std::string> &words);

}  // namespace va::json
