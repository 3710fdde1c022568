// The demo page in a real browser (ctest web_page; docs/web.md): headless Chromium (Debian's, with
// SwiftShader's WebGL2) loads web/site from a server on 127.0.0.1, the page draws a fixed view
// from the model's sky-view table into a float target and posts its linear cd/m^2 pixels back;
// `atmo render` renders the same view natively, and the two must agree.
//
//   node tests/web/page_test.mjs SITE_DIR ATMO_CLI
//
// Tolerances, per model, away from the sun disc (pixels within 1 degree of the sun's centre are
// compared by their summed energy instead). hillaire: `atmo render` evaluates it through the same
// 192 x 108 sky-view table, in float on the CPU, so the two differ by float rounding in the
// mapping and the GPU's bilinear weights: median relative difference under 3e-4, 99th percentile
// under 3e-3; at most 1 % of the values (one image row is 0.56 %) may differ by more than 1 %:
// a pixel within ~1e-4 rad of the horizon may land on the other side of it in float (measured:
// one row). source4d: `atmo render` evaluates it exactly, the page through the table, which adds
// the table's interpolation error: median under 2e-3, 99th percentile under 2e-2. The sun disc's
// energy (the sum of L over its pixels) agrees within 2 % (8 x 8 samples per pixel against the
// CPU's stratified integration). Exits 1 on failure; prints the measured figures and the page's
// timings.
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';

import { compareFrames, findChromium, nativeRender, percentile, runChromium, startServer } from './browser.mjs';
import { readExr } from './exr.mjs';

const [siteDir, cli] = process.argv.slice(2);
if (!siteDir || !cli) {
  console.error('usage: node tests/web/page_test.mjs SITE_DIR ATMO_CLI');
  process.exit(2);
}
const chromium = findChromium();
// Served cross-origin isolated, the page runs the threaded module (docs/web.md); with
// ATMO_WEB_TEST_ISOLATED=0 the single-threaded one, as from a plain static server.
const isolated = process.env.ATMO_WEB_TEST_ISOLATED !== '0';
const expectedThreads = Math.min(Math.max(os.availableParallelism?.() ?? os.cpus().length, 1), 8);
let waiting = null;  // {resolve, reject, result, name}
const server = await startServer(siteDir, (name, headers, body) => {
  if (!waiting) return;
  if (name === 'result') {
    waiting.result = { width: Number(headers['x-width']), height: Number(headers['x-height']),
                       timings: JSON.parse(headers['x-timings']),
                       pixels: new Float32Array(body.buffer, body.byteOffset, body.byteLength / 4) };
  } else if (name === 'screenshot') {
    // The page as displayed, kept where ATMO_WEB_SCREENSHOTS names a folder.
    if (process.env.ATMO_WEB_SCREENSHOTS) fs.writeFileSync(path.join(process.env.ATMO_WEB_SCREENSHOTS, `${waiting.name}.png`), body);
    waiting.resolve(waiting.result);
  } else if (name === 'error') {
    waiting.reject(new Error(`the page failed: ${body}`));
  }
}, { isolated });
const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'atmo-web-page-'));

// Headless Chromium's window holds 143 pixels of its own above the page: a window this much taller
// than 720 gives the page a 1280 x 720 viewport.
const kWindowFrame = 143;
let failures = 0;
const width = 320;
const height = 180;
const cases = [
  { params: { model: 'hillaire', preset: 'earth', sunElevation: 10, sunAzimuth: 180, yaw: 160, pitch: 8, fov: 90, altitude: 0,
              error: '1' },
    median: 3e-4, p99: 3e-3, sunEnergy: 0.02 },
  { params: { model: 'source4d', preset: 'earth', sunElevation: 5, sunAzimuth: 250, yaw: 230, pitch: 5, fov: 100, altitude: 0,
              error: '1' },
    median: 2e-3, p99: 2e-2, sunEnergy: 0.02 },
];
// ATMO_WEB_TEST_MODELS (a comma list) keeps those cases only: the single-threaded run checks the
// page's fallback on hillaire alone (source4d's single-threaded module is tests/web/api_test.mjs's).
const models = process.env.ATMO_WEB_TEST_MODELS?.split(',');
const chosen = cases.filter((c) => !models || models.includes(c.params.model));
if (chosen.length === 0) {
  console.error(`ATMO_WEB_TEST_MODELS=${process.env.ATMO_WEB_TEST_MODELS} names no case`);
  process.exit(2);
}
for (const c of chosen) {
  const label = `${c.params.model} sun ${c.params.sunElevation} deg`;
  const url = `http://127.0.0.1:${server.port}/index.html?test=${width}x${height}#${new URLSearchParams(c.params)}`;
  const page = await runChromium(chromium, url, new Promise((resolve, reject) => {
    waiting = { resolve, reject, result: null, name: `${c.params.model}-sun${c.params.sunElevation}` };
  }), { width: 1280, height: 720 + kWindowFrame });
  waiting = null;
  const exr = path.join(tmp, 'native.exr');
  nativeRender(cli, c.params, width, height, exr);
  const { differences, pageSun, nativeSun } = compareFrames(c.params, width, height, page.pixels, readExr(exr));
  const median = percentile(differences, 0.5);
  const p99 = percentile(differences, 0.99);
  const largest = differences[differences.length - 1];
  const offByOnePercent = differences.filter((d) => d > 0.01).length / differences.length;
  const sunRatio = nativeSun > 0 ? pageSun / nativeSun : NaN;
  console.log(`${label}: ${differences.length} values, relative difference to atmo render: median ${median.toExponential(2)}, ` +
              `p99 ${p99.toExponential(2)}, largest ${largest.toExponential(2)}, ` +
              `${(100 * offByOnePercent).toFixed(2)} % off by more than 1 %; sun disc energy page/native ${sunRatio.toFixed(4)}`);
  console.log(`${label}: page timings ${JSON.stringify(page.timings)}`);
  const fail = (what) => {
    console.error(`FAIL: ${label}: ${what}`);
    failures += 1;
  };
  if (!(median <= c.median)) fail(`median ${median} > ${c.median}`);
  if (!(p99 <= c.p99)) fail(`p99 ${p99} > ${c.p99}`);
  if (!(offByOnePercent <= 0.01)) fail(`${100 * offByOnePercent} % of the values off by more than 1 %`);
  if (!(Math.abs(sunRatio - 1) <= c.sunEnergy)) fail(`sun energy ratio ${sunRatio}`);
  // The module the page chose: the threaded one when isolated on a machine with cores to spare.
  const threads = page.timings.threads;
  if (isolated ? expectedThreads > 1 && !(threads > 1) : threads !== 1) {
    fail(`the page's module runs ${threads} threads (served ${isolated ? '' : 'not '}cross-origin isolated)`);
  }
  // The error map's statistics against the shipped reference, recomputed here from the native
  // library's samples of the same directions: the page must report the same numbers.
  const stats = page.timings.errorStats;
  if (c.params.error === '1') {
    const csv = fs.readFileSync(path.join(siteDir, 'reference_earth.csv'), 'utf8').trim().split('\n').slice(1)
      .map((line) => line.split(',').map(Number)).filter((f) => Math.abs(90 - f[1] - c.params.sunElevation) < 1e-9);
    const grid = path.join(tmp, 'grid.csv');
    fs.writeFileSync(grid, 'altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg\n' +
                           csv.map((f) => f.slice(0, 4).join(',')).join('\n') + '\n');
    const native = execFileSync(cli, ['sample', '--model', c.params.model, '--preset', 'earth', '--grid', grid, '--unit',
                                      'luminance'], { encoding: 'utf8' }).trim().split('\n').slice(1)
      .map((line) => Number(line.split(',')[4]));
    const errors = native.map((v, i) => Math.abs(v / csv[i][4] - 1)).sort((a, b) => a - b);
    const median = errors[Math.floor(errors.length / 2)];
    console.log(`${label}: error map against the reference: page median |error| ${stats && stats.median}, ` +
                `native ${median} (${errors.length} directions)`);
    if (!stats || stats.points !== errors.length || !(Math.abs(stats.median - median) <= 1e-5 * median + 1e-9)) {
      fail(`error map statistics ${JSON.stringify(stats)} against native median ${median}`);
    }
  }
}
server.close();
fs.rmSync(tmp, { recursive: true, force: true });
if (failures > 0) process.exit(1);
console.log('all checks passed');
