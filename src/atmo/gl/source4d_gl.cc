#include "gl/source4d_gl.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <future>
#include <memory>
#include <string>
#include <vector>

#include <epoxy/gl.h>

#include "atmo/error.h"
#include "cpu/camera.h"
#include "cpu/hillaire_tables.h"
#include "gl/hillaire_gl.h"
#include "gl/program.h"
#include "physics/shared_parameters.h"

namespace atmo::gl {
namespace {

// The tables' uniforms of the frame and sky-view passes (set by BindSource4dTables), declared
// before each pass's own main source.
constexpr const char* kSource4dTableUniforms = R"glsl(
uniform AtmosphereParameters atmosphere;
uniform sampler2D transmittance_texture;
uniform sampler3D rayleigh_texture;
uniform sampler3D mie_texture;
uniform sampler2D irradiance_texture;
uniform int mu_s_size;
uniform int sample_count;
)glsl";

// The view ray of each pixel marched through the tables (GetSource4dRadiance: single scattering
// exactly, orders >= 2 from ln G, the lit ground from the transmittance and the ground
// irradiance), and the disc per pixel for interactive use.
constexpr const char* kSource4dFrameMain = R"glsl(
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform writeonly image2D output_image;
uniform CameraParameters camera;
uniform float r;             // km
uniform vec3 sun_direction;  // unit, local frame (x east, y north, z up)
uniform bool ground;
uniform bool sun_disc;
uniform vec3 solar_irradiance;
#if USE_SKY_VIEW
uniform sampler2D sky_view_texture;  // the sky alone, or with the lit ground (as `ground` asks)
uniform float horizon_nadir_angle;
#endif

void main() {
  ivec2 size = imageSize(output_image);
  ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(pixel, size))) return;
  vec3 direction;
  bool seen = GetCameraRayDirection(camera, vec2(pixel) + vec2(0.5), direction);
  vec3 radiance = vec3(0.0);
  if (seen) {
    float mu = ClampCosine(direction.z);
    float nu = ClampCosine(dot(direction, sun_direction));
#if USE_SKY_VIEW
    vec2 uv = GetSkyViewTextureUvFromBeta(textureSize(sky_view_texture, 0), horizon_nadir_angle, mu,
        GetAzimuthFromSun(direction, sun_direction));
    radiance = texture(sky_view_texture, uv).rgb;
#else
    vec3 ground_radiance;
    radiance = GetSource4dRadiance(atmosphere, transmittance_texture, rayleigh_texture, mie_texture,
        irradiance_texture, mu_s_size, r, mu, ClampCosine(sun_direction.z), nu, sample_count, ground_radiance);
    if (ground) radiance += ground_radiance;
#endif
    if (sun_disc) radiance += GetSunDiscRadiance(atmosphere, transmittance_texture, r, mu, nu);
  }
  imageStore(output_image, pixel, vec4(radiance * solar_irradiance, seen ? 1.0 : 0.0));
}
)glsl";

// The sky-view tables' texels (ComputeSource4dSkyViewTexel): the sky into image 0, the sky with
// the lit ground into image 1. Texel x and width - x are mirror images: the invocations march
// columns 0 .. width / 2 and write both.
constexpr const char* kSource4dSkyViewMain = R"glsl(
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform writeonly image2D sky_image;
layout(rgba32f, binding = 1) uniform writeonly image2D sky_and_ground_image;
uniform float r;     // km
uniform float mu_s;

void main() {
  ivec2 size = imageSize(sky_image);
  ivec2 texel = ivec2(gl_GlobalInvocationID.xy);
  if (texel.x > size.x / 2 || texel.y >= size.y) return;
  vec3 ground_radiance;
  vec3 radiance = ComputeSource4dSkyViewTexel(atmosphere, transmittance_texture, rayleigh_texture, mie_texture,
      irradiance_texture, mu_s_size, size, vec2(texel) + vec2(0.5), r, mu_s, sample_count, ground_radiance);
  ivec2 mirror = ivec2((size.x - texel.x) % size.x, texel.y);
  imageStore(sky_image, texel, vec4(radiance, 1.0));
  imageStore(sky_image, mirror, vec4(radiance, 1.0));
  imageStore(sky_and_ground_image, texel, vec4(radiance + ground_radiance, 1.0));
  imageStore(sky_and_ground_image, mirror, vec4(radiance + ground_radiance, 1.0));
}
)glsl";

constexpr std::string_view kSource4dFiles[] = {"definitions.glsl",         "geometry.glsl", "medium.glsl",
                                               "phase.glsl",               "transmittance.glsl",
                                               "multiple_scattering.glsl", "sun.glsl",      "sky.glsl",
                                               "camera.glsl",              "source4d.glsl"};

const ComputeProgram& Source4dFrameProgram(const Context& context, bool use_sky_view, double* compile_ms = nullptr) {
  // Two programs, not a uniform branch (llvmpipe runs a frame with a runtime branch between
  // whole code paths far slower: docs/performance.md).
  static const std::string march =
      std::string("#define USE_SKY_VIEW 0\n") + kSource4dTableUniforms + kSource4dFrameMain;
  static const std::string table =
      std::string("#define USE_SKY_VIEW 1\n") + kSource4dTableUniforms + kSource4dFrameMain;
  return context.Program(kSource4dFiles, use_sky_view ? table : march,
                         use_sky_view ? "source4d frame (sky view)" : "source4d frame", compile_ms);
}

// The tables' uniforms and samplers, and `sky_view` (a sky-view table) as sampler
// sky_view_texture where not null.
void BindSource4dTables(const ComputeProgram& program, const shared::AtmosphereParameters& km_atmosphere,
                        const Source4dTablesGl& tables, int samples, const GpuTexture* sky_view = nullptr) {
  SetAtmosphereUniforms(program, "atmosphere", km_atmosphere);
  program.SetInt("mu_s_size", tables.mu_s_size);
  program.SetInt("sample_count", samples);
  if (sky_view != nullptr) {
    BindSamplers(program, {{"transmittance_texture", &tables.transmittance},
                           {"rayleigh_texture", &tables.rayleigh},
                           {"mie_texture", &tables.mie},
                           {"irradiance_texture", &tables.ground_irradiance},
                           {"sky_view_texture", sky_view}});
  } else {
    BindSamplers(program, {{"transmittance_texture", &tables.transmittance},
                           {"rayleigh_texture", &tables.rayleigh},
                           {"mie_texture", &tables.mie},
                           {"irradiance_texture", &tables.ground_irradiance}});
  }
}

}  // namespace

Source4dTablesGl UploadSource4dTables(const cpu::Source4dTables& tables) {
  if (tables.mu_s_size < 2 || tables.rayleigh.depth == 0) {
    throw Error("GL source4d: the model's tables are not computed (Precompute first)");
  }
  Source4dTablesGl gl;
  gl.transmittance = GpuTexture::Upload(tables.transmittance);
  gl.rayleigh = GpuTexture::Upload(tables.rayleigh);
  gl.mie = GpuTexture::Upload(tables.mie);
  gl.ground_irradiance = GpuTexture::Upload(tables.ground_irradiance);
  gl.mu_s_size = tables.mu_s_size;
  return gl;
}

bool Source4dSkyViewServes(const Source4dModelSettings& settings, const shared::AtmosphereParameters& km_atmosphere,
                           double r_km) {
  return settings.sky_view != Source4dModelSettings::SkyViewMode::kOff && r_km <= km_atmosphere.top_radius;
}

void RunSource4dSkyViewPass(const Context& context, const shared::AtmosphereParameters& km_atmosphere,
                            const Source4dTablesGl& tables, int samples, glm::ivec2 size, double r_km,
                            const glm::dvec3& sun_direction, Source4dSkyViewGl& out) {
  if (size.x < 4 || size.y < 4 || size.x % 2 != 0 || size.y % 2 != 0) {
    throw Error("GL source4d sky-view table: the width and the height must be even and >= 4");
  }
  context.MakeCurrent();
  if (out.sky.empty() || out.sky.size2() != shared::ivec2(size.x, size.y)) {
    out.sky = GpuTexture::Make2D({size.x, size.y}, /*repeat_u=*/true);
    out.sky_and_ground = GpuTexture::Make2D({size.x, size.y}, /*repeat_u=*/true);
  }
  static const std::string main = std::string(kSource4dTableUniforms) + kSource4dSkyViewMain;
  const ComputeProgram& program = context.Program(kSource4dFiles, main, "source4d sky view");
  BindSource4dTables(program, km_atmosphere, tables, samples);
  program.SetFloat("r", r_km);
  program.SetFloat("mu_s", shared::ClampCosine(glm::normalize(sun_direction).z));
  out.sky.BindImage(0);
  out.sky_and_ground.BindImage(1);
  DispatchCompute2D(program, {size.x / 2 + 1, size.y});
  CheckGlError("source4d sky view");
  out.horizon_nadir_angle = shared::GetHorizonNadirAngle(km_atmosphere, r_km);
}

void RunSource4dFramePass(const Context& context, const shared::AtmosphereParameters& km_atmosphere,
                          const Source4dTablesGl& tables, int samples, const shared::CameraParameters& camera,
                          double r_km, const glm::dvec3& sun_direction, bool ground, bool sun_disc,
                          const shared::vec3& solar_irradiance, const GpuTexture& out,
                          const Source4dSkyViewGl* sky_view) {
  context.MakeCurrent();
  const ComputeProgram& program = Source4dFrameProgram(context, sky_view != nullptr);
  const GpuTexture* table = sky_view == nullptr ? nullptr : ground ? &sky_view->sky_and_ground : &sky_view->sky;
  BindSource4dTables(program, km_atmosphere, tables, samples, table);
  SetCameraUniforms(program, "camera", camera);
  program.SetFloat("r", r_km);
  program.SetVec3("sun_direction", glm::normalize(sun_direction));
  program.SetInt("ground", ground ? 1 : 0);
  program.SetInt("sun_disc", sun_disc ? 1 : 0);
  program.SetVec3("solar_irradiance", solar_irradiance);
  if (sky_view != nullptr) program.SetFloat("horizon_nadir_angle", sky_view->horizon_nadir_angle);
  out.BindImage(0);
  DispatchCompute2D(program, out.size2());
  CheckGlError("source4d frame");
}

namespace {

// Batch by batch: its tables (`make_tables(b)`), the frame pass and the frame's read-back into its
// channels; the disc on the host.
template <typename MakeTables>
Image RenderFrames(const Context& context, const Source4dModel& model, const RenderSettings& render,
                   PassTimings* timings, const MakeTables& make_tables) {
  ValidateCamera(render.camera);
  for (const double value : {render.altitude_m, render.sun_elevation_deg, render.sun_azimuth_deg}) {
    if (!std::isfinite(value)) throw Error("altitude and sun angles must be finite");
  }
  const glm::dvec3 sun = glm::normalize(SunDirection(render.sun_elevation_deg, render.sun_azimuth_deg));
  model.View(render.altitude_m, sun);  // what the CPU rejects (altitude < 0)
  const AtmosphereParameters& parameters = model.parameters();
  context.MakeCurrent();
  double compile_ms = 0.0;
  const double r_km = (parameters.ground_radius_m + render.altitude_m) / 1000.0;
  const bool use_sky_view = Source4dSkyViewServes(model.settings(), ToSharedParameters(parameters, 0, 1000.0), r_km);
  Source4dFrameProgram(context, use_sky_view, &compile_ms);  // compiled before any pass is timed
  if (timings != nullptr) timings->Add("source4d_gl_compile", compile_ms);

  const shared::CameraParameters camera = ToSharedCamera(render.camera);
  const std::size_t nc = parameters.channel_count();
  const std::size_t n = static_cast<std::size_t>(camera.width) * camera.height;
  Image image(camera.width, camera.height, static_cast<int>(nc));
  const bool has_alpha = camera.kind == shared::kCameraFisheye;
  if (has_alpha) image.alpha.assign(n, 0.0f);
  const GpuTexture frame = GpuTexture::Make2D({camera.width, camera.height});
  std::vector<shared::Texture2D> transmittance;  // per batch, for the host's sun disc
  for (std::size_t b = 0; b < model.batches().size(); ++b) {
    const Source4dTablesGl tables = make_tables(b);
    const shared::AtmosphereParameters km = ToSharedParameters(parameters, b, 1000.0);
    Source4dSkyViewGl sky_view;
    if (use_sky_view) {
      GpuPassTimer timer(timings);
      RunSource4dSkyViewPass(context, km, tables, model.settings().samples, model.settings().sky_view_lut, r_km, sun,
                             sky_view);
      timer.Stop("sky_view_lut");
    }
    {
      GpuPassTimer timer(timings);
      RunSource4dFramePass(context, km, tables, model.settings().samples, camera, r_km, sun, render.terms.ground,
                           /*sun_disc=*/false, BatchValues(parameters.solar_irradiance, b), frame,
                           use_sky_view ? &sky_view : nullptr);
      timer.Stop("frame_" + std::to_string(camera.width) + "x" + std::to_string(camera.height));
    }
    const std::vector<float> rgba = frame.DownloadRgba();
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t c = 0; c < 3 && 3 * b + c < nc; ++c) image.pixels[nc * i + 3 * b + c] = rgba[4 * i + c];
      if (has_alpha && b == 0) image.alpha[i] = rgba[4 * i + 3];
    }
    if (render.terms.sun_disc) transmittance.push_back(tables.transmittance.Download2D());
  }
  if (render.terms.sun_disc) AddSunDiscOnHost(parameters, transmittance, render, image);
  return image;
}

}  // namespace

Image RenderSource4dGl(const Context& context, const Source4dModel& model, const RenderSettings& render,
                       PassTimings* timings) {
  return RenderFrames(context, model, render, timings, [&](std::size_t b) {
    const auto start = std::chrono::steady_clock::now();
    Source4dTablesGl tables = UploadSource4dTables(model.batches()[b].tables);
    if (timings != nullptr) {
      timings->Add("source4d_gl_upload",
                   std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    }
    return tables;
  });
}

Image RenderSource4dGl(const Context& context, const AtmosphereParameters& parameters,
                       const Source4dModelSettings& settings, const RenderSettings& render, PassTimings* timings) {
  const Source4dModel model(parameters, settings);  // checks the parameters (spherical, valid); no tables
  return RenderFrames(context, model, render, timings, [&](std::size_t b) {
    return ComputeSource4dTablesGl(context, ToSharedParameters(parameters, b, 1000.0), settings.tables, timings);
  });
}

// ---------------------------------------------------------------------------------------------
// The table builder on the GPU (ComputeSource4dTablesGl): the passes of
// cpu::ComputeSource4dTables, with the field and the G of each order in storage buffers in the
// CPU's layouts (field[ab * columns + node * 3 + channel], g[(medium * out_count + cd) * columns
// + column]) and every ln-G table an rgba32f 3D texture.

namespace {

// The grid's nodes as cpu/source4d_tables.cc places them (Grid, NodeAngle), shared by the passes.
constexpr const char* kBuilderHeader = R"glsl(
uniform AtmosphereParameters atmosphere;
uniform int r_size;
uniform int mu_s_size;
uniform int gather_zeniths;
uniform int gather_azimuths;
uniform int out_count;
uniform int columns;

float GetSource4dNodeAngle(int i, int n, float range) { return range * float(i) / float(n - 1); }
float GetSource4dNodeR(int i) { return GetSource4dRFromUnit(atmosphere, float(i) / float(r_size - 1)); }
float GetSource4dNodeMuS(int j) {
  return cos(GetSource4dSunZenithFromUnit(float(j) / float(mu_s_size - 1), mu_s_size));
}
)glsl";

// One invocation per gathering ray and node: order 1 single scattering and the ground's
// reflection of the direct sun, order n >= 2 the march through the order's ln-G tables and the
// reflection of the previous order's ground irradiance (GatherRadiance).
constexpr const char* kGatherMain = R"glsl(
layout(local_size_x = 64) in;
layout(std430, binding = 0) writeonly buffer FieldBuffer { float field[]; };
uniform sampler2D transmittance_texture;
uniform sampler3D rayleigh_texture;
uniform sampler3D mie_texture;
uniform sampler2D irradiance_texture;
uniform int gather_samples;
uniform int order;
uniform int id_offset;  // the first invocation of this dispatch (Source4dTablesBuilder's steps)

void main() {
  int id = int(gl_GlobalInvocationID.x) + id_offset;
  int nodes = r_size * mu_s_size;
  if (id >= nodes * gather_zeniths * gather_azimuths) return;
  int node = id % nodes;
  int ab = id / nodes;
  int a = ab / gather_azimuths;
  int b = ab % gather_azimuths;
  float r = GetSource4dNodeR(node / mu_s_size);
  float mu_s = GetSource4dNodeMuS(node % mu_s_size);
  float sin_s = sqrt(max(1.0 - mu_s * mu_s, 0.0));
  float theta = GetSource4dNodeAngle(a, gather_zeniths, kPi);
  // cos(theta) as sin(pi / 2 - theta): exactly 0 for the horizontal node, where the float cos of
  // the float pi / 2 is -4.4e-8 and would put the ground node's horizontal ray into the ground
  // (the CPU's double cos gives +6e-17: the ray runs along the horizon).
  float mu = sin(0.5 * kPi - theta);
  float sin_v = sin(theta);
  bool hits_ground = RayIntersectsGround(atmosphere, r, mu);
  float nu = ClampCosine(mu * mu_s + sin_v * sin_s * cos(GetSource4dNodeAngle(b, gather_azimuths, kPi)));
  vec3 path_transmittance;
  vec3 radiance = IntegrateSource4dRadianceInside(atmosphere, transmittance_texture, rayleigh_texture, mie_texture,
      mu_s_size, r, mu, mu_s, nu, hits_ground, 1e30, gather_samples, order == 1 ? 1.0 : 0.0, order == 1 ? 0.0 : 1.0,
      GetSource4dGatherMiePhase(atmosphere, a, b, gather_zeniths, gather_azimuths, mu_s, nu), path_transmittance);
  if (hits_ground && any(notEqual(atmosphere.ground_albedo, vec3(0.0)))) {
    float t = DistanceToBottomAtmosphereBoundary(atmosphere, r, mu);
    float mu_s_ground = ClampCosine((r * mu_s + t * nu) / atmosphere.bottom_radius);
    vec3 e;
    if (order == 1) {
      e = mu_s_ground > 0.0 ?
          mu_s_ground * GetTransmittanceToSun(atmosphere, transmittance_texture, atmosphere.bottom_radius, mu_s_ground) :
          vec3(0.0);
    } else {
      e = GetSource4dGroundIrradiance(irradiance_texture, mu_s_ground);
    }
    radiance += path_transmittance * atmosphere.ground_albedo / kPi * e;
  }
  field[3 * id] = radiance.x;
  field[3 * id + 1] = radiance.y;
  field[3 * id + 2] = radiance.z;
}
)glsl";

// G of the next order, both media, by the quadrature matrices (Convolve on the CPU), added to the
// sums: the matrix product C = W F with W the quadrature matrices stacked ((2 out_count) x
// in_count: [medium][cd][ab]), F the field (in_count x columns) and C laid out as g, computed as a
// GEMM of 64 x 64 tiles of C per work group of 16 x 16 invocations, 4 x 4 values each, through
// shared-memory tiles of W and F 16 deep. Each value of W and F is read from memory once per tile
// instead of once per output, and the inner loop is 16 fused multiply-adds per 8 shared reads.
// The sum over ab runs in blocks of 16 in ab's order (float rounding differs from the CPU's
// order by ~1e-7 relative). On an H200 the earth table's product (2304 x 441 x 384) took
// 2.36 ms as one invocation per column and block of 8 directions.
constexpr int kConvolveTile = 64;
constexpr const char* kConvolveMain = R"glsl(
layout(local_size_x = 16, local_size_y = 16) in;
layout(std430, binding = 0) readonly buffer FieldBuffer { float field[]; };
layout(std430, binding = 1) readonly buffer WeightBuffer { float weights[]; };  // [medium][cd][ab]
layout(std430, binding = 2) writeonly buffer GBuffer { float g[]; };
layout(std430, binding = 3) buffer SumBuffer { float sum[]; };
uniform int in_count;
uniform int group_offset;  // the first tile of this dispatch (Source4dTablesBuilder's steps)
const int kTile = 64;
const int kDepth = 16;
shared float w_tile[kDepth][kTile];  // w_tile[ab][row]
shared float f_tile[kDepth][kTile];  // f_tile[ab][column]

void main() {
  const int rows = 2 * out_count;
  const int tiles_across = (columns + kTile - 1) / kTile;
  const int tile = int(gl_WorkGroupID.x) + group_offset;
  const int row_0 = (tile / tiles_across) * kTile;
  const int column_0 = (tile % tiles_across) * kTile;
  if (row_0 >= rows) return;  // the whole work group: no barrier is skipped by some only
  const int tx = int(gl_LocalInvocationID.x);
  const int ty = int(gl_LocalInvocationID.y);
  const int lane = ty * 16 + tx;
  float value[4][4];
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) value[i][j] = 0.0;
  }
  for (int ab_0 = 0; ab_0 < in_count; ab_0 += kDepth) {
    for (int e = lane; e < kTile * kDepth; e += 256) {
      // W: consecutive invocations read consecutive ab of one row; F: consecutive columns.
      const int w_row = e / kDepth;
      const int w_ab = e % kDepth;
      const int row = row_0 + w_row;
      const int ab = ab_0 + w_ab;
      w_tile[w_ab][w_row] = row < rows && ab < in_count ? weights[row * in_count + ab] : 0.0;
      const int f_ab = e / kTile;
      const int f_column = e % kTile;
      const int column = column_0 + f_column;
      const int fab = ab_0 + f_ab;
      f_tile[f_ab][f_column] = fab < in_count && column < columns ? field[fab * columns + column] : 0.0;
    }
    barrier();
    for (int k = 0; k < kDepth; ++k) {
      float w[4];
      float f[4];
      for (int i = 0; i < 4; ++i) w[i] = w_tile[k][ty + 16 * i];
      for (int j = 0; j < 4; ++j) f[j] = f_tile[k][tx + 16 * j];
      for (int i = 0; i < 4; ++i) {
        for (int j = 0; j < 4; ++j) value[i][j] += w[i] * f[j];
      }
    }
    barrier();
  }
  for (int i = 0; i < 4; ++i) {
    const int row = row_0 + ty + 16 * i;
    if (row >= rows) continue;
    for (int j = 0; j < 4; ++j) {
      const int column = column_0 + tx + 16 * j;
      if (column >= columns) continue;
      const int at = row * columns + column;
      g[at] = value[i][j];
      sum[at] += value[i][j];
    }
  }
}
)glsl";

// The quadrature matrices (cpu::ComputeSource4dQuadrature) on the GPU: one work group per output
// direction cd, an invocation per gathering node ab (strided), which sums over the 4 x 4
// sub-samples of the up to four cells around its node the phase functions of the view and its
// mirror image times the sub-sample's solid angle and the node's hat weight; the row is then
// normalised by its sum (the hats of a sub-sample sum to 1, so the row sums to the CPU's sum
// over sub-samples). Float against the CPU's double, summed per node instead of per sub-sample.
constexpr const char* kQuadratureBody = R"glsl(
layout(std430, binding = 0) buffer WeightBuffer { float weights[]; };  // [medium][cd][ab]
uniform int mu_size;
uniform int phi_size;
const int kSub = 4;  // cpu/source4d_tables.cc, kSubSamples

void main() {
  const int cd = int(gl_WorkGroupID.x);
  const int lane = int(gl_LocalInvocationIndex);
  const int in_count = gather_zeniths * gather_azimuths;
  const float theta_v = GetSource4dNodeAngle(cd / phi_size, mu_size, kPi);
  const float phi_v = GetSource4dNodeAngle(cd % phi_size, phi_size, kPi);
  const float cv = cos(theta_v);
  const float sv = sin(theta_v);
  const float cos_phi_v = cos(phi_v);
  const float sin_phi_v = sin(phi_v);
  const float d_theta = kPi / float(gather_zeniths - 1);
  const float d_phi = kPi / float(gather_azimuths - 1);
  float sum_r = 0.0;
  float sum_m = 0.0;
  for (int ab = lane; ab < in_count; ab += 64) {
    const int a = ab / gather_azimuths;
    const int b = ab % gather_azimuths;
    float wr = 0.0;
    float wm = 0.0;
    for (int ca = max(a - 1, 0); ca <= min(a, gather_zeniths - 2); ++ca) {
      for (int cb = max(b - 1, 0); cb <= min(b, gather_azimuths - 2); ++cb) {
        for (int u = 0; u < kSub; ++u) {
          const float fu = (float(u) + 0.5) / float(kSub);
          const float theta = (float(ca) + fu) * d_theta;
          const float cos_theta = cos(theta);
          const float sin_theta = sin(theta);
          const float hat_u = a == ca + 1 ? fu : 1.0 - fu;
          const float solid_angle = sin_theta * d_theta * d_phi / float(kSub * kSub);
          for (int v = 0; v < kSub; ++v) {
            const float fv = (float(v) + 0.5) / float(kSub);
            const float phi = (float(cb) + fv) * d_phi;
            const float cos_phi = cos(phi);
            const float sin_phi = sin(phi);
            const float hat = hat_u * (b == cb + 1 ? fv : 1.0 - fv);
            // The view and its mirror image: cos(phi - phi_v) and cos(phi + phi_v).
            const float nu_0 = ClampCosine(cv * cos_theta + sv * sin_theta * (cos_phi * cos_phi_v + sin_phi * sin_phi_v));
            const float nu_1 = ClampCosine(cv * cos_theta + sv * sin_theta * (cos_phi * cos_phi_v - sin_phi * sin_phi_v));
            const float w = solid_angle * hat;
            wr += w * (GetRayleighPhase(atmosphere, nu_0) + GetRayleighPhase(atmosphere, nu_1));
            wm += w * (GetMiePhase(atmosphere, nu_0) + GetMiePhase(atmosphere, nu_1));
          }
        }
      }
    }
    weights[cd * in_count + ab] = wr;
    weights[(out_count + cd) * in_count + ab] = wm;
    sum_r += wr;
    sum_m += wm;
  }
  vec3 sums = vec3(sum_r, sum_m, 0.0);
  vec3 unused = vec3(0.0);
  SumOverWorkGroup(lane, sums, unused);
  const float total_r = sums.x;
  const float total_m = sums.y;
  for (int ab = lane; ab < in_count; ab += 64) {  // this invocation's own writes, read back
    weights[cd * in_count + ab] /= total_r;
    weights[(out_count + cd) * in_count + ab] /= total_m;
  }
}
)glsl";

std::string QuadratureMain() { return std::string(kWorkGroupSumSource) + kQuadratureBody; }

// One invocation per sun-zenith node: the ground node's irradiance from the field
// (GroundIrradiance), kept as this order's (slot), added to the sum and written as the table
// that the next gathering reads.
constexpr const char* kGroundMain = R"glsl(
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer FieldBuffer { float field[]; };
layout(std430, binding = 1) readonly buffer IrradianceWeightBuffer { float irradiance_weights[]; };
layout(std430, binding = 2) buffer IrradianceBuffer { float irradiance[]; };  // [slot 0, slot 1, sum][j][channel]
layout(rgba32f, binding = 0) uniform writeonly image2D irradiance_image;
uniform int in_count;
uniform int slot;

void main() {
  int j = int(gl_GlobalInvocationID.x);
  if (j >= mu_s_size) return;
  vec3 e = vec3(0.0);
  for (int ab = 0; ab < in_count; ++ab) {
    float w = irradiance_weights[ab];
    if (w == 0.0) continue;
    int at = ab * columns + 3 * j;  // node i = 0: the ground
    e += w * vec3(field[at], field[at + 1], field[at + 2]);
  }
  for (int c = 0; c < 3; ++c) {
    irradiance[(slot * mu_s_size + j) * 3 + c] = e[c];
    irradiance[(2 * mu_s_size + j) * 3 + c] += e[c];
  }
  imageStore(irradiance_image, ivec2(j, 0), vec4(e, 1.0));
}
)glsl";

// One invocation per column: the geometric tail of the orders above the last, G^(N) q / (1 - q)
// with q the ratio of the last two orders' Rayleigh G summed over directions, added to both sums.
constexpr const char* kTailMain = R"glsl(
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer LastBuffer { float last_g[]; };
layout(std430, binding = 1) readonly buffer BeforeBuffer { float before_g[]; };
layout(std430, binding = 2) buffer SumBuffer { float sum[]; };
uniform float max_ratio;

void main() {
  int k = int(gl_GlobalInvocationID.x);
  if (k >= columns) return;
  float last = 0.0;
  float before = 0.0;
  for (int cd = 0; cd < out_count; ++cd) {
    last += last_g[cd * columns + k];
    before += before_g[cd * columns + k];
  }
  float ratio = before > 0.0 ? clamp(last / before, 0.0, max_ratio) : 0.0;
  float factor = ratio / (1.0 - ratio);
  for (int m = 0; m < 2; ++m) {
    for (int cd = 0; cd < out_count; ++cd) {
      int i = (m * out_count + cd) * columns + k;
      sum[i] += factor * last_g[i];
    }
  }
}
)glsl";

// One invocation per sun-zenith node: the sky's ground irradiance table, the sum of the orders
// plus, with `tail`, E^(N-1) q / (1 - q), q = E^(N-1) / E^(N-2) (slots `slot` and 1 - slot).
constexpr const char* kGroundSumMain = R"glsl(
layout(local_size_x = 64) in;
layout(std430, binding = 2) readonly buffer IrradianceBuffer { float irradiance[]; };
layout(rgba32f, binding = 0) uniform writeonly image2D irradiance_image;
uniform int slot;
uniform bool tail;
uniform float max_ratio;

void main() {
  int j = int(gl_GlobalInvocationID.x);
  if (j >= mu_s_size) return;
  vec3 e;
  for (int c = 0; c < 3; ++c) {
    float value = irradiance[(2 * mu_s_size + j) * 3 + c];
    if (tail) {
      float last = irradiance[(slot * mu_s_size + j) * 3 + c];
      float before = irradiance[((1 - slot) * mu_s_size + j) * 3 + c];
      float ratio = before > 0.0 ? clamp(last / before, 0.0, max_ratio) : 0.0;
      value += last * ratio / (1.0 - ratio);
    }
    e[c] = value;
  }
  imageStore(irradiance_image, ivec2(j, 0), vec4(e, 1.0));
}
)glsl";

// One invocation per texel (d, c, node): ln G of both media into the table layout
// (WriteLogTable), below kLogFloor clamped to it.
constexpr const char* kLogMain = R"glsl(
layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;
layout(std430, binding = 0) readonly buffer GBuffer { float g[]; };
layout(rgba32f, binding = 0) uniform writeonly image3D rayleigh_image;
layout(rgba32f, binding = 1) uniform writeonly image3D mie_image;
uniform int phi_size;
uniform int mu_size;

void main() {
  ivec3 texel = ivec3(gl_GlobalInvocationID);
  if (texel.x >= phi_size || texel.y >= mu_size || texel.z >= r_size * mu_s_size) return;
  int at = (texel.y * phi_size + texel.x) * columns + texel.z * 3;
  int mie_at = at + out_count * columns;
  vec3 rayleigh = vec3(g[at], g[at + 1], g[at + 2]);
  vec3 mie = vec3(g[mie_at], g[mie_at + 1], g[mie_at + 2]);
  imageStore(rayleigh_image, texel, vec4(log(max(rayleigh, vec3(1e-30))), 1.0));
  imageStore(mie_image, texel, vec4(log(max(mie, vec3(1e-30))), 1.0));
}
)glsl";

// A shader storage buffer of floats (move-only, deleted with it).
class StorageBuffer {
 public:
  explicit StorageBuffer(const std::vector<float>& values) {
    glCreateBuffers(1, &buffer_);
    glNamedBufferStorage(buffer_, static_cast<GLsizeiptr>(values.size() * sizeof(float)), values.data(),
                         GL_DYNAMIC_STORAGE_BIT);
  }
  explicit StorageBuffer(std::size_t count) : StorageBuffer(std::vector<float>(count, 0.0f)) {}
  ~StorageBuffer() {
    if (buffer_ != 0) glDeleteBuffers(1, &buffer_);
  }
  StorageBuffer(const StorageBuffer&) = delete;
  StorageBuffer& operator=(const StorageBuffer&) = delete;
  void Bind(unsigned binding) const { glBindBufferBase(GL_SHADER_STORAGE_BUFFER, binding, buffer_); }
  std::vector<float> Download(std::size_t count) const {  // waits for the GPU
    std::vector<float> values(count);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    glGetNamedBufferSubData(buffer_, 0, static_cast<GLsizeiptr>(count * sizeof(float)), values.data());
    return values;
  }

 private:
  GLuint buffer_ = 0;
};

const ComputeProgram& BuilderProgram(const Context& context, const char* main_source, const char* name,
                                     double& compile_ms) {
  double ms = 0.0;
  const ComputeProgram& program =
      context.Program({"definitions.glsl", "geometry.glsl", "medium.glsl", "phase.glsl", "transmittance.glsl",
                       "multiple_scattering.glsl", "sun.glsl", "sky.glsl", "camera.glsl", "source4d.glsl"},
                      std::string(kBuilderHeader) + main_source, name, &ms);
  compile_ms += ms;
  return program;
}


int GroupCount1D(long long count) { return static_cast<int>((count + kGroupSize1D - 1) / kGroupSize1D); }

// The quadrature matrices on the GPU into `weights` ((2 out_count) x in_count floats).
void RunQuadraturePass(const Context& context, const shared::AtmosphereParameters& km, const cpu::Source4dSettings& t,
                       const StorageBuffer& weights, double& compile_ms) {
  const ComputeProgram& p = BuilderProgram(context, QuadratureMain().c_str(), "source4d quadrature", compile_ms);
  p.Use();
  SetAtmosphereUniforms(p, "atmosphere", km);
  p.SetInt("gather_zeniths", t.gather_zeniths);
  p.SetInt("gather_azimuths", t.gather_azimuths);
  p.SetInt("out_count", t.mu_size * t.phi_size);
  p.SetInt("mu_size", t.mu_size);
  p.SetInt("phi_size", t.phi_size);
  weights.Bind(0);
  DispatchWorkGroups(p, {t.mu_size * t.phi_size, 1, 1});
}

// A matrix-product work group (a 64 x 64 tile of G over all 441 gathering directions by default)
// is 4x the work of the product's invocations of 64 gathering steps' (a gathering work group): its
// steps are 32x fewer work groups, so that every step takes a few ms on llvmpipe.
constexpr int kConvolveStepDivisor = 32;

// The builder's work on the CPU (the quadrature matrices, which depend only on the phase
// functions) and its time.
struct Source4dHostParts {
  cpu::Source4dQuadrature quadrature;
  double quadrature_ms = 0.0;
};

Source4dHostParts ComputeHostParts(const shared::AtmosphereParameters& km, const cpu::Source4dSettings& settings) {
  Source4dHostParts parts;
  auto start = std::chrono::steady_clock::now();
  const auto since = [&start] {
    const auto now = std::chrono::steady_clock::now();
    const double ms = std::chrono::duration<double, std::milli>(now - start).count();
    start = now;
    return ms;
  };
  parts.quadrature = cpu::ComputeSource4dQuadrature(km, settings);
  parts.quadrature_ms = since();
  return parts;
}

}  // namespace

struct Source4dTablesBuilder::State {
  State(const Context& c, const shared::AtmosphereParameters& k, const cpu::Source4dSettings& s)
      : context(c), km(k), settings(s) {}
  const Context& context;
  shared::AtmosphereParameters km;
  cpu::Source4dSettings settings;
  const ComputeProgram* gather = nullptr;
  const ComputeProgram* convolve = nullptr;
  bool gpu_quadrature = false;  // the matrices on the GPU (else on the CPU, on a thread)
  const ComputeProgram* ground = nullptr;
  const ComputeProgram* tail = nullptr;
  const ComputeProgram* ground_sum = nullptr;
  const ComputeProgram* log_table = nullptr;
  Source4dTablesGl tables;
  // The CPU's part: on a thread of its own when the builder steps (the window keeps drawing), else
  // run by the first step.
  std::future<Source4dHostParts> host;
  // Made by the CPU stage (the quadrature's sizes): the weights, the field of the order being
  // gathered, G of this order and the one before, their sum, the ground irradiance per order.
  int out_count = 0;
  int in_count = 0;
  std::unique_ptr<StorageBuffer> weights;
  std::unique_ptr<StorageBuffer> irradiance_weights;
  std::unique_ptr<StorageBuffer> field;
  std::unique_ptr<StorageBuffer> g[2];
  std::unique_ptr<StorageBuffer> sum;
  std::unique_ptr<StorageBuffer> irradiance;
  GpuTexture order_r;
  GpuTexture order_m;
  GpuTexture order_irradiance;
  struct Stage {
    std::string name;  // the pass it belongs to (timings)
    int groups;        // work groups of its dispatch; 1 for a stage that runs whole
    int groups_per_step;  // 0: all
    // Runs the step; false when it could not yet (the CPU's part still running: tried again).
    std::function<bool(int first_group, int group_count, PassTimings* timings)> run;
    bool host = false;  // times itself (the CPU's part), instead of a GpuPassTimer
  };
  std::vector<Stage> stages;
  std::size_t stage = 0;
  int next_group = 0;
  std::size_t steps_done = 0;
  std::size_t steps_total = 0;
};

Source4dTablesBuilder::Source4dTablesBuilder(const Context& context, const shared::AtmosphereParameters& km_atmosphere,
                                             const cpu::Source4dSettings& settings, int groups_per_step,
                                             PassTimings* timings)
    : state_(std::make_unique<State>(context, km_atmosphere, settings)) {
  const cpu::Source4dSettings& t = settings;
  const int nodes = t.r_size * t.mu_s_size;
  const int columns = nodes * 3;
  const long long gather_count = static_cast<long long>(nodes) * t.gather_zeniths * t.gather_azimuths;
  const long long convolve_groups = ((2LL * t.mu_size * t.phi_size + kConvolveTile - 1) / kConvolveTile) *
                                    ((columns + kConvolveTile - 1) / kConvolveTile);
  if (gather_count > 65535LL * kGroupSize1D || convolve_groups > 65535LL) {
    throw Error("GL source4d: table " + std::to_string(t.r_size) + "x" + std::to_string(t.mu_size) + "x" +
                std::to_string(t.mu_s_size) + "x" + std::to_string(t.phi_size) + " with gather " +
                std::to_string(t.gather_zeniths) + "x" + std::to_string(t.gather_azimuths) +
                " needs more than 65535 work groups in one pass; use --backend cpu");
  }
  context.MakeCurrent();
  State& s = *state_;
  double compile_ms = 0.0;
  s.gather = &BuilderProgram(context, kGatherMain, "source4d gather", compile_ms);
  s.convolve = &BuilderProgram(context, kConvolveMain, "source4d convolve", compile_ms);
  s.ground = &BuilderProgram(context, kGroundMain, "source4d ground", compile_ms);
  s.tail = &BuilderProgram(context, kTailMain, "source4d tail", compile_ms);
  s.ground_sum = &BuilderProgram(context, kGroundSumMain, "source4d ground sum", compile_ms);
  s.log_table = &BuilderProgram(context, kLogMain, "source4d log table", compile_ms);
  if (!context.software_renderer()) {
    BuilderProgram(context, QuadratureMain().c_str(), "source4d quadrature", compile_ms);
  }
  if (timings != nullptr) timings->Add("source4d_gl_compile", compile_ms);
  s.tables.mu_s_size = t.mu_s_size;

  // Every step sets all the uniforms and bindings it uses: between steps other passes (a viewer's
  // frames, another builder) use the same programs and units.
  const auto use = [&s, columns](const ComputeProgram& program) {
    program.Use();
    SetAtmosphereUniforms(program, "atmosphere", s.km);
    program.SetInt("r_size", s.settings.r_size);
    program.SetInt("mu_s_size", s.settings.mu_s_size);
    program.SetInt("gather_zeniths", s.settings.gather_zeniths);
    program.SetInt("gather_azimuths", s.settings.gather_azimuths);
    program.SetInt("out_count", s.out_count);
    program.SetInt("columns", columns);
  };
  // A stage of `groups` work groups, `per_step` of them a step (0: whole).
  const auto add_part = [&s](std::string name, int groups, int per_step, std::function<void(int, int)> run) {
    s.stages.push_back({std::move(name), groups, per_step, [run = std::move(run)](int first, int count, PassTimings*) {
                          run(first, count);
                          return true;
                        }});
  };
  const auto add = [&add_part](std::string name, int groups, std::function<void(int, int)> run) {
    add_part(std::move(name), groups, 0, std::move(run));
  };
  // A 1D pass over invocations [64 first, 64 (first + count)) of its whole dispatch.
  const auto dispatch_part = [](const ComputeProgram& program, int first_group, int group_count) {
    program.SetInt("id_offset", first_group * kGroupSize1D);
    DispatchWorkGroups(program, {group_count, 1, 1});
  };

  // The transmittance table on the GPU: the kernel of hillaire's table (RunTransmittancePass),
  // the same texel function as the CPU's ComputeTransmittanceTable, in float. On an H200 the CPU's
  // table took 10 ms on 16 cores of the tables' 27 ms.
  add("source4d_transmittance_lut", 1, [&s](int, int) {
    s.tables.transmittance = GpuTexture::Make2D({s.settings.transmittance_lut.x, s.settings.transmittance_lut.y});
    RunTransmittancePass(s.context, s.km, s.settings.transmittance_samples, s.tables.transmittance);
  });
  // The buffers of the orders, once the quadrature's sizes are known.
  const auto allocate = [&s, nodes, columns](int out_count, int in_count, const std::vector<double>& irradiance) {
    s.out_count = out_count;
    s.in_count = in_count;
    s.irradiance_weights = std::make_unique<StorageBuffer>(std::vector<float>(irradiance.begin(), irradiance.end()));
    const std::size_t g_size = 2 * static_cast<std::size_t>(out_count) * columns;
    s.field = std::make_unique<StorageBuffer>(static_cast<std::size_t>(in_count) * columns);
    s.g[0] = std::make_unique<StorageBuffer>(g_size);
    s.g[1] = std::make_unique<StorageBuffer>(g_size);
    s.sum = std::make_unique<StorageBuffer>(g_size);
    s.irradiance = std::make_unique<StorageBuffer>(3 * static_cast<std::size_t>(s.settings.mu_s_size) * 3);
    const shared::ivec3 table_size(s.settings.phi_size, s.settings.mu_size, nodes);
    s.order_r = GpuTexture::Make3D(table_size);
    s.order_m = GpuTexture::Make3D(table_size);
    s.order_irradiance = GpuTexture::Make2D({s.settings.mu_s_size, 1});
    s.tables.rayleigh = GpuTexture::Make3D(table_size);
    s.tables.mie = GpuTexture::Make3D(table_size);
    s.tables.ground_irradiance = GpuTexture::Make2D({s.settings.mu_s_size, 1});
  };
  // The quadrature matrices: on a GPU by its own pass (on an H200 the CPU's took 4 to 7 ms on 16
  // cores, the GPU's 0.23 ms); on a software GL by the CPU on a thread while the transmittance
  // table is built (on llvmpipe the pass took ~34 ms, the CPU's double loops 15 ms).
  s.gpu_quadrature = !context.software_renderer();
  if (s.gpu_quadrature) {
    add("source4d_quadrature", 1, [&s, allocate](int, int) {
      const cpu::Source4dSettings& t = s.settings;
      allocate(t.mu_size * t.phi_size, t.gather_zeniths * t.gather_azimuths, cpu::ComputeSource4dIrradianceWeights(t));
      s.weights = std::make_unique<StorageBuffer>(2 * static_cast<std::size_t>(s.out_count) * s.in_count);
      double compile_ms = 0.0;
      RunQuadraturePass(s.context, s.km, t, *s.weights, compile_ms);
    });
  } else {
    s.host = std::async(groups_per_step > 0 ? std::launch::async : std::launch::deferred, ComputeHostParts, s.km,
                        s.settings);
    State::Stage host_stage;
    host_stage.name = "cpu_source4d";
    host_stage.groups = 1;
    host_stage.groups_per_step = 0;
    host_stage.host = true;
    host_stage.run = [&s, allocate, groups_per_step](int, int, PassTimings* timings) {
      if (groups_per_step > 0 && s.host.wait_for(std::chrono::milliseconds(1)) != std::future_status::ready) {
        return false;
      }
      const auto start = std::chrono::steady_clock::now();
      const Source4dHostParts parts = s.host.get();
      const cpu::Source4dQuadrature& q = parts.quadrature;
      std::vector<float> weights = q.rayleigh;
      weights.insert(weights.end(), q.mie.begin(), q.mie.end());
      s.weights = std::make_unique<StorageBuffer>(weights);
      allocate(q.out_count, q.in_count, q.irradiance);
      const double upload_ms =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      if (timings != nullptr) timings->Add("cpu_source4d_quadrature", parts.quadrature_ms + upload_ms);
      return true;
    };
    s.stages.push_back(std::move(host_stage));
  }

  const int gather_groups = GroupCount1D(gather_count);
  const int convolve_per_step = groups_per_step <= 0 ? 0 : std::max(1, groups_per_step / kConvolveStepDivisor);
  const auto add_gather = [&](int order) {
    add_part("source4d_gather_" + std::to_string(order), gather_groups, groups_per_step,
        [&s, use, dispatch_part, order](int first, int count) {
          const ComputeProgram& p = *s.gather;
          use(p);
          p.SetInt("gather_samples", s.settings.gather_samples);
          p.SetInt("order", order);
          BindSamplers(p, {{"transmittance_texture", &s.tables.transmittance},
                           {"rayleigh_texture", &s.order_r},
                           {"mie_texture", &s.order_m},
                           {"irradiance_texture", &s.order_irradiance}});
          s.field->Bind(0);
          dispatch_part(p, first, count);
        });
  };
  // ln G of buffer `g` (an index into s.g, or -1: the sum) into this order's tables or (final)
  // the model's.
  const auto write_log = [&s, use](int g, bool final) {
    const ComputeProgram& p = *s.log_table;
    use(p);
    p.SetInt("phi_size", s.settings.phi_size);
    p.SetInt("mu_size", s.settings.mu_size);
    (g < 0 ? *s.sum : *s.g[g]).Bind(0);
    (final ? s.tables.rayleigh : s.order_r).BindImage(0);
    (final ? s.tables.mie : s.order_m).BindImage(1);
    DispatchCompute3D(p, {s.settings.phi_size, s.settings.mu_size, s.settings.r_size * s.settings.mu_s_size});
  };

  // The orders, as ComputeSource4dTables: g[gi] is this order's G, g[1 - gi] the one before.
  int gi = 0;
  int slot = 0;  // of this order's ground irradiance
  if (t.orders >= 2) add_gather(1);
  for (int n = 2; n <= t.orders; ++n) {
    gi = 1 - gi;
    slot = 1 - slot;
    const std::string name = "source4d_convolve_" + std::to_string(n);
    add_part(name, static_cast<int>(convolve_groups), convolve_per_step, [&s, use, gi](int first, int count) {
      const ComputeProgram& p = *s.convolve;
      use(p);
      p.SetInt("in_count", s.in_count);
      p.SetInt("group_offset", first);
      s.field->Bind(0);
      s.weights->Bind(1);
      s.g[gi]->Bind(2);
      s.sum->Bind(3);
      DispatchWorkGroups(p, {count, 1, 1});
    });
    add(name, 1, [&s, use, slot](int, int) {
      const ComputeProgram& p = *s.ground;
      use(p);
      p.SetInt("in_count", s.in_count);
      p.SetInt("slot", slot);
      s.field->Bind(0);
      s.irradiance_weights->Bind(1);
      s.irradiance->Bind(2);
      s.order_irradiance.BindImage(0);
      DispatchCompute1D(p, s.settings.mu_s_size);
    });
    if (n == t.orders) break;
    add("source4d_gather_" + std::to_string(n), 1, [write_log, gi](int, int) { write_log(gi, false); });
    add_gather(n);
  }
  const bool with_tail = t.tail && t.orders >= 3;
  add("source4d_sum", 1, [&s, use, write_log, gi, slot, with_tail, columns](int, int) {
    if (with_tail) {
      const ComputeProgram& p = *s.tail;
      use(p);
      p.SetFloat("max_ratio", cpu::kSource4dMaxTailRatio);
      s.g[gi]->Bind(0);
      s.g[1 - gi]->Bind(1);
      s.sum->Bind(2);
      DispatchCompute1D(p, columns);
    }
    write_log(-1, true);
    const ComputeProgram& p = *s.ground_sum;
    use(p);
    p.SetFloat("max_ratio", cpu::kSource4dMaxTailRatio);
    p.SetInt("slot", slot);
    p.SetInt("tail", with_tail ? 1 : 0);
    s.irradiance->Bind(2);
    s.tables.ground_irradiance.BindImage(0);
    DispatchCompute1D(p, s.settings.mu_s_size);
  });
  for (const State::Stage& stage : s.stages) {
    const int per_step = stage.groups_per_step <= 0 ? stage.groups : std::min(stage.groups_per_step, stage.groups);
    s.steps_total += static_cast<std::size_t>((stage.groups + per_step - 1) / per_step);
  }
}

Source4dTablesBuilder::~Source4dTablesBuilder() = default;

bool Source4dTablesBuilder::done() const { return state_->stage >= state_->stages.size(); }

double Source4dTablesBuilder::progress() const {
  return static_cast<double>(state_->steps_done) / static_cast<double>(state_->steps_total);
}

cpu::Source4dQuadrature ComputeSource4dQuadratureGl(const Context& context,
                                                    const shared::AtmosphereParameters& km_atmosphere,
                                                    const cpu::Source4dSettings& settings) {
  context.MakeCurrent();
  cpu::Source4dQuadrature q;
  q.out_count = settings.mu_size * settings.phi_size;
  q.in_count = settings.gather_zeniths * settings.gather_azimuths;
  q.irradiance = cpu::ComputeSource4dIrradianceWeights(settings);
  const std::size_t count = static_cast<std::size_t>(q.out_count) * q.in_count;
  const StorageBuffer weights(2 * count);
  double compile_ms = 0.0;
  RunQuadraturePass(context, km_atmosphere, settings, weights, compile_ms);
  const std::vector<float> both = weights.Download(2 * count);
  q.rayleigh.assign(both.begin(), both.begin() + static_cast<std::ptrdiff_t>(count));
  q.mie.assign(both.begin() + static_cast<std::ptrdiff_t>(count), both.end());
  CheckGlError("source4d quadrature");
  return q;
}

std::string Source4dTablesBuilder::next_step_kind() const {
  const State& s = *state_;
  if (done()) return "";
  const State::Stage& stage = s.stages[s.stage];
  if (stage.host) return "host";
  return StepKind(stage.name, stage.groups_per_step <= 0 || stage.groups <= 1);
}

void Source4dTablesBuilder::Step(PassTimings* timings) {
  State& s = *state_;
  if (done()) return;
  s.context.MakeCurrent();
  const State::Stage& stage = s.stages[s.stage];
  const int per_step = stage.groups_per_step <= 0 ? stage.groups : std::min(stage.groups_per_step, stage.groups);
  const int count = std::min(per_step, stage.groups - s.next_group);
  if (stage.host) {
    if (!stage.run(s.next_group, count, timings)) return;  // the CPU's part is still running
  } else {
    GpuPassTimer timer(timings);
    stage.run(s.next_group, count, timings);
    timer.Stop(stage.name);
  }
  s.next_group += count;
  ++s.steps_done;
  if (s.next_group >= stage.groups) {
    ++s.stage;
    s.next_group = 0;
  }
  if (done()) {
    // The temporaries are no longer read.
    s.weights.reset();
    s.irradiance_weights.reset();
    s.field.reset();
    s.g[0].reset();
    s.g[1].reset();
    s.sum.reset();
    s.irradiance.reset();
    s.order_r = {};
    s.order_m = {};
    s.order_irradiance = {};
    CheckGlError("source4d tables");
  }
}

Source4dTablesGl Source4dTablesBuilder::Take() {
  if (!done()) throw Error("GL source4d: the tables are not complete");
  return std::move(state_->tables);
}

Source4dTablesGl ComputeSource4dTablesGl(const Context& context, const shared::AtmosphereParameters& km_atmosphere,
                                         const cpu::Source4dSettings& settings, PassTimings* timings) {
  Source4dTablesBuilder builder(context, km_atmosphere, settings, /*groups_per_step=*/0, timings);
  while (!builder.done()) builder.Step(timings);
  return builder.Take();
}

void PrecomputeSource4dGl(const Context& context, Source4dModel& model, PassTimings* timings) {
  for (std::size_t b = 0; b < model.batches().size(); ++b) {
    const Source4dTablesGl gl =
        ComputeSource4dTablesGl(context, ToSharedParameters(model.parameters(), b, 1000.0), model.settings().tables,
                                timings);
    cpu::Source4dTables tables;
    tables.transmittance = gl.transmittance.Download2D();
    tables.rayleigh = gl.rayleigh.Download3D();
    tables.mie = gl.mie.Download3D();
    tables.ground_irradiance = gl.ground_irradiance.Download2D();
    tables.mu_s_size = gl.mu_s_size;
    model.SetComputedTables(b, std::move(tables));
  }
}

}  // namespace atmo::gl
