// atmo-sky's three.js adapter (docs/web.md): a sky background and a PBR environment from an atmo
// model, in physical units (cd/m^2), in three's world frame (Y up, +X east, -Z north: the
// convention of atmo's `--target three`, docs/environment.md). It replaces three's
// examples/jsm/objects/Sky.js (Preetham's 1999 analytic sky):
//
//   import { loadAtmo, loadSkyGlsl, exposureFromEv100 } from 'atmo-sky';
//   import { AtmoSky, atmoEnvironment } from 'atmo-sky/three';
//   const atmo = await loadAtmo();
//   const model = new atmo.Model('hillaire', { preset: 'earth' });
//   const sky = new AtmoSky(await loadSkyGlsl());
//   sky.update(model, { sunElevation: 20, sunAzimuth: 135 });       // builds the sky-view table
//   scene.add(sky);
//   const env = atmoEnvironment(renderer, model, { sunElevation: 20, sunAzimuth: 135 });
//   scene.environment = env.texture;
//   scene.environmentIntensity = env.intensity;                     // back to cd/m^2
//   renderer.toneMapping = THREE.AgXToneMapping;
//   renderer.toneMappingExposure = exposureFromEv100(14);           // physical exposure
//
// Exposure: the sky and the environment are in cd/m^2 (a clear noon sky is ~10^4, the sun's disc
// ~10^9), so a tone mapping with toneMappingExposure = exposureFromEv100(EV100) maps them as a
// camera would (EV100 15 for a sunny day, 12 at sunset, about 0 in deep twilight); lights of your
// own should then be in physical units too (lux for a DirectionalLight).
import * as THREE from 'three';

import { kSkyShading, skyUniformValues } from './sky_shading.js';

const kVertex = `
varying vec3 vWorldDirection;
void main() {
  vec4 world = modelMatrix * vec4(position, 1.0);
  vWorldDirection = world.xyz - cameraPosition;
  gl_Position = projectionMatrix * viewMatrix * world;
  gl_Position.z = gl_Position.w;  // on the far plane: behind everything
}
`;

// GLSL 3 ShaderMaterials declare their output themselves; three's tone-mapping and colour-space
// chunks write gl_FragColor.
const kFragment = `
layout(location = 0) out highp vec4 atmo_frag_colour;
#define gl_FragColor atmo_frag_colour
varying vec3 vWorldDirection;
void main() {
  vec3 d = normalize(vWorldDirection);
  // three's world (x east, y up, -z north) to atmo's local frame (x east, y north, z up).
  vec3 view = vec3(d.x, -d.z, d.y);
  vec3 radiance = AtmoSky(view) + AtmoSunDisc(view, dFdx(view), dFdy(view));
  gl_FragColor = vec4(radiance, 1.0);
  #include <tonemapping_fragment>
  #include <colorspace_fragment>
}
`;

// A sky-view table (Model.skyView) as a float texture, filtered linearly where the browser can.
function skyViewTexture(table, renderer) {
  const gl = renderer?.getContext?.();
  const floatLinear = !gl || gl.getExtension('OES_texture_float_linear') !== null;
  const data = floatLinear ? table.texels : Uint16Array.from(table.texels, (v) => THREE.DataUtils.toHalfFloat(v));
  const texture = new THREE.DataTexture(data, table.width, table.height, THREE.RGBAFormat,
                                        floatLinear ? THREE.FloatType : THREE.HalfFloatType);
  texture.wrapS = THREE.RepeatWrapping;
  texture.wrapT = THREE.ClampToEdgeWrapping;
  texture.magFilter = THREE.LinearFilter;
  texture.minFilter = THREE.LinearFilter;
  texture.colorSpace = THREE.LinearSRGBColorSpace;
  texture.flipY = false;  // row 0 of the table is t = 0
  texture.needsUpdate = true;
  return texture;
}

// The sky as a background mesh: a box around the camera drawn on the far plane, its colour the
// model's radiance along each pixel's direction (the sky-view table and the pixel-integrated sun
// disc of sky_shading.js).
export class AtmoSky extends THREE.Mesh {
  // glsl: the text of atmo_web.glsl (loadSkyGlsl()).
  constructor(glsl) {
    const material = new THREE.ShaderMaterial({
      name: 'AtmoSkyMaterial',
      glslVersion: THREE.GLSL3,
      uniforms: {
        atmo_sky_view: { value: null },
        atmo_r_km: { value: 6360 },
        atmo_bottom_radius_km: { value: 6360 },
        atmo_top_radius_km: { value: 6460 },
        atmo_horizon_nadir_angle: { value: Math.PI / 2 },
        atmo_sun_direction: { value: new THREE.Vector3(0, 0, 1) },
        atmo_sun_centre: { value: new THREE.Vector3() },
        atmo_sun_radius: { value: 0 },
      },
      vertexShader: kVertex,
      fragmentShader: glsl + kSkyShading + kFragment,
      side: THREE.BackSide,
      depthWrite: false,
    });
    super(new THREE.BoxGeometry(1, 1, 1), material);
    this.name = 'AtmoSky';
    this.frustumCulled = false;
    this.scale.setScalar(1e4);
    this.table = null;
  }

  // Draws the model's sky for an observer and sun: view = {altitude (m), sunElevation, sunAzimuth
  // (compass degrees), sunDisc, tableWidth, tableHeight}. Builds the sky-view table in atmo.wasm
  // (a few ms for hillaire, ~0.5 s for source4d on one core); returns it.
  update(model, view = {}, renderer = null) {
    const table = model.skyView({ altitude: view.altitude ?? 0, sunElevation: view.sunElevation ?? 10,
                                  width: view.tableWidth ?? 192, height: view.tableHeight ?? 108 });
    this.setTable(table, view.sunElevation ?? 10, view.sunAzimuth ?? 180, view.sunDisc ?? true, renderer);
    return table;
  }

  // The same from a table made elsewhere (a worker, say).
  setTable(table, sunElevation, sunAzimuth, sunDisc = true, renderer = null) {
    const u = this.material.uniforms;
    u.atmo_sky_view.value?.dispose();
    u.atmo_sky_view.value = skyViewTexture(table, renderer);
    for (const [name, value] of Object.entries(skyUniformValues(table, sunElevation, sunAzimuth, sunDisc))) {
      if (Array.isArray(value)) u[name].value.set(value[0], value[1], value[2]);
      else u[name].value = value;
    }
    this.table = table;
  }

  // The sun's direction in three's world frame (unit), e.g. for a DirectionalLight.
  sunDirection(target = new THREE.Vector3()) {
    const s = this.material.uniforms.atmo_sun_direction.value;
    return target.set(s.x, s.z, -s.y);
  }

  dispose() {
    this.material.uniforms.atmo_sky_view.value?.dispose();
    this.material.dispose();
    this.geometry.dispose();
  }
}

// The model's sky as a CubeTexture in three's convention (Model.cubeMap: faces px, nx, py, ny, pz,
// nz as three samples them), RGBA float in cd/m^2, with the sun's disc at its true energy.
// `scale` multiplies every value (atmoEnvironment keeps the largest under half-float's range).
export function atmoCubeTexture(model, view = {}, scale = 1) {
  const cube = model.cubeMap({ size: view.size ?? 128, altitude: view.altitude ?? 0,
                               sunElevation: view.sunElevation ?? 10, sunAzimuth: view.sunAzimuth ?? 180,
                               sunDisc: view.sunDisc ?? true, ground: view.ground ?? true });
  const faces = cube.faces.map((rgb) => {
    const rgba = new Float32Array((rgb.length / 3) * 4);
    for (let i = 0, j = 0; i < rgb.length; i += 3, j += 4) {
      rgba[j] = rgb[i] * scale;
      rgba[j + 1] = rgb[i + 1] * scale;
      rgba[j + 2] = rgb[i + 2] * scale;
      rgba[j + 3] = 1;
    }
    const face = new THREE.DataTexture(rgba, cube.size, cube.size, THREE.RGBAFormat, THREE.FloatType);
    face.flipY = false;
    return face;
  });
  const texture = new THREE.CubeTexture(faces, THREE.CubeReflectionMapping, THREE.ClampToEdgeWrapping,
                                        THREE.ClampToEdgeWrapping, THREE.LinearFilter, THREE.LinearFilter,
                                        THREE.RGBAFormat, THREE.FloatType);
  texture.colorSpace = THREE.LinearSRGBColorSpace;
  texture.generateMipmaps = false;
  texture.flipY = false;
  texture.needsUpdate = true;
  return texture;
}

// scene.environment for physically based materials: the cube map prefiltered by three's
// PMREMGenerator. PMREM filters in half floats (largest 65504), and the sun's texel holds ~10^9
// cd/m^2, so the map is stored scaled down and `intensity` scales it back: set
//   scene.environment = env.texture; scene.environmentIntensity = env.intensity;
// and a white Lambertian surface facing up shows the horizontal illuminance / pi in cd/m^2.
export function atmoEnvironment(renderer, model, view = {}) {
  const probe = model.cubeMap({ size: view.size ?? 128, altitude: view.altitude ?? 0,
                                sunElevation: view.sunElevation ?? 10, sunAzimuth: view.sunAzimuth ?? 180,
                                sunDisc: view.sunDisc ?? true, ground: view.ground ?? true });
  let largest = 0;
  for (const face of probe.faces) for (const v of face) largest = Math.max(largest, v);
  // A power of two keeps the scaling exact.
  const scale = largest > 16384 ? 2 ** -Math.ceil(Math.log2(largest / 16384)) : 1;
  const cube = atmoCubeTexture(model, view, scale);
  const pmrem = new THREE.PMREMGenerator(renderer);
  const target = pmrem.fromCubemap(cube);
  pmrem.dispose();
  cube.dispose();
  return { texture: target.texture, intensity: 1 / scale, renderTarget: target };
}
