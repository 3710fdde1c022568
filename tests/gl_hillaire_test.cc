// The GL backend runs the shared per-texel kernels as GLSL and agrees with the CPU tables.
//
// Label `gl`. Each test skips only when no headless OpenGL context can be made (no EGL/Mesa
// driver); on the CI image (Mesa llvmpipe through EGL surfaceless) they run.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include <gtest/gtest.h>

#include "atmo/error.h"
#include "atmo/parameters.h"
#include "cpu/hillaire_tables.h"
#include "gl/context.h"
#include "gl/hillaire_gl.h"
#include "gl/shader_sources.h"
#include "physics/shared_parameters.h"
#include "shared/shared.h"
#include "test_atmospheres.h"

namespace atmo::gl {
namespace {

using shared::ivec2;
using shared::Texture2D;

// One context for the whole program (creating one costs ~10 ms on llvmpipe); null when none
// can be made, with the reason kept for the skip message.
struct SharedContext {
  std::unique_ptr<Context> context;
  std::string error;
};

SharedContext& GetSharedContext() {
  static SharedContext shared = [] {
    SharedContext s;
    try {
      s.context = std::make_unique<Context>();
    } catch (const Error& e) {
      s.error = e.what();
    }
    return s;
  }();
  return shared;
}

#define ATMO_REQUIRE_GL_CONTEXT(context)                            \
  if (GetSharedContext().context == nullptr) {                      \
    GTEST_SKIP() << GetSharedContext().error;                       \
  }                                                                 \
  const Context& context = *GetSharedContext().context

struct Difference {
  double max_abs = 0.0;
  double max_rel = 0.0;  // relative to the CPU value, over texels where it is > 1e-3
};

// The largest differences of `gl` from `cpu`, texel by texel.
Difference Compare(const Texture2D& gl, const Texture2D& cpu) {
  Difference d;
  for (std::size_t i = 0; i < cpu.texels.size(); ++i) {
    const glm::vec3& reference = cpu.texels[i];
    for (int c = 0; c < 3; ++c) {
      const double a = gl.texels[i][c];
      const double b = reference[c];
      d.max_abs = std::max(d.max_abs, std::abs(a - b));
      if (b > 1e-3) d.max_rel = std::max(d.max_rel, std::abs(a - b) / b);
    }
  }
  return d;
}

TEST(GlContext, ReportsRendererAndVersion) {
  ATMO_REQUIRE_GL_CONTEXT(context);
  EXPECT_FALSE(context.renderer().empty());
  EXPECT_EQ(context.version().rfind("4.", 0), 0u) << context.version();
  RecordProperty("gl_renderer", context.renderer());
  RecordProperty("gl_version", context.version());
  std::printf("GL_RENDERER=%s\nGL_VERSION=%s\n", context.renderer().c_str(), context.version().c_str());
}

TEST(GlShaderSources, EmbedsTheSharedFilesVerbatim) {
  // The GL backend compiles the very text that shared.h includes as C++.
  EXPECT_NE(SharedGlslSource("transmittance.glsl").find("ComputeTransmittanceToTopAtmosphereBoundaryTexel"),
            std::string_view::npos);
  EXPECT_THROW(SharedGlslSource("no_such_file.glsl"), Error);
  const std::string source = BuildComputeShaderSource({"definitions.glsl"}, "void main() {}\n");
  EXPECT_EQ(source.rfind("#version 430 core\n", 0), 0u);
}

TEST(GlHillaire, TransmittanceTableMatchesCpu) {
  ATMO_REQUIRE_GL_CONTEXT(context);
  const AtmosphereParameters earth = Preset("earth");
  const shared::AtmosphereParameters metres = ToSharedParameters(earth, 0, 1.0);
  const shared::AtmosphereParameters km = ToSharedParameters(earth, 0, 1000.0);
  const ivec2 size(256, 64);
  const int samples = 40;
  GlPassTiming timing;
  const Texture2D gl = ComputeTransmittanceTableGl(context, km, size, samples, &timing);
  Texture2D cpu(size.x, size.y);
  cpu::ComputeTransmittanceTable(metres, samples, cpu);
  // (The quadrature is one grid over the whole ray, continuous in mu: the horizontal ray from the
  // ground, where float and double round mu to opposite sides of 0, needs no special case.)
  const Difference d = Compare(gl, cpu);
  std::printf("transmittance %dx%d, %d samples: GL vs CPU max abs %.3g, max rel (T > 1e-3) %.3g; "
              "GL compile %.1f ms, dispatch %.2f ms, readback %.2f ms\n",
              size.x, size.y, samples, d.max_abs, d.max_rel, timing.compile_ms, timing.dispatch_ms,
              timing.readback_ms);
  // Tolerance: float32 on the GPU against double on the CPU, in km. The radii (~6400 km) carry a
  // float ulp of ~0.5 m, so every sample's altitude (r_i - bottom_radius, r_i from a law of
  // cosines in r^2 ~ 4e7 km^2) is off by up to ~0.5 m, i.e. up to 4e-4 of the Mie scale height
  // (1.2 km) in relative density; these errors partly cancel along a ray, and exp/sqrt on
  // llvmpipe add only ~1e-7 relative. Measured on llvmpipe (Mesa 22.3.6): max abs 1.5e-5, max rel
  // 2.6e-4 where T > 1e-3; the bounds leave a factor of 2.
  EXPECT_LT(d.max_abs, 3e-5);
  EXPECT_LT(d.max_rel, 5e-4);
}

TEST(GlHillaire, MultipleScatteringTableMatchesCpu) {
  ATMO_REQUIRE_GL_CONTEXT(context);
  const AtmosphereParameters earth = Preset("earth");
  const shared::AtmosphereParameters metres = ToSharedParameters(earth, 0, 1.0);
  const shared::AtmosphereParameters km = ToSharedParameters(earth, 0, 1000.0);
  // Both backends read the same (CPU) transmittance table, so this compares the kernels alone.
  Texture2D transmittance(256, 64);
  cpu::ComputeTransmittanceTable(metres, 40, transmittance);
  const ivec2 size(32, 32);
  for (bool media_phase : {false, true}) {
    const shared::vec3 ground_transfer = shared::GetGroundTransfer(metres, 32, 20);  // unitless
    GlPassTiming timing;
    const Texture2D gl =
        ComputeMultipleScatteringTableGl(context, km, transmittance, size, 64, 20, media_phase, ground_transfer, &timing);
    Texture2D cpu(size.x, size.y);
    cpu::ComputeMultipleScatteringTable(metres, transmittance, 64, 20, media_phase, ground_transfer, cpu);
    const Difference d = Compare(gl, cpu);
    std::printf("multiple scattering %dx%d, 64 directions x 20 samples, media_phase %d: GL vs CPU max abs %.3g, "
                "max rel %.3g; GL compile %.1f ms, dispatch %.2f ms\n",
                size.x, size.y, media_phase, d.max_abs, d.max_rel, timing.compile_ms, timing.dispatch_ms);
    // Tolerance: the same float-vs-double altitude errors as the transmittance table (relative
    // ~1e-4 per sample, averaging over 64 x 20 samples), plus llvmpipe's GL_LINEAR taps of the
    // transmittance table, which it blends in float as shared::Texture2D does in double.
    // Measured on llvmpipe: max rel 6.8e-5 (values 1e-3 and above), max abs 7.8e-7.
    EXPECT_LT(d.max_rel, 2e-4);
    EXPECT_LT(d.max_abs, 3e-6);
  }
}

}  // namespace
}  // namespace atmo::gl
