// The demo page (docs/web.md): atmo.wasm in a worker builds the model and its sky-view table,
// WebGL2 draws every frame from the table (renderer.js). Drag to look around, the wheel to change
// the field of view; the panel sets the model, the preset, the haze, the sun (or date and place),
// the altitude up to orbit and the exposure. The URL's hash holds every parameter (share link).
//
// Test hook (tests/web/page_test.mjs): with ?test=WIDTHxHEIGHT the page draws the hash's view once
// into a float target and POSTs the linear cd/m^2 pixels to /result, with its timings, then the
// canvas as displayed to /screenshot.
import { encodeExr } from './exr.js';
import { SkyRenderer } from './renderer.js';

const defaults = {
  model: 'hillaire', preset: 'earth', aod: '', sunElevation: 10, sunAzimuth: 180, altitude: 0, ev: '', fov: 90,
  yaw: 180, pitch: 10, camera: 'perspective', date: '', latitude: 48.85, longitude: 2.35, error: '',
};
const state = { ...defaults };
for (const [key, value] of new URLSearchParams(location.hash.slice(1))) {
  if (key in defaults) state[key] = typeof defaults[key] === 'number' ? Number(value) : value;
}

const $ = (id) => document.getElementById(id);
const canvas = $('sky');
const statusLines = {};
function status(key, text) {
  statusLines[key] = text;
  $('status').textContent = Object.values(statusLines).join('\n');
}
function showError(message) {
  $('error').textContent = message ?? '';
}

// The worker's requests as promises.
const worker = new Worker('worker.js', { type: 'module' });
let nextId = 0;
const pending = new Map();
worker.onmessage = (event) => {
  const { id, ok, value, error } = event.data;
  const p = pending.get(id);
  pending.delete(id);
  if (ok) p.resolve(value);
  else p.reject(new Error(error));
};
function ask(type, message = {}) {
  const id = nextId++;
  return new Promise((resolve, reject) => {
    pending.set(id, { resolve, reject });
    worker.postMessage({ id, type, ...message });
  });
}

// Altitude slider: 0..1 maps to 0..400 km, the square for fine steps near the ground.
const altitudeFromSlider = (u) => 400000 * u * u;
const sliderFromAltitude = (a) => Math.sqrt(Math.max(a, 0) / 400000);

const glsl = await (await fetch('atmo_web.glsl')).text();
const renderer = new SkyRenderer(canvas, glsl);
const test = new URLSearchParams(location.search).get('test');

let modelInfo = null;
let table = null;
let autoEv = 12;
let building = null;  // the latest requested model key
let lastModelRoundTripMs = 0;  // the latest model's request to its answer (tables and sky view included)
let frameCount = 0;
let frameClock = performance.now();

function modelConfig() {
  const config = { preset: state.preset };
  if (state.aod !== '') config.aod = Number(state.aod);
  return config;
}

async function rebuildModel(interactive = false) {
  const key = JSON.stringify([state.model, modelConfig()]);
  building = key;
  status('model', `building ${state.model} ...`);
  const start = performance.now();
  try {
    const info = await ask('model', { name: state.model, config: modelConfig(), skyView: skyViewRequest() });
    if (building !== key) return;  // a newer request superseded this one
    lastModelRoundTripMs = performance.now() - start;
    modelInfo = info;
    if (state.error === '1') {
      // Where there are reference samples the map needs the worker, and is drawn when it comes;
      // elsewhere its legend says so at once, and the new sky's frame below is the only one drawn.
      if (referenceApplies()) setTimeout(showErrorMap, 0);
      else clearErrorMap();
    }
    status('model', `${info.name} (${info.preset}): tables ${info.precomputeMs.toFixed(0)} ms on ` +
                    `${info.threads} thread${info.threads > 1 ? 's' : ''} ` +
                    `(${(performance.now() - start).toFixed(0)} ms to the page)`);
    showError(null);
    ++skyViewSerial;
    applySkyView(info.table, start, interactive);
  } catch (error) {
    showError(error.message);
    status('model', `${state.model}: failed`);
  }
}

function skyViewRequest() {
  return { altitude: state.altitude, sunElevation: state.sunElevation };
}

function applySkyView(t, start, interactive) {
  table = t;
  autoEv = t.autoEv100;
  renderer.setSkyView(t);
  status('view', `sky view ${t.width}x${t.height}: ${t.ms.toFixed(1)} ms in wasm, ` +
                 `${(performance.now() - start).toFixed(1)} ms to the GPU`);
  if (interactive) {
    // A parameter change: the new sky at once (the frame is shown at the next composite), not an
    // animation frame later.
    requestDraw(true);
    drawFrame();
  } else {
    requestDraw();
  }
}

let skyViewSerial = 0;
async function refreshSkyView(interactive = false) {
  if (!modelInfo) return;
  const serial = ++skyViewSerial;
  const start = performance.now();
  try {
    const t = await ask('skyView', { request: skyViewRequest() });
    if (serial !== skyViewSerial) return;
    showError(null);
    applySkyView(t, start, interactive);
  } catch (error) {
    showError(error.message);
  }
}

function view() {
  const ev = state.ev === '' ? autoEv : Number(state.ev);
  return { camera: state.camera, yaw: state.yaw, pitch: state.pitch, fov: state.fov, sunElevation: state.sunElevation,
           sunAzimuth: state.sunAzimuth, exposure: 1 / (1.2 * 2 ** ev) };
}

// Dynamic resolution: while the view moves, the drawing buffer shrinks until a frame takes at
// most ~45 ms (a software WebGL such as SwiftShader fills ~7 million pixels a second on two cores,
// 138 ms for a flat 1280 x 720 frame); when the view rests, the next frame is drawn at full
// resolution. The canvas keeps its size on the page; the browser scales the buffer up.
let drawQueued = false;
let moving = false;
let movingScale = 1;
let lastFrameAt = 0;
let restTimer = null;
function requestDraw(interactive = false) {
  if (interactive) {
    moving = true;
    clearTimeout(restTimer);
    restTimer = setTimeout(() => {
      moving = false;
      requestDraw();
    }, 200);
  }
  if (drawQueued) return;
  drawQueued = true;
  requestAnimationFrame(() => {
    if (drawQueued) drawFrame();
  });
}

// Draws now (at the moving resolution while the view moves).
function drawFrame() {
  drawQueued = false;
  const now = performance.now();
  if (moving && lastFrameAt > 0) {
    const interval = now - lastFrameAt;
    if (interval > 55) movingScale = Math.max(0.25, movingScale * 0.8);
    else if (interval < 35) movingScale = Math.min(1, movingScale * 1.1);
  }
  lastFrameAt = now;
  const scale = Math.min(window.devicePixelRatio || 1, 2) * (moving ? movingScale : 1);
  const width = Math.max(1, Math.round(canvas.clientWidth * scale));
  const height = Math.max(1, Math.round(canvas.clientHeight * scale));
  if (canvas.width !== width || canvas.height !== height) {
    canvas.width = width;
    canvas.height = height;
  }
  renderer.draw(view(), width, height);
  ++frameCount;
  if (now - frameClock > 1000) {
    status('frames', `${canvas.clientWidth}x${canvas.clientHeight}: ${(1000 * frameCount / (now - frameClock)).toFixed(0)} ` +
                     `frames/s${moving ? ` while moving (drawn at ${width}x${height})` : ''}`);
    frameCount = 0;
    frameClock = now;
  }
}

// Looks around for `frames` frames as a drag would (the test's measure of interactivity): returns
// the frames per second and the last drawing buffer's size.
async function lookAround(frames) {
  const start = performance.now();
  for (let i = 0; i < frames; ++i) {
    state.yaw = (state.yaw + 1) % 360;
    requestDraw(true);
    await new Promise((resolve) => requestAnimationFrame(() => requestAnimationFrame(resolve)));
  }
  const fps = (1000 * frames) / (performance.now() - start);
  return { fps, width: canvas.width, height: canvas.height };
}

function saveHash() {
  const params = new URLSearchParams();
  for (const key of Object.keys(defaults)) {
    if (String(state[key]) !== String(defaults[key])) params.set(key, String(state[key]));
  }
  history.replaceState(null, '', `#${params}`);
}

// The view direction of a canvas point (CSS pixels), in the local frame x east, y north, z up:
// atmo's perspective camera (src/atmo/shared/camera.glsl, GetCameraRayDirection).
function directionAt(x, y) {
  const radians = Math.PI / 180;
  const w = canvas.clientWidth;
  const h = canvas.clientHeight;
  const yaw = state.yaw * radians;
  const pitch = state.pitch * radians;
  const forward = [Math.cos(pitch) * Math.sin(yaw), Math.cos(pitch) * Math.cos(yaw), Math.sin(pitch)];
  const right = [Math.cos(yaw), -Math.sin(yaw), 0];
  const up = [right[1] * forward[2] - right[2] * forward[1], right[2] * forward[0] - right[0] * forward[2],
              right[0] * forward[1] - right[1] * forward[0]];
  const t = Math.tan(0.5 * state.fov * radians);
  const u = (2 * x / w - 1) * t;
  const v = (1 - 2 * y / h) * t * h / w;
  const d = forward.map((f, k) => f + u * right[k] + v * up[k]);
  const n = Math.hypot(...d);
  return d.map((c) => c / n);
}

// The panel.
const atmoNames = { models: ['hillaire', 'source4d', 'elek', 'simple'] };
function fillSelect(select, names, value) {
  select.replaceChildren(...names.map((n) => new Option(n, n, false, n === value)));
}
fillSelect($('model'), atmoNames.models, state.model);
fillSelect($('preset'), ['earth', 'earth-spectral', 'us-standard', 'tropical', 'midlatitude-summer', 'midlatitude-winter',
                         'subarctic-summer', 'subarctic-winter', 'atmosphere-plus', 'simple'], state.preset);
const sliders = {
  sunElevation: { get: () => state.sunElevation, set: (v) => { state.sunElevation = v; }, text: (v) => `${v.toFixed(1)}°`, sky: true },
  sunAzimuth: { get: () => state.sunAzimuth, set: (v) => { state.sunAzimuth = v; }, text: (v) => `${v.toFixed(0)}°` },
  altitude: { get: () => sliderFromAltitude(state.altitude), set: (v) => { state.altitude = altitudeFromSlider(v); },
              text: () => (state.altitude < 10000 ? `${state.altitude.toFixed(0)} m` : `${(state.altitude / 1000).toFixed(1)} km`),
              sky: true },
  ev: { get: () => (state.ev === '' ? autoEv : Number(state.ev)), set: (v) => { state.ev = String(v); },
        text: (v) => (state.ev === '' ? `auto ${v.toFixed(1)}` : v.toFixed(1)) },
  fov: { get: () => state.fov, set: (v) => { state.fov = v; }, text: (v) => `${v.toFixed(0)}°` },
};
for (const [id, s] of Object.entries(sliders)) {
  const input = $(id);
  const output = input.nextElementSibling;
  input.value = s.get();
  output.textContent = s.text(Number(input.value));
  input.addEventListener('input', () => {
    s.set(Number(input.value));
    output.textContent = s.text(Number(input.value));
    saveHash();
    if (s.sky) refreshSkyView(true);
    else requestDraw(true);
  });
  input.addEventListener('dblclick', () => {  // double click: back to automatic exposure
    if (id === 'ev') {
      state.ev = '';
      saveHash();
      requestDraw();
    }
  });
}
$('aod').value = state.aod === '' ? 0.1 : state.aod;
$('aod-value').textContent = state.aod === '' ? 'preset' : Number(state.aod).toFixed(2);
$('aod').addEventListener('change', () => {
  state.aod = $('aod').value;
  $('aod-value').textContent = Number(state.aod).toFixed(2);
  saveHash();
  rebuildModel(true);
});
for (const id of ['model', 'preset']) {
  $(id).addEventListener('change', () => {
    state[id] = $(id).value;
    saveHash();
    rebuildModel();
  });
}
$('date').value = state.date;
$('latitude').value = state.latitude;
$('longitude').value = state.longitude;
$('useDate').addEventListener('click', async () => {
  try {
    state.date = $('date').value || new Date().toISOString().slice(0, 19) + 'Z';
    state.latitude = Number($('latitude').value);
    state.longitude = Number($('longitude').value);
    const sun = await ask('sun', { date: state.date, latitude: state.latitude, longitude: state.longitude });
    state.sunElevation = Math.round(sun.elevation * 100) / 100;
    state.sunAzimuth = Math.round(sun.azimuth * 100) / 100;
    for (const id of ['sunElevation', 'sunAzimuth']) {
      $(id).value = state[id];
      $(id).nextElementSibling.textContent = sliders[id].text(state[id]);
    }
    $('date').value = state.date;
    saveHash();
    showError(null);
    refreshSkyView();
  } catch (error) {
    showError(error.message);
  }
});

function download(bytes, name, type) {
  const url = URL.createObjectURL(new Blob([bytes], { type }));
  const a = document.createElement('a');
  a.href = url;
  a.download = name;
  a.click();
  setTimeout(() => URL.revokeObjectURL(url), 10000);
}
$('exr').addEventListener('click', async () => {
  try {
    const w = Math.min(canvas.width, 1920);
    const h = Math.round(w * canvas.height / canvas.width);
    const frame = await ask('frame', { request: { width: w, height: h, fov: state.fov, yaw: state.yaw, pitch: state.pitch,
                                                  altitude: state.altitude, sunElevation: state.sunElevation,
                                                  sunAzimuth: state.sunAzimuth } });
    download(encodeExr(frame.width, frame.height, ['R', 'G', 'B'], frame.pixels,
                       { 'atmo:model': state.model, 'atmo:unit': 'cd/m^2 (linear sRGB)', 'atmo:view': location.hash }),
             'atmo-view.exr', 'image/x-exr');
  } catch (error) {
    showError(error.message);
  }
});
$('ktx2').addEventListener('click', async () => {
  try {
    const bytes = await ask('ktx2', { request: { size: 256, mips: true, altitude: state.altitude,
                                                 sunElevation: state.sunElevation, sunAzimuth: state.sunAzimuth } });
    download(bytes, 'atmo-environment.ktx2', 'image/ktx2');
  } catch (error) {
    showError(error.message);
  }
});
$('share').addEventListener('click', () => {
  saveHash();
  navigator.clipboard?.writeText(location.href);
  status('share', `link: ${location.href}`);
});

// Looking around and the probe.
let drag = null;
canvas.addEventListener('pointerdown', (e) => {
  drag = { x: e.clientX, y: e.clientY, yaw: state.yaw, pitch: state.pitch };
  canvas.setPointerCapture(e.pointerId);
});
canvas.addEventListener('pointerup', () => {
  drag = null;
  saveHash();
});
let probeSerial = 0;
canvas.addEventListener('pointermove', async (e) => {
  if (drag) {
    const degreesPerPixel = state.fov / canvas.clientWidth;
    state.yaw = (((drag.yaw - (e.clientX - drag.x) * degreesPerPixel) % 360) + 360) % 360;
    state.pitch = Math.max(-89, Math.min(89, drag.pitch + (e.clientY - drag.y) * degreesPerPixel));
    requestDraw(true);
    return;
  }
  if (!modelInfo) return;
  const d = directionAt(e.clientX, e.clientY);
  const viewZenith = Math.acos(Math.max(-1, Math.min(1, d[2]))) * 180 / Math.PI;
  const azimuth = ((Math.atan2(d[0], d[1]) * 180 / Math.PI - state.sunAzimuth) % 360 + 360) % 360;
  const serial = ++probeSerial;
  const probe = $('probe');
  try {
    const s = await ask('sample', { point: [state.altitude, 90 - state.sunElevation, viewZenith, azimuth] });
    if (serial !== probeSerial) return;
    probe.style.display = 'block';
    probe.style.left = `${e.clientX + 14}px`;
    probe.style.top = `${e.clientY + 10}px`;
    probe.textContent = `${s.luminance.toPrecision(4)} cd/m²  (elevation ${(90 - viewZenith).toFixed(1)}°)`;
  } catch (error) {
    probe.style.display = 'none';
  }
});
canvas.addEventListener('pointerleave', () => { $('probe').style.display = 'none'; });
canvas.addEventListener('wheel', (e) => {
  e.preventDefault();
  state.fov = Math.max(20, Math.min(150, state.fov * Math.exp(0.001 * e.deltaY)));
  $('fov').value = state.fov;
  $('fov').nextElementSibling.textContent = sliders.fov.text(state.fov);
  requestDraw(true);
}, { passive: false });
window.addEventListener('resize', requestDraw);

// The model's error against the reference (reference_earth.csv, scripts/make_web_reference.sh:
// atmo's path tracer on preset earth, on the ground, six sun elevations, the sky above the horizon).
const kErrorScale = 0.05;  // the colour scale's ends: -5 % and +5 %
const reference = await (async () => {
  const text = await (await fetch('reference_earth.csv')).text();
  const lines = text.trim().split('\n');
  const header = lines[0].split(',');
  const column = (name) => header.indexOf(name);
  const [sz, vz, az, lum, err] = ['sun_zenith_deg', 'view_zenith_deg', 'azimuth_deg', 'luminance_cd_m2', 'stderr'].map(column);
  return lines.slice(1).map((line) => {
    const f = line.split(',').map(Number);
    return { sunZenith: f[sz], viewZenith: f[vz], azimuth: f[az], luminance: f[lum], stderr: f[err] };
  });
})();
const referenceElevations = [...new Set(reference.map((r) => 90 - r.sunZenith))].sort((a, b) => a - b);

function colourBar() {
  // The diverging scale of the shader (the viewer's Diverging), encoded as the shader encodes it.
  const encode = (c) => c.map((v) => Math.round(255 * v ** (1 / 2.2)));
  const stops = [];
  for (let i = 0; i <= 20; ++i) {
    const t = i / 10 - 1;
    const end = t < 0 ? [0.05, 0.25, 0.85] : [0.85, 0.05, 0.05];
    const c = [0, 1, 2].map((k) => 1 + (end[k] - 1) * Math.abs(t));
    stops.push(`rgb(${encode(c).join(',')}) ${i * 5}%`);
  }
  $('colourBar').style.background = `linear-gradient(to right, ${stops.join(', ')})`;
  $('barLow').textContent = `${(-100 * kErrorScale).toFixed(0)} %`;
  $('barHigh').textContent = `+${(100 * kErrorScale).toFixed(0)} %`;
}

// Whether the shipped reference samples apply: preset earth with its own haze, on the ground.
function referenceApplies() {
  return state.preset === 'earth' && state.altitude <= 1 && state.aod === '';
}

// The error map's legend without a map, where the reference does not apply (no draw of its own).
function clearErrorMap() {
  renderer.setErrorMap(null);
  $('errorLegend').style.display = 'block';
  colourBar();
  $('errorStats').textContent = 'reference samples exist for preset earth (its own haze) on the ground only';
}

// Computes and shows the error map for the current model and sun (snapped to the nearest
// reference elevation); returns the statistics, or null where there is no reference.
async function showErrorMap() {
  if (state.error !== '1') {
    renderer.setErrorMap(null);
    $('errorLegend').style.display = 'none';
    requestDraw();
    return null;
  }
  if (!referenceApplies()) {
    clearErrorMap();
    requestDraw();
    return null;
  }
  $('errorLegend').style.display = 'block';
  colourBar();
  const nearest = referenceElevations.reduce((a, b) => (Math.abs(b - state.sunElevation) < Math.abs(a - state.sunElevation) ? b : a));
  if (nearest !== state.sunElevation) {
    state.sunElevation = nearest;
    $('sunElevation').value = nearest;
    $('sunElevation').nextElementSibling.textContent = sliders.sunElevation.text(nearest);
    saveHash();
    await refreshSkyView();
  }
  const rows = reference.filter((r) => Math.abs(90 - r.sunZenith - nearest) < 1e-9);
  const s = await ask('sampleMany', { altitude: rows.map(() => 0), sunZenith: rows.map((r) => r.sunZenith),
                                      viewZenith: rows.map((r) => r.viewZenith), azimuth: rows.map((r) => r.azimuth) });
  const errors = rows.map((r, i) => s.radiance[i] / r.luminance - 1);
  // Onto a regular grid (2-degree steps) by bilinear interpolation between the reference's rows
  // of zenith angle and columns of azimuth.
  const zeniths = [...new Set(rows.map((r) => r.viewZenith))].sort((a, b) => a - b);
  const azimuths = [...new Set(rows.map((r) => r.azimuth))].sort((a, b) => a - b);
  const at = new Map(rows.map((r, i) => [`${r.viewZenith},${r.azimuth}`, errors[i]]));
  const bracket = (list, v) => {
    let k = 0;
    while (k + 2 < list.length && list[k + 1] < v) ++k;
    const f = Math.min(1, Math.max(0, (v - list[k]) / (list[k + 1] - list[k])));
    return [k, f];
  };
  const width = 91;
  const height = 46;
  const values = new Float32Array(width * height);
  for (let y = 0; y < height; ++y) {
    const [zi, zf] = bracket(zeniths, 2 * y);
    for (let x = 0; x < width; ++x) {
      const [ai, af] = bracket(azimuths, 2 * x);
      const e = (z, a) => at.get(`${zeniths[z]},${azimuths[a]}`);
      values[y * width + x] = (1 - zf) * ((1 - af) * e(zi, ai) + af * e(zi, ai + 1)) +
                              zf * ((1 - af) * e(zi + 1, ai) + af * e(zi + 1, ai + 1));
    }
  }
  renderer.setErrorMap({ width, height, values }, kErrorScale);
  const absolute = errors.map(Math.abs).sort((a, b) => a - b);
  const noise = rows.map((r) => r.stderr / r.luminance).sort((a, b) => a - b);
  const stats = { sunElevation: nearest, points: rows.length, median: absolute[Math.floor(absolute.length / 2)],
                  p95: absolute[Math.floor(0.95 * (absolute.length - 1))], max: absolute[absolute.length - 1],
                  referenceNoise: noise[Math.floor(noise.length / 2)] };
  $('errorStats').textContent =
    `${state.model} against the reference, sun ${nearest}°, ${rows.length} directions: |error| median ` +
    `${(100 * stats.median).toFixed(2)} %, p95 ${(100 * stats.p95).toFixed(2)} %, largest ${(100 * stats.max).toFixed(2)} %; ` +
    `the reference's own noise ${(100 * stats.referenceNoise).toFixed(2)} % (median)`;
  requestDraw();
  return stats;
}
$('showError').checked = state.error === '1';
for (const id of ['sunElevation', 'altitude']) {
  $(id).addEventListener('change', () => { if (state.error === '1') showErrorMap(); });
}
$('showError').addEventListener('change', () => {
  state.error = $('showError').checked ? '1' : '';
  saveHash();
  showErrorMap();
});

await rebuildModel();
await showErrorMap();

if (test) {
  // One fixed view for the browser test: linear cd/m^2 read back from a float target.
  const [width, height] = test.split('x').map(Number);
  const start = performance.now();
  const errorStats = state.error === '1' ? await showErrorMap() : null;
  const pixels = renderer.readLinear(view(), width, height);
  const drawMs = performance.now() - start;
  const frameMs720p = renderer.timeFrames(view(), 1280, 720);
  // Looking around in the window (960 x 540 under the test), with dynamic resolution.
  const yaw = state.yaw;
  await lookAround(10);  // settle the scale
  const looking = await lookAround(30);
  state.yaw = yaw;
  // A parameter change as the panel's sun slider makes it: the worker makes the new table, the
  // GPU gets it, the next frame (at the resolution looking around settled on) is drawn; the time to that picture.
  const sunChange = [];
  for (let i = 0; i < 5; ++i) {
    const changeStart = performance.now();
    state.sunElevation += 0.5;
    await refreshSkyView(true);
    await new Promise((resolve) => requestAnimationFrame(() => setTimeout(resolve, 0)));
    renderer.gl.readPixels(0, 0, 1, 1, renderer.gl.RGBA, renderer.gl.UNSIGNED_BYTE, new Uint8Array(4));
    sunChange.push(performance.now() - changeStart);
  }
  state.sunElevation -= 2.5;
  await refreshSkyView();
  const sunChangeMs = sunChange.sort((a, b) => a - b)[2];  // the median
  // A haze change from a page at rest (the hand is on the panel: the rest timer has drawn the
  // full frame and the GPU has finished it): a new model (its tables), its table, the next frame.
  await new Promise((resolve) => setTimeout(resolve, 300));
  renderer.gl.readPixels(0, 0, 1, 1, renderer.gl.RGBA, renderer.gl.UNSIGNED_BYTE, new Uint8Array(4));
  const hazeStart = performance.now();
  state.aod = '0.2';
  await rebuildModel(true);
  await new Promise((resolve) => requestAnimationFrame(() => setTimeout(resolve, 0)));
  renderer.gl.readPixels(0, 0, 1, 1, renderer.gl.RGBA, renderer.gl.UNSIGNED_BYTE, new Uint8Array(4));
  const hazeChangeMs = performance.now() - hazeStart;
  const hazeModelMs = lastModelRoundTripMs;
  const hazeTablesMs = modelInfo.precomputeMs;
  const hazePasses = modelInfo.passes;
  state.aod = '';
  await rebuildModel();
  await fetch('/result', {
    method: 'POST',
    headers: { 'x-width': String(width), 'x-height': String(height),
               'x-timings': JSON.stringify({ tablesMs: modelInfo.precomputeMs, skyViewMs: table.ms, drawMs, frameMs720p,
                                             sunChangeMs, hazeChangeMs, hazeModelMs, hazeTablesMs, hazePasses,
                                             threads: modelInfo.threads, lookingAroundFps: looking.fps,
                                             lookingAroundBuffer: `${looking.width}x${looking.height}`, errorStats }) },
    body: pixels,
  });
  // And the page as the user sees it (the panel aside): the displayed canvas as PNG.
  moving = false;
  clearTimeout(restTimer);
  canvas.width = canvas.clientWidth;
  canvas.height = canvas.clientHeight;
  renderer.draw(view(), canvas.width, canvas.height);
  const png = await new Promise((resolve) => canvas.toBlob(resolve, 'image/png'));
  await fetch('/screenshot', { method: 'POST', body: png });
}
