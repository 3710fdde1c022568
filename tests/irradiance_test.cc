// Irradiance on planes (include/atmo/irradiance.h): the view factors of a uniform sky, the
// horizontal plane against atmo::ComputeIlluminance, the symmetry of a sky about the sun's
// vertical, and the components against an independent integration of the same radiance.
#include <cmath>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "atmo/colour.h"
#include "atmo/error.h"
#include "atmo/illuminance.h"
#include "atmo/irradiance.h"
#include "atmo/model.h"
#include "atmo/parameters.h"
#include "atmo/render.h"
#include "atmo/sky_patches.h"

namespace atmo {
namespace {

constexpr double kPi = std::numbers::pi;

// A sky of the same radiance everywhere and the same transmittance towards the sun.
class UniformSky : public SkyView {
 public:
  UniformSky(const glm::dvec3& sun, double radiance, double transmittance)
      : SkyView(0.0, sun, 1), radiance_(radiance), transmittance_(transmittance) {}
  void Radiance(const glm::dvec3&, std::span<double> out) const override { out[0] = radiance_; }
  void Transmittance(const glm::dvec3&, std::span<double> out) const override { out[0] = transmittance_; }
  void SunDiscRadiance(const glm::dvec3&, std::span<double> out) const override { out[0] = 0.0; }

 private:
  double radiance_;
  double transmittance_;
};

AtmosphereParameters OneChannel(double albedo) {
  AtmosphereParameters p = Preset("earth");
  p.wavelengths_nm = {550.0};
  for (Medium* m : {&p.rayleigh, &p.mie, &p.ozone}) {
    m->scattering_per_m.resize(1);
    m->absorption_per_m.resize(1);
  }
  p.ground_albedo = {albedo};
  p.solar_irradiance = {1.0};
  return p;
}

// A uniform sky of radiance L seen by a plane tilted by beta: L pi (1 + cos beta) / 2 (its sky
// view factor); the ground of albedo rho under it, lit by G_h = pi L + T sin(elevation), gives
// rho G_h (1 - cos beta) / 2; the direct light is T cos(incidence).
TEST(Irradiance, UniformSkyGivesTheViewFactors) {
  const double L = 0.1, T = 0.7, rho = 0.3;
  const glm::dvec3 sun = SunDirection(30.0, 180.0);
  const UniformSky sky(sun, L, T);
  IrradianceSettings settings;
  settings.circumsolar_half_angle_deg = 0.0;
  const std::vector<Plane> planes = {{0.0, 0.0}, {35.0, 180.0}, {90.0, 90.0}, {135.0, 0.0}, {180.0, 0.0}};
  const IrradianceResult r = ComputeIrradiance(sky, OneChannel(rho), planes, settings);
  EXPECT_DOUBLE_EQ(r.direct_normal[0], T);
  const double g_h = kPi * L + T * 0.5;
  for (std::size_t i = 0; i < planes.size(); ++i) {
    const double beta = glm::radians(planes[i].tilt_deg);
    const glm::dvec3 n = planes[i].Normal(sun);
    SCOPED_TRACE(planes[i].tilt_deg);
    EXPECT_NEAR(r.planes[i].sky_diffuse[0], L * kPi * 0.5 * (1.0 + std::cos(beta)), 2e-4 * L * kPi);
    EXPECT_EQ(r.planes[i].circumsolar[0], 0.0);
    EXPECT_NEAR(r.planes[i].ground_reflected[0], rho * g_h * 0.5 * (1.0 - std::cos(beta)), 1e-4 * g_h);
    EXPECT_NEAR(r.planes[i].direct[0], T * std::max(0.0, glm::dot(n, sun)), 1e-12);
  }
}

// The circumsolar cone of half-angle a, seen face on, holds L pi sin^2(a) of a uniform sky; the rest
// of the hemisphere the remainder, so the sum does not depend on the cone.
TEST(Irradiance, CircumsolarConeHoldsItsSolidAngle) {
  const double L = 1.0;
  const glm::dvec3 sun = SunDirection(50.0, 200.0);
  const UniformSky sky(sun, L, 0.5);
  const std::vector<Plane> planes = {Plane::FacingSun(), Plane::Horizontal()};
  for (double a : {1.0, 2.5, 5.0}) {
    IrradianceSettings settings;
    settings.circumsolar_half_angle_deg = a;
    const IrradianceResult r = ComputeIrradiance(sky, OneChannel(0.0), planes, settings);
    const double cone = L * kPi * std::pow(std::sin(glm::radians(a)), 2);
    SCOPED_TRACE(a);
    EXPECT_NEAR(r.planes[0].circumsolar[0], cone, 0.01 * cone);
    EXPECT_NEAR(r.planes[1].circumsolar[0] + r.planes[1].sky_diffuse[0], kPi * L, 2e-4 * kPi);
    // On the horizontal, the cone's light comes in at about the sun's incidence.
    EXPECT_NEAR(r.planes[1].circumsolar[0], cone * sun.z, 0.02 * cone);
  }
}

class IrradianceOfModel : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { model_ = CreateModel("hillaire", Preset("earth")).release(); }
  static void TearDownTestSuite() {
    delete model_;
    model_ = nullptr;
  }
  static Model* model_;
};
Model* IrradianceOfModel::model_ = nullptr;

// The horizontal plane's sky light is atmo illuminance's diffuse, integrated on its own grid.
TEST_F(IrradianceOfModel, HorizontalPlaneIsTheIlluminanceCommands) {
  for (double elevation : {5.0, 30.0, 75.0}) {
    const auto sky = model_->View(0.0, SunDirection(elevation, 180.0));
    const IrradianceResult r = ComputeIrradiance(*sky, model_->parameters(), std::vector<Plane>{Plane::Horizontal()});
    const Illuminance e = ComputeIlluminance(*sky, model_->parameters());
    const SpectralConversion convert(model_->parameters().wavelengths_nm);
    const IrradianceComponents& h = r.planes[0];
    std::vector<double> sky_light(3);
    for (int c = 0; c < 3; ++c) sky_light[c] = h.circumsolar[c] + h.sky_diffuse[c];
    SCOPED_TRACE(elevation);
    EXPECT_NEAR(convert.Luminance(sky_light), e.diffuse_horizontal_lux, 2e-3 * e.diffuse_horizontal_lux);
    EXPECT_NEAR(convert.Luminance(h.direct), e.direct_horizontal_lux, 1e-9 * e.direct_horizontal_lux);
    EXPECT_NEAR(convert.Luminance(r.direct_normal), e.direct_normal_lux, 1e-9 * e.direct_normal_lux);
  }
}

// A sky is symmetric about the sun's vertical: planes mirrored across it receive the same light.
TEST_F(IrradianceOfModel, MirroredPlanesReceiveTheSameLight) {
  const auto sky = model_->View(0.0, SunDirection(25.0, 180.0));
  const std::vector<Plane> planes = {{90.0, 90.0}, {90.0, 270.0}, {40.0, 130.0}, {40.0, 230.0}};
  const IrradianceResult r = ComputeIrradiance(*sky, model_->parameters(), planes);
  for (int pair = 0; pair < 2; ++pair) {
    const IrradianceComponents& a = r.planes[2 * pair];
    const IrradianceComponents& b = r.planes[2 * pair + 1];
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(a.sky_diffuse[c], b.sky_diffuse[c], 1e-5 * a.sky_diffuse[c]) << pair;
      EXPECT_NEAR(a.direct[c], b.direct[c], 1e-9) << pair;
      EXPECT_NEAR(a.ground_reflected[c], b.ground_reflected[c], 1e-9) << pair;
    }
  }
}

// Against an independent integration of the same radiance: a Fibonacci lattice of 200 000 directions
// over the sphere (equal solid angles, no grid, no refinement near the sun), the sky light that a
// tilted plane receives agrees within 0.3 % (the lattice's own error near the aureole).
TEST_F(IrradianceOfModel, AgreesWithAnIndependentIntegration) {
  const glm::dvec3 sun = SunDirection(35.0, 160.0);
  const auto sky = model_->View(0.0, sun);
  const std::vector<Plane> planes = {{30.0, 180.0}, {90.0, 250.0}, {60.0, 20.0}};
  const IrradianceResult r = ComputeIrradiance(*sky, model_->parameters(), planes);
  constexpr int kCount = 200000;
  std::vector<glm::dvec3> views;
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < kCount; ++i) {
    const double z = 1.0 - (i + 0.5) / (0.5 * kCount);  // the upper hemisphere's half of the lattice
    if (z <= 0.0) break;
    const double s = std::sqrt(1.0 - z * z);
    views.emplace_back(s * std::cos(golden * i), s * std::sin(golden * i), z);
  }
  std::vector<float> radiance(views.size() * 3);
  sky->RadianceBatch(views, RadianceTerms{false, false}, radiance);
  const double solid_angle = 2.0 * kPi / static_cast<double>(views.size());
  for (std::size_t p = 0; p < planes.size(); ++p) {
    const glm::dvec3 n = planes[p].Normal(sun);
    for (int c = 0; c < 3; ++c) {
      double sum = 0.0;
      for (std::size_t k = 0; k < views.size(); ++k) sum += solid_angle * std::max(0.0, glm::dot(n, views[k])) * radiance[3 * k + c];
      const double ours = r.planes[p].circumsolar[c] + r.planes[p].sky_diffuse[c];
      EXPECT_NEAR(ours, sum, 3e-3 * sum) << "plane " << p << " channel " << c;
    }
  }
}

TEST(Irradiance, ScalesWithTheSunsDistance) {
  const UniformSky sky(SunDirection(40.0, 180.0), 0.2, 0.6);
  IrradianceSettings near;
  near.sun_scale = 1.0 / (0.983 * 0.983);
  const std::vector<Plane> planes = {{20.0, 180.0}};
  const IrradianceResult a = ComputeIrradiance(sky, OneChannel(0.2), planes);
  const IrradianceResult b = ComputeIrradiance(sky, OneChannel(0.2), planes, near);
  EXPECT_NEAR(b.planes[0].Global()[0], a.planes[0].Global()[0] * near.sun_scale, 1e-12);
}

TEST(Irradiance, RefusesWhatItCannotIntegrate) {
  const UniformSky sky(SunDirection(40.0, 180.0), 0.2, 0.6);
  const AtmosphereParameters p = OneChannel(0.2);
  EXPECT_THROW(ComputeIrradiance(sky, p, std::vector<Plane>{{190.0, 0.0}}), Error);
  EXPECT_THROW(ComputeIrradiance(sky, p, std::vector<Plane>{{10.0, std::nan("")}}), Error);
  IrradianceSettings bad;
  bad.circumsolar_half_angle_deg = 20.0;
  EXPECT_THROW(ComputeIrradiance(sky, p, std::vector<Plane>{}, bad), Error);
  bad = {};
  bad.zenith_steps = 1;
  EXPECT_THROW(ComputeIrradiance(sky, p, std::vector<Plane>{}, bad), Error);
  bad = {};
  bad.sun_scale = -1.0;
  EXPECT_THROW(ComputeIrradiance(sky, p, std::vector<Plane>{}, bad), Error);
  EXPECT_THROW(ComputeIrradiance(sky, Preset("earth"), std::vector<Plane>{}), Error);  // 3 channels, 1 in the view
}

// Tregenza's 145 patches and Reinhart's 577 and 2305 (Radiance's reinhart.cal): they tile the
// hemisphere, the first of each row is centred on north and the numbers grow towards the east, and
// every patch's centre is found in that patch.
TEST(SkyPatches, TileTheHemisphereInRadiancesOrder) {
  for (const auto& [mf, count] : {std::pair{1, 145}, std::pair{2, 577}, std::pair{4, 2305}}) {
    const SkyPatches patches = SkyPatches::Reinhart(mf);
    ASSERT_EQ(patches.count(), static_cast<std::size_t>(count));
    double total = 0.0;
    for (std::size_t i = 0; i < patches.count(); ++i) {
      total += patches.patches()[i].solid_angle_sr;
      EXPECT_EQ(patches.Index(patches.patches()[i].centre), static_cast<int>(i)) << mf << " " << i;
    }
    EXPECT_NEAR(total, 2.0 * kPi, 1e-12);
    const glm::dvec3 first = patches.patches()[0].centre;
    EXPECT_NEAR(first.x, 0.0, 1e-12);
    EXPECT_GT(first.y, 0.0);
    EXPECT_GT(patches.patches()[1].centre.x, 0.0);  // east of north
    EXPECT_EQ(patches.Index({0.0, 0.0, 1.0}), count - 1);
    EXPECT_EQ(patches.Index({0.0, 1.0, -0.1}), -1);
  }
  // Tregenza's rows: 30 patches 12 degrees high at the horizon, the cap above 84 degrees.
  const SkyPatches tregenza = SkyPatches::Reinhart(1);
  EXPECT_EQ(tregenza.Index(SunDirection(11.9, 354.0)), 0);
  EXPECT_EQ(tregenza.Index(SunDirection(11.9, 6.5)), 1);
  EXPECT_EQ(tregenza.Index(SunDirection(12.1, 0.0)), 30);
  EXPECT_EQ(tregenza.Index(SunDirection(84.1, 123.0)), 144);
  EXPECT_THROW(SkyPatches::Reinhart(0), Error);
}

// Sampled by patches, a uniform sky's patches all have its radiance and the view factors hold.
TEST(Irradiance, PatchSamplingOfAUniformSky) {
  const double L = 0.25;
  const glm::dvec3 sun = SunDirection(33.0, 140.0);
  const UniformSky sky(sun, L, 0.5);
  const SkyPatches patches = SkyPatches::Reinhart(2);
  IrradianceSettings settings;
  settings.patches = &patches;
  settings.patch_samples = 2;
  const std::vector<Plane> planes = {Plane::Horizontal(), {60.0, 300.0}};
  const IrradianceResult r = ComputeIrradiance(sky, OneChannel(0.1), planes, settings);
  ASSERT_EQ(r.patch_radiance.size(), patches.count());
  for (double value : r.patch_radiance) EXPECT_NEAR(value, L, 1e-12);
  for (std::size_t i = 0; i < planes.size(); ++i) {
    const double beta = glm::radians(planes[i].tilt_deg);
    EXPECT_NEAR(r.planes[i].circumsolar[0] + r.planes[i].sky_diffuse[0], L * kPi * 0.5 * (1.0 + std::cos(beta)),
                3e-3 * L * kPi);
  }
}

// The patch quadrature (3 x 3 samples per Tregenza patch, 2 x 2 for annual runs; the rows below 12
// degrees four times as many; the sun's neighbourhood refined) against the fine grid, on a model's
// sky: within 0.5 % (3 x 3) and 1 % (2 x 2) for every component and plane.
TEST_F(IrradianceOfModel, PatchQuadratureAgreesWithTheFineGrid) {
  const SkyPatches patches = SkyPatches::Reinhart(1);
  const std::vector<Plane> planes = {Plane::Horizontal(), Plane::FacingSun(), {35.0, 180.0}, {90.0, 90.0}};
  for (const auto& [samples, tolerance] : {std::pair{3, 5e-3}, std::pair{2, 1e-2}}) {
    IrradianceSettings coarse;
    coarse.patches = &patches;
    coarse.patch_samples = samples;
    coarse.circumsolar_subdivisions = 6;
    for (double elevation : {8.0, 40.0, 70.0}) {
      const auto sky = model_->View(0.0, SunDirection(elevation, 170.0));
      const IrradianceResult fine = ComputeIrradiance(*sky, model_->parameters(), planes);
      const IrradianceResult fast = ComputeIrradiance(*sky, model_->parameters(), planes, coarse);
      for (std::size_t p = 0; p < planes.size(); ++p) {
        for (int c = 0; c < 3; ++c) {
          SCOPED_TRACE(::testing::Message() << samples << " samples, sun " << elevation << " plane " << p << " channel " << c);
          EXPECT_NEAR(fast.planes[p].sky_diffuse[c], fine.planes[p].sky_diffuse[c], tolerance * fine.planes[p].sky_diffuse[c]);
          EXPECT_NEAR(fast.planes[p].circumsolar[c], fine.planes[p].circumsolar[c],
                      tolerance * fine.planes[p].circumsolar[c] + 1e-9);
        }
      }
    }
  }
}

}  // namespace
}  // namespace atmo
