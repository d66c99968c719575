// JSON input with places: parse a file with nlohmann::json, and map a JSON path (objects[1].translate)
// back to FILE:LINE:COL for error messages (STYLE 10).
//
// nlohmann's DOM keeps no source positions, so `locate` re-scans the (already validated) text along the
// path with a small skipping tokenizer: it costs one pass over the text per error message, nothing on
// the success path.
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

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

// Reads and parses `file`. Syntax errors: "FILE:LINE:COL: JSON syntax error: ...".
bool parseFile(const std::string &file, Doc *doc, std::string *err);

// Byte offset of the value at `p` (or of its key's opening quote when `key` is true); the offset of
// the deepest existing ancestor when the path does not exist.
size_t locate(const std::string &text, const Path &p, bool key = false);
// 1-based line and column (in bytes) of a byte offset.
void lineCol(const std::string &text, size_t offset, size_t *line, size_t *col);
// "FILE:LINE:COL" of the value (or key) at p.
std::string where(const Doc &doc, const Path &p, bool key = false);

// "a string", "a number", "an object", "an array", "true/false", "null".
std::string typeName(const Json &j);
// The closest known word within edit distance 2 (or a third of its length), or "".
std::string closest(const std::string &word, const std::vector<std::string> &known);
// "a, b, c"
std::string joinList(const std::vector<std::string> &words);

}  // namespace va::json
