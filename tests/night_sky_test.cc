// The night sky's own light (include/atmo/night_sky.h, docs/night.md): airglow and zodiacal light
// against published levels, their geometry, their spectra and their place in the renderers.
#include <cmath>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "atmo/colour.h"
#include "atmo/error.h"
#include "atmo/model.h"
#include "atmo/night_sky.h"
#include "atmo/parameters.h"
#include "atmo/render.h"
#include "atmo/spectrum.h"
#include "atmo/sun_position.h"
#include "physics/data/airglow_table.h"

namespace atmo {
namespace {

constexpr double kPi = std::numbers::pi;

glm::dvec3 Elevated(double elevation_deg, double azimuth_deg) {
  return DirectionFromZenithAzimuth(glm::radians(90.0 - elevation_deg), glm::radians(azimuth_deg));
}

double Luminance(const AtmosphereParameters& p, const NightSky& night, const glm::dvec3& view) {
  std::vector<double> radiance(p.channel_count());
  night.Radiance(view, radiance);
  return SpectralConversion(p.wavelengths_nm).Luminance(radiance);
}

// The published dark sky at the zenith, sea level, no moon: 21.4 to 22.3 V mag/arcsec^2 (Benn and
// Ellison 1998 at La Palma, 21.9 at solar minimum and 0.4 mag brighter at maximum; Patat 2003 at
// Paranal, 21.6 at solar maximum), which is 1.2e-4 to 2.7e-4 cd/m^2 (Garstang 1986's conversion,
// L = 1.085e5 10^(-0.4 V) cd/m^2). Those sites are 2.4 and 2.6 km up; sea level adds about
// 0.1 mag of extinction, inside the range.
TEST(NightSky, MoonlessZenithIsThePublishedDarkSky) {
  for (const char* preset : {"earth", "earth-spectral", "us-standard"}) {
    const AtmosphereParameters p = Preset(preset);
    const NightSky night(p, 0.0, Elevated(-30.0, 270.0));
    const double zenith = Luminance(p, night, glm::dvec3(0, 0, 1));
    EXPECT_GE(zenith, 1.2e-4) << preset;
    EXPECT_LE(zenith, 2.7e-4) << preset;
    // The airglow brighter towards the horizon (van Rhijn) until the extinction wins right at it.
    std::vector<double> up(p.channel_count()), low(p.channel_count());
    night.AirglowRadiance(glm::dvec3(0, 0, 1), up);
    night.AirglowRadiance(Elevated(20.0, 90.0), low);
    const SpectralConversion convert(p.wavelengths_nm);
    EXPECT_GT(convert.Luminance(low), 1.3 * convert.Luminance(up)) << preset;
    const double at_20 = Luminance(p, night, Elevated(20.0, 90.0));
    std::printf("%s zenith %.3g cd/m2, 20 deg %.3g, 5 deg %.3g, 1 deg %.3g\n", preset, zenith, at_20,
                Luminance(p, night, Elevated(5.0, 90.0)), Luminance(p, night, Elevated(1.0, 90.0)));
  }
}

}  // namespace
}  // namespace atmo
