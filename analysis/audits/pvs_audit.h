// The PVS audit of a whole Quake 3 map (`visaudit pvs-audit MAP`; docs/pvs-audit.md): eye points
// sampled inside every cluster look in all directions, and what their rays see is compared with
// the cluster's PVS row.
//
// What "cluster D is seen from sample s" means (the definition every count rests on):
//   A ray from s sees every cluster whose leaf volume it passes through before it stops. The ray is
//   walked through the world's BSP tree front to back (an explicit stack: nothing recurses on the
//   tree's depth); it stops at the first of
//     - an opaque surface: a drawn face of the world (model 0) hit from its front (Embree,
//       rtcIntersect16 streams) -- faces that do not block sight are listed below;
//     - a leaf with no cluster (cluster -1: solid structure or the void outside the map);
//     - the map's box (a sealed map never gets there).
//   A leaf counts when the ray stays in it for more than the tolerance `tolerance` (a length
//   derived from float rounding; shorter visits are grazes of an edge or corner and are not counted:
//   conservative, a miss is never claimed from a graze). The leaf's cluster is then seen within the
//   far plane when that stay begins before the far-plane distance (with more than the tolerance
//   left before it), else seen beyond the far plane.
// What does not block sight: sky (the ray goes on into the sky brush: a solid leaf, where it stops),
// water, slime, lava and fog (the loader's non-solid see-through faces), translucent faces
// (CONTENTS_TRANSLUCENT: glass, grates -- vis sees through them too), nodraw/hint/skip/clip tool
// surfaces (never drawn), brush entities (models 1..n: doors taken as open, movers and triggers
// not where they rest in play -- as the cells stage takes every door as open), and back faces
// (the renderer culls them; the project's reference visibility treats them the same way).
//
// Eye points are drawn anywhere in the cluster's volume outside solid (every cluster with room in
// it is audited); each is also classified: can a player's eye be there (playerEyeFits)?
// Per audited cluster C:
//   misses       = clusters seen within the far plane although C's PVS row says invisible, from an
//                  eye point where a player's eye can be (a PVS bug a player sees: each carries
//                  its evidence);
//   crack misses = the same seen only from eye points no player's eye reaches (slivers by walls,
//                  where q3map2 drops tiny portals): listed with evidence, not counted as misses;
//   slack        = clusters C's PVS row marks visible that no eye point of C sees within the far
//                  plane (draws the level pays for; an upper bound, which more samples and rays can
//                  only lower).
// Deterministic: each cluster draws its eye points and ray rotations from its own seeded sequence
// (splitmix64 of the seed and the cluster), rays go in a fixed order, and totals are summed in
// cluster order -- the same counts for any thread count.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "analysis/scene.h"

namespace va {

struct PvsAuditSettings {
    int samples = 32;             // eye points per cluster (--samples)
    int resolution = 12;          // cube-face side: rays per eye point = 6 * resolution^2 (--resolution)
    uint64_t seed = 1;            // --seed
    double farPlane = -1;         // < 0: the map's own (_farplanedist); 0: unlimited; > 0: this distance
    std::vector<int32_t> clusters;  // the clusters to audit, ascending; empty: every cluster
    int imageSize = 1024;         // longest side of the top-down map image, pixels (0: none)
    int threads = 0;              // 0: every core
    const std::atomic<int> *cancel = nullptr;  // polled between clusters: nonzero stops the audit
    // Called after each cluster from the worker that audited it (progress lines): clusters done, total.
    std::function<void(size_t, size_t)> progress;
};
constexpr int kPvsAttemptsPerSample = 32;  // candidate points drawn per eye point before a cluster gives up

// Where a ray stopped; `eye`: no ray, the eye point itself lies in the cluster (a row without its own bit).
enum class PvsStop : uint8_t { surface, solid, bounds, eye };
const char *pvsStopName(PvsStop s);  // "surface", "solid_leaf", "map_bounds", "eye"

// The evidence of one miss: the first ray (in sample, then ray order) from an eye point where a
// player's eye can be that saw cluster `to` from cluster `from` within the far plane although bit
// `to` of row `from` is 0 -- or, for a crack miss, the first such ray from any eye point.
struct PvsMiss {
    int32_t from = -1, to = -1;
    uint32_t sample = 0;          // index of the eye point among `from`'s
    Vec3 eye;                     // the eye point (world units)
    Vec3 direction;               // unit direction of the ray
    int32_t eyeLeaf = -1;         // the leaf holding the eye (cluster `from`)
    bool playerEye = false;       // a player's eye can be at `eye` (a miss; false: a crack miss)
    int32_t leaf = -1;            // the leaf of cluster `to` the ray passed through
    double enter = 0, exit = 0;   // distances from the eye where the ray entered and left that leaf
    double stop = 0;              // distance where the ray stopped
    PvsStop stoppedBy = PvsStop::bounds;
    uint32_t stopTriangle = 0xFFFFFFFFu;  // surface: the source triangle hit
    uint32_t stopFace = 0xFFFFFFFFu;      // surface: its face (faces lump index)
    int32_t stopLeaf = -1;        // solid: the leaf with no cluster it entered
    uint64_t rays = 0;            // rays of `from`'s eye points that saw `to` within the far plane
    uint64_t pvsByte = 0;         // the byte holding the bit: offset from the start of the PVS rows
                                  //   (visdata byte 8 + this), = from * row bytes + to / 8
    int pvsBit = 0;               // bit (to & 7) of that byte: its value is 0
    uint8_t pvsByteValue = 0;     // the whole byte as stored
};

struct PvsClusterAudit {
    int32_t cluster = -1;
    uint32_t leafs = 0;           // leafs of the world's tree in the cluster
    Aabb bounds;                  // union of their boxes
    uint32_t samples = 0;         // eye points found (settings.samples unless the attempts ran out)
    uint32_t attempts = 0;        // candidate points drawn (uniform in a leaf's box, leafs by volume)
    uint32_t rejectedOther = 0;   // candidates whose leaf (walking the tree) is not in this cluster
    uint32_t rejectedSolid = 0;   // candidates inside a solid brush of their leaf (a detail brush)
    std::vector<Vec3> eyes;       // the eye points, in sampling order
    std::vector<uint8_t> playerEye;  // per eye point: 1 when a player's eye can be there (playerEyeFits)
    uint32_t playerSamples = 0;   // eye points where a player's eye can be
    uint64_t rays = 0;            // rays cast: samples * 6 * resolution^2
    uint32_t pvsVisible = 0;      // clusters the PVS row marks visible (itself included)
    uint32_t seen = 0;            // clusters seen within the far plane (itself included once sampled)
    uint32_t misses = 0;          // seen within the far plane from an eye point where a player's eye can
                                  //   be, PVS bit 0: a PVS bug a player sees -- best 0
    uint32_t crackMisses = 0;     // seen within the far plane with PVS bit 0 only from eye points where no
                                  //   player's eye can be (cracks, slivers by walls): no player sees them
    uint32_t slack = 0;           // PVS bit 1, not seen within the far plane -- lower is tighter
    uint32_t seenBeyondFar = 0;   // seen only beyond the far plane
    uint32_t hiddenByFarPlane = 0;  // of those, PVS bit 0: left out by the map's distance limit, by design
    std::vector<PvsMiss> missList;  // one per missed cluster (misses and crack misses), ascending `to`
    double slackShare() const { return pvsVisible ? double(slack) / pvsVisible : 0.0; }
};

// The surfaces the rays treat as opaque, and those they pass (triangles of the scene).
struct PvsOccluders {
    uint64_t opaque = 0;          // drawn world triangles (degenerate ones excluded): block rays
    uint64_t translucent = 0;     // drawn world triangles with CONTENTS_TRANSLUCENT: passed
    uint64_t entity = 0;          // drawn triangles of brush models 1..n: passed
};

struct PvsAuditTotals {
    uint32_t clusters = 0;        // clusters in the map (PVS rows)
    uint32_t requested = 0;       // clusters asked for (all, or --clusters)
    uint32_t audited = 0;         // of those, clusters with at least one eye point
    uint32_t unsampled = 0;       // clusters asked for where no eye point was found (no leaf in the tree,
                                  //   or every candidate in solid): listed, not audited -- best 0
    uint64_t samples = 0, rays = 0;
    uint64_t pvsVisiblePairs = 0; // over audited clusters: PVS bits set in their rows
    uint64_t seenPairs = 0;       // (cluster, cluster) pairs seen within the far plane
    uint64_t misses = 0;          // pairs seen within the far plane with PVS bit 0 -- best 0
    uint32_t missClusters = 0;    // audited clusters with at least one miss -- best 0
    uint64_t crackMisses = 0;     // pairs seen with PVS bit 0 only from eye points where no player's eye can be
    uint32_t playerClusters = 0;  // audited clusters with at least one eye point where a player's eye can be
    uint64_t slackPairs = 0;      // pairs with PVS bit 1 never seen within the far plane
    double slackShare = 0;        // slackPairs / pvsVisiblePairs (0..1) -- lower is tighter
    uint64_t seenBeyondFarPairs = 0;     // pairs seen only beyond the far plane
    uint64_t hiddenByFarPlanePairs = 0;  // of those, PVS bit 0 (by design, not misses)
};

// The level seen from above (orthographic, looking down -z): one ray per pixel center with back
// faces passed (floors face up, ceilings down), the same opaque surfaces as the audit.
struct PvsTopView {
    int width = 0, height = 0;
    double x0 = 0, y1 = 0, pixel = 1;  // world x of column 0's left edge, y of row 0's top edge, units per pixel
    std::vector<float> surfaceZ;  // per pixel: the surface's z (NaN: nothing below)
    std::vector<float> slope;     // per pixel: |normal . z| of the surface, 1 for a floor, 0 for a wall
    std::vector<int32_t> cluster; // per pixel: the cluster just above the surface (-1: none)
    // World (x, y) -> pixel coordinates (column, row), fractional.
    double column(double x) const { return (x - x0) / pixel; }
    double row(double y) const { return (y1 - y) / pixel; }
};

struct PvsAuditResult {
    std::string map;
    PvsAuditSettings settings;    // as run (samples, resolution, seed, clusters)
    int raysPerSample = 0;        // 6 * resolution^2
    double farPlane = 0;          // the distance used; 0: unlimited
    std::string farPlaneSource;   // "_farplanedist" (or the worldspawn key that set it), "--far-plane", "none"
    std::string farPlaneText;     // the key's text as the map stores it ("" otherwise)
    double tolerance = 0;         // shortest stay in a leaf that counts as seeing it, world units
    double mapDiagonal = 0;       // the box's diagonal: no ray goes farther
    int32_t clusterCount = 0;
    uint32_t pvsRowBytes = 0;
    PvsOccluders occluders;
    std::vector<PvsClusterAudit> clusters;  // the requested clusters, ascending
    PvsAuditTotals totals;
    // Audited clusters per slack share: bin k holds shares in [k/10, (k+1)/10) (the last bin includes 1).
    std::vector<uint64_t> slackHistogram;
    // Audited clusters per miss count: 0, 1, 2-3, 4-7, 8-15, 16-31, 32+.
    std::vector<uint64_t> missHistogram;
    PvsTopView top;
    // Time: wall milliseconds of the phases, and thread milliseconds inside the cluster loop.
    double setupMs = 0;           // the ray scene built, clusters' leafs listed
    double auditMs = 0;           // every cluster (wall)
    double topViewMs = 0;         // the map image's rays
    double sampleThreadMs = 0, castThreadMs = 0, walkThreadMs = 0;  // summed over threads: eye points, Embree, BSP walk
};

// The map's designed far plane: the worldspawn's "_farplanedist" (q3map2's vis; also "fogclip",
// "distancecull" of other games): its number, > 0; 0 when it has none. *key and *text (optional)
// receive the key and its value.
double mapFarPlane(const BspLevel &level, std::string *key = nullptr, std::string *text = nullptr);

// Why the audit cannot run on this scene (nullptr: it can): not a Quake 3 map, or no PVS.
const char *pvsAuditSkipReason(const Scene &scene);

// Whether a player's eye can be at `eye`: Quake 3's crouched player box around it (x, y within 15
// units, z from 36 below to 4 above: bg_public.h's mins -15 -15 -24, crouched maxs 15 15 16, eye 12
// above the origin) reaches no leaf without a cluster and overlaps no brush that stops a player
// (CONTENTS_SOLID or CONTENTS_PLAYERCLIP). A standing player's box around its eye contains the
// crouched one, so every position a player's eye can take passes.
bool playerEyeFits(const BspLevel &level, Vec3 eye);

// Runs the audit. False + *err on bad settings (a cluster out of range, samples or resolution < 1)
// or when cancelled ("interrupted").
bool auditPvs(const Scene &scene, const PvsAuditSettings &settings, PvsAuditResult *out, std::string *err);

// The walk behind the definition above, exposed for tests: calls leaf(leafIndex, t0, t1) for each
// leaf the segment eye + t * dir, t in [0, tEnd], passes through, front to back; stops early when
// leaf returns false. Iterative (explicit stack).
void walkBspSegment(const BspLevel &level, Vec3 eye, Vec3 dir, double tEnd,
                    const std::function<bool(int32_t, double, double)> &leaf);

}  // namespace va
