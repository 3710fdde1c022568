// atmo-sky's three.js example (docs/web.md): three's Sky replaced by atmo's, a physically based
// sphere lit by atmo's environment map, a physical exposure. After `npm install atmo-sky three`,
// serve this folder (with node_modules) from any local server.
//
// Test hook (tests/web/npm_test.mjs): with ?test=WIDTHxHEIGHT#PARAMS it renders the sky alone into
// a float target without tone mapping (linear cd/m^2), posts the pixels to /result, then renders
// a white diffuse sphere lit only by the environment and posts its top pixel's value and the
// horizontal illuminance of the cube map to /sphere.
import * as THREE from 'three';
import { exposureFromEv100, loadAtmo, loadSkyGlsl } from 'atmo-sky';
import { AtmoSky, atmoEnvironment } from 'atmo-sky/three';

const params = { model: 'hillaire', preset: 'earth', sunElevation: 20, sunAzimuth: 135, yaw: 135, pitch: 10, fov: 90,
                 altitude: 0, ev: 14 };
for (const [key, value] of new URLSearchParams(location.hash.slice(1))) {
  params[key] = typeof params[key] === 'number' ? Number(value) : value;
}
const test = new URLSearchParams(location.search).get('test');

const atmo = await loadAtmo();
const model = new atmo.Model(params.model, { preset: params.preset });
const renderer = new THREE.WebGLRenderer({ antialias: false });
renderer.setPixelRatio(1);
document.body.appendChild(renderer.domElement);
const scene = new THREE.Scene();
const sky = new AtmoSky(await loadSkyGlsl());
const view = { altitude: params.altitude, sunElevation: params.sunElevation, sunAzimuth: params.sunAzimuth };
sky.update(model, view, renderer);
scene.add(sky);

// atmo's camera: horizontal field of view, yaw as a compass azimuth, pitch up from the horizon.
function makeCamera(width, height) {
  const radians = Math.PI / 180;
  const vertical = 2 * Math.atan(Math.tan(0.5 * params.fov * radians) * height / width) / radians;
  const camera = new THREE.PerspectiveCamera(vertical, width / height, 0.1, 1000);
  const yaw = params.yaw * radians;
  const pitch = params.pitch * radians;
  camera.lookAt(new THREE.Vector3(Math.cos(pitch) * Math.sin(yaw), Math.sin(pitch), -Math.cos(pitch) * Math.cos(yaw)));
  return camera;
}

if (!test) {
  const env = atmoEnvironment(renderer, model, view);
  scene.environment = env.texture;
  scene.environmentIntensity = env.intensity;
  const sphere = new THREE.Mesh(new THREE.SphereGeometry(1, 64, 32),
                                new THREE.MeshStandardMaterial({ color: 0xffffff, roughness: 0.35, metalness: 0 }));
  scene.add(sphere);
  renderer.toneMapping = THREE.AgXToneMapping;
  renderer.toneMappingExposure = exposureFromEv100(params.ev);
  const resize = () => {
    renderer.setSize(innerWidth, innerHeight);
    const camera = makeCamera(innerWidth, innerHeight);
    camera.position.set(0, 0, 0).addScaledVector(camera.getWorldDirection(new THREE.Vector3()), -4);
    renderer.render(scene, camera);
  };
  addEventListener('resize', resize);
  resize();
} else {
  const [width, height] = test.split('x').map(Number);
  renderer.setSize(width, height);
  renderer.toneMapping = THREE.NoToneMapping;
  renderer.outputColorSpace = THREE.LinearSRGBColorSpace;
  const target = new THREE.WebGLRenderTarget(width, height, { type: THREE.FloatType, format: THREE.RGBAFormat });
  const camera = makeCamera(width, height);
  renderer.setRenderTarget(target);
  renderer.render(scene, camera);
  const pixels = new Float32Array(width * height * 4);
  renderer.readRenderTargetPixels(target, 0, 0, width, height, pixels);
  const flipped = new Float32Array(pixels.length);  // rows from the top
  for (let y = 0; y < height; ++y) flipped.set(pixels.subarray((height - 1 - y) * width * 4, (height - y) * width * 4), y * width * 4);
  await fetch('/result', { method: 'POST', headers: { 'x-width': String(width), 'x-height': String(height) }, body: flipped });

  // A white Lambertian sphere lit by the environment alone, seen from above: its top pixel
  // shows E_h / pi (E_h the horizontal illuminance of the cube map, summed here from its faces).
  scene.remove(sky);
  const env = atmoEnvironment(renderer, model, view);
  scene.environment = env.texture;
  scene.environmentIntensity = env.intensity;
  const sphere = new THREE.Mesh(new THREE.SphereGeometry(1, 128, 64),
                                new THREE.MeshStandardMaterial({ color: 0xffffff, roughness: 1, metalness: 0 }));
  scene.add(sphere);
  const top = new THREE.PerspectiveCamera(10, 1, 0.1, 100);
  top.position.set(0, 20, 0);
  top.up.set(0, 0, -1);
  top.lookAt(0, 0, 0);
  const small = new THREE.WebGLRenderTarget(64, 64, { type: THREE.FloatType, format: THREE.RGBAFormat });
  renderer.setRenderTarget(small);
  renderer.render(scene, top);
  const centre = new Float32Array(4);
  renderer.readRenderTargetPixels(small, 32, 32, 1, 1, centre);
  renderer.setRenderTarget(null);
  const cube = model.cubeMap({ size: 64, ...view });
  let illuminance = 0;  // sum over the +Y face (three's up) and the four sides' upper halves of L cos dOmega
  const n = cube.size;
  cube.faces.forEach((face, f) => {
    for (let j = 0; j < n; ++j) {
      for (let i = 0; i < n; ++i) {
        const s = 2 * (i + 0.5) / n - 1;
        const t = 2 * (j + 0.5) / n - 1;
        // The direction three samples for texel (i, j) of face f (cube-map convention, x mirrored).
        const d = [[1, -t, -s], [-1, -t, s], [s, 1, t], [s, -1, -t], [s, -t, 1], [-s, -t, -1]][f];
        d[0] = -d[0];  // CubeTextureForThree: three looks up (-x, y, z)
        const length = Math.hypot(...d);
        const cosine = d[1] / length;
        if (cosine <= 0) continue;
        const solidAngle = (4 / (n * n)) / length ** 3;
        const k = 3 * (j * n + i);
        const y = 0.2126 * face[k] + 0.7152 * face[k + 1] + 0.0722 * face[k + 2];
        illuminance += y * cosine * solidAngle;
      }
    }
  });
  const luminance = 0.2126 * centre[0] + 0.7152 * centre[1] + 0.0722 * centre[2];
  await fetch('/sphere', { method: 'POST', body: JSON.stringify({ luminance, illuminance }) });
}
