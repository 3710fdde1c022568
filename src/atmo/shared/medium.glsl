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

// The knot coordinate of an altitude in the density table (0 at the ground, kDensityTableSize - 1
// at density_table_top and above).
Number GetDensityTableCoord(IN(AtmosphereParameters) atmosphere, Number altitude) {
  Number x = ClampToRange(altitude / atmosphere.density_table_top, 0.0, 1.0);
  return sqrt(x) * Number(kDensityTableSize - 1);
}

// The four densities from the table: exponential in altitude between knots (their logarithms
// linear in altitude, not in the knot coordinate), with the end knots' values outside.
vec4 GetTabulatedDensities(IN(AtmosphereParameters) atmosphere, Number altitude) {
  Number u = GetDensityTableCoord(atmosphere, altitude);
  Number lower = min(floor(u), Number(kDensityTableSize - 2));
  int i = int(lower);
  // Knot altitudes top * (k / (N - 1))^2 for k = i and i + 1.
  Number scale = atmosphere.density_table_top / Number((kDensityTableSize - 1) * (kDensityTableSize - 1));
  Number h_0 = scale * lower * lower;
  Number h_1 = scale * (lower + 1.0) * (lower + 1.0);
  Number f = ClampToRange((altitude - h_0) / (h_1 - h_0), 0.0, 1.0);
  vec4 l_0 = atmosphere.density_table[i];
  vec4 l_1 = atmosphere.density_table[i + 1];
  vec4 log_density = mix(l_0, l_1, f);
  vec4 density = exp(log_density);
  // Linear in density next to a knot of density 0 (the edge of a layer), as the public profile.
  Number zero = kDensityTableLogZero + 1.0;
  if (min(l_0.x, l_1.x) < zero) density.x = mix(exp(l_0.x), exp(l_1.x), f);
  if (min(l_0.y, l_1.y) < zero) density.y = mix(exp(l_0.y), exp(l_1.y), f);
  if (min(l_0.z, l_1.z) < zero) density.z = mix(exp(l_0.z), exp(l_1.z), f);
  if (min(l_0.w, l_1.w) < zero) density.w = mix(exp(l_0.w), exp(l_1.w), f);
  return density;
}

// Densities (unitless, in [0, 1]) of the Rayleigh, Mie, ozone and water vapour media at radius r
// (water vapour only through the table: 0 with layer profiles).
vec4 GetDensities(IN(AtmosphereParameters) atmosphere, Number r) {
  Number altitude = max(r - atmosphere.bottom_radius, 0.0);
  if (atmosphere.density_table_enabled != 0) return GetTabulatedDensities(atmosphere, altitude);
  return vec4(GetProfileDensity(atmosphere.rayleigh_density, altitude),
              GetProfileDensity(atmosphere.mie_density, altitude),
              GetProfileDensity(atmosphere.absorption_density, altitude), 0.0);
}

// Extinction (per length) from the four densities.
vec3 GetExtinctionFromDensities(IN(AtmosphereParameters) atmosphere, IN(vec4) densities) {
  return atmosphere.rayleigh_extinction * densities.x + atmosphere.mie_extinction * densities.y +
      atmosphere.absorption_extinction * densities.z + atmosphere.water_vapor_extinction * densities.w;
}

struct MediumSample {
  vec3 rayleigh_scattering;  // per length
  vec3 mie_scattering;       // per length
  vec3 scattering;           // per length, all media
  vec3 extinction;           // per length, all media
};

MediumSample SampleMedium(IN(AtmosphereParameters) atmosphere, Number r) {
  vec4 densities = GetDensities(atmosphere, r);
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
