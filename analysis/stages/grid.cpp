// The grid stage: build (object registration per cell, CSR) and per-view culling.
#include "analysis/stages/grid.h"
#include "analysis/stage.h"

#include <algorithm>
#include <cmath>

#include "analysis/stages/frustum.h"

namespace va {

namespace {

// Cell edge from the settings, or automatic (GridSettings::cellSize's rule).
double chooseCellSize(const Scene &scene, const GridSettings &settings, Vec3 e) {
    if (settings.cellSize > 0) return settings.cellSize;
    const double target = std::max(1.0, double(scene.objects.size()) / GridSettings::kObjectsPerCell);
    double measure = 1;
    int axes = 0;
    for (int a = 0; a < 3; ++a)
        if (e[a] > 0) {
            measure *= e[a];
            ++axes;
        }
    if (axes == 0) return 1;  // every object is one point: one cell
    return std::pow(measure / target, 1.0 / axes);
}

}  // namespace

Aabb Grid::cellBox(int x, int y, int z) const {
    // The same expression as the registration's bounds checks, so the union of an object's cells
    // covers its box in the computed arithmetic too.
    Aabb b;
    b.lo = {bounds.lo.x + x * cellSize, bounds.lo.y + y * cellSize, bounds.lo.z + z * cellSize};
    b.hi = {bounds.lo.x + (x + 1) * cellSize, bounds.lo.y + (y + 1) * cellSize, bounds.lo.z + (z + 1) * cellSize};
    return b;
}

Grid buildGrid(const Scene &scene, const GridSettings &settings) {
    Grid g;
    g.objectCellCount.assign(scene.objects.size(), 0);
    if (scene.objects.empty() || scene.bounds.empty()) {
        g.cellBegin.assign(1, 0);
        return g;
    }
    g.bounds = scene.bounds;
    const Vec3 lo = g.bounds.lo, e = g.bounds.extent();
    double s = chooseCellSize(scene, settings, e);
    // Cells per axis: enough to reach the bounds' far side (checked in the computed arithmetic),
    // and at most kMaxCells in all (the edge grows by 1/4 until it fits).
    for (;;) {
        uint64_t total = 1;
        for (int a = 0; a < 3; ++a) {
            double n = std::max(1.0, std::ceil(e[a] / s));
            if (n > 1e9) n = 1e9;
            while (lo[a] + n * s < g.bounds.hi[a]) n += 1;
            g.dims[a] = int(n);
            total = uint64_t(std::min<double>(double(total) * n, 1e18));
        }
        if (total <= GridSettings::kMaxCells) break;
        s *= 1.25;
    }
    g.cellSize = s;

    // Each object's cell range per axis: floor of its box's position, then widened until the cells'
    // boxes (Grid::cellBox's expression) cover the object's box exactly as computed.
    auto range = [&](const Aabb &b, int a, int *i0, int *i1) {
        int x0 = int(std::clamp(std::floor((b.lo[a] - lo[a]) / s), 0.0, double(g.dims[a] - 1)));
        int x1 = int(std::clamp(std::floor((b.hi[a] - lo[a]) / s), 0.0, double(g.dims[a] - 1)));
        while (x0 > 0 && lo[a] + x0 * s > b.lo[a]) --x0;
        while (x1 < g.dims[a] - 1 && lo[a] + (x1 + 1) * s < b.hi[a]) ++x1;
        *i0 = x0;
        *i1 = std::max(x0, x1);
    };
    const uint64_t nCells = g.cellCount();
    std::vector<uint32_t> counts(nCells + 1, 0);
    std::vector<int> ranges(scene.objects.size() * 6);
    for (size_t o = 0; o < scene.objects.size(); ++o) {
        int *r = &ranges[o * 6];
        for (int a = 0; a < 3; ++a) range(scene.objects[o].bounds, a, &r[2 * a], &r[2 * a + 1]);
        for (int z = r[4]; z <= r[5]; ++z)
            for (int y = r[2]; y <= r[3]; ++y)
                for (int x = r[0]; x <= r[1]; ++x) ++counts[g.cellIndex(x, y, z)];
        g.objectCellCount[o] = uint32_t((r[1] - r[0] + 1) * (r[3] - r[2] + 1) * (r[5] - r[4] + 1));
    }
    g.cellBegin.assign(nCells + 1, 0);
    for (uint64_t c = 0; c < nCells; ++c) g.cellBegin[c + 1] = g.cellBegin[c] + counts[c];
    g.cellObjects.resize(g.cellBegin[nCells]);
    std::vector<uint32_t> fill(g.cellBegin.begin(), g.cellBegin.end() - 1);
    for (size_t o = 0; o < scene.objects.size(); ++o) {
        const int *r = &ranges[o * 6];
        for (int z = r[4]; z <= r[5]; ++z)
            for (int y = r[2]; y <= r[3]; ++y)
                for (int x = r[0]; x <= r[1]; ++x) g.cellObjects[fill[g.cellIndex(x, y, z)]++] = uint32_t(o);
    }
    return g;
}

const char *gridSkipReason(const Scene &scene) {
    if (!scene.cells.empty()) return "scene has cells and portals (the cells stage is its coarse stage)";
    if (scene.bsp && scene.bsp->hasPvs()) return "scene has a PVS (the cells stage is its coarse stage)";
    if (scene.objects.empty()) return "scene has no objects";
    return nullptr;
}

GridResult cullGrid(const Scene &scene, const Grid &grid, const Camera &cam, const std::vector<uint32_t> *candidates) {
    GridResult r;
    GridStats &st = r.stats;
    for (int a = 0; a < 3; ++a) st.dims[a] = grid.dims[a];
    st.cellSize = grid.cellSize;
    st.cellsTotal = grid.cellCount();
    st.registrations = grid.cellObjects.size();

    std::vector<uint8_t> isCandidate(scene.objects.size(), candidates ? 0 : 1);
    if (candidates)
        for (uint32_t o : *candidates) isCandidate[o] = 1;
    std::vector<uint8_t> keep(scene.objects.size(), 0);

    if (st.cellsTotal > 0) {
        const FrustumPlanes fp = worldFrustumPlanes(cam);
        // The frustum's bounding box: its 8 corners (near and far rectangles; a rectangle at view
        // depth d has half sizes d/sx, d/sy, or 1/sx, 1/sy orthographically), widened by a rounding
        // bound, then by one grid cell per side when turned into a cell range (so a rounding in the
        // division never skips a cell the frustum touches). Cells outside it cost nothing.
        Aabb fb;
        double mag = maxAbs(cam.eye);
        for (int i = 0; i < 2; ++i) {
            const double d = i == 0 ? cam.nearZ : cam.farZ;
            const double hx = cam.orthographic ? 1 / cam.sx : d / cam.sx, hy = cam.orthographic ? 1 / cam.sy : d / cam.sy;
            mag = std::max(mag, maxAbs(cam.eye) + d + hx + hy);
            for (int sx = -1; sx <= 1; sx += 2)
                for (int sy = -1; sy <= 1; sy += 2) fb.extend(cam.eye + cam.forward * d + cam.right * (sx * hx) + cam.up * (sy * hy));
        }
        const double pad = gamma(32) * mag;
        int lo[3], hi[3];
        bool none = false;
        for (int a = 0; a < 3; ++a) {
            const double l = std::floor((fb.lo[a] - pad - grid.bounds.lo[a]) / grid.cellSize) - 1;
            const double h = std::floor((fb.hi[a] + pad - grid.bounds.lo[a]) / grid.cellSize) + 1;
            lo[a] = int(std::max(0.0, l));
            hi[a] = int(std::min(double(grid.dims[a] - 1), h));
            if (l > double(grid.dims[a] - 1) || h < 0) none = true;
        }
        uint64_t inRange = 0;
        if (!none) {
            inRange = uint64_t(hi[0] - lo[0] + 1) * uint64_t(hi[1] - lo[1] + 1) * uint64_t(hi[2] - lo[2] + 1);
            for (int z = lo[2]; z <= hi[2]; ++z)
                for (int y = lo[1]; y <= hi[1]; ++y)
                    for (int x = lo[0]; x <= hi[0]; ++x) {
                        const uint64_t c = grid.cellIndex(x, y, z);
                        if (grid.cellBegin[c] == grid.cellBegin[c + 1]) {
                            ++st.cellsEmpty;
                            continue;
                        }
                        ++st.cellsTested;
                        // Box against each plane: the corner farthest along the plane's normal
                        // (the p-vertex); outside when even it is outside by more than the rounding
                        // bound of the evaluation (conservative: in doubt, visible).
                        const Aabb b = grid.cellBox(x, y, z);
                        bool outside = false;
                        for (int p = 0; p < 6 && !outside; ++p) {
                            ++st.planeTests;
                            const Vec3 &n = fp.n[p];
                            const Vec3 v{n.x >= 0 ? b.hi.x : b.lo.x, n.y >= 0 ? b.hi.y : b.lo.y, n.z >= 0 ? b.hi.z : b.lo.z};
                            const double dist = dot(n, v) + fp.k[p];
                            const double err = gamma(16) * (std::fabs(n.x * v.x) + std::fabs(n.y * v.y) + std::fabs(n.z * v.z) + std::fabs(fp.k[p]));
                            outside = dist < -err;
                        }
                        if (outside) continue;
                        ++st.cellsVisible;
                        for (uint32_t k = grid.cellBegin[c]; k < grid.cellBegin[c + 1]; ++k) keep[grid.cellObjects[k]] = 1;
                    }
        }
        st.cellsSkipped = st.cellsTotal - inRange;
    }

    for (uint32_t o = 0; o < scene.objects.size(); ++o) {
        if (!isCandidate[o]) continue;
        const SceneObject &obj = scene.objects[o];
        ++st.objectsIn;
        st.trianglesIn += obj.triEnd - obj.triBegin;
        // Objects in no grid cell (none: every object has bounds) would be kept.
        if (keep[o] || o >= grid.objectCellCount.size() || grid.objectCellCount[o] == 0) {
            r.visible.push_back(o);
        } else {
            r.culled.push_back(o);
            ++st.objectsCulled;
            st.trianglesCulled += obj.triEnd - obj.triBegin;
        }
    }
    return r;
}


// The pipeline's row (analysis/stage.h): the coarse stage where the scene has no cells.
namespace {
std::string gridSkip(const ViewContext &c) {
    if (const char *why = gridSkipReason(c.scene)) return why;
    return c.s.grid ? "" : "turned off by --no-grid";
}
ObjectCull gridRun(ViewContext &c, const std::vector<uint32_t> &objects) {
    GridResult g = cullGrid(c.scene, c.ps.grid, c.cam, &objects);
    c.r.grid = g.stats;
    return {std::move(g.visible), std::move(g.culled), {}, 0};
}
}  // namespace
extern const ObjectStage kGridStage = {"grid", gridSkip, gridRun};

}  // namespace va
