// The display transform of atmo-viewer and of the web page in GLSL against the library's: AgX as
// apps/viewer/viewer.cc writes it (AgxSigmoid, AgxEncoded and Agx, the text that
// web/CMakeLists.txt also extracts into the page's shader) against atmo::AgxDisplay
// (src/atmo/io/display.cc), what `atmo render --tonemap agx` writes.
//
// Label `gl`; skips only when no headless OpenGL context can be made.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include "atmo/image.h"
#include "cli_fixture.h"
#include "gl/program.h"
#include "gl/resources.h"
#include "gl_test_context.h"
#include "shared/shared.h"

namespace atmo::gl {
namespace {

// The text of the function whose definition starts with `signature`, up to its closing brace at
// the start of a line.
std::string FunctionText(const std::string& source, const std::string& signature) {
  const std::size_t start = source.find(signature);
  EXPECT_NE(start, std::string::npos) << signature;
  if (start == std::string::npos) return {};
  const std::size_t end = source.find("\n}\n", start);
  EXPECT_NE(end, std::string::npos) << signature;
  return source.substr(start, end + 3 - start);
}

TEST(GlDisplay, ViewerAgxMatchesTheLibrarysAgx) {
  ATMO_REQUIRE_GL_CONTEXT(context);
  const std::string viewer = ::atmo::testing::ReadFile(ATMO_SOURCE_DIR "/apps/viewer/viewer.cc");
  const std::string functions = FunctionText(viewer, "float AgxSigmoid(float x)") +
                                FunctionText(viewer, "vec3 AgxEncoded(vec3 v)") + FunctionText(viewer, "vec3 Agx(vec3 v)");
  ASSERT_FALSE(HasFailure());
  // Exposed linear pixels from 2^-16 to 2^8 (AgX's range is 2^-12.5 to 2^4, the ends clamped), in
  // grey and in five colours, saturated ones included.
  const glm::vec3 colours[] = {{1.0f, 1.0f, 1.0f}, {1.0f, 0.5f, 0.2f}, {0.1f, 0.3f, 1.0f},
                               {1.0f, 0.0f, 0.0f}, {0.0f, 0.8f, 0.1f}, {0.02f, 0.02f, 0.9f}};
  constexpr int kSteps = 97;
  const int count = kSteps * static_cast<int>(std::size(colours));
  shared::Texture2D input(count, 1);
  for (int i = 0; i < count; ++i) {
    const float stops = -16.0f + 24.0f * static_cast<float>(i / 6) / static_cast<float>(kSteps - 1);
    input.texels[static_cast<std::size_t>(i)] = std::exp2(stops) * colours[i % 6];
  }
  const ComputeProgram& program = context.Program({}, functions + R"glsl(
layout(local_size_x = 64) in;
layout(rgba32f, binding = 0) uniform writeonly image2D encoded_image;
layout(rgba32f, binding = 1) uniform writeonly image2D linear_image;
uniform sampler2D input_texture;

void main() {
  int i = int(gl_GlobalInvocationID.x);
  if (i >= imageSize(encoded_image).x) return;
  vec3 v = texelFetch(input_texture, ivec2(i, 0), 0).rgb;
  imageStore(encoded_image, ivec2(i, 0), vec4(AgxEncoded(v), 1.0));
  imageStore(linear_image, ivec2(i, 0), vec4(Agx(v), 1.0));
}
)glsl", "the viewer's AgX");
  const GpuTexture input_texture = GpuTexture::Upload(input);
  const GpuTexture encoded = GpuTexture::Make2D({count, 1});
  const GpuTexture linear = GpuTexture::Make2D({count, 1});
  BindSamplers(program, {{"input_texture", &input_texture}});
  encoded.BindImage(0);
  linear.BindImage(1);
  DispatchCompute1D(program, count);
  const shared::Texture2D gl_encoded = encoded.Download2D();
  const shared::Texture2D gl_linear = linear.Download2D();
  double worst = 0.0;
  double worst_linear = 0.0;
  for (int i = 0; i < count; ++i) {
    const glm::vec3 v = input.texels[static_cast<std::size_t>(i)];
    const std::array<double, 3> expected = AgxDisplay(v.x, v.y, v.z);
    for (int c = 0; c < 3; ++c) {
      const double e = gl_encoded.texels[static_cast<std::size_t>(i)][c];
      worst = std::max(worst, std::abs(e - expected[static_cast<std::size_t>(c)]));
      // Agx is the encoded value decoded for a 2.2 power display.
      worst_linear = std::max(worst_linear, std::abs(gl_linear.texels[static_cast<std::size_t>(i)][c] -
                                                     std::pow(e, 2.2)));
    }
  }
  std::printf("viewer AgX (GLSL) vs AgxDisplay over %d pixels: max |difference| %.3g of the display range; "
              "Agx vs AgxEncoded^2.2: %.3g\n",
              count, worst, worst_linear);
  // The library's sigmoid is a table of the same curve (display.cc's CurveTable) in double, the
  // shader's is evaluated in float: measured on llvmpipe (Mesa 22.3.6) 2.7e-7, and 2.3e-7 between
  // Agx and AgxEncoded^2.2. The GPU bound allows a GPU's coarser log2 and pow. (A sigmoid with
  // its two sides' exponents swapped differs by 3.5e-2; an outset matrix off by 5e-4 of an entry
  // by 4.6e-5.)
  EXPECT_LT(worst, testing::GlBound(context, 5e-6, 2e-5));
  EXPECT_LT(worst_linear, testing::GlBound(context, 5e-6, 2e-5));
}

}  // namespace
}  // namespace atmo::gl
