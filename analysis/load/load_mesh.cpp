// Mesh files (OBJ, PLY, OFF, STL) through OpenMesh's readers, into a RawMesh that keeps every face.
//
// OpenMesh's readers talk to the mesh through OpenMesh::IO::BaseImporter. Its stock importer
// (ImporterT) builds a half-edge mesh, which refuses non-manifold faces (three faces on one edge, a
// duplicate face, a "complex vertex") and drops them with only a log line. Game levels are full of
// such faces, so FaceRecorder below implements BaseImporter itself: every vertex and every face is
// recorded as the reader hands it over, and polygons are fan-triangulated from their first vertex.
//
// What the readers themselves do before our importer sees anything (checked against OpenMesh 9.0):
//   - STL (ascii and binary) merges vertices with bit-identical float coordinates and skips, without
//     telling the importer, every facet whose three merged vertices are not distinct. We count the
//     facets in the file ourselves (binary: the header's count; ascii: "outer loop" lines) so those
//     facets are reported as dropped, never silently lost.
//   - OBJ resolves negative (relative) indices itself; indices out of range are reported by the
//     reader on omerr and the face is not handed over; we count faces in the file ourselves to
//     report the difference as dropped.
//   - All readers store coordinates as float (Vec3f) except where a PLY declares double properties.
#include <unistd.h>

#include <OpenMesh/Core/IO/IOManager.hh>
#include <OpenMesh/Core/IO/Options.hh>
#include <OpenMesh/Core/IO/importer/BaseImporter.hh>
#include <OpenMesh/Core/System/omstream.hh>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <charconv>
#include <cmath>
#include <string_view>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>

#include "analysis/load/load.h"

namespace va {
namespace {

using OpenMesh::EdgeHandle;
using OpenMesh::FaceHandle;
using OpenMesh::HalfedgeHandle;
using OpenMesh::VertexHandle;

class FaceRecorder final : public OpenMesh::IO::BaseImporter {
public:
    explicit FaceRecorder(RawMesh *m) : m_(m) {}

    VertexHandle add_vertex(const OpenMesh::Vec3f &p) override {
        m_->positions.push_back({double(p[0]), double(p[1]), double(p[2])});
        return VertexHandle(int(m_->positions.size() - 1));
    }
    VertexHandle add_vertex(const OpenMesh::Vec3d &p) override {
        m_->positions.push_back({p[0], p[1], p[2]});
        return VertexHandle(int(m_->positions.size() - 1));
    }
    VertexHandle add_vertex() override {
        m_->positions.push_back({0, 0, 0});
        return VertexHandle(int(m_->positions.size() - 1));
    }
    void set_point(VertexHandle vh, const OpenMesh::Vec3f &p) override {
        if (vh.is_valid() && size_t(vh.idx()) < m_->positions.size())
            m_->positions[vh.idx()] = {double(p[0]), double(p[1]), double(p[2])};
    }

    // Every face the reader hands over counts as read. A face is dropped when one of its indices
    // is invalid, or when it has fewer than 3 distinct vertices; otherwise it becomes a fan
    // (v0, v[i], v[i+1]) in the given order: a triangle with a repeated corner inside a polygon
    // stays, as a zero-area triangle that buildScene counts as degenerate.
    FaceHandle add_face(const VHandles &vs) override {
        ++m_->facesRead;
        const FaceHandle fh(int(faces_++));
        const size_t nv = m_->positions.size();
        for (const auto &v : vs)
            if (!v.is_valid() || size_t(v.idx()) >= nv) {
                if (!badIndexFaces) badFace = {uint64_t(fh.idx()), int64_t(v.idx()), nv};
                ++m_->facesDropped;
                ++badIndexFaces;
                return fh;
            }
        distinct_.clear();
        for (const auto &v : vs) distinct_.push_back(v.idx());
        std::sort(distinct_.begin(), distinct_.end());
        if (std::unique(distinct_.begin(), distinct_.end()) - distinct_.begin() < 3) {
            ++m_->facesDropped;
            if (!tooFewFaces++) firstTooFew = uint64_t(fh.idx());
            return fh;
        }
        if (vs.size() > 3) ++m_->polygonsTriangulated;
        for (size_t i = 1; i + 1 < vs.size(); ++i) {
            m_->indices.push_back(uint32_t(vs[0].idx()));
            m_->indices.push_back(uint32_t(vs[i].idx()));
            m_->indices.push_back(uint32_t(vs[i + 1].idx()));
        }
        return fh;
    }

    // Half-edge level construction (only OpenMesh's own .om format uses it): not supported.
    HalfedgeHandle add_edge(VertexHandle, VertexHandle) override { return HalfedgeHandle(); }
    FaceHandle add_face(HalfedgeHandle) override { return FaceHandle(); }

    // Attributes we do not need: accepted and ignored.
    void add_face_texcoords(FaceHandle, VertexHandle, const std::vector<OpenMesh::Vec2f> &) override {}
    void add_face_texcoords(FaceHandle, VertexHandle, const std::vector<OpenMesh::Vec3f> &) override {}
    void set_face_texindex(FaceHandle, int) override {}
    void set_halfedge(VertexHandle, HalfedgeHandle) override {}
    void set_normal(VertexHandle, const OpenMesh::Vec3f &) override {}
    void set_normal(VertexHandle, const OpenMesh::Vec3d &) override {}
    void set_color(VertexHandle, const OpenMesh::Vec3uc &) override {}
    void set_color(VertexHandle, const OpenMesh::Vec4uc &) override {}
    void set_color(VertexHandle, const OpenMesh::Vec3f &) override {}
    void set_color(VertexHandle, const OpenMesh::Vec4f &) override {}
    void set_texcoord(VertexHandle, const OpenMesh::Vec2f &) override {}
    void set_status(VertexHandle, const OpenMesh::Attributes::StatusInfo &) override {}
    void set_next(HalfedgeHandle, HalfedgeHandle) override {}
    void set_face(HalfedgeHandle, FaceHandle) override {}
    void request_face_texcoords2D() override {}
    void set_texcoord(HalfedgeHandle, const OpenMesh::Vec2f &) override {}
    void set_texcoord(VertexHandle, const OpenMesh::Vec3f &) override {}
    void set_texcoord(HalfedgeHandle, const OpenMesh::Vec3f &) override {}
    void set_status(HalfedgeHandle, const OpenMesh::Attributes::StatusInfo &) override {}
    void set_color(EdgeHandle, const OpenMesh::Vec3uc &) override {}
    void set_color(EdgeHandle, const OpenMesh::Vec4uc &) override {}
    void set_color(EdgeHandle, const OpenMesh::Vec3f &) override {}
    void set_color(EdgeHandle, const OpenMesh::Vec4f &) override {}
    void set_status(EdgeHandle, const OpenMesh::Attributes::StatusInfo &) override {}
    void set_normal(FaceHandle, const OpenMesh::Vec3f &) override {}
    void set_normal(FaceHandle, const OpenMesh::Vec3d &) override {}
    void set_color(FaceHandle, const OpenMesh::Vec3uc &) override {}
    void set_color(FaceHandle, const OpenMesh::Vec4uc &) override {}
    void set_color(FaceHandle, const OpenMesh::Vec3f &) override {}
    void set_color(FaceHandle, const OpenMesh::Vec4f &) override {}
    void set_status(FaceHandle, const OpenMesh::Attributes::StatusInfo &) override {}
    void add_texture_information(int, std::string) override {}

    void reserve(unsigned int nV, unsigned int, unsigned int nF) override {
        // Sizes come from file headers: cap the reservation so a lying header cannot exhaust memory.
        constexpr unsigned int kCap = 1u << 24;
        m_->positions.reserve(std::min(nV, kCap));
        m_->indices.reserve(size_t(std::min(nF, kCap)) * 3);
    }
    size_t n_vertices() const override { return m_->positions.size(); }
    size_t n_faces() const override { return faces_; }
    size_t n_edges() const override { return 0; }

    uint64_t badIndexFaces = 0, tooFewFaces = 0;
    uint64_t firstTooFew = 0;  // the first face with fewer than 3 distinct vertices (file order, from 0)
    struct {
        uint64_t face;      // the first face with an invalid index (file order, from 0)
        int64_t index;      // that index
        size_t vertices;    // vertices read when the face came
    } badFace{};

private:
    RawMesh *m_;
    size_t faces_ = 0;
    std::vector<int> distinct_;
};

// OpenMesh's readers are driven through a process-wide IOManager and log to the global streams
// omerr/omlog/omout. One mutex serializes reads; while it is held the three streams write into a
// string instead of the console, which becomes part of our message when the read fails.
// The streams' buffers are swapped (std::ostream::rdbuf), not re-targeted with OpenMesh's
// connect/disconnect: disconnect drops its target without deleting it, 16 bytes lost per stream
// and read (found by fuzz_obj's leak check; tests/test_fuzz_regressions.cpp).
std::mutex gOpenMeshMutex;

class CaptureOpenMeshLog {
public:
    CaptureOpenMeshLog() {
        for (int i = 0; i < 3; ++i) {
            streams_[i]->flush();
            saved_[i] = streams_[i]->rdbuf(buf_.rdbuf());
        }
    }
    ~CaptureOpenMeshLog() {
        for (int i = 0; i < 3; ++i) {
            streams_[i]->flush();
            streams_[i]->rdbuf(saved_[i]);
        }
    }
    std::string text() {
        for (auto *s : streams_) s->flush();
        std::string t = buf_.str();
        while (!t.empty() && std::isspace((unsigned char)t.back())) t.pop_back();
        return t;
    }

private:
    std::ostream *streams_[3] = {&omerr(), &omlog(), &omout()};
    std::streambuf *saved_[3] = {};
    std::ostringstream buf_;
};

std::string lowerExtension(const std::string &path) {
    std::string e = std::filesystem::path(path).extension().string();
    for (auto &c : e) c = char(std::tolower((unsigned char)c));
    return e;
}

// Reads a whole file into memory (mesh files are read twice at most: once by OpenMesh, once here).
bool readAll(const std::string &path, std::string *text) {
    std::ifstream f(path, std::ios::binary);
    if (!f) return false;
    std::ostringstream ss;
    ss << f.rdbuf();
    *text = std::move(ss).str();
    return true;
}

// Calls fn(lineNumber, line) for every line (without its end-of-line characters).
template <class Fn>
void forEachLine(const std::string &text, Fn fn) {
    size_t b = 0, line = 1;
    while (b < text.size()) {
        size_t e = text.find('\n', b);
        if (e == std::string::npos) e = text.size();
        size_t end = e;
        if (end > b && text[end - 1] == '\r') --end;
        if (!fn(line, std::string_view(text).substr(b, end - b))) return;
        b = e + 1;
        ++line;
    }
}

std::string_view firstWord(std::string_view l) {
    size_t i = l.find_first_not_of(" \t");
    if (i == std::string_view::npos) return {};
    size_t j = l.find_first_of(" \t", i);
    return l.substr(i, (j == std::string_view::npos ? l.size() : j) - i);
}

// An STL file's structure, checked before OpenMesh reads it (its readers stop quietly at a cut and
// hand over what they had: an ASCII file cut inside its last facet loaded as 0 triangles, exit 0).
// Binary (the size is 84 + 50 n for the count n in the header, OpenMesh's own test): nothing to
// check. Otherwise a file that does not start with "solid" is a binary file whose size does not
// match its count: truncated or padded. ASCII: every "facet" must run "outer loop", three
// "vertex x y z", "endloop", "endfacet" (keywords case-insensitive, as the readers take them); a
// file ending inside a facet, or a line out of that order, is refused at its line. `facets` receives
// the file's facet count, counted independently of OpenMesh (which skips degenerate facets
// silently), `firstDegenerate` the first facet with two equal vertices, or -1.
bool checkStl(const std::string &path, uint64_t *facets, int64_t *firstDegenerate, std::string *err) {
    *facets = 0;
    *firstDegenerate = -1;
    std::string text;
    if (!readAll(path, &text)) return true;  // the reader reports it
    const uint64_t size = text.size();
    if (size >= 84) {
        uint32_t count;
        std::memcpy(&count, text.data() + 80, 4);  // little-endian on every platform we build for
        if (84 + 50 * uint64_t(count) == size) {
            *facets = count;
            // Binary: facet k is a normal and three corners (float x 3 each) and 2 attribute bytes.
            for (uint64_t k = 0; k < count && *firstDegenerate < 0; ++k) {
                float v[9];
                std::memcpy(v, text.data() + 84 + 50 * k + 12, sizeof v);
                auto same = [&](int a, int b) { return v[3 * a] == v[3 * b] && v[3 * a + 1] == v[3 * b + 1] && v[3 * a + 2] == v[3 * b + 2]; };
                if (same(0, 1) || same(1, 2) || same(0, 2)) *firstDegenerate = int64_t(k);
            }
            return true;
        }
    }
    const size_t start = text.find_first_not_of(" \t\r\n");
    auto lower = [](std::string_view w) {
        std::string l(w);
        for (char &c : l) c = char(std::tolower((unsigned char)c));
        return l;
    };
    if (start == std::string::npos || lower(std::string_view(text).substr(start, 5)) != "solid") {
        if (size >= 84) {
            uint32_t count;
            std::memcpy(&count, text.data() + 80, 4);
            *err = path + ": a binary STL whose header counts " + std::to_string(count) + " facets (" +
                   std::to_string(84 + 50 * uint64_t(count)) + " bytes) but the file has " + std::to_string(size) +
                   " bytes: it is truncated or damaged; export it again";
        } else {
            *err = path + ": " + std::to_string(size) +
                   " bytes, shorter than a binary STL's 84-byte header, and not an ASCII STL (no 'solid'): the file "
                   "is truncated or not an STL file";
        }
        return false;
    }
    // ASCII: the state is where in a facet the next line must be.
    enum State { kOutside, kOuter, kVertex, kEndloop, kEndfacet } state = kOutside;
    int vertices = 0;
    int64_t facet = -1;
    size_t facetLine = 0;
    bool ok = true;
    Vec3 corner[3];
    forEachLine(text, [&](size_t line, std::string_view l) {
        std::istringstream in{std::string(l)};
        std::string word;
        if (!(in >> word)) return true;  // blank
        const std::string w = lower(word);
        auto bad = [&](const std::string &what) {
            *err = path + ":" + std::to_string(line) + ": " + what;
            ok = false;
            return false;
        };
        switch (state) {
            case kOutside:
                if (w == "facet") {
                    ++facet, facetLine = line, state = kOuter;
                } else if (w != "solid" && w != "endsolid") {
                    return bad("'" + word + "' outside a facet; expected 'facet' (or 'endsolid')");
                }
                return true;
            case kOuter:
                if (w != "outer") return bad("facet " + std::to_string(facet) + ": expected 'outer loop', got '" + word + "'");
                state = kVertex, vertices = 0;
                return true;
            case kVertex: {
                if (w != "vertex")
                    return bad("facet " + std::to_string(facet) + ": expected vertex " + std::to_string(vertices + 1) +
                               " of 3, got '" + word + "'");
                double x, y, z;
                if (!(in >> x >> y >> z))
                    return bad("facet " + std::to_string(facet) + ": vertex " + std::to_string(vertices + 1) +
                               " needs 3 numbers, got '" + std::string(l.substr(l.find_first_not_of(" \t"))) + "'");
                corner[vertices] = {x, y, z};
                if (++vertices == 3) {
                    state = kEndloop;
                    if (*firstDegenerate < 0 &&
                        (corner[0] == corner[1] || corner[1] == corner[2] || corner[0] == corner[2]))
                        *firstDegenerate = facet;
                }
                return true;
            }
            case kEndloop:
                if (w != "endloop") return bad("facet " + std::to_string(facet) + ": expected 'endloop', got '" + word + "'");
                state = kEndfacet;
                return true;
            case kEndfacet:
                if (w != "endfacet") return bad("facet " + std::to_string(facet) + ": expected 'endfacet', got '" + word + "'");
                state = kOutside;
                return true;
        }
        return true;
    });
    if (!ok) return false;
    *facets = uint64_t(facet + 1);
    if (state != kOutside) {
        *err = path + ":" + std::to_string(facetLine) + ": facet " + std::to_string(facet) +
               " is cut off: the file ends inside it (" +
               (state == kVertex ? std::to_string(vertices) + " of its 3 vertices read" : std::string("before its end")) +
               "); the file is truncated: export it again";
        return false;
    }
    return true;
}


// OBJ checks where OpenMesh's reader is silent. Its reader parses a "v" line with iostream and skips
// the vertex when that fails: "nan", "inf", an overflowing number or fewer than 3 coordinates. The
// skipped vertex shifts every later index by one, so every later face would silently use the wrong
// vertices. We count "v" and "f" lines; when the vertex count differs from what the reader stored,
// the first vertex line whose three coordinates are not finite numbers is named in the error.
// (A non-finite coordinate therefore cannot come from an OBJ file; the other formats hand NaN over
// and loadMeshFile refuses it.) A face index outside the vertex list (1..n, or -1..-k relative to the
// k vertices before it) is refused too, naming the face's line: OpenMesh would drop the face.
bool checkObj(const std::string &path, const std::string &text, size_t positionsRead, uint64_t *faceLines,
              std::string *err) {
    uint64_t vLines = 0, fLines = 0;
    forEachLine(text, [&](size_t, std::string_view l) {
        const std::string_view w = firstWord(l);
        if (w == "v") ++vLines;
        else if (w == "f") ++fLines;
        return true;
    });
    *faceLines = fLines;
    std::string bad;
    uint64_t vSoFar = 0;
    forEachLine(text, [&](size_t n, std::string_view l) {
        const std::string_view w = firstWord(l);
        if (w == "v") ++vSoFar;
        if (w != "f") return true;
        const std::string line(l);
        std::istringstream in(line.substr(line.find('f') + 1));
        std::string corner;
        while (in >> corner) {
            const long long i = std::strtoll(corner.c_str(), nullptr, 10);  // "7/1/2": the vertex is 7
            if ((i > 0 && uint64_t(i) <= vLines) || (i < 0 && uint64_t(-i) <= vSoFar)) continue;
            bad = path + ":" + std::to_string(n) + ": face '" + line + "': vertex index " + std::to_string(i) +
                  " is out of range (the file has " + std::to_string(vLines) +
                  " vertices, counting from 1); fix the index or add the vertex";
            return false;
        }
        return true;
    });
    // A skipped vertex (below) is the root cause of any index error: report it first.
    if (!bad.empty() && vLines == positionsRead) {
        *err = bad;
        return false;
    }
    if (vLines == positionsRead) return true;
    std::string msg;
    forEachLine(text, [&](size_t n, std::string_view l) {
        if (firstWord(l) != "v") return true;
        std::string line(l);
        const char *p = line.c_str() + line.find('v') + 1;
        for (int k = 0; k < 3; ++k) {
            char *end = nullptr;
            const double x = std::strtod(p, &end);
            if (end == p || !std::isfinite(x)) {
                msg = path + ":" + std::to_string(n) + ": vertex '" + line + "': " +
                      (end == p ? "expected 3 numbers" : "coordinate is not a finite number") +
                      "; OpenMesh's OBJ reader skips such a vertex, which would shift every later face "
                      "index, so the file is refused: write three finite coordinates";
                return false;
            }
            p = end;
        }
        return true;
    });
    if (msg.empty())
        msg = path + ": the file has " + std::to_string(vLines) + " vertex lines but OpenMesh's OBJ reader read " +
              std::to_string(positionsRead) + " vertices; refusing the file (later face indices would be wrong)";
    *err = msg;
    return false;
}

// OFF checks: OpenMesh's OFF reader misreads a counts line without the edge count and comment lines
// after the header, silently producing garbage. The counts line (after "OFF" and any '#' comment or
// blank lines) must match what the reader produced.
bool checkOff(const std::string &path, const std::string &text, size_t positionsRead, uint64_t facesRead,
              std::string *err) {
    bool headerSeen = false, binary = false;
    std::string counts;
    size_t countsLine = 0;
    forEachLine(text, [&](size_t n, std::string_view l) {
        const std::string_view w = firstWord(l);
        if (w.empty() || w[0] == '#') return true;
        if (!headerSeen) {
            headerSeen = true;
            if (w.size() >= 3 && w.substr(w.size() - 3) == "OFF") {
                binary = l.find("BINARY") != std::string_view::npos;
                return true;
            }
        }
        counts = std::string(l);
        countsLine = n;
        return false;
    });
    if (binary) return true;
    std::istringstream in(counts);
    long long nv = -1, nf = -1, ne = -1;
    in >> nv >> nf >> ne;
    if (!in || nv < 0 || nf < 0) {
        *err = path + ":" + std::to_string(countsLine) + ": expected the OFF counts line 'VERTICES FACES EDGES'"
               " (three integers; OpenMesh's reader needs the edge count, 0 is fine), got '" + counts + "'";
        return false;
    }
    if (uint64_t(nv) != positionsRead || uint64_t(nf) != facesRead) {
        *err = path + ": the header declares " + std::to_string(nv) + " vertices and " + std::to_string(nf) +
               " faces but OpenMesh's OFF reader read " + std::to_string(positionsRead) + " and " +
               std::to_string(facesRead) + "; OpenMesh's OFF reader does not accept '#' comment lines after the OFF keyword: remove them, and check the counts";
        return false;
    }
    return true;
}

// ---- Structure checks before OpenMesh's readers see a file ----------------------------------------
// OpenMesh's readers trust the file: an OBJ face corner without a vertex index fails an assert
// (abort), and an OFF or PLY count (vertices, faces, a face's corners, a list's length) larger than
// the file drives a read loop on a failed stream for up to 2^32 iterations (a hang). The checks below
// walk the file's structure first, bounding every count by the bytes that are there; found by
// fuzz_obj, fuzz_off and fuzz_ply (tests/test_fuzz_regressions.cpp).

std::string clip(std::string_view l) {
    std::string s(l.substr(0, 80));
    for (auto &c : s)
        if (!std::isprint((unsigned char)c)) c = '?';
    return l.size() > 80 ? s + "..." : s;
}

// No corner of an "f" line starts with '/' ("/vt", "//vn": no vertex index), which fails OpenMesh's
// assert. Other malformed corners ("a") become invalid indices that the reader reports and drops.
bool preCheckObj(const std::string &path, const std::string &text, std::string *err) {
    std::string msg;
    forEachLine(text, [&](size_t n, std::string_view l) {
        if (firstWord(l) != "f") return true;
        size_t i = l.find('f') + 1;
        while (i < l.size()) {
            i = l.find_first_not_of(" \t", i);
            if (i == std::string_view::npos) break;
            const size_t e = std::min(l.size(), l.find_first_of(" \t", i));
            const std::string_view tok = l.substr(i, e - i);
            if (tok[0] == '/') {
                msg = path + ":" + std::to_string(n) + ": face '" + clip(l) + "': corner '" + clip(tok) +
                      "' has no vertex index; write corners as v, v/vt, v//vn or v/vt/vn with integer indices";
                return false;
            }
            i = e;
        }
        return true;
    });
    if (msg.empty()) return true;
    *err = msg;
    return false;
}

std::vector<std::string_view> words(std::string_view l) {
    std::vector<std::string_view> w;
    size_t i = 0;
    while ((i = l.find_first_not_of(" \t\r\f\v", i)) != std::string_view::npos) {
        const size_t e = std::min(l.size(), l.find_first_of(" \t\r\f\v", i));
        w.push_back(l.substr(i, e - i));
        i = e;
    }
    return w;
}

bool parseCount(std::string_view w, uint64_t *out) {
    if (w.empty() || w.size() > 19) return false;
    uint64_t v = 0;
    for (char c : w) {
        if (!std::isdigit((unsigned char)c)) return false;
        v = v * 10 + uint64_t(c - '0');
    }
    *out = v;
    return true;
}

// ASCII OFF: one vertex per line, then one face per line "N i1 .. iN [color]". Blank and '#' lines
// are skipped here (checkOff reports the '#' lines OpenMesh misreads). Binary OFF is refused: its
// counts would have to be trusted.
bool preCheckOff(const std::string &path, const std::string &text, std::string *err) {
    // Text only: OpenMesh's stream extraction and our line split then agree on what a word is.
    const auto bad = std::find_if(text.begin(), text.end(), [](char ch) {
        const unsigned char c = (unsigned char)ch;
        return !((c >= 0x20 && c < 0x7f) || c == '\t' || c == '\n' || c == '\r');
    });
    if (bad != text.end()) {
        const size_t line = 1 + size_t(std::count(text.begin(), bad, '\n'));
        char hex[8];
        std::snprintf(hex, sizeof hex, "0x%02x", unsigned((unsigned char)*bad));
        *err = path + ":" + std::to_string(line) + ": byte " + hex + " is not text; visaudit reads ascii OFF "
               "(binary OFF is not supported: its counts cannot be checked before OpenMesh's reader trusts "
               "them); convert the mesh to ascii OFF or PLY";
        return false;
    }
    enum { kHeader, kCounts, kVertices, kFaces, kDone } state = kHeader;
    uint64_t nv = 0, nf = 0, ne = 0, seen = 0;
    // OpenMesh's ascii reader takes a vertex's 3 coordinates (and 3 normal components with N) word
    // by word and then the rest of its line; a face's corner count and corners word by word, and
    // the rest of its line (a color) only when the header asks for colors (C): anything else left
    // on a line would be read as the next vertex or face, every later one off.
    bool plain = false;       // "OFF": exactly 3 coordinates per vertex line
    bool normals = false;     // [ST][C]N...OFF: a vertex line holds 3 normal components too
    bool faceColors = false;  // [ST]C...OFF: a face line may end with a color
    std::string msg;
    forEachLine(text, [&](size_t n, std::string_view l) {
        // Words as the stream extraction sees them (a line of only '\r' holds none).
        const std::vector<std::string_view> lineWords = words(l);
        if (lineWords.empty() || lineWords[0][0] == '#') return true;
        const std::string_view w = lineWords[0];
        const std::string at = path + ":" + std::to_string(n) + ": ";
        if (state == kHeader) {
            state = kCounts;
            if (w.size() >= 3 && w.substr(w.size() - 3) == "OFF") {
                plain = w == "OFF";
                std::string_view prefix = w.substr(0, w.size() - 3);  // [ST][C][N][4][n], as OpenMesh reads it
                if (prefix.substr(0, 2) == "ST") prefix.remove_prefix(2);
                faceColors = !prefix.empty() && prefix[0] == 'C';
                if (faceColors) prefix.remove_prefix(1);
                normals = !prefix.empty() && prefix[0] == 'N';
                if (l.find("BINARY") != std::string_view::npos) {
                    msg = at + "binary OFF is not supported (its counts cannot be checked before OpenMesh's "
                               "reader trusts them); convert the mesh to ascii OFF or PLY";
                    return false;
                }
                return true;
            }
            msg = at + "expected the OFF keyword (OFF, COFF, NOFF, ...) as the first word, got '" + clip(l) + "'";
            return false;
        }
        if (state == kCounts) {
            const auto &c = lineWords;
            // Exactly three: OpenMesh's reader takes the words after them as the first vertex, and
            // everything after that one word off (a vertex line read as a corner count of 2^32 - 1).
            if (c.size() != 3 || !parseCount(c[0], &nv) || !parseCount(c[1], &nf) || !parseCount(c[2], &ne)) {
                msg = at + "expected the OFF counts line 'VERTICES FACES EDGES' (exactly three integers; OpenMesh's "
                           "reader needs the edge count, 0 is fine), got '" + clip(l) + "'";
                return false;
            }
            state = nv > 0 ? kVertices : nf > 0 ? kFaces : kDone;
            return state != kDone;
        }
        ++seen;
        if (state == kVertices) {
            const size_t nw = lineWords.size(), need = normals ? 6 : 3;
            if (plain ? nw != 3 : nw < need) {
                msg = at + "vertex " + std::to_string(seen - 1) + " '" + clip(l) + "': expected " +
                      (plain ? "exactly " : "") +
                      (normals ? "3 coordinates and 3 normal components" : "3 coordinates") +
                      " on the line";
                return false;
            }
            // Decimal numbers the stream extraction reads whole ("~", "0x1", "nan" stop it, and every
            // read after fails: the file would load as garbage indices).
            for (size_t k = 0; k < need; ++k) {
                const std::string t(lineWords[k]);
                char *end = nullptr;
                const double x = std::strtod(t.c_str(), &end);
                if (t.find_first_not_of("0123456789+-.eE") != std::string::npos || end != t.c_str() + t.size() ||
                    !std::isfinite(x)) {
                    msg = at + "vertex " + std::to_string(seen - 1) + " '" + clip(l) + "': '" + clip(t) +
                          "' is not a finite decimal number; write finite coordinates";
                    return false;
                }
            }
            if (seen == nv) state = nf > 0 ? kFaces : kDone, seen = 0;
            return state != kDone;
        }
        const auto &f = lineWords;
        // N, N indices below the vertex count, then at most a color (up to 4 numbers 0..255) when the
        // header has C, nothing else otherwise: every word stays small and the reader stays on its
        // line, so no misread can become a huge corner count.
        uint64_t corners = 0, index = 0;
        bool ok = parseCount(f[0], &corners) && corners + 1 <= f.size() && f.size() <= corners + (faceColors ? 5 : 1);
        for (uint64_t k = 1; ok && k <= corners; ++k) ok = parseCount(f[k], &index) && index < nv;
        for (size_t k = size_t(corners) + 1; ok && k < f.size(); ++k) {
            const std::string t(f[k]);
            char *end = nullptr;
            const double c = std::strtod(t.c_str(), &end);
            ok = end == t.c_str() + t.size() && c >= 0 && c <= 255;
        }
        if (!ok) {
            msg = at + "face " + std::to_string(seen - 1) + " '" + clip(l) + "': expected the number of corners N, then N vertex "
                       "indices below " + std::to_string(nv) +
                  (faceColors ? " and at most a color on the line"
                              : " and nothing else on the line (a face color needs a C header: COFF)") +
                  "; fix the face (or the counts line)";
            return false;
        }
        if (seen == nf) state = kDone;
        return state != kDone;
    });
    if (!msg.empty()) {
        *err = msg;
        return false;
    }
    if (state == kHeader || state == kCounts) {
        *err = path + ": no " + std::string(state == kHeader ? "OFF keyword and no " : "") +
               "counts line 'VERTICES FACES EDGES'; the file is truncated or not an OFF file";
        return false;
    }
    if (state == kVertices || state == kFaces) {
        *err = path + ": the counts line declares " + std::to_string(nv) + " vertices and " + std::to_string(nf) +
               " faces but the file ends after " + std::string(state == kVertices ? "vertex " : "face ") +
               std::to_string(seen) + "; the file is truncated, or fix the counts";
        return false;
    }
    return true;
}

// PLY: the header's elements and properties, then every row of the body (ascii tokens or binary
// bytes), each list length checked against what is left of the file.
// `skipped` receives the header lines that are neither PLY keywords nor comments (old Blender
// exports write a bare "Created by Blender3D 247 - www.blender.org" line; obj_info lines), which the
// reference readers (rply, plyfile) skip: 1-based line numbers and their text.
bool preCheckPly(const std::string &path, const std::string &text, std::string *err,
                 std::vector<std::pair<size_t, std::string>> *skipped) {
    struct Property {
        int countBytes = 0;  // a list's length type; 0 for a scalar
        int bytes = 0;       // the (item) type's size
    };
    struct Element {
        std::string name;
        uint64_t rows = 0;
        std::vector<Property> props;
    };
    auto typeBytes = [](std::string_view t) {
        if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
        if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
        if (t == "int" || t == "uint" || t == "int32" || t == "uint32" || t == "float" || t == "float32") return 4;
        if (t == "double" || t == "float64") return 8;
        return 0;
    };
    std::vector<Element> elements;
    std::string format, msg;
    size_t body = std::string::npos;
    size_t b = 0, line = 0;
    while (b < text.size() && body == std::string::npos) {
        size_t e = text.find('\n', b);
        if (e == std::string::npos) e = text.size();
        const std::string_view l = std::string_view(text).substr(b, e - b);
        const auto w = words(l);
        ++line;
        const std::string at = path + ":" + std::to_string(line) + ": ";
        // Header lines are text: OpenMesh's header parser and this one then split words alike.
        for (char ch : l)
            if (!((unsigned char)ch >= 0x20 && (unsigned char)ch < 0x7f) && ch != '\t' && ch != '\r')
                return *err = at + "the PLY header holds a byte that is not text; is the header truncated?", false;
        if (line == 1) {
            if (w.size() != 1 || w[0] != "ply") return *err = path + ":1: expected 'ply', got '" + clip(l) + "'", false;
        } else if (w.empty() || w[0] == "comment") {
        } else if (w[0] == "obj_info" || (w[0] != "format" && w[0] != "element" && w[0] != "property" &&
                                            w[0] != "end_header" && w[0] != "ply")) {
            // Not a keyword: skipped as the reference readers skip it (OpenMesh's header parser would
            // read its words as keywords; loadMeshFile hands it a copy with these lines made comments).
            skipped->push_back({line, std::string(l)});
        } else if (w[0] == "end_header") {
            body = e + 1;
        } else if (w[0] == "format" && w.size() == 3 && format.empty() && w[2] == "1.0" &&
                   (w[1] == "ascii" || w[1] == "binary_little_endian" || w[1] == "binary_big_endian")) {
            format = std::string(w[1]);
        } else if (w[0] == "element" && w.size() == 3 && parseCount(w[2], &elements.emplace_back().rows)) {
            elements.back().name = std::string(w[1]);
        } else if (w[0] == "property" && !elements.empty() && w.size() == 3 && typeBytes(w[1])) {
            elements.back().props.push_back({0, typeBytes(w[1])});
        } else if (w[0] == "property" && !elements.empty() && w.size() == 5 && w[1] == "list" &&
                   typeBytes(w[2]) && typeBytes(w[3]) && w[2] != "float" && w[2] != "float32" && w[2] != "double" &&
                   w[2] != "float64") {
            elements.back().props.push_back({typeBytes(w[2]), typeBytes(w[3])});
        } else {
            return *err = at + "unexpected header line '" + clip(l) + "'; expected format, element, property " +
                          "(types char uchar short ushort int uint float double, or int8..float64), comment or end_header",
                   false;
        }
        b = e + 1;
    }
    if (body == std::string::npos) return *err = path + ": the PLY header has no 'end_header' line", false;
    if (format.empty()) return *err = path + ": the PLY header has no 'format' line; add 'format ascii 1.0' (or binary_little_endian 1.0)", false;
    for (const auto &el : elements)
        if (el.rows > 0 && el.props.empty())
            return *err = path + ": element '" + el.name + "' declares " + std::to_string(el.rows) +
                          " rows but no properties; fix the header", false;

    size_t pos = body;
    const bool ascii = format == "ascii", big = format == "binary_big_endian";
    // One value of the body: an ascii token, or `bytes` bytes (returned as an unsigned number).
    auto next = [&](int bytes, uint64_t *value) {
        if (ascii) {
            pos = text.find_first_not_of(" \t\r\n\f\v", pos);
            if (pos == std::string::npos) return pos = text.size(), false;
            const size_t e = std::min(text.size(), text.find_first_of(" \t\r\n\f\v", pos));
            const std::string_view tok = std::string_view(text).substr(pos, e - pos);
            pos = e;
            if (value) {
                // A list length: a whole number; anything else is refused below.
                char *end = nullptr;
                const std::string t(tok);
                const double x = std::strtod(t.c_str(), &end);
                if (end != t.c_str() + t.size() || !(x >= 0) || x != std::floor(x) || x > 4294967295.0) return false;
                *value = uint64_t(x);
            }
            return true;
        }
        if (text.size() - pos < size_t(bytes)) return false;
        if (value) {
            uint64_t v = 0;
            for (int k = 0; k < bytes; ++k)
                v |= uint64_t((unsigned char)text[pos + (big ? size_t(bytes - 1 - k) : size_t(k))]) << (8 * k);
            // Signed length types: a negative length is as wrong as a huge one.
            *value = v;
        }
        pos += size_t(bytes);
        return true;
    };
    for (const auto &el : elements) {
        for (uint64_t r = 0; r < el.rows; ++r) {
            for (const auto &pr : el.props) {
                const std::string place = path + ": element '" + el.name + "' row " + std::to_string(r) + ": ";
                if (pr.countBytes == 0) {
                    if (!next(pr.bytes, nullptr))
                        return *err = place + "the file ends early (the header declares " + std::to_string(el.rows) +
                                      " rows); the file is truncated, or fix the element's count", false;
                    continue;
                }
                uint64_t n = 0;
                if (!next(pr.countBytes, &n))
                    return *err = place + "expected a list length; the file is truncated or the row is malformed", false;
                // Every item takes at least one byte (a token and its separator, or its binary size).
                const uint64_t left = text.size() - pos;
                if (n > left / uint64_t(ascii ? 1 : pr.bytes))
                    return *err = place + "a list of " + std::to_string(n) + " items, more than the " + std::to_string(left) +
                                  " bytes left in the file; the row is malformed", false;
                for (uint64_t k = 0; k < n; ++k)
                    if (!next(pr.bytes, nullptr))
                        return *err = place + "the file ends inside a list of " + std::to_string(n) + " items", false;
            }
        }
    }
    return true;
}

}  // namespace

// The common OBJ, read without OpenMesh: OpenMesh's reader parses every line through iostreams
// (a stringstream, locale facets and a dynamic_cast per number), 4-6 s for a 1M-triangle file here,
// where this takes a fraction of a second. Only files made of nothing but "v x y z" lines (three
// finite numbers), "f i j k ..." lines (positive indices, no slashes, each naming a vertex already
// read), comments and blank lines take this path; anything else (texture coordinates, normals,
// negative indices, groups, materials, a malformed number) goes to OpenMesh as before. The vertices
// and faces are handed to the same FaceRecorder, as floats like OpenMesh's reader hands them, so
// the result is identical either way. Returns false, having recorded nothing, when the file is not
// in that subset.
bool readPlainObj(const std::string &text, FaceRecorder &rec) {
    std::vector<OpenMesh::Vec3f> verts;
    std::vector<uint32_t> corners, faceBegin;  // face f: corners[faceBegin[f] .. faceBegin[f + 1])
    auto skipBlank = [](const char *p, const char *e) {
        while (p < e && (*p == ' ' || *p == '\t')) ++p;
        return p;
    };
    bool plain = true;
    forEachLine(text, [&](size_t, std::string_view l) {
        const char *p = l.data(), *e = l.data() + l.size();
        p = skipBlank(p, e);
        if (p == e || *p == '#') return true;
        if (e - p >= 2 && p[0] == 'v' && (p[1] == ' ' || p[1] == '\t')) {
            OpenMesh::Vec3f v;
            p += 2;
            for (int k = 0; k < 3; ++k) {
                p = skipBlank(p, e);
                const auto r = std::from_chars(p, e, v[k]);
                if (r.ec != std::errc() || !std::isfinite(v[k]) || (r.ptr < e && *r.ptr != ' ' && *r.ptr != '\t'))
                    return plain = false;
                p = r.ptr;
            }
            if (skipBlank(p, e) != e) return plain = false;
            verts.push_back(v);
            return true;
        }
        if (e - p >= 2 && p[0] == 'f' && (p[1] == ' ' || p[1] == '\t')) {
            faceBegin.push_back(uint32_t(corners.size()));
            p += 2;
            while ((p = skipBlank(p, e)) < e) {
                uint32_t i = 0;
                const auto r = std::from_chars(p, e, i);
                if (r.ec != std::errc() || i == 0 || i > verts.size() || (r.ptr < e && *r.ptr != ' ' && *r.ptr != '\t'))
                    return plain = false;
                corners.push_back(i - 1);
                p = r.ptr;
            }
            if (corners.size() - faceBegin.back() < 3) return plain = false;
            return true;
        }
        return plain = false;
    });
    if (!plain) return false;
    faceBegin.push_back(uint32_t(corners.size()));
    rec.reserve(unsigned(std::min<size_t>(verts.size(), UINT32_MAX)), 0,
                unsigned(std::min<size_t>(faceBegin.size() - 1, UINT32_MAX)));
    for (const OpenMesh::Vec3f &v : verts) rec.add_vertex(v);
    OpenMesh::IO::BaseImporter::VHandles vs;
    for (size_t f = 0; f + 1 < faceBegin.size(); ++f) {
        vs.clear();
        for (uint32_t c = faceBegin[f]; c < faceBegin[f + 1]; ++c) vs.push_back(VertexHandle(int(corners[c])));
        rec.add_face(vs);
    }
    return true;
}

bool loadMeshFile(const std::string &path, RawMesh *out, std::string *err) {
    auto fail = [&](const std::string &m) {
        if (err) *err = m;
        return false;
    };
    const std::string ext = lowerExtension(path);
    if (ext != ".obj" && ext != ".ply" && ext != ".off" && ext != ".stl")
        return fail(path + ": unsupported mesh format '" + ext + "'; supported: .obj .ply .off .stl");
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) return fail(path + ": file not found");
    if (std::filesystem::is_directory(path, ec)) return fail(path + ": is a directory, not a mesh file");
    {
        std::ifstream probe(path, std::ios::binary);
        if (!probe) return fail(path + ": cannot open the file for reading (check its permissions)");
        if (probe.peek() == std::ifstream::traits_type::eof()) return fail(path + ": the file is empty");
    }

    std::string text;
    std::vector<std::pair<size_t, std::string>> plySkipped;  // PLY header lines skipped (line, text)
    uint64_t stlFacets = 0;
    int64_t firstDegenerateFacet = -1;
    if (ext == ".stl" && !checkStl(path, &stlFacets, &firstDegenerateFacet, err)) return false;
    if (ext != ".stl") {
        if (!readAll(path, &text)) return fail(path + ": cannot read the file");
        if (ext == ".obj" && !preCheckObj(path, text, err)) return false;
        if (ext == ".ply" && !preCheckPly(path, text, err, &plySkipped)) return false;
        if (ext == ".off" && !preCheckOff(path, text, err)) return false;
    }

    RawMesh m;
    FaceRecorder rec(&m);
    bool ok = false;
    std::string log;
    if (ext == ".obj" && readPlainObj(text, rec)) {
        ok = true;
    } else {
        std::lock_guard<std::mutex> lock(gOpenMeshMutex);
        CaptureOpenMeshLog capture;
        OpenMesh::IO::Options opt;  // positions and faces only
        // A PLY header with skipped lines is read from a copy in which they are comments (the same
        // number of lines; the body's bytes unchanged), written next to nothing the user owns.
        std::string readPath = path;
        std::filesystem::path copy;
        if (!plySkipped.empty()) {
            std::string fixed = text;
            size_t pos = 0, line = 1, k = 0;
            while (k < plySkipped.size() && pos < fixed.size()) {
                if (line == plySkipped[k].first) {
                    fixed.insert(pos, "comment ");
                    ++k;
                }
                pos = fixed.find('\n', pos);
                if (pos == std::string::npos) break;
                ++pos, ++line;
            }
            static std::atomic<unsigned> counter{0};
            copy = std::filesystem::temp_directory_path() /
                   ("visaudit-ply-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + ".ply");
            std::ofstream(copy, std::ios::binary) << fixed;
            readPath = copy.string();
        }
        try {
            ok = OpenMesh::IO::IOManager().read(readPath, rec, opt);
        } catch (const std::exception &e) {
            ok = false;
            log += std::string("exception: ") + e.what();
        }
        if (!copy.empty()) {
            std::error_code ec;
            std::filesystem::remove(copy, ec);
        }
        std::string t = capture.text();
        if (!t.empty()) log = log.empty() ? t : t + "; " + log;
    }
    if (!plySkipped.empty())
        m.warnings.push_back(path + ": " + std::to_string(plySkipped.size()) +
                             " header line(s) that are not PLY keywords skipped, as the reference readers do (the "
                             "first: line " + std::to_string(plySkipped[0].first) + ", '" + plySkipped[0].second + "')");
    // Collapse the reader's log into one line for our messages, and keep it short (a reader may log
    // once per bad face).
    for (auto &c : log)
        if (c == '\n' || c == '\r') c = ' ';
    if (log.size() > 400) log = log.substr(0, 400) + "...";

    if (!ok)
        return fail(path + ": OpenMesh's " + ext.substr(1) + " reader could not read the file" +
                    (log.empty() ? std::string() : " (reader said: " + log + ")") +
                    "; check that it is a valid " + ext.substr(1) + " file");

    // Our own checks where the readers are silent, and faces the reader never handed over (see the
    // header comment): those are counted as dropped.
    uint64_t inFile = m.facesRead;
    if (ext == ".stl") {
        inFile = std::max<uint64_t>(inFile, stlFacets);
    } else if (ext == ".obj" || ext == ".off") {
        if (ext == ".obj") {
            uint64_t faceLines = 0;
            if (!checkObj(path, text, m.positions.size(), &faceLines, err)) return false;
            inFile = std::max<uint64_t>(inFile, faceLines);
        } else if (!checkOff(path, text, m.positions.size(), m.facesRead, err)) {
            return false;
        }
    }
    if (inFile > m.facesRead) {
        const uint64_t skipped = inFile - m.facesRead;
        m.facesDropped += skipped;
        m.facesRead = inFile;
        m.warnings.push_back(path + ": " + std::to_string(skipped) + " face(s) skipped by OpenMesh's " +
                             ext.substr(1) + " reader (" +
                             (ext == ".stl" ? std::string("facets with repeated vertices") +
                                                  (firstDegenerateFacet >= 0 ? ", the first: facet " +
                                                                                   std::to_string(firstDegenerateFacet) +
                                                                                   " (counting from 0)"
                                                                             : std::string())
                                            : std::string("faces with repeated or out-of-range vertex indices")) +
                             "), counted as dropped");
    }
    if (rec.badIndexFaces)
        return fail(path + ": face " + std::to_string(rec.badFace.face) + " (counting from 0) has vertex index " +
                    std::to_string(rec.badFace.index) + ", out of range (the file has " +
                    std::to_string(rec.badFace.vertices) + " vertices); fix the index or add the vertex");
    // A NaN or infinite coordinate means a damaged file (NaN passes every range test downstream).
    for (size_t i = 0; i < m.positions.size(); ++i)
        if (!isFinite(m.positions[i])) {
            char c[96];
            std::snprintf(c, sizeof c, "%g, %g, %g", m.positions[i].x, m.positions[i].y, m.positions[i].z);
            return fail(path + ": vertex " + std::to_string(i) + " (counting from 0) has a non-finite coordinate (" + c +
                        "); the file is damaged: write finite numbers");
        }
    if (rec.tooFewFaces)
        m.warnings.push_back(path + ": " + std::to_string(rec.tooFewFaces) +
                             " face(s) with fewer than 3 distinct vertices dropped (the first: face " +
                             std::to_string(rec.firstTooFew) + ", counting from 0)");
    if (!log.empty())
        m.warnings.push_back(path + ": reader said: " + log);
    if (m.positions.size() > std::numeric_limits<uint32_t>::max())
        return fail(path + ": more than 4294967295 vertices; visaudit's indices are 32-bit");
    if (m.facesRead == 0 && m.positions.empty())
        return fail(path + ": no vertices and no faces found; is this really a " + ext.substr(1) + " file?" +
                    (log.empty() ? std::string() : " (reader said: " + log + ")"));
    *out = std::move(m);
    return true;
}

}  // namespace va
