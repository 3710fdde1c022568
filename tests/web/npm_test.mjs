// The npm package atmo-sky in a real three.js page (ctest web_npm; docs/web.md):
//
//   node tests/web/npm_test.mjs PACKAGE_DIR THREE_DIR EXAMPLE_DIR ATMO_CLI
//
// `npm pack` makes the package's tarball, `npm install --offline` installs it into a fresh
// project next to three (THREE_DIR, the three.js the other tests use), and headless Chromium runs
// the package's three.js example (web/examples/three) in its test mode:
//   1. the sky alone (AtmoSky as the background, no tone mapping, a float target) must equal
//      `atmo render` of the same view within the demo page's tolerances (median relative
//      difference under 3e-4, 99th percentile under 3e-3, at most 1 % of values off by more than
//      1 %, the sun disc's energy within 2 %): the adapter's directions, frame and units are
//      three's, and a turned or mirrored sky fails at once;
//   2. a white Lambertian sphere lit by atmoEnvironment alone shows, at its top, E_h / pi where E_h
//      is the horizontal illuminance of the same cube map, within 12 % (three's PMREM
//      approximates the cosine lobe from its roughest level, and its GGX term at roughness 1 adds a
//      few per cent): the environment is in cd/m^2 and environmentIntensity undoes its scaling.
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';

import { compareFrames, findChromium, nativeRender, percentile, runChromium, startServer } from './browser.mjs';
import { readExr } from './exr.mjs';

const [packageDir, threeDir, exampleDir, cli] = process.argv.slice(2);
if (!packageDir || !threeDir || !exampleDir || !cli) {
  console.error('usage: node tests/web/npm_test.mjs PACKAGE_DIR THREE_DIR EXAMPLE_DIR ATMO_CLI');
  process.exit(2);
}
const chromium = findChromium();
const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'atmo-web-npm-'));
const site = path.join(tmp, 'site');
fs.mkdirSync(site);

// npm pack, then npm install of the tarball, as a user of the package would.
const tarball = execFileSync('npm', ['pack', '--silent', '--pack-destination', tmp], { cwd: packageDir, encoding: 'utf8' })
  .trim().split('\n').pop();
const tarballBytes = fs.statSync(path.join(tmp, tarball)).size;
fs.writeFileSync(path.join(site, 'package.json'), JSON.stringify({ name: 'atmo-sky-example', private: true }));
execFileSync('npm', ['install', '--offline', '--no-audit', '--no-fund', '--silent', path.join(tmp, tarball)],
             { cwd: site, stdio: 'inherit' });
fs.symlinkSync(path.resolve(threeDir), path.join(site, 'node_modules', 'three'));
for (const file of fs.readdirSync(exampleDir)) fs.copyFileSync(path.join(exampleDir, file), path.join(site, file));
console.log(`npm pack: ${tarball}, ${(tarballBytes / 1024).toFixed(0)} KiB; installed with npm install --offline`);

let failures = 0;
const fail = (what) => {
  console.error(`FAIL: ${what}`);
  failures += 1;
};
let waiting = null;
const server = await startServer(site, (name, headers, body) => {
  if (!waiting) return;
  if (name === 'result') {
    waiting.frame = new Float32Array(body.buffer.slice(body.byteOffset, body.byteOffset + body.byteLength));
  } else if (name === 'sphere') {
    waiting.resolve({ frame: waiting.frame, sphere: JSON.parse(body.toString()) });
  } else if (name === 'error') {
    waiting.reject(new Error(`the example failed: ${body}`));
  }
});

const width = 320;
const height = 180;
const params = { model: 'hillaire', preset: 'earth', sunElevation: 20, sunAzimuth: 135, yaw: 120, pitch: 12, fov: 90,
                 altitude: 0 };
const url = `http://127.0.0.1:${server.port}/index.html?test=${width}x${height}#${new URLSearchParams(params)}`;
const { frame, sphere } = await runChromium(chromium, url, new Promise((resolve, reject) => {
  waiting = { resolve, reject, frame: null };
}));
server.close();

const exr = path.join(tmp, 'native.exr');
nativeRender(cli, params, width, height, exr);
const { differences, pageSun, nativeSun } = compareFrames(params, width, height, frame, readExr(exr));
const median = percentile(differences, 0.5);
const p99 = percentile(differences, 0.99);
const offByOnePercent = differences.filter((d) => d > 0.01).length / differences.length;
const sunRatio = pageSun / nativeSun;
console.log(`three.js AtmoSky against atmo render: median ${median.toExponential(2)}, p99 ${p99.toExponential(2)}, ` +
            `${(100 * offByOnePercent).toFixed(2)} % off by more than 1 %, sun disc energy ${sunRatio.toFixed(4)}`);
if (!(median <= 3e-4)) fail(`median ${median}`);
if (!(p99 <= 3e-3)) fail(`p99 ${p99}`);
if (!(offByOnePercent <= 0.01)) fail(`${100 * offByOnePercent} % off by more than 1 %`);
if (!(Math.abs(sunRatio - 1) <= 0.02)) fail(`sun energy ratio ${sunRatio}`);

const expected = sphere.illuminance / Math.PI;
const ratio = sphere.luminance / expected;
console.log(`three.js atmoEnvironment: a white diffuse sphere's top ${sphere.luminance.toFixed(0)} cd/m^2, ` +
            `E_h / pi of the cube map ${expected.toFixed(0)} cd/m^2 (E_h ${sphere.illuminance.toFixed(0)} lx): ratio ${ratio.toFixed(4)}`);
if (!(Math.abs(ratio - 1) <= 0.12)) fail(`sphere/expected ${ratio}`);

fs.rmSync(tmp, { recursive: true, force: true });
if (failures > 0) process.exit(1);
console.log('all checks passed');
