// Browser test of grade.html and the class's index.html (docs/grading.md): makes an assignment kit of
// the built-in demo, a submission with known mistakes taken from the reference answers themselves,
// grades it as a class of one, and opens the pages from file:// URLs in headless Debian chromium
// through playwright-core (as report.test.mjs does).
//
//   node grade.test.mjs --visaudit BUILD/visaudit --out DIR [--screenshot FILE.png]
//
// The submission: every answer copied (its id images are the answers' own EXR files), then
// backface's kept ids replaced by the ones the reference culls (winding reversed), clip's
// per_plane.near set to 0 (near plane not clipped) and the painter's order replaced by the
// nearest-vertex key's: three hints. Its folder's name holds markup, which must show as text.
// Checks, in light and in dark color scheme: no console error, no page error, no failed or
// non-file request, no dialog; index.html lists the student and links to the page; the page's
// heading is the name as text, the score, one row per check of grade.json, the three hints, a
// section per view, every image loaded and shown at a usable size.
// Exit codes: 0 pass, 1 fail, 77 skipped (no chromium, or playwright-core not installed).
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { pathToFileURL } from 'node:url';

const SKIP = 77;
const args = {};
for (let i = 2; i + 1 < process.argv.length; i += 2) args[process.argv[i].replace(/^--/, '')] = process.argv[i + 1];
if (!args.visaudit || !args.out) {
  console.error('usage: node grade.test.mjs --visaudit BIN --out DIR [--screenshot FILE.png]');
  process.exit(2);
}
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

// The kit, its answers and the submission.
const out = path.resolve(args.out);
fs.rmSync(out, { recursive: true, force: true });
fs.mkdirSync(out, { recursive: true });
const kit = path.join(out, 'kit'), answers = path.join(out, 'answers');
execFileSync(args.visaudit, ['assignment', '--width', '160', '--height', '90', '--images', 'ids', '--out', kit,
                             '--answers', answers, '--quiet'], { stdio: 'inherit' });
const student = 'eve<img src=x onerror=alert(1)>';
const sub = path.join(out, 'subs', student);
fs.mkdirSync(sub, { recursive: true });
const assignment = JSON.parse(fs.readFileSync(path.join(kit, 'assignment.json'), 'utf8'));
const views = {};
for (const v of assignment.views) {
  const block = {};
  for (const stage of assignment.stages) {
    const a = JSON.parse(fs.readFileSync(path.join(answers, 'views', v.dir, `${stage}.json`), 'utf8'));
    const b = structuredClone(a.answer);
    if (a.images && a.images.ids) {
      const name = `${v.dir}.${stage}.ids.exr`;
      fs.copyFileSync(path.join(answers, 'views', v.dir, a.images.ids), path.join(sub, name));
      b.ids = name;
    }
    if (stage === 'backface') b.kept = a.extra.culled;
    if (stage === 'clip') b.per_plane.near = 0;
    if (stage === 'painter') b.order = a.extra.orders.nearest_vertex;
    block[stage] = b;
  }
  views[v.name] = block;
}
fs.writeFileSync(path.join(sub, 'submission.json'),
                 JSON.stringify({ format: 'visaudit-submission/1', student, views }, null, 1));
const grades = path.join(out, 'grades');
execFileSync(args.visaudit, ['grade', '--kit', kit, '--reference', answers, '--submissions', sub, '--out', grades,
                             '--quiet'], { stdio: 'inherit' });
const index = path.join(grades, 'index.html');
const gradeJson = JSON.parse(fs.readFileSync(path.join(grades, 'students', 'eve_img_src_x_onerror_alert_1__', 'grade.json'), 'utf8'));

const failures = [];
const fail = (msg) => failures.push(msg);
const browser = await chromium.launch({
  executablePath: chromiumPath,
  headless: true,
  args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
         '--disable-component-update', '--disable-sync'],
});

async function checkScheme(colorScheme, screenshot) {
  const tag = `[${colorScheme}]`;
  const context = await browser.newContext({ viewport: { width: 1280, height: 900 }, colorScheme });
  const page = await context.newPage();
  page.setDefaultTimeout(10000);
  page.on('console', (m) => { if (m.type() === 'error') fail(`${tag} console error: ${m.text()}`); });
  page.on('pageerror', (e) => fail(`${tag} page error: ${e.message}`));
  page.on('requestfailed', (r) => fail(`${tag} request failed: ${r.url()} (${r.failure()?.errorText})`));
  page.on('dialog', (d) => { fail(`${tag} a script opened a ${d.type()} dialog: ${d.message()}`); d.dismiss(); });
  page.on('request', (r) => { if (!r.url().startsWith('file:')) fail(`${tag} network request: ${r.url()}`); });

  // The class page lists the student (as text) and links to the student's page.
  await page.goto(pathToFileURL(index).href, { waitUntil: 'load' });
  const link = page.locator('a', { hasText: student });
  if ((await link.count()) !== 1) fail(`${tag} index.html: no link named ${JSON.stringify(student)}`);
  await link.click();
  await page.waitForLoadState('load');

  const h1 = await page.locator('h1').textContent();
  if (h1 !== `Grade: ${student}`) fail(`${tag} heading ${JSON.stringify(h1)} is not the student's name as text`);
  const score = await page.locator('#score').textContent();
  if (score !== `${(100 * gradeJson.score).toFixed(1)}%`) fail(`${tag} score ${score}, grade.json has ${gradeJson.score}`);
  const rows = await page.locator('section.view table tr:not(:first-child)').count();
  if (rows !== gradeJson.items.length) fail(`${tag} ${rows} check rows for ${gradeJson.items.length} items`);
  const failedRows = await page.locator('section.view tr.failed').count();
  if (failedRows !== gradeJson.failed) fail(`${tag} ${failedRows} failed rows for ${gradeJson.failed} failed items`);
  const hintText = await page.locator('#hints').textContent();
  for (const h of ['Winding reversed', 'Near plane not clipped', "Painter's key"])
    if (!hintText.includes(h)) fail(`${tag} hint "${h}" is not shown`);
  const sections = await page.locator('section.view').count();
  if (sections !== assignment.views.length) fail(`${tag} ${sections} view sections for ${assignment.views.length} views`);
  const imgs = await page.locator('img').evaluateAll((all) => all.map((im) => ({ src: im.getAttribute('src'),
    ok: im.complete && im.naturalWidth > 0, w: im.getBoundingClientRect().width })));
  if (imgs.length !== gradeJson.images.length) fail(`${tag} ${imgs.length} images for ${gradeJson.images.length} compared`);
  for (const im of imgs) {
    if (!im.ok) fail(`${tag} image did not load: ${im.src}`);
    if (!(im.w >= 300)) fail(`${tag} image not displayed at a usable size: ${im.src} (${im.w}px wide)`);
  }
  const bg = await page.evaluate(() => getComputedStyle(document.documentElement).backgroundColor);
  const rgb = bg.match(/\d+/g).map(Number);
  const lum = (0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]) / 255;
  if (colorScheme === 'dark' ? lum > 0.3 : lum < 0.7) fail(`${tag} background ${bg} does not follow the color scheme`);
  if (screenshot) {
    await page.screenshot({ path: screenshot, fullPage: false });
    console.log(`${tag} screenshot: ${screenshot}`);
  }
  await context.close();
}

try {
  await checkScheme('light', args.screenshot);
  await checkScheme('dark', args.screenshot ? args.screenshot.replace(/\.png$/, '-dark.png') : undefined);
} catch (e) {
  fail(`exception: ${e.stack || e}`);
} finally {
  await browser.close();
}
if (failures.length) {
  for (const f of failures) console.error(`FAIL: ${f}`);
  process.exit(1);
}
console.log(`PASS: ${index} and the student's grade.html in light and dark, no console errors`);
