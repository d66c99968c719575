// Grading a submission against an assignment kit (kit_grade.h; docs/grading.md).
#include "reports/kit_grade.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>


#include "common/json_util.h"
#include "reports/legend.h"
#include "reports/report.h"

namespace va::kit {

namespace fs = std::filesystem;
using OJson = nlohmann::ordered_json;

namespace {

// A submission's JSON: read once, by the bounded parser (json::parseFile), in its own key order.
using SJson = json::Json;

std::string dumps(const OJson &j) { return j.dump(-1, ' ', false, OJson::error_handler_t::replace); }
std::string dumps(const SJson &j) { return j.dump(-1, ' ', false, SJson::error_handler_t::replace); }

std::string fmtDouble(double v) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}
std::string capitalize(std::string s) {
    if (!s.empty() && s[0] >= 'a' && s[0] <= 'z') s[0] = char(s[0] - 'a' + 'A');
    return s;
}
// The shortest decimal that reads back as v ("0.1", not "0.10000000000000001").
std::string shortest(double v) { return OJson(v).dump(); }
std::string percent(double share) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.2f%%", 100 * share);
    return buf;
}
// Up to `n` ids of a list, for notes ("17, 18, 40, ...").
std::string someIds(const std::vector<uint32_t> &ids, size_t n = 5) {
    std::string s;
    for (size_t i = 0; i < ids.size() && i < n; ++i) s += (i ? ", " : "") + std::to_string(ids[i]);
    if (ids.size() > n) s += ", ...";
    return s;
}

// Reads `text` as an ordered document (key order kept) after the bounded parse that checks depth
// and syntax and places errors (json::parseText).
bool parseOrdered(const std::string &file, const std::string &text, OJson *out, std::string *err, uint64_t maxDepth) {
    json::Doc doc;
    if (!json::parseText(file, text, &doc, err, maxDepth)) return false;
    *out = OJson::parse(doc.text);
    return true;
}
bool slurp(const std::string &path, std::string *out) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) return false;
    std::ifstream f(path, std::ios::binary);
    if (!f) return false;
    std::ostringstream ss;
    ss << f.rdbuf();
    *out = std::move(ss).str();
    return true;
}

}  // namespace

// ---- The answers ------------------------------------------------------------------------------------

bool readAnswers(const std::string &dir, const Kit &kit, AnswerSet *out, std::string *err, uint64_t maxJsonDepth) {
    const std::string top = (fs::path(dir) / "answers.json").string();
    std::string text;
    if (!slurp(top, &text)) {
        *err = top + ": file not found; --reference names the answers folder `visaudit assignment --answers` wrote";
        return false;
    }
    json::Doc doc;
    if (!json::parseText(top, text, &doc, err, maxJsonDepth)) return false;
    const json::Json &root = doc.root;
    auto failAt = [&](const json::Path &p, const std::string &msg) {
        *err = json::where(doc, p) + ": " + json::pathString(p) + ": " + msg;
        return false;
    };
    if (!root.is_object() || !root.contains("format") || root["format"] != kAnswersFormat)
        return failAt(json::Path{} / "format", std::string("expected \"") + kAnswersFormat +
                                                   "\": --reference names the answers folder `visaudit assignment` wrote");
    if (!root.contains("kit_files") || !root["kit_files"].is_object())
        return failAt(json::Path{} / "kit_files", "expected an object of kit files and their fingerprints");
    const json::Json &files = root["kit_files"];
    const std::string remake = "; grade with the kit made together with these answers (or make both again with "
                               "visaudit assignment)";
    for (const auto &[rel, fp] : kit.fingerprints) {
        if (!files.contains(rel))
            return failAt(json::Path{} / "kit_files",
                          "the kit's " + rel + " is not among the files these answers were made for" + remake);
        if (files[rel] != fp)
            return failAt(json::Path{} / "kit_files" / rel,
                          (fs::path(kit.dir) / rel).string() + " is not the file these answers were made for (its "
                          "fingerprint is " + fp + ")" + remake);
    }
    for (const auto &[rel, fp] : files.items())
        if (!kit.fingerprints.count(rel))
            return failAt(json::Path{} / "kit_files" / rel,
                          "the answers were made for " + rel + ", which the kit " + kit.dir + " does not hold" + remake);

    if (!root.contains("answer_files") || !root["answer_files"].is_object())
        return failAt(json::Path{} / "answer_files", "expected an object of answer files and their fingerprints");
    const json::Json &answerPrints = root["answer_files"];

    AnswerSet set;
    set.dir = dir;
    for (const KitView &v : kit.views) {
        std::vector<StageAnswer> stages;
        for (Stage st : kit.stages) {
            const std::string rel = "views/" + v.dir + "/" + stageName(st) + ".json";
            const std::string file = (fs::path(dir) / rel).string();
            std::string t;
            if (!slurp(file, &t)) {
                *err = file + ": file not found; the answers folder is incomplete (make it again with visaudit assignment)";
                return false;
            }
            // Written by visaudit assignment and unchanged since (so its shape is the one the grader reads).
            if (!answerPrints.contains(rel) || answerPrints[rel] != fingerprint(t)) {
                *err = file + ": not the file visaudit assignment wrote for these answers (" +
                       (answerPrints.contains(rel) ? "changed since" : "not listed in answers.json") +
                       "); make the answers again with visaudit assignment";
                return false;
            }
            OJson j;
            if (!parseOrdered(file, t, &j, err, maxJsonDepth)) return false;
            if (!j.is_object() || j.value("format", "") != kAnswerFormat || !j.contains("answer") ||
                !j["answer"].is_object()) {
                *err = file + ": not a reference answer (\"format\": \"" + kAnswerFormat +
                       "\" with an \"answer\" object); make the answers again with visaudit assignment";
                return false;
            }
            StageAnswer a;
            a.stage = st;
            a.answer = j["answer"];
            if (j.contains("extra")) a.extra = j["extra"];
            if (j.contains("images") && j["images"].is_object() && j["images"].contains("ids")) {
                const OJson &name = j["images"]["ids"];
                const std::string path = (fs::path(dir) / "views" / v.dir / (name.is_string() ? name.get<std::string>() : "")).string();
                ImageData im;
                std::string e;
                if (!name.is_string() || !readImage(path, &im, &e)) {
                    *err = file + ": images.ids: " + (name.is_string() ? e : "expected a file name") +
                           "; make the answers again with visaudit assignment";
                    return false;
                }
                if (im.width != v.cam.width || im.height != v.cam.height || im.u32.empty() || im.channels() != 1) {
                    *err = path + ": expected one uint32 channel of " + std::to_string(v.cam.width) + "x" +
                           std::to_string(v.cam.height) + " ids; make the answers again with visaudit assignment";
                    return false;
                }
                for (uint32_t id : im.u32)
                    if (id > kit.sourceTriangles) {
                        *err = path + ": holds id " + std::to_string(id) + ", past the scene's " +
                               std::to_string(kit.sourceTriangles) + " triangles; make the answers again with visaudit assignment";
                        return false;
                    }
                a.ids = std::move(im.u32);
                a.width = im.width;
                a.height = im.height;
            }
            stages.push_back(std::move(a));
        }
        set.views.push_back(std::move(stages));
    }
    *out = std::move(set);
    return true;
}

std::string hintTitle(const std::string &id, PainterKey kitKey) {
    const std::string own = painterKeyName(kitKey);
    if (id == "fill_rule") return "Fill rule: the top-left rule inverted";
    if (id == "tie_rule") return "Ties: LESS_EQUAL instead of LESS";
    if (id == "depth_test_greater") return "Depth test GREATER: the farthest surface wins";
    if (id == "near_not_clipped") return "Near plane not clipped";
    if (id == "winding_reversed") return "Winding reversed";
    if (id == "painter_key_nearest") return "Painter's key: the nearest vertex instead of the " + own;
    if (id == "painter_key_farthest") return "Painter's key: the farthest vertex instead of the " + own;
    if (id == "painter_key_centroid") return "Painter's key: the centroid instead of the " + own;
    if (id == "painter_front_to_back") return "Painter's order: front to back";
    return id;
}

Tolerance kitTolerance(const ToleranceRules &t, const std::string &metric, bool integer) {
    auto ends = [&](const char *suffix) {
        const size_t n = std::strlen(suffix);
        return metric.size() >= n && metric.compare(metric.size() - n, n, suffix) == 0;
    };
    Tolerance builtin{0, integer ? 0 : 1e-9};
    if (ends(".polygons")) builtin = {1e-9, 1e-9};
    else if (ends(".depth_values")) builtin = {0, 1e-6};
    else if (ends(".ids") || ends(".depth")) builtin = {0, 0};
    return toleranceFor(t, metric, builtin);
}

namespace {

// Whether `path`, its links followed, lies inside `dir` (followed too): a submission's files are read
// only there, so a link cannot make the grader read, and quote in a message, someone else's file.
bool withinFolder(const fs::path &path, const fs::path &dir) {
    std::error_code ec;
    const fs::path d = fs::weakly_canonical(dir, ec);
    if (ec) return false;
    const fs::path p = fs::weakly_canonical(path, ec);
    if (ec) return false;
    auto pi = p.begin();
    for (auto di = d.begin(); di != d.end(); ++di, ++pi) {
        if (di->empty()) continue;  // a trailing separator
        if (pi == p.end() || *pi != *di) return false;
    }
    return true;
}

// ---- Student images ---------------------------------------------------------------------------------

struct Pixels {
    int width = 0, height = 0;
    std::vector<double> v;  // row-major, top row first
};

std::string lowerExt(const std::string &path) {
    std::string e = fs::path(path).extension().string();
    for (char &c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
    return e;
}

// A CSV image: `height` lines of `width` numbers. Stops at the first line or value past the
// expected size (a wrong size is said without reading the rest).
bool readCsvImage(const std::string &path, const std::string &shown, int W, int H, Pixels *out, std::string *why) {
    std::ifstream f(path, std::ios::binary);
    if (!f) {
        *why = shown + ": cannot be read";
        return false;
    }
    Pixels px;
    std::string line;
    int row = 0, cols0 = -1;
    while (std::getline(f, line)) {
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (line.empty()) continue;
        if (row >= H) {
            *why = shown + ": more than " + std::to_string(H) + " rows; the view is " + std::to_string(W) + "x" +
                   std::to_string(H) + " (one line per pixel row)";
            return false;
        }
        int cols = 0;
        size_t i = 0;
        while (i <= line.size()) {
            size_t j = line.find(',', i);
            if (j == std::string::npos) j = line.size();
            std::string cell = line.substr(i, j - i);
            while (!cell.empty() && std::isspace(static_cast<unsigned char>(cell.front()))) cell.erase(cell.begin());
            while (!cell.empty() && std::isspace(static_cast<unsigned char>(cell.back()))) cell.pop_back();
            char *end = nullptr;
            const double d = std::strtod(cell.c_str(), &end);
            if (cell.empty() || *end) {
                *why = shown + ":" + std::to_string(row + 1) + ": value " + std::to_string(cols + 1) + " is '" + cell +
                       "', not a number";
                return false;
            }
            if (++cols > W) {
                *why = shown + ":" + std::to_string(row + 1) + ": more than " + std::to_string(W) +
                       " values; the view is " + std::to_string(W) + " pixels wide";
                return false;
            }
            px.v.push_back(d);
            i = j + 1;
        }
        if (cols0 < 0) cols0 = cols;
        if (cols != W) {
            *why = shown + ":" + std::to_string(row + 1) + ": " + std::to_string(cols) + " values; the view is " +
                   std::to_string(W) + " pixels wide";
            return false;
        }
        ++row;
    }
    if (row != H) {
        *why = shown + ": " + std::to_string(row) + " rows; the view is " + std::to_string(H) + " pixels high";
        return false;
    }
    px.width = W;
    px.height = H;
    *out = std::move(px);
    return true;
}

// A PFM file (Paul Debevec's portable float map): "Pf" (one channel) or "PF" (three; the first is
// used), the width and height, a scale whose sign gives the byte order (negative: little-endian),
// then 32-bit floats row by row from the *bottom* row up. Read here: PNG and EXR are read through
// libpng and OpenEXR (readImage), and none of the libraries visaudit links reads PFM.
bool readPfm(const std::string &path, const std::string &shown, int W, int H, Pixels *out, std::string *why) {
    std::ifstream f(path, std::ios::binary);
    std::string magic;
    long w = 0, h = 0;
    double scale = 0;
    if (!(f >> magic >> w >> h >> scale) || (magic != "Pf" && magic != "PF") || w <= 0 || h <= 0 || scale == 0) {
        *why = shown + ": not a PFM file (expected \"Pf\" or \"PF\", the width, the height and the scale)";
        return false;
    }
    f.get();  // the single whitespace byte after the scale
    if (w != W || h != H) {
        *why = shown + " is " + std::to_string(w) + "x" + std::to_string(h) + "; the view is " + std::to_string(W) + "x" +
               std::to_string(H);
        return false;
    }
    const int channels = magic == "PF" ? 3 : 1;
    const size_t n = size_t(W) * size_t(H);
    std::vector<unsigned char> bytes(n * size_t(channels) * 4);
    if (!f.read(reinterpret_cast<char *>(bytes.data()), std::streamsize(bytes.size()))) {
        *why = shown + ": the file ends before its " + std::to_string(n) + " pixels";
        return false;
    }
    const bool little = scale < 0;
    Pixels px;
    px.width = W;
    px.height = H;
    px.v.resize(n);
    for (int row = 0; row < H; ++row)
        for (int x = 0; x < W; ++x) {
            const unsigned char *b = &bytes[(size_t(row) * size_t(W) + size_t(x)) * size_t(channels) * 4];
            const uint32_t u = little ? uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24
                                      : uint32_t(b[3]) | uint32_t(b[2]) << 8 | uint32_t(b[1]) << 16 | uint32_t(b[0]) << 24;
            float v;
            std::memcpy(&v, &u, 4);
            px.v[size_t(H - 1 - row) * size_t(W) + size_t(x)] = v;  // stored bottom row first
        }
    *out = std::move(px);
    return true;
}

// A per-pixel image as the student wrote it: PNG (8 or 16-bit, one channel; ids only), EXR or PFM
// (the first channel), or CSV. `shown` names it in messages.
bool readStudentImage(const std::string &path, const std::string &shown, bool depth, int W, int H, Pixels *out,
                      std::string *why) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) {
        *why = shown + ": file not found";
        return false;
    }
    const std::string ext = lowerExt(path);
    if (ext == ".csv") return readCsvImage(path, shown, W, H, out, why);
    if (ext == ".pfm") return readPfm(path, shown, W, H, out, why);
    if (ext != ".png" && ext != ".exr" && ext != ".pfm") {
        *why = shown + ": unknown image type '" + ext + "'; use .png (16-bit gray, ids only), .exr, .pfm or .csv";
        return false;
    }
    if (ext == ".png" && depth) {
        *why = shown + ": a PNG holds integers; write the depth image as .exr, .pfm or .csv";
        return false;
    }
    ImageData im;
    std::string e;
    if (!readImage(path, &im, &e)) {
        *why = shown + ": " + e;
        return false;
    }
    if (im.width != W || im.height != H) {
        *why = shown + " is " + std::to_string(im.width) + "x" + std::to_string(im.height) + "; the view is " +
               std::to_string(W) + "x" + std::to_string(H);
        return false;
    }
    if (ext == ".png" && im.channels() != 1) {
        *why = shown + ": " + std::to_string(im.channels()) + " channels; write a one-channel (grayscale) PNG";
        return false;
    }
    // The first channel, integers in their own type.
    const size_t n = size_t(W) * size_t(H), C = size_t(im.channels());
    Pixels px;
    px.width = W;
    px.height = H;
    px.v.resize(n);
    for (size_t i = 0; i < n; ++i)
        px.v[i] = !im.u8.empty() ? double(im.u8[i * C])
                  : !im.u16.empty() ? double(im.u16[i * C])
                  : !im.u32.empty() ? double(im.u32[i * C])
                                    : double(im.f32[i * C]);
    *out = std::move(px);
    return true;
}

// Checks the values: ids are whole numbers >= 0 (a float image holds them exactly below 2^24);
// depths are numbers (NaN is refused: +inf or 0 mean background).
bool checkValues(const Pixels &px, const std::string &shown, bool depth, std::string *why) {
    for (size_t i = 0; i < px.v.size(); ++i) {
        const double d = px.v[i];
        if (!std::isnan(d) && (depth || (d >= 0 && d <= 4294967295.0 && d == std::floor(d)))) continue;
        const int x = int(i % size_t(px.width)), y = int(i / size_t(px.width));
        const std::string at = " at pixel (" + std::to_string(x) + ", " + std::to_string(y) + ")";
        if (std::isnan(d)) {
            *why = shown + ": NaN" + at + (depth ? "; write +inf or 0 for background" : "; write 0 for background");
            return false;
        }
        if (!depth && !(d >= 0 && d <= 4294967295.0 && d == std::floor(d))) {
            *why = shown + ": " + fmtDouble(d) + at + " is not an id (1 + a triangle id, 0 for background)";
            return false;
        }
    }
    return true;
}

// ---- Pixel comparison -------------------------------------------------------------------------------

// What classifying a stage's pixels needs: its screen triangles by source id.
struct StageScreen {
    const KitView *view = nullptr;
    const ScreenTriangles *screen = nullptr;
    std::map<uint32_t, std::pair<uint32_t, uint32_t>> pieces;  // id -> [begin, end) of its screen triangles
    DepthEncoder encoder;
    // Tiles of 32 x 32 pixels, each listing the screen triangles whose box meets it (for pixels
    // where the reference sees background and no submitted id names a triangle).
    int tilesX = 0;
    std::vector<std::vector<uint32_t>> tiles;

    StageScreen(const KitView &v, const ScreenTriangles &st) : view(&v), screen(&st) {
        for (uint32_t t = 0; t < st.size(); ++t) {
            auto [it, fresh] = pieces.try_emplace(st.source[t], t, t + 1);
            if (!fresh) it->second.second = t + 1;
        }
        encoder = makeDepthEncoder(v.spec.depthFormat, v.cam.nearZ, v.cam.farZ);
        const int W = v.cam.width, H = v.cam.height;
        tilesX = (W + 31) / 32;
        const int tilesY = (H + 31) / 32;
        tiles.resize(size_t(tilesX) * size_t(tilesY));
        for (uint32_t t = 0; t < st.size(); ++t) {
            const int32_t *p = &st.xy[6 * size_t(t)];
            const double x0 = std::min({p[0], p[2], p[4]}) / 256.0, x1 = std::max({p[0], p[2], p[4]}) / 256.0;
            const double y0 = std::min({p[1], p[3], p[5]}) / 256.0, y1 = std::max({p[1], p[3], p[5]}) / 256.0;
            const int tx0 = std::clamp(int(std::floor(x0)) / 32 - 1, 0, tilesX - 1);
            const int tx1 = std::clamp(int(std::ceil(x1)) / 32 + 1, 0, tilesX - 1);
            const int ty0 = std::clamp(int(std::floor(y0)) / 32 - 1, 0, tilesY - 1);
            const int ty1 = std::clamp(int(std::ceil(y1)) / 32 + 1, 0, tilesY - 1);
            if (x1 < -1 || y1 < -1 || x0 > W + 1 || y0 > H + 1) continue;
            for (int ty = ty0; ty <= ty1; ++ty)
                for (int tx = tx0; tx <= tx1; ++tx) tiles[size_t(ty) * size_t(tilesX) + size_t(tx)].push_back(t);
        }
    }
    bool known(uint32_t id1) const { return id1 && pieces.count(id1 - 1); }
    const DepthPlane &plane(uint32_t id1) const { return screen->planes[screen->plane[pieces.at(id1 - 1).first]]; }
    double depthAt(uint32_t id1, int x, int y) const { return viewDepthAt(view->cam, plane(id1), x + 0.5, y + 0.5); }

    // Pixel (x, y)'s centre within one fixed-point unit (1/256 px) of the boundary of screen
    // triangle t, and not farther outside it: who covers it is decided by the fill rule, or by a
    // rounding of the corners finer than the fixed point.
    bool nearEdgeOf(uint32_t t, int x, int y) const {
        const int32_t *p = &screen->xy[6 * size_t(t)];
        int64_t x0 = p[0], y0 = p[1], x1 = p[2], y1 = p[3], x2 = p[4], y2 = p[5];
        const int64_t area = (x1 - x0) * (y2 - y0) - (y1 - y0) * (x2 - x0);
        if (area == 0) return false;
        if (area < 0) std::swap(x1, x2), std::swap(y1, y2);
        const int64_t cx = int64_t(x) * 256 + 128, cy = int64_t(y) * 256 + 128;
        const int64_t ax[3] = {x1, x2, x0}, ay[3] = {y1, y2, y0}, bx[3] = {x2, x0, x1}, by[3] = {y2, y0, y1};
        bool outside = false, within = false;
        for (int k = 0; k < 3; ++k) {
            const int64_t dx = bx[k] - ax[k], dy = by[k] - ay[k];
            const double e = double(dx * (cy - ay[k]) - dy * (cx - ax[k]));
            const double len = std::hypot(double(dx), double(dy));
            if (e < -len) outside = true;
            if (e <= len) within = true;
        }
        return !outside && within;
    }
    bool nearEdge(uint32_t id1, int x, int y) const {
        if (!known(id1)) return false;
        const auto [b, e] = pieces.at(id1 - 1);
        for (uint32_t t = b; t < e; ++t)
            if (nearEdgeOf(t, x, y)) return true;
        return false;
    }
    // Any screen triangle near (x, y)'s edge (the reference sees background there).
    bool anyNearEdge(int x, int y) const {
        const size_t k = size_t(y / 32) * size_t(tilesX) + size_t(x / 32);
        for (uint32_t t : tiles[k])
            if (nearEdgeOf(t, x, y)) return true;
        return false;
    }
};

// The ids image: each pixel against the reference's id.
void compareIds(const StageScreen &ss, const std::vector<uint32_t> &ref, const Pixels &sub, PixelGrade *g) {
    const int W = ss.view->cam.width;
    g->cls.assign(ref.size(), uint8_t(Disagreement::none));
    g->pixels = ref.size();
    for (size_t i = 0; i < ref.size(); ++i) {
        const uint32_t a = ref[i], b = uint32_t(sub.v[i]);
        if (a == b) {
            ++g->agree;
            continue;
        }
        const int x = int(i % size_t(W)), y = int(i / size_t(W));
        Disagreement d = Disagreement::genuine;
        if ((a && ss.nearEdge(a, x, y)) || (b && ss.nearEdge(b, x, y))) {
            d = Disagreement::edge;
        } else if (b && !ss.known(b)) {
            ++g->unknownIds;
        } else if (a && b) {
            const double da = ss.depthAt(a, x, y), db = ss.depthAt(b, x, y);
            if (depthKey(ss.encoder, da) == depthKey(ss.encoder, db)) {
                d = Disagreement::tie;
            } else {
                ++g->comparedDepths;
                g->fartherPixels += db > da;
            }
        }
        g->cls[i] = uint8_t(d);
        (d == Disagreement::edge ? g->edge : d == Disagreement::tie ? g->tie : g->genuine)++;
    }
}

// The depth image: each pixel against the reference's depth (from its visible triangle's plane);
// `idsGrade` (the same view's ids comparison, when the student handed one in) classifies where the
// visible triangles differ.
void compareDepths(const StageScreen &ss, const std::vector<uint32_t> &ref, const Pixels &sub, Tolerance tol,
                   const PixelGrade *idsGrade, PixelGrade *g) {
    const int W = ss.view->cam.width;
    g->cls.assign(ref.size(), uint8_t(Disagreement::none));
    g->pixels = ref.size();
    for (size_t i = 0; i < ref.size(); ++i) {
        const uint32_t a = ref[i];
        const int x = int(i % size_t(W)), y = int(i / size_t(W));
        const double s = sub.v[i];
        const bool subBg = !(s > 0) || std::isinf(s);
        const double dref = a && ss.known(a) ? ss.depthAt(a, x, y) : INFINITY;
        bool agree;
        if (!a || subBg) agree = !a && subBg;
        else agree = std::fabs(s - dref) <= tol.abs || std::fabs(s - dref) <= tol.rel * dref;
        if (agree) {
            ++g->agree;
            continue;
        }
        Disagreement d = Disagreement::genuine;
        if (idsGrade && idsGrade->cls[i] != uint8_t(Disagreement::none)) {
            d = Disagreement(idsGrade->cls[i]);
        } else if (!idsGrade) {
            if ((a && ss.nearEdge(a, x, y)) || (!a && ss.anyNearEdge(x, y))) d = Disagreement::edge;
            else if (a && !subBg && depthKey(ss.encoder, s) == depthKey(ss.encoder, dref)) d = Disagreement::tie;
        }
        if (d == Disagreement::genuine && a && !subBg) {
            ++g->comparedDepths;
            g->fartherPixels += s > dref;
        }
        g->cls[i] = uint8_t(d);
        (d == Disagreement::edge ? g->edge : d == Disagreement::tie ? g->tie : g->genuine)++;
    }
}

// The reference's depth per pixel as depth.png's gray, for the diff image's background.
std::vector<uint8_t> referenceGrays(const StageScreen &ss, const std::vector<uint32_t> &ref) {
    const int W = ss.view->cam.width;
    std::vector<double> d(ref.size(), INFINITY);
    for (size_t i = 0; i < ref.size(); ++i)
        if (ss.known(ref[i])) d[i] = ss.depthAt(ref[i], int(i % size_t(W)), int(i / size_t(W)));
    return depthGrays(d);
}

// ---- Grading one submission -----------------------------------------------------------------------

struct Grader {
    const Kit &kit;
    const AnswerSet &answers;
    const ToleranceRules &tol;
    KitGrade &g;
    std::string subDir;
    std::string missingWhy;  // set when the whole submission (or a view, or a stage) is missing

    void item(const KitView &v, Stage st, const std::string &key, const std::string &ref, const std::string &sub,
              bool pass, const std::string &note = "") {
        GradeItem it;
        it.view = v.name;
        it.stage = stageName(st);
        it.key = key;
        it.reference = ref;
        it.submitted = sub;
        it.pass = pass;
        it.note = note;
        g.items.push_back(std::move(it));
    }
    void hint(const KitView &v, Stage st, const std::string &id, const std::string &text) {
        for (const GradeHint &h : g.hints)
            if (h.id == id && h.view == v.name && h.stage == stageName(st)) return;
        g.hints.push_back({id, v.name, stageName(st), hintTitle(id, kit.painterKey), text});
    }
    std::string metric(Stage st, const std::string &key) const { return std::string(stageName(st)) + "." + key; }

    // A number of the answer against the submission's value at the same key.
    void number(const KitView &v, Stage st, const std::string &key, const OJson &ref, const SJson *sub) {
        const std::string r = dumps(ref);
        if (!sub || sub->is_null()) return item(v, st, key, r, "missing", false, missingWhy);
        if (!sub->is_number()) return item(v, st, key, r, "not a number: " + dumps(*sub), false);
        const Tolerance t = kitTolerance(tol, metric(st, key), ref.is_number_integer());
        const double a = ref.get<double>(), b = sub->get<double>();
        const double diff = std::fabs(a - b);
        item(v, st, key, r, dumps(*sub), diff <= t.abs || diff <= t.rel * std::fabs(a));
    }

    void histogram(const KitView &v, Stage st, const OJson &ref, const SJson *sub) {
        const std::string key = "histogram";
        std::vector<double> a, b;
        for (const OJson &x : ref) a.push_back(x.get<double>());
        const std::string r = dumps(ref);
        if (!sub || sub->is_null()) return item(v, st, key, r, "missing", false, missingWhy);
        if (!sub->is_array()) return item(v, st, key, r, "not an array: " + dumps(*sub), false);
        for (const SJson &x : *sub) {
            if (!x.is_number()) return item(v, st, key, r, dumps(*sub), false, "not every entry is a number");
            b.push_back(x.get<double>());
        }
        while (!a.empty() && a.back() == 0) a.pop_back();
        while (!b.empty() && b.back() == 0) b.pop_back();
        const Tolerance t = kitTolerance(tol, metric(st, key), true);
        bool pass = a.size() == b.size();
        std::string note;
        for (size_t k = 0; pass && k < a.size(); ++k) {
            const double diff = std::fabs(a[k] - b[k]);
            if (!(diff <= t.abs || diff <= t.rel * std::fabs(a[k]))) {
                pass = false;
                note = "histogram[" + std::to_string(k) + "]: " + fmtDouble(b[k]) + " vs " + fmtDouble(a[k]);
            }
        }
        if (a.size() != b.size())
            note = std::to_string(b.size()) + " entries up to the last nonzero one, the reference has " + std::to_string(a.size());
        item(v, st, key, r, dumps(*sub), pass, note);
    }

    // A list of ids (backface's kept): compared as sets.
    bool idSet(const SJson *sub, std::vector<uint32_t> *out, std::string *why) const {
        if (!sub->is_array()) {
            *why = "not an array of ids: " + dumps(*sub).substr(0, 60);
            return false;
        }
        std::set<uint32_t> seen;
        for (const SJson &x : *sub) {
            if (!x.is_number_unsigned() || x.get<uint64_t>() > UINT32_MAX) {
                *why = "not an id: " + dumps(x);
                return false;
            }
            if (!seen.insert(x.get<uint32_t>()).second) {
                *why = "id " + std::to_string(x.get<uint32_t>()) + " is listed twice";
                return false;
            }
        }
        out->assign(seen.begin(), seen.end());
        return true;
    }

    void kept(const KitView &v, const StageAnswer &a, const SJson *sub) {
        std::vector<uint32_t> ref;
        for (const OJson &x : a.answer["kept"]) ref.push_back(x.get<uint32_t>());
        const std::string r = std::to_string(ref.size()) + " ids";
        if (!sub || sub->is_null()) return item(v, Stage::backface, "kept", r, "missing", false, missingWhy);
        std::vector<uint32_t> s;
        std::string why;
        if (!idSet(sub, &s, &why)) return item(v, Stage::backface, "kept", r, "unreadable", false, why);
        std::vector<uint32_t> missing, extra;
        std::set_difference(ref.begin(), ref.end(), s.begin(), s.end(), std::back_inserter(missing));
        std::set_difference(s.begin(), s.end(), ref.begin(), ref.end(), std::back_inserter(extra));
        std::string note;
        if (!missing.empty()) note += std::to_string(missing.size()) + " kept by the reference, not by you (" + someIds(missing) + ")";
        if (!extra.empty()) note += std::string(note.empty() ? "" : "; ") + std::to_string(extra.size()) +
                                    " kept by you, culled by the reference (" + someIds(extra) + ")";
        item(v, Stage::backface, "kept", r, std::to_string(s.size()) + " ids", missing.empty() && extra.empty(), note);

        // Winding reversed: the submission keeps most of what the reference culls and culls most
        // of what it keeps (among the single-sided triangles; double-sided ones are always kept).
        std::set<uint32_t> twoSided;
        for (const BackfaceInput::Triangle &t : v.backface->triangles)
            if (t.doubleSided) twoSided.insert(t.id);
        std::vector<uint32_t> culled;
        for (const OJson &x : a.extra["culled"]) culled.push_back(x.get<uint32_t>());
        size_t front = 0, frontKept = 0, backKept = 0;
        const std::set<uint32_t> sset(s.begin(), s.end());
        for (uint32_t id : ref)
            if (!twoSided.count(id)) ++front, frontKept += sset.count(id);
        for (uint32_t id : culled) backKept += sset.count(id);
        if (front + culled.size() > 0 && 10 * backKept >= 9 * culled.size() && 10 * frontKept <= front &&
            !(missing.empty() && extra.empty()))
            hint(v, Stage::backface, "winding_reversed",
                 "You keep " + std::to_string(backKept) + " of the " + std::to_string(culled.size()) +
                     " triangles facing away and cull " + std::to_string(front - frontKept) + " of the " +
                     std::to_string(front) + " facing the eye. Front faces are counter-clockwise seen from the front: "
                     "with n = (v1 − v0) × (v2 − v0), a triangle faces the eye when n·(eye − v0) > 0.");
    }

    void polygons(const KitView &v, const StageAnswer &a, const SJson *sub) {
        const Stage st = Stage::clip;
        const OJson &ref = a.answer["polygons"];
        const std::string r = std::to_string(ref.size()) + " polygons";
        if (!sub || sub->is_null()) return item(v, st, "polygons", r, "missing", false, missingWhy);
        if (!sub->is_array()) return item(v, st, "polygons", r, "unreadable", false, "not an array of polygons");
        // The submission's polygons by id.
        std::map<uint32_t, std::vector<std::array<double, 4>>> mine;
        double nearest = INFINITY;  // the least d of any submitted vertex
        for (size_t i = 0; i < sub->size(); ++i) {
            const SJson &p = (*sub)[i];
            const std::string at = "polygons[" + std::to_string(i) + "]";
            if (!p.is_object() || !p.contains("id") || !p["id"].is_number_unsigned() || !p.contains("vertices") ||
                !p["vertices"].is_array())
                return item(v, st, "polygons", r, "unreadable", false, at + ": expected {\"id\": ID, \"vertices\": [[x, y, w, d], ...]}");
            std::vector<std::array<double, 4>> vs;
            for (const SJson &q : p["vertices"]) {
                if (!q.is_array() || q.size() != 4)
                    return item(v, st, "polygons", r, "unreadable", false, at + ": a vertex is [x, y, w, d]");
                std::array<double, 4> c{};
                for (size_t k = 0; k < 4; ++k) {
                    if (!q[k].is_number()) return item(v, st, "polygons", r, "unreadable", false, at + ": a vertex holds 4 numbers");
                    c[k] = q[k].get<double>();
                }
                nearest = std::min(nearest, c[3]);
                vs.push_back(c);
            }
            if (p["id"].get<uint64_t>() > UINT32_MAX || !mine.emplace(p["id"].get<uint32_t>(), std::move(vs)).second)
                return item(v, st, "polygons", r, "unreadable", false, at + ": id " + dumps(p["id"]) + " is listed twice");
        }
        const Tolerance t = kitTolerance(tol, metric(st, "polygons"), false);
        auto close = [&](double x, double y) { return std::fabs(x - y) <= t.abs || std::fabs(x - y) <= t.rel * std::fabs(x); };
        size_t matched = 0, missing = 0, count = 0, off = 0;
        std::string first;
        std::set<uint32_t> refIds;
        for (const OJson &p : ref) {
            const uint32_t id = p["id"].get<uint32_t>();
            refIds.insert(id);
            auto it = mine.find(id);
            if (it == mine.end()) {
                ++missing;
                if (first.empty()) first = "triangle " + std::to_string(id) + ": no polygon";
                continue;
            }
            const OJson &rv = p["vertices"];
            const auto &sv = it->second;
            if (sv.size() != rv.size()) {
                ++count;
                if (first.empty())
                    first = "triangle " + std::to_string(id) + ": " + std::to_string(sv.size()) + " vertices, the reference has " +
                            std::to_string(rv.size());
                continue;
            }
            bool any = false;
            for (size_t rot = 0; rot < sv.size() && !any; ++rot) {
                bool all = true;
                for (size_t k = 0; k < sv.size() && all; ++k)
                    for (size_t c = 0; c < 4 && all; ++c) all = close(rv[k][c].get<double>(), sv[(k + rot) % sv.size()][c]);
                any = all;
            }
            if (any) {
                ++matched;
            } else {
                ++off;
                if (first.empty()) {
                    first = "triangle " + std::to_string(id) + ": [";
                    for (size_t k = 0; k < sv.size(); ++k)
                        first += std::string(k ? ", " : "") + "[" + fmtDouble(sv[k][0]) + ", " + fmtDouble(sv[k][1]) + ", " +
                                 fmtDouble(sv[k][2]) + ", " + fmtDouble(sv[k][3]) + "]";
                    first += "] vs " + dumps(rv);
                }
            }
        }
        size_t extra = 0;
        for (const auto &[id, vs] : mine) extra += !refIds.count(id);
        std::string note = std::to_string(matched) + " of " + std::to_string(ref.size()) + " match";
        if (missing) note += "; " + std::to_string(missing) + " missing";
        if (count) note += "; " + std::to_string(count) + " with another vertex count";
        if (off) note += "; " + std::to_string(off) + " off by more than the tolerance";
        if (extra) note += "; " + std::to_string(extra) + " for triangles the reference drops";
        if (!first.empty()) note += ". First: " + first;
        item(v, st, "polygons", r, std::to_string(mine.size()) + " polygons", matched == ref.size() && !extra, note);
        if (nearest < v.cam.nearZ * (1 - 1e-9)) nearPlaneHint(v, "a submitted polygon has a vertex at d = " + shortest(nearest) +
                                                                   ", nearer than the near plane " + shortest(v.cam.nearZ));
    }

    void nearPlaneHint(const KitView &v, const std::string &why) {
        hint(v, Stage::clip, "near_not_clipped",
             capitalize(why) + ". The near plane (d ≥ near) must always be clipped, in clip space "
             "before the divide, whenever a corner is behind it: a vertex with d < near, and above all one behind "
             "the eye (w ≤ 0), cannot be projected.");
    }

    void order(const KitView &v, const StageAnswer &a, const SJson *sub) {
        const Stage st = Stage::painter;
        const OJson &ref = a.answer["order"];
        const std::string r = std::to_string(ref.size()) + " ids";
        if (!sub || sub->is_null()) return item(v, st, "order", r, "missing", false, missingWhy);
        if (!sub->is_array()) return item(v, st, "order", r, "unreadable", false, "not an array of ids");
        std::vector<uint32_t> s;
        for (const SJson &x : *sub) {
            if (!x.is_number_unsigned() || x.get<uint64_t>() > UINT32_MAX)
                return item(v, st, "order", r, "unreadable", false, "not an id: " + dumps(x));
            s.push_back(x.get<uint32_t>());
        }
        auto list = [](const OJson &j) {
            std::vector<uint32_t> o;
            for (const OJson &x : j) o.push_back(x.get<uint32_t>());
            return o;
        };
        const std::vector<uint32_t> rv = list(ref);
        std::string note;
        if (s != rv) {
            size_t k = 0;
            while (k < s.size() && k < rv.size() && s[k] == rv[k]) ++k;
            note = "first difference at position " + std::to_string(k) + ": " +
                   (k < s.size() ? std::to_string(s[k]) : std::string("(end)")) + " vs " +
                   (k < rv.size() ? std::to_string(rv[k]) : std::string("(end)"));
        }
        item(v, st, "order", r, std::to_string(s.size()) + " ids", s == rv, note);
        if (s == rv || !a.extra.contains("orders")) return;
        // The order under another key, or the reference's reversed.
        const std::string own = painterKeyName(kit.painterKey);
        for (const auto &[key, o] : a.extra["orders"].items()) {
            if (key == own || list(o) != s) continue;
            const std::string what = key == "nearest_vertex" ? "its nearest vertex's depth" : key == "farthest_vertex" ? "its farthest vertex's depth" : "its centroid's depth";
            hint(v, st, "painter_key_" + (key == "nearest_vertex" ? std::string("nearest") : key == "farthest_vertex" ? std::string("farthest") : key),
                 "Your order sorts each triangle by " + what + " (" + key + "); this assignment's key "
                 "is " + own + (own == "centroid" ? ", the mean (d0 + d1 + d2) / 3 of its three corners' depths" : "") +
                 ". Sort by the key, the largest first; equal keys: the larger id first.");
            return;
        }
        std::vector<uint32_t> rev(rv.rbegin(), rv.rend());
        if (s == rev)
            hint(v, st, "painter_front_to_back",
                 "The painter draws the farthest triangle first (the largest key) so that nearer "
                 "ones overwrite it.");
    }

    // A per-pixel image of the submission against the reference's ids.
    void image(const KitView &v, Stage st, const std::string &which, const StageAnswer &a, const SJson *block,
               const ScreenTriangles &screen, const PixelGrade *idsGrade) {
        const std::string key = which;
        const std::string r = "all " + std::to_string(a.ids.size()) + " pixels";
        const SJson *name = block && block->contains(which) ? &(*block)[which] : nullptr;
        if (!name || name->is_null()) return item(v, st, key, r, "missing", false, missingWhy);
        if (!name->is_string() || name->get<std::string>().empty())
            return item(v, st, key, r, "unreadable", false, "expected the image's file name, got " + dumps(*name));
        const std::string file = name->get<std::string>();
        // A file of the submission folder (or below it): the grader reads nothing else.
        bool inside = !fs::path(file).is_absolute();
        for (const fs::path &part : fs::path(file)) inside = inside && part != "..";
        const fs::path path = fs::path(subDir) / file;
        if (!inside || !withinFolder(path, subDir))
            return item(v, st, key, r, "unreadable", false,
                        "'" + file + "' is not a file of the submission folder; name the image relative to it");
        Pixels px;
        std::string why;
        const bool depth = which == "depth";
        if (!readStudentImage(path.string(), file, depth, v.cam.width, v.cam.height, &px, &why) ||
            !checkValues(px, file, depth, &why))
            return item(v, st, key, r, "unreadable", false, why);
        const StageScreen ss(v, screen);
        PixelGrade pg;
        pg.view = v.name;
        pg.viewDir = v.dir;
        pg.stage = stageName(st);
        pg.image = which;
        pg.width = v.cam.width;
        pg.height = v.cam.height;
        if (depth) compareDepths(ss, a.ids, px, kitTolerance(tol, metric(st, "depth_values"), false), idsGrade, &pg);
        else compareIds(ss, a.ids, px, &pg);
        pg.gray = referenceGrays(ss, a.ids);
        const Tolerance t = kitTolerance(tol, metric(st, key), false);
        const double share = pg.share();
        std::string note = "edge " + std::to_string(pg.edge) + ", tie " + std::to_string(pg.tie) + ", genuine " +
                           std::to_string(pg.genuine);
        if (pg.unknownIds) note += " (" + std::to_string(pg.unknownIds) + " px show an id the input does not hold)";
        item(v, st, key, r, percent(share) + " agree", 1 - share <= t.abs, note);
        imageHints(v, st, pg, depth);
        g.images.push_back(std::move(pg));
    }

    void imageHints(const KitView &v, Stage st, const PixelGrade &pg, bool depth) {
        const uint64_t bad = pg.edge + pg.tie + pg.genuine;
        if (!bad) return;
        if (pg.edge > 0 && pg.tie == 0 && pg.genuine == 0)
            hint(v, st, "fill_rule",
                 "Every pixel that differs (" + std::to_string(pg.edge) + ") has its centre on an edge, so "
                 "the other triangle got it. This is the pattern of the top-left rule inverted (or of testing E ≥ 0 or "
                 "E > 0 on every edge): a centre exactly on an edge belongs to the triangle only when that edge is a "
                 "left edge (dy < 0) or a top edge (dy = 0, dx > 0).");
        if (pg.tie > 0 && pg.genuine == 0 && st == Stage::zbuffer)
            hint(v, st, "tie_rule",
                 "At " + std::to_string(pg.tie) + " pixels another triangle with the same stored depth shows. At "
                 "equal stored values the first drawn fragment must win: the test is LESS, not LESS_EQUAL, and "
                 "triangles are drawn in the input's order.");
        if (st == Stage::zbuffer && pg.comparedDepths > 0 && 10 * pg.fartherPixels >= 9 * pg.comparedDepths)
            hint(v, st, "depth_test_greater",
                 "At " + std::to_string(pg.fartherPixels) + " of the " + std::to_string(pg.comparedDepths) +
                 " pixels where a wrong surface shows, it is farther than the right one: the farthest surface wins, as "
                 "with a GREATER test. The nearer fragment must win: LESS on the stored value (for a format where "
                 "nearer is larger, the raw values compare the other way round)" +
                 ".");
    }

    void stage(const KitView &v, const StageAnswer &a, const SJson *block) {
        const Stage st = a.stage;
        const std::string saved = missingWhy;
        if (!missingWhy.empty()) {
            // the submission or the view is missing as a whole: that is the reason
        } else if (!block) {
            missingWhy = "no \"" + std::string(stageName(st)) + "\" block for view '" + v.name + "' in submission.json";
        } else if (!block->is_object()) {
            missingWhy = "views." + v.name + "." + stageName(st) + " is " + dumps(*block).substr(0, 40) + ", not an object";
            block = nullptr;
        }
        auto sub = [&](const std::string &k) -> const SJson * {
            return block && block->contains(k) ? &(*block)[k] : nullptr;
        };
        for (auto it = a.answer.begin(); it != a.answer.end(); ++it) {
            const std::string &k = it.key();
            const OJson &ref = it.value();
            if (k == "kept") kept(v, a, sub(k));
            else if (k == "polygons") polygons(v, a, sub(k));
            else if (k == "order") order(v, a, sub(k));
            else if (k == "histogram") histogram(v, st, ref, sub(k));
            else if (ref.is_object()) {
                const SJson *o = sub(k);
                for (auto jt = ref.begin(); jt != ref.end(); ++jt) {
                    const SJson *x = o && o->is_object() && o->contains(jt.key()) ? &(*o)[jt.key()] : nullptr;
                    number(v, st, k + "." + jt.key(), jt.value(), x);
                }
            } else {
                number(v, st, k, ref, sub(k));
            }
        }
        if (st == Stage::clip) {
            const SJson *pp = sub("per_plane");
            const SJson *near = pp && pp->is_object() && pp->contains("near") ? &(*pp)["near"] : nullptr;
            if (near && near->is_number() && near->get<double>() == 0 && a.answer["per_plane"]["near"].get<uint64_t>() > 0)
                nearPlaneHint(v, "per_plane.near is 0 where " + dumps(a.answer["per_plane"]["near"]) +
                                     " triangles cross the near plane");
        }
        if (st == Stage::zbuffer) {
            const size_t before = g.images.size();
            const bool hasIds = std::find(kit.images.begin(), kit.images.end(), "ids") != kit.images.end();
            if (hasIds) image(v, st, "ids", a, block, v.zbuffer->triangles, nullptr);
            const PixelGrade *ids = hasIds && g.images.size() > before ? &g.images.back() : nullptr;
            if (std::find(kit.images.begin(), kit.images.end(), "depth") != kit.images.end())
                image(v, st, "depth", a, block, v.zbuffer->triangles, ids);
        } else if (st == Stage::painter) {
            image(v, st, "ids", a, block, v.painter->screen, nullptr);
        }
        missingWhy = saved;
    }
};

}  // namespace

KitGrade gradeSubmission(const Kit &kit, const AnswerSet &answers, const ToleranceRules &tol, const std::string &dir,
                         uint64_t maxJsonDepth) {
    KitGrade g;
    g.dir = dir;
    g.student = fs::path(dir).filename().string();
    if (g.student.empty()) g.student = fs::path(dir).parent_path().filename().string();
    Grader gr{kit, answers, tol, g, dir, ""};

    // The submission document: an error here is graded (every item fails with it), never fatal.
    const std::string file = (fs::path(dir) / "submission.json").string();
    json::Doc doc;
    std::string err;
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) g.error = dir + ": not a folder (a submission is a folder holding submission.json)";
    else if (fs::exists(file, ec) && !withinFolder(file, dir))
        g.error = file + ": a link to a file outside the submission folder; hand in the file itself";
    else if (!json::parseFile(file, &doc, &err, maxJsonDepth)) g.error = err;
    else if (!doc.root.is_object() || !doc.root.contains("format") || doc.root["format"] != kSubmissionFormat)
        g.error = json::where(doc, json::Path{} / "format") + ": \"format\" must be \"" + kSubmissionFormat +
                  "\" (start from the kit's template/submission.json)";
    else if (!doc.root.contains("views") || !doc.root["views"].is_object())
        g.error = json::where(doc, json::Path{} / "views") + ": expected \"views\": {\"VIEW\": {...}} as in the kit's "
                  "template/submission.json";
    const SJson &root = doc.root;
    gr.missingWhy = g.error;

    for (size_t vi = 0; vi < kit.views.size(); ++vi) {
        const KitView &v = kit.views[vi];
        const SJson *vb = nullptr;
        std::string saved = gr.missingWhy;
        if (g.error.empty()) {
            if (root["views"].contains(v.name)) vb = &root["views"][v.name];
            else gr.missingWhy = "no view '" + v.name + "' in submission.json";
            if (vb && !vb->is_object()) {
                gr.missingWhy = "views." + v.name + " is not an object";
                vb = nullptr;
            }
        }
        for (size_t si = 0; si < kit.stages.size(); ++si) {
            const StageAnswer &a = answers.views[vi][si];
            const SJson *block = vb && vb->contains(stageName(a.stage)) ? &(*vb)[stageName(a.stage)] : nullptr;
            gr.stage(v, a, vb ? block : nullptr);
        }
        gr.missingWhy = saved;
    }
    for (Stage st : kit.stages) {
        StageScore s;
        s.stage = stageName(st);
        for (const GradeItem &it : g.items)
            if (it.stage == s.stage) ++s.total, s.passed += it.pass;
        s.score = s.total ? double(s.passed) / double(s.total) : 0;
        g.stages.push_back(s);
    }
    double sum = 0;
    for (const StageScore &s : g.stages) sum += s.score;
    g.score = g.stages.empty() ? 0 : sum / double(g.stages.size());
    for (const GradeItem &it : g.items) (it.pass ? g.passed : g.failed)++;
    return g;
}

// ---- Outputs ------------------------------------------------------------------------------------

OJson kitGradeJson(const KitGrade &g) {
    OJson j;
    j["format"] = "visaudit-grade/2";
    j["student"] = g.student;
    if (!g.error.empty()) j["error"] = g.error;
    j["score"] = g.score;
    j["passed"] = g.passed;
    j["failed"] = g.failed;
    OJson stages = OJson::array();
    for (const StageScore &s : g.stages)
        stages.push_back({{"stage", s.stage}, {"score", s.score}, {"passed", s.passed}, {"total", s.total}});
    j["stages"] = stages;
    OJson hints = OJson::array();
    for (const GradeHint &h : g.hints)
        hints.push_back({{"id", h.id}, {"view", h.view}, {"stage", h.stage}, {"title", h.title}, {"text", h.text}});
    j["hints"] = hints;
    OJson images = OJson::array();
    for (const PixelGrade &p : g.images) {
        OJson im{{"view", p.view}, {"stage", p.stage}, {"image", p.image}, {"pixels", p.pixels}, {"agree", p.agree},
                 {"edge", p.edge}, {"tie", p.tie}, {"genuine", p.genuine}, {"share", p.share()}};
        if (!p.diffFile.empty()) im["diff"] = p.diffFile;
        images.push_back(im);
    }
    j["images"] = images;
    OJson items = OJson::array();
    for (const GradeItem &it : g.items) {
        OJson x{{"view", it.view}, {"stage", it.stage}, {"key", it.key}, {"reference", it.reference},
                {"submitted", it.submitted}, {"pass", it.pass}};
        if (!it.note.empty()) x["note"] = it.note;
        items.push_back(x);
    }
    j["items"] = items;
    return j;
}

std::string kitGradeTable(const KitGrade &g) {
    std::ostringstream s;
    char line[512];
    std::snprintf(line, sizeof line, "%-20s %-10s %8s %8s\n", "view", "stage", "passed", "of");
    s << line;
    std::vector<std::pair<std::string, std::string>> order;
    std::map<std::pair<std::string, std::string>, std::pair<int, int>> counts;
    for (const GradeItem &it : g.items) {
        const auto k = std::make_pair(it.view, it.stage);
        if (!counts.count(k)) order.push_back(k);
        counts[k].first += it.pass;
        counts[k].second += 1;
    }
    for (const auto &k : order) {
        std::snprintf(line, sizeof line, "%-20s %-10s %8d %8d\n", k.first.c_str(), k.second.c_str(), counts[k].first,
                      counts[k].second);
        s << line;
    }
    if (!g.error.empty()) s << "submission: " << g.error << "\n";
    for (const GradeItem &it : g.items)
        if (!it.pass && g.error.empty())
            s << "FAIL " << it.view << " " << it.stage << "." << it.key << ": submitted " << it.submitted << ", reference "
              << it.reference << (it.note.empty() ? "" : " (" + it.note + ")") << "\n";
    for (const GradeHint &h : g.hints) s << "HINT " << h.view << " " << h.stage << ": " << h.text << "\n";
    for (const StageScore &st : g.stages) {
        std::snprintf(line, sizeof line, "%s %.1f%% (%zu of %zu)\n", st.stage.c_str(), 100 * st.score, st.passed, st.total);
        s << line;
    }
    std::snprintf(line, sizeof line, "score %.1f%% (the mean of the stage scores)\n", 100 * g.score);
    s << line;
    return s.str();
}

bool writeGradeImages(KitGrade &g, const std::string &dir, std::string *err) {
    for (PixelGrade &p : g.images) {
        const int W = p.width, H = p.height;
        const size_t n = size_t(W) * size_t(H);
        std::vector<uint8_t> img(n * 3);
        for (size_t i = 0; i < n; ++i) {
            const Disagreement d = Disagreement(p.cls[i]);
            Rgb8 c;
            if (d == Disagreement::none) {
                const uint8_t v = uint8_t(p.gray[i] / 4);
                c = {v, v, v};
            } else {
                c = d == Disagreement::edge ? Rgb8{64, 128, 255} : d == Disagreement::tie ? Rgb8{255, 220, 0} : Rgb8{255, 0, 0};
            }
            img[3 * i] = c.r, img[3 * i + 1] = c.g, img[3 * i + 2] = c.b;
        }
        const std::vector<LegendEntry> legend = {{{64, 128, 255}, "edge " + std::to_string(p.edge)},
                                                 {{255, 220, 0}, "tie " + std::to_string(p.tie)},
                                                 {{255, 0, 0}, "genuine " + std::to_string(p.genuine)}};
        // A small view is enlarged by a whole factor (each pixel a square of them) to at least 256
        // pixels wide, so its pixels and the legend's counts stay legible.
        const int k = std::clamp((256 + W - 1) / std::max(W, 1), 1, 8);
        std::vector<uint8_t> big = img;
        if (k > 1) {
            big.assign(size_t(W * k) * size_t(H * k) * 3, 0);
            for (int y = 0; y < H * k; ++y)
                for (int x = 0; x < W * k; ++x)
                    for (int c = 0; c < 3; ++c)
                        big[(size_t(y) * size_t(W * k) + size_t(x)) * 3 + size_t(c)] =
                            img[(size_t(y / k) * size_t(W) + size_t(x / k)) * 3 + size_t(c)];
        }
        int CH = 0;
        const std::vector<uint8_t> rgb = withLegend(big, W * k, H * k, legend, &CH);
        p.diffFile = p.viewDir + "." + p.stage + "." + p.image + ".diff.png";
        p.diffWidth = W * k;
        if (!writePngRgb8((fs::path(dir) / p.diffFile).string(), W * k, CH, rgb.data(), err)) return false;
        std::vector<uint8_t>().swap(p.cls);
        std::vector<uint8_t>().swap(p.gray);
    }
    return true;
}

// ---- A class ------------------------------------------------------------------------------------

namespace {
std::string csvField(const std::string &s) {
    if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
    std::string o = "\"";
    for (char c : s) o += c == '"' ? std::string("\"\"") : std::string(1, c);
    return o + "\"";
}
std::string pct(double share) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.2f", 100 * share);
    return buf;
}
}  // namespace

std::string gradesCsv(const std::vector<KitGrade> &grades, const Kit &kit) {
    std::string o = "student,score";
    for (Stage st : kit.stages) o += std::string(",") + stageName(st);
    o += ",passed,failed,failures,hints,error\n";
    for (const KitGrade &g : grades) {
        o += csvField(g.student) + "," + pct(g.score);
        for (const StageScore &s : g.stages) o += "," + pct(s.score);
        std::string failures, hints;
        for (const GradeItem &it : g.items)
            if (!it.pass) failures += (failures.empty() ? "" : "; ") + it.view + " " + it.stage + "." + it.key;
        std::set<std::string> said;  // a mistake in two stages of a view (the rasterizer's fill rule) once
        for (const GradeHint &h : g.hints)
            if (said.insert(h.view + " " + h.id).second) hints += (hints.empty() ? "" : "; ") + h.view + " " + h.id;
        o += "," + std::to_string(g.passed) + "," + std::to_string(g.failed) + "," + csvField(failures) + "," +
             csvField(hints) + "," + csvField(g.error) + "\n";
    }
    return o;
}

OJson classSummary(const std::vector<KitGrade> &grades, const Kit &kit) {
    OJson j;
    j["format"] = "visaudit-class/1";
    j["submissions"] = grades.size();
    size_t unreadable = 0, perfect = 0;
    double sum = 0;
    for (const KitGrade &g : grades) {
        unreadable += !g.error.empty();
        perfect += g.failed == 0 && !g.items.empty();
        sum += g.score;
    }
    j["unreadable"] = unreadable;
    j["full_marks"] = perfect;
    j["mean_score"] = grades.empty() ? 0.0 : sum / double(grades.size());
    OJson stages;
    for (size_t k = 0; k < kit.stages.size(); ++k) {
        double s = 0;
        for (const KitGrade &g : grades) s += k < g.stages.size() ? g.stages[k].score : 0;
        stages[stageName(kit.stages[k])] = grades.empty() ? 0.0 : s / double(grades.size());
    }
    j["mean_stage_scores"] = stages;
    // Checks by how many students fail them (most first; ties in the grade's own order).
    std::vector<std::string> order;
    std::map<std::string, size_t> failed;
    for (const KitGrade &g : grades)
        for (const GradeItem &it : g.items) {
            const std::string name = it.view + " " + it.stage + "." + it.key;
            if (!failed.count(name)) order.push_back(name), failed[name] = 0;
            failed[name] += !it.pass;
        }
    std::stable_sort(order.begin(), order.end(), [&](const std::string &a, const std::string &b) { return failed[a] > failed[b]; });
    OJson checks = OJson::array();
    for (const std::string &c : order)
        if (failed[c] > 0) checks.push_back({{"check", c}, {"failed", failed[c]}, {"of", grades.size()}});
    j["checks_failed"] = checks;
    std::vector<std::string> hintOrder;
    std::map<std::string, std::set<size_t>> hinted;
    for (size_t i = 0; i < grades.size(); ++i)
        for (const GradeHint &h : grades[i].hints) {
            if (!hinted.count(h.id)) hintOrder.push_back(h.id);
            hinted[h.id].insert(i);
        }
    std::stable_sort(hintOrder.begin(), hintOrder.end(),
                     [&](const std::string &a, const std::string &b) { return hinted[a].size() > hinted[b].size(); });
    OJson hints = OJson::array();
    for (const std::string &h : hintOrder) hints.push_back({{"hint", h}, {"students", hinted[h].size()}});
    j["hints"] = hints;
    return j;
}

std::string classTable(const OJson &s) {
    std::ostringstream o;
    char line[512];
    std::snprintf(line, sizeof line, "%zu submissions, mean score %.1f%%, %zu with full marks, %zu unreadable\n",
                  s["submissions"].get<size_t>(), 100 * s["mean_score"].get<double>(), s["full_marks"].get<size_t>(),
                  s["unreadable"].get<size_t>());
    o << line;
    for (const auto &[stage, score] : s["mean_stage_scores"].items()) {
        std::snprintf(line, sizeof line, "  %-10s mean %.1f%%\n", stage.c_str(), 100 * score.get<double>());
        o << line;
    }
    size_t shown = 0;
    for (const OJson &c : s["checks_failed"]) {
        if (shown++ == 0) o << "checks most students fail:\n";
        if (shown > 10) break;
        std::snprintf(line, sizeof line, "  %4zu of %zu  %s\n", c["failed"].get<size_t>(), c["of"].get<size_t>(),
                      c["check"].get<std::string>().c_str());
        o << line;
    }
    for (const OJson &h : s["hints"]) {
        std::snprintf(line, sizeof line, "  hint %-22s %zu students\n", h["hint"].get<std::string>().c_str(),
                      h["students"].get<size_t>());
        o << line;
    }
    return o.str();
}

}  // namespace va::kit
