// The WebAssembly build's JavaScript API against the native library (ctest web_api; docs/web.md).
//
//   node tests/web/api_test.mjs BUILD_WEB_DIR ATMO_CLI
//
// For each model the same points are sampled by atmo.wasm (Model.sample) and by the native
// `atmo sample --grid` (the same C++ compiled by g++ for x86-64); every radiance and transmittance
// must agree to within 2e-6 relative (plus 1e-12 absolute for values near 0): both evaluate the
// same float tables in double precision, and only the libm (Emscripten's musl against glibc) and
// the order of a few vectorised float sums differ. The CLI prints ten significant digits, which
// bounds what can be compared at 5e-10. Bad input must throw a JavaScript Error whose message is
// the library's one line, the same text the native code gives. Exits 1 on any failure and prints
// the measured differences and the table times.
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';

import { readExr } from './exr.mjs';

const [buildDir, cli] = process.argv.slice(2);
if (!buildDir || !cli) {
  console.error('usage: node tests/web/api_test.mjs BUILD_WEB_DIR ATMO_CLI');
  process.exit(2);
}
const { default: createAtmo } = await import(path.resolve(buildDir, 'atmo.mjs'));
const atmo = await createAtmo({ wasmBinary: fs.readFileSync(path.join(buildDir, 'atmo.wasm')) });

let failures = 0;
function check(condition, message) {
  if (!condition) {
    console.error(`FAIL: ${message}`);
    failures += 1;
  }
}

const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'atmo-web-api-'));
const points = [];
for (const altitude of [0, 1500, 25000]) {
  for (const sunZenith of [20, 75, 89, 94]) {
    for (const viewZenith of [0, 40, 80, 89.5, 91, 130]) {
      for (const azimuth of [0, 60, 180]) points.push([altitude, sunZenith, viewZenith, azimuth]);
    }
  }
}
const grid = path.join(tmp, 'grid.csv');
fs.writeFileSync(grid, 'altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg\n' + points.map((p) => p.join(',')).join('\n') + '\n');
const column = (i) => points.map((p) => p[i]);

// The native rows of `atmo sample`: per point (and wavelength) the radiance and transmittance.
function nativeSample(args, unit) {
  const csv = execFileSync(cli, ['sample', ...args, '--grid', grid, '--unit', unit], { encoding: 'utf8' });
  const lines = csv.trim().split('\n');
  const header = lines[0].split(',');
  const radiance = header.findIndex((h) => h === 'radiance' || h === 'luminance_cd_m2');
  const transmittance = header.findIndex((h) => h === 'transmittance' || h === 'luminous_transmittance');
  return lines.slice(1).map((line) => {
    const f = line.split(',');
    return [Number(f[radiance]), Number(f[transmittance])];
  });
}

const cases = [
  { model: 'hillaire', config: { preset: 'earth' }, args: ['--preset', 'earth'] },
  { model: 'source4d', config: { preset: 'earth' }, args: ['--preset', 'earth'] },
  { model: 'hillaire', config: { preset: 'earth', spectral: 8 }, args: ['--preset', 'earth', '--spectral', '8'] },
  { model: 'hillaire', config: { preset: 'us-standard', aod: 0.3 }, args: ['--preset', 'us-standard', '--aod', '0.3'] },
  { model: 'elek', config: { preset: 'atmosphere-plus' }, args: ['--preset', 'atmosphere-plus'] },
  { model: 'simple', config: { preset: 'simple' }, args: ['--preset', 'simple'] },
];
for (const c of cases) {
  const model = new atmo.Model(c.model, c.config);
  const label = `${c.model} ${JSON.stringify(c.config)}`;
  for (const unit of ['relative', 'luminance']) {
    const web = model.sample(column(0), column(1), column(2), column(3), unit);
    const native = nativeSample(['--model', c.model, ...c.args], unit);
    check(native.length === web.radiance.length, `${label} ${unit}: ${web.radiance.length} values, native ${native.length}`);
    let worst = 0;
    let worstAt = -1;
    for (let i = 0; i < native.length; ++i) {
      for (const [k, values] of [[0, web.radiance], [1, web.transmittance]]) {
        const a = values[i];
        const b = native[i][k];
        const difference = Math.abs(a - b) / (Math.abs(b) + 1e-12 / 2e-6);
        if (!(difference <= worst)) {
          worst = difference;
          worstAt = i;
        }
      }
    }
    check(worst <= 2e-6, `${label} ${unit}: relative difference ${worst.toExponential(2)} at row ${worstAt}`);
    console.log(`${label} ${unit}: ${native.length} values, largest relative difference to native ${worst.toExponential(2)}`);
  }
  console.log(`${label}: tables ${model.precomputeMs.toFixed(1)} ms (single thread)`);
  model.delete();
}

// Errors: a JavaScript Error carrying the library's one-line message.
function errorOf(f) {
  try {
    f();
  } catch (error) {
    return error;
  }
  return null;
}
function nativeError(args) {
  try {
    execFileSync(cli, args, { encoding: 'utf8', stdio: ['ignore', 'pipe', 'pipe'] });
  } catch (error) {
    return error.stderr.trim().replace(/^atmo: error: /, '');
  }
  return null;
}
const unknownPreset = errorOf(() => new atmo.Model('hillaire', { preset: 'no-such-preset' }));
check(unknownPreset instanceof Error, 'an unknown preset throws an Error');
const nativeUnknown = nativeError(['sample', '--preset', 'no-such-preset', '--grid', grid]);
check(unknownPreset && unknownPreset.message === nativeUnknown,
      `unknown preset: '${unknownPreset && unknownPreset.message}' against native '${nativeUnknown}'`);
const unknownModel = errorOf(() => new atmo.Model('no-such-model', {}));
check(unknownModel instanceof Error && /no-such-model/.test(unknownModel.message), `unknown model: ${unknownModel}`);
const badJson = errorOf(() => new atmo.Model('hillaire', { json: '{"ground_radius_m": -1}' }));
check(badJson instanceof Error && badJson.message.length > 0 && !badJson.message.includes('\n'), `bad JSON: ${badJson}`);
const model = new atmo.Model('hillaire', { preset: 'earth' });
for (const [what, f] of [
  ['NaN altitude', () => model.sample([NaN], [0], [0], [0], 'relative')],
  ['sun zenith 200', () => model.sample([0], [200], [0], [0], 'relative')],
  ['arrays of two lengths', () => model.sample([0, 0], [0], [0], [0], 'relative')],
  ['unknown unit', () => model.sample([0], [0], [0], [0], 'furlongs')],
  ['NaN sun elevation', () => model.renderFrame({ sunElevation: NaN })],
  ['an absurd resolution', () => model.renderFrame({ width: 1e6, height: 1e6 })],
  ['a non-numeric width', () => model.renderFrame({ width: 'wide' })],
  ['a sky view of odd height', () => model.skyView({ height: 7 })],
  ['a cube map of size 0', () => model.cubeMap({ size: 0 })],
]) {
  const error = errorOf(f);
  check(error instanceof Error && error.message.length > 0 && !error.message.includes('\n'), `${what}: ${error}`);
  if (error) console.log(`${what}: ${error.message}`);
}
// The module still works after the errors.
const after = model.sample([0], [30], [10], [0], 'luminance');
check(after.radiance[0] > 0 && Number.isFinite(after.radiance[0]), 'the module works after errors');
// This is the single-threaded module (atmo.wasm): its loops run on the calling thread alone.
check(atmo.threads() === 1, `atmo.threads() is ${atmo.threads()} in the single-threaded module`);

// A frame equals the native `atmo render` of the same view: both run RenderViewFolded.
const frame = model.renderFrame({ width: 64, height: 36, fov: 90, yaw: 150, pitch: 5, sunElevation: 12, sunAzimuth: 180 });
const exr = path.join(tmp, 'frame.exr');
execFileSync(cli, ['render', '--model', 'hillaire', '--preset', 'earth', '--width', '64', '--height', '36', '--fov', '90',
                   '--yaw', '150', '--pitch', '5', '--sun-elevation', '12', '--sun-azimuth', '180', '--no-night-glow',
                   '--no-stars', '--no-moon', '--exr', exr, '--no-png'], { stdio: 'ignore' });
const image = readExr(exr);
const nativePixels = new Float32Array(image.width * image.height * 3);
['R', 'G', 'B'].forEach((name, k) => image.channels[name].forEach((v, i) => { nativePixels[3 * i + k] = v; }));
check(nativePixels.length === frame.pixels.length, `frame: ${frame.pixels.length} floats, native ${nativePixels.length}`);
let worstPixel = 0;
for (let i = 0; i < nativePixels.length; ++i) {
  worstPixel = Math.max(worstPixel, Math.abs(frame.pixels[i] - nativePixels[i]) / (Math.abs(nativePixels[i]) + 1e-3));
}
check(worstPixel <= 2e-6, `frame: relative difference ${worstPixel.toExponential(2)}`);
console.log(`frame 64x36: largest relative difference to atmo render ${worstPixel.toExponential(2)}`);

fs.rmSync(tmp, { recursive: true, force: true });
if (failures > 0) {
  console.error(`${failures} check(s) failed`);
  process.exit(1);
}
console.log('all checks passed');
