// Sky radiance after Hillaire 2020: ray marching of single scattering (true phase functions,
// transmittance to the sun from the table, hard planet shadow) plus the isotropic
// multiple-scattering term from its table; the sky-view table that caches this march for one
// observer and sun; the sun disc; and the lit ground for images. (The aerial-perspective
// volume marches segments with IntegrateScatteredRadiance.)
//
// A view is given by r (observer's distance from the planet centre), mu (cosine of the view
// zenith angle), mu_s (cosine of the sun zenith angle) and nu (cosine of the angle between the
// view and sun directions). Radiance is per unit solar irradiance at the top of the atmosphere.

// Moves an observer outside the atmosphere to where its ray enters it, updating r, mu, mu_s and
// the remaining distance limit. Returns false when the ray misses the atmosphere.
bool MoveToAtmosphereEntry(IN(AtmosphereParameters) atmosphere, INOUT(Number) r, INOUT(Number) mu,
    INOUT(Number) mu_s, Number nu, INOUT(Number) t_limit) {
  if (r <= atmosphere.top_radius) {
    return true;
  }
  Number d = DistanceToAtmosphereEntry(atmosphere, r, mu);
  if (d < 0.0 || d >= t_limit) {
    return false;
  }
  Number r_entry = sqrt(d * d + 2.0 * r * mu * d + r * r);
  mu = ClampCosine((r * mu + d) / r_entry);
  mu_s = ClampCosine((r * mu_s + d * nu) / r_entry);
  r = min(r_entry, atmosphere.top_radius);
  t_limit = t_limit - d;
  return true;
}

// Integrates the scattered radiance along the ray up to the ground, the top of the atmosphere,
// or t_limit, whichever comes first, with `sample_count` steps (quadratic in distance), each integrated
// analytically for the transmittance across it (Hillaire 2020, eq. 11 of the 2015 course notes).
// `transmittance` receives the transmittance over the marched segment.
// For an observer inside the atmosphere, with whether the ray meets the ground given: a table
// whose rows are split into sky and ground halves decides it by the half, not by the sign of a
// rounded mu at the horizon (in float the last sky row's mu can round below the horizon).
// IntegrateScatteredRadianceInsideSteps marches only the steps first_step ... end_step - 1 of the
// `sample_count`, from a transmittance of 1 at the first: a GPU work group splits a ray into
// segments, one per invocation, and weighs each segment's radiance by the transmittances of the
// segments before it.
vec3 IntegrateScatteredRadianceInsideSteps(IN(AtmosphereParameters) atmosphere,
    IN(TransmittanceTexture) transmittance_texture, IN(MultiScatteringTexture) multiple_scattering_texture, Number r,
    Number mu, Number mu_s, Number nu, bool ray_r_mu_intersects_ground, Number t_limit, int sample_count,
    int first_step, int end_step, OUT(vec3) transmittance) {
  transmittance = vec3(1.0);
  Number t_max = min(DistanceToNearestAtmosphereBoundary(atmosphere, r, mu, ray_r_mu_intersects_ground), t_limit);
  Number rayleigh_phase = GetRayleighPhase(atmosphere, nu);
  Number mie_phase = GetMiePhase(atmosphere, nu);
  vec3 radiance = vec3(0.0);
  for (int i = first_step; i < end_step; ++i) {
    // Step i spans [t_max x_i^2, t_max x_{i+1}^2] with x uniform: short steps near the observer,
    // where the density is highest for rays that rise and the transmittance weighs most for all.
    Number x_0 = Number(i) / Number(sample_count);
    Number x_1 = Number(i + 1) / Number(sample_count);
    Number t_0 = t_max * x_0 * x_0;
    Number t_1 = t_max * x_1 * x_1;
    Number dt = t_1 - t_0;
    Number t = 0.5 * (t_0 + t_1);
    Number r_i = sqrt(t * t + 2.0 * r * mu * t + r * r);
    Number mu_s_i = ClampCosine((r * mu_s + t * nu) / r_i);
    MediumSample medium = SampleMedium(atmosphere, r_i);
    vec3 step_transmittance = exp(-medium.extinction * dt);
    vec3 sun_transmittance = GetTransmittanceToSun(atmosphere, transmittance_texture, r_i, mu_s_i);
    vec3 multiple_scattering = GetMultiScattering(atmosphere, multiple_scattering_texture, r_i, mu_s_i);
    vec3 source = sun_transmittance * (medium.rayleigh_scattering * rayleigh_phase + medium.mie_scattering * mie_phase) +
        multiple_scattering * medium.scattering;
    radiance += transmittance * source * IntegrateStep(medium.extinction, step_transmittance, dt);
    transmittance *= step_transmittance;
  }
  return radiance;
}

vec3 IntegrateScatteredRadianceInside(IN(AtmosphereParameters) atmosphere,
    IN(TransmittanceTexture) transmittance_texture, IN(MultiScatteringTexture) multiple_scattering_texture, Number r,
    Number mu, Number mu_s, Number nu, bool ray_r_mu_intersects_ground, Number t_limit, int sample_count,
    OUT(vec3) transmittance) {
  return IntegrateScatteredRadianceInsideSteps(atmosphere, transmittance_texture, multiple_scattering_texture, r, mu,
      mu_s, nu, ray_r_mu_intersects_ground, t_limit, sample_count, 0, sample_count, transmittance);
}

vec3 IntegrateScatteredRadiance(IN(AtmosphereParameters) atmosphere, IN(TransmittanceTexture) transmittance_texture,
    IN(MultiScatteringTexture) multiple_scattering_texture, Number r, Number mu, Number mu_s, Number nu,
    Number t_limit, int sample_count, OUT(vec3) transmittance) {
  transmittance = vec3(1.0);
  if (!MoveToAtmosphereEntry(atmosphere, r, mu, mu_s, nu, t_limit)) {
    return vec3(0.0);
  }
  return IntegrateScatteredRadianceInside(atmosphere, transmittance_texture, multiple_scattering_texture, r, mu, mu_s,
      nu, RayIntersectsGround(atmosphere, r, mu), t_limit, sample_count, transmittance);
}

// Transmittance along the view ray to the top of the atmosphere, 0 where the ray meets the
// ground, for an observer inside or outside the atmosphere.
vec3 GetViewTransmittance(IN(AtmosphereParameters) atmosphere, IN(TransmittanceTexture) transmittance_texture,
    Number r, Number mu) {
  if (r > atmosphere.top_radius) {
    Number d = DistanceToAtmosphereEntry(atmosphere, r, mu);
    if (d < 0.0) {
      return vec3(1.0);
    }
    Number r_entry = sqrt(d * d + 2.0 * r * mu * d + r * r);
    mu = ClampCosine((r * mu + d) / r_entry);
    r = atmosphere.top_radius;
  }
  if (RayIntersectsGround(atmosphere, r, mu)) {
    return vec3(0.0);
  }
  return GetTransmittanceToTopAtmosphereBoundary(atmosphere, transmittance_texture, r, mu);
}

// Radiance of the sun disc seen along the view ray: the limb-darkened disc of angular radius
// alpha whose irradiance at the top of the atmosphere is 1 (sun.glsl), attenuated by the view
// transmittance. Zero outside the disc.
vec3 GetSunDiscRadiance(IN(AtmosphereParameters) atmosphere, IN(TransmittanceTexture) transmittance_texture,
    Number r, Number mu, Number nu) {
  vec3 radiance = GetSunDiscUnattenuatedRadiance(atmosphere, nu);
  if (radiance == vec3(0.0)) {
    return vec3(0.0);
  }
  return GetViewTransmittance(atmosphere, transmittance_texture, r, mu) * radiance;
}

// The sky-view table (Hillaire 2020, section 5.3) for one observer radius: x is the azimuth from
// the sun over the full 360 degrees (texel i centred on 2 pi i / width; the sampler repeats in x),
// y the view zenith with the non-linear latitude of the seed, which puts the horizon, dipping as
// the observer rises, in the middle and samples densely around it:
//   above the horizon  y = 1 - sqrt(1 - theta / theta_h)        over the upper half of the rows,
//   below the horizon  y = sqrt((theta - theta_h) / beta)        over the lower half,
// where theta_h = pi - beta is the zenith angle of the horizon and beta the angle between the
// nadir and the horizon, cos beta = sqrt(r^2 - R^2) / r (pi/2 on the ground, -> 0 far away). Each
// half maps its y in [0, 1] onto its own texel centres (after Bruneton's split of the scattering
// texture), so that bilinear filtering never blends a sky row with a ground row: seen from the
// ground, rays just below the horizon have zero length and rays just above it cross the whole
// atmosphere. The height must be even. A ray exactly along the horizon is a sky ray, as in
// RayIntersectsGround.
Number GetHorizonNadirAngle(IN(AtmosphereParameters) atmosphere, Number r) {
  Number cos_beta = ClampToRange(SafeSqrt((r - atmosphere.bottom_radius) * (r + atmosphere.bottom_radius)) / r, 0.0, 1.0);
  return max(acos(cos_beta), 1e-9);
}

// The mapping with beta = GetHorizonNadirAngle(r) computed once per observer.
vec2 GetSkyViewTextureUvFromBeta(IN(ivec2) texture_size, Number beta, Number mu, Number azimuth) {
  Number zenith_horizon_angle = kPi - beta;
  Number view_zenith = acos(ClampCosine(mu));
  int half_height = texture_size.y / 2;
  Number v;
  if (view_zenith <= zenith_horizon_angle) {
    Number y = 1.0 - SafeSqrt(1.0 - view_zenith / zenith_horizon_angle);
    v = 0.5 * GetTextureCoordFromUnitRange(y, half_height);
  } else {
    Number y = SafeSqrt(min((view_zenith - zenith_horizon_angle) / beta, 1.0));
    v = 0.5 + 0.5 * GetTextureCoordFromUnitRange(y, half_height);
  }
  Number x = azimuth / (2.0 * kPi);
  return vec2(x + 0.5 / Number(texture_size.x), v);
}

vec2 GetSkyViewTextureUvFromViewAngles(IN(AtmosphereParameters) atmosphere, IN(ivec2) texture_size, Number r,
    Number mu, Number azimuth) {
  return GetSkyViewTextureUvFromBeta(texture_size, GetHorizonNadirAngle(atmosphere, r), mu, azimuth);
}

void GetViewAnglesFromSkyViewTextureUv(IN(AtmosphereParameters) atmosphere, IN(ivec2) texture_size, Number r,
    IN(vec2) uv, OUT(Number) mu, OUT(Number) azimuth) {
  Number beta = GetHorizonNadirAngle(atmosphere, r);
  Number zenith_horizon_angle = kPi - beta;
  int half_height = texture_size.y / 2;
  Number view_zenith;
  if (uv.y < 0.5) {
    Number y = ClampToRange(GetUnitRangeFromTextureCoord(2.0 * uv.y, half_height), 0.0, 1.0);
    view_zenith = zenith_horizon_angle * (1.0 - (1.0 - y) * (1.0 - y));
  } else {
    Number y = ClampToRange(GetUnitRangeFromTextureCoord(2.0 * uv.y - 1.0, half_height), 0.0, 1.0);
    view_zenith = zenith_horizon_angle + beta * y * y;
  }
  mu = cos(view_zenith);
  azimuth = (uv.x - 0.5 / Number(texture_size.x)) * 2.0 * kPi;
}

// The per-texel kernel of the sky-view table for an observer at radius r and a sun at zenith
// cosine mu_s (azimuth 0).
// ComputeSkyViewTexelSteps marches the steps first_step ... end_step - 1 only (as
// IntegrateScatteredRadianceInsideSteps), with the transmittance over them.
vec3 ComputeSkyViewTexelSteps(IN(AtmosphereParameters) atmosphere, IN(TransmittanceTexture) transmittance_texture,
    IN(MultiScatteringTexture) multiple_scattering_texture, IN(ivec2) texture_size, IN(vec2) frag_coord, Number r,
    Number mu_s, int sample_count, int first_step, int end_step, OUT(vec3) transmittance) {
  Number mu;
  Number azimuth;
  GetViewAnglesFromSkyViewTextureUv(atmosphere, texture_size, r, frag_coord / vec2(texture_size), mu, azimuth);
  Number nu = SafeSqrt(1.0 - mu * mu) * SafeSqrt(1.0 - mu_s * mu_s) * cos(azimuth) + mu * mu_s;
  return IntegrateScatteredRadianceInsideSteps(atmosphere, transmittance_texture, multiple_scattering_texture, r, mu,
      mu_s, nu, frag_coord.y >= 0.5 * Number(texture_size.y), 1e30, sample_count, first_step, end_step,
      transmittance);
}

vec3 ComputeSkyViewTexel(IN(AtmosphereParameters) atmosphere, IN(TransmittanceTexture) transmittance_texture,
    IN(MultiScatteringTexture) multiple_scattering_texture, IN(ivec2) texture_size, IN(vec2) frag_coord, Number r,
    Number mu_s, int sample_count) {
  vec3 transmittance;
  return ComputeSkyViewTexelSteps(atmosphere, transmittance_texture, multiple_scattering_texture, texture_size,
      frag_coord, r, mu_s, sample_count, 0, sample_count, transmittance);
}

vec3 GetSkyRadianceFromSkyView(IN(AtmosphereParameters) atmosphere, IN(SkyViewTexture) sky_view_texture, Number r,
    Number mu, Number azimuth) {
  vec2 uv = GetSkyViewTextureUvFromViewAngles(atmosphere, textureSize(sky_view_texture, 0), r, mu, azimuth);
  return vec3(texture(sky_view_texture, uv));
}


// Ground lighting, for images (docs/design.md's radiance excludes it; renderers add it). The ground is
// Lambertian with the atmosphere's albedo, lit by the attenuated sun and by the sky.
//
// The sky irradiance of a horizontal ground patch as a function of the sun zenith cosine there,
//   E_sky(mu_s) = integral over the upper hemisphere of L(R, w) cos(theta) dw,
// is a 1D table (x = (mu_s + 1) / 2 on texel centres). Its per-texel kernel integrates the
// ray-marched radiance over `direction_count` directions uniform in z = cos(theta) (each of
// solid angle 2 pi / count) with golden-angle azimuths.
// The sun zenith cosine of the texel at frag_x of the ground-irradiance table.
Number GetGroundIrradianceTexelMuS(int texture_width, Number frag_x) {
  return 2.0 * GetUnitRangeFromTextureCoord(frag_x / Number(texture_width), texture_width) - 1.0;
}

// Direction k of the quadrature below: a Fibonacci lattice of `direction_count` points over the
// upper hemisphere (z up), each standing for 2 pi / direction_count sr.
vec3 GetGroundIrradianceDirection(int k, int direction_count) {
  Number golden_angle = kPi * (3.0 - sqrt(5.0));
  Number z = 1.0 - (Number(k) + 0.5) / Number(direction_count);
  Number phi = Number(k) * golden_angle;
  Number s = SafeSqrt(1.0 - z * z);
  return vec3(s * cos(phi), s * sin(phi), z);
}

// Direction k's term of the quadrature below, z L(R, w_k), for a sun at zenith cosine mu_s; the
// Steps form marches the steps first_step ... end_step - 1 only (IntegrateScatteredRadianceInsideSteps).
// The ground point is inside the atmosphere, and the upward rays miss the ground.
vec3 ComputeGroundIrradianceTermSteps(IN(AtmosphereParameters) atmosphere,
    IN(TransmittanceTexture) transmittance_texture, IN(MultiScatteringTexture) multiple_scattering_texture, Number mu_s,
    int k, int direction_count, int sample_count, int first_step, int end_step, OUT(vec3) transmittance) {
  vec3 sun_direction = vec3(SafeSqrt(1.0 - mu_s * mu_s), 0.0, mu_s);
  vec3 direction = GetGroundIrradianceDirection(k, direction_count);
  Number r = atmosphere.bottom_radius;
  return direction.z * IntegrateScatteredRadianceInsideSteps(atmosphere, transmittance_texture,
      multiple_scattering_texture, r, direction.z, mu_s, dot(direction, sun_direction),
      RayIntersectsGround(atmosphere, r, direction.z), 1e30, sample_count, first_step, end_step, transmittance);
}

vec3 ComputeGroundIrradianceTerm(IN(AtmosphereParameters) atmosphere, IN(TransmittanceTexture) transmittance_texture,
    IN(MultiScatteringTexture) multiple_scattering_texture, Number mu_s, int k, int direction_count,
    int sample_count) {
  vec3 transmittance;
  return ComputeGroundIrradianceTermSteps(atmosphere, transmittance_texture, multiple_scattering_texture, mu_s, k,
      direction_count, sample_count, 0, sample_count, transmittance);
}

// The sum of the terms k = first, first + stride, ... < direction_count (all with (0, 1); see
// SumMultiScatteringRays for the shares of a GPU work group).
vec3 SumGroundIrradianceTerms(IN(AtmosphereParameters) atmosphere, IN(TransmittanceTexture) transmittance_texture,
    IN(MultiScatteringTexture) multiple_scattering_texture, Number mu_s, int first, int stride, int direction_count,
    int sample_count) {
  vec3 sum = vec3(0.0);
  for (int k = first; k < direction_count; k += stride) {
    sum += ComputeGroundIrradianceTerm(atmosphere, transmittance_texture, multiple_scattering_texture, mu_s, k,
        direction_count, sample_count);
  }
  return sum;
}

// The irradiance from the sum of all the terms: each direction stands for 2 pi / count sr.
vec3 GetGroundIrradianceFromSum(IN(vec3) sum, int direction_count) {
  return sum * (2.0 * kPi / Number(direction_count));
}

vec3 ComputeGroundIrradianceTexel(IN(AtmosphereParameters) atmosphere, IN(TransmittanceTexture) transmittance_texture,
    IN(MultiScatteringTexture) multiple_scattering_texture, int texture_width, Number frag_x, int direction_count,
    int sample_count) {
  Number mu_s = GetGroundIrradianceTexelMuS(texture_width, frag_x);
  return GetGroundIrradianceFromSum(SumGroundIrradianceTerms(atmosphere, transmittance_texture,
      multiple_scattering_texture, mu_s, 0, 1, direction_count, sample_count), direction_count);
}

vec3 GetGroundIrradianceFromSky(IN(TransmittanceTexture) ground_irradiance_texture, Number mu_s) {
  ivec2 size = textureSize(ground_irradiance_texture, 0);
  return vec3(texture(ground_irradiance_texture, vec2(GetTextureCoordFromUnitRange(0.5 * mu_s + 0.5, size.x), 0.5)));
}

// Radiance that the ground reflects towards an observer at radius r looking along mu (0 where the
// ray misses the ground), attenuated by the atmosphere in between.
// For an observer inside the atmosphere whose ray meets the ground (given, as above).
vec3 GetGroundRadianceInside(IN(AtmosphereParameters) atmosphere, IN(TransmittanceTexture) transmittance_texture,
    IN(TransmittanceTexture) ground_irradiance_texture, Number r, Number mu, Number mu_s, Number nu) {
  Number d = DistanceToBottomAtmosphereBoundary(atmosphere, r, mu);
  vec3 transmittance = GetTransmittance(atmosphere, transmittance_texture, r, mu, d, true);
  Number mu_s_ground = ClampCosine((r * mu_s + d * nu) / atmosphere.bottom_radius);
  vec3 sun_irradiance = GetTransmittanceToSun(atmosphere, transmittance_texture, atmosphere.bottom_radius, mu_s_ground) *
      max(mu_s_ground, 0.0);
  vec3 sky_irradiance = GetGroundIrradianceFromSky(ground_irradiance_texture, mu_s_ground);
  return transmittance * atmosphere.ground_albedo * (1.0 / kPi) * (sun_irradiance + sky_irradiance);
}

// Radiance that the ground reflects towards an observer at radius r looking along mu (0 where the
// ray misses the ground), attenuated by the atmosphere in between.
vec3 GetGroundRadiance(IN(AtmosphereParameters) atmosphere, IN(TransmittanceTexture) transmittance_texture,
    IN(TransmittanceTexture) ground_irradiance_texture, Number r, Number mu, Number mu_s, Number nu) {
  Number t_limit = 1e30;
  if (!MoveToAtmosphereEntry(atmosphere, r, mu, mu_s, nu, t_limit) || !RayIntersectsGround(atmosphere, r, mu)) {
    return vec3(0.0);
  }
  return GetGroundRadianceInside(atmosphere, transmittance_texture, ground_irradiance_texture, r, mu, mu_s, nu);
}

// The per-texel kernel of the ground part of the sky-view table: the ground radiance of the
// texel's direction (zero above the horizon), for an observer at r and a sun at mu_s.
vec3 ComputeGroundViewTexel(IN(AtmosphereParameters) atmosphere, IN(TransmittanceTexture) transmittance_texture,
    IN(TransmittanceTexture) ground_irradiance_texture, IN(ivec2) texture_size, IN(vec2) frag_coord, Number r,
    Number mu_s) {
  Number mu;
  Number azimuth;
  GetViewAnglesFromSkyViewTextureUv(atmosphere, texture_size, r, frag_coord / vec2(texture_size), mu, azimuth);
  Number nu = SafeSqrt(1.0 - mu * mu) * SafeSqrt(1.0 - mu_s * mu_s) * cos(azimuth) + mu * mu_s;
  if (frag_coord.y < 0.5 * Number(texture_size.y)) {
    return vec3(0.0);  // the sky half
  }
  return GetGroundRadianceInside(atmosphere, transmittance_texture, ground_irradiance_texture, r, mu, mu_s, nu);
}
