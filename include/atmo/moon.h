// The moon as a second light (docs/night.md): its place from a date and a place (libnova's lunar
// ephemeris) or by hand, its disc irradiance and spectrum from the ROLO lunar photometric model
// (Kieffer and Stone 2005), and its disc as seen, with the phase.
//
// To use it:
//   const atmo::MoonPosition place = atmo::ComputeMoonPosition(jd, 46.5, 7.9);
//   const atmo::Moon moon = atmo::Moon::FromPosition(place, parameters.wavelengths_nm, sun_direction);
//   // moon.relative_irradiance()[c]: the moon's irradiance over the sun's at channel c
//
// Moonlight through the models. Every model is linear in its source: the sky lit by the moon is the
// model's sky for a sun in the moon's direction times the moon's irradiance over the sun's, per
// channel (relative_irradiance). The renderers add it through RadianceTerms::moon (a SkyView made
// for the moon's direction), and the planet's shadow, the transmittance and the lit ground come
// with it as they come with the sun.
//
// Photometry. Kieffer and Stone 2005 (AJ 129, 2887), equations 8 and 10 with Table 4 (the ROLO
// model 311g): the disk-equivalent reflectance A(lambda, g) of the moon at phase angle g, in 32
// bands from 350 to 2384 nm, from which the irradiance at the Earth is E = A Omega_M E_sun / pi,
// with Omega_M = 6.4177e-5 sr the moon's solid angle at 384 400 km. The opposition surge (the
// brightening within a few degrees of full moon) is its exp(-g / 4.06 degrees) term. The
// libration terms are taken at 0 (mean libration) and the selenographic longitude of the sun at 0,
// which averages the waxing and waning moon (their difference, the b-terms, is up to ~4 % at
// quarter). The fit covers 1.55 to 97 degrees of phase; below 1.55 degrees, where its opposition
// term extrapolates up to ~0.3 mag too bright, the reflectance is held at its 1.55-degree value.
//
// Earthshine. The sunlit Earth lights the whole disc, the night side included, from almost the
// observer's direction (the Earth-moon-observer angle is under a degree). Its irradiance at the
// moon over the sun's is (2/3) p* Phi(alpha_E) (R_E / d)^2: a Lambert sphere of the Earth's
// apparent albedo p* = 0.30, the value of the earthshine measurements that define it (Goode et al.
// 2001, GRL 28, 1671; Qiu et al. 2003, JGR 108, 4709, find it varying by about +-20 % with the
// season, the clouds and the phase), at the Earth's phase angle alpha_E = 180 degrees - the moon's,
// with Phi(a) = (sin a + (pi - a) cos a) / pi. The moon returns it as the ROLO reflectance at zero
// phase (the opposition surge included), uniformly over the disc, with the sun's spectrum (the
// Earth's bluer reflectance is left out).
#pragma once

#include <span>
#include <vector>

#include <glm/glm.hpp>

namespace atmo {

// The smallest phase angle of the ROLO fit (degrees); LunarDiskReflectance holds its value below.
inline constexpr double kRoloMinPhaseDeg = 1.55;
// The moon's mean distance of the ROLO model (km) and its radius (km).
inline constexpr double kMoonReferenceDistanceKm = 384400.0;
inline constexpr double kMoonRadiusKm = 1737.4;
inline constexpr double kEarthRadiusKm = 6371.0;
inline constexpr double kEarthApparentAlbedo = 0.30;  // p* of the earthshine measurements (above)

struct MoonPosition {
  double elevation_deg = 0.0;      // topocentric, geometric (no refraction), of the centre
  double azimuth_deg = 0.0;        // compass: 0 north, 90 east
  double phase_angle_deg = 0.0;    // sun-moon-observer angle: 0 full, 180 new
  double distance_km = kMoonReferenceDistanceKm;  // from the observer
};

// The moon at `julian_day_utc` for an observer at `latitude_deg`, `longitude_deg` (east +):
// libnova's ELP 2000-82 lunar ephemeris (Meeus ch. 47) in Terrestrial Time, the topocentric
// parallax of the observer (up to 1 degree), and the horizontal place as ComputeSunPosition gives
// the sun's. Throws atmo::Error as ComputeSunPosition does.
MoonPosition ComputeMoonPosition(double julian_day_utc, double latitude_deg, double longitude_deg);

// The ROLO disk-equivalent reflectance at `wavelength_nm` (ln A linear in wavelength between the
// model's bands, held beyond them) and phase angle `phase_angle_deg` in [0, 180].
double LunarDiskReflectance(double wavelength_nm, double phase_angle_deg);

class Moon {
 public:
  // A moon along `direction` (unit, local frame) at `phase_angle_deg` in [0, 180] and
  // `distance_km`, for the channels at `wavelengths_nm`; `sun_direction` (unit) orients the lit
  // side of the disc: the bright limb faces the sun's place in the sky. Throws atmo::Error for a
  // phase outside [0, 180], a non-unit direction or a distance outside [3.0e5, 5.0e5] km.
  Moon(const glm::dvec3& direction, double phase_angle_deg, double distance_km, std::span<const double> wavelengths_nm,
       const glm::dvec3& sun_direction);

  const glm::dvec3& direction() const { return direction_; }
  double phase_angle_deg() const { return phase_angle_deg_; }
  double angular_radius_rad() const { return angular_radius_rad_; }
  // Per channel: the moon's irradiance at the top of the atmosphere over the sun's (at 1 au) at
  // the channel's wavelength: the sunlit disc's A Omega_M / pi (384 400 km / distance)^2 plus the
  // earthshine's radiance times the disc's solid angle. Scales the moonlit sky.
  const std::vector<double>& relative_irradiance() const { return relative_irradiance_; }
  // Per channel: the earthshine's radiance over the whole disc (sr^-1 per unit solar irradiance).
  const std::vector<double>& earthshine_radiance() const { return earthshine_radiance_; }

  // The disc's radiance along `view` per unit solar irradiance, unattenuated, per channel: 0 off
  // the disc; the earthshine everywhere on it; on the lit side also the sunlight by the
  // Lommel-Seeliger law mu0 / (mu0 + mu) of the lunar surface (no limb darkening at full moon),
  // normalised so that the disc's irradiance is relative_irradiance() exactly.
  void DiscRadiance(const glm::dvec3& view, std::span<double> out) const;
  // The sunlit part's shape for one channel's scale 1 (sr^-1), which integrates to 1.
  double DiscShape(const glm::dvec3& view) const;

 private:
  glm::dvec3 direction_;
  glm::dvec3 sun_from_moon_;  // unit: towards the sun, seen from the moon
  double phase_angle_deg_;
  double angular_radius_rad_;
  double shape_normalisation_ = 1.0;  // 1 / integral over the disc of the unnormalised law
  std::vector<double> sunlit_irradiance_;  // per channel: the sunlit part's share of relative_irradiance_
  std::vector<double> earthshine_radiance_;
  std::vector<double> relative_irradiance_;
};

}  // namespace atmo
