// The evidence of a Quake 3 map's PVS false culls (docs/quake3.md, "Reading the evidence"): for one
// view, the camera's leaf and cluster, and per falsely culled object its falsely culled faces, every
// leaf listing each face with the leaf's cluster and the PVS bit "camera cluster sees that cluster",
// the brush model's box leafs, and the distance of what is seen. Everything in it can be checked
// against the map's bytes (header, nodes, planes, leafs, leaffaces, models, visdata): the test
// Audit.RealMapEvidenceAgreesWithTheFile does so with a reader of its own.
//
// Bounded, whatever the map: at most kEvidenceObjects objects per view (the stage's worst offenders,
// in the same order), kEvidenceFaces faces per object, kEvidenceLeafs leafs per face and per model
// box, kEvidenceClusters clusters per object; every list says how many it left out.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "analysis/audits/audit.h"
#include "analysis/stages/cells.h"
#include "analysis/scene.h"
#include "render/camera.h"

namespace va {

constexpr size_t kEvidenceObjects = kWorstOffenders;  // 20
constexpr size_t kEvidenceFaces = 4;
constexpr size_t kEvidenceLeafs = 8;
constexpr size_t kEvidenceClusters = 16;

// A leaf and what the PVS says about it from the camera's cluster.
struct PvsLeafBit {
    int32_t leaf = -1;
    int32_t cluster = -1;     // the leaf's cluster (-1: none)
    bool inTree = false;      // the world's tree reaches the leaf (a model's own leaf: false)
    int pvsBit = -1;          // bit `cluster` of the camera cluster's PVS row: 1 visible, 0 not; -1: no cluster
};

struct PvsFaceEvidence {
    uint32_t face = 0;        // index in the faces lump
    uint64_t pixels = 0;      // reference pixels where a falsely culled triangle of the face is visible
    double nearest = 0;       // the nearest of those pixels' points from the eye (world units)
    int x = 0, y = 0;         // that pixel
    std::vector<PvsLeafBit> leafs;  // every leaf listing the face (leaffaces), ascending, at most kEvidenceLeafs
    uint32_t leafsOmitted = 0;
};

struct PvsClusterBit {
    int32_t cluster = 0;
    int pvsBit = 0;           // the camera cluster's PVS bit for it: 0 for every cluster of a culled object
};

struct PvsObjectEvidence {
    uint32_t object = 0;      // culling object
    std::string name;         // its name ("leafN", "modelK", "#k" for chunk k)
    uint32_t model = 0;       // 0: world faces; K: brush model K
    int32_t entity = -1;      // the entity drawing model K (-1: world)
    std::string classname;    // its classname ("" for the world)
    uint64_t triangles = 0;   // its falsely culled triangles
    uint64_t pixels = 0;      // reference pixels they cover
    double nearest = 0;       // the nearest of those pixels' points from the eye
    std::vector<PvsClusterBit> clusters;  // its cluster set (what the cells stage tested), at most kEvidenceClusters
    uint32_t clustersOmitted = 0;
    std::vector<PvsLeafBit> boxLeafs;     // brush model: the leafs its box reaches (they give its clusters)
    uint32_t boxLeafsOmitted = 0;
    std::vector<PvsFaceEvidence> faces;   // most pixels first (ties: lower face), at most kEvidenceFaces
    uint32_t facesOmitted = 0;
};

struct PvsEvidence {
    bool ran = false;         // the view's cells stage was a map's PVS and the audit ran
    int32_t cameraLeaf = -1, cameraCluster = -1;
    double designFarPlane = 0;     // the map's far plane (0: none); every distance here is within it
    uint64_t falseCullObjects = 0; // objects the PVS culled falsely (all of them, listed or not)
    uint64_t falseCullPixels = 0;  // their pixels
    std::vector<PvsObjectEvidence> objects;  // most pixels first (ties: more triangles, lower index)
    uint64_t objectsOmitted = 0;
};

// `cellsStage`: the index of the cells stage in audit.stages (its fate is kFateCulledFirst + it).
// Needs the reference's per-pixel buffers (before they are released) and a map with a PVS.
PvsEvidence pvsEvidence(const Scene &scene, const Camera &cam, const CellsStats &cells, const ReferenceVisibility &ref,
                        const CullAudit &audit, size_t cellsStage);

}  // namespace va
