// The PVS audit (analysis/audits/pvs_audit.h, docs/pvs-audit.md): hand-built maps with a known miss, a known
// crack miss and known slack (exact counts), the far plane, the BSP segment walk, the player's eye
// box, the loader's brushes, a real map checked against its own bytes, determinism across thread
// counts, the command's files and messages, and `check` gating on pvs_misses.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include "analysis/load/load.h"
#include "analysis/load/load_bsp.h"
#include "analysis/audits/pvs_audit.h"
#include "analysis/load/zip.h"
#include "reports/budget.h"
#include "reports/pvs_audit_report.h"
#include "tests/bsp_writer.h"
#include "tests/temp_dir_test.h"

using namespace va;
using va::testing_util::BspWriter;
namespace fs = std::filesystem;

namespace {

// ---- A corridor of rooms along x ------------------------------------------------------------------
//
// Space outside y in [-Y, Y], z in [0, Z] is solid; inside, x is cut at the rooms' boundaries into
// leafs: room k spans [x[k], x[k + 1]) with cluster clusters[k] (-1: a solid wall); x < x[0] and
// x >= x.back() are solid. The tree is a chain: four nodes for the y and z walls, then one node per
// x boundary (front: x >= boundary).
struct Corridor {
    double Y = 100, Z = 200;
    std::vector<double> x;
    std::vector<int32_t> clusters;
    std::vector<std::vector<int>> pvs;
    std::string worldspawn;               // extra "key" "value" lines
    bool quad = false;                    // a drawn quad across the corridor at x = quadX, facing -x
    double quadX = 150;
    int quadRoom = 1;                     // the room whose leaf lists it
    bool crate = false;                   // a solid detail brush in room 0: x 20..80, y -90..-20, z 0..100
};

std::vector<uint8_t> corridorFile(const Corridor &c) {
    BspWriter w;
    w.entities("{\n\"classname\" \"worldspawn\"\n" + c.worldspawn + "}\n");
    const int32_t solid = w.shader("textures/base/wall", 0, 1);
    // Faces: the quad (world model 0), listed by room quadRoom.
    int32_t nFaces = 0;
    if (c.quad) {
        // Stored clockwise seen from its front (-x): (v1 - v0) x (v2 - v0) points to +x.
        const int32_t v = w.vertex({c.quadX, -c.Y, 0});
        w.vertex({c.quadX, c.Y, 0}), w.vertex({c.quadX, c.Y, c.Z}), w.vertex({c.quadX, -c.Y, c.Z});
        w.face(solid, 1, v, 4, w.meshverts({0, 1, 2, 0, 2, 3}), 6);
        nFaces = 1;
        w.i32(va::testing_util::LLeafFaces, 0);
    }
    if (c.crate) {
        w.boxBrush({20, -90, 0}, {80, -20, 100}, solid);
        w.i32(va::testing_util::LLeafBrushes, 0);
    }
    const Vec3 lo{c.x.front() - 64, -c.Y - 64, -64}, hi{c.x.back() + 64, c.Y + 64, c.Z + 64};
    auto solidLeaf = [&] { return -(w.leaf(-1, lo, hi, 0, 0) + 1); };
    // Node k's children are filled in order; a node's "next" is the node written after it.
    const int32_t pyHi = w.plane({0, 1, 0}, c.Y), pyLo = w.plane({0, 1, 0}, -c.Y);
    const int32_t pzHi = w.plane({0, 0, 1}, c.Z), pzLo = w.plane({0, 0, 1}, 0);
    int32_t next = 1;
    w.node(pyHi, solidLeaf(), next++);
    w.node(pyLo, next++, solidLeaf());
    w.node(pzHi, solidLeaf(), next++);
    w.node(pzLo, next++, solidLeaf());
    for (size_t k = 0; k < c.x.size(); ++k) {
        const int32_t pl = w.plane({1, 0, 0}, c.x[k]);
        const bool last = k + 1 == c.x.size();
        int32_t back;
        if (k == 0) {
            back = solidLeaf();
        } else {
            const size_t room = k - 1;
            const bool faces = c.quad && int(room) == c.quadRoom, brushes = c.crate && room == 0;
            back = -(w.leaf(c.clusters[room], {c.x[k - 1], -c.Y, 0}, {c.x[k], c.Y, c.Z}, 0, faces ? nFaces : 0, 0,
                            brushes ? 1 : 0) +
                     1);
        }
        w.node(pl, last ? solidLeaf() : next++, back);
    }
    w.model({lo.x, lo.y, lo.z}, {hi.x, hi.y, hi.z}, 0, nFaces);
    w.pvs(c.pvs);
    return w.file();
}

Scene loadCorridor(const Corridor &c, const fs::path &dir, const std::string &name = "corridor.bsp") {
    const fs::path p = dir / name;
    const std::vector<uint8_t> bytes = corridorFile(c);
    std::ofstream(p, std::ios::binary).write(reinterpret_cast<const char *>(bytes.data()), std::streamsize(bytes.size()));
    Scene s;
    std::string err;
    EXPECT_TRUE(loadBspScene(p.string(), {}, {}, &s, &err)) << err;
    return s;
}

// The five-room map of the literal tests (docs/pvs-audit.md draws it):
//   A [0,100) c0 | B [100,200) c1, a quad at x = 150 facing A | C [200,300) c2 | wall [300,310) |
//   D [310,410) c3 | E [410,415) c4, a 5-unit sliver no player's box fits in.
// Rows: A {0,2,3}, B {0,1,2}, C {1,2}, D {3,4}, E {4}.
// Seen: A {0,1} (the quad's front stops it), B {0,1,2}, C {0,1,2} (through the quad's back), D {3,4},
// E {3,4}. So: A misses B and has slack C, D; C misses A; E misses D from a crack only.
Corridor fiveRooms() {
    Corridor c;
    c.x = {0, 100, 200, 300, 310, 410, 415};
    c.clusters = {0, 1, 2, -1, 3, 4};
    c.pvs = {{0, 2, 3}, {0, 1, 2}, {1, 2}, {3, 4}, {4}};
    c.quad = true;
    c.crate = true;
    return c;
}

class PvsAuditTest : public va::testing_util::TempDirTest {
  protected:
    PvsAuditTest() : TempDirTest("pvs") {}
};

const PvsClusterAudit &clusterOf(const PvsAuditResult &r, int32_t c) {
    for (const PvsClusterAudit &a : r.clusters)
        if (a.cluster == c) return a;
    throw std::runtime_error("no cluster " + std::to_string(c));
}

PvsAuditResult audit(const Scene &s, PvsAuditSettings settings = {}) {
    PvsAuditResult r;
    std::string err;
    EXPECT_TRUE(auditPvs(s, settings, &r, &err)) << err;
    return r;
}

}  // namespace

// ---- Literal cases --------------------------------------------------------------------------------

TEST_F(PvsAuditTest, FiveRoomsKnownMissesCrackMissAndSlack) {
    const Scene s = loadCorridor(fiveRooms(), dir_);
    const PvsAuditResult r = audit(s);
    ASSERT_EQ(r.clusters.size(), 5u);
    struct Want {
        uint32_t pvsVisible, seen, misses, crackMisses, slack;
    };
    const Want want[5] = {{3, 2, 1, 0, 2}, {3, 3, 0, 0, 0}, {2, 3, 1, 0, 0}, {2, 2, 0, 0, 0}, {1, 2, 0, 1, 0}};
    for (int c = 0; c < 5; ++c) {
        const PvsClusterAudit &a = clusterOf(r, c);
        SCOPED_TRACE("cluster " + std::to_string(c));
        EXPECT_EQ(a.samples, 32u);
        EXPECT_EQ(a.pvsVisible, want[c].pvsVisible);
        EXPECT_EQ(a.seen, want[c].seen);
        EXPECT_EQ(a.misses, want[c].misses);
        EXPECT_EQ(a.crackMisses, want[c].crackMisses);
        EXPECT_EQ(a.slack, want[c].slack);
        EXPECT_EQ(a.rays, 32u * 864u);
    }
    // E is 5 units deep against a solid wall: no crouching player's box fits; the rooms have room.
    EXPECT_EQ(clusterOf(r, 4).playerSamples, 0u);
    EXPECT_GT(clusterOf(r, 0).playerSamples, 0u);
    const PvsAuditTotals &t = r.totals;
    EXPECT_EQ(t.clusters, 5u);
    EXPECT_EQ(t.audited, 5u);
    EXPECT_EQ(t.unsampled, 0u);
    EXPECT_EQ(t.pvsVisiblePairs, 11u);
    EXPECT_EQ(t.seenPairs, 12u);
    EXPECT_EQ(t.misses, 2u);
    EXPECT_EQ(t.missClusters, 2u);
    EXPECT_EQ(t.crackMisses, 1u);
    EXPECT_EQ(t.slackPairs, 2u);
    EXPECT_DOUBLE_EQ(t.slackShare, 2.0 / 11.0);
    EXPECT_EQ(t.seenBeyondFarPairs, 0u);
    EXPECT_EQ(r.farPlane, 0);
    EXPECT_EQ(r.farPlaneSource, "none");
    // One opaque quad (2 triangles), nothing passed.
    EXPECT_EQ(r.occluders.opaque, 2u);
    EXPECT_EQ(r.occluders.translucent + r.occluders.entity, 0u);
    // Histograms: slack shares 2/3 (A) and 0 (the rest); misses 1 (A, C), 0 (B, D, E).
    EXPECT_EQ(r.slackHistogram[0], 4u);
    EXPECT_EQ(r.slackHistogram[6], 1u);
    EXPECT_EQ(r.missHistogram[0], 3u);
    EXPECT_EQ(r.missHistogram[1], 2u);
}

TEST_F(PvsAuditTest, MissEvidenceIsTheRayThatSawIt) {
    const Scene s = loadCorridor(fiveRooms(), dir_);
    const PvsAuditResult r = audit(s);
    // A (0) sees B (1): a ray from a player's eye point in A crossed x = 100 into B's leaf.
    const PvsClusterAudit &a = clusterOf(r, 0);
    ASSERT_EQ(a.missList.size(), 1u);
    const PvsMiss &m = a.missList[0];
    EXPECT_EQ(m.from, 0);
    EXPECT_EQ(m.to, 1);
    EXPECT_TRUE(m.playerEye);
    EXPECT_TRUE(playerEyeFits(*s.bsp, m.eye));
    EXPECT_EQ(s.bsp->leafs[size_t(m.eyeLeaf)].cluster, 0);
    EXPECT_EQ(s.bsp->leafs[size_t(m.leaf)].cluster, 1);
    EXPECT_EQ(s.bsp->leafAt(m.eye), m.eyeLeaf);
    // It entered B where it crossed x = 100 (to rounding), left no later than where it stopped: at
    // the quad (x = 150) or a wall of B, before the quad.
    const Vec3 enter = m.eye + m.direction * m.enter;
    EXPECT_NEAR(enter.x, 100, 1e-9 * 400);
    EXPECT_GT(m.exit - m.enter, r.tolerance);
    EXPECT_LE(m.exit, m.stop);
    EXPECT_LE((m.eye + m.direction * m.stop).x, 150 + 1e-3);
    if (m.stoppedBy == PvsStop::surface) {
        EXPECT_EQ(m.stopFace, 0u);
        EXPECT_NEAR((m.eye + m.direction * m.stop).x, 150, 1e-3);
    } else {
        EXPECT_EQ(m.stoppedBy, PvsStop::solid);
    }
    // The bit: row 0 is byte 0 (one byte per row), bit 1; the byte is 0b1101 (clusters 0, 2, 3).
    EXPECT_EQ(m.pvsByte, 0u);
    EXPECT_EQ(m.pvsBit, 1);
    EXPECT_EQ(m.pvsByteValue, 0x0D);
    EXPECT_GE(m.rays, 1u);
    EXPECT_LE(m.rays, a.rays);  // counted once per ray, however many of its leafs it crossed
    // C (2) sees A (0) through the quad's back face: the ray crossed x = 150 and x = 100 going -x.
    const PvsClusterAudit &c = clusterOf(r, 2);
    ASSERT_EQ(c.missList.size(), 1u);
    EXPECT_EQ(c.missList[0].to, 0);
    EXPECT_LT(c.missList[0].direction.x, 0);
    EXPECT_NEAR((c.missList[0].eye + c.missList[0].direction * c.missList[0].enter).x, 100, 1e-9 * 400);
    EXPECT_EQ(c.missList[0].pvsByte, 2u);
    EXPECT_EQ(c.missList[0].pvsByteValue, 0x06);
    // E (4) sees D (3) only from eye points where no player fits: a crack miss.
    const PvsClusterAudit &e = clusterOf(r, 4);
    ASSERT_EQ(e.missList.size(), 1u);
    EXPECT_EQ(e.missList[0].to, 3);
    EXPECT_FALSE(e.missList[0].playerEye);
}

TEST_F(PvsAuditTest, EyePointsAvoidSolidDetailBrushes) {
    const Scene s = loadCorridor(fiveRooms(), dir_);
    const PvsAuditResult r = audit(s);
    const PvsClusterAudit &a = clusterOf(r, 0);
    // The crate (x 20..80, y -90..-20, z 0..100) fills 0.21 of A: some candidates fell in it.
    EXPECT_GT(a.rejectedSolid, 0u);
    EXPECT_EQ(a.attempts, a.samples + a.rejectedSolid + a.rejectedOther);
    for (const Vec3 &e : a.eyes)
        EXPECT_FALSE(e.x >= 20 && e.x <= 80 && e.y >= -90 && e.y <= -20 && e.z >= 0 && e.z <= 100) << e.x << " " << e.y << " " << e.z;
    // The loader kept the brush: one brush, six sides, listed by A's leaf.
    ASSERT_EQ(s.bsp->brushes.size(), 1u);
    EXPECT_EQ(s.bsp->brushes[0].sideCount, 6u);
    EXPECT_EQ(s.bsp->shaders[s.bsp->brushes[0].shader].contents, 1u);
    const BspLeaf &la = s.bsp->leafs[size_t(s.bsp->leafAt({50, 0, 150}))];
    EXPECT_EQ(la.leafBrushCount, 1u);
}

TEST_F(PvsAuditTest, PlayerEyeBox) {
    const Scene s = loadCorridor(fiveRooms(), dir_);
    const BspLevel &lv = *s.bsp;
    // The box reaches 15 units sideways, 36 down and 4 up from the eye.
    EXPECT_TRUE(playerEyeFits(lv, {50, 50, 100}));
    EXPECT_TRUE(playerEyeFits(lv, {50, 50, 36.5}));    // 36.5 above the floor
    EXPECT_FALSE(playerEyeFits(lv, {50, 50, 35.5}));   // its feet in the floor
    EXPECT_TRUE(playerEyeFits(lv, {50, 50, 195.5}));   // 4.5 below the ceiling
    EXPECT_FALSE(playerEyeFits(lv, {50, 50, 196.5}));
    EXPECT_TRUE(playerEyeFits(lv, {50, 84.5, 100}));   // 15.5 from the wall at y = 100
    EXPECT_FALSE(playerEyeFits(lv, {50, 85.5, 100}));
    EXPECT_FALSE(playerEyeFits(lv, {50, -50, 120}));   // the crate's top is at 100: 20 below the eye
    EXPECT_TRUE(playerEyeFits(lv, {50, -50, 137}));
    EXPECT_FALSE(playerEyeFits(lv, {412, 0, 100}));    // E: 3 units from the wall at 415
    EXPECT_FALSE(playerEyeFits(lv, {305, 0, 100}));    // inside the wall
}

TEST_F(PvsAuditTest, FarPlaneLeavesDistantClustersOutByDesign) {
    // A [0,100) c0 | B [100,1000) c1 | D [1000,1100) c2, 1000 x 1000 in y and z. Rows A {0,1},
    // B {0,1,2}, D {1,2}: A and D see each other only from 900 units or more.
    Corridor c;
    c.Y = 500, c.Z = 1000;
    c.x = {0, 100, 1000, 1100};
    c.clusters = {0, 1, 2};
    c.pvs = {{0, 1}, {0, 1, 2}, {1, 2}};
    c.worldspawn = "\"_farplanedist\" \"500\"\n";
    const Scene s = loadCorridor(c, dir_);
    EXPECT_EQ(mapFarPlane(*s.bsp), 500);
    PvsAuditSettings st;
    st.samples = 16;
    st.resolution = 8;
    const PvsAuditResult r = audit(s, st);
    EXPECT_EQ(r.farPlane, 500);
    EXPECT_EQ(r.farPlaneSource, "_farplanedist");
    EXPECT_EQ(r.farPlaneText, "500");
    EXPECT_EQ(r.totals.misses, 0u);
    EXPECT_EQ(r.totals.seenBeyondFarPairs, 2u);     // A -> D, D -> A
    EXPECT_EQ(r.totals.hiddenByFarPlanePairs, 2u);  // both left out of the rows: by design
    EXPECT_EQ(r.totals.slackPairs, 0u);
    EXPECT_EQ(clusterOf(r, 0).hiddenByFarPlane, 1u);
    // Without a far plane (--far-plane 0) the same two pairs are misses.
    st.farPlane = 0;
    const PvsAuditResult u = audit(s, st);
    EXPECT_EQ(u.farPlaneSource, "none");
    EXPECT_EQ(u.totals.misses, 2u);
    EXPECT_EQ(u.totals.hiddenByFarPlanePairs, 0u);
    ASSERT_EQ(clusterOf(u, 0).missList.size(), 1u);
    EXPECT_GE(clusterOf(u, 0).missList[0].enter, 900);
}

TEST_F(PvsAuditTest, SubsetOfClustersAndBadSettings) {
    const Scene s = loadCorridor(fiveRooms(), dir_);
    PvsAuditSettings st;
    st.clusters = {2, 4};
    const PvsAuditResult r = audit(s, st);
    ASSERT_EQ(r.clusters.size(), 2u);
    EXPECT_EQ(r.totals.requested, 2u);
    EXPECT_EQ(r.totals.misses, 1u);       // C -> A
    EXPECT_EQ(r.totals.crackMisses, 1u);  // E -> D
    // The same cluster gives the same result in a subset as in the whole audit.
    const PvsAuditResult all = audit(s);
    EXPECT_EQ(clusterOf(r, 2).eyes, clusterOf(all, 2).eyes);
    EXPECT_EQ(clusterOf(r, 2).seen, clusterOf(all, 2).seen);
    PvsAuditResult bad;
    std::string err;
    st.clusters = {5};
    EXPECT_FALSE(auditPvs(s, st, &bad, &err));
    EXPECT_EQ(err, "--clusters: cluster 5 is outside the map's 5 clusters (0..4)");
    Scene notMap;
    notMap.path = "x.obj";
    EXPECT_FALSE(auditPvs(notMap, {}, &bad, &err));
    EXPECT_EQ(err, "x.obj: not a Quake 3 map (.bsp): only a map has clusters and a PVS");
}

TEST_F(PvsAuditTest, SegmentWalkVisitsLeafsFrontToBack) {
    const Scene s = loadCorridor(fiveRooms(), dir_);
    const BspLevel &lv = *s.bsp;
    // From (50, 0, 100) along +x for 400 units: A from 0, B from 50, C from 150, the wall from 250
    // (x = 300), D from 260, E from 360, solid from 365 to 400.
    std::vector<std::tuple<int32_t, double, double>> got;
    walkBspSegment(lv, {50, 0, 100}, {1, 0, 0}, 400, [&](int32_t leaf, double a, double b) {
        got.emplace_back(lv.leafs[size_t(leaf)].cluster, a, b);
        return true;
    });
    const std::vector<std::tuple<int32_t, double, double>> want = {
        {0, 0, 50}, {1, 50, 150}, {2, 150, 250}, {-1, 250, 260}, {3, 260, 360}, {4, 360, 365}, {-1, 365, 400}};
    EXPECT_EQ(got, want);
    // Stopping early: the callback's false ends the walk.
    int calls = 0;
    walkBspSegment(lv, {50, 0, 100}, {1, 0, 0}, 400, [&](int32_t, double, double) { return ++calls < 2; });
    EXPECT_EQ(calls, 2);
}

TEST_F(PvsAuditTest, DeterministicAcrossThreadCounts) {
    const Scene s = loadCorridor(fiveRooms(), dir_);
    PvsAuditSettings st;
    st.imageSize = 64;
    std::string one, two;
    for (int threads : {1, 2, 5}) {
        st.threads = threads;
        PvsAuditResult r = audit(s, st);
        r.setupMs = r.auditMs = r.topViewMs = r.sampleThreadMs = r.castThreadMs = r.walkThreadMs = 0;
        const std::string j = pvsAuditJson(r, "pvs-audit.png").dump();
        if (one.empty()) one = j;
        EXPECT_EQ(j, one) << threads << " threads";
    }
}

// ---- A real map ---------------------------------------------------------------------------------

namespace {
const std::string kOa = std::string(VISAUDIT_SOURCE_DIR) + "/data/openarena/";
}

// q3dm6ish (247 clusters), 50 clusters at 8 eye points x 384 rays: every count checked against the
// map's own bytes (the PVS rows decoded here from the raw visdata lump), every miss's evidence walked
// again, and the same counts on 1 and 2 threads.
TEST_F(PvsAuditTest, RealMapSubsetAgainstItsBytes) {
    const std::string path = kOa + "pak1-maps.pk3:maps/q3dm6ish.bsp";
    if (!fs::exists(kOa + "pak1-maps.pk3")) GTEST_SKIP() << "scripts/fetch-data.sh fetches the OpenArena maps";
    Scene s;
    std::string err;
    ASSERT_TRUE(loadScene(path, {}, &s, &err)) << err;
    std::vector<uint8_t> bytes;
    ASSERT_TRUE(readBspBytes(path, 1u << 30, &bytes, &err)) << err;
    auto u32 = [&](size_t at) {
        return uint32_t(bytes[at]) | uint32_t(bytes[at + 1]) << 8 | uint32_t(bytes[at + 2]) << 16 | uint32_t(bytes[at + 3]) << 24;
    };
    const size_t vis = u32(8 + 8 * 16);
    const uint32_t n = u32(vis), rowBytes = u32(vis + 4);
    ASSERT_EQ(n, 247u);
    auto bit = [&](int32_t from, int32_t to) { return (bytes[vis + 8 + size_t(from) * rowBytes + size_t(to >> 3)] >> (to & 7)) & 1; };

    PvsAuditSettings st;
    st.samples = 8;
    st.resolution = 8;
    for (int32_t c = 0; c < 50; ++c) st.clusters.push_back(c);
    st.threads = 1;
    const PvsAuditResult r = audit(s, st);
    st.threads = 2;
    const PvsAuditResult r2 = audit(s, st);
    ASSERT_EQ(r.clusters.size(), 50u);
    EXPECT_EQ(r.totals.rays, r2.totals.rays);
    EXPECT_EQ(r.totals.misses, r2.totals.misses);
    EXPECT_EQ(r.totals.slackPairs, r2.totals.slackPairs);
    EXPECT_EQ(r.totals.crackMisses, r2.totals.crackMisses);
    uint64_t visible = 0;
    for (const PvsClusterAudit &c : r.clusters) {
        uint32_t row = 0;
        for (int32_t t = 0; t < int32_t(n); ++t) row += bit(c.cluster, t);
        EXPECT_EQ(c.pvsVisible, row) << "cluster " << c.cluster;
        if (c.samples) visible += row;
        EXPECT_EQ(c.slack + (c.seen - c.misses - c.crackMisses), c.pvsVisible) << "cluster " << c.cluster;
        for (const PvsMiss &m : c.missList) {
            EXPECT_EQ(bit(m.from, m.to), 0) << m.from << " -> " << m.to;
            EXPECT_EQ(m.pvsByteValue, bytes[vis + 8 + m.pvsByte]);
            // Walk the evidence's ray again: it passes through the missed leaf where it says.
            bool found = false;
            walkBspSegment(*s.bsp, m.eye, m.direction, m.stop, [&](int32_t leaf, double a, double b) {
                found |= leaf == m.leaf && a == m.enter && b == m.exit;
                return true;
            });
            EXPECT_TRUE(found) << m.from << " -> " << m.to;
        }
    }
    EXPECT_EQ(r.totals.pvsVisiblePairs, visible);
    EXPECT_EQ(r.totals.audited + r.totals.unsampled, 50u);
    // What this subset finds (pinned: a change in the sampling or the walk shows here).
    EXPECT_EQ(r.totals.misses, 0u);
    EXPECT_GT(r.totals.slackPairs, 0u);
}

// ---- The command --------------------------------------------------------------------------------

namespace {
struct CmdResult {
    int code = -1;
    std::string out, err;
};
std::string slurp(const fs::path &p) {
    std::ifstream f(p);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}
CmdResult run(const fs::path &dir, const std::string &args) {
    const fs::path o = dir / "stdout.txt", e = dir / "stderr.txt";
    const std::string cmd = std::string(VISAUDIT_BINARY) + " " + args + " </dev/null >" + o.string() + " 2>" + e.string();
    const int status = std::system(cmd.c_str());
    CmdResult r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = slurp(o);
    r.err = slurp(e);
    return r;
}
}  // namespace

TEST_F(PvsAuditTest, CommandWritesJsonImageAndPage) {
    loadCorridor(fiveRooms(), dir_, "five.bsp");
    const fs::path out = dir_ / "audit";
    const CmdResult r = run(dir_, "pvs-audit " + (dir_ / "five.bsp").string() + " --out " + out.string() + " --samples 8 --resolution 8");
    ASSERT_EQ(r.code, 0) << r.err;
    for (const char *f : {"pvs-audit.json", "pvs-audit.png", "pvs-audit.html"}) EXPECT_TRUE(fs::exists(out / f)) << f;
    const nlohmann::json j = nlohmann::json::parse(slurp(out / "pvs-audit.json"));
    EXPECT_EQ(j["format"], "visaudit-pvs-audit/1");
    EXPECT_EQ(j["totals"]["misses"], 2);
    EXPECT_EQ(j["totals"]["crack_misses"], 1);
    EXPECT_EQ(j["totals"]["slack_pairs"], 2);
    EXPECT_EQ(j["settings"]["rays_per_sample"], 384);
    EXPECT_EQ(j["misses"].size(), 3u);
    EXPECT_EQ(j["image"], "pvs-audit.png");
    const std::string html = slurp(out / "pvs-audit.html");
    EXPECT_NE(html.find("<img src=\"pvs-audit.png\""), std::string::npos);
    EXPECT_EQ(html.find("http://"), std::string::npos);
    EXPECT_EQ(html.find("https://"), std::string::npos);
    EXPECT_NE(r.out.find("misses      2 cluster pairs"), std::string::npos) << r.out;
    // A second run replaces the folder (it holds pvs-audit.json); --json prints the totals.
    const CmdResult again = run(dir_, "pvs-audit " + (dir_ / "five.bsp").string() + " --out " + out.string() +
                                    " --samples 8 --resolution 8 --json");
    ASSERT_EQ(again.code, 0) << again.err;
    EXPECT_EQ(nlohmann::json::parse(again.out)["totals"]["misses"], 2);
}

TEST_F(PvsAuditTest, CommandRefusesWithMessages) {
    loadCorridor(fiveRooms(), dir_, "five.bsp");
    const std::string map = (dir_ / "five.bsp").string();
    CmdResult r = run(dir_, "pvs-audit " + map + " --clusters 3-1 --out " + (dir_ / "o").string());
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.err, "visaudit: error: --clusters 3-1: '3-1' is not a cluster or a range A-B (A <= B); give e.g. "
                     "--clusters 0-99,200\n");
    r = run(dir_, "pvs-audit " + map + " --clusters 9 --out " + (dir_ / "o").string());
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.err, "visaudit: error: --clusters: cluster 9 is outside the map's 5 clusters (0..4)\n");
    EXPECT_FALSE(fs::exists(dir_ / "o"));
    std::ofstream(dir_ / "cube.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    r = run(dir_, "pvs-audit " + (dir_ / "cube.obj").string() + " --out " + (dir_ / "o").string());
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.err, "visaudit: error: " + (dir_ / "cube.obj").string() +
                         ": cannot audit the PVS: not a Quake 3 map (.bsp): only a map has clusters and a PVS; give a "
                         "Quake 3 map (.bsp or pak.pk3:maps/x.bsp)\n");
}

TEST_F(PvsAuditTest, CheckGatesOnPvsMisses) {
    loadCorridor(fiveRooms(), dir_, "five.bsp");
    std::ofstream(dir_ / "budget.json") << R"({"format": "visaudit-budget/1", "limits": {"pvs_misses": 0, "pvs_slack_share": 0.5}})";
    std::ofstream(dir_ / "views.json")
        << R"({"views": [{"name": "a", "eye": [50, 0, 100], "target": [100, 0, 100], "width": 32, "height": 18}]})";
    const CmdResult r = run(dir_, "check " + (dir_ / "five.bsp").string() + " --views " + (dir_ / "views.json").string() +
                                " --budget " + (dir_ / "budget.json").string() + " --out " + (dir_ / "ck").string());
    EXPECT_EQ(r.code, 1) << r.err;
    EXPECT_NE(r.out.find("FAIL   (map)                pvs_misses"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("ok     (map)                pvs_slack_share"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("FAIL: pvs_misses of the map is 2, allowed 0"), std::string::npos) << r.out;
    EXPECT_TRUE(fs::exists(dir_ / "ck" / "pvs-audit.json"));
    EXPECT_TRUE(fs::exists(dir_ / "ck" / "report.json"));
    EXPECT_NE(slurp(dir_ / "ck" / "report.html").find("href=\"pvs-audit.html\""), std::string::npos);
    // Per view, a map-wide metric is refused before any work.
    std::ofstream(dir_ / "perview.json") << R"({"format": "visaudit-budget/1", "views": {"a": {"pvs_misses": 0}}})";
    const CmdResult bad = run(dir_, "check " + (dir_ / "five.bsp").string() + " --views " + (dir_ / "views.json").string() +
                                  " --budget " + (dir_ / "perview.json").string() + " --out " + (dir_ / "ck2").string());
    EXPECT_EQ(bad.code, 2);
    EXPECT_NE(bad.err.find("'pvs_misses' is one number for the whole map (the PVS audit), not per view"), std::string::npos)
        << bad.err;
}

// docs/pvs-audit.md names every key pvs-audit.json writes (as `key`), so the page a reader follows
// never lags the file.
TEST_F(PvsAuditTest, DocsNameEveryJsonKey) {
    const Scene s = loadCorridor(fiveRooms(), dir_);
    PvsAuditSettings st;
    st.samples = 4;
    st.resolution = 4;
    const nlohmann::ordered_json j = pvsAuditJson(audit(s, st), "pvs-audit.png");
    const std::string doc = slurp(fs::path(VISAUDIT_SOURCE_DIR) / "docs" / "pvs-audit.md");
    ASSERT_FALSE(doc.empty());
    auto keysOf = [&](const nlohmann::ordered_json &o, const std::string &where) {
        ASSERT_TRUE(o.is_object()) << where;
        for (const auto &[k, v] : o.items()) EXPECT_NE(doc.find("`" + k + "`"), std::string::npos) << where << "." << k;
    };
    keysOf(j, "top");
    for (const char *k : {"settings", "far_plane", "definition", "occluders", "totals", "histograms", "worst", "timings_ms"})
        keysOf(j[k], k);
    keysOf(j["clusters"][0], "clusters[]");
    ASSERT_FALSE(j["misses"].empty());
    keysOf(j["misses"][0], "misses[]");
    ASSERT_FALSE(j["worst"]["slack"].empty());
    keysOf(j["worst"]["slack"][0], "worst.slack[]");
    keysOf(j["histograms"]["misses"][0], "histograms.misses[]");
}
