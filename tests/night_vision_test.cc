// Night vision for display (include/atmo/night_vision.h): the CIE 191 mesopic system, the scotopic
// luminance from the channels, and the image as seen.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "atmo/colour.h"
#include "atmo/error.h"
#include "atmo/night_vision.h"
#include "atmo/parameters.h"
#include "atmo/spectrum.h"

namespace atmo {
namespace {

// CIE 191:2010: photopic (m = 1) at and above about 5 cd/m^2, scotopic (m = 0) at and below a
// scotopic luminance of about 0.005 cd/m^2, monotone between; the published dark sky (2e-4 cd/m^2)
// is scotopic.
TEST(NightVision, MesopicAdaptationFollowsCie191) {
  EXPECT_EQ(MesopicAdaptation(5.0, 12.0), 1.0);
  EXPECT_EQ(MesopicAdaptation(1000.0, 2500.0), 1.0);
  EXPECT_EQ(MesopicAdaptation(2e-4, 5e-4), 0.0);
  EXPECT_LT(MesopicAdaptation(0.002, 0.005), 0.01);
  double previous = 0.0;
  for (double l = 0.005; l <= 5.0; l *= 1.5) {
    const double m = MesopicAdaptation(l, 2.3 * l);
    EXPECT_GE(m, previous) << l;
    previous = m;
  }
  double mesopic = 0.0;
  const double m = MesopicAdaptation(0.1, 0.25, &mesopic);
  EXPECT_GT(m, 0.2);
  EXPECT_LT(m, 0.8);
  EXPECT_GT(mesopic, 0.1);  // a blue-rich light looks brighter to a partly scotopic eye
  EXPECT_LT(mesopic, 0.25 / 0.402);
}

// Sunlight's scotopic-to-photopic ratio (S/P) is about 2.3-2.5 (D65: 2.47); the scotopic luminance
// from the colour equals the channels' own for three channels, and is close for fifteen.
TEST(NightVision, ScotopicLuminanceFromTheChannels) {
  for (const char* preset : {"earth", "earth-spectral"}) {
    const AtmosphereParameters p = Preset(preset);
    const SpectralConversion convert(p.wavelengths_nm);
    const std::vector<double> sun(p.channel_count(), 1.0);
    const double ratio = convert.ScotopicLuminance(sun) / convert.Luminance(sun);
    EXPECT_GT(ratio, 2.1) << preset;
    EXPECT_LT(ratio, 2.7) << preset;
    const NightVision vision(p.wavelengths_nm);
    // A blue sky-like spectrum (lambda^-4) and the sun's.
    std::vector<double> blue(p.channel_count());
    for (std::size_t c = 0; c < blue.size(); ++c) blue[c] = std::pow(550.0 / p.wavelengths_nm[c], 4.0);
    const std::vector<double>* spectra[] = {&sun, &blue};
    for (const std::vector<double>* r : spectra) {
      const glm::dvec3 rgb = convert.LinearSrgb(*r);
      // Exact for 3 channels; from the colour of 15, within 10 % (the colour does not fix the spectrum).
      const double tolerance = p.channel_count() == 3 ? 1e-6 : 0.1;
      EXPECT_NEAR(vision.ScotopicLuminance(rgb), convert.ScotopicLuminance(*r),
                  tolerance * convert.ScotopicLuminance(*r))
          << preset;
    }
  }
  EXPECT_NEAR(ScotopicEfficiency(505.0), 0.998, 1e-9);
  EXPECT_NEAR(ScotopicEfficiency(555.0), 0.402, 1e-9);
  EXPECT_EQ(ScotopicEfficiency(800.0), 0.0);
}

// Daylight is seen as it is; a night image loses its colour to blue-grey at its mesopic luminance.
TEST(NightVision, DaylightUnchangedNightDesaturated) {
  const NightVision vision(Preset("earth").wavelengths_nm);
  Image day(2, 1, 3);
  day.colour_space = ColourSpace::kLinearSrgb;
  day.pixels = {3000.0f, 4000.0f, 6000.0f, 500.0f, 400.0f, 300.0f};
  Image seen = day;
  EXPECT_EQ(ApplyNightVision(seen, vision), 1.0);
  for (std::size_t i = 0; i < day.pixels.size(); ++i) EXPECT_NEAR(seen.pixels[i], day.pixels[i], 1e-3 * day.pixels[i]);
  Image night(2, 1, 3);
  night.colour_space = ColourSpace::kLinearSrgb;
  night.pixels = {3e-4f, 2e-4f, 1e-4f, 1e-4f, 1.5e-4f, 3e-4f};  // an orange and a blue pixel
  Image dark = night;
  EXPECT_EQ(ApplyNightVision(dark, vision), 0.0);
  // Fully scotopic: both pixels take the same chromaticity, their luminance the scotopic one.
  const double r0 = dark.pixels[0] / dark.pixels[2];
  const double r1 = dark.pixels[3] / dark.pixels[5];
  EXPECT_NEAR(r0, r1, 1e-4 * r0);
  EXPECT_LT(dark.pixels[0], dark.pixels[2]);  // blue-grey
  const glm::dvec3 orange(3e-4, 2e-4, 1e-4);
  const double y = 0.2126 * dark.pixels[0] + 0.7152 * dark.pixels[1] + 0.0722 * dark.pixels[2];
  EXPECT_NEAR(y, vision.ScotopicLuminance(orange), 1e-3 * y);
  Image wrong(1, 1, 4);
  EXPECT_THROW(ApplyNightVision(wrong, vision), Error);
}

}  // namespace
}  // namespace atmo
