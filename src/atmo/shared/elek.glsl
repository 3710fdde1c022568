// The precomputed scattering table of the Atmosphere Plus seed (after Elek 2009, "Rendering
// Parametrizable Planetary Atmospheres with Multiple Scattering in Real-Time"): a 3D table
// I(h, cos phi, cos delta) over altitude, view zenith and sun zenith that holds the *factored*
// scattered light, Rayleigh per channel and Mie, so that the renderer applies the phase function
// of nu = cos(view, sun) (docs/design.md §2) and the sun's irradiance itself:
//   L(h, mu, mu_s, nu) = p_R(nu) I_R(h, mu, mu_s) + p_M(nu) I_M(h, mu, mu_s).
// With phase functions normalised to 1 (ours), the seed's F beta / (4 pi) is p beta, so
//   I^(1)_c(P0, V) = int_Pa^Pb sigma_c(P) T(P, Pc) T(P, Pa) ds                (c = R, M)
//   G^(k)_c(P, V)  = int_4pi p_c(dot(w, V)) I^(k)_c(P, w) dw                   (the gather)
//   I^(k+1)_c(P0,V)= int_Pa^Pb sigma_c(P) G^(k)_c(P, V) T(P, Pa) ds
// where sigma_c is the scattering coefficient at P, Pc the exit point towards the sun (a sample
// whose sun ray meets the ground contributes nothing: the seed's P_c rule), and I(P, w) inside
// the gather is read from the previous order's table at (h_P, mu_w, mu_s_P), ignoring the view-sun
// azimuth the table does not have. With that read the gather depends only on (h, mu_V, mu_s): it
// is the row-by-row product of the table with a matrix of azimuth-integrated phase weights
// (ComputeElekGatherWeightTexel), which is how the CPU evaluates it.
//
// Textures: `Texture3D` (GL: sampler3D with GL_LINEAR, clamp to edge) holds the Rayleigh part in
// one texture and the Mie part in another; Texture2D holds the transmittance table.

// Table parameterisations (the seed's section 2.4).
const int kElekMappingLinear = 0;     // u = h / H_a, v = (mu + 1) / 2, w = (mu_s + 1) / 2
const int kElekMappingNonLinear = 1;  // u = sqrt(h / H_a), v = 0.5 (1 + sign(mu) |mu|^(1/3)), w likewise

// Step distributions of the ray integrals (trapezoidal rule on N + 1 nodes).
const int kElekStepsQuadratic = 0;  // t_i = t_max (i / N)^2: short steps near the observer
const int kElekStepsUniform = 1;    // t_i = t_max i / N

Number ElekSignedCubeRoot(Number x) {
  Number root = pow(abs(x), 1.0 / 3.0);
  return x < 0.0 ? -root : root;
}

// (h, mu, mu_s) -> (u, v, w) in [0, 1]^3. h is the altitude above the ground (length).
vec3 GetElekUvwFromHMuMuS(IN(AtmosphereParameters) atmosphere, int mapping, Number h, Number mu, Number mu_s) {
  Number x_h = ClampToRange(h / (atmosphere.top_radius - atmosphere.bottom_radius), 0.0, 1.0);
  mu = ClampCosine(mu);
  mu_s = ClampCosine(mu_s);
  if (mapping == kElekMappingLinear) {
    return vec3(x_h, 0.5 * (mu + 1.0), 0.5 * (mu_s + 1.0));
  }
  return vec3(sqrt(x_h), 0.5 * (1.0 + ElekSignedCubeRoot(mu)), 0.5 * (1.0 + ElekSignedCubeRoot(mu_s)));
}

// The inverse: h = u^2 H_a, mu = (2v - 1)^3, mu_s = (2w - 1)^3 for the non-linear mapping.
void GetElekHMuMuSFromUvw(IN(AtmosphereParameters) atmosphere, int mapping, IN(vec3) uvw, OUT(Number) h,
    OUT(Number) mu, OUT(Number) mu_s) {
  Number height = atmosphere.top_radius - atmosphere.bottom_radius;
  vec3 c = vec3(ClampToRange(uvw.x, 0.0, 1.0), ClampToRange(uvw.y, 0.0, 1.0), ClampToRange(uvw.z, 0.0, 1.0));
  if (mapping == kElekMappingLinear) {
    h = c.x * height;
    mu = 2.0 * c.y - 1.0;
    mu_s = 2.0 * c.z - 1.0;
    return;
  }
  h = c.x * c.x * height;
  Number a = 2.0 * c.y - 1.0;
  Number b = 2.0 * c.z - 1.0;
  mu = a * a * a;
  mu_s = b * b * b;
}

// The seed's texel positions: texel (x, y, z) of a W x H x D table sits at
// (u, v, w) = (x / (W - 1), y / (H - 1), z / (D - 1)), so the first and last texels hold the bounds.
vec3 GetElekUvwFromTexel(IN(ivec3) texture_size, IN(ivec3) texel) {
  return vec3(Number(texel.x) / Number(texture_size.x - 1), Number(texel.y) / Number(texture_size.y - 1),
              Number(texel.z) / Number(texture_size.z - 1));
}

// The GL sampler coordinate that reads (u, v, w) with texels placed as above: texel x has its
// centre at (x + 0.5) / W, so u = x / (W - 1) maps to (u (W - 1) + 0.5) / W.
vec3 GetElekTextureCoordFromUvw(IN(ivec3) texture_size, IN(vec3) uvw) {
  return vec3(GetTextureCoordFromUnitRange(uvw.x, texture_size.x), GetTextureCoordFromUnitRange(uvw.y, texture_size.y),
              GetTextureCoordFromUnitRange(uvw.z, texture_size.z));
}

vec3 GetElekTableValue(IN(AtmosphereParameters) atmosphere, IN(Texture3D) table, int mapping, Number h, Number mu,
    Number mu_s) {
  vec3 uvw = GetElekUvwFromHMuMuS(atmosphere, mapping, h, mu, mu_s);
  return vec3(texture(table, GetElekTextureCoordFromUvw(textureSize(table, 0), uvw)));
}

// Node i (0..N) of a ray of length t_max.
Number GetElekNodeDistance(int steps, Number t_max, int i, int sample_count) {
  Number x = Number(i) / Number(sample_count);
  return steps == kElekStepsUniform ? t_max * x : t_max * x * x;
}

// Trapezoidal weight of node i: half of each adjacent step.
Number GetElekNodeWeight(int steps, Number t_max, int i, int sample_count) {
  Number t_before = i > 0 ? GetElekNodeDistance(steps, t_max, i - 1, sample_count)
                          : GetElekNodeDistance(steps, t_max, 0, sample_count);
  Number t_after = i < sample_count ? GetElekNodeDistance(steps, t_max, i + 1, sample_count)
                                    : GetElekNodeDistance(steps, t_max, sample_count, sample_count);
  return 0.5 * (t_after - t_before);
}

// What a node of the view ray carries that does not depend on the sun.
struct ElekRayNode {
  Number t;              // distance from the observer (length)
  Number weight;         // trapezoidal weight (length)
  Number r;              // distance from the planet centre
  Number mu;             // cosine of the view zenith angle at the node
  vec4 densities;        // Rayleigh, Mie, ozone, water vapour
  vec3 extinction;       // per length
};

ElekRayNode GetElekRayNode(IN(AtmosphereParameters) atmosphere, int steps, Number r, Number mu, Number t_max, int i,
    int sample_count) {
  ElekRayNode node;
  node.t = GetElekNodeDistance(steps, t_max, i, sample_count);
  node.weight = GetElekNodeWeight(steps, t_max, i, sample_count);
  node.r = sqrt(max(node.t * node.t + 2.0 * r * mu * node.t + r * r, 0.0));
  // The last node of a ray that meets the ground is on it. The law of cosines above cancels to R
  // there, off by ~1 m in float (km): a ground node would then see a sun down to ~6e-4 below its
  // horizon that double (off by ~1e-9 m) shadows, where Mie is densest (the GL tables differed by
  // up to 15x in such texels). Exact R gives both backends the P_c rule of the true ground point.
  if (i == sample_count && RayIntersectsGround(atmosphere, r, mu)) {
    node.r = atmosphere.bottom_radius;
  }
  node.mu = ClampCosine((r * mu + node.t) / max(node.r, 1e-30));
  node.densities = GetDensities(atmosphere, node.r);
  node.extinction = GetExtinctionFromDensities(atmosphere, node.densities);
  return node;
}

// Optical depth from the observer to node i given that to node i - 1: the trapezoidal rule on
// the same nodes (the view transmittance is integrated along the march, not read from a table).
vec3 AccumulateElekOpticalDepth(IN(vec3) previous_depth, IN(ElekRayNode) previous, IN(ElekRayNode) node) {
  return previous_depth + 0.5 * (previous.extinction + node.extinction) * (node.t - previous.t);
}

// Sun zenith cosine at a node (the sun is a direction: r mu_s + t nu, over r_i).
Number GetElekNodeSunCosine(Number r, Number mu_s, Number nu, IN(ElekRayNode) node) {
  return ClampCosine((r * mu_s + node.t * nu) / max(node.r, 1e-30));
}

// The canonical form of the seed: view and sun in one vertical plane on the same side (azimuth
// 0), so nu = cos(phi - delta).
Number GetElekCanonicalNu(Number mu, Number mu_s) {
  return mu * mu_s + SafeSqrt(1.0 - mu * mu) * SafeSqrt(1.0 - mu_s * mu_s);
}

// The view ray of a texel: observer radius r, view cosine mu, sun cosine mu_s, length t_max.
void GetElekTexelRay(IN(AtmosphereParameters) atmosphere, int mapping, IN(ivec3) texture_size, IN(ivec3) texel,
    OUT(Number) r, OUT(Number) mu, OUT(Number) mu_s, OUT(Number) t_max) {
  Number h;
  GetElekHMuMuSFromUvw(atmosphere, mapping, GetElekUvwFromTexel(texture_size, texel), h, mu, mu_s);
  r = atmosphere.bottom_radius + h;
  t_max = DistanceToNearestAtmosphereBoundary(atmosphere, r, mu, RayIntersectsGround(atmosphere, r, mu));
}

// Single scattering, factored (I^(1)_R per channel, I^(1)_M per channel), of texel `texel`.
void ComputeElekSingleScatteringTexel(IN(AtmosphereParameters) atmosphere,
    IN(TransmittanceTexture) transmittance_texture, int mapping, int steps, IN(ivec3) texture_size, IN(ivec3) texel,
    int sample_count, OUT(vec3) rayleigh, OUT(vec3) mie) {
  Number r;
  Number mu;
  Number mu_s;
  Number t_max;
  GetElekTexelRay(atmosphere, mapping, texture_size, texel, r, mu, mu_s, t_max);
  Number nu = GetElekCanonicalNu(mu, mu_s);
  vec3 rayleigh_sum = vec3(0.0);
  vec3 mie_sum = vec3(0.0);
  vec3 optical_depth = vec3(0.0);
  ElekRayNode previous = GetElekRayNode(atmosphere, steps, r, mu, t_max, 0, sample_count);
  for (int i = 0; i <= sample_count; ++i) {
    ElekRayNode node = GetElekRayNode(atmosphere, steps, r, mu, t_max, i, sample_count);
    if (i > 0) optical_depth = AccumulateElekOpticalDepth(optical_depth, previous, node);
    // P_c rule: GetTransmittanceToSun is 0 where the sun ray from the node meets the ground.
    vec3 sun = GetTransmittanceToSun(atmosphere, transmittance_texture, node.r,
                                     GetElekNodeSunCosine(r, mu_s, nu, node));
    vec3 light = sun * exp(-optical_depth) * node.weight;
    rayleigh_sum += light * node.densities.x;
    mie_sum += light * node.densities.y;
    previous = node;
  }
  rayleigh = rayleigh_sum * atmosphere.rayleigh_scattering;
  mie = mie_sum * atmosphere.mie_scattering;
}

// Order k >= 2 of texel `texel` from the gather tables of order k - 1 (one pair per azimuth
// slice: the gather tables of the seed's rebuild have none and are passed twice). At a node of
// the canonical ray the view and the sun stay in one vertical plane, on the same side (slice 0)
// or on opposite sides (slice pi) of the local zenith.
void ComputeElekMultipleScatteringTexel(IN(AtmosphereParameters) atmosphere, IN(Texture3D) gather_rayleigh_0,
    IN(Texture3D) gather_mie_0, IN(Texture3D) gather_rayleigh_pi, IN(Texture3D) gather_mie_pi, int mapping,
    int steps, IN(ivec3) texture_size, IN(ivec3) texel, int sample_count, OUT(vec3) rayleigh, OUT(vec3) mie) {
  Number r;
  Number mu;
  Number mu_s;
  Number t_max;
  GetElekTexelRay(atmosphere, mapping, texture_size, texel, r, mu, mu_s, t_max);
  Number nu = GetElekCanonicalNu(mu, mu_s);
  vec3 rayleigh_sum = vec3(0.0);
  vec3 mie_sum = vec3(0.0);
  vec3 optical_depth = vec3(0.0);
  ElekRayNode previous = GetElekRayNode(atmosphere, steps, r, mu, t_max, 0, sample_count);
  for (int i = 0; i <= sample_count; ++i) {
    ElekRayNode node = GetElekRayNode(atmosphere, steps, r, mu, t_max, i, sample_count);
    if (i > 0) optical_depth = AccumulateElekOpticalDepth(optical_depth, previous, node);
    Number mu_s_i = GetElekNodeSunCosine(r, mu_s, nu, node);
    bool same_side = nu - node.mu * mu_s_i >= 0.0;
    // GetElekTableValue of the slice's tables, with the coordinate (the same for the four
    // tables, which have one size) formed once.
    vec3 uvw = GetElekUvwFromHMuMuS(atmosphere, mapping, node.r - atmosphere.bottom_radius, node.mu, mu_s_i);
    vec3 coord = GetElekTextureCoordFromUvw(textureSize(gather_rayleigh_0, 0), uvw);
    vec3 g_r = vec3(same_side ? texture(gather_rayleigh_0, coord) : texture(gather_rayleigh_pi, coord));
    vec3 g_m = vec3(same_side ? texture(gather_mie_0, coord) : texture(gather_mie_pi, coord));
    vec3 view = exp(-optical_depth) * node.weight;
    rayleigh_sum += g_r * view * node.densities.x;
    mie_sum += g_m * view * node.densities.y;
    previous = node;
  }
  rayleigh = rayleigh_sum * atmosphere.rayleigh_scattering;
  mie = mie_sum * atmosphere.mie_scattering;
}

// --- The gather ---------------------------------------------------------------------------------

// Gauss-Legendre nodes and weights on [0, 1] for 1, 2 or 4 points.
Number GetElekGaussNode(int count, int i) {
  if (count == 1) return 0.5;
  if (count == 2) return i == 0 ? 0.21132486540518713 : 0.7886751345948129;
  if (i == 0) return 0.06943184420297371;
  if (i == 1) return 0.33000947820757187;
  if (i == 2) return 0.6699905217924281;
  return 0.9305681557970262;
}

Number GetElekGaussWeight(int count, int i) {
  if (count == 1) return 1.0;
  if (count == 2) return 0.5;
  return (i == 0 || i == 3) ? 0.17392742256872692 : 0.3260725774312731;
}

// d mu / d v of the view mapping (mu as a function of v).
Number GetElekMuDerivative(int mapping, Number v) {
  if (mapping == kElekMappingLinear) return 2.0;
  Number a = 2.0 * v - 1.0;
  return 6.0 * a * a;
}

Number GetElekMuFromV(int mapping, Number v) {
  if (mapping == kElekMappingLinear) return 2.0 * v - 1.0;
  Number a = 2.0 * v - 1.0;
  return a * a * a;
}

// K(mu_v, mu_w) = int_0^2pi p(dot(w, V)) d phi, the phase function integrated over the azimuth
// of w about the zenith, with dot(w, V) = a + b cos(phi), a = mu_v mu_w, b = sin_v sin_w.
// Rayleigh-like phases A + B nu^2 have the closed form 2 pi (A + B (a^2 + b^2 / 2)); the others use
// the periodic trapezoidal rule with 2 * azimuth_count intervals (folded onto [0, pi] by symmetry),
// which converges geometrically for these smooth periodic integrands.
Number GetElekAzimuthIntegratedPhase(IN(AtmosphereParameters) atmosphere, int kind, Number g, Number mu_v, Number mu_w,
    int azimuth_count) {
  Number a = mu_v * mu_w;
  Number b = SafeSqrt(1.0 - mu_v * mu_v) * SafeSqrt(1.0 - mu_w * mu_w);
  Number mean_square = a * a + 0.5 * b * b;
  if (kind == kPhaseIsotropic) return 0.5;
  if (kind == kPhaseRayleigh) return 2.0 * kPi * 3.0 / (16.0 * kPi) * (1.0 + mean_square);
  if (kind == kPhaseModifiedRayleigh) return 2.0 * kPi * (1.4 + 0.5 * mean_square) / (47.0 / 30.0 * 4.0 * kPi);
  Number sum = 0.0;
  for (int i = 0; i <= azimuth_count; ++i) {
    Number phi = kPi * Number(i) / Number(azimuth_count);
    Number weight = (i == 0 || i == azimuth_count) ? 0.5 : 1.0;
    sum += weight * GetMediumPhase(atmosphere, kind, g, a + b * cos(phi));
  }
  return sum * 2.0 * kPi / Number(azimuth_count);
}

// The gather weight of table row j for gather row y (the per-texel kernel of the gather matrix,
// a `gather_rows` x `rows` table): with I(w) linear in v between rows (the sampler's
// interpolation, rows at v_j = j / (rows - 1)),
//   G(mu_y) = sum_j M[y][j] I_j,  M[y][j] = int hat_j(v) K(mu_y, mu(v)) |d mu / d v| dv,
// by `point_count`-point Gauss-Legendre on each of the two intervals next to row j. Returns the
// Rayleigh weight in x, the Mie weight in y. The rows of M sum to int p dw = 1 up to quadrature
// error; the CPU normalises them to exactly 1, which conserves energy for a uniform field.
vec2 ComputeElekGatherWeightTexel(IN(AtmosphereParameters) atmosphere, int mapping, int gather_rows, int rows,
    int y, int j, int point_count, int azimuth_count) {
  Number mu_v = GetElekMuFromV(mapping, Number(y) / Number(gather_rows - 1));
  Number dv = 1.0 / Number(rows - 1);
  vec2 weight = vec2(0.0);
  for (int side = 0; side < 2; ++side) {
    int first = j - 1 + side;  // the interval [v_first, v_first + dv]
    if (first < 0 || first >= rows - 1) continue;
    for (int q = 0; q < point_count; ++q) {
      Number s = GetElekGaussNode(point_count, q);
      Number v = (Number(first) + s) * dv;
      Number hat = side == 0 ? s : 1.0 - s;
      Number w = GetElekGaussWeight(point_count, q) * dv * hat * GetElekMuDerivative(mapping, v);
      Number mu_w = GetElekMuFromV(mapping, v);
      weight.x += w * GetElekAzimuthIntegratedPhase(atmosphere, atmosphere.rayleigh_phase, 0.0, mu_v, mu_w, azimuth_count);
      weight.y += w * GetElekAzimuthIntegratedPhase(atmosphere, atmosphere.mie_phase, atmosphere.mie_g, mu_v, mu_w, azimuth_count);
    }
  }
  return weight;
}

// The same for the rebuild that restores single scattering's own phase in the first gather:
// I^(1)(w) becomes 4 pi p_d(dot(w, S)) I^(1)_d(w) (4 pi: the mean of 4 pi p is 1, so the result
// keeps the seed's scale), which makes the weight depend on the sun cosine mu_s and on the side of
// V (azimuth 0 or pi from the sun). Returns (RR, RM, MR, MM): gather phase p_c first, restored
// phase p_d second.
vec4 ComputeElekPhaseGatherWeightTexel(IN(AtmosphereParameters) atmosphere, int mapping, int gather_rows, int rows,
    int y, int j, Number mu_s, bool opposite_side, int point_count, int azimuth_count) {
  Number mu_v = GetElekMuFromV(mapping, Number(y) / Number(gather_rows - 1));
  Number sin_v = SafeSqrt(1.0 - mu_v * mu_v) * (opposite_side ? -1.0 : 1.0);
  Number sin_s = SafeSqrt(1.0 - mu_s * mu_s);
  Number dv = 1.0 / Number(rows - 1);
  vec4 weight = vec4(0.0);
  for (int side = 0; side < 2; ++side) {
    int first = j - 1 + side;
    if (first < 0 || first >= rows - 1) continue;
    for (int q = 0; q < point_count; ++q) {
      Number s = GetElekGaussNode(point_count, q);
      Number v = (Number(first) + s) * dv;
      Number hat = side == 0 ? s : 1.0 - s;
      Number w = GetElekGaussWeight(point_count, q) * dv * hat * GetElekMuDerivative(mapping, v);
      Number mu_w = GetElekMuFromV(mapping, v);
      Number sin_w = SafeSqrt(1.0 - mu_w * mu_w);
      vec4 sum = vec4(0.0);
      for (int i = 0; i <= azimuth_count; ++i) {
        Number c = cos(kPi * Number(i) / Number(azimuth_count));
        Number nu_v = mu_v * mu_w + sin_v * sin_w * c;
        Number nu_s = mu_s * mu_w + sin_s * sin_w * c;
        Number p_r_v = EvaluatePhaseFunction(atmosphere.rayleigh_phase, 0.0, nu_v);
        Number p_m_v = GetMiePhase(atmosphere, nu_v);
        Number p_r_s = EvaluatePhaseFunction(atmosphere.rayleigh_phase, 0.0, nu_s);
        Number p_m_s = GetMiePhase(atmosphere, nu_s);
        Number e = (i == 0 || i == azimuth_count) ? 0.5 : 1.0;
        sum += e * vec4(p_r_v * p_r_s, p_r_v * p_m_s, p_m_v * p_r_s, p_m_v * p_m_s);
      }
      weight += (w * 2.0 * kPi / Number(azimuth_count) * 4.0 * kPi) * sum;
    }
  }
  return weight;
}

// --- The ground (option ground) -----------------------------------------------------------------
//
// An idealised Lambertian planet of albedo rho lit by the sun and the sky, whose reflection feeds
// the next order (as Bruneton 2017's ground irradiance does; the seed itself has none). All ground
// points are at h = 0, so the ground's irradiance per unit solar irradiance is a function of the
// sun cosine there alone, E(mu_s), kept as a D x 1 table at the sun cosines of the table's slices.
// Light of j scattering events ending in the air (order j's table, j >= 1; j = 0: the sun itself)
// reaches the ground as E^(j), and the ground sends L_g = T(P, G) rho / pi E^(j)(mu_s_G) towards
// every P whose ray meets it at G. The gather of order k >= 2 reads I^(k-1) + 4 pi L_g[E^(k-2)] (4 pi:
// the tables' factored scale, below): light of k - 1 events either way. mu_s_G comes from the table's canonical form (view and sun in one
// vertical plane on the same side), as every other node's sun cosine does.

const int kElekGroundIntervals = 16;  // of mu_w in the sky's irradiance on the ground

// E^(0): the sun's irradiance on the ground per unit solar irradiance (0 once it has set).
vec3 ComputeElekGroundDirectIrradiance(IN(AtmosphereParameters) atmosphere,
    IN(TransmittanceTexture) transmittance_texture, Number mu_s) {
  return GetTransmittanceToSun(atmosphere, transmittance_texture, atmosphere.bottom_radius, mu_s) * max(mu_s, 0.0);
}

// E^(j), j >= 1: the sky of order j's table over the ground's upper hemisphere,
//   E(mu_s) = int_0^1 mu_w int_0^2pi L(mu_w, phi) dphi dmu_w,  L = p_R(nu) I_R + p_M(nu) I_M,
// whose azimuth integral is the azimuth-integrated phase K(mu_s, mu_w) of the gather. The mu_w
// integral: 4-point Gauss-Legendre on each of `interval_count` equal intervals of (0, 1) (the
// weight mu_w takes the integrand to 0 at the horizon, where the table changes fastest).
vec3 ComputeElekGroundSkyIrradiance(IN(AtmosphereParameters) atmosphere, IN(Texture3D) rayleigh_table,
    IN(Texture3D) mie_table, int mapping, Number mu_s, int interval_count, int azimuth_count) {
  vec3 sum = vec3(0.0);
  for (int i = 0; i < interval_count; ++i) {
    for (int q = 0; q < 4; ++q) {
      Number mu_w = (Number(i) + GetElekGaussNode(4, q)) / Number(interval_count);
      Number weight = GetElekGaussWeight(4, q) / Number(interval_count) * mu_w;
      vec3 i_r = GetElekTableValue(atmosphere, rayleigh_table, mapping, 0.0, mu_w, mu_s);
      vec3 i_m = GetElekTableValue(atmosphere, mie_table, mapping, 0.0, mu_w, mu_s);
      Number k_r = GetElekAzimuthIntegratedPhase(atmosphere, atmosphere.rayleigh_phase, 0.0, mu_s, mu_w, azimuth_count);
      Number k_m = GetElekAzimuthIntegratedPhase(atmosphere, atmosphere.mie_phase, atmosphere.mie_g, mu_s, mu_w, azimuth_count);
      sum += weight * (k_r * i_r + k_m * i_m);
    }
  }
  return sum;
}

// L_g of texel `texel`: what the ground sends back along the texel's ray, T(P, G) rho / pi E(mu_s_G)
// with E read from `ground_irradiance` (D x 1, texel z at the sun cosine of slice z, linear in the
// table's w); 0 for a ray that misses the ground. Returned in the table's factored scale, 4 pi L_g:
// the tables hold I with L = p(nu) I, and the mean of p over the sphere is 1 / (4 pi), so light
// arriving as a radiance L enters the gather as 4 pi L (the same 4 pi as the phase gather's).
vec3 ComputeElekGroundRadianceTexel(IN(AtmosphereParameters) atmosphere,
    IN(TransmittanceTexture) transmittance_texture, IN(Texture2D) ground_irradiance, int mapping,
    IN(ivec3) texture_size, IN(ivec3) texel) {
  Number r;
  Number mu;
  Number mu_s;
  Number t_max;
  GetElekTexelRay(atmosphere, mapping, texture_size, texel, r, mu, mu_s, t_max);
  if (!RayIntersectsGround(atmosphere, r, mu)) return vec3(0.0);
  Number nu = GetElekCanonicalNu(mu, mu_s);
  Number mu_s_ground = ClampCosine((r * mu_s + t_max * nu) / atmosphere.bottom_radius);
  vec3 to_ground = GetTransmittance(atmosphere, transmittance_texture, r, mu, t_max, true);
  Number w = GetElekUvwFromHMuMuS(atmosphere, mapping, 0.0, 0.0, mu_s_ground).z;
  vec2 coord = vec2(GetTextureCoordFromUnitRange(w, textureSize(ground_irradiance, 0).x), 0.5);
  return to_ground * atmosphere.ground_albedo * 4.0 * vec3(texture(ground_irradiance, coord));  // 4 pi rho / pi
}

// Radiance per unit solar irradiance from the factored table (RGB = I_R, the Mie channel
// `mie_first` = I_M of the batch's first channel), the Mie of the other channels rebuilt with
// Bruneton 2008's ratio: I_M(l) = I_M(l0) I_R(l) / I_R(l0) * beta_R(l0) / beta_R(l) * beta_M(l) / beta_M(l0).
vec3 GetElekMieFromFirstChannel(IN(AtmosphereParameters) atmosphere, IN(vec3) rayleigh, Number mie_first) {
  vec3 beta_r = atmosphere.rayleigh_scattering;
  vec3 beta_m = atmosphere.mie_scattering;
  if (beta_m.x <= 0.0) return vec3(0.0);
  if (beta_r.x <= 0.0 || rayleigh.x <= 0.0 || beta_r.y <= 0.0 || beta_r.z <= 0.0) {
    return mie_first * beta_m / beta_m.x;
  }
  return mie_first * (rayleigh / rayleigh.x) * (beta_r.x / beta_r) * (beta_m / beta_m.x);
}

// Radiance per unit solar irradiance seen from radius r along the view (mu, nu) with the sun at
// mu_s, from the summed tables: L = p_R(nu) I_R + p_M(nu) I_M at the point where the view ray
// enters the atmosphere (the observer itself when inside); 0 for a ray that misses it. The Mie
// part is the table's own per channel (`mie_per_channel`, option mie=rgb) or that of the first
// channel rebuilt by GetElekMieFromFirstChannel (the seed's RGBA table). The elek sky view on the
// CPU and the GL frame both call it.
vec3 GetElekRadiance(IN(AtmosphereParameters) atmosphere, IN(Texture3D) rayleigh_table, IN(Texture3D) mie_table,
    int mapping, bool mie_per_channel, Number r, Number mu, Number mu_s, Number nu) {
  Number t_limit = 1e30;  // no limit: longer than any ray to the atmosphere (length)
  if (!MoveToAtmosphereEntry(atmosphere, r, mu, mu_s, nu, t_limit)) {
    return vec3(0.0);
  }
  Number h = r - atmosphere.bottom_radius;
  vec3 rayleigh = GetElekTableValue(atmosphere, rayleigh_table, mapping, h, mu, mu_s);
  vec3 mie_value = GetElekTableValue(atmosphere, mie_table, mapping, h, mu, mu_s);
  vec3 mie = mie_per_channel ? mie_value : GetElekMieFromFirstChannel(atmosphere, rayleigh, mie_value.x);
  return GetRayleighPhase(atmosphere, nu) * rayleigh + GetMiePhase(atmosphere, nu) * mie;
}
