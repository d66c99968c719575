#include "common/json_util.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace va::json {

std::string pathString(const Path &p) {
    if (p.empty()) return "the top level";
    std::string s;
    for (const auto &st : p) {
        if (st.isIndex) s += "[" + std::to_string(st.index) + "]";
        else s += (s.empty() ? "" : ".") + st.key;
    }
    return s;
}

void lineCol(std::string_view text, size_t offset, size_t *line, size_t *col) {
    offset = std::min(offset, text.size());
    size_t l = 1, lineStart = 0;
    for (size_t i = 0; i < offset; ++i)
        if (text[i] == '\n') ++l, lineStart = i + 1;
    *line = l;
    *col = offset - lineStart + 1;
}

bool checkDepth(std::string_view text, const std::string &file, uint64_t maxDepth, std::string *err) {
    // One pass, a counter instead of a stack: '[' and '{' open a level, ']' and '}' close one, and
    // a string (from '"' to the next '"' not escaped by '\\') is skipped whole.
    uint64_t depth = 0, deepest = 0;
    size_t firstOver = std::string_view::npos;
    for (size_t i = 0; i < text.size(); ++i) {
        const char c = text[i];
        if (c == '"') {
            for (++i; i < text.size() && text[i] != '"'; ++i)
                if (text[i] == '\\') ++i;
        } else if (c == '[' || c == '{') {
            if (++depth > deepest) deepest = depth;
            if (depth > maxDepth && firstOver == std::string_view::npos) firstOver = i;
        } else if ((c == ']' || c == '}') && depth > 0) {
            --depth;
        }
    }
    if (firstOver == std::string_view::npos) return true;
    size_t line = 0, col = 0;
    lineCol(text, firstOver, &line, &col);
    *err = file + ":" + std::to_string(line) + ":" + std::to_string(col) + ": arrays and objects nested " +
           std::to_string(deepest) + " levels deep, more than the limit of " + std::to_string(maxDepth) + "; ";
    if (deepest <= kMaxJsonDepthCeiling)
        *err += "raise it with --max-json-depth " + std::to_string(deepest) + " if the file is meant to nest so deep";
    else
        *err += "--max-json-depth accepts at most " + std::to_string(kMaxJsonDepthCeiling) +
                " (no scene, views, glTF, budget or report file nests so deep): the file is damaged or was "
                "made to exhaust a parser's stack";
    return false;
}

bool parseFile(const std::string &file, Doc *doc, std::string *err, uint64_t maxDepth) {
    std::error_code ec;
    if (!std::filesystem::exists(file, ec)) {
        *err = file + ": file not found";
        return false;
    }
    std::ifstream f(file, std::ios::binary);
    if (!f) {
        *err = file + ": cannot open the file for reading (check its permissions)";
        return false;
    }
    std::ostringstream ss;
    ss << f.rdbuf();
    return parseText(file, std::move(ss).str(), doc, err, maxDepth);
}

bool parseText(const std::string &file, std::string text, Doc *doc, std::string *err, uint64_t maxDepth) {
    doc->file = file;
    doc->text = std::move(text);
    if (!checkDepth(doc->text, file, maxDepth, err)) return false;
    try {
        doc->root = Json::parse(doc->text);
    } catch (const Json::parse_error &e) {
        // e.byte is the 1-based offset of the last character read; nlohmann's message starts with
        // "[json.exception.parse_error.101] parse error at line L, column C: ", which we replace by
        // our own FILE:LINE:COL (computed from the same offset).
        size_t line = 0, col = 0;
        lineCol(doc->text, e.byte > 0 ? e.byte - 1 : 0, &line, &col);
        std::string what = e.what();
        const size_t k = what.find(": ", what.find("column"));
        if (k != std::string::npos) what = what.substr(k + 2);
        *err = file + ":" + std::to_string(line) + ":" + std::to_string(col) + ": JSON syntax error: " + what;
        return false;
    } catch (const Json::exception &e) {
        // out_of_range.406: a number literal too large for a double ("number overflow parsing
        // '1e999'"). nlohmann gives no offset: place it at the literal's first occurrence.
        std::string what = e.what();
        const size_t k = what.find("] ");
        if (k != std::string::npos) what = what.substr(k + 2);
        size_t at = std::string::npos;
        const size_t q = what.find('\'');
        if (q != std::string::npos) {
            const size_t q2 = what.find('\'', q + 1);
            if (q2 != std::string::npos) at = doc->text.find(what.substr(q + 1, q2 - q - 1));
        }
        size_t line = 1, col = 1;
        if (at != std::string::npos) lineCol(doc->text, at, &line, &col);
        *err = file + ":" + std::to_string(line) + ":" + std::to_string(col) + ": JSON error: " + what +
               " (the number does not fit a double)";
        return false;
    }
    return true;
}

namespace {

// A skipping tokenizer over valid JSON text.
struct Scanner {
    const std::string &t;
    size_t i = 0;
    void ws() {
        while (i < t.size() && (t[i] == ' ' || t[i] == '\t' || t[i] == '\n' || t[i] == '\r')) ++i;
    }
    std::string string() {  // at '"'; returns the decoded key (escapes kept verbatim except \" and \\)
        std::string s;
        ++i;
        while (i < t.size() && t[i] != '"') {
            if (t[i] == '\\' && i + 1 < t.size()) {
                ++i;
                s += t[i] == 'n' ? '\n' : t[i] == 't' ? '\t' : t[i];
            } else {
                s += t[i];
            }
            ++i;
        }
        ++i;
        return s;
    }
    // Skips one value. Arrays and objects are skipped by counting brackets (strings skipped whole),
    // never by recursion: the text's depth is bounded by checkDepth, but this walk needs no bound.
    void value() {
        ws();
        if (i >= t.size()) return;
        const char c = t[i];
        if (c == '"') {
            string();
        } else if (c == '{' || c == '[') {
            size_t depth = 0;
            while (i < t.size()) {
                const char d = t[i];
                if (d == '"') {
                    string();
                    continue;
                }
                ++i;
                if (d == '{' || d == '[') ++depth;
                else if ((d == '}' || d == ']') && --depth == 0) return;
            }
        } else {
            while (i < t.size() && t[i] != ',' && t[i] != '}' && t[i] != ']' && t[i] != ' ' && t[i] != '\n' &&
                   t[i] != '\t' && t[i] != '\r')
                ++i;
        }
    }
};

}  // namespace

size_t locate(const std::string &text, const Path &p, bool key) {
    Scanner s{text};
    s.ws();
    size_t found = s.i, keyPos = s.i;
    for (size_t d = 0; d < p.size(); ++d) {
        const Step &st = p[d];
        s.ws();
        if (s.i >= text.size()) return found;
        bool ok = false;
        if (st.isIndex && text[s.i] == '[') {
            ++s.i;
            for (size_t k = 0;; ++k) {
                s.ws();
                if (s.i >= text.size() || text[s.i] == ']') break;
                if (k == st.index) {
                    ok = true;
                    keyPos = s.i;
                    break;
                }
                s.value();
                s.ws();
                if (s.i < text.size() && text[s.i] == ',') ++s.i;
            }
        } else if (!st.isIndex && text[s.i] == '{') {
            ++s.i;
            // nlohmann keeps the last of duplicate keys: remember the last match.
            size_t lastVal = std::string::npos, lastKey = 0;
            while (true) {
                s.ws();
                if (s.i >= text.size() || text[s.i] != '"') break;
                const size_t kp = s.i;
                const std::string k = s.string();
                s.ws();
                ++s.i;  // ':'
                s.ws();
                if (k == st.key) lastVal = s.i, lastKey = kp;
                s.value();
                s.ws();
                if (s.i < text.size() && text[s.i] == ',') ++s.i;
                else break;
            }
            if (lastVal != std::string::npos) {
                ok = true;
                s.i = lastVal;
                keyPos = lastKey;
            }
        }
        if (!ok) return found;
        found = s.i;
    }
    return key ? keyPos : found;
}

std::string where(const Doc &doc, const Path &p, bool key) {
    size_t line = 0, col = 0;
    lineCol(doc.text, locate(doc.text, p, key), &line, &col);
    return doc.file + ":" + std::to_string(line) + ":" + std::to_string(col);
}

std::string typeName(const Json &j) {
    switch (j.type()) {
    case Json::value_t::string: return "a string";
    case Json::value_t::number_integer:
    case Json::value_t::number_unsigned:
    case Json::value_t::number_float: return "a number";
    case Json::value_t::object: return "an object";
    case Json::value_t::array: return "an array";
    case Json::value_t::boolean: return "true/false";
    case Json::value_t::null: return "null";
    default: return "an unknown value";
    }
}

std::string closest(const std::string &word, const std::vector<std::string> &known) {
    // Levenshtein distance, case-insensitive.
    auto lower = [](std::string s) {
        for (auto &c : s) c = char(std::tolower((unsigned char)c));
        return s;
    };
    const std::string w = lower(word);
    std::string best;
    size_t bestD = std::max<size_t>(2, w.size() / 3) + 1;
    for (const auto &kRaw : known) {
        const std::string k = lower(kRaw);
        std::vector<size_t> prev(k.size() + 1), cur(k.size() + 1);
        for (size_t j = 0; j <= k.size(); ++j) prev[j] = j;
        for (size_t i = 1; i <= w.size(); ++i) {
            cur[0] = i;
            for (size_t j = 1; j <= k.size(); ++j)
                cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (w[i - 1] == k[j - 1] ? 0 : 1)});
            std::swap(prev, cur);
        }
        if (prev[k.size()] < bestD) bestD = prev[k.size()], best = kRaw;
    }
    return best;
}

std::string joinList(const std::vector<std::string> &words) {
    std::string s;
    for (const auto &w : words) s += (s.empty() ? "" : ", ") + w;
    return s;
}

}  // namespace va::json
