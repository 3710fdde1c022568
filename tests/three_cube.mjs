// Reads the six Radiance HDR faces of `atmo render --camera cubemap --target three --hdr-faces NAME`
// with three.js's own HDRLoader (what its HDRCubeTextureLoader runs on each face) and finds where
// three looks up a world direction in a CubeTexture, for tests/engine_target_test.cc. Prints JSON:
// the face size, the sun's texel (face, column, row of the loaded data, at the brightest texel's
// luminance-weighted centroid within its face) and where three samples the given direction.
//   node three_cube.mjs NAME X Y Z      (NODE_PATH: where three is installed; X, Y, Z in three's world)
//
// three samples a CubeTexture that is not a render target along diag(-1, 1, 1) d (the matrix _m of
// WebGLBackground.js and WebGLMaterials.js, checked below in three's source); the sampled direction
// then picks a face and (s, t) by the OpenGL rule (OpenGL 4.6, table 8.19), and a CubeTexture's
// images are uploaded with flipY false, so t = 0 is row 0 of the loaded data.
import { existsSync, readFileSync } from 'node:fs';
import { pathToFileURL } from 'node:url';
import path from 'node:path';

function threeFile(file) {
  for (const root of (process.env.NODE_PATH || '').split(path.delimiter).filter(Boolean)) {
    const full = path.join(root, 'three', file);
    if (existsSync(full)) return full;
  }
  throw new Error('three is not installed in NODE_PATH');
}
const THREE = await import(pathToFileURL(threeFile('build/three.module.js')).href);
const { HDRLoader } = await import(pathToFileURL(threeFile('examples/jsm/loaders/HDRLoader.js')).href);

// The flip, as three's source has it.
for (const file of ['src/renderers/webgl/WebGLBackground.js', 'src/renderers/webgl/WebGLMaterials.js']) {
  const source = readFileSync(threeFile(file), 'utf8').replace(/\s+/g, ' ');
  if (!source.includes('_m.set( - 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0 )') ||
      !source.includes('isRenderTargetTexture === false')) {
    throw new Error(file + ' no longer flips x for cube textures that are not render targets');
  }
}
const flipY = new THREE.CubeTexture().flipY;

const [name, x, y, z] = [process.argv[2], ...process.argv.slice(3, 6).map(Number)];
const loader = new HDRLoader().setDataType(THREE.FloatType);
const faces = ['px', 'nx', 'py', 'ny', 'pz', 'nz'].map((f) => {
  const bytes = readFileSync(`${name}_${f}.hdr`);
  return loader.parse(bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength));
});
const n = faces[0].width;

// The brightest texel, then the centroid of its face's texels above half of it.
let best = { value: -1, face: -1 };
faces.forEach((f, k) => {
  for (let i = 0; i < n * n; ++i) {
    const l = 0.2126 * f.data[4 * i] + 0.7152 * f.data[4 * i + 1] + 0.0722 * f.data[4 * i + 2];
    if (l > best.value) best = { value: l, face: k };
  }
});
let sum = 0, sc = 0, sr = 0;
const data = faces[best.face].data;
for (let row = 0; row < n; ++row) {
  for (let col = 0; col < n; ++col) {
    const i = row * n + col;
    const l = 0.2126 * data[4 * i] + 0.7152 * data[4 * i + 1] + 0.0722 * data[4 * i + 2];
    if (l > 0.5 * best.value) { sum += l; sc += l * (col + 0.5); sr += l * (row + 0.5); }
  }
}

// Where three samples the direction: diag(-1, 1, 1), then OpenGL's face selection.
const [rx, ry, rz] = [-x, y, z];
const ax = Math.abs(rx), ay = Math.abs(ry), az = Math.abs(rz);
let face, s, t, ma;
if (ax >= ay && ax >= az) { face = rx > 0 ? 0 : 1; ma = ax; s = rx > 0 ? -rz : rz; t = -ry; }
else if (ay >= az) { face = ry > 0 ? 2 : 3; ma = ay; s = rx; t = ry > 0 ? rz : -rz; }
else { face = rz > 0 ? 4 : 5; ma = az; s = rz > 0 ? rx : -rx; t = -ry; }
s = (s / ma + 1) / 2;
t = (t / ma + 1) / 2;
console.log(JSON.stringify({
  size: n, flipY, sunFace: best.face, sunColumn: sc / sum, sunRow: sr / sum,
  expectedFace: face, expectedColumn: s * n, expectedRow: t * n,
}));
