#include "gl/hillaire_gl.h"

#include <chrono>
#include <cstddef>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <epoxy/gl.h>

#include "atmo/error.h"
#include "gl/program.h"
#include "gl/shader_sources.h"

namespace atmo::gl {
namespace {

using Clock = std::chrono::steady_clock;

double MillisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// 8 x 8 invocations per work group: a multiple of the SIMD width everywhere, 64 <= the minimum
// of GL_MAX_COMPUTE_WORK_GROUP_INVOCATIONS (1024).
constexpr int kGroupSize = 8;

// The declarations every table pass shares: one rgba32f output image, the atmosphere.
constexpr const char* kTablePassHeader = R"glsl(
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform writeonly image2D output_table;
uniform AtmosphereParameters atmosphere;
)glsl";

void CheckGlError(const char* what) {
  const GLenum error = glGetError();
  if (error != GL_NO_ERROR) {
    throw Error(std::string("GL ") + what + " failed: GL error " + std::to_string(static_cast<unsigned>(error)));
  }
}

// Dispatches `program` (already configured) over an rgba32f image of `size` (bound to image unit 0)
// and reads it back, rgba per texel, row 0 first. The dispatch is timed by the wall clock up to
// glFinish and on the GPU by a GL_TIME_ELAPSED query.
std::vector<float> DispatchImagePass(const ComputeProgram& program, shared::ivec2 size, const char* name,
                                     GlPassTiming* timing) {
  if (size.x < 1 || size.y < 1) throw Error(std::string("GL ") + name + ": the image must have at least one texel");
  auto start = Clock::now();
  GLuint texture = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &texture);
  glTextureStorage2D(texture, 1, GL_RGBA32F, size.x, size.y);
  GLuint query = 0;
  glGenQueries(1, &query);
  program.Use();
  glBindImageTexture(0, texture, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
  glBeginQuery(GL_TIME_ELAPSED, query);
  glDispatchCompute(static_cast<GLuint>((size.x + kGroupSize - 1) / kGroupSize),
                    static_cast<GLuint>((size.y + kGroupSize - 1) / kGroupSize), 1);
  glEndQuery(GL_TIME_ELAPSED);
  glMemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT);
  glFinish();
  if (timing != nullptr) timing->dispatch_ms = MillisecondsSince(start);
  GLuint64 gpu_ns = 0;
  glGetQueryObjectui64v(query, GL_QUERY_RESULT, &gpu_ns);
  glDeleteQueries(1, &query);
  // llvmpipe runs a compute dispatch on the CPU inside glDispatchCompute and its timer query does
  // not measure it (it reports ~0); there the wall-clock dispatch time is the "GPU" time.
  const auto* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const bool software = renderer != nullptr && std::string_view(renderer).find("llvmpipe") != std::string_view::npos;
  if (timing != nullptr) timing->gpu_ms = software ? timing->dispatch_ms : static_cast<double>(gpu_ns) * 1e-6;
  start = Clock::now();
  std::vector<float> rgba(static_cast<std::size_t>(size.x) * size.y * 4);
  glGetTextureImage(texture, 0, GL_RGBA, GL_FLOAT, static_cast<GLsizei>(rgba.size() * sizeof(float)), rgba.data());
  glDeleteTextures(1, &texture);
  CheckGlError(name);
  if (timing != nullptr) timing->readback_ms = MillisecondsSince(start);
  return rgba;
}

// DispatchImagePass, read back into a table (rgb).
shared::Texture2D RunTablePass(const ComputeProgram& program, shared::ivec2 size, const char* name,
                               GlPassTiming* timing) {
  const std::vector<float> rgba = DispatchImagePass(program, size, name, timing);
  const auto start = Clock::now();
  shared::Texture2D table(size.x, size.y);
  for (std::size_t i = 0; i < table.texels.size(); ++i) {
    table.texels[i] = glm::vec3(rgba[4 * i], rgba[4 * i + 1], rgba[4 * i + 2]);
  }
  if (timing != nullptr) timing->readback_ms += MillisecondsSince(start);
  return table;
}

// A sampled GL_LINEAR, clamp-to-edge (or repeat on s) rgba32f copy of a table, deleted with it.
class SampledTable {
 public:
  explicit SampledTable(const shared::Texture2D& table) {
    std::vector<float> rgba(table.texels.size() * 4);
    for (std::size_t i = 0; i < table.texels.size(); ++i) {
      rgba[4 * i] = table.texels[i].x;
      rgba[4 * i + 1] = table.texels[i].y;
      rgba[4 * i + 2] = table.texels[i].z;
      rgba[4 * i + 3] = 1.0f;
    }
    glCreateTextures(GL_TEXTURE_2D, 1, &texture_);
    glTextureStorage2D(texture_, 1, GL_RGBA32F, table.width, table.height);
    glTextureSubImage2D(texture_, 0, 0, 0, table.width, table.height, GL_RGBA, GL_FLOAT, rgba.data());
    glTextureParameteri(texture_, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTextureParameteri(texture_, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTextureParameteri(texture_, GL_TEXTURE_WRAP_S, table.repeat_u ? GL_REPEAT : GL_CLAMP_TO_EDGE);
    glTextureParameteri(texture_, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  }
  ~SampledTable() { glDeleteTextures(1, &texture_); }
  SampledTable(const SampledTable&) = delete;
  SampledTable& operator=(const SampledTable&) = delete;

  void Bind(GLuint unit) const { glBindTextureUnit(unit, texture_); }

 private:
  GLuint texture_ = 0;
};

// The tables a pass samples: table i is uploaded, bound to texture unit i and given to the
// sampler uniform named with it, so that names and units cannot disagree. Deleted with it.
class SampledTables {
 public:
  SampledTables(const ComputeProgram& program,
                std::initializer_list<std::pair<const char*, const shared::Texture2D*>> tables) {
    GLuint unit = 0;
    for (const auto& [sampler, table] : tables) {
      program.SetInt(sampler, static_cast<int>(unit));
      tables_.push_back(std::make_unique<SampledTable>(*table));
      tables_.back()->Bind(unit++);
    }
  }

 private:
  std::vector<std::unique_ptr<SampledTable>> tables_;
};

// Compiles and links a pass from the shared files and its main(), timing the build in
// timing->compile_ms.
ComputeProgram MakeProgram(std::initializer_list<std::string_view> files, const std::string& main_source,
                           const char* name, GlPassTiming* timing) {
  // Sets timing->compile_ms when the program is built (the return below is elided, not moved).
  struct CompileTimer {
    GlPassTiming* timing;
    Clock::time_point start = Clock::now();
    ~CompileTimer() {
      if (timing != nullptr) timing->compile_ms = MillisecondsSince(start);
    }
  } timer{timing};
  return ComputeProgram(BuildComputeShaderSource(files, main_source), name, DescribeSourceStrings(files));
}

}  // namespace

shared::Texture2D ComputeTransmittanceTableGl(const Context& context, const shared::AtmosphereParameters& km_atmosphere,
                                              shared::ivec2 size, int sample_count, GlPassTiming* timing) {
  context.MakeCurrent();
  const auto files = {std::string_view("definitions.glsl"), std::string_view("geometry.glsl"),
                      std::string_view("medium.glsl"), std::string_view("transmittance.glsl")};
  const std::string main_source = std::string(kTablePassHeader) + R"glsl(
uniform int sample_count;

void main() {
  ivec2 size = imageSize(output_table);
  ivec2 texel = ivec2(gl_GlobalInvocationID.xy);
  if (texel.x >= size.x || texel.y >= size.y) return;
  vec3 transmittance =
      ComputeTransmittanceToTopAtmosphereBoundaryTexel(atmosphere, size, vec2(texel) + vec2(0.5), sample_count);
  imageStore(output_table, texel, vec4(transmittance, 1.0));
}
)glsl";
  const ComputeProgram program = MakeProgram(files, main_source, "transmittance table", timing);
  SetAtmosphereUniforms(program, "atmosphere", km_atmosphere);
  program.SetInt("sample_count", sample_count);
  return RunTablePass(program, size, "transmittance table", timing);
}

shared::Texture2D ComputeMultipleScatteringTableGl(const Context& context,
                                                   const shared::AtmosphereParameters& km_atmosphere,
                                                   const shared::Texture2D& transmittance, shared::ivec2 size,
                                                   int direction_count, int sample_count, bool media_phase,
                                                   const shared::vec3& ground_transfer, GlPassTiming* timing) {
  context.MakeCurrent();
  const auto files = {std::string_view("definitions.glsl"), std::string_view("geometry.glsl"),
                      std::string_view("medium.glsl"),      std::string_view("phase.glsl"),
                      std::string_view("transmittance.glsl"), std::string_view("multiple_scattering.glsl")};
  const std::string main_source = std::string(kTablePassHeader) + R"glsl(
uniform sampler2D transmittance_texture;
uniform int direction_count;
uniform int sample_count;
uniform bool media_phase;
uniform vec3 ground_transfer;

void main() {
  ivec2 size = imageSize(output_table);
  ivec2 texel = ivec2(gl_GlobalInvocationID.xy);
  if (texel.x >= size.x || texel.y >= size.y) return;
  vec3 psi_ms = ComputeMultiScatteringTexel(atmosphere, transmittance_texture, size, vec2(texel) + vec2(0.5),
      direction_count, sample_count, media_phase, ground_transfer);
  imageStore(output_table, texel, vec4(psi_ms, 1.0));
}
)glsl";
  const ComputeProgram program = MakeProgram(files, main_source, "multiple-scattering table", timing);
  SetAtmosphereUniforms(program, "atmosphere", km_atmosphere);
  program.SetInt("direction_count", direction_count);
  program.SetInt("sample_count", sample_count);
  program.SetInt("media_phase", media_phase ? 1 : 0);
  program.SetVec3("ground_transfer", ground_transfer);
  const SampledTables tables(program, {{"transmittance_texture", &transmittance}});
  return RunTablePass(program, size, "multiple-scattering table", timing);
}

namespace {

// The shared files of the passes that read the sky (sky.glsl and camera.glsl), in shared.h's order.
constexpr std::string_view kSkyFiles[] = {"definitions.glsl", "geometry.glsl",      "medium.glsl",
                                          "phase.glsl",       "transmittance.glsl", "multiple_scattering.glsl",
                                          "sky.glsl",         "camera.glsl"};

ComputeProgram MakeSkyProgram(const std::string& main_source, const char* name, GlPassTiming* timing) {
  return MakeProgram({kSkyFiles[0], kSkyFiles[1], kSkyFiles[2], kSkyFiles[3], kSkyFiles[4], kSkyFiles[5],
                      kSkyFiles[6], kSkyFiles[7]},
                     main_source, name, timing);
}

void SetCameraUniforms(const ComputeProgram& program, const std::string& name, const shared::CameraParameters& c) {
  const std::string p = name + ".";
  program.SetInt(p + "kind", c.kind);
  program.SetInt(p + "width", c.width);
  program.SetInt(p + "height", c.height);
  program.SetFloat(p + "horizontal_fov", c.horizontal_fov);
  program.SetFloat(p + "yaw", c.yaw);
  program.SetFloat(p + "pitch", c.pitch);
  program.SetVec3(p + "forward", c.forward);
  program.SetVec3(p + "right", c.right);
  program.SetVec3(p + "up", c.up);
  program.SetFloat(p + "tan_half_fov", c.tan_half_fov);
}

}  // namespace

shared::Texture2D ComputeGroundIrradianceTableGl(const Context& context,
                                                 const shared::AtmosphereParameters& km_atmosphere,
                                                 const shared::Texture2D& transmittance,
                                                 const shared::Texture2D& multiple_scattering, int width,
                                                 int direction_count, int sample_count, GlPassTiming* timing) {
  context.MakeCurrent();
  const std::string main_source = std::string(kTablePassHeader) + R"glsl(
uniform sampler2D transmittance_texture;
uniform sampler2D multiple_scattering_texture;
uniform int direction_count;
uniform int sample_count;

void main() {
  ivec2 size = imageSize(output_table);
  ivec2 texel = ivec2(gl_GlobalInvocationID.xy);
  if (texel.x >= size.x || texel.y >= size.y) return;
  vec3 irradiance = ComputeGroundIrradianceTexel(atmosphere, transmittance_texture, multiple_scattering_texture,
      size.x, float(texel.x) + 0.5, direction_count, sample_count);
  imageStore(output_table, texel, vec4(irradiance, 1.0));
}
)glsl";
  const ComputeProgram program = MakeSkyProgram(main_source, "ground-irradiance table", timing);
  SetAtmosphereUniforms(program, "atmosphere", km_atmosphere);
  program.SetInt("direction_count", direction_count);
  program.SetInt("sample_count", sample_count);
  const SampledTables tables(
      program, {{"transmittance_texture", &transmittance}, {"multiple_scattering_texture", &multiple_scattering}});
  return RunTablePass(program, {width, 1}, "ground-irradiance table", timing);
}

shared::Texture2D ComputeSkyViewTableGl(const Context& context, const shared::AtmosphereParameters& km_atmosphere,
                                        const shared::Texture2D& transmittance,
                                        const shared::Texture2D& multiple_scattering, shared::ivec2 size, double r_km,
                                        double mu_s, int sample_count, GlPassTiming* timing) {
  context.MakeCurrent();
  if (size.y < 4 || size.y % 2 != 0) throw Error("GL sky-view table: the height must be even and >= 4");
  const std::string main_source = std::string(kTablePassHeader) + R"glsl(
uniform sampler2D transmittance_texture;
uniform sampler2D multiple_scattering_texture;
uniform float r;     // km
uniform float mu_s;
uniform int sample_count;

void main() {
  ivec2 size = imageSize(output_table);
  ivec2 texel = ivec2(gl_GlobalInvocationID.xy);
  if (texel.x >= size.x || texel.y >= size.y) return;
  vec3 radiance = ComputeSkyViewTexel(atmosphere, transmittance_texture, multiple_scattering_texture, size,
      vec2(texel) + vec2(0.5), r, mu_s, sample_count);
  imageStore(output_table, texel, vec4(radiance, 1.0));
}
)glsl";
  const ComputeProgram program = MakeSkyProgram(main_source, "sky-view table", timing);
  SetAtmosphereUniforms(program, "atmosphere", km_atmosphere);
  program.SetFloat("r", r_km);
  program.SetFloat("mu_s", mu_s);
  program.SetInt("sample_count", sample_count);
  const SampledTables tables(
      program, {{"transmittance_texture", &transmittance}, {"multiple_scattering_texture", &multiple_scattering}});
  shared::Texture2D table = RunTablePass(program, size, "sky-view table", timing);
  table.repeat_u = true;
  return table;
}

shared::Texture2D AddGroundViewGl(const Context& context, const shared::AtmosphereParameters& km_atmosphere,
                                  const shared::Texture2D& transmittance, const shared::Texture2D& ground_irradiance,
                                  const shared::Texture2D& sky_view, double r_km, double mu_s, GlPassTiming* timing) {
  context.MakeCurrent();
  const std::string main_source = std::string(kTablePassHeader) + R"glsl(
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
)glsl";
  const ComputeProgram program = MakeSkyProgram(main_source, "ground-view table", timing);
  SetAtmosphereUniforms(program, "atmosphere", km_atmosphere);
  program.SetFloat("r", r_km);
  program.SetFloat("mu_s", mu_s);
  const SampledTables tables(program, {{"transmittance_texture", &transmittance},
                                       {"ground_irradiance_texture", &ground_irradiance},
                                       {"sky_view_texture", &sky_view}});
  shared::Texture2D table = RunTablePass(program, {sky_view.width, sky_view.height}, "ground-view table", timing);
  table.repeat_u = true;
  return table;
}

Image RenderSkyViewFrameGl(const Context& context, const shared::AtmosphereParameters& km_atmosphere,
                           const shared::Texture2D& transmittance, const shared::Texture2D& sky_view,
                           const shared::CameraParameters& camera, double r_km, double horizon_nadir_angle,
                           const shared::vec3& sun_direction, bool sun_disc, const shared::vec3& solar_irradiance,
                           GlPassTiming* timing) {
  context.MakeCurrent();
  const std::string main_source = R"glsl(
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform writeonly image2D output_image;
uniform AtmosphereParameters atmosphere;
uniform sampler2D transmittance_texture;
uniform sampler2D sky_view_texture;
uniform CameraParameters camera;
uniform float r;                    // km
uniform float horizon_nadir_angle;  // GetHorizonNadirAngle(atmosphere, r), radians
uniform vec3 sun_direction;         // unit, local frame (x east, y north, z up)
uniform bool sun_disc;
uniform vec3 solar_irradiance;

void main() {
  ivec2 size = imageSize(output_image);
  ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
  if (pixel.x >= size.x || pixel.y >= size.y) return;
  vec3 direction;
  bool seen = GetCameraRayDirection(camera, vec2(pixel) + vec2(0.5), direction);
  vec3 radiance = vec3(0.0);
  if (seen) {
    float azimuth = GetAzimuthFromSun(direction, sun_direction);
    vec2 uv = GetSkyViewTextureUvFromBeta(textureSize(sky_view_texture, 0), horizon_nadir_angle, direction.z, azimuth);
    radiance = texture(sky_view_texture, uv).rgb;
    if (sun_disc) {
      radiance += GetSunDiscRadiance(atmosphere, transmittance_texture, r, direction.z, dot(direction, sun_direction));
    }
  }
  imageStore(output_image, pixel, vec4(radiance * solar_irradiance, seen ? 1.0 : 0.0));
}
)glsl";
  const ComputeProgram program = MakeSkyProgram(main_source, "frame", timing);
  SetAtmosphereUniforms(program, "atmosphere", km_atmosphere);
  SetCameraUniforms(program, "camera", camera);
  program.SetFloat("r", r_km);
  program.SetFloat("horizon_nadir_angle", horizon_nadir_angle);
  program.SetVec3("sun_direction", sun_direction);
  program.SetInt("sun_disc", sun_disc ? 1 : 0);
  program.SetVec3("solar_irradiance", solar_irradiance);
  const SampledTables tables(program, {{"transmittance_texture", &transmittance}, {"sky_view_texture", &sky_view}});
  const std::vector<float> rgba = DispatchImagePass(program, {camera.width, camera.height}, "frame", timing);
  const auto start = Clock::now();
  Image image(camera.width, camera.height, 3);
  const bool has_alpha = camera.kind == shared::kCameraFisheye;
  if (has_alpha) image.alpha.assign(static_cast<std::size_t>(camera.width) * camera.height, 0.0f);
  for (std::size_t i = 0; i < static_cast<std::size_t>(camera.width) * camera.height; ++i) {
    for (int c = 0; c < 3; ++c) image.pixels[3 * i + c] = rgba[4 * i + c];
    if (has_alpha) image.alpha[i] = rgba[4 * i + 3];
  }
  if (timing != nullptr) timing->readback_ms += MillisecondsSince(start);
  return image;
}

}  // namespace atmo::gl
