// Headless Chromium for the web tests (page_test.mjs, npm_test.mjs): a static server on
// 127.0.0.1 (browsers refuse wasm from file://) that also takes the pages' POSTs, and a run of
// Chromium (Debian's, with SwiftShader's WebGL2) on one URL until the page has posted what the
// test waits for.
import { execFileSync, spawn } from 'node:child_process';
import fs from 'node:fs';
import http from 'node:http';
import os from 'node:os';
import path from 'node:path';

// The browser's path, or exit 77 (ctest's skip) without one.
export function findChromium() {
  for (const name of ['chromium', 'chromium-browser', 'google-chrome']) {
    try {
      const found = execFileSync('sh', ['-c', `command -v ${name}`], { encoding: 'utf8' }).trim();
      if (found) return found;
    } catch {
      // not this one
    }
  }
  console.error('no chromium (apt-get install chromium; scripts/install_deps.sh --web)');
  process.exit(77);
}

const kTypes = { '.html': 'text/html', '.js': 'text/javascript', '.mjs': 'text/javascript', '.wasm': 'application/wasm',
                 '.glsl': 'text/plain', '.css': 'text/css', '.json': 'application/json' };

// Serves `root` (symbolic links followed, nothing above root) on 127.0.0.1; a POST to /NAME
// calls posted(NAME, headers, body Buffer). A POST to /error is the page's uncaught error. With
// `isolated`, every answer carries COOP and COEP, which make the page cross-origin isolated (shared
// memory, hence the threaded module: docs/web.md).
export async function startServer(root, posted, { isolated = false } = {}) {
  const base = fs.realpathSync(root);
  const server = http.createServer((request, response) => {
    const url = new URL(request.url, 'http://127.0.0.1');
    if (process.env.ATMO_WEB_TEST_VERBOSE) console.log(`${request.method} ${request.url}`);
    if (request.method === 'POST') {
      const chunks = [];
      request.on('data', (c) => chunks.push(c));
      request.on('end', () => {
        response.end('ok');
        posted(url.pathname.slice(1), request.headers, Buffer.concat(chunks));
      });
      return;
    }
    const file = path.join(base, path.normalize(decodeURIComponent(url.pathname)).replace(/^(\.\.[/\\])+/, ''));
    let ok = false;
    try {
      ok = fs.statSync(file).isFile();
    } catch {
      ok = false;
    }
    if (!ok || !file.startsWith(base)) {
      response.statusCode = 404;
      response.end();
      return;
    }
    response.setHeader('content-type', kTypes[path.extname(file)] ?? 'application/octet-stream');
    response.setHeader('cache-control', 'no-store');
    if (isolated) {
      response.setHeader('cross-origin-opener-policy', 'same-origin');
      response.setHeader('cross-origin-embedder-policy', 'require-corp');
    }
    fs.createReadStream(file).pipe(response);
  });
  await new Promise((resolve) => server.listen(0, '127.0.0.1', resolve));
  return { port: server.address().port, close: () => server.close() };
}

// Opens `url` in headless Chromium and waits until `until()` resolves (the test's own promise,
// settled from its server's POSTs), at most ATMO_WEB_TEST_TIMEOUT_MS (240 s); `failed` is called
// to report the browser's exit. The browser is killed after.
export async function runChromium(chromium, url, until, { width = 960, height = 540 } = {}) {
  const profile = fs.mkdtempSync(path.join(os.tmpdir(), 'atmo-chromium-'));
  const browser = spawn(chromium, ['--headless=new', '--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
                                   '--no-first-run', '--disable-extensions', `--user-data-dir=${profile}`,
                                   '--enable-logging=stderr', '--v=0', `--window-size=${width},${height}`, url],
                        { stdio: ['ignore', 'ignore', 'pipe'] });
  let log = '';
  browser.stderr.on('data', (d) => { log += d; });
  const limit = Number(process.env.ATMO_WEB_TEST_TIMEOUT_MS ?? 240000);
  let timer;
  try {
    return await Promise.race([
      until,
      new Promise((_, reject) => {
        timer = setTimeout(() => reject(new Error(`no answer from the page in ${limit / 1000} s; browser log:\n${log.slice(-4000)}`)), limit);
      }),
      new Promise((_, reject) => {
        browser.on('exit', (code) => reject(new Error(`chromium exited (${code}) before the page answered:\n${log.slice(-4000)}`)));
      }),
    ]);
  } finally {
    clearTimeout(timer);
    // The page's console (WebGL and shader errors, warnings) where ATMO_WEB_TEST_VERBOSE is set.
    if (process.env.ATMO_WEB_TEST_VERBOSE) {
      for (const line of log.split('\n')) if (!/dbus|vkCreate|VulkanError|sandbox/.test(line)) console.log(line.slice(0, 2000));
    }
    browser.kill('SIGKILL');
    await new Promise((resolve) => setTimeout(resolve, 200));
    fs.rmSync(profile, { recursive: true, force: true });
  }
}

// atmo's perspective camera's pixel directions (src/atmo/shared/camera.glsl), local frame x east,
// y north, z up: a function of the pixel (x, y), rows from the top.
export function perspectiveRays(params, width, height) {
  const radians = Math.PI / 180;
  const yaw = params.yaw * radians;
  const pitch = params.pitch * radians;
  const forward = [Math.cos(pitch) * Math.sin(yaw), Math.cos(pitch) * Math.cos(yaw), Math.sin(pitch)];
  const right = [Math.cos(yaw), -Math.sin(yaw), 0];
  const up = [right[1] * forward[2] - right[2] * forward[1], right[2] * forward[0] - right[0] * forward[2],
              right[0] * forward[1] - right[1] * forward[0]];
  const t = Math.tan(0.5 * params.fov * radians);
  return (x, y) => {
    const u = (2 * (x + 0.5) / width - 1) * t;
    const v = (1 - 2 * (y + 0.5) / height) * t * height / width;
    const d = forward.map((f, k) => f + u * right[k] + v * up[k]);
    const n = Math.hypot(...d);
    return d.map((c) => c / n);
  };
}

// `atmo render` of the same view as linear sRGB cd/m^2 (readExr's channels).
export function nativeRender(cli, params, width, height, exr) {
  execFileSync(cli, ['render', '--model', params.model, '--preset', params.preset, '--width', String(width),
                     '--height', String(height), '--fov', String(params.fov), '--yaw', String(params.yaw),
                     '--pitch', String(params.pitch), '--sun-elevation', String(params.sunElevation),
                     '--sun-azimuth', String(params.sunAzimuth), '--altitude', String(params.altitude),
                     '--no-night-glow', '--no-stars', '--no-moon', '--exr', exr, '--no-png'], { stdio: 'ignore' });
}

// Relative differences of two RGBA/RGB frames away from the sun (1 degree around it), and the
// sun's summed G against the native's: {differences (sorted), pageSun, nativeSun}.
export function compareFrames(params, width, height, pagePixels, native) {
  const radians = Math.PI / 180;
  const e = params.sunElevation * radians;
  const a = params.sunAzimuth * radians;
  const sun = [Math.cos(e) * Math.sin(a), Math.cos(e) * Math.cos(a), Math.sin(e)];
  const ray = perspectiveRays(params, width, height);
  const differences = [];
  let pageSun = 0;
  let nativeSun = 0;
  for (let y = 0; y < height; ++y) {
    for (let x = 0; x < width; ++x) {
      const d = ray(x, y);
      const cosine = d[0] * sun[0] + d[1] * sun[1] + d[2] * sun[2];
      const i = y * width + x;
      const n = ['R', 'G', 'B'].map((ch) => native.channels[ch][i]);
      const p = [0, 1, 2].map((k) => pagePixels[4 * i + k]);
      if (cosine > Math.cos(1 * radians)) {
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
  differences.sort((u, v) => u - v);
  return { differences, pageSun, nativeSun };
}

export function percentile(sorted, p) {
  return sorted[Math.min(sorted.length - 1, Math.floor(p * sorted.length))];
}
