#include "gl/source4d_gl.h"

#include <algorithm>
#include <chrono>
#include <cmath>
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

// The view ray of each pixel marched through the tables (GetSource4dRadiance: single scattering
// exactly, orders >= 2 from ln G, the lit ground from the transmittance and the ground
// irradiance), and the disc per pixel for interactive use.
constexpr const char* kSource4dFrameMain = R"glsl(
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform writeonly image2D output_image;
uniform AtmosphereParameters atmosphere;
uniform sampler2D transmittance_texture;
uniform sampler3D rayleigh_texture;
uniform sampler3D mie_texture;
uniform sampler2D irradiance_texture;
uniform int mu_s_size;
uniform int sample_count;
uniform CameraParameters camera;
uniform float r;             // km
uniform vec3 sun_direction;  // unit, local frame (x east, y north, z up)
uniform bool ground;
uniform bool sun_disc;
uniform vec3 solar_irradiance;

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
    vec3 ground_radiance;
    radiance = GetSource4dRadiance(atmosphere, transmittance_texture, rayleigh_texture, mie_texture,
        irradiance_texture, mu_s_size, r, mu, ClampCosine(sun_direction.z), nu, sample_count, ground_radiance);
    if (ground) radiance += ground_radiance;
    if (sun_disc) radiance += GetSunDiscRadiance(atmosphere, transmittance_texture, r, mu, nu);
  }
  imageStore(output_image, pixel, vec4(radiance * solar_irradiance, seen ? 1.0 : 0.0));
}
)glsl";

const ComputeProgram& Source4dFrameProgram(const Context& context, double* compile_ms = nullptr) {
  return context.Program({"definitions.glsl", "geometry.glsl", "medium.glsl", "phase.glsl", "transmittance.glsl",
                          "multiple_scattering.glsl", "sun.glsl", "sky.glsl", "camera.glsl", "source4d.glsl"},
                         kSource4dFrameMain, "source4d frame", compile_ms);
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

void RunSource4dFramePass(const Context& context, const shared::AtmosphereParameters& km_atmosphere,
                          const Source4dTablesGl& tables, int samples, const shared::CameraParameters& camera,
                          double r_km, const glm::dvec3& sun_direction, bool ground, bool sun_disc,
                          const shared::vec3& solar_irradiance, const GpuTexture& out) {
  context.MakeCurrent();
  const ComputeProgram& program = Source4dFrameProgram(context);
  SetAtmosphereUniforms(program, "atmosphere", km_atmosphere);
  SetCameraUniforms(program, "camera", camera);
  program.SetInt("mu_s_size", tables.mu_s_size);
  program.SetInt("sample_count", samples);
  program.SetFloat("r", r_km);
  program.SetVec3("sun_direction", glm::normalize(sun_direction));
  program.SetInt("ground", ground ? 1 : 0);
  program.SetInt("sun_disc", sun_disc ? 1 : 0);
  program.SetVec3("solar_irradiance", solar_irradiance);
  BindSamplers(program, {{"transmittance_texture", &tables.transmittance},
                         {"rayleigh_texture", &tables.rayleigh},
                         {"mie_texture", &tables.mie},
                         {"irradiance_texture", &tables.ground_irradiance}});
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
  Source4dFrameProgram(context, &compile_ms);  // compiled before any pass is timed
  if (timings != nullptr) timings->Add("source4d_gl_compile", compile_ms);

  const shared::CameraParameters camera = ToSharedCamera(render.camera);
  const std::size_t nc = parameters.channel_count();
  const std::size_t n = static_cast<std::size_t>(camera.width) * camera.height;
  Image image(camera.width, camera.height, static_cast<int>(nc));
  const bool has_alpha = camera.kind == shared::kCameraFisheye;
  if (has_alpha) image.alpha.assign(n, 0.0f);
  const GpuTexture frame = GpuTexture::Make2D({camera.width, camera.height});
  const double r_km = (parameters.ground_radius_m + render.altitude_m) / 1000.0;
  std::vector<shared::Texture2D> transmittance;  // per batch, for the host's sun disc
  for (std::size_t b = 0; b < model.batches().size(); ++b) {
    const Source4dTablesGl tables = make_tables(b);
    {
      GpuPassTimer timer(timings);
      RunSource4dFramePass(context, ToSharedParameters(parameters, b, 1000.0), tables, model.settings().samples,
                           camera, r_km, sun, render.terms.ground, /*sun_disc=*/false,
                           BatchValues(parameters.solar_irradiance, b), frame);
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
float GetSource4dNodeMuS(int j) { return cos(GetSource4dSunZenithFromUnit(float(j) / float(mu_s_size - 1))); }
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

void main() {
  int id = int(gl_GlobalInvocationID.x);
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
      path_transmittance);
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

// One invocation per column and block of kSource4dConvolveBlock output directions: G of the next
// order, both media, by the quadrature matrices (Convolve, in the CPU's order of summation over
// the field's directions), added to the sums. A block reads each field value once for all its
// directions (8 times fewer reads than an invocation per direction; on llvmpipe, where the reads
// are strided across invocations, the default table's products ran 1.7x faster at the median).
constexpr int kSource4dConvolveBlock = 8;
constexpr const char* kConvolveMain = R"glsl(
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer FieldBuffer { float field[]; };
layout(std430, binding = 1) readonly buffer WeightBuffer { float weights[]; };  // [medium][cd][ab]
layout(std430, binding = 2) writeonly buffer GBuffer { float g[]; };
layout(std430, binding = 3) buffer SumBuffer { float sum[]; };
uniform int in_count;
const int kBlock = 8;  // kSource4dConvolveBlock

void main() {
  int id = int(gl_GlobalInvocationID.x);
  int blocks = (out_count + kBlock - 1) / kBlock;
  if (id >= blocks * columns) return;
  int k = id % columns;
  int cd_0 = (id / columns) * kBlock;
  int count = min(kBlock, out_count - cd_0);
  for (int m = 0; m < 2; ++m) {
    float value[kBlock];
    for (int q = 0; q < kBlock; ++q) value[q] = 0.0;
    for (int ab = 0; ab < in_count; ++ab) {
      float f = field[ab * columns + k];
      for (int q = 0; q < count; ++q) {
        float w = weights[(m * out_count + cd_0 + q) * in_count + ab];
        if (w != 0.0) value[q] += w * f;
      }
    }
    for (int q = 0; q < count; ++q) {
      int at = (m * out_count + cd_0 + q) * columns + k;
      g[at] = value[q];
      sum[at] += value[q];
    }
  }
}
)glsl";

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

}  // namespace

Source4dTablesGl ComputeSource4dTablesGl(const Context& context, const shared::AtmosphereParameters& km_atmosphere,
                                         const cpu::Source4dSettings& s, PassTimings* timings) {
  context.MakeCurrent();
  const int nodes = s.r_size * s.mu_s_size;
  const int columns = nodes * 3;
  const long long gather_count = static_cast<long long>(nodes) * s.gather_zeniths * s.gather_azimuths;
  const long long convolve_count =
      static_cast<long long>((s.mu_size * s.phi_size + kSource4dConvolveBlock - 1) / kSource4dConvolveBlock) * columns;
  if (std::max(gather_count, convolve_count) > 65535LL * kGroupSize1D) {
    throw Error("GL source4d: table " + std::to_string(s.r_size) + "x" + std::to_string(s.mu_size) + "x" +
                std::to_string(s.mu_s_size) + "x" + std::to_string(s.phi_size) + " with gather " +
                std::to_string(s.gather_zeniths) + "x" + std::to_string(s.gather_azimuths) +
                " needs more than 65535 work groups in one pass; use --backend cpu");
  }
  double compile_ms = 0.0;
  const ComputeProgram& gather = BuilderProgram(context, kGatherMain, "source4d gather", compile_ms);
  const ComputeProgram& convolve = BuilderProgram(context, kConvolveMain, "source4d convolve", compile_ms);
  const ComputeProgram& ground = BuilderProgram(context, kGroundMain, "source4d ground", compile_ms);
  const ComputeProgram& tail = BuilderProgram(context, kTailMain, "source4d tail", compile_ms);
  const ComputeProgram& ground_sum = BuilderProgram(context, kGroundSumMain, "source4d ground sum", compile_ms);
  const ComputeProgram& log_table = BuilderProgram(context, kLogMain, "source4d log table", compile_ms);
  if (timings != nullptr) timings->Add("source4d_gl_compile", compile_ms);

  // On the CPU: the transmittance table and the quadrature matrices (which depend only on the
  // phase functions), uploaded.
  auto start = std::chrono::steady_clock::now();
  const auto note_cpu = [&](const char* pass) {
    if (timings != nullptr) {
      timings->Add(pass, std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    }
    start = std::chrono::steady_clock::now();
  };
  Source4dTablesGl tables;
  tables.mu_s_size = s.mu_s_size;
  {
    shared::Texture2D transmittance(s.transmittance_lut.x, s.transmittance_lut.y);
    cpu::ComputeTransmittanceTable(km_atmosphere, s.transmittance_samples, transmittance);
    tables.transmittance = GpuTexture::Upload(transmittance);
  }
  note_cpu("cpu_source4d_transmittance_lut");
  const cpu::Source4dQuadrature q = cpu::ComputeSource4dQuadrature(km_atmosphere, s);
  std::vector<float> weights = q.rayleigh;
  weights.insert(weights.end(), q.mie.begin(), q.mie.end());
  const StorageBuffer weight_buffer(weights);
  const StorageBuffer irradiance_weights(std::vector<float>(q.irradiance.begin(), q.irradiance.end()));
  note_cpu("cpu_source4d_quadrature");

  const std::size_t g_size = 2 * static_cast<std::size_t>(q.out_count) * columns;
  const StorageBuffer field(static_cast<std::size_t>(q.in_count) * columns);
  const StorageBuffer g_a(g_size), g_b(g_size), sum(g_size);
  const StorageBuffer irradiance(3 * static_cast<std::size_t>(s.mu_s_size) * 3);
  const shared::ivec3 table_size(s.phi_size, s.mu_size, nodes);
  GpuTexture order_r = GpuTexture::Make3D(table_size);
  GpuTexture order_m = GpuTexture::Make3D(table_size);
  const GpuTexture order_irradiance = GpuTexture::Make2D({s.mu_s_size, 1});
  tables.rayleigh = GpuTexture::Make3D(table_size);
  tables.mie = GpuTexture::Make3D(table_size);
  tables.ground_irradiance = GpuTexture::Make2D({s.mu_s_size, 1});

  for (const ComputeProgram* program : {&gather, &convolve, &ground, &tail, &ground_sum, &log_table}) {
    SetAtmosphereUniforms(*program, "atmosphere", km_atmosphere);
    program->SetInt("r_size", s.r_size);
    program->SetInt("mu_s_size", s.mu_s_size);
    program->SetInt("gather_zeniths", s.gather_zeniths);
    program->SetInt("gather_azimuths", s.gather_azimuths);
    program->SetInt("out_count", q.out_count);
    program->SetInt("columns", columns);
  }
  gather.SetInt("gather_samples", s.gather_samples);
  convolve.SetInt("in_count", q.in_count);
  ground.SetInt("in_count", q.in_count);
  tail.SetFloat("max_ratio", cpu::kSource4dMaxTailRatio);
  ground_sum.SetFloat("max_ratio", cpu::kSource4dMaxTailRatio);
  log_table.SetInt("phi_size", s.phi_size);
  log_table.SetInt("mu_size", s.mu_size);

  const auto run_gather = [&](int order) {
    gather.SetInt("order", order);
    BindSamplers(gather, {{"transmittance_texture", &tables.transmittance},
                          {"rayleigh_texture", &order_r},
                          {"mie_texture", &order_m},
                          {"irradiance_texture", &order_irradiance}});
    field.Bind(0);
    DispatchCompute1D(gather, static_cast<int>(gather_count));
  };
  const auto write_log = [&](const StorageBuffer& g, const GpuTexture& rayleigh, const GpuTexture& mie) {
    log_table.Use();
    g.Bind(0);
    rayleigh.BindImage(0);
    mie.BindImage(1);
    DispatchCompute3D(log_table, table_size);
  };

  const StorageBuffer* g = &g_a;         // this order's G
  const StorageBuffer* previous = &g_b;  // the order before
  int slot = 0;                          // of this order's ground irradiance
  GpuPassTimer timer(timings);
  if (s.orders >= 2) {
    run_gather(1);
    timer.Stop("source4d_gather_1");
  }
  for (int n = 2; n <= s.orders; ++n) {
    std::swap(g, previous);
    slot = 1 - slot;
    convolve.Use();
    field.Bind(0);
    weight_buffer.Bind(1);
    g->Bind(2);
    sum.Bind(3);
    DispatchCompute1D(convolve, static_cast<int>(convolve_count));
    ground.Use();
    ground.SetInt("slot", slot);
    field.Bind(0);
    irradiance_weights.Bind(1);
    irradiance.Bind(2);
    order_irradiance.BindImage(0);
    DispatchCompute1D(ground, s.mu_s_size);
    timer.Stop("source4d_convolve_" + std::to_string(n));
    if (n == s.orders) break;
    write_log(*g, order_r, order_m);
    run_gather(n);
    timer.Stop("source4d_gather_" + std::to_string(n));
  }
  const bool with_tail = s.tail && s.orders >= 3;
  if (with_tail) {
    tail.Use();
    g->Bind(0);
    previous->Bind(1);
    sum.Bind(2);
    DispatchCompute1D(tail, columns);
  }
  write_log(sum, tables.rayleigh, tables.mie);
  ground_sum.Use();
  ground_sum.SetInt("slot", slot);
  ground_sum.SetInt("tail", with_tail ? 1 : 0);
  irradiance.Bind(2);
  tables.ground_irradiance.BindImage(0);
  DispatchCompute1D(ground_sum, s.mu_s_size);
  timer.Stop("source4d_sum");
  CheckGlError("source4d tables");
  return tables;
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
