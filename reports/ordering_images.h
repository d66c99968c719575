// Images of the ordering analysis (analysis/audits/ordering.h; docs/ordering.md), next to each view's other
// images:
//
//   BASE.painter_errors.png  the reference visibility shaded by depth (gray, dimmed), every pixel the
//                            painter's algorithm gets wrong in red, every depth tie in yellow and
//                            every edge pixel (coverage uncertainty, ordering.h) in blue;
//                            a legend strip below with the counts.
//   BASE.overdraw_order.png  a bar chart: overdraw (depth-test passes / covered pixels, best 1) of the
//                            view under each draw order, the value written at the end of each bar.
//   BASE.abuffer.png         the A-buffer's antialiased composite (only where the A-buffer ran).
// Files go through writePngRgb8 (a temporary name, then renamed).
#pragma once

#include <string>
#include <vector>

#include "analysis/audits/ordering.h"
#include "reports/palette_image.h"
#include "reports/report.h"

namespace va {

struct OrderingImageNames {
    std::string painterErrorsPng;  // BASE.painter_errors.png
    std::string overdrawOrderPng;  // BASE.overdraw_order.png
    std::string abufferPng;        // BASE.abuffer.png
};
OrderingImageNames orderingImageNames(const std::string &baseName);

constexpr Rgb8 kOrderWrongColor{255, 32, 32};
constexpr Rgb8 kOrderTieColor{255, 220, 0};
constexpr Rgb8 kOrderEdgeColor{64, 128, 255};

// The painter-errors picture (width x (height + legend)).
// grays (both): the reference depth's depthGrays when the caller has them (else computed here).
PaletteImage renderPainterErrors(const ReferenceVisibility &ref, const PainterResult &painter,
                                 const std::vector<uint8_t> *grays = nullptr);
bool writePainterErrorsImage(const ReferenceVisibility &ref, const PainterResult &painter, const std::string &path,
                             std::string *err, const std::vector<uint8_t> *grays = nullptr);

// The bar chart as RGB8, kOverdrawChartWidth wide; *canvasH receives its height.
constexpr int kOverdrawChartWidth = 480;
std::vector<uint8_t> renderOverdrawByOrder(const std::vector<OrderOverdraw> &orders, int *canvasH);
bool writeOverdrawByOrderChart(const std::vector<OrderOverdraw> &orders, const std::string &path, std::string *err);

bool writeABufferImage(const ABufferResult &abuffer, const std::string &path, std::string *err);

}  // namespace va
