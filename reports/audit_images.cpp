// Images of the audits (audit_images.h).
#include "reports/audit_images.h"

#include <algorithm>
#include <cmath>

#include "reports/font.h"
#include "reports/legend.h"

namespace va {

AuditImageNames auditImageNames(const std::string &baseName) {
    return {baseName + ".culling.png", baseName + ".raycast_diff.png", baseName + ".raycast.ids.exr"};
}

Rgb8 cullStageColor(size_t stage) {
    // Saturated, mutually distinct, none gray or magenta (those mean drawn / unaccounted).
    static constexpr Rgb8 kColors[] = {{255, 48, 32}, {255, 200, 0}, {0, 200, 255}, {64, 220, 64}, {255, 128, 0}, {64, 96, 255}};
    return kColors[stage % std::size(kColors)];
}

Rgb8 disagreementColor(Disagreement d) {
    switch (d) {
    case Disagreement::edge: return {64, 128, 255};
    case Disagreement::tie: return {255, 220, 0};
    case Disagreement::genuine: return {255, 0, 0};
    case Disagreement::none: break;
    }
    return {0, 0, 0};
}

bool writeCullingImage(const ReferenceVisibility &ref, const CullAudit &audit, const std::string &path, std::string *err,
                       const std::vector<uint8_t> *grays) {
    const int W = ref.width, H = ref.height;
    const size_t n = size_t(std::max(W, 0)) * size_t(std::max(H, 0));
    if (W <= 0 || H <= 0 || ref.id.size() != n || audit.fate.size() != n) {
        if (err) *err = "cannot write image '" + path + "': the reference and the culling audit have no matching " +
                        std::to_string(W) + "x" + std::to_string(H) + " buffers";
        return false;
    }
    std::vector<LegendEntry> legend = {{{200, 200, 200}, "drawn"}};
    for (size_t k = 0; k < audit.stages.size(); ++k)
        legend.push_back({cullStageColor(k), "false cull: " + audit.stages[k].stage + " (" +
                                                 std::to_string(audit.stages[k].falseCullPixels) + " px)"});
    uint64_t snapped = 0;
    for (const StageCullAudit &s : audit.stages) snapped += s.snappedPixels;
    if (snapped) legend.push_back({kCullSnapped, "snapped sliver (" + std::to_string(snapped) + " px)"});
    if (audit.beyondFarPlanePixels)
        legend.push_back({kCullBeyondFarPlane, "beyond the map's far plane, by design (" +
                                                   std::to_string(audit.beyondFarPlanePixels) + " px)"});
    if (audit.unaccountedPixels) legend.push_back({kCullUnaccounted, "unaccounted"});
    PaletteImage img = legendCanvas(W, H, legend);
    // Each pixel's color from its fate, and a drawn pixel's from its depth gray, through tables.
    uint16_t fateCode[256], drawnCode[256];  // by fate; by depth gray
    for (int f = 0; f < 256; ++f) {
        Rgb8 c{0, 0, 0};
        if (f == kFateUnaccounted) c = kCullUnaccounted;
        else if (f == kFateSnapped) c = kCullSnapped;
        else if (f == kFateBeyondFarPlane) c = kCullBeyondFarPlane;
        else if (f >= kFateCulledFirst) c = cullStageColor(size_t(f - kFateCulledFirst));
        fateCode[f] = img.codeOf(c);
        drawnCode[f] = img.codeOf({uint8_t(f * kCullDrawnTint.r / 255), uint8_t(f * kCullDrawnTint.g / 255),
                                   uint8_t(f * kCullDrawnTint.b / 255)});  // f as the depth gray
    }
    const PixelGrays gray(ref.depth, grays);
    for (size_t i = 0; i < n; ++i) {  // the canvas is W wide: pixel i of the image is code i
        const uint8_t f = audit.fate[i];
        img.code[i] = f == kFateDrawn ? drawnCode[gray[i]] : fateCode[f];
    }
    return writePngPalette(path, img, err);
}

bool writeRaycastDiffImage(const ZBuffer &zb, const CrossCheck &check, const std::string &path, std::string *err,
                           const std::vector<uint8_t> *grays) {
    const int W = zb.width, H = zb.height;
    const size_t n = size_t(std::max(W, 0)) * size_t(std::max(H, 0));
    if (W <= 0 || H <= 0 || zb.depth.size() != n || check.cls.size() != n) {
        if (err) *err = "cannot write image '" + path + "': the z-buffer and the cross-check have no matching " +
                        std::to_string(W) + "x" + std::to_string(H) + " buffers";
        return false;
    }
    const std::vector<LegendEntry> legend = {
        {disagreementColor(Disagreement::edge), "edge " + std::to_string(check.edge)},
        {disagreementColor(Disagreement::tie), "tie " + std::to_string(check.tie)},
        {disagreementColor(Disagreement::genuine), "genuine " + std::to_string(check.genuine)}};
    PaletteImage img = legendCanvas(W, H, legend);
    // Agreeing pixels dimmed gray (the classes stand out), the others their class's color.
    uint16_t dimmed[256], classCode[256];
    for (int k = 0; k < 256; ++k) {
        const uint8_t g = uint8_t(k / 4);
        dimmed[k] = img.codeOf({g, g, g});
        classCode[k] = img.codeOf(disagreementColor(Disagreement(k)));
    }
    const PixelGrays gray(zb.depth, grays);
    for (size_t i = 0; i < n; ++i) {  // the canvas is W wide: pixel i of the image is code i
        const uint8_t d = check.cls[i];
        img.code[i] = Disagreement(d) == Disagreement::none ? dimmed[gray[i]] : classCode[d];
    }
    return writePngPalette(path, img, err);
}

bool writeRaycastIds(int width, int height, const std::vector<uint32_t> &ids, const std::string &path, std::string *err,
                     ExrChunks *chunks) {
    if (width <= 0 || height <= 0 || ids.size() != size_t(width) * size_t(height)) {
        if (err) *err = "cannot write image '" + path + "': no " + std::to_string(width) + "x" + std::to_string(height) +
                        " ray-cast ids";
        return false;
    }
    return writeExrUint32(path, width, height, ids.data(), "id", err, chunks);
}

}  // namespace va
