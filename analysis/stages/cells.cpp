// The PVS cells stage: leaf by BSP walk, cluster, PVS row, and per-object cluster sets.
#include "analysis/stages/cells.h"
#include "analysis/stage.h"

namespace va {

const char *cellsSkipReason(const Scene &scene) {
    if (!scene.bsp) return "scene has no cells, portals or PVS";
    if (!scene.bsp->hasPvs()) return "map has no PVS (its visdata lump is empty: compiled without vis)";
    return nullptr;
}

CellsResult cullCells(const Scene &scene, const Camera &cam) {
    CellsResult r;
    CellsStats &s = r.stats;
    const BspLevel &lv = *scene.bsp;
    s.clustersTotal = uint64_t(lv.clusterCount);
    s.objectsIn = scene.objects.size();
    s.trianglesIn = scene.objectTriangles.size();

    // The camera's leaf and cluster. The eye decides (not the near plane): Quake 3 does the same.
    s.cameraLeaf = lv.leafAt(cam.eye);
    s.cameraCluster = s.cameraLeaf >= 0 ? lv.leafs[size_t(s.cameraLeaf)].cluster : -1;
    r.visible.reserve(scene.objects.size());
    if (s.cameraCluster < 0 || s.cameraCluster >= lv.clusterCount) {
        s.cameraInVoid = true;
        s.clustersVisible = s.clustersTotal;
        for (uint32_t o = 0; o < scene.objects.size(); ++o) r.visible.push_back(o);
        for (size_t src = 0; src < scene.sources.size() && src < lv.sourceCluster.size(); ++src)
            if (lv.sourceClustersBegin[src] == lv.sourceClustersBegin[src + 1]) s.objectsNoCluster += scene.sources[src].chunkCount;
        r.note = "camera in the void: leaf " + std::to_string(s.cameraLeaf) +
                 " is outside every cluster (outside the map or inside a wall); nothing culled";
        return r;
    }

    // Visible clusters: the camera cluster's PVS row.
    const int32_t from = s.cameraCluster;
    std::vector<uint8_t> seen(size_t(lv.clusterCount), 0);
    for (int32_t c = 0; c < lv.clusterCount; ++c) {
        seen[size_t(c)] = lv.clusterVisible(from, c);
        s.clustersVisible += seen[size_t(c)];
    }

    // Per source object: kept when it has no cluster or any of its clusters is visible. Chunks of a
    // source share its verdict.
    std::vector<uint8_t> keepSource(scene.sources.size(), 1);
    std::vector<uint8_t> noCluster(scene.sources.size(), 0);
    for (size_t src = 0; src < scene.sources.size() && src < lv.sourceCluster.size(); ++src) {
        const uint32_t b = lv.sourceClustersBegin[src], e = lv.sourceClustersBegin[src + 1];
        if (b == e) {
            noCluster[src] = 1;
            continue;
        }
        bool any = false;
        for (uint32_t k = b; k < e && !any; ++k) any = seen[size_t(lv.sourceClusters[k])];
        keepSource[src] = any;
    }
    for (uint32_t o = 0; o < scene.objects.size(); ++o) {
        const SceneObject &obj = scene.objects[o];
        if (noCluster[obj.source]) ++s.objectsNoCluster;
        if (keepSource[obj.source]) {
            r.visible.push_back(o);
        } else {
            ++s.objectsCulled;
            s.trianglesCulled += obj.triEnd - obj.triBegin;
        }
    }
    return r;
}


// The pipeline's row (analysis/stage.h): the scene's portals (from its file) or a map's PVS.
namespace {
std::string cellsSkip(const ViewContext &c) {
    if (!hasPortals(c.scene) && !hasPvs(c.scene)) return "scene has no cells, portals or PVS";
    return c.s.cells ? "" : "turned off by --no-cells";
}
ObjectCull cellsRun(ViewContext &c, const std::vector<uint32_t> &) {
    ObjectCull out;
    if (hasPortals(c.scene)) {
        PortalResult p = cullPortals(c.scene, c.cam, c.s.portals);
        c.r.cellsArePortals = true;
        c.r.portals = p.stats;
        c.r.cellsNote = p.note;
        out.kept = std::move(p.visible);
    } else {
        CellsResult cr = cullCells(c.scene, c.cam);
        c.r.cells = cr.stats;
        c.r.cellsNote = cr.note;
        out.kept = std::move(cr.visible);
        // A map's PVS leaves out on purpose what lies beyond its designed far plane.
        if (c.scene.bsp) out.designFarPlane = c.scene.bsp->farPlane.distance;
    }
    return out;
}
}  // namespace
extern const ObjectStage kCellsStage = {"cells", cellsSkip, cellsRun};

}  // namespace va
