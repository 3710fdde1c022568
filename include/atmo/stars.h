// The stars: a catalogue read from Debian's stellarium-data (Hipparcos and Tycho-2, with NOMAD
// magnitudes; GPL-2+, read at run time, not shipped), the celestial sphere placed over the observer,
// and each star's light per channel (docs/night.md).
//
// To use it:
//   const atmo::StarCatalogue& stars = atmo::StarCatalogue::Default();        // to V 7.5, cached
//   const atmo::CelestialFrame frame = atmo::CelestialFrame::FromDate(jd, 46.5, 7.9);
//   glm::dvec3 local = frame.ToLocal(stars.stars()[0], jd);                    // x east, y north, z up
//
// The format is Stellarium 0.22's binary zone catalogue (its files stars_0_0v0_8.cat to V 6 and
// stars_1_0v0_8.cat to V 7.5): a header, star counts per zone of an icosahedron subdivided
// `level` times, and 28-byte records of positions in each zone's tangent plane (J2000 equatorial),
// proper motions in 0.1 mas/yr, V magnitude and B-V in steps. atmo reads it with its own code from
// the format's description; docs/night.md gives the layout.
#pragma once

#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace atmo {

struct Star {
  glm::dvec3 direction;      // unit, J2000 equatorial (x towards the equinox, z to the pole), at J2000.0
  glm::dvec3 motion_per_yr;  // proper motion: the change of `direction` per Julian year (radians, tangent)
  float v_mag = 0.0f;        // Johnson V
  float b_v = 0.0f;          // B - V colour index
  int hip = 0;               // Hipparcos number, 0 for a Tycho-2 star
};

class StarCatalogue {
 public:
  // Reads the catalogue files in `folder` whose faintest stars reach `limiting_magnitude` (the
  // first two of stellarium-data give V <= 7.5), keeping the stars at most that faint. Throws
  // atmo::Error with one line naming the file for a missing folder or file, a wrong magic number,
  // an unknown record type, a truncated file or a value out of range.
  static StarCatalogue Load(const std::filesystem::path& folder, double limiting_magnitude = 7.5);
  // Where Debian's stellarium-data puts its stars, or $ATMO_STAR_CATALOGUE when set.
  static std::filesystem::path DefaultFolder();
  // Load(DefaultFolder()) once per process (thread-safe); throws as Load.
  static const StarCatalogue& Default();

  const std::vector<Star>& stars() const { return stars_; }
  double limiting_magnitude() const { return limiting_magnitude_; }

 private:
  std::vector<Star> stars_;
  double limiting_magnitude_ = 0.0;
};

// The rotation from J2000 equatorial directions to the observer's local frame (x east, y north,
// z up), with the precession to the date.
class CelestialFrame {
 public:
  // The sky over latitude/longitude (east +) at `julian_day_utc`: precession from J2000 (Meeus
  // eq. 21.3, IAU 1976), the Greenwich mean sidereal time (Meeus eq. 12.4). Nutation and aberration
  // (< 40") are left out. Throws atmo::Error for a non-finite day or a latitude/longitude out of range.
  static CelestialFrame FromDate(double julian_day_utc, double latitude_deg, double longitude_deg);
  // The sky when only the sun's direction is known (no date): the celestial sphere turned so that the
  // sun, at ecliptic longitude 270 degrees (the December solstice), lies along `sun_direction` and
  // the ecliptic's north pole along DefaultEclipticPole (include/atmo/night_sky.h). The stars and
  // the zodiacal light then agree with the sun; the place and date are whatever that rotation means.
  static CelestialFrame FromSun(const glm::dvec3& sun_direction);

  const glm::dmat3& equatorial_to_local() const { return to_local_; }
  double julian_day_utc() const { return julian_day_utc_; }
  // A star's local direction at the frame's date (its proper motion applied from J2000.0).
  glm::dvec3 ToLocal(const Star& star) const;
  // The ecliptic's north pole in the local frame.
  glm::dvec3 EclipticPole() const;

 private:
  glm::dmat3 to_local_{1.0};  // column-major: local = to_local_ * equatorial (J2000)
  double julian_day_utc_ = 2451545.0;
};

// The star's spectral irradiance outside the atmosphere over the sun's (at 1 au), at each of
// `wavelengths_nm`: a black body at the effective temperature of its B-V (Ballesteros 2012,
// EPL 97, 34008), scaled to its V magnitude with V = 0 at 3.631e-11 W m^-2 nm^-1 at 545 nm (Bessell,
// Castelli and Plez 1998, Table A2).
void StarRelativeIrradiance(const Star& star, std::span<const double> wavelengths_nm, std::span<double> out);
// Ballesteros's effective temperature (K) of a B-V, clamped to [-0.4, 2.0].
double StarTemperatureK(double b_v);

}  // namespace atmo
