// The PVS audit (analysis/audits/pvs_audit.h; docs/pvs-audit.md). Structure:
//   1. Setup: the leafs the world's tree reaches, listed per cluster; the map's box; the opaque
//      triangles (drawn world faces without CONTENTS_TRANSLUCENT) in an Embree scene; the cube of
//      ray directions; the far plane and the tolerance.
//   2. Per cluster, in parallel (each cluster's work depends on nothing but the cluster):
//      a. eye points: a leaf of the cluster drawn by box volume, a point uniform in its box, kept
//         when the tree puts it in a leaf of the cluster and no solid brush of that leaf holds it;
//      b. per eye point, the cube of directions under a seeded random rotation, cast as one Embree
//         stream (rtcIntersect16); each ray then walked through the tree up to its hit;
//      c. the clusters seen compared with the PVS row: misses (with evidence), slack, far plane.
//   3. Totals and histograms in cluster order; the top-down view of the level.
#include "analysis/audits/pvs_audit.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <optional>

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include "analysis/splitmix.h"
#include "render/raycast.h"
#include "render/stopwatch.h"

namespace va {

namespace {

constexpr uint32_t kContentsSolid = 0x1, kContentsPlayerClip = 0x10000, kContentsTranslucent = 0x20000000;
constexpr uint32_t kNoIndex = 0xFFFFFFFFu;

// ---- The walk -----------------------------------------------------------------------------------

// The tree as the walk reads it: each node with its plane inline (one memory access per node).
struct FlatNode {
    Vec3 normal;
    double dist;
    int32_t children[2];
};
std::vector<FlatNode> flatNodes(const BspLevel &lv) {
    std::vector<FlatNode> f(lv.nodes.size());
    for (size_t i = 0; i < f.size(); ++i) {
        const BspPlane &pl = lv.planes[lv.nodes[i].plane];
        f[i] = {pl.normal, pl.dist, {lv.nodes[i].children[0], lv.nodes[i].children[1]}};
    }
    return f;
}
// Per node, dot(n, eye) - dist: the same for every ray from one eye, computed once per eye point.
void nodeDistances(const std::vector<FlatNode> &nodes, Vec3 eye, std::vector<double> *at) {
    at->resize(nodes.size());
    for (size_t i = 0; i < nodes.size(); ++i) (*at)[i] = dot(nodes[i].normal, eye) - nodes[i].dist;
}

// Front-to-back walk of the segment eye + t dir, t in [0, tEnd] (Quake 3's CM_TraceThroughTree
// without the recursion). A node's plane splits the segment where dot(n, p) - dist = at + rate t
// changes sign (at: the eye's value, from nodeDistances; rate = dot(n, dir)); the side holding the
// segment's start is walked first and the other part is pushed. The side of a point is leafAt's:
// dot(n, p) - dist >= 0 is the front, so the first leaf is leafAt(eye). The stack holds at most one
// entry per node on the current path (the tree's depth); nodes come after their parents (checked
// when loading), so every path ends.
struct Segment {
    int32_t node;
    double t0, t1;
};
template <class LeafFn>
void walk(const std::vector<FlatNode> &nodes, const double *eyeAt, bool noLeafs, Vec3 dir, double tEnd,
          std::vector<Segment> &stack, LeafFn &&leaf) {
    if (noLeafs) return;
    if (nodes.empty()) {
        leaf(0, 0.0, tEnd);
        return;
    }
    stack.clear();
    stack.push_back({0, 0.0, tEnd});
    while (!stack.empty()) {
        Segment s = stack.back();
        stack.pop_back();
        int32_t n = s.node;
        while (n >= 0) {
            const FlatNode &node = nodes[size_t(n)];
            const double at = eyeAt[n], rate = dot(node.normal, dir);
            const double d0 = at + rate * s.t0, d1 = at + rate * s.t1;
            if (d0 >= 0 && d1 >= 0) {
                n = node.children[0];
            } else if (d0 < 0 && d1 < 0) {
                n = node.children[1];
            } else {
                // d0 and d1 differ in sign, so rate != 0; the crossing, kept inside [t0, t1].
                const double tm = std::clamp(-at / rate, s.t0, s.t1);
                const int near = d0 >= 0 ? 0 : 1;
                stack.push_back({node.children[1 - near], tm, s.t1});
                n = node.children[near];
                s.t1 = tm;
            }
        }
        if (!leaf(-(n + 1), s.t0, s.t1)) return;
    }
}

// ---- Setup --------------------------------------------------------------------------------------

// A unit quaternion's rotation matrix; the quaternion uniform over rotations (Shoemake's method).
struct Rotation {
    double m[3][3];
    Vec3 apply(Vec3 v) const {
        return {m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z, m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
                m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z};
    }
    static Rotation random(SplitMix64 &rng) {
        const double u1 = rng.unit(), u2 = rng.unit(), u3 = rng.unit();
        const double a = std::sqrt(1 - u1), b = std::sqrt(u1);
        const double x = a * std::sin(2 * kPi * u2), y = a * std::cos(2 * kPi * u2);
        const double z = b * std::sin(2 * kPi * u3), w = b * std::cos(2 * kPi * u3);
        Rotation r;
        r.m[0][0] = 1 - 2 * (y * y + z * z), r.m[0][1] = 2 * (x * y - z * w), r.m[0][2] = 2 * (x * z + y * w);
        r.m[1][0] = 2 * (x * y + z * w), r.m[1][1] = 1 - 2 * (x * x + z * z), r.m[1][2] = 2 * (y * z - x * w);
        r.m[2][0] = 2 * (x * z - y * w), r.m[2][1] = 2 * (y * z + x * w), r.m[2][2] = 1 - 2 * (x * x + y * y);
        return r;
    }
};

// The cube's directions: per face (+x, -x, +y, -y, +z, -z) the centers of an R x R grid on the
// face, normalized; the grid is visited in 4x4 tiles, so that each packet of 16 rays is a small cone.
std::vector<Vec3> cubeDirections(int R) {
    const Vec3 axes[6][3] = {{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}},  {{-1, 0, 0}, {0, -1, 0}, {0, 0, 1}},
                             {{0, 1, 0}, {-1, 0, 0}, {0, 0, 1}}, {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}},
                             {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}},  {{0, 0, -1}, {1, 0, 0}, {0, -1, 0}}};
    std::vector<Vec3> dirs;
    dirs.reserve(size_t(6) * R * R);
    for (const auto &f : axes)
        for (int ty = 0; ty < R; ty += 4)
            for (int tx = 0; tx < R; tx += 4)
                for (int y = ty; y < std::min(R, ty + 4); ++y)
                    for (int x = tx; x < std::min(R, tx + 4); ++x) {
                        const double u = (2 * (x + 0.5)) / R - 1, v = (2 * (y + 0.5)) / R - 1;
                        dirs.push_back(normalize(f[0] + f[1] * u + f[2] * v));
                    }
    return dirs;
}

// Whether a box lies in empty space: every leaf it reaches through the tree has a cluster, and
// no brush of those leafs that stops a player (CONTENTS_SOLID or CONTENTS_PLAYERCLIP) overlaps
// it. The walk is CM_BoxLeafnums' (both children when the box straddles a plane; a box touching
// a plane reaches the leaf on its front, as leafAt does); the overlap test is the engine's
// CM_TestBoxInBrush: the box is clear of a brush when some side's plane has the whole box on or
// in front of it (q3map2 gives every brush its axial and edge bevel sides, which makes the test
// exact for boxes). Touching a solid leaf counts as not free (conservative: rejects more).
bool boxFree(const BspLevel &lv, const Aabb &box, std::vector<int32_t> &stack) {
    const Vec3 c = box.center(), h = box.extent() * 0.5;
    auto leafFree = [&](int32_t leaf) {
        const BspLeaf &l = lv.leafs[size_t(leaf)];
        if (l.cluster < 0) return false;
        for (uint32_t k = 0; k < l.leafBrushCount; ++k) {
            const BspBrush &b = lv.brushes[lv.leafBrushes[l.firstLeafBrush + k]];
            if (!(lv.shaders[b.shader].contents & (kContentsSolid | kContentsPlayerClip))) continue;
            bool separated = false;
            for (uint32_t j = 0; j < b.sideCount && !separated; ++j) {
                const BspPlane &pl = lv.planes[lv.brushSides[b.firstSide + j]];
                const double reach = h.x * std::fabs(pl.normal.x) + h.y * std::fabs(pl.normal.y) +
                                     h.z * std::fabs(pl.normal.z);
                separated = dot(pl.normal, c) - pl.dist - reach >= 0;
            }
            if (!separated) return false;
        }
        return true;
    };
    if (lv.nodes.empty()) return leafFree(0);
    stack.clear();
    stack.push_back(0);
    while (!stack.empty()) {
        const int32_t i = stack.back();
        stack.pop_back();
        if (i < 0) {
            if (!leafFree(-(i + 1))) return false;
            continue;
        }
        const BspNode &n = lv.nodes[size_t(i)];
        const BspPlane &pl = lv.planes[n.plane];
        const double at = dot(pl.normal, c) - pl.dist;
        const double reach = h.x * std::fabs(pl.normal.x) + h.y * std::fabs(pl.normal.y) + h.z * std::fabs(pl.normal.z);
        if (at + reach >= 0) stack.push_back(n.children[0]);
        if (at - reach < 0) stack.push_back(n.children[1]);
    }
    return true;
}

// Quake 3's crouched player (bg_public.h, bg_pmove.c): box mins (-15, -15, -24), maxs (15, 15, 16),
// the eye CROUCH_VIEWHEIGHT = 12 above the origin; relative to the eye, x and y in [-15, 15] and z
// in [-36, 4]. A standing player's box around its eye (z in [-50, 6]) contains it, so wherever a
// player's eye can be, this box is free of solid and player clip.
constexpr double kPlayerHalfWidth = 15, kPlayerBelowEye = 36, kPlayerAboveEye = 4;
Aabb playerBox(Vec3 eye) {
    return {{eye.x - kPlayerHalfWidth, eye.y - kPlayerHalfWidth, eye.z - kPlayerBelowEye},
            {eye.x + kPlayerHalfWidth, eye.y + kPlayerHalfWidth, eye.z + kPlayerAboveEye}};
}

struct Context {
    const Scene &scene;
    const BspLevel &lv;
    const PvsAuditSettings &s;
    RayScene rays;
    Vec3 origin;
    double diagonal = 0, farPlane = 0, tolerance = 0;
    std::vector<uint32_t> clusterLeafsBegin, clusterLeafs;  // CSR: leafs of the tree per cluster
    std::vector<FlatNode> nodes;
    std::vector<Vec3> dirs;
    Context(const Scene &sc, const PvsAuditSettings &st) : scene(sc), lv(*sc.bsp), s(st) {}

    bool inSolidBrush(int32_t leaf, Vec3 p) const {
        const BspLeaf &l = lv.leafs[size_t(leaf)];
        for (uint32_t k = 0; k < l.leafBrushCount; ++k) {
            const BspBrush &b = lv.brushes[lv.leafBrushes[l.firstLeafBrush + k]];
            if (!(lv.shaders[b.shader].contents & kContentsSolid)) continue;
            bool inside = true;
            for (uint32_t j = 0; j < b.sideCount && inside; ++j) {
                const BspPlane &pl = lv.planes[lv.brushSides[b.firstSide + j]];
                inside = dot(pl.normal, p) - pl.dist <= 0;  // on a side counts as inside (rejected)
            }
            if (inside) return true;
        }
        return false;
    }
    bool pvsBit(int32_t from, int32_t to) const { return lv.clusterVisible(from, to); }
};


constexpr uint8_t kWithin = 1, kBeyond = 2, kPlayer = 4;

// Per-thread scratch, reused from cluster to cluster.
struct Scratch {
    std::vector<uint8_t> flag;        // per cluster: kWithin | kBeyond | kPlayer
    std::vector<uint64_t> rays;       // per cluster: rays that saw it within the far plane
    std::vector<uint64_t> lastRay;    // per cluster: 1 + the index of the last ray that did (0: none yet)
    std::vector<int32_t> evidence;    // per cluster: index into misses, -1 none
    std::vector<int32_t> touched;
    std::vector<int32_t> updated;
    std::vector<LocalRay> batch;
    std::vector<Vec3> dirs;
    std::vector<LocalHit> hits;
    std::vector<Segment> stack;
    std::vector<double> eyeAt;        // per node: the eye point's dot(n, eye) - dist
    std::vector<int32_t> boxStack;
    std::vector<double> weights;
    std::vector<PvsMiss> misses;
    double sampleMs = 0, castMs = 0, walkMs = 0;
};

double msBetween(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
    return std::chrono::duration<double, std::milli>(b - a).count();
}

// ---- One cluster --------------------------------------------------------------------------------

// a. Eye points in cluster c (its leafs lb..le of cx.clusterLeafs), drawn by box volume (all
// equally when every box is flat), outside other clusters and solid brushes.
void sampleEyes(const Context &cx, int32_t c, uint32_t lb, uint32_t le, SplitMix64 &rng, Scratch &sc,
                PvsClusterAudit &r) {
    const BspLevel &lv = cx.lv;
    sc.weights.clear();
    double total = 0;
    for (uint32_t k = lb; k < le; ++k) {
        const Vec3 e = lv.leafs[cx.clusterLeafs[k]].bounds.extent();
        total += std::max(0.0, e.x) * std::max(0.0, e.y) * std::max(0.0, e.z);
        sc.weights.push_back(total);
    }
    const uint32_t maxAttempts = uint32_t(cx.s.samples) * kPvsAttemptsPerSample;
    while (r.leafs > 0 && r.eyes.size() < size_t(cx.s.samples) && r.attempts < maxAttempts) {
        ++r.attempts;
        uint32_t k;
        if (total > 0) {
            const double pick = rng.unit() * total;
            k = uint32_t(std::upper_bound(sc.weights.begin(), sc.weights.end(), pick) - sc.weights.begin());
            k = std::min(k, r.leafs - 1);
        } else {
            k = uint32_t(rng.below(r.leafs));
        }
        const Aabb &b = lv.leafs[cx.clusterLeafs[lb + k]].bounds;
        const double ux = rng.unit(), uy = rng.unit(), uz = rng.unit();
        const Vec3 p{b.lo.x + ux * (b.hi.x - b.lo.x), b.lo.y + uy * (b.hi.y - b.lo.y), b.lo.z + uz * (b.hi.z - b.lo.z)};
        const int32_t at = lv.leafAt(p);
        if (at < 0 || lv.leafs[size_t(at)].cluster != c) {
            ++r.rejectedOther;
            continue;
        }
        if (cx.inSolidBrush(at, p)) {
            ++r.rejectedSolid;
            continue;
        }
        r.eyes.push_back(p);
        r.playerEye.push_back(boxFree(cx.lv, playerBox(p), sc.boxStack) ? 1 : 0);
        r.playerSamples += r.playerEye.back();
    }
    r.samples = uint32_t(r.eyes.size());
}

// b. Rays from every eye point. flag[t]: kWithin = seen within the far plane, kBeyond = seen beyond
// it, kPlayer = seen within it from an eye point where a player's eye can be; a hidden cluster's
// evidence is kept in sc.misses.
void castRays(const Context &cx, int32_t c, SplitMix64 &rng, Scratch &sc, PvsClusterAudit &r) {
    using Clock = std::chrono::steady_clock;
    const BspLevel &lv = cx.lv;
    sc.touched.clear();
    sc.misses.clear();
    auto touch = [&](int32_t t) {
        if (sc.flag[size_t(t)] == 0) sc.touched.push_back(t);
    };
    touch(c);
    // A sampled cluster sees itself: its eye points are in it.
    const auto firstPlayer = std::find(r.playerEye.begin(), r.playerEye.end(), 1);
    sc.flag[size_t(c)] = kWithin | (firstPlayer != r.playerEye.end() ? kPlayer : 0);
    if (!cx.pvsBit(c, c)) {
        // The row leaves out the cluster itself (the engine would not draw the camera's own cluster):
        // the evidence is the first eye point in it (where a player's eye can be, if any).
        const size_t e = firstPlayer != r.playerEye.end() ? size_t(firstPlayer - r.playerEye.begin()) : 0;
        sc.evidence[size_t(c)] = 0;
        PvsMiss m;
        m.from = m.to = c, m.sample = uint32_t(e), m.eye = r.eyes[e], m.playerEye = r.playerEye[e];
        m.eyeLeaf = m.leaf = lv.leafAt(m.eye);
        m.stoppedBy = PvsStop::eye;
        sc.misses.push_back(m);
    }
    const size_t nd = cx.dirs.size();
    sc.batch.resize(nd);
    sc.hits.resize(nd);
    const double F = cx.farPlane > 0 ? cx.farPlane : INFINITY, tol = cx.tolerance;
    for (uint32_t si = 0; si < r.samples; ++si) {
        const Vec3 eye = r.eyes[si];
        const bool player = r.playerEye[si];
        const int32_t eyeLeaf = lv.leafAt(eye);
        const Rotation rot = Rotation::random(rng);
        nodeDistances(cx.nodes, eye, &sc.eyeAt);
        const auto c0 = Clock::now();
        const Vec3 rel = eye - cx.origin;
        std::vector<Vec3> &dirs = sc.dirs;  // this eye point's directions (double, unit)
        dirs.resize(nd);
        for (size_t i = 0; i < nd; ++i) {
            const Vec3 d = rot.apply(cx.dirs[i]);
            dirs[i] = d;
            LocalRay &ray = sc.batch[i];
            ray.org[0] = float(rel.x), ray.org[1] = float(rel.y), ray.org[2] = float(rel.z);
            ray.dir[0] = float(d.x), ray.dir[1] = float(d.y), ray.dir[2] = float(d.z);
            ray.tnear = 0;
            ray.tfar = float(cx.diagonal);
        }
        cx.rays.intersectStream(sc.batch.data(), nd, true, sc.hits.data());
        const auto c1 = Clock::now();
        sc.castMs += msBetween(c0, c1);
        r.rays += nd;
        for (size_t i = 0; i < nd; ++i) {
            const LocalHit &h = sc.hits[i];
            const bool hit = h.prim != kNoHit;
            const double tEnd = hit ? std::min(double(h.t), cx.diagonal) : cx.diagonal;
            PvsStop stop = hit ? PvsStop::surface : PvsStop::bounds;
            double stopT = tEnd;
            int32_t stopLeaf = -1;
            sc.updated.clear();  // misses whose evidence this ray (re)wrote
            const uint64_t rayId = uint64_t(si) * nd + i + 1;
            walk(cx.nodes, sc.eyeAt.data(), lv.leafs.empty(), dirs[i], tEnd, sc.stack, [&](int32_t leaf, double a, double b) {
                const int32_t t = lv.leafs[size_t(leaf)].cluster;
                if (t < 0) {
                    stop = PvsStop::solid, stopT = a, stopLeaf = leaf;
                    return false;
                }
                if (std::min(b, F) - a > tol) {  // seen within the far plane
                    touch(t);
                    uint8_t &f = sc.flag[size_t(t)];
                    if (sc.lastRay[size_t(t)] != rayId) sc.lastRay[size_t(t)] = rayId, ++sc.rays[size_t(t)];
                    // Evidence for a hidden cluster: the first ray that saw it, replaced once by the first
                    // from an eye point where a player's eye can be.
                    if (!cx.pvsBit(c, t) && (!(f & kWithin) || (player && !(f & kPlayer)))) {
                        if (sc.evidence[size_t(t)] < 0) {
                            sc.evidence[size_t(t)] = int32_t(sc.misses.size());
                            sc.misses.emplace_back();
                        }
                        PvsMiss &m = sc.misses[size_t(sc.evidence[size_t(t)])];
                        m = PvsMiss{};
                        m.from = c, m.to = t, m.sample = si, m.eye = eye, m.playerEye = player, m.direction = dirs[i];
                        m.eyeLeaf = eyeLeaf, m.leaf = leaf, m.enter = a, m.exit = b;
                        sc.updated.push_back(sc.evidence[size_t(t)]);
                    }
                    f |= kWithin | (player ? kPlayer : 0);
                } else if (b - a > tol) {  // seen beyond the far plane
                    touch(t);
                    sc.flag[size_t(t)] |= kBeyond;
                }
                return true;
            });
            for (int32_t k : sc.updated) {
                PvsMiss &m = sc.misses[size_t(k)];
                m.stop = stopT, m.stoppedBy = stop, m.stopLeaf = stopLeaf;
                if (stop == PvsStop::surface) {
                    m.stopTriangle = cx.rays.sourceOf(h.prim);
                    if (m.stopTriangle < lv.triangleFace.size()) m.stopFace = lv.triangleFace[m.stopTriangle];
                }
            }
        }
        sc.walkMs += msBetween(c1, Clock::now());
    }

}

// c. The row against what was seen; the scratch cleared for the next cluster.
void compareRow(const Context &cx, int32_t c, Scratch &sc, PvsClusterAudit &r) {
    const BspLevel &lv = cx.lv;
    std::sort(sc.touched.begin(), sc.touched.end());
    uint32_t seenVisible = 0;  // seen clusters whose bit is set
    for (int32_t t : sc.touched) {
        const bool bit = cx.pvsBit(c, t);
        const uint8_t f = sc.flag[size_t(t)];
        if (f & kWithin) {
            ++r.seen;
            seenVisible += bit;
            if (!bit) {
                PvsMiss m = sc.misses[size_t(sc.evidence[size_t(t)])];
                m.rays = sc.rays[size_t(t)];
                m.pvsByte = uint64_t(c) * lv.pvsRowBytes + uint64_t(t >> 3);
                m.pvsBit = t & 7;
                m.pvsByteValue = lv.pvs[m.pvsByte];
                (m.playerEye ? r.misses : r.crackMisses) += 1;
                r.missList.push_back(m);
            }
        } else if (f & kBeyond) {
            ++r.seenBeyondFar;
            r.hiddenByFarPlane += !bit;
        }
        sc.flag[size_t(t)] = 0, sc.rays[size_t(t)] = 0, sc.lastRay[size_t(t)] = 0, sc.evidence[size_t(t)] = -1;
    }
    r.slack = r.pvsVisible - seenVisible;  // visible in the row, never seen
}

void auditCluster(const Context &cx, int32_t c, Scratch &sc, PvsClusterAudit *out) {
    using Clock = std::chrono::steady_clock;
    const BspLevel &lv = cx.lv;
    PvsClusterAudit &r = *out;
    r.cluster = c;
    const uint32_t lb = cx.clusterLeafsBegin[size_t(c)], le = cx.clusterLeafsBegin[size_t(c) + 1];
    r.leafs = le - lb;
    for (uint32_t k = lb; k < le; ++k) r.bounds.extend(lv.leafs[cx.clusterLeafs[k]].bounds);
    // The PVS row.
    for (int32_t t = 0; t < lv.clusterCount; ++t) r.pvsVisible += cx.pvsBit(c, t);
    // Each cluster's own sequence: the seed and the cluster mixed through splitmix64.
    SplitMix64 rng{cx.s.seed ^ (0x9E3779B97F4A7C15ull * (uint64_t(c) + 1))};
    rng.next();
    const auto t0 = Clock::now();
    sampleEyes(cx, c, lb, le, rng, sc, r);
    sc.sampleMs += msBetween(t0, Clock::now());
    if (r.samples == 0) return;
    castRays(cx, c, rng, sc, r);
    compareRow(cx, c, sc, r);
}

// ---- Top-down view ------------------------------------------------------------------------------

void topView(const Context &cx, const Aabb &box, int size, PvsTopView *out) {
    PvsTopView &v = *out;
    const Vec3 e = box.extent();
    if (size <= 0 || box.empty() || !(e.x > 0) || !(e.y > 0)) return;
    v.pixel = std::max(e.x, e.y) / size;
    v.width = std::max(1, int(std::ceil(e.x / v.pixel)));
    v.height = std::max(1, int(std::ceil(e.y / v.pixel)));
    v.x0 = box.lo.x;
    v.y1 = box.hi.y;
    v.surfaceZ.assign(size_t(v.width) * v.height, NAN);
    v.slope.assign(size_t(v.width) * v.height, 0.0f);
    v.cluster.assign(size_t(v.width) * v.height, -1);
    const double top = box.hi.z + 1, depth = e.z + 2;
    tbb::parallel_for(0, v.height, [&](int y) {
        std::vector<LocalRay> rays(size_t(v.width));
        std::vector<LocalHit> hits(size_t(v.width));
        for (int x = 0; x < v.width; ++x) {
            const Vec3 o = Vec3{v.x0 + (x + 0.5) * v.pixel, v.y1 - (y + 0.5) * v.pixel, top} - cx.origin;
            LocalRay &r = rays[size_t(x)];
            r.org[0] = float(o.x), r.org[1] = float(o.y), r.org[2] = float(o.z);
            r.dir[0] = 0, r.dir[1] = 0, r.dir[2] = -1;
            r.tnear = 0;
            r.tfar = float(depth);
        }
        cx.rays.intersectStream(rays.data(), rays.size(), true, hits.data());
        for (int x = 0; x < v.width; ++x) {
            const LocalHit &h = hits[size_t(x)];
            if (h.prim == kNoHit) continue;
            const size_t p = size_t(y) * v.width + x;
            const double z = top - h.t;
            v.surfaceZ[p] = float(z);
            v.slope[p] = float(std::fabs(h.ng[2]) / std::sqrt(double(h.ng[0]) * h.ng[0] + double(h.ng[1]) * h.ng[1] +
                                                             double(h.ng[2]) * h.ng[2]));
            // The cluster a player standing there is in: 1 unit above the surface.
            const int32_t leaf = cx.lv.leafAt({v.x0 + (x + 0.5) * v.pixel, v.y1 - (y + 0.5) * v.pixel, z + 1});
            v.cluster[p] = leaf >= 0 ? cx.lv.leafs[size_t(leaf)].cluster : -1;
        }
    });
}

}  // namespace

const char *pvsStopName(PvsStop s) {
    switch (s) {
    case PvsStop::surface: return "surface";
    case PvsStop::solid: return "solid_leaf";
    case PvsStop::bounds: return "map_bounds";
    case PvsStop::eye: return "eye";
    }
    return "map_bounds";
}

double mapFarPlane(const BspLevel &level, std::string *key, std::string *text) {
    for (const BspEntity &e : level.entities) {
        const std::string *cls = e.get("classname");
        if (!cls || *cls != "worldspawn") continue;
        for (const char *k : {"_farplanedist", "fogclip", "distancecull"}) {
            const std::string *v = e.get(k);
            if (!v) continue;
            const double d = std::strtod(v->c_str(), nullptr);
            if (!(std::isfinite(d) && d > 0)) return 0;
            if (key) *key = k;
            if (text) *text = *v;
            return d;
        }
        return 0;
    }
    return 0;
}

const char *pvsAuditSkipReason(const Scene &scene) {
    if (!scene.bsp) return "not a Quake 3 map (.bsp): only a map has clusters and a PVS";
    if (!scene.bsp->hasPvs()) return "the map has no PVS (its visdata lump is empty: compiled without vis)";
    return nullptr;
}

bool playerEyeFits(const BspLevel &level, Vec3 eye) {
    std::vector<int32_t> stack;
    return boxFree(level, playerBox(eye), stack);
}

void walkBspSegment(const BspLevel &level, Vec3 eye, Vec3 dir, double tEnd,
                    const std::function<bool(int32_t, double, double)> &leaf) {
    std::vector<Segment> stack;
    const std::vector<FlatNode> nodes = flatNodes(level);
    std::vector<double> at;
    nodeDistances(nodes, eye, &at);
    walk(nodes, at.data(), level.leafs.empty(), dir, tEnd, stack, leaf);
}

namespace {
// The leafs of each cluster the world's tree reaches (CSR in cx.clusterLeafs), and the box of the
// scene and those leafs.
void indexClusterLeafs(const Scene &scene, const BspLevel &lv, Context &cx, Aabb *boxOut) {
    // The leafs the world's tree reaches (a brush model's own leafs are not in it): nodes are in
    // pre-order, so one pass marks every reachable node and leaf.
    std::vector<uint8_t> inTree(lv.leafs.size(), 0);
    if (lv.nodes.empty()) {
        if (!lv.leafs.empty()) inTree[0] = 1;
    } else {
        std::vector<uint8_t> nodeIn(lv.nodes.size(), 0);
        nodeIn[0] = 1;
        for (size_t i = 0; i < lv.nodes.size(); ++i)
            if (nodeIn[i])
                for (int32_t ch : lv.nodes[i].children) {
                    if (ch >= 0) nodeIn[size_t(ch)] = 1;
                    else inTree[size_t(-(int64_t(ch) + 1))] = 1;
                }
    }
    cx.clusterLeafsBegin.assign(size_t(lv.clusterCount) + 1, 0);
    Aabb box = scene.bounds;
    for (size_t l = 0; l < lv.leafs.size(); ++l)
        if (inTree[l] && lv.leafs[l].cluster >= 0) {
            ++cx.clusterLeafsBegin[size_t(lv.leafs[l].cluster) + 1];
            box.extend(lv.leafs[l].bounds);
        }
    for (size_t c = 0; c < size_t(lv.clusterCount); ++c) cx.clusterLeafsBegin[c + 1] += cx.clusterLeafsBegin[c];
    cx.clusterLeafs.resize(cx.clusterLeafsBegin.back());
    {
        std::vector<uint32_t> fill(cx.clusterLeafsBegin.begin(), cx.clusterLeafsBegin.end() - 1);
        for (size_t l = 0; l < lv.leafs.size(); ++l)
            if (inTree[l] && lv.leafs[l].cluster >= 0) cx.clusterLeafs[fill[size_t(lv.leafs[l].cluster)]++] = uint32_t(l);
    }
    *boxOut = box;
}

// The triangles the rays stop at; the others counted in `occluders`.
std::vector<uint32_t> opaqueTriangles(const Scene &scene, const BspLevel &lv, PvsOccluders *occluders) {
    // The opaque triangles: drawn world faces without CONTENTS_TRANSLUCENT (the loader has already
    // left out sky, tool surfaces and see-through liquids). A scene whose triangles cannot be traced
    // to faces (no triangleFace) treats every triangle as opaque world geometry.
    std::vector<uint32_t> opaque;
    const bool faces = lv.triangleFace.size() == scene.triangleCount();
    for (size_t t = 0; t < scene.triangleCount(); ++t) {
        if (scene.triangleObject[t] == kExcludedTriangle) continue;
        if (faces) {
            const uint32_t f = lv.triangleFace[t];
            if (f < lv.worldFirstFace || f - lv.worldFirstFace >= lv.worldFaceCount) {
                ++occluders->entity;
                continue;
            }
            if (f < lv.faceShader.size() && lv.faceShader[f] < lv.shaders.size() &&
                (lv.shaders[lv.faceShader[f]].contents & kContentsTranslucent)) {
                ++occluders->translucent;
                continue;
            }
        }
        opaque.push_back(uint32_t(t));
    }
    occluders->opaque = opaque.size();
    return opaque;
}

// 2. Every cluster of `todo`, in parallel; each result goes to its own slot of res.clusters. False
// when s.cancel stopped it.
bool auditClusters(const Context &cx, const BspLevel &lv, const PvsAuditSettings &s, const std::vector<int32_t> &todo,
                   PvsAuditResult &res) {
    res.clusters.resize(todo.size());
    std::atomic<size_t> done{0};
    std::atomic<bool> stopped{false};
    struct ThreadTimes {
        double sample = 0, cast = 0, walk = 0;
    };
    std::vector<ThreadTimes> perCluster(todo.size());
    tbb::parallel_for(size_t(0), todo.size(), [&](size_t i) {
        if (stopped.load(std::memory_order_relaxed)) return;
        if (s.cancel && s.cancel->load(std::memory_order_relaxed)) {
            stopped = true;
            return;
        }
        thread_local std::unique_ptr<Scratch> scratch;
        if (!scratch) scratch = std::make_unique<Scratch>();
        Scratch &sc = *scratch;
        if (sc.flag.size() != size_t(lv.clusterCount)) {
            sc.flag.assign(size_t(lv.clusterCount), 0);
            sc.rays.assign(size_t(lv.clusterCount), 0);
            sc.lastRay.assign(size_t(lv.clusterCount), 0);
            sc.evidence.assign(size_t(lv.clusterCount), -1);
        }
        sc.sampleMs = sc.castMs = sc.walkMs = 0;
        auditCluster(cx, todo[i], sc, &res.clusters[i]);
        perCluster[i] = {sc.sampleMs, sc.castMs, sc.walkMs};
        const size_t k = ++done;
        if (s.progress) s.progress(k, todo.size());
    });
    if (stopped) return false;
    if (!Stopwatch::fixedTimings())
        for (const ThreadTimes &t : perCluster) {
            res.sampleThreadMs += t.sample;
            res.castThreadMs += t.cast;
            res.walkThreadMs += t.walk;
        }
    return true;
}

// 3. Totals and histograms, in cluster order.
void sumClusters(int32_t clusterCount, size_t requested, PvsAuditResult &res) {
    PvsAuditTotals &T = res.totals;
    T.clusters = uint32_t(clusterCount);
    T.requested = uint32_t(requested);
    res.slackHistogram.assign(10, 0);
    res.missHistogram.assign(7, 0);
    for (const PvsClusterAudit &c : res.clusters) {
        T.samples += c.samples;
        T.rays += c.rays;
        if (c.samples == 0) {
            ++T.unsampled;
            continue;
        }
        ++T.audited;
        T.pvsVisiblePairs += c.pvsVisible;
        T.seenPairs += c.seen;
        T.misses += c.misses;
        T.missClusters += c.misses > 0;
        T.crackMisses += c.crackMisses;
        T.playerClusters += c.playerSamples > 0;
        T.slackPairs += c.slack;
        T.seenBeyondFarPairs += c.seenBeyondFar;
        T.hiddenByFarPlanePairs += c.hiddenByFarPlane;
        ++res.slackHistogram[std::min<size_t>(9, size_t(c.slackShare() * 10))];
        size_t bin = 0;
        for (uint32_t m = c.misses; m > 0 && bin < 6; m >>= 1) ++bin;  // 0, 1, 2-3, 4-7, ..., 32+
        ++res.missHistogram[bin];
    }
    T.slackShare = T.pvsVisiblePairs ? double(T.slackPairs) / double(T.pvsVisiblePairs) : 0.0;

}

}  // namespace

bool auditPvs(const Scene &scene, const PvsAuditSettings &s, PvsAuditResult *out, std::string *err) {
    if (const char *why = pvsAuditSkipReason(scene)) {
        *err = scene.path + ": " + why;
        return false;
    }
    if (s.samples < 1 || s.resolution < 1) {
        *err = "--samples and --resolution must be at least 1";
        return false;
    }
    const BspLevel &lv = *scene.bsp;
    std::optional<tbb::global_control> threads;
    if (s.threads > 0) threads.emplace(tbb::global_control::max_allowed_parallelism, size_t(s.threads));
    PvsAuditResult res;
    res.map = scene.path;
    res.settings = s;
    res.settings.progress = nullptr;
    res.settings.cancel = nullptr;
    res.raysPerSample = 6 * s.resolution * s.resolution;
    res.clusterCount = lv.clusterCount;
    res.pvsRowBytes = lv.pvsRowBytes;
    for (int32_t c : s.clusters)
        if (c < 0 || c >= lv.clusterCount) {
            *err = "--clusters: cluster " + std::to_string(c) + " is outside the map's " +
                   std::to_string(lv.clusterCount) + " clusters (0.." + std::to_string(lv.clusterCount - 1) + ")";
            return false;
        }

    // 1. Setup.
    const Stopwatch setup;
    Context cx(scene, res.settings);
    Aabb box;
    indexClusterLeafs(scene, lv, cx, &box);
    if (box.empty()) box.extend(Vec3{0, 0, 0});
    cx.origin = box.center();
    // Every ray starts inside the box, so it leaves it within the diagonal (+1: the eye may lie on it).
    cx.diagonal = std::ceil(length(box.extent())) + 1;
    res.mapDiagonal = cx.diagonal;
    // The tolerance: Embree's hit distance is computed in float from the eye and the vertices (each
    // within E of the float frame's origin, rounded to 2^-24 relative) through a handful of float
    // operations on quantities up to 3E (eye, vertex, distance), each adding at most 2^-24 of its
    // magnitude; 64 such roundings bound its error, and a stay in a leaf no longer than that is not
    // counted (conservative: a miss is never claimed from a stay the rounding could have made).
    const double E = std::max(maxAbs(box.lo - cx.origin), maxAbs(box.hi - cx.origin));
    cx.tolerance = 64 * 0x1.0p-24 * 3 * E;
    res.tolerance = cx.tolerance;
    // The far plane.
    if (s.farPlane >= 0) {
        cx.farPlane = s.farPlane;
        res.farPlaneSource = s.farPlane > 0 ? "--far-plane" : "none";
    } else {
        std::string key, text;
        cx.farPlane = mapFarPlane(lv, &key, &text);
        res.farPlaneSource = cx.farPlane > 0 ? key : "none";
        res.farPlaneText = text;
    }
    res.farPlane = cx.farPlane;
    const std::vector<uint32_t> opaque = opaqueTriangles(scene, lv, &res.occluders);
    if (!cx.rays.build(MeshView{scene.positions.data(), scene.indices.data()}, scene.positions.size(), opaque,
                       cx.origin, err))
        return false;
    cx.dirs = cubeDirections(s.resolution);
    cx.nodes = flatNodes(lv);
    // The clusters to audit.
    std::vector<int32_t> todo = s.clusters;
    if (todo.empty())
        for (int32_t c = 0; c < lv.clusterCount; ++c) todo.push_back(c);
    res.setupMs = setup.ms();

    // 2. Every cluster, in parallel.
    const Stopwatch audit;
    if (!auditClusters(cx, lv, s, todo, res)) {
        *err = "interrupted";
        return false;
    }
    res.auditMs = audit.ms();

    sumClusters(lv.clusterCount, todo.size(), res);
    const Stopwatch top;
    topView(cx, box, s.imageSize, &res.top);
    res.topViewMs = top.ms();
    *out = std::move(res);
    return true;
}

}  // namespace va
