// The contract of an object-culling stage (docs/architecture.md, "The stage contract"). A stage's
// culling function works on plain inputs (the scene, a camera, the objects still in); next to it, in
// the same file, a `const ObjectStage` row says when the stage runs and how its result enters the
// view's result. The pipeline's table (analysis/pipeline.cpp, kObjectStages) lists the rows in the
// fixed coarse-to-fine order, and runObjectStage does what every stage needs: the skip record,
// timing, triangles in/culled/out and the list of culled objects the culling audit judges. A row is
// defined `extern const ObjectStage kNameStage = {...}` (external linkage: the table names it).
#pragma once

#include <atomic>
#include <optional>
#include <string>
#include <vector>

#include "analysis/pipeline.h"
#include "analysis/stages/cells.h"
#include "analysis/stages/portals.h"

namespace va {

// What one view's stages and audits share while they run.
struct ViewContext {
    const PreparedScene &ps;
    const Scene &scene;
    const ViewSpec &view;
    const Camera &cam;
    const PipelineSettings &s;
    ViewResult &r;
    std::vector<StageCulls> culls;  // what each culling stage removed, for the audit
    bool stopped() const { return s.cancel && s.cancel->load(std::memory_order_relaxed) != 0; }
};

// An object stage's answer for one view.
struct ObjectCull {
    std::vector<uint32_t> kept;                   // ascending
    std::optional<std::vector<uint32_t>> culled;  // the objects it removed, when the stage lists them
                                                  //   (else: the difference of its input and `kept`)
    std::optional<double> ms;                     // its own time where that excludes set-up (occlusion)
    double designFarPlane = 0;                    // StageCulls::designFarPlane (a map's PVS)
};

struct ObjectStage {
    const char *name;                          // the funnel row's name in report.json
    std::string (*skip)(const ViewContext &);  // why it does not run here; empty: it runs
    // Given the objects still in (ascending): stores its statistics in the view's result (c.r) and
    // returns what it keeps.
    ObjectCull (*run)(ViewContext &c, const std::vector<uint32_t> &objects);
};

// Whether the scene has portals (from its file) or a map's PVS: the cells stage's two kinds.
inline bool hasPortals(const Scene &scene) { return !portalsSkipReason(scene); }
inline bool hasPvs(const Scene &scene) { return !cellsSkipReason(scene); }

}  // namespace va
