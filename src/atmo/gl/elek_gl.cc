#include "gl/elek_gl.h"

#include <algorithm>
#include <chrono>
#include <functional>
#include <cmath>
#include <string>
#include <string_view>
#include <utility>

#include <epoxy/gl.h>

#include "atmo/error.h"
#include "cpu/camera.h"
#include "gl/hillaire_gl.h"
#include "gl/program.h"
#include "physics/shared_parameters.h"

namespace atmo::gl {
namespace {

using Clock = std::chrono::steady_clock;

double MillisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// Every elek pass compiles the same shared files (in shared.h's order): elek.glsl reads the
// transmittance (transmittance.glsl), the phases (phase.glsl) and, for the radiance lookup, the
// atmosphere entry of sky.glsl; the frame adds the camera.
const ComputeProgram& ElekProgram(const Context& context, const std::string& main_source, const char* name,
                                  double& compile_ms) {
  double ms = 0.0;
  const ComputeProgram& program =
      context.Program({"definitions.glsl", "geometry.glsl", "medium.glsl", "phase.glsl", "transmittance.glsl",
                       "multiple_scattering.glsl", "sun.glsl", "sky.glsl", "camera.glsl", "elek.glsl"},
                      main_source, name, &ms);
  compile_ms += ms;
  return program;
}

// The declarations of the 3D table passes (work groups of kGroupSize3D^3 = 4 x 4 x 4).
// ElekStoredTexel is the CPU's Store (cpu/elek_tables.cc): what would be a subnormal float
// (|x| < 1e-30, far below any visible radiance) is stored as 0.
constexpr const char* kTable3DHeader = R"glsl(
layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;
uniform AtmosphereParameters atmosphere;
// A dispatch may cover only some work-group rows (y) of its table, from this one on
// (ElekTablesBuilder's steps); 0 for a whole pass.
uniform int group_row_offset;

ivec3 GetElekTexel() { return ivec3(gl_GlobalInvocationID) + ivec3(0, 4 * group_row_offset, 0); }

vec4 ElekStoredTexel(vec3 value) {
  return vec4(mix(value, vec3(0.0), lessThan(abs(value), vec3(1e-30))), 1.0);
}
)glsl";

// Order 1, texel by texel (cpu::ComputeElekSingleScatteringTable).
constexpr const char* kSingleMain = R"glsl(
layout(rgba32f, binding = 0) uniform writeonly image3D rayleigh_table;
layout(rgba32f, binding = 1) uniform writeonly image3D mie_table;
uniform sampler2D transmittance_texture;
uniform int mapping;
uniform int steps;
uniform int sample_count;

void main() {
  ivec3 size = imageSize(rayleigh_table);
  ivec3 texel = GetElekTexel();
  if (any(greaterThanEqual(texel, size))) return;
  vec3 rayleigh;
  vec3 mie;
  ComputeElekSingleScatteringTexel(atmosphere, transmittance_texture, mapping, steps, size, texel, sample_count,
      rayleigh, mie);
  imageStore(rayleigh_table, texel, ElekStoredTexel(rayleigh));
  imageStore(mie_table, texel, ElekStoredTexel(mie));
}
)glsl";

// Order k >= 2 from the gather tables of order k - 1 (cpu::ComputeElekMultipleScatteringTable);
// without the phase gather the same tables are bound to both azimuth slices.
constexpr const char* kScatterMain = R"glsl(
layout(rgba32f, binding = 0) uniform writeonly image3D rayleigh_table;
layout(rgba32f, binding = 1) uniform writeonly image3D mie_table;
uniform sampler3D gather_rayleigh_0;
uniform sampler3D gather_mie_0;
uniform sampler3D gather_rayleigh_pi;
uniform sampler3D gather_mie_pi;
uniform int mapping;
uniform int steps;
uniform int sample_count;

void main() {
  ivec3 size = imageSize(rayleigh_table);
  ivec3 texel = GetElekTexel();
  if (any(greaterThanEqual(texel, size))) return;
  vec3 rayleigh;
  vec3 mie;
  ComputeElekMultipleScatteringTexel(atmosphere, gather_rayleigh_0, gather_mie_0, gather_rayleigh_pi, gather_mie_pi,
      mapping, steps, size, texel, sample_count, rayleigh, mie);
  imageStore(rayleigh_table, texel, ElekStoredTexel(rayleigh));
  imageStore(mie_table, texel, ElekStoredTexel(mie));
}
)glsl";

// The gather matrix, texel (j, y) = ComputeElekGatherWeightTexel of gather row y and table row j
// (Rayleigh in x, Mie in y), not normalised: the gather pass divides by the row sums, as
// cpu::ComputeElekGatherMatrix normalises its rows.
constexpr const char* kGatherMatrixMain = R"glsl(
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform writeonly image2D gather_matrix;
uniform AtmosphereParameters atmosphere;
uniform int mapping;
uniform int point_count;
uniform int azimuth_count;

void main() {
  ivec2 size = imageSize(gather_matrix);  // (table rows, gather rows)
  ivec2 texel = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(texel, size))) return;
  vec2 weight = ComputeElekGatherWeightTexel(atmosphere, mapping, size.y, size.x, texel.y, texel.x, point_count,
      azimuth_count);
  imageStore(gather_matrix, texel, vec4(weight, 0.0, 1.0));
}
)glsl";

// G_c[x, y, z] = sum_j M_c[y][j] I_c[x, j, z] / sum_j M_c[y][j] (cpu::ComputeElekGatherTable;
// `coupled`: I_R + I_M feeds both components).
constexpr const char* kGatherMain = R"glsl(
layout(rgba32f, binding = 0) uniform writeonly image3D gather_rayleigh;
layout(rgba32f, binding = 1) uniform writeonly image3D gather_mie;
layout(rgba32f, binding = 2) uniform readonly image2D gather_matrix;
layout(rgba32f, binding = 3) uniform readonly image3D order_rayleigh;
layout(rgba32f, binding = 4) uniform readonly image3D order_mie;
uniform bool coupled;

void main() {
  ivec3 size = imageSize(gather_rayleigh);  // (W, gather rows, D)
  ivec3 texel = GetElekTexel();
  if (any(greaterThanEqual(texel, size))) return;
  int rows = imageSize(order_rayleigh).y;
  vec2 row_sum = vec2(0.0);
  vec3 rayleigh_sum = vec3(0.0);
  vec3 mie_sum = vec3(0.0);
  for (int j = 0; j < rows; ++j) {
    vec2 m = imageLoad(gather_matrix, ivec2(j, texel.y)).xy;
    vec3 i_r = imageLoad(order_rayleigh, ivec3(texel.x, j, texel.z)).rgb;
    vec3 i_m = imageLoad(order_mie, ivec3(texel.x, j, texel.z)).rgb;
    rayleigh_sum += m.x * (coupled ? i_r + i_m : i_r);
    mie_sum += m.y * (coupled ? i_r + i_m : i_m);
    row_sum += m;
  }
  imageStore(gather_rayleigh, texel, ElekStoredTexel(rayleigh_sum / row_sum.x));
  imageStore(gather_mie, texel, ElekStoredTexel(mie_sum / row_sum.y));
}
)glsl";

// The weights of the phase gather of one azimuth slice, texel (j, y, z) =
// ComputeElekPhaseGatherWeightTexel of gather row y, table row j and the sun cosine of slice z:
// (RR, RM, MR, MM).
constexpr const char* kPhaseWeightsMain = R"glsl(
layout(rgba32f, binding = 0) uniform writeonly image3D weights;
uniform int mapping;
uniform bool opposite_side;
uniform int point_count;
uniform int azimuth_count;

void main() {
  ivec3 size = imageSize(weights);  // (table rows, gather rows, D)
  ivec3 texel = GetElekTexel();
  if (any(greaterThanEqual(texel, size))) return;
  float h;
  float mu;
  float mu_s;
  GetElekHMuMuSFromUvw(atmosphere, mapping, GetElekUvwFromTexel(size, ivec3(0, 0, texel.z)), h, mu, mu_s);
  vec4 weight = ComputeElekPhaseGatherWeightTexel(atmosphere, mapping, size.y, size.x, texel.y, texel.x, mu_s,
      opposite_side, point_count, azimuth_count);
  imageStore(weights, texel, weight);
}
)glsl";

// The phase gather of one slice (cpu::ComputeElekPhaseGatherTables).
constexpr const char* kPhaseGatherMain = R"glsl(
layout(rgba32f, binding = 0) uniform writeonly image3D gather_rayleigh;
layout(rgba32f, binding = 1) uniform writeonly image3D gather_mie;
layout(rgba32f, binding = 2) uniform readonly image3D weights;
layout(rgba32f, binding = 3) uniform readonly image3D order_rayleigh;
layout(rgba32f, binding = 4) uniform readonly image3D order_mie;
uniform bool coupled;

void main() {
  ivec3 size = imageSize(gather_rayleigh);  // (W, gather rows, D)
  ivec3 texel = GetElekTexel();
  if (any(greaterThanEqual(texel, size))) return;
  int rows = imageSize(order_rayleigh).y;
  vec3 rayleigh_sum = vec3(0.0);
  vec3 mie_sum = vec3(0.0);
  for (int j = 0; j < rows; ++j) {
    vec4 k = imageLoad(weights, ivec3(j, texel.y, texel.z));
    vec3 i_r = imageLoad(order_rayleigh, ivec3(texel.x, j, texel.z)).rgb;
    vec3 i_m = imageLoad(order_mie, ivec3(texel.x, j, texel.z)).rgb;
    if (coupled) {
      rayleigh_sum += k.x * i_r + k.y * i_m;
      mie_sum += k.z * i_r + k.w * i_m;
    } else {
      rayleigh_sum += k.x * i_r;
      mie_sum += k.w * i_m;
    }
  }
  imageStore(gather_rayleigh, texel, ElekStoredTexel(rayleigh_sum));
  imageStore(gather_mie, texel, ElekStoredTexel(mie_sum));
}
)glsl";

// The ground (option ground; cpu::ComputeElekGroundIrradiance): E at the sun cosine of slice x of
// a table `table_depth` deep, from the sun (`direct`) or from one order's table.
constexpr const char* kGroundIrradianceMain = R"glsl(
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform writeonly image2D ground_irradiance;
uniform AtmosphereParameters atmosphere;
uniform sampler2D transmittance_texture;
uniform sampler3D rayleigh_table;
uniform sampler3D mie_table;
uniform bool direct;
uniform int mapping;
uniform int azimuth_count;

void main() {
  ivec2 size = imageSize(ground_irradiance);  // (D, 1)
  ivec2 texel = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(texel, size))) return;
  float h;
  float mu;
  float mu_s;
  GetElekHMuMuSFromUvw(atmosphere, mapping, GetElekUvwFromTexel(ivec3(2, 2, size.x), ivec3(0, 0, texel.x)), h, mu,
      mu_s);
  vec3 e = direct ? ComputeElekGroundDirectIrradiance(atmosphere, transmittance_texture, mu_s)
                  : ComputeElekGroundSkyIrradiance(atmosphere, rayleigh_table, mie_table, mapping, mu_s,
                        kElekGroundIntervals, azimuth_count);
  imageStore(ground_irradiance, texel, vec4(e, 1.0));
}
)glsl";

// L_g per texel (cpu::ComputeElekGroundRadianceTable).
constexpr const char* kGroundRadianceMain = R"glsl(
layout(rgba32f, binding = 0) uniform writeonly image3D ground_radiance;
uniform sampler2D transmittance_texture;
uniform sampler2D ground_irradiance;
uniform int mapping;

void main() {
  ivec3 size = imageSize(ground_radiance);
  ivec3 texel = GetElekTexel();
  if (any(greaterThanEqual(texel, size))) return;
  imageStore(ground_radiance, texel, ElekStoredTexel(ComputeElekGroundRadianceTexel(atmosphere,
      transmittance_texture, ground_irradiance, mapping, size, texel)));
}
)glsl";

// gather_c += sum_j M_c[y][j] L_g[x, j, z] / sum_j M_c[y][j] (cpu::AddElekGatheredGround).
constexpr const char* kGroundGatherMain = R"glsl(
layout(rgba32f, binding = 0) uniform image3D gather_rayleigh;
layout(rgba32f, binding = 1) uniform image3D gather_mie;
layout(rgba32f, binding = 2) uniform readonly image2D gather_matrix;
layout(rgba32f, binding = 3) uniform readonly image3D ground_radiance;

void main() {
  ivec3 size = imageSize(gather_rayleigh);  // (W, gather rows, D)
  ivec3 texel = GetElekTexel();
  if (any(greaterThanEqual(texel, size))) return;
  int rows = imageSize(ground_radiance).y;
  vec2 row_sum = vec2(0.0);
  vec3 rayleigh_sum = vec3(0.0);
  vec3 mie_sum = vec3(0.0);
  for (int j = 0; j < rows; ++j) {
    vec2 m = imageLoad(gather_matrix, ivec2(j, texel.y)).xy;
    vec3 l = imageLoad(ground_radiance, ivec3(texel.x, j, texel.z)).rgb;
    rayleigh_sum += m.x * l;
    mie_sum += m.y * l;
    row_sum += m;
  }
  imageStore(gather_rayleigh, texel,
      ElekStoredTexel(imageLoad(gather_rayleigh, texel).rgb + rayleigh_sum / row_sum.x));
  imageStore(gather_mie, texel, ElekStoredTexel(imageLoad(gather_mie, texel).rgb + mie_sum / row_sum.y));
}
)glsl";

// total = order (first_order) or total + order, in the CPU's order of float additions.
constexpr const char* kSumMain = R"glsl(
layout(rgba32f, binding = 0) uniform image3D total_rayleigh;
layout(rgba32f, binding = 1) uniform image3D total_mie;
uniform sampler3D order_rayleigh;
uniform sampler3D order_mie;
uniform bool first_order;

void main() {
  ivec3 size = imageSize(total_rayleigh);
  ivec3 texel = GetElekTexel();
  if (any(greaterThanEqual(texel, size))) return;
  vec3 rayleigh = texelFetch(order_rayleigh, texel, 0).rgb;
  vec3 mie = texelFetch(order_mie, texel, 0).rgb;
  if (!first_order) {
    rayleigh = imageLoad(total_rayleigh, texel).rgb + rayleigh;
    mie = imageLoad(total_mie, texel).rgb + mie;
  }
  imageStore(total_rayleigh, texel, vec4(rayleigh, 1.0));
  imageStore(total_mie, texel, vec4(mie, 1.0));
}
)glsl";

// The frame: what RenderView asks of ElekModel's SkyView (Radiance; no ground), with the same
// cosine clamps, times the solar irradiance. The per-pixel SunDiscRadiance term (uniform
// sun_disc) stays for interactive use; RenderElekGl sets it off and adds the disc on the host,
// integrated over the pixels (AddSunDiscOnHost).
constexpr const char* kFrameMain = R"glsl(
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform writeonly image2D output_image;
uniform AtmosphereParameters atmosphere;
uniform sampler2D transmittance_texture;
uniform sampler3D rayleigh_table;
uniform sampler3D mie_table;
uniform CameraParameters camera;
uniform int mapping;
uniform bool mie_per_channel;
uniform float r;             // km
uniform vec3 sun_direction;  // unit, local frame (x east, y north, z up)
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
    float nu = dot(direction, sun_direction);
    radiance = GetElekRadiance(atmosphere, rayleigh_table, mie_table, mapping, mie_per_channel, r, mu,
        ClampCosine(sun_direction.z), ClampCosine(nu));
    if (sun_disc) {
      radiance += GetSunDiscRadiance(atmosphere, transmittance_texture, r, mu, nu);
    }
  }
  imageStore(output_image, pixel, vec4(radiance * solar_irradiance, seen ? 1.0 : 0.0));
}
)glsl";

// The programs of the table passes, compiled (or taken from the context's cache) before any pass
// is timed.
struct ElekPrograms {
  const ComputeProgram* single = nullptr;
  const ComputeProgram* scatter = nullptr;
  const ComputeProgram* gather_matrix = nullptr;
  const ComputeProgram* gather = nullptr;
  const ComputeProgram* phase_weights = nullptr;
  const ComputeProgram* phase_gather = nullptr;
  const ComputeProgram* sum = nullptr;
  const ComputeProgram* ground_irradiance = nullptr;
  const ComputeProgram* ground_radiance = nullptr;
  const ComputeProgram* ground_gather = nullptr;
};

std::string Table3D(const char* main_source) { return std::string(kTable3DHeader) + main_source; }

ElekPrograms GetElekPrograms(const Context& context, const ElekSettings& settings, bool ground, double& compile_ms) {
  ElekPrograms p;
  p.single = &ElekProgram(context, Table3D(kSingleMain), "elek single scattering", compile_ms);
  p.sum = &ElekProgram(context, Table3D(kSumMain), "elek sum", compile_ms);
  if (settings.orders >= 2) {
    p.scatter = &ElekProgram(context, Table3D(kScatterMain), "elek multiple scattering", compile_ms);
    p.gather_matrix = &ElekProgram(context, kGatherMatrixMain, "elek gather matrix", compile_ms);
    p.gather = &ElekProgram(context, Table3D(kGatherMain), "elek gather", compile_ms);
    if (settings.phase_gather) {
      p.phase_weights = &ElekProgram(context, Table3D(kPhaseWeightsMain), "elek phase gather weights", compile_ms);
      p.phase_gather = &ElekProgram(context, Table3D(kPhaseGatherMain), "elek phase gather", compile_ms);
    }
    if (ground) {
      p.ground_irradiance = &ElekProgram(context, kGroundIrradianceMain, "elek ground irradiance", compile_ms);
      p.ground_radiance = &ElekProgram(context, Table3D(kGroundRadianceMain), "elek ground radiance", compile_ms);
      p.ground_gather = &ElekProgram(context, Table3D(kGroundGatherMain), "elek ground gather", compile_ms);
    }
  }
  return p;
}

ElekScatteringGl MakeScattering(shared::ivec3 size) { return {GpuTexture::Make3D(size), GpuTexture::Make3D(size)}; }

void BindOutputs(const ElekScatteringGl& out) {
  out.rayleigh.BindImage(0);
  out.mie.BindImage(1);
}

// Binds tables to image units 2, 3, ... for imageLoad (units 0 and 1 hold the outputs): the
// matrix products read texels without filtering, and on llvmpipe imageLoad costs a fraction of
// texelFetch (the gather pass of 32x64x32 x 256 rows: 45 ms instead of 260 ms).
void BindInputImages(std::initializer_list<const GpuTexture*> tables) {
  GLuint unit = 2;
  for (const GpuTexture* t : tables) {
    glBindImageTexture(unit++, t->id(), 0, t->is_3d() ? GL_TRUE : GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
  }
}

void CheckSettings(const ElekSettings& s) {
  if (!s.table.empty()) {
    throw Error("the gl backend computes the elek table; option table=" + s.table + " (a loaded table) is CPU-only");
  }
  const bool ok = s.size.x >= 2 && s.size.y >= 2 && s.size.z >= 2 && s.orders >= 1 && s.samples >= 1 &&
                  s.gather_rows >= 2 && (s.gather_points == 1 || s.gather_points == 2 || s.gather_points == 4) &&
                  s.gather_azimuths >= 2 && s.transmittance_lut.x >= 2 && s.transmittance_lut.y >= 2 &&
                  s.transmittance_samples >= 1;
  if (!ok) throw Error("elek settings out of range (see ElekSettings::FromOptions)");
}


}  // namespace

shared::AtmosphereParameters ElekKmAtmosphere(const ElekModel& model, std::size_t batch) {
  shared::AtmosphereParameters km = ToSharedParameters(model.parameters(), batch, 1000.0);
  km.rayleigh_phase = model.batches().at(batch).atmosphere.rayleigh_phase;  // option rayleigh_phase
  return km;
}

// The passes of ElekModel::ComputeTables, in its order, as a list of stages (a pass, or one
// dispatch of a pass with several); a 3D stage runs in steps of some work-group rows.
struct ElekTablesBuilder::State {
  State(const Context& c, const shared::AtmosphereParameters& k, const ElekSettings& s)
      : context(c), km(k), settings(s) {}
  const Context& context;
  shared::AtmosphereParameters km;
  ElekSettings settings;
  ElekPrograms p;
  ElekTablesGl tables;
  GpuTexture matrix;
  // The temporaries of the order being computed.
  ElekScatteringGl gather_0;
  ElekScatteringGl gather_pi;
  GpuTexture weights[2];
  GpuTexture irradiance;
  GpuTexture radiance;
  struct Stage {
    std::string name;  // the pass it belongs to (timings)
    int rows;          // work-group rows (y) of its dispatch; 1 for a stage that runs whole
    std::function<void(int first_row, int row_count)> run;
  };
  std::vector<Stage> stages;
  std::size_t stage = 0;
  int next_row = 0;
  int rows_per_step = 0;
  std::size_t steps_done = 0;
  std::size_t steps_total = 0;
};

namespace {

int GroupRows(int size_y) { return (size_y + kGroupSize3D - 1) / kGroupSize3D; }

// Rows [first_row, first_row + row_count) of work groups of a 3D pass over `size`.
void DispatchRows3D(const ComputeProgram& program, shared::ivec3 size, int first_row, int row_count) {
  program.SetInt("group_row_offset", first_row);
  DispatchWorkGroups(program, {(size.x + kGroupSize3D - 1) / kGroupSize3D, row_count,
                               (size.z + kGroupSize3D - 1) / kGroupSize3D});
}

}  // namespace

ElekTablesBuilder::ElekTablesBuilder(const Context& context, const shared::AtmosphereParameters& km,
                                     const ElekSettings& settings, int rows_per_step, PassTimings* timings)
    : state_(std::make_unique<State>(context, km, settings)) {
  CheckSettings(settings);
  context.MakeCurrent();
  State& s = *state_;
  s.rows_per_step = rows_per_step;
  double compile_ms = 0.0;
  // The ground term where this batch's albedo is above 0 (ElekSettings::UsesGround; a batch of
  // albedo 0 would add 0).
  const bool ground = settings.ground != "off" && settings.orders >= 2 &&
                      (km.ground_albedo.x > 0.0 || km.ground_albedo.y > 0.0 || km.ground_albedo.z > 0.0);
  s.p = GetElekPrograms(context, settings, ground, compile_ms);
  if (timings != nullptr) timings->Add("elek_gl_compile", compile_ms);
  const shared::ivec3 size = settings.size;
  const shared::ivec3 gather_size(size.x, settings.gather_rows, size.z);
  const auto set_ray = [&s](const ComputeProgram& program) {
    SetAtmosphereUniforms(program, "atmosphere", s.km);
    program.SetInt("mapping", s.settings.mapping);
    program.SetInt("steps", s.settings.steps);
    program.SetInt("sample_count", s.settings.samples);
  };
  // Every step sets all the uniforms and bindings it uses: between steps other passes (a viewer's
  // frames) use the same programs and units.
  const auto add = [&s](std::string name, int rows, std::function<void(int, int)> run) {
    s.stages.push_back({std::move(name), rows, std::move(run)});
  };

  // The transmittance table of the sun rays: hillaire's pass (the CPU's cpu::ComputeTransmittanceTable).
  add("elek_transmittance_lut", 1, [&s](int, int) {
    s.tables.transmittance = GpuTexture::Make2D(s.settings.transmittance_lut);
    RunTransmittancePass(s.context, s.km, s.settings.transmittance_samples, s.tables.transmittance);
  });
  add("elek_single_lut", GroupRows(size.y), [&s, set_ray, size](int first, int count) {
    if (first == 0) s.tables.orders.push_back(MakeScattering(size));
    set_ray(*s.p.single);
    BindSamplers(*s.p.single, {{"transmittance_texture", &s.tables.transmittance}});
    BindOutputs(s.tables.orders[0]);
    DispatchRows3D(*s.p.single, size, first, count);
  });
  if (settings.orders >= 2) {
    add("elek_gather_matrix_lut", 1, [&s, size](int, int) {
      s.matrix = GpuTexture::Make2D({size.y, s.settings.gather_rows});
      const ComputeProgram& program = *s.p.gather_matrix;
      SetAtmosphereUniforms(program, "atmosphere", s.km);
      program.SetInt("mapping", s.settings.mapping);
      program.SetInt("point_count", s.settings.gather_points);
      program.SetInt("azimuth_count", s.settings.gather_azimuths);
      s.matrix.BindImage(0);
      DispatchCompute2D(program, s.matrix.size2());
    });
  }
  for (int k = 2; k <= settings.orders; ++k) {
    const bool phase = settings.phase_gather && k == 2;
    const std::string gather_name = "elek_gather_" + std::to_string(k) + "_lut";
    if (phase) {
      // The CPU's point count for the phase gather (ElekModel::ComputeTables): 4 points become 2.
      const int point_count = settings.gather_points == 4 ? 2 : settings.gather_points;
      const shared::ivec3 weights_size(size.y, settings.gather_rows, size.z);
      for (int slice = 0; slice < 2; ++slice) {
        // One weight table per slice, so that no pass overwrites a table an earlier pass reads.
        add(gather_name, GroupRows(weights_size.y), [&s, slice, point_count, weights_size, gather_size](int first,
                                                                                                       int count) {
          if (first == 0) {
            if (slice == 0) {
              s.gather_0 = MakeScattering(gather_size);
              s.gather_pi = MakeScattering(gather_size);
            }
            s.weights[slice] = GpuTexture::Make3D(weights_size);
          }
          const ComputeProgram& program = *s.p.phase_weights;
          SetAtmosphereUniforms(program, "atmosphere", s.km);
          program.SetInt("mapping", s.settings.mapping);
          program.SetInt("point_count", point_count);
          program.SetInt("azimuth_count", s.settings.gather_azimuths);
          program.SetInt("opposite_side", slice);
          s.weights[slice].BindImage(0);
          DispatchRows3D(program, weights_size, first, count);
        });
        add(gather_name, GroupRows(gather_size.y), [&s, slice, k, gather_size](int first, int count) {
          const ElekScatteringGl& previous = s.tables.orders[k - 2];
          const ComputeProgram& program = *s.p.phase_gather;
          SetAtmosphereUniforms(program, "atmosphere", s.km);
          program.SetInt("coupled", s.settings.coupled ? 1 : 0);
          BindInputImages({&s.weights[slice], &previous.rayleigh, &previous.mie});
          BindOutputs(slice == 0 ? s.gather_0 : s.gather_pi);
          DispatchRows3D(program, gather_size, first, count);
        });
      }
    } else {
      add(gather_name, GroupRows(gather_size.y), [&s, k, gather_size](int first, int count) {
        if (first == 0) {
          s.gather_0 = MakeScattering(gather_size);
          s.gather_pi = ElekScatteringGl{};
        }
        const ElekScatteringGl& previous = s.tables.orders[k - 2];
        const ComputeProgram& program = *s.p.gather;
        SetAtmosphereUniforms(program, "atmosphere", s.km);
        program.SetInt("coupled", s.settings.coupled ? 1 : 0);
        BindInputImages({&s.matrix, &previous.rayleigh, &previous.mie});
        BindOutputs(s.gather_0);
        DispatchRows3D(program, gather_size, first, count);
      });
    }
    if (ground) {
      // The ground's light of k - 1 events: the reflection of E^(k-2) (the sun itself for k = 2).
      const std::string ground_name = "elek_ground_" + std::to_string(k) + "_lut";
      add(ground_name, 1, [&s, k, size](int, int) {
        s.irradiance = GpuTexture::Make2D({size.z, 1});
        const ComputeProgram& program = *s.p.ground_irradiance;
        SetAtmosphereUniforms(program, "atmosphere", s.km);
        program.SetInt("direct", k == 2 ? 1 : 0);
        program.SetInt("mapping", s.settings.mapping);
        program.SetInt("azimuth_count", s.settings.gather_azimuths);
        const ElekScatteringGl& source = s.tables.orders[k == 2 ? 0 : k - 3];
        BindSamplers(program, {{"transmittance_texture", &s.tables.transmittance},
                               {"rayleigh_table", &source.rayleigh},
                               {"mie_table", &source.mie}});
        s.irradiance.BindImage(0);
        DispatchCompute2D(program, s.irradiance.size2());
      });
      add(ground_name, GroupRows(size.y), [&s, size](int first, int count) {
        if (first == 0) s.radiance = GpuTexture::Make3D(size);
        const ComputeProgram& program = *s.p.ground_radiance;
        SetAtmosphereUniforms(program, "atmosphere", s.km);
        program.SetInt("mapping", s.settings.mapping);
        BindSamplers(program,
                     {{"transmittance_texture", &s.tables.transmittance}, {"ground_irradiance", &s.irradiance}});
        s.radiance.BindImage(0);
        DispatchRows3D(program, size, first, count);
      });
      for (int slice = 0; slice < (phase ? 2 : 1); ++slice) {
        add(ground_name, GroupRows(gather_size.y), [&s, slice, gather_size](int first, int count) {
          const ElekScatteringGl& gather = slice == 0 ? s.gather_0 : s.gather_pi;
          const ComputeProgram& program = *s.p.ground_gather;
          SetAtmosphereUniforms(program, "atmosphere", s.km);
          glBindImageTexture(0, gather.rayleigh.id(), 0, GL_TRUE, 0, GL_READ_WRITE, GL_RGBA32F);
          glBindImageTexture(1, gather.mie.id(), 0, GL_TRUE, 0, GL_READ_WRITE, GL_RGBA32F);
          BindInputImages({&s.matrix, &s.radiance});
          DispatchRows3D(program, gather_size, first, count);
        });
      }
    }
    add("elek_scatter_" + std::to_string(k) + "_lut", GroupRows(size.y),
        [&s, set_ray, phase, size](int first, int count) {
          if (first == 0) s.tables.orders.push_back(MakeScattering(size));
          const ElekScatteringGl& slice_pi = phase ? s.gather_pi : s.gather_0;
          set_ray(*s.p.scatter);
          BindSamplers(*s.p.scatter, {{"gather_rayleigh_0", &s.gather_0.rayleigh},
                                      {"gather_mie_0", &s.gather_0.mie},
                                      {"gather_rayleigh_pi", &slice_pi.rayleigh},
                                      {"gather_mie_pi", &slice_pi.mie}});
          BindOutputs(s.tables.orders.back());
          DispatchRows3D(*s.p.scatter, size, first, count);
        });
  }
  for (int k = 0; k < settings.orders; ++k) {
    add("elek_sum_lut", GroupRows(size.y), [&s, k, size](int first, int count) {
      if (k == 0 && first == 0) s.tables.total = MakeScattering(size);
      const ComputeProgram& program = *s.p.sum;
      SetAtmosphereUniforms(program, "atmosphere", s.km);
      glBindImageTexture(0, s.tables.total.rayleigh.id(), 0, GL_TRUE, 0, GL_READ_WRITE, GL_RGBA32F);
      glBindImageTexture(1, s.tables.total.mie.id(), 0, GL_TRUE, 0, GL_READ_WRITE, GL_RGBA32F);
      program.SetInt("first_order", k == 0 ? 1 : 0);
      BindSamplers(program, {{"order_rayleigh", &s.tables.orders[k].rayleigh}, {"order_mie", &s.tables.orders[k].mie}});
      DispatchRows3D(program, size, first, count);
    });
  }
  for (const State::Stage& stage : s.stages) {
    const int per_step = rows_per_step <= 0 ? stage.rows : std::min(rows_per_step, stage.rows);
    s.steps_total += static_cast<std::size_t>((stage.rows + per_step - 1) / per_step);
  }
}

ElekTablesBuilder::~ElekTablesBuilder() = default;

bool ElekTablesBuilder::done() const { return state_->stage >= state_->stages.size(); }

double ElekTablesBuilder::progress() const {
  return static_cast<double>(state_->steps_done) / static_cast<double>(state_->steps_total);
}

std::string ElekTablesBuilder::next_step_kind() const {
  const State& s = *state_;
  if (done()) return "";
  const State::Stage& stage = s.stages[s.stage];
  return StepKind(stage.name, s.rows_per_step <= 0 || stage.rows <= s.rows_per_step);
}

void ElekTablesBuilder::Step(PassTimings* timings) {
  State& s = *state_;
  if (done()) return;
  s.context.MakeCurrent();
  const State::Stage& stage = s.stages[s.stage];
  const int per_step = s.rows_per_step <= 0 ? stage.rows : std::min(s.rows_per_step, stage.rows);
  const int count = std::min(per_step, stage.rows - s.next_row);
  GpuPassTimer timer(timings);
  stage.run(s.next_row, count);
  timer.Stop(stage.name);
  s.next_row += count;
  ++s.steps_done;
  if (s.next_row >= stage.rows) {
    ++s.stage;
    s.next_row = 0;
  }
  if (done()) {
    // The temporaries of the last order are no longer read.
    s.gather_0 = {};
    s.gather_pi = {};
    s.weights[0] = {};
    s.weights[1] = {};
    s.irradiance = {};
    s.radiance = {};
    s.matrix = {};
    CheckGlError("elek tables");
  }
}

ElekTablesGl ElekTablesBuilder::Take() {
  if (!done()) throw Error("GL elek: the tables are not complete");
  return std::move(state_->tables);
}

ElekTablesGl ComputeElekTablesGl(const Context& context, const shared::AtmosphereParameters& km,
                                 const ElekSettings& settings, PassTimings* timings) {
  ElekTablesBuilder builder(context, km, settings, /*rows_per_step=*/0, timings);
  while (!builder.done()) builder.Step(timings);
  return builder.Take();
}

void PrecomputeElekGl(const Context& context, ElekModel& model, PassTimings* timings) {
  CheckSettings(model.settings());
  for (std::size_t b = 0; b < model.batches().size(); ++b) {
    ElekTablesGl tables = ComputeElekTablesGl(context, ElekKmAtmosphere(model, b), model.settings(), timings);
    const auto start = Clock::now();
    std::vector<cpu::ElekScattering> orders;
    const auto download = [](const ElekScatteringGl& t) {
      cpu::ElekScattering s;
      s.rayleigh = t.rayleigh.Download3D();
      s.mie = t.mie.Download3D();
      return s;
    };
    for (const ElekScatteringGl& order : tables.orders) orders.push_back(download(order));
    model.SetComputedTables(b, tables.transmittance.Download2D(), std::move(orders), download(tables.total));
    if (timings != nullptr) timings->Add("elek_gl_readback", MillisecondsSince(start));
  }
}

void RunElekFramePass(const Context& context, const shared::AtmosphereParameters& km, const ElekSettings& settings,
                      const ElekTablesGl& tables, const shared::CameraParameters& camera, double r_km,
                      const glm::dvec3& sun_direction, bool sun_disc, const shared::vec3& solar_irradiance,
                      const GpuTexture& out) {
  context.MakeCurrent();
  double compile_ms = 0.0;
  const ComputeProgram& program = ElekProgram(context, kFrameMain, "elek frame", compile_ms);
  SetAtmosphereUniforms(program, "atmosphere", km);
  SetCameraUniforms(program, "camera", camera);
  program.SetInt("mapping", settings.mapping);
  program.SetInt("mie_per_channel", settings.mie_per_channel ? 1 : 0);
  program.SetFloat("r", r_km);
  program.SetVec3("sun_direction", sun_direction);
  program.SetInt("sun_disc", sun_disc ? 1 : 0);
  program.SetVec3("solar_irradiance", solar_irradiance);
  BindSamplers(program, {{"transmittance_texture", &tables.transmittance},
                         {"rayleigh_table", &tables.total.rayleigh},
                         {"mie_table", &tables.total.mie}});
  out.BindImage(0);
  DispatchCompute2D(program, out.size2());
}

Image RenderElekGl(const Context& context, const AtmosphereParameters& parameters, const ElekSettings& settings,
                   const RenderSettings& render, PassTimings* timings) {
  ValidateCamera(render.camera);
  for (const double value : {render.altitude_m, render.sun_elevation_deg, render.sun_azimuth_deg}) {
    if (!std::isfinite(value)) throw Error("altitude and sun angles must be finite");
  }
  const ElekModel model(parameters, settings);  // checks the parameters (spherical, valid)
  CheckSettings(settings);
  if (render.altitude_m < 0.0) throw Error("altitude_m must be >= 0 for model elek");

  double compile_ms = 0.0;
  ElekProgram(context, kFrameMain, "elek frame", compile_ms);  // compiled before any pass is timed
  if (timings != nullptr) timings->Add("elek_gl_compile", compile_ms);
  const glm::dvec3 sun = glm::normalize(SunDirection(render.sun_elevation_deg, render.sun_azimuth_deg));
  const shared::CameraParameters camera = ToSharedCamera(render.camera);
  const std::size_t nc = parameters.channel_count();
  const std::size_t n = static_cast<std::size_t>(camera.width) * camera.height;
  Image image(camera.width, camera.height, static_cast<int>(nc));
  const bool has_alpha = camera.kind == shared::kCameraFisheye;
  if (has_alpha) image.alpha.assign(n, 0.0f);
  const GpuTexture frame = GpuTexture::Make2D({camera.width, camera.height});
  std::vector<shared::Texture2D> transmittance;  // per batch, for the host's sun disc
  // Batch by batch: its tables, its frame pass and the frame's read-back into its channels; the
  // tables of a batch are freed before the next one's are made. Passes of the same name add up
  // over the batches in `timings`.
  for (std::size_t b = 0; b < model.batches().size(); ++b) {
    const shared::AtmosphereParameters km = ElekKmAtmosphere(model, b);
    const ElekTablesGl tables = ComputeElekTablesGl(context, km, settings, timings);
    {
      GpuPassTimer timer(timings);
      RunElekFramePass(context, km, settings, tables, camera, (parameters.ground_radius_m + render.altitude_m) / 1000.0,
                       sun, /*sun_disc=*/false, BatchValues(parameters.solar_irradiance, b), frame);
      timer.Stop("frame_" + std::to_string(camera.width) + "x" + std::to_string(camera.height));
    }
    const std::vector<float> rgba = frame.DownloadRgba();
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t c = 0; c < 3 && 3 * b + c < nc; ++c) image.pixels[nc * i + 3 * b + c] = rgba[4 * i + c];
      if (has_alpha && b == 0) image.alpha[i] = rgba[4 * i + 3];
    }
    if (render.terms.sun_disc) transmittance.push_back(tables.transmittance.Download2D());
  }
  CheckGlError("elek frame");
  if (render.terms.sun_disc) AddSunDiscOnHost(parameters, transmittance, render, image);
  return image;
}

}  // namespace atmo::gl
