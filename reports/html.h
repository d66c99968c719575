// report.html: the whole report as one self-contained page (docs/html-report.md).
//
// The page is generated from report.json alone (plus the image files next to it), so analyze,
// merge and check all write the same page for the same report. It needs nothing but a browser:
// CSS and JavaScript are inline (reports/assets/, embedded by CMakeLists.txt), charts are inline SVG, images are
// relative links to the PNGs in the same folder; no fonts, no CDN, no network.
//
// Every section is optional: a view without `audit`, `depth`, `raycast`, `effects`, `ordering`,
// `detail`, ... gets its other sections and "not analysed" where a question needs the missing one.
// Every string from the report is HTML-escaped. Same report and folder -> same bytes.
#pragma once

#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace va {

// The page for `report` (a visaudit-report/1 document). `dir` is the folder the page will live
// in: images are referenced only when their file exists there (and their pixel size is read from
// the PNG header so that highlight boxes can be placed without script). An empty `dir` references
// no image files.
std::string reportHtml(const nlohmann::ordered_json &report, const std::string &dir);

// Writes dir/report.html atomically (writeFileAtomic). Call it after report.json and every image
// are in `dir` (the OutputDir staging folder), before commit(). False + *err naming the path on
// failure; a report of an unexpected shape never fails (missing parts are left out of the page).
bool writeReportHtml(const nlohmann::ordered_json &report, const std::string &dir, std::string *err);

// Text made safe for HTML content and quoted attributes (report.html's own escaping: markup
// characters as entities, control characters and invalid UTF-8 as U+FFFD); other pages use it.
std::string htmlEscape(std::string_view text);

}  // namespace va
