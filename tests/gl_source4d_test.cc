// Model source4d on the GL backend agrees with the CPU: the shared functions of
// src/atmo/shared/source4d.glsl compiled as GLSL (configuration gl_f32_rgb against cpu_f64_rgb,
// STYLE.md).
//
// Label `gl`. Each test skips only when no headless OpenGL context can be made (no EGL/Mesa
// driver); on the CI image (Mesa llvmpipe through EGL surfaceless) they run.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>

#include "atmo/error.h"
#include "atmo/parameters.h"
#include "gl/context.h"
#include "gl/program.h"
#include "gl/resources.h"
#include "gl_test_context.h"
#include "physics/shared_parameters.h"
#include "shared/shared.h"

namespace atmo::gl {
namespace {

// Per invocation i of `count`: the sun-zenith axis's unit of mu_s = -1 + 2 (i + 0.5) / count, the
// polynomial acos of mu_s, the inverse of the axis at the unit i / (count - 1) and the shadow
// interval of a ray 1 km above the ground (mu 0.3, 60 degrees in azimuth from the sun), for
// comparison with the CPU.
constexpr const char* kMappingMain = R"glsl(
layout(local_size_x = 64) in;
layout(rgba32f, binding = 0) uniform writeonly image2D output_image;
uniform AtmosphereParameters atmosphere;
uniform int count;

void main() {
  int i = int(gl_GlobalInvocationID.x);
  if (i >= count) return;
  float mu_s = -1.0 + 2.0 * (float(i) + 0.5) / float(count);
  float nu = 0.3 * mu_s + 0.5 * sqrt((1.0 - 0.09) * (1.0 - mu_s * mu_s));
  float t_0;
  float t_1;
  bool shadow = GetSource4dShadowInterval(atmosphere, atmosphere.bottom_radius + 1.0, 0.3, mu_s, nu, 500.0, t_0, t_1);
  imageStore(output_image, ivec2(i, 0), vec4(GetSource4dUnitSunZenith(mu_s), Source4dAcos(mu_s),
      GetSource4dSunZenithFromUnit(float(i) / float(count - 1)), shadow ? t_1 - t_0 : -1.0));
}
)glsl";

// source4d.glsl compiles as GLSL 4.30 with the shared files it uses, and its float results are
// those of the CPU's double to float precision.
TEST(GlSource4d, SharedFunctionsCompileAndMatchCpu) {
  ATMO_REQUIRE_GL_CONTEXT(context);
  context.MakeCurrent();
  const ComputeProgram& program =
      context.Program({"definitions.glsl", "geometry.glsl", "medium.glsl", "phase.glsl", "transmittance.glsl",
                       "multiple_scattering.glsl", "sun.glsl", "sky.glsl", "camera.glsl", "source4d.glsl"},
                      kMappingMain, "source4d mapping");
  const AtmosphereParameters parameters = Preset("earth");
  const shared::AtmosphereParameters km = ToSharedParameters(parameters, 0, 1000.0);
  constexpr int kCount = 256;
  SetAtmosphereUniforms(program, "atmosphere", km);
  program.SetInt("count", kCount);
  const GpuTexture out = GpuTexture::Make2D({kCount, 1});
  out.BindImage(0);
  DispatchCompute1D(program, kCount);
  CheckGlError("source4d mapping");
  const std::vector<float> gl = out.DownloadRgba();
  int shadowed = 0;
  double max_unit = 0.0, max_angle = 0.0, max_shadow = 0.0;
  for (int i = 0; i < kCount; ++i) {
    const double mu_s = -1.0 + 2.0 * (i + 0.5) / kCount;
    const double nu = 0.3 * mu_s + 0.5 * std::sqrt((1.0 - 0.09) * (1.0 - mu_s * mu_s));
    double t_0, t_1;
    const bool shadow =
        shared::GetSource4dShadowInterval(km, km.bottom_radius + 1.0, 0.3, mu_s, nu, 500.0, t_0, t_1);
    max_unit = std::max(max_unit, std::abs(gl[4 * i] - shared::GetSource4dUnitSunZenith(mu_s)));
    max_angle = std::max(max_angle, std::abs(gl[4 * i + 1] - shared::Source4dAcos(mu_s)));
    max_angle = std::max(max_angle,
                         std::abs(gl[4 * i + 2] - shared::GetSource4dSunZenithFromUnit(i / double(kCount - 1))));
    // A shadowed ray is shadowed on both; an unshadowed one gives -1.
    ASSERT_EQ(gl[4 * i + 3] >= 0.0f, shadow) << "mu_s " << mu_s;
    if (shadow) {
      ++shadowed;
      max_shadow = std::max(max_shadow, std::abs(gl[4 * i + 3] - (t_1 - t_0)));
    }
  }
  std::printf("source4d mapping: max |unit| diff %.2g, max |angle| diff %.2g rad, shadowed %d, max shadow diff %.2g km\n",
              max_unit, max_angle, shadowed, max_shadow);
  // Float rounding of angles up to pi (ulp 2.4e-7) through a few operations: measured 3.4e-7 on
  // both. The shadow's length, up to the 500 km of the ray, from the roots of a quadratic whose
  // coefficients are ~r^2 = 4e7 km^2 in float: measured 0.91 m (2e-6 of the ray); bound 5 m.
  EXPECT_LT(max_unit, 1e-6);
  EXPECT_LT(max_angle, 1e-6);
  EXPECT_GT(shadowed, 10);
  EXPECT_LT(max_shadow, 5e-3);
}


}  // namespace
}  // namespace atmo::gl
