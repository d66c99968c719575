// Portal traversal: camera cells, Sutherland-Hodgman clipping of portals against the current
// frustum, frustum narrowing through each portal, and per-object cell sets (docs/coarse-stages.md).
#include "analysis/stages/portals.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "analysis/stages/frustum.h"

namespace va {

namespace {

// Rounding bound of evaluating n.p + k for a face of a cell (normal given in the scene file, not
// computed: no tilt term).
double faceErrorBound(const HalfSpace &f, Vec3 p) {
    return gamma(16) * (std::fabs(f.n.x * p.x) + std::fabs(f.n.y * p.y) + std::fabs(f.n.z * p.z) + std::fabs(f.k));
}

bool cellContains(const Cell &c, Vec3 p) {
    for (const HalfSpace &f : c.faces)
        if (dot(f.n, p) + f.k < -faceErrorBound(f, p)) return false;
    return true;
}

// Conservative box-cell overlap: the box is outside the cell when it is outside one face by more
// than the rounding bound (the corner farthest along the face's normal decides).
bool boxOverlapsCell(const Aabb &b, const Cell &c) {
    for (const HalfSpace &f : c.faces) {
        const Vec3 far{f.n.x >= 0 ? b.hi.x : b.lo.x, f.n.y >= 0 ? b.hi.y : b.lo.y, f.n.z >= 0 ? b.hi.z : b.lo.z};
        if (dot(f.n, far) + f.k < -faceErrorBound(f, far)) return false;
    }
    return true;
}

// A portal's plane: Newell normal (exact for planar polygons, a least-squares-like normal
// otherwise) through the centroid, and how far the points stray from it (0 for a planar
// polygon up to rounding; the loader refuses more than 1e-6 of the polygon's size).
struct PortalPlane {
    Vec3 n;          // unit
    double k = 0;
    Vec3 centroid;
    double deviation = 0;  // max |n.p + k| over the points, plus its own rounding bound
    double tilt = 0;       // bound on the angle error of n (radians)
    bool valid = false;    // false: zero area (collinear points)
};

PortalPlane portalPlane(const std::vector<Vec3> &pts) {
    PortalPlane pp;
    const size_t m = pts.size();
    Vec3 N{0, 0, 0}, c{0, 0, 0};
    double M = 0;
    for (size_t i = 0; i < m; ++i) {
        const Vec3 &a = pts[i], &b = pts[(i + 1) % m];
        N.x += (a.y - b.y) * (a.z + b.z);
        N.y += (a.z - b.z) * (a.x + b.x);
        N.z += (a.x - b.x) * (a.y + b.y);
        c = c + a;
        M = std::max(M, maxAbs(a));
    }
    c = c / double(m);
    const double len = length(N);
    if (!(len > 0)) return pp;
    pp.n = N / len;
    pp.centroid = c;
    pp.k = -dot(pp.n, c);
    // Each Newell component sums m products of a difference (|.| <= 2M) and a sum (|.| <= 2M), each
    // term with gamma(3) relative error, the sum gamma(m) more: error <= gamma(m + 3) 4 m M^2 per
    // component; against |N|, the angle error.
    pp.tilt = gamma(int(m) + 3) * 4.0 * double(m) * M * M * std::sqrt(3.0) / len + gamma(4);
    for (const Vec3 &p : pts) {
        const double d = std::fabs(dot(pp.n, p) + pp.k);
        pp.deviation = std::max(pp.deviation, d + gamma(16) * (maxAbs(p) * 3 + std::fabs(pp.k)) +
                                                  pp.tilt * length(p - c));
    }
    pp.valid = true;
    return pp;
}

// Is the eye (in the portal's plane) inside the polygon? Each edge's inward side, in the plane:
// dot(n, (b - a) x (e - a)) >= 0 for a counter-clockwise polygon about n (the Newell normal's
// orientation), with a rounding bound on the triple product.
bool eyeInsidePolygon(const std::vector<Vec3> &pts, const PortalPlane &pp, Vec3 e) {
    const size_t m = pts.size();
    for (size_t i = 0; i < m; ++i) {
        const Vec3 &a = pts[i], &b = pts[(i + 1) % m];
        const Vec3 ab = b - a, ae = e - a;
        const double t = dot(pp.n, cross(ab, ae));
        const double bound = (gamma(8) + pp.tilt) * 3 * (length(ab) + maxAbs(a) + maxAbs(b)) *
                             (length(ae) + maxAbs(a) + maxAbs(e));
        if (t < -bound) return false;
    }
    return true;
}

struct Traversal {
    const Scene &scene;
    const Camera &cam;
    const PortalSettings &settings;
    PortalStats &st;
    std::vector<uint8_t> &visible;
    std::vector<std::vector<uint32_t>> adjacency;  // per cell: its portals
    std::vector<PortalPlane> planes;               // per portal
    std::vector<uint8_t> onPath;
    FrustumPlane camNear, camFar;
    bool budgetOut = false;

    // Conservative fallback: every cell the portal graph reaches from `start`.
    void markReachable(uint32_t start) {
        std::vector<uint8_t> seen(visible.size(), 0);
        std::vector<uint32_t> stack{start};
        seen[start] = 1;
        while (!stack.empty()) {
            const uint32_t c = stack.back();
            stack.pop_back();
            visible[c] = 1;
            for (uint32_t p : adjacency[c]) {
                const Portal &po = scene.portals[p];
                const uint32_t nb = po.cells[0] == c ? po.cells[1] : po.cells[0];
                if (!seen[nb]) {
                    seen[nb] = 1;
                    stack.push_back(nb);
                }
            }
        }
    }

    // The frustum seen through `poly` (already clipped): the planes through the eye (perspective) or
    // along the view direction (orthographic) and each edge, inward, then the portal's plane as a
    // near plane (the eye's side outside) and the camera's near and far planes.
    std::vector<FrustumPlane> narrow(const std::vector<Vec3> &poly, const PortalPlane &pp, bool eyeOnPositiveSide) const {
        std::vector<FrustumPlane> out;
        Vec3 g{0, 0, 0};
        for (const Vec3 &v : poly) g = g + v;
        g = g / double(poly.size());
        const Vec3 e = cam.eye;
        for (size_t i = 0; i < poly.size(); ++i) {
            const Vec3 &vi = poly[i], &vj = poly[(i + 1) % poly.size()];
            Vec3 n, anchor;
            double condition = 0;  // |a||b| (with the rounding of a and b) over |a x b|
            if (cam.orthographic) {
                const Vec3 a = vj - vi;
                n = cross(a, cam.forward);
                anchor = vi;
                condition = (length(a) + maxAbs(vi) + maxAbs(vj)) * 1.0;
            } else {
                const Vec3 a = vi - e, b = vj - e;
                n = cross(a, b);
                anchor = e;
                condition = (length(a) + maxAbs(vi) + maxAbs(e)) * (length(b) + maxAbs(vj) + maxAbs(e));
            }
            const double len = length(n);
            // Coincident clipped vertices or an edge in line with the eye give no plane: dropping a
            // plane only widens the frustum (conservative).
            if (!(len > 0)) continue;
            // Cross product of rounded differences: each component's error is at most
            // gamma(4) (|a| + rounding)(|b| + rounding) summed over its two products; over |a x b|
            // that bounds the angle error of the normal.
            const double tilt = 3 * gamma(4) * condition / len;
            if (!(tilt < 0.5)) continue;  // too ill-conditioned to mean anything: drop (conservative)
            n = n / len;
            double k = -dot(n, anchor);
            const FrustumPlane cand{n, k, tilt, anchor};
            // Inward: the centroid of the (convex) clipped polygon is inside. A centroid within the
            // plane's error bound means a degenerate sliver: no plane (conservative).
            const double s = dot(n, g) + k;
            if (std::fabs(s) <= planeErrorBound(cand, g)) continue;
            if (s < 0) {
                n = -n;
                k = -k;
            }
            out.push_back({n, k, tilt, anchor});
        }
        // The portal's plane, oriented with the eye outside, moved towards the eye by the points'
        // deviation so that every point of the portal is inside it.
        FrustumPlane near{pp.n, pp.k, pp.tilt, pp.centroid};
        if (eyeOnPositiveSide) {
            near.n = -near.n;
            near.k = -near.k;
        }
        near.k += pp.deviation;
        out.push_back(near);
        out.push_back(camNear);
        out.push_back(camFar);
        return out;
    }

    void enter(uint32_t cell, const std::vector<FrustumPlane> &fr, uint32_t depth) {
        onPath[cell] = 1;
        for (uint32_t p : adjacency[cell]) {
            if (budgetOut) break;
            const Portal &po = scene.portals[p];
            const uint32_t nb = po.cells[0] == cell ? po.cells[1] : po.cells[0];
            if (onPath[nb]) continue;  // back along the current path: never a new view
            if (st.portalsTested >= settings.maxPortalTests) {
                budgetOut = true;
                break;
            }
            ++st.portalsTested;
            const PortalPlane &pp = planes[p];
            if (!pp.valid) continue;  // zero area (the loader refuses these)

            // Which side of the portal's plane the camera is on; within the bound: in the plane.
            bool positive = false, inPlane = false;
            if (cam.orthographic) {
                const double s = -dot(pp.n, cam.forward);
                inPlane = std::fabs(s) <= gamma(16) * 3 + pp.tilt;
                positive = s > 0;
            } else {
                const double s = dot(pp.n, cam.eye) + pp.k;
                const double bound = gamma(16) * (std::fabs(pp.n.x * cam.eye.x) + std::fabs(pp.n.y * cam.eye.y) +
                                                  std::fabs(pp.n.z * cam.eye.z) + std::fabs(pp.k)) +
                                     pp.deviation + pp.tilt * length(cam.eye - pp.centroid);
                inPlane = std::fabs(s) <= bound;
                positive = s > 0;
            }
            std::vector<FrustumPlane> next;
            if (inPlane) {
                // The eye stands in the portal's plane. Inside the polygon (in the doorway): the
                // camera is as much in the neighbour as here, which is seen with the whole current
                // frustum. Outside it: the portal is seen edge-on and shows no area.
                if (cam.orthographic || !eyeInsidePolygon(po.points, pp, cam.eye)) {
                    ++st.portalsEdgeOn;
                    continue;
                }
                ++st.portalsInPortal;
                next = fr;
            } else {
                const std::vector<Vec3> clipped = clipPolygon(po.points, fr);
                if (clipped.size() < 3) continue;  // outside the current frustum: nothing seen through it
                next = narrow(clipped, pp, positive);
            }
            ++st.portalsPassed;
            ++st.cellsVisited;
            visible[nb] = 1;
            if (depth + 1 >= settings.maxDepth) {
                ++st.depthLimitHits;
                markReachable(nb);
                continue;
            }
            enter(nb, next, depth + 1);
        }
        onPath[cell] = 0;
    }
};

}  // namespace

double planeErrorBound(const FrustumPlane &pl, Vec3 p) {
    return gamma(16) * (std::fabs(pl.n.x * p.x) + std::fabs(pl.n.y * p.y) + std::fabs(pl.n.z * p.z) + std::fabs(pl.k)) +
           pl.tilt * length(p - pl.anchor);
}

std::vector<Vec3> clipPolygon(const std::vector<Vec3> &poly, const std::vector<FrustumPlane> &planes) {
    std::vector<Vec3> cur = poly, next;
    std::vector<double> d;
    for (const FrustumPlane &pl : planes) {
        if (cur.size() < 3) break;
        // Signed distances, each raised by its error bound: >= 0 is inside (or too close to tell),
        // so the clip can only keep more than the exact one.
        d.resize(cur.size());
        bool allIn = true, allOut = true;
        for (size_t i = 0; i < cur.size(); ++i) {
            d[i] = dot(pl.n, cur[i]) + pl.k + planeErrorBound(pl, cur[i]);
            allIn = allIn && d[i] >= 0;
            allOut = allOut && d[i] < 0;
        }
        if (allIn) continue;
        if (allOut) return {};
        // Sutherland-Hodgman: keep inside vertices, add the crossing point of every edge that
        // changes side, computed from the inside vertex towards the outside one.
        next.clear();
        for (size_t i = 0; i < cur.size(); ++i) {
            const size_t j = (i + 1) % cur.size();
            const bool inI = d[i] >= 0, inJ = d[j] >= 0;
            if (inI) next.push_back(cur[i]);
            if (inI != inJ) {
                const size_t a = inI ? i : j, b = inI ? j : i;
                const double t = d[a] / (d[a] - d[b]);  // in [0, 1): d[a] >= 0 > d[b]
                next.push_back(cur[a] + (cur[b] - cur[a]) * t);
            }
        }
        std::swap(cur, next);
    }
    if (cur.size() < 3) return {};
    return cur;
}

void assignObjectsToCells(Scene &scene) {
    scene.objectCellsBegin.assign(1, 0);
    scene.objectCells.clear();
    if (scene.cells.empty()) {
        scene.objectCellsBegin.assign(scene.objects.size() + 1, 0);
        return;
    }
    for (const SceneObject &o : scene.objects) {
        for (uint32_t c = 0; c < scene.cells.size(); ++c)
            if (boxOverlapsCell(o.bounds, scene.cells[c])) scene.objectCells.push_back(c);
        scene.objectCellsBegin.push_back(uint32_t(scene.objectCells.size()));
    }
}

std::vector<uint32_t> cellsContaining(const Scene &scene, Vec3 p) {
    std::vector<uint32_t> out;
    for (uint32_t c = 0; c < scene.cells.size(); ++c)
        if (cellContains(scene.cells[c], p)) out.push_back(c);
    return out;
}

const char *portalsSkipReason(const Scene &scene) {
    if (scene.cells.empty()) return "scene has no cells or portals";
    return nullptr;
}

PortalResult cullPortals(const Scene &scene, const Camera &cam, const PortalSettings &settings,
                         const std::vector<uint32_t> *candidates) {
    PortalResult r;
    PortalStats &st = r.stats;
    const uint32_t nCells = uint32_t(scene.cells.size());
    st.cellsTotal = nCells;
    r.cellVisible.assign(nCells, 0);

    // The camera's cells: every cell whose closed region holds the eye (the eye decides, not the
    // near plane). Two cells when it stands on their shared face.
    const std::vector<uint32_t> start = cellsContaining(scene, cam.eye);
    st.cameraCells = uint32_t(start.size());
    st.cameraCell = start.empty() ? -1 : int32_t(start[0]);
    st.cameraOutside = start.empty();

    if (!start.empty()) {
        Traversal tr{scene, cam, settings, st, r.cellVisible, {}, {}, {}, {}, {}, false};
        tr.adjacency.assign(nCells, {});
        for (uint32_t p = 0; p < scene.portals.size(); ++p) {
            tr.adjacency[scene.portals[p].cells[0]].push_back(p);
            tr.adjacency[scene.portals[p].cells[1]].push_back(p);
            tr.planes.push_back(portalPlane(scene.portals[p].points));
        }
        tr.onPath.assign(nCells, 0);
        // The camera's frustum: the six planes of the frustum stage (camera.h conventions), with
        // the same gamma(16) bound on their construction as a tilt.
        const FrustumPlanes fp = worldFrustumPlanes(cam);
        std::vector<FrustumPlane> fr;
        for (int i = 0; i < 6; ++i) fr.push_back({fp.n[i], fp.k[i], gamma(16), cam.eye});
        tr.camNear = fr[kPlaneNear];
        tr.camFar = fr[kPlaneFar];
        for (uint32_t c : start) {
            r.cellVisible[c] = 1;
            ++st.cellsVisited;
        }
        for (uint32_t c : start) {
            if (tr.budgetOut) break;
            tr.enter(c, fr, 0);
        }
        if (tr.budgetOut) {
            st.budgetExceeded = true;
            for (uint32_t c : start) tr.markReachable(c);
            r.note = "portal budget of " + std::to_string(settings.maxPortalTests) +
                     " tests exceeded: every cell the portal graph reaches from the camera's is visible";
        }
    } else {
        r.cellVisible.assign(nCells, 1);
        char buf[160];
        std::snprintf(buf, sizeof buf, "camera outside every cell: the eye (%g, %g, %g) is in none of the %u cells; nothing culled",
                      cam.eye.x, cam.eye.y, cam.eye.z, nCells);
        r.note = buf;
    }
    for (uint8_t v : r.cellVisible) st.cellsVisible += v;

    // Objects: culled when they have cells and none was reached.
    auto visit = [&](uint32_t o) {
        const SceneObject &obj = scene.objects[o];
        ++st.objectsIn;
        st.trianglesIn += obj.triEnd - obj.triBegin;
        const bool assigned = o + 1 < scene.objectCellsBegin.size();
        const uint32_t b = assigned ? scene.objectCellsBegin[o] : 0, e = assigned ? scene.objectCellsBegin[o + 1] : 0;
        bool keep = b == e;
        if (b == e) ++st.objectsNoCell;
        for (uint32_t k = b; k < e && !keep; ++k) keep = r.cellVisible[scene.objectCells[k]];
        if (keep) {
            r.visible.push_back(o);
        } else {
            r.culled.push_back(o);
            ++st.objectsCulled;
            st.trianglesCulled += obj.triEnd - obj.triBegin;
        }
    };
    if (candidates) {
        for (uint32_t o : *candidates) visit(o);
    } else {
        for (uint32_t o = 0; o < scene.objects.size(); ++o) visit(o);
    }
    return r;
}

}  // namespace va
