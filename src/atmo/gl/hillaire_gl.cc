#include "gl/hillaire_gl.h"

#include <cmath>
#include <cstddef>
#include <string>
#include <string_view>

#include <epoxy/gl.h>

#include "atmo/error.h"
#include "cpu/camera.h"
#include "cpu/sun_disc.h"
#include "gl/program.h"
#include "io/hillaire_table_file.h"
#include "io/table_files.h"
#include "physics/shared_parameters.h"

namespace atmo::gl {
namespace {

// The shared files of the table passes, and of the passes that read the sky, in shared.h's order.
constexpr std::string_view kTransmittanceFiles[] = {"definitions.glsl", "geometry.glsl", "medium.glsl",
                                                    "transmittance.glsl"};
constexpr std::string_view kMultipleScatteringFiles[] = {"definitions.glsl", "geometry.glsl",
                                                         "medium.glsl",      "phase.glsl",
                                                         "transmittance.glsl", "multiple_scattering.glsl"};
constexpr std::string_view kSkyFiles[] = {"definitions.glsl",   "geometry.glsl",
                                          "medium.glsl",        "phase.glsl",
                                          "transmittance.glsl", "multiple_scattering.glsl",
                                          "sun.glsl",           "sky.glsl",
                                          "camera.glsl"};

// The declarations every table pass shares: one rgba32f output image (unit 0), the atmosphere.
constexpr std::string_view kTablePassHeader = R"glsl(
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform writeonly image2D output_table;
uniform AtmosphereParameters atmosphere;
)glsl";

std::string TablePass(std::string_view body) { return std::string(kTablePassHeader) + std::string(body); }

// The sky seen along a direction, for the frame and the sample passes: the sky-view table or the
// per-direction ray march (HillaireSkyView::Radiance on the CPU).
constexpr std::string_view kSkyRadianceSource = R"glsl(
uniform AtmosphereParameters atmosphere;
uniform sampler2D transmittance_texture;
uniform sampler2D multiple_scattering_texture;
uniform sampler2D ground_irradiance_texture;
uniform sampler2D sky_view_texture;
uniform float r;                    // km
uniform float mu_s;
uniform vec3 sun_direction;         // unit, local frame (x east, y north, z up)
uniform float horizon_nadir_angle;  // GetHorizonNadirAngle(atmosphere, r), radians
uniform int ray_march_samples;

vec3 GetSkyRadianceAlong(vec3 direction) {
#if USE_SKY_VIEW
  float azimuth = GetAzimuthFromSun(direction, sun_direction);
  vec2 uv = GetSkyViewTextureUvFromBeta(textureSize(sky_view_texture, 0), horizon_nadir_angle, direction.z, azimuth);
  return texture(sky_view_texture, uv).rgb;
#else
  vec3 transmittance;
  return IntegrateScatteredRadiance(atmosphere, transmittance_texture, multiple_scattering_texture, r, direction.z,
      mu_s, dot(direction, sun_direction), 1e30, ray_march_samples, transmittance);
#endif
}
)glsl";

// The sky function of the sky-view table or of the ray march: two programs, each without the
// other's code (with a runtime branch, llvmpipe ran the 1920x1080 frame 2.3x slower).
std::string SkyRadianceSource(bool use_sky_view) {
  return std::string("#define USE_SKY_VIEW ") + (use_sky_view ? "1" : "0") + std::string(kSkyRadianceSource);
}

}  // namespace

namespace {

// How a pass lays its texels out over work groups. Each texel's work is split over `ray_slots`
// runs of `segments` invocations: a run marches one ray, each invocation a segment of it (the
// shared files' *Steps functions), and the texel's sums gather over its runs. A work group holds texels_x x texels_y
// texels. A GPU gets many invocations per texel: every pass here is a few thousand texels or
// fewer, each a serial march of 16 to 41 steps, too few threads to hide a step's latency on a
// large chip. On a software rasteriser (Context::work_group_forms() false) a texel per
// invocation: there the barriers cost more than the lanes win (docs/performance.md).
struct TexelLayout {
  int segments = 1;
  int ray_slots = 1;
  int texels_x = 8;
  int texels_y = 8;
};

constexpr TexelLayout kTexelPerInvocation{};

// The GLSL of a layout: the work group's size, GroupTexel(), Segment(), RaySlot(), the steps of
// this invocation's segment (SegmentFirstStep, SegmentEndStep), ThroughputBefore (the product of
// the throughputs of the segments before this one in its run), SumOverTexel (the sums over the
// texel's invocations, in its TexelLead() invocation). Every invocation of a group must call
// ThroughputBefore and SumOverTexel alike (barriers): texels outside the table are computed
// clamped and not stored, never returned from early.
std::string TexelLayoutSource(const TexelLayout& layout) {
  const int lanes_per_texel = layout.segments * layout.ray_slots;
  std::string source = "layout(local_size_x = " + std::to_string(lanes_per_texel * layout.texels_x) +
                       ", local_size_y = " + std::to_string(layout.texels_y) + ") in;\n" +
                       "const int kSegments = " + std::to_string(layout.segments) + ";\n" +
                       "const int kRaySlots = " + std::to_string(layout.ray_slots) + ";\n" +
                       "const int kTexelLanes = " + std::to_string(lanes_per_texel) + ";\n" +
                       "const ivec2 kGroupTexels = ivec2(" + std::to_string(layout.texels_x) + ", " +
                       std::to_string(layout.texels_y) + ");\n";
  source += R"glsl(
int Lane() { return int(gl_LocalInvocationIndex); }
int Segment() { return int(gl_LocalInvocationID.x) % kSegments; }
int RaySlot() { return (int(gl_LocalInvocationID.x) / kSegments) % kRaySlots; }
bool TexelLead() { return int(gl_LocalInvocationID.x) % kTexelLanes == 0; }
ivec2 GroupTexel() {
  return ivec2(gl_WorkGroupID.xy) * kGroupTexels +
      ivec2(int(gl_LocalInvocationID.x) / kTexelLanes, int(gl_LocalInvocationID.y));
}
// Segment s of a march of n steps: steps s n / S ... (s + 1) n / S - 1.
int SegmentFirstStep(int step_count) { return Segment() * step_count / kSegments; }
int SegmentEndStep(int step_count) { return (Segment() + 1) * step_count / kSegments; }
)glsl";
  if (lanes_per_texel == 1) {
    return source + R"glsl(
vec3 ThroughputBefore(vec3 throughput) { return vec3(1.0); }
void SumOverTexel(inout vec3 a, inout vec3 b, inout vec3 c) {}
)glsl";
  }
  return source + R"glsl(
shared vec3 lane_a[gl_WorkGroupSize.x * gl_WorkGroupSize.y];
shared vec3 lane_b[gl_WorkGroupSize.x * gl_WorkGroupSize.y];
shared vec3 lane_c[gl_WorkGroupSize.x * gl_WorkGroupSize.y];

vec3 ThroughputBefore(vec3 throughput) {
  int lane = Lane();
  lane_a[lane] = throughput;
  memoryBarrierShared();
  barrier();
  vec3 product = vec3(1.0);
  for (int j = lane - Segment(); j < lane; ++j) product *= lane_a[j];
  barrier();  // every invocation has read before the array is written again
  return product;
}

// A tree over the texel's kTexelLanes (a power of two) adjacent invocations.
void SumOverTexel(inout vec3 a, inout vec3 b, inout vec3 c) {
  int lane = Lane();
  lane_a[lane] = a;
  lane_b[lane] = b;
  lane_c[lane] = c;
  memoryBarrierShared();
  barrier();
  for (int stride = kTexelLanes / 2; stride > 0; stride /= 2) {
    if (lane % kTexelLanes < stride) {
      lane_a[lane] += lane_a[lane + stride];
      lane_b[lane] += lane_b[lane + stride];
      lane_c[lane] += lane_c[lane + stride];
    }
    memoryBarrierShared();
    barrier();
  }
  a = lane_a[lane];
  b = lane_b[lane];
  c = lane_c[lane];
  barrier();
}
)glsl";
}

void DispatchTexels(const ComputeProgram& program, const TexelLayout& layout, shared::ivec2 texels) {
  DispatchWorkGroups(program, {(texels.x + layout.texels_x - 1) / layout.texels_x,
                               (texels.y + layout.texels_y - 1) / layout.texels_y, 1});
}

// The layouts of the passes on a GPU: a march of 16 to 41 steps in segments of 4 to 8 steps, at
// least 64 invocations per work group. Chosen from the passes' sizes, not yet timed on a GPU
// (docs/performance.md, "On an NVIDIA GPU", has the times of the form before).
TexelLayout TransmittanceLayout(const Context& context) {
  return context.work_group_forms() ? TexelLayout{8, 1, 8, 1} : kTexelPerInvocation;
}
TexelLayout MultipleScatteringLayout(const Context& context) {
  return context.work_group_forms() ? TexelLayout{4, 32, 1, 1} : kTexelPerInvocation;
}
TexelLayout GroundIrradianceLayout(const Context& context) {
  return context.work_group_forms() ? TexelLayout{4, 64, 1, 1} : TexelLayout{1, 1, 8, 1};
}
TexelLayout SkyViewLayout(const Context& context) {
  return context.work_group_forms() ? TexelLayout{4, 1, 8, 8} : kTexelPerInvocation;
}

// SumMultiScatteringRays and SumMultiScatteringGatherRays (multiple_scattering.glsl) over a texel's
// invocations: each ray's segments on a run, each run's rays kRaySlots apart, the sums in the
// texel's lead invocation. With one invocation per texel the same sums in the same order.
constexpr std::string_view kMultipleScatteringSumsSource = R"glsl(
void SumFirstOrderRays(AtmosphereParameters atmosphere, sampler2D transmittance_texture, float r,
    vec3 sun_direction, int direction_count, int sample_count, bool media_phase, vec3 ground_transfer,
    out vec3 luminance_sum, out vec3 transfer_sum, out vec3 irradiance_sum) {
  luminance_sum = vec3(0.0);
  transfer_sum = vec3(0.0);
  irradiance_sum = vec3(0.0);
  bool mirrored = direction_count != 2;
  int marched = mirrored ? direction_count / 2 : direction_count;
  int first_step = SegmentFirstStep(sample_count);
  int end_step = SegmentEndStep(sample_count);
  for (int base = 0; base < marched; base += kRaySlots) {
    int k = base + RaySlot();
    vec3 luminance = vec3(0.0);
    vec3 transfer = vec3(0.0);
    vec3 throughput = vec3(1.0);
    float z = 0.0;
    if (k < marched) {
      vec3 direction = GetMultiScatteringDirection(k, direction_count);
      z = direction.z;
      IntegrateMultiScatteringRaySteps(atmosphere, transmittance_texture, r, direction, sun_direction, sample_count,
          first_step, end_step, media_phase, ground_transfer, luminance, transfer, throughput);
    }
    vec3 before = ThroughputBefore(throughput);
    luminance *= before;
    luminance_sum += luminance;
    transfer_sum += transfer * before;
    irradiance_sum += z > 0.0 ? luminance * z : vec3(0.0);
  }
  if (mirrored) {
    luminance_sum *= 2.0;
    transfer_sum *= 2.0;
    irradiance_sum *= 2.0;
  }
  SumOverTexel(luminance_sum, transfer_sum, irradiance_sum);
}

void SumGatherRays(AtmosphereParameters atmosphere, sampler2D previous_order_texture,
    sampler2D ground_irradiance_texture, float r, vec3 sun_direction, int direction_count, int sample_count,
    out vec3 luminance_sum, out vec3 irradiance_sum) {
  luminance_sum = vec3(0.0);
  irradiance_sum = vec3(0.0);
  bool mirrored = direction_count != 2;
  int marched = mirrored ? direction_count / 2 : direction_count;
  int first_step = SegmentFirstStep(sample_count);
  int end_step = SegmentEndStep(sample_count);
  for (int base = 0; base < marched; base += kRaySlots) {
    int k = base + RaySlot();
    vec3 luminance = vec3(0.0);
    vec3 throughput = vec3(1.0);
    float z = 0.0;
    if (k < marched) {
      vec3 direction = GetMultiScatteringDirection(k, direction_count);
      z = direction.z;
      luminance = IntegrateMultiScatteringGatherRaySteps(atmosphere, previous_order_texture,
          ground_irradiance_texture, r, direction, sun_direction, sample_count, first_step, end_step, throughput);
    }
    luminance *= ThroughputBefore(throughput);
    luminance_sum += luminance;
    irradiance_sum += z > 0.0 ? luminance * z : vec3(0.0);
  }
  if (mirrored) {
    luminance_sum *= 2.0;
    irradiance_sum *= 2.0;
  }
  vec3 unused = vec3(0.0);
  SumOverTexel(luminance_sum, irradiance_sum, unused);
}
)glsl";

}  // namespace

void RunTransmittancePass(const Context& context, const shared::AtmosphereParameters& km, int sample_count,
                          const GpuTexture& out) {
  const TexelLayout layout = TransmittanceLayout(context);
  // The samples of a texel's quadrature are dealt to its invocations in turn (no march: the sum
  // needs no throughput).
  const ComputeProgram& program = context.Program(kTransmittanceFiles, TexelLayoutSource(layout) + R"glsl(
layout(rgba32f, binding = 0) uniform writeonly image2D output_table;
uniform AtmosphereParameters atmosphere;
uniform int sample_count;

void main() {
  ivec2 size = imageSize(output_table);
  ivec2 texel = GroupTexel();
  bool inside = texel.x < size.x && texel.y < size.y;
  texel = min(texel, size - 1);
  float r;
  float mu;
  GetRMuFromTransmittanceTextureUv(atmosphere, size, (vec2(texel) + vec2(0.5)) / vec2(size), r, mu);
  vec3 optical_depth = SumOpticalDepthSamplesToTopAtmosphereBoundary(atmosphere, r, mu, sample_count, Segment(),
      kSegments);
  vec3 unused_b = vec3(0.0);
  vec3 unused_c = vec3(0.0);
  SumOverTexel(optical_depth, unused_b, unused_c);
  if (inside && TexelLead()) imageStore(output_table, texel, vec4(exp(-optical_depth), 1.0));
}
)glsl", "transmittance table");
  SetAtmosphereUniforms(program, "atmosphere", km);
  program.SetInt("sample_count", sample_count);
  out.BindImage(0);
  DispatchTexels(program, layout, out.size2());
}

void RunMultipleScatteringPass(const Context& context, const shared::AtmosphereParameters& km,
                               const GpuTexture& transmittance, int direction_count, int sample_count,
                               bool media_phase, const shared::vec3& ground_transfer, const GpuTexture& out) {
  const TexelLayout layout = MultipleScatteringLayout(context);
  const ComputeProgram& program = context.Program(kMultipleScatteringFiles, TexelLayoutSource(layout) +
      std::string(kMultipleScatteringSumsSource) + R"glsl(
layout(rgba32f, binding = 0) uniform writeonly image2D output_table;
uniform AtmosphereParameters atmosphere;
uniform sampler2D transmittance_texture;
uniform int direction_count;
uniform int sample_count;
uniform bool media_phase;
uniform vec3 ground_transfer;

void main() {
  ivec2 size = imageSize(output_table);
  ivec2 texel = GroupTexel();
  bool inside = texel.x < size.x && texel.y < size.y;
  texel = min(texel, size - 1);
  float r;
  vec3 sun_direction;
  GetMultiScatteringTexelPoint(atmosphere, size, vec2(texel) + vec2(0.5), r, sun_direction);
  vec3 luminance_sum;
  vec3 transfer_sum;
  vec3 unused_irradiance_sum;
  SumFirstOrderRays(atmosphere, transmittance_texture, r, sun_direction, direction_count, sample_count, media_phase,
      ground_transfer, luminance_sum, transfer_sum, unused_irradiance_sum);
  if (inside && TexelLead()) {
    vec3 psi_ms = GetMultiScatteringFromMeans(luminance_sum / float(direction_count),
        transfer_sum / float(direction_count));
    imageStore(output_table, texel, vec4(EncodeMultiScattering(psi_ms), 1.0));
  }
}
)glsl", "multiple-scattering table");
  SetAtmosphereUniforms(program, "atmosphere", km);
  program.SetInt("direction_count", direction_count);
  program.SetInt("sample_count", sample_count);
  program.SetInt("media_phase", media_phase ? 1 : 0);
  program.SetVec3("ground_transfer", ground_transfer);
  BindSamplers(program, {{"transmittance_texture", &transmittance}});
  out.BindImage(0);
  DispatchTexels(program, layout, out.size2());
}

void RunGatheredMultipleScatteringPasses(const Context& context, const shared::AtmosphereParameters& km,
                                         const GpuTexture& transmittance, int direction_count, int sample_count,
                                         bool media_phase, const shared::vec3& ground_transfer, int orders,
                                         int gather_direction_count, const GpuTexture& out) {
  const TexelLayout layout = MultipleScatteringLayout(context);
  const shared::ivec2 size = out.size2();
  GpuTexture order[2] = {GpuTexture::Make2D(size), GpuTexture::Make2D(size)};
  GpuTexture sum[2] = {GpuTexture::Make2D(size), GpuTexture::Make2D(size)};
  GpuTexture ground[2] = {GpuTexture::Make2D({size.x, 1}), GpuTexture::Make2D({size.x, 1})};
  GpuTexture f_ms = GpuTexture::Make2D(size);

  // Order 1: Psi_1 (encoded, and plain as the first sum), f_ms, E_1.
  const ComputeProgram& first = context.Program(kMultipleScatteringFiles, TexelLayoutSource(layout) +
      std::string(kMultipleScatteringSumsSource) + R"glsl(
layout(rgba32f, binding = 0) uniform writeonly image2D order_image;
layout(rgba32f, binding = 1) uniform writeonly image2D sum_image;
layout(rgba32f, binding = 2) uniform writeonly image2D f_image;
layout(rgba32f, binding = 3) uniform writeonly image2D ground_image;
uniform AtmosphereParameters atmosphere;
uniform sampler2D transmittance_texture;
uniform int direction_count;
uniform int sample_count;
uniform bool media_phase;
uniform vec3 ground_transfer;

void main() {
  ivec2 size = imageSize(order_image);
  ivec2 texel = GroupTexel();
  bool inside = texel.x < size.x && texel.y < size.y;
  texel = min(texel, size - 1);
  float r;
  vec3 sun_direction;
  GetMultiScatteringTexelPoint(atmosphere, size, vec2(texel) + vec2(0.5), r, sun_direction);
  vec3 luminance_sum;
  vec3 transfer_sum;
  vec3 irradiance_sum;
  SumFirstOrderRays(atmosphere, transmittance_texture, r, sun_direction, direction_count, sample_count, media_phase,
      ground_transfer, luminance_sum, transfer_sum, irradiance_sum);
  if (inside && TexelLead()) {
    vec3 psi = luminance_sum / float(direction_count);
    imageStore(order_image, texel, vec4(EncodeMultiScattering(psi), 1.0));
    imageStore(sum_image, texel, vec4(psi, 1.0));
    imageStore(f_image, texel, vec4(transfer_sum / float(direction_count), 1.0));
    if (texel.y == 0) {
      vec3 irradiance = GetGatheredGroundIrradianceFromSum(irradiance_sum, direction_count);
      imageStore(ground_image, ivec2(texel.x, 0), vec4(EncodeMultiScattering(irradiance), 1.0));
    }
  }
}
)glsl", "multiple-scattering table, first gathered order");
  SetAtmosphereUniforms(first, "atmosphere", km);
  first.SetInt("direction_count", direction_count);
  first.SetInt("sample_count", sample_count);
  first.SetInt("media_phase", media_phase ? 1 : 0);
  first.SetVec3("ground_transfer", ground_transfer);
  BindSamplers(first, {{"transmittance_texture", &transmittance}});
  order[0].BindImage(0);
  sum[0].BindImage(1);
  f_ms.BindImage(2);
  ground[0].BindImage(3);
  DispatchTexels(first, layout, size);

  // Orders 2 ... K, each from the previous one's tables. The last also writes the table: the sum,
  // and the series after it (GetMultiScatteringFromOrders), in the same pass.
  const ComputeProgram& gather = context.Program(kMultipleScatteringFiles, TexelLayoutSource(layout) +
      std::string(kMultipleScatteringSumsSource) + R"glsl(
layout(rgba32f, binding = 0) uniform writeonly image2D order_image;
layout(rgba32f, binding = 1) uniform writeonly image2D sum_image;
layout(rgba32f, binding = 2) uniform writeonly image2D ground_image;
layout(rgba32f, binding = 3) uniform writeonly image2D table_image;
uniform AtmosphereParameters atmosphere;
uniform sampler2D previous_order_texture;
uniform sampler2D ground_irradiance_texture;
uniform sampler2D sum_texture;
uniform sampler2D f_texture;
uniform int direction_count;
uniform int sample_count;
uniform bool last_order;

void main() {
  ivec2 size = imageSize(order_image);
  ivec2 texel = GroupTexel();
  bool inside = texel.x < size.x && texel.y < size.y;
  texel = min(texel, size - 1);
  float r;
  vec3 sun_direction;
  GetMultiScatteringTexelPoint(atmosphere, size, vec2(texel) + vec2(0.5), r, sun_direction);
  vec3 luminance_sum;
  vec3 irradiance_sum;
  SumGatherRays(atmosphere, previous_order_texture, ground_irradiance_texture, r, sun_direction, direction_count,
      sample_count, luminance_sum, irradiance_sum);
  if (inside && TexelLead()) {
    vec3 psi = luminance_sum / float(direction_count);
    vec3 order_sum = texelFetch(sum_texture, texel, 0).rgb + psi;
    if (last_order) {
      vec3 psi_ms = GetMultiScatteringFromOrders(order_sum, DecodeMultiScattering(EncodeMultiScattering(psi)),
          texelFetch(f_texture, texel, 0).rgb);
      imageStore(table_image, texel, vec4(EncodeMultiScattering(psi_ms), 1.0));
    } else {
      imageStore(order_image, texel, vec4(EncodeMultiScattering(psi), 1.0));
      imageStore(sum_image, texel, vec4(order_sum, 1.0));
      if (texel.y == 0) {
        vec3 irradiance = GetGatheredGroundIrradianceFromSum(irradiance_sum, direction_count);
        imageStore(ground_image, ivec2(texel.x, 0), vec4(EncodeMultiScattering(irradiance), 1.0));
      }
    }
  }
}
)glsl", "multiple-scattering table, a gathered order");
  int current = 0;
  for (int n = 2; n <= orders; ++n) {
    const int next = 1 - current;
    SetAtmosphereUniforms(gather, "atmosphere", km);
    gather.SetInt("direction_count", gather_direction_count);
    gather.SetInt("sample_count", sample_count);
    gather.SetInt("last_order", n == orders ? 1 : 0);
    BindSamplers(gather, {{"previous_order_texture", &order[current]},
                          {"ground_irradiance_texture", &ground[current]},
                          {"sum_texture", &sum[current]},
                          {"f_texture", &f_ms}});
    order[next].BindImage(0);
    sum[next].BindImage(1);
    ground[next].BindImage(2);
    out.BindImage(3);
    DispatchTexels(gather, layout, size);
    current = next;
  }
}

void RunGroundIrradiancePass(const Context& context, const shared::AtmosphereParameters& km,
                             const GpuTexture& transmittance, const GpuTexture& multiple_scattering,
                             int direction_count, int sample_count, const GpuTexture& out) {
  const TexelLayout layout = GroundIrradianceLayout(context);
  // SumGroundIrradianceTerms (sky.glsl) over the texel's invocations, as the rays above.
  const ComputeProgram& program = context.Program(kSkyFiles, TexelLayoutSource(layout) + R"glsl(
layout(rgba32f, binding = 0) uniform writeonly image2D output_table;
uniform AtmosphereParameters atmosphere;
uniform sampler2D transmittance_texture;
uniform sampler2D multiple_scattering_texture;
uniform int direction_count;
uniform int sample_count;

void main() {
  ivec2 size = imageSize(output_table);
  ivec2 texel = GroupTexel();
  bool inside = texel.x < size.x && texel.y < size.y;
  texel = min(texel, size - 1);
  float mu_s = GetGroundIrradianceTexelMuS(size.x, float(texel.x) + 0.5);
  int first_step = SegmentFirstStep(sample_count);
  int end_step = SegmentEndStep(sample_count);
  vec3 sum = vec3(0.0);
  for (int base = 0; base < direction_count; base += kRaySlots) {
    int k = base + RaySlot();
    vec3 term = vec3(0.0);
    vec3 transmittance = vec3(1.0);
    if (k < direction_count) {
      term = ComputeGroundIrradianceTermSteps(atmosphere, transmittance_texture, multiple_scattering_texture, mu_s, k,
          direction_count, sample_count, first_step, end_step, transmittance);
    }
    sum += term * ThroughputBefore(transmittance);
  }
  vec3 unused_b = vec3(0.0);
  vec3 unused_c = vec3(0.0);
  SumOverTexel(sum, unused_b, unused_c);
  if (inside && TexelLead()) imageStore(output_table, texel, vec4(GetGroundIrradianceFromSum(sum, direction_count), 1.0));
}
)glsl", "ground-irradiance table");
  SetAtmosphereUniforms(program, "atmosphere", km);
  program.SetInt("direction_count", direction_count);
  program.SetInt("sample_count", sample_count);
  BindSamplers(program,
               {{"transmittance_texture", &transmittance}, {"multiple_scattering_texture", &multiple_scattering}});
  out.BindImage(0);
  DispatchTexels(program, layout, out.size2());
}

void RunSkyViewPass(const Context& context, const shared::AtmosphereParameters& km, const GpuTexture& transmittance,
                    const GpuTexture& multiple_scattering, double r_km, double mu_s, int sample_count,
                    const GpuTexture& out) {
  if (out.size().y < 4 || out.size().y % 2 != 0) throw Error("GL sky-view table: the height must be even and >= 4");
  const TexelLayout layout = SkyViewLayout(context);
  const ComputeProgram& program = context.Program(kSkyFiles, TexelLayoutSource(layout) + R"glsl(
layout(rgba32f, binding = 0) uniform writeonly image2D output_table;
uniform AtmosphereParameters atmosphere;
uniform sampler2D transmittance_texture;
uniform sampler2D multiple_scattering_texture;
uniform float r;     // km
uniform float mu_s;
uniform int sample_count;

// Column x and column width - x see azimuths phi and 2 pi - phi, the same nu: the texels of
// columns 0 .. width / 2 are marched, and each is written to both (as cpu::ComputeSkyViewTable).
void main() {
  ivec2 size = imageSize(output_table);
  ivec2 texel = GroupTexel();
  bool inside = 2 * texel.x <= size.x && texel.y < size.y;
  texel = min(texel, ivec2(size.x / 2, size.y - 1));
  vec3 transmittance;
  vec3 radiance = ComputeSkyViewTexelSteps(atmosphere, transmittance_texture, multiple_scattering_texture, size,
      vec2(texel) + vec2(0.5), r, mu_s, sample_count, SegmentFirstStep(sample_count), SegmentEndStep(sample_count),
      transmittance);
  radiance *= ThroughputBefore(transmittance);
  vec3 unused_b = vec3(0.0);
  vec3 unused_c = vec3(0.0);
  SumOverTexel(radiance, unused_b, unused_c);
  if (inside && TexelLead()) {
    imageStore(output_table, texel, vec4(radiance, 1.0));
    imageStore(output_table, ivec2((size.x - texel.x) % size.x, texel.y), vec4(radiance, 1.0));
  }
}
)glsl", "sky-view table");
  SetAtmosphereUniforms(program, "atmosphere", km);
  program.SetFloat("r", r_km);
  program.SetFloat("mu_s", mu_s);
  program.SetInt("sample_count", sample_count);
  BindSamplers(program,
               {{"transmittance_texture", &transmittance}, {"multiple_scattering_texture", &multiple_scattering}});
  out.BindImage(0);
  DispatchTexels(program, layout, {out.size().x / 2 + 1, out.size().y});
}

void RunGroundViewPass(const Context& context, const shared::AtmosphereParameters& km, const GpuTexture& transmittance,
                       const GpuTexture& ground_irradiance, const GpuTexture& sky_view, double r_km, double mu_s,
                       const GpuTexture& out) {
  const ComputeProgram& program = context.Program(kSkyFiles, TablePass(R"glsl(
uniform sampler2D transmittance_texture;
uniform sampler2D ground_irradiance_texture;
uniform sampler2D sky_view_texture;
uniform float r;     // km
uniform float mu_s;

void main() {
  ivec2 size = imageSize(output_table);
  ivec2 texel = ivec2(gl_GlobalInvocationID.xy);
  if (texel.x >= size.x || texel.y >= size.y) return;
  vec3 radiance = texelFetch(sky_view_texture, texel, 0).rgb + ComputeGroundViewTexel(atmosphere,
      transmittance_texture, ground_irradiance_texture, size, vec2(texel) + vec2(0.5), r, mu_s);
  imageStore(output_table, texel, vec4(radiance, 1.0));
}
)glsl"), "ground-view table");
  SetAtmosphereUniforms(program, "atmosphere", km);
  program.SetFloat("r", r_km);
  program.SetFloat("mu_s", mu_s);
  BindSamplers(program, {{"transmittance_texture", &transmittance},
                         {"ground_irradiance_texture", &ground_irradiance},
                         {"sky_view_texture", &sky_view}});
  out.BindImage(0);
  DispatchCompute2D(program, out.size2());
}

HillaireGl::HillaireGl(const Context& context, const AtmosphereParameters& parameters,
                       const HillaireSettings& settings)
    : context_(context), settings_(settings) {
  Validate(parameters);
  if (parameters.geometry != Geometry::kSpherical) {
    throw Error("model hillaire needs a spherical atmosphere; the half-space of preset '" + parameters.name +
                "' is the geometry of the simple model");
  }
  channel_count_ = parameters.channel_count();
  batches_.resize(ChannelBatchCount(channel_count_));
  for (std::size_t b = 0; b < batches_.size(); ++b) {
    batches_[b].metres = ToSharedParameters(parameters, b);
    batches_[b].km = ToSharedParameters(parameters, b, 1000.0);
    batches_[b].solar_irradiance = BatchValues(parameters.solar_irradiance, b);
  }
}

// Each pass runs for every batch before the next pass (as HillaireModel::Precompute), so that
// each timed pass name holds the sum of its batches.
void HillaireGl::Precompute(PassTimings* timings) {
  context_.MakeCurrent();
  const HillaireSettings& s = settings_;
  if (batches_.front().transmittance.empty()) {
    for (Batch& batch : batches_) {
      batch.transmittance = GpuTexture::Make2D(s.transmittance_lut);
      batch.multiple_scattering = GpuTexture::Make2D(s.multiple_scattering_lut);
      batch.ground_irradiance = GpuTexture::Make2D({s.ground_irradiance_lut, 1});
    }
  }
  // The ground's share of orders >= 2 is a small hemisphere sum, computed on the host as the CPU does.
  std::vector<shared::vec3> ground_transfer(batches_.size(), shared::vec3(0.0));
  if (s.multiple_scattering_ground) {
    for (std::size_t b = 0; b < batches_.size(); ++b) {
      ground_transfer[b] = shared::GetGroundTransfer(batches_[b].metres, s.multiple_scattering_directions / 2,
                                                     s.multiple_scattering_samples);
    }
  }
  GpuPassTimer timer(timings);
  for (const Batch& batch : batches_) {
    RunTransmittancePass(context_, batch.km, s.transmittance_samples, batch.transmittance);
  }
  timer.Stop("transmittance_lut");
  for (std::size_t b = 0; b < batches_.size(); ++b) {
    const Batch& batch = batches_[b];
    if (s.multiple_scattering_orders > 1) {
      RunGatheredMultipleScatteringPasses(context_, batch.km, batch.transmittance, s.multiple_scattering_directions,
                                          s.multiple_scattering_samples, s.multiple_scattering_media_phase,
                                          ground_transfer[b], s.multiple_scattering_orders,
                                          s.multiple_scattering_gather_directions, batch.multiple_scattering);
    } else {
      RunMultipleScatteringPass(context_, batch.km, batch.transmittance, s.multiple_scattering_directions,
                                s.multiple_scattering_samples, s.multiple_scattering_media_phase, ground_transfer[b],
                                batch.multiple_scattering);
    }
  }
  timer.Stop("multiple_scattering_lut");
  for (const Batch& batch : batches_) {
    RunGroundIrradiancePass(context_, batch.km, batch.transmittance, batch.multiple_scattering,
                            s.ground_irradiance_directions, s.ground_irradiance_samples, batch.ground_irradiance);
  }
  timer.Stop("ground_irradiance_lut");
  CheckGlError("hillaire tables");
  precomputed_ = true;
}

void HillaireGl::SetView(double altitude_m, const glm::dvec3& sun_direction, bool ground, PassTimings* timings) {
  if (!precomputed_) throw Error("GL hillaire: SetView before Precompute");
  if (!std::isfinite(altitude_m) || altitude_m < 0.0) {
    throw Error("altitude_m must be finite and >= 0 for model hillaire (got " + std::to_string(altitude_m) + ")");
  }
  if (!std::isfinite(glm::length(sun_direction)) || glm::length(sun_direction) == 0.0) {
    throw Error("the sun direction must be a finite, non-zero vector");
  }
  context_.MakeCurrent();
  sun_ = glm::normalize(sun_direction);
  mu_s_ = shared::ClampCosine(sun_.z);
  // Double-precision metres for what the host decides, km for the GPU; the radii are those of
  // every batch.
  const shared::AtmosphereParameters& metres = batches_.front().metres;
  const double r_m = metres.bottom_radius + altitude_m;
  r_km_ = r_m / 1000.0;
  horizon_nadir_angle_ = shared::GetHorizonNadirAngle(metres, r_m);
  uses_sky_view_ = settings_.use_sky_view_lut && r_m <= metres.top_radius;
  has_ground_view_ = false;
  view_set_ = true;
  if (!uses_sky_view_) return;
  if (batches_.front().sky_view.empty()) {
    for (Batch& batch : batches_) {
      batch.sky_view = GpuTexture::Make2D(settings_.sky_view_lut, /*repeat_u=*/true);
      batch.sky_and_ground_view = GpuTexture::Make2D(settings_.sky_view_lut, /*repeat_u=*/true);
    }
  }
  GpuPassTimer timer(timings);
  for (const Batch& batch : batches_) {
    RunSkyViewPass(context_, batch.km, batch.transmittance, batch.multiple_scattering, r_km_, mu_s_,
                   settings_.sky_view_samples, batch.sky_view);
  }
  timer.Stop("sky_view_lut");
  if (ground) {
    for (const Batch& batch : batches_) {
      RunGroundViewPass(context_, batch.km, batch.transmittance, batch.ground_irradiance, batch.sky_view, r_km_, mu_s_,
                        batch.sky_and_ground_view);
    }
    timer.Stop("ground_view_lut");
    has_ground_view_ = true;
  }
  CheckGlError("hillaire sky view");
}

void HillaireGl::SetSkyUniforms(const ComputeProgram& program, const Batch& batch) const {
  SetAtmosphereUniforms(program, "atmosphere", batch.km);
  program.SetFloat("r", r_km_);
  program.SetFloat("mu_s", mu_s_);
  program.SetVec3("sun_direction", sun_);
  program.SetFloat("horizon_nadir_angle", horizon_nadir_angle_);
  program.SetInt("ray_march_samples", settings_.ray_march_samples);
}


std::span<const std::string_view> HillaireGl::FrameSharedFiles() { return kSkyFiles; }

std::string HillaireGl::FrameFunctionSource() const {
  return SkyRadianceSource(uses_sky_view_) + R"glsl(
uniform CameraParameters camera;
uniform bool sun_disc;
uniform bool ground;  // per pixel where the ray is marched; the sky-view table has it otherwise
uniform vec3 solar_irradiance;

vec4 GetFrameTexel(vec2 frag_coord) {
  vec3 direction;
  bool seen = GetCameraRayDirection(camera, frag_coord, direction);
  vec3 radiance = vec3(0.0);
  if (seen) {
    radiance = GetSkyRadianceAlong(direction);
    float nu = dot(direction, sun_direction);
    if (sun_disc) {
      radiance += GetSunDiscRadiance(atmosphere, transmittance_texture, r, direction.z, nu);
    }
    if (ground && USE_SKY_VIEW == 0) {
      radiance += GetGroundRadiance(atmosphere, transmittance_texture, ground_irradiance_texture, r, direction.z,
          mu_s, nu);
    }
  }
  return vec4(radiance * solar_irradiance, seen ? 1.0 : 0.0);
}
)glsl";
}

void HillaireGl::SetFrameUniforms(const ComputeProgram& program, const shared::CameraParameters& camera,
                                  const RadianceTerms& terms, std::size_t batch_index) const {
  if (!view_set_) throw Error("GL hillaire: a frame before SetView");
  if (terms.ground && uses_sky_view_ && !has_ground_view_) {
    throw Error("GL hillaire: a frame with the ground term needs SetView(..., ground = true)");
  }
  const Batch& batch = batches_.at(batch_index);
  SetCameraUniforms(program, "camera", camera);
  program.SetInt("sun_disc", terms.sun_disc ? 1 : 0);
  program.SetInt("ground", terms.ground ? 1 : 0);
  SetSkyUniforms(program, batch);
  program.SetVec3("solar_irradiance", batch.solar_irradiance);
  const GpuTexture& sky_view = terms.ground ? batch.sky_and_ground_view : batch.sky_view;
  BindSamplers(program, {{"transmittance_texture", &batch.transmittance},
                         {"multiple_scattering_texture", &batch.multiple_scattering},
                         {"ground_irradiance_texture", &batch.ground_irradiance},
                         {"sky_view_texture", &sky_view}});
}

void HillaireGl::RenderFrame(const shared::CameraParameters& camera, const RadianceTerms& terms,
                             PassTimings* timings) {
  if (!view_set_) throw Error("GL hillaire: RenderFrame before SetView");
  if (terms.ground && uses_sky_view_ && !has_ground_view_) {
    throw Error("GL hillaire: a frame with the ground term needs SetView(..., ground = true)");
  }
  context_.MakeCurrent();
  const ComputeProgram& program = context_.Program(kSkyFiles, R"glsl(
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform writeonly image2D output_image;
)glsl" + FrameFunctionSource() + R"glsl(
void main() {
  ivec2 size = imageSize(output_image);
  ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
  if (pixel.x >= size.x || pixel.y >= size.y) return;
  imageStore(output_image, pixel, GetFrameTexel(vec2(pixel) + vec2(0.5)));
}
)glsl", "frame");
  for (Batch& batch : batches_) {
    if (batch.frame.empty() || batch.frame.size2() != shared::ivec2(camera.width, camera.height)) {
      batch.frame = GpuTexture::Make2D({camera.width, camera.height});
    }
  }
  frame_has_alpha_ = camera.kind == shared::kCameraFisheye;
  GpuPassTimer timer(timings);
  for (std::size_t b = 0; b < batches_.size(); ++b) {
    SetFrameUniforms(program, camera, terms, b);
    batches_[b].frame.BindImage(0);
    DispatchCompute2D(program, batches_[b].frame.size2());
  }
  timer.Stop("frame_" + std::to_string(camera.width) + "x" + std::to_string(camera.height));
  CheckGlError("frame");
}

Image HillaireGl::ReadFrame() const {
  if (batches_.front().frame.empty()) throw Error("GL hillaire: ReadFrame before RenderFrame");
  context_.MakeCurrent();
  const shared::ivec2 size = batches_.front().frame.size2();
  const std::size_t n = static_cast<std::size_t>(size.x) * size.y;
  const std::size_t nc = channel_count_;
  Image image(size.x, size.y, static_cast<int>(nc));
  if (frame_has_alpha_) image.alpha.assign(n, 0.0f);
  for (std::size_t b = 0; b < batches_.size(); ++b) {
    const std::vector<float> rgba = batches_[b].frame.DownloadRgba();
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t c = 0; c < 3 && 3 * b + c < nc; ++c) image.pixels[nc * i + 3 * b + c] = rgba[4 * i + c];
      if (frame_has_alpha_ && b == 0) image.alpha[i] = rgba[4 * i + 3];
    }
  }
  return image;
}

void HillaireGl::Sample(std::span<const glm::dvec3> views, std::vector<double>& radiance,
                        std::vector<double>& transmittance, PassTimings* timings) {
  if (!view_set_) throw Error("GL hillaire: Sample before SetView");
  const std::size_t nc = channel_count_;
  radiance.assign(views.size() * nc, 0.0);
  transmittance.assign(views.size() * nc, 0.0);
  if (views.empty()) return;
  context_.MakeCurrent();
  const ComputeProgram& program = context_.Program(kSkyFiles, R"glsl(
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Directions { vec4 directions[]; };
layout(std430, binding = 1) writeonly buffer Results { vec4 results[]; };  // radiance, transmittance
)glsl" + SkyRadianceSource(uses_sky_view_) + R"glsl(
uniform int count;

void main() {
  int i = int(gl_GlobalInvocationID.x);
  if (i >= count) return;
  vec3 direction = directions[i].xyz;
  results[2 * i] = vec4(GetSkyRadianceAlong(direction), 1.0);
  results[2 * i + 1] = vec4(GetViewTransmittance(atmosphere, transmittance_texture, r, direction.z), 1.0);
}
)glsl", "sample");
  std::vector<float> directions(4 * views.size());
  for (std::size_t i = 0; i < views.size(); ++i) {
    const glm::dvec3 v = glm::normalize(views[i]);
    directions[4 * i] = static_cast<float>(v.x);
    directions[4 * i + 1] = static_cast<float>(v.y);
    directions[4 * i + 2] = static_cast<float>(v.z);
  }
  // The directions, then one results buffer per batch.
  const std::size_t batch_count = batches_.size();
  std::vector<GLuint> buffers(1 + batch_count, 0);
  glCreateBuffers(static_cast<GLsizei>(buffers.size()), buffers.data());
  glNamedBufferStorage(buffers[0], static_cast<GLsizeiptr>(directions.size() * sizeof(float)), directions.data(), 0);
  const auto results_bytes = static_cast<GLsizeiptr>(8 * views.size() * sizeof(float));
  for (std::size_t b = 0; b < batch_count; ++b) {
    glNamedBufferStorage(buffers[1 + b], results_bytes, nullptr, GL_DYNAMIC_STORAGE_BIT);
  }
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, buffers[0]);
  program.SetInt("count", static_cast<int>(views.size()));
  {
    GpuPassTimer timer(timings);
    for (std::size_t b = 0; b < batch_count; ++b) {
      const Batch& batch = batches_[b];
      glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, buffers[1 + b]);
      SetSkyUniforms(program, batch);
      BindSamplers(program, {{"transmittance_texture", &batch.transmittance},
                             {"multiple_scattering_texture", &batch.multiple_scattering},
                             {"ground_irradiance_texture", &batch.ground_irradiance},
                             {"sky_view_texture", &batch.sky_view}});
      DispatchCompute1D(program, static_cast<int>(views.size()));
    }
    timer.Stop("sample_" + std::to_string(views.size()));
  }
  std::vector<float> results(8 * views.size());
  for (std::size_t b = 0; b < batch_count; ++b) {
    glGetNamedBufferSubData(buffers[1 + b], 0, results_bytes, results.data());
    for (std::size_t i = 0; i < views.size(); ++i) {
      for (std::size_t c = 0; c < 3 && 3 * b + c < nc; ++c) {
        radiance[nc * i + 3 * b + c] = results[8 * i + c];
        transmittance[nc * i + 3 * b + c] = results[8 * i + 4 + c];
      }
    }
  }
  glDeleteBuffers(static_cast<GLsizei>(buffers.size()), buffers.data());
  CheckGlError("sample");
}

AerialPerspectiveVolume HillaireGl::ComputeAerialPerspective(const Camera& camera,
                                                            const AerialPerspectiveSettings& settings,
                                                            PassTimings* timings) {
  if (!view_set_) throw Error("GL hillaire: ComputeAerialPerspective before SetView");
  ValidateCamera(camera);
  ValidateAerialPerspectiveSettings(settings);
  context_.MakeCurrent();
  const ComputeProgram& program = context_.Program(kSkyFiles, R"glsl(
layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;
layout(rgba32f, binding = 0) uniform writeonly image3D radiance_volume;
layout(rgba32f, binding = 1) uniform writeonly image3D transmittance_volume;
uniform AtmosphereParameters atmosphere;
uniform sampler2D transmittance_texture;
uniform sampler2D multiple_scattering_texture;
uniform CameraParameters camera;
uniform float r;                // km
uniform float mu_s;
uniform vec3 sun_direction;     // unit, local frame
uniform float max_distance;     // km, the far end of the last slice
uniform int ray_march_samples;

void main() {
  ivec3 size = imageSize(radiance_volume);
  ivec3 froxel = ivec3(gl_GlobalInvocationID);
  if (any(greaterThanEqual(froxel, size))) return;
  // The froxel's centre in image pixels, and its slice's far distance.
  vec2 frag = (vec2(froxel.xy) + vec2(0.5)) / vec2(size.xy) * vec2(camera.width, camera.height);
  float distance = float(froxel.z + 1) / float(size.z) * max_distance;
  vec3 direction;
  vec3 radiance = vec3(0.0);
  vec3 transmittance = vec3(1.0);
  if (GetCameraRayDirection(camera, frag, direction)) {
    radiance = IntegrateScatteredRadiance(atmosphere, transmittance_texture, multiple_scattering_texture, r,
        direction.z, mu_s, dot(direction, sun_direction), distance, ray_march_samples, transmittance);
  }
  imageStore(radiance_volume, froxel, vec4(radiance, 1.0));
  imageStore(transmittance_volume, froxel, vec4(transmittance, 1.0));
}
)glsl", "aerial-perspective volume");
  const shared::ivec3 size(settings.width, settings.height, settings.depth);
  if (aerial_radiance_.empty() || aerial_radiance_.size() != size) {
    aerial_radiance_ = GpuTexture::Make3D(size);
    aerial_transmittance_ = GpuTexture::Make3D(size);
  }
  SetCameraUniforms(program, "camera", ToSharedCamera(camera));
  program.SetFloat("r", r_km_);
  program.SetFloat("mu_s", mu_s_);
  program.SetVec3("sun_direction", sun_);
  program.SetFloat("max_distance", settings.max_distance_m / 1000.0);
  program.SetInt("ray_march_samples", settings_.ray_march_samples);
  aerial_radiance_.BindImage(0);
  aerial_transmittance_.BindImage(1);
  // Batch by batch into the same two textures, each read back into the CPU's volume layout
  // (channel_count values per froxel, in its x + width (y + height z) order).
  const std::size_t nc = channel_count_;
  const std::size_t froxels = static_cast<std::size_t>(size.x) * size.y * size.z;
  std::vector<float> radiance(froxels * nc);
  std::vector<float> transmittance(froxels * nc);
  for (std::size_t b = 0; b < batches_.size(); ++b) {
    const Batch& batch = batches_[b];
    SetAtmosphereUniforms(program, "atmosphere", batch.km);
    BindSamplers(program, {{"transmittance_texture", &batch.transmittance},
                           {"multiple_scattering_texture", &batch.multiple_scattering}});
    {
      GpuPassTimer timer(timings);
      DispatchCompute3D(program, size);
      timer.Stop("aerial_perspective_lut");
    }
    CheckGlError("aerial perspective");
    const std::vector<float> l = aerial_radiance_.DownloadRgba();
    const std::vector<float> t = aerial_transmittance_.DownloadRgba();
    for (std::size_t i = 0; i < froxels; ++i) {
      for (std::size_t c = 0; c < 3 && 3 * b + c < nc; ++c) {
        radiance[nc * i + 3 * b + c] = l[4 * i + c];
        transmittance[nc * i + 3 * b + c] = t[4 * i + c];
      }
    }
  }
  return AerialPerspectiveVolume(settings, camera, nc, std::move(radiance), std::move(transmittance));
}

void AddSunDiscOnHost(const AtmosphereParameters& parameters, std::span<const shared::Texture2D> transmittance_km,
                      const RenderSettings& render, Image& image) {
  const std::size_t batch_count = ChannelBatchCount(parameters.channel_count());
  if (transmittance_km.size() != batch_count) {
    throw Error("the GL sun disc needs one transmittance table per batch of 3 channels (" +
                std::to_string(batch_count) + "), got " + std::to_string(transmittance_km.size()));
  }
  std::vector<shared::AtmosphereParameters> km;
  for (std::size_t b = 0; b < batch_count; ++b) km.push_back(ToSharedParameters(parameters, b, 1000.0));
  const double r_km = (parameters.ground_radius_m + render.altitude_m) / 1000.0;
  const glm::dvec3 sun = glm::normalize(SunDirection(render.sun_elevation_deg, render.sun_azimuth_deg));
  AddSunDisc(
      render.camera, sun, parameters.sun_angular_radius_rad,
      [&](const glm::dvec3& view, std::span<double> out) {
        const double mu = shared::ClampCosine(view.z);
        const double nu = glm::dot(view, sun);
        ScatterBatches(batch_count, out, [&](std::size_t b) {
          return shared::GetSunDiscRadiance(km[b], transmittance_km[b], r_km, mu, nu);
        });
      },
      parameters.solar_irradiance, image);
}

Image RenderHillaireGl(const Context& context, const AtmosphereParameters& parameters,
                       const HillaireSettings& settings, const RenderSettings& render, PassTimings* timings) {
  ValidateCamera(render.camera);
  for (const double value : {render.altitude_m, render.sun_elevation_deg, render.sun_azimuth_deg}) {
    if (!std::isfinite(value)) throw Error("altitude and sun angles must be finite");
  }
  HillaireGl sky(context, parameters, settings);
  sky.Precompute(timings);
  sky.SetView(render.altitude_m, SunDirection(render.sun_elevation_deg, render.sun_azimuth_deg), render.terms.ground,
              timings);
  // The frame without the disc; the host adds it integrated over the pixels (AddSunDiscOnHost).
  RadianceTerms frame_terms = render.terms;
  frame_terms.sun_disc = false;
  sky.RenderFrame(ToSharedCamera(render.camera), frame_terms, timings);
  Image image = sky.ReadFrame();
  if (render.terms.sun_disc) {
    std::vector<shared::Texture2D> transmittance;
    for (std::size_t b = 0; b < sky.batch_count(); ++b) transmittance.push_back(sky.ReadTransmittance(b));
    AddSunDiscOnHost(parameters, transmittance, render, image);
  }
  return image;
}

HillaireTables ComputeHillaireTablesGl(const Context& context, const AtmosphereParameters& parameters,
                                       const HillaireSettings& settings, const HillaireExportView& view,
                                       PassTimings* timings) {
  Validate(parameters);
  ValidateHillaireExportView(parameters, view);
  HillaireSettings with_sky_view = settings;
  with_sky_view.use_sky_view_lut = true;
  HillaireGl sky(context, parameters, with_sky_view);
  sky.Precompute(timings);
  sky.SetView(view.altitude_m, SunDirection(view.sun_elevation_deg, view.sun_azimuth_deg), /*ground=*/true, timings);
  HillaireTables tables;
  tables.parameters = parameters;
  tables.options = HillaireTableOptions(settings);
  tables.view = view;
  tables.backend = "gl";
  const auto read = [&](const char* name, shared::Texture2D (HillaireGl::*download)(std::size_t) const) {
    std::vector<shared::Texture2D> textures;
    for (std::size_t b = 0; b < sky.batch_count(); ++b) textures.push_back((sky.*download)(b));
    std::vector<const shared::Texture2D*> pointers;
    for (const auto& t : textures) pointers.push_back(&t);
    tables.tables.push_back(io::TableFromTextures(name, pointers));
  };
  read("transmittance", &HillaireGl::ReadTransmittance);
  read("multiple_scattering", &HillaireGl::ReadMultipleScattering);
  read("sky_view", &HillaireGl::ReadSkyView);
  read("sky_view_ground", &HillaireGl::ReadSkyAndGroundView);
  const AerialPerspectiveVolume volume = sky.ComputeAerialPerspective(view.camera, view.aerial, timings);
  tables.tables.push_back(AerialPerspectiveTable(volume, /*radiance=*/true));
  tables.tables.push_back(AerialPerspectiveTable(volume, /*radiance=*/false));
  return tables;
}

}  // namespace atmo::gl
