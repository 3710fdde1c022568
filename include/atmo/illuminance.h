// Illuminance from the sun and the sky: what a lux meter reads, from any model.
//
// To use it:
//   auto model = atmo::CreateModel("hillaire", atmo::Preset("earth-spectral"));
//   auto sky = model->View(0.0, atmo::SunDirection(/*elevation_deg=*/60.0, /*azimuth_deg=*/180.0));
//   atmo::Illuminance e = atmo::ComputeIlluminance(*sky, model->parameters());
//   // e.direct_normal_lux, e.diffuse_horizontal_lux, e.global_horizontal_lux
//
// direct: the sun's transmitted irradiance, sum over wavelengths of E_sun(lambda) T(lambda) (T the
// transmittance towards the sun's centre), with the luminous weights of atmo::SpectralConversion.
// diffuse: the scattered radiance of the upper hemisphere, integral of L cos(theta) d(omega) (the
// sun disc excluded, the ground below the horizon not seen), by a midpoint rule in zenith and
// azimuth. night sky: the same integral of the night sky's own light (airglow and zodiacal light,
// include/atmo/night_sky.h) when the settings give one. moon: the same for the moon (its direct
// light through the transmittance towards it, its scattered light from the moon's view, each times
// its relative irradiance). global = diffuse + night sky + direct x cos(sun zenith) (the direct
// part 0 for a sun below the horizon) + the moon's direct horizontal and diffuse.
#pragma once

#include "atmo/model.h"
#include "atmo/moon.h"
#include "atmo/night_sky.h"
#include "atmo/parameters.h"

namespace atmo {

struct Illuminance {
  double direct_normal_lux = 0.0;
  double direct_horizontal_lux = 0.0;
  double diffuse_horizontal_lux = 0.0;
  double night_sky_horizontal_lux = 0.0;  // airglow, zodiacal light and the stars of NightSky::SetStars, attenuated
  // The moon (when the settings give one): its transmitted light and its light scattered by the sky.
  double moon_direct_normal_lux = 0.0;
  double moon_direct_horizontal_lux = 0.0;
  double moon_diffuse_horizontal_lux = 0.0;
  double global_horizontal_lux = 0.0;
  // The same, radiometric, over 360..830 nm, W m^-2.
  double direct_normal_w_m2 = 0.0;
  double diffuse_horizontal_w_m2 = 0.0;
  double night_sky_horizontal_w_m2 = 0.0;
};

struct IlluminanceSettings {
  int zenith_steps = 90;    // 1 degree
  int azimuth_steps = 180;  // 2 degrees
  // The night sky of the same parameters, altitude and sun; none: night_sky_* stay 0. Not owned.
  const NightSky* night_sky = nullptr;
  // The moon and the model's view for a sun in its direction (RadianceTerms::moon): both or neither.
  const Moon* moon = nullptr;
  const SkyView* moon_sky = nullptr;
};

// Throws atmo::Error for step counts outside [2, 4096] or a view whose channels do not match the
// parameters.
Illuminance ComputeIlluminance(const SkyView& sky, const AtmosphereParameters& parameters,
                               const IlluminanceSettings& settings = {});

}  // namespace atmo
