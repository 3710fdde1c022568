#include "gl/hillaire_gl.h"

#include <chrono>
#include <cstddef>
#include <string>
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

// Dispatches `program` (already configured) over an rgba32f image of `size` and reads it back.
shared::Texture2D RunTablePass(const ComputeProgram& program, shared::ivec2 size, const char* name,
                               GlPassTiming* timing) {
  if (size.x < 2 || size.y < 2) throw Error(std::string("GL ") + name + ": table size must be at least 2x2");
  auto start = Clock::now();
  GLuint texture = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &texture);
  glTextureStorage2D(texture, 1, GL_RGBA32F, size.x, size.y);
  program.Use();
  glBindImageTexture(0, texture, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
  glDispatchCompute(static_cast<GLuint>((size.x + kGroupSize - 1) / kGroupSize),
                    static_cast<GLuint>((size.y + kGroupSize - 1) / kGroupSize), 1);
  glMemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT);
  glFinish();
  if (timing != nullptr) timing->dispatch_ms = MillisecondsSince(start);
  start = Clock::now();
  std::vector<float> rgba(static_cast<std::size_t>(size.x) * size.y * 4);
  glGetTextureImage(texture, 0, GL_RGBA, GL_FLOAT, static_cast<GLsizei>(rgba.size() * sizeof(float)), rgba.data());
  glDeleteTextures(1, &texture);
  CheckGlError(name);
  shared::Texture2D table(size.x, size.y);
  for (std::size_t i = 0; i < table.texels.size(); ++i) {
    table.texels[i] = glm::vec3(rgba[4 * i], rgba[4 * i + 1], rgba[4 * i + 2]);
  }
  if (timing != nullptr) timing->readback_ms = MillisecondsSince(start);
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
  const auto start = Clock::now();
  const ComputeProgram program(BuildComputeShaderSource(files, main_source), "transmittance table",
                               DescribeSourceStrings(files));
  if (timing != nullptr) timing->compile_ms = MillisecondsSince(start);
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
  const auto start = Clock::now();
  const ComputeProgram program(BuildComputeShaderSource(files, main_source), "multiple-scattering table",
                               DescribeSourceStrings(files));
  if (timing != nullptr) timing->compile_ms = MillisecondsSince(start);
  SetAtmosphereUniforms(program, "atmosphere", km_atmosphere);
  program.SetInt("transmittance_texture", 0);
  program.SetInt("direction_count", direction_count);
  program.SetInt("sample_count", sample_count);
  program.SetInt("media_phase", media_phase ? 1 : 0);
  program.SetVec3("ground_transfer", ground_transfer);
  const SampledTable transmittance_table(transmittance);
  transmittance_table.Bind(0);
  return RunTablePass(program, size, "multiple-scattering table", timing);
}

}  // namespace atmo::gl
