// Spectral tables, Rayleigh scattering from first principles, spectral atmospheres, and the colour
// conversion: checked against independent published values and closed forms.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "atmo/colour.h"
#include "atmo/error.h"
#include "atmo/parameters.h"
#include "atmo/spectrum.h"
#include "physics/shared_parameters.h"

namespace atmo {
namespace {

// E. Shettle's fit to the Bodhaine et al. 1999 cross-sections (valid 200..2000 nm), as published
// in the GATS molec_scatter2 routine (M. Hervig): sigma = a l^-4 / (1 + b l^-2 + c l^-4) cm^2 with
// l in nm, a = 3.96815e-16, b = -1.15682e4, c = -3.68073e7. An independent check of our
// first-principles evaluation.
double ShettleFitCrossSectionM2(double l) {
  const double l2 = 1.0 / (l * l);
  return 3.96815e-16 * l2 * l2 / (1.0 - 1.15682e4 * l2 - 3.68073e7 * l2 * l2) * 1e-4;
}

TEST(Spectrum, RayleighCrossSectionMatchesShettleFitOfBodhaine) {
  for (double l = 360.0; l <= 830.0; l += 10.0) {
    // The fit's stated accuracy is a few tenths of a per cent over the visible.
    EXPECT_NEAR(RayleighCrossSection(l) / ShettleFitCrossSectionM2(l), 1.0, 3e-3) << l << " nm";
  }
}

TEST(Spectrum, RayleighCrossSectionFallsSlightlyFasterThanLambdaToTheMinusFour) {
  // The refractive index and the King factor both grow towards the blue: the exponent is ~ -4.08.
  const double exponent = std::log(RayleighCrossSection(400.0) / RayleighCrossSection(800.0)) / std::log(0.5);
  EXPECT_LT(exponent, -4.0);
  EXPECT_GT(exponent, -4.2);
  EXPECT_THROW(RayleighCrossSection(-1.0), Error);
  EXPECT_THROW(RayleighCrossSection(550.0, std::nan("")), Error);
}

TEST(Spectrum, LuminousSolarConstantMatchesPublishedValue) {
  // Darula, Kittler and Gueymard 2005, "Reference luminous solar constant and solar luminance for
  // illuminance calculations", Solar Energy 79: 133.8 klx. Our 10 nm bins of ASTM G-173 and the
  // 360..830 nm range give it to about 1 %.
  double lux = 0.0;
  for (double l = 360.0; l <= 830.0; l += 1.0) {
    const double w = (l == 360.0 || l == 830.0) ? 0.5 : 1.0;
    lux += kMaxLuminousEfficacy * CieColourMatching(l).y * SolarSpectralIrradiance(l) * w;
  }
  EXPECT_NEAR(lux, 133.8e3, 0.015 * 133.8e3);
}

TEST(Spectrum, CieTablesHaveTheirKnownValues) {
  // CIE 1931: y-bar(555) = 1 (peak of V), x-bar(600) = 1.0622, z-bar(445) = 1.7826.
  EXPECT_DOUBLE_EQ(CieColourMatching(555.0).y, 1.0);
  EXPECT_DOUBLE_EQ(CieColourMatching(600.0).x, 1.0622);
  EXPECT_DOUBLE_EQ(CieColourMatching(445.0).z, 1.7826);
  EXPECT_EQ(CieColourMatching(300.0), glm::dvec3(0.0));
  // Equal-energy white has x = y = 1/3 by the definition of the functions.
  glm::dvec3 sum(0.0);
  for (double l = 360.0; l <= 830.0; l += 5.0) sum += CieColourMatching(l);
  EXPECT_NEAR(sum.x / (sum.x + sum.y + sum.z), 1.0 / 3.0, 2e-4);
  EXPECT_NEAR(sum.y / (sum.x + sum.y + sum.z), 1.0 / 3.0, 2e-4);
}

TEST(Spectrum, EarthSpectralIsPhysicalAndMatchesEarthWhereItShould) {
  const AtmosphereParameters p = EarthSpectral();
  ASSERT_EQ(p.channel_count(), 15u);
  EXPECT_DOUBLE_EQ(p.wavelengths_nm.front(), 360.0);
  EXPECT_DOUBLE_EQ(p.wavelengths_nm.back(), 830.0);
  const AtmosphereParameters earth = Preset("earth");
  // 300 DU in the earth preset's 15 km tent with Serdyuchenko's cross-sections is the earth
  // preset's ozone (Bruneton 2017's values) to the precision of the bin placement.
  SpectralEarthSettings s;
  s.wavelength_count = 3;
  const AtmosphereParameters three = EarthSpectral(s);
  EXPECT_NEAR(three.ozone.absorption_per_m[0], 300.0 * kDobsonUnitPerM2 / 15e3 * OzoneCrossSection(360.0), 1e-20);
  // Rayleigh at 550 nm: Bodhaine's 4.51e-31 m^2 x 2.547e25 m^-3 = 1.149e-5 m^-1, ~15 % below the
  // lambda^-4 law of the earth preset (13.558e-6), which was fitted for other constants.
  EXPECT_NEAR(RayleighCrossSection(550.0) * kAirNumberDensityAtSeaLevel, 1.149e-5, 0.005e-5);
  // Aerosol optical depth at 550 nm is what was asked: extinction x scale height.
  const double e550 = s.aerosol_optical_depth_550 / 1200.0;
  SpectralEarthSettings at550 = s;
  at550.angstrom_exponent = 0.0;
  const AtmosphereParameters flat = EarthSpectral(at550);
  EXPECT_NEAR(flat.mie.extinction_per_m(1), e550, 1e-15);
  EXPECT_NEAR(flat.mie.scattering_per_m[1] / flat.mie.extinction_per_m(1), 0.9, 1e-12);
  EXPECT_EQ(p.rayleigh.density, earth.rayleigh.density);
  EXPECT_EQ(p.ozone.density, earth.ozone.density);
  for (std::size_t i = 0; i < p.channel_count(); ++i) {
    EXPECT_DOUBLE_EQ(p.solar_irradiance[i], SolarSpectralIrradiance(p.wavelengths_nm[i]));
  }
  SpectralEarthSettings bad;
  bad.aerosol_optical_depth_550 = -1.0;
  EXPECT_THROW(EarthSpectral(bad), Error);
  EXPECT_NO_THROW(Preset("earth-spectral"));
}

TEST(Spectrum, MakeSpectralContinuesEachMediumByItsPhysics) {
  const AtmosphereParameters earth = Preset("earth");
  const AtmosphereParameters p = MakeSpectral(earth, 48);
  ASSERT_EQ(p.channel_count(), 48u);
  // Rayleigh: a scaled Bodhaine law that passes close to the preset's three values (the preset
  // follows lambda^-4 exactly, Bodhaine ~lambda^-4.08: a few per cent apart at the ends).
  const double k = p.rayleigh.scattering_per_m[10] / RayleighCrossSection(p.wavelengths_nm[10]);
  for (std::size_t i = 0; i < 48; ++i) {
    EXPECT_NEAR(p.rayleigh.scattering_per_m[i] / RayleighCrossSection(p.wavelengths_nm[i]), k, 1e-9 * k);
  }
  for (std::size_t c = 0; c < 3; ++c) {
    EXPECT_NEAR(k * RayleighCrossSection(earth.wavelengths_nm[c]) / earth.rayleigh.scattering_per_m[c], 1.0, 0.05);
  }
  // Mie: the earth preset's flat extinction stays flat (alpha = 0), its albedo 0.9 stays 0.9.
  for (std::size_t i = 0; i < 48; ++i) {
    EXPECT_NEAR(p.mie.extinction_per_m(i), 4.44e-6, 1e-12);
    EXPECT_NEAR(p.mie.scattering_per_m[i], 3.996e-6, 1e-12);
    EXPECT_DOUBLE_EQ(p.ground_albedo[i], 0.3);
  }
  // Ozone: the preset's values are 300 DU of the 10 nm bin means taken at the bins' lower edges
  // (Bruneton 2017's reading); we place them at the bin centres, so the fit finds 300 DU within
  // the ~8 % that the half-bin shift makes in the Chappuis band's slopes.
  const double du = p.ozone.absorption_per_m[20] / OzoneCrossSection(p.wavelengths_nm[20]) * 15e3 / kDobsonUnitPerM2;
  EXPECT_NEAR(du, 300.0, 30.0);
  // An Angstrom law is recovered exactly from its own samples.
  AtmosphereParameters hazy = earth;
  for (std::size_t c = 0; c < 3; ++c) {
    const double e = 1e-5 * std::pow(earth.wavelengths_nm[c] / 550.0, -1.3);
    hazy.mie.scattering_per_m[c] = 0.8 * e;
    hazy.mie.absorption_per_m[c] = 0.2 * e;
  }
  const AtmosphereParameters q = MakeSpectral(hazy, 8);
  for (std::size_t i = 0; i < 8; ++i) {
    EXPECT_NEAR(q.mie.extinction_per_m(i), 1e-5 * std::pow(q.wavelengths_nm[i] / 550.0, -1.3), 1e-14);
  }
  EXPECT_THROW(MakeSpectral(earth, 2), Error);
  EXPECT_THROW(MakeSpectral(earth, 1000), Error);
  EXPECT_NO_THROW(MakeSpectral(Preset("simple"), 9));
  EXPECT_NO_THROW(MakeSpectral(Preset("atmosphere-plus"), 9));
}

TEST(Colour, Ciede2000MatchesSharmaTestData) {
  // Sharma, Wu and Dalal 2005, Table 1, pairs 1, 7, 17 and 25.
  EXPECT_NEAR(DeltaE2000({50.0, 2.6772, -79.7751}, {50.0, 0.0, -82.7485}), 2.0425, 1e-4);
  EXPECT_NEAR(DeltaE2000({50.0, 0.0, 0.0}, {50.0, -1.0, 2.0}), 2.3669, 1e-4);
  EXPECT_NEAR(DeltaE2000({50.0, 2.5, 0.0}, {73.0, 25.0, -18.0}), 27.1492, 1e-4);
  EXPECT_NEAR(DeltaE2000({60.2574, -34.0099, 36.2677}, {60.4626, -34.1751, 39.4387}), 1.2644, 1e-4);
  EXPECT_DOUBLE_EQ(DeltaE2000({40.0, 10.0, -5.0}, {40.0, 10.0, -5.0}), 0.0);
}

TEST(Colour, SrgbMatrixMapsD65WhiteToEqualRgb) {
  // D65 white, Y = 1: x = 0.3127, y = 0.3290.
  const glm::dvec3 d65(0.3127 / 0.3290, 1.0, (1.0 - 0.3127 - 0.3290) / 0.3290);
  const glm::dvec3 rgb = XyzToLinearSrgb(d65);
  EXPECT_NEAR(rgb.x, 1.0, 2e-3);
  EXPECT_NEAR(rgb.y, 1.0, 2e-3);
  EXPECT_NEAR(rgb.z, 1.0, 2e-3);
  const glm::dvec3 back = LinearSrgbToXyz(rgb);
  EXPECT_NEAR(back.y, 1.0, 1e-12);
}

TEST(Colour, ConversionOfAFlatRelativeSpectrumIsTheSunItself) {
  // r(lambda) = c for all channels: L = c E(lambda), whatever the channel set. Its luminance is
  // c times the luminous solar constant of the shipped spectrum.
  double sun_lux = 0.0;
  for (double l = 360.0; l <= 830.0; l += 1.0) {
    sun_lux += kMaxLuminousEfficacy * CieColourMatching(l).y * SolarSpectralIrradiance(l) *
               ((l == 360.0 || l == 830.0) ? 0.5 : 1.0);
  }
  for (const std::vector<double>& wavelengths :
       {std::vector<double>{680.0, 550.0, 440.0}, SpectralWavelengths(16), SpectralWavelengths(81)}) {
    const SpectralConversion convert(wavelengths);
    const std::vector<double> r(wavelengths.size(), 2.0);
    EXPECT_NEAR(convert.Luminance(r), 2.0 * sun_lux, 1e-9 * sun_lux);
  }
  // The sun's colour through sRGB: slightly warm of D65 white (a 5800 K black body is warmer
  // than D65's 6504 K): R > B.
  const SpectralConversion convert(SpectralWavelengths(81));
  const glm::dvec3 rgb = convert.LinearSrgb(std::vector<double>(81, 1.0));
  EXPECT_GT(rgb.x, rgb.z);
}

TEST(Colour, LinearSpectrumIsReproducedExactlyByItsSamples) {
  // A spectrum linear in wavelength is represented exactly by any channel set that spans 360..830:
  // the 16- and 81-channel conversions agree to rounding.
  const auto linear = [](double l) { return 1.0 + (l - 360.0) / 470.0; };
  const std::vector<double> w16 = SpectralWavelengths(16);
  const std::vector<double> w81 = SpectralWavelengths(81);
  std::vector<double> r16, r81;
  for (double l : w16) r16.push_back(linear(l));
  for (double l : w81) r81.push_back(linear(l));
  const glm::dvec3 a = SpectralConversion(w16).Xyz(r16);
  const glm::dvec3 b = SpectralConversion(w81).Xyz(r81);
  EXPECT_NEAR(a.x / b.x, 1.0, 1e-12);
  EXPECT_NEAR(a.y / b.y, 1.0, 1e-12);
  EXPECT_NEAR(a.z / b.z, 1.0, 1e-12);
}

TEST(Colour, ConvertImageRecordsTheColourSpace) {
  Image relative(2, 1, 3);
  for (float& v : relative.pixels) v = 0.01f;
  const SpectralConversion convert(std::vector<double>{680.0, 550.0, 440.0});
  const Image rgb = ConvertImage(relative, convert, ImageColour::kLinearSrgb);
  EXPECT_EQ(rgb.colour_space, ColourSpace::kLinearSrgb);
  const Image xyz = ConvertImage(relative, convert, ImageColour::kXyz);
  EXPECT_EQ(xyz.colour_space, ColourSpace::kCieXyz);
  // Rec.709 luminance of the RGB equals Y of the XYZ image.
  const double y = 0.2126 * rgb.at(0, 0, 0) + 0.7152 * rgb.at(0, 0, 1) + 0.0722 * rgb.at(0, 0, 2);
  EXPECT_NEAR(y / xyz.at(0, 0, 1), 1.0, 2e-3);
  EXPECT_THROW(ConvertImage(Image(2, 1, 4), convert, ImageColour::kXyz), Error);
}

// The values of one batch of three channels (the GL backend's solar irradiance per batch): a
// last batch with fewer channels repeats its last one, as ToSharedParameters does.
TEST(Spectrum, BatchValuesRepeatTheLastChannel) {
  const std::vector<double> values = {1.0, 2.0, 3.0, 4.0, 5.0};
  EXPECT_EQ(BatchValues(values, 0), glm::dvec3(1.0, 2.0, 3.0));
  EXPECT_EQ(BatchValues(values, 1), glm::dvec3(4.0, 5.0, 5.0));
  const AtmosphereParameters p = MakeSpectral(Preset("earth"), 7);
  EXPECT_EQ(BatchValues(p.wavelengths_nm, 2), ToSharedParameters(p, 2).wavelength);
  EXPECT_EQ(ChannelBatchCount(7), 3u);
  EXPECT_THROW(BatchValues(std::vector<double>{}, 0), Error);
}

}  // namespace
}  // namespace atmo
