// Model `simple`: the closed form of the seed "Simple Atmosphere" (Gijs Bellaard), in the seed's
// own variables, so that any up vector works.
//
// The medium is homogeneous and fills the half-space Omega = {p : <u, p> < 0} below a boundary
// plane through the origin with unit normal u ("up"). p is the observer, d the unit view
// direction, s the unit sun direction. Per channel (vec3): sigma_t the extinction coefficient
// (scattering + absorption) and beta = sum over media of sigma_s,m p_m(nu), the in-scattering
// coefficient per unit solid angle at nu = <d, s>, which is constant along a ray.
//
// The seed's path length to the boundary from p along d is
//   l(p, d) = -<u, p> / <u, d>  if <u, d> > 0,  infinite otherwise,
// linear in p: l(p + tau d, s) = l(p, s) + tau l(d, s). Single scattering with the sun's light
// attenuated on its way in and the scattered light on its way out is
//   I = int_0^{l(p, d)} beta T(l(p + tau d, s)) T(tau) dtau,   T(x) = exp(-sigma_t x),
// and the exponent a(tau) = l(p + tau d, s) + tau = l(p, s) + f tau is linear in tau, with the
// seed's f = l(d, s) + 1 = 1 - <u, d> / <u, s>. Hence, on a finite path of length L = l(p, d),
//   I = beta T(l(p, s)) (1 - T(f L)) / (sigma_t f)                               (the seed's form)
//     = beta L exp(-sigma_t min(a0, a1)) G(sigma_t |a1 - a0|),   G(x) = (1 - exp(-x)) / x,
// with a0 = a(0) = l(p, s) and a1 = a(L) = L (the exit point lies on the boundary, where
// l(., s) = 0). The second form is what the code evaluates: G takes x >= 0 only, so no
// exponential grows (f < 0, looking up more steeply than the sun, gives a1 < a0 and is the same
// expression), and G(x) -> 1 as f -> 0 gives the limit beta L exp(-sigma_t L) without a division
// by f. On an infinite path (<u, d> <= 0, looking down or along the plane) f >= 1 and
//   I = beta T(l(p, s)) / (sigma_t f),   1 / f = <u, s> / (<u, s> - <u, d>) <= 1.
//
// Infinite lengths never enter arithmetic: the path length to the boundary is capped at
// kSimpleInfiniteLength (a distance no light crosses in any atmosphere this model is given) and the
// infinite path has its own branch. Lengths are in the unit of the coefficients (the preset's
// length unit). All functions take u explicitly; the model's local frame has u = (0, 0, 1).

// Stands for an infinite path length (l = infinity): finite in float and double, so that it can
// be multiplied by a zero extinction coefficient without a NaN.
const Number kSimpleInfiniteLength = 1.0e30;

// The seed's l(p, d): the distance from p along d to the boundary plane, for p in the closed
// half-space (a p slightly above the plane from rounding counts as on it). Capped at
// kSimpleInfiniteLength, which it returns for <u, d> <= 0.
Number GetSimpleDistanceToBoundary(IN(vec3) u, IN(vec3) p, IN(vec3) d) {
  Number depth = max(-dot(u, p), 0.0);
  Number mu = dot(u, d);
  // depth / mu >= kSimpleInfiniteLength, tested without dividing by a tiny mu.
  if (mu <= 0.0 || depth >= kSimpleInfiniteLength * mu) {
    return kSimpleInfiniteLength;
  }
  return depth / mu;
}

// Where the ray from p along d starts to see the medium. Inside (or on the plane) that is p itself.
// From above the plane (<u, p> > 0) the ray enters only if <u, d> < 0, after
// entry_distance = <u, p> / -<u, d>. The medium is invariant under translations along the plane,
// so every quantity at the entry point depends only on its depth, 0: `entry` is returned as the
// projection of p onto the plane, which has that depth and needs no (possibly huge) entry distance.
// Returns false for a ray that never meets the medium.
bool GetSimpleEntryPoint(IN(vec3) u, IN(vec3) p, IN(vec3) d, OUT(vec3) entry, OUT(Number) entry_distance) {
  Number height = dot(u, p);
  entry = p;
  entry_distance = 0.0;
  if (height <= 0.0) {
    return true;
  }
  Number mu = dot(u, d);
  if (mu >= 0.0) {
    return false;
  }
  entry = p - height * u;
  entry_distance = height >= kSimpleInfiniteLength * -mu ? kSimpleInfiniteLength : height / -mu;
  return true;
}

// G(x) = (1 - exp(-x)) / x for x >= 0, with G(0) = 1. Below x = 0.01 the Taylor series
// 1 - x/2 + x^2/6 - x^3/24 + x^4/120 (truncation error < x^5/720 < 1.4e-13) replaces the quotient,
// whose numerator loses digits to cancellation there.
Number GetSimpleExponentialAverage(Number x) {
  if (x < 0.01) {
    return 1.0 - x / 2.0 * (1.0 - x / 3.0 * (1.0 - x / 4.0 * (1.0 - x / 5.0)));
  }
  return (1.0 - exp(-x)) / x;
}

// int_0^t exp(-sigma a(tau)) dtau per channel for an exponent a that is linear in tau, from a0 at
// tau = 0 to a1 at tau = t: t exp(-sigma min(a0, a1)) G(sigma |a1 - a0|). t, a0, a1 >= 0 and finite.
vec3 IntegrateSimpleLinearExponent(IN(vec3) sigma, Number t, Number a0, Number a1) {
  Number delta = abs(a1 - a0);
  vec3 average = vec3(GetSimpleExponentialAverage(sigma.x * delta), GetSimpleExponentialAverage(sigma.y * delta),
      GetSimpleExponentialAverage(sigma.z * delta));
  return t * exp(-sigma * min(a0, a1)) * average;
}

// The part of beta that one medium contributes: its scattering coefficient times its phase function
// (normalised to 1 over the sphere, see phase.glsl) at nu = <d, s>. For the seed's isotropic medium
// this is sigma_s / (4 pi): the seed's in-scattering has phase 1 rather than 1 / (4 pi), so its I
// is 4 pi times our radiance (the `simple` preset's exposure 4 pi makes up for it).
vec3 GetSimpleMediumScattering(IN(vec3) scattering, int phase, Number g, Number nu) {
  return scattering * EvaluatePhaseFunction(phase, g, nu);
}

// Radiance scattered towards p along d by the medium between p and the point at `distance` along
// the ray (kSimpleInfiniteLength or more: the whole ray), per unit solar irradiance, sun disc
// excluded; and the transmittance over that segment, exp(-sigma_t (length of it in the medium)).
vec3 ComputeSimpleScatteringAlongSegment(IN(vec3) u, IN(vec3) p, IN(vec3) d, IN(vec3) s, IN(vec3) sigma_t,
    IN(vec3) beta, Number distance, OUT(vec3) transmittance) {
  transmittance = vec3(1.0);
  vec3 entry;
  Number entry_distance;
  if (!GetSimpleEntryPoint(u, p, d, entry, entry_distance)) {
    return vec3(0.0);  // the ray stays above the plane: vacuum
  }
  bool whole_ray = distance >= kSimpleInfiniteLength;
  if (!whole_ray && distance <= entry_distance) {
    return vec3(0.0);  // the segment ends before the medium starts
  }
  Number mu = dot(u, d);
  Number mu_s = dot(u, s);
  Number path = GetSimpleDistanceToBoundary(u, entry, d);
  Number t = whole_ray ? path : min(distance - entry_distance, path);
  transmittance = exp(-sigma_t * t);
  if (mu_s <= 0.0) {
    return vec3(0.0);  // the sun is below the plane's horizon: l(p, s) is infinite, no sunlight
  }
  Number a0 = GetSimpleDistanceToBoundary(u, entry, s);
  if (mu <= 0.0 && t >= kSimpleInfiniteLength) {
    // The infinite path: beta T(l(p, s)) / (sigma_t f). A channel without extinction has no
    // scattering either (beta <= sigma_s <= sigma_t), so it contributes 0.
    Number inverse_f = mu_s / (mu_s - mu);
    vec3 attenuated = beta * exp(-sigma_t * a0) * inverse_f;
    return vec3(sigma_t.x > 0.0 ? attenuated.x / sigma_t.x : 0.0, sigma_t.y > 0.0 ? attenuated.y / sigma_t.y : 0.0,
        sigma_t.z > 0.0 ? attenuated.z / sigma_t.z : 0.0);
  }
  // A finite segment [0, t]: a(t) = t + l(entry + t d, s), which is t at the boundary.
  Number a1 = t + GetSimpleDistanceToBoundary(u, entry + t * d, s);
  return beta * IntegrateSimpleLinearExponent(sigma_t, t, a0, a1);
}

// The radiance of the whole view ray: the seed's in-scattering I(p, d) with the phase function and
// absorption of the parameters.
vec3 ComputeSimpleScatteredRadiance(IN(vec3) u, IN(vec3) p, IN(vec3) d, IN(vec3) s, IN(vec3) sigma_t,
    IN(vec3) beta) {
  vec3 transmittance;
  return ComputeSimpleScatteringAlongSegment(u, p, d, s, sigma_t, beta, kSimpleInfiniteLength, transmittance);
}

// Transmittance along the view ray out of the medium, T(l(p, d)): 1 for a ray that never meets the
// medium, and 0 for a ray with an infinite path (<u, d> <= 0 inside the medium, or entering it
// from above): such a ray never leaves the atmosphere, the half-space's analogue of a ray that
// meets the ground in the sample contract (docs/design.md §4).
vec3 GetSimpleViewTransmittance(IN(vec3) u, IN(vec3) p, IN(vec3) d, IN(vec3) sigma_t) {
  vec3 entry;
  Number entry_distance;
  if (!GetSimpleEntryPoint(u, p, d, entry, entry_distance)) {
    return vec3(1.0);
  }
  if (dot(u, d) <= 0.0) {
    return vec3(0.0);
  }
  return exp(-sigma_t * GetSimpleDistanceToBoundary(u, entry, d));
}

// The seed's direct light S(d) T(l(p, d)) for a sun disc of angular radius alpha and unit
// irradiance: the limb-darkened disc of sun.glsl (a uniform one, radiance 1 / (solid angle), with
// the atmosphere's sun_limb_darkening = 0), with the per-channel wavelengths and centre radiance
// of `sun` (its other members are not used).
vec3 GetSimpleSunDiscRadiance(IN(vec3) u, IN(vec3) p, IN(vec3) d, IN(vec3) s, IN(vec3) sigma_t,
    IN(AtmosphereParameters) sun) {
  vec3 radiance = GetSunDiscUnattenuatedRadiance(sun, dot(d, s));
  if (radiance == vec3(0.0)) {
    return vec3(0.0);
  }
  return GetSimpleViewTransmittance(u, p, d, sigma_t) * radiance;
}
