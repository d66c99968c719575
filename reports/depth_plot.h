// Log-log plot of depth resolution against view depth, one curve per format (depth-resolution.png
// of `visaudit depth-audit`).
#pragma once

#include <string>

#include "analysis/audits/depth_audit.h"
#include "reports/report.h"

namespace va {

// Where things are in the plot (pixels; x right, y down, pixel (0,0) top-left). The plot area is
// [left, right] x [top, bottom]; x is log10 of depth over [log10 near, log10 far], y is log10 of
// resolution over whole decades [yDecadeMin, yDecadeMax] covering every plotted value.
struct DepthPlotLayout {
    int width = 1200, height = 800;
    int left = 0, right = 0, top = 0, bottom = 0;
    double xLogMin = 0, xLogMax = 1;
    int yDecadeMin = 0, yDecadeMax = 1;
    // Pixel column of depth d and pixel row of resolution r (r > 0), rounded to nearest.
    int xOf(double d) const;
    int yOf(double r) const;
};
// The layout writeDepthResolutionPlot uses for this result (valid when the result has formats and
// at least one positive finite curve value).
DepthPlotLayout depthPlotLayout(const DepthAuditResult &result);

// A format's curve color: fixed per format (the same in every plot), 18 distinct colors; every
// log24:C=X with C != 1 shares one more (dark olive).
Rgb8 depthPlotColor(DepthFormat format);
Rgb8 depthPlotColor(const DepthFormatSpec &format);
constexpr Rgb8 kDepthPlotBackground{255, 255, 255};

// Writes a width x height RGB PNG at `path` (temporary name in the same folder, then renamed):
// resolution (m) against view depth d (m) on log-log axes, decade grid lines with labelled ticks,
// one colored curve per format through its dense curve (DepthFormatAudit::curveResolution at
// DepthAuditResult::curveDepths; absent samples break the curve), dashed grey lines at each fight
// gap and at twice it with, per format, a filled 9x9 square at (onset, gap) and a hollow one at
// (likely, 2 x gap) in its color, a legend of the format names in their colors, axis titles, in
// the bitmap font of reports/font.h. Integer formats draw as steps.
// Returns false with *err (the path and the reason) when the result has an error or nothing to
// plot, or the file cannot be written.
bool writeDepthResolutionPlot(const DepthAuditResult &result, const std::string &path, std::string *err);

}  // namespace va
