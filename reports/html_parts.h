// report.html's parts (reports/html.h is the interface): what the page's files share. Each file
// draws one kind of thing:
//   html.cpp          the page: head, header and verdict, summary, planner, map, audits' links
//   html_view.cpp     a view's sections: answers, funnel, stage table, images, hotspots, false
//                     culls, PVS evidence, ray-cast cross-check, depth formats, accuracy, the rest
//   html_charts.cpp   inline SVG: the stage funnel, the accuracy scatter, depth resolution curves
//   html_images.cpp   the image files next to the page (kImageKinds) and highlight boxes over them
//   html_markup.cpp   escaping, value formatting and the generic tables any section falls back to
//   html_routes.cpp   the routes' plots and the level maps (only in reports that have them)
// The page presents the report's numbers and its findings (reports/findings.h); it computes
// neither. Everything reads the report through reports/report_read.h, which never throws.
#pragma once

#include <map>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "reports/report_read.h"
#include "reports/text_format.h"

namespace va::html {

using namespace va::rjson;

// ---- Markup (html_markup.cpp) -------------------------------------------------------------------

// Text for HTML content and quoted attribute values: the five markup characters become entities,
// control characters (but tab and newline) and invalid UTF-8 become U+FFFD. A report string can
// therefore never open a tag, close an attribute or break the page's encoding.
std::string esc(std::string_view s);
// Length of the valid UTF-8 sequence at s[i], or 0 when the bytes there are not one.
size_t utf8Length(std::string_view s, size_t i);
// A name made safe for an id or class: [a-z0-9_-] kept (upper case lowered), others -> '_'.
std::string slug(std::string_view s);
// A JSON value as table text: integers as counts, reals with 4 digits, null as an em dash.
std::string fmtValue(const Json *j);
// A percentage for SVG/CSS geometry (fixed decimals: deterministic and short).
std::string fx(double v);
// A report key as a column header: "false_cull_pixels" -> "false cull pixels".
std::string label(std::string_view key);
// An integer as it is written in the report (no separators), or an em dash.
std::string rawInt(const Json *j);
// Column keys of an array of row objects: the scalar members, in first-seen order.
std::vector<std::string> scalarColumns(const std::vector<const Json *> &rows);
// A table of row objects (their scalar members); firstColumn, when given, heads each row.
std::string rowsTable(const std::vector<const Json *> &rows, const std::string &firstHeader = "",
                      const std::vector<std::string> &firstColumn = {});
// Any JSON value as nested tables.
std::string genericJson(const Json *j, int depth = 0);

// ---- Image files next to the page (html_images.cpp) ----------------------------------------------

std::optional<std::pair<int, int>> pngSize(const std::string &path);
bool safeFileName(const std::string &name);
std::string urlOf(const std::string &name);

// The page's folder: an image is referenced only when its file is there.
struct Folder {
    std::string dir;
    bool exists(const std::string &name) const;
    std::optional<std::pair<int, int>> png(const std::string &name) const;
};

struct ViewImage {
    std::string file, slug, title, legend;
    int width = 0, height = 0;  // of the PNG (0 when not a readable PNG)
};
// The base name of a view's images (BASE of BASE.depth.png), or empty.
std::string imageBase(const Json *view);
// The view's images that exist in the folder, in page order (kImageKinds).
std::vector<ViewImage> viewImages(const Json *view, const Folder &folder);
// The image with this slug, or nullptr.
const ViewImage *findImage(const std::vector<ViewImage> &imgs, std::string_view slugName);
// A highlight box over an image, hidden until it is the :target; (x0, y0, x1, y1) inclusive pixels.
std::string highlightBox(const std::string &boxId, const ViewImage &im, double x0, double y0, double x1, double y1,
                         const std::string &title);

// ---- Charts (html_charts.cpp) --------------------------------------------------------------------

// The stage funnel of a view.
std::string funnelSvg(const Json *v, const std::string &id);
struct ScatterPoint {
    std::string label;
    double x = 0, y = 0;
};
// A scatter of time (x, ms) against error (y, pixels), linear axes from 0, labelled points.
std::string scatterSvg(const std::vector<ScatterPoint> &pts, const std::string &id, const std::string &xTitle,
                       const std::string &yTitle);
// Depth resolution against view depth, every format of a report's depth curve set
// (report.depth_curves[k]), `ownFormat` drawn bold; markers are labelled depths (hotspots). The
// grid and the curves are the set's, shared by every view of it: defined (id sharedId) when
// defineShared, else referenced.
std::string resolutionSvg(const Json *curve, const std::string &ownFormat,
                          const std::vector<std::pair<std::string, double>> &markers, const std::string &id,
                          const std::string &sharedId, bool defineShared);

// ---- The page (html.cpp, html_view.cpp) ------------------------------------------------------------

// The report's views worst first (findings.worst_first; positions past the views left out).
std::vector<size_t> worstFirstOf(const Json &report, size_t views);

// Views whose images load with the page; later views' images load when scrolled near.
constexpr size_t kEagerViews = 8;
inline std::string viewId(size_t pos) { return "v" + std::to_string(pos); }

struct HtmlWriter {
    HtmlWriter(const Json &r, Folder f) : report(r), folder(std::move(f)) {}
    const Json &report;
    Folder folder;
    std::vector<const Json *> views = viewsOf(report);
    std::vector<size_t> worstFirst = worstFirstOf(report, views.size());
    std::set<size_t> curvesDrawn;  // depth_curves sets already drawn (later views reference them)
    std::string o;

    void header();
    void summary();
    void planner();
    void quakeMap();
    void depthAuditImage();
    void pvsAuditLink();
    void routes();     // html_routes.cpp: each route's series as a plot, worst frames linked
    void levelMaps();  // html_routes.cpp: the level maps, worst positions linked
    void view(const Json *v, size_t pos);
    void answers(const Json *v);
    // eager: load with the page (the first views); else lazily, when scrolled near (reports of
    // hundreds of views would otherwise load thousands of PNGs at once).
    void images(const Json *v, const std::string &id, const std::vector<ViewImage> &imgs, bool eager);
    void hotspots(const Json *v, const std::string &id, const std::vector<ViewImage> &imgs);
    void falseCulls(const Json *v, const std::string &id, const std::vector<ViewImage> &imgs);
    void pvsEvidence(const Json *v, const std::string &id, const std::vector<ViewImage> &imgs);
    void raycast(const Json *v, const std::string &id, const std::vector<ViewImage> &imgs);
    void depthFormats(const Json *v, const std::string &id);
    void accuracy(const Json *v, const std::string &id,
                  const std::vector<std::pair<std::string, const Json *>> &methods);
    void stageTable(const Json *v);
};

}  // namespace va::html
