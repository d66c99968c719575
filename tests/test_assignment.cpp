// Assignment kits and kit grading (analysis/kit.h, reports/kit_grade.h, docs/grading.md).
//
// The submissions here are made by small student implementations written in this file from the
// kit's conventions alone (CONVENTIONS.md): each reads the kit's input files as a student would
// (plain JSON), computes its stage, and writes submission.json and its images. A correct student
// scores 100%; each deliberately wrong one -- a z-buffer with GREATER or LESS_EQUAL, a rasterizer
// with the fill rule inverted, a clipper that skips the near plane, backface culling with the
// winding reversed, painter's with the nearest-vertex key -- fails exactly the checks its mistake
// touches, with the hint that names it, and never a check of another stage.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "analysis/kit.h"
#include "analysis/load/demo.h"
#include "analysis/pipeline.h"
#include "reports/kit_grade.h"
#include "reports/report.h"
#include "tests/image_files.h"
#include "tests/run_binary.h"
#include "tests/temp_dir_test.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace va {
namespace {

// ---- The kit ------------------------------------------------------------------------------------

// Two views of the built-in demo: "spawn" (perspective; the wall beside the camera crosses the near
// plane, the decal is coplanar with the floor) and "top" (orthographic, straight down on the floor,
// whose 32 x 32 quads of 1.25 units land on 2 x 2 pixels: every quad's diagonal passes exactly
// through two pixel centres, where only the fill rule decides who covers them).
std::vector<ViewSpec> kitViews() {
    ViewSpec spawn;
    spawn.name = "spawn";
    spawn.camera.eye = {0, 1.7, 12};
    spawn.camera.target = {0, 1, 0};
    spawn.camera.nearZ = 0.1;
    spawn.camera.farZ = 200;
    spawn.camera.width = 96;
    spawn.camera.height = 54;
    ViewSpec top;
    top.name = "top";
    top.camera.eye = {0, 10, 0};
    top.camera.target = {0, 0, 0};
    top.camera.up = {0, 0, -1};
    top.camera.orthographic = true;
    top.camera.orthoHeight = 40;
    top.camera.nearZ = 0.5;
    top.camera.farZ = 20;
    top.camera.width = 64;
    top.camera.height = 64;
    top.depthFormat = DepthFormat::unorm24;
    return {spawn, top};
}

void writeFiles(const fs::path &root, const std::vector<std::pair<std::string, std::string>> &files) {
    for (const auto &[rel, text] : files) {
        fs::create_directories((root / rel).parent_path());
        std::ofstream(root / rel, std::ios::binary) << text;
    }
}

// The kit and answers folders, made once for the whole suite (in-process, as the command does).
struct KitOnDisk {
    fs::path root, kit, answers;
    kit::KitFiles files;
};
const KitOnDisk &demoKit() {
    static const KitOnDisk k = [] {
        KitOnDisk d;
        d.root = fs::temp_directory_path() / ("visaudit-assignment-" + std::to_string(getpid()));
        fs::remove_all(d.root);
        d.kit = d.root / "kit";
        d.answers = d.root / "answers";
        const Scene scene = demoScene();
        std::string err;
        const std::vector<ViewSpec> views = kitViews();
        EXPECT_TRUE(kit::buildKit(scene, views, imageBaseNames(views), PipelineSettings{}, kit::KitSettings{}, "demo",
                                  &d.files, &err))
            << err;
        writeFiles(d.kit, d.files.kit);
        writeFiles(d.answers, d.files.answers);
        for (const auto &im : d.files.answerImages)
            EXPECT_TRUE(writeExrUint32((d.answers / im.path).string(), im.width, im.height, im.ids.data(), "id", &err)) << err;
        return d;
    }();
    return k;
}

// Removes the suite's kit folder when the test program ends.
struct KitCleanup : ::testing::Environment {
    void TearDown() override {
        std::error_code ec;
        fs::remove_all(fs::temp_directory_path() / ("visaudit-assignment-" + std::to_string(getpid())), ec);
    }
};
[[maybe_unused]] ::testing::Environment *const kCleanup = ::testing::AddGlobalTestEnvironment(new KitCleanup);

json readJson(const fs::path &p) {
    std::ifstream f(p);
    std::stringstream s;
    s << f.rdbuf();
    return json::parse(s.str());
}
Vec3 vec(const json &j) { return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()}; }

// ---- Student implementations, from CONVENTIONS.md ---------------------------------------------

struct Mistakes {
    bool reverseWinding = false;  // backface: keeps the faces turned away
    bool skipNear = false;        // clip: never clips against the near plane
    bool greater = false;         // zbuffer: the farthest fragment wins
    bool lessEqual = false;       // zbuffer: at equal stored depth the last drawn wins
    bool invertFill = false;      // zbuffer, painter: bottom-right instead of top-left
    std::string painterKey = "centroid";
};

json studentBackface(const json &in, const Mistakes &m) {
    const bool ortho = in["projection"] == "orthographic";
    const Vec3 eye = vec(in["eye"]), f = vec(in["forward"]);
    uint64_t tested = 0, culled = 0, exempt = 0, edgeOn = 0;
    json kept = json::array();
    for (const json &t : in["triangles"]) {
        if (t["double_sided"].get<bool>()) {
            ++exempt;
            kept.push_back(t["id"]);
            continue;
        }
        ++tested;
        const Vec3 v0 = vec(t["v"][0]), v1 = vec(t["v"][1]), v2 = vec(t["v"][2]);
        const Vec3 n = cross(v1 - v0, v2 - v0);
        bool front;
        if (ortho) {
            const double s = -dot(n, f);
            const double err = gamma(4) * (std::fabs(n.x * f.x) + std::fabs(n.y * f.y) + std::fabs(n.z * f.z));
            front = m.reverseWinding ? s < err : s > -err;
            edgeOn += !front && s == 0;
        } else {
            const double s = dot(n, eye) + -dot(n, v0);
            front = m.reverseWinding ? s < 0 : s > 0;
            edgeOn += s == 0;
        }
        if (front) kept.push_back(t["id"]);
        else ++culled;
    }
    return {{"triangles_in", in["triangles"].size()}, {"triangles_tested", tested}, {"triangles_culled", culled},
            {"double_sided_exempt", exempt},          {"edge_on", edgeOn},          {"triangles_out", kept.size()},
            {"kept", kept}};
}

struct CV {
    double x, y, w, d;
};

json studentClip(const json &in, const Mistakes &m) {
    const bool ortho = in["projection"] == "orthographic";
    const double W = in["width"], H = in["height"], nearZ = in["near"], farZ = in["far"], sx = in["sx"], sy = in["sy"],
                 G = in["guard_band_px"];
    const double gx = 1 + G / (W / 2), gy = 1 + G / (H / 2);
    uint64_t rejected = 0, inside = 0, guard = 0, clipped = 0, away = 0, edgeOn = 0, out = 0;
    uint64_t perPlane[6] = {}, verts[10] = {};
    auto dist = [&](const CV &v, int p) {
        switch (p) {
        case 0: return v.d - nearZ;
        case 1: return farZ - v.d;
        case 2: return v.x + gx * v.w;
        case 3: return gx * v.w - v.x;
        case 4: return v.y + gy * v.w;
        default: return gy * v.w - v.y;
        }
    };
    json polygons = json::array();
    for (const json &t : in["triangles"]) {
        Vec3 v[3];
        CV c[3];
        unsigned frustum[3], guardOut[3];
        for (int k = 0; k < 3; ++k) {
            v[k] = vec(t["v"][k]);
            const double d = -v[k].z;
            c[k] = {sx * v[k].x, sy * v[k].y, ortho ? 1.0 : d, d};
            frustum[k] = (c[k].d < nearZ) | (c[k].d > farZ) << 1 | (c[k].x < -c[k].w) << 2 | (c[k].x > c[k].w) << 3 |
                         (c[k].y < -c[k].w) << 4 | (c[k].y > c[k].w) << 5;
            guardOut[k] = (c[k].d < nearZ) | (c[k].d > farZ) << 1 | (c[k].x < -gx * c[k].w) << 2 |
                          (c[k].x > gx * c[k].w) << 3 | (c[k].y < -gy * c[k].w) << 4 | (c[k].y > gy * c[k].w) << 5;
        }
        if (frustum[0] & frustum[1] & frustum[2]) {
            ++rejected;
            continue;
        }
        const Vec3 n = cross(v[1] - v[0], v[2] - v[0]);
        if (ortho ? n.z == 0 : dot(n, v[0]) == 0) {
            ++edgeOn;
            continue;
        }
        unsigned need = guardOut[0] | guardOut[1] | guardOut[2];
        if (m.skipNear) need &= ~1u;
        std::vector<CV> poly(c, c + 3);
        if (!need) {
            ((frustum[0] | frustum[1] | frustum[2]) ? guard : inside)++;
        } else {
            ++clipped;
            for (int p = 0; p < 6 && poly.size() >= 3; ++p) {
                if (!(need >> p & 1)) continue;
                ++perPlane[p];
                std::vector<CV> next;
                for (size_t i = 0; i < poly.size(); ++i) {
                    const CV &a = poly[i], &b = poly[(i + 1) % poly.size()];
                    const double da = dist(a, p), db = dist(b, p);
                    if (da >= 0) next.push_back(a);
                    if ((da >= 0) != (db >= 0)) {
                        const CV &pi = da >= 0 ? a : b, &qo = da >= 0 ? b : a;
                        const double dp = da >= 0 ? da : db, dq = da >= 0 ? db : da;
                        const double s = dp / (dp - dq);
                        next.push_back({pi.x + s * (qo.x - pi.x), pi.y + s * (qo.y - pi.y), pi.w + s * (qo.w - pi.w),
                                        pi.d + s * (qo.d - pi.d)});
                    }
                }
                poly = std::move(next);
            }
            if (poly.size() < 3) {
                ++away;
                continue;
            }
            ++verts[std::min<size_t>(poly.size(), 9)];
        }
        out += poly.size() - 2;
        json vs = json::array();
        for (const CV &p : poly) vs.push_back({p.x, p.y, p.w, p.d});
        polygons.push_back({{"id", t["id"]}, {"vertices", vs}});
    }
    const char *names[6] = {"near", "far", "left", "right", "bottom", "top"};
    json pp, pv;
    for (int p = 0; p < 6; ++p) pp[names[p]] = perPlane[p];
    for (int k = 3; k <= 9; ++k) pv[k == 9 ? "9+" : std::to_string(k)] = verts[k];
    return {{"triangles_in", in["triangles"].size()},
            {"trivially_rejected", rejected},
            {"inside", inside},
            {"guard_band_accepted", guard},
            {"clipped", clipped},
            {"clipped_away", away},
            {"edge_on", edgeOn},
            {"per_plane", pp},
            {"polygon_vertices", pv},
            {"triangles_out", out},
            {"polygons", polygons}};
}

int64_t floorDiv(int64_t a, int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

// Calls frag(x, y) for every pixel centre the fixed-point triangle covers; false when its area is 0.
// *front: counter-clockwise as the viewer sees it (negative area in y-down coordinates).
template <class Frag>
bool cover(const json &xy, int W, int H, bool invertFill, bool *front, Frag &&frag) {
    int64_t x[3], y[3];
    for (int k = 0; k < 3; ++k) x[k] = xy[2 * k].get<int64_t>(), y[k] = xy[2 * k + 1].get<int64_t>();
    const int64_t area = (x[1] - x[0]) * (y[2] - y[0]) - (y[1] - y[0]) * (x[2] - x[0]);
    *front = area < 0;
    if (area == 0) return false;
    if (area < 0) std::swap(x[1], x[2]), std::swap(y[1], y[2]);
    const int64_t minX = std::min({x[0], x[1], x[2]}), maxX = std::max({x[0], x[1], x[2]});
    const int64_t minY = std::min({y[0], y[1], y[2]}), maxY = std::max({y[0], y[1], y[2]});
    const int64_t bx0 = std::max<int64_t>(0, floorDiv(minX - 128 + 255, 256)), bx1 = std::min<int64_t>(W - 1, floorDiv(maxX - 128, 256));
    const int64_t by0 = std::max<int64_t>(0, floorDiv(minY - 128 + 255, 256)), by1 = std::min<int64_t>(H - 1, floorDiv(maxY - 128, 256));
    const int a[3] = {1, 2, 0}, b[3] = {2, 0, 1};
    for (int64_t py = by0; py <= by1; ++py)
        for (int64_t px = bx0; px <= bx1; ++px) {
            const int64_t cx = 256 * px + 128, cy = 256 * py + 128;
            bool in = true;
            for (int k = 0; k < 3 && in; ++k) {
                const int64_t dx = x[b[k]] - x[a[k]], dy = y[b[k]] - y[a[k]];
                const int64_t e = dx * (cy - y[a[k]]) - dy * (cx - x[a[k]]);
                const bool topLeft = dy < 0 || (dy == 0 && dx > 0);
                in = e > 0 || (e == 0 && (invertFill ? !topLeft : topLeft));
            }
            if (in) frag(int(px), int(py));
        }
    return true;
}

void writeGray16(const fs::path &p, int W, int H, const std::vector<uint32_t> &ids) {
    std::vector<uint16_t> v(ids.begin(), ids.end());
    ASSERT_TRUE(va::test::writePngFile(p.string(), W, H, 1, 16, v.data())) << p;
}
// A PFM: "Pf", the size, -1 (little-endian), then the rows from the bottom one up.
void writePfm(const fs::path &p, int W, int H, const std::vector<float> &v) {
    std::ofstream f(p, std::ios::binary);
    f << "Pf\n" << W << " " << H << "\n-1.0\n";
    for (int row = H - 1; row >= 0; --row) f.write(reinterpret_cast<const char *>(&v[size_t(row) * size_t(W)]), 4 * W);
}

json studentZBuffer(const json &in, const Mistakes &m, const fs::path &dir, const std::string &base) {
    const int W = in["width"], H = in["height"];
    const bool ortho = in["projection"] == "orthographic";
    DepthFormatSpec format;
    std::string err;
    EXPECT_TRUE(parseDepthFormat(in["depth_format"].get<std::string>(), &format, &err));
    const DepthEncoder enc = makeDepthEncoder(format, in["near"], in["far"]);
    const size_t n = size_t(W) * size_t(H);
    std::vector<uint32_t> key(n, m.greater ? 0u : UINT32_MAX), id(n, 0), frags(n, 0);
    std::vector<float> depth(n, INFINITY);
    uint64_t drawn = 0, empty = 0, fragments = 0, passes = 0, oor = 0;
    for (const json &t : in["triangles"]) {
        const double a = t["plane"][0], b = t["plane"][1], c = t["plane"][2];
        const uint32_t ident = t["id"].get<uint32_t>() + 1;
        uint64_t covered = 0;
        bool front;
        cover(t["xy"], W, H, m.invertFill, &front, [&](int x, int y) {
            const size_t p = size_t(y) * size_t(W) + size_t(x);
            ++covered, ++fragments, ++frags[p];
            const double v = (a * (x + 0.5) + b * (y + 0.5)) + c;
            const double d = ortho ? v : 1 / v;
            bool out = false;
            const uint32_t k = depthKey(enc, d, &out);
            oor += out;
            const bool pass = m.greater ? k > key[p] : m.lessEqual ? k <= key[p] : k < key[p];
            if (pass) key[p] = k, id[p] = ident, depth[p] = float(d), ++passes;
        });
        (covered ? drawn : empty)++;
    }
    uint64_t coveredPixels = 0, maxC = 0;
    std::vector<uint64_t> hist(1, 0);
    for (uint32_t f : frags) {
        if (f >= hist.size()) hist.resize(f + 1, 0);
        ++hist[f];
        coveredPixels += f > 0;
        maxC = std::max<uint64_t>(maxC, f);
    }
    writeGray16(dir / (base + ".ids.png"), W, H, id);
    writePfm(dir / (base + ".depth.pfm"), W, H, depth);
    return {{"triangles_in", in["triangles"].size()},
            {"triangles_drawn", drawn},
            {"triangles_empty", empty},
            {"fragments", fragments},
            {"depth_passes", passes},
            {"out_of_range_fragments", oor},
            {"covered_pixels", coveredPixels},
            {"overdraw", double(passes) / double(coveredPixels)},
            {"depth_complexity", double(fragments) / double(coveredPixels)},
            {"max_depth_complexity", maxC},
            {"histogram", hist},
            {"ids", base + ".ids.png"},
            {"depth", base + ".depth.pfm"}};
}

json studentPainter(const json &in, const Mistakes &m, const fs::path &dir, const std::string &base) {
    const int W = in["width"], H = in["height"];
    std::vector<std::pair<double, uint32_t>> keyed;
    std::map<uint32_t, const json *> byId;
    for (const json &t : in["triangles"]) {
        const double d0 = t["depths"][0], d1 = t["depths"][1], d2 = t["depths"][2];
        const double k = m.painterKey == "nearest_vertex" ? std::min({d0, d1, d2}) : (d0 + d1 + d2) / 3;
        keyed.push_back({k, t["id"].get<uint32_t>()});
        byId[t["id"].get<uint32_t>()] = &t;
    }
    std::sort(keyed.begin(), keyed.end(),
              [](const auto &a, const auto &b) { return a.first > b.first || (a.first == b.first && a.second > b.second); });
    std::vector<uint32_t> id(size_t(W) * size_t(H), 0);
    uint64_t fragments = 0;
    json order = json::array();
    for (const auto &[k, ident] : keyed) {
        order.push_back(ident);
        const json &t = *byId[ident];
        for (const json &xy : t["screen"]) {
            bool front;
            bool drawIt = true;
            // The winding first: a single-sided triangle seen from behind is not drawn.
            cover(xy, W, H, m.invertFill, &front, [](int, int) {});
            if (t["single_sided"].get<bool>() && !front) drawIt = false;
            if (!drawIt) continue;
            cover(xy, W, H, m.invertFill, &front, [&](int x, int y) {
                id[size_t(y) * size_t(W) + size_t(x)] = ident + 1;
                ++fragments;
            });
        }
    }
    uint64_t covered = 0;
    for (uint32_t v : id) covered += v != 0;
    writeGray16(dir / (base + ".painter.png"), W, H, id);
    return {{"triangles_drawn", keyed.size()}, {"fragments", fragments}, {"covered_pixels", covered},
            {"overdraw", double(fragments) / double(covered)}, {"order", order}, {"ids", base + ".painter.png"}};
}

// A student's whole submission for the kit, into `dir`.
void writeSubmission(const fs::path &kitDir, const fs::path &dir, const Mistakes &m) {
    fs::create_directories(dir);
    const json a = readJson(kitDir / "assignment.json");
    json views;
    for (const json &v : a["views"]) {
        const std::string vd = v["dir"];
        const fs::path in = kitDir / "views" / vd;
        json block;
        block["backface"] = studentBackface(readJson(in / "backface.json"), m);
        block["clip"] = studentClip(readJson(in / "clip.json"), m);
        block["zbuffer"] = studentZBuffer(readJson(in / "zbuffer.json"), m, dir, vd);
        block["painter"] = studentPainter(readJson(in / "painter.json"), m, dir, vd);
        views[v["name"].get<std::string>()] = block;
    }
    std::ofstream(dir / "submission.json") << json{{"format", "visaudit-submission/1"}, {"student", dir.filename()},
                                                   {"views", views}}
                                                  .dump(1);
}

// ---- Grading helpers ----------------------------------------------------------------------------

struct Loaded {
    kit::Kit kit;
    kit::AnswerSet answers;
};
const Loaded &loaded() {
    static const Loaded l = [] {
        Loaded x;
        std::string err;
        EXPECT_TRUE(kit::readKit(demoKit().kit.string(), &x.kit, &err)) << err;
        EXPECT_TRUE(kit::readAnswers(demoKit().answers.string(), x.kit, &x.answers, &err)) << err;
        return x;
    }();
    return l;
}

kit::KitGrade grade(const fs::path &dir, const ToleranceRules &tol = {}) {
    return kit::gradeSubmission(loaded().kit, loaded().answers, tol, dir.string());
}

std::vector<std::string> failures(const kit::KitGrade &g) {
    std::vector<std::string> f;
    for (const GradeItem &it : g.items)
        if (!it.pass) f.push_back(it.view + " " + it.stage + "." + it.key);
    return f;
}
std::set<std::string> hintIds(const kit::KitGrade &g) {
    std::set<std::string> h;
    for (const kit::GradeHint &x : g.hints) h.insert(x.view + " " + x.id);
    return h;
}
size_t itemsOf(const kit::KitGrade &g, const std::string &stage) {
    size_t n = 0;
    for (const GradeItem &it : g.items) n += it.stage == stage;
    return n;
}
class Assignment : public testing_util::TempDirTest {
  protected:
    Assignment() : TempDirTest("assignment") {}
    // A submission by a student making `m`, graded (VISAUDIT_PRINT_GRADES=1 prints each grade's table).
    kit::KitGrade submit(const std::string &name, const Mistakes &m) {
        writeSubmission(demoKit().kit, dir_ / name, m);
        kit::KitGrade g = grade(dir_ / name);
        if (std::getenv("VISAUDIT_PRINT_GRADES")) std::printf("== %s\n%s", name.c_str(), kit::kitGradeTable(g).c_str());
        return g;
    }
};

std::string describe(const kit::KitGrade &g) {
    std::string s = kit::kitGradeTable(g);
    return s.size() > 6000 ? s.substr(0, 6000) : s;
}

// ---- Tests --------------------------------------------------------------------------------------

// Every stage's input written to the kit and read back from its files gives, through the
// project's own stage functions, answers identical to the ones in the answers folder (their
// JSON text, every double included, and the id images bit for bit).
TEST(AssignmentKit, InputsReadBackGiveTheSameAnswers) {
    const Loaded &l = loaded();
    ASSERT_EQ(l.kit.views.size(), 2u);
    ASSERT_EQ(l.kit.stages.size(), 4u);
    for (size_t v = 0; v < l.kit.views.size(); ++v) {
        const kit::KitView &kv = l.kit.views[v];
        const kit::StageAnswer again[] = {kit::answerBackface(kv, *kv.backface), kit::answerClip(kv, *kv.clip),
                                          kit::answerZBuffer(kv, *kv.zbuffer),
                                          kit::answerPainter(kv, *kv.painter, l.kit.painterKey)};
        for (size_t s = 0; s < 4; ++s) {
            const kit::StageAnswer &a = l.answers.views[v][s];
            EXPECT_EQ(again[s].answer.dump(), a.answer.dump()) << kv.name << " " << kit::stageName(a.stage);
            EXPECT_EQ(again[s].extra.dump(), a.extra.dump()) << kv.name << " " << kit::stageName(a.stage);
            EXPECT_TRUE(again[s].ids == a.ids) << kv.name << " " << kit::stageName(a.stage);
        }
    }
    // The kit's views exercise what the tests below need: near-plane clipping in spawn, centres on
    // shared edges in the top view, coplanar surfaces (the decal on the floor) in both.
    EXPECT_GT(l.answers.views[0][1].answer["per_plane"]["near"].get<uint64_t>(), 0u);
    EXPECT_EQ(l.kit.views[1].cam.orthographic, true);
}

// The kit's answers are the pipeline's own numbers for the same views: what `analyze` reports for
// the backface, clip and z-buffer stages and the painter's draw, and the z-buffer's ids pixel for
// pixel.
TEST(AssignmentKit, AnswersEqualThePipelinesNumbers) {
    const Scene scene = demoScene();
    PipelineSettings s;
    s.raycast = false;
    s.zfight = false;
    s.detail = false;
    AnalysisResult r;
    std::string err;
    ASSERT_TRUE(analyzeScene(scene, kitViews(), s, nullptr, &r, &err)) << err;
    const Loaded &l = loaded();
    for (size_t v = 0; v < 2; ++v) {
        const ViewResult &vr = r.views[v];
        const auto &ans = l.answers.views[v];
        const nlohmann::ordered_json &bf = ans[0].answer, &cl = ans[1].answer, &zb = ans[2].answer, &pa = ans[3].answer;
        EXPECT_EQ(bf["triangles_tested"].get<uint64_t>(), vr.backface.trianglesTested);
        EXPECT_EQ(bf["double_sided_exempt"].get<uint64_t>(), vr.backface.doubleSidedExempt);
        EXPECT_EQ(bf["edge_on"].get<uint64_t>(), vr.backface.edgeOn);
        EXPECT_EQ(cl["triangles_in"].get<uint64_t>(), vr.clip.trianglesIn);
        EXPECT_EQ(cl["trivially_rejected"].get<uint64_t>(), vr.clip.trivialRejected);
        EXPECT_EQ(cl["clipped"].get<uint64_t>(), vr.clip.clipped);
        EXPECT_EQ(cl["per_plane"]["near"].get<uint64_t>(), vr.clip.perPlane[kPlaneNear]);
        EXPECT_EQ(cl["triangles_out"].get<uint64_t>(), vr.clip.trianglesOut);
        EXPECT_EQ(zb["fragments"].get<uint64_t>(), vr.zbuffer.fragments);
        EXPECT_EQ(zb["depth_passes"].get<uint64_t>(), vr.zbuffer.depthPasses);
        EXPECT_EQ(zb["triangles_drawn"].get<uint64_t>(), vr.zbuffer.trianglesDrawn);
        EXPECT_EQ(zb["overdraw"].get<double>(), vr.zbuffer.overdraw);
        EXPECT_TRUE(ans[2].ids == vr.buffer.id) << vr.spec.name;
        ASSERT_TRUE(vr.ordering.ran()) << vr.ordering.reason();
        EXPECT_EQ(pa["triangles_drawn"].get<uint64_t>(), vr.ordering->painter.trianglesDrawn);
        EXPECT_EQ(pa["fragments"].get<uint64_t>(), vr.ordering->painter.fragments);
        EXPECT_EQ(pa["covered_pixels"].get<uint64_t>(), vr.ordering->painter.coveredPixels);
        EXPECT_TRUE(std::ranges::equal(ans[3].ids, vr.ordering->painter.id)) << vr.spec.name;
    }
}

TEST_F(Assignment, ACorrectSubmissionScores100) {
    const kit::KitGrade g = submit("correct", {});
    EXPECT_EQ(g.score, 1.0) << describe(g);
    EXPECT_EQ(g.failed, 0u);
    EXPECT_TRUE(g.hints.empty()) << describe(g);
    EXPECT_EQ(g.error, "");
    // Checks per view: backface 7 (6 counts, kept), clip 22 (16 counts, per_plane's 6 and
    // polygon_vertices' 7 among them, polygons), zbuffer 13 (11 counts, ids, depth), painter 6
    // (4 counts, order, ids).
    EXPECT_EQ(itemsOf(g, "backface"), 14u);
    EXPECT_EQ(itemsOf(g, "clip"), 44u);
    EXPECT_EQ(itemsOf(g, "zbuffer"), 26u);
    EXPECT_EQ(itemsOf(g, "painter"), 12u);
    // Every image was compared pixel by pixel: 2 views x (ids, depth, painter ids).
    ASSERT_EQ(g.images.size(), 6u);
    for (const kit::PixelGrade &p : g.images) EXPECT_EQ(p.agree, p.pixels) << p.view << " " << p.stage << " " << p.image;
}

TEST_F(Assignment, DepthTestGreaterFailsTheZBufferOnly) {
    Mistakes m;
    m.greater = true;
    kit::KitGrade g = submit("greater", m);
    // The farthest surface wins: which fragments pass, and so the picture and its depths, change;
    // coverage (fragments, the histogram, triangles drawn) does not, nor does any other stage.
    const std::vector<std::string> expected = {"spawn zbuffer.depth_passes", "spawn zbuffer.overdraw", "spawn zbuffer.ids",
                                               "spawn zbuffer.depth",        "top zbuffer.depth_passes", "top zbuffer.overdraw",
                                               "top zbuffer.ids",            "top zbuffer.depth"};
    EXPECT_EQ(failures(g), expected) << describe(g);
    EXPECT_DOUBLE_EQ(g.score, (3 + 18.0 / 26) / 4);
    EXPECT_EQ(hintIds(g), (std::set<std::string>{"spawn depth_test_greater", "top depth_test_greater"})) << describe(g);
    for (const kit::PixelGrade &p : g.images) {
        if (p.stage != "zbuffer") continue;
        EXPECT_GT(p.genuine, 0u) << p.view << " " << p.image;
        EXPECT_EQ(p.tie, 0u) << p.view << " " << p.image;
        EXPECT_EQ(p.fartherPixels, p.comparedDepths) << p.view << " " << p.image;  // every wrong surface is farther
    }

    // The depth image alone tells the same: without the ids, each differing pixel is judged by the
    // depth the student stored.
    json sub = readJson(dir_ / "greater" / "submission.json");
    for (auto &[name, v] : sub["views"].items()) v["zbuffer"].erase("ids");
    std::ofstream(dir_ / "greater" / "submission.json") << sub.dump();
    g = grade(dir_ / "greater");
    EXPECT_EQ(hintIds(g), (std::set<std::string>{"spawn depth_test_greater", "top depth_test_greater"})) << describe(g);
}

TEST_F(Assignment, InvertedFillRuleIsToldApartFromAWrongDepthTest) {
    Mistakes m;
    m.invertFill = true;
    const kit::KitGrade g = submit("fill", m);
    // The student's one rasterizer serves the z-buffer and the painter. The top view's floor
    // diagonals pass through two centres per quad (2021 of them visible); spawn's perspective corners
    // put two centres exactly on an edge. Every differing pixel is an edge pixel; no count changes
    // (each such centre changes owner between two triangles sharing the edge).
    const std::vector<std::string> expected = {"spawn zbuffer.ids", "spawn painter.ids", "top zbuffer.ids",
                                               "top painter.ids"};
    EXPECT_EQ(failures(g), expected) << describe(g);
    EXPECT_DOUBLE_EQ(g.score, (2 + 24.0 / 26 + 10.0 / 12) / 4);
    for (const kit::PixelGrade &p : g.images) {
        if (p.image != "ids") continue;
        EXPECT_EQ(p.edge, p.view == "top" ? 2021u : 2u) << p.view << " " << p.stage;
        EXPECT_EQ(p.tie + p.genuine, 0u) << p.view << " " << p.stage;
    }
    EXPECT_EQ(hintIds(g), (std::set<std::string>{"spawn fill_rule", "top fill_rule"})) << describe(g);
    for (const kit::GradeHint &h : g.hints) EXPECT_NE(h.text.find("top-left rule inverted"), std::string::npos) << h.text;
}

TEST_F(Assignment, LessEqualLetsTheCoplanarDecalWinTies) {
    Mistakes m;
    m.lessEqual = true;
    const kit::KitGrade g = submit("lequal", m);
    // The decal lies on the floor's plane and is drawn after it: with LESS_EQUAL it wins the ties.
    const std::vector<std::string> expected = {"spawn zbuffer.depth_passes", "spawn zbuffer.overdraw", "spawn zbuffer.ids",
                                               "top zbuffer.depth_passes",   "top zbuffer.overdraw",   "top zbuffer.ids"};
    EXPECT_EQ(failures(g), expected) << describe(g);
    EXPECT_DOUBLE_EQ(g.score, (3 + 20.0 / 26) / 4);
    EXPECT_EQ(hintIds(g), (std::set<std::string>{"spawn tie_rule", "top tie_rule"})) << describe(g);
    for (const kit::PixelGrade &p : g.images)
        if (p.stage == "zbuffer" && p.image == "ids") {
            EXPECT_GT(p.tie, 0u) << p.view;
            EXPECT_EQ(p.genuine, 0u) << p.view;
        }
}

TEST_F(Assignment, ClipperSkippingTheNearPlaneIsHinted) {
    Mistakes m;
    m.skipNear = true;
    const kit::KitGrade g = submit("near", m);
    // Only spawn has triangles crossing the near plane (two of the wall's, beside the camera): one
    // the reference clips to a triangle and one to a quad; unclipped, both stay triangles (so one
    // more fan triangle), and one polygon keeps a corner behind the near plane.
    const std::vector<std::string> expected = {"spawn clip.per_plane.near", "spawn clip.polygon_vertices.3",
                                               "spawn clip.polygon_vertices.4", "spawn clip.triangles_out",
                                               "spawn clip.polygons"};
    EXPECT_EQ(failures(g), expected) << describe(g);
    EXPECT_DOUBLE_EQ(g.score, (3 + 39.0 / 44) / 4);
    EXPECT_EQ(hintIds(g), (std::set<std::string>{"spawn near_not_clipped"})) << describe(g);
}

TEST_F(Assignment, ReversedWindingFailsBackfaceOnly) {
    Mistakes m;
    m.reverseWinding = true;
    const kit::KitGrade g = submit("winding", m);
    const std::vector<std::string> expected = {"spawn backface.triangles_culled", "spawn backface.triangles_out",
                                               "spawn backface.kept", "top backface.triangles_culled",
                                               "top backface.triangles_out", "top backface.kept"};
    EXPECT_EQ(failures(g), expected) << describe(g);
    EXPECT_DOUBLE_EQ(g.score, (3 + 8.0 / 14) / 4);
    EXPECT_EQ(hintIds(g), (std::set<std::string>{"spawn winding_reversed", "top winding_reversed"})) << describe(g);
}

TEST_F(Assignment, NearestVertexPainterKeyIsHinted) {
    Mistakes m;
    m.painterKey = "nearest_vertex";
    const kit::KitGrade g = submit("painter", m);
    // Another order in both views; in spawn it shows (the decal and the floor swap at tied pixels),
    // from above every overlap is resolved the same way.
    const std::vector<std::string> expected = {"spawn painter.order", "spawn painter.ids", "top painter.order"};
    EXPECT_EQ(failures(g), expected) << describe(g);
    EXPECT_DOUBLE_EQ(g.score, (3 + 9.0 / 12) / 4);
    EXPECT_EQ(hintIds(g), (std::set<std::string>{"spawn painter_key_nearest", "top painter_key_nearest"})) << describe(g);
}

// ---- Bad submissions: graded as failures with the reason, never a crash, never a pass ----------

class BadSubmission : public Assignment {
  protected:
    void SetUp() override {
        Assignment::SetUp();
        writeSubmission(demoKit().kit, dir_ / "good", {});
    }
    fs::path copy(const std::string &name) {
        fs::copy(dir_ / "good", dir_ / name, fs::copy_options::recursive);
        return dir_ / name;
    }
    void edit(const fs::path &d, const std::function<void(json &)> &f) {
        json j = readJson(d / "submission.json");
        f(j);
        std::ofstream(d / "submission.json") << j.dump();
    }
    // The item's note (its reason), or "" when it passed or is absent.
    static const GradeItem *find(const kit::KitGrade &g, const std::string &view, const std::string &key) {
        for (const GradeItem &it : g.items)
            if (it.view == view && it.stage + "." + it.key == key) return &it;
        return nullptr;
    }
};

// The correct pictures written as CSV and as float EXR (ids and depth) grade the same: 100%.
TEST_F(BadSubmission, EveryImageFormatGradesTheSame) {
    const fs::path d = copy("formats");
    auto readIds = [](const fs::path &png, std::vector<float> *v, int *W, int *H) {
        ImageData im;
        std::string err;
        ASSERT_TRUE(readImage(png.string(), &im, &err)) << err;
        ASSERT_EQ(im.pixelType, "uint16");
        ASSERT_EQ(im.channels(), 1);
        *W = im.width, *H = im.height;
        v->assign(im.u16.begin(), im.u16.end());
    };
    auto csv = [](const fs::path &p, int W, const std::vector<float> &v) {
        std::ofstream f(p);
        for (size_t i = 0; i < v.size(); ++i) f << (std::isinf(v[i]) ? std::string("inf") : json(double(v[i])).dump())
                                                 << ((i + 1) % size_t(W) ? "," : "\n");
    };
    auto readPfm = [](const fs::path &p, int W, int H) {
        std::ifstream f(p, std::ios::binary);
        std::string magic;
        int w, h;
        double scale;
        f >> magic >> w >> h >> scale;
        f.get();
        std::vector<float> rows(size_t(W) * size_t(H)), v(rows.size());
        f.read(reinterpret_cast<char *>(rows.data()), std::streamsize(4 * rows.size()));
        for (int y = 0; y < H; ++y)
            std::copy_n(&rows[size_t(H - 1 - y) * size_t(W)], W, &v[size_t(y) * size_t(W)]);
        return v;
    };
    std::vector<float> spawnIds, topIds;
    int W, H, TW, TH;
    readIds(d / "spawn.ids.png", &spawnIds, &W, &H);
    readIds(d / "top.ids.png", &topIds, &TW, &TH);
    csv(d / "spawn.ids.csv", W, spawnIds);
    csv(d / "spawn.depth.csv", W, readPfm(d / "spawn.depth.pfm", W, H));
    {
        ASSERT_TRUE(va::test::writeExrFile((d / "top.ids.exr").string(), TW, TH, {"Y"}, Imf::FLOAT, topIds.data()));
        const std::vector<float> depth = readPfm(d / "top.depth.pfm", TW, TH);
        ASSERT_TRUE(va::test::writeExrFile((d / "top.depth.exr").string(), TW, TH, {"Y"}, Imf::FLOAT, depth.data()));
    }
    edit(d, [](json &j) {
        j["views"]["spawn"]["zbuffer"]["ids"] = "spawn.ids.csv";
        j["views"]["spawn"]["zbuffer"]["depth"] = "spawn.depth.csv";
        j["views"]["top"]["zbuffer"]["ids"] = "top.ids.exr";
        j["views"]["top"]["zbuffer"]["depth"] = "top.depth.exr";
    });
    const kit::KitGrade g = grade(d);
    EXPECT_EQ(g.score, 1.0) << describe(g);
    EXPECT_EQ(g.images.size(), 6u);
}

TEST_F(BadSubmission, UnreadableSubmissionsFailEveryCheckWithTheReason) {
    const kit::KitGrade none = grade(dir_ / "nobody");
    EXPECT_NE(none.error.find("not a folder"), std::string::npos) << none.error;
    fs::create_directories(dir_ / "empty");
    const kit::KitGrade empty = grade(dir_ / "empty");
    EXPECT_NE(empty.error.find("submission.json: file not found"), std::string::npos) << empty.error;
    fs::create_directories(dir_ / "syntax");
    std::ofstream(dir_ / "syntax" / "submission.json") << "{\"format\": \"visaudit-submission/1\",\n \"views\": {,}}";
    const kit::KitGrade syntax = grade(dir_ / "syntax");
    EXPECT_NE(syntax.error.find("submission.json:2:12: JSON syntax error"), std::string::npos) << syntax.error;
    fs::create_directories(dir_ / "shape");
    std::ofstream(dir_ / "shape" / "submission.json") << R"({"format": "visaudit-submission/1", "views": []})";
    const kit::KitGrade shape = grade(dir_ / "shape");
    EXPECT_NE(shape.error.find("expected \"views\": {\"VIEW\": {...}}"), std::string::npos) << shape.error;
    fs::create_directories(dir_ / "link");
    fs::create_symlink(dir_ / "syntax" / "submission.json", dir_ / "link" / "submission.json");
    const kit::KitGrade link = grade(dir_ / "link");
    EXPECT_NE(link.error.find("submission.json: a link to a file outside the submission folder"), std::string::npos)
        << link.error;
    for (const kit::KitGrade *g : {&none, &empty, &syntax, &shape, &link}) {
        EXPECT_EQ(g->score, 0.0);
        EXPECT_EQ(g->passed, 0u);
        EXPECT_EQ(g->failed, 96u);
        for (const GradeItem &it : g->items) EXPECT_EQ(it.note, g->error);
    }
}

TEST_F(BadSubmission, AViewThatIsNotAnObjectFailsThatViewOnly) {
    const fs::path d = copy("view");
    edit(d, [](json &j) { j["views"]["spawn"] = 3; });
    const kit::KitGrade g = grade(d);
    EXPECT_EQ(g.error, "");
    EXPECT_EQ(g.failed, 48u);  // every check of spawn; top passes
    for (const GradeItem &it : g.items) {
        EXPECT_EQ(it.pass, it.view == "top") << it.view << " " << it.key;
        if (it.view == "spawn") {
            EXPECT_EQ(it.note, "views.spawn is not an object");
        }
    }
}

TEST_F(BadSubmission, BadImagesAndListsAreNamedFailures) {
    const fs::path d = copy("images");
    // A 10 x 10 id image, an RGB one, a depth image with a NaN, an id that is not a whole number in a
    // CSV, a file outside the folder, a kept list that is not a list, a polygon without vertices.
    std::vector<uint32_t> small(100, 0);
    writeGray16(d / "small.png", 10, 10, small);
    {
        std::vector<uint8_t> rgb(96 * 54 * 3, 0);
        ASSERT_TRUE(va::test::writePngFile((d / "rgb.png").string(), 96, 54, 3, 8, rgb.data()));
    }
    std::vector<float> nan(64 * 64, 1.0f);
    nan[64 * 5 + 7] = NAN;
    writePfm(d / "nan.pfm", 64, 64, nan);
    {
        std::ofstream csv(d / "half.csv");
        for (int y = 0; y < 64; ++y)
            for (int x = 0; x < 64; ++x) csv << (x == 3 && y == 2 ? "2.5" : "0") << (x == 63 ? "\n" : ",");
    }
    fs::create_symlink(dir_ / "good" / "spawn.depth.pfm", d / "link.pfm");  // a link out of the folder
    edit(d, [](json &j) {
        j["views"]["spawn"]["zbuffer"]["ids"] = "small.png";
        j["views"]["spawn"]["painter"]["ids"] = "rgb.png";
        j["views"]["top"]["zbuffer"]["depth"] = "nan.pfm";
        j["views"]["top"]["zbuffer"]["ids"] = "half.csv";
        j["views"]["top"]["painter"]["ids"] = "../good/top.painter.png";
        j["views"]["spawn"]["zbuffer"]["depth"] = "link.pfm";
        j["views"]["spawn"]["backface"]["kept"] = "abc";
        j["views"]["spawn"]["clip"]["polygons"][0] = json{{"id", 1}};
        j["views"]["top"]["zbuffer"]["histogram"] = json::array({1, "two"});
    });
    const kit::KitGrade g = grade(d);
    EXPECT_EQ(g.error, "");
    const std::map<std::pair<std::string, std::string>, std::string> reasons = {
        {{"spawn", "zbuffer.ids"}, "small.png is 10x10; the view is 96x54"},
        {{"spawn", "painter.ids"}, "rgb.png: 3 channels; write a one-channel (grayscale) PNG"},
        {{"top", "zbuffer.depth"}, "nan.pfm: NaN at pixel (7, 5); write +inf or 0 for background"},
        {{"top", "zbuffer.ids"}, "half.csv: 2.5 at pixel (3, 2) is not an id (1 + a triangle id, 0 for background)"},
        {{"top", "painter.ids"}, "'../good/top.painter.png' is not a file of the submission folder; name the image relative to it"},
        {{"spawn", "zbuffer.depth"}, "'link.pfm' is not a file of the submission folder; name the image relative to it"},
        {{"spawn", "backface.kept"}, "not an array of ids: \"abc\""},
        {{"spawn", "clip.polygons"}, "polygons[0]: expected {\"id\": ID, \"vertices\": [[x, y, w, d], ...]}"},
        {{"top", "zbuffer.histogram"}, "not every entry is a number"},
    };
    for (const auto &[at, why] : reasons) {
        const GradeItem *it = find(g, at.first, at.second);
        ASSERT_NE(it, nullptr) << at.second;
        EXPECT_FALSE(it->pass) << at.second;
        EXPECT_EQ(it->note, why) << at.first << " " << at.second;
    }
    EXPECT_EQ(g.failed, reasons.size()) << describe(g);
}

}  // namespace
}  // namespace va

namespace va {
namespace {

// ---- The commands, as an instructor runs them ----------------------------------------------------

class AssignmentCli : public testing_util::TempDirTest {
  protected:
    AssignmentCli() : TempDirTest("assignment-cli") {}
    testing_util::ChildResult run(const std::vector<std::string> &args) { return testing_util::runBinary(args, dir_); }
    std::string file(const fs::path &p) { return testing_util::slurpFile(p); }
    // The demo's kit for kitViews() (a views file), by the command; `extra` replaces the views.
    void makeKit(const std::string &name = "kit", const std::vector<std::string> &extra = {}) {
        json views = json::array();
        for (const ViewSpec &v : kitViews()) views.push_back(json::parse(kit::viewSpecJson(v).dump()));
        std::ofstream(dir_ / "views.json") << json{{"views", views}}.dump();
        std::vector<std::string> args = {"assignment", "--out", (dir_ / name).string(), "--quiet"};
        if (extra.empty()) args.insert(args.end(), {"--views", (dir_ / "views.json").string()});
        args.insert(args.end(), extra.begin(), extra.end());
        const testing_util::ChildResult r = run(args);
        ASSERT_EQ(r.code, 0) << r.err;
    }
};

TEST_F(AssignmentCli, KitAndAnswersAreWrittenApart) {
    makeKit();
    for (const char *f : {"assignment.json", "README.md", "CONVENTIONS.md", "scene.obj", "views.json",
                          "template/submission.json", "views/spawn/clip.json", "views/top/painter.json"})
        EXPECT_TRUE(fs::is_regular_file(dir_ / "kit" / f)) << f;
    for (const char *f : {"answers.json", "views/spawn/zbuffer.json", "views/spawn/zbuffer.ids.exr", "views/top/painter.ids.exr"})
        EXPECT_TRUE(fs::is_regular_file(dir_ / "kit-answers" / f)) << f;
    // Nothing of the answers in the students' kit.
    for (const auto &e : fs::recursive_directory_iterator(dir_ / "kit")) {
        EXPECT_NE(e.path().extension(), ".exr") << e.path();
        if (e.is_regular_file()) {
            EXPECT_EQ(file(e.path()).find("visaudit-answer"), std::string::npos) << e.path();
        }
    }
    // The OBJ has one face per triangle id; views.json loads as a views file.
    const std::string obj = file(dir_ / "kit" / "scene.obj");
    const json a = readJson(dir_ / "kit" / "assignment.json");
    size_t faces = 0;
    for (size_t i = 0; i + 1 < obj.size(); ++i) faces += (i == 0 || obj[i - 1] == '\n') && obj[i] == 'f' && obj[i + 1] == ' ';
    EXPECT_EQ(faces, a["scene"]["source_triangles"].get<size_t>());
    const testing_util::ChildResult info =
        run({"info", (dir_ / "kit" / "scene.obj").string(), "--views", (dir_ / "kit" / "views.json").string()});
    EXPECT_EQ(info.code, 0) << info.err;
}

TEST_F(AssignmentCli, GradesAClassDeterministicallyAndBadSubmissionsStopNothing) {
    makeKit();
    const fs::path kitDir = dir_ / "kit", subs = dir_ / "subs";
    writeSubmission(kitDir, subs / "alice", {});
    Mistakes greater;
    greater.greater = true;
    writeSubmission(kitDir, subs / "bob", greater);
    fs::create_directories(subs / "carol");
    std::ofstream(subs / "carol" / "submission.json") << "{\"format\": ";
    std::vector<std::string> args = {"grade", "--kit", kitDir.string(), "--reference", (dir_ / "kit-answers").string(),
                                     "--submissions", (subs / "alice").string(), (subs / "bob").string(),
                                     (subs / "carol").string(), (subs / "dave").string(), "--quiet", "--out"};
    std::vector<std::string> one = args, two = args;
    one.insert(one.end(), {(dir_ / "g1").string(), "--threads", "1"});
    two.insert(two.end(), {(dir_ / "g2").string(), "--threads", "2"});
    const testing_util::ChildResult r1 = run(one), r2 = run(two);
    ASSERT_EQ(r1.code, 0) << r1.err;
    ASSERT_EQ(r2.code, 0) << r2.err;
    for (const char *f : {"grades.csv", "class.json", "index.html", "students/alice/grade.json", "students/bob/grade.json",
                          "students/bob/grade.html", "students/bob/spawn.zbuffer.ids.diff.png", "students/carol/grade.json",
                          "students/dave/grade.json"})
        EXPECT_EQ(file(dir_ / "g1" / f), file(dir_ / "g2" / f)) << f;

    std::vector<std::string> rows;
    std::stringstream csv(file(dir_ / "g1" / "grades.csv"));
    for (std::string line; std::getline(csv, line);) rows.push_back(line);
    ASSERT_EQ(rows.size(), 5u);
    EXPECT_EQ(rows[0], "student,score,backface,clip,zbuffer,painter,passed,failed,failures,hints,error");
    EXPECT_EQ(rows[1].rfind("alice,100.00,100.00,100.00,100.00,100.00,", 0), 0u) << rows[1];
    EXPECT_EQ(rows[2].rfind("bob,", 0), 0u) << rows[2];
    EXPECT_NE(rows[2].find("spawn depth_test_greater"), std::string::npos) << rows[2];
    EXPECT_EQ(rows[3].rfind("carol,0.00,0.00,0.00,0.00,0.00,0,96,", 0), 0u) << rows[3];
    EXPECT_NE(rows[3].find("submission.json:1:12: JSON syntax error"), std::string::npos) << rows[3];
    EXPECT_NE(rows[4].find("not a folder"), std::string::npos) << rows[4];

    // The class summary: bob, carol and dave fail the z-buffer's depth passes; only carol and dave
    // the backface checks. The greater hint was given to one student.
    const json s = readJson(dir_ / "g1" / "class.json");
    EXPECT_EQ(s["submissions"], 4);
    EXPECT_EQ(s["unreadable"], 2);
    EXPECT_EQ(s["full_marks"], 1);
    EXPECT_EQ(s["checks_failed"][0]["failed"], 3);
    EXPECT_EQ(s["checks_failed"][0]["check"], "spawn zbuffer.depth_passes");
    EXPECT_EQ(s["hints"], json::parse(R"([{"hint": "depth_test_greater", "students": 1}])"));
}

TEST_F(AssignmentCli, RefusesBadInstructorInputWithExit2) {
    makeKit();
    makeKit("other", {"--views", "orbit:2"});
    const std::string kit = (dir_ / "kit").string(), answers = (dir_ / "kit-answers").string();
    fs::create_directories(dir_ / "sub");
    struct Case {
        std::vector<std::string> args;
        std::string message;
    };
    const std::vector<Case> cases = {
        {{"assignment", "--stages", "clip,zbufer", "--out", (dir_ / "k2").string()},
         "--stages clip,zbufer: unknown stage 'zbufer', did you mean 'zbuffer'?"},
        {{"assignment", "--out", (dir_ / "k3").string(), "--answers", (dir_ / "k3" / "answers").string()},
         "overlap; the answers go to a folder of their own"},
        {{"grade", "--kit", kit, "--submission", (dir_ / "sub").string()}, "--kit needs --reference ANSWERS"},
        {{"grade", "--kit", (dir_ / "nothing").string(), "--reference", answers, "--submission", (dir_ / "sub").string()},
         "nothing: not a folder; --kit names the folder"},
        {{"grade", "--kit", kit, "--reference", (dir_ / "other-answers").string(), "--submission", (dir_ / "sub").string()},
         "is not among the files these answers were made for"},
        {{"grade", "--kit", kit, "--reference", answers, "--submissions", (dir_ / "sub").string()},
         "--submissions needs --out FOLDER"},
        {{"grade", "--submissions", (dir_ / "sub").string()}, "--submissions grades against an assignment kit"},
    };
    for (const Case &c : cases) {
        const testing_util::ChildResult r = run(c.args);
        EXPECT_EQ(r.code, 2) << c.args[0] << " " << c.args[1] << ": " << r.err;
        EXPECT_NE(r.err.find(c.message), std::string::npos) << r.err;
    }
    // An answer file edited after the command wrote it is refused, naming it.
    {
        std::ofstream f(dir_ / "kit-answers" / "views" / "spawn" / "clip.json", std::ios::app);
        f << " ";
    }
    const testing_util::ChildResult r =
        run({"grade", "--kit", kit, "--reference", answers, "--submission", (dir_ / "sub").string()});
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find("clip.json: not the file visaudit assignment wrote for these answers (changed since)"),
              std::string::npos)
        << r.err;
}

// VISAUDIT_GRADE_PAGE=DIR keeps a copy of the grade folder there (docs/images/grade-html.png is a
// screenshot of its grade.html).
TEST_F(AssignmentCli, OneSubmissionGetsItsPageAndExit1OnAFailure) {
    makeKit();
    Mistakes m;
    m.invertFill = true;
    m.skipNear = true;
    writeSubmission(dir_ / "kit", dir_ / "erin", m);
    const testing_util::ChildResult r = run({"grade", "--kit", (dir_ / "kit").string(), "--reference",
                                             (dir_ / "kit-answers").string(), "--submission", (dir_ / "erin").string(),
                                             "--out", (dir_ / "grade").string()});
    EXPECT_EQ(r.code, 1) << r.err;
    EXPECT_NE(r.out.find("score "), std::string::npos) << r.out;
    const std::string html = file(dir_ / "grade" / "grade.html");
    EXPECT_NE(html.find("<h1>Grade: erin</h1>"), std::string::npos);
    EXPECT_NE(html.find("top-left rule inverted"), std::string::npos);
    EXPECT_NE(html.find("Near plane not clipped"), std::string::npos);
    if (const char *keep = std::getenv("VISAUDIT_GRADE_PAGE")) {
        fs::remove_all(keep);
        fs::copy(dir_ / "grade", keep, fs::copy_options::recursive);
    }
    // Every image the page shows is a file next to it.
    for (size_t at = html.find("<img src=\""); at != std::string::npos; at = html.find("<img src=\"", at + 1)) {
        const size_t b = at + 10, e = html.find('"', b);
        EXPECT_TRUE(fs::is_regular_file(dir_ / "grade" / html.substr(b, e - b))) << html.substr(b, e - b);
    }
}

}  // namespace
}  // namespace va
