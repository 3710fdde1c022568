// atmo-sky: the atmo library compiled to WebAssembly (docs/web.md). loadAtmo() gives the module:
//   const atmo = await loadAtmo();
//   const model = new atmo.Model('hillaire', { preset: 'earth' });   // tables built here
//   const frame = model.renderFrame({ width: 640, height: 360, sunElevation: 10 });  // cd/m^2
//   model.delete();                                                   // Embind objects are freed by hand
// Every call checks its input and throws an Error with atmo's one-line message.
import createAtmo from './atmo.mjs';

export { exposureFromEv100, kSkyShading, skyUniformValues } from './sky_shading.js';

// Instantiates atmo.wasm (fetched next to this file unless options.wasmBinary holds its bytes).
export function loadAtmo(options = {}) {
  return createAtmo({ locateFile: (file) => new URL(file, import.meta.url).href, ...options });
}

// The GLSL ES 3.00 functions the sky's shading needs (atmo_web.glsl, generated from atmo's shared
// sources), for custom shaders and the three.js adapter.
export async function loadSkyGlsl() {
  const response = await fetch(new URL('./atmo_web.glsl', import.meta.url));
  if (!response.ok) throw new Error(`cannot load atmo_web.glsl: HTTP ${response.status}`);
  return response.text();
}
