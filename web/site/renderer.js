// The page's WebGL2 renderer: each frame is drawn in one fragment shader from the model's sky-view
// table (atmo.wasm's Model.skyView: the model's radiance at the texel centres of hillaire's
// sky-view mapping, linear sRGB cd/m^2), as the GL backend draws its frames. The shader is
// atmo_web.glsl, which web/CMakeLists.txt generates from atmo's shared sources
// (cmake/GenerateTablesGlsl.cmake: the sky-view mapping, the camera rays and the limb darkening the
// C++ renderer compiles, the viewer's AgX display transform), then the sky's shading
// (sky_shading.js, shared with the three.js adapter), then main() below. docs/web.md.
import { kSkyShading, skyUniformValues } from './sky_shading.js';

// Before atmo_web.glsl: precision.
const kPrelude = `#version 300 es
precision highp float;
precision highp int;
precision highp sampler2D;
precision highp sampler3D;
`;

// The vertex stage makes the camera once per vertex (atmo's MakeCameraParameters, with its
// trigonometry), and hands its vectors to the pixels unchanged.
const kVertexMain = `
uniform int camera_kind;
uniform vec2 camera_yaw_pitch; // radians
uniform float camera_fov;      // horizontal, radians
uniform ivec2 size;
flat out vec3 camera_forward;
flat out vec3 camera_right;
flat out vec3 camera_up;
flat out float camera_tan_half_fov;
void main() {
  atmo_CameraParameters camera = atmo_MakeCameraParameters(camera_kind, size.x, size.y, camera_fov, camera_yaw_pitch.x,
                                                      camera_yaw_pitch.y);
  camera_forward = camera.forward;
  camera_right = camera.right;
  camera_up = camera.up;
  camera_tan_half_fov = camera.tan_half_fov;
  // One triangle over the viewport.
  vec2 p = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);
  gl_Position = vec4(p, 0.0, 1.0);
}
`;

const kMain = `
flat in vec3 camera_forward;
flat in vec3 camera_right;
flat in vec3 camera_up;
flat in float camera_tan_half_fov;
uniform int camera_kind;
uniform vec2 camera_yaw_pitch; // radians
uniform float camera_fov;      // horizontal, radians
uniform ivec2 size;            // the image's size in pixels
uniform float exposure;        // scene-referred multiplier before the display transform
uniform int output_mode;       // 0 display (AgX, sRGB 2.2), 1 linear cd/m^2 (float read-back)
uniform bool show_error;       // the model's error against the reference instead of the sky
uniform sampler2D error_map;   // relative error, x: azimuth from the sun 0..180 deg, y: zenith 0..90 deg
uniform float error_scale;     // the relative error at the colour scale's ends
out vec4 colour;

void main() {
  // Row 0 at the top, as atmo's cameras count rows.
  vec2 frag = vec2(gl_FragCoord.x, float(size.y) - gl_FragCoord.y);
  atmo_CameraParameters camera;
  camera.kind = camera_kind;
  camera.width = size.x;
  camera.height = size.y;
  camera.horizontal_fov = camera_fov;
  camera.yaw = camera_yaw_pitch.x;
  camera.pitch = camera_yaw_pitch.y;
  camera.forward = camera_forward;
  camera.right = camera_right;
  camera.up = camera_up;
  camera.tan_half_fov = camera_tan_half_fov;
  vec3 view;
  if (!atmo_GetCameraRayDirection(camera, frag, view)) {
    colour = vec4(0.0, 0.0, 0.0, output_mode == 1 ? 0.0 : 1.0);
    return;
  }
  // The pixel's footprint: the change of the ray to the next pixel across and down.
  vec3 radiance = AtmoSky(view) + AtmoSunDisc(view, dFdx(view), -dFdy(view));
  if (output_mode == 1) {
    colour = vec4(radiance, 1.0);
    return;
  }
  if (show_error) {
    // Above the horizon: the error's colour (the viewer's diverging scale), shaded a little by
    // the sky's own brightness so that the scene stays readable; below it the ground, dimmed.
    vec3 shade = atmo_Agx(max(radiance, vec3(0.0)) * exposure);
    if (view.z >= 0.0) {
      float azimuth = atmo_GetAzimuthFromSun(view, atmo_sun_direction);
      azimuth = azimuth > atmo_kPi ? 2.0 * atmo_kPi - azimuth : azimuth;
      vec2 uv = vec2(azimuth / atmo_kPi, acos(clamp(view.z, 0.0, 1.0)) / (0.5 * atmo_kPi));
      vec2 size = vec2(textureSize(error_map, 0));
      float error = texture(error_map, (0.5 + uv * (size - 1.0)) / size).r;
      vec3 c = atmo_Diverging(clamp(error / error_scale, -1.0, 1.0));
      colour = vec4(pow(c * (0.75 + 0.25 * dot(shade, vec3(0.2126, 0.7152, 0.0722))), vec3(1.0 / 2.2)), 1.0);
    } else {
      colour = vec4(pow(0.3 * shade, vec3(1.0 / 2.2)), 1.0);
    }
    return;
  }
  // AgX's display value, encoded with the 2.2 power that the canvas expects.
  colour = vec4(atmo_AgxEncoded(max(radiance, vec3(0.0)) * exposure), 1.0);
}
`;

function compile(gl, type, source) {
  const shader = gl.createShader(type);
  gl.shaderSource(shader, source);
  gl.compileShader(shader);
  if (!gl.getShaderParameter(shader, gl.COMPILE_STATUS)) {
    const log = gl.getShaderInfoLog(shader);
    throw new Error(`shader: ${log}`);
  }
  return shader;
}

export const CameraKind = { perspective: 0, fisheye: 1, equirect: 2 };

export class SkyRenderer {
  // canvas: an HTMLCanvasElement; glsl: the text of atmo_web.glsl.
  constructor(canvas, glsl) {
    const gl = canvas.getContext('webgl2', { antialias: false, preserveDrawingBuffer: true });
    if (!gl) throw new Error('this browser has no WebGL2');
    this.gl = gl;
    this.floatTargets = gl.getExtension('EXT_color_buffer_float') !== null;
    this.floatLinear = gl.getExtension('OES_texture_float_linear') !== null;
    const program = gl.createProgram();
    gl.attachShader(program, compile(gl, gl.VERTEX_SHADER, kPrelude + glsl + kVertexMain));
    gl.attachShader(program, compile(gl, gl.FRAGMENT_SHADER, kPrelude + glsl + kSkyShading + kMain));
    gl.linkProgram(program);
    if (!gl.getProgramParameter(program, gl.LINK_STATUS)) throw new Error(`link: ${gl.getProgramInfoLog(program)}`);
    this.program = program;
    this.uniforms = {};
    const count = gl.getProgramParameter(program, gl.ACTIVE_UNIFORMS);
    for (let i = 0; i < count; ++i) {
      const name = gl.getActiveUniform(program, i).name;
      this.uniforms[name] = gl.getUniformLocation(program, name);
    }
    this.texture = gl.createTexture();
    this.errorTexture = gl.createTexture();
    this.errorScale = 0;  // 0: no error map
    this.vao = gl.createVertexArray();
    this.table = null;
  }

  // table: the value of Model.skyView.
  setSkyView(table) {
    const gl = this.gl;
    gl.bindTexture(gl.TEXTURE_2D, this.texture);
    // RGBA32F filters linearly where OES_texture_float_linear is (SwiftShader, desktop GPUs);
    // elsewhere RGBA16F, which WebGL2 always filters.
    if (this.floatLinear) {
      gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA32F, table.width, table.height, 0, gl.RGBA, gl.FLOAT, table.texels);
    } else {
      gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA16F, table.width, table.height, 0, gl.RGBA, gl.FLOAT, table.texels);
    }
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.LINEAR);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.LINEAR);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.REPEAT);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);
    this.table = table;
  }

  // The model's relative error against the reference on a grid of width (azimuth from the sun,
  // 0..180 degrees) x height (zenith angle, 0..90 degrees), row 0 at the zenith; scale: the error
  // at the colour scale's ends; null: back to the sky.
  setErrorMap(grid, scale) {
    const gl = this.gl;
    if (!grid) {
      this.errorScale = 0;
      return;
    }
    gl.bindTexture(gl.TEXTURE_2D, this.errorTexture);
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.R32F, grid.width, grid.height, 0, gl.RED, gl.FLOAT, grid.values);
    const filter = this.floatLinear ? gl.LINEAR : gl.NEAREST;
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, filter);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, filter);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);
    this.errorScale = scale;
  }

  // view: {camera, yaw, pitch, fov (degrees), sunElevation, sunAzimuth, exposure}; output 'display'
  // or 'linear'. Draws into the bound framebuffer of width x height.
  draw(view, width, height, output = 'display') {
    const gl = this.gl;
    const t = this.table;
    if (!t) return;
    const u = this.uniforms;
    const radians = Math.PI / 180;
    gl.viewport(0, 0, width, height);
    gl.useProgram(this.program);
    gl.activeTexture(gl.TEXTURE0);
    gl.bindTexture(gl.TEXTURE_2D, this.texture);
    gl.uniform1i(u.atmo_sky_view, 0);
    const values = skyUniformValues(t, view.sunElevation, view.sunAzimuth, view.sunDisc !== false);
    for (const [name, value] of Object.entries(values)) {
      if (Array.isArray(value)) gl.uniform3fv(u[name], value);
      else gl.uniform1f(u[name], value);
    }
    gl.uniform1i(u.camera_kind, CameraKind[view.camera ?? 'perspective']);
    gl.uniform2f(u.camera_yaw_pitch, view.yaw * radians, view.pitch * radians);
    gl.uniform1f(u.camera_fov, view.fov * radians);
    gl.uniform2i(u.size, width, height);
    gl.uniform1f(u.exposure, view.exposure);
    gl.uniform1i(u.output_mode, output === 'linear' ? 1 : 0);
    gl.uniform1i(u.show_error, this.errorScale > 0 && output !== 'linear' ? 1 : 0);
    gl.activeTexture(gl.TEXTURE1);
    gl.bindTexture(gl.TEXTURE_2D, this.errorTexture);
    gl.uniform1i(u.error_map, 1);
    gl.uniform1f(u.error_scale, this.errorScale || 1);
    gl.bindVertexArray(this.vao);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
  }

  // Milliseconds per displayed frame of width x height (an RGBA8 target, as the canvas), the
  // mean over `frames` draws, each waited for.
  timeFrames(view, width, height, frames = 20) {
    const gl = this.gl;
    return this.withTarget(gl.RGBA8, width, height, () => {
      const pixel = new Uint8Array(4);
      this.draw(view, width, height);
      gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);  // warm: compile and first use
      const start = performance.now();
      for (let i = 0; i < frames; ++i) {
        this.draw({ ...view, yaw: view.yaw + i }, width, height);
        gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
      }
      return (performance.now() - start) / frames;
    });
  }

  // The frame in linear cd/m^2 as floats (RGBA, rows from the top), drawn into a float target.
  readLinear(view, width, height) {
    const gl = this.gl;
    if (!this.floatTargets) throw new Error('this browser cannot render to float targets (EXT_color_buffer_float)');
    const pixels = this.withTarget(gl.RGBA32F, width, height, () => {
      this.draw(view, width, height, 'linear');
      const values = new Float32Array(width * height * 4);
      gl.readPixels(0, 0, width, height, gl.RGBA, gl.FLOAT, values);
      return values;
    });
    // GL's rows start at the bottom.
    const flipped = new Float32Array(pixels.length);
    const row = width * 4;
    for (let y = 0; y < height; ++y) flipped.set(pixels.subarray((height - 1 - y) * row, (height - y) * row), y * row);
    return flipped;
  }

  // Runs draw() into an offscreen target of `internalFormat`, width x height, then frees it.
  withTarget(internalFormat, width, height, draw) {
    const gl = this.gl;
    const target = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_2D, target);
    gl.texStorage2D(gl.TEXTURE_2D, 1, internalFormat, width, height);
    const fbo = gl.createFramebuffer();
    gl.bindFramebuffer(gl.FRAMEBUFFER, fbo);
    gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, target, 0);
    try {
      return draw();
    } finally {
      gl.bindFramebuffer(gl.FRAMEBUFFER, null);
      gl.deleteFramebuffer(fbo);
      gl.deleteTexture(target);
    }
  }
}
