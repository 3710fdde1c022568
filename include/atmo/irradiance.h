// Irradiance on any plane from any model's sky: what a pyranometer, a pyrheliometer or a solar
// panel receives, split into the components daylighting and solar-energy tools use. Integrated from
// the sky's radiance itself (no transposition model such as Perez or Hay-Davies).
//
// To use it:
//   auto model = atmo::CreateModel("source4d", atmo::Preset("us-standard"));
//   auto sky = model->View(0.0, atmo::SunDirection(/*elevation_deg=*/40.0, /*azimuth_deg=*/180.0));
//   const atmo::Plane planes[] = {atmo::Plane::Horizontal(), {/*tilt_deg=*/35.0, /*azimuth_deg=*/180.0}};
//   atmo::IrradianceResult e = atmo::ComputeIrradiance(*sky, model->parameters(), planes);
//   atmo::SpectralConversion convert(model->parameters().wavelengths_nm);
//   double ghi_lux = convert.Luminance(e.planes[0].Global());
//
// Units: like the model's radiance, per unit solar irradiance at the top of the atmosphere, one
// value per channel, times IrradianceSettings::sun_scale (the inverse square of the Earth-sun
// distance in au for a dated sun). atmo::SpectralConversion turns a component into lux
// (Luminance), W m^-2 over 360-830 nm (Radiance) or W m^-2 nm^-1 per channel (SpectralRadiance).
//
// The components of a plane whose unit normal is n, for a sun in direction s (docs/daylighting.md):
// - direct: the sun disc's transmitted irradiance T(s) max(0, n.s), 0 for a sun below the horizon;
// - circumsolar: the sky's radiance within circumsolar_half_angle_deg of the sun's centre (above
//   the horizon), integral of L max(0, n.v) d(omega): the aureole that a pyrheliometer's field of
//   view (2.5 degrees half-angle, WMO) counts as direct light;
// - sky_diffuse: the same integral over the rest of the sky above the horizon;
// - ground_reflected: a horizontal Lambertian ground of the parameters' albedo, lit by the global
//   horizontal irradiance G_h (direct + circumsolar + sky diffuse), has radiance albedo G_h / pi;
//   seen below the horizon by the plane, it gives albedo G_h (1 - cos(tilt)) / 2. The air between
//   the plane and the ground is neglected (an observer near the ground).
#pragma once

#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "atmo/model.h"
#include "atmo/parameters.h"
#include "atmo/sky_patches.h"

namespace atmo {

struct Plane {
  // The angle between the plane's normal and the zenith, in [0, 180] (0 horizontal facing up, 90
  // vertical, 180 facing down), and the compass azimuth the normal leans towards (0 north, 90 east).
  double tilt_deg = 0.0;
  double azimuth_deg = 180.0;
  // A plane that faces the sun whatever its position (a two-axis tracker, a pyrheliometer's
  // aperture); tilt and azimuth are then ignored.
  bool tracks_sun = false;

  static Plane Horizontal() { return {}; }
  static Plane FacingSun() { return {0.0, 0.0, true}; }
  // The plane's unit normal for a sun in `sun_direction` (local frame, x east, y north, z up).
  glm::dvec3 Normal(const glm::dvec3& sun_direction) const;
};

struct IrradianceComponents {
  std::vector<double> direct;  // per channel
  std::vector<double> circumsolar;
  std::vector<double> sky_diffuse;
  std::vector<double> ground_reflected;
  // direct + circumsolar + sky_diffuse + ground_reflected, per channel.
  std::vector<double> Global() const;
  // circumsolar + sky_diffuse + ground_reflected: everything but the sun disc.
  std::vector<double> Diffuse() const;
};

struct IrradianceSettings {
  // The hemisphere's midpoint grid (the cells near the sun are refined further).
  int zenith_steps = 90;    // 1 degree
  int azimuth_steps = 180;  // 2 degrees
  // The circumsolar region's half-angle around the sun's centre, in [0, 10] degrees; 0: none (all
  // sky light is sky_diffuse).
  double circumsolar_half_angle_deg = 2.5;
  // Grid cells within reach of the circumsolar cone are split into this many sub-cells per side,
  // in [1, 64], so that the cone's edge and the aureole are resolved.
  int circumsolar_subdivisions = 16;
  // Multiplies every component: 1 / d^2 for an Earth-sun distance d in au (SunPosition::distance_au).
  double sun_scale = 1.0;
  // Sky patches (include/atmo/sky_patches.h): when given, the sky is sampled on each patch split
  // into patch_samples x patch_samples cells (the polar cap into patch_samples rings of 6 x
  // patch_samples) instead of the zenith-azimuth grid, and IrradianceResult::patch_radiance holds
  // each patch's mean radiance. Not owned.
  const SkyPatches* patches = nullptr;
  int patch_samples = 3;  // in [1, 16]
};

struct IrradianceResult {
  // The sun disc's transmitted irradiance on a plane facing it, per channel: DNI without the
  // circumsolar light (times sun_scale).
  std::vector<double> direct_normal;
  // One entry per requested plane, in order.
  std::vector<IrradianceComponents> planes;
  // With IrradianceSettings::patches: the mean radiance of each patch (the sun disc excluded, the
  // aureole included), channel_count() values per patch, times sun_scale.
  std::vector<double> patch_radiance;
};

// Throws atmo::Error for step counts outside [2, 4096], settings outside their ranges, a tilt
// outside [0, 180] or a non-finite plane angle, or a view whose channels do not match the
// parameters.
IrradianceResult ComputeIrradiance(const SkyView& sky, const AtmosphereParameters& parameters,
                                   std::span<const Plane> planes, const IrradianceSettings& settings = {});

}  // namespace atmo
