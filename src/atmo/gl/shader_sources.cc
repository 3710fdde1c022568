#include "gl/shader_sources.h"

#include "atmo/error.h"

namespace atmo::gl {

std::string_view SharedGlslSource(std::string_view file_name) {
  for (int i = 0; i < detail::kEmbeddedGlslFileCount; ++i) {
    if (file_name == detail::kEmbeddedGlslFiles[i].name) return detail::kEmbeddedGlslFiles[i].source;
  }
  throw Error("GL backend: shared shader file '" + std::string(file_name) +
              "' is not embedded (add it to ATMO_GL_SHARED_GLSL in src/atmo/gl/CMakeLists.txt)");
}

// The GLSL side of glsl_cpp.h. Compute shaders need GLSL 4.30; GL_LINEAR samplers stand for
// shared::Texture2D, whose sampling rules are those of GL_LINEAR with clamp to edge, and
// Texture3D. TexturePair3D, which finds the taps once for two textures on the CPU, is two
// texture() calls here (the sampler finds them in hardware).
std::string_view GlslPrelude() {
  return R"glsl(#version 430 core
#define Number float
#define IN(x) in x
#define OUT(x) out x
#define INOUT(x) inout x
#define TransmittanceTexture sampler2D
#define MultiScatteringTexture sampler2D
#define SkyViewTexture sampler2D
#define Texture2D sampler2D
#define Texture3D sampler3D
#define Source4dTexture sampler3D
void TexturePair3D(sampler3D a, sampler3D b, vec3 uvw, out vec3 value_a, out vec3 value_b) {
  value_a = texture(a, uvw).rgb;
  value_b = texture(b, uvw).rgb;
}
)glsl";
}

std::string BuildComputeShaderSource(std::span<const std::string_view> shared_files, std::string_view main_source) {
  std::string source(GlslPrelude());
  int part = 1;
  for (std::string_view file : shared_files) {
    source += "#line 1 " + std::to_string(part++) + "\n";
    source += SharedGlslSource(file);
    source += "\n";
  }
  source += "#line 1 " + std::to_string(part) + "\n";
  source += main_source;
  return source;
}

std::string DescribeSourceStrings(std::span<const std::string_view> shared_files) {
  std::string text = "source strings: 0 prelude";
  int part = 1;
  for (std::string_view file : shared_files) text += ", " + std::to_string(part++) + " " + std::string(file);
  text += ", " + std::to_string(part) + " main";
  return text;
}

}  // namespace atmo::gl
