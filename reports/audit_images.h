// Images of the audits (analysis/audits/audit.h), next to each view's other images (reports/report.h):
//
//   BASE.culling.png       the reference visibility, each pixel colored by the fate of its visible
//                          triangle: drawn (gray, shaded by depth like depth.png), falsely culled by
//                          stage k (one saturated color per stage), unaccounted (magenta),
//                          background (black); a legend strip below names the colors.
//   BASE.raycast_diff.png  the z-buffer's depth image dimmed to a quarter, with every pixel where the
//                          ray caster sees another triangle colored by its class: edge (blue),
//                          tie (yellow), genuine (red).
//   BASE.raycast.ids.exr   one UINT32 channel "id": 1 + the ray caster's visible triangle, 0 = background
//                          (the same layout as BASE.ids.exr).
// Every file goes to a temporary name in the folder and is renamed (writePngRgb8 / writeExrUint32).
#pragma once

#include <string>
#include <vector>

#include "analysis/audits/audit.h"
#include "reports/report.h"

namespace va {

struct AuditImageNames {
    std::string cullingPng;      // BASE.culling.png
    std::string raycastDiffPng;  // BASE.raycast_diff.png
    std::string raycastIdsExr;   // BASE.raycast.ids.exr
};
AuditImageNames auditImageNames(const std::string &baseName);

// Stage colors of the culling image, in stage order (cycled past the last).
Rgb8 cullStageColor(size_t stage);
constexpr Rgb8 kCullDrawnTint{255, 255, 255};  // multiplied by the depth gray
constexpr Rgb8 kCullUnaccounted{255, 0, 255};
constexpr Rgb8 kCullSnapped{150, 150, 200};  // culled by facing, shown only as a snapped sliver
constexpr Rgb8 kCullBeyondFarPlane{0, 120, 120};  // culled beyond the map's design far plane: by design
Rgb8 disagreementColor(Disagreement d);  // none: black (not used: the dimmed image shows)

// BASE.culling.png from a view's reference and culling audit.
// grays: the reference depth's depthGrays when the caller has them (else computed here).
bool writeCullingImage(const ReferenceVisibility &ref, const CullAudit &audit, const std::string &path, std::string *err,
                       const std::vector<uint8_t> *grays = nullptr);
// BASE.raycast_diff.png from the z-buffer's depths (the dimmed background) and a cross-check.
// grays: the z-buffer depth's depthGrays when the caller has them (else computed here).
bool writeRaycastDiffImage(const ZBuffer &zb, const CrossCheck &check, const std::string &path, std::string *err,
                           const std::vector<uint8_t> *grays = nullptr);
// BASE.raycast.ids.exr (chunks: as writeExrUint32's).
bool writeRaycastIds(int width, int height, const std::vector<uint32_t> &ids, const std::string &path, std::string *err,
                     ExrChunks *chunks = nullptr);

}  // namespace va
