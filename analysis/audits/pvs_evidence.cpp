// Evidence of the PVS's false culls (pvs_evidence.h). Structure:
//   1. One pass over the pixels the cells stage culled falsely (fate kFateCulledFirst + cellsStage):
//      per object and per (object, face) the pixels, the distinct triangles, the nearest point.
//   2. Objects sorted as the stage's worst offenders; the first kEvidenceObjects kept.
//   3. Per kept object: its cluster set and the PVS bits, its model's box leafs, its faces sorted by
//      pixels, and per face every leaf listing it (BspLevel::faceLeafs) with cluster and bit.
#include "analysis/audits/pvs_evidence.h"

#include <algorithm>
#include <map>
#include <utility>

namespace va {

namespace {

PvsLeafBit leafBit(const BspLevel &lv, int32_t cameraCluster, int32_t leaf) {
    PvsLeafBit b;
    b.leaf = leaf;
    b.cluster = lv.leafs[size_t(leaf)].cluster;
    b.inTree = size_t(leaf) < lv.leafInTree.size() && lv.leafInTree[size_t(leaf)];
    if (b.cluster >= 0 && b.cluster < lv.clusterCount) b.pvsBit = lv.clusterVisible(cameraCluster, b.cluster) ? 1 : 0;
    return b;
}

}  // namespace

PvsEvidence pvsEvidence(const Scene &scene, const Camera &cam, const CellsStats &cells, const ReferenceVisibility &ref,
                        const CullAudit &audit, size_t cellsStage) {
    PvsEvidence e;
    if (!scene.bsp || !scene.bsp->hasPvs() || cellsStage >= audit.stages.size()) return e;
    const BspLevel &lv = *scene.bsp;
    e.ran = true;
    e.cameraLeaf = cells.cameraLeaf;
    e.cameraCluster = cells.cameraCluster;
    e.designFarPlane = audit.stages[cellsStage].designFarPlane;
    if (cells.cameraCluster < 0 || cells.cameraCluster >= lv.clusterCount) return e;  // the void: nothing culled
    const bool faces = lv.triangleFace.size() == scene.triangleCount();

    // 1. The falsely culled pixels, aggregated.
    struct FaceAgg {
        uint64_t pixels = 0;
        double nearest = 0;
        size_t pixel = 0;
    };
    struct ObjAgg {
        uint64_t pixels = 0;
        double nearest = 0;
        std::vector<uint32_t> triangles;
        std::map<uint32_t, FaceAgg> faces;
    };
    std::map<uint32_t, ObjAgg> objs;
    const uint8_t fate = uint8_t(kFateCulledFirst + cellsStage);
    for (size_t i = 0; i < ref.id.size() && i < audit.fate.size(); ++i) {
        if (audit.fate[i] != fate) continue;
        const uint32_t t = ref.id[i] - 1;
        const double d = pixelPointDistance(cam, i, ref.depth[i]);
        ObjAgg &o = objs[scene.triangleObject[t]];
        ++o.pixels;
        if (o.pixels == 1 || d < o.nearest) o.nearest = d;
        o.triangles.push_back(t);
        if (!faces) continue;
        FaceAgg &f = o.faces[lv.triangleFace[t]];
        ++f.pixels;
        if (f.pixels == 1 || d < f.nearest) f.nearest = d, f.pixel = i;
    }

    // 2. Worst first, as the stage's offender list.
    std::vector<std::pair<uint32_t, ObjAgg *>> order;
    for (auto &[o, agg] : objs) {
        std::sort(agg.triangles.begin(), agg.triangles.end());
        agg.triangles.erase(std::unique(agg.triangles.begin(), agg.triangles.end()), agg.triangles.end());
        order.emplace_back(o, &agg);
        e.falseCullPixels += agg.pixels;
    }
    e.falseCullObjects = order.size();
    std::sort(order.begin(), order.end(), [](const auto &a, const auto &b) {
        if (a.second->pixels != b.second->pixels) return a.second->pixels > b.second->pixels;
        if (a.second->triangles.size() != b.second->triangles.size())
            return a.second->triangles.size() > b.second->triangles.size();
        return a.first < b.first;
    });
    if (order.size() > kEvidenceObjects) {
        e.objectsOmitted = order.size() - kEvidenceObjects;
        order.resize(kEvidenceObjects);
    }

    // 3. Per object: clusters, box leafs, faces and their leafs.
    const size_t w = size_t(std::max(cam.width, 1));
    for (const auto &[o, agg] : order) {
        PvsObjectEvidence ob;
        ob.object = o;
        ob.name = scene.objects[o].name;
        ob.triangles = agg->triangles.size();
        ob.pixels = agg->pixels;
        ob.nearest = agg->nearest;
        const uint32_t src = scene.objects[o].source;
        if (src < lv.sourceModel.size()) ob.model = lv.sourceModel[src];
        if (ob.model > 0 && ob.model < lv.models.size()) {
            const BspModel &m = lv.models[ob.model];
            ob.entity = m.entity;
            ob.classname = m.classname;
            for (int32_t l : m.boxLeafs) {
                if (ob.boxLeafs.size() == kEvidenceLeafs) {
                    ++ob.boxLeafsOmitted;
                    continue;
                }
                ob.boxLeafs.push_back(leafBit(lv, cells.cameraCluster, l));
            }
        }
        if (src + 1 < lv.sourceClustersBegin.size())
            for (uint32_t k = lv.sourceClustersBegin[src]; k < lv.sourceClustersBegin[src + 1]; ++k) {
                if (ob.clusters.size() == kEvidenceClusters) {
                    ++ob.clustersOmitted;
                    continue;
                }
                const int32_t c = lv.sourceClusters[k];
                ob.clusters.push_back({c, lv.clusterVisible(cells.cameraCluster, c) ? 1 : 0});
            }
        std::vector<std::pair<uint32_t, const FaceAgg *>> fs;
        for (const auto &[f, fa] : agg->faces) fs.emplace_back(f, &fa);
        std::sort(fs.begin(), fs.end(), [](const auto &a, const auto &b) {
            if (a.second->pixels != b.second->pixels) return a.second->pixels > b.second->pixels;
            return a.first < b.first;
        });
        if (fs.size() > kEvidenceFaces) {
            ob.facesOmitted = uint32_t(fs.size() - kEvidenceFaces);
            fs.resize(kEvidenceFaces);
        }
        for (const auto &[f, fa] : fs) {
            PvsFaceEvidence fe;
            fe.face = f;
            fe.pixels = fa->pixels;
            fe.nearest = fa->nearest;
            fe.x = int(fa->pixel % w);
            fe.y = int(fa->pixel / w);
            for (uint32_t k = lv.faceLeafsBegin[f]; k < lv.faceLeafsBegin[f + 1]; ++k) {
                if (fe.leafs.size() == kEvidenceLeafs) {
                    ++fe.leafsOmitted;
                    continue;
                }
                fe.leafs.push_back(leafBit(lv, cells.cameraCluster, int32_t(lv.faceLeafs[k])));
            }
            ob.faces.push_back(std::move(fe));
        }
        e.objects.push_back(std::move(ob));
    }
    return e;
}

}  // namespace va
