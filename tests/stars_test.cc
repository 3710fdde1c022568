// The stars (include/atmo/stars.h, docs/night.md): the catalogue read from Debian's stellarium-data
// against known stars, the celestial frame against libnova, and the stars' light.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>
#include <libnova/julian_day.h>
#include <libnova/precession.h>
#include <libnova/transform.h>

#include "atmo/colour.h"
#include "atmo/error.h"
#include "atmo/model.h"
#include "atmo/night_sky.h"
#include "atmo/render.h"
#include "atmo/stars.h"
#include "atmo/sun_position.h"
#include "cpu/camera.h"
#include "shared/shared.h"

namespace atmo {
namespace {

constexpr double kPi = std::numbers::pi;

// The catalogue when Debian's stellarium-data is installed (scripts/install_deps.sh installs it);
// the tests that need it skip where it is absent.
const StarCatalogue* Catalogue() {
  if (!std::filesystem::is_directory(StarCatalogue::DefaultFolder())) return nullptr;
  return &StarCatalogue::Default();
}

const Star* FindHip(const StarCatalogue& catalogue, int hip) {
  for (const Star& star : catalogue.stars()) {
    if (star.hip == hip) return &star;
  }
  return nullptr;
}

double RaDeg(const glm::dvec3& d) {
  const double ra = glm::degrees(std::atan2(d.y, d.x));
  return ra < 0.0 ? ra + 360.0 : ra;
}
double DecDeg(const glm::dvec3& d) { return glm::degrees(std::asin(d.z)); }

// Known stars at J2000 (Hipparcos): Sirius HIP 32349 at RA 101.2872, Dec -16.7161, V -1.46;
// Polaris HIP 11767 at RA 37.9546, Dec 89.2641, V 1.97; Vega HIP 91262 at RA 279.2347, Dec 38.7837,
// V 0.03, B-V 0.00. And the count: about 9 100 stars to V 6.5 (the Yale Bright Star Catalogue's 9 110).
TEST(Stars, CatalogueHoldsTheKnownStars) {
  const StarCatalogue* catalogue = Catalogue();
  if (catalogue == nullptr) GTEST_SKIP() << "no stellarium-data at " << StarCatalogue::DefaultFolder();
  struct Known {
    int hip;
    double ra, dec, v;
  };
  for (const Known& k : {Known{32349, 101.2872, -16.7161, -1.46}, Known{11767, 37.9546, 89.2641, 1.97},
                         Known{91262, 279.2347, 38.7837, 0.03}}) {
    const Star* star = FindHip(*catalogue, k.hip);
    ASSERT_NE(star, nullptr) << k.hip;
    EXPECT_NEAR(DecDeg(star->direction), k.dec, 0.002) << k.hip;
    EXPECT_NEAR(RaDeg(star->direction) * std::cos(glm::radians(k.dec)), k.ra * std::cos(glm::radians(k.dec)), 0.002)
        << k.hip;
    EXPECT_NEAR(star->v_mag, k.v, 0.05) << k.hip;
  }
  EXPECT_NEAR(FindHip(*catalogue, 91262)->b_v, 0.0, 0.05);
  // Sirius moves 1.34"/yr at position angle 204.1 degrees (Hipparcos: -546 mas/yr in RA, -1223 in
  // Dec). The format stores the motion in the zone's tangent plane; read back as Stellarium reads it
  // (the derivative of the normalised position) it gives 1.42"/yr at 205.8 degrees for Sirius, far
  // from its zone's centre: 2" of position in 26 years. (The two other readings, without the
  // projection's 1/length and without the projection, give 1.50 and 1.59"/yr.) The bounds hold the
  // reader to the Hipparcos motion within that measured difference.
  EXPECT_NEAR(glm::length(FindHip(*catalogue, 32349)->motion_per_yr) * 180.0 / kPi * 3600.0, 1.339, 0.1);
  {
    const Star& sirius = *FindHip(*catalogue, 32349);
    const double ra = glm::radians(RaDeg(sirius.direction)), dec = glm::radians(DecDeg(sirius.direction));
    const glm::dvec3 east(-std::sin(ra), std::cos(ra), 0.0);
    const glm::dvec3 north(-std::sin(dec) * std::cos(ra), -std::sin(dec) * std::sin(ra), std::cos(dec));
    double angle = glm::degrees(std::atan2(glm::dot(sirius.motion_per_yr, east), glm::dot(sirius.motion_per_yr, north)));
    if (angle < 0.0) angle += 360.0;
    EXPECT_NEAR(angle, 204.1, 2.0);
  }
  int to_6_5 = 0;
  for (const Star& star : catalogue->stars()) to_6_5 += star.v_mag <= 6.5f;
  EXPECT_GT(to_6_5, 8000);
  EXPECT_LT(to_6_5, 10500);
  EXPECT_GT(catalogue->stars().size(), 25000u);  // to V 7.5
}

// A star's horizontal place from CelestialFrame::FromDate against libnova's (precession
// ln_get_equ_prec2, then ln_get_hrz_from_equ with the mean sidereal time), within 0.01 degrees.
TEST(Stars, FrameFromDatePlacesStarsAsLibnova) {
  Star star;
  for (const auto& [ra, dec] : {std::pair{101.2872, -16.7161}, std::pair{37.9546, 89.2641}, std::pair{279.2347, 38.7837}}) {
    star.direction = glm::dvec3(std::cos(glm::radians(dec)) * std::cos(glm::radians(ra)),
                                std::cos(glm::radians(dec)) * std::sin(glm::radians(ra)), std::sin(glm::radians(dec)));
    star.motion_per_yr = glm::dvec3(0.0);
    for (const char* date : {"2026-12-04T03:00Z", "2031-07-01T22:00Z"}) {
      const double jd = ParseIsoDateTime(date);
      const double latitude = 46.5, longitude = 7.9;
      const glm::dvec3 local = CelestialFrame::FromDate(jd, latitude, longitude).ToLocal(star);
      ln_equ_posn mean{ra, dec}, precessed{};
      ln_get_equ_prec2(&mean, JD2000, jd, &precessed);
      ln_lnlat_posn observer{longitude, latitude};
      ln_hrz_posn hrz{};
      ln_get_hrz_from_equ(&precessed, &observer, jd, &hrz);
      const double azimuth = glm::radians(hrz.az + 180.0);  // libnova's from the south, westward
      const glm::dvec3 expected = DirectionFromZenithAzimuth(glm::radians(90.0 - hrz.alt), azimuth);
      EXPECT_LT(glm::degrees(std::acos(std::min(1.0, glm::dot(local, expected)))), 0.01) << ra << " " << date;
    }
  }
  // Polaris stands at about the latitude.
  star.direction = glm::dvec3(0, 0, 1);
  const glm::dvec3 pole = CelestialFrame::FromDate(ParseIsoDateTime("2026-12-04T03:00Z"), 46.5, 7.9).ToLocal(star);
  EXPECT_NEAR(glm::degrees(std::asin(pole.z)), 46.5, 0.3);  // the precessed pole moved 0.36 degrees since 2000
  EXPECT_THROW(CelestialFrame::FromDate(ParseIsoDateTime("2026-12-04T03:00Z"), 91.0, 0.0), Error);
}

// Without a date the celestial sphere is turned so that the sun (at the December solstice) is where
// it was asked and the ecliptic is the default one: stars, zodiacal light and sun agree.
TEST(Stars, FrameFromTheSunAgreesWithTheEcliptic) {
  for (const glm::dvec3& sun : {DirectionFromZenithAzimuth(glm::radians(120.0), glm::radians(200.0)),
                                DirectionFromZenithAzimuth(glm::radians(60.0), glm::radians(10.0))}) {
    const CelestialFrame frame = CelestialFrame::FromSun(sun);
    const double epsilon = glm::radians(23.4392911);
    // The sun at ecliptic longitude 270: RA 270, Dec -epsilon.
    Star solstice;
    solstice.direction = glm::dvec3(0.0, -std::cos(epsilon), -std::sin(epsilon));
    EXPECT_NEAR(glm::dot(frame.ToLocal(solstice), sun), 1.0, 1e-12);
    EXPECT_NEAR(glm::dot(frame.EclipticPole(), DefaultEclipticPole(sun)), 1.0, 1e-12);
  }
}

// A star's light: an A0 star of V = 0 gives 2.5e-6 lx outside the atmosphere (the V zero point of
// Bessell, Castelli and Plez 1998 through the photopic curve), redder stars more in the red.
TEST(Stars, StarLightFromItsMagnitudeAndColour) {
  const std::vector<double> wavelengths = [] {
    std::vector<double> w;
    for (int i = 0; i < 48; ++i) w.push_back(360.0 + 10.0 * i);
    return w;
  }();
  const SpectralConversion convert(wavelengths);
  Star vega;
  vega.v_mag = 0.0f;
  vega.b_v = 0.0f;
  std::vector<double> r(wavelengths.size());
  StarRelativeIrradiance(vega, wavelengths, r);
  EXPECT_NEAR(convert.Luminance(r), 2.54e-6, 0.25e-6);
  Star faint = vega;
  faint.v_mag = 5.0f;
  std::vector<double> q(wavelengths.size());
  StarRelativeIrradiance(faint, wavelengths, q);
  EXPECT_NEAR(convert.Luminance(q) / convert.Luminance(r), 0.01, 1e-6);
  Star red = vega;
  red.b_v = 1.5f;
  StarRelativeIrradiance(red, wavelengths, q);
  EXPECT_GT(q.back() / q.front(), 10.0 * r.back() / r.front());
  EXPECT_NEAR(StarTemperatureK(0.65), 5750.0, 150.0);  // the sun's B-V and temperature
}

// Drawn into the pixels, the stars' energy (sum of value x pixel solid angle) is the same at two
// resolutions and equals the sum of their attenuated irradiances.
TEST(Stars, StarsKeepTheirEnergyAtAnyResolution) {
  const StarCatalogue* catalogue = Catalogue();
  if (catalogue == nullptr) GTEST_SKIP() << "no stellarium-data";
  AtmosphereParameters p = Preset("earth");
  p.night_sky.airglow_scale = 0.0;
  p.night_sky.zodiacal_scale = 0.0;
  p.night_sky.starlight_scale = 0.0;  // the stars drawn one by one alone
  const auto model = CreateModel("hillaire", p);
  const glm::dvec3 sun = DirectionFromZenithAzimuth(glm::radians(125.0), 0.0);
  const auto sky = model->View(0.0, sun);
  NightSky night(p, 0.0, sun);
  night.SetStars(*catalogue, CelestialFrame::FromDate(ParseIsoDateTime("2026-12-04T00:00Z"), 46.5, 7.9));
  RadianceTerms terms;
  terms.night_sky = &night;
  const SpectralConversion convert(p.wavelengths_nm);
  std::vector<double> energies;
  for (int size : {256, 1024}) {
    const Camera camera{CameraKind::kFisheye, size, size};
    const Image image = RenderView(*sky, camera, terms, std::vector<double>(3, 1.0));
    std::vector<double> sum(3, 0.0);
    for (int y = 0; y < size; ++y) {
      for (int x = 0; x < size; ++x) {
        const double omega = [&] {
          const shared::CameraParameters c = ToSharedCamera(camera);
          return shared::GetCameraPixelSolidAngle(c, shared::ivec2(x, y));
        }();
        for (int k = 0; k < 3; ++k) sum[k] += image.pixels[(static_cast<std::size_t>(y) * size + x) * 3 + k] * omega;
      }
    }
    energies.push_back(convert.Luminance(sum));
  }
  std::vector<double> expected(3, 0.0), t(3);
  for (std::size_t i = 0; i < catalogue->stars().size(); ++i) {
    const glm::dvec3 d = night.frame().ToLocal(catalogue->stars()[i]);
    night.Transmittance(d.z, t);
    for (int c = 0; c < 3; ++c) expected[c] += night.star_irradiance()[i * 3 + c] * t[c];
  }
  EXPECT_NEAR(energies[0], energies[1], 1e-3 * energies[1]);
  EXPECT_NEAR(energies[1], convert.Luminance(expected), 2e-3 * energies[1]);
  // Starlight on the whole sky, seen through the air: of the order of 1e-4 lx in the hemisphere
  // (Roach and Gordon's starlight to V 7.5 is a few 1e-4 lx outside the atmosphere).
  EXPECT_GT(energies[1], 3e-5);
  EXPECT_LT(energies[1], 1e-3);
}

// A catalogue file that is not one: a one-line error naming it.
TEST(Stars, RejectsACorruptCatalogue) {
  const std::filesystem::path folder = std::filesystem::temp_directory_path() / "atmo_stars_corrupt";
  std::filesystem::create_directories(folder);
  std::ofstream(folder / "stars_0_0v0_8.cat", std::ios::binary) << "not a catalogue at all, just text";
  try {
    StarCatalogue::Load(folder);
    ADD_FAILURE() << "a corrupt catalogue was read";
  } catch (const Error& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("stars_0_0v0_8.cat"), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos);
  }
  EXPECT_THROW(StarCatalogue::Load(folder / "missing"), Error);
  std::filesystem::remove_all(folder);
}

}  // namespace
}  // namespace atmo
