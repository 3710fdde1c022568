// Atmospheres for tests of the shared math, built directly in the shared struct so that these
// tests do not depend on presets or JSON.
#pragma once

#include "shared/shared.h"

namespace atmo::testing {

inline shared::DensityProfile ExponentialProfile(double scale_height) {
  shared::DensityProfile p{};
  p.layers[1].exp_term = 1.0;
  p.layers[1].exp_scale = -1.0 / scale_height;
  return p;
}

// Earth-like values of the `earth` preset (docs/design.md §3), in metres.
inline shared::AtmosphereParameters EarthLike() {
  shared::AtmosphereParameters a{};
  a.bottom_radius = 6360e3;
  a.top_radius = 6460e3;
  a.rayleigh_density = ExponentialProfile(8000.0);
  a.rayleigh_scattering = shared::vec3(5.802e-6, 13.558e-6, 33.1e-6);
  a.rayleigh_extinction = a.rayleigh_scattering;
  a.rayleigh_phase = shared::kPhaseRayleigh;
  a.mie_density = ExponentialProfile(1200.0);
  a.mie_scattering = shared::vec3(3.996e-6);
  a.mie_extinction = shared::vec3(4.44e-6);
  a.mie_phase = shared::kPhaseCornetteShanks;
  a.mie_g = 0.8;
  // Ozone tent: 0 at 10 km, 1 at 25 km, 0 at 40 km.
  a.absorption_density.layers[0] = {25e3, 0.0, 0.0, 1.0 / 15e3, -2.0 / 3.0};
  a.absorption_density.layers[1] = {0.0, 0.0, 0.0, -1.0 / 15e3, 8.0 / 3.0};
  a.absorption_extinction = shared::vec3(0.65e-6, 1.881e-6, 0.085e-6);
  a.ground_albedo = shared::vec3(0.3);
  a.sun_angular_radius = 0.004675;
  a.wavelength = shared::vec3(680.0, 550.0, 440.0);
  a.sun_limb_darkening = 1;
  for (int i = 0; i < 3; ++i) {
    a.sun_centre_radiance[i] = shared::GetSunDiscCentreRadiance(a.wavelength[i], a.sun_angular_radius, true);
  }
  return a;
}

// A small made-up planet (after Bruneton's tests): ground 1000 m, top 1100 m, constant density,
// so that optical depths have closed forms.
inline shared::AtmosphereParameters SmallHomogeneous() {
  shared::AtmosphereParameters a{};
  a.bottom_radius = 1000.0;
  a.top_radius = 1100.0;
  a.rayleigh_density.layers[1].constant_term = 1.0;
  a.rayleigh_scattering = shared::vec3(1e-3, 2e-3, 4e-3);
  a.rayleigh_extinction = a.rayleigh_scattering;
  a.rayleigh_phase = shared::kPhaseRayleigh;
  a.mie_phase = shared::kPhaseHenyeyGreenstein;
  a.mie_g = 0.5;
  a.ground_albedo = shared::vec3(0.0);
  a.sun_angular_radius = 0.004675;
  a.wavelength = shared::vec3(680.0, 550.0, 440.0);
  a.sun_limb_darkening = 1;
  for (int i = 0; i < 3; ++i) {
    a.sun_centre_radiance[i] = shared::GetSunDiscCentreRadiance(a.wavelength[i], a.sun_angular_radius, true);
  }
  return a;
}

}  // namespace atmo::testing
