// Light in physical units against published clear-sky values: zenith luminance, direct and
// diffuse illuminance, the energy bookkeeping of the colour conversion, and the spectral models.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "atmo/colour.h"
#include "atmo/error.h"
#include "atmo/illuminance.h"
#include "atmo/model.h"
#include "atmo/render.h"
#include "atmo/spectrum.h"

namespace atmo {
namespace {

// The clear-sky zenith luminance of Karayel, Navvab, Ne'eman and Selkowitz 1984 ("Zenith
// luminance and sky luminance distributions for daylighting calculations", Energy and Buildings
// 6), as Radiance's gensky uses it: L_z = (1.376 T - 1.81) tan(alpha) + 0.38 kcd/m^2 for Linke
// turbidity T and solar altitude alpha. Clear skies span T = 2 (very clean) to 3.5.
double KarayelZenithLuminance(double turbidity, double altitude_deg) {
  return ((1.376 * turbidity - 1.81) * std::tan(altitude_deg * std::numbers::pi / 180.0) + 0.38) * 1e3;
}

class EarthSpectralTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { model_ = CreateModel("hillaire", EarthSpectral()).release(); }
  static void TearDownTestSuite() {
    delete model_;
    model_ = nullptr;
  }
  static Model* model_;
};
Model* EarthSpectralTest::model_ = nullptr;

TEST_F(EarthSpectralTest, ZenithLuminanceIsInThePublishedClearSkyRange) {
  const SpectralConversion convert(model_->parameters().wavelengths_nm);
  std::vector<double> r(model_->channel_count());
  for (double altitude : {20.0, 30.0, 45.0, 60.0, 66.5}) {
    const auto sky = model_->View(0.0, SunDirection(altitude, 180.0));
    sky->Radiance({0.0, 0.0, 1.0}, r);
    const double l = convert.Luminance(r);
    EXPECT_GT(l, KarayelZenithLuminance(2.0, altitude)) << altitude;
    EXPECT_LT(l, KarayelZenithLuminance(3.5, altitude)) << altitude;
  }
}

TEST_F(EarthSpectralTest, IlluminanceMatchesTheIesClearSkyModel) {
  // IESNA Lighting Handbook (9th ed., daylighting chapter), clear sky: direct normal illuminance
  // E_dn = E_sc exp(-c m) with E_sc = 127.5 klx, c = 0.21 and m the relative air mass
  // (Kasten & Young 1989), and sky illuminance on a horizontal plane E_kh = A + B sin(alpha)^C with
  // A = 0.8 klx, B = 15.5 klx, C = 0.5. Our earth-spectral is a cleaner sky (aerosol optical depth
  // 0.05) with the ASTM sun (133.8 klx at the top): measured +9 to +19 % direct (the most at low sun, where the
  // thin aerosol matters most) and -10 to -19 % diffuse; the bound is 22 % for both.
  for (double altitude : {20.0, 30.0, 45.0, 60.0, 90.0}) {
    const auto sky = model_->View(0.0, SunDirection(altitude, 180.0));
    const Illuminance e = ComputeIlluminance(*sky, model_->parameters());
    const double zenith = 90.0 - altitude;
    const double m = 1.0 / (std::cos(zenith * std::numbers::pi / 180.0) + 0.50572 * std::pow(96.07995 - zenith, -1.6364));
    const double direct = 127.5e3 * std::exp(-0.21 * m);
    const double diffuse = 0.8e3 + 15.5e3 * std::sqrt(std::sin(altitude * std::numbers::pi / 180.0));
    EXPECT_NEAR(e.direct_normal_lux / direct, 1.0, 0.22) << altitude;
    EXPECT_NEAR(e.diffuse_horizontal_lux / diffuse, 1.0, 0.22) << altitude;
    EXPECT_NEAR(e.global_horizontal_lux, e.diffuse_horizontal_lux + e.direct_normal_lux * std::sin(altitude * std::numbers::pi / 180.0), 1e-6 * e.global_horizontal_lux);
  }
}

TEST_F(EarthSpectralTest, DirectIlluminanceFromSpaceIsTheLuminousSolarConstant) {
  // Above the atmosphere the transmittance is 1: the direct normal illuminance is the sun's
  // (Darula, Kittler and Gueymard 2005: 133.8 klx), and the sky is black.
  const auto sky = model_->View(1e6, SunDirection(45.0, 180.0));
  const Illuminance e = ComputeIlluminance(*sky, model_->parameters(), {16, 32});
  EXPECT_NEAR(e.direct_normal_lux, 133.8e3, 0.015 * 133.8e3);
}

TEST(Illuminance, UniformSkyIntegratesToPiL) {
  // A sky of constant radiance L: diffuse = pi L exactly by the cell weights.
  class UniformSky : public SkyView {
   public:
    UniformSky() : SkyView(0.0, {0.0, 0.0, 1.0}, 3) {}
    void Radiance(const glm::dvec3&, std::span<double> out) const override { std::fill(out.begin(), out.end(), 0.01); }
    void Transmittance(const glm::dvec3&, std::span<double> out) const override { std::fill(out.begin(), out.end(), 1.0); }
    void SunDiscRadiance(const glm::dvec3&, std::span<double> out) const override { std::fill(out.begin(), out.end(), 0.0); }
  };
  AtmosphereParameters p = Preset("earth");
  const Illuminance e = ComputeIlluminance(UniformSky(), p, {7, 5});
  const SpectralConversion convert(p.wavelengths_nm);
  // Exact but for the float radiance of RadianceBatch.
  const double expected = std::numbers::pi * convert.Luminance(std::vector<double>(3, 0.01));
  EXPECT_NEAR(e.diffuse_horizontal_lux / expected, 1.0, 1e-6);
  EXPECT_THROW(ComputeIlluminance(UniformSky(), p, {1, 5}), Error);
}

TEST(SpectralModels, EveryCpuModelRunsSpectralAndAgreesWithItsRgbSelfAtSharedWavelengths) {
  // A 7-channel resampling of the presets whose wavelengths include the middle one: every model
  // answers per channel, with finite non-negative radiance and transmittance in [0, 1], and the
  // batches of three do not mix channels: the channel's radiance does not depend on which other
  // channels are computed beside it.
  struct Case {
    const char* model;
    const char* preset;
    ModelOptions options;
  };
  const Case cases[] = {{"hillaire", "earth", {}},
                        {"elek", "atmosphere-plus", {{"size", "8x32x8"}, {"orders", "2"}}},
                        {"simple", "simple", {}},
                        {"reference", "earth", {{"samples", "64"}, {"seed", "3"}}}};
  for (const Case& c : cases) {
    const AtmosphereParameters spectral = MakeSpectral(Preset(c.preset), 7);
    const auto model = CreateModel(c.model, spectral, c.options);
    ASSERT_EQ(model->channel_count(), 7u);
    const auto sky = model->View(c.preset == std::string("simple") ? -0.3 : 0.0, SunDirection(30.0, 0.0));
    std::vector<double> l(7), t(7);
    const glm::dvec3 view = DirectionFromZenithAzimuth(1.2, 0.5);
    sky->Radiance(view, l);
    sky->Transmittance(view, t);
    for (std::size_t i = 0; i < 7; ++i) {
      EXPECT_TRUE(std::isfinite(l[i]) && l[i] >= 0.0) << c.model << " " << i;
      EXPECT_TRUE(t[i] >= 0.0 && t[i] <= 1.0) << c.model << " " << i;
    }
    // Radiance rises towards the blue for these Rayleigh-dominated skies (the simple preset's
    // coefficients follow the same fitted power law).
    EXPECT_GT(l[1], l[5]) << c.model;
  }
}

TEST(SpectralModels, RenderGivesOneChannelPerWavelength) {
  const auto model = CreateModel("hillaire", MakeSpectral(Preset("earth"), 5));
  RenderSettings settings;
  settings.camera = {CameraKind::kEquirect, 16, 8};
  const Image image = Render(*model, settings);
  EXPECT_EQ(image.channels, 5);
  const SpectralConversion convert(model->parameters().wavelengths_nm);
  const Image rgb = ConvertImage(image, convert, ImageColour::kLinearSrgb);
  EXPECT_EQ(rgb.channels, 3);
  // Clear sky looking up: blue above red.
  EXPECT_GT(rgb.at(8, 1, 2), rgb.at(8, 1, 0));
}

}  // namespace
}  // namespace atmo

namespace atmo {
namespace {

TEST(SpectralRender, FoldedColourFrameEqualsTheConvertedSpectralFrame) {
  // RenderViewFolded folds the colour matrix into the sky-view texels (hillaire) or after the
  // lookups (the default, here elek); both are linear, so the folded frame is the conversion of the
  // per-wavelength frame up to float rounding (relative 1e-4; the sun disc pass included).
  struct Case {
    const char* model;
    const char* preset;
    ModelOptions options;
  };
  for (const Case& c : {Case{"hillaire", "earth", {}},
                        Case{"elek", "atmosphere-plus", {{"size", "8x32x8"}, {"orders", "2"}}}}) {
    for (int n : {3, 7}) {
      AtmosphereParameters p = n == 3 ? Preset(c.preset) : MakeSpectral(Preset(c.preset), n);
      p.solar_irradiance.assign(p.channel_count(), 1.0);
      const auto model = CreateModel(c.model, p, c.options);
      const auto sky = model->View(0.0, SunDirection(20.0, 180.0));
      const Camera camera{CameraKind::kEquirect, 64, 32};
      const SpectralConversion convert(p.wavelengths_nm);
      const Image converted = ConvertImage(RenderView(*sky, camera, {}, p.solar_irradiance), convert,
                                           ImageColour::kLinearSrgb);
      const Image folded = RenderViewFolded(*sky, camera, {}, ColourWeights(convert, ImageColour::kLinearSrgb));
      ASSERT_EQ(folded.channels, 3);
      double worst = 0.0;
      for (std::size_t i = 0; i < folded.pixels.size(); ++i) {
        const double a = folded.pixels[i], b = converted.pixels[i];
        worst = std::max(worst, std::abs(a - b) / std::max(std::abs(b), 1.0));
      }
      EXPECT_LT(worst, 1e-4) << c.model << " " << n;
    }
  }
}

// A render loop's target: RenderView into an image reuses its storage when the frame's size and
// channels match (no fresh pages per frame) and gives the pixels of a fresh RenderView, the sun
// disc pass included; another size or camera replaces it, dropping the last frame's alpha and
// environment-map tag.
TEST(SpectralRender, RenderingIntoAnImageReusesItsStorage) {
  const AtmosphereParameters p = MakeSpectral(Preset("earth"), 5);
  const auto model = CreateModel("hillaire", p);
  const auto sky = model->View(0.0, SunDirection(10.0, 0.0));
  RadianceTerms terms;
  terms.sun_disc = true;
  Camera camera{CameraKind::kPerspective, 48, 24};
  camera.fov_deg = 40.0;
  const Image fresh = RenderView(*sky, camera, terms, p.solar_irradiance);
  // The disc is in the frame (what a second, added pass would double).
  RadianceTerms sky_only = terms;
  sky_only.sun_disc = false;
  const Image no_disc = RenderView(*sky, camera, sky_only, p.solar_irradiance);
  EXPECT_GT(*std::max_element(fresh.pixels.begin(), fresh.pixels.end()),
            10.0f * *std::max_element(no_disc.pixels.begin(), no_disc.pixels.end()));
  Image target;
  RenderView(*sky, camera, terms, p.solar_irradiance, target);
  const float* storage = target.pixels.data();
  RenderView(*sky, camera, terms, p.solar_irradiance, target);  // the disc must not add twice
  EXPECT_EQ(target.pixels.data(), storage);
  EXPECT_EQ(target.pixels, fresh.pixels);
  const std::vector<glm::vec3> weights =
      ColourWeights(SpectralConversion(p.wavelengths_nm), ImageColour::kLinearSrgb);
  Image folded;
  RenderViewFolded(*sky, camera, terms, weights, folded);
  RenderViewFolded(*sky, camera, terms, weights, folded);
  EXPECT_EQ(folded.pixels, RenderViewFolded(*sky, camera, terms, weights).pixels);
  // A fisheye of another size: replaced, with its own alpha; then an equirect without it.
  RenderView(*sky, Camera{CameraKind::kFisheye, 16, 16}, {}, p.solar_irradiance, target);
  EXPECT_EQ(target.width, 16);
  EXPECT_EQ(target.alpha.size(), 256u);
  RenderView(*sky, Camera{CameraKind::kEquirect, 16, 16}, {}, p.solar_irradiance, target);
  EXPECT_TRUE(target.alpha.empty());
  EXPECT_EQ(target.envmap, EnvMap::kLatLong);
}

}  // namespace
}  // namespace atmo
