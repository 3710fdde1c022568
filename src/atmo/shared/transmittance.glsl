// Transmittance to the top of the atmosphere: direct quadrature, and the 2D lookup table of
// Bruneton 2017 (section 2.3) that Hillaire 2020 uses unchanged.

// Optical depth (per channel, unitless) from radius r along mu to the top of the atmosphere, by the
// trapezoidal rule with `sample_count` intervals in x, where t = t_low + x |x| about the ray's
// lowest point t_low = max(-r mu, 0), x from -sqrt(t_low) to sqrt(d - t_low). The density falls
// roughly exponentially away from the lowest point, so the quadratic substitution puts the
// samples where the integrand varies fastest; one grid over the whole ray keeps the result
// continuous in mu (splitting the ray into two fixed halves made it jump by 4e-4 at mu = 0).
// Measured over all altitudes and zenith angles of the `earth` preset (ozone tent included)
// against 20000 intervals (Transmittance.QuadratureConverges): 40 intervals err by at most
// 2.5e-3 in transmittance (uniform steps: 6e-3).
// This function sums the samples i = first, first + stride, ... <= sample_count: all of them with
// (0, 1). A GPU work group gives each of its invocations a share and adds the partial optical
// depths (the extinction is linear in the densities).
vec3 SumOpticalDepthSamplesToTopAtmosphereBoundary(IN(AtmosphereParameters) atmosphere, Number r, Number mu,
    int sample_count, int first, int stride) {
  Number d = DistanceToTopAtmosphereBoundary(atmosphere, r, mu);
  Number t_low = ClampToRange(-r * mu, 0.0, d);
  Number x_0 = -sqrt(t_low);
  Number dx = (sqrt(d - t_low) - x_0) / Number(sample_count);
  // The integrals of the four densities, combined with the coefficients once at the end.
  vec4 density_integrals = vec4(0.0);
  for (int i = first; i <= sample_count; i += stride) {
    Number x = x_0 + Number(i) * dx;
    Number t = t_low + x * abs(x);
    // Distance from the planet centre to the sample point (law of cosines).
    Number r_i = sqrt(max(t * t + 2.0 * r * mu * t + r * r, 0.0));
    Number weight = (i == 0 || i == sample_count) ? 0.5 : 1.0;
    density_integrals += GetDensities(atmosphere, r_i) * (weight * 2.0 * abs(x));
  }
  return GetExtinctionFromDensities(atmosphere, density_integrals * dx);
}

vec3 ComputeOpticalDepthToTopAtmosphereBoundary(IN(AtmosphereParameters) atmosphere, Number r, Number mu,
    int sample_count) {
  return SumOpticalDepthSamplesToTopAtmosphereBoundary(atmosphere, r, mu, sample_count, 0, 1);
}

vec3 ComputeTransmittanceToTopAtmosphereBoundary(IN(AtmosphereParameters) atmosphere, Number r, Number mu,
    int sample_count) {
  return exp(-ComputeOpticalDepthToTopAtmosphereBoundary(atmosphere, r, mu, sample_count));
}

// Texture coordinates of the unit range [0, 1] that put 0 and 1 on the centres of the first and
// last texels, so that the table holds exact values at its bounds.
// (0.5 / n + x (1 - 1 / n), written with one division.)
Number GetTextureCoordFromUnitRange(Number x, int texture_size) {
  return (0.5 + x * Number(texture_size - 1)) / Number(texture_size);
}

Number GetUnitRangeFromTextureCoord(Number u, int texture_size) {
  return (u * Number(texture_size) - 0.5) / Number(texture_size - 1);
}

// Bruneton's mapping: x_r = rho / H, with rho the distance to the horizon and H its value at the
// top; x_mu = (d - d_min) / (d_max - d_min), with d the distance to the top boundary. It covers the
// rays that do not meet the ground, and samples densely near the horizon.
vec2 GetTransmittanceTextureUvFromRMu(IN(AtmosphereParameters) atmosphere, IN(ivec2) texture_size,
    Number r, Number mu) {
  Number H = sqrt((atmosphere.top_radius - atmosphere.bottom_radius) *
                  (atmosphere.top_radius + atmosphere.bottom_radius));
  Number rho = SafeSqrt((r - atmosphere.bottom_radius) * (r + atmosphere.bottom_radius));
  Number d = DistanceToTopAtmosphereBoundary(atmosphere, r, mu);
  Number d_min = atmosphere.top_radius - r;
  Number d_max = rho + H;
  Number x_mu = (d - d_min) / (d_max - d_min);
  Number x_r = rho / H;
  return vec2(GetTextureCoordFromUnitRange(x_mu, texture_size.x),
              GetTextureCoordFromUnitRange(x_r, texture_size.y));
}

void GetRMuFromTransmittanceTextureUv(IN(AtmosphereParameters) atmosphere, IN(ivec2) texture_size,
    IN(vec2) uv, OUT(Number) r, OUT(Number) mu) {
  Number x_mu = GetUnitRangeFromTextureCoord(uv.x, texture_size.x);
  Number x_r = GetUnitRangeFromTextureCoord(uv.y, texture_size.y);
  Number H = sqrt((atmosphere.top_radius - atmosphere.bottom_radius) *
                  (atmosphere.top_radius + atmosphere.bottom_radius));
  Number rho = H * x_r;
  r = sqrt(rho * rho + atmosphere.bottom_radius * atmosphere.bottom_radius);
  Number d_min = atmosphere.top_radius - r;
  Number d_max = rho + H;
  Number d = d_min + x_mu * (d_max - d_min);
  // Law of cosines on the triangle (centre, point, exit point): top^2 = r^2 + d^2 + 2 r mu d.
  mu = d == 0.0 ? 1.0 : (H * H - rho * rho - d * d) / (2.0 * r * d);
  mu = ClampCosine(mu);
}

// The per-texel kernel of the transmittance table; frag_coord is the texel centre (x + 0.5, y + 0.5).
vec3 ComputeTransmittanceToTopAtmosphereBoundaryTexel(IN(AtmosphereParameters) atmosphere,
    IN(ivec2) texture_size, IN(vec2) frag_coord, int sample_count) {
  Number r;
  Number mu;
  GetRMuFromTransmittanceTextureUv(atmosphere, texture_size, frag_coord / vec2(texture_size), r, mu);
  return ComputeTransmittanceToTopAtmosphereBoundary(atmosphere, r, mu, sample_count);
}

vec3 GetTransmittanceToTopAtmosphereBoundary(IN(AtmosphereParameters) atmosphere,
    IN(TransmittanceTexture) transmittance_texture, Number r, Number mu) {
  vec2 uv = GetTransmittanceTextureUvFromRMu(atmosphere, textureSize(transmittance_texture, 0), r, mu);
  return vec3(texture(transmittance_texture, uv));
}

// Transmittance between the point (r, mu) and the point at distance d along the ray, as the ratio
// of two transmittances to the top (Bruneton 2017, GetTransmittance). For a ray that meets the
// ground both ends are mirrored (mu -> -mu) so that the table is read only above the horizon.
vec3 GetTransmittance(IN(AtmosphereParameters) atmosphere, IN(TransmittanceTexture) transmittance_texture,
    Number r, Number mu, Number d, bool ray_r_mu_intersects_ground) {
  Number r_d = ClampToRange(sqrt(d * d + 2.0 * r * mu * d + r * r), atmosphere.bottom_radius, atmosphere.top_radius);
  Number mu_d = ClampCosine((r * mu + d) / r_d);
  if (ray_r_mu_intersects_ground) {
    return min(GetTransmittanceToTopAtmosphereBoundary(atmosphere, transmittance_texture, r_d, -mu_d) /
               max(GetTransmittanceToTopAtmosphereBoundary(atmosphere, transmittance_texture, r, -mu), vec3(1e-30)),
               vec3(1.0));
  }
  return min(GetTransmittanceToTopAtmosphereBoundary(atmosphere, transmittance_texture, r, mu) /
             max(GetTransmittanceToTopAtmosphereBoundary(atmosphere, transmittance_texture, r_d, mu_d), vec3(1e-30)),
             vec3(1.0));
}

// Transmittance from radius r towards a point sun at zenith cosine mu_s; zero in the planet's
// shadow (a hard shadow, as in Hillaire 2020: the sun is a direction, its disc is not integrated).
vec3 GetTransmittanceToSun(IN(AtmosphereParameters) atmosphere, IN(TransmittanceTexture) transmittance_texture,
    Number r, Number mu_s) {
  if (RayIntersectsGround(atmosphere, r, mu_s)) {
    return vec3(0.0);
  }
  return GetTransmittanceToTopAtmosphereBoundary(atmosphere, transmittance_texture, r, mu_s);
}
