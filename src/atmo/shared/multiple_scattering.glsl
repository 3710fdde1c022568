// The multiple-scattering table of Hillaire 2020 (section 5.5.2): for a point at radius r lit by a
// sun at zenith cosine mu_s, the radiance that orders >= 2 scatter towards any direction, per unit
// scattering coefficient, assuming an isotropic phase function for those orders and that the
// neighbourhood of the point receives the same second-order light:
//   Psi_ms = L_2nd / (1 - f_ms),
//   L_2nd  = 1/(4 pi) * integral over the sphere of L(x, w) dw   (L: single scattering, isotropic
//            phase, plus the sunlight reflected once by the Lambertian ground),
//   f_ms   = 1/(4 pi) * integral over the sphere of integral_0^d sigma_s T dt dw
// and 1 / (1 - f_ms) sums the geometric series of all higher orders.
// The table is indexed by x = (1 + sign(mu_s) sqrt(|mu_s|)) / 2 and y = (r - bottom) / (top - bottom).
// The square root puts the sun-angle texels where Psi_ms changes fastest, around the horizontal
// (mu_s near 0): there Psi_ms falls by orders of magnitude over a few degrees as the sun sets for
// the point and its surroundings, while it is smooth with the sun high. With 32 columns the
// spacing near mu_s = 0 is 0.2 degrees instead of 3.6 (docs/models/hillaire.md measures it).
//
// Gathered orders (option multiple_scattering_orders = K > 1). The series assumes that every point
// around x receives x's own second-order light. Near the ground with a low sun that is far from
// true: the air above is brighter than x, and the table comes out up to 40 % dark at the horizon
// (docs/accuracy.md, "hillaire at the sunset horizon"). With K > 1 the orders are gathered one by
// one, each from the previous order's own table, as Bruneton 2008 gathers his 4D orders, but with
// the isotropic radiance of Hillaire's table:
//   Psi_1(x) = L_2nd(x)
//   Psi_n(x) = 1/(4 pi) * integral over the sphere of [ integral_0^d sigma_s T Psi_{n-1}(y) dt
//              + T(x, g) albedo / pi * E_{n-1}(g) ] dw               (g: the ground the ray meets)
//   E_n(g)   = integral over the upper hemisphere of L_n(g, w) cos(theta) dw (the ground row, r = bottom)
//   Psi_ms   = Psi_1 + ... + Psi_K + Psi_K * f_ms / (1 - f_ms)      (the series for the rest)
// K = 1 is Hillaire 2020's Psi_1 / (1 - f_ms).

Number GetMultiScatteringUnitFromMuS(Number mu_s) {
  Number m = ClampToRange(mu_s, -1.0, 1.0);
  Number root = sqrt(abs(m));
  return ClampToRange(0.5 + 0.5 * (m < 0.0 ? -root : root), 0.0, 1.0);
}

Number GetMuSFromMultiScatteringUnit(Number x_mu_s) {
  Number a = 2.0 * x_mu_s - 1.0;
  return a < 0.0 ? -a * a : a * a;
}

vec2 GetMultiScatteringTextureUvFromRMuS(IN(AtmosphereParameters) atmosphere, IN(ivec2) texture_size,
    Number r, Number mu_s) {
  Number x_mu_s = GetMultiScatteringUnitFromMuS(mu_s);
  Number x_r = ClampToRange((r - atmosphere.bottom_radius) / (atmosphere.top_radius - atmosphere.bottom_radius), 0.0, 1.0);
  return vec2(GetTextureCoordFromUnitRange(x_mu_s, texture_size.x),
              GetTextureCoordFromUnitRange(x_r, texture_size.y));
}

void GetRMuSFromMultiScatteringTextureUv(IN(AtmosphereParameters) atmosphere, IN(ivec2) texture_size,
    IN(vec2) uv, OUT(Number) r, OUT(Number) mu_s) {
  Number x_mu_s = ClampToRange(GetUnitRangeFromTextureCoord(uv.x, texture_size.x), 0.0, 1.0);
  Number x_r = ClampToRange(GetUnitRangeFromTextureCoord(uv.y, texture_size.y), 0.0, 1.0);
  mu_s = GetMuSFromMultiScatteringUnit(x_mu_s);
  r = atmosphere.bottom_radius + x_r * (atmosphere.top_radius - atmosphere.bottom_radius);
}

// The table holds ln(Psi_ms) per channel (ln 1e-30 where Psi_ms is smaller, in the planet's
// shadow), so that bilinear filtering interpolates Psi_ms geometrically: across the terminator it
// falls by orders of magnitude nearly exponentially, which linear interpolation of the values
// turns into errors of several times the value (docs/models/hillaire.md measures both).
vec3 EncodeMultiScattering(IN(vec3) psi_ms) {
  return log(max(psi_ms, vec3(1e-30)));
}

vec3 DecodeMultiScattering(IN(vec3) stored) {
  vec3 psi_ms = exp(stored);
  return vec3(psi_ms.x < 2e-30 ? 0.0 : psi_ms.x, psi_ms.y < 2e-30 ? 0.0 : psi_ms.y, psi_ms.z < 2e-30 ? 0.0 : psi_ms.z);
}

vec3 GetMultiScattering(IN(AtmosphereParameters) atmosphere, IN(MultiScatteringTexture) multiple_scattering_texture,
    Number r, Number mu_s) {
  vec2 uv = GetMultiScatteringTextureUvFromRMuS(atmosphere, textureSize(multiple_scattering_texture, 0), r, mu_s);
  return DecodeMultiScattering(vec3(texture(multiple_scattering_texture, uv)));
}

// Direction k of `count` (even) over the unit sphere (z up). For count == 2 the seed's variant:
// straight up and straight down. Otherwise a Fibonacci lattice of count / 2 points whose azimuths
// are compressed into [0, pi) (uniform over the half sphere y >= 0), and its mirror image in the
// plane y = 0 that holds the sun: uniformly distributed, each point standing for 4 pi / count sr,
// and symmetric, so that mirrored pairs see the same sun. (An 8 x 8 grid of equal-area cells,
// also symmetric, errs five times more against 400 directions: 1.9 % vs 0.37 %.)
vec3 GetMultiScatteringDirection(int k, int count) {
  if (count == 2) {
    return vec3(0.0, 0.0, k == 0 ? 1.0 : -1.0);
  }
  int half_count = count / 2;
  int j = k < half_count ? k : k - half_count;
  Number z = 1.0 - (2.0 * Number(j) + 1.0) / Number(half_count);
  Number golden_angle = kPi * (3.0 - sqrt(5.0));
  Number turns = Number(j) * golden_angle / (2.0 * kPi);
  Number phi = kPi * (turns - floor(turns));
  Number s = SafeSqrt(1.0 - z * z);
  return vec3(s * cos(phi), (k < half_count ? 1.0 : -1.0) * s * sin(phi), z);
}

// Integrates, along the ray from radius r in direction `direction` (z up; the sun is
// `sun_direction`), the isotropically single-scattered light L (with the ground bounce) and the
// transfer term f = integral of sigma_s T dt.
// With `media_phase` the first scattering uses the media's own phase functions (Rayleigh, Mie)
// instead of Hillaire's isotropic one; the orders after it stay isotropic. `ground_transfer`
// (GetGroundTransfer, or 0 for Hillaire 2020's series) adds the ground's reflection of the
// orders >= 2 to f.
// The Steps form marches the steps first_step ... end_step - 1 only, from a throughput of 1, and
// gives the throughput over them; the ground is counted by the segment that ends the ray. A GPU
// work group splits a ray into segments, one per invocation, and weighs each segment by the
// throughputs of the segments before it.
void IntegrateMultiScatteringRaySteps(IN(AtmosphereParameters) atmosphere,
    IN(TransmittanceTexture) transmittance_texture, Number r, IN(vec3) direction, IN(vec3) sun_direction,
    int sample_count, int first_step, int end_step, bool media_phase, IN(vec3) ground_transfer, OUT(vec3) luminance,
    OUT(vec3) transfer, OUT(vec3) throughput) {
  Number mu = direction.z;
  Number mu_s = sun_direction.z;
  Number nu = dot(direction, sun_direction);
  bool ray_r_mu_intersects_ground = RayIntersectsGround(atmosphere, r, mu);
  Number t_max = DistanceToNearestAtmosphereBoundary(atmosphere, r, mu, ray_r_mu_intersects_ground);
  Number rayleigh_phase = media_phase ? GetRayleighPhase(atmosphere, nu) : IsotropicPhaseFunction();
  Number mie_phase = media_phase ? GetMiePhase(atmosphere, nu) : IsotropicPhaseFunction();
  throughput = vec3(1.0);
  luminance = vec3(0.0);
  transfer = vec3(0.0);
  for (int i = first_step; i < end_step; ++i) {
    // Quadratic steps, as in IntegrateScatteredRadiance: short near the point, long far away.
    Number x_0 = Number(i) / Number(sample_count);
    Number x_1 = Number(i + 1) / Number(sample_count);
    Number dt = t_max * (x_1 * x_1 - x_0 * x_0);
    Number t = 0.5 * t_max * (x_0 * x_0 + x_1 * x_1);
    Number r_i = sqrt(t * t + 2.0 * r * mu * t + r * r);
    Number mu_s_i = ClampCosine((r * mu_s + t * nu) / r_i);
    MediumSample medium = SampleMedium(atmosphere, r_i);
    vec3 step_transmittance = exp(-medium.extinction * dt);
    vec3 step_integral = throughput * IntegrateStep(medium.extinction, step_transmittance, dt);
    vec3 sun_transmittance = GetTransmittanceToSun(atmosphere, transmittance_texture, r_i, mu_s_i);
    luminance += step_integral * sun_transmittance *
        (medium.rayleigh_scattering * rayleigh_phase + medium.mie_scattering * mie_phase);
    transfer += step_integral * medium.scattering;
    throughput *= step_transmittance;
  }
  if (ray_r_mu_intersects_ground && end_step == sample_count) {
    // Sunlight reflected by the Lambertian ground at the end of the ray: albedo / pi * E * cos.
    Number r_g = atmosphere.bottom_radius;
    Number mu_s_g = ClampCosine((r * mu_s + t_max * nu) / r_g);
    vec3 sun_transmittance = GetTransmittanceToSun(atmosphere, transmittance_texture, r_g, mu_s_g);
    luminance += throughput * sun_transmittance * atmosphere.ground_albedo * (max(mu_s_g, 0.0) / kPi);
    transfer += throughput * atmosphere.ground_albedo * ground_transfer;
  }
}

void IntegrateMultiScatteringRay(IN(AtmosphereParameters) atmosphere, IN(TransmittanceTexture) transmittance_texture,
    Number r, IN(vec3) direction, IN(vec3) sun_direction, int sample_count, bool media_phase,
    IN(vec3) ground_transfer, OUT(vec3) luminance, OUT(vec3) transfer) {
  vec3 throughput;
  IntegrateMultiScatteringRaySteps(atmosphere, transmittance_texture, r, direction, sun_direction, sample_count, 0,
      sample_count, media_phase, ground_transfer, luminance, transfer, throughput);
}

// The ground's share of the series 1/(1 - f_ms). Under the isotropic unit field of one order, a
// horizontal Lambertian ground receives the irradiance pi F_g with
//   F_g = 1/pi * integral over the upper hemisphere of (integral_0^d sigma_s T dt) cos(theta) dw,
// and reflects the radiance albedo F_g (times the field) towards every direction: the same
// "neighbourhood receives the same light" assumption as Hillaire's f_ms, applied to the ground.
// Estimated with `direction_count` cosine-distributed zenith angles (z = sqrt(1 - (k + 0.5) / n));
// the integrand does not depend on the azimuth.
vec3 GetGroundTransfer(IN(AtmosphereParameters) atmosphere, int direction_count, int sample_count) {
  Number r = atmosphere.bottom_radius;
  vec3 sum = vec3(0.0);
  for (int k = 0; k < direction_count; ++k) {
    Number mu = sqrt(1.0 - (Number(k) + 0.5) / Number(direction_count));
    Number t_max = DistanceToTopAtmosphereBoundary(atmosphere, r, mu);
    vec3 throughput = vec3(1.0);
    for (int i = 0; i < sample_count; ++i) {
      Number x_0 = Number(i) / Number(sample_count);
      Number x_1 = Number(i + 1) / Number(sample_count);
      Number dt = t_max * (x_1 * x_1 - x_0 * x_0);
      Number t = 0.5 * t_max * (x_0 * x_0 + x_1 * x_1);
      MediumSample medium = SampleMedium(atmosphere, sqrt(t * t + 2.0 * r * mu * t + r * r));
      vec3 step_transmittance = exp(-medium.extinction * dt);
      sum += throughput * IntegrateStep(medium.extinction, step_transmittance, dt) * medium.scattering;
      throughput *= step_transmittance;
    }
  }
  return sum / Number(direction_count);
}

// The point and the sun of the texel at frag_coord of the multiple-scattering table: radius r
// and the sun in the plane y = 0 at zenith cosine mu_s.
void GetMultiScatteringTexelPoint(IN(AtmosphereParameters) atmosphere, IN(ivec2) texture_size, IN(vec2) frag_coord,
    OUT(Number) r, OUT(vec3) sun_direction) {
  Number mu_s;
  GetRMuSFromMultiScatteringTextureUv(atmosphere, texture_size, frag_coord / vec2(texture_size), r, mu_s);
  sun_direction = vec3(SafeSqrt(1.0 - mu_s * mu_s), 0.0, mu_s);
}

// Psi_ms from the means over the directions of IntegrateMultiScatteringRay's luminance (L_2nd)
// and transfer (f_ms). Each direction stands for 4 pi / count sr; with the isotropic phase
// 1 / (4 pi) both integrals are plain means. f_ms < 1 always; 0.999 guards the division.
vec3 GetMultiScatteringFromMeans(IN(vec3) second_order, IN(vec3) f_ms) {
  return second_order / (vec3(1.0) - min(f_ms, vec3(0.999)));
}

// The sums of IntegrateMultiScatteringRay's luminance and transfer over the directions k = first,
// first + stride, ... < direction_count, and the sum of the luminance times cos(theta) over the
// upward directions (the irradiance's, GetGatheredGroundIrradianceFromSum): all of them with
// (0, 1); a GPU work group gives each of
// its invocations a share (first = invocation, stride = group size) and adds the partial sums.
// With the sun in the plane y = 0 (GetMultiScatteringTexelPoint), direction k + count / 2, the
// mirror image of direction k, has the same mu and nu and so the same integrals: the first half
// is marched and counted twice (the seed's pair, count 2, is not mirrored), as
// cpu::ComputeMultipleScatteringTable does.
void SumMultiScatteringRays(IN(AtmosphereParameters) atmosphere, IN(TransmittanceTexture) transmittance_texture,
    Number r, IN(vec3) sun_direction, int first, int stride, int direction_count, int sample_count, bool media_phase,
    IN(vec3) ground_transfer, OUT(vec3) luminance_sum, OUT(vec3) transfer_sum, OUT(vec3) irradiance_sum) {
  luminance_sum = vec3(0.0);
  transfer_sum = vec3(0.0);
  irradiance_sum = vec3(0.0);
  bool mirrored = direction_count != 2;
  int marched = mirrored ? direction_count / 2 : direction_count;
  for (int k = first; k < marched; k += stride) {
    vec3 direction = GetMultiScatteringDirection(k, direction_count);
    vec3 luminance;
    vec3 transfer;
    IntegrateMultiScatteringRay(atmosphere, transmittance_texture, r, direction, sun_direction, sample_count,
        media_phase, ground_transfer, luminance, transfer);
    luminance_sum += luminance;
    transfer_sum += transfer;
    irradiance_sum += direction.z > 0.0 ? luminance * direction.z : vec3(0.0);
  }
  if (mirrored) {
    luminance_sum *= 2.0;
    transfer_sum *= 2.0;
    irradiance_sum *= 2.0;
  }
}

// The per-texel kernel of the multiple-scattering table: the stored texel, EncodeMultiScattering(Psi_ms).
vec3 ComputeMultiScatteringTexel(IN(AtmosphereParameters) atmosphere, IN(TransmittanceTexture) transmittance_texture,
    IN(ivec2) texture_size, IN(vec2) frag_coord, int direction_count, int sample_count, bool media_phase,
    IN(vec3) ground_transfer) {
  Number r;
  vec3 sun_direction;
  GetMultiScatteringTexelPoint(atmosphere, texture_size, frag_coord, r, sun_direction);
  vec3 luminance_sum;
  vec3 transfer_sum;
  vec3 irradiance_sum;
  SumMultiScatteringRays(atmosphere, transmittance_texture, r, sun_direction, 0, 1, direction_count, sample_count,
      media_phase, ground_transfer, luminance_sum, transfer_sum, irradiance_sum);
  return EncodeMultiScattering(
      GetMultiScatteringFromMeans(luminance_sum / Number(direction_count), transfer_sum / Number(direction_count)));
}

// The gathered orders (K > 1; see the top of this file).

// The irradiance E of the ground from SumMultiScatteringRays' or SumMultiScatteringGatherRays'
// irradiance sum: each direction stands for 4 pi / count sr.
vec3 GetGatheredGroundIrradianceFromSum(IN(vec3) irradiance_sum, int direction_count) {
  return irradiance_sum * (4.0 * kPi / Number(direction_count));
}

// E_{n-1} of the ground where the sun is at zenith cosine mu_s, from its table (width x 1, the
// columns of the multiple-scattering table, EncodeMultiScattering's logarithms, GL_LINEAR).
vec3 GetGatheredGroundIrradiance(IN(MultiScatteringTexture) ground_irradiance_texture, Number mu_s) {
  Number u = GetTextureCoordFromUnitRange(GetMultiScatteringUnitFromMuS(mu_s),
      textureSize(ground_irradiance_texture, 0).x);
  return DecodeMultiScattering(vec3(texture(ground_irradiance_texture, vec2(u, 0.5))));
}

// L_n(x, w) for n > 1 along the ray from radius r in `direction`: the air lit by the previous
// order's isotropic light Psi_{n-1} (its table, at each sample's own radius and sun), and the ground
// lit by that order's irradiance E_{n-1}. The steps are IntegrateMultiScatteringRay's.
// The Steps form marches a segment, as IntegrateMultiScatteringRaySteps.
vec3 IntegrateMultiScatteringGatherRaySteps(IN(AtmosphereParameters) atmosphere,
    IN(MultiScatteringTexture) previous_order_texture, IN(MultiScatteringTexture) ground_irradiance_texture,
    Number r, IN(vec3) direction, IN(vec3) sun_direction, int sample_count, int first_step, int end_step,
    OUT(vec3) throughput) {
  Number mu = direction.z;
  Number mu_s = sun_direction.z;
  Number nu = dot(direction, sun_direction);
  bool ray_r_mu_intersects_ground = RayIntersectsGround(atmosphere, r, mu);
  Number t_max = DistanceToNearestAtmosphereBoundary(atmosphere, r, mu, ray_r_mu_intersects_ground);
  throughput = vec3(1.0);
  vec3 luminance = vec3(0.0);
  for (int i = first_step; i < end_step; ++i) {
    Number x_0 = Number(i) / Number(sample_count);
    Number x_1 = Number(i + 1) / Number(sample_count);
    Number dt = t_max * (x_1 * x_1 - x_0 * x_0);
    Number t = 0.5 * t_max * (x_0 * x_0 + x_1 * x_1);
    Number r_i = sqrt(t * t + 2.0 * r * mu * t + r * r);
    Number mu_s_i = ClampCosine((r * mu_s + t * nu) / r_i);
    MediumSample medium = SampleMedium(atmosphere, r_i);
    vec3 step_transmittance = exp(-medium.extinction * dt);
    vec3 step_integral = throughput * IntegrateStep(medium.extinction, step_transmittance, dt);
    luminance += step_integral * medium.scattering *
        GetMultiScattering(atmosphere, previous_order_texture, r_i, mu_s_i);
    throughput *= step_transmittance;
  }
  if (ray_r_mu_intersects_ground && end_step == sample_count) {
    Number mu_s_g = ClampCosine((r * mu_s + t_max * nu) / atmosphere.bottom_radius);
    luminance += throughput * atmosphere.ground_albedo / kPi *
        GetGatheredGroundIrradiance(ground_irradiance_texture, mu_s_g);
  }
  return luminance;
}

vec3 IntegrateMultiScatteringGatherRay(IN(AtmosphereParameters) atmosphere,
    IN(MultiScatteringTexture) previous_order_texture, IN(MultiScatteringTexture) ground_irradiance_texture,
    Number r, IN(vec3) direction, IN(vec3) sun_direction, int sample_count) {
  vec3 throughput;
  return IntegrateMultiScatteringGatherRaySteps(atmosphere, previous_order_texture, ground_irradiance_texture, r,
      direction, sun_direction, sample_count, 0, sample_count, throughput);
}

// SumMultiScatteringRays for order n > 1: the sums of IntegrateMultiScatteringGatherRay's
// luminance, and of the luminance times cos(theta) over the upward directions.
void SumMultiScatteringGatherRays(IN(AtmosphereParameters) atmosphere,
    IN(MultiScatteringTexture) previous_order_texture, IN(MultiScatteringTexture) ground_irradiance_texture,
    Number r, IN(vec3) sun_direction, int first, int stride, int direction_count, int sample_count,
    OUT(vec3) luminance_sum, OUT(vec3) irradiance_sum) {
  luminance_sum = vec3(0.0);
  irradiance_sum = vec3(0.0);
  bool mirrored = direction_count != 2;
  int marched = mirrored ? direction_count / 2 : direction_count;
  for (int k = first; k < marched; k += stride) {
    vec3 direction = GetMultiScatteringDirection(k, direction_count);
    vec3 luminance = IntegrateMultiScatteringGatherRay(atmosphere, previous_order_texture, ground_irradiance_texture,
        r, direction, sun_direction, sample_count);
    luminance_sum += luminance;
    irradiance_sum += direction.z > 0.0 ? luminance * direction.z : vec3(0.0);
  }
  if (mirrored) {
    luminance_sum *= 2.0;
    irradiance_sum *= 2.0;
  }
}

// The per-texel kernel of order 1 when orders are gathered: Psi_1 = L_2nd (not divided by
// 1 - f_ms), f_ms, and on the ground row (r = bottom radius) E_1, for the tables of the orders.
void ComputeMultiScatteringFirstOrderTexel(IN(AtmosphereParameters) atmosphere,
    IN(TransmittanceTexture) transmittance_texture, IN(ivec2) texture_size, IN(vec2) frag_coord, int direction_count,
    int sample_count, bool media_phase, IN(vec3) ground_transfer, OUT(vec3) psi, OUT(vec3) f_ms,
    OUT(vec3) ground_irradiance) {
  Number r;
  vec3 sun_direction;
  GetMultiScatteringTexelPoint(atmosphere, texture_size, frag_coord, r, sun_direction);
  vec3 luminance_sum;
  vec3 transfer_sum;
  vec3 irradiance_sum;
  SumMultiScatteringRays(atmosphere, transmittance_texture, r, sun_direction, 0, 1, direction_count, sample_count,
      media_phase, ground_transfer, luminance_sum, transfer_sum, irradiance_sum);
  psi = luminance_sum / Number(direction_count);
  f_ms = transfer_sum / Number(direction_count);
  ground_irradiance = GetGatheredGroundIrradianceFromSum(irradiance_sum, direction_count);
}

// The per-texel kernel of order n > 1: Psi_n, and E_n on the ground row.
void ComputeMultiScatteringGatherTexel(IN(AtmosphereParameters) atmosphere,
    IN(MultiScatteringTexture) previous_order_texture, IN(MultiScatteringTexture) ground_irradiance_texture,
    IN(ivec2) texture_size, IN(vec2) frag_coord, int direction_count, int sample_count, OUT(vec3) psi,
    OUT(vec3) ground_irradiance) {
  Number r;
  vec3 sun_direction;
  GetMultiScatteringTexelPoint(atmosphere, texture_size, frag_coord, r, sun_direction);
  vec3 luminance_sum;
  vec3 irradiance_sum;
  SumMultiScatteringGatherRays(atmosphere, previous_order_texture, ground_irradiance_texture, r, sun_direction, 0, 1,
      direction_count, sample_count, luminance_sum, irradiance_sum);
  psi = luminance_sum / Number(direction_count);
  ground_irradiance = GetGatheredGroundIrradianceFromSum(irradiance_sum, direction_count);
}

// Psi_ms from the sum of the gathered orders Psi_1 + ... + Psi_K, the last one Psi_K, and f_ms:
// Hillaire's series 1 / (1 - f_ms) continues from Psi_K.
vec3 GetMultiScatteringFromOrders(IN(vec3) order_sum, IN(vec3) last_order, IN(vec3) f_ms) {
  return order_sum + last_order * (vec3(1.0) / (vec3(1.0) - min(f_ms, vec3(0.999))) - vec3(1.0));
}
