// Model source4d (docs/models/source4d.md): the radiance of a view ray is the integral along it
// of the transmittance times the source function J, split into
//   J = J1 + J>=2,
// where J1, single scattering, is evaluated exactly at each step (true phase functions, the
// transmittance to the sun from the transmittance table, the planet's shadow as an interval of
// the ray found analytically, so that no step straddles its edge), and J>=2, the light of orders
// 2 and up scattered towards the observer, comes from a 4D table of the *phase-weighted incident
// radiance* of each medium:
//   J>=2(x, v) = sigma_R(r) G_R(r, mu, mu_s, phi) + sigma_M(r) G_M(r, mu, mu_s, phi),
//   G_m(x, v)  = integral over the sphere of p_m(v . w) L>=1(x, w) dw,
// with L>=1(x, w) the radiance of orders >= 1 arriving at x from direction w. G is smooth in all
// four variables (it is an angular average of radiance, without the horizon's discontinuity or
// the exponential fall of the densities, which sigma(r) carries exactly), so a small table
// interpolates it well. The CPU builds G order by order by gathering (cpu/source4d_tables.cc).
//
// Table layout. G_R and G_M are two 3D textures of ln G per channel (geometric interpolation:
// G falls by decades with the sun in twilight) with the 4D (r, mu, mu_s, phi) packed as
//   x = phi (azimuth of the view from the sun's, 0..pi),  y = theta (view zenith, 0..pi),
//   z = r layer * mu_s_size + theta_s (sun zenith, 0..kSource4dMaxSunZenith),
// each axis on texel centres (GetTextureCoordFromUnitRange); r by Bruneton's rho / H. The r
// layers are blended by hand: the z coordinate of one lookup stays inside its layer.

// The sun zeniths the table covers; beyond it the table's last row (sun 120 degrees, where G is
// about 1e-6 of its daytime value) is used. The axis is piecewise linear in the sun zenith with
// knots at 60, 84 and 104 degrees: G varies slowly with a high sun, steepens as the sun nears the
// horizon, bends most between 84 and 104 degrees (21 of 48 rows, 0.95 degrees apart) and falls by
// decades into the night.
//
// Each knot lies on a row: at 3/20, 7/20 and 39/50 of the rows, rounded to the nearest row in
// integer arithmetic (the same on the CPU and the GPU). The lookups interpolate linearly in the
// unit coordinate between two rows, which is linear in the sun zenith only if no knot lies
// between them; with a knot between two rows the interpolation crossed the kink, and ln G, which
// falls by a decade in 2 degrees at 104 degrees, came out 12 % low there (48 rows, the knot at
// unit 0.78 between rows 36 and 37). Tables need at least 8 rows, where the four pieces have a
// row each (kSource4dMinSunZenithRows).
const Number kSource4dMaxSunZenith = 2.0943951023931953;  // 120 degrees
const Number kSource4dSunKnot1 = 1.0471975511965976;      // 60 degrees
const Number kSource4dSunKnot2 = 1.4660765716752369;      // 84 degrees
const Number kSource4dSunKnot3 = 1.8151424220741028;      // 104 degrees
const int kSource4dMinSunZenithRows = 8;

// The unit coordinate (0..1 over the rows' centres) of the knot at numerator / denominator of the
// axis in a table of mu_s_size rows.
Number GetSource4dSunKnotUnit(int numerator, int denominator, int mu_s_size) {
  int rows = mu_s_size - 1;
  return Number((numerator * rows + denominator / 2) / denominator) / Number(rows);
}

// The knots' unit coordinates of a table of mu_s_size rows.
struct Source4dSunAxis {
  Number unit_1;
  Number unit_2;
  Number unit_3;
};

Source4dSunAxis GetSource4dSunAxis(int mu_s_size) {
  Source4dSunAxis axis;
  axis.unit_1 = GetSource4dSunKnotUnit(3, 20, mu_s_size);
  axis.unit_2 = GetSource4dSunKnotUnit(7, 20, mu_s_size);
  axis.unit_3 = GetSource4dSunKnotUnit(39, 50, mu_s_size);
  return axis;
}

Number Source4dLerp(Number x, Number x_0, Number x_1, Number y_0, Number y_1) {
  return y_0 + (y_1 - y_0) * (x - x_0) / (x_1 - x_0);
}

Number GetSource4dUnitFromSunZenith(Number theta_s, int mu_s_size) {
  Source4dSunAxis a = GetSource4dSunAxis(mu_s_size);
  if (theta_s < kSource4dSunKnot1) return Source4dLerp(theta_s, 0.0, kSource4dSunKnot1, 0.0, a.unit_1);
  if (theta_s < kSource4dSunKnot2) {
    return Source4dLerp(theta_s, kSource4dSunKnot1, kSource4dSunKnot2, a.unit_1, a.unit_2);
  }
  if (theta_s < kSource4dSunKnot3) {
    return Source4dLerp(theta_s, kSource4dSunKnot2, kSource4dSunKnot3, a.unit_2, a.unit_3);
  }
  return min(Source4dLerp(theta_s, kSource4dSunKnot3, kSource4dMaxSunZenith, a.unit_3, 1.0), 1.0);
}

Number GetSource4dSunZenithFromUnit(Number x, int mu_s_size) {
  Source4dSunAxis a = GetSource4dSunAxis(mu_s_size);
  if (x < a.unit_1) return Source4dLerp(x, 0.0, a.unit_1, 0.0, kSource4dSunKnot1);
  if (x < a.unit_2) return Source4dLerp(x, a.unit_1, a.unit_2, kSource4dSunKnot1, kSource4dSunKnot2);
  if (x < a.unit_3) return Source4dLerp(x, a.unit_2, a.unit_3, kSource4dSunKnot2, kSource4dSunKnot3);
  return Source4dLerp(x, a.unit_3, 1.0, kSource4dSunKnot3, kSource4dMaxSunZenith);
}

// acos by Abramowitz and Stegun 4.4.46 (|error| <= 2e-8 rad): the table's three coordinates
// need one each per lookup, and this is several times cheaper than the library's on the CPU.
Number Source4dAcos(Number x) {
  Number a = min(abs(x), 1.0);
  Number p = -0.0012624911;
  p = p * a + 0.0066700901;
  p = p * a - 0.0170881256;
  p = p * a + 0.0308918810;
  p = p * a - 0.0501743046;
  p = p * a + 0.0889789874;
  p = p * a - 0.2145988016;
  p = p * a + 1.5707963050;
  Number angle = sqrt(1.0 - a) * p;
  return x < 0.0 ? kPi - angle : angle;
}

Number GetSource4dUnitSunZenith(Number mu_s, int mu_s_size) {
  return GetSource4dUnitFromSunZenith(Source4dAcos(ClampCosine(mu_s)), mu_s_size);
}

Number GetSource4dUnitR(IN(AtmosphereParameters) atmosphere, Number r) {
  Number H = sqrt((atmosphere.top_radius - atmosphere.bottom_radius) *
                  (atmosphere.top_radius + atmosphere.bottom_radius));
  Number rho = SafeSqrt((r - atmosphere.bottom_radius) * (r + atmosphere.bottom_radius));
  return ClampToRange(rho / H, 0.0, 1.0);
}

Number GetSource4dRFromUnit(IN(AtmosphereParameters) atmosphere, Number x_r) {
  Number H = sqrt((atmosphere.top_radius - atmosphere.bottom_radius) *
                  (atmosphere.top_radius + atmosphere.bottom_radius));
  Number rho = H * x_r;
  return min(sqrt(rho * rho + atmosphere.bottom_radius * atmosphere.bottom_radius), atmosphere.top_radius);
}

// Azimuth (0..pi) between the view and the sun seen from a point where the view has zenith
// cosine mu and the sun mu_s, nu = cos(view, sun); 0 where it is undefined (either at a pole).
Number GetSource4dAzimuth(Number mu, Number mu_s, Number nu) {
  Number s = SafeSqrt((1.0 - mu * mu) * (1.0 - mu_s * mu_s));
  return s > 1e-9 ? Source4dAcos(ClampCosine((nu - mu * mu_s) / s)) : 0.0;
}

// The texture coordinates of a lookup: x (azimuth) and y (view zenith) of the textures, s the
// sun-zenith row within an r layer (in texels, 0.5 .. mu_s_size - 0.5), and the r layer's
// position (0 .. r_size - 1).
Number GetSource4dAzimuthCoord(IN(Source4dTexture) rayleigh_texture, Number mu, Number mu_s, Number nu) {
  return GetTextureCoordFromUnitRange(GetSource4dAzimuth(mu, mu_s, nu) / kPi, textureSize(rayleigh_texture, 0).x);
}

Number GetSource4dZenithCoord(IN(Source4dTexture) rayleigh_texture, Number mu) {
  return GetTextureCoordFromUnitRange(Source4dAcos(ClampCosine(mu)) / kPi, textureSize(rayleigh_texture, 0).y);
}

Number GetSource4dSunRow(int mu_s_size, Number mu_s) {
  return 0.5 + GetSource4dUnitSunZenith(mu_s, mu_s_size) * Number(mu_s_size - 1);
}

Number GetSource4dLayer(IN(AtmosphereParameters) atmosphere, IN(Source4dTexture) rayleigh_texture, int mu_s_size,
    Number r) {
  int r_size = textureSize(rayleigh_texture, 0).z / mu_s_size;
  return GetSource4dUnitR(atmosphere, r) * Number(r_size - 1);
}

// ln G of both media, per channel, at the coordinates above.
void GetSource4dLogTermsAt(IN(Source4dTexture) rayleigh_texture, IN(Source4dTexture) mie_texture, int mu_s_size,
    Number x, Number y, Number s, Number layer, OUT(vec3) log_rayleigh, OUT(vec3) log_mie) {
  int depth = textureSize(rayleigh_texture, 0).z;
  int r_size = depth / mu_s_size;
  int layer_0 = int(min(floor(layer), Number(r_size - 2)));
  Number w = layer - Number(layer_0);
  vec3 uvw_0 = vec3(x, y, (Number(layer_0 * mu_s_size) + s) / Number(depth));
  vec3 uvw_1 = vec3(x, y, (Number((layer_0 + 1) * mu_s_size) + s) / Number(depth));
  vec3 rayleigh_0;
  vec3 mie_0;
  vec3 rayleigh_1;
  vec3 mie_1;
  TexturePair3D(rayleigh_texture, mie_texture, uvw_0, rayleigh_0, mie_0);
  TexturePair3D(rayleigh_texture, mie_texture, uvw_1, rayleigh_1, mie_1);
  log_rayleigh = mix(rayleigh_0, rayleigh_1, w);
  log_mie = mix(mie_0, mie_1, w);
}

// ln G of both media, per channel, at (r, mu, mu_s, nu); `mu_s_size` is the number of
// sun-zenith rows per r layer.
void GetSource4dLogTerms(IN(AtmosphereParameters) atmosphere, IN(Source4dTexture) rayleigh_texture,
    IN(Source4dTexture) mie_texture, int mu_s_size, Number r, Number mu, Number mu_s, Number nu,
    OUT(vec3) log_rayleigh, OUT(vec3) log_mie) {
  GetSource4dLogTermsAt(rayleigh_texture, mie_texture, mu_s_size,
      GetSource4dAzimuthCoord(rayleigh_texture, mu, mu_s, nu), GetSource4dZenithCoord(rayleigh_texture, mu),
      GetSource4dSunRow(mu_s_size, mu_s), GetSource4dLayer(atmosphere, rayleigh_texture, mu_s_size, r),
      log_rayleigh, log_mie);
}

// The source function of orders >= 2 (per length, per unit solar irradiance, per sr) at a point
// of the given medium.
vec3 GetSource4dMultipleScattering(IN(AtmosphereParameters) atmosphere, IN(Source4dTexture) rayleigh_texture,
    IN(Source4dTexture) mie_texture, int mu_s_size, IN(MediumSample) medium, Number r, Number mu, Number mu_s,
    Number nu) {
  vec3 log_rayleigh;
  vec3 log_mie;
  GetSource4dLogTerms(atmosphere, rayleigh_texture, mie_texture, mu_s_size, r, mu, mu_s, nu, log_rayleigh, log_mie);
  return medium.rayleigh_scattering * exp(log_rayleigh) + medium.mie_scattering * exp(log_mie);
}

// The sky's irradiance of the ground (per unit solar irradiance, orders >= 1) from a table over
// the sun zenith (the table's sun-zenith rows, one texel each, height 1).
vec3 GetSource4dGroundIrradiance(IN(TransmittanceTexture) irradiance_texture, Number mu_s) {
  int width = textureSize(irradiance_texture, 0).x;
  return vec3(texture(irradiance_texture,
                      vec2(GetTextureCoordFromUnitRange(GetSource4dUnitSunZenith(mu_s, width), width), 0.5)));
}

// The part [t_0, t_1] of [0, t_max] of the ray (r, mu) where the point is in the planet's shadow
// (a point sun: the half-cylinder of radius R behind the planet). With p(t) the point, its
// squared distance from the sun's axis minus R^2 is
//   q(t) = (1 - nu^2) t^2 + 2 r (mu - mu_s nu) t + r^2 (1 - mu_s^2) - R^2,
// and it is behind the planet where dot(p, sun) = r mu_s + t nu < 0. Returns false when no part
// of the ray is in shadow.
bool GetSource4dShadowInterval(IN(AtmosphereParameters) atmosphere, Number r, Number mu, Number mu_s, Number nu,
    Number t_max, OUT(Number) t_0, OUT(Number) t_1) {
  t_0 = 0.0;
  t_1 = t_max;
  Number R = atmosphere.bottom_radius;
  Number a = 1.0 - nu * nu;
  Number b = r * (mu - mu_s * nu);
  Number c = (r * SafeSqrt(1.0 - mu_s * mu_s) - R) * (r * SafeSqrt(1.0 - mu_s * mu_s) + R);
  if (a < 1e-12) {
    // Along the sun's axis: inside the cylinder for all t or for none.
    if (c >= 0.0) return false;
  } else {
    Number discriminant = b * b - a * c;
    if (discriminant <= 0.0) return false;
    Number root = sqrt(discriminant);
    // Roots without cancellation: q = -(b + sign(b) root), t = q / a and c / q.
    Number q = b >= 0.0 ? -(b + root) : -(b - root);
    Number r_0 = q / a;
    Number r_1 = q != 0.0 ? c / q : r_0;
    t_0 = max(t_0, min(r_0, r_1));
    t_1 = min(t_1, max(r_0, r_1));
  }
  // Behind the planet: r mu_s + t nu < 0.
  if (nu > 0.0) {
    t_1 = min(t_1, -r * mu_s / nu);
  } else if (nu < 0.0) {
    t_0 = max(t_0, -r * mu_s / nu);
  } else if (mu_s >= 0.0) {
    return false;
  }
  return t_1 > t_0;
}

// The marching steps of one segment [t_a, t_b] of a ray on which the altitude is monotonic
// (no perigee inside): quadratic in distance from the segment's lower end, where the densities
// are highest. Step i of n spans [GetSource4dStep(i), GetSource4dStep(i + 1)].
Number GetSource4dStep(Number t_a, Number t_b, bool dense_at_a, int i, int n) {
  Number x = Number(i) / Number(n);
  return dense_at_a ? t_a + (t_b - t_a) * x * x : t_b - (t_b - t_a) * (1.0 - x) * (1.0 - x);
}

// The Mie phase function of the first order at a node of source4d's gathering grid (zenith node
// a of `zeniths` over [0, pi], azimuth node b of `azimuths` over [0, pi] from the sun's, each
// standing for a hat, a tent one node wide on either side), for the sun at cosine mu_s and the
// node's nu. A tabulated phase function's forward peak inside kPhasePeakAngle is far narrower than
// the grid (22.5 degrees of azimuth by default): sampled at the node next to the sun, the hats
// would spread the aureole over their cells. So the phase is capped at its value at
// kPhasePeakAngle, and the peak's mass above the cap goes where the hats put the sun's direction:
// the node's hat at the sun over the hat's solid angle (exact on the sphere), which keeps the
// peak's energy and puts it in the sun's direction (delta-M, on the grid). Other phase
// functions are broad against the grid and are returned as they are.
Number GetSource4dGatherMiePhase(IN(AtmosphereParameters) atmosphere, int a, int b, int zeniths, int azimuths,
    Number mu_s, Number nu) {
  Number phase = GetMiePhase(atmosphere, nu);
  if (atmosphere.mie_phase != kPhaseTabulated) return phase;
  phase = min(phase, atmosphere.mie_phase_peak_cap);
  if (b != 0) return phase;  // the sun is at azimuth 0: only the b = 0 hats reach it
  Number h = kPi / Number(zeniths - 1);
  Number theta = kPi * Number(a) / Number(zeniths - 1);
  Number hat = max(1.0 - abs(theta - acos(ClampCosine(mu_s))) / h, 0.0);
  if (!(hat > 0.0)) return phase;
  // The hat's solid angle: dphi times the integral of the zenith tent times sin(theta), whose
  // closed forms are 2 sin(theta_a) (1 - cos h) / h inside and 1 - sin(h) / h at either pole.
  Number d_phi = kPi / Number(azimuths - 1);
  Number zenith_part = (a == 0 || a == zeniths - 1) ? 1.0 - sin(h) / h : 2.0 * sin(theta) * (1.0 - cos(h)) / h;
  return phase + atmosphere.mie_phase_peak_mass * hat / (d_phi * zenith_part);
}

// Radiance scattered towards the observer at radius r (inside the atmosphere) along (mu, nu),
// up to the ground, the top or t_limit: `single_weight` times single scattering plus
// `multiple_weight` times the orders >= 2 of the table (weights 0 or 1: the gathering passes
// integrate one order at a time). About `sample_count` steps in all, spread over the segments
// between the observer, the ray's lowest point and the edges of the planet's shadow.
// `transmittance` receives the transmittance over the marched ray.
vec3 IntegrateSource4dRadianceInside(IN(AtmosphereParameters) atmosphere,
    IN(TransmittanceTexture) transmittance_texture, IN(Source4dTexture) rayleigh_texture,
    IN(Source4dTexture) mie_texture, int mu_s_size, Number r, Number mu, Number mu_s, Number nu,
    bool ray_r_mu_intersects_ground, Number t_limit, int sample_count, Number single_weight,
    Number multiple_weight, Number mie_phase_value, OUT(vec3) transmittance) {
  transmittance = vec3(1.0);
  Number t_max = min(DistanceToNearestAtmosphereBoundary(atmosphere, r, mu, ray_r_mu_intersects_ground), t_limit);
  vec3 radiance = vec3(0.0);
  if (!(t_max > 0.0)) return radiance;
  // Breakpoints: the lowest point and the shadow's edges, in increasing order.
  Number breaks[4];
  int break_count = 0;
  Number t_low = -r * mu;
  if (t_low > 0.0 && t_low < t_max) {
    breaks[break_count] = t_low;
    break_count += 1;
  }
  Number shadow_0;
  Number shadow_1;
  if (single_weight > 0.0 && GetSource4dShadowInterval(atmosphere, r, mu, mu_s, nu, t_max, shadow_0, shadow_1)) {
    if (shadow_0 > 0.0) {
      breaks[break_count] = shadow_0;
      break_count += 1;
    }
    if (shadow_1 < t_max) {
      breaks[break_count] = shadow_1;
      break_count += 1;
    }
  }
  breaks[break_count] = t_max;
  break_count += 1;
  // Insertion sort (at most four values).
  for (int i = 1; i < break_count; ++i) {
    for (int j = i; j > 0 && breaks[j] < breaks[j - 1]; --j) {
      Number swap = breaks[j];
      breaks[j] = breaks[j - 1];
      breaks[j - 1] = swap;
    }
  }
  Number rayleigh_phase = GetRayleighPhase(atmosphere, nu);
  // mie_phase_value < 0: the atmosphere's own (the gathering passes GetSource4dGatherMiePhase's).
  Number mie_phase = mie_phase_value < 0.0 ? GetMiePhase(atmosphere, nu) : mie_phase_value;
  int steps_per_segment = max(2, (sample_count + break_count - 1) / break_count);
  Number t_a = 0.0;
  for (int k = 0; k < break_count; ++k) {
    Number t_b = breaks[k];
    if (t_b > t_a) {
      // The lower end of the segment: the altitude falls along it when it ends at or before
      // the lowest point.
      bool dense_at_a = !(t_b <= t_low);
      for (int i = 0; i < steps_per_segment; ++i) {
        Number t_0 = GetSource4dStep(t_a, t_b, dense_at_a, i, steps_per_segment);
        Number t_1 = GetSource4dStep(t_a, t_b, dense_at_a, i + 1, steps_per_segment);
        Number dt = t_1 - t_0;
        Number t = 0.5 * (t_0 + t_1);
        Number r_i = sqrt(max(t * t + 2.0 * r * mu * t + r * r, 0.0));
        Number mu_i = ClampCosine((r * mu + t) / r_i);
        Number mu_s_i = ClampCosine((r * mu_s + t * nu) / r_i);
        MediumSample medium = SampleMedium(atmosphere, r_i);
        vec3 step_transmittance = exp(-medium.extinction * dt);
        vec3 source = vec3(0.0);
        if (single_weight > 0.0) {
          source += single_weight * GetTransmittanceToSun(atmosphere, transmittance_texture, r_i, mu_s_i) *
              (medium.rayleigh_scattering * rayleigh_phase + medium.mie_scattering * mie_phase);
        }
        if (multiple_weight > 0.0) {
          source += multiple_weight * GetSource4dMultipleScattering(atmosphere, rayleigh_texture, mie_texture,
              mu_s_size, medium, r_i, mu_i, mu_s_i, nu);
        }
        radiance += transmittance * source * IntegrateStep(medium.extinction, step_transmittance, dt);
        transmittance *= step_transmittance;
      }
    }
    t_a = max(t_a, t_b);
  }
  return radiance;
}

// The same for an observer anywhere (above the atmosphere: from where the ray enters it).
vec3 IntegrateSource4dRadiance(IN(AtmosphereParameters) atmosphere, IN(TransmittanceTexture) transmittance_texture,
    IN(Source4dTexture) rayleigh_texture, IN(Source4dTexture) mie_texture, int mu_s_size, Number r, Number mu,
    Number mu_s, Number nu, Number t_limit, int sample_count, OUT(vec3) transmittance) {
  transmittance = vec3(1.0);
  if (!MoveToAtmosphereEntry(atmosphere, r, mu, mu_s, nu, t_limit)) {
    return vec3(0.0);
  }
  return IntegrateSource4dRadianceInside(atmosphere, transmittance_texture, rayleigh_texture, mie_texture, mu_s_size,
      r, mu, mu_s, nu, RayIntersectsGround(atmosphere, r, mu), t_limit, sample_count, 1.0, 1.0, -1.0, transmittance);
}

// Radiance scattered towards an observer inside the atmosphere along (mu, nu) with all orders,
// and in `ground_radiance` the light that the Lambertian ground reflects towards it where the ray
// meets the ground (`hits_ground`: the direct sun, exactly, and the sky's irradiance from the
// table), attenuated.
vec3 GetSource4dRadianceInside(IN(AtmosphereParameters) atmosphere, IN(TransmittanceTexture) transmittance_texture,
    IN(Source4dTexture) rayleigh_texture, IN(Source4dTexture) mie_texture,
    IN(TransmittanceTexture) irradiance_texture, int mu_s_size, Number r, Number mu, Number mu_s, Number nu,
    bool hits_ground, Number t_limit, int sample_count, OUT(vec3) ground_radiance) {
  ground_radiance = vec3(0.0);
  vec3 transmittance;
  vec3 radiance = IntegrateSource4dRadianceInside(atmosphere, transmittance_texture, rayleigh_texture, mie_texture,
      mu_s_size, r, mu, mu_s, nu, hits_ground, t_limit, sample_count, 1.0, 1.0, -1.0, transmittance);
  if (hits_ground) {
    Number t = DistanceToBottomAtmosphereBoundary(atmosphere, r, mu);
    Number mu_s_ground = ClampCosine((r * mu_s + t * nu) / atmosphere.bottom_radius);
    vec3 direct = mu_s_ground > 0.0 ?
        mu_s_ground * GetTransmittanceToSun(atmosphere, transmittance_texture, atmosphere.bottom_radius, mu_s_ground) :
        vec3(0.0);
    ground_radiance = transmittance * atmosphere.ground_albedo / kPi *
        (direct + GetSource4dGroundIrradiance(irradiance_texture, mu_s_ground));
  }
  return radiance;
}

// The same for an observer anywhere (above the atmosphere: from where the ray enters it).
vec3 GetSource4dRadiance(IN(AtmosphereParameters) atmosphere, IN(TransmittanceTexture) transmittance_texture,
    IN(Source4dTexture) rayleigh_texture, IN(Source4dTexture) mie_texture,
    IN(TransmittanceTexture) irradiance_texture, int mu_s_size, Number r, Number mu, Number mu_s, Number nu,
    int sample_count, OUT(vec3) ground_radiance) {
  ground_radiance = vec3(0.0);
  Number t_limit = 1e30;
  if (!MoveToAtmosphereEntry(atmosphere, r, mu, mu_s, nu, t_limit)) {
    return vec3(0.0);
  }
  return GetSource4dRadianceInside(atmosphere, transmittance_texture, rayleigh_texture, mie_texture,
      irradiance_texture, mu_s_size, r, mu, mu_s, nu, RayIntersectsGround(atmosphere, r, mu), t_limit, sample_count,
      ground_radiance);
}

// The per-texel kernel of source4d's sky-view table: the directions of sky.glsl's sky-view
// mapping (GetViewAnglesFromSkyViewTextureUv; the lower half of the rows meets the ground) for an
// observer inside the atmosphere at radius r and a sun at zenith cosine mu_s and azimuth 0. The
// march of GetSource4dRadiance per texel: the scattered radiance, and the ground's in
// `ground_radiance`.
vec3 ComputeSource4dSkyViewTexel(IN(AtmosphereParameters) atmosphere, IN(TransmittanceTexture) transmittance_texture,
    IN(Source4dTexture) rayleigh_texture, IN(Source4dTexture) mie_texture,
    IN(TransmittanceTexture) irradiance_texture, int mu_s_size, IN(ivec2) texture_size, IN(vec2) frag_coord,
    Number r, Number mu_s, int sample_count, OUT(vec3) ground_radiance) {
  Number mu;
  Number azimuth;
  GetViewAnglesFromSkyViewTextureUv(atmosphere, texture_size, r, frag_coord / vec2(texture_size), mu, azimuth);
  Number nu = ClampCosine(SafeSqrt(1.0 - mu * mu) * SafeSqrt(1.0 - mu_s * mu_s) * cos(azimuth) + mu * mu_s);
  return GetSource4dRadianceInside(atmosphere, transmittance_texture, rayleigh_texture, mie_texture,
      irradiance_texture, mu_s_size, r, mu, mu_s, nu, frag_coord.y >= 0.5 * Number(texture_size.y), 1e30,
      sample_count, ground_radiance);
}
