// Opens a report.html written by `multicue demo` in headless Chromium (software WebGL) and checks
// what a person would see: the 3D view draws the scene, the object list is the one of result.json,
// clicking an object in the list or in the view selects it, the colour buttons recolour the cloud.
// Saves a screenshot and prints the page's load time and size.
//
//   node report_browser.mjs --multicue PATH --out DIR [--chromium PATH] [--screenshot FILE]
//
// Exits 77 (ctest's skip code) when Chromium or web/node_modules/playwright-core is missing.

import {execFileSync} from 'node:child_process';
import {existsSync, mkdirSync, readFileSync, statSync} from 'node:fs';
import {createRequire} from 'node:module';
import {dirname, join, resolve} from 'node:path';
import {fileURLToPath, pathToFileURL} from 'node:url';

const SKIP = 77;
const here = dirname(fileURLToPath(import.meta.url));
const args = {};
for (let i = 2; i + 1 < process.argv.length; i += 2) args[process.argv[i].replace(/^--/, '')] = process.argv[i + 1];
if (!args.multicue || !args.out) {
    console.error('usage: node report_browser.mjs --multicue PATH --out DIR [--chromium PATH] [--screenshot FILE]');
    process.exit(2);
}
const chromiumPath = args.chromium || '/usr/bin/chromium';
if (!existsSync(chromiumPath)) {
    console.log(`SKIP: no Chromium at ${chromiumPath} (scripts/setup.sh installs it)`);
    process.exit(SKIP);
}
let chromium;
try {
    chromium = createRequire(join(here, '..', 'package.json'))('playwright-core').chromium;
} catch {
    console.log('SKIP: web/node_modules/playwright-core is missing (run scripts/setup.sh)');
    process.exit(SKIP);
}

const failures = [];
function check(ok, what) {
    console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`);
    if (!ok) failures.push(what);
}

// 1. A report of the synthetic 640x480 demo scene.
const out = resolve(args.out);
mkdirSync(out, {recursive: true});
const demoDir = join(out, 'demo');
execFileSync(resolve(args.multicue), ['--threads', '2', 'demo', '--out', 'demo'], {cwd: out, stdio: 'inherit'});
const reportPath = join(demoDir, 'report.html');
const result = JSON.parse(readFileSync(join(demoDir, 'result.json'), 'utf8'));
const html = readFileSync(reportPath, 'utf8');
if (!html.includes('id="mc-data"')) {
    console.log('SKIP: this multicue build has no 3D viewer (web/node_modules was missing)');
    process.exit(SKIP);
}
const sizeMiB = statSync(reportPath).size / (1024 * 1024);

const browser = await chromium.launch({
    executablePath: chromiumPath,
    headless: true,
    args: ['--headless=new', '--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
           '--ignore-gpu-blocklist'],
});
try {
    const page = await browser.newPage({viewport: {width: 1280, height: 800}});
    const errors = [];
    page.on('pageerror', (e) => errors.push(String(e)));
    page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
    const requests = [];
    page.on('request', (r) => { if (!r.url().startsWith('file:') && !r.url().startsWith('data:')) requests.push(r.url()); });

    // 2. Load time: navigation start to the first frame drawn (the viewer's own mark).
    const t0 = Date.now();
    await page.goto(pathToFileURL(reportPath).href, {waitUntil: 'load'});
    await page.waitForFunction(() => window.multicueReport && (window.multicueReport.ready || window.multicueReport.error),
                               null, {timeout: 60000});
    const wallMs = Date.now() - t0;
    const state = await page.evaluate(() => ({
        error: window.multicueReport.error, loadMs: window.multicueReport.loadMs,
        objects: window.multicueReport.objects, timings: window.multicueReport.timings,
    }));
    check(!state.error, `viewer started${state.error ? ': ' + state.error : ''}`);

    // 3. The object list is result.json's.
    const rows = await page.$$eval('[data-object]', (els) => els.map((e) => ({id: Number(e.dataset.object), category: e.dataset.category})));
    const expected = result.objects.map((o) => ({id: o.id, category: o.category}));
    check(JSON.stringify(rows) === JSON.stringify(expected),
          `object list matches result.json (${rows.length} objects: ${rows.map((r) => r.category).join(', ')})`);
    check(JSON.stringify(state.objects) === JSON.stringify(expected.map((o) => o.id)), 'viewer data has the same objects');
    check(expected.length > 0, 'the demo scene has objects');

    // 4. The canvas shows the scene: count pixels that differ from the background.
    const pixels = () => page.evaluate(() => {
        const gl = document.querySelector('#mc-view canvas');
        const c = document.createElement('canvas');
        c.width = gl.width;
        c.height = gl.height;
        const ctx = c.getContext('2d');
        ctx.drawImage(gl, 0, 0);
        const d = ctx.getImageData(0, 0, c.width, c.height).data;
        let lit = 0;
        let sum = 0;
        for (let i = 0; i < d.length; i += 4) {
            if (Math.abs(d[i] - 0x1b) + Math.abs(d[i + 1] - 0x1f) + Math.abs(d[i + 2] - 0x24) > 24) ++lit;
            sum += d[i] + d[i + 1] + d[i + 2];
        }
        return {lit, total: d.length / 4, sum};
    });
    const before = await pixels();
    const share = before.lit / before.total;
    check(share > 0.05, `canvas shows the scene: ${(100 * share).toFixed(1)} % of ${before.total} pixels are not background`);

    // 5. Colour modes recolour the view.
    await page.click('[data-color-mode="category"]');
    const category = await pixels();
    check(category.sum !== before.sum, 'category colouring changes the picture');
    check(await page.isVisible('[data-legend="category"]'), 'category legend shown');

    // 6. Selecting from the list highlights the object (the rest is dimmed).
    const first = expected[0].id;
    await page.click(`[data-object="${first}"]`);
    const selected = await page.$$eval('.mc-object.selected', (els) => els.map((e) => Number(e.dataset.object)));
    check(JSON.stringify(selected) === JSON.stringify([first]), `clicking list entry #${first} selects it`);
    const dimmed = await pixels();
    check(dimmed.sum < category.sum, 'selection dims the other points');

    // 7. Clicking an object in the view selects it: aim at the projected centroid of another object.
    const target = expected.length > 1 ? expected[1].id : first;
    const at = await page.evaluate((id) => {
        const v = window.multicueReport.viewer;
        const obj = v.data.objects.find((o) => o.id === id);
        const p = v.camera.position.clone().fromArray(obj.centroid).project(v.camera);
        const r = v.renderer.domElement.getBoundingClientRect();
        return {x: r.left + (p.x + 1) / 2 * r.width, y: r.top + (1 - p.y) / 2 * r.height};
    }, target);
    await page.mouse.click(at.x, at.y);
    const picked = await page.$$eval('.mc-object.selected', (els) => els.map((e) => Number(e.dataset.object)));
    check(JSON.stringify(picked) === JSON.stringify([target]), `clicking object #${target} in the view selects it (got ${picked})`);

    // 8. Toggles hide the cloud; the models and the table remain.
    await page.click('[data-object="' + target + '"]');  // deselect
    await page.uncheck('[data-toggle="cloud"]');
    const noCloud = await pixels();
    check(noCloud.lit < before.lit && noCloud.lit > 0, 'hiding the cloud leaves models and support plane');
    await page.check('[data-toggle="cloud"]');
    await page.click('[data-color-mode="object"]');

    check(errors.length === 0, `no page errors${errors.length ? ': ' + errors.join(' | ') : ''}`);
    check(requests.length === 0, `no network requests${requests.length ? ': ' + requests.join(' ') : ''}`);

    const shot = resolve(args.screenshot || join(out, 'report.png'));
    await page.screenshot({path: shot});
    // A smaller picture for the documentation (docs/images/report.png).
    await page.setViewportSize({width: 960, height: 600});
    await page.waitForTimeout(200);
    await page.screenshot({path: shot.replace(/\.png$/, '-small.png')});
    console.log(`report: ${reportPath}`);
    console.log(`report size: ${sizeMiB.toFixed(2)} MiB, ${result.points} points in the scene`);
    console.log(`load time: ${state.loadMs.toFixed(0)} ms to the first frame (page clock), ${wallMs} ms navigation to ready (wall)`);
    console.log(`  of which: ${Object.entries(state.timings).map(([k, v]) => `${k} ${v.toFixed(0)} ms`).join(', ')}`);
    console.log(`screenshot: ${shot}`);
} finally {
    await browser.close();
}
if (failures.length) {
    console.log(`${failures.length} check(s) failed`);
    process.exit(1);
}
console.log('all checks passed');
