// The participating media: density profiles and the scattering and extinction coefficients at a
// point, as a function of its distance r from the planet centre.

Number GetLayerDensity(IN(DensityProfileLayer) layer, Number altitude) {
  Number exponential = layer.exp_term == 0.0 ? 0.0 : layer.exp_term * exp(layer.exp_scale * altitude);
  Number density = exponential + layer.linear_term * altitude + layer.constant_term;
  return ClampToRange(density, 0.0, 1.0);
}

Number GetProfileDensity(IN(DensityProfile) profile, Number altitude) {
  return altitude < profile.layers[0].width ? GetLayerDensity(profile.layers[0], altitude)
                                            : GetLayerDensity(profile.layers[1], altitude);
}

// Densities (unitless, in [0, 1]) of the Rayleigh, Mie and absorbing media at radius r.
vec3 GetDensities(IN(AtmosphereParameters) atmosphere, Number r) {
  Number altitude = max(r - atmosphere.bottom_radius, 0.0);
  return vec3(GetProfileDensity(atmosphere.rayleigh_density, altitude),
              GetProfileDensity(atmosphere.mie_density, altitude),
              GetProfileDensity(atmosphere.absorption_density, altitude));
}

// Extinction (per length) from the three densities.
vec3 GetExtinctionFromDensities(IN(AtmosphereParameters) atmosphere, IN(vec3) densities) {
  return atmosphere.rayleigh_extinction * densities.x + atmosphere.mie_extinction * densities.y +
      atmosphere.absorption_extinction * densities.z;
}

struct MediumSample {
  vec3 rayleigh_scattering;  // per length
  vec3 mie_scattering;       // per length
  vec3 scattering;           // per length, all media
  vec3 extinction;           // per length, all media
};

MediumSample SampleMedium(IN(AtmosphereParameters) atmosphere, Number r) {
  vec3 densities = GetDensities(atmosphere, r);
  MediumSample medium;
  medium.rayleigh_scattering = atmosphere.rayleigh_scattering * densities.x;
  medium.mie_scattering = atmosphere.mie_scattering * densities.y;
  medium.scattering = medium.rayleigh_scattering + medium.mie_scattering;
  medium.extinction = GetExtinctionFromDensities(atmosphere, densities);
  return medium;
}

// Integral of exp(-sigma t) over a step of length dt, per unit source: (1 - exp(-sigma dt)) / sigma,
// which tends to dt as sigma -> 0 (Hillaire 2020, energy-conserving integration, eq. 3 of the
// Frostbite course notes). step_transmittance = exp(-sigma dt).
vec3 IntegrateStep(IN(vec3) extinction, IN(vec3) step_transmittance, Number dt) {
  vec3 result;
  result.x = extinction.x > 1e-30 ? (1.0 - step_transmittance.x) / extinction.x : dt;
  result.y = extinction.y > 1e-30 ? (1.0 - step_transmittance.y) / extinction.y : dt;
  result.z = extinction.z > 1e-30 ? (1.0 - step_transmittance.z) / extinction.z : dt;
  return result;
}
