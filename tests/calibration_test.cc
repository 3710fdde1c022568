// Calibration of a clear sky to a measured hour (include/atmo/calibration.h): a sky whose aerosol is
// known is "measured" as the instruments would, and the calibration finds that aerosol again;
// measurements no clear sky gives are told apart.
#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "atmo/calibration.h"
#include "atmo/colour.h"
#include "atmo/error.h"
#include "atmo/irradiance.h"
#include "atmo/model.h"
#include "atmo/parameters.h"
#include "atmo/render.h"

namespace atmo {
namespace {

// What a pyrheliometer (the disc and 2.5 degrees around it) and a shaded pyranometer read under
// the model's sky of `p`.
DaylightMeasurement Measure(const AtmosphereParameters& p, const std::string& model_name, const glm::dvec3& sun) {
  const auto model = CreateModel(model_name, p);
  const auto view = model->View(0.0, sun);
  const std::vector<Plane> planes = {Plane::Horizontal(), Plane::FacingSun()};
  const IrradianceResult e = ComputeIrradiance(*view, p, planes);
  const SpectralConversion convert(p.wavelengths_nm);
  return {convert.Luminance(e.direct_normal) + convert.Luminance(e.planes[1].circumsolar),
          convert.Luminance(e.planes[0].sky_diffuse)};
}

TEST(Calibration, WithAerosolSetsTheAlbedoAndKeepsTheExtinction) {
  const AtmosphereParameters own = WithAerosol(Preset("earth"), "urban", 0.4, std::nan(""));
  const AtmosphereParameters shifted = WithAerosol(Preset("earth"), "urban", 0.4, 0.95);
  EXPECT_LT(MieSingleScatteringAlbedo550(own), 0.9);
  EXPECT_NEAR(MieSingleScatteringAlbedo550(shifted), 0.95, 1e-12);
  for (std::size_t c = 0; c < 3; ++c) {
    EXPECT_NEAR(shifted.mie.extinction_per_m(c), own.mie.extinction_per_m(c), 1e-15 * own.mie.extinction_per_m(c));
    EXPECT_GT(shifted.mie.scattering_per_m[c], own.mie.scattering_per_m[c]);
  }
  EXPECT_THROW(WithAerosol(Preset("earth"), "urban", 0.4, 1.5), Error);
  EXPECT_THROW(WithAerosol(Preset("earth"), "no-such-type", 0.4, 0.9), Error);
}

// The round trip: a haze of tau 0.35, omega 0.88 measured, then calibrated from the two numbers.
TEST(Calibration, FindsTheAerosolOfAMeasuredSky) {
  const glm::dvec3 sun = SunDirection(35.0, 180.0);
  const AtmosphereParameters truth = WithAerosol(Preset("earth"), "continental-average", 0.35, 0.88);
  const DaylightMeasurement m = Measure(truth, "hillaire", sun);
  CalibrationSettings settings;
  settings.model = "hillaire";
  settings.tolerance = 0.002;
  const CalibrationResult r = CalibrateClearSky(Preset("earth"), 0.0, sun, m, settings);
  ASSERT_EQ(r.status, CalibrationStatus::kClear) << r.message;
  EXPECT_NEAR(r.aod_550, 0.35, 0.005);
  EXPECT_NEAR(r.single_scattering_albedo_550, 0.88, 0.01);
  EXPECT_NEAR(r.direct_normal_lux, m.direct_normal_lux, 0.002 * m.direct_normal_lux);
  EXPECT_NEAR(r.diffuse_horizontal_lux, m.diffuse_horizontal_lux, 0.002 * m.diffuse_horizontal_lux);
  // The parameters it returns give the same light when measured again.
  const DaylightMeasurement again = Measure(r.parameters, "hillaire", sun);
  EXPECT_NEAR(again.direct_normal_lux, m.direct_normal_lux, 0.002 * m.direct_normal_lux);
  EXPECT_NEAR(again.diffuse_horizontal_lux, m.diffuse_horizontal_lux, 0.002 * m.diffuse_horizontal_lux);
  EXPECT_LE(r.model_builds, 8);
}

// Clouds add diffuse light and take direct light: no clear sky gives twice the diffuse light of
// the most scattering aerosol; more direct light than aerosol-free air transmits is a bad
// measurement; nearly no direct light is beyond tau 10.
TEST(Calibration, TellsWhatNoClearSkyGives) {
  const glm::dvec3 sun = SunDirection(35.0, 180.0);
  const DaylightMeasurement m = Measure(WithAerosol(Preset("earth"), "continental-average", 0.3, 0.9), "hillaire", sun);
  CalibrationSettings settings;
  settings.model = "hillaire";
  const CalibrationResult cloudy =
      CalibrateClearSky(Preset("earth"), 0.0, sun, {m.direct_normal_lux, 2.0 * m.diffuse_horizontal_lux}, settings);
  EXPECT_EQ(cloudy.status, CalibrationStatus::kTooMuchDiffuse) << cloudy.message;
  EXPECT_NE(cloudy.message.find("clouds"), std::string::npos);
  EXPECT_NEAR(cloudy.single_scattering_albedo_550, 1.0, 1e-9);
  const CalibrationResult dark =
      CalibrateClearSky(Preset("earth"), 0.0, sun, {m.direct_normal_lux, 0.2 * m.diffuse_horizontal_lux}, settings);
  EXPECT_EQ(dark.status, CalibrationStatus::kTooLittleDiffuse) << dark.message;
  const CalibrationResult bright =
      CalibrateClearSky(Preset("earth"), 0.0, sun, {2.0 * m.direct_normal_lux, m.diffuse_horizontal_lux}, settings);
  EXPECT_EQ(bright.status, CalibrationStatus::kTooMuchDirect) << bright.message;
  const CalibrationResult overcast = CalibrateClearSky(Preset("earth"), 0.0, sun, {0.0, 20000.0}, settings);
  EXPECT_EQ(overcast.status, CalibrationStatus::kTooLittleDirect) << overcast.message;
  EXPECT_EQ(overcast.model_builds, 0);
}

TEST(Calibration, RefusesInvalidInput) {
  const glm::dvec3 sun = SunDirection(35.0, 180.0);
  CalibrationSettings settings;
  settings.model = "hillaire";
  EXPECT_THROW(CalibrateClearSky(Preset("earth"), 0.0, sun, {-1.0, 100.0}, settings), Error);
  EXPECT_THROW(CalibrateClearSky(Preset("earth"), 0.0, sun, {1e4, 0.0}, settings), Error);
  EXPECT_THROW(CalibrateClearSky(Preset("earth"), 0.0, sun, {std::nan(""), 100.0}, settings), Error);
  EXPECT_THROW(CalibrateClearSky(Preset("earth"), 0.0, SunDirection(0.5, 180.0), {1e4, 1e4}, settings), Error);
  EXPECT_THROW(CalibrateClearSky(Preset("simple"), 0.0, sun, {1e4, 1e4}, settings), Error);
  EXPECT_THROW(CalibrateClearSky(Preset("earth"), -5.0, sun, {1e4, 1e4}, settings), Error);
  settings.aerosol_type = "smoke";
  EXPECT_THROW(CalibrateClearSky(Preset("earth"), 0.0, sun, {1e4, 1e4}, settings), Error);
}

}  // namespace
}  // namespace atmo
