// The GL backend runs the shared per-texel kernels as GLSL and agrees with the CPU tables.
//
// Label `gl`. Each test skips only when no headless OpenGL context can be made (no EGL/Mesa
// driver); on the CI image (Mesa llvmpipe through EGL surfaceless) they run.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "atmo/aerial_perspective.h"
#include "atmo/error.h"
#include "atmo/image.h"
#include "atmo/parameters.h"
#include "atmo/render.h"
#include "atmo/spectrum.h"
#include "cli_fixture.h"
#include "cpu/hillaire_tables.h"
#include "gl/context.h"
#include "gl_test_context.h"
#include "gl/hillaire_gl.h"
#include "gl/shader_sources.h"
#include "models/hillaire_model.h"
#include "physics/shared_parameters.h"
#include "shared/shared.h"
#include "test_atmospheres.h"

namespace atmo::gl {
namespace {

using shared::ivec2;
using shared::Texture2D;

using testing::GetSharedContext;
using testing::GlBound;
using testing::SamplerSlack;

// Runs `pass` (writing the GpuTexture it is given) into a fresh table of `size` and reads it
// back; `gpu_ms` receives the pass's GPU time (GpuPassTimer).
template <typename Pass>
Texture2D RunTablePass(ivec2 size, bool repeat_u, Pass pass, double* gpu_ms = nullptr) {
  const GpuTexture out = GpuTexture::Make2D(size, repeat_u);
  PassTimings timings;
  {
    GpuPassTimer timer(&timings);
    pass(out);
    timer.Stop("pass");
  }
  if (gpu_ms != nullptr) *gpu_ms = timings.LastMs("pass");
  return out.Download2D();
}

struct Difference {
  double max_abs = 0.0;
  double max_rel = 0.0;  // relative to the CPU value, over texels where it is > 1e-3
  std::size_t worst_texel = 0;  // index of the largest relative difference
};

// The largest differences of `gl` from `cpu`, texel by texel, leaving out the rows in
// [skip_first_row, skip_end_row).
Difference Compare(const Texture2D& gl, const Texture2D& cpu, int skip_first_row = 0, int skip_end_row = 0) {
  Difference d;
  for (std::size_t i = 0; i < cpu.texels.size(); ++i) {
    const int row = static_cast<int>(i / static_cast<std::size_t>(cpu.width));
    if (row >= skip_first_row && row < skip_end_row) continue;
    const glm::vec3& reference = cpu.texels[i];
    for (int c = 0; c < 3; ++c) {
      const double a = gl.texels[i][c];
      const double b = reference[c];
      d.max_abs = std::max(d.max_abs, std::abs(a - b));
      if (b > 1e-3 && std::abs(a - b) / b > d.max_rel) {
        d.max_rel = std::abs(a - b) / b;
        d.worst_texel = i;
      }
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

// Mesa's software rasterisers by their GL_RENDERER strings (what atmo-viewer's --source4d-tables
// auto reads), and hardware ones that are not.
TEST(GlContext, TellsSoftwareRenderersApart) {
  for (const char* software : {"llvmpipe (LLVM 15.0.6, 256 bits)", "softpipe", "SWR (LLVM 6.0.0, 256 bits)",
                               "Mesa X11 swrast", "Software Rasterizer"}) {
    EXPECT_TRUE(IsSoftwareRenderer(software)) << software;
  }
  for (const char* hardware : {"NVIDIA H200/PCIe/SSE2", "AMD Radeon RX 7900 XTX (radeonsi, navi31, LLVM 15.0.7)",
                               "Mesa Intel(R) UHD Graphics 620 (KBL GT2)", ""}) {
    EXPECT_FALSE(IsSoftwareRenderer(hardware)) << hardware;
  }
  ATMO_REQUIRE_GL_CONTEXT(context);
  EXPECT_EQ(context.software_renderer(), IsSoftwareRenderer(context.renderer()));
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
  const Texture2D gl = RunTablePass(size, false, [&](const GpuTexture& out) {
    RunTransmittancePass(context, km, samples, out);
  });
  Texture2D cpu(size.x, size.y);
  cpu::ComputeTransmittanceTable(metres, samples, cpu);
  // (The quadrature is one grid over the whole ray, continuous in mu: the horizontal ray from the
  // ground, where float and double round mu to opposite sides of 0, needs no special case.)
  const Difference d = Compare(gl, cpu);
  std::printf("transmittance %dx%d, %d samples: GL vs CPU max abs %.3g, max rel (T > 1e-3) %.3g\n", size.x,
              size.y, samples, d.max_abs, d.max_rel);
  // Tolerance: float32 on the GPU against double on the CPU, in km. The radii (~6400 km) carry a
  // float ulp of ~0.5 m, so every sample's altitude (r_i - bottom_radius, r_i from a law of
  // cosines in r^2 ~ 4e7 km^2) is off by up to ~0.5 m, i.e. up to 4e-4 of the Mie scale height
  // (1.2 km) in relative density; these errors partly cancel along a ray, and exp/sqrt on
  // llvmpipe add only ~1e-7 relative. Measured on llvmpipe (Mesa 22.3.6): max abs 1.5e-5, max rel
  // 2.6e-4 where T > 1e-3; the bounds leave a factor of 2. On an H200 (coarser exp and sqrt):
  // max abs 4.0e-5, max rel 7.8e-4.
  EXPECT_LT(d.max_abs, GlBound(context, 3e-5, 8e-5));
  EXPECT_LT(d.max_rel, GlBound(context, 5e-4, 1.6e-3));
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
  const shared::vec3 ground_transfer = shared::GetGroundTransfer(metres, 32, 20);  // unitless
  for (bool media_phase : {false, true}) {
    const GpuTexture transmittance_gpu = GpuTexture::Upload(transmittance);
    double gpu_ms = 0.0;
    const Texture2D gl = RunTablePass(size, false, [&](const GpuTexture& out) {
      RunMultipleScatteringPass(context, km, transmittance_gpu, 64, 20, media_phase, ground_transfer, out);
    }, &gpu_ms);
    Texture2D cpu(size.x, size.y);
    cpu::ComputeMultipleScatteringTable(metres, transmittance, 64, 20, media_phase, ground_transfer, cpu);
    // The tables hold ln(Psi_ms); compared as Psi_ms, the quantity the passes read.
    const auto decoded = [](Texture2D t) {
      for (glm::vec3& v : t.texels) v = glm::vec3(shared::DecodeMultiScattering(shared::vec3(v)));
      return t;
    };
    const Difference d = Compare(decoded(gl), decoded(cpu));
    std::printf("multiple scattering %dx%d, 64 directions x 20 samples, media_phase %d: GL vs CPU max abs %.3g, "
                "max rel %.3g; GPU %.2f ms\n",
                size.x, size.y, media_phase, d.max_abs, d.max_rel, gpu_ms);
    // Tolerance: the same float-vs-double altitude errors as the transmittance table (relative
    // ~1e-4 per sample, averaging over 64 x 20 samples), plus llvmpipe's GL_LINEAR taps of the
    // transmittance table, which it blends in float as shared::Texture2D does in double.
    // Measured on llvmpipe: max rel 6.8e-5 (values 1e-3 and above), max abs 7.8e-7.
    EXPECT_LT(d.max_rel, SamplerSlack(context) * 2e-4);
    EXPECT_LT(d.max_abs, SamplerSlack(context) * 3e-6);
  }
}

// The gathered orders (the default, 4): order 1, three gathered passes and the sum, on the GPU
// against the CPU's table from the same transmittance table.
TEST(GlHillaire, GatheredMultipleScatteringTableMatchesCpu) {
  ATMO_REQUIRE_GL_CONTEXT(context);
  const AtmosphereParameters earth = Preset("earth");
  const shared::AtmosphereParameters metres = ToSharedParameters(earth, 0, 1.0);
  const shared::AtmosphereParameters km = ToSharedParameters(earth, 0, 1000.0);
  Texture2D transmittance(256, 64);
  cpu::ComputeTransmittanceTable(metres, 40, transmittance);
  const ivec2 size(32, 32);
  const shared::vec3 ground_transfer = shared::GetGroundTransfer(metres, 32, 20);
  const GpuTexture transmittance_gpu = GpuTexture::Upload(transmittance);
  double gpu_ms = 0.0;
  const Texture2D gl = RunTablePass(size, false, [&](const GpuTexture& out) {
    RunGatheredMultipleScatteringPasses(context, km, transmittance_gpu, 64, 20, false, ground_transfer, 4, 64, out);
  }, &gpu_ms);
  Texture2D cpu(size.x, size.y);
  cpu::ComputeMultipleScatteringTable(metres, transmittance, 64, 20, false, ground_transfer, cpu, 4);
  Texture2D hillaire_2020(size.x, size.y);
  cpu::ComputeMultipleScatteringTable(metres, transmittance, 64, 20, false, ground_transfer, hillaire_2020, 1);
  const auto decoded = [](Texture2D t) {
    for (glm::vec3& v : t.texels) v = glm::vec3(shared::DecodeMultiScattering(shared::vec3(v)));
    return t;
  };
  const Difference d = Compare(decoded(gl), decoded(cpu));
  const Difference gathering = Compare(decoded(hillaire_2020), decoded(cpu));
  std::printf("gathered multiple scattering, 4 orders: GL vs CPU max abs %.3g, max rel %.3g (the gathering itself "
              "changes the table by max rel %.3g); GPU %.2f ms\n",
              d.max_abs, d.max_rel, gathering.max_rel, gpu_ms);
  // Each order carries the single pass's float errors (MultipleScatteringTableMatchesCpu) and
  // reads the previous order through float logarithms; four passes in all.
  EXPECT_LT(d.max_rel, SamplerSlack(context) * 4e-4);
  EXPECT_LT(d.max_abs, SamplerSlack(context) * 6e-6);
  EXPECT_GT(gathering.max_rel, 100.0 * d.max_rel);  // the comparison can tell the gathering apart
}

// The sky-view table of an observer and sun, from the same (CPU) transmittance and
// multiple-scattering tables on both sides, so that this compares the sky-view kernels alone.
TEST(GlHillaire, SkyViewTableMatchesCpu) {
  ATMO_REQUIRE_GL_CONTEXT(context);
  const AtmosphereParameters earth = Preset("earth");
  const shared::AtmosphereParameters metres = ToSharedParameters(earth, 0, 1.0);
  const shared::AtmosphereParameters km = ToSharedParameters(earth, 0, 1000.0);
  Texture2D transmittance(256, 64);
  cpu::ComputeTransmittanceTable(metres, 40, transmittance);
  Texture2D multiple_scattering(32, 32);
  cpu::ComputeMultipleScatteringTable(metres, transmittance, 64, 20, false, shared::GetGroundTransfer(metres, 32, 20),
                                      multiple_scattering);
  const ivec2 size(192, 108);
  const int samples = 30;
  // Tolerance, per case: float32 in km on the GPU against double in metres on the CPU. Each step
  // carries the altitude error of the transmittance table (the radii's float ulp, ~0.5 m, up to
  // ~4e-4 of the Mie scale height) and float acos/cos/sqrt (~1e-7 relative); these average along
  // a ray: ~1e-4 relative (measured 7.6e-5 from the ground). Grazing rays near the horizon are
  // ill-conditioned in float: the distance to the ground, -r mu - sqrt(r^2 (mu^2 - 1) + R^2),
  // takes the square root of a small difference of ~4e7 km^2 terms whose float rounding is
  // ~2 km^2; measured 9.6e-4 at 5 km (the second ground row). At 20 km with the sun 3 degrees
  // below the horizon the sunlit air is a thin band at the terminator, where the same grazing
  // geometry decides the transmittance to the sun: measured 2.9% (red, value 4.6e-3 sr^-1).
  struct Case {
    double altitude_m;
    double sun_elevation_deg;
    double max_rel;
  };
  for (const Case c : {Case{0.0, 10.0, 2e-4}, Case{5000.0, 45.0, 2e-3}, Case{20000.0, -3.0, 5e-2}}) {
    const double r_m = metres.bottom_radius + c.altitude_m;
    const double mu_s = std::sin(glm::radians(c.sun_elevation_deg));
    const GpuTexture transmittance_gpu = GpuTexture::Upload(transmittance);
    const GpuTexture multiple_scattering_gpu = GpuTexture::Upload(multiple_scattering);
    double gpu_ms = 0.0;
    const Texture2D gl = RunTablePass(size, true, [&](const GpuTexture& out) {
      RunSkyViewPass(context, km, transmittance_gpu, multiple_scattering_gpu, r_m / 1000.0, mu_s, samples, out);
    }, &gpu_ms);
    EXPECT_TRUE(gl.repeat_u);
    Texture2D cpu(size.x, size.y, true);
    cpu::ComputeSkyViewTable(metres, transmittance, multiple_scattering, r_m, mu_s, samples, cpu);
    // The rows at the split hold the horizon ray. Each half says whether its rays meet the ground
    // (shared ComputeSkyViewTexel), so from the ground (a horizontal ray) float and double agree
    // there too. Above the ground the horizon ray is tangent to the planet, and its ground
    // distance hangs on the discriminant r^2 mu^2 - (r^2 - R^2) ~ 0, ill-conditioned in float: up to
    // 6 % on llvmpipe at 20 km. Those two rows are then left out and checked to be finite.
    const int half = size.y / 2;
    for (int x = 0; x < size.x; ++x) {
      EXPECT_TRUE(std::isfinite(gl.at(x, half - 1).x) && std::isfinite(gl.at(x, half).x));
    }
    const Difference d = c.altitude_m > 0.0 ? Compare(gl, cpu, half - 1, half + 1) : Compare(gl, cpu);
    std::printf("worst texel (%zu, %zu): GL %g %g %g CPU %g %g %g\n", d.worst_texel % size.x, d.worst_texel / size.x,
                gl.texels[d.worst_texel].x, gl.texels[d.worst_texel].y, gl.texels[d.worst_texel].z,
                cpu.texels[d.worst_texel].x, cpu.texels[d.worst_texel].y, cpu.texels[d.worst_texel].z);
    std::printf("sky view %dx%d, %d samples, altitude %.0f m, sun %.0f deg: GL vs CPU max abs %.3g, max rel (L > "
                "1e-3) %.3g; GPU %.2f ms\n",
                size.x, size.y, samples, c.altitude_m, c.sun_elevation_deg, d.max_abs, d.max_rel, gpu_ms);
    EXPECT_LT(d.max_rel, SamplerSlack(context) * c.max_rel);
  }
}

// The ground-view addition: the CPU sky-view table plus the lit ground, GL against
// HillaireModel::AddGroundView, from the same CPU tables.
TEST(GlHillaire, GroundViewMatchesCpu) {
  ATMO_REQUIRE_GL_CONTEXT(context);
  const AtmosphereParameters earth = Preset("earth");
  HillaireModel model(earth, HillaireSettings{});
  model.Precompute();
  const HillaireModel::Batch& batch = model.batches().front();
  const shared::AtmosphereParameters km = ToSharedParameters(earth, 0, 1000.0);
  const double r_m = batch.atmosphere.bottom_radius + 1000.0;
  const double mu_s = std::sin(glm::radians(20.0));
  const Texture2D sky = model.ComputeSkyViewLut(batch, r_m, mu_s);
  Texture2D cpu = sky;
  model.AddGroundView(batch, r_m, mu_s, cpu);
  const GpuTexture transmittance_gpu = GpuTexture::Upload(batch.transmittance);
  const GpuTexture ground_irradiance_gpu = GpuTexture::Upload(batch.ground_irradiance);
  const GpuTexture sky_gpu = GpuTexture::Upload(sky);
  const Texture2D gl = RunTablePass({sky.width, sky.height}, true, [&](const GpuTexture& out) {
    RunGroundViewPass(context, km, transmittance_gpu, ground_irradiance_gpu, sky_gpu, r_m / 1000.0, mu_s, out);
  });
  // The two rows at the split: the tangent horizon ray from 1 km, ill-conditioned in float (as above).
  const Difference d = Compare(gl, cpu, cpu.height / 2 - 1, cpu.height / 2 + 1);
  std::printf("sky + ground view %dx%d: GL vs CPU max abs %.3g, max rel %.3g\n", cpu.width, cpu.height, d.max_abs,
              d.max_rel);
  // Tolerance: as the sky-view table at low altitude; the ground term adds one transmittance
  // lookup and one ground-irradiance lookup per texel (GL_LINEAR in float against double).
  // Measured on llvmpipe: max rel 1.3e-4, max abs 5.8e-6.
  EXPECT_LT(d.max_rel, SamplerSlack(context) * 5e-4);
  EXPECT_LT(d.max_abs, SamplerSlack(context) * 2e-5);

  // Its ground irradiance table, GL from the same tables.
  const GpuTexture multiple_scattering_gpu = GpuTexture::Upload(batch.multiple_scattering);
  const Texture2D ground_gl =
      RunTablePass({batch.ground_irradiance.width, 1}, false, [&](const GpuTexture& out) {
        RunGroundIrradiancePass(context, km, transmittance_gpu, multiple_scattering_gpu, 64, 16, out);
      });
  const Difference g = Compare(ground_gl, batch.ground_irradiance);
  std::printf("ground irradiance %d: GL vs CPU max abs %.3g, max rel %.3g\n", batch.ground_irradiance.width, g.max_abs,
              g.max_rel);
  EXPECT_LT(g.max_rel, SamplerSlack(context) * 1e-3);
}

struct FrameDifference {
  double max_rel = 0.0;   // over pixels whose CPU value is above the floor (CompareFrames)
  double mean_rel = 0.0;  // same pixels
  double max_abs_alpha = 0.0;
  std::size_t worst = 0;  // the value (pixel x channels + channel) of max_rel
};

// Over the sky and ground pixels, every channel: the sun disc pixel `skip_pixel` (if any) is
// checked apart, and values below 1e-2 of the median (the black outside a fisheye) are left out.
FrameDifference CompareFrames(const Image& gl, const Image& cpu, std::size_t skip_pixel) {
  FrameDifference d;
  std::vector<float> sorted = cpu.pixels;
  std::sort(sorted.begin(), sorted.end());
  const float floor = 1e-2f * sorted[sorted.size() / 2];
  double sum = 0.0;
  int count = 0;
  for (std::size_t i = 0; i < cpu.pixels.size(); ++i) {
    if (cpu.pixels[i] <= floor || i / static_cast<std::size_t>(cpu.channels) == skip_pixel) continue;
    const double rel = std::abs(double(gl.pixels[i]) - cpu.pixels[i]) / cpu.pixels[i];
    if (rel > d.max_rel) {
      d.max_rel = rel;
      d.worst = i;
    }
    sum += rel;
    ++count;
  }
  d.mean_rel = count > 0 ? sum / count : 0.0;
  for (std::size_t i = 0; i < cpu.alpha.size(); ++i) {
    d.max_abs_alpha = std::max(d.max_abs_alpha, double(std::abs(gl.alpha[i] - cpu.alpha[i])));
  }
  return d;
}

// One frame of `render` on GL (every pass on the GPU, the GPU times into `timings`) and on the
// CPU through `model` (precomputed with the same settings), in that order.
std::pair<Image, Image> RenderOnBothBackends(const Context& context, const AtmosphereParameters& parameters,
                                             const HillaireModel& model, const RenderSettings& render,
                                             PassTimings& timings) {
  Image gl = RenderHillaireGl(context, parameters, model.settings(), render, &timings);
  const std::unique_ptr<SkyView> view =
      model.View(render.altitude_m, SunDirection(render.sun_elevation_deg, render.sun_azimuth_deg));
  Image cpu = RenderView(*view, render.camera, render.terms, parameters.solar_irradiance);
  EXPECT_EQ(gl.pixels.size(), cpu.pixels.size());
  EXPECT_EQ(gl.alpha.size(), cpu.alpha.size());
  return {std::move(gl), std::move(cpu)};
}

// The whole GL frame (every table and the frame pass on the GPU, gl_f32_rgb) against the CPU
// frame (cpu tables in double, the float vectorised sky-view lookup), for each camera kind.
TEST(GlHillaire, FrameMatchesCpuForEachCamera) {
  ATMO_REQUIRE_GL_CONTEXT(context);
  const AtmosphereParameters earth = Preset("earth");
  const HillaireSettings settings;
  HillaireModel model(earth, settings);
  model.Precompute();
  for (const CameraKind kind : {CameraKind::kPerspective, CameraKind::kFisheye, CameraKind::kEquirect}) {
    RenderSettings render;
    // 65 x 33: the perspective camera's centre pixel looks exactly at the sun (pitch = sun
    // elevation, yaw = sun azimuth), so the sun disc term is compared too.
    render.camera = {kind, 65, 33, 90.0, 180.0, 10.0};
    render.altitude_m = 500.0;
    render.sun_elevation_deg = 10.0;
    render.sun_azimuth_deg = 180.0;
    render.terms = RadianceTerms{true, true};
    PassTimings timings;
    const auto [gl, cpu] = RenderOnBothBackends(context, earth, model, render, timings);
    ASSERT_EQ(gl.pixels.size(), cpu.pixels.size());
    const std::size_t sun_pixel = 16 * 65 + 32;
    const FrameDifference d =
        CompareFrames(gl, cpu, kind == CameraKind::kPerspective ? sun_pixel : cpu.pixels.size());
    std::printf("frame %s 65x33: GL vs CPU max rel %.3g, mean rel %.3g, alpha max diff %.3g; GPU ms:",
                std::string(ToString(kind)).c_str(), d.max_rel, d.mean_rel, d.max_abs_alpha);
    for (const PassTiming& pass : timings.entries()) std::printf(" %s %.2f", pass.name.c_str(), pass.last_ms);
    std::printf("\n");
    if (kind == CameraKind::kPerspective) {
      const std::size_t centre = sun_pixel * 3;
      EXPECT_GT(cpu.pixels[centre], 100.0f * cpu.pixels[0]) << "the centre pixel should see the sun disc";
      std::printf("sun disc pixel: GL / CPU = %.6f\n", gl.pixels[centre] / cpu.pixels[centre]);
      // Tolerance: both backends add the disc by the same host pass (AddSunDiscOnHost, in double),
      // the GL frame on the GPU's transmittance table read back: the pixel differs by the tables
      // (up to 2.2e-4 relative, above) plus the frame's sky under the disc. Measured on llvmpipe: +2e-6.
      EXPECT_NEAR(gl.pixels[centre] / cpu.pixels[centre], 1.0, SamplerSlack(context) * 3e-4);
    }
    // Tolerance: the tables differ by float-vs-double (above: ~1e-4 relative), and the frame
    // adds float camera rays and uv (the CPU lookup is float too) and the GPU's bilinear
    // filtering; where the sky-view table changes steeply (across the horizon rows) a uv
    // difference of ~1e-7 moves the result by up to ~1e-4 relative.
    // Measured on llvmpipe: max rel 1.0e-3, mean rel 2.2e-4 (perspective), 1.7e-4 (fisheye),
    // 6.7e-5 (equirect).
    EXPECT_LT(d.max_rel, SamplerSlack(context) * 2e-3);
    EXPECT_LT(d.mean_rel, SamplerSlack(context) * 5e-4);
    EXPECT_EQ(d.max_abs_alpha, 0.0);
  }
}

// Above the atmosphere, and with sky_view=off, every pixel is ray marched (with the lit ground
// per pixel): the GL frame against the CPU's per-pixel ray march.
TEST(GlHillaire, RayMarchedFrameMatchesCpu) {
  ATMO_REQUIRE_GL_CONTEXT(context);
  const AtmosphereParameters earth = Preset("earth");
  struct Case {
    double altitude_m;
    bool sky_view;
    CameraKind kind;
    double pitch_deg;
  };
  for (const Case c : {Case{400e3, true, CameraKind::kPerspective, -60.0}, Case{400e3, true, CameraKind::kEquirect, 0.0},
                       Case{1000.0, false, CameraKind::kPerspective, 10.0}}) {
    HillaireSettings settings;
    settings.use_sky_view_lut = c.sky_view;
    HillaireModel model(earth, settings);
    model.Precompute();
    RenderSettings render;
    render.camera = {c.kind, 48, 24, 90.0, 180.0, c.pitch_deg};
    render.altitude_m = c.altitude_m;
    render.sun_elevation_deg = 20.0;
    render.sun_azimuth_deg = 150.0;
    render.terms = RadianceTerms{true, true};
    PassTimings timings;
    const auto [gl, cpu] = RenderOnBothBackends(context, earth, model, render, timings);
    EXPECT_LT(timings.LastMs("sky_view_lut"), 0.0) << "the frame should be ray marched, not looked up";
    ASSERT_EQ(gl.pixels.size(), cpu.pixels.size());
    const FrameDifference d = CompareFrames(gl, cpu, cpu.pixels.size());
    std::printf("ray-marched frame %s at %.0f m (sky_view %s): GL vs CPU max rel %.3g, mean rel %.3g\n",
                std::string(ToString(c.kind)).c_str(), c.altitude_m, c.sky_view ? "auto" : "off", d.max_rel,
                d.mean_rel);
    // Tolerance: the same float-vs-double per-step errors as the sky-view table (~1e-4 relative
    // on average), now per pixel and without a table's bilinear taps. Measured on llvmpipe: max
    // rel 1.9e-5 / 3.9e-5 (400 km, perspective / equirect, limb included), 1.3e-4 (1 km);
    // mean rel <= 1.1e-5. The bounds leave room for grazing rays at the limb, where distances
    // are square roots of small differences of ~4e7 km^2 terms in float.
    EXPECT_LT(d.max_rel, SamplerSlack(context) * 1e-3);
    EXPECT_LT(d.mean_rel, SamplerSlack(context) * 1e-4);
    EXPECT_EQ(d.max_abs_alpha, 0.0);
  }
}

// `atmo sample` on GL: the radiance and transmittance of single directions against the CPU view,
// through the sky-view table (ground) and by ray march (above the atmosphere).
TEST(GlHillaire, SampleMatchesCpu) {
  ATMO_REQUIRE_GL_CONTEXT(context);
  const AtmosphereParameters earth = Preset("earth");
  HillaireModel model(earth, HillaireSettings{});
  model.Precompute();
  HillaireGl sky(context, earth, HillaireSettings{});
  sky.Precompute();
  std::vector<glm::dvec3> views;
  for (double zenith_deg = 2.0; zenith_deg < 180.0; zenith_deg += 11.0) {
    for (double azimuth_deg = 0.0; azimuth_deg < 360.0; azimuth_deg += 45.0) {
      const double theta = glm::radians(zenith_deg);
      const double phi = glm::radians(azimuth_deg);
      views.emplace_back(std::sin(theta) * std::sin(phi), std::sin(theta) * std::cos(phi), std::cos(theta));
    }
  }
  for (const double altitude_m : {0.0, 8000.0, 300e3}) {
    const glm::dvec3 sun = SunDirection(25.0, 0.0);
    sky.SetView(altitude_m, sun, false);
    EXPECT_EQ(sky.uses_sky_view(), altitude_m < 100e3);
    std::vector<double> radiance, transmittance;  // 3 values per view
    sky.Sample(views, radiance, transmittance);
    const std::unique_ptr<SkyView> view = model.View(altitude_m, sun);
    double max_rel = 0.0;
    double max_abs_t = 0.0;
    std::vector<double> l(3), t(3);
    for (std::size_t i = 0; i < views.size(); ++i) {
      view->Radiance(views[i], l);
      view->Transmittance(views[i], t);
      for (int c = 0; c < 3; ++c) {
        if (l[c] > 1e-4) max_rel = std::max(max_rel, std::abs(radiance[3 * i + c] - l[c]) / l[c]);
        max_abs_t = std::max(max_abs_t, std::abs(transmittance[3 * i + c] - t[c]));
      }
    }
    std::printf("sample at %.0f m, %zu directions: GL vs CPU radiance max rel %.3g, transmittance max abs %.3g\n",
                altitude_m, views.size(), max_rel, max_abs_t);
    // Tolerance: as the sky-view table and the ray-marched frame (float against double, ~1e-4
    // relative per table, the GPU's bilinear taps); the transmittance is one lookup of the
    // transmittance table (max abs 1.5e-5 between the backends' tables).
    EXPECT_LT(max_rel, SamplerSlack(context) * 2e-3);
    EXPECT_LT(max_abs_t, SamplerSlack(context) * 5e-5);
  }
}

// The aerial-perspective volume (Hillaire 2020's fourth table) against the CPU's.
TEST(GlHillaire, AerialPerspectiveMatchesCpu) {
  ATMO_REQUIRE_GL_CONTEXT(context);
  const AtmosphereParameters earth = Preset("earth");
  HillaireModel model(earth, HillaireSettings{});
  model.Precompute();
  HillaireGl sky(context, earth, HillaireSettings{});
  sky.Precompute();
  struct Case {
    double altitude_m;
    double max_distance_m;
  };
  for (const Case c : {Case{500.0, 32000.0}, Case{10000.0, 200000.0}}) {
    const Camera camera{CameraKind::kPerspective, 320, 180, 90.0, 150.0, -5.0};
    const AerialPerspectiveSettings settings{16, 8, 16, c.max_distance_m};
    const glm::dvec3 sun = SunDirection(12.0, 180.0);
    sky.SetView(c.altitude_m, sun, false);
    PassTimings timings;
    const AerialPerspectiveVolume gl = sky.ComputeAerialPerspective(camera, settings, &timings);
    const AerialPerspectiveVolume cpu = ComputeAerialPerspectiveVolume(*model.View(c.altitude_m, sun), camera, settings);
    double max_rel_l = 0.0;
    double max_abs_t = 0.0;
    for (int z = 0; z < settings.depth; ++z) {
      for (int y = 0; y < settings.height; ++y) {
        for (int x = 0; x < settings.width; ++x) {
          for (std::size_t ch = 0; ch < 3; ++ch) {
            const double l = cpu.RadianceAt(x, y, z, ch);
            if (l > 1e-4) max_rel_l = std::max(max_rel_l, std::abs(gl.RadianceAt(x, y, z, ch) - l) / l);
            max_abs_t = std::max(max_abs_t, std::abs(gl.TransmittanceAt(x, y, z, ch) - cpu.TransmittanceAt(x, y, z, ch)));
          }
        }
      }
    }
    std::printf("aerial perspective 16x8x16 to %.0f km from %.0f m: GL vs CPU radiance max rel %.3g, transmittance "
                "max abs %.3g; GPU %.2f ms\n",
                c.max_distance_m / 1000.0, c.altitude_m, max_rel_l, max_abs_t, timings.LastMs("aerial_perspective_lut"));
    // Tolerance: the ray march of the ray-marched frames (float against double, ~1e-4 relative
    // per sample, averaged along the segment) plus the multiple-scattering table's lookups.
    // Measured on llvmpipe: radiance max rel 1.3e-4 (32 km) and 7.2e-5 (200 km), transmittance
    // max abs 8.2e-6.
    EXPECT_LT(max_rel_l, SamplerSlack(context) * 1e-3);
    EXPECT_LT(max_abs_t, SamplerSlack(context) * 1e-4);
    EXPECT_GT(cpu.RadianceAt(8, 4, 15, 2), 0.0) << "the far slices should hold in-scattered light";
  }
  EXPECT_THROW(sky.ComputeAerialPerspective(Camera{}, AerialPerspectiveSettings{0, 8, 8, 1000.0}), Error);
}

// Spectral atmospheres: the channels in batches of three, each batch with its own GPU tables.
// MakeSpectral(earth, 7) is three batches, the last with one channel (repeated), so every path
// through the batch loop is taken. Its 360 nm channel has ~5x the Rayleigh optical depth of
// earth's blue (440 nm): the float-vs-double differences of the RGB tests are those of the
// kernels, and the bounds below are measured on this atmosphere.
AtmosphereParameters SpectralEarth(int channel_count) { return MakeSpectral(Preset("earth"), channel_count); }

TEST(GlHillaireSpectral, TablesMatchCpuInEveryBatch) {
  ATMO_REQUIRE_GL_CONTEXT(context);
  const AtmosphereParameters spectral = SpectralEarth(7);
  HillaireModel model(spectral, HillaireSettings{});
  model.Precompute();
  HillaireGl sky(context, spectral, HillaireSettings{});
  EXPECT_EQ(sky.channel_count(), 7u);
  ASSERT_EQ(sky.batch_count(), 3u);
  ASSERT_EQ(model.batches().size(), 3u);
  PassTimings timings;
  sky.Precompute(&timings);
  sky.SetView(1000.0, SunDirection(15.0, 180.0), /*ground=*/true, &timings);
  const double r_m = model.batches()[0].atmosphere.bottom_radius + 1000.0;
  const double mu_s = std::sin(glm::radians(15.0));
  for (std::size_t b = 0; b < 3; ++b) {
    const HillaireModel::Batch& cpu = model.batches()[b];
    const Difference t = Compare(sky.ReadTransmittance(b), cpu.transmittance);
    const Difference m = Compare(sky.ReadMultipleScattering(b), cpu.multiple_scattering);
    const Difference g = Compare(sky.ReadGroundIrradiance(b), cpu.ground_irradiance);
    Texture2D cpu_view = model.ComputeSkyViewLut(cpu, r_m, mu_s);
    model.AddGroundView(cpu, r_m, mu_s, cpu_view);
    // The two rows at the split: the tangent horizon ray from 1 km (GlHillaire.GroundViewMatchesCpu).
    const int half = cpu_view.height / 2;
    const Difference v = Compare(sky.ReadSkyAndGroundView(b), cpu_view, half - 1, half + 1);
    std::printf("spectral 7, batch %zu: GL vs CPU transmittance max abs %.3g max rel %.3g; multiple scattering "
                "max rel %.3g; ground irradiance max rel %.3g; sky + ground view max rel %.3g\n",
                b, t.max_abs, t.max_rel, m.max_rel, g.max_rel, v.max_rel);
    // Tolerances: the RGB tests' (transmittance 5e-4 relative; multiple scattering 2e-4 and
    // ground irradiance 1e-3 from a shared CPU transmittance table; sky and ground view 5e-4),
    // each table now also inheriting the GL transmittance table's difference (<= 2.5e-4
    // relative) through the tables it reads. The absolute transmittance bound is twice the RGB
    // test's 3e-5: the float altitude error is relative to the optical depth, which at 360 nm is
    // ~5x that at 440 nm, so dT = T d(tau) is larger. Measured on llvmpipe, over the three
    // batches: transmittance max abs 2.7e-5, max rel 2.5e-4; multiple scattering max rel 6.5e-5;
    // ground irradiance 1.9e-5; sky + ground view 3.9e-4.
    EXPECT_LT(t.max_abs, GlBound(context, 6e-5, 1.3e-4)) << b;  // H200: 6.2e-5 (batch 2)
    EXPECT_LT(t.max_rel, GlBound(context, 5e-4, 1.2e-3)) << b;  // H200: 5.4e-4
    EXPECT_LT(m.max_rel, SamplerSlack(context) * 1e-3) << b;
    EXPECT_LT(g.max_rel, SamplerSlack(context) * 2e-3) << b;
    EXPECT_LT(v.max_rel, SamplerSlack(context) * 1e-3) << b;
  }
  // Each pass ran once per batch, timed as one pass (the sum of its batches).
  for (const char* pass : {"transmittance_lut", "multiple_scattering_lut", "ground_irradiance_lut", "sky_view_lut",
                           "ground_view_lut"}) {
    EXPECT_GE(timings.LastMs(pass), 0.0) << pass;
  }
  EXPECT_THROW(sky.ReadTransmittance(3), std::out_of_range);
}

// The GPU's form of the table passes (Context::work_group_forms: each ray's march split into
// segments over a run of invocations, weighed by the throughputs before them, the texel's rays
// summed over the work group) against a texel per invocation, the form of llvmpipe and of the
// comparisons with the CPU above, on whatever context runs the tests: the same sums, added in
// another order. For the Hillaire 2020 table (1 order) and the gathered one (4, the default).
TEST(GlHillaire, WorkGroupFormsMatchATexelPerInvocation) {
  ATMO_REQUIRE_GL_CONTEXT(context);
  const AtmosphereParameters earth = Preset("earth");
  struct Tables {
    Texture2D transmittance, multiple_scattering, ground_irradiance, view;
  };
  const auto decoded = [](Texture2D t) {
    for (glm::vec3& v : t.texels) v = glm::vec3(shared::DecodeMultiScattering(shared::vec3(v)));
    return t;
  };
  for (const int orders : {1, 4}) {
    HillaireSettings settings;
    settings.multiple_scattering_orders = orders;
    const auto build = [&](bool work_group_forms) {
      const testing::ScopedWorkGroupForms forms(work_group_forms);
      HillaireGl sky(context, earth, settings);
      sky.Precompute(nullptr);
      sky.SetView(1000.0, SunDirection(15.0, 180.0), /*ground=*/true, nullptr);
      return Tables{sky.ReadTransmittance(0), decoded(sky.ReadMultipleScattering(0)), sky.ReadGroundIrradiance(0),
                    sky.ReadSkyAndGroundView(0)};
    };
    const Tables per_texel = build(false);
    const Tables grouped = build(true);
    const Difference t = Compare(grouped.transmittance, per_texel.transmittance);
    const Difference m = Compare(grouped.multiple_scattering, per_texel.multiple_scattering);
    const Difference g = Compare(grouped.ground_irradiance, per_texel.ground_irradiance);
    const Difference v = Compare(grouped.view, per_texel.view);
    std::printf("%d order(s): work-group forms vs a texel per invocation, max rel: transmittance %.3g, multiple "
                "scattering %.3g, ground irradiance %.3g, sky + ground view %.3g\n",
                orders, t.max_rel, m.max_rel, g.max_rel, v.max_rel);
    // Float sums of 5 to 41 terms per invocation and of up to 256 partial sums, in another
    // order: a few float ulp per addition, and each table inherits the differences of the tables
    // it reads. Measured on llvmpipe (Mesa 22.3.6): transmittance 2.6e-6, multiple scattering 1.1e-6,
    // ground irradiance 3.7e-7, sky and ground view 6.3e-7 (either order count).
    EXPECT_LT(t.max_rel, 1e-5);
    EXPECT_LT(m.max_rel, 1e-4);
    EXPECT_LT(g.max_rel, 1e-4);
    EXPECT_LT(v.max_rel, 1e-4);
  }
}

// The frame, one channel per wavelength, against the CPU's N-channel render, for each camera;
// the perspective camera's centre pixel looks at the sun, whose disc the host adds per channel.
// The cameras are GlHillaire.FrameMatchesCpuForEachCamera's (65 x 33), whose pixel centres keep
// off the horizon rows: at 63 x 31 one perspective pixel centre lies at the horizon, where the
// ground-view table steps from sky to ground, and differs by 1.1e-2 (830 nm; measured).
TEST(GlHillaireSpectral, FrameMatchesCpu) {
  ATMO_REQUIRE_GL_CONTEXT(context);
  const AtmosphereParameters spectral = SpectralEarth(5);
  HillaireModel model(spectral, HillaireSettings{});
  model.Precompute();
  for (const CameraKind kind : {CameraKind::kPerspective, CameraKind::kFisheye, CameraKind::kEquirect}) {
    RenderSettings render;
    render.camera = {kind, 65, 33, 90.0, 180.0, 10.0};
    render.altitude_m = 500.0;
    render.sun_elevation_deg = 10.0;
    render.sun_azimuth_deg = 180.0;
    render.terms = RadianceTerms{true, true};
    PassTimings timings;
    const auto [gl, cpu] = RenderOnBothBackends(context, spectral, model, render, timings);
    ASSERT_EQ(gl.channels, 5);
    ASSERT_EQ(cpu.channels, 5);
    ASSERT_EQ(gl.pixels.size(), cpu.pixels.size());
    const std::size_t sun_pixel = 16 * 65 + 32;
    const FrameDifference d =
        CompareFrames(gl, cpu, kind == CameraKind::kPerspective ? sun_pixel : cpu.pixels.size());
    std::printf("spectral 5 frame %s 65x33: GL vs CPU max rel %.3g (pixel (%zu, %zu), channel %zu: GL %.6g, CPU "
                "%.6g), mean rel %.3g, alpha max diff %.3g\n",
                std::string(ToString(kind)).c_str(), d.max_rel, d.worst / 5 % 65, d.worst / 5 / 65, d.worst % 5,
                gl.pixels[d.worst], cpu.pixels[d.worst], d.mean_rel, d.max_abs_alpha);
    if (kind == CameraKind::kPerspective) {
      double worst = 0.0;
      for (std::size_t c = 0; c < 5; ++c) {
        const std::size_t i = sun_pixel * 5 + c;
        EXPECT_GT(cpu.pixels[i], 100.0f * cpu.pixels[c]) << "the centre pixel should see the sun disc, channel " << c;
        worst = std::max(worst, std::abs(double(gl.pixels[i]) / cpu.pixels[i] - 1.0));
      }
      std::printf("spectral 5 sun disc pixel: GL / CPU - 1 at most %.3g over the channels\n", worst);
      // Tolerance: as GlHillaire.FrameMatchesCpuForEachCamera's disc pixel (the same host pass,
      // on each batch's GL transmittance table). Measured on llvmpipe: 1.6e-5.
      EXPECT_LT(worst, SamplerSlack(context) * 3e-4);
    }
    // Tolerance: GlHillaire.FrameMatchesCpuForEachCamera's (2e-3 max, 5e-4 mean), per channel.
    // Measured on llvmpipe: max rel 1.2e-3 / 1.3e-3 / 1.2e-3 (perspective / fisheye / equirect,
    // all at 830 nm), mean rel 2.2e-4 / 1.7e-4 / 6.7e-5: those of the RGB frames.
    EXPECT_LT(d.max_rel, SamplerSlack(context) * 2e-3);
    EXPECT_LT(d.mean_rel, SamplerSlack(context) * 5e-4);
    EXPECT_EQ(d.max_abs_alpha, 0.0);
  }
}

// `atmo sample` and the aerial perspective on GL with 5 channels: every channel of every
// direction against the CPU view, by the sky-view table (ground) and by ray march (300 km).
TEST(GlHillaireSpectral, SampleAndAerialPerspectiveMatchCpu) {
  ATMO_REQUIRE_GL_CONTEXT(context);
  const AtmosphereParameters spectral = SpectralEarth(5);
  HillaireModel model(spectral, HillaireSettings{});
  model.Precompute();
  HillaireGl sky(context, spectral, HillaireSettings{});
  sky.Precompute();
  std::vector<glm::dvec3> views;
  for (double zenith_deg = 2.0; zenith_deg < 180.0; zenith_deg += 11.0) {
    for (double azimuth_deg = 0.0; azimuth_deg < 360.0; azimuth_deg += 45.0) {
      const double theta = glm::radians(zenith_deg);
      const double phi = glm::radians(azimuth_deg);
      views.emplace_back(std::sin(theta) * std::sin(phi), std::sin(theta) * std::cos(phi), std::cos(theta));
    }
  }
  const glm::dvec3 sun = SunDirection(25.0, 0.0);
  for (const double altitude_m : {0.0, 300e3}) {
    sky.SetView(altitude_m, sun, false);
    std::vector<double> radiance, transmittance;
    sky.Sample(views, radiance, transmittance);
    ASSERT_EQ(radiance.size(), 5 * views.size());
    ASSERT_EQ(transmittance.size(), 5 * views.size());
    const std::unique_ptr<SkyView> view = model.View(altitude_m, sun);
    double max_rel = 0.0;
    double max_abs_t = 0.0;
    std::vector<double> l(5), t(5);
    for (std::size_t i = 0; i < views.size(); ++i) {
      view->Radiance(views[i], l);
      view->Transmittance(views[i], t);
      for (std::size_t c = 0; c < 5; ++c) {
        if (l[c] > 1e-4) max_rel = std::max(max_rel, std::abs(radiance[5 * i + c] - l[c]) / l[c]);
        max_abs_t = std::max(max_abs_t, std::abs(transmittance[5 * i + c] - t[c]));
      }
    }
    std::printf("spectral 5 sample at %.0f m: GL vs CPU radiance max rel %.3g, transmittance max abs %.3g\n",
                altitude_m, max_rel, max_abs_t);
    // Tolerance: GlHillaire.SampleMatchesCpu's (2e-3, 5e-5), per channel. Measured on llvmpipe:
    // radiance max rel 5.8e-4 (0 m) and 4.3e-5 (300 km), transmittance max abs 6.5e-6.
    EXPECT_LT(max_rel, SamplerSlack(context) * 2e-3);
    EXPECT_LT(max_abs_t, SamplerSlack(context) * 5e-5);
  }
  // The aerial perspective, 5 values per froxel.
  sky.SetView(500.0, sun, false);
  const Camera camera{CameraKind::kPerspective, 320, 180, 90.0, 150.0, -5.0};
  const AerialPerspectiveSettings settings{8, 4, 8, 32000.0};
  const AerialPerspectiveVolume gl = sky.ComputeAerialPerspective(camera, settings);
  const AerialPerspectiveVolume cpu = ComputeAerialPerspectiveVolume(*model.View(500.0, sun), camera, settings);
  ASSERT_EQ(gl.channel_count(), 5u);
  double max_rel_l = 0.0;
  for (int z = 0; z < settings.depth; ++z) {
    for (int y = 0; y < settings.height; ++y) {
      for (int x = 0; x < settings.width; ++x) {
        for (std::size_t c = 0; c < 5; ++c) {
          const double l = cpu.RadianceAt(x, y, z, c);
          if (l > 1e-4) max_rel_l = std::max(max_rel_l, std::abs(gl.RadianceAt(x, y, z, c) - l) / l);
        }
      }
    }
  }
  std::printf("spectral 5 aerial perspective: GL vs CPU radiance max rel %.3g\n", max_rel_l);
  // Tolerance: GlHillaire.AerialPerspectiveMatchesCpu's (1e-3). Measured on llvmpipe: 2.0e-4.
  EXPECT_LT(max_rel_l, SamplerSlack(context) * 1e-3);
}

TEST(GlHillaire, RejectsWhatItCannotRender) {
  ATMO_REQUIRE_GL_CONTEXT(context);
  EXPECT_THROW(HillaireGl(context, Preset("simple"), HillaireSettings{}), Error);
  RenderSettings render;
  render.camera = {CameraKind::kPerspective, 8, 4};
  render.altitude_m = -1.0;
  EXPECT_THROW(RenderHillaireGl(context, Preset("earth"), HillaireSettings{}, render), Error);
  HillaireGl sky(context, Preset("earth"), HillaireSettings{});
  EXPECT_THROW(sky.SetView(0.0, {0.0, 0.0, 1.0}, false), Error) << "SetView before Precompute";
}

using GlCliTest = atmo::testing::CliFixture;

TEST_F(GlCliTest, RenderWritesBothFiles) {
  if (GetSharedContext().context == nullptr) GTEST_SKIP() << GetSharedContext().error;
  const atmo::testing::RunResult r = Run("render --model hillaire --preset earth --backend gl --width 64 --height 32 --exr sky.exr --png sky.png");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(std::filesystem::exists(dir_ / "sky.exr"));
  EXPECT_TRUE(std::filesystem::exists(dir_ / "sky.png"));
  EXPECT_NE(r.out.find("wrote sky.exr, sky.png (64x32 perspective, hillaire, earth)"), std::string::npos) << r.out;
}

TEST_F(GlCliTest, BenchReportsTheGlPasses) {
  if (GetSharedContext().context == nullptr) GTEST_SKIP() << GetSharedContext().error;
  const atmo::testing::RunResult r = Run("bench --backend gl --quick --width 64 --height 32");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  for (const char* pass : {"transmittance_lut", "multiple_scattering_lut", "sky_view_lut", "all_luts", "frame_64x32"}) {
    EXPECT_NE(r.out.find(pass), std::string::npos) << pass << "\n" << r.out;
  }
}


// The radiance column of an `atmo sample` CSV (docs/design.md section 4), row by row.
std::vector<double> RadianceColumn(const std::string& csv) {
  std::vector<double> radiance;
  const std::vector<std::string> lines = atmo::testing::Lines(csv);
  for (std::size_t i = 1; i < lines.size(); ++i) radiance.push_back(std::stod(atmo::testing::Split(lines[i])[5]));
  return radiance;
}

// Largest relative difference of b from a where a > floor; the sizes must agree.
double MaxRelativeDifference(const std::vector<double>& a, const std::vector<double>& b, double floor) {
  EXPECT_EQ(a.size(), b.size());
  double worst = 0.0;
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
    if (a[i] > floor) worst = std::max(worst, std::abs(b[i] - a[i]) / a[i]);
  }
  return worst;
}

constexpr const char* kSampleGrid =
    "altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg\n"
    "0,45,60,90\n0,45,89,0\n0,45,30,180\n1000,80,89,0\n1000,80,45,120\n8000,95,80,0\n300000,60,100,10\n"
    "0,45,120,30\n";

// Runs `sample` (its flags without --backend and --out) on both backends and returns the largest
// relative difference of the radiance column; fails the test if either run fails or the CSVs do
// not have `rows` rows.
class GlSampleTest : public GlCliTest {
 protected:
  double SampleGlVersusCpu(const std::string& sample, std::size_t rows) const {
    const atmo::testing::RunResult cpu = Run(sample + " --out cpu.csv");
    const atmo::testing::RunResult gl = Run(sample + " --backend gl --out gl.csv");
    EXPECT_EQ(cpu.exit_code, 0) << cpu.err;
    EXPECT_EQ(gl.exit_code, 0) << gl.err;
    const std::vector<double> a = RadianceColumn(atmo::testing::ReadFile(dir_ / "cpu.csv"));
    const std::vector<double> b = RadianceColumn(atmo::testing::ReadFile(dir_ / "gl.csv"));
    EXPECT_EQ(a.size(), rows);
    EXPECT_EQ(b.size(), rows);
    if (a.size() != rows || b.size() != rows) return 1e300;
    const double worst = MaxRelativeDifference(a, b, 1e-6);
    std::printf("atmo %s: gl vs cpu max rel %.3g\n", sample.c_str(), worst);
    return worst;
  }
};

TEST_F(GlSampleTest, SampleMatchesTheCpuBackend) {
  if (GetSharedContext().context == nullptr) GTEST_SKIP() << GetSharedContext().error;
  atmo::testing::WriteFile(dir_ / "grid.csv", kSampleGrid);
  for (const char* model : {"--model hillaire --preset earth", "--model elek --preset atmosphere-plus --option size=16x64x16"}) {
    const double worst = SampleGlVersusCpu(std::string("sample ") + model + " --grid grid.csv", 8u * 3u);
    // Tolerance: the tables' float-vs-double differences (GlHillaire.SampleMatchesCpu, the elek
    // table tests in gl_elek_test.cc), including twilight (sun 95 degrees) where the values are
    // 1e-4 of the day's. Measured on llvmpipe: 7.1e-4 (hillaire), 1.5e-5 (elek).
    EXPECT_LT(worst, SamplerSlack(*GetSharedContext().context) * 2e-3) << model;
  }
}

// The in-range extremes of docs/reliability.md in float on the GPU: every sample finite (the
// GLSL clamps map NaN into the tables, and the bounds keep float's intermediates finite).
TEST_F(GlCliTest, InRangeExtremesGiveFiniteSamples) {
  if (GetSharedContext().context == nullptr) GTEST_SKIP() << GetSharedContext().error;
  atmo::testing::WriteFile(dir_ / "grid.csv", "altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg\n"
                                              "0,30,60,90\n0,30,90,0\n0,95,90,0\n1e6,30,180,0\n1e11,30,180,0\n");
  const char* extremes[] = {
      R"({"ground_radius_m": 1, "top_radius_m": 1.00001})",
      R"({"ground_radius_m": 1, "top_radius_m": 11})",
      R"({"ground_radius_m": 1e10, "top_radius_m": 1.00001e10})",
      R"({"rayleigh": {"scattering_per_m": 1000}, "mie": {"absorption_per_m": 1000}})",
      R"({"mie": {"phase_g": 0.999, "density": {"upper": {"exp_term": 1e6, "exp_scale_per_m": 1e6,
          "linear_term_per_m": -1e6, "constant_term": -1e6}}}, "sun_angular_radius_rad": 1e-6})",
  };
  for (const char* json : extremes) {
    atmo::testing::WriteFile(dir_ / "extreme.json", json);
    for (const char* model : {"--model hillaire", "--model elek --option size=4x8x4 --option orders=1"}) {
      const atmo::testing::RunResult r =
          Run(std::string("sample --backend gl ") + model + " --config extreme.json --grid grid.csv", 60);
      ASSERT_EQ(r.exit_code, 0) << json << " " << model << ": " << r.err;
      const std::vector<std::string> lines = atmo::testing::Lines(r.out);
      ASSERT_EQ(lines.size(), 1u + 5u * 3u) << json << " " << model;
      for (std::size_t i = 1; i < lines.size(); ++i) {
        for (const std::string& field : atmo::testing::Split(lines[i])) {
          EXPECT_TRUE(std::isfinite(std::strtod(field.c_str(), nullptr))) << json << " " << model << ": " << lines[i];
        }
      }
    }
  }
}

TEST_F(GlCliTest, PrecomputeOnGlWritesATableTheCpuLoads) {
  if (GetSharedContext().context == nullptr) GTEST_SKIP() << GetSharedContext().error;
  const std::string elek = "--model elek --preset atmosphere-plus --option size=8x32x8 --option orders=2";
  const atmo::testing::RunResult r = Run("precompute --backend gl " + elek + " --out table");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  atmo::testing::WriteFile(dir_ / "grid.csv", kSampleGrid);
  const atmo::testing::RunResult loaded = Run("sample " + elek + " --option table=table --grid grid.csv --out loaded.csv");
  const atmo::testing::RunResult cpu = Run("sample " + elek + " --grid grid.csv --out cpu.csv");
  ASSERT_EQ(loaded.exit_code, 0) << loaded.err;
  ASSERT_EQ(cpu.exit_code, 0) << cpu.err;
  const double worst = MaxRelativeDifference(RadianceColumn(atmo::testing::ReadFile(dir_ / "cpu.csv")),
                                             RadianceColumn(atmo::testing::ReadFile(dir_ / "loaded.csv")), 1e-6);
  std::printf("elek table precomputed on gl, loaded on the cpu: max rel %.3g against the cpu table\n", worst);
  // As SampleMatchesTheCpuBackend (measured 2.3e-5).
  EXPECT_LT(worst, SamplerSlack(*GetSharedContext().context) * 2e-3);
}

// `atmo render --spectral 5 --unit luminance` on GL: the five channels rendered in two batches and
// converted to luminance (linear sRGB, Y in cd/m^2) exactly as on the CPU.
TEST_F(GlCliTest, SpectralRenderMatchesTheCpuBackend) {
  if (GetSharedContext().context == nullptr) GTEST_SKIP() << GetSharedContext().error;
  const std::string render = "render --model hillaire --preset earth --spectral 5 --unit luminance --width 64 --height 32 --sun-elevation 12 --png '' ";
  const atmo::testing::RunResult cpu = Run(render + "--exr cpu.exr");
  const atmo::testing::RunResult gl = Run(render + "--backend gl --exr gl.exr");
  ASSERT_EQ(cpu.exit_code, 0) << cpu.err;
  ASSERT_EQ(gl.exit_code, 0) << gl.err;
  const Image a = ReadExr(dir_ / "cpu.exr");
  const Image b = ReadExr(dir_ / "gl.exr");
  ASSERT_EQ(a.channels, 3);
  ASSERT_EQ(b.channels, 3);
  ASSERT_EQ(a.pixels.size(), b.pixels.size());
  // The sun disc (pixels above 100x the median) is compared apart, as its few pixels hold ~10^4
  // times the sky's luminance.
  std::vector<float> sorted = a.pixels;
  std::sort(sorted.begin(), sorted.end());
  const float median = sorted[sorted.size() / 2];
  double sky_max_rel = 0.0, disc_max_rel = 0.0;
  int disc_values = 0;
  for (std::size_t i = 0; i < a.pixels.size(); ++i) {
    if (a.pixels[i] <= 1e-2f * median) continue;
    const double rel = std::abs(double(b.pixels[i]) - a.pixels[i]) / a.pixels[i];
    const bool disc = a.pixels[i] > 100.0f * median;
    disc_values += disc;
    double& worst = disc ? disc_max_rel : sky_max_rel;
    worst = std::max(worst, rel);
  }
  std::printf("render --spectral 5 --unit luminance: gl vs cpu max rel %.3g (sky), %.3g (sun disc, %d values)\n",
              sky_max_rel, disc_max_rel, disc_values);
  // Tolerance: the frames' (GlHillaireSpectral.FrameMatchesCpu: 2e-3 per channel), through the
  // same linear conversion (a weighted sum of the channels, all positive weights for Y, so a
  // relative bound per channel bounds Y; the R, G, B of the matrix mix signs, but the sky's
  // values are far from 0). The disc's pixels (12 values) are the host pass on the GL
  // transmittance tables: 1e-3, a factor of 2 over the transmittance's 5e-4. Measured on
  // llvmpipe: 1.0e-3 (sky), 3.7e-6 (disc).
  const double slack = SamplerSlack(*GetSharedContext().context);
  EXPECT_GT(disc_values, 0) << "the camera should see the sun disc";
  EXPECT_LT(sky_max_rel, slack * 2e-3);
  EXPECT_LT(disc_max_rel, slack * 1e-3);
}

// `atmo sample --spectral 5` on GL: all five rows of every point, as the CPU's.
TEST_F(GlSampleTest, SpectralSampleMatchesTheCpuBackend) {
  if (GetSharedContext().context == nullptr) GTEST_SKIP() << GetSharedContext().error;
  atmo::testing::WriteFile(dir_ / "grid.csv", kSampleGrid);
  for (const char* model : {"--model hillaire --preset earth", "--model elek --preset earth --option size=16x64x16"}) {
    const double worst = SampleGlVersusCpu(std::string("sample --spectral 5 ") + model + " --grid grid.csv", 8u * 5u);
    // Tolerance: SampleMatchesTheCpuBackend's (2e-3). Measured on llvmpipe: 6.8e-4 (hillaire),
    // 4.0e-5 (elek).
    EXPECT_LT(worst, SamplerSlack(*GetSharedContext().context) * 2e-3) << model;
  }
}

// The elek table of a 5-channel atmosphere precomputed on GL: both batches exported (the format's
// one table per batch, include/atmo/elek.h), loaded by the CPU, and answering as the CPU's table.
TEST_F(GlCliTest, SpectralPrecomputeOnGlWritesATableTheCpuLoads) {
  if (GetSharedContext().context == nullptr) GTEST_SKIP() << GetSharedContext().error;
  const std::string elek = "--model elek --preset earth --spectral 5 --option size=8x32x8 --option orders=2";
  const atmo::testing::RunResult r = Run("precompute --backend gl " + elek + " --out table");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(atmo::testing::ReadFile(dir_ / "table.json").find("\"batches\": 2"), std::string::npos);
  atmo::testing::WriteFile(dir_ / "grid.csv", kSampleGrid);
  const atmo::testing::RunResult loaded =
      Run("sample " + elek + " --option table=table --grid grid.csv --out loaded.csv");
  const atmo::testing::RunResult cpu = Run("sample " + elek + " --grid grid.csv --out cpu.csv");
  ASSERT_EQ(loaded.exit_code, 0) << loaded.err;
  ASSERT_EQ(cpu.exit_code, 0) << cpu.err;
  const std::vector<double> a = RadianceColumn(atmo::testing::ReadFile(dir_ / "cpu.csv"));
  ASSERT_EQ(a.size(), 8u * 5u);
  const double worst = MaxRelativeDifference(a, RadianceColumn(atmo::testing::ReadFile(dir_ / "loaded.csv")), 1e-6);
  std::printf("spectral elek table precomputed on gl, loaded on the cpu: max rel %.3g against the cpu table\n", worst);
  // As PrecomputeOnGlWritesATableTheCpuLoads (2e-3). Measured on llvmpipe: 1.8e-5.
  EXPECT_LT(worst, SamplerSlack(*GetSharedContext().context) * 2e-3);
}

// `atmo bench --backend gl` with 4 channels (two batches): the passes under their usual names.
TEST_F(GlCliTest, BenchRunsSpectralOnGl) {
  if (GetSharedContext().context == nullptr) GTEST_SKIP() << GetSharedContext().error;
  for (const char* model : {"--model hillaire --preset earth", "--model elek --preset earth --option size=8x32x8 --option orders=2"}) {
    const atmo::testing::RunResult r =
        Run(std::string("bench --backend gl --spectral 4 --repeat 1 --width 32 --height 16 ") + model);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    for (const char* pass : {"_lut", "all_luts", "frame_32x16"}) {
      EXPECT_NE(r.out.find(pass), std::string::npos) << pass << "\n" << r.out;
    }
  }
}

TEST_F(GlCliTest, BenchRunsElekOnGl) {
  if (GetSharedContext().context == nullptr) GTEST_SKIP() << GetSharedContext().error;
  const atmo::testing::RunResult r = Run(
      "bench --backend gl --model elek --preset atmosphere-plus --option size=8x32x8 --option orders=2 --quick "
      "--width 32 --height 16");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  for (const char* pass : {"elek_single_lut", "elek_scatter_2_lut", "all_luts", "frame_32x16", "gl device"}) {
    EXPECT_NE(r.out.find(pass), std::string::npos) << pass << "\n" << r.out;
  }
}

}  // namespace
}  // namespace atmo::gl

namespace atmo::gl {
namespace {

// The moon on the GL backend (a second GL frame lit from the moon's direction, added on the host
// with its disc: atmo::AddMoonLight) against the CPU's moon (the model's second view), at night:
// the moonlit sky, the disc with its phase, the night glow. Measured: max rel 6.1e-4 over the
// pixels, the disc's brightest pixel within 4e-4.
TEST_F(GlCliTest, MoonMatchesTheCpuBackend) {
  if (GetSharedContext().context == nullptr) GTEST_SKIP() << GetSharedContext().error;
  const std::string night = "render --model hillaire --preset earth --sun-elevation -30 --camera fisheye --width 128 --height 128 --no-stars --png '' ";
  const std::string render = night + "--moon-elevation 40 --moon-azimuth 150 --moon-phase 30 ";
  const atmo::testing::RunResult cpu = Run(render + "--exr cpu.exr");
  const atmo::testing::RunResult gl = Run(render + "--backend gl --exr gl.exr");
  const atmo::testing::RunResult moonless = Run(night + "--backend gl --exr dark.exr");
  ASSERT_EQ(cpu.exit_code, 0) << cpu.err;
  ASSERT_EQ(gl.exit_code, 0) << gl.err;
  ASSERT_EQ(moonless.exit_code, 0) << moonless.err;
  const Image a = ReadExr(dir_ / "cpu.exr");
  const Image b = ReadExr(dir_ / "gl.exr");
  const Image dark = ReadExr(dir_ / "dark.exr");
  ASSERT_EQ(a.pixels.size(), b.pixels.size());
  double worst = 0.0, sum_a = 0.0, sum_b = 0.0, sum_dark = 0.0;
  for (std::size_t i = 0; i < a.pixels.size(); ++i) {
    sum_a += a.pixels[i];
    sum_b += b.pixels[i];
    sum_dark += dark.pixels[i];
    if (a.pixels[i] > 1e-9f) worst = std::max(worst, std::abs(double(b.pixels[i]) / a.pixels[i] - 1.0));
  }
  std::printf("moon on gl vs cpu: max rel %.3g, image sums %.6g / %.6g (without the moon %.3g)\n", worst, sum_b, sum_a,
              sum_dark);
  EXPECT_GT(sum_b, 30.0 * sum_dark);  // the moon is there: its disc and its sky outshine the night (70x)
  EXPECT_NEAR(sum_b / sum_a, 1.0, 2e-3);
  EXPECT_LT(worst, SamplerSlack(*GetSharedContext().context) * 3e-3);
}

}  // namespace
}  // namespace atmo::gl
