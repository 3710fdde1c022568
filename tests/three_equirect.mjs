// Reads an equirect EXR with three.js's own EXRLoader and finds where three's own equirect lookup
// (the GLSL function equirectUv of its ShaderChunk, run here as JavaScript) puts a direction, for
// tests/engine_target_test.cc. Prints JSON: the image size, the sun's centroid in texture
// coordinates (u from the left, v from row 0 of the loaded data), where equirectUv puts the given
// direction, and the loaded texture's flipY.
//   node three_equirect.mjs FILE X Y Z      (NODE_PATH: where three is installed; X, Y, Z in three's world)
import { existsSync, readFileSync } from 'node:fs';
import { pathToFileURL } from 'node:url';
import path from 'node:path';

// three's ES modules, found through NODE_PATH explicitly (ES imports ignore NODE_PATH): the
// package's ES entry (its "import" export), so that THREE and the EXRLoader share one module.
async function importFromThree(file) {
  for (const root of (process.env.NODE_PATH || '').split(path.delimiter).filter(Boolean)) {
    const full = path.join(root, 'three', file);
    if (existsSync(full)) return import(pathToFileURL(full).href);
  }
  throw new Error('three is not installed in NODE_PATH');
}
const THREE = await importFromThree('build/three.module.js');
const { EXRLoader } = await importFromThree('examples/jsm/loaders/EXRLoader.js');

// three's equirectUv, taken from its shader source and run as JavaScript: the GLSL body with its
// types dropped and atan/asin/clamp mapped to Math. Throws when the source has a form not handled.
function equirectUvFromThree() {
  const source = THREE.ShaderChunk.common;
  const match = source.match(/vec2 equirectUv\(\s*in vec3 dir\s*\)\s*\{([\s\S]*?)\n\}/);
  if (!match) throw new Error('equirectUv not found in THREE.ShaderChunk.common');
  let body = match[1].replace(/\/\/.*$/gm, '');
  body = body.replace(/\bfloat\s+/g, 'const ')
             .replace(/\batan\(/g, 'Math.atan2(')
             .replace(/\basin\(/g, 'Math.asin(')
             .replace(/\bvec2\(\s*u\s*,\s*v\s*\)/g, '[u, v]')
             .replace(/\bRECIPROCAL_PI2\b/g, String(0.5 / Math.PI))
             .replace(/\bRECIPROCAL_PI\b/g, String(1.0 / Math.PI));
  if (/vec|float|\bin\b/.test(body)) throw new Error('equirectUv has a form this test does not run: ' + body);
  // eslint-disable-next-line no-new-func
  return new Function('dir', 'clamp', body);
}
const clamp = (x, lo, hi) => Math.min(Math.max(x, lo), hi);

const [file, x, y, z] = [process.argv[2], ...process.argv.slice(3, 6).map(Number)];
const bytes = readFileSync(file);
const loader = new EXRLoader().setDataType(THREE.FloatType);
const data = loader.parse(bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength));
const { width, height } = data;
const stride = data.data.length / (width * height);

// The sun: the luminance-weighted centroid of the texels above half the brightest.
let brightest = 0;
const luminance = (i) => 0.2126 * data.data[i * stride] + 0.7152 * data.data[i * stride + 1] +
                         0.0722 * data.data[i * stride + 2];
for (let i = 0; i < width * height; ++i) brightest = Math.max(brightest, luminance(i));
let sum = 0, su = 0, sv = 0;
for (let row = 0; row < height; ++row) {
  for (let col = 0; col < width; ++col) {
    const l = luminance(row * width + col);
    if (l > 0.5 * brightest) { sum += l; su += l * (col + 0.5) / width; sv += l * (row + 0.5) / height; }
  }
}
const norm = Math.hypot(x, y, z);
const [u, v] = equirectUvFromThree()({ x: x / norm, y: y / norm, z: z / norm }, clamp);
const texture = new THREE.DataTexture();  // what EXRLoader's load() would hand a scene: flipY as set
console.log(JSON.stringify({
  width, height, sunU: su / sum, sunV: sv / sum, expectedU: u, expectedV: v,
  loaderFlipY: data.flipY === undefined ? texture.flipY : data.flipY,
}));
