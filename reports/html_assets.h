// The inline CSS and JavaScript of report.html (reports/html.cpp). Kept here as raw string
// literals so the page stays one file: no external style sheet, script, font or network request.
//
// Colors are CSS custom properties with a light and a dark set (prefers-color-scheme); the SVG
// charts take their colors from the same properties through classes, so they follow the scheme.
// Highlight boxes over images need no script: each is an element with an id, hidden until it is
// the URL's :target (a table row's link sets the fragment). The script only enlarges images in a
// <dialog> (without script the image link opens the PNG itself).
#pragma once

namespace va::html_assets {

inline constexpr const char *kCss = R"CSS(
:root {
  color-scheme: light dark;
  --bg: #ffffff; --fg: #1b1f24; --muted: #5b6570; --card: #f5f7f9; --border: #d5dbe1;
  --accent: #1f6feb; --in: #b8cdf0; --out: #1f6feb; --skip: #c9ced4; --grid: #e3e7eb;
  --bad: #c62828; --warn: #b26a00; --good: #2e7d32; --mark: #e6007e;
}
@media (prefers-color-scheme: dark) {
  :root {
    --bg: #0f1115; --fg: #e6e8eb; --muted: #9aa4af; --card: #181b21; --border: #2c323a;
    --accent: #58a6ff; --in: #24406b; --out: #58a6ff; --skip: #3a4048; --grid: #262b33;
    --bad: #ff6b6b; --warn: #f0b429; --good: #5fd068; --mark: #ff4fc3;
  }
}
* { box-sizing: border-box; }
html { background: var(--bg); color: var(--fg); }
body {
  margin: 0 auto; max-width: 1280px; padding: 0 20px 60px;
  font: 15px/1.45 system-ui, -apple-system, "Segoe UI", Roboto, "Helvetica Neue", Arial, sans-serif;
}
header { padding: 18px 0 10px; border-bottom: 1px solid var(--border); margin-bottom: 16px; }
h1 { font-size: 1.5em; margin: 0 0 4px; }
h2 { font-size: 1.25em; margin: 0 0 6px; }
h3 { font-size: 1.05em; margin: 22px 0 6px; }
a { color: var(--accent); }
code, .mono { font-family: ui-monospace, "SFMono-Regular", Menlo, Consolas, "Liberation Mono", monospace; font-size: 0.92em; }
.meta, .note, figcaption, .muted { color: var(--muted); }
.verdict { font-size: 1.08em; margin: 6px 0 0; }
.verdict.bad b, .bad { color: var(--bad); }
.verdict.good b, .good { color: var(--good); }
.warn { color: var(--warn); }
nav.toc { margin: 6px 0 0; }
nav.toc a { margin-right: 12px; }
section.view, section.block { border: 1px solid var(--border); border-radius: 8px; background: var(--card);
  padding: 14px 16px; margin: 18px 0; }
section.view:target { outline: 2px solid var(--accent); }
table { border-collapse: collapse; margin: 4px 0 8px; font-variant-numeric: tabular-nums; }
th, td { border-bottom: 1px solid var(--border); padding: 3px 9px; text-align: left; vertical-align: top; }
th { font-weight: 600; white-space: nowrap; }
#summary-table th { white-space: normal; vertical-align: bottom; }
td.n, th.n { text-align: right; white-space: nowrap; }
tr.mine td { font-weight: 600; }
tr.skipped td { color: var(--muted); }
.scroll { overflow-x: auto; }
ul.questions { margin: 4px 0 8px; padding-left: 20px; }
ul.questions li { margin: 3px 0; }
ul.questions .q { font-weight: 600; }
svg.chart { width: 100%; height: auto; display: block; max-width: 900px; }
svg.chart text { fill: var(--fg); font: 12px system-ui, -apple-system, "Segoe UI", Roboto, Arial, sans-serif; }
svg.chart text.muted { fill: var(--muted); }
svg.chart .in { fill: var(--in); }
svg.chart .out { fill: var(--out); }
svg.chart .skip { fill: var(--skip); }
svg.chart .grid { stroke: var(--grid); stroke-width: 1; }
svg.chart .axis { stroke: var(--muted); stroke-width: 1; }
svg.chart .pt { fill: var(--accent); }
svg.chart .mark { stroke: var(--mark); stroke-width: 1.5; stroke-dasharray: 4 3; }
svg.chart text.marklabel { fill: var(--mark); }
svg.lightpanel .panel { fill: #ffffff; }
svg.lightpanel text, svg.lightpanel text.muted { fill: #1b1f24; }
svg.lightpanel .grid { stroke: #e3e7eb; }
svg.lightpanel .axis { stroke: #5b6570; }
.gallery { display: grid; grid-template-columns: repeat(auto-fill, minmax(440px, 1fr)); gap: 14px; }
figure { margin: 0; scroll-margin-top: 12px; }
figure:target { outline: 3px solid var(--mark); outline-offset: 3px; }
.imgwrap { position: relative; display: block; line-height: 0; overflow: hidden; border: 1px solid var(--border); }
.imgwrap img { width: 100%; height: auto; display: block; image-rendering: auto; }
.hl { position: absolute; display: none; border: 2px solid var(--mark); box-shadow: 0 0 0 2px #000a;
  min-width: 6px; min-height: 6px; scroll-margin-top: 80px; }
.hl:target { display: block; }
figcaption { font-size: 0.9em; margin-top: 4px; }
figcaption b { color: var(--fg); }
dialog { max-width: 96vw; max-height: 96vh; padding: 8px; border: 1px solid var(--border);
  background: var(--bg); color: var(--fg); }
dialog::backdrop { background: #000b; }
dialog img { max-width: 92vw; max-height: 88vh; display: block; }
dialog p { margin: 4px 0 0; }
details > summary { cursor: pointer; color: var(--muted); }
.swatch { display: inline-block; width: 10px; height: 10px; margin-right: 4px; vertical-align: baseline; }
.evidence { display: grid; grid-template-columns: minmax(280px, 2fr) 3fr; gap: 14px; align-items: start; }
@media (max-width: 900px) { .evidence { grid-template-columns: 1fr; } }
)CSS";

inline constexpr const char *kScript = R"JS(
'use strict';
(function () {
  var dlg = document.getElementById('enlarge');
  if (!dlg || typeof dlg.showModal !== 'function') return;  // no <dialog>: links open the PNG
  var big = dlg.querySelector('img');
  var cap = dlg.querySelector('p');
  document.querySelectorAll('a.enlarge').forEach(function (a) {
    a.addEventListener('click', function (ev) {
      ev.preventDefault();
      big.src = a.getAttribute('href');
      big.alt = a.dataset.title || '';
      cap.textContent = a.dataset.title || '';
      dlg.showModal();
    });
  });
  dlg.addEventListener('click', function () { dlg.close(); });
})();
)JS";

}  // namespace va::html_assets
