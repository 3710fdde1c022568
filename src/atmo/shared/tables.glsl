// Lookups of the exported hillaire tables (`atmo precompute --model hillaire`, docs/tables.md):
// what an engine calls to sample them. cmake/GenerateTablesGlsl.cmake copies these functions, and
// the mapping functions they call, into the one self-contained file build/share/atmo/atmo_tables.glsl
// that an engine includes; the CPU compiles the same text as C++ (tests/hillaire_export_test.cc).
// Only the atmosphere's two radii are read (bottom_radius, top_radius), in the unit of r and of
// the distances (km in the exported manifest).

// Transmittance from radius r along mu to the top of the atmosphere; 0 for a ray that meets the
// ground (the exported 2D table, Bruneton's mapping: GetTransmittanceTextureUvFromRMu).
vec3 atmoTransmittance(IN(AtmosphereParameters) atmosphere, IN(TransmittanceTexture) transmittance_texture, Number r,
    Number mu) {
  if (RayIntersectsGround(atmosphere, r, mu)) {
    return vec3(0.0);
  }
  return GetTransmittanceToTopAtmosphereBoundary(atmosphere, transmittance_texture, r, mu);
}

// Transmittance over the segment of length d from (r, mu), as the ratio of two table values
// (GetTransmittance; rays that meet the ground read the mirrored rays).
vec3 atmoTransmittanceAlong(IN(AtmosphereParameters) atmosphere, IN(TransmittanceTexture) transmittance_texture,
    Number r, Number mu, Number d) {
  return GetTransmittance(atmosphere, transmittance_texture, r, mu, d, RayIntersectsGround(atmosphere, r, mu));
}

// Transmittance towards the sun at zenith cosine mu_s; 0 in the planet's shadow.
vec3 atmoTransmittanceToSun(IN(AtmosphereParameters) atmosphere, IN(TransmittanceTexture) transmittance_texture,
    Number r, Number mu_s) {
  return GetTransmittanceToSun(atmosphere, transmittance_texture, r, mu_s);
}

// Psi_ms(r, mu_s) of the multiple-scattering table (multiply by the scattering coefficient at r
// to get the source term of orders >= 2, per unit solar irradiance).
vec3 atmoMultipleScattering(IN(AtmosphereParameters) atmosphere,
    IN(MultiScatteringTexture) multiple_scattering_texture, Number r, Number mu_s) {
  return GetMultiScattering(atmosphere, multiple_scattering_texture, r, mu_s);
}

// The sky-view table of the exported observer radius r (km) and sun: the radiance per unit solar
// irradiance seen along the unit `view_direction`, both directions in the observer's local frame
// (z up; the sun's azimuth is free, the table is stored relative to it). Multiply by the
// manifest's solar_irradiance for the values of `atmo render --unit relative`.
vec3 atmoSkyView(IN(AtmosphereParameters) atmosphere, IN(SkyViewTexture) sky_view_texture, Number r,
    IN(vec3) view_direction, IN(vec3) sun_direction) {
  return GetSkyRadianceFromSkyView(atmosphere, sky_view_texture, r, view_direction.z,
      GetAzimuthFromSun(view_direction, sun_direction));
}

// The aerial-perspective volume (Hillaire 2020, section 5.4) of one camera: froxel (x, y, z) of a
// W x H x D volume holds, for the camera ray through the screen point ((x + 0.5) / W,
// (y + 0.5) / H) (v = 0 at the image's top row), the in-scattered radiance and the transmittance
// from the camera to the distance (z + 1) / D * max_distance. The continuous slice of a distance:
// s = distance / max_distance * D - 1, clamped to [-1, D - 1]; s = -1 is the camera itself
// (radiance 0, transmittance 1), which has no texel.
Number GetAerialPerspectiveSliceFromDistance(Number distance, Number max_distance, int depth) {
  return ClampToRange(distance / max_distance * Number(depth) - 1.0, -1.0, Number(depth) - 1.0);
}

// The sampler coordinate of a screen point and a distance (slices >= 0; a distance before the
// first slice gets the first slice's w, and atmoAerialPerspective blends it with the camera).
vec3 GetAerialPerspectiveTextureUvwFromScreenDistance(IN(ivec3) texture_size, IN(vec2) screen_uv, Number distance,
    Number max_distance) {
  Number s = GetAerialPerspectiveSliceFromDistance(distance, max_distance, texture_size.z);
  return vec3(screen_uv, (max(s, 0.0) + 0.5) / Number(texture_size.z));
}

// The inverse, for w of slices >= 0: the screen point and the distance.
void GetScreenDistanceFromAerialPerspectiveTextureUvw(IN(ivec3) texture_size, IN(vec3) uvw, Number max_distance,
    OUT(vec2) screen_uv, OUT(Number) distance) {
  screen_uv = vec2(uvw.x, uvw.y);
  distance = (uvw.z * Number(texture_size.z) + 0.5) / Number(texture_size.z) * max_distance;
}

// The in-scattered radiance (per unit solar irradiance) and the transmittance between the camera
// and the point at `distance` seen at `screen_uv`: trilinear between froxels, linear from the
// camera to the first slice. A surface of radiance L_s is seen as L_s * transmittance + radiance.
void atmoAerialPerspective(IN(Texture3D) radiance_texture, IN(Texture3D) transmittance_texture, IN(vec2) screen_uv,
    Number distance, Number max_distance, OUT(vec3) radiance, OUT(vec3) transmittance) {
  ivec3 size = textureSize(radiance_texture, 0);
  Number s = GetAerialPerspectiveSliceFromDistance(distance, max_distance, size.z);
  vec3 uvw = GetAerialPerspectiveTextureUvwFromScreenDistance(size, screen_uv, distance, max_distance);
  Number weight = ClampToRange(s + 1.0, 0.0, 1.0);
  radiance = vec3(texture(radiance_texture, uvw)) * weight;
  transmittance = mix(vec3(1.0), vec3(texture(transmittance_texture, uvw)), weight);
}
