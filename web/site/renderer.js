// The page's WebGL2 renderer: each frame is drawn in one fragment shader from the model's sky-view
// table (atmo.wasm's Model.skyView: the model's radiance at the texel centres of hillaire's
// sky-view mapping, linear sRGB cd/m^2), as the GL backend draws its frames. The shader is the
// page's main() after atmo_web.glsl, which web/CMakeLists.txt generates from atmo's shared
// sources (cmake/GenerateTablesGlsl.cmake): the same mapping, camera rays and limb darkening the
// C++ renderer compiles, and the viewer's AgX display transform. docs/web.md.

const kVertex = `#version 300 es
void main() {
  // One triangle over the viewport.
  vec2 p = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);
  gl_Position = vec4(p, 0.0, 1.0);
}
`;

// Before atmo_web.glsl: precision and what its camera functions take from atmo's definitions.
const kPrelude = `#version 300 es
precision highp float;
precision highp int;
precision highp sampler2D;
precision highp sampler3D;
struct CameraParameters {
  int kind;
  int width;
  int height;
  float horizontal_fov;
  float yaw;
  float pitch;
  vec3 forward;
  vec3 right;
  vec3 up;
  float tan_half_fov;
};
`;

const kMain = `
uniform sampler2D sky_view;    // RGBA32F, linear sRGB cd/m^2 (GL_LINEAR, s repeats)
uniform float r_km;            // the observer's radius
uniform float bottom_radius_km;
uniform float top_radius_km;
uniform vec3 sun_direction;    // local frame: x east, y north, z up
uniform vec3 sun_centre;       // the sun disc's centre radiance through the air, linear sRGB cd/m^2
uniform float sun_radius;      // angular radius, radians
uniform int camera_kind;
uniform vec2 camera_yaw_pitch; // radians
uniform float camera_fov;      // horizontal, radians
uniform ivec2 size;            // the image's size in pixels
uniform float exposure;        // scene-referred multiplier before the display transform
uniform int output_mode;       // 0 display (AgX, sRGB 2.2), 1 linear cd/m^2 (float read-back)
out vec4 colour;

// The sky and ground (no sun disc) along a direction.
vec3 Sky(vec3 view) {
  AtmoGeometry atmosphere = AtmoGeometry(bottom_radius_km, top_radius_km);
  return atmoSkyView(atmosphere, sky_view, r_km, view, sun_direction);
}

// The sun disc's mean radiance over the pixel: limb-darkened (Neckel and Labs at 610, 550 and
// 465 nm for R, G, B, relative to the centre), sampled on a 4 x 4 grid of the pixel where the disc
// spans pixels; a disc smaller than a pixel gives its whole energy to the pixel holding its
// centre, so that its irradiance is right at any resolution.
vec3 SunDisc(CameraParameters camera, vec2 frag, vec3 view) {
  vec3 darkening_centre = vec3(atmo_GetSunLimbDarkening(610.0, 1.0), atmo_GetSunLimbDarkening(550.0, 1.0),
                               atmo_GetSunLimbDarkening(465.0, 1.0));
  // The pixel's angular size along its row (perspective: at the pixel; equirect: its height).
  vec3 next;
  atmo_GetCameraRayDirection(camera, frag + vec2(1.0, 0.0), next);
  float pixel = acos(clamp(dot(view, next), -1.0, 1.0));
  if (dot(view, sun_direction) < cos(sun_radius + 2.0 * pixel)) {
    return vec3(0.0);
  }
  if (sun_radius < 0.5 * pixel) {
    // The pixel holds the disc's centre when the sun is nearer its direction than any neighbour's.
    float d = dot(sun_direction, view);
    vec3 n[4];
    atmo_GetCameraRayDirection(camera, frag + vec2(1.0, 0.0), n[0]);
    atmo_GetCameraRayDirection(camera, frag - vec2(1.0, 0.0), n[1]);
    atmo_GetCameraRayDirection(camera, frag + vec2(0.0, 1.0), n[2]);
    atmo_GetCameraRayDirection(camera, frag - vec2(0.0, 1.0), n[3]);
    for (int i = 0; i < 4; ++i) {
      if (dot(n[i], sun_direction) > d) return vec3(0.0);
    }
    // Solid angles: the disc's and the pixel's (its two spans).
    float across = acos(clamp(dot(n[0], n[1]), -1.0, 1.0)) * 0.5;
    float along = acos(clamp(dot(n[2], n[3]), -1.0, 1.0)) * 0.5;
    float sin_half = sin(0.5 * sun_radius);
    float disc = 4.0 * atmo_kPi * sin_half * sin_half;  // 2 pi (1 - cos r), without cos's error near 0
    // The disc's mean limb darkening relative to its centre: the mean of f(mu) mu over the disc's
    // area, with mu on the solar surface; 8 rings suffice at the precision of a sub-pixel disc.
    vec3 mean = vec3(0.0);
    for (int k = 0; k < 8; ++k) {
      float rho = (float(k) + 0.5) / 8.0;
      float mu = sqrt(max(1.0 - rho * rho, 0.0));
      mean += 2.0 * rho / 8.0 * vec3(atmo_GetSunLimbDarkening(610.0, mu), atmo_GetSunLimbDarkening(550.0, mu),
                                     atmo_GetSunLimbDarkening(465.0, mu));
    }
    return sun_centre * (mean / darkening_centre) * disc / max(across * along, 1e-20);
  }
  vec3 sum = vec3(0.0);
  for (int j = 0; j < 8; ++j) {
    for (int i = 0; i < 8; ++i) {
      vec3 v;
      atmo_GetCameraRayDirection(camera, frag + (vec2(i, j) + 0.5) / 8.0 - 0.5, v);
      float mu = atmo_GetSunDiscSurfaceCosine(dot(v, sun_direction), sun_radius);
      if (mu >= 0.0) {
        sum += vec3(atmo_GetSunLimbDarkening(610.0, mu), atmo_GetSunLimbDarkening(550.0, mu),
                    atmo_GetSunLimbDarkening(465.0, mu)) / darkening_centre;
      }
    }
  }
  return sun_centre * sum / 64.0;
}

void main() {
  // Row 0 at the top, as atmo's cameras count rows.
  vec2 frag = vec2(gl_FragCoord.x, float(size.y) - gl_FragCoord.y);
  CameraParameters camera = atmo_MakeCameraParameters(camera_kind, size.x, size.y, camera_fov, camera_yaw_pitch.x,
                                                      camera_yaw_pitch.y);
  vec3 view;
  if (!atmo_GetCameraRayDirection(camera, frag, view)) {
    colour = vec4(0.0, 0.0, 0.0, output_mode == 1 ? 0.0 : 1.0);
    return;
  }
  vec3 radiance = Sky(view) + SunDisc(camera, frag, view);
  if (output_mode == 1) {
    colour = vec4(radiance, 1.0);
    return;
  }
  vec3 display = atmo_Agx(max(radiance, vec3(0.0)) * exposure);  // linear display light
  colour = vec4(pow(display, vec3(1.0 / 2.2)), 1.0);
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
    gl.attachShader(program, compile(gl, gl.VERTEX_SHADER, kVertex));
    gl.attachShader(program, compile(gl, gl.FRAGMENT_SHADER, kPrelude + glsl + kMain));
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
    gl.uniform1i(u.sky_view, 0);
    gl.uniform1f(u.r_km, t.rKm);
    gl.uniform1f(u.bottom_radius_km, t.bottomRadiusKm);
    gl.uniform1f(u.top_radius_km, t.topRadiusKm);
    const e = view.sunElevation * radians;
    const a = view.sunAzimuth * radians;
    gl.uniform3f(u.sun_direction, Math.cos(e) * Math.sin(a), Math.cos(e) * Math.cos(a), Math.sin(e));
    gl.uniform3f(u.sun_centre, t.sunDisc[0], t.sunDisc[1], t.sunDisc[2]);
    gl.uniform1f(u.sun_radius, view.sunDisc === false ? 0.0 : t.sunAngularRadius);
    gl.uniform1i(u.camera_kind, CameraKind[view.camera ?? 'perspective']);
    gl.uniform2f(u.camera_yaw_pitch, view.yaw * radians, view.pitch * radians);
    gl.uniform1f(u.camera_fov, view.fov * radians);
    gl.uniform2i(u.size, width, height);
    gl.uniform1f(u.exposure, view.exposure);
    gl.uniform1i(u.output_mode, output === 'linear' ? 1 : 0);
    gl.bindVertexArray(this.vao);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
  }

  // The frame in linear cd/m^2 as floats (RGBA, rows from the top), drawn into a float target.
  readLinear(view, width, height) {
    const gl = this.gl;
    if (!this.floatTargets) throw new Error('this browser cannot render to float targets (EXT_color_buffer_float)');
    const target = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_2D, target);
    gl.texStorage2D(gl.TEXTURE_2D, 1, gl.RGBA32F, width, height);
    const fbo = gl.createFramebuffer();
    gl.bindFramebuffer(gl.FRAMEBUFFER, fbo);
    gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, target, 0);
    this.draw(view, width, height, 'linear');
    const pixels = new Float32Array(width * height * 4);
    gl.readPixels(0, 0, width, height, gl.RGBA, gl.FLOAT, pixels);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    gl.deleteFramebuffer(fbo);
    gl.deleteTexture(target);
    // GL's rows start at the bottom.
    const flipped = new Float32Array(pixels.length);
    const row = width * 4;
    for (let y = 0; y < height; ++y) flipped.set(pixels.subarray((height - 1 - y) * row, (height - y) * row), y * row);
    return flipped;
  }
}
