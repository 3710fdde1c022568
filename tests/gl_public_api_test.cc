// The GL backend's public entry points (include/atmo/gl/hillaire_gl.h, elek_gl.h), which take the
// model options by name: each against the CPU model that atmo::CreateModel makes from the same
// options, so that an option the entry point dropped or read differently shows as a difference
// (every option below changes the tables), and their errors. This file includes only public
// headers, as a program outside atmo would (tests/gl_test_context.h for the shared context).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include "atmo/error.h"
#include "atmo/gl/context.h"
#include "atmo/gl/elek_gl.h"
#include "atmo/gl/hillaire_gl.h"
#include "atmo/model.h"
#include "atmo/parameters.h"
#include "atmo/render.h"
#include "gl_test_context.h"

namespace atmo::gl {
namespace {

using testing::MeanRelative;
using testing::SamplerSlack;

// Directions over the sky and below the horizon, around the sun's azimuth and away from it.
std::vector<glm::dvec3> Views() {
  std::vector<glm::dvec3> views;
  for (const double zenith_deg : {0.0, 30.0, 60.0, 80.0, 89.0, 95.0, 120.0}) {
    for (const double azimuth_deg : {0.0, 90.0, 170.0, 260.0}) {
      views.push_back(DirectionFromZenithAzimuth(glm::radians(zenith_deg), glm::radians(azimuth_deg)));
    }
  }
  return views;
}

// The largest relative difference over values above `floor` of the largest.
double MaxRelative(const std::vector<double>& a, const std::vector<double>& b, double floor = 1e-4) {
  EXPECT_EQ(a.size(), b.size());
  const double peak = *std::max_element(b.begin(), b.end());
  double max_rel = 0.0;
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
    if (b[i] > floor * peak) max_rel = std::max(max_rel, std::abs(a[i] - b[i]) / b[i]);
  }
  return max_rel;
}

// Small tables that differ from every default, and the seed, which CreateModel accepts.
const ModelOptions kHillaireOptions = {{"transmittance_lut", "128x32"},    {"multiple_scattering_lut", "16x16"},
                                       {"sky_view_lut", "96x54"},          {"sky_view_samples", "20"},
                                       {"multiple_scattering_ground", "off"}, {"seed", "7"}};
const ModelOptions kElekOptions = {{"size", "16x64x16"},      {"orders", "3"},   {"gather_rows", "32"},
                                   {"gather_azimuths", "32"}, {"samples", "20"}, {"seed", "7"}};

TEST(GlPublicApi, HillaireSamplerMatchesCpuModelWithTheSameOptions) {
  ATMO_REQUIRE_GL_CONTEXT(context);
  const AtmosphereParameters earth = Preset("earth");
  const std::unique_ptr<Model> cpu = CreateModel("hillaire", earth, kHillaireOptions);
  HillaireSampler gpu(context, earth, kHillaireOptions);
  ASSERT_EQ(gpu.channel_count(), cpu->channel_count());
  const std::vector<glm::dvec3> views = Views();
  const std::size_t n = cpu->channel_count();
  for (const double altitude_m : {0.0, 5000.0}) {
    const glm::dvec3 sun = SunDirection(12.0, 170.0);
    gpu.SetView(altitude_m, sun);
    std::vector<double> radiance, transmittance;
    gpu.Sample(views, radiance, transmittance);
    const std::unique_ptr<SkyView> sky = cpu->View(altitude_m, sun);
    std::vector<double> cpu_radiance(views.size() * n), cpu_transmittance(views.size() * n);
    for (std::size_t i = 0; i < views.size(); ++i) {
      sky->Radiance(views[i], std::span<double>(cpu_radiance).subspan(i * n, n));
      sky->Transmittance(views[i], std::span<double>(cpu_transmittance).subspan(i * n, n));
    }
    double max_abs_t = 0.0;
    for (std::size_t i = 0; i < transmittance.size(); ++i) {
      max_abs_t = std::max(max_abs_t, std::abs(transmittance[i] - cpu_transmittance[i]));
    }
    const double max_rel = MaxRelative(radiance, cpu_radiance);
    std::printf("%.0f m: HillaireSampler vs CreateModel radiance max rel %.3g, transmittance max abs %.3g\n",
                altitude_m, max_rel, max_abs_t);
    // The bounds of GlHillaire.SampleMatchesCpu (gl_hillaire_test.cc): float against double
    // tables, ~1e-4 relative per table, and the GPU's bilinear taps. Measured on llvmpipe: max rel
    // 5.3e-4 (0 m), 7.4e-4 (5 km); transmittance max abs 1.8e-6. With the GPU on the default
    // options instead (an option dropped) the radiance differs by 4.7e-2 and 6.6e-2.
    EXPECT_LT(max_rel, SamplerSlack(context) * 2e-3);
    EXPECT_LT(max_abs_t, SamplerSlack(context) * 5e-5);
  }
}

TEST(GlPublicApi, RenderHillaireMatchesCpuRenderWithTheSameOptions) {
  ATMO_REQUIRE_GL_CONTEXT(context);
  const AtmosphereParameters earth = Preset("earth");
  RenderSettings render;
  render.camera = {CameraKind::kFisheye, 48, 48};
  render.sun_elevation_deg = 15.0;
  render.terms.sun_disc = false;  // its pixels, ~10^4 times the sky, would dominate the mean
  const Image gpu = RenderHillaire(context, earth, kHillaireOptions, render);
  const Image cpu = Render(*CreateModel("hillaire", earth, kHillaireOptions), render);
  ASSERT_EQ(gpu.width, cpu.width);
  ASSERT_EQ(gpu.channels, cpu.channels);
  EXPECT_EQ(gpu.alpha, cpu.alpha);  // the fisheye's circle
  const double mean_rel = MeanRelative(gpu, cpu);
  std::printf("RenderHillaire vs Render: mean rel %.3g\n", mean_rel);
  // The frame reads the same kind of float sky-view table as the sampler. Measured on llvmpipe:
  // 1.65e-4 (2.0e-2 with the GPU on the default options); the bound leaves a factor of ~4.
  EXPECT_LT(mean_rel, SamplerSlack(context) * 6e-4);
}

TEST(GlPublicApi, CreateElekModelMatchesCpuModelWithTheSameOptions) {
  ATMO_REQUIRE_GL_CONTEXT(context);
  const AtmosphereParameters parameters = Preset("atmosphere-plus");
  const std::unique_ptr<Model> gpu = CreateElekModel(context, parameters, kElekOptions);
  const std::unique_ptr<Model> cpu = CreateModel("elek", parameters, kElekOptions);
  EXPECT_EQ(gpu->name(), "elek");
  const glm::dvec3 sun = SunDirection(8.0, 160.0);
  const std::unique_ptr<SkyView> a = gpu->View(0.0, sun);
  const std::unique_ptr<SkyView> b = cpu->View(0.0, sun);
  const std::vector<glm::dvec3> views = Views();
  const std::size_t n = cpu->channel_count();
  std::vector<double> ga(views.size() * n), cb(views.size() * n);
  for (std::size_t i = 0; i < views.size(); ++i) {
    a->Radiance(views[i], std::span<double>(ga).subspan(i * n, n));
    b->Radiance(views[i], std::span<double>(cb).subspan(i * n, n));
  }
  const double max_rel = MaxRelative(ga, cb);
  std::printf("CreateElekModel vs CreateModel(\"elek\") radiance max rel %.3g\n", max_rel);
  // The lookups blend 8 texels of tables that differ by float against double (gl_elek_test.cc:
  // table rel_mae <= 1.0e-4). Measured on llvmpipe: 6.7e-5 (1.5e-2 with the GPU on the default
  // orders, samples and gather sizes); the bound leaves a factor of ~4.
  EXPECT_LT(max_rel, SamplerSlack(context) * 3e-4);

  RenderSettings render;
  render.camera = {CameraKind::kPerspective, 48, 24, 90.0, 160.0, 10.0};
  render.sun_elevation_deg = 8.0;
  render.sun_azimuth_deg = 160.0;
  render.terms.sun_disc = false;
  const double mean_rel = MeanRelative(RenderElek(context, parameters, kElekOptions, render), Render(*cpu, render));
  std::printf("RenderElek vs Render: mean rel %.3g\n", mean_rel);
  // GlElek.PerspectiveImageMatchesCpu's bound on rel_mae. Measured on llvmpipe: 5.9e-6 (5.7e-3
  // with the GPU on the default options).
  EXPECT_LT(mean_rel, SamplerSlack(context) * 3e-5);
}

TEST(GlPublicApi, BadOptionsThrowOneLineErrors) {
  ATMO_REQUIRE_GL_CONTEXT(context);
  const ModelOptions unknown = {{"no_such_option", "1"}};
  const RenderSettings render;
  EXPECT_THROW(RenderHillaire(context, Preset("earth"), unknown, render), Error);
  EXPECT_THROW(HillaireSampler(context, Preset("earth"), unknown), Error);
  EXPECT_THROW(RenderElek(context, Preset("atmosphere-plus"), unknown, render), Error);
  EXPECT_THROW(CreateElekModel(context, Preset("atmosphere-plus"), unknown), Error);
  // A table to load is CreateModel's: here the table is computed.
  try {
    CreateElekModel(context, Preset("atmosphere-plus"), {{"table", "sky"}});
    ADD_FAILURE() << "table=NAME was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace atmo::gl
