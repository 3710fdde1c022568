// The moon: ROLO photometry and the disc (include/atmo/moon.h).
#include "atmo/moon.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "atmo/error.h"
#include "physics/data/rolo_table.h"

namespace atmo {
namespace {

constexpr double kPi = std::numbers::pi;

// ln A of band `b` at phase angle g (equation 10 with zero libration and zero selenographic
// longitude of the sun): g in radians in the polynomial, in degrees in the exponential and cosine
// terms, as Kieffer and Stone write it.
double LogReflectance(int b, double g_deg) {
  const double* row = data::kRolo[b];
  const double g = g_deg * kPi / 180.0;
  const double polynomial = row[1] + g * (row[2] + g * (row[3] + g * row[4]));
  const double opposition = row[8] * std::exp(-g_deg / data::kRoloP1) + row[9] * std::exp(-g_deg / data::kRoloP2) +
                            row[10] * std::cos((g_deg - data::kRoloP3) / data::kRoloP4);
  return polynomial + opposition;
}

bool IsUnit(const glm::dvec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z) && std::abs(glm::length(v) - 1.0) < 1e-6;
}

}  // namespace

double LunarDiskReflectance(double wavelength_nm, double phase_angle_deg) {
  if (!(phase_angle_deg >= 0.0 && phase_angle_deg <= 180.0)) {
    throw Error("the moon's phase angle must be in [0, 180] degrees (got " + std::to_string(phase_angle_deg) + ")");
  }
  // Below the smallest phase angle of the fit the model's opposition term runs away (the literature
  // finds it up to 0.3 mag bright at 0): held at the fit's edge. Only a moon near an eclipse is
  // closer to full than that.
  phase_angle_deg = std::max(phase_angle_deg, kRoloMinPhaseDeg);
  const int last = data::kRoloBandCount - 1;
  if (wavelength_nm <= data::kRolo[0][0]) return std::exp(LogReflectance(0, phase_angle_deg));
  if (wavelength_nm >= data::kRolo[last][0]) return std::exp(LogReflectance(last, phase_angle_deg));
  int b = 0;
  while (data::kRolo[b + 1][0] < wavelength_nm) ++b;
  const double f = (wavelength_nm - data::kRolo[b][0]) / (data::kRolo[b + 1][0] - data::kRolo[b][0]);
  return std::exp((1.0 - f) * LogReflectance(b, phase_angle_deg) + f * LogReflectance(b + 1, phase_angle_deg));
}

Moon::Moon(const glm::dvec3& direction, double phase_angle_deg, double distance_km,
           std::span<const double> wavelengths_nm, const glm::dvec3& sun_direction)
    : direction_(direction), phase_angle_deg_(phase_angle_deg) {
  if (!(phase_angle_deg >= 0.0 && phase_angle_deg <= 180.0)) {
    throw Error("--moon-phase must be in [0, 180] degrees, 0 = full (got " + std::to_string(phase_angle_deg) + ")");
  }
  if (!IsUnit(direction) || !IsUnit(sun_direction)) throw Error("the moon and the sun need unit directions");
  if (!(distance_km >= 3.0e5 && distance_km <= 5.0e5)) {
    throw Error("the moon's distance must be in [300000, 500000] km (got " + std::to_string(distance_km) + ")");
  }
  angular_radius_rad_ = std::asin(kMoonRadiusKm / distance_km);
  // Towards the sun from the moon: at phase angle i from the direction back to the observer, on the
  // side of the sun's place in the sky (include/atmo/moon.h).
  const glm::dvec3 back = -direction;
  glm::dvec3 towards_sun = sun_direction - glm::dot(sun_direction, direction) * direction;
  if (glm::length(towards_sun) < 1e-9) {
    towards_sun = glm::cross(direction, std::abs(direction.z) < 0.9 ? glm::dvec3(0, 0, 1) : glm::dvec3(1, 0, 0));
  }
  towards_sun = glm::normalize(towards_sun);
  const double i = phase_angle_deg * kPi / 180.0;
  sun_from_moon_ = glm::normalize(std::cos(i) * back + std::sin(i) * towards_sun);

  const double scale = data::kMoonSolidAngleSr / kPi * (kMoonReferenceDistanceKm / distance_km) *
                       (kMoonReferenceDistanceKm / distance_km);
  for (double nm : wavelengths_nm) sunlit_irradiance_.push_back(LunarDiskReflectance(nm, phase_angle_deg) * scale);

  // Earthshine (include/atmo/moon.h): the Earth at phase angle pi - i, a Lambert sphere of the
  // apparent albedo p*, lights the disc; the moon returns it at zero phase.
  const double earth_phase = kPi - i;
  const double lambert = (std::sin(earth_phase) + (kPi - earth_phase) * std::cos(earth_phase)) / kPi;
  const double earth_size = kEarthRadiusKm / distance_km;
  const double earthlight = 2.0 / 3.0 * kEarthApparentAlbedo * std::max(lambert, 0.0) * earth_size * earth_size;
  const double disc_solid_angle = 2.0 * kPi * (1.0 - std::cos(angular_radius_rad_));
  for (std::size_t c = 0; c < wavelengths_nm.size(); ++c) {
    earthshine_radiance_.push_back(LunarDiskReflectance(wavelengths_nm[c], 0.0) * earthlight / kPi);
    relative_irradiance_.push_back(sunlit_irradiance_[c] + earthshine_radiance_[c] * disc_solid_angle);
  }

  // The disc's shape integrates to 1: the unnormalised law summed over a fine grid of the disc's
  // tangent plane (solid angle per cell ~ cell area for so small a disc; the grid's error is < 0.1 %
  // at the terminator's edge).
  shape_normalisation_ = 1.0;
  const glm::dvec3 e1 = glm::normalize(glm::cross(direction, std::abs(direction.z) < 0.9 ? glm::dvec3(0, 0, 1)
                                                                                          : glm::dvec3(1, 0, 0)));
  const glm::dvec3 e2 = glm::cross(direction, e1);
  const int n = 400;
  const double t = std::tan(angular_radius_rad_);
  const double cell = 2.0 * t / n;
  double sum = 0.0;
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      const double u = -t + (x + 0.5) * cell;
      const double v = -t + (y + 0.5) * cell;
      const glm::dvec3 ray = direction + u * e1 + v * e2;
      const double length = glm::length(ray);
      // d(omega) = dA cos^3 / 1 on the tangent plane at unit distance.
      sum += DiscShape(ray / length) * cell * cell / (length * length * length);
    }
  }
  shape_normalisation_ = sum > 0.0 ? 1.0 / sum : 0.0;
}

double Moon::DiscShape(const glm::dvec3& view) const {
  const double cos_alpha = glm::dot(view, direction_);
  const double sin_radius = std::sin(angular_radius_rad_);
  if (cos_alpha <= std::cos(angular_radius_rad_)) return 0.0;
  // The ray meets the sphere of unit radius at distance 1 / sin_radius: the point's normal.
  const double distance = 1.0 / sin_radius;
  const double sin2_alpha = std::max(0.0, 1.0 - cos_alpha * cos_alpha);
  const double along = distance * cos_alpha - std::sqrt(std::max(0.0, 1.0 - distance * distance * sin2_alpha));
  const glm::dvec3 normal = glm::normalize(along * view - distance * direction_);
  const double mu = std::max(0.0, -glm::dot(normal, view));
  const double mu0 = glm::dot(normal, sun_from_moon_);
  if (mu0 <= 0.0 || mu + mu0 <= 0.0) return 0.0;
  return shape_normalisation_ * mu0 / (mu0 + mu);
}

void Moon::DiscRadiance(const glm::dvec3& view, std::span<double> out) const {
  const bool on_disc = glm::dot(view, direction_) > std::cos(angular_radius_rad_);
  const double shape = on_disc ? DiscShape(view) : 0.0;
  for (std::size_t c = 0; c < relative_irradiance_.size() && c < out.size(); ++c) {
    out[c] = on_disc ? shape * sunlit_irradiance_[c] + earthshine_radiance_[c] : 0.0;
  }
}

}  // namespace atmo
