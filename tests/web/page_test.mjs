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
import { execFileSync, spawn } from 'node:child_process';
import fs from 'node:fs';
import http from 'node:http';
import os from 'node:os';
import path from 'node:path';

import { readExr } from './exr.mjs';

const [siteArgument, cli] = process.argv.slice(2);
const siteDir = siteArgument && path.resolve(siteArgument);
if (!siteArgument || !cli) {
  console.error('usage: node tests/web/page_test.mjs SITE_DIR ATMO_CLI');
  process.exit(2);
}
const chromium = ['chromium', 'chromium-browser', 'google-chrome'].map((name) => {
  try {
    return execFileSync('sh', ['-c', `command -v ${name}`], { encoding: 'utf8' }).trim();
  } catch {
    return '';
  }
}).find((p) => p !== '');
if (!chromium) {
  console.error('no chromium (apt-get install chromium; scripts/install_deps.sh --web)');
  process.exit(77);
}

const types = { '.html': 'text/html', '.js': 'text/javascript', '.mjs': 'text/javascript', '.wasm': 'application/wasm',
                '.glsl': 'text/plain', '.css': 'text/css', '.json': 'application/json' };
let onResult = null;
let onPageError = null;
const server = http.createServer((request, response) => {
  const url = new URL(request.url, 'http://127.0.0.1');
  if (process.env.ATMO_WEB_TEST_VERBOSE) console.log(`${request.method} ${request.url}`);
  if (request.method === 'POST' && url.pathname === '/result') {
    const chunks = [];
    request.on('data', (c) => chunks.push(c));
    request.on('end', () => {
      response.end('ok');
      const body = Buffer.concat(chunks);
      onResult?.({ width: Number(request.headers['x-width']), height: Number(request.headers['x-height']),
                   timings: JSON.parse(request.headers['x-timings']),
                   pixels: new Float32Array(body.buffer, body.byteOffset, body.byteLength / 4) });
    });
    return;
  }
  if (request.method === 'POST' && url.pathname === '/error') {
    let text = '';
    request.on('data', (c) => { text += c; });
    request.on('end', () => {
      response.end('ok');
      onPageError?.(text);
    });
    return;
  }
  const file = path.join(siteDir, path.normalize(url.pathname).replace(/^(\.\.[/\\])+/, ''));
  if (!file.startsWith(path.resolve(siteDir)) || !fs.existsSync(file) || fs.statSync(file).isDirectory()) {
    response.statusCode = 404;
    response.end();
    return;
  }
  response.setHeader('content-type', types[path.extname(file)] ?? 'application/octet-stream');
  fs.createReadStream(file).pipe(response);
});
await new Promise((resolve) => server.listen(0, '127.0.0.1', resolve));
const port = server.address().port;
const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'atmo-web-page-'));

// The page's pixels for one view: the result of ?test=WxH#PARAMS.
async function pageFrame(params, width, height) {
  const url = `http://127.0.0.1:${port}/index.html?test=${width}x${height}#${new URLSearchParams(params)}`;
  const browser = spawn(chromium, ['--headless=new', '--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
                                   '--no-first-run', '--disable-extensions', `--user-data-dir=${tmp}/profile`,
                                   '--enable-logging=stderr', '--v=0', `--window-size=${width},${height}`, url],
                        { stdio: ['ignore', 'ignore', 'pipe'] });
  let log = '';
  browser.stderr.on('data', (d) => { log += d; });
  try {
    return await new Promise((resolve, reject) => {
      const timer = setTimeout(() => reject(new Error(`no result from the page in time; browser log:\n${log.slice(-4000)}`)), Number(process.env.ATMO_WEB_TEST_TIMEOUT_MS ?? 240000));
      onResult = (result) => {
        clearTimeout(timer);
        resolve(result);
      };
      onPageError = (text) => {
        clearTimeout(timer);
        reject(new Error(`the page failed: ${text}`));
      };
      browser.on('exit', (code) => reject(new Error(`chromium exited (${code}) before the page answered:\n${log.slice(-4000)}`)));
    });
  } finally {
    onResult = null;
    onPageError = null;
    browser.kill('SIGKILL');
  }
}

function nativeFrame(params, width, height) {
  const exr = path.join(tmp, 'native.exr');
  execFileSync(cli, ['render', '--model', params.model, '--preset', params.preset, '--width', String(width),
                     '--height', String(height), '--fov', String(params.fov), '--yaw', String(params.yaw),
                     '--pitch', String(params.pitch), '--sun-elevation', String(params.sunElevation),
                     '--sun-azimuth', String(params.sunAzimuth), '--altitude', String(params.altitude),
                     '--no-night-glow', '--no-stars', '--no-moon', '--exr', exr, '--no-png'], { stdio: 'ignore' });
  return readExr(exr);
}

function percentile(sorted, p) {
  return sorted[Math.min(sorted.length - 1, Math.floor(p * sorted.length))];
}

let failures = 0;
const width = 320;
const height = 180;
const cases = [
  { params: { model: 'hillaire', preset: 'earth', sunElevation: 12, sunAzimuth: 180, yaw: 160, pitch: 8, fov: 90, altitude: 0 },
    median: 3e-4, p99: 3e-3, sunEnergy: 0.02 },
  { params: { model: 'source4d', preset: 'earth', sunElevation: 4, sunAzimuth: 250, yaw: 230, pitch: 5, fov: 100, altitude: 300 },
    median: 2e-3, p99: 2e-2, sunEnergy: 0.02 },
];
for (const c of cases) {
  const page = await pageFrame(c.params, width, height);
  const native = nativeFrame(c.params, width, height);
  const radians = Math.PI / 180;
  const e = c.params.sunElevation * radians;
  const a = c.params.sunAzimuth * radians;
  const sun = [Math.cos(e) * Math.sin(a), Math.cos(e) * Math.cos(a), Math.sin(e)];
  // Pixel directions of atmo's perspective camera, to set the sun's pixels apart.
  const yaw = c.params.yaw * radians;
  const pitch = c.params.pitch * radians;
  const forward = [Math.cos(pitch) * Math.sin(yaw), Math.cos(pitch) * Math.cos(yaw), Math.sin(pitch)];
  const right = [Math.cos(yaw), -Math.sin(yaw), 0];
  const up = [right[1] * forward[2] - right[2] * forward[1], right[2] * forward[0] - right[0] * forward[2],
              right[0] * forward[1] - right[1] * forward[0]];
  const t = Math.tan(0.5 * c.params.fov * radians);
  const differences = [];
  let pageSun = 0;
  let nativeSun = 0;
  for (let y = 0; y < height; ++y) {
    for (let x = 0; x < width; ++x) {
      const u = (2 * (x + 0.5) / width - 1) * t;
      const v = (1 - 2 * (y + 0.5) / height) * t * height / width;
      const d = forward.map((f, k) => f + u * right[k] + v * up[k]);
      const cosine = d.reduce((s, dk, k) => s + dk * sun[k], 0) / Math.hypot(...d);
      const i = y * width + x;
      const n = ['R', 'G', 'B'].map((ch) => native.channels[ch][i]);
      const p = [0, 1, 2].map((k) => page.pixels[4 * i + k]);
      if (cosine > Math.cos(1 * radians)) {
        if (process.env.ATMO_WEB_TEST_VERBOSE && (p[1] > 1e5 || n[1] > 1e5)) console.log(`sun ${x},${y}: page ${p[1]} native ${n[1]}`);
        pageSun += p[1];
        nativeSun += n[1];
        continue;
      }
      for (let k = 0; k < 3; ++k) {
        const difference = Math.abs(p[k] - n[k]) / Math.max(Math.abs(n[k]), 1e-6);
        if (process.env.ATMO_WEB_TEST_VERBOSE && difference > 0.01) console.log(`pixel ${x},${y}[${k}]: page ${p[k]} native ${n[k]}`);
        differences.push(difference);
      }
    }
  }
  differences.sort((x, y) => x - y);
  const median = percentile(differences, 0.5);
  const p99 = percentile(differences, 0.99);
  const largest = differences[differences.length - 1];
  const offByOnePercent = differences.filter((d) => d > 0.01).length / differences.length;
  const sunRatio = nativeSun > 0 ? pageSun / nativeSun : NaN;
  const label = `${c.params.model} sun ${c.params.sunElevation} deg`;
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
  if (Number.isFinite(c.sunEnergy) && !(Math.abs(sunRatio - 1) <= c.sunEnergy)) fail(`sun energy ratio ${sunRatio}`);
}
server.close();
fs.rmSync(tmp, { recursive: true, force: true });
if (failures > 0) process.exit(1);
console.log('all checks passed');
