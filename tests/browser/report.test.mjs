// Browser test of report.html (docs/html-report.md): opens the page from a file:// URL in headless
// Debian chromium through playwright-core (no browser download) and fails on anything a reader
// would see broken.
//
//   node report.test.mjs --visaudit BUILD/visaudit --out DIR [--views V] [--analyze-args "A B"]
//                        [--screenshot FILE.png]
//       runs `visaudit analyze --out DIR --quiet` (the built-in demo; --views and the space-separated
//       --analyze-args passed on), then tests DIR/report.html
//   node report.test.mjs --report DIR [--screenshot FILE.png]
//       tests an existing report folder
//
// Checks, in light and in dark color scheme:
//   - no console error, no uncaught page error, no failed request, no request that is not file:
//   - one section per view of report.json, headed by the view's name as text (a name holding
//     markup must not become markup, nor open an alert), a summary row per view;
//   - per view a visible stage-funnel SVG with one row per stage of report.json;
//   - every <img> loaded (complete, naturalWidth > 0), and every PNG report.json lists is shown;
//   - a hotspot row's link outlines the hotspot's bbox on the z-fight image, at the right place;
//   - clicking an image opens it enlarged in a dialog;
//   - with routes (--views route:...): per route a plot with a line per metric, its worst frames
//     linking to views that exist; with level maps: every map image loaded, a ring over each
//     numbered worst position, centred on the position's dot and linking to its view.
// Exit codes: 0 pass, 1 fail, 77 skipped (no chromium, or playwright-core not installed in
// tests/browser/node_modules: `npm ci` there), as CTest's SKIP_RETURN_CODE.
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { pathToFileURL } from 'node:url';

const SKIP = 77;
const stem = (file) => file.replace(/\.png$/, '');

function parseArgs(argv) {
  const a = {};
  for (let i = 2; i < argv.length; i += 2) {
    if (!argv[i].startsWith('--') || i + 1 >= argv.length) {
      console.error(`usage: node report.test.mjs (--visaudit BIN --out DIR | --report DIR) [--screenshot FILE]; bad argument '${argv[i]}'`);
      process.exit(2);
    }
    a[argv[i].slice(2)] = argv[i + 1];
  }
  return a;
}

const args = parseArgs(process.argv);
const chromiumPath = process.env.VISAUDIT_CHROMIUM || '/usr/bin/chromium';
if (!fs.existsSync(chromiumPath)) {
  console.log(`SKIP: no chromium at ${chromiumPath} (scripts/install-deps.sh installs Debian's chromium)`);
  process.exit(SKIP);
}
let chromium;
try {
  ({ chromium } = await import('playwright-core'));
} catch (e) {
  console.log(`SKIP: playwright-core is not installed (run 'npm ci' in tests/browser; scripts/test.sh does): ${e.message}`);
  process.exit(SKIP);
}

// The report folder: made by the binary, or given.
let dir = args.report;
if (args.visaudit) {
  if (!args.out) {
    console.error('--visaudit needs --out DIR');
    process.exit(2);
  }
  dir = args.out;
  execFileSync(args.visaudit, ['analyze', '--out', dir, '--quiet', ...(args.views ? ['--views', args.views] : []),
                               ...(args['analyze-args'] ? args['analyze-args'].split(' ').filter((x) => x) : [])],
               { stdio: 'inherit' });
}
if (!dir) {
  console.error('give --visaudit BIN --out DIR or --report DIR');
  process.exit(2);
}
const failures = [];
const fail = (msg) => failures.push(msg);
const htmlPath = path.resolve(dir, 'report.html');
if (!fs.existsSync(htmlPath)) {
  console.error(`FAIL: ${htmlPath} does not exist: the command did not write report.html (is writeReportHtml called after report.json?)`);
  process.exit(1);
}
const report = JSON.parse(fs.readFileSync(path.resolve(dir, 'report.json'), 'utf8'));
const url = pathToFileURL(htmlPath).href;

// Every PNG the report lists for a view (strings and arrays of strings under keys ending in _png).
function listedPngs(view) {
  const out = [];
  for (const [k, v] of Object.entries(view.images || {})) {
    if (!k.endsWith('_png')) continue;
    for (const f of Array.isArray(v) ? v : [v]) if (typeof f === 'string') out.push(f);
  }
  return out;
}

// playwright-core's launch() gives chromium a new empty profile folder of its own (it refuses a
// --user-data-dir argument) and removes it on close.
const browser = await chromium.launch({
  executablePath: chromiumPath,
  headless: true,
  args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
         '--disable-component-update', '--disable-sync'],
});

async function checkScheme(colorScheme, screenshot) {
  const tag = `[${colorScheme}]`;
  const context = await browser.newContext({ viewport: { width: 1400, height: 1000 }, colorScheme });
  const page = await context.newPage();
  page.setDefaultTimeout(10000);  // the page is local: anything slower is broken
  page.on('console', (m) => { if (m.type() === 'error') fail(`${tag} console error: ${m.text()}`); });
  page.on('pageerror', (e) => fail(`${tag} page error: ${e.message}`));
  page.on('requestfailed', (r) => fail(`${tag} request failed: ${r.url()} (${r.failure()?.errorText})`));
  page.on('dialog', (d) => { fail(`${tag} a script opened a ${d.type()} dialog: ${d.message()}`); d.dismiss(); });
  page.on('request', (r) => { if (!r.url().startsWith('file:')) fail(`${tag} network request: ${r.url()}`); });
  await page.goto(url, { waitUntil: 'load' });

  // Sections and the summary.
  const sections = await page.locator('section.view').count();
  if (sections !== report.views.length) fail(`${tag} ${sections} view sections for ${report.views.length} views`);
  const summaryRows = await page.locator('#summary-table tr').count();
  if (summaryRows !== report.views.length + 1) fail(`${tag} summary has ${summaryRows - 1} rows for ${report.views.length} views`);

  for (let i = 0; i < report.views.length; ++i) {
    const view = report.views[i];
    // The name shows as text, exactly as the report has it (markup in a name is not markup).
    const title = await page.locator(`#v${i} > h2`).textContent();
    if (title !== (view.name || '(unnamed view)')) fail(`${tag} view ${i}: heading ${JSON.stringify(title)} is not the name ${JSON.stringify(view.name)}`);
    // The funnel: visible, sized, one row per stage.
    const funnel = page.locator(`#v${i}-funnel`);
    const box = await funnel.boundingBox();
    if (!box || box.width < 300 || box.height < 60) fail(`${tag} view ${i}: funnel chart not visible (${JSON.stringify(box)})`);
    const rows = await funnel.locator('g.stage').count();
    if (rows !== view.stages.length) fail(`${tag} view ${i}: funnel has ${rows} rows for ${view.stages.length} stages`);
    // A stage that ran draws a bar with a width proportional to its triangles_in, at least 1 (a
    // stage of 12 triangles after one of 8,000 is that thin).
    for (const st of view.stages.filter((s) => s.ran && s.triangles_in > 0)) {
      const bar = funnel.locator(`g.stage[data-stage="${st.name}"] rect.in`);
      const w = (await bar.count()) === 1 ? await bar.evaluate((r) => r.getBBox().width) : 0;
      if (!(w >= 1)) fail(`${tag} view ${i}: stage ${st.name} has no bar`);
    }
    // Every listed PNG is on the page.
    const srcs = await page.locator(`#v${i} img`).evaluateAll((imgs) => imgs.map((im) => im.getAttribute('src')));
    for (const f of listedPngs(view))
      if (!srcs.includes(encodeURI(f)) && !srcs.includes(f)) fail(`${tag} view ${i}: image ${f} is not shown`);
  }

  // Every image loaded (lazily loaded ones of later views are made to load first).
  await page.evaluate(() => Promise.all([...document.querySelectorAll('img[loading="lazy"]')].map((im) => {
    im.loading = 'eager';
    return im.complete ? null : new Promise((res) => { im.onload = im.onerror = res; });
  })));
  const imgs = await page.locator('img').evaluateAll((all) =>
    all.filter((im) => im.closest('dialog') === null).map((im) => ({ src: im.getAttribute('src'), ok: im.complete && im.naturalWidth > 0,
                                                                        w: im.getBoundingClientRect().width })));
  if (imgs.length === 0) fail(`${tag} no images on the page`);
  for (const im of imgs) {
    if (!im.ok) fail(`${tag} image did not load: ${im.src}`);
    if (!(im.w > 100)) fail(`${tag} image not displayed at a usable size: ${im.src} (${im.w}px wide)`);
  }

  // A hotspot link outlines its bbox on the z-fight image.
  const vi = report.views.findIndex((v) => v.depth && v.depth.hotspots && v.depth.hotspots.length > 0 && v.images.zfight_png);
  if (vi >= 0) {
    const h = report.views[vi].depth.hotspots[0];
    const link = page.locator(`#v${vi} table.hotspots a.px`).first();
    await link.click();
    const hl = page.locator(`#v${vi}-hs${h.id}`);
    const hb = await hl.boundingBox();
    const img = page.locator(`#v${vi}-img-zfight img`);
    const ib = await img.boundingBox();
    const natural = await img.evaluate((im) => im.naturalWidth);
    if (!hb || !ib) {
      fail(`${tag} hotspot ${h.id}: no highlight box after clicking its row`);
    } else {
      const s = ib.width / natural;
      const [x0, y0, x1] = h.bbox;
      const near = (a, b) => Math.abs(a - b) <= 3;
      if (!near(hb.x, ib.x + x0 * s) || !near(hb.y, ib.y + y0 * s) || !near(hb.width, Math.max(6, (x1 - x0 + 1) * s)))
        fail(`${tag} hotspot ${h.id}: box ${JSON.stringify(hb)} is not over bbox ${h.bbox} of the image at ${JSON.stringify(ib)}`);
      if (screenshot) await page.locator(`#v${vi}-img-zfight`).screenshot({ path: stem(screenshot) + '-hotspot.png' });
    }
  } else {
    console.log(`${tag} note: no view with hotspots; highlight not tested`);
  }

  // Routes: a plot per route, a line per metric, the worst frames linking to views on the page.
  for (const route of report.routes || []) {
    const id = 'route-' + route.name.toLowerCase().replace(/[^a-z0-9_-]/g, '_');
    const plot = page.locator(`#${id}-plot`);
    const pb = await plot.boundingBox();
    if (!pb || pb.width < 300 || pb.height < 200) fail(`${tag} route ${route.name}: plot not visible (${JSON.stringify(pb)})`);
    const lines = await plot.locator('polyline.line').evaluateAll((ls) => ls.map((l) => l.getAttribute('points').split(' ').length));
    const analysed = Object.keys(route.series).filter((k) => !['view', 'frame', 'time'].includes(k) &&
                                                             route.series[k].some((v) => v !== null));
    if (lines.length !== analysed.length) fail(`${tag} route ${route.name}: ${lines.length} lines for ${analysed.length} metrics`);
    for (const n of lines) if (n !== route.series.time.length) fail(`${tag} route ${route.name}: a line of ${n} points for ${route.series.time.length} frames`);
    const worst = await plot.locator('a.worstframe').evaluateAll((as) => as.map((a) => a.getAttribute('href')));
    const listed = Object.values(route.worst).reduce((n, w) => n + w.length, 0);
    if (worst.length !== listed) fail(`${tag} route ${route.name}: ${worst.length} worst-frame links for ${listed} worst frames`);
    for (const h of worst) if ((await page.locator(h).count()) !== 1) fail(`${tag} route ${route.name}: worst frame link ${h} leads nowhere`);
  }
  // Level maps: every map loaded; a ring over each numbered worst position, on its dot.
  if (report.level_maps && report.level_maps.maps) {
    for (const m of report.level_maps.maps) {
      if (!m.image) continue;
      const fig = page.locator(`#level-map-${m.metric.toLowerCase().replace(/[^a-z0-9_-]/g, '_')}`);
      const img = fig.locator('img');
      const ib = await img.boundingBox();
      const natural = await img.evaluate((im) => ({ w: im.naturalWidth, h: im.naturalHeight }));
      if (!ib || !(natural.w > 0)) { fail(`${tag} level map ${m.metric}: image not shown`); continue; }
      const pins = fig.locator('a.lm-pin');
      if ((await pins.count()) !== m.worst.length) fail(`${tag} level map ${m.metric}: ${await pins.count()} rings for ${m.worst.length} worst positions`);
      for (let k = 0; k < Math.min(m.worst.length, await pins.count()); ++k) {
        const w = m.worst[k], p = report.level_maps.positions[w.position];
        const b = await pins.nth(k).boundingBox();
        const cx = ib.x + (Math.floor(p.x) + 0.5) * ib.width / natural.w, cy = ib.y + (Math.floor(p.y) + 0.5) * ib.height / natural.h;
        if (!b || Math.abs(b.x + b.width / 2 - cx) > 2 || Math.abs(b.y + b.height / 2 - cy) > 2)
          fail(`${tag} level map ${m.metric}: ring ${k + 1} at ${JSON.stringify(b)} is not on position ${w.position} (${cx}, ${cy})`);
        const href = await pins.nth(k).getAttribute('href');
        if (href !== `#v${w.view}`) fail(`${tag} level map ${m.metric}: ring ${k + 1} links to ${href}, not #v${w.view}`);
      }
    }
  }

  // Click to enlarge.
  await page.locator('a.enlarge').first().click();
  const open = await page.locator('dialog#enlarge').evaluate((d) => d.open);
  const bigOk = await page.locator('dialog#enlarge img').evaluate((im) => new Promise((res) => {
    if (im.complete) res(im.naturalWidth > 0); else im.onload = () => res(im.naturalWidth > 0);
  }));
  if (!open || !bigOk) fail(`${tag} clicking an image does not open it enlarged`);
  await page.keyboard.press('Escape');

  // The color scheme is applied.
  const bg = await page.evaluate(() => getComputedStyle(document.documentElement).backgroundColor);
  const rgb = bg.match(/\d+/g).map(Number);
  const lum = (0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]) / 255;
  if (colorScheme === 'dark' ? lum > 0.3 : lum < 0.7) fail(`${tag} background ${bg} does not follow the color scheme`);

  if (screenshot) {
    await page.evaluate(() => { document.activeElement?.blur(); window.location.hash = ''; window.scrollTo(0, 0); });
    await page.screenshot({ path: screenshot, fullPage: false });
    await page.locator('#v0').screenshot({ path: stem(screenshot) + '-view0.png' });
    console.log(`${tag} screenshots: ${screenshot}, ${stem(screenshot)}-view0.png`);
  }
  await context.close();
}

try {
  await checkScheme('light', args.screenshot);
  await checkScheme('dark', args.screenshot ? stem(args.screenshot) + '-dark.png' : undefined);
} catch (e) {
  fail(`exception: ${e.stack || e}`);
} finally {
  await browser.close();
}
if (failures.length) {
  for (const f of failures) console.error(`FAIL: ${f}`);
  process.exit(1);
}
console.log(`PASS: ${url} (${report.views.length} views) in light and dark, no console errors`);
