// The BSP tree (bsp_tree.h; docs/ordering.md). The only translation unit of the ordering work
// that includes CGAL: everything else asks orient3d().
#include "analysis/audits/bsp_tree.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

#include <tbb/parallel_for.h>

#include "render/stopwatch.h"

namespace va {

namespace {
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
constexpr uint32_t kInputVertex = std::numeric_limits<uint32_t>::max();

K::Point_3 P(Vec3 v) { return K::Point_3(v.x, v.y, v.z); }

// Candidate scorings (candidates x sampled pieces) from which a node scores its candidates in
// parallel: below, a task costs more than it saves.
constexpr size_t kParallelScoring = 1024;

// Side of a piece with respect to a plane.
enum Side : uint8_t { kCoplanar, kFront, kBack, kStraddle };

struct Builder {
    const Scene &scene;
    const BspSettings &settings;
    BspTree &tree;
    std::vector<uint32_t> vertexTag;  // per tree vertex: the node whose split made it, or kInputVertex
    uint64_t predicates = 0;
    // chooseSplitter's sampled pieces: their points as arrays of coordinates, and per piece its
    // source, whether it was split, and where its points start (first[j + 1]: where they end).
    struct SampleSoA {
        std::vector<double> x, y, z;
        std::vector<uint32_t> source, first;
        std::vector<uint8_t> split;
        void clear() { x.clear(), y.clear(), z.clear(), source.clear(), first.clear(), split.clear(); }
        void add(Vec3 p) { x.push_back(p.x), y.push_back(p.y), z.push_back(p.z); }
    } sample;

    Vec3 sourceVertex(uint32_t s, int i) const { return scene.positions[scene.indices[3 * size_t(s) + i]]; }

    // Exact side of tree vertex v against the plane of source triangle s used at node `node`:
    // a vertex made by that node's split is on it by construction.
    int vertexSide(uint32_t v, uint32_t node, const PlaneSide &plane, uint64_t &count) const {
        if (vertexTag[v] == node) return 0;
        ++count;
        return plane(tree.vertices[v]);
    }

    // The classification rule, over sides given by functions (classify asks the plane; the
    // splitter's scoring reads signs computed ahead): a piece of the plane's own source is coplanar;
    // a split piece's coplanarity is decided on its source's input vertices (exact), not on its
    // constructed ones (rounded) -- sourceSide(i), i < 3, each counted in `count`; otherwise the
    // sides of its vertices, vertexSide(i), i < vertexCount (which count themselves).
    template <class SourceSide, class VertexSide>
    static Side classifyBy(bool planeSource, bool split, uint32_t vertexCount, SourceSide &&sourceSide,
                           VertexSide &&vertexSide, uint64_t &count) {
        if (planeSource) return kCoplanar;
        if (split) {
            bool allOn = true;
            for (int i = 0; i < 3 && allOn; ++i) {
                ++count;
                allOn = sourceSide(i) == 0;
            }
            if (allOn) return kCoplanar;
        }
        bool front = false, back = false;
        for (uint32_t i = 0; i < vertexCount; ++i) {
            const int sd = vertexSide(i);
            front |= sd > 0;
            back |= sd < 0;
        }
        if (front && back) return kStraddle;
        if (front) return kFront;
        if (back) return kBack;
        return kCoplanar;
    }

    // Classifies piece p against the plane of source s (node `node`), sides per vertex into `sides`.
    // `count` adds the predicates evaluated (BspStats::predicateCalls).
    Side classify(uint32_t p, uint32_t s, uint32_t node, const PlaneSide &plane, int *sides, uint64_t &count) const {
        const BspPiece &pc = tree.pieces[p];
        return classifyBy(
            pc.source == s, pc.constraintCount != 0, pc.vertexCount,
            [&](int i) { return plane(sourceVertex(pc.source, i)); },
            [&](uint32_t i) { return sides[i] = vertexSide(pc.firstVertex + i, node, plane, count); }, count);
    }

    // The point where segment a-b crosses the plane (n, through q), in double, computed from the
    // lexicographically smaller endpoint so that two pieces sharing the edge get the same point.
    static Vec3 crossing(Vec3 a, Vec3 b, Vec3 n, Vec3 q) {
        const bool swap = b.x < a.x || (b.x == a.x && (b.y < a.y || (b.y == a.y && b.z < a.z)));
        if (swap) std::swap(a, b);
        const double da = dot(n, a - q), db = dot(n, b - q);
        const double den = da - db;
        // The exact predicate says a and b lie strictly on opposite sides; in double da, db may
        // round towards zero, so t is clamped into [0, 1].
        double t = den != 0 ? da / den : 0.5;
        t = std::clamp(t, 0.0, 1.0);
        return a + (b - a) * t;
    }

    // Splits piece p (straddling, vertex sides given) by node `node`'s plane into a front and a back
    // piece, appended to tree.pieces; returns their indices.
    std::pair<uint32_t, uint32_t> split(uint32_t p, uint32_t node, const Vec3 abc[3], const int *sides) {
        const BspPiece pc = tree.pieces[p];
        const Vec3 n = cross(abc[1] - abc[0], abc[2] - abc[0]);
        std::vector<uint32_t> fv, bv;
        for (uint32_t i = 0; i < pc.vertexCount; ++i) {
            const uint32_t j = (i + 1) % pc.vertexCount;
            const uint32_t vi = pc.firstVertex + i, vj = pc.firstVertex + j;
            if (sides[i] >= 0) fv.push_back(vi);
            if (sides[i] <= 0) bv.push_back(vi);
            if (sides[i] * sides[j] < 0) {
                const Vec3 x = crossing(tree.vertices[vi], tree.vertices[vj], n, abc[0]);
                const uint32_t nv = uint32_t(tree.vertices.size());
                tree.vertices.push_back(x);
                vertexTag.push_back(node);
                fv.push_back(nv);
                bv.push_back(nv);
            }
        }
        auto make = [&](const std::vector<uint32_t> &vs, bool front) {
            BspPiece q;
            q.source = pc.source;
            // Copy the vertex run so a piece's vertices stay contiguous (the originals stay shared
            // by value: same doubles, same tags).
            q.firstVertex = uint32_t(tree.vertices.size());
            q.vertexCount = uint32_t(vs.size());
            for (uint32_t v : vs) {
                tree.vertices.push_back(tree.vertices[v]);
                vertexTag.push_back(vertexTag[v]);
            }
            q.firstConstraint = uint32_t(tree.constraints.size());
            q.constraintCount = pc.constraintCount + 1;
            for (uint32_t c = 0; c < pc.constraintCount; ++c)
                tree.constraints.push_back(tree.constraints[pc.firstConstraint + c]);
            tree.constraints.push_back({node, front});
            tree.pieces.push_back(q);
            return uint32_t(tree.pieces.size() - 1);
        };
        const uint32_t f = make(fv, true);
        const uint32_t b = make(bv, false);
        return {f, b};
    }

    void source3(uint32_t s, Vec3 abc[3]) const {
        for (int i = 0; i < 3; ++i) abc[i] = sourceVertex(s, i);
    }

    // Picks the splitter for a node's pieces: `candidates` pieces evenly spread over the list, each
    // scored over at most `scoreSample` pieces, also evenly spread (all of them for small nodes):
    // the score estimates the split count and the imbalance at a bounded cost per node.
    uint32_t chooseSplitter(const std::vector<uint32_t> &list) {
        const size_t n = list.size();
        const size_t k = settings.candidates == 0 ? n : std::min<size_t>(settings.candidates, n);
        if (k <= 1) return list[0];
        const size_t m = settings.scoreSample == 0 ? n : std::min<size_t>(settings.scoreSample, n);
        // The sampled pieces' points, gathered once for every candidate: their vertices, and for a
        // split piece first its source's three input vertices (classifyBy's coplanarity check). No
        // vertex was made by this node's split yet, so classify would test every one of them.
        SampleSoA &g = sample;
        g.clear();
        for (size_t j = 0; j < m; ++j) {
            const BspPiece &pc = tree.pieces[list[(j * n) / m]];
            g.source.push_back(pc.source);
            g.split.push_back(pc.constraintCount != 0);
            g.first.push_back(uint32_t(g.x.size()));
            if (pc.constraintCount)
                for (int i = 0; i < 3; ++i) g.add(sourceVertex(pc.source, i));
            for (uint32_t i = 0; i < pc.vertexCount; ++i) g.add(tree.vertices[pc.firstVertex + i]);
        }
        g.first.push_back(uint32_t(g.x.size()));
        // The candidates are scored independently (in parallel when there is enough work: the
        // nodes near the root), then the first with the lowest score wins, as in a serial loop.
        std::vector<double> score(k);
        std::vector<uint64_t> count(k, 0);
        auto scoreCandidate = [&](size_t c) {
            const uint32_t cand = list[(c * n) / k];
            const uint32_t candSource = tree.pieces[cand].source;
            Vec3 abc[3];
            source3(candSource, abc);
            const PlaneSide plane(abc[0], abc[1], abc[2]);
            thread_local std::vector<int32_t> signs;
            signs.resize(g.x.size());
            plane.filterSigns(g.x.data(), g.y.data(), g.z.data(), g.x.size(), signs.data());
            auto sideOf = [&](uint32_t i) {
                if (signs[i] == 2) signs[i] = plane.undecided({g.x[i], g.y[i], g.z[i]});
                return signs[i];
            };
            uint64_t front = 0, back = 0, splits = 0, predicates = 0;
            for (size_t j = 0; j < m; ++j) {
                const uint32_t first = g.first[j], vertices = g.first[j + 1] - first - (g.split[j] ? 3 : 0);
                const uint32_t firstVertex = first + (g.split[j] ? 3 : 0);
                const Side side = classifyBy(
                    g.source[j] == candSource, g.split[j] != 0, vertices,
                    [&](int i) { return sideOf(first + uint32_t(i)); },
                    [&](uint32_t i) {
                        ++predicates;
                        return sideOf(firstVertex + i);
                    },
                    predicates);
                front += side == kFront || side == kStraddle;
                back += side == kBack || side == kStraddle;
                splits += side == kStraddle;
            }
            count[c] = predicates;
            score[c] = settings.splitWeight * double(splits) + settings.balanceWeight * std::fabs(double(front) - double(back));
        };
        if (k * m >= kParallelScoring)
            tbb::parallel_for(size_t(0), k, scoreCandidate);
        else
            for (size_t c = 0; c < k; ++c) scoreCandidate(c);
        double best = std::numeric_limits<double>::infinity();
        uint32_t bestPiece = list[0];
        for (size_t c = 0; c < k; ++c) {
            predicates += count[c];
            if (score[c] < best) {
                best = score[c];
                bestPiece = list[(c * n) / k];
            }
        }
        return bestPiece;
    }

    void build(std::vector<uint32_t> rootList) {
        // A node to build: its pieces, its parent (by index: `nodes` reallocates) and which child.
        struct Work {
            int32_t parent;       // -1 for the root
            bool frontChild;
            std::vector<uint32_t> list;
            uint32_t depth;
        };
        std::vector<Work> stack;
        if (rootList.empty()) return;
        stack.push_back({-1, false, std::move(rootList), 1});
        uint64_t leafDepthSum = 0, leaves = 0;
        std::vector<int> sides;
        while (!stack.empty()) {
            Work w = std::move(stack.back());
            stack.pop_back();
            const uint32_t node = uint32_t(tree.nodes.size());
            tree.nodes.push_back({});
            if (w.parent >= 0) {
                BspTreeNode &par = tree.nodes[size_t(w.parent)];
                (w.frontChild ? par.front : par.back) = int32_t(node);
            }
            tree.stats.depth = std::max(tree.stats.depth, w.depth);

            const uint32_t splitter = chooseSplitter(w.list);
            const uint32_t s = tree.pieces[splitter].source;
            Vec3 abc[3];
            source3(s, abc);
            const PlaneSide plane(abc[0], abc[1], abc[2]);
            tree.nodes[node].planeSource = s;
            tree.nodes[node].firstPiece = uint32_t(tree.nodePieces.size());
            std::vector<uint32_t> front, back;
            for (uint32_t p : w.list) {
                sides.assign(tree.pieces[p].vertexCount, 0);
                switch (classify(p, s, node, plane, sides.data(), predicates)) {
                    case kCoplanar: tree.nodePieces.push_back(p); break;
                    case kFront: front.push_back(p); break;
                    case kBack: back.push_back(p); break;
                    case kStraddle: {
                        const auto [f, b] = split(p, node, abc, sides.data());
                        ++tree.stats.splits;
                        front.push_back(f);
                        back.push_back(b);
                        break;
                    }
                }
            }
            tree.nodes[node].pieceCount = uint32_t(tree.nodePieces.size()) - tree.nodes[node].firstPiece;
            if (front.empty() && back.empty()) {
                leafDepthSum += w.depth;
                ++leaves;
            }
            if (!back.empty()) stack.push_back({int32_t(node), false, std::move(back), w.depth + 1});
            if (!front.empty()) stack.push_back({int32_t(node), true, std::move(front), w.depth + 1});
        }
        tree.stats.averageLeafDepth = leaves ? double(leafDepthSum) / double(leaves) : 0;
    }
};

double area2(const BspTree &t, const BspPiece &p) {
    // Twice the area of the convex polygon (fan from vertex 0), in double.
    Vec3 sum{};
    const Vec3 o = t.vertices[p.firstVertex];
    for (uint32_t i = 1; i + 1 < p.vertexCount; ++i)
        sum = sum + cross(t.vertices[p.firstVertex + i] - o, t.vertices[p.firstVertex + i + 1] - o);
    return length(sum);
}

}  // namespace

namespace {

// Whether the rounded difference x = fl(h - l) is exact: Knuth's TwoSum error of x + l, which is
// exact (no overflow at level magnitudes), is 0 and x + l == h (Shewchuk's Two_Diff_Tail).
bool differenceIsExact(double h, double l, double x) {
    const double bvirt = h - x, avirt = x + bvirt;
    const double bround = bvirt - l, around = h - avirt;
    return around + bround == 0;
}

// The exponent of the lowest set bit of finite nonzero v's significand: v = m 2^k with m odd.
int lowestBitExponent(double v) {
    int k;
    const double m = std::frexp(v, &k);                   // v = m 2^k, 0.5 <= |m| < 1
    const uint64_t bits = uint64_t(std::fabs(std::ldexp(m, 53)));  // 53-bit integer significand
    return k - 53 + std::countr_zero(bits);
}

// Sign of det[b - a, c - a, d - a] when the twelve coordinates are integer multiples of one power
// of two 2^e below 2^61 in magnitude -- as a level's grid coordinates together with the points its
// BSP splits construct near them are -- or 2 when they are not (or one is subnormal or not finite).
// The coordinates' integers X (exact: a power-of-two scale) differ by less than 2^62, so the nine
// differences are exact in 64 bits, the three 2x2 minors (below 2^125) in 128, and each row entry
// times its minor is summed in 192 bits as (high 128) * 2^64 + (low 64): the determinant of the
// integers, whose sign is the sign sought (it is 2^-3e times the real one).
int orientScaledIntegers(const double c[12]) {
    int lo = INT32_MAX, hi = INT32_MIN;
    int exponent[12];
    uint64_t significand[12];
    for (int i = 0; i < 12; ++i) {
        significand[i] = 0;
        if (c[i] == 0) continue;
        const uint64_t bits = std::bit_cast<uint64_t>(c[i]);
        const int biased = int((bits >> 52) & 0x7FF);
        if (biased == 0 || biased == 0x7FF) return 2;
        significand[i] = (bits & ((uint64_t(1) << 52) - 1)) | (uint64_t(1) << 52);
        exponent[i] = biased - 1075;  // c = +-significand * 2^exponent
        lo = std::min(lo, exponent[i] + std::countr_zero(significand[i]));
        hi = std::max(hi, exponent[i] + 52);
    }
    if (lo == INT32_MAX) return 0;  // all twelve zero
    if (hi - lo > 60) return 2;     // some |X| would reach 2^61
    int64_t X[12];
    for (int i = 0; i < 12; ++i) {
        if (!significand[i]) {
            X[i] = 0;
            continue;
        }
        const int shift = exponent[i] - lo;  // >= -(trailing zeros): a right shift drops only zeros
        const uint64_t m = shift >= 0 ? significand[i] << shift : significand[i] >> -shift;
        X[i] = c[i] < 0 ? -int64_t(m) : int64_t(m);
    }
    const int64_t r[9] = {X[3] - X[0], X[4] - X[1], X[5] - X[2], X[6] - X[0], X[7] - X[1],
                          X[8] - X[2], X[9] - X[0], X[10] - X[1], X[11] - X[2]};
    using I128 = __int128;
    const I128 minor[3] = {I128(r[4]) * r[8] - I128(r[5]) * r[7], I128(r[5]) * r[6] - I128(r[3]) * r[8],
                           I128(r[3]) * r[7] - I128(r[4]) * r[6]};
    I128 high = 0;             // |high| < 2^126
    unsigned __int128 low = 0;  // three values below 2^64
    for (int k = 0; k < 3; ++k) {
        const int64_t mh = int64_t(minor[k] >> 64);  // minor = mh * 2^64 + ml, |mh| <= 2^61
        const uint64_t ml = uint64_t(minor[k]);
        const I128 t = I128(r[k]) * I128(ml);         // below 2^126 in magnitude
        high += I128(r[k]) * mh + (t >> 64);
        low += uint64_t(t);
    }
    high += I128(low >> 64);
    if (high != 0) return high > 0 ? 1 : -1;
    return uint64_t(low) != 0 ? 1 : 0;
}

// orient3d after its filter (or PlaneSide's, the same expansion along another row) could not tell.
int orient3dExact(Vec3 a, Vec3 b, Vec3 c, Vec3 d) {
    const double r1x = b.x - a.x, r1y = b.y - a.y, r1z = b.z - a.z;
    const double r2x = c.x - a.x, r2y = c.y - a.y, r2z = c.z - a.z;
    const double r3x = d.x - a.x, r3y = d.y - a.y, r3z = d.z - a.z;
    // Exact zeros the filter cannot see (its bound is 0 or the terms cancel), common in levels:
    // d equal to a corner, and every term of the expansion holding a factor that is exactly zero
    // (a difference of doubles is 0 only when they are equal, so the exact difference is 0 too),
    // as for four points on one axis-aligned plane. Then the exact determinant is 0.
    if (d == a || d == b || d == c) return 0;
    const bool z1 = r2y == 0 || r3z == 0, z2 = r2z == 0 || r3y == 0, z3 = r2z == 0 || r3x == 0,
               z4 = r2x == 0 || r3z == 0, z5 = r2x == 0 || r3y == 0, z6 = r2y == 0 || r3x == 0;
    if ((r1x == 0 || (z1 && z2)) && (r1y == 0 || (z3 && z4)) && (r1z == 0 || (z5 && z6))) return 0;
    {
        const double coords[12] = {a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z, d.x, d.y, d.z};
        const int sign = orientScaledIntegers(coords);
        if (sign != 2) return sign;
    }
    // Integer stage: when the nine differences are exact and are integer multiples of one power of
    // two 2^e with quotients below 2^40 in magnitude -- as level coordinates on a grid, or floats of
    // similar size, are -- the determinant of the quotients is exact in 128-bit integers (products
    // of three below 2^120, six of them below 2^123), and its sign is the sign sought.
    {
        const double r[9] = {r1x, r1y, r1z, r2x, r2y, r2z, r3x, r3y, r3z};
        const double hi[9] = {b.x, b.y, b.z, c.x, c.y, c.z, d.x, d.y, d.z};
        const double lo[3] = {a.x, a.y, a.z};
        bool exact = true;
        int e = INT32_MAX;
        for (int i = 0; i < 9 && exact; ++i) {
            exact = differenceIsExact(hi[i], lo[i % 3], r[i]);
            if (r[i] != 0) e = std::min(e, lowestBitExponent(r[i]));
        }
        if (exact) {
            __int128 q[9];
            for (int i = 0; i < 9 && exact; ++i) {
                const double v = std::ldexp(r[i], -e);  // an integer: exact (a power-of-two scale)
                exact = std::fabs(v) < 0x1p40;
                q[i] = exact ? __int128(int64_t(v)) : 0;
            }
            if (exact) {
                const __int128 det128 = q[0] * (q[4] * q[8] - q[5] * q[7]) + q[1] * (q[5] * q[6] - q[3] * q[8]) +
                                        q[2] * (q[3] * q[7] - q[4] * q[6]);
                return det128 > 0 ? 1 : (det128 < 0 ? -1 : 0);
            }
        }
    }
    // CGAL::orientation(p, q, r, s) is the sign of det[q - p, r - p, s - p] (POSITIVE when s is on
    // the side the counter-clockwise normal of (p, q, r) points to; tested in BspTree.Orient3d*).
    const CGAL::Orientation o = CGAL::orientation(P(a), P(b), P(c), P(d));
    return o == CGAL::POSITIVE ? 1 : (o == CGAL::NEGATIVE ? -1 : 0);
}

}  // namespace

int orient3d(Vec3 a, Vec3 b, Vec3 c, Vec3 d) {
    // Static filter first (Shewchuk's orient3d, stage A): with the three rows as rounded
    // differences r1 = b - a, r2 = c - a, r3 = d - a, the double determinant r1 . (r2 x r3) is
    // within (7 + 56 eps) eps * permanent of the exact one, eps = 2^-53, permanent = the same
    // expansion with every product in absolute value (the bound covers the rounded differences).
    // Only when the sign is not certain do the exact stages (orient3dExact) decide.
    const double r1x = b.x - a.x, r1y = b.y - a.y, r1z = b.z - a.z;
    const double r2x = c.x - a.x, r2y = c.y - a.y, r2z = c.z - a.z;
    const double r3x = d.x - a.x, r3y = d.y - a.y, r3z = d.z - a.z;
    const double m1 = r2y * r3z, m2 = r2z * r3y, m3 = r2z * r3x, m4 = r2x * r3z, m5 = r2x * r3y, m6 = r2y * r3x;
    const double det = r1x * (m1 - m2) + r1y * (m3 - m4) + r1z * (m5 - m6);
    const double permanent = std::fabs(r1x) * (std::fabs(m1) + std::fabs(m2)) +
                             std::fabs(r1y) * (std::fabs(m3) + std::fabs(m4)) +
                             std::fabs(r1z) * (std::fabs(m5) + std::fabs(m6));
    constexpr double eps = 0x1p-53;
    const double bound = (7.0 + 56.0 * eps) * eps * permanent;
    if (det > bound) return 1;
    if (det < -bound) return -1;
    return orient3dExact(a, b, c, d);
}

PlaneSide::PlaneSide(Vec3 a, Vec3 b, Vec3 c) : a_(a), b_(b), c_(c) {
    for (int k = 0; k < 3 && axis_ < 0; ++k)
        if (a[k] == b[k] && a[k] == c[k]) axis_ = k;
    if (axis_ >= 0) {
        // det[b - a, c - a, d - a] with the axis column of the first two rows exactly zero is
        // (d - a)[axis] times the cofactor of that entry; its sign is orient3d's at a point just
        // beyond a on the axis (the next double up: d - a > 0 exactly there).
        Vec3 e = a;
        e[axis_] = std::nextafter(a[axis_], std::numeric_limits<double>::infinity());
        axisSign_ = orient3d(a, b, c, e);
        return;
    }
    // orient3d's stage A with r3 = d - a outside and the minors of r1 = b - a, r2 = c - a: the
    // same expansion along another row, so the same bound, (7 + 56 eps) eps * permanent.
    const double r1x = b.x - a.x, r1y = b.y - a.y, r1z = b.z - a.z;
    const double r2x = c.x - a.x, r2y = c.y - a.y, r2z = c.z - a.z;
    const double p1 = r1y * r2z, p2 = r1z * r2y, p3 = r1z * r2x, p4 = r1x * r2z, p5 = r1x * r2y, p6 = r1y * r2x;
    n_[0] = p1 - p2, n_[1] = p3 - p4, n_[2] = p5 - p6;
    m_[0] = std::fabs(p1) + std::fabs(p2), m_[1] = std::fabs(p3) + std::fabs(p4), m_[2] = std::fabs(p5) + std::fabs(p6);
}

int PlaneSide::undecided(Vec3 d) const { return orient3dExact(a_, b_, c_, d); }

namespace {

// PlaneSide::filterSigns's loops, built twice (AVX2 and the baseline; the first call picks by the
// CPU): the same operations per point either way (no FMA: -ffp-contract=off).
__attribute__((target_clones("avx2", "default")))
void filterSignsLoop(const double *x, const double *y, const double *z, size_t n, int32_t *out, int axis, int axisSign,
                     Vec3 a, const double *nv, const double *mv) {
    if (axis >= 0) {
        const double *c = axis == 0 ? x : (axis == 1 ? y : z);
        const double k = a[axis];
        for (size_t i = 0; i < n; ++i) out[i] = axisSign * (int32_t(c[i] > k) - int32_t(c[i] < k));
        return;
    }
    for (size_t i = 0; i < n; ++i) out[i] = PlaneSide::filterSign(x[i] - a.x, y[i] - a.y, z[i] - a.z, nv, mv);
}

}  // namespace

void PlaneSide::filterSigns(const double *x, const double *y, const double *z, size_t n, int32_t *out) const {
    filterSignsLoop(x, y, z, n, out, axis_, axisSign_, a_, n_, m_);
}

BspTree buildBspTree(const Scene &scene, const std::vector<uint32_t> &triangles, const BspSettings &settings) {
    const Stopwatch t0;
    BspTree tree;
    Builder b{scene, settings, tree, {}, 0, {}};
    std::vector<uint32_t> list;
    list.reserve(triangles.size());
    for (uint32_t t : triangles) {
        BspPiece p;
        p.source = t;
        p.firstVertex = uint32_t(tree.vertices.size());
        p.vertexCount = 3;
        for (int i = 0; i < 3; ++i) {
            tree.vertices.push_back(scene.positions[scene.indices[3 * size_t(t) + i]]);
            b.vertexTag.push_back(kInputVertex);
        }
        list.push_back(uint32_t(tree.pieces.size()));
        tree.pieces.push_back(p);
    }
    b.build(std::move(list));

    // Stats: the pieces that ended in nodes are the tree's pieces (split parents are not).
    BspStats &st = tree.stats;
    st.trianglesIn = triangles.size();
    st.nodes = tree.nodes.size();
    st.pieces = tree.nodePieces.size();
    std::vector<uint8_t> splitSource(scene.triangleCount(), 0);
    for (uint32_t p : tree.nodePieces) {
        const BspPiece &pc = tree.pieces[p];
        st.trianglesOut += pc.vertexCount - 2;
        if (pc.constraintCount) {
            splitSource[pc.source] = 1;
            if (area2(tree, pc) == 0) ++st.degeneratePieces;
        }
    }
    for (uint8_t s : splitSource) st.splitSources += s;
    st.predicateCalls = b.predicates;
    st.memoryBytes = tree.nodes.size() * sizeof(BspTreeNode) + tree.pieces.size() * sizeof(BspPiece) +
                     tree.nodePieces.size() * sizeof(uint32_t) + tree.vertices.size() * sizeof(Vec3) +
                     tree.constraints.size() * sizeof(BspConstraint);
    st.buildMs = t0.ms();
    return tree;
}

BspTree buildBspTree(const Scene &scene, const BspSettings &settings) {
    std::vector<uint32_t> all;
    all.reserve(scene.triangleCount());
    for (uint32_t t = 0; t < scene.triangleCount(); ++t)
        if (scene.triangleObject[t] != kExcludedTriangle) all.push_back(t);
    return buildBspTree(scene, all, settings);
}

std::vector<uint32_t> bspBackToFront(const BspTree &tree, const Scene &scene, const Camera &cam) {
    std::vector<uint32_t> order;
    order.reserve(tree.nodePieces.size());
    if (tree.nodes.empty()) return order;
    // Explicit stack of (node, stage): stage 0 = first visit, 1 = far side done (emit the node's
    // pieces, then the near side).
    struct Item {
        int32_t node;
        int stage;
        bool eyeFront;
    };
    std::vector<Item> stack{{0, 0, false}};
    while (!stack.empty()) {
        Item it = stack.back();
        stack.pop_back();
        const BspTreeNode &n = tree.nodes[size_t(it.node)];
        if (it.stage == 0) {
            const uint32_t s = n.planeSource;
            const Vec3 a = scene.positions[scene.indices[3 * size_t(s)]];
            const Vec3 b = scene.positions[scene.indices[3 * size_t(s) + 1]];
            const Vec3 c = scene.positions[scene.indices[3 * size_t(s) + 2]];
            int side;
            if (cam.orthographic) {
                // The eye at infinity behind the view direction: the front side faces it when the
                // plane's normal points against the view direction (edge-on: either order is right).
                const double v = -dot(cross(b - a, c - a), cam.forward);
                side = v > 0 ? 1 : (v < 0 ? -1 : 0);
            } else {
                side = orient3d(a, b, c, cam.eye);
            }
            // Eye in front (or on the plane: the two sides then project to disjoint regions):
            // the back side is far.
            const bool eyeFront = side >= 0;
            const int32_t far = eyeFront ? n.back : n.front;
            stack.push_back({it.node, 1, eyeFront});
            if (far >= 0) stack.push_back({far, 0, false});
        } else {
            for (uint32_t i = 0; i < n.pieceCount; ++i) order.push_back(tree.nodePieces[n.firstPiece + i]);
            const int32_t nearChild = it.eyeFront ? n.front : n.back;
            if (nearChild >= 0) stack.push_back({nearChild, 0, false});
        }
    }
    return order;
}

BspViewPlanes bspViewPlanes(const BspTree &tree, const Scene &scene, const Camera &cam) {
    // World plane n.p_w + k = 0 through the source's vertex v0, n = (v1 - v0) x (v2 - v0). With
    // p_w = eye + x right + y up - z forward (viewFromWorld's rows are right, up, -forward):
    //   n.p_w + k = (n.right) x + (n.up) y - (n.forward) z + n.(eye - v0).
    BspViewPlanes vp;
    vp.plane.resize(4 * tree.nodes.size());
    for (size_t i = 0; i < tree.nodes.size(); ++i) {
        const uint32_t s = tree.nodes[i].planeSource;
        const Vec3 a = scene.positions[scene.indices[3 * size_t(s)]];
        const Vec3 b = scene.positions[scene.indices[3 * size_t(s) + 1]];
        const Vec3 c = scene.positions[scene.indices[3 * size_t(s) + 2]];
        const Vec3 n = cross(b - a, c - a);
        vp.plane[4 * i + 0] = dot(n, cam.right);
        vp.plane[4 * i + 1] = dot(n, cam.up);
        vp.plane[4 * i + 2] = -dot(n, cam.forward);
        vp.plane[4 * i + 3] = dot(n, cam.eye - a);
    }
    return vp;
}

}  // namespace va
