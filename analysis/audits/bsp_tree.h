// A BSP tree over the scene's view-independent triangles (docs/architecture.md, Audits: Ordering;
// docs/ordering.md). Built once per scene; traversed per view back to front (painter's order
// that is always right) or front to back (least overdraw with a depth test).
//
// Robust plane classification. A node's plane is the plane of one *source* triangle, given by its
// three input vertices (exact doubles). Which side of it a vertex lies on is decided by CGAL's
// exact orientation predicate (filtered: exact arithmetic only when the double result is
// uncertain), so topology -- coplanar, front, back, straddling -- never depends on rounding:
//   * a vertex of an input triangle is classified exactly;
//   * a vertex made by a split (a construction, computed in double on the split edge) is ON the
//     plane that made it by definition (never re-evaluated against it), and classified exactly
//     *as the double point it is* against every later plane (the rounded point, which lies within
//     rounding of the true intersection; a later plane through the true intersection may then see
//     it a few ulps off and cut a sliver -- counted in BspStats::degeneratePieces when one is empty);
//   * a piece is coplanar with a plane when its source triangle's three input vertices are all on
//     it (exact), whatever the rounding of its constructed vertices.
// Only pieces with a vertex strictly in front and one strictly behind are split; vertices on the
// plane go to both halves, so a vertex exactly on a splitting plane makes no split and no sliver.
// Coplanar pieces stay on the node.
#pragma once

#include <cstdint>
#include <vector>

#include "analysis/scene.h"
#include "render/camera.h"

namespace va {

// Exact sign of det[b - a, c - a, d - a] = ((b - a) x (c - a)) . (d - a): +1 when d lies on the front
// side of triangle (a, b, c) (where its counter-clockwise normal points), -1 behind, 0 coplanar.
// A static filter, then exact stages (zeros it can see, integer arithmetic when the coordinates lie
// on one power-of-two grid), then CGAL's orientation predicate (Exact_predicates_inexact_constructions_kernel).
int orient3d(Vec3 a, Vec3 b, Vec3 c, Vec3 d);

// orient3d(a, b, c, d) for many points d against one plane: the same exact sign, with the work that
// depends on the plane alone done once. A plane whose three points share one coordinate exactly
// (an axis-aligned face: most faces of a brush-built level) decides by comparing that coordinate
// (the determinant is (d - a) on that axis times a fixed cofactor, whose exact sign orient3d gives
// once); any other runs orient3d's static filter with the plane's minors and their magnitudes
// precomputed, and orient3d itself only where the filter cannot tell.
class PlaneSide {
public:
    PlaneSide(Vec3 a, Vec3 b, Vec3 c);
    // Inline: the BSP build asks this for every vertex of every piece it scores or partitions.
    int operator()(Vec3 d) const {
        if (axis_ >= 0) return axisSign_ * ((d[axis_] > a_[axis_]) - (d[axis_] < a_[axis_]));
        const int s = filterSign(d.x - a_.x, d.y - a_.y, d.z - a_.z, n_, m_);
        return s != 2 ? s : undecided(d);
    }

    // The filter's sign for each of n points (x[i], y[i], z[i]) into out[i], or 2 where it cannot
    // tell (then operator() decides: undecided()). A loop the compiler vectorizes.
    void filterSigns(const double *x, const double *y, const double *z, size_t n, int32_t *out) const;
    int undecided(Vec3 d) const;  // orient3d's exact stages, for the points the filter cannot tell

    // orient3d's static filter for r3 = d - a against a plane's minors n and their magnitudes m
    // (below): the sign, or 2 when the double determinant is within its error bound of 0.
    static int filterSign(double r3x, double r3y, double r3z, const double *n, const double *m) {
        const double det = r3x * n[0] + r3y * n[1] + r3z * n[2];
        const double permanent = std::fabs(r3x) * m[0] + std::fabs(r3y) * m[1] + std::fabs(r3z) * m[2];
        constexpr double eps = 0x1p-53;
        const double bound = (7.0 + 56.0 * eps) * eps * permanent;
        return det > bound ? 1 : (det < -bound ? -1 : 2);
    }

private:
    Vec3 a_, b_, c_;
    int axis_ = -1;        // 0, 1, 2: a, b and c share that coordinate; -1: none
    int axisSign_ = 0;     // the sign for a point beyond a on that axis (0: a degenerate triangle)
    double n_[3] = {};     // (b - a) x (c - a), rounded as orient3d's filter rounds its minors
    double m_[3] = {};     // per component, the sum of its two products' magnitudes (the permanent's)
};

// Splitter choice (a stated heuristic, Thibault & Naylor / Fuchs' "least splits" family): at each
// node, `candidates` pieces spread evenly over the node's list are tried as the splitting plane
// (0 = every piece), each scored over `scoreSample` pieces spread evenly over the list (0 = all) as
//     splitWeight * (pieces it splits) + balanceWeight * |pieces in front - pieces behind|,
// and the lowest score wins (ties: the earlier candidate). {16, 1, 0}: fewest splits; {16, 0, 1}:
// balance. A node costs O(candidates * scoreSample) for the choice and O(pieces) for the partition.
struct BspSettings {
    uint32_t candidates = 16;
    double splitWeight = 8;
    double balanceWeight = 1;
    uint32_t scoreSample = 256;
};

// A convex piece of a source triangle: the whole triangle, or what splits left of it.
struct BspPiece {
    uint32_t source = 0;                               // source triangle id (kept through splits)
    uint32_t firstVertex = 0, vertexCount = 0;         // BspTree::vertices, in the source's winding
    uint32_t firstConstraint = 0, constraintCount = 0; // BspTree::constraints: the splits that cut it
                                                       //   out of its source (0 for an unsplit piece)
};

// "The piece lies on this side of node `node`'s plane" (a split that produced it).
struct BspConstraint {
    uint32_t node = 0;
    bool front = false;  // true: the plane's front side (>= 0), false: behind
};

struct BspTreeNode {
    uint32_t planeSource = 0;            // the source triangle whose plane splits here
    int32_t front = -1, back = -1;       // child nodes (-1: empty)
    uint32_t firstPiece = 0, pieceCount = 0;  // BspTree::nodePieces: the pieces coplanar with the plane
};

struct BspStats {
    uint64_t trianglesIn = 0;        // source triangles the tree was built over (non-excluded)
    uint64_t pieces = 0;             // convex pieces in the tree (= trianglesIn + splits); best trianglesIn
    uint64_t trianglesOut = 0;       // triangles of the pieces' fans (a k-gon is k - 2); best trianglesIn
    uint64_t splits = 0;             // pieces split in two; best 0 (worst case of a BSP of n triangles: O(n^2))
    uint64_t splitSources = 0;       // source triangles split at least once
    uint64_t degeneratePieces = 0;   // pieces with zero area in double (slivers of constructed vertices); best 0
    uint64_t nodes = 0;              // nodes (each holds at least one coplanar piece)
    uint32_t depth = 0;              // longest root-to-leaf path, in nodes (1 = a single node)
    double averageLeafDepth = 0;     // mean depth of the nodes without children
    uint64_t predicateCalls = 0;     // exact orientation predicates evaluated (candidate scoring + partition)
    double buildMs = 0;              // wall time of the build
    uint64_t memoryBytes = 0;        // bytes held by the tree (nodes, pieces, vertices, constraints)
};

struct BspTree {
    std::vector<BspTreeNode> nodes;             // nodes[0] is the root (empty: no triangles)
    std::vector<BspPiece> pieces;
    std::vector<uint32_t> nodePieces;       // pieces per node, contiguous runs
    std::vector<Vec3> vertices;             // world space; input vertices copied exactly
    std::vector<BspConstraint> constraints;
    BspStats stats;
};

// Builds the tree over every non-excluded triangle of the scene (in source order).
BspTree buildBspTree(const Scene &scene, const BspSettings &settings = {});

// The same over an explicit list of source triangles (tests, subsets).
BspTree buildBspTree(const Scene &scene, const std::vector<uint32_t> &triangles, const BspSettings &settings);

// Piece indices in back-to-front order for a viewer at cam.eye (orthographic: looking along
// cam.forward): at each node the far side, then the node's pieces, then the near side. The eye's
// side of a node's plane is decided by the exact predicate (perspective). Reverse it for front to
// back.
std::vector<uint32_t> bspBackToFront(const BspTree &tree, const Scene &scene, const Camera &cam);

// Whether the view-space point p lies in piece k's part of its source triangle, i.e. satisfies
// every constraint of the piece (node plane >= 0 for front, < 0 for behind, in double). The pieces of
// one source partition its plane: every point satisfies exactly one piece's constraints.
struct BspViewPlanes {
    std::vector<double> plane;  // 4 per node: the node's world plane in view space, n.p + k
};
BspViewPlanes bspViewPlanes(const BspTree &tree, const Scene &scene, const Camera &cam);
inline bool bspPieceContains(const BspTree &tree, const BspViewPlanes &vp, uint32_t piece, Vec3 pView) {
    const BspPiece &p = tree.pieces[piece];
    for (uint32_t i = 0; i < p.constraintCount; ++i) {
        const BspConstraint &c = tree.constraints[p.firstConstraint + i];
        const double *q = &vp.plane[4 * size_t(c.node)];
        const bool front = (q[0] * pView.x + q[1] * pView.y + q[2] * pView.z) + q[3] >= 0;
        if (front != c.front) return false;
    }
    return true;
}

}  // namespace va
