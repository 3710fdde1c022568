// The gases' band absorption (include/atmo/gas_absorption.h), the water vapour medium and the
// gases in the standard-atmosphere presets, on every model.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "error_of.h"

#include "atmo/error.h"
#include "atmo/gas_absorption.h"
#include "atmo/model.h"
#include "atmo/parameters.h"
#include "atmo/spectrum.h"
#include "atmo/standard_atmosphere.h"

namespace atmo {
namespace {

using atmo::testing::ErrorOf;

double O2Column() { return kOxygenMixingRatio * ClimatologyColumns(Climatology::kUsStandard1976).air_per_m2; }
double WaterColumn() { return ClimatologyColumns(Climatology::kUsStandard1976).water_per_m2; }

// The integral of a profile's density over the atmosphere (m).
double ProfileIntegral(const DensityProfile& profile) {
  double sum = 0.0;
  for (double h = 1.0; h < 100e3; h += 2.0) sum += profile.Evaluate(h) * 2.0;
  return sum;
}

TEST(ChannelBands, TileTheSpectrumHalfwayBetweenChannels) {
  const std::vector<double> w = {400.0, 410.0, 430.0};
  const std::vector<WavelengthBand> b = ChannelBands(w);
  ASSERT_EQ(b.size(), 3u);
  EXPECT_DOUBLE_EQ(b[0].lower_nm, 395.0);
  EXPECT_DOUBLE_EQ(b[0].upper_nm, 405.0);
  EXPECT_DOUBLE_EQ(b[1].lower_nm, 405.0);
  EXPECT_DOUBLE_EQ(b[1].upper_nm, 420.0);
  EXPECT_DOUBLE_EQ(b[2].lower_nm, 420.0);
  EXPECT_DOUBLE_EQ(b[2].upper_nm, 440.0);
  const std::vector<double> one = {550.0};
  EXPECT_DOUBLE_EQ(ChannelBands(one)[0].upper_nm - ChannelBands(one)[0].lower_nm, 10.0);
  const std::vector<double> unordered = {500.0, 500.0};
  EXPECT_NE(ErrorOf([&] { ChannelBands(unordered); }).find("increasing"), std::string::npos);
  const std::vector<double> negative = {-1.0, 500.0};
  EXPECT_NE(ErrorOf([&] { ChannelBands(negative); }).find("positive"), std::string::npos);
}

TEST(GasAbsorption, BandTransmittanceIsAProbabilityThatFallsWithTheAmount) {
  for (Gas gas : {Gas::kOxygen, Gas::kWaterVapor, Gas::kOxygenCollisions}) {
    const double amount = gas == Gas::kOxygenCollisions ? 1.3e53 : (gas == Gas::kOxygen ? O2Column() : WaterColumn());
    for (double lower = 360.0; lower < 830.0; lower += 7.0) {
      const WavelengthBand band{lower, lower + 7.0};
      EXPECT_DOUBLE_EQ(GasBandTransmittance(gas, band, 0.0, 1.0), 1.0);
      double previous = 1.0;
      for (double m : {0.5, 1.0, 2.0, 8.0, 40.0}) {
        const double t = GasBandTransmittance(gas, band, amount, m);
        EXPECT_GE(t, 0.0);
        EXPECT_LE(t, previous + 1e-15) << lower << " nm, air mass " << m;
        previous = t;
      }
    }
  }
  // Outside the tables (360-830 nm) the gases do not absorb; a band half outside is half absorbed.
  EXPECT_DOUBLE_EQ(GasBandTransmittance(Gas::kOxygen, {900.0, 950.0}, O2Column(), 5.0), 1.0);
  const double inside = GasBandTransmittance(Gas::kWaterVapor, {820.0, 830.0}, WaterColumn(), 2.0);
  EXPECT_NEAR(GasBandTransmittance(Gas::kWaterVapor, {820.0, 840.0}, WaterColumn(), 2.0), 0.5 * (inside + 1.0), 1e-12);
  EXPECT_NE(ErrorOf([] { GasBandTransmittance(Gas::kOxygen, {700.0, 710.0}, -1.0, 1.0); }).find(">= 0"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { GasBandTransmittance(Gas::kOxygen, {700.0, 710.0}, 1.0, NAN); }).find("air mass"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { GasBandTransmittance(Gas::kOxygen, {710.0, 700.0}, 1.0, 1.0); }).find("lower < upper"),
            std::string::npos);
}

// Independent data: ASTM G-173's direct spectrum (docs/data/validation/astm_g173_direct.csv, from
// SMARTS on the US Standard Atmosphere at air mass 1.5). Its transmittance in the O2-A bin 760-770 nm
// relative to the mean of its neighbours' (750-760, 770-780, which O2 and water barely touch) is
// (0.6622 / 1.2345) / (0.5 (1.0778 / 1.2668 + 1.0773 / 1.2071)) = 0.615; in the water band
// 720-730 nm relative to 740-750 nm, (0.9916 / 1.3412) / (1.1286 / 1.2826) = 0.840. The
// neighbours' Rayleigh and aerosol differ from the band's by under 1 %.
TEST(GasAbsorption, BandsAgreeWithAstmG173) {
  const double a_band = GasBandTransmittance(Gas::kOxygen, {760.0, 770.0}, O2Column(), 1.5);
  const double a_neighbours = 0.5 * (GasBandTransmittance(Gas::kOxygen, {750.0, 760.0}, O2Column(), 1.5) +
                                     GasBandTransmittance(Gas::kOxygen, {770.0, 780.0}, O2Column(), 1.5));
  EXPECT_NEAR(a_band / a_neighbours, 0.615, 0.03);
  const double water = GasBandTransmittance(Gas::kWaterVapor, {720.0, 730.0}, WaterColumn(), 1.5) /
                       GasBandTransmittance(Gas::kWaterVapor, {740.0, 750.0}, WaterColumn(), 1.5);
  EXPECT_NEAR(water, 0.840, 0.025);
  // The US standard water column is 1.42 cm of precipitable water (18.015 g/mol, 1 g/cm^3).
  EXPECT_NEAR(WaterColumn() * 18.015 / 6.02214076e23 / 1e4, 1.42, 0.01);
}

// The lines saturate: the Beer-equivalent cross-section falls as the amount grows, is exact at the
// reference air mass, and tends to the band mean for a vanishing amount.
TEST(GasAbsorption, BeerEquivalentCrossSectionSaturates) {
  const WavelengthBand a_band{760.0, 770.0};
  double previous = INFINITY;
  for (double f : {1e-4, 1e-2, 0.1, 1.0, 10.0}) {
    const double sigma = GasEffectiveCrossSection(Gas::kOxygen, a_band, f * O2Column());
    EXPECT_LT(sigma, previous) << f;
    previous = sigma;
  }
  EXPECT_LT(GasEffectiveCrossSection(Gas::kOxygen, a_band, 10.0 * O2Column()),
            0.3 * GasEffectiveCrossSection(Gas::kOxygen, a_band, 1e-4 * O2Column()));
  for (double lower = 600.0; lower < 830.0; lower += 10.0) {
    const WavelengthBand band{lower, lower + 10.0};
    const double sigma = GasEffectiveCrossSection(Gas::kWaterVapor, band, WaterColumn());
    EXPECT_NEAR(std::exp(-sigma * WaterColumn() * kGasReferenceAirMass),
                GasBandTransmittance(Gas::kWaterVapor, band, WaterColumn(), kGasReferenceAirMass), 1e-12);
  }
  // A weak band: Beer's law holds (O2-O2 is smooth, its effective cross-section does not depend on
  // the amount), and a vanishing amount gives the band mean, not 0.
  const WavelengthBand o4{570.0, 585.0};
  EXPECT_NEAR(GasEffectiveCrossSection(Gas::kOxygenCollisions, o4, 1e43),
              GasEffectiveCrossSection(Gas::kOxygenCollisions, o4, 1e53), 2e-3 *
              GasEffectiveCrossSection(Gas::kOxygenCollisions, o4, 1e53));
  EXPECT_GT(GasEffectiveCrossSection(Gas::kOxygen, a_band, 0.0), 0.0);
}

// Measured with the 15 channels of us-standard (docs/parameters.md, "Gases"): the Beer-equivalent
// coefficient is exact at air mass 1.5 and, in the strongest band (O2-A in 746-779 nm), its
// transmittance is within 2.5 % of the band's at air mass 1-2, 22 % low at 5 and 48 % at 10. The
// bounds are those figures with a margin.
TEST(GasAbsorption, BeerEquivalentErrorAwayFromTheReferenceAirMass) {
  const std::vector<WavelengthBand> bands = ChannelBands(SpectralWavelengths(15));
  const struct {
    double air_mass, bound;
  } cases[] = {{1.0, 0.03}, {2.0, 0.035}, {5.0, 0.25}, {10.0, 0.52}};
  for (const auto& c : cases) {
    double worst = 0.0;
    for (const WavelengthBand& band : bands) {
      for (Gas gas : {Gas::kOxygen, Gas::kWaterVapor}) {
        const double n = gas == Gas::kOxygen ? O2Column() : WaterColumn();
        const double beer = std::exp(-GasEffectiveCrossSection(gas, band, n) * n * c.air_mass);
        const double exact = GasBandTransmittance(gas, band, n, c.air_mass);
        worst = std::max(worst, std::fabs(beer / exact - 1.0));
      }
    }
    EXPECT_LT(worst, c.bound) << "air mass " << c.air_mass;
  }
}

TEST(GasAbsorption, StandardPresetsCarryTheirGases) {
  const AtmosphereParameters p = Preset("us-standard");
  ASSERT_TRUE(p.water_vapor.present());
  EXPECT_TRUE(p.water_vapor.density.tabulated());
  // The water vapour column: peak density (from the strongest channel) times the profile.
  const std::vector<WavelengthBand> bands = ChannelBands(p.wavelengths_nm);
  const std::size_t c = 11;  // 729 nm, the strongest water band among the channels
  ASSERT_NEAR(p.wavelengths_nm[c], 729.29, 0.01);
  const double column = WaterColumn();
  const double peak = p.water_vapor.absorption_per_m[c] / GasEffectiveCrossSection(Gas::kWaterVapor, bands[c], column);
  EXPECT_NEAR(peak * ProfileIntegral(p.water_vapor.density), column, 0.01 * column);
  // O2-A in the air's absorption: the channel at 762.9 nm absorbs; 460.7 nm almost not.
  EXPECT_GT(p.rayleigh.absorption_per_m[12] * ProfileIntegral(p.rayleigh.density), 0.05);
  EXPECT_LT(p.rayleigh.absorption_per_m[3] * ProfileIntegral(p.rayleigh.density), 2e-3);
  // Gases off: the preset of before.
  StandardSkySettings settings;
  settings.gases = false;
  const AtmosphereParameters dry = StandardSky(settings);
  EXPECT_FALSE(dry.water_vapor.present());
  for (double a : dry.rayleigh.absorption_per_m) EXPECT_EQ(a, 0.0);
  // A wetter climatology holds more water: tropical 4.1 cm against 1.4.
  const AtmosphereParameters tropical = Preset("tropical");
  EXPECT_GT(tropical.water_vapor.absorption_per_m[c] * ProfileIntegral(tropical.water_vapor.density),
            2.0 * p.water_vapor.absorption_per_m[c] * ProfileIntegral(p.water_vapor.density));
}

// --spectral and --wavelengths recompute the gases for the new channels' bands from the amounts
// the old channels imply: at the preset's own wavelengths they give the preset back.
TEST(GasAbsorption, ResamplingRecomputesTheBands) {
  const AtmosphereParameters p = Preset("us-standard");
  const AtmosphereParameters same = MakeSpectral(p, 15);
  for (std::size_t c = 0; c < p.channel_count(); ++c) {
    EXPECT_NEAR(same.rayleigh.absorption_per_m[c], p.rayleigh.absorption_per_m[c],
                1e-6 * p.rayleigh.absorption_per_m[c] + 1e-15) << c;
    EXPECT_NEAR(same.water_vapor.absorption_per_m[c], p.water_vapor.absorption_per_m[c],
                1e-6 * p.water_vapor.absorption_per_m[c] + 1e-15) << c;
  }
  // A narrow channel on the A band absorbs far more than a wide one around it.
  const std::vector<double> narrow = {755.0, 765.0, 775.0};
  const AtmosphereParameters a = MakeSpectral(p, narrow);
  EXPECT_GT(a.rayleigh.absorption_per_m[1], 2.0 * p.rayleigh.absorption_per_m[12]);
  EXPECT_NO_THROW(Validate(a));
  // Bad wavelengths: one-line errors.
  const std::vector<double> outside = {300.0, 400.0};
  EXPECT_NE(ErrorOf([&] { MakeSpectral(p, outside); }).find("outside [360, 830] nm"), std::string::npos);
  const std::vector<double> decreasing = {500.0, 400.0};
  EXPECT_NE(ErrorOf([&] { MakeSpectral(p, decreasing); }).find("must increase"), std::string::npos);
}

TEST(WaterVapor, JsonRoundTripsAndBadValuesAreRefused) {
  const AtmosphereParameters p = Preset("us-standard");
  EXPECT_EQ(FromJson(ToJson(p)), p);
  // The seed presets have none, and their JSON does not mention it.
  EXPECT_EQ(ToJson(Preset("earth")).find("water_vapor"), std::string::npos);
  EXPECT_FALSE(FromJson(ToJson(Preset("earth"))).water_vapor.present());
  // Water vapour added to the earth preset: constant absorption, its own exponential profile.
  const AtmosphereParameters wet = FromJson(
      R"({"preset": "earth", "water_vapor": {"absorption_per_m": 1e-6, "density": {"table": [[0, 1], [2000, 0.37], [10000, 0.007]]}}})");
  EXPECT_TRUE(wet.water_vapor.present());
  EXPECT_EQ(wet.water_vapor.absorption_per_m.size(), 3u);
  EXPECT_NE(ErrorOf([] { FromJson(R"({"water_vapor": {"scattering_per_m": 1e-6}})"); })
                .find("water_vapor.scattering_per_m[0] must be 0"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { FromJson(R"({"water_vapor": {"absorption_per_m": -1}})"); })
                .find("water_vapor.absorption_per_m"),
            std::string::npos);
}

// Every model attenuates by the water vapour's optical depth: the transmittance to the zenith with
// and without it differs by exp(-absorption * profile integral), and the radiance drops.
TEST(WaterVapor, EveryModelAbsorbsItsOpticalDepth) {
  const std::vector<double> w = {650.0, 720.0, 820.0};
  const AtmosphereParameters wet = MakeSpectral(Preset("us-standard"), w);
  AtmosphereParameters dry = wet;
  dry.water_vapor.absorption_per_m.assign(3, 0.0);
  const glm::dvec3 sun = DirectionFromZenithAzimuth(glm::radians(60.0), 0.0);
  const glm::dvec3 zenith(0.0, 0.0, 1.0);
  const double integral = ProfileIntegral(wet.water_vapor.density);
  for (const char* model : {"hillaire", "elek", "source4d", "reference"}) {
    SCOPED_TRACE(model);
    const ModelOptions options =
        std::string(model) == "reference" ? ModelOptions{{"samples", "64"}, {"seed", "3"}} : ModelOptions{};
    const auto wet_model = CreateModel(model, wet, options);  // views borrow their model
    const auto dry_model = CreateModel(model, dry, options);
    const auto with = wet_model->View(0.0, sun);
    const auto without = dry_model->View(0.0, sun);
    std::vector<double> t_with(3), t_without(3), l_with(3), l_without(3);
    with->Transmittance(zenith, t_with);
    without->Transmittance(zenith, t_without);
    with->Radiance(zenith, l_with);
    without->Radiance(zenith, l_without);
    for (int c = 0; c < 3; ++c) {
      const double tau = wet.water_vapor.absorption_per_m[c] * integral;
      EXPECT_NEAR(std::log(t_without[c] / t_with[c]), tau, 0.01 * tau + 1e-5) << "channel " << c;
      // The reference's radiance is an estimate; its transmittance is exact quadrature.
      if (tau > 0.01 && std::string(model) != "reference") EXPECT_LT(l_with[c], l_without[c] * (1.0 - 0.3 * tau)) << "channel " << c;
    }
  }
}

}  // namespace
}  // namespace atmo
